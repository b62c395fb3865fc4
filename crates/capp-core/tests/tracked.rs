//! Tracked motion end to end (issue 22): every row at the fixed period, every
//! joint within its rate, acceleration and jerk limits read back from the
//! positions alone (backward differences over the period, in f64, rest before
//! the first row), every reached target reached at rest, and the invariants of
//! `run_checked` (limits, clearance, link gaps) on every row.

mod common;

use capp_core::pips;
use capp_core::tracker::limits::DriveLimits;
use capp_core::{Mission, Motion, Outcome, Planner, Robot, Settings, SuperEllipsoid, Waypoint};
use common::Sc;

/// Runs `sc` from `start` and checks the drive limits from the positions.
/// Returns the outcome and the number of ticks.
fn run_tracked(sc: &Sc, start: &[f32]) -> (Outcome, usize) {
    let dt = sc.settings().time_step_s as f64;
    let limits: Vec<DriveLimits> = sc.drive_limits().to_vec();
    let mut planner = Planner::new(sc, start).unwrap();
    let mut rows: Vec<Vec<f64>> = vec![start.iter().map(|&x| x as f64).collect()];
    let outcome = planner
        .run(sc, |p, r| {
            assert_eq!(r.time_step_s as f64, dt, "step {}: off the period", r.step);
            rows.push(p.joints().iter().map(|&x| x as f64).collect());
        })
        .unwrap();
    let at = |k: isize, j: usize| rows[k.max(0) as usize][j];
    for (j, l) in limits.iter().enumerate() {
        let v = |k: isize| (at(k, j) - at(k - 1, j)) / dt;
        let a = |k: isize| (v(k) - v(k - 1)) / dt;
        for k in 0..rows.len() as isize {
            let jerk = (a(k) - a(k - 1)) / dt;
            // f32 positions: their rounding over dt^p.
            let ulp = 2.0 * f32::EPSILON as f64 * at(k, j).abs().max(1.0);
            assert!(
                v(k).abs() <= l.max_rate as f64 * (1.0 + 1e-4) + 2.0 * ulp / dt,
                "row {k} joint {j}: rate {}",
                v(k)
            );
            assert!(
                a(k).abs() <= l.max_accel as f64 * (1.0 + 1e-3) + 4.0 * ulp / (dt * dt),
                "row {k} joint {j}: accel {} > {}",
                a(k),
                l.max_accel
            );
            assert!(
                jerk.abs() <= l.max_jerk as f64 * (1.0 + 1e-3) + 8.0 * ulp / (dt * dt * dt),
                "row {k} joint {j}: jerk {jerk} > {}",
                l.max_jerk
            );
        }
        if outcome == Outcome::Reached {
            let last = rows.len() as isize - 1;
            assert!(
                v(last).abs() <= 0.01 * l.max_rate as f64 + 2.0 * f32::EPSILON as f64 * 1e3 / dt,
                "arrives moving: joint {j} at {}",
                v(last)
            );
        }
    }
    // The independent invariants on the same plan.
    let run = common::run_checked(sc, start);
    assert_eq!(run.outcome, outcome);
    (outcome, rows.len())
}

fn tracked(mut settings: Settings) -> Settings {
    settings.motion = Motion::Tracked;
    settings
}

#[test]
fn pips_between_random_configurations_moves_within_its_drive_limits() {
    let joints = pips::joints();
    let mut rng = common::Rng(5);
    let (mut runs, mut reached) = (0, 0);
    while runs < 8 {
        let start = common::random_config(&mut rng, &joints);
        let goal = common::random_config(&mut rng, &joints);
        let (p, r) = common::pose_of(&joints, &goal);
        let robot = Robot::new(&joints).unwrap();
        let mut settings = tracked(Settings::for_robot(&robot));
        settings.max_steps = 1500;
        let obstacle = SuperEllipsoid::aligned(
            [0.5 * (p[0] + 100.0), p[1], p[2] + 60.0],
            [10.0, 10.0, 10.0],
            2.0,
        );
        let mut sc = Sc::new(
            robot,
            &[obstacle],
            &Mission::new(&[Waypoint::pose(p, r)], settings).unwrap(),
        )
        .unwrap();
        common::pips_capsules(&mut sc);
        if Planner::new(&sc, &start).is_err() {
            continue;
        }
        runs += 1;
        let (outcome, _) = run_tracked(&sc, &start);
        if outcome == Outcome::Reached {
            reached += 1;
        }
    }
    assert!(reached >= 6, "reached {reached} of 8");
}
