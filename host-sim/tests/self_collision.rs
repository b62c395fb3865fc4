//! Self-collision in the independent checker: the `f64` segment distance
//! against brute force, the links' motion bound against the motion itself,
//! the checker's capsule gaps against the planner's own chords (the same
//! links, numbered the same way), and `capp check` rejecting a trajectory
//! that passes one link through another, at rows and between rows.

use std::path::Path;

use capp_sim::check::{self, ViolationKind};
use capp_sim::geometry::{segment_distance, Geometry, SWEEP_FRACTION};
use capp_sim::input::scenario_file;
use capp_sim::trajectory::{Trajectory, TrajectoryRow};
use capp_sim::Problem;

mod common;

use common::{random_q, Rng};

/// The tests' points.
trait Points {
    fn point(&mut self, size: f64) -> [f64; 3];
}

impl Points for Rng {
    fn point(&mut self, size: f64) -> [f64; 3] {
        [
            self.range(-size, size),
            self.range(-size, size),
            self.range(-size, size),
        ]
    }
}

fn at(p0: [f64; 3], p1: [f64; 3], s: f64) -> [f64; 3] {
    [
        p0[0] + s * (p1[0] - p0[0]),
        p0[1] + s * (p1[1] - p0[1]),
        p0[2] + s * (p1[2] - p0[2]),
    ]
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// The minimum over `[0, 1]` of a convex `f`, by golden section.
fn golden(f: impl Fn(f64) -> f64) -> f64 {
    let r = (5.0f64.sqrt() - 1.0) / 2.0;
    let (mut a, mut b) = (0.0, 1.0);
    let (mut c, mut d) = (b - r * (b - a), a + r * (b - a));
    let (mut fc, mut fd) = (f(c), f(d));
    for _ in 0..70 {
        if fc < fd {
            b = d;
            d = c;
            fd = fc;
            c = b - r * (b - a);
            fc = f(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + r * (b - a);
            fd = f(d);
        }
    }
    fc.min(fd).min(f(0.0)).min(f(1.0))
}

/// Brute force: `|P(s) - Q(t)|` is convex on the square, so a golden-section
/// search over `s` of golden-section searches over `t` finds its minimum (no
/// closed form, no projection).
fn reference(p0: [f64; 3], p1: [f64; 3], q0: [f64; 3], q1: [f64; 3]) -> f64 {
    golden(|s| {
        let p = at(p0, p1, s);
        golden(|t| dist(p, at(q0, q1, t)))
    })
}

/// The smallest distance over a grid of point pairs: never below the truth.
fn grid(p0: [f64; 3], p1: [f64; 3], q0: [f64; 3], q1: [f64; 3]) -> f64 {
    const K: usize = 24;
    let mut best = f64::INFINITY;
    for i in 0..=K {
        let p = at(p0, p1, i as f64 / K as f64);
        for j in 0..=K {
            best = best.min(dist(p, at(q0, q1, j as f64 / K as f64)));
        }
    }
    best
}

fn agrees(what: &str, p0: [f64; 3], p1: [f64; 3], q0: [f64; 3], q1: [f64; 3]) {
    let d = segment_distance(p0, p1, q0, q1);
    let r = reference(p0, p1, q0, q1);
    let size = [p0, p1, q0, q1]
        .iter()
        .flatten()
        .fold(1.0f64, |m, x| m.max(x.abs()));
    assert!(
        (d.distance - r).abs() <= 1e-9 * size,
        "{what}: {p0:?} {p1:?} / {q0:?} {q1:?}: {} against {r}",
        d.distance
    );
    assert!(d.distance <= grid(p0, p1, q0, q1) + 1e-12 * size, "{what}");
    // The reported parameters attain it.
    assert!(
        (0.0..=1.0).contains(&d.s) && (0.0..=1.0).contains(&d.t),
        "{what}"
    );
    let attained = dist(at(p0, p1, d.s), at(q0, q1, d.t));
    assert!((attained - d.distance).abs() <= 1e-12 * size, "{what}");
    // Symmetric, and independent of each segment's direction.
    for (e, how) in [
        (segment_distance(q0, q1, p0, p1), "swapped"),
        (segment_distance(p1, p0, q1, q0), "reversed"),
    ] {
        assert!(
            (e.distance - d.distance).abs() <= 1e-9 * size,
            "{what} {how}: {} against {}",
            e.distance,
            d.distance
        );
    }
}

#[test]
fn segment_distance_matches_brute_force() {
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    for i in 0..600 {
        // General position, at several scales.
        let size = [1.0, 100.0, 1e-3][i % 3];
        let (p0, p1, q0, q1) = (
            rng.point(size),
            rng.point(size),
            rng.point(size),
            rng.point(size),
        );
        agrees("random", p0, p1, q0, q1);

        // Parallel and anti-parallel, overlapping or not, and collinear.
        let u = [p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]];
        let k = rng.range(-2.0, 2.0);
        let off = if i % 4 == 0 {
            [0.0; 3]
        } else {
            rng.point(size)
        };
        let shift = rng.range(-1.5, 1.5);
        let q0p = [
            p0[0] + off[0] + shift * u[0],
            p0[1] + off[1] + shift * u[1],
            p0[2] + off[2] + shift * u[2],
        ];
        let q1p = [q0p[0] + k * u[0], q0p[1] + k * u[1], q0p[2] + k * u[2]];
        agrees("parallel", p0, p1, q0p, q1p);

        // Nearly parallel (an angle down to 1e-9 rad), crossing or not.
        let tilt = 10f64.powf(-rng.range(3.0, 9.0));
        let n = rng.point(1.0);
        let q1t = [
            q1p[0] + tilt * size * n[0],
            q1p[1] + tilt * size * n[1],
            q1p[2] + tilt * size * n[2],
        ];
        agrees("nearly parallel", p0, p1, q0p, q1t);

        // Crossing at a tiny angle.
        let c = at(p0, p1, rng.next());
        let w = [
            u[0] + tilt * n[0] * size,
            u[1] + tilt * n[1] * size,
            u[2] + tilt * n[2] * size,
        ];
        let (a, b) = (rng.range(0.05, 1.0), rng.range(0.05, 1.0));
        let q0c = [c[0] - a * w[0], c[1] - a * w[1], c[2] - a * w[2]];
        let q1c = [c[0] + b * w[0], c[1] + b * w[1], c[2] + b * w[2]];
        agrees("crossing nearly parallel", p0, p1, q0c, q1c);
        assert!(segment_distance(p0, p1, q0c, q1c).distance <= 1e-9 * size);

        // Crossing: the second segment passes through a point of the first.
        let c = at(p0, p1, rng.next());
        let dir = rng.point(size);
        let (a, b) = (rng.range(0.05, 1.0), rng.range(0.05, 1.0));
        let q0c = [c[0] - a * dir[0], c[1] - a * dir[1], c[2] - a * dir[2]];
        let q1c = [c[0] + b * dir[0], c[1] + b * dir[1], c[2] + b * dir[2]];
        agrees("crossing", p0, p1, q0c, q1c);
        assert!(segment_distance(p0, p1, q0c, q1c).distance <= 1e-9 * size);

        // Degenerate: one or both of zero length; touching at an end.
        agrees("a point", p0, p0, q0, q1);
        agrees("a point, second", p0, p1, q1, q1);
        agrees("two points", p0, p0, q1, q1);
        agrees("sharing an end", p0, p1, p1, q1);
    }
}

#[test]
fn segment_distance_known_values() {
    let d = |p0, p1, q0, q1| segment_distance(p0, p1, q0, q1).distance;
    // Skew unit segments one apart, crossing in projection.
    assert_eq!(
        d(
            [-1.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, -1.0, 1.0],
            [0.0, 1.0, 1.0]
        ),
        1.0
    );
    // Collinear, a gap of 2 between them.
    assert_eq!(
        d(
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [3.0, 0.0, 0.0],
            [5.0, 0.0, 0.0]
        ),
        2.0
    );
    // Parallel, side by side.
    assert_eq!(
        d(
            [0.0, 0.0, 0.0],
            [4.0, 0.0, 0.0],
            [1.0, 3.0, 0.0],
            [2.0, 3.0, 0.0]
        ),
        3.0
    );
    // The lines cross, the segments do not: an end (1, 0, 0) to the other
    // segment's end (2, 0, 0).
    assert_eq!(
        d(
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [2.0, 1.0, 0.0]
        ),
        1.0
    );
}

fn pips() -> Problem {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/pips_free_space.toml");
    Problem::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// How far the chord points of each link travel (path length, sampled) on
/// the straight joint-space segment `a -> b`, against `t delta` all along.
fn motion_within_bound(geometry: &Geometry, a: &[f64], b: &[f64]) {
    let delta = geometry.link_motion(a, b);
    let mut last = geometry.pose(a).origins;
    let mut travelled = vec![0.0f64; delta.len()];
    const K: usize = 200;
    for i in 1..=K {
        // The bound of the segment a -> q(t) is t delta.
        let t = i as f64 / K as f64;
        let q: Vec<f64> = a.iter().zip(b).map(|(x, y)| x + t * (y - x)).collect();
        let o = geometry.pose(&q).origins;
        for (k, (d, moved)) in delta.iter().zip(&mut travelled).enumerate() {
            // The chord's ends and points along it; the farthest travelled.
            *moved += [0.0, 0.3, 0.5, 1.0]
                .iter()
                .map(|&s| dist(at(o[k], o[k + 1], s), at(last[k], last[k + 1], s)))
                .fold(0.0, f64::max);
            assert!(
                *moved <= t * d * (1.0 + 1e-9) + 1e-12,
                "link {}: travelled {moved} by t = {t}, bound {}",
                k + 1,
                t * d
            );
        }
        last = o;
    }
}

/// No point of a link travels farther than [`Geometry::link_motion`] says,
/// on random straight joint-space segments of PIPS (both joint kinds); and
/// the bound is tight where it should be: a stretched planar arm turning
/// about its base moves its far end exactly that far.
#[test]
fn the_link_motion_bound_holds() {
    let problem = pips();
    let geometry = Geometry::new(&problem);
    let mut rng = Rng(7);
    for _ in 0..40 {
        let a = random_q(&problem, &mut rng);
        let mut b = random_q(&problem, &mut rng);
        // Short steps and long ones.
        let f = rng.next().powi(3);
        for (x, y) in b.iter_mut().zip(&a) {
            *x = y + f * (*x - y);
        }
        motion_within_bound(&geometry, &a, &b);
    }
    let planar = folding_arm(false);
    let geometry = Geometry::new(&planar);
    let (a, b) = ([0.0; 4], [0.5, 0.0, 0.0, 0.0]);
    motion_within_bound(&geometry, &a, &b);
    // Four 1 m links, 0.5 rad: the tip's arc is 2 m, the bound's.
    let delta = geometry.link_motion(&a, &b);
    assert!((delta[3] - 2.0).abs() < 1e-12, "{delta:?}");
    let o = geometry.pose(&b).origins;
    assert!((o[4][0] - 4.0 * 0.5f64.cos()).abs() < 1e-12);
}

/// The checker's capsule gaps are the planner's chords (`Frames::pivot` to
/// `Frames::link_end`, `f32`) less the radii: the same links, numbered the
/// same way, for every checked pair.
#[test]
fn the_checker_measures_the_planners_links() {
    use capp_core::kinematics::{forward_kinematics, Frames};
    use capp_core::self_collision::segment::closest_points;
    let problem = pips();
    let geometry = Geometry::new(&problem);
    assert!(geometry.self_collision() && !geometry.checked_pairs().is_empty());
    let robot = capp_core::Robot::<32>::new(&problem.joints).unwrap();
    let mut frames = Frames::<32>::default();
    let mut rng = Rng(11);
    for _ in 0..50 {
        let q = random_q(&problem, &mut rng);
        let q32: Vec<f32> = q.iter().map(|&x| x as f32).collect();
        forward_kinematics(&robot, &q32, &mut frames);
        let q: Vec<f64> = q32.iter().map(|&x| x as f64).collect();
        let gaps = geometry.link_gaps(&geometry.pose(&q));
        for (&(a, b), gap) in geometry.checked_pairs().iter().zip(gaps) {
            let c = closest_points(
                &frames.pivot(a),
                &frames.link_end(a),
                &frames.pivot(b),
                &frames.link_end(b),
            );
            let radii = (problem.links.radius[a] + problem.links.radius[b]) as f64;
            let theirs = (c.distance_sq as f64).sqrt() - radii;
            assert!(
                (theirs - gap).abs() < 1e-3,
                "links {} and {}: {gap} here, {theirs} in the planner",
                a + 1,
                b + 1
            );
        }
    }
}

/// A planar arm of four 1 m links (every joint about z), capsules of radius
/// 0.1 m, at rest with the elbow folded: link 2 turned 2.6 rad back over
/// link 1, link 3 (and 4 straight after it) pointing along -x, 0.52 m above
/// link 1. Turning joint 3 by pi swings link 3 down through link 1 and up
/// on the other side, pointing along +x.
fn folding_arm(self_collision: bool) -> Problem {
    let text = format!(
        "name = \"fold\"\nstart = \"home\"\n\
         [units]\nangle = \"radians\"\nlength = \"metres\"\n\
         [robot]\nlink_radius = 0.1\nself_collision = {self_collision}\n\
         [[robot.joints]]\ntype = \"revolute\"\nalpha = 0.0\na = 1.0\ntheta = 0.0\nmin = -6.0\nmax = 6.0\nmax_rate = 100.0\n\
         [[robot.joints]]\ntype = \"revolute\"\nalpha = 0.0\na = 1.0\ntheta = 2.6\nmin = -6.0\nmax = 6.0\nmax_rate = 100.0\n\
         [[robot.joints]]\ntype = \"revolute\"\nalpha = 0.0\na = 1.0\ntheta = {}\nmin = -6.0\nmax = 6.0\nmax_rate = 100.0\n\
         [[robot.joints]]\ntype = \"revolute\"\nalpha = 0.0\na = 1.0\ntheta = 0.0\nmin = -6.0\nmax = 6.0\nmax_rate = 100.0\n\
         [target]\nposition = [2.0, 1.0, 0.0]\n",
        std::f64::consts::PI - 2.6
    );
    let problem =
        scenario_file::parse(&text, Path::new("fold.toml")).unwrap_or_else(|e| panic!("{e}"));
    problem.validate().unwrap_or_else(|e| panic!("{e}"));
    problem
}

/// Rows from `start` turning joint 3 by `turn` in `rows - 1` equal steps of 0.05 s.
fn swing(problem: &Problem, turn: f64, rows: usize) -> Trajectory {
    let start: Vec<f64> = problem.start.iter().map(|&x| x as f64).collect();
    Trajectory {
        joints: 4,
        rows: (0..rows)
            .map(|k| {
                let mut q = start.clone();
                q[2] += turn * k as f64 / (rows - 1) as f64;
                TrajectoryRow {
                    line: k + 2,
                    step: k as u64,
                    h: if k == 0 { 0.0 } else { 0.05 },
                    q,
                    velocity: None,
                    acceleration: None,
                    position: None,
                    v: None,
                    position_error: None,
                    orientation_error: None,
                    clearance: None,
                    escape: None,
                }
            })
            .collect(),
    }
}

#[test]
fn check_rejects_a_link_passing_through_another_at_rows() {
    let problem = folding_arm(true);
    let geometry = Geometry::new(&problem);
    assert!(
        geometry.checked_pairs().contains(&(0, 2)),
        "{:?}",
        geometry.checked_pairs()
    );
    let t = swing(&problem, std::f64::consts::PI, 41);
    let report = check::check(&problem, &t);
    assert!(report.has(ViolationKind::SelfCollision), "{report}");
    assert!(!report.accepted());
    let worst = report.worst_self_collision.expect("the deepest overlap");
    // Link 3 crosses link 1 (and link 4 follows it, crossing link 1 or 2).
    assert!(
        worst.pair.links.0 == 0 && worst.pair.gap < -0.1,
        "{worst:?}"
    );
    let rows_colliding = report.self_collisions - report.self_collisions_between;
    assert!(rows_colliding >= 3, "{report}");
    let text = report.to_string();
    assert!(
        text.contains("self-collision: link 1 and link 3 overlap"),
        "{text}"
    );
    assert!(text.contains("self-collisions:"), "{text}");
    assert_eq!(
        report.self_collisions,
        report
            .violations
            .iter()
            .filter(|v| v.kind == ViolationKind::SelfCollision)
            .count()
    );
    // Nothing else is wrong with it.
    assert!(
        report
            .violations
            .iter()
            .all(|v| v.kind == ViolationKind::SelfCollision),
        "{text}"
    );
}

#[test]
fn check_rejects_a_step_that_jumps_one_link_through_another() {
    let problem = folding_arm(true);
    // Two rows, both clear: the step between them swings link 3 through link 1.
    let t = swing(&problem, std::f64::consts::PI, 2);
    let geometry = Geometry::new(&problem);
    for row in &t.rows {
        let c = geometry.closest_link_pair(&row.q).unwrap();
        assert!(c.gap > 0.3, "row {}: {c:?}", row.step);
    }
    let report = check::check(&problem, &t);
    assert_eq!(report.self_collisions, 1, "{report}");
    assert_eq!(report.self_collisions_between, 1, "{report}");
    let worst = report.worst_self_collision.unwrap();
    assert!(worst.between && worst.step == 1, "{worst:?}");
    assert!(worst.pair.gap < -0.1, "{worst:?}");
    let text = report.to_string();
    assert!(text.contains("between steps 0 and 1"), "{text}");
    assert!(text.contains("link 1 and link 3 overlap"), "{text}");
    assert!(report.sparse_segments == 0, "{text}");
}

#[test]
fn the_same_swing_is_accepted_with_self_collision_off() {
    let problem = folding_arm(false);
    for rows in [2, 41] {
        let report = check::check(&problem, &swing(&problem, std::f64::consts::PI, rows));
        assert!(report.accepted(), "{report}");
        assert!(!report.self_checked && report.closest_links.is_none());
        assert!(report.to_string().contains("self-collision: not checked"));
    }
}

/// A swing that stops short of link 1 by more than the capsules: accepted,
/// with the closest pair named; the dense check samples no more than a
/// fraction of a radius apart where it samples at all.
#[test]
fn a_near_miss_is_accepted_and_its_closest_pair_named() {
    let problem = folding_arm(true);
    // Link 3 from pointing along -x down to 0.4 rad above straight down.
    let turn = std::f64::consts::FRAC_PI_2 - 0.9;
    let t = swing(&problem, turn, 2);
    let report = check::check(&problem, &t);
    assert!(report.accepted(), "{report}");
    let c = report.closest_links.unwrap();
    assert!(c.pair.gap > 0.0, "{c:?}");
    assert!(
        report.to_string().contains("closest link pair: links"),
        "{report}"
    );
    let _ = SWEEP_FRACTION;
}
