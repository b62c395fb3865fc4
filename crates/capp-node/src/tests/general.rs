//! General (URDF) joints and the tool (protocol 9): a joint's origin and
//! axis and the robot's tool reach the board's robot bit for bit (capp-core's
//! `Robot::new_with_tool`, as the host builds it), the board plans the
//! host's plan, and bad origins and tools are refused with an error reply.

use std::vec::Vec;

use capp_core::robot::{general_from_dh, JointOrigin, Placement};
use capp_core::{pips, Mission, Phase, Planner, Robot, Scenario};
use capp_proto::{Command, ErrorCode, Joints, Part, Reply, State, NO_INDEX};

use super::{exchange, outcomes, replies, target, FakeUart};
use crate::Node;

fn bits(v: &[f32]) -> Vec<u32> {
    v.iter().map(|x| x.to_bits()).collect()
}

/// PIPS as general joints (every axis `z`, each origin the previous row's
/// fixed part) and its tool, the last row's.
fn general_pips() -> (Vec<capp_core::Joint>, Placement) {
    let dh = pips::joints();
    let mut joints = dh;
    let tool = general_from_dh(&dh, &mut joints);
    (joints.to_vec(), tool)
}

/// The upload of a robot with `tool` (sent when it is not the identity),
/// PIPS's home as the start and [`target`] as the waypoint.
fn load(joints: &[capp_core::Joint], tool: &Placement) -> Vec<Command> {
    let mut commands = std::vec![Command::Clear(Part::All)];
    for (i, j) in joints.iter().enumerate() {
        commands.push(Command::Joint {
            index: i as u8,
            joint: (*j).into(),
        });
    }
    if !tool.is_identity() {
        commands.push(Command::Tool((*tool).into()));
    }
    commands.push(Command::Waypoint {
        index: 0,
        waypoint: target().into(),
    });
    commands.push(Command::Start(
        Joints::from_slice(&pips::home()[..joints.len()]).unwrap(),
    ));
    commands
}

const RUN: Command = Command::Run {
    every: 1,
    error_change: None,
};

#[test]
fn a_general_robot_with_a_tool_plans_the_hosts_plan_bit_for_bit() {
    let (joints, tool) = general_pips();
    assert!(joints.iter().all(|j| j.origin.is_some()));
    assert!(!tool.is_identity());
    let mut uart = FakeUart::new(usize::MAX);
    for c in load(&joints, &tool) {
        uart.send(&c);
    }
    uart.send(&RUN);
    let mut node = Node::<2048>::new();
    let got = exchange(&mut node, &mut uart);
    assert!(
        outcomes(&got).iter().all(|o| o.1 == ErrorCode::Framing),
        "all acks: {got:?}"
    );
    let robot = node.plan.scenario.robot();
    assert!(robot.is_general());
    assert_eq!(robot.tool(), &tool);
    assert_eq!(robot.joints(), joints.as_slice());

    // The host's plan: the same robot, built as the host builds it.
    let host = Robot::<32>::new_with_tool(&joints, &tool).unwrap();
    let mission = Mission::<16>::new(&[target()], capp_core::Settings::default()).unwrap();
    let scenario = Scenario::<32, 64, 16>::new(host, &[] as &[capp_core::Solid], &mission).unwrap();
    let mut planner = Planner::new(&scenario, &pips::home()).unwrap();
    let mut expected = std::vec![bits(planner.joints())];
    loop {
        let r = planner.step(&scenario).unwrap();
        expected.push(bits(planner.joints()));
        if let Phase::Done(_) = r.phase {
            break;
        }
    }
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
    assert!(expected.len() > 10, "{} steps", expected.len());
    assert_eq!(streamed, expected);
    assert_eq!(node.status().state, State::Done);

    // Clear(Robot) forgets the tool: DH rows after it make a robot without one.
    uart.send(&Command::Clear(Part::Robot));
    for (i, j) in pips::joints().iter().enumerate() {
        uart.send(&Command::Joint {
            index: i as u8,
            joint: (*j).into(),
        });
    }
    uart.send(&Command::Start(Joints::from_slice(&pips::home()).unwrap()));
    uart.send(&RUN);
    let got = exchange(&mut node, &mut uart);
    assert!(
        outcomes(&got).iter().all(|o| o.1 == ErrorCode::Framing),
        "all acks: {got:?}"
    );
    let robot = node.plan.scenario.robot();
    assert!(!robot.is_general());
    assert!(robot.tool().is_identity());
}

#[test]
fn bad_origins_and_tools_are_refused() {
    let (joints, tool) = general_pips();
    let mut node = Node::<2048>::new();
    let mut uart = FakeUart::new(usize::MAX);
    for c in load(&joints, &tool) {
        uart.send(&c);
    }
    exchange(&mut node, &mut uart);

    // Non-finite values are refused on arrival: an origin's (the joint) and
    // the tool's (no index).
    let mut nan = joints[0];
    let mut origin: JointOrigin = nan.origin.unwrap();
    origin.axis[1] = f32::NAN;
    nan.origin = Some(origin);
    uart.send(&Command::Clear(Part::Robot));
    uart.send(&Command::Joint {
        index: 0,
        joint: nan.into(),
    });
    let mut bad_tool = tool;
    bad_tool.translation[2] = f32::INFINITY;
    uart.send(&Command::Tool(bad_tool.into()));
    let got = exchange(&mut node, &mut uart);
    assert_eq!(
        outcomes(&got),
        [
            (1, ErrorCode::Framing, 0xAA),
            (3, ErrorCode::NotFinite, 0),
            (14, ErrorCode::NotFinite, NO_INDEX),
        ]
    );

    // Validated by `Run` (capp-core's robot checks): a tool that is no
    // rotation (`NO_INDEX`: capp-core's TOOL), an origin that is none (the
    // joint), a zero axis (the joint), DH rows mixed with general joints
    // (the first joint that differs).
    let mut skewed = tool;
    skewed.rotation[0][0] = 2.0;
    let mut not_rotation = joints.clone();
    if let Some(o) = not_rotation[4].origin.as_mut() {
        o.placement.rotation[1] = [0.0, 0.0, 0.0];
    }
    let mut zero_axis = joints.clone();
    if let Some(o) = zero_axis[7].origin.as_mut() {
        o.axis = [0.0; 3];
    }
    let mut mixed = joints.clone();
    mixed[2] = pips::joints()[2];
    let cases: [(Vec<capp_core::Joint>, Placement, u8); 4] = [
        (joints.clone(), skewed, NO_INDEX),
        (not_rotation, tool, 4),
        (zero_axis, tool, 7),
        (mixed, tool, 2),
    ];
    for (chain, t, index) in cases {
        for c in load(&chain, &t) {
            uart.send(&c);
        }
        uart.send(&RUN);
        let got = exchange(&mut node, &mut uart);
        let last = *outcomes(&got).last().unwrap();
        assert_eq!(last, (8, ErrorCode::InvalidRobot, index), "{got:?}");
        assert_eq!(node.status().state, State::Idle);
    }
}
