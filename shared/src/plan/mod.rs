//! Path planners on the occupancy grid: BFS (the seed's), A* (octile, optimal) and an any-angle
//! variant, plus the pruning of a plan to what the sonar has just seen.
//!
//! **Status: API skeleton.** The bodies are being written (issue 2); the types and signatures
//! below are the contract the host, the simulator and the firmware code against.
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
//!   number of cells expanded.

use heapless::Vec;

use crate::geom::{Cell, PointM};
use crate::grid::Grid;

/// Cost of a side step in A* (integer octile costs: `DIAGONAL_COST / STRAIGHT_COST` ≈ √2).
pub const STRAIGHT_COST: u32 = 5741;
/// Cost of a diagonal step in A*.
pub const DIAGONAL_COST: u32 = 8119;

/// Largest number of vertices in a returned path polyline.
pub const MAX_PATH_POINTS: usize = 1024;

/// A path in world metres, first point = start cell centre, last = goal cell centre.
pub type PathM = Vec<PointM, MAX_PATH_POINTS>;

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
    /// The path has more vertices than [`MAX_PATH_POINTS`].
    PathFull {
        /// Path capacity, vertices.
        capacity: u32,
    },
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

/// A planner with its scratch memory: `SCRATCH_WORDS` 32-bit words hold 8 cells each (4 bits
/// per cell), `QUEUE` is the open-list capacity in entries.
pub struct Planner<const SCRATCH_WORDS: usize, const QUEUE: usize> {
    _scratch: [u32; SCRATCH_WORDS],
}

impl<const SCRATCH_WORDS: usize, const QUEUE: usize> Planner<SCRATCH_WORDS, QUEUE> {
    /// Cells the scratch memory covers.
    pub const CAPACITY_CELLS: usize = SCRATCH_WORDS * 8;

    /// A planner with cleared scratch.
    pub const fn new() -> Self {
        Self {
            _scratch: [0; SCRATCH_WORDS],
        }
    }

    /// Plan from `start` to `goal` on `grid`, writing the polyline to `path` (cleared first).
    pub fn plan<const W: usize>(
        &mut self,
        kind: PlannerKind,
        grid: &Grid<W>,
        start: PointM,
        goal: PointM,
        path: &mut PathM,
    ) -> Result<PlanReport, PlanError> {
        let _ = (kind, grid, start, goal);
        path.clear();
        let _: Option<Cell> = None;
        Err(PlanError::ScratchTooSmall {
            cells: 0,
            capacity: 0,
        })
    }
}

impl<const SCRATCH_WORDS: usize, const QUEUE: usize> Default for Planner<SCRATCH_WORDS, QUEUE> {
    fn default() -> Self {
        Self::new()
    }
}
