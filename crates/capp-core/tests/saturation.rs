//! Saturation in the null space (`control::saturation`) against the uniform
//! scaling it replaces, checked with an independent f64 model: it keeps every
//! rate and joint limit, never leaves more of the error after a step nor
//! lowers `V` more slowly (to first order, with a Jacobian from f64 finite
//! differences), usually leaves less, and leaves arms with little redundancy
//! alone.

mod common;

use capp_core::control::damped::{damped_rate, DampedWorkspace};
use capp_core::control::{LawInput, LawSettings};
use capp_core::kinematics::{forward_kinematics, Frames};
use capp_core::math::{vec3, Mat3};
use capp_core::step_size::StepRule;
use capp_core::target::{pose_error, Target};
use capp_core::{Joint, Robot};
use common::*;

const N: usize = 32;

/// The damped law's rate at `q` toward the pose of `goal`, with saturation on or off.
fn rate(
    joints: &[Joint],
    q: &[f32],
    target: &Target,
    saturation: bool,
    time_step_s: f32,
) -> Vec<f32> {
    let robot = Robot::<N>::new(joints).unwrap();
    let mut frames = Frames::<N>::default();
    forward_kinematics(&robot, q, &mut frames);
    let law = LawSettings {
        saturation,
        ..LawSettings::default()
    };
    let error = pose_error(&frames, target, law.orientation_scale);
    let zeros = vec![0.0; joints.len()];
    let input = LawInput {
        robot: &robot,
        frames: &frames,
        q,
        error: &error,
        mu: &zeros,
        clearance: None,
        law: &law,
        engage_clearance: 1.0,
        step: StepRule {
            time_step_s,
            fine_radius: 0.0,
            fine_step_fraction: 1.0,
        },
        error_step: 0.0,
    };
    let mut ws = DampedWorkspace::<N>::default();
    let mut out = vec![0.0; joints.len()];
    damped_rate(&input, &mut ws, &mut out);
    out
}

/// Position and rotation vector (axis times angle) of `R_target R^T`, f64.
fn pose_error64(joints: &[Joint], q: &[f64], target: &([f32; 3], [[f32; 3]; 3])) -> [f64; 6] {
    let chain = fk64(joints, q);
    let p = *chain.origins.last().unwrap();
    let r = *chain.rotations.last().unwrap();
    let rt = target.1.map(|row| row.map(|x| x as f64));
    let e = mat_mul(&rt, &transpose(&r));
    let cos = ((e[0][0] + e[1][1] + e[2][2] - 1.0) / 2.0).clamp(-1.0, 1.0);
    let angle = cos.acos();
    let axis = [e[2][1] - e[1][2], e[0][2] - e[2][0], e[1][0] - e[0][1]];
    let k = if angle > 1e-12 {
        angle / (2.0 * angle.sin())
    } else {
        0.5
    };
    [
        target.0[0] as f64 - p[0],
        target.0[1] as f64 - p[1],
        target.0[2] as f64 - p[2],
        axis[0] * k,
        axis[1] * k,
        axis[2] * k,
    ]
}

/// What is left of the error after the step `dq`, to first order, in eq. 12's
/// weights (orientation rows by `2 l^2`): `|e - J dq|_Lambda`, with `J` by
/// central differences of the f64 model.
fn left_after(
    joints: &[Joint],
    q: &[f32],
    dq: &[f64],
    target: &([f32; 3], [[f32; 3]; 3]),
    l: f64,
) -> f64 {
    let (e0, moved) = first_order(joints, q, dq, target);
    let w = weights(l);
    (0..6)
        .map(|i| w[i] * (e0[i] - moved[i]).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// How fast the step `dq` lowers eq. 12's `V`, to first order:
/// `e^T Lambda J dq`.
fn descent(
    joints: &[Joint],
    q: &[f32],
    dq: &[f64],
    target: &([f32; 3], [[f32; 3]; 3]),
    l: f64,
) -> f64 {
    let (e0, moved) = first_order(joints, q, dq, target);
    let w = weights(l);
    (0..6).map(|i| w[i] * e0[i] * moved[i]).sum()
}

/// Eq. 12's weights `Lambda`, position rows first.
fn weights(l: f64) -> [f64; 6] {
    [1.0, 1.0, 1.0, 2.0 * l * l, 2.0 * l * l, 2.0 * l * l]
}

/// The pose error at `q` and `J dq`, by central differences of the f64 model.
fn first_order(
    joints: &[Joint],
    q: &[f32],
    dq: &[f64],
    target: &([f32; 3], [[f32; 3]; 3]),
) -> ([f64; 6], [f64; 6]) {
    let q64: Vec<f64> = q.iter().map(|&x| x as f64).collect();
    let e0 = pose_error64(joints, &q64, target);
    let mut moved = [0.0f64; 6];
    let h = 1e-6;
    for (j, &d) in dq.iter().enumerate() {
        let mut plus = q64.clone();
        let mut minus = q64.clone();
        plus[j] += h;
        minus[j] -= h;
        let (ep, em) = (
            pose_error64(joints, &plus, target),
            pose_error64(joints, &minus, target),
        );
        for i in 0..6 {
            // d e / d q_j = -J_j.
            moved[i] -= (ep[i] - em[i]) / (2.0 * h) * d;
        }
    }
    (e0, moved)
}

fn target_of(pose: &([f32; 3], [[f32; 3]; 3])) -> Target {
    let rows = pose.1;
    let r = Mat3::from_row_slice(&[
        rows[0][0], rows[0][1], rows[0][2], rows[1][0], rows[1][1], rows[1][2], rows[2][0],
        rows[2][1], rows[2][2],
    ]);
    Target::pose(vec3(pose.0), Some(r))
}

#[test]
fn saturation_keeps_the_limits_and_never_leaves_more_error_than_uniform_scaling() {
    let mut rng = Rng(0x5A7);
    let h = 0.05f32;
    let l = LawSettings::default().orientation_scale as f64;
    let (mut cases, mut better) = (0, 0);
    for case in 0..60 {
        let n = 12 + rng.below(13);
        let joints = random_chain(&mut rng, n);
        let q = random_config(&mut rng, &joints);
        let goal = random_config(&mut rng, &joints);
        let pose = pose_of(&joints, &goal);
        let target = target_of(&pose);
        let uniform = rate(&joints, &q, &target, false, h);
        let saturated = rate(&joints, &q, &target, true, h);
        for (j, ((joint, &r), &qj)) in joints.iter().zip(&saturated).zip(&q).enumerate() {
            assert!(
                r.abs() <= joint.max_rate * (1.0 + 1e-5),
                "case {case}: joint {j} at {r} over its limit {}",
                joint.max_rate
            );
            let end = qj + h * r;
            let slack = 1e-5 * (joint.max - joint.min);
            assert!(
                end >= joint.min - slack && end <= joint.max + slack,
                "case {case}: joint {j} would leave its range ({end})"
            );
        }
        let step = |r: &[f32]| r.iter().map(|&x| (h * x) as f64).collect::<Vec<f64>>();
        let (left_uniform, left_saturated) = (
            left_after(&joints, &q, &step(&uniform), &pose, l),
            left_after(&joints, &q, &step(&saturated), &pose, l),
        );
        assert!(
            left_saturated <= left_uniform * (1.0 + 1e-3) + 1e-6,
            "case {case} ({n} joints): saturation leaves {left_saturated}, uniform scaling {left_uniform}"
        );
        // It never lowers V more slowly than the uniform scaling (to first
        // order): far from the target the damping is large, and a step that
        // leaves less error could still turn away from the gradient.
        let (descent_uniform, descent_saturated) = (
            descent(&joints, &q, &step(&uniform), &pose, l),
            descent(&joints, &q, &step(&saturated), &pose, l),
        );
        assert!(
            descent_saturated >= descent_uniform * (1.0 - 1e-3) - 1e-6,
            "case {case} ({n} joints): saturation lowers V at {descent_saturated}, uniform scaling at {descent_uniform}"
        );
        if saturated != uniform {
            cases += 1;
            // What each removes of the error in one step.
            let before = left_after(&joints, &q, &vec![0.0; n], &pose, l);
            let (removed_uniform, removed_saturated) =
                (before - left_uniform, before - left_saturated);
            if removed_saturated > 1.2 * removed_uniform {
                better += 1;
            }
        }
    }
    // Random far targets need many steps: saturation engages in most cases
    // and removes at least a fifth more of the error per step in three
    // quarters of those (1.2 to 3.5 times as much, measured).
    assert!(
        cases >= 30,
        "saturation engaged in only {cases} of 60 cases"
    );
    assert!(
        better * 4 >= cases * 3,
        "saturation removed a fifth more in only {better} of {cases} cases"
    );
}

#[test]
fn arms_with_little_redundancy_keep_the_uniform_scaling() {
    let mut rng = Rng(0x7E5);
    for (n, orientation) in [(7, true), (11, true), (3, false), (5, false)] {
        for _ in 0..10 {
            let joints = random_chain(&mut rng, n);
            let q = random_config(&mut rng, &joints);
            let goal = random_config(&mut rng, &joints);
            let pose = pose_of(&joints, &goal);
            let mut target = target_of(&pose);
            if !orientation {
                target.orientation = None;
            }
            let on = rate(&joints, &q, &target, true, 0.05);
            let off = rate(&joints, &q, &target, false, 0.05);
            // Fewer than twice the task's rows: saturation does nothing, to the bit.
            assert_eq!(
                on.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                off.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                "{n} joints"
            );
        }
    }
}
