//! The body corridor of a prefix: is everything the body will pass within reach of known?
//!
//! The seed's band check (`plan::needs_full_sweep`) asks only that the *path* lie within the
//! band the last sweep covered. The body is wider than the path: an obstacle just outside the
//! band can lie within the planning radius of a path that turns sideways near the robot. With a
//! 3 m sonar at 0.25-0.35 m/s, stop mode drove into the lower end of the office's right-hand
//! interior wall that way: the robot faced south, the path turned east 0.15 m below the wall's
//! unseen end, 125° off the heading as seen from the sonar.
//!
//! Here each path sample (every cell along the prefix, within sonar range of the robot) has two
//! side points, one planning radius to each side of the path. A side point is *known* when its
//! cell is occupied on the map (an obstacle within reach is already grown into it), was seen by
//! some earlier ray, or lies inside the last sweep's band as seen from the sonar. The prefix is
//! good up to the first sample with an unknown side point.

use crate::control::Pose;
use crate::geom::PointM;
use crate::grid::Grid;
use crate::math::{abs, atan2, hypot, wrap_angle_rad};

/// Most samples looked at (a 6 m sonar range at 0.05 m per sample is 120).
const MAX_SAMPLES: u32 = 512;

/// The map, the seen grid and the last sweep, read together.
pub(super) struct Corridor<'a, const W: usize> {
    /// The robot's map (obstacles grown by the planning radius).
    pub grid: &'a Grid<W>,
    /// Cells some ray crossed before its echo.
    pub seen: &'a Grid<W>,
    /// Where the robot stands and faces (the sweep's pose).
    pub pose: Pose,
    /// Sonar ahead of the centre, metres.
    pub sonar_offset_m: f32,
    /// Half-width of the band the sweep covered, radians.
    pub half_band_rad: f32,
    /// Planning radius, metres.
    pub radius_m: f32,
}

impl<const W: usize> Corridor<'_, W> {
    /// Length along `prefix` up to the first sample whose side points are not all known, or
    /// `None` when every sample within `range_m` of the robot is known.
    pub fn first_unknown_m(&self, prefix: &[PointM], range_m: f32) -> Option<f32> {
        let step_m = self.grid.geometry().resolution_m();
        if !(step_m > 0.0 && self.radius_m.is_finite() && range_m.is_finite()) {
            return None;
        }
        let centre = self.pose.position();
        let mut along_m = 0.0;
        let mut samples = 0;
        for w in prefix.windows(2) {
            let (a, b) = (w[0], w[1]);
            let len_m = hypot(b.x_m - a.x_m, b.y_m - a.y_m);
            if !(len_m.is_finite() && len_m > 1.0e-6) {
                continue;
            }
            // Unit normal to the segment.
            let (nx, ny) = (-(b.y_m - a.y_m) / len_m, (b.x_m - a.x_m) / len_m);
            let mut s_m = 0.0;
            while s_m <= len_m {
                samples += 1;
                if samples > MAX_SAMPLES {
                    return None;
                }
                let t = s_m / len_m;
                let p = PointM::new(a.x_m + t * (b.x_m - a.x_m), a.y_m + t * (b.y_m - a.y_m));
                if hypot(p.x_m - centre.x_m, p.y_m - centre.y_m) > range_m {
                    return None;
                }
                for side in [1.0, -1.0] {
                    let q = PointM::new(
                        p.x_m + side * self.radius_m * nx,
                        p.y_m + side * self.radius_m * ny,
                    );
                    if !self.known(q) {
                        return Some(along_m + s_m);
                    }
                }
                s_m += step_m;
            }
            along_m += len_m;
        }
        None
    }

    fn known(&self, q: PointM) -> bool {
        let g = self.grid.geometry();
        // Off the map: nothing can be there (the map's edge is a wall to the planner).
        let Some((x, y)) = g.cell_xy_of(q) else {
            return true;
        };
        if !g.contains_xy(x, y) {
            return true;
        }
        if self.grid.is_occupied_xy(x, y) || self.seen.is_occupied_xy(x, y) {
            return true;
        }
        let sonar = self.pose.point_ahead(self.sonar_offset_m);
        let bearing = atan2(q.y_m - sonar.y_m, q.x_m - sonar.x_m);
        abs(wrap_angle_rad(bearing - self.pose.heading_rad)) <= self.half_band_rad
    }
}
