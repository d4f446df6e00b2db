//! Pictures of the manipulator planner, drawn by [`crate::picture`]: the configuration map
//! with the path (left panel, joint units) and the arm moving along the path in its workspace
//! (right panel, workspace units), side by side as in the thesis' figures 4.5/4.6; a still PNG
//! and a GIF of the arm moving.

use std::path::Path;

use anyhow::Context;
use image::Rgb;
use twil_core::cspace::{
    geometry::{Frame, WorkPoint},
    map::{arm_frames, ConfigMap, Occupancy},
    rob::{JointKind, Polygon, Robot},
};

use crate::picture::animation::GifWriter;
use crate::picture::{
    palette, Axis, Figure, FigureSpec, LegendEntry, Mark, Marker, PanelSpec, Plot,
};

/// Our path in the map and the arm end's trail.
pub const PATH: Rgb<u8> = Rgb([215, 30, 30]);
/// The current configuration in the GIF's map.
pub const CURRENT: Rgb<u8> = Rgb([20, 20, 20]);

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
    /// The `.ROB` file's name, for the caption.
    pub name: String,
    /// The search's verdict and length, e.g. `found, length 370.94`.
    pub result: String,
    /// The compared path's label, e.g. `thesis' path 371.3`.
    pub compare_label: Option<String>,
}

/// Height of the configuration map's plot, pixels (about).
const MAP_H_PX: f32 = 360.0;
/// Widest configuration map plot, pixels.
const MAP_W_PX: f32 = 560.0;

fn unit(kind: JointKind) -> &'static str {
    match kind {
        JointKind::Rotational => "°",
        JointKind::Prismatic => "units",
    }
}

/// Joint ranges of a wrapping joint: one turn.
fn period(map: &ConfigMap, k: usize) -> Option<f32> {
    let a = &map.axes()[k];
    a.wraps.then_some(a.cells as f32 * a.increment)
}

/// The configuration map panel: each value's cell centred on it.
fn map_panel(scene: &Scene<'_>) -> PanelSpec {
    let axes = scene.map.axes();
    let (nc, nl) = scene.map.size();
    let cell_px = (MAP_H_PX / nl.max(1) as f32)
        .min(MAP_W_PX / nc.max(1) as f32)
        .floor()
        .max(1.0);
    let axis = |k: usize, n: u16, label: &str| {
        let a = &axes[k];
        Axis {
            min: a.min - a.increment / 2.0,
            max: a.value(n as i32 - 1) + a.increment / 2.0,
            px_per_unit: cell_px / a.increment,
            title: format!("{label} ({})", scene.robot.joints[k].unit()),
        }
    };
    PanelSpec {
        x: axis(0, nc, "joint 1"),
        y: axis(1, nl, "joint 2"),
        unit: unit(scene.robot.joints[0].kind).into(),
        title: Some("configuration map".into()),
    }
}

/// Bounds of the workspace: obstacles and the arm at the path's points and the map's corners.
fn work_bounds(scene: &Scene<'_>) -> (WorkPoint, WorkPoint) {
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
    let finite = || pts.iter().filter(|p| p.x.is_finite() && p.y.is_finite());
    let lo = WorkPoint::new(
        finite().map(|p| p.x).fold(f32::INFINITY, f32::min),
        finite().map(|p| p.y).fold(f32::INFINITY, f32::min),
    );
    let hi = WorkPoint::new(
        finite().map(|p| p.x).fold(f32::NEG_INFINITY, f32::max),
        finite().map(|p| p.y).fold(f32::NEG_INFINITY, f32::max),
    );
    // A margin of 3 % so that outlines are not cut by the frame.
    let m = 0.03 * (hi.x - lo.x).max(hi.y - lo.y).max(1e-3);
    (
        WorkPoint::new(lo.x - m, lo.y - m),
        WorkPoint::new(hi.x + m, hi.y + m),
    )
}

fn work_panel(scene: &Scene<'_>, plot_h_px: f32) -> PanelSpec {
    let (lo, hi) = work_bounds(scene);
    let span_y = (hi.y - lo.y).max(1e-3);
    let s = plot_h_px / span_y;
    let axis = |min: f32, max: f32, title: &str| Axis {
        min,
        max: max.max(min + 1e-3),
        px_per_unit: s,
        title: title.into(),
    };
    PanelSpec {
        x: axis(lo.x, hi.x, "x (units)"),
        y: axis(lo.y, hi.y, "y (units)"),
        unit: "units".into(),
        title: Some("workspace".into()),
    }
}

fn has_cells(map: &ConfigMap, which: Occupancy) -> bool {
    let (nc, nl) = map.size();
    (0..nl as i32).any(|j| (0..nc as i32).any(|i| map.occupancy(i, j) == which))
}

/// The legend's words for the cells where link 1 and link 2 collide: an arm's, or, with two
/// prismatic joints (the thesis' navigation case), a moving object's (link 2 is the object,
/// link 1 the slide that carries it).
fn collision_labels(robot: &Robot) -> [&'static str; 2] {
    let prismatic = robot
        .joints
        .iter()
        .all(|j| j.kind == twil_core::cspace::rob::JointKind::Prismatic);
    if prismatic {
        ["the slide collides", "the object collides"]
    } else {
        ["arm 1 collides", "arm 2 collides"]
    }
}

fn legend(scene: &Scene<'_>, animated: bool) -> Vec<LegendEntry> {
    let mut l = Vec::new();
    let [arm1, arm2] = collision_labels(scene.robot);
    if has_cells(scene.map, Occupancy::Arm1) {
        l.push(LegendEntry::new(arm1, Mark::Fill(palette::ARM1_CELL)));
    }
    if has_cells(scene.map, Occupancy::Arm2) {
        l.push(LegendEntry::new(arm2, Mark::Fill(palette::ARM2_CELL)));
    }
    l.push(LegendEntry::new("our path", Mark::Line(PATH, 3.0)));
    if let Some(label) = &scene.compare_label {
        l.push(LegendEntry::new(
            label.clone(),
            Mark::Line(palette::COMPARE, 1.5),
        ));
    }
    l.push(LegendEntry::new(
        "start",
        Mark::Marker(Marker::Disc, palette::START),
    ));
    l.push(LegendEntry::new(
        "goal",
        Mark::Marker(Marker::Diamond, palette::GOAL),
    ));
    if animated {
        l.push(LegendEntry::new(
            "current configuration",
            Mark::Marker(Marker::Square, CURRENT),
        ));
    }
    if !scene.robot.obstacles.is_empty() {
        l.push(LegendEntry::new(
            "obstacles",
            Mark::FillOutline(palette::OBSTACLE, palette::OUTLINE),
        ));
    }
    if !scene.robot.joints[0].polygons.is_empty() {
        l.push(LegendEntry::new("arm 1", Mark::Fill(palette::ARM1)));
    }
    let second = if scene.robot.joints[0].polygons.is_empty() {
        "moving object"
    } else {
        "arm 2"
    };
    l.push(LegendEntry::new(second, Mark::Fill(palette::ARM2)));
    if !animated {
        l.push(LegendEntry::new(
            "earlier positions",
            Mark::Fill(palette::GHOST),
        ));
    }
    l.push(LegendEntry::new(
        format!("{second}'s end: trail"),
        Mark::Line(PATH, 2.0),
    ));
    l
}

fn caption(scene: &Scene<'_>) -> Vec<String> {
    let q = |q: [f32; 2]| format!("({}, {})", fmt_num(q[0]), fmt_num(q[1]));
    vec![
        format!(
            "{} · twil cspace (arm planner: no stops, 1 plan) · any-angle A* over the corners of the collision regions · {}",
            scene.name, scene.result
        ),
        format!(
            "Why this plan: the least joint movement √(Δq₁² + Δq₂²) from start {} to goal {} on the configuration map.",
            q(scene.start),
            q(scene.goal)
        ),
    ]
}

fn fmt_num(v: f32) -> String {
    if (v - v.round()).abs() < 1e-3 {
        format!("{}", v.round() as i64)
    } else {
        format!("{v:.1}")
    }
}

fn figure(scene: &Scene<'_>, animated: bool) -> anyhow::Result<Figure> {
    let map = map_panel(scene);
    let plot_h = (map.y.max - map.y.min) * map.y.px_per_unit;
    let work = work_panel(scene, plot_h);
    let fig = Figure::new(&FigureSpec {
        caption: caption(scene),
        caption_lines: None,
        panels: vec![map, work],
        panels_per_row: None,
        legend: legend(scene, animated),
    })?;
    Ok(fig)
}

/// Copies of `q` shifted by whole turns of the wrapping joints that may show on the map.
fn images(map: &ConfigMap, q: [f32; 2]) -> Vec<[f32; 2]> {
    let axes = map.axes();
    let shifts = |k: usize| -> Vec<f32> {
        match period(map, k) {
            Some(p) => {
                let turns = ((q[k] - axes[k].min) / p).floor();
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

/// `q` brought into the first turn of each wrapping joint.
fn wrapped(map: &ConfigMap, q: [f32; 2]) -> [f32; 2] {
    let axes = map.axes();
    let mut q = q;
    for (k, v) in q.iter_mut().enumerate() {
        if let Some(p) = period(map, k) {
            *v = axes[k].min + (*v - axes[k].min).rem_euclid(p);
        }
    }
    q
}

/// A joint-space polyline; across the seam of a wrapping joint it continues on the other side
/// (the plot clips what lies off the map).
fn joint_polyline(plot: &mut Plot<'_>, map: &ConfigMap, path: &[[f32; 2]], c: Rgb<u8>, w: f32) {
    for seg in path.windows(2) {
        for d in images(map, seg[0]) {
            plot.polyline(
                &[
                    (seg[0][0] + d[0], seg[0][1] + d[1]),
                    (seg[1][0] + d[0], seg[1][1] + d[1]),
                ],
                c,
                w,
            );
        }
    }
    for q in path {
        let p = wrapped(map, *q);
        plot.disc_fixed(p[0], p[1], w * 0.9, c);
    }
}

/// The map panel's data: collision cells, paths, start and goal.
fn draw_map(fig: &mut Figure, scene: &Scene<'_>) -> anyhow::Result<()> {
    let mut plot = fig.plot(0).context("picture: no map plot")?;
    let axes = scene.map.axes();
    let (nc, nl) = scene.map.size();
    let (h0, h1) = (axes[0].increment / 2.0, axes[1].increment / 2.0);
    for j in 0..nl as i32 {
        for i in 0..nc as i32 {
            let c = match scene.map.occupancy(i, j) {
                Occupancy::Free => continue,
                Occupancy::Arm1 => palette::ARM1_CELL,
                Occupancy::Arm2 => palette::ARM2_CELL,
            };
            let (x, y) = (axes[0].value(i), axes[1].value(j));
            plot.fill_box(x - h0, y - h1, x + h0, y + h1, c, 1.0);
        }
    }
    joint_polyline(&mut plot, scene.map, scene.path, PATH, 3.0);
    if let Some(c) = scene.compare {
        joint_polyline(&mut plot, scene.map, c, palette::COMPARE, 1.5);
    }
    let s = wrapped(scene.map, scene.start);
    plot.marker(s[0], s[1], Marker::Disc, 11.0, palette::START);
    let g = wrapped(scene.map, scene.goal);
    plot.marker(g[0], g[1], Marker::Diamond, 12.0, palette::GOAL);
    Ok(())
}

fn work_polygon(plot: &mut Plot<'_>, poly: &Polygon, frame: &Frame, c: Rgb<u8>, edge: Rgb<u8>) {
    let pts: Vec<(f32, f32)> = poly
        .iter()
        .map(|p| {
            let w = frame.apply(*p);
            (w.x, w.y)
        })
        .collect();
    match pts.len() {
        0 => {}
        1 => plot.disc_fixed(pts[0].0, pts[0].1, 2.5, c),
        2 => plot.polyline(&pts, c, 3.0),
        _ => {
            plot.fill_polygon(&pts, c, 1.0);
            plot.stroke_polygon(&pts, edge, 1.0);
        }
    }
}

fn draw_obstacles(plot: &mut Plot<'_>, scene: &Scene<'_>) {
    for o in &scene.robot.obstacles {
        work_polygon(
            plot,
            o,
            &Frame::IDENTITY,
            palette::OBSTACLE,
            palette::OUTLINE,
        );
    }
}

fn draw_arm(plot: &mut Plot<'_>, scene: &Scene<'_>, q: [f32; 2], ghost: bool) {
    let frames = arm_frames(scene.robot, q);
    for (k, f) in frames.iter().enumerate() {
        let (c, edge) = match (ghost, k) {
            (true, _) => (palette::GHOST, palette::REAL),
            (false, 0) => (palette::ARM1, palette::OUTLINE),
            (false, _) => (palette::ARM2, palette::OUTLINE),
        };
        for poly in &scene.robot.joints[k].polygons {
            work_polygon(plot, poly, f, c, edge);
        }
    }
    if !ghost {
        // Joints that move a visible arm, and the far end of arm 2 (whose trail is drawn).
        if !scene.robot.joints[0].polygons.is_empty() {
            plot.disc_fixed(0.0, 0.0, 2.5, palette::TEXT);
            let j1 = frames[0].origin();
            plot.disc_fixed(j1.x, j1.y, 2.5, palette::TEXT);
        }
        let j2 = frames[1].origin();
        plot.disc_fixed(j2.x, j2.y, 2.5, PATH);
    }
}

fn draw_trail(plot: &mut Plot<'_>, scene: &Scene<'_>, configs: &[[f32; 2]]) {
    let pts: Vec<(f32, f32)> = configs
        .iter()
        .map(|q| {
            let o = arm_frames(scene.robot, *q)[1].origin();
            (o.x, o.y)
        })
        .collect();
    plot.polyline(&pts, PATH, 2.0);
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

/// The still picture: map with path (left), workspace with the arm along the path (right).
pub fn picture(scene: &Scene<'_>) -> anyhow::Result<Figure> {
    let mut fig = figure(scene, false)?;
    draw_map(&mut fig, scene)?;
    let mut plot = fig.plot(1).context("picture: no workspace plot")?;
    draw_obstacles(&mut plot, scene);
    let samples = resample(scene.path, 7);
    for q in samples.iter().skip(1).take(samples.len().saturating_sub(2)) {
        draw_arm(&mut plot, scene, *q, true);
    }
    draw_trail(&mut plot, scene, &resample(scene.path, 200));
    if let Some(first) = scene.path.first() {
        draw_arm(&mut plot, scene, *first, false);
    }
    if let Some(last) = scene.path.last() {
        draw_arm(&mut plot, scene, *last, false);
    }
    if scene.path.is_empty() {
        draw_arm(&mut plot, scene, scene.start, false);
    }
    Ok(fig)
}

/// Write the still picture as PNG.
pub fn write_png(scene: &Scene<'_>, path: &Path) -> anyhow::Result<()> {
    picture(scene)?.save_png(path)?;
    Ok(())
}

fn gif_frame(scene: &Scene<'_>, configs: &[[f32; 2]], k: usize) -> anyhow::Result<Figure> {
    let mut fig = figure(scene, true)?;
    draw_map(&mut fig, scene)?;
    let q = configs[k];
    {
        let mut plot = fig.plot(0).context("picture: no map plot")?;
        let p = wrapped(scene.map, q);
        plot.marker(p[0], p[1], Marker::Square, 9.0, CURRENT);
    }
    let mut plot = fig.plot(1).context("picture: no workspace plot")?;
    draw_obstacles(&mut plot, scene);
    draw_trail(&mut plot, scene, &configs[..=k]);
    draw_arm(&mut plot, scene, q, false);
    Ok(fig)
}

/// Write the animation: the arm moving along the path, with its configuration in the map.
pub fn write_gif(scene: &Scene<'_>, frames: usize, path: &Path) -> anyhow::Result<()> {
    let configs = if scene.path.is_empty() {
        vec![scene.start]
    } else {
        resample(scene.path, frames.max(2))
    };
    let last_k = configs.len() - 1;
    let first = gif_frame(scene, &configs, 0)?;
    let last = gif_frame(scene, &configs, last_k)?;
    let keys = [
        palette::BACKGROUND,
        palette::TEXT,
        palette::AXIS,
        palette::SCALE_BAR,
        palette::ARM1_CELL,
        palette::ARM2_CELL,
        PATH,
        palette::COMPARE,
        palette::START,
        palette::GOAL,
        CURRENT,
        palette::OBSTACLE,
        palette::ARM1,
        palette::ARM2,
    ];
    let mut gif = GifWriter::create(path, &[&first.to_image(), &last.to_image()], &keys)?;
    for k in 0..configs.len() {
        let delay = if k == 0 || k == last_k { 120 } else { 6 };
        if k == 0 {
            gif.add_figure(&first, delay)?;
        } else if k == last_k {
            gif.add_figure(&last, delay)?;
        } else {
            gif.add_figure(&gif_frame(scene, &configs, k)?, delay)?;
        }
    }
    gif.finish()
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
    fn both_panels_have_scale_bars_in_their_units_and_the_legend_shows_every_mark() {
        let rob = format!("{}/../worlds/seed000-nav.ROB", env!("CARGO_MANIFEST_DIR"));
        let robot = crate::cspace::load::load_robot(Path::new(&rob)).unwrap();
        let map = ConfigMap::build(&robot, [2.0, 2.0]).unwrap();
        let path = [[-60.0, -35.0], [40.0, 97.0], [140.0, -5.0]];
        let compare = [[-60.0, -35.0], [140.0, -5.0]];
        let scene = Scene {
            robot: &robot,
            map: &map,
            path: &path,
            start: path[0],
            goal: path[2],
            compare: Some(&compare),
            name: "nav".into(),
            result: "found".into(),
            compare_label: Some("compared path".into()),
        };
        let fig = picture(&scene).unwrap();
        let img = fig.to_image();
        let count = |r: crate::picture::PxRect, c: Rgb<u8>| {
            (r.y0..r.y1)
                .flat_map(|y| (r.x0..r.x1).map(move |x| (x, y)))
                .filter(|&(x, y)| img.get_pixel(x as u32, y as u32) == &c)
                .count()
        };
        // Map: 173 x 111 values at 3 px a cell, 2 units a cell: 1.5 px per unit, bar 50
        // units = 75 px. Workspace: its own scale; both bars in SCALE_BAR, nothing else is.
        let map_bar = fig.scale_bar(0).unwrap();
        assert_eq!(map_bar.length, 50.0);
        assert_eq!(map_bar.rect.x1 - map_bar.rect.x0, 75);
        let work_bar = fig.scale_bar(1).unwrap();
        let mut fig = fig;
        let s = fig.plot(1).unwrap().px_per_unit();
        assert_eq!(
            (work_bar.rect.x1 - work_bar.rect.x0) as f32,
            (work_bar.length * s).round()
        );
        let bar_px: usize = [map_bar, work_bar]
            .iter()
            .map(|b| count(b.rect, palette::SCALE_BAR))
            .sum();
        assert_eq!(
            img.pixels().filter(|p| **p == palette::SCALE_BAR).count(),
            bar_px
        );
        assert!(bar_px > 0);
        let entries = legend(&scene, false);
        assert!(entries.len() >= 8);
        for (e, sw) in entries.iter().zip(fig.legend_swatches()) {
            let grown = crate::picture::PxRect {
                x0: sw.x0 - 3,
                y0: sw.y0 - 3,
                x1: sw.x1 + 3,
                y1: sw.y1 + 3,
            };
            assert!(fig.legend_box().contains(sw.x0, sw.y0));
            assert!(count(grown, e.mark.color()) >= 3, "{}", e.label);
        }
        // The map's collision cells and our path are drawn in the map panel.
        let plot = fig.plot_rect(0).unwrap();
        assert!(count(plot, palette::ARM2_CELL) > 1000);
        assert!(count(plot, PATH) > 50);
    }
}
