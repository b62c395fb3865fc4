//! A small scene list written both as SVG and as pixels.
//!
//! [`Canvas`] holds shapes in pixel coordinates (origin top left, y down).
//! [`Canvas::svg`] writes them as SVG text; [`Pixmap`] paints them with
//! coverage anti-aliasing (lines and discs by distance, polygons by exact
//! horizontal span coverage on four sub-scanlines) and the shipped font
//! ([`super::font`]), so a PNG carries the same text as its SVG on every
//! machine: no system font is ever looked up.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use ab_glyph::{point, Font};
use anyhow::Result;

use super::font;

/// A point in pixels.
pub type P2 = (f64, f64);
/// An sRGB colour.
pub type Rgb = [u8; 3];
/// A clip rectangle `(x0, y0, x1, y1)` in pixels.
pub type Clip = (f64, f64, f64, f64);

/// Where a text's anchor point is along its baseline.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Anchor {
    /// The text starts at the anchor.
    Start,
    /// The text is centred on the anchor.
    Middle,
    /// The text ends at the anchor.
    End,
}

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
        /// Dashed (5 px on, 4 px off).
        dashed: bool,
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
    /// One line of text in the shipped font.
    Text {
        /// Anchor on the baseline, pixels.
        at: P2,
        /// Font size (em), pixels.
        size: f64,
        /// The text.
        text: String,
        /// Where `at` is along the text.
        anchor: Anchor,
        /// Colour.
        color: Rgb,
    },
}

impl Shape {
    /// A solid polyline, unclipped.
    pub fn line(points: Vec<P2>, color: Rgb, width: f64) -> Shape {
        Shape::Line {
            points,
            color,
            width,
            dashed: false,
            clip: None,
        }
    }

    /// Black text starting at `at`.
    pub fn text(at: P2, size: f64, text: impl Into<String>) -> Shape {
        Shape::Text {
            at,
            size,
            text: text.into(),
            anchor: Anchor::Start,
            color: [0, 0, 0],
        }
    }

    /// The same shape clipped to `clip` (lines and polygons; others unchanged).
    pub fn clipped(mut self, to: Clip) -> Shape {
        if let Shape::Line { clip, .. } | Shape::Polygon { clip, .. } = &mut self {
            *clip = Some(to);
        }
        self
    }

    /// The same line dashed (lines only).
    pub fn dashed(mut self) -> Shape {
        if let Shape::Line { dashed, .. } = &mut self {
            *dashed = true;
        }
        self
    }

    /// The same text with another anchor (text only).
    pub fn anchored(mut self, to: Anchor) -> Shape {
        if let Shape::Text { anchor, .. } = &mut self {
            *anchor = to;
        }
        self
    }

    /// The same text or line in another colour.
    pub fn colored(mut self, to: Rgb) -> Shape {
        match &mut self {
            Shape::Text { color, .. } | Shape::Line { color, .. } | Shape::Disc { color, .. } => {
                *color = to
            }
            Shape::Polygon { fill, .. } => *fill = to,
        }
        self
    }
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

/// `s` with the characters XML reserves escaped.
pub fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn points_attr(points: &[P2]) -> String {
    let mut s = String::new();
    for (x, y) in points {
        let _ = write!(s, "{x:.2},{y:.2} ");
    }
    s
}

const DASH: (f64, f64) = (5.0, 4.0);

impl Canvas {
    /// An empty white page.
    pub fn new(width: u32, height: u32) -> Self {
        Canvas {
            width,
            height,
            shapes: Vec::new(),
        }
    }

    /// Appends a shape.
    pub fn push(&mut self, shape: Shape) {
        self.shapes.push(shape);
    }

    /// The SVG document; `extra` is inserted before the closing tag.
    pub fn svg_with(&self, extra: &str) -> String {
        let mut s = format!(
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\" font-family=\"DejaVu Sans, Verdana, sans-serif\">\n<rect width=\"{w}\" height=\"{h}\" fill=\"white\"/>\n",
            w = self.width,
            h = self.height
        );
        let mut clips: Vec<Clip> = Vec::new();
        let mut clip_attr = |c: Option<Clip>, s: &mut String| -> String {
            let Some(c) = c else {
                return String::new();
            };
            let id = match clips.iter().position(|&k| k == c) {
                Some(i) => i,
                None => {
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
                }
            };
            format!(" clip-path=\"url(#c{id})\"")
        };
        for shape in &self.shapes {
            match shape {
                Shape::Line {
                    points,
                    color,
                    width,
                    dashed,
                    clip,
                } => {
                    let c = clip_attr(*clip, &mut s);
                    let dash = if *dashed {
                        format!(" stroke-dasharray=\"{} {}\"", DASH.0, DASH.1)
                    } else {
                        String::new()
                    };
                    let _ = writeln!(
                        s,
                        "<polyline points=\"{}\" fill=\"none\" stroke=\"{}\" stroke-width=\"{width}\" stroke-linejoin=\"round\"{dash}{c}/>",
                        points_attr(points),
                        hex(*color),
                    );
                }
                Shape::Polygon {
                    points,
                    fill,
                    opacity,
                    clip,
                } => {
                    let c = clip_attr(*clip, &mut s);
                    let _ = writeln!(
                        s,
                        "<polygon points=\"{}\" fill=\"{}\" fill-opacity=\"{opacity}\"{c}/>",
                        points_attr(points),
                        hex(*fill),
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
                Shape::Text {
                    at,
                    size,
                    text,
                    anchor,
                    color,
                } => {
                    let anchor = match anchor {
                        Anchor::Start => "",
                        Anchor::Middle => " text-anchor=\"middle\"",
                        Anchor::End => " text-anchor=\"end\"",
                    };
                    let _ = writeln!(
                        s,
                        "<text x=\"{:.1}\" y=\"{:.1}\" font-size=\"{size}\" fill=\"{}\"{anchor}>{}</text>",
                        at.0,
                        at.1,
                        hex(*color),
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

    /// The painted page.
    pub fn pixmap(&self) -> Pixmap {
        let mut p = Pixmap::new(self.width as usize, self.height as usize);
        for shape in &self.shapes {
            p.draw(shape);
        }
        p
    }

    /// RGB pixels, row by row.
    pub fn raster(&self) -> Vec<u8> {
        self.pixmap().rgb
    }

    /// PNG bytes.
    pub fn png(&self) -> Result<Vec<u8>> {
        self.pixmap().png()
    }

    /// Writes `STEM.svg` and `STEM.png` into `dir`; returns both paths.
    pub fn write(&self, dir: &Path, stem: &str) -> Result<Vec<PathBuf>> {
        let svg = dir.join(format!("{stem}.svg"));
        let png = dir.join(format!("{stem}.png"));
        std::fs::write(&svg, self.svg())?;
        std::fs::write(&png, self.png()?)?;
        Ok(vec![svg, png])
    }
}

/// RGB pixels that shapes are painted onto.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Pixmap {
    /// Width, pixels.
    pub width: usize,
    /// Height, pixels.
    pub height: usize,
    /// `width * height * 3` bytes, row by row.
    pub rgb: Vec<u8>,
}

impl Pixmap {
    /// A white page.
    pub fn new(width: usize, height: usize) -> Self {
        Pixmap {
            width,
            height,
            rgb: vec![255; width * height * 3],
        }
    }

    fn full(&self) -> Clip {
        (0.0, 0.0, self.width as f64, self.height as f64)
    }

    /// Blends `color` at coverage `alpha` into pixel `(x, y)` if its centre is in `clip`.
    pub fn blend(&mut self, x: i64, y: i64, color: Rgb, alpha: f64, clip: Clip) {
        if x < 0 || y < 0 || x as usize >= self.width || y as usize >= self.height {
            return;
        }
        let (fx, fy) = (x as f64 + 0.5, y as f64 + 0.5);
        if fx < clip.0 || fy < clip.1 || fx > clip.2 || fy > clip.3 || alpha <= 0.0 {
            return;
        }
        let a = alpha.min(1.0);
        let i = (y as usize * self.width + x as usize) * 3;
        for (old, new) in self.rgb[i..i + 3].iter_mut().zip(color) {
            *old = (*old as f64 + (new as f64 - *old as f64) * a).round() as u8;
        }
    }

    /// Paints one shape.
    pub fn draw(&mut self, shape: &Shape) {
        let full = self.full();
        match shape {
            Shape::Line {
                points,
                color,
                width,
                dashed,
                clip,
            } => {
                let clip = clip.unwrap_or(full);
                if *dashed {
                    for piece in dash(points, DASH) {
                        self.stroke(&piece, *color, *width, clip);
                    }
                } else {
                    self.stroke(points, *color, *width, clip);
                }
            }
            Shape::Polygon {
                points,
                fill,
                opacity,
                clip,
            } => self.fill(points, *fill, *opacity, clip.unwrap_or(full)),
            Shape::Disc {
                centre,
                radius,
                color,
            } => {
                let (x0, x1) = (
                    (centre.0 - radius - 1.0) as i64,
                    (centre.0 + radius + 1.0) as i64,
                );
                let (y0, y1) = (
                    (centre.1 - radius - 1.0) as i64,
                    (centre.1 + radius + 1.0) as i64,
                );
                for y in y0..=y1 {
                    for x in x0..=x1 {
                        let (dx, dy) = (x as f64 + 0.5 - centre.0, y as f64 + 0.5 - centre.1);
                        let cover = radius + 0.5 - (dx * dx + dy * dy).sqrt();
                        self.blend(x, y, *color, cover.clamp(0.0, 1.0), full);
                    }
                }
            }
            Shape::Text {
                at,
                size,
                text,
                anchor,
                color,
            } => self.draw_text(*at, *size, text, *anchor, *color),
        }
    }

    /// Paints `text` with its baseline anchor at `at`, in the shipped font
    /// ([`font`]: its layout, `ab_glyph`'s coverage rasterisation).
    pub fn draw_text(&mut self, at: P2, size: f64, text: &str, anchor: Anchor, color: Rgb) {
        let Some(font) = font::font() else {
            return;
        };
        let (glyphs, advance) = font::layout(font, size, text);
        let x0 = at.0 as f32
            - match anchor {
                Anchor::Start => 0.0,
                Anchor::Middle => advance / 2.0,
                Anchor::End => advance,
            };
        let full = (0.0, 0.0, self.width as f64, self.height as f64);
        let s = font::scale(font, size);
        for (id, caret) in glyphs {
            let glyph = id.with_scale_and_position(s, point(x0 + caret, at.1 as f32));
            if let Some(outline) = font.outline_glyph(glyph) {
                let b = outline.px_bounds();
                let (bx, by) = (b.min.x as i64, b.min.y as i64);
                outline.draw(|x, y, c| {
                    self.blend(bx + x as i64, by + y as i64, color, c as f64, full);
                });
            }
        }
    }

    /// A polyline of `width`, each pixel blended once with its largest coverage.
    fn stroke(&mut self, points: &[P2], color: Rgb, width: f64, clip: Clip) {
        let r = (width / 2.0).max(0.5);
        let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
        for p in points {
            x0 = x0.min(p.0);
            y0 = y0.min(p.1);
            x1 = x1.max(p.0);
            y1 = y1.max(p.1);
        }
        let bx0 = ((x0 - r - 1.0).floor().max(clip.0.floor()).max(0.0)) as i64;
        let by0 = ((y0 - r - 1.0).floor().max(clip.1.floor()).max(0.0)) as i64;
        let bx1 = ((x1 + r + 1.0)
            .ceil()
            .min(clip.2.ceil())
            .min(self.width as f64)) as i64;
        let by1 = ((y1 + r + 1.0)
            .ceil()
            .min(clip.3.ceil())
            .min(self.height as f64)) as i64;
        if bx1 <= bx0 || by1 <= by0 || points.len() < 2 {
            return;
        }
        let bw = (bx1 - bx0) as usize;
        let mut cover = vec![0.0f32; bw * (by1 - by0) as usize];
        for seg in points.windows(2) {
            let (a, b) = (seg[0], seg[1]);
            let sx0 = ((a.0.min(b.0) - r - 1.0).floor() as i64).max(bx0);
            let sx1 = ((a.0.max(b.0) + r + 1.0).ceil() as i64).min(bx1 - 1);
            let sy0 = ((a.1.min(b.1) - r - 1.0).floor() as i64).max(by0);
            let sy1 = ((a.1.max(b.1) + r + 1.0).ceil() as i64).min(by1 - 1);
            for y in sy0..=sy1 {
                for x in sx0..=sx1 {
                    let d = segment_distance((x as f64 + 0.5, y as f64 + 0.5), a, b);
                    let c = (r + 0.5 - d).clamp(0.0, 1.0) as f32;
                    let i = (y - by0) as usize * bw + (x - bx0) as usize;
                    if c > cover[i] {
                        cover[i] = c;
                    }
                }
            }
        }
        for (i, &c) in cover.iter().enumerate() {
            if c > 0.0 {
                let (x, y) = (bx0 + (i % bw) as i64, by0 + (i / bw) as i64);
                self.blend(x, y, color, c as f64, clip);
            }
        }
    }

    /// Even-odd fill; coverage from four sub-scanlines per row.
    fn fill(&mut self, points: &[P2], color: Rgb, opacity: f64, clip: Clip) {
        if points.len() < 3 {
            return;
        }
        const SUB: usize = 4;
        let w = self.width;
        let y0 = points.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
        let y1 = points.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max);
        let (y0, y1) = (
            y0.max(0.0).floor() as i64,
            y1.min(self.height as f64 - 1.0).ceil() as i64,
        );
        let mut row = vec![0.0f64; w];
        for y in y0..=y1 {
            row.iter_mut().for_each(|c| *c = 0.0);
            let (mut lo, mut hi) = (w, 0usize);
            for s in 0..SUB {
                let fy = y as f64 + (s as f64 + 0.5) / SUB as f64;
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
                        if xb <= xa {
                            continue;
                        }
                        let (first, last) = (xa.floor() as usize, (xb.ceil() as usize).min(w));
                        lo = lo.min(first);
                        hi = hi.max(last);
                        for (x, c) in row.iter_mut().enumerate().take(last).skip(first) {
                            let overlap = (xb.min(x as f64 + 1.0) - xa.max(x as f64)).max(0.0);
                            *c += overlap / SUB as f64;
                        }
                    }
                }
            }
            for (x, c) in row.iter().enumerate().take(hi).skip(lo) {
                self.blend(x as i64, y, color, opacity * c.min(1.0), clip);
            }
        }
    }

    /// PNG bytes.
    pub fn png(&self) -> Result<Vec<u8>> {
        let mut out = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut out, self.width as u32, self.height as u32);
            enc.set_color(png::ColorType::Rgb);
            enc.set_depth(png::BitDepth::Eight);
            let mut writer = enc.write_header()?;
            writer.write_image_data(&self.rgb)?;
        }
        Ok(out)
    }
}

/// The "on" pieces of a dashed polyline.
fn dash(points: &[P2], (on, off): (f64, f64)) -> Vec<Vec<P2>> {
    let mut pieces = Vec::new();
    let mut current: Vec<P2> = points.first().copied().into_iter().collect();
    let (mut drawing, mut left) = (true, on);
    for seg in points.windows(2) {
        let (mut a, b) = (seg[0], seg[1]);
        let mut len = ((b.0 - a.0).powi(2) + (b.1 - a.1).powi(2)).sqrt();
        while len > left {
            let t = left / len;
            let p = (a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t);
            if drawing {
                current.push(p);
                pieces.push(std::mem::take(&mut current));
            } else {
                current = vec![p];
            }
            drawing = !drawing;
            len -= left;
            left = if drawing { on } else { off };
            a = p;
        }
        left -= len;
        if drawing {
            current.push(b);
        }
    }
    if drawing && current.len() >= 2 {
        pieces.push(current);
    }
    pieces
}

/// Distance from `p` to the segment `a b`.
pub fn segment_distance(p: P2, a: P2, b: P2) -> f64 {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dashes_alternate_along_the_line() {
        let pieces = dash(&[(0.0, 0.0), (20.0, 0.0)], (5.0, 4.0));
        assert_eq!(pieces.len(), 3);
        assert_eq!(pieces[0], vec![(0.0, 0.0), (5.0, 0.0)]);
        assert_eq!(pieces[1], vec![(9.0, 0.0), (14.0, 0.0)]);
        assert_eq!(pieces[2], vec![(18.0, 0.0), (20.0, 0.0)]);
    }

    #[test]
    fn a_filled_square_covers_its_pixels_exactly() {
        let mut p = Pixmap::new(10, 10);
        p.fill(
            &[(2.0, 2.0), (6.0, 2.0), (6.0, 6.0), (2.0, 6.0)],
            [0, 0, 0],
            1.0,
            p.full(),
        );
        let dark = p.rgb.chunks(3).filter(|c| c[0] == 0).count();
        assert_eq!(dark, 16);
        assert_eq!(p.rgb.chunks(3).filter(|c| c[0] == 255).count(), 84);
    }

    #[test]
    fn text_is_painted_and_measured() {
        let mut px = Pixmap::new(120, 30);
        px.draw_text((60.0, 20.0), 14.0, "V, in²", Anchor::Middle, [0, 0, 0]);
        let inked = px.rgb.chunks(3).filter(|c| c[0] < 128).count();
        assert!(inked > 30, "{inked}");
        let w = font::width("V, in²", 14.0);
        assert!(w > 30.0 && w < 60.0, "{w}");
        assert!(font::width("WWW", 12.0) > font::width("iii", 12.0));
    }
}
