//! [`Frames`]: every frame of the chain at one configuration, written by the
//! forward passes of [`super`] (DH rows) and `general` (general joints),
//! read by everything downstream.

use crate::math::{Mat3, Vec3};
use crate::robot::JointKind;

/// Every frame of the chain at one configuration. Sized once for `N` joints.
#[derive(Clone, Debug)]
pub struct Frames<const N: usize> {
    pub(super) n: usize,
    /// The pivot of the first joint (DH: the base's origin `o_0`).
    pub(super) base: Vec3,
    /// `link_end[j]`, where link `j` ends: the pivot of joint `j + 1`, and
    /// for the last link the end effector (DH: `o_{j+1}`). Each joint's
    /// pivot is stored once, as the end of the link before it: the
    /// avoidance points and conservative advancement read every link from
    /// its pivot to its end, so this layout costs no lookup more than the
    /// DH one it replaces.
    pub(super) link_end: [Vec3; N],
    /// `axis[j]`, the unit axis joint `j` moves about or along (DH: `z_j`).
    pub(super) axis: [Vec3; N],
    /// Orientation of the end-effector frame `n`: columns `r_n1, r_n2, r_n3` (eq. 6).
    pub(super) end_rotation: Mat3,
    /// Each link's capsule segment, world, when the robot has segments of
    /// its own ([`crate::robot::Robot::set_link_segments`]).
    pub(super) segment: [[Vec3; 2]; N],
    /// Whether `segment` holds them (else each link's capsule is its chord).
    pub(super) segments: bool,
}

impl<const N: usize> Default for Frames<N> {
    fn default() -> Self {
        Frames {
            n: 0,
            base: Vec3::zeros(),
            link_end: [Vec3::zeros(); N],
            axis: [Vec3::z(); N],
            end_rotation: Mat3::identity(),
            segment: [[Vec3::zeros(); 2]; N],
            segments: false,
        }
    }
}

impl<const N: usize> Frames<N> {
    /// [`Frames::default`] in place, field by field (no frames-sized
    /// temporary: `Frames` of 32 joints is 2 KiB).
    pub fn clear(&mut self) {
        let Frames {
            n,
            base,
            link_end,
            axis,
            end_rotation,
            segment,
            segments,
        } = self;
        *n = 0;
        *base = Vec3::zeros();
        link_end.fill(Vec3::zeros());
        axis.fill(Vec3::z());
        *end_rotation = Mat3::identity();
        segment.fill([Vec3::zeros(); 2]);
        *segments = false;
    }

    /// Number of joints these frames were computed for.
    #[inline]
    pub fn len(&self) -> usize {
        self.n
    }

    /// Whether no frames have been computed.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Where link `j` ends, length units: the pivot of joint `j + 1`, or the
    /// end effector after the last joint (DH: `o_{j+1}`).
    #[inline]
    pub fn link_end(&self, j: usize) -> Vec3 {
        // `get`: no panic path; every caller passes `j < len()`.
        self.link_end.get(j).copied().unwrap_or_else(Vec3::zeros)
    }

    /// The point joint `j` turns about (a prismatic joint: where its link
    /// starts), length units (DH: `o_j`).
    #[inline]
    pub fn pivot(&self, j: usize) -> Vec3 {
        if j == 0 {
            self.base
        } else {
            self.link_end(j - 1)
        }
    }

    /// The segment link `j`'s self-collision capsule is round, world, length
    /// units: its own segment when the robot has them
    /// ([`crate::robot::Robot::set_link_segments`]), else its chord, from
    /// [`Frames::pivot`] to [`Frames::link_end`]. Either is fixed in the
    /// body joint `j` moves (a prismatic joint's chord stretches with it).
    #[inline]
    pub fn capsule(&self, j: usize) -> (Vec3, Vec3) {
        if self.segments {
            let [a, b] = self.segment.get(j).copied().unwrap_or([Vec3::zeros(); 2]);
            (a, b)
        } else {
            (self.pivot(j), self.link_end(j))
        }
    }

    /// Whether the links' capsules are segments of their own, not chords
    /// ([`Frames::capsule`]).
    #[inline]
    pub fn has_segments(&self) -> bool {
        self.segments
    }

    /// Unit axis `z_j` joint `j` turns about or slides along.
    #[inline]
    pub fn axis(&self, j: usize) -> Vec3 {
        self.axis.get(j).copied().unwrap_or_else(Vec3::z)
    }

    /// Column `j` of the Jacobian of a point `p` carried by a link at or
    /// after joint `j` (of kind `kind`): `(dp/dq_j, dw/dq_j)`, the linear and
    /// the angular velocity per unit rate of joint `j`: `(z x (p - o), z)`
    /// for a revolute joint, `(z, 0)` for a prismatic one. O(1).
    #[inline]
    pub fn column(&self, j: usize, kind: JointKind, p: &Vec3) -> (Vec3, Vec3) {
        let z = self.axis(j);
        match kind {
            JointKind::Revolute => (z.cross(&(p - self.pivot(j))), z),
            JointKind::Prismatic => (z, Vec3::zeros()),
        }
    }

    /// End-effector position `r_n4`.
    #[inline]
    pub fn end_position(&self) -> Vec3 {
        match self
            .n
            .checked_sub(1)
            .and_then(|last| self.link_end.get(last))
        {
            Some(&o) => o,
            None => self.base,
        }
    }

    /// End-effector orientation (columns `r_n1..r_n3`).
    #[inline]
    pub fn end_rotation(&self) -> &Mat3 {
        &self.end_rotation
    }
}
