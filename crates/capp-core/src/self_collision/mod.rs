//! Self-collision: the arm's links as capsules, the pairs of links that must
//! stay apart, and what they add to the obstacle field every step.
//!
//! * [`LinkCapsules`]: each link `k` (from its joint's pivot to the next
//!   pivot, DH link `k + 1`) is the capsule of radius `r_k` round that chord,
//!   or round a segment of its own fixed in its body when the robot has
//!   them ([`crate::robot::Robot::set_link_segments`]: a URDF link whose
//!   body lies off its chord); [`crate::kinematics::Frames::capsule`] gives
//!   either. Built once per scenario ([`crate::Scenario::set_link_capsules`]);
//!   a scenario without them has no self-collision checks.
//! * [`pairs`]: which pairs are checked (an allowed-collision matrix, as
//!   MoveIt's setup assistant builds one): adjacent links, links sharing a
//!   knuckle, pairs in contact at home or in every sampled configuration,
//!   and pairs a user allows are skipped; every other pair is checked.
//! * [`field`]: per evaluation, each checked pair's clearance (the chords'
//!   distance [`segment`] less both radii): a term of the potential with its
//!   exact gradient through both links' Jacobian columns, the closest pair,
//!   and each link's room for conservative advancement. A broad phase (a
//!   bounding sphere per link) settles most pairs in one comparison.
//!
//! The clearance of a pair is dimensionless, as the obstacles' `C - 1` is:
//! `c = gap / (CLEARANCE_SCALE (r_a + r_b))`, so the projection (eq. 24)
//! engages for a link pair at `c < 2 engage_clearance` as it does for an
//! obstacle, and the potential
//! term `1 / c` has the shape of eq. 26's `1 / (C - 1)`.

pub mod field;
pub mod pairs;
pub mod segment;

use crate::robot::{Robot, SegmentError, MAX_LENGTH};

/// Most links a scenario with self-collision may have (the checked pairs of
/// a link are one `u64` of bits).
pub const MAX_LINKS: usize = 64;

/// Link pairs are in the potential (and narrow-phase tested) while their
/// clearance `c` is below this; beyond it a pair is at
/// least this many clearance units (`CLEARANCE_SCALE` radius sums) apart, which is all conservative advancement
/// needs to know of it. 2 is the band where the projection engages with the
/// default `engage_clearance` (1: engaged below `c = 2`). A wider band
/// (4 was tried) keeps the truss's links two apart (9 in apart at PIPS
/// home, structurally) in the potential all the time: a constant push in
/// `mu` that only tilts the projection, and twice the narrow-phase tests.
pub const INFLUENCE: f32 = 2.0;

/// A link pair's clearance is its gap in units of this fraction of the
/// two radii: `c = gap / (CLEARANCE_SCALE (r_a + r_b))`. With 0.5 the
/// projection engages (`c < 2`) once two capsules are closer than the sum
/// of their radii (PIPS: 3 in) and in full below half of it; with 1 (the
/// first choice) the arm kept 3 in from itself while travelling and some
/// payload-bay targets next to the pedestal were no longer reached.
pub const CLEARANCE_SCALE: f32 = 0.5;

/// Why link capsules were rejected. `link` is 0-based (DH link `link + 1`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CapsuleError {
    /// A radius or a row of checked pairs per link was not given.
    WrongLength {
        /// Values given.
        given: usize,
        /// Links of the robot.
        links: usize,
    },
    /// More links than [`MAX_LINKS`].
    TooManyLinks {
        /// Links of the robot.
        links: usize,
    },
    /// A radius that is not finite, not positive, or over [`MAX_LENGTH`].
    BadRadius {
        /// The link.
        link: u8,
    },
    /// A checked pair naming a link the robot does not have, or a link with
    /// itself (row `a` may hold only links `b > a`).
    BadPair {
        /// The link whose row is wrong.
        link: u8,
    },
    /// A link segment with an end that is not finite or beyond
    /// [`MAX_LENGTH`] ([`Robot::set_link_segments`]).
    BadSegment {
        /// The link.
        link: u8,
    },
    /// Link segments for a robot of DH rows (only general joints take them).
    SegmentsNeedGeneralJoints,
}

impl From<SegmentError> for CapsuleError {
    fn from(e: SegmentError) -> Self {
        match e {
            SegmentError::NeedGeneralJoints => CapsuleError::SegmentsNeedGeneralJoints,
            SegmentError::WrongLength { given, links } => {
                CapsuleError::WrongLength { given, links }
            }
            SegmentError::BadSegment { link } => CapsuleError::BadSegment { link },
        }
    }
}

impl core::fmt::Display for CapsuleError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            CapsuleError::WrongLength { given, links } => {
                write!(f, "link capsules: {given} values for {links} links")
            }
            CapsuleError::TooManyLinks { links } => write!(
                f,
                "link capsules: {links} links, more than the {MAX_LINKS} self-collision supports"
            ),
            CapsuleError::BadRadius { link } => write!(
                f,
                "link {}: the capsule radius must be positive and finite",
                link as u32 + 1
            ),
            CapsuleError::BadPair { link } => write!(
                f,
                "link {}: a checked pair names a link that is not after it on the robot",
                link as u32 + 1
            ),
            CapsuleError::BadSegment { link } => write!(
                f,
                "link {}: the capsule segment's ends must be finite and within {MAX_LENGTH}",
                link as u32 + 1
            ),
            CapsuleError::SegmentsNeedGeneralJoints => write!(
                f,
                "link capsule segments are for general joints; a DH robot's capsules are round its chords"
            ),
        }
    }
}

/// The links' capsules and the pairs checked, validated against a robot.
#[derive(Clone, Debug, PartialEq)]
pub struct LinkCapsules<const N: usize> {
    /// Links with capsules (the robot's joint count), 0 when there are none.
    n: usize,
    /// Capsule radius per link, length units.
    radius: [f32; N],
    /// Per link, the radius of the sphere round its segment's mid-point
    /// ([`crate::kinematics::Frames::capsule`]) that holds its capsule
    /// inflated by [`INFLUENCE`] radii in every configuration: half its
    /// longest segment plus `(1 + INFLUENCE CLEARANCE_SCALE) r`.
    reach: [f32; N],
    /// Per link, the room it may use in one step against the pairs too far
    /// apart to be tested: `INFLUENCE CLEARANCE_SCALE r` (infinity when it has no checked pair).
    far_room: [f32; N],
    /// Row `a`: bit `b` set (`b > a`) when the pair `(a, b)` is checked.
    checked: [u64; N],
}

impl<const N: usize> Default for LinkCapsules<N> {
    fn default() -> Self {
        Self::none()
    }
}

impl<const N: usize> LinkCapsules<N> {
    /// No capsules: self-collision is not checked.
    pub const fn none() -> Self {
        LinkCapsules {
            n: 0,
            radius: [0.0; N],
            reach: [0.0; N],
            far_room: [f32::INFINITY; N],
            checked: [0; N],
        }
    }

    /// Capsules of `radius` (one per link, length units) round the links of
    /// `robot`, with the pairs of `checked` (row `a`: bit `b > a` set when
    /// the pair is checked; see [`pairs::PairTable::checked_rows`]).
    pub fn new(robot: &Robot<N>, radius: &[f32], checked: &[u64]) -> Result<Self, CapsuleError> {
        let n = robot.len();
        if n > MAX_LINKS {
            return Err(CapsuleError::TooManyLinks { links: n });
        }
        for given in [radius.len(), checked.len()] {
            if given != n {
                return Err(CapsuleError::WrongLength { given, links: n });
            }
        }
        let mut capsules = Self::none();
        // Zipped iterators, not indices: no panic path on the board.
        let slots = capsules.radius.iter_mut().zip(capsules.checked.iter_mut());
        for (link, (((&r, &row), _), (radius, checked))) in radius
            .iter()
            .zip(checked)
            .zip(robot.joints())
            .zip(slots)
            .enumerate()
        {
            if !(r.is_finite() && r > 0.0 && r <= MAX_LENGTH) {
                return Err(CapsuleError::BadRadius { link: link as u8 });
            }
            // Only links after this one, and only links the robot has.
            let robot_links = if n >= 64 { u64::MAX } else { (1u64 << n) - 1 };
            let after = !((2u64 << link) - 1);
            if row & !(robot_links & after) != 0 {
                return Err(CapsuleError::BadPair { link: link as u8 });
            }
            *radius = r;
            *checked = row;
        }
        capsules.n = n;
        capsules.fit(robot);
        // A link has a far room when it is in any checked pair.
        let mut paired = 0u64;
        for (a, &row) in capsules.checked.iter().enumerate() {
            if row != 0 {
                paired |= row | (1u64 << (a & 63));
            }
        }
        for (a, (room, &r)) in capsules
            .far_room
            .iter_mut()
            .zip(&capsules.radius)
            .enumerate()
        {
            if a < 64 && paired & (1u64 << a) != 0 {
                *room = INFLUENCE * CLEARANCE_SCALE * r;
            }
        }
        Ok(capsules)
    }

    /// Sizes the broad phase's spheres ([`LinkCapsules::reach`]) for
    /// `robot`'s capsules: at [`LinkCapsules::new`], and again after
    /// [`Robot::set_link_segments`].
    pub(crate) fn fit(&mut self, robot: &Robot<N>) {
        for (k, (reach, &r)) in self
            .reach
            .iter_mut()
            .zip(&self.radius)
            .enumerate()
            .take(self.n)
        {
            *reach = 0.5 * robot.capsule_length(k) + (1.0 + INFLUENCE * CLEARANCE_SCALE) * r;
        }
    }

    /// Whether there are capsules (and so self-collision checks).
    #[inline]
    pub fn is_on(&self) -> bool {
        self.n > 0
    }

    /// Links with capsules (0 when off).
    #[inline]
    pub fn len(&self) -> usize {
        self.n
    }

    /// Whether there are none.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Capsule radius of link `k`, length units (0 when off).
    #[inline]
    pub fn radius(&self, k: usize) -> f32 {
        self.radius.get(k).copied().unwrap_or(0.0)
    }

    /// Whether the pair of links `a`, `b` (either order) is checked.
    #[inline]
    pub fn is_checked(&self, a: usize, b: usize) -> bool {
        let (a, b) = if a < b { (a, b) } else { (b, a) };
        b < 64
            && self
                .checked
                .get(a)
                .is_some_and(|row| row & (1u64 << b) != 0)
    }

    /// The checked pairs' rows (row `a`: bit `b > a` per checked pair), as
    /// [`LinkCapsules::new`] takes them.
    pub fn checked_rows(&self) -> &[u64] {
        &self.checked[..self.n.min(N)]
    }

    /// The radii, one per link.
    pub fn radii(&self) -> &[f32] {
        &self.radius[..self.n.min(N)]
    }

    /// How many pairs are checked.
    pub fn checked_count(&self) -> usize {
        self.checked_rows()
            .iter()
            .map(|r| r.count_ones() as usize)
            .sum()
    }
}
