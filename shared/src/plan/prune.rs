//! Pruning a plan to what the sonar has just seen (seed `gt()`), and the sweep-band check (seed
//! `traj_fora_faixa_leit`).
//!
//! The robot only trusts the part of a new plan that it could have seen from where it stands:
//! the prefix within sonar range whose points are visible from the first point. The seed walked
//! the cell-by-cell path and kept at most `range / (√2 · resolution)` cells, stopping at the
//! first cell not visible from the first one. We keep the same idea on the polyline, with two
//! choices made explicit:
//!
//! - **Range is measured along the path** from its first point. The along-path distance is
//!   never below the Euclidean one, so every kept point is also within `range_m` in a straight
//!   line (the seed's `√2` factor was the same conservative bound on cells).
//! - **Visibility is sampled** along each segment every half cell with [`line_of_sight`] from
//!   the first point's cell; the prefix stops at the last visible sample, so it may end in the
//!   middle of a segment.

use super::line_of_sight;
use crate::geom::PointM;
use crate::grid::Grid;
use crate::math::hypot;

/// The seed's nominal normal sweep: ±95° around the heading (`AMPLITUDE_LEITURA_NORMAL_SONAR`).
/// Its stepper's readings reach only ±93.6° (52 steps of 1.8°); the mission's band checks use
/// that read extent ([`crate::sonar::SweepPlan::covered_half_angle_rad`]), not this constant.
pub const NORMAL_HALF_BAND_RAD: f32 = 95.0 * core::f32::consts::PI / 180.0;

/// Why a pruned prefix ends where it does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PruneEnd {
    /// The whole path was kept.
    PathEnd,
    /// Cut at `range_m` along the path.
    Range,
    /// Cut before the first point not visible from the first point (or off the map).
    Hidden,
    /// The output ran out of room.
    Capacity,
}

/// Result of [`prune_visible_prefix`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Pruned {
    /// Length of the kept prefix along the path, metres.
    pub length_m: f32,
    /// Why it ends there.
    pub end: PruneEnd,
}

/// Keep the prefix of `path` that lies within `range_m` (measured along the path) of its first
/// point and whose points are all visible from the first point on `grid` (see the module docs).
///
/// `out` is cleared, then receives the first point, the whole path vertices that are kept and,
/// when the cut falls inside a segment, the cut point. An empty `path` gives an empty `out`.
/// A first point off the map or in an occupied cell sees nothing: `out` is that single point
/// and the end is [`PruneEnd::Hidden`]. A non-finite or non-positive `range_m` keeps only the
/// first point ([`PruneEnd::Range`]). Zero-length segments are skipped.
///
/// ```
/// use twil_core::geom::PointM;
/// use twil_core::grid::{Grid300, GridGeometry};
/// use twil_core::plan::{prune_visible_prefix, PathM, PruneEnd};
/// let grid = Grid300::new(GridGeometry::new(100, 100, 0.1).unwrap()).unwrap();
/// let path = [PointM::new(0.5, 0.5), PointM::new(5.5, 0.5)];
/// let mut out = PathM::new();
/// let pruned = prune_visible_prefix(&grid, &path, 3.0, &mut out);
/// assert_eq!(pruned.end, PruneEnd::Range);
/// assert_eq!(out.len(), 2);
/// assert!((out[1].x_m - 3.5).abs() < 1e-4);
/// ```
pub fn prune_visible_prefix<const W: usize, const P: usize>(
    grid: &Grid<W>,
    path: &[PointM],
    range_m: f32,
    out: &mut heapless::Vec<PointM, P>,
) -> Pruned {
    out.clear();
    let mut length_m = 0.0f32;
    let done = |length_m: f32, end: PruneEnd| Pruned { length_m, end };
    let Some(&first) = path.first() else {
        return done(0.0, PruneEnd::PathEnd);
    };
    if out.push(first).is_err() {
        return done(0.0, PruneEnd::Capacity);
    }
    let geometry = *grid.geometry();
    let from = match geometry.cell_of(first) {
        Ok(c) if !grid.is_occupied(c) => c,
        _ => return done(0.0, PruneEnd::Hidden),
    };
    if !(range_m.is_finite() && range_m > 0.0) {
        return done(0.0, PruneEnd::Range);
    }
    let step_m = 0.5 * geometry.resolution_m();
    let visible = |p: PointM| match geometry.cell_of(p) {
        Ok(c) => line_of_sight(grid, from, c),
        Err(_) => false,
    };
    for pair in path.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        if !b.is_finite() {
            return done(length_m, PruneEnd::Hidden);
        }
        let (dx, dy) = (b.x_m - a.x_m, b.y_m - a.y_m);
        let segment_m = hypot(dx, dy);
        if segment_m.is_nan() || segment_m <= 0.0 {
            continue;
        }
        let remaining_m = range_m - length_m;
        let allowed_m = if segment_m < remaining_m {
            segment_m
        } else {
            remaining_m
        };
        // Samples every half cell, the last one exactly at `allowed_m`.
        let samples = {
            let n = allowed_m / step_m;
            if n >= 1.0e6 {
                1_000_000u32
            } else {
                (n as u32).saturating_add(1)
            }
        };
        let at = |t_m: f32| {
            PointM::new(
                a.x_m + dx * (t_m / segment_m),
                a.y_m + dy * (t_m / segment_m),
            )
        };
        let mut last_visible_m = 0.0f32;
        for k in 1..=samples {
            let t_m = allowed_m * (k as f32 / samples as f32);
            if !visible(at(t_m)) {
                if last_visible_m > 0.0 && out.push(at(last_visible_m)).is_err() {
                    return done(length_m, PruneEnd::Capacity);
                }
                return done(length_m + last_visible_m, PruneEnd::Hidden);
            }
            last_visible_m = t_m;
        }
        if allowed_m < segment_m {
            if out.push(at(allowed_m)).is_err() {
                return done(length_m, PruneEnd::Capacity);
            }
            return done(range_m, PruneEnd::Range);
        }
        if out.push(b).is_err() {
            return done(length_m, PruneEnd::Capacity);
        }
        length_m += segment_m;
    }
    done(length_m, PruneEnd::PathEnd)
}

/// `true` when a point of `prefix` lies more than `half_band_rad` off `heading_rad` as seen from
/// `pose` (seed `traj_fora_faixa_leit`): the last sweep did not cover it, so the robot should
/// sweep the full 360° before following the path. Use [`NORMAL_HALF_BAND_RAD`] for the seed's
/// ±95° sweep.
///
/// Points within 1 mm of `pose` have no direction and are skipped. A non-finite point, pose or
/// heading gives `true` (sweeping is the safe answer).
///
/// ```
/// use twil_core::geom::PointM;
/// use twil_core::plan::{needs_full_sweep, NORMAL_HALF_BAND_RAD};
/// let pose = PointM::new(1.0, 1.0);
/// let ahead = [pose, PointM::new(2.0, 1.5)];
/// let behind = [pose, PointM::new(0.0, 1.0)];
/// assert!(!needs_full_sweep(&ahead, pose, 0.0, NORMAL_HALF_BAND_RAD));
/// assert!(needs_full_sweep(&behind, pose, 0.0, NORMAL_HALF_BAND_RAD));
/// ```
pub fn needs_full_sweep(
    prefix: &[PointM],
    pose: PointM,
    heading_rad: f32,
    half_band_rad: f32,
) -> bool {
    const MIN_DISTANCE_M: f32 = 1.0e-3;
    if !pose.is_finite() || !heading_rad.is_finite() || half_band_rad.is_nan() {
        return true;
    }
    prefix.iter().any(|p| {
        if !p.is_finite() {
            return true;
        }
        let (dx, dy) = (p.x_m - pose.x_m, p.y_m - pose.y_m);
        if dx * dx + dy * dy < MIN_DISTANCE_M * MIN_DISTANCE_M {
            return false;
        }
        let bearing_rad = crate::math::atan2(dy, dx);
        let off_rad = crate::math::wrap_angle_rad(bearing_rad - heading_rad);
        crate::math::abs(off_rad) > half_band_rad
    })
}
