//! The marking as it was before clipping and row runs (test only): every cell of the whole
//! (clamped) Bresenham walk grows to a square, filled row by row. Its cost grows with the
//! coordinates, so tests use it only on edges near the grid; it defines what must be marked.

use super::BresenhamLine;
use crate::geom::PointM;
use crate::grid::Grid;

/// The square of half-side `half_side` around (`x`, `y`), clipped to the grid.
pub(super) fn mark_square<const W: usize>(grid: &mut Grid<W>, x: i32, y: i32, half_side: u16) {
    let h = half_side as i32;
    for row in y.saturating_sub(h)..=y.saturating_add(h) {
        grid.fill_row(row, x.saturating_sub(h), x.saturating_add(h));
    }
}

/// Every cell of the walk from `from` to `to`, grown.
pub(super) fn mark_line<const W: usize>(
    grid: &mut Grid<W>,
    from: (i32, i32),
    to: (i32, i32),
    half_side: u16,
) {
    for (x, y) in BresenhamLine::new(from, to) {
        mark_square(grid, x, y, half_side);
    }
}

/// The closed outline of a polygon in metres, grown.
pub(super) fn mark_polygon<const W: usize>(
    grid: &mut Grid<W>,
    vertices: &[PointM],
    half_side: u16,
) {
    let geometry = *grid.geometry();
    let mut cells = vertices.iter().filter_map(|v| geometry.cell_xy_of(*v));
    let Some(first) = cells.next() else {
        return;
    };
    let mut previous = first;
    let mut edges = 0usize;
    for cell in cells {
        mark_line(grid, previous, cell, half_side);
        previous = cell;
        edges += 1;
    }
    if edges == 0 {
        mark_square(grid, first.0, first.1, half_side);
    } else {
        mark_line(grid, previous, first, half_side);
    }
}
