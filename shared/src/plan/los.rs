//! Line of sight on the grid: a Bresenham walk with the planners' no-corner-cutting rule.

use crate::geom::{Cell, PointM};
use crate::grid::Grid;

/// `true` when the straight segment from cell `a` to cell `b` is free on `grid`.
///
/// The test walks the Bresenham cells (those of [`crate::raster::BresenhamLine`]) of the segment (both ends included): every cell must be
/// inside the grid and free, and on every diagonal Bresenham step both side cells must be free
/// too (the planners' neighbour rule, so a segment never squeezes between two obstacles that
/// touch at a corner). The walk always runs from the smaller to the larger cell in `(y, x)` order,
/// so the result is symmetric: `line_of_sight(g, a, b) == line_of_sight(g, b, a)`.
/// Cost: `max(|dx|, |dy|) + 1` cells.
///
/// ```
/// use twil_core::geom::Cell;
/// use twil_core::grid::{Grid300, GridGeometry};
/// use twil_core::plan::line_of_sight;
/// let mut grid = Grid300::new(GridGeometry::new(10, 10, 0.1).unwrap()).unwrap();
/// assert!(line_of_sight(&grid, Cell::new(0, 0), Cell::new(9, 4)));
/// grid.set(Cell::new(1, 0), true);
/// grid.set(Cell::new(0, 1), true);
/// // The diagonal step (0,0) -> (1,1) would cut between two occupied corners.
/// assert!(!line_of_sight(&grid, Cell::new(0, 0), Cell::new(1, 1)));
/// ```
pub fn line_of_sight<const W: usize>(grid: &Grid<W>, a: Cell, b: Cell) -> bool {
    let (from, to) = if (a.y, a.x) <= (b.y, b.x) {
        (a, b)
    } else {
        (b, a)
    };
    let geometry = grid.geometry();
    // Between two cells of the map the walk stays in their bounding box, so only the ends can
    // be off the map (and off-map cells count as occupied).
    if !geometry.contains_xy(from.x as i32, from.y as i32)
        || !geometry.contains_xy(to.x as i32, to.y as i32)
    {
        return false;
    }
    // The Bresenham walk of [`crate::raster::BresenhamLine`] on row-major bit indices: a side step in x adds
    // `sx`, in y adds `width` (y only grows, as `from` is the lower end).
    let words = grid.words();
    let occupied = |i: usize| match words.get(i >> 5) {
        Some(w) => (w >> (i & 31)) & 1 != 0,
        None => true,
    };
    let width = geometry.width() as usize;
    let (x0, y0, x1, y1) = (from.x as i32, from.y as i32, to.x as i32, to.y as i32);
    let dx = (x1 - x0).abs();
    let dy = -(y1 - y0).abs();
    let step_x = if x0 < x1 { 1usize } else { usize::MAX }; // +1 or -1, wrapping
    let mut err = dx + dy;
    let mut i = y0 as usize * width + x0 as usize;
    if occupied(i) {
        return false;
    }
    for _ in 0..dx.max(-dy) {
        let e2 = 2 * err;
        let mut next = i;
        let moves_x = e2 >= dy;
        let moves_y = e2 <= dx;
        if moves_x {
            err += dy;
            next = next.wrapping_add(step_x);
        }
        if moves_y {
            err += dx;
            next += width;
        }
        if occupied(next) {
            return false;
        }
        // A diagonal step also needs both side cells free (no corner cutting).
        if moves_x && moves_y && (occupied(i.wrapping_add(step_x)) || occupied(i + width)) {
            return false;
        }
        i = next;
    }
    true
}

/// [`line_of_sight`] between the cells that contain two points in world metres; `false` when
/// either point is off the map or not finite.
pub fn line_of_sight_m<const W: usize>(grid: &Grid<W>, a: PointM, b: PointM) -> bool {
    let geometry = grid.geometry();
    match (geometry.cell_of(a), geometry.cell_of(b)) {
        (Ok(a), Ok(b)) => line_of_sight(grid, a, b),
        _ => false,
    }
}
