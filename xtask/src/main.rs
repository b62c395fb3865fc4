//! Project tasks, run as `cargo xtask <task>` (alias in `.cargo/config.toml`).
//!
//! * `cargo xtask bench`: every benchmark figure of BENCHMARKS.md. Runs the
//!   criterion benches (`crates/capp-bench/benches/step.rs`) and the
//!   interleaved host scaling sweep (`crates/capp-bench/examples/host_scaling.rs`), builds the
//!   Cortex-M4F counter (`firmware/examples/step_count.rs`) and runs it under
//!   `qemu-system-arm -machine mps2-an386 -icount shift=0`, measures the
//!   firmware (flash, static RAM from `size -A`; peak stack from the QEMU
//!   end-to-end test), then rewrites the generated part of `BENCHMARKS.md` and
//!   the scaling plot `docs/img/scaling.{svg,png}`. A few minutes.
//! * `cargo xtask bench --quick`: a smoke check in well under a minute of
//!   measuring: short criterion runs, a short sweep, the M4F counts, no
//!   end-to-end test; prints the tables, writes nothing.
//! * `cargo xtask suite`: the planning-quality benchmark (`crates/capp-suite`):
//!   seeded case families, RRT-Connect as the oracle, every planner variant on
//!   every case; writes `PLANNING.md`, `target/suite/results.csv` and the
//!   cases that were not reached (`target/suite/cases/`). A few minutes.
//!   `--quick` plans 4 cases per family and prints, writing nothing; see
//!   `capp_suite::cli` for `--seed`, `--family`, `--variant`, `--cases`,
//!   `--write-cases DIR`.

mod m4f;
mod plot;
mod report;

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{bail, Context, Result};

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("bench") => {
            let quick = args.iter().any(|a| a == "--quick");
            bench(quick)
        }
        Some("suite") => capp_suite::cli::main(&args[1..], &root()),
        _ => {
            eprintln!(
                "usage: cargo xtask bench [--quick]\n       {}",
                &capp_suite::cli::USAGE[7..]
            );
            std::process::exit(2);
        }
    }
}

/// The repository root (the parent of this crate).
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."))
}

/// Runs `cmd`, failing with its name when it fails.
fn run(cmd: &mut Command) -> Result<()> {
    eprintln!("xtask: {cmd:?}");
    let status = cmd.status().with_context(|| format!("starting {cmd:?}"))?;
    if !status.success() {
        bail!("{cmd:?} failed: {status}");
    }
    Ok(())
}

/// Runs `cmd` and returns its standard output (standard error passes through).
fn output(cmd: &mut Command) -> Result<String> {
    eprintln!("xtask: {cmd:?}");
    let out = cmd
        .stderr(std::process::Stdio::inherit())
        .output()
        .with_context(|| format!("starting {cmd:?}"))?;
    if !out.status.success() {
        bail!("{cmd:?} failed: {}", out.status);
    }
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
}

fn bench(quick: bool) -> Result<()> {
    let root = root();
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());

    // 1. Host: criterion.
    let mut criterion = Command::new(&cargo);
    criterion
        .current_dir(&root)
        .args(["bench", "-p", "capp-bench", "--bench", "step", "--"])
        .arg("--noplot");
    if quick {
        criterion.args([
            "--warm-up-time",
            "0.2",
            "--measurement-time",
            "0.5",
            "pips/",
        ]);
    }
    run(&mut criterion)?;
    let mut host = report::Host::load(&root.join("target/criterion"))?;
    let rounds = if quick { "21" } else { "301" };
    let sweep = output(Command::new(&cargo).current_dir(&root).args([
        "run",
        "--release",
        "-p",
        "capp-bench",
        "--example",
        "host_scaling",
        "--",
        rounds,
    ]))?;
    host.add_scaling(&sweep)?;

    // 2. Cortex-M4F: the counter under QEMU.
    let firmware = root.join("firmware");
    run(Command::new(&cargo).current_dir(&firmware).args([
        "build",
        "--release",
        "--example",
        "step_count",
    ]))?;
    let elf = firmware.join("target/thumbv7em-none-eabihf/release/examples/step_count");
    let text = output(Command::new("qemu-system-arm").args(m4f::qemu_args(&elf)))?;
    let counts = m4f::Counts::parse(&text)?;

    // 3. The firmware itself: sizes, and the peak stack from the end-to-end test.
    let firmware_size = if quick {
        None
    } else {
        run(Command::new(&cargo)
            .current_dir(&firmware)
            .args(["build", "--release"]))?;
        let elf = firmware.join("target/thumbv7em-none-eabihf/release/capp-firmware");
        let sizes = output(Command::new("size").arg("-A").arg(&elf))?;
        // The Nucleo-F446RE build: sizes only (no hardware here).
        run(Command::new(&cargo).current_dir(&firmware).args(["f446"]))?;
        let f446_elf = firmware.join("target/f446/thumbv7em-none-eabihf/f446/capp-firmware");
        let f446_sizes = output(Command::new("size").arg("-A").arg(&f446_elf))?;
        let e2e = Command::new(&cargo)
            .current_dir(&root)
            .env("CAPP_REQUIRE_QEMU", "1")
            .args([
                "test",
                "-p",
                "capp-system-tests",
                "--test",
                "qemu_link",
                "--",
                "--nocapture",
            ])
            .output()
            .context("running the QEMU end-to-end test")?;
        if !e2e.status.success() {
            bail!(
                "the QEMU end-to-end test (tests/qemu_link.rs) failed: {}\n{}",
                e2e.status,
                String::from_utf8_lossy(&e2e.stderr)
            );
        }
        let log = String::from_utf8_lossy(&e2e.stderr).into_owned()
            + &String::from_utf8_lossy(&e2e.stdout);
        Some(report::Firmware {
            mps2: report::FirmwareSize::parse(&sizes, &log),
            f446: report::FirmwareSize::parse(&f446_sizes, ""),
        })
    };

    let machine = report::Machine::probe(&cargo);
    let tables = report::tables(&host, &counts, firmware_size.as_ref(), &machine, quick);
    if quick {
        println!("{tables}");
        return Ok(());
    }
    let path = root.join("BENCHMARKS.md");
    let doc = std::fs::read_to_string(&path).context("reading BENCHMARKS.md")?;
    std::fs::write(&path, report::splice(&doc, &tables)?)?;
    let img = root.join("docs/img");
    std::fs::create_dir_all(&img)?;
    let canvas = plot::scaling(&host, &counts);
    std::fs::write(img.join("scaling.svg"), canvas.svg())?;
    std::fs::write(img.join("scaling.png"), canvas.png()?)?;
    eprintln!("xtask: wrote BENCHMARKS.md, docs/img/scaling.svg, docs/img/scaling.png");
    Ok(())
}
