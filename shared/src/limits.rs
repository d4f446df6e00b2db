//! Safe mission parameters: the fastest cruise speed and the planning radii the robot model
//! can be trusted with, derived from the controller, the motors and the sonar.
//!
//! Every way a speed or a radius enters a mission goes through here: the `.par` reader
//! ([`crate::world::parse_par`]), [`crate::mission::MissionConfig::validate`] (so `SetMission`
//! over the link answers `BadMission` naming the speed field) and the host's command lines.
//! Values beyond the bounds are **refused**, never clamped: a mission that silently drives
//! slower than its file says would hide the mistake.
//!
//! ```
//! use twil_core::robot::RobotConfig;
//! let v = RobotConfig::DEFAULT.max_safe_speed_m_s();
//! assert!((v - 0.364).abs() < 0.001);
//! assert!(twil_core::limits::check_speed_m_s(&RobotConfig::DEFAULT, 0.2).is_ok());
//! assert!(twil_core::limits::check_speed_m_s(&RobotConfig::DEFAULT, 0.4).is_err());
//! ```

use crate::robot::{RobotConfig, PLANNING_MARGIN_M};

/// Largest change of direction the trajectory supplier takes without stopping to turn in
/// place, degrees (`MissionConfig::turn_in_place_above_rad`, 30°; larger turns are done
/// standing and cost no speed).
pub const SMOOTH_TURN_MAX_DEG: f32 = 30.0;

/// `sin(SMOOTH_TURN_MAX_DEG)`, written out so the bound is a `const fn`.
const SIN_SMOOTH_TURN_MAX: f32 = 0.5;

/// Fraction of the motors' top speed the controller lets a wheel reference reach
/// (`control::WHEEL_SPEED_HEADROOM`).
const WHEEL_HEADROOM: f32 = crate::control::WHEEL_SPEED_HEADROOM;

/// Smallest planning radius accepted, metres: the physical radius is the planning radius
/// minus [`PLANNING_MARGIN_M`], so below the margin the body would be a point.
pub const MIN_PLANNING_RADIUS_M: f32 = PLANNING_MARGIN_M;

impl RobotConfig {
    /// The fastest cruise speed (`.par` speed, `MissionSetup::speed_m_s`) this robot tracks
    /// safely, m/s. **0.364 m/s** for [`RobotConfig::DEFAULT`].
    ///
    /// Derivation (numbers for the default robot):
    ///
    /// 1. *Motors.* A wheel turns at most `K·V_max` = 0.8 rad/s/V × 11.7 V = 9.36 rad/s, i.e.
    ///    `r·K·V_max` = 0.702 m/s at the rim; the controller caps wheel references at 90 % of
    ///    that ([`crate::control::WHEEL_SPEED_HEADROOM`]) so the wheel PIDs keep voltage to
    ///    correct errors: `v_cap` = **0.632 m/s**.
    /// 2. *Steering headroom (tracking).* The controller steers a point `d` = 0.15 m ahead of
    ///    the axle. Where the path turns by `α` without a turn in place (any vertex up to
    ///    [`SMOOTH_TURN_MAX_DEG`] = 30°), that point's velocity turns by `α` at once and the
    ///    heading follows at `ω ≈ v·sin α / d`; the outer wheel then runs at `v + b·ω =
    ///    v·(1 + b·sin α / d)` with `b` = 0.22 m the half axle: 1.73·v. Above
    ///    `v_cap / (1 + b·sin α / d)` = 0.632 / 1.733 = **0.364 m/s** the outer wheel saturates
    ///    at every such vertex; the controller then scales both wheels down, the robot falls
    ///    behind its reference and cuts the next corner by more than the 0.10 m between the
    ///    planning and the physical radius. (Measured, `limits` tests: at 0.364 m/s a 30°
    ///    vertex stays inside the cap and the centre stays within 0.03 m of the path.)
    /// 3. *Stopping within what the sonar saw.* Each prefix ends at most `sonar range −
    ///    planning radius` from where its sweep was taken (1.1 m at 1.5 m; a moving pass's
    ///    prefix is shortened by how far the robot has gone since, `Mission` `stale_m`), so
    ///    the body stops short of anything unseen if it overshoots the prefix's end by less
    ///    than the 0.10 m margin minus half a 0.05 m cell's diagonal, 0.065 m. The reference
    ///    stops dead at the end; the wheels follow within about one control period plus the
    ///    motor time constant, 0.05 + 0.10 s, so `v ≤ 0.065 / 0.15` = **0.43 m/s** (measured
    ///    overshoot: 0.008 m at 0.2 m/s).
    ///
    /// The bound is the smallest of the three: `min(0.632, 0.364, 0.43)` = 0.364 m/s. The sweep
    /// time does not enter it: stop mode sweeps standing, and continuous mode's prefix rule
    /// discounts the distance travelled during a pass (3.8 s per ±95° pass: above
    /// `(1.5 − 0.4) / (3.78 + 0.05)` = 0.29 m/s a pass leaves no prefix through unseen space,
    /// so continuous mode stops more often but stays safe).
    ///
    /// An invalid config gives 0 (refuse every speed).
    pub const fn max_safe_speed_m_s(&self) -> f32 {
        let v_top = self.wheel_radius_m * self.motor_gain_rad_s_per_v * self.max_voltage_v;
        let v_cap = WHEEL_HEADROOM * v_top;
        let steering = 1.0 + self.half_axle_m * SIN_SMOOTH_TURN_MAX / self.point_offset_m;
        let v_track = v_cap / steering;
        let lag_s = self.controller_period_s + self.motor_time_constant_s;
        let v_stop = stop_slack_m() / lag_s;
        let v = min(v_cap, min(v_track, v_stop));
        if v.is_finite() && v > 0.0 {
            v
        } else {
            0.0
        }
    }

    /// The largest planning radius (`.par` radius, `SetParams`) this robot's sonar covers,
    /// metres: **1.1 m** for the default robot at its 1.5 m range.
    ///
    /// The seed's prefix rule keeps the path within `sonar range − planning radius` of the
    /// sweep, so that the body, grown by the radius, stays inside the swept circle. The robot
    /// must get somewhere between two sweeps: at least 0.4 m (eight 0.05 m cells) of prefix,
    /// so `radius ≤ sonar range − 0.4 m` (1.1 m at 1.5 m, 5.6 m at 6 m). Radii below
    /// [`MIN_PLANNING_RADIUS_M`] leave no body and are refused too.
    pub const fn max_safe_planning_radius_m(&self) -> f32 {
        let r = self.sonar_range_m - MIN_PREFIX_M;
        if r.is_finite() && r > MIN_PLANNING_RADIUS_M {
            r
        } else {
            MIN_PLANNING_RADIUS_M
        }
    }
}

/// Shortest prefix a sweep must allow, metres (see
/// [`RobotConfig::max_safe_planning_radius_m`]).
pub const MIN_PREFIX_M: f32 = 0.4;

/// Grid cell assumed by the stopping bound, metres (the seed's 0.05 m).
const CELL_M: f32 = 0.05;

/// What an overshoot may use of the planning margin: the margin minus half a cell's diagonal
/// (a grown obstacle's edge lies anywhere in its cell), metres.
const fn stop_slack_m() -> f32 {
    PLANNING_MARGIN_M - 0.5 * core::f32::consts::SQRT_2 * CELL_M
}

const fn min(a: f32, b: f32) -> f32 {
    if a < b {
        a
    } else {
        b
    }
}

/// A speed or radius the robot cannot be trusted with.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LimitError {
    /// The value refused.
    pub value: f32,
    /// Smallest value accepted.
    pub min: f32,
    /// `min` itself is accepted (radii) or only values above it (speeds).
    pub min_inclusive: bool,
    /// Largest value accepted (inclusive).
    pub max: f32,
}

impl core::fmt::Display for LimitError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "{} is outside {} {:.3} to {:.3} (the safe bound of this robot)",
            self.value,
            if self.min_inclusive { "from" } else { "above" },
            self.min,
            self.max
        )
    }
}

/// Check a cruise speed: above 0 and at most [`RobotConfig::max_safe_speed_m_s`].
pub fn check_speed_m_s(robot: &RobotConfig, speed_m_s: f32) -> Result<(), LimitError> {
    let max = robot.max_safe_speed_m_s();
    if speed_m_s.is_finite() && speed_m_s > 0.0 && speed_m_s <= max {
        Ok(())
    } else {
        Err(LimitError {
            value: speed_m_s,
            min: 0.0,
            min_inclusive: false,
            max,
        })
    }
}

/// Check a planning radius: [`MIN_PLANNING_RADIUS_M`] to
/// [`RobotConfig::max_safe_planning_radius_m`].
pub fn check_planning_radius_m(robot: &RobotConfig, radius_m: f32) -> Result<(), LimitError> {
    let max = robot.max_safe_planning_radius_m();
    if radius_m.is_finite() && (MIN_PLANNING_RADIUS_M..=max).contains(&radius_m) {
        Ok(())
    } else {
        Err(LimitError {
            value: radius_m,
            min: MIN_PLANNING_RADIUS_M,
            min_inclusive: true,
            max,
        })
    }
}
