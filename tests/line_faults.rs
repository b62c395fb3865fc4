//! Faults on the line: the firmware under QEMU streams a plan through
//! [`FaultProxy`], which flips bits, drops and duplicates bytes, cuts frames
//! short, repeats frames and pauses, on a seeded schedule, for a stretch of
//! the stream. The host must report every gap (exactly the setpoints the proxy
//! damaged, plus any the board itself dropped and counted), count the damaged
//! frames, keep repeated setpoints once, and never accept a damaged setpoint:
//! every setpoint it keeps is bit-identical to the host's own plan. Then
//! commands are damaged on their way to the board: each is answered with an
//! error, and the board answers the next clean command. Last, with the line
//! clean again, `capp serial` through the same proxy receives the whole plan.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;
use std::process::ExitCode;
use std::time::Duration;

use capp_link::qemu::Qemu;
use capp_link::LinkError;
use capp_proto::NO_COMMAND;
use capp_sim::Problem;
use capp_system_tests::capp;
use capp_system_tests::fault_proxy::{FaultProxy, Faults};

/// Setpoint rows of a `setpoints.csv` by step, without the columns a board
/// does not send (`h_s`, `constrained`, `halvings`).
fn rows_by_step(path: &Path) -> BTreeMap<u32, Vec<String>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let keep: Vec<usize> = (0..header.len())
        .filter(|&i| !["h_s", "constrained", "halvings"].contains(&header[i]))
        .collect();
    lines
        .map(|l| {
            let cells: Vec<&str> = l.split(',').collect();
            (
                cells[0].parse().unwrap(),
                keep.iter().map(|&i| cells[i].to_string()).collect(),
            )
        })
        .collect()
}

#[test]
fn faults_on_the_line_are_reported_never_accepted_and_the_stream_recovers() {
    let Some(elf) = capp_system_tests::firmware_or_skip() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    // PIPS in free space under the first-order gradient law (a long plan,
    // 6 500 steps), a setpoint every second step: ~3 300 frames.
    let scenario = dir.path().join("free_space_dense.toml");
    let base =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../host-sim/scenarios/pips_free_space.toml");
    let mut text = std::fs::read_to_string(base).unwrap();
    assert!(
        !text.contains("[settings]"),
        "the scenario grew a [settings] table"
    );
    text.push_str("\n[settings]\nlaw = \"gradient\"\n\n[output]\nsetpoints = 2\n");
    std::fs::write(&scenario, text).unwrap();
    let scenario_arg = scenario.to_str().unwrap();
    let host_dir = dir.path().join("host");
    assert_eq!(
        capp(&[
            "run",
            scenario_arg,
            "--out",
            host_dir.to_str().unwrap(),
            "--quiet"
        ]),
        ExitCode::SUCCESS
    );
    let host_rows = rows_by_step(&host_dir.join("setpoints.csv"));

    let (_qemu, board) = Qemu::boot(&elf, None).expect("boot QEMU");
    let proxy = FaultProxy::start(board).unwrap();
    let address = format!("127.0.0.1:{}", proxy.port);

    // 1. Board to host: 1 500 frames of faults, starting inside the stream.
    let to_host = Faults {
        seed: 0x5EED_CAFE,
        after_frames: 80,
        for_frames: 1500,
        flip: 0.02,
        drop: 0.02,
        duplicate: 0.02,
        cut: 0.02,
        repeat: 0.02,
        pause: 0.004,
        pause_for: Duration::from_millis(150),
    };
    proxy.set_faults(to_host, Faults::NONE);
    let problem = Problem::load(&scenario).unwrap();
    let validated = problem.validate().unwrap();
    let (result, report) = {
        let mut link = capp_link::connect_tcp(address.as_str()).unwrap();
        capp_sim::serial::plan_on_board(
            &mut link,
            &problem,
            &validated,
            Duration::from_secs(8),
            |_| {},
        )
        .expect("the plan completes despite the faults")
    };
    let (log, _) = proxy.logs();
    eprintln!("injected: {log:?}");
    eprintln!("host report:\n{report}");
    assert_eq!(result.outcome, capp_core::Outcome::Reached);
    assert!(log.damaged() >= 80, "enough faults were injected: {log:?}");
    assert!(log.repeated >= 10 && log.paused >= 1, "{log:?}");

    // Every gap is reported: exactly the damaged setpoints, plus the board's own drops.
    let missing: BTreeSet<u32> = report.missing.iter().copied().collect();
    assert!(
        log.damaged_setpoints.is_subset(&missing),
        "a damaged setpoint was not reported missing"
    );
    assert_eq!(
        missing.len() as u64,
        log.damaged_setpoints.len() as u64 + report.dropped_by_board as u64,
        "gaps beyond the damage are the board's counted drops"
    );
    assert_eq!(
        report.received as u64 + missing.len() as u64,
        report.produced as u64
    );
    assert!(report.frame_errors.total() as u64 >= log.damaged());
    assert_eq!(
        report.duplicates as usize,
        log.repeated_setpoints.len(),
        "repeats kept once"
    );
    // No damaged setpoint is accepted: every kept row is the host's, bit for bit.
    let out = dir.path().join("faulty");
    let mut summary = capp_sim::output::summary::Summary::new(&problem, &result);
    summary.link = Some(report.clone());
    capp_sim::output::write_run(&out, &problem, &result, &summary, |_| Ok(())).unwrap();
    let board_rows = rows_by_step(&out.join("setpoints.csv"));
    assert_eq!(board_rows.len(), report.received);
    for (step, row) in &board_rows {
        assert_eq!(Some(row), host_rows.get(step), "step {step}");
    }
    // After the faults stop, the stream is whole: nothing missing after the
    // last damaged setpoint's stretch.
    let last_faulted = log.damaged_setpoints.iter().max().copied().unwrap_or(0);
    let tail: Vec<u32> = (last_faulted + 1..report.produced).collect();
    assert!(tail.len() > 500, "the clean tail is long: {}", tail.len());
    assert!(
        tail.iter().all(|s| !missing.contains(s)),
        "setpoints lost after the faults stopped"
    );

    // 2. Host to board: every command frame damaged; each gets an error reply.
    proxy.set_faults(
        Faults::NONE,
        Faults {
            seed: 7,
            after_frames: 0,
            for_frames: 6,
            // Cut short: one bad frame each (a flipped bit could make a
            // 0x00 and so two frames, two error replies).
            cut: 1.0,
            ..Faults::NONE
        },
    );
    let mut link = capp_link::connect_tcp(address.as_str()).unwrap();
    link.timeout = Duration::from_secs(3);
    let rx_errors_before = {
        // The first six frames are damaged: use them up with pings.
        let mut refused = 0;
        for nonce in 0..6 {
            match link.ping(nonce) {
                Err(LinkError::Refused { command, .. }) => {
                    assert_eq!(command, NO_COMMAND);
                    refused += 1;
                }
                other => panic!("a damaged ping got {other:?}"),
            }
        }
        assert_eq!(refused, 6);
        // Clean from here: the board answers.
        assert_eq!(link.ping(99).unwrap(), capp_proto::VERSION);
        link.status().unwrap().rx_errors
    };
    let (_, to_board) = proxy.logs();
    eprintln!("injected towards the board: {to_board:?}; board rx_errors {rx_errors_before}");
    assert!(rx_errors_before >= 6);
    drop(link);

    // 3. A clean line: `capp serial` through the proxy gets the whole plan.
    proxy.set_faults(Faults::NONE, Faults::NONE);
    let clean = dir.path().join("clean");
    assert_eq!(
        capp(&[
            "serial",
            scenario_arg,
            "--tcp",
            &address,
            "--out",
            clean.to_str().unwrap(),
            "--quiet"
        ]),
        ExitCode::SUCCESS,
        "whole stream and target reached"
    );
    assert_eq!(rows_by_step(&clean.join("setpoints.csv")), host_rows);
}
