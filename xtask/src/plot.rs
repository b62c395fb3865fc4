//! The scaling plot: per-step cost against joints, one line per obstacle
//! count; left the M4F instruction counts, right the host medians. Drawn with
//! the simulator's canvas (SVG with titles; PNG with the numbers drawn as
//! seven-segment digits, since its rasteriser has no fonts).

use capp_sim::render::{Canvas, Shape};

use crate::m4f::Counts;
use crate::report::{Host, SCALING_JOINTS, SCALING_OBSTACLES};

const COLORS: [[u8; 3]; 5] = [
    [0x1f, 0x77, 0xb4],
    [0xff, 0x7f, 0x0e],
    [0x2c, 0xa0, 0x2c],
    [0xd6, 0x27, 0x28],
    [0x94, 0x67, 0xbd],
];
const BLACK: [u8; 3] = [0, 0, 0];
const GREY: [u8; 3] = [0xcc, 0xcc, 0xcc];

/// Segments a-g of each digit, as bits 0-6.
const DIGITS: [u8; 10] = [
    0b011_1111, 0b000_0110, 0b101_1011, 0b100_1111, 0b110_0110, 0b110_1101, 0b111_1101, 0b000_0111,
    0b111_1111, 0b110_1111,
];

fn line(shapes: &mut Vec<Shape>, points: Vec<(f64, f64)>, color: [u8; 3], width: f64) {
    shapes.push(Shape::Line {
        points,
        color,
        width,
        clip: None,
    });
}

/// `text` (digits only) in seven segments, height `h`, left end at `(x, y)` (baseline).
fn digits(shapes: &mut Vec<Shape>, x: f64, y: f64, h: f64, text: &str) {
    let w = h * 0.5;
    let mut left = x;
    for ch in text.chars() {
        if let Some(d) = ch.to_digit(10) {
            let bits = DIGITS[d as usize];
            let (top, mid, bottom) = (y - h, y - h / 2.0, y);
            let segs = [
                ((left, top), (left + w, top)),
                ((left + w, top), (left + w, mid)),
                ((left + w, mid), (left + w, bottom)),
                ((left, bottom), (left + w, bottom)),
                ((left, mid), (left, bottom)),
                ((left, top), (left, mid)),
                ((left, mid), (left + w, mid)),
            ];
            for (i, (a, b)) in segs.iter().enumerate() {
                if bits & (1 << i) != 0 {
                    line(shapes, vec![*a, *b], BLACK, 1.2);
                }
            }
        }
        left += w + h * 0.3;
    }
}

/// A "nice" upper bound and tick step for `max`.
fn axis(max: f64) -> (f64, f64) {
    let raw = (max / 5.0).max(1e-9);
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|k| k * mag)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * mag);
    ((max / step).ceil() * step, step)
}

/// One panel: `series[i]` = points `(joints, value)` for obstacle count `i`.
fn panel(
    shapes: &mut Vec<Shape>,
    origin: (f64, f64),
    size: (f64, f64),
    title: &str,
    series: &[Vec<(f64, f64)>],
) {
    let (x0, y0) = origin;
    let (w, h) = size;
    let max_y = series.iter().flatten().map(|p| p.1).fold(0.0, f64::max);
    let (top, step) = axis(max_y);
    let (n_min, n_max) = (0.0, 32.0);
    let px = |n: f64| x0 + (n - n_min) / (n_max - n_min) * w;
    let py = |v: f64| y0 + h - v / top * h;
    // Grid, axes, ticks.
    let mut v = 0.0;
    while v <= top + step * 0.5 {
        line(shapes, vec![(px(0.0), py(v)), (px(32.0), py(v))], GREY, 0.6);
        digits(
            shapes,
            x0 - 10.0 - 8.0 * format!("{v:.0}").len() as f64,
            py(v) + 5.0,
            10.0,
            &format!("{v:.0}"),
        );
        v += step;
    }
    for n in SCALING_JOINTS {
        line(
            shapes,
            vec![(px(n as f64), y0 + h), (px(n as f64), y0 + h + 5.0)],
            BLACK,
            1.0,
        );
        digits(
            shapes,
            px(n as f64) - 6.0,
            y0 + h + 20.0,
            10.0,
            &n.to_string(),
        );
    }
    line(
        shapes,
        vec![(x0, y0), (x0, y0 + h), (x0 + w, y0 + h)],
        BLACK,
        1.2,
    );
    for (i, points) in series.iter().enumerate() {
        let color = COLORS[i % COLORS.len()];
        let pts: Vec<(f64, f64)> = points.iter().map(|&(n, v)| (px(n), py(v))).collect();
        for p in &pts {
            shapes.push(Shape::Disc {
                centre: *p,
                radius: 3.0,
                color,
            });
        }
        line(shapes, pts, color, 2.0);
    }
    shapes.push(Shape::Text {
        at: (x0, y0 - 12.0),
        size: 14.0,
        text: title.into(),
    });
    shapes.push(Shape::Text {
        at: (x0 + w / 2.0 - 20.0, y0 + h + 38.0),
        size: 12.0,
        text: "joints".into(),
    });
}

/// The two panels and the legend (obstacle counts).
pub fn scaling(host: &Host, counts: &Counts) -> Canvas {
    let mut shapes = Vec::new();
    let m4f: Vec<Vec<(f64, f64)>> = SCALING_OBSTACLES
        .iter()
        .map(|&m| {
            SCALING_JOINTS
                .iter()
                .filter_map(|&n| Some((n as f64, counts.get("chain", n, m, "step")? / 1000.0)))
                .collect()
        })
        .collect();
    let host_us: Vec<Vec<(f64, f64)>> = SCALING_OBSTACLES
        .iter()
        .map(|&m| {
            SCALING_JOINTS
                .iter()
                .filter_map(|&n| Some((n as f64, host.scaling(n, m)? / 1000.0)))
                .collect()
        })
        .collect();
    panel(
        &mut shapes,
        (80.0, 50.0),
        (360.0, 300.0),
        "Cortex-M4F: thousand instructions per step",
        &m4f,
    );
    panel(
        &mut shapes,
        (560.0, 50.0),
        (360.0, 300.0),
        "host: microseconds per step (median)",
        &host_us,
    );
    // Legend: one coloured line and the obstacle count.
    for (i, m) in SCALING_OBSTACLES.iter().enumerate() {
        let x = 960.0;
        let y = 70.0 + 28.0 * i as f64;
        line(
            &mut shapes,
            vec![(x, y), (x + 24.0, y)],
            COLORS[i % COLORS.len()],
            3.0,
        );
        digits(&mut shapes, x + 32.0, y + 6.0, 12.0, &m.to_string());
    }
    shapes.push(Shape::Text {
        at: (960.0, 50.0),
        size: 12.0,
        text: "obstacles".into(),
    });
    Canvas {
        width: 1040,
        height: 420,
        shapes,
    }
}
