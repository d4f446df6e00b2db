//! Host adapter of the generalized Voronoi roadmap (`twil_core::classic::voronoi`, seed 004
//! §2.1.1 and §2.1.3): builds the buffers, runs the retraction planner on the world's grid and
//! polygon outlines, and fills a [`Run`] with the path, the ridge cells as overlay and the
//! roadmap's figures.
//!
//! The buffers are `Vec`s sized for this map (the core takes slices): 17 bytes per cell
//! (site 4, distance 2, label 2, flags 1, search cost 4, path 4) plus the heap, one 8-byte
//! entry per [`HEAP_ENTRIES_PER_CELL`]-th cell. Measured on the bundled worlds: see
//! `docs/classic.md`.

use anyhow::Context;
use twil_core::classic::distance::DIST_PER_CELL;
use twil_core::classic::voronoi::{self, VoronoiBuffers, CONNECTOR, RIDGE};
use twil_core::geom::PointM;

use super::{polyline_length_m, Method, Run, Status};
use crate::planning::World;

/// One heap entry per this many cells (the ridge is thin: its searches hold far fewer).
pub const HEAP_ENTRIES_PER_CELL: usize = 2;

/// Map a core plan status to the classic one.
pub fn status_of(status: twil_core::plan::PlanStatus) -> Status {
    use twil_core::plan::PlanStatus;
    match status {
        PlanStatus::Found => Status::Found,
        PlanStatus::Unreachable => Status::Unreachable,
        PlanStatus::StartBlocked => Status::StartBlocked,
        PlanStatus::GoalBlocked => Status::GoalBlocked,
        PlanStatus::OutOfBounds => Status::OutOfBounds,
    }
}

/// A path of cell indices as metres: the exact start, the cell centres between, the exact
/// goal; points in the middle of a straight run are dropped (the polyline is the same).
pub fn cells_to_path(world: &World, cells: &[u32]) -> Vec<PointM> {
    let g = world.grid.geometry();
    let mut pts: Vec<PointM> = Vec::with_capacity(cells.len() + 2);
    pts.push(world.params.start);
    for (k, &c) in cells.iter().enumerate() {
        if k == 0 || k + 1 == cells.len() {
            continue;
        }
        pts.push(g.center_of(g.cell_at(c as usize)));
    }
    pts.push(world.params.goal);
    simplify_collinear(&pts)
}

/// Drop the points that lie exactly on the line of their neighbours (same direction).
pub fn simplify_collinear(pts: &[PointM]) -> Vec<PointM> {
    let mut out: Vec<PointM> = Vec::with_capacity(pts.len());
    for &p in pts {
        if out.len() >= 2 {
            let (a, b) = (out[out.len() - 2], out[out.len() - 1]);
            let cross = (b.x_m - a.x_m) * (p.y_m - b.y_m) - (b.y_m - a.y_m) * (p.x_m - b.x_m);
            let dot = (b.x_m - a.x_m) * (p.x_m - b.x_m) + (b.y_m - a.y_m) * (p.y_m - b.y_m);
            if cross.abs() < 1e-6 && dot > 0.0 {
                out.pop();
            }
        }
        if out.last() != Some(&p) {
            out.push(p);
        }
    }
    out
}

/// Run the Voronoi roadmap on `world`.
pub fn run(world: &World) -> anyhow::Result<Run> {
    let g = *world.grid.geometry();
    let n = g.cell_count();
    let mut sites = vec![0u32; n];
    let mut dist = vec![0u16; n];
    let mut labels = vec![0u16; n];
    let mut flags = vec![0u8; n];
    let mut cost = vec![0u32; n];
    let mut heap = vec![0u64; n / HEAP_ENTRIES_PER_CELL + 16];
    let mut path = vec![0u32; n];
    let memory_bytes = n * (4 + 2 + 2 + 1 + 4 + 4) + heap.len() * 8;
    let report = voronoi::plan(
        &world.grid,
        &world.raw,
        world.params.start,
        world.params.goal,
        VoronoiBuffers {
            sites: &mut sites,
            dist: &mut dist,
            labels: &mut labels,
            flags: &mut flags,
            cost: &mut cost,
            heap: &mut heap,
            path: &mut path,
        },
    )
    .context("planner voronoi")?;
    let mut run = Run::empty(Method::Voronoi, status_of(report.status), "cells");
    if report.status == twil_core::plan::PlanStatus::Found {
        run.path = cells_to_path(world, &path[..report.path_cells]);
        run.length_m = polyline_length_m(&run.path);
    }
    // The roadmap (ridge, bridges and connectors) as short edges between 8-adjacent roadmap
    // cells (each pair once).
    let w = g.width() as i32;
    let ridge = |x: i32, y: i32| {
        g.contains_xy(x, y) && flags[(y * w + x) as usize] & (RIDGE | CONNECTOR) != 0
    };
    for i in 0..n {
        let c = g.cell_at(i);
        let (x, y) = (c.x as i32, c.y as i32);
        if !ridge(x, y) {
            continue;
        }
        for (dx, dy) in [(1, 0), (0, 1), (1, 1), (-1, 1)] {
            if ridge(x + dx, y + dy) {
                let other = g.center_of(g.cell_at(((y + dy) * w + x + dx) as usize));
                run.overlay.edges.push([g.center_of(c), other]);
            }
        }
    }
    run.expanded = report.expanded;
    run.memory_bytes = memory_bytes;
    let res = g.resolution_m();
    let e = &mut run.extra;
    e.insert("ridge_cells".into(), report.ridge_cells.into());
    e.insert("connector_cells".into(), report.connector_cells.into());
    e.insert("bridge_cells".into(), report.bridge_cells.into());
    e.insert("components".into(), report.components.into());
    e.insert(
        "bottleneck_m".into(),
        crate::planning::round_m(report.bottleneck as f32 / DIST_PER_CELL as f32 * res).into(),
    );
    e.insert(
        "retraction_cells".into(),
        serde_json::json!(report.retraction_cells),
    );
    e.insert("heap_peak".into(), report.heap_peak.into());
    Ok(run)
}
