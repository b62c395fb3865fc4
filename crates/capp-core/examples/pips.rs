//! Plans a PIPS manoeuvre and prints its outcome: from the home configuration
//! of Table 1 to a pose in front of a payload-sized obstacle, around a second
//! obstacle that stands across the straight path.
//!
//!     cargo run --release -p capp-core --example pips

use capp_core::kinematics::{forward_kinematics, Frames};
use capp_core::*;

fn main() {
    let robot = pips::robot::<18>().expect("the preset is valid");
    let home = pips::home();
    let mut frames = Frames::<18>::default();
    forward_kinematics(&robot, &home, &mut frames);
    let from = frames.end_position();

    // Target: the pose of a bent configuration (reachable by construction).
    let mut bent = home;
    for (j, q) in bent.iter_mut().enumerate().skip(5).take(11) {
        *q += if j % 2 == 0 { 0.35 } else { -0.25 };
    }
    forward_kinematics(&robot, &bent, &mut frames);
    let to = frames.end_position();
    let r = frames.end_rotation();
    let rows = [0, 1, 2].map(|i| [r[(i, 0)], r[(i, 1)], r[(i, 2)]]);

    let halfway = [0, 1, 2].map(|i| 0.5 * (from[i] + to[i]));
    let obstacles = [SuperEllipsoid::aligned(halfway, [4.0, 4.0, 4.0], 2.0)];
    let mission = Mission::<4>::new(&[Waypoint::pose(to.into(), rows)], Settings::default())
        .expect("one waypoint fits");
    let scenario = Scenario::<18, 8, 4>::new(robot, &obstacles, &mission).expect("valid scenario");
    let mut planner = Planner::new(&scenario, &home).expect("home is clear of the obstacle");

    let mut closest = f32::INFINITY;
    let mut constrained = 0;
    let outcome = planner
        .run(&scenario, |_, report| {
            if let Some(c) = report.clearance {
                closest = closest.min(c.value);
            }
            constrained += report.constrained as u32;
        })
        .expect("same scenario throughout");
    let last = planner.last_report();
    println!("outcome: {outcome:?}");
    println!(
        "steps: {} ({} constrained by the obstacle)",
        last.step, constrained
    );
    println!(
        "final errors: position {:.3} in, orientation {:.4}",
        last.position_error, last.orientation_error
    );
    println!("closest approach: C - 1 = {closest:.3} (> 0 is clear of the inflated obstacle)");
    println!("final joints: {:?}", planner.joints());
    std::process::exit(if outcome == Outcome::Reached { 0 } else { 1 });
}
