//! What a CAD mesh's separate parts become on the board (issue 24): boxes,
//! cylinders and balls where they are those, hulls for the rest, and
//! neighbouring parts merged into shared hulls when there are more than the
//! scenario has hull slots for (`capp_core::obstacle::MAX_HULLS`).
//!
//! A part that is a box (a shelf's board, a plate, a block, a table's leg:
//! its convex hull has 8 corners, each at a corner of the box its edges
//! span) is planned as a box obstacle: the same solid, exact, about a third
//! of a hull's cost a pair on the board (`BENCHMARKS.md`: 119 against 395
//! M4F instructions a pair in the loop), and it takes no hull slot, so a
//! shelving unit of a dozen boards loads. A part whose hull's corners all
//! lie on a round cylinder (two end faces, every corner nearly one distance
//! from the axis: a pipe, a drum, a shaft) or on a ball, fine enough that
//! the solid through its corners reaches at most 2 % of its radius beyond
//! the hull (16 sides or more), is planned as that cylinder or ball (and a
//! part whose corners all lie nearly one distance from a segment, longer
//! than wide, as that capsule: a pin, a rod with rounded ends): a CAD
//! tessellation puts its vertices on the true surface, so the solid through
//! them is the part as designed, where its hull (or an enclosure of 32
//! corners, `crate::enclosure`) would take a hull slot and cost 4-6 times
//! more a pair. [`fit`] recognises each from the hull alone and fits it
//! round the hull's corners (every corner inside by construction);
//! [`Fitted::placed`] places it in the world for the core, checking that
//! the `f32` solid the core builds still holds every corner.
//!
//! The other parts are hulls. When more of them than the slots left,
//! [`merge`] joins them greedily, each time the two groups whose joint hull
//! adds the least volume to theirs (agglomerative clustering by the hulls'
//! volume, as bounding-volume hierarchies are built bottom-up; Goldsmith and
//! Salmon, "Automatic creation of object hierarchies for ray tracing",
//! 1987, use the same least-growth rule top-down). A merged hull holds
//! every point of its parts, so a plan that keeps its margins from it keeps
//! them from the parts; it only closes gaps between parts the merge joined,
//! which the loader's note names.
//!
//! Written here: recognising a box among a mesh's parts and merging parts
//! under a hull budget are not what mesh or decomposition crates offer
//! (they split non-convex parts, the opposite direction).

use crate::polytope::{cloud_hull, cross, dot, spread, sub, CloudHull, V3};

/// Corners within this of a box's corners (relative to the part's size)
/// make the part a box: a few `f32` ulps of a rotated box written by CAD
/// (binary STL stores `f32`), far below any modelling detail.
const BOX_TOLERANCE: f64 = 1e-6;

/// Relative slack on a placed solid's sizes beyond the measured growth: two
/// `f32` ulps of its size and distance from the origin, for the core's own
/// rounding as it takes a point into the solid's frame.
const ROUNDING: f64 = 2.0 * f32::EPSILON as f64;

/// A cylinder or a ball is fitted to a part's hull when every corner is on
/// it to this fraction of its radius, and it reaches no farther than this
/// fraction of its radius beyond the hull: a tessellation of 16 sides or
/// more round (`1 - cos(pi / 16)` = 1.9 %), so a fine CAD mesh of a pipe or
/// a ball, not a hexagonal bar.
const ROUND_OVERSHOOT: f64 = 0.02;

/// The most sides a drum [`fit`] tries as a cylinder has (its hull's
/// triangles are compared pairwise to find the end faces).
const MAX_CYLINDER_SIDES: usize = 512;

/// Most groups [`merge`] compares pairwise (each comparison builds a
/// hull): more parts than this are first paired off along the mesh's
/// longest axis, neighbour with neighbour, until they are this few.
const MAX_COMPARED: usize = 128;

/// One separate part of a mesh: its positions (each once) and its
/// triangles (indices into them, wound as the file winds them).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshPart {
    /// The positions, length units (the mesh's frame).
    pub points: Vec<V3>,
    /// The triangles.
    pub triangles: Vec<[usize; 3]>,
}

impl MeshPart {
    /// The volume the part's surface encloses, when the surface is closed
    /// and consistently wound (every edge of a triangle met once the other
    /// way by another; degenerate triangles left out): the divergence
    /// theorem's sum of the triangles' cones from the origin. `None` for an
    /// open or inconsistently wound surface.
    pub fn volume(&self) -> Option<f64> {
        use std::collections::HashMap;
        let proper = self
            .triangles
            .iter()
            .filter(|[a, b, c]| a != b && b != c && a != c);
        let mut edges: HashMap<(usize, usize), u32> = HashMap::new();
        let mut volume = 0.0;
        for &[a, b, c] in proper {
            for edge in [(a, b), (b, c), (c, a)] {
                *edges.entry(edge).or_default() += 1;
            }
            let [pa, pb, pc] = [a, b, c].map(|i| self.points.get(i).copied());
            volume += dot(pa?, cross(pb?, pc?)) / 6.0;
        }
        let closed = !edges.is_empty()
            && edges
                .iter()
                .all(|(&(a, b), &n)| n == 1 && edges.get(&(b, a)) == Some(&1));
        closed.then_some(volume.abs())
    }

    /// The share of its convex hull's volume that is not the part (0 for a
    /// convex part), when its surface is closed ([`MeshPart::volume`]).
    pub fn hollowness(&self) -> Option<f64> {
        let part = self.volume()?;
        let hull = volume(&cloud_hull(&self.points).ok()?);
        (hull > 0.0).then(|| (1.0 - part / hull).max(0.0))
    }
}

/// A primitive a part is, fitted round its hull, in the part's (the mesh
/// file's) frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Fitted {
    /// The solid's centre, length units.
    pub centre: V3,
    /// Its axes (unit, right-handed), the columns of its rotation: a box's
    /// edges, a cylinder's axis the third.
    pub axes: [V3; 3],
    /// What it is and its size.
    pub form: FitForm,
    /// How far the solid reaches beyond the part's hull at most, length
    /// units (0 for a box: it is the hull).
    pub overshoot: f64,
    /// The hull's corners: the solid holds each (so the whole part).
    corners: Vec<V3>,
}

/// The primitive of a [`Fitted`] part, length units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FitForm {
    /// A box of these half-extents along the axes.
    Box {
        /// Half-extents.
        half_extents: V3,
    },
    /// A round cylinder along the third axis.
    Cylinder {
        /// Radius.
        radius: f64,
        /// Full length.
        length: f64,
    },
    /// A ball.
    Sphere {
        /// Radius.
        radius: f64,
    },
    /// A capsule: the points within `radius` of a segment of `length`
    /// along the third axis, centred.
    Capsule {
        /// Radius.
        radius: f64,
        /// The segment's length (the capsule's less two radii).
        length: f64,
    },
}

/// A fitted part placed for the core: the `f32` values an obstacle takes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placed {
    /// World centre, length units.
    pub centre: [f32; 3],
    /// `R = Rz Ry Rx` of these angles (radians, `[rx, ry, rz]`) turns the
    /// solid's frame into the world's.
    pub euler_123: [f32; 3],
    /// The core's shape (`Cuboid`, `Cylinder`, `Sphere` or `Capsule`).
    pub shape: capp_core::Shape,
}

/// The primitive `points` are, when their convex hull is one: a box (8
/// corners, each at a corner of the box the edges from one of them span,
/// to `BOX_TOLERANCE` (1e-6 of its size)), or a cylinder, a ball or a capsule through every corner that
/// reaches at most `ROUND_OVERSHOOT` (2 %) of its radius beyond the hull (a
/// tessellated CAD cylinder of 16 sides or more, a ball of 16 x 32 facets
/// or finer); `None` otherwise (or for points that span no volume).
pub fn fit(points: &[V3]) -> Option<Fitted> {
    let hull = cloud_hull(points).ok()?;
    box_of(&hull)
        .or_else(|| cylinder_of(&hull))
        .or_else(|| sphere_of(&hull))
        .or_else(|| capsule_of(&hull))
}

const IDENTITY: [V3; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// [`fit`]'s box.
fn box_of(hull: &CloudHull) -> Option<Fitted> {
    let corners = &hull.corners;
    if corners.len() != 8 {
        return None;
    }
    let tolerance = BOX_TOLERANCE * spread(corners);
    let centre = mean(corners);
    // From one corner, the nearest other is along an edge (a diagonal is
    // longer than the edges it spans); the nearest of those square to it is
    // along a second edge; the third axis is square to both.
    let p0 = corners[0];
    let from_p0: Vec<V3> = corners[1..].iter().map(|&p| sub(p, p0)).collect();
    let shortest =
        |it: &mut dyn Iterator<Item = V3>| it.min_by(|a, b| dot(*a, *a).total_cmp(&dot(*b, *b)));
    let u = unit(shortest(&mut from_p0.iter().copied())?)?;
    let e2 = shortest(
        &mut from_p0
            .iter()
            .copied()
            .filter(|&e| dot(e, u).abs() <= tolerance),
    )?;
    let v = unit(sub(e2, scaled(u, dot(e2, u))))?;
    let mut axes = [u, v, cross(u, v)];
    // Along the part's own axes (as most parts are drawn): those axes, in
    // their order, so the box keeps the mesh's placement.
    let along: Vec<usize> = axes
        .iter()
        .filter_map(|a| (0..3).find(|&k| a[k].abs() >= 1.0 - 1e-12))
        .collect();
    if along.len() == 3
        && along
            .iter()
            .all(|k| along.iter().filter(|&j| j == k).count() == 1)
    {
        axes = IDENTITY;
    }
    // Half-extents from the corners themselves: every corner within them.
    let half_extents = axes.map(|a| {
        corners
            .iter()
            .map(|&p| dot(sub(p, centre), a).abs())
            .fold(0.0, f64::max)
    });
    if half_extents.iter().any(|&h| h <= tolerance) {
        return None;
    }
    // A box: each corner at one of its corners, all eight taken.
    let mut seen = 0u8;
    for &p in corners {
        let mut pattern = 0u8;
        for (k, (&a, &h)) in axes.iter().zip(&half_extents).enumerate() {
            let x = dot(sub(p, centre), a);
            if (x.abs() - h).abs() > tolerance {
                return None;
            }
            pattern |= u8::from(x > 0.0) << k;
        }
        seen |= 1 << pattern;
    }
    (seen == u8::MAX).then(|| Fitted {
        centre,
        axes,
        form: FitForm::Box { half_extents },
        overshoot: 0.0,
        corners: corners.clone(),
    })
}

/// [`fit`]'s cylinder: the hull is a prism whose two end faces (the
/// direction most of its triangles face, a cap's fan) hold every corner,
/// the corners all at nearly one distance from the axis through their
/// mean; the cylinder through the farthest. It reaches beyond the hull by
/// at most its radius less the least distance of a side face's plane from
/// the axis (the hull holds the cylinder of that radius).
fn cylinder_of(hull: &CloudHull) -> Option<Fitted> {
    let corners = &hull.corners;
    // Two triangles compared for each pair: a drum of 512 sides at most.
    if corners.len() > 2 * MAX_CYLINDER_SIDES {
        return None;
    }
    let tolerance = BOX_TOLERANCE * spread(corners);
    // The normal most triangles share (up to sign): the caps'.
    let parallel = |a: V3, b: V3| dot(a, b).abs() >= 1.0 - 1e-9;
    let axis = hull
        .triangles
        .iter()
        .map(|t| {
            let count = hull
                .triangles
                .iter()
                .filter(|u| parallel(t.normal, u.normal))
                .count();
            (count, t.normal)
        })
        .max_by_key(|&(count, _)| count)
        .filter(|&(count, _)| count >= 12)?
        .1;
    let along: Vec<f64> = corners.iter().map(|&p| dot(p, axis)).collect();
    let (lo, hi) = extent(&along);
    if along
        .iter()
        .any(|&t| (t - lo).abs() > tolerance && (t - hi).abs() > tolerance)
    {
        return None;
    }
    let m = mean(corners);
    let centre = add(m, scaled(axis, (lo + hi) / 2.0 - dot(m, axis)));
    let radial = |p: V3| {
        let d = sub(p, centre);
        let off = sub(d, scaled(axis, dot(d, axis)));
        dot(off, off).sqrt()
    };
    // The side faces' distances from the axis.
    let sides = hull
        .triangles
        .iter()
        .filter(|t| dot(t.normal, axis).abs() <= 1e-6)
        .map(|t| t.offset - dot(t.normal, centre));
    let (radius, overshoot) = round_through(corners, radial, sides)?;
    Some(Fitted {
        centre,
        axes: round_axes(axis)?,
        form: FitForm::Cylinder {
            radius,
            length: hi - lo,
        },
        overshoot,
        corners: corners.clone(),
    })
}

/// [`fit`]'s ball: every corner at nearly one distance from their mean,
/// the ball through the farthest; it reaches beyond the hull by at most its
/// radius less the least distance of a face's plane from its centre.
fn sphere_of(hull: &CloudHull) -> Option<Fitted> {
    let corners = &hull.corners;
    let centre = mean(corners);
    let distance = |p: V3| {
        let d = sub(p, centre);
        dot(d, d).sqrt()
    };
    let faces = hull
        .triangles
        .iter()
        .map(|t| t.offset - dot(t.normal, centre));
    let (radius, overshoot) = round_through(corners, distance, faces)?;
    Some(Fitted {
        centre,
        axes: IDENTITY,
        form: FitForm::Sphere { radius },
        overshoot,
        corners: corners.clone(),
    })
}

/// [`fit`]'s capsule: its axis the line through the means of the corners
/// on either side of their mean's plane across a far pair (refined
/// twice: for a capsule, symmetric about its middle, that is the axis), its
/// segment what the corners' extent along it leaves after a radius at each
/// end, every corner nearly at the radius from the segment; it reaches
/// beyond the hull by at most its radius less the least distance of a
/// face's plane from the segment.
fn capsule_of(hull: &CloudHull) -> Option<Fitted> {
    let corners = &hull.corners;
    let centre = mean(corners);
    // A far pair in two linear passes (the corner farthest from the mean,
    // then the one farthest from it): a hull may have thousands of corners.
    let farthest_from = |from: V3| {
        corners.iter().copied().max_by(|&p, &q| {
            dot(sub(p, from), sub(p, from)).total_cmp(&dot(sub(q, from), sub(q, from)))
        })
    };
    let a = farthest_from(centre)?;
    let b = farthest_from(a)?;
    let mut axis = unit(sub(a, b))?;
    for _ in 0..2 {
        let side = |sign: f64| {
            let near: Vec<V3> = corners
                .iter()
                .copied()
                .filter(|&p| sign * dot(sub(p, centre), axis) > 0.0)
                .collect();
            (!near.is_empty()).then(|| mean(&near))
        };
        axis = unit(sub(side(1.0)?, side(-1.0)?))?;
    }
    let along: Vec<f64> = corners.iter().map(|&p| dot(sub(p, centre), axis)).collect();
    let (lo, hi) = extent(&along);
    let centre = add(centre, scaled(axis, (lo + hi) / 2.0));
    let radial = |p: V3| {
        let d = sub(p, centre);
        let off = sub(d, scaled(axis, dot(d, axis)));
        dot(off, off).sqrt()
    };
    let radius = corners.iter().map(|&p| radial(p)).fold(0.0, f64::max);
    let half = (hi - lo) / 2.0 - radius;
    // Longer than wide by a radius at least (shorter is a ball's work, or
    // no capsule's); NaN is neither.
    if half.is_nan() || half < radius {
        return None;
    }
    let from_segment = |p: V3| {
        let d = sub(p, centre);
        let t = dot(d, axis).clamp(-half, half);
        let off = sub(d, scaled(axis, t));
        dot(off, off).sqrt()
    };
    let faces = hull
        .triangles
        .iter()
        .map(|t| t.offset - dot(t.normal, centre) - half * dot(t.normal, axis).abs());
    let (radius, overshoot) = round_through(corners, from_segment, faces)?;
    Some(Fitted {
        centre,
        axes: round_axes(axis)?,
        form: FitForm::Capsule {
            radius,
            length: 2.0 * half,
        },
        overshoot,
        corners: corners.clone(),
    })
}

/// The least and the largest of `values`.
fn extent(values: &[f64]) -> (f64, f64) {
    values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &t| {
            (lo.min(t), hi.max(t))
        })
}

/// A round solid's axes, `axis` the third: along the mesh's z the mesh's
/// own (its placement kept); else x level (square to the axis and to the
/// mesh's z).
fn round_axes(axis: V3) -> Option<[V3; 3]> {
    if axis[2].abs() >= 1.0 - 1e-12 {
        return Some(IDENTITY);
    }
    let x = unit(cross(axis, [0.0, 0.0, 1.0]))?;
    Some([x, cross(axis, x), axis])
}

/// The radius of the round solid (a cylinder, a ball or a capsule) through the
/// farthest of `corners`, each at `distance` from its axis or centre, and
/// how far it reaches beyond the hull whose face planes lie at `planes`
/// from the axis or centre (the hull holds the solid of their least
/// radius): `None` unless every corner is nearly on it and it reaches at
/// most [`ROUND_OVERSHOOT`] of its radius beyond.
fn round_through(
    corners: &[V3],
    distance: impl Fn(V3) -> f64,
    planes: impl Iterator<Item = f64>,
) -> Option<(f64, f64)> {
    let (nearest, radius) = corners
        .iter()
        .map(|&p| distance(p))
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), d| {
            (lo.min(d), hi.max(d))
        });
    let inner = planes.fold(f64::INFINITY, f64::min);
    if nearest < radius * (1.0 - ROUND_OVERSHOOT) || !inner.is_finite() {
        return None;
    }
    let overshoot = radius - inner.min(radius);
    (overshoot <= ROUND_OVERSHOOT * radius).then_some((radius, overshoot))
}

impl Fitted {
    /// The solid in the world, for a mesh placed at `centre` turned by
    /// `euler` (radians, `R = Rz Ry Rx`), as the core's `f32` values. A
    /// solid along the mesh's axes keeps the mesh's angles (a ball takes
    /// none); another box's axis called x is the one nearest the world's
    /// horizontal plane (a box is the same whichever of its axes is called
    /// x), and another cylinder's x is level, so the angles are far from
    /// the `ry = +-90 deg` lock (`|sin ry| <= 1/sqrt 3`). The sizes are
    /// grown by what the `f32` angles and centre move the hull's corners
    /// (measured: the core's own rotation of the rounded angles) plus
    /// `ROUNDING` (two `f32` ulps) of the solid's size and distance from the origin, so the
    /// solid the core builds holds every corner of the part.
    pub fn placed(&self, centre: V3, euler: V3) -> Placed {
        let rotation = crate::geometry::rotation(euler);
        let turn = |a: V3| -> V3 { [0, 1, 2].map(|i| dot(rotation[i], a)) };
        let world_centre = add(centre, turn(self.centre));
        let world_axes = self.axes.map(turn);
        let mut order = [0, 1, 2];
        let angles = match self.form {
            FitForm::Sphere { .. } => [0.0; 3],
            _ if self.axes == IDENTITY => euler,
            form => {
                if let FitForm::Box { .. } = form {
                    // The cyclic order (right-handed) whose x is most level.
                    let first = (0..3)
                        .min_by(|&a, &b| world_axes[a][2].abs().total_cmp(&world_axes[b][2].abs()))
                        .unwrap_or(0);
                    order = [first, (first + 1) % 3, (first + 2) % 3];
                }
                let [x, y, z] = order.map(|k| world_axes[k]);
                // R's columns are x, y, z: R[2][0] = x_z = -sin ry, R[2][1]
                // = y_z = cos ry sin rx, R[2][2] = z_z, R[1][0] = x_y = sin
                // rz cos ry, R[0][0] = x_x.
                [
                    libm::atan2(y[2], z[2]),
                    libm::asin((-x[2]).clamp(-1.0, 1.0)),
                    libm::atan2(x[1], x[0]),
                ]
            }
        };
        let euler_123 = angles.map(|a| a as f32);
        let centre_f32 = world_centre.map(|c| c as f32);
        // Each corner of the hull in the f32 solid's frame.
        let r = capp_core::math::rotation_123(euler_123[0], euler_123[1], euler_123[2]);
        let local: Vec<V3> = self
            .corners
            .iter()
            .map(|&p| {
                let world = add(centre, turn(p));
                let d = [0, 1, 2].map(|i| world[i] - f64::from(centre_f32[i]));
                [0, 1, 2].map(|k| (0..3).map(|i| f64::from(r[(i, k)]) * d[i]).sum())
            })
            .collect();
        let largest = |f: &dyn Fn(&V3) -> f64| local.iter().map(f).fold(0.0, f64::max);
        let far = world_centre.iter().fold(0.0, |m: f64, &c| m.max(c.abs()));
        let grow = |size: f64, need: f64| round_up(size.max(need) + ROUNDING * (size + far));
        let shape = match self.form {
            FitForm::Box { half_extents } => {
                let half = order.map(|k| half_extents[k]);
                capp_core::Shape::Cuboid {
                    half_extents: [0, 1, 2].map(|k| grow(half[k], largest(&|l| l[k].abs()))),
                }
            }
            FitForm::Cylinder { radius, length } => capp_core::Shape::Cylinder {
                radius: grow(radius, largest(&|l| (l[0] * l[0] + l[1] * l[1]).sqrt())),
                length: 2.0 * grow(length / 2.0, largest(&|l| l[2].abs())),
            },
            FitForm::Sphere { radius } => capp_core::Shape::Sphere {
                radius: grow(radius, largest(&|l| dot(*l, *l).sqrt())),
            },
            FitForm::Capsule { radius, length } => {
                // The f32 segment no shorter than the fitted one; the
                // radius grown to every corner's distance from it.
                let half = round_up(length / 2.0);
                let from_segment = |l: &V3| {
                    let z = l[2] - l[2].clamp(-f64::from(half), f64::from(half));
                    (l[0] * l[0] + l[1] * l[1] + z * z).sqrt()
                };
                capp_core::Shape::Capsule {
                    radius: grow(radius, largest(&from_segment)),
                    length: 2.0 * half,
                }
            }
        };
        Placed {
            centre: centre_f32,
            euler_123,
            shape,
        }
    }
}

/// Groups of `parts` (each a part's points), at most `groups` of them (at
/// least 1), as the module docs merge them: each group the indices of the
/// parts it holds, ascending, the groups in the order of their first part.
/// Parts whose points span no volume count as points of their group.
pub fn merge(parts: &[Vec<V3>], groups: usize) -> Vec<Vec<usize>> {
    let groups = groups.max(1);
    let mut clusters: Vec<Cluster> = parts
        .iter()
        .enumerate()
        .map(|(k, points)| Cluster::new(vec![k], points.clone()))
        .collect();
    // Too many to compare pairwise: neighbours along the longest axis
    // first, pair by pair.
    while clusters.len() > MAX_COMPARED.max(groups) {
        let all: Vec<V3> = clusters.iter().flat_map(|c| c.corners.clone()).collect();
        let axis = longest_axis(&all);
        clusters.sort_by(|a, b| a.mean()[axis].total_cmp(&b.mean()[axis]));
        let mut paired = Vec::with_capacity(clusters.len() / 2 + 1);
        let mut it = clusters.into_iter();
        while let Some(a) = it.next() {
            paired.push(match it.next() {
                Some(b) => a.joined(&b),
                None => a,
            });
        }
        clusters = paired;
    }
    // Least growth first. Each pair's growth is kept (a hull a pair) and
    // only the merged group's recomputed (a hull per other group).
    let growth = |a: &Cluster, b: &Cluster| a.joined(b).volume - a.volume - b.volume;
    let n = clusters.len();
    let mut slots: Vec<Option<Cluster>> = clusters.into_iter().map(Some).collect();
    let mut grows = vec![vec![f64::INFINITY; n]; n];
    for i in 0..n {
        for j in i + 1..n {
            if let (Some(a), Some(b)) = (&slots[i], &slots[j]) {
                grows[i][j] = growth(a, b);
            }
        }
    }
    let mut count = n;
    while count > groups {
        let mut best: Option<(f64, usize, usize)> = None;
        for (i, row) in grows.iter().enumerate() {
            for (j, &g) in row.iter().enumerate().skip(i + 1) {
                if slots[i].is_some() && slots[j].is_some() && best.is_none_or(|b| g < b.0) {
                    best = Some((g, i, j));
                }
            }
        }
        let Some((_, i, j)) = best else { break };
        let (Some(a), Some(b)) = (slots[i].take(), slots[j].take()) else {
            break;
        };
        let joined = a.joined(&b);
        for (k, other) in slots.iter().enumerate() {
            if let Some(other) = other {
                let g = growth(&joined, other);
                let (lo, hi) = (k.min(i), k.max(i));
                grows[lo][hi] = g;
            }
        }
        slots[i] = Some(joined);
        count -= 1;
    }
    let clusters: Vec<Cluster> = slots.into_iter().flatten().collect();
    let mut out: Vec<Vec<usize>> = clusters
        .into_iter()
        .map(|mut c| {
            c.parts.sort_unstable();
            c.parts
        })
        .collect();
    out.sort_by_key(|g| g.first().copied());
    out
}

/// Parts merged so far: their indices, their hull's corners and volume.
struct Cluster {
    parts: Vec<usize>,
    corners: Vec<V3>,
    volume: f64,
}

impl Cluster {
    fn new(parts: Vec<usize>, points: Vec<V3>) -> Self {
        match cloud_hull(&points) {
            Ok(hull) => Cluster {
                parts,
                volume: volume(&hull),
                corners: hull.corners,
            },
            // No volume (flat, a line, a point): its points, volume 0.
            Err(_) => Cluster {
                parts,
                corners: points,
                volume: 0.0,
            },
        }
    }

    fn joined(&self, other: &Cluster) -> Cluster {
        let mut parts = self.parts.clone();
        parts.extend(&other.parts);
        let mut points = self.corners.clone();
        points.extend(&other.corners);
        Cluster::new(parts, points)
    }

    fn mean(&self) -> V3 {
        mean(&self.corners)
    }
}

/// The volume of the convex hull of `points`, `None` when they span none.
pub fn hull_volume(points: &[V3]) -> Option<f64> {
    cloud_hull(points).ok().map(|hull| volume(&hull))
}

/// The volume of a hull: its boundary triangles' cones from the origin
/// (signed, the outward triangles counter-clockwise).
fn volume(hull: &CloudHull) -> f64 {
    hull.triangles
        .iter()
        .map(|t| dot(t.corners[0], cross(t.corners[1], t.corners[2])) / 6.0)
        .sum()
}

/// The axis (0, 1, 2) along which `points` spread the most.
fn longest_axis(points: &[V3]) -> usize {
    let extent = |k: usize| {
        let (lo, hi) = points
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p[k]), hi.max(p[k]))
            });
        hi - lo
    };
    (0..3)
        .max_by(|&a, &b| extent(a).total_cmp(&extent(b)))
        .unwrap_or(0)
}

fn mean(points: &[V3]) -> V3 {
    let n = points.len().max(1) as f64;
    let s = points
        .iter()
        .fold([0.0; 3], |s, p| [s[0] + p[0], s[1] + p[1], s[2] + p[2]]);
    s.map(|x| x / n)
}

fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn scaled(a: V3, s: f64) -> V3 {
    a.map(|x| x * s)
}

fn unit(a: V3) -> Option<V3> {
    let n = dot(a, a).sqrt();
    (n > 0.0 && n.is_finite()).then(|| scaled(a, 1.0 / n))
}

/// The least `f32` not below `x`.
fn round_up(x: f64) -> f32 {
    let f = x as f32;
    if f64::from(f) < x {
        f.next_up()
    } else {
        f
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::rotation;

    fn lcg(state: &mut u64) -> f64 {
        *state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (*state >> 11) as f64 / (1u64 << 53) as f64
    }

    /// `local` turned by `r` (rows) and moved to `centre`.
    fn moved(centre: V3, r: &[[f64; 3]; 3], local: V3) -> V3 {
        add(centre, [0, 1, 2].map(|i| dot(r[i], local)))
    }

    /// The corners of a box of `half` about `centre` turned by `r` (its
    /// axes the columns).
    fn box_corners(centre: V3, r: &[[f64; 3]; 3], half: V3) -> Vec<V3> {
        (0..8)
            .map(|c: usize| {
                let local = [0, 1, 2].map(|a| if c >> a & 1 == 1 { half[a] } else { -half[a] });
                moved(centre, r, local)
            })
            .collect()
    }

    fn random_rotation(rng: &mut u64) -> [[f64; 3]; 3] {
        rotation([0, 1, 2].map(|_| (lcg(rng) - 0.5) * 7.0))
    }

    /// Whether world point `x` is in the solid the core builds of `placed`
    /// (its f32 rotation, centre and sizes).
    fn holds(placed: &Placed, x: V3) -> bool {
        let [ex, ey, ez] = placed.euler_123;
        let r = capp_core::math::rotation_123(ex, ey, ez);
        let d = [0, 1, 2].map(|i| x[i] - f64::from(placed.centre[i]));
        let l: [f64; 3] = [0, 1, 2].map(|k| (0..3).map(|i| f64::from(r[(i, k)]) * d[i]).sum());
        match placed.shape {
            capp_core::Shape::Cuboid { half_extents } => {
                (0..3).all(|k| l[k].abs() <= f64::from(half_extents[k]))
            }
            capp_core::Shape::Cylinder { radius, length } => {
                (l[0] * l[0] + l[1] * l[1]).sqrt() <= f64::from(radius)
                    && l[2].abs() <= f64::from(length) / 2.0
            }
            capp_core::Shape::Sphere { radius } => dot(l, l).sqrt() <= f64::from(radius),
            capp_core::Shape::Capsule { radius, length } => {
                let half = f64::from(length) / 2.0;
                let z = l[2] - l[2].clamp(-half, half);
                (l[0] * l[0] + l[1] * l[1] + z * z).sqrt() <= f64::from(radius)
            }
            _ => false,
        }
    }

    /// `points` placed by a mesh frame at `origin` turned by `angles`.
    fn in_world(points: &[V3], origin: V3, angles: V3) -> Vec<V3> {
        let frame = rotation(angles);
        points.iter().map(|&p| moved(origin, &frame, p)).collect()
    }

    #[test]
    fn turned_boxes_of_any_size_are_recognised_and_the_core_box_holds_them() {
        let mut rng = 11u64;
        for case in 0..300 {
            let scale = 10f64.powf(lcg(&mut rng) * 6.0 - 3.0);
            let half = [0, 1, 2].map(|_| scale * (0.01 + lcg(&mut rng)));
            let centre = [0, 1, 2].map(|_| scale * 20.0 * (lcg(&mut rng) - 0.5));
            let r = random_rotation(&mut rng);
            let mut points = box_corners(centre, &r, half);
            // Mesh vertices on its faces and edges are not corners.
            points.push(add(centre, [0, 1, 2].map(|i| r[i][0] * half[0])));
            points.push(centre);
            let part = fit(&points).unwrap_or_else(|| panic!("case {case}: not a box"));
            let FitForm::Box { half_extents } = part.form else {
                panic!("case {case}: {part:?}");
            };
            assert_eq!(part.overshoot, 0.0);
            let mut got = half_extents;
            got.sort_by(f64::total_cmp);
            let mut want = half;
            want.sort_by(f64::total_cmp);
            for k in 0..3 {
                assert!(
                    (got[k] - want[k]).abs() <= 1e-9 * scale,
                    "case {case}: {got:?} {want:?}"
                );
            }
            // Placed by a turned, moved mesh frame: the core's f32 box
            // holds every corner, and is no more than a little larger.
            let angles = [0, 1, 2].map(|_| (lcg(&mut rng) - 0.5) * 7.0);
            let origin = [0, 1, 2].map(|_| scale * 50.0 * (lcg(&mut rng) - 0.5));
            let placed = part.placed(origin, angles);
            assert!(placed.euler_123[1].abs() <= 0.62, "case {case}: {placed:?}");
            for x in in_world(&points, origin, angles) {
                assert!(holds(&placed, x), "case {case}: outside");
            }
            let spread = 1e-5
                * (scale
                    + origin
                        .iter()
                        .chain(&centre)
                        .fold(0.0, |m: f64, c| m.max(c.abs())));
            let capp_core::Shape::Cuboid { half_extents } = placed.shape else {
                panic!("case {case}: {placed:?}");
            };
            let mut placed_half = half_extents.map(f64::from);
            placed_half.sort_by(f64::total_cmp);
            for k in 0..3 {
                assert!(
                    placed_half[k] - want[k] <= spread,
                    "case {case}: {placed_half:?} {want:?}"
                );
            }
        }
    }

    #[test]
    fn eight_cornered_parts_that_are_not_boxes_are_not() {
        let id = rotation([0.0; 3]);
        let cube = box_corners([0.0; 3], &id, [1.0, 1.0, 1.0]);
        // A frustum: the top face smaller.
        let frustum: Vec<V3> = cube
            .iter()
            .map(|p| {
                if p[2] > 0.0 {
                    [p[0] * 0.9, p[1] * 0.9, p[2]]
                } else {
                    *p
                }
            })
            .collect();
        // A parallelepiped: sheared.
        let sheared: Vec<V3> = cube
            .iter()
            .map(|p| [p[0] + 0.3 * p[2], p[1], p[2]])
            .collect();
        // One corner moved out by a thousandth.
        let mut dented = cube.clone();
        dented[5] = dented[5].map(|x| x * 1.001);
        // A tetrahedron, and a square (no volume).
        let tetra = vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let flat: Vec<V3> = cube.iter().map(|p| [p[0], p[1], 0.0]).collect();
        for (name, points) in [
            ("frustum", frustum),
            ("sheared", sheared),
            ("dented", dented),
            ("tetrahedron", tetra),
            ("flat", flat),
        ] {
            assert_eq!(fit(&points), None, "{name}");
        }
        assert!(fit(&cube).is_some());
    }

    #[test]
    fn a_solid_along_the_meshs_axes_keeps_its_placement() {
        let id = rotation([0.0; 3]);
        let part = fit(&box_corners([0.5, -0.25, 2.0], &id, [0.1, 0.05, 0.2])).unwrap();
        assert_eq!(part.axes, IDENTITY);
        let FitForm::Box { half_extents } = part.form else {
            panic!("{part:?}");
        };
        for (got, want) in half_extents.iter().zip([0.1, 0.05, 0.2]) {
            assert!((got - want).abs() < 1e-12, "{part:?}");
        }
        let euler = [0.1, -1.5, 3.0];
        let placed = part.placed([1.0, 2.0, 3.0], euler);
        assert_eq!(placed.euler_123, euler.map(|a| a as f32));
        let frame = rotation(euler);
        for (k, row) in frame.iter().enumerate() {
            let world = 1.0 + k as f64 + dot(*row, [0.5, -0.25, 2.0]);
            assert!((f64::from(placed.centre[k]) - world).abs() < 1e-6);
        }
        let capp_core::Shape::Cuboid { half_extents } = placed.shape else {
            panic!("{placed:?}");
        };
        for (got, want) in half_extents.iter().zip([0.1, 0.05, 0.2]) {
            assert!(
                f64::from(*got) >= want && f64::from(*got) - want < 2e-6,
                "{placed:?}"
            );
        }
        // A drum along the mesh's z too.
        let drum = prism(32, 0.1, 0.1, 0.3, &id, [0.0, 0.0, 1.0]);
        let part = fit(&drum).unwrap();
        assert_eq!(part.axes, IDENTITY);
        assert_eq!(
            part.placed([0.0; 3], euler).euler_123,
            euler.map(|a| a as f32)
        );
    }

    /// The corners of a prism of `sides` round an ellipse of semi-axes
    /// `(a, b)`, `length` long, about `centre` turned by `r`.
    fn prism(sides: usize, a: f64, b: f64, length: f64, r: &[[f64; 3]; 3], centre: V3) -> Vec<V3> {
        let mut points = Vec::new();
        for k in 0..sides {
            let t = std::f64::consts::TAU * k as f64 / sides as f64;
            for z in [-length / 2.0, length / 2.0] {
                let local = [a * t.cos(), b * t.sin(), z];
                points.push(moved(centre, r, local));
            }
        }
        points
    }

    #[test]
    fn fine_drums_and_balls_are_cylinders_and_balls_through_their_corners() {
        let mut rng = 5u64;
        for case in 0..120 {
            let scale = 10f64.powf(lcg(&mut rng) * 4.0 - 2.0);
            let radius = scale * (0.05 + lcg(&mut rng));
            let length = scale * (0.05 + 3.0 * lcg(&mut rng));
            let sides = 16 + (lcg(&mut rng) * 60.0) as usize;
            let r = random_rotation(&mut rng);
            let centre = [0, 1, 2].map(|_| scale * 10.0 * (lcg(&mut rng) - 0.5));
            let points = prism(sides, radius, radius, length, &r, centre);
            let part = fit(&points).unwrap_or_else(|| panic!("case {case}: {sides} sides"));
            let FitForm::Cylinder {
                radius: got,
                length: long,
            } = part.form
            else {
                panic!("case {case}: {part:?}");
            };
            assert!((got - radius).abs() <= 1e-9 * radius, "case {case}");
            assert!((long - length).abs() <= 1e-9 * scale, "case {case}");
            let sagitta = radius * (1.0 - (std::f64::consts::PI / sides as f64).cos());
            assert!(
                (part.overshoot - sagitta).abs() <= 1e-9 * radius,
                "case {case}"
            );
            let angles = [0, 1, 2].map(|_| (lcg(&mut rng) - 0.5) * 7.0);
            let origin = [0, 1, 2].map(|_| scale * 30.0 * (lcg(&mut rng) - 0.5));
            let placed = part.placed(origin, angles);
            for x in in_world(&points, origin, angles) {
                assert!(holds(&placed, x), "case {case}: outside");
            }
        }
        // Too coarse to be a cylinder (a hexagonal or 12-sided bar), or not
        // round (an elliptic drum): no primitive.
        let id = rotation([0.0; 3]);
        for (sides, b) in [(6, 1.0), (12, 1.0), (15, 1.0), (40, 0.8)] {
            assert_eq!(
                fit(&prism(sides, 1.0, b, 2.0, &id, [0.0; 3])),
                None,
                "{sides} {b}"
            );
        }
        // Balls: latitude rings and poles.
        let ball = |rings: usize, segments: usize, squash: f64| {
            let mut points = vec![[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]];
            for i in 1..rings {
                let polar = std::f64::consts::PI * i as f64 / rings as f64;
                for k in 0..segments {
                    let t = std::f64::consts::TAU * k as f64 / segments as f64;
                    points.push([
                        polar.sin() * t.cos() * squash,
                        polar.sin() * t.sin(),
                        polar.cos(),
                    ]);
                }
            }
            points
        };
        let part = fit(&ball(24, 48, 1.0)).unwrap();
        let FitForm::Sphere { radius } = part.form else {
            panic!("{part:?}");
        };
        assert!(
            (radius - 1.0).abs() < 1e-9 && part.overshoot < 0.02,
            "{part:?}"
        );
        let placed = part.placed([3.0, -2.0, 1.0], [0.3, 0.2, 0.1]);
        assert_eq!(placed.euler_123, [0.0; 3]);
        for x in in_world(&ball(24, 48, 1.0), [3.0, -2.0, 1.0], [0.3, 0.2, 0.1]) {
            assert!(holds(&placed, x));
        }
        for (rings, segments, squash) in [(8, 16, 1.0), (24, 48, 0.9)] {
            assert_eq!(
                fit(&ball(rings, segments, squash)),
                None,
                "{rings} {squash}"
            );
        }
    }

    /// A capsule's tessellation (a UV capsule, as CAD and Blender write
    /// one): `segments` round, `rings` latitude rings a cap with its pole,
    /// radius `a` across x (`b` across y: round when equal), the segment
    /// `length` along z; turned by `r` and moved to `centre`.
    #[allow(clippy::too_many_arguments)]
    fn capsule_points(
        segments: usize,
        rings: usize,
        a: f64,
        b: f64,
        length: f64,
        r: &[[f64; 3]; 3],
        centre: V3,
    ) -> Vec<V3> {
        let mut local = vec![[0.0, 0.0, length / 2.0 + a], [0.0, 0.0, -length / 2.0 - a]];
        for cap in [1.0, -1.0] {
            for i in 0..rings {
                // From the equator (i = 0) toward the pole.
                let polar = std::f64::consts::FRAC_PI_2 * i as f64 / rings as f64;
                for k in 0..segments {
                    let t = std::f64::consts::TAU * k as f64 / segments as f64;
                    local.push([
                        a * polar.cos() * t.cos(),
                        b * polar.cos() * t.sin(),
                        cap * (length / 2.0 + a * polar.sin()),
                    ]);
                }
            }
        }
        local.iter().map(|&p| moved(centre, r, p)).collect()
    }

    #[test]
    fn fine_capsules_are_capsules_through_their_corners() {
        let mut rng = 17u64;
        for case in 0..80 {
            let scale = 10f64.powf(lcg(&mut rng) * 4.0 - 2.0);
            let radius = scale * (0.05 + lcg(&mut rng));
            let length = radius * (2.0 + 4.0 * lcg(&mut rng));
            let segments = 24 + (lcg(&mut rng) * 40.0) as usize;
            let rings = 6 + (lcg(&mut rng) * 10.0) as usize;
            let r = random_rotation(&mut rng);
            let centre = [0, 1, 2].map(|_| scale * 10.0 * (lcg(&mut rng) - 0.5));
            let points = capsule_points(segments, rings, radius, radius, length, &r, centre);
            let part = fit(&points).unwrap_or_else(|| panic!("case {case}"));
            let FitForm::Capsule {
                radius: got,
                length: long,
            } = part.form
            else {
                panic!("case {case}: {:?}", part.form);
            };
            assert!(
                (got - radius).abs() <= 1e-9 * radius,
                "case {case}: {got} {radius}"
            );
            assert!(
                (long - length).abs() <= 1e-9 * scale,
                "case {case}: {long} {length}"
            );
            assert!(part.overshoot <= 0.02 * radius, "case {case}");
            let angles = [0, 1, 2].map(|_| (lcg(&mut rng) - 0.5) * 7.0);
            let origin = [0, 1, 2].map(|_| scale * 30.0 * (lcg(&mut rng) - 0.5));
            let placed = part.placed(origin, angles);
            assert!(matches!(placed.shape, capp_core::Shape::Capsule { .. }));
            for x in in_world(&points, origin, angles) {
                assert!(holds(&placed, x), "case {case}: outside");
            }
        }
        // Too coarse (8 round), not round (elliptic), or no longer than a
        // ball: no capsule (the last a ball).
        let id = rotation([0.0; 3]);
        for (segments, b, length) in [(8, 1.0, 3.0), (48, 0.8, 3.0)] {
            assert_eq!(
                fit(&capsule_points(segments, 8, 1.0, b, length, &id, [0.0; 3])),
                None,
                "{segments} {b}"
            );
        }
        let short = fit(&capsule_points(48, 12, 1.0, 1.0, 0.0, &id, [0.0; 3]));
        assert!(
            matches!(short.as_ref().map(|f| f.form), Some(FitForm::Sphere { .. })),
            "{short:?}"
        );
    }

    /// A small tetrahedron at `at`.
    fn tetra(at: V3, size: f64) -> Vec<V3> {
        [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ]
        .iter()
        .map(|v| add(at, scaled(*v, size)))
        .collect()
    }

    #[test]
    fn merging_keeps_every_part_once_and_joins_neighbours_first() {
        // Three clusters of small parts far apart: three groups are the
        // clusters, whatever the parts' order.
        let mut rng = 3u64;
        let centres = [[0.0, 0.0, 0.0], [5.0, 0.0, 0.0], [0.0, 5.0, 1.0]];
        let mut parts = Vec::new();
        let mut cluster_of = Vec::new();
        for k in 0..15 {
            let c = (k * 7) % 3;
            let jitter = [0, 1, 2].map(|_| lcg(&mut rng) * 0.5);
            parts.push(tetra(add(centres[c], jitter), 0.1));
            cluster_of.push(c);
        }
        let groups = merge(&parts, 3);
        assert_eq!(groups.len(), 3);
        for g in &groups {
            assert!(
                g.iter().all(|&p| cluster_of[p] == cluster_of[g[0]]),
                "{groups:?}"
            );
        }
        for budget in [1, 2, 5, 8, 14, 15, 20] {
            let groups = merge(&parts, budget);
            assert_eq!(groups.len(), budget.min(15), "budget {budget}");
            let mut all: Vec<usize> = groups.concat();
            all.sort_unstable();
            assert_eq!(all, (0..15).collect::<Vec<_>>());
            assert!(groups.iter().all(|g| g.windows(2).all(|w| w[0] < w[1])));
        }
        // Many parts (past the pairwise comparison's bound) still end in
        // the budget, every part once.
        let many: Vec<Vec<V3>> = (0..300)
            .map(|k| tetra([k as f64 * 0.3, (k % 7) as f64, 0.0], 0.1))
            .collect();
        let groups = merge(&many, 8);
        assert_eq!(groups.len(), 8);
        let mut all: Vec<usize> = groups.concat();
        all.sort_unstable();
        assert_eq!(all, (0..300).collect::<Vec<_>>());
    }

    #[test]
    fn a_hulls_volume_is_its_solids() {
        let id = rotation([0.0; 3]);
        let cube = cloud_hull(&box_corners([3.0, -2.0, 1.0], &id, [1.0, 2.0, 0.5])).unwrap();
        assert!((volume(&cube) - 8.0).abs() < 1e-12);
        let t = cloud_hull(&tetra([1.0, 1.0, 1.0], 2.0)).unwrap();
        assert!((volume(&t) - 8.0 / 6.0).abs() < 1e-12);
    }
}
