//! What a setpoint tells a drive (protocol 7): the joints' velocities and
//! accelerations beside their positions, bit for bit the host planner's
//! (`Planner::drive`: the tracker's state; stepped, the step's rate and its
//! change over the step), and the
//! tracked ticks whose work overran the control period, counted.

use core::sync::atomic::{AtomicU32, Ordering};
use std::vec::Vec;

use capp_core::{pips, Mission, Motion, Phase, Planner, Robot, Scenario};
use capp_proto::{Command, Reply, State};

use super::{load_commands_with, replies, target, FakeUart};
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

/// The host's plan with `settings`, every step, as the board should stream
/// it: the start, then the state after every step.
fn host_rows(settings: capp_core::Settings) -> Vec<Row> {
    let robot = Robot::<32>::new(&pips::joints()).unwrap();
    let mission = Mission::<16>::new(&[target()], settings).unwrap();
    let scenario = Scenario::<32, 64, 16>::new(robot, &[], &mission).unwrap();
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

/// Plans with `settings` on a node (cycle counter `counter` at `hz`, if
/// any), every step streamed over a UART that keeps up; the setpoints and
/// the final status.
fn board_rows(
    settings: capp_core::Settings,
    counter: Option<(fn() -> u32, u32)>,
) -> (Vec<Row>, capp_proto::Status) {
    let mut node = Node::<2048>::new();
    if let Some((counter, hz)) = counter {
        node.set_cycle_counter(counter, hz);
    }
    let mut uart = FakeUart::new(usize::MAX);
    for c in load_commands_with(settings) {
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
    let expected = host_rows(tracked());
    let (rows, status) = board_rows(tracked(), None);
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
    let expected = host_rows(settings);
    let (rows, _) = board_rows(settings, None);
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
    let (rows, status) = board_rows(tracked(), Some((slow, 1000)));
    let steps = (rows.len() - 1) as u32;
    assert_eq!(status.step, steps);
    assert_eq!(status.step_cycles_max, 60);
    assert_eq!(status.period_overruns, steps, "every tick overran");
    // The same plan, bit for bit: timing changes nothing but the count.
    assert_eq!(rows, host_rows(tracked()));

    let (_, status) = board_rows(tracked(), Some((fast, 1000)));
    assert_eq!(status.step_cycles_max, 40);
    assert_eq!(status.period_overruns, 0, "every tick within its period");

    // A stepped plan has no period to overrun.
    let (_, status) = board_rows(capp_core::Settings::default(), Some((slow_stepped, 1000)));
    assert_eq!(status.step_cycles_max, 60);
    assert_eq!(status.period_overruns, 0);
}
