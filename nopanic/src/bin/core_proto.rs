//! Everything of capp-core and capp-proto that the firmware calls, on values
//! the optimiser cannot see (`black_box`): robot, scenario and planner
//! construction, `step` until done, the receive accumulator, `decode` of
//! commands and `encode` of replies.
#![no_std]
#![no_main]

use capp_nopanic as _;

use capp_core::obstacle::{MAX_HULLS, MAX_HULL_VERTICES};
use capp_core::robot::Placement;
use capp_core::{
    Joint, Mission, Planner, Robot, Scenario, Settings, Solid, SuperEllipsoid, Waypoint,
};
use capp_proto::{Accumulator, Command, Reply, MAX_FRAME};
use core::hint::black_box;

const N: usize = capp_proto::MAX_JOINTS;
const M: usize = capp_proto::MAX_OBSTACLES;
const W: usize = capp_proto::MAX_WAYPOINTS;

fn plan() {
    let joints: [Joint; N] = black_box([capp_core::pips::joints()[0]; N]);
    let n = black_box(N);
    // Every shape is data the optimiser cannot see: each one's code is linked.
    let obstacles: [Solid; M] =
        black_box([Solid::from(SuperEllipsoid::aligned([0.0; 3], [1.0; 3], 2.0)); M]);
    let waypoints: [Waypoint; W] = black_box([Waypoint::at([1.0; 3]); W]);
    let settings: Settings = black_box(Settings::default());
    let start: [f32; N] = black_box([0.0; N]);
    // Counts the optimiser cannot see, as from a decoded command.
    let (m, w) = (black_box(M), black_box(W));
    let (Some(joints), Some(start), Some(obstacles), Some(waypoints)) = (
        joints.get(..n),
        start.get(..n),
        obstacles.get(..m),
        waypoints.get(..w),
    ) else {
        return;
    };
    let Ok(robot) = Robot::<N>::new(joints) else {
        return;
    };
    let Ok(mission) = Mission::<W>::new(waypoints, settings) else {
        return;
    };
    let Ok(scenario) = Scenario::<N, M, W>::new(robot, obstacles, &mission) else {
        return;
    };
    // In place with hulls, as the board builds it: the hulls' checks and
    // GJK are linked too.
    let vertices: [[f32; 3]; MAX_HULL_VERTICES] = black_box([[1.0; 3]; MAX_HULL_VERTICES]);
    let (h, v) = (black_box(MAX_HULLS), black_box(MAX_HULL_VERTICES));
    let Some(hull) = vertices.get(..v) else {
        return;
    };
    let hulls: [&[[f32; 3]]; MAX_HULLS] = [hull; MAX_HULLS];
    let Some(hulls) = hulls.get(..h) else {
        return;
    };
    let mut in_place = Scenario::<N, M, W>::empty();
    if in_place
        .init_with_hulls(
            joints,
            &Placement::IDENTITY,
            obstacles,
            hulls,
            waypoints,
            settings,
        )
        .is_ok()
    {
        run(&in_place, start);
    }
    run(&scenario, start);
}

fn run(scenario: &Scenario<N, M, W>, start: &[f32]) {
    let Ok(mut planner) = Planner::new(scenario, start) else {
        return;
    };
    while let Ok(report) = planner.step(scenario) {
        black_box(&report);
        black_box(planner.joints());
        if planner.is_done() {
            break;
        }
    }
}

fn protocol() {
    let mut rx = Accumulator::<{ MAX_FRAME - 1 }>::new();
    loop {
        match rx.feed_message::<Command>(black_box(0)) {
            Some(Ok(command)) => {
                black_box(&command);
                let mut out = [0u8; MAX_FRAME];
                let reply = Reply::Ack {
                    command: command.code(),
                };
                if let Ok(n) = capp_proto::encode(&reply, &mut out) {
                    black_box(out.get(..n));
                }
            }
            Some(Err(e)) => {
                black_box(e);
            }
            None => {}
        }
        if black_box(false) {
            break;
        }
    }
    let mut out = [0u8; MAX_FRAME];
    let reply: Reply = black_box(Reply::Ack { command: 0 });
    let _ = black_box(capp_proto::encode(&reply, &mut out));
}

/// The entry point the linker keeps; everything reachable from it is checked.
#[no_mangle]
pub extern "C" fn _start() -> ! {
    loop {
        #[cfg(feature = "canary")]
        {
            let bytes = [0u8; 4];
            black_box(bytes[black_box(4)]);
        }
        if black_box(true) {
            plan();
        }
        if black_box(true) {
            protocol();
        }
    }
}
