//! Saturation in the null space (SNS; Flacco, De Luca and Khatib, "Control
//! of redundant robots under hard joint constraints: saturation in the null
//! space", IEEE T-RO 2015): how a redundant arm spends its rate limits.
//!
//! The damped step [`crate::control::damped`] is the displacement `dq*` that
//! removes the pose error with the least motion in the metric `M` (a 2-norm
//! in seconds at the rate limits). When it needs more than one time step,
//! scaling it uniformly into the limits runs only its most loaded joint at
//! its limit; the others idle below theirs. SNS instead holds the joint that
//! would overrun at its bound for this step and hands the rest of the task to
//! the free joints, joint after joint, keeping the candidate that leaves the
//! least error:
//!
//! ```text
//! A_W = J W M J^T + D          (W: 1 for free joints, 0 for held ones; D = mu Lambda^-1)
//! a   = W M J^T A_W^-1 eps     (the task, by the free joints)
//! b   = q_N - W M J^T A_W^-1 J q_N   (the held joints' motion q_N, compensated)
//! dq  = s a + b,   s = the largest scale in [0, 1] with every free joint within its bounds
//! ```
//!
//! The bounds of a step of `h` seconds are the rate limits, `|dq_j| <= qdot_max_j h`,
//! narrowed by the joint limits (`q_min - q <= dq_j <= q_max - q`). What the
//! candidate leaves of the error is, with no further pass over the joints
//! (`J a = eps - D y_a`, `J b = D y_b`),
//!
//! ```text
//! r = eps - J dq = (1 - s) eps + D (s y_a - y_b),   y_a = A_W^-1 eps,  y_b = A_W^-1 J q_N
//! ```
//!
//! measured in eq. 12's weights `Lambda`. The first candidate (nothing held)
//! is the uniform scaling itself, so the result never leaves more error than
//! it; a later one counts only if it lowers `V` at least as fast, to first
//! order (`eps^T Lambda J dq = eps^T Lambda (eps - r)`). Holding a joint removes its term from `A_W`, a rank-one downdate of
//! the law's own `L D L^T` factor (O(36), [`crate::linalg::update`]); each
//! round is then two 6 x 6 solves and one pass over the joints. At most
//! [`MOST_HELD`] joints are held, and never more than `n - 2 m` (`m`
//! task rows): an arm with no more than twice as many joints as rows (a
//! 7-joint arm for a pose, a 3-joint planar arm for a point) keeps the
//! uniform scaling, whose straight task-space step its few free joints could
//! not improve on without turning the end effector off its line.
//!
//! The result is returned as the displacement that completes the task at the
//! candidate's pace, `dq / s`: the law projects and scales it as it did
//! `dq*`, and `(dq / s) s = dq` is what one step moves when nothing else cuts
//! it.

use crate::linalg::{solve, update, Sym6, Vec6};
use crate::math::{max, min};
use crate::robot::Robot;

/// Most joints held in one step: each round costs a rank-one downdate, two
/// 6 x 6 solves and a pass over the joints (on the Cortex-M4F a PIPS step
/// with 8 obstacles took 46 536 instructions with saturation, 38 166
/// without: BENCHMARKS.md), and the first few give most of the gain (median
/// motion time of the suite's PIPS free-space cases, seeds 1-3: 8.5 s for
/// uniform scaling, 6.05 s holding at most 2 joints, 5.3 s at most 4, 4.95 s
/// at most 6).
pub const MOST_HELD: usize = 4;

/// Buffers of [`saturate`], sized once for `N` joints.
#[derive(Clone, Debug)]
pub struct SaturationWorkspace<const N: usize> {
    /// Whether each joint is still free (not held at a bound).
    free: [bool; N],
    /// The displacement of held joints (`q_N`), 0 for free ones.
    held: [f32; N],
    /// This step's bounds of each joint's displacement: rate and joint limits.
    lower: [f32; N],
    /// See `lower`.
    upper: [f32; N],
    /// `a` of the current round (free joints).
    task: [f32; N],
    /// `b` of the current round.
    compensation: [f32; N],
    /// The best candidate so far.
    best: [f32; N],
}

impl<const N: usize> Default for SaturationWorkspace<N> {
    fn default() -> Self {
        SaturationWorkspace {
            free: [true; N],
            held: [0.0; N],
            lower: [0.0; N],
            upper: [0.0; N],
            task: [0.0; N],
            compensation: [0.0; N],
            best: [0.0; N],
        }
    }
}

impl<const N: usize> SaturationWorkspace<N> {
    /// Every buffer to its initial value, in place.
    pub fn clear(&mut self) {
        // Every field is named: a field added here fails to compile.
        let SaturationWorkspace {
            free,
            held,
            lower,
            upper,
            task,
            compensation,
            best,
        } = self;
        free.fill(true);
        held.fill(0.0);
        lower.fill(0.0);
        upper.fill(0.0);
        task.fill(0.0);
        compensation.fill(0.0);
        best.fill(0.0);
    }
}

/// The damped problem [`saturate`] rebalances: `J` by columns, the metric,
/// the factor of `A = J M J^T + D`, the damping `D`, `Lambda`'s weights, the
/// error `eps` the step was solved for and the law's solution `A^-1 eps`.
#[derive(Clone, Copy, Debug)]
pub struct Problem<'a, const N: usize> {
    /// Task columns `J_j` (six rows; unused rows zero).
    pub columns: &'a [Vec6; N],
    /// `M_jj`.
    pub metric: &'a [f32; N],
    /// The `L D L^T` factor of `J M J^T + D` ([`crate::linalg::factor`]).
    pub factor: &'a Sym6,
    /// The diagonal of `D = mu Lambda^-1`.
    pub damping: Vec6,
    /// The diagonal of `Lambda` (eq. 12's weights; 0 for unused rows).
    pub weights: Vec6,
    /// The error the step removes.
    pub eps: Vec6,
    /// `A^-1 eps`, the law's own solve (`dq* = M J^T y`).
    pub y: Vec6,
    /// Task rows in use (3: position only; 6: pose).
    pub rows: usize,
}

/// What [`saturate`] did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Saturation {
    /// Joints held at a bound in the chosen candidate.
    pub held: u8,
    /// The chosen candidate's task scale `s`: the fraction of the error one
    /// step removes (to first order).
    pub scale: f32,
}

#[inline]
fn dot6(a: &Vec6, b: &Vec6) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3] + a[4] * b[4] + a[5] * b[5]
}

/// Rebalances `dq` (in: the damped step `dq*`, the whole displacement; out:
/// the candidate with the least error left, as `dq / s`) for a step of
/// `time_step_s` from `q`; see the module docs. Returns `None`, leaving `dq`
/// as it was, when the arm has too little redundancy, the step fits in one
/// time step, or no candidate beats the uniform scaling.
pub fn saturate<const N: usize>(
    robot: &Robot<N>,
    problem: &Problem<'_, N>,
    q: &[f32],
    time_step_s: f32,
    ws: &mut SaturationWorkspace<N>,
    dq: &mut [f32],
) -> Option<Saturation> {
    let n = robot.len().min(dq.len()).min(q.len()).min(N);
    let joints = robot.joints().get(..n)?;
    let (q, dq) = (q.get(..n)?, dq.get_mut(..n)?);
    // Joints that may be held while twice the task's rows stay free.
    let holdable = n.checked_sub(2 * problem.rows)?.min(MOST_HELD);
    if holdable == 0 {
        return None;
    }
    // Round 0 holds nothing: a = dq*, b = 0, y_a = y.
    for ((((((joint, &qj), &d), free), held), (lower, upper)), (task, compensation)) in joints
        .iter()
        .zip(q)
        .zip(dq.iter())
        .zip(ws.free.iter_mut())
        .zip(ws.held.iter_mut())
        .zip(ws.lower.iter_mut().zip(ws.upper.iter_mut()))
        .zip(ws.task.iter_mut().zip(ws.compensation.iter_mut()))
    {
        let step = joint.max_rate * time_step_s;
        *lower = max(-step, joint.min - qj);
        *upper = min(step, joint.max - qj);
        *free = true;
        *held = 0.0;
        *task = d;
        *compensation = 0.0;
    }
    let mut f = *problem.factor;
    let (mut ya, mut yb) = (problem.y, [0.0f32; 6]);
    // J q_N, kept as joints are held.
    let mut moved: Vec6 = [0.0; 6];
    let mut best: Option<(f32, Saturation)> = None;
    let mut uniform_descent = 0.0f32;
    let (free, held) = (&mut ws.free[..n], &mut ws.held[..n]);
    let (lower, upper) = (&ws.lower[..n], &ws.upper[..n]);
    let (task, compensation) = (&mut ws.task[..n], &mut ws.compensation[..n]);
    let (columns, metric) = (&problem.columns[..n], &problem.metric[..n]);
    for round in 0..=holdable {
        if round > 0 {
            ya = problem.eps;
            solve(&f, &mut ya);
            yb = moved;
            solve(&f, &mut yb);
        }
        // a and b of the free joints (round 0: already there), the largest
        // scale that keeps every free joint within its bounds, and the joint
        // that sets it.
        let mut scale = 1.0f32;
        let mut critical = None;
        for (j, ((((column, &m), &free), (task, compensation)), (&lower, &upper))) in columns
            .iter()
            .zip(metric)
            .zip(free.iter())
            .zip(task.iter_mut().zip(compensation.iter_mut()))
            .zip(lower.iter().zip(upper))
            .enumerate()
        {
            if !free {
                continue;
            }
            if round > 0 {
                *task = m * dot6(column, &ya);
                *compensation = -m * dot6(column, &yb);
            }
            let (t, c) = (*task, *compensation);
            let bound = if t > 0.0 {
                upper
            } else if t < 0.0 {
                lower
            } else {
                continue;
            };
            let limit = (bound - c) / t;
            if limit < scale {
                scale = limit;
                critical = Some((j, bound));
            }
        }
        let scale = max(scale, 0.0);
        // The error this candidate leaves, and how fast it lowers V (to first
        // order, `G . dq = eps^T Lambda J dq`), in Lambda's weights.
        let (mut left, mut descent) = (0.0f32, 0.0f32);
        for i in 0..6 {
            let r = (1.0 - scale) * problem.eps[i] + problem.damping[i] * (scale * ya[i] - yb[i]);
            left += problem.weights[i] * r * r;
            descent += problem.weights[i] * problem.eps[i] * (problem.eps[i] - r);
        }
        if !(left.is_finite() && descent.is_finite()) {
            break;
        }
        if round == 0 {
            uniform_descent = descent;
        }
        // A candidate must lower V at least as fast as the uniform scaling:
        // where the damping is large, one that leaves less error could in
        // principle turn away from the gradient, and the planner would refuse
        // its steps. A guard: it changed no run of the suite's 1 600 cases
        // (seeds 1-5), nor any case of `tests/saturation.rs`.
        let improved =
            scale > 0.0 && descent >= uniform_descent && best.is_none_or(|(b, _)| left < b);
        if improved {
            best = Some((
                left,
                Saturation {
                    held: round as u8,
                    scale,
                },
            ));
        }
        // Round 0 is the uniform scaling, returned as `None` with `dq`
        // untouched: only a later candidate needs its joints kept.
        if improved && round > 0 {
            for ((((out, &free), &task), &compensation), &held) in ws.best[..n]
                .iter_mut()
                .zip(free.iter())
                .zip(task.iter())
                .zip(compensation.iter())
                .zip(held.iter())
            {
                *out = if free {
                    scale * task + compensation
                } else {
                    held
                };
            }
        }
        let Some((c, value)) = critical else {
            break;
        };
        if scale >= 1.0 || round == holdable {
            break;
        }
        // Hold the critical joint at the bound it reached.
        let (Some(flag), Some(h), Some(column), Some(&m)) = (
            free.get_mut(c),
            held.get_mut(c),
            columns.get(c),
            metric.get(c),
        ) else {
            break;
        };
        // A_W loses the held joint's term: a rank-one downdate of its factor.
        if !update(&mut f, -m, column) {
            break;
        }
        *flag = false;
        *h = value;
        for (moved, &x) in moved.iter_mut().zip(column) {
            *moved += x * value;
        }
    }
    let (_, chosen) = best?;
    if chosen.held == 0 {
        // The uniform scaling itself: nothing to change.
        return None;
    }
    let inverse = 1.0 / chosen.scale;
    for (d, &b) in dq.iter_mut().zip(&ws.best) {
        *d = b * inverse;
    }
    Some(chosen)
}
