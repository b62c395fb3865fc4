//! Driving the joints straight to a configuration: the dead-end escape's
//! walks and its return to the best configuration ([`crate::escape`]), and
//! joint-space waypoints.
//!
//! The step toward `goal` is `dq* = goal - q`, the straight joint-space
//! segment; the metric is the rate limits', `M = diag(qdot_max^2)`, so its
//! length is seconds at the limits and the law, like the damped one, does not
//! depend on the units. Obstacles: the one-sided projection against the
//! potential's gradient `mu` (eq. 24) in that metric,
//!
//! ```text
//! dq = dq* - k M mu,   k = (mu . dq* - allowed) / (mu . M mu)
//! ```
//!
//! with the same [`Guard`] as the damped law (retreat while travelling, a
//! geometric approach within [`FINAL_APPROACH_STEPS`] of the goal). Then the
//! rate is `dq` scaled uniformly so that the most loaded joint runs at its
//! limit, or the whole rest in one step. The planner checks every step like
//! any other (conservative advancement, clearance).

use crate::control::damped::FINAL_APPROACH_STEPS;
use crate::control::{time_at_limits, Drive, LawInput, Proposal};
use crate::math::{dot_slice, max};
use crate::projection::{Guard, CONTACT_FLOOR};
use crate::robot::Robot;

/// How far `q` is from `goal`: seconds for the most loaded joint at its rate
/// limit, `max_j |goal_j - q_j| / qdot_max_j`.
pub fn gap<const N: usize>(robot: &Robot<N>, q: &[f32], goal: &[f32]) -> f32 {
    robot
        .joints()
        .iter()
        .zip(q.iter().zip(goal))
        .map(|(joint, (&qj, &gj))| (gj - qj).abs() / joint.max_rate)
        .fold(0.0f32, max)
}

/// The joint-space counterpart of `V` for a joint goal, seconds squared:
/// `1/2 sum_j ((goal_j - q_j) / qdot_max_j)^2`, so that a step toward the goal
/// lowers it, as a step of the law lowers `V`.
pub fn joint_v<const N: usize>(robot: &Robot<N>, q: &[f32], goal: &[f32]) -> f32 {
    0.5 * robot
        .joints()
        .iter()
        .zip(q.iter().zip(goal))
        .map(|(joint, (&qj, &gj))| {
            let t = (gj - qj) / joint.max_rate;
            t * t
        })
        .sum::<f32>()
}

/// The rate (per second, into `rate`) that takes the joints from
/// `input.q` toward `goal` at the rate limits, projected against the
/// obstacles (eq. 24, the guard from `input`'s gradient and closest pair),
/// for a step of `input.step.time_step_s`. `walk`: an escape's walk, which
/// may raise `V` (it is leaving a dead end); otherwise only a constrained
/// step may. `project`: whether to project (false for a searched path's
/// edge, checked clear by the search). `rate` and `goal` hold
/// `robot.len()` values.
pub fn joint_rate<const N: usize>(
    input: &LawInput<'_, N>,
    goal: &[f32],
    walk: bool,
    project: bool,
    rate: &mut [f32],
) -> Proposal {
    let (robot, q, time_step_s) = (input.robot, input.q, input.step.time_step_s);
    let guard = Guard::at(
        input.mu,
        input.clearance,
        input.engage_clearance,
        CONTACT_FLOOR,
    );
    let n = robot.len().min(rate.len());
    let rate = &mut rate[..n];
    for ((r, &qj), &gj) in rate.iter_mut().zip(q).zip(goal) {
        *r = gj - qj;
    }
    let gap = time_at_limits(robot, rate);
    let mut constrained = false;
    let approach = dot_slice(guard.gradient, rate);
    let allowed = guard
        .allowed(approach, gap <= FINAL_APPROACH_STEPS * time_step_s)
        .filter(|_| project);
    if let Some(allowed) = allowed {
        let metric = |j: usize| {
            robot
                .joints()
                .get(j)
                .map_or(0.0, |joint| joint.max_rate * joint.max_rate)
        };
        let along: f32 = guard
            .gradient
            .iter()
            .enumerate()
            .map(|(j, g)| g * g * metric(j))
            .sum();
        if along > 0.0 && along.is_finite() {
            let k = (approach - allowed) / along;
            for (j, (r, g)) in rate.iter_mut().zip(guard.gradient).enumerate() {
                *r -= k * metric(j) * g;
            }
            constrained = true;
        }
    }
    let time = time_at_limits(robot, rate);
    if !(time > 0.0 && time.is_finite()) {
        rate.fill(0.0);
        return Proposal {
            time_step_s,
            ..Proposal::IDLE
        };
    }
    let arrival_s = max(time, time_step_s);
    let k = 1.0 / arrival_s;
    rate.iter_mut().for_each(|r| *r *= k);
    Proposal {
        drive: Drive::Joints,
        constrained,
        time_step_s,
        may_rise: constrained || walk,
        arrival_s,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::LawSettings;
    use crate::kinematics::{forward_kinematics, Frames};
    use crate::robot::Joint;
    use crate::step_size::StepRule;
    use crate::target::PoseError;

    /// A walk's step toward a configuration is projected when it runs
    /// toward a close obstacle (the gradient `mu` against it, the
    /// clearance inside the engaged band); a searched path's step to the
    /// same configuration is not: it is the straight segment at the rate
    /// limits, whatever `mu` says.
    #[test]
    fn a_walk_is_projected_and_a_searched_path_is_not() {
        let joints = [Joint::revolute(0.0, 1.0, 0.0, -3.0, 3.0, 1.0); 3];
        let robot = Robot::<3>::new(&joints).unwrap();
        let q = [0.1f32, 0.2, 0.3];
        let goal = [0.6f32, -0.3, 0.5];
        let mut frames = Frames::<3>::default();
        forward_kinematics(&robot, &q, &mut frames);
        // The gradient rises along the way to the goal: the motion approaches.
        let mu = [1.0f32, -1.0, 0.5];
        let law = LawSettings::default();
        let error = PoseError::default();
        let input = LawInput {
            robot: &robot,
            frames: &frames,
            q: &q,
            error: &error,
            mu: &mu,
            clearance: Some(0.2),
            law: &law,
            engage_clearance: 1.0,
            step: StepRule {
                time_step_s: 0.05,
                fine_radius: 0.0,
                fine_step_fraction: 1.0,
            },
            error_step: 0.0,
        };
        let (mut walk, mut path) = ([0.0f32; 3], [0.0f32; 3]);
        let walked = joint_rate(&input, &goal, true, true, &mut walk);
        let followed = joint_rate(&input, &goal, true, false, &mut path);
        assert!(walked.constrained && !followed.constrained);
        assert!(dot_slice(&mu, &walk) < dot_slice(&mu, &path));
        // The path's rate is the straight segment with its most loaded
        // joints (0.5 rad each) at their limit (1 rad/s).
        let straight: [f32; 3] = core::array::from_fn(|j| (goal[j] - q[j]) / 0.5);
        for j in 0..3 {
            assert!(
                (path[j] - straight[j]).abs() < 1e-6,
                "{path:?} vs {straight:?}"
            );
        }
        assert!(followed.may_rise);
    }
}
