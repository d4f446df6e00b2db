//! Points in the world frame (metres), the robot's pose, and cells of the grid (integer
//! indices); the length of a polyline.
//!
//! The point and the cell are distinct types so that a cell index is never used where metres
//! are meant; the conversion between them lives in [`crate::grid::GridGeometry`], which knows
//! the resolution. [`Pose`] is here (not beside the controller) because the sonar, the robot
//! and the mission all read it: it depends on nothing but the maths (issue 27, item 2).

use serde::{Deserialize, Serialize};

use crate::math::{cos, sin, wrap_angle_rad};

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

/// Position and heading of the robot's axle midpoint in the world frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Pose {
    /// Abscissa, metres.
    pub x_m: f32,
    /// Ordinate, metres.
    pub y_m: f32,
    /// Heading, radians counter-clockwise from +x, in `(-π, π]`.
    pub heading_rad: f32,
}

impl Pose {
    /// A pose; the heading is wrapped to `(-π, π]`.
    pub fn new(x_m: f32, y_m: f32, heading_rad: f32) -> Self {
        Self {
            x_m,
            y_m,
            heading_rad: wrap_angle_rad(heading_rad),
        }
    }

    /// The position as a point.
    pub fn position(&self) -> PointM {
        PointM::new(self.x_m, self.y_m)
    }

    /// The point `distance_m` ahead along the heading (the control point, the sonar).
    pub fn point_ahead(&self, distance_m: f32) -> PointM {
        PointM::new(
            self.x_m + distance_m * cos(self.heading_rad),
            self.y_m + distance_m * sin(self.heading_rad),
        )
    }

    /// `true` when all three numbers are finite.
    pub fn is_finite(&self) -> bool {
        self.x_m.is_finite() && self.y_m.is_finite() && self.heading_rad.is_finite()
    }
}

/// Distance from `p` to the segment `a`–`b`, metres.
pub fn distance_to_segment_m(p: PointM, a: PointM, b: PointM) -> f32 {
    let (dx, dy) = (b.x_m - a.x_m, b.y_m - a.y_m);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p.x_m - a.x_m) * dx + (p.y_m - a.y_m) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    crate::math::hypot(p.x_m - (a.x_m + t * dx), p.y_m - (a.y_m + t * dy))
}

/// Euclidean length of a polyline, metres (0 for fewer than two points): the one sum the
/// trajectory, the mission's prefix and blind-zone checks and the host's classic methods share.
pub fn polyline_length_m(points: &[PointM]) -> f32 {
    let mut length_m = 0.0;
    for w in points.windows(2) {
        length_m += w[0].distance_m(w[1]);
    }
    length_m
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
