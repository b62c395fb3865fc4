//! When a waypoint is passed: a pose within the position (and orientation)
//! tolerance, or a joint configuration within a fraction of a time step at
//! the rate limits.

use crate::control::joint_space::gap;
use crate::evaluation::Evaluation;
use crate::scenario::Scenario;
use crate::target::{pose_error, Target};

/// A joint goal is passed when the joints are within this fraction of a
/// time step of it at their rate limits.
pub const JOINT_GOAL_TOLERANCE: f32 = 0.05;

/// Whether the arm at `q` (evaluated as `now`) is within tolerance of
/// `target`. While `detouring`, `now.error` is the detour point's, so the
/// waypoint is judged by its own error.
pub fn within<const N: usize, const M: usize, const W: usize>(
    scenario: &Scenario<N, M, W>,
    q: &[f32],
    now: &Evaluation<N>,
    target: &Target,
    detouring: bool,
) -> bool {
    let settings = scenario.settings();
    match target.joints.and_then(|k| scenario.joint_goal(k)) {
        Some(goal) => gap(scenario.robot(), q, goal) <= JOINT_GOAL_TOLERANCE * settings.time_step_s,
        None => {
            let e = if detouring {
                pose_error(&now.frames, target, settings.law.orientation_scale)
            } else {
                now.error
            };
            e.position <= settings.position_tolerance
                && (!e.has_orientation || e.orientation <= settings.orientation_tolerance)
        }
    }
}
