//! # capp-proto: the CAPP serial protocol
//!
//! The messages a host (or a joint controller) and a CAPP board exchange over
//! a UART, and their framing. Both ends use this crate; `PROTOCOL.md` in the
//! crate directory specifies the same bytes for implementers in other languages.
//!
//! | module | owns |
//! |---|---|
//! | [`crc`] | CRC-32/ISO-HDLC |
//! | [`cobs`] | COBS encoding and in-place decoding |
//! | [`frame`] | frame layout, [`frame::encode`], [`frame::decode`], the receive [`frame::Accumulator`] |
//! | this module | the messages: [`Command`] (host to board) and [`Reply`] (board to host) |
//!
//! The payload is postcard's wire format (varint integers, little-endian
//! `f32`, enum variants as varint indices, structs as their fields in order).
//! **Stability rule:** a change to any type below that changes its bytes
//! changes [`VERSION`]; variants and fields are only ever appended.
//!
//! Nothing here allocates or panics on received bytes.
#![no_std]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

#[cfg(test)]
extern crate std;

pub mod cobs;
#[cfg(feature = "core")]
mod convert;
#[cfg(feature = "core")]
pub use convert::{escape_status, run_command, setpoint_filter};
pub mod crc;
pub mod frame;

pub use frame::{decode, decode_command, encode, Accumulator, Feed, FrameError, MAX_FRAME};

use serde::{Deserialize, Serialize};

/// Protocol version: the first byte of every frame body.
pub const VERSION: u8 = 12;
/// Most joints a load may hold.
pub const MAX_JOINTS: usize = 32;
/// Most obstacles a load may hold.
pub const MAX_OBSTACLES: usize = 64;
/// Most hulls in a load (since version 11; capp-core's `MAX_HULLS`).
pub const MAX_HULLS: usize = 8;
/// Most vertices a hull has (since version 11; capp-core's
/// `MAX_HULL_VERTICES`).
pub const MAX_HULL_VERTICES: usize = 32;
/// A hull's vertices, `[x, y, z]` each in its obstacle's frame.
pub type HullVertices = heapless::Vec<[f32; 3], MAX_HULL_VERTICES>;
/// Most waypoints a load may hold.
pub const MAX_WAYPOINTS: usize = 16;
/// The `command` field of an [`Reply::Error`] when the command could not be
/// decoded (framing, CRC, version, unknown message).
pub const NO_COMMAND: u8 = 0xFF;
/// The `index` field of an [`Reply::Error`] when no item is concerned.
pub const NO_INDEX: u8 = 0xFF;

/// A joint vector on the wire.
pub type Joints = heapless::Vec<f32, MAX_JOINTS>;

/// Revolute or prismatic.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum JointKind {
    /// Variable `theta`, radians.
    Revolute,
    /// Variable `d`, length units.
    Prismatic,
}

/// A rigid transform (capp-core's `robot::Placement`): `p -> rotation p +
/// translation` (since version 9).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Placement {
    /// Rotation, row by row (a proper rotation).
    pub rotation: [[f32; 3]; 3],
    /// Translation, length units.
    pub translation: [f32; 3],
}

/// Where a general (URDF) joint sits and what it moves about (capp-core's
/// `robot::JointOrigin`; since version 9).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Origin {
    /// The transform from the previous joint's (moved) frame, or the base,
    /// to this joint's frame at `q = 0` (a URDF joint's `<origin>`).
    pub placement: Placement,
    /// The axis the joint turns about or slides along, in its own frame (a
    /// URDF joint's `<axis>`; any length above 1e-3, it is normalised).
    pub axis: [f32; 3],
}

/// One joint and its link (capp-core's `Joint`, field for field).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Joint {
    /// Revolute or prismatic.
    pub kind: JointKind,
    /// Link twist, radians.
    pub alpha: f32,
    /// Link length.
    pub a: f32,
    /// Fixed angle of a prismatic joint, radians.
    pub theta: f32,
    /// Fixed offset of a revolute joint.
    pub d: f32,
    /// Lower limit.
    pub min: f32,
    /// Upper limit.
    pub max: f32,
    /// Rate limit, per second.
    pub max_rate: f32,
    /// Weight in `(0, 1]`.
    pub weight: f32,
    /// A general joint's origin and axis (then `alpha`, `a`, `theta` and `d`
    /// are not used), or none: a DH row. A robot's joints are all one or all
    /// the other (since version 9).
    pub origin: Option<Origin>,
}

/// An obstacle (capp-core's `Solid`): a super-ellipsoid, or since version
/// 10 a primitive measured on true distance.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Obstacle {
    /// Centre.
    pub centre: [f32; 3],
    /// Semi-axes (a super-ellipsoid's; zeros for a primitive).
    pub semi_axes: [f32; 3],
    /// Exponents (a super-ellipsoid's; zeros for a primitive).
    pub exponents: [f32; 3],
    /// Euler angles (1-2-3), radians.
    pub euler_123: [f32; 3],
    /// The primitive, or none: the super-ellipsoid of `semi_axes` and
    /// `exponents` (since version 10).
    pub primitive: Option<Primitive>,
}

/// A CAD primitive in its own frame (capp-core's `Shape`, but the
/// super-ellipsoid), sizes in length units; since version 10.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Primitive {
    /// 0: a ball.
    Sphere {
        /// Radius.
        radius: f32,
    },
    /// 1: a box.
    Cuboid {
        /// Half-extents along the obstacle's x, y, z.
        half_extents: [f32; 3],
    },
    /// 2: a capsule along z.
    Capsule {
        /// Radius.
        radius: f32,
        /// The segment's full length.
        length: f32,
    },
    /// 3: a cylinder along z, flat ends.
    Cylinder {
        /// Radius.
        radius: f32,
        /// Full length.
        length: f32,
    },
    /// 4: the convex hull of the load's hull number `hull` (0-based, sent
    /// by [`Command::Hull`]; since version 11).
    Convex {
        /// The hull.
        hull: u8,
    },
}

/// A waypoint: a position and optionally a rotation matrix, row by row.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Waypoint {
    /// Position.
    pub position: [f32; 3],
    /// Orientation rows, or none.
    pub orientation: Option<[[f32; 3]; 3]>,
}

/// Which form of the control law.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LawKind {
    /// Normalised total gradient (the default).
    Gradient,
    /// Eq. 15 as printed.
    Paper,
    /// Damped least squares on `V` (capp-core's `control::damped`).
    DampedLeastSquares,
}

/// Every planner setting (capp-core's `Settings`, flattened).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Settings {
    /// Largest integration step, seconds.
    pub time_step_s: f32,
    /// Radius of the fine-step zone.
    pub fine_radius: f32,
    /// Fraction of the step inside it.
    pub fine_step_fraction: f32,
    /// Position tolerance.
    pub position_tolerance: f32,
    /// Orientation tolerance.
    pub orientation_tolerance: f32,
    /// Law form.
    pub law: LawKind,
    /// Orientation length scale.
    pub orientation_scale: f32,
    /// Approach radius.
    pub approach_radius: f32,
    /// Margin of joint points.
    pub joint_margin: f32,
    /// Margin of link points.
    pub link_margin: f32,
    /// Interior avoidance points per link.
    pub points_per_link: u8,
    /// Influence distance.
    pub influence_distance: f32,
    /// Clearance `C - 1` below which approaching motion is removed in full.
    pub engage_clearance: f32,
    /// Conservative advancement fraction (protocol 3).
    pub advance_fraction: f32,
    /// Damping floor of the damped least-squares law (protocol 3).
    pub damping: f32,
    /// Iteration cap.
    pub max_steps: u32,
    /// Stall window, steps.
    pub stall_window: u32,
    /// Relative progress that counts.
    pub stall_progress: f32,
    /// Most step halvings.
    pub max_halvings: u8,
    /// Dead-end escape attempts per waypoint (0: none).
    pub escape_attempts: u8,
    /// Steps without progress that make a dead end.
    pub escape_window: u32,
    /// Most steps of one escape walk.
    pub escape_walk_steps: u32,
    /// A first walk's reach, fraction of each joint's range.
    pub escape_reach: f32,
    /// Seed of the walks' generator.
    pub escape_seed: u32,
    /// Searches for a path per waypoint, before walking (0: none; since version 4).
    pub escape_searches: u8,
    /// Whether the damped law spends every usable joint's rate limit when a
    /// step is rate-limited (saturation in the null space; since version 5).
    pub saturation: bool,
    /// Tracked motion: a fixed control period (`time_step_s`), each joint
    /// within its rate, acceleration and jerk limits, every tick's stop
    /// cleared (capp-core's `Motion::Tracked`; `false`: `Motion::Stepped`;
    /// since version 7). Each joint's acceleration and jerk limits are the
    /// load's [`Command::Drive`]s, or without them the defaults from the
    /// rates (capp-core's `DriveLimits::from_rate`).
    pub tracked: bool,
}

/// The listing's setpoint rule (`joints.dat`): a setpoint whenever the
/// position or orientation error changed by more than these amounts since the
/// last one (capp-core's `SetpointFilter::ErrorChange`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ErrorChange {
    /// Position error change, length units (listing: 1.0).
    pub position: f32,
    /// Orientation error change (listing: 0.1).
    pub orientation: f32,
}

/// A built-in robot.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Preset {
    /// The 18-joint PIPS of the paper's Table 1; start = its home.
    Pips,
}

/// The capsule round one link and the pairs it is checked against
/// (capp-core's `self_collision::LinkCapsules`, one link of it; since version 6).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Capsule {
    /// Radius of the capsule round the link's chord, length units (positive
    /// and finite).
    pub radius: f32,
    /// The links this one is checked against: bit `b` set when the pair
    /// (this link, `b`) is checked; only links after this one (`b > index`).
    pub checked: u64,
    /// The segment the capsule is round, when not the link's chord: its two
    /// ends in the frame of the body the joint moves, after its motion,
    /// length units (capp-core's `Robot::set_link_segments`; general joints
    /// only, and then every capsule of a load has one; since version 12).
    pub segment: Option<[[f32; 3]; 2]>,
}

/// One joint's drive limits beyond its rate (capp-core's
/// `tracker::limits::DriveLimits` without `max_rate`, which is the joint's;
/// since version 8). Units are the joint's: radians (revolute) or length
/// units (prismatic), per second squared and per second cubed.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Drive {
    /// Largest `|acceleration|`, per second squared (positive and finite).
    pub max_accel: f32,
    /// Largest `|jerk|`, per second cubed (positive and finite).
    pub max_jerk: f32,
}

/// Which part of the load [`Command::Clear`] empties.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Part {
    /// Everything: joints, capsules, obstacles, waypoints, start; settings
    /// to defaults.
    All,
    /// The joints (and the start, the capsules, the drive limits and the
    /// tool).
    Robot,
    /// The obstacles.
    Obstacles,
    /// The waypoints.
    Waypoints,
    /// The link capsules: self-collision off until capsules are sent again
    /// (since version 6).
    Capsules,
    /// The joints' drive limits: the defaults from the rates until drive
    /// limits are sent again (since version 8).
    Drives,
}

/// Host to board. Each is answered by exactly one reply: [`Reply::Pong`] for
/// `Ping`, [`Reply::Status`] for `Status`, otherwise [`Reply::Ack`] or [`Reply::Error`].
// `Hull` (388 bytes of vertices) sizes the enum: without allocation there
// is no box to put it in, and a command is decoded into one value on the
// serving loop's stack, counted in the board's painted stack peak.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Command {
    /// 0: liveness and version check.
    Ping {
        /// Echoed in the pong.
        nonce: u32,
    },
    /// 1: empty part of the load being built.
    Clear(Part),
    /// 2: replace the load's joints and start by a preset's.
    Preset(Preset),
    /// 3: append a joint; `index` must equal the number of joints loaded.
    Joint {
        /// Position in the chain (0-based).
        index: u8,
        /// The joint.
        joint: Joint,
    },
    /// 4: append an obstacle; `index` must equal the number loaded.
    Obstacle {
        /// Index (0-based).
        index: u8,
        /// The obstacle.
        obstacle: Obstacle,
    },
    /// 5: append a waypoint; `index` must equal the number loaded.
    Waypoint {
        /// Index (0-based); the last waypoint is the target.
        index: u8,
        /// The waypoint.
        waypoint: Waypoint,
    },
    /// 6: replace the settings.
    Settings(Settings),
    /// 7: the start configuration (one value per joint).
    Start(Joints),
    /// 8: validate the load and start planning, streaming a setpoint every
    /// `every` steps (0 is read as 1) plus the first and the last, or, with
    /// `error_change`, whenever an error changed by more than its threshold.
    Run {
        /// Decimation.
        every: u32,
        /// The listing's rule instead of `every` (since version 2).
        error_change: Option<ErrorChange>,
    },
    /// 9: stop a running plan (a final status follows the ack).
    Stop,
    /// 10: ask for a status.
    Status,
    /// 11: append a waypoint that is a joint configuration (one value per
    /// joint); `index` must equal the number of waypoints loaded (since
    /// version 3). At most 4 per load.
    JointWaypoint {
        /// Index (0-based) among the waypoints; the last is the target.
        index: u8,
        /// The configuration, radians or length units.
        joints: Joints,
    },
    /// 12: append the capsule of link `index` (the link after joint `index`);
    /// `index` must equal the number of capsules loaded (since version 6).
    /// A load with capsules has one per joint and checks self-collision; a
    /// load without any does not.
    Capsule {
        /// The link (0-based): the link after joint `index`.
        index: u8,
        /// Its radius and checked pairs.
        capsule: Capsule,
    },
    /// 13: append joint `index`'s acceleration and jerk limits; `index`
    /// must equal the number of drive limits loaded (since version 8). A
    /// load with drive limits has one per joint and a tracked plan keeps
    /// every joint within them; a load without any takes the defaults from
    /// the rates (full rate from rest in 0.5 s, full acceleration in 0.1 s).
    Drive {
        /// The joint (0-based).
        index: u8,
        /// Its limits.
        drive: Drive,
    },
    /// 14: the tool: the end effector's frame in the last joint's frame (for
    /// DH rows frame `n`, for general joints the last joint's moved frame;
    /// since version 9). Until one is sent (and after `Clear(All)`,
    /// `Clear(Robot)` or `Preset`) the identity.
    Tool(Placement),
    /// 15: append hull `index`'s vertices (4 to [`MAX_HULL_VERTICES`], its
    /// obstacles' frame, length units); `index` must equal the number of
    /// hulls loaded (since version 11). A [`Primitive::Convex`] obstacle
    /// names it; `Clear(Obstacles)` empties the hulls too.
    Hull {
        /// The hull (0-based).
        index: u8,
        /// Its vertices.
        vertices: HullVertices,
    },
}

impl Command {
    /// The variant index, as echoed in [`Reply::Ack`] and [`Reply::Error`].
    pub fn code(&self) -> u8 {
        match self {
            Command::Ping { .. } => 0,
            Command::Clear(_) => 1,
            Command::Preset(_) => 2,
            Command::Joint { .. } => 3,
            Command::Obstacle { .. } => 4,
            Command::Waypoint { .. } => 5,
            Command::Settings(_) => 6,
            Command::Start(_) => 7,
            Command::Run { .. } => 8,
            Command::Stop => 9,
            Command::Status => 10,
            Command::JointWaypoint { .. } => 11,
            Command::Capsule { .. } => 12,
            Command::Drive { .. } => 13,
            Command::Tool(_) => 14,
            Command::Hull { .. } => 15,
        }
    }
}

/// Why a command was refused. The board keeps its previous state.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ErrorCode {
    /// 0: the bytes between delimiters are not valid COBS or too short.
    Framing,
    /// 1: CRC mismatch.
    Crc,
    /// 2: the frame's version byte is not [`VERSION`].
    Version,
    /// 3: unknown message or malformed payload.
    UnknownMessage,
    /// 4: a frame longer than the receive buffer.
    Overfull,
    /// 5: a NaN or infinite value (`index` = the item).
    NotFinite,
    /// 6: `index` is not the next free index.
    OutOfOrder,
    /// 7: more items than the capacity.
    Capacity,
    /// 8: the robot failed validation (`index` = the joint, or `NO_INDEX`:
    /// the chain as a whole or, since version 9, the tool).
    InvalidRobot,
    /// 9: an obstacle failed validation (`index` = the obstacle).
    InvalidObstacle,
    /// 10: the waypoints or settings failed validation (`index` = the waypoint).
    InvalidMission,
    /// 11: the start configuration is invalid (`index` = the joint).
    InvalidStart,
    /// 12: not allowed while a plan runs (load or run); send `Stop` first.
    Busy,
    /// 13: `Stop` while no plan runs.
    NotRunning,
    /// 14: the link capsules failed validation (`index` = the link, or
    /// `NO_INDEX` when their number is not the number of joints; since
    /// version 6).
    InvalidCapsules,
    /// 15: the drive limits failed validation (`index` = the joint whose
    /// acceleration or jerk limit is not positive, or `NO_INDEX` when their
    /// number is not the number of joints; since version 8).
    InvalidDrive,
    /// 16: a hull failed validation (`index` = the hull, or `NO_INDEX`:
    /// too many; since version 11).
    InvalidHull,
}

/// Where the board is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum State {
    /// No plan has run since boot.
    Idle,
    /// Planning and streaming.
    Running,
    /// The last plan ended by itself (see `outcome`).
    Done,
    /// The last plan was stopped by the host.
    Stopped,
}

/// How a plan ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Outcome {
    /// Reached the target.
    Reached,
    /// Dead end.
    Stalled,
    /// Iteration cap.
    Capped,
}

/// The board's state and counters.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Status {
    /// State.
    pub state: State,
    /// Outcome when `Done`.
    pub outcome: Option<Outcome>,
    /// Planner steps taken in the current / last plan.
    pub step: u32,
    /// Lyapunov value `V` after the last step.
    pub v: f32,
    /// Position error after the last step.
    pub position_error: f32,
    /// Orientation error after the last step.
    pub orientation_error: f32,
    /// Smallest clearance `C - 1` within influence, if any.
    pub clearance: Option<f32>,
    /// Setpoints produced in this plan: sequence numbers `0..setpoints` were
    /// used, whether sent or dropped.
    pub setpoints: u32,
    /// Setpoints dropped because the transmit queue was full.
    pub dropped: u32,
    /// Bad frames received since boot.
    pub rx_errors: u32,
    /// Timer ticks that arrived while a step was still running, this plan.
    pub overruns: u32,
    /// Deepest stack use measured since boot, bytes (0 if not measured).
    pub stack_peak: u32,
    /// Received bytes lost since boot because the board's receive queue was
    /// full (the frame they belonged to fails its check and is answered with
    /// an error) (since version 3).
    pub rx_overflows: u32,
    /// Fewest core clock cycles one tick's work took in this plan (the
    /// planner step and its setpoint); 0 before the first step or without a
    /// cycle counter (since version 3).
    pub step_cycles_min: u32,
    /// Mean cycles per tick's work in this plan (since version 3).
    pub step_cycles_mean: u32,
    /// Most cycles one tick's work took in this plan (since version 3).
    pub step_cycles_max: u32,
    /// What the dead-end escape is doing (since version 3).
    pub escape: EscapeMode,
    /// Escape attempts made for the current waypoint (since version 3).
    pub escape_attempt: u8,
    /// Ticks of a tracked plan (`Settings::tracked`) whose work (the planner
    /// step and its setpoint) took longer than the control period
    /// (`time_step_s`) on the board's cycle counter, this plan: the board
    /// could not have kept the drive's period in real time. Always 0 for a
    /// stepped plan or without a cycle counter (since version 7).
    pub period_overruns: u32,
}

/// The planner's dead-end escape, as the board reports it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum EscapeMode {
    /// 0: not escaping: the law drives.
    Descending,
    /// 1: walking away from a dead end in joint space.
    Walking,
    /// 2: sending the end effector round the blocking obstacle.
    Detouring,
    /// 3: the attempts spent, back to the best configuration.
    Returning,
    /// 4: searching for a path, the arm holding still (since version 4).
    Searching,
    /// 5: walking the path a search found (since version 4).
    Following,
}

/// Board to host.
// A setpoint holds three joint vectors (about 400 bytes) and the other
// replies a few bytes; no_std has no `Box`, and a reply lives on the stack
// only while it is encoded or handled.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Reply {
    /// 0: answer to `Ping`.
    Pong {
        /// The ping's nonce.
        nonce: u32,
        /// [`VERSION`].
        version: u8,
        /// Joint capacity.
        max_joints: u8,
        /// Obstacle capacity.
        max_obstacles: u8,
        /// Waypoint capacity.
        max_waypoints: u8,
    },
    /// 1: the command with this code was accepted.
    Ack {
        /// [`Command::code`] of the command.
        command: u8,
    },
    /// 2: a command was refused, or a frame was bad.
    Error {
        /// [`Command::code`], or [`NO_COMMAND`].
        command: u8,
        /// Why.
        code: ErrorCode,
        /// The item concerned, or [`NO_INDEX`].
        index: u8,
    },
    /// 3: one joint vector of the plan.
    Setpoint {
        /// Sequence number: 0 for the first setpoint of a plan, +1 for every
        /// setpoint produced (a gap = setpoints dropped or lost).
        seq: u32,
        /// Planner step this vector follows.
        step: u32,
        /// The joint vector.
        joints: Joints,
        /// Plan time at this setpoint, seconds: the sum of the step sizes
        /// taken (varies: fine zone, halvings), so a joint driver knows when
        /// to be there (since version 2).
        time_s: f32,
        /// The waypoint being approached, 0-based (the last one once the plan
        /// is over) (since version 2).
        waypoint: u8,
        /// Each joint's velocity, per second (radians or length units): with
        /// tracked motion the drive state after this tick (capp-core's
        /// `Planner::drive`); stepped, the rate of the last step
        /// (`Planner::rates`). One value per joint (since version 7).
        velocity: Joints,
        /// Each joint's acceleration, per second squared: tracked, the drive
        /// state after this tick; stepped, zeros (a stepped plan has no
        /// acceleration of its own). One value per joint (since version 7).
        acceleration: Joints,
    },
    /// 4: status, on request and at the end of every plan.
    Status(Status),
}
