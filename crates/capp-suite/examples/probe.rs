use capp_sim::check::Geometry;
use capp_suite::{metrics, runner};
fn main() {
    let path = std::env::args().nth(1).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    let (problem, result) = runner::plan_text(&text, "probe").unwrap();
    let g = Geometry::new(&problem);
    let rows: Vec<Vec<f64>> = result
        .rows
        .iter()
        .map(|r| r.q.iter().map(|&x| x as f64).collect())
        .collect();
    for (k, w) in rows.windows(2).enumerate() {
        let mut worst = f64::INFINITY;
        let mut wc = None;
        metrics::between(&w[0], &w[1], |q| {
            let c = g.clearance(q).unwrap();
            if c.value < worst {
                worst = c.value;
                wc = Some(c);
            }
            true
        });
        if worst <= 0.0 {
            let a = g.clearance(&w[0]).unwrap();
            let b = g.clearance(&w[1]).unwrap();
            let dq: f64 = w[0]
                .iter()
                .zip(&w[1])
                .map(|(x, y)| (y - x).abs())
                .fold(0.0, f64::max);
            println!("step {}->{}: rows C-1 {:.5} {:.5} (pt {} obs {}), between min {:.5} {:?} maxdq {:.4} h {}", k, k+1, a.value, b.value, b.point, b.obstacle, worst, wc, dq, result.rows[k+1].h);
        }
    }
    println!("{:?} {}", result.outcome, result.steps());
}
