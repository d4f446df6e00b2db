//! Pictures of the manipulator planner: the configuration map with the path (PNG) and the arm
//! moving along the path in its workspace (GIF), side by side as in the thesis' figures 4.5/4.6.
//!
//! Drawing happens on an indexed canvas with a fixed palette, so the same pixels go to the PNG
//! (through `image`) and to the GIF frames (through `gif`, no colour quantization).

use std::io::Write;

use anyhow::Context;
use twil_core::cspace::{
    geometry::{Frame, WorkPoint},
    map::{arm_frames, ConfigMap, Occupancy},
    rob::{Polygon, Robot},
};

/// Palette entries.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Ink {
    /// Background.
    White = 0,
    /// Text, frames, axes.
    Black,
    /// Map cells where arm 1 collides.
    Arm1Cell,
    /// Map cells where arm 2 collides.
    Arm2Cell,
    /// Our path.
    Path,
    /// Start marker.
    Start,
    /// Goal marker.
    Goal,
    /// A compared path (the thesis' one).
    Compare,
    /// Obstacles in the workspace.
    Obstacle,
    /// Arm 1 in the workspace.
    Arm1,
    /// Arm 2 (or the moving object) in the workspace.
    Arm2,
    /// Earlier arm positions (ghosts).
    Ghost,
    /// Light grid / frame lines.
    Light,
    /// Outline of earlier arm positions.
    GhostEdge,
}

/// RGB of each [`Ink`], in order.
pub const PALETTE: [[u8; 3]; 14] = [
    [255, 255, 255],
    [20, 20, 20],
    [150, 170, 205],
    [95, 95, 110],
    [215, 30, 30],
    [20, 150, 40],
    [30, 70, 220],
    [245, 150, 20],
    [70, 70, 80],
    [60, 120, 200],
    [30, 160, 150],
    [200, 200, 210],
    [225, 225, 225],
    [150, 150, 165],
];

/// An indexed image.
#[derive(Clone)]
pub struct Canvas {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// Palette index per pixel, row-major.
    pub pixels: Vec<u8>,
    /// Drawing is limited to `[x0, x1) × [y0, y1)` when set.
    pub clip: Option<(i64, i64, i64, i64)>,
}

impl Canvas {
    /// A white canvas.
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            pixels: vec![Ink::White as u8; width as usize * height as usize],
            clip: None,
        }
    }

    /// Set one pixel (ignored outside).
    pub fn put(&mut self, x: i64, y: i64, ink: Ink) {
        if let Some((x0, y0, x1, y1)) = self.clip {
            if x < x0 || x >= x1 || y < y0 || y >= y1 {
                return;
            }
        }
        if x >= 0 && y >= 0 && (x as u32) < self.width && (y as u32) < self.height {
            self.pixels[y as usize * self.width as usize + x as usize] = ink as u8;
        }
    }

    /// Fill a rectangle `[x0, x1) × [y0, y1)`.
    pub fn rect(&mut self, x0: i64, y0: i64, x1: i64, y1: i64, ink: Ink) {
        for y in y0..y1 {
            for x in x0..x1 {
                self.put(x, y, ink);
            }
        }
    }

    /// A rectangle outline.
    pub fn frame(&mut self, x0: i64, y0: i64, x1: i64, y1: i64, ink: Ink) {
        self.line(x0 as f32, y0 as f32, x1 as f32, y0 as f32, 1, ink);
        self.line(x0 as f32, y1 as f32, x1 as f32, y1 as f32, 1, ink);
        self.line(x0 as f32, y0 as f32, x0 as f32, y1 as f32, 1, ink);
        self.line(x1 as f32, y0 as f32, x1 as f32, y1 as f32, 1, ink);
    }

    /// A line of `width` pixels.
    pub fn line(&mut self, x0: f32, y0: f32, x1: f32, y1: f32, width: i64, ink: Ink) {
        let n = ((x1 - x0).abs().max((y1 - y0).abs()).ceil() as i64).clamp(1, 100_000);
        let r0 = -(width - 1) / 2;
        let r1 = width / 2;
        for k in 0..=n {
            let t = k as f32 / n as f32;
            let x = (x0 + (x1 - x0) * t).round() as i64;
            let y = (y0 + (y1 - y0) * t).round() as i64;
            for dy in r0..=r1 {
                for dx in r0..=r1 {
                    self.put(x + dx, y + dy, ink);
                }
            }
        }
    }

    /// A filled disc.
    pub fn disc(&mut self, cx: f32, cy: f32, radius: f32, ink: Ink) {
        let r = radius.ceil() as i64;
        let (x0, y0) = (cx.round() as i64, cy.round() as i64);
        for dy in -r..=r {
            for dx in -r..=r {
                if ((dx * dx + dy * dy) as f32) <= radius * radius {
                    self.put(x0 + dx, y0 + dy, ink);
                }
            }
        }
    }

    /// Fill a convex polygon given in pixels (scanline: the span between the edges' crossings).
    pub fn fill_convex(&mut self, pts: &[(f32, f32)], ink: Ink) {
        if pts.len() < 3 {
            return;
        }
        let ymin = pts
            .iter()
            .map(|p| p.1)
            .fold(f32::INFINITY, f32::min)
            .floor() as i64;
        let ymax = pts
            .iter()
            .map(|p| p.1)
            .fold(f32::NEG_INFINITY, f32::max)
            .ceil() as i64;
        for y in ymin.max(0)..=ymax.min(self.height as i64) {
            let yc = y as f32 + 0.5;
            let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
            for i in 0..pts.len() {
                let (a, b) = (pts[i], pts[(i + 1) % pts.len()]);
                if (a.1 <= yc && b.1 > yc) || (b.1 <= yc && a.1 > yc) {
                    let x = a.0 + (yc - a.1) / (b.1 - a.1) * (b.0 - a.0);
                    lo = lo.min(x);
                    hi = hi.max(x);
                }
            }
            if lo <= hi {
                for x in lo.round() as i64..=hi.round() as i64 {
                    self.put(x, y, ink);
                }
            }
        }
    }

    /// Draw text with the built-in 3×5 font, `scale` pixels per font pixel, top-left at (x, y).
    pub fn text(&mut self, x: i64, y: i64, scale: i64, s: &str, ink: Ink) {
        let mut cx = x;
        for c in s.chars() {
            let glyph = glyph(c);
            for (row, bits) in glyph.iter().enumerate() {
                for col in 0..3 {
                    if bits & (0b100 >> col) != 0 {
                        self.rect(
                            cx + col * scale,
                            y + row as i64 * scale,
                            cx + (col + 1) * scale,
                            y + (row as i64 + 1) * scale,
                            ink,
                        );
                    }
                }
            }
            cx += 4 * scale;
        }
    }

    /// Copy another canvas into this one at (x, y).
    pub fn blit(&mut self, other: &Canvas, x: i64, y: i64) {
        for oy in 0..other.height as i64 {
            for ox in 0..other.width as i64 {
                let p = other.pixels[oy as usize * other.width as usize + ox as usize];
                if x + ox >= 0
                    && y + oy >= 0
                    && ((x + ox) as u32) < self.width
                    && ((y + oy) as u32) < self.height
                {
                    self.pixels[(y + oy) as usize * self.width as usize + (x + ox) as usize] = p;
                }
            }
        }
    }

    /// The RGB image.
    pub fn to_rgb(&self) -> image::RgbImage {
        image::RgbImage::from_fn(self.width, self.height, |x, y| {
            let i = self.pixels[y as usize * self.width as usize + x as usize] as usize;
            image::Rgb(PALETTE.get(i).copied().unwrap_or([255, 0, 255]))
        })
    }
}

/// A 3×5 bitmap glyph (rows top to bottom, 3 bits each, high bit left).
fn glyph(c: char) -> [u8; 5] {
    match c.to_ascii_lowercase() {
        '0' => [7, 5, 5, 5, 7],
        '1' => [2, 6, 2, 2, 7],
        '2' => [7, 1, 7, 4, 7],
        '3' => [7, 1, 7, 1, 7],
        '4' => [5, 5, 7, 1, 1],
        '5' => [7, 4, 7, 1, 7],
        '6' => [7, 4, 7, 5, 7],
        '7' => [7, 1, 2, 2, 2],
        '8' => [7, 5, 7, 5, 7],
        '9' => [7, 5, 7, 1, 7],
        '-' => [0, 0, 7, 0, 0],
        '.' => [0, 0, 0, 0, 2],
        ',' => [0, 0, 0, 2, 4],
        ':' => [0, 2, 0, 2, 0],
        '=' => [0, 7, 0, 7, 0],
        '(' => [2, 4, 4, 4, 2],
        ')' => [2, 1, 1, 1, 2],
        '/' => [1, 1, 2, 4, 4],
        'a' => [2, 5, 7, 5, 5],
        'b' => [6, 5, 6, 5, 6],
        'c' => [7, 4, 4, 4, 7],
        'd' => [6, 5, 5, 5, 6],
        'e' => [7, 4, 6, 4, 7],
        'f' => [7, 4, 6, 4, 4],
        'g' => [7, 4, 5, 5, 7],
        'h' => [5, 5, 7, 5, 5],
        'i' => [7, 2, 2, 2, 7],
        'j' => [1, 1, 1, 5, 7],
        'k' => [5, 5, 6, 5, 5],
        'l' => [4, 4, 4, 4, 7],
        'm' => [5, 7, 7, 5, 5],
        'n' => [6, 5, 5, 5, 5],
        'o' => [7, 5, 5, 5, 7],
        'p' => [7, 5, 7, 4, 4],
        'q' => [7, 5, 5, 7, 1],
        'r' => [6, 5, 6, 5, 5],
        's' => [7, 4, 7, 1, 7],
        't' => [7, 2, 2, 2, 2],
        'u' => [5, 5, 5, 5, 7],
        'v' => [5, 5, 5, 5, 2],
        'w' => [5, 5, 7, 7, 5],
        'x' => [5, 5, 2, 5, 5],
        'y' => [5, 5, 2, 2, 2],
        'z' => [7, 1, 2, 4, 7],
        _ => [0, 0, 0, 0, 0],
    }
}

/// Margins around a panel's plot area, pixels.
const MARGIN: i64 = 34;
/// Font scale of labels.
const FONT: i64 = 2;

/// What to draw.
pub struct Scene<'a> {
    /// The robot (obstacles and arms).
    pub robot: &'a Robot,
    /// The configuration map.
    pub map: &'a ConfigMap,
    /// Our path, joint values, start first (may be empty).
    pub path: &'a [[f32; 2]],
    /// Requested start and goal, joint values.
    pub start: [f32; 2],
    /// Goal.
    pub goal: [f32; 2],
    /// Another path to show in the map (the thesis' one), joint values.
    pub compare: Option<&'a [[f32; 2]]>,
    /// Texts written above the map, right-aligned, with their colours.
    pub legend: Vec<(String, Ink)>,
}

/// The map panel: cells, path, markers, axis labels.
struct MapPanel {
    canvas: Canvas,
    cell_px: f32,
    min: [f32; 2],
    inc: [f32; 2],
    rows: f32,
    /// Joint range of a full turn for wrapping joints.
    period: [Option<f32>; 2],
    /// The plot area, pixels.
    area: (i64, i64, i64, i64),
}

impl MapPanel {
    fn new(scene: &Scene<'_>, target_h: u32) -> Self {
        let (nc, nl) = scene.map.size();
        let cell_px = ((target_h as f32 - 2.0 * MARGIN as f32) / nl as f32)
            .min(900.0 / nc as f32)
            .max(1.0)
            .floor();
        let w = (nc as f32 * cell_px) as i64 + 2 * MARGIN;
        let h = (nl as f32 * cell_px) as i64 + 2 * MARGIN;
        let mut canvas = Canvas::new(w as u32, h as u32);
        let axes = scene.map.axes();
        for j in 0..nl as i32 {
            for i in 0..nc as i32 {
                let ink = match scene.map.occupancy(i, j) {
                    Occupancy::Free => continue,
                    Occupancy::Arm1 => Ink::Arm1Cell,
                    Occupancy::Arm2 => Ink::Arm2Cell,
                };
                let x0 = MARGIN + (i as f32 * cell_px) as i64;
                let y0 = MARGIN + ((nl as i32 - 1 - j) as f32 * cell_px) as i64;
                canvas.rect(x0, y0, x0 + cell_px as i64, y0 + cell_px as i64, ink);
            }
        }
        canvas.frame(MARGIN - 1, MARGIN - 1, w - MARGIN, h - MARGIN, Ink::Black);
        let mut panel = MapPanel {
            canvas,
            cell_px,
            min: [axes[0].min, axes[1].min],
            inc: [axes[0].increment, axes[1].increment],
            rows: nl as f32,
            period: [0, 1].map(|k| {
                axes[k]
                    .wraps
                    .then(|| axes[k].cells as f32 * axes[k].increment)
            }),
            area: (MARGIN, MARGIN, w - MARGIN, h - MARGIN),
        };
        // Axis labels: joint ranges.
        let j1 = &scene.robot.joints[0];
        let j2 = &scene.robot.joints[1];
        let last = [axes[0].value(nc as i32 - 1), axes[1].value(nl as i32 - 1)];
        panel.canvas.text(
            MARGIN,
            h - MARGIN + 6,
            FONT,
            &fmt_num(axes[0].min),
            Ink::Black,
        );
        let label = format!("joint 1 ({})", j1.unit());
        panel.canvas.text(
            (w - 4 * FONT * label.len() as i64) / 2,
            h - MARGIN + 6,
            FONT,
            &label,
            Ink::Black,
        );
        let s = fmt_num(last[0]);
        panel.canvas.text(
            w - MARGIN - 4 * FONT * s.len() as i64,
            h - MARGIN + 6,
            FONT,
            &s,
            Ink::Black,
        );
        panel.canvas.text(
            2,
            h - MARGIN - 5 * FONT,
            FONT,
            &fmt_num(axes[1].min),
            Ink::Black,
        );
        panel
            .canvas
            .text(2, MARGIN, FONT, &fmt_num(last[1]), Ink::Black);
        let label = format!("joint 2 ({})", j2.unit());
        panel.canvas.text(MARGIN, 8, FONT, &label, Ink::Black);
        panel
    }

    fn px(&self, q: [f32; 2]) -> (f32, f32) {
        let i = (q[0] - self.min[0]) / self.inc[0];
        let j = (q[1] - self.min[1]) / self.inc[1];
        (
            MARGIN as f32 + (i + 0.5) * self.cell_px,
            MARGIN as f32 + (self.rows - 1.0 - j + 0.5) * self.cell_px,
        )
    }

    /// Copies of `q` shifted by whole turns of the wrapping joints that may show on the map.
    fn images(&self, q: [f32; 2]) -> Vec<[f32; 2]> {
        let shifts = |k: usize| -> Vec<f32> {
            match self.period[k] {
                Some(p) => {
                    // Bring q into the first turn, then also one turn either side.
                    let turns = ((q[k] - self.min[k]) / p).floor();
                    let base = -turns * p;
                    vec![base - p, base, base + p]
                }
                None => vec![0.0],
            }
        };
        let mut out = Vec::new();
        for dx in shifts(0) {
            for dy in shifts(1) {
                out.push([dx, dy]);
            }
        }
        out
    }

    /// Draw a joint-space polyline, clipped to the map; across the seam of a wrapping joint it
    /// continues on the other side.
    fn polyline(&mut self, path: &[[f32; 2]], width: i64, ink: Ink) {
        let saved = self.canvas.clip;
        self.canvas.clip = Some(self.area);
        for w in path.windows(2) {
            for d in self.images(w[0]) {
                let a = self.px([w[0][0] + d[0], w[0][1] + d[1]]);
                let b = self.px([w[1][0] + d[0], w[1][1] + d[1]]);
                self.canvas.line(a.0, a.1, b.0, b.1, width, ink);
            }
        }
        for q in path {
            let p = self.px(self.wrapped(*q));
            self.canvas.disc(p.0, p.1, width as f32 * 0.9, ink);
        }
        self.canvas.clip = saved;
    }

    /// `q` brought into the first turn of each wrapping joint.
    fn wrapped(&self, q: [f32; 2]) -> [f32; 2] {
        let mut q = q;
        for ((v, min), period) in q.iter_mut().zip(self.min).zip(self.period) {
            if let Some(p) = period {
                *v = min + (*v - min).rem_euclid(p);
            }
        }
        q
    }
}

fn fmt_num(v: f32) -> String {
    if (v - v.round()).abs() < 1e-3 {
        format!("{}", v.round() as i64)
    } else {
        format!("{v:.1}")
    }
}

/// The workspace panel: world-to-pixel transform.
struct WorkPanel {
    width: u32,
    height: u32,
    lo: WorkPoint,
    hi: WorkPoint,
    scale: f32,
}

impl WorkPanel {
    fn new(scene: &Scene<'_>, height: u32) -> Self {
        // Bounds: obstacles and the arm at the path's points and the map's extreme values.
        let mut pts: Vec<WorkPoint> = scene.robot.obstacles.iter().flatten().copied().collect();
        let axes = scene.map.axes();
        let (nc, nl) = scene.map.size();
        let mut configs: Vec<[f32; 2]> = resample(scene.path, 120);
        for i in [0, nc as i32 / 2, nc as i32 - 1] {
            for j in [0, nl as i32 / 2, nl as i32 - 1] {
                configs.push([axes[0].value(i), axes[1].value(j)]);
            }
        }
        configs.push(scene.start);
        configs.push(scene.goal);
        for q in &configs {
            for (k, f) in arm_frames(scene.robot, *q).iter().enumerate() {
                for poly in &scene.robot.joints[k].polygons {
                    pts.extend(poly.iter().map(|p| f.apply(*p)));
                }
                pts.push(f.origin());
            }
        }
        pts.push(WorkPoint::new(0.0, 0.0));
        let lo = WorkPoint::new(
            pts.iter().map(|p| p.x).fold(f32::INFINITY, f32::min),
            pts.iter().map(|p| p.y).fold(f32::INFINITY, f32::min),
        );
        let hi = WorkPoint::new(
            pts.iter().map(|p| p.x).fold(f32::NEG_INFINITY, f32::max),
            pts.iter().map(|p| p.y).fold(f32::NEG_INFINITY, f32::max),
        );
        let span_x = (hi.x - lo.x).max(1e-3);
        let span_y = (hi.y - lo.y).max(1e-3);
        let scale = (height as f32 - 2.0 * MARGIN as f32) / span_y;
        let width = (span_x * scale) as u32 + 2 * MARGIN as u32;
        Self {
            width,
            height,
            lo,
            hi,
            scale,
        }
    }

    fn px(&self, p: WorkPoint) -> (f32, f32) {
        (
            MARGIN as f32 + (p.x - self.lo.x) * self.scale,
            MARGIN as f32 + (self.hi.y - p.y) * self.scale,
        )
    }

    fn polygon(&self, c: &mut Canvas, poly: &Polygon, frame: &Frame, ink: Ink, outline: Ink) {
        let pts: Vec<(f32, f32)> = poly.iter().map(|p| self.px(frame.apply(*p))).collect();
        match pts.len() {
            0 => {}
            1 => c.disc(pts[0].0, pts[0].1, 2.5, ink),
            2 => c.line(pts[0].0, pts[0].1, pts[1].0, pts[1].1, 3, ink),
            n => {
                c.fill_convex(&pts, ink);
                for i in 0..n {
                    let (a, b) = (pts[i], pts[(i + 1) % n]);
                    c.line(a.0, a.1, b.0, b.1, 1, outline);
                }
            }
        }
    }

    fn background(&self, scene: &Scene<'_>) -> Canvas {
        let mut c = Canvas::new(self.width, self.height);
        for o in &scene.robot.obstacles {
            self.polygon(&mut c, o, &Frame::IDENTITY, Ink::Obstacle, Ink::Black);
        }
        c.text(MARGIN, 8, FONT, "workspace", Ink::Black);
        c
    }

    fn arm(&self, c: &mut Canvas, scene: &Scene<'_>, q: [f32; 2], ghost: bool) {
        let frames = arm_frames(scene.robot, q);
        let base = self.px(WorkPoint::new(0.0, 0.0));
        let j1 = self.px(frames[0].origin());
        let j2 = self.px(frames[1].origin());
        for (k, f) in frames.iter().enumerate() {
            let ink = match (ghost, k) {
                (true, _) => Ink::Ghost,
                (false, 0) => Ink::Arm1,
                (false, _) => Ink::Arm2,
            };
            let outline = if ghost { Ink::GhostEdge } else { Ink::Black };
            for poly in &scene.robot.joints[k].polygons {
                self.polygon(c, poly, f, ink, outline);
            }
        }
        if !ghost {
            // Joints that move a visible arm, and the far end of arm 2 (whose trail is drawn).
            if !scene.robot.joints[0].polygons.is_empty() {
                c.disc(base.0, base.1, 2.5, Ink::Black);
            }
            if !scene.robot.joints[0].polygons.is_empty() {
                c.disc(j1.0, j1.1, 2.5, Ink::Black);
            }
            c.disc(j2.0, j2.1, 2.5, Ink::Path);
        }
    }

    fn trail(&self, c: &mut Canvas, scene: &Scene<'_>, configs: &[[f32; 2]]) {
        let pts: Vec<(f32, f32)> = configs
            .iter()
            .map(|q| self.px(arm_frames(scene.robot, *q)[1].origin()))
            .collect();
        for w in pts.windows(2) {
            c.line(w[0].0, w[0].1, w[1].0, w[1].1, 2, Ink::Path);
        }
    }
}

/// Configurations evenly spaced along a polyline in joint space (the thesis' simulator divides
/// the path into intervals of equal length), `frames` of them, both ends included.
pub fn resample(path: &[[f32; 2]], frames: usize) -> Vec<[f32; 2]> {
    if path.len() < 2 || frames < 2 {
        return path.to_vec();
    }
    let seg: Vec<f32> = path
        .windows(2)
        .map(|w| ((w[1][0] - w[0][0]).powi(2) + (w[1][1] - w[0][1]).powi(2)).sqrt())
        .collect();
    let total: f32 = seg.iter().sum();
    let mut out = Vec::with_capacity(frames);
    for k in 0..frames {
        let mut s = total * k as f32 / (frames - 1) as f32;
        let mut idx = 0;
        while idx + 1 < seg.len() && s > seg[idx] {
            s -= seg[idx];
            idx += 1;
        }
        let t = if seg[idx] > 0.0 {
            (s / seg[idx]).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let (a, b) = (path[idx], path[idx + 1]);
        out.push([a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t]);
    }
    out
}

/// Height of both panels, pixels.
const PANEL_H: u32 = 420;

fn map_panel(scene: &Scene<'_>) -> MapPanel {
    let mut panel = MapPanel::new(scene, PANEL_H);
    panel.polyline(scene.path, 3, Ink::Path);
    if let Some(c) = scene.compare {
        panel.polyline(c, 1, Ink::Compare);
    }
    let mut x = panel.canvas.width as i64 - MARGIN;
    for (text, ink) in scene.legend.iter().rev() {
        x -= 4 * FONT * text.len() as i64;
        panel.canvas.text(x, 8, FONT, text, *ink);
        x -= 4 * FONT * 2;
    }
    let s = panel.px(panel.wrapped(scene.start));
    panel.canvas.disc(s.0, s.1, 5.0, Ink::Start);
    let g = panel.px(panel.wrapped(scene.goal));
    panel.canvas.disc(g.0, g.1, 5.0, Ink::Goal);
    panel
}

/// The still picture: map with path (left), workspace with the arm along the path (right).
pub fn picture(scene: &Scene<'_>) -> Canvas {
    let map = map_panel(scene);
    let work = WorkPanel::new(scene, PANEL_H.max(map.canvas.height));
    let mut right = work.background(scene);
    let samples = resample(scene.path, 7);
    for q in samples.iter().skip(1).take(samples.len().saturating_sub(2)) {
        work.arm(&mut right, scene, *q, true);
    }
    work.trail(&mut right, scene, &resample(scene.path, 200));
    if let Some(first) = scene.path.first() {
        work.arm(&mut right, scene, *first, false);
    }
    if let Some(last) = scene.path.last() {
        work.arm(&mut right, scene, *last, false);
    }
    if scene.path.is_empty() {
        work.arm(&mut right, scene, scene.start, false);
    }
    side_by_side(&map.canvas, &right)
}

fn side_by_side(a: &Canvas, b: &Canvas) -> Canvas {
    let mut c = Canvas::new(a.width + b.width, a.height.max(b.height));
    c.blit(a, 0, 0);
    c.blit(b, a.width as i64, 0);
    c.line(
        a.width as f32,
        0.0,
        a.width as f32,
        c.height as f32,
        1,
        Ink::Light,
    );
    c
}

/// Write the still picture as PNG.
pub fn write_png(scene: &Scene<'_>, path: &std::path::Path) -> anyhow::Result<()> {
    picture(scene)
        .to_rgb()
        .save_with_format(path, image::ImageFormat::Png)
        .with_context(|| format!("writing {}", path.display()))
}

/// Write the animation: the arm moving along the path, with its point in the map.
pub fn write_gif(scene: &Scene<'_>, frames: usize, path: &std::path::Path) -> anyhow::Result<()> {
    let map = map_panel(scene);
    let work = WorkPanel::new(scene, PANEL_H.max(map.canvas.height));
    let background = work.background(scene);
    let configs = if scene.path.is_empty() {
        vec![scene.start]
    } else {
        resample(scene.path, frames.max(2))
    };
    let width = map.canvas.width + work.width;
    let height = map.canvas.height.max(work.height);
    let (Ok(w16), Ok(h16)) = (u16::try_from(width), u16::try_from(height)) else {
        anyhow::bail!("picture of {width}x{height} pixels is too large for a GIF");
    };
    let palette: Vec<u8> = PALETTE.iter().flatten().copied().collect();
    let file =
        std::fs::File::create(path).with_context(|| format!("creating {}", path.display()))?;
    let mut out = std::io::BufWriter::new(file);
    {
        let mut enc = gif::Encoder::new(&mut out, w16, h16, &palette)
            .with_context(|| format!("writing {}", path.display()))?;
        enc.set_repeat(gif::Repeat::Infinite)?;
        for (k, q) in configs.iter().enumerate() {
            let mut left = map.canvas.clone();
            let p = map.px(map.wrapped(*q));
            left.disc(p.0, p.1, 4.0, Ink::Black);
            let mut right = background.clone();
            work.trail(&mut right, scene, &configs[..=k]);
            work.arm(&mut right, scene, *q, false);
            let c = side_by_side(&left, &right);
            let mut frame = gif::Frame::from_indexed_pixels(w16, h16, c.pixels, None);
            frame.delay = if k == 0 || k + 1 == configs.len() {
                120
            } else {
                6
            };
            enc.write_frame(&frame)
                .with_context(|| format!("writing {}", path.display()))?;
        }
    }
    out.flush()
        .with_context(|| format!("writing {}", path.display()))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resampling_keeps_ends_and_spaces_evenly() {
        let path = [[0.0, 0.0], [3.0, 0.0], [3.0, 1.0]];
        let r = resample(&path, 5);
        assert_eq!(r.len(), 5);
        assert_eq!(r[0], [0.0, 0.0]);
        assert_eq!(r[4], [3.0, 1.0]);
        assert_eq!(r[1], [1.0, 0.0]);
        assert_eq!(r[3], [3.0, 0.0]);
    }

    #[test]
    fn convex_fill_covers_the_inside_only() {
        let mut c = Canvas::new(20, 20);
        c.fill_convex(
            &[(2.0, 2.0), (12.0, 2.0), (12.0, 12.0), (2.0, 12.0)],
            Ink::Black,
        );
        assert_eq!(c.pixels[5 * 20 + 5], Ink::Black as u8);
        assert_eq!(c.pixels[15 * 20 + 15], Ink::White as u8);
    }
}
