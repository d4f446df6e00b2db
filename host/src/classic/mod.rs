//! The seeds' classic planning methods (issue 15), side by side with the grid planners.
//!
//! Every method answers the same question as `twil plan`: a path for the robot (a disc of the
//! `.par` radius) from the `.par` start to its goal among the `.da` polygons. Each one lives in
//! its own file and is reached through [`run`]; `twil plan --planner NAME` and `twil compare`
//! call it and print the same JSON.
//!
//! What each method needs beyond the grid planners: the polygons themselves (`--world`; a saved
//! `--map` has none, so the classic methods refuse it).

use std::time::Instant;

use anyhow::bail;
use twil_core::geom::PointM;

use crate::planning::World;

pub mod bug;
pub mod clearance;
pub mod picture;
pub mod potential;
pub mod quadtree;
pub mod trapezoid;
pub mod visgraph;
pub mod voronoi;

/// Every planning method `twil plan` and `twil compare` know, in the order `compare` lists them.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Method {
    /// Breadth-first search on the grid (the seed's planner): fewest 8-connected steps.
    Bfs,
    /// A* with octile costs on the grid: shortest 8-connected path.
    Astar,
    /// Any-angle (Theta*-like) on the grid: straight segments with line of sight.
    Anyangle,
    /// Visibility graph of the grown obstacles, shortest path by A*: the continuous optimum.
    Visgraph,
    /// Generalized Voronoi roadmap (retraction): the paths of maximum clearance.
    Voronoi,
    /// Exact trapezoidal (vertical) cell decomposition by a sweep line.
    Trapezoid,
    /// Quadtree approximate decomposition: EMPTY-leaf channel, MIXED leaves refined until one.
    Quadtree,
    /// Potential field: attractive paraboloid plus repulsive term, gradient descent.
    Potential,
    /// Lumelsky's Bug, run in the simulator with the sonar (sensor-based, no map).
    Bug,
}

impl Method {
    /// Every method, in the order of the comparison table.
    pub const ALL: [Method; 9] = [
        Method::Bfs,
        Method::Astar,
        Method::Anyangle,
        Method::Visgraph,
        Method::Voronoi,
        Method::Trapezoid,
        Method::Quadtree,
        Method::Potential,
        Method::Bug,
    ];

    /// The name on the command line and in the JSON.
    pub fn as_str(self) -> &'static str {
        match self {
            Method::Bfs => "bfs",
            Method::Astar => "astar",
            Method::Anyangle => "anyangle",
            Method::Visgraph => "visgraph",
            Method::Voronoi => "voronoi",
            Method::Trapezoid => "trapezoid",
            Method::Quadtree => "quadtree",
            Method::Potential => "potential",
            Method::Bug => "bug",
        }
    }

    /// The grid planner this method is, if it is one.
    pub fn grid_planner(self) -> Option<twil_core::plan::PlannerKind> {
        use twil_core::plan::PlannerKind;
        match self {
            Method::Bfs => Some(PlannerKind::Bfs),
            Method::Astar => Some(PlannerKind::AStar),
            Method::Anyangle => Some(PlannerKind::AnyAngle),
            _ => None,
        }
    }
}

/// How a classic method's run ended (the grid planners' statuses, plus `local_minimum`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// A path from start to goal.
    Found,
    /// No path exists for this method's model of the free space.
    Unreachable,
    /// The start is inside a grown obstacle.
    StartBlocked,
    /// The goal is inside a grown obstacle.
    GoalBlocked,
    /// Start or goal outside the map.
    OutOfBounds,
    /// The potential field's descent stopped at a minimum that is not the goal.
    LocalMinimum,
    /// A sensor-based method (Bug) gave up: its step or distance limit ran out.
    GaveUp,
}

impl Status {
    /// The name in the JSON.
    pub fn as_str(self) -> &'static str {
        match self {
            Status::Found => "found",
            Status::Unreachable => "unreachable",
            Status::StartBlocked => "start_blocked",
            Status::GoalBlocked => "goal_blocked",
            Status::OutOfBounds => "out_of_bounds",
            Status::LocalMinimum => "local_minimum",
            Status::GaveUp => "gave_up",
        }
    }
}

/// What a method drew on its way, for the pictures: its roadmap, cells or field.
#[derive(Clone, Debug, Default)]
pub struct Overlay {
    /// Graph or roadmap edges (visibility graph, Voronoi ridges, cell connectivity), metres.
    pub edges: Vec<[PointM; 2]>,
    /// Cells of a decomposition (trapezoids, quadtree leaves), as closed polygons, metres.
    pub cells: Vec<Vec<PointM>>,
    /// Cells the decomposition found blocked (quadtree FULL leaves), metres.
    pub blocked_cells: Vec<Vec<PointM>>,
    /// Nodes worth a dot (graph vertices, midpoints of shared edges, hit/leave points).
    pub nodes: Vec<PointM>,
    /// What the dots are, for the legend; empty: "node".
    pub node_label: &'static str,
}

/// One method's answer.
#[derive(Clone, Debug)]
pub struct Run {
    /// Which method.
    pub method: Method,
    /// How it ended.
    pub status: Status,
    /// The path, world metres, start to goal (for `local_minimum` / `gave_up`: as far as it
    /// got; empty when nothing was found).
    pub path: Vec<PointM>,
    /// Euclidean length of `path`, metres.
    pub length_m: f32,
    /// Work done: nodes expanded, cells visited or steps taken (see `expanded_unit`).
    pub expanded: u64,
    /// What `expanded` counts, e.g. `graph nodes`, `cells`, `descent steps`.
    pub expanded_unit: &'static str,
    /// Bytes of the method's data structures (graph, cells, field, scratch), as allocated.
    pub memory_bytes: usize,
    /// Wall-clock time of the method, microseconds (filled by [`run`]).
    pub elapsed_us: u64,
    /// What to draw besides the path.
    pub overlay: Overlay,
    /// Method-specific fields added to the JSON after the standard ones (e.g. `nodes`,
    /// `edges`, `cells`, `bound_m`).
    pub extra: serde_json::Map<String, serde_json::Value>,
}

impl Run {
    /// A run with `status` and no path (for the early exits every method shares).
    pub fn empty(method: Method, status: Status, expanded_unit: &'static str) -> Self {
        Self {
            method,
            status,
            path: Vec::new(),
            length_m: 0.0,
            expanded: 0,
            expanded_unit,
            memory_bytes: 0,
            elapsed_us: 0,
            overlay: Overlay::default(),
            extra: serde_json::Map::new(),
        }
    }
}

/// Options that only some methods read.
#[derive(Clone, Debug)]
pub struct Options {
    /// Sonar range for the sensor-based Bug, metres.
    pub sonar_range_m: f32,
}

impl Default for Options {
    fn default() -> Self {
        Self { sonar_range_m: 3.0 }
    }
}

/// Euclidean length of a polyline, metres (the core's one sum).
pub use twil_core::geom::polyline_length_m;

/// Run `method` on `world` (which must come from `--world`: the classic methods work on its
/// polygons). The grid planners go through `planning::plan`.
pub fn run(method: Method, world: &World, options: &Options) -> anyhow::Result<Run> {
    if world.obstacles.is_empty() && world.saved.is_some() {
        bail!(
            "planner {}: needs the obstacle polygons of --world; a saved --map has none",
            method.as_str()
        );
    }
    let t0 = Instant::now();
    let mut run = match method {
        Method::Bfs | Method::Astar | Method::Anyangle => {
            let kind = method.grid_planner().expect("a grid planner");
            let outcome = crate::planning::plan(world, kind)?;
            grid_run(method, world, &outcome)
        }
        Method::Visgraph => visgraph::run(world)?,
        Method::Trapezoid => trapezoid::run(world)?,
        Method::Quadtree => quadtree::run(world)?,
        Method::Voronoi => voronoi::run(world)?,
        Method::Potential => potential::run(world)?,
        Method::Bug => bug::run(world, options)?,
    };
    if run.elapsed_us == 0 {
        run.elapsed_us = t0.elapsed().as_micros() as u64;
    }
    Ok(run)
}

/// A grid planner's outcome as a [`Run`]. Its memory is what this map needs: the bit map (1 bit
/// a cell), the planner's scratch (4 bits a cell) and the open-list entries it held at its peak
/// (12 bytes each).
pub fn grid_run(method: Method, world: &World, outcome: &crate::planning::Outcome) -> Run {
    let cells = world.grid.geometry().cell_count();
    let mut extra = serde_json::Map::new();
    extra.insert("queue_peak".into(), outcome.queue_peak.into());
    Run {
        method,
        status: match outcome.report.status {
            twil_core::plan::PlanStatus::Found => Status::Found,
            twil_core::plan::PlanStatus::Unreachable => Status::Unreachable,
            twil_core::plan::PlanStatus::StartBlocked => Status::StartBlocked,
            twil_core::plan::PlanStatus::GoalBlocked => Status::GoalBlocked,
            twil_core::plan::PlanStatus::OutOfBounds => Status::OutOfBounds,
        },
        path: outcome.path.clone(),
        length_m: outcome.report.length_m,
        expanded: outcome.report.expanded as u64,
        // BFS expands jump points on room maps and cells on cluttered ones, and does not
        // say which: "nodes" is true of both.
        expanded_unit: match method {
            Method::Bfs => "nodes",
            _ => "jump points",
        },
        memory_bytes: cells / 8 + cells / 2 + outcome.queue_peak as usize * 12,
        elapsed_us: outcome.elapsed_us,
        overlay: Overlay::default(),
        extra,
    }
}

/// The smallest clearance of `run`'s path on `world` (see [`clearance`]), metres.
pub fn min_clearance_m(world: &World, run: &Run) -> Option<f32> {
    let g = world.grid.geometry();
    clearance::min_clearance_m(
        &run.path,
        &world.obstacles,
        g.width_m(),
        g.height_m(),
        world.params.robot_radius_m,
    )
}

/// The JSON of `twil plan --planner NAME --json` for any method: the grid planners' fields in
/// their order, then `min_clearance_m` (null without a path), `memory_bytes`,
/// `expanded_unit` and the method's own fields.
pub fn json(world: &World, run: &Run) -> crate::planning::PlanJson {
    use crate::planning::round_m;
    let mut extra = serde_json::Map::new();
    extra.insert(
        "min_clearance_m".into(),
        min_clearance_m(world, run).map(round_m).into(),
    );
    extra.insert("memory_bytes".into(), run.memory_bytes.into());
    extra.insert("expanded_unit".into(), run.expanded_unit.into());
    for (k, v) in &run.extra {
        extra.insert(k.clone(), v.clone());
    }
    crate::planning::PlanJson {
        status: run.status.as_str(),
        planner: run.method.as_str(),
        path: run
            .path
            .iter()
            .map(|p| [round_m(p.x_m), round_m(p.y_m)])
            .collect(),
        length_m: round_m(run.length_m),
        expanded: run.expanded.min(u32::MAX as u64) as u32,
        elapsed_us: run.elapsed_us,
        extra,
    }
}

/// A short human summary of `run` (no trailing newline).
pub fn summary(world: &World, run: &Run) -> String {
    let p = &world.params;
    let mut s = format!(
        "{}: start ({}, {}) m -> goal ({}, {}) m, robot radius {} m: {}",
        run.method.as_str(),
        p.start.x_m,
        p.start.y_m,
        p.goal.x_m,
        p.goal.y_m,
        p.robot_radius_m,
        run.status.as_str()
    );
    if !run.path.is_empty() {
        s.push_str(&format!(
            ", {} points, {:.3} m",
            run.path.len(),
            run.length_m
        ));
    }
    if let Some(c) = min_clearance_m(world, run) {
        // A path that touches a grown obstacle measures -0.0002 m or so: that is 0.000.
        let c = format!("{c:.3}").replace("-0.000", "0.000");
        s.push_str(&format!(", clearance {c} m"));
    }
    s.push_str(&format!(
        "\n{} {} in {} us, {} bytes",
        run.expanded, run.expanded_unit, run.elapsed_us, run.memory_bytes
    ));
    s
}
