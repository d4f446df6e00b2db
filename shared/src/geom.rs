//! Points in the world frame (metres) and cells of the grid (integer indices).
//!
//! The two are distinct types so that a cell index is never used where metres are meant; the
//! conversion between them lives in [`crate::grid::GridGeometry`], which knows the resolution.

use serde::{Deserialize, Serialize};

/// A point in the world frame, in metres. The origin is the map's lower-left corner, as in the
/// seed (`x` to the right, `y` up).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PointM {
    /// Abscissa, metres.
    pub x_m: f32,
    /// Ordinate, metres.
    pub y_m: f32,
}

impl PointM {
    /// A point at (`x_m`, `y_m`).
    pub const fn new(x_m: f32, y_m: f32) -> Self {
        Self { x_m, y_m }
    }

    /// Euclidean distance to `other`, metres.
    pub fn distance_m(self, other: PointM) -> f32 {
        let dx = other.x_m - self.x_m;
        let dy = other.y_m - self.y_m;
        crate::math::hypot(dx, dy)
    }

    /// `true` when both coordinates are finite numbers.
    pub fn is_finite(self) -> bool {
        self.x_m.is_finite() && self.y_m.is_finite()
    }
}

/// A cell of the grid: column `x`, row `y`. Only a [`crate::grid::GridGeometry`] makes cells
/// that are known to lie inside the grid; a bare `Cell` is just a pair of indices.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize,
)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Cell {
    /// Column.
    pub x: u16,
    /// Row.
    pub y: u16,
}

impl Cell {
    /// The cell at column `x`, row `y`.
    pub const fn new(x: u16, y: u16) -> Self {
        Self { x, y }
    }
}
