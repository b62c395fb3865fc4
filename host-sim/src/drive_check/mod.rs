//! Whether a trajectory is motion a joint drive can follow (issue 22),
//! measured from its positions alone against the problem's drive limits
//! ([`crate::problem::DriveLimits`]: control period `dt`, and per joint
//! `R = max_rate`, `A = max_accel`, `J = max_jerk`). Independent of the
//! planner: nothing here calls `capp-core`'s tracker; the geometry of the
//! braking stops is [`crate::geometry`]'s, as [`crate::check`] uses it.
//!
//! **Fixed period.** Row `k` must be at `t_k = k dt`, `t_k` the sum of the
//! rows' `h_s` up to it, within `1e-6 max(k, 1) dt` ([`PERIOD_TOLERANCE`],
//! relative). Every row off it is counted (so one short step puts every row
//! after it off the period).
//!
//! **Rate, acceleration, jerk**, per joint, by backward differences over
//! each row's interval `h_k` (its `h_s`; `dt` at the fixed period), with
//! rest before the first row (`q_{-1} = q_{-2} = q_{-3} = q_0`, so row 0 has
//! `v = a = j = 0` and row 1 is a start from rest):
//!
//! ```text
//! v_k = (q_k - q_{k-1}) / h_k,  a_k = (v_k - v_{k-1}) / h_k,  j_k = (a_k - a_{k-1}) / h_k
//! ```
//!
//! A row with `h_s = 0` (a refused step, or a hold while the escape
//! searches: the plan holds the arm in zero time) is taken as a hold of one
//! control period (`h_k = dt`): the drive needs at least that, and an
//! instant stop then shows as the acceleration and jerk it takes. Rows not
//! at the fixed period are measured over their actual intervals, so today's
//! variable steps get meaningful figures; at the fixed period every `h_k`
//! is `dt` and these are exactly the definitions of issue 22. A row is
//! *over* a limit when some joint has `|v| > R (1 + 1e-4) + 2u / h`, `|a| >
//! A (1 + 1e-4) + 4u / h^2` or `|j| > J (1 + 1e-4) + 8u / h^3`
//! ([`LIMIT_SLACK`]), `h` the shortest interval the difference spans and
//! `u` one `f32` ulp-bound (`f32::EPSILON` times the largest `|q|`) of the
//! positions it uses: the positions are stored as `f32`, each within `u` of
//! the value its maker meant, and `q_k - 3 q_{k-1} + 3 q_{k-2} - q_{k-3}` (the
//! jerk's numerator) amplifies that by at most 8, the acceleration's by 4,
//! the velocity's by 2. The ratios reported (*worst 3.2x its limit*) are
//! of the figure less that allowance, `(|a| - 4u / h^2) / A`.
//!
//! **Ends at rest.** When the run reached its target, the final row's
//! velocity (its last difference) must be below 1 % of every joint's rate
//! ([`AT_REST_FRACTION`], plus the rounding above), else it *arrives moving*.
//!
//! **Braking stops.** From every row not already at rest (some joint's `|v|`
//! or `|a|` beyond its rounding), with the state `(q, v, a)` of the
//! differences above, each joint brakes independently to rest at its
//! limits in ticks of `dt` ([`braking`]: the time-optimal greedy stop under
//! the same discrete definitions, so the stop itself never exceeds a
//! limit). Every tick of the stop is checked for obstacle collisions
//! (`C - 1 <= 0` for an avoidance point, the scenario's margins, as
//! [`crate::check`]) and self-collisions (a checked pair of capsules
//! overlapping by more than [`crate::check::self_tolerance`]), and so are
//! configurations between ticks: for obstacles, on the straight
//! joint-space segment, so that no frame origin (so no avoidance point,
//! each an interpolation of two) moves more than [`STOP_SPACING`] of the
//! smaller margin between checks (at most [`STOP_SAMPLES`] per tick); for
//! capsules, [`Geometry::sweep_links`]. A row whose stop collides is
//! counted once. A stop is followed for at most [`MAX_STOP_TICKS`] ticks.
//!
//! **Not enforced yet.** These are *drive figures*: [`ENFORCED`] says
//! whether they count against [`crate::check::CheckReport::accepted`].
//! Today's planner breaks them almost everywhere; the tracker of issue 22
//! will keep them, and then the switch is turned on.

pub mod braking;
pub mod rest_to_rest;

use std::fmt;

use crate::geometry::Geometry;
use crate::problem::Problem;
use crate::trajectory::Trajectory;
use braking::Brake;

/// Whether the drive figures reject a trajectory
/// ([`crate::check::CheckReport::accepted`] and `capp check`'s exit
/// status). Off while the planner does not yet track the limits (issue 22
/// in progress): today's plans would all fail, and `capp check` guards the
/// host-sim tests, the firmware's end-to-end tests and the suite. The lead
/// turns it on when the tracker lands.
pub const ENFORCED: bool = false;

/// Relative tolerance of a row's time against `k dt`.
pub const PERIOD_TOLERANCE: f64 = 1.0e-6;

/// Relative slack of the rate, acceleration and jerk limits (beyond the
/// `f32` rounding of the positions: module docs).
pub const LIMIT_SLACK: f64 = 1.0e-4;

/// A run that reached arrives at rest when every joint's final speed is
/// below this fraction of its rate.
pub const AT_REST_FRACTION: f64 = 0.01;

/// Most ticks of one braking stop followed (100 s at 0.05 s).
pub const MAX_STOP_TICKS: usize = 2000;

/// Between two checked configurations of a stop, no frame origin moves
/// more than this fraction of the smaller obstacle margin.
pub const STOP_SPACING: f64 = 0.25;

/// Most configurations checked against the obstacles between two ticks of
/// a stop.
pub const STOP_SAMPLES: usize = 1024;

/// The largest ratio of a figure to its limit, and where.
#[derive(Clone, Debug, PartialEq)]
pub struct Peak {
    /// `|figure| / limit`.
    pub ratio: f64,
    /// 0-based joint.
    pub joint: usize,
    /// `joint 3 ("name")`.
    pub joint_label: String,
    /// The row's step.
    pub step: u64,
    /// The row's line in the trajectory file.
    pub line: usize,
}

/// One limit over the rows.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Excess {
    /// Rows where some joint is over the limit (beyond rounding).
    pub rows: usize,
    /// The largest ratio to the limit over every row and joint, over or
    /// not, of the figure less its rounding allowance (module docs).
    pub peak: Option<Peak>,
}

/// A row not at `k dt`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OffPeriod {
    /// The row's step.
    pub step: u64,
    /// The row's line.
    pub line: usize,
    /// Its time (sum of `h_s`), s.
    pub time: f64,
    /// `k dt`, s.
    pub expected: f64,
}

/// A braking stop that collides.
#[derive(Clone, Debug, PartialEq)]
pub struct BrakingCollision {
    /// The step of the row it brakes from.
    pub step: u64,
    /// The row's line.
    pub line: usize,
    /// The tick of the stop where it collides (1-based; between ticks:
    /// the tick ending that segment).
    pub tick: usize,
    /// What collides, in words.
    pub what: String,
}

/// The drive figures of a trajectory (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct DriveReport {
    /// The control period measured against, s.
    pub control_period_s: f64,
    /// Rows measured.
    pub rows: usize,
    /// Rows off the fixed period.
    pub off_period: usize,
    /// The first of them.
    pub first_off_period: Option<OffPeriod>,
    /// Rate.
    pub rate: Excess,
    /// Acceleration.
    pub accel: Excess,
    /// Jerk.
    pub jerk: Excess,
    /// The final row's speed as a fraction of the rate, the fastest joint.
    pub final_speed: Option<Peak>,
    /// Whether the run reached (as the checker decides) and arrives with a
    /// joint above [`AT_REST_FRACTION`] of its rate.
    pub arrives_moving: bool,
    /// Rows whose braking stop was followed (not already at rest).
    pub stops: usize,
    /// The longest of those stops, ticks.
    pub longest_stop: usize,
    /// Stops that did not settle within [`MAX_STOP_TICKS`].
    pub unsettled_stops: usize,
    /// Rows whose braking stop collides.
    pub braking_collisions: usize,
    /// The first of them.
    pub first_braking_collision: Option<BrakingCollision>,
}

impl DriveReport {
    /// Nothing measured yet, at `control_period_s`.
    pub fn new(control_period_s: f64) -> Self {
        DriveReport {
            control_period_s,
            rows: 0,
            off_period: 0,
            first_off_period: None,
            rate: Excess::default(),
            accel: Excess::default(),
            jerk: Excess::default(),
            final_speed: None,
            arrives_moving: false,
            stops: 0,
            longest_stop: 0,
            unsettled_stops: 0,
            braking_collisions: 0,
            first_braking_collision: None,
        }
    }

    /// Whether the trajectory is motion a drive can follow: every row at
    /// the period and within every limit, at rest on arrival, every
    /// braking stop clear.
    pub fn clean(&self) -> bool {
        self.off_period == 0
            && self.rate.rows == 0
            && self.accel.rows == 0
            && self.jerk.rows == 0
            && !self.arrives_moving
            && self.braking_collisions == 0
            && self.unsettled_stops == 0
    }
}

/// Per row, the interval and each joint's backward differences (module
/// docs), with the rounding each may carry.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Differences {
    /// `h_k`, s (`dt` for row 0 and for rows with `h_s = 0`).
    pub interval: Vec<f64>,
    /// `[v, a, j]` per row, per joint.
    pub values: Vec<Vec<[f64; 3]>>,
    /// The rounding allowance of each (`2u / h`, `4u / h^2`, `8u / h^3`).
    pub rounding: Vec<Vec<[f64; 3]>>,
}

/// The backward differences of `trajectory`'s positions at period `dt`
/// (module docs).
pub fn differences(trajectory: &Trajectory, dt: f64) -> Differences {
    let rows = &trajectory.rows;
    let n = trajectory.joints;
    let mut d = Differences::default();
    let mut last = vec![[0.0f64; 3]; n];
    for (k, row) in rows.iter().enumerate() {
        let h = if k > 0 && row.h > 0.0 && row.h.is_finite() {
            row.h
        } else {
            dt
        };
        d.interval.push(h);
        let shortest = d.interval[k.saturating_sub(2)..]
            .iter()
            .fold(h, |m, &x| m.min(x));
        let back = |i: usize| &rows[k.saturating_sub(i)].q;
        let mut values = Vec::with_capacity(n);
        let mut rounding = Vec::with_capacity(n);
        for (j, prev) in last.iter_mut().enumerate() {
            let v = (row.q[j] - back(1)[j]) / h;
            let a = (v - prev[0]) / h;
            let jerk = (a - prev[1]) / h;
            *prev = [v, a, jerk];
            values.push(*prev);
            let u = f32::EPSILON as f64 * (0..4).map(|i| back(i)[j].abs()).fold(0.0, f64::max);
            rounding.push([
                2.0 * u / shortest,
                4.0 * u / shortest.powi(2),
                8.0 * u / shortest.powi(3),
            ]);
        }
        d.values.push(values);
        d.rounding.push(rounding);
    }
    d
}

/// What the braking stops are checked with.
struct Stops<'a> {
    geometry: &'a Geometry,
    problem: &'a Problem,
    dt: f64,
    /// Largest frame-origin move between obstacle checks, length units.
    spacing: f64,
    /// Capsule overlap that is a self-collision.
    self_tolerance: f64,
}

impl Stops<'_> {
    /// Follows the stop from `q` with per-joint `(v, a)`; the ticks taken
    /// and the first collision (tick, what), if any.
    fn follow(&self, q: &[f64], state: &[(f64, f64)]) -> (usize, Option<(usize, String)>) {
        let g = self.geometry;
        let limits = &self.problem.drive.joints;
        let mut brakes: Vec<Brake> = state
            .iter()
            .zip(limits)
            .map(|(&(v, a), l)| Brake::new(v, a, l, self.dt))
            .collect();
        let mut prev = q.to_vec();
        let mut prev_pose = g.pose(&prev);
        let mut prev_gaps = g.link_gaps(&prev_pose);
        let mut next = prev.clone();
        let mut sample = prev.clone();
        for tick in 1..=MAX_STOP_TICKS {
            let mut moved = false;
            for (x, b) in next.iter_mut().zip(&mut brakes) {
                if let Some(dq) = b.tick() {
                    *x += dq;
                    moved = true;
                }
            }
            if !moved {
                return (tick - 1, None);
            }
            let pose = g.pose(&next);
            let travel = pose
                .origins
                .iter()
                .zip(&prev_pose.origins)
                .map(|(a, b)| {
                    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
                })
                .fold(0.0, f64::max);
            let samples = ((travel / self.spacing).ceil() as usize).clamp(1, STOP_SAMPLES);
            for i in 1..=samples {
                let t = i as f64 / samples as f64;
                for ((s, a), b) in sample.iter_mut().zip(&prev).zip(&next) {
                    *s = a + t * (b - a);
                }
                let at = if i == samples { &next } else { &sample };
                if !g.is_clear(at, 0.0) {
                    let what = match g.clearance(at) {
                        Some(c) => format!(
                            "{} inside obstacle {}{} (C-1 = {:.5}){}",
                            self.problem.describe_point(c.point as u16),
                            c.obstacle + 1,
                            self.problem.obstacle_label(c.obstacle),
                            c.value,
                            if i == samples { "" } else { ", between ticks" }
                        ),
                        None => "an obstacle".into(),
                    };
                    return (tick, Some((tick, what)));
                }
            }
            let gaps = g.link_gaps(&pose);
            let floor = -self.self_tolerance;
            let worst = g
                .worst_gap(&gaps)
                .filter(|w| w.gap.is_nan() || w.gap < floor)
                .map(|w| (w, ""))
                .or_else(|| {
                    g.sweep_links(&prev, &next, &prev_gaps, &gaps, floor, false)
                        .worst
                        .filter(|(w, _)| w.gap.is_nan() || w.gap < floor)
                        .map(|(w, _)| (w, ", between ticks"))
                });
            if let Some((w, between)) = worst {
                let what = format!(
                    "{} and {} overlap by {:.4} {}{between}",
                    self.problem.link_label(w.links.0),
                    self.problem.link_label(w.links.1),
                    -w.gap,
                    self.problem.length_unit
                );
                return (tick, Some((tick, what)));
            }
            prev.copy_from_slice(&next);
            prev_pose = pose;
            prev_gaps = gaps;
        }
        (MAX_STOP_TICKS + 1, None)
    }
}

/// Keeps the larger ratio.
fn raise(peak: &mut Option<Peak>, ratio: f64, problem: &Problem, joint: usize, row: (u64, usize)) {
    if ratio.is_finite() && peak.as_ref().is_none_or(|p| ratio > p.ratio) {
        *peak = Some(Peak {
            ratio,
            joint,
            joint_label: problem.joint_label(joint),
            step: row.0,
            line: row.1,
        });
    }
}

/// Measures `trajectory` against `problem`'s drive limits (module docs).
/// `reached`: whether the run reached its target (the checker's word);
/// `self_tolerance`: the capsule overlap that is a self-collision
/// ([`crate::check::self_tolerance`]); `scale`: the arm's size
/// ([`crate::check::scale`]), the floor of the stops' sample spacing when
/// the margins are 0. The trajectory must have the problem's joint count.
pub fn measure(
    problem: &Problem,
    geometry: &Geometry,
    trajectory: &Trajectory,
    reached: bool,
    self_tolerance: f64,
    scale: f64,
) -> DriveReport {
    let dt = problem.drive.control_period_s;
    let mut report = DriveReport::new(dt);
    let limits = &problem.drive.joints;
    if trajectory.joints != problem.joints.len() || limits.len() != trajectory.joints {
        return report;
    }
    report.rows = trajectory.rows.len();
    let diff = differences(trajectory, dt);

    // The period.
    let mut time = 0.0;
    for (k, row) in trajectory.rows.iter().enumerate() {
        time += row.h;
        let expected = k as f64 * dt;
        let on = (time - expected).abs() <= PERIOD_TOLERANCE * dt * (k.max(1) as f64);
        if !on {
            report.off_period += 1;
            report.first_off_period.get_or_insert(OffPeriod {
                step: row.step,
                line: row.line,
                time,
                expected,
            });
        }
    }

    // The limits, row by row.
    for (k, row) in trajectory.rows.iter().enumerate() {
        let at = (row.step, row.line);
        let kinds = [&mut report.rate, &mut report.accel, &mut report.jerk];
        for (i, excess) in kinds.into_iter().enumerate() {
            let mut over = false;
            for (j, l) in limits.iter().enumerate() {
                let bound = [l.max_rate, l.max_accel, l.max_jerk][i];
                // Beyond the rounding the positions may carry.
                let x = (diff.values[k][j][i].abs() - diff.rounding[k][j][i]).max(0.0);
                over |= x > bound * (1.0 + LIMIT_SLACK);
                raise(&mut excess.peak, x / bound, problem, j, at);
            }
            excess.rows += over as usize;
        }
    }

    // The end.
    if let Some(row) = trajectory.rows.last() {
        let k = trajectory.rows.len() - 1;
        let mut moving = false;
        for (j, l) in limits.iter().enumerate() {
            let v = (diff.values[k][j][0].abs() - diff.rounding[k][j][0]).max(0.0);
            moving |= v > AT_REST_FRACTION * l.max_rate;
            raise(
                &mut report.final_speed,
                v / l.max_rate,
                problem,
                j,
                (row.step, row.line),
            );
        }
        report.arrives_moving = reached && moving;
    }

    // The braking stops.
    let avoid = &problem.settings.avoidance;
    let margin = (avoid.joint_margin.min(avoid.link_margin) as f64).max(1e-3 * scale);
    let stops = Stops {
        geometry,
        problem,
        dt,
        spacing: STOP_SPACING * margin,
        self_tolerance,
    };
    for (k, row) in trajectory.rows.iter().enumerate() {
        if !row.q.iter().all(|x| x.is_finite()) {
            continue;
        }
        let state: Vec<(f64, f64)> = diff.values[k]
            .iter()
            .zip(&diff.rounding[k])
            .map(|(x, r)| {
                if x[0].abs() <= r[0] && x[1].abs() <= r[1] {
                    (0.0, 0.0)
                } else {
                    (x[0], x[1])
                }
            })
            .collect();
        if state.iter().all(|&s| s == (0.0, 0.0)) {
            continue;
        }
        report.stops += 1;
        let (ticks, hit) = stops.follow(&row.q, &state);
        report.longest_stop = report.longest_stop.max(ticks.min(MAX_STOP_TICKS));
        report.unsettled_stops += (ticks > MAX_STOP_TICKS) as usize;
        if let Some((tick, what)) = hit {
            report.braking_collisions += 1;
            report
                .first_braking_collision
                .get_or_insert(BrakingCollision {
                    step: row.step,
                    line: row.line,
                    tick,
                    what,
                });
        }
    }
    report
}

impl fmt::Display for DriveReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "drive figures (issue 22, control period {} s; {}):",
            self.control_period_s,
            if ENFORCED {
                "enforced: any of them rejects the trajectory"
            } else {
                "measured, not yet enforced: they do not reject the trajectory"
            }
        )?;
        match self.first_off_period {
            Some(o) => writeln!(
                f,
                "  period: {} of {} rows off t = k dt (first: step {}, t = {:.4} s, not {:.4} s)",
                self.off_period, self.rows, o.step, o.time, o.expected
            )?,
            None => writeln!(f, "  period: every row at t = k dt")?,
        }
        for (name, e) in [
            ("rate", &self.rate),
            ("acceleration", &self.accel),
            ("jerk", &self.jerk),
        ] {
            match &e.peak {
                Some(p) => writeln!(
                    f,
                    "  {name}: {} rows over, worst {:.3}x its limit ({}, step {})",
                    e.rows, p.ratio, p.joint_label, p.step
                )?,
                None => writeln!(f, "  {name}: {} rows over", e.rows)?,
            }
        }
        if let Some(p) = &self.final_speed {
            writeln!(
                f,
                "  end: {} at {:.1} % of its rate: {}",
                p.joint_label,
                100.0 * p.ratio,
                if self.arrives_moving {
                    "arrives moving"
                } else if p.ratio <= AT_REST_FRACTION {
                    "at rest"
                } else {
                    "moving, but the target was not reached"
                }
            )?;
        }
        write!(
            f,
            "  braking stops: {} followed (longest {} ticks), {} would collide",
            self.stops, self.longest_stop, self.braking_collisions
        )?;
        if let Some(c) = &self.first_braking_collision {
            write!(
                f,
                " (first: from step {}, tick {}: {})",
                c.step, c.tick, c.what
            )?;
        }
        if self.unsettled_stops > 0 {
            write!(
                f,
                "; {} did not settle within {MAX_STOP_TICKS} ticks",
                self.unsettled_stops
            )?;
        }
        writeln!(f)
    }
}

#[cfg(test)]
mod tests;
