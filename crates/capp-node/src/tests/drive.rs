//! What a setpoint tells a drive (protocol 7): the joints' velocities and
//! accelerations beside their positions, bit for bit the host planner's
//! (`Planner::drive`: the tracker's state; stepped, the step's rate and its
//! change over the step), and the
//! tracked ticks whose work overran the control period, counted. The drive
//! limits a load carries (protocol 8's `Drive`), checked and planned with.

use core::sync::atomic::{AtomicU32, Ordering};
use std::vec::Vec;

use capp_core::{pips, Mission, Motion, Phase, Planner, Robot, Scenario};
use capp_proto::{Command, ErrorCode, Part, Preset, Reply, State, NO_INDEX};

use super::{exchange, load_commands_with, outcomes, replies, target, FakeUart};
use crate::Node;

/// One joint vector, as bits.
fn bits(v: &[f32]) -> Vec<u32> {
    v.iter().map(|x| x.to_bits()).collect()
}

/// Per setpoint: positions, velocities, accelerations and plan time, as bits.
type Row = (Vec<u32>, Vec<u32>, Vec<u32>, u32);

fn tracked() -> capp_core::Settings {
    capp_core::Settings {
        motion: Motion::Tracked,
        ..capp_core::Settings::default()
    }
}

/// Each joint's acceleration and jerk limits, or none: the defaults.
type Drives<'a> = &'a [(f32, f32)];

/// The host's plan with `settings` and the drive limits `drive`, every
/// step, as the board should stream it: the start, then the state after
/// every step.
fn host_rows(settings: capp_core::Settings, drive: Drives) -> Vec<Row> {
    let robot = Robot::<32>::new(&pips::joints()).unwrap();
    let mission = Mission::<16>::new(&[target()], settings).unwrap();
    let mut scenario =
        Scenario::<32, 64, 16>::new(robot, &[] as &[capp_core::Solid], &mission).unwrap();
    if !drive.is_empty() {
        let (accel, jerk): (Vec<f32>, Vec<f32>) = drive.iter().copied().unzip();
        scenario.set_drive_limits(&accel, &jerk).unwrap();
    }
    let mut planner = Planner::new(&scenario, &pips::home()).unwrap();
    let row = |p: &Planner<32>, time_s: f32| -> Row {
        if settings.motion == Motion::Stepped {
            // A stepped plan's velocity is its step's rate.
            assert_eq!(bits(p.drive().velocity()), bits(p.rates()));
        }
        (
            bits(p.joints()),
            bits(p.drive().velocity()),
            bits(p.drive().acceleration()),
            time_s.to_bits(),
        )
    };
    let mut out = std::vec![row(&planner, 0.0)];
    let mut time_s = 0.0f32;
    loop {
        let r = planner.step(&scenario).unwrap();
        // Tracked: the tick count times the period; stepped: the sum.
        time_s = if settings.motion == Motion::Tracked {
            r.step as f32 * settings.time_step_s
        } else {
            time_s + r.time_step_s
        };
        out.push(row(&planner, time_s));
        if let Phase::Done(_) = r.phase {
            return out;
        }
    }
}

/// The `Drive` commands of `drive`, joint by joint.
fn drive_commands(drive: Drives) -> Vec<Command> {
    drive
        .iter()
        .enumerate()
        .map(|(i, &(max_accel, max_jerk))| Command::Drive {
            index: i as u8,
            drive: capp_proto::Drive {
                max_accel,
                max_jerk,
            },
        })
        .collect()
}

/// Plans with `settings` and the drive limits `drive` on a node (cycle
/// counter `counter` at `hz`, if any), every step streamed over a UART that
/// keeps up; the setpoints and the final status.
fn board_rows(
    settings: capp_core::Settings,
    drive: Drives,
    counter: Option<(fn() -> u32, u32)>,
) -> (Vec<Row>, capp_proto::Status) {
    let mut node = Node::<2048>::new();
    if let Some((counter, hz)) = counter {
        node.set_cycle_counter(counter, hz);
    }
    let mut uart = FakeUart::new(usize::MAX);
    for c in load_commands_with(settings)
        .into_iter()
        .chain(drive_commands(drive))
    {
        uart.send(&c);
    }
    uart.send(&Command::Run {
        every: 1,
        error_change: None,
    });
    for _ in 0..4 {
        node.poll(&mut uart);
    }
    uart.tx.clear();
    for _ in 0..100_000 {
        node.tick(1);
        node.poll(&mut uart);
        if node.status().state != State::Running && node.tx_len() == 0 {
            break;
        }
    }
    let mut rows = Vec::new();
    let mut status = None;
    for r in replies(&uart.tx) {
        match r {
            Reply::Setpoint {
                joints,
                velocity,
                acceleration,
                time_s,
                ..
            } => rows.push((
                bits(&joints),
                bits(&velocity),
                bits(&acceleration),
                time_s.to_bits(),
            )),
            Reply::Status(s) => status = Some(s),
            other => panic!("{other:?}"),
        }
    }
    (rows, status.unwrap())
}

#[test]
fn a_tracked_plan_streams_the_drive_state_bit_for_bit() {
    let expected = host_rows(tracked(), &[]);
    let (rows, status) = board_rows(tracked(), &[], None);
    assert_eq!(
        (status.state, status.outcome),
        (State::Done, Some(capp_proto::Outcome::Reached))
    );
    assert_eq!(rows.len(), expected.len());
    for (i, (r, e)) in rows.iter().zip(&expected).enumerate() {
        assert_eq!(r, e, "setpoint {i}");
    }
    // The drive moved, accelerated and came to rest.
    let moving = |row: &Row| row.1.iter().any(|&v| f32::from_bits(v) != 0.0);
    let accelerating = |row: &Row| row.2.iter().any(|&a| f32::from_bits(a) != 0.0);
    assert!(rows.iter().any(moving) && rows.iter().any(accelerating));
    // No cycle counter: no tick can be seen to overrun.
    assert_eq!(status.period_overruns, 0);
}

#[test]
fn a_stepped_plan_streams_its_rates_and_their_change() {
    let settings = capp_core::Settings::default();
    let expected = host_rows(settings, &[]);
    let (rows, _) = board_rows(settings, &[], None);
    assert_eq!(rows, expected);
    assert!(rows.iter().skip(1).any(|r| r.1.iter().any(|&v| v != 0)));
    assert!(rows.iter().skip(1).any(|r| r.2.iter().any(|&a| a != 0)));
}

/// Cycle counters for the overrun test: every reading `STEP` cycles after
/// the last, so a tick's work (two readings) takes exactly `STEP` cycles.
/// One counter per test: the tests run in parallel.
macro_rules! counter {
    ($name:ident, $step:expr) => {
        fn $name() -> u32 {
            static NOW: AtomicU32 = AtomicU32::new(0);
            NOW.fetch_add($step, Ordering::Relaxed)
        }
    };
}
counter!(slow, 60);
counter!(fast, 40);
counter!(slow_stepped, 60);

#[test]
fn tracked_ticks_longer_than_the_control_period_are_counted() {
    // A 1 kHz "core clock": the default 0.05 s period is 50 cycles.
    let (rows, status) = board_rows(tracked(), &[], Some((slow, 1000)));
    let steps = (rows.len() - 1) as u32;
    assert_eq!(status.step, steps);
    assert_eq!(status.step_cycles_max, 60);
    assert_eq!(status.period_overruns, steps, "every tick overran");
    // The same plan, bit for bit: timing changes nothing but the count.
    assert_eq!(rows, host_rows(tracked(), &[]));

    let (_, status) = board_rows(tracked(), &[], Some((fast, 1000)));
    assert_eq!(status.step_cycles_max, 40);
    assert_eq!(status.period_overruns, 0, "every tick within its period");

    // A stepped plan has no period to overrun.
    let (_, status) = board_rows(
        capp_core::Settings::default(),
        &[],
        Some((slow_stepped, 1000)),
    );
    assert_eq!(status.step_cycles_max, 60);
    assert_eq!(status.period_overruns, 0);
}

/// PIPS's drive limits for the tests below: not the defaults (full rate
/// from rest in 0.5 s, full acceleration in 0.1 s) but a ramp of 0.3 to
/// 0.8 s and a jerk time of 0.05 to 0.2 s, differing joint by joint.
fn own_drives() -> Vec<(f32, f32)> {
    pips::joints()
        .iter()
        .enumerate()
        .map(|(j, joint)| {
            let accel = joint.max_rate / (0.3 + 0.5 * (j % 3) as f32 / 2.0);
            (accel, accel / (0.05 + 0.15 * (j % 4) as f32 / 3.0))
        })
        .collect()
}

#[test]
fn drive_limits_reach_the_boards_scenario_bit_for_bit() {
    let drive = own_drives();
    let expected = host_rows(tracked(), &drive);
    // Another plan than with the defaults: the board must use what came.
    assert_ne!(expected, host_rows(tracked(), &[]));
    let (rows, status) = board_rows(tracked(), &drive, None);
    assert_eq!(status.state, State::Done);
    assert_eq!(rows.len(), expected.len());
    for (i, (r, e)) in rows.iter().zip(&expected).enumerate() {
        assert_eq!(r, e, "setpoint {i}");
    }
    // Each joint within its own limits, read back from the streamed
    // velocities: the acceleration limit bounds their change per tick.
    let dt = tracked().time_step_s;
    for pair in rows.windows(2) {
        for (j, (&v0, &v1)) in pair[0].1.iter().zip(&pair[1].1).enumerate() {
            let change = (f32::from_bits(v1) - f32::from_bits(v0)).abs() / dt;
            assert!(change <= drive[j].0 * (1.0 + 1e-4), "joint {j}: {change}");
        }
    }

    // The node's scenario holds them; Clear(Drives), a new robot or the
    // preset bring back the defaults.
    let mut node = Node::<2048>::new();
    let mut uart = FakeUart::new(usize::MAX);
    let run = Command::Run {
        every: 1,
        error_change: None,
    };
    let defaults = |node: &Node<2048>| {
        node.plan
            .scenario
            .drive_limits()
            .iter()
            .all(|l| *l == capp_core::tracker::limits::DriveLimits::from_rate(l.max_rate))
    };
    for clear in [
        Command::Clear(Part::Drives),
        Command::Clear(Part::All),
        Command::Preset(Preset::Pips),
    ] {
        for c in load_commands_with(tracked())
            .into_iter()
            .chain(drive_commands(&drive))
        {
            uart.send(&c);
        }
        uart.send(&run);
        exchange(&mut node, &mut uart);
        let limits = node.plan.scenario.drive_limits();
        assert_eq!(limits.len(), drive.len());
        for (l, &(a, j)) in limits.iter().zip(&drive) {
            assert_eq!(
                (l.max_accel.to_bits(), l.max_jerk.to_bits()),
                (a.to_bits(), j.to_bits())
            );
        }
        uart.send(&Command::Stop);
        uart.send(&clear);
        if clear == Command::Clear(Part::All) {
            for c in load_commands_with(tracked()) {
                uart.send(&c);
            }
        }
        uart.send(&run);
        exchange(&mut node, &mut uart);
        assert_eq!(node.status().state, State::Running, "after {clear:?}");
        assert!(defaults(&node), "after {clear:?}");
        uart.send(&Command::Stop);
        exchange(&mut node, &mut uart);
    }
}

#[test]
fn bad_drive_limits_are_refused_with_the_joint() {
    let drive = own_drives();
    let mut node = Node::<2048>::new();
    let mut uart = FakeUart::new(usize::MAX);
    for c in load_commands_with(tracked()) {
        uart.send(&c);
    }
    exchange(&mut node, &mut uart);
    let one = |index: u8, max_accel: f32, max_jerk: f32| Command::Drive {
        index,
        drive: capp_proto::Drive {
            max_accel,
            max_jerk,
        },
    };
    // On arrival: a limit that is not a number or infinite, out of order.
    uart.send(&one(0, f32::NAN, 1.0));
    uart.send(&one(0, 1.0, f32::INFINITY));
    uart.send(&one(1, 1.0, 1.0));
    assert_eq!(
        outcomes(&exchange(&mut node, &mut uart)),
        [
            (13, ErrorCode::NotFinite, 0),
            (13, ErrorCode::NotFinite, 0),
            (13, ErrorCode::OutOfOrder, 1)
        ]
    );
    let run = Command::Run {
        every: 1,
        error_change: None,
    };
    // At `Run`: joint 4's acceleration or jerk limit zero or negative.
    for (accel, jerk) in [(0.0, 1.0), (-1.0, 1.0), (1.0, 0.0), (1.0, -0.5)] {
        uart.send(&Command::Clear(Part::Drives));
        let mut commands = drive_commands(&drive);
        commands[4] = one(4, accel, jerk);
        for c in &commands {
            uart.send(c);
        }
        uart.send(&run);
        let got = outcomes(&exchange(&mut node, &mut uart));
        assert_eq!(
            got.last(),
            Some(&(8, ErrorCode::InvalidDrive, 4)),
            "{accel} {jerk}"
        );
        assert_ne!(node.status().state, State::Running);
    }
    // Not one per joint.
    uart.send(&Command::Clear(Part::Drives));
    for c in drive_commands(&drive[..17]) {
        uart.send(&c);
    }
    uart.send(&run);
    let got = outcomes(&exchange(&mut node, &mut uart));
    assert_eq!(got.last(), Some(&(8, ErrorCode::InvalidDrive, NO_INDEX)));
    // A 33rd does not fit.
    uart.send(&Command::Clear(Part::Drives));
    for i in 0..33u8 {
        uart.send(&one(i, 1.0, 1.0));
    }
    let got = outcomes(&exchange(&mut node, &mut uart));
    assert_eq!(got.last(), Some(&(13, ErrorCode::Capacity, 32)));
    // And the good ones run.
    uart.send(&Command::Clear(Part::Drives));
    for c in drive_commands(&drive) {
        uart.send(&c);
    }
    uart.send(&run);
    let got = outcomes(&exchange(&mut node, &mut uart));
    assert_eq!(got.last(), Some(&(8, ErrorCode::Framing, 0xAA)));
    assert_eq!(node.status().state, State::Running);
}
