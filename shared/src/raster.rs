//! Rasterization: Bresenham lines and obstacle expansion.
//!
//! The seed plans for a point robot by growing every obstacle by the robot's radius: each
//! obstacle point marks a square of half-side `ceil(radius / resolution)` cells (`marca_pto`),
//! and polygon edges are traced with Bresenham's algorithm (`marca_linha`). The seed marked only
//! every `ceil(radius / resolution)`-th point of an edge; we mark every point, which costs little
//! (rows are filled a word at a time) and leaves no gaps for thin diagonal walls.
//!
//! Nothing here ever writes outside the grid: lines and squares are clipped.

use crate::geom::PointM;
use crate::grid::Grid;

/// The cells of a Bresenham line from `from` to `to`, both ends included, in order.
///
/// Cells are signed so that lines may start or end outside a grid; the walk is always finite
/// (`max(|dx|, |dy|) + 1` cells).
///
/// ```
/// use twil_core::raster::BresenhamLine;
/// let cells: Vec<(i32, i32)> = BresenhamLine::new((0, 0), (4, 2)).collect();
/// // Ties (y = 0.5 at x = 1) round up.
/// assert_eq!(cells, vec![(0, 0), (1, 1), (2, 1), (3, 2), (4, 2)]);
/// ```
#[derive(Clone, Debug)]
pub struct BresenhamLine {
    x: i32,
    y: i32,
    dx: i32,
    dy: i32,
    sx: i32,
    sy: i32,
    err: i32,
    remaining: u32,
}

impl BresenhamLine {
    /// The line from `from` to `to`. Coordinates are clamped to ±1 000 000 cells.
    pub fn new(from: (i32, i32), to: (i32, i32)) -> Self {
        const LIMIT: i32 = 1_000_000;
        let c = |v: i32| v.clamp(-LIMIT, LIMIT);
        let (x0, y0, x1, y1) = (c(from.0), c(from.1), c(to.0), c(to.1));
        let dx = (x1 - x0).abs();
        let dy = -(y1 - y0).abs();
        Self {
            x: x0,
            y: y0,
            dx,
            dy,
            sx: if x0 < x1 { 1 } else { -1 },
            sy: if y0 < y1 { 1 } else { -1 },
            err: dx + dy,
            remaining: dx.max(-dy) as u32 + 1,
        }
    }
}

impl Iterator for BresenhamLine {
    type Item = (i32, i32);

    fn next(&mut self) -> Option<(i32, i32)> {
        if self.remaining == 0 {
            return None;
        }
        self.remaining -= 1;
        let here = (self.x, self.y);
        let e2 = 2 * self.err;
        if e2 >= self.dy {
            self.err += self.dy;
            self.x += self.sx;
        }
        if e2 <= self.dx {
            self.err += self.dx;
            self.y += self.sy;
        }
        Some(here)
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        (self.remaining as usize, Some(self.remaining as usize))
    }
}

/// Mark the square of half-side `half_side` cells centred on cell (`x`, `y`) (seed `marca_pto`),
/// clipped to the grid.
pub fn mark_square<const W: usize>(grid: &mut Grid<W>, x: i32, y: i32, half_side: u16) {
    let h = half_side as i32;
    for row in y.saturating_sub(h)..=y.saturating_add(h) {
        grid.fill_row(row, x.saturating_sub(h), x.saturating_add(h));
    }
}

/// Mark every cell of the Bresenham line between two cells, each grown to a square of half-side
/// `half_side` (seed `marca_linha`).
pub fn mark_line<const W: usize>(
    grid: &mut Grid<W>,
    from: (i32, i32),
    to: (i32, i32),
    half_side: u16,
) {
    if half_side == 0 {
        for (x, y) in BresenhamLine::new(from, to) {
            grid.set_xy(x, y, true);
        }
        return;
    }
    // Consecutive squares overlap: after the first, only the new row or column of each step is
    // new, but filling whole squares keeps this simple and it is fast enough (a row is a few
    // word operations).
    for (x, y) in BresenhamLine::new(from, to) {
        mark_square(grid, x, y, half_side);
    }
}

/// Mark one obstacle point in world metres, grown by `half_side` cells. Non-finite points are
/// ignored; points off the map mark only the part of their square that is on it.
pub fn mark_point_m<const W: usize>(grid: &mut Grid<W>, point: PointM, half_side: u16) {
    if let Some((x, y)) = grid.geometry().cell_xy_of(point) {
        mark_square(grid, x, y, half_side);
    }
}

/// Mark the closed outline of a polygon given by its vertices in metres (seed
/// `carrega_descr_amb`): each edge, including the one from the last vertex back to the first, is
/// traced with [`mark_line`]. A single vertex marks one square. Non-finite vertices are skipped.
pub fn mark_polygon<const W: usize>(grid: &mut Grid<W>, vertices: &[PointM], half_side: u16) {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{Grid300, GridGeometry};

    fn line(a: (i32, i32), b: (i32, i32)) -> heapless::Vec<(i32, i32), 64> {
        BresenhamLine::new(a, b).collect()
    }

    #[test]
    fn bresenham_covers_all_octants_end_to_end() {
        for &(dx, dy) in &[
            (5, 2),
            (2, 5),
            (-5, 2),
            (-2, 5),
            (5, -2),
            (2, -5),
            (-5, -2),
            (-2, -5),
            (0, 0),
            (7, 0),
            (0, -7),
            (4, 4),
        ] {
            let cells = line((10, 10), (10 + dx, 10 + dy));
            assert_eq!(cells.first(), Some(&(10, 10)));
            assert_eq!(cells.last(), Some(&(10 + dx, 10 + dy)));
            assert_eq!(cells.len() as i32, dx.abs().max(dy.abs()) + 1);
            for w in cells.windows(2) {
                assert!((w[0].0 - w[1].0).abs() <= 1 && (w[0].1 - w[1].1).abs() <= 1);
            }
        }
    }

    #[test]
    fn square_is_clipped_at_the_border() {
        let mut grid = Grid300::new(GridGeometry::new(10, 10, 0.1).unwrap()).unwrap();
        mark_square(&mut grid, 0, 0, 2);
        assert_eq!(grid.count_occupied(), 9);
        mark_square(&mut grid, -100, 5, 3);
        assert_eq!(grid.count_occupied(), 9);
        mark_square(&mut grid, i32::MAX, i32::MIN, u16::MAX);
        assert_eq!(grid.count_occupied(), 9);
    }

    #[test]
    fn polygon_outline_is_grown() {
        let mut grid = Grid300::new(GridGeometry::new(100, 100, 0.1).unwrap()).unwrap();
        let square = [
            PointM::new(3.0, 3.0),
            PointM::new(6.0, 3.0),
            PointM::new(6.0, 6.0),
            PointM::new(3.0, 6.0),
        ];
        mark_polygon(&mut grid, &square, 1);
        // The outline from cell 30 to 60 grown by one cell: a 33x33 ring, 3 cells thick.
        assert_eq!(grid.count_occupied(), 33 * 33 - 27 * 27);
        assert!(
            !grid.is_occupied_xy(45, 45),
            "inside of the outline stays free"
        );
        assert!(grid.is_occupied_xy(29, 45));
        assert!(!grid.is_occupied_xy(28, 45));
    }

    #[test]
    fn polygon_far_outside_marks_nothing_and_terminates() {
        let mut grid = Grid300::new(GridGeometry::new(10, 10, 0.1).unwrap()).unwrap();
        mark_polygon(
            &mut grid,
            &[
                PointM::new(-1.0e9, 5.0),
                PointM::new(-1.0e9, 6.0),
                PointM::new(f32::NAN, 1.0),
            ],
            3,
        );
        assert_eq!(grid.count_occupied(), 0);
    }
}
