//! A long snake arm (metres) reaching folded targets: targets the arm can
//! reach only by curling back on itself, so that links far apart on the
//! chain come near each other and self-collision avoidance matters.
//!
//! The snake: 12, 16, 20 or 24 revolute joints (cases `4k`, `4k + 1`,
//! `4k + 2`, `4k + 3`), links of [`LINK`] (standard DH, `a = 0.1 m`,
//! `d = 0`), twists alternating `+90` and `-90` degrees, so the axes
//! alternate yaw and pitch and the arm curls in 3-D; straight along `+x` at
//! zero. Limits `+-90` degrees; rate limits from 40 degrees per second at the
//! base to 90 at the tip. Capsules of radius [`RADIUS`] (a 7 cm thick arm
//! of 10 cm links, as snake arms are built); obstacle margins 0.06 m at
//! joints, 0.05 m inside links.
//!
//! Pairs of links: neighbours share a joint (skipped by the chain); a link
//! and the next but one are allowed in the file (`[robot] allow`,
//! [`next_but_one`]) because they cannot touch: every bend is at most 90
//! degrees, so every point of link `k + 2` lies at least one link length
//! beyond every point of link `k` along link `k + 1`, and `LINK > 2 RADIUS`
//! (MoveIt's setup assistant would skip them as never in collision; here it
//! is proved, and `tests/subset.rs` samples it). Every other pair is checked
//! (`capp acm`). Checked, those pairs sit at a constant clearance `(LINK -
//! 2 RADIUS) / 2 RADIUS = 0.43`, inside the planner's influence, and their
//! room (half their gap against each link's whole travel) throttles every
//! step: the planner then reached 29 of seed 1's 60 cases instead of 59,
//! 22 of seed 2's instead of 60 (`examples/snake_links.rs` plans both, and
//! with self-collision off, where 9 and 10 of the 60 runs put two links into
//! each other).
//!
//! Scene: a floor 0.45 to 0.7 m below the base, a slim pedestal under it;
//! then a folded goal configuration (random within 80 % of each range,
//! clear of the scene, its checked pairs apart by [`LINK_MARGIN`] radius
//! sums and two links at least [`FOLD_APART`] apart on the chain within
//! [`FOLDED`] radius sums of each other) whose end effector is, by the
//! case's kind (`index % 3`):
//!
//! * `base`: within 0.25 arm lengths of the base;
//! * `behind`: behind the base (`x < -0.15` arm lengths), where the first
//!   joint's +-90 degrees cannot turn the arm;
//! * `ring`: within 0.45 arm lengths of the base, inside a ring of four to
//!   six posts standing on the floor and a little above the target, so the
//!   arm comes in from above and folds down into it.
//!
//! Then one or two boxes in the way of the joint-space midpoint's links and
//! one on the straight end-effector path, as the other families place them.
//! About half the cases start stretched along `+x`, the others from a random
//! clear configuration within 40 % of each range (its links apart too);
//! about half the targets are a pose (tolerances 0.005 m and 0.05), the
//! others a position (0.005 m).

use super::scene::{end_pose, random_config, Draft};
use super::Family;
use crate::case::{num, Case, DhJoint, Obstacle, RobotSpec, Spec, Unit};
use crate::rng::Rng;

/// The family.
pub const FAMILY: Family = Family {
    name: "snake_folds",
    description: "a 12- to 24-joint snake arm curling back to targets near its base, behind it, or inside a ring of posts; tolerances 0.005 m / 0.05",
    count: 60,
    generate,
};

const DEG: f64 = std::f64::consts::PI / 180.0;

/// Length of every link, metres.
pub const LINK: f64 = 0.1;
/// Capsule radius of every link, metres.
pub const RADIUS: f64 = 0.035;
/// Smallest `gap / (r_a + r_b)` of any checked link pair at a start or goal
/// (the planner's dimensionless link clearance): 5 mm between two links.
pub const LINK_MARGIN: f64 = 0.1;
/// A goal is folded when two links at least [`FOLD_APART`] apart on the
/// chain are within this many radius sums of each other.
pub const FOLDED: f64 = 2.0;
/// See [`FOLDED`]: links closer on the chain are near each other whenever
/// the joints between them bend (a link and the next but one are never
/// more than one link length apart).
pub const FOLD_APART: usize = 4;
/// Joint counts, by `index % 4`.
pub const JOINTS: [usize; 4] = [12, 16, 20, 24];

const NAMES: [&str; 24] = [
    "j1", "j2", "j3", "j4", "j5", "j6", "j7", "j8", "j9", "j10", "j11", "j12", "j13", "j14", "j15",
    "j16", "j17", "j18", "j19", "j20", "j21", "j22", "j23", "j24",
];

/// The snake's DH table, `n` joints (at most 24).
pub fn joints(n: usize) -> Vec<DhJoint> {
    let n = n.min(NAMES.len());
    (0..n)
        .map(|i| {
            let along = i as f64 / (n - 1).max(1) as f64;
            DhJoint {
                name: NAMES[i],
                alpha: if i % 2 == 0 { 90.0 } else { -90.0 } * DEG,
                a: LINK,
                d: 0.0,
                theta: 0.0,
                min: -90.0 * DEG,
                max: 90.0 * DEG,
                max_rate: (40.0 + 50.0 * along) * DEG,
            }
        })
        .collect()
}

/// `[[robot.allow]]` of every link and the next but one, inline: `[{ links
/// = [1, 3] }, ...]` (DH link numbers). They never touch: with every bend
/// at most 90 degrees, link `k + 1` lies between them and every point of
/// link `k + 2` is at least one link length from every point of link `k`
/// along it, and `LINK > 2 RADIUS` (the module header says why they are
/// not left checked).
pub fn next_but_one(n: usize) -> String {
    let pairs: Vec<String> = (1..=n.saturating_sub(2))
        .map(|k| format!("{{ links = [{k}, {}] }}", k + 2))
        .collect();
    format!("[{}]", pairs.join(", "))
}

/// Where the goal is, by `index % 3`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Base,
    Behind,
    Ring,
}

impl Kind {
    fn name(self) -> &'static str {
        match self {
            Kind::Base => "base",
            Kind::Behind => "behind",
            Kind::Ring => "ring",
        }
    }

    /// Whether an end-effector position `p` is a target of this kind for an
    /// arm of `length`.
    fn wants(self, p: [f64; 3], length: f64) -> bool {
        let r = libm::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        match self {
            Kind::Base => r <= 0.25 * length,
            Kind::Behind => p[0] <= -0.15 * length,
            Kind::Ring => r <= 0.45 * length,
        }
    }
}

fn generate(rng: &mut Rng, index: usize) -> Option<Case> {
    let n = JOINTS[index % JOINTS.len()];
    let kind = [Kind::Base, Kind::Behind, Kind::Ring][index % 3];
    let length = n as f64 * LINK;
    let pose = rng.chance(0.5);
    let stretched = rng.chance(0.5);
    let name = format!("{}-{index:03}", FAMILY.name);
    let mut settings = vec![("position_tolerance".into(), num(0.005))];
    if pose {
        settings.push(("orientation_tolerance".into(), num(0.05)));
    }
    settings.extend([
        ("joint_margin".into(), num(0.06)),
        ("link_margin".into(), num(0.05)),
    ]);
    let mut draft = Draft::new(Spec {
        name: name.clone(),
        description: format!(
            "A {n}-joint snake arm curling back to a folded target (generated by capp-suite)."
        ),
        comments: vec![format!(
            "capp-suite case {name}: `capp run` this file to plan it."
        )],
        unit: Unit::Metres,
        robot: RobotSpec::Table(joints(n)),
        robot_settings: vec![
            ("link_radius".into(), num(RADIUS)),
            ("allow".into(), next_but_one(n)),
        ],
        start: vec![0.0; n],
        target: [0.0; 3],
        orientation: None,
        obstacles: Vec::new(),
        settings,
    })?;
    draft.keep_links_apart(LINK_MARGIN)?;

    let floor = -rng.range(0.45, 0.7);
    draft.push(Obstacle::cuboid(
        "floor",
        [0.0, 0.0, floor - 0.05],
        [3.0, 3.0, 0.05],
    ));
    let top = -0.1;
    draft.push(Obstacle::cylinder(
        "pedestal",
        [0.0, 0.0, 0.5 * (floor + top)],
        2,
        0.06,
        0.5 * (top - floor),
    ));

    let home = vec![0.0; n];
    let stretched = stretched && draft.clear(&home);
    let start = if stretched {
        home
    } else {
        draft.random_clear(rng, 0.4, 400)?
    };
    let p0 = end_pose(draft.problem(), &start).0;
    let limits = draft.limits();
    let goal = (0..3000)
        .map(|_| random_config(rng, &limits, 0.8))
        .find(|q| {
            let p = end_pose(draft.problem(), q).0;
            kind.wants(p, length)
                && super::scene::dist(p, p0) >= 0.3
                && draft.clear(q)
                && draft
                    .link_gap(q, FOLD_APART)
                    .is_some_and(|g| g.clearance <= FOLDED)
        })?;

    let mut rings = 0;
    if kind == Kind::Ring {
        let p = end_pose(draft.problem(), &goal).0;
        let radius = rng.range(0.12, 0.2);
        let posts = 4 + rng.below(3);
        let turn = rng.range(0.0, std::f64::consts::TAU);
        let high = p[2] + rng.range(0.0, 0.15);
        for k in 0..posts {
            let angle =
                turn + std::f64::consts::TAU * (k as f64 + rng.range(-0.15, 0.15)) / posts as f64;
            let (s, c) = libm::sincos(angle);
            let post = Obstacle::cylinder(
                format!("ring post {}", k + 1),
                [p[0] + radius * c, p[1] + radius * s, 0.5 * (floor + high)],
                2,
                rng.range(0.015, 0.03),
                0.5 * (high - floor),
            );
            rings += draft.push_if_clear(post, &[&start, &goal]) as usize;
        }
        if rings < 3 {
            return None;
        }
    }
    let placed = draft.boxes_in_the_way(rng, &start, &goal, 2, (0.03, 0.07));
    let gap = draft.link_gap(&goal, FOLD_APART)?;
    let tags = format!(
        "{n} joints; {}; start {}; {}; goal folds links {} and {} to {:.3} m; {} obstacles ({placed} in the way{})",
        kind.name(),
        if stretched { "stretched" } else { "random" },
        if pose { "pose" } else { "position" },
        gap.links.0 + 1,
        gap.links.1 + 1,
        gap.gap,
        draft.spec.obstacles.len(),
        if rings > 0 {
            format!(", {rings} ring posts")
        } else {
            String::new()
        },
    );
    draft.finish(FAMILY.name, index, tags, &start, &goal, pose)
}
