//! Property tests (issue 6, part 1): random chains of 3 to 32 joints of both
//! kinds, random limits, rates and weights, random obstacles that clear the
//! start configuration, random targets and settings. At every step of every
//! run, checked independently of the planner's f32 code where it matters:
//!
//! * every joint value, rate, `V` and error is finite;
//! * every joint is within its limits;
//! * no joint moved faster than its rate limit (`|dq| <= h max_rate`);
//! * no avoidance point is inside an inflated obstacle (f64 super-ellipsoids
//!   and CAD primitives of `tests/common`, two thirds of the obstacles spheres,
//!   boxes, capsules and cylinders measured on their true distance; the planner decides in f32, so the check allows 16
//!   f32 ulps of the arm's reach of position rounding, and no more), at the
//!   step's end and along the straight joint-space segment to it, checked
//!   every [`DENSE_STEP`] of joint motion (conservative advancement);
//! * the run ends (reached, stalled or capped) within the step cap, and a run
//!   that says `Reached` is within tolerance of its target (f64 kinematics).
//!
//! The random source is proptest's ChaCha with a fixed seed, so every run of
//! `cargo test` checks the same cases; `PROPERTY_CASES=n` asks for another
//! number of cases (the default is in [`CASES`]).

mod common;

use std::cell::Cell;

use capp_core::control::LawKind;
use capp_core::*;
use common::*;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, RngSeed, TestCaseError, TestRunner};

/// Room for the largest chain (32 joints), 6 obstacles and 2 waypoints.
type Sc = Scenario<32, 6, 2>;

/// Cases of the random-chain property in a normal test run.
const CASES: u32 = 1000;
/// Position rounding allowed in the clearance check, relative to the arm's
/// reach: 16 f32 ulps (see `check_run`).
const ROUNDING: f64 = 16.0 * f32::EPSILON as f64;
/// Cases of the PIPS property.
const PIPS_CASES: u32 = 100;
/// Largest joint motion (radians or length units) between two configurations
/// the clearance check looks at inside one step.
const DENSE_STEP: f32 = 0.02;

/// One joint as drawn: kind, DH constants, limits, rate, weight.
#[derive(Clone, Debug)]
struct JointSpec {
    prismatic: bool,
    alpha: f32,
    a: f32,
    /// `theta` of a prismatic joint, `d` of a revolute one.
    fixed: f32,
    min: f32,
    span: f32,
    max_rate: f32,
    weight: f32,
}

impl JointSpec {
    fn joint(&self) -> Joint {
        let max = self.min + self.span;
        let j = if self.prismatic {
            Joint::prismatic(self.alpha, self.a, self.fixed, self.min, max, self.max_rate)
        } else {
            Joint::revolute(self.alpha, self.a, self.fixed, self.min, max, self.max_rate)
        };
        j.with_weight(self.weight)
    }
}

fn joint_spec() -> impl Strategy<Value = JointSpec> {
    (
        prop::bool::weighted(0.25),
        -3.2f32..3.2,
        -3.0f32..6.0,
        -2.0f32..2.0,
        -3.0f32..0.5,
        0.05f32..6.0,
        0.05f32..2.0,
        0.05f32..=1.0,
    )
        .prop_map(
            |(prismatic, alpha, a, fixed, min, span, max_rate, weight)| JointSpec {
                prismatic,
                alpha,
                a,
                fixed,
                min,
                span,
                max_rate,
                weight,
            },
        )
}

/// An obstacle placed near the arm: centred on a point between link `link`'s
/// origin at the start and at the target configuration, then moved by `offset`.
#[derive(Clone, Debug)]
struct ObstacleSpec {
    link: f32,
    along: f32,
    offset: [f32; 3],
    semi_axes: [f32; 3],
    exponents: [f32; 3],
    euler_123: [f32; 3],
    /// 0, 1: a super-ellipsoid; 2-5: a sphere, box, capsule, cylinder (sizes
    /// from `semi_axes`); 6: a hull ([`ObstacleSpec::hull`]).
    shape: u8,
}

impl ObstacleSpec {
    /// The shape; a hull is the scenario's hull number `hull`.
    fn shape(&self, hull: u8) -> Shape {
        let [a, b, c] = self.semi_axes;
        match self.shape {
            2 => Shape::Sphere { radius: a },
            3 => Shape::Cuboid {
                half_extents: self.semi_axes,
            },
            4 => Shape::Capsule {
                radius: a.min(b),
                length: 2.0 * c,
            },
            5 => Shape::Cylinder {
                radius: a,
                length: 2.0 * b,
            },
            6 => Shape::Convex { hull },
            _ => Shape::SuperEllipsoid {
                semi_axes: self.semi_axes,
                exponents: self.exponents,
            },
        }
    }

    /// A hull's vertices (shape 6): the six points on the axes at the
    /// semi-axes, a tilted square cap at a fraction of them set by the
    /// exponents (some inside the octahedron, some out), off-centre.
    fn hull(&self) -> Vec<[f32; 3]> {
        let [a, b, c] = self.semi_axes;
        let [p, q, r] = self.exponents.map(|k| k / 12.0);
        let mut vertices = vec![
            [a, 0.0, 0.0],
            [-a, 0.0, 0.0],
            [0.0, b, 0.0],
            [0.0, -b, 0.0],
            [0.0, 0.0, c],
            [0.0, 0.0, -c],
        ];
        for (sx, sy) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
            vertices.push([sx * p * a, sy * q * b, r * c + 0.2 * sx * a]);
        }
        for v in &mut vertices {
            v[0] += 0.25 * a;
        }
        vertices
    }
}

fn obstacle_spec() -> impl Strategy<Value = ObstacleSpec> {
    let exponent = prop_oneof![Just(2.0f32), Just(4.0), Just(8.0), 1.0f32..12.0];
    (
        0.0f32..1.0,
        0.0f32..1.0,
        [-3.0f32..3.0, -3.0f32..3.0, -3.0f32..3.0],
        [0.1f32..3.0, 0.1f32..3.0, 0.1f32..3.0],
        [exponent.clone(), exponent.clone(), exponent],
        [-3.2f32..3.2, -3.2f32..3.2, -3.2f32..3.2],
        0u8..7,
    )
        .prop_map(
            |(link, along, offset, semi_axes, exponents, euler_123, shape)| ObstacleSpec {
                link,
                along,
                offset,
                semi_axes,
                exponents,
                euler_123,
                shape,
            },
        )
}

/// How the target is drawn.
#[derive(Clone, Copy, Debug)]
enum TargetKind {
    /// Position and orientation of a random configuration (reachable).
    Pose,
    /// Position of a random configuration.
    Position,
    /// A random point, usually out of reach.
    Anywhere([f32; 3]),
}

#[derive(Clone, Debug)]
struct SettingsSpec {
    time_step_s: f32,
    position_tolerance: f32,
    orientation_tolerance: f32,
    law: u8,
    orientation_scale: f32,
    approach_radius: f32,
    joint_margin: f32,
    link_margin: f32,
    points_per_link: u8,
    influence_distance: f32,
    engage_clearance: f32,
    advance_fraction: f32,
    damping: f32,
    saturation: bool,
    escape: (u8, u16, u16, f32, u32),
    max_steps: u32,
    stall_window: u32,
    max_halvings: u8,
}

impl SettingsSpec {
    fn settings(&self) -> Settings {
        let mut s = Settings {
            time_step_s: self.time_step_s,
            position_tolerance: self.position_tolerance,
            orientation_tolerance: self.orientation_tolerance,
            max_steps: self.max_steps,
            stall_window: self.stall_window,
            max_halvings: self.max_halvings,
            ..Settings::default()
        };
        s.law.kind = match self.law {
            0 => LawKind::Paper,
            1 => LawKind::Gradient,
            _ => LawKind::DampedLeastSquares,
        };
        s.law.damping = self.damping;
        s.law.saturation = self.saturation;
        s.avoidance.advance_fraction = self.advance_fraction;
        let (attempts, window, walk_steps, reach, seed) = self.escape;
        s.escape.attempts = attempts;
        s.escape.window = window;
        s.escape.walk_steps = walk_steps;
        s.escape.reach = reach;
        s.escape.seed = seed;
        s.law.orientation_scale = self.orientation_scale;
        s.law.approach_radius = self.approach_radius;
        s.avoidance.joint_margin = self.joint_margin;
        s.avoidance.link_margin = self.link_margin;
        s.avoidance.points_per_link = self.points_per_link;
        s.avoidance.influence_distance = self.influence_distance;
        s.avoidance.engage_clearance = self.engage_clearance;
        s
    }
}

fn settings_spec(max_steps: u32) -> impl Strategy<Value = SettingsSpec> {
    (
        (
            0.005f32..0.2,
            0.01f32..0.5,
            0.01f32..0.5,
            // Paper 1 in 5, gradient 1 in 5, damped least squares 3 in 5.
            prop_oneof![1 => Just(0u8), 1 => Just(1u8), 3 => Just(2u8)],
            0.0f32..10.0,
            0.0f32..3.0,
        ),
        (
            0.0f32..1.0,
            0.0f32..1.0,
            1u8..=3,
            0.01f32..6.0,
            0.0f32..2.0,
            (max_steps / 2)..=max_steps,
            5u32..200,
            0u8..=10,
        ),
        (
            0.05f32..=1.0,
            prop_oneof![Just(1.0e-3f32), 1.0e-5f32..=1.0],
            any::<bool>(),
        ),
        // Escapes off in a third of the cases, so that runs also stall.
        (
            prop_oneof![1 => Just(0u8), 2 => 1u8..=6],
            3u16..60,
            1u16..40,
            0.02f32..=1.0,
            any::<u32>(),
        ),
    )
        .prop_map(
            |(
                (
                    time_step_s,
                    position_tolerance,
                    orientation_tolerance,
                    law,
                    orientation_scale,
                    approach_radius,
                ),
                (
                    joint_margin,
                    link_margin,
                    points_per_link,
                    influence_distance,
                    engage_clearance,
                    max_steps,
                    stall_window,
                    max_halvings,
                ),
                (advance_fraction, damping, saturation),
                escape,
            )| SettingsSpec {
                time_step_s,
                position_tolerance,
                orientation_tolerance,
                law,
                orientation_scale,
                approach_radius,
                joint_margin,
                link_margin,
                points_per_link,
                influence_distance,
                engage_clearance,
                advance_fraction,
                damping,
                saturation,
                escape,
                max_steps,
                stall_window,
                max_halvings,
            },
        )
}

fn target_kind() -> impl Strategy<Value = TargetKind> {
    prop_oneof![
        2 => Just(TargetKind::Pose),
        2 => Just(TargetKind::Position),
        1 => [-40.0f32..40.0, -40.0f32..40.0, -40.0f32..40.0].prop_map(TargetKind::Anywhere),
    ]
}

/// A whole problem as drawn; [`Case::build`] turns it into a scenario and start.
#[derive(Clone, Debug)]
struct Case {
    joints: Vec<JointSpec>,
    /// Start and target configurations as fractions of each joint's half range.
    start: Vec<f32>,
    goal: Vec<f32>,
    /// A second configuration, used as a first waypoint when `via` is set.
    via: Option<Vec<f32>>,
    target: TargetKind,
    obstacles: Vec<ObstacleSpec>,
    settings: SettingsSpec,
}

fn fractions() -> impl Strategy<Value = Vec<f32>> {
    prop::collection::vec(-0.95f32..0.95, 32)
}

fn case(
    joint_count: std::ops::RangeInclusive<usize>,
    max_steps: u32,
) -> impl Strategy<Value = Case> {
    (
        prop::collection::vec(joint_spec(), joint_count),
        fractions(),
        fractions(),
        prop::option::weighted(0.2, fractions()),
        target_kind(),
        prop::collection::vec(obstacle_spec(), 0..=6),
        settings_spec(max_steps),
    )
        .prop_map(
            |(joints, start, goal, via, target, obstacles, settings)| Case {
                joints,
                start,
                goal,
                via,
                target,
                obstacles,
                settings,
            },
        )
}

fn config_at(joints: &[Joint], fractions: &[f32]) -> Vec<f32> {
    joints
        .iter()
        .zip(fractions)
        .map(|(j, &f)| {
            let (mid, half) = (0.5 * (j.min + j.max), 0.5 * (j.max - j.min));
            j.clamp(mid + f * half)
        })
        .collect()
}

fn to64(q: &[f32]) -> Vec<f64> {
    q.iter().map(|&x| x as f64).collect()
}

/// Builds the scenario; obstacles that touch the start configuration are
/// dropped one by one (the planner names the first it finds) until the start
/// is clear, so every obstacle kept clears the start.
fn build(joints: &[Joint], case: &Case) -> (Sc, Vec<f32>) {
    let start = config_at(joints, &case.start);
    let goal = config_at(joints, &case.goal);
    let (start_chain, goal_chain) = (fk64(joints, &to64(&start)), fk64(joints, &to64(&goal)));
    let mut hulls: Vec<Vec<[f32; 3]>> = Vec::new();
    let mut obstacles: Vec<Solid> = case
        .obstacles
        .iter()
        .map(|o| {
            let hull = hulls.len() as u8;
            if o.shape == 6 {
                hulls.push(o.hull());
            }
            let k = 1 + ((o.link * joints.len() as f32) as usize).min(joints.len() - 1);
            let (a, b) = (start_chain.origins[k], goal_chain.origins[k]);
            let centre = add(
                add(a, scale(sub(b, a), o.along as f64)),
                o.offset.map(|x| x as f64),
            );
            Solid {
                centre: centre.map(|x| x as f32),
                euler_123: o.euler_123,
                shape: o.shape(hull),
            }
        })
        .collect();
    let (goal_position, goal_rotation) = pose_of(joints, &goal);
    let target = match case.target {
        TargetKind::Pose => Waypoint::pose(goal_position, goal_rotation),
        TargetKind::Position => Waypoint::at(goal_position),
        TargetKind::Anywhere(p) => Waypoint::at(p),
    };
    let mut waypoints = vec![target];
    if let Some(via) = &case.via {
        waypoints.insert(0, Waypoint::at(pose_of(joints, &config_at(joints, via)).0));
    }
    let settings = case.settings.settings();
    loop {
        let hull_lists: Vec<&[[f32; 3]]> = hulls.iter().map(|h| &h[..]).collect();
        let mut sc = Sc::empty();
        sc.init_with_hulls(
            joints,
            &capp_core::robot::Placement::IDENTITY,
            &obstacles,
            &hull_lists,
            &waypoints,
            settings,
        )
        .expect("the drawn scenario is valid");
        match Planner::new(&sc, &start) {
            Ok(_) => return (sc, start),
            Err(planner::StartError::InObstacle { obstacle, .. }) => {
                obstacles.remove(obstacle as usize);
            }
            Err(e) => panic!("start refused: {e}"),
        }
    }
}

/// Runs `case` to the end and checks every invariant at every step.
fn check_run(sc: &Sc, start: &[f32]) -> Result<Outcome, TestCaseError> {
    let joints = sc.robot().joints().to_vec();
    let s = *sc.settings();
    let margins = (
        s.avoidance.joint_margin as f64,
        s.avoidance.link_margin as f64,
    );
    let interior = s.avoidance.points_per_link as usize;
    let obstacles: Vec<Solid> = sc.obstacles().iter().map(|o| *o.source()).collect();
    let hulls: Vec<Vec<[f64; 3]>> = sc
        .hulls()
        .iter()
        .map(|h| {
            h.vertices()
                .iter()
                .map(|v| [v.x, v.y, v.z].map(f64::from))
                .collect()
        })
        .collect();
    // The planner decides in f32; exact (f64) arithmetic may put a point that
    // f32 saw a hair outside a hair inside. The check allows the f32 rounding
    // of the positions and nothing more: it evaluates obstacles inflated by the
    // margins less `ROUNDING * reach` (a few f32 ulps of the arm's size).
    let reach: f64 = joints
        .iter()
        .map(|j| (j.a.abs() + j.d.abs() + j.min.abs().max(j.max.abs())) as f64)
        .sum();
    let slack = ROUNDING * reach;
    let shrunk = (margins.0 - slack, margins.1 - slack);
    let clearance =
        |q: &[f32]| min_clearance_solids64(&joints, &to64(q), &obstacles, &hulls, shrunk, interior);

    let mut planner = Planner::new(sc, start).expect("build() checked the start");
    if !obstacles.is_empty() {
        let c = clearance(start);
        prop_assert!(c > 0.0, "start inside an inflated obstacle: C - 1 = {c}");
    }
    let mut previous = start.to_vec();
    // One more step than the cap: the step after the cap must not be needed.
    for _ in 0..=s.max_steps {
        let r = planner.step(sc).expect("same scenario");
        let q = planner.joints();
        let rates = planner.rates();
        prop_assert!(r.time_step_s.is_finite() && r.time_step_s >= 0.0);
        prop_assert!(r.time_step_s <= s.time_step_s);
        prop_assert!(
            r.v.is_finite() && r.position_error.is_finite() && r.orientation_error.is_finite(),
            "step {}: V or an error is not finite: {r:?}",
            r.step
        );
        for (j, joint) in joints.iter().enumerate() {
            prop_assert!(q[j].is_finite(), "step {}: joint {j} not finite", r.step);
            prop_assert!(rates[j].is_finite(), "step {}: rate {j} not finite", r.step);
            prop_assert!(
                q[j] >= joint.min && q[j] <= joint.max,
                "step {}: joint {j} = {} outside [{}, {}]",
                r.step,
                q[j],
                joint.min,
                joint.max
            );
            // f32 rounding only: q + h rate is one rounded product and sum.
            let slack = 1e-5 * joint.max_rate;
            prop_assert!(
                rates[j].abs() <= joint.max_rate + slack,
                "step {}: joint {j} rate {} above its limit {}",
                r.step,
                rates[j],
                joint.max_rate
            );
            let moved = (q[j] - previous[j]).abs();
            let allowed = r.time_step_s * (joint.max_rate + slack)
                + 4.0 * f32::EPSILON * q[j].abs().max(previous[j].abs());
            prop_assert!(
                moved <= allowed,
                "step {}: joint {j} moved {moved} in {} s, more than its rate allows ({allowed})",
                r.step,
                r.time_step_s
            );
        }
        if !obstacles.is_empty() {
            let c = clearance(q);
            prop_assert!(
                c > 0.0,
                "step {}: an avoidance point is inside an inflated obstacle (C - 1 = {c}; \
                 the planner's closest pair: {:?})",
                r.step,
                r.clearance
            );
            // And on the way there: the straight joint-space segment, densely.
            let largest = previous
                .iter()
                .zip(q)
                .map(|(a, b)| (b - a).abs())
                .fold(0.0f32, f32::max);
            let pieces = ((largest / DENSE_STEP).ceil() as usize).clamp(1, 64);
            for i in 1..pieces {
                let t = i as f32 / pieces as f32;
                let mid: Vec<f32> = previous
                    .iter()
                    .zip(q)
                    .map(|(a, b)| a + t * (b - a))
                    .collect();
                let c = clearance(&mid);
                prop_assert!(
                    c > 0.0,
                    "step {}: an avoidance point passes through an inflated obstacle \
                     at {t} of the step (C - 1 = {c})",
                    r.step
                );
            }
        }
        previous.copy_from_slice(q);
        if let Phase::Done(outcome) = r.phase {
            prop_assert!(r.step <= s.max_steps, "ran past the cap: {}", r.step);
            if outcome == Outcome::Reached {
                let p = sc.targets().last().unwrap().position;
                let target = [p.x as f64, p.y as f64, p.z as f64];
                let chain = fk64(&joints, &to64(q));
                let hand = *chain.origins.last().unwrap();
                let d = dot(sub(hand, target), sub(hand, target)).sqrt();
                let tolerance = s.position_tolerance as f64;
                prop_assert!(
                    d <= tolerance * (1.0 + 1e-3) + 1e-4,
                    "reached, but the hand is {d} from the target (tolerance {tolerance})"
                );
            }
            return Ok(outcome);
        }
    }
    Err(TestCaseError::fail(format!(
        "no outcome after {} steps (cap {})",
        s.max_steps + 1,
        s.max_steps
    )))
}

/// Seeded and without failure files: every run checks the same cases.
fn runner(cases: u32, seed: u64) -> TestRunner {
    let cases = std::env::var("PROPERTY_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(cases);
    TestRunner::new(Config {
        cases,
        rng_algorithm: RngAlgorithm::ChaCha,
        rng_seed: RngSeed::Fixed(seed),
        failure_persistence: None,
        ..Config::default()
    })
}

/// Counts of outcomes, so a property that only ever tests one kind of run is seen.
/// (Counted through `&self`: proptest's runner takes an `Fn` closure.)
#[derive(Default, Debug)]
struct Tally {
    reached: Cell<u32>,
    stalled: Cell<u32>,
    capped: Cell<u32>,
    with_obstacles: Cell<u32>,
}

impl Tally {
    fn add(&self, outcome: Outcome, obstacles: usize) {
        let count = match outcome {
            Outcome::Reached => &self.reached,
            Outcome::Stalled => &self.stalled,
            Outcome::Capped => &self.capped,
        };
        count.set(count.get() + 1);
        self.with_obstacles
            .set(self.with_obstacles.get() + (obstacles > 0) as u32);
    }
}

#[test]
fn random_chains_keep_every_invariant_at_every_step() {
    let tally = Tally::default();
    let result = runner(CASES, 0x6361_7070_0006_0001).run(&case(3..=32, 300), |case| {
        let joints: Vec<Joint> = case.joints.iter().map(JointSpec::joint).collect();
        let (sc, start) = build(&joints, &case);
        let outcome = check_run(&sc, &start)?;
        tally.add(outcome, sc.obstacles().len());
        Ok(())
    });
    if let Err(e) = result {
        panic!("{e}");
    }
    println!("random chains: {tally:?}");
    // The cases must exercise every ending and obstacles (over the full default count).
    if std::env::var("PROPERTY_CASES").is_err() {
        let (reached, stalled, capped) =
            (tally.reached.get(), tally.stalled.get(), tally.capped.get());
        assert!(reached > 50 && stalled > 50 && capped > 50, "{tally:?}");
        assert!(tally.with_obstacles.get() > CASES / 2, "{tally:?}");
    }
}

#[test]
fn pips_keeps_every_invariant_among_random_obstacles() {
    let pips = pips::joints();
    let spec = (
        fractions(),
        fractions(),
        target_kind(),
        prop::collection::vec(obstacle_spec(), 1..=6),
        settings_spec(400),
    );
    let tally = Tally::default();
    let result = runner(PIPS_CASES, 0x6361_7070_0006_0002).run(
        &spec,
        |(start, goal, target, obstacles, settings)| {
            // Obstacles a few inches across, margins of an inch or so: PIPS is ~100 in long.
            let obstacles = obstacles
                .into_iter()
                .map(|mut o| {
                    o.semi_axes = o.semi_axes.map(|x| 3.0 * x);
                    o.offset = o.offset.map(|x| 5.0 * x);
                    o
                })
                .collect();
            let case = Case {
                joints: vec![],
                start,
                goal,
                via: None,
                target,
                obstacles,
                settings,
            };
            let (sc, start) = build(&pips, &case);
            let outcome = check_run(&sc, &start)?;
            tally.add(outcome, sc.obstacles().len());
            Ok(())
        },
    );
    if let Err(e) = result {
        panic!("{e}");
    }
    println!("PIPS: {tally:?}");
}
