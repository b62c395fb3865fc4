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
//!   [`LawSettings::damping`]. Far from the target (`V / L^2` large) the step
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
//!   along a curved surface does not creep closer step by step.
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
use crate::control::{joint_weight, time_at_limits, Drive, LawSettings, PoseError};
use crate::kinematics::Frames;
use crate::linalg::{factor, solve, Sym6, Vec6};
use crate::math::{dot_slice, max, norm, Vec3};
use crate::projection::Guard;
use crate::robot::{JointKind, Robot};

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
            saturation,
        } = self;
        columns.fill([0.0; 6]);
        metric.fill(0.0);
        drive.fill(0.0);
        factor.fill([0.0; 6]);
        saturation.clear();
    }
}

/// What the damped law did this step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DampedStep {
    /// How the direction was formed ([`Drive::Damped`] or [`Drive::Idle`]).
    pub drive: Drive,
    /// Whether the obstacle projection changed the step.
    pub constrained: bool,
    /// `T`: seconds the undamped-by-speed step needs at the rate limits.
    pub time_at_limits_s: f32,
}

/// For `K g = M g - M J^T t`, `t = (J M J^T + mu Lambda^-1)^-1 J M g`: returns
/// `(g . K g, t)`; `K g` itself is then one O(n) pass ([`apply_metric`]).
fn metric_of<const N: usize>(
    g: &[f32],
    columns: &[Vec6; N],
    metric: &[f32; N],
    factor: &Sym6,
) -> (f32, Vec6) {
    let mut t = [0.0f32; 6];
    for ((column, &m), &gj) in columns.iter().zip(metric).zip(g) {
        let u = m * gj;
        for (ti, ci) in t.iter_mut().zip(column) {
            *ti += u * ci;
        }
    }
    solve(factor, &mut t);
    let mut along = 0.0f32;
    for ((column, &m), &gj) in columns.iter().zip(metric).zip(g) {
        along += gj * (m * gj - m * dot6(column, &t));
    }
    (along, t)
}

/// `rate -= k K g`, with `t` from [`metric_of`].
fn apply_metric<const N: usize>(
    rate: &mut [f32],
    k: f32,
    g: &[f32],
    t: &Vec6,
    columns: &[Vec6; N],
    metric: &[f32; N],
) {
    for (((r, column), &m), &gj) in rate.iter_mut().zip(columns).zip(metric).zip(g) {
        *r -= k * (m * gj - m * dot6(column, t));
    }
}

/// Projects `rate` (the step `dq*`) against `guard` in the metric `K`: the
/// least change in `K^-1` that brings `g . dq` down to what the guard allows.
/// Returns whether it changed the step.
fn project_guard<const N: usize>(
    guard: &Guard<'_>,
    final_approach: bool,
    ws: &mut DampedWorkspace<N>,
    rate: &mut [f32],
) -> bool {
    let approach = dot_slice(guard.gradient, rate);
    let Some(allowed) = guard.allowed(approach, final_approach) else {
        return false;
    };
    let (along, t) = metric_of(guard.gradient, &ws.columns, &ws.metric, &ws.factor);
    if !(along > 0.0 && along.is_finite()) {
        return false;
    }
    let k = (approach - allowed) / along;
    apply_metric(rate, k, guard.gradient, &t, &ws.columns, &ws.metric);
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

/// The damped least-squares step (module docs) for the arm in `frames` at `q`
/// with pose `error` and the obstacle `guard`; writes the joint rate (per second) into `rate` for a step of
/// `time_step_s`. All slices hold `robot.len()` values.
#[allow(clippy::too_many_arguments)]
pub fn damped_rate<const N: usize>(
    robot: &Robot<N>,
    frames: &Frames<N>,
    q: &[f32],
    error: &PoseError,
    guard: &Guard<'_>,
    law: &LawSettings,
    time_step_s: f32,
    ws: &mut DampedWorkspace<N>,
    rate: &mut [f32],
) -> DampedStep {
    let n = robot.len();
    let len = n.min(rate.len());
    let rate = &mut rate[..len];
    let idle = |rate: &mut [f32]| {
        rate.fill(0.0);
        DampedStep {
            drive: Drive::Idle,
            constrained: false,
            time_at_limits_s: 0.0,
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
        let z = frames.axis(j);
        let angular = if error.has_orientation {
            z
        } else {
            Vec3::zeros()
        };
        *column = match joint.kind {
            JointKind::Revolute => six(z.cross(&(p - frames.pivot(j))), angular),
            JointKind::Prismatic => six(z, Vec3::zeros()),
        };
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
    let constrained = project_guard(guard, final_approach, ws, rate);

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
    let k = 1.0 / max(time_at_limits, time_step_s);
    rate.iter_mut().for_each(|r| *r *= k);
    DampedStep {
        drive: Drive::Damped,
        constrained,
        time_at_limits_s: time_at_limits,
    }
}
