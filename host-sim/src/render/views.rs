//! Three orthographic views of a run (top XY, front XZ, side YZ) with ticks
//! in the scenario's length unit, the obstacles' silhouettes and names, the
//! end-effector path and the arm at a few instants.
//!
//! Silhouettes are convex hulls of projected surface samples: super-ellipsoids
//! with exponents >= 1 are convex, so the hull is exact up to sampling.

use super::canvas::{Anchor, Canvas, Clip, Rgb, Shape, P2};
use super::chart::{diamond, legend_marker, nice_step, tick_label, Marker};
use super::font;
use crate::escapes::{Kind, Stretch};
use crate::geometry::forward;
use crate::polytope::Polytope;
use crate::problem::Problem;
use crate::trajectory::Trajectory;

/// Start and end colours of the arm snapshots.
pub const START: Rgb = [40, 90, 220];
/// See [`START`].
pub const END: Rgb = [220, 50, 40];
/// Waypoints and target.
pub const TARGET: Rgb = [20, 150, 60];
/// Obstacle fill.
pub const OBSTACLE: Rgb = [120, 130, 140];
const PATH: Rgb = [30, 30, 30];
/// The end-effector path while detouring round an obstacle.
pub const DETOUR: Rgb = [0, 150, 160];
/// ... while walking away from a dead end.
pub const WALK: Rgb = [235, 135, 0];
/// ... while returning to the best configuration (dashed).
pub const RETURN: Rgb = [150, 90, 40];
/// ... while walking a path a search found.
pub const SEARCHED: Rgb = [140, 60, 170];

/// The colour of an escape stretch in every picture.
pub fn escape_color(kind: Kind) -> Rgb {
    match kind {
        Kind::Detour => DETOUR,
        Kind::Walk => WALK,
        Kind::Return => RETURN,
        Kind::Search | Kind::Path => SEARCHED,
    }
}

/// The legend entries for the escape kinds in `stretches`, in a fixed order.
pub fn escape_legend(stretches: &[Stretch]) -> Vec<(String, Rgb, Marker)> {
    let mut items = Vec::new();
    for (kind, name) in [
        (Kind::Detour, "detour round an obstacle"),
        (Kind::Walk, "walk from a dead end"),
        (Kind::Path, "path found by a search"),
        (Kind::Return, "return to the best configuration"),
    ] {
        if stretches.iter().any(|s| s.kind == kind) {
            let marker = if kind == Kind::Return {
                Marker::Dashed
            } else {
                Marker::Line
            };
            items.push((name.to_string(), escape_color(kind), marker));
        }
    }
    items
}
const INK: Rgb = [30, 30, 30];
const MUTED: Rgb = [90, 90, 90];

/// `a + (b - a) t`, per channel.
pub fn lerp(a: Rgb, b: Rgb, t: f64) -> Rgb {
    [0, 1, 2].map(|i| (a[i] as f64 + (b[i] as f64 - a[i] as f64) * t).round() as u8)
}

/// `R = Rz Ry Rx` of the obstacle's Euler angles.
fn rotation(e: [f64; 3]) -> [[f64; 3]; 3] {
    let (sx, cx) = e[0].sin_cos();
    let (sy, cy) = e[1].sin_cos();
    let (sz, cz) = e[2].sin_cos();
    [
        [cz * cy, cz * sy * sx - sz * cx, cz * sy * cx + sz * sx],
        [sz * cy, sz * sy * sx + cz * cx, sz * sy * cx - cz * sx],
        [-sy, cy * sx, cy * cx],
    ]
}

/// Surface samples of obstacle `o` in world coordinates: `lat + 1` rings of
/// `lon` points from the +z pole to the -z pole (of the obstacle's frame).
/// A super-ellipsoid is sampled along rays from its centre; a primitive is
/// drawn as it is ([`primitive_surface`]: flat faces, sharp edges); a
/// convex hull along rays from its vertices' mean, each corner on the grid
/// ([`hull_surface`]).
pub fn surface(problem: &Problem, o: usize, lat: usize, lon: usize) -> Vec<[f64; 3]> {
    let s = &problem.obstacles[o];
    let local = match s.shape {
        capp_core::Shape::SuperEllipsoid {
            semi_axes,
            exponents,
        } => ray_cast(semi_axes.map(f64::from), exponents.map(f64::from), lat, lon),
        capp_core::Shape::Convex { hull } => match problem.hulls.get(hull as usize) {
            Some(h) => hull_surface(&hull_polytope(h), lat, lon),
            None => Vec::new(),
        },
        shape => primitive_surface(&shape, lat, lon),
    };
    to_world(s, local)
}

/// Local points of obstacle `s` in world coordinates.
fn to_world(s: &capp_core::Solid, local: Vec<[f64; 3]>) -> Vec<[f64; 3]> {
    let r = rotation(s.euler_123.map(f64::from));
    let c = s.centre.map(f64::from);
    local
        .into_iter()
        .map(|x| [0, 1, 2].map(|a| c[a] + r[a][0] * x[0] + r[a][1] * x[1] + r[a][2] * x[2]))
        .collect()
}

/// A hull's vertices (`f32`, its frame) with its faces enumerated.
fn hull_polytope(vertices: &[[f32; 3]]) -> Polytope {
    Polytope::new(
        &vertices
            .iter()
            .map(|v| v.map(f64::from))
            .collect::<Vec<_>>(),
    )
}

/// The faces of convex obstacle `o` in world coordinates, each a polygon
/// (counter-clockwise seen from outside); `None` for other shapes.
pub fn hull_faces(problem: &Problem, o: usize) -> Option<Vec<Vec<[f64; 3]>>> {
    let s = &problem.obstacles[o];
    let capp_core::Shape::Convex { hull } = s.shape else {
        return None;
    };
    let p = hull_polytope(problem.hulls.get(hull as usize)?);
    Some(
        p.faces()
            .iter()
            .map(|f| to_world(s, f.polygon.iter().map(|&i| p.vertices()[i]).collect()))
            .collect(),
    )
}

/// A hull's surface in its frame as [`surface`]'s grid: along each ray from
/// the vertices' mean, where it leaves the hull (the nearest face plane
/// ahead); then each corner replaces the grid point nearest its direction,
/// so outlines drawn from the samples ([`silhouettes`]) are the hull's own.
pub fn hull_surface(p: &Polytope, lat: usize, lon: usize) -> Vec<[f64; 3]> {
    let v = p.vertices();
    if v.is_empty() {
        return Vec::new();
    }
    let m = [0, 1, 2].map(|a| v.iter().map(|q| q[a]).sum::<f64>() / v.len() as f64);
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let mut rays = Vec::with_capacity((lat + 1) * lon);
    for i in 0..=lat {
        let phi = std::f64::consts::PI * i as f64 / lat as f64;
        for j in 0..lon {
            let th = std::f64::consts::TAU * j as f64 / lon as f64;
            rays.push([phi.sin() * th.cos(), phi.sin() * th.sin(), phi.cos()]);
        }
    }
    let mut out: Vec<[f64; 3]> = rays
        .iter()
        .map(|&d| {
            let t = p
                .faces()
                .iter()
                .filter(|f| dot(f.normal, d) > 0.0)
                .map(|f| (f.offset - dot(f.normal, m)) / dot(f.normal, d))
                .fold(f64::INFINITY, f64::min);
            [0, 1, 2].map(|a| m[a] + t * d[a])
        })
        .collect();
    for c in p.corners() {
        let d = [0, 1, 2].map(|a| v[c][a] - m[a]);
        let nearest = (0..rays.len())
            .max_by(|&a, &b| dot(rays[a], d).total_cmp(&dot(rays[b], d)))
            .unwrap_or(0);
        out[nearest] = v[c];
    }
    out
}

/// A super-ellipsoid's surface in its frame: along each ray of a latitude
/// and longitude grid, the largest `t` with `C(t d) <= 1`, by bisection.
fn ray_cast(axes: [f64; 3], k: [f64; 3], lat: usize, lon: usize) -> Vec<[f64; 3]> {
    let mut out = Vec::with_capacity((lat + 1) * lon);
    for i in 0..=lat {
        let phi = std::f64::consts::PI * i as f64 / lat as f64;
        for j in 0..lon {
            let th = std::f64::consts::TAU * j as f64 / lon as f64;
            let d = [phi.sin() * th.cos(), phi.sin() * th.sin(), phi.cos()];
            // Largest t with C(t d) <= 1, by bisection (C grows with t).
            let f = |t: f64| -> f64 { (0..3).map(|a| (t * d[a] / axes[a]).abs().powf(k[a])).sum() };
            let (mut lo, mut hi) = (0.0, axes.iter().cloned().fold(0.0, f64::max) * 2.0);
            for _ in 0..40 {
                let mid = 0.5 * (lo + hi);
                if f(mid) <= 1.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            out.push(d.map(|v| v * lo));
        }
    }
    out
}

/// A primitive's surface in its frame, as the same `lat + 1` rings of `lon`
/// points: each ring is the cross-section outline (a circle, or for a box
/// its rectangle, with a vertex on every corner when `lon` is a multiple of
/// 4) scaled by `s` at height `z`. Ring 0 is the top's centre, ring 1 the
/// top's edge, the side runs down to ring `lat - 1`, the bottom's edge, and
/// ring `lat` is the bottom's centre; a capsule's ends are hemispheres.
pub fn primitive_surface(shape: &capp_core::Shape, lat: usize, lon: usize) -> Vec<[f64; 3]> {
    use capp_core::Shape as S;
    use std::f64::consts::{FRAC_PI_2, PI, TAU};
    let lat = lat.max(4);
    let outline = |j: usize| -> [f64; 2] {
        match *shape {
            S::Cuboid { half_extents } => {
                // Around the rectangle by arc length, corners at j = 0,
                // lon/4, lon/2, 3 lon/4.
                let [hx, hy] = [half_extents[0] as f64, half_extents[1] as f64];
                let t = 4.0 * j as f64 / lon as f64;
                let (side, f) = (t.floor() as usize % 4, t - t.floor());
                let corners = [[hx, hy], [-hx, hy], [-hx, -hy], [hx, -hy]];
                let (p, q) = (corners[side], corners[(side + 1) % 4]);
                [p[0] + (q[0] - p[0]) * f, p[1] + (q[1] - p[1]) * f]
            }
            _ => {
                let th = TAU * j as f64 / lon as f64;
                [th.cos(), th.sin()]
            }
        }
    };
    // (scale of the outline, height) per ring.
    let rings: Vec<(f64, f64)> = match *shape {
        S::Sphere { radius } => (0..=lat)
            .map(|i| {
                let phi = PI * i as f64 / lat as f64;
                (radius as f64 * phi.sin(), radius as f64 * phi.cos())
            })
            .collect(),
        S::Capsule { radius, length } => {
            let (r, h) = (radius as f64, 0.5 * length as f64);
            // The top hemisphere on the first rings, the side's middle on
            // ring lat / 2, the bottom mirroring the top.
            let half = lat / 2;
            let ring = |i: usize| -> (f64, f64) {
                if i < half {
                    let phi = FRAC_PI_2 * i as f64 / (half - 1) as f64;
                    (r * phi.sin(), h + r * phi.cos())
                } else {
                    (r, 0.0)
                }
            };
            (0..=lat)
                .map(|i| {
                    if i <= half {
                        ring(i)
                    } else {
                        let (s, z) = ring(lat - i);
                        (s, -z)
                    }
                })
                .collect()
        }
        S::Cuboid { half_extents } => flat_ended(1.0, half_extents[2] as f64, lat),
        S::Cylinder { radius, length } => flat_ended(radius as f64, 0.5 * length as f64, lat),
        // Not primitives: [`ray_cast`] and [`hull_surface`] draw them.
        S::SuperEllipsoid { .. } | S::Convex { .. } => Vec::new(),
    };
    rings
        .iter()
        .flat_map(|&(scale, z)| {
            (0..lon).map(move |j| {
                let [x, y] = outline(j);
                [x * scale, y * scale, z]
            })
        })
        .collect()
}

/// Rings of a flat-ended prism of outline scale `scale` and half height `h`:
/// the top's centre, its edge, the side, the bottom's edge and centre.
fn flat_ended(scale: f64, h: f64, lat: usize) -> Vec<(f64, f64)> {
    (0..=lat)
        .map(|i| match i {
            0 => (0.0, h),
            i if i == lat => (0.0, -h),
            i => (scale, h - 2.0 * h * (i - 1) as f64 / (lat - 2) as f64),
        })
        .collect()
}

/// Convex hull (monotone chain), counter-clockwise in a y-up frame.
fn hull(mut pts: Vec<P2>) -> Vec<P2> {
    pts.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    pts.dedup();
    if pts.len() < 3 {
        return pts;
    }
    let cross = |o: P2, a: P2, b: P2| (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0);
    let mut lower: Vec<P2> = Vec::new();
    for &p in &pts {
        while lower.len() >= 2 && cross(lower[lower.len() - 2], lower[lower.len() - 1], p) <= 0.0 {
            lower.pop();
        }
        lower.push(p);
    }
    let mut upper: Vec<P2> = Vec::new();
    for &p in pts.iter().rev() {
        while upper.len() >= 2 && cross(upper[upper.len() - 2], upper[upper.len() - 1], p) <= 0.0 {
            upper.pop();
        }
        upper.push(p);
    }
    lower.pop();
    upper.pop();
    lower.extend(upper);
    lower
}

/// `poly` clipped to the rectangle `c` (Sutherland-Hodgman).
fn clip_polygon(poly: &[P2], c: Clip) -> Vec<P2> {
    let mut out = poly.to_vec();
    let edges: [(usize, f64, bool); 4] = [
        (0, c.0, true),
        (0, c.2, false),
        (1, c.1, true),
        (1, c.3, false),
    ];
    for (axis, at, keep_above) in edges {
        let input = std::mem::take(&mut out);
        let coord = |p: &P2| if axis == 0 { p.0 } else { p.1 };
        let inside = |p: &P2| (coord(p) >= at) == keep_above;
        for i in 0..input.len() {
            let (a, b) = (input[i], input[(i + 1) % input.len()]);
            if inside(&b) {
                if !inside(&a) {
                    out.push(cut(a, b, coord(&a), coord(&b), at));
                }
                out.push(b);
            } else if inside(&a) {
                out.push(cut(a, b, coord(&a), coord(&b), at));
            }
        }
    }
    out
}

fn cut(a: P2, b: P2, ca: f64, cb: f64, at: f64) -> P2 {
    let t = (at - ca) / (cb - ca);
    (a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t)
}

fn area(poly: &[P2]) -> f64 {
    let n = poly.len();
    (0..n)
        .map(|i| poly[i].0 * poly[(i + 1) % n].1 - poly[(i + 1) % n].0 * poly[i].1)
        .sum::<f64>()
        .abs()
        / 2.0
}

fn contains(poly: &[P2], p: P2) -> bool {
    let mut inside = false;
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        if (a.1 > p.1) != (b.1 > p.1) && p.0 < a.0 + (p.1 - a.1) / (b.1 - a.1) * (b.0 - a.0) {
            inside = !inside;
        }
    }
    inside
}

/// One orthographic panel: world axes `(u, v)` mapped into a pixel square.
#[derive(Clone, Copy, Debug)]
pub struct Panel {
    /// World axes shown right and up.
    pub axes: (usize, usize),
    /// Top left corner, pixels.
    pub origin: P2,
    /// Side, pixels.
    pub size: f64,
    /// World coordinates at the bottom left corner.
    pub lo: (f64, f64),
    /// Pixels per length unit.
    pub scale: f64,
}

impl Panel {
    /// Pixel position of a world point.
    pub fn map(&self, p: &[f64; 3]) -> P2 {
        let (u, v) = (p[self.axes.0], p[self.axes.1]);
        (
            self.origin.0 + (u - self.lo.0) * self.scale,
            self.origin.1 + self.size - (v - self.lo.1) * self.scale,
        )
    }

    /// The panel's pixel rectangle.
    pub fn clip(&self) -> Clip {
        (
            self.origin.0,
            self.origin.1,
            self.origin.0 + self.size,
            self.origin.1 + self.size,
        )
    }
}

/// The drawing of a run: canvas, panels and every row's frame origins.
pub struct ArmScene {
    /// The page (without the moving arm when drawn with no snapshots).
    pub canvas: Canvas,
    /// Top, front, side.
    pub panels: [Panel; 3],
    /// Frame origins `o_0..o_n` of every row.
    pub origins: Vec<Vec<[f64; 3]>>,
}

/// Centre and side of a cube holding the arm over the whole run and the
/// waypoints, with 15 % room on each side.
pub fn bounds(problem: &Problem, origins: &[Vec<[f64; 3]>]) -> ([f64; 3], f64) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    let waypoints = problem.waypoints.iter().map(|w| w.position.map(f64::from));
    for p in origins.iter().flatten().copied().chain(waypoints) {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    if !lo[0].is_finite() {
        return ([0.0; 3], 1.0);
    }
    let span = (0..3).map(|a| hi[a] - lo[a]).fold(0.0, f64::max).max(1e-6);
    ([0, 1, 2].map(|a| 0.5 * (lo[a] + hi[a])), 1.3 * span)
}

/// Frame origins of every row.
pub fn origins(problem: &Problem, t: &Trajectory) -> Vec<Vec<[f64; 3]>> {
    t.rows.iter().map(|r| forward(problem, &r.q).0).collect()
}

/// `count` rows spread evenly in a mix of end-effector path length and row
/// number, so neither a fast swing nor a long slow creep takes every frame.
/// Increasing, first and last row included, no repeats.
pub fn frames(origins: &[Vec<[f64; 3]>], count: usize) -> Vec<usize> {
    let n = origins.len();
    if n == 0 {
        return Vec::new();
    }
    let mut length = vec![0.0];
    for w in origins.windows(2) {
        let step = match (w[0].last(), w[1].last()) {
            (Some(a), Some(b)) => (0..3).map(|i| (a[i] - b[i]).powi(2)).sum::<f64>().sqrt(),
            _ => 0.0,
        };
        length.push(length.last().copied().unwrap_or(0.0) + step);
    }
    let total = length.last().copied().unwrap_or(0.0);
    let mix = |k: usize| {
        let rows = if n > 1 {
            k as f64 / (n - 1) as f64
        } else {
            1.0
        };
        if total > 0.0 {
            0.5 * length[k] / total + 0.5 * rows
        } else {
            rows
        }
    };
    let count = count.clamp(1, n);
    let mut out: Vec<usize> = Vec::with_capacity(count);
    let mut k = 0;
    for f in 0..count {
        let goal = if count > 1 {
            f as f64 / (count - 1) as f64
        } else {
            1.0
        };
        while k + 1 < n && mix(k) < goal - 1e-12 {
            k += 1;
        }
        if out.last() != Some(&k) {
            out.push(k);
        }
    }
    if out.last() != Some(&(n - 1)) {
        out.push(n - 1);
    }
    out
}

/// Left margin of the first panel, pixels.
pub const LEFT: f64 = 58.0;
const GAP: f64 = 72.0;
/// Top of the panels, pixels.
pub const TOP: f64 = 74.0;
const BOTTOM: f64 = 80.0;

/// The three views, each `panel` pixels square; the arm at `snapshots`
/// instants (none: the page for an animation to draw the arm on).
pub fn arm_scene(problem: &Problem, t: &Trajectory, panel: f64, snapshots: usize) -> ArmScene {
    let origins = origins(problem, t);
    let (centre, side) = bounds(problem, &origins);
    let panels = panels(centre, side, panel);
    let escapes = t.escapes();
    let legend_rows = if escapes.is_empty() { 0.0 } else { 20.0 };
    let mut canvas = page(panel, legend_rows);
    let unit = &problem.length_unit;
    let headline = if snapshots > 0 {
        format!(
            "{}: {} steps, the arm at {snapshots} instants",
            problem.name,
            t.rows.len().saturating_sub(1)
        )
    } else {
        format!("{}: {} steps", problem.name, t.rows.len().saturating_sub(1))
    };
    canvas.push(Shape::text((LEFT, 26.0), 16.0, headline).colored(INK));
    let unit_name = unit_name(unit);
    let subtitle = if snapshots > 0 {
        format!("orthographic views, lengths in {unit_name}; grey: obstacles (true surfaces, not inflated by the clearance margins)")
    } else {
        format!("orthographic views, lengths in {unit_name}")
    };
    canvas.push(Shape::text((LEFT, 46.0), 11.5, subtitle).colored(MUTED));
    let surfaces = surfaces(problem);
    let instants = if snapshots > 0 {
        instants(&origins, snapshots)
    } else {
        Vec::new()
    };
    for (pi, p) in panels.iter().enumerate() {
        panel_frame(&mut canvas, p, TITLES[pi], side, unit);
        let hulls = silhouettes(&mut canvas, p, &surfaces);
        // End-effector path, at most ~2000 points.
        let stride = (origins.len() / 2000).max(1);
        let path: Vec<P2> = origins
            .iter()
            .step_by(stride)
            .chain(origins.last())
            .filter_map(|o| o.last().map(|e| p.map(e)))
            .collect();
        let avoid: Vec<P2> = path
            .iter()
            .copied()
            .chain(
                instants
                    .iter()
                    .flat_map(|&k| origins[k].iter().map(|q| p.map(q))),
            )
            .collect();
        canvas.push(Shape::line(path, PATH, 1.0).clipped(p.clip()));
        for (s, &k) in instants.iter().enumerate() {
            let frac = s as f64 / (snapshots.max(2) - 1) as f64;
            canvas.push(
                Shape::line(
                    origins[k].iter().map(|q| p.map(q)).collect(),
                    lerp(START, END, frac),
                    2.0,
                )
                .clipped(p.clip()),
            );
        }
        // The escape stretches over the path and the arm, thicker, and where each started.
        for e in &escapes {
            let stretch: Vec<P2> = origins[e.first..=e.end(origins.len())]
                .iter()
                .filter_map(|o| o.last().map(|q| p.map(q)))
                .collect();
            let line = Shape::line(stretch, escape_color(e.kind), 2.0).clipped(p.clip());
            canvas.push(if e.kind == Kind::Return {
                line.dashed()
            } else {
                line
            });
        }
        for e in escapes.iter().filter(|e| e.kind != Kind::Return) {
            if let Some(q) = origins[e.first].last() {
                let at = p.map(q);
                let (x0, y0, x1, y1) = p.clip();
                if (x0..=x1).contains(&at.0) && (y0..=y1).contains(&at.1) {
                    diamond(&mut canvas, at, escape_color(e.kind));
                }
            }
        }
        for w in &problem.waypoints {
            canvas.push(Shape::Disc {
                centre: p.map(&w.position.map(f64::from)),
                radius: 4.0,
                color: TARGET,
            });
        }
        obstacle_names(&mut canvas, problem, p, &hulls, &avoid);
        border(&mut canvas, p);
    }
    legend(&mut canvas, (LEFT, TOP + panel + 60.0), snapshots, &escapes);
    ArmScene {
        canvas,
        panels,
        origins,
    }
}

/// Titles of the three panels.
pub const TITLES: [&str; 3] = ["top (from +z)", "front (from −y)", "side (from +x)"];

/// The three panels (top, front, side), each `panel` pixels square,
/// showing a cube of `side` length units round `centre`.
pub fn panels(centre: [f64; 3], side: f64, panel: f64) -> [Panel; 3] {
    let axes = [(0, 1), (0, 2), (1, 2)];
    [0, 1, 2].map(|i| Panel {
        axes: axes[i],
        origin: (LEFT + i as f64 * (panel + GAP), TOP),
        size: panel,
        lo: (
            centre[axes[i].0] - side / 2.0,
            centre[axes[i].1] - side / 2.0,
        ),
        scale: panel / side,
    })
}

/// An empty page for three `panel`-pixel panels, their titles, ticks and a
/// legend with `legend_rows` pixels of extra rows.
pub fn page(panel: f64, legend_rows: f64) -> Canvas {
    let width = (LEFT + 3.0 * panel + 2.0 * GAP + 24.0) as u32;
    let height = (TOP + panel + BOTTOM + legend_rows) as u32;
    Canvas::new(width, height)
}

/// The length unit in words, for subtitles.
pub fn unit_name(unit: &str) -> &str {
    match unit {
        "in" => "inches",
        "m" => "metres",
        other => other,
    }
}

/// Surface samples of every obstacle ([`surface`], 24 x 48).
pub fn surfaces(problem: &Problem) -> Vec<Vec<[f64; 3]>> {
    (0..problem.obstacles.len())
        .map(|o| surface(problem, o, 24, 48))
        .collect()
}

/// Panel `p`'s grid and ticks every round step of its `side` (length
/// units), axis names in `unit`, and its title.
pub fn panel_frame(canvas: &mut Canvas, p: &Panel, title: &str, side: f64, unit: &str) {
    let names = ["x", "y", "z"];
    let step = nice_step(side, 5.0);
    let (x0, y0, x1, y1) = p.clip();
    for horizontal in [true, false] {
        let lo = if horizontal { p.lo.0 } else { p.lo.1 };
        let mut k = (lo / step).ceil() as i64;
        while (k as f64) * step <= lo + side + 1e-9 {
            let v = k as f64 * step;
            let px = (v - lo) * p.scale;
            let label = tick_label(v, step);
            if horizontal {
                let x = x0 + px;
                canvas.push(Shape::line(vec![(x, y0), (x, y1)], [236, 236, 236], 1.0));
                canvas.push(Shape::line(vec![(x, y1), (x, y1 + 4.0)], INK, 1.0));
                canvas.push(
                    Shape::text((x, y1 + 16.0), 10.5, label)
                        .anchored(Anchor::Middle)
                        .colored(INK),
                );
            } else {
                let y = y1 - px;
                canvas.push(Shape::line(vec![(x0, y), (x1, y)], [236, 236, 236], 1.0));
                canvas.push(Shape::line(vec![(x0 - 4.0, y), (x0, y)], INK, 1.0));
                canvas.push(
                    Shape::text((x0 - 7.0, y + 4.0), 10.5, label)
                        .anchored(Anchor::End)
                        .colored(INK),
                );
            }
            k += 1;
        }
    }
    canvas.push(
        Shape::text(
            ((x0 + x1) / 2.0, y1 + 33.0),
            11.5,
            format!("{} [{unit}]", names[p.axes.0]),
        )
        .anchored(Anchor::Middle)
        .colored(MUTED),
    );
    canvas.push(
        Shape::text(
            (x0 - 7.0, y0 - 9.0),
            11.5,
            format!("{} [{unit}]", names[p.axes.1]),
        )
        .anchored(Anchor::End)
        .colored(MUTED),
    );
    canvas.push(Shape::text((x0, y0 - 9.0), 13.0, title).colored(INK));
}

/// The obstacles' silhouettes in panel `p`, drawn; returned for their names.
pub fn silhouettes(canvas: &mut Canvas, p: &Panel, surfaces: &[Vec<[f64; 3]>]) -> Vec<Vec<P2>> {
    let hulls: Vec<Vec<P2>> = surfaces
        .iter()
        .map(|s| hull(s.iter().map(|q| p.map(q)).collect()))
        .collect();
    for h in &hulls {
        canvas.push(Shape::Polygon {
            points: h.clone(),
            fill: OBSTACLE,
            opacity: 0.35,
            clip: Some(p.clip()),
        });
    }
    hulls
}

/// Each obstacle's name inside its silhouette (`hulls`), away from the
/// pixels in `avoid` and from each other.
pub fn obstacle_names(
    canvas: &mut Canvas,
    problem: &Problem,
    p: &Panel,
    hulls: &[Vec<P2>],
    avoid: &[P2],
) {
    let mut placed: Vec<P2> = Vec::new();
    for (o, h) in hulls.iter().enumerate() {
        let name = problem
            .obstacle_names
            .get(o)
            .filter(|n| !n.is_empty())
            .cloned()
            .unwrap_or_else(|| format!("obstacle {}", o + 1));
        if let Some(at) = label_spot(h, p.clip(), &name, avoid, &placed) {
            placed.push(at);
            canvas.push(
                Shape::text(at, 11.0, name)
                    .anchored(Anchor::Middle)
                    .colored([45, 50, 60]),
            );
        }
    }
}

/// Panel `p`'s border.
pub fn border(canvas: &mut Canvas, p: &Panel) {
    let (x0, y0, x1, y1) = p.clip();
    canvas.push(Shape::line(
        vec![(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)],
        [130, 130, 130],
        1.0,
    ));
}

/// The outline of a capsule (the segment `a`-`b`, `radius` length units)
/// as panel `p` projects it: the hull of a circle round each end.
pub fn capsule_outline(p: &Panel, a: &[f64; 3], b: &[f64; 3], radius: f64) -> Vec<P2> {
    let r = radius * p.scale;
    let ring = |c: P2| {
        (0..32).map(move |i| {
            let th = std::f64::consts::TAU * i as f64 / 32.0;
            (c.0 + r * th.cos(), c.1 + r * th.sin())
        })
    };
    hull(ring(p.map(a)).chain(ring(p.map(b))).collect())
}

/// Where to write an obstacle's name inside its silhouette: the centre of a
/// small one if the arm is not there; else the spot (on a grid) farthest
/// from the arm and from names already placed. `None` if it is
/// not in the panel.
fn label_spot(hull: &[P2], panel: Clip, name: &str, avoid: &[P2], placed: &[P2]) -> Option<P2> {
    let inset = (panel.0 + 6.0, panel.1 + 14.0, panel.2 - 6.0, panel.3 - 6.0);
    let visible = clip_polygon(hull, inset);
    let a = area(&visible);
    if visible.len() < 3 || a < 300.0 {
        return None;
    }
    let half = font::width(name, 11.0) / 2.0;
    let fits = |p: P2| p.0 - half >= inset.0 && p.0 + half <= inset.2;
    let panel_area = (inset.2 - inset.0) * (inset.3 - inset.1);
    let n = visible.len() as f64;
    let centroid = (
        visible.iter().map(|p| p.0).sum::<f64>() / n,
        visible.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let clearance = |p: P2| {
        avoid
            .iter()
            .chain(placed)
            .map(|q| (q.0 - p.0).hypot(2.0 * (q.1 - p.1)))
            .fold(f64::INFINITY, f64::min)
    };
    if a < 0.4 * panel_area
        && contains(&visible, centroid)
        && fits(centroid)
        && clearance(centroid) > half + 8.0
    {
        return Some((centroid.0, centroid.1 + 4.0));
    }
    let (x0, y0, x1, y1) = visible
        .iter()
        .fold((f64::MAX, f64::MAX, f64::MIN, f64::MIN), |b, p| {
            (b.0.min(p.0), b.1.min(p.1), b.2.max(p.0), b.3.max(p.1))
        });
    let mut best: Option<(f64, P2)> = None;
    for i in 0..=6 {
        for j in 0..=6 {
            let p = (
                x0 + (x1 - x0) * (0.08 + 0.84 * i as f64 / 6.0),
                y0 + (y1 - y0) * (0.08 + 0.84 * j as f64 / 6.0),
            );
            if !contains(&visible, p) || !fits(p) {
                continue;
            }
            let c = clearance(p);
            if best.is_none_or(|(b, _)| c > b) {
                best = Some((c, p));
            }
        }
    }
    best.map(|(_, p)| (p.0, p.1 + 4.0))
}

/// The legend row under the panels.
fn legend(canvas: &mut Canvas, at: P2, snapshots: usize, escapes: &[Stretch]) {
    let (mut x, y) = at;
    let size = 11.5;
    let arm = if snapshots > 0 {
        format!("arm at {snapshots} instants, blue: start → red: end")
    } else {
        "arm now".to_string()
    };
    // A three-colour swatch for the arm.
    for (k, c) in [START, lerp(START, END, 0.5), END].into_iter().enumerate() {
        let x0 = x + 6.0 * k as f64;
        let c = if snapshots > 0 { c } else { END };
        canvas.push(Shape::line(vec![(x0, y), (x0 + 6.0, y)], c, 3.0));
    }
    canvas.push(Shape::text((x + 24.0, y + 4.0), size, arm.clone()).colored(INK));
    x += 24.0 + font::width(&arm, size) + 28.0;
    for (name, color, marker) in [
        ("end-effector path", PATH, Marker::Line),
        ("waypoints and target", TARGET, Marker::Dot),
        ("obstacle", OBSTACLE, Marker::Bar),
    ] {
        legend_marker(canvas, (x, y), color, marker);
        canvas.push(Shape::text((x + 24.0, y + 4.0), size, name).colored(INK));
        x += 24.0 + font::width(name, size) + 28.0;
    }
    // A second row for the escapes, when there were any.
    let mut items = escape_legend(escapes);
    if items.is_empty() {
        return;
    }
    let starts = escapes.iter().filter(|e| e.kind != Kind::Return).count();
    if starts > 0 {
        let colour = escapes.first().map_or(WALK, |e| escape_color(e.kind));
        items.push((
            format!("escape started ({starts})"),
            colour,
            Marker::Diamond,
        ));
    }
    let (mut x, y) = (at.0, at.1 + 20.0);
    for (name, color, marker) in items {
        legend_marker(canvas, (x, y), color, marker);
        canvas.push(Shape::text((x + 24.0, y + 4.0), size, name.clone()).colored(INK));
        x += 24.0 + font::width(&name, size) + 28.0;
    }
}

/// `count` rows at equal fractions of the end effector's path length (so a
/// long slow creep at the end does not take every snapshot).
pub fn instants(origins: &[Vec<[f64; 3]>], count: usize) -> Vec<usize> {
    let mut length = vec![0.0];
    for w in origins.windows(2) {
        let (a, b) = (w[0].last(), w[1].last());
        let step = match (a, b) {
            (Some(a), Some(b)) => (0..3).map(|i| (a[i] - b[i]).powi(2)).sum::<f64>().sqrt(),
            _ => 0.0,
        };
        length.push(length.last().copied().unwrap_or(0.0) + step);
    }
    let total = length.last().copied().unwrap_or(0.0);
    let count = count.max(2);
    (0..count)
        .map(|s| {
            let goal = total * s as f64 / (count - 1) as f64;
            length
                .iter()
                .position(|&l| l >= goal)
                .unwrap_or(origins.len().saturating_sub(1))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_increasing_and_cover_the_run() {
        let origins: Vec<Vec<[f64; 3]>> = (0..1000)
            .map(|k| vec![[0.0; 3], [(k.min(100)) as f64, 0.0, 0.0]])
            .collect();
        let f = frames(&origins, 50);
        assert_eq!(f.first(), Some(&0));
        assert_eq!(f.last(), Some(&999));
        assert!(f.windows(2).all(|w| w[0] < w[1]));
        // Half the frames go to the swing over the first 100 rows.
        let swing = f.iter().filter(|&&k| k <= 100).count();
        assert!((20..=35).contains(&swing), "{swing}");
        assert_eq!(frames(&origins[..3], 50), vec![0, 1, 2]);
    }

    #[test]
    fn polygons_are_clipped_to_the_rectangle() {
        let square = [(-5.0, -5.0), (5.0, -5.0), (5.0, 5.0), (-5.0, 5.0)];
        let c = clip_polygon(&square, (0.0, 0.0, 10.0, 10.0));
        assert!((area(&c) - 25.0).abs() < 1e-9);
        assert!(contains(&c, (2.0, 2.0)));
        assert!(!contains(&c, (-2.0, 2.0)));
    }
}
