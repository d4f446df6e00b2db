//! Path planners on the occupancy grid: BFS (the seed's), A* (octile, optimal) and an any-angle
//! variant, plus the pruning of a plan to what the sonar has just seen.
//!
//! ## Contract
//!
//! - Neighbour rule (seed §IV.2, `gera_trajetoria`): the 4 side neighbours, plus a diagonal
//!   neighbour only when both side cells it passes between are free (no corner cutting).
//! - Costs: BFS counts steps (a diagonal step is one step); A* uses the integer octile costs
//!   [`STRAIGHT_COST`] / [`DIAGONAL_COST`] (their ratio is √2 to 7 digits), so costs compare
//!   exactly with a reference implementation.
//! - Memory: a [`Planner`] owns all its scratch: 4 bits per cell and a queue of fixed capacity.
//!   Running out of queue or path capacity is a [`PlanError`], never a panic.
//! - Output: the path as a polyline in world metres (cell centres), from the start cell to the
//!   goal cell, with collinear cells merged; a [`PlanReport`] with the status, cost, length and the
//!   number of cells expanded. The same polyline as cells is [`Planner::path_cells`].
//!
//! ## Memory layout
//!
//! The scratch memory is one nibble (4 bits) per cell, 8 cells per `u32` word, row-major like
//! the grid:
//!
//! | code      | meaning                                                        |
//! |-----------|----------------------------------------------------------------|
//! | 0         | not reached yet                                                |
//! | 1 ..= 8   | reached, final; the code names the step *from* the parent      |
//! | 9         | the start cell (no parent)                                     |
//! | 10 ..= 15 | unused                                                         |
//!
//! For the seed's 300 × 300 grid that is **45 000 bytes** of scratch (`SCRATCH_WORDS = 11 250`,
//! [`SCRATCH_WORDS_300`]), plus the queue: 12 bytes per entry (`QUEUE = 4096` → 49 152 bytes),
//! plus the vertex buffer of [`MAX_PATH_POINTS`] cells (4 096 bytes). Nothing else is
//! allocated; the grid itself is only read. [`Planner::queue_peak`] tells how much of the queue
//! a search used (on the benchmark's 300 × 300 grids: BFS ≤ 600 entries, A* ≤ 3 800).
//!
//! ## Why A* needs no g-table
//!
//! A textbook A* keeps the best known cost `g` of every cell so that it can decrease a key in the
//! open list. Here the open list holds `(f, cell, step)` entries with *lazy deletion*: a cell may
//! be pushed several times (once per neighbour that reaches it), and only its first pop counts.
//! Because the octile heuristic is consistent for these integer costs (it is the exact cost on an
//! empty grid, a metric), the first time a cell leaves the open list at the minimum `f` its `g`
//! is optimal, so the pop writes the parent step into the cell's nibble and later entries of the
//! same cell are skipped. Cells already closed are never pushed again. `g` itself is not stored:
//! it is `f - h(cell)`.
//!
//! The open list is a *radix heap* (a monotone priority queue: a consistent heuristic never
//! pushes an `f` below the last one popped): 33 buckets by the highest bit in which a key differs
//! from the last popped key, each a linked list threaded through the fixed pool of entries. A
//! push is O(1); a pop takes the head of bucket 0 (keys equal to the last) or, when that is
//! empty, relinks the lowest non-empty bucket around its minimum, dropping entries whose cell
//! was closed meanwhile. On the benchmark this is 6–8× faster than the binary heap it replaced.
//! Ties on `f` pop the last pushed entry first: the children of the cell just expanded, i.e. the
//! deeper entries, which on open floors walks straight to the goal instead of flooding the whole
//! diamond of equal-`f` cells (294 cells expanded corner to corner on an empty 300 × 300 grid).
//!
//! BFS marks a cell (with its parent step) when it is first *discovered*: in a FIFO queue the
//! first discovery is by a fewest-steps parent, so every cell enters the ring buffer at most once.
//!
//! Search loops carry cell coordinates in their queue entries (no division per cell) and test
//! the 8 neighbours with index arithmetic on the row-major bit and nibble arrays.
//!
//! ## Complexity
//!
//! BFS: `O(n)` time for `n` free cells. A*: `O(n · 8)` pushes, each O(1), and pops amortized
//! O(log C) for the cost range `C` (32-bit keys: at most 32 moves per entry). Clearing the
//! scratch costs `n / 8` word writes. Rebuilding the path walks the parent steps from the goal
//! back to the start: `O(path cells)`, plus, for the any-angle planner, one line-of-sight test
//! per path cell (`O(path cells × segment length)`).
//!
//! ## Any-angle
//!
//! [`PlannerKind::AnyAngle`] runs A*, then pulls the string on the A* cell path: walking from the
//! goal towards the start, it keeps an anchor vertex and advances along the cell path while the
//! next cell is visible from the anchor by [`line_of_sight`]; at the first cell that is not, the
//! last visible cell becomes a vertex and the new anchor. Every segment therefore passes the same
//! no-corner-cutting line-of-sight test, and by the triangle inequality the polyline is never
//! longer than the A* path it shortcuts.
//!
//! ```
//! use twil_core::geom::PointM;
//! use twil_core::grid::{Grid, GridGeometry, words_for_cells};
//! use twil_core::plan::{PathM, Planner, PlannerKind, PlanStatus, scratch_words_for_cells};
//!
//! let geometry = GridGeometry::new(20, 10, 0.1).unwrap();
//! let mut grid = Grid::<{ words_for_cells(200) }>::new(geometry).unwrap();
//! for y in 0..8 {
//!     grid.set_xy(10, y, true); // a wall with a gap at the top
//! }
//! let mut planner = Planner::<{ scratch_words_for_cells(200) }, 256>::new();
//! let mut path = PathM::new();
//! let report = planner
//!     .plan(PlannerKind::AStar, &grid, PointM::new(0.15, 0.15), PointM::new(1.85, 0.15), &mut path)
//!     .unwrap();
//! assert_eq!(report.status, PlanStatus::Found);
//! assert_eq!(path.first(), Some(&PointM::new(0.15, 0.15)));
//! assert!(report.length_m > 1.7);
//! ```

mod los;
mod prune;

#[cfg(test)]
mod tests;

pub use los::{line_of_sight, line_of_sight_m};
pub use prune::{needs_full_sweep, prune_visible_prefix, PruneEnd, Pruned, NORMAL_HALF_BAND_RAD};

use heapless::Vec;

use crate::geom::{Cell, PointM};
use crate::grid::{Grid, GridGeometry};

/// Cost of a side step in A* (integer octile costs: `DIAGONAL_COST / STRAIGHT_COST` ≈ √2).
pub const STRAIGHT_COST: u32 = 5741;
/// Cost of a diagonal step in A*.
pub const DIAGONAL_COST: u32 = 8119;

/// Largest number of vertices in a returned path polyline.
pub const MAX_PATH_POINTS: usize = 1024;

/// A path in world metres, first point = start cell centre, last = goal cell centre.
pub type PathM = Vec<PointM, MAX_PATH_POINTS>;

/// The same polyline as [`PathM`], as grid cells.
pub type PathCells = Vec<Cell, MAX_PATH_POINTS>;

/// Number of scratch words a [`Planner`] needs for `cells` cells (4 bits per cell).
pub const fn scratch_words_for_cells(cells: usize) -> usize {
    cells.div_ceil(8)
}

/// Scratch words for the seed's 300 × 300 grid (45 000 bytes).
pub const SCRATCH_WORDS_300: usize = scratch_words_for_cells(300 * 300);
/// Scratch words for a 400 × 400 grid (80 000 bytes).
pub const SCRATCH_WORDS_400: usize = scratch_words_for_cells(400 * 400);

/// Which planner to run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PlannerKind {
    /// Breadth-first search, the seed's planner: fewest steps.
    Bfs,
    /// A* with octile costs: shortest 8-connected path.
    #[default]
    AStar,
    /// A* followed by line-of-sight shortcuts: straight segments, never longer than A*.
    AnyAngle,
}

/// How a planning request ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PlanStatus {
    /// A path was found.
    Found,
    /// Start and goal are free but not connected.
    Unreachable,
    /// The start cell is occupied.
    StartBlocked,
    /// The goal cell is occupied.
    GoalBlocked,
    /// Start or goal lies outside the map.
    OutOfBounds,
}

/// A capacity ran out while planning.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PlanError {
    /// The grid has more cells than the planner's scratch memory covers.
    ScratchTooSmall {
        /// Cells in the grid.
        cells: u32,
        /// Cells the scratch covers.
        capacity: u32,
    },
    /// The open queue filled up.
    QueueFull {
        /// Queue capacity, entries.
        capacity: u32,
    },
    /// The path has more vertices than [`MAX_PATH_POINTS`]. The search itself succeeded:
    /// [`Planner::last_report`] has its cost, length and expansions.
    PathFull {
        /// Path capacity, vertices.
        capacity: u32,
    },
}

impl core::fmt::Display for PlanError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            PlanError::ScratchTooSmall { cells, capacity } => write!(
                f,
                "grid has {cells} cells but the planner's scratch covers {capacity}"
            ),
            PlanError::QueueFull { capacity } => {
                write!(f, "planner queue full ({capacity} entries)")
            }
            PlanError::PathFull { capacity } => {
                write!(f, "path has more than {capacity} vertices")
            }
        }
    }
}

/// What a planning request produced (the path itself goes to the caller's [`PathM`]).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PlanReport {
    /// How it ended.
    pub status: PlanStatus,
    /// Cells taken off the queue and expanded.
    pub expanded: u32,
    /// BFS: steps; A* and any-angle: the A* cost in [`STRAIGHT_COST`] units. 0 unless found.
    pub cost: u32,
    /// Euclidean length of the returned polyline, metres. 0 unless found.
    pub length_m: f32,
}

impl PlanReport {
    const fn empty(status: PlanStatus) -> Self {
        Self {
            status,
            expanded: 0,
            cost: 0,
            length_m: 0.0,
        }
    }
}

/// One open-list / queue entry: 12 bytes.
#[derive(Clone, Copy, Debug)]
struct OpenEntry {
    /// `g + h` (A*), unused by BFS.
    f: u32,
    /// `cell_index << 4 | step code` (A*), `cell_index` (BFS).
    node: u32,
    /// Next entry of the same radix bucket (A*), unused by BFS.
    next: u32,
}

impl OpenEntry {
    const ZERO: Self = Self {
        f: 0,
        node: 0,
        next: NIL,
    };
}

/// Nibble code of the start cell.
const CODE_START: u32 = 9;

/// Step of each code 1..=8 (index = code - 1): E, N, W, S, NE, NW, SW, SE.
const STEPS: [(i32, i32); 8] = [
    (1, 0),
    (0, 1),
    (-1, 0),
    (0, -1),
    (1, 1),
    (-1, 1),
    (-1, -1),
    (1, -1),
];
const E: u32 = 1;
const N: u32 = 2;
const W: u32 = 3;
const S: u32 = 4;
const NE: u32 = 5;
const NW: u32 = 6;
const SW: u32 = 7;
const SE: u32 = 8;

#[inline(always)]
fn nibble(scratch: &[u32], index: usize) -> u32 {
    match scratch.get(index >> 3) {
        Some(w) => (w >> ((index & 7) * 4)) & 0xF,
        None => 0xF,
    }
}

#[inline(always)]
fn set_nibble(scratch: &mut [u32], index: usize, code: u32) {
    if let Some(w) = scratch.get_mut(index >> 3) {
        let shift = (index & 7) * 4;
        *w = (*w & !(0xF << shift)) | (code << shift);
    }
}

/// Octile distance in A* cost units.
#[inline(always)]
fn octile(dx: u32, dy: u32) -> u32 {
    let (lo, hi) = if dx < dy { (dx, dy) } else { (dy, dx) };
    DIAGONAL_COST
        .saturating_mul(lo)
        .saturating_add(STRAIGHT_COST.saturating_mul(hi - lo))
}

/// End of a bucket list.
const NIL: u32 = u32::MAX;
/// Radix buckets: 0 holds keys equal to the last popped key, `b` keys whose highest bit that
/// differs from it is bit `b - 1`.
const BUCKETS: usize = 33;

/// A monotone priority queue (radix heap) over a fixed pool of entries: keys pushed are never
/// below the last key popped, which A* with a consistent heuristic guarantees for `f`.
///
/// Buckets are singly linked lists threaded through the pool, so a push is O(1) (link at the
/// head of its bucket, update the bucket's minimum) and a pop is O(1) from bucket 0, or, when
/// bucket 0 is empty, one pass over the lowest non-empty bucket that relinks its entries into
/// lower buckets relative to the bucket's minimum (the new reference key). Each entry moves down
/// at most 32 times; in practice once or twice, since `f` grows slowly. Entries that went stale
/// (their cell was closed meanwhile) are dropped during that pass instead of being moved.
/// Within bucket 0 (equal `f`) the last pushed entry pops first: the children of the cell just
/// expanded, i.e. the deeper entries (larger `g`), which on open floors keeps the search on one
/// straight line instead of flooding every cell of equal `f`.
struct RadixQueue<'a> {
    pool: &'a mut [OpenEntry],
    heads: [u32; BUCKETS],
    mins: [u32; BUCKETS],
    nonempty: u64,
    last: u32,
    bump: u32,
    free: u32,
}

impl<'a> RadixQueue<'a> {
    fn new(pool: &'a mut [OpenEntry]) -> Self {
        Self {
            pool,
            heads: [NIL; BUCKETS],
            mins: [u32::MAX; BUCKETS],
            nonempty: 0,
            last: 0,
            bump: 0,
            free: NIL,
        }
    }

    #[inline(always)]
    fn bucket(&self, key: u32) -> usize {
        let diff = key ^ self.last;
        (u32::BITS - diff.leading_zeros()) as usize
    }

    /// Insert; `false` when the pool is full.
    #[inline(always)]
    fn push(&mut self, key: u32, node: u32) -> bool {
        let slot = if self.free != NIL {
            let slot = self.free;
            self.free = self.pool[slot as usize].next;
            slot
        } else if (self.bump as usize) < self.pool.len() {
            self.bump += 1;
            self.bump - 1
        } else {
            return false;
        };
        let b = self.bucket(key);
        self.pool[slot as usize] = OpenEntry {
            f: key,
            node,
            next: self.heads[b],
        };
        self.heads[b] = slot;
        self.mins[b] = self.mins[b].min(key);
        self.nonempty |= 1 << b;
        true
    }

    /// Drop every stale entry (`stale(node)`) from every bucket, recomputing the buckets'
    /// minima. Returns how many slots were freed. O(entries); used only when the pool is full.
    #[cold]
    fn collect(&mut self, stale: impl Fn(u32) -> bool) -> usize {
        let mut freed = 0;
        for b in 0..BUCKETS {
            let mut slot = self.heads[b];
            let (mut head, mut min) = (NIL, u32::MAX);
            while slot != NIL {
                let e = &mut self.pool[slot as usize];
                let next = e.next;
                if stale(e.node) {
                    e.next = self.free;
                    self.free = slot;
                    freed += 1;
                } else {
                    min = min.min(e.f);
                    e.next = head;
                    head = slot;
                }
                slot = next;
            }
            self.heads[b] = head;
            self.mins[b] = min;
            if head == NIL {
                self.nonempty &= !(1 << b);
            }
        }
        freed
    }

    /// Remove an entry of the smallest key: `(key, node)`. `stale(node)` tells which entries
    /// may be dropped unseen when a bucket is redistributed.
    #[inline(always)]
    fn pop(&mut self, stale: impl Fn(u32) -> bool) -> Option<(u32, u32)> {
        while self.heads[0] == NIL {
            let rest = self.nonempty & !1;
            if rest == 0 {
                return None;
            }
            let b = rest.trailing_zeros() as usize;
            let min = self.mins[b];
            self.last = min;
            let mut slot = self.heads[b];
            self.heads[b] = NIL;
            self.mins[b] = u32::MAX;
            self.nonempty &= !(1 << b);
            while slot != NIL {
                let e = &mut self.pool[slot as usize];
                let next = e.next;
                if stale(e.node) {
                    e.next = self.free;
                    self.free = slot;
                } else {
                    let key = e.f;
                    let nb = (u32::BITS - (key ^ min).leading_zeros()) as usize;
                    e.next = self.heads[nb];
                    self.heads[nb] = slot;
                    self.mins[nb] = self.mins[nb].min(key);
                    self.nonempty |= 1 << nb;
                }
                slot = next;
            }
        }
        let slot = self.heads[0];
        let e = self.pool[slot as usize];
        self.heads[0] = e.next;
        if e.next == NIL {
            self.nonempty &= !1;
            self.mins[0] = u32::MAX;
        }
        self.pool[slot as usize].next = self.free;
        self.free = slot;
        Some((e.f, e.node))
    }
}

/// Precise square root for lengths: micromath's estimate (±5 %) refined by three Newton steps.
/// Only `+ - * /`, so host and MCU agree bit for bit.
#[inline]
pub(crate) fn sqrt_precise(x: f32) -> f32 {
    if x.is_nan() || x <= 0.0 {
        return 0.0;
    }
    if x == f32::INFINITY {
        return x;
    }
    let mut y = crate::math::sqrt(x);
    for _ in 0..3 {
        y = 0.5 * (y + x / y);
    }
    y
}

/// Euclidean length of the segment between two cells, in cells.
#[inline]
fn cells_distance(a: Cell, b: Cell) -> f32 {
    let dx = a.x as f32 - b.x as f32;
    let dy = a.y as f32 - b.y as f32;
    sqrt_precise(dx * dx + dy * dy)
}

/// Outcome of the search phase, before the path is rebuilt.
struct Search {
    found: bool,
    expanded: u32,
    cost: u32,
}

/// A planner with its scratch memory: `SCRATCH_WORDS` 32-bit words hold 8 cells each (4 bits
/// per cell, see [`scratch_words_for_cells`]), `QUEUE` is the open-list capacity in entries
/// (12 bytes each).
///
/// A planner is reusable: every call clears the scratch of the cells it uses. It is large
/// (`4 × SCRATCH_WORDS + 12 × QUEUE + 4 096` bytes), so keep it in a `static` or a `Box`, not on a
/// small stack.
pub struct Planner<const SCRATCH_WORDS: usize, const QUEUE: usize> {
    scratch: [u32; SCRATCH_WORDS],
    queue: [OpenEntry; QUEUE],
    cells: PathCells,
    last: Option<PlanReport>,
    queue_peak: u32,
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
            last: None,
            queue_peak: 0,
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
    /// polyline has more than [`MAX_PATH_POINTS`] vertices (`path` then holds nothing and
    /// [`Planner::last_report`] has the search's result).
    pub fn plan<const W: usize>(
        &mut self,
        kind: PlannerKind,
        grid: &Grid<W>,
        start: PointM,
        goal: PointM,
        path: &mut PathM,
    ) -> Result<PlanReport, PlanError> {
        path.clear();
        self.cells.clear();
        self.last = None;
        let geometry = *grid.geometry();
        let (Ok(start_cell), Ok(goal_cell)) = (geometry.cell_of(start), geometry.cell_of(goal))
        else {
            self.check_scratch(&geometry)?;
            let report = PlanReport::empty(PlanStatus::OutOfBounds);
            self.last = Some(report);
            return Ok(report);
        };
        let report = self.plan_cells(kind, grid, start_cell, goal_cell)?;
        for &c in self.cells.iter() {
            if path.push(geometry.center_of(c)).is_err() {
                path.clear();
                return Err(PlanError::PathFull {
                    capacity: MAX_PATH_POINTS as u32,
                });
            }
        }
        Ok(report)
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
        self.cells.clear();
        self.last = None;
        self.queue_peak = 0;
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
            let report = PlanReport::empty(status);
            self.last = Some(report);
            return Ok(report);
        }
        let used_words = scratch_words_for_cells(geometry.cell_count());
        if let Some(used) = self.scratch.get_mut(..used_words) {
            used.fill(0);
        }
        let start_index = geometry.index(start);
        let goal_index = geometry.index(goal);
        let search = if start_index == goal_index {
            set_nibble(&mut self.scratch, start_index, CODE_START);
            Search {
                found: true,
                expanded: 0,
                cost: 0,
            }
        } else {
            match kind {
                PlannerKind::Bfs => self.bfs(grid, start_index, goal_index)?,
                PlannerKind::AStar | PlannerKind::AnyAngle => {
                    self.astar(grid, start_index, goal, goal_index)?
                }
            }
        };
        if !search.found {
            let report = PlanReport {
                status: PlanStatus::Unreachable,
                expanded: search.expanded,
                cost: 0,
                length_m: 0.0,
            };
            self.last = Some(report);
            return Ok(report);
        }
        let (length_cells, steps, fits) = match kind {
            PlannerKind::AnyAngle => self.rebuild_any_angle(grid, goal),
            _ => self.rebuild_merged(&geometry, goal),
        };
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
            self.cells.clear();
            return Err(PlanError::PathFull {
                capacity: MAX_PATH_POINTS as u32,
            });
        }
        Ok(report)
    }

    /// The polyline of the last successful plan, as cells (start cell first). Empty after a
    /// failed plan or an error.
    pub fn path_cells(&self) -> &[Cell] {
        &self.cells
    }

    /// The report of the last planning request, also when it ended in
    /// [`PlanError::PathFull`] (then `status` is `Found` and cost/length/expanded are those of
    /// the path that did not fit). `None` before the first request and after the other errors.
    pub fn last_report(&self) -> Option<PlanReport> {
        self.last
    }

    /// Most queue entries in use at once during the last search (BFS: ring-buffer entries;
    /// A*: open-list entries, stale ones included). Size `QUEUE` from this on your maps.
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

    /// Breadth-first search from `start` until `goal` is discovered.
    fn bfs<const GW: usize>(
        &mut self,
        grid: &Grid<GW>,
        start: usize,
        goal: usize,
    ) -> Result<Search, PlanError> {
        let geometry = grid.geometry();
        let width = geometry.width() as usize;
        let height = geometry.height() as usize;
        let scratch = &mut self.scratch[..];
        let queue = &mut self.queue[..];
        let capacity = queue.len();
        let full = PlanError::QueueFull {
            capacity: capacity as u32,
        };
        let (mut head, mut tail, mut count) = (0usize, 0usize, 0usize);
        let mut peak = 1usize;
        let mut expanded = 0u32;

        set_nibble(scratch, start, CODE_START);
        // Entries carry the index (`node`) and the packed coordinates (`f` = y << 16 | x) so
        // the loop never divides.
        match queue.get_mut(tail) {
            Some(slot) => {
                slot.node = start as u32;
                slot.f = (((start / width) as u32) << 16) | (start % width) as u32;
            }
            None => return Err(full),
        }
        tail = if tail + 1 == capacity { 0 } else { tail + 1 };
        count += 1;

        while count > 0 {
            let (index, x, y) = match queue.get(head) {
                Some(e) => (
                    e.node as usize,
                    (e.f & 0xFFFF) as usize,
                    (e.f >> 16) as usize,
                ),
                None => break,
            };
            head = if head + 1 == capacity { 0 } else { head + 1 };
            count -= 1;
            expanded += 1;

            let free_e = x + 1 < width && !grid.bit(index + 1);
            let free_w = x > 0 && !grid.bit(index - 1);
            let free_n = y + 1 < height && !grid.bit(index + width);
            let free_s = y > 0 && !grid.bit(index - width);

            macro_rules! visit {
                ($n:expr, $nx:expr, $ny:expr, $code:expr) => {{
                    let n = $n;
                    if nibble(scratch, n) == 0 {
                        set_nibble(scratch, n, $code);
                        if n == goal {
                            self.queue_peak = peak as u32;
                            return Ok(Search {
                                found: true,
                                expanded,
                                cost: 0,
                            });
                        }
                        if count == capacity {
                            self.queue_peak = peak as u32;
                            return Err(full);
                        }
                        if let Some(slot) = queue.get_mut(tail) {
                            slot.node = n as u32;
                            slot.f = (($ny as u32) << 16) | $nx as u32;
                        }
                        tail = if tail + 1 == capacity { 0 } else { tail + 1 };
                        count += 1;
                        peak = peak.max(count);
                    }
                }};
            }

            if free_e {
                visit!(index + 1, x + 1, y, E);
            }
            if free_n {
                visit!(index + width, x, y + 1, N);
            }
            if free_w {
                visit!(index - 1, x - 1, y, W);
            }
            if free_s {
                visit!(index - width, x, y - 1, S);
            }
            if free_n && free_e && !grid.bit(index + width + 1) {
                visit!(index + width + 1, x + 1, y + 1, NE);
            }
            if free_n && free_w && !grid.bit(index + width - 1) {
                visit!(index + width - 1, x - 1, y + 1, NW);
            }
            if free_s && free_w && !grid.bit(index - width - 1) {
                visit!(index - width - 1, x - 1, y - 1, SW);
            }
            if free_s && free_e && !grid.bit(index - width + 1) {
                visit!(index - width + 1, x + 1, y - 1, SE);
            }
        }
        self.queue_peak = peak as u32;
        Ok(Search {
            found: false,
            expanded,
            cost: 0,
        })
    }

    /// A* with the octile heuristic and a lazy-deletion open list.
    fn astar<const GW: usize>(
        &mut self,
        grid: &Grid<GW>,
        start: usize,
        goal_cell: Cell,
        goal: usize,
    ) -> Result<Search, PlanError> {
        let geometry = grid.geometry();
        let width = geometry.width() as usize;
        let height = geometry.height() as usize;
        let (gx, gy) = (goal_cell.x as usize, goal_cell.y as usize);
        let scratch = &mut self.scratch[..];
        let mut open = RadixQueue::new(&mut self.queue[..]);
        let full = PlanError::QueueFull {
            capacity: open.pool.len() as u32,
        };
        let mut expanded = 0u32;

        let h = |x: usize, y: usize| octile(x.abs_diff(gx) as u32, y.abs_diff(gy) as u32);
        let (sx, sy) = (start % width, start / width);
        // Entries carry `y << 16 | x << 4 | step code` (sides are at most 4096 cells), so the
        // loop never divides.
        let pack = |x: usize, y: usize, code: u32| ((y as u32) << 16) | ((x as u32) << 4) | code;
        if !open.push(h(sx, sy), pack(sx, sy, CODE_START)) {
            return Err(full);
        }

        let unpack_index =
            |node: u32| (node >> 16) as usize * width + ((node >> 4) & 0xFFF) as usize;
        while let Some((f, node)) = open.pop(|node| nibble(scratch, unpack_index(node)) != 0) {
            let x = ((node >> 4) & 0xFFF) as usize;
            let y = (node >> 16) as usize;
            let index = y * width + x;
            if nibble(scratch, index) != 0 {
                continue; // already closed by a cheaper entry
            }
            set_nibble(scratch, index, node & 0xF);
            expanded += 1;
            // The entry does not store g: f = g + h exactly (costs stay far below u32::MAX on
            // grids that fit a planner's scratch).
            let g = f.wrapping_sub(h(x, y));
            if index == goal {
                self.queue_peak = open.bump;
                return Ok(Search {
                    found: true,
                    expanded,
                    cost: g,
                });
            }

            let free_e = x + 1 < width && !grid.bit(index + 1);
            let free_w = x > 0 && !grid.bit(index - 1);
            let free_n = y + 1 < height && !grid.bit(index + width);
            let free_s = y > 0 && !grid.bit(index - width);

            macro_rules! visit {
                ($n:expr, $nx:expr, $ny:expr, $cost:expr, $code:expr) => {{
                    let n = $n;
                    if nibble(scratch, n) == 0 {
                        let f = g.saturating_add($cost).saturating_add(h($nx, $ny));
                        let node = pack($nx, $ny, $code);
                        if !open.push(f, node) {
                            // Full: drop the entries of cells closed meanwhile and retry, unless
                            // that frees too little to be worth it (no thrashing).
                            let freed =
                                open.collect(|node| nibble(scratch, unpack_index(node)) != 0);
                            if freed < (open.pool.len() / 16).max(1) || !open.push(f, node) {
                                self.queue_peak = open.bump;
                                return Err(full);
                            }
                        }
                    }
                }};
            }

            if free_e {
                visit!(index + 1, x + 1, y, STRAIGHT_COST, E);
            }
            if free_n {
                visit!(index + width, x, y + 1, STRAIGHT_COST, N);
            }
            if free_w {
                visit!(index - 1, x - 1, y, STRAIGHT_COST, W);
            }
            if free_s {
                visit!(index - width, x, y - 1, STRAIGHT_COST, S);
            }
            if free_n && free_e && !grid.bit(index + width + 1) {
                visit!(index + width + 1, x + 1, y + 1, DIAGONAL_COST, NE);
            }
            if free_n && free_w && !grid.bit(index + width - 1) {
                visit!(index + width - 1, x - 1, y + 1, DIAGONAL_COST, NW);
            }
            if free_s && free_w && !grid.bit(index - width - 1) {
                visit!(index - width - 1, x - 1, y - 1, DIAGONAL_COST, SW);
            }
            if free_s && free_e && !grid.bit(index - width + 1) {
                visit!(index - width + 1, x + 1, y - 1, DIAGONAL_COST, SE);
            }
        }
        self.queue_peak = open.bump;
        Ok(Search {
            found: false,
            expanded,
            cost: 0,
        })
    }

    /// The parent of `cell` by its nibble, or `None` at the start (or on a corrupt code).
    #[inline]
    fn parent(&self, geometry: &GridGeometry, cell: Cell) -> Option<(Cell, u32)> {
        let code = nibble(&self.scratch, geometry.index(cell));
        let &(dx, dy) = STEPS.get((code as usize).wrapping_sub(1))?;
        let parent = geometry.cell_xy(cell.x as i32 - dx, cell.y as i32 - dy)?;
        Some((parent, code))
    }

    /// Rebuild the BFS / A* path from the parent steps, merging collinear cells. Returns the
    /// length in cells, the number of steps and whether every vertex fitted.
    fn rebuild_merged(&mut self, geometry: &GridGeometry, goal: Cell) -> (f32, u32, bool) {
        let mut fits = self.cells.push(goal).is_ok();
        let (mut straight, mut diagonal) = (0u32, 0u32);
        let mut previous_code = 0u32;
        let mut cell = goal;
        // A parent chain never revisits a cell; the bound only guards against a corrupt one.
        for _ in 0..geometry.cell_count() {
            let Some((parent, code)) = self.parent(geometry, cell) else {
                break;
            };
            if previous_code != 0 && code != previous_code {
                fits &= self.cells.push(cell).is_ok();
            }
            if code >= NE {
                diagonal += 1;
            } else {
                straight += 1;
            }
            previous_code = code;
            cell = parent;
        }
        if cell != goal {
            fits &= self.cells.push(cell).is_ok();
        }
        self.cells.reverse();
        let length = straight as f32 + diagonal as f32 * core::f32::consts::SQRT_2;
        (length, straight + diagonal, fits)
    }

    /// Rebuild the A* path and pull the string with line-of-sight shortcuts. Returns the length
    /// in cells, the number of A* steps and whether every vertex fitted.
    fn rebuild_any_angle<const GW: usize>(
        &mut self,
        grid: &Grid<GW>,
        goal: Cell,
    ) -> (f32, u32, bool) {
        let geometry = *grid.geometry();
        let mut fits = self.cells.push(goal).is_ok();
        let mut length = 0.0f32;
        let mut anchor = goal;
        let mut cell = goal;
        let mut steps = 0u32;
        for _ in 0..geometry.cell_count() {
            let Some((parent, _)) = self.parent(&geometry, cell) else {
                break;
            };
            if !line_of_sight(grid, anchor, parent) {
                fits &= self.cells.push(cell).is_ok();
                length += cells_distance(anchor, cell);
                anchor = cell;
            }
            steps += 1;
            cell = parent;
        }
        if cell != anchor {
            fits &= self.cells.push(cell).is_ok();
            length += cells_distance(anchor, cell);
        }
        self.cells.reverse();
        (length, steps, fits)
    }
}

impl<const SCRATCH_WORDS: usize, const QUEUE: usize> Default for Planner<SCRATCH_WORDS, QUEUE> {
    fn default() -> Self {
        Self::new()
    }
}
