//! End-to-end runs of the planner, checked against independent computations:
//! targets reached, V monotone in free space, no avoidance point ever inside an
//! inflated obstacle, limits and rate limits kept, dead ends detected, no
//! chatter near the goal, and bad input refused.

mod common;

use capp_core::control::LawKind;
use capp_core::planner::StartError;
use capp_core::*;
use common::*;

fn pips_target(rng: &mut Rng) -> ([f32; 3], [[f32; 3]; 3]) {
    let joints = pips::joints();
    let q: Vec<f32> = joints
        .iter()
        .map(|j| {
            let (mid, half) = (0.5 * (j.min + j.max), 0.5 * (j.max - j.min));
            mid + 0.6 * half * rng.uniform(-1.0, 1.0) as f32
        })
        .collect();
    pose_of(&joints, &q)
}

#[test]
fn free_space_reaches_reachable_poses_and_v_never_increases() {
    let mut rng = Rng(2024);
    for trial in 0..6 {
        let (p, r) = pips_target(&mut rng);
        let sc = scenario(
            &pips::joints(),
            &[],
            &[Waypoint::pose(p, r)],
            Settings::default(),
        );
        let run = run_checked(&sc, &pips::home());
        assert_eq!(run.outcome, Outcome::Reached, "trial {trial}");
        for (k, w) in run.v.windows(2).enumerate() {
            assert!(
                w[1] <= w[0],
                "trial {trial}: V rose at step {k}: {} -> {}",
                w[0],
                w[1]
            );
        }
    }
}

#[test]
fn no_chatter_near_the_goal() {
    // Near the goal the rate shrinks with the error and the step stays below
    // the stiffest mode's limit, so no joint rate flips sign step after step.
    // The damped least-squares law gets there in a few Gauss-Newton steps;
    // the gradient law creeps in over hundreds. Neither may chatter.
    let mut rng = Rng(99);
    for trial in 0..12 {
        let (p, r) = pips_target(&mut rng);
        let mut settings = Settings::default();
        // Within `radius` of the goal: the last 2 in for the gradient law,
        // the last 10 in (the end of the full-speed run and the approach)
        // for the damped one, which covers 2 in in a step or two.
        let (kind, radius, least) = if trial % 2 == 0 {
            (LawKind::DampedLeastSquares, 10.0, 4)
        } else {
            (LawKind::Gradient, 2.0, 10)
        };
        settings.law.kind = kind;
        let sc = scenario(&pips::joints(), &[], &[Waypoint::pose(p, r)], settings);
        let run = run_checked(&sc, &pips::home());
        assert_eq!(run.outcome, Outcome::Reached);
        let near: Vec<&Vec<f32>> = run
            .rates
            .iter()
            .filter(|(_, e)| *e < radius)
            .map(|(r, _)| r)
            .collect();
        assert!(
            near.len() >= least,
            "trial {trial} ({kind:?}): the run should spend steps near the goal"
        );
        let mut flip_flops = 0;
        for w in near.windows(3) {
            // A rate under 0.1% of its limit is a joint at rest, not chatter.
            let at_rest = 1e-3 * pips::REVOLUTE_RATE.min(pips::PRISMATIC_RATE);
            flip_flops += (0..18)
                .filter(|&j| {
                    let (a, b, c) = (w[0][j], w[1][j], w[2][j]);
                    a * b < 0.0 && b * c < 0.0 && b.abs() > at_rest
                })
                .count();
        }
        assert_eq!(
            flip_flops, 0,
            "trial {trial}: joint rates flip sign step after step near the goal"
        );
    }
}

#[test]
fn obstacles_across_the_straight_path_are_avoided_and_targets_reached() {
    let joints = pips::joints();
    let start = pips::home();
    let (home_p, _) = pose_of(&joints, &start);
    let mut rng = Rng(7);
    let mut reached = 0;
    let mut constrained_runs = 0;
    for _ in 0..6 {
        let (p, _) = pips_target(&mut rng);
        // A ball on the straight end-effector path, halfway.
        let mid = [0, 1, 2].map(|i| 0.5 * (home_p[i] + p[i]));
        let ball = SuperEllipsoid::aligned(mid, [4.0; 3], 2.0);
        let sc = scenario(&joints, &[ball], &[Waypoint::at(p)], Settings::default());
        if Planner::new(&sc, &start).is_err() {
            continue;
        }
        let run = run_checked(&sc, &start);
        assert_eq!(run.outcome, Outcome::Reached, "target {p:?} around {mid:?}");
        reached += 1;
        let mut planner = Planner::new(&sc, &start).unwrap();
        let mut constrained = false;
        planner
            .run(&sc, |_, r| constrained |= r.constrained)
            .unwrap();
        constrained_runs += constrained as u32;
    }
    assert!(reached >= 5, "only {reached} scenarios were valid");
    assert!(
        constrained_runs >= 3,
        "the obstacles should have constrained most runs"
    );
}

/// The planar arm, 3 avoidance points per link, with `obstacles` and
/// `waypoints`, and `escape_attempts`.
fn planar_scenario(
    obstacles: &[SuperEllipsoid],
    waypoints: &[Waypoint],
    escape_attempts: u8,
) -> Sc {
    let mut settings = planar_settings(1.0);
    settings.escape.attempts = escape_attempts;
    settings.avoidance.points_per_link = 3;
    scenario(&planar(), obstacles, waypoints, settings)
}

/// The trap: the planar arm starts at `TRAP_START`, its hand at
/// (28.38, 4.79); the target is that point's mirror image across y = 0, at
/// `d0` = 9.59 in from the hand (the configuration `-TRAP_START` reaches it).
/// A wall along y = 0 from x = 17 to x = 39 stands between them. Every
/// point of the disk of radius `d0` round the target that lies on y = 0 has
/// x in [20.07, 36.68] (half chord sqrt(d0^2 - 4.79^2) = 8.30 round x =
/// 28.38), inside the bare wall: the wall cuts that disk in two, the hand
/// on one side, the target on the other. So every collision-free path of
/// the hand to the target (the hand moves in the plane z = 0 only) leaves
/// the disk: the position error, and with it V, must first rise above its
/// value at the start. No law that keeps V at or below where it started can
/// pass, however good. A path exists, though: round the wall's inner end
/// (x < 16 with the margin; the outer end, at 39, is beyond the arm's reach
/// of 30), folded. `trap_is_a_dead_end_by_construction` checks the
/// geometry.
const TRAP_START: [f32; 3] = [0.5, -0.3, -0.4];

fn trap_wall() -> SuperEllipsoid {
    SuperEllipsoid::aligned([28.0, 0.0, 0.0], [11.0, 1.0, 50.0], 8.0)
}

fn trap_target() -> [f32; 3] {
    let (hand, _) = pose_of(&planar(), &TRAP_START);
    [hand[0], -hand[1], 0.0]
}

#[test]
fn trap_is_a_dead_end_by_construction() {
    let (hand, _) = pose_of(&planar(), &TRAP_START);
    let target = trap_target();
    let d0 = (hand[1] - target[1]).abs() as f64;
    assert!(hand[1] > 0.0 && (hand[0] - target[0]).abs() < 1e-6);
    // The disk's chord along y = 0 lies inside the bare wall (C <= 1).
    let half = (d0 * d0 - (hand[1] as f64).powi(2)).sqrt();
    for i in 0..=100 {
        let x = target[0] as f64 - half + 2.0 * half * i as f64 / 100.0;
        assert!(c64(&trap_wall(), 0.0, [x, 0.0, 0.0]) <= 1.0, "x = {x}");
    }
    // Free space reaches the target: the mirrored configuration is there.
    let mirrored = TRAP_START.map(|q| -q);
    assert!(miss(&planar(), &mirrored, target) < 1e-4);
}

#[test]
fn a_planar_arm_stalls_in_a_trap_and_leaves_it_with_waypoints_or_an_escape() {
    let target = Waypoint::at(trap_target());
    let tolerance = Settings::default().position_tolerance;
    // Escapes off: the law descends V and the trap (see `TRAP_START`) has
    // no descending way out; a dead end, detected well before the cap.
    let sc = planar_scenario(&[trap_wall()], &[target], 0);
    let run = run_checked(&sc, &TRAP_START);
    assert_eq!(run.outcome, Outcome::Stalled);
    assert!(run.steps < sc.settings().max_steps);
    let (hand, _) = pose_of(&planar(), &run.joints);
    assert!(hand[1] > 0.0, "still on the start side: {hand:?}");
    // The operator's remedy (paper, section 5): waypoints round the wall's
    // inner end.
    let round = [
        Waypoint::at([11.0, 6.0, 0.0]),
        Waypoint::at([11.0, -6.0, 0.0]),
        target,
    ];
    let sc = planar_scenario(&[trap_wall()], &round, 0);
    let run = run_checked(&sc, &TRAP_START);
    assert_eq!(run.outcome, Outcome::Reached);
    assert!(miss(&planar(), &run.joints, trap_target()) <= tolerance + 1e-4);
    // The planner's own: escapes on, it leaves the trap and goes round,
    // never touching the wall (`run_checked`).
    let sc = planar_scenario(
        &[trap_wall()],
        &[target],
        Settings::default().escape.attempts,
    );
    let run = run_checked(&sc, &TRAP_START);
    assert_eq!(run.outcome, Outcome::Reached);
    assert!(run.escape_steps > 0, "it escaped");
    assert!(miss(&planar(), &run.joints, trap_target()) <= tolerance + 1e-4);
}

/// A wall across the planar arm's whole reach: the band 18.5 <= x <= 21.5,
/// 40 in either way along y (and 50 along z). The arm's hand is never more
/// than 30 in from its base at the origin, so a hand path from x < 20 to x >
/// 20 crosses the line x = 20 at |y| <= 30, inside the bare wall. The
/// target (25, 5) is within reach (25.5 in) but behind it: unreachable
/// without a collision, whatever the law or the escape.
fn closed_wall() -> SuperEllipsoid {
    SuperEllipsoid::aligned([20.0, 0.0, 0.0], [1.5, 40.0, 50.0], 8.0)
}

#[test]
fn a_planar_arm_behind_a_wall_across_its_reach_stalls_escapes_or_not() {
    let target: [f32; 3] = [25.0, 5.0, 0.0];
    assert!(target[0].hypot(target[1]) < PLANAR_REACH);
    for y in [-30.0, 0.0, 30.0] {
        assert!(c64(&closed_wall(), 0.0, [20.0, y, 0.0]) <= 1.0);
    }
    let start = [0.5, 0.5, 0.5];
    for attempts in [0, Settings::default().escape.attempts] {
        let sc = planar_scenario(&[closed_wall()], &[Waypoint::at(target)], attempts);
        let run = run_checked(&sc, &start);
        assert_eq!(run.outcome, Outcome::Stalled, "{attempts} attempts");
        assert!(run.steps < sc.settings().max_steps, "{attempts} attempts");
        assert_eq!(run.escape_steps > 0, attempts > 0, "{attempts} attempts");
        let (hand, _) = pose_of(&planar(), &run.joints);
        assert!(hand[0] < 20.0, "{attempts} attempts: {hand:?}");
    }
}

#[test]
fn unreachable_target_ends_stalled_within_the_cap() {
    let sc = scenario(
        &pips::joints(),
        &[],
        &[Waypoint::at([400.0, 0.0, 50.0])],
        Settings::default(),
    );
    let run = run_checked(&sc, &pips::home());
    assert_eq!(run.outcome, Outcome::Stalled);
    assert!(run.steps < Settings::default().max_steps);
}

#[test]
fn target_inside_an_obstacle_ends_stalled_and_never_enters() {
    let joints = pips::joints();
    let mut rng = Rng(5);
    let (p, _) = pips_target(&mut rng);
    let ball = SuperEllipsoid::aligned(p, [3.0; 3], 2.0);
    let sc = scenario(&joints, &[ball], &[Waypoint::at(p)], Settings::default());
    let run = run_checked(&sc, &pips::home());
    assert_eq!(run.outcome, Outcome::Stalled);
    assert!(run.steps < Settings::default().max_steps);
}

#[test]
fn waypoints_are_passed_in_order() {
    let mut rng = Rng(31);
    let (a, _) = pips_target(&mut rng);
    let (b, r) = pips_target(&mut rng);
    let sc = scenario(
        &pips::joints(),
        &[],
        &[Waypoint::at(a), Waypoint::pose(b, r)],
        Settings::default(),
    );
    let mut planner = Planner::new(&sc, &pips::home()).unwrap();
    let mut seen = vec![];
    let outcome = planner
        .run(&sc, |_, r| {
            if let Phase::Moving { waypoint } = r.phase {
                if seen.last() != Some(&waypoint) {
                    seen.push(waypoint);
                }
            }
        })
        .unwrap();
    assert_eq!(outcome, Outcome::Reached);
    assert_eq!(seen, vec![0, 1]);
}

#[test]
fn a_finished_planner_stays_put() {
    let joints = pips::joints();
    let (p, r) = pose_of(&joints, &pips::home());
    let sc = scenario(&joints, &[], &[Waypoint::pose(p, r)], Settings::default());
    let mut planner = Planner::new(&sc, &pips::home()).unwrap();
    let report = planner.step(&sc).unwrap();
    assert_eq!(report.phase, Phase::Done(Outcome::Reached));
    assert_eq!(planner.joints(), &pips::home());
    assert_eq!(
        planner.step(&sc).unwrap().phase,
        Phase::Done(Outcome::Reached)
    );
}

#[test]
fn capped_when_the_iteration_cap_is_tiny() {
    let mut rng = Rng(3);
    let (p, r) = pips_target(&mut rng);
    let settings = Settings {
        max_steps: 5,
        ..Settings::default()
    };
    let sc = scenario(&pips::joints(), &[], &[Waypoint::pose(p, r)], settings);
    let run = run_checked(&sc, &pips::home());
    assert_eq!(run.outcome, Outcome::Capped);
    assert_eq!(run.steps, 5);
}

#[test]
fn bad_inputs_are_errors_not_panics() {
    let joints = pips::joints();
    let robot = || Robot::<18>::new(&joints).unwrap();
    let good_waypoint = Waypoint::at([50.0, 50.0, 10.0]);
    let mission = |w: Waypoint, s: Settings| Mission::<4>::new(&[w], s).unwrap();

    // Robot: NaN and inverted limits name the joint.
    let mut bad = joints;
    bad[4].a = f32::NAN;
    assert!(matches!(
        Robot::<18>::new(&bad),
        Err(RobotError::NotFinite { joint: 4, .. })
    ));
    let mut bad = joints;
    bad[7].min = bad[7].max;
    assert_eq!(
        Robot::<18>::new(&bad).unwrap_err(),
        RobotError::InvertedLimits { joint: 7 }
    );

    // Obstacles: zero semi-axis, NaN, infinite exponent.
    let zero = SuperEllipsoid::aligned([0.0; 3], [1.0, 0.0, 1.0], 2.0);
    let err = Sc::new(
        robot(),
        &[zero],
        &mission(good_waypoint, Settings::default()),
    )
    .unwrap_err();
    assert_eq!(
        err,
        ScenarioError::Obstacle(ObstacleError::SemiAxisOutOfRange { obstacle: 0 })
    );
    let nan = SuperEllipsoid::aligned([f32::NAN, 0.0, 0.0], [1.0; 3], 2.0);
    assert!(Sc::new(
        robot(),
        &[nan],
        &mission(good_waypoint, Settings::default())
    )
    .is_err());
    let inf = SuperEllipsoid::aligned([0.0; 3], [1.0; 3], f32::INFINITY);
    assert!(Sc::new(
        robot(),
        &[inf],
        &mission(good_waypoint, Settings::default())
    )
    .is_err());

    // Waypoints: NaN position, a reflection instead of a rotation.
    let err = Sc::new(
        robot(),
        &[] as &[capp_core::Solid],
        &mission(Waypoint::at([f32::NAN, 0.0, 0.0]), Settings::default()),
    )
    .unwrap_err();
    assert_eq!(
        err,
        ScenarioError::Mission(MissionError::BadPosition { waypoint: 0 })
    );
    let mirror = Waypoint::pose(
        [1.0; 3],
        [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]],
    );
    assert!(matches!(
        Sc::new(
            robot(),
            &[] as &[capp_core::Solid],
            &mission(mirror, Settings::default())
        ),
        Err(ScenarioError::Mission(MissionError::NotARotation { .. }))
    ));
    let err = Sc::new(
        robot(),
        &[] as &[capp_core::Solid],
        &Mission {
            waypoints: heapless::Vec::new(),
            settings: Settings::default(),
        },
    )
    .unwrap_err();
    assert_eq!(err, ScenarioError::Mission(MissionError::NoWaypoints));

    // Settings.
    for broken in [
        Settings {
            time_step_s: f32::NAN,
            ..Settings::default()
        },
        Settings {
            time_step_s: -1.0,
            ..Settings::default()
        },
        Settings {
            stall_progress: 1.0,
            ..Settings::default()
        },
        Settings {
            max_steps: 0,
            ..Settings::default()
        },
    ] {
        assert!(matches!(
            Sc::new(
                robot(),
                &[] as &[capp_core::Solid],
                &mission(good_waypoint, broken)
            ),
            Err(ScenarioError::Mission(MissionError::BadSetting(_)))
        ));
    }

    // Start configurations.
    let sc = Sc::new(
        robot(),
        &[] as &[capp_core::Solid],
        &mission(good_waypoint, Settings::default()),
    )
    .unwrap();
    let mut q = pips::home();
    q[3] = f32::INFINITY;
    assert_eq!(
        Planner::new(&sc, &q).unwrap_err(),
        StartError::NotFinite { joint: 3 }
    );
    let mut q = pips::home();
    q[2] = 100.0;
    assert_eq!(
        Planner::new(&sc, &q).unwrap_err(),
        StartError::OutsideLimits { joint: 2 }
    );
    assert!(matches!(
        Planner::new(&sc, &q[..5]).unwrap_err(),
        StartError::WrongLength {
            given: 5,
            joints: 18
        }
    ));
    let (p, _) = pose_of(&joints, &pips::home());
    let around_hand = SuperEllipsoid::aligned(p, [2.0; 3], 2.0);
    let sc = Sc::new(
        robot(),
        &[around_hand],
        &mission(good_waypoint, Settings::default()),
    )
    .unwrap();
    assert!(matches!(
        Planner::new(&sc, &pips::home()).unwrap_err(),
        StartError::InObstacle { obstacle: 0, .. }
    ));
}

#[test]
fn runs_are_deterministic_to_the_bit() {
    let mut rng = Rng(77);
    let (p, r) = pips_target(&mut rng);
    let sc = scenario(
        &pips::joints(),
        &[],
        &[Waypoint::pose(p, r)],
        Settings::default(),
    );
    let trace = || {
        let mut planner = Planner::new(&sc, &pips::home()).unwrap();
        let mut bits = vec![];
        planner
            .run(&sc, |p, _| {
                bits.extend(p.joints().iter().map(|x| x.to_bits()))
            })
            .unwrap();
        bits
    };
    assert_eq!(trace(), trace());
}

#[test]
fn the_listing_decimation_emits_start_changes_and_end() {
    let mut rng = Rng(8);
    let (p, r) = pips_target(&mut rng);
    // The gradient law's small steps: most of them change the errors by less
    // than the thresholds, so the decimation has something to drop.
    let mut settings = Settings::default();
    settings.law.kind = LawKind::Gradient;
    let sc = scenario(&pips::joints(), &[], &[Waypoint::pose(p, r)], settings);
    let mut planner = Planner::new(&sc, &pips::home()).unwrap();
    let mut decimator = setpoint::Decimator::new(SetpointFilter::LISTING);
    assert!(
        decimator.offer(planner.last_report()),
        "the start is always a setpoint"
    );
    let mut emitted = vec![*planner.last_report()];
    let mut total = 0;
    planner
        .run(&sc, |_, r| {
            total += 1;
            if decimator.offer(r) {
                emitted.push(*r);
            }
        })
        .unwrap();
    assert!(
        emitted.len() > 2 && emitted.len() < total / 2,
        "{} of {total}",
        emitted.len()
    );
    assert!(
        matches!(emitted.last().unwrap().phase, Phase::Done(_)),
        "the end is always a setpoint"
    );
    for w in emitted.windows(2).take(emitted.len().saturating_sub(2)) {
        let moved = (w[1].position_error - w[0].position_error).abs() > 1.0
            || (w[1].orientation_error - w[0].orientation_error).abs() > 0.1;
        assert!(
            moved,
            "a setpoint was emitted without the errors changing enough"
        );
    }
}

#[test]
fn joint_space_waypoints_are_reached_in_joint_space_then_the_pose_target() {
    // PIPS from home via a joint configuration to a pose, and to a joint
    // configuration as the target.
    let joints = pips::joints();
    let home = pips::home();
    let mut via = home;
    for (q, j) in via.iter_mut().zip(&joints) {
        *q = j.clamp(*q + 0.35 * (j.max - j.min) * 0.5);
    }
    let mut goal = home;
    for (i, (q, j)) in goal.iter_mut().zip(&joints).enumerate() {
        let sign = if i % 2 == 0 { 1.0 } else { -1.0 };
        *q = j.clamp(*q + sign * 0.2 * (j.max - j.min) * 0.5);
    }
    let (p, r) = pose_of(&joints, &home);
    let waypoints = [
        Waypoint::at([0.0; 3]),
        Waypoint::pose(p, r),
        Waypoint::at([0.0; 3]),
    ];
    let mut sc = scenario(&joints, &[], &waypoints, Settings::default());
    sc.set_joint_goal(0, &via).unwrap();
    sc.set_joint_goal(2, &goal).unwrap();
    assert_eq!(sc.targets()[0].joints, Some(0));
    assert_eq!(sc.joint_goal(1), Some(&goal[..]));
    // The joint goal's pose is its configuration's.
    let (gp, _) = pose_of(&joints, &goal);
    let t = sc.targets()[2].position;
    assert!((t.x - gp[0]).abs() < 1e-3 && (t.y - gp[1]).abs() < 1e-3 && (t.z - gp[2]).abs() < 1e-3);

    let mut planner = Planner::new(&sc, &home).unwrap();
    let mut seen = Vec::new();
    let mut at_via = None;
    let outcome = planner
        .run(&sc, |pl, r| {
            if let Phase::Moving { waypoint } = r.phase {
                if seen.last() != Some(&waypoint) {
                    if waypoint == 1 {
                        at_via = Some(pl.joints().to_vec());
                    }
                    seen.push(waypoint);
                }
            }
        })
        .unwrap();
    assert_eq!(outcome, Outcome::Reached);
    assert_eq!(seen, vec![0, 1, 2]);
    let tolerance = |q: &[f32], g: &[f32]| {
        q.iter()
            .zip(g)
            .zip(&joints)
            .all(|((a, b), j)| (a - b).abs() <= 0.05 * 0.05 * j.max_rate + 1e-5)
    };
    assert!(
        tolerance(at_via.as_deref().unwrap(), &via),
        "passed the via configuration"
    );
    assert!(
        tolerance(planner.joints(), &goal),
        "ended at the goal configuration"
    );

    // What a joint goal may not be.
    let mut sc = scenario(&joints, &[], &waypoints, Settings::default());
    let problem = |e: ScenarioError| match e {
        ScenarioError::Mission(MissionError::BadJointGoal { problem, .. }) => problem,
        other => panic!("{other:?}"),
    };
    use capp_core::mission::JointGoalProblem as P;
    assert_eq!(
        problem(sc.set_joint_goal(0, &via[..17]).unwrap_err()),
        P::WrongLength
    );
    let mut out = via;
    out[3] = 1e3;
    assert_eq!(
        problem(sc.set_joint_goal(0, &out).unwrap_err()),
        P::OutsideLimits
    );
    out[3] = f32::NAN;
    assert_eq!(
        problem(sc.set_joint_goal(0, &out).unwrap_err()),
        P::OutsideLimits
    );
    assert_eq!(
        problem(sc.set_joint_goal(3, &via).unwrap_err()),
        P::NoSuchWaypoint
    );
    for _ in 0..capp_core::scenario::MAX_JOINT_GOALS {
        sc.set_joint_goal(0, &via).unwrap();
    }
    assert_eq!(problem(sc.set_joint_goal(0, &via).unwrap_err()), P::TooMany);
}
