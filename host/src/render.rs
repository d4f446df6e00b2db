//! A small raster renderer for maps, paths and robots, on [`image::RgbImage`].
//!
//! `twil plan --png` draws with it, and so do the simulator's per-replan pictures and GIF frames:
//! one [`Canvas`] per picture, layers drawn back to front, then [`Canvas::save_png`] or
//! [`Canvas::into_image`].
//!
//! ## Coordinates
//!
//! Everything is given in **world metres** ([`PointM`]) or **grid cells** ([`Cell`]); the canvas
//! knows the [`GridGeometry`] and a scale of `px_per_cell` pixels per cell (2-3 makes a
//! 300 x 300 map 600-900 px wide). The world's y axis points up, so image rows are flipped: the
//! map's lower-left corner (0, 0) m is the image's bottom-left pixel. Pixel coordinates (only
//! used for text) count from the image's top-left corner. Anything drawn off the picture is
//! clipped; non-finite coordinates draw nothing. No drawing call can panic.
//!
//! An optional caption band below the map ([`Canvas::with_caption`]) holds lines of text in a
//! built-in 5x7 bitmap font (digits, letters shown upper-case, `. , : - + = / ( ) % _ * < > ?`).
//!
//! ## Opacity
//!
//! [`Canvas::set_opacity`] applies to every later drawing call until changed, so a faint layer
//! is `set_opacity(0.3)`, draw, `set_opacity(1.0)`.
//!
//! ## API at a glance
//!
//! | call | draws |
//! |---|---|
//! | [`Canvas::new`], [`Canvas::with_caption`] | a white canvas for a geometry |
//! | [`Canvas::draw_grid`] | every occupied cell of a grid, filled |
//! | [`Canvas::fill_cell`], [`Canvas::draw_cells`] | single cells (e.g. visited cells) |
//! | [`Canvas::draw_polygons`], [`Canvas::draw_polygon`] | closed outlines, `width_px` wide |
//! | [`Canvas::fill_polygons`], [`Canvas::fill_polygon`] | filled polygons (even-odd rule) |
//! | [`Canvas::draw_polyline`], [`Canvas::draw_segment`] | open polylines (paths) |
//! | [`Canvas::draw_disc`], [`Canvas::draw_circle`] | filled / outlined circles of a radius in metres |
//! | [`Canvas::draw_robot`] | a robot disc with a heading line |
//! | [`Canvas::draw_marker`], [`Canvas::draw_cross`] | fixed-size markers (start, goal) |
//! | [`Canvas::draw_points`] | small dots (sonar hits) |
//! | [`Canvas::draw_metre_lines`] | a faint coordinate grid every `step_m` |
//! | [`Canvas::draw_text`], [`Canvas::caption_text`], [`Canvas::caption_legend`] | labels |
//! | [`Canvas::into_image`], [`Canvas::image`], [`Canvas::save_png`] | the result |
//!
//! ```
//! use twil_core::geom::PointM;
//! use twil_core::grid::{Grid400, GridGeometry};
//! use twil_host::render::{palette, Canvas, Marker};
//!
//! let geometry = GridGeometry::from_size_m(5.0, 4.0, 0.05).unwrap(); // 100 x 80 cells
//! let mut grid = Grid400::new(geometry).unwrap();
//! grid.fill_row(40, 10, 60);
//! let mut canvas = Canvas::new(geometry, 2).unwrap();
//! canvas.draw_grid(&grid, palette::EXPANSION);
//! canvas.draw_polyline(&[PointM::new(0.5, 0.5), PointM::new(4.5, 3.5)], palette::PATH, 3.0);
//! canvas.draw_marker(PointM::new(0.5, 0.5), Marker::Disc, 9, palette::START);
//! let image = canvas.into_image();
//! assert_eq!(image.dimensions(), (200, 160));
//! // y up: cell row 40 of 80 is drawn on image rows 78..80 (counted from the top).
//! assert_eq!(image.get_pixel(40, 79).0, palette::EXPANSION.0);
//! ```

use std::path::Path;

use image::{Rgb, RgbImage};
use twil_core::geom::{Cell, PointM};
use twil_core::grid::{Grid, GridGeometry};
use twil_core::world::PolygonSet;

/// Largest accepted scale, pixels per cell.
pub const MAX_PX_PER_CELL: u32 = 16;
/// Largest accepted image side, pixels.
pub const MAX_SIDE_PX: u32 = 8192;
/// Height of one caption line, pixels (7-pixel glyphs at scale 2 plus spacing).
pub const CAPTION_LINE_PX: u32 = 20;

/// Colours that the twil pictures share, so that plan and simulation pictures read alike.
pub mod palette {
    use image::Rgb;
    /// Background (free space).
    pub const BACKGROUND: Rgb<u8> = Rgb([255, 255, 255]);
    /// Grid cells occupied only because obstacles are grown by the robot radius.
    pub const EXPANSION: Rgb<u8> = Rgb([250, 200, 150]);
    /// Cells occupied by the obstacles themselves (or a saved map).
    pub const OBSTACLE: Rgb<u8> = Rgb([90, 90, 100]);
    /// Polygon outlines as given in the `.da` file.
    pub const POLYGON: Rgb<u8> = Rgb([20, 20, 30]);
    /// A planned path.
    pub const PATH: Rgb<u8> = Rgb([30, 90, 220]);
    /// A second path (e.g. the pruned prefix, or the driven trajectory).
    pub const PATH_ALT: Rgb<u8> = Rgb([200, 30, 160]);
    /// The start marker.
    pub const START: Rgb<u8> = Rgb([20, 160, 60]);
    /// The goal marker.
    pub const GOAL: Rgb<u8> = Rgb([220, 30, 30]);
    /// The robot.
    pub const ROBOT: Rgb<u8> = Rgb([0, 120, 140]);
    /// Sonar hits.
    pub const SONAR: Rgb<u8> = Rgb([230, 120, 0]);
    /// Faint metre lines.
    pub const METRE_LINES: Rgb<u8> = Rgb([225, 228, 235]);
    /// Text.
    pub const TEXT: Rgb<u8> = Rgb([0, 0, 0]);
}

/// Why a canvas could not be made or saved.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The scale is 0 or above [`MAX_PX_PER_CELL`], or the picture would exceed
    /// [`MAX_SIDE_PX`] on a side.
    #[error("picture of {width_cells}x{height_cells} cells at {px_per_cell} px per cell is not possible (scale 1..={MAX_PX_PER_CELL}, at most {MAX_SIDE_PX} px a side)")]
    BadScale {
        /// Map width, cells.
        width_cells: u32,
        /// Map height, cells.
        height_cells: u32,
        /// Scale asked for.
        px_per_cell: u32,
    },
    /// Writing the file failed.
    #[error("{path}: cannot write the picture: {error}")]
    Save {
        /// The file.
        path: String,
        /// Why (part of the message, so not also a `source`).
        error: image::ImageError,
    },
}

/// Marker shapes of a fixed size in pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Marker {
    /// A filled disc with a white rim.
    Disc,
    /// A filled square with a white rim.
    Square,
    /// A filled diamond with a white rim.
    Diamond,
    /// A diagonal cross.
    Cross,
    /// An upright plus sign.
    Plus,
    /// A ring (circle outline).
    Ring,
}

/// A picture of a map: see the module documentation.
#[derive(Clone, Debug)]
pub struct Canvas {
    geometry: GridGeometry,
    px_per_cell: u32,
    map_width_px: u32,
    map_height_px: u32,
    opacity: f32,
    image: RgbImage,
}

impl Canvas {
    /// A white canvas for `geometry` at `px_per_cell` pixels per cell, without caption band.
    ///
    /// Fails when `px_per_cell` is 0 or above [`MAX_PX_PER_CELL`], or a side would exceed
    /// [`MAX_SIDE_PX`].
    pub fn new(geometry: GridGeometry, px_per_cell: u32) -> Result<Self, RenderError> {
        Self::with_caption(geometry, px_per_cell, 0)
    }

    /// A white canvas with `caption_lines` lines of [`CAPTION_LINE_PX`] pixels below the map.
    pub fn with_caption(
        geometry: GridGeometry,
        px_per_cell: u32,
        caption_lines: u32,
    ) -> Result<Self, RenderError> {
        let (w, h) = (geometry.width() as u32, geometry.height() as u32);
        let bad = RenderError::BadScale {
            width_cells: w,
            height_cells: h,
            px_per_cell,
        };
        if px_per_cell == 0 || px_per_cell > MAX_PX_PER_CELL {
            return Err(bad);
        }
        let map_width_px = w * px_per_cell;
        let map_height_px = h * px_per_cell;
        let caption_px = caption_lines.saturating_mul(CAPTION_LINE_PX);
        let total_height = map_height_px.saturating_add(caption_px);
        if map_width_px > MAX_SIDE_PX || total_height > MAX_SIDE_PX {
            return Err(bad);
        }
        Ok(Self {
            geometry,
            px_per_cell,
            map_width_px,
            map_height_px,
            opacity: 1.0,
            image: RgbImage::from_pixel(map_width_px, total_height, palette::BACKGROUND),
        })
    }

    /// A scale that makes the longer side of `geometry` about `target_px` pixels (at least 1,
    /// at most [`MAX_PX_PER_CELL`]).
    ///
    /// ```
    /// use twil_core::grid::GridGeometry;
    /// assert_eq!(twil_host::render::Canvas::fit_scale(GridGeometry::seed_default(), 900), 3);
    /// ```
    pub fn fit_scale(geometry: GridGeometry, target_px: u32) -> u32 {
        let side = geometry.width().max(geometry.height()).max(1) as u32;
        (target_px / side).clamp(1, MAX_PX_PER_CELL)
    }

    /// The map geometry.
    pub fn geometry(&self) -> GridGeometry {
        self.geometry
    }

    /// Pixels per cell.
    pub fn px_per_cell(&self) -> u32 {
        self.px_per_cell
    }

    /// Pixels per metre.
    pub fn px_per_m(&self) -> f32 {
        self.px_per_cell as f32 / self.geometry.resolution_m()
    }

    /// Size of the map part of the picture, pixels (width, height).
    pub fn map_size_px(&self) -> (u32, u32) {
        (self.map_width_px, self.map_height_px)
    }

    /// Opacity of later drawing calls, 0 (invisible) to 1 (opaque; the default). Values outside
    /// are clamped; NaN counts as 1.
    pub fn set_opacity(&mut self, opacity: f32) {
        self.opacity = if opacity.is_nan() {
            1.0
        } else {
            opacity.clamp(0.0, 1.0)
        };
    }

    /// Pixel position (x right, y down, fractional) of a world point.
    pub fn to_px(&self, point: PointM) -> (f32, f32) {
        let s = self.px_per_m();
        (point.x_m * s, self.map_height_px as f32 - point.y_m * s)
    }

    /// The picture drawn so far.
    pub fn image(&self) -> &RgbImage {
        &self.image
    }

    /// The finished picture.
    pub fn into_image(self) -> RgbImage {
        self.image
    }

    /// Write the picture as PNG.
    pub fn save_png(&self, path: &Path) -> Result<(), RenderError> {
        self.image
            .save_with_format(path, image::ImageFormat::Png)
            .map_err(|error| RenderError::Save {
                path: path.display().to_string(),
                error,
            })
    }

    // ----- pixels -----

    /// Blend one pixel at signed coordinates with the current opacity; outside: nothing.
    fn put(&mut self, x: i64, y: i64, color: Rgb<u8>) {
        if x < 0 || y < 0 || x >= self.image.width() as i64 || y >= self.image.height() as i64 {
            return;
        }
        let a = self.opacity;
        let p = self.image.get_pixel_mut(x as u32, y as u32);
        if a >= 1.0 {
            *p = color;
        } else if a > 0.0 {
            for (d, s) in p.0.iter_mut().zip(color.0) {
                *d = (*d as f32 * (1.0 - a) + s as f32 * a).round() as u8;
            }
        }
    }

    /// Same as `put` but only inside the map area (not the caption band).
    fn put_map(&mut self, x: i64, y: i64, color: Rgb<u8>) {
        if y < self.map_height_px as i64 {
            self.put(x, y, color);
        }
    }

    /// Fill the pixel rectangle `[x0, x1) x [y0, y1)` of the map area.
    fn fill_rect_px(&mut self, x0: i64, y0: i64, x1: i64, y1: i64, color: Rgb<u8>) {
        let (x0, x1) = (x0.max(0), x1.min(self.map_width_px as i64));
        let (y0, y1) = (y0.max(0), y1.min(self.map_height_px as i64));
        for y in y0..y1 {
            for x in x0..x1 {
                self.put(x, y, color);
            }
        }
    }

    /// Fill every pixel whose centre lies within `radius_px` of (`cx`, `cy`).
    fn fill_disc_px(&mut self, cx: f32, cy: f32, radius_px: f32, color: Rgb<u8>) {
        if !(cx.is_finite() && cy.is_finite() && radius_px.is_finite()) || radius_px <= 0.0 {
            return;
        }
        let limit = 2.0 * MAX_SIDE_PX as f32;
        if cx < -limit || cy < -limit || cx > limit || cy > limit || radius_px > limit {
            return;
        }
        let r2 = radius_px * radius_px;
        let (y0, y1) = (
            (cy - radius_px).floor() as i64,
            (cy + radius_px).ceil() as i64,
        );
        let (x0, x1) = (
            (cx - radius_px).floor() as i64,
            (cx + radius_px).ceil() as i64,
        );
        let (y0, y1) = (y0.max(0), y1.min(self.map_height_px as i64 - 1));
        let (x0, x1) = (x0.max(0), x1.min(self.map_width_px as i64 - 1));
        for y in y0..=y1 {
            let dy = y as f32 + 0.5 - cy;
            for x in x0..=x1 {
                let dx = x as f32 + 0.5 - cx;
                if dx * dx + dy * dy <= r2 {
                    self.put(x, y, color);
                }
            }
        }
    }

    /// A line between two pixel positions, `width_px` wide. With partial opacity overlapping
    /// stamps would darken, so thick translucent lines are first collected in a mask.
    fn line_px(&mut self, a: (f32, f32), b: (f32, f32), color: Rgb<u8>, width_px: f32) {
        let finite = a.0.is_finite() && a.1.is_finite() && b.0.is_finite() && b.1.is_finite();
        if !finite || !width_px.is_finite() {
            return;
        }
        // Clip to a generous box so that absurd coordinates cannot make a long walk.
        let Some((a, b)) = clip_segment(
            a,
            b,
            -16.0,
            self.map_width_px as f32 + 16.0,
            -16.0,
            self.map_height_px as f32 + 16.0,
        ) else {
            return;
        };
        if width_px <= 1.5 {
            let from = (a.0.floor() as i32, a.1.floor() as i32);
            let to = (b.0.floor() as i32, b.1.floor() as i32);
            for (x, y) in twil_core::raster::BresenhamLine::new(from, to) {
                self.put_map(x as i64, y as i64, color);
            }
            return;
        }
        let r = width_px / 2.0;
        let mut mask = PixelMask::new(a, b, r, self.map_width_px, self.map_height_px);
        let length = ((b.0 - a.0).powi(2) + (b.1 - a.1).powi(2)).sqrt();
        let steps = (length / 0.5).ceil().max(1.0) as u32;
        for i in 0..=steps {
            let t = i as f32 / steps as f32;
            mask.disc(a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t, r);
        }
        mask.paint(self, color);
    }

    // ----- grid layers -----

    /// Fill one cell.
    pub fn fill_cell(&mut self, cell: Cell, color: Rgb<u8>) {
        let s = self.px_per_cell as i64;
        let x0 = cell.x as i64 * s;
        let y1 = self.map_height_px as i64 - cell.y as i64 * s;
        self.fill_rect_px(x0, y1 - s, x0 + s, y1, color);
    }

    /// Fill each of `cells`.
    pub fn draw_cells(&mut self, cells: impl IntoIterator<Item = Cell>, color: Rgb<u8>) {
        for cell in cells {
            self.fill_cell(cell, color);
        }
    }

    /// Fill every occupied cell of `grid`. Its geometry should be the canvas's; cells beyond the
    /// canvas are clipped.
    pub fn draw_grid<const W: usize>(&mut self, grid: &Grid<W>, color: Rgb<u8>) {
        let g = *grid.geometry();
        for y in 0..g.height() {
            for x in 0..g.width() {
                let cell = Cell::new(x, y);
                if grid.is_occupied(cell) {
                    self.fill_cell(cell, color);
                }
            }
        }
    }

    /// Faint lines every `step_m` metres (e.g. 1.0) over the whole map.
    pub fn draw_metre_lines(&mut self, step_m: f32, color: Rgb<u8>) {
        if !(step_m.is_finite() && step_m > 0.0) {
            return;
        }
        let s = self.px_per_m();
        let (w_m, h_m) = (self.geometry.width_m(), self.geometry.height_m());
        if w_m / step_m > 10_000.0 || h_m / step_m > 10_000.0 {
            return;
        }
        let mut x_m = step_m;
        while x_m < w_m {
            let x = (x_m * s).round() as i64;
            for y in 0..self.map_height_px as i64 {
                self.put(x, y, color);
            }
            x_m += step_m;
        }
        let mut y_m = step_m;
        while y_m < h_m {
            let y = (self.map_height_px as f32 - y_m * s).round() as i64;
            for x in 0..self.map_width_px as i64 {
                self.put(x, y, color);
            }
            y_m += step_m;
        }
    }

    // ----- vector layers -----

    /// A segment between two world points, `width_px` pixels wide.
    pub fn draw_segment(&mut self, a: PointM, b: PointM, color: Rgb<u8>, width_px: f32) {
        self.line_px(self.to_px(a), self.to_px(b), color, width_px);
    }

    /// An open polyline through `points` (world metres), `width_px` wide. One point draws a dot.
    pub fn draw_polyline(&mut self, points: &[PointM], color: Rgb<u8>, width_px: f32) {
        match points {
            [] => {}
            [p] => {
                let (x, y) = self.to_px(*p);
                self.fill_disc_px(x, y, (width_px / 2.0).max(1.0), color);
            }
            _ => {
                for w in points.windows(2) {
                    self.draw_segment(w[0], w[1], color, width_px);
                }
            }
        }
    }

    /// The closed outline of a polygon (last vertex joined to the first).
    pub fn draw_polygon(&mut self, vertices: &[PointM], color: Rgb<u8>, width_px: f32) {
        self.draw_polyline(vertices, color, width_px);
        if let (Some(first), Some(last), true) =
            (vertices.first(), vertices.last(), vertices.len() > 2)
        {
            self.draw_segment(*last, *first, color, width_px);
        }
    }

    /// The outlines of every polygon of a set.
    pub fn draw_polygons<const V: usize, const P: usize>(
        &mut self,
        polygons: &PolygonSet<V, P>,
        color: Rgb<u8>,
        width_px: f32,
    ) {
        for polygon in polygons.iter() {
            self.draw_polygon(polygon, color, width_px);
        }
    }

    /// Fill a polygon (even-odd rule, pixel centres), e.g. to show obstacle interiors.
    pub fn fill_polygon(&mut self, vertices: &[PointM], color: Rgb<u8>) {
        if vertices.len() < 3 || vertices.iter().any(|v| !v.is_finite()) {
            return;
        }
        let px: Vec<(f32, f32)> = vertices.iter().map(|v| self.to_px(*v)).collect();
        let (min_y, max_y) = px.iter().fold((f32::MAX, f32::MIN), |(lo, hi), p| {
            (lo.min(p.1), hi.max(p.1))
        });
        let y0 = (min_y.floor() as i64).max(0);
        let y1 = (max_y.ceil() as i64).min(self.map_height_px as i64 - 1);
        let mut crossings: Vec<f32> = Vec::new();
        for y in y0..=y1 {
            let yc = y as f32 + 0.5;
            crossings.clear();
            for i in 0..px.len() {
                let (a, b) = (px[i], px[(i + 1) % px.len()]);
                if (a.1 <= yc) != (b.1 <= yc) {
                    crossings.push(a.0 + (yc - a.1) / (b.1 - a.1) * (b.0 - a.0));
                }
            }
            crossings.sort_by(f32::total_cmp);
            for pair in crossings.chunks_exact(2) {
                let x0 = ((pair[0] - 0.5).ceil() as i64).max(0);
                let x1 = ((pair[1] - 0.5).floor() as i64).min(self.map_width_px as i64 - 1);
                for x in x0..=x1 {
                    self.put(x, y, color);
                }
            }
        }
    }

    /// Fill every polygon of a set.
    pub fn fill_polygons<const V: usize, const P: usize>(
        &mut self,
        polygons: &PolygonSet<V, P>,
        color: Rgb<u8>,
    ) {
        for polygon in polygons.iter() {
            self.fill_polygon(polygon, color);
        }
    }

    /// A filled disc of `radius_m` metres (at least one pixel).
    pub fn draw_disc(&mut self, center: PointM, radius_m: f32, color: Rgb<u8>) {
        let (x, y) = self.to_px(center);
        self.fill_disc_px(x, y, (radius_m * self.px_per_m()).max(0.7), color);
    }

    /// A circle outline of `radius_m` metres, `width_px` wide.
    pub fn draw_circle(&mut self, center: PointM, radius_m: f32, color: Rgb<u8>, width_px: f32) {
        let (cx, cy) = self.to_px(center);
        let r = radius_m * self.px_per_m();
        if !(r.is_finite() && r > 0.0 && width_px.is_finite() && width_px > 0.0) {
            return;
        }
        let mut mask = PixelMask::new(
            (cx - r, cy - r),
            (cx + r, cy + r),
            width_px / 2.0 + 1.0,
            self.map_width_px,
            self.map_height_px,
        );
        mask.ring(cx, cy, r, width_px / 2.0);
        mask.paint(self, color);
    }

    /// The robot: a translucent disc of `radius_m`, its outline, and a line from the centre to
    /// the rim along `heading_rad` (counter-clockwise from +x).
    pub fn draw_robot(&mut self, center: PointM, radius_m: f32, heading_rad: f32, color: Rgb<u8>) {
        let saved = self.opacity;
        self.set_opacity(saved * 0.35);
        self.draw_disc(center, radius_m, color);
        self.opacity = saved;
        self.draw_circle(center, radius_m, color, 2.0);
        if heading_rad.is_finite() {
            let tip = PointM::new(
                center.x_m + radius_m * heading_rad.cos(),
                center.y_m + radius_m * heading_rad.sin(),
            );
            self.draw_segment(center, tip, color, 2.5);
        }
    }

    /// A marker `size_px` pixels across centred on a world point.
    pub fn draw_marker(&mut self, at: PointM, marker: Marker, size_px: u32, color: Rgb<u8>) {
        let (cx, cy) = self.to_px(at);
        if !(cx.is_finite() && cy.is_finite()) {
            return;
        }
        let h = size_px.clamp(1, 200) as f32 / 2.0;
        let white = palette::BACKGROUND;
        match marker {
            Marker::Disc => {
                self.fill_disc_px(cx, cy, h + 1.5, white);
                self.fill_disc_px(cx, cy, h, color);
            }
            Marker::Square => {
                self.square_px(cx, cy, h + 1.5, white);
                self.square_px(cx, cy, h, color);
            }
            Marker::Diamond => {
                self.diamond_px(cx, cy, h + 2.0, white);
                self.diamond_px(cx, cy, h, color);
            }
            Marker::Cross => {
                self.line_px((cx - h, cy - h), (cx + h, cy + h), color, 3.0);
                self.line_px((cx - h, cy + h), (cx + h, cy - h), color, 3.0);
            }
            Marker::Plus => {
                self.line_px((cx - h, cy), (cx + h, cy), color, 3.0);
                self.line_px((cx, cy - h), (cx, cy + h), color, 3.0);
            }
            Marker::Ring => {
                let mut mask = PixelMask::new(
                    (cx - h, cy - h),
                    (cx + h, cy + h),
                    3.0,
                    self.map_width_px,
                    self.map_height_px,
                );
                mask.ring(cx, cy, h, 1.25);
                mask.paint(self, color);
            }
        }
    }

    /// A diagonal cross marker (shorthand for [`Marker::Cross`]).
    pub fn draw_cross(&mut self, at: PointM, size_px: u32, color: Rgb<u8>) {
        self.draw_marker(at, Marker::Cross, size_px, color);
    }

    /// Small dots of `radius_px` pixels at each point (sonar hits).
    pub fn draw_points(&mut self, points: &[PointM], radius_px: f32, color: Rgb<u8>) {
        for p in points {
            let (x, y) = self.to_px(*p);
            self.fill_disc_px(x, y, radius_px.max(0.6), color);
        }
    }

    fn square_px(&mut self, cx: f32, cy: f32, h: f32, color: Rgb<u8>) {
        self.fill_rect_px(
            (cx - h).round() as i64,
            (cy - h).round() as i64,
            (cx + h).round() as i64,
            (cy + h).round() as i64,
            color,
        );
    }

    fn diamond_px(&mut self, cx: f32, cy: f32, h: f32, color: Rgb<u8>) {
        let (y0, y1) = ((cy - h).floor() as i64, (cy + h).ceil() as i64);
        let (x0, x1) = ((cx - h).floor() as i64, (cx + h).ceil() as i64);
        for y in y0..=y1 {
            for x in x0..=x1 {
                let d = (x as f32 + 0.5 - cx).abs() + (y as f32 + 0.5 - cy).abs();
                if d <= h {
                    self.put_map(x, y, color);
                }
            }
        }
    }

    // ----- text -----

    /// Width in pixels of `text` drawn at `scale` (each glyph 5 x 7 dots plus a 1-dot gap).
    pub fn text_width_px(text: &str, scale: u32) -> u32 {
        (text.chars().count() as u32).saturating_mul(6 * scale.max(1))
    }

    /// Draw `text` with its top-left corner at pixel (`x_px`, `y_px`) of the whole image, each
    /// font dot `scale` pixels wide. Letters are shown upper-case; unknown characters as `?`.
    pub fn draw_text(&mut self, x_px: i64, y_px: i64, text: &str, color: Rgb<u8>, scale: u32) {
        let s = scale.clamp(1, 16) as i64;
        let mut x = x_px;
        for c in text.chars() {
            let rows = glyph(c);
            for (row, bits) in rows.iter().enumerate() {
                for col in 0..5 {
                    if bits & (0x10 >> col) != 0 {
                        for dy in 0..s {
                            for dx in 0..s {
                                self.put(x + col * s + dx, y_px + row as i64 * s + dy, color);
                            }
                        }
                    }
                }
            }
            x += 6 * s;
            if x > self.image.width() as i64 {
                break;
            }
        }
    }

    /// Draw `text` on caption line `line` (0 = first line below the map), in the 5x7 font at
    /// scale 2, or 1 when the text would not fit the width. Does nothing for a line that the
    /// canvas does not have.
    pub fn caption_text(&mut self, line: u32, text: &str, color: Rgb<u8>) {
        if let Some(y) = self.caption_y(line) {
            let scale = self.caption_scale(Canvas::text_width_px(text, 2));
            self.draw_text(6, y, text, color, scale);
        }
    }

    /// A legend on caption line `line`: for each entry a colour swatch then its label (scale 2,
    /// or 1 when the legend would not fit the width).
    pub fn caption_legend(&mut self, line: u32, entries: &[(&str, Rgb<u8>)]) {
        let Some(y) = self.caption_y(line) else {
            return;
        };
        let width_at_2: u32 = entries
            .iter()
            .map(|(label, _)| 36 + Canvas::text_width_px(label, 2))
            .sum();
        let scale = self.caption_scale(width_at_2) as i64;
        let saved = self.opacity;
        self.opacity = 1.0;
        let mut x = 6i64;
        let swatch = 7 * scale;
        for (label, color) in entries {
            for yy in y..y + swatch {
                for xx in x..x + swatch {
                    self.put(xx, yy, *color);
                }
            }
            x += swatch + 3 * scale;
            self.draw_text(x, y, label, palette::TEXT, scale as u32);
            x += Canvas::text_width_px(label, scale as u32) as i64 + 8 * scale;
        }
        self.opacity = saved;
    }

    /// Font scale for a caption that is `width_at_2` pixels wide at scale 2: 2 when it fits
    /// the picture, else 1 (the caption is clipped if even that does not fit).
    fn caption_scale(&self, width_at_2: u32) -> u32 {
        if width_at_2.saturating_add(12) <= self.image.width() {
            2
        } else {
            1
        }
    }

    fn caption_y(&self, line: u32) -> Option<i64> {
        let y = self.map_height_px as i64 + line as i64 * CAPTION_LINE_PX as i64 + 3;
        (y + 14 <= self.image.height() as i64).then_some(y)
    }
}

/// A boolean mask over a pixel box, so that overlapping stamps paint each pixel once (keeps
/// translucent thick lines even).
struct PixelMask {
    x0: i64,
    y0: i64,
    width: i64,
    height: i64,
    bits: Vec<bool>,
}

impl PixelMask {
    /// A mask covering the box of `a`, `b` grown by `margin`, clipped to the map.
    fn new(a: (f32, f32), b: (f32, f32), margin: f32, map_w: u32, map_h: u32) -> Self {
        let x0 = ((a.0.min(b.0) - margin).floor() as i64).max(0);
        let y0 = ((a.1.min(b.1) - margin).floor() as i64).max(0);
        let x1 = ((a.0.max(b.0) + margin).ceil() as i64).min(map_w as i64);
        let y1 = ((a.1.max(b.1) + margin).ceil() as i64).min(map_h as i64);
        let (width, height) = ((x1 - x0).max(0), (y1 - y0).max(0));
        Self {
            x0,
            y0,
            width,
            height,
            bits: vec![false; (width * height) as usize],
        }
    }

    fn mark_where(
        &mut self,
        bx0: f32,
        by0: f32,
        bx1: f32,
        by1: f32,
        inside: impl Fn(f32, f32) -> bool,
    ) {
        let xs = (
            (bx0.floor() as i64).max(self.x0),
            (bx1.ceil() as i64).min(self.x0 + self.width - 1),
        );
        let ys = (
            (by0.floor() as i64).max(self.y0),
            (by1.ceil() as i64).min(self.y0 + self.height - 1),
        );
        for y in ys.0..=ys.1 {
            for x in xs.0..=xs.1 {
                if inside(x as f32 + 0.5, y as f32 + 0.5) {
                    let i = ((y - self.y0) * self.width + (x - self.x0)) as usize;
                    if let Some(b) = self.bits.get_mut(i) {
                        *b = true;
                    }
                }
            }
        }
    }

    fn disc(&mut self, cx: f32, cy: f32, r: f32) {
        let r2 = r * r;
        self.mark_where(cx - r, cy - r, cx + r, cy + r, |x, y| {
            (x - cx).powi(2) + (y - cy).powi(2) <= r2
        });
    }

    fn ring(&mut self, cx: f32, cy: f32, r: f32, half_width: f32) {
        let (lo, hi) = ((r - half_width).max(0.0), r + half_width);
        self.mark_where(cx - hi, cy - hi, cx + hi, cy + hi, |x, y| {
            let d = ((x - cx).powi(2) + (y - cy).powi(2)).sqrt();
            d >= lo && d <= hi
        });
    }

    fn paint(&self, canvas: &mut Canvas, color: Rgb<u8>) {
        for (i, on) in self.bits.iter().enumerate() {
            if *on {
                let i = i as i64;
                canvas.put(self.x0 + i % self.width, self.y0 + i / self.width, color);
            }
        }
    }
}

/// Liang-Barsky clipping of a segment to a box; `None` when it lies wholly outside.
fn clip_segment(
    a: (f32, f32),
    b: (f32, f32),
    xmin: f32,
    xmax: f32,
    ymin: f32,
    ymax: f32,
) -> Option<((f32, f32), (f32, f32))> {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let (mut t0, mut t1) = (0.0f32, 1.0f32);
    for (p, q) in [
        (-dx, a.0 - xmin),
        (dx, xmax - a.0),
        (-dy, a.1 - ymin),
        (dy, ymax - a.1),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
            if t0 > t1 {
                return None;
            }
        }
    }
    Some((
        (a.0 + t0 * dx, a.1 + t0 * dy),
        (a.0 + t1 * dx, a.1 + t1 * dy),
    ))
}

/// The 5x7 dots of a character, one byte per row, bit 4 = leftmost column.
fn glyph(c: char) -> [u8; 7] {
    match c.to_ascii_uppercase() {
        '0' => [0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E],
        '1' => [0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E],
        '2' => [0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F],
        '3' => [0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E],
        '4' => [0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02],
        '5' => [0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E],
        '6' => [0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E],
        '7' => [0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08],
        '8' => [0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E],
        '9' => [0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C],
        'A' => [0x0E, 0x11, 0x11, 0x11, 0x1F, 0x11, 0x11],
        'B' => [0x1E, 0x11, 0x11, 0x1E, 0x11, 0x11, 0x1E],
        'C' => [0x0E, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0E],
        'D' => [0x1C, 0x12, 0x11, 0x11, 0x11, 0x12, 0x1C],
        'E' => [0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F],
        'F' => [0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x10],
        'G' => [0x0E, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0F],
        'H' => [0x11, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11],
        'I' => [0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E],
        'J' => [0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0C],
        'K' => [0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11],
        'L' => [0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F],
        'M' => [0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11],
        'N' => [0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11],
        'O' => [0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E],
        'P' => [0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10],
        'Q' => [0x0E, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0D],
        'R' => [0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11],
        'S' => [0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E],
        'T' => [0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04],
        'U' => [0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E],
        'V' => [0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04],
        'W' => [0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0A],
        'X' => [0x11, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x11],
        'Y' => [0x11, 0x11, 0x11, 0x0A, 0x04, 0x04, 0x04],
        'Z' => [0x1F, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1F],
        ' ' => [0; 7],
        '.' => [0, 0, 0, 0, 0, 0x0C, 0x0C],
        ',' => [0, 0, 0, 0, 0x0C, 0x04, 0x08],
        ':' => [0, 0x0C, 0x0C, 0, 0x0C, 0x0C, 0],
        '-' => [0, 0, 0, 0x1F, 0, 0, 0],
        '+' => [0, 0x04, 0x04, 0x1F, 0x04, 0x04, 0],
        '=' => [0, 0, 0x1F, 0, 0x1F, 0, 0],
        '/' => [0, 0x01, 0x02, 0x04, 0x08, 0x10, 0],
        '(' => [0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02],
        ')' => [0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08],
        '%' => [0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03],
        '_' => [0, 0, 0, 0, 0, 0, 0x1F],
        '*' => [0, 0x04, 0x15, 0x0E, 0x15, 0x04, 0],
        '<' => [0x02, 0x04, 0x08, 0x10, 0x08, 0x04, 0x02],
        '>' => [0x08, 0x04, 0x02, 0x01, 0x02, 0x04, 0x08],
        _ => [0x0E, 0x11, 0x01, 0x02, 0x04, 0, 0x04],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use twil_core::grid::Grid400;

    fn geometry() -> GridGeometry {
        GridGeometry::new(40, 30, 0.1).unwrap()
    }

    fn count(image: &RgbImage, color: Rgb<u8>) -> usize {
        image.pixels().filter(|p| **p == color).count()
    }

    #[test]
    fn refuses_bad_scales() {
        assert!(Canvas::new(geometry(), 0).is_err());
        assert!(Canvas::new(geometry(), MAX_PX_PER_CELL + 1).is_err());
        let big = GridGeometry::new(4000, 10, 0.1).unwrap();
        assert!(Canvas::new(big, 3).is_err());
        assert!(Canvas::new(big, 2).is_ok());
    }

    #[test]
    fn cells_are_drawn_with_y_up() {
        let mut c = Canvas::new(geometry(), 3).unwrap();
        c.fill_cell(Cell::new(0, 0), palette::OBSTACLE);
        let img = c.into_image();
        assert_eq!(img.dimensions(), (120, 90));
        assert_eq!(*img.get_pixel(0, 89), palette::OBSTACLE);
        assert_eq!(*img.get_pixel(2, 87), palette::OBSTACLE);
        assert_eq!(*img.get_pixel(3, 89), palette::BACKGROUND);
        assert_eq!(*img.get_pixel(0, 86), palette::BACKGROUND);
        assert_eq!(count(&img, palette::OBSTACLE), 9);
    }

    #[test]
    fn grid_cells_become_blocks() {
        let mut grid = Grid400::new(geometry()).unwrap();
        grid.fill_row(29, 0, 39); // top row
        grid.set_xy(5, 5, true);
        let mut c = Canvas::new(geometry(), 2).unwrap();
        c.draw_grid(&grid, palette::EXPANSION);
        let img = c.into_image();
        assert_eq!(count(&img, palette::EXPANSION), 41 * 4);
        assert_eq!(*img.get_pixel(79, 0), palette::EXPANSION);
    }

    #[test]
    fn opacity_blends() {
        let mut c = Canvas::new(geometry(), 1).unwrap();
        c.set_opacity(0.5);
        c.fill_cell(Cell::new(1, 1), Rgb([0, 0, 0]));
        c.set_opacity(f32::NAN);
        c.fill_cell(Cell::new(2, 2), Rgb([0, 0, 0]));
        let img = c.into_image();
        assert_eq!(img.get_pixel(1, 28).0, [128, 128, 128]);
        assert_eq!(img.get_pixel(2, 27).0, [0, 0, 0]);
    }

    #[test]
    fn polyline_reaches_its_ends_and_stays_on_the_line() {
        let mut c = Canvas::new(geometry(), 2).unwrap();
        let a = PointM::new(0.5, 0.5);
        let b = PointM::new(3.5, 2.5);
        c.draw_polyline(&[a, b], palette::PATH, 3.0);
        let (ax, ay) = c.to_px(a);
        let (bx, by) = c.to_px(b);
        let img = c.image().clone();
        assert_eq!(*img.get_pixel(ax as u32, ay as u32), palette::PATH);
        assert_eq!(*img.get_pixel(bx as u32, by as u32), palette::PATH);
        // Every painted pixel lies within 2 px of the segment.
        for (x, y, p) in img.enumerate_pixels() {
            if *p == palette::PATH {
                let (px, py) = (x as f32 + 0.5, y as f32 + 0.5);
                let (dx, dy) = (bx - ax, by - ay);
                let t = (((px - ax) * dx + (py - ay) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
                let d = ((ax + t * dx - px).powi(2) + (ay + t * dy - py).powi(2)).sqrt();
                assert!(d <= 2.0, "pixel ({x}, {y}) is {d} px off the line");
            }
        }
    }

    #[test]
    fn filled_square_polygon_covers_its_cells() {
        let mut c = Canvas::new(geometry(), 1).unwrap();
        let sq = [
            PointM::new(1.0, 1.0),
            PointM::new(2.0, 1.0),
            PointM::new(2.0, 2.0),
            PointM::new(1.0, 2.0),
        ];
        c.fill_polygon(&sq, palette::OBSTACLE);
        assert_eq!(count(c.image(), palette::OBSTACLE), 100);
    }

    #[test]
    fn absurd_input_draws_nothing_and_does_not_panic() {
        let mut c = Canvas::with_caption(geometry(), 2, 1).unwrap();
        let far = PointM::new(1.0e30, -1.0e30);
        let nan = PointM::new(f32::NAN, 1.0);
        c.draw_polyline(&[far, nan, PointM::new(1.0e30, 1.0e30)], palette::PATH, 5.0);
        c.draw_polyline(&[far, PointM::new(1.0e30, 1.0e30)], palette::PATH, 1.0);
        c.draw_disc(far, 1.0e30, palette::PATH);
        c.draw_circle(nan, 3.0, palette::PATH, 2.0);
        c.draw_robot(far, f32::INFINITY, f32::NAN, palette::PATH);
        c.draw_marker(nan, Marker::Diamond, u32::MAX, palette::PATH);
        c.fill_polygon(&[far, nan, far], palette::PATH);
        c.draw_points(&[far, nan], 3.0, palette::PATH);
        c.draw_metre_lines(0.0, palette::PATH);
        c.draw_text(i64::MIN / 4, i64::MAX / 4, "xyz", palette::PATH, 99);
        c.caption_text(5, "no such line", palette::PATH);
        assert_eq!(count(c.image(), palette::PATH), 0);
    }

    #[test]
    fn caption_text_lands_below_the_map() {
        let mut c = Canvas::with_caption(geometry(), 2, 2).unwrap();
        c.caption_text(1, "A* 1.5 M", palette::TEXT);
        c.caption_legend(0, &[("PATH", palette::PATH)]);
        let img = c.into_image();
        assert_eq!(img.height(), 60 + 2 * CAPTION_LINE_PX);
        let text_rows: Vec<u32> = img
            .enumerate_pixels()
            .filter(|(_, _, p)| **p == palette::TEXT)
            .map(|(_, y, _)| y)
            .collect();
        assert!(!text_rows.is_empty());
        assert!(text_rows.iter().all(|&y| y >= 60));
        // The 80 px wide picture is too narrow for scale 2: the swatch is drawn at scale 1.
        assert_eq!(count(&img, palette::PATH), 7 * 7);
        // A wide picture keeps scale 2.
        let mut wide =
            Canvas::with_caption(GridGeometry::new(200, 10, 0.1).unwrap(), 2, 1).unwrap();
        wide.caption_legend(0, &[("PATH", palette::PATH)]);
        assert_eq!(count(wide.image(), palette::PATH), 14 * 14);
    }

    #[test]
    fn markers_are_centred() {
        let mut c = Canvas::new(geometry(), 4).unwrap();
        let p = PointM::new(2.0, 1.5);
        for (m, color) in [
            (Marker::Disc, Rgb([1, 0, 0])),
            (Marker::Square, Rgb([2, 0, 0])),
            (Marker::Diamond, Rgb([3, 0, 0])),
            (Marker::Cross, Rgb([4, 0, 0])),
            (Marker::Plus, Rgb([5, 0, 0])),
        ] {
            c.draw_marker(p, m, 10, color);
            let (x, y) = c.to_px(p);
            assert_eq!(*c.image().get_pixel(x as u32, y as u32), color, "{m:?}");
        }
    }
}
