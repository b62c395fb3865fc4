//! The notional Payload Inspection and Processing System (PIPS), paper Table 1.
//!
//! A pedestal (2 revolute + 3 prismatic joints), the Foster-Miller serpentine
//! truss (12 revolute joints) and a revolute wrist: 18 joints, 16 independent
//! degrees of freedom. The table, in its own units (degrees, inches):
//!
//! | i | alpha | theta | a | d | type |
//! |---|---|---|---|---|---|
//! | 1 | 90 | 90 | 0 | 22 | R |
//! | 2 | 90 | 0 | 0 | 0 | R |
//! | 3 | 0 | 0 | -2.593 | 20 | P |
//! | 4 | 0 | -45 | 0 | 1 | P |
//! | 5 | -90 | 90 | 0 | 0 | P |
//! | 6 | 90 | 0 | 20 | 0 | R |
//! | 7 | -90 | 0 | 1.25 | 0 | R |
//! | 8 | 90 | 0 | 20 | 0 | R |
//! | 9 | -90 | 0 | 16.003 | 0 | R |
//! | 10 | 90 | 0 | 16.004 | 0 | R |
//! | 11 | -90 | 0 | 1.188 | 0 | R |
//! | 12 | 90 | 0 | 16.004 | 0 | R |
//! | 13 | -90 | 0 | 12.006 | 0 | R |
//! | 14 | 90 | 0 | 12.004 | 0 | R |
//! | 15 | -90 | 0 | .813 | 0 | R |
//! | 16 | 90 | 0 | 12.004 | 0 | R |
//! | 17 | -90 | 90 | .833 | -.833 | R |
//! | 18 | 0 | 45 | 0 | 1.793 | R |
//!
//! The `theta` column of revolute joints and the `d` column of prismatic ones
//! are the "home" configuration ([`home`]). Inside the code, angles are radians
//! and lengths inches.
//!
//! The paper gives no joint limits or rates; ours (documented per joint in
//! [`TABLE`]) are: pedestal yaw +-180 deg, pedestal pitch +-90 deg, the three
//! telescopes [10, 40], [0, 30] and [-20, 20] in, truss joints +-60 deg about
//! home, wrist +-180 deg; revolute rates 0.2 rad/s, prismatic rates 2 in/s.

use crate::robot::{Joint, JointKind, Robot, RobotError};

/// Number of PIPS joints.
pub const JOINTS: usize = 18;

/// One row of Table 1 in the table's units, plus our limits (same units).
#[derive(Clone, Copy, Debug)]
pub struct TableRow {
    /// Twist, degrees.
    pub alpha_deg: f32,
    /// Angle, degrees (home value for revolute joints).
    pub theta_deg: f32,
    /// Length, inches.
    pub a_in: f32,
    /// Offset, inches (home value for prismatic joints).
    pub d_in: f32,
    /// Revolute or prismatic.
    pub kind: JointKind,
    /// Lower limit: degrees (revolute) or inches (prismatic).
    pub min: f32,
    /// Upper limit: degrees (revolute) or inches (prismatic).
    pub max: f32,
}

const fn r(alpha_deg: f32, theta_deg: f32, a_in: f32, d_in: f32, min: f32, max: f32) -> TableRow {
    TableRow {
        alpha_deg,
        theta_deg,
        a_in,
        d_in,
        kind: JointKind::Revolute,
        min,
        max,
    }
}

const fn p(alpha_deg: f32, theta_deg: f32, a_in: f32, d_in: f32, min: f32, max: f32) -> TableRow {
    TableRow {
        alpha_deg,
        theta_deg,
        a_in,
        d_in,
        kind: JointKind::Prismatic,
        min,
        max,
    }
}

/// Table 1, with our joint limits.
pub const TABLE: [TableRow; JOINTS] = [
    r(90.0, 90.0, 0.0, 22.0, -180.0, 180.0),
    r(90.0, 0.0, 0.0, 0.0, -90.0, 90.0),
    p(0.0, 0.0, -2.593, 20.0, 10.0, 40.0),
    p(0.0, -45.0, 0.0, 1.0, 0.0, 30.0),
    p(-90.0, 90.0, 0.0, 0.0, -20.0, 20.0),
    r(90.0, 0.0, 20.0, 0.0, -60.0, 60.0),
    r(-90.0, 0.0, 1.25, 0.0, -60.0, 60.0),
    r(90.0, 0.0, 20.0, 0.0, -60.0, 60.0),
    r(-90.0, 0.0, 16.003, 0.0, -60.0, 60.0),
    r(90.0, 0.0, 16.004, 0.0, -60.0, 60.0),
    r(-90.0, 0.0, 1.188, 0.0, -60.0, 60.0),
    r(90.0, 0.0, 16.004, 0.0, -60.0, 60.0),
    r(-90.0, 0.0, 12.006, 0.0, -60.0, 60.0),
    r(90.0, 0.0, 12.004, 0.0, -60.0, 60.0),
    r(-90.0, 0.0, 0.813, 0.0, -60.0, 60.0),
    r(90.0, 0.0, 12.004, 0.0, -60.0, 60.0),
    r(-90.0, 90.0, 0.833, -0.833, 30.0, 150.0),
    r(0.0, 45.0, 0.0, 1.793, -180.0, 180.0),
];

/// Revolute joint rate limit, radians per second.
pub const REVOLUTE_RATE: f32 = 0.2;
/// Prismatic joint rate limit, inches per second.
pub const PRISMATIC_RATE: f32 = 2.0;

const DEG: f32 = core::f32::consts::PI / 180.0;

/// The joints of PIPS, in radians and inches.
pub fn joints() -> [Joint; JOINTS] {
    TABLE.map(|row| match row.kind {
        JointKind::Revolute => Joint::revolute(
            row.alpha_deg * DEG,
            row.a_in,
            row.d_in,
            row.min * DEG,
            row.max * DEG,
            REVOLUTE_RATE,
        ),
        JointKind::Prismatic => Joint::prismatic(
            row.alpha_deg * DEG,
            row.a_in,
            row.theta_deg * DEG,
            row.min,
            row.max,
            PRISMATIC_RATE,
        ),
    })
}

/// The home configuration of Table 1 (radians for revolute joints, inches for prismatic).
pub fn home() -> [f32; JOINTS] {
    TABLE.map(|row| match row.kind {
        JointKind::Revolute => row.theta_deg * DEG,
        JointKind::Prismatic => row.d_in,
    })
}

/// Capsule radius of every link, inches: the chords keep at least 3 in
/// apart. The PIPS geometry: the truss tubes, the pedestal and its
/// telescopes within 1.5 in of their chords.
pub const LINK_RADIUS: f32 = 1.5;

/// Links of the pedestal (DH links 1-5: the yaw and pitch joints and the
/// three telescoping sections), one rigid group: its parts slide inside
/// one another and are never checked against each other.
pub const PEDESTAL_LINKS: usize = 5;

/// The pairs of links the PIPS geometry allows to touch (0-based): every
/// pair within the pedestal. The knuckles (the short offsets, under 3 in,
/// inside each truss knuckle and the wrist) are found from the chain
/// itself ([`crate::self_collision::pairs`]).
pub fn allowed_pairs() -> impl Iterator<Item = (u8, u8)> {
    (0..PEDESTAL_LINKS as u8).flat_map(|a| (a + 1..PEDESTAL_LINKS as u8).map(move |b| (a, b)))
}

/// PIPS as a validated robot. `N` must be at least 18.
pub fn robot<const N: usize>() -> Result<Robot<N>, RobotError> {
    Robot::new(&joints())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pips_validates_and_home_is_within_limits() {
        let pips = robot::<18>().unwrap();
        assert_eq!(pips.len(), 18);
        assert!(pips.accepts(&home()));
        assert_eq!(
            robot::<17>().unwrap_err(),
            RobotError::TooManyJoints {
                count: 18,
                capacity: 17
            }
        );
    }
}
