//! Convex hull obstacles in whole plans: the scenario's hull list and its
//! errors, and a plan past a box given as the hull of its corners, checked
//! against an `f64` box distance (independent of the core's GJK) at every
//! step, and against the same box as a primitive.

use capp_core::kinematics::{forward_kinematics, Frames};
use capp_core::obstacle::{HullError, MAX_HULLS};
use capp_core::*;

type Sc = Scenario<18, 4, 3>;

const HALF: [f32; 3] = [12.0, 10.0, 8.0];

fn corners(half: [f32; 3]) -> [[f32; 3]; 8] {
    let mut corners = [[0.0f32; 3]; 8];
    for (i, corner) in corners.iter_mut().enumerate() {
        for (axis, h) in half.into_iter().enumerate() {
            corner[axis] = if i >> axis & 1 == 1 { h } else { -h };
        }
    }
    corners
}

/// PIPS's end effector at a nearby configuration, and a point of the arm
/// half-way there, where the box goes (in the way: the plan takes 77
/// steps round it, 35 without).
fn target_and_box_centre() -> (Waypoint, [f32; 3]) {
    let robot = pips::robot::<18>().unwrap();
    let mut frames = Frames::<18>::default();
    let mut q = pips::home();
    forward_kinematics(&robot, &q, &mut frames);
    let start = frames.end_position();
    q[0] += 0.9;
    q[5] += 0.6;
    q[9] -= 0.5;
    forward_kinematics(&robot, &q, &mut frames);
    let p = frames.end_position();
    let mid = (start + p) * 0.5;
    (Waypoint::at([p.x, p.y, p.z]), [mid.x, mid.y, mid.z])
}

fn box_distance64(centre: [f32; 3], p: [f64; 3]) -> f64 {
    let mut out = 0.0f64;
    let mut inside = f64::NEG_INFINITY;
    for axis in 0..3 {
        let e = (p[axis] - centre[axis] as f64).abs() - HALF[axis] as f64;
        out += e.max(0.0).powi(2);
        inside = inside.max(e);
    }
    if out > 0.0 {
        out.sqrt()
    } else {
        inside
    }
}

fn plan(shape: Shape, hulls: &[&[[f32; 3]]]) -> (Outcome, Vec<Vec<f32>>, [f32; 3]) {
    let (target, centre) = target_and_box_centre();
    let mut scenario = Sc::empty();
    scenario
        .init_with_hulls(
            &pips::joints(),
            &robot::Placement::IDENTITY,
            &[Solid::aligned(centre, shape)],
            hulls,
            &[target],
            Settings::default(),
        )
        .unwrap();
    let mut planner = Planner::new(&scenario, &pips::home()).unwrap();
    let mut rows = vec![planner.joints().to_vec()];
    let outcome = planner
        .run(&scenario, |p, _| rows.push(p.joints().to_vec()))
        .unwrap();
    (outcome, rows, centre)
}

#[test]
fn a_plan_past_a_box_hull_keeps_the_margin_and_matches_the_box() {
    let box_corners = corners(HALF);
    let (outcome, rows, centre) = plan(Shape::Convex { hull: 0 }, &[&box_corners]);
    assert_eq!(outcome, Outcome::Reached);
    let robot = pips::robot::<18>().unwrap();
    let margin = Settings::default().avoidance.joint_margin as f64;
    let mut frames = Frames::<18>::default();
    let mut closest = f64::INFINITY;
    for q in &rows {
        forward_kinematics(&robot, q, &mut frames);
        for j in 0..18 {
            let o = frames.link_end(j);
            let d = box_distance64(centre, [o.x as f64, o.y as f64, o.z as f64]);
            assert!(d >= margin - 1e-3, "joint {j} at {d} from the box");
            closest = closest.min(d);
        }
    }
    let influence = Settings::default().avoidance.influence_distance as f64;
    assert!(
        closest < margin + influence,
        "the box never mattered ({closest})"
    );
    // The same box as a primitive: C, its gradient and the bounds agree
    // to rounding, so the plans end alike.
    let (primitive_outcome, primitive_rows, _) = plan(Shape::Cuboid { half_extents: HALF }, &[]);
    assert_eq!(primitive_outcome, outcome);
    let (a, b) = (rows.last().unwrap(), primitive_rows.last().unwrap());
    let apart = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f32::max);
    assert!(apart < 1e-2, "final configurations {apart} rad apart");
}

#[test]
fn the_hull_list_is_checked() {
    let (target, centre) = target_and_box_centre();
    let good = corners(HALF);
    let flat = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.0],
    ];
    let init = |obstacles: &[Solid], hulls: &[&[[f32; 3]]]| {
        Sc::empty().init_with_hulls(
            &pips::joints(),
            &robot::Placement::IDENTITY,
            obstacles,
            hulls,
            &[target],
            Settings::default(),
        )
    };
    let hull = |i| Solid::aligned(centre, Shape::Convex { hull: i });
    assert!(init(&[hull(1)], &[&good, &good]).is_ok());
    assert_eq!(
        init(&[hull(0)], &[&good, &flat]),
        Err(ScenarioError::Obstacle(ObstacleError::BadHull {
            hull: 1,
            why: HullError::Flat
        }))
    );
    assert_eq!(
        init(&[hull(2)], &[&good, &good]),
        Err(ScenarioError::Obstacle(ObstacleError::NoSuchHull {
            obstacle: 0
        }))
    );
    let many: Vec<&[[f32; 3]]> = (0..=MAX_HULLS).map(|_| &good[..]).collect();
    assert_eq!(
        init(&[], &many),
        Err(ScenarioError::Obstacle(ObstacleError::TooManyHulls {
            capacity: MAX_HULLS
        }))
    );
    let five = [good[0], good[1], good[2]];
    assert_eq!(
        init(&[], &[&five]),
        Err(ScenarioError::Obstacle(ObstacleError::BadHull {
            hull: 0,
            why: HullError::TooFewVertices
        }))
    );
}
