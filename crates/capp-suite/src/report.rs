//! The report: markdown tables per family and variant, overall, the shipped
//! scenarios, the oracle, the stalled cases; and the per-case CSV.
//!
//! Medians and percentiles are nearest-rank over the runs a column names;
//! times and ratios are over reached runs (a stalled run's time says nothing
//! about how long a motion takes), counts over every run.

use std::fmt::Write as _;

use capp_core::Outcome;
use capp_sim::escapes::Kind;

use crate::families::Family;
use crate::metrics::RunMetrics;
use crate::oracle::Budget;
use crate::runner::CaseResult;
use crate::variants::Variant;

/// A shipped scenario run with one variant.
#[derive(Clone, Debug)]
pub struct ShippedRun {
    /// File name.
    pub scenario: String,
    /// The variant.
    pub variant: Variant,
    /// `time_step_s` of the file.
    pub time_step: f32,
    /// The run.
    pub metrics: Result<RunMetrics, String>,
}

/// What the header says about the run.
#[derive(Clone, Debug)]
pub struct RunInfo {
    /// The seed.
    pub seed: u64,
    /// Cases per family, as generated.
    pub counts: Vec<(String, usize)>,
    /// Threads used.
    pub threads: usize,
    /// CPU and toolchain.
    pub machine: String,
    /// Wall time of the whole run, seconds.
    pub wall_s: f64,
    /// The oracle's budget.
    pub budget: Budget,
    /// The command that made it.
    pub command: String,
}

/// Nearest-rank percentile `p` (0..=1) of `values`.
pub fn percentile(values: &[f64], p: f64) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let rank = ((p * v.len() as f64).ceil() as usize).clamp(1, v.len());
    Some(v[rank - 1])
}

/// The median.
pub fn median(values: &[f64]) -> Option<f64> {
    percentile(values, 0.5)
}

/// An integer with thin groups of three ("13 901").
pub fn grouped(x: f64) -> String {
    let v = x.round() as i64;
    let digits = v.unsigned_abs().to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(' ');
        }
        out.push(c);
    }
    if v < 0 {
        format!("-{out}")
    } else {
        out
    }
}

fn opt(x: Option<f64>, digits: usize) -> String {
    x.map_or("-".into(), |v| format!("{v:.digits$}"))
}

fn opt_int(x: Option<f64>) -> String {
    x.map_or("-".into(), grouped)
}

fn pct(num: usize, den: usize) -> String {
    if den == 0 {
        "-".into()
    } else {
        format!("{:.0} %", 100.0 * num as f64 / den as f64)
    }
}

/// One row of the family x variant (or overall) table.
struct Tally<'a> {
    runs: Vec<(&'a CaseResult, &'a RunMetrics)>,
    errors: usize,
    cases: usize,
    certified: usize,
}

impl<'a> Tally<'a> {
    fn new(results: &[&'a CaseResult], variant: &str) -> Self {
        let mut runs = Vec::new();
        let mut errors = 0;
        for r in results {
            for v in r.runs.iter().filter(|v| v.variant.name == variant) {
                match &v.metrics {
                    Ok(m) => runs.push((*r, m)),
                    Err(_) => errors += 1,
                }
            }
        }
        Tally {
            runs,
            errors,
            cases: results.len(),
            certified: results.iter().filter(|r| certified(r)).count(),
        }
    }

    fn count(&self, outcome: Outcome) -> usize {
        self.runs
            .iter()
            .filter(|(_, m)| m.outcome == outcome)
            .count()
    }

    fn reached(&self) -> impl Iterator<Item = &(&'a CaseResult, &'a RunMetrics)> {
        self.runs
            .iter()
            .filter(|(_, m)| m.outcome == Outcome::Reached)
    }

    fn reached_values(&self, f: impl Fn(&CaseResult, &RunMetrics) -> Option<f64>) -> Vec<f64> {
        self.reached().filter_map(|(c, m)| f(c, m)).collect()
    }

    fn row(&self, lead: &str) -> String {
        let reached = self.count(Outcome::Reached);
        let reached_certified = self.reached().filter(|(c, _)| certified(c)).count();
        let collisions: usize = self.runs.iter().map(|(_, m)| m.collisions).sum();
        let self_collisions: usize = self.runs.iter().map(|(_, m)| m.self_collisions).sum();
        let self_checked = self.runs.iter().any(|(_, m)| m.closest_links.is_some());
        let contacts: usize = self.runs.iter().map(|(_, m)| m.contacts).sum();
        let broken: usize = self
            .runs
            .iter()
            .map(|(_, m)| m.not_finite + m.joint_limit + m.rate_limit + m.other)
            .sum();
        let steps = self.reached_values(|_, m| Some(m.steps as f64));
        let motion = self.reached_values(|_, m| Some(m.motion_time));
        let same = self.reached_values(|_, m| ratio(m.motion_time, m.same_path_time));
        let straight = self.reached_values(|_, m| ratio(m.motion_time, m.straight_time));
        let vs_rrt = self.reached_values(|c, m| {
            c.oracle
                .as_ref()
                .and_then(|o| o.path_time)
                .and_then(|t| ratio(m.motion_time, t))
        });
        let fine = self.reached_values(|_, m| m.steps_10x.map(|s| s as f64));
        let wall: Vec<f64> = self.runs.iter().map(|(_, m)| m.wall_ms).collect();
        let mut errors = String::new();
        if self.errors > 0 {
            errors = format!(" ({} refused)", self.errors);
        }
        let unconfirmed = self.reached().filter(|(_, m)| !m.reaches).count();
        let unconfirmed = if unconfirmed > 0 {
            format!(" ({unconfirmed} not confirmed by the checker)")
        } else {
            String::new()
        };
        format!(
            "| {lead} | {}{errors} | {} | {}{unconfirmed} | {} | {} | {} | {}{} | {} | {} | {} / {} / {} | {} | {} | {} | {} | {} / {} | {} |",
            self.cases,
            self.certified,
            reached,
            self.count(Outcome::Stalled),
            self.count(Outcome::Capped),
            pct(reached_certified, self.certified),
            collisions,
            if broken > 0 { format!(" (+{broken} limit/NaN)") } else { String::new() },
            if self_checked { self_collisions.to_string() } else { "off".into() },
            contacts,
            opt_int(median(&steps)),
            opt_int(percentile(&steps, 0.9)),
            opt_int(steps.iter().copied().reduce(f64::max)),
            opt(median(&motion), 1),
            opt(median(&same), 1),
            opt(median(&straight), 1),
            opt(median(&vs_rrt), 1),
            opt_int(median(&fine)),
            opt_int(fine.iter().copied().reduce(f64::max)),
            opt(median(&wall), 1),
        )
    }
}

/// The motion times of the escaped-and-reached runs with an RRT path, and
/// the RRT shortcut paths' times on the same cases.
fn escaped_times(runs: &[(&CaseResult, &RunMetrics)]) -> (Vec<f64>, Vec<f64>) {
    runs.iter()
        .filter(|(_, m)| m.outcome == Outcome::Reached && m.escape.attempts() > 0)
        .filter_map(|(c, m)| Some((m.motion_time, c.oracle.as_ref()?.path_time?)))
        .unzip()
}

/// `12: -x 5, +x 4, none 3`: how often each side was taken by `kind`.
fn side_counts(runs: &[(&CaseResult, &RunMetrics)], kind: Kind) -> String {
    let mut counts: Vec<(String, usize)> = Vec::new();
    for (_, m) in runs {
        for (k, side) in &m.escape.sides {
            if *k != kind {
                continue;
            }
            let name = side.map_or("none".to_string(), capp_sim::escapes::side_name);
            match counts.iter_mut().find(|c| c.0 == name) {
                Some(c) => c.1 += 1,
                None => counts.push((name, 1)),
            }
        }
    }
    let total: usize = counts.iter().map(|c| c.1).sum();
    if total == 0 {
        return "-".into();
    }
    counts.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    let list: Vec<String> = counts.iter().map(|(n, c)| format!("{n} {c}")).collect();
    format!("{total}: {}", list.join(", "))
}

impl Tally<'_> {
    fn escape_row(&self, lead: &str) -> String {
        let escaped: Vec<_> = self
            .runs
            .iter()
            .filter(|(_, m)| m.escape.attempts() > 0)
            .copied()
            .collect();
        let reached: Vec<f64> = escaped
            .iter()
            .filter(|(_, m)| m.outcome == Outcome::Reached)
            .map(|(_, m)| m.escape.attempts() as f64)
            .collect();
        let (motion, rrt) = escaped_times(&self.runs);
        let ratios: Vec<f64> = motion
            .iter()
            .zip(&rrt)
            .filter_map(|(&a, &b)| ratio(a, b))
            .collect();
        let of_medians = median(&motion)
            .zip(median(&rrt))
            .and_then(|(a, b)| ratio(a, b));
        let returned = self.runs.iter().filter(|(_, m)| m.escape.returned).count();
        format!(
            "| {lead} | {} | {} | {} | {} / {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            self.runs.len(),
            escaped.len(),
            reached.len(),
            opt(median(&reached), 0),
            opt_int(reached.iter().copied().reduce(f64::max)),
            opt(median(&motion), 1),
            opt(median(&rrt), 1),
            opt(of_medians, 2),
            opt(median(&ratios), 2),
            returned,
            side_counts(&self.runs, Kind::Detour),
            side_counts(&self.runs, Kind::Walk),
            side_counts(&self.runs, Kind::Path),
        )
    }
}

impl Tally<'_> {
    fn drive_row(&self, lead: &str) -> String {
        let runs = self.runs.len();
        let share = |f: &dyn Fn(&RunMetrics) -> bool| {
            let n = self.runs.iter().filter(|(_, m)| f(m)).count();
            format!("{n} ({})", pct(n, runs))
        };
        let reached = self.count(Outcome::Reached);
        let moving = self
            .reached()
            .filter(|(_, m)| m.drive.arrives_moving)
            .count();
        let peaks = |f: &dyn Fn(&RunMetrics) -> Option<f64>| -> Vec<f64> {
            self.runs.iter().filter_map(|(_, m)| f(m)).collect()
        };
        let accel = peaks(&|m| m.drive.peak_accel);
        let jerk = peaks(&|m| m.drive.peak_jerk);
        let floor = self.reached_values(|_, m| ratio(m.motion_time, m.rest_to_rest_time));
        format!(
            "| {lead} | {runs} | {} | {} | {} / {} / {} | {moving} of {reached} ({}) | {} | {} / {} | {} / {} | {} |",
            share(&|m| m.drive.off_period > 0),
            share(&|m| m.drive.over_limit()),
            share(&|m| m.drive.over_rate > 0),
            share(&|m| m.drive.over_accel > 0),
            share(&|m| m.drive.over_jerk > 0),
            pct(moving, reached),
            share(&|m| m.drive.braking_collisions > 0),
            opt(median(&accel), 1),
            opt(accel.iter().copied().reduce(f64::max), 1),
            opt(median(&jerk), 1),
            opt(jerk.iter().copied().reduce(f64::max), 1),
            opt(median(&floor), 2),
        )
    }
}

const DRIVE_HEAD: &str = "| runs | any row off the period | any row over a limit | over rate / acceleration / jerk | reached, arriving moving | any braking stop colliding | peak acceleration / limit, median / max | peak jerk / limit, median / max | motion time / rest-to-rest floor, reached, median |";
const DRIVE_RULE: &str = "|---|---|---|---|---|---|---|---|---|";

const ESCAPE_HEAD: &str = "| runs | escaped (any attempt) | escaped and reached | attempts of those, median / max | their motion time, median (s) | RRT shortcut path on the same cases, median (s) | motion / RRT: ratio of the medians | motion / RRT: median of the ratios | ended by the return (attempts spent) | detours: sides taken | walks: sides taken | searched paths: sides taken |";
const ESCAPE_RULE: &str = "|---|---|---|---|---|---|---|---|---|---|---|---|";

const TABLE_HEAD: &str = "| cases | RRT-certified | reached | stalled | capped | reached % of certified | collisions | self-collisions | contacts within rounding | steps median / p90 / max | motion time median (s) | motion / same path at rate limits | motion / straight line at rate limits | motion / RRT path | steps 10x tol -> tol median / max | wall ms per run median |";
const TABLE_RULE: &str = "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|";

fn ratio(a: f64, b: f64) -> Option<f64> {
    (b > 0.0 && a.is_finite()).then(|| a / b)
}

/// Whether the oracle certified the case.
pub fn certified(r: &CaseResult) -> bool {
    r.oracle.as_ref().is_some_and(|o| o.solved)
}

/// The markdown report.
pub fn markdown(
    info: &RunInfo,
    families: &[Family],
    variants: &[Variant],
    results: &[CaseResult],
    shipped: &[ShippedRun],
) -> String {
    markdown_with_figures(info, families, variants, results, shipped, &[])
}

/// One table line per family (those with results) and variant: `row` of
/// their tally, led by `family | variant`.
fn family_rows(
    s: &mut String,
    results: &[CaseResult],
    families: &[Family],
    variants: &[Variant],
    row: impl Fn(&Tally, &str) -> String,
) {
    for f in families {
        let of: Vec<&CaseResult> = results.iter().filter(|r| r.case.family == f.name).collect();
        if of.is_empty() {
            continue;
        }
        for v in variants {
            let line = row(
                &Tally::new(&of, v.name),
                &format!("{} | {}", f.name, v.name),
            );
            let _ = writeln!(s, "{line}");
        }
    }
}

/// [`markdown`] with `figures` (relative path, alt text, caption) embedded
/// after the overall table.
pub fn markdown_with_figures(
    info: &RunInfo,
    families: &[Family],
    variants: &[Variant],
    results: &[CaseResult],
    shipped: &[ShippedRun],
    figures: &[(String, String, String)],
) -> String {
    let mut s = String::new();
    let total: usize = info.counts.iter().map(|c| c.1).sum();
    let counts: Vec<String> = info
        .counts
        .iter()
        .map(|(f, n)| format!("{f} {n}"))
        .collect();
    let _ = writeln!(
        s,
        "# Planning quality\n\n\
         Generated by `{}` (`crates/capp-suite`); do not edit by hand, run it again. \
         Seed {}; {total} cases ({}); variants: {}. Machine: {}; {} threads; the whole run took {:.0} s \
         (wall times below are per run, with the other thread busy on the same 2 cores: noisy).\n",
        info.command,
        info.seed,
        counts.join(", "),
        variants.iter().map(|v| format!("`{}`", v.name)).collect::<Vec<_>>().join(", "),
        info.machine,
        info.threads,
        info.wall_s,
    );
    s.push_str(
        "Every case is an ordinary scenario file planned as `capp run` plans it \
         (`capp-core`, `Planner<32>`); `cargo xtask suite --write-cases DIR` writes them, \
         and every run that did not reach its target is written to `target/suite/cases/` \
         with its variant's settings, so `capp run target/suite/cases/NAME.toml` reproduces it. \
         Collisions, self-collisions, NaN, joint and rate limits are counted by the independent \
         `f64` checker (`capp_sim::check`), on every row and densely between rows (no joint moving \
         more than 0.01 rad or 0.01 length units between obstacle checks; wherever two checked \
         link capsules may come near, no link moving more than a quarter of its capsule radius \
         between capsule checks), never by the planner's own flags. *Self-collisions*: rows and \
         segments between rows where two checked link capsules (`capp acm`) overlap by more than \
         `f32` rounding (`off`: the cases do not check self-collision). \
         Per-case figures: `target/suite/results.csv`.\n\n",
    );
    s.push_str("Families:\n\n");
    for f in families {
        let _ = writeln!(s, "- `{}`: {}.", f.name, f.description);
    }
    s.push_str("\nVariants:\n\n");
    for v in variants {
        let settings = if v.settings.is_empty() {
            "no settings added".to_string()
        } else {
            format!("`{}`", v.settings.replace('\n', "`, `"))
        };
        let _ = writeln!(s, "- `{}`: {} ({settings}).", v.name, v.description);
    }
    let _ = writeln!(
        s,
        "\nThe oracle is RRT-Connect in joint space, start to goal configuration \
         (`crates/capp-suite/src/oracle.rs`): distances in seconds at the rate limits, \
         every edge checked densely by the same independent checker, at most {} iterations \
         and {} nodes per case (no time limit, so it repeats on any machine), the path re-checked \
         densely and shortened by {} random shortcuts. A case it solves is *certified* \
         solvable; one it does not is *not certified* (perhaps unsolvable, perhaps beyond the budget).\n",
        info.budget.iterations, info.budget.nodes, info.budget.shortcuts
    );
    s.push_str(
        "Columns: steps, times and ratios are medians over the runs that reached their target; \
         *same path at rate limits* is `sum_k max_j |dq_j| / max_rate_j` over the run's steps, \
         *straight line* `max_j |q_end_j - q_start_j| / max_rate_j`, *RRT path* the oracle's \
         shortcut path at the rate limits (cases both solve); *steps 10x tol -> tol* counts the \
         steps after the last one whose position error exceeded 10 x the position tolerance \
         (or orientation error 10 x its tolerance); *wall ms* is the planning loop alone.\n",
    );

    // Per family and variant.
    s.push_str("\n## Per family and variant\n\n");
    let _ = writeln!(s, "| family | variant {TABLE_HEAD}");
    let _ = writeln!(s, "|---|---{TABLE_RULE}");
    let all: Vec<&CaseResult> = results.iter().collect();
    family_rows(&mut s, results, families, variants, |t, lead| t.row(lead));

    s.push_str("\n## Overall\n\n");
    let _ = writeln!(s, "| variant {TABLE_HEAD}");
    let _ = writeln!(s, "|---{TABLE_RULE}");
    for v in variants {
        let _ = writeln!(s, "{}", Tally::new(&all, v.name).row(v.name));
    }

    // Drive figures (issue 22).
    s.push_str(
        "\n## What a joint drive could follow (issue 22)\n\n\
         Measured by the independent checker from the positions alone (`capp_sim::drive_check`, \
         `capp check`'s *drive figures*), against each joint's rate, acceleration and jerk limits \
         (defaults: full rate from rest in 0.5 s, full acceleration in 0.1 s) and the fixed control \
         period (0.05 s): *off the period*, a row not at `t = k dt`; *over a limit*, a row where \
         some joint's backward difference (velocity, acceleration or jerk, over the row's own \
         interval, a zero-time hold as one period, rest before the first row) exceeds its limit \
         beyond `f32` rounding; *arriving moving*, a reached run whose last row has a joint above \
         1 % of its rate; *braking stop colliding*, a run with a row from which each joint braking \
         to rest at its limits would hit an obstacle or another link (every tick and densely \
         between). Shares of runs; the peaks are the largest ratio per run. *Rest-to-rest floor*: \
         the least time any motion within the limits takes from the run's start to its final \
         configuration, each joint alone from rest to rest (`capp_sim::drive_check::rest_to_rest`); \
         no plan between the same configurations can beat it, so a stepped plan's ratio below 1 is \
         time no drive could follow, and `1 / ratio` is the least slowdown any drive-followable \
         plan of the same move must take against it. The stepped variants do not track these \
         limits (`motion = \"tracked\"` does, issue 22).\n\n",
    );
    let _ = writeln!(s, "| family | variant {DRIVE_HEAD}");
    let _ = writeln!(s, "|---|---{DRIVE_RULE}");
    family_rows(&mut s, results, families, variants, |t, lead| {
        t.drive_row(lead)
    });
    for v in variants {
        let _ = writeln!(
            s,
            "{}",
            Tally::new(&all, v.name).drive_row(&format!("all | {}", v.name))
        );
    }

    // Figures (a full run writes them).
    if !figures.is_empty() {
        s.push_str("\n## Figures\n");
        for (path, alt, caption) in figures {
            let _ = writeln!(s, "\n![{alt}]({path})\n\n{caption}");
        }
    }

    // Dead-end escapes.
    s.push_str(
        "\n## Dead-end escapes\n\n\
         When the law stops making progress short of the target, the planner escapes \
         (`capp-core`'s `escape`): detours send the end effector round the blocking obstacle; \
         then a search (`capp-core`'s `tree`, the first attempts of a waypoint, the arm holding \
         still) looks for a goal configuration and a tree to it and walks its path (*searched \
         paths*), or random walks move the joints away from the dead end; up to the scenario's \
         attempts per waypoint; then it walks back to the best configuration and ends `stalled` (*ended by the \
         return*). Counted from the planner's step reports (the trajectory's `escape` column). \
         *Escaped*: runs with at least one attempt; attempts and motion times are over the \
         escaped runs that reached, the motion time and the RRT comparison over those whose case \
         the oracle solved (its shortcut path at the rate limits). *Sides*: the side of the \
         blocking obstacle each attempt took, an axis of the obstacle's own frame (*none*: a walk \
         with no obstacle blocking), over all runs.\n\n",
    );
    let _ = writeln!(s, "| family | variant {ESCAPE_HEAD}");
    let _ = writeln!(s, "|---|---{ESCAPE_RULE}");
    family_rows(&mut s, results, families, variants, |t, lead| {
        t.escape_row(lead)
    });
    for v in variants {
        let _ = writeln!(
            s,
            "{}",
            Tally::new(&all, v.name).escape_row(&format!("all | {}", v.name))
        );
    }
    if let Some(default) = variants.first() {
        let (motion, rrt) = escaped_times(&Tally::new(&all, default.name).runs);
        let ratios: Vec<f64> = motion
            .iter()
            .zip(&rrt)
            .filter_map(|(&a, &b)| ratio(a, b))
            .collect();
        let verdict = |r: f64| if r <= 2.0 { "met" } else { "missed" };
        let text = match (median(&motion).zip(median(&rrt)), median(&ratios)) {
            (Some((m, r)), Some(each)) if r > 0.0 => format!(
                "over the {} escaped cases reached with an RRT path, the median motion time is \
                 {m:.1} s against {r:.1} s, {:.3}x ({}); the median of the per-case ratios is \
                 {each:.3}x ({})",
                motion.len(),
                m / r,
                verdict(m / r),
                verdict(each)
            ),
            _ => "no escaped case was reached".into(),
        };
        let _ = writeln!(
            s,
            "\nThe target (issue 13): the median motion time of escaped cases within 2x the \
             rate-limited time of RRT-Connect's shortcut path on the same cases. `{}`, all \
             families: {text}.",
            default.name
        );
    }

    // The oracle.
    s.push_str("\n## RRT-Connect (the oracle)\n\n");
    s.push_str("| family | cases | certified | certified % | time median / max (ms) | iterations median / max | path as found, median (s at rate limits) | shortcut path, median (s at rate limits) |\n|---|---|---|---|---|---|---|---|\n");
    let mut oracle_row = |label: &str, of: &[&CaseResult]| {
        let solved: Vec<&CaseResult> = of.iter().copied().filter(|r| certified(r)).collect();
        let time: Vec<f64> = of
            .iter()
            .filter_map(|r| r.oracle.as_ref().map(|o| o.wall_ms))
            .collect();
        let iterations: Vec<f64> = of
            .iter()
            .filter_map(|r| r.oracle.as_ref().map(|o| o.iterations as f64))
            .collect();
        let raw: Vec<f64> = solved
            .iter()
            .filter_map(|r| r.oracle.as_ref()?.raw_time)
            .collect();
        let short: Vec<f64> = solved
            .iter()
            .filter_map(|r| r.oracle.as_ref()?.path_time)
            .collect();
        let _ = writeln!(
            s,
            "| {label} | {} | {} | {} | {} / {} | {} / {} | {} | {} |",
            of.len(),
            solved.len(),
            pct(solved.len(), of.len()),
            opt(median(&time), 0),
            opt(time.iter().copied().reduce(f64::max), 0),
            opt_int(median(&iterations)),
            opt_int(iterations.iter().copied().reduce(f64::max)),
            opt(median(&raw), 1),
            opt(median(&short), 1),
        );
    };
    for f in families {
        let of: Vec<&CaseResult> = results.iter().filter(|r| r.case.family == f.name).collect();
        if !of.is_empty() {
            oracle_row(f.name, &of);
        }
    }
    oracle_row("all", &all);
    let uncertified: Vec<&str> = results
        .iter()
        .filter(|r| !certified(r))
        .map(|r| r.case.name.as_str())
        .collect();
    if !uncertified.is_empty() {
        let _ = writeln!(s, "\nNot certified: {}.", uncertified.join(", "));
    }
    let solved_anyway: Vec<String> = results
        .iter()
        .filter(|r| !certified(r))
        .filter_map(|r| {
            let by: Vec<&str> = r
                .runs
                .iter()
                .filter(|v| {
                    v.metrics
                        .as_ref()
                        .is_ok_and(|m| m.outcome == Outcome::Reached)
                })
                .map(|v| v.variant.name)
                .collect();
            (!by.is_empty()).then(|| format!("{} ({})", r.case.name, by.join(", ")))
        })
        .collect();
    if !solved_anyway.is_empty() {
        let _ = writeln!(
            s,
            "\nNot certified but reached by the planner (so solvable: the oracle's budget was too small): {}.",
            solved_anyway.join(", ")
        );
    }

    // Shipped scenarios.
    if !shipped.is_empty() {
        s.push_str(
            "\n## The shipped scenarios\n\n\
             `host-sim/scenarios/`, as shipped, each with every variant's settings added.\n\n\
             | scenario | variant | outcome | steps | motion time (sum of h) | same path at the rate limits | straight joint-space line at the rate limits | time step |\n\
             |---|---|---|---|---|---|---|---|\n",
        );
        for r in shipped {
            match &r.metrics {
                Ok(m) => {
                    let _ = writeln!(
                        s,
                        "| `{}` | {} | {} | {} | {:.1} s | {:.1} s | {:.1} s | {} s |",
                        r.scenario,
                        r.variant.name,
                        capp_sim::output::summary::outcome_name(m.outcome),
                        grouped(m.steps as f64),
                        m.motion_time,
                        m.same_path_time,
                        m.straight_time,
                        r.time_step
                    );
                }
                Err(e) => {
                    let _ = writeln!(
                        s,
                        "| `{}` | {} | refused: {e} | | | | | |",
                        r.scenario, r.variant.name
                    );
                }
            }
        }
    }

    // Safety findings.
    let mut unsafe_runs = Vec::new();
    for r in results {
        for v in &r.runs {
            if let Ok(m) = &v.metrics {
                if m.violations() > 0 || m.contacts > 0 {
                    unsafe_runs.push(format!(
                        "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                        r.case.name,
                        v.variant.name,
                        capp_sim::output::summary::outcome_name(m.outcome),
                        m.collisions - m.collisions_between,
                        m.collisions_between,
                        m.contacts,
                        m.closest.map_or("-".into(), |c| format!("{c:.2e}")),
                        m.self_collisions - m.self_collisions_between,
                        m.self_collisions_between,
                        m.closest_links.map_or("-".into(), |g| format!("{g:.3}")),
                        m.not_finite + m.joint_limit + m.rate_limit,
                        m.other
                    ));
                }
            }
        }
    }
    s.push_str("\n## Runs the checker rejects\n\n");
    if unsafe_runs.is_empty() {
        s.push_str("None: no collision, self-collision or contact (rows or between rows), NaN, joint- or rate-limit violation in any run.\n");
    } else {
        let _ = writeln!(
            s,
            "{} runs. *Collisions at rows*: recorded configurations with a point inside an inflated \
             obstacle by more than rounding (`C - 1 <= -1e-4`); *between rows*: dense points on the \
             straight joint-space segment between two recorded configurations, both clear, that are \
             inside (the step jumped through an edge or a corner); *contacts*: configurations with \
             `-1e-4 < C - 1 <= 0`, on the inflated surface within what the planner's `f32` arithmetic \
             decides (`capp check`'s exact test rejects them too; the margins, 3 to 6 in for PIPS, \
             are what keeps the arm off the real surface); *closest*: the smallest `C - 1` seen; \
             *self-collisions at rows* / *between rows*: rows and segments between rows where two \
             checked link capsules overlap; *closest link gap*: the smallest gap between checked \
             capsules seen (length units, negative: overlap).\n",
            unsafe_runs.len()
        );
        s.push_str("| case | variant | outcome | collisions at rows | collisions between rows | contacts within rounding | closest C - 1 | self-collisions at rows | self-collisions between rows | closest link gap | limit / NaN violations | other |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n");
        for line in unsafe_runs {
            let _ = writeln!(s, "{line}");
        }
    }

    // Dead ends of the default variant.
    if let Some(default) = variants.first() {
        const PER_FAMILY: usize = 12;
        let missed = |r: &CaseResult| -> Option<RunMetrics> {
            let m = r.runs.iter().find(|v| v.variant.name == default.name)?;
            let m = m.metrics.as_ref().ok()?;
            (m.outcome != Outcome::Reached).then(|| m.clone())
        };
        let total = results
            .iter()
            .filter(|r| certified(r) && missed(r).is_some())
            .count();
        let _ = writeln!(
            s,
            "\n## Dead ends: certified cases `{}` did not reach ({total})\n\n\
             The oracle found a path, the planner did not: what the next issues are judged on. \
             Final errors are exact (the checker's kinematics), *closest* is the smallest `C - 1` \
             over the run (0: the inflated surface). At most {PER_FAMILY} per family here; \
             `target/suite/results.csv` has every run and `target/suite/cases/` every file.\n\n\
             | case | what | outcome | steps | position error: start -> end | final orientation error | closest C - 1 |\n|---|---|---|---|---|---|---|",
            default.name,
        );
        for f in families {
            let of: Vec<(&CaseResult, RunMetrics)> = results
                .iter()
                .filter(|r| r.case.family == f.name && certified(r))
                .filter_map(|r| missed(r).map(|m| (r, m)))
                .collect();
            for (r, m) in of.iter().take(PER_FAMILY) {
                let unit = if r.case.family.starts_with("pips") {
                    "in"
                } else {
                    "m"
                };
                let _ = writeln!(
                    s,
                    "| {} | {} | {} | {} | {:.3} -> {:.3} {unit} | {} | {} |",
                    r.case.name,
                    r.case.tags,
                    capp_sim::output::summary::outcome_name(m.outcome),
                    grouped(m.steps as f64),
                    m.initial_position_error,
                    m.final_position_error,
                    opt(m.final_orientation_error, 3),
                    m.closest.map_or("-".into(), |c| format!("{c:.2e}")),
                );
            }
            if of.len() > PER_FAMILY {
                let _ = writeln!(
                    s,
                    "| ... | {} more in `{}` | | | | | |",
                    of.len() - PER_FAMILY,
                    f.name
                );
            }
        }
    }

    s.push_str(
        "\n## For context: what the field reports (their figures, not ours)\n\n\
         From `shared/docs/planning.md`; different robots, scenes and budgets, so not comparable \
         number for number. NEO (Haviland & Corke, RA-L 2021), a reactive QP controller on a \
         7-DoF arm: 74.2 % of 198 problems in 5 scenes; on the same set RRT-Connect 85.4 % \
         (615 ms), TrajOpt 81.8 %, CHOMP 65.2 %. cuRobo: 99.7-100 % of 2 600 MotionBenchMaker + \
         MpiNets problems. A purely reactive controller near 74 % of cluttered problems is where \
         the field stands; global planners reach 85-100 %.\n",
    );
    s
}

/// `detour -x obstacle 2; walk +y obstacle 1; walk none`: each attempt's kind
/// and side (1-based obstacle), in order.
fn escape_sides(e: &crate::metrics::EscapeCounts) -> String {
    let parts: Vec<String> = e
        .sides
        .iter()
        .map(|(kind, side)| match side {
            Some(s) => format!(
                "{} {} obstacle {}",
                kind.name(),
                capp_sim::escapes::side_name(*s),
                s.obstacle as u32 + 1
            ),
            None => format!("{} none", kind.name()),
        })
        .collect();
    parts.join("; ")
}

/// The per-case, per-variant CSV.
pub fn csv(results: &[CaseResult]) -> String {
    let mut s = String::from(
        "family,case,tags,variant,outcome,reaches,steps,motion_time_s,same_path_time_s,straight_time_s,steps_10x,final_position_error,final_orientation_error,closest,collisions,collisions_between,contacts,self_collisions,closest_link_gap,not_finite,joint_limit,rate_limit,other,drive_off_period_rows,drive_over_rate_rows,drive_over_accel_rows,drive_over_jerk_rows,drive_arrives_moving,drive_braking_collisions,drive_peak_accel_ratio,drive_peak_jerk_ratio,drive_rest_to_rest_s,escape_attempts,escape_walks,escape_detours,escape_searches,escape_paths,escape_returned,escape_first_step,escape_sides,trajectory_bits,wall_ms,rrt_solved,rrt_ms,rrt_iterations,rrt_nodes,rrt_raw_time_s,rrt_path_time_s,error\n",
    );
    let o = |x: Option<f64>| x.map_or(String::new(), |v| format!("{v}"));
    // A refused file: every measurement column empty (all but the case's 4,
    // the oracle's 6 and the error).
    let columns = s.trim_end().split(',').count();
    let empty = ",".repeat(columns - 11);
    for r in results {
        let (solved, ms, it, nodes, raw, path) = match &r.oracle {
            Some(x) => (
                x.solved.to_string(),
                format!("{:.1}", x.wall_ms),
                x.iterations.to_string(),
                x.nodes.to_string(),
                o(x.raw_time),
                o(x.path_time),
            ),
            None => Default::default(),
        };
        for v in &r.runs {
            let lead = format!(
                "{},{},\"{}\",{}",
                r.case.family, r.case.name, r.case.tags, v.variant.name
            );
            let tail = format!("{solved},{ms},{it},{nodes},{raw},{path}");
            match &v.metrics {
                Ok(m) => {
                    let _ = writeln!(
                        s,
                        "{lead},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},\"{}\",{:016x},{:.3},{tail},",
                        capp_sim::output::summary::outcome_name(m.outcome),
                        m.reaches,
                        m.steps,
                        m.motion_time,
                        m.same_path_time,
                        m.straight_time,
                        m.steps_10x.map_or(String::new(), |x| x.to_string()),
                        m.final_position_error,
                        o(m.final_orientation_error),
                        o(m.closest),
                        m.collisions,
                        m.collisions_between,
                        m.contacts,
                        m.self_collisions,
                        o(m.closest_links),
                        m.not_finite,
                        m.joint_limit,
                        m.rate_limit,
                        m.other,
                        m.drive.off_period,
                        m.drive.over_rate,
                        m.drive.over_accel,
                        m.drive.over_jerk,
                        m.drive.arrives_moving,
                        m.drive.braking_collisions,
                        o(m.drive.peak_accel),
                        o(m.drive.peak_jerk),
                        m.rest_to_rest_time,
                        m.escape.attempts(),
                        m.escape.walks,
                        m.escape.detours,
                        m.escape.searches,
                        m.escape.paths,
                        m.escape.returned,
                        m.escape.first_step.map_or(String::new(), |x| x.to_string()),
                        escape_sides(&m.escape),
                        m.fingerprint,
                        m.wall_ms,
                    );
                }
                Err(e) => {
                    let _ = writeln!(s, "{lead},{empty}{tail},\"{}\"", e.replace('"', "'"));
                }
            }
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_rank() {
        let v = [5.0, 1.0, 4.0, 2.0, 3.0];
        assert_eq!(median(&v), Some(3.0));
        assert_eq!(percentile(&v, 0.9), Some(5.0));
        assert_eq!(percentile(&v, 0.2), Some(1.0));
        assert_eq!(median(&[]), None);
        assert_eq!(grouped(13901.0), "13 901");
        assert_eq!(grouped(999.0), "999");
        assert_eq!(grouped(1234567.0), "1 234 567");
    }
}
