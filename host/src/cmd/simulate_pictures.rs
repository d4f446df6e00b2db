//! Tests of `sim::pictures` on a short simulated run set up from `twil simulate`'s own
//! arguments (here, so that `sim` never imports `cmd`).

use super::{setup_from_args, Args};
use crate::picture::{self, palette};
use crate::sim::pictures::*;
use crate::sim::{run as run_sim, NoProgress, SimResult, SimSetup};
use clap::Parser;
use image::{Rgb, RgbImage};
use std::path::Path;

#[derive(Parser)]
struct Cli {
    #[command(flatten)]
    args: Args,
}

fn world(name: &str) -> String {
    format!("{}/../worlds/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// The corridor world in continuous mode with snapshots: a short run.
fn run() -> (SimSetup, SimResult) {
    let cli = Cli::try_parse_from([
        "simulate",
        "--real",
        &world("corridor.da"),
        "--params",
        &world("corridor.par"),
        "--mode",
        "continuous",
        "--out",
        "unused",
    ])
    .unwrap();
    let setup = setup_from_args(&cli.args).unwrap();
    let result = run_sim(&setup, &mut NoProgress).unwrap();
    (setup, result)
}

fn count_in(img: &RgbImage, r: picture::PxRect, c: Rgb<u8>) -> usize {
    (r.y0.max(0)..r.y1.min(img.height() as i32))
        .flat_map(|y| (r.x0.max(0)..r.x1.min(img.width() as i32)).map(move |x| (x, y)))
        .filter(|&(x, y)| img.get_pixel(x as u32, y as u32) == &c)
        .count()
}

#[test]
fn a_plan_picture_has_scale_bar_legend_band_range_and_seen_space() {
    let (setup, result) = run();
    assert!(result.plans.len() >= 2);
    let snap = &result.plans[1];
    let fig = snapshot_figure(&setup, &result, snap, 2, Frame::Plan).unwrap();
    let img = fig.to_image();
    // Scale bar: 1 m at 2 px per 0.05 m cell = 40 px, nothing else in its colour.
    let bar = fig.scale_bar(0).unwrap();
    assert_eq!(bar.length, 1.0);
    assert_eq!(bar.rect.x1 - bar.rect.x0, 40);
    assert_eq!(
        count_in(&img, bar.rect, palette::SCALE_BAR),
        40 * picture::SCALE_BAR_THICKNESS_PX as usize
    );
    // Legend: every mark named, each swatch's colour inside the legend box.
    let entries = legend(&setup, &result);
    let labels: Vec<&str> = entries.iter().map(|e| e.label.as_str()).collect();
    for needle in [
        "start",
        "goal",
        "robot",
        "trail",
        "plan",
        "kept prefix",
        "real obstacles",
        "sonar hits",
        "seen space",
        "swept band",
        "sonar range",
    ] {
        assert!(labels.iter().any(|l| l.starts_with(needle)), "{needle}");
    }
    let lb = fig.legend_box();
    for (e, sw) in entries.iter().zip(fig.legend_swatches()) {
        assert!(lb.contains(sw.x0, sw.y0), "{}", e.label);
        let grown = picture::PxRect {
            x0: sw.x0 - 3,
            y0: sw.y0 - 3,
            x1: sw.x1 + 3,
            y1: sw.y1 + 3,
        };
        assert!(count_in(&img, grown, e.mark.color()) >= 3, "{}", e.label);
    }
    // Seen space is shaded in the map (drawn without the band, which tints most of it).
    let plot = fig.plot_rect(0).unwrap();
    let mut bandless = snap.clone();
    bandless.band = None;
    let plain = snapshot_figure(&setup, &result, &bandless, 2, Frame::Plan)
        .unwrap()
        .to_image();
    let seen_cells = snap.seen.as_ref().unwrap().count_occupied();
    assert!(seen_cells > 100);
    assert!(count_in(&plain, plot, palette::SEEN) > seen_cells);
    // The sonar range circle passes range_m from the robot: look along the four axes.
    let mut fig = fig;
    let p = fig.plot(0).unwrap();
    let (rx, ry) = p.to_px(snap.pose.x_m, snap.pose.y_m);
    let r_px = setup.robot.sonar_range_m * p.px_per_unit();
    let near = |x: f32, y: f32, c: Rgb<u8>| {
        (-2..=2).any(|dy| {
            (-2..=2).any(|dx| {
                let (px, py) = (x as i32 + dx, y as i32 + dy);
                plot.contains(px, py) && img.get_pixel(px as u32, py as u32) == &c
            })
        })
    };
    let on_circle = [(1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0)]
        .iter()
        .filter(|(dx, dy)| near(rx + dx * r_px, ry + dy * r_px, palette::RANGE))
        .count();
    assert!(on_circle >= 2, "range circle not found at {r_px} px");
    // The band: yellow-tinted pixels within the range, ahead of the robot.
    let band = snap.band.unwrap();
    assert!(band.half_angle_deg > 0.0);
    let ahead = (
        rx + 0.6 * r_px * snap.pose.heading_rad.cos(),
        ry - 0.6 * r_px * snap.pose.heading_rad.sin(),
    );
    let px = img.get_pixel(ahead.0 as u32, ahead.1 as u32).0;
    assert!(
        px[2] + 40 < px[0],
        "no band tint ahead of the robot: {px:?}"
    );
    // The caption names world, mode, planner and the reason.
    let text = caption(&setup, &result, snap, Frame::Plan).join(" ");
    for needle in [
        "corridor.da",
        "continuous",
        "anyangle",
        "plan 2 of",
        "Why plan 2",
    ] {
        assert!(text.contains(needle), "{needle} not in {text}");
    }
}

#[test]
fn captions_name_the_world_and_say_when_the_reason_is_unknown() {
    assert_eq!(
        world_name(
            Some(Path::new("worlds/office.da")),
            Some(Path::new("w/office-walls.da"))
        ),
        "office.da (known before the start: office-walls.da)"
    );
    assert_eq!(world_name(None, None), "the device's world");
    let (setup, result) = run();
    // A device's snapshot: no reason, no seen space, no band.
    let mut snap = result.frames[result.frames.len() / 2].clone();
    snap.reason = None;
    snap.seen = None;
    snap.band = None;
    let text = caption(&setup, &result, &snap, Frame::Animation { last: false }).join(" ");
    assert!(text.contains("not reported by the device"), "{text}");
    let last = result.frames.last().unwrap();
    let text = caption(&setup, &result, last, Frame::Animation { last: true }).join(" ");
    assert!(text.contains("Mission ended: reached."), "{text}");
    // Drawn without them, it still has its scale bar.
    let fig = snapshot_figure(&setup, &result, &snap, 2, Frame::Plan).unwrap();
    assert_eq!(fig.scale_bar(0).unwrap().length, 1.0);
}

#[test]
fn gif_frames_keep_one_size() {
    let (setup, mut result) = run();
    // A few frames from the start and the end (debug builds draw slowly).
    let n = result.frames.len();
    assert!(n > 8);
    result.frames.drain(3..n - 3);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("m.gif");
    write_gif(&path, &setup, &result, 1).unwrap();
    let mut d = gif::DecodeOptions::new()
        .read_info(std::fs::File::open(&path).unwrap())
        .unwrap();
    let (w, h) = (d.width(), d.height());
    let mut frames = 0;
    while let Some(f) = d.read_next_frame().unwrap() {
        assert_eq!((f.width, f.height), (w, h));
        frames += 1;
    }
    assert_eq!(
        frames,
        pick_frames(result.frames.len(), MAX_GIF_FRAMES).len()
    );
}
