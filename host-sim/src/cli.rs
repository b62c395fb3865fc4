//! The `capp` command line: argument parsing, the subcommands, exit codes.
//! Lives in the library so that tests drive exactly what users run
//! ([`main`] with an argument list).
//!
//! Exit codes: 0 success (target reached / trajectory accepted; for `serial`
//! also the whole stream received), 1 the plan did not reach its target, the
//! trajectory was rejected, or setpoints were lost or damaged on the line, 2
//! bad input or an I/O or link failure.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use capp_core::Outcome;
use std::ffi::OsString;
use std::time::Duration;

use crate::output::{self, summary::Summary};
use crate::serial::{self, Connection};
use crate::{check, plan, render, trajectory, Problem};
use clap::{Args, Parser, Subcommand};

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
    /// Plan a scenario on a board (or the firmware under QEMU) over its serial
    /// line and write the same output folder as `run` from the received stream.
    Serial {
        /// Scenario file: `*.toml`, anything else is read as input.dat.
        scenario: PathBuf,
        #[command(flatten)]
        board: BoardArgs,
        #[command(flatten)]
        line: LineArgs,
        /// Output folder (default: out/<scenario name>-serial).
        #[arg(short, long)]
        out: Option<PathBuf>,
        /// Also draw the pictures into the output folder.
        #[arg(long)]
        render: bool,
        /// Print nothing on success.
        #[arg(short, long)]
        quiet: bool,
        /// Give up after this many seconds without a good frame (the board is
        /// asked for its status every quarter of it).
        #[arg(long, default_value_t = 20.0)]
        idle_timeout: f64,
    },
    /// Print the robot as the planner sees it: the chain (DH rows, or a
    /// URDF's joints with origins, axes and the tool), limits, rates, and
    /// each link's capsule with the collision geometry it encloses.
    Robot {
        /// Scenario file: `*.toml`, anything else is read as input.dat.
        scenario: PathBuf,
        /// Also draw the robot at its start configuration into this folder
        /// (robot.svg / robot.png: the three views with the link capsules
        /// and a URDF's collision capsules; viewer.html: the 3-D viewer).
        /// Like an output folder: refused if it exists and is neither empty
        /// nor a finished capp folder.
        #[arg(long, value_name = "DIR")]
        render: Option<PathBuf>,
    },
    /// Print the link capsules and the pairs of links checked for
    /// self-collision, and why each other pair is skipped.
    Acm {
        /// Scenario file: `*.toml`, anything else is read as input.dat.
        scenario: PathBuf,
    },
    /// Draw the pictures of an output folder (SVG and PNG views and plots, 3-D viewer.html, motion.gif).
    Render {
        /// Output folder of `capp run`.
        dir: PathBuf,
        /// Scenario (default: the copy in the folder).
        #[arg(short, long)]
        scenario: Option<PathBuf>,
    },
}

/// Where `capp serial` finds the board: exactly one of these.
#[derive(Args)]
#[group(required = true, multiple = false)]
struct BoardArgs {
    /// Serial port of the board (e.g. /dev/ttyACM0).
    #[arg(long)]
    port: Option<String>,
    /// TCP serial, HOST:PORT (e.g. firmware/qemu.sh's 127.0.0.1:4444).
    #[arg(long)]
    tcp: Option<String>,
    /// Boot the firmware under qemu-system-arm (mps2-an386) and use its UART.
    #[arg(long)]
    qemu: bool,
}

/// The rest of `capp serial`'s board options.
#[derive(Args)]
struct LineArgs {
    /// Baud rate for --port.
    #[arg(long, default_value_t = 115_200)]
    baud: u32,
    /// Firmware ELF for --qemu (default: the workspace's release build).
    #[arg(long)]
    elf: Option<PathBuf>,
}

/// Runs `capp` with `args` (the program name first), as the binary does.
pub fn main<I, T>(args: I) -> ExitCode
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    let cli = match Cli::try_parse_from(args) {
        Ok(cli) => cli,
        Err(e) => {
            let _ = e.print();
            return if e.use_stderr() {
                ExitCode::from(2)
            } else {
                ExitCode::SUCCESS
            };
        }
    };
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
        Command::Serial {
            scenario,
            board,
            line,
            out,
            render,
            quiet,
            idle_timeout,
        } => serial_cmd(
            &scenario,
            connection(board, line),
            out,
            render,
            quiet,
            Duration::from_secs_f64(idle_timeout.clamp(0.1, 86_400.0)),
        ),
        Command::Render { dir, scenario } => render_cmd(&dir, scenario.as_deref()),
        Command::Acm { scenario } => acm_cmd(&scenario),
        Command::Robot { scenario, render } => robot_cmd(&scenario, render.as_deref()),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}

/// A progress bar on a terminal, none otherwise.
fn progress_bar(max_steps: u32) -> Option<indicatif::ProgressBar> {
    std::io::stderr().is_terminal().then(|| {
        let bar = indicatif::ProgressBar::new(max_steps as u64);
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{spinner} step {pos}/{len} [{elapsed_precise}] {msg}",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        bar
    })
}

/// Writes the output folder of a finished plan and prints its summary.
fn finish(
    problem: &Problem,
    result: &plan::RunResult,
    summary: &Summary,
    out: &Path,
    draw: bool,
    quiet: bool,
) -> Result<()> {
    output::write_run(out, problem, result, summary, |staging| {
        if draw {
            let t = trajectory::read(&staging.join("trajectory.csv"))?;
            render::render(problem, &t, staging)?;
        }
        Ok(())
    })?;
    if !quiet {
        say(&format!("{summary}output:            {}\n", out.display()));
    }
    Ok(())
}

fn run(path: &Path, out: Option<PathBuf>, draw: bool, quiet: bool) -> Result<ExitCode> {
    let problem = Problem::load(path)?;
    let scenario = problem.validate()?;
    let out = out.unwrap_or_else(|| PathBuf::from("out").join(&problem.name));
    let bar = progress_bar(problem.settings.max_steps);
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
    finish(&problem, &result, &summary, &out, draw, quiet)?;
    Ok(if result.outcome == Outcome::Reached {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

fn connection(board: BoardArgs, line: LineArgs) -> Connection {
    match (board.port, board.tcp) {
        (Some(path), _) => Connection::Port {
            path,
            baud: line.baud,
        },
        (None, Some(addr)) => Connection::Tcp(addr),
        (None, None) => Connection::Qemu(line.elf.unwrap_or_else(capp_link::qemu::default_elf)),
    }
}

fn serial_cmd(
    path: &Path,
    connection: Connection,
    out: Option<PathBuf>,
    draw: bool,
    quiet: bool,
    idle: Duration,
) -> Result<ExitCode> {
    let problem = Problem::load(path)?;
    let scenario = problem.validate()?;
    let out = out.unwrap_or_else(|| PathBuf::from("out").join(format!("{}-serial", problem.name)));
    let bar = progress_bar(problem.settings.max_steps);
    let watch = |s: &capp_proto::Status| {
        if let Some(bar) = &bar {
            bar.set_position(s.step as u64);
            bar.set_message(format!(
                "board: V {:.3e}  position error {:.3}",
                s.v, s.position_error
            ));
        }
    };
    let planned = match &connection {
        Connection::Port { path, baud } => {
            let mut link = capp_link::open_serial(path, *baud)
                .with_context(|| format!("cannot open serial port {path}"))?;
            serial::plan_on_board(&mut link, &problem, &scenario, idle, watch)
        }
        Connection::Tcp(addr) => {
            let mut link = capp_link::connect_tcp(addr.as_str())
                .with_context(|| format!("cannot connect to {addr}"))?;
            serial::plan_on_board(&mut link, &problem, &scenario, idle, watch)
        }
        Connection::Qemu(elf) => {
            if !elf.is_file() {
                anyhow::bail!(
                    "firmware ELF {} not found (cd firmware && cargo build --release)",
                    elf.display()
                );
            }
            let (_qemu, mut link) = capp_link::qemu::Qemu::launch(elf, None)
                .with_context(|| format!("cannot boot {} under QEMU", elf.display()))?;
            serial::plan_on_board(&mut link, &problem, &scenario, idle, watch)
        }
    };
    if let Some(bar) = &bar {
        bar.finish_and_clear();
    }
    let (result, link) = planned?;
    let whole = link.whole();
    let mut summary = Summary::new(&problem, &result);
    summary.link = Some(link);
    finish(&problem, &result, &summary, &out, draw, quiet)?;
    if !whole {
        eprintln!("capp serial: the stream from the board is incomplete (see the summary)");
    }
    if let Some(warning) = summary.link.as_ref().and_then(|l| l.period_warning()) {
        eprintln!("capp serial: {warning}");
    }
    Ok(if result.outcome == Outcome::Reached && whole {
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
    // The obstacles checked are the planner's: a mesh's enclosure, say so.
    for note in &problem.notes {
        say(&format!("note: {note}\n"));
    }
    say(&report.to_string());
    Ok(if report.accepted() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

fn robot_cmd(path: &Path, draw: Option<&Path>) -> Result<ExitCode> {
    let problem = Problem::load(path)?;
    say(&crate::robot_report::report(&problem)?);
    if let Some(dir) = draw {
        output::write_folder(dir, "robot", |staging| {
            render::robot::render_robot(&problem, staging).map(|_| ())
        })?;
        say(&format!("\npictures:          {}\n", dir.display()));
    }
    Ok(ExitCode::SUCCESS)
}

fn acm_cmd(path: &Path) -> Result<ExitCode> {
    let problem = Problem::load(path)?;
    say(&crate::acm::report(&problem)?);
    Ok(ExitCode::SUCCESS)
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
