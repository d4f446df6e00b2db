//! The body corridor of a prefix: is everything the body will pass within reach of known?
//!
//! The seed's band check (`plan::needs_full_sweep`) asks only that the *path* lie within the
//! band the last sweep covered. The body is wider than the path: an obstacle just outside the
//! band can lie within the planning radius of a path that turns sideways near the robot. With a
//! 3 m sonar at 0.25-0.35 m/s, stop mode drove into the lower end of the office's right-hand
//! interior wall that way: the robot faced south, the path turned east 0.15 m below the wall's
//! unseen end, 125° off the heading as seen from the sonar.
//!
//! Here each path sample (every cell along the prefix, within sonar range of the robot) has
//! points beside it, every cell out to one planning radius on each side of the path. A point is
//! *known* when it was seen by some earlier ray or the last standing sweep vouches for it
//! between its rays (`swept`); the two outermost ones also when their cell is occupied on the map (an obstacle
//! within reach is already grown into it). The prefix is good up to where the body, a disc of the
//! planning radius, would first reach an unknown point.

use super::evidence::EvidenceMap;
use super::swept::Swept;
use crate::control::Pose;
use crate::geom::PointM;
use crate::grid::Grid;
use crate::math::{hypot, sqrt};

/// Most samples looked at (a 6 m sonar range at 0.05 m per sample is 120).
const MAX_SAMPLES: u32 = 512;

/// The map, the seen grid and the last sweep, read together.
pub(super) struct Corridor<'a, const W: usize, const E: usize> {
    /// The robot's map (obstacles grown by the planning radius).
    pub grid: &'a Grid<W>,
    /// Cells some ray crossed before its echo.
    pub seen: &'a Grid<W>,
    /// Where the robot stands and faces (the sweep's pose).
    pub pose: Pose,
    /// The last standing sweep, with the band it may vouch for (`Swept::NOTHING` after a
    /// full sweep's `occupied_only` check or a moving pass).
    pub swept: Swept<'a>,
    /// Planning radius, metres.
    pub radius_m: f32,
    /// The body's radius, metres: what lies within it of where the robot stands is free.
    pub body_radius_m: f32,
    /// Only occupied cells no ray saw are unknown (after a full sweep, which saw all it
    /// could: the gaps between its rays are not worth another).
    pub occupied_only: bool,
    /// The evidence map's rule: only free evidence (a ray crossed it before its echo), what
    /// the sweep vouches for and the body's own disc (and half a cell) are known; not "not
    /// occupied on the map". The centre line is checked from the path itself, and the stop is
    /// the least over the samples.
    pub evidence: bool,
    /// The evidence map's marks, when it has them: a marked cell is known (an obstacle heard
    /// there) beyond the body's reach of the path, and never within it, whatever else says so
    /// (a confirmed mark carries the free bit too, and a sweep's vouching only steps a mark
    /// down). Without this a path planned out of a start inside the grown marks (a 0.70 m
    /// slot) took the body onto a wall heard at its foot.
    pub marks: Option<&'a EvidenceMap<W, E>>,
}

impl<const W: usize, const E: usize> Corridor<'_, W, E> {
    /// Length along `prefix` the centre may go before the body reaches an unknown point, or
    /// `None` when everything beside the prefix within `range_m` of the robot is known.
    pub fn first_unknown_m(&self, prefix: &[PointM], range_m: f32) -> Option<f32> {
        self.first_unknown(prefix, range_m)
            .map(|(stop_m, _)| stop_m)
    }

    /// [`Corridor::first_unknown_m`], with the unknown point that set the stop.
    pub fn first_unknown(&self, prefix: &[PointM], range_m: f32) -> Option<(f32, PointM)> {
        let step_m = self.grid.geometry().resolution_m();
        if !(step_m > 0.0 && self.radius_m.is_finite() && range_m.is_finite()) {
            return None;
        }
        let centre = self.pose.position();
        let r = self.radius_m;
        let mut along_m = 0.0;
        let mut samples = 0;
        // Evidence map: the least stop over the samples (a later sample can stop the centre
        // earlier, by up to the radius); without it, the first.
        let mut best: Option<(f32, PointM)> = None;
        let segments = prefix.len().saturating_sub(1);
        for (i, w) in prefix.windows(2).enumerate() {
            let (a, b) = (w[0], w[1]);
            let len_m = hypot(b.x_m - a.x_m, b.y_m - a.y_m);
            if !(len_m.is_finite() && len_m > 1.0e-6) {
                continue;
            }
            // Unit direction and normal of the segment.
            let (ux, uy) = ((b.x_m - a.x_m) / len_m, (b.y_m - a.y_m) / len_m);
            let (nx, ny) = (-uy, ux);
            // Past the last point the body still reaches one radius ahead: sample on into the
            // disc it covers there.
            let last = i + 1 == segments;
            let end_m = if last { len_m + r } else { len_m };
            let mut s_m = 0.0;
            while s_m <= end_m {
                samples += 1;
                if samples > MAX_SAMPLES {
                    return best;
                }
                if best.is_some_and(|(b, _)| along_m + s_m - r > b) {
                    return best;
                }
                let p = PointM::new(a.x_m + s_m * ux, a.y_m + s_m * uy);
                if s_m <= len_m && hypot(p.x_m - centre.x_m, p.y_m - centre.y_m) > range_m {
                    return best;
                }
                let beyond_m = (s_m - len_m).max(0.0);
                let half_width_m = sqrt((r * r - beyond_m * beyond_m).max(0.0));
                if let Some((ahead_m, q)) =
                    self.first_unknown_beside(p, nx, ny, step_m, half_width_m)
                {
                    // The body reaches `ahead_m` ahead of its centre at that lateral offset:
                    // stop its centre that much short of the sample.
                    let stop_m = (along_m + s_m - ahead_m).max(0.0);
                    if !self.evidence {
                        return Some((stop_m, q));
                    }
                    if best.is_none_or(|(b, _)| stop_m < b) {
                        best = Some((stop_m, q));
                    }
                }
                s_m += step_m;
            }
            along_m += len_m;
        }
        best
    }

    /// The points beside `p` along the unit normal `(nx, ny)`, every `step_m` out to
    /// `half_width_m` (at most the planning radius) on each side, and `p` itself past the
    /// prefix's end: `None` when all are known, else how far ahead of its centre the body
    /// reaches at the lateral offset of the first unknown one, `sqrt(r² − d²)`, and that point.
    fn first_unknown_beside(
        &self,
        p: PointM,
        nx: f32,
        ny: f32,
        step_m: f32,
        half_width_m: f32,
    ) -> Option<(f32, PointM)> {
        let r = self.radius_m;
        let full = half_width_m >= r - 1.0e-4;
        // On the prefix the centre line is the path's (checked by the pruning); past its end
        // it is the body's.
        let mut d = if full && !self.evidence {
            step_m.min(r)
        } else {
            0.0
        };
        loop {
            for side in [1.0, -1.0] {
                let q = PointM::new(p.x_m + side * d * nx, p.y_m + side * d * ny);
                // At the radius an occupied cell is known (the obstacle within reach is
                // already grown into it). Nearer the path it is not: an occupied cell there
                // may be the unseen end of a wall whose seen part grew it (a 0.15 m wall's
                // end met this way put the body 0.30 m from it: a collision at 0.36 m/s).
                let known = if self.marked(q) {
                    // The body reaches a mark half a cell past its radius (the cell's extent).
                    d > self.body_radius_m + 0.5 * step_m
                } else if self.occupied_only {
                    self.free_or_seen(q)
                } else if full && d >= r {
                    self.known(q)
                } else {
                    self.free_or_seen(q)
                };
                if !known {
                    return Some((sqrt((r * r - d * d).max(0.0)), q));
                }
            }
            if d >= half_width_m {
                return None;
            }
            d = (d + step_m).min(half_width_m);
        }
    }

    /// Free on the map, seen by some ray, off the map, inside the last sweep's band as seen
    /// from the sonar, or under the body now.
    fn free_or_seen(&self, q: PointM) -> bool {
        let g = self.grid.geometry();
        // Off the map: nothing can be there (the map's edge is a wall to the planner).
        let Some((x, y)) = g.cell_xy_on_map(q) else {
            return true;
        };
        if self.evidence {
            return self.seen.is_occupied_xy(x, y) || self.in_band(q) || self.under_body(q);
        }
        !self.grid.is_occupied_xy(x, y)
            || self.seen.is_occupied_xy(x, y)
            || self.in_band(q)
            || self.under_body(q)
    }

    /// Is `q`'s cell marked on the evidence map (never without its marks, nor off the map)?
    fn marked(&self, q: PointM) -> bool {
        let Some(marks) = self.marks else {
            return false;
        };
        self.grid
            .geometry()
            .cell_xy_on_map(q)
            .is_some_and(|(x, y)| marks.is_occupied_xy(x, y))
    }

    fn in_band(&self, q: PointM) -> bool {
        self.swept.vouches(q)
    }

    fn under_body(&self, q: PointM) -> bool {
        let c = self.pose.position();
        // The evidence map assumes half a cell more (the robot stands there: see `blind`).
        let margin_m = if self.evidence {
            0.5 * self.grid.geometry().resolution_m()
        } else {
            1.0e-3
        };
        hypot(q.x_m - c.x_m, q.y_m - c.y_m) <= self.body_radius_m + margin_m
    }

    fn known(&self, q: PointM) -> bool {
        let g = self.grid.geometry();
        // Off the map: nothing can be there (the map's edge is a wall to the planner).
        let Some((x, y)) = g.cell_xy_on_map(q) else {
            return true;
        };
        self.grid.is_occupied_xy(x, y) || self.seen.is_occupied_xy(x, y) || self.in_band(q)
    }
}
