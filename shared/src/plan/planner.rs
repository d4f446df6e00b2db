//! [`Planner`]: the scratch, the queue and the path buffer of one planner, and the dispatch of
//! a request: status checks, then BFS (jump points or layered), A* (jump points or cell by
//! cell) or any-angle, then the path rebuild and the report. A plan that may overflow the path
//! keeps the last one ([`Kept`]): an error never changes what [`Planner::path_cells`] returns.
//! The searches themselves live in `jump.rs`, `astar.rs` and `bfs/`, the rebuilds in `path.rs`
//! and `any_angle.rs`.

use super::choice::{cluttered, JPS_STEPS_MAX_EXPANSIONS};
use super::codes::{set_nibble, spread_bits_to_nibbles, BLOCKED, BLOCKED_NIBBLES, CODE_START};
use super::goal::GOAL_TABLE_WORDS;
use super::meet::Meet;
use super::open_list::OpenEntry;
use super::{
    scratch_words_for_cells, PathCells, PlanError, PlanReport, PlanStatus, PlannerKind,
    MAX_PATH_POINTS, STRAIGHT_COST,
};
use crate::geom::{Cell, PointM};
use crate::grid::{Grid, GridGeometry};
use heapless::Vec;

/// Outcome of the search phase, before the path is rebuilt.
pub(super) struct Search {
    pub(super) found: bool,
    pub(super) expanded: u32,
    pub(super) cost: u32,
}

/// A planner with its scratch memory: `SCRATCH_WORDS` 32-bit words hold 8 cells each (4 bits
/// per cell, see [`scratch_words_for_cells`]), `QUEUE` is the open-list capacity in entries
/// (12 bytes each).
///
/// A planner is reusable: every call clears the scratch of the cells it uses. It is large
/// (`4 × SCRATCH_WORDS + 12 × QUEUE + 12 288 + 2 560` bytes: the vertex buffer and the
/// cell-by-cell A*'s goal table), so keep it in a `static` or a `Box`, not on a small stack.
pub struct Planner<const SCRATCH_WORDS: usize, const QUEUE: usize> {
    pub(super) scratch: [u32; SCRATCH_WORDS],
    pub(super) queue: [OpenEntry; QUEUE],
    pub(super) cells: PathCells,
    /// The per-axis goal table of the cell-by-cell A* ([`goal_axis_entry`](crate::plan::goal::goal_axis_entry)), refilled by
    /// every framed search on a grid of at most [`GOAL_AXIS_CELLS`](crate::plan::goal::GOAL_AXIS_CELLS) a side.
    pub(super) goal_axis: [u32; GOAL_TABLE_WORDS],
    pub(super) last: Option<PlanReport>,
    pub(super) queue_peak: u32,
    /// Where the last search left each cell's nibble (read by the path rebuild).
    pub(super) layout: Layout,
}

/// Where the nibble of a cell is in the scratch after a search.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Layout {
    /// Row-major, `width` nibbles a row (jump points, scalar BFS, [`Flat`](crate::plan::layout::Flat) A*).
    Flat,
    /// [`Framed`](crate::plan::layout::Framed) A*: rows of `stride` nibbles, one frame row and column before the map.
    Framed { stride: usize },
}

impl Layout {
    /// The scratch index of `cell` (a cell of the map).
    pub(super) fn index(self, geometry: &GridGeometry, cell: Cell) -> usize {
        match self {
            Layout::Flat => geometry.index(cell),
            Layout::Framed { stride } => (cell.y as usize + 1) * stride + cell.x as usize + 1,
        }
    }

    /// The scratch index step of one row up.
    pub(super) fn row_step(self, geometry: &GridGeometry) -> usize {
        match self {
            Layout::Flat => geometry.width() as usize,
            Layout::Framed { stride } => stride,
        }
    }
}

impl<const SCRATCH_WORDS: usize, const QUEUE: usize> Planner<SCRATCH_WORDS, QUEUE> {
    /// Cells the scratch memory covers.
    pub const CAPACITY_CELLS: usize = SCRATCH_WORDS * 8;

    /// A planner with cleared scratch.
    pub const fn new() -> Self {
        Self {
            scratch: [0; SCRATCH_WORDS],
            queue: [OpenEntry::ZERO; QUEUE],
            cells: Vec::new(),
            goal_axis: [0; GOAL_TABLE_WORDS],
            last: None,
            queue_peak: 0,
            layout: Layout::Flat,
        }
    }

    /// Plan from `start` to `goal` on `grid`, writing the polyline to `path` (cleared first).
    ///
    /// Start and goal are snapped to the cells that contain them; the path runs from the start
    /// cell's centre to the goal cell's centre. A start or goal off the map or not finite gives
    /// `Ok` with [`PlanStatus::OutOfBounds`]; occupied ones [`PlanStatus::StartBlocked`] /
    /// [`PlanStatus::GoalBlocked`] (checked in that order); `start` and `goal` in the same free
    /// cell give [`PlanStatus::Found`] with a one-point path. `path` is empty unless found.
    ///
    /// Errors: [`PlanError::ScratchTooSmall`] when the grid has more cells than the scratch,
    /// [`PlanError::QueueFull`] when the open list overflows, [`PlanError::PathFull`] when the
    /// polyline has more vertices than `path` holds (at most [`MAX_PATH_POINTS`]: `path` then
    /// holds nothing and
    /// [`Planner::last_report`] has the search's result).
    pub fn plan<const W: usize, const P: usize>(
        &mut self,
        kind: PlannerKind,
        grid: &Grid<W>,
        start: PointM,
        goal: PointM,
        path: &mut Vec<PointM, P>,
    ) -> Result<PlanReport, PlanError> {
        path.clear();
        let report = self.plan_at(kind, grid, start, goal)?;
        let geometry = *grid.geometry();
        for &c in self.cells.iter() {
            if path.push(geometry.center_of(c)).is_err() {
                path.clear();
                return Err(PlanError::PathFull {
                    capacity: P.min(MAX_PATH_POINTS) as u32,
                });
            }
        }
        Ok(report)
    }

    /// [`Planner::plan`] without the polyline in metres: it stays in [`Planner::path_cells`]
    /// (until the next plan), so a caller that only reads it back needs no path buffer of its
    /// own.
    pub fn plan_at<const W: usize>(
        &mut self,
        kind: PlannerKind,
        grid: &Grid<W>,
        start: PointM,
        goal: PointM,
    ) -> Result<PlanReport, PlanError> {
        self.last = None;
        let geometry = *grid.geometry();
        let (Ok(start_cell), Ok(goal_cell)) = (geometry.cell_of(start), geometry.cell_of(goal))
        else {
            self.check_scratch(&geometry)?;
            self.cells.clear();
            let report = PlanReport::empty(PlanStatus::OutOfBounds);
            self.last = Some(report);
            return Ok(report);
        };
        self.plan_cells(kind, grid, start_cell, goal_cell)
    }

    /// Plan between two cells; the polyline (as cells) is then [`Planner::path_cells`].
    ///
    /// Same contract as [`Planner::plan`]; cells outside the grid give
    /// [`PlanStatus::OutOfBounds`].
    pub fn plan_cells<const W: usize>(
        &mut self,
        kind: PlannerKind,
        grid: &Grid<W>,
        start: Cell,
        goal: Cell,
    ) -> Result<PlanReport, PlanError> {
        self.plan_cells_with(kind, grid, start, goal, true)
    }

    /// [`Planner::plan_cells`]; with `bfs_jump_points` false BFS always runs the layered search
    /// (the tests check it on maps where the planner would run jump points).
    pub(super) fn plan_cells_with<const W: usize>(
        &mut self,
        kind: PlannerKind,
        grid: &Grid<W>,
        start: Cell,
        goal: Cell,
        bfs_jump_points: bool,
    ) -> Result<PlanReport, PlanError> {
        // The last path stays until this plan has a result: an error (scratch, queue or path
        // capacity) leaves it as it was.
        self.last = None;
        self.queue_peak = 0;
        self.layout = Layout::Flat;
        let geometry = *grid.geometry();
        self.check_scratch(&geometry)?;
        let inside = |c: Cell| geometry.contains_xy(c.x as i32, c.y as i32);
        let status = if !inside(start) || !inside(goal) {
            Some(PlanStatus::OutOfBounds)
        } else if grid.is_occupied(start) {
            Some(PlanStatus::StartBlocked)
        } else if grid.is_occupied(goal) {
            Some(PlanStatus::GoalBlocked)
        } else {
            None
        };
        if let Some(status) = status {
            self.cells.clear();
            let report = PlanReport::empty(status);
            self.last = Some(report);
            return Ok(report);
        }
        let (search, bfs_meet) = self.search(kind, grid, start, goal, bfs_jump_points)?;
        if !search.found {
            self.cells.clear();
            let report = PlanReport {
                status: PlanStatus::Unreachable,
                expanded: search.expanded,
                cost: 0,
                length_m: 0.0,
            };
            self.last = Some(report);
            return Ok(report);
        }
        self.write_path(kind, grid, goal, search, bfs_meet)
    }

    /// The search of a request whose start and goal are free cells of the map: jump points on
    /// uncluttered maps (octile costs for A\* and any-angle, unit costs for BFS), else, or when
    /// they give up, the layered BFS or the cell-by-cell A\*; and where the layered BFS met
    /// (`None` for the other searches, whose path is in the nibbles).
    fn search<const W: usize>(
        &mut self,
        kind: PlannerKind,
        grid: &Grid<W>,
        start: Cell,
        goal: Cell,
        bfs_jump_points: bool,
    ) -> Result<(Search, Option<Meet>), PlanError> {
        let geometry = *grid.geometry();
        // Jump point search (A* and any-angle with octile costs, BFS with unit costs) reads
        // the map's own bits and needs cleared nibbles only (its fallbacks set up their own
        // scratch). On a cluttered map (nearly every free cell would be a jump point) A* runs
        // cell by cell at once, from a copy of the map, and BFS runs the layered search, which
        // sets up its own bit planes (or, in narrow maps, a copy of the map).
        let used_words = scratch_words_for_cells(geometry.cell_count());
        let jump_points = (kind != PlannerKind::Bfs || bfs_jump_points)
            && !cluttered(grid.words(), &geometry, start, goal);
        match kind {
            _ if jump_points => self
                .scratch
                .get_mut(..used_words)
                .unwrap_or(&mut [])
                .fill(0),
            // The layered BFS sets up its own bit planes, cell-by-cell A* its copy of the map.
            _ => {}
        }
        let start_index = geometry.index(start);
        let goal_index = geometry.index(goal);
        // Where the layered BFS met (else, when found, the scalar BFS left its path in the
        // nibbles).
        let mut bfs_meet = None;
        let search = if start_index == goal_index {
            set_nibble(&mut self.scratch, start_index, CODE_START);
            Search {
                found: true,
                expanded: 0,
                cost: 0,
            }
        } else {
            match kind {
                PlannerKind::Bfs if jump_points => {
                    match self.jps_steps(
                        grid,
                        start_index,
                        goal,
                        goal_index,
                        JPS_STEPS_MAX_EXPANSIONS,
                    ) {
                        Ok(search) => search,
                        Err(jps_expanded) => {
                            // Jump points turned out too many, or the queue ran out of entries
                            // for them: the layered BFS.
                            let (search, meet) = self.bfs(grid, start, goal)?;
                            bfs_meet = meet;
                            Search {
                                expanded: search.expanded.saturating_add(jps_expanded),
                                ..search
                            }
                        }
                    }
                }
                PlannerKind::Bfs => {
                    let (search, meet) = self.bfs(grid, start, goal)?;
                    bfs_meet = meet;
                    search
                }
                PlannerKind::AStar | PlannerKind::AnyAngle if !jump_points => {
                    self.astar(grid, start_index, goal)?
                }
                PlannerKind::AStar | PlannerKind::AnyAngle => {
                    match self.jps(grid, start_index, goal, goal_index) {
                        Ok(search) => search,
                        Err(jps_expanded) => {
                            // Cluttered map (JPS scans more than it saves) or the queue ran
                            // out of entries for jump points and their records: cell-by-cell
                            // A*, which also reclaims stale entries more finely.
                            let plain = self.astar(grid, start_index, goal)?;
                            Search {
                                expanded: plain.expanded.saturating_add(jps_expanded),
                                ..plain
                            }
                        }
                    }
                }
            }
        };
        Ok((search, bfs_meet))
    }

    /// Writes the path of a search that found the goal into the cell buffer and reports it;
    /// `PathFull` keeps the last path.
    fn write_path<const W: usize>(
        &mut self,
        kind: PlannerKind,
        grid: &Grid<W>,
        goal: Cell,
        search: Search,
        bfs_meet: Option<Meet>,
    ) -> Result<PlanReport, PlanError> {
        let geometry = *grid.geometry();
        // `PathFull` must keep the last path. Only long paths may not fit: a path of `steps`
        // moves has at most `steps + 2` vertices (any-angle adds at most one per run of the
        // A* path, and the final one). For those the last path is first put aside in the
        // queue, free once the search is over (the firmware's 1 024 entries hold all 3 072
        // vertices, 3 a entry), and put back if the new one does not fit; a planner whose
        // queue is too small counts the new path before writing it (its rebuild twice).
        let steps_bound = match kind {
            PlannerKind::Bfs if search.cost > 0 => search.cost,
            PlannerKind::Bfs => u32::MAX, // the layered BFS does not count its steps
            _ => search.cost / STRAIGHT_COST,
        };
        let may_overflow = steps_bound.saturating_add(2) as usize > MAX_PATH_POINTS;
        let rebuild = |planner: &mut Self, count_only: bool| match kind {
            PlannerKind::AnyAngle => planner.rebuild_any_angle(grid, goal, count_only),
            PlannerKind::Bfs => match bfs_meet {
                Some(meet) => planner.bfs_rebuild(grid, goal, meet, count_only),
                None => planner.rebuild_merged(&geometry, goal, count_only),
            },
            _ => planner.rebuild_merged(&geometry, goal, count_only),
        };
        let last_path = self.cells.len();
        let kept = match may_overflow && last_path > 0 {
            false => Kept::Nothing,
            true if self.stash_path() => Kept::InQueue(last_path),
            true => Kept::Counted,
        };
        let counted = match kept {
            Kept::Counted => Some(rebuild(self, true)),
            _ => None,
        };
        let (length_cells, steps, fits) = match counted {
            Some(counted) if !counted.2 => counted,
            _ => {
                self.cells.clear();
                rebuild(self, false)
            }
        };
        if !fits {
            match kept {
                Kept::InQueue(n) => self.unstash_path(n),
                Kept::Counted => {} // not written
                Kept::Nothing => self.cells.clear(),
            }
        }
        let report = PlanReport {
            status: PlanStatus::Found,
            expanded: search.expanded,
            cost: match kind {
                PlannerKind::Bfs => steps,
                _ => search.cost,
            },
            length_m: length_cells * geometry.resolution_m(),
        };
        self.last = Some(report);
        if !fits {
            return Err(PlanError::PathFull {
                capacity: MAX_PATH_POINTS as u32,
            });
        }
        Ok(report)
    }

    /// The polyline of the last successful plan, as cells (start cell first). Empty after a
    /// plan that found no path; an error ([`PlanError`]) leaves the previous path.
    pub fn path_cells(&self) -> &[Cell] {
        &self.cells
    }

    /// Copy the last path into the queue (3 cells an entry); `false` when it does not fit.
    /// Only after a search: the queue is free until the next one.
    fn stash_path(&mut self) -> bool {
        if self.cells.len().div_ceil(3) > QUEUE {
            return false;
        }
        let pack = |c: Option<&Cell>| c.map_or(0, |c| (c.x as u32) << 16 | c.y as u32);
        for (entry, chunk) in self.queue.iter_mut().zip(self.cells.chunks(3)) {
            entry.f = pack(chunk.first());
            entry.node = pack(chunk.get(1));
            entry.next = pack(chunk.get(2));
        }
        true
    }

    /// Put back the `n` cells of the path [`Planner::stash_path`] copied.
    fn unstash_path(&mut self, n: usize) {
        self.cells.clear();
        for entry in self.queue.iter().take(n.div_ceil(3)) {
            for word in [entry.f, entry.node, entry.next] {
                if self.cells.len() < n {
                    let _ = self.cells.push(Cell::new((word >> 16) as u16, word as u16));
                }
            }
        }
    }

    /// The report of the last planning request, also when it ended in
    /// [`PlanError::PathFull`] (then `status` is `Found` and cost/length/expanded are those of
    /// the path that did not fit). `None` before the first request and after the other errors.
    pub fn last_report(&self) -> Option<PlanReport> {
        self.last
    }

    /// Most queue entries in use at once during the last search (A*: open-list entries, stale
    /// ones included; scalar BFS: ring-buffer entries). Size `QUEUE` from this on your maps. The
    /// layered BFS uses no queue entries: there it is the most frontier (row, word) pairs of one
    /// layer.
    pub fn queue_peak(&self) -> u32 {
        self.queue_peak
    }

    fn check_scratch(&self, geometry: &GridGeometry) -> Result<(), PlanError> {
        if geometry.cell_count() > Self::CAPACITY_CELLS {
            return Err(PlanError::ScratchTooSmall {
                cells: geometry.cell_count() as u32,
                capacity: Self::CAPACITY_CELLS as u32,
            });
        }
        Ok(())
    }

    /// Copy the map into the scratch: occupied cells [`BLOCKED`], free cells 0.
    pub(super) fn copy_map<const GW: usize>(&mut self, grid: &Grid<GW>) {
        let used_words = scratch_words_for_cells(grid.geometry().cell_count());
        let used = self.scratch.get_mut(..used_words).unwrap_or(&mut []);
        let mut quads = used.chunks_exact_mut(4);
        let mut bits = grid.words().iter();
        for (quad, &b) in (&mut quads).zip(&mut bits) {
            if let [w0, w1, w2, w3] = quad {
                *w0 = BLOCKED_NIBBLES[(b & 0xFF) as usize];
                *w1 = BLOCKED_NIBBLES[((b >> 8) & 0xFF) as usize];
                *w2 = BLOCKED_NIBBLES[((b >> 16) & 0xFF) as usize];
                *w3 = BLOCKED_NIBBLES[(b >> 24) as usize];
            }
        }
        // The last grid word may cover fewer than four scratch words.
        if let Some(&b) = bits.next() {
            for (k, word) in quads.into_remainder().iter_mut().enumerate() {
                *word = spread_bits_to_nibbles(b >> (8 * k)) * BLOCKED;
            }
        }
    }
}

/// How a plan that may overflow the path keeps the last one.
#[derive(Clone, Copy, Debug)]
enum Kept {
    /// No last path, or the new one surely fits.
    Nothing,
    /// Copied into the queue: this many cells.
    InQueue(usize),
    /// The new path is counted before it is written.
    Counted,
}

impl<const SCRATCH_WORDS: usize, const QUEUE: usize> Default for Planner<SCRATCH_WORDS, QUEUE> {
    fn default() -> Self {
        Self::new()
    }
}
