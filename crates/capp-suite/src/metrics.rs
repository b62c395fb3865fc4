//! What one planner run is measured by. Everything about safety comes from
//! the independent `f64` checker (`capp_sim::check`), never from the
//! planner's own flags: every recorded row is checked (limits, rates, NaN,
//! kinematics, clearance), and so is the straight joint-space segment between
//! consecutive rows, at points no more than [`DENSE_STEP`] apart in any joint,
//! so a step that jumps through an obstacle is counted even if both its ends
//! are clear. Self-collisions (two checked link capsules overlapping) are
//! `capp check`'s own count, on every row and densely between rows
//! ([`capp_sim::geometry::Geometry::sweep_links`]: no link moving more than a
//! quarter of its capsule radius between checks wherever a pair may come
//! near), one per row or segment between rows.
//!
//! Times: `motion_time` is the sum of the step sizes `h`; `same_path_time`
//! the same path driven at the joints' rate limits, `sum_k max_j |dq_j| /
//! max_rate_j`; `straight_time` the straight joint-space line from the start
//! to the final configuration at the rate limits, `max_j |q_end_j -
//! q_start_j| / max_rate_j`; `rest_to_rest_time` the least time any motion
//! a drive can follow takes from the start to the final configuration, each
//! joint alone from rest to rest at its rate, acceleration and jerk limits
//! ([`capp_sim::drive_check::rest_to_rest`]): a floor no plan between the
//! same configurations can beat, which a plan with unlimited acceleration
//! (the stepped one) may.
//!
//! Drive figures (issue 22) are `capp check`'s
//! ([`capp_sim::drive_check`]): from the positions alone, rows off the fixed
//! control period, rows over the rate, acceleration or jerk limit, whether a
//! run that reached arrives moving, and rows whose braking stop would
//! collide. They are measurements, not violations (not in
//! [`RunMetrics::violations`]) until the planner tracks the limits.
//!
//! Escapes (`capp_core::escape`) are counted from the planner's step reports
//! ([`capp_sim::escapes`]): walks and detours made, the side of the blocking
//! obstacle each took, and whether the run ended by the return to the best
//! configuration (the attempts spent).

use capp_core::escape::Side;
use capp_core::Outcome;
use capp_sim::check::{self, ViolationKind};
use capp_sim::escapes::{self, Kind};
use capp_sim::geometry::Geometry;
use capp_sim::plan::RunResult;
use capp_sim::trajectory::Trajectory;
use capp_sim::Problem;

/// Largest move of any joint (radians or length units) between two checked
/// configurations, in the dense re-check between rows and in the oracle.
pub const DENSE_STEP: f64 = 0.01;

/// `C - 1` above `-ROUNDING` (and at most 0) is a *contact*: the point is on
/// the inflated surface within what `f32` arithmetic can decide. The planner
/// accepts a point when its `f32` evaluation says `C - 1 > 0`; the exact value
/// can then be a few 1e-6 below 0 (the README's "limits found on the way").
/// Below `-ROUNDING` (1e-4, ten times the worst rounding of the families'
/// scales) it is a *collision*: no rounding explains it.
pub const ROUNDING: f64 = 1.0e-4;

/// How the checker classes one configuration's closest pair.
fn class(value: f64) -> (bool, bool) {
    let collision = value.is_nan() || value <= -ROUNDING;
    (collision, !collision && value <= 0.0)
}

/// The dead-end escapes of one run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EscapeCounts {
    /// Random walks made.
    pub walks: u32,
    /// Detours round a blocking obstacle made.
    pub detours: u32,
    /// Searches for a path made (`capp_core::escape::search`; each before a walk or a
    /// path of the same attempt).
    pub searches: u32,
    /// Paths found by a search and walked.
    pub paths: u32,
    /// Whether the run ended by the return to the best configuration (every
    /// attempt spent).
    pub returned: bool,
    /// Each attempt in order: walk or detour, and the side of the blocking
    /// obstacle taken (`None`: a walk with no obstacle blocking).
    pub sides: Vec<(Kind, Option<Side>)>,
    /// Step at which the first escape started.
    pub first_step: Option<u32>,
}

impl EscapeCounts {
    /// Walks, detours and searched paths.
    pub fn attempts(&self) -> u32 {
        self.walks + self.detours + self.paths
    }

    /// The escapes of `rows`.
    pub fn of(rows: &[capp_sim::plan::Row]) -> EscapeCounts {
        let mut c = EscapeCounts::default();
        for s in escapes::of_rows(rows) {
            match s.kind {
                Kind::Walk => c.walks += 1,
                Kind::Detour => c.detours += 1,
                Kind::Path => c.paths += 1,
                Kind::Search => {
                    c.searches += 1;
                    c.first_step.get_or_insert(s.step);
                    continue;
                }
                Kind::Return => {
                    c.returned = true;
                    continue;
                }
            }
            c.sides.push((s.kind, s.side));
            c.first_step.get_or_insert(s.step);
        }
        c
    }
}

/// A run's drive figures ([`capp_sim::drive_check::DriveReport`], in brief).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DriveFigures {
    /// Rows not at `t = k dt`.
    pub off_period: usize,
    /// Rows with a joint over its rate limit (by differences of positions).
    pub over_rate: usize,
    /// Rows over an acceleration limit.
    pub over_accel: usize,
    /// Rows over a jerk limit.
    pub over_jerk: usize,
    /// Reached with a joint above 1 % of its rate.
    pub arrives_moving: bool,
    /// Rows whose braking stop would collide.
    pub braking_collisions: usize,
    /// The largest acceleration over its limit, a ratio (`None`: one row).
    pub peak_accel: Option<f64>,
    /// The largest jerk over its limit, a ratio.
    pub peak_jerk: Option<f64>,
}

impl DriveFigures {
    /// The figures of `drive`.
    pub fn of(drive: &capp_sim::drive_check::DriveReport) -> Self {
        DriveFigures {
            off_period: drive.off_period,
            over_rate: drive.rate.rows,
            over_accel: drive.accel.rows,
            over_jerk: drive.jerk.rows,
            arrives_moving: drive.arrives_moving,
            braking_collisions: drive.braking_collisions,
            peak_accel: drive.accel.peak.as_ref().map(|p| p.ratio),
            peak_jerk: drive.jerk.peak.as_ref().map(|p| p.ratio),
        }
    }

    /// Whether any row is over the rate, acceleration or jerk limit.
    pub fn over_limit(&self) -> bool {
        self.over_rate + self.over_accel + self.over_jerk > 0
    }
}

/// One planner run, measured.
#[derive(Clone, Debug, PartialEq)]
pub struct RunMetrics {
    /// How it ended (the planner's word; `reached` is also re-checked, see `reaches`).
    pub outcome: Outcome,
    /// Whether the checker's exact final pose is within the tolerances.
    pub reaches: bool,
    /// Steps taken.
    pub steps: u32,
    /// Sum of `h`, seconds.
    pub motion_time: f64,
    /// The same path at the rate limits, seconds.
    pub same_path_time: f64,
    /// The straight joint-space line start -> final configuration at the rate limits, seconds.
    pub straight_time: f64,
    /// The least time from the start to the final configuration within the
    /// drive limits, each joint from rest to rest, seconds.
    pub rest_to_rest_time: f64,
    /// Steps after the last row outside 10x the tolerances (reached runs).
    pub steps_10x: Option<u32>,
    /// Position error at the start (the planner's, row 0).
    pub initial_position_error: f64,
    /// Exact final position error.
    pub final_position_error: f64,
    /// Exact final orientation error, when the target has an orientation.
    pub final_orientation_error: Option<f64>,
    /// Smallest `C - 1` over rows and the dense points between them.
    pub closest: Option<f64>,
    /// Checked configurations (rows and between rows) with an avoidance point
    /// inside an inflated obstacle beyond rounding (`C - 1 <= -ROUNDING`, or NaN).
    pub collisions: usize,
    /// Of those, how many were between rows.
    pub collisions_between: usize,
    /// Rows and segments between rows where two checked link capsules
    /// overlap (`capp check`'s [`ViolationKind::SelfCollision`]).
    pub self_collisions: usize,
    /// Of those, segments between rows.
    pub self_collisions_between: usize,
    /// The smallest gap of a checked pair of link capsules (length units;
    /// negative: overlap) over the rows and the configurations checked
    /// between them; `None` without self-collision checks.
    pub closest_links: Option<f64>,
    /// Checked configurations touching an inflated surface within rounding
    /// (`-ROUNDING < C - 1 <= 0`; `capp check`'s exact test counts these too).
    pub contacts: usize,
    /// Rows with a NaN or infinite value.
    pub not_finite: usize,
    /// Joint-limit violations.
    pub joint_limit: usize,
    /// Rate-limit violations.
    pub rate_limit: usize,
    /// Any other violation the checker reports (row 0 not the start, kinematics mismatch).
    pub other: usize,
    /// Configurations the dense re-check evaluated between rows.
    pub dense_checks: usize,
    /// Wall time of the planning loop, milliseconds.
    pub wall_ms: f64,
    /// Dead-end escapes.
    pub escape: EscapeCounts,
    /// What a joint drive could follow of it (issue 22).
    pub drive: DriveFigures,
    /// FNV-1a (64 bits) over every row's step, time step, joint values and
    /// `V`, as `f32` bits, and the outcome: two runs with the same
    /// fingerprint made the same trajectory to the bit (a refactor's
    /// evidence, `results.csv`'s `trajectory_bits`).
    pub fingerprint: u64,
}

impl RunMetrics {
    /// Violations of every kind that must never happen (contacts within
    /// rounding are not among them; see [`ROUNDING`]).
    pub fn violations(&self) -> usize {
        self.collisions
            + self.self_collisions
            + self.not_finite
            + self.joint_limit
            + self.rate_limit
            + self.other
    }
}

/// `max_j |b_j - a_j| / rate_j`: the time from `a` to `b` at the rate limits.
pub fn rate_time(rates: &[f64], a: &[f64], b: &[f64]) -> f64 {
    rates
        .iter()
        .zip(a.iter().zip(b))
        .map(|(r, (x, y))| (y - x).abs() / r)
        .fold(0.0, f64::max)
}

/// The joints' rate limits.
pub fn rates(problem: &Problem) -> Vec<f64> {
    problem.joints.iter().map(|j| j.max_rate as f64).collect()
}

/// Calls `f` with every point strictly between `a` and `b` on the straight
/// joint-space segment, no joint moving more than [`DENSE_STEP`] between
/// consecutive points; stops when `f` returns `false`. Returns how many it visited.
pub fn between(a: &[f64], b: &[f64], mut f: impl FnMut(&[f64]) -> bool) -> usize {
    let d = a
        .iter()
        .zip(b)
        .map(|(x, y)| (y - x).abs())
        .fold(0.0, f64::max);
    if !d.is_finite() {
        return 0;
    }
    let steps = (d / DENSE_STEP).ceil() as usize;
    let mut q = vec![0.0; a.len()];
    let mut visited = 0;
    for i in 1..steps {
        let t = i as f64 / steps as f64;
        for (k, v) in q.iter_mut().enumerate() {
            *v = a[k] + t * (b[k] - a[k]);
        }
        visited += 1;
        if !f(&q) {
            break;
        }
    }
    visited
}

/// Measures `result`, a run of `problem`.
pub fn measure(problem: &Problem, result: &RunResult) -> RunMetrics {
    let trajectory = Trajectory::from_rows(&result.rows);
    let geometry = Geometry::new(problem);
    let report = check::check_with(problem, &geometry, &trajectory);
    let count = |kind| report.violations.iter().filter(|v| v.kind == kind).count();
    let rates = rates(problem);
    let rows: Vec<Vec<f64>> = trajectory.rows.iter().map(|r| r.q.clone()).collect();

    // The checker reports every point / obstacle pair of a row in collision;
    // here each configuration is classed once by its closest pair.
    let mut closest: Option<f64> = None;
    let (mut collision_rows, mut collisions_between, mut contacts) = (0, 0, 0);
    let mut visit = |q: &[f64], at_row: bool| {
        if let Some(c) = geometry.clearance(q) {
            let (collision, contact) = class(c.value);
            collision_rows += (collision && at_row) as usize;
            collisions_between += (collision && !at_row) as usize;
            contacts += contact as usize;
            if closest.is_none_or(|m| c.value < m) {
                closest = Some(c.value);
            }
        }
    };
    let mut dense_checks = 0;
    let mut same_path_time = 0.0;
    if let Some(first) = rows.first() {
        visit(first, true);
    }
    for pair in rows.windows(2) {
        same_path_time += rate_time(&rates, &pair[0], &pair[1]);
        dense_checks += between(&pair[0], &pair[1], |q| {
            visit(q, false);
            true
        });
        visit(&pair[1], true);
    }
    let motion_time = trajectory.rows.iter().map(|r| r.h).sum();
    let straight_time = match (rows.first(), rows.last()) {
        (Some(a), Some(b)) => rate_time(&rates, a, b),
        _ => 0.0,
    };

    let rest_to_rest_time = match (rows.first(), rows.last()) {
        (Some(a), Some(b)) => {
            capp_sim::drive_check::rest_to_rest::floor_s(a, b, &problem.drive.joints)
        }
        _ => 0.0,
    };

    let steps = result.steps();
    let steps_10x = (result.outcome == Outcome::Reached).then(|| {
        let s = &problem.settings;
        let oriented = problem
            .waypoints
            .last()
            .is_some_and(|w| w.orientation.is_some());
        let outside = |r: &capp_sim::plan::Row| {
            r.position_error > 10.0 * s.position_tolerance
                || (oriented && r.orientation_error > 10.0 * s.orientation_tolerance)
        };
        match result.rows.iter().rposition(outside) {
            Some(k) => steps - result.rows[k].step,
            None => steps,
        }
    });

    RunMetrics {
        outcome: result.outcome,
        reaches: report.reaches_target,
        steps,
        motion_time,
        same_path_time,
        straight_time,
        rest_to_rest_time,
        steps_10x,
        initial_position_error: result
            .rows
            .first()
            .map_or(f64::NAN, |r| r.position_error as f64),
        final_position_error: report.final_position_error,
        final_orientation_error: report.final_orientation_error,
        closest,
        collisions: collision_rows + collisions_between,
        collisions_between,
        self_collisions: count(ViolationKind::SelfCollision),
        self_collisions_between: report.self_collisions_between,
        closest_links: report.closest_links.map(|c| c.pair.gap),
        contacts,
        not_finite: count(ViolationKind::NotFinite),
        joint_limit: count(ViolationKind::JointLimit),
        rate_limit: count(ViolationKind::RateLimit),
        other: count(ViolationKind::Shape) + count(ViolationKind::Kinematics),
        dense_checks,
        wall_ms: result.wall_time.as_secs_f64() * 1e3,
        escape: EscapeCounts::of(&result.rows),
        drive: DriveFigures::of(&report.drive),
        fingerprint: fingerprint(result),
    }
}

/// [`RunMetrics::fingerprint`] of `result`.
pub fn fingerprint(result: &RunResult) -> u64 {
    let mut h: u64 = 0xCBF2_9CE4_8422_2325;
    let mut eat = |word: u32| {
        for b in word.to_le_bytes() {
            h = (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01B3);
        }
    };
    for r in &result.rows {
        eat(r.step);
        eat(r.h.to_bits());
        r.q.iter().for_each(|x| eat(x.to_bits()));
        eat(r.v.to_bits());
    }
    eat(result.outcome as u32);
    h
}
