//! The TOML scenario format. Every field is documented in `docs/scenario.md`;
//! this module is its reader.
//!
//! Units are explicit: `[units] angle = "degrees" | "radians"`, `length =
//! "inches" | "metres"`. Every angle in the file (DH twists and angles, limits,
//! revolute rates, start values, Euler angles) is in the angle unit; every
//! length (DH lengths, prismatic limits and rates, positions, semi-axes, length
//! settings) in the length unit. The loaded [`Problem`] is in radians and the
//! file's length unit; the PIPS preset (inches) and the length-valued default
//! settings (sized in inches) are converted to it.
//!
//! Unknown keys are errors (a misspelt setting must not be silently ignored).

use std::path::Path;

use capp_core::control::LawKind;
use capp_core::math::rotation_123;
use capp_core::obstacle::{Hull, MAX_HULLS, MAX_HULL_VERTICES};
use capp_core::{
    pips, Joint, JointKind, Motion, Robot, SetpointFilter, Settings, Shape, Solid, Waypoint,
};

use crate::enclosure::{enclose, Enclosure};
use crate::mesh_parts::{fit, merge, FitForm, MeshPart, Placed};
use serde::Deserialize;
use toml::Spanned;

use crate::problem::{
    DriveLimits, JointDriveLimits, LoadError, Problem, SourceKind, DEFAULT_CONTROL_PERIOD_S,
    DEFAULT_JERK_TIME_S, DEFAULT_RAMP_TIME_S, MAX_JOINTS, MAX_OBSTACLES,
};

/// Length of one inch in metres.
pub const INCH_M: f64 = 0.0254;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    name: Option<String>,
    #[serde(default)]
    description: String,
    units: Units,
    // Not `Spanned`: `[[robot.joints]]` defines the table implicitly, and an
    // implicit table has no span.
    robot: RobotSpec,
    start: Option<Spanned<StartSpec>>,
    #[serde(default)]
    waypoints: Vec<Spanned<PoseSpec>>,
    target: Spanned<PoseSpec>,
    #[serde(default)]
    obstacles: Vec<Spanned<ObstacleSpec>>,
    settings: Option<Spanned<SettingsSpec>>,
    output: Option<OutputSpec>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Units {
    angle: AngleUnit,
    length: LengthUnit,
}

#[derive(Deserialize, Clone, Copy)]
#[serde(rename_all = "lowercase")]
enum AngleUnit {
    Degrees,
    Radians,
}

#[derive(Deserialize, Clone, Copy, PartialEq)]
#[serde(rename_all = "lowercase")]
enum LengthUnit {
    Inches,
    #[serde(alias = "meters")]
    Metres,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RobotSpec {
    preset: Option<String>,
    joints: Option<Vec<Spanned<JointSpec>>>,
    /// A URDF file, relative to the scenario file.
    urdf: Option<String>,
    /// The URDF chain's base link (default: the tree's root).
    base_link: Option<String>,
    /// The URDF chain's tip link (default: the only leaf below the base
    /// reached through moving joints).
    tip_link: Option<String>,
    /// `package://NAME/...` roots, relative to the scenario file.
    #[serde(default)]
    packages: std::collections::BTreeMap<String, String>,
    /// Directories holding ROS packages, relative to the scenario file.
    #[serde(default)]
    package_dirs: Vec<String>,
    /// Whether each URDF joint's pivot is slid along its axis so the
    /// links' chords run through their bodies (default true).
    slide_pivots: Option<bool>,
    #[serde(default)]
    overrides: Vec<Spanned<OverrideSpec>>,
    /// Capsule radius of every link without its own `radius`, length units.
    link_radius: Option<f64>,
    /// Whether link pairs are kept apart (default true).
    self_collision: Option<bool>,
    /// More pairs of links allowed to touch.
    #[serde(default)]
    allow: Vec<Spanned<AllowSpec>>,
    /// Default `max_accel = max_rate / ramp_time_s`, s.
    ramp_time_s: Option<f64>,
    /// Default `max_jerk = max_accel / jerk_time_s`, s.
    jerk_time_s: Option<f64>,
}

/// `[[robot.allow]] links = [a, b]`: two links, by DH number (1 to n, link
/// `k` after joint `k`) or by the name of the joint before them.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct AllowSpec {
    links: [LinkRef; 2],
}

#[derive(Deserialize, Clone)]
#[serde(untagged)]
enum LinkRef {
    Number(i64),
    Name(String),
}

#[derive(Deserialize)]
#[serde(rename_all = "lowercase")]
enum JointType {
    Revolute,
    Prismatic,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct JointSpec {
    #[serde(default)]
    name: String,
    #[serde(rename = "type")]
    kind: JointType,
    alpha: f64,
    a: f64,
    #[serde(default)]
    theta: f64,
    #[serde(default)]
    d: f64,
    min: f64,
    max: f64,
    max_rate: f64,
    /// Acceleration limit, angle or length units per s^2.
    max_accel: Option<f64>,
    /// Jerk limit, angle or length units per s^3.
    max_jerk: Option<f64>,
    #[serde(default = "one")]
    weight: f64,
    /// Capsule radius of the link after this joint, length units.
    radius: Option<f64>,
}

fn one() -> f64 {
    1.0
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct OverrideSpec {
    /// By number (1 to n) or by name.
    joint: LinkRef,
    min: Option<f64>,
    max: Option<f64>,
    max_rate: Option<f64>,
    max_accel: Option<f64>,
    max_jerk: Option<f64>,
    weight: Option<f64>,
    radius: Option<f64>,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum StartSpec {
    Named(String),
    Values(Vec<f64>),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PoseSpec {
    position: Option<[f64; 3]>,
    euler: Option<[f64; 3]>,
    matrix: Option<[[f64; 3]; 3]>,
    /// A joint configuration instead of a pose.
    joints: Option<Vec<f64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ObstacleSpec {
    #[serde(default)]
    name: String,
    /// `superellipsoid` (the default), `sphere`, `box`, `capsule`, `cylinder`.
    shape: Option<String>,
    centre: [f64; 3],
    semi_axes: Option<[f64; 3]>,
    exponents: Option<[f64; 3]>,
    exponent: Option<f64>,
    radius: Option<f64>,
    length: Option<f64>,
    half_extents: Option<[f64; 3]>,
    /// `convex`: the points whose hull the obstacle is (its frame).
    vertices: Option<Vec<[f64; 3]>>,
    /// `mesh`: an STL or OBJ file, relative to the scenario file.
    mesh: Option<String>,
    /// `mesh`: length units per mesh unit (default 1).
    scale: Option<f64>,
    /// `mesh`: `"separate"` (the default: a hull per separate part) or
    /// `"one"` (one hull round the whole mesh).
    parts: Option<String>,
    #[serde(default)]
    euler: [f64; 3],
}

/// What an `[[obstacles]]` entry's keys describe.
enum Given {
    /// A primitive or a super-ellipsoid.
    Shape(Shape),
    /// `shape = "convex"`: the hull of these points (obstacle frame, length units).
    Vertices(Vec<[f64; 3]>),
    /// `shape = "mesh"`: the hull of a mesh file's vertices, times `scale`
    /// (or one hull per separate part).
    Mesh {
        /// The file as written.
        file: String,
        /// Length units per mesh unit.
        scale: f64,
        /// A hull per separate part (`parts = "separate"`), not one round all.
        separate: bool,
    },
}

/// Why points make no hull the core takes.
enum NoHull {
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
fn hull_of(points: &[[f64; 3]]) -> Result<Vec<[f32; 3]>, NoHull> {
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
fn mesh_parts(file: &Path, shown: &str) -> Result<Vec<MeshPart>, String> {
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
/// one part ([`crate::decompose`]).
struct Piece {
    parts: Vec<usize>,
    /// `"part"`, or `"piece"` for a piece of a part split in convex pieces.
    word: &'static str,
    form: Form,
}

enum Form {
    /// A mesh part that is a box, a cylinder or a ball
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
/// own (a closed part): each part that is a box, a cylinder or a ball
/// ([`fit`]) that solid, each other part a hull, and when those are more
/// than `slots` (the hull slots this obstacle may take), neighbouring ones
/// merged into `slots` hulls. Else (`parts = "one"`, or an open surface
/// such as a mesh of loose faces, whose parts are flat) one piece round
/// them all, a primitive if it is one.
/// `placement` is the mesh's centre and Euler angles, radians (for the
/// boxes).
fn mesh_pieces(
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
            form: Form::Hull(as_f32(&hull.corners), note),
        })
    };
    let solid = |parts: Vec<usize>, f: &crate::mesh_parts::Fitted| {
        let note = (f.overshoot > 0.0).then(|| {
            let what = match f.form {
                FitForm::Cylinder { .. } => "a cylinder",
                FitForm::Sphere { .. } => "a ball",
                FitForm::Box { .. } => "a box",
            };
            format!(
                "its hull's corners lie on {what}: planned as {what} through them, at most {} {unit} beyond the part's own hull",
                two_digits(f.overshoot)
            )
        });
        Piece {
            parts,
            word: "part",
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
    let mut note = None;
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
        for k in rest {
            pieces.push(hull_piece(vec![k], &parts[k].points, Some(&parts[k]))?);
        }
    }
    pieces.sort_by_key(|p| p.parts.first().copied());
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
    // How many pieces of each kind: boxes, cylinders, balls, hulls.
    let mut counts = [0usize; 4];
    for f in &fitted {
        counts[match f.as_ref().map(|f| f.form) {
            Some(FitForm::Box { .. }) => 0,
            Some(FitForm::Cylinder { .. }) => 1,
            Some(FitForm::Sphere { .. }) => 2,
            None => 3,
        }] += 1;
    }
    let kinds = [
        ("box", "boxes"),
        ("cylinder", "cylinders"),
        ("ball", "balls"),
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

impl ObstacleSpec {
    /// The shape the keys describe, or why not: each shape takes its own
    /// keys and no other's.
    fn shape(&self) -> Result<Given, String> {
        let kind = self.shape.as_deref().unwrap_or("superellipsoid");
        let given = [
            ("semi_axes", self.semi_axes.is_some()),
            ("exponents", self.exponents.is_some()),
            ("exponent", self.exponent.is_some()),
            ("radius", self.radius.is_some()),
            ("length", self.length.is_some()),
            ("half_extents", self.half_extents.is_some()),
            ("vertices", self.vertices.is_some()),
            ("mesh", self.mesh.is_some()),
            ("scale", self.scale.is_some()),
            ("parts", self.parts.is_some()),
        ];
        let takes: &[&str] = match kind {
            "superellipsoid" => &["semi_axes", "exponents", "exponent"],
            "sphere" => &["radius"],
            "box" => &["half_extents"],
            "capsule" | "cylinder" => &["radius", "length"],
            "convex" => &["vertices"],
            "mesh" => &["mesh", "scale", "parts"],
            other => {
                return Err(format!(
                    "obstacle: unknown shape \"{other}\" (superellipsoid, sphere, box, capsule, cylinder, convex, mesh)"
                ))
            }
        };
        if let Some((key, _)) = given.iter().find(|(key, set)| *set && !takes.contains(key)) {
            return Err(format!(
                "obstacle: `{key}` is not a key of shape \"{kind}\""
            ));
        }
        let missing = |key: &str| format!("obstacle: shape \"{kind}\" needs `{key}`");
        let f = |x: f64| x as f32;
        Ok(Given::Shape(match kind {
            "convex" => {
                return Ok(Given::Vertices(
                    self.vertices.clone().ok_or_else(|| missing("vertices"))?,
                ))
            }
            "mesh" => {
                let scale = self.scale.unwrap_or(1.0);
                if !(scale.is_finite() && scale > 0.0) {
                    return Err(format!(
                        "obstacle: `scale` must be positive and finite (got {scale})"
                    ));
                }
                let separate = match self.parts.as_deref() {
                    None | Some("separate") => true,
                    Some("one") => false,
                    Some(other) => {
                        return Err(format!(
                            "obstacle: `parts` is \"separate\" or \"one\" (got \"{other}\")"
                        ))
                    }
                };
                return Ok(Given::Mesh {
                    file: self.mesh.clone().ok_or_else(|| missing("mesh"))?,
                    scale,
                    separate,
                });
            }
            "superellipsoid" => {
                let semi_axes = self.semi_axes.ok_or_else(|| missing("semi_axes"))?;
                let exponents = match (self.exponents, self.exponent) {
                    (Some(_), Some(_)) => {
                        return Err(
                            "obstacle: give either `exponents` or `exponent`, not both".into()
                        )
                    }
                    (Some(k), None) => k,
                    (None, Some(k)) => [k; 3],
                    (None, None) => {
                        return Err(
                            "obstacle: missing `exponents` (or `exponent` for all three axes)"
                                .into(),
                        )
                    }
                };
                Shape::SuperEllipsoid {
                    semi_axes: semi_axes.map(f),
                    exponents: exponents.map(f),
                }
            }
            "sphere" => Shape::Sphere {
                radius: f(self.radius.ok_or_else(|| missing("radius"))?),
            },
            "box" => Shape::Cuboid {
                half_extents: self
                    .half_extents
                    .ok_or_else(|| missing("half_extents"))?
                    .map(f),
            },
            _ => {
                let radius = f(self.radius.ok_or_else(|| missing("radius"))?);
                let length = f(self.length.ok_or_else(|| missing("length"))?);
                if kind == "capsule" {
                    Shape::Capsule { radius, length }
                } else {
                    Shape::Cylinder { radius, length }
                }
            }
        }))
    }
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct SettingsSpec {
    characteristic_length: Option<f64>,
    time_step_s: Option<f64>,
    control_period_s: Option<f64>,
    fine_radius: Option<f64>,
    fine_step_fraction: Option<f64>,
    position_tolerance: Option<f64>,
    orientation_tolerance: Option<f64>,
    law: Option<LawSpec>,
    orientation_scale: Option<f64>,
    approach_radius: Option<f64>,
    joint_margin: Option<f64>,
    link_margin: Option<f64>,
    points_per_link: Option<u8>,
    influence_distance: Option<f64>,
    engage_clearance: Option<f64>,
    advance_fraction: Option<f64>,
    damping: Option<f64>,
    saturation: Option<bool>,
    motion: Option<MotionSpec>,
    max_steps: Option<u32>,
    stall_window: Option<u32>,
    stall_progress: Option<f64>,
    max_halvings: Option<u8>,
    escape_attempts: Option<u8>,
    escape_window: Option<u16>,
    escape_walk_steps: Option<u16>,
    escape_reach: Option<f64>,
    escape_seed: Option<u32>,
    escape_searches: Option<u8>,
}

#[derive(Deserialize, PartialEq)]
#[serde(rename_all = "lowercase")]
enum MotionSpec {
    Stepped,
    Tracked,
}

#[derive(Deserialize)]
#[serde(rename_all = "lowercase")]
enum LawSpec {
    Gradient,
    Paper,
    #[serde(rename = "damped_least_squares")]
    DampedLeastSquares,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct OutputSpec {
    setpoints: Option<SetpointSpec>,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum SetpointSpec {
    Named(String),
    Every(u32),
}

/// 1-based line of byte offset `at` in `text`.
fn line_of(text: &str, at: usize) -> usize {
    text.as_bytes()[..at.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// Parses a TOML scenario (not yet validated by the core: see [`Problem::validate`]).
pub fn parse(text: &str, path: &Path) -> Result<Problem, LoadError> {
    let file: File = toml::from_str(text).map_err(|e| {
        let line = e.span().map(|s| line_of(text, s.start));
        LoadError::new(path, line, e.message().trim().to_string())
    })?;
    let err = |line: usize, msg: String| LoadError::new(path, Some(line), msg);
    let at = |span: std::ops::Range<usize>| line_of(text, span.start);

    let angle = match file.units.angle {
        AngleUnit::Degrees => std::f64::consts::PI / 180.0,
        AngleUnit::Radians => 1.0,
    };
    // File length units per inch: converts inch-sized presets and defaults.
    let per_inch = match file.units.length {
        LengthUnit::Inches => 1.0,
        LengthUnit::Metres => INCH_M,
    };
    let length_unit = match file.units.length {
        LengthUnit::Inches => "in",
        LengthUnit::Metres => "m",
    };

    // Robot.
    let robot_line = text
        .lines()
        .position(|l| l.trim_start().starts_with("[robot") || l.trim_start().starts_with("robot"))
        .map_or(1, |i| i + 1);
    let robot = file.robot;
    let preset_pips = robot.preset.is_some();
    let mut radii: Vec<Option<f32>> = Vec::new();
    let mut link_segments: Vec<[[f32; 3]; 2]> = Vec::new();
    // Per joint, the acceleration and jerk limits the file gives (internal
    // units); the others default from the rate once overrides are applied.
    let mut drive_given: Vec<[Option<f64>; 2]> = Vec::new();
    // A drive limit as given: positive and finite, in the file's units.
    let positive = |line: usize, what: String, v: Option<f64>| -> Result<(), LoadError> {
        match v {
            Some(x) if !(x.is_finite() && x > 0.0) => Err(LoadError::new(
                path,
                Some(line),
                format!("{what} must be positive and finite (got {x})"),
            )),
            _ => Ok(()),
        }
    };
    let given = [
        robot.preset.is_some(),
        robot.joints.is_some(),
        robot.urdf.is_some(),
    ];
    match given.iter().filter(|&&g| g).count() {
        0 => {
            return Err(err(
                robot_line,
                "robot: missing `preset`, `joints` (a DH table) or `urdf` (a URDF file)".into(),
            ))
        }
        1 => {}
        _ => {
            return Err(err(
                robot_line,
                "robot: give one of `preset`, `joints` and `urdf`".into(),
            ))
        }
    }
    if robot.urdf.is_none()
        && (robot.base_link.is_some()
            || robot.tip_link.is_some()
            || robot.slide_pivots.is_some()
            || !robot.packages.is_empty()
            || !robot.package_dirs.is_empty())
    {
        return Err(err(
            robot_line,
            "robot: `base_link`, `tip_link`, `packages`, `package_dirs` and `slide_pivots` go with `urdf`".into(),
        ));
    }
    let mut tool = capp_core::robot::Placement::IDENTITY;
    let mut from_urdf = false;
    let mut urdf_source = None;
    let (mut joints, mut names, mut joint_lines, mut home) = match (&robot.preset, robot.joints) {
        (None, None) => {
            let file = robot.urdf.as_deref().unwrap_or_default();
            let here = path.parent().unwrap_or(Path::new("."));
            let options = capp_urdf::LoadOptions {
                base_link: robot.base_link.clone(),
                tip_link: robot.tip_link.clone(),
                packages: robot
                    .packages
                    .iter()
                    .map(|(name, dir)| (name.clone(), here.join(dir)))
                    .collect(),
                package_dirs: robot.package_dirs.iter().map(|d| here.join(d)).collect(),
                capsules_per_mesh: capp_urdf::CapsuleCount::Auto,
            };
            let imported = super::urdf::import(
                &here.join(file),
                &options,
                per_inch / INCH_M,
                robot.slide_pivots.unwrap_or(true),
            )
            .map_err(|e| err(robot_line, format!("robot.urdf: {e}")))?;
            let n = imported.joints.len();
            radii = imported.radii;
            link_segments = imported.segments;
            drive_given = vec![[None; 2]; n];
            tool = imported.tool;
            from_urdf = true;
            urdf_source = Some(crate::problem::UrdfSource {
                file: here.join(file),
                robot_name: imported.chain.robot_name.clone(),
                base_link: imported.chain.base_link.clone(),
                tip_link: imported.chain.tip_link.clone(),
                bodies: imported.chain.bodies.clone(),
                pivot_slide: imported.pivot_slide.clone(),
                per_metre: per_inch / INCH_M,
            });
            (
                imported.joints,
                imported.names,
                vec![Some(robot_line); n],
                imported.home,
            )
        }
        (Some(_), Some(_)) => {
            return Err(err(
                robot_line,
                "robot: give one of `preset`, `joints` and `urdf`".into(),
            ))
        }
        (Some(preset), None) => {
            if !preset.eq_ignore_ascii_case("pips") {
                return Err(err(
                    robot_line,
                    format!("robot: unknown preset \"{preset}\" (known: \"pips\")"),
                ));
            }
            let scale = per_inch as f32;
            let joints: Vec<Joint> = pips::joints()
                .iter()
                .map(|j| scale_lengths(*j, scale))
                .collect();
            let home: Vec<f32> = pips::home()
                .iter()
                .zip(&joints)
                .map(|(&q, j)| match j.kind {
                    JointKind::Revolute => q,
                    JointKind::Prismatic => q * scale,
                })
                .collect();
            let names = (1..=joints.len()).map(|i| format!("pips{i}")).collect();
            let lines = vec![Some(robot_line); joints.len()];
            radii = vec![None; joints.len()];
            drive_given = vec![[None; 2]; joints.len()];
            (joints, names, lines, home)
        }
        (None, Some(specs)) => {
            if specs.is_empty() {
                return Err(err(robot_line, "robot: `joints` is empty".into()));
            }
            let mut joints = Vec::new();
            let mut names = Vec::new();
            let mut lines = Vec::new();
            let mut home = Vec::new();
            for spec in specs {
                let line = at(spec.span());
                let s = spec.into_inner();
                radii.push(s.radius.map(|r| r as f32));
                let label = match s.name.as_str() {
                    "" => format!("robot: joint {}", joints.len() + 1),
                    name => format!("robot: joint {} (\"{name}\")", joints.len() + 1),
                };
                positive(line, format!("{label}: max_accel"), s.max_accel)?;
                positive(line, format!("{label}: max_jerk"), s.max_jerk)?;
                let unit = match s.kind {
                    JointType::Revolute => angle,
                    JointType::Prismatic => 1.0,
                };
                drive_given.push([s.max_accel.map(|v| v * unit), s.max_jerk.map(|v| v * unit)]);
                let (joint, q0) = match s.kind {
                    JointType::Revolute => (
                        Joint {
                            kind: JointKind::Revolute,
                            alpha: (s.alpha * angle) as f32,
                            a: s.a as f32,
                            theta: 0.0,
                            d: s.d as f32,
                            min: (s.min * angle) as f32,
                            max: (s.max * angle) as f32,
                            max_rate: (s.max_rate * angle) as f32,
                            weight: s.weight as f32,
                            origin: None,
                        },
                        (s.theta * angle) as f32,
                    ),
                    JointType::Prismatic => (
                        Joint {
                            kind: JointKind::Prismatic,
                            alpha: (s.alpha * angle) as f32,
                            a: s.a as f32,
                            theta: (s.theta * angle) as f32,
                            d: 0.0,
                            min: s.min as f32,
                            max: s.max as f32,
                            max_rate: s.max_rate as f32,
                            weight: s.weight as f32,
                            origin: None,
                        },
                        s.d as f32,
                    ),
                };
                joints.push(joint);
                names.push(s.name);
                lines.push(Some(line));
                home.push(q0);
            }
            (joints, names, lines, home)
        }
    };
    for o in robot.overrides {
        let line = at(o.span());
        let o = o.into_inner();
        let index = match &o.joint {
            LinkRef::Number(i) if *i >= 1 && (*i as usize) <= joints.len() => *i as usize,
            LinkRef::Number(i) => {
                return Err(err(
                    line,
                    format!(
                        "robot override: joint {i} does not exist (joints are numbered 1 to {})",
                        joints.len()
                    ),
                ))
            }
            LinkRef::Name(name) => match names.iter().position(|n| n == name) {
                Some(k) => k + 1,
                None => {
                    return Err(err(
                        line,
                        format!("robot override: no joint is named \"{name}\""),
                    ))
                }
            },
        };
        let j = &mut joints[index - 1];
        let unit = match j.kind {
            JointKind::Revolute => angle,
            JointKind::Prismatic => 1.0,
        };
        if let Some(v) = o.min {
            j.min = (v * unit) as f32;
        }
        if let Some(v) = o.max {
            j.max = (v * unit) as f32;
        }
        if let Some(v) = o.max_rate {
            j.max_rate = (v * unit) as f32;
        }
        positive(
            line,
            format!("robot override of joint {index}: max_accel"),
            o.max_accel,
        )?;
        positive(
            line,
            format!("robot override of joint {index}: max_jerk"),
            o.max_jerk,
        )?;
        let given = &mut drive_given[index - 1];
        if let Some(v) = o.max_accel {
            given[0] = Some(v * unit);
        }
        if let Some(v) = o.max_jerk {
            given[1] = Some(v * unit);
        }
        if let Some(v) = o.weight {
            j.weight = v as f32;
        }
        if let Some(v) = o.radius {
            radii[index - 1] = Some(v as f32);
        }
        joint_lines[index - 1] = Some(line);
    }
    if from_urdf {
        for (k, joint) in joints.iter().enumerate() {
            let missing = super::urdf::missing_fields(joint);
            if !missing.is_empty() {
                return Err(err(
                    joint_lines[k].unwrap_or(robot_line),
                    format!(
                        "robot: joint {} (\"{}\"): the URDF gives no {}; give {} in a [[robot.overrides]] entry",
                        k + 1,
                        names[k],
                        missing.join(", "),
                        missing.join(" and "),
                    ),
                ));
            }
        }
    }
    if names.iter().all(|n| n.is_empty()) {
        names.clear();
    }

    // Drive limits: those given, else from the rate (the rate as the core
    // holds it, after the preset's unit conversion and the overrides).
    let ramp_time_s = robot.ramp_time_s.unwrap_or(DEFAULT_RAMP_TIME_S);
    let jerk_time_s = robot.jerk_time_s.unwrap_or(DEFAULT_JERK_TIME_S);
    positive(robot_line, "robot.ramp_time_s".into(), Some(ramp_time_s))?;
    positive(robot_line, "robot.jerk_time_s".into(), Some(jerk_time_s))?;
    let drive_joints: Vec<JointDriveLimits> = joints
        .iter()
        .zip(&drive_given)
        .map(|(j, [accel, jerk])| {
            let max_rate = j.max_rate as f64;
            let max_accel = accel.unwrap_or(max_rate / ramp_time_s);
            JointDriveLimits {
                max_rate,
                max_accel,
                max_jerk: jerk.unwrap_or(max_accel / jerk_time_s),
            }
        })
        .collect();

    // Pairs of links allowed to touch, by number or joint name.
    let mut allowed: Vec<(usize, usize)> = if preset_pips {
        pips::allowed_pairs()
            .map(|(a, b)| (a as usize, b as usize))
            .collect()
    } else {
        Vec::new()
    };
    let mut allow_lines = Vec::new();
    for spec in robot.allow {
        let line = at(spec.span());
        let mut pair = [0usize; 2];
        for (k, link) in spec.into_inner().links.iter().enumerate() {
            pair[k] = match link {
                LinkRef::Number(i) if *i >= 1 && (*i as usize) <= joints.len() => *i as usize - 1,
                LinkRef::Number(i) => {
                    return Err(err(
                        line,
                        format!(
                            "robot.allow: link {i} does not exist (links are numbered 1 to {})",
                            joints.len()
                        ),
                    ))
                }
                LinkRef::Name(name) => match names.iter().position(|n| n == name) {
                    Some(j) => j,
                    None => {
                        return Err(err(
                            line,
                            format!("robot.allow: unknown link \"{name}\" (name a link by its number or by the joint before it)"),
                        ))
                    }
                },
            };
        }
        if pair[0] == pair[1] {
            return Err(err(
                line,
                format!(
                    "robot.allow: a link cannot be paired with itself (link {})",
                    pair[0] + 1
                ),
            ));
        }
        allowed.push((pair[0], pair[1]));
        allow_lines.push(Some(line));
    }
    let link_home = home.clone();

    // Start configuration.
    let (start, start_line) = match file.start {
        None => (std::mem::take(&mut home), None),
        Some(spec) => {
            let line = at(spec.span());
            match spec.into_inner() {
                StartSpec::Named(name) if name == "home" => (std::mem::take(&mut home), Some(line)),
                StartSpec::Named(name) => {
                    return Err(err(
                        line,
                        format!("start: unknown configuration \"{name}\" (give \"home\" or a list of joint values)"),
                    ))
                }
                StartSpec::Values(values) => {
                    if values.len() != joints.len() {
                        return Err(err(
                            line,
                            format!(
                                "start: {} values for {} joints",
                                values.len(),
                                joints.len()
                            ),
                        ));
                    }
                    let q = values
                        .iter()
                        .zip(&joints)
                        .map(|(&v, j)| match j.kind {
                            JointKind::Revolute => (v * angle) as f32,
                            JointKind::Prismatic => v as f32,
                        })
                        .collect();
                    (q, Some(line))
                }
            }
        }
    };

    // Waypoints, then the target.
    let mut waypoints = Vec::new();
    let mut joint_goals = Vec::new();
    let mut waypoint_lines = Vec::new();
    let count = file.waypoints.len();
    for (i, spec) in file.waypoints.into_iter().chain([file.target]).enumerate() {
        let line = at(spec.span());
        let what = if i == count {
            "target".to_string()
        } else {
            format!("waypoint {}", i + 1)
        };
        let s = spec.into_inner();
        let position = match (s.position, s.joints) {
            (Some(p), None) => p,
            (None, Some(values)) => {
                if s.euler.is_some() || s.matrix.is_some() {
                    return Err(err(
                        line,
                        format!("{what}: a joint configuration has no `euler` or `matrix`"),
                    ));
                }
                if values.len() != joints.len() {
                    return Err(err(
                        line,
                        format!(
                            "{what}: `joints` has {} values for {} joints",
                            values.len(),
                            joints.len()
                        ),
                    ));
                }
                let q: Vec<f32> = values
                    .iter()
                    .zip(&joints)
                    .map(|(&v, j)| match j.kind {
                        JointKind::Revolute => (v * angle) as f32,
                        JointKind::Prismatic => v as f32,
                    })
                    .collect();
                joint_goals.push((i, q));
                // A placeholder: the core puts the configuration's pose here.
                waypoints.push(Waypoint::at([0.0; 3]));
                waypoint_lines.push(Some(line));
                continue;
            }
            (Some(_), Some(_)) => {
                return Err(err(
                    line,
                    format!("{what}: give either `position` or `joints`, not both"),
                ))
            }
            (None, None) => return Err(err(line, format!("{what}: give `position` or `joints`"))),
        };
        let orientation = match (s.euler, s.matrix) {
            (Some(_), Some(_)) => {
                return Err(err(
                    line,
                    format!("{what}: give either `euler` or `matrix`, not both"),
                ))
            }
            (Some(e), None) => {
                if !e.iter().all(|x| x.is_finite()) {
                    return Err(err(line, format!("{what}: `euler` is not finite")));
                }
                let r = rotation_123(
                    (e[0] * angle) as f32,
                    (e[1] * angle) as f32,
                    (e[2] * angle) as f32,
                );
                Some([
                    [r[(0, 0)], r[(0, 1)], r[(0, 2)]],
                    [r[(1, 0)], r[(1, 1)], r[(1, 2)]],
                    [r[(2, 0)], r[(2, 1)], r[(2, 2)]],
                ])
            }
            (None, Some(m)) => Some(m.map(|row| row.map(|x| x as f32))),
            (None, None) => None,
        };
        waypoints.push(Waypoint {
            position: position.map(|x| x as f32),
            orientation,
        });
        waypoint_lines.push(Some(line));
    }

    // Obstacles.
    let mut obstacles = Vec::new();
    let mut obstacle_names = Vec::new();
    let mut obstacle_lines = Vec::new();
    let mut hulls: Vec<Vec<[f32; 3]>> = Vec::new();
    // What the loader did that a user should know of (meshes enclosed).
    let mut notes: Vec<String> = Vec::new();
    // Whether each obstacle needs hull slots (a `convex` or a `mesh`): a
    // mesh of many parts leaves one slot for each such obstacle after it.
    let needs_hull: Vec<bool> = file
        .obstacles
        .iter()
        .map(|spec| matches!(spec.get_ref().shape.as_deref(), Some("convex" | "mesh")))
        .collect();
    for (index, spec) in file.obstacles.into_iter().enumerate() {
        let line = at(spec.span());
        let s = spec.into_inner();
        let solid = |shape| Solid {
            centre: s.centre.map(|x| x as f32),
            euler_123: s.euler.map(|x| (x * angle) as f32),
            shape,
        };
        let who = |name: &str, index: usize| {
            if name.is_empty() {
                format!("obstacle {index} (line {line})")
            } else {
                format!("obstacle \"{name}\" (line {line})")
            }
        };
        let later = needs_hull.iter().skip(index + 1).filter(|&&h| h).count();
        let slots = MAX_HULLS.saturating_sub(hulls.len() + later);
        // The obstacles a split part may become: one each left for the
        // entries after it.
        let room = MAX_OBSTACLES.saturating_sub(obstacles.len() + (needs_hull.len() - index - 1));
        let pieces: Vec<Piece> = match s.shape().map_err(|e| err(line, e))? {
            Given::Shape(shape) => {
                obstacles.push(solid(shape));
                obstacle_names.push(s.name);
                obstacle_lines.push(Some(line));
                continue;
            }
            Given::Vertices(v) => {
                let corners = hull_of(&v).map_err(|e| err(line, format!("obstacle: {e}")))?;
                vec![Piece {
                    parts: Vec::new(),
                    word: "part",
                    form: Form::Hull(corners, None),
                }]
            }
            Given::Mesh {
                file,
                scale,
                separate,
            } => {
                let here = path.parent().unwrap_or(Path::new("."));
                let parts = mesh_parts(&here.join(&file), &file).map_err(|e| err(line, e))?;
                let scaled: Vec<MeshPart> = parts
                    .into_iter()
                    .map(|part| MeshPart {
                        points: part.points.iter().map(|p| p.map(|x| x * scale)).collect(),
                        triangles: part.triangles,
                    })
                    .collect();
                let placement = (s.centre, s.euler.map(|x| x * angle));
                let (pieces, merged) =
                    mesh_pieces(scaled, separate, (slots, room), &placement, length_unit)
                        .map_err(|e| err(line, format!("obstacle: mesh \"{file}\": {e}")))?;
                if let Some(m) = merged {
                    notes.push(format!("{}: {m}", who(&s.name, obstacles.len())));
                }
                pieces
            }
        };
        let wanted = pieces
            .iter()
            .filter(|p| matches!(p.form, Form::Hull(..)))
            .count();
        if hulls.len() + wanted > MAX_HULLS {
            return Err(err(
                line,
                format!("obstacle: more than {MAX_HULLS} convex or mesh obstacles (each has its own hull, and a scenario holds {MAX_HULLS})"),
            ));
        }
        let several = pieces.len() > 1 || pieces.iter().any(|p| p.parts.len() > 1);
        for piece in pieces {
            let name = if several {
                let list: Vec<String> = piece.parts.iter().map(|k| (k + 1).to_string()).collect();
                let plural = if piece.parts.len() > 1 { "s" } else { "" };
                format!("{} {}{plural} {}", s.name, piece.word, list.join(", "))
                    .trim_start()
                    .to_string()
            } else {
                s.name.clone()
            };
            match piece.form {
                Form::Solid(placed, note) => {
                    obstacles.push(Solid {
                        centre: placed.centre,
                        euler_123: placed.euler_123,
                        shape: placed.shape,
                    });
                    if let Some(note) = note {
                        notes.push(format!("{}: {note}", who(&name, obstacles.len() - 1)));
                    }
                }
                Form::Hull(corners, note) => {
                    hulls.push(corners);
                    obstacles.push(solid(Shape::Convex {
                        hull: (hulls.len() - 1) as u8,
                    }));
                    if let Some(note) = note {
                        notes.push(format!("{}: {note}", who(&name, obstacles.len() - 1)));
                    }
                }
            }
            obstacle_names.push(name);
            obstacle_lines.push(Some(line));
        }
    }

    // Settings: the core's defaults relative to the robot's characteristic
    // length (its reach, or the one the file states), so they mean the same
    // in any unit. A robot the core will refuse gets the inch defaults
    // converted; validation then reports what is wrong with it.
    let settings_line = file.settings.as_ref().map(|s| at(s.span()));
    let s = file.settings.map(|s| s.into_inner()).unwrap_or_default();
    let f = |v: Option<f64>, d: f32| v.map_or(d, |x| x as f32);
    let mut settings = match (
        s.characteristic_length,
        Robot::<MAX_JOINTS>::new_with_tool(&joints, &tool),
    ) {
        (Some(length), _) if length.is_finite() && length > 0.0 => {
            Settings::relative_to(length as f32)
        }
        (Some(_), _) => {
            return Err(LoadError::new(
                path,
                settings_line,
                "settings.characteristic_length must be positive and finite",
            ))
        }
        (None, Ok(robot)) => Settings::for_robot(&robot),
        (None, Err(_)) => default_settings(per_inch as f32),
    };
    settings.time_step_s = f(s.time_step_s, settings.time_step_s);
    let control_period_s = s.control_period_s.unwrap_or(DEFAULT_CONTROL_PERIOD_S);
    if !(control_period_s > 0.0 && control_period_s <= 1.0) {
        return Err(LoadError::new(
            path,
            settings_line,
            format!("settings.control_period_s must be in (0, 1] s (got {control_period_s})"),
        ));
    }
    settings.fine_radius = f(s.fine_radius, settings.fine_radius);
    settings.fine_step_fraction = f(s.fine_step_fraction, settings.fine_step_fraction);
    settings.position_tolerance = f(s.position_tolerance, settings.position_tolerance);
    settings.orientation_tolerance = f(s.orientation_tolerance, settings.orientation_tolerance);
    if let Some(law) = s.law {
        settings.law.kind = match law {
            LawSpec::Gradient => LawKind::Gradient,
            LawSpec::Paper => LawKind::Paper,
            LawSpec::DampedLeastSquares => LawKind::DampedLeastSquares,
        };
    }
    settings.law.damping = f(s.damping, settings.law.damping);
    if s.motion == Some(MotionSpec::Tracked) {
        // The tracker's tick is the drives' period.
        if s.time_step_s.is_some_and(|h| h != control_period_s) {
            return Err(LoadError::new(
                path,
                settings_line,
                "settings.time_step_s: with motion = \"tracked\" the step is control_period_s; give that one",
            ));
        }
        settings.motion = Motion::Tracked;
        settings.time_step_s = control_period_s as f32;
    }
    if let Some(v) = s.saturation {
        settings.law.saturation = v;
    }
    settings.avoidance.engage_clearance =
        f(s.engage_clearance, settings.avoidance.engage_clearance);
    settings.avoidance.advance_fraction =
        f(s.advance_fraction, settings.avoidance.advance_fraction);
    settings.law.orientation_scale = f(s.orientation_scale, settings.law.orientation_scale);
    settings.law.approach_radius = f(s.approach_radius, settings.law.approach_radius);
    settings.avoidance.joint_margin = f(s.joint_margin, settings.avoidance.joint_margin);
    settings.avoidance.link_margin = f(s.link_margin, settings.avoidance.link_margin);
    settings.avoidance.influence_distance =
        f(s.influence_distance, settings.avoidance.influence_distance);
    if let Some(v) = s.points_per_link {
        settings.avoidance.points_per_link = v;
    }
    if let Some(v) = s.max_steps {
        settings.max_steps = v;
    }
    if let Some(v) = s.stall_window {
        settings.stall_window = v;
    }
    settings.stall_progress = f(s.stall_progress, settings.stall_progress);
    if let Some(v) = s.max_halvings {
        settings.max_halvings = v;
    }
    if let Some(v) = s.escape_attempts {
        settings.escape.attempts = v;
    }
    if let Some(v) = s.escape_window {
        settings.escape.window = v;
    }
    if let Some(v) = s.escape_walk_steps {
        settings.escape.walk_steps = v;
    }
    settings.escape.reach = f(s.escape_reach, settings.escape.reach);
    if let Some(v) = s.escape_seed {
        settings.escape.seed = v;
    }
    if let Some(v) = s.escape_searches {
        settings.escape.searches = v;
    }

    // Link capsules: a joint's own `radius`, else `[robot] link_radius`,
    // else the preset's, else half the link margin (PIPS: 1.5 in).
    let default_radius = match robot.link_radius {
        Some(r) => r as f32,
        None if preset_pips => pips::LINK_RADIUS * per_inch as f32,
        None => 0.5 * settings.avoidance.link_margin,
    };
    if !(default_radius.is_finite() && default_radius > 0.0) {
        return Err(err(
            robot_line,
            "robot.link_radius must be positive and finite".into(),
        ));
    }
    let links = crate::problem::LinkGeometry {
        enabled: robot.self_collision.unwrap_or(true),
        radius: radii.iter().map(|r| r.unwrap_or(default_radius)).collect(),
        segments: link_segments,
        allowed,
        home: link_home,
    };

    let setpoints = match file.output.and_then(|o| o.setpoints) {
        None => SetpointFilter::LISTING,
        Some(SetpointSpec::Named(n)) if n == "listing" => SetpointFilter::LISTING,
        Some(SetpointSpec::Named(n)) => {
            return Err(LoadError::new(
                path,
                None,
                format!(
                    "output.setpoints: unknown policy \"{n}\" (give \"listing\" or a step count)"
                ),
            ))
        }
        Some(SetpointSpec::Every(k)) => SetpointFilter::Every(k.max(1)),
    };

    let name = file.name.unwrap_or_else(|| {
        path.file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default()
    });
    // A joint goal's waypoint is its configuration's pose (the core's own
    // kinematics, as the planner will compute it), for reports and pictures.
    if let Ok(robot) = Robot::<MAX_JOINTS>::new_with_tool(&joints, &tool) {
        let mut frames = capp_core::kinematics::Frames::<MAX_JOINTS>::default();
        for (w, q) in &joint_goals {
            if q.len() == joints.len() {
                capp_core::kinematics::forward_kinematics(&robot, q, &mut frames);
                let p = frames.end_position();
                let r = frames.end_rotation();
                if let Some(waypoint) = waypoints.get_mut(*w) {
                    *waypoint = Waypoint::pose(
                        [p.x, p.y, p.z],
                        [0, 1, 2].map(|i| [r[(i, 0)], r[(i, 1)], r[(i, 2)]]),
                    );
                }
            }
        }
    }
    Ok(Problem {
        joint_goals,
        notes,
        name,
        description: file.description.trim().to_string(),
        source: path.to_path_buf(),
        kind: SourceKind::Toml,
        length_unit: length_unit.into(),
        joints,
        tool,
        urdf: urdf_source,
        joint_names: names,
        obstacles,
        obstacle_names,
        hulls,
        waypoints,
        settings,
        start,
        setpoints,
        links,
        drive: DriveLimits {
            control_period_s,
            joints: drive_joints,
        },
        lines: crate::problem::Lines {
            robot: Some(robot_line),
            joints: joint_lines,
            obstacles: obstacle_lines,
            waypoints: waypoint_lines,
            orientations: Vec::new(),
            settings: settings_line,
            start: start_line,
            allow: allow_lines,
        },
    })
}

/// The core's defaults (sized for inches) with every length scaled by `per_inch`.
pub fn default_settings(per_inch: f32) -> Settings {
    let mut s = Settings::default();
    if per_inch != 1.0 {
        s.fine_radius *= per_inch;
        s.position_tolerance *= per_inch;
        s.law.orientation_scale *= per_inch;
        s.law.approach_radius *= per_inch;
        s.avoidance.joint_margin *= per_inch;
        s.avoidance.link_margin *= per_inch;
        s.avoidance.influence_distance *= per_inch;
    }
    s
}

fn scale_lengths(mut j: Joint, scale: f32) -> Joint {
    if scale == 1.0 {
        return j;
    }
    j.a *= scale;
    j.d *= scale;
    if j.kind == JointKind::Prismatic {
        j.min *= scale;
        j.max *= scale;
        j.max_rate *= scale;
    }
    j
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
