//! The node driven through a simulated UART: complete streams when the UART
//! keeps up, counted gaps when it does not, error replies for bad input.

use std::collections::VecDeque;
use std::vec::Vec;

use capp_core::kinematics::{forward_kinematics, Frames};
use capp_core::{pips, Mission, Phase, Planner, Robot, Scenario};
use capp_proto::{
    Accumulator, Command, ErrorCode, Joints, Outcome, Reply, State, MAX_FRAME, NO_COMMAND,
};
use embedded_hal_nb::{nb, serial};

use super::*;

mod drive;
mod general;
mod line;

/// A UART that takes at most `budget` bytes per `refill` (a slow line).
struct FakeUart {
    rx: VecDeque<u8>,
    tx: Vec<u8>,
    budget: usize,
    left: usize,
}

impl FakeUart {
    fn new(budget: usize) -> Self {
        FakeUart {
            rx: VecDeque::new(),
            tx: Vec::new(),
            budget,
            left: budget,
        }
    }
    fn send(&mut self, c: &Command) {
        let mut f = [0u8; MAX_FRAME];
        let n = capp_proto::encode(c, &mut f).unwrap();
        self.rx.extend(&f[..n]);
    }
}

impl serial::ErrorType for FakeUart {
    type Error = serial::ErrorKind;
}
impl serial::Read<u8> for FakeUart {
    fn read(&mut self) -> nb::Result<u8, Self::Error> {
        self.rx.pop_front().ok_or(nb::Error::WouldBlock)
    }
}
impl serial::Write<u8> for FakeUart {
    fn write(&mut self, b: u8) -> nb::Result<(), Self::Error> {
        if self.left == 0 {
            return Err(nb::Error::WouldBlock);
        }
        self.left -= 1;
        self.tx.push(b);
        Ok(())
    }
    fn flush(&mut self) -> nb::Result<(), Self::Error> {
        Ok(())
    }
}

fn replies(bytes: &[u8]) -> Vec<Reply> {
    let mut acc = Accumulator::<{ MAX_FRAME - 1 }>::new();
    bytes
        .iter()
        .filter_map(|&b| acc.feed_message::<Reply>(b))
        .map(|r| r.unwrap())
        .collect()
}

/// The frames in `bytes` that decode, skipping damaged ones.
fn replies_lossy(bytes: &[u8]) -> Vec<Reply> {
    let mut acc = Accumulator::<{ MAX_FRAME - 1 }>::new();
    bytes
        .iter()
        .filter_map(|&b| acc.feed_message::<Reply>(b))
        .filter_map(Result::ok)
        .collect()
}

fn target() -> capp_core::Waypoint {
    let robot = pips::robot::<32>().unwrap();
    // Far enough for a plan of about a hundred steps.
    let mut q = pips::home();
    q[0] += 1.0;
    q[5] += 0.6;
    q[9] -= 0.5;
    let mut frames = Frames::<32>::default();
    forward_kinematics(&robot, &q, &mut frames);
    let p = frames.end_position();
    capp_core::Waypoint::at([p.x, p.y, p.z])
}

/// The host's plan: the start, then the joint vector after every step, each
/// with its plan time (the f32 sum of the step sizes, as the board keeps it).
fn host_plan() -> Vec<(Vec<f32>, f32)> {
    host_plan_with(capp_core::Settings::default())
}

/// [`host_plan`] with `settings`.
fn host_plan_with(settings: capp_core::Settings) -> Vec<(Vec<f32>, f32)> {
    let robot = Robot::<32>::new(&pips::joints()).unwrap();
    let mission = Mission::<16>::new(&[target()], settings).unwrap();
    let scenario =
        Scenario::<32, 64, 16>::new(robot, &[] as &[capp_core::Solid], &mission).unwrap();
    let mut planner = Planner::new(&scenario, &pips::home()).unwrap();
    let mut out = std::vec![(planner.joints().to_vec(), 0.0)];
    let mut time_s = 0.0f32;
    loop {
        let r = planner.step(&scenario).unwrap();
        time_s += r.time_step_s;
        out.push((planner.joints().to_vec(), time_s));
        if let Phase::Done(_) = r.phase {
            return out;
        }
    }
}

/// PIPS to [`target`], default settings: what [`host_plan`] plans.
fn load_commands() -> Vec<Command> {
    std::vec![
        Command::Clear(Part::All),
        Command::Preset(Preset::Pips),
        Command::Waypoint {
            index: 0,
            waypoint: target().into(),
        },
    ]
}

/// [`load_commands`] then `settings`: what [`host_plan_with`] plans.
fn load_commands_with(settings: capp_core::Settings) -> Vec<Command> {
    let mut commands = load_commands();
    commands.push(Command::Settings(settings.into()));
    commands
}

/// Settings for a plan of a couple of thousand steps (the first-order
/// gradient law, in quarter steps): long enough for a host to send many
/// commands while it runs.
fn long_plan() -> capp_core::Settings {
    let mut s = capp_core::Settings::default();
    s.law.kind = capp_core::control::LawKind::Gradient;
    s.time_step_s *= 0.25;
    s
}

fn load(uart: &mut FakeUart) {
    for c in load_commands() {
        uart.send(&c);
    }
}

/// Runs a plan with `budget` bytes of UART per tick; returns all replies after `Run`'s ack.
fn run_plan(budget: usize) -> (Vec<Reply>, Vec<(Vec<f32>, f32)>) {
    run_plan_with(
        budget,
        Command::Run {
            every: 1,
            error_change: None,
        },
    )
}

/// [`run_plan`] started by `run`.
fn run_plan_with(budget: usize, run: Command) -> (Vec<Reply>, Vec<(Vec<f32>, f32)>) {
    let mut node = Node::<2048>::new();
    (run_on(&mut node, budget, run), host_plan())
}

/// [`run_plan_with`] on `node`; the replies only.
fn run_on(node: &mut Node<2048>, budget: usize, run: Command) -> Vec<Reply> {
    let mut uart = FakeUart::new(usize::MAX);
    load(&mut uart);
    uart.send(&run);
    node.poll(&mut uart);
    node.poll(&mut uart);
    let acks = replies(&uart.tx);
    assert_eq!(acks.len(), 4);
    assert!(
        acks.iter().all(|r| matches!(r, Reply::Ack { .. })),
        "{acks:?}"
    );
    uart.tx.clear();
    uart.budget = budget;
    for _ in 0..100_000 {
        uart.left = uart.budget;
        node.tick(1);
        node.poll(&mut uart);
        if node.status().state != State::Running && node.tx_len() == 0 {
            break;
        }
    }
    replies(&uart.tx)
}

#[test]
fn a_reset_node_is_a_new_node() {
    let run = || Command::Run {
        every: 1,
        error_change: None,
    };
    let fresh = run_on(&mut Node::new(), usize::MAX, run());
    // A node in some other state: another plan stopped half way, a draft with
    // obstacles and settings, a bad frame counted, replies still queued.
    let mut node = Node::<2048>::new();
    node.set_cycle_counter(|| 7, 1000);
    let mut uart = FakeUart::new(usize::MAX);
    load(&mut uart);
    uart.send(&Command::Settings(capp_core::Settings::default().into()));
    uart.send(&run());
    node.poll(&mut uart);
    for _ in 0..20 {
        node.tick(1);
    }
    uart.send(&Command::Obstacle {
        index: 0,
        obstacle: capp_core::SuperEllipsoid::aligned([500.0; 3], [1.0; 3], 2.0).into(),
    });
    uart.rx.extend([1, 2, 3, 0]);
    uart.budget = 0;
    uart.left = 0;
    node.poll(&mut uart);
    assert!(node.tx_len() > 0 && node.status().rx_errors == 1);
    node.reset();
    assert_eq!(node.status(), Node::<2048>::new().status());
    assert_eq!(node.tx_len(), 0);
    assert_eq!(run_on(&mut node, usize::MAX, run()), fresh);
}

#[test]
fn a_fast_uart_gets_every_setpoint_bit_for_bit() {
    let (replies, plan) = run_plan(usize::MAX);
    let (last, setpoints) = replies.split_last().unwrap();
    assert_eq!(setpoints.len(), plan.len());
    for (i, r) in setpoints.iter().enumerate() {
        let Reply::Setpoint {
            seq,
            step,
            joints,
            time_s,
            waypoint,
            ..
        } = r
        else {
            panic!("{r:?}")
        };
        assert_eq!((*seq, *step, *waypoint), (i as u32, i as u32, 0));
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(joints), bits(&plan[i].0));
        assert_eq!(time_s.to_bits(), plan[i].1.to_bits());
    }
    let Reply::Status(s) = last else { panic!() };
    assert_eq!((s.state, s.outcome), (State::Done, Some(Outcome::Reached)));
    assert_eq!((s.setpoints, s.dropped), (plan.len() as u32, 0));
}

#[test]
fn the_listing_rule_streams_what_the_host_decimator_picks() {
    let listing = capp_core::SetpointFilter::LISTING;
    let (replies, _) = run_plan_with(usize::MAX, capp_proto::run_command(listing));
    // The host: the same plan through capp-core's decimator.
    let robot = Robot::<32>::new(&pips::joints()).unwrap();
    let mission = Mission::<16>::new(&[target()], capp_core::Settings::default()).unwrap();
    let scenario =
        Scenario::<32, 64, 16>::new(robot, &[] as &[capp_core::Solid], &mission).unwrap();
    let mut planner = Planner::new(&scenario, &pips::home()).unwrap();
    let mut decimator = capp_core::setpoint::Decimator::new(listing);
    let mut expected = Vec::new();
    let mut report = *planner.last_report();
    loop {
        if decimator.offer(&report) {
            expected.push((report.step, planner.joints().to_vec()));
        }
        if let Phase::Done(_) = report.phase {
            break;
        }
        report = planner.step(&scenario).unwrap();
    }
    let received: Vec<(u32, Vec<f32>)> = replies
        .iter()
        .filter_map(|r| match r {
            Reply::Setpoint { step, joints, .. } => Some((*step, joints.to_vec())),
            _ => None,
        })
        .collect();
    // The decimation dropped steps, and kept more than the start and end.
    assert!(
        expected.len() > 3 && expected.len() < report.step as usize,
        "{} of {}",
        expected.len(),
        report.step
    );
    assert_eq!(received, expected);
}

#[test]
fn a_slow_uart_shows_gaps_that_the_status_counts() {
    // ~20 bytes per tick: a fraction of one setpoint frame (~90 bytes) per step.
    let (replies, plan) = run_plan(20);
    let (last, setpoints) = replies.split_last().unwrap();
    let Reply::Status(s) = last else {
        panic!("{last:?}")
    };
    assert_eq!((s.state, s.outcome), (State::Done, Some(Outcome::Reached)));
    assert_eq!(s.setpoints, plan.len() as u32);
    assert!(s.dropped > 0);
    let mut seen = std::vec![false; plan.len()];
    let mut previous = None;
    for r in setpoints {
        let Reply::Setpoint {
            seq, step, joints, ..
        } = r
        else {
            panic!("{r:?}")
        };
        assert!(previous.is_none_or(|p| *seq > p), "in order");
        previous = Some(*seq);
        seen[*seq as usize] = true;
        assert_eq!(*step, *seq);
        assert_eq!(joints.as_slice(), plan[*seq as usize].0.as_slice());
    }
    let missing = seen.iter().filter(|s| !**s).count() as u32;
    assert_eq!(missing, s.dropped, "every gap is a counted drop");
}

fn exchange(node: &mut Node<2048>, uart: &mut FakeUart) -> Vec<Reply> {
    uart.tx.clear();
    for _ in 0..4 {
        node.poll(uart);
    }
    replies(&uart.tx)
}

#[test]
fn bad_commands_get_errors_and_change_nothing() {
    let mut node = Node::<2048>::new();
    let mut uart = FakeUart::new(usize::MAX);
    load(&mut uart);
    uart.send(&Command::Run {
        every: 1,
        error_change: None,
    });
    exchange(&mut node, &mut uart);
    while node.status().state == State::Running {
        node.tick(1);
    }
    let done = *node.status();
    exchange(&mut node, &mut uart);

    // A corrupted frame, then garbage longer than the buffer.
    let mut f = [0u8; MAX_FRAME];
    let n = capp_proto::encode(&Command::Status, &mut f).unwrap();
    f[n - 2] = f[n - 2].wrapping_add(1).max(1);
    uart.rx.extend(&f[..n]);
    uart.rx.extend(std::iter::repeat_n(7u8, 600));
    uart.rx.push_back(0);
    let mut nan: capp_proto::Joint = pips::joints()[0].into();
    nan.weight = f32::NAN;
    uart.send(&Command::Joint {
        index: 0,
        joint: nan,
    });
    uart.send(&Command::Obstacle {
        index: 5,
        obstacle: capp_core::SuperEllipsoid::aligned([0.0; 3], [1.0; 3], 2.0).into(),
    });
    uart.send(&Command::Start(
        Joints::from_slice(&[f32::INFINITY]).unwrap(),
    ));
    uart.send(&Command::Stop);
    // A start outside the limits: Run is refused, the last plan stays.
    let mut q = pips::home();
    q[2] = 1000.0;
    uart.send(&Command::Start(Joints::from_slice(&q).unwrap()));
    uart.send(&Command::Run {
        every: 1,
        error_change: None,
    });
    let got = exchange(&mut node, &mut uart);
    let errors: Vec<_> = got
        .iter()
        .map(|r| match r {
            Reply::Error {
                command,
                code,
                index,
            } => (*command, *code, *index),
            Reply::Ack { command } => (*command, ErrorCode::Framing, 0xAA),
            other => panic!("{other:?}"),
        })
        .collect();
    assert_eq!(
        errors,
        [
            (NO_COMMAND, ErrorCode::Crc, NO_INDEX),
            (NO_COMMAND, ErrorCode::Overfull, NO_INDEX),
            (3, ErrorCode::NotFinite, 0),
            (4, ErrorCode::OutOfOrder, 5),
            (7, ErrorCode::NotFinite, 0),
            (9, ErrorCode::NotRunning, NO_INDEX),
            (7, ErrorCode::Framing, 0xAA), // the ack of the (finite) start
            (8, ErrorCode::InvalidStart, 2),
        ]
    );
    let after = *node.status();
    assert_eq!(after.rx_errors, done.rx_errors + 2);
    assert_eq!(
        Status {
            rx_errors: done.rx_errors,
            ..after
        },
        done
    );

    // And the next valid plan runs.
    uart.send(&Command::Start(Joints::from_slice(&pips::home()).unwrap()));
    uart.send(&Command::Run {
        every: 1,
        error_change: None,
    });
    let got = exchange(&mut node, &mut uart);
    assert_eq!(got, [Reply::Ack { command: 7 }, Reply::Ack { command: 8 }]);
    assert_eq!(node.status().state, State::Running);
    // Run while running is refused; Stop acks and sends the final status.
    node.tick(1);
    uart.send(&Command::Run {
        every: 1,
        error_change: None,
    });
    uart.send(&Command::Stop);
    let got = exchange(&mut node, &mut uart);
    let tail: Vec<_> = got
        .iter()
        .filter(|r| !matches!(r, Reply::Setpoint { .. }))
        .collect();
    assert!(matches!(
        tail[0],
        Reply::Error {
            command: 8,
            code: ErrorCode::Busy,
            ..
        }
    ));
    assert_eq!(tail[1], &Reply::Ack { command: 9 });
    let Reply::Status(s) = tail[2] else { panic!() };
    assert_eq!((s.state, s.step), (State::Stopped, 1));
}

#[test]
fn replies_are_never_dropped_when_the_uart_stalls() {
    // The UART takes nothing: the node stops reading once its reserve is used,
    // so no command goes unanswered.
    let mut node = Node::<{ RESERVE + 64 }>::new();
    let mut uart = FakeUart::new(0);
    for i in 0..50 {
        uart.send(&Command::Ping { nonce: i });
    }
    for _ in 0..10 {
        node.poll(&mut uart);
    }
    assert!(!uart.rx.is_empty(), "the node stopped reading");
    uart.budget = usize::MAX;
    for _ in 0..200 {
        uart.left = usize::MAX;
        node.poll(&mut uart);
    }
    let got = replies(&uart.tx);
    assert_eq!(got.len(), 50);
    for (i, r) in got.iter().enumerate() {
        assert!(matches!(r, Reply::Pong { nonce, .. } if *nonce == i as u32));
    }
}

#[test]
fn a_joint_space_waypoint_is_planned_as_the_host_plans_it() {
    // PIPS to a joint configuration as the target: the stream is the host's
    // plan to the same configuration, bit for bit, and ends there.
    let joints = pips::joints();
    let mut goal = pips::home();
    goal[0] += 0.6;
    goal[7] -= 0.4;
    goal[3] += 5.0;
    let mut uart = FakeUart::new(usize::MAX);
    for c in [
        Command::Clear(Part::All),
        Command::Preset(Preset::Pips),
        Command::JointWaypoint {
            index: 0,
            joints: Joints::from_slice(&goal).unwrap(),
        },
        Command::Run {
            every: 1,
            error_change: None,
        },
    ] {
        uart.send(&c);
    }
    let mut node = Node::<2048>::new();
    for _ in 0..4 {
        node.poll(&mut uart);
    }
    assert!(replies(&uart.tx)
        .iter()
        .all(|r| matches!(r, Reply::Ack { .. })));
    uart.tx.clear();
    for _ in 0..100_000 {
        node.tick(1);
        node.poll(&mut uart);
        if node.status().state != State::Running && node.tx_len() == 0 {
            break;
        }
    }
    let streamed: Vec<Vec<f32>> = replies(&uart.tx)
        .into_iter()
        .filter_map(|r| match r {
            Reply::Setpoint { joints, .. } => Some(joints.to_vec()),
            _ => None,
        })
        .collect();
    // The host.
    let robot = Robot::<32>::new(&joints).unwrap();
    let mission = Mission::<16>::new(
        &[capp_core::Waypoint::at([0.0; 3])],
        capp_core::Settings::default(),
    )
    .unwrap();
    let mut scenario =
        Scenario::<32, 64, 16>::new(robot, &[] as &[capp_core::Solid], &mission).unwrap();
    scenario.set_joint_goal(0, &goal).unwrap();
    let mut planner = Planner::new(&scenario, &pips::home()).unwrap();
    let mut expected = std::vec![planner.joints().to_vec()];
    let outcome = planner
        .run(&scenario, |p, _| expected.push(p.joints().to_vec()))
        .unwrap();
    assert_eq!(outcome, capp_core::Outcome::Reached);
    assert_eq!(node.status().outcome, Some(Outcome::Reached));
    let bits = |v: &Vec<Vec<f32>>| {
        v.iter()
            .map(|q| q.iter().map(|x| x.to_bits()).collect::<Vec<_>>())
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(&streamed), bits(&expected));
    // A fifth joint waypoint does not fit.
    let mut uart = FakeUart::new(usize::MAX);
    uart.send(&Command::Clear(Part::All));
    uart.send(&Command::Preset(Preset::Pips));
    for i in 0..5u8 {
        uart.send(&Command::JointWaypoint {
            index: i,
            joints: Joints::from_slice(&goal).unwrap(),
        });
    }
    let mut node = Node::<2048>::new();
    for _ in 0..8 {
        node.poll(&mut uart);
    }
    let r = replies(&uart.tx);
    assert!(
        matches!(
            r.last(),
            Some(Reply::Error {
                code: ErrorCode::Capacity,
                ..
            })
        ),
        "{r:?}"
    );
}

/// PIPS's link capsules as the host computes them (`capp run`'s defaults:
/// radius 1.5 in, the preset's allowed pairs, the pair table's seed 1).
fn pips_capsules() -> (Vec<f32>, Vec<u64>) {
    use capp_core::self_collision::pairs::{PairTable, SAMPLES};
    let robot = pips::robot::<32>().unwrap();
    let radius = std::vec![pips::LINK_RADIUS; pips::JOINTS];
    let allowed: Vec<(u8, u8)> = pips::allowed_pairs().collect();
    let table = PairTable::new(&robot, &radius, &allowed, &pips::home(), SAMPLES, 1).unwrap();
    (radius, table.checked_rows().to_vec())
}

fn capsule_commands(radius: &[f32], rows: &[u64]) -> Vec<Command> {
    radius
        .iter()
        .zip(rows)
        .enumerate()
        .map(|(i, (&radius, &checked))| Command::Capsule {
            index: i as u8,
            capsule: capp_proto::Capsule {
                radius,
                checked,
                segment: None,
            },
        })
        .collect()
}

/// `(command, code, index)` of each reply; an ack as `(command, Framing, 0xAA)`.
fn outcomes(got: &[Reply]) -> Vec<(u8, ErrorCode, u8)> {
    got.iter()
        .filter(|r| !matches!(r, Reply::Setpoint { .. } | Reply::Status(_)))
        .map(|r| match r {
            Reply::Error {
                command,
                code,
                index,
            } => (*command, *code, *index),
            Reply::Ack { command } => (*command, ErrorCode::Framing, 0xAA),
            other => panic!("{other:?}"),
        })
        .collect()
}

#[test]
fn link_capsules_reach_the_boards_scenario_bit_for_bit() {
    // PIPS with its capsules and checked pairs: the board's scenario holds
    // the host's radii and rows to the bit, and plans the host's plan.
    let (radius, rows) = pips_capsules();
    assert!(rows.iter().any(|r| *r != 0));
    let mut uart = FakeUart::new(usize::MAX);
    for c in load_commands()
        .into_iter()
        .chain(capsule_commands(&radius, &rows))
    {
        uart.send(&c);
    }
    uart.send(&Command::Run {
        every: 1,
        error_change: None,
    });
    let mut node = Node::<2048>::new();
    let got = exchange(&mut node, &mut uart);
    assert!(
        outcomes(&got).iter().all(|o| o.1 == ErrorCode::Framing),
        "{got:?}"
    );
    let capsules = node.plan.scenario.capsules();
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(capsules.radii()), bits(&radius));
    assert_eq!(capsules.checked_rows(), rows.as_slice());
    // The host's plan with the same capsules.
    let robot = Robot::<32>::new(&pips::joints()).unwrap();
    let mission = Mission::<16>::new(&[target()], capp_core::Settings::default()).unwrap();
    let mut scenario =
        Scenario::<32, 64, 16>::new(robot, &[] as &[capp_core::Solid], &mission).unwrap();
    scenario.set_link_capsules(&radius, &rows).unwrap();
    let mut planner = Planner::new(&scenario, &pips::home()).unwrap();
    let mut expected = std::vec![planner.joints().to_vec()];
    planner
        .run(&scenario, |p, _| expected.push(p.joints().to_vec()))
        .unwrap();
    uart.tx.clear();
    for _ in 0..100_000 {
        node.tick(1);
        node.poll(&mut uart);
        if node.status().state != State::Running && node.tx_len() == 0 {
            break;
        }
    }
    let streamed: Vec<Vec<u32>> = replies(&uart.tx)
        .into_iter()
        .filter_map(|r| match r {
            Reply::Setpoint { joints, .. } => Some(bits(&joints)),
            _ => None,
        })
        .collect();
    let expected: Vec<Vec<u32>> = expected.iter().map(|q| bits(q)).collect();
    assert_eq!(streamed, expected);
    assert_eq!(node.status().outcome, Some(Outcome::Reached));

    // Clear(Capsules): the next plan checks no pairs; capsules sent again do.
    uart.send(&Command::Clear(Part::Capsules));
    uart.send(&Command::Run {
        every: 1,
        error_change: None,
    });
    let got = exchange(&mut node, &mut uart);
    assert_eq!(
        outcomes(&got),
        [(1, ErrorCode::Framing, 0xAA), (8, ErrorCode::Framing, 0xAA)]
    );
    assert!(!node.plan.scenario.capsules().is_on());
    uart.send(&Command::Stop);
    for c in capsule_commands(&radius, &rows) {
        uart.send(&c);
    }
    // The preset replaces the robot: its old capsules go with it.
    uart.send(&Command::Preset(Preset::Pips));
    uart.send(&Command::Run {
        every: 1,
        error_change: None,
    });
    exchange(&mut node, &mut uart);
    assert_eq!(node.status().state, State::Running);
    assert!(!node.plan.scenario.capsules().is_on());
}

#[test]
fn bad_link_capsules_are_refused_with_the_link() {
    let (radius, rows) = pips_capsules();
    let mut node = Node::<2048>::new();
    let mut uart = FakeUart::new(usize::MAX);
    // A good plan first: refusals leave its status as it is.
    load(&mut uart);
    uart.send(&Command::Run {
        every: 1,
        error_change: None,
    });
    exchange(&mut node, &mut uart);
    while node.status().state == State::Running {
        node.tick(1);
    }
    exchange(&mut node, &mut uart);
    let done = *node.status();
    let run = Command::Run {
        every: 1,
        error_change: None,
    };
    let capsule = |index: u8, radius: f32, checked: u64| Command::Capsule {
        index,
        capsule: capp_proto::Capsule {
            radius,
            checked,
            segment: None,
        },
    };
    // On arrival: a radius that is not a number, a capsule out of order.
    uart.send(&capsule(0, f32::NAN, rows[0]));
    uart.send(&capsule(1, 1.5, rows[1]));
    assert_eq!(
        outcomes(&exchange(&mut node, &mut uart)),
        [
            (12, ErrorCode::NotFinite, 0),
            (12, ErrorCode::OutOfOrder, 1)
        ]
    );
    // At `Run`, against the robot: link 4's radius 0, negative, too large;
    // link 6 naming itself, a link before it, a link PIPS does not have.
    let refused = |bad: Command, node: &mut Node<2048>, uart: &mut FakeUart| {
        uart.send(&Command::Clear(Part::Capsules));
        let mut commands = capsule_commands(&radius, &rows);
        let Command::Capsule { index, .. } = bad else {
            panic!()
        };
        commands[index as usize] = bad;
        for c in &commands {
            uart.send(c);
        }
        uart.send(&run);
        let got = outcomes(&exchange(node, uart));
        assert!(got[..got.len() - 1]
            .iter()
            .all(|o| o.1 == ErrorCode::Framing));
        got[got.len() - 1]
    };
    let radius4 = [0.0, -1.5, 2.0e4];
    for r in radius4 {
        assert_eq!(
            refused(capsule(4, r, rows[4]), &mut node, &mut uart),
            (8, ErrorCode::InvalidCapsules, 4),
            "radius {r}"
        );
    }
    for row in [rows[6] | 1 << 6, rows[6] | 1 << 2, rows[6] | 1 << 18] {
        assert_eq!(
            refused(capsule(6, 1.5, row), &mut node, &mut uart),
            (8, ErrorCode::InvalidCapsules, 6),
            "row {row:#x}"
        );
    }
    // Not one capsule per joint.
    uart.send(&Command::Clear(Part::Capsules));
    for c in capsule_commands(&radius[..17], &rows[..17]) {
        uart.send(&c);
    }
    uart.send(&run);
    let got = outcomes(&exchange(&mut node, &mut uart));
    assert_eq!(got.last(), Some(&(8, ErrorCode::InvalidCapsules, NO_INDEX)));
    // Segments for a DH robot, and one capsule round a segment among
    // chords: the load as a whole.
    let segment = Some([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]);
    for every in [true, false] {
        uart.send(&Command::Clear(Part::Capsules));
        for (i, mut c) in capsule_commands(&radius, &rows).into_iter().enumerate() {
            if let Command::Capsule { capsule, .. } = &mut c {
                if every || i == 3 {
                    capsule.segment = segment;
                }
            }
            uart.send(&c);
        }
        uart.send(&run);
        let got = outcomes(&exchange(&mut node, &mut uart));
        assert_eq!(
            got.last(),
            Some(&(8, ErrorCode::InvalidCapsules, NO_INDEX)),
            "every capsule with a segment: {every}"
        );
    }
    // A 33rd capsule does not fit.
    uart.send(&Command::Clear(Part::Capsules));
    for i in 0..33u8 {
        uart.send(&capsule(i, 1.5, 0));
    }
    let got = outcomes(&exchange(&mut node, &mut uart));
    assert_eq!(got.last(), Some(&(12, ErrorCode::Capacity, 32)));
    // Nothing changed the last plan's status.
    assert_eq!(
        Status {
            rx_errors: done.rx_errors,
            ..*node.status()
        },
        done
    );
    // And the good capsules run.
    uart.send(&Command::Clear(Part::Capsules));
    for c in capsule_commands(&radius, &rows) {
        uart.send(&c);
    }
    uart.send(&run);
    let got = outcomes(&exchange(&mut node, &mut uart));
    assert_eq!(got.last(), Some(&(8, ErrorCode::Framing, 0xAA)));
    assert_eq!(node.status().state, State::Running);
}

#[test]
fn a_start_in_self_collision_is_refused() {
    // A planar arm of three 1 m links folded so that its first and last
    // links cross: with their pair checked, `Run` is refused; with no
    // capsules the same start runs.
    let joint = capp_proto::Joint {
        kind: capp_proto::JointKind::Revolute,
        alpha: 0.0,
        a: 1.0,
        theta: 0.0,
        d: 0.0,
        min: -3.1,
        max: 3.1,
        max_rate: 1.0,
        weight: 1.0,
        origin: None,
    };
    let start = [0.0, 2.9, 2.9];
    let robot = Robot::<32>::new(&[capp_core::Joint::from(joint); 3]).unwrap();
    let mission = Mission::<16>::new(
        &[capp_core::Waypoint::at([1.0, 1.0, 0.0])],
        capp_core::Settings::for_robot(&robot),
    )
    .unwrap();
    let mut scenario =
        Scenario::<32, 64, 16>::new(robot, &[] as &[capp_core::Solid], &mission).unwrap();
    scenario
        .set_link_capsules(&[0.1; 3], &[1 << 2, 0, 0])
        .unwrap();
    assert!(matches!(
        Planner::new(&scenario, &start),
        Err(capp_core::StartError::SelfCollision { links: [0, 2] })
    ));
    let mut uart = FakeUart::new(usize::MAX);
    let mut commands = std::vec![Command::Clear(Part::All)];
    for i in 0..3 {
        commands.push(Command::Joint { index: i, joint });
    }
    commands.extend(capsule_commands(&[0.1; 3], &[1 << 2, 0, 0]));
    commands.push(Command::Waypoint {
        index: 0,
        waypoint: capp_core::Waypoint::at([1.0, 1.0, 0.0]).into(),
    });
    commands.push(Command::Settings((*scenario.settings()).into()));
    commands.push(Command::Start(Joints::from_slice(&start).unwrap()));
    commands.push(Command::Run {
        every: 1,
        error_change: None,
    });
    for c in &commands {
        uart.send(c);
    }
    let mut node = Node::<2048>::new();
    let got = outcomes(&exchange(&mut node, &mut uart));
    assert_eq!(got.last(), Some(&(8, ErrorCode::InvalidStart, NO_INDEX)));
    uart.send(&Command::Clear(Part::Capsules));
    uart.send(&Command::Run {
        every: 1,
        error_change: None,
    });
    let got = outcomes(&exchange(&mut node, &mut uart));
    assert_eq!(got.last(), Some(&(8, ErrorCode::Framing, 0xAA)));
}

#[test]
fn a_bad_primitive_is_refused_with_its_index() {
    // Protocol 10's primitives: a sphere of radius 0 is stored as sent and
    // refused at `Run` by the core's validation, naming the obstacle; a
    // good box in its place plans.
    let mut node = Node::<2048>::new();
    let mut uart = FakeUart::new(usize::MAX);
    load(&mut uart);
    uart.send(&Command::Clear(Part::Obstacles));
    let solid = |centre: [f32; 3], shape| -> capp_proto::Obstacle {
        capp_core::Solid::aligned(centre, shape).into()
    };
    uart.send(&Command::Obstacle {
        index: 0,
        obstacle: solid(
            [500.0; 3],
            capp_core::Shape::Cuboid {
                half_extents: [1.0, 2.0, 3.0],
            },
        ),
    });
    uart.send(&Command::Obstacle {
        index: 1,
        obstacle: solid([400.0; 3], capp_core::Shape::Sphere { radius: 0.0 }),
    });
    uart.send(&Command::Run {
        every: 1,
        error_change: None,
    });
    let got = exchange(&mut node, &mut uart);
    assert_eq!(
        got.last(),
        Some(&Reply::Error {
            command: 8,
            code: ErrorCode::InvalidObstacle,
            index: 1,
        })
    );
    assert_ne!(node.status().state, State::Running);
    // The same with the sphere's radius fixed.
    uart.send(&Command::Clear(Part::Obstacles));
    uart.send(&Command::Obstacle {
        index: 0,
        obstacle: solid([400.0; 3], capp_core::Shape::Sphere { radius: 2.0 }),
    });
    uart.send(&Command::Run {
        every: 1,
        error_change: None,
    });
    let got = exchange(&mut node, &mut uart);
    assert_eq!(got.last(), Some(&Reply::Ack { command: 8 }));
    assert_eq!(node.status().state, State::Running);
}

#[test]
fn hulls_are_loaded_checked_and_cleared_with_the_obstacles() {
    // Protocol 11: a hull is sent by `Hull` and named by a convex obstacle.
    // A flat hull is refused at `Run` naming the hull; a convex obstacle
    // naming a hull never sent, naming the obstacle; `Clear(Obstacles)`
    // empties the hulls too; a good hull plans.
    let mut node = Node::<2048>::new();
    let mut uart = FakeUart::new(usize::MAX);
    load(&mut uart);
    uart.send(&Command::Clear(Part::Obstacles));
    let vertices = |z: f32| {
        capp_proto::HullVertices::from_slice(&[
            [0.0, 0.0, 0.0],
            [3.0, 0.0, 0.0],
            [0.0, 3.0, 0.0],
            [0.0, 0.0, z],
        ])
        .unwrap()
    };
    let convex = |hull| -> capp_proto::Obstacle {
        capp_core::Solid::aligned([400.0; 3], capp_core::Shape::Convex { hull }).into()
    };
    let run = Command::Run {
        every: 1,
        error_change: None,
    };
    uart.send(&Command::Hull {
        index: 0,
        vertices: vertices(3.0),
    });
    uart.send(&Command::Hull {
        index: 1,
        vertices: vertices(0.0),
    });
    uart.send(&Command::Obstacle {
        index: 0,
        obstacle: convex(0),
    });
    uart.send(&run);
    assert_eq!(
        outcomes(&exchange(&mut node, &mut uart)).last(),
        Some(&(8, ErrorCode::InvalidHull, 1))
    );
    // Out of order: hull 3 while two are loaded.
    uart.send(&Command::Hull {
        index: 3,
        vertices: vertices(3.0),
    });
    assert_eq!(
        outcomes(&exchange(&mut node, &mut uart)).last(),
        Some(&(15, ErrorCode::OutOfOrder, 3))
    );
    uart.send(&Command::Clear(Part::Obstacles));
    uart.send(&Command::Obstacle {
        index: 0,
        obstacle: convex(0),
    });
    uart.send(&run);
    assert_eq!(
        outcomes(&exchange(&mut node, &mut uart)).last(),
        Some(&(8, ErrorCode::InvalidObstacle, 0))
    );
    uart.send(&Command::Hull {
        index: 0,
        vertices: vertices(3.0),
    });
    uart.send(&run);
    let got = exchange(&mut node, &mut uart);
    assert_eq!(got.last(), Some(&Reply::Ack { command: 8 }));
    assert_eq!(node.status().state, State::Running);
}
