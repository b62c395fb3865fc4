//! The vendored Panda and UR5 URDFs (`robots/`) against Pinocchio's forward
//! kinematics (`robots/golden/urdf_fk.py`, 100 seeded configurations each,
//! itself cross-checked against a plain numpy chain product): every joint's
//! world origin and axis, and the tip pose, to 1e-9 m (f64 against f64).

use std::path::{Path, PathBuf};

use capp_urdf::{load, CapsuleCount, Chain, LoadOptions};
use nalgebra::{Point3, Vector3};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The golden rows: one value per joint, then per joint its world origin
/// and axis, then the tip position and rotation (row-major).
fn rows(csv: &str, joints: usize) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(repo().join("robots/golden").join(csv)).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    assert_eq!(
        header.split(',').count(),
        joints + 6 * joints + 12,
        "{csv} header"
    );
    lines
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect()
}

fn check(chain: &Chain, csv: &str) {
    let n = chain.joints.len();
    let rows = rows(csv, n);
    assert_eq!(rows.len(), 100, "{csv}");
    for (r, row) in rows.iter().enumerate() {
        let q = &row[..n];
        let frames = chain.forward(q).unwrap();
        for (i, joint) in chain.joints.iter().enumerate() {
            let at = n + 6 * i;
            let origin = frames[i].translation.vector;
            let axis = frames[i].rotation * joint.axis.into_inner();
            let expect_origin = Vector3::new(row[at], row[at + 1], row[at + 2]);
            let expect_axis = Vector3::new(row[at + 3], row[at + 4], row[at + 5]);
            assert!(
                (origin - expect_origin).norm() < 1e-9,
                "{csv} row {r} {}: origin {origin:?} vs {expect_origin:?}",
                joint.name
            );
            assert!(
                (axis - expect_axis).norm() < 1e-9,
                "{csv} row {r} {}: axis",
                joint.name
            );
        }
        let tip = frames[n];
        let at = 7 * n;
        let expect = Point3::new(row[at], row[at + 1], row[at + 2]);
        assert!(
            (Point3::from(tip.translation.vector) - expect).norm() < 1e-9,
            "{csv} row {r} tip"
        );
        let m = tip.rotation.to_rotation_matrix();
        for i in 0..3 {
            for j in 0..3 {
                let e = row[at + 3 + 3 * i + j];
                assert!(
                    (m[(i, j)] - e).abs() < 1e-9,
                    "{csv} row {r} tip R[{i}][{j}]"
                );
            }
        }
    }
}

#[test]
fn panda_matches_pinocchio() {
    let options = LoadOptions {
        base_link: Some("panda_link0".into()),
        tip_link: Some("panda_link8".into()),
        ..LoadOptions::default()
    };
    let path = repo().join("robots/panda_description/urdf/panda_collision.urdf");
    let chain = load(&path, &options).unwrap();
    let names: Vec<&str> = chain.joints.iter().map(|j| j.name.as_str()).collect();
    assert_eq!(
        names,
        (1..=7)
            .map(|i| format!("panda_joint{i}"))
            .collect::<Vec<_>>()
    );
    check(&chain, "panda_fk.csv");
}

#[test]
fn ur5_with_its_collision_meshes_matches_pinocchio() {
    let options = LoadOptions {
        base_link: Some("base_link".into()),
        tip_link: Some("tool0".into()),
        // The vendored tree is example-robot-data's `robots/` folder.
        packages: vec![("example-robot-data".into(), repo())],
        capsules_per_mesh: CapsuleCount::default(),
        ..LoadOptions::default()
    };
    let path = repo().join("robots/ur_description/urdf/ur5_robot.urdf");
    let chain = load(&path, &options).unwrap();
    assert_eq!(chain.joints.len(), 6);
    // Every moving body got capsules from its STL.
    for (i, body) in chain.bodies.iter().enumerate().skip(1) {
        assert!(!body.capsules.is_empty(), "body {i} ({:?})", body.links);
    }
    check(&chain, "ur5_fk.csv");
}
