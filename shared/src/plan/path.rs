//! Path rebuild: from the goal, the parent steps are walked back run by run (maximal straight
//! pieces, [`Planner::run_back`]), so a polyline of merged cells costs `O(path cells)` reads
//! and one vertex per turn. [`PathOut`] writes the vertices or only counts them (to learn
//! whether a path fits before the last one is overwritten).

use super::codes::{nibble, NE, STEPS};
use super::planner::Planner;
use super::{PathCells, MAX_PATH_POINTS};
use crate::geom::Cell;
use crate::grid::GridGeometry;

impl<const SCRATCH_WORDS: usize, const QUEUE: usize> Planner<SCRATCH_WORDS, QUEUE> {
    /// The parent of `cell` by its nibble, or `None` at the start (or on a corrupt code).
    #[inline]
    pub(super) fn parent(&self, geometry: &GridGeometry, cell: Cell) -> Option<(Cell, u32)> {
        let code = nibble(&self.scratch, self.layout.index(geometry, cell));
        let &(dx, dy) = STEPS.get((code as usize).wrapping_sub(1))?;
        let parent = geometry.cell_xy(cell.x as i32 - dx, cell.y as i32 - dy)?;
        Some((parent, code))
    }

    /// The run of parent steps of code `code` that goes on back from `cell` (the parent of a
    /// cell reached with `code`): the first cell back whose own code is not `code` (the run's
    /// far end) and the number of steps to it. Walks the scratch index, a few instructions per
    /// cell (the parent chain of a search's nibbles never leaves the map; the bound only guards
    /// against a corrupt one).
    pub(super) fn run_back(&self, geometry: &GridGeometry, cell: Cell, code: u32) -> (Cell, u32) {
        let Some(&(dx, dy)) = STEPS.get((code as usize).wrapping_sub(1)) else {
            return (cell, 0);
        };
        let offset = (dy as isize)
            .wrapping_mul(self.layout.row_step(geometry) as isize)
            .wrapping_add(dx as isize) as usize;
        let mut index = self.layout.index(geometry, cell);
        let longest = geometry.width().max(geometry.height()) as u32;
        let mut steps = 0u32;
        while steps < longest && nibble(&self.scratch, index) == code {
            index = index.wrapping_sub(offset);
            steps += 1;
        }
        let end = geometry.cell_xy(
            cell.x as i32 - dx * steps as i32,
            cell.y as i32 - dy * steps as i32,
        );
        end.map_or((cell, 0), |end| (end, steps))
    }

    /// Rebuild the BFS / A* path from the parent steps, run by run ([`Planner::run_back`]), so
    /// collinear cells are merged. Returns the length in cells, the number of steps and whether
    /// every vertex fitted.
    ///
    /// With `count_only` the cells are counted, not written (`fits` and the figures are the
    /// same).
    pub(super) fn rebuild_merged(
        &mut self,
        geometry: &GridGeometry,
        goal: Cell,
        count_only: bool,
    ) -> (f32, u32, bool) {
        let mut out = PathOut::new(count_only);
        let mut fits = out.push(&mut self.cells, goal);
        let (mut straight, mut diagonal) = (0u32, 0u32);
        let mut cell = goal;
        // A parent chain never revisits a cell; the bound only guards against a corrupt one.
        for _ in 0..geometry.cell_count() {
            let Some((parent, code)) = self.parent(geometry, cell) else {
                break;
            };
            let (end, more) = self.run_back(geometry, parent, code);
            if code >= NE {
                diagonal += 1 + more;
            } else {
                straight += 1 + more;
            }
            cell = end;
            fits &= out.push(&mut self.cells, cell);
        }
        out.reverse(&mut self.cells);
        let length = straight as f32 + diagonal as f32 * core::f32::consts::SQRT_2;
        (length, straight + diagonal, fits)
    }
}

/// Where a path rebuild puts its vertices: the planner's cells, or only a count of them (to
/// learn whether a path fits before the last one is overwritten).
#[derive(Clone, Copy, Debug)]
pub(super) struct PathOut {
    pub(super) count_only: bool,
    pub(super) count: usize,
}

impl PathOut {
    pub(super) fn new(count_only: bool) -> Self {
        Self {
            count_only,
            count: 0,
        }
    }

    /// Add a vertex; `false` when it does not fit.
    pub(super) fn push(&mut self, cells: &mut PathCells, cell: Cell) -> bool {
        self.count += 1;
        if self.count_only {
            self.count <= MAX_PATH_POINTS
        } else {
            cells.push(cell).is_ok()
        }
    }

    /// Vertices added so far.
    pub(super) fn count(&self) -> usize {
        self.count
    }

    /// Only counting.
    pub(super) fn is_counting(&self) -> bool {
        self.count_only
    }

    /// Turn the written path round (nothing to do when counting).
    pub(super) fn reverse(&self, cells: &mut PathCells) {
        if !self.count_only {
            cells.reverse();
        }
    }
}
