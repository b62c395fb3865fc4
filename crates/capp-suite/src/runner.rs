//! Plans every case with every variant (and asks the oracle once per case),
//! on a few threads, results in case order whatever the scheduling.
//!
//! A planner run is exactly `capp run`'s: the variant's settings are put into
//! the case file's text, the text is read by `capp_sim::input::scenario_file::parse`
//! and validated, and `capp_sim::plan::run` drives `Planner<32>`.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use capp_sim::plan::{self, RunResult};
use capp_sim::Problem;

use crate::case::{self, Case};
use crate::metrics::{self, RunMetrics};
use crate::oracle::{self, Budget, OracleResult};
use crate::rng::Rng;
use crate::variants::{with_settings, Variant};

/// One variant's run of one case.
#[derive(Clone, Debug)]
pub struct VariantRun {
    /// The variant.
    pub variant: Variant,
    /// The measurements, or why the file was refused.
    pub metrics: Result<RunMetrics, String>,
}

/// Everything about one case.
#[derive(Clone, Debug)]
pub struct CaseResult {
    /// The case.
    pub case: Case,
    /// The oracle (`None` when not asked).
    pub oracle: Option<OracleResult>,
    /// One run per variant, in variant order.
    pub runs: Vec<VariantRun>,
}

/// Reads `text` as `name.toml` and plans it.
pub fn plan_text(text: &str, name: &str) -> Result<(Problem, RunResult), String> {
    plan_problem(case::parse(text, name).map_err(|e| e.to_string())?)
}

/// Plans a problem as `capp run` would.
fn plan_problem(problem: Problem) -> Result<(Problem, RunResult), String> {
    let scenario = problem.validate().map_err(|e| e.to_string())?;
    let result = plan::run(&problem, &scenario, |_| {}).map_err(|e| e.to_string())?;
    Ok((problem, result))
}

/// Plans `text` with `variant` and measures the run.
pub fn measure_variant(text: &str, name: &str, variant: Variant) -> VariantRun {
    let text = with_settings(text, variant.settings);
    VariantRun {
        variant,
        metrics: plan_text(&text, name)
            .map(|(problem, result)| metrics::measure(&problem, &result)),
    }
}

/// Plans the text of the scenario file at `path` (its relative paths, a
/// `mesh` or a URDF, from the file's folder) with `variant` and measures
/// the run: the shipped scenarios.
pub fn measure_file(text: &str, path: &std::path::Path, variant: Variant) -> VariantRun {
    let text = with_settings(text, variant.settings);
    VariantRun {
        variant,
        metrics: case::parse_at(&text, path)
            .map_err(|e| e.to_string())
            .and_then(plan_problem)
            .map(|(problem, result)| metrics::measure(&problem, &result)),
    }
}

/// The oracle on `case` (its start and goal, the file's obstacles and margins).
pub fn oracle_of(case: &Case, seed: u64, budget: Budget) -> Result<OracleResult, String> {
    let problem = case::parse(&case.text, &case.name).map_err(|e| e.to_string())?;
    let mut rng = Rng::derive(seed, &format!("oracle {}", case.name), 0);
    Ok(oracle::rrt_connect(
        &problem,
        &case.start,
        &case.goal,
        budget,
        &mut rng,
    ))
}

/// One case: the oracle (when `budget` is given) and every variant.
pub fn run_case(
    case: &Case,
    variants: &[Variant],
    seed: u64,
    budget: Option<Budget>,
) -> CaseResult {
    CaseResult {
        case: case.clone(),
        oracle: budget.and_then(|b| oracle_of(case, seed, b).ok()),
        runs: variants
            .iter()
            .map(|&v| measure_variant(&case.text, &case.name, v))
            .collect(),
    }
}

/// `f` over `items` on `threads` threads; results in `items` order.
/// `done(k)` is called after each item with the number finished so far.
pub fn par_map<T: Sync, R: Send>(
    items: &[T],
    threads: usize,
    f: impl Fn(&T) -> R + Sync,
    done: impl Fn(usize) + Sync,
) -> Vec<R> {
    let next = AtomicUsize::new(0);
    let finished = AtomicUsize::new(0);
    let slots: Mutex<Vec<Option<R>>> = Mutex::new((0..items.len()).map(|_| None).collect());
    std::thread::scope(|s| {
        for _ in 0..threads.max(1) {
            s.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                let Some(item) = items.get(i) else { break };
                let r = f(item);
                if let Ok(mut slots) = slots.lock() {
                    slots[i] = Some(r);
                }
                done(finished.fetch_add(1, Ordering::Relaxed) + 1);
            });
        }
    });
    slots
        .into_inner()
        .unwrap_or_default()
        .into_iter()
        .flatten()
        .collect()
}
