//! The obstacle potential's exact joint-space gradient (eq. 20) against central
//! finite differences of an independent f64 potential (eqs. 25-26).

mod common;

use capp_core::avoidance::{potential_gradient, AvoidanceSettings};
use capp_core::kinematics::{forward_kinematics, Frames};
use capp_core::obstacle::Obstacle;
use capp_core::{pips, Robot, SuperEllipsoid};
use common::*;

fn random_obstacle(rng: &mut Rng, around: V3, spread: f64) -> SuperEllipsoid {
    let k = [1.0, 2.0, 3.0, 2.5, 4.0, 8.0, 1.5];
    SuperEllipsoid {
        centre: [0, 1, 2].map(|i| (around[i] + rng.uniform(-spread, spread)) as f32),
        semi_axes: [0, 1, 2].map(|_| rng.uniform(0.3, 2.0) as f32),
        exponents: [0, 1, 2].map(|_| k[rng.below(k.len())] as f32),
        euler_123: [0, 1, 2].map(|_| rng.uniform(-3.0, 3.0) as f32),
    }
}

#[test]
fn potential_gradient_matches_central_differences() {
    let mut rng = Rng(11);
    let mut frames = Frames::<32>::default();
    let mut mu = [0.0f32; 32];
    let mut checked = 0;
    let chains = vec![
        pips::joints().to_vec(),
        random_chain(&mut rng, 5),
        random_chain(&mut rng, 14),
        random_chain(&mut rng, 32),
    ];
    for joints in chains {
        let robot = Robot::<32>::new(&joints).unwrap();
        let n = joints.len();
        for interior in [1u8, 3] {
            let settings = AvoidanceSettings {
                joint_margin: 0.5,
                link_margin: 0.25,
                points_per_link: interior,
                influence_distance: 1.0e4, // every pair: P is smooth
                engage_clearance: 1.0,
                advance_fraction: 0.5,
            };
            let mut trials = 0;
            while trials < 15 {
                let q = random_config(&mut rng, &joints);
                let q64: Vec<f64> = q.iter().map(|&x| x as f64).collect();
                let chain = fk64(&joints, &q64);
                // Obstacles near random points of the arm, so gradients are large.
                let obstacles: Vec<SuperEllipsoid> = (0..4)
                    .map(|_| {
                        let o = chain.origins[1 + rng.below(n)];
                        random_obstacle(&mut rng, o, 4.0)
                    })
                    .collect();
                let margins = (0.5, 0.25);
                // Only configurations with every point clear, and not grazing (FD needs room).
                if min_clearance64(&joints, &q64, &obstacles, margins, interior as usize) < 0.05 {
                    continue;
                }
                trials += 1;
                let validated: Vec<Obstacle> = obstacles
                    .iter()
                    .enumerate()
                    .map(|(i, s)| {
                        Obstacle::new(i as u8, s, settings.margins(), settings.influence_distance)
                            .unwrap()
                    })
                    .collect();
                forward_kinematics(&robot, &q, &mut frames);
                let mut distance = [0.0f32; 32];
                let field = potential_gradient(
                    &robot,
                    &frames,
                    capp_core::World::of(&validated),
                    &settings,
                    &mut mu[..n],
                    &mut distance[..n],
                    None,
                );
                assert!(field.clear);
                let p64 = potential64(&joints, &q64, &obstacles, margins, interior as usize);
                assert!(
                    ((field.potential as f64) - p64).abs() <= 1e-3 * p64.abs().max(1.0),
                    "P {} vs {p64}",
                    field.potential
                );
                let h = 1e-6;
                let fd: Vec<f64> = (0..n)
                    .map(|j| {
                        let mut plus = q64.clone();
                        let mut minus = q64.clone();
                        plus[j] += h;
                        minus[j] -= h;
                        (potential64(&joints, &plus, &obstacles, margins, interior as usize)
                            - potential64(&joints, &minus, &obstacles, margins, interior as usize))
                            / (2.0 * h)
                    })
                    .collect();
                let size = fd.iter().map(|x| x * x).sum::<f64>().sqrt().max(1e-3);
                for j in 0..n {
                    assert!(
                        (mu[j] as f64 - fd[j]).abs() <= 2e-3 * size,
                        "n={n} interior={interior} joint {j}: exact {} vs finite difference {} (|mu| {size})",
                        mu[j],
                        fd[j]
                    );
                }
                checked += 1;
            }
        }
    }
    assert_eq!(checked, 4 * 2 * 15);
}

/// The nearest pair's half-space (what conservative advancement lets a link
/// slide along) holds all of its obstacle inflated by either margin, whichever
/// of the two is the larger: points sampled inside the obstacle, by the
/// independent f64 `C`, are never on its free side.
#[test]
fn the_nearest_half_space_holds_the_obstacle_under_either_margin() {
    let mut rng = Rng(23);
    let mut frames = Frames::<32>::default();
    let mut mu = [0.0f32; 32];
    let mut distance = [0.0f32; 32];
    for (joint_margin, link_margin) in [(0.5, 0.25), (0.25, 0.75)] {
        let settings = AvoidanceSettings {
            joint_margin,
            link_margin,
            points_per_link: 2,
            influence_distance: 3.0,
            engage_clearance: 1.0,
            advance_fraction: 0.5,
        };
        let (mut planes, mut inside) = (0, 0);
        while planes < 150 {
            let n = 3 + rng.below(10);
            let joints = random_chain(&mut rng, n);
            let robot = Robot::<32>::new(&joints).unwrap();
            let q = random_config(&mut rng, &joints);
            let q64: Vec<f64> = q.iter().map(|&x| x as f64).collect();
            let near = fk64(&joints, &q64).origins[1 + rng.below(n)];
            let s = random_obstacle(&mut rng, near, 2.0);
            let obstacle =
                Obstacle::new(0, &s, settings.margins(), settings.influence_distance).unwrap();
            forward_kinematics(&robot, &q, &mut frames);
            let field = potential_gradient(
                &robot,
                &frames,
                capp_core::World::of(core::slice::from_ref(&obstacle)),
                &settings,
                &mut mu[..n],
                &mut distance[..n],
                None,
            );
            let Some(plane) = field.nearest.filter(|_| field.clear) else {
                continue;
            };
            planes += 1;
            let normal = plane.normal.map(f64::from);
            let reach = s
                .semi_axes
                .iter()
                .map(|&a| (a as f64 + 0.75).powi(2))
                .sum::<f64>();
            let reach = reach.sqrt();
            for _ in 0..400 {
                let y = [0, 1, 2].map(|i| s.centre[i] as f64 + rng.uniform(-reach, reach));
                for margin in [joint_margin, link_margin] {
                    if c64(&s, margin as f64, y) <= 1.0 {
                        inside += 1;
                        let free = dot(normal, y) - plane.offset as f64;
                        assert!(
                            free <= 1e-4 * (1.0 + reach),
                            "margins {joint_margin}/{link_margin}: a point inside (margin {margin}) is {free} on the free side of {plane:?}"
                        );
                    }
                }
            }
        }
        assert!(inside > 2_000, "{inside} points inside");
    }
}
