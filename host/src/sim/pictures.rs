//! The pictures of `twil simulate --out` and `twil mission --out`: `plan-NNN.png` (one per
//! plan) and `mission.gif`, drawn by [`crate::picture`].
//!
//! Each picture shows, back to front: the space the sonar has seen free (light blue), the real
//! obstacles (faint grey; the robot does not know them until its sonar hits them), the robot's
//! map (obstacles grown by the planning radius, light orange), the real outlines, the
//! `--known` polygons (dark outlines), the band the latest sweep covered (translucent yellow,
//! out to the sonar range, at the robot's pose) and the sonar range (purple circle), the full
//! plan (light blue), the trail (green), the kept prefix (dark blue), the latest sweep's hits
//! (red), start, goal and the robot (orange disc, physical radius, heading line). The caption
//! says world, mode, planner, time, stop and plan counts and why the plan was made.

use std::path::Path;

use anyhow::{Context, Result};
use image::{Rgb, RgbImage};

use super::{SimResult, SimSetup, SimStatus, Snapshot};
use crate::picture::animation::GifWriter;
use crate::picture::{
    self, over_white, palette, Figure, FigureSpec, LegendEntry, Mark, Marker, PanelSpec,
    BAND_ALPHA, REAL_ALPHA,
};
use twil_core::mission::MissionMode;

/// Most frames in `mission.gif`.
pub const MAX_GIF_FRAMES: usize = 200;
/// Caption lines of every GIF frame (one size for the whole animation).
const GIF_CAPTION_LINES: usize = 4;

/// A world's name for the captions: the real world's file name, and the known one's.
pub fn world_name(real: Option<&Path>, known: Option<&Path>) -> String {
    let name = |p: &Path| {
        p.file_name().map_or_else(
            || p.display().to_string(),
            |n| n.to_string_lossy().into_owned(),
        )
    };
    let mut s = real.map_or_else(|| "the device's world".to_string(), name);
    if let Some(k) = known {
        s.push_str(&format!(" (known before the start: {})", name(k)));
    }
    s
}

/// Which kind of picture a snapshot is drawn for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Frame {
    /// `plan-NNN.png`: the snapshot taken when plan N was made.
    Plan,
    /// A frame of `mission.gif`; `last` is the final state.
    Animation {
        /// The mission's final frame.
        last: bool,
    },
}

/// The legend of every picture of a run (the same for all frames, so GIF frames keep their
/// size): every mark the run's pictures can show.
pub fn legend(setup: &SimSetup, result: &SimResult) -> Vec<LegendEntry> {
    let all = || result.plans.iter().chain(&result.frames);
    let mut l = vec![
        LegendEntry::new("start", Mark::Marker(Marker::Disc, palette::START)),
        LegendEntry::new("goal", Mark::Marker(Marker::Diamond, palette::GOAL)),
        LegendEntry::new("robot", Mark::Robot(palette::ROBOT)),
        LegendEntry::new("trail", Mark::Line(palette::TRAIL, 2.0)),
        LegendEntry::new("plan", Mark::Line(palette::PLAN, 1.5)),
        LegendEntry::new("kept prefix", Mark::Line(palette::PREFIX, 3.0)),
    ];
    if setup.known.is_some() {
        l.push(LegendEntry::new(
            "known obstacles",
            Mark::Outline(palette::KNOWN),
        ));
    }
    l.push(LegendEntry::new(
        "real obstacles",
        Mark::FillOutline(over_white(palette::REAL, REAL_ALPHA), palette::REAL),
    ));
    l.push(LegendEntry::new(
        "robot's map (grown)",
        Mark::Fill(palette::MAP),
    ));
    l.push(LegendEntry::new("sonar hits", Mark::Dots(palette::HITS)));
    if all().any(|s| s.seen.is_some()) {
        l.push(LegendEntry::new("seen space", Mark::Fill(palette::SEEN)));
    }
    if all().any(|s| s.band.is_some()) {
        let standing = setup.robot.normal_half_sweep_deg;
        let moving = setup.moving_half_sweep_deg;
        let label = if setup.mode == MissionMode::Continuous && moving != standing {
            format!("swept band (±{standing:.0}° stopped, ±{moving:.0}° moving, full ±180°)")
        } else {
            format!("swept band (±{standing:.0}°, full ±180°)")
        };
        l.push(LegendEntry::new(
            label,
            Mark::Fill(over_white(palette::BAND, BAND_ALPHA)),
        ));
    }
    l.push(LegendEntry::new(
        format!("sonar range {:.1} m", setup.robot.sonar_range_m),
        Mark::Ring(palette::RANGE),
    ));
    l
}

fn mode_name(mode: MissionMode) -> &'static str {
    match mode {
        MissionMode::Stop => "stop-and-sweep",
        MissionMode::Continuous => "continuous",
    }
}

/// The caption of a snapshot.
pub fn caption(setup: &SimSetup, result: &SimResult, snap: &Snapshot, frame: Frame) -> Vec<String> {
    let head = format!(
        "{} · {} mode · planner {}",
        setup.world_name,
        mode_name(setup.mode),
        setup.planner.as_str(),
    );
    let counts = match frame {
        Frame::Plan => format!(
            "t = {:.1} s · stops so far: {} · plan {} of {}",
            snap.t_s, snap.stops, snap.plan_number, result.stats.plans
        ),
        Frame::Animation { .. } => format!(
            "t = {:.1} s · stops so far: {} · plans so far: {}",
            snap.t_s, snap.stops, snap.plans
        ),
    };
    let why = match snap.reason {
        Some(r) => r.text().to_string(),
        None if snap.plans == 0 => "no plan yet: the robot is sweeping at the start".into(),
        None => "not reported by the device".into(),
    };
    let mut second = match frame {
        Frame::Plan => format!("Why plan {}: {why}.", snap.plan_number),
        Frame::Animation { .. } if snap.plans == 0 => format!("{why}."),
        Frame::Animation { .. } => format!("Latest plan ({}): {why}.", snap.plans),
    };
    if snap.path.is_empty() && snap.plans > 0 {
        second.push_str(" No path: the goal is unreachable on the robot's map.");
    }
    if frame == (Frame::Animation { last: true }) {
        second.push_str(&format!(" Mission ended: {}.", status_text(result.status)));
    }
    vec![head, counts, second]
}

fn status_text(s: SimStatus) -> &'static str {
    s.name()
}

/// Draw one snapshot (see the module documentation).
pub fn snapshot_figure(
    setup: &SimSetup,
    result: &SimResult,
    snap: &Snapshot,
    px_per_cell: u32,
    frame: Frame,
) -> Result<Figure> {
    let mut fig = Figure::new(&FigureSpec {
        caption: caption(setup, result, snap, frame),
        caption_lines: match frame {
            Frame::Plan => None,
            Frame::Animation { .. } => Some(GIF_CAPTION_LINES),
        },
        panels: vec![PanelSpec::map(setup.geometry, px_per_cell, None)],
        panels_per_row: None,
        legend: legend(setup, result),
    })
    .context("picture")?;
    let mut plot = fig.plot(0).context("picture: no plot")?;
    if let Some(seen) = &snap.seen {
        plot.fill_grid(seen.as_ref(), palette::SEEN, 1.0);
    }
    let ends = [setup.params.start, setup.params.goal];
    for polygon in setup.real.iter() {
        if !picture::encloses(polygon, &ends) {
            plot.fill_polygon(&picture::points(polygon), palette::REAL, REAL_ALPHA);
        }
    }
    plot.fill_grid(snap.grid.as_ref(), palette::MAP, 1.0);
    for polygon in setup.real.iter() {
        plot.stroke_polygon(&picture::points(polygon), palette::REAL, 1.0);
    }
    if let Some(known) = &setup.known {
        for polygon in known.iter() {
            plot.stroke_polygon(&picture::points(polygon), palette::KNOWN, 1.5);
        }
    }
    let (x, y, heading) = (snap.pose.x_m, snap.pose.y_m, snap.pose.heading_rad);
    let range_m = setup.robot.sonar_range_m;
    if let Some(band) = snap.band {
        plot.wedge(
            (x, y),
            range_m,
            heading,
            band.half_angle_deg.to_radians(),
            palette::BAND,
            BAND_ALPHA,
        );
    }
    plot.circle(x, y, range_m, palette::RANGE, 2.0);
    let trail: Vec<(f32, f32)> = result.trajectory[..snap.trail_len.min(result.trajectory.len())]
        .iter()
        .map(|r| (r.pose.x_m, r.pose.y_m))
        .collect();
    plot.polyline(&picture::points(&snap.path), palette::PLAN, 1.5);
    plot.polyline(&trail, palette::TRAIL, 2.0);
    plot.polyline(&picture::points(&snap.prefix), palette::PREFIX, 3.0);
    plot.dots(&picture::points(&snap.hits), 2.0, palette::HITS);
    let p = &setup.params;
    plot.marker(p.start.x_m, p.start.y_m, Marker::Disc, 11.0, palette::START);
    plot.marker(p.goal.x_m, p.goal.y_m, Marker::Diamond, 12.0, palette::GOAL);
    let radius_m = p.robot_radius_m - twil_core::robot::PLANNING_MARGIN_M;
    plot.robot(x, y, radius_m.max(0.05), heading, palette::ROBOT);
    Ok(fig)
}

/// Draw one snapshot as an image.
pub fn render_snapshot(
    setup: &SimSetup,
    result: &SimResult,
    snap: &Snapshot,
    px_per_cell: u32,
) -> Result<RgbImage> {
    Ok(snapshot_figure(setup, result, snap, px_per_cell, Frame::Plan)?.to_image())
}

/// Write `plan-NNN.png` for every plan snapshot.
pub fn write_plan_pngs(dir: &Path, setup: &SimSetup, result: &SimResult) -> Result<usize> {
    for (i, snap) in result.plans.iter().enumerate() {
        let fig = snapshot_figure(setup, result, snap, 2, Frame::Plan)?;
        let path = dir.join(format!("plan-{:03}.png", i + 1));
        fig.save_png(&path)?;
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

/// Every colour a mark is drawn in (kept exact in the GIF's palette).
fn key_colors() -> Vec<Rgb<u8>> {
    use palette::*;
    vec![
        BACKGROUND,
        TEXT,
        AXIS,
        GRID_LINES,
        SCALE_BAR,
        LEGEND_BORDER,
        MAP,
        REAL,
        over_white(REAL, REAL_ALPHA),
        KNOWN,
        SEEN,
        PLAN,
        PREFIX,
        TRAIL,
        HITS,
        ROBOT,
        START,
        GOAL,
        over_white(BAND, BAND_ALPHA),
        RANGE,
    ]
}

/// Write `mission.gif`: at most [`MAX_GIF_FRAMES`] frames of the mission at `px_per_cell`.
pub fn write_gif(
    path: &Path,
    setup: &SimSetup,
    result: &SimResult,
    px_per_cell: u32,
) -> Result<()> {
    let picked = pick_frames(result.frames.len(), MAX_GIF_FRAMES);
    let render = |n: usize| -> Result<Figure> {
        let i = picked[n];
        let last = n + 1 == picked.len();
        snapshot_figure(
            setup,
            result,
            &result.frames[i],
            px_per_cell,
            Frame::Animation { last },
        )
    };
    let (Some(_), Some(last_n)) = (picked.first(), picked.len().checked_sub(1)) else {
        anyhow::bail!("{}: no frame to write", path.display());
    };
    let first = render(0)?;
    let last = render(last_n)?;
    let mut gif = GifWriter::create(path, &[&first.to_image(), &last.to_image()], &key_colors())?;
    for n in 0..picked.len() {
        // 10 ms units; hold the last frame.
        let delay = if n == last_n { 300 } else { 8 };
        if n == 0 {
            gif.add_figure(&first, delay)?;
        } else if n == last_n {
            gif.add_figure(&last, delay)?;
        } else {
            gif.add_figure(&render(n)?, delay)?;
        }
    }
    gif.finish()
}
