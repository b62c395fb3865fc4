//! A mesh part that is not convex, split into convex pieces along its own
//! face planes (issue 24: "several hulls when it is not convex").
//!
//! A piece is the part's surface within a cell of space (the triangles
//! clipped to the cell's half-spaces), planned round its convex hull. The
//! hull holds the part within the cell: the solid there is bounded by the
//! clipped surface and by cross-sections on the cell's planes, and a plane
//! cross-section lies within the hull of its boundary, which is where the
//! surface meets the plane (clipping keeps those points on both sides). So
//! the pieces together hold the whole part, and a plan that keeps its
//! margins from them keeps them from the part, while the arm may now go
//! into the part's hollows (the notch of an L, a shelf's compartments).
//!
//! The cuts are chosen greedily: each time, over every piece and every
//! candidate plane (the part's own face planes, the largest by area first:
//! CAD parts are made of few large flat faces, and a concave edge lies on
//! two of them), the cut that takes the most volume off the hulls, until no
//! cut takes off `MIN_GAIN` of the part's hull or the pieces are spent (a
//! closed part still hollow by that much may instead have a box split off,
//! see `Rank::Slab`). A
//! convex part has no such cut (any cut's two hulls fill the one). This is
//! the top-down, cut-by-plane family of approximate convex decompositions
//! (Mamou's V-HACD and Wei et al.'s CoACD, SIGGRAPH 2022, cut by planes and
//! measure concavity; here the measure is the hulls' volume and the planes
//! are the part's own, which suits CAD parts of flat faces), written here
//! for a small budget of pieces and no dependencies (the Rust convex
//! decomposition in parry3d would bring nalgebra's `std` into the
//! workspace; see README).

use crate::mesh_parts::{fit, hull_volume, FitForm, MeshPart};
use crate::polytope::{cross, dot, spread, sub, V3};

/// A cut must take at least this share of the part's hull volume off the
/// pieces' hulls to be made.
const MIN_GAIN: f64 = 0.02;

/// A part of more triangles is not split (each cut tried clips every
/// triangle and builds two hulls: a 2 000-triangle torus takes 0.4 s to
/// load, a 40 000-triangle one minutes). CAD parts of flat faces, the parts
/// planes split well, have far fewer.
pub const MAX_TRIANGLES: usize = 2_000;

/// Candidate planes: the part's largest distinct face planes, by area.
const MAX_PLANES: usize = 48;

/// Two face planes closer than this (relative to the part's size, in
/// offset; and in direction) are one.
const SAME_PLANE: f64 = 1e-9;

/// The pieces of `part`: at most `max_pieces` point sets (each the clipped
/// surface within its cell), their hulls holding the part; one piece, the
/// part's points, when no cut pays.
pub fn decompose(part: &MeshPart, max_pieces: usize) -> Vec<Vec<V3>> {
    if part.triangles.len() > MAX_TRIANGLES {
        return vec![part.points.clone()];
    }
    let size = spread(&part.points);
    let whole = Piece::new(
        part.triangles
            .iter()
            .filter_map(|t| {
                let corners: Option<Vec<V3>> =
                    t.iter().map(|&i| part.points.get(i).copied()).collect();
                corners
            })
            .collect(),
    );
    let Some(whole) = whole else {
        return vec![part.points.clone()];
    };
    let planes = face_planes(part, size);
    let tolerance = 1e-9 * size;
    let least = MIN_GAIN * whole.volume;
    let no_loss = -tolerance * whole.volume;
    // A closed part's own volume: while the pieces' hulls hold more than
    // it by MIN_GAIN, a cut that takes nothing off may still split off a
    // box (a tote's floor, then its walls one by one: no single cut of a
    // closed ring of walls shrinks a hull).
    let solid = part.volume();
    let is_box = |piece: &Piece| {
        matches!(
            fit(&piece.points()).map(|f| f.form),
            Some(FitForm::Box { .. })
        )
    };
    let best_cut = |piece: &Piece| -> Option<Cut> {
        planes
            .iter()
            .filter_map(|&(normal, offset)| {
                let (a, b) = piece.split(normal, offset, tolerance)?;
                let gain = piece.volume - a.volume - b.volume;
                let rank = if gain >= least {
                    Rank::Gain(gain)
                } else if solid.is_some() && gain >= no_loss {
                    match (is_box(&a), is_box(&b)) {
                        (true, _) => Rank::Slab(a.volume),
                        (_, true) => Rank::Slab(b.volume),
                        _ => return None,
                    }
                } else {
                    return None;
                };
                Some((rank, a, b))
            })
            .max_by(|x, y| x.0.cmp(&y.0))
    };
    let mut pieces: Vec<(Piece, Option<Cut>)> = Vec::new();
    let cut = best_cut(&whole);
    pieces.push((whole, cut));
    while pieces.len() < max_pieces.max(1) {
        let held: f64 = pieces.iter().map(|(p, _)| p.volume).sum();
        let hollow = solid.is_some_and(|v| held > v * (1.0 + MIN_GAIN));
        let Some(i) = (0..pieces.len())
            .filter(|&i| match &pieces[i].1 {
                Some((Rank::Gain(_), ..)) => true,
                Some((Rank::Slab(_), ..)) => hollow,
                None => false,
            })
            .max_by(|&i, &j| {
                let rank = |k: usize| pieces[k].1.as_ref().map(|c| c.0);
                rank(i).cmp(&rank(j))
            })
        else {
            break;
        };
        let Some((_, a, b)) = pieces[i].1.take() else {
            break;
        };
        let (cut_a, cut_b) = (best_cut(&a), best_cut(&b));
        pieces[i] = (a, cut_a);
        pieces.push((b, cut_b));
    }
    pieces.into_iter().map(|(p, _)| p.points()).collect()
}

/// A cut of a piece: how good it is, and the two pieces.
type Cut = (Rank, Piece, Piece);

/// How good a cut is: any cut that takes volume off the hulls before any
/// that only splits off a box; then by the volume taken off, or the box's.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Rank {
    /// Splits off a box of this volume, taking nothing off the hulls.
    Slab(f64),
    /// Takes this much volume off the hulls.
    Gain(f64),
}

impl Eq for Rank {}

impl PartialOrd for Rank {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Rank {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        match (self, other) {
            (Rank::Gain(a), Rank::Gain(b)) | (Rank::Slab(a), Rank::Slab(b)) => a.total_cmp(b),
            (Rank::Gain(_), Rank::Slab(_)) => std::cmp::Ordering::Greater,
            (Rank::Slab(_), Rank::Gain(_)) => std::cmp::Ordering::Less,
        }
    }
}

/// The part's surface within a cell: polygons, and their hull's volume.
struct Piece {
    polygons: Vec<Vec<V3>>,
    volume: f64,
}

impl Piece {
    /// A piece of these polygons, `None` when their points span no volume.
    fn new(polygons: Vec<Vec<V3>>) -> Option<Piece> {
        let points: Vec<V3> = polygons.iter().flatten().copied().collect();
        let volume = hull_volume(&points)?;
        Some(Piece { polygons, volume })
    }

    fn points(&self) -> Vec<V3> {
        self.polygons.iter().flatten().copied().collect()
    }

    /// The piece cut by the plane `normal . x = offset` into the parts
    /// behind it and before it, `None` when the plane leaves either side
    /// without volume (it does not cut the piece).
    fn split(&self, normal: V3, offset: f64, tolerance: f64) -> Option<(Piece, Piece)> {
        // Behind the plane, closed: faces on the plane go there. Before it,
        // open: a polygon joins only with a point strictly before the plane
        // (its points on the plane are then limits of the part's points
        // there); a face on the plane does not, so the piece before a
        // face's plane does not reach back along that face.
        let side = |sign: f64| -> Vec<Vec<V3>> {
            self.polygons
                .iter()
                .filter(|p| sign > 0.0 || p.iter().any(|&x| dot(normal, x) - offset > tolerance))
                .map(|p| clip(p, normal, offset, sign, tolerance))
                .filter(|p| !p.is_empty())
                .collect()
        };
        Some((Piece::new(side(1.0))?, Piece::new(side(-1.0))?))
    }
}

/// The polygon `points` clipped to the half-space `sign (normal . x -
/// offset) <= tolerance` (Sutherland-Hodgman): the points there, and where
/// its edges cross the plane.
fn clip(points: &[V3], normal: V3, offset: f64, sign: f64, tolerance: f64) -> Vec<V3> {
    let height = |p: V3| sign * (dot(normal, p) - offset);
    let mut out = Vec::new();
    for (k, &p) in points.iter().enumerate() {
        let q = points[(k + 1) % points.len()];
        let (hp, hq) = (height(p), height(q));
        if hp <= tolerance {
            out.push(p);
        }
        // An edge from one side to the other beyond the tolerance band: the
        // point where it meets the plane.
        if (hp < -tolerance && hq > tolerance) || (hp > tolerance && hq < -tolerance) {
            let t = hp / (hp - hq);
            out.push([0, 1, 2].map(|i| p[i] + t * (q[i] - p[i])));
        }
    }
    out
}

/// The part's distinct face planes (unit outward normal, offset), the
/// largest by summed area first, at most [`MAX_PLANES`].
fn face_planes(part: &MeshPart, size: f64) -> Vec<(V3, f64)> {
    let mut planes: Vec<(V3, f64, f64)> = Vec::new();
    for t in &part.triangles {
        let [Some(a), Some(b), Some(c)] = t.map(|i| part.points.get(i).copied()) else {
            continue;
        };
        let n = cross(sub(b, a), sub(c, a));
        let twice_area = dot(n, n).sqrt();
        if twice_area <= 0.0 || !twice_area.is_finite() {
            continue;
        }
        let normal = n.map(|x| x / twice_area);
        let offset = dot(normal, a);
        match planes.iter_mut().find(|(m, o, _)| {
            dot(*m, normal) >= 1.0 - SAME_PLANE && (o - offset).abs() <= SAME_PLANE * size.max(1.0)
        }) {
            Some(plane) => plane.2 += twice_area,
            None => planes.push((normal, offset, twice_area)),
        }
    }
    planes.sort_by(|x, y| y.2.total_cmp(&x.2));
    planes
        .into_iter()
        .take(MAX_PLANES)
        .map(|(n, o, _)| (n, o))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::polytope::cloud_hull;

    /// Triangles of a simple counter-clockwise polygon (ear clipping).
    fn triangulate(poly: &[[f64; 2]]) -> Vec<[usize; 3]> {
        let turn = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
            (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
        };
        let mut left: Vec<usize> = (0..poly.len()).collect();
        let mut triangles = Vec::new();
        while left.len() > 3 {
            let n = left.len();
            let ear = (0..n).find(|&i| {
                let (a, b, c) = (left[(i + n - 1) % n], left[i], left[(i + 1) % n]);
                turn(poly[a], poly[b], poly[c]) > 0.0
                    && !left.iter().any(|&j| {
                        j != a
                            && j != b
                            && j != c
                            && turn(poly[a], poly[b], poly[j]) >= 0.0
                            && turn(poly[b], poly[c], poly[j]) >= 0.0
                            && turn(poly[c], poly[a], poly[j]) >= 0.0
                    })
            });
            let Some(i) = ear else { break };
            triangles.push([left[(i + n - 1) % n], left[i], left[(i + 1) % n]]);
            left.remove(i);
        }
        triangles.push([left[0], left[1], left[2]]);
        triangles
    }

    /// A closed prism of the simple polygon `outline` (counter-clockwise
    /// in x, y) from z = -h to h, as a mesh part.
    fn prism(outline: &[[f64; 2]], h: f64) -> MeshPart {
        let n = outline.len();
        let mut points = Vec::new();
        for z in [-h, h] {
            for &[x, y] in outline {
                points.push([x, y, z]);
            }
        }
        let mut triangles = Vec::new();
        for [a, b, c] in triangulate(outline) {
            triangles.push([a, c, b]);
            triangles.push([n + a, n + b, n + c]);
        }
        for k in 0..n {
            let j = (k + 1) % n;
            triangles.push([k, j, n + j]);
            triangles.push([k, n + j, n + k]);
        }
        MeshPart { points, triangles }
    }

    /// Reproducible uniform numbers in `[lo, hi)`.
    fn uniform_from(mut state: u64) -> impl FnMut(f64, f64) -> f64 {
        move |lo, hi| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            lo + (hi - lo) * ((state >> 11) as f64 / (1u64 << 53) as f64)
        }
    }

    fn inside_some_hull(pieces: &[Vec<V3>], x: V3) -> bool {
        pieces.iter().any(|p| {
            let hull = cloud_hull(p).unwrap();
            hull.triangles
                .iter()
                .all(|t| dot(t.normal, x) <= t.offset + 1e-9)
        })
    }

    #[test]
    fn an_l_is_two_boxes_and_its_notch_is_free() {
        // The bay's bracket: an L of 16 x 10 with a 12 x 6 notch.
        let l = prism(
            &[
                [-8.0, -5.0],
                [8.0, -5.0],
                [8.0, -1.0],
                [-4.0, -1.0],
                [-4.0, 5.0],
                [-8.0, 5.0],
            ],
            6.0,
        );
        assert!((l.volume().unwrap() - 88.0 * 12.0).abs() < 1e-9);
        let pieces = decompose(&l, 8);
        assert_eq!(pieces.len(), 2, "{pieces:?}");
        let total: f64 = pieces.iter().map(|p| hull_volume(p).unwrap()).sum();
        assert!((total - 88.0 * 12.0).abs() < 1e-6, "{total}");
        // The notch's middle is in no piece; every point of the L is in one.
        assert!(!inside_some_hull(&pieces, [2.0, 2.0, 0.0]));
        let mut uniform = uniform_from(9);
        for _ in 0..2000 {
            let p = [uniform(-8.0, 8.0), uniform(-5.0, 5.0), uniform(-6.0, 6.0)];
            let in_l = p[1] <= -1.0 || p[0] <= -4.0;
            if in_l {
                assert!(
                    inside_some_hull(&pieces, p),
                    "{p:?} of the L is in no piece"
                );
            }
        }
    }

    /// A tote as one closed solid: a box of half-sizes `(x, y)` and height
    /// `h` with an open top, walls and floor `t` thick.
    fn tote(x: f64, y: f64, h: f64, t: f64) -> MeshPart {
        let ring =
            |hx: f64, hy: f64, z: f64| [[-hx, -hy, z], [hx, -hy, z], [hx, hy, z], [-hx, hy, z]];
        let (xi, yi) = (x - t, y - t);
        let mut points = Vec::new();
        for r in [
            ring(x, y, 0.0),
            ring(x, y, h),
            ring(xi, yi, t),
            ring(xi, yi, h),
        ] {
            points.extend(r);
        }
        // Outer bottom 0-3, outer top 4-7, inner bottom 8-11, inner top 12-15.
        let mut triangles = Vec::new();
        let mut quad = |a: usize, b: usize, c: usize, d: usize| {
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        };
        quad(0, 3, 2, 1);
        quad(8, 9, 10, 11);
        for k in 0..4 {
            let j = (k + 1) % 4;
            quad(k, j, 4 + j, 4 + k);
            quad(4 + k, 4 + j, 12 + j, 12 + k);
            quad(8 + j, 8 + k, 12 + k, 12 + j);
        }
        MeshPart { points, triangles }
    }

    #[test]
    fn a_tote_is_its_floor_and_four_walls() {
        // No single cut of its closed ring of walls shrinks a hull: the
        // floor and the walls are split off as boxes one by one.
        let part = tote(0.2, 0.15, 0.15, 0.01);
        let volume = 0.4 * 0.3 * 0.15 - 0.38 * 0.28 * 0.14;
        assert!((part.volume().unwrap() - volume).abs() < 1e-12);
        let pieces = decompose(&part, 8);
        assert_eq!(pieces.len(), 5, "{pieces:?}");
        for p in &pieces {
            assert!(
                matches!(fit(p).map(|f| f.form), Some(FitForm::Box { .. })),
                "{p:?}"
            );
        }
        let held: f64 = pieces.iter().map(|p| hull_volume(p).unwrap()).sum();
        assert!((held - volume).abs() < 1e-9, "{held} {volume}");
        // The inside is free; every point of the tote is in a piece.
        assert!(!inside_some_hull(&pieces, [0.0, 0.0, 0.05]));
        assert!(!inside_some_hull(&pieces, [0.185, 0.135, 0.02]));
        let mut uniform = uniform_from(17);
        for _ in 0..3000 {
            let p = [uniform(-0.2, 0.2), uniform(-0.15, 0.15), uniform(0.0, 0.15)];
            let inside = p[0].abs() < 0.19 && p[1].abs() < 0.14 && p[2] > 0.01;
            if !inside {
                assert!(
                    inside_some_hull(&pieces, p),
                    "{p:?} of the tote is in no piece"
                );
            }
        }
        // Open (its floor left out), it has no volume to tell it is hollow,
        // and no cut pays: one piece.
        let mut open = part.clone();
        open.triangles.drain(2..4);
        assert_eq!(open.volume(), None);
        assert_eq!(decompose(&open, 8).len(), 1);
    }

    #[test]
    fn convex_parts_stay_whole_and_the_budget_holds() {
        let square = prism(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], 0.5);
        assert_eq!(decompose(&square, 8).len(), 1);
        let octagon: Vec<[f64; 2]> = (0..8)
            .map(|k| {
                let t = std::f64::consts::TAU * k as f64 / 8.0;
                [t.cos(), t.sin()]
            })
            .collect();
        assert_eq!(decompose(&prism(&octagon, 1.0), 8).len(), 1);
        // A comb of five teeth on a bar: with eight pieces the gaps between
        // the teeth are free; with fewer, fewer are; every point of the comb
        // is in a piece whatever the budget.
        let mut comb = vec![[0.0, 0.0], [9.0, 0.0]];
        for k in (0..5).rev() {
            let x = 2.0 * k as f64;
            comb.extend([[x + 1.0, 3.0], [x, 3.0]]);
            if k > 0 {
                comb.extend([[x, 1.0], [x - 1.0, 1.0]]);
            }
        }
        let part = prism(&comb, 0.5);
        assert!(
            (part.volume().unwrap() - 19.0).abs() < 1e-9,
            "the comb is closed"
        );
        let mut uniform = uniform_from(3);
        let samples: Vec<V3> = (0..1500)
            .map(|_| [uniform(0.0, 9.0), uniform(0.0, 3.0), uniform(-0.5, 0.5)])
            .filter(|p| p[1] <= 1.0 || (p[0] % 2.0) <= 1.0)
            .collect();
        for budget in [1, 3, 8] {
            let pieces = decompose(&part, budget);
            assert!(pieces.len() <= budget, "{budget}: {}", pieces.len());
            for &p in &samples {
                assert!(inside_some_hull(&pieces, p), "{budget}: {p:?} in no piece");
            }
            let free = (0..4)
                .filter(|k| !inside_some_hull(&pieces, [2.0 * *k as f64 + 1.5, 2.5, 0.0]))
                .count();
            match budget {
                1 => assert_eq!(free, 0),
                3 => assert!(free >= 1, "{budget}: {free}"),
                _ => assert_eq!(free, 4, "{budget}"),
            }
        }
    }
}
