//! GIF animations of figures: one 256-colour palette for the whole animation: the marks' own
//! colours exactly (so that small marks such as sonar hits keep their colour), and the rest
//! learnt by `color_quant`'s NeuQuant from sample frames (anti-aliased edges, text); every
//! pixel then takes the nearest entry. Anti-aliased pictures have thousands of colours, so
//! exact per-frame palettes do not work. After the first frame, pixels that did not change are
//! written as the transparent entry [`TRANSPARENT`] over the kept previous frame: long runs of
//! one index, which LZW packs small.

use std::collections::HashMap;
use std::fs;
use std::io::BufWriter;
use std::path::Path;

use anyhow::{Context, Result};
use color_quant::NeuQuant;
use image::{Rgb, RgbImage};

/// The palette entry that means "as in the previous frame".
pub const TRANSPARENT: u8 = 255;

/// Writes frames of one size to a GIF file.
pub struct GifWriter {
    encoder: gif::Encoder<BufWriter<fs::File>>,
    palette: Vec<[u8; 3]>,
    cache: HashMap<[u8; 3], u8>,
    /// The previous frame: its bytes (as given) and its pixels' palette indices.
    previous: Option<(Vec<u8>, Vec<u8>)>,
    size: (u16, u16),
    path: String,
}

impl GifWriter {
    /// Create `path` for frames the size of `samples[0]`, with a palette learnt from `samples`
    /// (e.g. the first and the last frame) and `key_colors` (the marks' colours).
    pub fn create(path: &Path, samples: &[&RgbImage], key_colors: &[Rgb<u8>]) -> Result<Self> {
        let name = path.display().to_string();
        let first = samples
            .first()
            .with_context(|| format!("{name}: no frame to write"))?;
        let (w, h) = first.dimensions();
        let size = (
            u16::try_from(w).with_context(|| format!("{name}: frame wider than 65535 px"))?,
            u16::try_from(h).with_context(|| format!("{name}: frame taller than 65535 px"))?,
        );
        let mut palette: Vec<[u8; 3]> = Vec::new();
        for c in key_colors.iter().take(128) {
            if !palette.contains(&c.0) {
                palette.push(c.0);
            }
        }
        let mut rgba = Vec::new();
        for s in samples {
            for p in s.pixels() {
                rgba.extend_from_slice(&[p.0[0], p.0[1], p.0[2], 255]);
            }
        }
        // 255 entries for colours; the last one is TRANSPARENT.
        let learnt = NeuQuant::new(10, 255 - palette.len(), &rgba).color_map_rgb();
        palette.extend(learnt.chunks_exact(3).map(|c| [c[0], c[1], c[2]]));
        let mut flat: Vec<u8> = palette.concat();
        flat.resize(256 * 3, 0);
        let file = fs::File::create(path).with_context(|| format!("{name}: cannot create"))?;
        let mut encoder = gif::Encoder::new(BufWriter::new(file), size.0, size.1, &flat)
            .with_context(|| format!("{name}: cannot write GIF"))?;
        encoder
            .set_repeat(gif::Repeat::Infinite)
            .with_context(|| format!("{name}: cannot write GIF"))?;
        Ok(Self {
            encoder,
            palette,
            cache: HashMap::new(),
            previous: None,
            size,
            path: name,
        })
    }

    /// Palette index of a colour (nearest entry, remembered).
    fn index(&mut self, c: [u8; 3]) -> u8 {
        if let Some(i) = self.cache.get(&c) {
            return *i;
        }
        let mut best = (u32::MAX, 0u8);
        for (i, p) in self.palette.iter().enumerate() {
            let d: u32 = (0..3)
                .map(|k| (p[k] as i32 - c[k] as i32).unsigned_abs().pow(2))
                .sum();
            if d < best.0 {
                best = (d, i as u8);
            }
        }
        let i = best.1;
        self.cache.insert(c, i);
        i
    }

    /// Append a frame shown for `delay_cs` hundredths of a second. Frames of another size than
    /// the first are refused.
    pub fn add(&mut self, image: &RgbImage, delay_cs: u16) -> Result<()> {
        let (w, h) = image.dimensions();
        self.add_raw(image.as_raw(), 3, (w, h), delay_cs)
    }

    /// Append a figure as a frame (its pixels as they are, without a copy to RGB).
    pub fn add_figure(&mut self, figure: &super::Figure, delay_cs: u16) -> Result<()> {
        self.add_raw(figure.rgba(), 4, figure.size_px(), delay_cs)
    }

    /// Append a frame of `size` pixels, `bpp` bytes a pixel (RGB first).
    fn add_raw(&mut self, raw: &[u8], bpp: usize, size: (u32, u32), delay_cs: u16) -> Result<()> {
        let (w, h) = size;
        if (w, h) != (self.size.0 as u32, self.size.1 as u32)
            || raw.len() != w as usize * h as usize * bpp
        {
            anyhow::bail!(
                "{}: frame of {w}x{h} px in an animation of {}x{} px",
                self.path,
                self.size.0,
                self.size.1
            );
        }
        let row_bytes = w as usize * bpp;
        let mut frame = match self.previous.take() {
            Some((prev_raw, prev_indices)) if prev_raw.len() == raw.len() => {
                // Unchanged pixels keep their index (no palette search) and are sent as
                // TRANSPARENT.
                let mut indices = prev_indices;
                let mut changed = vec![TRANSPARENT; indices.len()];
                let rows = raw
                    .chunks_exact(row_bytes)
                    .zip(prev_raw.chunks_exact(row_bytes));
                for (y, (row, prev_row)) in rows.enumerate() {
                    // Whole rows compare as memory first: most rows do not change.
                    if row == prev_row {
                        continue;
                    }
                    let pixels = row.chunks_exact(bpp).zip(prev_row.chunks_exact(bpp));
                    for (x, (p, q)) in pixels.enumerate() {
                        if p != q {
                            let k = y * w as usize + x;
                            let i = self.index([p[0], p[1], p[2]]);
                            if i != indices[k] {
                                indices[k] = i;
                                changed[k] = i;
                            }
                        }
                    }
                }
                self.previous = Some((raw.to_vec(), indices));
                gif::Frame::from_indexed_pixels(
                    self.size.0,
                    self.size.1,
                    changed,
                    Some(TRANSPARENT),
                )
            }
            _ => {
                let indices: Vec<u8> = raw
                    .chunks_exact(bpp)
                    .map(|p| self.index([p[0], p[1], p[2]]))
                    .collect();
                self.previous = Some((raw.to_vec(), indices.clone()));
                gif::Frame::from_indexed_pixels(self.size.0, self.size.1, indices, None)
            }
        };
        frame.dispose = gif::DisposalMethod::Keep;
        frame.delay = delay_cs;
        self.encoder
            .write_frame(&frame)
            .with_context(|| format!("{}: cannot write GIF frame", self.path))
    }

    /// Write the GIF's trailer and flush the file.
    pub fn finish(self) -> Result<()> {
        let path = self.path;
        let mut out = self
            .encoder
            .into_inner()
            .with_context(|| format!("{path}: cannot finish the GIF"))?;
        std::io::Write::flush(&mut out).with_context(|| format!("{path}: cannot write"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn key_colours_survive_and_unchanged_pixels_are_transparent() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.gif");
        let red = Rgb([230, 20, 20]);
        // A gradient with one tiny red mark; the second frame adds another.
        let mut one = RgbImage::from_fn(64, 48, |x, y| Rgb([(x * 4) as u8, (y * 5) as u8, 128]));
        one.put_pixel(3, 3, red);
        let mut two = one.clone();
        two.put_pixel(40, 30, red);
        let mut w = GifWriter::create(&path, &[&one, &two], &[red]).unwrap();
        w.add(&one, 10).unwrap();
        w.add(&two, 10).unwrap();
        assert!(w.add(&RgbImage::new(10, 10), 10).is_err());
        w.finish().unwrap();
        let mut decoder = gif::DecodeOptions::new();
        decoder.set_color_output(gif::ColorOutput::RGBA);
        let mut d = decoder.read_info(fs::File::open(&path).unwrap()).unwrap();
        let px = |f: &gif::Frame, x: usize, y: usize| {
            let i = (y * 64 + x) * 4;
            f.buffer[i..i + 4].to_vec()
        };
        let f1 = d.read_next_frame().unwrap().unwrap().clone();
        assert_eq!(px(&f1, 3, 3), vec![230, 20, 20, 255]);
        assert!(
            f1.buffer.chunks(4).all(|p| p[3] == 255),
            "first frame is whole"
        );
        let f2 = d.read_next_frame().unwrap().unwrap().clone();
        assert_eq!(px(&f2, 40, 30), vec![230, 20, 20, 255]);
        assert_eq!(px(&f2, 3, 3)[3], 0, "unchanged: transparent");
        assert_eq!(f2.buffer.chunks(4).filter(|p| p[3] == 255).count(), 1);
        assert!(d.read_next_frame().unwrap().is_none());
    }
}
