//! `snake_fold.toml`, the shipped scenario where self-collision acts: a
//! 14-joint snake folded into a U reaches across its own outgoing links.
//! Measured here independently of the planner (frame origins from host-sim's
//! f64 kinematics, chords' distance segment to segment in f64, the checked
//! pairs from the scenario's pair table): with self-collision on, the plan
//! reaches and no two checked links' capsules touch, on any row or densely
//! between rows, and the independent checker accepts it; with it off, the
//! plan passes two links through each other.

use std::path::Path;

use capp_core::Outcome;
use capp_sim::output::rows_csv;
use capp_sim::plan::{self, RunResult};
use capp_sim::{check, geometry, trajectory, Problem};

type P3 = [f64; 3];

fn sub(a: P3, b: P3) -> P3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: P3, b: P3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn along(p: P3, d: P3, s: f64) -> P3 {
    [p[0] + s * d[0], p[1] + s * d[1], p[2] + s * d[2]]
}

/// Distance between the segments `p1 q1` and `p2 q2` (Ericson, Real-Time
/// Collision Detection 5.1.9).
fn segment_distance(p1: P3, q1: P3, p2: P3, q2: P3) -> f64 {
    let (d1, d2, r) = (sub(q1, p1), sub(q2, p2), sub(p1, p2));
    let (a, e, f) = (dot(d1, d1), dot(d2, d2), dot(d2, r));
    let (s, t) = if a <= 1e-18 && e <= 1e-18 {
        (0.0, 0.0)
    } else if a <= 1e-18 {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = dot(d1, r);
        if e <= 1e-18 {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = dot(d1, d2);
            let denom = a * e - b * b;
            let mut s = if denom > 1e-18 {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut t = (b * s + f) / e;
            if t < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            }
            (s, t)
        }
    };
    let w = sub(along(p1, d1, s), along(p2, d2, t));
    dot(w, w).sqrt()
}

/// The closest checked pair at `q`: (gap between the capsules, chords'
/// distance, the two links 1-based).
fn closest_pair(problem: &Problem, rows: &[u64], q: &[f64]) -> (f64, f64, [usize; 2]) {
    let (o, _) = geometry::forward(problem, q);
    let r = &problem.links.radius;
    let mut best = (f64::INFINITY, f64::INFINITY, [0, 0]);
    for (a, &row) in rows.iter().enumerate() {
        for b in (a + 1..rows.len()).filter(|b| row & (1u64 << b) != 0) {
            let distance = segment_distance(o[a], o[a + 1], o[b], o[b + 1]);
            let gap = distance - r[a] as f64 - r[b] as f64;
            if gap < best.0 {
                best = (gap, distance, [a + 1, b + 1]);
            }
        }
    }
    best
}

fn snake(self_collision: bool) -> (Problem, RunResult) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/snake_fold.toml");
    let mut problem = Problem::load(&path).unwrap_or_else(|e| panic!("{e}"));
    problem.links.enabled = self_collision;
    let scenario = problem.validate().unwrap();
    assert_eq!(scenario.capsules().is_on(), self_collision);
    let result = plan::run(&problem, &scenario, |_| {}).unwrap();
    (problem, result)
}

fn q64(q: &[f32]) -> Vec<f64> {
    q.iter().map(|&x| x as f64).collect()
}

#[test]
fn the_snake_keeps_its_links_apart_only_with_self_collision_on() {
    let (problem, on) = snake(true);
    // Every pair of links that are not adjacent is checked (no knuckles, no
    // contact at home): 91 pairs less the 13 adjacent ones.
    let table = problem.pair_table().unwrap();
    let rows = table.checked_rows().to_vec();
    let checked: u32 = rows.iter().map(|r| r.count_ones()).sum();
    assert_eq!(checked, 78);
    let radius = problem.links.radius[0] as f64;
    assert!(problem.links.radius.iter().all(|&r| r as f64 == radius));

    // On: reached in a short run, every row clear, and densely between rows
    // (16 joint-space substeps).
    assert_eq!(on.outcome, Outcome::Reached);
    assert!(on.steps() < 300, "{} steps", on.steps());
    let mut closest = (f64::INFINITY, 0, [0, 0]);
    for (i, pair) in on.rows.windows(2).enumerate() {
        let (q0, q1) = (q64(&pair[0].q), q64(&pair[1].q));
        for k in 0..16 {
            let s = k as f64 / 16.0;
            let q: Vec<f64> = q0.iter().zip(&q1).map(|(a, b)| a + s * (b - a)).collect();
            let (gap, _, links) = closest_pair(&problem, &rows, &q);
            if gap < closest.0 {
                closest = (gap, i, links);
            }
        }
    }
    let last = on.rows.last().unwrap();
    let (gap, _, links) = closest_pair(&problem, &rows, &q64(&last.q));
    if gap < closest.0 {
        closest = (gap, on.rows.len() - 1, links);
    }
    eprintln!(
        "self-collision on: {} steps, closest checked pair {:?} gap {:.5} m after row {}",
        on.steps(),
        closest.2,
        closest.0,
        closest.1
    );
    assert!(closest.0 > 0.0, "{closest:?}");
    // Self-avoidance acts: the closest pair comes within one radius.
    assert!(closest.0 < radius, "{closest:?}");
    // And the independent checker accepts the plan (limits, rates, the post).
    let text = rows_csv(problem.joints.len(), &on.rows).unwrap();
    let t = trajectory::parse(&text, Path::new("trajectory.csv")).unwrap();
    let report = check::check(&problem, &t);
    assert!(report.accepted() && report.reaches_target, "{report}");

    // Off: the same problem, planned as if links could pass through each
    // other, does just that: two checked links' chords meet on a row.
    let (problem_off, off) = snake(false);
    assert_eq!(off.outcome, Outcome::Reached);
    let (row, (gap, distance, links)) = off
        .rows
        .iter()
        .map(|r| closest_pair(&problem_off, &rows, &q64(&r.q)))
        .enumerate()
        .min_by(|a, b| a.1 .1.total_cmp(&b.1 .1))
        .unwrap();
    eprintln!(
        "self-collision off: {} steps, links {links:?} chords {distance:.2e} m apart (gap {gap:.5} m) at row {row}",
        off.steps()
    );
    assert!(distance < 1e-6, "links {links:?} {distance} m apart");
    assert!(gap <= -2.0 * radius + 1e-6);
    assert_ne!(off.steps(), on.steps());
}
