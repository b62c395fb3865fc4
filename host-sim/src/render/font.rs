//! The one font pictures use: DejaVu Sans 2.37, compiled in
//! (`host-sim/assets/DejaVuSans.ttf`, Bitstream Vera license with DejaVu's
//! public-domain changes: `assets/LICENSE-DejaVu.txt`).
//!
//! Text is laid out on one baseline with the font's advances and kerning and
//! rasterised by `ab_glyph` (coverage anti-aliasing); nothing depends on the
//! machine's fonts, so a PNG is the same everywhere. Sizes are CSS font
//! sizes (the em in pixels), as in the SVG.

use std::sync::OnceLock;

use ab_glyph::{point, Font, FontRef, GlyphId, PxScale, ScaleFont};

use super::canvas::{Anchor, Pixmap, Rgb, P2};

/// The TTF file, as shipped.
pub static DEJAVU_SANS: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");

/// The parsed font (`None` only if the shipped file were broken, which a test rules out).
pub fn font() -> Option<&'static FontRef<'static>> {
    static FONT: OnceLock<Option<FontRef<'static>>> = OnceLock::new();
    FONT.get_or_init(|| FontRef::try_from_slice(DEJAVU_SANS).ok())
        .as_ref()
}

/// `ab_glyph`'s scale (ascent to descent) for a CSS font size.
fn scale(font: &FontRef<'_>, size: f64) -> PxScale {
    let em = font.units_per_em().unwrap_or(2048.0);
    PxScale::from(size as f32 * font.height_unscaled() / em)
}

/// Glyphs of `text` with their caret positions, and the total advance.
fn layout(font: &FontRef<'static>, size: f64, text: &str) -> (Vec<(GlyphId, f32)>, f32) {
    let scaled = font.as_scaled(scale(font, size));
    let mut caret = 0.0f32;
    let mut prev: Option<GlyphId> = None;
    let mut glyphs = Vec::with_capacity(text.len());
    for c in text.chars() {
        let id = scaled.glyph_id(c);
        if let Some(p) = prev {
            caret += scaled.kern(p, id);
        }
        glyphs.push((id, caret));
        caret += scaled.h_advance(id);
        prev = Some(id);
    }
    (glyphs, caret)
}

/// Width of `text` at `size`, pixels.
pub fn width(text: &str, size: f64) -> f64 {
    font().map_or(0.6 * size * text.chars().count() as f64, |f| {
        layout(f, size, text).1 as f64
    })
}

/// Paints `text` with its baseline anchor at `at`.
pub fn draw(px: &mut Pixmap, at: P2, size: f64, text: &str, anchor: Anchor, color: Rgb) {
    let Some(font) = font() else {
        return;
    };
    let (glyphs, advance) = layout(font, size, text);
    let x0 = at.0 as f32
        - match anchor {
            Anchor::Start => 0.0,
            Anchor::Middle => advance / 2.0,
            Anchor::End => advance,
        };
    let full = (0.0, 0.0, px.width as f64, px.height as f64);
    let s = scale(font, size);
    for (id, caret) in glyphs {
        let glyph = id.with_scale_and_position(s, point(x0 + caret, at.1 as f32));
        if let Some(outline) = font.outline_glyph(glyph) {
            let b = outline.px_bounds();
            let (bx, by) = (b.min.x as i64, b.min.y as i64);
            outline.draw(|x, y, c| {
                px.blend(bx + x as i64, by + y as i64, color, c as f64, full);
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shipped_font_loads_and_has_the_glyphs_labels_use() {
        let f = font().expect("DejaVuSans.ttf parses");
        for c in "Vxyz[in]0123456789⁻⁰¹²³⁴⁵⁶⁷⁸⁹−→·²λ".chars() {
            assert_ne!(f.glyph_id(c).0, 0, "{c:?} missing");
        }
    }

    #[test]
    fn text_is_painted_and_measured() {
        let mut px = Pixmap::new(120, 30);
        draw(
            &mut px,
            (60.0, 20.0),
            14.0,
            "V, in²",
            Anchor::Middle,
            [0, 0, 0],
        );
        let inked = px.rgb.chunks(3).filter(|c| c[0] < 128).count();
        assert!(inked > 30, "{inked}");
        let w = width("V, in²", 14.0);
        assert!(w > 30.0 && w < 60.0, "{w}");
        assert!(width("WWW", 12.0) > width("iii", 12.0));
    }
}
