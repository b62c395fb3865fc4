//! An independent check of a joint trajectory against a problem.
//!
//! Nothing here uses the planner's kinematics, obstacles, potential or link
//! capsules: every pose, clearance and capsule gap comes from
//! [`crate::geometry`], the independent `f64` model of the robot and
//! obstacles (DH products in `f64`, each obstacle evaluated directly from
//! eq. 25, with the margin of the point's kind; link capsules' segments,
//! chords or the scenario's link segments, segment to segment). Avoidance
//! points are every frame origin `o_1..o_n` and `points_per_link` interior
//! points per link (on the chords), at every row of the trajectory.
//!
//! Per row: finite values, joint limits, recorded end-effector position against
//! the exact one, clearance of every point from every obstacle, and, when the
//! scenario checks self-collision, the gap of every checked pair of link
//! capsules (the pairs of [`Problem::pair_table`]). Between rows:
//! `|q[k+1] - q[k]| <= h[k+1] max_rate (1 + 1e-4)` per joint, plus two `f32`
//! ulps of the values (the trajectory is stored in `f32`); and the capsules
//! densely along the straight joint-space segment from one row to the next
//! ([`Geometry::sweep_links`]: wherever a pair might come near, no link moves
//! more than a quarter of its capsule radius between the configurations
//! checked; at most 4 096 per segment). Row 0 must be the problem's start
//! configuration.
//!
//! A pair *self-collides* when its gap is below `-SELF_SLACK x scale`
//! ([`self_tolerance`]; [`scale`], the arm's size, as the kinematics
//! tolerance has it). The trajectory's joint values are the planner's `f32`
//! values exactly, but the planner computed its frames and gaps in `f32`:
//! each frame origin carries rounding of a few ulps of the arm's size per
//! joint (the recorded/exact end-effector mismatch the report prints shows
//! it: 3e-5 to 5e-5 in on PIPS, about 2e-7 of its scale of 250 in), so a
//! pair the planner accepted at a gap just above 0 can be that far below 0
//! here. `1e-5 x scale` is fifty times that and still tiny (2.5 thousandths
//! of an inch on PIPS, a sixth of a percent of its 1.5 in capsule radius):
//! an overlap beyond it is no rounding. Each row with such a pair, and each
//! segment between rows with one at a configuration checked inside it, is
//! one [`ViolationKind::SelfCollision`].
//!
//! The report also carries the *drive figures* ([`crate::drive_check`],
//! issue 22): rows off the fixed control period, rows over the rate,
//! acceleration or jerk limit by differences of the positions, arriving
//! moving, braking stops that would collide. They are measured on every
//! check and reject the trajectory only when [`drive_check::ENFORCED`]
//! (off until the planner's tracker keeps them).
use std::fmt;

use capp_core::JointKind;

use crate::drive_check::{self, DriveReport};
use crate::geometry::{Geometry, LinkGap};
use crate::problem::Problem;
use crate::trajectory::Trajectory;

/// Relative slack of the rate check.
pub const RATE_SLACK: f64 = 1.0e-4;

/// A capsule gap below `-SELF_SLACK` times the arm's scale is a
/// self-collision ([`self_tolerance`]; the module docs say why).
pub const SELF_SLACK: f64 = 1.0e-5;

/// The arm's size, length units: 1 plus every DH joint's `|a| + |d|` (and
/// a prismatic joint's largest extension); for general joints, 1 plus the
/// first one's distance from the base and every link's longest chord
/// ([`crate::geometry::longest_links`]). The tolerances of the kinematics
/// and self-collision checks are fractions of it.
pub fn scale(problem: &Problem) -> f64 {
    let norm = |t: [f32; 3]| {
        t.iter()
            .map(|&x| (x as f64) * (x as f64))
            .sum::<f64>()
            .sqrt()
    };
    if let Some(first) = problem.joints.first().and_then(|j| j.origin) {
        return 1.0
            + norm(first.placement.translation)
            + crate::geometry::longest_links(&problem.joints, &problem.tool)
                .iter()
                .sum::<f64>();
    }
    1.0 + norm(problem.tool.translation)
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
            .sum::<f64>()
}

/// How far two capsules may overlap before it counts as a self-collision,
/// length units: [`SELF_SLACK`] times [`scale`].
pub fn self_tolerance(problem: &Problem) -> f64 {
    SELF_SLACK * scale(problem)
}

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
    /// Two checked link capsules overlapping, at a row or between rows.
    SelfCollision,
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
            ViolationKind::SelfCollision => "self-collision",
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

/// The closest approach of two checked link capsules.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinkApproach {
    /// The pair and its gap (length units; negative: overlap).
    pub pair: LinkGap,
    /// The step of the row, or of the row ending the segment it was found in.
    pub step: u64,
    /// Whether it was between rows (on the segment ending at `step`).
    pub between: bool,
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
    /// Whether self-collision was checked (the scenario enables it).
    pub self_checked: bool,
    /// Rows and segments between rows with a self-collision (the
    /// [`ViolationKind::SelfCollision`] violations).
    pub self_collisions: usize,
    /// Of those, segments between rows.
    pub self_collisions_between: usize,
    /// The closest checked pair of link capsules over the rows and the
    /// configurations checked between them; `None` when none is checked.
    pub closest_links: Option<LinkApproach>,
    /// The deepest self-collision, when there is one.
    pub worst_self_collision: Option<LinkApproach>,
    /// Segments between rows whose capsule check ran out of its budget
    /// before it was as dense as asked (a step far beyond the rate limits).
    pub sparse_segments: usize,
    /// The overlap a self-collision exceeds ([`self_tolerance`]).
    pub self_tolerance: f64,
    /// The problem's length unit, for the text.
    pub unit: String,
    /// Largest difference between recorded and exact end-effector positions.
    pub max_position_mismatch: f64,
    /// Exact final position error to the target.
    pub final_position_error: f64,
    /// Exact final orientation error (root sum square of column errors), if the target has one.
    pub final_orientation_error: Option<f64>,
    /// Whether the final configuration is within the target's tolerances.
    pub reaches_target: bool,
    /// The drive figures ([`crate::drive_check`]): the period, rate,
    /// acceleration and jerk from positions, the end, the braking stops.
    /// They reject the trajectory only when [`drive_check::ENFORCED`].
    pub drive: DriveReport,
}

impl CheckReport {
    /// Whether the trajectory broke no rule; the drive figures count only
    /// when [`drive_check::ENFORCED`] (off until the planner tracks the
    /// drive limits, issue 22).
    pub fn accepted(&self) -> bool {
        self.violations.is_empty() && (!drive_check::ENFORCED || self.drive.clean())
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
        let unit = &self.unit;
        let at = |a: &LinkApproach| {
            if a.between {
                format!("between rows, in the step to step {}", a.step)
            } else {
                format!("at step {}", a.step)
            }
        };
        if !self.self_checked {
            writeln!(f, "self-collision: not checked (off for this scenario)")?;
        } else if let Some(c) = self.closest_links {
            let (a, b) = c.pair.links;
            let apart = if c.pair.gap >= 0.0 {
                format!("capsules {:.4} {unit} apart", c.pair.gap)
            } else {
                format!("capsules overlap by {:.4} {unit}", -c.pair.gap)
            };
            writeln!(
                f,
                "closest link pair: links {} and {}, {apart} {}",
                a + 1,
                b + 1,
                at(&c)
            )?;
        } else {
            writeln!(f, "self-collision: no pair of links is checked")?;
        }
        if self.self_checked {
            match self.worst_self_collision {
                Some(w) => writeln!(
                    f,
                    "self-collisions: {} ({} at rows, {} between rows); the deepest: links {} and {} overlap by {:.4} {unit} {}",
                    self.self_collisions,
                    self.self_collisions - self.self_collisions_between,
                    self.self_collisions_between,
                    w.pair.links.0 + 1,
                    w.pair.links.1 + 1,
                    -w.pair.gap,
                    at(&w)
                )?,
                None => writeln!(
                    f,
                    "self-collisions: 0 (no checked capsules overlap by more than {:.1e} {unit})",
                    self.self_tolerance
                )?,
            }
            if self.sparse_segments > 0 {
                writeln!(
                    f,
                    "{} segments between rows moved too far for the capsule check's budget: checked less densely",
                    self.sparse_segments
                )?;
            }
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
        )?;
        write!(f, "{}", self.drive)
    }
}

/// Checks `trajectory` against `problem`.
pub fn check(problem: &Problem, trajectory: &Trajectory) -> CheckReport {
    check_with(problem, &Geometry::new(problem), trajectory)
}

/// [`check`] with `problem`'s geometry already prepared ([`Geometry::new`]).
pub fn check_with(problem: &Problem, geometry: &Geometry, trajectory: &Trajectory) -> CheckReport {
    let n = problem.joints.len();
    let mut violations = Vec::new();
    let self_tolerance = self_tolerance(problem);
    let mut report = CheckReport {
        rows: trajectory.rows.len(),
        violations: Vec::new(),
        min_clearance: None,
        self_checked: geometry.self_collision(),
        self_collisions: 0,
        self_collisions_between: 0,
        closest_links: None,
        worst_self_collision: None,
        sparse_segments: 0,
        self_tolerance,
        unit: problem.length_unit.clone(),
        max_position_mismatch: 0.0,
        final_position_error: f64::INFINITY,
        final_orientation_error: None,
        reaches_target: false,
        drive: DriveReport::new(problem.drive.control_period_s),
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
    let position_tolerance = 1.0e-4 * scale(problem);
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

    if problem.links.enabled && !geometry.self_collision() {
        let why = problem
            .pair_table()
            .err()
            .map_or_else(String::new, |e| format!(": {}", e.message));
        push(
            1,
            0,
            ViolationKind::Shape,
            format!("self-collision is on but the link capsules are invalid{why}"),
        );
    }

    // Describes an overlap of `pair` in words.
    let overlap = |pair: &LinkGap| {
        let (a, b) = pair.links;
        let (ra, rb) = (
            problem.links.radius[a] as f64,
            problem.links.radius[b] as f64,
        );
        format!(
            "{} and {} overlap: their capsules are {:.4} {unit} into each other (segments {:.4} {unit} apart, radii {ra} + {rb})",
            problem.link_label(a),
            problem.link_label(b),
            -pair.gap,
            pair.gap + ra + rb,
            unit = problem.length_unit,
        )
    };
    let approach = |found: LinkApproach, report: &mut CheckReport| {
        if report
            .closest_links
            .is_none_or(|c| found.pair.gap < c.pair.gap || found.pair.gap.is_nan())
        {
            report.closest_links = Some(found);
        }
        let collides = found.pair.gap.is_nan() || found.pair.gap < -self_tolerance;
        if collides
            && report
                .worst_self_collision
                .is_none_or(|w| found.pair.gap < w.pair.gap || found.pair.gap.is_nan())
        {
            report.worst_self_collision = Some(found);
        }
        collides
    };

    // The last finite row: its configuration, capsule gaps and step.
    let mut previous: Option<(&[f64], Vec<f64>, u64)> = None;
    let mut last_end = None;
    for (k, row) in trajectory.rows.iter().enumerate() {
        if !row.q.iter().all(|x| x.is_finite()) || !row.h.is_finite() {
            push(
                row.line,
                row.step,
                ViolationKind::NotFinite,
                "a joint value or the step size is not finite".into(),
            );
            previous = None;
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
        let pose = geometry.pose(&row.q);
        let end = pose.end;
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
        geometry.pairs(&pose.origins, |c, id, o| {
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
        let gaps = geometry.link_gaps(&pose);
        if let Some(pair) = geometry.worst_gap(&gaps) {
            let found = LinkApproach {
                pair,
                step: row.step,
                between: false,
            };
            if approach(found, &mut report) {
                report.self_collisions += 1;
                let others = gaps
                    .iter()
                    .filter(|g| g.is_nan() || **g < -self_tolerance)
                    .count()
                    - 1;
                let more = if others > 0 {
                    format!(" (and {others} more pairs)")
                } else {
                    String::new()
                };
                push(
                    row.line,
                    row.step,
                    ViolationKind::SelfCollision,
                    format!("{}{more}", overlap(&pair)),
                );
            }
        }
        if let Some((q0, gaps0, step0)) = &previous {
            let sweep = geometry.sweep_links(q0, &row.q, gaps0, &gaps, -self_tolerance, false);
            report.sparse_segments += sweep.truncated as usize;
            if let Some((pair, t)) = sweep.worst {
                let found = LinkApproach {
                    pair,
                    step: row.step,
                    between: true,
                };
                if approach(found, &mut report) {
                    report.self_collisions += 1;
                    report.self_collisions_between += 1;
                    push(
                        row.line,
                        row.step,
                        ViolationKind::SelfCollision,
                        format!(
                            "between steps {step0} and {} ({:.0}% of the way): {}",
                            row.step,
                            100.0 * t,
                            overlap(&pair)
                        ),
                    );
                }
            }
        }
        previous = Some((&row.q, gaps, row.step));
        last_end = Some(end);
    }
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
    report.drive = drive_check::measure(
        problem,
        geometry,
        trajectory,
        report.reaches_target,
        self_tolerance,
        scale(problem),
    );
    report.violations = violations;
    report
}
