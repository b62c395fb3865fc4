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
use capp_core::obstacle::MAX_HULLS;
use capp_core::{
    pips, Joint, JointKind, Motion, Robot, SetpointFilter, Settings, Shape, Solid, Waypoint,
};

use super::mesh_obstacle::{hull_of, mesh_parts, mesh_pieces, Form, Piece};
use crate::mesh_parts::MeshPart;
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
                    within: None,
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
                let within = piece.within.map(|k| format!(" part {}", k + 1));
                format!(
                    "{}{} {}{plural} {}",
                    s.name,
                    within.unwrap_or_default(),
                    piece.word,
                    list.join(", ")
                )
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
