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
//! The step moves the joints along the straight segment `q(s) = q + s dq`,
//! `s` in `[0, 1]`, `dq = h qdot` (what a joint controller interpolating
//! between setpoints does). A point `p` on link `k` then travels at most
//!
//! ```text
//! s |J_p dq| + s^2 Q_k,   Q_k = 1/2 sum_m |dq_m| (2 Phi_<m + |dq_m|) L_mk  +  sum_prismatic j |dq_j| Phi_<j
//! ```
//!
//! the first sum over the revolute joints `m <= k`, with `Phi_<m` the sum of
//! `|dq_i|` over the revolute joints before `m` and `L_mk` the chain length
//! from joint `m`'s pivot to the end of link `k` (prismatic links at their
//! longest: a bound on `|p - o_m|` in every configuration). Why: the path
//! length is at most `|p'(0)| + sup |p''| / 2`, and
//! `p'' = sum_ij dq_i dq_j d2p/dq_i dq_j` with `d2p/dq_i dq_j = z_i x (z_m x
//! (p - o_m))`, `m = max(i, j)` (Jacobi's identity), for two revolute joints;
//! `z_i x z_j` for a revolute `i` before a prismatic `j`; 0 otherwise. Grouped
//! by `m`, the revolute terms are `dq_m (2 w_<m + dq_m z_m) x (z_m x (p -
//! o_m))`. `J_p dq` is linear in `p` along a link (`v(x) = w x x + b`), so a
//! link's worst point is one of its ends. The largest `s` with travel at most
//! `fraction` times the link's distance `D` solves the quadratic:
//! `s = 2 D / (A + sqrt(A^2 + 4 Q D))`. Each link's distance is the lower
//! bound of [`crate::obstacle::Contact::distance_sq`] (it holds for every
//! convex `C`), or the influence distance for a link no obstacle is near.

use crate::control::PoseError;
use crate::kinematics::Frames;
use crate::math::{max, Vec3};
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
    // Phi_<m, and the sums giving Q_k: sum a_m, sum a_m L_0m, the prismatic sum.
    let mut phi = 0.0f32;
    let (mut lever_sum, mut lever_base, mut sliding) = (0.0f32, 0.0f32, 0.0f32);
    let mut pivot_chain = 0.0f32;
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
        let size = step.abs();
        let z = frames.axis(j);
        match joint.kind {
            JointKind::Revolute => {
                w += z * step;
                b -= z.cross(&frames.pivot(j)) * step;
                let a = size * (2.0 * phi + size);
                lever_sum += a;
                lever_base += a * pivot_chain;
                phi += size;
            }
            JointKind::Prismatic => {
                b += z * step;
                sliding += size * phi;
            }
        }
        pivot_chain = link.chain;
        let v = w.cross(&frames.origin(j)) + b;
        let end_speed_sq = v.dot(&v);
        let first_sq = max(start_speed_sq, end_speed_sq);
        start_speed_sq = end_speed_sq;
        let second = max(0.5 * (link.chain * lever_sum - lever_base), 0.0) + sliding;
        let allowed_sq = fraction_sq * d_sq;
        if 2.0 * (first_sq + second * second) <= allowed_sq {
            continue;
        }
        let first = libm::sqrtf(first_sq);
        let allowed = libm::sqrtf(allowed_sq);
        // s first + s^2 second = allowed.
        let root = libm::sqrtf(first * first + 4.0 * second * allowed);
        let s = 2.0 * allowed / (first + root);
        if s < scale {
            scale = s;
        }
    }
    if scale.is_finite() {
        h * max(scale, 0.0)
    } else {
        0.0
    }
}
