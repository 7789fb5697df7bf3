//! Text for the figures: DejaVu Sans (a subset, committed under
//! `assets/` with its licence and embedded in the binary, so no system font
//! is needed), laid out with its advances and kerning and rasterised
//! anti-aliased with `ab_glyph`. The SVG writer ([`crate::svg`]) embeds the
//! same font, so a figure's text measures the same in PNG and SVG.
//!
//! Sizes are font sizes in pixels (the em height); positions are pixels of
//! the canvas, x to the right, y down, a pixel `(i, j)` covering
//! `[i, i+1] × [j, j+1]`.

use std::sync::OnceLock;

use ab_glyph::{point, Font, FontRef, GlyphId, PxScale, ScaleFont};

use crate::plot::{Canvas, Rgb};

/// The embedded font file (TrueType): DejaVu Sans 2.37, subset.
pub const FONT_TTF: &[u8] = include_bytes!("../assets/DejaVuSans-subset.ttf");
/// The font's family name as the SVG declares it.
pub const FONT_FAMILY: &str = "DejaVu Sans";

/// The embedded font, parsed once.
pub fn font() -> &'static FontRef<'static> {
    static FONT: OnceLock<FontRef<'static>> = OnceLock::new();
    // the font is a constant of the build, checked by a unit test
    FONT.get_or_init(|| FontRef::try_from_slice(FONT_TTF).expect("the embedded font parses"))
}

/// Where a text's x coordinate is: its start, its middle or its end
/// (SVG's `text-anchor`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Anchor {
    Start,
    Middle,
    End,
}

impl Anchor {
    /// The fraction of the text's width left of the anchor.
    pub fn fraction(self) -> f64 {
        match self {
            Anchor::Start => 0.0,
            Anchor::Middle => 0.5,
            Anchor::End => 1.0,
        }
    }

    /// SVG `text-anchor` value.
    pub fn svg(self) -> &'static str {
        match self {
            Anchor::Start => "start",
            Anchor::Middle => "middle",
            Anchor::End => "end",
        }
    }
}

/// `ab_glyph`'s scale for a font size of `size` [px, the em as in CSS's
/// `font-size`]: `ab_glyph` scales the ascent-to-descent height to the given
/// pixels, SVG the em.
fn px_scale(size: f64) -> PxScale {
    let f = font();
    let em = f.units_per_em().unwrap_or(2048.0);
    PxScale::from(size as f32 * f.height_unscaled() / em)
}

/// The glyphs of `s` at `size` [px]: (glyph, x offset from the start [px]),
/// and the advance of the whole line [px].
fn layout(s: &str, size: f64) -> (Vec<(GlyphId, f32)>, f32) {
    let f = font().as_scaled(px_scale(size));
    let mut caret = 0.0f32;
    let mut prev: Option<GlyphId> = None;
    let mut out = Vec::with_capacity(s.len());
    for ch in s.chars() {
        let id = f.glyph_id(ch);
        if let Some(p) = prev {
            caret += f.kern(p, id);
        }
        out.push((id, caret));
        caret += f.h_advance(id);
        prev = Some(id);
    }
    (out, caret)
}

/// Width of `s` at `size` \[px\]: the sum of its advances and kerning.
pub fn width(s: &str, size: f64) -> f64 {
    layout(s, size).1 as f64
}

/// Height of a capital letter above the baseline at `size` \[px\] (to centre
/// a line of text on a point: baseline at the point's y + cap height / 2).
pub fn cap_height(size: f64) -> f64 {
    let f = font();
    let id = f.glyph_id('H');
    let em = f.units_per_em().unwrap_or(2048.0);
    // an outline's bounds are in font units, y up: `min.y` is its top
    let units = f.outline(id).map_or(0.73 * em, |o| o.bounds.min.y);
    (units / em) as f64 * size
}

/// Draw `s` anti-aliased at `size` \[px\], its baseline at `y` and its anchor
/// at `x` \[px\]: each pixel a glyph covers is blended towards `col` by the
/// covered fraction.
pub fn draw(c: &mut Canvas, x: f64, y: f64, s: &str, col: Rgb, size: f64, anchor: Anchor) {
    let (glyphs, w) = layout(s, size);
    let x0 = x - anchor.fraction() * w as f64;
    let scale = px_scale(size);
    for (id, dx) in glyphs {
        let g = id.with_scale_and_position(scale, point(x0 as f32 + dx, y as f32));
        if let Some(outline) = font().outline_glyph(g) {
            let b = outline.px_bounds();
            outline.draw(|gx, gy, coverage| {
                let px = b.min.x as i64 + gx as i64;
                let py = b.min.y as i64 + gy as i64;
                c.blend(px, py, col, coverage);
            });
        }
    }
}

/// A tick value with as many decimals as the tick step needs.
pub fn tick_label(v: f64, step: f64) -> String {
    let decimals = if step > 0.0 && step.is_finite() {
        (-step.log10().floor()).max(0.0) as usize
    } else {
        0
    };
    let s = format!("{v:.decimals$}");
    // "-0" and "-0.00" are 0
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        s.trim_start_matches('-').to_string()
    } else {
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plot::{BLACK, WHITE};

    #[test]
    fn the_embedded_font_has_the_glyphs_of_the_labels() {
        let f = font();
        for ch in "0123456789 AZaz.,-+[]()/:=|%<>_µ°²‖−≤ρτ".chars() {
            assert_ne!(f.glyph_id(ch), GlyphId(0), "no glyph for {ch:?}");
        }
        assert_eq!(
            f.glyph_id('\u{4e00}'),
            GlyphId(0),
            "a CJK character is not in the subset"
        );
    }

    #[test]
    fn widths_grow_with_text_and_size_and_kerning_applies() {
        assert_eq!(width("", 16.0), 0.0);
        let w1 = width("1", 16.0);
        // DejaVu Sans digits advance 1303/2048 em
        assert!((w1 - 16.0 * 1303.0 / 2048.0).abs() < 0.01, "{w1}");
        assert!((width("11", 16.0) - 2.0 * w1).abs() < 1e-6);
        assert!((width("11", 32.0) - 2.0 * width("11", 16.0)).abs() < 1e-4);
        // "AV" is kerned tighter than its two advances
        assert!(width("AV", 16.0) < width("A", 16.0) + width("V", 16.0) - 0.5);
        let cap = cap_height(20.0);
        assert!((14.0..15.5).contains(&cap), "{cap}");
    }

    #[test]
    fn text_is_anti_aliased_and_anchored() {
        let mut c = Canvas::new(120, 40);
        draw(&mut c, 60.0, 25.0, "Hx [m]", BLACK, 16.0, Anchor::Middle);
        let greys: Vec<u8> = c.px.chunks(3).map(|p| p[0]).collect();
        let black = greys.iter().filter(|&&g| g < 40).count();
        let partial = greys.iter().filter(|&&g| (40..215).contains(&g)).count();
        assert!(black > 30, "{black} dark pixels");
        assert!(
            partial > 30,
            "{partial} intermediate pixels: not anti-aliased"
        );
        // centred on x = 60: ink on both sides, nothing near the edges
        let ink_cols: Vec<usize> = (0..120)
            .filter(|&x| (0..40).any(|y| c.get(x, y) != WHITE))
            .collect();
        let (lo, hi) = (ink_cols[0], *ink_cols.last().unwrap());
        assert!(lo > 5 && hi < 115, "{lo}..{hi}");
        let w = width("Hx [m]", 16.0);
        assert!(
            ((lo + hi) as f64 / 2.0 - 60.0).abs() < 3.0,
            "{lo}..{hi}, width {w}"
        );
        // 'H' stands on the baseline (y = 25): ink above it, none far below but the bracket's
        assert!((0..120).all(|x| (30..40).all(|y| c.get(x, y) == WHITE || x > 60)));
        // right-anchored text ends at its x
        let mut c = Canvas::new(120, 40);
        draw(&mut c, 100.0, 25.0, "10", BLACK, 16.0, Anchor::End);
        let last = (0..120)
            .filter(|&x| (0..40).any(|y| c.get(x, y) != WHITE))
            .max()
            .unwrap();
        assert!((97..=100).contains(&last), "{last}");
    }

    #[test]
    fn tick_labels_have_the_step_decimals() {
        assert_eq!(tick_label(0.30000000000000004, 0.1), "0.3");
        assert_eq!(tick_label(-0.0, 0.05), "0.00");
        assert_eq!(tick_label(12.0, 5.0), "12");
        assert_eq!(tick_label(-2.5, 0.5), "-2.5");
    }
}
