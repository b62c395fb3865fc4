//! `cargo xtask suite`: generate, plan, certify, report.
//!
//! ```text
//! cargo xtask suite                 full run: writes PLANNING.md, its figures docs/img/planning_*.{svg,png},
//!                                   target/suite/results.csv, target/suite/cases/ (every run that did not reach)
//! cargo xtask suite --quick         4 cases per family, prints the report, writes nothing
//!   --seed N                        another seed (default 1)
//!   --family NAME[,NAME]            only these families
//!   --variant NAME[,NAME]           only these variants
//!   --cases K                       K cases per family
//!   --threads N                     worker threads (default: available cores)
//!   --no-oracle                     skip RRT-Connect
//!   --write-cases DIR               also write every case file to DIR
//! ```
//!
//! Only a full run (no option narrowing it) rewrites `PLANNING.md` and its figures; any other
//! prints the report and writes only under `target/suite/` (nothing with `--quick`).

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use capp_core::Outcome;

use crate::families::{self, Family};
use crate::figures;
use crate::oracle::Budget;
use crate::report::{self, RunInfo, ShippedRun};
use crate::runner::{self, CaseResult};
use crate::variants::{self, with_settings, Variant};

/// The shipped scenarios of the issue's table.
pub const SHIPPED: [&str; 5] = [
    "planar_arm.toml",
    "pips_free_space.toml",
    "pips_payload_bay.toml",
    "pips_payload_bay_cad.toml",
    "pips_payload_bay_mesh.toml",
];

/// Parsed command line.
#[derive(Clone, Debug)]
pub struct Options {
    /// `--quick`.
    pub quick: bool,
    /// `--seed`.
    pub seed: u64,
    /// `--family`.
    pub families: Option<Vec<String>>,
    /// `--variant`.
    pub variants: Option<Vec<String>>,
    /// `--cases`.
    pub cases: Option<usize>,
    /// `--threads`.
    pub threads: usize,
    /// `--no-oracle`.
    pub no_oracle: bool,
    /// `--help` or `-h`: print the usage, run nothing.
    pub help: bool,
    /// `--write-cases`.
    pub write_cases: Option<PathBuf>,
}

impl Options {
    /// Parses `args` (after `suite`).
    pub fn parse(args: &[String]) -> Result<Options> {
        let mut o = Options {
            quick: false,
            seed: 1,
            families: None,
            variants: None,
            cases: None,
            threads: std::thread::available_parallelism().map_or(2, |n| n.get()),
            no_oracle: false,
            help: false,
            write_cases: None,
        };
        let mut it = args.iter();
        while let Some(a) = it.next() {
            let mut value = |name: &str| {
                it.next()
                    .cloned()
                    .with_context(|| format!("{name} needs a value"))
            };
            let list = |v: String| v.split(',').map(str::to_string).collect::<Vec<_>>();
            match a.as_str() {
                "--quick" => o.quick = true,
                "--no-oracle" => o.no_oracle = true,
                "--help" | "-h" => o.help = true,
                "--seed" => o.seed = value("--seed")?.parse().context("--seed")?,
                "--cases" => o.cases = Some(value("--cases")?.parse().context("--cases")?),
                "--threads" => o.threads = value("--threads")?.parse().context("--threads")?,
                "--family" => o.families = Some(list(value("--family")?)),
                "--variant" => o.variants = Some(list(value("--variant")?)),
                "--write-cases" => o.write_cases = Some(PathBuf::from(value("--write-cases")?)),
                other => bail!("unknown option {other}\n\n{USAGE}"),
            }
        }
        Ok(o)
    }

    /// Whether this is the full run that rewrites `PLANNING.md`.
    pub fn is_full(&self) -> bool {
        !self.quick
            && self.seed == 1
            && self.families.is_none()
            && self.variants.is_none()
            && self.cases.is_none()
            && !self.no_oracle
    }
}

/// Usage text.
pub const USAGE: &str = "usage: cargo xtask suite [--quick] [--seed N] [--family NAME[,NAME]] [--variant NAME[,NAME]] [--cases K] [--threads N] [--no-oracle] [--write-cases DIR]";

/// The host's CPU model, from `/proc/cpuinfo` ("unknown CPU" elsewhere).
pub fn cpu_model() -> String {
    let cpuinfo = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
    cpuinfo
        .lines()
        .find_map(|l| {
            l.strip_prefix("model name")
                .map(|m| m.trim_start_matches([' ', '\t', ':']).to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into())
}

fn machine() -> String {
    let model = cpu_model();
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    let rustc = Command::new("rustc")
        .arg("-V")
        .output()
        .ok()
        .and_then(|o| String::from_utf8(o.stdout).ok())
        .map(|s| s.trim().to_string())
        .unwrap_or_else(|| "rustc unknown".into());
    format!("{model} ({cores} cores), {rustc}, release build")
}

fn select<T: Clone>(
    all: Vec<T>,
    wanted: &Option<Vec<String>>,
    name: impl Fn(&T) -> &str,
    what: &str,
) -> Result<Vec<T>> {
    let Some(wanted) = wanted else { return Ok(all) };
    let mut out = Vec::new();
    for w in wanted {
        match all.iter().find(|x| name(x) == w) {
            Some(x) => out.push(x.clone()),
            None => bail!(
                "unknown {what} \"{w}\" (known: {})",
                all.iter()
                    .map(|x| name(x).to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        }
    }
    Ok(out)
}

/// Runs the suite from the repository at `root`; `command` is how it was invoked (for the report).
pub fn main(args: &[String], root: &Path) -> Result<()> {
    let started = Instant::now();
    let options = Options::parse(args)?;
    if options.help {
        println!("{USAGE}");
        return Ok(());
    }
    let families: Vec<Family> = select(
        families::families(),
        &options.families,
        |f| f.name,
        "family",
    )?;
    let variants: Vec<Variant> = select(
        variants::variants(),
        &options.variants,
        |v| v.name,
        "variant",
    )?;
    let budget = Budget::default();

    let mut cases = Vec::new();
    let mut counts = Vec::new();
    for f in &families {
        let n = options
            .cases
            .unwrap_or(if options.quick { 4 } else { f.count });
        let of = families::cases(f, options.seed, n)?;
        counts.push((f.name.to_string(), of.len()));
        cases.extend(of);
    }
    eprintln!(
        "suite: {} cases generated in {:.1} s; planning with {} variants{} on {} threads",
        cases.len(),
        started.elapsed().as_secs_f64(),
        variants.len(),
        if options.no_oracle {
            ""
        } else {
            " and RRT-Connect"
        },
        options.threads
    );
    if let Some(dir) = &options.write_cases {
        std::fs::create_dir_all(dir)?;
        for c in &cases {
            std::fs::write(dir.join(format!("{}.toml", c.name)), &c.text)?;
        }
        eprintln!(
            "suite: wrote {} case files to {}",
            cases.len(),
            dir.display()
        );
    }

    let total = cases.len();
    let oracle = (!options.no_oracle).then_some(budget);
    let results: Vec<CaseResult> = runner::par_map(
        &cases,
        options.threads,
        |c| runner::run_case(c, &variants, options.seed, oracle),
        |k| {
            if k % 20 == 0 || k == total {
                eprintln!(
                    "suite: {k}/{total} cases, {:.0} s",
                    started.elapsed().as_secs_f64()
                );
            }
        },
    );

    let mut shipped = Vec::new();
    for name in SHIPPED {
        let path = root.join("host-sim/scenarios").join(name);
        let text = std::fs::read_to_string(&path)
            .with_context(|| format!("reading {}", path.display()))?;
        for &v in &variants {
            let run = runner::measure_file(&text, &path, v);
            let time_step = crate::case::parse_at(&with_settings(&text, v.settings), &path)
                .map_or(f32::NAN, |p| p.settings.time_step_s);
            shipped.push(ShippedRun {
                scenario: name.to_string(),
                variant: v,
                time_step,
                metrics: run.metrics,
            });
        }
    }

    let command = if options.is_full() {
        "cargo xtask suite".to_string()
    } else {
        format!("cargo xtask suite {}", args.join(" "))
    };
    let info = RunInfo {
        seed: options.seed,
        counts,
        threads: options.threads,
        machine: machine(),
        wall_s: started.elapsed().as_secs_f64(),
        budget,
        command,
    };
    // The figures go with PLANNING.md: only a full run draws them.
    let figures = if options.is_full() {
        figures::write(&root.join("docs/img"), &families, &variants, &results)?
    } else {
        Vec::new()
    };
    let text =
        report::markdown_with_figures(&info, &families, &variants, &results, &shipped, &figures);
    if options.quick {
        println!("{text}");
        return Ok(());
    }
    let out = root.join("target/suite");
    let case_dir = out.join("cases");
    if case_dir.exists() {
        std::fs::remove_dir_all(&case_dir)?;
    }
    std::fs::create_dir_all(&case_dir)?;
    std::fs::write(out.join("results.csv"), report::csv(&results))?;
    let mut written = 0;
    for r in &results {
        for v in &r.runs {
            let missed = v.metrics.as_ref().map_or(true, |m| {
                m.outcome != Outcome::Reached || m.violations() > 0
            });
            if missed {
                let name = format!("{}.{}", r.case.name, v.variant.name);
                std::fs::write(
                    case_dir.join(format!("{name}.toml")),
                    with_settings(&r.case.text, v.variant.settings),
                )?;
                written += 1;
            }
        }
    }
    eprintln!(
        "suite: wrote target/suite/results.csv and {written} runs that did not reach to target/suite/cases/"
    );
    if options.is_full() {
        std::fs::write(root.join("PLANNING.md"), &text)?;
        eprintln!(
            "suite: wrote PLANNING.md and {} ({:.0} s)",
            figures
                .iter()
                .map(|f| f.0.trim_end_matches(".png").to_string() + ".{svg,png}")
                .collect::<Vec<_>>()
                .join(", "),
            started.elapsed().as_secs_f64()
        );
    } else {
        println!("{text}");
    }
    Ok(())
}
