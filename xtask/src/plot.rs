//! The scaling plot: per-step cost against joints, one line per obstacle
//! count; left the M4F instruction counts, right the host medians. Drawn with
//! the simulator's labelled charts (the SVG and the PNG carry the same text,
//! in the font the simulator ships).

use capp_sim::render::chart::{Axes, Marker, Scale, PALETTE};
use capp_sim::render::{Canvas, Shape};

use crate::m4f::Counts;
use crate::report::{Host, SCALING_JOINTS, SCALING_OBSTACLES};

/// One panel: `series[i]` = points `(joints, value)` for obstacle count
/// `SCALING_OBSTACLES[i]`.
fn panel(
    canvas: &mut Canvas,
    rect: (f64, f64, f64, f64),
    title: &str,
    y_label: &str,
    series: &[Vec<(f64, f64)>],
) {
    let max_y = series.iter().flatten().map(|p| p.1).fold(0.0, f64::max);
    let mut axes = Axes::new(
        rect,
        Scale {
            lo: 4.0,
            hi: 34.0,
            log: false,
        },
        Scale::linear(0.0, max_y.max(1.0)),
    );
    axes.x_ticks = SCALING_JOINTS
        .iter()
        .map(|&n| (n as f64, n.to_string()))
        .collect();
    axes.draw(canvas, title, "joints", y_label);
    let mut items = Vec::new();
    for (i, points) in series.iter().enumerate() {
        let color = PALETTE[i % PALETTE.len()];
        let pts: Vec<(f64, f64)> = points.iter().filter_map(|&(n, v)| axes.map(n, v)).collect();
        for p in &pts {
            canvas.push(Shape::Disc {
                centre: *p,
                radius: 3.0,
                color,
            });
        }
        canvas.push(Shape::line(pts, color, 2.0));
        let m = SCALING_OBSTACLES.get(i).copied().unwrap_or(0);
        items.push((format!("{m} obstacles"), color, Marker::Line));
    }
    axes.legend_in(canvas, &items, true);
}

/// The two panels.
pub fn scaling(host: &Host, counts: &Counts) -> Canvas {
    let series = |value: &dyn Fn(usize, usize) -> Option<f64>| -> Vec<Vec<(f64, f64)>> {
        SCALING_OBSTACLES
            .iter()
            .map(|&m| {
                SCALING_JOINTS
                    .iter()
                    .filter_map(|&n| Some((n as f64, value(n, m)?)))
                    .collect()
            })
            .collect()
    };
    let m4f = series(&|n, m| Some(counts.get("chain", n, m, "step")? / 1000.0));
    let host_us = series(&|n, m| Some(host.scaling(n, m)? / 1000.0));
    let mut canvas = Canvas::new(1000, 440);
    canvas.push(Shape::text(
        (80.0, 24.0),
        16.0,
        "One planner step against chain length and obstacle count",
    ));
    panel(
        &mut canvas,
        (80.0, 86.0, 470.0, 376.0),
        "Cortex-M4F (QEMU instruction count)",
        "thousand instructions per step",
        &m4f,
    );
    panel(
        &mut canvas,
        (580.0, 86.0, 970.0, 376.0),
        "host (criterion median)",
        "microseconds per step",
        &host_us,
    );
    canvas
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scaling_plot_is_labelled() {
        let mut m4f = String::new();
        let mut host = String::new();
        for n in SCALING_JOINTS {
            for m in SCALING_OBSTACLES {
                m4f.push_str(&format!(
                    "M4F chain {n} {m} step {}\n",
                    2000 + 700 * n + 40 * n * m
                ));
                host.push_str(&format!("HOST {n} {m} {}\n", 300 + 50 * n + 9 * n * m));
            }
        }
        m4f.push_str("step_count: done\n");
        let counts = Counts::parse(&m4f).unwrap();
        let mut h = Host::default();
        h.add_scaling(&host).unwrap();
        let svg = scaling(&h, &counts).svg();
        for label in ["joints", "64 obstacles", "microseconds per step", "32"] {
            assert!(svg.contains(&format!(">{label}</text>")), "{label}");
        }
        assert_eq!(svg.matches("<circle").count(), 2 * 25);
    }
}
