//! Seen space: how far the robot may trust a path beyond the seed's rule.
//!
//! The seed keeps only the prefix within sonar range that is visible from the robot. The
//! mission also keeps a second bit grid of the cells some sonar ray crossed before its echo
//! ([`super::Mission::seen`]). A path sample is *trusted* when its cell is free and seen (within
//! [`SEEN_NEAR_CELLS`], for the gaps between rays 1.8° apart) and every cell within the planning
//! radius around it is seen or occupied: then no unseen obstacle can lie within reach of the
//! robot's body there. The prefix may go on through trusted samples up to
//! `MissionConfig::max_trusted_path_m` along the path.
//!
//! Cost: each sample reads (2 × expansion + 1)² cells, each with a 3 × 3 look-up; samples are
//! half a cell apart and stop at the first untrusted one.

use heapless::Vec;

use crate::geom::PointM;
use crate::grid::Grid;
use crate::math::hypot;

/// A path cell counts as seen when a ray crossed a cell within this many cells of it (rays
/// 1.8° apart are one cell apart at 1.6 m, two at 3.2 m).
pub const SEEN_NEAR_CELLS: i32 = 1;

/// The map and the seen-space grid, read together.
pub(super) struct SeenSpace<'a, const W: usize> {
    /// The robot's map (obstacles grown by the planning radius).
    pub grid: &'a Grid<W>,
    /// Cells a ray crossed before its echo.
    pub seen: &'a Grid<W>,
    /// The planning radius in cells.
    pub expansion_cells: i32,
}

impl<const W: usize> SeenSpace<'_, W> {
    /// `true` when the cell of `p` is free, seen, and every cell within the planning radius
    /// around it is seen or occupied.
    pub fn trusted(&self, p: PointM) -> bool {
        let g = self.grid.geometry();
        let Some((x, y)) = g.cell_xy_of(p) else {
            return false;
        };
        if !g.contains_xy(x, y) || self.grid.is_occupied_xy(x, y) || !self.seen_near(x, y) {
            return false;
        }
        let h = self.expansion_cells;
        for cy in y - h..=y + h {
            for cx in x - h..=x + h {
                if g.contains_xy(cx, cy)
                    && !self.grid.is_occupied_xy(cx, cy)
                    && !self.seen_near(cx, cy)
                {
                    return false;
                }
            }
        }
        true
    }

    /// A ray crossed a cell within [`SEEN_NEAR_CELLS`] of (`x`, `y`).
    fn seen_near(&self, x: i32, y: i32) -> bool {
        let g = self.grid.geometry();
        let h = SEEN_NEAR_CELLS;
        for cy in y - h..=y + h {
            for cx in x - h..=x + h {
                if g.contains_xy(cx, cy) && self.seen.is_occupied_xy(cx, cy) {
                    return true;
                }
            }
        }
        false
    }

    /// The prefix of `path` through trusted samples, at most `cap_m` along the path; returns
    /// its length and, when `out` is given, writes its vertices there (cut short if `out`
    /// fills). With `out` `None` it only measures, so the caller can compare rules without a
    /// second buffer.
    pub fn prune_through_seen<const P: usize>(
        &self,
        path: &[PointM],
        cap_m: f32,
        mut out: Option<&mut Vec<PointM, P>>,
    ) -> f32 {
        if let Some(v) = out.as_deref_mut() {
            v.clear();
        }
        let mut push = |p: PointM| match out.as_deref_mut() {
            Some(v) => v.push(p).is_ok(),
            None => true,
        };
        let Some(&first) = path.first() else {
            return 0.0;
        };
        push(first);
        let step_m = 0.5 * self.grid.geometry().resolution_m();
        let mut length_m = 0.0f32;
        for pair in path.windows(2) {
            let (a, b) = (pair[0], pair[1]);
            let (dx, dy) = (b.x_m - a.x_m, b.y_m - a.y_m);
            let segment_m = hypot(dx, dy);
            if segment_m.is_nan() || segment_m <= 0.0 {
                continue;
            }
            let allowed_m = segment_m.min(cap_m - length_m);
            let samples = ((allowed_m / step_m) as u32)
                .saturating_add(1)
                .min(1_000_000);
            let at = |t_m: f32| {
                PointM::new(
                    a.x_m + dx * (t_m / segment_m),
                    a.y_m + dy * (t_m / segment_m),
                )
            };
            let mut last_ok_m = 0.0f32;
            for k in 1..=samples {
                let t_m = allowed_m * (k as f32 / samples as f32);
                if !self.trusted(at(t_m)) {
                    if last_ok_m > 0.0 {
                        push(at(last_ok_m));
                    }
                    return length_m + last_ok_m;
                }
                last_ok_m = t_m;
            }
            if allowed_m < segment_m {
                push(at(allowed_m));
                return length_m + allowed_m;
            }
            if !push(b) {
                return length_m;
            }
            length_m += segment_m;
        }
        length_m
    }
}
