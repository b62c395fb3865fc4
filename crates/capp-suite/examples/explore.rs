use capp_suite::{families, oracle::Budget, runner, variants::variants};
use std::time::Instant;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(4);
    let fam_filter = args.get(2).cloned();
    for f in families::families() {
        if fam_filter.as_ref().is_some_and(|x| x != f.name) {
            continue;
        }
        let t = Instant::now();
        let cases = families::cases(&f, 1, n).unwrap();
        eprintln!(
            "{}: {} cases generated in {:?}",
            f.name,
            cases.len(),
            t.elapsed()
        );
        std::fs::create_dir_all("/tmp/cases").unwrap();
        for c in &cases {
            std::fs::write(format!("/tmp/cases/{}.toml", c.name), &c.text).unwrap();
            let t = Instant::now();
            let r = runner::run_case(
                c,
                &variants(),
                1,
                Some(Budget {
                    iterations: std::env::var("ITER")
                        .ok()
                        .and_then(|s| s.parse().ok())
                        .unwrap_or(3000),
                    nodes: 200_000,
                    shortcuts: 200,
                }),
            );
            let o = r.oracle.as_ref().unwrap();
            let runs: Vec<String> = r
                .runs
                .iter()
                .map(|v| match &v.metrics {
                    Ok(m) => format!(
                        "{}:{:?} {} st {:.1}s col{} dense{} {:.0}ms",
                        v.variant.name,
                        m.outcome,
                        m.steps,
                        m.motion_time,
                        m.collisions,
                        m.dense_checks,
                        m.wall_ms
                    ),
                    Err(e) => format!("{}: ERR {e}", v.variant.name),
                })
                .collect();
            eprintln!(
                "  {} [{}] rrt {} it{} n{} {:.0}ms t{:?}->{:?} | {} | total {:?}",
                c.name,
                c.tags,
                o.solved,
                o.iterations,
                o.nodes,
                o.wall_ms,
                o.raw_time,
                o.path_time,
                runs.join(" | "),
                t.elapsed()
            );
        }
    }
}
