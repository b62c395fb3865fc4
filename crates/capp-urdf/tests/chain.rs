//! The chain: forward kinematics against poses derived by hand, folding of
//! fixed joints, the bodies, and the choice of base and tip.

mod common;

use capp_urdf::{JointKind, LoadOptions};
use common::{joint, link, load_text, origin, pose_gap, robot, LIMIT};
use nalgebra::{Isometry3, Matrix3, Matrix4, Point3, Vector3};

fn tip(name: &str) -> LoadOptions {
    LoadOptions {
        tip_link: Some(name.into()),
        ..LoadOptions::default()
    }
}

/// R = Rz(yaw) Ry(pitch) Rx(roll), written out.
fn rpy(r: f64, p: f64, y: f64) -> Matrix3<f64> {
    let rx = Matrix3::new(1.0, 0.0, 0.0, 0.0, r.cos(), -r.sin(), 0.0, r.sin(), r.cos());
    let ry = Matrix3::new(p.cos(), 0.0, p.sin(), 0.0, 1.0, 0.0, -p.sin(), 0.0, p.cos());
    let rz = Matrix3::new(y.cos(), -y.sin(), 0.0, y.sin(), y.cos(), 0.0, 0.0, 0.0, 1.0);
    rz * ry * rx
}

/// Rodrigues: rotation by `angle` about the unit vector along `axis`.
fn rodrigues(axis: [f64; 3], angle: f64) -> Matrix3<f64> {
    let k = Vector3::from(axis).normalize();
    let kx = Matrix3::new(0.0, -k.z, k.y, k.z, 0.0, -k.x, -k.y, k.x, 0.0);
    Matrix3::identity() + kx * angle.sin() + kx * kx * (1.0 - angle.cos())
}

fn homogeneous(r: Matrix3<f64>, t: [f64; 3]) -> Matrix4<f64> {
    let mut m = Matrix4::identity();
    m.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
    m.fixed_view_mut::<3, 1>(0, 3).copy_from(&Vector3::from(t));
    m
}

fn placement(xyz: [f64; 3], rpy_: [f64; 3]) -> Matrix4<f64> {
    homogeneous(rpy(rpy_[0], rpy_[1], rpy_[2]), xyz)
}

fn gap(a: &Isometry3<f64>, b: &Matrix4<f64>) -> f64 {
    (a.to_homogeneous() - b).abs().max()
}

#[test]
fn planar_arm_matches_the_textbook() {
    let urdf = robot(
        &[
            link("base"),
            link("l1"),
            link("l2"),
            link("tool"),
            joint(
                "j1",
                "revolute",
                "base",
                "l1",
                &format!(
                    "{}<axis xyz=\"0 0 1\"/>{LIMIT}",
                    origin([0.0, 0.0, 0.5], [0.0; 3])
                ),
            ),
            joint(
                "j2",
                "revolute",
                "l1",
                "l2",
                &format!(
                    "{}<axis xyz=\"0 0 1\"/>{LIMIT}",
                    origin([0.4, 0.0, 0.0], [0.0; 3])
                ),
            ),
            joint(
                "end",
                "fixed",
                "l2",
                "tool",
                &origin([0.3, 0.0, 0.0], [0.0; 3]),
            ),
        ]
        .join("\n"),
    );
    let (_dir, chain) = load_text(&urdf, "planar.urdf", &LoadOptions::default());
    let chain = chain.unwrap();
    assert_eq!(
        (chain.base_link.as_str(), chain.tip_link.as_str()),
        ("base", "tool")
    );
    let (q1, q2) = (0.3, -0.8);
    let frames = chain.forward(&[q1, q2]).unwrap();
    assert_eq!(frames.len(), 3);
    let at = |f: &Isometry3<f64>| f * Point3::origin();
    let expected_elbow = Point3::new(0.4 * q1.cos(), 0.4 * q1.sin(), 0.5);
    let expected_tip = Point3::new(
        0.4 * q1.cos() + 0.3 * (q1 + q2).cos(),
        0.4 * q1.sin() + 0.3 * (q1 + q2).sin(),
        0.5,
    );
    assert!((at(&frames[0]) - Point3::new(0.0, 0.0, 0.5)).norm() < 1e-12);
    assert!((at(&frames[1]) - expected_elbow).norm() < 1e-12);
    assert!((at(&frames[2]) - expected_tip).norm() < 1e-12);
    assert!((frames[2].rotation.angle() - (q1 + q2).abs()).abs() < 1e-12);
}

/// Base, a fixed pedestal, a revolute joint with rpy, a revolute joint about
/// a tilted axis, a fixed link in the middle, a prismatic joint about another
/// tilted axis, a fixed flange at the end; a camera bolted to link1 and a
/// finger sliding off link3.
fn arm() -> String {
    robot(&[
        link("base"),
        link("pedestal"),
        link("link1"),
        link("link2"),
        "<link name=\"link2b\"><collision><origin xyz=\"0 0 0.05\"/><geometry><sphere radius=\"0.02\"/></geometry></collision></link>".into(),
        link("link3"),
        link("flange"),
        "<link name=\"camera\"><collision><origin xyz=\"0.01 0 0\"/><geometry><sphere radius=\"0.03\"/></geometry></collision></link>".into(),
        link("finger"),
        joint("mount", "fixed", "base", "pedestal", &origin([0.0, 0.0, 0.1], [0.0, 0.0, 0.3])),
        joint("j1", "revolute", "pedestal", "link1", &format!("{}<axis xyz=\"0 0 1\"/>{LIMIT}", origin([0.0, 0.0, 0.2], [0.1, 0.2, 0.3]))),
        joint("j2", "revolute", "link1", "link2", &format!("{}<axis xyz=\"1 1 0\"/>{LIMIT}", origin([0.3, 0.0, 0.0], [0.0, 0.5, 0.0]))),
        joint("mid", "fixed", "link2", "link2b", &origin([0.1, 0.0, 0.0], [0.2, 0.0, 0.0])),
        joint("j3", "prismatic", "link2b", "link3", &format!("{}<axis xyz=\"0.3 -0.4 1.2\"/>{LIMIT}", origin([0.0, 0.1, 0.0], [0.0; 3]))),
        joint("flange_joint", "fixed", "link3", "flange", &origin([0.0, 0.0, 0.05], [0.0, 0.0, 1.0])),
        joint("camera_mount", "fixed", "link1", "camera", &origin([0.0, 0.05, 0.0], [0.0, -0.4, 0.0])),
        joint("finger_joint", "prismatic", "link3", "finger", &format!("<axis xyz=\"0 1 0\"/>{LIMIT}")),
    ]
    .join("\n"))
}

#[test]
fn forward_matches_poses_composed_by_hand() {
    let (_dir, chain) = load_text(&arm(), "arm.urdf", &tip("flange"));
    let chain = chain.unwrap();
    let kinds: Vec<_> = chain.joints.iter().map(|j| j.kind).collect();
    assert_eq!(
        kinds,
        [
            JointKind::Revolute,
            JointKind::Revolute,
            JointKind::Prismatic
        ]
    );
    let q = [0.7, -1.1, 0.25];
    let frames = chain.forward(&q).unwrap();

    let mount = placement([0.0, 0.0, 0.1], [0.0, 0.0, 0.3]);
    let t1 = mount
        * placement([0.0, 0.0, 0.2], [0.1, 0.2, 0.3])
        * homogeneous(rodrigues([0.0, 0.0, 1.0], q[0]), [0.0; 3]);
    let t2 = t1
        * placement([0.3, 0.0, 0.0], [0.0, 0.5, 0.0])
        * homogeneous(rodrigues([1.0, 1.0, 0.0], q[1]), [0.0; 3]);
    let axis3 = Vector3::new(0.3, -0.4, 1.2).normalize() * q[2];
    let t3 = t2
        * placement([0.1, 0.0, 0.0], [0.2, 0.0, 0.0])
        * placement([0.0, 0.1, 0.0], [0.0; 3])
        * homogeneous(Matrix3::identity(), axis3.into());
    let tip = t3 * placement([0.0, 0.0, 0.05], [0.0, 0.0, 1.0]);
    for (got, want) in frames.iter().zip([t1, t2, t3, tip]) {
        assert!(gap(got, &want) < 1e-12, "{got} vs {want}");
    }

    // Bodies: what rides on what, in the moving joint's frame.
    let links: Vec<Vec<&str>> = chain
        .bodies
        .iter()
        .map(|b| b.links.iter().map(String::as_str).collect())
        .collect();
    assert_eq!(
        links,
        [
            vec!["base", "pedestal"],
            vec!["link1", "camera"],
            vec!["link2", "link2b"],
            vec!["link3", "flange"]
        ]
    );
    let camera = chain.bodies[1].capsules[0];
    let camera_world = t1
        * placement([0.0, 0.05, 0.0], [0.0, -0.4, 0.0])
        * Point3::new(0.01, 0.0, 0.0).to_homogeneous();
    assert!(((frames[0] * camera.a).coords - camera_world.xyz()).norm() < 1e-12);
    assert_eq!((camera.a, camera.radius), (camera.b, 0.03));
    let sphere = chain.bodies[2].capsules[0];
    let sphere_world = t2
        * placement([0.1, 0.0, 0.0], [0.2, 0.0, 0.0])
        * Point3::new(0.0, 0.0, 0.05).to_homogeneous();
    assert!(((frames[1] * sphere.a).coords - sphere_world.xyz()).norm() < 1e-12);
    assert_eq!(chain.joints[0].velocity, Some(1.5));
    assert_eq!((chain.joints[1].lower, chain.joints[1].upper), (-2.0, 2.0));
}

#[test]
fn folding_a_fixed_joint_changes_no_pose() {
    // The same two-joint arm, with the second joint's origin split into a
    // fixed joint (A) and the joint's own origin (B), and as one origin A*B.
    let (a_xyz, a_yaw) = ([0.1, 0.02, 0.0], 0.4_f64);
    let (b_xyz, b_yaw) = ([0.2, 0.0, 0.03], 0.3);
    let joined = [
        a_xyz[0] + b_xyz[0] * a_yaw.cos() - b_xyz[1] * a_yaw.sin(),
        a_xyz[1] + b_xyz[0] * a_yaw.sin() + b_xyz[1] * a_yaw.cos(),
        a_xyz[2] + b_xyz[2],
    ];
    let revolute = |name: &str, parent: &str, child: &str, xyz: [f64; 3], yaw: f64| {
        joint(
            name,
            "revolute",
            parent,
            child,
            &format!(
                "{}<axis xyz=\"0 1 1\"/>{LIMIT}",
                origin(xyz, [0.0, 0.0, yaw])
            ),
        )
    };
    let split = robot(
        &[
            link("base"),
            link("l1"),
            link("mid"),
            link("l2"),
            link("tip"),
            revolute("j1", "base", "l1", [0.0, 0.0, 0.3], 0.0),
            joint(
                "fixed_a",
                "fixed",
                "l1",
                "mid",
                &origin(a_xyz, [0.0, 0.0, a_yaw]),
            ),
            revolute("j2", "mid", "l2", b_xyz, b_yaw),
            joint(
                "fixed_end",
                "fixed",
                "l2",
                "tip",
                &origin([0.05, 0.0, 0.0], [0.3, 0.0, 0.0]),
            ),
        ]
        .join("\n"),
    );
    let single = robot(
        &[
            link("base"),
            link("l1"),
            link("l2"),
            revolute("j1", "base", "l1", [0.0, 0.0, 0.3], 0.0),
            revolute("j2", "l1", "l2", joined, a_yaw + b_yaw),
        ]
        .join("\n"),
    );
    let (_d1, split) = load_text(&split, "split.urdf", &LoadOptions::default());
    let (_d2, single) = load_text(&single, "single.urdf", &LoadOptions::default());
    let (split, single) = (split.unwrap(), single.unwrap());
    assert_eq!(split.tip_link, "tip");
    assert!(pose_gap(&split.joints[1].origin, &single.joints[1].origin) < 1e-12);
    assert!(pose_gap(&single.tool, &Isometry3::identity()) < 1e-15);
    let tool = placement([0.05, 0.0, 0.0], [0.3, 0.0, 0.0]);
    assert!(gap(&split.tool, &tool) < 1e-15);
    for q in [[0.0, 0.0], [0.5, -1.0], [-2.0, 1.9]] {
        let (a, b) = (split.forward(&q).unwrap(), single.forward(&q).unwrap());
        for (x, y) in a.iter().zip(&b).take(2) {
            assert!(pose_gap(x, y) < 1e-12);
        }
        assert!(gap(&a[2], &(b[2].to_homogeneous() * tool)) < 1e-12);
    }
}

#[test]
fn default_tip_follows_the_only_moving_branch() {
    // The camera branch off link1 has no moving joint, so it is passed by;
    // at link3 the finger is the only moving branch, so it is the tip.
    let (_dir, chain) = load_text(&arm(), "arm.urdf", &LoadOptions::default());
    let chain = chain.unwrap();
    assert_eq!(chain.tip_link, "finger");
    assert_eq!(chain.joints.len(), 4);
    // A base in the middle: the chain starts there.
    let options = LoadOptions {
        base_link: Some("link2".into()),
        tip_link: Some("flange".into()),
        ..LoadOptions::default()
    };
    let (_dir, chain) = load_text(&arm(), "arm.urdf", &options);
    let chain = chain.unwrap();
    let names: Vec<_> = chain.joints.iter().map(|j| j.name.as_str()).collect();
    assert_eq!(names, ["j3"]);
    assert_eq!(chain.bodies[0].links, ["link2", "link2b"]);
}

#[test]
fn continuous_joints_are_unlimited_and_velocity_zero_is_none() {
    let urdf = robot(
        &[
            link("a"),
            link("b"),
            joint(
                "spin",
                "continuous",
                "a",
                "b",
                "<axis xyz=\"0 0 2\"/><limit effort=\"1\" velocity=\"0\"/>",
            ),
        ]
        .join("\n"),
    );
    let (_dir, chain) = load_text(&urdf, "spin.urdf", &LoadOptions::default());
    let spin = &chain.unwrap().joints[0];
    assert_eq!(spin.kind, JointKind::Continuous);
    assert_eq!((spin.lower, spin.upper), (f64::NEG_INFINITY, f64::INFINITY));
    assert_eq!(spin.velocity, None);
    assert_eq!(spin.axis.into_inner(), Vector3::z());
}

#[test]
fn default_axis_is_x() {
    let urdf = robot(
        &[
            link("a"),
            link("b"),
            joint("j", "prismatic", "a", "b", LIMIT),
        ]
        .join("\n"),
    );
    let (_dir, chain) = load_text(&urdf, "x.urdf", &LoadOptions::default());
    assert_eq!(chain.unwrap().joints[0].axis.into_inner(), Vector3::x());
}
