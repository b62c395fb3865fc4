//! Obstacles given as points: a `convex` entry's vertex list and a `mesh`
//! entry's file, made into what the core takes. A mesh is read into its
//! separate parts ([`mesh_parts`]); each part becomes the box, cylinder or
//! ball it is ([`crate::mesh_parts`]), else its hull (or an enclosure of at
//! most [`MAX_HULL_VERTICES`] corners, [`crate::enclosure`]); parts beyond
//! the hull slots share hulls, and one non-convex part is split into convex
//! pieces ([`crate::decompose`]). The notes say what was done to each.

use std::path::Path;

use capp_core::obstacle::{Hull, MAX_HULLS, MAX_HULL_VERTICES};

use crate::enclosure::{enclose, Enclosure};
use crate::mesh_parts::{fit, merge, FitForm, MeshPart, Placed};

/// Why points make no hull the core takes.
pub(super) enum NoHull {
    /// The points themselves: none, not finite, or flat.
    Points(crate::polytope::HullFailure),
    /// Their hull has this many corners, more than [`MAX_HULL_VERTICES`].
    Corners(usize),
}

impl std::fmt::Display for NoHull {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            NoHull::Points(e) => write!(f, "{e}"),
            NoHull::Corners(n) => write!(
                f,
                "its hull has {n} vertices, more than the {MAX_HULL_VERTICES} a hull may have (give fewer, or the part as a `mesh`: a mesh is enclosed in {MAX_HULL_VERTICES})"
            ),
        }
    }
}

/// The corners of the hull of `points` (obstacle frame, length units) as
/// the core takes them, or why not.
pub(super) fn hull_of(points: &[[f64; 3]]) -> Result<Vec<[f32; 3]>, NoHull> {
    let corners = crate::polytope::hull_vertices(points).map_err(NoHull::Points)?;
    if corners.len() > MAX_HULL_VERTICES {
        return Err(NoHull::Corners(corners.len()));
    }
    Ok(as_f32(&corners))
}

/// Corners in `f32`, as the core takes them.
fn as_f32(corners: &[[f64; 3]]) -> Vec<[f32; 3]> {
    corners.iter().map(|v| v.map(|x| x as f32)).collect()
}

/// The separate parts of mesh file `file` (STL, binary or ASCII, or OBJ),
/// each as its vertices as written in the file: every object of the file
/// (an OBJ's `o` or `g`, an ASCII STL's `solid`), split further into the
/// groups of faces that share no vertex (vertices at the same position are
/// one: STL repeats them per triangle). `shown` names the file in errors.
pub(super) fn mesh_parts(file: &Path, shown: &str) -> Result<Vec<MeshPart>, String> {
    if !file.is_file() {
        return Err(format!(
            "obstacle: mesh \"{shown}\" not found ({})",
            file.display()
        ));
    }
    let extension = file
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let loader = mesh_loader::Loader::default();
    let scene = match extension.as_deref() {
        Some("stl") => loader.load_stl(file),
        // An OBJ's objects (`o`) as its groups (`g`): the loader starts a
        // mesh at each group, and a convex decomposition (V-HACD, CoACD)
        // writes each piece as an object.
        Some("obj") => std::fs::read(file).and_then(|bytes| {
            let text = String::from_utf8_lossy(&bytes);
            let grouped: String = text
                .lines()
                .map(|l| match l.trim_start().strip_prefix("o ") {
                    Some(name) => format!("g {name}\n"),
                    None => format!("{l}\n"),
                })
                .collect();
            loader.load_obj_from_slice(grouped.as_bytes(), file)
        }),
        _ => {
            return Err(format!(
                "obstacle: mesh \"{shown}\" is neither .stl nor .obj"
            ))
        }
    }
    .map_err(|e| {
        let reason = e
            .to_string()
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ");
        format!("obstacle: mesh \"{shown}\" is unreadable: {reason}")
    })?;
    let mut parts = Vec::new();
    for mesh in &scene.meshes {
        let vertices: Vec<[f64; 3]> = mesh.vertices.iter().map(|v| v.map(f64::from)).collect();
        parts.extend(connected_parts(&vertices, &mesh.faces));
    }
    if parts.iter().all(|p| p.points.is_empty()) {
        return Err(format!("obstacle: mesh \"{shown}\" has no vertices"));
    }
    Ok(parts)
}

/// The groups of `faces` (triangles of indices into `vertices`) that share
/// no vertex, each as its distinct vertices; vertices at the same position
/// are one, and vertices no face names are a group of their own.
fn connected_parts(vertices: &[[f64; 3]], faces: &[[u32; 3]]) -> Vec<MeshPart> {
    use std::collections::BTreeMap;
    // Each position once (by its bits), then a union-find over faces.
    let mut welded = BTreeMap::new();
    let ids: Vec<usize> = vertices
        .iter()
        .map(|v| {
            let n = welded.len();
            // -0 and +0 are one position.
            *welded
                .entry(v.map(|x| if x == 0.0 { 0.0f64 } else { x }.to_bits()))
                .or_insert(n)
        })
        .collect();
    let mut root: Vec<usize> = (0..welded.len()).collect();
    fn find(root: &mut [usize], mut i: usize) -> usize {
        while root[i] != i {
            root[i] = root[root[i]];
            i = root[i];
        }
        i
    }
    let named = |k: u32| ids.get(k as usize).copied();
    for face in faces {
        if let [Some(a), Some(b), Some(c)] = face.map(named) {
            for other in [b, c] {
                let (x, y) = (find(&mut root, a), find(&mut root, other));
                root[x.max(y)] = x.min(y);
            }
        }
    }
    // Each part's positions in the order of their first writing, and each
    // welded position's index within its part.
    let mut groups: BTreeMap<usize, MeshPart> = BTreeMap::new();
    let mut positions: Vec<(usize, [u64; 3])> =
        welded.into_iter().map(|(bits, id)| (id, bits)).collect();
    positions.sort();
    let mut within = vec![0; positions.len()];
    for (id, bits) in positions {
        let r = find(&mut root, id);
        let part = groups.entry(r).or_default();
        within[id] = part.points.len();
        part.points.push(bits.map(f64::from_bits));
    }
    for face in faces {
        if let [Some(a), Some(b), Some(c)] = face.map(named) {
            let r = find(&mut root, a);
            if let Some(part) = groups.get_mut(&r) {
                part.triangles.push([a, b, c].map(|id| within[id]));
            }
        }
    }
    groups.into_values().collect()
}

/// A mesh part's hull as the core takes it: its convex hull, or, when that
/// has more than [`MAX_HULL_VERTICES`] corners (a curved CAD part), an
/// enclosure of at most that many ([`crate::enclosure`]).
fn mesh_hull(points: &[[f64; 3]]) -> Result<Enclosure, NoHull> {
    enclose(points, MAX_HULL_VERTICES).map_err(NoHull::Points)
}

/// What one obstacle entry becomes: a primitive or a hull, made of these parts
/// of its mesh (0-based; empty for a `convex` entry), or this piece of its
/// one part ([`crate::decompose`]), or of part `within` of several.
pub(super) struct Piece {
    pub(super) parts: Vec<usize>,
    /// `"part"`, or `"piece"` for a piece of a part split in convex pieces.
    pub(super) word: &'static str,
    /// For a piece of one part of a mesh of several, that part (0-based).
    pub(super) within: Option<usize>,
    pub(super) form: Form,
}

pub(super) enum Form {
    /// A mesh part that is a box, a cylinder, a ball or a capsule
    /// ([`crate::mesh_parts`]), and the note when it reaches beyond the
    /// part's hull.
    Solid(Placed, Option<String>),
    /// A hull's corners, and the note when they enclose the part's hull.
    Hull(Vec<[f32; 3]>, Option<String>),
}

/// The pieces of a mesh's `parts` (already scaled), and a note when parts
/// were merged or a part split. One part (with `separate`) is split into
/// convex pieces when a cut pays ([`split_pieces`], at most `room`
/// obstacles). With `separate` and every part spanning a volume of its
/// own (a closed part): each part that is a box, a cylinder, a ball or a capsule
/// ([`fit`]) that solid, each other part a hull, and when those are more
/// than `slots` (the hull slots this obstacle may take), neighbouring ones
/// merged into `slots` hulls; when fewer, the hollow ones (closed,
/// [`SPLIT_HOLLOW`] or more of their hull empty; the most hollow first)
/// split into convex pieces with the slots and obstacles to spare. Else
/// (`parts = "one"`, or an open surface such as a mesh of loose faces,
/// whose parts are flat) one piece round them all, a primitive if it is
/// one.
/// `placement` is the mesh's centre and Euler angles, radians (for the
/// boxes).
pub(super) fn mesh_pieces(
    parts: Vec<MeshPart>,
    separate: bool,
    (slots, room): (usize, usize),
    placement: &([f64; 3], [f64; 3]),
    unit: &str,
) -> Result<Pieces, String> {
    let closed = |part: &[[f64; 3]]| {
        mesh_hull(part).is_ok_and(|hull| Hull::new(&as_f32(&hull.corners)).is_ok())
    };
    // A hull of `points`; `part`, when it is one part alone, for the note
    // on how hollow it is.
    let hull_piece = |parts: Vec<usize>,
                      points: &[[f64; 3]],
                      part: Option<&MeshPart>|
     -> Result<Piece, String> {
        let hull = mesh_hull(points).map_err(|e| e.to_string())?;
        let note = enclosure_note(&hull, unit).or_else(|| part.and_then(hollow_note));
        Ok(Piece {
            parts,
            word: "part",
            within: None,
            form: Form::Hull(as_f32(&hull.corners), note),
        })
    };
    let solid = |parts: Vec<usize>, f: &crate::mesh_parts::Fitted| {
        let note = (f.overshoot > 0.0).then(|| {
            let what = match f.form {
                FitForm::Cylinder { .. } => "a cylinder",
                FitForm::Sphere { .. } => "a ball",
                FitForm::Box { .. } => "a box",
                FitForm::Capsule { .. } => "a capsule",
            };
            format!(
                "its hull's corners lie on {what}: planned as {what} through them, at most {} {unit} beyond the part's own hull",
                two_digits(f.overshoot)
            )
        });
        Piece {
            parts,
            word: "part",
            within: None,
            form: Form::Solid(f.placed(placement.0, placement.1), note),
        }
    };
    // One part: its convex pieces, when a cut pays (a part that is not
    // convex may still have a primitive for its hull: a tote's is a box).
    if let ([part], true) = (parts.as_slice(), separate) {
        if let Some(split) = split_pieces(part, (slots, room), &solid, &hull_piece)? {
            return Ok(split);
        }
    }
    if !(separate && parts.len() > 1 && parts.iter().all(|p| closed(&p.points))) {
        let all: Vec<[f64; 3]> = parts.iter().flat_map(|p| p.points.clone()).collect();
        let alone = match parts.as_slice() {
            [part] => Some(part),
            _ => None,
        };
        let piece = match fit(&all) {
            Some(f) => {
                // A primitive round a hollow part says how hollow, too.
                let mut piece = solid(Vec::new(), &f);
                if let (Form::Solid(_, note), Some(hollow)) =
                    (&mut piece.form, alone.and_then(hollow_note))
                {
                    *note = Some(match note.take() {
                        Some(n) => format!("{n}; {hollow}"),
                        None => hollow,
                    });
                }
                piece
            }
            None => hull_piece(Vec::new(), &all, alone)?,
        };
        return Ok((vec![piece], None));
    }
    let mut pieces = Vec::new();
    let mut rest = Vec::new();
    for (k, part) in parts.iter().enumerate() {
        match fit(&part.points) {
            Some(f) => pieces.push(solid(vec![k], &f)),
            None => rest.push(k),
        }
    }
    let note;
    if rest.len() > slots && slots > 0 {
        let points: Vec<Vec<[f64; 3]>> = rest.iter().map(|&k| parts[k].points.clone()).collect();
        let groups: Vec<Vec<usize>> = merge(&points, slots)
            .into_iter()
            .map(|g| g.into_iter().map(|i| rest[i]).collect())
            .collect();
        let listed: Vec<String> = groups
            .iter()
            .filter(|g| g.len() > 1)
            .map(|g| {
                let parts: Vec<String> = g.iter().map(|k| (k + 1).to_string()).collect();
                parts.join(" + ")
            })
            .collect();
        note = Some(format!(
            "its mesh has {} parts that are not boxes, cylinders or balls, more than the {slots} hull slots left for it (a scenario holds {MAX_HULLS} hulls): neighbouring parts share a hull that holds them ({}), which closes the gaps between them",
            rest.len(),
            listed.join("; ")
        ));
        for group in groups {
            let points: Vec<[f64; 3]> = group
                .iter()
                .flat_map(|&k| parts[k].points.clone())
                .collect();
            let alone = match group.as_slice() {
                [k] => parts.get(*k),
                _ => None,
            };
            pieces.push(hull_piece(group, &points, alone)?);
        }
    } else {
        // Hull slots and obstacles to spare: the parts that are not convex
        // (closed, `SPLIT_HOLLOW` or more of their hull empty), the most
        // hollow first, are split into convex pieces while they last.
        let mut spare = slots.saturating_sub(rest.len());
        let mut room_left = room.saturating_sub(parts.len());
        let hollowness = |k: usize| parts[k].hollowness().unwrap_or(0.0);
        let mut order = rest.clone();
        order.sort_by(|&a, &b| hollowness(b).total_cmp(&hollowness(a)));
        let mut split_notes = Vec::new();
        for k in order {
            let part = &parts[k];
            if spare > 0 && room_left > 0 && hollowness(k) >= SPLIT_HOLLOW {
                if let Some((split, split_note)) =
                    split_pieces(part, (1 + spare, 1 + room_left), &solid, &hull_piece)?
                {
                    let hulls = split
                        .iter()
                        .filter(|p| matches!(p.form, Form::Hull(..)))
                        .count();
                    spare = (spare + 1).saturating_sub(hulls);
                    room_left = (room_left + 1).saturating_sub(split.len());
                    pieces.extend(split.into_iter().map(|p| Piece {
                        within: Some(k),
                        ..p
                    }));
                    if let Some(n) = split_note {
                        split_notes.push((k, n));
                    }
                    continue;
                }
            }
            pieces.push(hull_piece(vec![k], &part.points, Some(part))?);
        }
        split_notes.sort_by_key(|(k, _)| *k);
        let listed: Vec<String> = split_notes
            .into_iter()
            .map(|(k, n)| format!("part {}: {n}", k + 1))
            .collect();
        note = (!listed.is_empty()).then(|| listed.join("; "));
    }
    pieces.sort_by_key(|p| match p.within {
        Some(k) => (Some(k), p.parts.first().copied()),
        None => (p.parts.first().copied(), None),
    });
    Ok((pieces, note))
}

/// A mesh's pieces, and the note on how they were made.
type Pieces = (Vec<Piece>, Option<String>);

/// Makes the piece of a fitted primitive (the parts it is made of).
type SolidPiece<'a> = dyn Fn(Vec<usize>, &crate::mesh_parts::Fitted) -> Piece + 'a;

/// Makes the piece of a hull round points (the parts it is made of, and the
/// part itself when it is one alone, for its note).
type HullPiece<'a> =
    dyn Fn(Vec<usize>, &[[f64; 3]], Option<&MeshPart>) -> Result<Piece, String> + 'a;

/// `part` split into convex pieces ([`crate::decompose`]), each a
/// primitive (`solid`) or a hull (`hull_piece`), at most `slots` of them
/// hulls and `room` in all (the obstacles the scenario has left for it),
/// and the note that says so; `None` when no cut pays (the part stays
/// whole). A first split within `slots` pieces; when some of them are
/// primitives (which take no hull slot), a second with that many more
/// pieces, kept if its hulls still fit.
fn split_pieces(
    part: &MeshPart,
    (slots, room): (usize, usize),
    solid: &SolidPiece,
    hull_piece: &HullPiece,
) -> Result<Option<Pieces>, String> {
    let pieces_of = |budget: usize| {
        let points = crate::decompose::decompose(part, budget);
        let fitted: Vec<_> = points.iter().map(|p| fit(p)).collect();
        (points, fitted)
    };
    let (mut points, mut fitted) = pieces_of(slots.min(room).max(1));
    let primitives = fitted.iter().filter(|f| f.is_some()).count();
    if primitives > 0 {
        let (more, more_fitted) =
            pieces_of((slots + primitives).min(MAX_SPLIT_PIECES).min(room).max(1));
        if more_fitted.iter().filter(|f| f.is_none()).count() <= slots {
            (points, fitted) = (more, more_fitted);
        }
    }
    if points.len() < 2 {
        return Ok(None);
    }
    let mut pieces = Vec::new();
    for (k, (p, f)) in points.iter().zip(&fitted).enumerate() {
        let mut piece = match f {
            Some(f) => solid(vec![k], f),
            None => hull_piece(vec![k], p, None)?,
        };
        piece.word = "piece";
        pieces.push(piece);
    }
    // How many pieces of each kind: boxes, cylinders, balls, capsules,
    // hulls.
    let mut counts = [0usize; 5];
    for f in &fitted {
        counts[match f.as_ref().map(|f| f.form) {
            Some(FitForm::Box { .. }) => 0,
            Some(FitForm::Cylinder { .. }) => 1,
            Some(FitForm::Sphere { .. }) => 2,
            Some(FitForm::Capsule { .. }) => 3,
            None => 4,
        }] += 1;
    }
    let kinds = [
        ("box", "boxes"),
        ("cylinder", "cylinders"),
        ("ball", "balls"),
        ("capsule", "capsules"),
        ("hull", "hulls"),
    ];
    let listed: Vec<String> = counts
        .iter()
        .zip(kinds)
        .filter(|(&n, _)| n > 0)
        .map(|(&n, (one, many))| format!("{n} {}", if n == 1 { one } else { many }))
        .collect();
    let held: f64 = points
        .iter()
        .filter_map(|p| crate::mesh_parts::hull_volume(p))
        .sum();
    let hollow = match part.volume().filter(|_| held > 0.0) {
        Some(v) if 1.0 - v / held < 0.005 => ", which hold it exactly".to_string(),
        Some(v) => format!(
            ", {:.0} % of whose volume is not the part",
            100.0 * (1.0 - v / held)
        ),
        None => String::new(),
    };
    let note = format!(
        "it is not convex: split along its own faces into {} convex pieces ({}){hollow}",
        points.len(),
        listed.join(", ")
    );
    Ok(Some((pieces, Some(note))))
}

/// Most pieces a part is split into.
const MAX_SPLIT_PIECES: usize = 24;

/// A part's hull is at least this hollow (the share of its volume that is
/// not the part) before the loader says so.
const HOLLOW_NOTE: f64 = 0.05;

/// A closed part of a mesh of several with this share of its hull or more
/// empty is split into convex pieces when hull slots are left
/// ([`mesh_pieces`]; a mesh of one part is always tried).
const SPLIT_HOLLOW: f64 = 0.02;

/// What the notes say of a part that is not convex (its closed surface
/// leaves [`HOLLOW_NOTE`] or more of its hull empty); `None` for a convex
/// part or an open surface.
fn hollow_note(part: &MeshPart) -> Option<String> {
    let hollow = part.hollowness().filter(|&h| h >= HOLLOW_NOTE)?;
    Some(format!(
        "it is not convex: planned round its convex hull, {:.0} % of which is not the part (no cut along its own faces pays: the arm keeps out of its hollows; to let it in, split the part into convex pieces, in CAD or with CoACD or V-HACD, written as OBJ objects)",
        100.0 * hollow
    ))
}

/// `x` (not negative) to two significant digits, in plain decimals (a
/// note's lengths run from microns to metres).
fn two_digits(x: f64) -> String {
    if x <= 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let decimals = (1 - x.log10().floor() as i32).max(0) as usize;
    format!("{x:.decimals$}")
}

/// What the notes say of a mesh part planned round an enclosure instead of
/// its hull (`None` when it is its hull).
fn enclosure_note(e: &Enclosure, unit: &str) -> Option<String> {
    (!e.is_exact()).then(|| {
        format!(
            "its hull has {} corners, more than the {MAX_HULL_VERTICES} a hull may have: planned round an enclosing hull of {} corners, at most {} {unit} beyond the part's own hull",
            e.hull_corners,
            e.corners.len(),
            two_digits(e.overshoot)
        )
    })
}

#[cfg(test)]
mod tests {
    use super::connected_parts;
    use crate::mesh_parts::MeshPart;

    #[test]
    fn parts_are_the_groups_of_faces_that_share_a_position() {
        // A tetrahedron written per triangle (as STL does), one corner as
        // -0 in some triangles and +0 in others, and a triangle apart.
        let (a, b, c) = ([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
        let (d, minus) = ([0.0, 0.0, 1.0], [-0.0, 0.0, -0.0]);
        let far = [[5.0, 0.0, 0.0], [6.0, 0.0, 0.0], [5.0, 1.0, 0.0]];
        let mut vertices = vec![a, b, c, minus, b, d, a, c, d, b, c, d];
        vertices.extend(far);
        let faces: Vec<[u32; 3]> = (0..5).map(|f| [3 * f, 3 * f + 1, 3 * f + 2]).collect();
        let parts = connected_parts(&vertices, &faces);
        let sorted = |p: &MeshPart| {
            let mut points = p.points.clone();
            points.sort_by(|x, y| x.partial_cmp(y).unwrap());
            points
        };
        assert_eq!(parts.len(), 2, "{parts:?}");
        assert_eq!(
            parts[0].points.len(),
            4,
            "the tetrahedron's 4 corners once each"
        );
        assert_eq!(sorted(&parts[1]), [far[0], far[2], far[1]]);
        // Each part keeps its triangles, on its own positions.
        assert_eq!(parts[0].triangles.len(), 4);
        assert_eq!(parts[1].triangles.len(), 1);
        let at = |p: &MeshPart, t: usize| p.triangles[t].map(|i| p.points[i]);
        assert_eq!(at(&parts[1], 0), far);
        assert_eq!(at(&parts[0], 3), [b, c, d]);
        // Wound two ways (its first face inward), the tetrahedron has no
        // volume to tell; wound outward, a sixth; the lone triangle is open.
        assert_eq!(parts[0].volume(), None);
        assert_eq!(parts[1].volume(), None);
        let outward = [a, c, b, a, b, d, a, d, c, b, c, d];
        let tetra = connected_parts(&outward, &faces[..4]);
        assert!((tetra[0].volume().unwrap() - 1.0 / 6.0).abs() < 1e-15);
        assert_eq!(tetra[0].hollowness(), Some(0.0));
        // A vertex no face names is a part of its own.
        vertices.push([9.0, 9.0, 9.0]);
        assert_eq!(connected_parts(&vertices, &faces).len(), 3);
    }
}
