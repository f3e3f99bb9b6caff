//! A robot described as ROS describes it: the UR10 of `ur10.urdf` with a
//! `world` root, `base_link` turned half a turn, side frames (`base`,
//! `ft_frame`, `flange` before `tool0`) and a collision mesh
//! (`tests/cells/ros_layout/`). It must be the same arm as the built-in
//! one: the same scenarios packed with the same motions.

mod common;

use common::{packwright, root, scratch};
use std::fs;

const ROS_CELL: &str = "tests/cells/ros_layout/bench_ros.pack";

fn text(out: &std::process::Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

/// The execution report of `scenario` in `pack` (bundled model).
fn executes(pack: &str, scenario: &str) -> serde_json::Value {
    let out = packwright(&["execute", pack, "--scenario", scenario, "--json"]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));
    serde_json::from_slice(&out.stdout).expect("an execution report")
}

#[test]
fn a_ros_layout_of_the_ur10_packs_as_the_built_in_one_does() {
    let out = packwright(&["check", ROS_CELL]);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out));

    // The same cell with the built-in arm.
    let dir = scratch("robot_description", "builtin");
    let builtin = dir.join("bench_builtin.pack");
    let source = fs::read_to_string(root().join(ROS_CELL)).expect("the cell");
    let replaced = source.replace(r#"robot urdf "ur10_ros.urdf""#, "robot ur10");
    assert_ne!(replaced, source);
    fs::write(&builtin, replaced).expect("written");
    let builtin = builtin.display().to_string();

    for scenario in ["ros_3of5/1", "ros_3of5/2"] {
        let ros = executes(ROS_CELL, scenario);
        let ur10 = executes(&builtin, scenario);
        for report in [&ros, &ur10] {
            assert_eq!(report["complete"], true, "{report}");
            assert_eq!(
                report["fallbacks"].as_array().map(Vec::len),
                Some(0),
                "{report}"
            );
            assert_eq!(
                report["collisions"].as_array().map(Vec::len),
                Some(0),
                "{report}"
            );
        }
        // The same motions: each product's execution time to the
        // millisecond (the turned base and the mesh change nothing).
        let times = |r: &serde_json::Value| -> Vec<i64> {
            r["products"]
                .as_array()
                .expect("products")
                .iter()
                .map(|p| (p["execution_s"].as_f64().expect("a time") * 1000.0).round() as i64)
                .collect()
        };
        assert_eq!(times(&ros), times(&ur10), "{scenario}");
    }
}

#[test]
fn a_description_with_a_mesh_it_cannot_find_is_refused_at_check() {
    let dir = scratch("robot_description", "missing_mesh");
    let urdf = fs::read_to_string(root().join("tests/cells/ros_layout/ur10_ros.urdf"))
        .expect("the description");
    fs::write(
        dir.join("arm.urdf"),
        urdf.replace(
            "meshes/wrist3.obj",
            "package://my_cup_holder/meshes/holder.stl",
        ),
    )
    .expect("written");
    let cell = fs::read_to_string(root().join(ROS_CELL))
        .expect("the cell")
        .replace(r#"robot urdf "ur10_ros.urdf""#, r#"robot urdf "arm.urdf""#);
    let pack = dir.join("cell.pack");
    fs::write(&pack, cell).expect("written");
    let out = packwright(&["check", &pack.display().to_string()]);
    let said = text(&out);
    assert_eq!(out.status.code(), Some(1), "{said}");
    assert!(said.contains("error[E013]"), "{said}");
    assert!(
        said.contains("package `my_cup_holder` not found on ROS_PACKAGE_PATH"),
        "{said}"
    );
    // execute says the same, once, and exits 2 without packing.
    let out = packwright(&[
        "execute",
        &pack.display().to_string(),
        "--scenario",
        "ros_3of5/1",
    ]);
    let said = text(&out);
    assert_ne!(out.status.code(), Some(0), "{said}");
    assert_eq!(
        said.matches("not found on ROS_PACKAGE_PATH").count(),
        1,
        "{said}"
    );
}
