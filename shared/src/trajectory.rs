//! Trajectory supplier: turns the kept path prefix into one reference point per controller
//! period (seed `ft.c` + `path()` of `twlckin.cpp`).
//!
//! ## What it does
//!
//! 1. [`FrameTransform`] carries points from the world frame (the map, metres) to the odometry
//!    frame (the frame the controller's dead reckoning works in). The seed put the odometry
//!    origin at the robot's initial pose (`pto_ctrl`: translate by the initial position, rotate
//!    by minus the initial heading); [`FrameTransform::new`] does the same.
//! 2. [`TrajectorySupplier::start`] copies the prefix (transformed) and starts a constant-speed
//!    profile at `speed_m_s`. Each call to [`TrajectorySupplier::tick`] advances the clock by one
//!    period and returns a [`Supply`]: the point of the path where the robot should be at that
//!    instant and the direction of travel there.
//!
//!    The seed's `path()` walked the vertices and handed out the *vertex* nearest in time,
//!    which was fine because its BFS paths had a vertex every 5 cm. Our planners merge collinear
//!    cells into long segments, so the supplier interpolates along the polyline instead: the
//!    point handed out is the path point at arc length `speed × t`, the nearest path point to
//!    where the robot should be.
//! 3. Sharp corners: at the start, and at every vertex where the direction of travel turns by
//!    more than [`SupplierConfig::turn_in_place_above_rad`], the profile pauses and turns the
//!    reference direction in place at `turn_rate_rad_s`. The mission puts the controller's
//!    reference (a point ahead of the axle) at `point + offset × direction`, so a pure turn of
//!    the direction rotates the robot about its centre instead of swinging the centre out by the
//!    control-point offset.
//! 4. When the last point is reached, [`SupplyEvent::EndOfTrajectory`] is emitted once (the
//!    seed's `sem_post(&sem_ft)`), the last point keeps being supplied (the robot holds), and
//!    after `settle_time_s` (the reference model's time to come within 2 %, seed
//!    `espera_robo_parar`) [`SupplyEvent::Settled`] is emitted once.
//!
//! No heap: the trajectory lives in a [`heapless::Vec`] of [`MAX_TRAJECTORY_POINTS`] points.
//!
//! ```
//! use twil_core::geom::PointM;
//! use twil_core::trajectory::{FrameTransform, SupplierConfig, SupplyEvent, TrajectorySupplier};
//!
//! let path = [PointM::new(1.0, 1.0), PointM::new(2.0, 1.0)];
//! let frame = FrameTransform::identity();
//! let config = SupplierConfig { speed_m_s: 0.5, settle_time_s: 1.0, ..SupplierConfig::default() };
//! let mut supplier = TrajectorySupplier::new();
//! supplier.start(&path, &frame, 0.0, &config).unwrap();
//! let mut ended_at = None;
//! for n in 1..=100 {
//!     let s = supplier.tick(0.05);
//!     if s.event == Some(SupplyEvent::EndOfTrajectory) {
//!         ended_at = Some(n);
//!     }
//! }
//! // 1 m at 0.5 m/s: 2 s = 40 periods.
//! assert_eq!(ended_at, Some(40));
//! ```

use heapless::Vec;

use crate::geom::{polyline_length_m, PointM};
use crate::math::{abs, atan2, cos, hypot, sin, wrap_angle_rad};

/// Largest number of points a supplied trajectory can hold (the mission's prefix capacity,
/// `mission::MISSION_PATH_POINTS`: 8 KiB).
pub const MAX_TRAJECTORY_POINTS: usize = 1024;

/// Segments shorter than this are skipped (they have no reliable direction), metres.
pub const MIN_SEGMENT_M: f32 = 1.0e-3;

/// The rigid transform between the world frame and the odometry frame: the odometry frame's
/// origin and heading, expressed in the world frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameTransform {
    origin: PointM,
    heading_rad: f32,
    cos_h: f32,
    sin_h: f32,
}

impl FrameTransform {
    /// The odometry frame whose origin is `origin` (world metres) with its x axis along
    /// `heading_rad` (world, counter-clockwise from +x). Non-finite inputs give the identity.
    pub fn new(origin: PointM, heading_rad: f32) -> Self {
        if !origin.is_finite() || !heading_rad.is_finite() {
            return Self::identity();
        }
        let heading_rad = wrap_angle_rad(heading_rad);
        Self {
            origin,
            heading_rad,
            cos_h: cos(heading_rad),
            sin_h: sin(heading_rad),
        }
    }

    /// Odometry frame = world frame.
    pub const fn identity() -> Self {
        Self {
            origin: PointM::new(0.0, 0.0),
            heading_rad: 0.0,
            cos_h: 1.0,
            sin_h: 0.0,
        }
    }

    /// A world point in the odometry frame (seed `pto_ctrl`).
    pub fn world_to_odom(&self, p: PointM) -> PointM {
        let dx = p.x_m - self.origin.x_m;
        let dy = p.y_m - self.origin.y_m;
        PointM::new(
            self.cos_h * dx + self.sin_h * dy,
            -self.sin_h * dx + self.cos_h * dy,
        )
    }

    /// An odometry-frame point in the world frame (inverse of [`Self::world_to_odom`]).
    pub fn odom_to_world(&self, p: PointM) -> PointM {
        PointM::new(
            self.origin.x_m + self.cos_h * p.x_m - self.sin_h * p.y_m,
            self.origin.y_m + self.sin_h * p.x_m + self.cos_h * p.y_m,
        )
    }

    /// A world heading in the odometry frame, wrapped to `(-π, π]`.
    pub fn heading_world_to_odom(&self, heading_rad: f32) -> f32 {
        wrap_angle_rad(heading_rad - self.heading_rad)
    }

    /// An odometry heading in the world frame, wrapped to `(-π, π]`.
    pub fn heading_odom_to_world(&self, heading_rad: f32) -> f32 {
        wrap_angle_rad(heading_rad + self.heading_rad)
    }
}

/// How the supplier times a trajectory.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SupplierConfig {
    /// Cruise speed along the path, metres per second (the `.par` speed).
    pub speed_m_s: f32,
    /// Turn rate of the reference direction when turning in place, radians per second.
    pub turn_rate_rad_s: f32,
    /// A change of direction larger than this (at the start or at a vertex) is done as a turn
    /// in place before moving on, radians.
    pub turn_in_place_above_rad: f32,
    /// Time to hold the last point after the end before [`SupplyEvent::Settled`], seconds.
    pub settle_time_s: f32,
}

impl Default for SupplierConfig {
    /// 0.2 m/s, 0.8 rad/s turns above 30°, 4 s settle (four time constants of a 1 s reference
    /// model: within 2 %).
    fn default() -> Self {
        Self {
            speed_m_s: 0.2,
            turn_rate_rad_s: 0.8,
            turn_in_place_above_rad: 30.0 * core::f32::consts::PI / 180.0,
            settle_time_s: 4.0,
        }
    }
}

/// Why a trajectory was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TrajectoryError {
    /// No points.
    Empty,
    /// More points than [`MAX_TRAJECTORY_POINTS`].
    TooLong {
        /// Points offered.
        points: u32,
    },
    /// A point or a configuration value is not a finite number, or a speed/rate is not
    /// positive.
    NotFinite,
}

impl core::fmt::Display for TrajectoryError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            TrajectoryError::Empty => write!(f, "the trajectory has no points"),
            TrajectoryError::TooLong { points } => write!(
                f,
                "the trajectory has {points} points, more than {MAX_TRAJECTORY_POINTS}"
            ),
            TrajectoryError::NotFinite => write!(
                f,
                "a point or a configuration value is not a finite number, or a speed/rate is \
                 not positive"
            ),
        }
    }
}

impl core::error::Error for TrajectoryError {}

/// A one-off event of the supplier.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SupplyEvent {
    /// The last point of the trajectory has just been handed out (seed: the controller wakes
    /// the trajectory supplier).
    EndOfTrajectory,
    /// The settle time after the end has elapsed: the robot is still and a new sweep may start.
    Settled,
}

/// What the supplier hands the controller for one period.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Supply {
    /// Where the robot's centre should be now, odometry frame.
    pub point: PointM,
    /// Direction of travel there, odometry frame, radians.
    pub heading_rad: f32,
    /// `true` while turning in place (the point does not move).
    pub turning: bool,
    /// Speed of the point along `heading_rad` this period, m/s (0 unless moving).
    pub speed_m_s: f32,
    /// Signed turn rate of `heading_rad` this period, rad/s (0 unless turning in place).
    pub turn_rate_rad_s: f32,
    /// An event that happened during this period.
    pub event: Option<SupplyEvent>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Phase {
    Idle,
    /// Turning in place before segment `segment` (heading in the odometry frame).
    Turning,
    Moving,
    Settling {
        left_s: f32,
    },
    Done,
}

/// The trajectory supplier (seed `ft()` and `path()`): one reference per period along a
/// prefix, at constant speed.
#[derive(Clone, Debug)]
pub struct TrajectorySupplier {
    points: Vec<PointM, MAX_TRAJECTORY_POINTS>,
    config: SupplierConfig,
    phase: Phase,
    /// Index of the segment being followed (from `points[segment]` to `points[segment + 1]`).
    segment: usize,
    /// Distance travelled along the current segment, metres.
    along_m: f32,
    /// Reference direction, odometry frame.
    heading_rad: f32,
    /// Time since start, seconds.
    elapsed_s: f32,
}

impl Default for TrajectorySupplier {
    fn default() -> Self {
        Self::new()
    }
}

impl TrajectorySupplier {
    /// An idle supplier (no trajectory: [`Self::tick`] supplies the origin with no event).
    pub const fn new() -> Self {
        Self {
            points: Vec::new(),
            config: SupplierConfig {
                speed_m_s: 0.2,
                turn_rate_rad_s: 0.8,
                turn_in_place_above_rad: core::f32::consts::FRAC_PI_6,
                settle_time_s: 4.0,
            },
            phase: Phase::Idle,
            segment: 0,
            along_m: 0.0,
            heading_rad: 0.0,
            elapsed_s: 0.0,
        }
    }

    /// Start supplying `prefix_world` (world metres), carried into the odometry frame by
    /// `frame`. `heading_odom_rad` is the robot's current heading in the odometry frame: if the
    /// first segment points elsewhere by more than the turn threshold, the supplier first turns
    /// in place. A one-point prefix ends at once (after any settle time).
    ///
    /// On error the supplier is left idle-safe: its previous trajectory is kept unchanged.
    pub fn start(
        &mut self,
        prefix_world: &[PointM],
        frame: &FrameTransform,
        heading_odom_rad: f32,
        config: &SupplierConfig,
    ) -> Result<(), TrajectoryError> {
        if prefix_world.is_empty() {
            return Err(TrajectoryError::Empty);
        }
        if prefix_world.len() > MAX_TRAJECTORY_POINTS {
            return Err(TrajectoryError::TooLong {
                points: prefix_world.len() as u32,
            });
        }
        let config_ok = config.speed_m_s.is_finite()
            && config.speed_m_s > 0.0
            && config.turn_rate_rad_s.is_finite()
            && config.turn_rate_rad_s > 0.0
            && config.turn_in_place_above_rad.is_finite()
            && config.settle_time_s.is_finite()
            && config.settle_time_s >= 0.0;
        if !config_ok
            || !heading_odom_rad.is_finite()
            || prefix_world.iter().any(|p| !p.is_finite())
        {
            return Err(TrajectoryError::NotFinite);
        }
        self.points.clear();
        for p in prefix_world {
            // Length checked above.
            let _ = self.points.push(frame.world_to_odom(*p));
        }
        self.config = *config;
        self.segment = 0;
        self.along_m = 0.0;
        self.elapsed_s = 0.0;
        self.heading_rad = wrap_angle_rad(heading_odom_rad);
        self.phase = Phase::Moving;
        self.skip_short_segments();
        if self.segment + 1 >= self.points.len() {
            // Nothing to travel: end at the next tick.
            self.segment = self.points.len() - 1;
        } else {
            self.enter_segment();
        }
        Ok(())
    }

    /// Stop supplying: the supplier becomes idle and keeps supplying its last point.
    pub fn stop(&mut self) {
        if let Some(last) = self.current_point_opt() {
            self.points.clear();
            let _ = self.points.push(last);
        }
        self.segment = 0;
        self.along_m = 0.0;
        self.phase = Phase::Idle;
    }

    /// `true` from [`Self::start`] until the end of the trajectory (turning or moving).
    pub fn is_following(&self) -> bool {
        matches!(self.phase, Phase::Turning | Phase::Moving)
    }

    /// `true` after [`SupplyEvent::Settled`] (or when idle).
    pub fn is_done(&self) -> bool {
        matches!(self.phase, Phase::Done | Phase::Idle)
    }

    /// Index of the segment being followed: the robot is between vertex `segment` and
    /// `segment + 1` of the prefix. At the end, the index of the last vertex.
    pub fn segment(&self) -> usize {
        self.segment
    }

    /// Seconds since [`Self::start`].
    pub fn elapsed_s(&self) -> f32 {
        self.elapsed_s
    }

    /// The point being supplied now, odometry frame (the origin when idle and empty).
    pub fn current_point_odom(&self) -> PointM {
        self.current_point_opt().unwrap_or_default()
    }

    /// The trajectory being supplied, odometry frame.
    pub fn points(&self) -> &[PointM] {
        &self.points
    }

    /// Total duration at cruise speed of the path, seconds, without turns (for progress
    /// estimates).
    pub fn cruise_time_s(&self) -> f32 {
        polyline_length_m(&self.points) / self.config.speed_m_s
    }

    /// Advance by `period_s` (the controller period) and return the reference for this period.
    /// Non-finite or negative periods advance nothing.
    pub fn tick(&mut self, period_s: f32) -> Supply {
        let dt = if period_s.is_finite() && period_s > 0.0 {
            period_s
        } else {
            0.0
        };
        self.elapsed_s += dt;
        let mut event = None;
        let mut speed_m_s = 0.0;
        let mut turn_rate_rad_s = 0.0;
        match self.phase {
            Phase::Idle | Phase::Done => {}
            Phase::Turning => {
                let target = self.segment_heading(self.segment);
                let diff = wrap_angle_rad(target - self.heading_rad);
                let step = self.config.turn_rate_rad_s * dt;
                if abs(diff) <= step {
                    self.heading_rad = target;
                    self.phase = Phase::Moving;
                } else if diff > 0.0 {
                    self.heading_rad = wrap_angle_rad(self.heading_rad + step);
                    turn_rate_rad_s = self.config.turn_rate_rad_s;
                } else {
                    self.heading_rad = wrap_angle_rad(self.heading_rad - step);
                    turn_rate_rad_s = -self.config.turn_rate_rad_s;
                }
            }
            Phase::Moving => {
                speed_m_s = self.config.speed_m_s;
                self.along_m += self.config.speed_m_s * dt;
                loop {
                    if self.segment + 1 >= self.points.len() {
                        break;
                    }
                    let len = self.segment_length(self.segment);
                    // A micrometre of slack absorbs float noise in the accumulated distance.
                    if self.along_m + 1.0e-6 < len {
                        break;
                    }
                    self.along_m = (self.along_m - len).max(0.0);
                    self.segment += 1;
                    self.skip_short_segments();
                    if self.segment + 1 >= self.points.len() {
                        break;
                    }
                    if self.enter_segment() {
                        // Turning in place: the rest of this period is spent turning.
                        self.along_m = 0.0;
                        break;
                    }
                }
                if self.segment + 1 >= self.points.len() {
                    self.segment = self.points.len().saturating_sub(1);
                    self.along_m = 0.0;
                    event = Some(SupplyEvent::EndOfTrajectory);
                    speed_m_s = 0.0;
                    self.phase = Phase::Settling {
                        left_s: self.config.settle_time_s,
                    };
                }
            }
            Phase::Settling { left_s } => {
                let left_s = left_s - dt;
                if left_s <= 1.0e-6 {
                    self.phase = Phase::Done;
                    event = Some(SupplyEvent::Settled);
                } else {
                    self.phase = Phase::Settling { left_s };
                }
            }
        }
        Supply {
            point: self.current_point_opt().unwrap_or_default(),
            heading_rad: self.heading_rad,
            turning: self.phase == Phase::Turning,
            speed_m_s: if self.phase == Phase::Turning {
                0.0
            } else {
                speed_m_s
            },
            turn_rate_rad_s,
            event,
        }
    }

    /// Advance `segment` past segments too short to have a direction.
    fn skip_short_segments(&mut self) {
        while self.segment + 1 < self.points.len()
            && self.segment_length(self.segment) < MIN_SEGMENT_M
        {
            self.segment += 1;
        }
    }

    /// Set up the start of segment `self.segment`: turn in place first when its direction is
    /// too far from the current one. Returns `true` when turning.
    fn enter_segment(&mut self) -> bool {
        let target = self.segment_heading(self.segment);
        let diff = wrap_angle_rad(target - self.heading_rad);
        if abs(diff) > self.config.turn_in_place_above_rad {
            self.phase = Phase::Turning;
            true
        } else {
            self.heading_rad = target;
            self.phase = Phase::Moving;
            false
        }
    }

    fn segment_length(&self, i: usize) -> f32 {
        match (self.points.get(i), self.points.get(i + 1)) {
            (Some(a), Some(b)) => distance_m(*a, *b),
            _ => 0.0,
        }
    }

    fn segment_heading(&self, i: usize) -> f32 {
        match (self.points.get(i), self.points.get(i + 1)) {
            (Some(a), Some(b)) => atan2(b.y_m - a.y_m, b.x_m - a.x_m),
            _ => self.heading_rad,
        }
    }

    fn current_point_opt(&self) -> Option<PointM> {
        let a = *self.points.get(self.segment)?;
        let Some(b) = self.points.get(self.segment + 1) else {
            return Some(a);
        };
        let len = distance_m(a, *b);
        if len < MIN_SEGMENT_M {
            return Some(a);
        }
        let f = (self.along_m / len).clamp(0.0, 1.0);
        Some(PointM::new(
            a.x_m + (b.x_m - a.x_m) * f,
            a.y_m + (b.y_m - a.y_m) * f,
        ))
    }
}

/// Euclidean distance with [`hypot`] (segment lengths must be exact enough for the
/// constant-speed profile; the same sum as `PointM::distance_m`, which
/// [`polyline_length_m`] adds up).
fn distance_m(a: PointM, b: PointM) -> f32 {
    hypot(b.x_m - a.x_m, b.y_m - a.y_m)
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f32::consts::PI;

    fn cfg(speed: f32, settle: f32) -> SupplierConfig {
        SupplierConfig {
            speed_m_s: speed,
            settle_time_s: settle,
            ..SupplierConfig::default()
        }
    }

    fn close(a: PointM, b: PointM, tol: f32) -> bool {
        a.distance_m(b) <= tol
    }

    #[test]
    fn transform_round_trips_and_matches_the_seed_rotation() {
        let f = FrameTransform::new(PointM::new(1.5, 1.5), PI / 2.0);
        // A point 1 m north of the origin is 1 m straight ahead in the odometry frame.
        let p = f.world_to_odom(PointM::new(1.5, 2.5));
        assert!(close(p, PointM::new(1.0, 0.0), 1e-3), "{p:?}");
        let q = f.odom_to_world(PointM::new(0.3, -0.7));
        let back = f.world_to_odom(q);
        assert!(close(back, PointM::new(0.3, -0.7), 1e-4));
        assert!(abs(f.heading_world_to_odom(PI / 2.0)) < 1e-3);
        assert!(abs(f.heading_odom_to_world(0.0) - PI / 2.0) < 1e-3);
    }

    #[test]
    fn constant_speed_profile_interpolates_along_the_polyline() {
        let path = [
            PointM::new(0.0, 0.0),
            PointM::new(1.0, 0.0),
            PointM::new(1.0, 0.2),
        ];
        let mut s = TrajectorySupplier::new();
        s.start(&path, &FrameTransform::identity(), 0.0, &cfg(0.5, 0.0))
            .unwrap();
        // After 1 s: 0.5 m along the first segment.
        let mut last = None;
        for _ in 0..20 {
            last = Some(s.tick(0.05));
        }
        let last = last.unwrap();
        assert!(close(last.point, PointM::new(0.5, 0.0), 1e-3), "{last:?}");
        assert!(abs(last.heading_rad) < 1e-4);
        assert!(s.is_following());
    }

    #[test]
    fn sharp_corner_turns_in_place_then_continues() {
        let path = [
            PointM::new(0.0, 0.0),
            PointM::new(0.5, 0.0),
            PointM::new(0.5, 0.5),
        ];
        let config = SupplierConfig {
            speed_m_s: 0.5,
            turn_rate_rad_s: PI / 2.0,
            settle_time_s: 0.0,
            ..SupplierConfig::default()
        };
        let mut s = TrajectorySupplier::new();
        s.start(&path, &FrameTransform::identity(), 0.0, &config)
            .unwrap();
        let mut turning_ticks = 0;
        let mut end_tick = None;
        for n in 1..=200 {
            let out = s.tick(0.05);
            if out.turning {
                turning_ticks += 1;
                assert!(close(out.point, PointM::new(0.5, 0.0), 1e-4));
            }
            if out.event == Some(SupplyEvent::EndOfTrajectory) {
                end_tick = Some(n);
                assert!(close(out.point, PointM::new(0.5, 0.5), 1e-4));
                assert!(abs(out.heading_rad - PI / 2.0) < 1e-3);
            }
        }
        // 90° at 90°/s = 1 s = 20 periods of turning (the last one finishes it).
        assert!((19..=21).contains(&turning_ticks), "{turning_ticks}");
        // 1 m at 0.5 m/s = 40 periods + the turn.
        let end = end_tick.unwrap();
        assert!((59..=62).contains(&end), "{end}");
    }

    #[test]
    fn initial_heading_far_off_turns_first() {
        let path = [PointM::new(0.0, 0.0), PointM::new(-1.0, 0.0)];
        let mut s = TrajectorySupplier::new();
        s.start(&path, &FrameTransform::identity(), 0.0, &cfg(0.2, 0.0))
            .unwrap();
        let first = s.tick(0.05);
        assert!(first.turning);
        assert!(close(first.point, PointM::new(0.0, 0.0), 1e-6));
    }

    #[test]
    fn end_event_once_then_settled_after_settle_time() {
        let path = [PointM::new(0.0, 0.0), PointM::new(0.1, 0.0)];
        let mut s = TrajectorySupplier::new();
        s.start(&path, &FrameTransform::identity(), 0.0, &cfg(0.1, 1.0))
            .unwrap();
        let mut ends = 0;
        let mut settled_at = None;
        for n in 1..=100 {
            let out = s.tick(0.05);
            match out.event {
                Some(SupplyEvent::EndOfTrajectory) => {
                    ends += 1;
                    assert_eq!(n, 20);
                }
                Some(SupplyEvent::Settled) => settled_at = Some(n),
                None => {}
            }
        }
        assert_eq!(ends, 1);
        assert_eq!(settled_at, Some(40));
        assert!(s.is_done());
    }

    #[test]
    fn one_point_prefix_ends_at_once() {
        let mut s = TrajectorySupplier::new();
        s.start(
            &[PointM::new(2.0, 3.0)],
            &FrameTransform::identity(),
            1.0,
            &cfg(0.2, 0.0),
        )
        .unwrap();
        let out = s.tick(0.05);
        assert_eq!(out.event, Some(SupplyEvent::EndOfTrajectory));
        assert!(close(out.point, PointM::new(2.0, 3.0), 1e-6));
    }

    #[test]
    fn bad_inputs_are_errors_and_keep_the_old_trajectory() {
        let mut s = TrajectorySupplier::new();
        let good = [PointM::new(0.0, 0.0), PointM::new(1.0, 0.0)];
        s.start(&good, &FrameTransform::identity(), 0.0, &cfg(0.2, 0.0))
            .unwrap();
        assert_eq!(
            s.start(&[], &FrameTransform::identity(), 0.0, &cfg(0.2, 0.0)),
            Err(TrajectoryError::Empty)
        );
        let nan = [PointM::new(f32::NAN, 0.0), PointM::new(1.0, 0.0)];
        assert_eq!(
            s.start(&nan, &FrameTransform::identity(), 0.0, &cfg(0.2, 0.0)),
            Err(TrajectoryError::NotFinite)
        );
        assert_eq!(
            s.start(&good, &FrameTransform::identity(), 0.0, &cfg(0.0, 0.0)),
            Err(TrajectoryError::NotFinite)
        );
        assert_eq!(s.points(), &good);
        // NaN periods advance nothing.
        let before = s.tick(0.0).point;
        let after = s.tick(f32::NAN).point;
        assert_eq!(before, after);
    }

    #[test]
    fn points_are_supplied_in_the_odometry_frame() {
        let frame = FrameTransform::new(PointM::new(1.0, 1.0), PI / 2.0);
        let path = [PointM::new(1.0, 1.0), PointM::new(1.0, 3.0)];
        let mut s = TrajectorySupplier::new();
        s.start(&path, &frame, 0.0, &cfg(1.0, 0.0)).unwrap();
        let out = s.tick(1.0);
        // 1 m straight ahead of the odometry origin.
        assert!(close(out.point, PointM::new(1.0, 0.0), 1e-3), "{out:?}");
        assert!(abs(out.heading_rad) < 1e-3);
    }

    mod props {
        extern crate std;
        use super::*;
        use proptest::prelude::*;

        fn seg_dist(p: PointM, a: PointM, b: PointM) -> f32 {
            crate::geom::distance_to_segment_m(p, a, b)
        }

        proptest! {
            /// Every supplied point lies on the polyline, the end comes exactly once and no
            /// later than the cruise time plus the turns, and the last point is the end.
            #[test]
            fn supplied_points_stay_on_the_path(
                raw in prop::collection::vec((-5.0f32..5.0, -5.0f32..5.0), 1..12),
                heading in -3.2f32..3.2,
                speed in 0.05f32..1.0,
            ) {
                let path: std::vec::Vec<PointM> =
                    raw.iter().map(|&(x, y)| PointM::new(x, y)).collect();
                let config = SupplierConfig { speed_m_s: speed, settle_time_s: 0.5, ..SupplierConfig::default() };
                let mut s = TrajectorySupplier::new();
                s.start(&path, &FrameTransform::identity(), heading, &config).unwrap();
                let length = polyline_length_m(&path);
                let turns = path.len() as f32 * core::f32::consts::PI / config.turn_rate_rad_s;
                let max_ticks = ((length / speed + turns) / 0.05) as usize + path.len() * 2 + 20;
                let mut ends = 0;
                let mut settled = 0;
                for _ in 0..max_ticks + 20 {
                    let out = s.tick(0.05);
                    let on_path = if path.len() == 1 {
                        out.point.distance_m(path[0])
                    } else {
                        path.windows(2).map(|w| seg_dist(out.point, w[0], w[1])).fold(f32::INFINITY, f32::min)
                    };
                    prop_assert!(on_path < 1e-3, "{:?} off the path by {}", out.point, on_path);
                    match out.event {
                        Some(SupplyEvent::EndOfTrajectory) => {
                            ends += 1;
                            prop_assert!(distance_m(out.point, *path.last().unwrap()) < 1e-3);
                        }
                        Some(SupplyEvent::Settled) => settled += 1,
                        None => {}
                    }
                }
                prop_assert_eq!(ends, 1);
                prop_assert_eq!(settled, 1);
            }
        }
    }
}
