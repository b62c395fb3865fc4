//! The manipulator model: a serial chain in standard (distal) Denavit-Hartenberg
//! form (paper eq. 5), with per-joint limits, rate limits and weights.
//!
//! Link `i` (1-based in the paper, `i - 1` here) transforms frame `i-1` to
//! frame `i`:
//!
//! ```text
//! A_i = Rot_z(theta_i) Trans_z(d_i) Trans_x(a_i) Rot_x(alpha_i)       (eq. 5)
//! ```
//!
//! A revolute joint varies `theta` (radians), a prismatic joint varies `d`
//! (length units). The joint value `q_i` *is* that variable: the fixed DH
//! column of a revolute joint is its `d`, of a prismatic one its `theta`.
//!
//! A joint can also be given as a fixed transform from the previous joint's
//! frame followed by a motion about its own axis (a URDF joint: [`origin`]);
//! a robot's joints are all one kind or all the other.
//!
//! Joint rates: `max_rate` bounds `|q_i'|` (radians or length per second).
//! `weight` in `(0, 1]` scales the joint's share of the motion:
//! `k_i = weight_i * max_rate_i / 2`, which keeps eq. 18's `k_i <= qdot_max / 2`.

pub mod origin;

use crate::math::{all_finite, Mat3, Vec3};
pub use origin::{JointOrigin, Placement};
use origin::{PlacementFault, Transform};

/// What a joint's variable is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum JointKind {
    /// Rotation about `z_{i-1}`: the variable is `theta`, in radians.
    Revolute,
    /// Translation along `z_{i-1}`: the variable is `d`, in length units.
    Prismatic,
}

/// One joint and the link after it, as given by a user (not yet validated).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Joint {
    /// Revolute or prismatic.
    pub kind: JointKind,
    /// Link twist `alpha`, radians.
    pub alpha: f32,
    /// Link length `a`, length units.
    pub a: f32,
    /// Fixed joint angle `theta` of a prismatic joint, radians (ignored for revolute joints).
    pub theta: f32,
    /// Fixed offset `d` of a revolute joint, length units (ignored for prismatic joints).
    pub d: f32,
    /// Lower limit of the joint variable (radians or length units).
    pub min: f32,
    /// Upper limit of the joint variable.
    pub max: f32,
    /// Largest joint rate magnitude, per second. Must be > 0.
    pub max_rate: f32,
    /// Relative weight in `(0, 1]` of this joint in the motion (the listing's `metric`).
    pub weight: f32,
    /// A general joint's transform and axis ([`origin`]); `None` for a DH
    /// row. When given, `alpha`, `a`, `theta` and `d` are not used (keep
    /// them 0).
    pub origin: Option<JointOrigin>,
}

impl Joint {
    /// A revolute joint with the given DH constants and limits, weight 1.
    pub fn revolute(alpha: f32, a: f32, d: f32, min: f32, max: f32, max_rate: f32) -> Self {
        Joint {
            kind: JointKind::Revolute,
            alpha,
            a,
            theta: 0.0,
            d,
            min,
            max,
            max_rate,
            weight: 1.0,
            origin: None,
        }
    }

    /// A prismatic joint with the given DH constants and limits, weight 1.
    pub fn prismatic(alpha: f32, a: f32, theta: f32, min: f32, max: f32, max_rate: f32) -> Self {
        Joint {
            kind: JointKind::Prismatic,
            alpha,
            a,
            theta,
            d: 0.0,
            min,
            max,
            max_rate,
            weight: 1.0,
            origin: None,
        }
    }

    /// A general joint ([`origin`]): `origin`'s transform from the previous
    /// joint's frame, then a motion of kind `kind` about or along its axis;
    /// weight 1.
    pub fn general(
        kind: JointKind,
        origin: JointOrigin,
        min: f32,
        max: f32,
        max_rate: f32,
    ) -> Self {
        Joint {
            kind,
            alpha: 0.0,
            a: 0.0,
            theta: 0.0,
            d: 0.0,
            min,
            max,
            max_rate,
            weight: 1.0,
            origin: Some(origin),
        }
    }

    /// A DH row's fixed part, the transform after its motion: DH joint `k`
    /// is `Rot_z(q) [Trans_z(d) Trans_x(a) Rot_x(alpha)]` (revolute) or
    /// `Trans_z(q) [Rot_z(theta) Trans_x(a) Rot_x(alpha)]` (prismatic), so
    /// written as general joints, this bracket is the next joint's origin
    /// (or the tool after the last): see [`general_from_dh`].
    pub fn dh_fixed_part(&self) -> Placement {
        let (theta, d) = match self.kind {
            JointKind::Revolute => (0.0, self.d),
            JointKind::Prismatic => (self.theta, 0.0),
        };
        let (sa, ca) = crate::math::sin_cos(self.alpha);
        let (st, ct) = crate::math::sin_cos(theta);
        Placement {
            rotation: [
                [ct, -st * ca, st * sa],
                [st, ct * ca, -ct * sa],
                [0.0, sa, ca],
            ],
            translation: [self.a * ct, self.a * st, d],
        }
    }

    /// Builder: the same joint with another weight.
    pub fn with_weight(mut self, weight: f32) -> Self {
        self.weight = weight;
        self
    }

    /// Where `q` stands in the joint's range: -1 at `min`, +1 at `max` (eq. 18's `f_i`).
    #[inline]
    pub fn range_fraction(&self, q: f32) -> f32 {
        (2.0 * q - (self.max + self.min)) / (self.max - self.min)
    }

    /// `q` clamped into `[min, max]`.
    #[inline]
    pub fn clamp(&self, q: f32) -> f32 {
        crate::math::min(crate::math::max(q, self.min), self.max)
    }
}

/// Which field of a joint an error is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum JointField {
    /// `alpha`
    Alpha,
    /// `a`
    A,
    /// `theta`
    Theta,
    /// `d`
    D,
    /// `min` or `max`
    Limits,
    /// `max_rate`
    MaxRate,
    /// `weight`
    Weight,
    /// A general joint's (or the tool's) transform ([`Placement`]).
    Origin,
    /// A general joint's axis.
    Axis,
}

/// The same arm as the DH rows `dh`, as general joints into `out` (as many
/// as both hold; every axis `z`, the first origin the identity, each next
/// origin the previous row's [`Joint::dh_fixed_part`]); returns the tool,
/// the last row's fixed part. Equal to the DH chain to `f32` rounding.
pub fn general_from_dh(dh: &[Joint], out: &mut [Joint]) -> Placement {
    let mut previous = Placement::IDENTITY;
    for (j, o) in dh.iter().zip(out.iter_mut()) {
        let origin = JointOrigin {
            placement: previous,
            axis: [0.0, 0.0, 1.0],
        };
        *o = Joint::general(j.kind, origin, j.min, j.max, j.max_rate).with_weight(j.weight);
        previous = j.dh_fixed_part();
    }
    previous
}

/// The `joint` of a [`RobotError`] about the tool ([`Robot::new_with_tool`]).
pub const TOOL: u8 = u8::MAX;

/// Why a robot description was rejected. `joint` is 0-based.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RobotError {
    /// The chain has no joints.
    Empty,
    /// More joints than the capacity `N`.
    TooManyJoints {
        /// Joints offered.
        count: usize,
        /// Capacity.
        capacity: usize,
    },
    /// A field is NaN or infinite.
    NotFinite {
        /// The joint.
        joint: u8,
        /// The field.
        field: JointField,
    },
    /// `min >= max`.
    InvertedLimits {
        /// The joint.
        joint: u8,
    },
    /// `max_rate <= 0`.
    NonPositiveRate {
        /// The joint.
        joint: u8,
    },
    /// `weight` outside `(0, 1]`.
    WeightOutOfRange {
        /// The joint.
        joint: u8,
    },
    /// A general joint's (or the tool's) rotation is not a proper rotation
    /// (orthonormal, determinant +1, to [`origin::ROTATION_TOLERANCE`]).
    NotRotation {
        /// The joint, or [`TOOL`].
        joint: u8,
    },
    /// A general joint's axis is (nearly) zero.
    ZeroAxis {
        /// The joint.
        joint: u8,
    },
    /// A DH row and a general joint in one robot.
    MixedJoints {
        /// The first joint of the other kind.
        joint: u8,
    },
    /// `|a|`, `|d|` or a prismatic limit beyond [`MAX_LENGTH`], or a revolute
    /// limit beyond [`MAX_ANGLE`]: sizes that would overflow `f32` products.
    OutOfRange {
        /// The joint.
        joint: u8,
        /// The field.
        field: JointField,
    },
}

/// Largest accepted link length, offset or prismatic travel, length units.
pub const MAX_LENGTH: f32 = 1.0e4;
/// Largest accepted revolute limit magnitude, radians (a few hundred turns).
pub const MAX_ANGLE: f32 = 1.0e3;

impl core::fmt::Display for JointField {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            JointField::Alpha => "alpha",
            JointField::A => "a",
            JointField::Theta => "theta",
            JointField::D => "d",
            JointField::Limits => "limits",
            JointField::MaxRate => "max_rate",
            JointField::Weight => "weight",
            JointField::Origin => "origin",
            JointField::Axis => "axis",
        })
    }
}

/// "joint 3" (1-based) or "the tool".
struct Which(u8);

impl core::fmt::Display for Which {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        if self.0 == TOOL {
            f.write_str("the tool")
        } else {
            write!(f, "joint {}", self.0 as u32 + 1)
        }
    }
}

impl core::fmt::Display for RobotError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            RobotError::NotRotation { joint } => {
                write!(
                    f,
                    "{}: origin rotation is not a proper rotation",
                    Which(joint)
                )
            }
            RobotError::ZeroAxis { joint } => {
                write!(f, "{}: the axis has no length", Which(joint))
            }
            RobotError::MixedJoints { joint } => write!(
                f,
                "{}: DH rows and general joints cannot be mixed in one robot",
                Which(joint)
            ),
            RobotError::Empty => write!(f, "the robot has no joints"),
            RobotError::TooManyJoints { count, capacity } => {
                write!(f, "{count} joints, more than the capacity of {capacity}")
            }
            RobotError::NotFinite { joint, field } => {
                write!(f, "{}: {field} is not a finite number", Which(joint))
            }
            RobotError::InvertedLimits { joint } => {
                write!(
                    f,
                    "joint {}: lower limit is not below the upper limit",
                    joint as u32 + 1
                )
            }
            RobotError::NonPositiveRate { joint } => {
                write!(f, "joint {}: rate limit must be positive", joint as u32 + 1)
            }
            RobotError::WeightOutOfRange { joint } => {
                write!(f, "joint {}: weight must be in (0, 1]", joint as u32 + 1)
            }
            RobotError::OutOfRange { joint, field } => {
                write!(f, "{}: {field} is implausibly large", Which(joint))
            }
        }
    }
}

/// Why link segments were rejected ([`Robot::set_link_segments`]; the
/// scenario reports them as `self_collision::CapsuleError`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SegmentError {
    /// Segments for a robot of DH rows (only general joints take them).
    NeedGeneralJoints,
    /// Not one segment per link.
    WrongLength {
        /// Segments given.
        given: usize,
        /// Links of the robot.
        links: usize,
    },
    /// An end that is not finite or beyond [`MAX_LENGTH`] (`link` 0-based).
    BadSegment {
        /// The link.
        link: u8,
    },
}

/// Per-joint constants derived once at validation, used by forward kinematics.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct LinkConstants {
    pub(crate) cos_alpha: f32,
    pub(crate) sin_alpha: f32,
    /// `cos theta`, `sin theta` of a prismatic joint (unused for revolute).
    pub(crate) cos_theta: f32,
    pub(crate) sin_theta: f32,
    /// A general joint's origin, turned so that its axis is `z`
    /// ([`origin::align_z`]); identity for a DH row.
    pub(crate) origin: Transform,
    /// The longest this link's chord (from its joint's pivot to the next
    /// pivot, or to the end effector) is in any configuration, length units.
    pub(crate) longest: f32,
    /// Length of the chain from the base to the end of this link (`o_{j+1}`),
    /// prismatic links at their longest: an upper bound, in every
    /// configuration, on the distance between any two points of the arm up to
    /// this link (length units).
    pub(crate) chain: f32,
    /// The link's capsule segment ([`Robot::set_link_segments`]), its two
    /// ends in the joint's `z`-aligned frame after its motion (the frame the
    /// forward pass carries), length units; zeros without segments.
    pub(crate) segment: [Vec3; 2],
    /// `chain` for the capsule's points as well as the chord's: the chain
    /// up to this link's pivot plus the farthest either reaches from it
    /// (`chain` itself without segments). Bounds `|p - o_m|` for every point
    /// `p` of this link's chord or capsule and every earlier pivot `o_m`.
    pub(crate) capsule_chain: f32,
}

/// All zeros (the origin's rotation too: it is read only for a general
/// joint, which sets it), so that clearing `N` of them is one `memset`.
impl Default for LinkConstants {
    fn default() -> Self {
        LinkConstants {
            cos_alpha: 0.0,
            sin_alpha: 0.0,
            cos_theta: 0.0,
            sin_theta: 0.0,
            origin: Transform {
                rotation: Mat3::zeros(),
                translation: Vec3::zeros(),
            },
            longest: 0.0,
            chain: 0.0,
            segment: [Vec3::zeros(); 2],
            capsule_chain: 0.0,
        }
    }
}

/// A validated serial chain of at most `N` joints. Immutable once built.
#[derive(Clone, Debug)]
pub struct Robot<const N: usize> {
    joints: heapless::Vec<Joint, N>,
    links: [LinkConstants; N],
    /// The tool as given (the end effector's frame in the last joint's frame).
    tool: Placement,
    /// The tool as the forward pass applies it (for general joints, in the
    /// last joint's `z`-aligned frame).
    tool_transform: Transform,
    /// Whether `tool_transform` is not the identity (a DH robot without a
    /// tool skips it: its plans are the same to the bit as before tools).
    has_tool: bool,
    /// Whether the joints are general joints ([`origin`]), not DH rows.
    general: bool,
    /// How far the first joint's pivot is from the base, length units.
    base_offset: f32,
    /// Whether the links' capsules are segments of their own
    /// ([`Robot::set_link_segments`]), not their chords.
    segments: bool,
}

impl<const N: usize> Robot<N> {
    /// Checks every joint and precomputes the link constants.
    ///
    /// Rejects: an empty chain, more than `N` joints (or more than 255), any
    /// non-finite field, `min >= max`, `max_rate <= 0`, weight outside `(0, 1]`,
    /// DH rows mixed with general joints, a general joint's rotation that is
    /// not one or its axis of no length.
    pub fn new(joints: &[Joint]) -> Result<Self, RobotError> {
        Self::new_with_tool(joints, &Placement::IDENTITY)
    }

    /// [`Robot::new`] with a tool: the end effector is `tool` in the last
    /// joint's frame (for a DH robot, frame `n`; for general joints, the
    /// last joint's moved frame). The identity gives [`Robot::new`]'s robot.
    pub fn new_with_tool(joints: &[Joint], tool: &Placement) -> Result<Self, RobotError> {
        let mut robot = Self::empty();
        robot.init_with_tool(joints, tool)?;
        Ok(robot)
    }

    /// A robot with no joints: a placeholder for a robot built in place by
    /// [`Robot::init`] (a board keeps its model in a `static`). No planner
    /// starts on it.
    pub fn empty() -> Self {
        Robot {
            joints: heapless::Vec::new(),
            links: [LinkConstants::default(); N],
            tool: Placement::IDENTITY,
            tool_transform: Transform::default(),
            has_tool: false,
            general: false,
            base_offset: 0.0,
            segments: false,
        }
    }

    /// [`Robot::new`] in place: the same checks, the same robot, no
    /// robot-sized value on the stack. On error `self` is left empty.
    pub fn init(&mut self, joints: &[Joint]) -> Result<(), RobotError> {
        self.init_with_tool(joints, &Placement::IDENTITY)
    }

    /// [`Robot::new_with_tool`] in place. On error `self` is left empty.
    pub fn init_with_tool(&mut self, joints: &[Joint], tool: &Placement) -> Result<(), RobotError> {
        let result = self.fill(joints, tool);
        if result.is_err() {
            self.clear();
        }
        result
    }

    /// Empties the robot (see [`Robot::empty`]).
    pub(crate) fn clear(&mut self) {
        let Robot {
            joints,
            links,
            tool,
            tool_transform,
            has_tool,
            general,
            base_offset,
            segments,
        } = self;
        joints.clear();
        links.fill(LinkConstants::default());
        *tool = Placement::IDENTITY;
        *tool_transform = Transform::default();
        *has_tool = false;
        *general = false;
        *base_offset = 0.0;
        *segments = false;
    }

    fn fill(&mut self, joints: &[Joint], tool: &Placement) -> Result<(), RobotError> {
        // Every field is rebuilt: a field added to `Robot` fails to compile here.
        self.clear();
        let Robot {
            joints: out,
            links,
            tool: tool_out,
            tool_transform,
            has_tool,
            general,
            base_offset,
            segments: _,
        } = self;
        if joints.is_empty() {
            return Err(RobotError::Empty);
        }
        if joints.len() > N || joints.len() > u8::MAX as usize - 1 {
            return Err(RobotError::TooManyJoints {
                count: joints.len(),
                capacity: N.min(u8::MAX as usize - 1),
            });
        }
        let is_general = joints.first().is_some_and(|j| j.origin.is_some());
        // The previous joint's alignment `A_{j-1}` (the base's: identity).
        let mut previous_align = Mat3::identity();
        for (i, (j, link)) in joints.iter().zip(links.iter_mut()).enumerate() {
            let joint = i as u8;
            let fields = [
                (j.alpha, JointField::Alpha),
                (j.a, JointField::A),
                (j.theta, JointField::Theta),
                (j.d, JointField::D),
                (j.min, JointField::Limits),
                (j.max, JointField::Limits),
                (j.max_rate, JointField::MaxRate),
                (j.weight, JointField::Weight),
            ];
            for (value, field) in fields {
                if !value.is_finite() {
                    return Err(RobotError::NotFinite { joint, field });
                }
            }
            if j.min >= j.max {
                return Err(RobotError::InvertedLimits { joint });
            }
            let limit_bound = match j.kind {
                JointKind::Revolute => MAX_ANGLE,
                JointKind::Prismatic => MAX_LENGTH,
            };
            let sizes = [
                (j.a, MAX_LENGTH, JointField::A),
                (j.d, MAX_LENGTH, JointField::D),
                (j.min, limit_bound, JointField::Limits),
                (j.max, limit_bound, JointField::Limits),
            ];
            if let Some(&(_, _, field)) = sizes.iter().find(|(v, bound, _)| v.abs() > *bound) {
                return Err(RobotError::OutOfRange { joint, field });
            }
            if j.max_rate <= 0.0 {
                return Err(RobotError::NonPositiveRate { joint });
            }
            if !(j.weight > 0.0 && j.weight <= 1.0) {
                return Err(RobotError::WeightOutOfRange { joint });
            }
            let travel = crate::math::max(j.min.abs(), j.max.abs());
            let (sin_alpha, cos_alpha) = crate::math::sin_cos(j.alpha);
            let (sin_theta, cos_theta) = crate::math::sin_cos(j.theta);
            let mut origin = Transform::default();
            // The link from o_j to o_{j+1} is `d z + a x`: |.| = sqrt(a^2 + d^2).
            // (A general link's chord is known once the next joint is: below.)
            let mut longest = {
                let d = match j.kind {
                    JointKind::Revolute => j.d.abs(),
                    JointKind::Prismatic => travel,
                };
                crate::math::sqrt(j.a * j.a + d * d)
            };
            match (j.origin, is_general) {
                (None, false) => {}
                (Some(o), true) => {
                    let fault = |fault| placement_error(joint, fault);
                    let placed = origin::validate(&o.placement, MAX_LENGTH).map_err(fault)?;
                    let axis = origin::unit_axis(&o.axis).map_err(|f| match f {
                        PlacementFault::NotFinite => RobotError::NotFinite {
                            joint,
                            field: JointField::Axis,
                        },
                        f => placement_error(joint, f),
                    })?;
                    let align = origin::align_z(&axis);
                    origin = Transform {
                        rotation: previous_align.transpose() * placed.rotation * align,
                        translation: previous_align.transpose() * placed.translation,
                    };
                    previous_align = align;
                    if i == 0 {
                        *base_offset = crate::math::norm(&placed.translation);
                    }
                    longest = match j.kind {
                        JointKind::Revolute => 0.0,
                        JointKind::Prismatic => travel,
                    };
                }
                _ => return Err(RobotError::MixedJoints { joint }),
            }
            *link = LinkConstants {
                cos_alpha,
                sin_alpha,
                cos_theta,
                sin_theta,
                origin,
                longest,
                chain: 0.0,
                segment: [Vec3::zeros(); 2],
                capsule_chain: 0.0,
            };
            // Capacity was checked above, so the push cannot fail.
            let _ = out.push(*j);
        }
        let placed_tool =
            origin::validate(tool, MAX_LENGTH).map_err(|f| placement_error(TOOL, f))?;
        *tool_transform = Transform {
            rotation: previous_align.transpose() * placed_tool.rotation,
            translation: previous_align.transpose() * placed_tool.translation,
        };
        *tool_out = *tool;
        // A general chain always ends with its tool (at least `A_{n-1}^T`).
        *has_tool = is_general || !tool.is_identity();
        *general = is_general;
        // A general link's chord ends at the next joint's pivot (or the
        // tool): its length is that placement's translation (plus the
        // travel of a prismatic joint, added above).
        // (Indexed with `get`: no panic path.)
        let n = out.len();
        let tool_offset = crate::math::norm(&tool_transform.translation);
        let mut chain = 0.0f32;
        for k in 0..n {
            let offset = match links.get(k + 1) {
                Some(next) if k + 1 < n => crate::math::norm(&next.origin.translation),
                _ => tool_offset,
            };
            let Some(link) = links.get_mut(k) else {
                break;
            };
            // A DH chain's links are complete but for a tool, which extends
            // the last one.
            if is_general || (*has_tool && k + 1 == n) {
                link.longest += offset;
            }
            chain += link.longest;
            link.chain = chain;
            link.capsule_chain = chain;
        }
        Ok(())
    }

    /// Gives each link a capsule segment of its own, fixed in the body its
    /// joint moves, in place of its chord: `segments[k]` holds the two ends
    /// in joint `k`'s frame after its motion (a URDF joint's frame: the
    /// parent's, then the joint's `<origin>`, then the motion about or along
    /// its axis), length units. Self-collision then measures link `k` as the
    /// capsule round `T_k a -> T_k b` ([`crate::kinematics::Frames::capsule`]);
    /// the obstacles' avoidance points stay on the chords. An empty slice
    /// goes back to the chords. Only general joints take segments (a DH
    /// robot keeps its chords, and its plans their bits).
    ///
    /// On error the robot keeps its chords. Never inlined: called once per
    /// load, it need not grow the load's code on the board.
    #[inline(never)]
    pub fn set_link_segments(&mut self, segments: &[[[f32; 3]; 2]]) -> Result<(), SegmentError> {
        let n = self.len();
        self.segments = false;
        let mut chain_before = 0.0f32;
        for link in self.links.iter_mut().take(n) {
            link.segment = [Vec3::zeros(); 2];
            link.capsule_chain = link.chain;
        }
        if segments.is_empty() {
            return Ok(());
        }
        if !self.general {
            return Err(SegmentError::NeedGeneralJoints);
        }
        if segments.len() != n {
            return Err(SegmentError::WrongLength {
                given: segments.len(),
                links: n,
            });
        }
        for (k, segment) in segments.iter().enumerate() {
            if !segment
                .iter()
                .flatten()
                .all(|x| x.is_finite() && x.abs() <= MAX_LENGTH)
            {
                return Err(SegmentError::BadSegment { link: k as u8 });
            }
        }
        for ((link, joint), segment) in self.links.iter_mut().zip(self.joints.iter()).zip(segments)
        {
            // The forward pass carries the joint's frame turned so that its
            // axis is z: `R_urdf = R_core A^T`, so a point `p` of the URDF
            // frame is `A^T p` in the core's.
            let align = joint
                .origin
                .and_then(|o| origin::unit_axis(&o.axis).ok())
                .map_or_else(Mat3::identity, |axis| origin::align_z(&axis));
            let ends = segment.map(|p| align.transpose() * crate::math::vec3(p));
            let extension = match joint.kind {
                JointKind::Revolute => 0.0,
                JointKind::Prismatic => crate::math::max(joint.min.abs(), joint.max.abs()),
            };
            let farthest =
                crate::math::max(crate::math::norm(&ends[0]), crate::math::norm(&ends[1]))
                    + extension;
            link.segment = ends;
            link.capsule_chain = crate::math::max(link.chain, chain_before + farthest);
            chain_before = link.chain;
        }
        self.segments = true;
        Ok(())
    }

    /// Whether the links' capsules are segments of their own
    /// ([`Robot::set_link_segments`]), not their chords.
    #[inline]
    pub fn has_link_segments(&self) -> bool {
        self.segments
    }

    /// The longest link `k`'s capsule segment is, length units: its own
    /// segment's length ([`Robot::set_link_segments`]), else its chord's
    /// longest ([`Robot::longest_link`]).
    pub fn capsule_length(&self, k: usize) -> f32 {
        match self.links().get(k) {
            Some(l) if self.segments => crate::math::norm(&(l.segment[1] - l.segment[0])),
            Some(l) => l.longest,
            None => 0.0,
        }
    }

    /// Number of joints `n`.
    #[inline]
    pub fn len(&self) -> usize {
        // Never above N (a heapless::Vec<_, N>); the `min` tells the optimiser,
        // so slicing `[_; N]` buffers by it cannot panic.
        self.joints.len().min(N)
    }

    /// False for every validated robot (it has at least one joint); true
    /// only for [`Robot::empty`].
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.joints.is_empty()
    }

    /// The joints, in order from the base.
    #[inline]
    pub fn joints(&self) -> &[Joint] {
        &self.joints
    }

    #[inline]
    pub(crate) fn links(&self) -> &[LinkConstants] {
        &self.links[..self.len()]
    }

    /// Whether the joints are general joints ([`origin`]), not DH rows.
    #[inline]
    pub fn is_general(&self) -> bool {
        self.general
    }

    /// The tool: the end effector's frame in the last joint's frame
    /// (identity unless given to [`Robot::new_with_tool`]).
    #[inline]
    pub fn tool(&self) -> &Placement {
        &self.tool
    }

    /// The tool as the forward pass applies it, when it is not the identity.
    #[inline]
    pub(crate) fn tool_transform(&self) -> Option<&Transform> {
        self.has_tool.then_some(&self.tool_transform)
    }

    /// The longest link `j`'s chord (from its joint's pivot to the next
    /// pivot, or the end effector) is in any configuration, length units.
    #[inline]
    pub fn longest_link(&self, j: usize) -> f32 {
        self.links().get(j).map_or(0.0, |l| l.longest)
    }

    /// The robot's reach, length units: the length of the whole chain, every
    /// prismatic joint at its longest. No point of the arm is ever farther
    /// than this from the base. It is the robot's characteristic length: the
    /// planner's length-valued defaults are fractions of it
    /// ([`crate::Settings::for_robot`]), so they mean the same for a robot
    /// described in inches or in metres.
    #[inline]
    pub fn reach(&self) -> f32 {
        self.base_offset + self.links().last().map_or(0.0, |l| l.chain)
    }

    /// The first joint whose value in `q` is outside its limits, or not finite.
    pub fn first_outside_limits(&self, q: &[f32]) -> Option<usize> {
        self.joints
            .iter()
            .zip(q)
            .position(|(j, &v)| !(v >= j.min && v <= j.max))
    }

    /// Whether `q` has one finite value per joint, each within its limits.
    pub fn accepts(&self, q: &[f32]) -> bool {
        q.len() == self.len() && all_finite(q) && self.first_outside_limits(q).is_none()
    }
}

/// A placement fault as the robot's error, for `joint` (or [`TOOL`]).
fn placement_error(joint: u8, fault: PlacementFault) -> RobotError {
    match fault {
        PlacementFault::NotFinite => RobotError::NotFinite {
            joint,
            field: JointField::Origin,
        },
        PlacementFault::NotRotation => RobotError::NotRotation { joint },
        PlacementFault::TooFar => RobotError::OutOfRange {
            joint,
            field: JointField::Origin,
        },
        PlacementFault::ZeroAxis => RobotError::ZeroAxis { joint },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ok_joint() -> Joint {
        Joint::revolute(0.5, 1.0, 0.0, -1.0, 1.0, 0.5)
    }

    #[test]
    fn rejects_bad_chains_with_the_joint_and_reason() {
        assert_eq!(Robot::<4>::new(&[]).unwrap_err(), RobotError::Empty);
        assert_eq!(
            Robot::<2>::new(&[ok_joint(); 3]).unwrap_err(),
            RobotError::TooManyJoints {
                count: 3,
                capacity: 2
            }
        );
        let mut j = ok_joint();
        j.a = f32::NAN;
        assert_eq!(
            Robot::<4>::new(&[ok_joint(), j]).unwrap_err(),
            RobotError::NotFinite {
                joint: 1,
                field: JointField::A
            }
        );
        let mut j = ok_joint();
        j.alpha = f32::INFINITY;
        assert!(matches!(
            Robot::<4>::new(&[j]).unwrap_err(),
            RobotError::NotFinite {
                joint: 0,
                field: JointField::Alpha
            }
        ));
        let mut j = ok_joint();
        j.min = 2.0;
        assert_eq!(
            Robot::<4>::new(&[j]).unwrap_err(),
            RobotError::InvertedLimits { joint: 0 }
        );
        let mut j = ok_joint();
        j.max_rate = 0.0;
        assert_eq!(
            Robot::<4>::new(&[j]).unwrap_err(),
            RobotError::NonPositiveRate { joint: 0 }
        );
        let j = ok_joint().with_weight(1.5);
        assert_eq!(
            Robot::<4>::new(&[j]).unwrap_err(),
            RobotError::WeightOutOfRange { joint: 0 }
        );
        let j = ok_joint().with_weight(f32::NAN);
        assert!(Robot::<4>::new(&[j]).is_err());
        let mut j = ok_joint();
        j.a = 1.0e30;
        assert_eq!(
            Robot::<4>::new(&[j]).unwrap_err(),
            RobotError::OutOfRange {
                joint: 0,
                field: JointField::A
            }
        );
    }

    #[test]
    fn range_fraction_is_minus_one_to_one() {
        let j = Joint::prismatic(0.0, 0.0, 0.0, 2.0, 6.0, 1.0);
        assert_eq!(j.range_fraction(2.0), -1.0);
        assert_eq!(j.range_fraction(6.0), 1.0);
        assert_eq!(j.range_fraction(4.0), 0.0);
    }

    #[test]
    fn limits_check_catches_nan_and_out_of_range() {
        let r = Robot::<4>::new(&[ok_joint(), ok_joint()]).unwrap();
        assert!(r.accepts(&[0.0, 0.5]));
        assert!(!r.accepts(&[0.0, 1.5]));
        assert!(!r.accepts(&[f32::NAN, 0.0]));
        assert!(!r.accepts(&[0.0]));
        assert_eq!(r.first_outside_limits(&[0.0, -3.0]), Some(1));
    }
}
