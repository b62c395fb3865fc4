//! End to end: the firmware under QEMU plans PIPS from home to a reachable
//! pose, streamed over the emulated UART; the stream must be complete, its
//! frames intact, and every joint vector bit-identical to capp-core's plan on
//! the host. Then bad commands get their error replies and a valid plan still
//! runs. Skipped (with a message) when qemu-system-arm or the firmware ELF is
//! missing: build it with `cargo build --release` in firmware/.

use std::time::Duration;

use capp_core::kinematics::{forward_kinematics, Frames};
use capp_core::setpoint::Decimator;
use capp_core::{
    pips, Mission, Phase, Planner, Robot, Scenario, SetpointFilter, Settings, Waypoint,
};
use capp_link::qemu::Qemu;
use capp_link::{LinkError, Upload};
use capp_proto::{Command, ErrorCode, Outcome, Reply, State, NO_COMMAND};

/// A pose PIPS reaches: forward kinematics of home with a few joints moved.
fn target() -> Waypoint {
    let robot = pips::robot::<32>().unwrap();
    let mut q = pips::home();
    q[0] += 0.3;
    q[5] += 0.25;
    q[7] -= 0.2;
    q[11] += 0.3;
    let mut frames = Frames::<32>::default();
    forward_kinematics(&robot, &q, &mut frames);
    let p = frames.end_position();
    let r = frames.end_rotation();
    let rows = [
        [r[(0, 0)], r[(0, 1)], r[(0, 2)]],
        [r[(1, 0)], r[(1, 1)], r[(1, 2)]],
        [r[(2, 0)], r[(2, 1)], r[(2, 2)]],
    ];
    Waypoint::pose([p.x, p.y, p.z], rows)
}

/// The host's plan: (step, joints) of every setpoint for decimation `every`,
/// the start included.
fn host_plan(
    waypoints: &[Waypoint],
    settings: Settings,
    every: u32,
) -> (Vec<(u32, Vec<f32>)>, Outcome) {
    let robot = Robot::<32>::new(&pips::joints()).unwrap();
    let mission = Mission::<16>::new(waypoints, settings).unwrap();
    let scenario =
        Scenario::<32, 64, 16>::new(robot, &[] as &[capp_core::Solid], &mission).unwrap();
    let mut planner = Planner::new(&scenario, &pips::home()).unwrap();
    let mut decimator = Decimator::new(SetpointFilter::Every(every));
    let mut out = Vec::new();
    let mut report = *planner.last_report();
    loop {
        if decimator.offer(&report) {
            out.push((report.step, planner.joints().to_vec()));
        }
        if let Phase::Done(o) = report.phase {
            return (out, o.into());
        }
        report = planner.step(&scenario).unwrap();
    }
}

fn bits(v: &[f32]) -> Vec<u32> {
    v.iter().map(|x| x.to_bits()).collect()
}

#[test]
fn firmware_under_qemu_streams_the_host_plan_bit_for_bit() {
    let Some(elf) = capp_system_tests::firmware_or_skip() else {
        return;
    };
    let log = std::env::temp_dir().join(format!("capp-qemu-{}.defmt", std::process::id()));
    let (_qemu, mut link) = Qemu::launch(&elf, Some(&log)).expect("boot QEMU");
    link.timeout = Duration::from_secs(10);
    assert_eq!(link.ping(0xC0FFEE).unwrap(), capp_proto::VERSION);

    let settings = Settings::default();
    let waypoints = [target()];
    let joints = pips::joints();
    let start = pips::home();
    let upload = Upload {
        joints: &joints,
        tool: capp_core::robot::Placement::IDENTITY,
        capsule_radius: &[],
        capsule_rows: &[],
        capsule_segments: &[],
        drive: &[],
        obstacles: &[],
        hulls: &[],
        waypoints: &waypoints,
        joint_goals: &[],
        settings,
        start: &start,
    };
    let (expected, outcome) = host_plan(&waypoints, settings, 1);
    assert_eq!(outcome, Outcome::Reached, "the host plan reaches the pose");

    link.upload(&upload).unwrap();
    link.run(SetpointFilter::Every(1)).unwrap();
    let record = link.receive_plan(Duration::from_secs(30)).unwrap();
    eprintln!(
        "plan: {} setpoints, status {:?}, frame errors {:?}",
        record.setpoints.len(),
        record.status,
        record.frame_errors
    );
    assert_eq!(record.status.state, State::Done);
    assert_eq!(record.status.outcome, Some(outcome));
    assert_eq!(record.frame_errors.total(), 0, "no frame failed");
    assert!(
        record.missing.is_empty(),
        "missing seqs {:?}",
        record.missing
    );
    assert_eq!(record.status.dropped, 0);
    assert_eq!(record.setpoints.len(), expected.len());
    for (i, (got, (step, q))) in record.setpoints.iter().zip(&expected).enumerate() {
        assert_eq!(got.seq, i as u32);
        assert_eq!(got.step, *step);
        assert_eq!(
            bits(&got.joints),
            bits(q),
            "setpoint {i} (step {step}) differs"
        );
    }

    // Bad commands: each gets its error reply, nothing changes on the board.
    let bad_crc = {
        let mut f = [0u8; 300];
        let n = capp_proto::encode(&Command::Ping { nonce: 0x0101_0101 }, &mut f).unwrap();
        // Corrupt a CRC byte (never to zero, which would cut the frame).
        f[n - 2] = if f[n - 2] == 0x40 {
            0x41
        } else {
            f[n - 2] ^ 0x40
        };
        f[..n].to_vec()
    };
    link.send_raw(&bad_crc).unwrap();
    expect_error(&mut link, NO_COMMAND, ErrorCode::Crc);
    // An unknown message (variant 200) with a valid CRC.
    let unknown = raw_frame(&[capp_proto::VERSION, 200, 1]);
    link.send_raw(&unknown).unwrap();
    expect_error(&mut link, NO_COMMAND, ErrorCode::UnknownMessage);
    // NaN in a joint.
    let mut j: capp_proto::Joint = joints[0].into();
    j.alpha = f32::NAN;
    expect_refused(
        &mut link,
        &Command::Joint { index: 0, joint: j },
        ErrorCode::NotFinite,
    );
    // An invalid robot: inverted limits, then Run.
    link.request(&Command::Clear(capp_proto::Part::Robot))
        .unwrap();
    let mut j: capp_proto::Joint = joints[0].into();
    j.min = 1.0;
    j.max = -1.0;
    link.request(&Command::Joint { index: 0, joint: j })
        .unwrap();
    expect_refused(
        &mut link,
        &Command::Run {
            every: 1,
            error_change: None,
        },
        ErrorCode::InvalidRobot,
    );
    // Link capsules with a radius of 0 (link 3's), then Run.
    link.request(&Command::Clear(capp_proto::Part::Robot))
        .unwrap();
    for (i, j) in joints.iter().enumerate() {
        link.request(&Command::Joint {
            index: i as u8,
            joint: (*j).into(),
        })
        .unwrap();
        let capsule = capp_proto::Capsule {
            radius: if i == 3 { 0.0 } else { 1.5 },
            checked: 0,
            segment: None,
        };
        link.request(&Command::Capsule {
            index: i as u8,
            capsule,
        })
        .unwrap();
    }
    match link.request(&Command::Run {
        every: 1,
        error_change: None,
    }) {
        Err(LinkError::Refused {
            command,
            code,
            index,
        }) => {
            assert_eq!((command, code, index), (8, ErrorCode::InvalidCapsules, 3))
        }
        other => panic!("expected a refusal, got {other:?}"),
    }
    // The previous plan's status is kept.
    let s = link.status().unwrap();
    assert_eq!((s.state, s.outcome), (State::Done, Some(Outcome::Reached)));
    assert_eq!(s.rx_errors, 2);
    assert_eq!(s.rx_overflows, 0);
    eprintln!("peak stack: {} bytes", s.stack_peak);
    // The stack budget (README, BENCHMARKS.md): a plan built in place needs
    // a few KiB; 43 KiB when the scenario was returned by value.
    assert!(
        s.stack_peak > 0 && s.stack_peak <= 8 * 1024,
        "peak stack {} bytes",
        s.stack_peak
    );
    // Cycles per step were counted (by TIMER0 under QEMU: emulated time).
    assert!(s.step_cycles_min <= s.step_cycles_mean && s.step_cycles_mean <= s.step_cycles_max);
    assert!(s.step_cycles_max > 0);
    eprintln!(
        "cycles per step (QEMU TIMER0, emulated time): min {} mean {} max {}",
        s.step_cycles_min, s.step_cycles_mean, s.step_cycles_max
    );

    // A valid plan still runs, decimated this time.
    link.upload(&upload).unwrap();
    link.run(SetpointFilter::Every(10)).unwrap();
    let record = link.receive_plan(Duration::from_secs(30)).unwrap();
    let (expected, _) = host_plan(&waypoints, settings, 10);
    assert!(record.missing.is_empty());
    assert_eq!(record.frame_errors.total(), 0);
    assert_eq!(record.setpoints.len(), expected.len());
    for (got, (step, q)) in record.setpoints.iter().zip(&expected) {
        assert_eq!(got.step, *step);
        assert_eq!(bits(&got.joints), bits(q));
    }
    let s = link.status().unwrap();
    eprintln!("final status {s:?}");
}

/// A farther pose (position only); there and back to [`target`] twice is a
/// plan of more than a thousand steps (over a second at 1 kHz).
fn far_target() -> Waypoint {
    let robot = pips::robot::<32>().unwrap();
    let mut q = pips::home();
    q[0] += 0.9;
    q[5] += 0.6;
    q[7] -= 0.5;
    q[11] += 0.7;
    q[14] -= 0.6;
    let mut frames = Frames::<32>::default();
    forward_kinematics(&robot, &q, &mut frames);
    let p = frames.end_position();
    Waypoint::at([p.x, p.y, p.z])
}

#[test]
fn commands_sent_while_a_plan_runs_are_all_answered() {
    let Some(elf) = capp_system_tests::firmware_or_skip() else {
        return;
    };
    let (_qemu, mut link) = Qemu::launch(&elf, None).expect("boot QEMU");
    link.timeout = Duration::from_secs(10);
    // The first-order gradient law: a long plan (some 1 900 steps), so that
    // many commands arrive while it runs.
    let mut settings = Settings::default();
    settings.law.kind = capp_core::control::LawKind::Gradient;
    let waypoints = [far_target(), target(), far_target(), target()];
    let joints = pips::joints();
    let start = pips::home();
    let (expected, outcome) = host_plan(&waypoints, settings, 1);
    assert!(expected.len() > 1000, "{} steps", expected.len());
    link.upload(&Upload {
        joints: &joints,
        tool: capp_core::robot::Placement::IDENTITY,
        capsule_radius: &[],
        capsule_rows: &[],
        capsule_segments: &[],
        drive: &[],
        obstacles: &[],
        hulls: &[],
        waypoints: &waypoints,
        joint_goals: &[],
        settings,
        start: &start,
    })
    .unwrap();
    link.run(SetpointFilter::Every(1)).unwrap();

    // While the stream runs: a ping or a status request after every 25th
    // setpoint, each sent without waiting for the last one's answer.
    let deadline = std::time::Instant::now() + Duration::from_secs(120);
    let mut setpoints = Vec::new();
    let (mut pings, mut statuses) = (0u32, 0u32);
    let mut pongs = Vec::new();
    let mut running_statuses = 0u32;
    let mut finals = Vec::new();
    loop {
        let outstanding = pings as usize - pongs.len() + (statuses - running_statuses) as usize;
        if !finals.is_empty() && outstanding < finals.len() {
            break;
        }
        match link.recv(deadline).expect("a reply before the deadline") {
            Reply::Setpoint { seq, joints, .. } => {
                setpoints.push((seq, joints.to_vec()));
                if setpoints.len() % 25 == 0 && finals.is_empty() {
                    if setpoints.len() % 50 == 0 {
                        link.send(&Command::Status).unwrap();
                        statuses += 1;
                    } else {
                        link.send(&Command::Ping { nonce: pings }).unwrap();
                        pings += 1;
                    }
                }
            }
            Reply::Pong { nonce, .. } => pongs.push(nonce),
            Reply::Status(s) if s.state == State::Running => running_statuses += 1,
            Reply::Status(s) => finals.push(s),
            other => panic!("unexpected reply {other:?}"),
        }
    }
    eprintln!(
        "{} setpoints; {pings} pings and {statuses} status requests sent while running, all answered",
        setpoints.len()
    );
    assert!(pings >= 20 && statuses >= 20);
    // Every ping answered, in order.
    assert_eq!(pongs, (0..pings).collect::<Vec<_>>());
    // Every status request answered (after the plan ended the answer says Done).
    assert_eq!(
        running_statuses as usize + finals.len(),
        statuses as usize + 1
    );
    let last = finals.last().unwrap();
    assert_eq!((last.state, last.outcome), (State::Done, Some(outcome)));
    assert_eq!((last.rx_errors, last.rx_overflows, last.dropped), (0, 0, 0));
    assert_eq!(link.frame_errors.total(), 0);
    // And the stream is the host's plan, bit for bit.
    assert_eq!(setpoints.len(), expected.len());
    for (i, ((seq, got), (step, q))) in setpoints.iter().zip(&expected).enumerate() {
        assert_eq!(*seq, i as u32);
        assert_eq!(bits(got), bits(q), "setpoint {i} (step {step}) differs");
    }
}

fn raw_frame(body: &[u8]) -> Vec<u8> {
    let mut b = body.to_vec();
    b.extend_from_slice(&capp_proto::crc::crc32(body).to_le_bytes());
    let mut out = vec![0u8; 300];
    let n = capp_proto::cobs::encode(&b, &mut out).unwrap();
    out.truncate(n);
    out.push(0);
    out
}

fn expect_error<T: std::io::Read + std::io::Write>(
    link: &mut capp_link::Link<T>,
    command: u8,
    code: ErrorCode,
) {
    let deadline = std::time::Instant::now() + Duration::from_secs(5);
    match link.recv(deadline).unwrap() {
        Reply::Error {
            command: c,
            code: e,
            ..
        } => assert_eq!((c, e), (command, code)),
        other => panic!("expected an error reply, got {other:?}"),
    }
}

fn expect_refused<T: std::io::Read + std::io::Write>(
    link: &mut capp_link::Link<T>,
    command: &Command,
    code: ErrorCode,
) {
    match link.request(command) {
        Err(LinkError::Refused {
            command: c,
            code: e,
            ..
        }) => {
            assert_eq!((c, e), (command.code(), code))
        }
        other => panic!("expected a refusal, got {other:?}"),
    }
}
