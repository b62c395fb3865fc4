//! The loaded planning problem: everything `capp-core` needs (joints,
//! obstacles, waypoints, settings) plus the start configuration and where each
//! item came from in its file, so that every rejection names the file and line.
//!
//! This module is a leaf: it names the types the readers produce and knows
//! nothing of file formats. Both readers ([`crate::input::scenario_file`],
//! [`crate::input::legacy`]) produce a [`Problem`], and [`crate::input`]
//! chooses between them ([`Problem::load`]); [`Problem::validate`] then runs
//! the core's own checks (robot, obstacles, mission, start) and turns their
//! errors into [`LoadError`]s.
//! Capacities: [`MAX_JOINTS`] joints, [`MAX_OBSTACLES`] obstacles,
//! [`MAX_WAYPOINTS`] waypoints (the target included).

use std::fmt;
use std::path::{Path, PathBuf};

use capp_core::robot::{Placement, RobotError};
use capp_core::self_collision::pairs::{PairTable, SAMPLES};
use capp_core::{
    Joint, Mission, MissionError, Planner, Robot, Scenario, ScenarioError, SetpointFilter,
    Settings, Solid, StartError, Waypoint,
};

/// Joint capacity of the simulator.
pub const MAX_JOINTS: usize = 32;
/// Obstacle capacity of the simulator.
pub const MAX_OBSTACLES: usize = 64;
/// Waypoint capacity (the target included).
pub const MAX_WAYPOINTS: usize = 16;

/// The core scenario at the simulator's capacities.
pub type CoreScenario = Scenario<MAX_JOINTS, MAX_OBSTACLES, MAX_WAYPOINTS>;
/// The core planner at the simulator's capacity.
pub type CorePlanner = Planner<MAX_JOINTS>;

/// A rejected input: the file, the line where the format has lines, the problem.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LoadError {
    /// The file.
    pub file: PathBuf,
    /// 1-based line, when known.
    pub line: Option<usize>,
    /// What is wrong, in one sentence.
    pub message: String,
}

impl LoadError {
    /// An error at `line` (if any) of `file`.
    pub fn new(file: &Path, line: Option<usize>, message: impl Into<String>) -> Self {
        LoadError {
            file: file.to_path_buf(),
            line,
            message: message.into(),
        }
    }
}

impl fmt::Display for LoadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(line) => write!(f, "{}:{line}: {}", self.file.display(), self.message),
            None => write!(f, "{}: {}", self.file.display(), self.message),
        }
    }
}

impl std::error::Error for LoadError {}

/// Which reader produced a problem.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SourceKind {
    /// A TOML scenario file.
    Toml,
    /// CAPP.c's `input.dat`.
    Legacy,
}

/// 1-based lines of the items of a problem in its file (`None` where unknown).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Lines {
    /// The robot section.
    pub robot: Option<usize>,
    /// Per joint.
    pub joints: Vec<Option<usize>>,
    /// Per obstacle.
    pub obstacles: Vec<Option<usize>>,
    /// Per waypoint (the target last).
    pub waypoints: Vec<Option<usize>>,
    /// Per waypoint, the line of its orientation when that is elsewhere.
    pub orientations: Vec<Option<usize>>,
    /// The settings section.
    pub settings: Option<usize>,
    /// The start configuration.
    pub start: Option<usize>,
    /// Per `[[robot.allow]]` entry.
    pub allow: Vec<Option<usize>>,
}

/// The links' capsules and the pairs allowed to touch, as the file gives
/// them (the core checks them: [`capp_core::self_collision`]).
#[derive(Clone, Debug, PartialEq)]
pub struct LinkGeometry {
    /// Whether self-collision is checked at all (`[robot] self_collision`).
    pub enabled: bool,
    /// Capsule radius per link, length units.
    pub radius: Vec<f32>,
    /// Each link's capsule segment, when it is not the chord: empty for a
    /// robot whose capsules are round its chords (every DH robot), else one
    /// per link, the segment's two ends in the frame of the body joint `k`
    /// moves (after its motion: `geometry::joint_frames`' `T_k`), length
    /// units. The core's `Scenario::set_link_segments` takes them.
    pub segments: Vec<[[f32; 3]; 2]>,
    /// Pairs of links (0-based) allowed to touch: the preset's and `[[robot.allow]]`'s.
    pub allowed: Vec<(usize, usize)>,
    /// The home configuration, for the pairs in contact there.
    pub home: Vec<f32>,
}

/// A URDF robot's file, chain ends and collision geometry, for reports.
#[derive(Clone, Debug, PartialEq)]
pub struct UrdfSource {
    /// The URDF file.
    pub file: PathBuf,
    /// `<robot name>`.
    pub robot_name: String,
    /// The chain's base link.
    pub base_link: String,
    /// The chain's tip link.
    pub tip_link: String,
    /// Per rigid body, metres: `bodies[0]` on the base, `bodies[k + 1]`
    /// moved by joint `k`, each with its links and fitted capsules in its
    /// own frame (its pivot slid as [`UrdfSource::pivot_slide`] says).
    pub bodies: Vec<capp_urdf::Body>,
    /// How far each joint's pivot was slid along its unit axis from the
    /// URDF's joint origin, metres (`input::pivots`): the joints' origins
    /// and the bodies are given in the slid frames.
    pub pivot_slide: Vec<f64>,
    /// The scenario's length units per metre (`bodies` times this is in
    /// the scenario's units).
    pub per_metre: f64,
}

/// Seed of the sampled configurations of the allowed-collision matrix.
pub const PAIR_SEED: u32 = 1;

/// Default `[robot] ramp_time_s`: a joint reaches its rate limit from rest
/// in this long at its acceleration limit (`max_accel = max_rate / ramp_time_s`).
pub const DEFAULT_RAMP_TIME_S: f64 = 0.5;
/// Default `[robot] jerk_time_s`: a joint reaches its acceleration limit
/// from zero in this long at its jerk limit (`max_jerk = max_accel / jerk_time_s`).
pub const DEFAULT_JERK_TIME_S: f64 = 0.1;
/// Default `[settings] control_period_s`: the drives' fixed period, s.
pub const DEFAULT_CONTROL_PERIOD_S: f64 = 0.05;

/// One joint's drive limits, in the problem's units (radians or length
/// units, per s, s^2, s^3). The rate is the joint's `max_rate` widened
/// exactly from `f32`, the limit the planner works to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointDriveLimits {
    /// Largest speed, per s (the joint's `max_rate`).
    pub max_rate: f64,
    /// Largest acceleration, per s^2.
    pub max_accel: f64,
    /// Largest jerk, per s^3.
    pub max_jerk: f64,
}

impl JointDriveLimits {
    /// The defaults from a rate: `max_accel = max_rate / ramp_time_s`,
    /// `max_jerk = max_accel / jerk_time_s`.
    pub fn from_rate(max_rate: f64, ramp_time_s: f64, jerk_time_s: f64) -> Self {
        let max_accel = max_rate / ramp_time_s;
        JointDriveLimits {
            max_rate,
            max_accel,
            max_jerk: max_accel / jerk_time_s,
        }
    }
}

/// What a joint drive can follow (issue 22): a fixed control period and
/// each joint's rate, acceleration and jerk limits. Today the independent
/// checker ([`crate::drive_check`]) measures trajectories against them; the
/// planner does not yet obey them.
#[derive(Clone, Debug, PartialEq)]
pub struct DriveLimits {
    /// The drives' fixed period, s, in (0, 1].
    pub control_period_s: f64,
    /// Per joint, in joint order.
    pub joints: Vec<JointDriveLimits>,
}

impl DriveLimits {
    /// The defaults for `joints` ([`DEFAULT_RAMP_TIME_S`],
    /// [`DEFAULT_JERK_TIME_S`], [`DEFAULT_CONTROL_PERIOD_S`]): what the
    /// listing's `input.dat` and a file without drive keys get.
    pub fn defaults(joints: &[Joint]) -> Self {
        DriveLimits {
            control_period_s: DEFAULT_CONTROL_PERIOD_S,
            joints: joints
                .iter()
                .map(|j| {
                    JointDriveLimits::from_rate(
                        j.max_rate as f64,
                        DEFAULT_RAMP_TIME_S,
                        DEFAULT_JERK_TIME_S,
                    )
                })
                .collect(),
        }
    }
}

/// A planning problem in the core's units (radians, the file's length unit, seconds).
#[derive(Clone, Debug, PartialEq)]
pub struct Problem {
    /// Short name (the file stem unless the file names it).
    pub name: String,
    /// What the reader did that the user should know of, one line each
    /// (a mesh planned round an enclosure of its hull: `capp run` and
    /// `capp check` print them).
    pub notes: Vec<String>,
    /// One paragraph of description (may be empty).
    pub description: String,
    /// The file it was read from.
    pub source: PathBuf,
    /// Which reader.
    pub kind: SourceKind,
    /// Name of the length unit, for labels ("in", "m").
    pub length_unit: String,
    /// The joints: DH rows, or general joints (a URDF robot).
    pub joints: Vec<Joint>,
    /// The end effector's frame in the last joint's (a URDF robot's fixed
    /// joints after its last moving one); the identity for a DH table.
    pub tool: Placement,
    /// Where a URDF robot came from, with its collision geometry; `None`
    /// for a DH table or the preset.
    pub urdf: Option<UrdfSource>,
    /// Joint names (for messages and plots).
    pub joint_names: Vec<String>,
    /// The obstacles.
    pub obstacles: Vec<Solid>,
    /// Obstacle names.
    pub obstacle_names: Vec<String>,
    /// The hulls `Shape::Convex { hull }` obstacles name, by index: each
    /// one's vertices in its obstacle's frame, length units (at most
    /// `capp_core::obstacle::MAX_HULLS`, each validated by the core).
    pub hulls: Vec<Vec<[f32; 3]>>,
    /// Waypoints; the last is the target.
    pub waypoints: Vec<Waypoint>,
    /// Planner settings.
    pub settings: Settings,
    /// Start configuration.
    pub start: Vec<f32>,
    /// Which steps become setpoints.
    pub setpoints: SetpointFilter,
    /// Waypoints that are joint configurations: (waypoint index, one value
    /// per joint, radians or length units). Their entry in `waypoints` is a
    /// placeholder the core replaces by the configuration's pose.
    pub joint_goals: Vec<(usize, Vec<f32>)>,
    /// The links' capsules and allowed pairs.
    pub links: LinkGeometry,
    /// The control period and each joint's rate, acceleration and jerk limits.
    pub drive: DriveLimits,
    /// Where each item is in the file.
    pub lines: Lines,
}

impl Problem {
    fn error(&self, line: Option<usize>, message: impl Into<String>) -> LoadError {
        LoadError::new(&self.source, line, message)
    }

    /// The core robot: the joints and the tool, validated.
    pub fn robot(&self) -> Result<Robot<MAX_JOINTS>, RobotError> {
        Robot::new_with_tool(&self.joints, &self.tool)
    }

    /// The validated core scenario.
    pub fn scenario(&self) -> Result<CoreScenario, LoadError> {
        self.robot().map_err(|e| {
            let line = robot_error_joint(&e)
                .and_then(|j| self.lines.joints.get(j).copied().flatten())
                .or(self.lines.robot);
            self.error(line, format!("robot: {e}"))
        })?;
        Mission::<MAX_WAYPOINTS>::new(&self.waypoints, self.settings).map_err(|e| {
            self.error(
                self.lines.waypoints.last().copied().flatten(),
                e.to_string(),
            )
        })?;
        // The robot and the mission were checked above, so the scenario's
        // own checks report in the same order as `Scenario::new`'s.
        let hulls: Vec<&[[f32; 3]]> = self.hulls.iter().map(Vec::as_slice).collect();
        let mut scenario = CoreScenario::empty();
        let built = scenario.init_with_hulls(
            &self.joints,
            &self.tool,
            &self.obstacles,
            &hulls,
            &self.waypoints,
            self.settings,
        );
        built.map_err(|e| {
            let line = match e {
                ScenarioError::Robot(r) => {
                    robot_error_joint(&r).and_then(|j| self.lines.joints.get(j).copied().flatten())
                }
                ScenarioError::Obstacle(o) => obstacle_error_index(&o)
                    .or_else(|| self.hull_error_obstacle(&o))
                    .and_then(|i| self.lines.obstacles.get(i).copied().flatten()),
                ScenarioError::Mission(MissionError::BadSetting(_)) => self.lines.settings,
                ScenarioError::Mission(MissionError::NotARotation { waypoint }) => self
                    .lines
                    .orientations
                    .get(waypoint as usize)
                    .copied()
                    .flatten()
                    .or(self
                        .lines
                        .waypoints
                        .get(waypoint as usize)
                        .copied()
                        .flatten()),
                ScenarioError::Mission(MissionError::BadPosition { waypoint }) => self
                    .lines
                    .waypoints
                    .get(waypoint as usize)
                    .copied()
                    .flatten(),
                ScenarioError::Drive { joint, .. } => {
                    self.lines.joints.get(joint as usize).copied().flatten()
                }
                ScenarioError::Mission(_)
                | ScenarioError::Capsules(_)
                | ScenarioError::DriveLength => None,
            };
            let mut message = e.to_string();
            if let ScenarioError::Obstacle(o @ capp_core::ObstacleError::BadHull { why, .. }) = e {
                if let Some(i) = self.hull_error_obstacle(&o) {
                    message = format!("obstacle {}: its hull: {why}", i + 1);
                }
            }
            if let ScenarioError::Obstacle(o) = e {
                if let Some(i) = obstacle_error_index(&o).or_else(|| self.hull_error_obstacle(&o)) {
                    if let Some(name) = self.obstacle_names.get(i).filter(|n| !n.is_empty()) {
                        message = format!("{message} (\"{name}\")");
                    }
                }
            }
            if let ScenarioError::Mission(MissionError::BadPosition { .. }) = e {
                if self.kind == SourceKind::Toml && Some(self.waypoints.len() - 1) == last_index(&e)
                {
                    message =
                        message.replace(&format!("waypoint {}", self.waypoints.len()), "target");
                }
            }
            self.error(line, message)
        })?;
        for (waypoint, joints) in &self.joint_goals {
            scenario.set_joint_goal(*waypoint, joints).map_err(|e| {
                let mut message = e.to_string();
                if self.kind == SourceKind::Toml && *waypoint + 1 == self.waypoints.len() {
                    message = message.replace(&format!("waypoint {}", waypoint + 1), "target");
                }
                self.error(
                    self.lines.waypoints.get(*waypoint).copied().flatten(),
                    message,
                )
            })?;
        }
        if self.links.enabled {
            let table = self.pair_table()?;
            scenario
                .set_link_capsules(&self.links.radius, table.checked_rows())
                .map_err(|e| self.capsule_error(e))?;
            // As the board takes them: after the capsules (none: chords).
            scenario
                .set_link_segments(&self.links.segments)
                .map_err(|e| self.capsule_error(e))?;
        }
        // The defaults are the core's own (computed in f32, as the board
        // computes them), so host and board plan to the bit.
        let accel: Vec<f32> = self
            .drive
            .joints
            .iter()
            .map(|j| j.max_accel as f32)
            .collect();
        let jerk: Vec<f32> = self
            .drive
            .joints
            .iter()
            .map(|j| j.max_jerk as f32)
            .collect();
        let set = if self.default_drive_limits() {
            Ok(())
        } else {
            scenario.set_drive_limits(&accel, &jerk)
        };
        set.map_err(|e| {
            let line = match e {
                ScenarioError::Drive { joint, .. } => {
                    self.lines.joints.get(joint as usize).copied().flatten()
                }
                _ => self.lines.robot,
            };
            self.error(line, e.to_string())
        })?;
        Ok(scenario)
    }

    /// Whether every joint's acceleration and jerk limits are the defaults
    /// from its rate (capp-core's `DriveLimits::from_rate`, to a part in a
    /// million: the file's are computed in f64): the scenario keeps
    /// `from_rate`'s, and `capp serial` sends no drive limits (the board
    /// takes the same defaults).
    pub fn default_drive_limits(&self) -> bool {
        let near = |a: f64, b: f32| (a - b as f64).abs() <= 1e-6 * (b as f64).abs();
        self.joints.iter().zip(&self.drive.joints).all(|(j, d)| {
            let core = capp_core::tracker::limits::DriveLimits::from_rate(j.max_rate);
            near(d.max_accel, core.max_accel) && near(d.max_jerk, core.max_jerk)
        })
    }

    /// Which pairs of links are checked and why the others are skipped
    /// ([`capp_core::self_collision::pairs`]).
    pub fn pair_table(&self) -> Result<PairTable<MAX_JOINTS>, LoadError> {
        let mut robot = self
            .robot()
            .map_err(|e| self.error(self.lines.robot, format!("robot: {e}")))?;
        // The capsules as the planner checks them.
        robot
            .set_link_segments(&self.links.segments)
            .map_err(|e| self.capsule_error(ScenarioError::Capsules(e.into())))?;
        let allowed: Vec<(u8, u8)> = self
            .links
            .allowed
            .iter()
            .map(|&(a, b)| (a.min(255) as u8, b.min(255) as u8))
            .collect();
        PairTable::new(
            &robot,
            &self.links.radius,
            &allowed,
            &self.links.home,
            SAMPLES,
            PAIR_SEED,
        )
        .map_err(|e| self.capsule_error(ScenarioError::Capsules(e)))
    }

    fn capsule_error(&self, e: ScenarioError) -> LoadError {
        let line = match e {
            ScenarioError::Capsules(capp_core::self_collision::CapsuleError::BadRadius {
                link,
            }) => self.lines.joints.get(link as usize).copied().flatten(),
            _ => None,
        }
        .or(self.lines.robot);
        self.error(line, e.to_string())
    }

    /// `link 3 ("name")` for messages: DH link `k + 1`, after joint `k + 1`.
    pub fn link_label(&self, k: usize) -> String {
        match self.joint_names.get(k).filter(|n| !n.is_empty()) {
            Some(name) => format!("link {} (after joint \"{name}\")", k + 1),
            None => format!("link {}", k + 1),
        }
    }

    /// Runs every check of the core (robot, obstacles, mission, start
    /// configuration) and returns the scenario.
    pub fn validate(&self) -> Result<CoreScenario, LoadError> {
        let scenario = self.scenario()?;
        self.check_drive()?;
        CorePlanner::new(&scenario, &self.start).map_err(|e| {
            let message = match e {
                StartError::OutsideLimits { joint } => {
                    let j = joint as usize;
                    let joint = &self.joints[j];
                    format!(
                        "start configuration: {} = {} is outside its limits [{}, {}]",
                        self.joint_label(j),
                        self.start[j],
                        joint.min,
                        joint.max
                    )
                }
                StartError::NotFinite { joint } => format!(
                    "start configuration: {} is not a finite number",
                    self.joint_label(joint as usize)
                ),
                StartError::InObstacle { point, obstacle } => format!(
                    "start configuration puts the arm inside obstacle {}{} ({}; obstacles are inflated by the {} margin)",
                    obstacle as usize + 1,
                    self.obstacle_label(obstacle as usize),
                    self.describe_point(point),
                    if self.point_is_joint(point) { "joint" } else { "link" },
                ),
                StartError::SelfCollision { links: [a, b] } => format!(
                    "start configuration puts {} into {} (self-collision: their capsules touch{})",
                    self.link_label(a as usize),
                    self.link_label(b as usize),
                    // A URDF's capsules are round the chords between pivots,
                    // which can be far thicker than the bodies.
                    if self.urdf.is_some() {
                        "; `capp robot` shows each link's capsule against its body"
                    } else {
                        ""
                    },
                ),
                other => format!("start configuration: {other}"),
            };
            self.error(self.lines.start, message)
        })?;
        Ok(scenario)
    }

    /// The drive limits ([`DriveLimits`]): the control period in (0, 1] s,
    /// one entry per joint, every limit positive and finite (after the
    /// core has checked the rates they default from).
    fn check_drive(&self) -> Result<(), LoadError> {
        let period = self.drive.control_period_s;
        if !(period > 0.0 && period <= 1.0) {
            return Err(self.error(
                self.lines.settings,
                format!("settings.control_period_s must be in (0, 1] s (got {period})"),
            ));
        }
        if self.drive.joints.len() != self.joints.len() {
            return Err(self.error(
                self.lines.robot,
                format!(
                    "robot: drive limits for {} joints, the robot has {}",
                    self.drive.joints.len(),
                    self.joints.len()
                ),
            ));
        }
        for (j, limits) in self.drive.joints.iter().enumerate() {
            for (name, value) in [
                ("max_rate", limits.max_rate),
                ("max_accel", limits.max_accel),
                ("max_jerk", limits.max_jerk),
            ] {
                if !(value.is_finite() && value > 0.0) {
                    return Err(self.error(
                        self.lines
                            .joints
                            .get(j)
                            .copied()
                            .flatten()
                            .or(self.lines.robot),
                        format!(
                            "robot: {}: {name} must be positive and finite (got {value})",
                            self.joint_label(j)
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// The obstacle (0-based) whose hull a hull error is about: the first
    /// convex obstacle naming the bad hull, or for too many hulls the first
    /// convex obstacle past the capacity.
    fn hull_error_obstacle(&self, e: &capp_core::ObstacleError) -> Option<usize> {
        use capp_core::ObstacleError as E;
        let names = |o: &Solid| match o.shape {
            capp_core::Shape::Convex { hull } => Some(hull as usize),
            _ => None,
        };
        match *e {
            E::BadHull { hull, .. } => self
                .obstacles
                .iter()
                .position(|o| names(o) == Some(hull as usize)),
            E::TooManyHulls { capacity } => self
                .obstacles
                .iter()
                .position(|o| names(o).is_some_and(|h| h >= capacity)),
            _ => None,
        }
    }

    /// `joint 3 ("name")` for messages.
    pub fn joint_label(&self, j: usize) -> String {
        match self.joint_names.get(j).filter(|n| !n.is_empty()) {
            Some(name) => format!("joint {} (\"{name}\")", j + 1),
            None => format!("joint {}", j + 1),
        }
    }

    /// ` "name"` for messages, or nothing.
    pub fn obstacle_label(&self, i: usize) -> String {
        match self.obstacle_names.get(i).filter(|n| !n.is_empty()) {
            Some(name) => format!(" \"{name}\""),
            None => String::new(),
        }
    }

    fn point_is_joint(&self, id: u16) -> bool {
        let per = self.settings.avoidance.points_per_link as usize + 1;
        id as usize % per == per - 1
    }

    /// Where avoidance point `id` is on the arm, in words.
    pub fn describe_point(&self, id: u16) -> String {
        let per = self.settings.avoidance.points_per_link as usize + 1;
        let link = id as usize / per;
        let i = id as usize % per;
        if i == per - 1 {
            format!("point {id}, the far end of link {}", link + 1)
        } else {
            format!(
                "point {id}, {}/{} of the way along link {}",
                i + 1,
                per,
                link + 1
            )
        }
    }
}

fn last_index(e: &ScenarioError) -> Option<usize> {
    match e {
        ScenarioError::Mission(MissionError::BadPosition { waypoint }) => Some(*waypoint as usize),
        _ => None,
    }
}

fn robot_error_joint(e: &capp_core::RobotError) -> Option<usize> {
    use capp_core::RobotError as E;
    match *e {
        E::NotFinite { joint, .. }
        | E::InvertedLimits { joint }
        | E::NonPositiveRate { joint }
        | E::WeightOutOfRange { joint }
        | E::NotRotation { joint }
        | E::ZeroAxis { joint }
        | E::MixedJoints { joint }
        | E::OutOfRange { joint, .. } => Some(joint as usize),
        _ => None,
    }
}

fn obstacle_error_index(e: &capp_core::ObstacleError) -> Option<usize> {
    use capp_core::ObstacleError as E;
    match *e {
        E::NotFinite { obstacle, .. }
        | E::SemiAxisOutOfRange { obstacle }
        | E::CentreOutOfRange { obstacle }
        | E::ExponentOutOfRange { obstacle }
        | E::SizeOutOfRange { obstacle } => Some(obstacle as usize),
        E::NoSuchHull { obstacle } => Some(obstacle as usize),
        E::TooMany { .. } | E::TooManyHulls { .. } | E::BadHull { .. } => None,
    }
}
