//! The one font pictures use: DejaVu Sans 2.37, compiled in
//! (`host-sim/assets/DejaVuSans.ttf`, Bitstream Vera license with DejaVu's
//! public-domain changes: `assets/LICENSE-DejaVu.txt`).
//!
//! Text is laid out here on one baseline with the font's advances and kerning
//! ([`width`] measures it); [`super::canvas::Pixmap::draw_text`] rasterises the
//! laid-out glyphs with `ab_glyph` (coverage anti-aliasing). Nothing depends on
//! the machine's fonts, so a PNG is the same everywhere. Sizes are CSS font
//! sizes (the em in pixels), as in the SVG. This module knows nothing of
//! pixmaps or shapes.

use std::sync::OnceLock;

use ab_glyph::{Font, FontRef, GlyphId, PxScale, ScaleFont};

/// The TTF file, as shipped.
pub static DEJAVU_SANS: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");

/// The parsed font (`None` only if the shipped file were broken, which a test rules out).
pub fn font() -> Option<&'static FontRef<'static>> {
    static FONT: OnceLock<Option<FontRef<'static>>> = OnceLock::new();
    FONT.get_or_init(|| FontRef::try_from_slice(DEJAVU_SANS).ok())
        .as_ref()
}

/// `ab_glyph`'s scale (ascent to descent) for a CSS font size.
pub(super) fn scale(font: &FontRef<'_>, size: f64) -> PxScale {
    let em = font.units_per_em().unwrap_or(2048.0);
    PxScale::from(size as f32 * font.height_unscaled() / em)
}

/// Glyphs of `text` with their caret positions, and the total advance.
pub(super) fn layout(font: &FontRef<'static>, size: f64, text: &str) -> (Vec<(GlyphId, f32)>, f32) {
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
}
