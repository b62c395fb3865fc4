//! The in-place constructors (`Robot::init`, `Scenario::init`,
//! `Planner::restart`) against the by-value ones: the same checks, the same
//! errors, the same plan to the bit, on values that held another plan before.

mod common;

use capp_core::kinematics::{forward_kinematics, Frames};
use capp_core::*;
use common::planar;

type Sc = Scenario<18, 4, 3>;
/// Joints, obstacles, waypoints and settings, as `Scenario::init` takes them.
type Load<'a> = (&'a [Joint], &'a [SuperEllipsoid], &'a [Waypoint], Settings);

fn obstacles() -> [SuperEllipsoid; 2] {
    [
        SuperEllipsoid::aligned([60.0, 40.0, -30.0], [5.0, 5.0, 5.0], 2.0),
        SuperEllipsoid::aligned([-80.0, 10.0, 90.0], [8.0, 3.0, 6.0], 4.0),
    ]
}

/// A reachable target: PIPS's end effector at a nearby configuration, with
/// its orientation.
fn target() -> Waypoint {
    let robot = pips::robot::<18>().unwrap();
    let mut q = pips::home();
    q[0] += 0.9;
    q[5] += 0.6;
    q[9] -= 0.5;
    let mut frames = Frames::<18>::default();
    forward_kinematics(&robot, &q, &mut frames);
    let p = frames.end_position();
    Waypoint::at([p.x, p.y, p.z])
}

/// Every joint vector of a plan, as f32 bits, and the outcome.
fn trajectory(scenario: &Sc, planner: &mut Planner<18>) -> (Vec<Vec<u32>>, Outcome) {
    let bits = |q: &[f32]| q.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let mut out = vec![bits(planner.joints())];
    let outcome = planner
        .run(scenario, |p, _| out.push(bits(p.joints())))
        .unwrap();
    (out, outcome)
}

/// A different, smaller plan first, so the in-place values hold stale state.
fn used() -> (Sc, Planner<18>) {
    let mut scenario = Sc::empty();
    scenario
        .init(
            &planar(),
            &[SuperEllipsoid::aligned([0.0, 25.0, 0.0], [2.0; 3], 2.0)],
            &[
                Waypoint::at([5.0, 20.0, 0.0]),
                Waypoint::at([0.0, 28.0, 0.0]),
            ],
            Settings::default(),
        )
        .unwrap();
    let mut planner = Planner::empty();
    planner.restart(&scenario, &[0.1, 0.2, 0.3]).unwrap();
    for _ in 0..50 {
        planner.step(&scenario).unwrap();
    }
    (scenario, planner)
}

#[test]
fn in_place_builds_the_same_plan_bit_for_bit() {
    let settings = Settings {
        max_steps: 3_000,
        ..Settings::default()
    };
    let waypoints = [target()];
    let by_value = Sc::new(
        Robot::new(&pips::joints()).unwrap(),
        &obstacles(),
        &Mission::new(&waypoints, settings).unwrap(),
    )
    .unwrap();
    let (expected, outcome) = trajectory(
        &by_value,
        &mut Planner::new(&by_value, &pips::home()).unwrap(),
    );
    assert_eq!(outcome, Outcome::Reached);
    assert!(expected.len() > 20, "{}", expected.len());

    let (mut scenario, mut planner) = used();
    scenario
        .init(&pips::joints(), &obstacles(), &waypoints, settings)
        .unwrap();
    assert_eq!(scenario.obstacles().len(), 2);
    assert!(scenario.waypoints().eq(by_value.waypoints()));
    assert_eq!(scenario.targets(), by_value.targets());
    assert_eq!(scenario.settings(), by_value.settings());
    assert_eq!(scenario.robot().joints(), by_value.robot().joints());
    planner.restart(&scenario, &pips::home()).unwrap();
    assert_eq!(
        planner.last_report(),
        Planner::new(&by_value, &pips::home())
            .unwrap()
            .last_report()
    );
    let (got, outcome2) = trajectory(&scenario, &mut planner);
    assert_eq!(outcome2, outcome);
    assert_eq!(got, expected);

    // Restarting the same planner again gives the same plan again.
    planner.restart(&scenario, &pips::home()).unwrap();
    assert_eq!(trajectory(&scenario, &mut planner).0, expected);
}

#[test]
fn in_place_refuses_what_new_refuses_and_leaves_an_empty_value() {
    let joints = pips::joints();
    let mut bad_joint = joints;
    bad_joint[4].weight = 0.0;
    let bad_settings = Settings {
        time_step_s: -1.0,
        ..Settings::default()
    };
    let bad_obstacle = [SuperEllipsoid::aligned([0.0; 3], [0.0, 1.0, 1.0], 2.0)];
    let tilted = Waypoint::pose(
        [10.0, 0.0, 0.0],
        [[1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 1.0]],
    );
    let far = Waypoint::at([1.0e9, 0.0, 0.0]);
    let ok = [target()];
    let four = [target(); 4];
    let cases: [Load; 8] = [
        (&[], &[], &ok, Settings::default()),
        (&bad_joint, &[], &ok, Settings::default()),
        (&joints, &[], &four, Settings::default()),
        (&joints, &[], &ok, bad_settings),
        (&joints, &bad_obstacle, &ok, Settings::default()),
        (&joints, &[], &[], Settings::default()),
        (&joints, &[], &[tilted], Settings::default()),
        (&joints, &[], &[far], Settings::default()),
    ];
    for (i, (j, o, w, s)) in cases.into_iter().enumerate() {
        let by_value = Robot::<18>::new(j)
            .map_err(ScenarioError::from)
            .and_then(|r| {
                let m = Mission::<3>::new(w, s).map_err(ScenarioError::from)?;
                Sc::new(r, o, &m)
            });
        let expected = by_value
            .err()
            .unwrap_or_else(|| panic!("case {i} was accepted"));
        let (mut scenario, _) = used();
        assert_eq!(scenario.init(j, o, w, s), Err(expected), "case {i}");
        assert!(scenario.robot().is_empty(), "case {i}");
        assert!(scenario.obstacles().is_empty() && scenario.targets().is_empty());
        assert_eq!(scenario.waypoints().count(), 0);
        // No planner starts on what is left.
        let mut planner = Planner::<18>::empty();
        assert!(planner.restart(&scenario, &[]).is_err());
    }

    // Starts new refuses: restart refuses them the same way and leaves an empty planner.
    let sc = Sc::new(
        Robot::new(&joints).unwrap(),
        &[SuperEllipsoid::aligned(
            [0.0; 3],
            [1.0e4, 1.0e4, 1.0e4],
            2.0,
        )],
        &Mission::new(&ok, Settings::default()).unwrap(),
    );
    let inside = sc.unwrap();
    let clear = Sc::new(
        Robot::new(&joints).unwrap(),
        &[] as &[capp_core::Solid],
        &Mission::new(&ok, Settings::default()).unwrap(),
    )
    .unwrap();
    let mut nan = pips::home();
    nan[3] = f32::NAN;
    let mut outside = pips::home();
    outside[2] = 1.0e3;
    let starts: [(&Sc, &[f32]); 4] = [
        (&clear, &pips::home()[..5]),
        (&clear, &nan),
        (&clear, &outside),
        (&inside, &pips::home()),
    ];
    for (i, (sc, q)) in starts.into_iter().enumerate() {
        let expected = Planner::new(sc, q).err().unwrap();
        let (_, mut planner) = used();
        assert_eq!(planner.restart(sc, q), Err(expected), "start {i}");
        assert!(
            planner.joints().is_empty() && planner.is_done(),
            "start {i}"
        );
        let before = *planner.last_report();
        // Stepping what is left changes nothing (or is refused).
        let _ = planner.step(sc);
        assert!(planner.joints().is_empty());
        assert_eq!(before.step, planner.last_report().step);
    }
}

#[test]
fn clear_empties_in_place() {
    let (mut scenario, mut planner) = used();
    scenario.clear();
    planner.clear();
    assert!(scenario.robot().is_empty() && scenario.obstacles().is_empty());
    assert!(scenario.waypoints().count() == 0 && scenario.targets().is_empty());
    assert_eq!(scenario.settings(), Sc::empty().settings());
    assert!(planner.joints().is_empty() && planner.is_done());
    assert_eq!(planner.last_report(), Planner::<18>::empty().last_report());
    assert!(planner.restart(&scenario, &[]).is_err());
}
