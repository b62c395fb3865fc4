//! The benchmark scenarios, built the same way (same `f32` bits) on the host
//! and on the Cortex-M4F, so both sets of figures are for the same problems.
//!
//! * [`pips`]: PIPS (Table 1) from home toward the payload-bay target of
//!   `host-sim/scenarios/pips_payload_bay.toml` (inches, 6 in from a point aft
//!   of the payload, looking along -y). With `k >= 3` obstacles the first three
//!   are that scenario's bay floor, payload and aft bulkhead; the rest are
//!   small "equipment" super-ellipsoids (semi-axes 2 to 6 in, exponents 2, 4
//!   or 8) scattered around the arm's path from its start to the target. With
//!   `k < 3` only equipment is used.
//! * [`chain`]: a serpentine chain of `n` revolute joints (alternating +-90 deg
//!   twists, like the PIPS truss) of 160 in total length, from a gentle arc to
//!   a reachable pose, with `m` equipment obstacles scattered the same way.
//! * [`pips_escape`] and [`pips_dead_end`]: the shipped scenarios of those
//!   names (`host-sim/scenarios/*.toml`, the same bits: a test plans both
//!   ways), where the planner escapes a dead end, and where it spends its
//!   escape budget and stalls. Their steps measure what escaping costs.
//!
//! Equipment is placed by a fixed pseudo-random sequence; a candidate is kept
//! only when every avoidance point of the start configuration, and the target
//! point, is clear of it by `C - 1 >= MIN_START_CLEARANCE` (so the planner can
//! start and the target is not inside anything). The scene is then advanced
//! [`WARM_UP_STEPS`] planner steps ([`warm_up`]) so the arm is moving and the
//! obstacles near it are within influence; that planner state is the
//! configuration every figure is measured at.

use capp_core::avoidance::points;
use capp_core::control::LawKind;
use capp_core::kinematics::{forward_kinematics, Frames};
use capp_core::math::Vec3;
use capp_core::obstacle::Obstacle;
use capp_core::self_collision::pairs::{PairTable, SAMPLES};
use capp_core::{
    pips, Joint, Mission, Planner, Robot, Scenario, ScenarioError, Settings, StartError, StepError,
    SuperEllipsoid, Waypoint,
};

/// Obstacle capacity of every benchmark scenario.
pub const MAX_OBSTACLES: usize = 64;
/// Joint capacity of the chain scenarios.
pub const MAX_CHAIN_JOINTS: usize = 32;
/// PIPS joints.
pub const PIPS_JOINTS: usize = pips::JOINTS;
/// Planner steps taken from the start before anything is measured.
pub const WARM_UP_STEPS: u32 = 10;
/// Obstacle counts of the PIPS figures.
pub const PIPS_OBSTACLES: [usize; 3] = [0, 8, 32];
/// Joint counts of the scaling sweep.
pub const SCALING_JOINTS: [usize; 5] = [6, 12, 18, 24, 32];
/// Obstacle counts of the scaling sweep.
pub const SCALING_OBSTACLES: [usize; 5] = [0, 8, 16, 32, 64];
/// Clearance (`C - 1` of the inflated obstacle) every start point keeps from placed equipment.
pub const MIN_START_CLEARANCE: f32 = 0.5;
/// Total length of a benchmark chain, inches.
pub const CHAIN_LENGTH_IN: f32 = 160.0;

/// A PIPS scenario.
pub type PipsScenario = Scenario<PIPS_JOINTS, MAX_OBSTACLES, 1>;
/// A chain scenario (up to 32 joints).
pub type ChainScenario = Scenario<MAX_CHAIN_JOINTS, MAX_OBSTACLES, 1>;

/// Why a benchmark scene could not be built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SceneError {
    /// The capp-core constructors refused it.
    Scenario(ScenarioError),
    /// The planner refused the start.
    Start(StartError),
    /// The planner refused a step.
    Step(StepError),
    /// More joints or obstacles than the capacities, or fewer than 2 joints.
    Size,
    /// No free place was found for an equipment obstacle.
    Crowded,
}

impl From<ScenarioError> for SceneError {
    fn from(e: ScenarioError) -> Self {
        SceneError::Scenario(e)
    }
}

impl From<StartError> for SceneError {
    fn from(e: StartError) -> Self {
        SceneError::Start(e)
    }
}

impl From<StepError> for SceneError {
    fn from(e: StepError) -> Self {
        SceneError::Step(e)
    }
}

/// A scenario, its start configuration (`n` values used) and its joint count.
#[derive(Clone, Debug)]
pub struct Scene<const N: usize> {
    /// Robot, obstacles, mission.
    pub scenario: Scenario<N, MAX_OBSTACLES, 1>,
    /// Start configuration (first `joints` values).
    pub start: [f32; N],
    /// Joints of the robot.
    pub joints: usize,
}

/// Reproducible uniform numbers (64-bit LCG, upper bits).
struct Lcg(u64);

impl Lcg {
    /// Uniform in `[lo, hi)`.
    fn uniform(&mut self, lo: f32, hi: f32) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let unit = (self.0 >> 40) as f32 / (1u64 << 24) as f32;
        lo + (hi - lo) * unit
    }
}

/// The payload-bay target: position (inches) and orientation rows (end z axis along -y).
pub const BAY_TARGET: ([f32; 3], [[f32; 3]; 3]) = (
    [124.0, 51.0, 32.0],
    [[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]],
);

/// Bay floor, payload (a cylinder along x) and aft bulkhead of `pips_payload_bay.toml`.
pub fn bay() -> [SuperEllipsoid; 3] {
    [
        SuperEllipsoid::aligned([60.0, 50.0, -18.0], [250.0, 250.0, 10.0], 8.0),
        SuperEllipsoid {
            centre: [70.0, 45.0, 32.0],
            semi_axes: [30.0, 18.0, 18.0],
            exponents: [8.0, 2.0, 2.0],
            euler_123: [0.0; 3],
        },
        SuperEllipsoid::aligned([160.0, 50.0, 40.0], [10.0, 250.0, 250.0], 8.0),
    ]
}

/// Settings of every benchmark scene: the defaults, with the payload-bay run's step cap.
pub fn settings() -> Settings {
    Settings {
        max_steps: 30_000,
        ..Settings::default()
    }
}

/// Whether `s` keeps every start point and the target clear (see module docs).
fn clear_of<const N: usize>(
    s: &SuperEllipsoid,
    frames: &Frames<N>,
    target: &Vec3,
    settings: &Settings,
) -> bool {
    let avoidance = &settings.avoidance;
    let Ok(o) = Obstacle::new(0, s, avoidance.margins(), avoidance.influence_distance) else {
        return false;
    };
    let ok = |p: &Vec3, kind| o.clearance_uncut(p, kind, &[]) >= MIN_START_CLEARANCE;
    points(frames, avoidance).all(|point| ok(&point.position, point.kind))
        && ok(target, capp_core::obstacle::PointKind::Joint)
}

/// Appends `count` equipment obstacles around the path from the start points
/// (`frames`) to `target`: a random start point, a random fraction of the way
/// to the target, 8 to 30 in off it in a random direction.
fn scatter<const N: usize>(
    frames: &Frames<N>,
    target: [f32; 3],
    count: usize,
    seed: u64,
    out: &mut heapless::Vec<SuperEllipsoid, MAX_OBSTACLES>,
) -> Result<(), SceneError> {
    let settings = settings();
    let target_v = Vec3::new(target[0], target[1], target[2]);
    let mut rng = Lcg(seed);
    let n = frames.len();
    let mut placed = 0;
    let mut tries = 0;
    while placed < count {
        tries += 1;
        if tries > 400 * (count + 1) {
            return Err(SceneError::Crowded);
        }
        let from = frames.link_end((rng.uniform(0.0, n as f32) as usize).min(n - 1));
        let t = rng.uniform(0.0, 1.0);
        let on_path = from + (target_v - from) * t;
        let dir = Vec3::new(
            rng.uniform(-1.0, 1.0),
            rng.uniform(-1.0, 1.0),
            rng.uniform(-1.0, 1.0),
        );
        let size = libm::sqrtf(dir.dot(&dir));
        if !(0.1..=1.0).contains(&size) {
            continue;
        }
        let centre = on_path + dir * (rng.uniform(8.0, 30.0) / size);
        let exponent = [2.0, 4.0, 8.0][(rng.uniform(0.0, 3.0) as usize).min(2)];
        let s = SuperEllipsoid::aligned(
            [centre.x, centre.y, centre.z],
            [
                rng.uniform(2.0, 6.0),
                rng.uniform(2.0, 6.0),
                rng.uniform(2.0, 6.0),
            ],
            exponent,
        );
        if clear_of(&s, frames, &target_v, &settings) {
            out.push(s).map_err(|_| SceneError::Size)?;
            placed += 1;
        }
    }
    Ok(())
}

/// Influence distances (inches) of the sweep that shows what the setting
/// costs: the default (24 in) and smaller ones (PIPS, 8 obstacles).
pub const INFLUENCE_SWEEP_IN: [f32; 4] = [24.0, 12.0, 6.0, 3.0];

/// Gives a PIPS scenario the capsules and checked pairs `capp run` gives
/// it: [`pips::LINK_RADIUS`], the pedestal group allowed, the
/// allowed-collision matrix of the host's seed.
pub fn pips_capsules<const M: usize, const W: usize>(
    scenario: &mut Scenario<PIPS_JOINTS, M, W>,
) -> Result<(), SceneError> {
    let radius = [pips::LINK_RADIUS; PIPS_JOINTS];
    let mut allowed = heapless::Vec::<(u8, u8), 16>::new();
    for pair in pips::allowed_pairs() {
        allowed.push(pair).map_err(|_| SceneError::Size)?;
    }
    let table = PairTable::<PIPS_JOINTS>::new(
        scenario.robot(),
        &radius,
        &allowed,
        &pips::home(),
        SAMPLES,
        PAIR_SEED,
    )
    .map_err(ScenarioError::Capsules)?;
    scenario.set_link_capsules(&radius, table.checked_rows())?;
    Ok(())
}

/// The seed of the host's allowed-collision matrix (`capp_sim::problem::PAIR_SEED`).
pub const PAIR_SEED: u32 = 1;

/// [`pips`] without self-collision checks (the cost they add is the
/// difference of the two).
pub fn pips_without_self_collision(obstacles: usize) -> Result<Scene<PIPS_JOINTS>, SceneError> {
    pips_with(obstacles, settings(), false)
}

/// [`pips`] under the tracker (`Motion::Tracked`, issue 22): fixed ticks
/// within the drive limits, each tick's stop cleared.
pub fn pips_tracked(obstacles: usize) -> Result<Scene<PIPS_JOINTS>, SceneError> {
    let settings = Settings {
        motion: capp_core::Motion::Tracked,
        ..settings()
    };
    pips_with(obstacles, settings, true)
}

/// PIPS from home toward the payload-bay target with `obstacles` obstacles (at most 64).
pub fn pips(obstacles: usize) -> Result<Scene<PIPS_JOINTS>, SceneError> {
    pips_with(obstacles, settings(), true)
}

/// [`pips`] with the avoidance influence distance set to `influence_in` inches
/// (the same obstacles: where they are placed does not depend on it).
pub fn pips_with_influence(
    obstacles: usize,
    influence_in: f32,
) -> Result<Scene<PIPS_JOINTS>, SceneError> {
    let mut s = settings();
    s.avoidance.influence_distance = influence_in;
    pips_with(obstacles, s, true)
}

/// [`pips`] driven by the law `kind` (the same obstacles).
pub fn pips_with_law(obstacles: usize, kind: LawKind) -> Result<Scene<PIPS_JOINTS>, SceneError> {
    let mut s = settings();
    s.law.kind = kind;
    pips_with(obstacles, s, true)
}

/// [`pips`] with the arm written as general joints
/// ([`capp_core::robot::general_from_dh`]): what a URDF robot's forward
/// pass costs against the DH one, on the same arm and obstacles.
pub fn pips_general(obstacles: usize) -> Result<Scene<PIPS_JOINTS>, SceneError> {
    let mut joints = pips::joints();
    let tool = capp_core::robot::general_from_dh(&pips::joints(), &mut joints);
    let robot = Robot::new_with_tool(&joints, &tool).map_err(ScenarioError::Robot)?;
    pips_robot(robot, obstacles, settings(), true)
}

/// [`pips_general`] with every link's self-collision capsule a segment of
/// its own ([`Robot::set_link_segments`]): its chord written in its body's
/// frame (a prismatic link's from its moved origin), what a URDF robot
/// whose bodies lie off their chords costs against chords.
pub fn pips_segments(obstacles: usize) -> Result<Scene<PIPS_JOINTS>, SceneError> {
    let mut joints = pips::joints();
    let tool = capp_core::robot::general_from_dh(&pips::joints(), &mut joints);
    let mut robot = Robot::new_with_tool(&joints, &tool).map_err(ScenarioError::Robot)?;
    let mut segments = [[[0.0f32; 3]; 2]; PIPS_JOINTS];
    for (k, segment) in segments.iter_mut().enumerate() {
        let end = match joints.get(k + 1).and_then(|j| j.origin) {
            Some(next) => next.placement.translation,
            None => tool.translation,
        };
        segment[1] = end;
    }
    robot
        .set_link_segments(&segments)
        .map_err(|e| ScenarioError::Capsules(e.into()))?;
    pips_robot(robot, obstacles, settings(), true)
}

fn pips_with(
    obstacles: usize,
    settings: Settings,
    self_collision: bool,
) -> Result<Scene<PIPS_JOINTS>, SceneError> {
    let robot = pips::robot::<PIPS_JOINTS>().map_err(ScenarioError::Robot)?;
    pips_robot(robot, obstacles, settings, self_collision)
}

fn pips_robot(
    robot: Robot<PIPS_JOINTS>,
    obstacles: usize,
    settings: Settings,
    self_collision: bool,
) -> Result<Scene<PIPS_JOINTS>, SceneError> {
    if obstacles > MAX_OBSTACLES {
        return Err(SceneError::Size);
    }
    let start = pips::home();
    let mut frames = Frames::<PIPS_JOINTS>::default();
    forward_kinematics(&robot, &start, &mut frames);
    let mut list = heapless::Vec::new();
    let equipment = if obstacles >= 3 {
        for s in bay() {
            list.push(s).map_err(|_| SceneError::Size)?;
        }
        obstacles - 3
    } else {
        obstacles
    };
    scatter(&frames, BAY_TARGET.0, equipment, 0x5eed_0018, &mut list)?;
    let mission = Mission::new(&[Waypoint::pose(BAY_TARGET.0, BAY_TARGET.1)], settings)
        .map_err(ScenarioError::Mission)?;
    let mut scenario = Scenario::new(robot, &list, &mission)?;
    if self_collision {
        pips_capsules(&mut scenario)?;
    }
    Ok(Scene {
        scenario,
        start,
        joints: PIPS_JOINTS,
    })
}

/// Start configuration of `pips_escape.toml` (radians, inches).
pub const ESCAPE_START: [f32; PIPS_JOINTS] = [
    -1.6832609,
    1.0917926,
    15.179916,
    6.093105,
    2.0797715,
    -0.14854138,
    -0.5489637,
    -0.22456053,
    -0.32395813,
    -0.2730467,
    0.4145076,
    0.13431841,
    -0.10170754,
    0.5062611,
    -0.43130675,
    0.2986523,
    2.1118379,
    -1.8190794,
];

/// Target of `pips_escape.toml`: position (inches) and orientation rows.
pub const ESCAPE_TARGET: ([f32; 3], [[f32; 3]; 3]) = (
    [-39.453037, -52.63705, 85.17095],
    [
        [-0.7504836, 0.63740444, 0.17461392],
        [0.6010404, 0.7681348, -0.22072454],
        [-0.27481782, -0.060700104, -0.9595784],
    ],
);

/// The obstacles of `pips_escape.toml`, in its order.
pub fn escape_obstacles() -> [SuperEllipsoid; 7] {
    [
        // bay floor
        SuperEllipsoid {
            centre: [60.0, 50.0, -18.704313],
            semi_axes: [250.0, 250.0, 10.0],
            exponents: [8.0, 8.0, 8.0],
            euler_123: [0.0; 3],
        },
        // aft bulkhead
        SuperEllipsoid {
            centre: [163.18277, 50.0, 40.0],
            semi_axes: [10.0, 250.0, 250.0],
            exponents: [8.0, 8.0, 8.0],
            euler_123: [0.0; 3],
        },
        // payload 1
        SuperEllipsoid {
            centre: [42.630444, 41.290623, 22.82558],
            semi_axes: [29.411991, 12.669356, 12.669356],
            exponents: [8.0, 2.0, 2.0],
            euler_123: [0.0; 3],
        },
        // payload 2
        SuperEllipsoid {
            centre: [63.17576, 44.907036, 33.079994],
            semi_axes: [27.14336, 18.073282, 18.073282],
            exponents: [8.0, 2.0, 2.0],
            euler_123: [0.0; 3],
        },
        // equipment 1
        SuperEllipsoid {
            centre: [113.51032, 67.19522, -0.059413668],
            semi_axes: [7.024546, 9.962389, 8.644899],
            exponents: [8.0, 8.0, 8.0],
            euler_123: [0.0; 3],
        },
        // bracket
        SuperEllipsoid {
            centre: [-34.856926, -68.290985, 50.455906],
            semi_axes: [2.4768205, 1.8619685, 2.5057402],
            exponents: [8.0, 8.0, 8.0],
            euler_123: [0.0; 3],
        },
        // box (in the way)
        SuperEllipsoid {
            centre: [-35.09874, -74.08408, 87.66051],
            semi_axes: [6.9067373, 7.884667, 5.923332],
            exponents: [8.0, 8.0, 8.0],
            euler_123: [0.0; 3],
        },
    ]
}

/// `host-sim/scenarios/pips_escape.toml`: a dead end (a box on the
/// end-effector path) the planner escapes by a detour, then reaches.
pub fn pips_escape() -> Result<Scene<PIPS_JOINTS>, SceneError> {
    pips_scene(
        |defaults| Settings {
            position_tolerance: 0.1,
            ..defaults
        },
        &[Waypoint::pose(ESCAPE_TARGET.0, ESCAPE_TARGET.1)],
        &escape_obstacles(),
        ESCAPE_START,
    )
}

/// `host-sim/scenarios/pips_dead_end.toml`: from home toward a target walled
/// in by a 600 in wall; no path exists, the escape spends its budget and the
/// run ends stalled.
pub fn pips_dead_end() -> Result<Scene<PIPS_JOINTS>, SceneError> {
    let wall = SuperEllipsoid {
        centre: [14.142, -14.142, 0.0],
        semi_axes: [3.0, 300.0, 300.0],
        exponents: [8.0; 3],
        euler_123: [0.0, 0.0, -core::f32::consts::FRAC_PI_4],
    };
    pips_scene(
        |defaults| Settings {
            stall_window: 300,
            ..defaults
        },
        &[Waypoint::at([100.0, 40.0, 10.0])],
        &[wall],
        pips::home(),
    )
}

/// A PIPS scene of a shipped scenario: `settings` amends the defaults for
/// PIPS (`Settings::for_robot`) as the file's `[settings]` table does.
fn pips_scene(
    settings: impl FnOnce(Settings) -> Settings,
    waypoints: &[Waypoint],
    obstacles: &[SuperEllipsoid],
    start: [f32; PIPS_JOINTS],
) -> Result<Scene<PIPS_JOINTS>, SceneError> {
    let robot = pips::robot::<PIPS_JOINTS>().map_err(ScenarioError::Robot)?;
    let settings = settings(Settings::for_robot(&robot));
    let mission = Mission::new(waypoints, settings).map_err(ScenarioError::Mission)?;
    let mut scenario = Scenario::new(robot, obstacles, &mission)?;
    pips_capsules(&mut scenario)?;
    Ok(Scene {
        scenario,
        start,
        joints: PIPS_JOINTS,
    })
}

/// The joints of a benchmark chain of `n` revolute joints: alternating +-90
/// deg twists, links of `CHAIN_LENGTH_IN / n` in, a 10 in pedestal offset on
/// the first joint, limits +-120 deg, PIPS's revolute rate limit.
pub fn chain_joints(n: usize) -> impl Iterator<Item = Joint> {
    let half_pi = core::f32::consts::FRAC_PI_2;
    let limit = 120.0f32.to_radians();
    let link = CHAIN_LENGTH_IN / n as f32;
    (0..n).map(move |j| {
        let alpha = if j % 2 == 0 { half_pi } else { -half_pi };
        let d = if j == 0 { 10.0 } else { 0.0 };
        Joint::revolute(alpha, link, d, -limit, limit, pips::REVOLUTE_RATE)
    })
}

/// Start configuration of joint `j` of a chain: a gentle arc.
fn chain_start(j: usize) -> f32 {
    0.1 + 0.05 * (j % 3) as f32
}

/// Target configuration of joint `j` (its pose is the target).
fn chain_goal(j: usize) -> f32 {
    chain_start(j) + 1.0 * libm::sinf(1.3 * j as f32 + 0.5)
}

/// A chain of `joints` (2 to 32) revolute joints with `obstacles` (at most 64)
/// equipment obstacles, from a gentle arc to the pose of another configuration.
pub fn chain(joints: usize, obstacles: usize) -> Result<Scene<MAX_CHAIN_JOINTS>, SceneError> {
    if !(2..=MAX_CHAIN_JOINTS).contains(&joints) || obstacles > MAX_OBSTACLES {
        return Err(SceneError::Size);
    }
    let mut list: heapless::Vec<Joint, MAX_CHAIN_JOINTS> = heapless::Vec::new();
    for joint in chain_joints(joints) {
        list.push(joint).map_err(|_| SceneError::Size)?;
    }
    let robot = Robot::<MAX_CHAIN_JOINTS>::new(&list).map_err(ScenarioError::Robot)?;
    let mut start = [0.0; MAX_CHAIN_JOINTS];
    let mut goal = [0.0; MAX_CHAIN_JOINTS];
    for j in 0..joints {
        start[j] = chain_start(j);
        goal[j] = chain_goal(j);
    }
    let mut frames = Frames::<MAX_CHAIN_JOINTS>::default();
    forward_kinematics(&robot, &goal[..joints], &mut frames);
    let p = frames.end_position();
    let r = frames.end_rotation();
    let target = [p.x, p.y, p.z];
    let rows = [0, 1, 2].map(|i| [r[(i, 0)], r[(i, 1)], r[(i, 2)]]);
    forward_kinematics(&robot, &start[..joints], &mut frames);
    let mission = Mission::new(&[Waypoint::pose(target, rows)], settings())
        .map_err(ScenarioError::Mission)?;
    // The first placement whose warmed-up planner takes plain steps: a trapped
    // arm halving every step would measure the halvings, not the scaling.
    let mut attempt = 0;
    loop {
        let mut placed = heapless::Vec::new();
        let seed = 0x5eed_0000 + ((attempt as u64) << 8) + joints as u64;
        scatter(&frames, target, obstacles, seed, &mut placed)?;
        let scene = Scene {
            scenario: Scenario::new(robot.clone(), &placed, &mission)?,
            start,
            joints,
        };
        attempt += 1;
        if attempt >= PLACEMENT_ATTEMPTS || settle(&scene)?.1 {
            return Ok(scene);
        }
    }
}

/// Placements [`chain`] tries before it keeps one whose steps halve.
pub const PLACEMENT_ATTEMPTS: u32 = 8;

/// Most steps [`warm_up`] takes beyond [`WARM_UP_STEPS`] looking for a plain step.
pub const MAX_EXTRA_STEPS: u32 = 200;

/// A planner started at `scene.start` and advanced [`WARM_UP_STEPS`] steps,
/// then on until its next step is a plain one (taken at its first step size,
/// no halving; at most [`MAX_EXTRA_STEPS`] more): the state every figure is
/// measured from. A step that halves costs one more evaluation per halving
/// (up to `max_halvings + 1` in all); the trajectory windows include those.
pub fn warm_up<const N: usize>(scene: &Scene<N>) -> Result<Planner<N>, SceneError> {
    settle(scene).map(|(planner, _)| planner)
}

/// [`warm_up`], and whether a plain step was found.
fn settle<const N: usize>(scene: &Scene<N>) -> Result<(Planner<N>, bool), SceneError> {
    let sc = &scene.scenario;
    let mut planner = Planner::new(sc, &scene.start[..scene.joints])?;
    for _ in 0..WARM_UP_STEPS {
        planner.step(sc)?;
    }
    for _ in 0..MAX_EXTRA_STEPS {
        let mut trial = planner.clone();
        let report = trial.step(sc)?;
        if report.halvings == 0 && report.time_step_s > 0.0 {
            return Ok((planner, true));
        }
        planner = trial;
    }
    Ok((planner, false))
}
