//! [`Plot`]: drawing on one panel of a [`Figure`] in data units.

use image::Rgb;
use tiny_skia::PathBuilder;
use twil_core::grid::Grid;

use super::{finite_px, Figure, Marker, PanelLayout};

/// Drawing on one panel, in its data units (x right, y up), clipped to the plot area.
pub struct Plot<'a> {
    pub(super) fig: &'a mut Figure,
    pub(super) index: usize,
}

impl Plot<'_> {
    fn layout(&self) -> &PanelLayout {
        &self.fig.panels[self.index]
    }

    /// Pixel position (fractional, from the picture's top-left corner) of a data point.
    pub fn to_px(&self, x: f32, y: f32) -> (f32, f32) {
        let l = self.layout();
        (
            l.plot.x0 as f32 + (x - l.spec.x.min) * l.spec.x.px_per_unit,
            l.plot.y1 as f32 - (y - l.spec.y.min) * l.spec.y.px_per_unit,
        )
    }

    /// Pixels per data unit along x.
    pub fn px_per_unit(&self) -> f32 {
        self.layout().spec.x.px_per_unit
    }

    fn pts(&self, points: &[(f32, f32)]) -> Vec<(f32, f32)> {
        points.iter().map(|&(x, y)| self.to_px(x, y)).collect()
    }

    /// Fill the data rectangle `[x0, x1] × [y0, y1]`, snapped to whole pixels (cells).
    pub fn fill_box(&mut self, x0: f32, y0: f32, x1: f32, y1: f32, c: Rgb<u8>, alpha: f32) {
        let (a, b) = (self.to_px(x0, y1), self.to_px(x1, y0));
        if !(finite_px(a.0, a.1) && finite_px(b.0, b.1)) {
            return;
        }
        let clip = self.layout().plot;
        self.fig.blend_px(
            a.0.round() as i32,
            a.1.round() as i32,
            b.0.round() as i32,
            b.1.round() as i32,
            c,
            alpha,
            Some(clip),
        );
    }

    /// Fill every occupied cell of `grid` (its geometry in metres from this panel's origin),
    /// runs of a row at a time.
    pub fn fill_grid<const W: usize>(&mut self, grid: &Grid<W>, c: Rgb<u8>, alpha: f32) {
        let g = *grid.geometry();
        let r = g.resolution_m();
        for y in 0..g.height() {
            let mut x = 0;
            while x < g.width() {
                if !grid.is_occupied_xy(x as i32, y as i32) {
                    x += 1;
                    continue;
                }
                let start = x;
                while x < g.width() && grid.is_occupied_xy(x as i32, y as i32) {
                    x += 1;
                }
                self.fill_box(
                    start as f32 * r,
                    y as f32 * r,
                    x as f32 * r,
                    (y + 1) as f32 * r,
                    c,
                    alpha,
                );
            }
        }
    }

    /// Fill a polygon (even-odd rule).
    pub fn fill_polygon(&mut self, points: &[(f32, f32)], c: Rgb<u8>, alpha: f32) {
        let px = self.pts(points);
        if px.len() < 3 || px.iter().any(|&(x, y)| !finite_px(x, y)) {
            return;
        }
        let mut pb = PathBuilder::new();
        pb.move_to(px[0].0, px[0].1);
        for p in &px[1..] {
            pb.line_to(p.0, p.1);
        }
        pb.close();
        self.fig.fill_path_px(pb, c, alpha, Some(self.index));
    }

    /// A closed outline `width_px` wide.
    pub fn stroke_polygon(&mut self, points: &[(f32, f32)], c: Rgb<u8>, width_px: f32) {
        let mut px = self.pts(points);
        if let Some(first) = px.first().copied() {
            px.push(first);
        }
        self.fig.line_px(&px, c, width_px, 1.0, Some(self.index));
    }

    /// An open polyline `width_px` wide; one point draws a dot.
    pub fn polyline(&mut self, points: &[(f32, f32)], c: Rgb<u8>, width_px: f32) {
        match points {
            [] => {}
            [p] => {
                let (x, y) = self.to_px(p.0, p.1);
                self.fig
                    .disc_px(x, y, (width_px / 2.0).max(1.0), c, 1.0, Some(self.index));
            }
            _ => {
                let px = self.pts(points);
                self.fig.line_px(&px, c, width_px, 1.0, Some(self.index));
            }
        }
    }

    /// Dots of `radius_px` at each point.
    pub fn dots(&mut self, points: &[(f32, f32)], radius_px: f32, c: Rgb<u8>) {
        for &(x, y) in points {
            let (px, py) = self.to_px(x, y);
            self.fig
                .disc_px(px, py, radius_px, c, 1.0, Some(self.index));
        }
    }

    /// A disc of `radius` data units (along x) at `alpha`.
    pub fn disc(&mut self, x: f32, y: f32, radius: f32, c: Rgb<u8>, alpha: f32) {
        let (px, py) = self.to_px(x, y);
        let r = radius * self.px_per_unit();
        self.fig.disc_px(px, py, r, c, alpha, Some(self.index));
    }

    /// A disc `radius_px` pixels across at a data point (joints, arm ends).
    pub fn disc_fixed(&mut self, x: f32, y: f32, radius_px: f32, c: Rgb<u8>) {
        let (px, py) = self.to_px(x, y);
        self.fig
            .disc_px(px, py, radius_px, c, 1.0, Some(self.index));
    }

    /// A circle outline of `radius` data units.
    pub fn circle(&mut self, x: f32, y: f32, radius: f32, c: Rgb<u8>, width_px: f32) {
        let (px, py) = self.to_px(x, y);
        let r = radius * self.px_per_unit();
        self.fig.circle_px(px, py, r, c, width_px, Some(self.index));
    }

    /// A wedge of `radius` data units from `centre`, `half_angle_rad` either side of
    /// `heading_rad` (counter-clockwise from +x; a half angle of π or more is the whole disc),
    /// filled at `alpha`.
    pub fn wedge(
        &mut self,
        centre: (f32, f32),
        radius: f32,
        heading_rad: f32,
        half_angle_rad: f32,
        c: Rgb<u8>,
        alpha: f32,
    ) {
        if !(heading_rad.is_finite() && half_angle_rad.is_finite() && radius.is_finite()) {
            return;
        }
        if half_angle_rad >= std::f32::consts::PI - 1e-3 {
            self.disc(centre.0, centre.1, radius, c, alpha);
            return;
        }
        let steps = 48;
        let mut pts = vec![centre];
        for k in 0..=steps {
            let a = heading_rad - half_angle_rad + 2.0 * half_angle_rad * k as f32 / steps as f32;
            pts.push((centre.0 + radius * a.cos(), centre.1 + radius * a.sin()));
        }
        self.fill_polygon(&pts, c, alpha);
    }

    /// The robot: a translucent disc of `radius`, its outline and a heading line.
    pub fn robot(&mut self, x: f32, y: f32, radius: f32, heading_rad: f32, c: Rgb<u8>) {
        self.disc(x, y, radius, c, 0.35);
        self.circle(x, y, radius, c, 2.0);
        if heading_rad.is_finite() {
            let tip = (
                x + radius * heading_rad.cos(),
                y + radius * heading_rad.sin(),
            );
            self.polyline(&[(x, y), tip], c, 2.5);
        }
    }

    /// A marker `size_px` across at a data point, with a white rim.
    pub fn marker(&mut self, x: f32, y: f32, m: Marker, size_px: f32, c: Rgb<u8>) {
        let (px, py) = self.to_px(x, y);
        self.fig.marker_px(px, py, m, size_px, c, Some(self.index));
    }
}
