//! Where each URDF joint's pivot sits on its axis, so that each link's chord
//! runs through the link's body.
//!
//! The core checks each link as a capsule round its chord, from its joint's
//! pivot to the next joint's (or to the end effector). A URDF puts a joint's
//! frame wherever its author liked along the joint's axis, often where two
//! axes cross, so a chord can miss the body it stands for: the Panda's first
//! and second joints share a point 0.333 m above the base, leaving the
//! column between them (a cylinder 0.28 m long) with a chord of zero length,
//! enclosed only by a ball of radius 0.42 m.
//!
//! A revolute joint's frame can slide along its own axis without changing
//! any motion: the rotation about `a` leaves the translation `lambda a`
//! where it is, so with `T'_k = T_k Trans(lambda_k a_k)`,
//!
//! ```text
//! O'_k = Trans(-lambda_{k-1} a_{k-1}) O_k Trans(lambda_k a_k)
//!   (t'_k = t_k - lambda_{k-1} a_{k-1} + lambda_k R_k a_k)
//! tool' = Trans(-lambda_{n-1} a_{n-1}) tool
//! body points of joint k:  p' = p - lambda_k a_k
//! ```
//!
//! every body, the end effector and every axis stay where they were in
//! every configuration; only the pivots (the chords' ends) move along the
//! axes. [`slides`] chooses the `lambda` that make the capsules small: the
//! sum of the enclosing capsules' volumes (each link's radius round its
//! chord holding every collision capsule of its body) is least, by a few
//! sweeps of one joint at a time over a grid along its axis. A prismatic
//! joint stays where it is (its chord's length changes with the joint).
//! [`slid`] applies them to a chain.

use capp_urdf::{Body, Capsule, Chain, JointKind};
use nalgebra::{Point3, Translation3, Vector3};

/// Sweeps over the joints.
const SWEEPS: usize = 4;
/// Grid points per search (each way from the current value, and again on a
/// grid 1 / `GRID` as fine about the best).
const GRID: usize = 200;

/// The smallest radius of a capsule round the segment `p`-`e` that holds
/// every capsule of `body` (metres); `None` if the body has no collision
/// geometry. The distance to a segment is convex, so a capsule's farthest
/// point from the chord is at one of its ends.
pub fn enclosing_radius(body: &Body, p: &Point3<f64>, e: &Point3<f64>) -> Option<f64> {
    let chord = Capsule {
        a: *p,
        b: *e,
        radius: 0.0,
    };
    body.capsules
        .iter()
        .map(|c| {
            chord
                .segment_distance(&c.a)
                .max(chord.segment_distance(&c.b))
                + c.radius
        })
        .reduce(f64::max)
}

/// Link `k`'s chord in its body's URDF frame (joint `k`'s), for slides
/// `lambda` (none given: 0): from joint `k`'s slid pivot to joint
/// `k + 1`'s, or to the tip.
pub fn chord(chain: &Chain, lambda: &[f64], k: usize) -> (Point3<f64>, Point3<f64>) {
    let slide = |j: usize| lambda.get(j).copied().unwrap_or(0.0);
    let axis = |j: usize| chain.joints[j].axis.into_inner();
    let p = Point3::from(axis(k) * slide(k));
    let e = match chain.joints.get(k + 1) {
        Some(next) => Point3::from(
            next.origin.translation.vector + next.origin.rotation * (axis(k + 1) * slide(k + 1)),
        ),
        None => Point3::from(chain.tool.translation.vector),
    };
    (p, e)
}

/// The volume of link `k`'s enclosing capsule (0 for a body without
/// geometry), cubic metres.
fn link_volume(chain: &Chain, lambda: &[f64], k: usize) -> f64 {
    let (p, e) = chord(chain, lambda, k);
    chain
        .bodies
        .get(k + 1)
        .and_then(|body| enclosing_radius(body, &p, &e))
        .map_or(0.0, |r| {
            Capsule {
                a: p,
                b: e,
                radius: r,
            }
            .volume()
        })
}

/// The slides `lambda_k` (metres along each joint's unit axis) that make
/// the links' enclosing capsules least in total volume; 0 for prismatic
/// joints and where nothing is gained.
pub fn slides(chain: &Chain) -> Vec<f64> {
    let n = chain.joints.len();
    let mut lambda = vec![0.0; n];
    // As far as the chain and its bodies reach: no useful pivot is farther.
    let span = chain
        .joints
        .iter()
        .map(|j| j.origin.translation.vector.norm())
        .sum::<f64>()
        + chain.tool.translation.vector.norm()
        + chain
            .bodies
            .iter()
            .flat_map(|b| &b.capsules)
            .map(|c| c.a.coords.norm().max(c.b.coords.norm()) + c.radius)
            .fold(0.0, f64::max);
    if !(span.is_finite() && span > 0.0) {
        return lambda;
    }
    let around = |lambda: &[f64], k: usize| {
        link_volume(chain, lambda, k)
            + k.checked_sub(1)
                .map_or(0.0, |j| link_volume(chain, lambda, j))
    };
    for _ in 0..SWEEPS {
        for k in 0..n {
            if chain.joints[k].kind == JointKind::Prismatic {
                continue;
            }
            let mut best = lambda[k];
            let mut best_volume = around(&lambda, k);
            let mut step = span / GRID as f64;
            let mut centre = 0.0;
            for _ in 0..2 {
                for i in 0..=2 * GRID {
                    let candidate = centre + (i as f64 - GRID as f64) * step;
                    lambda[k] = candidate;
                    let v = around(&lambda, k);
                    // Strictly smaller only: no slide where nothing is gained.
                    if v < best_volume * (1.0 - 1e-9) {
                        best = candidate;
                        best_volume = v;
                    }
                }
                centre = best;
                step /= GRID as f64;
            }
            lambda[k] = best;
        }
    }
    lambda
}

/// `chain` with joint `k`'s pivot slid `lambda[k]` metres along its axis
/// (module docs): origins, tool and body capsules moved so that nothing
/// else moves.
pub fn slid(chain: &Chain, lambda: &[f64]) -> Chain {
    let mut out = chain.clone();
    let shift = |k: usize| -> Vector3<f64> {
        chain.joints[k].axis.into_inner() * lambda.get(k).copied().unwrap_or(0.0)
    };
    for k in 0..chain.joints.len() {
        let origin = &chain.joints[k].origin;
        let mut t = origin.translation.vector + origin.rotation * shift(k);
        if k > 0 {
            t -= shift(k - 1);
        }
        out.joints[k].origin.translation = Translation3::from(t);
        if let Some(body) = out.bodies.get_mut(k + 1) {
            for c in &mut body.capsules {
                c.a -= shift(k);
                c.b -= shift(k);
            }
        }
    }
    if let Some(last) = chain.joints.len().checked_sub(1) {
        out.tool.translation = Translation3::from(chain.tool.translation.vector - shift(last));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn load(urdf: &str, tip: &str) -> Chain {
        let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
        let options = capp_urdf::LoadOptions {
            tip_link: Some(tip.into()),
            packages: vec![("example-robot-data".into(), root.clone())],
            capsules_per_mesh: capp_urdf::CapsuleCount::Auto,
            ..Default::default()
        };
        capp_urdf::load(&root.join(urdf), &options).unwrap()
    }

    fn chains() -> Vec<Chain> {
        vec![
            load(
                "robots/panda_description/urdf/panda_collision.urdf",
                "panda_link8",
            ),
            load("robots/ur_description/urdf/ur5_robot.urdf", "tool0"),
        ]
    }

    /// Sliding moves no body, no axis and not the tip, in 200 random
    /// configurations of both robots: every capsule end and every joint's
    /// axis line and the tip frame are where the URDF's own forward
    /// kinematics put them; the pivots moved along their axes by `lambda`.
    #[test]
    fn sliding_the_pivots_moves_nothing_else() {
        for chain in chains() {
            let lambda = slides(&chain);
            assert!(lambda.iter().any(|l| l.abs() > 1e-3), "{lambda:?}");
            let moved = slid(&chain, &lambda);
            let mut rng = 12345u64;
            let mut uniform = || {
                rng = rng
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (rng >> 11) as f64 / (1u64 << 53) as f64
            };
            for _ in 0..100 {
                let q: Vec<f64> = chain
                    .joints
                    .iter()
                    .map(|j| {
                        let (lo, hi) = (j.lower.max(-3.0), j.upper.min(3.0));
                        lo + (hi - lo) * uniform()
                    })
                    .collect();
                let before = chain.forward(&q).unwrap();
                let after = moved.forward(&q).unwrap();
                for (k, (b, a)) in before.iter().zip(&after).enumerate() {
                    let axis = chain.joints.get(k).map(|j| j.axis.into_inner());
                    if let Some(axis) = axis {
                        // The frame slid along its axis by lambda.
                        let expect = b * Point3::from(axis * lambda[k]);
                        assert!((a.translation.vector - expect.coords).norm() < 1e-12);
                        assert!(a.rotation.angle_to(&b.rotation) < 1e-12);
                        // Its body's capsules are where they were.
                        for (cb, ca) in chain.bodies[k + 1]
                            .capsules
                            .iter()
                            .zip(&moved.bodies[k + 1].capsules)
                        {
                            assert!((b * cb.a - a * ca.a).norm() < 1e-12);
                            assert!((b * cb.b - a * ca.b).norm() < 1e-12);
                        }
                    } else {
                        // The tip.
                        assert!((a.translation.vector - b.translation.vector).norm() < 1e-12);
                        assert!(a.rotation.angle_to(&b.rotation) < 1e-12);
                    }
                }
            }
        }
    }

    /// The slid chords hold their bodies in smaller capsules: the Panda's
    /// column (link 1) and its fifth link, whose chords had no length, at
    /// least halve their radius, and both robots' total volume shrinks.
    #[test]
    fn slid_chords_run_through_the_bodies() {
        let radii = |chain: &Chain, lambda: &[f64]| -> Vec<f64> {
            (0..chain.joints.len())
                .map(|k| {
                    let (p, e) = chord(chain, lambda, k);
                    enclosing_radius(&chain.bodies[k + 1], &p, &e).unwrap()
                })
                .collect()
        };
        for (chain, halved) in chains().into_iter().zip([&[0usize, 4][..], &[]]) {
            let lambda = slides(&chain);
            let zero = vec![0.0; lambda.len()];
            let (before, after) = (radii(&chain, &zero), radii(&chain, &lambda));
            let volume = |l: &[f64]| (0..l.len()).map(|k| link_volume(&chain, l, k)).sum::<f64>();
            println!(
                "{}: radii {before:.3?} -> {after:.3?}, volume {:.4} -> {:.4} m^3",
                chain.robot_name,
                volume(&zero),
                volume(&lambda)
            );
            assert!(volume(&lambda) < 0.9 * volume(&zero));
            for &k in halved {
                assert!(after[k] <= 0.5 * before[k], "{before:?} -> {after:?}");
            }
        }
    }
}
