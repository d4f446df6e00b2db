//! Sonar: the sweep plan, time of flight, the validity window, the regions-of-constant-depth
//! filter, and turning hits into world points and grid marks.
//!
//! # The sensor (seed `defs.h`, `sonar.cpp`)
//!
//! An ultrasonic ranger sits on a neck driven by a stepper motor of 1.8° per step, 0.20 m ahead
//! of the robot's centre. A *sweep* turns the neck from −half to +half of the sweep width,
//! taking one reading per step: ±95° normally, ±180° when the planner asks for a full look
//! around. Each reading times the echo: `range = 343.2 m/s × time / 2`. Readings nearer than
//! 0.26 m (the receiver is still blanked by its own ping) or farther than the trusted range
//! (1.5 m by default, the seed's `ALCANCE_SONAR`; at most 6 m) count as *no echo*.
//!
//! # Plan
//!
//! [`SweepPlan`] lists the neck angles: `n = ⌊half / step⌋` steps each side of straight ahead,
//! `2n + 1` readings (105 for ±95°, 201 for ±180°), symmetric around 0° so straight ahead is
//! always read. (The seed started at −half and took `2⌊half/step⌋` readings, missing the last
//! one; the symmetric plan is simpler to reason about. [`SweepLayout::Seed`] reads as the seed
//! did, for `--preset seed`.) [`SWEEP_CAPACITY`] = 360/1.8 + 1 = 201 readings is what a
//! [`SweepBuffer`] holds.
//!
//! # Regions of constant depth (seed `sonar.cpp`, after Renon & Lages)
//!
//! A sonar's wide beam returns the *nearest* surface anywhere in the beam, so a wall produces
//! a run of readings of nearly the same depth around its perpendicular (a "region of constant
//! depth", RCD), while multipath and crosstalk produce isolated spikes. The filter keeps only
//! readings that belong to a trusted RCD:
//!
//! - two neighbouring readings belong to the same region when both have an echo and their
//!   depths differ by at most [`RcdParams::depth_tolerance_m`] (seed `PRECISION` = 0.5 px on a
//!   50 px/m picture = **0.01 m**);
//! - a region is trusted when it has at least [`RcdParams::min_pairs`] such neighbour pairs
//!   (seed `PADROES` = **4**, i.e. five readings, 7.2° of neck rotation) **or** when the arc it
//!   spans at its depth, `Σ range × step`, reaches [`RcdParams::min_arc_m`] (seed `ARC` = 2π px
//!   = **0.126 m**: far regions cover more wall per step, so fewer readings suffice);
//! - every reading of a trusted region is reported at the region's mean depth (the seed used a
//!   running average that weighted the last readings most; the plain mean is what it meant).
//!
//! Everything else (spikes, ragged returns, oblique surfaces whose depth changes faster than
//! the tolerance per step) is dropped. Setting `min_pairs = 0` turns the filter off: every
//! reading with an echo becomes a hit at its own depth.
//!
//! ```
//! use twil_core::control::Pose;
//! use twil_core::robot::RobotConfig;
//! use twil_core::sonar::{filter_constant_depth, HitBuffer, RcdParams, Reading, SweepBuffer};
//! let config = RobotConfig::default();
//! let mut sweep = SweepBuffer::new();
//! for i in 0..10 {
//!     let range_m = if i == 3 { Some(0.5) } else { Some(1.0) }; // one spike
//!     let neck_angle_rad = (i as f32 - 5.0) * 1.8f32.to_radians();
//!     sweep.push(Reading { neck_angle_rad, range_m, pose: Pose::default() }).unwrap();
//! }
//! let mut hits = HitBuffer::new();
//! let regions = filter_constant_depth(&sweep, &RcdParams::from_config(&config), &mut hits);
//! assert_eq!(regions, 1); // readings 4..=9 (5 pairs); 0..=2 has only 2 pairs, the spike none
//! assert_eq!(hits.len(), 6);
//! ```

use heapless::Vec;
use serde::{Deserialize, Serialize};

use crate::geom::PointM;
use crate::geom::Pose;
use crate::grid::Grid;
use crate::math::{abs, cos, floor, sin};
use crate::raster::mark_point_m;
use crate::robot::{RobotConfig, SPEED_OF_SOUND_M_S};
// The layout is part of the robot's configuration (`robot.rs`, which so need not import this
// file: issue 27, no cycle between files); here too, where sweeps are planned.
pub use crate::robot::SweepLayout;

/// Readings of the widest sweep: 360° / 1.8° + 1 (both ±180° ends).
pub const SWEEP_CAPACITY: usize = 201;

const DEG: f32 = core::f32::consts::PI / 180.0;

/// Which sweep to make.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SweepKind {
    /// ±[`RobotConfig::normal_half_sweep_deg`] (95°), the usual look ahead.
    Normal,
    /// ±[`RobotConfig::full_half_sweep_deg`] (180°), a full look around.
    Full,
}

/// Time of flight (out and back) of an echo from `range_m`, seconds, at 343.2 m/s.
///
/// ```
/// use twil_core::sonar::{range_to_time_of_flight_s, time_of_flight_to_range_m};
/// let t = range_to_time_of_flight_s(1.716);
/// assert!((t - 0.01).abs() < 1e-6);
/// assert!((time_of_flight_to_range_m(t) - 1.716).abs() < 1e-5);
/// ```
pub fn range_to_time_of_flight_s(range_m: f32) -> f32 {
    2.0 * range_m / SPEED_OF_SOUND_M_S
}

/// Range of an echo that came back after `time_of_flight_s` (out and back), metres.
pub fn time_of_flight_to_range_m(time_of_flight_s: f32) -> f32 {
    0.5 * time_of_flight_s * SPEED_OF_SOUND_M_S
}

/// Apply the validity window: `Some(range)` when `min_range_m ≤ range ≤ max_range_m` and
/// finite, else `None` (no echo).
pub fn valid_range_m(range_m: f32, min_range_m: f32, max_range_m: f32) -> Option<f32> {
    if range_m.is_finite() && range_m >= min_range_m && range_m <= max_range_m {
        Some(range_m)
    } else {
        None
    }
}

/// A measured time of flight as a reading: the window of `config`
/// ([`RobotConfig::sonar_min_range_m`] … [`RobotConfig::sonar_range_m`]) applied.
pub fn reading_from_time_of_flight(config: &RobotConfig, time_of_flight_s: f32) -> Option<f32> {
    valid_range_m(
        time_of_flight_to_range_m(time_of_flight_s),
        config.sonar_min_range_m,
        config.sonar_range_m,
    )
}

/// The neck angles of one sweep.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SweepPlan {
    /// Which sweep.
    pub kind: SweepKind,
    /// Steps each side of straight ahead (`n`, readings = `2n + 1`).
    pub steps_each_side: u16,
    /// Neck angle per step, radians.
    pub step_rad: f32,
    /// Which positions are read ([`RobotConfig::sweep_layout`]).
    pub layout: SweepLayout,
}

impl SweepPlan {
    /// The plan for `kind` with the config's step and widths: `n = ⌊half/step⌋` (with 1e-4
    /// slack so 180/1.8 is 100), capped so the plan fits [`SWEEP_CAPACITY`]. A nonsense config
    /// (non-finite or non-positive step) gives a single reading straight ahead.
    pub fn new(config: &RobotConfig, kind: SweepKind) -> Self {
        let half_deg = match kind {
            SweepKind::Normal => config.normal_half_sweep_deg,
            SweepKind::Full => config.full_half_sweep_deg,
        };
        let step_deg = config.neck_step_deg;
        let max_n = ((SWEEP_CAPACITY - 1) / 2) as f32;
        let n = if step_deg.is_finite() && step_deg > 0.0 && half_deg.is_finite() && half_deg > 0.0
        {
            let n = floor(half_deg / step_deg + 1.0e-4);
            if n > max_n {
                max_n
            } else {
                n
            }
        } else {
            0.0
        };
        Self {
            kind,
            steps_each_side: n as u16,
            step_rad: if step_deg.is_finite() && step_deg > 0.0 {
                step_deg * DEG
            } else {
                0.0
            },
            layout: config.sweep_layout,
        }
    }

    /// Number of readings: `2n + 1`, or `2n` (at least 1) with [`SweepLayout::Seed`]
    /// (≤ [`SWEEP_CAPACITY`]).
    pub fn readings(&self) -> usize {
        let n = self.steps_each_side as usize;
        match self.layout {
            SweepLayout::Symmetric => 2 * n + 1,
            SweepLayout::Seed => (2 * n).max(1),
        }
    }

    /// Neck angle of reading `index` (0 = leftmost negative end), radians, or `None` past the
    /// end.
    pub fn neck_angle_rad(&self, index: usize) -> Option<f32> {
        if index >= self.readings() {
            return None;
        }
        Some((index as f32 - self.steps_each_side as f32) * self.step_rad)
    }

    /// All neck angles, in sweep order.
    pub fn angles_rad(&self) -> impl Iterator<Item = f32> + '_ {
        (0..self.readings()).filter_map(move |i| self.neck_angle_rad(i))
    }

    /// The largest neck angle actually read, radians (the band a path must stay in to have
    /// been seen).
    pub fn covered_half_angle_rad(&self) -> f32 {
        self.steps_each_side as f32 * self.step_rad
    }

    /// How long the sweep takes with the config's echo wait and stepper time.
    pub fn timing(&self, config: &RobotConfig) -> SweepTiming {
        SweepTiming {
            readings: self.readings() as u16,
            neck_steps: 4 * self.steps_each_side as u32,
            echo_wait_s: config.echo_wait_s,
            neck_step_time_s: config.neck_step_time_s,
        }
    }
}

/// Simulated duration of a sweep: the neck goes from straight ahead to −half (`n` steps),
/// sweeps to +half reading at each of the `2n + 1` positions (`2n` steps), and comes back
/// (`n` steps): `4n` steps and `2n + 1` echo waits.
///
/// ```
/// use twil_core::robot::RobotConfig;
/// use twil_core::sonar::{SweepKind, SweepPlan};
/// let c = RobotConfig::default();
/// let t = SweepPlan::new(&c, SweepKind::Normal).timing(&c);
/// assert_eq!((t.readings, t.neck_steps), (105, 208));
/// assert!((t.total_s() - (105.0 * 0.035 + 208.0 * 0.001)).abs() < 1e-4);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SweepTiming {
    /// Readings taken.
    pub readings: u16,
    /// Neck steps made, including going to the start and coming back.
    pub neck_steps: u32,
    /// Wait per reading, seconds.
    pub echo_wait_s: f32,
    /// Time per neck step, seconds.
    pub neck_step_time_s: f32,
}

impl SweepTiming {
    /// Time between two readings during the sweep: one echo wait and one step, seconds.
    pub fn per_reading_s(&self) -> f32 {
        self.echo_wait_s + self.neck_step_time_s
    }

    /// Time to move the neck from straight ahead to the first reading, seconds.
    pub fn lead_in_s(&self) -> f32 {
        (self.neck_steps / 4) as f32 * self.neck_step_time_s
    }

    /// Whole sweep, from straight ahead back to straight ahead, seconds.
    pub fn total_s(&self) -> f32 {
        self.readings as f32 * self.echo_wait_s + self.neck_steps as f32 * self.neck_step_time_s
    }
}

/// One sonar reading: neck angle, range or no echo, and the robot pose when it was taken
/// (poses differ within a sweep when the robot moves).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Reading {
    /// Neck angle relative to the heading, radians (positive = left).
    pub neck_angle_rad: f32,
    /// Range from the sonar, metres; `None` = no echo.
    pub range_m: Option<f32>,
    /// Robot pose when the reading was taken.
    pub pose: Pose,
}

/// A sweep's buffer was full.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SweepFull;

impl core::fmt::Display for SweepFull {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "sweep buffer full ({SWEEP_CAPACITY} readings)")
    }
}

impl core::error::Error for SweepFull {}

/// The readings of one sweep, in angle order, at most [`SWEEP_CAPACITY`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SweepBuffer {
    readings: Vec<Reading, SWEEP_CAPACITY>,
}

impl SweepBuffer {
    /// An empty buffer.
    pub const fn new() -> Self {
        Self {
            readings: Vec::new(),
        }
    }

    /// Append a reading; when full, nothing changes and [`SweepFull`] is returned.
    pub fn push(&mut self, reading: Reading) -> Result<(), SweepFull> {
        self.readings.push(reading).map_err(|_| SweepFull)
    }

    /// Forget all readings.
    pub fn clear(&mut self) {
        self.readings.clear();
    }

    /// Readings held.
    pub fn len(&self) -> usize {
        self.readings.len()
    }

    /// `true` when empty.
    pub fn is_empty(&self) -> bool {
        self.readings.is_empty()
    }

    /// The readings, in the order pushed.
    pub fn as_slice(&self) -> &[Reading] {
        &self.readings
    }
}

/// An obstacle hit that passed the filter.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Hit {
    /// Neck angle of the reading, radians.
    pub neck_angle_rad: f32,
    /// Range reported for it (the region's mean depth), metres.
    pub range_m: f32,
    /// Robot pose when it was read.
    pub pose: Pose,
}

impl Hit {
    /// The obstacle point in the world frame (see [`hit_to_world`]).
    pub fn world_point(&self, sonar_offset_m: f32) -> PointM {
        hit_to_world(self.pose, sonar_offset_m, self.neck_angle_rad, self.range_m)
    }
}

/// Hits of one sweep, at most [`SWEEP_CAPACITY`].
pub type HitBuffer = Vec<Hit, SWEEP_CAPACITY>;

/// The constants of the regions-of-constant-depth filter (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RcdParams {
    /// Largest depth difference between neighbours of one region, metres (seed 0.01).
    pub depth_tolerance_m: f32,
    /// Neighbour pairs that make a region trusted (seed 4); 0 turns the filter off.
    pub min_pairs: u8,
    /// Arc length that makes a region trusted with fewer pairs, metres (seed 0.126).
    pub min_arc_m: f32,
    /// Sonar ahead of the robot's centre, metres: where each reading was taken from, for the
    /// depths of a sweep taken while moving (see [`filter_constant_depth`]).
    pub sonar_offset_m: f32,
}

impl RcdParams {
    /// The filter constants of `config`.
    pub fn from_config(config: &RobotConfig) -> Self {
        Self {
            depth_tolerance_m: config.rcd_depth_tolerance_m,
            min_pairs: config.rcd_min_pairs,
            min_arc_m: config.rcd_min_arc_m,
            sonar_offset_m: config.sonar_offset_m,
        }
    }
}

/// Run the regions-of-constant-depth filter over a sweep (readings in angle order) and put
/// the surviving hits in `hits` (cleared first). Returns the number of trusted regions (with
/// the filter off, the number of hits). Readings without an echo, or with a non-finite or
/// negative range, end a region and are never hits. Never fails: there cannot be more hits
/// than readings.
pub fn filter_constant_depth(
    sweep: &SweepBuffer,
    params: &RcdParams,
    hits: &mut HitBuffer,
) -> usize {
    hits.clear();
    // Capacities are equal: a sweep cannot give more hits than readings.
    for_each_constant_depth_hit(sweep, params, |hit| {
        let _ = hits.push(hit);
    })
}

/// [`filter_constant_depth`] without a buffer: hands each surviving hit to `emit`, in the
/// sweep's order, and returns the number of trusted regions (with the filter off, of hits).
/// The mission marks hits as they come, so it keeps no [`HitBuffer`] (4 KB of the MCU's CCM).
pub fn for_each_constant_depth_hit(
    sweep: &SweepBuffer,
    params: &RcdParams,
    mut emit: impl FnMut(Hit),
) -> usize {
    let readings = sweep.as_slice();
    let valid = |r: &Reading| r.range_m.filter(|d| d.is_finite() && *d >= 0.0);
    if params.min_pairs == 0 {
        let mut count = 0;
        for r in readings {
            if let Some(d) = valid(r) {
                emit(Hit {
                    neck_angle_rad: r.neck_angle_rad,
                    range_m: d,
                    pose: r.pose,
                });
                count += 1;
            }
        }
        return count;
    }
    // Depths are compared as seen from where a region's first reading was taken: a sweep taken
    // while moving towards a wall at 0.3 m/s would otherwise see its depth fall by more than
    // the 1 cm tolerance between readings, and the filter would drop every wall ahead (the
    // seed swept standing; there every correction is 0).
    let offset_m = if params.sonar_offset_m.is_finite() {
        params.sonar_offset_m
    } else {
        0.0
    };
    let shift = |r: &Reading, from: PointM| -> f32 {
        let at = r.pose.point_ahead(offset_m);
        let angle = r.pose.heading_rad + r.neck_angle_rad;
        let d = (at.x_m - from.x_m) * cos(angle) + (at.y_m - from.y_m) * sin(angle);
        if d.is_finite() {
            d
        } else {
            0.0
        }
    };
    let tolerance = if params.depth_tolerance_m.is_finite() {
        params.depth_tolerance_m
    } else {
        0.0
    };
    let mut regions = 0;
    let mut start = 0usize;
    while start < readings.len() {
        let Some(first) = readings.get(start).and_then(valid) else {
            start += 1;
            continue;
        };
        let from = readings
            .get(start)
            .map_or(PointM::new(0.0, 0.0), |r| r.pose.point_ahead(offset_m));
        // Grow the region while neighbours agree.
        let mut end = start; // inclusive
        let mut arc_m = 0.0f32;
        let mut sum_m = first;
        let mut previous = first;
        let mut previous_angle = readings.get(start).map_or(0.0, |r| r.neck_angle_rad);
        while let Some(reading) = readings.get(end + 1) {
            let Some(next) = valid(reading).map(|d| d + shift(reading, from)) else {
                break;
            };
            if abs(next - previous) > tolerance {
                break;
            }
            let step = abs(reading.neck_angle_rad - previous_angle);
            previous_angle = reading.neck_angle_rad;
            if step.is_finite() {
                arc_m += previous * step;
            }
            sum_m += next;
            previous = next;
            end += 1;
        }
        let pairs = end - start;
        let trusted =
            pairs >= 1 && (pairs >= params.min_pairs as usize || arc_m >= params.min_arc_m);
        if trusted {
            regions += 1;
            let mean = sum_m / (pairs + 1) as f32;
            for r in readings.iter().take(end + 1).skip(start) {
                emit(Hit {
                    neck_angle_rad: r.neck_angle_rad,
                    range_m: mean - shift(r, from),
                    pose: r.pose,
                });
            }
        }
        start = end + 1;
    }
    regions
}

/// The world point seen at `range_m` by the sonar, which sits `sonar_offset_m` ahead of the
/// centre of `pose` along its heading and looks along `heading + neck_angle_rad`.
///
/// ```
/// use twil_core::control::Pose;
/// use twil_core::sonar::hit_to_world;
/// let p = hit_to_world(Pose::new(1.0, 2.0, 0.0), 0.20, core::f32::consts::FRAC_PI_2, 1.0);
/// assert!((p.x_m - 1.2).abs() < 1e-5 && (p.y_m - 3.0).abs() < 1e-5);
/// ```
pub fn hit_to_world(pose: Pose, sonar_offset_m: f32, neck_angle_rad: f32, range_m: f32) -> PointM {
    let sonar = pose.point_ahead(sonar_offset_m);
    let angle = pose.heading_rad + neck_angle_rad;
    PointM::new(
        sonar.x_m + range_m * cos(angle),
        sonar.y_m + range_m * sin(angle),
    )
}

/// Mark every hit in the grid as an obstacle grown by `expansion_cells` (seed `marca_pto` with
/// the robot's expansion, [`crate::grid::GridGeometry::expansion_cells`]). Hits whose point is
/// not finite are skipped; points off the map mark only what is on it. Returns the number of
/// hits marked.
pub fn mark_hits<const W: usize>(
    grid: &mut Grid<W>,
    hits: &[Hit],
    sonar_offset_m: f32,
    expansion_cells: u16,
) -> usize {
    let mut marked = 0;
    for hit in hits {
        let p = hit.world_point(sonar_offset_m);
        if p.is_finite() {
            mark_point_m(grid, p, expansion_cells);
            marked += 1;
        }
    }
    marked
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{Grid300, GridGeometry};
    use crate::plant::Plant;
    use crate::world::Obstacles;

    fn sweep_of(ranges: &[Option<f32>]) -> SweepBuffer {
        let mut s = SweepBuffer::new();
        let n = ranges.len() as f32;
        for (i, r) in ranges.iter().enumerate() {
            s.push(Reading {
                neck_angle_rad: (i as f32 - n / 2.0) * 1.8 * DEG,
                range_m: *r,
                pose: Pose::default(),
            })
            .unwrap();
        }
        s
    }

    fn filter(ranges: &[Option<f32>]) -> (usize, HitBuffer) {
        let mut hits = HitBuffer::new();
        let n = filter_constant_depth(
            &sweep_of(ranges),
            &RcdParams::from_config(&RobotConfig::default()),
            &mut hits,
        );
        (n, hits)
    }

    #[test]
    fn the_seed_layout_reads_2n_positions_from_the_negative_end() {
        let c = RobotConfig {
            sweep_layout: SweepLayout::Seed,
            ..RobotConfig::default()
        };
        let normal = SweepPlan::new(&c, SweepKind::Normal);
        assert_eq!(normal.readings(), 104);
        let first = normal.neck_angle_rad(0).unwrap();
        let last = normal.neck_angle_rad(103).unwrap();
        assert!((first + 93.6 * DEG).abs() < 1e-5, "{first}");
        assert!((last - 91.8 * DEG).abs() < 1e-5, "{last}");
        assert_eq!(normal.neck_angle_rad(104), None);
        // The neck still goes n steps out, 2n across and n back.
        assert_eq!(normal.timing(&c).neck_steps, 208);
        assert_eq!(normal.timing(&c).readings, 104);
        let full = SweepPlan::new(&c, SweepKind::Full);
        assert_eq!(full.readings(), 200);
        let last = full.neck_angle_rad(199).unwrap();
        assert!((last - 178.2 * DEG).abs() < 1e-4, "{last}");
        // A zero-step plan still reads once.
        let broken = RobotConfig {
            neck_step_deg: f32::NAN,
            ..c
        };
        assert_eq!(SweepPlan::new(&broken, SweepKind::Normal).readings(), 1);
    }

    #[test]
    fn plans_are_symmetric_and_fit() {
        let c = RobotConfig::default();
        let normal = SweepPlan::new(&c, SweepKind::Normal);
        assert_eq!(normal.steps_each_side, 52);
        assert_eq!(normal.readings(), 105);
        let first = normal.neck_angle_rad(0).unwrap();
        let last = normal.neck_angle_rad(104).unwrap();
        assert!((first + 93.6 * DEG).abs() < 1e-5 && (last - 93.6 * DEG).abs() < 1e-5);
        assert_eq!(normal.neck_angle_rad(52), Some(0.0));
        assert_eq!(normal.neck_angle_rad(105), None);
        assert_eq!(normal.angles_rad().count(), 105);
        let full = SweepPlan::new(&c, SweepKind::Full);
        assert_eq!(full.readings(), SWEEP_CAPACITY);
        assert!((full.covered_half_angle_rad() - core::f32::consts::PI).abs() < 1e-5);
        // A finer neck would not fit: capped, never past the capacity.
        let fine = RobotConfig {
            neck_step_deg: 0.9,
            ..c
        };
        assert!(fine.validate().is_err());
        assert_eq!(
            SweepPlan::new(&fine, SweepKind::Full).readings(),
            SWEEP_CAPACITY
        );
        let broken = RobotConfig {
            neck_step_deg: f32::NAN,
            ..c
        };
        assert_eq!(SweepPlan::new(&broken, SweepKind::Full).readings(), 1);
    }

    #[test]
    fn sweep_timing() {
        let c = RobotConfig::default();
        let full = SweepPlan::new(&c, SweepKind::Full).timing(&c);
        assert_eq!((full.readings, full.neck_steps), (201, 400));
        assert!((full.total_s() - (201.0 * 0.035 + 0.4)).abs() < 1e-4);
        assert!((full.per_reading_s() - 0.036).abs() < 1e-6);
        assert!((full.lead_in_s() - 0.1).abs() < 1e-6);
    }

    #[test]
    fn time_of_flight_and_window() {
        assert!((range_to_time_of_flight_s(3.432) - 0.02).abs() < 1e-7);
        assert!((time_of_flight_to_range_m(0.02) - 3.432).abs() < 1e-5);
        let c = RobotConfig::default();
        let tof = |r: f32| range_to_time_of_flight_s(r);
        assert_eq!(reading_from_time_of_flight(&c, tof(0.25)), None);
        assert!(reading_from_time_of_flight(&c, tof(0.27)).is_some());
        assert!(reading_from_time_of_flight(&c, tof(1.49)).is_some());
        assert_eq!(reading_from_time_of_flight(&c, tof(1.51)), None);
        assert_eq!(reading_from_time_of_flight(&c, f32::NAN), None);
        assert_eq!(reading_from_time_of_flight(&c, -1.0), None);
        let far = RobotConfig {
            sonar_range_m: 6.0,
            ..c
        };
        assert!(reading_from_time_of_flight(&far, tof(5.9)).is_some());
    }

    #[test]
    fn flat_run_gives_hits_at_its_mean() {
        let (regions, hits) = filter(&[Some(1.0), Some(1.005), Some(1.0), Some(0.995), Some(1.0)]);
        assert_eq!(regions, 1);
        assert_eq!(hits.len(), 5);
        assert!(hits.iter().all(|h| (h.range_m - 1.0).abs() < 1e-6));
    }

    #[test]
    fn isolated_spike_is_rejected() {
        let mut ranges = [Some(1.2f32); 15];
        ranges[7] = Some(0.6);
        let (regions, hits) = filter(&ranges);
        assert_eq!(regions, 2);
        assert_eq!(hits.len(), 14);
        assert!(hits.iter().all(|h| (h.range_m - 1.2).abs() < 1e-6));
        // Ragged readings: no region.
        let ragged = [
            Some(1.0),
            Some(1.1),
            Some(0.9),
            Some(1.3),
            Some(0.7),
            Some(1.05),
        ];
        assert_eq!(filter(&ragged).0, 0);
    }

    #[test]
    fn short_regions_need_arc_length() {
        // 3 pairs: at 1.5 m the arc is 3 × 1.5 × π/100 = 0.141 m ≥ 0.126 m: trusted.
        let far = [None, Some(1.5), Some(1.5), Some(1.5), Some(1.5), None];
        assert_eq!(filter(&far).0, 1);
        // At 0.5 m the same 4 readings span 0.047 m: rejected.
        let near = [None, Some(0.5), Some(0.5), Some(0.5), Some(0.5), None];
        assert_eq!(filter(&near).0, 0);
        // 4 pairs are enough at any depth.
        let near5 = [Some(0.5); 5];
        assert_eq!(filter(&near5).0, 1);
    }

    #[test]
    fn no_echo_splits_regions() {
        let mut ranges = [Some(1.0f32); 12];
        ranges[6] = None;
        let (regions, hits) = filter(&ranges);
        // 0..=5 (5 pairs) and 7..=11 (4 pairs).
        assert_eq!((regions, hits.len()), (2, 11));
        assert!(hits.iter().all(|h| h.range_m == 1.0));
        let (regions, hits) = filter(&[None; 20]);
        assert_eq!((regions, hits.len()), (0, 0));
    }

    #[test]
    fn a_wall_ahead_of_a_moving_sweep_is_one_region() {
        // The robot drives at a wall 2 m ahead, 1.5 cm per reading (0.4 m/s, 36 ms a
        // reading): each reading is 1.5 cm nearer than the last, beyond the 1 cm tolerance,
        // but the same depth seen from where the region began.
        let config = RobotConfig::default();
        let mut sweep = SweepBuffer::new();
        for i in 0..9 {
            let x_m = 0.015 * i as f32;
            let sonar_x_m = x_m + config.sonar_offset_m;
            let _ = sweep.push(Reading {
                neck_angle_rad: (i as f32 - 4.0) * 1.0f32.to_radians(),
                range_m: Some(2.0 - sonar_x_m),
                pose: Pose::new(x_m, 0.0, 0.0),
            });
        }
        let mut hits = HitBuffer::new();
        let params = RcdParams::from_config(&config);
        assert_eq!(filter_constant_depth(&sweep, &params, &mut hits), 1);
        assert_eq!(hits.len(), 9);
        // Each hit is reported from its own pose: all land on the wall.
        for h in hits.iter() {
            let p = h.world_point(config.sonar_offset_m);
            assert!((p.x_m - 2.0).abs() < 0.01, "{p:?}");
        }
        // Without the poses (all taken from the first), the same ranges make no region.
        let mut standing = SweepBuffer::new();
        for r in sweep.as_slice() {
            let _ = standing.push(Reading {
                pose: Pose::new(0.0, 0.0, 0.0),
                ..*r
            });
        }
        assert_eq!(filter_constant_depth(&standing, &params, &mut hits), 0);
    }

    #[test]
    fn filter_off_passes_every_echo() {
        let sweep = sweep_of(&[Some(1.0), None, Some(0.4), Some(f32::NAN)]);
        let params = RcdParams {
            min_pairs: 0,
            ..RcdParams::from_config(&RobotConfig::default())
        };
        let mut hits = HitBuffer::new();
        assert_eq!(filter_constant_depth(&sweep, &params, &mut hits), 2);
        assert_eq!(hits[1].range_m, 0.4);
    }

    #[test]
    fn simulated_wall_is_seen_around_its_perpendicular() {
        let c = RobotConfig::default();
        let mut walls = Obstacles::new();
        walls
            .push(&[PointM::new(3.2, -5.0), PointM::new(3.2, 5.0)])
            .unwrap();
        // Sonar at x = 2.2: the wall is 1 m ahead.
        let mut plant = Plant::new(&c, Pose::new(2.0, 0.0, 0.0));
        let plan = SweepPlan::new(&c, SweepKind::Normal);
        let mut sweep = SweepBuffer::new();
        for a in plan.angles_rad() {
            let range_m = plant.sonar_range_m(&walls, a, c.sonar_range_m);
            sweep
                .push(Reading {
                    neck_angle_rad: a,
                    range_m,
                    pose: plant.pose(),
                })
                .unwrap();
        }
        let mut hits = HitBuffer::new();
        let regions = filter_constant_depth(&sweep, &RcdParams::from_config(&c), &mut hits);
        assert_eq!(regions, 1);
        // Depth within 1 cm per step near the perpendicular: ±10 steps at 1 m.
        assert!(hits.len() >= 15 && hits.len() <= 25, "{}", hits.len());
        for h in &hits {
            assert!(h.neck_angle_rad.abs() < 20.0 * DEG);
            let p = h.world_point(c.sonar_offset_m);
            assert!((p.x_m - 3.2).abs() < 0.07, "{p:?}");
        }
        // Into the grid with the robot's expansion.
        let geometry = GridGeometry::new(100, 100, 0.05).unwrap();
        let mut grid = Grid300::new(geometry).unwrap();
        let cells = geometry.expansion_cells(c.planning_radius_m);
        assert_eq!(
            mark_hits(&mut grid, &hits, c.sonar_offset_m, cells),
            hits.len()
        );
        let wall_cell = geometry.cell_of(PointM::new(3.2, 0.0)).unwrap();
        assert!(grid.is_occupied(wall_cell));
        // Grown by 0.40 m towards the robot, not much further.
        assert!(grid.is_occupied(geometry.cell_of(PointM::new(2.85, 0.0)).unwrap()));
        assert!(!grid.is_occupied(geometry.cell_of(PointM::new(2.6, 0.0)).unwrap()));
    }

    #[test]
    fn hit_to_world_uses_the_sonar_offset_and_heading() {
        let pose = Pose::new(1.0, 1.0, core::f32::consts::FRAC_PI_2);
        let p = hit_to_world(pose, 0.2, 0.0, 1.0);
        assert!(
            (p.x_m - 1.0).abs() < 2e-3 && (p.y_m - 2.2).abs() < 2e-3,
            "{p:?}"
        );
        let p = hit_to_world(pose, 0.2, -core::f32::consts::FRAC_PI_2, 0.5);
        assert!(
            (p.x_m - 1.5).abs() < 2e-3 && (p.y_m - 1.2).abs() < 2e-3,
            "{p:?}"
        );
    }

    #[test]
    fn full_buffer_refuses_and_keeps_its_readings() {
        let mut s = SweepBuffer::new();
        for _ in 0..SWEEP_CAPACITY {
            s.push(Reading::default()).unwrap();
        }
        let before = s.clone();
        assert_eq!(s.push(Reading::default()), Err(SweepFull));
        assert_eq!(s, before);
    }

    proptest::proptest! {
        #[test]
        fn filter_never_panics_and_reports_only_echoes(
            ranges in proptest::collection::vec(
                proptest::option::of(proptest::num::f32::ANY), 0..SWEEP_CAPACITY),
            angles in proptest::collection::vec(proptest::num::f32::ANY, SWEEP_CAPACITY),
        ) {
            let mut sweep = SweepBuffer::new();
            for (r, a) in ranges.iter().zip(angles.iter()) {
                sweep.push(Reading { neck_angle_rad: *a, range_m: *r, pose: Pose::default() }).unwrap();
            }
            let mut hits = HitBuffer::new();
            let regions = filter_constant_depth(&sweep, &RcdParams::from_config(&RobotConfig::default()), &mut hits);
            proptest::prop_assert!(hits.len() <= sweep.len());
            proptest::prop_assert!(regions <= hits.len());
            for h in &hits {
                proptest::prop_assert!(h.range_m.is_finite() && h.range_m >= 0.0);
            }
            let geometry = GridGeometry::new(50, 50, 0.1).unwrap();
            let mut grid = Grid300::new(geometry).unwrap();
            mark_hits(&mut grid, &hits, 0.2, 3);
        }
    }
}
