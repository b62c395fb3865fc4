//! Convex polytopes given by their vertices, and the distance from a point
//! to one by GJK (Gilbert, Johnson and Keerthi 1988; the point query as van
//! den Bergen, "Collision Detection in Interactive 3D Environments", 2004,
//! ch. 4, writes it).
//!
//! A hull is the convex hull of 4 to [`MAX_HULL_VERTICES`] points in its
//! obstacle's own frame. Its vertices are kept once, in the scenario's hull
//! list (at most [`MAX_HULLS`]), and an obstacle of shape
//! [`super::Shape::Convex`] names its hull by index, so a board's obstacle
//! table does not grow by a vertex array per obstacle (64 obstacles of 32
//! inline vertices would take 48 KiB in two copies).
//!
//! [`Hull::distance`] first tries the hull's faces and edges (found once,
//! by brute force, when the hull is built: at most [`MAX_HULL_FACES`] and
//! [`MAX_HULL_EDGES`]): the highest face's plane and its neighbours' planes
//! give the distance when `x` is over the face, and otherwise the edge to
//! the neighbour whose plane `x` is farthest beyond (or that edge's end) is
//! certified the closest point by its Voronoi region (`Hull::by_faces`).
//! With 8 faces or more, the highest face is sought only among the few
//! that sampling found highest in `x`'s direction cell (3 of the prism's
//! 10 in each cell): any face's height bounds the distance below, so an
//! answer holds whichever face it starts from, and a face the sampling
//! missed only sends a query to GJK. On the 16-vertex prism of
//! `BENCHMARKS.md` every query outside is answered so, at under half GJK's
//! cost (about 450 M4F instructions a pair against 1 080). Where that
//! certifies nothing (inside, a hull beyond the limits, rounding at a
//! region's border) GJK
//! answers: each iteration takes the vertex farthest along the search
//! direction (the support, one dot product a vertex) and the closest point
//! of the simplex of at most four support points found so far (Ericson, "Real-Time
//! Collision Detection", 2005, 5.1.5-5.1.6, by Voronoi regions). It stops
//! when the support no longer moves the bound by more than f32 rounding, or
//! after [`MAX_GJK_ITERATIONS`]: the work per query is bounded. It returns
//! the distance `|x - v|` to the closest point `v` found (an upper bound,
//! exact at convergence), the unit normal `(x - v) / |x - v|` (the
//! distance's exact gradient), and the lower bound `(x - w) . n` from the
//! last support `w` (no point of the hull lies beyond the plane through `w`
//! normal to `n`), which conservative advancement takes. Inside the hull
//! the distance is 0 and the normal points away from the vertices' mean: a
//! depth inside would need the hull's faces (EPA), and the planner never
//! lets a point in.
//!
//! Written here, not taken from `parry3d`: parry's point queries need its
//! `alloc` shapes (`ConvexPolyhedron` holds `Vec`s) and are written for its
//! own f32 rounding, so a board's answer and the host's would not be tied
//! to one implementation; this one (GJK and the faces) is 500 lines and
//! its cost is in BENCHMARKS.md. The host's checker measures hulls
//! independently, by their enumerated faces in f64 (`host-sim/src/polytope.rs`).

use crate::math::{max, min, norm, sqrt_inline as sqrt, vec3, Vec3};

/// Most hulls a scenario holds.
pub const MAX_HULLS: usize = 8;
/// Most vertices a hull has.
pub const MAX_HULL_VERTICES: usize = 32;
/// Fewest vertices a hull has (a tetrahedron).
pub const MIN_HULL_VERTICES: usize = 4;
/// Most GJK iterations per distance query. Each adds a hull vertex that
/// strictly improves the bound, so in exact arithmetic the vertex count
/// bounds them; in f32 it ends at rounding well before this.
pub const MAX_GJK_ITERATIONS: usize = 24;

/// Most faces (distinct supporting planes through three vertices) a
/// hull's topology holds: a box has 6, a 16-vertex prism 10, a 32-vertex
/// 16-gon prism 18. A hull with more is measured by GJK alone.
pub const MAX_HULL_FACES: usize = 32;
/// Most edges (vertex pairs on two faces) a hull's topology holds: a box
/// has 12, a 16-vertex prism 24, a 32-vertex 16-gon prism 48.
pub const MAX_HULL_EDGES: usize = 48;

/// How far (relative to the hull's largest vertex spread) a vertex may lie
/// off a face's plane and still be on it, and how far beyond the planes a
/// face's projection may fall and still be taken: far above f32 rounding,
/// far below any margin.
const TOPOLOGY_TOLERANCE: f32 = 1.0e-5;

/// Direction cells of the support's candidate lists: the 6 faces of the
/// cube of directions, each cut in 4 by the signs of its other two axes.
const DIRECTION_CELLS: usize = 24;

/// Fewest vertices for which the support tries only its direction's cell's
/// candidates: a candidate costs about 21 M4F instructions against 12.5 a
/// vertex for the plain scan, and finding the cell about 30, so an 8-vertex
/// box is cheaper scanned (BENCHMARKS.md has the counts).
const CELL_MIN_VERTICES: usize = 12;

/// Fewest faces for which `Hull::highest_face` tries only its cell's
/// candidates: a candidate costs about 22 M4F instructions against 14.5 a
/// face for the plain scan, and finding the cell about 25, so a box's six
/// faces are cheaper scanned (419 against 397 a query); the 16-vertex
/// prism's 10 faces (3 candidates a cell) and the 32-vertex prism's 18 are
/// not.
const CELL_MIN_FACES: usize = 8;

/// How far (relative to the hull's largest coordinate) one vertex must beat
/// another at every corner of a direction cell for the other to be left out
/// of the cell's candidates: 45 times the rounding of the support's f32 dot
/// products (at most `7.2e-7 |d|_1 M` between two of them, and a direction
/// `d` of a cell is a sum of its corners with `|d|_1` at most 3 times the
/// sum of their weights), so no vertex left out can be the support, ties
/// included, as f32 computes it.
const CELL_MARGIN: f32 = 1.0e-4;

/// Smallest accepted volume of a hull's largest tetrahedron, relative to
/// the cube of its largest vertex spread: below it the hull is flat.
const MIN_RELATIVE_VOLUME: f32 = 1.0e-6;

/// Why a hull's vertices were rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum HullError {
    /// Fewer than [`MIN_HULL_VERTICES`] vertices.
    TooFewVertices,
    /// More than [`MAX_HULL_VERTICES`] vertices.
    TooManyVertices {
        /// The most a hull takes.
        capacity: usize,
    },
    /// A coordinate is NaN or infinite.
    NotFinite,
    /// A coordinate beyond [`super::MAX_EXTENT`].
    OutOfRange,
    /// The vertices span no volume (all on a plane, a line or a point), or
    /// the hull is thinner than [`super::MIN_SEMI_AXIS`] across some axis.
    Flat,
}

impl core::fmt::Display for HullError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            HullError::TooFewVertices => write!(
                f,
                "fewer than {MIN_HULL_VERTICES} vertices (a hull needs a volume)"
            ),
            HullError::TooManyVertices { capacity } => {
                write!(f, "more than {capacity} vertices")
            }
            HullError::NotFinite => f.write_str("a vertex is not finite"),
            HullError::OutOfRange => write!(
                f,
                "a vertex farther than {} from the obstacle's centre",
                super::MAX_EXTENT
            ),
            HullError::Flat => f.write_str("the vertices are coplanar (no volume)"),
        }
    }
}

/// A validated hull: its vertices in the obstacle's frame and what the pair
/// code needs of it.
#[derive(Clone, Debug, PartialEq)]
pub struct Hull {
    vertices: heapless::Vec<Vec3, MAX_HULL_VERTICES>,
    /// Half-extents of the smallest box about the frame's origin that holds
    /// the hull, length units.
    half_box: Vec3,
    /// The vertices' mean.
    mean: Vec3,
    /// Half the hull's smallest width along the frame's axes, length units.
    half_width: f32,
    /// For each direction cell ([`direction_cell`]), the vertices (bit `i`
    /// for vertex `i`) that may be the support of a direction in it: every
    /// vertex no single other vertex beats over the whole cell by
    /// [`CELL_MARGIN`].
    candidates: [u32; DIRECTION_CELLS],
    /// For each direction cell of `x - mean` ([`direction_cell`]), the
    /// faces (bit `f` for face `f`) `Hull::highest_face` tries: those found
    /// highest at some sampled point outside the hull in the cell
    /// ([`face_candidates`]). Zero when the hull has no faces.
    face_candidates: [u32; DIRECTION_CELLS],
    /// The faces, for [`Hull::distance`]'s first try: the first
    /// `face_count` (none when the hull has more than [`MAX_HULL_FACES`]
    /// or [`MAX_HULL_EDGES`]), the rest zero. A fixed array: the queries
    /// index it by a face number masked into range, no bounds test.
    face_planes: [Face; MAX_HULL_FACES],
    /// See `face_planes`.
    face_count: u8,
    /// Each face's sides, face by face: face `f`'s are
    /// `face_sides[face_start[f]..face_start[f + 1]]`. A side carries its
    /// edge's ends and the face across it, so the query reads no edge list
    /// (the edges themselves are not kept).
    face_sides: [Side; 2 * MAX_HULL_EDGES],
    /// See `face_sides`.
    face_start: [u8; MAX_HULL_FACES + 1],
    /// Each vertex's neighbours (the far ends of its edges), vertex by
    /// vertex, as `face_sides`.
    vertex_neighbours: [u8; 2 * MAX_HULL_EDGES],
    /// See `vertex_neighbours`.
    vertex_start: [u8; MAX_HULL_VERTICES + 1],
    /// [`TOPOLOGY_TOLERANCE`] times the largest vertex spread, length units.
    tolerance: f32,
}

/// A face: its plane `normal . p = offset` (unit outward normal; the offset
/// the largest `normal . v` of the vertices, so every vertex is on or
/// behind it as f32 computes it).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Face {
    normal: Vec3,
    offset: f32,
}

impl Face {
    /// An unused slot.
    const NONE: Face = Face {
        normal: Vec3::new(0.0, 0.0, 0.0),
        offset: 0.0,
    };

    /// Whether `v` is on the face's plane, within `tolerance` (no vertex is
    /// beyond it).
    fn holds(&self, v: &Vec3, tolerance: f32) -> bool {
        self.offset - self.normal.dot(v) <= tolerance
    }
}

/// An edge: its two vertices and its two faces (indices), while the
/// topology is built.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Edge {
    ends: [u8; 2],
    faces: [u8; 2],
}

/// One side of a face: its edge's two vertices and the face across it
/// (indices).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Side {
    ends: [u8; 2],
    across: u8,
}

/// The distance from a point to a hull, [`Hull::distance`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HullDistance {
    /// `|x - v|`, `v` the closest hull point found: an upper bound on the
    /// distance, exact at convergence; 0 inside; NaN for a point not finite.
    pub distance: f32,
    /// The unit outward normal `(x - v) / |x - v|`, the gradient of the
    /// distance (inside: away from the vertices' mean).
    pub normal: Vec3,
    /// A lower bound on the distance, `<= distance` (0 inside).
    pub lower_bound: f32,
}

impl Hull {
    /// Validates `vertices` (the obstacle's frame, length units): 4 to
    /// [`MAX_HULL_VERTICES`] finite points within `MAX_EXTENT` of the origin
    /// that span a volume. Vertices inside the hull are kept (they cost a
    /// dot product a query and change no answer).
    pub fn new(vertices: &[[f32; 3]]) -> Result<Self, HullError> {
        let mut hull = Hull::empty();
        hull.set(vertices)?;
        Ok(hull)
    }

    /// A hull of no vertices (a placeholder: [`Hull::set`] fills it).
    pub fn empty() -> Self {
        Hull {
            vertices: heapless::Vec::new(),
            half_box: Vec3::zeros(),
            mean: Vec3::zeros(),
            half_width: 0.0,
            candidates: [0; DIRECTION_CELLS],
            face_candidates: [0; DIRECTION_CELLS],
            face_planes: [Face::NONE; MAX_HULL_FACES],
            face_count: 0,
            face_sides: [Side::default(); 2 * MAX_HULL_EDGES],
            face_start: [0; MAX_HULL_FACES + 1],
            vertex_neighbours: [0; 2 * MAX_HULL_EDGES],
            vertex_start: [0; MAX_HULL_VERTICES + 1],
            tolerance: 0.0,
        }
    }

    /// [`Hull::new`] in place (a hull is over a kilobyte: a board builds
    /// its hulls where they live, never on its stack). On an error the
    /// hull is left empty.
    pub fn set(&mut self, vertices: &[[f32; 3]]) -> Result<(), HullError> {
        self.vertices.clear();
        self.face_planes = [Face::NONE; MAX_HULL_FACES];
        self.face_count = 0;
        if vertices.len() < MIN_HULL_VERTICES {
            return Err(HullError::TooFewVertices);
        }
        if vertices.len() > MAX_HULL_VERTICES {
            return Err(HullError::TooManyVertices {
                capacity: MAX_HULL_VERTICES,
            });
        }
        if !vertices.iter().flatten().all(|c| c.is_finite()) {
            return Err(HullError::NotFinite);
        }
        if !vertices
            .iter()
            .flatten()
            .all(|c| c.abs() <= super::MAX_EXTENT)
        {
            return Err(HullError::OutOfRange);
        }
        let first = vec3(vertices.first().copied().unwrap_or_default());
        let (mut low, mut high) = (first, first);
        let mut sum = Vec3::zeros();
        for v in vertices {
            let v = vec3(*v);
            low = low.inf(&v);
            high = high.sup(&v);
            sum += v;
            let _ = self.vertices.push(v);
        }
        let widths = high - low;
        let half_width = 0.5 * widths.min();
        if half_width < 0.5 * super::MIN_SEMI_AXIS || !spans_a_volume(&self.vertices, widths.max())
        {
            self.vertices.clear();
            return Err(HullError::Flat);
        }
        self.half_box = low.abs().sup(&high.abs());
        self.mean = sum / self.vertices.len() as f32;
        self.half_width = half_width;
        self.candidates = candidates(&self.vertices, CELL_MARGIN * self.half_box.max());
        self.tolerance = TOPOLOGY_TOLERANCE * widths.max();
        let (mut faces, mut edges) = (heapless::Vec::new(), heapless::Vec::new());
        if topology(&self.vertices, self.tolerance, &mut faces, &mut edges).is_none() {
            faces.clear();
            edges.clear();
        }
        for (slot, face) in self.face_planes.iter_mut().zip(&faces) {
            *slot = *face;
        }
        self.face_count = faces.len() as u8;
        self.face_candidates = if faces.len() < CELL_MIN_FACES {
            [0; DIRECTION_CELLS]
        } else {
            face_candidates(&faces, &self.mean, self.tolerance)
        };
        edges_by(
            faces.len(),
            &edges,
            |edge| edge.faces,
            |edge, face| Side {
                ends: edge.ends,
                across: other(edge.faces, face),
            },
            &mut self.face_sides,
            &mut self.face_start,
        );
        edges_by(
            self.vertices.len(),
            &edges,
            |edge| edge.ends,
            |edge, vertex| other(edge.ends, vertex),
            &mut self.vertex_neighbours,
            &mut self.vertex_start,
        );
        Ok(())
    }

    /// The vertices, the obstacle's frame.
    pub fn vertices(&self) -> &[Vec3] {
        &self.vertices
    }

    /// Half-extents of the smallest box about the frame's origin holding the
    /// hull, length units.
    pub fn half_box(&self) -> Vec3 {
        self.half_box
    }

    /// Half the hull's smallest width along its frame's axes, length units:
    /// the `rho` of its potential (the inradius when the hull is a box).
    pub fn half_width(&self) -> f32 {
        self.half_width
    }

    /// The vertex farthest along `direction` (the hull's support point)
    /// and its index: the first of the farthest, by index, as a scan of
    /// every vertex finds it. Only the direction's cell's candidates are
    /// tried (a scan of all for a direction zero or not finite).
    // Out of line: inlined at its two calls it saved 46 M4F instructions a
    // 16-vertex query and took 450 bytes of flash the board has not got.
    #[inline(never)]
    fn support(&self, direction: &Vec3) -> (u8, Vec3) {
        let vertices = &self.vertices[..];
        let dot = |v: &Vec3| v.x * direction.x + v.y * direction.y + v.z * direction.z;
        let (mut best, mut best_dot) = (0, f32::NEG_INFINITY);
        let cell = if vertices.len() < CELL_MIN_VERTICES {
            None
        } else {
            direction_cell(direction).and_then(|cell| self.candidates.get(cell))
        };
        if let Some(&candidates) = cell {
            // Ascending, as the scan: the first of the farthest.
            let mut mask = candidates;
            while mask != 0 {
                let i = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                if let Some(v) = vertices.get(i) {
                    let d = dot(v);
                    if d > best_dot {
                        (best, best_dot) = (i, d);
                    }
                }
            }
        } else {
            // Every vertex, two a pass, for half the loop's tests.
            let mut pairs = vertices.chunks_exact(2);
            let mut i = 0;
            for pair in &mut pairs {
                if let [a, b] = pair {
                    let (da, db) = (dot(a), dot(b));
                    if da > best_dot {
                        (best, best_dot) = (i, da);
                    }
                    if db > best_dot {
                        (best, best_dot) = (i + 1, db);
                    }
                }
                i += 2;
            }
            if let [c] = pairs.remainder() {
                if dot(c) > best_dot {
                    best = i;
                }
            }
        }
        match vertices.get(best) {
            Some(v) => (best as u8, *v),
            None => (0, Vec3::zeros()),
        }
    }

    /// The distance from `x` (the obstacle's frame) to the hull: by its
    /// faces and edges when it has them and they give a certified answer
    /// (`Hull::by_faces`), else by GJK (`Hull::by_gjk`).
    pub fn distance(&self, x: &Vec3) -> HullDistance {
        self.by_faces(x).unwrap_or_else(|| self.by_gjk(x))
    }

    /// The faces (none without a topology).
    fn faces(&self) -> &[Face] {
        self.face_planes
            .get(..self.face_count as usize)
            .unwrap_or(&[])
    }

    /// Face `f`'s plane, `f` masked into the array (a face number the
    /// topology gave is below the count, and so in range).
    #[inline(always)]
    fn face(&self, f: usize) -> &Face {
        &self.face_planes[f % MAX_HULL_FACES]
    }

    /// Whether the hull has a topology (`Hull::by_faces` can answer).
    pub fn has_faces(&self) -> bool {
        self.face_count > 0
    }

    /// The distance from `x` outside the hull by its faces and edges, when
    /// that is certified; `None` sends the query to GJK (inside, a point
    /// not finite, no topology, or an answer no check certified).
    ///
    /// Every face's height `h_f = n_f . x - offset_f` bounds the distance
    /// below (the hull is behind each plane). If `x`'s projection on the
    /// highest face's plane (the highest of its cell's candidates,
    /// [`Hull::highest_face`]) is behind every neighbour's plane (`h_g - h*
    /// (n_g . n*)` at most the tolerance), it is on the hull and the
    /// distance is `h*`, the normal `n*`: whichever face that is, its
    /// height is a lower bound and its projection a hull point at that
    /// distance. Otherwise the closest point is on the edge
    /// to the neighbour whose plane the projection is farthest beyond, when
    /// `Hull::certified_side` certifies it (where `x` is past two
    /// neighbours' planes, that edge's end is the closest point more often
    /// than the first's: every query round the prism of `BENCHMARKS.md`
    /// against 53 in 62).
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    fn by_faces(&self, x: &Vec3) -> Option<HullDistance> {
        let (top, highest) = self.highest_face(x);
        // Inside, NaN or no faces: GJK's answer.
        if !(top > 0.0) {
            return None;
        }
        let face = self.face(highest);
        // The face's polygon is its plane behind its neighbours' planes
        // (the faces across its sides): test those alone, at `x`'s
        // projection `y` on the face's plane.
        let y = x - face.normal * top;
        let Some(side) = self.farthest_beyond(highest, &y) else {
            return Some(HullDistance {
                distance: top,
                normal: face.normal,
                lower_bound: top,
            });
        };
        self.certified_side(x, side, top)
    }

    /// The side of face `f` whose neighbour's plane `y` (on the face's
    /// plane) is farthest beyond, by more than the tolerance; `None` when
    /// `y` is on the face.
    fn farthest_beyond(&self, f: usize, y: &Vec3) -> Option<&Side> {
        let (mut beyond, mut farthest) = (None, self.tolerance);
        let past = |side: &Side| {
            let g = self.face(side.across as usize);
            g.normal.dot(y) - g.offset
        };
        // Two sides a pass, as the faces in `Hull::highest_face`.
        let mut pairs = self.sides_of(f).chunks_exact(2);
        for pair in &mut pairs {
            if let [a, b] = pair {
                let (past_a, past_b) = (past(a), past(b));
                if past_a > farthest {
                    (beyond, farthest) = (Some(a), past_a);
                }
                if past_b > farthest {
                    (beyond, farthest) = (Some(b), past_b);
                }
            }
        }
        if let [c] = pairs.remainder() {
            if past(c) > farthest {
                beyond = Some(c);
            }
        }
        beyond
    }

    /// The height of `x` over the face it is highest over of those its
    /// direction cell from the mean names ([`Hull::face_candidates`]; every
    /// face for `x` at the mean or not finite), and that face (the first
    /// of the highest; `-inf` and 0 for no faces or `x` not finite). Every
    /// face's height is a lower bound on the distance, so the answers built
    /// on it hold whichever face it is (see [`Hull::by_faces`]).
    fn highest_face(&self, x: &Vec3) -> (f32, usize) {
        let height = |face: &Face| face.normal.dot(x) - face.offset;
        let (mut top, mut highest) = (f32::NEG_INFINITY, 0);
        // A hull of fewer faces has no cells (all zero): tested first so
        // that it does not pay for finding its cell.
        let candidates = if self.face_count as usize >= CELL_MIN_FACES {
            self.face_candidates
                .get(any_cell(&(x - self.mean)))
                .copied()
                .unwrap_or(0)
        } else {
            0
        };
        if candidates != 0 {
            // Ascending, as the scan: the first of the highest.
            let mut mask = candidates;
            while mask != 0 {
                let f = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                let h = height(self.face(f));
                if h > top {
                    (top, highest) = (h, f);
                }
            }
            return (top, highest);
        }
        // Two faces a pass, as the support's scan: half the loop's counting
        // (37 M4F instructions a 10-face query).
        let mut pairs = self.faces().chunks_exact(2);
        let mut f = 0;
        for pair in &mut pairs {
            if let [a, b] = pair {
                let (height_a, height_b) = (height(a), height(b));
                if height_a > top {
                    (top, highest) = (height_a, f);
                }
                if height_b > top {
                    (top, highest) = (height_b, f + 1);
                }
            }
            f += 2;
        }
        if let [c] = pairs.remainder() {
            let height_c = height(c);
            if height_c > top {
                (top, highest) = (height_c, f);
            }
        }
        (top, highest)
    }

    /// The point closest to `x` of the edge between vertices `ends`, its
    /// squared distance, and the end vertex it is (`None` inside the edge).
    fn closest_on(&self, x: &Vec3, ends: [u8; 2]) -> Option<(Vec3, f32, Option<u8>)> {
        let a = *self.vertices.get(ends[0] as usize)?;
        let b = *self.vertices.get(ends[1] as usize)?;
        let ab = b - a;
        let along = (x - a).dot(&ab);
        let length_sq = ab.dot(&ab);
        let (q, end) = if along <= 0.0 {
            (a, Some(ends[0]))
        } else if along >= length_sq {
            (b, Some(ends[1]))
        } else {
            (a + ab * (along / length_sq), None)
        };
        let r = x - q;
        Some((q, r.dot(&r), end))
    }

    /// Vertex `v`'s neighbours (the far ends of its edges).
    fn neighbours_of(&self, v: usize) -> &[u8] {
        let start = self.vertex_start.get(v).copied().unwrap_or(0) as usize;
        let end = self.vertex_start.get(v + 1).copied().unwrap_or(0) as usize;
        self.vertex_neighbours.get(start..end).unwrap_or(&[])
    }

    /// Face `f`'s sides.
    fn sides_of(&self, f: usize) -> &[Side] {
        // `f` is below MAX_HULL_FACES: the remainder changes nothing, and
        // the optimiser sees both look-ups in range (no test, no branch).
        let f = f % MAX_HULL_FACES;
        let end = self.face_start.get(f + 1).map_or(0, |&end| end as usize);
        let end = end.min(self.face_sides.len());
        let start = self.face_start.get(f).map_or(0, |&start| start as usize);
        self.face_sides.get(start.min(end)..end).unwrap_or(&[])
    }

    /// The distance from `x` to the closest point `q` of the highest
    /// face's `side`, the side whose plane `x`'s projection `y` on the face
    /// is beyond, when `q` is certified the hull's closest point. Inside the
    /// edge, by that side: `x - q = a n_1 + b n_2` (`n_1` the face's normal,
    /// `n_2` the face's across) is in the edge's Voronoi region when `a`
    /// and `b` are not negative, and with the faces' heights `h_1 = n_1 .
    /// (x - q)` and `h_2`, `c = n_1 . n_2`: `b (1 - c^2) = h_2 - c h_1 = n_2
    /// . y - offset_2`, positive as the side was chosen, and `a (1 - c^2) =
    /// h_1 - c h_2`, not negative since `h_1 >= h_2` and `b > 0`: known
    /// when every face was scanned, and tested when only the cell's
    /// candidates were (the face across may be higher). At a vertex, when
    /// `x - q` makes no acute angle with any of the vertex's edges (they
    /// span the hull's directions from a vertex, so no hull point is
    /// nearer). `top`, the highest face's height, is a
    /// lower bound whatever the answer.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    fn certified_side(&self, x: &Vec3, side: &Side, top: f32) -> Option<HullDistance> {
        let (q, distance_sq, end) = self.closest_on(x, side.ends)?;
        let r = x - q;
        if !(distance_sq > 0.0) {
            return None;
        }
        let distance = sqrt(distance_sq);
        // Inside the edge: `h_1 >= h_2`, the face across no higher (with
        // `CELL_MIN_FACES` faces or more, the face `top` is from is the
        // highest of its cell's candidates, not always of every face).
        if end.is_none()
            && self.face_count as usize >= CELL_MIN_FACES
            && !{
                let g = self.face(side.across as usize);
                g.normal.dot(x) - g.offset <= top
            }
        {
            return None;
        }
        // At a vertex `q`: `x - q` makes no acute angle with any of its
        // edges (they span the hull's directions from `q`).
        if let Some(end) = end {
            let certified = self.neighbours_of(end as usize).iter().all(|&far| {
                self.vertices
                    .get(far as usize)
                    .is_some_and(|w| r.dot(&(w - q)) <= self.tolerance * distance)
            });
            if !certified {
                return None;
            }
        }
        Some(HullDistance {
            distance,
            normal: r / distance,
            // Certified: the distance to rounding (a few ulps below it).
            lower_bound: min(max(top, distance * (1.0 - 4.0 * f32::EPSILON)), distance),
        })
    }

    /// The distance from `x` (the obstacle's frame) to the hull, by GJK:
    /// see the module docs. At most [`MAX_GJK_ITERATIONS`] supports.
    // `!(v_sq > 0.0)`: NaN (a point not finite) ends the search too.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    fn by_gjk(&self, x: &Vec3) -> HullDistance {
        // The simplex holds support points relative to `x` (the Minkowski
        // difference hull - x), so the closest point to the origin is
        // sought, and the vertices they are (to stop when one comes back).
        // Start from the vertex farthest toward `x` from the mean.
        let (first, vertex) = self.support(&(x - self.mean));
        // Slots past `count` are never read: filled with the first point
        // rather than cleared (a call to `memclr` a query).
        let mut simplex = Simplex {
            points: [vertex - x; 4],
            vertices: [first; 4],
            count: 1,
        };
        let mut v = simplex.points[0];
        // The last support's `w . v` and `|v|^2`: every hull point q has
        // (q - x) . v >= w . v, so w . v / |v| bounds the distance below.
        let (mut last_vw, mut last_v_sq) = (0.0, 1.0);
        for _ in 0..MAX_GJK_ITERATIONS {
            let v_sq = v.dot(&v);
            if !(v_sq > 0.0) {
                break;
            }
            let (id, vertex) = self.support(&-v);
            let w = vertex - x;
            let vw = v.dot(&w);
            (last_vw, last_v_sq) = (vw, v_sq);
            // No progress beyond rounding (v is the closest point), or a
            // vertex the simplex holds came back (rounding would cycle).
            if v_sq - vw <= 4.0 * f32::EPSILON * v_sq
                || simplex
                    .vertices
                    .iter()
                    .take(simplex.count)
                    .any(|&k| k == id)
            {
                break;
            }
            match simplex.add(id, w) {
                Some(closest) => v = closest,
                None => {
                    // The origin is in the tetrahedron: x is inside.
                    v = Vec3::zeros();
                    break;
                }
            }
        }
        let v_sq = v.dot(&v);
        if v_sq.is_nan() {
            // A point not finite: no distance (the pair code drops it, as it
            // drops such a point for every shape).
            return HullDistance {
                distance: f32::NAN,
                normal: Vec3::zeros(),
                lower_bound: f32::NAN,
            };
        }
        if !(v_sq > 0.0) {
            return self.inside(x);
        }
        let distance = sqrt(v_sq);
        let lower = last_vw / sqrt(last_v_sq);
        HullDistance {
            distance,
            normal: -v / distance,
            lower_bound: if lower > 0.0 {
                if lower < distance {
                    lower
                } else {
                    distance
                }
            } else {
                0.0
            },
        }
    }

    /// [`Hull::distance`] for a point inside.
    fn inside(&self, x: &Vec3) -> HullDistance {
        let out = x - self.mean;
        let length = sqrt(out.dot(&out));
        HullDistance {
            distance: 0.0,
            normal: if length > 0.0 {
                out / length
            } else {
                Vec3::z()
            },
            lower_bound: 0.0,
        }
    }
}

/// The one of `pair` that is not `one` (an edge's other face, or end).
fn other(pair: [u8; 2], one: u8) -> u8 {
    if pair[0] == one {
        pair[1]
    } else {
        pair[0]
    }
}

/// The cell of a direction: the cube face of its largest component (ties
/// to the lower axis) and the signs of the other two, a closed cone each
/// (a zero component, either sign, lies on both sides' cones); `None` for
/// a direction zero or not finite. On the bits: for floats not NaN the
/// order of `|x|` is the integer order of `x`'s bits without the sign, and
/// integer compares need no move of the FPU's flags.
#[inline(always)]
fn direction_cell(d: &Vec3) -> Option<usize> {
    const MAGNITUDE: u32 = 0x7fff_ffff;
    const INFINITY: u32 = 0x7f80_0000;
    let (x, y, z) = (d.x.to_bits(), d.y.to_bits(), d.z.to_bits());
    let (ax, ay, az) = (x & MAGNITUDE, y & MAGNITUDE, z & MAGNITUDE);
    if ax >= INFINITY || ay >= INFINITY || az >= INFINITY || (ax | ay | az) == 0 {
        return None;
    }
    Some(any_cell(d))
}

/// [`direction_cell`] without its test: a cell for any bits (a zero
/// direction's, or a NaN's, is some cell), for callers whose answer holds
/// from any cell.
#[inline(always)]
fn any_cell(d: &Vec3) -> usize {
    const MAGNITUDE: u32 = 0x7fff_ffff;
    let (x, y, z) = (d.x.to_bits(), d.y.to_bits(), d.z.to_bits());
    let (ax, ay, az) = (x & MAGNITUDE, y & MAGNITUDE, z & MAGNITUDE);
    let (axis, major, u, w) = if ax >= ay && ax >= az {
        (0, x, y, z)
    } else if ay >= az {
        (1, y, x, z)
    } else {
        (2, z, x, y)
    };
    axis * 8 + (major >> 31) as usize * 4 + (u >> 31) as usize * 2 + (w >> 31) as usize
}

/// The hull's faces and edges, or `None` when it has more than
/// [`MAX_HULL_FACES`] or [`MAX_HULL_EDGES`]. A face is the plane through
/// three vertices with every vertex within `tolerance` behind it (its
/// offset then the largest `normal . v`), found once however many of its
/// vertices' triples give it (a triple all on a face found is that face);
/// an edge is a vertex pair within `tolerance` of two faces' planes; `None` too when they do not make a polytope's
/// boundary (see the end). Brute force, at most 4 960 triples and 496 pairs
/// for 32 vertices, once when the hull is built; a wrong or missing face
/// or edge can only send a query to GJK or take a lower bound below the
/// distance (see [`Hull::by_faces`]).
// `!(length > ..)`: a NaN length is too thin too.
#[allow(clippy::neg_cmp_op_on_partial_ord)]
fn topology(
    vertices: &[Vec3],
    tolerance: f32,
    faces: &mut heapless::Vec<Face, MAX_HULL_FACES>,
    edges: &mut heapless::Vec<Edge, MAX_HULL_EDGES>,
) -> Option<()> {
    for (i, &a) in vertices.iter().enumerate() {
        for (j, &b) in vertices.iter().enumerate().skip(i + 1) {
            for &c in vertices.iter().skip(j + 1) {
                let cross = (b - a).cross(&(c - a));
                let length = sqrt(cross.dot(&cross));
                // A triangle too thin to give its plane's direction.
                if !(length > tolerance * max(norm(&(b - a)), norm(&(c - a)))) {
                    continue;
                }
                let unit = cross / length;
                let (mut low, mut high) = (0.0f32, 0.0f32);
                for v in vertices {
                    let side = unit.dot(&(v - a));
                    low = min(low, side);
                    high = max(high, side);
                    if low < -tolerance && high > tolerance {
                        break;
                    }
                }
                let normal = if high <= tolerance {
                    unit
                } else if low >= -tolerance {
                    -unit
                } else {
                    continue;
                };
                // The same facet from another three of its vertices: all
                // three on a face found (by their distances, not the
                // normals': two facets may meet at a very flat edge).
                if faces.iter().any(|f| {
                    f.normal.dot(&normal) > 0.0 && [a, b, c].iter().all(|v| f.holds(v, tolerance))
                }) {
                    continue;
                }
                let offset = vertices
                    .iter()
                    .fold(f32::NEG_INFINITY, |m, v| max(m, normal.dot(v)));
                faces.push(Face { normal, offset }).ok()?;
            }
        }
    }
    for (i, a) in vertices.iter().enumerate() {
        for (j, b) in vertices.iter().enumerate().skip(i + 1) {
            let mut shared = [0u8; 2];
            let mut count = 0;
            for (f, face) in faces.iter().enumerate() {
                if face.holds(a, tolerance) && face.holds(b, tolerance) {
                    if let Some(slot) = shared.get_mut(count) {
                        *slot = f as u8;
                    }
                    count += 1;
                }
            }
            // On three faces or more: the tolerance joined what is not one
            // edge; the hull is left to GJK.
            if count > 2 {
                return None;
            }
            if count == 2 {
                edges
                    .push(Edge {
                        ends: [i as u8, j as u8],
                        faces: shared,
                    })
                    .ok()?;
            }
        }
    }
    // A polytope's boundary: every face a polygon of at least three edges,
    // and Euler's V - E + F = 2 (V the vertices on three faces or more; a
    // vertex midway along an edge or inside a face breaks it, and the
    // hull is left to GJK).
    let corners = vertices
        .iter()
        .filter(|v| faces.iter().filter(|f| f.holds(v, tolerance)).count() >= 3)
        .count();
    let sides_ok = (0..faces.len()).all(|f| {
        edges
            .iter()
            .filter(|edge| edge.faces.contains(&(f as u8)))
            .count()
            >= 3
    });
    if !sides_ok || corners + faces.len() != edges.len() + 2 {
        return None;
    }
    Some(())
}

/// What each face (or vertex) sees of its edges, face by face: `of(edge)`
/// names the two an edge belongs to (its faces, or its ends), `seen(edge,
/// k)` is what the `k`-th of `count` keeps of it; `start[k]..start[k + 1]`
/// indexes `list` for the `k`-th.
fn edges_by<T: Copy + Default, const S: usize>(
    count: usize,
    edges: &[Edge],
    of: impl Fn(&Edge) -> [u8; 2],
    seen: impl Fn(&Edge, u8) -> T,
    list: &mut [T; 2 * MAX_HULL_EDGES],
    start: &mut [u8; S],
) {
    list.fill(T::default());
    let count = count.min(S.saturating_sub(1));
    let mut next = 0usize;
    for k in 0..count {
        if let Some(slot) = start.get_mut(k) {
            *slot = next as u8;
        }
        for edge in edges {
            if of(edge).contains(&(k as u8)) {
                if let Some(slot) = list.get_mut(next) {
                    *slot = seen(edge, k as u8);
                    next += 1;
                }
            }
        }
    }
    for slot in start.iter_mut().skip(count) {
        *slot = next as u8;
    }
}

/// Each direction cell's support candidates: vertex `i` is left out of a
/// cell when some vertex `j` has `c . (v_j - v_i) > margin` at each of the
/// cell's four corner directions `c` (then at every direction of the cell,
/// a sum of its corners, `j` beats `i` beyond rounding).
fn candidates(vertices: &[Vec3], margin: f32) -> [u32; DIRECTION_CELLS] {
    let all = u32::MAX >> (32 - vertices.len().clamp(1, 32));
    let mut cells = [all; DIRECTION_CELLS];
    for (cell, mask) in cells.iter_mut().enumerate() {
        let axis = cell / 8;
        let sign = |bit: usize| if cell & bit == 0 { 1.0 } else { -1.0 };
        // The cell's axis and its other two, as `direction_cell` orders them.
        let (k, i, j) = match axis {
            0 => (0, 1, 2),
            1 => (1, 0, 2),
            _ => (2, 0, 1),
        };
        let (sk, si, sj) = (sign(4), sign(2), sign(1));
        for (a, va) in vertices.iter().enumerate() {
            let beaten = vertices.iter().any(|vb| {
                let w = vb - va;
                let part = |n: usize| match n {
                    0 => w.x,
                    1 => w.y,
                    _ => w.z,
                };
                let base = sk * part(k);
                let (along_i, along_j) = (si * part(i), sj * part(j));
                base > margin
                    && base + along_i > margin
                    && base + along_j > margin
                    && base + along_i + along_j > margin
            });
            if beaten {
                *mask &= !1u32.wrapping_shl(a as u32);
            }
        }
    }
    cells
}

/// Each direction cell's faces for [`Hull::highest_face`]: every face
/// that is the highest (or within `near` of it) at some sampled point `m +
/// t u` outside the hull, `m` the vertices' mean, `u` on a 7 x 7 grid of
/// the cell's directions (its edges included), `t` from just beyond where
/// the ray leaves the hull to eleven times as far, and at infinity (the
/// face whose normal is most along `u`). A sample proves nothing: a face
/// left out only sends a query to GJK (a height from any face is a lower
/// bound, a projection over the face it is taken on is the closest point,
/// and an edge is taken only past a lower face: see [`Hull::by_faces`]).
/// On 64 random hulls of 8 to 18 faces, the highest face was among its
/// cell's candidates at every one of 6 297 points outside within three
/// sizes (a 5 x 5 grid and five distances did as well there; a 9 x 9 grid
/// and eight distances cost twice as much to build). Built once a hull, in
/// about 3 million M4F instructions for 10 faces (BENCHMARKS.md).
fn face_candidates(faces: &[Face], mean: &Vec3, near: f32) -> [u32; DIRECTION_CELLS] {
    const GRID: usize = 7;
    const BEYOND: [f32; 6] = [1.0e-3, 0.02, 0.1, 0.4, 1.5, 10.0];
    let mut cells = [0u32; DIRECTION_CELLS];
    for (cell, mask) in cells.iter_mut().enumerate() {
        let axis = cell / 8;
        let sign = |bit: usize| if cell & bit == 0 { 1.0 } else { -1.0 };
        let (sk, si, sj) = (sign(4), sign(2), sign(1));
        for a in 0..GRID {
            for b in 0..GRID {
                let (p, q) = (
                    si * a as f32 / (GRID - 1) as f32,
                    sj * b as f32 / (GRID - 1) as f32,
                );
                // The cell's axis and its other two, as `direction_cell`
                // orders them.
                let u = match axis {
                    0 => Vec3::new(sk, p, q),
                    1 => Vec3::new(p, sk, q),
                    _ => Vec3::new(p, q, sk),
                };
                // At infinity: the normal most along `u`.
                *mask |= highest(faces, near, |face| face.normal.dot(&u));
                // Where the ray from the mean leaves the hull, and beyond.
                let exit = faces.iter().fold(f32::INFINITY, |t, face| {
                    let along = face.normal.dot(&u);
                    if along > 0.0 {
                        min(t, (face.offset - face.normal.dot(mean)) / along)
                    } else {
                        t
                    }
                });
                if !exit.is_finite() {
                    continue;
                }
                for beyond in BEYOND {
                    let x = mean + u * (exit * (1.0 + beyond));
                    *mask |= highest(faces, near, |face| face.normal.dot(&x) - face.offset);
                }
            }
        }
    }
    cells
}

/// The faces (bit `f` for face `f`) within `near` of the highest by
/// `height`.
fn highest(faces: &[Face], near: f32, height: impl Fn(&Face) -> f32) -> u32 {
    let top = faces
        .iter()
        .fold(f32::NEG_INFINITY, |t, face| max(t, height(face)));
    faces
        .iter()
        .enumerate()
        .filter(|(_, face)| height(face) >= top - near)
        .fold(0, |mask, (f, _)| mask | 1u32.wrapping_shl(f as u32))
}

/// Whether the points span a tetrahedron of volume at least
/// `MIN_RELATIVE_VOLUME spread^3`: the farthest point from the first, the
/// farthest from their line, the farthest from their plane.
fn spans_a_volume(points: &[Vec3], spread: f32) -> bool {
    let Some(&a) = points.first() else {
        return false;
    };
    let farthest = |score: &dyn Fn(&Vec3) -> f32| {
        let mut best = (a, 0.0f32);
        for p in points {
            let s = score(p);
            if s > best.1 {
                best = (*p, s);
            }
        }
        best
    };
    let (b, _) = farthest(&|p| (p - a).norm_squared());
    let ab = b - a;
    let (c, _) = farthest(&|p| ab.cross(&(p - a)).norm_squared());
    let normal = ab.cross(&(c - a));
    let (_, volume) = farthest(&|p| normal.dot(&(p - a)).abs());
    volume >= 6.0 * MIN_RELATIVE_VOLUME * spread * spread * spread
}

/// GJK's simplex: 1 to 4 points of the Minkowski difference.
struct Simplex {
    points: [Vec3; 4],
    /// The hull vertex each point is.
    vertices: [u8; 4],
    count: usize,
}

impl Simplex {
    /// Adds support point `w` (hull vertex `vertex`) and returns the point
    /// of the simplex closest to the origin; the simplex is reduced to the
    /// points whose hull holds it. `None` when the origin is inside the
    /// tetrahedron (the simplex had four points and no face sees it).
    fn add(&mut self, vertex: u8, w: Vec3) -> Option<Vec3> {
        let (Some(slot), Some(id)) = (
            self.points.get_mut(self.count),
            self.vertices.get_mut(self.count),
        ) else {
            return Some(w);
        };
        (*slot, *id) = (w, vertex);
        let p = self.points;
        let (closest, kept) = match self.count {
            0 => (p[0], Kept::from([0])),
            1 => segment(p[0], p[1]),
            2 => triangle(p[0], p[1], p[2]),
            _ => tetrahedron(p[0], p[1], p[2], p[3])?,
        };
        let ids = self.vertices;
        for (n, &i) in kept.index.iter().take(kept.count).enumerate() {
            if let (Some(slot), Some(id), Some(&point), Some(&vertex)) = (
                self.points.get_mut(n),
                self.vertices.get_mut(n),
                p.get(i as usize),
                ids.get(i as usize),
            ) {
                (*slot, *id) = (point, vertex);
            }
        }
        self.count = kept.count;
        Some(closest)
    }
}

/// Which of a simplex's points (by index) hold its closest point.
#[derive(Clone, Copy)]
struct Kept {
    index: [u8; 3],
    count: usize,
}

impl<const K: usize> From<[u8; K]> for Kept {
    fn from(ids: [u8; K]) -> Self {
        let mut index = [0; 3];
        for (slot, id) in index.iter_mut().zip(ids) {
            *slot = id;
        }
        Kept {
            index,
            count: K.min(3),
        }
    }
}

/// The closest point of segment `ab` to the origin.
fn segment(a: Vec3, b: Vec3) -> (Vec3, Kept) {
    let ab = b - a;
    let t = -a.dot(&ab);
    if t <= 0.0 {
        return (a, Kept::from([0]));
    }
    let length_sq = ab.dot(&ab);
    if t >= length_sq {
        return (b, Kept::from([1]));
    }
    (a + ab * (t / length_sq), Kept::from([0, 1]))
}

/// The closest point of triangle `abc` to the origin, by its Voronoi
/// regions (Ericson 5.1.5). A triangle too thin for its barycentric
/// denominator falls back to its nearest edge.
#[inline(never)]
fn triangle(a: Vec3, b: Vec3, c: Vec3) -> (Vec3, Kept) {
    let (ab, ac) = (b - a, c - a);
    let d1 = -ab.dot(&a);
    let d2 = -ac.dot(&a);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, Kept::from([0]));
    }
    let d3 = -ab.dot(&b);
    let d4 = -ac.dot(&b);
    if d3 >= 0.0 && d4 <= d3 {
        return (b, Kept::from([1]));
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let t = d1 / (d1 - d3);
        return (a + ab * t, Kept::from([0, 1]));
    }
    let d5 = -ab.dot(&c);
    let d6 = -ac.dot(&c);
    if d6 >= 0.0 && d5 <= d6 {
        return (c, Kept::from([2]));
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let t = d2 / (d2 - d6);
        return (a + ac * t, Kept::from([0, 2]));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        let t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + (c - b) * t, Kept::from([1, 2]));
    }
    // Inside the face: the origin's projection on its plane, `n (a . n) /
    // |n|^2`, whose direction is the normal's to rounding (the
    // barycentric sum `a + v ab + w ac` cancels when the triangle is large
    // against the distance, and turns the direction).
    let normal = ab.cross(&ac);
    let normal_sq = normal.dot(&normal);
    if !(normal_sq > 0.0 && va + vb + vc > 0.0) {
        return thin_triangle(a, b, c);
    }
    (normal * (a.dot(&normal) / normal_sq), Kept::from([0, 1, 2]))
}

/// The nearest of a degenerate triangle's edges to the origin.
#[cold]
fn thin_triangle(a: Vec3, b: Vec3, c: Vec3) -> (Vec3, Kept) {
    let mut best = (Vec3::zeros(), Kept::from([0]));
    let mut best_sq = f32::INFINITY;
    for (p, q, ends) in [(a, b, [0u8, 1]), (a, c, [0, 2]), (b, c, [1, 2])] {
        let (point, kept) = segment(p, q);
        let sq = point.norm_squared();
        if sq < best_sq {
            let mut index = [0; 3];
            for (slot, &i) in index.iter_mut().zip(kept.index.iter().take(kept.count)) {
                *slot = ends.get(i as usize).copied().unwrap_or_default();
            }
            best_sq = sq;
            best = (
                point,
                Kept {
                    index,
                    count: kept.count,
                },
            );
        }
    }
    best
}

/// The closest point of tetrahedron `abcd` to the origin (Ericson 5.1.6):
/// the nearest of the closest points of the faces the origin is outside
/// of; `None` when it is outside of none (inside, or on the boundary).
#[inline(never)]
fn tetrahedron(a: Vec3, b: Vec3, c: Vec3, d: Vec3) -> Option<(Vec3, Kept)> {
    let points = [a, b, c, d];
    // Each face and the vertex opposite it.
    const FACES: [([u8; 3], u8); 4] = [
        ([0, 1, 2], 3),
        ([0, 2, 3], 1),
        ([0, 3, 1], 2),
        ([1, 3, 2], 0),
    ];
    let mut best: Option<(Vec3, Kept)> = None;
    let mut best_sq = f32::INFINITY;
    let mut degenerate = false;
    for (face, opposite) in FACES {
        let corner = |n: u8| points.get(n as usize).copied().unwrap_or_default();
        let [i, j, k] = face.map(corner);
        let normal = (j - i).cross(&(k - i));
        let origin_side = -i.dot(&normal);
        let opposite_side = (corner(opposite) - i).dot(&normal);
        if opposite_side == 0.0 {
            degenerate = true;
        }
        if origin_side * opposite_side < 0.0 || opposite_side == 0.0 {
            let (point, kept) = triangle(i, j, k);
            let sq = point.norm_squared();
            if sq < best_sq {
                let mut index = [0; 3];
                for (slot, &n) in index.iter_mut().zip(kept.index.iter().take(kept.count)) {
                    *slot = face.get(n as usize).copied().unwrap_or_default();
                }
                best_sq = sq;
                best = Some((
                    point,
                    Kept {
                        index,
                        count: kept.count,
                    },
                ));
            }
        }
    }
    // A flat tetrahedron holds no volume for the origin to be in.
    if degenerate && best.is_none() {
        return Some(triangle(a, b, c));
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec;

    fn lcg(state: &mut u64) -> f32 {
        *state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*state >> 40) as f32) / (1u64 << 24) as f32
    }

    /// Checks `got` (the query at `p`, outside the hull of `points`)
    /// against the brute-force distance: the distance and the lower bound
    /// within `2e-5 (1 + d)`. Returns the oracle's distance and that scale.
    fn agrees_with_the_oracle(
        points: &[[f32; 3]],
        p: [f64; 3],
        got: &HullDistance,
        case: usize,
    ) -> (f64, f64) {
        let want = brute_distance(points, p);
        let scale = 1.0 + want;
        assert!(
            (got.distance as f64 - want).abs() <= 2e-5 * scale,
            "case {case} p {p:?}: {} against {want}",
            got.distance
        );
        assert!(got.lower_bound as f64 <= want + 2e-5 * scale);
        assert!(
            got.lower_bound as f64 >= want - 2e-5 * scale,
            "lower {} against {want}: case {case} p {p:?} points {points:?}",
            got.lower_bound
        );
        (want, scale)
    }

    /// Random half-extents for a hull's points: 1-4 by 0.5-2.5 by 1-2.
    fn random_size(state: &mut u64) -> [f32; 3] {
        [
            1.0 + 3.0 * lcg(state),
            0.5 + 2.0 * lcg(state),
            1.0 + lcg(state),
        ]
    }

    /// `count` random points in a box of half-extents `size`, off the origin.
    fn random_points(state: &mut u64, count: usize, size: [f32; 3]) -> heapless::Vec<[f32; 3], 32> {
        let mut points = heapless::Vec::new();
        for _ in 0..count {
            let p = [0, 1, 2].map(|i| (2.0 * lcg(state) - 1.0) * size[i] + 0.3 * size[i]);
            let _ = points.push(p);
        }
        points
    }

    /// The closest point of triangle `abc` to `p`, f64, by projection and
    /// clamping to the edges (an independent method: the plane, then each
    /// edge and vertex).
    fn triangle_distance(p: [f64; 3], a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
        let sub = |x: [f64; 3], y: [f64; 3]| [x[0] - y[0], x[1] - y[1], x[2] - y[2]];
        let dot = |x: [f64; 3], y: [f64; 3]| x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
        let cross = |x: [f64; 3], y: [f64; 3]| {
            [
                x[1] * y[2] - x[2] * y[1],
                x[2] * y[0] - x[0] * y[2],
                x[0] * y[1] - x[1] * y[0],
            ]
        };
        let seg = |a: [f64; 3], b: [f64; 3]| {
            let ab = sub(b, a);
            let t = (dot(sub(p, a), ab) / dot(ab, ab)).clamp(0.0, 1.0);
            let q = [a[0] + t * ab[0], a[1] + t * ab[1], a[2] + t * ab[2]];
            dot(sub(p, q), sub(p, q)).sqrt()
        };
        let n = cross(sub(b, a), sub(c, a));
        let nn = dot(n, n);
        let mut best = seg(a, b).min(seg(b, c)).min(seg(c, a));
        if nn > 0.0 {
            let s = dot(sub(p, a), n) / nn;
            let q = [p[0] - s * n[0], p[1] - s * n[1], p[2] - s * n[2]];
            let inside = [(a, b), (b, c), (c, a)]
                .iter()
                .all(|&(u, v)| dot(cross(sub(v, u), sub(q, u)), n) >= 0.0);
            if inside {
                best = best.min(s.abs() * nn.sqrt());
            }
        }
        best
    }

    /// Distance from `p` to the hull of `points`, f64: the least distance
    /// to any triangle of three of them (the closest hull point lies on a
    /// face, which is such a triangle, and every triangle is in the hull).
    /// Meaningful for `p` outside the hull.
    fn brute_distance(points: &[[f32; 3]], p: [f64; 3]) -> f64 {
        let v: Vec<[f64; 3]> = points.iter().map(|q| q.map(f64::from)).collect();
        let mut best = f64::INFINITY;
        for i in 0..v.len() {
            for j in i + 1..v.len() {
                for k in j + 1..v.len() {
                    best = best.min(triangle_distance(p, v[i], v[j], v[k]));
                }
            }
        }
        best
    }

    /// Whether `p` is in the hull of `points`, f64: in some tetrahedron of
    /// four of them (Caratheodory).
    fn brute_inside(points: &[[f32; 3]], p: [f64; 3]) -> bool {
        let v: Vec<[f64; 3]> = points.iter().map(|q| q.map(f64::from)).collect();
        let det = |a: [f64; 3], b: [f64; 3], c: [f64; 3], d: [f64; 3]| {
            let (x, y, z) = (
                [b[0] - a[0], b[1] - a[1], b[2] - a[2]],
                [c[0] - a[0], c[1] - a[1], c[2] - a[2]],
                [d[0] - a[0], d[1] - a[1], d[2] - a[2]],
            );
            x[0] * (y[1] * z[2] - y[2] * z[1]) - x[1] * (y[0] * z[2] - y[2] * z[0])
                + x[2] * (y[0] * z[1] - y[1] * z[0])
        };
        let n = v.len();
        for i in 0..n {
            for j in i + 1..n {
                for k in j + 1..n {
                    for l in k + 1..n {
                        let (a, b, c, d) = (v[i], v[j], v[k], v[l]);
                        let whole = det(a, b, c, d);
                        if whole.abs() < 1e-12 {
                            continue;
                        }
                        let parts = [
                            det(p, b, c, d),
                            det(a, p, c, d),
                            det(a, b, p, d),
                            det(a, b, c, p),
                        ];
                        if parts.iter().all(|s| s * whole >= 0.0) {
                            return true;
                        }
                    }
                }
            }
        }
        false
    }

    #[test]
    fn distances_match_a_brute_force_oracle_on_random_hulls() {
        let mut state = 7u64;
        let mut checked = 0;
        for case in 0..300 {
            let count = 4 + case % 17;
            let size = random_size(&mut state);
            let points = random_points(&mut state, count, size);
            let Ok(hull) = Hull::new(&points) else {
                continue;
            };
            for _ in 0..10 {
                let x = [0, 1, 2].map(|i| (2.0 * lcg(&mut state) - 1.0) * 3.0 * size[i]);
                let p = x.map(f64::from);
                let got = hull.distance(&vec3(x));
                if brute_inside(&points, p) {
                    assert_eq!(got.distance, 0.0, "case {case} x {x:?}: inside");
                    continue;
                }
                let (_, scale) = agrees_with_the_oracle(&points, p, &got, case);
                // The normal leads from the closest point to x.
                let closest = vec3(x) - got.normal * got.distance;
                assert!((got.normal.norm() - 1.0).abs() < 1e-5);
                assert!(brute_distance(&points, closest.map(f64::from).into()) < 1e-4 * scale);
                checked += 1;
            }
        }
        assert!(checked > 1500, "only {checked} outside points");
    }

    /// BENCHMARKS.md's 16-vertex hull: an octagonal prism, its octagon's
    /// corners on the ellipse of semi-axes 20 and 15, z = +-10.
    fn octagonal_prism() -> [[f32; 3]; 16] {
        core::array::from_fn(|i| {
            let angle = core::f32::consts::FRAC_PI_4 * (i % 8) as f32 + 0.3;
            [
                20.0 * angle.cos(),
                15.0 * angle.sin(),
                if i < 8 { 10.0 } else { -10.0 },
            ]
        })
    }

    #[test]
    fn the_faces_answer_most_queries_and_agree_with_the_oracle_and_gjk() {
        let mut state = 11u64;
        let (mut answered, mut outside, mut with_faces, mut without) = (0, 0, 0, 0);
        let prism = octagonal_prism();
        for case in 0..300 {
            let count = 4 + case % 29;
            let size = random_size(&mut state);
            let points: heapless::Vec<[f32; 3], 32> = if case % 10 == 0 {
                prism.iter().copied().collect()
            } else {
                random_points(&mut state, count, size)
            };
            let Ok(hull) = Hull::new(&points) else {
                continue;
            };
            if !hull.has_faces() {
                without += 1;
                continue;
            }
            with_faces += 1;
            let scale_of = [0, 1, 2].map(|i| points.iter().map(|p| p[i].abs()).fold(0.0, f32::max));
            for _ in 0..20 {
                let x = [0, 1, 2].map(|i| (2.0 * lcg(&mut state) - 1.0) * 2.0 * scale_of[i]);
                let p = x.map(f64::from);
                if brute_inside(&points, p) {
                    continue;
                }
                outside += 1;
                let Some(got) = hull.by_faces(&vec3(x)) else {
                    continue;
                };
                answered += 1;
                let (_, scale) = agrees_with_the_oracle(&points, p, &got, case);
                assert!(got.lower_bound <= got.distance);
                assert!((got.normal.norm() - 1.0).abs() < 1e-5);
                let gjk = hull.by_gjk(&vec3(x));
                assert!((got.distance - gjk.distance).abs() <= 2e-5 * scale as f32);
                assert!(
                    (got.normal - gjk.normal).norm() <= 1e-3,
                    "case {case} x {x:?}"
                );
            }
        }
        // Random hulls of up to 32 points often have more faces than the
        // topology holds; boxes, prisms and small hulls do not.
        assert!(
            with_faces > 100 && without > 10,
            "{with_faces} with faces, {without} without"
        );
        assert!(
            answered * 100 >= 95 * outside,
            "the faces answered {answered} of {outside} outside points"
        );
    }

    /// The hull's edges: each is a side of two faces.
    fn edge_count(hull: &Hull) -> usize {
        hull.face_start[hull.faces().len()] as usize / 2
    }

    #[test]
    fn a_prism_has_its_faces_and_edges() {
        let prism = octagonal_prism();
        let hull = Hull::new(&prism).unwrap();
        assert_eq!((hull.faces().len(), edge_count(&hull)), (10, 24));
        // BENCHMARKS.md's 96 points round it (a spiral at 30 from its
        // centre): every one answered by the faces, as GJK answers it.
        for i in 0..96u32 {
            let z = 1.0 - (2.0 * i as f32 + 1.0) / 96.0;
            let ring = (1.0 - z * z).sqrt();
            let (s, c) = crate::math::sin_cos(2.399_963 * i as f32);
            let x = Vec3::new(30.0 * ring * c, 30.0 * ring * s, 30.0 * z);
            let got = hull.by_faces(&x).unwrap();
            let gjk = hull.by_gjk(&x);
            assert!(
                (got.distance - gjk.distance).abs() < 1e-4,
                "{x:?}: {got:?} {gjk:?}"
            );
            assert!(
                (got.normal - gjk.normal).norm() < 1e-3,
                "{x:?}: {got:?} {gjk:?}"
            );
        }
        let corners: [[f32; 3]; 8] = core::array::from_fn(|i| {
            [0, 1, 2].map(|axis| if i >> axis & 1 == 0 { 1.0 } else { -1.0 })
        });
        let cube = Hull::new(&corners).unwrap();
        assert_eq!((cube.faces().len(), edge_count(&cube)), (6, 12));
        // Off a corner, an edge and a face of the cube: the corner's, the
        // edge's and the face's distances.
        for (x, want) in [
            ([2.0, 2.0, 2.0], 3.0f32.sqrt()),
            ([2.0, 2.0, 0.5], 2.0f32.sqrt()),
            ([0.2, -0.3, 3.0], 2.0),
        ] {
            let got = cube.by_faces(&vec3(x)).unwrap();
            assert!((got.distance - want).abs() < 1e-6, "{x:?}: {got:?}");
        }
    }

    /// The first farthest vertex by a plain scan of every vertex, as the
    /// support must find it.
    fn scanned_support(vertices: &[Vec3], d: &Vec3) -> usize {
        let mut best = (0, f32::NEG_INFINITY);
        for (i, v) in vertices.iter().enumerate() {
            let dot = v.x * d.x + v.y * d.y + v.z * d.z;
            if dot > best.1 {
                best = (i, dot);
            }
        }
        best.0
    }

    #[test]
    fn the_cells_candidates_give_the_scans_support() {
        let mut state = 11u64;
        // Hulls with ties and coplanar faces (an octagonal prism, a grid of
        // a box's faces) and random ones, 12 to 32 vertices.
        let mut sets: Vec<heapless::Vec<[f32; 3], 32>> = Vec::new();
        let mut prism = heapless::Vec::new();
        for i in 0..16 {
            let a = core::f32::consts::FRAC_PI_4 * (i % 8) as f32;
            let _ = prism.push([
                20.0 * a.cos(),
                15.0 * a.sin(),
                if i < 8 { 10.0 } else { -10.0 },
            ]);
        }
        sets.push(prism);
        let mut grid = heapless::Vec::new();
        for i in 0..27 {
            let c = [i % 3, (i / 3) % 3, i / 9].map(|k| 5.0 * (k as f32 - 1.0));
            let _ = grid.push(c);
        }
        sets.push(grid);
        for n in 0..200 {
            sets.push(random_points(&mut state, 12 + n % 21, [20.0, 15.0, 10.0]));
        }
        // Directions: random, the axes, the cells' corners and edges, -0.
        let mut directions: Vec<Vec3> = Vec::new();
        for i in 0..27 {
            let c = [i % 3, (i / 3) % 3, i / 9].map(|k| k as f32 - 1.0);
            directions.push(vec3(c));
        }
        directions.push(Vec3::new(-0.0, 1.0, -0.0));
        directions.push(Vec3::new(1.0, 1.0, 1.0e-30));
        for _ in 0..300 {
            directions.push(Vec3::new(
                2.0 * lcg(&mut state) - 1.0,
                2.0 * lcg(&mut state) - 1.0,
                2.0 * lcg(&mut state) - 1.0,
            ));
        }
        let mut tried_fewer = 0usize;
        for set in &sets {
            let hull = Hull::new(set).unwrap();
            for d in &directions {
                let (found, vertex) = hull.support(d);
                let expected = scanned_support(hull.vertices(), d);
                assert_eq!(found as usize, expected, "direction {d:?}, hull {set:?}");
                assert_eq!(vertex, hull.vertices()[expected]);
                if let Some(cell) = direction_cell(d) {
                    tried_fewer += (hull.candidates[cell].count_ones() < set.len() as u32) as usize;
                }
            }
        }
        // The cells leave vertices out (the speed-up is real, not a scan).
        assert!(
            tried_fewer > sets.len() * directions.len() / 2,
            "{tried_fewer}"
        );
    }

    #[test]
    fn the_normal_is_the_gradient_of_the_distance() {
        let mut state = 99u64;
        for _ in 0..100 {
            let points = random_points(&mut state, 12, [2.0, 1.5, 1.0]);
            let Ok(hull) = Hull::new(&points) else {
                continue;
            };
            let x = vec3([0, 1, 2].map(|_| (2.0 * lcg(&mut state) - 1.0) * 8.0));
            let at = hull.distance(&x);
            if at.distance < 0.1 {
                continue;
            }
            let h = 1e-2;
            for axis in 0..3 {
                let mut e = Vec3::zeros();
                e[axis] = h;
                let slope = (hull.distance(&(x + e)).distance - hull.distance(&(x - e)).distance)
                    / (2.0 * h);
                assert!(
                    (slope - at.normal[axis]).abs() < 2e-2,
                    "axis {axis}: {slope} against {}",
                    at.normal[axis]
                );
            }
        }
    }

    #[test]
    fn a_box_hull_measures_as_the_box() {
        let mut corners = [[0.0f32; 3]; 8];
        for (i, corner) in corners.iter_mut().enumerate() {
            for (axis, h) in [1.0, 2.0, 0.5].into_iter().enumerate() {
                corner[axis] = if i >> axis & 1 == 1 { h } else { -h };
            }
        }
        let hull = Hull::new(&corners).unwrap();
        assert_eq!(hull.half_box(), Vec3::new(1.0, 2.0, 0.5));
        assert_eq!(hull.half_width(), 0.5);
        let face = hull.distance(&Vec3::new(3.0, 0.5, 0.1));
        assert!((face.distance - 2.0).abs() < 1e-6 && (face.normal - Vec3::x()).norm() < 1e-6);
        let corner = hull.distance(&Vec3::new(2.0, 3.0, 1.5));
        assert!((corner.distance - 3.0f32.sqrt()).abs() < 1e-5);
        let inside = hull.distance(&Vec3::new(0.5, -1.0, 0.2));
        assert_eq!((inside.distance, inside.lower_bound), (0.0, 0.0));
    }

    #[test]
    fn rejects_bad_vertex_sets() {
        let tetra = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        assert!(Hull::new(&tetra).is_ok());
        assert_eq!(Hull::new(&tetra[..3]), Err(HullError::TooFewVertices));
        let flat = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.5, 0.2, 0.0],
        ];
        assert_eq!(Hull::new(&flat), Err(HullError::Flat));
        let line = [
            [0.0, 0.0, 0.0],
            [1.0, 1.0, 1.0],
            [2.0, 2.0, 2.0],
            [3.0, 3.0, 3.0],
        ];
        assert_eq!(Hull::new(&line), Err(HullError::Flat));
        let mut nan = tetra;
        nan[2][1] = f32::NAN;
        assert_eq!(Hull::new(&nan), Err(HullError::NotFinite));
        let mut far = tetra;
        far[1][0] = 2.0e4;
        assert_eq!(Hull::new(&far), Err(HullError::OutOfRange));
        let many = [[0.0; 3]; 33];
        assert_eq!(
            Hull::new(&many),
            Err(HullError::TooManyVertices { capacity: 32 })
        );
    }

    #[test]
    fn queries_are_bounded_and_finite_on_hard_input() {
        // Nearly coplanar points, duplicates, and far queries.
        let points = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 1.0, 1.0e-2],
            [1.0, 1.0, 1.0e-2],
            [0.5, 0.5, -1.0e-2],
        ];
        let hull = Hull::new(&points).unwrap();
        let nan = hull.distance(&Vec3::new(f32::NAN, 0.0, 1.0));
        assert!(nan.distance.is_nan() && nan.lower_bound.is_nan());
        for x in [
            [0.5, 0.5, 1.0e3],
            [1.0e4, -1.0e4, 3.0],
            [0.5, 0.5, 0.0],
            [0.3, 0.3, 1.0e-7],
        ] {
            let d = hull.distance(&vec3(x));
            assert!(
                d.distance.is_finite() && d.lower_bound <= d.distance && d.normal.norm() > 0.99
            );
        }
    }

    /// Hulls with a topology of at least `CELL_MIN_FACES` faces: prisms of
    /// 6 to 16 sides on random ellipses, and clouds of 8 to 12 points.
    fn hulls_with_cells(state: &mut u64) -> heapless::Vec<(heapless::Vec<[f32; 3], 32>, Hull), 64> {
        let mut hulls = heapless::Vec::new();
        while !hulls.is_full() {
            let size = random_size(state);
            let points: heapless::Vec<[f32; 3], 32> = if hulls.len() % 2 == 0 {
                let sides = 6 + (lcg(state) * 11.0) as usize;
                let turn = lcg(state) * 6.0;
                (0..2 * sides)
                    .map(|i| {
                        let angle =
                            core::f32::consts::TAU * (i % sides) as f32 / sides as f32 + turn;
                        let z = if i < sides { size[2] } else { -size[2] };
                        [size[0] * angle.cos(), size[1] * angle.sin(), z]
                    })
                    .collect()
            } else {
                let count = 8 + (lcg(state) * 5.0) as usize;
                random_points(state, count, size)
            };
            if let Ok(hull) = Hull::new(&points) {
                if hull.faces().len() >= CELL_MIN_FACES {
                    let _ = hulls.push((points, hull));
                }
            }
        }
        hulls
    }

    /// A random point outside the hull, within three times its size of it.
    fn outside_point(state: &mut u64, points: &[[f32; 3]]) -> Option<([f32; 3], [f64; 3])> {
        let scale = [0, 1, 2].map(|i| points.iter().map(|p| p[i].abs()).fold(0.0, f32::max));
        let x = [0, 1, 2].map(|i| (2.0 * lcg(state) - 1.0) * 3.0 * scale[i]);
        let p = x.map(f64::from);
        (!brute_inside(points, p)).then_some((x, p))
    }

    #[test]
    fn the_cells_face_candidates_hold_the_highest_face() {
        let mut state = 5u64;
        let (mut queries, mut highest, mut answered, mut tried) = (0, 0, 0, 0u32);
        for (points, hull) in hulls_with_cells(&mut state) {
            for cell in hull.face_candidates {
                assert!(cell != 0 && cell >> hull.faces().len() == 0);
                tried += cell.count_ones();
            }
            for _ in 0..100 {
                let Some((x, p)) = outside_point(&mut state, &points) else {
                    continue;
                };
                queries += 1;
                let x = vec3(x);
                let all = hull.faces().iter().map(|f| f.normal.dot(&x) - f.offset);
                let top = all.fold(f32::NEG_INFINITY, max);
                if hull.highest_face(&x).0 == top {
                    highest += 1;
                }
                if let Some(got) = hull.by_faces(&x) {
                    answered += 1;
                    agrees_with_the_oracle(&points, p, &got, 0);
                }
            }
        }
        // The sampled candidates miss the highest face at very few points
        // (each only costs GJK), and hold few faces a cell.
        assert!(highest * 1000 >= 998 * queries, "{highest} of {queries}");
        assert!(answered * 100 >= 95 * queries, "{answered} of {queries}");
        assert!(
            tried < 64 * 24 * 5,
            "{tried} candidates in {} cells",
            64 * 24
        );
    }

    #[test]
    fn answers_hold_whichever_faces_a_cell_tries() {
        // Candidates chosen at random, the highest face often left out: an
        // answer is still the distance (or none, and GJK answers).
        let mut state = 9u64;
        let (mut answered, mut queries, mut missed) = (0, 0, 0);
        for (points, mut hull) in hulls_with_cells(&mut state) {
            let all = u32::MAX >> (32 - hull.faces().len());
            for cell in hull.face_candidates.iter_mut() {
                *cell = (((lcg(&mut state) * 4294967296.0) as u64 as u32) & all).max(1);
            }
            for _ in 0..100 {
                let Some((x, p)) = outside_point(&mut state, &points) else {
                    continue;
                };
                queries += 1;
                let x = vec3(x);
                let top = hull
                    .faces()
                    .iter()
                    .map(|f| f.normal.dot(&x) - f.offset)
                    .fold(f32::NEG_INFINITY, max);
                if hull.highest_face(&x).0 < top {
                    missed += 1;
                }
                if let Some(got) = hull.by_faces(&x) {
                    answered += 1;
                    agrees_with_the_oracle(&points, p, &got, 0);
                    assert!((hull.by_gjk(&x).distance - got.distance).abs() <= 1e-4);
                }
            }
        }
        assert!(
            missed * 4 > queries,
            "the highest face left out {missed} of {queries} times"
        );
        assert!(answered * 3 > queries, "{answered} of {queries}");
    }
}
