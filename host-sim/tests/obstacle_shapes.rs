//! CAD primitives in scenario files (`shape = "sphere"`, `"box"`,
//! `"capsule"`, `"cylinder"`): each loads as the shape it names, the
//! checker's f64 clearance agrees with the core's `f32` one, margins are
//! true distances in both, and every bad shape gets a one-line error naming
//! the file and the obstacle's line.

use std::path::PathBuf;

use capp_core::math::vec3;
use capp_core::obstacle::{Obstacle, PointKind};
use capp_core::Shape;
use capp_sim::geometry::signed_distance;
use capp_sim::Problem;

mod common;

/// The planar arm with a target, before the obstacles.
fn head() -> String {
    format!(
        "name = \"shapes\"\n{}\n[target]\nposition = [0.4, 0.7, 0.0]\n",
        common::PLANAR_ARM
    )
}

fn write(dir: &tempfile::TempDir, text: &str) -> PathBuf {
    let p = dir.path().join("s.toml");
    std::fs::write(&p, text).unwrap();
    p
}

fn load(obstacles: &str) -> Result<Problem, String> {
    let dir = tempfile::tempdir().unwrap();
    let path = write(&dir, &format!("{}{obstacles}", head()));
    Problem::load(&path).map_err(|e| {
        let msg = e.to_string();
        let prefix = format!("{}:", path.display());
        assert!(msg.starts_with(&prefix), "names the file: {msg}");
        assert!(!msg.contains('\n'), "one line: {msg}");
        msg[prefix.len()..].to_string()
    })
}

const SHAPES: &str = r#"
[[obstacles]]
name = "ball"
shape = "sphere"
centre = [0.9, 0.4, 0.0]
radius = 0.1

[[obstacles]]
name = "crate"
shape = "box"
centre = [-0.6, 0.5, 0.0]
half_extents = [0.1, 0.2, 0.3]
euler = [0.0, 0.0, 30.0]

[[obstacles]]
name = "pipe"
shape = "cylinder"
centre = [0.0, -0.8, 0.0]
radius = 0.05
length = 1.0
euler = [90.0, 0.0, 0.0]

[[obstacles]]
name = "rail"
shape = "capsule"
centre = [-0.8, -0.4, 0.2]
radius = 0.04
length = 0.6

[[obstacles]]
name = "post"
centre = [0.5, -0.5, 0.0]
semi_axes = [0.08, 0.08, 0.5]
exponents = [2.0, 2.0, 8.0]
"#;

#[test]
fn every_shape_loads_as_the_shape_it_names() {
    let p = load(SHAPES).unwrap();
    let shapes: Vec<Shape> = p.obstacles.iter().map(|o| o.shape).collect();
    assert_eq!(
        shapes,
        vec![
            Shape::Sphere { radius: 0.1 },
            Shape::Cuboid {
                half_extents: [0.1, 0.2, 0.3]
            },
            Shape::Cylinder {
                radius: 0.05,
                length: 1.0
            },
            Shape::Capsule {
                radius: 0.04,
                length: 0.6
            },
            Shape::SuperEllipsoid {
                semi_axes: [0.08, 0.08, 0.5],
                exponents: [2.0, 2.0, 8.0]
            },
        ]
    );
    // Euler angles in the file's unit, converted to radians.
    assert!((p.obstacles[1].euler_123[2] - 30f32.to_radians()).abs() < 1e-6);
    // Each becomes a planner obstacle.
    p.scenario().expect("a valid scenario");
}

/// Reproducible uniform numbers in [-1, 1).
fn lcg(state: &mut u64) -> f64 {
    *state = state
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
}

#[test]
fn the_checker_and_the_core_agree_and_margins_are_distances() {
    // The checker's f64 geometry (written apart from the core's) and the
    // core's f32 pair code give the same clearance, and a point is inside
    // the inflated shape exactly when its distance to the surface is below
    // the margin.
    let p = load(SHAPES).unwrap();
    let margins = [0.06f32, 0.03];
    let mut rng = 3u64;
    for (index, solid) in p.obstacles.iter().enumerate() {
        if matches!(solid.shape, Shape::SuperEllipsoid { .. }) {
            continue;
        }
        let core = Obstacle::new(index as u8, solid, margins, 0.5).unwrap();
        let c = solid.centre.map(f64::from);
        let r = capp_sim::geometry::rotation(solid.euler_123.map(f64::from));
        for _ in 0..2000 {
            let world = [0, 1, 2].map(|i| c[i] + 0.6 * lcg(&mut rng));
            let d = [0, 1, 2].map(|i| world[i] - c[i]);
            let local = [0, 1, 2].map(|i| r[0][i] * d[0] + r[1][i] * d[1] + r[2][i] * d[2]);
            let distance = signed_distance(&solid.shape, &[], local);
            let point = vec3(world.map(|x| x as f32));
            for kind in [PointKind::Joint, PointKind::Link] {
                let m = margins[kind as usize] as f64;
                let uncut = core.clearance_uncut(&point, kind, &[]) as f64;
                assert_eq!(
                    uncut <= 0.0,
                    distance <= m,
                    "{solid:?} at {world:?}: distance {distance}, C - 1 {uncut}"
                );
                // The same C - 1 to f32 rounding.
                let rho = match solid.shape {
                    Shape::Sphere { radius } | Shape::Capsule { radius, .. } => radius as f64,
                    Shape::Cuboid { half_extents } => half_extents[0] as f64,
                    Shape::Cylinder { radius, .. } => radius as f64,
                    Shape::SuperEllipsoid { .. } | Shape::Convex { .. } => unreachable!(),
                };
                let expected = ((distance + rho) / (m + rho)).powi(2) - 1.0;
                assert!(
                    (uncut - expected).abs() <= 1e-4 * (1.0 + expected.abs()),
                    "{solid:?} at {world:?}: {uncut} against {expected}"
                );
                if let Some(contact) = core.contact(&point, kind, &[]) {
                    let gap = (distance - m).max(0.0);
                    assert!((contact.distance_sq as f64).sqrt() - gap <= 1e-5);
                }
            }
        }
    }
}

#[test]
fn bad_shapes_get_one_line_errors_at_their_line() {
    let one = |keys: &str| format!("\n[[obstacles]]\nname = \"thing\"\n{keys}\n");
    for (keys, needle) in [
        (
            "shape = \"sphere\"\ncentre = [1.0, 0.0, 0.0]\nradius = 0.0",
            "every radius, length and half-extent must be between",
        ),
        (
            "shape = \"box\"\ncentre = [1.0, 0.0, 0.0]\nhalf_extents = [0.1, -0.2, 0.3]",
            "every radius, length and half-extent must be between",
        ),
        (
            "shape = \"cylinder\"\ncentre = [1.0, 0.0, 0.0]\nradius = nan\nlength = 1.0",
            "size is not finite",
        ),
        (
            "shape = \"capsule\"\ncentre = [1.0, 0.0, 0.0]\nradius = 0.1",
            "shape \"capsule\" needs `length`",
        ),
        (
            "shape = \"sphere\"\ncentre = [1.0, 0.0, 0.0]\nradius = 0.1\nsemi_axes = [1.0, 1.0, 1.0]",
            "`semi_axes` is not a key of shape \"sphere\"",
        ),
        (
            "shape = \"box\"\ncentre = [1.0, 0.0, 0.0]\nhalf_extents = [0.1, 0.1, 0.1]\nradius = 0.1",
            "`radius` is not a key of shape \"box\"",
        ),
        (
            "shape = \"torus\"\ncentre = [1.0, 0.0, 0.0]\nradius = 0.1",
            "unknown shape \"torus\"",
        ),
        (
            "shape = \"sphere\"\ncentre = [1.0, 0.0, 0.0]\nradius = 0.1\nwidth = 2.0",
            "unknown field `width`",
        ),
    ] {
        let msg = load(&one(keys)).expect_err(keys);
        // The obstacle's table starts on the line after the head; an
        // unknown key is reported at its own line.
        let table = head().lines().count() + 2;
        let line = if needle.starts_with("unknown field") {
            table + keys.lines().count() + 1
        } else {
            table
        };
        assert!(
            msg.starts_with(&format!("{line}: ")),
            "{keys}: at line {line}? {msg}"
        );
        assert!(msg.contains(needle), "{keys}: {msg} lacks {needle}");
    }
}

#[test]
fn pictures_draw_each_primitive_as_it_is() {
    // Every vertex of the drawn surface is on the shape's surface, and a
    // box's eight corners are among them (sharp edges, not rounded).
    use capp_sim::render::views::primitive_surface;
    let p = load(SHAPES).unwrap();
    for solid in &p.obstacles {
        if matches!(solid.shape, Shape::SuperEllipsoid { .. }) {
            continue;
        }
        let vertices = primitive_surface(&solid.shape, 24, 48);
        assert_eq!(vertices.len(), 25 * 48);
        for v in &vertices {
            let d = signed_distance(&solid.shape, &[], *v);
            assert!(d.abs() < 1e-6, "{:?}: {v:?} at {d}", solid.shape);
        }
        if let Shape::Cuboid { half_extents: h } = solid.shape {
            for corner in 0..8 {
                let c = [0, 1, 2].map(|a| {
                    let s = if corner >> a & 1 == 1 { -1.0 } else { 1.0 };
                    s * h[a] as f64
                });
                assert!(
                    vertices
                        .iter()
                        .any(|v| (0..3).all(|a| (v[a] - c[a]).abs() < 1e-9)),
                    "corner {c:?} drawn"
                );
            }
        }
    }
    // And the world-frame surface the pictures and the viewer use is the
    // same outline moved to the obstacle's pose: its centroid is the centre.
    for o in 0..p.obstacles.len() {
        let xyz = capp_sim::render::views::surface(&p, o, 24, 48);
        let mean = [0, 1, 2].map(|a| xyz.iter().map(|v| v[a]).sum::<f64>() / xyz.len() as f64);
        let c = p.obstacles[o].centre.map(f64::from);
        // Symmetric outlines: the mean of the vertices is the centre.
        assert!(
            (0..3).all(|a| (mean[a] - c[a]).abs() < 1e-3),
            "{:?}: {mean:?} against {c:?}",
            p.obstacles[o].shape
        );
    }
}
