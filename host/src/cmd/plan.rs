//! `twil plan`: plan a path on a known world and report it as text, JSON and a picture.
//!
//! The command is split into steps that other commands and the tests reuse:
//!
//! 1. [`load`] reads the files and builds the map: the `.da` polygons grown by the `.par` robot
//!    radius (`GridGeometry::expansion_cells` + `raster::mark_polygon`, seed `marca_linha`), and/or
//!    a saved map (already grown, see [`crate::world_io`]), on a
//!    [`Grid400`](twil_core::grid::Grid400).
//! 2. [`plan`] runs one planner of `twil_core::plan` and times it.
//! 3. [`plan_json`] builds the JSON object; [`render_png`] draws the picture.
//!
//! Exit status (`crate::exit`): 0 when a path was found; 3 when none was (`unreachable`,
//! `start_blocked`, `goal_blocked`, `out_of_bounds`, and the classic methods' `local_minimum`,
//! `gave_up`; the output says which); 1 on any error (unreadable or malformed file,
//! impossible geometry, planner capacity), with one message on stderr naming the file, the
//! line and the value; 2 on command-line usage errors.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context};
use twil_core::plan::{PlanStatus, PlannerKind};

pub use crate::planning::{
    geometry_for, parse_size, plan, plan_json, planner_name, round_m, status_name, HostPlanner,
    Outcome, PlanJson, SizeM, World, WorldFiles, HOST_CELLS, HOST_QUEUE, HOST_SCRATCH_WORDS,
};

use super::args::PlanningArgs;
use crate::classic::Method;
use crate::picture::{self, palette, Figure, FigureSpec, LegendEntry, Mark, Marker, PanelSpec};

/// Arguments of `twil plan`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// Environment file (.da): obstacle polygons, grown by the robot radius.
    #[arg(long, value_name = "W.da", required_unless_present = "map")]
    pub world: Option<PathBuf>,
    /// `--params`, `--size`, `--resolution`, `--robot`.
    #[command(flatten)]
    pub planning: PlanningArgs,
    /// Saved map (the seed's `-s` file: width*height bytes, x-major, nonzero = occupied,
    /// already grown). Replaces --world, or is combined with it (cells of both are occupied).
    #[arg(long, value_name = "FILE")]
    pub map: Option<PathBuf>,
    /// Which planner: a grid planner (bfs, astar, anyangle; these also run on the device) or
    /// one of the seeds' classic methods (docs/classic.md).
    #[arg(long, value_enum, default_value_t = Method::Astar)]
    pub planner: Method,
    /// Print one JSON object instead of the human summary.
    #[arg(long)]
    pub json: bool,
    /// Draw the map, the grown obstacles, the path, start and goal to this PNG file.
    #[arg(long, value_name = "OUT.png")]
    pub png: Option<PathBuf>,
    /// Write the world, the map and the plan as Foxglove messages to this MCAP file, one
    /// message per topic (`/world`, `/map`, `/plan`; docs/recording.md).
    #[arg(long, value_name = "FILE.mcap")]
    pub record: Option<PathBuf>,
    /// Pixels per cell in the PNG (default: about 800 px for the map's longer side).
    #[arg(long, value_name = "PX")]
    pub scale: Option<u32>,
    /// Plan on the firmware instead: `qemu` (starts QEMU with the firmware), `tcp:HOST:PORT`
    /// or a serial port. The world is uploaded, the device plans; the output is the device's
    /// plan, and the JSON adds `mcu_instructions`, `static_ram_bytes` and `matches_host`.
    #[arg(long, value_name = "DEVICE")]
    pub remote: Option<crate::remote::RemoteSpec>,
}

/// Read the files named by `args` and build the map ([`crate::planning::load_world`]).
pub fn load(args: &Args) -> anyhow::Result<World> {
    crate::planning::load_world(&args.planning.files(args.world.clone(), args.map.clone()))
}

/// A short human summary (several lines, no trailing newline).
pub fn summary(world: &World, outcome: &Outcome) -> String {
    let g = world.grid.geometry();
    let source = match (&world.world_path, &world.map_path) {
        (Some(w), Some(m)) => format!("{} + {}", w.display(), m.display()),
        (Some(w), None) => w.display().to_string(),
        (None, Some(m)) => m.display().to_string(),
        (None, None) => "(empty map)".into(),
    };
    let p = &world.params;
    let mut s = format!(
        "{} on {source}: {}x{} cells of {} m, robot radius {} m grows obstacles by {} cells\n\
         start ({}, {}) m -> goal ({}, {}) m: {}",
        planner_name(outcome.kind),
        g.width(),
        g.height(),
        g.resolution_m(),
        p.robot_radius_m,
        world.expansion_cells,
        p.start.x_m,
        p.start.y_m,
        p.goal.x_m,
        p.goal.y_m,
        status_name(outcome.report.status),
    );
    if outcome.report.status == PlanStatus::Found {
        s.push_str(&format!(
            ", {} points, {:.3} m",
            outcome.path.len(),
            outcome.report.length_m
        ));
    }
    if let Some(why) = why(world, outcome.report.status) {
        s.push_str(&format!(": {why}"));
    }
    s.push_str(&format!(
        "\n{} {} expanded in {} us",
        outcome.report.expanded,
        expanded_unit(outcome.kind),
        outcome.elapsed_us
    ));
    s
}

/// The sentence that says why no path was found (crate::answer), `None` for a found one.
pub fn why(world: &World, status: PlanStatus) -> Option<String> {
    let p = &world.params;
    let source = [&world.world_path, &world.map_path]
        .into_iter()
        .flatten()
        .map(|path| crate::answer::file_name(path))
        .collect::<Vec<_>>()
        .join(" + ");
    let source = if source.is_empty() {
        "the empty map".to_string()
    } else {
        source
    };
    Some(match status {
        PlanStatus::Found => return None,
        PlanStatus::StartBlocked => {
            crate::answer::start_blocked_on_map(p.start, &source, p.robot_radius_m)
        }
        PlanStatus::GoalBlocked => {
            crate::answer::goal_blocked_on_map(p.goal, &source, p.robot_radius_m)
        }
        PlanStatus::Unreachable => crate::answer::walled_in_on_map(p.start, p.goal, &source),
        PlanStatus::OutOfBounds => {
            let g = world.grid.geometry();
            let (which, point) = if g.cell_of(p.start).is_err() {
                ("start", p.start)
            } else {
                ("goal", p.goal)
            };
            let metres = |cells: u16| (cells as f32 * g.resolution_m() * 1000.0).round() / 1000.0;
            let size = format!("{}x{}", metres(g.width()), metres(g.height()));
            crate::answer::off_map(which, point, &size)
        }
    })
}

/// Draw `world` and `outcome` to a PNG (see [`plan_figure`]). Missing parent folders of `out`
/// are created.
pub fn render_png(
    world: &World,
    outcome: &Outcome,
    out: &Path,
    px_per_cell: Option<u32>,
) -> anyhow::Result<()> {
    plan_figure(world, outcome, px_per_cell)?.save_png(out)?;
    Ok(())
}

/// The picture of a plan: grown obstacles (light orange), saved-map cells and the obstacle
/// polygons (grey, outlined dark), the path (blue, with its vertices), the robot's size at
/// the start (a disc with its heading), start (green disc) and goal (magenta diamond), with
/// axes in metres, a scale bar, a legend and a caption (world, planner, result, why).
pub fn plan_figure(
    world: &World,
    outcome: &Outcome,
    px_per_cell: Option<u32>,
) -> anyhow::Result<Figure> {
    let g = *world.grid.geometry();
    let scale = px_per_cell.unwrap_or_else(|| picture::fit_px_per_cell(g, 800));
    let name = |p: &Option<PathBuf>| {
        p.as_ref()
            .and_then(|p| p.file_name())
            .map(|n| n.to_string_lossy().into_owned())
    };
    let world_name = [name(&world.world_path), name(&world.map_path)]
        .into_iter()
        .flatten()
        .collect::<Vec<_>>()
        .join(" + ");
    let mut result = status_name(outcome.report.status).replace('_', " ");
    if outcome.report.status == PlanStatus::Found {
        result.push_str(&format!(", {:.2} m", outcome.report.length_m));
    }
    let caption = vec![
        format!(
            "{world_name} · twil plan (no mission: 0 stops, 1 plan) · planner {} · {result}",
            planner_name(outcome.kind)
        ),
        format!(
            "Why this plan: the one plan from start to goal on the fully known map (obstacles grown by the robot radius {:.2} m); {} {} expanded; {}x{} cells of {} m.",
            world.params.robot_radius_m,
            outcome.report.expanded,
            expanded_unit(outcome.kind),
            g.width(),
            g.height(),
            g.resolution_m()
        ),
    ];
    let obstacle = if world.saved.is_some() {
        "obstacle / saved map"
    } else {
        "obstacle"
    };
    let legend = vec![
        LegendEntry::new(
            obstacle,
            Mark::FillOutline(palette::OBSTACLE, palette::OUTLINE),
        ),
        LegendEntry::new("grown by robot radius", Mark::Fill(palette::MAP)),
        LegendEntry::new("path", Mark::Line(palette::PREFIX, 3.0)),
        LegendEntry::new("robot at start", Mark::Robot(palette::ROBOT)),
        LegendEntry::new("start", Mark::Marker(Marker::Disc, palette::START)),
        LegendEntry::new("goal", Mark::Marker(Marker::Diamond, palette::GOAL)),
    ];
    let mut fig = Figure::new(&FigureSpec {
        caption,
        caption_lines: None,
        panels: vec![PanelSpec::map(g, scale, None)],
        panels_per_row: None,
        legend,
    })
    .with_context(|| format!("--scale {scale}: the picture"))?;
    let mut plot = fig.plot(0).context("picture: no plot")?;
    plot.fill_grid(&world.grid, palette::MAP, 1.0);
    if let Some(saved) = &world.saved {
        plot.fill_grid(saved, palette::OBSTACLE, 1.0);
    }
    plot.fill_grid(&world.raw, palette::OBSTACLE, 1.0);
    let ends = [world.params.start, world.params.goal];
    for polygon in world.obstacles.iter() {
        let pts = picture::points(polygon);
        if !picture::encloses(polygon, &ends) {
            plot.fill_polygon(&pts, palette::OBSTACLE, 1.0);
        }
        plot.stroke_polygon(&pts, palette::OUTLINE, 1.0);
    }
    let p = &world.params;
    plot.robot(
        p.start.x_m,
        p.start.y_m,
        p.robot_radius_m,
        p.initial_heading_deg.to_radians(),
        palette::ROBOT,
    );
    let path = picture::points(&outcome.path);
    plot.polyline(&path, palette::PREFIX, 3.0);
    if path.len() <= 16 {
        plot.dots(&path, 3.5, palette::PREFIX);
    }
    plot.marker(p.start.x_m, p.start.y_m, Marker::Disc, 14.0, palette::START);
    plot.marker(p.goal.x_m, p.goal.y_m, Marker::Diamond, 16.0, palette::GOAL);
    Ok(fig)
}

/// Run `twil plan`.
pub fn run(args: Args) -> anyhow::Result<crate::exit::Ending> {
    let world = load(&args)?;
    let Some(kind) = args.planner.grid_planner() else {
        return run_classic(&args, &world);
    };
    let outcome = plan(&world, kind)?;
    let mut extra = serde_json::Map::new();
    let outcome = match &args.remote {
        Some(device) => crate::remote::plan_on_device(device, &world, &outcome, &mut extra)?,
        None => outcome,
    };
    if let Some(out) = &args.png {
        render_png(&world, &outcome, out, args.scale)?;
    }
    let recorded = match &args.record {
        Some(path) => Some(record_plan(path, &world, &outcome)?),
        None => None,
    };
    if args.json {
        let mut json = plan_json(&outcome);
        json.extra = extra;
        if let Some(why) = why(&world, outcome.report.status) {
            json.extra.insert("why".into(), why.into());
        }
        println!("{}", serde_json::to_string(&json)?);
    } else {
        println!("{}", summary(&world, &outcome));
        // A figure the device does not measure (`null`) is left out.
        for (key, value) in extra.iter().filter(|(_, v)| !v.is_null()) {
            println!("{key}: {value}");
        }
        if let Some(out) = &args.png {
            println!("picture: {}", out.display());
        }
    }
    if let Some(summary) = &recorded {
        summary.print(args.json);
    }
    Ok(crate::exit::Ending::of_plan_status(status_name(
        outcome.report.status,
    )))
}

/// `twil plan --planner` with one of the classic methods (`crate::classic`): the same JSON as
/// the grid planners, plus `min_clearance_m`, `memory_bytes` and the method's own fields.
fn run_classic(args: &Args, world: &World) -> anyhow::Result<crate::exit::Ending> {
    if args.remote.is_some() {
        bail!(
            "--planner {} runs on the host only; the device plans with bfs, astar or anyangle",
            args.planner.as_str()
        );
    }
    if args.record.is_some() {
        bail!("--record: only the grid planners are recorded (bfs, astar, anyangle)");
    }
    let run = crate::classic::run(args.planner, world, &crate::classic::Options::default())?;
    if let Some(out) = &args.png {
        crate::classic::picture::figure(world, &run, args.scale)?.save_png(out)?;
    }
    // A start or goal off the map says why in the grid planners' words (crate::answer). The
    // methods' other ends rest on each method's model of the free space (a blocked start
    // includes one near the border, `unreachable` may be the model's), described in
    // docs/classic.md: no sentence of the grid planners' would be true of them all.
    let why = match run.status {
        crate::classic::Status::OutOfBounds => why(world, PlanStatus::OutOfBounds),
        _ => None,
    };
    if args.json {
        let mut json = crate::classic::json(world, &run);
        if let Some(why) = &why {
            json.extra.insert("why".into(), why.as_str().into());
        }
        println!("{}", serde_json::to_string(&json)?);
    } else {
        let text = crate::classic::summary(world, &run);
        match (&why, text.split_once('\n')) {
            // The status ends the first line: the sentence follows it.
            (Some(why), Some((first, rest))) => println!("{first}: {why}\n{rest}"),
            _ => println!("{text}"),
        }
        if let Some(out) = &args.png {
            println!("picture: {}", out.display());
        }
    }
    Ok(crate::exit::Ending::of_plan_status(run.status.as_str()))
}

/// `--record`: the world (the `.da` polygons, start, goal), the map the planner used and the
/// plan, one message each at time 0.
fn record_plan(
    path: &Path,
    world: &World,
    outcome: &Outcome,
) -> anyhow::Result<crate::record::RecordSummary> {
    use crate::record::topics::{PathKind, WorldScene};
    let mut recorder = crate::record::Recorder::open(Some(path), None)?;
    recorder.world(
        0.0,
        &WorldScene {
            real: None,
            known: (!world.obstacles.is_empty()).then_some(&world.obstacles),
            start: world.params.start,
            goal: world.params.goal,
            body_radius_m: None,
        },
    );
    recorder.map(0.0, &world.grid);
    recorder.path(0.0, PathKind::Plan, &outcome.path);
    recorder.close()
}

/// What `expanded` counts: A* (and so any-angle) expands jump points; BFS jump points on room
/// maps and cells on cluttered ones (its report does not say which), so "nodes".
fn expanded_unit(planner: PlannerKind) -> &'static str {
    match planner {
        PlannerKind::Bfs => "nodes",
        PlannerKind::AStar | PlannerKind::AnyAngle => "jump points",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn command_line_names_match_the_json_names() {
        use clap::ValueEnum;
        for arg in Method::value_variants() {
            let name = arg.to_possible_value().unwrap().get_name().to_string();
            assert_eq!(arg.as_str(), name);
            if let Some(kind) = arg.grid_planner() {
                assert_eq!(planner_name(kind), name);
            }
        }
    }

    #[test]
    fn the_picture_has_a_scale_bar_and_a_too_large_scale_is_an_error_naming_the_option() {
        use clap::Parser;
        #[derive(Parser)]
        struct Cli {
            #[command(flatten)]
            args: Args,
        }
        let world = |n: &str| format!("{}/../worlds/{n}", env!("CARGO_MANIFEST_DIR"));
        let cli = Cli::try_parse_from([
            "plan",
            "--world",
            &world("office.da"),
            "--params",
            &world("office.par"),
        ])
        .unwrap();
        let w = load(&cli.args).unwrap();
        let outcome = plan(&w, PlannerKind::AnyAngle).unwrap();
        let fig = plan_figure(&w, &outcome, None).unwrap();
        let bar = fig.scale_bar(0).unwrap();
        assert_eq!((bar.length, bar.rect.x1 - bar.rect.x0), (1.0, 40));
        let e = plan_figure(&w, &outcome, Some(40)).err().unwrap();
        assert!(format!("{e:#}").contains("--scale 40"), "{e:#}");
        assert!(plan_figure(&w, &outcome, Some(0)).is_err());
    }
}
