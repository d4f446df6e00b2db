//! What `twil plan`, `twil compare`, the classic methods and `--remote` share: the world read
//! from the files and its map, one grid planner's run, and its JSON.
//!
//! It sits below the commands (`cmd::plan`, `cmd::compare`) and the modules they use
//! (`classic`, `remote`), so none of them imports another's command module.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context};
use serde::Serialize;
use twil_core::geom::PointM;
use twil_core::grid::{Grid400, GridGeometry};
use twil_core::plan::{PathM, PlanReport, PlanStatus, Planner, PlannerKind};
use twil_core::raster::mark_polygon;
use twil_core::robot::RobotConfig;
use twil_core::world::{Obstacles, Params};

use crate::world_io;

/// Cells of the largest host grid (400 x 400).
pub const HOST_CELLS: usize = 400 * 400;
/// Planner scratch words for [`HOST_CELLS`] (4 bits per cell, 8 cells per word).
pub const HOST_SCRATCH_WORDS: usize = HOST_CELLS / 8;
/// Planner queue capacity on the host: one entry per cell.
pub const HOST_QUEUE: usize = HOST_CELLS;
/// The planner the host uses.
pub type HostPlanner = Planner<HOST_SCRATCH_WORDS, HOST_QUEUE>;

/// Map size in metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SizeM {
    /// Width, metres.
    pub width_m: f32,
    /// Height, metres.
    pub height_m: f32,
}

impl std::fmt::Display for SizeM {
    /// As `--size` takes it: `15x10` (`15x15` for `--size 15`).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}x{}", self.width_m, self.height_m)
    }
}

/// The one `--size` grammar of every command (clap's value parser, so a bad value is a usage
/// error naming the option and the value): `15x10`, `15X10`, or `15` for a 15 x 15 m square
/// (one number cannot be read two ways), each side a positive number of metres.
pub fn parse_size(text: &str) -> Result<SizeM, String> {
    let number = |t: &str| -> Result<f32, String> {
        match t.trim().parse::<f32>() {
            Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
            _ => Err(format!(
                "`{t}` is not a positive number of metres (expected WIDTHxHEIGHT, e.g. 15x10, \
                 or one number for a square)"
            )),
        }
    };
    match text.split_once(['x', 'X']) {
        Some((w, h)) => Ok(SizeM {
            width_m: number(w)?,
            height_m: number(h)?,
        }),
        None => {
            let s = number(text)?;
            Ok(SizeM {
                width_m: s,
                height_m: s,
            })
        }
    }
}

/// The planner's name as in the JSON and on the command line (`PlannerKind::as_str`).
pub fn planner_name(kind: PlannerKind) -> &'static str {
    kind.as_str()
}

/// The status's name as in the JSON (`PlanStatus::as_str`).
pub fn status_name(status: PlanStatus) -> &'static str {
    status.as_str()
}

/// Everything read from the files, and the map built from it.
#[derive(Clone, Debug)]
pub struct World {
    /// The mission parameters.
    pub params: Params,
    /// The polygons of the `.da` file (empty without `--world`).
    pub obstacles: Obstacles,
    /// The grid the planner uses: grown polygons, plus the saved map's cells.
    pub grid: Box<Grid400>,
    /// The cells of the polygon outlines themselves, not grown (for the picture).
    pub raw: Box<Grid400>,
    /// The saved map's cells alone, when `--map` was given (for the picture).
    pub saved: Option<Box<Grid400>>,
    /// Half-side of the growth square, cells.
    pub expansion_cells: u16,
    /// Work of marking the polygons on `grid` and `raw` (`twil_core::raster::Work`: walk steps,
    /// rows and words), bounded by the map and the vertex count, not by the coordinates.
    pub marking_work: u64,
    /// The `--world` file, if any.
    pub world_path: Option<PathBuf>,
    /// The `--map` file, if any.
    pub map_path: Option<PathBuf>,
    /// The robot: the defaults with the `.par` radius, or a `--robot` file's constants.
    pub robot: RobotConfig,
}

/// The geometry for a size and resolution, refused with a clear message when it does not fit
/// a [`Grid400`].
pub fn geometry_for(size: SizeM, resolution_m: f32) -> anyhow::Result<GridGeometry> {
    let what = format!(
        "--size {}x{} m at --resolution {resolution_m} m",
        size.width_m, size.height_m
    );
    if !(resolution_m.is_finite() && resolution_m > 0.0) {
        bail!("{what}: the resolution must be a positive number of metres");
    }
    if resolution_m > size.width_m.min(size.height_m) {
        bail!("{what}: a cell is larger than the map");
    }
    // Cells per side, computed in f64 so that absurd values give a readable count.
    let cells = |side_m: f32| (side_m as f64 / resolution_m as f64).ceil();
    let (w, h) = (cells(size.width_m), cells(size.height_m));
    let too_big = || {
        anyhow::anyhow!(
            "{what} needs about {w:.0}x{h:.0} cells, more than the {HOST_CELLS} cells (400x400) \
             of the host grid; use a coarser --resolution or a smaller --size"
        )
    };
    if w * h > HOST_CELLS as f64 * 1.01 {
        return Err(too_big());
    }
    let g = GridGeometry::from_size_m(size.width_m, size.height_m, resolution_m)
        .with_context(|| what.clone())?;
    if g.cell_count() > HOST_CELLS || Grid400::new(g).is_err() {
        return Err(too_big());
    }
    Ok(g)
}

/// The files a world is read from, and the map's size.
#[derive(Clone, Debug)]
pub struct WorldFiles {
    /// The `.da` polygons, if any.
    pub world: Option<PathBuf>,
    /// The `.par` parameters.
    pub params: PathBuf,
    /// A saved map (already grown), if any.
    pub map: Option<PathBuf>,
    /// Map size.
    pub size: SizeM,
    /// Cell side, metres.
    pub resolution_m: f32,
    /// A robot file (`--robot`): its `planning_radius_m`, if set, replaces the `.par` radius.
    pub robot: Option<PathBuf>,
}

/// Read `files` and build the map: the `.da` polygons grown by the `.par` robot radius
/// (`GridGeometry::expansion_cells` + `raster::mark_polygon`, seed `marca_linha`), and/or a
/// saved map (already grown, see [`crate::world_io`]), on a [`Grid400`].
pub fn load_world(files: &WorldFiles) -> anyhow::Result<World> {
    let geometry = geometry_for(files.size, files.resolution_m)?;
    let mut params = world_io::read_par(&files.params)?;
    let file = files
        .robot
        .as_deref()
        .map(crate::robot_file::read)
        .transpose()?;
    let base = RobotConfig::DEFAULT.with_planning_radius_m(params.robot_radius_m);
    let robot = crate::robot_file::resolve(base, file.as_ref(), &[])?;
    params.robot_radius_m = robot.planning_radius_m;
    let empty = || {
        Grid400::new(geometry)
            .map(Box::new)
            .map_err(anyhow::Error::from)
    };
    let mut grid = empty()?;
    let mut raw = empty()?;
    let expansion_cells = geometry.expansion_cells(params.robot_radius_m);
    let obstacles = match &files.world {
        Some(path) => world_io::read_da(path)?,
        None => Obstacles::new(),
    };
    let mut marking_work = 0;
    for polygon in obstacles.iter() {
        marking_work += mark_polygon(&mut grid, polygon, expansion_cells);
        marking_work += mark_polygon(&mut raw, polygon, 0);
    }
    let saved = match &files.map {
        Some(path) => {
            let mut saved = empty()?;
            world_io::read_saved_map(path, &mut saved)?;
            grid.union_with(&saved);
            Some(saved)
        }
        None => None,
    };
    Ok(World {
        params,
        obstacles,
        grid,
        raw,
        saved,
        expansion_cells,
        marking_work,
        world_path: files.world.clone(),
        map_path: files.map.clone(),
        robot,
    })
}

/// One planning run.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// The planner used.
    pub kind: PlannerKind,
    /// Status, cost, length, expanded cells.
    pub report: PlanReport,
    /// The path, world metres, start to goal (empty unless found).
    pub path: Vec<PointM>,
    /// Wall-clock time of the planner call, microseconds.
    pub elapsed_us: u64,
    /// Most entries the planner's open list held at once (0 when unknown, e.g. `--remote`).
    pub queue_peak: u32,
}

/// Run planner `kind` from the `.par` start to its goal on `world`'s grid.
///
/// The planner's scratch and queue (a few MB for 400 x 400 cells) live on the stack of a
/// helper thread with a large stack, so this works from any thread (test threads have 2 MB).
pub fn plan(world: &World, kind: PlannerKind) -> anyhow::Result<Outcome> {
    let grid: &Grid400 = &world.grid;
    let (start, goal) = (world.params.start, world.params.goal);
    let result = std::thread::scope(|scope| {
        std::thread::Builder::new()
            .name("planner".into())
            .stack_size(64 * 1024 * 1024)
            .spawn_scoped(scope, move || {
                let mut planner = HostPlanner::new();
                let mut path = PathM::new();
                let t0 = Instant::now();
                let report = planner.plan(kind, grid, start, goal, &mut path);
                let elapsed_us = t0.elapsed().as_micros() as u64;
                report.map(|report| Outcome {
                    kind,
                    report,
                    path: path.iter().copied().collect(),
                    elapsed_us,
                    queue_peak: planner.queue_peak(),
                })
            })
            .map(|h| h.join())
    });
    match result {
        Ok(Ok(Ok(outcome))) => Ok(outcome),
        Ok(Ok(Err(e))) => bail!("planner {}: {e:?}", planner_name(kind)),
        Ok(Err(_)) => bail!("planner {} failed unexpectedly", planner_name(kind)),
        Err(e) => bail!("cannot start the planner thread: {e}"),
    }
}

/// The JSON object of `twil plan --json`, fields in this order. Other commands add fields
/// (e.g. `--remote` adds `mcu_instructions`, `static_ram_bytes`) through [`PlanJson::extra`],
/// which is flattened after the standard fields.
#[derive(Serialize, Debug, Clone, PartialEq)]
pub struct PlanJson {
    /// `found`, `unreachable`, `start_blocked`, `goal_blocked` or `out_of_bounds`.
    pub status: &'static str,
    /// `bfs`, `astar` or `anyangle`.
    pub planner: &'static str,
    /// The path, `[x, y]` in world metres, start to goal (empty unless found), rounded to
    /// 0.1 mm so that `f32` noise (`7.5750003`) does not show.
    pub path: Vec<[f64; 2]>,
    /// Euclidean length of the path, metres, rounded to 0.1 mm.
    pub length_m: f64,
    /// Cells expanded by the planner.
    pub expanded: u32,
    /// Planner wall-clock time, microseconds.
    pub elapsed_us: u64,
    /// Further fields, serialized after the standard ones.
    #[serde(flatten)]
    pub extra: serde_json::Map<String, serde_json::Value>,
}

/// Metres rounded to 0.1 mm, as `f64` so that the JSON shows the short decimal.
pub fn round_m(value_m: f32) -> f64 {
    (value_m as f64 * 1e4).round() / 1e4
}

/// The JSON object for a planning outcome (add fields to `extra` before printing).
pub fn plan_json(outcome: &Outcome) -> PlanJson {
    PlanJson {
        status: status_name(outcome.report.status),
        planner: planner_name(outcome.kind),
        path: outcome
            .path
            .iter()
            .map(|p| [round_m(p.x_m), round_m(p.y_m)])
            .collect(),
        length_m: round_m(outcome.report.length_m),
        expanded: outcome.report.expanded,
        elapsed_us: outcome.elapsed_us,
        extra: serde_json::Map::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse() {
        assert_eq!(
            parse_size("15x10").unwrap(),
            SizeM {
                width_m: 15.0,
                height_m: 10.0
            }
        );
        assert_eq!(parse_size("7").unwrap().height_m, 7.0);
        assert_eq!(parse_size(" 7 X 5 ").unwrap().to_string(), "7x5");
        assert_eq!(parse_size("15").unwrap().to_string(), "15x15");
        assert_eq!(parse_size("12.5x10").unwrap().to_string(), "12.5x10");
        assert!(parse_size("0x3").is_err());
        assert!(parse_size("ax3").is_err());
        assert!(parse_size("inf").is_err());
    }

    #[test]
    fn geometry_beyond_the_host_grid_is_refused() {
        let ok = geometry_for(parse_size("20x20").unwrap(), 0.05).unwrap();
        assert_eq!((ok.width(), ok.height()), (400, 400));
        let e = geometry_for(parse_size("30x15").unwrap(), 0.05).unwrap_err();
        assert!(e.to_string().contains("600x300 cells"), "{e}");
        assert!(geometry_for(parse_size("15").unwrap(), 0.0).is_err());
        let e = geometry_for(parse_size("1e9").unwrap(), 0.05).unwrap_err();
        assert!(e.to_string().contains("cells, more than the 160000"), "{e}");
        let e = geometry_for(parse_size("15").unwrap(), 1.0e-30).unwrap_err();
        assert!(e.to_string().contains("400x400"), "{e}");
        let e = geometry_for(parse_size("15").unwrap(), 1.0e30).unwrap_err();
        assert!(e.to_string().contains("larger than the map"), "{e}");
    }

    #[test]
    fn json_keeps_field_order_and_takes_extras() {
        let outcome = Outcome {
            kind: PlannerKind::AnyAngle,
            report: PlanReport {
                status: PlanStatus::Found,
                expanded: 7,
                cost: 0,
                length_m: 1.5,
            },
            path: vec![PointM::new(0.25, 0.5), PointM::new(7.575_000_3, 0.5)],
            elapsed_us: 3,
            queue_peak: 0,
        };
        let mut json = plan_json(&outcome);
        assert_eq!(
            serde_json::to_string(&json).unwrap(),
            r#"{"status":"found","planner":"anyangle","path":[[0.25,0.5],[7.575,0.5]],"length_m":1.5,"expanded":7,"elapsed_us":3}"#
        );
        json.extra.insert("static_ram_bytes".into(), 42.into());
        assert!(serde_json::to_string(&json)
            .unwrap()
            .ends_with(r#""elapsed_us":3,"static_ram_bytes":42}"#));
    }
}
