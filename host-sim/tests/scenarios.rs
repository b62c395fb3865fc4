//! The shipped scenarios run end to end, reach their targets (the dead end
//! stalls; the escape scenario reaches only by escaping), and the independent checker accepts their trajectories; the
//! legacy `input.dat` and its TOML twin give the same trajectory; the checker
//! rejects trajectories made to collide or to break a limit
//! (`self_collision.rs`: to pass one link through another).

use std::path::{Path, PathBuf};

use capp_core::Outcome;
use capp_sim::check::{self, ViolationKind};
use capp_sim::output::rows_csv;
use capp_sim::plan::{self, RunResult};
use capp_sim::trajectory::{self, Trajectory};
use capp_sim::Problem;

fn scenario(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenarios")
        .join(name)
}

fn plan(name: &str) -> (Problem, RunResult) {
    let problem = Problem::load(&scenario(name)).unwrap_or_else(|e| panic!("{e}"));
    let s = problem.validate().unwrap();
    let result = plan::run(&problem, &s, |_| {}).unwrap();
    (problem, result)
}

fn as_trajectory(problem: &Problem, result: &RunResult) -> Trajectory {
    let text = rows_csv(problem.joints.len(), &result.rows).unwrap();
    trajectory::parse(&text, Path::new("trajectory.csv")).unwrap()
}

fn runs_and_checks(name: &str, expected: Outcome) -> (Problem, Trajectory) {
    let (problem, result) = plan(name);
    assert_eq!(result.outcome, expected, "{name}");
    let t = as_trajectory(&problem, &result);
    let report = check::check(&problem, &t);
    assert!(report.accepted(), "{name}: {report}");
    // Self-collision is on in every shipped scenario, and checked.
    assert!(report.self_checked, "{name}: {report}");
    assert_eq!(report.self_collisions, 0, "{name}: {report}");
    assert_eq!(
        report.reaches_target,
        expected == Outcome::Reached,
        "{name}: {report}"
    );
    (problem, t)
}

#[test]
fn pips_free_space_reaches() {
    runs_and_checks("pips_free_space.toml", Outcome::Reached);
}

#[test]
fn pips_payload_bay_reaches_around_the_payload() {
    let (problem, t) = runs_and_checks("pips_payload_bay.toml", Outcome::Reached);
    // PIPS checks pairs of links, and the checker names the closest.
    let report = check::check(&problem, &t);
    let closest = report.closest_links.expect("checked link pairs");
    assert!(closest.pair.gap > 0.0, "{report}");
    assert!(
        report.to_string().contains("closest link pair: links"),
        "{report}"
    );
    // The payload actually constrains the path.
    let closest = closest_clearance(&t);
    assert!(closest < 1.0, "closest approach C-1 = {closest}");
}

/// The least `C - 1` over a trajectory's rows.
fn closest_clearance(t: &Trajectory) -> f64 {
    t.rows
        .iter()
        .filter_map(|r| r.clearance)
        .fold(f64::INFINITY, f64::min)
}

/// Motion time of a run: the sum of its steps' `h`, seconds.
fn motion_time(result: &RunResult) -> f64 {
    result.rows.iter().map(|r| r.h as f64).sum()
}

#[test]
fn pips_payload_bay_cad_reaches_among_true_boxes_and_a_true_cylinder() {
    use capp_core::Shape;
    let (problem, _) = runs_and_checks("pips_payload_bay_cad.toml", Outcome::Reached);
    // The same bay as `pips_payload_bay.toml`, from CAD primitives.
    let shapes: Vec<Shape> = problem.obstacles.iter().map(|o| o.shape).collect();
    assert!(matches!(shapes[0], Shape::Cuboid { .. }), "{shapes:?}");
    assert!(matches!(shapes[1], Shape::Cylinder { .. }), "{shapes:?}");
    assert!(matches!(shapes[2], Shape::Cuboid { .. }), "{shapes:?}");
    let (bay, se) = plan("pips_payload_bay.toml");
    assert_eq!(problem.start, bay.start);
    assert_eq!(problem.joints.len(), bay.joints.len());
    // The target: no more than 20 % slower than the
    // super-ellipsoid bay.
    let (_, cad) = plan("pips_payload_bay_cad.toml");
    assert!(
        motion_time(&cad) <= 1.2 * motion_time(&se),
        "{} s against {} s",
        motion_time(&cad),
        motion_time(&se)
    );
}

#[test]
fn pips_payload_bay_mesh_reaches_past_a_bracket_from_an_stl() {
    use capp_core::Shape;
    let (problem, t) = runs_and_checks("pips_payload_bay_mesh.toml", Outcome::Reached);
    // The bracket is an L (its STL closed): split along its own faces into
    // two boxes, the bar and the upright, which hold it exactly (its hull
    // would fill the notch, 29 % of the hull), no hull slot taken.
    let n = problem.obstacles.len();
    assert!(problem.hulls.is_empty());
    assert_eq!(
        problem.obstacle_names[n - 2..],
        ["bracket piece 1", "bracket piece 2"]
    );
    let mut halves: Vec<[f32; 3]> = problem.obstacles[n - 2..]
        .iter()
        .map(|o| match o.shape {
            Shape::Cuboid { half_extents } => half_extents,
            other => panic!("{other:?}"),
        })
        .collect();
    halves.sort_by(|a, b| a.partial_cmp(b).unwrap());
    for (got, want) in halves.iter().zip([[2.0, 3.0, 6.0], [8.0, 2.0, 6.0]]) {
        assert!(
            (0..3).all(|k| got[k] >= want[k] && got[k] - want[k] < 1e-4),
            "{got:?}"
        );
    }
    assert_eq!(
        problem.notes,
        ["obstacle \"bracket\" (line 45): it is not convex: split along its own faces into 2 convex pieces (2 boxes), which hold it exactly"]
    );
    let (_, without) = plan("pips_payload_bay_cad.toml");
    let (_, with) = plan("pips_payload_bay_mesh.toml");
    assert_ne!(
        with.rows.len(),
        without.rows.len(),
        "the bracket changed nothing"
    );
    assert!(!t.rows.is_empty());
}

/// `problem` has `n` obstacles, every one a box, and no hull.
fn assert_boxes_only(problem: &Problem, n: usize) {
    assert_eq!(problem.obstacles.len(), n);
    assert!(problem.hulls.is_empty());
    assert!(problem
        .obstacles
        .iter()
        .all(|o| matches!(o.shape, capp_core::Shape::Cuboid { .. })));
}

#[test]
fn panda_shelf_mesh_reaches_into_a_shelf_of_ten_boards_from_one_stl() {
    let (problem, t) = runs_and_checks("panda_shelf_mesh.toml", Outcome::Reached);
    // Ten separate parts, more than a scenario's 8 hulls: each board is a
    // box, none a hull.
    assert_boxes_only(&problem, 10);
    assert_eq!(problem.obstacle_names[9], "shelf part 10");
    // The hand goes in between the boards: the arm comes within the
    // boards' influence.
    let closest = closest_clearance(&t);
    assert!(closest < 1.0, "closest approach C-1 = {closest}");
}

#[test]
fn panda_tote_mesh_reaches_into_a_tote_from_one_closed_stl() {
    let (problem, t) = runs_and_checks("panda_tote_mesh.toml", Outcome::Reached);
    // One closed solid whose hull (a box) would hold the target: split into
    // its floor and four walls, each a box.
    assert_boxes_only(&problem, 5);
    assert_eq!(
        problem.notes,
        ["obstacle \"tote\" (line 32): it is not convex: split along its own faces into 5 convex pieces (5 boxes), which hold it exactly"]
    );
    // The hand goes in: within the floor's and walls' influence.
    assert!(closest_clearance(&t) < 5.0, "{}", closest_clearance(&t));
}

#[test]
fn pips_dead_end_stalls() {
    runs_and_checks("pips_dead_end.toml", Outcome::Stalled);
}

#[test]
fn pips_escape_reaches_by_a_detour_and_stalls_without_escapes() {
    use capp_core::escape::EscapeState;
    let (problem, result) = plan("pips_escape.toml");
    assert_eq!(result.outcome, Outcome::Reached);
    let escaping = result
        .rows
        .iter()
        .filter(|r| !matches!(r.escape, Some(EscapeState::Descending { .. }) | None))
        .count();
    assert!(escaping > 0, "reached without escaping");
    let t = as_trajectory(&problem, &result);
    let report = check::check(&problem, &t);
    assert!(report.accepted() && report.reaches_target, "{report}");

    // The same dead end without the escape: the law alone stalls there.
    let mut alone = problem.clone();
    alone.settings.escape.attempts = 0;
    let s = alone.validate().unwrap();
    let stalled = plan::run(&alone, &s, |_| {}).unwrap();
    assert_eq!(stalled.outcome, Outcome::Stalled);
    let last = stalled.rows.last().unwrap();
    assert!(last.position_error > 1.0, "{}", last.position_error);
}

/// The search (`capp_core::escape::search`) on a dead end two detours do not pass:
/// the arm holds still while it runs (every searching row repeats the
/// configuration, with no time step), then walks the path it found and the
/// law finishes; the checker accepts the whole run. Without searches the
/// same dead end takes ten times the motion.
#[test]
fn planar_search_reaches_by_a_searched_path() {
    use capp_core::escape::EscapeState;
    let (problem, result) = plan("planar_search.toml");
    assert_eq!(result.outcome, Outcome::Reached);
    let searching = |e: &Option<EscapeState>| matches!(e, Some(EscapeState::Searching { .. }));
    let following = |e: &Option<EscapeState>| matches!(e, Some(EscapeState::Following { .. }));
    let rows = &result.rows;
    let first = rows
        .iter()
        .position(|r| searching(&r.escape))
        .expect("a search");
    // A row records the state after its step: the steps after a searching
    // row hold the arm still until the search ends.
    let mut held = 0;
    for w in rows[first..].windows(2) {
        if !searching(&w[0].escape) {
            break;
        }
        assert_eq!(w[1].h, 0.0, "step {}", w[1].step);
        assert_eq!(w[1].q, w[0].q, "step {}", w[1].step);
        held += 1;
    }
    assert!(held > 0);
    let path = rows.iter().filter(|r| following(&r.escape)).count();
    assert!(path > 5, "{path} rows along the searched path");
    let moved: f32 = rows
        .iter()
        .skip_while(|r| !following(&r.escape))
        .take_while(|r| following(&r.escape))
        .map(|r| r.h)
        .sum();
    assert!(moved > 0.0);
    let t = as_trajectory(&problem, &result);
    let report = check::check(&problem, &t);
    assert!(report.accepted() && report.reaches_target, "{report}");

    let mut without = problem.clone();
    without.settings.escape.searches = 0;
    let s = without.validate().unwrap();
    let walked = plan::run(&without, &s, |_| {}).unwrap();
    let time = |r: &RunResult| r.rows.iter().map(|r| r.h as f64).sum::<f64>();
    assert!(
        walked.outcome != Outcome::Reached || time(&walked) > 3.0 * time(&result),
        "{:?} in {} s without searches, {} s with",
        walked.outcome,
        time(&walked),
        time(&result)
    );
}

/// The same dead end with the waypoint given as a joint configuration (the
/// configuration `planar_search.toml`'s pose came from): the search takes
/// it as its goal configuration as it is, finds a path, and the arm ends
/// at that configuration (within the joint goal's tolerance, a twentieth of
/// a step at the rate limits); the checker accepts the run. (Descending
/// toward its pose instead, as the search did before, all four searches
/// found no path and the run stalled after 64 attempts.)
#[test]
fn a_joint_goal_behind_a_post_is_the_search_goal() {
    use capp_core::escape::EscapeState;
    let mut problem = Problem::load(&scenario("planar_search.toml")).unwrap();
    let goal = vec![2.6397583f32, 0.60187143, 1.4365302];
    problem.joint_goals = vec![(0, goal.clone())];
    let s = problem.validate().unwrap();
    let result = plan::run(&problem, &s, |_| {}).unwrap();
    assert_eq!(result.outcome, Outcome::Reached);
    let following = |e: &Option<EscapeState>| matches!(e, Some(EscapeState::Following { .. }));
    assert!(
        result.rows.iter().any(|r| following(&r.escape)),
        "a searched path"
    );
    let last = result.rows.last().unwrap();
    let dt = problem.settings.time_step_s;
    for (j, (q, g)) in last.q.iter().zip(&goal).enumerate() {
        let rate = problem.joints[j].max_rate;
        assert!(
            (q - g).abs() <= 0.05 * dt * rate + 1e-6,
            "joint {j}: {q} for {g}"
        );
    }
    let report = check::check(&problem, &as_trajectory(&problem, &result));
    assert!(report.accepted() && report.reaches_target, "{report}");
}

#[test]
fn planar_arm_reaches() {
    runs_and_checks("planar_arm.toml", Outcome::Reached);
}

#[test]
fn legacy_input_and_its_toml_twin_give_the_same_trajectory() {
    let (legacy, a) = plan("legacy/input.dat");
    let (twin, b) = plan("legacy/twin.toml");
    assert_eq!(a.outcome, Outcome::Reached);
    assert_eq!(legacy.joints, twin.joints);
    let n = legacy.joints.len();
    assert_eq!(rows_csv(n, &a.rows).unwrap(), rows_csv(n, &b.rows).unwrap());
    let report = check::check(&legacy, &as_trajectory(&legacy, &a));
    assert!(report.accepted(), "{report}");
}

#[test]
fn joints_dat_has_the_listing_layout() {
    let (problem, result) = plan("legacy/input.dat");
    let text = capp_sim::output::joints_dat(result.setpoints());
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 2 * result.setpoints().count());
    // 18 joints: 9 values a line, "%f " each.
    assert_eq!(lines[0].split_whitespace().count(), 9);
    assert_eq!(
        lines[0],
        "1.570796 0.000000 20.000000 1.000000 0.000000 0.000000 0.000000 0.000000 0.000000 "
    );
    assert_eq!(problem.start.len(), 18);
}

fn planar() -> (Problem, Trajectory) {
    let (problem, result) = plan("planar_arm.toml");
    let t = as_trajectory(&problem, &result);
    (problem, t)
}

#[test]
fn check_rejects_a_joint_beyond_its_limit() {
    let (problem, mut t) = planar();
    let k = t.rows.len() / 2;
    t.rows[k].q[1] = problem.joints[1].max as f64 + 0.01;
    let report = check::check(&problem, &t);
    assert!(!report.accepted());
    assert!(report.has(ViolationKind::JointLimit), "{report}");
    assert!(
        report.to_string().contains("joint 2 (\"elbow\")"),
        "{report}"
    );
}

#[test]
fn check_rejects_a_rate_violation() {
    let (problem, mut t) = planar();
    let k = t.rows.len() / 3;
    // Twice as far as the step allows on the wrist.
    let allowed = t.rows[k].h * problem.joints[2].max_rate as f64;
    t.rows[k].q[2] = t.rows[k - 1].q[2] + 2.0 * allowed + 1e-3;
    let report = check::check(&problem, &t);
    assert!(report.has(ViolationKind::RateLimit), "{report}");
}

#[test]
fn check_rejects_a_collision() {
    let (problem, mut t) = planar();
    // Point the straight arm at the post: its links pass through it.
    let k = t.rows.len() / 2;
    let angle = (0.42f64).atan2(0.9);
    t.rows[k].q = vec![angle, 0.0, 0.0];
    t.rows[k].position = None;
    let report = check::check(&problem, &t);
    assert!(report.has(ViolationKind::Collision), "{report}");
    assert!(report.to_string().contains("\"post\""), "{report}");
}

#[test]
fn check_rejects_a_wrong_recorded_position_and_a_wrong_start() {
    let (problem, mut t) = planar();
    t.rows[3].position = Some([5.0, 5.0, 5.0]);
    t.rows[0].q[0] += 0.1;
    let report = check::check(&problem, &t);
    assert!(report.has(ViolationKind::Kinematics), "{report}");
    assert!(report.has(ViolationKind::Shape), "{report}");
}
