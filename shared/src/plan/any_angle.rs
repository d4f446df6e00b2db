//! Any-angle: A*, then string pulling on the A* cell path, run by run from the goal: a run whose
//! far end the anchor sees by [`line_of_sight`] is skipped whole, else its last visible cell is
//! found by bisection and becomes a vertex. Every segment passes the no-corner-cutting
//! line-of-sight test and the polyline is never longer than the A* path. A side-step turn with
//! a blocked inner corner right after a run from the anchor becomes a vertex with one cell read.
//! Measured effect (`cargo xtask mcu-bench`): the 300 × 300 maze 7.8 M → 4.1 M instructions
//! with the inner-corner rule; the open grid 4.2 M (first cell-by-cell version) → 0.5 M.

use super::codes::{S, STEPS};
use super::los::line_of_sight;
use super::path::PathOut;
use super::planner::Planner;
use crate::geom::Cell;
use crate::grid::Grid;

/// Euclidean length of the segment between two cells, in cells.
#[inline]
fn cells_distance(a: Cell, b: Cell) -> f32 {
    let dx = a.x as f32 - b.x as f32;
    let dy = a.y as f32 - b.y as f32;
    crate::math::hypot(dx, dy)
}

impl<const SCRATCH_WORDS: usize, const QUEUE: usize> Planner<SCRATCH_WORDS, QUEUE> {
    /// Rebuild the A* path and pull the string with line-of-sight shortcuts. Returns the length
    /// in cells, the number of A* steps and whether every vertex fitted.
    ///
    /// Works run by run (maximal straight pieces of the A* path), from the goal back: if the far
    /// end of the next run is visible from the anchor, the whole run is skipped; otherwise the
    /// last visible cell of the run is found by bisection and becomes a vertex and the new
    /// anchor. Every emitted segment has been tested with [`line_of_sight`].
    pub(super) fn rebuild_any_angle<const GW: usize>(
        &mut self,
        grid: &Grid<GW>,
        goal: Cell,
        count_only: bool,
    ) -> (f32, u32, bool) {
        let geometry = *grid.geometry();
        let mut out = PathOut::new(count_only);
        let mut fits = out.push(&mut self.cells, goal);
        let mut length = 0.0f32;
        let mut anchor = goal;
        let mut cur = goal;
        let mut steps = 0u32;
        // The code of the run just taken from the anchor (the anchor lies on its line behind
        // `cur`), else 0.
        let mut prev_code = 0u32;
        // Each pass either moves `cur` towards the start or moves the anchor forward; the
        // bound only guards against a corrupt parent chain.
        for _ in 0..2 * geometry.cell_count() {
            // The run that ends at `cur`: `run` steps of `code`, back to `end`.
            let Some((mut end, code)) = self.parent(&geometry, cur) else {
                break;
            };
            let (far, more) = self.run_back(&geometry, end, code);
            end = far;
            let run = 1 + more;
            // From the anchor itself the run is an A* move sequence: visible without a test.
            if cur == anchor {
                cur = end;
                steps += run;
                prev_code = code;
                continue;
            }
            // A side-step turn after a run from the anchor, whose inner corner (the cell
            // beside the previous run and the next one) is blocked: no cell of the next run is
            // visible past it (the Bresenham line to the first one crosses that corner or
            // steps diagonally past it), so `cur` is the vertex, with no line-of-sight test.
            if prev_code != 0 && prev_code <= S && code <= S && (prev_code ^ code) & 1 == 1 {
                let (Some(&(px, py)), Some(&(dx, dy))) = (
                    STEPS.get(prev_code as usize - 1),
                    STEPS.get(code as usize - 1),
                ) else {
                    break;
                };
                if grid.is_occupied_xy(cur.x as i32 + px - dx, cur.y as i32 + py - dy) {
                    fits &= out.push(&mut self.cells, cur);
                    length += cells_distance(anchor, cur);
                    anchor = cur;
                    cur = end;
                    steps += run;
                    prev_code = code;
                    continue;
                }
            }
            prev_code = 0;
            if line_of_sight(grid, anchor, end) {
                cur = end;
                steps += run;
                continue;
            }
            // `cur` is visible, `end` is not: bisect for the last visible cell of the run.
            let Some(&(dx, dy)) = STEPS.get(code as usize - 1) else {
                break;
            };
            let at = |i: u32| {
                Cell::new(
                    (cur.x as i32 - dx * i as i32) as u16,
                    (cur.y as i32 - dy * i as i32) as u16,
                )
            };
            let (mut lo, mut hi) = (0u32, run);
            while hi - lo > 1 {
                let mid = lo + (hi - lo) / 2;
                if line_of_sight(grid, anchor, at(mid)) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            // The step after the anchor is an A* move, always visible; never stall.
            let cut = if lo == 0 && cur == anchor { 1 } else { lo };
            let vertex = at(cut);
            fits &= out.push(&mut self.cells, vertex);
            length += cells_distance(anchor, vertex);
            anchor = vertex;
            cur = vertex;
            steps += cut;
        }
        if cur != anchor {
            fits &= out.push(&mut self.cells, cur);
            length += cells_distance(anchor, cur);
        }
        out.reverse(&mut self.cells);
        (length, steps, fits)
    }
}
