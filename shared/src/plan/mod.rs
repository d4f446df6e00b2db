//! Path planners on the occupancy grid: BFS (the seed's), A* (octile, optimal) and an any-angle
//! variant, plus the line-of-sight test and the pruning of a plan to what the sonar has just
//! seen. How they work, why, and what each piece measured (with the commands): `docs/planners.md`.
//!
//! - **Contract** (`docs/planners.md#contract`): 4 side neighbours, a diagonal only between two
//!   free side cells (no corner cutting); BFS counts steps, A* uses the integer octile costs
//!   [`STRAIGHT_COST`] / [`DIAGONAL_COST`]; a [`Planner`] owns all its scratch (4 bits per cell,
//!   a queue of fixed capacity), and running out of either is a [`PlanError`], never a panic;
//!   the path is a polyline of cell centres with collinear cells merged, plus a [`PlanReport`].
//! - **Memory** (`#memory-layout`): nibble codes (`codes.rs`), the flat and framed layouts of
//!   the cell-by-cell A* (`layout.rs`), the layered BFS's bit planes (`bfs/`). 300 × 300 cells
//!   take 45 000 bytes of scratch ([`SCRATCH_WORDS_300`]) plus 12 bytes per queue entry.
//! - **A\*** (`#a-jump-point-search-jps-without-corner-cutting`, `#cell-by-cell-a`): jump point
//!   search on uncluttered maps (`jump.rs`, its heap `heap.rs`), else cell by cell (`astar.rs`)
//!   with corridor walks (`corridor.rs`, `#corridors`), step classes by goal region
//!   (`goal.rs`) and an open list by reduced-cost class (`open_list.rs`, `class_queue.rs`,
//!   `ring_queue.rs`).
//! - **BFS** (`#bfs-on-uncluttered-maps-jump-points-with-unit-costs`, `#bfs-layered-bit-parallel`):
//!   unit-cost jump point search on uncluttered maps, else layered and bit-parallel from both
//!   ends (`bfs/`), scalar in narrow corridors.
//! - **Any-angle** (`#any-angle`): string pulling on the A* path (`any_angle.rs`, `los.rs`).
//! - **The rest**: request dispatch and reports (`planner.rs`), path rebuild (`path.rs`),
//!   pruning and the sweep-band check (`prune.rs`), tests by subject (`tests/`); costs per
//!   piece in `#complexity`.
//!
//! Budget: 5 M Cortex-M4 instructions per 300 × 300 plan (`cargo xtask mcu-bench` fails past
//! it).
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

mod any_angle;
mod astar;
mod bfs;
mod choice;
mod class_queue;
mod codes;
mod corridor;
mod goal;
mod heap;
mod jump;
mod layout;
mod los;
mod meet;
mod open_list;
mod path;
mod planner;
mod prune;
mod ring_queue;

#[cfg(test)]
mod tests;

pub use layout::FRAMED_SCRATCH_WORDS;
pub use los::{line_of_sight, line_of_sight_m};
pub use planner::Planner;
pub use prune::{needs_full_sweep, prune_visible_prefix, PruneEnd, Pruned, NORMAL_HALF_BAND_RAD};

use heapless::Vec;

use crate::geom::{Cell, PointM};

/// Cost of a side step in A* (integer octile costs: `DIAGONAL_COST / STRAIGHT_COST` ≈ √2).
pub const STRAIGHT_COST: u32 = 5741;
/// Cost of a diagonal step in A*.
pub const DIAGONAL_COST: u32 = 8119;

/// Largest number of vertices in a returned path polyline. The 300 x 300 benchmark maze (1-cell
/// corridors, 8 948 steps) needs 2 845; room worlds need a few dozen.
pub const MAX_PATH_POINTS: usize = 3072;

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

/// The usual planner for the seed's 300 × 300 grid: 45 000 bytes of scratch, 3 072 queue
/// entries (36 864 bytes; jump point search uses at most 40 of them on the bundled worlds, the
/// cell-by-cell A* 766 on 20 % random obstacles), the 12 288-byte vertex buffer and the
/// cell-by-cell A*'s 2 560-byte goal table: about 97 KB in all.
pub type Planner300 = Planner<SCRATCH_WORDS_300, 3072>;

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

impl PlannerKind {
    /// The planner's name on the command line and in JSON: `bfs`, `astar`, `anyangle`.
    pub const fn as_str(self) -> &'static str {
        match self {
            PlannerKind::Bfs => "bfs",
            PlannerKind::AStar => "astar",
            PlannerKind::AnyAngle => "anyangle",
        }
    }
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

impl PlanStatus {
    /// The status in snake case, as in the JSON of `twil plan`: `found`, `unreachable`,
    /// `start_blocked`, `goal_blocked`, `out_of_bounds`.
    pub const fn as_str(self) -> &'static str {
        match self {
            PlanStatus::Found => "found",
            PlanStatus::Unreachable => "unreachable",
            PlanStatus::StartBlocked => "start_blocked",
            PlanStatus::GoalBlocked => "goal_blocked",
            PlanStatus::OutOfBounds => "out_of_bounds",
        }
    }
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

impl core::error::Error for PlanError {}

/// What a planning request produced (the path itself goes to the caller's [`PathM`]).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PlanReport {
    /// How it ended.
    pub status: PlanStatus,
    /// Nodes expanded: for BFS on uncluttered maps the jump points expanded (unit-cost jump
    /// point search), on cluttered ones the cells reached (layered search; the scalar one in
    /// narrow maps: the cells taken off its queue), both added when jump points gave up; jump
    /// points for A* and any-angle (plus the cells of the cell-by-cell search when it fell back
    /// to it: the cells it closed, those closed by corridor walks included).
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
