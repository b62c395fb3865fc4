//! From a proposed rate to a motion: the rate bounded by the joint limits
//! and by conservative advancement, then the clamped Euler step
//! `q' = clamp(q + h qdot)`.

use crate::evaluation::Evaluation;
use crate::math::all_finite;
use crate::robot::Robot;
use crate::scenario::Scenario;
use crate::step_size::advancement;

/// Bounds the law's `rate` for a step of at most `h` seconds from `q`
/// (evaluated as `now`) and returns the step: a rate that is not finite
/// becomes zero; a joint that would pass a limit within `h` stops at it (the
/// step is then the straight segment to the clamped point, so every shorter
/// step is a part of it and stays within the limits); no avoidance point
/// may travel farther than its clearance allows
/// ([`crate::step_size::advancement`]).
#[inline]
pub fn bound<const N: usize, const M: usize, const W: usize>(
    scenario: &Scenario<N, M, W>,
    now: &Evaluation<N>,
    q: &[f32],
    rate: &mut [f32],
    h: f32,
) -> f32 {
    let robot = scenario.robot();
    let n = robot.len().min(N).min(rate.len());
    let rate = &mut rate[..n];
    if !all_finite(rate) {
        rate.fill(0.0);
    }
    if h > 0.0 {
        for ((r, &qj), joint) in rate.iter_mut().zip(q).zip(robot.joints()) {
            let end = joint.clamp(qj + h * *r);
            if end != qj + h * *r {
                *r = (end - qj) / h;
            }
        }
    }
    advancement(
        robot,
        &now.frames,
        &now.distance_sq[..n],
        now.field.nearest.as_ref(),
        rate,
        h,
        scenario.settings().avoidance.advance_fraction,
    )
}

/// `q_next = clamp(q + h rate)`, joint by joint.
#[inline]
pub fn integrate<const N: usize>(
    robot: &Robot<N>,
    q: &[f32],
    rate: &[f32],
    h: f32,
    q_next: &mut [f32],
) {
    for (((next, &qj), &r), joint) in q_next.iter_mut().zip(q).zip(rate).zip(robot.joints()) {
        *next = joint.clamp(qj + h * r);
    }
}
