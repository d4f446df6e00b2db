//! Generalized Voronoi roadmap by retraction (seed 004 §2.1.1 and §2.1.3), on the grid.
//!
//! The roadmap is the set of cells equidistant from two different parts of the obstacle
//! boundary: the paths of maximum clearance. The plan is the seed's three pieces: a retraction
//! of the start onto the roadmap, a path along the roadmap, and the reversed retraction of the
//! goal.
//!
//! Design:
//! - **Distance from the polygons, freedom from the grown grid.** The distance transform
//!   ([`super::distance`]) runs on the raw polygon outlines (`raw`), so the ridge is the GVD of
//!   the obstacles themselves and of the map border; a cell may carry the robot only where the
//!   grid of grown obstacles (`grid`) is free.
//! - **Ridge cells** are free cells with a 4-neighbour whose nearest site belongs to another
//!   obstacle (component labels: touching walls are one obstacle, so no ridge runs into their
//!   seam), or to the same obstacle but more than √8 cells and more than the cell's own
//!   distance away (the two sites span more than 60° seen from the cell: the medial axis of a
//!   single obstacle's concavity, e.g. a room whose walls all touch the border, where labels
//!   alone give no ridge at all). Both cells of such a pair are marked, so the ridge is a
//!   4-connected band one or two cells wide.
//! - **Bridges** keep the roadmap connected. The 60° rule cuts a concavity's medial axis short
//!   of the point where it meets the rest of the diagram (in `worlds/trap` the axis of the U
//!   stops 0.25 m before the ridge between the U and the border, so a start inside the U had
//!   no roadmap path out). From every ridge cell the distance is climbed (steepest ascent); a
//!   climb that leaves the ridge and reaches another roadmap cell marks its cells as
//!   [`CONNECTOR`]s, one that ends on a maximum off the roadmap marks nothing. A climb never
//!   lowers the clearance, and each cell is climbed through once, so this is linear in cells.
//! - **Retraction** climbs the distance (steepest ascent over the 8 neighbours) until it
//!   reaches a ridge cell; the clearance never decreases on the way. If it stops on a plateau
//!   or a maximum that is not marked, the shortest free path to the nearest ridge cell joins
//!   the roadmap as a connector.
//! - **Search** in two passes over ridge cells: a widest-path Dijkstra finds the largest
//!   bottleneck distance B between the two retraction points, then A* (octile costs) finds the
//!   shortest roadmap path whose cells all keep a distance ≥ B. So the path has the best
//!   clearance the roadmap offers, and among those paths the shortest.
//! - No smoothing: every shortcut would leave the ridge and lower the clearance the method is
//!   for.
//!
//! Buffers are the caller's ([`VoronoiBuffers`], one entry per cell, `heap` as long as the
//! caller likes: a full heap is [`VoronoiError::HeapFull`]).

use super::cell_heap::CellHeap;
use super::distance::{self, site_dist2, site_label, DistanceError, NEIGHBOURS_8, NO_SITE};
use crate::geom::{Cell, PointM};
use crate::grid::{Grid, GridGeometry};
use crate::plan::PlanStatus;

/// Flag bit: the cell is on the roadmap's ridge.
pub const RIDGE: u8 = 1;
/// Flag bit: the cell joins a retraction that stopped off the ridge to the ridge.
pub const CONNECTOR: u8 = 2;
/// Flag bit: a bridge climb went through the cell (each cell is climbed through once).
const CLIMBED: u8 = 4;
const PARENT_SHIFT: u8 = 4;
/// Cost of an orthogonal step in the searches (a diagonal costs [`DIAGONAL_COST`]).
pub const STEP_COST: u32 = 1000;
/// Cost of a diagonal step (√2 · [`STEP_COST`]).
pub const DIAGONAL_COST: u32 = 1414;

/// Why the roadmap could not be computed (an input that merely has no path is a status).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum VoronoiError {
    /// A buffer is too short, or too many components.
    Distance(DistanceError),
    /// The priority queue's slice is full.
    HeapFull {
        /// Its capacity, entries.
        capacity: usize,
    },
    /// The path does not fit the `path` buffer.
    PathTooLong,
    /// `grid` and `raw` have different geometries.
    GeometryMismatch,
}

impl core::fmt::Display for VoronoiError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            VoronoiError::Distance(e) => write!(f, "{e}"),
            VoronoiError::HeapFull { capacity } => {
                write!(f, "the priority queue is full ({capacity} entries)")
            }
            VoronoiError::PathTooLong => write!(f, "the path does not fit the path buffer"),
            VoronoiError::GeometryMismatch => {
                write!(f, "the grid and the raw map have different geometries")
            }
        }
    }
}

impl core::error::Error for VoronoiError {}

impl From<DistanceError> for VoronoiError {
    fn from(e: DistanceError) -> Self {
        VoronoiError::Distance(e)
    }
}

/// The caller's buffers: one entry per cell for all but `heap`.
#[derive(Debug)]
pub struct VoronoiBuffers<'a> {
    /// Nearest site of each cell (see [`distance::nearest_sites`]).
    pub sites: &'a mut [u32],
    /// Distance to the nearest site, 1/16 cell.
    pub dist: &'a mut [u16],
    /// Obstacle component labels.
    pub labels: &'a mut [u16],
    /// [`RIDGE`], [`CONNECTOR`] and the searches' parent directions.
    pub flags: &'a mut [u8],
    /// Search costs (and the labelling's stack).
    pub cost: &'a mut [u32],
    /// The priority queue.
    pub heap: &'a mut [u64],
    /// Output: the path's cell indices (row-major), start cell first.
    pub path: &'a mut [u32],
}

/// What a run found and did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VoronoiReport {
    /// How it ended.
    pub status: PlanStatus,
    /// Cells of the path written to `path`.
    pub path_cells: usize,
    /// Ridge cells of the roadmap.
    pub ridge_cells: usize,
    /// Connector cells added for retractions that stopped off the ridge.
    pub connector_cells: usize,
    /// Connector cells of the bridges between ridge ends and the rest of the roadmap.
    pub bridge_cells: usize,
    /// Cells popped by the searches.
    pub expanded: u64,
    /// The widest roadmap path's bottleneck: the smallest distance along it, 1/16 cell.
    pub bottleneck: u16,
    /// Obstacle components (the border's included).
    pub components: u16,
    /// Most entries the heap held.
    pub heap_peak: usize,
    /// Cells of the start's and the goal's retraction climbs.
    pub retraction_cells: [usize; 2],
}

/// The start and goal cells of a plan, or the status that ends it before any work.
pub fn endpoints<const W: usize>(
    grid: &Grid<W>,
    start: PointM,
    goal: PointM,
) -> Result<(Cell, Cell), PlanStatus> {
    let g = grid.geometry();
    let (Ok(s), Ok(t)) = (g.cell_of(start), g.cell_of(goal)) else {
        return Err(PlanStatus::OutOfBounds);
    };
    if grid.is_occupied(s) {
        return Err(PlanStatus::StartBlocked);
    }
    if grid.is_occupied(t) {
        return Err(PlanStatus::GoalBlocked);
    }
    Ok((s, t))
}

/// Whether the cells of `c` and its neighbour `n` see their nearest sites on two sides of a
/// ridge (see the module doc).
fn ridge_pair(geo: &GridGeometry, labels: &[u16], x: i32, y: i32, sc: u32, sn: u32) -> bool {
    if sc == sn || sc == NO_SITE || sn == NO_SITE {
        return false;
    }
    if site_label(geo, labels, sc) != site_label(geo, labels, sn) {
        return true;
    }
    let (nx, ny) = distance::unpack_site(sn);
    let separation2 = site_dist2(nx, ny, sc);
    separation2 > 8 && separation2 > site_dist2(x, y, sc)
}

struct Ctx<'g, 'b, const W: usize> {
    grid: &'g Grid<W>,
    w: i32,
    h: i32,
    flags: &'b mut [u8],
    cost: &'b mut [u32],
    dist: &'b [u16],
    heap: CellHeap<'b>,
    expanded: u64,
}

impl<const W: usize> Ctx<'_, '_, W> {
    fn reset(&mut self) {
        for f in self.flags.iter_mut() {
            *f &= (1 << PARENT_SHIFT) - 1;
        }
        self.cost.fill(u32::MAX);
        self.heap.clear();
    }

    fn xy(&self, i: usize) -> (i32, i32) {
        ((i % self.w as usize) as i32, (i / self.w as usize) as i32)
    }

    /// The neighbour of `i` in direction `d` (index into [`NEIGHBOURS_8`]) and its step cost,
    /// if on the map, free, and (for a diagonal) not cutting an occupied corner.
    fn step(&self, i: usize, d: usize) -> Option<(usize, u32)> {
        let (x, y) = self.xy(i);
        let &(dx, dy) = NEIGHBOURS_8.get(d)?;
        let (nx, ny) = (x + dx, y + dy);
        if self.grid.is_occupied_xy(nx, ny) {
            return None;
        }
        if dx != 0 && dy != 0 {
            if self.grid.is_occupied_xy(x + dx, y) || self.grid.is_occupied_xy(x, y + dy) {
                return None;
            }
            return Some(((ny * self.w + nx) as usize, DIAGONAL_COST));
        }
        Some(((ny * self.w + nx) as usize, STEP_COST))
    }

    fn push(&mut self, key: u32, item: usize) -> Result<(), VoronoiError> {
        self.heap
            .push(key, item as u32)
            .map_err(|e| VoronoiError::HeapFull {
                capacity: e.capacity,
            })
    }

    /// A* / Dijkstra from `from` over cells where `allowed`, to the first popped cell where
    /// `target` holds; parents are left in the flags. `goal` gives the octile heuristic.
    fn shortest(
        &mut self,
        from: usize,
        allowed: impl Fn(&Self, usize) -> bool,
        target: impl Fn(usize) -> bool,
        goal: Option<(i32, i32)>,
    ) -> Result<Option<usize>, VoronoiError> {
        self.reset();
        let heuristic = |this: &Self, i: usize| -> u32 {
            let Some((gx, gy)) = goal else { return 0 };
            let (x, y) = this.xy(i);
            let (dx, dy) = ((x - gx).unsigned_abs(), (y - gy).unsigned_abs());
            let (lo, hi) = (dx.min(dy), dx.max(dy));
            lo * DIAGONAL_COST + (hi - lo) * STEP_COST
        };
        *self.cost.get_mut(from).ok_or(VoronoiError::PathTooLong)? = 0;
        self.push(heuristic(self, from), from)?;
        while let Some((key, item)) = self.heap.pop() {
            let i = item as usize;
            let g = self.cost[i];
            if key != g.saturating_add(heuristic(self, i)) {
                continue; // stale entry
            }
            self.expanded += 1;
            if target(i) {
                return Ok(Some(i));
            }
            for d in 0..NEIGHBOURS_8.len() {
                let Some((j, c)) = self.step(i, d) else {
                    continue;
                };
                if !allowed(self, j) {
                    continue;
                }
                let ng = g.saturating_add(c);
                if ng < self.cost[j] {
                    self.cost[j] = ng;
                    self.flags[j] = (self.flags[j] & 0x0f) | ((d as u8 + 1) << PARENT_SHIFT);
                    self.push(ng.saturating_add(heuristic(self, j)), j)?;
                }
            }
        }
        Ok(None)
    }

    /// Widest path (largest smallest distance) from `from` to `to` over cells where `allowed`:
    /// its bottleneck, or `None` when not connected.
    fn widest(
        &mut self,
        from: usize,
        to: usize,
        allowed: impl Fn(&Self, usize) -> bool,
    ) -> Result<Option<u16>, VoronoiError> {
        self.reset();
        let first = *self.dist.get(from).ok_or(VoronoiError::PathTooLong)?;
        self.cost[from] = first as u32;
        self.push(u16::MAX as u32 - first as u32, from)?;
        while let Some((key, item)) = self.heap.pop() {
            let i = item as usize;
            let b = self.cost[i];
            if key != u16::MAX as u32 - b {
                continue;
            }
            self.expanded += 1;
            if i == to {
                return Ok(Some(b as u16));
            }
            for d in 0..NEIGHBOURS_8.len() {
                let Some((j, _)) = self.step(i, d) else {
                    continue;
                };
                if !allowed(self, j) {
                    continue;
                }
                let nb = b.min(self.dist[j] as u32);
                if self.cost[j] == u32::MAX || nb > self.cost[j] {
                    self.cost[j] = nb;
                    self.push(u16::MAX as u32 - nb, j)?;
                }
            }
        }
        Ok(None)
    }

    /// The cell a search reached `i` from, following the parent direction in the flags.
    fn parent(&self, i: usize) -> Option<usize> {
        let d = (self.flags.get(i)? >> PARENT_SHIFT).checked_sub(1)? as usize;
        let (dx, dy) = *NEIGHBOURS_8.get(d)?;
        let (x, y) = self.xy(i);
        Some(((y - dy) * self.w + (x - dx)) as usize)
    }

    /// Steepest ascent of the distance from `from` until a roadmap cell (or until `stop_at`,
    /// when given: the second time, after connectors were added); writes the cells to `out`
    /// (from first) and returns how many.
    fn climb(
        &self,
        from: usize,
        out: &mut [u32],
        stop_at: Option<usize>,
    ) -> Result<usize, VoronoiError> {
        let mut cur = from;
        let mut n = 0;
        loop {
            *out.get_mut(n).ok_or(VoronoiError::PathTooLong)? = cur as u32;
            n += 1;
            let stop = match stop_at {
                Some(c) => cur == c,
                None => self.flags[cur] & (RIDGE | CONNECTOR) != 0,
            };
            if stop {
                return Ok(n);
            }
            let mut best = (self.dist[cur], cur);
            for d in 0..NEIGHBOURS_8.len() {
                if let Some((j, _)) = self.step(cur, d) {
                    if self.dist[j] > best.0 {
                        best = (self.dist[j], j);
                    }
                }
            }
            if best.1 == cur {
                return Ok(n); // a maximum or plateau off the ridge
            }
            cur = best.1;
        }
    }

    /// The free 8-neighbour of `i` with the largest distance, if larger than `i`'s own.
    fn ascent(&self, i: usize) -> Option<usize> {
        let mut best = (*self.dist.get(i)?, i);
        for d in 0..NEIGHBOURS_8.len() {
            if let Some((j, _)) = self.step(i, d) {
                if self.dist[j] > best.0 {
                    best = (self.dist[j], j);
                }
            }
        }
        (best.1 != i).then_some(best.1)
    }

    /// Climb from every ridge cell; keep the climbs that leave the ridge and reach the roadmap
    /// again as connector cells (see the module doc). Returns the cells added.
    fn bridge_ridge_ends(&mut self) -> usize {
        let mut added = 0;
        for i in 0..self.flags.len() {
            if self.flags[i] & RIDGE == 0 {
                continue;
            }
            let (mut cur, mut marked, mut joined) = (i, 0usize, false);
            while let Some(j) = self.ascent(cur) {
                let f = self.flags[j];
                if f & (RIDGE | CONNECTOR) != 0 {
                    joined = true;
                    break;
                }
                if f & CLIMBED != 0 {
                    break; // an earlier climb from here ended off the roadmap
                }
                self.flags[j] |= CLIMBED | CONNECTOR;
                marked += 1;
                cur = j;
            }
            if joined {
                added += marked;
                continue;
            }
            // A dead end: the climb is deterministic, so walk it again and unmark it.
            let mut cur = i;
            for _ in 0..marked {
                let Some(j) = self.ascent(cur) else { break };
                self.flags[j] &= !CONNECTOR;
                cur = j;
            }
        }
        added
    }

    fn on_roadmap(&self, i: usize) -> bool {
        self.flags
            .get(i)
            .is_some_and(|f| f & (RIDGE | CONNECTOR) != 0)
    }

    /// Join `from` (off the roadmap) to the nearest roadmap cell by marking the shortest free
    /// path to it as connector cells. `false` when no roadmap cell is reachable.
    fn connect(&mut self, from: usize) -> Result<(bool, usize), VoronoiError> {
        if self.on_roadmap(from) {
            return Ok((true, 0));
        }
        self.reset();
        // Dijkstra by hand: its target test reads the flags, which `shortest`'s closures
        // cannot while the search writes them.
        self.cost[from] = 0;
        self.push(0, from)?;
        let mut hit = None;
        while let Some((key, item)) = self.heap.pop() {
            let i = item as usize;
            if key != self.cost[i] {
                continue;
            }
            self.expanded += 1;
            if self.flags[i] & (RIDGE | CONNECTOR) != 0 {
                hit = Some(i);
                break;
            }
            for d in 0..NEIGHBOURS_8.len() {
                let Some((j, c)) = self.step(i, d) else {
                    continue;
                };
                let ng = key.saturating_add(c);
                if ng < self.cost[j] {
                    self.cost[j] = ng;
                    self.flags[j] = (self.flags[j] & 0x0f) | ((d as u8 + 1) << PARENT_SHIFT);
                    self.push(ng, j)?;
                }
            }
        }
        let Some(mut i) = hit else {
            return Ok((false, 0));
        };
        let mut added = 0;
        while i != from {
            let Some(p) = self.parent(i) else { break };
            if self.flags[p] & (RIDGE | CONNECTOR) == 0 {
                self.flags[p] |= CONNECTOR;
                added += 1;
            }
            i = p;
        }
        Ok((true, added))
    }
}

/// Plan from `start` to `goal` along the Voronoi roadmap of `raw`'s obstacles, moving only
/// through `grid`'s free cells. The path's cells are left in `bufs.path`.
pub fn plan<const W: usize>(
    grid: &Grid<W>,
    raw: &Grid<W>,
    start: PointM,
    goal: PointM,
    bufs: VoronoiBuffers<'_>,
) -> Result<VoronoiReport, VoronoiError> {
    let geo = *grid.geometry();
    if *raw.geometry() != geo {
        return Err(VoronoiError::GeometryMismatch);
    }
    let n = geo.cell_count();
    for len in [
        bufs.dist.len(),
        bufs.labels.len(),
        bufs.flags.len(),
        bufs.cost.len(),
        bufs.path.len(),
    ] {
        distance::check_len(&geo, len)?;
    }
    let components = distance::label_components(raw, true, bufs.labels, bufs.cost)?;
    distance::nearest_sites(raw, true, bufs.sites)?;
    distance::distances(&geo, bufs.sites, bufs.dist)?;
    let (w, h) = (geo.width() as i32, geo.height() as i32);
    let mut ridge_cells = 0;
    for i in 0..n {
        let (x, y) = ((i % w as usize) as i32, (i / w as usize) as i32);
        let mut on = false;
        if !grid.bit(i) {
            for (dx, dy) in [(1, 0), (-1, 0), (0, 1), (0, -1)] {
                let (nx, ny) = (x + dx, y + dy);
                if nx < 0 || ny < 0 || nx >= w || ny >= h {
                    continue;
                }
                let j = (ny * w + nx) as usize;
                if ridge_pair(&geo, bufs.labels, x, y, bufs.sites[i], bufs.sites[j]) {
                    on = true;
                    break;
                }
            }
        }
        bufs.flags[i] = if on { RIDGE } else { 0 };
        ridge_cells += on as usize;
    }
    let mut report = VoronoiReport {
        status: PlanStatus::Unreachable,
        path_cells: 0,
        ridge_cells,
        connector_cells: 0,
        bridge_cells: 0,
        expanded: 0,
        bottleneck: 0,
        components,
        heap_peak: 0,
        retraction_cells: [0, 0],
    };
    let (s, t) = match endpoints(grid, start, goal) {
        Ok(st) => st,
        Err(status) => {
            report.status = status;
            return Ok(report);
        }
    };
    let (s, t) = (geo.index(s), geo.index(t));
    let path = bufs.path;
    let mut ctx = Ctx {
        grid,
        w,
        h,
        flags: bufs.flags,
        cost: bufs.cost,
        dist: bufs.dist,
        heap: CellHeap::new(bufs.heap),
        expanded: 0,
    };
    let _ = ctx.h;
    report.bridge_cells = ctx.bridge_ridge_ends();
    if s == t {
        if let Some(p) = path.first_mut() {
            *p = s as u32;
        }
        report.status = PlanStatus::Found;
        report.path_cells = 1;
        return Ok(report);
    }
    // Retractions (the climbs are recomputed when the path is written: they are deterministic).
    let a = ctx.climb(s, path, None)?;
    let rs = path[a - 1] as usize;
    let (ok_s, added_s) = ctx.connect(rs)?;
    let b = ctx.climb(t, path, None)?;
    let rt = path[b - 1] as usize;
    let (ok_t, added_t) = ctx.connect(rt)?;
    report.connector_cells = added_s + added_t;
    report.retraction_cells = [a, b];
    let finish = |ctx: &Ctx<'_, '_, W>, report: &mut VoronoiReport| {
        report.expanded = ctx.expanded;
        report.heap_peak = ctx.heap.peak();
    };
    if !(ok_s && ok_t) {
        finish(&ctx, &mut report);
        return Ok(report);
    }
    let roadmap = |c: &Ctx<'_, '_, W>, j: usize| c.on_roadmap(j);
    let Some(bottleneck) = ctx.widest(rs, rt, roadmap)? else {
        finish(&ctx, &mut report);
        return Ok(report);
    };
    report.bottleneck = bottleneck;
    let (gx, gy) = ctx.xy(rt);
    let wide = |c: &Ctx<'_, '_, W>, j: usize| c.on_roadmap(j) && c.dist[j] >= bottleneck;
    if ctx
        .shortest(rs, wide, |i| i == rt, Some((gx, gy)))?
        .is_none()
    {
        finish(&ctx, &mut report);
        return Ok(report);
    }
    // Write start climb, roadmap path, reversed goal climb.
    let a = ctx.climb(s, path, Some(rs))?;
    if path.get(a - 1) != Some(&(rs as u32)) {
        return Err(VoronoiError::PathTooLong);
    }
    let mut road = 0usize;
    let mut i = rt;
    while i != rs {
        road += 1;
        i = ctx.parent(i).ok_or(VoronoiError::PathTooLong)?;
        if road > n {
            return Err(VoronoiError::PathTooLong);
        }
    }
    let end = a + road;
    if end > path.len() {
        return Err(VoronoiError::PathTooLong);
    }
    let mut i = rt;
    for k in (a..end).rev() {
        path[k] = i as u32;
        i = ctx.parent(i).ok_or(VoronoiError::PathTooLong)?;
    }
    let tail = path.get_mut(end..).ok_or(VoronoiError::PathTooLong)?;
    let b = ctx.climb(t, tail, Some(rt))?;
    // The goal climb ends on rt, already written: drop it and reverse the rest.
    let tail = &mut tail[..b];
    tail.reverse();
    let tail_len = b - 1;
    path.copy_within(end + 1..end + b, end);
    report.path_cells = end + tail_len;
    report.status = PlanStatus::Found;
    finish(&ctx, &mut report);
    Ok(report)
}
