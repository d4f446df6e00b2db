//! The occupancy grid: one bit per cell, capacity fixed at compile time, size chosen at run time.
//!
//! The seed kept a byte per cell (`mapa[MAXX][MAXY]`, value 127 for an obstacle) and borrowed
//! the top bit as the BFS "visited" mark. Here the map is one bit per cell and every planner keeps
//! its own scratch memory, so planning never writes to the map.
//!
//! Capacity is a const generic counted in 32-bit words (stable Rust cannot compute an array length
//! from two generic parameters); [`words_for_cells`] converts, and [`Grid300`] / [`Grid400`] name
//! the usual sizes. The geometry (width, height, resolution) is a run-time value that must fit the
//! capacity: [`Grid::new`] says so with an error, not a panic.
//!
//! ```
//! use twil_core::grid::{Grid400, GridGeometry};
//! use twil_core::geom::PointM;
//! // The seed's default map: 15 m x 15 m at 0.05 m = 300 x 300 cells.
//! let geometry = GridGeometry::from_size_m(15.0, 15.0, 0.05).unwrap();
//! let mut grid = Grid400::new(geometry).unwrap();
//! let cell = geometry.cell_of(PointM::new(1.02, 2.0)).unwrap();
//! assert_eq!((cell.x, cell.y), (20, 40));
//! grid.set(cell, true);
//! assert!(grid.is_occupied(cell));
//! assert!(geometry.cell_of(PointM::new(-0.1, 2.0)).is_err());
//! ```

use crate::geom::{Cell, PointM};

/// Number of 32-bit words that hold `cells` bits.
pub const fn words_for_cells(cells: usize) -> usize {
    cells.div_ceil(32)
}

/// Cells per side of the default grid (15 m at 0.05 m, seed `defs.h`).
pub const DEFAULT_SIDE_CELLS: u16 = 300;
/// Default resolution, metres per cell (seed `PRECISAO`).
pub const DEFAULT_RESOLUTION_M: f32 = 0.05;
/// Default map side, metres (seed `LARGURA`, `COMPRIMENTO`).
pub const DEFAULT_SIDE_M: f32 = 15.0;
/// Largest width or height accepted, in cells (cell indices are `u16`).
pub const MAX_SIDE_CELLS: u16 = 4096;

/// A grid that holds up to 300 x 300 cells (11 252 bytes).
pub type Grid300 = Grid<{ words_for_cells(300 * 300) }>;
/// A grid that holds up to 400 x 400 cells (20 000 bytes).
pub type Grid400 = Grid<{ words_for_cells(400 * 400) }>;

/// Why a grid or a coordinate was refused.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum GridError {
    /// The resolution is not a finite number greater than zero.
    BadResolution {
        /// The value given, metres.
        resolution_m: f32,
    },
    /// Width or height is zero or larger than [`MAX_SIDE_CELLS`].
    BadSize {
        /// Width asked for, cells.
        width: u32,
        /// Height asked for, cells.
        height: u32,
    },
    /// The geometry needs more cells than the grid's capacity.
    CapacityExceeded {
        /// Cells asked for.
        cells: u32,
        /// Cells the grid can hold.
        capacity: u32,
    },
    /// A point lies outside the map (or is not a finite number).
    OutOfBounds {
        /// The point, metres.
        point: PointM,
    },
    /// Two grids that must have the same geometry do not.
    GeometryMismatch,
}

impl core::fmt::Display for GridError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            GridError::BadResolution { resolution_m } => {
                write!(f, "resolution {resolution_m} m is not a positive number")
            }
            GridError::BadSize { width, height } => write!(
                f,
                "grid size {width}x{height} cells is empty or above {MAX_SIDE_CELLS} per side"
            ),
            GridError::CapacityExceeded { cells, capacity } => write!(
                f,
                "grid needs {cells} cells but its capacity is {capacity} cells"
            ),
            GridError::OutOfBounds { point } => write!(
                f,
                "point ({}, {}) m is outside the map",
                point.x_m, point.y_m
            ),
            GridError::GeometryMismatch => write!(f, "the two grids' geometries differ"),
        }
    }
}

impl core::error::Error for GridError {}

/// Size and resolution of a grid, and the transforms between world metres and cells.
///
/// The world origin is the lower-left corner of cell (0, 0); cell (x, y) covers
/// `[x*res, (x+1)*res) x [y*res, (y+1)*res)`. Only a validated geometry can be built.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GridGeometry {
    width: u16,
    height: u16,
    resolution_m: f32,
}

impl GridGeometry {
    /// A geometry of `width` x `height` cells of `resolution_m` metres.
    pub const fn new(width: u32, height: u32, resolution_m: f32) -> Result<Self, GridError> {
        if !(resolution_m.is_finite() && resolution_m > 0.0) {
            return Err(GridError::BadResolution { resolution_m });
        }
        if width == 0
            || height == 0
            || width > MAX_SIDE_CELLS as u32
            || height > MAX_SIDE_CELLS as u32
        {
            return Err(GridError::BadSize { width, height });
        }
        Ok(Self {
            width: width as u16,
            height: height as u16,
            resolution_m,
        })
    }

    /// A geometry that covers `width_m` x `height_m` metres, rounding up to whole cells as the
    /// seed's `TETO` did (a side that is a whole number of cells within 1e-4 is not rounded up).
    pub fn from_size_m(width_m: f32, height_m: f32, resolution_m: f32) -> Result<Self, GridError> {
        if !(resolution_m.is_finite() && resolution_m > 0.0) {
            return Err(GridError::BadResolution { resolution_m });
        }
        let cells = |side_m: f32| -> u32 {
            let c = side_m / resolution_m;
            if !(c.is_finite() && c > 0.0) {
                return 0;
            }
            if c > MAX_SIDE_CELLS as f32 + 1.0 {
                return u32::MAX;
            }
            ceil_tolerant(c) as u32
        };
        Self::new(cells(width_m), cells(height_m), resolution_m)
    }

    /// The seed's default: 15 m x 15 m at 0.05 m (300 x 300 cells).
    pub const fn seed_default() -> Self {
        Self {
            width: DEFAULT_SIDE_CELLS,
            height: DEFAULT_SIDE_CELLS,
            resolution_m: DEFAULT_RESOLUTION_M,
        }
    }

    /// Width, cells.
    pub const fn width(&self) -> u16 {
        self.width
    }
    /// Height, cells.
    pub const fn height(&self) -> u16 {
        self.height
    }
    /// Side of a cell, metres.
    pub const fn resolution_m(&self) -> f32 {
        self.resolution_m
    }
    /// Number of cells.
    pub const fn cell_count(&self) -> usize {
        self.width as usize * self.height as usize
    }
    /// Width of the map, metres.
    pub fn width_m(&self) -> f32 {
        self.width as f32 * self.resolution_m
    }
    /// Height of the map, metres.
    pub fn height_m(&self) -> f32 {
        self.height as f32 * self.resolution_m
    }

    /// `true` when the signed indices name a cell of this grid.
    #[inline]
    pub const fn contains_xy(&self, x: i32, y: i32) -> bool {
        x >= 0 && y >= 0 && x < self.width as i32 && y < self.height as i32
    }

    /// The cell at signed indices, if inside.
    #[inline]
    pub const fn cell_xy(&self, x: i32, y: i32) -> Option<Cell> {
        if self.contains_xy(x, y) {
            Some(Cell::new(x as u16, y as u16))
        } else {
            None
        }
    }

    /// Row-major index of a cell (`y * width + x`).
    #[inline]
    pub const fn index(&self, cell: Cell) -> usize {
        cell.y as usize * self.width as usize + cell.x as usize
    }

    /// The cell of a row-major index.
    #[inline]
    pub const fn cell_at(&self, index: usize) -> Cell {
        Cell::new(
            (index % self.width as usize) as u16,
            (index / self.width as usize) as u16,
        )
    }

    /// Signed cell indices of a point (floor of metres / resolution), possibly outside the grid.
    /// Non-finite coordinates give `None`.
    pub fn cell_xy_of(&self, point: PointM) -> Option<(i32, i32)> {
        if !point.is_finite() {
            return None;
        }
        let fx = floor(point.x_m / self.resolution_m);
        let fy = floor(point.y_m / self.resolution_m);
        // Clamp far-away points so the casts are defined; they stay outside the grid.
        let clamp = |v: f32| v.clamp(-1.0e6, 1.0e6) as i32;
        Some((clamp(fx), clamp(fy)))
    }

    /// The `(x, y)` of the map cell that contains `point`, or `None` off the map (or for a
    /// non-finite point).
    pub fn cell_xy_on_map(&self, point: PointM) -> Option<(i32, i32)> {
        self.cell_xy_of(point)
            .filter(|&(x, y)| self.contains_xy(x, y))
    }

    /// The cell that contains `point`.
    pub fn cell_of(&self, point: PointM) -> Result<Cell, GridError> {
        self.cell_xy_of(point)
            .and_then(|(x, y)| self.cell_xy(x, y))
            .ok_or(GridError::OutOfBounds { point })
    }

    /// Centre of a cell, metres.
    pub fn center_of(&self, cell: Cell) -> PointM {
        PointM::new(
            (cell.x as f32 + 0.5) * self.resolution_m,
            (cell.y as f32 + 0.5) * self.resolution_m,
        )
    }

    /// Half-side, in cells, of the square that an obstacle point marks for a robot of
    /// `radius_m` (seed `marca_pto`: `ceil(radius / resolution)`). A radius that is a whole
    /// number of cells within 1e-4 is not rounded up, so 0.40 m at 0.05 m gives 8, not 9.
    /// Negative or non-finite radii give 0; absurd ones are capped at the grid's larger side.
    pub fn expansion_cells(&self, radius_m: f32) -> u16 {
        let c = radius_m / self.resolution_m;
        if !(c.is_finite() && c > 0.0) {
            return 0;
        }
        let cap = self.width.max(self.height);
        if c >= cap as f32 {
            return cap;
        }
        ceil_tolerant(c) as u16
    }
}

/// `floor` without `std`.
fn floor(v: f32) -> f32 {
    let t = v as i64 as f32;
    if t > v {
        t - 1.0
    } else {
        t
    }
}

/// `ceil`, but a value within 1e-4 above an integer counts as that integer (float noise in
/// divisions such as 0.4 / 0.05).
fn ceil_tolerant(v: f32) -> f32 {
    let f = floor(v);
    if v - f <= 1.0e-4 {
        f
    } else {
        f + 1.0
    }
}

/// A bit-packed occupancy grid of at most `WORDS * 32` cells. Bit set = occupied (an obstacle or
/// its expansion).
#[derive(Clone, Debug, PartialEq)]
pub struct Grid<const WORDS: usize> {
    geometry: GridGeometry,
    bits: [u32; WORDS],
}

impl<const WORDS: usize> Grid<WORDS> {
    /// Cells this grid type can hold.
    pub const CAPACITY_CELLS: usize = WORDS * 32;

    /// An empty (all free) grid with the given geometry.
    pub fn new(geometry: GridGeometry) -> Result<Self, GridError> {
        Self::check_capacity(geometry)?;
        Ok(Self {
            geometry,
            bits: [0; WORDS],
        })
    }

    fn check_capacity(geometry: GridGeometry) -> Result<(), GridError> {
        if geometry.cell_count() > Self::CAPACITY_CELLS {
            return Err(GridError::CapacityExceeded {
                cells: geometry.cell_count() as u32,
                capacity: Self::CAPACITY_CELLS as u32,
            });
        }
        Ok(())
    }

    /// An empty grid, as a `const fn`: a grid of a large capacity can then be built at compile
    /// time straight into a `static` (the firmware does this; a large value returned by
    /// [`Grid::new`] would pass through the stack). Same contract as [`Grid::new`].
    pub const fn new_const(geometry: GridGeometry) -> Result<Self, GridError> {
        if geometry.cell_count() > Self::CAPACITY_CELLS {
            return Err(GridError::CapacityExceeded {
                cells: geometry.cell_count() as u32,
                capacity: Self::CAPACITY_CELLS as u32,
            });
        }
        Ok(Self {
            geometry,
            bits: [0; WORDS],
        })
    }

    /// Change the geometry and clear the map. On error nothing changes.
    pub fn reset(&mut self, geometry: GridGeometry) -> Result<(), GridError> {
        Self::check_capacity(geometry)?;
        self.geometry = geometry;
        self.clear();
        Ok(())
    }

    /// The grid's geometry.
    pub const fn geometry(&self) -> &GridGeometry {
        &self.geometry
    }

    /// Mark every cell free.
    pub fn clear(&mut self) {
        self.bits.fill(0);
    }

    /// `true` when the cell is occupied. A cell outside the grid counts as occupied.
    #[inline]
    pub fn is_occupied(&self, cell: Cell) -> bool {
        self.is_occupied_xy(cell.x as i32, cell.y as i32)
    }

    /// `true` when the cell at signed indices is occupied or lies outside the grid.
    #[inline]
    pub fn is_occupied_xy(&self, x: i32, y: i32) -> bool {
        if !self.geometry.contains_xy(x, y) {
            return true;
        }
        let i = y as usize * self.geometry.width as usize + x as usize;
        self.bit(i)
    }

    /// Occupancy of a row-major index (which must be below the cell count; beyond it, `true`).
    #[inline]
    pub fn bit(&self, index: usize) -> bool {
        match self.bits.get(index / 32) {
            Some(w) => (w >> (index % 32)) & 1 == 1,
            None => true,
        }
    }

    /// Set or clear one cell. Cells outside the grid are ignored.
    #[inline]
    pub fn set(&mut self, cell: Cell, occupied: bool) {
        self.set_xy(cell.x as i32, cell.y as i32, occupied);
    }

    /// Set or clear the cell at signed indices; outside the grid nothing happens.
    #[inline]
    pub fn set_xy(&mut self, x: i32, y: i32, occupied: bool) {
        if !self.geometry.contains_xy(x, y) {
            return;
        }
        let i = y as usize * self.geometry.width as usize + x as usize;
        if let Some(w) = self.bits.get_mut(i / 32) {
            if occupied {
                *w |= 1 << (i % 32);
            } else {
                *w &= !(1 << (i % 32));
            }
        }
    }

    /// Mark occupied the cells `x0..=x1` of row `y`, clipped to the grid, a word at a time.
    /// Returns the number of words written (0 when nothing of the run is on the grid).
    #[inline]
    pub fn fill_row(&mut self, y: i32, x0: i32, x1: i32) -> usize {
        let w = self.geometry.width as i32;
        if y < 0 || y >= self.geometry.height as i32 {
            return 0;
        }
        let (x0, x1) = (x0.max(0), x1.min(w - 1));
        if x0 > x1 {
            return 0;
        }
        let row = y as usize * w as usize;
        self.fill_bits(row + x0 as usize, row + x1 as usize)
    }

    /// Mark occupied every cell of rows `y0..=y1`, clipped to the grid: one run of bits, since
    /// consecutive rows are consecutive in memory. Returns the number of words written.
    pub fn fill_rows(&mut self, y0: i32, y1: i32) -> usize {
        let (y0, y1) = (y0.max(0), y1.min(self.geometry.height as i32 - 1));
        if y0 > y1 {
            return 0;
        }
        let w = self.geometry.width as usize;
        self.fill_bits(y0 as usize * w, (y1 as usize + 1) * w - 1)
    }

    /// Set the bits `first..=last` (row-major indices below the cell count).
    #[inline]
    fn fill_bits(&mut self, first: usize, last: usize) -> usize {
        let (first_word, last_word) = (first / 32, last / 32);
        // Bits from `first % 32` up in the first word, up to `last % 32` in the last one.
        let head = u32::MAX << (first % 32);
        let tail = u32::MAX >> (31 - last % 32);
        let Some(words) = self.bits.get_mut(first_word..=last_word) else {
            return 0; // cannot happen: the geometry fits the capacity
        };
        match words {
            [only] => *only |= head & tail,
            [start, middle @ .., end] => {
                *start |= head;
                // Most runs of a grown edge span one or two words: no library call for none.
                if !middle.is_empty() {
                    middle.fill(u32::MAX);
                }
                *end |= tail;
            }
            [] => {}
        }
        words.len()
    }

    /// Number of occupied cells.
    pub fn count_occupied(&self) -> usize {
        let n = self.geometry.cell_count();
        let full = n / 32;
        let mut count: usize = self.bits[..full]
            .iter()
            .map(|w| w.count_ones() as usize)
            .sum();
        if !n.is_multiple_of(32) {
            count += (self.bits[full] & ((1u32 << (n % 32)) - 1)).count_ones() as usize;
        }
        count
    }

    /// The packed bits of the used cells (row-major, bit `i % 32` of word `i / 32` is cell `i`).
    pub fn words(&self) -> &[u32] {
        &self.bits[..words_for_cells(self.geometry.cell_count())]
    }

    /// Mark every cell that is occupied in `other`, a grid of the same geometry (of any
    /// capacity). Errors, changing nothing, when the geometries differ.
    pub fn merge_from<const V: usize>(&mut self, other: &Grid<V>) -> Result<(), GridError> {
        if other.geometry() != self.geometry() {
            return Err(GridError::GeometryMismatch);
        }
        for (mine, theirs) in self.bits.iter_mut().zip(other.words()) {
            *mine |= *theirs;
        }
        Ok(())
    }

    /// Overwrite packed words starting at word `offset` (for chunked map transfers). Words beyond
    /// the used cells are refused with `CapacityExceeded` and nothing is written.
    pub fn write_words(&mut self, offset: usize, words: &[u32]) -> Result<(), GridError> {
        let used = words_for_cells(self.geometry.cell_count());
        let end = offset.saturating_add(words.len());
        if end > used {
            return Err(GridError::CapacityExceeded {
                cells: end.saturating_mul(32).min(u32::MAX as usize) as u32,
                capacity: (used * 32) as u32,
            });
        }
        self.bits[offset..end].copy_from_slice(words);
        // Keep the bits past the last cell clear, whatever was sent.
        let n = self.geometry.cell_count();
        if !n.is_multiple_of(32) && end == used {
            self.bits[used - 1] &= (1u32 << (n % 32)) - 1;
        }
        Ok(())
    }

    /// Copy the occupancy of `other` (same geometry) into this grid, cell by cell OR-ed in.
    pub fn union_with(&mut self, other: &Self) {
        if other.geometry == self.geometry {
            for (a, b) in self.bits.iter_mut().zip(other.bits.iter()) {
                *a |= *b;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_geometry_is_300_by_300() {
        let g = GridGeometry::from_size_m(15.0, 15.0, 0.05).unwrap();
        assert_eq!((g.width(), g.height()), (300, 300));
        assert_eq!(g, GridGeometry::seed_default());
    }

    #[test]
    fn refuses_bad_geometry() {
        assert!(matches!(
            GridGeometry::new(300, 300, 0.0),
            Err(GridError::BadResolution { .. })
        ));
        assert!(matches!(
            GridGeometry::new(300, 300, f32::NAN),
            Err(GridError::BadResolution { .. })
        ));
        assert!(matches!(
            GridGeometry::new(0, 3, 0.05),
            Err(GridError::BadSize { .. })
        ));
        assert!(matches!(
            GridGeometry::from_size_m(1.0e9, 3.0, 0.05),
            Err(GridError::BadSize { .. })
        ));
        let big = GridGeometry::new(401, 400, 0.05).unwrap();
        assert!(matches!(
            Grid400::new(big),
            Err(GridError::CapacityExceeded { .. })
        ));
    }

    #[test]
    fn world_cell_round_trip() {
        let g = GridGeometry::seed_default();
        for (x, y) in [(0.0, 0.0), (0.049, 0.051), (14.99, 7.3)] {
            let c = g.cell_of(PointM::new(x, y)).unwrap();
            let centre = g.center_of(c);
            assert!((centre.x_m - x).abs() <= 0.025 + 1e-6);
            assert!((centre.y_m - y).abs() <= 0.025 + 1e-6);
        }
        assert!(g.cell_of(PointM::new(15.0, 1.0)).is_err());
        assert!(g.cell_of(PointM::new(-0.001, 1.0)).is_err());
        assert!(g.cell_of(PointM::new(f32::INFINITY, 1.0)).is_err());
        assert!(g.cell_of(PointM::new(1.0e30, -1.0e30)).is_err());
    }

    #[test]
    fn expansion_matches_seed() {
        let g = GridGeometry::seed_default();
        assert_eq!(g.expansion_cells(0.4), 8);
        assert_eq!(g.expansion_cells(0.35), 7);
        assert_eq!(g.expansion_cells(0.36), 8);
        assert_eq!(g.expansion_cells(-1.0), 0);
        assert_eq!(g.expansion_cells(f32::NAN), 0);
        assert_eq!(g.expansion_cells(1.0e9), 300);
    }

    #[test]
    fn set_fill_and_count() {
        let g = GridGeometry::new(37, 5, 0.1).unwrap();
        let mut grid = Grid300::new(g).unwrap();
        grid.fill_row(2, -5, 100);
        assert_eq!(grid.count_occupied(), 37);
        grid.fill_row(7, 0, 10); // outside: ignored
        assert_eq!(grid.fill_rows(5, 9), 0, "outside: ignored");
        grid.set_xy(-1, 0, true); // outside: ignored
        assert_eq!(grid.count_occupied(), 37);
        assert!(grid.is_occupied_xy(36, 2));
        assert!(!grid.is_occupied_xy(36, 3));
        assert!(grid.is_occupied_xy(37, 3), "outside counts as occupied");
        grid.set(Cell::new(3, 3), false);
        grid.set(Cell::new(3, 2), false);
        assert_eq!(grid.count_occupied(), 36);
        // Rows 3 and 4 (cells 111..=184): words 3 to 5.
        assert_eq!(grid.fill_rows(3, 9), 3);
        assert_eq!(grid.count_occupied(), 36 + 2 * 37);
        assert!(!grid.is_occupied_xy(36, 0) && grid.is_occupied_xy(0, 3));
    }

    #[test]
    fn write_words_refuses_overflow_without_change() {
        let g = GridGeometry::new(40, 1, 0.1).unwrap();
        let mut grid = Grid300::new(g).unwrap();
        assert!(grid.write_words(1, &[1, 2]).is_err());
        assert_eq!(grid.count_occupied(), 0);
        grid.write_words(0, &[u32::MAX, u32::MAX]).unwrap();
        assert_eq!(grid.count_occupied(), 40);
    }
}
