//! How much of a fresh plan the robot follows: the prefix rules, applied in turn to the
//! path a plan brought back.
//!
//! 1. The seed's prune (within `sonar range − planning radius`, visible), or the seen-space
//!    rule (`trust`) when it keeps more.
//! 2. The band check (seed `traj_fora_faixa_leit`) and the body corridor (`corridor`): a full
//!    sweep first, or (continuous mode) a cut.
//! 3. What the sweep could not see through (`swept`), then the blind zone at the prefix's end
//!    (`blind`).
//!
//! Each rule only shortens the prefix; the rules themselves live in their own files, this one
//! sets them up from the mission's state and applies them in order.

use heapless::Vec;

use crate::control::Pose;
use crate::geom::{polyline_length_m, PointM};
use crate::math::hypot;
use crate::plan::{needs_full_sweep, prune_visible_prefix};
use crate::sonar::{SweepKind, SweepPlan};

use super::blind::BlindZone;
use super::corridor::Corridor;
use super::messages::push;
use super::swept::Swept;
use super::trust::SeenSpace;
use super::{Mission, MissionEvent, MissionMode, MissionOutput, PendingPlan, MISSION_PATH_POINTS};

impl<const W: usize, const E: usize> Mission<W, E> {
    /// Keep what the sonar has just seen of the new path (the seed's prune, or the seen-space
    /// rule when it keeps more), starting at `origin`.
    pub(super) fn keep_prefix(&mut self, pending: &PendingPlan, origin: PointM) {
        let g = *self.grid.geometry();
        // Prune: keep what the sonar has just seen. The seed's rule looks from the first path
        // vertex; the first steps of a path often go to a neighbouring cell, and seen from the
        // start cell the next segment may graze an obstacle corner (the no-corner-cutting
        // rule) although it is clear from its own first cell. So the prune starts from the
        // last vertex within 1.5 cells of the start, and if that keeps nothing beyond a cell,
        // from each later vertex within 3 cells in turn.
        let res_m = g.resolution_m();
        let first = self.path.first().copied().unwrap_or(origin);
        let from_first = |p: &PointM| hypot(p.x_m - first.x_m, p.y_m - first.y_m);
        let skip = self
            .path
            .iter()
            .take_while(|p| from_first(p) <= 1.5 * res_m)
            .count()
            .saturating_sub(1);
        let last_try = self
            .path
            .iter()
            .take_while(|p| from_first(p) <= 3.0 * res_m)
            .count()
            .saturating_sub(1)
            .max(skip);
        // Each try writes the seed's prefix into `self.prefix`; the seen-space rule is measured
        // first and written over it only when it keeps more (no second path buffer: on the MCU
        // this runs on a task's stack).
        let range_m = (self.prune_range_m() - Self::stale_m(pending, origin)).max(res_m);
        let cap_m = self.config.max_trusted_path_m;
        for k in skip..=last_try {
            let rest = self.path.get(k..).unwrap_or(&[]);
            let mut pruned_m =
                prune_visible_prefix(&self.grid, rest, range_m, &mut self.prefix).length_m;
            if self.config.trust_seen_space {
                let seen = SeenSpace {
                    grid: &self.grid,
                    seen: self.evidence.free_plane(),
                    expansion_cells: self.expansion_cells as i32,
                };
                let length_m = seen.prune_through_seen::<MISSION_PATH_POINTS>(rest, cap_m, None);
                if length_m > pruned_m + 1.0e-3 {
                    seen.prune_through_seen(rest, cap_m, Some(&mut self.prefix));
                    pruned_m = length_m;
                }
            }
            if pruned_m > res_m {
                break;
            }
        }
        // The trajectory starts where the robot is (or where it is told to be). Path points
        // within a cell of the origin are dropped: a cell centre a few centimetres behind the
        // robot would otherwise make it turn round for nothing.
        let near_m = g.resolution_m();
        let dropped = self
            .prefix
            .iter()
            .take_while(|p| hypot(p.x_m - origin.x_m, p.y_m - origin.y_m) < near_m)
            .count();
        start_with(&mut self.prefix, dropped, origin);
    }

    /// Shorten the kept prefix to what the last sweep vouches for: the band, the body
    /// corridor, what it could not see through, the blind zone at the end. Returns `false`
    /// when a full sweep or a new plan must come first (it has been asked for).
    pub(super) fn fit_prefix_to_sweep(&mut self, moving: bool, out: &mut MissionOutput) -> bool {
        let g = *self.grid.geometry();
        let res_m = g.resolution_m();
        // Band check (seed traj_fora_faixa_leit): a kept point more than the normal half sweep
        // off the heading needs a full sweep first, unless the last sweep was one.
        let pose = self.pose_world();
        // The band is what the sweep actually read: its outermost readings (±93.6° for the
        // ±95° sweep at 1.8° steps), not the nominal half-width, which the stepper never
        // reaches (the 1.4° beyond the last reading were never looked at).
        let band_rad =
            SweepPlan::new(&self.sweep_robot(moving), SweepKind::Normal).covered_half_angle_rad();
        // Only the part within sonar range is the last sweep's business: farther points were
        // trusted through space seen earlier.
        let range_m = self.config.robot.sonar_range_m;
        let near = self
            .prefix
            .iter()
            .take_while(|p| hypot(p.x_m - pose.x_m, p.y_m - pose.y_m) <= range_m)
            .count()
            .max(1);
        // The body is wider than the path: what lies within the planning radius of the near
        // part must be known too (see `corridor`).
        // A pass taken while moving read each bearing from another pose and heading: its band
        // around the heading now proves nothing, only the rays' cells do.
        let trusted_band_rad = if moving { 0.0 } else { band_rad };
        let mut unknown_at_m = if self.last_sweep_full {
            None
        } else {
            self.first_unknown_beside_prefix_m(pose, trusted_band_rad, false)
        };
        let mut path_outside_band = needs_full_sweep(
            self.prefix.get(..near).unwrap_or(&[]),
            PointM::new(pose.x_m, pose.y_m),
            pose.heading_rad,
            band_rad,
        );
        let mut ends_at_unknown = false;
        // The point a cut after a full sweep stops the body short of (evidence map).
        let mut cut_short_of = None;
        // Two cells, and with the evidence map a rounding error more (a cut of 0.10000005 m is
        // one of two cells: it stalled 1.2 m from the pillars' goal); the seed's marking keeps
        // its comparison.
        let two_cells_m = 2.0 * res_m
            + if self.config.evidence_map {
                1.0e-4
            } else {
                0.0
            };
        if self.last_sweep_full {
            // A full sweep saw all it could from here. What it could not see beside a known
            // obstacle (its end in the sonar's blind zone, or behind it) may reach further:
            // follow only up to where the body would meet it, when that is a move at all.
            let beside_known = Corridor {
                grid: &self.grid,
                seen: self.evidence.free_plane(),
                pose,
                swept: Swept::NOTHING,
                radius_m: self.config.robot.planning_radius_m,
                body_radius_m: self.config.robot.physical_radius_m(),
                occupied_only: true,
                evidence: self.config.evidence_map,
                marks: self.config.evidence_map.then_some(&self.evidence),
            }
            .first_unknown(&self.prefix, range_m);
            match beside_known {
                Some((m, unknown)) if m > two_cells_m => {
                    self.truncate_prefix_m(m);
                    self.stats.band_cuts += 1;
                    cut_short_of = Some(unknown);
                }
                // The body would reach, within two cells, a point the full sweep could not
                // vouch for: following the prefix would take it there (this let it drive into
                // a silent wall between two sparse reflectors, 0.3 m from the path), and no
                // move is short enough to look again. An unknown point is a suspect: mark it
                // and plan again, round it (a verdict may still visit it as a gap). A point
                // on a mark is already grown into the planner's grid: the path keeps the
                // planning radius from the mark's cell, the body 0.1 m more than it needs.
                Some((_, unknown)) if self.config.evidence_map && self.mark_suspect_m(unknown) => {
                    self.stats.band_cuts += 1;
                    self.replan_round_suspect(out);
                    return false;
                }
                _ => {}
            }
        } else {
            let continuous = self.config.mode == MissionMode::Continuous;
            if continuous && path_outside_band {
                // Sweeping while moving: instead of stopping for a full sweep, follow only the
                // part inside the band (at least one cell towards the path, which makes the
                // supplier turn in place first); the sonar keeps sweeping around the new
                // heading and the next pass replans. The body corridor is then the cut
                // prefix's (a cut that turns beside an unseen wall end must stop short of it).
                self.cut_prefix_to_band(
                    PointM::new(pose.x_m, pose.y_m),
                    pose.heading_rad,
                    band_rad,
                );
                self.stats.band_cuts += 1;
                path_outside_band = false;
                let length_m = polyline_length_m(&self.prefix);
                unknown_at_m = self
                    .first_unknown_beside_prefix_m(pose, trusted_band_rad, false)
                    .filter(|m| *m < length_m);
            }
            // Continuous mode may follow a prefix cut short; a cut of two cells or less would
            // stall it (the sonar, 0.20 m ahead, never sees beside the centre while moving),
            // so it stops for a full sweep like stop mode.
            let cut_m = unknown_at_m.filter(|m| *m > 2.0 * g.resolution_m());
            if continuous && cut_m.is_some() {
                // Follow only up to where the body would reach unknown space; the sonar keeps
                // sweeping and the next pass replans.
                self.truncate_prefix_m(unknown_at_m.unwrap_or(0.0));
                self.stats.band_cuts += 1;
                // With the evidence map a moving pass vouches for nothing, so the robot may
                // well reach this end and sweep standing there: the unknown point the body
                // would meet must not then lie in the sonar's blind disc, where no sweep from
                // there can vouch for it (it became a suspect and closed the way).
                ends_at_unknown = self.config.evidence_map;
            } else if path_outside_band || unknown_at_m.is_some() {
                push(out, MissionEvent::FullSweepRequested);
                self.begin_standing_sweep(true, out);
                return false;
            }
        }

        // What the sweep read but could not see through (behind an echo, or in the sonar's
        // blind zone) is no business of a full sweep: follow only up to where the body would
        // reach it, when that is a move at all, and look again from there (see `swept`).
        if !self.last_sweep_full {
            let hidden_at_m = self.first_unknown_beside_prefix_m(pose, trusted_band_rad, true);
            if let Some(m) = hidden_at_m.filter(|m| *m > 2.0 * res_m) {
                self.truncate_prefix_m(m);
                self.stats.band_cuts += 1;
            } else if hidden_at_m.is_some() && self.config.evidence_map {
                // Evidence map: a cut of two cells or less would stall; a full standing sweep
                // reads every bearing of the Thales window (see `swept`).
                push(out, MissionEvent::FullSweepRequested);
                self.begin_standing_sweep(true, out);
                return false;
            }
        }

        // Where the prefix ends the sonar reads again, deaf within its minimum range: end it
        // where that zone is known (see `blind`).
        let swept_half_band_rad = if self.last_sweep_full && !moving {
            core::f32::consts::PI
        } else {
            trusted_band_rad
        };
        let blind = BlindZone {
            grid: &self.grid,
            marks: self.config.evidence_map.then_some(&self.evidence),
            seen: self.evidence.free_plane(),
            pose,
            sonar_offset_m: self.config.robot.sonar_offset_m,
            blind_radius_m: self.config.robot.sonar_min_range_m,
            radius_m: self.config.robot.planning_radius_m,
            body_radius_m: self.config.robot.physical_radius_m(),
            swept: self.swept(pose, swept_half_band_rad, true),
        };
        // A moving pass's prefix is replaced by the next pass's long before its end.
        let blind_cut = if moving && !ends_at_unknown {
            None
        } else {
            blind.keep_m(&self.prefix)
        };
        if let Some(m) = blind_cut {
            self.truncate_prefix_m(m);
            self.stats.blind_cuts += 1;
        }
        // After a full sweep, the blind zone left no move of the cut short of an unknown
        // point: the body could only stand and sweep again, which would vouch for nothing
        // new (a stall 1.2 m from the pillars' goal). The point is a suspect, as when the
        // cut itself was that short: mark it and plan round it.
        if let Some(unknown) = cut_short_of.filter(|_| self.config.evidence_map) {
            if polyline_length_m(&self.prefix) <= two_cells_m && self.mark_suspect_m(unknown) {
                self.replan_round_suspect(out);
                return false;
            }
        }
        true
    }

    /// How far along the prefix the body may go before it reaches space not known to be free
    /// (see [`Corridor`]), within sonar range of `pose`.
    fn first_unknown_beside_prefix_m(
        &self,
        pose: Pose,
        band_rad: f32,
        echo_limited: bool,
    ) -> Option<f32> {
        Corridor {
            grid: &self.grid,
            seen: self.evidence.free_plane(),
            pose,
            swept: self.swept(pose, band_rad, echo_limited),
            radius_m: self.config.robot.planning_radius_m,
            body_radius_m: self.config.robot.physical_radius_m(),
            occupied_only: false,
            evidence: self.config.evidence_map,
            marks: self.config.evidence_map.then_some(&self.evidence),
        }
        .first_unknown_m(&self.prefix, self.config.robot.sonar_range_m)
    }

    /// Keep the first `length_m` of the prefix (cut inside a segment where needed).
    fn truncate_prefix_m(&mut self, length_m: f32) {
        let mut along_m = 0.0;
        for i in 1..self.prefix.len() {
            let (a, b) = (self.prefix[i - 1], self.prefix[i]);
            let len_m = hypot(b.x_m - a.x_m, b.y_m - a.y_m);
            if along_m + len_m > length_m && len_m > 0.0 {
                let t = ((length_m - along_m) / len_m).clamp(0.0, 1.0);
                self.prefix.truncate(i);
                let _ = self.prefix.push(PointM::new(
                    a.x_m + t * (b.x_m - a.x_m),
                    a.y_m + t * (b.y_m - a.y_m),
                ));
                return;
            }
            along_m += len_m;
        }
    }

    /// Keep the prefix up to its last vertex inside the ±`band_rad` band around `heading_rad`
    /// seen from `position`; when the first vertex after the origin is already outside, keep
    /// one cell of the first segment.
    fn cut_prefix_to_band(&mut self, position: PointM, heading_rad: f32, band_rad: f32) {
        let Some(&origin) = self.prefix.first() else {
            return;
        };
        let mut keep = 1;
        for p in self.prefix.iter().skip(1) {
            if needs_full_sweep(&[*p], position, heading_rad, band_rad) {
                break;
            }
            keep += 1;
        }
        if keep >= 2 {
            self.prefix.truncate(keep);
            return;
        }
        let Some(&next) = self.prefix.get(1) else {
            return;
        };
        let d = hypot(next.x_m - origin.x_m, next.y_m - origin.y_m);
        let step_m = self.grid.geometry().resolution_m().min(d);
        self.prefix.truncate(1);
        if d > 0.0 {
            let _ = self.prefix.push(PointM::new(
                origin.x_m + (next.x_m - origin.x_m) * (step_m / d),
                origin.y_m + (next.y_m - origin.y_m) * (step_m / d),
            ));
        }
    }
    /// The last sweep as seen from `pose`, vouching within `half_band_rad` of the heading
    /// (see `swept`).
    pub(super) fn swept(&self, pose: Pose, half_band_rad: f32, echo_limited: bool) -> Swept<'_> {
        Swept::of(
            &self.config,
            self.readings.as_slice(),
            self.grid.geometry().resolution_m(),
            (pose, half_band_rad, echo_limited),
        )
        .with_blind_cells(&self.blind_cells)
    }
    /// How far along the path the seed's rule may keep: the sonar range minus the planning
    /// radius. An obstacle just beyond the range is not seen, and the robot's disc must stay
    /// clear of it wherever the path goes, also sideways where the sonar's 0.20 m offset ahead
    /// of the centre does not help: with the full range (the seed's rule; the seed's cell
    /// count came to 1.06 m) the robot drove its body into a wall 3.0 m to its side with a
    /// 3 m sonar. At least one cell.
    fn prune_range_m(&self) -> f32 {
        let r = &self.config.robot;
        (r.sonar_range_m - r.planning_radius_m).max(self.grid.geometry().resolution_m())
    }
}

/// Replace the first `dropped` points of `path` by `first` (shifting the rest; when `dropped`
/// is 0 and `path` is full, its last point falls off).
pub(super) fn start_with<const P: usize>(path: &mut Vec<PointM, P>, dropped: usize, first: PointM) {
    let n = path.len();
    if dropped == 0 {
        if path.push(first).is_err() {
            // Full: drop the last point to make room.
            path.truncate(n.saturating_sub(1));
            let _ = path.push(first);
        }
        // Rotate the new point to the front.
        path.rotate_right(1);
        return;
    }
    // Keep path[dropped..], preceded by `first`.
    path.rotate_left(dropped - 1);
    path.truncate(n - (dropped - 1));
    if let Some(p) = path.first_mut() {
        *p = first;
    }
}

#[cfg(test)]
mod tests {
    extern crate std;

    use super::*;

    #[test]
    fn the_prefix_starts_at_the_origin_without_the_points_near_it() {
        let p = |x: f32| PointM::new(x, 0.0);
        let origin = PointM::new(-1.0, 0.0);
        let xs = |v: &Vec<PointM, 4>| v.iter().map(|q| q.x_m).collect::<std::vec::Vec<_>>();
        // Nothing dropped: the origin goes in front.
        let mut v: Vec<PointM, 4> = Vec::from_slice(&[p(1.0), p(2.0)]).unwrap();
        start_with(&mut v, 0, origin);
        assert_eq!(xs(&v), [-1.0, 1.0, 2.0]);
        // Full: the last point falls off.
        let mut v: Vec<PointM, 4> = Vec::from_slice(&[p(1.0), p(2.0), p(3.0), p(4.0)]).unwrap();
        start_with(&mut v, 0, origin);
        assert_eq!(xs(&v), [-1.0, 1.0, 2.0, 3.0]);
        // Two dropped.
        let mut v: Vec<PointM, 4> = Vec::from_slice(&[p(1.0), p(2.0), p(3.0), p(4.0)]).unwrap();
        start_with(&mut v, 2, origin);
        assert_eq!(xs(&v), [-1.0, 3.0, 4.0]);
        // All dropped; empty.
        let mut v: Vec<PointM, 4> = Vec::from_slice(&[p(1.0), p(2.0)]).unwrap();
        start_with(&mut v, 2, origin);
        assert_eq!(xs(&v), [-1.0]);
        let mut v: Vec<PointM, 4> = Vec::new();
        start_with(&mut v, 0, origin);
        assert_eq!(xs(&v), [-1.0]);
    }
}
