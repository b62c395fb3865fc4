//! Convex hull obstacles in scenario files (`shape = "convex"` with
//! `vertices`, `shape = "mesh"` with an STL or OBJ file): each loads as its
//! hull's corners (a mesh of separate parts as a solid per part: a box, a cylinder or a ball where the part is one, hulls shared by neighbouring parts beyond the hull slots; one non-convex part split into convex pieces), the checker's exact f64 distance agrees with the core's
//! GJK and with `shape = "box"`, every bad hull gets a one-line error naming
//! the file and the obstacle's line (exit 2, no output folder), and a hull
//! scenario plans end to end with the checker accepting it.

use std::path::{Path, PathBuf};

use capp_core::math::vec3;
use capp_core::obstacle::{Hull, Obstacle, PointKind};
use capp_core::Shape;
use capp_sim::geometry::{hull_polytopes, signed_distance, to_local};
use capp_sim::Problem;

mod common;

/// The planar arm with a target, before the obstacles.
fn head() -> String {
    format!(
        "name = \"hulls\"\n{}\n[target]\nposition = [0.4, 0.7, 0.0]\n",
        common::PLANAR_ARM
    )
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Loads the head and `obstacles` as `s.toml` in `dir`; the error without
/// its `file:` prefix (checked to name the file, on one line).
fn load_in(dir: &Path, obstacles: &str) -> Result<Problem, String> {
    let path = write(dir, "s.toml", &format!("{}{obstacles}", head()));
    Problem::load(&path)
        .and_then(|p| p.validate().map(|_| p))
        .map_err(|e| {
            let msg = e.to_string();
            let prefix = format!("{}:", path.display());
            assert!(msg.starts_with(&prefix), "names the file: {msg}");
            assert!(!msg.contains('\n'), "one line: {msg}");
            msg[prefix.len()..].to_string()
        })
}

fn load(obstacles: &str) -> Result<Problem, String> {
    let dir = tempfile::tempdir().unwrap();
    load_in(dir.path(), obstacles)
}

/// A box of half-extents `h` as its 8 corners, TOML.
fn box_vertices(h: [f64; 3]) -> String {
    let mut rows = Vec::new();
    for c in 0..8 {
        let v = [0, 1, 2].map(|a| if c >> a & 1 == 1 { -h[a] } else { h[a] });
        rows.push(format!("[{}, {}, {}]", v[0], v[1], v[2]));
    }
    format!("[{}]", rows.join(", "))
}

/// Reproducible uniform numbers in [-1, 1).
fn lcg(state: &mut u64) -> f64 {
    *state = state
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
}

/// The triangles of a box of half-extents `h` (12, outward).
fn box_triangles(h: [f32; 3]) -> Vec<[[f32; 3]; 3]> {
    let corner = |c: usize| [0, 1, 2].map(|a| if c >> a & 1 == 1 { h[a] } else { -h[a] });
    // Faces as corner indices (bit a set: +h along axis a), counter-clockwise.
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    quads
        .iter()
        .flat_map(|q| {
            [
                [corner(q[0]), corner(q[1]), corner(q[2])],
                [corner(q[0]), corner(q[2]), corner(q[3])],
            ]
        })
        .collect()
}

fn binary_stl(triangles: &[[[f32; 3]; 3]]) -> Vec<u8> {
    let mut b = vec![0u8; 80];
    b.extend((triangles.len() as u32).to_le_bytes());
    for t in triangles {
        b.extend([0u8; 12]);
        for v in t {
            for x in v {
                b.extend(x.to_le_bytes());
            }
        }
        b.extend([0u8; 2]);
    }
    b
}

fn ascii_stl(triangles: &[[[f32; 3]; 3]]) -> String {
    let mut s = String::from("solid part\n");
    for t in triangles {
        s.push_str("facet normal 0 0 0\nouter loop\n");
        for v in t {
            s.push_str(&format!("vertex {} {} {}\n", v[0], v[1], v[2]));
        }
        s.push_str("endloop\nendfacet\n");
    }
    s.push_str("endsolid part\n");
    s
}

fn sorted(mut v: Vec<[f32; 3]>) -> Vec<[f32; 3]> {
    v.sort_by(|a, b| a.partial_cmp(b).unwrap());
    v
}

fn corners(h: [f32; 3]) -> Vec<[f32; 3]> {
    sorted(
        (0..8)
            .map(|c| [0, 1, 2].map(|a| if c >> a & 1 == 1 { h[a] } else { -h[a] }))
            .collect(),
    )
}

/// A box of half-extents `h` with its top (`+z`) face shrunk to 0.8 of it
/// in x and y: 8 corners, 6 flat faces, not a box (a hull, not a box).
fn frustum_triangles(h: [f32; 3]) -> Vec<[[f32; 3]; 3]> {
    box_triangles(h)
        .iter()
        .map(|t| {
            t.map(|v| {
                if v[2] > 0.0 {
                    [0.8 * v[0], 0.8 * v[1], v[2]]
                } else {
                    v
                }
            })
        })
        .collect()
}

/// The signed distance of world point `x` from obstacle `k` of `p`, by the
/// checker's f64 geometry.
fn world_distance(p: &Problem, k: usize, x: [f64; 3]) -> f64 {
    let o = &p.obstacles[k];
    let r = capp_sim::geometry::rotation(o.euler_123.map(f64::from));
    let local = to_local(o.centre.map(f64::from), &r, x);
    signed_distance(&o.shape, &hull_polytopes(p), local)
}

/// The half-extents of obstacle `k` of `p`, which must be a box.
fn half_extents(p: &Problem, k: usize) -> [f32; 3] {
    match p.obstacles[k].shape {
        Shape::Cuboid { half_extents } => half_extents,
        other => panic!("obstacle {k} is not a box: {other:?}"),
    }
}

/// Whether `a` is `b` to within `1e-6` of `b`'s size, per component.
fn close(a: [f32; 3], b: [f32; 3]) -> bool {
    let size = b.iter().fold(0.0f32, |m, x| m.max(x.abs()));
    (0..3).all(|k| a[k] >= b[k] && a[k] - b[k] <= 1e-6 * size.max(1.0))
}

#[test]
fn convex_vertices_load_as_their_hulls_corners() {
    // A box's corners, one repeated, plus its centre and a face centre:
    // only the 8 corners reach the core.
    let vertices = box_vertices([0.1, 0.2, 0.3]).replace(
        "]]",
        "], [0.1, 0.2, 0.3], [0.0, 0.0, 0.0], [0.1, 0.0, 0.0]]",
    );
    let p = load(&format!(
        "\n[[obstacles]]\nname = \"part\"\nshape = \"convex\"\ncentre = [1.0, 0.5, 0.0]\neuler = [0.0, 0.0, 30.0]\nvertices = {vertices}\n"
    ))
    .unwrap();
    assert_eq!(p.obstacles[0].shape, Shape::Convex { hull: 0 });
    assert!((p.obstacles[0].euler_123[2] - 30f32.to_radians()).abs() < 1e-6);
    assert_eq!(p.hulls.len(), 1);
    assert_eq!(sorted(p.hulls[0].clone()), corners([0.1, 0.2, 0.3]));
    let scenario = p.scenario().unwrap();
    assert_eq!(scenario.hulls().len(), 1);
    assert_eq!(scenario.hulls()[0].vertices().len(), 8);
}

#[test]
fn meshes_load_binary_ascii_stl_and_obj_a_box_as_a_box_the_rest_as_hulls() {
    let dir = tempfile::tempdir().unwrap();
    let h = [0.1f32, 0.05, 0.2];
    let triangles = box_triangles(h);
    std::fs::write(dir.path().join("part.stl"), binary_stl(&triangles)).unwrap();
    std::fs::create_dir(dir.path().join("cad")).unwrap();
    // In millimetres, made metres by `scale`.
    let mm: Vec<[[f32; 3]; 3]> = triangles
        .iter()
        .map(|t| t.map(|v| v.map(|x| x * 1000.0)))
        .collect();
    write(&dir.path().join("cad"), "part_ascii.stl", &ascii_stl(&mm));
    // An OBJ: an L-shaped (non-convex) prism, enclosed by its hull.
    let mut obj = String::new();
    let l = [
        [0.0, 0.0],
        [0.2, 0.0],
        [0.2, 0.05],
        [0.05, 0.05],
        [0.05, 0.2],
        [0.0, 0.2],
    ];
    for z in [-0.05, 0.05] {
        for [x, y] in l {
            obj.push_str(&format!("v {x} {y} {z}\n"));
        }
    }
    obj.push_str("f 1 2 3\nf 1 3 4\nf 1 4 5\nf 1 5 6\nf 7 9 8\nf 7 10 9\nf 7 11 10\nf 7 12 11\n");
    write(dir.path(), "bracket.obj", &obj);
    // Eight corners, but not a box.
    let frustum = frustum_triangles(h);
    std::fs::write(dir.path().join("frustum.stl"), binary_stl(&frustum)).unwrap();
    let p = load_in(
        dir.path(),
        "\n[[obstacles]]\nname = \"binary\"\nshape = \"mesh\"\nmesh = \"part.stl\"\ncentre = [1.0, 0.5, 0.0]\n\n[[obstacles]]\nname = \"ascii\"\nshape = \"mesh\"\nmesh = \"cad/part_ascii.stl\"\nscale = 0.001\ncentre = [-1.0, 0.5, 0.0]\neuler = [10.0, 20.0, 30.0]\n\n[[obstacles]]\nname = \"bracket\"\nshape = \"mesh\"\nmesh = \"bracket.obj\"\ncentre = [0.0, -1.0, 0.0]\n\n[[obstacles]]\nname = \"frustum\"\nshape = \"mesh\"\nmesh = \"frustum.stl\"\ncentre = [0.0, 1.0, 0.0]\n",
    )
    .unwrap();
    // The boxes are boxes where the files put them (along the mesh's axes:
    // the mesh's own placement), a hair larger at most; no hull slot.
    assert!(close(half_extents(&p, 0), h), "{:?}", p.obstacles[0]);
    assert_eq!(p.obstacles[0].centre, [1.0, 0.5, 0.0]);
    assert_eq!(p.obstacles[0].euler_123, [0.0; 3]);
    assert!(close(half_extents(&p, 1), h), "{:?}", p.obstacles[1]);
    let turned = [10f64, 20.0, 30.0].map(|a| a.to_radians() as f32);
    assert_eq!(p.obstacles[1].euler_123, turned);
    assert!((0..3).all(|k| (p.obstacles[1].centre[k] - [-1.0, 0.5, 0.0][k]).abs() < 1e-6));
    assert_eq!(
        [2, 3].map(|k| p.obstacles[k].shape),
        [Shape::Convex { hull: 0 }, Shape::Convex { hull: 1 }]
    );
    // The L's inner corner (0.05, 0.05) is not on its hull: 5 of 6 per end.
    assert_eq!(p.hulls[0].len(), 10);
    assert!(!p.hulls[0].iter().any(|v| v[0] == 0.05 && v[1] == 0.05));
    let mut frustum_corners: Vec<[f32; 3]> = frustum.iter().flatten().copied().collect();
    frustum_corners.sort_by(|a, b| a.partial_cmp(b).unwrap());
    frustum_corners.dedup();
    assert_eq!(sorted(p.hulls[1].clone()), frustum_corners);
    // Nothing to say: the boxes are boxes, the frustum is convex, and the
    // L (its ends alone, an open surface) has no volume to tell how hollow
    // its hull is.
    assert!(p.notes.is_empty(), "{:?}", p.notes);
    p.scenario().unwrap();
}

/// A random convex polytope: `n` points on a squashed sphere.
fn random_hull(rng: &mut u64, n: usize) -> Vec<[f64; 3]> {
    let axes = [0.3, 0.15, 0.1];
    let points: Vec<[f64; 3]> = (0..n)
        .map(|_| {
            let d = [0, 1, 2].map(|_| lcg(rng));
            let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            [0, 1, 2].map(|a| (axes[a] * d[a] / l) as f32 as f64)
        })
        .collect();
    capp_sim::polytope::hull_vertices(&points).unwrap()
}

#[test]
fn the_checkers_hull_distance_agrees_with_the_cores_gjk() {
    let mut rng = 5u64;
    for _ in 0..10 {
        let vertices = random_hull(&mut rng, 24);
        let f32s: Vec<[f32; 3]> = vertices.iter().map(|v| v.map(|x| x as f32)).collect();
        let core = Hull::new(&f32s).unwrap();
        let checker = capp_sim::polytope::Polytope::new(&vertices);
        for _ in 0..1000 {
            let x = [0, 1, 2].map(|_| 0.6 * lcg(&mut rng));
            let mine = checker.signed_distance(x);
            let theirs = core.distance(&vec3(x.map(|c| c as f32)));
            if mine <= 0.0 {
                assert_eq!(theirs.distance, 0.0, "{x:?} inside at {mine}");
            } else {
                let d = theirs.distance as f64;
                assert!(
                    (d - mine).abs() <= 1e-4 * mine + 1e-6,
                    "{x:?}: checker {mine}, core {d}"
                );
                assert!(theirs.lower_bound as f64 <= mine + 1e-6);
            }
        }
    }
}

#[test]
fn a_box_as_eight_vertices_is_the_box() {
    // The same crate as `shape = "box"` and as a hull of its corners, turned
    // about every axis: the same checker distance, and the same core
    // clearance to f32 rounding, at random points in and around it.
    let p = load(&format!(
        "\n[[obstacles]]\nshape = \"box\"\ncentre = [1.0, 0.5, 0.2]\neuler = [20.0, -35.0, 50.0]\nhalf_extents = [0.1, 0.2, 0.3]\n\n[[obstacles]]\nshape = \"convex\"\ncentre = [1.0, 0.5, 0.2]\neuler = [20.0, -35.0, 50.0]\nvertices = {}\n",
        box_vertices([0.1, 0.2, 0.3])
    ))
    .unwrap();
    let hulls = hull_polytopes(&p);
    let scenario = p.scenario().unwrap();
    let world = scenario.world();
    let margins = [0.06f32, 0.03];
    let core: Vec<Obstacle> = (0..2)
        .map(|i| {
            Obstacle::new_in(i as u8, &p.obstacles[i], scenario.hulls(), margins, 0.5).unwrap()
        })
        .collect();
    let c = p.obstacles[0].centre.map(f64::from);
    let r = capp_sim::geometry::rotation(p.obstacles[0].euler_123.map(f64::from));
    let mut rng = 11u64;
    for _ in 0..3000 {
        let world_point = [0, 1, 2].map(|i| c[i] + 0.5 * lcg(&mut rng));
        let local = to_local(c, &r, world_point);
        let as_box = signed_distance(&p.obstacles[0].shape, &hulls, local);
        let as_hull = signed_distance(&p.obstacles[1].shape, &hulls, local);
        assert!(
            (as_box - as_hull).abs() < 1e-6,
            "{local:?}: {as_box} vs {as_hull}"
        );
        let point = vec3(world_point.map(|x| x as f32));
        for kind in [PointKind::Joint, PointKind::Link] {
            let m = margins[kind as usize] as f64;
            let [b, h] = [0, 1].map(|i| core[i].clearance_uncut(&point, kind, world.hulls) as f64);
            // rho: the box's inradius, the hull's half smallest width: 0.1
            // both. Inside, the core's hull distance is 0 (GJK gives no depth).
            if as_hull > 0.0 {
                assert!(
                    (b - h).abs() <= 1e-4 * (1.0 + b.abs()),
                    "{local:?}: {b} vs {h}"
                );
            } else {
                assert!(b <= 0.0 && h <= 0.0, "{local:?}: {b} and {h} inside");
            }
            assert_eq!(h <= 0.0, as_hull <= m, "{local:?}: {as_hull} at {h}");
        }
    }
}

#[test]
fn pictures_draw_a_hull_through_its_corners_on_its_surface() {
    use capp_sim::render::views::{hull_faces, surface};
    let p = load(&format!(
        "\n[[obstacles]]\nshape = \"convex\"\ncentre = [1.0, 0.5, 0.2]\neuler = [0.0, 0.0, 90.0]\nvertices = {}\n",
        box_vertices([0.1, 0.2, 0.3])
    ))
    .unwrap();
    let hulls = hull_polytopes(&p);
    let c = p.obstacles[0].centre.map(f64::from);
    let r = capp_sim::geometry::rotation(p.obstacles[0].euler_123.map(f64::from));
    let local = |w: [f64; 3]| to_local(c, &r, w);
    let xyz = surface(&p, 0, 24, 48);
    assert_eq!(xyz.len(), 25 * 48);
    for w in &xyz {
        let d = signed_distance(&p.obstacles[0].shape, &hulls, local(*w));
        assert!(d.abs() < 1e-9, "{w:?} at {d}");
    }
    // Every corner is drawn (the outlines are the box's own).
    for corner in corners([0.1, 0.2, 0.3]) {
        let corner = corner.map(f64::from);
        assert!(
            xyz.iter()
                .any(|w| (0..3).all(|a| (local(*w)[a] - corner[a]).abs() < 1e-6)),
            "{corner:?}"
        );
    }
    // The viewer's faces: six rectangles.
    let faces = hull_faces(&p, 0).unwrap();
    assert_eq!(faces.len(), 6);
    assert!(faces.iter().all(|f| f.len() == 4));
}

use common::capp;

#[test]
fn bad_hulls_are_refused_on_one_line_at_their_obstacle_exit_2_no_output() {
    let dir = tempfile::tempdir().unwrap();
    // 40 points on a circle's two rings: a hull of 40 corners.
    let ring: Vec<String> = (0..40)
        .map(|k| {
            let a = std::f64::consts::TAU * k as f64 / 20.0;
            let z = if k < 20 { -0.1 } else { 0.1 };
            format!("[{}, {}, {z}]", 0.1 * a.cos(), 0.1 * a.sin())
        })
        .collect();
    std::fs::write(dir.path().join("empty.obj"), "# nothing\n").unwrap();
    std::fs::write(dir.path().join("broken.stl"), [1u8, 2, 3]).unwrap();
    std::fs::write(dir.path().join("part.ply"), "ply\n").unwrap();
    let nine: String = (0..9)
        .map(|k| {
            format!(
                "\n[[obstacles]]\nshape = \"convex\"\ncentre = [{}, 1.5, 0.0]\nvertices = {}\n",
                k as f64 * 0.5 - 2.0,
                box_vertices([0.1, 0.1, 0.1])
            )
        })
        .collect();
    let one = |keys: &str| {
        format!("\n[[obstacles]]\nname = \"part\"\ncentre = [1.0, 0.5, 0.0]\n{keys}\n")
    };
    let table = head().lines().count() + 2;
    let cases: Vec<(String, usize, &str)> = vec![
        (
            one("shape = \"convex\"\nvertices = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.0, 0.1, 0.0], [0.1, 0.1, 0.0]]"),
            table,
            "obstacle: its vertices span no volume (fewer than 4 that are not coplanar)",
        ),
        (
            one("shape = \"convex\"\nvertices = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.0, 0.1, 0.0]]"),
            table,
            "span no volume",
        ),
        (
            one(&format!("shape = \"convex\"\nvertices = [{}]", ring.join(", "))),
            table,
            "obstacle: its hull has 40 vertices, more than the 32 a hull may have",
        ),
        (
            one("shape = \"mesh\"\nmesh = \"missing.stl\""),
            table,
            "obstacle: mesh \"missing.stl\" not found",
        ),
        (
            one("shape = \"mesh\"\nmesh = \"empty.obj\""),
            table,
            "obstacle: mesh \"empty.obj\" has no vertices",
        ),
        (
            one("shape = \"mesh\"\nmesh = \"broken.stl\""),
            table,
            "obstacle: mesh \"broken.stl\" is unreadable",
        ),
        (
            one("shape = \"mesh\"\nmesh = \"part.ply\""),
            table,
            "obstacle: mesh \"part.ply\" is neither .stl nor .obj",
        ),
        (
            one("shape = \"mesh\""),
            table,
            "obstacle: shape \"mesh\" needs `mesh`",
        ),
        (
            one("shape = \"mesh\"\nmesh = \"part.stl\"\nscale = -1.0"),
            table,
            "obstacle: `scale` must be positive and finite",
        ),
        (
            nine,
            table + 8 * 5,
            "obstacle: more than 8 convex or mesh obstacles",
        ),
        (
            one(&format!("shape = \"convex\"\nradius = 0.1\nvertices = {}", box_vertices([0.1; 3]))),
            table,
            "`radius` is not a key of shape \"convex\"",
        ),
        (
            one("shape = \"box\"\nhalf_extents = [0.1, 0.1, 0.1]\nmesh = \"part.stl\""),
            table,
            "`mesh` is not a key of shape \"box\"",
        ),
        (
            one("shape = \"sphere\"\nradius = 0.1\nvertices = [[0.0, 0.0, 0.0]]"),
            table,
            "`vertices` is not a key of shape \"sphere\"",
        ),
        (
            one(&format!("shape = \"convex\"\nvertices = {}\nfaces = [1, 2, 3]", box_vertices([0.1; 3]))),
            table + 5,
            "unknown field `faces`",
        ),
        (
            // Thinner than the core's smallest size: its own refusal.
            one(&format!("shape = \"convex\"\nvertices = {}", box_vertices([0.1, 0.1, 1e-7]))),
            table,
            "obstacle 1: its hull: the vertices are coplanar",
        ),
    ];
    for (i, (obstacles, line, needle)) in cases.iter().enumerate() {
        let msg = load_in(dir.path(), obstacles).expect_err(needle);
        assert!(
            msg.starts_with(&format!("{line}: ")),
            "{needle}: at line {line}? {msg}"
        );
        assert!(msg.contains(needle), "{msg} lacks {needle}");
        // The binary: exit 2, the same one line, no output folder.
        let path = write(dir.path(), "bad.toml", &format!("{}{obstacles}", head()));
        let out = dir.path().join(format!("out{i}"));
        let o = capp()
            .args(["run", path.to_str().unwrap(), "-o", out.to_str().unwrap()])
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{needle}");
        let stderr = String::from_utf8(o.stderr).unwrap();
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        assert!(stderr.contains(needle), "{stderr}");
        assert!(!stderr.contains("panicked"));
        assert!(!out.exists(), "{needle}: no output folder");
    }
}

#[test]
fn a_hull_scenario_plans_end_to_end_and_the_checker_accepts_it() {
    // A part from CAD (a binary STL) across the planar arm's way (the
    // planner escapes round it and passes it at its margin), and a wedge
    // given by its vertices: `capp run` reaches the target, the copy of the
    // scenario loads where it is, and `capp check` accepts the run.
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("part.stl"),
        binary_stl(&box_triangles([0.08, 0.08, 0.2])),
    )
    .unwrap();
    let path = write(
        dir.path(),
        "cell.toml",
        &format!(
            "{}\n[[obstacles]]\nname = \"part\"\nshape = \"mesh\"\nmesh = \"part.stl\"\ncentre = [0.65, 0.35, 0.0]\neuler = [0.0, 0.0, 20.0]\n\n[[obstacles]]\nname = \"wedge\"\nshape = \"convex\"\ncentre = [-0.2, 0.9, 0.0]\nvertices = [[-0.1, -0.1, -0.2], [0.1, -0.1, -0.2], [0.0, 0.1, -0.2], [-0.1, -0.1, 0.2], [0.1, -0.1, 0.2], [0.0, 0.1, 0.2]]\n",
            head()
        ),
    );
    let out = dir.path().join("run");
    let stdout = common::run_rendered(&path, &out);
    assert!(
        stdout.contains("obstacle 1 \"part\"") && !stdout.contains("escapes:           none"),
        "the part is in the way: {stdout}"
    );
    let copy = std::fs::read_to_string(out.join("scenario.toml")).unwrap();
    assert!(
        !copy.contains("\"part.stl\""),
        "the mesh path made absolute: {copy}"
    );
    let viewer = std::fs::read_to_string(out.join("viewer.html")).unwrap();
    assert!(
        viewer.contains("\"triangles\""),
        "the hulls drawn by their faces"
    );
    common::check_accepts(&out);
}

/// `triangles` moved by `by`.
fn moved(triangles: &[[[f32; 3]; 3]], by: [f32; 3]) -> Vec<[[f32; 3]; 3]> {
    triangles
        .iter()
        .map(|t| t.map(|v| [v[0] + by[0], v[1] + by[1], v[2] + by[2]]))
        .collect()
}

/// Half-extents of each of [`write_legs`]'s legs.
const LEG: [f32; 3] = [0.05, 0.05, 0.2];

/// `legs.stl` in `dir`: two boxes of half-extents [`LEG`] at x = -0.2 and
/// 0.2 in one binary STL (a table's two legs, say), 0.3 apart.
fn write_legs(dir: &Path) {
    let mut both = moved(&box_triangles(LEG), [-0.2, 0.0, 0.0]);
    both.extend(moved(&box_triangles(LEG), [0.2, 0.0, 0.0]));
    std::fs::write(dir.join("legs.stl"), binary_stl(&both)).unwrap();
}

#[test]
fn a_mesh_of_separate_parts_is_a_solid_per_part() {
    // Two boxes 0.3 apart in one binary STL (a table's two legs, say): a
    // box each, not one round both, so the gap between them stays free;
    // `parts = "one"` asks for the single solid round both (a box too).
    let dir = tempfile::tempdir().unwrap();
    write_legs(dir.path());
    // Two OBJ objects touching along a face (their shared corners written
    // twice, as a convex decomposition writes its pieces), neither a box: a
    // hull each.
    let mut obj = String::new();
    for (k, (name, x0)) in [("left", -0.1f32), ("right", 0.0)].into_iter().enumerate() {
        obj.push_str(&format!("o {name}\n"));
        for t in moved(
            &frustum_triangles([0.05, 0.05, 0.05]),
            [x0 + 0.05, 0.0, 0.0],
        ) {
            for v in t {
                obj.push_str(&format!("v {} {} {}\n", v[0], v[1], v[2]));
            }
        }
        // OBJ indices count from the file's first vertex.
        for f in 0..12 {
            let first = 36 * k + 3 * f + 1;
            obj.push_str(&format!("f {} {} {}\n", first, first + 1, first + 2));
        }
    }
    write(dir.path(), "pieces.obj", &obj);
    let p = load_in(
        dir.path(),
        "\n[[obstacles]]\nname = \"legs\"\nshape = \"mesh\"\nmesh = \"legs.stl\"\ncentre = [1.0, 0.5, 0.0]\neuler = [0.0, 0.0, 90.0]\n\n[[obstacles]]\nname = \"pieces\"\nshape = \"mesh\"\nmesh = \"pieces.obj\"\ncentre = [-1.0, 0.5, 0.0]\n\n[[obstacles]]\nname = \"legs as one\"\nshape = \"mesh\"\nmesh = \"legs.stl\"\nparts = \"one\"\ncentre = [0.0, -1.0, 0.0]\n",
    )
    .unwrap();
    assert_eq!(
        p.obstacle_names,
        [
            "legs part 1",
            "legs part 2",
            "pieces part 1",
            "pieces part 2",
            "legs as one"
        ]
    );
    // The legs: boxes of their size, each keeping the mesh's placement
    // (turned 90 degrees about z: the legs 0.2 either side along y).
    for (k, side) in [(0, -1.0f32), (1, 1.0)] {
        assert!(close(half_extents(&p, k), LEG), "{:?}", p.obstacles[k]);
        let want = [1.0, 0.5 + 0.2 * side, 0.0];
        assert!(
            (0..3).all(|i| (p.obstacles[k].centre[i] - want[i]).abs() < 1e-6),
            "{:?}",
            p.obstacles[k]
        );
        assert!((p.obstacles[k].euler_123[2] - 90f32.to_radians()).abs() < 1e-6);
    }
    // The pieces: a hull each, in the file's frame about the obstacle's
    // centre.
    assert_eq!(p.hulls.len(), 2);
    assert_eq!(
        [2, 3].map(|k| p.obstacles[k].shape),
        [Shape::Convex { hull: 0 }, Shape::Convex { hull: 1 }]
    );
    assert!(p.hulls.iter().all(|h| h.len() == 8));
    assert_eq!(p.obstacles[2].centre, [-1.0, 0.5, 0.0]);
    assert_eq!(p.obstacles[3].centre, [-1.0, 0.5, 0.0]);
    // One box round both legs.
    assert!(
        close(half_extents(&p, 4), [0.25, 0.05, 0.2]),
        "{:?}",
        p.obstacles[4]
    );
    // The gap between the legs (the obstacle's centre) is free of the
    // parts, 0.15 from each (the checker's geometry and the core's), and
    // inside the single box.
    let scenario = p.scenario().unwrap();
    let world = scenario.world();
    for part in 0..2 {
        let d = world_distance(&p, part, [1.0, 0.5, 0.0]);
        assert!((d - 0.15).abs() < 1e-5, "part {part}: {d}");
        let core =
            world[part].clearance_uncut(&vec3([1.0, 0.5, 0.0]), PointKind::Joint, world.hulls);
        assert!(core > 0.0, "the core sees the gap free too: {core}");
    }
    let d = world_distance(&p, 4, [0.0, -1.0, 0.0]);
    assert!(d < 0.0, "inside the one box: {d}");
}

#[test]
fn more_parts_than_hull_slots_share_hulls_that_hold_them_and_the_loader_says_so() {
    // Nine small parts along x in one STL, parts 6 and 7 the closest pair.
    let dir = tempfile::tempdir().unwrap();
    let at = |k: usize| 0.05 * k as f32 - if k == 6 { 0.02 } else { 0.0 };
    let nine = |shape: fn([f32; 3]) -> Vec<[[f32; 3]; 3]>| {
        let mut all = Vec::new();
        for k in 0..9 {
            all.extend(moved(&shape([0.01, 0.01, 0.01]), [at(k), 0.0, 0.0]));
        }
        all
    };
    let frusta = nine(frustum_triangles);
    std::fs::write(dir.path().join("frusta.stl"), binary_stl(&frusta)).unwrap();
    std::fs::write(
        dir.path().join("boxes.stl"),
        binary_stl(&nine(box_triangles)),
    )
    .unwrap();
    let mesh = |file: &str| {
        format!("\n[[obstacles]]\nname = \"nine\"\nshape = \"mesh\"\nmesh = \"{file}\"\ncentre = [1.0, 0.5, 0.0]\n")
    };
    let line = head().lines().count() + 2;
    // Nine boxes: nine box obstacles, no hull, nothing to say.
    let p = load_in(dir.path(), &mesh("boxes.stl")).unwrap();
    assert!(p.hulls.is_empty() && p.notes.is_empty(), "{:?}", p.notes);
    assert_eq!(p.obstacles.len(), 9);
    assert!((0..9).all(|k| close(half_extents(&p, k), [0.01; 3])));
    // Nine parts that are no primitive, eight hull slots: the closest two
    // share one, and the note says which.
    let p = load_in(dir.path(), &mesh("frusta.stl")).unwrap();
    assert_eq!(p.hulls.len(), 8);
    let mut names: Vec<String> = (1..=9)
        .filter(|k| *k != 6 && *k != 7)
        .map(|k| format!("nine part {k}"))
        .collect();
    names.insert(5, "nine parts 6, 7".into());
    assert_eq!(p.obstacle_names, names);
    assert_eq!(
        p.notes,
        [format!("obstacle \"nine\" (line {line}): its mesh has 9 parts that are not boxes, cylinders or balls, more than the 8 hull slots left for it (a scenario holds 8 hulls): neighbouring parts share a hull that holds them (6 + 7), which closes the gaps between them")]
    );
    // Every vertex of every part is in (or on) its obstacle.
    for (k, t) in frusta.chunks(12).enumerate() {
        let obstacle = if k < 6 { k } else { k - 1 };
        for v in t.iter().flatten() {
            let world = [
                1.0 + f64::from(v[0]),
                0.5 + f64::from(v[1]),
                f64::from(v[2]),
            ];
            let d = world_distance(&p, obstacle, world);
            assert!(d <= 1e-6, "part {} outside obstacle {obstacle}: {d}", k + 1);
        }
    }
    // A convex obstacle after it keeps its slot: the mesh gets seven.
    let p = load_in(
        dir.path(),
        &format!("{}\n[[obstacles]]\nname = \"after\"\nshape = \"convex\"\ncentre = [0.0, -1.0, 0.0]\nvertices = {}\n", mesh("frusta.stl"), box_vertices([0.1; 3])),
    )
    .unwrap();
    assert_eq!(p.hulls.len(), 8);
    assert_eq!(p.obstacle_names.last().unwrap(), "after");
    assert_eq!(p.obstacles.len(), 8);
    assert!(
        p.notes[0].contains("more than the 7 hull slots left for it"),
        "{:?}",
        p.notes
    );
    // Eight convex obstacles before it leave none: a one-line error there.
    let mut eight = String::new();
    for k in 0..8 {
        eight.push_str(&format!(
            "\n[[obstacles]]\nshape = \"convex\"\ncentre = [{}, -1.0, 0.0]\nvertices = {}\n",
            k as f32 * 0.3,
            box_vertices([0.1; 3])
        ));
    }
    let e = load_in(dir.path(), &format!("{eight}{}", mesh("frusta.stl"))).unwrap_err();
    let mesh_line = head().lines().count() + eight.lines().count() + 2;
    assert!(
        e.contains(&format!(
            "{mesh_line}: obstacle: more than 8 convex or mesh obstacles"
        )),
        "{e}"
    );
}

#[test]
fn mesh_parts_errors_are_one_line_at_the_obstacle() {
    let dir = tempfile::tempdir().unwrap();
    let mut nine = Vec::new();
    for k in 0..9 {
        nine.extend(moved(
            &box_triangles([0.01, 0.01, 0.01]),
            [0.05 * k as f32, 0.0, 0.0],
        ));
    }
    std::fs::write(dir.path().join("nine.stl"), binary_stl(&nine)).unwrap();
    let one = |keys: &str| {
        format!("\n[[obstacles]]\nname = \"part\"\nshape = \"mesh\"\nmesh = \"nine.stl\"\ncentre = [1.0, 0.5, 0.0]\n{keys}\n")
    };
    let line = head().lines().count() + 2;
    let e = load_in(dir.path(), &one("parts = \"some\"")).unwrap_err();
    assert!(
        e.contains(&format!("{line}")) && e.contains("`parts` is \"separate\" or \"one\""),
        "{e}"
    );
    // A 20-sided elliptic prism (40 corners) beside a box: that part is
    // planned round an enclosure of 32 corners, and the note names it.
    let ring = |k: usize, z: f32| {
        let a = std::f32::consts::TAU * (k % 20) as f32 / 20.0;
        [0.1 * a.cos(), 0.08 * a.sin(), z]
    };
    let mut prism = Vec::new();
    for k in 0..20 {
        let (a, b) = (ring(k, -0.1), ring(k + 1, -0.1));
        let (c, d) = (ring(k, 0.1), ring(k + 1, 0.1));
        prism.extend([
            [a, b, d],
            [a, d, c],
            [[0.0, 0.0, -0.1], b, a],
            [[0.0, 0.0, 0.1], c, d],
        ]);
    }
    prism.extend(moved(&box_triangles([0.05, 0.05, 0.05]), [0.5, 0.0, 0.0]));
    std::fs::write(dir.path().join("drum.stl"), binary_stl(&prism)).unwrap();
    let p = load_in(
        dir.path(),
        "\n[[obstacles]]\nname = \"drum\"\nshape = \"mesh\"\nmesh = \"drum.stl\"\ncentre = [1.0, 0.5, 0.0]\n",
    )
    .unwrap();
    // The drum a hull of at most 32 corners, the box beside it a box.
    assert_eq!(p.hulls.len(), 1);
    assert!(p.hulls[0].len() <= 32);
    assert_eq!(p.obstacles[0].shape, Shape::Convex { hull: 0 });
    assert!(close(half_extents(&p, 1), [0.05; 3]));
    assert_eq!(p.notes.len(), 1, "{:?}", p.notes);
    assert!(
        p.notes[0].starts_with(&format!("obstacle \"drum part 1\" (line {line}): its hull has 40 corners, more than the 32 a hull may have: planned round an enclosing hull of ")),
        "{:?}",
        p.notes
    );
    // Nine small boxes in a row as one: the box round them all.
    let p = load_in(dir.path(), &one("parts = \"one\"")).unwrap();
    assert!(p.hulls.is_empty());
    assert_eq!(p.obstacle_names, ["part"]);
    assert!(
        close(half_extents(&p, 0), [0.21, 0.01, 0.01]),
        "{:?}",
        p.obstacles[0]
    );
    let e = load(
        "\n[[obstacles]]\nshape = \"box\"\ncentre = [1.0, 0.5, 0.0]\nhalf_extents = [0.1, 0.1, 0.1]\nparts = \"one\"\n",
    )
    .unwrap_err();
    assert!(e.contains("`parts` is not a key of shape \"box\""), "{e}");
}

#[test]
fn the_arm_reaches_between_a_meshs_parts_and_not_into_one_hull_round_them() {
    // Two legs of a part from CAD, the target between them: with a hull
    // per part the arm reaches it and the checker accepts the run; one hull
    // round both legs holds the target, and the arm stops outside it.
    let dir = tempfile::tempdir().unwrap();
    write_legs(dir.path());
    let scenario = |parts: &str| {
        write(
            dir.path(),
            &format!("{parts}.toml"),
            &format!(
                "{}\n[[obstacles]]\nname = \"legs\"\nshape = \"mesh\"\nmesh = \"legs.stl\"\nparts = \"{parts}\"\ncentre = [0.4, 0.72, 0.0]\n",
                head()
            ),
        )
    };
    let out = dir.path().join("separate");
    let stdout = common::run_rendered(&scenario("separate"), &out);
    assert!(stdout.contains("\"legs part "), "{stdout}");
    common::check_accepts(&out);
    common::stops_short(&scenario("one"), &dir.path().join("one"));
}

/// A closed drum round z of `sides` sides (semi-axes `rx`, `ry`: a round
/// cylinder when equal; half-height `h`), as triangles: a curved CAD part,
/// its hull `2 sides` corners.
fn drum_triangles(sides: usize, rx: f32, ry: f32, h: f32) -> Vec<[[f32; 3]; 3]> {
    let ring = |k: usize, z: f32| {
        let a = std::f32::consts::TAU * (k % sides) as f32 / sides as f32;
        [rx * a.cos(), ry * a.sin(), z]
    };
    let mut triangles = Vec::new();
    for k in 0..sides {
        let (a, b) = (ring(k, -h), ring(k + 1, -h));
        let (c, d) = (ring(k, h), ring(k + 1, h));
        triangles.extend([
            [a, b, d],
            [a, d, c],
            [[0.0, 0.0, -h], b, a],
            [[0.0, 0.0, h], c, d],
        ]);
    }
    triangles
}

#[test]
fn a_curved_part_beyond_the_corner_budget_is_planned_round_an_enclosure_that_holds_it() {
    // An elliptic drum of 64 sides (a hull of 128 corners, four times what
    // a hull may have; not round, so no cylinder) in the planar arm's way:
    // the loader encloses it in at most 32 corners and says so, every point
    // of the part is inside the enclosure (the checker's own faces of it),
    // `capp run` prints the note and reaches the target round it, and
    // `capp check` accepts the run.
    let dir = tempfile::tempdir().unwrap();
    let triangles = drum_triangles(64, 0.1, 0.08, 0.2);
    std::fs::write(dir.path().join("drum.stl"), binary_stl(&triangles)).unwrap();
    let path = write(
        dir.path(),
        "cell.toml",
        &format!(
            "{}\n[[obstacles]]\nname = \"drum\"\nshape = \"mesh\"\nmesh = \"drum.stl\"\ncentre = [0.65, 0.35, 0.0]\neuler = [0.0, 0.0, 20.0]\n",
            head()
        ),
    );
    let p = Problem::load(&path).unwrap();
    assert_eq!(p.hulls.len(), 1);
    assert!(p.hulls[0].len() <= 32, "{}", p.hulls[0].len());
    assert!(Hull::new(&p.hulls[0]).is_ok());
    let line = head().lines().count() + 2;
    assert_eq!(p.notes.len(), 1);
    let note = &p.notes[0];
    let prefix = format!("obstacle \"drum\" (line {line}): its hull has 128 corners, more than the 32 a hull may have: planned round an enclosing hull of ");
    assert!(note.starts_with(&prefix), "{note}");
    // "... at most X m outside the part": the 16 or so planes round a
    // circle of radius 0.1 leave at most a few millimetres.
    let outside: f64 = note
        .rsplit("at most ")
        .next()
        .and_then(|t| t.split(' ').next())
        .and_then(|x| x.parse().ok())
        .unwrap();
    assert!(outside > 0.0 && outside < 0.005, "{note}");
    // Every vertex of the part is inside the enclosure, and some are on
    // its surface (it is tight): the checker's exact signed distance.
    let polytopes = hull_polytopes(&p);
    let (mut deepest, mut nearest) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in triangles.iter().flatten() {
        let d = signed_distance(&p.obstacles[0].shape, &polytopes, v.map(f64::from));
        assert!(d <= 1e-6, "a vertex of the part outside the enclosure: {d}");
        (deepest, nearest) = (deepest.min(d), nearest.max(d));
    }
    assert!(nearest > -1e-5, "the enclosure touches the part: {nearest}");
    assert!(deepest > -outside - 1e-6, "{deepest} {outside}");
    // End to end.
    let out = dir.path().join("run");
    let stdout = common::run_rendered(&path, &out);
    assert!(
        stdout.contains(&format!("note:              {prefix}")),
        "{stdout}"
    );
    assert!(stdout.contains("outcome:           reached"), "{stdout}");
    common::check_accepts(&out);
}

/// Writes `triangles` to the binary STL `file` in `dir` and a scenario
/// placing it, as obstacle `name`, at (0.65, 0.35, 0) turned 20 degrees
/// about z ([`MESH_CENTRE`], [`MESH_TURN_DEG`]); its path.
fn mesh_scenario(dir: &Path, file: &str, name: &str, triangles: &[[[f32; 3]; 3]]) -> PathBuf {
    std::fs::write(dir.join(file), binary_stl(triangles)).unwrap();
    write(
        dir,
        &format!("{name}.toml"),
        &format!(
            "{}\n[[obstacles]]\nname = \"{name}\"\nshape = \"mesh\"\nmesh = \"{file}\"\ncentre = [{:?}, {:?}, {:?}]\neuler = [0.0, 0.0, {MESH_TURN_DEG:?}]\n",
            head(),
            MESH_CENTRE[0],
            MESH_CENTRE[1],
            MESH_CENTRE[2]
        ),
    )
}

/// Where [`mesh_scenario`] places its mesh, and how far it turns it about
/// z (degrees).
const MESH_CENTRE: [f64; 3] = [0.65, 0.35, 0.0];
const MESH_TURN_DEG: f64 = 20.0;

/// Every vertex of [`mesh_scenario`]'s `triangles` in (or on) its obstacle
/// (`obstacle_of(k)` for triangle `k`), by the checker's geometry.
fn assert_vertices_inside(
    p: &Problem,
    triangles: &[[[f32; 3]; 3]],
    obstacle_of: impl Fn(usize) -> usize,
) {
    let frame = capp_sim::geometry::rotation([0.0, 0.0, MESH_TURN_DEG.to_radians()]);
    for (k, t) in triangles.iter().enumerate() {
        let obstacle = obstacle_of(k);
        for v in t {
            let v = v.map(f64::from);
            let world = [0, 1, 2]
                .map(|i| MESH_CENTRE[i] + frame[i].iter().zip(v).map(|(r, x)| r * x).sum::<f64>());
            let d = world_distance(p, obstacle, world);
            assert!(d <= 1e-6, "a vertex outside obstacle {obstacle}: {d}");
        }
    }
}

/// A closed UV capsule along z: `segments` round, `rings` latitude bands a
/// cap (its pole a vertex), radius `r`, segment `length`.
fn capsule_triangles(segments: usize, rings: usize, r: f32, length: f32) -> Vec<[[f32; 3]; 3]> {
    // Latitude `i` of `2 rings + 1` from the top pole (0) to the bottom
    // pole; the two equators (`rings`, `rings + 1`) bound the band.
    let point = |i: usize, k: usize| {
        let (polar, z) = if i <= rings {
            let polar = std::f32::consts::FRAC_PI_2 * i as f32 / rings as f32;
            (polar, length / 2.0 + r * polar.cos())
        } else {
            let polar = std::f32::consts::FRAC_PI_2 * (i - 1) as f32 / rings as f32;
            (polar, -length / 2.0 + r * polar.cos())
        };
        let t = std::f32::consts::TAU * (k % segments) as f32 / segments as f32;
        [r * polar.sin() * t.cos(), r * polar.sin() * t.sin(), z]
    };
    let mut triangles = Vec::new();
    for i in 0..=2 * rings {
        for k in 0..segments {
            let (a, b) = (point(i, k), point(i, k + 1));
            let (c, d) = (point(i + 1, k), point(i + 1, k + 1));
            if i > 0 {
                triangles.push([a, c, b]);
            }
            if i < 2 * rings {
                triangles.push([b, c, d]);
            }
        }
    }
    triangles
}

#[test]
fn a_capsule_from_cad_is_a_capsule() {
    // A UV capsule (radius 0.06, segment 0.2; 48 round, 8 bands a cap)
    // lying along the mesh's x: a capsule through its corners, no hull
    // slot, with its note; every vertex inside (the checker's geometry);
    // the arm reaches round it and `capp check` accepts the run.
    let dir = tempfile::tempdir().unwrap();
    let triangles: Vec<[[f32; 3]; 3]> = capsule_triangles(48, 8, 0.06, 0.2)
        .iter()
        .map(|t| t.map(|v| [v[2], v[1], -v[0]]))
        .collect();
    let path = mesh_scenario(dir.path(), "pill.stl", "pill", &triangles);
    let p = Problem::load(&path).unwrap();
    assert!(p.hulls.is_empty());
    let Shape::Capsule { radius, length } = p.obstacles[0].shape else {
        panic!("{:?}", p.obstacles[0]);
    };
    assert!(
        (radius - 0.06).abs() < 1e-5 && (length - 0.2).abs() < 1e-5,
        "{radius} {length}"
    );
    assert_eq!(p.notes.len(), 1, "{:?}", p.notes);
    assert!(
        p.notes[0]
            .contains("its hull's corners lie on a capsule: planned as a capsule through them"),
        "{:?}",
        p.notes
    );
    assert_vertices_inside(&p, &triangles, |_| 0);
    let out = dir.path().join("run");
    common::run_rendered(&path, &out);
    common::check_accepts(&out);
}

#[test]
fn a_round_drum_and_a_fine_ball_from_cad_are_a_cylinder_and_a_ball() {
    // A 64-sided drum (radius 0.1, turned in its file: its axis along x)
    // and a ball of 24 x 48 facets (radius 0.05) in one STL: a cylinder and
    // a ball through their corners, no hull slot, each with a note of how
    // far it reaches beyond the part's hull; every vertex inside (the
    // checker's geometry); the arm reaches round them and `capp check`
    // accepts the run.
    let dir = tempfile::tempdir().unwrap();
    let mut triangles: Vec<[[f32; 3]; 3]> = drum_triangles(64, 0.1, 0.1, 0.2)
        .iter()
        .map(|t| t.map(|v| [v[2], v[1], -v[0]]))
        .collect();
    let point = |i: usize, k: usize| {
        let polar = std::f32::consts::PI * i as f32 / 24.0;
        let t = std::f32::consts::TAU * (k % 48) as f32 / 48.0;
        [
            0.4 + 0.05 * polar.sin() * t.cos(),
            0.05 * polar.sin() * t.sin(),
            0.05 * polar.cos(),
        ]
    };
    for i in 0..24 {
        for k in 0..48 {
            let (a, b) = (point(i, k), point(i, k + 1));
            let (c, d) = (point(i + 1, k), point(i + 1, k + 1));
            triangles.extend([[a, c, d], [a, d, b]]);
        }
    }
    let path = mesh_scenario(dir.path(), "drum_ball.stl", "drum", &triangles);
    let p = Problem::load(&path).unwrap();
    assert!(p.hulls.is_empty());
    let Shape::Cylinder { radius, length } = p.obstacles[0].shape else {
        panic!("{:?}", p.obstacles[0]);
    };
    assert!(
        (radius - 0.1).abs() < 1e-5 && (length - 0.4).abs() < 1e-5,
        "{radius} {length}"
    );
    let Shape::Sphere { radius } = p.obstacles[1].shape else {
        panic!("{:?}", p.obstacles[1]);
    };
    assert!((radius - 0.05).abs() < 1e-5, "{radius}");
    let line = head().lines().count() + 2;
    assert_eq!(p.notes.len(), 2, "{:?}", p.notes);
    assert!(
        p.notes[0].starts_with(&format!("obstacle \"drum part 1\" (line {line}): its hull's corners lie on a cylinder: planned as a cylinder through them, at most 0.00012 m beyond")),
        "{:?}",
        p.notes
    );
    assert!(
        p.notes[1].contains("lie on a ball: planned as a ball"),
        "{:?}",
        p.notes
    );
    // Every vertex of both parts in (or on) its solid.
    assert_vertices_inside(&p, &triangles, |k| usize::from(k >= 256));
    let out = dir.path().join("run");
    let stdout = common::run_rendered(&path, &out);
    assert!(
        stdout.contains("its hull's corners lie on a cylinder"),
        "{stdout}"
    );
    common::check_accepts(&out);
}

/// A closed L-shaped prism 0.1 thick (one STL part) in the planar arm's
/// reach; its notch holds the point (0.4, 0.7, 0), 0.1 from each of the
/// two boxes it splits into, inside its hull.
fn l_triangles() -> Vec<[[f32; 3]; 3]> {
    let outline: [[f32; 2]; 6] = [
        [0.25, 0.8],
        [0.5, 0.8],
        [0.5, 0.55],
        [0.6, 0.55],
        [0.6, 0.9],
        [0.25, 0.9],
    ];
    let at = |k: usize, z: f32| [outline[k][0], outline[k][1], z];
    let (bottom, top) = (-0.05, 0.05);
    let mut triangles = Vec::new();
    // The ends: fans from the outer corner (the L is star-shaped from it).
    for k in [5, 0, 1, 2] {
        let j = if k == 5 { 0 } else { k + 1 };
        triangles.push([at(4, top), at(k, top), at(j, top)]);
        triangles.push([at(4, bottom), at(j, bottom), at(k, bottom)]);
    }
    for k in 0..6 {
        let j = (k + 1) % 6;
        triangles.push([at(k, bottom), at(j, bottom), at(j, top)]);
        triangles.push([at(k, bottom), at(j, top), at(k, top)]);
    }
    triangles
}

#[test]
fn a_part_of_several_that_is_not_convex_is_split_while_hull_slots_last() {
    // One STL of two parts: a frustum (a hull: no primitive) and the L. The
    // L is split into two boxes (its notch free), the frustum stays a hull,
    // the note names the part split; with no hull slot to spare (six
    // `convex` entries after it: two slots, one a part) the L stays a
    // hull, with its hollow note.
    let dir = tempfile::tempdir().unwrap();
    let mut triangles = moved(&frustum_triangles([0.05, 0.05, 0.05]), [-0.5, -0.6, 0.0]);
    triangles.extend(l_triangles());
    write(dir.path(), "two.stl", &ascii_stl(&triangles));
    let entry = "\n[[obstacles]]\nname = \"two\"\nshape = \"mesh\"\nmesh = \"two.stl\"\ncentre = [0.0, 0.0, 0.0]\n";
    let p = load_in(dir.path(), entry).unwrap();
    let frustum_first = p.obstacle_names[0] == "two part 1";
    let (frustum, l) = if frustum_first { (1, 2) } else { (2, 1) };
    let mut names = vec![
        format!("two part {frustum}"),
        format!("two part {l} piece 1"),
        format!("two part {l} piece 2"),
    ];
    names.sort();
    assert_eq!(p.obstacle_names, names);
    assert_eq!(p.hulls.len(), 1, "the frustum");
    assert_eq!(p.notes.len(), 1, "{:?}", p.notes);
    assert!(
        p.notes[0].ends_with(&format!(
            "part {l}: it is not convex: split along its own faces into 2 convex pieces (2 boxes), which hold it exactly"
        )),
        "{:?}",
        p.notes
    );
    // The notch's point is 0.1 from each box.
    for (k, name) in p.obstacle_names.iter().enumerate() {
        if name.contains("piece") {
            let d = world_distance(&p, k, [0.4, 0.7, 0.0]);
            assert!((d - 0.1).abs() < 1e-5, "{name}: {d}");
        }
    }
    // No hull slot to spare: the L is its hull, the note says how hollow.
    let mut crowded = entry.to_string();
    for k in 0..6 {
        crowded.push_str(&format!(
            "\n[[obstacles]]\nshape = \"convex\"\ncentre = [{}, -2.0, 0.0]\nvertices = {}\n",
            0.3 * k as f64,
            box_vertices([0.05, 0.05, 0.05])
        ));
    }
    let p = load_in(dir.path(), &crowded).unwrap();
    assert_eq!(p.hulls.len(), 8);
    assert_eq!(p.obstacle_names[..2], ["two part 1", "two part 2"]);
    assert!(
        p.notes
            .iter()
            .any(|n| n.contains("it is not convex: planned round its convex hull")),
        "{:?}",
        p.notes
    );
}

#[test]
fn the_arm_reaches_into_the_notch_of_an_l_that_its_hull_would_fill() {
    // One closed STL part, an L whose notch holds the target (inside the
    // L's hull, 0.1 from the L): split along its own faces into two boxes,
    // the arm reaches the target and the checker accepts the run; as one
    // hull round it (`parts = "one"`) the target is inside, and the arm
    // stops short.
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "l.stl", &ascii_stl(&l_triangles()));
    let scenario = |parts: &str| {
        write(
            dir.path(),
            &format!("{parts}.toml"),
            &format!(
                "{}\n[[obstacles]]\nname = \"l\"\nshape = \"mesh\"\nmesh = \"l.stl\"\nparts = \"{parts}\"\ncentre = [0.0, 0.0, 0.0]\n",
                head()
            ),
        )
    };
    let p = Problem::load(&scenario("separate")).unwrap();
    assert_eq!(p.obstacle_names, ["l piece 1", "l piece 2"]);
    assert!(p.hulls.is_empty());
    assert_eq!(
        p.notes,
        [format!(
            "obstacle \"l\" (line {}): it is not convex: split along its own faces into 2 convex pieces (2 boxes), which hold it exactly",
            head().lines().count() + 2
        )]
    );
    // The target is 0.1 from each box.
    for k in 0..2 {
        let d = world_distance(&p, k, [0.4, 0.7, 0.0]);
        assert!((d - 0.1).abs() < 1e-5, "piece {k}: {d}");
    }
    let out = dir.path().join("separate");
    common::run_rendered(&scenario("separate"), &out);
    common::check_accepts(&out);
    let one = Problem::load(&scenario("one")).unwrap();
    assert_eq!(one.hulls.len(), 1);
    assert!(world_distance(&one, 0, [0.4, 0.7, 0.0]) < 0.0);
    common::stops_short(&scenario("one"), &dir.path().join("one"));
}

#[test]
fn a_split_part_takes_no_more_obstacles_than_the_scenario_has_left() {
    // The shipped tote (five boxes when split) after 62 balls: two
    // obstacles are left, so it is split into two at most, and the
    // scenario loads with the core's 64.
    let dir = tempfile::tempdir().unwrap();
    let tote = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/meshes/tote.stl");
    let mut obstacles = String::new();
    for k in 0..62 {
        obstacles.push_str(&format!(
            "\n[[obstacles]]\nshape = \"sphere\"\nradius = 0.01\ncentre = [{}, -2.0, 0.0]\n",
            0.05 * k as f32
        ));
    }
    obstacles.push_str(&format!(
        "\n[[obstacles]]\nname = \"tote\"\nshape = \"mesh\"\nmesh = \"{}\"\ncentre = [2.0, 2.0, 0.0]\n",
        tote.display()
    ));
    let p = load_in(dir.path(), &obstacles).unwrap();
    assert_eq!(p.obstacles.len(), 64, "{:?}", p.obstacle_names);
    assert_eq!(p.obstacle_names[62..], ["tote piece 1", "tote piece 2"]);
    p.scenario().unwrap();
    // Alone, five.
    let p = load_in(
        dir.path(),
        &obstacles[obstacles.rfind("\n[[obstacles]]").unwrap()..],
    )
    .unwrap();
    assert_eq!(p.obstacles.len(), 5);
}
