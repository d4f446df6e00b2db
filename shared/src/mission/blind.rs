//! Where a prefix may end: not with unknown space in the sonar's blind zone.
//!
//! At the end of a prefix the robot reads again, and its sonar hears nothing nearer than
//! `sonar_min_range_m` (0.26 m, the transducer still ringing from its own ping). An obstacle in
//! that zone reads as silence, which the mission takes for free space. The body corridor
//! (`corridor`) keeps the body's disc out of unknown space; the sonar, 0.20 m ahead of the
//! centre, has its blind disc reaching 0.06 m further. So the prefix is shortened
//! until every point of that disc outside the body's is known: crossed by a ray, marked as an
//! obstacle, under the body now, or vouched for by the last standing sweep (`swept`).
//!
//! Without it a wall that sat on the range limit of the first sweep (its echoes on the
//! threshold, rejected by the regions-of-constant-depth filter) was met head-on: the robot
//! stopped with its sonar 0.20 m from it, heard nothing and planned through it
//! (`worlds/corridor`, 3 m, beam sonar with the filter; `worlds/enclosed`, 1.5 m, continuous).
//! The cut costs a few centimetres on prefixes that end sideways at the edge of what was read.

use super::evidence::EvidenceMap;
use super::swept::Swept;
use crate::control::Pose;
use crate::geom::polyline_length_m;
use crate::geom::PointM;
use crate::grid::Grid;
use crate::math::hypot;

/// Most end positions tried (one per cell back along the prefix).
const MAX_TRIES: u32 = 256;

/// What the blind-zone rule reads.
pub(super) struct BlindZone<'a, const W: usize, const E: usize = W> {
    /// The robot's map (obstacles grown by the planning radius).
    pub grid: &'a Grid<W>,
    /// With the evidence map: a point is known by its own cell's mark, not by lying in a
    /// mark's grown disc on `grid`. A wall heard only at one point (its foot, a region of
    /// constant depth) may run on from there into the blind disc, where it is silent: its
    /// foot 0.34 m from the sonar, its line 0.24 m (world 3 of `twil sonar-grid`, 25°/25°,
    /// 3 m, stop mode, where the sweep there then vouched the mark away and the robot drove
    /// through the wall).
    pub marks: Option<&'a EvidenceMap<W, E>>,
    /// Cells some ray crossed before its echo.
    pub seen: &'a Grid<W>,
    /// Where the robot stands and faces (the last sweep's pose).
    pub pose: Pose,
    /// Sonar ahead of the centre, metres.
    pub sonar_offset_m: f32,
    /// Radius of the blind disc around the sonar: its minimum range, metres.
    pub blind_radius_m: f32,
    /// Planning radius (the body's disc checked by the corridor), metres.
    pub radius_m: f32,
    /// The body's radius, metres.
    pub body_radius_m: f32,
    /// The last standing sweep (`Swept::NOTHING` after a moving pass, whose readings came from
    /// other poses).
    pub swept: Swept<'a>,
}

impl<const W: usize, const E: usize> BlindZone<'_, W, E> {
    /// Length of `prefix` to keep so that the sonar's blind disc at its end holds no unknown
    /// point, or `None` when the whole prefix may be kept (or no end within it would do).
    pub fn keep_m(&self, prefix: &[PointM]) -> Option<f32> {
        let step_m = self.grid.geometry().resolution_m();
        if !(step_m > 0.0 && self.blind_radius_m > 0.0 && self.radius_m.is_finite()) {
            return None;
        }
        let total_m = polyline_length_m(prefix);
        if !total_m.is_finite() {
            return None;
        }
        let mut keep_m = total_m;
        for _ in 0..MAX_TRIES {
            let (end, dir) = point_along(prefix, keep_m)?;
            if self.blind_disc_known(end, dir) {
                return (keep_m < total_m - 1.0e-4).then_some(keep_m);
            }
            if keep_m <= 0.0 {
                return None;
            }
            keep_m = (keep_m - step_m).max(0.0);
        }
        None
    }

    /// Every point of the sonar's blind disc at `end` facing `dir`, outside the body's disc,
    /// known?
    fn blind_disc_known(&self, end: PointM, dir: (f32, f32)) -> bool {
        let step_m = self.grid.geometry().resolution_m();
        let rho = self.blind_radius_m;
        let sonar = PointM::new(
            end.x_m + self.sonar_offset_m * dir.0,
            end.y_m + self.sonar_offset_m * dir.1,
        );
        let n = (rho / step_m) as i32 + 1;
        for i in -n..=n {
            for j in -n..=n {
                let (dx, dy) = (i as f32 * step_m, j as f32 * step_m);
                if dx * dx + dy * dy > rho * rho {
                    continue;
                }
                let q = PointM::new(sonar.x_m + dx, sonar.y_m + dy);
                if hypot(q.x_m - end.x_m, q.y_m - end.y_m) <= self.radius_m {
                    continue; // the body's disc: the corridor's business
                }
                if !self.known(q) {
                    return false;
                }
            }
        }
        true
    }

    fn known(&self, q: PointM) -> bool {
        let g = self.grid.geometry();
        // Off the map: nothing can be there (the map's edge is a wall to the planner).
        let Some((x, y)) = g.cell_xy_on_map(q) else {
            return true;
        };
        let marked = match self.marks {
            Some(evidence) => evidence.is_occupied_xy(x, y),
            None => self.grid.is_occupied_xy(x, y),
        };
        if marked || self.seen.is_occupied_xy(x, y) {
            return true;
        }
        let centre = self.pose.position();
        if hypot(q.x_m - centre.x_m, q.y_m - centre.y_m) <= self.body_radius_m + 1.0e-3 {
            return true;
        }
        // Read by the last standing sweep, between its rays.
        self.swept.vouches(q)
    }
}

/// The point `length_m` along `points` and the unit direction of the segment it lies on.
fn point_along(points: &[PointM], length_m: f32) -> Option<(PointM, (f32, f32))> {
    let mut along_m = 0.0;
    let mut last = None;
    for w in points.windows(2) {
        let (a, b) = (w[0], w[1]);
        let len_m = hypot(b.x_m - a.x_m, b.y_m - a.y_m);
        if !(len_m.is_finite() && len_m > 1.0e-6) {
            continue;
        }
        let dir = ((b.x_m - a.x_m) / len_m, (b.y_m - a.y_m) / len_m);
        if along_m + len_m >= length_m {
            let t = (length_m - along_m).clamp(0.0, len_m);
            return Some((PointM::new(a.x_m + t * dir.0, a.y_m + t * dir.1), dir));
        }
        along_m += len_m;
        last = Some((b, dir));
    }
    last
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::GridGeometry;
    use crate::sonar::Reading;

    const W: usize = crate::grid::words_for_cells(100 * 100);

    fn grids() -> (Grid<W>, Grid<W>) {
        let g = GridGeometry::new(100, 100, 0.05).unwrap();
        (Grid::new(g).unwrap(), Grid::new(g).unwrap())
    }

    /// A silent ±93.6° sweep from (1, 1) facing +y with a 1.5 m sonar.
    fn silent_sweep() -> heapless::Vec<Reading, 201> {
        let step = 1.8f32.to_radians();
        let mut v = heapless::Vec::new();
        for i in -52..=52 {
            let _ = v.push(Reading {
                neck_angle_rad: i as f32 * step,
                range_m: None,
                pose: pose(),
            });
        }
        v
    }

    fn pose() -> Pose {
        Pose::new(1.0, 1.0, core::f32::consts::FRAC_PI_2)
    }

    fn zone<'a>(
        grid: &'a Grid<W>,
        seen: &'a Grid<W>,
        readings: &'a [Reading],
        half_band_rad: f32,
    ) -> BlindZone<'a, W> {
        BlindZone {
            grid,
            marks: None,
            seen,
            pose: pose(),
            sonar_offset_m: 0.2,
            blind_radius_m: 0.31,
            radius_m: 0.4,
            body_radius_m: 0.2,
            swept: Swept {
                readings,
                pose: pose(),
                sonar_offset_m: 0.2,
                half_band_rad,
                min_range_m: 0.26,
                range_m: 1.5,
                cell_m: 0.05,
                echo_limited: true,
                thales_beam_rad: -1.0,
                heard_beam_rad: -1.0,
                reading_shift_m: 0.0,
                blind_cells: &crate::mission::swept::BlindCells::NONE,
                steps: None,
            },
        }
    }

    #[test]
    fn an_end_whose_blind_zone_was_read_is_kept() {
        let (grid, seen) = grids();
        let sweep = silent_sweep();
        let prefix = [PointM::new(1.0, 1.0), PointM::new(1.0, 2.0)];
        // Ahead, within the sweep's band and range: sonar at 2.2, disc to 2.51 < 1.2 + 1.45.
        assert_eq!(zone(&grid, &seen, &sweep, 1.63).keep_m(&prefix), None);
    }

    #[test]
    fn an_end_at_the_edge_of_what_was_read_is_pulled_back() {
        let (grid, seen) = grids();
        let sweep = silent_sweep();
        // 1.1 m ahead: the blind disc reaches 1.1 + 0.2 + 0.31 = 1.61 m from the centre,
        // 1.41 m from the sweep's sonar: read. 1.4 m ahead it reaches 1.71 m from the sonar.
        let prefix = [PointM::new(1.0, 1.0), PointM::new(1.0, 2.4)];
        let kept = zone(&grid, &seen, &sweep, 1.63)
            .keep_m(&prefix)
            .expect("cut");
        assert!((1.0..1.2).contains(&kept), "{kept}");
        // Cells crossed by a ray count whatever the band: mark the column ahead as seen.
        let (grid, mut seen) = grids();
        for y in 20..70 {
            for x in 10..31 {
                seen.set_xy(x, y, true);
            }
        }
        assert_eq!(zone(&grid, &seen, &sweep, 0.0).keep_m(&prefix), None);
    }

    #[test]
    fn with_the_evidence_map_a_marks_grown_disc_is_not_known_only_the_mark() {
        use crate::mission::evidence::EvidenceMap;
        use crate::raster::mark_point_m;
        // A mark 0.4 m ahead of the sonar where the prefix ends (at (1.0, 1.7)), outside its
        // 0.31 m blind disc, grown by the planning radius over the part of the disc outside
        // the body's; nothing seen, no sweep.
        let (mut grid, seen) = grids();
        let g = *grid.geometry();
        let mark = PointM::new(1.0, 2.1);
        mark_point_m(&mut grid, mark, 8);
        let mut evidence = EvidenceMap::<W, W>::new_const(g).unwrap();
        let (mx, my) = g.cell_xy_of(mark).unwrap();
        evidence.observe_occupied_xy(mx, my);
        let sweep = silent_sweep();
        let prefix = [PointM::new(1.0, 1.0), PointM::new(1.0, 1.5)];
        let mut z = zone(&grid, &seen, &sweep, 0.0);
        // Without the evidence map the grown disc counts as known: the whole prefix is kept
        // (the rule reports `None` then as when no end would do; the cut below tells them
        // apart).
        assert_eq!(z.keep_m(&prefix), None);
        assert!(z.blind_disc_known(PointM::new(1.0, 1.5), (0.0, 1.0)));
        // With it, only the mark's own cell does: the end's blind disc is not known.
        z.marks = Some(&evidence);
        assert!(!z.blind_disc_known(PointM::new(1.0, 1.5), (0.0, 1.0)));
    }

    #[test]
    fn after_a_moving_pass_only_rays_count() {
        let (grid, seen) = grids();
        let sweep = silent_sweep();
        let prefix = [PointM::new(1.0, 1.0), PointM::new(1.0, 1.5)];
        // Nothing seen and no band: even a short prefix ends blind; no end within it would
        // do better than the start, which the rule reports as "keep all" (None): the robot's
        // own blind zone is not the prefix's fault.
        let kept = zone(&grid, &seen, &sweep, 0.0).keep_m(&prefix);
        assert_eq!(kept, None);
    }
}
