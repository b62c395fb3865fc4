//! What the fuzz targets share: a bounded planner run that checks the
//! invariants every step must keep, whatever the (valid) problem.

use capp_core::{Phase, Planner, Scenario};

/// Steps planned per input: enough to leave the start, bounded so each input
/// takes milliseconds.
pub const STEPS: u32 = 48;

/// Plans up to [`STEPS`] steps from `start` (which may be refused) and checks
/// after each: joints finite and within their limits, no joint faster than its
/// rate limit, `V` and the errors not NaN, the step count honest.
pub fn plan_a_few_steps<const N: usize, const M: usize, const W: usize>(
    scenario: &Scenario<N, M, W>,
    start: &[f32],
) {
    let Ok(mut planner) = Planner::new(scenario, start) else {
        return;
    };
    let joints = scenario.robot().joints();
    let mut previous = [0.0f32; N];
    previous[..joints.len()].copy_from_slice(planner.joints());
    for k in 1..=STEPS {
        let report = planner.step(scenario).expect("the planner's own scenario");
        let q = planner.joints();
        assert!(report.step <= k && report.step <= scenario.settings().max_steps);
        assert!(report.time_step_s.is_finite() && report.time_step_s >= 0.0);
        assert!(!report.v.is_nan(), "V is NaN: {report:?}");
        assert!(!report.position_error.is_nan() && !report.orientation_error.is_nan());
        for (j, joint) in joints.iter().enumerate() {
            assert!(q[j].is_finite(), "joint {j} not finite");
            assert!(
                q[j] >= joint.min && q[j] <= joint.max,
                "joint {j} = {} outside [{}, {}]",
                q[j],
                joint.min,
                joint.max
            );
            let moved = (q[j] - previous[j]).abs();
            let allowed = report.time_step_s * joint.max_rate * (1.0 + 1e-5)
                + 4.0 * f32::EPSILON * q[j].abs().max(previous[j].abs());
            assert!(moved <= allowed, "joint {j} moved {moved} > {allowed}");
        }
        previous[..joints.len()].copy_from_slice(q);
        if let Phase::Done(_) = report.phase {
            return;
        }
    }
}
