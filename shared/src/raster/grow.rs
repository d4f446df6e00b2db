//! Growing a line by a square, one run per row.
//!
//! Every cell of the walk marks a square of half-side `h`. Row `y` of the union is the union of
//! `[x − h, x + h]` over the walk cells whose row is within `h` of `y`. Those cells are
//! consecutive along the walk (its rows are monotone) and their `x` are monotone and 8-connected,
//! so the union is the single run from the smaller to the larger `x` of the first and last of
//! them, widened by `h`. Two cursors over the walk (the first cell within `h` behind the row, the
//! last within `h` ahead) find those two cells; both only move forward as the row advances.

use super::{BresenhamLine, Work};
use crate::grid::Grid;

/// Mark cells `x0..=x1` of `row` (any integers: clipped to the grid here). Returns the words
/// written.
pub(super) fn fill_row<const W: usize>(grid: &mut Grid<W>, row: i64, x0: i64, x1: i64) -> Work {
    let g = grid.geometry();
    let (last_x, last_row) = (g.width() as i64 - 1, g.height() as i64 - 1);
    let (x0, x1) = (x0.max(0), x1.min(last_x));
    if x0 > x1 || !(0..=last_row).contains(&row) {
        return 0;
    }
    grid.fill_row(row as i32, x0 as i32, x1 as i32) as Work
}

/// Mark the Bresenham line from `from` to `to` grown by `half_side` cells (see the module doc).
pub(super) fn mark_grown_line<const W: usize>(
    grid: &mut Grid<W>,
    from: (i32, i32),
    to: (i32, i32),
    half_side: u16,
) -> Work {
    let g = *grid.geometry();
    let h = half_side as i32;
    let (width, height) = (g.width() as i32, g.height() as i32);
    // Only cells whose square reaches the grid matter.
    let Some(mut lead) =
        BresenhamLine::clipped(from, to, (-h, width - 1 + h), (-h, height - 1 + h))
    else {
        return 0;
    };
    let mut trail = lead.clone();
    let (Some(mut lead_cell), Some(mut trail_cell)) = (lead.next(), trail.next()) else {
        return 0;
    };
    let mut work: Work = 2;
    // Rows are visited in the walk's direction, from the first grid row the first cell's square
    // reaches, until the walk is left behind or the grid ends.
    let sy = lead.sy as i64;
    let (h, last_row) = (h as i64, height as i64 - 1);
    let mut y = if sy > 0 {
        (lead_cell.1 as i64 - h).max(0)
    } else {
        (lead_cell.1 as i64 + h).min(last_row)
    };
    // How far a cell's row is ahead of row `y`, along the walk.
    let ahead = |cell: (i32, i32), y: i64| (cell.1 as i64 - y) * sy;
    while (0..=last_row).contains(&y) {
        while let Some(next) = lead.peek() {
            if ahead(next, y) > h {
                break;
            }
            lead_cell = next;
            lead.next();
            work += 1;
        }
        while ahead(trail_cell, y) < -h {
            match trail.next() {
                Some(cell) => trail_cell = cell,
                // Every cell is more than `h` rows behind: this row and the next are free.
                None => return work,
            }
            work += 1;
        }
        work += 1;
        if ahead(trail_cell, y) <= h {
            let (xa, xb) = (trail_cell.0 as i64, lead_cell.0 as i64);
            work += fill_row(grid, y, xa.min(xb) - h, xa.max(xb) + h);
        }
        y += sy;
    }
    work
}
