//! An independent check of a joint trajectory against a problem.
//!
//! Nothing here uses the planner's kinematics, obstacles or potential: every
//! pose and clearance comes from [`crate::geometry`], the independent `f64`
//! model of the robot and obstacles (DH products in `f64`, each obstacle
//! evaluated directly from eq. 25, with the margin of the point's kind).
//! Avoidance points are every frame origin `o_1..o_n` and `points_per_link`
//! interior points per link, at every row of the trajectory.
//!
//! Per row: finite values, joint limits, recorded end-effector position against
//! the exact one, clearance of every point from every obstacle. Between rows:
//! `|q[k+1] - q[k]| <= h[k+1] max_rate (1 + 1e-4)` per joint, plus two `f32`
//! ulps of the values (the trajectory is stored in `f32`). Row 0 must be the
//! problem's start configuration.

use std::fmt;

use capp_core::JointKind;

use crate::geometry::{forward, Geometry};
use crate::problem::Problem;
use crate::trajectory::Trajectory;

/// Relative slack of the rate check.
pub const RATE_SLACK: f64 = 1.0e-4;

/// What kind of rule a row broke.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ViolationKind {
    /// Wrong joint count, or row 0 is not the start configuration.
    Shape,
    /// A NaN or infinite value.
    NotFinite,
    /// A joint outside its limits.
    JointLimit,
    /// A joint moved faster than its rate limit.
    RateLimit,
    /// An avoidance point inside an inflated obstacle.
    Collision,
    /// The recorded end-effector position disagrees with the exact kinematics.
    Kinematics,
}

impl fmt::Display for ViolationKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ViolationKind::Shape => "shape",
            ViolationKind::NotFinite => "not finite",
            ViolationKind::JointLimit => "joint limit",
            ViolationKind::RateLimit => "rate limit",
            ViolationKind::Collision => "collision",
            ViolationKind::Kinematics => "kinematics",
        })
    }
}

/// One broken rule.
#[derive(Clone, Debug, PartialEq)]
pub struct Violation {
    /// Line in the trajectory file.
    pub line: usize,
    /// Step number.
    pub step: u64,
    /// Which rule.
    pub kind: ViolationKind,
    /// Details.
    pub message: String,
}

/// The result of a check.
#[derive(Clone, Debug, PartialEq)]
pub struct CheckReport {
    /// Rows checked.
    pub rows: usize,
    /// Every violation found.
    pub violations: Vec<Violation>,
    /// Smallest `C - 1` of any point / obstacle pair: value, step, point, obstacle (1-based).
    pub min_clearance: Option<(f64, u64, usize, usize)>,
    /// Largest difference between recorded and exact end-effector positions.
    pub max_position_mismatch: f64,
    /// Exact final position error to the target.
    pub final_position_error: f64,
    /// Exact final orientation error (root sum square of column errors), if the target has one.
    pub final_orientation_error: Option<f64>,
    /// Whether the final configuration is within the target's tolerances.
    pub reaches_target: bool,
}

impl CheckReport {
    /// Whether the trajectory broke no rule.
    pub fn accepted(&self) -> bool {
        self.violations.is_empty()
    }

    /// Whether a violation of `kind` was found.
    pub fn has(&self, kind: ViolationKind) -> bool {
        self.violations.iter().any(|v| v.kind == kind)
    }
}

impl fmt::Display for CheckReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        const SHOWN: usize = 20;
        for v in self.violations.iter().take(SHOWN) {
            writeln!(
                f,
                "line {} (step {}): {}: {}",
                v.line, v.step, v.kind, v.message
            )?;
        }
        if self.violations.len() > SHOWN {
            writeln!(f, "... and {} more", self.violations.len() - SHOWN)?;
        }
        writeln!(
            f,
            "{}: {} rows, {} violations",
            if self.accepted() {
                "ACCEPTED"
            } else {
                "REJECTED"
            },
            self.rows,
            self.violations.len()
        )?;
        match self.min_clearance {
            Some((c, step, point, obstacle)) => writeln!(
                f,
                "minimum clearance C-1 = {c:.5} at step {step} (point {point}, obstacle {obstacle})"
            )?,
            None => writeln!(f, "no obstacles")?,
        }
        writeln!(
            f,
            "largest recorded/exact end-effector mismatch: {:.2e}",
            self.max_position_mismatch
        )?;
        write!(f, "final position error {:.5}", self.final_position_error)?;
        if let Some(o) = self.final_orientation_error {
            write!(f, ", orientation error {o:.5}")?;
        }
        writeln!(
            f,
            ": {}",
            if self.reaches_target {
                "target reached"
            } else {
                "target not reached"
            }
        )
    }
}

/// Checks `trajectory` against `problem`.
pub fn check(problem: &Problem, trajectory: &Trajectory) -> CheckReport {
    let n = problem.joints.len();
    let mut violations = Vec::new();
    let mut report = CheckReport {
        rows: trajectory.rows.len(),
        violations: Vec::new(),
        min_clearance: None,
        max_position_mismatch: 0.0,
        final_position_error: f64::INFINITY,
        final_orientation_error: None,
        reaches_target: false,
    };
    if trajectory.joints != n {
        report.violations.push(Violation {
            line: 1,
            step: 0,
            kind: ViolationKind::Shape,
            message: format!(
                "the trajectory has {} joint columns, the robot {n} joints",
                trajectory.joints
            ),
        });
        return report;
    }
    let geometry = Geometry::new(problem);
    let scale = 1.0
        + problem
            .joints
            .iter()
            .map(|j| {
                j.a.abs() as f64
                    + j.d.abs() as f64
                    + match j.kind {
                        JointKind::Prismatic => j.min.abs().max(j.max.abs()) as f64,
                        JointKind::Revolute => 0.0,
                    }
            })
            .sum::<f64>();
    let position_tolerance = 1.0e-4 * scale;
    let ulp = f32::EPSILON as f64;

    let mut push = |line, step, kind, message: String| {
        violations.push(Violation {
            line,
            step,
            kind,
            message,
        })
    };

    if let Some(first) = trajectory.rows.first() {
        for (j, (&q, &s)) in first.q.iter().zip(&problem.start).enumerate() {
            if (q - s as f64).abs() > 2.0 * ulp * (1.0 + (s as f64).abs()) {
                push(
                    first.line,
                    first.step,
                    ViolationKind::Shape,
                    format!(
                        "row 0 is not the start configuration: {} is {q}, the start {s}",
                        problem.joint_label(j)
                    ),
                );
            }
        }
    }

    let mut last_origins = Vec::new();
    let mut last_end = None;
    for (k, row) in trajectory.rows.iter().enumerate() {
        if !row.q.iter().all(|x| x.is_finite()) || !row.h.is_finite() {
            push(
                row.line,
                row.step,
                ViolationKind::NotFinite,
                "a joint value or the step size is not finite".into(),
            );
            continue;
        }
        for (j, (joint, &q)) in problem.joints.iter().zip(&row.q).enumerate() {
            let (lo, hi) = (joint.min as f64, joint.max as f64);
            let slack = ulp * lo.abs().max(hi.abs()).max(1.0);
            if q < lo - slack || q > hi + slack {
                push(
                    row.line,
                    row.step,
                    ViolationKind::JointLimit,
                    format!(
                        "{} = {q} is outside its limits [{lo}, {hi}]",
                        problem.joint_label(j)
                    ),
                );
            }
        }
        if k > 0 {
            let prev = &trajectory.rows[k - 1];
            for (j, joint) in problem.joints.iter().enumerate() {
                let moved = (row.q[j] - prev.q[j]).abs();
                let allowed = row.h.max(0.0) * joint.max_rate as f64 * (1.0 + RATE_SLACK)
                    + 2.0 * ulp * row.q[j].abs().max(prev.q[j].abs());
                if moved > allowed {
                    push(
                        row.line,
                        row.step,
                        ViolationKind::RateLimit,
                        format!(
                            "{} moved {moved:.6} in a step of {} s; its rate limit allows {:.6}",
                            problem.joint_label(j),
                            row.h,
                            row.h * joint.max_rate as f64
                        ),
                    );
                }
            }
        }
        let (origins, end) = forward(problem, &row.q);
        if let Some(p) = row.position {
            let e = ((p[0] - end[0][3]).powi(2)
                + (p[1] - end[1][3]).powi(2)
                + (p[2] - end[2][3]).powi(2))
            .sqrt();
            report.max_position_mismatch = report.max_position_mismatch.max(e);
            if e > position_tolerance {
                push(
                    row.line,
                    row.step,
                    ViolationKind::Kinematics,
                    format!("recorded end-effector position is {e:.6} from the exact one"),
                );
            }
        }
        geometry.pairs(&origins, |c, id, o| {
            if report.min_clearance.is_none_or(|m| c < m.0) {
                report.min_clearance = Some((c, row.step, id + 1, o + 1));
            }
            if c.is_nan() || c <= 0.0 {
                push(
                    row.line,
                    row.step,
                    ViolationKind::Collision,
                    format!(
                        "{} is inside obstacle {}{} (C-1 = {c:.5})",
                        problem.describe_point(id as u16),
                        o + 1,
                        problem.obstacle_label(o)
                    ),
                );
            }
            true
        });
        last_origins = origins;
        last_end = Some(end);
    }
    let _ = last_origins;
    if let (Some(end), Some(target)) = (last_end, problem.waypoints.last()) {
        let t = target.position.map(f64::from);
        report.final_position_error =
            ((t[0] - end[0][3]).powi(2) + (t[1] - end[1][3]).powi(2) + (t[2] - end[2][3]).powi(2))
                .sqrt();
        report.final_orientation_error = target.orientation.map(|rows| {
            let mut sum = 0.0;
            for (i, row) in rows.iter().enumerate() {
                for (j, &r) in row.iter().enumerate() {
                    sum += (r as f64 - end[i][j]).powi(2);
                }
            }
            sum.sqrt()
        });
        let s = &problem.settings;
        let slack = 1.0 + 1.0e-3;
        let last = problem.waypoints.len().saturating_sub(1);
        let joint_goal = problem.joint_goals.iter().find(|(w, _)| *w == last);
        report.reaches_target = match (joint_goal, trajectory.rows.last()) {
            // A joint-space target: every joint within a twentieth of a time
            // step of it at its rate limit.
            (Some((_, goal)), Some(row)) => {
                row.q
                    .iter()
                    .zip(goal)
                    .zip(&problem.joints)
                    .all(|((&q, &g), joint)| {
                        (q - g as f64).abs() / joint.max_rate as f64
                            <= 0.05 * s.time_step_s as f64 * slack
                    })
            }
            _ => {
                report.final_position_error <= s.position_tolerance as f64 * slack
                    && report
                        .final_orientation_error
                        .is_none_or(|o| o <= s.orientation_tolerance as f64 * slack)
            }
        };
    }
    report.violations = violations;
    report
}
