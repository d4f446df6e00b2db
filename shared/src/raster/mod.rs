//! Rasterization: Bresenham lines and obstacle expansion.
//!
//! The seed plans for a point robot by growing every obstacle by the robot's radius: each
//! obstacle point marks a square of half-side `ceil(radius / resolution)` cells (`marca_pto`),
//! and polygon edges are traced with Bresenham's algorithm (`marca_linha`). The seed marked only
//! every `ceil(radius / resolution)`-th point of an edge; we mark every point, which leaves no
//! gaps for thin diagonal walls and costs nothing more here, since a line is grown by rows (see
//! below), not point by point.
//!
//! Nothing here ever writes outside the grid, and the work is bounded by the map, not by the
//! numbers given:
//!
//! - an edge is first clipped, exactly and in integers ([`BresenhamLine::clipped`]), to the grid
//!   enlarged by the growth margin (`half_side` cells on every side): only the cells whose
//!   square can reach the map are walked, however far away the vertices are;
//! - the union of the squares along the clipped walk is marked row by row: in each row it is
//!   one run of cells (the walk is monotone and 8-connected), found from the closed form of the
//!   walk with a few additions per row and filled a word at a time ([`Grid::fill_row`]). An
//!   edge costs its rows on the grid, not its length nor the growth.
//!
//! The marked cells are exactly those of the seed's definition (every walk cell grown to a
//! square, clipped to the grid); the tests compare with that definition, kept as a test-only
//! reference. Every marking function returns its [`Work`]: edges, rows visited and words
//! written, a count that tests bound without timers. For one edge on a `W` × `H` grid it is at
//! most [`edge_work_bound`]` = 1 + H·(W/32 + 3)`, whatever the coordinates (±1e30, infinities
//! and NaN included: non-finite vertices are skipped, far ones clamped to ±1e6 cells and then
//! clipped) and whatever the growth.

mod clip;
mod grow;
#[cfg(test)]
mod reference;
#[cfg(test)]
mod tests;

use crate::geom::PointM;
use crate::grid::{Grid, GridGeometry};
use clip::LineSteps;

/// Work done by a marking function: edges, rows visited and grid words written. A count, not a
/// time: tests bound it (see the module doc).
pub type Work = u64;

/// Largest [`Work`] one edge (or one square) may cost on a grid of `geometry`: `1 + H·(W/32 +
/// 3)` (one for the edge; at most `H` rows, each one visit and at most `W/32 + 2` words). The
/// growth does not enter: a row costs the same however wide its run.
pub fn edge_work_bound(geometry: &GridGeometry) -> Work {
    let (w, h) = (geometry.width() as u64, geometry.height() as u64);
    1 + h * (w / 32 + 3)
}

/// Largest [`Work`] of [`mark_polygon`] with `vertices` vertices: one [`edge_work_bound`] per
/// edge (a polygon of `n` vertices has `n` edges, the closing one included; one vertex marks
/// one square).
pub fn polygon_work_bound(geometry: &GridGeometry, vertices: usize) -> Work {
    vertices.max(1) as u64 * edge_work_bound(geometry)
}

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
        let ((x0, y0), (x1, y1)) = (clamp_cell(from), clamp_cell(to));
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

/// A cell with both coordinates clamped to ±1 000 000 (the walk's limit: its differences and
/// doubled error terms then fit an `i32`).
fn clamp_cell(cell: (i32, i32)) -> (i32, i32) {
    const LIMIT: i32 = 1_000_000;
    (cell.0.clamp(-LIMIT, LIMIT), cell.1.clamp(-LIMIT, LIMIT))
}

impl BresenhamLine {
    /// The part of the line from `from` to `to` (clamped as [`BresenhamLine::new`] clamps) whose
    /// cells lie in `x_range` × `y_range` (inclusive bounds), in order: exactly the cells the
    /// whole line would visit there, found without walking the rest (see `clip.rs`). `None`
    /// when the line has no cell there.
    ///
    /// ```
    /// use twil_core::raster::BresenhamLine;
    /// let far: Vec<(i32, i32)> =
    ///     BresenhamLine::clipped((-900_000, 0), (900_000, 4), (-1, 1), (0, 9)).unwrap().collect();
    /// assert_eq!(far, vec![(-1, 2), (0, 2), (1, 2)]);
    /// ```
    pub fn clipped(
        from: (i32, i32),
        to: (i32, i32),
        x_range: (i32, i32),
        y_range: (i32, i32),
    ) -> Option<Self> {
        let (from, to) = (clamp_cell(from), clamp_cell(to));
        let whole = Self::new(from, to);
        let steps = LineSteps::new(from, to);
        let (first, last) = steps.steps_within(
            (x_range.0 as i64, x_range.1 as i64),
            (y_range.0 as i64, y_range.1 as i64),
        )?;
        let (x, y) = steps.cell(first);
        Some(Self {
            x: x as i32,
            y: y as i32,
            err: steps.error_at(first) as i32,
            remaining: (last - first + 1) as u32,
            ..whole
        })
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
/// clipped to the grid. Its [`Work`] is at most `H·(W/32 + 3)`.
pub fn mark_square<const W: usize>(grid: &mut Grid<W>, x: i32, y: i32, half_side: u16) -> Work {
    let h = half_side as i32;
    let last_row = grid.geometry().height() as i32 - 1;
    let (x0, x1) = (x.saturating_sub(h), x.saturating_add(h));
    let mut work = 0;
    // Only the rows on the grid: the loop is bounded by the grid, not by `half_side`.
    for row in y.saturating_sub(h).max(0)..=y.saturating_add(h).min(last_row) {
        work += 1 + grid.fill_row(row, x0, x1) as Work;
    }
    work
}

/// Mark every cell of the Bresenham line between two cells, each grown to a square of half-side
/// `half_side` (seed `marca_linha`), clipped to the grid. Its [`Work`] is at most
/// [`edge_work_bound`], wherever the ends are.
pub fn mark_line<const W: usize>(
    grid: &mut Grid<W>,
    from: (i32, i32),
    to: (i32, i32),
    half_side: u16,
) -> Work {
    grow::mark_grown_line(grid, from, to, half_side)
}

/// Mark one obstacle point in world metres, grown by `half_side` cells. Non-finite points are
/// ignored; points off the map mark only the part of their square that is on it.
pub fn mark_point_m<const W: usize>(grid: &mut Grid<W>, point: PointM, half_side: u16) -> Work {
    match grid.geometry().cell_xy_of(point) {
        Some((x, y)) => mark_square(grid, x, y, half_side),
        None => 0,
    }
}

/// Mark the closed outline of a polygon given by its vertices in metres (seed
/// `carrega_descr_amb`): each edge, including the one from the last vertex back to the first, is
/// traced with [`mark_line`]. A single vertex marks one square. Non-finite vertices are skipped.
/// Its [`Work`] is at most [`polygon_work_bound`] for `vertices.len()`.
pub fn mark_polygon<const W: usize>(
    grid: &mut Grid<W>,
    vertices: &[PointM],
    half_side: u16,
) -> Work {
    let geometry = *grid.geometry();
    let mut cells = vertices.iter().filter_map(|v| geometry.cell_xy_of(*v));
    let Some(first) = cells.next() else {
        return 0;
    };
    let mut previous = first;
    let mut edges = 0usize;
    let mut work = 0;
    for cell in cells {
        work += mark_line(grid, previous, cell, half_side);
        previous = cell;
        edges += 1;
    }
    work + if edges == 0 {
        mark_square(grid, first.0, first.1, half_side)
    } else {
        mark_line(grid, previous, first, half_side)
    }
}
