//! How close the links of each `snake_folds` case come when planned as
//! generated (self-collision on, a link and the next but one allowed to
//! touch, which they never can), with every pair checked (no `allow`), and
//! with self-collision off (`[robot] self_collision = false`): the closest
//! pair the generated file checks over every row, by the suite's own `f64`
//! capsules (`capp_sim::geometry::Geometry`). A negative gap is a self-collision.
//!
//!     cargo run --release -p capp-suite --example snake_links -- [SEED] [CASES]

use capp_core::Outcome;
use capp_sim::geometry::Geometry;
use capp_suite::families::{self, snake_folds};
use capp_suite::runner::plan_text;

struct Run {
    outcome: String,
    reached: bool,
    steps: u32,
    gap: Option<f64>,
    links: (usize, usize),
}

fn closest(text: &str, name: &str, pairs_of: &str) -> Run {
    match plan_text(text, name) {
        Err(e) => Run {
            outcome: format!("refused: {e}"),
            reached: false,
            steps: 0,
            gap: None,
            links: (0, 0),
        },
        Ok((_, result)) => {
            // Always measured over the pairs the default file checks.
            let reference = capp_suite::case::parse(pairs_of, name).unwrap();
            let geometry = Geometry::new(&reference);
            let worst = result
                .rows
                .iter()
                .filter_map(|r| {
                    let q: Vec<f64> = r.q.iter().map(|&x| x as f64).collect();
                    geometry.closest_link_pair(&q)
                })
                .min_by(|a, b| a.gap.total_cmp(&b.gap));
            Run {
                outcome: format!("{:?}", result.outcome),
                reached: result.outcome == Outcome::Reached,
                steps: result.steps(),
                gap: worst.map(|g| g.gap),
                links: worst.map_or((0, 0), |g| (g.links.0 + 1, g.links.1 + 1)),
            }
        }
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let seed: u64 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(1);
    let count: usize = args
        .get(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(snake_folds::FAMILY.count);
    let names = ["as generated", "every pair checked", "off"];
    let mut all: Vec<Vec<Run>> = vec![Vec::new(), Vec::new(), Vec::new()];
    for c in families::cases(&snake_folds::FAMILY, seed, count).unwrap() {
        let allow = format!("allow = {}\n", snake_folds::next_but_one(c.start.len()));
        assert!(c.text.contains(&allow));
        let texts = [
            c.text.clone(),
            c.text.replace(&allow, ""),
            c.text
                .replace("[robot]\n", "[robot]\nself_collision = false\n"),
        ];
        let f = |g: Option<f64>| g.map_or("-".into(), |g| format!("{g:+.4}"));
        let mut line = format!("{:<16}", c.name);
        for (i, text) in texts.iter().enumerate() {
            let r = closest(text, &c.name, &c.text);
            line += &format!(
                " | {}: {:<8} {:>5} st {} ({}-{})",
                names[i],
                r.outcome,
                r.steps,
                f(r.gap),
                r.links.0,
                r.links.1
            );
            all[i].push(r);
        }
        println!("{line} [{}]", c.tags);
    }
    for (i, runs) in all.iter().enumerate() {
        let mut steps: Vec<u32> = runs.iter().filter(|r| r.reached).map(|r| r.steps).collect();
        steps.sort_unstable();
        println!(
            "{:<20} reached {:>3} of {}, steps median {}, runs with two links in each other: {}",
            names[i],
            steps.len(),
            runs.len(),
            steps.get(steps.len() / 2).copied().unwrap_or(0),
            runs.iter()
                .filter(|r| r.gap.is_some_and(|g| g < 0.0))
                .count()
        );
    }
}
