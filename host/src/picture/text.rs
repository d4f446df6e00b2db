//! Text in the bundled DejaVu Sans (`host/assets/DejaVuSans.ttf`, its licence beside it),
//! laid out and rasterised with `ab_glyph` and blended onto the opaque picture.

use std::sync::OnceLock;

use ab_glyph::{point, Font, FontRef, GlyphId, PxScale, ScaleFont};
use image::Rgb;
use tiny_skia::{Pixmap, PremultipliedColorU8};

static FONT_BYTES: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");

/// The bundled font; `None` only if the bundled file were broken (a unit test checks it is not).
fn font() -> Option<&'static FontRef<'static>> {
    static FONT: OnceLock<Option<FontRef<'static>>> = OnceLock::new();
    FONT.get_or_init(|| FontRef::try_from_slice(FONT_BYTES).ok())
        .as_ref()
}

/// Glyph ids and their left edges (pixels from the text's start) of `text` at `size_px`, and
/// the text's whole advance width.
fn layout(text: &str, size_px: f32) -> (Vec<(GlyphId, f32)>, f32) {
    let Some(font) = font() else {
        return (Vec::new(), 0.0);
    };
    let scaled = font.as_scaled(PxScale::from(size_px));
    let mut caret = 0.0f32;
    let mut prev: Option<GlyphId> = None;
    let mut glyphs = Vec::with_capacity(text.len());
    for c in text.chars() {
        let id = font.glyph_id(c);
        if let Some(p) = prev {
            caret += scaled.kern(p, id);
        }
        glyphs.push((id, caret));
        caret += scaled.h_advance(id);
        prev = Some(id);
    }
    (glyphs, caret)
}

/// Width of `text` at `size_px` pixels, pixels.
pub fn width_px(text: &str, size_px: f32) -> f32 {
    layout(text, size_px).1
}

/// Height of a line of text at `size_px` (ascent + descent + a small gap), pixels.
pub fn line_height_px(size_px: f32) -> f32 {
    match font() {
        Some(f) => {
            let s = f.as_scaled(PxScale::from(size_px));
            (s.ascent() - s.descent() + s.line_gap()).ceil() + 2.0
        }
        None => size_px * 1.3,
    }
}

/// Draw `text` with the top of its line box at (`x_px`, `y_px`), `size_px` pixels high, in
/// `color`. Coverage is blended over what is there (the picture is opaque); pixels off the
/// picture are skipped, so no input can panic.
pub fn draw(pixmap: &mut Pixmap, x_px: f32, y_px: f32, text: &str, size_px: f32, color: Rgb<u8>) {
    let Some(font) = font() else {
        return;
    };
    if !(x_px.is_finite() && y_px.is_finite() && size_px.is_finite() && size_px > 0.0) {
        return;
    }
    let scale = PxScale::from(size_px.min(400.0));
    let baseline = y_px + font.as_scaled(scale).ascent();
    let (w, h) = (pixmap.width() as i64, pixmap.height() as i64);
    let pixels = pixmap.pixels_mut();
    for (id, dx) in layout(text, scale.y).0 {
        let glyph = id.with_scale_and_position(scale, point(x_px + dx, baseline));
        let Some(outline) = font.outline_glyph(glyph) else {
            continue;
        };
        let bounds = outline.px_bounds();
        outline.draw(|gx, gy, coverage| {
            let x = bounds.min.x as i64 + gx as i64;
            let y = bounds.min.y as i64 + gy as i64;
            if x < 0 || y < 0 || x >= w || y >= h {
                return;
            }
            let a = coverage.clamp(0.0, 1.0);
            let p = &mut pixels[(y * w + x) as usize];
            let mix = |d: u8, s: u8| (d as f32 * (1.0 - a) + s as f32 * a).round() as u8;
            let (r, g, b) = (
                mix(p.red(), color.0[0]),
                mix(p.green(), color.0[1]),
                mix(p.blue(), color.0[2]),
            );
            if let Some(c) = PremultipliedColorU8::from_rgba(r, g, b, 255) {
                *p = c;
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bundled_font_loads_and_measures() {
        assert!(font().is_some());
        let w1 = width_px("1 m", 14.0);
        assert!(w1 > 14.0 && w1 < 40.0, "{w1}");
        assert!((width_px("abc", 28.0) - 2.0 * width_px("abc", 14.0)).abs() < 1.5);
        assert!(line_height_px(14.0) >= 16.0);
    }

    #[test]
    fn text_is_drawn_where_asked_and_nowhere_else() {
        let mut p = Pixmap::new(100, 40).unwrap();
        p.fill(tiny_skia::Color::WHITE);
        draw(&mut p, 10.0, 5.0, "Hg", 20.0, Rgb([0, 0, 0]));
        let dark: Vec<(u32, u32)> = (0..40u32)
            .flat_map(|y| (0..100u32).map(move |x| (x, y)))
            .filter(|&(x, y)| p.pixel(x, y).unwrap().red() < 128)
            .collect();
        assert!(dark.len() > 30);
        assert!(dark
            .iter()
            .all(|&(x, y)| (10..40).contains(&x) && (5..35).contains(&y)));
        // Off the picture or absurd: nothing, no panic.
        draw(&mut p, -1.0e30, f32::NAN, "x", 1.0e9, Rgb([0, 0, 0]));
        draw(&mut p, 95.0, 35.0, "WWWW", 30.0, Rgb([0, 0, 0]));
    }
}
