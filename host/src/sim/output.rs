//! Files written by `twil simulate --out DIR`: `trajectory.csv`, one PNG per plan,
//! `mission.gif` and `summary.json`.

use std::collections::HashMap;
use std::fs;
use std::io::{BufWriter, Write};
use std::path::Path;

use anyhow::{Context, Result};
use image::{Rgb, RgbImage};
use twil_core::geom::PointM;
use twil_core::grid::GridGeometry;

use super::{SimResult, SimSetup, Snapshot};
use crate::render::{palette, Canvas, Marker};

/// Most frames in `mission.gif`.
pub const MAX_GIF_FRAMES: usize = 200;

const OCCUPIED: Rgb<u8> = Rgb([250, 200, 150]);
const REAL: Rgb<u8> = Rgb([120, 120, 130]);
const REAL_OUTLINE: Rgb<u8> = Rgb([90, 90, 100]);
const KNOWN_OUTLINE: Rgb<u8> = Rgb([40, 40, 40]);
const PATH: Rgb<u8> = Rgb([120, 160, 255]);
const PREFIX: Rgb<u8> = Rgb([0, 90, 230]);
const TRAIL: Rgb<u8> = Rgb([0, 150, 60]);
const HITS: Rgb<u8> = Rgb([230, 30, 30]);
const ROBOT: Rgb<u8> = Rgb([255, 150, 0]);
const START: Rgb<u8> = Rgb([0, 160, 0]);
const GOAL: Rgb<u8> = Rgb([200, 0, 200]);

/// Write `trajectory.csv`, one row per controller period (per pose report for
/// `twil mission`): time, true pose, then the controller's signals of the period that ended
/// at `t` (the reference point handed to the controller, wheel speed references, motor
/// voltages) and the mission's phase after it. A signal the source does not carry
/// (`twil mission` telemetry has no references) is an empty field.
pub fn write_trajectory_csv(path: &Path, result: &SimResult) -> Result<()> {
    use twil_core::mission::MissionPhase;
    /// A phase as one CSV word.
    fn phase_word(phase: MissionPhase) -> &'static str {
        match phase {
            MissionPhase::Sweep { full: true } => "full_sweep",
            MissionPhase::Sweep { full: false } => "sweep",
            MissionPhase::Follow => "follow",
            MissionPhase::Settle => "settle",
            MissionPhase::Plan => "plan",
            MissionPhase::Done => "done",
        }
    }
    let file =
        fs::File::create(path).with_context(|| format!("{}: cannot create", path.display()))?;
    let mut w = BufWriter::new(file);
    writeln!(
        w,
        "t,x,y,theta,ref_x,ref_y,left_speed_ref_rad_s,right_speed_ref_rad_s,left_v,right_v,phase"
    )?;
    let opt = |v: Option<f32>| v.map_or(String::new(), |v| format!("{v:.4}"));
    for row in &result.trajectory {
        let c = &row.control;
        writeln!(
            w,
            "{:.3},{:.4},{:.4},{:.4},{},{},{},{},{:.3},{:.3},{}",
            row.t_s,
            row.pose.x_m,
            row.pose.y_m,
            row.pose.heading_rad,
            opt(c.reference.map(|p| p.x_m)),
            opt(c.reference.map(|p| p.y_m)),
            opt(c.speed_ref_rad_s.map(|s| s.0)),
            opt(c.speed_ref_rad_s.map(|s| s.1)),
            c.left_voltage_v,
            c.right_voltage_v,
            row.phase.map_or("", phase_word),
        )?;
    }
    w.flush()
        .with_context(|| format!("{}: cannot write", path.display()))?;
    Ok(())
}

/// Draw one snapshot: the real polygons faint, the robot's map (expanded obstacles), the known
/// polygons as outlines, the full path, the kept prefix, the latest hits, the trail, start,
/// goal and the robot, with a caption line.
pub fn render_snapshot(
    setup: &SimSetup,
    result: &SimResult,
    snap: &Snapshot,
    px_per_cell: u32,
) -> Result<RgbImage> {
    let geometry: GridGeometry = setup.geometry;
    let mut canvas = Canvas::with_caption(geometry, px_per_cell, 2)
        .map_err(|e| anyhow::anyhow!("picture: {e}"))?;
    canvas.set_opacity(0.35);
    canvas.fill_polygons(&setup.real, REAL);
    canvas.set_opacity(1.0);
    canvas.draw_grid(&snap.grid, OCCUPIED);
    canvas.set_opacity(0.5);
    canvas.draw_polygons(&setup.real, REAL_OUTLINE, 1.0);
    canvas.set_opacity(1.0);
    if let Some(known) = &setup.known {
        canvas.draw_polygons(known, KNOWN_OUTLINE, 1.0);
    }
    let trail: Vec<PointM> = result.trajectory[..snap.trail_len.min(result.trajectory.len())]
        .iter()
        .map(|r| PointM::new(r.pose.x_m, r.pose.y_m))
        .collect();
    canvas.draw_polyline(&snap.path, PATH, 1.0);
    canvas.draw_polyline(&trail, TRAIL, 1.5);
    canvas.draw_polyline(&snap.prefix, PREFIX, 2.5);
    canvas.draw_points(&snap.hits, 1.5, HITS);
    canvas.draw_marker(setup.params.start, Marker::Disc, 9, START);
    canvas.draw_marker(setup.params.goal, Marker::Diamond, 11, GOAL);
    let radius_m = setup.params.robot_radius_m - twil_core::robot::PLANNING_MARGIN_M;
    canvas.draw_robot(
        PointM::new(snap.pose.x_m, snap.pose.y_m),
        radius_m.max(0.05),
        snap.pose.heading_rad,
        ROBOT,
    );
    let caption = if snap.plan_number > 0 {
        format!("t = {:.1} s   plan {}", snap.t_s, snap.plan_number)
    } else {
        format!("t = {:.1} s", snap.t_s)
    };
    canvas.caption_text(0, &caption, palette::TEXT);
    canvas.caption_legend(
        1,
        &[
            ("map", OCCUPIED),
            ("real", REAL_OUTLINE),
            ("path", PATH),
            ("prefix", PREFIX),
            ("trail", TRAIL),
            ("hits", HITS),
            ("robot", ROBOT),
        ],
    );
    Ok(canvas.into_image())
}

/// Write `plan-NNN.png` for every plan snapshot.
pub fn write_plan_pngs(dir: &Path, setup: &SimSetup, result: &SimResult) -> Result<usize> {
    for (i, snap) in result.plans.iter().enumerate() {
        let image = render_snapshot(setup, result, snap, 2)?;
        let path = dir.join(format!("plan-{:03}.png", i + 1));
        image
            .save(&path)
            .with_context(|| format!("{}: cannot write PNG", path.display()))?;
    }
    Ok(result.plans.len())
}

/// Indices of at most `max` frames, evenly spread, always including the last.
pub fn pick_frames(count: usize, max: usize) -> Vec<usize> {
    if count <= max || max < 2 {
        return (0..count.min(max.max(count))).collect();
    }
    let mut picked: Vec<usize> = (0..max).map(|k| k * (count - 1) / (max - 1)).collect();
    picked.dedup();
    picked
}

/// Write `mission.gif`: at most [`MAX_GIF_FRAMES`] frames of the mission at `px_per_cell`,
/// each with its own palette of the exact colours it uses (the drawing uses few colours, so
/// no quantization is needed).
pub fn write_gif(
    path: &Path,
    setup: &SimSetup,
    result: &SimResult,
    px_per_cell: u32,
) -> Result<()> {
    let picked = pick_frames(result.frames.len(), MAX_GIF_FRAMES);
    let file =
        fs::File::create(path).with_context(|| format!("{}: cannot create", path.display()))?;
    let mut encoder: Option<gif::Encoder<BufWriter<fs::File>>> = None;
    let mut writer = Some(BufWriter::new(file));
    for (n, &i) in picked.iter().enumerate() {
        let image = render_snapshot(setup, result, &result.frames[i], px_per_cell)?;
        let (w, h) = image.dimensions();
        let (w16, h16) = (
            u16::try_from(w).context("GIF frame wider than 65535 px")?,
            u16::try_from(h).context("GIF frame taller than 65535 px")?,
        );
        if encoder.is_none() {
            let sink = writer.take().context("GIF writer already used")?;
            let mut e = gif::Encoder::new(sink, w16, h16, &[])
                .with_context(|| format!("{}: cannot write GIF", path.display()))?;
            e.set_repeat(gif::Repeat::Infinite)?;
            encoder = Some(e);
        }
        let (palette, indices) = index_colours(&image);
        let mut frame = gif::Frame::from_palette_pixels(w16, h16, indices, palette, None);
        // 10 ms units; hold the last frame.
        frame.delay = if n + 1 == picked.len() { 300 } else { 8 };
        if let Some(e) = encoder.as_mut() {
            e.write_frame(&frame)
                .with_context(|| format!("{}: cannot write GIF frame", path.display()))?;
        }
    }
    Ok(())
}

/// A palette of the distinct colours of `image` (at most 256; further colours map to the
/// nearest one) and the index of every pixel.
fn index_colours(image: &RgbImage) -> (Vec<u8>, Vec<u8>) {
    let mut map: HashMap<[u8; 3], u8> = HashMap::new();
    let mut palette: Vec<[u8; 3]> = Vec::new();
    let mut indices = Vec::with_capacity((image.width() * image.height()) as usize);
    for p in image.pixels() {
        let c = p.0;
        let idx = match map.get(&c) {
            Some(&i) => i,
            None if palette.len() < 256 => {
                let i = palette.len() as u8;
                palette.push(c);
                map.insert(c, i);
                i
            }
            None => nearest(&palette, c),
        };
        indices.push(idx);
    }
    (palette.concat(), indices)
}

fn nearest(palette: &[[u8; 3]], c: [u8; 3]) -> u8 {
    let mut best = (u32::MAX, 0u8);
    for (i, p) in palette.iter().enumerate() {
        let d: u32 = (0..3)
            .map(|k| (p[k] as i32 - c[k] as i32).unsigned_abs().pow(2))
            .sum();
        if d < best.0 {
            best = (d, i as u8);
        }
    }
    best.1
}
