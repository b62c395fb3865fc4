//! Collision avoidance by projection (paper eqs. 21-24).
//!
//! With `mu = dP/dq` the potential's gradient (eq. 20), `dP/dt = mu . qdot`
//! (eq. 21). The paper removes from the weighted rate its component along
//! `mu_hat = mu / |mu|`:
//!
//! ```text
//! qdot = (I - mu_hat mu_hat^T) M eps_hat                      (eq. 24)
//! ```
//!
//! after the weighting, as the equation says (CAPP.c projected the Jacobian
//! before `M`, which matches only for `M = cI`). Two changes:
//!
//! * **one-sided**: only a rate that *approaches* the obstacles (`mu . qdot > 0`)
//!   is projected; motion away from them is left alone.
//! * **engaged near contact**: the paper's rule (`dP/dt <= 0` always) forbids
//!   ever getting closer to anything, so an arm cannot pass an obstacle it
//!   must go near. Here the approaching component is removed in full only once
//!   the closest pair's `C - 1` is below `engage_clearance`, not at all above
//!   twice that, and in proportion between: the arm slows its approach and
//!   then slides along the obstacle. Entry is still impossible: the planner
//!   never accepts a step that puts a point inside an inflated obstacle.
//! * **locked joints**: a joint held at a limit cannot take the correction, so
//!   the projection is done in the subspace of the free joints (`mu_i = 0` for
//!   locked ones), which keeps `mu . qdot = 0` exact after the integrator clamps.
//!
//! Obstacles beyond the influence distance contribute nothing to `mu` (see
//! [`crate::avoidance`]), so they do not constrain the arm at all.

use crate::math::{max, min};
use crate::robot::Robot;

/// Whether joint `j` at `q` would be pushed past a limit by `rate`.
#[inline]
fn blocked(min: f32, max: f32, q: f32, rate: f32) -> bool {
    (q <= min && rate < 0.0) || (q >= max && rate > 0.0)
}

/// How much of the approaching component to remove, from the closest pair's
/// clearance `c = C - 1`: all of it at `c <= engage`, none at `c >= 2 engage`,
/// linear between; all of it when `engage` is 0 (the paper's rule).
pub fn strength(clearance: Option<f32>, engage: f32) -> f32 {
    match clearance {
        None => 0.0,
        Some(c) if engage > 0.0 => min(max((2.0 * engage - c) / engage, 0.0), 1.0),
        Some(_) => 1.0,
    }
}

/// Fraction of `engage_clearance` (in `C - 1`) below which a step may not
/// bring the closest pair closer: the arm stops short of resting on an
/// inflated surface (where `f32` rounding decides contact) instead of
/// creeping onto it in ever smaller steps.
pub const CONTACT_FLOOR: f32 = 0.01;

/// A one-sided limit on a step's approach to obstacles, for the laws that
/// project in their own metric (damped least squares, joint-space moves):
/// after projection `gradient . dq` is at most [`Guard::allowed`].
#[derive(Clone, Copy, Debug)]
pub struct Guard<'a> {
    /// The gradient of a potential that grows as the arm approaches
    /// (`n` values): eq. 20's `mu = dP/dq`.
    pub gradient: &'a [f32],
    /// How much of the approach to remove, in `[0, 1]` ([`strength`]).
    pub strength: f32,
    /// How far to move away while travelling, in the potential's units
    /// ([`retreat`]).
    pub retreat: f32,
    /// How much closer the final approach may come in one step, in the
    /// potential's units ([`approach`]): a target near an obstacle lies
    /// inside the band the retreat keeps the arm out of.
    pub approach: f32,
}

impl<'a> Guard<'a> {
    /// The guard of a configuration with obstacle gradient `gradient` whose
    /// closest pair is at `clearance` (`C - 1`): [`strength`], [`retreat`]
    /// and [`approach`] for the projection engaged below `engage` and the
    /// final approach stopping at `contact_floor` of it.
    pub fn at(
        gradient: &'a [f32],
        clearance: Option<f32>,
        engage: f32,
        contact_floor: f32,
    ) -> Self {
        Guard {
            gradient,
            strength: strength(clearance, engage),
            retreat: retreat(clearance, engage),
            approach: approach(clearance, engage, contact_floor),
        }
    }

    /// The most `gradient . dq` may be for a step whose unprojected value is
    /// `approach`, or `None` when the step needs no projection: travelling,
    /// `(1 - strength) max(approach, 0) - retreat`; on the final approach,
    /// `(1 - strength) max(approach, 0) + strength approach_allowance`.
    pub fn allowed(&self, approach: f32, final_approach: bool) -> Option<f32> {
        if self.strength <= 0.0 || self.strength.is_nan() {
            return None;
        }
        let strength = min(self.strength, 1.0);
        let allowed = if final_approach {
            (1.0 - strength) * max(approach, 0.0) + strength * self.approach
        } else {
            (1.0 - strength) * max(approach, 0.0) - max(self.retreat, 0.0)
        };
        (approach > allowed && approach.is_finite() && allowed.is_finite()).then_some(allowed)
    }
}

/// Fraction of the potential's excess over its engaged level that the damped
/// law's projection removes per step (see [`retreat`]).
pub const RETREAT_GAIN: f32 = 0.2;

/// How far, in potential (eq. 26), the damped law's step must move away from
/// the obstacles, from the closest pair's clearance `c`: `RETREAT_GAIN (1/c -
/// 1/engage)` once `c` is below `engage`, 0 above it (and for the paper's
/// rule, `engage = 0`, which has no band to return to). A step that only
/// stops approaching (`mu . dq = 0`) still loses clearance along a curved
/// surface, to second order; this puts it back, geometrically: for one pair
/// `dP = -dc / c^2`, so `dc = RETREAT_GAIN c (1 - c / engage)` per step.
pub fn retreat(clearance: Option<f32>, engage: f32) -> f32 {
    match clearance {
        Some(c) if engage > 0.0 && c > 0.0 && c < engage => RETREAT_GAIN * (1.0 / c - 1.0 / engage),
        _ => 0.0,
    }
}

/// Fraction of its way down to the contact floor that the closest pair may
/// come closer in one step of the final approach (see [`approach`]).
pub const APPROACH_GAIN: f32 = 0.5;

/// How much the damped law's final approach may raise the potential in one
/// step, from the closest pair's clearance `c`: `APPROACH_GAIN (c - floor) /
/// c^2` with `floor = contact_floor * engage` (negative below the floor). For
/// one pair `dP = -dc / c^2`, so the pair may come `APPROACH_GAIN` of the way
/// to the floor per step: a target next to an obstacle is reached
/// geometrically, never the surface.
pub fn approach(clearance: Option<f32>, engage: f32, contact_floor: f32) -> f32 {
    let floor = contact_floor * engage;
    match clearance {
        Some(c) if c > 0.0 => APPROACH_GAIN * (c - floor) / (c * c),
        _ => 0.0,
    }
}

/// Removes the fraction `strength` (in `[0, 1]`) of the component of `rate`
/// (`n` values) that approaches the obstacles; with strength 1, afterwards
/// `mu . rate <= 0`. `locked` is scratch of `n` flags. Returns whether the
/// rate was constrained.
pub fn project<const N: usize>(
    robot: &Robot<N>,
    q: &[f32],
    mu: &[f32],
    strength: f32,
    rate: &mut [f32],
    locked: &mut [bool],
) -> bool {
    if strength.is_nan() || strength <= 0.0 {
        return false;
    }
    let n = robot.len();
    let joints = &robot.joints()[..n];
    // Inputs shorter than the robot (no caller passes them): left alone.
    let (Some(q), Some(mu), Some(rate), Some(locked)) = (
        q.get(..n),
        mu.get(..n),
        rate.get_mut(..n),
        locked.get_mut(..n),
    ) else {
        return false;
    };
    // A rate into a limit the joint already sits at will be clamped away by the
    // integrator: drop it now, so the projection sees the motion that happens.
    // (Zipped iterators rather than indices: no bounds checks, no panic path.)
    for (((joint, &qj), r), l) in joints
        .iter()
        .zip(q)
        .zip(rate.iter_mut())
        .zip(locked.iter_mut())
    {
        *l = blocked(joint.min, joint.max, qj, *r);
        if *l {
            *r = 0.0;
        }
    }
    // Two passes: a free joint at a limit that the first correction would push
    // into it is locked and the correction recomputed. Bounded work.
    for pass in 0..2 {
        let approach: f32 = mu.iter().zip(rate.iter()).map(|(m, r)| m * r).sum();
        let size_sq: f32 = mu
            .iter()
            .zip(locked.iter())
            .filter(|(_, &l)| !l)
            .map(|(m, _)| m * m)
            .sum();
        if !(approach > 0.0 && size_sq > 0.0 && approach.is_finite() && size_sq.is_finite()) {
            return pass > 0;
        }
        let k = min(strength, 1.0) * approach / size_sq;
        let mut newly_locked = false;
        for (((joint, &qj), (&r, &m)), l) in joints
            .iter()
            .zip(q)
            .zip(rate.iter().zip(mu))
            .zip(locked.iter_mut())
        {
            if !*l && blocked(joint.min, joint.max, qj, r - k * m) {
                *l = true;
                newly_locked = true;
            }
        }
        if newly_locked && pass == 0 {
            continue;
        }
        for ((r, &m), &l) in rate.iter_mut().zip(mu).zip(locked.iter()) {
            if !l {
                *r -= k * m;
            }
        }
        return true;
    }
    true
}

/// Scales `rate` uniformly so that no joint exceeds its rate limit; keeps the
/// direction (so orthogonality to `mu` and descent survive). Returns the scale.
pub fn limit_rates<const N: usize>(robot: &Robot<N>, rate: &mut [f32]) -> f32 {
    let worst = robot
        .joints()
        .iter()
        .zip(rate.iter())
        .map(|(joint, r)| r.abs() / joint.max_rate)
        .fold(0.0f32, max);
    if worst > 1.0 {
        let k = 1.0 / worst;
        rate.iter_mut().for_each(|r| *r *= k);
        k
    } else {
        1.0
    }
}
