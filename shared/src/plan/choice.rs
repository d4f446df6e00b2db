//! Which search the planner runs: [`cluttered`] sends A* cell by cell straight away on
//! cluttered maps, [`JPS_STEPS_MAX_EXPANSIONS`] bounds the unit-cost jump point search before
//! the layered BFS takes over. A leaf module: the planner and the searches both read it.

use crate::geom::Cell;
use crate::grid::GridGeometry;

/// Unit-cost jump point search (BFS) gives up, and the layered BFS runs, past this many jump
/// points (with the wide-frontier test of `JPS_WIDE_FRONTIER` in `jump.rs`): the bundled worlds need 8–15,
/// sparse random obstacles (1–3 %, not cluttered by the count) hundreds, at about 7 400
/// Cortex-M4 instructions each, which the layered BFS (about 4 M on 300 × 300) does not repay.
pub(super) const JPS_STEPS_MAX_EXPANSIONS: u32 = 32;

/// A* runs cell by cell straight away (no jump point search) when the rows between start and
/// goal (plus [`CLUTTER_MARGIN_ROWS`] on each side) hold more than one obstacle run per this
/// many cells: 20 % random obstacles have about 1 in 6, a maze of 1-cell corridors 1 in 4, the
/// bundled room worlds fewer than 1 in 100.
const CLUTTER_CELLS_PER_RUN: usize = 32;
/// [`cluttered`] reads one word in this many (of 32 cells each).
const CLUTTER_SAMPLE_STRIDE: usize = 16;
/// Rows beyond the start and goal rows that [`cluttered`] also counts.
const CLUTTER_MARGIN_ROWS: u32 = 16;

/// `true` when the map around start and goal is cluttered (see [`CLUTTER_CELLS_PER_RUN`]): it
/// counts the runs of occupied cells (a set bit after a clear one) in a sample of the grid's
/// words (one in [`CLUTTER_SAMPLE_STRIDE`]) over the rows from the lower of the two rows to the
/// higher, widened by [`CLUTTER_MARGIN_ROWS`]: about 180 word reads on a 300 × 300 grid.
pub(super) fn cluttered(words: &[u32], geometry: &GridGeometry, start: Cell, goal: Cell) -> bool {
    let width = geometry.width() as usize;
    let (lo, hi) = if start.y < goal.y {
        (start.y, goal.y)
    } else {
        (goal.y, start.y)
    };
    let first_row = (lo as u32).saturating_sub(CLUTTER_MARGIN_ROWS) as usize;
    let last_row =
        ((hi as u32) + CLUTTER_MARGIN_ROWS).min((geometry.height() as u32).saturating_sub(1));
    let (first_word, end_word) = (
        first_row * width / 32,
        ((last_row as usize + 1) * width).div_ceil(32),
    );
    // Every `CLUTTER_SAMPLE_STRIDE`-th word; a run that enters a sampled word counts as starting
    // there.
    let mut runs = 0usize;
    let mut sampled = 0usize;
    for &w in words
        .get(first_word..end_word)
        .unwrap_or(&[])
        .iter()
        .step_by(CLUTTER_SAMPLE_STRIDE)
    {
        if w != 0 {
            runs += (w & !(w << 1)).count_ones() as usize;
        }
        sampled += 1;
    }
    let cells = sampled * 32;
    runs * CLUTTER_CELLS_PER_RUN > cells
}
