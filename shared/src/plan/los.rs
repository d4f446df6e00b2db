//! Line of sight on the grid: a Bresenham walk with the planners' no-corner-cutting rule.

use crate::geom::{Cell, PointM};
use crate::grid::Grid;
use crate::raster::BresenhamLine;

/// `true` when the straight segment from cell `a` to cell `b` is free on `grid`.
///
/// The test walks the Bresenham cells of the segment (both ends included): every cell must be
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
    let (mut px, mut py) = (from.x as i32, from.y as i32);
    for (x, y) in BresenhamLine::new((px, py), (to.x as i32, to.y as i32)) {
        if grid.is_occupied_xy(x, y) {
            return false;
        }
        if x != px && y != py && (grid.is_occupied_xy(x, py) || grid.is_occupied_xy(px, y)) {
            return false;
        }
        px = x;
        py = y;
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
