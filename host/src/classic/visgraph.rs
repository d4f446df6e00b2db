//! `twil plan --planner visgraph`: the host side of `twil_core::classic::visgraph` (the
//! visibility graph of the square-grown polygons, searched by A*), and the grown obstacles of a
//! [`World`] that the trapezoidal decomposition shares.
//!
//! Seeds 003 §III.1.1 and 004 §2.1; the algorithm and its design choices are documented in the
//! core module. Here: grow the world's polygons (`twil_core::classic::grown`), run the search
//! (timed: growth + search), then enumerate the whole graph for the picture and the `edges`
//! count (not timed: the search never builds it).
//!
//! Measured (docs/classic.md): on the bundled worlds 20–70 nodes, well under a millisecond; on
//! a synthetic full `.da` (128 polygons, 1024 vertices) see the ignored test below.

use std::time::Instant;

use anyhow::Context;
use twil_core::classic::grown::{scratch_len, Grown};
use twil_core::classic::visgraph::{VisGraph, MAX_NODES};
use twil_core::geom::PointM;
use twil_core::world::{MAX_POLYGONS, MAX_VERTICES};

use super::{Method, Overlay, Run, Status};
use crate::planning::World;

/// Grown-polygon capacity for a full `.da`: each polygon may gain the square's 4 corners.
pub const GROWN_VERTICES: usize = MAX_VERTICES + 4 * MAX_POLYGONS;
/// The grown obstacles of a host world.
pub type HostGrown = Grown<GROWN_VERTICES, MAX_POLYGONS>;

/// Above this many nodes the picture shows no graph edges (they would hide the map) and the
/// `edges` count is skipped (it is O(n²) visibility tests).
pub const MAX_DRAWN_NODES: usize = 600;

/// `world`'s polygons grown by the square of half-side the robot radius, in its map.
pub fn grow(world: &World) -> anyhow::Result<Box<HostGrown>> {
    let g = world.grid.geometry();
    let largest = world
        .obstacles
        .iter()
        .map(<[PointM]>::len)
        .max()
        .unwrap_or(0);
    let mut scratch = vec![PointM::default(); scratch_len(largest)];
    HostGrown::build(
        world.obstacles.iter(),
        world.params.robot_radius_m,
        g.width_m(),
        g.height_m(),
        &mut scratch,
    )
    .map(Box::new)
    .context("growing the obstacles by the robot radius")
}

/// The status of a core [`twil_core::plan::PlanStatus`] as a classic [`Status`].
pub fn status(s: twil_core::plan::PlanStatus) -> Status {
    use twil_core::plan::PlanStatus;
    match s {
        PlanStatus::Found => Status::Found,
        PlanStatus::Unreachable => Status::Unreachable,
        PlanStatus::StartBlocked => Status::StartBlocked,
        PlanStatus::GoalBlocked => Status::GoalBlocked,
        PlanStatus::OutOfBounds => Status::OutOfBounds,
    }
}

/// Plan with the visibility graph on `world`.
pub fn run(world: &World) -> anyhow::Result<Run> {
    let t0 = Instant::now();
    let grown = grow(world)?;
    let mut graph = Box::new(VisGraph::<MAX_NODES>::new());
    let mut path = Box::new(heapless::Vec::<PointM, MAX_NODES>::new());
    let report = graph
        .plan(&grown, world.params.start, world.params.goal, &mut path)
        .context("visibility graph")?;
    let elapsed_us = t0.elapsed().as_micros() as u64;

    let mut overlay = Overlay::default();
    let nodes = graph.nodes().len();
    let mut extra = serde_json::Map::new();
    extra.insert("nodes".into(), nodes.into());
    if nodes <= MAX_DRAWN_NODES {
        let edges = graph.edges(&grown, |a, b| overlay.edges.push([a, b]));
        extra.insert("edges".into(), edges.into());
        overlay.nodes = graph.nodes().to_vec();
    } else {
        extra.insert("edges".into(), serde_json::Value::Null);
    }
    extra.insert("visibility_tests".into(), report.visibility_tests.into());
    extra.insert("grown_vertices".into(), grown.vertex_count().into());
    Ok(Run {
        method: Method::Visgraph,
        status: status(report.status),
        path: path.to_vec(),
        length_m: report.length_m,
        expanded: report.expanded as u64,
        expanded_unit: "graph nodes",
        memory_bytes: grown.memory_bytes() + graph.memory_bytes(),
        elapsed_us: elapsed_us.max(1),
        overlay,
        extra,
    })
}
