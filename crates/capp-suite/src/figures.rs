//! The report's figures, where a table is hard to read (issue 15): the reach
//! rate per family and variant, and the default variant's motion time
//! against RRT-Connect's shortcut path on the same case. Drawn with
//! `capp_sim::render::chart`, so the PNGs carry the shipped font and are the
//! same bytes on every machine; written by a full `cargo xtask suite` to
//! `docs/img/planning_reach.{svg,png}` and `docs/img/planning_motion.{svg,png}`.

use std::path::Path;

use anyhow::Result;
use capp_core::Outcome;
use capp_sim::render::chart::{
    bar_chart, scatter_chart, BarChart, PointSeries, ScatterChart, Series,
};
use capp_sim::render::Canvas;

use crate::families::Family;
use crate::report::certified;
use crate::runner::CaseResult;
use crate::variants::Variant;

/// The figures' file stems, under `docs/img/`.
pub const REACH: &str = "planning_reach";
/// See [`REACH`].
pub const MOTION: &str = "planning_motion";

/// The runs of `variant` in `results`, with their case.
fn runs<'a>(
    results: &'a [&'a CaseResult],
    variant: &'a str,
) -> impl Iterator<Item = (&'a CaseResult, &'a crate::metrics::RunMetrics)> + 'a {
    results.iter().flat_map(move |r| {
        r.runs
            .iter()
            .filter(move |v| v.variant.name == variant)
            .filter_map(move |v| v.metrics.as_ref().ok().map(|m| (*r, m)))
    })
}

/// Reached, % of the certified cases, per family (and all) and variant.
pub fn reach(families: &[Family], variants: &[Variant], results: &[CaseResult]) -> Canvas {
    let mut groups: Vec<(String, Vec<&CaseResult>)> = families
        .iter()
        .map(|f| {
            (
                f.name.to_string(),
                results
                    .iter()
                    .filter(|r| r.case.family == f.name)
                    .collect::<Vec<_>>(),
            )
        })
        .filter(|(_, of)| !of.is_empty())
        .collect();
    groups.push(("all".into(), results.iter().collect()));
    let categories = groups
        .iter()
        .map(|(name, of)| {
            let n = of.iter().filter(|r| certified(r)).count();
            format!("{name} ({n})")
        })
        .collect();
    let series = variants
        .iter()
        .map(|v| Series {
            name: v.name.to_string(),
            values: groups
                .iter()
                .map(|(_, of)| {
                    let certified_cases = of.iter().filter(|r| certified(r)).count();
                    let reached = runs(of, v.name)
                        .filter(|(c, m)| certified(c) && m.outcome == Outcome::Reached)
                        .count();
                    if certified_cases == 0 {
                        f64::NAN
                    } else {
                        100.0 * reached as f64 / certified_cases as f64
                    }
                })
                .collect(),
        })
        .collect();
    bar_chart(&BarChart {
        title: "Reached, % of the cases RRT-Connect certified solvable (how many in brackets)"
            .into(),
        y_label: "reached [% of certified]".into(),
        categories,
        series,
        y_max: Some(100.0),
    })
}

/// The default variant's motion time against the RRT shortcut path's time
/// at the rate limits, per reached case the oracle solved: one series per
/// family for runs that did not escape, one for the runs that escaped.
pub fn motion(families: &[Family], variant: &Variant, results: &[CaseResult]) -> Canvas {
    let all: Vec<&CaseResult> = results.iter().collect();
    let point = |(c, m): (&CaseResult, &crate::metrics::RunMetrics)| {
        let rrt = c.oracle.as_ref()?.path_time?;
        (m.outcome == Outcome::Reached).then_some((rrt, m.motion_time))
    };
    let mut series: Vec<PointSeries> = families
        .iter()
        .map(|f| PointSeries {
            name: format!("{}, no escape", f.name),
            points: runs(&all, variant.name)
                .filter(|(c, m)| c.case.family == f.name && m.escape.attempts() == 0)
                .filter_map(point)
                .collect(),
        })
        .filter(|s| !s.points.is_empty())
        .collect();
    series.push(PointSeries {
        name: "escaped (any family)".into(),
        points: runs(&all, variant.name)
            .filter(|(_, m)| m.escape.attempts() > 0)
            .filter_map(point)
            .collect(),
    });
    scatter_chart(&ScatterChart {
        title: format!(
            "{}: motion time against RRT-Connect's shortcut path, reached cases",
            variant.name
        ),
        x_label: "RRT-Connect shortcut path at the rate limits [s]".into(),
        y_label: "motion time, sum of the step sizes [s]".into(),
        series,
        diagonal: Some("as fast as the RRT path".into()),
        slopes: vec![(2.0, "twice the RRT path (the target)".into())],
        log: true,
    })
}

/// Writes both figures into `dir` (SVG and PNG); returns `(path relative
/// to the repository, alt text, caption)` for the report, `dir` being
/// `root/docs/img`.
pub fn write(
    dir: &Path,
    families: &[Family],
    variants: &[Variant],
    results: &[CaseResult],
) -> Result<Vec<(String, String, String)>> {
    std::fs::create_dir_all(dir)?;
    let mut out = Vec::new();
    reach(families, variants, results).write(dir, REACH)?;
    out.push((
        format!("docs/img/{REACH}.png"),
        "reach rate per family and variant".to_string(),
        "Reached, % of the RRT-certified cases, per family and variant (the tables' *reached % of certified*).".to_string(),
    ));
    if let Some(default) = variants.first() {
        motion(families, default, results).write(dir, MOTION)?;
        out.push((
            format!("docs/img/{MOTION}.png"),
            "motion time against the RRT path".to_string(),
            format!(
                "`{}`: each reached case the oracle solved, its motion time against the time of \
                 RRT-Connect's shortcut path at the rate limits (log axes); below the dashed \
                 diagonal the planner's motion is the faster, above the lighter one it takes more \
                 than twice as long. Escaped runs in their own colour.",
                default.name
            ),
        ));
    }
    Ok(out)
}
