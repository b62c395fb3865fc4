//! The run summary: the numbers a person wants after a run, printed on stdout
//! by `capp run` / `capp serial` and written as `summary.txt` into the output
//! folder ([`super::write_run`]): outcome, steps, final errors, the smallest
//! clearance, the closest pair of link capsules (when the scenario checks
//! self-collision; over the rows, by the independent model of
//! [`crate::geometry`]), joint range use, for a tracked plan the speed the
//! arm used ([`SpeedUse`]), the dead-end escapes told in words, setpoints,
//! wall time and, for a plan received from a board, what happened on the
//! line.

use std::fmt;

use capp_core::Outcome;

use crate::escapes::{self, Kind, Stretch};
use crate::geometry::{Geometry, LinkGap};
use crate::plan::{Row, RunResult};
use crate::problem::Problem;

/// Lower-case name of an outcome.
pub fn outcome_name(outcome: Outcome) -> &'static str {
    match outcome {
        Outcome::Reached => "reached",
        Outcome::Stalled => "stalled",
        Outcome::Capped => "capped",
    }
}

/// The numbers a person wants after a run.
#[derive(Clone, Debug, PartialEq)]
pub struct Summary {
    /// Scenario name.
    pub name: String,
    /// The reader's notes ([`Problem::notes`]).
    pub notes: Vec<String>,
    /// How it ended.
    pub outcome: Outcome,
    /// Steps taken.
    pub steps: u32,
    /// Simulated time, seconds (sum of the step sizes).
    pub sim_time_s: f64,
    /// Final position error and its tolerance.
    pub position_error: (f32, f32),
    /// Final orientation error and its tolerance (`None` when the target has no orientation).
    pub orientation_error: Option<(f32, f32)>,
    /// Smallest clearance `C - 1` seen: value, step, point description, obstacle label.
    pub min_clearance: Option<(f32, u32, String, String)>,
    /// The closest pair of checked link capsules over the rows and its
    /// step (`None`: self-collision off; `Some(None)`: no pair checked).
    pub closest_links: Option<Option<(LinkGap, u32)>>,
    /// Largest `|f_i|` (eq. 18: 1 at a limit) over all steps: value, joint label.
    pub range_use: (f32, String),
    /// Setpoints written.
    pub setpoints: usize,
    /// Wall time of the planning, seconds.
    pub wall_time_s: f64,
    /// Length unit name.
    pub unit: String,
    /// For a plan received from a board: what happened on the line.
    pub link: Option<crate::serial::LinkReport>,
    /// Where the planner escaped dead ends (`None`: not known, a plan
    /// received from a board).
    pub escapes: Option<EscapeSummary>,
    /// How fast a tracked plan moved (`None`: a stepped plan, or no tick
    /// moved).
    pub speed: Option<SpeedUse>,
}

/// How much of its joints' rate limits a tracked plan used, and how often
/// the tracker refused a candidate tick (issue 22): near obstacles the
/// stop after every tick must fit the room, so the arm moves slower than
/// the law asks; these say how much slower.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpeedUse {
    /// Rows that moved (every tick is a row of a plan made here; a board's
    /// stream has its setpoints): some joint above
    /// [`crate::drive_check::AT_REST_FRACTION`] of its rate (the rest a
    /// tracked plan arrives at).
    pub moving_rows: usize,
    /// Over those rows, the median of the largest `|v_j| / max_rate_j`.
    pub median: f64,
    /// Its largest value over the run.
    pub peak: f64,
    /// Candidate ticks the tracker refused (their stop not clear, or
    /// creeping onto a surface) and the ticks that had any (`None`: not
    /// known, a plan received from a board).
    pub refused: Option<(u64, usize)>,
}

impl SpeedUse {
    /// From the rows' velocities (one per joint, per s) against `rates`
    /// (each joint's `max_rate`, per s); `None` when no tick moved.
    pub fn new(rates: &[f64], rows: &[Row]) -> Option<SpeedUse> {
        let mut used: Vec<f64> = rows
            .iter()
            .map(|r| {
                r.velocity
                    .iter()
                    .zip(rates)
                    .map(|(&v, &rate)| (v as f64).abs() / rate)
                    .fold(0.0, f64::max)
            })
            .filter(|&u| u > crate::drive_check::AT_REST_FRACTION)
            .collect();
        if used.is_empty() {
            return None;
        }
        used.sort_by(f64::total_cmp);
        let n = used.len();
        let median = if n % 2 == 1 {
            used[n / 2]
        } else {
            0.5 * (used[n / 2 - 1] + used[n / 2])
        };
        let refused = rows.iter().try_fold((0u64, 0usize), |(sum, ticks), r| {
            r.halvings
                .map(|k| (sum + k as u64, ticks + usize::from(k > 0)))
        });
        Some(SpeedUse {
            moving_rows: n,
            median,
            peak: used[n - 1],
            refused,
        })
    }
}

/// One escape motion, as the summary tells it.
#[derive(Clone, Debug, PartialEq)]
pub struct EscapeLine {
    /// The stretch of rows.
    pub stretch: Stretch,
    /// Steps it took.
    pub steps: u32,
    /// The blocking obstacle, in words (`"payload 1"`, or `obstacle 3` when unnamed).
    pub obstacle: Option<String>,
}

/// The walk back to the best configuration once the attempts are spent.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Return {
    /// `V` at the end of the run.
    pub v: f32,
    /// The lowest `V` the law reached for that waypoint, and its step.
    pub best: (f32, u32),
    /// Steps the return took.
    pub steps: u32,
}

/// The dead-end escapes of a run.
#[derive(Clone, Debug, PartialEq)]
pub struct EscapeSummary {
    /// Every walk, detour and searched path, in order (the return is
    /// [`EscapeSummary::returned`]).
    pub attempts: Vec<EscapeLine>,
    /// Searches for a path made (each before a walk or a path of the same
    /// attempt; the arm holds still while one runs).
    pub searches: usize,
    /// The run ended by walking back to the best configuration.
    pub returned: Option<Return>,
    /// How the run ended.
    pub outcome: Outcome,
    /// Length unit name (for `V`).
    pub unit: String,
}

/// At most this many escapes are listed one per line; more are summarised.
const LISTED: usize = 3;

impl EscapeSummary {
    /// The escapes of recorded plan rows; `None` when the rows do not know
    /// them (received from a board).
    pub fn new(problem: &Problem, result: &RunResult) -> Option<EscapeSummary> {
        let rows = &result.rows[..];
        if rows.iter().any(|r| r.escape.is_none()) {
            return None;
        }
        let name = |o: u8| match problem.obstacle_names.get(o as usize) {
            Some(n) if !n.is_empty() => format!("\"{n}\""),
            _ => format!("obstacle {}", o as u32 + 1),
        };
        let stretches = escapes::of_rows(rows);
        let searches = stretches.iter().filter(|s| s.kind == Kind::Search).count();
        let attempts = stretches
            .iter()
            .filter(|s| s.kind != Kind::Return && s.kind != Kind::Search)
            .map(|s| EscapeLine {
                stretch: *s,
                steps: rows[s.end(rows.len())].step - rows[s.first].step,
                obstacle: s.side.map(|side| name(side.obstacle)),
            })
            .collect();
        let returned = stretches
            .iter()
            .find(|s| s.kind == Kind::Return)
            .and_then(|s| {
                let last = rows.last()?;
                // The law's rows of that waypoint: those whose step the law drove.
                let (best, step) = rows
                    .windows(2)
                    .filter(|w| {
                        w[1].waypoint == s.waypoint
                            && w[0].escape.and_then(escapes::classify).is_none()
                    })
                    .map(|w| (w[1].v, w[1].step))
                    .chain(
                        rows.iter()
                            .find(|r| r.waypoint == s.waypoint)
                            .map(|r| (r.v, r.step)),
                    )
                    .min_by(|a, b| a.0.total_cmp(&b.0))?;
                Some(Return {
                    v: last.v,
                    best: (best, step),
                    steps: last.step - rows[s.first].step,
                })
            });
        Some(EscapeSummary {
            attempts,
            searches,
            returned,
            outcome: result.outcome,
            unit: problem.length_unit.clone(),
        })
    }
}

/// The escapes of one kind past one obstacle (`None`: no obstacle blocking)
/// and how often each side was taken, the most used first.
struct SideGroup {
    kind: Kind,
    obstacle: Option<String>,
    sides: Vec<(String, usize)>,
}

/// `attempts` grouped by kind and obstacle, the largest group first.
fn side_groups(attempts: &[EscapeLine]) -> Vec<SideGroup> {
    let mut groups: Vec<SideGroup> = Vec::new();
    for l in attempts {
        let (kind, obstacle) = (l.stretch.kind, l.obstacle.clone());
        let side = l.stretch.side.map(escapes::side_name).unwrap_or_default();
        let at = match groups
            .iter()
            .position(|g| g.kind == kind && g.obstacle == obstacle)
        {
            Some(i) => i,
            None => {
                groups.push(SideGroup {
                    kind,
                    obstacle,
                    sides: Vec::new(),
                });
                groups.len() - 1
            }
        };
        let sides = &mut groups[at].sides;
        match sides.iter_mut().find(|s| s.0 == side) {
            Some(s) => s.1 += 1,
            None => sides.push((side, 1)),
        }
    }
    for g in &mut groups {
        g.sides.sort_by_key(|s| std::cmp::Reverse(s.1));
    }
    groups.sort_by_key(|g| std::cmp::Reverse(g.sides.iter().map(|s| s.1).sum::<usize>()));
    groups
}

/// Four decimals in a readable range, else scientific.
fn value(v: f32) -> String {
    if v != 0.0 && !(1e-3..1e5).contains(&v.abs()) {
        format!("{v:.3e}")
    } else {
        format!("{v:.4}")
    }
}

/// `"box" on its -x side`-style phrases for one escape.
fn escape_phrase(line: &EscapeLine) -> String {
    let s = &line.stretch;
    let side = s.side.map(escapes::side_name).unwrap_or_default();
    let what = match (s.kind, &line.obstacle) {
        (Kind::Detour, Some(o)) => {
            format!("detour at step {} round {o} on its {side} side", s.step)
        }
        (Kind::Path, Some(o)) => {
            format!("searched path at step {} to the {side} side of {o}", s.step)
        }
        (Kind::Path, None) => format!("searched path at step {}", s.step),
        (_, Some(o)) => format!("walk at step {} to the {side} side of {o}", s.step),
        (_, None) => format!("walk at step {} (no obstacle blocking)", s.step),
    };
    format!("{what}, {} steps", line.steps)
}

impl fmt::Display for EscapeSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        const INDENT: &str = "                   ";
        let n = self.attempts.len();
        let detours = self
            .attempts
            .iter()
            .filter(|l| l.stretch.kind == Kind::Detour)
            .count();
        let plural =
            |k: usize, one: &str, many: &str| format!("{k} {}", if k == 1 { one } else { many });
        let paths = self
            .attempts
            .iter()
            .filter(|l| l.stretch.kind == Kind::Path)
            .count();
        if n == 0 {
            writeln!(f, "escapes:           none")?;
        } else {
            let searched = if self.searches > 0 {
                format!(
                    ", {} ({} found a path)",
                    plural(self.searches, "search", "searches"),
                    paths
                )
            } else {
                String::new()
            };
            write!(
                f,
                "escapes:           {} ({}, {}{searched})",
                plural(n, "attempt", "attempts"),
                plural(detours, "detour", "detours"),
                plural(n - detours - paths, "walk", "walks")
            )?;
            if n <= LISTED {
                writeln!(f)?;
                for line in &self.attempts {
                    writeln!(f, "{INDENT}{}", escape_phrase(line))?;
                }
            } else {
                let steps: Vec<String> = self
                    .attempts
                    .iter()
                    .map(|l| l.stretch.step.to_string())
                    .collect();
                let shown = if n > 6 {
                    format!("{}, ..., {}", steps[..5].join(", "), steps[n - 1])
                } else {
                    steps.join(", ")
                };
                writeln!(f, ", starting at steps {shown}")?;
                let groups = side_groups(&self.attempts);
                let parts: Vec<String> = groups
                    .iter()
                    .take(3)
                    .map(|g| {
                        let k: usize = g.sides.iter().map(|s| s.1).sum();
                        match &g.obstacle {
                            Some(o) => {
                                let list: Vec<String> =
                                    g.sides.iter().map(|(s, c)| format!("{s} {c}")).collect();
                                let (round, what) = match g.kind {
                                    Kind::Detour => ("round ", plural(k, "detour", "detours")),
                                    Kind::Path => {
                                        ("", plural(k, "searched path", "searched paths"))
                                    }
                                    _ => ("", plural(k, "walk", "walks")),
                                };
                                format!("{round}{o} {} ({what})", list.join(", "))
                            }
                            None => {
                                format!("{} with no obstacle blocking", plural(k, "walk", "walks"))
                            }
                        }
                    })
                    .collect();
                let more = if groups.len() > 3 { "; ..." } else { "" };
                writeln!(f, "{INDENT}sides: {}{more}", parts.join("; "))?;
            }
        }
        if let Some(r) = self.returned {
            let unit = &self.unit;
            let ended = match self.outcome {
                Outcome::Stalled => format!(
                    "stalled after {}",
                    plural(n, "escape attempt", "escape attempts")
                ),
                other => format!("{} during the return", outcome_name(other)),
            };
            let (best, step) = r.best;
            if (r.v - best).abs() <= 1e-3 * best.abs() + f32::EPSILON {
                writeln!(
                    f,
                    "{INDENT}{ended}; held the best configuration, V = {} {unit}²",
                    value(r.v)
                )?;
            } else {
                // The return is a straight joint-space walk: it can be blocked.
                writeln!(
                    f,
                    "{INDENT}{ended}; the return to the best configuration (V = {} {unit}², step {step}) ended after {}, at V = {} {unit}²",
                    value(best),
                    plural(r.steps as usize, "step", "steps"),
                    value(r.v)
                )?;
            }
        }
        Ok(())
    }
}

impl Summary {
    /// Summarises `result` of `problem`.
    pub fn new(problem: &Problem, result: &RunResult) -> Summary {
        let last = result
            .rows
            .last()
            .expect("a run has at least its start row");
        let target = problem
            .waypoints
            .last()
            .expect("validated: at least one waypoint");
        let min_clearance = result
            .rows
            .iter()
            .filter_map(|r| r.clearance.map(|c| (c, r.step)))
            .min_by(|a, b| a.0.value.total_cmp(&b.0.value))
            .map(|(c, step)| {
                (
                    c.value,
                    step,
                    problem.describe_point(c.point),
                    format!(
                        "obstacle {}{}",
                        c.obstacle as usize + 1,
                        problem.obstacle_label(c.obstacle as usize)
                    ),
                )
            });
        let closest_links = problem.links.enabled.then(|| {
            let geometry = Geometry::new(problem);
            let mut closest: Option<(LinkGap, u32)> = None;
            for r in &result.rows {
                let q: Vec<f64> = r.q.iter().map(|&x| x as f64).collect();
                if let Some(pair) = geometry.closest_link_pair(&q) {
                    if closest.is_none_or(|(c, _)| pair.gap < c.gap || pair.gap.is_nan()) {
                        closest = Some((pair, r.step));
                    }
                }
            }
            closest
        });
        let mut range_use = (0.0f32, String::from("-"));
        for r in &result.rows {
            for (j, (joint, &q)) in problem.joints.iter().zip(&r.q).enumerate() {
                let f = joint.range_fraction(q).abs();
                if f > range_use.0 {
                    range_use = (f, problem.joint_label(j));
                }
            }
        }
        Summary {
            name: problem.name.clone(),
            notes: problem.notes.clone(),
            outcome: result.outcome,
            steps: result.steps(),
            sim_time_s: result.rows.iter().map(|r| r.h as f64).sum(),
            position_error: (last.position_error, problem.settings.position_tolerance),
            orientation_error: target.orientation.map(|_| {
                (
                    last.orientation_error,
                    problem.settings.orientation_tolerance,
                )
            }),
            min_clearance,
            closest_links,
            range_use,
            setpoints: result.setpoints().count(),
            wall_time_s: result.wall_time.as_secs_f64(),
            unit: problem.length_unit.clone(),
            link: None,
            escapes: EscapeSummary::new(problem, result),
            speed: if problem.settings.motion == capp_core::Motion::Tracked {
                let rates: Vec<f64> = problem.drive.joints.iter().map(|j| j.max_rate).collect();
                SpeedUse::new(&rates, &result.rows)
            } else {
                None
            },
        }
    }
}

impl fmt::Display for Summary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "scenario:          {}", self.name)?;
        for note in &self.notes {
            writeln!(f, "note:              {note}")?;
        }
        writeln!(f, "outcome:           {}", outcome_name(self.outcome))?;
        writeln!(
            f,
            "steps:             {} ({:.2} s simulated)",
            self.steps, self.sim_time_s
        )?;
        writeln!(
            f,
            "position error:    {:.4} {} (tolerance {})",
            self.position_error.0, self.unit, self.position_error.1
        )?;
        match self.orientation_error {
            Some((e, tol)) => writeln!(f, "orientation error: {e:.4} (tolerance {tol})")?,
            None => writeln!(f, "orientation error: - (target has no orientation)")?,
        }
        match &self.min_clearance {
            Some((v, step, point, obstacle)) => writeln!(
                f,
                "minimum clearance: C-1 = {v:.4} at step {step}: {point}, {obstacle}"
            )?,
            None => writeln!(f, "minimum clearance: no obstacle ever within influence")?,
        }
        match self.closest_links {
            None => {}
            Some(None) => writeln!(f, "closest link pair: none (no pair of links is checked)")?,
            Some(Some((pair, step))) => {
                let (a, b, unit) = (pair.links.0 + 1, pair.links.1 + 1, &self.unit);
                // Two decimals, four near contact.
                let length = |v: f64| {
                    if v.abs() >= 0.1 {
                        format!("{v:.2}")
                    } else {
                        format!("{v:.4}")
                    }
                };
                if pair.gap >= 0.0 {
                    writeln!(
                        f,
                        "closest link pair: links {a} and {b}, {} {unit} apart (capsules) at step {step}",
                        length(pair.gap)
                    )?
                } else {
                    writeln!(
                        f,
                        "closest link pair: links {a} and {b}, capsules overlap by {} {unit} at step {step}",
                        length(-pair.gap)
                    )?
                }
            }
        }
        writeln!(
            f,
            "joint range use:   {:.0}% of the way from centre to limit ({})",
            100.0 * self.range_use.0,
            self.range_use.1
        )?;
        if let Some(speed) = &self.speed {
            writeln!(
                f,
                "speed used:        median {:.0}% of the rate limits over {} moving rows (peak {:.0}%)",
                100.0 * speed.median,
                speed.moving_rows,
                100.0 * speed.peak
            )?;
            if let Some((candidates, ticks)) = speed.refused {
                writeln!(
                    f,
                    "refused:           {candidates} candidate ticks, on {ticks} ticks (the stop after them not clear, or creeping onto a surface)"
                )?;
            }
        }
        if let Some(escapes) = &self.escapes {
            write!(f, "{escapes}")?;
        }
        writeln!(f, "setpoints:         {}", self.setpoints)?;
        writeln!(f, "wall time:         {:.3} s", self.wall_time_s)?;
        if let Some(link) = &self.link {
            writeln!(
                f,
                "planned by:        the board (rows are its setpoints; clearance, errors, range use and speed used over them)"
            )?;
            write!(f, "{link}")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A row of two joints moving at `velocity`, with `refused` candidates.
    fn row(velocity: [f32; 2], refused: Option<u8>) -> Row {
        let mut row = Row::with_joints(1, 0.05, vec![0.0; 2]);
        row.velocity = velocity.to_vec();
        row.halvings = refused;
        row
    }

    #[test]
    fn speed_use_is_the_most_loaded_joint_over_the_moving_rows() {
        // Rates 2 and 0.5 per s: the ticks use 0.25, 0.8 (joint 2 against
        // its own rate, not joint 1's larger speed), 0.5 and 1.0; the first
        // and last rows are at rest (below 1 % of either rate), not counted.
        let rates = [2.0, 0.5];
        let rows = [
            row([0.0, 0.004], Some(0)),
            row([0.5, 0.1], Some(2)),
            row([-1.5, 0.4], Some(0)),
            row([1.0, -0.2], Some(1)),
            row([0.3, -0.5], Some(3)),
            row([0.01, 0.0], Some(0)),
        ];
        let speed = SpeedUse::new(&rates, &rows).unwrap();
        assert_eq!(speed.moving_rows, 4);
        // Sorted 0.25, 0.5, 0.8, 1.0: the median is between the middle two.
        assert!((speed.median - 0.65).abs() < 1e-6, "{speed:?}");
        assert!((speed.peak - 1.0).abs() < 1e-6, "{speed:?}");
        assert_eq!(speed.refused, Some((6, 3)));
    }

    #[test]
    fn speed_use_knows_no_refusals_a_board_did_not_send_and_no_speed_at_rest() {
        let rates = [1.0, 1.0];
        let rows = [row([0.0, 0.0], None), row([0.3, 0.1], None)];
        let speed = SpeedUse::new(&rates, &rows).unwrap();
        assert_eq!((speed.moving_rows, speed.refused), (1, None));
        assert!((speed.median - 0.3).abs() < 1e-6);
        assert_eq!(SpeedUse::new(&rates, &[row([0.001, 0.0], Some(0))]), None);
    }
}
