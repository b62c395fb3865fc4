//! What every family does the same way: a draft scene with its independent
//! geometry, random configurations within limits and clear of it, obstacles
//! placed in the way, and the finished, re-read and validated case file.
//!
//! A family may also ask that its configurations keep the links apart
//! ([`Draft::keep_links_apart`]): then "clear" also means that every pair of
//! links the scenario checks (its allowed-collision matrix, as `capp acm`
//! prints it) keeps its capsules `gap >= margin (r_a + r_b)` apart, by the
//! independent `f64` model's capsules ([`Geometry::link_gaps`]).

use capp_core::Solid;
use capp_sim::geometry::{forward, Geometry};
use capp_sim::Problem;

use crate::case::{self, num, round, Case, Obstacle, RobotSpec, Spec, Unit};
use crate::rng::Rng;

/// `C - 1` every avoidance point of a start or goal keeps from every inflated
/// obstacle (by the independent `f64` checker): far above `f32` rounding, so
/// the planner never refuses a start the checker accepts.
pub const CLEAR_MARGIN: f64 = 0.02;

/// A scene under construction: the spec and the problem the loader makes of
/// it (obstacles are added to both in the same `f32` values).
pub struct Draft {
    /// The file so far (its start and target are placeholders until [`Draft::finish`]).
    pub spec: Spec,
    problem: Problem,
    geometry: Geometry,
    /// The smallest link clearance starts and goals keep, when the family
    /// asks for it ([`Draft::keep_links_apart`]).
    link_margin: Option<f64>,
    /// The box random starts and goals are drawn in, when narrower than the
    /// joint limits ([`Draft::sample_within`]).
    sample_limits: Option<Vec<(f64, f64)>>,
}

/// The closest checked pair of links of a configuration, with the
/// planner's dimensionless clearance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinkClearance {
    /// The two links, 0-based (DH links `a + 1`, `b + 1`).
    pub links: (usize, usize),
    /// Distance between their capsules (the capsule segments' distance less both radii), length units.
    pub gap: f64,
    /// `gap / (r_a + r_b)`, as the planner measures a link pair.
    pub clearance: f64,
}

/// The closest pair of links at `q` among those `geometry` checks (the
/// scenario's allowed-collision matrix) at least `apart` links apart on the
/// chain (`b - a >= apart`); `None` when there is none. `problem` gives the
/// radii.
pub fn closest_links(
    problem: &Problem,
    geometry: &Geometry,
    q: &[f64],
    apart: usize,
) -> Option<LinkClearance> {
    let pose = geometry.pose(q);
    let radius = |k: usize| problem.links.radius.get(k).map_or(0.0, |&r| r as f64);
    geometry
        .checked_pairs()
        .iter()
        .zip(geometry.link_gaps(&pose))
        .filter(|(&(a, b), _)| b - a >= apart)
        .map(|(&(a, b), gap)| LinkClearance {
            links: (a, b),
            gap,
            clearance: gap / (radius(a) + radius(b)),
        })
        .min_by(|x, y| x.clearance.total_cmp(&y.clearance))
}

impl Draft {
    /// A draft from `spec` (start: any valid configuration, e.g. home).
    pub fn new(spec: Spec) -> Option<Draft> {
        let problem = spec.parse().ok()?;
        let geometry = Geometry::new(&problem);
        Some(Draft {
            spec,
            problem,
            geometry,
            link_margin: None,
            sample_limits: None,
        })
    }

    /// From now on a configuration is clear only if every pair of links the
    /// scenario checks keeps `gap / (r_a + r_b) >= margin` (see
    /// [`Draft::link_gap`]). `None` when the scenario has no self-collision
    /// checks.
    pub fn keep_links_apart(&mut self, margin: f64) -> Option<()> {
        self.geometry.self_collision().then(|| {
            self.link_margin = Some(margin);
        })
    }

    /// The closest checked pair of links at `q` at least `apart` links
    /// apart on the chain ([`closest_links`]).
    pub fn link_gap(&self, q: &[f64], apart: usize) -> Option<LinkClearance> {
        closest_links(&self.problem, &self.geometry, q, apart)
    }

    /// Whether the links at `q` keep the margin of [`Draft::keep_links_apart`]
    /// (always, when not asked).
    pub fn links_apart(&self, q: &[f64]) -> bool {
        match self.link_margin {
            Some(margin) => self.link_gap(q, 0).is_none_or(|g| g.clearance >= margin),
            None => true,
        }
    }

    /// From now on random starts and goals ([`Draft::random_clear`],
    /// [`Draft::random_goal`]) are drawn within `within` of each joint's
    /// middle (radians or length units), clipped to its limits; the
    /// planner and the oracle keep the whole range.
    pub fn sample_within(&mut self, within: f64) {
        let limits = self
            .limits()
            .into_iter()
            .map(|(lo, hi)| {
                let mid = 0.5 * (lo + hi);
                (lo.max(mid - within), hi.min(mid + within))
            })
            .collect();
        self.sample_limits = Some(limits);
    }

    fn sampling_box(&self) -> Vec<(f64, f64)> {
        self.sample_limits.clone().unwrap_or_else(|| self.limits())
    }

    /// The loaded problem of the draft.
    pub fn problem(&self) -> &Problem {
        &self.problem
    }

    /// Joint limits.
    pub fn limits(&self) -> Vec<(f64, f64)> {
        self.problem
            .joints
            .iter()
            .map(|j| (j.min as f64, j.max as f64))
            .collect()
    }

    /// Adds an obstacle.
    pub fn push(&mut self, o: Obstacle) {
        let hull = self.problem.hulls.len() as u8;
        if let Some(vertices) = o.shape.hull() {
            self.problem.hulls.push(vertices);
        }
        self.problem.obstacles.push(Solid {
            centre: o.centre.map(|x| x as f32),
            euler_123: o.euler.map(|x| x as f32),
            shape: o.shape.core(hull),
        });
        self.problem.obstacle_names.push(o.name.clone());
        self.spec.obstacles.push(o);
        self.geometry = Geometry::new(&self.problem);
    }

    /// Removes the last obstacle.
    pub fn pop(&mut self) {
        if let Some(Solid {
            shape: capp_core::Shape::Convex { .. },
            ..
        }) = self.problem.obstacles.pop()
        {
            self.problem.hulls.pop();
        }
        self.problem.obstacle_names.pop();
        self.spec.obstacles.pop();
        self.geometry = Geometry::new(&self.problem);
    }

    /// Whether `q` is within limits and clear of every obstacle by
    /// [`CLEAR_MARGIN`] (and its links apart, when the family asked:
    /// [`Draft::keep_links_apart`]).
    pub fn clear(&self, q: &[f64]) -> bool {
        within_limits(&self.problem, q)
            && self.geometry.is_clear(q, CLEAR_MARGIN)
            && self.links_apart(q)
    }

    /// Adds `o` if every configuration in `keep` stays clear; returns whether it did.
    pub fn push_if_clear(&mut self, o: Obstacle, keep: &[&[f64]]) -> bool {
        self.push(o);
        if keep.iter().all(|q| self.clear(q)) {
            true
        } else {
            self.pop();
            false
        }
    }

    /// The start of a case: `ready` when `from_ready` and it is clear, else
    /// a random clear configuration (within 0.8 of every range, 400 draws at
    /// most); and whether it is `ready`.
    pub fn ready_or_random(
        &self,
        rng: &mut Rng,
        ready: Vec<f64>,
        from_ready: bool,
    ) -> Option<(Vec<f64>, bool)> {
        if from_ready && self.clear(&ready) {
            Some((ready, true))
        } else {
            Some((self.random_clear(rng, 0.8, 400)?, false))
        }
    }

    /// A random configuration within `fraction` of every joint's range about
    /// its middle (of the box of [`Draft::sample_within`], when set), clear
    /// of the scene (`tries` draws at most).
    pub fn random_clear(&self, rng: &mut Rng, fraction: f64, tries: usize) -> Option<Vec<f64>> {
        let limits = self.sampling_box();
        (0..tries)
            .map(|_| random_config(rng, &limits, fraction))
            .find(|q| self.clear(q))
    }

    /// A random clear configuration whose end effector is at least `min_move`
    /// from that of `from`.
    pub fn random_goal(
        &self,
        rng: &mut Rng,
        from: &[f64],
        fraction: f64,
        min_move: f64,
        tries: usize,
    ) -> Option<Vec<f64>> {
        let p0 = end_pose(&self.problem, from).0;
        let limits = self.sampling_box();
        (0..tries)
            .map(|_| random_config(rng, &limits, fraction))
            .find(|q| dist(end_pose(&self.problem, q).0, p0) >= min_move && self.clear(q))
    }

    /// Places obstacles made by `make(rng, centre, scale)` at points drawn
    /// from `candidates`, keeping start and goal clear: up to `tries`
    /// candidates, each shrunk (scale 1, 0.7, 0.49, 0.34) until it fits.
    /// Returns whether one was placed.
    pub fn place(
        &mut self,
        rng: &mut Rng,
        candidates: &[[f64; 3]],
        keep: &[&[f64]],
        tries: usize,
        make: impl Fn(&mut Rng, [f64; 3], f64) -> Obstacle,
    ) -> bool {
        if candidates.is_empty() {
            return false;
        }
        for _ in 0..tries {
            let centre = candidates[rng.below(candidates.len())];
            let mut scale = 1.0;
            for _ in 0..4 {
                if self.push_if_clear(make(rng, centre, scale), keep) {
                    return true;
                }
                scale *= 0.7;
            }
        }
        false
    }

    /// Boxes in the way of the motion from `start` to `goal`: one or two at
    /// arm points of the joint-space midpoint (links from `skip` on), then
    /// one on the straight end-effector path, each of half sizes drawn from
    /// `half_size` (length units) and shrunk by `place` until start and goal
    /// stay clear. Returns how many were placed.
    pub fn boxes_in_the_way(
        &mut self,
        rng: &mut Rng,
        start: &[f64],
        goal: &[f64],
        skip: usize,
        half_size: (f64, f64),
    ) -> usize {
        let boxed = |label: &'static str| {
            move |rng: &mut Rng, centre: [f64; 3], scale: f64| {
                let s = [0, 1, 2].map(|_| scale * rng.range(half_size.0, half_size.1));
                Obstacle::cuboid(label, centre, s)
            }
        };
        let joint_path = arm_points(&self.problem, &midpoint(start, goal), skip);
        let mut placed = 0;
        for _ in 0..1 + rng.below(2) {
            placed += self.place(
                rng,
                &joint_path,
                &[start, goal],
                8,
                boxed("in the way (joint-space path)"),
            ) as usize;
        }
        let end_path = end_path_points(&self.problem, start, goal);
        placed += self.place(
            rng,
            &end_path,
            &[start, goal],
            8,
            boxed("in the way (end-effector path)"),
        ) as usize;
        placed
    }

    /// Writes the case: `start`, the target from `goal`'s forward kinematics
    /// (with its orientation when `orientation`), reads the file back as
    /// `capp run` would, and checks everything once more on what was read:
    /// the loader and `Planner::new` accept it, start and goal are clear.
    pub fn finish(
        mut self,
        family: &'static str,
        index: usize,
        tags: String,
        start: &[f64],
        goal: &[f64],
        orientation: bool,
    ) -> Option<Case> {
        let (position, rotation) = end_pose(&self.problem, goal);
        self.spec.start = start.to_vec();
        self.spec.target = position;
        self.spec.orientation = orientation.then_some(rotation);
        self.spec.comments.push(format!(
            "goal configuration (radians / {}; collision free, the target is its pose):",
            self.spec.unit.label()
        ));
        let goal_text: Vec<String> = goal.iter().map(|&g| case::num(g)).collect();
        self.spec
            .comments
            .push(format!("goal = [{}]", goal_text.join(", ")));
        let text = self.spec.to_toml();
        let problem = case::parse(&text, &self.spec.name).ok()?;
        problem.validate().ok()?;
        let geometry = Geometry::new(&problem);
        let start_read: Vec<f64> = problem.start.iter().map(|&x| x as f64).collect();
        let ok = |q: &[f64]| {
            within_limits(&problem, q) && geometry.is_clear(q, CLEAR_MARGIN) && self.links_apart(q)
        };
        if start_read != start || !ok(start) || !ok(goal) {
            return None;
        }
        Some(Case {
            family,
            index,
            name: self.spec.name.clone(),
            tags,
            text,
            start: start.to_vec(),
            goal: goal.to_vec(),
            obstacles: self.spec.obstacles.clone(),
        })
    }
}

/// Whether `q` is within the joint limits of `problem`.
pub fn within_limits(problem: &Problem, q: &[f64]) -> bool {
    q.len() == problem.joints.len()
        && problem
            .joints
            .iter()
            .zip(q)
            .all(|(j, &x)| x >= j.min as f64 && x <= j.max as f64)
}

/// Uniform within `fraction` of each range about its middle, as `f32` values.
pub fn random_config(rng: &mut Rng, limits: &[(f64, f64)], fraction: f64) -> Vec<f64> {
    limits
        .iter()
        .map(|&(lo, hi)| {
            let (mid, half) = (0.5 * (lo + hi), 0.5 * (hi - lo));
            round(mid + fraction * half * rng.range(-1.0, 1.0)).clamp(lo, hi)
        })
        .collect()
}

/// End-effector position and rotation (rows) at `q`, `f64` (the checker's kinematics).
pub fn end_pose(problem: &Problem, q: &[f64]) -> ([f64; 3], [[f64; 3]; 3]) {
    let (_, t) = forward(problem, q);
    (
        [t[0][3], t[1][3], t[2][3]],
        [0, 1, 2].map(|i| [t[i][0], t[i][1], t[i][2]]),
    )
}

/// Frame origins `o_1..o_n` and link mid-points at `q`, skipping the first
/// `skip` links (the pedestal or the base, which cannot get out of the way).
pub fn arm_points(problem: &Problem, q: &[f64], skip: usize) -> Vec<[f64; 3]> {
    let (o, _) = forward(problem, q);
    let mut points = Vec::new();
    for k in skip..o.len().saturating_sub(1) {
        let (a, b) = (o[k], o[k + 1]);
        points.push([
            0.5 * (a[0] + b[0]),
            0.5 * (a[1] + b[1]),
            0.5 * (a[2] + b[2]),
        ]);
        points.push(b);
    }
    points
}

/// The joint-space midpoint of `a` and `b`.
pub fn midpoint(a: &[f64], b: &[f64]) -> Vec<f64> {
    a.iter().zip(b).map(|(x, y)| 0.5 * (x + y)).collect()
}

/// Points on the straight end-effector path from `a`'s pose to `b`'s, in
/// its middle part (`t` in 0.3 to 0.7).
pub fn end_path_points(problem: &Problem, a: &[f64], b: &[f64]) -> Vec<[f64; 3]> {
    let (pa, pb) = (end_pose(problem, a).0, end_pose(problem, b).0);
    (0..5)
        .map(|i| {
            let t = 0.3 + 0.1 * i as f64;
            [0, 1, 2].map(|k| pa[k] + t * (pb[k] - pa[k]))
        })
        .collect()
}

/// Euclidean distance.
pub fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    libm::sqrt((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2))
}

/// The spec of a table-top arm case (metres): `robot` at `start`, the
/// target set later; tolerances 0.005 m and 0.05, margins 0.08 m at joints
/// and 0.06 m inside links, three points per link (arms about as thick as
/// the iiwa's); other settings default.
pub fn table_top_spec(name: &str, description: &str, robot: RobotSpec, start: Vec<f64>) -> Spec {
    Spec {
        name: name.into(),
        description: format!("{description} (generated by capp-suite)."),
        comments: vec![format!(
            "capp-suite case {name}: `capp run` this file to plan it."
        )],
        unit: Unit::Metres,
        robot,
        robot_settings: Vec::new(),
        start,
        target: [0.0; 3],
        orientation: None,
        obstacles: Vec::new(),
        settings: vec![
            ("position_tolerance".into(), num(0.005)),
            ("orientation_tolerance".into(), num(0.05)),
            ("joint_margin".into(), num(0.08)),
            ("link_margin".into(), num(0.06)),
            ("points_per_link".into(), "3".into()),
        ],
    }
}

/// Sizes of a shelf unit ([`shelf_unit`]), each a range to draw from, metres.
#[derive(Clone, Copy, Debug)]
pub struct ShelfSizes {
    /// Azimuth of the unit about the base, radians.
    pub azimuth: (f64, f64),
    /// Distance of its front from the base's axis.
    pub near: (f64, f64),
    /// Half its depth.
    pub half_depth: (f64, f64),
    /// Half its width.
    pub half_width: (f64, f64),
    /// Its height above the table top.
    pub height: (f64, f64),
    /// Most boards between the floor and the top (at least one).
    pub boards: usize,
    /// Each board is this much above or below its even spacing at most.
    pub board_jitter: f64,
}

/// A shelf unit standing on the table top `top`: two side panels, a top, one to `boards` boards, sometimes a
/// back panel, built facing the robot along `+x` and turned to a random
/// azimuth. Returns the panels and the number of boards.
pub fn shelf_unit(rng: &mut Rng, top: f64, sizes: &ShelfSizes) -> (Vec<Obstacle>, usize) {
    let azimuth = rng.range(sizes.azimuth.0, sizes.azimuth.1);
    let near = rng.range(sizes.near.0, sizes.near.1);
    let depth = rng.range(sizes.half_depth.0, sizes.half_depth.1);
    let width = rng.range(sizes.half_width.0, sizes.half_width.1);
    let height = rng.range(sizes.height.0, sizes.height.1);
    let x = near + depth;
    let t = 0.015;
    let mut shelf = vec![
        Obstacle::cuboid(
            "shelf side 1",
            [x, -width, top + 0.5 * height],
            [depth, t, 0.5 * height],
        ),
        Obstacle::cuboid(
            "shelf side 2",
            [x, width, top + 0.5 * height],
            [depth, t, 0.5 * height],
        ),
        Obstacle::cuboid("shelf top", [x, 0.0, top + height], [depth, width, t]),
    ];
    let boards = 1 + rng.below(sizes.boards.max(1));
    for k in 0..boards {
        let z = top
            + height * (k + 1) as f64 / (boards + 1) as f64
            + rng.range(-sizes.board_jitter, sizes.board_jitter);
        shelf.push(Obstacle::cuboid(
            format!("shelf board {}", k + 1),
            [x, 0.0, z],
            [depth, width, t],
        ));
    }
    if rng.chance(0.5) {
        shelf.push(Obstacle::cuboid(
            "shelf back",
            [x + depth, 0.0, top + 0.5 * height],
            [t, width, 0.5 * height],
        ));
    }
    (
        shelf.into_iter().map(|o| o.turned(azimuth)).collect(),
        boards,
    )
}

/// A box standing on the table top `top` at distance `reach` from the
/// base's axis and a random azimuth in `azimuth`, half sizes drawn from
/// `half_size` (its half height from `half_height`).
pub fn box_on_table(
    rng: &mut Rng,
    name: impl Into<String>,
    top: f64,
    reach: (f64, f64),
    azimuth: (f64, f64),
    half_size: (f64, f64),
    half_height: (f64, f64),
) -> Obstacle {
    let s = [
        rng.range(half_size.0, half_size.1),
        rng.range(half_size.0, half_size.1),
        rng.range(half_height.0, half_height.1),
    ];
    let r = rng.range(reach.0, reach.1);
    let spin = rng.range(-1.5, 1.5);
    let mut o = Obstacle::cuboid(name, [r, 0.0, top + s[2]], s);
    o.euler[2] = spin;
    o.turned(rng.range(azimuth.0, azimuth.1))
}
