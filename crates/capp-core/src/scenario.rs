//! Robot, obstacles and mission, validated together into the immutable model
//! every step reads. Capacities: `N` joints, `M` obstacles, `W` waypoints.

use crate::kinematics::{forward_kinematics, Frames};
use crate::math::{is_rotation, vec3, Mat3};
use crate::mission::{JointGoalProblem, Mission, MissionError, Settings, Waypoint};
use crate::obstacle::{Hull, Obstacle, ObstacleError, Solid, World, MAX_EXTENT, MAX_HULLS};
use crate::robot::{Joint, Placement, Robot, RobotError};
use crate::self_collision::{CapsuleError, LinkCapsules};
use crate::target::Target;
use crate::tracker::limits::{DriveLimitError, DriveLimits};

/// Most waypoints of a scenario that are joint configurations.
pub const MAX_JOINT_GOALS: usize = 4;

/// Tolerance on `R^T R - I` and `det R - 1` for a target orientation.
pub const ROTATION_TOLERANCE: f32 = 1.0e-3;

/// Why a scenario was rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ScenarioError {
    /// The robot (checked by [`Robot::new`]).
    Robot(RobotError),
    /// An obstacle.
    Obstacle(ObstacleError),
    /// The waypoints or settings.
    Mission(MissionError),
    /// The link capsules or the checked pairs.
    Capsules(CapsuleError),
    /// A joint's drive limits ([`Scenario::set_drive_limits`]; `joint` is
    /// 0-based, [`DriveLimitError`] says which limit).
    Drive {
        /// The joint, 0-based.
        joint: u8,
        /// Which limit.
        limit: DriveLimitError,
    },
    /// [`Scenario::set_drive_limits`] with a slice of the wrong length.
    DriveLength,
}

impl From<RobotError> for ScenarioError {
    fn from(e: RobotError) -> Self {
        ScenarioError::Robot(e)
    }
}
impl From<ObstacleError> for ScenarioError {
    fn from(e: ObstacleError) -> Self {
        ScenarioError::Obstacle(e)
    }
}
impl From<CapsuleError> for ScenarioError {
    fn from(e: CapsuleError) -> Self {
        ScenarioError::Capsules(e)
    }
}
impl From<MissionError> for ScenarioError {
    fn from(e: MissionError) -> Self {
        ScenarioError::Mission(e)
    }
}

impl core::fmt::Display for ScenarioError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ScenarioError::Robot(e) => write!(f, "robot: {e}"),
            ScenarioError::Obstacle(e) => write!(f, "{e}"),
            ScenarioError::Mission(e) => write!(f, "{e}"),
            ScenarioError::Capsules(e) => write!(f, "robot: {e}"),
            ScenarioError::Drive { joint, limit } => {
                let which = match limit {
                    DriveLimitError::Rate => "max_rate",
                    DriveLimitError::Accel => "max_accel",
                    DriveLimitError::Jerk => "max_jerk",
                    DriveLimitError::Period => "control period",
                };
                write!(
                    f,
                    "robot: joint {}: {which} must be finite and above 0",
                    joint + 1
                )
            }
            ScenarioError::DriveLength => write!(f, "robot: one drive limit per joint"),
        }
    }
}

/// Everything a plan depends on, checked once. Immutable.
#[derive(Clone, Debug)]
pub struct Scenario<const N: usize, const M: usize, const W: usize> {
    robot: Robot<N>,
    obstacles: heapless::Vec<Obstacle, M>,
    /// The hulls convex obstacles name ([`Scenario::init_with_hulls`]):
    /// the first `hull_count`, each built in place (a hull is over a
    /// kilobyte, never a temporary on a board's stack).
    hulls: [Hull; MAX_HULLS],
    /// How many of `hulls` are the scenario's.
    hull_count: u8,
    targets: heapless::Vec<Target, W>,
    /// Joint configurations some targets are ([`Scenario::set_joint_goal`]).
    joint_goals: heapless::Vec<[f32; N], MAX_JOINT_GOALS>,
    settings: Settings,
    /// The links' capsules and the pairs checked ([`Scenario::set_link_capsules`]).
    capsules: LinkCapsules<N>,
    /// Each joint's rate, acceleration and jerk limits
    /// ([`Scenario::set_drive_limits`]; by default from the rates).
    drive: [DriveLimits; N],
}

impl<const N: usize, const M: usize, const W: usize> Scenario<N, M, W> {
    /// Validates the obstacles and the mission against the robot.
    /// Obstacles are [`Solid`]s, or anything that becomes one (a
    /// [`crate::SuperEllipsoid`]).
    pub fn new<S: Into<Solid> + Copy>(
        robot: Robot<N>,
        obstacles: &[S],
        mission: &Mission<W>,
    ) -> Result<Self, ScenarioError> {
        let mut scenario = Self::empty();
        scenario.robot = robot;
        scenario.fill(obstacles, &[], &mission.waypoints, mission.settings)?;
        Ok(scenario)
    }

    /// A scenario with no robot, obstacles or waypoints: a placeholder for a
    /// scenario built in place by [`Scenario::init`] (a board keeps its model
    /// in a `static`). No planner starts on it.
    pub fn empty() -> Self {
        Scenario {
            robot: Robot::empty(),
            obstacles: heapless::Vec::new(),
            hulls: core::array::from_fn(|_| Hull::empty()),
            hull_count: 0,
            targets: heapless::Vec::new(),
            joint_goals: heapless::Vec::new(),
            settings: Settings::default(),
            capsules: LinkCapsules::none(),
            drive: [DriveLimits::from_rate(1.0); N],
        }
    }

    /// [`Robot::new`], [`Mission::new`] and [`Scenario::new`] in place: the
    /// same checks in the same order and the same scenario, without a
    /// scenario-sized value on the stack (17 KiB for PIPS with room for 64
    /// obstacles). On error `self` is left empty (as [`Scenario::empty`]).
    pub fn init<S: Into<Solid> + Copy>(
        &mut self,
        joints: &[Joint],
        obstacles: &[S],
        waypoints: &[Waypoint],
        settings: Settings,
    ) -> Result<(), ScenarioError> {
        self.init_with_tool(joints, &Placement::IDENTITY, obstacles, waypoints, settings)
    }

    /// [`Scenario::init`] with a tool: the robot is
    /// [`Robot::new_with_tool`]'s (`tool` the identity gives `init`'s).
    pub fn init_with_tool<S: Into<Solid> + Copy>(
        &mut self,
        joints: &[Joint],
        tool: &Placement,
        obstacles: &[S],
        waypoints: &[Waypoint],
        settings: Settings,
    ) -> Result<(), ScenarioError> {
        self.init_with_hulls(joints, tool, obstacles, &[], waypoints, settings)
    }

    /// [`Scenario::init_with_tool`] with convex hulls: `hulls[i]` is hull
    /// `i`'s vertices (its obstacle's frame, length units), which a
    /// [`crate::Shape::Convex`] obstacle names by `i`. At most
    /// [`MAX_HULLS`], each validated by [`Hull::new`].
    pub fn init_with_hulls<S: Into<Solid> + Copy>(
        &mut self,
        joints: &[Joint],
        tool: &Placement,
        obstacles: &[S],
        hulls: &[&[[f32; 3]]],
        waypoints: &[Waypoint],
        settings: Settings,
    ) -> Result<(), ScenarioError> {
        let result = self
            .robot
            .init_with_tool(joints, tool)
            .map_err(ScenarioError::from)
            .and_then(|()| {
                if waypoints.len() > W {
                    Err(MissionError::TooManyWaypoints { capacity: W }.into())
                } else {
                    Ok(())
                }
            })
            .and_then(|()| self.fill(obstacles, hulls, waypoints, settings));
        if result.is_err() {
            self.clear();
        }
        result
    }

    /// Makes this scenario [`Scenario::empty`], in place.
    pub fn clear(&mut self) {
        self.robot.clear();
        let _ = self.fill::<Solid>(&[], &[], &[], Settings::default());
    }

    /// Rebuilds every field but the robot (validated by `Robot::new` /
    /// `Robot::init`), in place; shared by `new` and `init`.
    fn fill<S: Into<Solid> + Copy>(
        &mut self,
        obstacles: &[S],
        hulls: &[&[[f32; 3]]],
        waypoints: &[Waypoint],
        settings: Settings,
    ) -> Result<(), ScenarioError> {
        // Every field is named: a field added to `Scenario` fails to compile here.
        let Scenario {
            robot,
            obstacles: validated,
            hulls: kept_hulls,
            hull_count,
            targets,
            joint_goals,
            settings: kept_settings,
            capsules,
            drive,
        } = self;
        *capsules = LinkCapsules::none();
        for (limits, joint) in drive.iter_mut().zip(robot.joints()) {
            *limits = DriveLimits::from_rate(joint.max_rate);
        }
        validated.clear();
        *hull_count = 0;
        targets.clear();
        joint_goals.clear();
        *kept_settings = settings;
        settings.validate()?;
        if obstacles.len() > M || obstacles.len() > u8::MAX as usize + 1 {
            return Err(ObstacleError::TooMany {
                capacity: M.min(256),
            }
            .into());
        }
        if hulls.len() > MAX_HULLS {
            return Err(ObstacleError::TooManyHulls {
                capacity: MAX_HULLS,
            }
            .into());
        }
        for (i, (vertices, hull)) in hulls.iter().zip(kept_hulls.iter_mut()).enumerate() {
            hull.set(vertices)
                .map_err(|why| ObstacleError::BadHull { hull: i as u8, why })?;
            *hull_count = i as u8 + 1;
        }
        let kept_hulls = kept_hulls.get(..*hull_count as usize).unwrap_or(&[]);
        for (i, s) in obstacles.iter().enumerate() {
            let o = Obstacle::new_in(
                i as u8,
                s,
                kept_hulls,
                settings.avoidance.margins(),
                settings.avoidance.influence_distance,
            )?;
            let _ = validated.push(o);
        }
        if waypoints.is_empty() {
            return Err(MissionError::NoWaypoints.into());
        }
        for (i, w) in waypoints.iter().enumerate() {
            let waypoint = i as u8;
            if !w
                .position
                .iter()
                .all(|x| x.is_finite() && x.abs() <= MAX_EXTENT)
            {
                return Err(MissionError::BadPosition { waypoint }.into());
            }
            let orientation = match &w.orientation {
                None => None,
                Some(rows) => {
                    let r = Mat3::from_row_slice(&[
                        rows[0][0], rows[0][1], rows[0][2], rows[1][0], rows[1][1], rows[1][2],
                        rows[2][0], rows[2][1], rows[2][2],
                    ]);
                    if !is_rotation(&r, ROTATION_TOLERANCE) {
                        return Err(MissionError::NotARotation { waypoint }.into());
                    }
                    Some(r)
                }
            };
            targets
                .push(Target::pose(vec3(w.position), orientation))
                .map_err(|_| MissionError::TooManyWaypoints { capacity: W })?;
        }
        Ok(())
    }

    /// The robot.
    pub fn robot(&self) -> &Robot<N> {
        &self.robot
    }

    /// The validated obstacles.
    pub fn obstacles(&self) -> &[Obstacle] {
        &self.obstacles
    }

    /// The validated hulls convex obstacles name.
    pub fn hulls(&self) -> &[Hull] {
        self.hulls.get(..self.hull_count as usize).unwrap_or(&[])
    }

    /// The obstacles with the hulls they name: what the pair code reads.
    pub fn world(&self) -> World<'_> {
        World {
            obstacles: &self.obstacles,
            hulls: self.hulls(),
        }
    }

    /// The waypoints, pose by pose (a joint goal's is its configuration's).
    pub fn waypoints(&self) -> impl Iterator<Item = Waypoint> + '_ {
        self.targets.iter().map(|t| Waypoint {
            position: [t.position.x, t.position.y, t.position.z],
            orientation: t
                .orientation
                .map(|r| [0, 1, 2].map(|i| [r[(i, 0)], r[(i, 1)], r[(i, 2)]])),
        })
    }

    /// Joint goal `k` (radians or length units), when there is one.
    pub fn joint_goal(&self, k: u8) -> Option<&[f32]> {
        let n = self.robot.len();
        self.joint_goals.get(k as usize).map(|q| &q[..n])
    }

    /// Makes waypoint `waypoint` (0-based) the joint configuration `joints`
    /// (one value per joint, finite, within the limits): the planner drives
    /// the joints there straight, in joint space
    /// ([`crate::control::joint_space`]), and passes it when the joints are
    /// within a twentieth of a time step of it at their rate limits. At most
    /// [`MAX_JOINT_GOALS`] per scenario; the waypoint's pose becomes the
    /// configuration's (for the reports). Never inlined: its `Frames` (2 KiB
    /// for 32 joints) must not sit in a caller's stack frame while the
    /// caller goes on to plan (the board's load).
    #[inline(never)]
    pub fn set_joint_goal(&mut self, waypoint: usize, joints: &[f32]) -> Result<(), ScenarioError> {
        let index = waypoint.min(u8::MAX as usize) as u8;
        let bad = |problem| MissionError::BadJointGoal {
            waypoint: index,
            problem,
        };
        let n = self.robot.len();
        if waypoint >= self.targets.len() {
            return Err(bad(JointGoalProblem::NoSuchWaypoint).into());
        }
        if joints.len() != n {
            return Err(bad(JointGoalProblem::WrongLength).into());
        }
        if self.robot.first_outside_limits(joints).is_some() {
            return Err(bad(JointGoalProblem::OutsideLimits).into());
        }
        let k = self.joint_goals.len();
        let mut goal = [0.0f32; N];
        goal[..n].copy_from_slice(joints);
        self.joint_goals
            .push(goal)
            .map_err(|_| bad(JointGoalProblem::TooMany))?;
        let mut frames = Frames::<N>::default();
        forward_kinematics(&self.robot, joints, &mut frames);
        if let Some(t) = self.targets.get_mut(waypoint) {
            *t = Target {
                position: frames.end_position(),
                orientation: Some(*frames.end_rotation()),
                joints: Some(k as u8),
            };
        }
        Ok(())
    }

    /// Gives the links capsules of `radius` (one per link, length units)
    /// and checks the pairs of `checked` (row `a`: bit `b > a` per checked
    /// pair; [`crate::self_collision::pairs::PairTable::checked_rows`]):
    /// from then on no step brings two checked capsules into contact
    /// ([`crate::self_collision`]). Without it a scenario has no
    /// self-collision checks. On error the scenario keeps none.
    pub fn set_link_capsules(
        &mut self,
        radius: &[f32],
        checked: &[u64],
    ) -> Result<(), ScenarioError> {
        self.capsules = LinkCapsules::none();
        self.capsules = LinkCapsules::new(&self.robot, radius, checked)?;
        Ok(())
    }

    /// Makes each link's capsule the segment `segments[k]` fixed in its
    /// body (its two ends in joint `k`'s frame after its motion, length
    /// units), not its chord ([`Robot::set_link_segments`]); an empty slice
    /// goes back to the chords. The capsules' radii and checked pairs stay
    /// (given before or after). On error the links keep their chords.
    pub fn set_link_segments(&mut self, segments: &[[[f32; 3]; 2]]) -> Result<(), ScenarioError> {
        let result = self.robot.set_link_segments(segments);
        self.capsules.fit(&self.robot);
        result.map_err(|e| ScenarioError::Capsules(e.into()))
    }

    /// The links' capsules and checked pairs (none unless
    /// [`Scenario::set_link_capsules`] gave them).
    pub fn capsules(&self) -> &LinkCapsules<N> {
        &self.capsules
    }

    /// Gives the joints' drives these acceleration (per second squared) and
    /// jerk (per second cubed) limits, one per joint, in the joints' units;
    /// the rate limit stays the joint's `max_rate`. Without it each joint
    /// has [`DriveLimits::from_rate`]'s. On error the scenario keeps those.
    pub fn set_drive_limits(
        &mut self,
        max_accel: &[f32],
        max_jerk: &[f32],
    ) -> Result<(), ScenarioError> {
        let n = self.robot.len().min(N);
        if max_accel.len() != n || max_jerk.len() != n {
            return Err(ScenarioError::DriveLength);
        }
        let mut limits = [DriveLimits::from_rate(1.0); N];
        for (j, ((out, joint), (&max_accel, &max_jerk))) in limits
            .iter_mut()
            .zip(self.robot.joints())
            .zip(max_accel.iter().zip(max_jerk))
            .enumerate()
        {
            *out = DriveLimits {
                max_rate: joint.max_rate,
                max_accel,
                max_jerk,
            };
            out.validate().map_err(|limit| ScenarioError::Drive {
                joint: j.min(u8::MAX as usize) as u8,
                limit,
            })?;
        }
        self.drive = limits;
        Ok(())
    }

    /// Each joint's drive limits (`robot().len()` of them).
    pub fn drive_limits(&self) -> &[DriveLimits] {
        &self.drive[..self.robot.len().min(N)]
    }

    /// The targets the planner drives to, one per waypoint.
    pub fn targets(&self) -> &[Target] {
        &self.targets
    }

    /// The settings.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }
}
