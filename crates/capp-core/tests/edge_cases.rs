//! Numerical edge cases (issue 6, part 5): a fully stretched (singular) arm,
//! a target exactly at the current pose, coincident avoidance points, an
//! obstacle touching the start configuration, and the same problem in inches
//! and in metres. Each must end sensibly with no NaN.

mod common;

use capp_core::avoidance::AvoidanceSettings;
use capp_core::planner::StartError;
use capp_core::*;
use common::*;

#[test]
fn a_fully_stretched_arm_folds_to_a_target_inside_its_reach() {
    // At q = 0 the arm is singular: every column of J_p is along y, so the
    // Jacobian has rank 1 in the plane; targets with a y component pull it
    // out of the singularity.
    let settings = Settings {
        max_steps: 4000,
        ..Settings::default()
    };
    for target in [[20.0, 5.0, 0.0], [0.0, 20.0, 0.0], [15.0, -0.5, 0.0]] {
        let sc = scenario(&planar(), &[], &[Waypoint::at(target)], settings);
        let Run {
            outcome,
            steps,
            joints: q,
            ..
        } = run_checked(&sc, &[0.0; 3]);
        assert_eq!(outcome, Outcome::Reached, "target {target:?}");
        assert!(steps > 1, "it had to move");
        let (p, _) = pose_of(&planar(), &q);
        assert!((p[0] - target[0]).hypot(p[1] - target[1]) <= 0.1 + 1e-4);
    }
}

#[test]
fn a_target_straight_back_along_a_stretched_arm_is_a_detected_dead_end() {
    // Exactly along the arm the error is orthogonal to every column of J_p:
    // the gradient J^T e is exactly zero, so no law can move. With escapes
    // off the planner must say so (Stalled, no NaN, not a single joint
    // moved) within one stall window, and the paper's remedy, a waypoint,
    // gets it there; with escapes on (the default) it gets there by itself.
    let mut settings = Settings {
        max_steps: 4000,
        ..Settings::default()
    };
    settings.escape.attempts = 0;
    let target = Waypoint::at([15.0, 0.0, 0.0]);
    let sc = scenario(&planar(), &[], &[target], settings);
    let Run {
        outcome,
        steps,
        joints: q,
        ..
    } = run_checked(&sc, &[0.0; 3]);
    assert_eq!(outcome, Outcome::Stalled);
    assert!(steps <= settings.stall_window + 1, "{steps} steps");
    assert_eq!(q, vec![0.0; 3]);
    let via = Waypoint::at([20.0, 8.0, 0.0]);
    let sc = scenario(&planar(), &[], &[via, target], settings);
    let Run { outcome, .. } = run_checked(&sc, &[0.0; 3]);
    assert_eq!(outcome, Outcome::Reached);
    settings.escape = Settings::default().escape;
    let sc = scenario(&planar(), &[], &[target], settings);
    let Run { outcome, .. } = run_checked(&sc, &[0.0; 3]);
    assert_eq!(outcome, Outcome::Reached, "escaped the dead end");
}

#[test]
fn a_stretched_arm_asked_beyond_its_reach_stalls_without_nan() {
    // Straight ahead, 10 in beyond the stretched arm's 30 in: the arm is
    // already as close as it can be, at a singular configuration.
    let sc = scenario(
        &planar(),
        &[],
        &[Waypoint::at([40.0, 0.0, 0.0])],
        Settings::default(),
    );
    let Run {
        outcome,
        steps,
        joints: q,
        ..
    } = run_checked(&sc, &[0.0; 3]);
    assert_eq!(outcome, Outcome::Stalled);
    assert!(steps < Settings::default().max_steps);
    assert!(q.iter().all(|x| x.abs() < 1e-3), "stays stretched: {q:?}");

    // PIPS stretched: every revolute joint at zero, prismatic joints home.
    let joints = pips::joints();
    let mut stretched = pips::home();
    for (q, j) in stretched.iter_mut().zip(&joints) {
        if j.kind == JointKind::Revolute {
            *q = j.clamp(0.0);
        }
    }
    let sc = scenario(
        &joints,
        &[],
        &[Waypoint::at([1000.0, 0.0, 0.0])],
        Settings::default(),
    );
    let Run { outcome, .. } = run_checked(&sc, &stretched);
    assert_eq!(outcome, Outcome::Stalled);
}

#[test]
fn a_target_at_the_current_pose_is_reached_at_once() {
    let joints = pips::joints();
    let home = pips::home();
    let (p, r) = pose_of(&joints, &home);
    for waypoint in [Waypoint::at(p), Waypoint::pose(p, r)] {
        let sc = scenario(&joints, &[], &[waypoint], Settings::default());
        let mut planner = Planner::new(&sc, &home).unwrap();
        let start = planner.last_report();
        assert!(start.v.is_finite() && start.v < 1e-6, "{start:?}");
        let report = planner.step(&sc).unwrap();
        assert_eq!(report.phase, Phase::Done(Outcome::Reached));
        assert_eq!(report.step, 0, "no step was needed");
        assert_eq!(planner.joints(), &home);
        assert!(planner.rates().iter().all(|r| *r == 0.0));
        assert!(report.v.is_finite() && report.position_error.is_finite());
    }
    // Tolerances far below f32 resolution. The target is the f64 pose
    // rounded to f32; the planner's f32 kinematics put the hand an ulp or so
    // off it, and no f32 step can close an error of 1e-12: the run cannot
    // end `Reached`. It must end `Stalled`, for want of progress, before the
    // cap, without NaN, and without wandering off the pose it was at.
    let settings = Settings {
        position_tolerance: 1e-12,
        orientation_tolerance: 1e-12,
        max_steps: 200,
        ..Settings::default()
    };
    let sc = scenario(&joints, &[], &[Waypoint::pose(p, r)], settings);
    let start = *Planner::new(&sc, &home).unwrap().last_report();
    assert!(
        start.position_error > 1e-12 || start.orientation_error > 1e-12,
        "{start:?}"
    );
    let Run {
        outcome, joints: q, ..
    } = run_checked(&sc, &home);
    assert_eq!(outcome, Outcome::Stalled);
    let d = miss(&joints, &q, p);
    assert!(d < 1e-3, "wandered {d} in from the target");
}

#[test]
fn coincident_avoidance_points_give_finite_gradients() {
    // Zero-length links (a = d = 0) put every point of a link, and the next
    // joint's points, on one spot; three interior points per link make four
    // coincident points each. An obstacle next to them.
    let joints = [
        Joint::revolute(0.0, 10.0, 0.0, -2.8, 2.8, 0.5),
        Joint::revolute(0.0, 0.0, 0.0, -2.8, 2.8, 0.5),
        Joint::revolute(std::f32::consts::FRAC_PI_2, 0.0, 0.0, -2.8, 2.8, 0.5),
        Joint::revolute(0.0, 10.0, 0.0, -2.8, 2.8, 0.5),
        Joint::prismatic(0.0, 0.0, 0.0, 0.0, 5.0, 1.0),
        Joint::revolute(0.0, 5.0, 0.0, -2.8, 2.8, 0.5),
    ];
    let mut settings = Settings::default();
    settings.avoidance.points_per_link = 3;
    settings.avoidance.joint_margin = 0.5;
    settings.avoidance.link_margin = 0.5;
    settings.avoidance.influence_distance = 5.0;
    settings.max_steps = 3000;
    let start = [0.5, 0.0, 0.0, 0.5, 0.0, 0.0];
    let (hand, _) = pose_of(&joints, &start);
    // A ball 4 in from the coincident points at the elbow (10 in along the first link).
    let elbow = [10.0 * 0.5f32.cos(), 10.0 * 0.5f32.sin(), 0.0];
    let ball = SuperEllipsoid::aligned([elbow[0], elbow[1] - 4.0, 0.0], [1.5; 3], 2.0);
    let target = Waypoint::at([hand[0] - 8.0, hand[1] - 6.0, hand[2]]);
    let sc = scenario(&joints, &[ball], &[target], settings);
    let planner = Planner::new(&sc, &start).unwrap();
    assert!(planner.obstacle_gradient().iter().all(|m| m.is_finite()));
    // The target is in free space and the ball is off the way there: the
    // run must get there.
    let run = run_checked(&sc, &start);
    assert_eq!(run.outcome, Outcome::Reached);
    assert!(run.last.position_error <= settings.position_tolerance);
    let d = miss(&joints, &run.joints, target.position);
    assert!(d <= settings.position_tolerance + 1e-4, "{d}");
}

#[test]
fn an_obstacle_touching_the_start_is_refused_and_one_just_clear_is_avoided() {
    // The planar arm stretched along x: its tip at (30, 0, 0) is a joint point
    // (margin 6 by default). A ball of radius r centred at (30, y, 0): C = 1
    // for the inflated ball exactly when y = r + 6.
    let settings = Settings::default();
    let target = Waypoint::at([0.0, 25.0, 0.0]);
    // Touching (C - 1 = 0 at the tip): refused, it names the tip and the ball.
    let touching = SuperEllipsoid::aligned([30.0, 8.0, 0.0], [2.0; 3], 2.0);
    let sc = scenario(&planar(), &[touching], &[target], settings);
    let err = Planner::new(&sc, &[0.0; 3]).unwrap_err();
    assert!(
        matches!(err, StartError::InObstacle { obstacle: 0, .. }),
        "{err:?}"
    );
    // Just clear (C - 1 = 1e-3 at the tip): accepted, and the run never enters.
    let y = 8.0 * (1.0f32 + 1e-3).sqrt();
    let just_clear = SuperEllipsoid::aligned([30.0, y, 0.0], [2.0; 3], 2.0);
    let sc = scenario(&planar(), &[just_clear], &[target], settings);
    // A way round exists (fold the hand in under the ball, then swing up):
    // the run must get there, escaping if it must.
    let run = run_checked(&sc, &[0.0; 3]);
    assert_eq!(run.outcome, Outcome::Reached);
    assert!(run.last.position_error <= settings.position_tolerance);
    let d = miss(&planar(), &run.joints, target.position);
    assert!(d <= settings.position_tolerance + 1e-4, "{d}");
}

/// The PIPS problem of `pips_target` with one ball near the path, scaled by
/// `k` (1 = inches, 1/39.37 = metres): every length, prismatic limit and rate,
/// margin, tolerance and length scale of the settings.
fn pips_scaled(k: f32) -> (Sc, Vec<f32>) {
    let mut joints = pips::joints();
    for j in &mut joints {
        j.a *= k;
        j.d *= k;
        if j.kind == JointKind::Prismatic {
            j.min *= k;
            j.max *= k;
            j.max_rate *= k;
        }
    }
    let mut start = pips::home().to_vec();
    for (q, j) in start.iter_mut().zip(&pips::joints()) {
        if j.kind == JointKind::Prismatic {
            *q *= k;
        }
    }
    let inches = pips::joints();
    let mut goal = pips::home();
    for (q, j) in goal.iter_mut().zip(&inches) {
        if j.kind == JointKind::Revolute {
            *q = j.clamp(*q + 0.3);
        }
    }
    let (target, rotation) = pose_of(&inches, &goal);
    let (home, _) = pose_of(&inches, &pips::home());
    let mid = [0, 1, 2].map(|i| 0.5 * (home[i] + target[i]) * k);
    let ball = SuperEllipsoid::aligned(mid, [4.0 * k; 3], 2.0);
    let mut s = Settings::default();
    s.fine_radius *= k;
    s.position_tolerance *= k;
    s.law.orientation_scale *= k;
    s.law.approach_radius *= k;
    s.avoidance.joint_margin *= k;
    s.avoidance.link_margin *= k;
    s.avoidance.influence_distance *= k;
    let waypoint = Waypoint::pose(target.map(|x| x * k), rotation);
    (scenario(&joints, &[ball], &[waypoint], s), start)
}

#[test]
fn metres_and_inches_give_the_same_outcome() {
    let (inches, start_in) = pips_scaled(1.0);
    let (metres, start_m) = pips_scaled(1.0 / 39.37);
    let Run {
        outcome: outcome_in,
        steps: steps_in,
        ..
    } = run_checked(&inches, &start_in);
    let Run {
        outcome: outcome_m,
        steps: steps_m,
        ..
    } = run_checked(&metres, &start_m);
    assert_eq!(outcome_in, Outcome::Reached);
    assert_eq!(outcome_m, outcome_in);
    // Not the same path, though: the drive direction normalises the gradient
    // G, whose revolute entries scale as length^2 and prismatic ones as
    // length, so a chain mixing both kinds shares its motion differently in
    // another unit (PIPS: 536 steps in inches, 757 in metres). A chain of one
    // kind is scale-invariant (`tiny_and_huge_scales_stay_finite`).
    assert!(
        steps_in.abs_diff(steps_m) < steps_in,
        "{steps_in} vs {steps_m}"
    );
    // Margins are lengths: the inch margins read as metres make an unrelated
    // (and here impossible) problem, refused at the start, not a NaN.
    let (_, start_m) = pips_scaled(1.0 / 39.37);
    let (mut bad, _) = pips_scaled(1.0 / 39.37);
    let robot = bad.robot().clone();
    let mut s = *bad.settings();
    s.avoidance = AvoidanceSettings::default();
    let obstacles: Vec<SuperEllipsoid> = bad
        .obstacles()
        .iter()
        .map(|o| o.source().super_ellipsoid().expect("a super-ellipsoid"))
        .collect();
    bad = Sc::new(
        robot,
        &obstacles,
        &Mission::new(&bad.waypoints().collect::<Vec<_>>(), s).unwrap(),
    )
    .unwrap();
    // Read as metres, the default margins (6 at a joint, 3 along a link)
    // inflate the 0.1 m ball over the arm's start: refused, and nothing else.
    let refused = Planner::new(&bad, &start_m).map(|_| ());
    assert!(
        matches!(refused, Err(StartError::InObstacle { .. })),
        "{refused:?}"
    );
}

#[test]
fn tiny_and_huge_scales_stay_finite() {
    // The revolute planar arm past a post, in units 1e-3 and 1e2 times
    // inches: the same outcome and, as every term then scales alike, the same
    // number of steps up to f32 rounding; no NaN, no overflow in V.
    let case = |k: f32| {
        let joints = planar_scaled(k);
        let mut s = planar_settings(k);
        s.fine_radius *= k;
        s.position_tolerance *= k;
        s.law.orientation_scale *= k;
        s.law.approach_radius *= k;
        let post =
            SuperEllipsoid::aligned([22.0 * k, 8.0 * k, 0.0], [1.0 * k, 1.0 * k, 50.0 * k], 2.0);
        let sc = scenario(
            &joints,
            &[post],
            &[Waypoint::at([15.0 * k, 15.0 * k, 0.0])],
            s,
        );
        run_checked(&sc, &[0.0, 0.3, 0.3])
    };
    let Run { outcome, steps, .. } = case(1.0);
    assert_eq!(outcome, Outcome::Reached);
    for k in [1e-3f32, 1.0 / 39.37, 1e2] {
        let Run {
            outcome: o,
            steps: n,
            ..
        } = case(k);
        assert_eq!(o, outcome, "scale {k}");
        assert!(
            n.abs_diff(steps) * 20 <= steps,
            "scale {k}: {n} steps, {steps} in inches"
        );
    }
}
