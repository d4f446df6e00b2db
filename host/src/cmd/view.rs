//! `twil view`: draw what a recording (`--record FILE.mcap`) held at a mission time, without
//! the Foxglove app.
//!
//! ```text
//! twil view out/office.mcap --png out/office-view.png [--at 120]
//! ```
//!
//! It reads the file back with the `mcap` crate and decodes each message with the Foxglove
//! SDK's own types (`crate::record::read`), then draws it with the picture module: the robot's
//! map, the real and known obstacles, the trail, the last plan and kept prefix, the last sweep's
//! hits (and the earlier ones, faint), the band it covered, the robot, start and goal. What the
//! recording does not carry (the space the sonar has seen) is not drawn.
//!
//! Exit status: 0 when the picture was written; 1 on errors (unreadable file, no message
//! before `--at`).

use std::path::PathBuf;

use anyhow::{bail, Context, Result};

use crate::picture::{
    self, over_white, palette, Figure, FigureSpec, LegendEntry, Mark, Marker, PanelSpec,
    BAND_ALPHA, REAL_ALPHA,
};
use crate::record::read::{self, RecordedState};

/// Opacity of the earlier sweeps' hits over white (the last sweep's are opaque).
const FAINT_HITS_ALPHA: f32 = 0.35;

/// Arguments of `twil view`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// The recording (`--record FILE.mcap` of `twil simulate`, `mission` or `plan`).
    #[arg(value_name = "FILE.mcap")]
    pub recording: PathBuf,
    /// Draw to this PNG file.
    #[arg(long, value_name = "OUT.png")]
    pub png: PathBuf,
    /// Mission time to draw, seconds (default: the end of the recording).
    #[arg(long, value_name = "SECONDS")]
    pub at: Option<f32>,
    /// Pixels per cell (default: about 800 px for the map's longer side).
    #[arg(long, value_name = "PX")]
    pub scale: Option<u32>,
    /// Print one JSON object (what was drawn) instead of the summary.
    #[arg(long)]
    pub json: bool,
}

/// The picture of `state`, named `name` in the caption.
pub fn figure(state: &RecordedState, name: &str, px_per_cell: Option<u32>) -> Result<Figure> {
    let Some(map) = &state.map else {
        bail!(
            "the recording has no /map before {:.1} s: nothing to draw on",
            state.t_s
        );
    };
    let g = *map.geometry();
    let scale = px_per_cell.unwrap_or_else(|| picture::fit_px_per_cell(g, 800));
    let status = state.status.as_ref();
    let caption = vec![
        format!(
            "{name} · a twil recording read back · t = {:.1} s of {:.1} s",
            state.t_s, state.end_s
        ),
        match status {
            Some(s) => format!(
                "phase {} · status {} · plans {} · stops {}{}",
                s.phase,
                s.status,
                s.plans,
                s.stops,
                if s.event.is_empty() {
                    String::new()
                } else {
                    format!(" · last event: {}", s.event)
                }
            ),
            None => "no /status message yet".into(),
        },
    ];
    let mut legend = vec![
        LegendEntry::new("start", Mark::Marker(Marker::Disc, palette::START)),
        LegendEntry::new("goal", Mark::Marker(Marker::Diamond, palette::GOAL)),
    ];
    if state.body_radius_m.is_some() && !state.trail.is_empty() {
        legend.push(LegendEntry::new("robot", Mark::Robot(palette::ROBOT)));
        legend.push(LegendEntry::new("trail", Mark::Line(palette::TRAIL, 2.0)));
    }
    legend.push(LegendEntry::new("plan", Mark::Line(palette::PLAN, 1.5)));
    if !state.prefix.is_empty() {
        legend.push(LegendEntry::new(
            "kept prefix",
            Mark::Line(palette::PREFIX, 3.0),
        ));
    }
    if !state.known.is_empty() {
        legend.push(LegendEntry::new(
            "known obstacles",
            Mark::Outline(palette::KNOWN),
        ));
    }
    if !state.real.is_empty() {
        legend.push(LegendEntry::new(
            "real obstacles",
            Mark::FillOutline(over_white(palette::REAL, REAL_ALPHA), palette::REAL),
        ));
    }
    legend.push(LegendEntry::new(
        "robot's map (grown)",
        Mark::Fill(palette::MAP),
    ));
    if !state.last_hits.is_empty() {
        legend.push(LegendEntry::new(
            "sonar hits (last sweep)",
            Mark::Dots(palette::HITS),
        ));
    }
    // Every earlier sweep's hits, faint: the pink streaks along the walls.
    if !state.hits.is_empty() {
        legend.push(LegendEntry::new(
            "sonar hits (earlier sweeps)",
            Mark::Dots(over_white(palette::HITS, FAINT_HITS_ALPHA)),
        ));
    }
    if !state.band.is_empty() {
        legend.push(LegendEntry::new(
            "last swept band, to the sonar range",
            Mark::Fill(over_white(palette::BAND, BAND_ALPHA)),
        ));
    }
    let mut fig = Figure::new(&FigureSpec {
        caption,
        caption_lines: None,
        panels: vec![PanelSpec::map(g, scale, None)],
        panels_per_row: None,
        legend,
    })
    .with_context(|| format!("--scale {scale}: the picture"))?;
    let mut plot = fig.plot(0).context("picture: no plot")?;
    let ends: Vec<_> = state
        .start
        .iter()
        .chain(state.goal.iter())
        .copied()
        .collect();
    for polygon in &state.real {
        if !picture::encloses(polygon, &ends) {
            plot.fill_polygon(&picture::points(polygon), palette::REAL, REAL_ALPHA);
        }
    }
    plot.fill_grid(map.as_ref(), palette::MAP, 1.0);
    for polygon in &state.real {
        plot.stroke_polygon(&picture::points(polygon), palette::REAL, 1.0);
    }
    for polygon in &state.known {
        plot.stroke_polygon(&picture::points(polygon), palette::KNOWN, 1.5);
    }
    if !state.band.is_empty() {
        plot.fill_polygon(&picture::points(&state.band), palette::BAND, BAND_ALPHA);
    }
    let faint = over_white(palette::HITS, FAINT_HITS_ALPHA);
    plot.dots(&picture::points(&state.hits), 1.5, faint);
    let trail: Vec<(f32, f32)> = state.trail.iter().map(|p| (p.x_m, p.y_m)).collect();
    plot.polyline(&picture::points(&state.plan), palette::PLAN, 1.5);
    plot.polyline(&trail, palette::TRAIL, 2.0);
    plot.polyline(&picture::points(&state.prefix), palette::PREFIX, 3.0);
    plot.dots(&picture::points(&state.last_hits), 2.0, palette::HITS);
    if let Some(p) = state.start {
        plot.marker(p.x_m, p.y_m, Marker::Disc, 11.0, palette::START);
    }
    if let Some(p) = state.goal {
        plot.marker(p.x_m, p.y_m, Marker::Diamond, 12.0, palette::GOAL);
    }
    if let (Some(r), Some(pose)) = (state.body_radius_m, state.trail.last()) {
        plot.robot(pose.x_m, pose.y_m, r, pose.heading_rad, palette::ROBOT);
    }
    Ok(fig)
}

/// Run `twil view`.
pub fn run(args: Args) -> Result<crate::exit::Ending> {
    if let Some(at) = args.at {
        if !(at.is_finite() && at >= 0.0) {
            bail!("--at {at}: a mission time is a number of seconds, 0 or more");
        }
    }
    let state = read::read(&args.recording, args.at)?;
    let name = args
        .recording
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    figure(&state, &name, args.scale)?.save_png(&args.png)?;
    if args.json {
        let json = serde_json::json!({
            "t_s": (state.t_s as f64 * 1000.0).round() / 1000.0,
            "end_s": (state.end_s as f64 * 1000.0).round() / 1000.0,
            "messages": state.messages,
            "poses": state.trail.len(),
            "plan_points": state.plan.len(),
            "prefix_points": state.prefix.len(),
            "hits": state.hits.len(),
            "status": state.status.as_ref().map(|s| s.status.clone()),
            "png": args.png.display().to_string(),
        });
        println!("{json}");
    } else {
        // An `--at` past the end draws the end: say so rather than let the time pass as read.
        let past_end = match args.at {
            Some(at) if at > state.end_s => {
                format!(" (--at {at} is past the end: the end is drawn)")
            }
            _ => String::new(),
        };
        println!(
            "{}: t = {:.1} s of {:.1} s{past_end}, {} messages, {} poses; picture: {}",
            args.recording.display(),
            state.t_s,
            state.end_s,
            state.messages,
            state.trail.len(),
            args.png.display()
        );
    }
    Ok(crate::exit::Ending::Done)
}
