//! Measures what our departures from the paper buy, on the same random PIPS
//! problems: eq. 15's separately normalised terms against the gradient law
//! and the damped least-squares law (the default), and the paper's always-on
//! projection against ours (engaged near contact), both under the default law.
//! Dead-end escapes are off throughout: these compare the laws and the
//! projections alone (a dead end ends the run `Stalled`).
//!
//!     cargo run --release -p capp-core --example compare

use capp_core::control::LawKind;
use capp_core::kinematics::{forward_kinematics, Frames};
use capp_core::*;

const TRIALS: usize = 40;

/// Reproducible uniform numbers in [-1, 1).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
    }
}

struct Tally {
    reached: usize,
    steps: u64,
}

fn run(
    obstacles: &[SuperEllipsoid],
    waypoint: Waypoint,
    settings: Settings,
) -> Option<(Outcome, u32)> {
    let robot = pips::robot::<18>().ok()?;
    let settings = Settings {
        escape: capp_core::escape::EscapeSettings {
            attempts: 0,
            ..settings.escape
        },
        ..settings
    };
    let mission = Mission::<1>::new(&[waypoint], settings).ok()?;
    let scenario = Scenario::<18, 1, 1>::new(robot, obstacles, &mission).ok()?;
    let mut planner = Planner::new(&scenario, &pips::home()).ok()?;
    let outcome = planner.run(&scenario, |_, _| {}).ok()?;
    Some((outcome, planner.last_report().step))
}

fn main() {
    let robot = pips::robot::<18>().unwrap();
    let mut frames = Frames::<18>::default();
    forward_kinematics(&robot, &pips::home(), &mut frames);
    let home_end = frames.end_position();
    let mut rng = Lcg(1993);
    let laws = [
        ("eq. 15 as printed (normalised terms)", LawKind::Paper),
        ("gradient law", LawKind::Gradient),
        (
            "damped least squares (ours, the default)",
            LawKind::DampedLeastSquares,
        ),
    ];
    let mut law = laws.map(|_| Tally {
        reached: 0,
        steps: 0,
    });
    let mut projection = [
        Tally {
            reached: 0,
            steps: 0,
        },
        Tally {
            reached: 0,
            steps: 0,
        },
    ];
    let mut obstacle_trials = 0;
    for _ in 0..TRIALS {
        let q: Vec<f32> = robot
            .joints()
            .iter()
            .map(|j| 0.5 * (j.min + j.max) + 0.3 * (j.max - j.min) * rng.next())
            .collect();
        forward_kinematics(&robot, &q, &mut frames);
        let p = frames.end_position();
        let r = frames.end_rotation();
        let rows = [0, 1, 2].map(|i| [r[(i, 0)], r[(i, 1)], r[(i, 2)]]);
        // Free space, full pose: the two laws.
        for (tally, (_, kind)) in law.iter_mut().zip(laws) {
            let mut settings = Settings::default();
            settings.law.kind = kind;
            if let Some((Outcome::Reached, steps)) =
                run(&[], Waypoint::pose(p.into(), rows), settings)
            {
                tally.reached += 1;
                tally.steps += steps as u64;
            }
        }
        // A ball across the straight path, position only: the two projections.
        let mid = [0, 1, 2].map(|i| 0.5 * (home_end[i] + p[i]));
        let ball = [SuperEllipsoid::aligned(mid, [5.0; 3], 2.0)];
        let mut any = false;
        for (tally, engage) in projection.iter_mut().zip([0.0, 1.0]) {
            let mut settings = Settings::default();
            settings.avoidance.engage_clearance = engage;
            settings.avoidance.influence_distance = if engage == 0.0 { 1.0e4 } else { 24.0 };
            match run(&ball, Waypoint::at(p.into()), settings) {
                Some((Outcome::Reached, steps)) => {
                    tally.reached += 1;
                    tally.steps += steps as u64;
                    any = true;
                }
                Some(_) => any = true,
                None => {}
            }
        }
        obstacle_trials += any as usize;
    }
    let line = |name: &str, t: &Tally, of: usize| {
        let mean = if t.reached > 0 {
            t.steps / t.reached as u64
        } else {
            0
        };
        println!("| {name} | {}/{of} | {mean} |", t.reached);
    };
    println!("| PIPS, home to a random reachable pose (no escapes) | reached | mean steps when reached |");
    println!("|---|---|---|");
    for ((name, _), tally) in laws.iter().zip(&law) {
        line(name, tally, TRIALS);
    }
    println!();
    println!("| PIPS, ball of radius 5 in across the straight path (no escapes) | reached | mean steps when reached |");
    println!("|---|---|---|");
    line(
        "always engaged, every obstacle counts (paper's rule, one-sided)",
        &projection[0],
        obstacle_trials,
    );
    line(
        "one-sided, engaged near contact, influence 24 in (ours)",
        &projection[1],
        obstacle_trials,
    );
}
