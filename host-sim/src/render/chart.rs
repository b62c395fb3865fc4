//! Labelled charts: axes with ticks, units and legends, and two ready-made
//! figures for reports ([`bar_chart`], [`scatter_chart`]).
//!
//! ```no_run
//! use capp_sim::render::chart::{bar_chart, BarChart, Series};
//! let figure = bar_chart(&BarChart {
//!     title: "Reach rate by family".into(),
//!     y_label: "reached [%]".into(),
//!     categories: vec!["planar".into(), "pips".into()],
//!     series: vec![Series { name: "gradient law".into(), values: vec![97.0, 92.5] }],
//!     y_max: Some(100.0),
//! });
//! figure.write(std::path::Path::new("out"), "reach_rate")?; // reach_rate.svg + .png
//! # Ok::<(), anyhow::Error>(())
//! ```

use super::canvas::{Anchor, Canvas, Clip, Rgb, Shape, P2};
use super::font;

/// Colours for series, in order (colour-blind-safe, Okabe and Ito).
pub const PALETTE: [Rgb; 7] = [
    [0, 114, 178],
    [213, 94, 0],
    [0, 158, 115],
    [204, 121, 167],
    [230, 159, 0],
    [86, 180, 233],
    [120, 120, 120],
];

const GRID: Rgb = [232, 232, 232];
const INK: Rgb = [30, 30, 30];
const MUTED: Rgb = [90, 90, 90];
const LIGHT: Rgb = [160, 160, 160];

/// One axis: the data range drawn and whether it is logarithmic.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scale {
    /// Low end (data units; for a log scale, > 0).
    pub lo: f64,
    /// High end.
    pub hi: f64,
    /// log10 scale.
    pub log: bool,
}

/// 1, 2 or 5 times a power of ten, about `span / count`.
pub fn nice_step(span: f64, count: f64) -> f64 {
    let raw = (span / count.max(1.0)).abs().max(1e-300);
    let p = 10f64.powf(raw.log10().floor());
    let m = raw / p;
    p * if m < 1.5 {
        1.0
    } else if m < 3.5 {
        2.0
    } else if m < 7.5 {
        5.0
    } else {
        10.0
    }
}

/// `n` in Unicode superscript digits (`-3` -> `⁻³`).
pub fn superscript(n: i64) -> String {
    const DIGITS: [char; 10] = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
    let mut s = String::new();
    if n < 0 {
        s.push('⁻');
    }
    for c in n.unsigned_abs().to_string().chars() {
        s.push(DIGITS[c.to_digit(10).unwrap_or(0) as usize]);
    }
    s
}

/// A tick label for `v` on a grid of `step`: as many decimals as the step needs.
pub fn tick_label(v: f64, step: f64) -> String {
    let decimals = if step >= 1.0 {
        0
    } else {
        (-step.log10() - 1e-9).ceil() as usize
    };
    let s = format!("{v:.decimals$}");
    // Never "-0".
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        s.trim_start_matches('-').to_string()
    } else {
        s.replace('-', "−")
    }
}

impl Scale {
    /// A linear scale over `[lo, hi]`, widened to whole ticks.
    pub fn linear(lo: f64, hi: f64) -> Scale {
        let (lo, hi) = if hi > lo {
            (lo, hi)
        } else {
            (lo - 0.5, lo + 0.5)
        };
        let step = nice_step(hi - lo, 5.0);
        Scale {
            lo: (lo / step).floor() * step,
            hi: (hi / step).ceil() * step,
            log: false,
        }
    }

    /// A log10 scale over whole decades covering `[lo, hi]` (both > 0).
    pub fn log(lo: f64, hi: f64) -> Scale {
        let (a, b) = (
            lo.max(1e-300).log10().floor(),
            hi.max(1e-300).log10().ceil(),
        );
        Scale {
            lo: 10f64.powf(a),
            hi: 10f64.powf(b.max(a + 1.0)),
            log: true,
        }
    }

    /// A log scale over the positive finite values, or `[0.1, 1]` when none.
    pub fn log_of(values: impl IntoIterator<Item = f64>) -> Scale {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for v in values.into_iter().filter(|v| *v > 0.0 && v.is_finite()) {
            lo = lo.min(v);
            hi = hi.max(v);
        }
        if lo.is_finite() {
            Scale::log(lo, hi)
        } else {
            Scale::log(0.1, 1.0)
        }
    }

    /// Where `v` falls, 0 at `lo` and 1 at `hi`; `None` if it cannot be drawn.
    pub fn frac(&self, v: f64) -> Option<f64> {
        if !v.is_finite() {
            return None;
        }
        if self.log {
            (v > 0.0).then(|| (v.log10() - self.lo.log10()) / (self.hi.log10() - self.lo.log10()))
        } else {
            Some((v - self.lo) / (self.hi - self.lo))
        }
    }

    /// Tick values and labels: decades (`10⁻³`; 1, 2, 5 in each over two
    /// decades or fewer) or 1-2-5 steps.
    pub fn ticks(&self) -> Vec<(f64, String)> {
        if self.log {
            let (a, b) = (
                self.lo.log10().round() as i64,
                self.hi.log10().round() as i64,
            );
            if b - a <= 2 {
                // Few decades: 1, 2, 5 in each, written out.
                return (a..=b)
                    .flat_map(|d| [1.0, 2.0, 5.0].map(|m| (m, d)))
                    .map(|(m, d)| (m * 10f64.powi(d as i32), 10f64.powi(d as i32)))
                    .filter(|(v, _)| *v <= self.hi * (1.0 + 1e-9))
                    .map(|(v, unit)| (v, tick_label(v, unit)))
                    .collect();
            }
            let every = ((b - a) / 8 + 1).max(1);
            (a..=b)
                .filter(|d| (d - a) % every == 0)
                .map(|d| (10f64.powf(d as f64), format!("10{}", superscript(d))))
                .collect()
        } else {
            let step = nice_step(self.hi - self.lo, 5.0);
            let first = (self.lo / step).ceil() as i64;
            let last = (self.hi / step + 1e-9).floor() as i64;
            (first..=last)
                .map(|k| (k as f64 * step, tick_label(k as f64 * step, step)))
                .collect()
        }
    }
}

/// How a legend entry is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Marker {
    /// A short line.
    Line,
    /// A short dashed line.
    Dashed,
    /// A dot.
    Dot,
    /// A filled square.
    Bar,
    /// A filled diamond with a dark outline (a place marked on a path).
    Diamond,
}

/// A plotting box in pixels with its two scales and tick labels.
#[derive(Clone, Debug)]
pub struct Axes {
    /// Left, top, right, bottom of the plotting box, pixels.
    pub rect: Clip,
    /// Horizontal scale.
    pub x: Scale,
    /// Vertical scale.
    pub y: Scale,
    /// Horizontal ticks (default: [`Scale::ticks`]).
    pub x_ticks: Vec<(f64, String)>,
    /// Vertical ticks (default: [`Scale::ticks`]).
    pub y_ticks: Vec<(f64, String)>,
}

impl Axes {
    /// Axes over `rect` with the scales' own ticks.
    pub fn new(rect: Clip, x: Scale, y: Scale) -> Axes {
        Axes {
            rect,
            x,
            y,
            x_ticks: x.ticks(),
            y_ticks: y.ticks(),
        }
    }

    /// Pixel position of a data point (`None` off a log scale's domain).
    pub fn map(&self, x: f64, y: f64) -> Option<P2> {
        let (x0, y0, x1, y1) = self.rect;
        Some((
            x0 + self.x.frac(x)? * (x1 - x0),
            y1 - self.y.frac(y)? * (y1 - y0),
        ))
    }

    /// Grid, frame, ticks, tick labels; the title above, the vertical axis's
    /// label (with its unit) above the axis, the horizontal one below.
    pub fn draw(&self, canvas: &mut Canvas, title: &str, x_label: &str, y_label: &str) {
        let (x0, y0, x1, y1) = self.rect;
        for (v, label) in &self.y_ticks {
            let Some((_, y)) = self.map(self.x.lo, *v) else {
                continue;
            };
            canvas.push(Shape::line(vec![(x0, y), (x1, y)], GRID, 1.0));
            canvas.push(Shape::line(vec![(x0 - 5.0, y), (x0, y)], INK, 1.0));
            canvas.push(
                Shape::text((x0 - 8.0, y + 4.0), 11.0, label.clone())
                    .anchored(Anchor::End)
                    .colored(INK),
            );
        }
        for (v, label) in &self.x_ticks {
            let Some((x, _)) = self.map(*v, self.y.lo.max(f64::MIN_POSITIVE)) else {
                continue;
            };
            canvas.push(Shape::line(vec![(x, y0), (x, y1)], GRID, 1.0));
            canvas.push(Shape::line(vec![(x, y1), (x, y1 + 5.0)], INK, 1.0));
            canvas.push(
                Shape::text((x, y1 + 17.0), 11.0, label.clone())
                    .anchored(Anchor::Middle)
                    .colored(INK),
            );
        }
        canvas.push(Shape::line(
            vec![(x0, y0), (x0, y1), (x1, y1), (x1, y0), (x0, y0)],
            [110, 110, 110],
            1.0,
        ));
        canvas.push(Shape::text((x0, y0 - 24.0), 13.5, title).colored(INK));
        canvas.push(Shape::text((x0, y0 - 7.0), 11.0, y_label).colored(MUTED));
        canvas.push(
            Shape::text(((x0 + x1) / 2.0, y1 + 33.0), 11.5, x_label)
                .anchored(Anchor::Middle)
                .colored(MUTED),
        );
    }

    /// A legend box in the top right corner of the plotting box.
    pub fn legend(&self, canvas: &mut Canvas, items: &[(String, Rgb, Marker)]) {
        self.legend_in(canvas, items, false);
    }

    /// A legend box in the top left (`left`) or top right corner.
    pub fn legend_in(&self, canvas: &mut Canvas, items: &[(String, Rgb, Marker)], left: bool) {
        if items.is_empty() {
            return;
        }
        let (x0, y0, x1, _) = self.rect;
        let size = 11.0;
        let w = items
            .iter()
            .map(|(n, ..)| font::width(n, size))
            .fold(0.0, f64::max)
            + 40.0;
        let h = 8.0 + 16.0 * items.len() as f64;
        let (bx, by) = (if left { x0 + 8.0 } else { x1 - w - 8.0 }, y0 + 8.0);
        let rect = vec![(bx, by), (bx + w, by), (bx + w, by + h), (bx, by + h)];
        canvas.push(Shape::Polygon {
            points: rect.clone(),
            fill: [255, 255, 255],
            opacity: 0.9,
            clip: None,
        });
        let mut outline = rect;
        outline.push((bx, by));
        canvas.push(Shape::line(outline, [190, 190, 190], 1.0));
        for (k, (name, color, marker)) in items.iter().enumerate() {
            let y = by + 12.0 + 16.0 * k as f64;
            legend_marker(canvas, (bx + 8.0, y), *color, *marker);
            canvas.push(Shape::text((bx + 32.0, y + 4.0), size, name.clone()).colored(INK));
        }
    }
}

/// A legend symbol 18 px wide starting at `at` (its vertical centre).
pub fn legend_marker(canvas: &mut Canvas, at: P2, color: Rgb, marker: Marker) {
    let (x, y) = at;
    match marker {
        Marker::Line => canvas.push(Shape::line(vec![(x, y), (x + 18.0, y)], color, 2.0)),
        Marker::Dashed => {
            canvas.push(Shape::line(vec![(x, y), (x + 18.0, y)], color, 1.5).dashed())
        }
        Marker::Dot => canvas.push(Shape::Disc {
            centre: (x + 9.0, y),
            radius: 4.0,
            color,
        }),
        Marker::Diamond => diamond(canvas, (x + 9.0, y), color),
        Marker::Bar => canvas.push(Shape::Polygon {
            points: vec![
                (x + 3.0, y - 6.0),
                (x + 15.0, y - 6.0),
                (x + 15.0, y + 6.0),
                (x + 3.0, y + 6.0),
            ],
            fill: color,
            opacity: 1.0,
            clip: None,
        }),
    }
}

/// A diamond 10 px across centred at `at`: `color` inside a dark outline.
pub fn diamond(canvas: &mut Canvas, at: P2, color: Rgb) {
    let (x, y) = at;
    let r = 5.0;
    let points = vec![(x, y - r), (x + r, y), (x, y + r), (x - r, y)];
    let mut outline = points.clone();
    outline.push((x, y - r));
    canvas.push(Shape::Polygon {
        points,
        fill: color,
        opacity: 1.0,
        clip: None,
    });
    canvas.push(Shape::line(outline, INK, 1.0));
}

/// A named list of values, one per category.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Legend entry.
    pub name: String,
    /// One value per category (NaN: no bar).
    pub values: Vec<f64>,
}

/// Grouped bars: categories along the bottom, one bar per series in each.
#[derive(Clone, Debug, PartialEq)]
pub struct BarChart {
    /// Title above the chart.
    pub title: String,
    /// Vertical axis label with its unit, e.g. `"reached [%]"`.
    pub y_label: String,
    /// Category names along the bottom.
    pub categories: Vec<String>,
    /// The series (colours from [`PALETTE`] in order).
    pub series: Vec<Series>,
    /// Top of the axis (default: the largest value, rounded up).
    pub y_max: Option<f64>,
}

/// Points of one series.
#[derive(Clone, Debug, PartialEq)]
pub struct PointSeries {
    /// Legend entry.
    pub name: String,
    /// `(x, y)` points.
    pub points: Vec<(f64, f64)>,
}

/// Points against two axes, optionally with the line `y = x` (a bound).
#[derive(Clone, Debug, PartialEq)]
pub struct ScatterChart {
    /// Title above the chart.
    pub title: String,
    /// Horizontal axis label with its unit, e.g. `"bound [s]"`.
    pub x_label: String,
    /// Vertical axis label with its unit, e.g. `"motion time [s]"`.
    pub y_label: String,
    /// The series (colours from [`PALETTE`] in order).
    pub series: Vec<PointSeries>,
    /// Legend entry for a dashed `y = x` line, if one is wanted.
    pub diagonal: Option<String>,
    /// Further dashed lines `y = k x` (e.g. a target of twice the bound),
    /// lighter, with their legend entries; drawn only with `diagonal`.
    pub slopes: Vec<(f64, String)>,
    /// Logarithmic axes (points with a coordinate <= 0 are left out).
    pub log: bool,
}

const CHART_W: f64 = 760.0;
const CHART_H: f64 = 460.0;

/// A grouped bar chart with value labels; `.write(dir, stem)` gives SVG and PNG.
pub fn bar_chart(chart: &BarChart) -> Canvas {
    let mut canvas = Canvas::new(CHART_W as u32, CHART_H as u32);
    let rect = (70.0, 60.0, CHART_W - 20.0, CHART_H - 60.0);
    let top = chart.y_max.unwrap_or_else(|| {
        chart
            .series
            .iter()
            .flat_map(|s| s.values.iter().copied())
            .filter(|v| v.is_finite())
            .fold(0.0, f64::max)
    });
    let n = chart.categories.len().max(1);
    let mut axes = Axes::new(
        rect,
        Scale {
            lo: 0.0,
            hi: n as f64,
            log: false,
        },
        Scale::linear(0.0, if top > 0.0 { top } else { 1.0 }),
    );
    axes.x_ticks = Vec::new();
    axes.draw(&mut canvas, &chart.title, "", &chart.y_label);
    let groups = chart.series.len().max(1) as f64;
    let step = nice_step(axes.y.hi - axes.y.lo, 5.0);
    for (c, name) in chart.categories.iter().enumerate() {
        let x = axes.map(c as f64 + 0.5, 0.0).map_or(0.0, |p| p.0);
        canvas.push(
            Shape::text((x, rect.3 + 18.0), 11.5, name.clone())
                .anchored(Anchor::Middle)
                .colored(INK),
        );
        for (s, series) in chart.series.iter().enumerate() {
            let Some(&v) = series.values.get(c).filter(|v| v.is_finite()) else {
                continue;
            };
            let left = c as f64 + 0.1 + 0.8 * s as f64 / groups;
            let right = left + 0.8 / groups * 0.9;
            let (Some(a), Some(b)) = (axes.map(left, 0.0), axes.map(right, v.max(0.0))) else {
                continue;
            };
            canvas.push(Shape::Polygon {
                points: vec![(a.0, a.1), (b.0, a.1), (b.0, b.1), (a.0, b.1)],
                fill: PALETTE[s % PALETTE.len()],
                opacity: 1.0,
                clip: Some(rect),
            });
            canvas.push(
                Shape::text(
                    ((a.0 + b.0) / 2.0, b.1 - 4.0),
                    10.0,
                    tick_label(v, step / 10.0),
                )
                .anchored(Anchor::Middle)
                .colored(INK),
            );
        }
    }
    let items: Vec<(String, Rgb, Marker)> = chart
        .series
        .iter()
        .enumerate()
        .map(|(s, series)| (series.name.clone(), PALETTE[s % PALETTE.len()], Marker::Bar))
        .collect();
    if items.len() > 1 {
        // A row under the category names: bars reach the top, where a
        // legend box would cover them.
        let size = 11.0;
        let width: f64 = items
            .iter()
            .map(|(n, ..)| 24.0 + font::width(n, size) + 18.0)
            .sum::<f64>()
            - 18.0;
        let mut x = ((rect.0 + rect.2 - width) / 2.0).max(rect.0);
        let y = rect.3 + 42.0;
        for (name, color, marker) in &items {
            legend_marker(&mut canvas, (x, y), *color, *marker);
            canvas.push(Shape::text((x + 24.0, y + 4.0), size, name.clone()).colored(INK));
            x += 24.0 + font::width(name, size) + 18.0;
        }
    }
    canvas
}

/// A scatter chart (with the dashed line `y = x` if asked); `.write(dir, stem)` gives SVG and PNG.
pub fn scatter_chart(chart: &ScatterChart) -> Canvas {
    let mut canvas = Canvas::new(CHART_W as u32, CHART_H as u32);
    let rect = (80.0, 60.0, CHART_W - 20.0, CHART_H - 60.0);
    let usable = |&(x, y): &(f64, f64)| {
        x.is_finite() && y.is_finite() && (!chart.log || (x > 0.0 && y > 0.0))
    };
    let points: Vec<(f64, f64)> = chart
        .series
        .iter()
        .flat_map(|s| s.points.iter().copied())
        .filter(usable)
        .collect();
    let (mut xs, mut ys): (Vec<f64>, Vec<f64>) = points.iter().copied().unzip();
    if chart.diagonal.is_some() {
        // Same range on both axes so that y = x is the diagonal.
        let all: Vec<f64> = xs.iter().chain(&ys).copied().collect();
        xs.clone_from(&all);
        ys = all;
    }
    let range = |v: &[f64]| {
        let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if lo.is_finite() {
            (lo, hi)
        } else {
            (0.0, 1.0)
        }
    };
    let scale = |v: &[f64]| {
        let (lo, hi) = range(v);
        if chart.log {
            Scale::log_of(v.iter().copied())
        } else {
            Scale::linear(lo.min(0.0), hi)
        }
    };
    let axes = Axes::new(rect, scale(&xs), scale(&ys));
    axes.draw(&mut canvas, &chart.title, &chart.x_label, &chart.y_label);
    let mut items = Vec::new();
    if let Some(name) = &chart.diagonal {
        let (lo, hi) = (axes.x.lo.max(axes.y.lo), axes.x.hi.min(axes.y.hi));
        let line: Vec<P2> = (0..=64)
            .filter_map(|k| {
                let t = k as f64 / 64.0;
                let v = if chart.log {
                    lo * (hi / lo).powf(t)
                } else {
                    lo + (hi - lo) * t
                };
                axes.map(v, v)
            })
            .collect();
        canvas.push(Shape::line(line, MUTED, 1.5).dashed().clipped(rect));
        items.push((name.clone(), MUTED, Marker::Dashed));
        for (k, name) in &chart.slopes {
            let line: Vec<P2> = (0..=64)
                .filter_map(|i| {
                    let t = i as f64 / 64.0;
                    let v = if chart.log {
                        axes.x.lo * (axes.x.hi / axes.x.lo).powf(t)
                    } else {
                        axes.x.lo + (axes.x.hi - axes.x.lo) * t
                    };
                    axes.map(v, k * v)
                })
                .collect();
            canvas.push(Shape::line(line, LIGHT, 1.2).dashed().clipped(rect));
            items.push((name.clone(), LIGHT, Marker::Dashed));
        }
    }
    for (s, series) in chart.series.iter().enumerate() {
        let color = PALETTE[s % PALETTE.len()];
        for p in series.points.iter().filter(|p| usable(p)) {
            if let Some(centre) = axes.map(p.0, p.1) {
                canvas.push(Shape::Disc {
                    centre,
                    radius: 3.5,
                    color,
                });
            }
        }
        items.push((series.name.clone(), color, Marker::Dot));
    }
    axes.legend(&mut canvas, &items);
    canvas
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_round_numbers() {
        assert_eq!(nice_step(100.0, 5.0), 20.0);
        assert_eq!(nice_step(0.7, 5.0), 0.1);
        let s = Scale::linear(3.0, 97.0);
        assert_eq!((s.lo, s.hi), (0.0, 100.0));
        let labels: Vec<String> = s.ticks().into_iter().map(|t| t.1).collect();
        assert_eq!(labels, ["0", "20", "40", "60", "80", "100"]);
        let l = Scale::log(0.004, 20.0);
        assert_eq!((l.lo, l.hi), (1e-3, 100.0));
        assert_eq!(l.ticks()[0].1, "10⁻³");
        let few: Vec<String> = Scale::log(0.11, 0.9)
            .ticks()
            .into_iter()
            .map(|t| t.1)
            .collect();
        assert_eq!(few, ["0.1", "0.2", "0.5", "1"]);
        assert_eq!(tick_label(-0.0, 0.5), "0.0");
        assert_eq!(tick_label(-1.5, 0.5), "−1.5");
    }

    #[test]
    fn charts_draw_bars_points_and_labels() {
        let bars = bar_chart(&BarChart {
            title: "reach".into(),
            y_label: "reached [%]".into(),
            categories: vec!["a".into(), "b".into()],
            series: vec![
                Series {
                    name: "one".into(),
                    values: vec![50.0, 100.0],
                },
                Series {
                    name: "two".into(),
                    values: vec![f64::NAN, 75.0],
                },
            ],
            y_max: Some(100.0),
        });
        let svg = bars.svg();
        assert_eq!(svg.matches("fill-opacity=\"1\"").count(), 3 + 2);
        assert!(svg.contains(">reached [%]</text>"));
        let scatter = scatter_chart(&ScatterChart {
            title: "time".into(),
            x_label: "bound [s]".into(),
            y_label: "motion time [s]".into(),
            series: vec![PointSeries {
                name: "runs".into(),
                points: vec![(1.0, 0.5), (2.0, 2.5), (f64::NAN, 1.0)],
            }],
            diagonal: Some("y = bound".into()),
            slopes: vec![(2.0, "y = 2 bound".into())],
            log: false,
        });
        assert_eq!(scatter.svg().matches("<circle").count(), 2 + 1);
        // The diagonal, the 2x line and their two legend swatches.
        assert_eq!(scatter.svg().matches("stroke-dasharray").count(), 4);
        assert!(scatter.svg().contains(">y = 2 bound</text>"));
    }
}
