//! Forward kinematics against an independent golden file, and every exact
//! derivative against central finite differences in f64.

mod common;

use capp_core::kinematics::{
    end_direction_error, end_point_force, end_twist, forward_kinematics, Frames,
};
use capp_core::{pips, Robot};
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

/// Robots to differentiate: PIPS and random chains of 3 to 32 joints.
fn robots(rng: &mut Rng) -> Vec<Vec<capp_core::Joint>> {
    let mut out = vec![pips::joints().to_vec()];
    for n in [3, 7, 12, 20, 32] {
        out.push(random_chain(rng, n));
    }
    out
}

#[test]
fn jacobian_transpose_products_match_central_differences() {
    let mut rng = Rng(7);
    let mut frames = Frames::<32>::default();
    let mut exact = [0.0f32; 32];
    for joints in robots(&mut rng) {
        let robot = Robot::<32>::new(&joints).unwrap();
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
            let fd = central(&joints, &q64, |c| dot(force, *c.origins.last().unwrap()));
            assert_close(&exact[..n], &fd, "position column");
            // Orientation columns: (J_u^T e)_j = d(e . u_i)/dq_j.
            for col in 0..3 {
                let u = frames.end_rotation().column(col).into_owned();
                end_direction_error(&robot, &frames, &u, &f32force, &mut exact[..n]);
                let fd = central(&joints, &q64, |c| {
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
            let (pp, pm) = (fk64(&joints, &plus), fk64(&joints, &minus));
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
fn central(joints: &[capp_core::Joint], q: &[f64], f: impl Fn(&Chain64) -> f64) -> Vec<f64> {
    let h = 1e-6;
    (0..q.len())
        .map(|j| {
            let mut plus = q.to_vec();
            let mut minus = q.to_vec();
            plus[j] += h;
            minus[j] -= h;
            (f(&fk64(joints, &plus)) - f(&fk64(joints, &minus))) / (2.0 * h)
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
