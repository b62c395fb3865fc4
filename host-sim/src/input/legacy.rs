//! CAPP.c's own file formats: `input.dat` (read) and `joints.dat` (written).
//!
//! `input.dat`, whitespace separated, as the listing's `fscanf` calls read it
//! (see `docs/algorithm.md`, section 5):
//!
//! ```text
//! n
//! alpha theta a d metric flag            (n lines; flag 1 = revolute, 0 = prismatic; radians)
//! step tolerance n_waypoints
//! x y z                                  (n_waypoints lines; the first is the first target)
//! r11 r12 r13 r21 r22 r23 r31 r32 r33    (target orientation, row by row)
//! n_obstacles
//! cx cy cz a b c kx ky kz rx ry rz       (per obstacle; R = Rz(rz) Ry(ry) Rx(rx))
//! ```
//!
//! What the listing leaves out, and what we put in its place:
//!
//! * **Start**: `theta` of revolute joints and `d` of prismatic ones, as the listing.
//! * **Joint limits**: none in the listing. Revolute joints get `[-2 pi, 2 pi]`,
//!   prismatic joints their start value `+-` [`PRISMATIC_RANGE`].
//! * **Rate limits**: the listing clips revolute rates to `0.175` rad/s
//!   ([`REVOLUTE_RATE`]); prismatic rates are unclipped there, [`PRISMATIC_RATE`] here.
//! * **Weights**: `metric / max(metric)` (the core needs weights in `(0, 1]`; the
//!   listing normalises the rate vector anyway, so only the ratios matter).
//! * **Orientation**: the one target orientation applies at every waypoint, and
//!   the orientation tolerance is the listing's `0.4`.
//! * **Flag**: 1 is revolute, 0 prismatic; any other value is rejected (the
//!   listing would silently read it as prismatic).
//! * Everything else is the core's default settings (lengths taken as inches).
//!
//! `joints.dat`: each joint vector on two lines, the first `n/2` values then
//! the rest, `%f ` each (six decimals and a trailing space), as `joints_print`.

use std::fmt::Write as _;
use std::path::Path;

use capp_core::{Joint, JointKind, SetpointFilter, Settings, Solid, SuperEllipsoid, Waypoint};

use crate::problem::{Lines, LoadError, Problem, SourceKind};

/// Revolute rate limit of the listing, rad/s (`fabs(rate_p[i]) > .175 * step_s`).
pub const REVOLUTE_RATE: f32 = 0.175;
/// Prismatic rate limit given to legacy inputs, length units per second.
pub const PRISMATIC_RATE: f32 = 2.0;
/// Half-range of prismatic joints around their start value, length units.
pub const PRISMATIC_RANGE: f32 = 100.0;
/// The listing's orientation tolerance.
pub const ORIENTATION_TOLERANCE: f32 = 0.4;

struct Tokens<'a> {
    items: Vec<(usize, &'a str)>,
    next: usize,
    path: &'a Path,
    last_line: usize,
}

impl<'a> Tokens<'a> {
    fn new(text: &'a str, path: &'a Path) -> Self {
        let items: Vec<(usize, &str)> = text
            .lines()
            .enumerate()
            .flat_map(|(i, l)| l.split_whitespace().map(move |t| (i + 1, t)))
            .collect();
        let last_line = text.lines().count().max(1);
        Tokens {
            items,
            next: 0,
            path,
            last_line,
        }
    }

    fn error(&self, line: usize, message: String) -> LoadError {
        LoadError::new(self.path, Some(line), message)
    }

    /// The next token, or an "ended early" error naming what was expected.
    fn take(&mut self, what: &str) -> Result<(usize, &'a str), LoadError> {
        match self.items.get(self.next) {
            Some(&t) => {
                self.next += 1;
                Ok(t)
            }
            None => Err(self.error(
                self.last_line,
                format!("the file ends early: expected {what}"),
            )),
        }
    }

    fn number(&mut self, what: &str) -> Result<(usize, f64), LoadError> {
        let (line, token) = self.take(what)?;
        let value: f64 = token.parse().map_err(|_| {
            self.error(
                line,
                format!("expected {what} (a number), found \"{token}\""),
            )
        })?;
        if !value.is_finite() {
            return Err(self.error(line, format!("{what} is \"{token}\", not a finite number")));
        }
        Ok((line, value))
    }

    fn count(&mut self, what: &str, max: usize) -> Result<(usize, usize), LoadError> {
        let (line, token) = self.take(what)?;
        let value: usize = token.parse().map_err(|_| {
            self.error(
                line,
                format!("expected {what} (a whole number), found \"{token}\""),
            )
        })?;
        if value > max {
            return Err(self.error(
                line,
                format!("{what} is {value}, more than the {max} supported"),
            ));
        }
        Ok((line, value))
    }
}

/// Parses `input.dat` text (not yet validated by the core: see [`Problem::validate`]).
pub fn parse(text: &str, path: &Path) -> Result<Problem, LoadError> {
    use crate::problem::{MAX_JOINTS, MAX_OBSTACLES, MAX_WAYPOINTS};
    let mut t = Tokens::new(text, path);
    let (n_line, n) = t.count("the number of joints", MAX_JOINTS)?;
    if n == 0 {
        return Err(t.error(n_line, "the number of joints is 0".into()));
    }
    let mut joints = Vec::with_capacity(n);
    let mut start = Vec::with_capacity(n);
    let mut metrics = Vec::with_capacity(n);
    let mut joint_lines = Vec::with_capacity(n);
    for j in 1..=n {
        let row = format!("joint {j} of {n}");
        let (line, alpha) = t.number(&format!("alpha of {row}"))?;
        let (_, theta) = t.number(&format!("theta of {row}"))?;
        let (_, a) = t.number(&format!("a of {row}"))?;
        let (_, d) = t.number(&format!("d of {row}"))?;
        let (m_line, metric) = t.number(&format!("metric of {row}"))?;
        let (f_line, flag) = t.take(&format!("flag of {row}"))?;
        if metric <= 0.0 {
            return Err(t.error(
                m_line,
                format!("joint {j}: metric is {metric}; it must be positive"),
            ));
        }
        let joint = match flag {
            "1" => Joint {
                kind: JointKind::Revolute,
                alpha: alpha as f32,
                a: a as f32,
                theta: 0.0,
                d: d as f32,
                min: -std::f32::consts::TAU,
                max: std::f32::consts::TAU,
                max_rate: REVOLUTE_RATE,
                weight: 1.0,
                origin: None,
            },
            "0" => Joint {
                kind: JointKind::Prismatic,
                alpha: alpha as f32,
                a: a as f32,
                theta: theta as f32,
                d: 0.0,
                min: d as f32 - PRISMATIC_RANGE,
                max: d as f32 + PRISMATIC_RANGE,
                max_rate: PRISMATIC_RATE,
                weight: 1.0,
                origin: None,
            },
            other => {
                let hint = if joints.len() + 1 < n && other.contains('.') {
                    " (is the joint count on line 1 right, and does every joint line have 6 values?)"
                } else {
                    ""
                };
                return Err(t.error(
                    f_line,
                    format!("joint {j}: unknown joint type flag \"{other}\" (1 = revolute, 0 = prismatic){hint}"),
                ));
            }
        };
        start.push(match joint.kind {
            JointKind::Revolute => theta as f32,
            JointKind::Prismatic => d as f32,
        });
        joints.push(joint);
        metrics.push(metric);
        joint_lines.push(Some(line));
    }
    let largest = metrics.iter().cloned().fold(0.0f64, f64::max);
    for (joint, m) in joints.iter_mut().zip(&metrics) {
        joint.weight = (m / largest) as f32;
    }

    let (s_line, step) = t.number("the step size")?;
    let (_, tolerance) = t.number("the position tolerance")?;
    let (w_line, n_waypoints) = t.count("the number of waypoints", MAX_WAYPOINTS)?;
    if n_waypoints == 0 {
        return Err(t.error(
            w_line,
            "the number of waypoints is 0: there is no target".into(),
        ));
    }
    let mut positions = Vec::new();
    let mut waypoint_lines = Vec::new();
    for w in 1..=n_waypoints {
        let (line, x) = t.number(&format!("x of waypoint {w} of {n_waypoints}"))?;
        let (_, y) = t.number(&format!("y of waypoint {w}"))?;
        let (_, z) = t.number(&format!("z of waypoint {w}"))?;
        positions.push([x as f32, y as f32, z as f32]);
        waypoint_lines.push(Some(line));
    }
    let mut rows = [[0.0f32; 3]; 3];
    let mut r_line = 0;
    for (i, row) in rows.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            let (line, x) = t.number(&format!("r{}{} of the target orientation", i + 1, j + 1))?;
            if i == 0 && j == 0 {
                r_line = line;
            }
            *v = x as f32;
        }
    }
    let (_, n_obstacles) = t.count("the number of obstacles", MAX_OBSTACLES)?;
    let mut obstacles = Vec::new();
    let mut obstacle_lines = Vec::new();
    for o in 1..=n_obstacles {
        let mut v = [0.0f32; 12];
        let mut first = 0;
        const NAMES: [&str; 12] = [
            "cx", "cy", "cz", "a", "b", "c", "kx", "ky", "kz", "rx", "ry", "rz",
        ];
        for (k, slot) in v.iter_mut().enumerate() {
            let (line, x) = t.number(&format!(
                "{} of obstacle {o} of {n_obstacles} (12 values: cx cy cz a b c kx ky kz rx ry rz)",
                NAMES[k]
            ))?;
            if k == 0 {
                first = line;
            }
            if (3..6).contains(&k) && x <= 0.0 {
                return Err(t.error(
                    line,
                    format!(
                        "obstacle {o}: semi-axis {} is {x}; semi-axes must be positive",
                        NAMES[k]
                    ),
                ));
            }
            *slot = x as f32;
        }
        obstacles.push(Solid::from(SuperEllipsoid {
            centre: [v[0], v[1], v[2]],
            semi_axes: [v[3], v[4], v[5]],
            exponents: [v[6], v[7], v[8]],
            euler_123: [v[9], v[10], v[11]],
        }));
        obstacle_lines.push(Some(first));
    }
    if let Some(&(line, token)) = t.items.get(t.next) {
        return Err(t.error(
            line,
            format!("unexpected extra value \"{token}\" after the last obstacle (do the joint, waypoint and obstacle counts match the data?)"),
        ));
    }

    let settings = Settings {
        time_step_s: step as f32,
        position_tolerance: tolerance as f32,
        orientation_tolerance: ORIENTATION_TOLERANCE,
        ..Settings::default()
    };
    // The listing's orientation holds at every waypoint.
    let waypoints = positions.iter().map(|&p| Waypoint::pose(p, rows)).collect();
    let orientation_lines = vec![Some(r_line); n_waypoints];
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let listing_home = start.clone();
    // The listing's robot is PIPS: then its capsules and pedestal group
    // are the preset's; any other DH table gets half the link margin.
    let is_pips = joints.len() == capp_core::pips::JOINTS
        && joints.iter().zip(capp_core::pips::joints()).all(|(a, b)| {
            a.kind == b.kind
                && (a.alpha - b.alpha).abs() < 1e-3
                && (a.a - b.a).abs() < 1e-3
                && (a.d - b.d).abs() < 1e-3
                && (a.theta - b.theta).abs() < 1e-3
        });
    let (radius, allowed) = if is_pips {
        (
            capp_core::pips::LINK_RADIUS,
            capp_core::pips::allowed_pairs()
                .map(|(a, b)| (a as usize, b as usize))
                .collect(),
        )
    } else {
        (0.5 * settings.avoidance.link_margin, Vec::new())
    };
    // The listing has no drive limits: the defaults from its rates.
    let drive = crate::problem::DriveLimits::defaults(&joints);
    Ok(Problem {
        notes: Vec::new(),
        tool: capp_core::robot::Placement::IDENTITY,
        urdf: None,
        joint_goals: Vec::new(),
        name,
        description: String::new(),
        source: path.to_path_buf(),
        kind: SourceKind::Legacy,
        length_unit: "in".into(),
        joints,
        joint_names: Vec::new(),
        obstacles,
        obstacle_names: Vec::new(),
        hulls: Vec::new(),
        waypoints,
        settings,
        start,
        setpoints: SetpointFilter::LISTING,
        // Pairs in contact at the listing's start are skipped.
        links: crate::problem::LinkGeometry {
            enabled: true,
            radius: vec![radius; n],
            segments: Vec::new(),
            allowed,
            home: listing_home,
        },
        drive,
        lines: Lines {
            robot: Some(n_line),
            joints: joint_lines,
            obstacles: obstacle_lines,
            waypoints: waypoint_lines,
            orientations: orientation_lines,
            settings: Some(s_line),
            start: Some(n_line + 1),
            allow: Vec::new(),
        },
    })
}

/// One joint vector as `joints_print` writes it: two lines, `n/2` values then the rest.
pub fn joints_dat_record(q: &[f32], out: &mut String) {
    let half = q.len() / 2;
    for v in &q[..half] {
        let _ = write!(out, "{v:.6} ");
    }
    out.push('\n');
    for v in &q[half..] {
        let _ = write!(out, "{v:.6} ");
    }
    out.push('\n');
}
