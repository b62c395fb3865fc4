//! The laws that drive the end effector (paper section 3) and the joint
//! weighting (section 4). Three laws, chosen by [`LawKind`]:
//!
//! * [`LawKind::DampedLeastSquares`] (the default, [`damped`]): a
//!   Levenberg-Marquardt step on `V` in the metric of the rate limits and eq.
//!   18, at the joints' speed: tens of steps, unit-invariant; on a redundant
//!   arm a rate-limited step is rebalanced by saturation in the null space
//!   ([`saturation`]);
//! * [`LawKind::Gradient`] ([`weighted_rate`]): the normalised total gradient,
//!   a first-order descent on `V`;
//! * [`LawKind::Paper`] ([`weighted_rate`]): eq. 15 as printed.
//!
//! This module holds what they share (the target, the pose error, the
//! Jacobian-transpose terms, eq. 18) and the two first-order laws.
//!
//! Target `T_target` has columns `r_T1..r_T3` (orientation) and `r_T4`
//! (position); the end effector's are `r_n1..r_n4`. Errors and energy:
//!
//! ```text
//! e_i = r_Ti - r_ni,  i = 1..4                              (eq. 11)
//! V   = sum_i 1/2 e_i . e_i                                 (eq. 12)
//! g_i = J_i^T e_i,  so  dV/dt = - sum_i g_i . qdot          (eqs. 13-14)
//! qdot_r = M sum_i g_i / |g_i|                              (eq. 15)
//! ```
//!
//! The orientation terms (`i = 1..3`) are present only when the target has an
//! orientation. What the first-order laws add to eq. 15, and why:
//!
//! * **weights**: the orientation terms carry `orientation_weight` (the
//!   listing used 10 on un-normalised terms).
//! * **smooth approach**: a normalised term has unit size however small its
//!   error, so the arm arrives at full speed and chatters about the goal. Each
//!   term is scaled by `min(1, |e| / approach)`: full speed far away, a rate
//!   proportional to the error near the goal (exponential, sign-stable arrival).
//! * **a true descent direction**: eq. 16 drops the cross terms `g_i . M g_j/|g_j|`,
//!   which can make `dV/dt` positive when the terms disagree. When the weighted
//!   sum is not a descent direction for `V`, the law falls back to the
//!   normalised total gradient `sum_i g_i`, for which `dV/dt = -G.M G/|G| < 0`.
//!
//! Joint weighting (eq. 18), `M` diagonal:
//!
//! ```text
//! f_i = (2 q_i - (qmax_i + qmin_i)) / (qmax_i - qmin_i)     (-1 at qmin, +1 at qmax)
//! m_ii = k_i (1 - eta_i f_i),  eta_i = sign of the drive on joint i,
//! k_i  = weight_i * qdot_max_i / 2
//! ```
//!
//! so a joint driven toward a limit slows to zero at it and one driven away
//! may move at up to `2 k_i <= qdot_max_i`.

pub mod damped;
pub mod first_order;
pub mod joint_space;
pub mod law;
pub mod saturation;

use crate::kinematics::{end_direction_error, end_point_force, Frames};
use crate::math::{dot_slice, max, min, norm_slice, Vec3};
use crate::robot::{Joint, Robot};
use crate::settings_field::{first_bad, non_negative, positive, SettingsField};
use crate::step_size::StepRule;
use crate::target::PoseError;

/// Which form of the law drives the joints.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LawKind {
    /// `eps = G / |G|` with `G = -dV/dq` the total gradient: every step is a
    /// descent step for `V`, and `V` has no spurious equilibria. The default.
    Gradient,
    /// Eq. 15 as printed: the sum of the four separately normalised terms.
    /// Where the terms disagree their unit vectors can cancel while `V > 0`
    /// (an equilibrium eq. 16 hides); kept as the paper's baseline.
    Paper,
    /// Damped least squares (Levenberg-Marquardt) on `V`, in the joint metric
    /// of the rate limits and eq. 18, moving at the joints' speed: see
    /// [`damped`].
    DampedLeastSquares,
}

/// Weights of the law's terms.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LawSettings {
    /// Which form of the law.
    pub kind: LawKind,
    /// Length scale `lambda` of the orientation terms, length units: `V` weighs
    /// the column errors by `lambda^2`, so a column error of `1/lambda` counts
    /// as one length unit of position error. `lambda = 1` is eq. 12 exactly.
    pub orientation_scale: f32,
    /// Error (length units, `sqrt(2 V)`) below which the drive shrinks in
    /// proportion to it: the smooth approach (first-order laws).
    pub approach_radius: f32,
    /// Damping floor `b` of the damped least-squares law, dimensionless: the
    /// damping is `(b + V / L^2)` times the mean eigenvalue of `J M J^T`
    /// (see [`damped`]), so task directions weaker than that are damped.
    pub damping: f32,
    /// Whether the damped law spends the rate limits of every joint the
    /// task can use when a step is rate-limited (saturation in the null
    /// space, [`saturation`]); `false` scales the step uniformly.
    pub saturation: bool,
}

impl LawSettings {
    /// Checks each value's range.
    pub fn validate(&self) -> Result<(), SettingsField> {
        first_bad(&[
            (
                non_negative(self.orientation_scale) && self.orientation_scale <= 1e4,
                SettingsField::OrientationScale,
            ),
            (
                non_negative(self.approach_radius),
                SettingsField::ApproachRadius,
            ),
            (
                positive(self.damping) && self.damping <= 1.0,
                SettingsField::Damping,
            ),
        ])
    }
}

impl Default for LawSettings {
    fn default() -> Self {
        LawSettings {
            kind: LawKind::DampedLeastSquares,
            orientation_scale: 10.0,
            approach_radius: 2.0,
            damping: 1.0e-3,
            saturation: true,
        }
    }
}

/// `g_i = J_i^T e_i` for the four terms, each into `terms[i][..n]` (zero when inactive).
pub fn lyapunov_terms<const N: usize>(
    robot: &Robot<N>,
    frames: &Frames<N>,
    error: &PoseError,
    terms: &mut [[f32; N]; 4],
) {
    let n = robot.len();
    end_point_force(robot, frames, &error.e[3], &mut terms[3][..n]);
    for (i, term) in terms.iter_mut().take(3).enumerate() {
        if error.has_orientation {
            let u: Vec3 = frames.end_rotation().column(i).into_owned();
            end_direction_error(robot, frames, &u, &error.e[i], &mut term[..n]);
        } else {
            term[..n].fill(0.0);
        }
    }
}

/// What every law reads: the arm's configuration and its evaluation (the
/// frames, the pose error from the target driven to, the obstacle gradient
/// and the closest pair), the law's settings and the step it plans for.
/// Built by the planner for each step and by the escape's search for each
/// imagined one ([`law::propose`]).
#[derive(Clone, Copy, Debug)]
pub struct LawInput<'a, const N: usize> {
    /// The chain.
    pub robot: &'a Robot<N>,
    /// The frames at `q` (eqs. 5-6).
    pub frames: &'a Frames<N>,
    /// The joint values, `robot.len()` of them (radians or length units).
    pub q: &'a [f32],
    /// The pose error from the target driven to (eqs. 11-12).
    pub error: &'a PoseError,
    /// The obstacle gradient `mu = dP/dq` (eq. 20), `robot.len()` values.
    pub mu: &'a [f32],
    /// `C - 1` of the closest pair within influence, if any (eq. 25).
    pub clearance: Option<f32>,
    /// The law's settings.
    pub law: &'a LawSettings,
    /// `C - 1` below which the projection engages (see [`crate::projection`]).
    pub engage_clearance: f32,
    /// The step planned for: `step.time_step_s` is the horizon of the damped
    /// and joint-space laws; the first-order laws apply the listing's rule.
    pub step: StepRule,
    /// Position error change over the last step, length units (the
    /// listing's `error_step`; the first-order laws' step rule needs it).
    pub error_step: f32,
}

/// What a law proposes for one step: the rate is written into the caller's
/// buffer; this says how it was formed and how to take it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Proposal {
    /// How the direction was formed.
    pub drive: Drive,
    /// Whether the obstacle projection (eq. 24) changed the rate.
    pub constrained: bool,
    /// The step to try first, seconds (before conservative advancement).
    pub time_step_s: f32,
    /// Whether the step may raise `V`: a constrained step trades descent for
    /// clearance, and an escape's walk is leaving a dead end.
    pub may_rise: bool,
    /// Seconds the rate would take to cover the law's whole motion (the
    /// damped law's step, the way to a joint configuration): each joint's
    /// remaining way is `|rate| arrival_s`, which the tracker brakes to
    /// arrive at rest within ([`crate::tracker`]). Infinite when the law
    /// does not know (the first-order laws).
    pub arrival_s: f32,
}

impl Proposal {
    /// Nothing to do: no rate, no step.
    pub const IDLE: Proposal = Proposal {
        drive: Drive::Idle,
        constrained: false,
        time_step_s: 0.0,
        may_rise: false,
        arrival_s: f32::INFINITY,
    };
}

/// How the drive direction was formed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Drive {
    /// Eq. 15's sum of normalised terms.
    Normalised,
    /// The normalised total gradient (the default law, or eq. 15's fallback
    /// when its sum was not a descent direction).
    TotalGradient,
    /// The damped least-squares step ([`damped`]).
    Damped,
    /// Straight to a joint configuration ([`joint_space`]): an escape walk,
    /// the return to the best configuration, a joint-space waypoint.
    Joints,
    /// Nothing to do: the gradient is zero, or every joint that could reduce
    /// `V` sits at a limit.
    Idle,
}

/// Forms the weighted rate `qdot_r = M eps` into `rate` (`n` values), with `eps`
/// the drive direction (written into `drive`). Returns how it was formed.
///
/// For the gradient law `rate_j = gain_j G_j` exactly, and `gain` receives
/// those per-joint gains (per second per unit of `G`); for eq. 15's sum, whose
/// rate is no fixed multiple of `G`, `gain` is all zero.
#[allow(clippy::too_many_arguments)]
pub fn weighted_rate<const N: usize>(
    robot: &Robot<N>,
    q: &[f32],
    error: &PoseError,
    terms: &[[f32; N]; 4],
    settings: &LawSettings,
    drive: &mut [f32],
    rate: &mut [f32],
    gain: &mut [f32],
) -> Drive {
    let n = robot.len();
    // Buffers shorter than the robot (no caller passes them): no rate.
    let (Some(drive), Some(gain), true) = (drive.get_mut(..n), gain.get_mut(..n), rate.len() >= n)
    else {
        rate.fill(0.0);
        return Drive::Idle;
    };
    let rate = &mut rate[..n];
    gain.fill(0.0);
    let lambda_sq = settings.orientation_scale * settings.orientation_scale;
    let weight = |i: usize| if i == 3 { 1.0 } else { lambda_sq };
    if settings.kind == LawKind::Paper {
        drive.fill(0.0);
        for (i, term) in terms.iter().enumerate() {
            let term = &term[..n];
            let size = norm_slice(term);
            let scale = if i == 3 {
                smooth(error.position, settings.approach_radius)
            } else {
                smooth(
                    settings.orientation_scale * error.orientation,
                    settings.approach_radius,
                )
            };
            if size > 0.0 && size.is_finite() {
                let k = scale / size;
                drive.iter_mut().zip(term).for_each(|(d, g)| *d += k * g);
            }
        }
        joint_weighting(robot, q, drive, rate);
        // dV/dt = -G . qdot: insist on descent, else fall back to the gradient.
        let descent: f32 = (0..n)
            .map(|j| (0..4).map(|i| weight(i) * terms[i][j]).sum::<f32>() * rate[j])
            .sum();
        if descent > 0.0 {
            return Drive::Normalised;
        }
    }
    for (j, d) in drive.iter_mut().enumerate() {
        *d = (0..4).map(|i| weight(i) * terms[i][j]).sum();
    }
    let size = norm_slice(drive);
    if size == 0.0 || !size.is_finite() {
        rate.fill(0.0);
        return Drive::Idle;
    }
    drive.iter_mut().for_each(|d| *d /= size);
    joint_weighting(robot, q, drive, rate);
    if dot_slice(drive, rate) <= 0.0 {
        rate.fill(0.0);
        return Drive::Idle;
    }
    // Spend the rate budget: the fastest joint (relative to its limit) runs at
    // the smoothing factor times its limit. Only the length changes, so the
    // rate stays a descent direction; joints the weighting slowed near their
    // limits no longer slow the whole arm.
    let worst = robot
        .joints()
        .iter()
        .zip(rate.iter())
        .map(|(joint, r)| r.abs() / joint.max_rate)
        .fold(0.0f32, max);
    let k = smooth(crate::math::sqrt(2.0 * error.v), settings.approach_radius) / worst;
    if !(k.is_finite()) {
        rate.fill(0.0);
        return Drive::Idle;
    }
    rate.iter_mut().for_each(|r| *r *= k);
    // rate_j = k m_j drive_j = (k m_j / size) G_j.
    for (((g, joint), &qj), &d) in gain.iter_mut().zip(robot.joints()).zip(q).zip(drive.iter()) {
        *g = k / size * joint_weight(joint, qj, d);
    }
    Drive::TotalGradient
}

/// `-dV/dt = G . rate` for a joint rate, with `G = sum_i w_i g_i` (eq. 13).
pub fn descent_rate<const N: usize>(
    terms: &[[f32; N]; 4],
    settings: &LawSettings,
    rate: &[f32],
) -> f32 {
    let lambda_sq = settings.orientation_scale * settings.orientation_scale;
    rate.iter()
        .enumerate()
        .map(|(j, r)| (terms[3][j] + lambda_sq * (terms[0][j] + terms[1][j] + terms[2][j])) * r)
        .sum()
}

/// `T = max_j |rate_j| / qdot_max_j`: how long `rate`, read as a joint
/// displacement, takes with the most loaded joint at its rate limit (seconds
/// for a displacement; the multiple of the limits for a rate).
pub fn time_at_limits<const N: usize>(robot: &Robot<N>, rate: &[f32]) -> f32 {
    robot
        .joints()
        .iter()
        .zip(rate)
        .map(|(joint, r)| r.abs() / joint.max_rate)
        .fold(0.0f32, max)
}

/// `min(1, error / radius)`; 1 when `radius` is not positive.
#[inline]
fn smooth(error: f32, radius: f32) -> f32 {
    if radius > 0.0 {
        min(error / radius, 1.0)
    } else {
        1.0
    }
}

/// Eq. 18: `m_ii = k_i (1 - eta_i f_i)` for joint `joint` at `q` driven in
/// the direction of `drive` (`eta = sign(drive)`, 0 for no drive).
#[inline]
pub fn joint_weight(joint: &Joint, q: f32, drive: f32) -> f32 {
    let k = joint.weight * joint.max_rate * 0.5;
    let eta = if drive > 0.0 {
        1.0
    } else if drive < 0.0 {
        -1.0
    } else {
        0.0
    };
    max(k * (1.0 - eta * joint.range_fraction(q)), 0.0)
}

/// Eq. 18 applied: `rate_i = m_ii drive_i`.
pub fn joint_weighting<const N: usize>(
    robot: &Robot<N>,
    q: &[f32],
    drive: &[f32],
    rate: &mut [f32],
) {
    for (((joint, &qj), &d), r) in robot.joints().iter().zip(q).zip(drive).zip(rate.iter_mut()) {
        *r = joint_weight(joint, qj, d) * d;
    }
}
