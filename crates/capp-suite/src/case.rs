//! A benchmark case: an ordinary scenario file (TOML, `host-sim/docs/scenario.md`)
//! and the goal configuration its target was computed from.
//!
//! [`Spec`] writes the file. Angles are radians and every number is written
//! as the `f32` the loader will read, so the start in the file, the start the
//! planner gets and the start the oracle checks are the same values. Settings
//! not written take the loader's defaults (sized in inches, converted for
//! metres), so the suite follows when the defaults change.

use std::fmt::Write as _;
use std::path::Path;

use capp_sim::input::scenario_file;
use capp_sim::{LoadError, Problem};

/// Length unit of a case file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Unit {
    /// Inches (PIPS).
    Inches,
    /// Metres (the iiwa and the planar arm).
    Metres,
}

impl Unit {
    /// The `[units] length` value.
    pub fn toml(self) -> &'static str {
        match self {
            Unit::Inches => "inches",
            Unit::Metres => "metres",
        }
    }

    /// Short label ("in", "m").
    pub fn label(self) -> &'static str {
        match self {
            Unit::Inches => "in",
            Unit::Metres => "m",
        }
    }
}

/// One revolute joint of a DH table (radians, the file's length unit).
#[derive(Clone, Debug, PartialEq)]
pub struct DhJoint {
    /// Name.
    pub name: &'static str,
    /// Link twist.
    pub alpha: f64,
    /// Link length.
    pub a: f64,
    /// Offset.
    pub d: f64,
    /// Home angle.
    pub theta: f64,
    /// Limits.
    pub min: f64,
    /// Limits.
    pub max: f64,
    /// Rate limit per second.
    pub max_rate: f64,
}

/// The robot of a case.
#[derive(Clone, Debug, PartialEq)]
pub enum RobotSpec {
    /// The loader's PIPS preset (Table 1).
    Pips,
    /// A revolute DH table.
    Table(Vec<DhJoint>),
    /// A URDF file's chain ([`UrdfRobot`]).
    Urdf(UrdfRobot),
}

/// A robot from a URDF file: `[robot] urdf`, `base_link`, `tip_link`,
/// `packages` and `[[robot.overrides]]`.
///
/// A generated case is read as `<name>.toml` in no particular directory
/// ([`parse`]), so a relative `urdf` path would resolve against the working
/// directory: the paths here are absolute ([`repo_path`]), and a case file
/// written anywhere (`--write-cases`) loads as it is.
#[derive(Clone, Debug, PartialEq)]
pub struct UrdfRobot {
    /// The URDF file (absolute).
    pub urdf: String,
    /// The chain's base link.
    pub base_link: &'static str,
    /// The chain's tip link.
    pub tip_link: &'static str,
    /// `package://NAME/...` roots (absolute).
    pub packages: Vec<(&'static str, String)>,
    /// Per joint (by URDF name): `key = value` lines (TOML, radians / file
    /// units), e.g. `("min", "-3.1415927")`.
    pub overrides: Vec<(&'static str, Vec<(&'static str, String)>)>,
}

/// `rel` (a path under the repository root, `/`-separated) as an absolute
/// path: the root is two folders above this crate's manifest.
pub fn repo_path(rel: &str) -> String {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .and_then(Path::parent)
        .unwrap_or(Path::new("."));
    let mut path = root.to_path_buf();
    if !rel.is_empty() {
        path.push(rel);
    }
    path.to_string_lossy().into_owned()
}

/// A TOML basic string: quoted, with backslashes and quotes escaped.
fn toml_string(s: &str) -> String {
    format!("\"{}\"", s.replace('\\', "\\\\").replace('"', "\\\""))
}

/// An obstacle: a shape placed at a centre, lengths in the file's unit,
/// Euler angles in radians.
#[derive(Clone, Debug, PartialEq)]
pub struct Obstacle {
    /// Name (says what it is: "floor", "shelf board 2", "in the way (joint path)").
    pub name: String,
    /// Centre.
    pub centre: [f64; 3],
    /// The shape in its own frame.
    pub shape: Form,
    /// 1-2-3 Euler angles, `R = Rz Ry Rx`.
    pub euler: [f64; 3],
}

/// An obstacle's shape in its own frame (capp-core's `Shape`, in `f64`;
/// capsules and cylinders along z).
#[derive(Clone, Debug, PartialEq)]
pub enum Form {
    /// Eq. 25.
    SuperEllipsoid {
        /// Semi-axes.
        semi_axes: [f64; 3],
        /// Exponents.
        exponents: [f64; 3],
    },
    /// A ball.
    Sphere {
        /// Radius.
        radius: f64,
    },
    /// A true box.
    Cuboid {
        /// Half-extents.
        half_extents: [f64; 3],
    },
    /// A capsule of segment `length` along z.
    Capsule {
        /// Radius.
        radius: f64,
        /// The segment's length.
        length: f64,
    },
    /// A cylinder along z, flat ends.
    Cylinder {
        /// Radius.
        radius: f64,
        /// Length.
        length: f64,
    },
    /// The convex hull of `vertices` (`shape = "convex"`), each written as
    /// the `f32` the loader reads: a part from CAD.
    Convex {
        /// The hull's corners in the obstacle's frame.
        vertices: Vec<[f64; 3]>,
    },
}

impl Form {
    /// capp-core's shape (`f32`); a convex one names hull `hull` (the
    /// scenario's hulls are its convex obstacles' in order).
    pub fn core(&self, hull: u8) -> capp_core::Shape {
        use capp_core::Shape as S;
        let f = |x: f64| x as f32;
        match *self {
            Form::SuperEllipsoid {
                semi_axes,
                exponents,
            } => S::SuperEllipsoid {
                semi_axes: semi_axes.map(f),
                exponents: exponents.map(f),
            },
            Form::Sphere { radius } => S::Sphere { radius: f(radius) },
            Form::Cuboid { half_extents } => S::Cuboid {
                half_extents: half_extents.map(f),
            },
            Form::Capsule { radius, length } => S::Capsule {
                radius: f(radius),
                length: f(length),
            },
            Form::Cylinder { radius, length } => S::Cylinder {
                radius: f(radius),
                length: f(length),
            },
            Form::Convex { .. } => S::Convex { hull },
        }
    }

    /// A convex shape's vertices as the loader reads them (`f32`).
    pub fn hull(&self) -> Option<Vec<[f32; 3]>> {
        match self {
            Form::Convex { vertices } => {
                Some(vertices.iter().map(|v| v.map(|x| x as f32)).collect())
            }
            _ => None,
        }
    }

    /// The scenario file's keys for the shape (`shape = ...` and its sizes).
    fn toml(&self) -> String {
        match self {
            Form::SuperEllipsoid {
                semi_axes,
                exponents,
            } => format!(
                "semi_axes = {}\nexponents = {}",
                list(semi_axes),
                list(exponents)
            ),
            Form::Sphere { radius } => format!("shape = \"sphere\"\nradius = {}", num(*radius)),
            Form::Cuboid { half_extents } => {
                format!("shape = \"box\"\nhalf_extents = {}", list(half_extents))
            }
            Form::Capsule { radius, length } => {
                let (r, l) = (num(*radius), num(*length));
                format!("shape = \"capsule\"\nradius = {r}\nlength = {l}")
            }
            Form::Cylinder { radius, length } => {
                let (r, l) = (num(*radius), num(*length));
                format!("shape = \"cylinder\"\nradius = {r}\nlength = {l}")
            }
            Form::Convex { vertices } => {
                let rows: Vec<String> = vertices.iter().map(|v| list(v)).collect();
                format!(
                    "shape = \"convex\"\nvertices = [\n  {},\n]",
                    rows.join(",\n  ")
                )
            }
        }
    }
}

impl Obstacle {
    /// A box (a super-ellipsoid of exponent 8), axis aligned.
    pub fn cuboid(name: impl Into<String>, centre: [f64; 3], semi_axes: [f64; 3]) -> Self {
        Obstacle {
            name: name.into(),
            centre,
            shape: Form::SuperEllipsoid {
                semi_axes,
                exponents: [8.0; 3],
            },
            euler: [0.0; 3],
        }
    }

    /// A shape placed at `centre`, axis aligned.
    pub fn solid(name: impl Into<String>, centre: [f64; 3], shape: Form) -> Self {
        Obstacle {
            name: name.into(),
            centre,
            shape,
            euler: [0.0; 3],
        }
    }

    /// A cylinder along axis `axis` (0 = x, 1 = y, 2 = z): flat ends (8), round section (2).
    pub fn cylinder(
        name: impl Into<String>,
        centre: [f64; 3],
        axis: usize,
        radius: f64,
        half_length: f64,
    ) -> Self {
        let mut semi_axes = [radius; 3];
        semi_axes[axis] = half_length;
        let mut exponents = [2.0; 3];
        exponents[axis] = 8.0;
        Obstacle {
            name: name.into(),
            centre,
            shape: Form::SuperEllipsoid {
                semi_axes,
                exponents,
            },
            euler: [0.0; 3],
        }
    }

    /// The same obstacle turned by `rz` about the world z axis through the origin.
    pub fn turned(mut self, rz: f64) -> Self {
        let (s, c) = libm::sincos(rz);
        let [x, y, z] = self.centre;
        self.centre = [c * x - s * y, s * x + c * y, z];
        self.euler[2] += rz;
        self
    }
}

/// Everything a case file says.
#[derive(Clone, Debug, PartialEq)]
pub struct Spec {
    /// `name`.
    pub name: String,
    /// `description`.
    pub description: String,
    /// Comment lines written at the top (without `#`).
    pub comments: Vec<String>,
    /// Length unit.
    pub unit: Unit,
    /// Robot.
    pub robot: RobotSpec,
    /// More `[robot]` lines (`key = value`, TOML, in the file's units):
    /// `link_radius`, `self_collision`. Empty: the loader's defaults.
    pub robot_settings: Vec<(String, String)>,
    /// Start configuration (radians / length units).
    pub start: Vec<f64>,
    /// Target position.
    pub target: [f64; 3],
    /// Target orientation, rows of the rotation matrix, or none.
    pub orientation: Option<[[f64; 3]; 3]>,
    /// Obstacles.
    pub obstacles: Vec<Obstacle>,
    /// `[settings]` lines, `key = value`, in the file's units.
    pub settings: Vec<(String, String)>,
}

/// `x` as the `f32` the loader reads, in a form that reads back to that `f32`.
pub fn num(x: f64) -> String {
    format!("{:?}", x as f32)
}

/// `x` rounded to the `f32` the loader will read.
pub fn round(x: f64) -> f64 {
    x as f32 as f64
}

fn list(values: &[f64]) -> String {
    let items: Vec<String> = values.iter().map(|&v| num(v)).collect();
    format!("[{}]", items.join(", "))
}

impl Spec {
    /// The scenario file.
    pub fn to_toml(&self) -> String {
        let mut s = String::new();
        for c in &self.comments {
            let _ = writeln!(s, "# {c}");
        }
        let _ = writeln!(s, "name = \"{}\"", self.name);
        let _ = writeln!(
            s,
            "description = \"\"\"\n{}\n\"\"\"",
            self.description.trim()
        );
        let _ = writeln!(s, "start = {}", list(&self.start));
        let _ = writeln!(
            s,
            "\n[units]\nangle = \"radians\"\nlength = \"{}\"",
            self.unit.toml()
        );
        if matches!(self.robot, RobotSpec::Pips | RobotSpec::Urdf(_))
            || !self.robot_settings.is_empty()
        {
            s.push_str("\n[robot]\n");
        }
        match &self.robot {
            RobotSpec::Pips => s.push_str("preset = \"pips\"\n"),
            RobotSpec::Urdf(u) => {
                let _ = writeln!(s, "urdf = {}", toml_string(&u.urdf));
                let _ = writeln!(s, "base_link = {}", toml_string(u.base_link));
                let _ = writeln!(s, "tip_link = {}", toml_string(u.tip_link));
                if !u.packages.is_empty() {
                    let items: Vec<String> = u
                        .packages
                        .iter()
                        .map(|(name, dir)| format!("{} = {}", toml_string(name), toml_string(dir)))
                        .collect();
                    let _ = writeln!(s, "packages = {{ {} }}", items.join(", "));
                }
            }
            RobotSpec::Table(_) => {}
        }
        for (k, v) in &self.robot_settings {
            let _ = writeln!(s, "{k} = {v}");
        }
        match &self.robot {
            RobotSpec::Pips => {}
            RobotSpec::Urdf(u) => {
                for (joint, lines) in &u.overrides {
                    let _ = writeln!(s, "\n[[robot.overrides]]\njoint = {}", toml_string(joint));
                    for (k, v) in lines {
                        let _ = writeln!(s, "{k} = {v}");
                    }
                }
            }
            RobotSpec::Table(joints) => {
                for j in joints {
                    let _ = writeln!(
                        s,
                        "\n[[robot.joints]]\nname = \"{}\"\ntype = \"revolute\"\nalpha = {}\na = {}\nd = {}\ntheta = {}\nmin = {}\nmax = {}\nmax_rate = {}",
                        j.name,
                        num(j.alpha),
                        num(j.a),
                        num(j.d),
                        num(j.theta),
                        num(j.min),
                        num(j.max),
                        num(j.max_rate)
                    );
                }
            }
        }
        let _ = writeln!(s, "\n[target]\nposition = {}", list(&self.target));
        if let Some(m) = &self.orientation {
            let _ = writeln!(
                s,
                "matrix = [{}, {}, {}]",
                list(&m[0]),
                list(&m[1]),
                list(&m[2])
            );
        }
        for o in &self.obstacles {
            let _ = writeln!(
                s,
                "\n[[obstacles]]\nname = \"{}\"\ncentre = {}\n{}",
                o.name,
                list(&o.centre),
                o.shape.toml()
            );
            if o.euler != [0.0; 3] {
                let _ = writeln!(s, "euler = {}", list(&o.euler));
            }
        }
        if !self.settings.is_empty() {
            s.push_str("\n[settings]\n");
            for (k, v) in &self.settings {
                let _ = writeln!(s, "{k} = {v}");
            }
        }
        s
    }

    /// The file as the loader reads it (not validated).
    pub fn parse(&self) -> Result<Problem, LoadError> {
        parse(&self.to_toml(), &self.name)
    }
}

/// Parses scenario text as `capp run` would read `<name>.toml`.
pub fn parse(text: &str, name: &str) -> Result<Problem, LoadError> {
    parse_at(text, Path::new(&format!("{name}.toml")))
}

/// Parses scenario text as `capp run` would read the file at `path`: its
/// relative paths (a `mesh`, a URDF) from the file's folder.
pub fn parse_at(text: &str, path: &Path) -> Result<Problem, LoadError> {
    scenario_file::parse(text, path)
}

/// A generated case.
#[derive(Clone, Debug, PartialEq)]
pub struct Case {
    /// Family name.
    pub family: &'static str,
    /// Index within the family.
    pub index: usize,
    /// `family-index`, also the scenario's `name`.
    pub name: String,
    /// What varies in this case, in a few words.
    pub tags: String,
    /// The scenario file.
    pub text: String,
    /// Start configuration, as in the file.
    pub start: Vec<f64>,
    /// Goal configuration: collision free, within limits; the target is its pose.
    pub goal: Vec<f64>,
    /// The obstacles written into the file, in its order.
    pub obstacles: Vec<Obstacle>,
}
