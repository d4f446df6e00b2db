//! `twil compare`: every planning method on one world, side by side (issue 15).
//!
//! ```text
//! twil compare --world worlds/office.da --params worlds/office.par --out out/compare-office
//! ```
//!
//! Runs the grid planners (bfs, astar, anyangle) and the seeds' classic methods
//! (`crate::classic`) on the same world and the same robot, and writes to `--out`:
//! `compare.png` (one panel per method), `compare.json` (one `twil plan --json` object per
//! method, plus `ratio_to_visgraph`) and `compare.md` (the table, as printed). The table gives
//! each path's length and its ratio to the visibility graph's (the continuous optimum),
//! its minimum clearance, time, memory and status.
//!
//! Exit status: 0 when every method ran (whatever each found); 1 on errors (files, options).

use std::io::IsTerminal;
use std::path::PathBuf;

use anyhow::Context;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use super::args::PlanningArgs;
use crate::classic::{self, Method, Options, Run, Status};
use crate::picture::{self, Figure, FigureSpec, PanelSpec};
use crate::planning::{self, World};

/// Arguments of `twil compare`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// Environment file (.da): obstacle polygons.
    #[arg(long, value_name = "W.da")]
    pub world: PathBuf,
    /// `--params`, `--size`, `--resolution`, `--robot`.
    #[command(flatten)]
    pub planning: PlanningArgs,
    /// Methods to run, comma-separated (default: all).
    #[arg(long, value_enum, value_delimiter = ',', value_name = "M,M,…")]
    pub planners: Vec<Method>,
    /// Sonar range of the Bug robot, metres [default: 3, or the --robot file's `sonar_range_m`].
    #[arg(long, value_name = "M")]
    pub sonar_range: Option<f32>,
    /// Write compare.png, compare.json and compare.md to this folder.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Print one JSON object (the rows) instead of the table.
    #[arg(long)]
    pub json: bool,
}

/// One row of the comparison.
#[derive(Clone, Debug)]
pub struct Row {
    /// The run.
    pub run: Run,
    /// Its minimum clearance, metres (`None` without a path).
    pub min_clearance_m: Option<f32>,
    /// Its length over the visibility graph's (`None` when either has no path).
    pub ratio_to_visgraph: Option<f64>,
}

/// Run `methods` on `world` (all of them when empty), reporting each to `progress`.
pub fn compare(
    world: &World,
    methods: &[Method],
    options: &Options,
    mut progress: impl FnMut(Method),
) -> anyhow::Result<Vec<Row>> {
    let methods: Vec<Method> = if methods.is_empty() {
        Method::ALL.to_vec()
    } else {
        methods.to_vec()
    };
    let mut rows = Vec::new();
    for method in methods {
        progress(method);
        let run = classic::run(method, world, options)
            .with_context(|| format!("planner {}", method.as_str()))?;
        rows.push(Row {
            min_clearance_m: classic::min_clearance_m(world, &run),
            run,
            ratio_to_visgraph: None,
        });
    }
    // The visibility graph is the continuous optimum: run it for the ratio even if not listed.
    let reference = match rows.iter().find(|r| r.run.method == Method::Visgraph) {
        Some(r) => Some(r.run.clone()),
        None => classic::run(Method::Visgraph, world, options).ok(),
    };
    if let Some(reference) = reference.filter(|r| r.status == Status::Found) {
        for row in &mut rows {
            if row.run.status == Status::Found && reference.length_m > 0.0 {
                row.ratio_to_visgraph = Some(row.run.length_m as f64 / reference.length_m as f64);
            }
        }
    }
    Ok(rows)
}

/// The table as Markdown (what `twil compare` prints and writes to `compare.md`).
pub fn table(rows: &[Row]) -> String {
    let mut s = String::from(
        "| planner | status | length (m) | / visgraph | min clearance (m) | time (ms) | memory (KiB) | work |\n\
         |---|---|---:|---:|---:|---:|---:|---|\n",
    );
    for row in rows {
        let r = &row.run;
        let opt = |v: Option<String>| v.unwrap_or_else(|| "–".into());
        s.push_str(&format!(
            "| {} | {} | {} | {} | {} | {:.1} | {:.1} | {} {} |\n",
            r.method.as_str(),
            r.status.as_str(),
            opt((!r.path.is_empty()).then(|| format!("{:.2}", r.length_m))),
            opt(row.ratio_to_visgraph.map(|x| format!("{x:.3}"))),
            opt(row
                .min_clearance_m
                .map(|c| format!("{:.3}", c + 0.0).replace("-0.000", "0.000"))),
            r.elapsed_us as f64 / 1000.0,
            r.memory_bytes as f64 / 1024.0,
            r.expanded,
            r.expanded_unit
        ));
    }
    s
}

/// The JSON of `twil compare --json` and `compare.json`: `{"world", "rows": [plan JSON + ratio]}`.
pub fn json(world: &World, rows: &[Row]) -> serde_json::Value {
    let rows: Vec<serde_json::Value> = rows
        .iter()
        .map(|row| {
            let mut j = classic::json(world, &row.run);
            j.extra.insert(
                "ratio_to_visgraph".into(),
                row.ratio_to_visgraph
                    .map(|x| (x * 1e4).round() / 1e4)
                    .into(),
            );
            serde_json::to_value(j).unwrap_or(serde_json::Value::Null)
        })
        .collect();
    serde_json::json!({
        "world": classic::picture::world_name(world),
        "rows": rows,
    })
}

/// The side-by-side picture: one panel per method, three to a row, one legend.
pub fn figure(world: &World, rows: &[Row]) -> anyhow::Result<Figure> {
    let g = *world.grid.geometry();
    let scale = picture::fit_px_per_cell(g, 330).max(1);
    let runs: Vec<&Run> = rows.iter().map(|r| &r.run).collect();
    let panels = rows
        .iter()
        .map(|row| {
            // Short enough not to run into the y axis title; the table has the rest.
            let r = &row.run;
            let mut title = format!("{}: ", r.method.as_str());
            match row.ratio_to_visgraph {
                Some(x) => title.push_str(&format!("{:.2} m, ×{x:.3}", r.length_m)),
                None => title.push_str(&r.status.as_str().replace('_', " ")),
            }
            PanelSpec::map(g, scale, Some(title))
        })
        .collect();
    let p = &world.params;
    let caption = vec![format!(
        "{} · twil compare · robot radius {:.2} m · start ({}, {}) → goal ({}, {}) · \
         lengths as a ratio (×) to the visibility graph's, the shortest path of the grown obstacles",
        classic::picture::world_name(world),
        p.robot_radius_m,
        p.start.x_m,
        p.start.y_m,
        p.goal.x_m,
        p.goal.y_m
    )];
    let mut fig = Figure::new(&FigureSpec {
        caption,
        caption_lines: None,
        panels,
        panels_per_row: Some(3),
        legend: classic::picture::legend(&runs),
    })
    .context("the comparison picture")?;
    for (i, row) in rows.iter().enumerate() {
        if let Some(mut plot) = fig.plot(i) {
            classic::picture::draw(&mut plot, world, &row.run);
        }
    }
    Ok(fig)
}

/// The Bug robot's sonar range without --sonar-range or a robot file's, metres.
const DEFAULT_BUG_SONAR_RANGE_M: f32 = 3.0;

/// Run `twil compare`.
pub fn run(args: Args) -> anyhow::Result<crate::exit::Ending> {
    let world = planning::load_world(&args.planning.files(Some(args.world.clone()), None))?;
    // The file's sonar range, if it sets one (load_world has checked it).
    let file = args
        .planning
        .robot
        .as_deref()
        .map(crate::robot_file::read)
        .transpose()?;
    let file_range = file
        .as_ref()
        .and_then(|f| f.get("sonar_range_m"))
        .map(|_| world.robot.sonar_range_m);
    let options = Options {
        sonar_range_m: args
            .sonar_range
            .or(file_range)
            .unwrap_or(DEFAULT_BUG_SONAR_RANGE_M),
    };
    let count = if args.planners.is_empty() {
        Method::ALL.len()
    } else {
        args.planners.len()
    };
    let bar = if args.json || !std::io::stderr().is_terminal() {
        ProgressBar::with_draw_target(Some(count as u64), ProgressDrawTarget::hidden())
    } else {
        let b = ProgressBar::new(count as u64);
        if let Ok(style) = ProgressStyle::with_template("{spinner} planner {pos}/{len}: {msg}") {
            b.set_style(style);
        }
        b
    };
    let rows = compare(&world, &args.planners, &options, |m| {
        bar.set_message(m.as_str());
        bar.inc(1);
    })?;
    bar.finish_and_clear();
    let table = table(&rows);
    let json = json(&world, &rows);
    if let Some(dir) = &args.out {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("{}: cannot create the folder", dir.display()))?;
        figure(&world, &rows)?.save_png(&dir.join("compare.png"))?;
        let write = |name: &str, text: &str| {
            let path = dir.join(name);
            std::fs::write(&path, text).with_context(|| format!("{}: cannot write", path.display()))
        };
        write("compare.json", &serde_json::to_string_pretty(&json)?)?;
        write("compare.md", &table)?;
    }
    if args.json {
        println!("{}", serde_json::to_string(&json)?);
    } else {
        print!("{table}");
        if let Some(dir) = &args.out {
            println!(
                "wrote {0}/compare.png, {0}/compare.json, {0}/compare.md",
                dir.display()
            );
        }
    }
    Ok(crate::exit::Ending::Done)
}
