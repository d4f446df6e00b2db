//! Host adapter of the quadtree approximate decomposition (`twil_core::classic::quadtree`,
//! seed 001 quadtrees, seed 004 §2.2 E- and M-channels): builds the buffers, runs the core on the
//! world's grid of grown obstacles (so "free" is what the grid planners mean), and fills a
//! [`Run`] with the path through the midpoints of shared sides, the leaves as overlay and the
//! decomposition's figures.
//!
//! `memory_bytes` counts the leaves the decomposition stores (8 bytes each), the figure to hold
//! against the flat bit grid (`grid_bytes`, 1 bit a cell); the search's scratch (the leaf of
//! every cell, a cost and a parent per leaf, the heap) is `scratch_bytes`. Measured on the
//! bundled worlds: see `docs/classic.md`.

use anyhow::Context;
use twil_core::classic::quadtree::{self, Leaf, LeafKind, QuadBuffers};
use twil_core::geom::PointM;

use super::voronoi::{simplify_collinear, status_of};
use super::{polyline_length_m, Method, Run};
use crate::planning::World;

/// Leaves the pool holds (1 MB); a decomposition that needs more is an error.
pub const LEAF_CAPACITY: usize = 1 << 17;
/// Heap entries per leaf of the pool (the search pushes once per improving step).
pub const HEAP_ENTRIES_PER_LEAF: usize = 4;

/// Run the quadtree decomposition on `world`.
pub fn run(world: &World) -> anyhow::Result<Run> {
    let g = *world.grid.geometry();
    let n = g.cell_count();
    let mut leaves = vec![Leaf::default(); LEAF_CAPACITY];
    let mut owner = vec![0u32; n];
    let mut cost = vec![0u32; LEAF_CAPACITY];
    let mut parent = vec![0u32; LEAF_CAPACITY];
    let mut heap = vec![0u64; LEAF_CAPACITY * HEAP_ENTRIES_PER_LEAF];
    let mut path = vec![0u32; LEAF_CAPACITY];
    let report = quadtree::plan(
        &world.grid,
        world.params.start,
        world.params.goal,
        QuadBuffers {
            leaves: &mut leaves,
            owner: &mut owner,
            cost: &mut cost,
            parent: &mut parent,
            heap: &mut heap,
            path: &mut path,
        },
    )
    .context("planner quadtree")?;
    let leaves = &leaves[..report.leaves];
    let res = g.resolution_m();
    let half_m = res / 2.0;
    let mut run = Run::empty(Method::Quadtree, status_of(report.status), "leaves");
    if report.status == twil_core::plan::PlanStatus::Found {
        let mut pts = vec![world.params.start];
        for pair in path[..report.path_leaves].windows(2) {
            let (a, b) = (&leaves[pair[0] as usize], &leaves[pair[1] as usize]);
            let (x2, y2) = quadtree::shared_side_mid2(a, b)
                .ok_or_else(|| anyhow::anyhow!("planner quadtree: path leaves not adjacent"))?;
            let mid = PointM::new(x2 as f32 * half_m, y2 as f32 * half_m);
            run.overlay.nodes.push(mid);
            pts.push(mid);
        }
        pts.push(world.params.goal);
        run.path = simplify_collinear(&pts);
        run.length_m = polyline_length_m(&run.path);
    }
    // The leaves as squares, clipped to the map (the root sticks out of it).
    let (w_m, h_m) = (g.width_m(), g.height_m());
    let mut count = [0usize; 3];
    for l in leaves {
        let kind = l.kind as usize;
        if let Some(c) = count.get_mut(kind) {
            *c += 1;
        }
        let x0 = l.x as f32 * res;
        let y0 = l.y as f32 * res;
        let x1 = ((l.x + l.side) as f32 * res).min(w_m);
        let y1 = ((l.y + l.side) as f32 * res).min(h_m);
        if x0 >= w_m || y0 >= h_m {
            continue;
        }
        let square = vec![
            PointM::new(x0, y0),
            PointM::new(x1, y0),
            PointM::new(x1, y1),
            PointM::new(x0, y1),
        ];
        match l.kind {
            LeafKind::Empty => run.overlay.cells.push(square),
            LeafKind::Full => run.overlay.blocked_cells.push(square),
            LeafKind::Mixed => {}
        }
    }
    run.expanded = report.expanded;
    run.memory_bytes = std::mem::size_of_val(leaves);
    let e = &mut run.extra;
    e.insert("leaves".into(), leaves.len().into());
    e.insert(
        "empty_leaves".into(),
        count[LeafKind::Empty as usize].into(),
    );
    e.insert("full_leaves".into(), count[LeafKind::Full as usize].into());
    e.insert(
        "mixed_leaves".into(),
        count[LeafKind::Mixed as usize].into(),
    );
    e.insert("refinements".into(), report.refinements.into());
    e.insert("rounds".into(), report.rounds.into());
    e.insert("root_side_cells".into(), report.root_side.into());
    e.insert("grid_bytes".into(), n.div_ceil(8).into());
    e.insert(
        "scratch_bytes".into(),
        (n * 4 + LEAF_CAPACITY * (4 + 4 + 4) + heap.len() * 8).into(),
    );
    e.insert("heap_peak".into(), report.heap_peak.into());
    Ok(run)
}
