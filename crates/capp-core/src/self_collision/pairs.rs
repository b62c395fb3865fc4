//! Which pairs of links are checked: an allowed-collision matrix, built as
//! MoveIt's setup assistant builds one (adjacent links, pairs in contact at
//! the default pose, pairs in contact in every sampled pose), plus the
//! chain's knuckles and the pairs a user allows.
//!
//! A pair is skipped, with its reason ([`PairStatus`]), when:
//!
//! 1. the links are consecutive ([`PairStatus::Adjacent`]): they share a joint;
//! 2. every link between them is a *knuckle link*, a link whose longest
//!    chord is shorter than its capsule's diameter (PIPS: the offsets under
//!    3 in inside each truss knuckle, and the wrist): the two links share
//!    that knuckle ([`PairStatus::Knuckle`]);
//! 3. a user allows it ([`PairStatus::Allowed`]), such as the parts of one
//!    rigid group (the PIPS pedestal, [`crate::pips::allowed_pairs`]);
//! 4. the capsules touch at the robot's home configuration
//!    ([`PairStatus::Home`]);
//! 5. they touch in every one of the sampled configurations (seeded,
//!    reproducible; [`PairStatus::Always`]).
//!
//! A pair is never skipped only because sampling never saw it touch: every
//! other pair is checked ([`PairStatus::Checked`]). Building the table is
//! host work (samples x pairs segment tests); the board receives its checked
//! rows ([`PairTable::checked_rows`]).

use super::segment::closest_points;
use super::{CapsuleError, MAX_LINKS};
use crate::escape::rng::Rng;
use crate::kinematics::{forward_kinematics, Frames};
use crate::robot::Robot;

/// Configurations sampled for [`PairStatus::Always`] (MoveIt's default
/// density). The test stops early once every candidate pair has been seen
/// apart, which is after a few samples on every robot tried.
pub const SAMPLES: u32 = 10_000;

/// Why a pair is checked or skipped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PairStatus {
    /// Checked every step.
    Checked,
    /// A link with itself (never a pair).
    Same,
    /// Consecutive links: they share a joint.
    Adjacent,
    /// Only knuckle links between them: they share a knuckle.
    Knuckle,
    /// Listed by the user (or the robot's preset).
    Allowed,
    /// In contact at the home configuration.
    Home,
    /// In contact in every sampled configuration.
    Always,
}

impl PairStatus {
    /// Why, in a few words (for `capp acm`).
    pub fn reason(self) -> &'static str {
        match self {
            PairStatus::Checked => "checked",
            PairStatus::Same => "the same link",
            PairStatus::Adjacent => "adjacent: they share a joint",
            PairStatus::Knuckle => "they share a knuckle (only short links between them)",
            PairStatus::Allowed => "allowed by the robot description",
            PairStatus::Home => "in contact at the home configuration",
            PairStatus::Always => "in contact in every sampled configuration",
        }
    }
}

/// The status of every pair of links of a robot.
#[derive(Clone, Debug, PartialEq)]
pub struct PairTable<const N: usize> {
    n: usize,
    /// `status[a][b]`, symmetric.
    status: [[PairStatus; N]; N],
    /// Row `a`: bit `b > a` set when the pair is checked.
    rows: [u64; N],
}

/// Whether the capsules of links `a` and `b` (radii `ra`, `rb`) touch at `frames`.
fn touching<const N: usize>(frames: &Frames<N>, a: usize, b: usize, ra: f32, rb: f32) -> bool {
    let ((start_a, end_a), (start_b, end_b)) = (frames.capsule(a), frames.capsule(b));
    let c = closest_points(&start_a, &end_a, &start_b, &end_b);
    let radii = ra + rb;
    c.distance_sq <= radii * radii
}

impl<const N: usize> PairTable<N> {
    /// The pairs skipped by the chain alone (adjacent links, shared
    /// knuckles) and by `allowed` (0-based link pairs, either order);
    /// every other pair checked. `radius` holds one capsule radius per link.
    /// Inputs that do not fit the robot are ignored here and refused by
    /// [`PairTable::new`].
    pub fn adjacency(robot: &Robot<N>, radius: &[f32], allowed: &[(u8, u8)]) -> Self {
        let n = robot.len().min(MAX_LINKS).min(radius.len());
        let mut table = PairTable {
            n,
            status: [[PairStatus::Checked; N]; N],
            rows: [0; N],
        };
        let knuckle = |k: usize| {
            k < robot.len()
                && radius
                    .get(k)
                    .is_some_and(|&r| robot.longest_link(k) < 2.0 * r)
        };
        for a in 0..n {
            table.status[a][a] = PairStatus::Same;
            for b in a + 1..n {
                let status = if b == a + 1 {
                    PairStatus::Adjacent
                } else if (a + 1..b).all(knuckle) {
                    PairStatus::Knuckle
                } else {
                    PairStatus::Checked
                };
                table.set(a, b, status);
            }
        }
        for &(a, b) in allowed {
            let (a, b) = (a as usize, b as usize);
            if a < n && b < n && table.status(a, b) == PairStatus::Checked {
                table.set(a, b, PairStatus::Allowed);
            }
        }
        table
    }

    /// The whole table: [`PairTable::adjacency`], then the pairs in
    /// contact at `home` and in every one of `samples` configurations drawn
    /// uniformly within the joint limits (xorshift seeded by `seed`).
    pub fn new(
        robot: &Robot<N>,
        radius: &[f32],
        allowed: &[(u8, u8)],
        home: &[f32],
        samples: u32,
        seed: u32,
    ) -> Result<Self, CapsuleError> {
        let n = robot.len();
        if n > MAX_LINKS {
            return Err(CapsuleError::TooManyLinks { links: n });
        }
        for given in [radius.len(), home.len()] {
            if given != n {
                return Err(CapsuleError::WrongLength { given, links: n });
            }
        }
        if let Some(link) = radius.iter().position(|r| !(r.is_finite() && *r > 0.0)) {
            return Err(CapsuleError::BadRadius { link: link as u8 });
        }
        if let Some(&(a, b)) = allowed
            .iter()
            .find(|(a, b)| *a as usize >= n || *b as usize >= n || a == b)
        {
            return Err(CapsuleError::BadPair { link: a.min(b) });
        }
        let mut table = Self::adjacency(robot, radius, allowed);
        let mut frames = Frames::<N>::default();
        forward_kinematics(robot, home, &mut frames);
        table.skip_touching(&frames, radius, PairStatus::Home);
        // Candidates for "always": checked pairs; each sample drops those it sees apart.
        let mut candidates = table.rows;
        let mut rng = Rng::seeded(seed, &[]);
        let mut q = [0.0f32; N];
        for _ in 0..samples {
            if candidates.iter().all(|&r| r == 0) {
                break;
            }
            for (x, joint) in q.iter_mut().zip(robot.joints()) {
                *x = joint.clamp(
                    0.5 * (joint.min + joint.max) + 0.5 * (joint.max - joint.min) * rng.uniform(),
                );
            }
            forward_kinematics(robot, &q[..n], &mut frames);
            for a in 0..n {
                let mut row = candidates[a];
                while row != 0 {
                    let b = row.trailing_zeros() as usize;
                    row &= row - 1;
                    if !touching(&frames, a, b, radius[a], radius[b]) {
                        candidates[a] &= !(1u64 << b);
                    }
                }
            }
        }
        if samples > 0 {
            for (a, &always) in candidates.iter().enumerate().take(n) {
                let mut row = always;
                while row != 0 {
                    let b = row.trailing_zeros() as usize;
                    row &= row - 1;
                    table.set(a, b, PairStatus::Always);
                }
            }
        }
        Ok(table)
    }

    fn skip_touching(&mut self, frames: &Frames<N>, radius: &[f32], status: PairStatus) {
        for a in 0..self.n {
            for b in a + 1..self.n {
                if self.status(a, b) == PairStatus::Checked
                    && touching(frames, a, b, radius[a], radius[b])
                {
                    self.set(a, b, status);
                }
            }
        }
    }

    fn set(&mut self, a: usize, b: usize, status: PairStatus) {
        let (a, b) = if a < b { (a, b) } else { (b, a) };
        if b >= self.n {
            return;
        }
        self.status[a][b] = status;
        self.status[b][a] = status;
        if status == PairStatus::Checked {
            self.rows[a] |= 1u64 << b;
        } else {
            self.rows[a] &= !(1u64 << b);
        }
    }

    /// Links of the robot.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Whether the robot has no links.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// The status of the pair of links `a`, `b` (0-based, either order).
    pub fn status(&self, a: usize, b: usize) -> PairStatus {
        self.status
            .get(a)
            .and_then(|row| row.get(b))
            .copied()
            .unwrap_or(PairStatus::Same)
    }

    /// Row `a`: bit `b > a` set for each checked pair, as
    /// [`super::LinkCapsules::new`] takes them.
    pub fn checked_rows(&self) -> &[u64] {
        &self.rows[..self.n]
    }

    /// Every pair `(a, b)`, `a < b`, with its status.
    pub fn pairs(&self) -> impl Iterator<Item = (usize, usize, PairStatus)> + '_ {
        (0..self.n).flat_map(move |a| (a + 1..self.n).map(move |b| (a, b, self.status(a, b))))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pips;

    #[test]
    fn pips_skips_its_knuckles_and_pedestal_and_checks_the_truss() {
        let robot = pips::robot::<18>().unwrap();
        let radius = [pips::LINK_RADIUS; 18];
        let allowed: heapless::Vec<(u8, u8), 32> = pips::allowed_pairs().collect();
        let t = PairTable::new(&robot, &radius, &allowed, &pips::home(), SAMPLES, 1).unwrap();
        // DH links 6 and 8 share the knuckle of link 7 (1.25 in); 16 and 18
        // the wrist (links 17, 18 are short).
        assert_eq!(t.status(5, 7), PairStatus::Knuckle);
        assert_eq!(t.status(15, 17), PairStatus::Knuckle);
        assert_eq!(t.status(8, 9), PairStatus::Adjacent);
        // The pedestal is one rigid group.
        assert_eq!(t.status(0, 4), PairStatus::Allowed);
        // The pedestal against the truss, and truss links two apart, are checked.
        assert_eq!(t.status(0, 11), PairStatus::Checked);
        assert_eq!(t.status(7, 11), PairStatus::Checked);
        assert_eq!(t.status(11, 13), PairStatus::Checked);
        // Rows and statuses agree.
        for (a, b, s) in t.pairs() {
            assert_eq!(
                t.checked_rows()[a] & (1 << b) != 0,
                s == PairStatus::Checked
            );
        }
    }

    #[test]
    fn the_table_is_reproducible_and_refuses_bad_input() {
        let robot = pips::robot::<18>().unwrap();
        let radius = [pips::LINK_RADIUS; 18];
        let a = PairTable::new(&robot, &radius, &[], &pips::home(), 500, 9).unwrap();
        let b = PairTable::new(&robot, &radius, &[], &pips::home(), 500, 9).unwrap();
        assert_eq!(a, b);
        let mut bad = radius;
        bad[3] = 0.0;
        assert_eq!(
            PairTable::new(&robot, &bad, &[], &pips::home(), 10, 1).unwrap_err(),
            CapsuleError::BadRadius { link: 3 }
        );
        assert_eq!(
            PairTable::new(&robot, &radius, &[(2, 18)], &pips::home(), 10, 1).unwrap_err(),
            CapsuleError::BadPair { link: 2 }
        );
    }
}
