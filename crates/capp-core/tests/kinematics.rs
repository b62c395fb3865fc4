//! Forward kinematics against an independent golden file, and every exact
//! derivative against central finite differences in f64.

mod common;

use capp_core::kinematics::{
    end_direction_error, end_point_force, end_twist, forward_kinematics, Frames,
};
use capp_core::robot::{JointOrigin, Placement, RobotError, TOOL};
use capp_core::{pips, Joint, JointKind, Robot};
use common::*;

#[test]
fn pips_forward_kinematics_matches_the_independent_golden_file() {
    let robot = pips::robot::<18>().unwrap();
    let text = include_str!("golden/pips_fk.csv");
    let mut frames = Frames::<18>::default();
    let mut rows = 0;
    for line in text.lines() {
        let v: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
        assert_eq!(v.len(), 18 + 18 * 3 + 9);
        let q: Vec<f32> = v[..18].iter().map(|&x| x as f32).collect();
        forward_kinematics(&robot, &q, &mut frames);
        for k in 0..18 {
            let o = frames.link_end(k);
            for axis in 0..3 {
                let expect = v[18 + 3 * k + axis];
                // f32 over an 18-link, ~150 in chain: a few thousandths of an inch.
                assert!(
                    (o[axis] as f64 - expect).abs() < 2e-3,
                    "row {rows} origin {k} axis {axis}: {} vs {expect}",
                    o[axis]
                );
            }
        }
        let r = frames.end_rotation();
        for i in 0..3 {
            for j in 0..3 {
                let expect = v[18 + 54 + 3 * i + j];
                assert!(
                    (r[(i, j)] as f64 - expect).abs() < 1e-5,
                    "row {rows} R[{i}][{j}]"
                );
            }
        }
        rows += 1;
    }
    assert_eq!(rows, 41, "home plus 40 random configurations");
}

/// Robots to differentiate: PIPS, random DH chains of 3 to 32 joints, a DH
/// chain with a tool, PIPS as general joints, and random general chains
/// (URDF-style origins and axes) with tools.
fn robots(rng: &mut Rng) -> Vec<(Vec<capp_core::Joint>, Placement)> {
    let mut out = vec![(pips::joints().to_vec(), Placement::IDENTITY)];
    for n in [3, 7, 12, 20, 32] {
        out.push((random_chain(rng, n), Placement::IDENTITY));
    }
    let (_, tool) = random_general_chain(rng, 1);
    out.push((random_chain(rng, 6), tool));
    out.push(dh_as_general(&pips::joints()));
    for n in [1, 4, 7, 16, 32] {
        out.push(random_general_chain(rng, n));
    }
    out
}

#[test]
fn jacobian_transpose_products_match_central_differences() {
    let mut rng = Rng(7);
    let mut frames = Frames::<32>::default();
    let mut exact = [0.0f32; 32];
    for (joints, tool) in robots(&mut rng) {
        let robot = Robot::<32>::new_with_tool(&joints, &tool).unwrap();
        let n = joints.len();
        for _ in 0..20 {
            let q = random_config(&mut rng, &joints);
            forward_kinematics(&robot, &q, &mut frames);
            let q64: Vec<f64> = q.iter().map(|&x| x as f64).collect();
            let force = [
                rng.uniform(-1.0, 1.0),
                rng.uniform(-1.0, 1.0),
                rng.uniform(-1.0, 1.0),
            ];
            let f32force =
                nalgebra::Vector3::new(force[0] as f32, force[1] as f32, force[2] as f32);
            // Position: (J_4^T f)_j = d(f . p)/dq_j.
            end_point_force(&robot, &frames, &f32force, &mut exact[..n]);
            let fd = central(&joints, &tool, &q64, |c| {
                dot(force, *c.origins.last().unwrap())
            });
            assert_close(&exact[..n], &fd, "position column");
            // Orientation columns: (J_u^T e)_j = d(e . u_i)/dq_j.
            for col in 0..3 {
                let u = frames.end_rotation().column(col).into_owned();
                end_direction_error(&robot, &frames, &u, &f32force, &mut exact[..n]);
                let fd = central(&joints, &tool, &q64, |c| {
                    let r = c.rotations.last().unwrap();
                    dot(force, [r[0][col], r[1][col], r[2][col]])
                });
                assert_close(&exact[..n], &fd, "orientation column");
            }
            // J qdot (the end-effector twist) against the derivative along qdot.
            let rate: Vec<f32> = (0..n).map(|_| rng.uniform(-1.0, 1.0) as f32).collect();
            let (v, _w) = end_twist(&robot, &frames, &rate);
            let h = 1e-6;
            let plus: Vec<f64> = q64
                .iter()
                .zip(&rate)
                .map(|(q, r)| q + h * *r as f64)
                .collect();
            let minus: Vec<f64> = q64
                .iter()
                .zip(&rate)
                .map(|(q, r)| q - h * *r as f64)
                .collect();
            let (pp, pm) = (
                fk64_tool(&joints, &tool, &plus),
                fk64_tool(&joints, &tool, &minus),
            );
            let fd_v = scale(
                sub(*pp.origins.last().unwrap(), *pm.origins.last().unwrap()),
                0.5 / h,
            );
            for axis in 0..3 {
                let size = dot(fd_v, fd_v).sqrt().max(1.0);
                assert!(
                    (v[axis] as f64 - fd_v[axis]).abs() < 2e-3 * size,
                    "twist {v:?} vs {fd_v:?}"
                );
            }
        }
    }
}

/// Central differences of `f(chain(q))` in f64, step 1e-6.
fn central(
    joints: &[capp_core::Joint],
    tool: &Placement,
    q: &[f64],
    f: impl Fn(&Chain64) -> f64,
) -> Vec<f64> {
    let h = 1e-6;
    (0..q.len())
        .map(|j| {
            let mut plus = q.to_vec();
            let mut minus = q.to_vec();
            plus[j] += h;
            minus[j] -= h;
            (f(&fk64_tool(joints, tool, &plus)) - f(&fk64_tool(joints, tool, &minus))) / (2.0 * h)
        })
        .collect()
}

/// Entry-wise agreement relative to the vector's size (f32 against f64).
pub fn assert_close(exact: &[f32], fd: &[f64], what: &str) {
    let size = fd.iter().map(|x| x * x).sum::<f64>().sqrt().max(1.0);
    for (j, (&e, &d)) in exact.iter().zip(fd).enumerate() {
        assert!(
            (e as f64 - d).abs() <= 1e-4 * size + 1e-4,
            "{what}, joint {j}: exact {e} vs finite difference {d}"
        );
    }
}

/// Every frame of `robot` at `q` against the f64 URDF-convention chain.
fn assert_frames_match(
    robot: &Robot<32>,
    joints: &[Joint],
    tool: &Placement,
    q: &[f32],
    what: &str,
) {
    let mut frames = Frames::<32>::default();
    forward_kinematics(robot, q, &mut frames);
    let q64: Vec<f64> = q.iter().map(|&x| x as f64).collect();
    let chain = fk64_tool(joints, tool, &q64);
    let n = joints.len();
    let size = chain
        .origins
        .iter()
        .map(|o| dot(*o, *o).sqrt())
        .fold(1.0f64, f64::max);
    for k in 0..n {
        let (pivot, end) = (frames.pivot(k), frames.link_end(k));
        for axis in 0..3 {
            for (got, expect, which) in [
                (pivot[axis], chain.origins[k][axis], "pivot"),
                (end[axis], chain.origins[k + 1][axis], "link end"),
            ] {
                assert!(
                    (got as f64 - expect).abs() < 2e-6 * size * n as f64,
                    "{what}: joint {k} {which} axis {axis}: {got} vs {expect}"
                );
            }
        }
    }
    let r = frames.end_rotation();
    let r64 = chain.rotations.last().unwrap();
    for i in 0..3 {
        for j in 0..3 {
            assert!(
                (r[(i, j)] as f64 - r64[i][j]).abs() < 2e-6 * n as f64,
                "{what}: end rotation [{i}][{j}]: {} vs {}",
                r[(i, j)],
                r64[i][j]
            );
        }
    }
}

#[test]
fn general_joints_match_the_urdf_convention_chain_in_f64() {
    let mut rng = Rng(23);
    for n in [1, 2, 5, 9, 18, 32] {
        for round in 0..10 {
            let (joints, tool) = random_general_chain(&mut rng, n);
            let robot = Robot::<32>::new_with_tool(&joints, &tool).unwrap();
            assert!(robot.is_general());
            for _ in 0..5 {
                let q = random_config(&mut rng, &joints);
                assert_frames_match(
                    &robot,
                    &joints,
                    &tool,
                    &q,
                    &format!("{n} joints, round {round}"),
                );
            }
        }
    }
}

#[test]
fn pips_as_general_joints_is_the_same_arm_as_its_dh_table() {
    let dh = pips::robot::<18>().unwrap();
    let (joints, tool) = dh_as_general(&pips::joints());
    let general = Robot::<18>::new_with_tool(&joints, &tool).unwrap();
    assert!(general.is_general() && !dh.is_general());
    // The core's own conversion (f32) builds the same arm.
    let mut converted = pips::joints();
    let core_tool = capp_core::robot::general_from_dh(&pips::joints(), &mut converted);
    let from_core = Robot::<18>::new_with_tool(&converted, &core_tool).unwrap();
    let mut c = Frames::<18>::default();
    let mut rng = Rng(5);
    let (mut a, mut b) = (Frames::<18>::default(), Frames::<18>::default());
    for round in 0..200 {
        let q = if round == 0 {
            pips::home().to_vec()
        } else {
            random_config(&mut rng, &pips::joints())
        };
        forward_kinematics(&dh, &q, &mut a);
        forward_kinematics(&general, &q, &mut b);
        forward_kinematics(&from_core, &q, &mut c);
        assert!((b.end_position() - c.end_position()).norm() < 1e-3);
        assert!((b.end_rotation() - c.end_rotation()).norm() < 1e-5);
        for k in 0..18 {
            let (pa, pb) = (a.pivot(k), b.pivot(k));
            let (ea, eb) = (a.link_end(k), b.link_end(k));
            // inches, over a chain of about 150 in
            assert!(
                (pa - pb).norm() < 2e-3,
                "round {round}, pivot {k}: {pa:?} vs {pb:?}"
            );
            assert!((ea - eb).norm() < 2e-3, "round {round}, link end {k}");
            assert!(
                (a.axis(k) - b.axis(k)).norm() < 1e-5,
                "round {round}, axis {k}"
            );
        }
        assert!((a.end_rotation() - b.end_rotation()).norm() < 1e-5);
        // The chord bounds hold in both forms, and agree for revolute
        // links (a prismatic general link's bound is the looser sum
        // travel + offset, the DH one the exact hypotenuse).
        for (k, joint) in pips::joints().iter().enumerate() {
            for (robot, frames) in [(&dh, &a), (&general, &b)] {
                let chord = (frames.link_end(k) - frames.pivot(k)).norm();
                assert!(
                    chord <= robot.longest_link(k) + 1e-3,
                    "round {round}, chord {k}"
                );
            }
            if joint.kind == JointKind::Revolute {
                let (l, m) = (dh.longest_link(k), general.longest_link(k));
                assert!((l - m).abs() < 1e-3, "longest {k}: {l} vs {m}");
            }
        }
        assert!(general.reach() + 1e-2 >= dh.reach());
    }
}

#[test]
fn bad_general_joints_and_tools_are_refused_with_the_joint_named() {
    let (joints, tool) = dh_as_general(&pips::joints()[..4]);
    assert!(Robot::<8>::new_with_tool(&joints, &tool).is_ok());
    // A scaled rotation, a reflection, a zero axis, a NaN axis, a mixed chain, a bad tool.
    let mut scaled = joints.clone();
    scaled[2].origin.as_mut().unwrap().placement.rotation[0][0] *= 1.01;
    assert_eq!(
        Robot::<8>::new_with_tool(&scaled, &tool).err(),
        Some(RobotError::NotRotation { joint: 2 })
    );
    let mut reflected = joints.clone();
    reflected[1].origin.as_mut().unwrap().placement.rotation[2] = [0.0, 0.0, -1.0];
    reflected[1].origin.as_mut().unwrap().placement.rotation[0] = [1.0, 0.0, 0.0];
    reflected[1].origin.as_mut().unwrap().placement.rotation[1] = [0.0, 1.0, 0.0];
    assert_eq!(
        Robot::<8>::new_with_tool(&reflected, &tool).err(),
        Some(RobotError::NotRotation { joint: 1 })
    );
    let mut zero = joints.clone();
    zero[3].origin.as_mut().unwrap().axis = [0.0, 1e-4, 0.0];
    assert_eq!(
        Robot::<8>::new_with_tool(&zero, &tool).err(),
        Some(RobotError::ZeroAxis { joint: 3 })
    );
    let mut nan = joints.clone();
    nan[0].origin.as_mut().unwrap().axis = [f32::NAN, 0.0, 1.0];
    assert!(matches!(
        Robot::<8>::new_with_tool(&nan, &tool).err(),
        Some(RobotError::NotFinite { joint: 0, .. })
    ));
    let mut mixed = joints.clone();
    mixed[2] = pips::joints()[2];
    assert_eq!(
        Robot::<8>::new_with_tool(&mixed, &tool).err(),
        Some(RobotError::MixedJoints { joint: 2 })
    );
    let mut bad_tool = tool;
    bad_tool.rotation[1][1] = 2.0;
    let err = Robot::<8>::new_with_tool(&joints, &bad_tool).err();
    assert_eq!(err, Some(RobotError::NotRotation { joint: TOOL }));
    assert_eq!(
        err.unwrap().to_string(),
        "the tool: origin rotation is not a proper rotation"
    );
    let mut far = joints.clone();
    far[1].origin.as_mut().unwrap().placement.translation = [2e4, 0.0, 0.0];
    assert!(matches!(
        Robot::<8>::new_with_tool(&far, &tool).err(),
        Some(RobotError::OutOfRange { joint: 1, .. })
    ));
    // A general joint refused by one robot is accepted by a fresh one: no state kept.
    let origin = JointOrigin {
        placement: Placement::IDENTITY,
        axis: [0.0, 0.0, 2.0],
    };
    let single = [Joint::general(JointKind::Revolute, origin, -1.0, 1.0, 1.0)];
    assert!(Robot::<8>::new(&single).unwrap().is_general());
}
