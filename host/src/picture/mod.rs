//! Every `twil` picture (plan, simulate and mission PNGs and GIFs, cspace PNG and GIF) is a
//! [`Figure`] drawn by this module: anti-aliased shapes from `tiny-skia`, text in the bundled
//! DejaVu Sans through `ab_glyph` ([`text`]), GIFs through [`animation`]. Why these crates:
//! `docs/pictures.md`.
//!
//! A figure is laid out once from a [`FigureSpec`]:
//!
//! ```text
//! caption lines (wrapped to the width)
//! ┌ panel title ─────────────┐ ┌ panel 2 … ┐
//! y (m)                       
//!  4 ┤ plot area (data units, │
//!  2 ┤ y up, clipped)         │
//!  0 ┼──┬──┬──┬──┬──┬──┬──┬──┘
//!    0  2  4  6  8 …
//! ▬▬▬ 1 m         x (m)
//! legend: swatch + label for every mark, in as many columns as fit
//! ```
//!
//! Each panel maps data units to pixels with its own scale (`px_per_x`, `px_per_y`), draws
//! axis ticks at 1-2-5 steps with labels, and a scale bar of a 1-2-5 length under the plot.
//! [`Figure::plot`] gives a [`Plot`] that draws in data units, clipped to the plot area.
//! Nothing here panics: non-finite coordinates draw nothing and sizes are bounded.

pub mod animation;
mod plot;
mod style;
pub mod text;

pub use plot::Plot;
pub use style::{over_white, palette, LegendEntry, Mark, Marker, BAND_ALPHA, REAL_ALPHA};

use image::{Rgb, RgbImage};
use tiny_skia::{
    FillRule, LineCap, LineJoin, Mask, Paint, PathBuilder, Pixmap, PremultipliedColorU8, Rect,
    Stroke, Transform,
};
use twil_core::grid::GridGeometry;

/// Largest accepted picture side, pixels.
pub const MAX_SIDE_PX: u32 = 8192;
/// Caption text size, pixels.
pub const CAPTION_PX: f32 = 15.0;
/// Tick, axis and legend text size, pixels.
pub const LABEL_PX: f32 = 13.0;
/// Thickness of the scale bar, pixels.
pub const SCALE_BAR_THICKNESS_PX: i32 = 5;
/// Side of a legend swatch, pixels.
pub const SWATCH_PX: i32 = 16;
/// Narrowest figure, pixels: small maps get room for a readable legend and caption.
pub const MIN_WIDTH_PX: u32 = 520;

const PAD: i32 = 8;
const TICK_PX: i32 = 5;
const PANEL_GAP: i32 = 24;

/// Why a figure could not be made.
#[derive(Debug, thiserror::Error)]
pub enum PictureError {
    /// The layout would exceed [`MAX_SIDE_PX`] on a side, or a scale is not positive.
    #[error("picture of {width_px}x{height_px} px is not possible (at most {MAX_SIDE_PX} px a side, positive scales)")]
    Size {
        /// Width asked for.
        width_px: f64,
        /// Height asked for.
        height_px: f64,
    },
    /// Writing a file failed.
    #[error("{path}: cannot write the picture: {error}")]
    Save {
        /// The file.
        path: String,
        /// Why.
        error: String,
    },
}

/// One axis of a panel.
#[derive(Clone, Debug, PartialEq)]
pub struct Axis {
    /// Data value at the left (x) or bottom (y) edge of the plot.
    pub min: f32,
    /// Data value at the right (x) or top (y) edge.
    pub max: f32,
    /// Pixels per data unit.
    pub px_per_unit: f32,
    /// The axis title with its unit, e.g. `x (m)`.
    pub title: String,
}

/// One plot of a figure.
#[derive(Clone, Debug, PartialEq)]
pub struct PanelSpec {
    /// Horizontal axis.
    pub x: Axis,
    /// Vertical axis (data y up).
    pub y: Axis,
    /// Unit of the scale bar (along x), e.g. `m`.
    pub unit: String,
    /// A title above the plot, if any.
    pub title: Option<String>,
}

impl PanelSpec {
    /// A map of `geometry` (origin at its lower-left corner) at `px_per_cell`, in metres.
    pub fn map(geometry: GridGeometry, px_per_cell: u32, title: Option<String>) -> Self {
        let px_per_m = px_per_cell as f32 / geometry.resolution_m();
        Self {
            x: Axis {
                min: 0.0,
                max: geometry.width_m(),
                px_per_unit: px_per_m,
                title: "x (m)".into(),
            },
            y: Axis {
                min: 0.0,
                max: geometry.height_m(),
                px_per_unit: px_per_m,
                title: "y (m)".into(),
            },
            unit: "m".into(),
            title,
        }
    }
}

/// Pixels per cell that make the longer side of `geometry` about `target_px` (1 to 16).
pub fn fit_px_per_cell(geometry: GridGeometry, target_px: u32) -> u32 {
    let side = geometry.width().max(geometry.height()).max(1) as u32;
    (target_px / side).clamp(1, 16)
}

/// World points as data points of a map panel.
pub fn points(points: &[twil_core::geom::PointM]) -> Vec<(f32, f32)> {
    points.iter().map(|p| (p.x_m, p.y_m)).collect()
}

/// `polygon` (3 or more vertices) holds one of `inside` (the start, the goal) strictly inside
/// it (even-odd rule): a room drawn as one enclosing outline. Only a `.da` polygon's edges are
/// obstacles (docs/formats.md#da), so its inside is floor: pictures draw such a polygon's
/// outline and no fill, which would paint the whole room as an obstacle.
pub fn encloses(polygon: &[twil_core::geom::PointM], inside: &[twil_core::geom::PointM]) -> bool {
    polygon.len() >= 3
        && inside.iter().any(|p| {
            let mut odd = false;
            let mut j = polygon.len() - 1;
            for (i, a) in polygon.iter().enumerate() {
                let b = polygon[j];
                if (a.y_m > p.y_m) != (b.y_m > p.y_m)
                    && p.x_m < (b.x_m - a.x_m) * (p.y_m - a.y_m) / (b.y_m - a.y_m) + a.x_m
                {
                    odd = !odd;
                }
                j = i;
            }
            odd
        })
}

/// What a figure shows around its plots.
#[derive(Clone, Debug, PartialEq)]
pub struct FigureSpec {
    /// Caption lines above the plots (wrapped to the figure's width).
    pub caption: Vec<String>,
    /// Exactly this many caption lines after wrapping (blank lines added, extra lines cut),
    /// so that the frames of an animation keep one size; `None`: as many as the text needs.
    pub caption_lines: Option<usize>,
    /// Plots, side by side.
    pub panels: Vec<PanelSpec>,
    /// At most this many panels on a row, further panels on rows below (`None`: one row).
    pub panels_per_row: Option<usize>,
    /// Legend entries, below the plots.
    pub legend: Vec<LegendEntry>,
}

/// A rectangle of pixels, `[x0, x1) × [y0, y1)` from the picture's top-left corner.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PxRect {
    /// Left.
    pub x0: i32,
    /// Top.
    pub y0: i32,
    /// Right (exclusive).
    pub x1: i32,
    /// Bottom (exclusive).
    pub y1: i32,
}

impl PxRect {
    /// Does it hold the pixel?
    pub fn contains(&self, x: i32, y: i32) -> bool {
        x >= self.x0 && x < self.x1 && y >= self.y0 && y < self.y1
    }
}

/// Where a scale bar was drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScaleBar {
    /// The bar's pixels (filled with [`palette::SCALE_BAR`]).
    pub rect: PxRect,
    /// Its length in data units.
    pub length: f32,
}

#[derive(Clone, Debug)]
struct PanelLayout {
    spec: PanelSpec,
    plot: PxRect,
    scale_bar: ScaleBar,
}

/// A laid-out picture: see the module documentation.
pub struct Figure {
    pixmap: Pixmap,
    panels: Vec<PanelLayout>,
    legend_box: PxRect,
    legend_swatches: Vec<PxRect>,
    masks: Vec<Mask>,
}

/// A length of 1, 2 or 5 × 10^k near `target`.
fn nice(target: f32) -> f32 {
    if !(target.is_finite() && target > 0.0) {
        return 1.0;
    }
    let p = 10f32.powf(target.log10().floor());
    let m = target / p;
    let f = if m < 1.5 {
        1.0
    } else if m < 3.5 {
        2.0
    } else if m < 7.5 {
        5.0
    } else {
        10.0
    };
    f * p
}

/// A tick label: as many decimals as the step needs.
fn tick_label(v: f32, step: f32) -> String {
    let decimals = if step >= 1.0 {
        0
    } else {
        (-step.log10().floor()) as usize
    };
    let s = format!("{v:.decimals$}");
    if s.starts_with('-') && s.trim_start_matches(['-', '0', '.']).is_empty() {
        s[1..].to_string()
    } else {
        s
    }
}

/// Ticks of an axis: values and their offsets from the axis's `min` edge, pixels.
fn ticks(axis: &Axis, min_spacing_px: f32) -> (f32, Vec<(f32, f32)>) {
    let step = nice(min_spacing_px / axis.px_per_unit);
    let step = if step * axis.px_per_unit < min_spacing_px * 0.75 {
        step * 2.0
    } else {
        step
    };
    let mut out = Vec::new();
    let first = (axis.min / step).ceil();
    for k in 0..200 {
        let v = (first + k as f32) * step;
        if v > axis.max + step * 1e-3 {
            break;
        }
        out.push((v, (v - axis.min) * axis.px_per_unit));
    }
    (step, out)
}

/// The scale bar's length in data units: one unit when that is 36 to 240 px long, else the
/// shortest 1-2-5 length of at least 36 px.
pub fn scale_bar_length(px_per_unit: f32) -> f32 {
    if (36.0..=240.0).contains(&px_per_unit) {
        return 1.0;
    }
    let mut l = nice(36.0 / px_per_unit);
    for _ in 0..3 {
        if l * px_per_unit >= 36.0 {
            break;
        }
        l = nice(l * 2.2);
    }
    l
}

fn wrap(text: &str, size_px: f32, width_px: f32) -> Vec<String> {
    let mut lines = Vec::new();
    let mut line = String::new();
    for word in text.split(' ') {
        let candidate = if line.is_empty() {
            word.to_string()
        } else {
            format!("{line} {word}")
        };
        if !line.is_empty() && text::width_px(&candidate, size_px) > width_px {
            lines.push(std::mem::take(&mut line));
            line = word.to_string();
        } else {
            line = candidate;
        }
    }
    lines.push(line);
    lines
}

fn color(c: Rgb<u8>, alpha: f32) -> tiny_skia::Color {
    tiny_skia::Color::from_rgba8(
        c.0[0],
        c.0[1],
        c.0[2],
        (alpha.clamp(0.0, 1.0) * 255.0) as u8,
    )
}

fn paint(c: Rgb<u8>, alpha: f32) -> Paint<'static> {
    let mut p = Paint::default();
    p.set_color(color(c, alpha));
    p.anti_alias = true;
    p
}

fn solid(c: Rgb<u8>) -> PremultipliedColorU8 {
    PremultipliedColorU8::from_rgba(c.0[0], c.0[1], c.0[2], 255)
        .unwrap_or(PremultipliedColorU8::TRANSPARENT)
}

/// Coordinates beyond this many pixels are not drawn (keeps the rasteriser's work bounded).
const FAR_PX: f32 = 1.0e5;

impl Figure {
    /// Lay out and draw everything but the data: caption, axes, ticks, scale bars, legend.
    pub fn new(spec: &FigureSpec) -> Result<Self, PictureError> {
        let label_h = text::line_height_px(LABEL_PX) as i32;
        let caption_h = text::line_height_px(CAPTION_PX) as i32;
        // Panel blocks: widths and heights.
        struct Block {
            gutter: i32,
            plot_w: i32,
            plot_h: i32,
            right: i32,
        }
        let mut blocks = Vec::new();
        for p in &spec.panels {
            let ok = |a: &Axis| {
                a.px_per_unit.is_finite()
                    && a.px_per_unit > 0.0
                    && a.min.is_finite()
                    && a.max.is_finite()
                    && a.max > a.min
            };
            let (w, h) = (
                (p.x.max - p.x.min) as f64 * p.x.px_per_unit as f64,
                (p.y.max - p.y.min) as f64 * p.y.px_per_unit as f64,
            );
            if !ok(&p.x) || !ok(&p.y) || w > MAX_SIDE_PX as f64 || h > MAX_SIDE_PX as f64 {
                return Err(PictureError::Size {
                    width_px: w,
                    height_px: h,
                });
            }
            let (ystep, yt) = ticks(&p.y, 60.0);
            let gutter = yt
                .iter()
                .map(|(v, _)| text::width_px(&tick_label(*v, ystep), LABEL_PX) as i32)
                .max()
                .unwrap_or(0)
                .max(text::width_px(&p.y.title, LABEL_PX) as i32 / 2)
                + TICK_PX
                + 4;
            let (xstep, xt) = ticks(&p.x, 60.0);
            let right = xt
                .last()
                .map(|(v, _)| text::width_px(&tick_label(*v, xstep), LABEL_PX) as i32 / 2 + 2)
                .unwrap_or(0)
                .max(6);
            blocks.push(Block {
                gutter,
                plot_w: w.round() as i32,
                plot_h: h.round() as i32,
                right,
            });
        }
        let per_row = spec.panels_per_row.unwrap_or(blocks.len()).max(1);
        let row_w = |row: &[Block]| {
            row.iter()
                .map(|b| b.gutter + b.plot_w + b.right)
                .sum::<i32>()
                + PANEL_GAP * (row.len() as i32 - 1).max(0)
        };
        let panels_w: i32 = blocks.chunks(per_row).map(row_w).max().unwrap_or(0);
        let width = (panels_w + 2 * PAD).max(MIN_WIDTH_PX as i32);
        let inner_w = (width - 2 * PAD) as f32;
        // Caption.
        let mut caption: Vec<String> = spec
            .caption
            .iter()
            .flat_map(|l| wrap(l, CAPTION_PX, inner_w))
            .collect();
        if let Some(n) = spec.caption_lines {
            caption.resize(n.min(64), String::new());
        }
        let caption_top = PAD;
        let panels_top = caption_top + caption.len() as i32 * caption_h + 4;
        // Room for the y title above the top tick label, which reaches half a line above the plot.
        let header_h = label_h + label_h / 2 + 2;
        let below_plot = TICK_PX + label_h + label_h + 6;
        // Each row of panels is as tall as its tallest plot.
        let row_h: Vec<i32> = blocks
            .chunks(per_row)
            .map(|row| header_h + row.iter().map(|b| b.plot_h).max().unwrap_or(0) + below_plot)
            .collect();
        let legend_top = panels_top + row_h.iter().sum::<i32>() + 4;
        // Legend grid.
        let entry_w = spec
            .legend
            .iter()
            .map(|e| SWATCH_PX + 6 + text::width_px(&e.label, LABEL_PX).ceil() as i32 + 14)
            .max()
            .unwrap_or(1);
        let cols = ((inner_w as i32 - 8) / entry_w).clamp(1, spec.legend.len().max(1) as i32);
        let rows = (spec.legend.len() as i32 + cols - 1) / cols;
        let entry_h = label_h.max(SWATCH_PX + 4);
        let legend_h = if spec.legend.is_empty() {
            0
        } else {
            rows * entry_h + 10
        };
        let height = legend_top + legend_h + PAD;
        if width as u32 > MAX_SIDE_PX || height as u32 > MAX_SIDE_PX {
            return Err(PictureError::Size {
                width_px: width as f64,
                height_px: height as f64,
            });
        }
        let mut pixmap = Pixmap::new(width as u32, height as u32).ok_or(PictureError::Size {
            width_px: width as f64,
            height_px: height as f64,
        })?;
        pixmap.fill(tiny_skia::Color::WHITE);
        let mut fig = Figure {
            pixmap,
            panels: Vec::new(),
            legend_box: PxRect {
                x0: PAD,
                y0: legend_top,
                x1: width - PAD,
                y1: legend_top + legend_h,
            },
            legend_swatches: Vec::new(),
            masks: Vec::new(),
        };
        for (i, line) in caption.iter().enumerate() {
            fig.text(
                PAD as f32,
                (caption_top + i as i32 * caption_h) as f32,
                line,
                CAPTION_PX,
                palette::TEXT,
            );
        }
        // Panels, row by row, each row centred.
        let mut x = 0;
        let mut top = panels_top;
        for (i, (p, b)) in spec.panels.iter().zip(&blocks).enumerate() {
            if i % per_row == 0 {
                let row = &blocks[i..(i + per_row).min(blocks.len())];
                x = PAD + (width - 2 * PAD - row_w(row)) / 2;
                if i > 0 {
                    top += row_h[i / per_row - 1];
                }
            }
            let plot = PxRect {
                x0: x + b.gutter,
                y0: top + header_h,
                x1: x + b.gutter + b.plot_w,
                y1: top + header_h + b.plot_h,
            };
            let scale_bar = fig.draw_axes(p, plot, header_h, label_h);
            let mut mask = Mask::new(width as u32, height as u32).ok_or(PictureError::Size {
                width_px: width as f64,
                height_px: height as f64,
            })?;
            if let Some(r) = Rect::from_ltrb(
                plot.x0 as f32,
                plot.y0 as f32,
                plot.x1 as f32,
                plot.y1 as f32,
            ) {
                mask.fill_path(
                    &PathBuilder::from_rect(r),
                    FillRule::Winding,
                    false,
                    Transform::identity(),
                );
            }
            fig.masks.push(mask);
            fig.panels.push(PanelLayout {
                spec: p.clone(),
                plot,
                scale_bar,
            });
            x += b.gutter + b.plot_w + b.right + PANEL_GAP;
        }
        // Legend.
        if !spec.legend.is_empty() {
            let lb = fig.legend_box;
            fig.stroke_px_rect(lb, palette::LEGEND_BORDER);
            let total_w = cols * entry_w;
            let x0 = lb.x0 + ((lb.x1 - lb.x0) - total_w).max(0) / 2;
            for (i, e) in spec.legend.iter().enumerate() {
                let (c, r) = (i as i32 % cols, i as i32 / cols);
                let sx = x0 + c * entry_w + 4;
                let sy = lb.y0 + 5 + r * entry_h + (entry_h - SWATCH_PX) / 2;
                let sw = PxRect {
                    x0: sx,
                    y0: sy,
                    x1: sx + SWATCH_PX,
                    y1: sy + SWATCH_PX,
                };
                fig.swatch(sw, e.mark);
                fig.legend_swatches.push(sw);
                let ty = lb.y0 + 5 + r * entry_h + (entry_h - label_h) / 2;
                fig.text(
                    (sx + SWATCH_PX + 6) as f32,
                    ty as f32,
                    &e.label,
                    LABEL_PX,
                    palette::TEXT,
                );
            }
        }
        Ok(fig)
    }

    /// Axes, ticks, tick labels, titles and the scale bar of one panel; returns the bar.
    fn draw_axes(&mut self, p: &PanelSpec, plot: PxRect, header_h: i32, label_h: i32) -> ScaleBar {
        let (xstep, xt) = ticks(&p.x, 60.0);
        let (ystep, yt) = ticks(&p.y, 60.0);
        // Faint lines at the ticks, under the data.
        for (_, off) in &xt {
            let x = plot.x0 + off.round() as i32;
            self.fill_px(x, plot.y0, x + 1, plot.y1, palette::GRID_LINES);
        }
        for (_, off) in &yt {
            let y = plot.y1 - 1 - off.round() as i32;
            self.fill_px(plot.x0, y, plot.x1, y + 1, palette::GRID_LINES);
        }
        // Axis lines and ticks, outside the plot.
        self.fill_px(plot.x0 - 1, plot.y0, plot.x0, plot.y1 + 1, palette::AXIS);
        self.fill_px(plot.x0 - 1, plot.y1, plot.x1, plot.y1 + 1, palette::AXIS);
        for (v, off) in &xt {
            let x = (plot.x0 + off.round() as i32).min(plot.x1 - 1);
            self.fill_px(x, plot.y1, x + 1, plot.y1 + TICK_PX, palette::AXIS);
            let s = tick_label(*v, xstep);
            let w = text::width_px(&s, LABEL_PX);
            self.text(
                x as f32 - w / 2.0,
                (plot.y1 + TICK_PX) as f32,
                &s,
                LABEL_PX,
                palette::TEXT,
            );
        }
        for (v, off) in &yt {
            let y = (plot.y1 - 1 - off.round() as i32).max(plot.y0);
            self.fill_px(plot.x0 - 1 - TICK_PX, y, plot.x0 - 1, y + 1, palette::AXIS);
            let s = tick_label(*v, ystep);
            let w = text::width_px(&s, LABEL_PX);
            self.text(
                plot.x0 as f32 - 3.0 - TICK_PX as f32 - w,
                y as f32 - label_h as f32 / 2.0,
                &s,
                LABEL_PX,
                palette::TEXT,
            );
        }
        // Header: y title at the left, panel title right-aligned.
        let header_y = (plot.y0 - header_h) as f32;
        let yw = text::width_px(&p.y.title, LABEL_PX);
        self.text(
            (plot.x0 as f32 - yw / 2.0).max(0.0),
            header_y,
            &p.y.title,
            LABEL_PX,
            palette::TEXT,
        );
        if let Some(title) = &p.title {
            let w = text::width_px(title, LABEL_PX);
            self.text(plot.x1 as f32 - w, header_y, title, LABEL_PX, palette::TEXT);
        }
        // Row under the tick labels: scale bar at the left, x title centred.
        let row_y = plot.y1 + TICK_PX + label_h + 2;
        let length = scale_bar_length(p.x.px_per_unit);
        let bar_px = (length * p.x.px_per_unit).round() as i32;
        let bar = PxRect {
            x0: plot.x0,
            y0: row_y + (label_h - SCALE_BAR_THICKNESS_PX) / 2,
            x1: plot.x0 + bar_px,
            y1: row_y + (label_h - SCALE_BAR_THICKNESS_PX) / 2 + SCALE_BAR_THICKNESS_PX,
        };
        self.fill_px(bar.x0, bar.y0, bar.x1, bar.y1, palette::SCALE_BAR);
        let unit_sep = if p.unit.starts_with('°') { "" } else { " " };
        let label = format!("{}{unit_sep}{}", tick_label(length, length), p.unit);
        self.text(
            (bar.x1 + 5) as f32,
            row_y as f32,
            &label,
            LABEL_PX,
            palette::TEXT,
        );
        let tw = text::width_px(&p.x.title, LABEL_PX);
        let centre = (plot.x0 + plot.x1) as f32 / 2.0 - tw / 2.0;
        let after_bar = (bar.x1 + 5) as f32 + text::width_px(&label, LABEL_PX) + 12.0;
        self.text(
            centre.max(after_bar),
            row_y as f32,
            &p.x.title,
            LABEL_PX,
            palette::TEXT,
        );
        ScaleBar { rect: bar, length }
    }

    fn swatch(&mut self, r: PxRect, mark: Mark) {
        let (cx, cy) = ((r.x0 + r.x1) as f32 / 2.0, (r.y0 + r.y1) as f32 / 2.0);
        let half = (r.x1 - r.x0) as f32 / 2.0;
        match mark {
            Mark::Fill(c) => self.fill_px(r.x0, r.y0, r.x1, r.y1, c),
            Mark::FillOutline(c, o) => {
                self.fill_px(r.x0, r.y0, r.x1, r.y1, c);
                self.stroke_px_rect(r, o);
            }
            Mark::Outline(c) => {
                self.stroke_px_rect(r, c);
                let inner = PxRect {
                    x0: r.x0 + 1,
                    y0: r.y0 + 1,
                    x1: r.x1 - 1,
                    y1: r.y1 - 1,
                };
                self.stroke_px_rect(inner, c);
            }
            Mark::Line(c, w) => {
                let t = (w.round() as i32).clamp(1, r.y1 - r.y0);
                let y0 = r.y0 + (r.y1 - r.y0 - t) / 2;
                self.fill_px(r.x0 - 2, y0, r.x1 + 2, y0 + t, c);
            }
            Mark::Marker(m, c) => self.marker_px(cx, cy, m, half * 1.6, c, None),
            Mark::Dots(c) => {
                for (dx, dy) in [(-4.0, 3.0), (0.0, -3.0), (4.0, 2.0)] {
                    self.disc_px(cx + dx, cy + dy, 2.2, c, 1.0, None);
                }
                // One exact pixel block in the middle, so the colour is certain to show.
                self.fill_px(cx as i32, cy as i32 - 3, cx as i32 + 1, cy as i32 - 2, c);
            }
            Mark::Ring(c) => {
                self.circle_px(cx, cy, half - 1.5, c, 2.0, None);
                self.fill_px(r.x0, cy as i32, r.x0 + 2, cy as i32 + 1, c);
            }
            Mark::Robot(c) => {
                self.disc_px(cx, cy, half - 1.0, c, 0.35, None);
                self.circle_px(cx, cy, half - 1.0, c, 2.0, None);
                self.line_px(&[(cx, cy), (cx + half - 1.0, cy)], c, 2.0, 1.0, None);
                self.fill_px(cx as i32, cy as i32, cx as i32 + 4, cy as i32 + 1, c);
            }
        }
    }

    // ----- geometry in pixels -----

    fn fill_px(&mut self, x0: i32, y0: i32, x1: i32, y1: i32, c: Rgb<u8>) {
        self.blend_px(x0, y0, x1, y1, c, 1.0, None);
    }

    /// Fill a pixel rectangle with `c` at `alpha`, limited to `clip` when given.
    #[allow(clippy::too_many_arguments)]
    fn blend_px(
        &mut self,
        x0: i32,
        y0: i32,
        x1: i32,
        y1: i32,
        c: Rgb<u8>,
        alpha: f32,
        clip: Option<PxRect>,
    ) {
        let (w, h) = (self.pixmap.width() as i32, self.pixmap.height() as i32);
        let bounds = clip.unwrap_or(PxRect {
            x0: 0,
            y0: 0,
            x1: w,
            y1: h,
        });
        let (x0, x1) = (x0.max(bounds.x0).max(0), x1.min(bounds.x1).min(w));
        let (y0, y1) = (y0.max(bounds.y0).max(0), y1.min(bounds.y1).min(h));
        if x0 >= x1 || y0 >= y1 {
            return;
        }
        let a = alpha.clamp(0.0, 1.0);
        let full = solid(c);
        let pixels = self.pixmap.pixels_mut();
        for y in y0..y1 {
            let row = &mut pixels[(y * w + x0) as usize..(y * w + x1) as usize];
            if a >= 1.0 {
                row.fill(full);
            } else {
                for p in row {
                    let mix = |d: u8, s: u8| (d as f32 * (1.0 - a) + s as f32 * a).round() as u8;
                    let m = Rgb([
                        mix(p.red(), c.0[0]),
                        mix(p.green(), c.0[1]),
                        mix(p.blue(), c.0[2]),
                    ]);
                    *p = solid(m);
                }
            }
        }
    }

    fn stroke_px_rect(&mut self, r: PxRect, c: Rgb<u8>) {
        self.fill_px(r.x0, r.y0, r.x1, r.y0 + 1, c);
        self.fill_px(r.x0, r.y1 - 1, r.x1, r.y1, c);
        self.fill_px(r.x0, r.y0, r.x0 + 1, r.y1, c);
        self.fill_px(r.x1 - 1, r.y0, r.x1, r.y1, c);
    }

    fn text(&mut self, x: f32, y: f32, s: &str, size: f32, c: Rgb<u8>) {
        text::draw(&mut self.pixmap, x, y, s, size, c);
    }

    fn fill_path_px(&mut self, pb: PathBuilder, c: Rgb<u8>, alpha: f32, panel: Option<usize>) {
        if let Some(path) = pb.finish() {
            let paint = paint(c, alpha);
            let mask = panel.and_then(|i| self.masks.get(i));
            self.pixmap.fill_path(
                &path,
                &paint,
                FillRule::EvenOdd,
                Transform::identity(),
                mask,
            );
        }
    }

    fn stroke_path_px(
        &mut self,
        pb: PathBuilder,
        c: Rgb<u8>,
        width: f32,
        alpha: f32,
        panel: Option<usize>,
    ) {
        if !(width.is_finite() && width > 0.0) {
            return;
        }
        if let Some(path) = pb.finish() {
            let paint = paint(c, alpha);
            let stroke = Stroke {
                width: width.min(200.0),
                line_cap: LineCap::Round,
                line_join: LineJoin::Round,
                ..Stroke::default()
            };
            let mask = panel.and_then(|i| self.masks.get(i));
            self.pixmap
                .stroke_path(&path, &paint, &stroke, Transform::identity(), mask);
        }
    }

    fn disc_px(&mut self, cx: f32, cy: f32, r: f32, c: Rgb<u8>, alpha: f32, panel: Option<usize>) {
        if !(finite_px(cx, cy) && r.is_finite() && r > 0.0 && r < FAR_PX) {
            return;
        }
        let mut pb = PathBuilder::new();
        pb.push_circle(cx, cy, r);
        self.fill_path_px(pb, c, alpha, panel);
    }

    fn circle_px(&mut self, cx: f32, cy: f32, r: f32, c: Rgb<u8>, w: f32, panel: Option<usize>) {
        if !(finite_px(cx, cy) && r.is_finite() && r > 0.0 && r < FAR_PX) {
            return;
        }
        let mut pb = PathBuilder::new();
        pb.push_circle(cx, cy, r);
        self.stroke_path_px(pb, c, w, 1.0, panel);
    }

    fn line_px(
        &mut self,
        pts: &[(f32, f32)],
        c: Rgb<u8>,
        w: f32,
        alpha: f32,
        panel: Option<usize>,
    ) {
        let mut pb = PathBuilder::new();
        let mut started = false;
        for &(x, y) in pts {
            if !finite_px(x, y) {
                started = false;
                continue;
            }
            if started {
                pb.line_to(x, y);
            } else {
                pb.move_to(x, y);
                started = true;
            }
        }
        self.stroke_path_px(pb, c, w, alpha, panel);
    }

    fn marker_px(
        &mut self,
        cx: f32,
        cy: f32,
        m: Marker,
        size: f32,
        c: Rgb<u8>,
        panel: Option<usize>,
    ) {
        if !finite_px(cx, cy) {
            return;
        }
        let h = size.clamp(2.0, 200.0) / 2.0;
        let shape = |h: f32| {
            let mut pb = PathBuilder::new();
            match m {
                Marker::Disc => pb.push_circle(cx, cy, h),
                Marker::Diamond => {
                    let h = h * 1.2;
                    pb.move_to(cx, cy - h);
                    pb.line_to(cx + h, cy);
                    pb.line_to(cx, cy + h);
                    pb.line_to(cx - h, cy);
                    pb.close();
                }
                Marker::Square => {
                    if let Some(r) = Rect::from_ltrb(cx - h, cy - h, cx + h, cy + h) {
                        pb.push_rect(r);
                    }
                }
            }
            pb
        };
        self.fill_path_px(shape(h + 2.0), palette::BACKGROUND, 1.0, panel);
        self.fill_path_px(shape(h), c, 1.0, panel);
    }

    // ----- access -----

    /// Drawing in data units on panel `index` (clipped to its plot area); `None` if there is
    /// no such panel.
    pub fn plot(&mut self, index: usize) -> Option<Plot<'_>> {
        (index < self.panels.len()).then_some(Plot { fig: self, index })
    }

    /// The plot area of panel `index`, pixels.
    pub fn plot_rect(&self, index: usize) -> Option<PxRect> {
        self.panels.get(index).map(|p| p.plot)
    }

    /// The scale bar of panel `index`.
    pub fn scale_bar(&self, index: usize) -> Option<ScaleBar> {
        self.panels.get(index).map(|p| p.scale_bar)
    }

    /// The legend's box, pixels.
    pub fn legend_box(&self) -> PxRect {
        self.legend_box
    }

    /// Each legend entry's swatch, in order, pixels.
    pub fn legend_swatches(&self) -> &[PxRect] {
        &self.legend_swatches
    }

    /// Picture size, pixels.
    pub fn size_px(&self) -> (u32, u32) {
        (self.pixmap.width(), self.pixmap.height())
    }

    /// The picture's pixels, RGBA (opaque) row by row.
    pub fn rgba(&self) -> &[u8] {
        self.pixmap.data()
    }

    /// The picture as an RGB image.
    pub fn to_image(&self) -> RgbImage {
        // The picture is opaque, so premultiplied RGBA is plain RGBA: drop the alpha bytes.
        let data = self.pixmap.data();
        let mut rgb = Vec::with_capacity(data.len() / 4 * 3);
        for p in data.chunks_exact(4) {
            rgb.extend_from_slice(&p[..3]);
        }
        RgbImage::from_raw(self.pixmap.width(), self.pixmap.height(), rgb)
            .unwrap_or_else(|| RgbImage::new(self.pixmap.width(), self.pixmap.height()))
    }

    /// Write the picture as PNG (missing parent folders are created).
    pub fn save_png(&self, path: &std::path::Path) -> Result<(), PictureError> {
        let err = |e: String| PictureError::Save {
            path: path.display().to_string(),
            error: e,
        };
        if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
            std::fs::create_dir_all(parent).map_err(|e| err(e.to_string()))?;
        }
        self.to_image()
            .save_with_format(path, image::ImageFormat::Png)
            .map_err(|e| err(e.to_string()))
    }
}

fn finite_px(x: f32, y: f32) -> bool {
    x.is_finite() && y.is_finite() && x.abs() < FAR_PX && y.abs() < FAR_PX
}

#[cfg(test)]
mod tests;
