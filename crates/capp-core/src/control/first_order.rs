//! The first-order laws as one step of the planner: the gradient law and eq.
//! 15 ([`super::weighted_rate`]), the Euclidean one-sided projection (eq. 24,
//! [`crate::projection`]), the rate limits, and the listing's step with its
//! descent and stiffness bounds ([`crate::step_size`]).

use crate::control::{descent_rate, lyapunov_terms, weighted_rate, LawInput, Proposal};
use crate::kinematics::{column_sizes, end_twist};
use crate::math::{all_finite, dot_slice, min};
use crate::projection::{limit_rates, project, strength};
use crate::step_size;

/// Buffers of the first-order laws, sized once for `N` joints.
#[derive(Clone, Debug)]
pub struct FirstOrderWorkspace<const N: usize> {
    /// `J_i^T e_i` of the four terms (eqs. 13-14).
    terms: [[f32; N]; 4],
    /// The drive direction `eps`.
    drive: [f32; N],
    /// Per-joint gains of the gradient law (`rate_j = gain_j G_j`).
    gain: [f32; N],
    /// Weighted squared Jacobian column sizes (for the stiffness bound).
    columns: [f32; N],
    /// Joints held at a limit during the projection.
    locked: [bool; N],
}

impl<const N: usize> Default for FirstOrderWorkspace<N> {
    fn default() -> Self {
        FirstOrderWorkspace {
            terms: [[0.0; N]; 4],
            drive: [0.0; N],
            gain: [0.0; N],
            columns: [0.0; N],
            locked: [false; N],
        }
    }
}

impl<const N: usize> FirstOrderWorkspace<N> {
    /// Every buffer to zero, in place.
    pub fn clear(&mut self) {
        // Every field is named: a field added here fails to compile.
        let FirstOrderWorkspace {
            terms,
            drive,
            gain,
            columns,
            locked,
        } = self;
        for t in terms.iter_mut() {
            t.fill(0.0);
        }
        drive.fill(0.0);
        gain.fill(0.0);
        columns.fill(0.0);
        locked.fill(false);
    }
}

/// One step's rate (into `rate`, per second) and step size for the arm of
/// `input`: the weighted rate (eqs. 15, 18), the Euclidean projection (eq.
/// 24, its strength from `input`'s closest pair), the rate limits, and the
/// listing's step with its descent and stiffness bounds. `rate` holds
/// `robot.len()` values.
// Not inlined into `propose`: one copy of each law, as before the
// interface (flash).
#[inline(never)]
pub fn first_order_rate<const N: usize>(
    input: &LawInput<'_, N>,
    ws: &mut FirstOrderWorkspace<N>,
    rate: &mut [f32],
) -> Proposal {
    let (robot, frames, error, law) = (input.robot, input.frames, input.error, input.law);
    let engage = strength(input.clearance, input.engage_clearance);
    let n = robot.len();
    let (q, mu) = (
        &input.q[..n.min(input.q.len())],
        &input.mu[..n.min(input.mu.len())],
    );
    let len = n.min(rate.len());
    let rate = &mut rate[..len];
    lyapunov_terms(robot, frames, error, &mut ws.terms);
    let drive = weighted_rate(
        robot,
        q,
        error,
        &ws.terms,
        law,
        &mut ws.drive,
        rate,
        &mut ws.gain,
    );
    let constrained = project(robot, q, mu, engage, rate, &mut ws.locked[..len]);
    limit_rates(robot, rate);
    if !all_finite(rate) {
        rate.fill(0.0);
    }
    let mut h = step_size::listing(&input.step, error, input.error_step);
    let descent = descent_rate(&ws.terms, law, rate);
    if descent > 0.0 {
        let twist = end_twist(robot, frames, rate);
        h = min(
            h,
            step_size::descent_bound(descent, twist, law.orientation_scale),
        );
    }
    column_sizes(robot, frames, law.orientation_scale, &mut ws.columns[..len]);
    let stiffness = dot_slice(&ws.gain[..len], &ws.columns[..len]);
    h = min(h, step_size::stiffness_bound(stiffness));
    Proposal {
        drive,
        constrained,
        time_step_s: h,
        may_rise: constrained,
        arrival_s: f32::INFINITY,
    }
}
