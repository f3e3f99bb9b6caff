//! Reading arms from URDF: the built-in UR10, UR detection, fixed joints,
//! limits, and the descriptions that are refused.

use super::*;

#[test]
fn the_builtin_ur10_is_read_from_its_urdf() {
    let arm = Arm::ur10();
    assert_eq!(arm.name, "ur10");
    let names: Vec<&str> = arm.links.iter().map(|l| l.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "base_link",
            "shoulder_link",
            "upper_arm_link",
            "forearm_link",
            "wrist_1_link",
            "wrist_2_link",
            "wrist_3_link"
        ]
    );
    let g = arm.ur.expect("the UR10 is detected as a UR arm");
    let expected = [D1, A2, A3, D4, D5, D6];
    for (got, want) in [g.d1, g.a2, g.a3, g.d4, g.d5, g.d6].iter().zip(expected) {
        assert!((got - want).abs() < 1e-12, "{g:?}");
    }
    assert_eq!(arm.flange, Isometry3::identity());
    for (i, l) in arm.limits.iter().enumerate() {
        let range = if i == 2 { PI } else { TAU };
        assert_eq!((l.lower, l.upper), (-range, range), "joint {i}");
        let speed = if i < 2 { 120.0 } else { 180.0 };
        assert!(
            (l.velocity - f64::to_radians(speed)).abs() < 1e-12,
            "joint {i}"
        );
        let (acc, jerk) = if i < 3 { (2.5, 10.0) } else { (4.0, 20.0) };
        assert_eq!((l.acceleration, l.jerk), (acc, jerk), "joint {i}");
    }
    // Every link but the flange has capsules; the upper arm tube runs along
    // x from 0 to a2, 0.176 m along the shoulder axis.
    assert!(arm.links.iter().all(|l| !l.shapes.is_empty()));
    let Shape::Capsule { a, b, radius } = &arm.links[2].shapes[1] else {
        panic!("a capsule")
    };
    let ends = [a.coords, b.coords];
    assert!(
        ends.iter()
            .any(|e| (e - Vector3::new(A2, 0.0, 0.176)).norm() < 1e-12),
        "{ends:?}"
    );
    assert!(
        ends.iter()
            .any(|e| (e - Vector3::new(0.0, 0.0, 0.176)).norm() < 1e-12),
        "{ends:?}"
    );
    assert_eq!(*radius, 0.06);
}

#[test]
fn ur_geometry_is_detected_whatever_the_collision_shapes() {
    let boxes = edited(
        r#"<geometry><cylinder radius="0.06" length="0.612"/></geometry>"#,
        r#"<geometry><box size="0.612 0.12 0.12"/></geometry>"#,
    )
    .replace(
        r#"<cylinder radius="0.047" length="0.17"/>"#,
        r#"<sphere radius="0.06"/>"#,
    )
    .replace(
        r#"<cylinder radius="0.045" length="0.08"/>"#,
        r#"<mesh filename="meshes/wrist3.obj" scale="0.001 0.001 0.001"/>"#,
    );
    // A collision mesh is read through the caller (this crate does no IO).
    let msg = rejected(&boxes);
    assert!(
        msg.contains("link `wrist_3_link`: collision mesh `meshes/wrist3.obj`"),
        "{msg}"
    );
    let asked = std::cell::RefCell::new(Vec::new());
    let cube = "v -45 -45 -90\nv 45 -45 -90\nv 45 45 -90\nv -45 45 -90\nv -45 -45 -10\nv 45 -45 -10\nv 45 45 -10\nv -45 45 -10\nf 1 2 3 4\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";
    let arm = from_urdf_with(&boxes, &|name: &str| {
        asked.borrow_mut().push(name.to_owned());
        Ok(cube.as_bytes().to_vec())
    })
    .unwrap();
    assert_eq!(asked.into_inner(), ["meshes/wrist3.obj"]);
    assert_eq!(arm.ur, Arm::ur10().ur);
    assert!(matches!(arm.links[2].shapes[1], Shape::Cuboid { .. }));
    assert!(matches!(arm.links[4].shapes[0], Shape::Capsule { a, b, .. } if a == b));
    // The mesh (in millimetres, scaled) is bounded by the box it is.
    let Shape::Cuboid { pose, half } = &arm.links[6].shapes[0] else {
        panic!("a box: {:?}", arm.links[6].shapes)
    };
    let mut h: Vec<f64> = half.iter().copied().collect();
    h.sort_by(f64::total_cmp);
    assert!(
        (h[0] - 0.04).abs() < 1e-9 && (h[2] - 0.045).abs() < 1e-9,
        "{h:?}"
    );
    // At the link's collision origin (z -0.05) plus the mesh's own -0.05.
    assert!((pose.translation.vector - Vector3::new(0.0, 0.0, -0.1)).norm() < 1e-9);
    // The same millimetres without their scale: 90 m across, a unit slip
    // said as one (every pose collided and `check` said "out of reach").
    let unscaled = boxes.replace(r#" scale="0.001 0.001 0.001""#, "");
    let msg = match from_urdf_with(&unscaled, &|_: &str| Ok(cube.as_bytes().to_vec())) {
        Ok(_) => panic!("accepted"),
        Err(e) => e.to_string(),
    };
    assert!(
        msg.contains("a collision shape of link `wrist_3_link` is 90 m across")
            && msg.contains(r#"scale="0.001 0.001 0.001""#),
        "{msg}"
    );

    // Angles rounded within the 1e-6 tolerance still count: the closed form
    // then lands within ~3e-8 and a few damped least squares steps polish it.
    let arm = from_urdf(&UR10_URDF.replace("1.5707963267948966", "1.5707963")).unwrap();
    assert!(arm.ur.is_some());
    let mut rng = ChaCha8Rng::seed_from_u64(13);
    for _ in 0..100 {
        solved_to_its_pose(&arm, &tool_down_joints(&arm, &mut rng));
    }

    // Rounded angles beyond the 1e-6 tolerance are the UR geometry still,
    // but not exactly: solved in closed form and polished.
    let rounded = UR10_URDF.replace("1.5707963267948966", "1.5708");
    let arm = from_urdf(&rounded).unwrap();
    assert!(arm.ur.is_some_and(|g| !g.exact), "{:?}", arm.ur);
    assert!(Arm::ur10().ur.is_some_and(|g| g.exact));
}

/// A calibrated UR10 (every joint origin off the DH encoding by up to 3
/// milliradians and 3 millimetres, as ROS's `ur_calibration` writes them)
/// is a UR arm, not exactly: its closed-form solutions, polished, put the
/// flange on the target to 1e-9, every branch is told, and the learned
/// loop's steps may turn the flange a milliradian (1e-6 on the exact arm).
#[test]
fn a_calibrated_ur_arm_is_solved_in_closed_form_and_polished() {
    let mut rng = ChaCha8Rng::seed_from_u64(21);
    let mut text = UR10_URDF.to_string();
    // Each revolute joint's origin, offset.
    let mut out = String::new();
    let mut in_joint = false;
    for line in text.lines() {
        if line.contains("type=\"revolute\"") {
            in_joint = true;
        }
        if in_joint && line.trim_start().starts_with("<origin") {
            in_joint = false;
            let (dx, dy, dz) = (
                rng.random_range(-3e-3..3e-3),
                rng.random_range(-3e-3..3e-3),
                rng.random_range(-3e-3..3e-3),
            );
            let (r, p, y) = (
                rng.random_range(-3e-3..3e-3),
                rng.random_range(-3e-3..3e-3),
                rng.random_range(-3e-3..3e-3),
            );
            out.push_str(&calibrated(line, [dx, dy, dz], [r, p, y]));
        } else {
            out.push_str(line);
        }
        out.push('\n');
    }
    text = out;
    let arm = from_urdf(&text).unwrap();
    assert_ne!(arm.origins, Arm::ur10().origins, "the origins were offset");
    let g = arm.ur.expect("a calibrated UR10 is a UR arm");
    assert!(!g.exact);
    assert_eq!(arm.cup_down_tolerance(), 1e-3);
    assert_eq!(Arm::ur10().cup_down_tolerance(), 1e-6);
    let mut on_branch = 0;
    for _ in 0..100 {
        let q = tool_down_joints(&arm, &mut rng);
        let sol = solved_to_its_pose(&arm, &q);
        // Its own solution, away from the stretched elbow (where the
        // nominal arm's closed form may fall short of the real arm).
        if q[2].abs() > 0.2 {
            assert!(joint_distance(&sol, &q) < 1e-9, "{sol:?} vs {q:?}");
        }
        if arm.ur_branch(&base(), &q).is_some() {
            on_branch += 1;
        }
    }
    // Most poses are told on their branch of the closed form (where the
    // nominal arm's closed form falls short of the real arm's pose, it is
    // solved numerically instead).
    eprintln!("{on_branch} of 100 on a branch");
    assert!(on_branch >= 90, "{on_branch} of 100 on a branch");
}

/// The inverse kinematics of `q`'s own flange pose (nearest `q`), which
/// must put the flange there to 1e-9 m and rad.
fn solved_to_its_pose(arm: &Arm, q: &Joints) -> Joints {
    let target = arm.flange_pose(&base(), q);
    let sol = arm.pose_ik(&base(), &target, q).expect("reachable");
    let got = arm.flange_pose(&base(), &sol);
    assert!((got.translation.vector - target.translation.vector).norm() < 1e-9);
    assert!(got.rotation.angle_to(&target.rotation) < 1e-9);
    sol
}

/// `line` (an `<origin xyz=".." rpy=".."/>`) with `d` added to its xyz and
/// `r` to its rpy.
fn calibrated(line: &str, d: [f64; 3], r: [f64; 3]) -> String {
    let numbers = |key: &str| -> [f64; 3] {
        let Some(at) = line.find(&format!("{key}=\"")) else {
            return [0.0; 3];
        };
        let rest = &line[at + key.len() + 2..];
        let end = rest.find('"').unwrap();
        let v: Vec<f64> = rest[..end]
            .split_whitespace()
            .map(|x| x.parse().unwrap())
            .collect();
        [v[0], v[1], v[2]]
    };
    let (xyz, rpy) = (numbers("xyz"), numbers("rpy"));
    let indent = &line[..line.len() - line.trim_start().len()];
    format!(
        "{indent}<origin xyz=\"{} {} {}\" rpy=\"{} {} {}\"/>",
        xyz[0] + d[0],
        xyz[1] + d[1],
        xyz[2] + d[2],
        rpy[0] + r[0],
        rpy[1] + r[1],
        rpy[2] + r[2]
    )
}

#[test]
fn fixed_joints_fold_into_origins_and_flange() {
    // A fixed mount before the base joint and a tool flange past tool0.
    let text = edited(
        r#"<link name="tool0"/>"#,
        r#"<link name="tool0"/><link name="mount"/><link name="cup"/>"#,
    )
    .replace(r#"<parent link="base_link"/>"#, r#"<parent link="mount"/>"#)
    .replace(
        r#"<joint name="flange_joint""#,
        r#"<joint name="m" type="fixed"><parent link="base_link"/><child link="mount"/><origin xyz="0 0 0.1" rpy="0 0 0.5"/></joint>
           <joint name="c" type="fixed"><parent link="tool0"/><child link="cup"/><origin xyz="0 0 0.2"/></joint>
           <joint name="flange_joint""#,
    );
    let arm = from_urdf(&text).unwrap();
    let g = arm.ur.expect("a turned mount is still the UR geometry");
    assert!(
        (g.heading - 0.5).abs() < 1e-12 && (g.d1 - (D1 + 0.1)).abs() < 1e-12,
        "{g:?}"
    );
    // The closed form solves the mounted arm: every branch it gives puts
    // the flange where asked.
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let mut solved = 0;
    for _ in 0..50 {
        let q = tool_down_joints(&arm, &mut rng);
        let target = arm.flange_pose(&base(), &q);
        for sol in arm
            .ur_ik_branches(&base(), &target, &q)
            .into_iter()
            .flatten()
        {
            let got = arm.flange_pose(&base(), &sol);
            assert!((got.translation.vector - target.translation.vector).norm() < 1e-9);
            assert!(got.rotation.angle_to(&target.rotation) < 1e-9);
            solved += 1;
        }
    }
    assert!(solved >= 50, "{solved}");
    // The dynamics policy reads the base joint as the DH frame's heading.
    let q = [0.3, -1.0, 1.2, 0.1, 0.4, -0.6];
    assert!((arm.policy_joints(&q)[0] - 0.8).abs() < 1e-12);
    assert_eq!(Arm::ur10().policy_joints(&q), [0.3, -1.0, 1.2]);
    assert_eq!(
        arm.flange,
        Isometry3::identity(),
        "tool0 is the flange, not the cup"
    );
    let ur10 = Arm::ur10();
    let mount = Isometry3::from_parts(
        Translation3::new(0.0, 0.0, 0.1),
        UnitQuaternion::from_euler_angles(0.0, 0.0, 0.5),
    );
    let q = [0.3, -1.0, 1.2, 0.1, 0.4, -0.6];
    let want = mount * ur10.flange_pose(&Isometry3::identity(), &q);
    let got = arm.flange_pose(&Isometry3::identity(), &q);
    assert!((want.translation.vector - got.translation.vector).norm() < 1e-12);
}

#[test]
fn limits_follow_the_urdf_version_and_joint_type() {
    // Before URDF 1.2, acceleration and jerk are ignored: the defaults apply.
    let old = from_urdf(&edited(r#"version="1.2""#, "")).unwrap();
    assert!(
        old.limits
            .iter()
            .all(|l| (l.acceleration, l.jerk) == (2.5, 10.0))
    );
    // Continuous joints get ±2π.
    let text = edited(
        r#"<joint name="elbow_joint" type="revolute">"#,
        r#"<joint name="elbow_joint" type="continuous">"#,
    );
    let arm = from_urdf(&text).unwrap();
    assert_eq!((arm.limits[2].lower, arm.limits[2].upper), (-TAU, TAU));

    // A given acceleration or jerk is held to a cell's bounds (E029's):
    // an explicit 0 is not "absent", and 1e6 rad/s² is a typo or another
    // unit, refused with the joint named.
    for (from, to, says) in [
        (
            r#"acceleration="2.5" jerk="10""#,
            r#"acceleration="0" jerk="10""#,
            "acceleration is 0",
        ),
        (
            r#"acceleration="2.5" jerk="10""#,
            r#"acceleration="1e6" jerk="10""#,
            "acceleration is 1e6",
        ),
        (
            r#"acceleration="2.5" jerk="10""#,
            r#"acceleration="2.5" jerk="1e9""#,
            "jerk is 1e9",
        ),
    ] {
        let msg = rejected(&edited(from, to));
        assert!(
            msg.contains(says) && msg.contains("shoulder_pan_joint"),
            "{msg}"
        );
    }

    // Narrow wrist-3 limits: yaw-free IK still puts joint 6 as near as allowed.
    let narrow = UR10_URDF.replace(
        r#"<limit lower="-6.283185307179586" upper="6.283185307179586" effort="56"
           velocity="3.141592653589793" acceleration="4" jerk="20"/>
  </joint>

  <joint name="flange_joint""#,
        r#"<limit lower="-0.5" upper="0.5" effort="56" velocity="3.141592653589793"/>
  </joint>

  <joint name="flange_joint""#,
    );
    let arm = from_urdf(&narrow).unwrap();
    assert_eq!((arm.limits[5].lower, arm.limits[5].upper), (-0.5, 0.5));
    let near = [0.0, -FRAC_PI_2, FRAC_PI_2, -FRAC_PI_2, -FRAC_PI_2, 2.0];
    let tip = Point3::new(0.7, 0.2, 0.1);
    let q = arm
        .yaw_free_tool_down_ik(&base(), tip, SUCTION, &near)
        .unwrap();
    assert_eq!(q[5], 0.5);
}

/// `text` with the numbers of every attribute `keys` names (`radius`, or
/// `<origin xyz` for origins alone) times `k`.
fn scaled_lengths(text: &str, keys: &[&str], k: f64) -> String {
    let mut out = String::new();
    let mut rest = text;
    while let Some(at) = keys
        .iter()
        .filter_map(|key| rest.find(&format!("{key}=\"")).map(|i| i + key.len() + 2))
        .min()
    {
        let end = at + rest[at..].find('"').unwrap();
        let scaled: Vec<String> = rest[at..end]
            .split_whitespace()
            .map(|v| (v.parse::<f64>().unwrap() * k).to_string())
            .collect();
        out.push_str(&rest[..at]);
        out.push_str(&scaled.join(" "));
        rest = &rest[end..];
    }
    out.push_str(rest);
    out
}

fn rejected(text: &str) -> String {
    match from_urdf(text) {
        Ok(_) => panic!("accepted"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn unusable_descriptions_are_rejected_with_reasons() {
    let five = edited(
        r#"<joint name="wrist_3_joint" type="revolute">"#,
        r#"<joint name="wrist_3_joint" type="fixed">"#,
    );
    let msg = rejected(&five);
    assert!(
        msg.contains("5 movable joints") && msg.contains("exactly 6"),
        "{msg}"
    );

    let branch = edited(
        r#"<link name="tool0"/>"#,
        r#"<link name="tool0"/><link name="finger"/>
           <joint name="finger_joint" type="revolute"><parent link="forearm_link"/><child link="finger"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" velocity="1"/></joint>"#,
    );
    let msg = rejected(&branch);
    assert!(msg.contains("branches at link `forearm_link`"), "{msg}");

    let prismatic = edited(
        r#"<joint name="elbow_joint" type="revolute">"#,
        r#"<joint name="elbow_joint" type="prismatic">"#,
    );
    let msg = rejected(&prismatic);
    assert!(msg.contains("`elbow_joint` is prismatic"), "{msg}");

    let unlimited = edited(
        r#"lower="-3.141592653589793" upper="3.141592653589793""#,
        "",
    );
    let msg = rejected(&unlimited);
    assert!(msg.contains("`elbow_joint` needs a <limit>"), "{msg}");

    // A velocity far too slow to move (a unit slip): refused, with the
    // unit said, not left to the smoother.
    let crawling = edited(
        r#"velocity="3.141592653589793" acceleration"#,
        r#"velocity="0.0001" acceleration"#,
    );
    let msg = rejected(&crawling);
    assert!(
        msg.contains("velocity of at least 0.01 rad/s, not 0.0001"),
        "{msg}"
    );

    // A description exported in millimetres: its base is 150 m across
    // (it was read, and `check` said its start pose was out of reach).
    let msg = rejected(&scaled_lengths(
        UR10_URDF,
        &["<origin xyz", "radius", "length"],
        1000.0,
    ));
    assert!(
        msg.contains("a collision shape of link `base_link` is 150 m across")
            && msg.contains("divided by 1000"),
        "{msg}"
    );
    // Its origins alone: the joints span about 1.6 km.
    let msg = rejected(&scaled_lengths(UR10_URDF, &["<origin xyz"], 1000.0));
    assert!(
        msg.contains("`ur10`'s joints span 1") && msg.contains("divided by 1000"),
        "{msg}"
    );
    // A description of a small arm in metres is read.
    assert!(
        from_urdf(&scaled_lengths(
            UR10_URDF,
            &["<origin xyz", "radius", "length"],
            0.3
        ))
        .is_ok()
    );

    let two_roots = edited(
        r#"<link name="tool0"/>"#,
        r#"<link name="tool0"/><link name="stray"/>"#,
    );
    assert!(rejected(&two_roots).contains("several root links"));
    assert!(rejected("<robot name='x'>").contains("invalid URDF"));
}

#[test]
fn side_branches_bolted_on_fold_into_their_link_as_ros_descriptions_need() {
    // ROS's layout: a `world` root, `base_link` turned half a turn to the
    // controller's base (`base_link_inertia`), a `base` frame and an
    // `ft_frame` hanging off the chain, `flange` then `tool0`; and a camera
    // bracket with a box bolted to the forearm.
    let text = edited(
        r#"<link name="tool0"/>"#,
        r#"<link name="tool0"/><link name="world"/><link name="base"/><link name="ft_frame"/><link name="flange"/>
           <link name="bracket"/>
           <link name="camera"><collision><origin xyz="0 0.1 0"/><geometry><box size="0.05 0.05 0.05"/></geometry></collision></link>
           <joint name="base_joint" type="fixed"><parent link="world"/><child link="base_link"/></joint>
           <joint name="base_frame" type="fixed"><parent link="base_link"/><child link="base"/><origin rpy="0 0 3.141592653589793"/></joint>
           <joint name="ft" type="fixed"><parent link="wrist_3_link"/><child link="ft_frame"/></joint>
           <joint name="bracket_joint" type="fixed"><parent link="forearm_link"/><child link="bracket"/><origin xyz="-0.3 0 0"/></joint>
           <joint name="camera_joint" type="fixed"><parent link="bracket"/><child link="camera"/></joint>"#,
    )
    .replace(
        r#"<joint name="flange_joint" type="fixed">
    <parent link="wrist_3_link"/>
    <child link="tool0"/>"#,
        r#"<joint name="to_flange" type="fixed"><parent link="wrist_3_link"/><child link="flange"/></joint>
  <joint name="flange_joint" type="fixed">
    <parent link="flange"/>
    <child link="tool0"/>"#,
    );
    let arm = from_urdf(&text).unwrap();
    let ur10 = Arm::ur10();
    assert_eq!(arm.ur, ur10.ur);
    assert_eq!(arm.flange, Isometry3::identity());
    let forearm = &arm.links[3];
    assert_eq!(forearm.shapes.len(), ur10.links[3].shapes.len() + 1);
    let Some(Shape::Cuboid { pose, .. }) = forearm.shapes.last() else {
        panic!("the camera's box on the forearm: {:?}", forearm.shapes)
    };
    assert!((pose.translation.vector - Vector3::new(-0.3, 0.1, 0.0)).norm() < 1e-12);

    // A turned base_link: the same arm, its base joint half a turn on.
    let turned = text.replace(
        r#"<joint name="shoulder_pan_joint" type="revolute">
    <parent link="base_link"/>"#,
        r#"<joint name="inertia" type="fixed"><parent link="base_link"/><child link="base_link_inertia"/><origin rpy="0 0 3.141592653589793"/></joint>
  <joint name="shoulder_pan_joint" type="revolute">
    <parent link="base_link_inertia"/>"#,
    )
    .replace(r#"<link name="world"/>"#, r#"<link name="world"/><link name="base_link_inertia"/>"#);
    let arm = from_urdf(&turned).unwrap();
    let g = arm.ur.expect("UR geometry under a turned base_link");
    assert!((g.heading.abs() - PI).abs() < 1e-9, "{g:?}");
    let q = [0.3, -1.0, 1.2, 0.1, 0.4, -0.6];
    let back = arm.from_ur_convention(&q);
    let (a, b) = (
        arm.flange_pose(&base(), &back),
        ur10.flange_pose(&base(), &q),
    );
    assert!((a.translation.vector - b.translation.vector).norm() < 1e-9);
    assert!(a.rotation.angle_to(&b.rotation) < 1e-9);
}
