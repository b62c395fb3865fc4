//! `capp`: the CAPP host simulator's command line. Everything it does lives in
//! the `capp_sim` library; this file parses arguments and sets exit codes.
//!
//! Exit codes: 0 success (target reached / trajectory accepted), 1 the plan
//! did not reach its target or the trajectory was rejected, 2 bad input or an
//! I/O failure.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use capp_core::Outcome;
use capp_sim::output::{self, Summary};
use capp_sim::{check, plan, render, trajectory, Problem};
use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "capp",
    version,
    about = "CAPP collision-avoiding path planner: host simulator"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Plan a scenario (TOML, or the listing's input.dat) and write an output folder.
    Run {
        /// Scenario file: `*.toml`, anything else is read as input.dat.
        scenario: PathBuf,
        /// Output folder (default: out/<scenario name>).
        #[arg(short, long)]
        out: Option<PathBuf>,
        /// Also draw the pictures into the output folder.
        #[arg(long)]
        render: bool,
        /// Print nothing on success.
        #[arg(short, long)]
        quiet: bool,
    },
    /// Check a trajectory CSV (or an output folder) independently of the planner.
    Check {
        /// trajectory.csv / setpoints.csv, or an output folder.
        trajectory: PathBuf,
        /// Scenario to check against (default: the copy in the output folder).
        #[arg(short, long)]
        scenario: Option<PathBuf>,
    },
    /// Draw the pictures of an output folder (SVG, PNG, HTML animation).
    Render {
        /// Output folder of `capp run`.
        dir: PathBuf,
        /// Scenario (default: the copy in the folder).
        #[arg(short, long)]
        scenario: Option<PathBuf>,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run {
            scenario,
            out,
            render,
            quiet,
        } => run(&scenario, out, render, quiet),
        Command::Check {
            trajectory,
            scenario,
        } => check_cmd(&trajectory, scenario.as_deref()),
        Command::Render { dir, scenario } => render_cmd(&dir, scenario.as_deref()),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}

fn run(path: &Path, out: Option<PathBuf>, draw: bool, quiet: bool) -> Result<ExitCode> {
    let problem = Problem::load(path)?;
    let scenario = problem.validate()?;
    let out = out.unwrap_or_else(|| PathBuf::from("out").join(&problem.name));
    let bar = std::io::stderr().is_terminal().then(|| {
        let bar = indicatif::ProgressBar::new(problem.settings.max_steps as u64);
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{spinner} step {pos}/{len} [{elapsed_precise}] {msg}",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        bar
    });
    let result = plan::run(&problem, &scenario, |report| {
        if let Some(bar) = &bar {
            if report.step % 64 == 0 {
                bar.set_position(report.step as u64);
                bar.set_message(format!(
                    "V {:.3e}  position error {:.3}",
                    report.v, report.position_error
                ));
            }
        }
    })?;
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    let summary = Summary::new(&problem, &result);
    output::write_run(&out, &problem, &result, &summary, |staging| {
        if draw {
            let t = trajectory::read(&staging.join("trajectory.csv"))?;
            render::render(&problem, &t, staging)?;
        }
        Ok(())
    })?;
    if !quiet {
        say(&format!("{summary}output:            {}\n", out.display()));
    }
    Ok(if result.outcome == Outcome::Reached {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

/// The trajectory file and scenario for `check` / `render`.
fn locate(path: &Path, scenario: Option<&Path>) -> Result<(PathBuf, Problem)> {
    let (file, dir) = if path.is_dir() {
        (path.join("trajectory.csv"), path.to_path_buf())
    } else {
        let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        (path.to_path_buf(), dir)
    };
    let scenario = match scenario {
        Some(s) => s.to_path_buf(),
        None => output::find_scenario_copy(&dir).with_context(|| {
            format!(
                "no scenario given and no scenario.toml / input.dat next to {}",
                file.display()
            )
        })?,
    };
    Ok((file, Problem::load(&scenario)?))
}

fn check_cmd(path: &Path, scenario: Option<&Path>) -> Result<ExitCode> {
    let (file, problem) = locate(path, scenario)?;
    let t = trajectory::read(&file)?;
    let report = check::check(&problem, &t);
    say(&report.to_string());
    Ok(if report.accepted() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

fn render_cmd(dir: &Path, scenario: Option<&Path>) -> Result<ExitCode> {
    let (file, problem) = locate(dir, scenario)?;
    let t = trajectory::read(&file)?;
    let target = file.parent().map(Path::to_path_buf).unwrap_or_default();
    for f in render::render(&problem, &t, &target)? {
        say(&format!("{}\n", f.display()));
    }
    Ok(ExitCode::SUCCESS)
}

/// Prints to stdout; a closed pipe (`capp ... | head`) is not an error worth a panic.
fn say(text: &str) {
    use std::io::Write;
    let _ = std::io::stdout().lock().write_all(text.as_bytes());
}
