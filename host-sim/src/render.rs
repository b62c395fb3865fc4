//! Pictures of a run, drawn without any font or plotting library.
//!
//! | file | what |
//! |---|---|
//! | `arm.svg`, `arm.png` | three orthographic views (top XY, front XZ, side YZ): obstacle silhouettes, the end-effector path, the arm at six instants (blue = start, red = end), the waypoints and target (green) |
//! | `plots.svg`, `plots.png` | `V`, position and orientation errors, clearance `C - 1` against step (log scales) |
//! | `animation.html` | the three views playing the motion (self-contained, no network) |
//!
//! A small scene list ([`Canvas`]) is written both as SVG (with text) and as
//! a PNG by a minimal anti-aliasing-free rasteriser (no text: CI machines have no fonts).
//! Obstacle silhouettes are the convex hulls of projected surface samples
//! (super-ellipsoids with exponents >= 1 are convex, so the hull is exact up to sampling).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Result;

use crate::check::forward;
use crate::problem::Problem;
use crate::trajectory::Trajectory;

type P2 = (f64, f64);
type Rgb = [u8; 3];

/// A clip rectangle `(x0, y0, x1, y1)` in pixels.
type Clip = (f64, f64, f64, f64);

/// One drawing primitive.
#[derive(Clone, Debug)]
pub enum Shape {
    /// An open polyline.
    Line {
        /// Points, pixels.
        points: Vec<P2>,
        /// Colour.
        color: Rgb,
        /// Width, pixels.
        width: f64,
        /// Clip rectangle.
        clip: Option<Clip>,
    },
    /// A filled polygon.
    Polygon {
        /// Points, pixels.
        points: Vec<P2>,
        /// Fill colour.
        fill: Rgb,
        /// Opacity in [0, 1].
        opacity: f64,
        /// Clip rectangle.
        clip: Option<Clip>,
    },
    /// A filled disc.
    Disc {
        /// Centre, pixels.
        centre: P2,
        /// Radius, pixels.
        radius: f64,
        /// Colour.
        color: Rgb,
    },
    /// Text (SVG only).
    Text {
        /// Anchor (left baseline), pixels.
        at: P2,
        /// Font size, pixels.
        size: f64,
        /// The text.
        text: String,
    },
}

/// A list of shapes on a white page.
#[derive(Clone, Debug, Default)]
pub struct Canvas {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// Shapes, painted in order.
    pub shapes: Vec<Shape>,
}

fn hex(c: Rgb) -> String {
    format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2])
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

fn points_attr(points: &[P2]) -> String {
    let mut s = String::new();
    for (x, y) in points {
        let _ = write!(s, "{x:.2},{y:.2} ");
    }
    s
}

impl Canvas {
    fn new(width: u32, height: u32) -> Self {
        Canvas {
            width,
            height,
            shapes: Vec::new(),
        }
    }

    /// The SVG document; `extra` is inserted before the closing tag.
    pub fn svg_with(&self, extra: &str) -> String {
        let mut s = format!(
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\">\n<rect width=\"{w}\" height=\"{h}\" fill=\"white\"/>\n",
            w = self.width,
            h = self.height
        );
        let mut clips: Vec<Clip> = Vec::new();
        let mut clip_id = |c: Clip, s: &mut String| -> usize {
            if let Some(i) = clips.iter().position(|&k| k == c) {
                return i;
            }
            let _ = writeln!(
                s,
                "<clipPath id=\"c{}\"><rect x=\"{:.1}\" y=\"{:.1}\" width=\"{:.1}\" height=\"{:.1}\"/></clipPath>",
                clips.len(),
                c.0,
                c.1,
                c.2 - c.0,
                c.3 - c.1
            );
            clips.push(c);
            clips.len() - 1
        };
        for shape in &self.shapes {
            match shape {
                Shape::Line {
                    points,
                    color,
                    width,
                    clip,
                } => {
                    let c = clip.map(|c| format!(" clip-path=\"url(#c{})\"", clip_id(c, &mut s)));
                    let _ = writeln!(
                        s,
                        "<polyline points=\"{}\" fill=\"none\" stroke=\"{}\" stroke-width=\"{width}\" stroke-linejoin=\"round\"{}/>",
                        points_attr(points),
                        hex(*color),
                        c.unwrap_or_default()
                    );
                }
                Shape::Polygon {
                    points,
                    fill,
                    opacity,
                    clip,
                } => {
                    let c = clip.map(|c| format!(" clip-path=\"url(#c{})\"", clip_id(c, &mut s)));
                    let _ = writeln!(
                        s,
                        "<polygon points=\"{}\" fill=\"{}\" fill-opacity=\"{opacity}\"{}/>",
                        points_attr(points),
                        hex(*fill),
                        c.unwrap_or_default()
                    );
                }
                Shape::Disc {
                    centre,
                    radius,
                    color,
                } => {
                    let _ = writeln!(
                        s,
                        "<circle cx=\"{:.2}\" cy=\"{:.2}\" r=\"{radius}\" fill=\"{}\"/>",
                        centre.0,
                        centre.1,
                        hex(*color)
                    );
                }
                Shape::Text { at, size, text } => {
                    let _ = writeln!(
                        s,
                        "<text x=\"{:.1}\" y=\"{:.1}\" font-family=\"sans-serif\" font-size=\"{size}\">{}</text>",
                        at.0,
                        at.1,
                        escape(text)
                    );
                }
            }
        }
        s.push_str(extra);
        s.push_str("</svg>\n");
        s
    }

    /// The SVG document.
    pub fn svg(&self) -> String {
        self.svg_with("")
    }

    /// RGB pixels (text omitted).
    pub fn raster(&self) -> Vec<u8> {
        let (w, h) = (self.width as usize, self.height as usize);
        let mut px = vec![255u8; w * h * 3];
        let full = (0.0, 0.0, w as f64, h as f64);
        let mut blend = |x: i64, y: i64, c: Rgb, a: f64, clip: Clip| {
            let (fx, fy) = (x as f64 + 0.5, y as f64 + 0.5);
            if x < 0 || y < 0 || x as usize >= w || y as usize >= h {
                return;
            }
            if fx < clip.0 || fy < clip.1 || fx > clip.2 || fy > clip.3 {
                return;
            }
            let i = (y as usize * w + x as usize) * 3;
            for k in 0..3 {
                px[i + k] = (px[i + k] as f64 * (1.0 - a) + c[k] as f64 * a).round() as u8;
            }
        };
        for shape in &self.shapes {
            match shape {
                Shape::Line {
                    points,
                    color,
                    width,
                    clip,
                } => {
                    let r = (width / 2.0).max(0.5);
                    let clip = clip.unwrap_or(full);
                    for seg in points.windows(2) {
                        let (a, b) = (seg[0], seg[1]);
                        let x0 = (a.0.min(b.0) - r).floor() as i64;
                        let x1 = (a.0.max(b.0) + r).ceil() as i64;
                        let y0 = (a.1.min(b.1) - r).floor() as i64;
                        let y1 = (a.1.max(b.1) + r).ceil() as i64;
                        if (x1 - x0) * (y1 - y0) > 4_000_000 {
                            continue;
                        }
                        for y in y0..=y1 {
                            for x in x0..=x1 {
                                let p = (x as f64 + 0.5, y as f64 + 0.5);
                                if segment_distance(p, a, b) <= r {
                                    blend(x, y, *color, 1.0, clip);
                                }
                            }
                        }
                    }
                }
                Shape::Polygon {
                    points,
                    fill,
                    opacity,
                    clip,
                } => {
                    let clip = clip.unwrap_or(full);
                    if points.len() < 3 {
                        continue;
                    }
                    let y0 = points.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
                    let y1 = points.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max);
                    let (y0, y1) = (y0.max(0.0) as i64, y1.min(h as f64) as i64);
                    for y in y0..=y1 {
                        let fy = y as f64 + 0.5;
                        let mut xs = Vec::new();
                        for i in 0..points.len() {
                            let (a, b) = (points[i], points[(i + 1) % points.len()]);
                            if (a.1 <= fy) != (b.1 <= fy) {
                                xs.push(a.0 + (fy - a.1) / (b.1 - a.1) * (b.0 - a.0));
                            }
                        }
                        xs.sort_by(|a, b| a.total_cmp(b));
                        for pair in xs.chunks(2) {
                            if let [xa, xb] = pair {
                                let (xa, xb) = (xa.max(0.0), xb.min(w as f64));
                                for x in (xa.round() as i64)..(xb.round() as i64) {
                                    blend(x, y, *fill, *opacity, clip);
                                }
                            }
                        }
                    }
                }
                Shape::Disc {
                    centre,
                    radius,
                    color,
                } => {
                    let (x0, x1) = ((centre.0 - radius) as i64, (centre.0 + radius) as i64 + 1);
                    let (y0, y1) = ((centre.1 - radius) as i64, (centre.1 + radius) as i64 + 1);
                    for y in y0..=y1 {
                        for x in x0..=x1 {
                            let (dx, dy) = (x as f64 + 0.5 - centre.0, y as f64 + 0.5 - centre.1);
                            if dx * dx + dy * dy <= radius * radius {
                                blend(x, y, *color, 1.0, full);
                            }
                        }
                    }
                }
                Shape::Text { .. } => {}
            }
        }
        px
    }

    /// PNG bytes (text omitted).
    pub fn png(&self) -> Result<Vec<u8>> {
        let mut out = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut out, self.width, self.height);
            enc.set_color(png::ColorType::Rgb);
            enc.set_depth(png::BitDepth::Eight);
            let mut writer = enc.write_header()?;
            writer.write_image_data(&self.raster())?;
        }
        Ok(out)
    }
}

fn segment_distance(p: P2, a: P2, b: P2) -> f64 {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p.0 - a.0) * dx + (p.1 - a.1) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (cx, cy) = (a.0 + t * dx - p.0, a.1 + t * dy - p.1);
    (cx * cx + cy * cy).sqrt()
}

/// Convex hull (monotone chain).
fn hull(mut pts: Vec<P2>) -> Vec<P2> {
    pts.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    pts.dedup();
    if pts.len() < 3 {
        return pts;
    }
    let cross = |o: P2, a: P2, b: P2| (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0);
    let mut lower: Vec<P2> = Vec::new();
    for &p in &pts {
        while lower.len() >= 2 && cross(lower[lower.len() - 2], lower[lower.len() - 1], p) <= 0.0 {
            lower.pop();
        }
        lower.push(p);
    }
    let mut upper: Vec<P2> = Vec::new();
    for &p in pts.iter().rev() {
        while upper.len() >= 2 && cross(upper[upper.len() - 2], upper[upper.len() - 1], p) <= 0.0 {
            upper.pop();
        }
        upper.push(p);
    }
    lower.pop();
    upper.pop();
    lower.extend(upper);
    lower
}

/// Surface samples of obstacle `o` in world coordinates.
fn surface(problem: &Problem, o: usize) -> Vec<[f64; 3]> {
    let s = &problem.obstacles[o];
    let axes = s.semi_axes.map(f64::from);
    let k = s.exponents.map(f64::from);
    let [rx, ry, rz] = s.euler_123.map(f64::from);
    let (sx, cx) = rx.sin_cos();
    let (sy, cy) = ry.sin_cos();
    let (sz, cz) = rz.sin_cos();
    let r = [
        [cz * cy, cz * sy * sx - sz * cx, cz * sy * cx + sz * sx],
        [sz * cy, sz * sy * sx + cz * cx, sz * sy * cx - cz * sx],
        [-sy, cy * sx, cy * cx],
    ];
    let c = s.centre.map(f64::from);
    let mut out = Vec::new();
    const LAT: usize = 24;
    const LON: usize = 48;
    for i in 0..=LAT {
        let phi = std::f64::consts::PI * i as f64 / LAT as f64;
        for j in 0..LON {
            let th = std::f64::consts::TAU * j as f64 / LON as f64;
            let d = [phi.sin() * th.cos(), phi.sin() * th.sin(), phi.cos()];
            // Largest t with C(t d) <= 1, by bisection (C grows with t).
            let f = |t: f64| -> f64 { (0..3).map(|a| (t * d[a] / axes[a]).abs().powf(k[a])).sum() };
            let (mut lo, mut hi) = (0.0, axes.iter().cloned().fold(0.0, f64::max) * 2.0);
            for _ in 0..40 {
                let mid = 0.5 * (lo + hi);
                if f(mid) <= 1.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let x = d.map(|v| v * lo);
            out.push([
                c[0] + r[0][0] * x[0] + r[0][1] * x[1] + r[0][2] * x[2],
                c[1] + r[1][0] * x[0] + r[1][1] * x[1] + r[1][2] * x[2],
                c[2] + r[2][0] * x[0] + r[2][1] * x[1] + r[2][2] * x[2],
            ]);
        }
    }
    out
}

/// One orthographic panel: world axes `(u, v)` mapped into a pixel box.
#[derive(Clone, Copy)]
struct Panel {
    axes: (usize, usize),
    origin: P2,
    size: f64,
    lo: (f64, f64),
    scale: f64,
    title: &'static str,
}

impl Panel {
    fn map(&self, p: &[f64; 3]) -> P2 {
        let (u, v) = (p[self.axes.0], p[self.axes.1]);
        (
            self.origin.0 + (u - self.lo.0) * self.scale,
            self.origin.1 + self.size - (v - self.lo.1) * self.scale,
        )
    }
    fn clip(&self) -> Clip {
        (
            self.origin.0,
            self.origin.1,
            self.origin.0 + self.size,
            self.origin.1 + self.size,
        )
    }
}

const PANEL: f64 = 360.0;
const PAD: f64 = 30.0;

/// The arm drawing: canvas, panels and every row's frame origins.
struct ArmScene {
    canvas: Canvas,
    panels: [Panel; 3],
    origins: Vec<Vec<[f64; 3]>>,
}

fn lerp(a: Rgb, b: Rgb, t: f64) -> Rgb {
    [0, 1, 2].map(|i| (a[i] as f64 + (b[i] as f64 - a[i] as f64) * t).round() as u8)
}

fn arm_scene(problem: &Problem, t: &Trajectory, snapshots: usize) -> ArmScene {
    let origins: Vec<Vec<[f64; 3]>> = t.rows.iter().map(|r| forward(problem, &r.q).0).collect();
    // Bounds: the arm over the whole run, the waypoints, plus room around them.
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    let mut grow = |p: &[f64; 3]| {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    };
    for o in &origins {
        o.iter().for_each(&mut grow);
    }
    for w in &problem.waypoints {
        grow(&w.position.map(f64::from));
    }
    let span = (0..3).map(|a| hi[a] - lo[a]).fold(0.0, f64::max).max(1e-6);
    let room = 0.15 * span;
    let side = span + 2.0 * room;
    let centre: Vec<f64> = (0..3).map(|a| 0.5 * (lo[a] + hi[a])).collect();
    let low = |a: usize| centre[a] - side / 2.0;
    let scale = PANEL / side;
    let titles = [
        "top (x right, y up)",
        "front (x right, z up)",
        "side (y right, z up)",
    ];
    let axes = [(0, 1), (0, 2), (1, 2)];
    let panels = [0, 1, 2].map(|i| Panel {
        axes: axes[i],
        origin: (PAD + i as f64 * (PANEL + PAD), PAD + 10.0),
        size: PANEL,
        lo: (low(axes[i].0), low(axes[i].1)),
        scale,
        title: titles[i],
    });
    let width = (3.0 * PANEL + 4.0 * PAD) as u32;
    let height = (PANEL + 2.0 * PAD + 30.0) as u32;
    let mut canvas = Canvas::new(width, height);
    canvas.shapes.push(Shape::Text {
        at: (PAD, 22.0),
        size: 14.0,
        text: format!(
            "{} — {} rows; arm at {} instants (blue = start, red = end); lengths in {}",
            problem.name,
            t.rows.len(),
            snapshots,
            problem.length_unit
        ),
    });
    let surfaces: Vec<Vec<[f64; 3]>> = (0..problem.obstacles.len())
        .map(|o| surface(problem, o))
        .collect();
    let instants = instants(&origins, snapshots);
    for p in &panels {
        let (x0, y0, x1, y1) = p.clip();
        canvas.shapes.push(Shape::Line {
            points: vec![(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)],
            color: [160, 160, 160],
            width: 1.0,
            clip: None,
        });
        canvas.shapes.push(Shape::Text {
            at: (x0, y1 + 18.0),
            size: 12.0,
            text: p.title.to_string(),
        });
        for s in &surfaces {
            canvas.shapes.push(Shape::Polygon {
                points: hull(s.iter().map(|q| p.map(q)).collect()),
                fill: [120, 130, 140],
                opacity: 0.35,
                clip: Some(p.clip()),
            });
        }
        // End-effector path, at most ~2000 points.
        let stride = (origins.len() / 2000).max(1);
        let path: Vec<P2> = origins
            .iter()
            .step_by(stride)
            .chain(origins.last())
            .filter_map(|o| o.last().map(|e| p.map(e)))
            .collect();
        canvas.shapes.push(Shape::Line {
            points: path,
            color: [30, 30, 30],
            width: 1.0,
            clip: Some(p.clip()),
        });
        for (s, &k) in instants.iter().enumerate() {
            let frac = s as f64 / (snapshots.max(2) - 1) as f64;
            let color = lerp([40, 90, 220], [220, 50, 40], frac);
            canvas.shapes.push(Shape::Line {
                points: origins[k].iter().map(|q| p.map(q)).collect(),
                color,
                width: 2.0,
                clip: Some(p.clip()),
            });
        }
        for w in &problem.waypoints {
            canvas.shapes.push(Shape::Disc {
                centre: p.map(&w.position.map(f64::from)),
                radius: 4.0,
                color: [20, 160, 60],
            });
        }
    }
    ArmScene {
        canvas,
        panels,
        origins,
    }
}

/// `count` rows at equal fractions of the end effector's path length (so a
/// long slow creep at the end does not take every snapshot).
fn instants(origins: &[Vec<[f64; 3]>], count: usize) -> Vec<usize> {
    let mut length = vec![0.0];
    for w in origins.windows(2) {
        let (a, b) = (w[0].last(), w[1].last());
        let step = match (a, b) {
            (Some(a), Some(b)) => (0..3).map(|i| (a[i] - b[i]).powi(2)).sum::<f64>().sqrt(),
            _ => 0.0,
        };
        length.push(length.last().copied().unwrap_or(0.0) + step);
    }
    let total = length.last().copied().unwrap_or(0.0);
    let count = count.max(2);
    (0..count)
        .map(|s| {
            let goal = total * s as f64 / (count - 1) as f64;
            length
                .iter()
                .position(|&l| l >= goal)
                .unwrap_or(origins.len() - 1)
        })
        .collect()
}

fn plots(problem: &Problem, t: &Trajectory) -> Canvas {
    let (w, ph) = (900.0, 200.0);
    let left = 70.0;
    let mut canvas = Canvas::new(w as u32, (3.0 * (ph + 40.0) + 30.0) as u32);
    canvas.shapes.push(Shape::Text {
        at: (left, 20.0),
        size: 14.0,
        text: format!("{}: against step (log10 scales)", problem.name),
    });
    let steps: Vec<f64> = t.rows.iter().map(|r| r.step as f64).collect();
    let smax = steps.last().copied().unwrap_or(1.0).max(1.0);
    type Series = (&'static str, Rgb, Vec<Option<f64>>);
    let panels: [(&str, Vec<Series>); 3] = [
        (
            "V (eq. 12)",
            vec![("V", [40, 90, 220], t.rows.iter().map(|r| r.v).collect())],
        ),
        (
            "errors",
            vec![
                (
                    "position",
                    [40, 90, 220],
                    t.rows.iter().map(|r| r.position_error).collect(),
                ),
                (
                    "orientation",
                    [220, 50, 40],
                    t.rows.iter().map(|r| r.orientation_error).collect(),
                ),
            ],
        ),
        (
            "clearance C-1 (closest pair within influence)",
            vec![(
                "C-1",
                [20, 160, 60],
                t.rows.iter().map(|r| r.clearance).collect(),
            )],
        ),
    ];
    for (i, (title, series)) in panels.iter().enumerate() {
        let top = 40.0 + i as f64 * (ph + 40.0);
        let (x0, x1, y0, y1) = (left, w - 20.0, top, top + ph);
        let logs: Vec<f64> = series
            .iter()
            .flat_map(|s| s.2.iter().flatten())
            .filter(|v| **v > 0.0 && v.is_finite())
            .map(|v| v.log10())
            .collect();
        let lo = logs.iter().cloned().fold(f64::INFINITY, f64::min);
        let hi = logs.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        let (lo, hi) = if lo.is_finite() {
            (lo.floor(), hi.ceil().max(lo.floor() + 1.0))
        } else {
            (0.0, 1.0)
        };
        canvas.shapes.push(Shape::Line {
            points: vec![(x0, y0), (x0, y1), (x1, y1)],
            color: [0, 0, 0],
            width: 1.0,
            clip: None,
        });
        canvas.shapes.push(Shape::Text {
            at: (x0 + 5.0, y0 - 6.0),
            size: 12.0,
            text: title.to_string(),
        });
        let mut decade = lo;
        while decade <= hi {
            let y = y1 - (decade - lo) / (hi - lo) * ph;
            canvas.shapes.push(Shape::Line {
                points: vec![(x0 - 4.0, y), (x1, y)],
                color: [225, 225, 225],
                width: 1.0,
                clip: None,
            });
            canvas.shapes.push(Shape::Text {
                at: (8.0, y + 4.0),
                size: 11.0,
                text: format!("1e{decade}"),
            });
            decade += 1.0;
        }
        canvas.shapes.push(Shape::Text {
            at: (x1 - 80.0, y1 + 16.0),
            size: 11.0,
            text: format!("step {}", smax as u64),
        });
        for (k, (name, color, values)) in series.iter().enumerate() {
            let stride = (values.len() / 3000).max(1);
            let mut run: Vec<P2> = Vec::new();
            let flush = |run: &mut Vec<P2>, canvas: &mut Canvas| {
                if run.len() >= 2 {
                    canvas.shapes.push(Shape::Line {
                        points: std::mem::take(run),
                        color: *color,
                        width: 1.5,
                        clip: Some((x0, y0, x1, y1)),
                    });
                }
                run.clear();
            };
            for (s, v) in steps.iter().zip(values).step_by(stride) {
                match v.filter(|v| *v > 0.0 && v.is_finite()) {
                    Some(v) => run.push((
                        x0 + s / smax * (x1 - x0),
                        y1 - (v.log10() - lo) / (hi - lo) * ph,
                    )),
                    None => flush(&mut run, &mut canvas),
                }
            }
            flush(&mut run, &mut canvas);
            canvas.shapes.push(Shape::Text {
                at: (x1 - 200.0 + 100.0 * k as f64, y0 + 14.0),
                size: 11.0,
                text: format!("— {name}"),
            });
        }
    }
    canvas
}

fn animation(problem: &Problem, scene: &ArmScene) -> String {
    let n = scene.origins.len();
    let frames = n.min(300);
    let mut data = String::from("[");
    for f in 0..frames {
        let k = if frames > 1 {
            f * (n - 1) / (frames - 1)
        } else {
            0
        };
        data.push('[');
        for p in &scene.panels {
            let pts: Vec<String> = scene.origins[k]
                .iter()
                .map(|q| {
                    let (x, y) = p.map(q);
                    format!("{x:.1},{y:.1}")
                })
                .collect();
            let _ = write!(data, "\"{}\",", pts.join(" "));
        }
        data.push_str("],");
    }
    data.push(']');
    let mut arms = String::new();
    for i in 0..3 {
        let _ = writeln!(
            arms,
            "<polyline id=\"arm{i}\" fill=\"none\" stroke=\"#d03020\" stroke-width=\"3\" stroke-linejoin=\"round\"/>"
        );
    }
    let svg = scene.canvas.svg_with(&arms);
    format!(
        r#"<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>{name}: CAPP motion</title></head>
<body style="font-family:sans-serif">
<h3>{name}</h3>
<div>{svg}</div>
<button id="play">pause</button>
<input id="seek" type="range" min="0" max="{last}" value="0" style="width:600px">
<span id="label"></span>
<script>
const frames = {data};
const rows = {n};
let i = 0, playing = true;
const seek = document.getElementById('seek');
function show(k) {{
  for (let p = 0; p < 3; p++) document.getElementById('arm' + p).setAttribute('points', frames[k][p]);
  seek.value = k;
  document.getElementById('label').textContent = 'frame ' + (k + 1) + ' / ' + frames.length + ' (of ' + rows + ' rows)';
}}
document.getElementById('play').onclick = function () {{ playing = !playing; this.textContent = playing ? 'pause' : 'play'; }};
seek.oninput = function () {{ i = +this.value; show(i); }};
setInterval(function () {{ if (playing) {{ i = (i + 1) % frames.length; show(i); }} }}, 40);
show(0);
</script>
</body></html>
"#,
        name = escape(&problem.name),
        last = frames.saturating_sub(1),
    )
}

/// Draws `trajectory` of `problem` into `dir`; returns the files written.
pub fn render(problem: &Problem, trajectory: &Trajectory, dir: &Path) -> Result<Vec<PathBuf>> {
    let scene = arm_scene(problem, trajectory, 6);
    let plots = plots(problem, trajectory);
    let files: Vec<(&str, Vec<u8>)> = vec![
        ("arm.svg", scene.canvas.svg().into_bytes()),
        ("arm.png", scene.canvas.png()?),
        ("plots.svg", plots.svg().into_bytes()),
        ("plots.png", plots.png()?),
        ("animation.html", animation(problem, &scene).into_bytes()),
    ];
    let mut written = Vec::new();
    for (name, bytes) in files {
        let path = dir.join(name);
        std::fs::write(&path, bytes)?;
        written.push(path);
    }
    Ok(written)
}
