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
//! it. Each round is one 6 x 6 factorisation and O(n); at most `n - 2 m`
//! joints are held (`m` task rows): an arm with less redundancy than that
//! (a 7-joint arm for a pose, a 3-joint planar arm for a point) keeps the
//! uniform scaling, whose straight task-space step its few free joints could
//! not improve on without turning the end effector off its line.
//!
//! The result is returned as the displacement that completes the task at the
//! candidate's pace, `dq / s`: the law projects and scales it as it did
//! `dq*`, and `(dq / s) s = dq` is what one step moves when nothing else cuts
//! it.

use crate::linalg::{factor, solve, Sym6, Vec6};
use crate::robot::Robot;

/// Buffers of [`saturate`], sized once for `N` joints.
#[derive(Clone, Debug)]
pub struct SaturationWorkspace<const N: usize> {
    /// Whether each joint is still free (not held at a bound).
    free: [bool; N],
    /// The displacement of held joints (`q_N`), 0 for free ones.
    held: [f32; N],
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
            task,
            compensation,
            best,
        } = self;
        free.fill(true);
        held.fill(0.0);
        task.fill(0.0);
        compensation.fill(0.0);
        best.fill(0.0);
    }
}

/// The damped problem [`saturate`] rebalances: `J` by columns, the metric,
/// `A = J M J^T + D` before factorisation (lower triangle), the damping `D`,
/// `Lambda`'s weights and the error `eps` the step was solved for.
#[derive(Clone, Copy, Debug)]
pub struct Problem<'a, const N: usize> {
    /// Task columns `J_j` (six rows; unused rows zero).
    pub columns: &'a [Vec6; N],
    /// `M_jj`.
    pub metric: &'a [f32; N],
    /// `J M J^T + D`, lower triangle, not factorised.
    pub system: &'a Sym6,
    /// The diagonal of `D = mu Lambda^-1`.
    pub damping: Vec6,
    /// The diagonal of `Lambda` (eq. 12's weights; 0 for unused rows).
    pub weights: Vec6,
    /// The error the step removes.
    pub eps: Vec6,
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
    let holdable = n.checked_sub(2 * problem.rows)?;
    if holdable == 0 {
        return None;
    }
    ws.free[..n].fill(true);
    ws.held[..n].fill(0.0);
    let bounds = |j: usize| -> (f32, f32) {
        match (joints.get(j), q.get(j)) {
            (Some(joint), Some(&qj)) => {
                let step = joint.max_rate * time_step_s;
                (
                    crate::math::max(-step, joint.min - qj),
                    crate::math::min(step, joint.max - qj),
                )
            }
            _ => (0.0, 0.0),
        }
    };
    let mut system = *problem.system;
    // J q_N, kept as joints are held.
    let mut moved: Vec6 = [0.0; 6];
    let mut best: Option<(f32, Saturation)> = None;
    for round in 0..=holdable {
        let mut f = system;
        if !factor(&mut f) {
            break;
        }
        let mut ya = problem.eps;
        solve(&f, &mut ya);
        let mut yb = moved;
        solve(&f, &mut yb);
        // a, b and the largest scale that keeps every free joint in bounds.
        let mut scale = 1.0f32;
        let mut critical = None;
        for (j, ((((column, &m), &free), task), compensation)) in problem
            .columns
            .iter()
            .zip(problem.metric)
            .zip(&ws.free)
            .zip(ws.task.iter_mut())
            .zip(ws.compensation.iter_mut())
            .take(n)
            .enumerate()
        {
            if !free {
                continue;
            }
            *task = m * dot6(column, &ya);
            *compensation = -m * dot6(column, &yb);
            let (lower, upper) = bounds(j);
            let bound = if *task > 0.0 {
                upper
            } else if *task < 0.0 {
                lower
            } else {
                continue;
            };
            let limit = (bound - *compensation) / *task;
            if limit < scale {
                scale = limit;
                critical = Some((j, bound));
            }
        }
        let scale = crate::math::max(scale, 0.0);
        // The error this candidate leaves, in Lambda's weights.
        let mut left = 0.0f32;
        for i in 0..6 {
            let r = (1.0 - scale) * problem.eps[i] + problem.damping[i] * (scale * ya[i] - yb[i]);
            left += problem.weights[i] * r * r;
        }
        if !left.is_finite() {
            break;
        }
        if best.is_none_or(|(b, _)| left < b) && scale > 0.0 {
            best = Some((
                left,
                Saturation {
                    held: round as u8,
                    scale,
                },
            ));
            for (j, out) in ws.best.iter_mut().take(n).enumerate() {
                *out = if ws.free[j] {
                    scale * ws.task[j] + ws.compensation[j]
                } else {
                    ws.held[j]
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
        let (Some(free), Some(held), Some(column), Some(&m)) = (
            ws.free.get_mut(c),
            ws.held.get_mut(c),
            problem.columns.get(c),
            problem.metric.get(c),
        ) else {
            break;
        };
        *free = false;
        *held = value;
        for r in 0..6 {
            moved[r] += column[r] * value;
            for k in 0..=r {
                system[r][k] -= m * column[r] * column[k];
            }
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
