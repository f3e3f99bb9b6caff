//! The scripted expert and RRT-Connect on generated cells whose box and
//! products stand on opposite sides of the robot: every feasible package is
//! packed. On development seed 1 (box behind the robot, products in front)
//! the inverse-kinematics solution nearest the arm at "above the slot" has
//! the wrist flipped, and the straight motion to it folds the wrist into the
//! forearm; the loop then joins another solution of the same cup pose
//! (`Station::route_any`). These scenarios failed before that.

mod common;
use common::{packwright, scratch};
use std::fs;

#[test]
fn front_to_back_packages_are_packed_by_the_expert_and_rrt_connect() {
    let dir = scratch("expert", "front-to-back");
    let out = packwright(&[
        "generate",
        "--seed",
        "1",
        "-o",
        dir.to_str().expect("utf-8"),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let pack = dir.join("gen_1.pack");
    let pack = pack.to_str().expect("utf-8");
    for (scenario, planner) in [
        ("gen_1_case1_n1/04", "expert"),
        ("gen_1_case1_n2/06", "expert"),
        ("gen_1_case1_n2/15", "expert"),
        ("gen_1_case1_n1/05", "rrt"),
    ] {
        let out = packwright(&[
            "execute",
            pack,
            "--scenario",
            scenario,
            "--planner",
            planner,
            "--json",
        ]);
        assert!(
            out.status.success(),
            "{scenario} with {planner}: exit {:?}\n{}",
            out.status.code(),
            String::from_utf8_lossy(&out.stdout)
        );
    }
    let _ = fs::remove_dir_all(dir);
}
