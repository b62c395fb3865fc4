//! How long a step is: the listing's rule and the bounds every candidate step
//! must respect before it is integrated.
//!
//! * [`listing`]: CAPP.c's rule, `h_max` far from the target,
//!   `|err / err_dot| h_max` when the last step's change would overshoot,
//!   `fine_step_fraction * h_max` within `fine_radius` (the first-order laws).
//! * [`descent_bound`]: never predict removing more than all of `V`: the
//!   Gauss-Newton step along the rate (first-order laws).
//! * [`stiffness_bound`]: no mode of the linearised error overshoots, so the
//!   rates do not chatter (first-order laws).
//! * [`advancement`]: conservative advancement, for every law: no avoidance
//!   point may travel, during the step, more than a fraction of its distance to
//!   the nearest inflated obstacle. A larger step cannot jump through anything.
//!
//! ## Conservative advancement
//!
//! The step moves the joints along the straight segment `q(s) = q + s h qdot`,
//! `s` in `[0, 1]` (what a joint controller interpolating between setpoints
//! does). A point `p` on link `k` then travels at most
//!
//! ```text
//! |J_p h qdot| + R_k Phi_r^2 + Phi_r Phi_p
//! ```
//!
//! where `Phi_r` and `Phi_p` sum `|h qdot_j|` over the revolute and prismatic
//! joints up to `k`, and `R_k` is the chain length to the end of link `k`
//! ([`crate::Robot::reach`] is the last one). Why: the path length is at most
//! `|p'(0)| + sup |p''| / 2`, and `p'' = sum_ij dq_i dq_j d2p/dq_i dq_j` with
//! `|d2p/dq_i dq_j| <= 2 R_k` for two revolute joints (a rotation of the
//! lever `z_j x (p - o_j)` by joint `i`), `<= 1` (`z_i x z_j`) for a revolute
//! and a prismatic one, and 0 for two prismatic ones. `J_p h qdot` is linear in
//! `p` along a link (`v(x) = w x x + b`), so a link's worst point is one of its
//! ends. Each link's distance is the lower bound of
//! [`crate::obstacle::Contact::distance_sq`] (it holds for every convex `C`),
//! or the influence distance for a link no obstacle is near.

use crate::control::PoseError;
use crate::kinematics::Frames;
use crate::math::{max, min, Vec3};
use crate::mission::Settings;
use crate::robot::{JointKind, Robot};

/// Fraction of the Gauss-Newton step taken by [`descent_bound`].
pub const STEP_FRACTION: f32 = 0.5;

/// The listing's step rule for the first-order laws: `h_max` far from the
/// target, `|err / err_dot| h_max` when the last step's change (`error_step`,
/// length units) would overshoot the error `err`, and `fine_step_fraction *
/// h_max` within `fine_radius`.
pub fn listing(settings: &Settings, error: &PoseError, error_step: f32) -> f32 {
    let h_max = settings.time_step_s;
    let err = error.position;
    if err > settings.fine_radius {
        if err > error_step.abs() {
            h_max
        } else {
            (err / error_step).abs() * h_max
        }
    } else {
        settings.fine_step_fraction * h_max
    }
}

/// The largest step that does not predict removing more than all of `V`:
/// to first order `V(h) = V - h G.qdot`; the Gauss-Newton step along the rate,
/// `V(h) ~ 1/2 |e - h J qdot|^2`, is least at `h = G.qdot / |J qdot|^2`
/// (orientation rows weighted by `lambda^2`; `sum_i |w x u_i|^2 = 2 |w|^2`
/// for an orthonormal frame). `descent = G.qdot`, `(v, w)` the end-effector
/// twist of the rate. Returns [`STEP_FRACTION`] of it, or infinity when the
/// rate does not descend.
pub fn descent_bound(descent: f32, twist: (Vec3, Vec3), orientation_scale: f32) -> f32 {
    let (v, w) = twist;
    let speed_sq = v.dot(&v) + 2.0 * orientation_scale * orientation_scale * w.dot(&w);
    if descent > 0.0 && speed_sq > 0.0 {
        STEP_FRACTION * descent / speed_sq
    } else {
        f32::INFINITY
    }
}

/// No mode of the linearised error may overshoot: with `rate = gain o G`,
/// `e' = -J diag(gain) J^T e`, whose largest eigenvalue is at most the trace
/// `stiffness = sum_j gain_j |J_j|^2`. A step below its inverse makes every
/// mode decay without changing sign, so the rates do not chatter.
pub fn stiffness_bound(stiffness: f32) -> f32 {
    if stiffness > 0.0 {
        1.0 / stiffness
    } else {
        f32::INFINITY
    }
}

/// Conservative advancement (module docs): the largest `h' <= h` for which no
/// avoidance point of any link travels more than `fraction` of that link's
/// obstacle distance (`distance_sq`, its square, one per link) when the
/// joints move by `h' rate`. `rate` and `distance_sq` hold one value per joint.
///
/// Square roots only where a link might be bound: `(a + b)^2 <= 2 (a^2 + b^2)`
/// settles most links in squares (a software square root is some forty
/// instructions on a Cortex-M4F).
pub fn advancement<const N: usize>(
    robot: &Robot<N>,
    frames: &Frames<N>,
    distance_sq: &[f32],
    rate: &[f32],
    h: f32,
    fraction: f32,
) -> f32 {
    // The velocity field of the links so far: v(x) = w x x + b, per unit s.
    let mut w = Vec3::zeros();
    let mut b = Vec3::zeros();
    let (mut phi_r, mut phi_p) = (0.0f32, 0.0f32);
    let mut start_speed_sq = 0.0f32;
    let mut scale = 1.0f32;
    let fraction_sq = fraction * fraction;
    for (j, ((joint, link), (&r, &d_sq))) in robot
        .joints()
        .iter()
        .zip(robot.links())
        .zip(rate.iter().zip(distance_sq))
        .enumerate()
    {
        let step = r * h;
        let z = frames.axis(j);
        match joint.kind {
            JointKind::Revolute => {
                w += z * step;
                b -= z.cross(&frames.pivot(j)) * step;
                phi_r += step.abs();
            }
            JointKind::Prismatic => {
                b += z * step;
                phi_p += step.abs();
            }
        }
        let v = w.cross(&frames.origin(j)) + b;
        let end_speed_sq = v.dot(&v);
        let first_sq = max(start_speed_sq, end_speed_sq);
        let second = link.chain * phi_r * phi_r + phi_r * phi_p;
        start_speed_sq = end_speed_sq;
        let allowed_sq = fraction_sq * d_sq;
        if 2.0 * (first_sq + second * second) <= allowed_sq {
            continue;
        }
        // travel(s h) <= s travel(h) for s <= 1: first-order terms scale with
        // s, second-order ones with s^2.
        let travel = libm::sqrtf(first_sq) + second;
        let allowed = libm::sqrtf(allowed_sq);
        if travel > allowed {
            scale = min(scale, allowed / travel);
        }
    }
    if scale.is_finite() {
        h * max(scale, 0.0)
    } else {
        0.0
    }
}
