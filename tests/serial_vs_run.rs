//! End to end through the command line users run: `capp serial --qemu` boots
//! the firmware under QEMU, uploads a scenario over the emulated UART and
//! receives the plan; `capp run` plans the same scenario on the host. The two
//! output folders must agree: the same setpoints (step numbers and joint
//! vectors, printed at full precision, so bit for bit), the same `joints.dat`,
//! the same recomputed poses, errors and clearances, and the serial run must
//! report the stream whole (exit status 0 means reached *and* nothing
//! missing, damaged or rejected).

use std::path::{Path, PathBuf};
use std::time::Duration;

use capp_core::{Motion, Phase};
use capp_sim::problem::CorePlanner;
use capp_sim::Problem;
use capp_system_tests::capp;

fn scenario(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../host-sim/scenarios")
        .join(name)
}

fn csv(path: &Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(path).unwrap();
    text.lines()
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect()
}

/// A scenario of the workspace tests only (`tests/scenarios/`).
fn test_scenario(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenarios")
        .join(name)
}

/// Runs `file` (in `host-sim/scenarios/`) both ways and compares the
/// outputs; returns the setpoint count.
fn serial_matches_run(file: &str, elf: &Path) -> usize {
    serial_matches_run_at(&scenario(file), elf)
}

/// [`serial_matches_run`] for the scenario at `path`.
fn serial_matches_run_at(path: &Path, elf: &Path) -> usize {
    let dir = tempfile::tempdir().unwrap();
    let host = dir.path().join("host");
    let board = dir.path().join("board");
    let file = path.file_name().unwrap().to_str().unwrap();
    let path = path.to_str().unwrap();
    let host_exit = capp(&["run", path, "--out", host.to_str().unwrap(), "--quiet"]);
    let board_exit = capp(&[
        "serial",
        path,
        "--qemu",
        "--elf",
        elf.to_str().unwrap(),
        "--out",
        board.to_str().unwrap(),
        "--quiet",
    ]);
    let summary = std::fs::read_to_string(board.join("summary.txt")).unwrap();
    eprintln!("{file} on the board:\n{summary}");
    assert_eq!(host_exit, board_exit, "same outcome both ways");
    assert!(
        summary.contains(", whole\n"),
        "stream incomplete:\n{summary}"
    );
    assert!(summary.contains("missing:           0 "), "{summary}");
    assert!(summary.contains("damaged frames:    0 "), "{summary}");
    assert!(
        summary.contains(" ticks over the control period, "),
        "{summary}"
    );

    let expected = csv(&host.join("setpoints.csv"));
    let received = csv(&board.join("setpoints.csv"));
    assert_eq!(expected[0], received[0], "same columns");
    let header = &expected[0];
    // Per-step details a setpoint frame does not carry (the board reports
    // its escape in `Status`, not per setpoint).
    let not_sent = ["h_s", "constrained", "halvings", "escape"];
    assert_eq!(received.len(), expected.len(), "same number of setpoints");
    for (row, (e, r)) in expected.iter().zip(&received).enumerate().skip(1) {
        for (column, (a, b)) in header.iter().zip(e.iter().zip(r)) {
            if !not_sent.contains(&column.as_str()) {
                assert_eq!(a, b, "setpoint row {row}, column {column}");
            }
        }
    }
    assert_eq!(
        std::fs::read(host.join("joints.dat")).unwrap(),
        std::fs::read(board.join("joints.dat")).unwrap(),
        "joints.dat"
    );
    // The received trajectory passes the independent checker.
    assert_eq!(capp(&["check", board.to_str().unwrap()]), host_exit);
    expected.len() - 1
}

#[test]
fn the_papers_manoeuvre_planned_on_the_board_is_the_host_plan() {
    let Some(elf) = capp_system_tests::firmware_or_skip() else {
        return;
    };
    let n = serial_matches_run("pips_payload_bay.toml", &elf);
    assert!(n > 20, "{n} setpoints");
}

/// The bay from CAD (issue 24): a true box floor and bulkhead and a
/// cylindrical payload travel in protocol 10's `Obstacle.primitive`, and
/// the board's plan round them is the host's to the bit.
#[test]
fn the_cad_bay_planned_on_the_board_is_the_host_plan() {
    let Some(elf) = capp_system_tests::firmware_or_skip() else {
        return;
    };
    let n = serial_matches_run("pips_payload_bay_cad.toml", &elf);
    assert!(n > 20, "{n} setpoints");
}

/// A part from a mesh file (issue 24): the host makes the STL's convex hull,
/// protocol 11's `Hull` carries its corners, the board measures it by its
/// own GJK, and its plan round the bracket is the host's to the bit.
#[test]
fn a_mesh_part_planned_on_the_board_is_the_host_plan() {
    let Some(elf) = capp_system_tests::firmware_or_skip() else {
        return;
    };
    let n = serial_matches_run("pips_payload_bay_mesh.toml", &elf);
    assert!(n > 20, "{n} setpoints");
}

#[test]
fn the_listings_input_dat_planned_on_the_board_is_the_host_plan() {
    let Some(elf) = capp_system_tests::firmware_or_skip() else {
        return;
    };
    let n = serial_matches_run("legacy/input.dat", &elf);
    assert!(n > 5, "{n} setpoints");
}

/// Issue 13's dead end on the board: the law alone stalls against the box
/// (host-sim's scenario tests show it), the board's own escape detours round
/// it, and the plan it streams is the host's to the bit and reaches the target.
#[test]
fn a_dead_end_escaped_on_the_board_is_the_host_plan() {
    let Some(elf) = capp_system_tests::firmware_or_skip() else {
        return;
    };
    let n = serial_matches_run("pips_escape.toml", &elf);
    assert!(n > 20, "{n} setpoints");
}

/// The search (`capp_core::escape::search`) on the board: it holds the arm still for
/// its slices, walks the tree's path and reaches the target, the host's plan
/// to the bit.
#[test]
fn a_searched_path_on_the_board_is_the_host_plan() {
    let Some(elf) = capp_system_tests::firmware_or_skip() else {
        return;
    };
    let n = serial_matches_run("planar_search.toml", &elf);
    assert!(n > 1, "{n} setpoints");
}

/// Self-collision on the board (issue 25): the snake folded into a U reaches
/// across its own links; the host uploads its link capsules and checked
/// pairs (protocol 6), and the board's plan, which keeps every checked pair
/// of capsules apart, is the host's to the bit.
#[test]
fn a_snake_kept_off_itself_on_the_board_is_the_host_plan() {
    let Some(elf) = capp_system_tests::firmware_or_skip() else {
        return;
    };
    let n = serial_matches_run("snake_fold.toml", &elf);
    assert!(n > 1, "{n} setpoints");
}

/// Tracked motion on the board (issue 22, protocols 7 and 8): the snake of
/// `snake_fold.toml` in fixed ticks of 0.05 s, each joint within its rate,
/// acceleration and jerk limits, which are not the defaults (the host sends
/// them). Through `capp serial` the board's outputs
/// are `capp run`'s (positions bit for bit); in process, every setpoint's
/// velocities and accelerations are the host planner's drive state after
/// that tick (`Planner::drive`), bit for bit too, and the board reports how
/// many ticks overran their period.
#[test]
fn a_tracked_plan_on_the_board_is_the_host_plan_with_its_drive_state() {
    let Some(elf) = capp_system_tests::firmware_or_skip() else {
        return;
    };
    let path = test_scenario("snake_fold_tracked.toml");
    let n = serial_matches_run_at(&path, &elf);
    assert!(n > 20, "{n} setpoints");

    let problem = Problem::load(&path).unwrap();
    assert_eq!(problem.settings.motion, Motion::Tracked);
    let scenario = problem.validate().unwrap();
    // Limits of the file's own, which the board can only have from the host:
    // a board on the defaults plans another trajectory.
    assert!(!problem.default_drive_limits());
    let first = scenario.drive_limits()[0];
    let default = capp_core::tracker::limits::DriveLimits::from_rate(first.max_rate);
    assert!(first.max_accel < 0.7 * default.max_accel, "{first:?}");
    // The host: capp run's planner (`capp_sim::plan::run`), every tick's
    // drive state kept, positions and plan time with it.
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let mut planner = CorePlanner::new(&scenario, &problem.start).unwrap();
    let state = |p: &CorePlanner| {
        (
            bits(p.joints()),
            bits(p.drive().velocity()),
            bits(p.drive().acceleration()),
        )
    };
    let mut expected = vec![(0, state(&planner))];
    planner
        .run(&scenario, |planner, report| {
            expected.push((report.step, state(planner)));
        })
        .unwrap();
    assert!(matches!(planner.phase(), Phase::Done(_)));

    let (_qemu, mut link) = capp_link::qemu::Qemu::launch(&elf, None).unwrap();
    let (run, report) = capp_sim::serial::plan_on_board(
        &mut link,
        &problem,
        &scenario,
        Duration::from_secs(30),
        |_| {},
    )
    .unwrap();
    eprintln!("{report}");
    assert!(report.whole(), "{report}");
    // `[output] setpoints = 1`: every tick is a setpoint.
    assert_eq!(run.rows.len(), expected.len(), "one setpoint per tick");
    let dt = problem.settings.time_step_s;
    let mut moved = false;
    let mut accelerated = false;
    for (row, (step, (q, v, a))) in run.rows.iter().zip(&expected) {
        assert_eq!(row.step, *step);
        assert_eq!(bits(&row.q), *q, "positions after tick {step}");
        assert_eq!(bits(&row.velocity), *v, "velocities after tick {step}");
        assert_eq!(
            bits(&row.acceleration),
            *a,
            "accelerations after tick {step}"
        );
        // Fixed ticks: the board's plan time is the tick count times the
        // period, so each received tick lasts exactly one period.
        if *step > 0 {
            assert_eq!(row.h, dt, "tick {step} lasted {} s", row.h);
        }
        moved |= row.velocity.iter().any(|&x| x != 0.0);
        accelerated |= row.acceleration.iter().any(|&x| x != 0.0);
    }
    assert!(moved && accelerated, "the drive state is not all zeros");
    // Arrived at rest, as the tracker brings it.
    let last = run.rows.last().unwrap();
    let rates = problem.joints.iter().map(|j| j.max_rate);
    for (v, rate) in last.velocity.iter().zip(rates) {
        assert!(v.abs() <= 0.01 * rate, "{v} at the end");
    }
    // Under QEMU the cycle counter runs in emulated time, which follows the
    // host's speed: the count is reported, whatever it is on a busy machine.
    eprintln!(
        "ticks over the control period on the board: {} of {}",
        report.period_overruns,
        expected.len() - 1
    );
}

/// A robot from its URDF on the board (issue 23, protocol 9): the UR5's six
/// general joints (each joint's origin and axis) and its tool travel in the
/// upload, with the link capsules fitted to its collision meshes (round
/// segments of their own), and the
/// board's plan round the box on the table is `capp run`'s to the bit.
#[test]
fn a_urdf_robot_planned_on_the_board_is_the_host_plan() {
    let Some(elf) = capp_system_tests::firmware_or_skip() else {
        return;
    };
    let path = scenario("ur5_table.toml");
    let problem = Problem::load(&path).unwrap();
    assert!(problem.joints.iter().all(|j| j.origin.is_some()));
    assert!(
        !problem.tool.is_identity(),
        "tool0 is a placement of its own"
    );
    // Its capsules are segments of their own (the upper arm's body lies
    // off its chord): protocol 12's `Capsule.segment` carries them.
    assert_eq!(problem.links.segments.len(), problem.joints.len());
    let n = serial_matches_run_at(&path, &elf);
    assert!(n > 5, "{n} setpoints");
}

/// The Panda from its URDF (seven general joints, a tool) on the board: the
/// host's plan to the bit.
#[test]
fn the_panda_from_its_urdf_planned_on_the_board_is_the_host_plan() {
    let Some(elf) = capp_system_tests::firmware_or_skip() else {
        return;
    };
    let n = serial_matches_run("panda_table.toml", &elf);
    assert!(n > 5, "{n} setpoints");
}

/// The Panda reaching into a shelf whose ten boards come from one STL, each
/// a box obstacle: on the board, the host's plan to the bit.
#[test]
fn a_shelf_of_boards_from_one_stl_planned_on_the_board_is_the_host_plan() {
    let Some(elf) = capp_system_tests::firmware_or_skip() else {
        return;
    };
    let n = serial_matches_run("panda_shelf_mesh.toml", &elf);
    assert!(n > 5, "{n} setpoints");
}

/// The Panda reaching into a tote from one closed STL solid, split into
/// five boxes on the host: on the board, the host's plan to the bit.
#[test]
fn a_tote_split_into_boxes_planned_on_the_board_is_the_host_plan() {
    let Some(elf) = capp_system_tests::firmware_or_skip() else {
        return;
    };
    let n = serial_matches_run("panda_tote_mesh.toml", &elf);
    assert!(n > 3, "{n} setpoints");
}
