//! The serial chain a URDF file describes between a base and a tip link, and
//! its forward kinematics.
//!
//! Frames: the world is the base link's frame. Joint i's frame is the frame
//! of its child link (URDF's convention), so at joint value q
//!
//! ```text
//! T_0     = I                                   (base link frame)
//! T_{i+1} = T_i * origin_i * M_i(q_i)           (frame of joints[i])
//! T_tip   = T_n * tool
//! M_i(q)  = rotation by q about axis_i          (revolute, continuous)
//!         = translation by q * axis_i           (prismatic)
//! ```
//!
//! with `origin_i` from the previous moving joint's frame (the base link
//! frame for joint 0) to joint i's frame at q = 0, any fixed joints between
//! them folded in. Units: metres, radians.

use nalgebra::{Isometry3, Point3, Translation3, Unit, UnitQuaternion, Vector3};

use crate::error::UrdfError;

/// A serial chain from a base link to a tip link.
#[derive(Debug, Clone, PartialEq)]
pub struct Chain {
    /// `<robot name>`.
    pub robot_name: String,
    /// The link whose frame is the world frame of [`Chain::forward`].
    pub base_link: String,
    /// The link whose frame is the last pose of [`Chain::forward`].
    pub tip_link: String,
    /// The moving joints from base to tip, in order.
    pub joints: Vec<ChainJoint>,
    /// The tip link's frame relative to the last moving joint's frame (the
    /// fixed joints after it folded in).
    pub tool: Isometry3<f64>,
    /// `bodies[0]`: everything rigidly attached to the base, in the base link
    /// frame; `bodies[i + 1]`: the rigid body `joints[i]` moves, in
    /// `joints[i]`'s frame. So `bodies.len() == joints.len() + 1`.
    pub bodies: Vec<Body>,
}

/// One moving joint of a [`Chain`].
#[derive(Debug, Clone, PartialEq)]
pub struct ChainJoint {
    /// `<joint name>`.
    pub name: String,
    /// How it moves.
    pub kind: JointKind,
    /// From the previous moving joint's frame (the base link frame for the
    /// first joint) to this joint's frame at q = 0, fixed joints in between
    /// folded in. URDF `<origin xyz rpy>`: R = Rz(yaw) Ry(pitch) Rx(roll).
    pub origin: Isometry3<f64>,
    /// The motion axis in this joint's frame (URDF `<axis xyz>`, default
    /// (1, 0, 0)), normalised.
    pub axis: Unit<Vector3<f64>>,
    /// Lower limit, radians or metres. `f64::NEG_INFINITY` for a continuous
    /// joint (whatever its `<limit>` says) and for a limit URDF 1.2 leaves
    /// out: the caller chooses a range.
    pub lower: f64,
    /// Upper limit, radians or metres. `f64::INFINITY` for a continuous
    /// joint and for a limit URDF 1.2 leaves out.
    pub upper: f64,
    /// `<limit velocity>`, rad/s or m/s; `None` when absent, 0 or infinite.
    pub velocity: Option<f64>,
}

/// The kinds of joint a [`Chain`] can hold.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JointKind {
    /// Rotation about the axis, within `lower..=upper` radians.
    Revolute,
    /// Rotation about the axis without limits.
    Continuous,
    /// Translation along the axis, within `lower..=upper` metres.
    Prismatic,
}

/// A rigid body of a [`Chain`]: the links it is made of and their collision
/// geometry as capsules in the body's frame.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Body {
    /// The links rigidly joined into this body (the first one is the body's
    /// frame), in the order they were met.
    pub links: Vec<String>,
    /// The links' `<collision>` geometry, each element as one or more capsules.
    pub capsules: Vec<Capsule>,
}

/// A capsule: the points within `radius` of the segment `a`-`b`, in the
/// frame of the [`Body`] that holds it (metres). `a == b` is a sphere.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Capsule {
    /// One end of the segment.
    pub a: Point3<f64>,
    /// The other end.
    pub b: Point3<f64>,
    /// The radius around the segment.
    pub radius: f64,
}

impl Capsule {
    /// The distance from `p` to the segment (not to the surface).
    pub fn segment_distance(&self, p: &Point3<f64>) -> f64 {
        let ab = self.b - self.a;
        let length2 = ab.norm_squared();
        let t = if length2 > 0.0 {
            ((p - self.a).dot(&ab) / length2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (p - (self.a + ab * t)).norm()
    }

    /// Whether `p` is inside, `tolerance` metres of slack allowed.
    pub fn contains(&self, p: &Point3<f64>, tolerance: f64) -> bool {
        self.segment_distance(p) <= self.radius + tolerance
    }

    /// The volume, m^3: a cylinder plus a sphere.
    pub fn volume(&self) -> f64 {
        let r = self.radius;
        core::f64::consts::PI * r * r * ((self.b - self.a).norm() + 4.0 / 3.0 * r)
    }

    /// The same capsule in the frame `to` maps into.
    pub fn transformed(&self, to: &Isometry3<f64>) -> Capsule {
        Capsule {
            a: to * self.a,
            b: to * self.b,
            radius: self.radius,
        }
    }
}

impl ChainJoint {
    /// M(q): this joint's motion at value `q`: the rotation by `q` radians
    /// about `axis` (revolute, continuous) or the translation by `q * axis`
    /// metres (prismatic), in this joint's frame.
    pub fn motion(&self, q: f64) -> Isometry3<f64> {
        match self.kind {
            JointKind::Revolute | JointKind::Continuous => Isometry3::from_parts(
                Translation3::identity(),
                UnitQuaternion::from_axis_angle(&self.axis, q),
            ),
            JointKind::Prismatic => Isometry3::from_parts(
                Translation3::from(self.axis.into_inner() * q),
                UnitQuaternion::identity(),
            ),
        }
    }
}

impl Chain {
    /// The frame of each moving joint at `q`, in the base link's frame, then
    /// the tip link's frame last: `joints.len() + 1` poses.
    ///
    /// ```text
    /// T_0     = I                                   (base link frame)
    /// T_{i+1} = T_i * origin_i * M_i(q_i)           (frame of joints[i])
    /// T_tip   = T_n * tool
    /// ```
    ///
    /// with M_i from [`ChainJoint::motion`].
    ///
    /// `q` holds one value per moving joint (radians or metres); limits are
    /// not checked. Errors: wrong length, a non-finite value.
    pub fn forward(&self, q: &[f64]) -> Result<Vec<Isometry3<f64>>, UrdfError> {
        if q.len() != self.joints.len() {
            return Err(UrdfError::JointCount {
                expected: self.joints.len(),
                got: q.len(),
            });
        }
        if let Some(index) = q.iter().position(|v| !v.is_finite()) {
            return Err(UrdfError::NonFiniteJointValue { index });
        }
        let mut frames = Vec::with_capacity(self.joints.len() + 1);
        let mut t = Isometry3::identity();
        for (joint, &value) in self.joints.iter().zip(q) {
            t = t * joint.origin * joint.motion(value);
            frames.push(t);
        }
        frames.push(t * self.tool);
        Ok(frames)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn joint(kind: JointKind, axis: Vector3<f64>) -> ChainJoint {
        ChainJoint {
            name: "j".into(),
            kind,
            origin: Isometry3::translation(0.0, 0.0, 1.0),
            axis: Unit::new_normalize(axis),
            lower: -1.0,
            upper: 1.0,
            velocity: None,
        }
    }

    #[test]
    fn forward_composes_origin_motion_and_tool() {
        let chain = Chain {
            robot_name: "r".into(),
            base_link: "a".into(),
            tip_link: "c".into(),
            joints: vec![
                joint(JointKind::Revolute, Vector3::z()),
                joint(JointKind::Prismatic, Vector3::x()),
            ],
            tool: Isometry3::translation(0.5, 0.0, 0.0),
            bodies: vec![Body::default(); 3],
        };
        let frames = chain
            .forward(&[core::f64::consts::FRAC_PI_2, 0.25])
            .unwrap();
        assert_eq!(frames.len(), 3);
        // Joint 0 at (0, 0, 1) turned 90 degrees about z: its x is world y.
        let tip = frames[2] * Point3::origin();
        assert!((tip - Point3::new(0.0, 0.75, 2.0)).norm() < 1e-12);
        assert_eq!(
            chain.forward(&[0.0]),
            Err(UrdfError::JointCount {
                expected: 2,
                got: 1
            })
        );
        assert_eq!(
            chain.forward(&[0.0, f64::NAN]),
            Err(UrdfError::NonFiniteJointValue { index: 1 })
        );
    }

    #[test]
    fn capsule_distance_and_volume() {
        let c = Capsule {
            a: Point3::new(0.0, 0.0, 0.0),
            b: Point3::new(0.0, 0.0, 2.0),
            radius: 1.0,
        };
        assert_eq!(c.segment_distance(&Point3::new(3.0, 0.0, 1.0)), 3.0);
        assert_eq!(c.segment_distance(&Point3::new(0.0, 0.0, -2.0)), 2.0);
        assert!(c.contains(&Point3::new(0.0, 1.0, 2.0), 0.0));
        let pi = core::f64::consts::PI;
        assert!((c.volume() - (2.0 * pi + 4.0 / 3.0 * pi)).abs() < 1e-12);
    }
}
