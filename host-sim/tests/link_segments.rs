//! Link segments in the independent checker (`Problem::links.segments`):
//! a link's capsule round a segment fixed in its body's frame instead of
//! its chord. The gap of two such capsules against a hand computation, the
//! links' motion bound against the motion of every capsule's points on
//! random straight joint-space segments (where the chord alone would not
//! bound it), and robots without segments measured exactly as before.

use std::f64::consts::FRAC_PI_2;
use std::path::Path;

use capp_core::robot::{JointOrigin, Placement};
use capp_core::{Joint, JointKind};
use capp_sim::geometry::{link_reach, longest_links, segment_distance, Geometry, Pose};
use capp_sim::input::scenario_file;
use capp_sim::Problem;

mod common;

use common::{random_q, Rng};

/// The tests' points.
trait Points {
    fn point(&mut self, size: f64) -> [f32; 3];
}

impl Points for Rng {
    fn point(&mut self, size: f64) -> [f32; 3] {
        [0; 3].map(|_| self.range(-size, size) as f32)
    }
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

fn at(p: [[f64; 3]; 2], s: f64) -> [f64; 3] {
    [0, 1, 2].map(|i| p[0][i] + s * (p[1][i] - p[0][i]))
}

fn translation(t: [f32; 3]) -> Placement {
    Placement {
        translation: t,
        ..Placement::IDENTITY
    }
}

fn general(kind: JointKind, at: [f32; 3], axis: [f32; 3], limit: f32) -> Joint {
    let origin = JointOrigin {
        placement: translation(at),
        axis,
    };
    Joint::general(kind, origin, -limit, limit, 1.0)
}

fn scenario(name: &str) -> Problem {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenarios")
        .join(name);
    Problem::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// Three revolute general joints, link capsules of radius 0.1 m: joint 1
/// about z at the base, joint 2 about y 1 m above it, joint 3 about z 1 m
/// along x from joint 2, the tool 1 m further along x. At `q = 0` the
/// chords run up the z axis, then along x at height 1.
fn three_link_arm(segments: Vec<[[f32; 3]; 2]>) -> Problem {
    let text = "name = \"three\"\nstart = \"home\"\n\
         [units]\nangle = \"radians\"\nlength = \"metres\"\n\
         [robot]\nlink_radius = 0.1\nself_collision = true\n\
         [[robot.joints]]\ntype = \"revolute\"\nalpha = 0.0\na = 1.0\ntheta = 0.0\nmin = -3.0\nmax = 3.0\nmax_rate = 1.0\n\
         [[robot.joints]]\ntype = \"revolute\"\nalpha = 0.0\na = 1.0\ntheta = 0.0\nmin = -3.0\nmax = 3.0\nmax_rate = 1.0\n\
         [[robot.joints]]\ntype = \"revolute\"\nalpha = 0.0\na = 1.0\ntheta = 0.0\nmin = -3.0\nmax = 3.0\nmax_rate = 1.0\n\
         [target]\nposition = [2.0, 0.0, 1.0]\n";
    let mut problem =
        scenario_file::parse(text, Path::new("three.toml")).unwrap_or_else(|e| panic!("{e}"));
    problem.joints = vec![
        general(JointKind::Revolute, [0.0; 3], [0.0, 0.0, 1.0], 3.0),
        general(JointKind::Revolute, [0.0, 0.0, 1.0], [0.0, 1.0, 0.0], 3.0),
        general(JointKind::Revolute, [1.0, 0.0, 0.0], [0.0, 0.0, 1.0], 3.0),
    ];
    problem.tool = translation([1.0, 0.0, 0.0]);
    problem.links.segments = segments;
    problem
}

/// Two offset segments: link 1's 0.5 m off its chord along its body's x,
/// link 3's 0.3 m off along its body's y. At `q = (pi/2, 0, pi/2)` they are
/// `x = 0, y = 0.5, z in [0, 0.8]` and `x in [-0.6, 0], y = 0.7, z = 1`
/// (link 3's body turned half round, at `(0, 1, 1)`), so their distance is
/// `sqrt(0.2^2 + 0.2^2)` (at `x = 0`), their gap that less both radii; the
/// chords (z axis to 1; `(0, 1, 1) -> (-1, 1, 1)`) are 1 m apart. Joint 2
/// turned by `acos(5/7)` brings link 3's near end to
/// `(0, 0.7 cos, 1 - 0.7 sin) = (0, 0.5, 1 - sqrt(0.24))`, on link 1's
/// segment: gap `-0.2`.
#[test]
fn the_gap_of_two_offset_segments_is_the_hand_computed_one() {
    let segments = vec![
        [[0.5, 0.0, 0.0], [0.5, 0.0, 0.8]],
        [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]],
        [[0.0, 0.3, 0.0], [0.6, 0.3, 0.0]],
    ];
    let problem = three_link_arm(segments);
    let geometry = Geometry::new(&problem);
    assert_eq!(geometry.checked_pairs(), &[(0, 2)]);
    let q = [FRAC_PI_2, 0.0, FRAC_PI_2];
    let pose = geometry.pose(&q);
    let expect = |got: [f64; 3], want: [f64; 3]| {
        assert!(dist(got, want) < 1e-6, "{got:?}, not {want:?}");
    };
    expect(pose.capsules[0][0], [0.0, 0.5, 0.0]);
    expect(pose.capsules[0][1], [0.0, 0.5, 0.8]);
    expect(pose.capsules[2][0], [0.0, 0.7, 1.0]);
    expect(pose.capsules[2][1], [-0.6, 0.7, 1.0]);
    let gaps = geometry.link_gaps(&pose);
    let hand = (0.2f64 * 0.2 + 0.2 * 0.2).sqrt() - 0.2;
    assert!(
        (gaps[0] - hand).abs() < 1e-6,
        "gap {}, by hand {hand}",
        gaps[0]
    );
    let closest = geometry.closest_link_pair(&q).unwrap();
    assert_eq!(closest.links, (0, 2));
    assert_eq!(closest.gap, gaps[0]);
    // The chords' gap is another number: the segments are what is checked.
    let chords = Geometry::new(&three_link_arm(Vec::new()));
    let chord_gap = chords.link_gaps(&chords.pose(&q))[0];
    assert!((chord_gap - 0.8).abs() < 1e-6, "{chord_gap}");
    // Tilted until the segments cross, the checker sees them overlap.
    let overlap = [FRAC_PI_2, (5.0f64 / 7.0).acos(), FRAC_PI_2];
    let pose = geometry.pose(&overlap);
    expect(pose.capsules[2][0], [0.0, 0.5, 1.0 - 0.24f64.sqrt()]);
    let g = geometry.link_gaps(&pose)[0];
    assert!((g + 0.2).abs() < 1e-6, "{g}");
    assert!(!geometry.is_free(&overlap) && geometry.is_free(&q));
}

/// `(pose at a + t (b - a))`.
fn pose_along(geometry: &Geometry, a: &[f64], b: &[f64], t: f64) -> Pose {
    let q: Vec<f64> = a.iter().zip(b).map(|(x, y)| x + t * (y - x)).collect();
    geometry.pose(&q)
}

/// The farthest any sampled point of each link's capsule segment travels
/// (path length over `K` steps of `t`), checked against `t bound` all
/// along the joint-space segment `a -> b`; returns the largest ratio of
/// travel to `other`'s bound of the same prefix (to show that a weaker
/// bound would fail).
fn capsule_travel_within(
    geometry: &Geometry,
    a: &[f64],
    b: &[f64],
    bound: &[f64],
    other: &[f64],
) -> f64 {
    const K: usize = 400;
    const POINTS: [f64; 5] = [0.0, 0.25, 0.5, 0.75, 1.0];
    let mut last = geometry.pose(a);
    let mut travelled = vec![[0.0f64; POINTS.len()]; bound.len()];
    let mut worst_other = 0.0f64;
    for i in 1..=K {
        let t = i as f64 / K as f64;
        let pose = pose_along(geometry, a, b, t);
        for (k, moved) in travelled.iter_mut().enumerate() {
            for (m, &s) in moved.iter_mut().zip(&POINTS) {
                *m += dist(at(pose.capsules[k], s), at(last.capsules[k], s));
                assert!(
                    *m <= t * bound[k] * (1.0 + 1e-9) + 1e-12,
                    "link {}, point {s} of its capsule: travelled {m} by t = {t}, bound {}",
                    k + 1,
                    t * bound[k]
                );
                worst_other = worst_other.max(*m / (t * other[k]));
            }
        }
        last = pose;
    }
    worst_other
}

/// The module docs' `delta_k` built on the longest chords alone (the bound
/// before link segments), to show that the tests below would catch it.
fn chord_motion(problem: &Problem, a: &[f64], b: &[f64]) -> Vec<f64> {
    let longest = longest_links(&problem.joints, &problem.tool);
    let n = problem.joints.len();
    let mut delta = vec![0.0; n];
    for (j, joint) in problem.joints.iter().enumerate() {
        let dq = (b[j] - a[j]).abs();
        let mut lever = 0.0;
        for k in j..n {
            lever += longest[k];
            delta[k] += dq
                * match joint.kind {
                    JointKind::Revolute => lever,
                    JointKind::Prismatic => 1.0,
                };
        }
    }
    delta
}

/// On `trials` random straight joint-space segments (short and long; every
/// other one turning a single joint, where the bound is tightest), no
/// sampled point of any link's capsule segment travels farther than
/// `link_motion` says; returns the largest travel over the chord-only
/// bound's.
fn motion_bound_holds(problem: &Problem, rng: &mut Rng, trials: usize) -> f64 {
    let geometry = Geometry::new(problem);
    let mut worst_chord = 0.0f64;
    for trial in 0..trials {
        let a = random_q(problem, rng);
        let mut b = random_q(problem, rng);
        let f = rng.next().powi(2);
        let only = (trial % 2 == 1).then(|| trial / 2 % a.len());
        for (j, (x, y)) in b.iter_mut().zip(&a).enumerate() {
            *x = match only {
                Some(k) if k != j => *y,
                _ => y + f * (*x - y),
            };
        }
        let bound = geometry.link_motion(&a, &b);
        let chord = chord_motion(problem, &a, &b);
        worst_chord = worst_chord.max(capsule_travel_within(&geometry, &a, &b, &bound, &chord));
    }
    worst_chord
}

/// The three-link arm with segments far off its chords (up to 1.5 m from
/// the pivot, where the chords are 1 m), and a prismatic joint in the
/// middle whose slide carries its link's segment away from the pivot: the
/// bound holds, and the chord-only bound does not.
#[test]
fn no_point_of_a_capsule_segment_outruns_the_motion_bound() {
    let mut rng = Rng(0x5E6_3E27);
    let segments = vec![
        [[1.2, 0.0, 0.3], [0.4, 0.9, 0.1]],
        [[0.0, 1.4, 0.0], [-0.5, -0.2, 0.6]],
        [[0.3, -1.5, 0.2], [0.7, 0.2, -0.9]],
    ];
    let problem = three_link_arm(segments);
    let worst = motion_bound_holds(&problem, &mut rng, 60);
    assert!(
        worst > 1.05,
        "the chord-only bound was never beaten ({worst}): the test has no teeth"
    );
    // A prismatic middle joint at the base's pivot, sliding along x up to
    // 1 m: its link's segment rides the slide, up to 1.8 m + 1 m out where
    // its chord reaches 1 m + 1 m, and joint 1 swings it round.
    let mut slider = three_link_arm(vec![
        [[0.0, 0.0, 0.0], [0.0, 0.0, 0.1]],
        [[1.8, 0.0, 0.0], [0.0, 0.6, 0.5]],
        [[0.0, 0.0, 0.0], [1.3, 0.4, 0.0]],
    ]);
    slider.joints[1] = general(JointKind::Prismatic, [0.0; 3], [1.0, 0.0, 0.0], 1.0);
    let worst = motion_bound_holds(&slider, &mut rng, 60);
    assert!(worst > 1.05, "{worst}");
    let reach = link_reach(&slider.joints, &slider.tool, &slider.links.segments);
    let chords = longest_links(&slider.joints, &slider.tool);
    assert!(
        reach[1] > chords[1] && reach[2] > chords[2],
        "{reach:?} {chords:?}"
    );
    // Random segments, many of them far off the chords.
    for _ in 0..10 {
        let segments = (0..3).map(|_| [rng.point(1.5), rng.point(1.5)]).collect();
        motion_bound_holds(&three_link_arm(segments), &mut rng, 8);
    }
}

/// The UR5 of `ur5_table.toml` (its real joints, slid pivots and tool)
/// with a segment per link, some far off the body: the bound holds there
/// too.
#[test]
fn the_motion_bound_holds_on_the_ur5_with_segments() {
    let mut problem = scenario("ur5_table.toml");
    let mut rng = Rng(42);
    problem.links.segments = (0..problem.joints.len())
        .map(|_| [rng.point(0.8), rng.point(0.8)])
        .collect();
    let worst = motion_bound_holds(&problem, &mut rng, 30);
    assert!(worst > 1.0, "{worst}");
}

/// The gap of checked pair `(a, b)` as the chord model computed it before
/// link segments: the chords `o_k -> o_{k+1}`.
fn chord_gap(problem: &Problem, origins: &[[f64; 3]], (a, b): (usize, usize)) -> f64 {
    let d = segment_distance(origins[a], origins[a + 1], origins[b], origins[b + 1]);
    d.distance - problem.links.radius[a] as f64 - problem.links.radius[b] as f64
}

/// Without segments every capsule is its chord and every gap is bit for
/// bit the chord model's, for a DH robot (PIPS), a URDF robot (UR5) and
/// the three-link arm; and the motion bound is the chords'.
#[test]
fn without_segments_the_gaps_are_the_chords_exactly() {
    let mut rng = Rng(3);
    // The UR5's capsules as chords (the loader gives it segments).
    let mut ur5 = scenario("ur5_table.toml");
    assert_eq!(ur5.links.segments.len(), ur5.joints.len());
    ur5.links.segments.clear();
    for problem in [
        scenario("pips_free_space.toml"),
        ur5,
        three_link_arm(Vec::new()),
    ] {
        assert!(problem.links.segments.is_empty());
        let geometry = Geometry::new(&problem);
        assert!(!geometry.checked_pairs().is_empty(), "{}", problem.name);
        for _ in 0..50 {
            let q = random_q(&problem, &mut rng);
            let pose = geometry.pose(&q);
            let (origins, end) = capp_sim::geometry::forward(&problem, &q);
            assert_eq!((&pose.origins, pose.end), (&origins, end));
            for (k, c) in pose.capsules.iter().enumerate() {
                assert_eq!(*c, [origins[k], origins[k + 1]]);
            }
            let gaps = geometry.link_gaps(&pose);
            for (&pair, gap) in geometry.checked_pairs().iter().zip(gaps) {
                assert_eq!(
                    gap.to_bits(),
                    chord_gap(&problem, &origins, pair).to_bits(),
                    "{}",
                    problem.name
                );
            }
            let b = random_q(&problem, &mut rng);
            assert_eq!(geometry.link_motion(&q, &b), chord_motion(&problem, &q, &b));
        }
        assert_eq!(
            link_reach(&problem.joints, &problem.tool, &[]),
            longest_links(&problem.joints, &problem.tool)
        );
    }
}

/// `capp robot`'s report and `capp acm`'s name the segment each link's
/// capsule is round, and the report's "misses this body" note weighs the
/// capsule checked: the UR5's upper arm, loaded, is its body's own capsule
/// (no note); round its chord it needs 0.2121 m against a body of 0.1006
/// m (the note), and so does a segment that misses the body.
#[test]
fn the_reports_name_the_segments() {
    let mut problem = scenario("ur5_table.toml");
    let n = problem.joints.len();
    let loaded = capp_sim::robot_report::report(&problem).unwrap();
    assert!(
        loaded.contains("segment a 0.0010 -0.1313 0.0004  b -0.0008 -0.1310 0.4246 (m, in joint \"shoulder_lift_joint\"'s frame), radius 0.1006 m"),
        "{loaded}"
    );
    assert!(!loaded.contains("misses this body"), "{loaded}");
    problem.links.segments.clear();
    problem.links.radius[1] = 0.2121;
    let chords = capp_sim::robot_report::report(&problem).unwrap();
    assert!(
        chords.contains("the chord misses this body: its capsule is 2.1 times as thick"),
        "{chords}"
    );
    assert!(!chords.contains("segment a"), "{chords}");
    problem.links.segments = vec![[[0.0, 0.0, 0.0], [0.0, 0.0, 0.1]]; n];
    problem.links.segments[1] = [[0.0, 0.0, 0.0], [0.425, 0.0, 0.0]];
    let report = capp_sim::robot_report::report(&problem).unwrap();
    let upper = report
        .split("link 2 (after joint \"shoulder_lift_joint\")")
        .nth(1)
        .and_then(|rest| rest.split("  link 3 ").next())
        .unwrap_or_else(|| panic!("{report}"));
    assert!(
        upper.contains("segment a 0.0000 0.0000 0.0000  b 0.4250 0.0000 0.0000 (m, in joint \"shoulder_lift_joint\"'s frame), radius 0.2121 m"),
        "{upper}"
    );
    assert!(
        upper.contains("the segment misses this body: its capsule is 2.1 times as thick"),
        "{upper}"
    );
    problem.links.radius[1] = 0.11;
    let report = capp_sim::robot_report::report(&problem).unwrap();
    assert!(!report.contains("segment misses"), "{report}");
    assert!(!report.contains("chord up to"), "{report}");
    let acm = capp_sim::acm::report(&problem).unwrap();
    assert!(acm.contains("capsules (each link's segment"), "{acm}");
}

/// The viewer's `RUN` carries each frame's capsule segments (`null`
/// without segments, the chords being the frame origins it has), the
/// same the checker measures (to the page's 4 decimals).
#[test]
fn the_viewer_draws_the_segments_checked() {
    use capp_sim::render::viewer::run_json;
    use capp_sim::trajectory::Trajectory;
    let field = |json: &str| -> Option<Vec<f64>> {
        let rest = json.split("\"link_segments\": ").nth(1).unwrap();
        let value = rest.split(",\n").next().unwrap();
        (value != "null").then(|| {
            value
                .trim_matches(['[', ']'])
                .split(',')
                .map(|x| x.parse().unwrap())
                .collect()
        })
    };
    let q = [FRAC_PI_2, 0.4, -0.7];
    let still = Trajectory::still(&q);
    assert_eq!(field(&run_json(&three_link_arm(Vec::new()), &still)), None);
    let problem = three_link_arm(vec![
        [[0.5, 0.0, 0.0], [0.5, 0.0, 0.8]],
        [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]],
        [[0.0, 0.3, 0.0], [0.6, 0.3, 0.0]],
    ]);
    let drawn = field(&run_json(&problem, &still)).unwrap();
    let checked: Vec<f64> = Geometry::new(&problem)
        .pose(&q)
        .capsules
        .iter()
        .flatten()
        .flatten()
        .copied()
        .collect();
    assert_eq!(drawn.len(), 18);
    for (d, c) in drawn.iter().zip(&checked) {
        assert!((d - c).abs() < 1e-4, "{drawn:?} against {checked:?}");
    }
}

/// The core's world segments (`Frames::capsule`, f32, the joints' frames
/// turned so their axes are z) against the checker's (f64, the URDF's own
/// frames) on the loaded UR5 and Panda, whose axes are y and z and whose
/// segments lie off their chords: within f32 rounding over 200
/// configurations each. A segment left in the URDF's frame, or turned the
/// wrong way, is centimetres off.
#[test]
fn the_cores_segments_are_the_checkers() {
    use capp_core::kinematics::{forward_kinematics, Frames};
    let mut rng = Rng(11);
    for name in ["ur5_table.toml", "panda_table.toml"] {
        let problem = scenario(name);
        assert_eq!(problem.links.segments.len(), problem.joints.len(), "{name}");
        let scenario = problem.scenario().unwrap();
        let robot = scenario.robot();
        assert!(robot.has_link_segments(), "{name}");
        let geometry = Geometry::new(&problem);
        let mut frames = Frames::<{ capp_sim::problem::MAX_JOINTS }>::default();
        let mut worst = 0.0f64;
        for _ in 0..200 {
            let q = random_q(&problem, &mut rng);
            let q32: Vec<f32> = q.iter().map(|&x| x as f32).collect();
            let q: Vec<f64> = q32.iter().map(|&x| x as f64).collect();
            forward_kinematics(robot, &q32, &mut frames);
            let pose = geometry.pose(&q);
            for (k, ends) in pose.capsules.iter().enumerate() {
                let (a, b) = frames.capsule(k);
                for (core, checker) in [a, b].iter().zip(ends) {
                    let core = [core.x as f64, core.y as f64, core.z as f64];
                    worst = worst.max(dist(core, *checker));
                }
            }
        }
        assert!(worst < 2e-6, "{name}: {worst} m");
    }
}
