//! The damped least-squares law: Levenberg-Marquardt on the paper's `V`
//! (eq. 12), in a joint metric made of the rate limits and eq. 18, moving at
//! the joints' speed. It converges in tens of steps where the first-order
//! laws take thousands, and no length unit changes its path.
//!
//! ## The step
//!
//! Task space has six coordinates: `J_j = [dp/dq_j; w_j]` is joint `j`'s
//! column (`[z x (p - o); z]` revolute, `[z; 0]` prismatic; see
//! [`crate::kinematics`]). With the column errors `e_i` of eq. 11 and
//! `sigma = sum_i r_ni x r_Ti` (`= 2 sin(theta) axis` for a rotation error
//! `theta`), `dV/dt = -G . qdot` with
//!
//! ```text
//! G   = J^T Lambda eps,   eps = [e_4; sigma / 2],   Lambda = diag(1, 1, 1, 2 l^2, 2 l^2, 2 l^2)
//! ```
//!
//! (`l` = `orientation_scale`, eq. 13's weights). The Gauss-Newton matrix of
//! `V` is exactly `J^T Lambda J`: `sum_i |dr_ni/dq|^2 = 2 |w|^2` for an
//! orthonormal frame. The damped step, in the metric `M`, is
//!
//! ```text
//! dq* = (J^T Lambda J + mu M^-1)^-1 G = M J^T (J M J^T + mu Lambda^-1)^-1 eps
//! ```
//!
//! a 6 x 6 symmetric positive definite solve ([`crate::linalg`]), O(n) to
//! build, no n x n matrix. It is a descent direction for `V` whatever `mu > 0`:
//! with `B = Lambda^1/2 J M J^T Lambda^1/2`, `G . dq* = x^T B (B + mu)^-1 x >= 0`
//! for `x = Lambda^1/2 eps`. Orientation targets absent: the angular rows are
//! dropped (zero columns, unit damping), leaving a position-only solve.
//!
//! * **Metric**: `M_jj = qdot_max_j m_jj`, eq. 18's `m_jj = k_j (1 - eta_j f_j)`
//!   (`k_j = weight_j qdot_max_j / 2`, `eta_j` the sign of `G_j`) times the
//!   rate limit, so joint displacements are measured in seconds at their
//!   limits (unit-free: no length against angle), and a joint driven toward a
//!   limit gets no share of the motion as it reaches it.
//! * **Damping** (Sugihara's `E + bias`, made scale-free):
//!   `mu = (b + V / L^2) tr(Lambda J M J^T) / m`, with `m` the task rows in
//!   use, `L` the robot's reach ([`crate::Robot::reach`]) and `b` =
//!   [`crate::control::LawSettings::damping`]. Far from the target (`V / L^2` large) the step
//!   leans toward the gradient; near it the damping falls to `b` times the
//!   mean eigenvalue and the step is Gauss-Newton, which converges
//!   quadratically in every direction stronger than that; directions weaker
//!   (a stretched or folded arm's singular ones) are damped, never inverted.
//!   Every term scales with the units, so the step does not.
//! * **Obstacles** (eq. 24 in the law's metric): the one-sided projection
//!   against `mu_P = dP/dq` is done in the metric of the damped problem,
//!   `H^-1 = (J^T Lambda J + mu M^-1)^-1`: with `K = mu H^-1`,
//!
//!   ```text
//!   dq = dq* - s (mu_P . dq* / mu_P . K mu_P) K mu_P,   K v = M v - M J^T (J M J^T + mu Lambda^-1)^-1 J M v
//!   ```
//!
//!   (one more solve with the same factor). It is the step of the damped
//!   problem constrained to `mu_P . dq = 0` (for strength `s = 1`), so it
//!   still lowers `V` wherever the constraint lets it (`G . dq >= 0`, by
//!   Cauchy-Schwarz in `H^-1`), and it prefers motion the end effector does
//!   not feel: near the target `K` is nearly the projector onto the null
//!   space of `J`, so a redundant arm bends around an obstacle while its end
//!   effector keeps converging. Only a step that approaches (`mu_P . dq* > 0`)
//!   is projected, with the strength of [`crate::projection::strength`];
//!   inside the engaged band the step must also move away by
//!   [`crate::projection::retreat`] (`mu_P . dq <= -retreat`), so sliding
//!   along a curved surface does not creep closer step by step. Where the
//!   target itself lies by an obstacle, `mu_P` is nearly in the task's range
//!   and `K mu_P` is a large null-space motion that the rate limits slow to
//!   a crawl; the same projection in the joint metric `M` (eq. 24's
//!   projection in eq. 18's weights times the rate limits) is then taken
//!   instead, whichever of the two lowers
//!   `V` faster per second at the rate limits (`project_guard`).
//! * **Speed**: `T = max_j |dq_j| / qdot_max_j` is the time the step needs at
//!   the rate limits. Longer than the time step `h`: the rate is `dq / T`, so
//!   the most loaded joint runs at its limit along the linearised path.
//!   Shorter: the whole step is taken in `h` (`rate = dq / h`), and the error
//!   falls by the Gauss-Newton factor each step: a short geometric approach.
//!   The planner then shortens `h` by conservative advancement
//!   ([`crate::step_size`]) and accepts a step only if it is clear and,
//!   unprojected, lowers `V`.
//! * **Saturation** ([`crate::control::saturation`], on by default): a
//!   uniform scaling runs only the most loaded joint at its limit. When the
//!   step needs more than `h` and the arm has more than twice as many joints
//!   as task rows, `dq*` is replaced, before the projection, by the step
//!   that holds the joints that would overrun at their bounds and gives the
//!   rest of the task to the free joints (the candidate that leaves the
//!   least error in `Lambda`, never more than the uniform scaling, among
//!   those that lower `V` no more slowly than it).

use crate::control::saturation::{saturate, Problem, SaturationWorkspace};
use crate::control::{joint_weight, time_at_limits, Drive, LawInput, Proposal};

use crate::kinematics::Frames;
use crate::linalg::{factor, solve, Sym6, Vec6};
use crate::math::{dot_slice, max, norm, Vec3};
use crate::projection::{Guard, CONTACT_FLOOR};
use crate::robot::Robot;
use crate::target::PoseError;

/// Steps within which the rest of the motion must fit (at the rate limits)
/// for the final approach, which may come closer to obstacles than the
/// travel's retreat allows ([`crate::projection::approach`]).
pub const FINAL_APPROACH_STEPS: f32 = 3.0;

/// Buffers of the damped least-squares law, sized once for `N` joints.
#[derive(Clone, Debug)]
pub struct DampedWorkspace<const N: usize> {
    /// Task columns `J_j` (angular part zero when the target has no orientation).
    columns: [Vec6; N],
    /// The metric `M_jj`, joint units squared per second squared.
    metric: [f32; N],
    /// `G_j = J_j . Lambda eps` (eq. 13), kept for the descent test.
    drive: [f32; N],
    /// `L D L^T` factor of `J M J^T + mu Lambda^-1`.
    factor: Sym6,
    /// The step projected in the joint metric `M`, the projection's other
    /// candidate ([`project_guard`]).
    joint_metric_step: [f32; N],
    /// Buffers of saturation in the null space.
    saturation: SaturationWorkspace<N>,
}

impl<const N: usize> Default for DampedWorkspace<N> {
    fn default() -> Self {
        DampedWorkspace {
            columns: [[0.0; 6]; N],
            metric: [0.0; N],
            drive: [0.0; N],
            factor: [[0.0; 6]; 6],
            joint_metric_step: [0.0; N],
            saturation: SaturationWorkspace::default(),
        }
    }
}

impl<const N: usize> DampedWorkspace<N> {
    /// Every buffer to zero, in place.
    pub fn clear(&mut self) {
        // Every field is named: a field added here fails to compile.
        let DampedWorkspace {
            columns,
            metric,
            drive,
            factor,
            joint_metric_step,
            saturation,
        } = self;
        columns.fill([0.0; 6]);
        metric.fill(0.0);
        drive.fill(0.0);
        factor.fill([0.0; 6]);
        joint_metric_step.fill(0.0);
        saturation.clear();
    }
}

/// For `K g = M g - M J^T t`, `t = (J M J^T + mu Lambda^-1)^-1 J M g`: returns
/// `(g . K g, g . M g, t)`; `K g` itself is then one O(n) pass.
fn metric_of<const N: usize>(
    g: &[f32],
    columns: &[Vec6; N],
    metric: &[f32; N],
    factor: &Sym6,
) -> (f32, f32, Vec6) {
    let mut t = [0.0f32; 6];
    let mut joint_along = 0.0f32;
    for ((column, &m), &gj) in columns.iter().zip(metric).zip(g) {
        let u = m * gj;
        for (ti, ci) in t.iter_mut().zip(column) {
            *ti += u * ci;
        }
        joint_along += gj * gj * m;
    }
    solve(factor, &mut t);
    let mut along = 0.0f32;
    for ((column, &m), &gj) in columns.iter().zip(metric).zip(g) {
        along += gj * (m * gj - m * dot6(column, &t));
    }
    (along, joint_along, t)
}

/// Projects `rate` (the step `dq*`) against `guard`: the least change that
/// brings `g . dq` down to what the guard allows, in whichever of two
/// metrics makes the step lower `V` faster at the rate limits (the larger
/// `G . dq / max(T(dq), h)`, `T` the step's time at the limits, `h` the
/// time step):
///
/// * `K`, the damped problem's: `dq* - k K g`. It prefers motion the end
///   effector does not feel and never stops the descent, but where `g` lies
///   nearly in the task's range (the target itself is near the obstacle)
///   the null space has little to give, `g . K g` is small and the
///   correction is a large null-space motion that the rate limits then
///   slow to a crawl;
/// * `M`, the law's joint metric (eq. 18's weights times the rate limits,
///   as eq. 24 projects): `dq* - k M g`. It gives up some of the task's
///   motion instead.
///
/// Returns whether it changed the step.
fn project_guard<const N: usize>(
    robot: &Robot<N>,
    guard: &Guard<'_>,
    final_approach: bool,
    time_step_s: f32,
    ws: &mut DampedWorkspace<N>,
    rate: &mut [f32],
) -> bool {
    let approach = dot_slice(guard.gradient, rate);
    let Some(allowed) = guard.allowed(approach, final_approach) else {
        return false;
    };
    let (along, joint_along, t) = metric_of(guard.gradient, &ws.columns, &ws.metric, &ws.factor);
    if !(along > 0.0 && along.is_finite()) {
        return false;
    }
    // One pass: the step projected in K (into `rate`) and in M (into the
    // workspace), from the unprojected step, and for each its descent
    // `G . dq` and its time at the rate limits.
    let excess = approach - allowed;
    let (k, joint_k) = (excess / along, excess / joint_along);
    let (mut descent, mut joint_descent) = (0.0f32, 0.0f32);
    let (mut time, mut joint_time) = (0.0f32, 0.0f32);
    for ((((((r, a), column), &m), &gj), &drive), joint) in rate
        .iter_mut()
        .zip(ws.joint_metric_step.iter_mut())
        .zip(&ws.columns)
        .zip(&ws.metric)
        .zip(guard.gradient)
        .zip(&ws.drive)
        .zip(robot.joints())
    {
        *a = *r - joint_k * m * gj;
        *r -= k * (m * gj - m * dot6(column, &t));
        descent += drive * *r;
        joint_descent += drive * *a;
        time = max(time, r.abs() / joint.max_rate);
        joint_time = max(joint_time, a.abs() / joint.max_rate);
    }
    // Descent per second of motion at the rate limits (a step shorter than
    // `h` is taken in `h`).
    let pace = descent / max(time, time_step_s);
    let joint_pace = joint_descent / max(joint_time, time_step_s);
    if joint_along > 0.0 && joint_pace.is_finite() && joint_pace > pace {
        for (r, &a) in rate.iter_mut().zip(&ws.joint_metric_step) {
            *r = a;
        }
    }
    true
}

/// `[a; b]` as a task-space 6-vector.
#[inline]
fn six(a: Vec3, b: Vec3) -> Vec6 {
    [a.x, a.y, a.z, b.x, b.y, b.z]
}

#[inline]
fn dot6(a: &Vec6, b: &Vec6) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3] + a[4] * b[4] + a[5] * b[5]
}

/// The end effector's rotation error: `(sin(theta) axis, theta axis)`, the
/// rotation by `theta` about `axis` (world frame) that takes the end
/// effector's orientation to the target's. From the column errors `e_i` of
/// eq. 11: `sum_i r_ni x e_i = 2 sin(theta) axis` and `sum_i r_ni . e_i =
/// 2 (cos(theta) - 1)`. At `theta = pi` (no sine to give the axis) the axis is
/// the dominant column of `(R_err + I) / 2 = axis axis^T`.
pub fn rotation_error<const N: usize>(frames: &Frames<N>, error: &PoseError) -> (Vec3, Vec3) {
    let r = frames.end_rotation();
    let mut sigma = Vec3::zeros();
    let mut trace = 0.0f32;
    for i in 0..3 {
        let u = r.column(i);
        sigma += u.cross(&error.e[i]);
        trace += u.dot(&error.e[i]);
    }
    let sin_axis = sigma * 0.5;
    let sin = norm(&sin_axis);
    let cos = 1.0 + 0.5 * trace;
    let theta = libm::atan2f(sin, cos);
    if sin > 1.0e-4 * theta || theta < 1.0e-6 {
        let k = if sin > 0.0 { theta / sin } else { 1.0 };
        return (sin_axis, sin_axis * k);
    }
    // theta near pi: R_err = R_T R_n^T, R_T = R_n + [e_1 e_2 e_3].
    let mut best = Vec3::zeros();
    let mut best_sq = -1.0f32;
    for c in 0..3 {
        // Column c of (R_err + I) / 2.
        let mut col = Vec3::zeros();
        for i in 0..3 {
            let target = r.column(i) + error.e[i];
            col += target * (0.5 * r[(c, i)]);
        }
        col[c] += 0.5;
        let sq = col.dot(&col);
        if sq > best_sq {
            best_sq = sq;
            best = col;
        }
    }
    let size = norm(&best);
    let axis = if size > 0.0 { best / size } else { Vec3::z() };
    (sin_axis, axis * theta)
}

/// The damped least-squares step (module docs) for the arm of `input`;
/// writes the joint rate (per second) into `rate` for a step of
/// `input.step.time_step_s`, projected against the obstacles (eq. 24, its
/// guard from `input`'s gradient and closest pair). `rate` holds
/// `robot.len()` values.
pub fn damped_rate<const N: usize>(
    input: &LawInput<'_, N>,
    ws: &mut DampedWorkspace<N>,
    rate: &mut [f32],
) -> Proposal {
    let (robot, frames, q, error, law) =
        (input.robot, input.frames, input.q, input.error, input.law);
    let time_step_s = input.step.time_step_s;
    let guard = &Guard::at(
        input.mu,
        input.clearance,
        input.engage_clearance,
        CONTACT_FLOOR,
    );
    let n = robot.len();
    let len = n.min(rate.len());
    let rate = &mut rate[..len];
    let idle = |rate: &mut [f32]| {
        rate.fill(0.0);
        Proposal {
            time_step_s,
            ..Proposal::IDLE
        }
    };
    // Lambda's angular weight (0: no orientation), sigma / 2 = sin(theta) axis
    // (for G) and the rotation vector theta axis (for the step's target).
    let l = law.orientation_scale;
    let (sigma_half, rotation, w_o) = if error.has_orientation {
        let (sigma_half, rotation) = rotation_error(frames, error);
        (sigma_half, rotation, 2.0 * l * l)
    } else {
        (Vec3::zeros(), Vec3::zeros(), 0.0)
    };
    let eps = six(error.e[3], rotation);
    let weighted = six(error.e[3], sigma_half * w_o);

    // Columns, the metric (eq. 18 with eta = sign G_j) and J M J^T.
    let p = frames.end_position();
    let mut a: Sym6 = [[0.0; 6]; 6];
    let mut trace = 0.0f32;
    for (j, ((((joint, &qj), column), m), g)) in robot
        .joints()
        .iter()
        .zip(q)
        .zip(ws.columns.iter_mut())
        .zip(ws.metric.iter_mut())
        .zip(ws.drive.iter_mut())
        .enumerate()
    {
        let (linear, angular) = frames.column(j, joint.kind, &p);
        let angular = if error.has_orientation {
            angular
        } else {
            Vec3::zeros()
        };
        *column = six(linear, angular);
        // G_j = J_j . Lambda eps (eq. 13), whose sign is eq. 18's eta.
        *g = dot6(column, &weighted);
        *m = joint.max_rate * joint_weight(joint, qj, *g);
        for r in 0..6 {
            let mc = *m * column[r];
            for c in 0..=r {
                a[r][c] += mc * column[c];
            }
        }
    }
    for (r, row) in a.iter().enumerate() {
        trace += if r < 3 { row[r] } else { w_o * row[r] };
    }
    let rows = if error.has_orientation { 6.0 } else { 3.0 };
    let reach = robot.reach();
    let relative_error = if reach > 0.0 {
        error.v / (reach * reach)
    } else {
        0.0
    };
    let mu = (law.damping + relative_error) * trace / rows;
    if !(mu > 0.0 && mu.is_finite()) {
        return idle(rate);
    }
    // D = mu Lambda^-1 (unit damping on unused angular rows).
    let angular_damping = if w_o == 0.0 { mu } else { mu / w_o };
    let damping = [
        mu,
        mu,
        mu,
        angular_damping,
        angular_damping,
        angular_damping,
    ];
    for (r, row) in a.iter_mut().enumerate() {
        row[r] += damping[r];
    }
    if !factor(&mut a) {
        return idle(rate);
    }
    ws.factor = a;

    // dq* = M J^T y, (J M J^T + mu Lambda^-1) y = eps. Toward the rotation
    // vector, unless that is not a descent direction for V (it always is
    // undamped); then toward sigma / 2, the exact Gauss-Newton step on V.
    let mut rhs = eps;
    let mut y = rhs;
    solve(&ws.factor, &mut y);
    let mut descent = 0.0f32;
    for (((r, column), &m), &g) in rate
        .iter_mut()
        .zip(&ws.columns)
        .zip(&ws.metric)
        .zip(&ws.drive)
    {
        *r = m * dot6(column, &y);
        descent += g * *r;
    }
    if (descent <= 0.0 || descent.is_nan()) && error.has_orientation {
        rhs = six(error.e[3], sigma_half);
        y = rhs;
        solve(&ws.factor, &mut y);
        for ((r, column), &m) in rate.iter_mut().zip(&ws.columns).zip(&ws.metric) {
            *r = m * dot6(column, &y);
        }
    }

    // One-sided projection in the metric of the damped problem; the final
    // approach (the rest within a few steps at the rate limits) may come
    // closer.
    let mut unconstrained_time = time_at_limits(robot, rate);
    let final_approach = unconstrained_time <= FINAL_APPROACH_STEPS * time_step_s;

    // More than a step's motion: every joint the task can use at its limit
    // (saturation in the null space), not only the most loaded one.
    if law.saturation && unconstrained_time > time_step_s {
        let problem = Problem {
            columns: &ws.columns,
            metric: &ws.metric,
            factor: &ws.factor,
            damping,
            weights: [1.0, 1.0, 1.0, w_o, w_o, w_o],
            eps: rhs,
            y,
            rows: if error.has_orientation { 6 } else { 3 },
        };
        if saturate(robot, &problem, q, time_step_s, &mut ws.saturation, rate).is_some() {
            unconstrained_time = time_at_limits(robot, rate);
        }
    }
    let constrained = project_guard(robot, guard, final_approach, time_step_s, ws, rate);

    // Speed: the most loaded joint at its limit, or the whole step in one
    // (the rate is the one just timed unless the projection changed it).
    let time_at_limits = if constrained {
        time_at_limits(robot, rate)
    } else {
        unconstrained_time
    };
    if !(time_at_limits > 0.0 && time_at_limits.is_finite()) {
        return idle(rate);
    }
    let step_s = max(time_at_limits, time_step_s);
    // How many such steps the rest of the way takes: `V` over the step's
    // predicted decrease `G . dq` (about `2 V` for a Gauss-Newton step that
    // removes the whole error; less for a damped one far away).
    let decrease: f32 = ws.drive.iter().zip(rate.iter()).map(|(g, r)| g * r).sum();
    let steps = if decrease > 0.0 {
        max(1.0, 2.0 * error.v / decrease)
    } else {
        f32::INFINITY
    };
    let arrival_s = step_s * steps;
    let k = 1.0 / step_s;
    rate.iter_mut().for_each(|r| *r *= k);
    Proposal {
        drive: Drive::Damped,
        constrained,
        time_step_s,
        may_rise: constrained,
        arrival_s,
    }
}

#[cfg(test)]
// Index loops read as the textbook elimination; the bounds are constants.
#[allow(clippy::needless_range_loop)]
mod tests {
    extern crate std;
    use super::*;
    use crate::control::LawSettings;
    use crate::kinematics::forward_kinematics;
    use crate::math::Mat3;
    use crate::robot::Joint;
    use crate::step_size::StepRule;
    use crate::target::{pose_error, Target};
    use std::vec::Vec;

    const N: usize = 16;

    /// A small linear congruential generator: the test's cases are seeded.
    struct Rng(u64);

    impl Rng {
        fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            lo + (hi - lo) * ((self.0 >> 11) as f64 / (1u64 << 53) as f64)
        }
    }

    /// `A = L D L^T` from [`factor`]'s output, in f64.
    fn unfactor(f: &Sym6) -> [[f64; 6]; 6] {
        let l = |i: usize, k: usize| match i.cmp(&k) {
            core::cmp::Ordering::Greater => f[i][k] as f64,
            core::cmp::Ordering::Equal => 1.0,
            core::cmp::Ordering::Less => 0.0,
        };
        let mut a = [[0.0; 6]; 6];
        for (i, row) in a.iter_mut().enumerate() {
            for (j, x) in row.iter_mut().enumerate() {
                *x = (0..6).map(|k| l(i, k) * f[k][k] as f64 * l(j, k)).sum();
            }
        }
        a
    }

    /// `A x = b` by Gaussian elimination with partial pivoting, f64.
    fn solve64(mut a: [[f64; 6]; 6], mut b: [f64; 6]) -> [f64; 6] {
        for c in 0..6 {
            let p = (c..6)
                .max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))
                .unwrap();
            a.swap(c, p);
            b.swap(c, p);
            for r in c + 1..6 {
                let k = a[r][c] / a[c][c];
                for cc in c..6 {
                    a[r][cc] -= k * a[c][cc];
                }
                b[r] -= k * b[c];
            }
        }
        let mut x = [0.0; 6];
        for r in (0..6).rev() {
            let s: f64 = (r + 1..6).map(|c| a[r][c] * x[c]).sum();
            x[r] = (b[r] - s) / a[r][r];
        }
        x
    }

    /// The projection takes whichever of its two candidates lowers `V`
    /// faster at the rate limits, and either meets the guard: checked
    /// against both candidates built in f64 from the law's own columns,
    /// metric and damped matrix, over random arms, targets, steps and
    /// obstacle gradients.
    #[test]
    fn the_projection_takes_the_faster_of_its_two_metrics_and_meets_the_guard() {
        let mut rng = Rng(7);
        let (mut joint_metric, mut damped_metric) = (0, 0);
        let h = 0.05f32;
        for _ in 0..400 {
            let n = 3 + (rng.uniform(0.0, 10.0) as usize);
            let joints: Vec<Joint> = (0..n)
                .map(|_| {
                    let (alpha, a) = (rng.uniform(-3.0, 3.0) as f32, rng.uniform(0.2, 3.0) as f32);
                    if rng.uniform(0.0, 1.0) < 0.25 {
                        Joint::prismatic(alpha, a, rng.uniform(-2.0, 2.0) as f32, -2.0, 3.0, 1.5)
                    } else {
                        let rate = rng.uniform(0.3, 2.0) as f32;
                        Joint::revolute(alpha, a, rng.uniform(-1.0, 1.0) as f32, -3.0, 3.0, rate)
                    }
                })
                .collect();
            let robot = Robot::<N>::new(&joints).unwrap();
            let q: Vec<f32> = (0..n).map(|_| rng.uniform(-1.5, 1.5) as f32).collect();
            let mut frames = Frames::<N>::default();
            forward_kinematics(&robot, &q, &mut frames);
            let goal = frames.end_position()
                + Vec3::new(
                    rng.uniform(-2.0, 2.0) as f32,
                    rng.uniform(-2.0, 2.0) as f32,
                    rng.uniform(-2.0, 2.0) as f32,
                );
            let orientation = (rng.uniform(0.0, 1.0) < 0.5).then(|| *frames.end_rotation());
            let target = Target::pose(goal, orientation.map(|r: Mat3| r));
            let law = LawSettings::default();
            let error = pose_error(&frames, &target, law.orientation_scale);
            // The law's columns, metric and factor, with no obstacle.
            let zeros = [0.0f32; N];
            let mut ws = DampedWorkspace::<N>::default();
            let mut rate = [0.0f32; N];
            let free = LawInput {
                robot: &robot,
                frames: &frames,
                q: &q,
                error: &error,
                mu: &zeros[..n],
                clearance: None,
                law: &law,
                engage_clearance: 1.0,
                step: StepRule {
                    time_step_s: h,
                    fine_radius: 0.0,
                    fine_step_fraction: 1.0,
                },
                error_step: 0.0,
            };
            damped_rate(&free, &mut ws, &mut rate[..n]);
            // A step to project and an obstacle it approaches.
            let scale = rng.uniform(0.02, 2.0) as f32;
            let step: Vec<f32> = rate[..n].iter().map(|r| r * scale).collect();
            let g: Vec<f32> = (0..n).map(|_| rng.uniform(-1.0, 1.0) as f32).collect();
            let guard = Guard::at(&g, Some(0.5), 1.0, 0.01);
            let approach = dot_slice(&g, &step);
            let Some(allowed) = guard.allowed(approach, false) else {
                continue;
            };
            // Both candidates in f64.
            let m: Vec<f64> = ws.metric[..n].iter().map(|&x| x as f64).collect();
            let col = |j: usize| ws.columns[j].map(|x| x as f64);
            let mut jmg = [0.0f64; 6];
            for j in 0..n {
                for r in 0..6 {
                    jmg[r] += col(j)[r] * m[j] * g[j] as f64;
                }
            }
            let t = solve64(unfactor(&ws.factor), jmg);
            let kg: Vec<f64> = (0..n)
                .map(|j| m[j] * g[j] as f64 - m[j] * (0..6).map(|r| col(j)[r] * t[r]).sum::<f64>())
                .collect();
            let mg: Vec<f64> = (0..n).map(|j| m[j] * g[j] as f64).collect();
            let excess = approach as f64 - allowed as f64;
            let candidate = |d: &[f64]| -> Vec<f64> {
                let along: f64 = d.iter().zip(&g).map(|(x, &y)| x * y as f64).sum();
                step.iter()
                    .zip(d)
                    .map(|(&s, x)| s as f64 - excess / along * x)
                    .collect()
            };
            let (by_k, by_m) = (candidate(&kg), candidate(&mg));
            let pace = |d: &[f64]| {
                let descent: f64 = d.iter().zip(&ws.drive).map(|(x, &y)| x * y as f64).sum();
                let time = d
                    .iter()
                    .zip(&joints)
                    .map(|(x, j)| x.abs() / j.max_rate as f64)
                    .fold(0.0, f64::max);
                descent / time.max(h as f64)
            };
            let (pace_k, pace_m) = (pace(&by_k), pace(&by_m));
            let mut out = step.clone();
            assert!(project_guard(&robot, &guard, false, h, &mut ws, &mut out));
            // The guard is met: g . dq = allowed.
            let size: f64 = g
                .iter()
                .zip(&step)
                .map(|(a, b)| (a * b).abs() as f64)
                .sum::<f64>()
                + allowed.abs() as f64;
            let met: f64 = g.iter().zip(&out).map(|(a, b)| (a * b) as f64).sum();
            assert!(
                (met - allowed as f64).abs() <= 1e-3 * size,
                "g.dq {met} vs allowed {allowed}"
            );
            // The faster candidate, where the two are told apart.
            if (pace_k - pace_m).abs() <= 0.01 * (pace_k.abs() + pace_m.abs()) {
                continue;
            }
            let expected = if pace_m > pace_k { &by_m } else { &by_k };
            if pace_m > pace_k {
                joint_metric += 1;
            } else {
                damped_metric += 1;
            }
            let norm = expected.iter().map(|x| x * x).sum::<f64>().sqrt().max(1e-6);
            for (o, e) in out.iter().zip(expected) {
                assert!(
                    (*o as f64 - e).abs() <= 2e-3 * norm,
                    "{out:?} vs {expected:?}"
                );
            }
        }
        assert!(
            joint_metric > 20 && damped_metric > 20,
            "{joint_metric} / {damped_metric}"
        );
    }
}
