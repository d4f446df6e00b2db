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
    ///    planning and the physical radius. (Measured, `cargo test -p twil-core --lib
    ///    tracking_at_the_bound -- --nocapture`: past a 29.5° vertex the centre stays within
    ///    0.026 / 0.040 / 0.059 m of the path at 0.1 / 0.2 / 0.364 m/s, inside the 0.065 m
    ///    below.)
    /// 3. *Stopping within what the sonar saw.* Each prefix ends at most `sonar range −
    ///    planning radius` from where its sweep was taken (1.1 m at 1.5 m; a moving pass's
    ///    prefix is shortened by how far the robot has gone since, `Mission` `stale_m`), so
    ///    the body stops short of anything unseen if it overshoots the prefix's end by less
    ///    than the 0.10 m margin minus half a 0.05 m cell's diagonal, 0.065 m. The reference
    ///    stops dead at the end; the wheels follow within about one control period plus the
    ///    motor time constant, 0.05 + 0.10 s, so `v ≤ 0.065 / 0.15` = **0.43 m/s** (measured
    ///    overshoot past the end: 0.015 / 0.030 / 0.059 m at 0.1 / 0.2 / 0.364 m/s).
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

    /// The smallest planning radius (`.par` radius, `SetParams`) this robot's sonar allows,
    /// metres: **0.31 m** for the default robot.
    ///
    /// The seed's prefix rule lets the centre go `sonar range − planning radius` towards an
    /// obstacle the sweep did not reach (just beyond the range, from the sonar). The sonar then
    /// stands `planning radius` from it, and must still hear it at the next sweep: echoes nearer
    /// than `sonar_min_range_m` (0.26 m, the transducer still ringing) read as "nothing". So
    /// `radius ≥ sonar_min_range_m + one 0.05 m cell` for the overshoot and the grid. With a
    /// 0.2 m radius the robot stopped with its sonar 0.07 m from the corridor's first wall,
    /// heard nothing there, planned through it and hit it.
    pub const fn min_safe_planning_radius_m(&self) -> f32 {
        let r = self.sonar_min_range_m + CELL_M;
        if r.is_finite() && r > 0.0 {
            r
        } else {
            CELL_M
        }
    }

    /// The largest planning radius (`.par` radius, `SetParams`) this robot's sonar covers,
    /// metres: **1.1 m** for the default robot at its 1.5 m range.
    ///
    /// The seed's prefix rule keeps the path within `sonar range − planning radius` of the
    /// sweep, so that the body, grown by the radius, stays inside the swept circle. The robot
    /// must get somewhere between two sweeps: at least [`MIN_PREFIX_M`] = 0.4 m (eight cells)
    /// of prefix, so `radius ≤ sonar range − 0.4 m` (1.1 m at 1.5 m, 5.6 m at 6 m).
    pub const fn max_safe_planning_radius_m(&self) -> f32 {
        let r = self.sonar_range_m - MIN_PREFIX_M;
        let min = self.min_safe_planning_radius_m();
        if r.is_finite() && r > min {
            r
        } else {
            min
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

impl core::error::Error for LimitError {}

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

/// Check a planning radius: [`RobotConfig::min_safe_planning_radius_m`] to
/// [`RobotConfig::max_safe_planning_radius_m`].
pub fn check_planning_radius_m(robot: &RobotConfig, radius_m: f32) -> Result<(), LimitError> {
    let (min, max) = (
        robot.min_safe_planning_radius_m(),
        robot.max_safe_planning_radius_m(),
    );
    if radius_m.is_finite() && (min..=max).contains(&radius_m) {
        Ok(())
    } else {
        Err(LimitError {
            value: radius_m,
            min,
            min_inclusive: true,
            max,
        })
    }
}

#[cfg(test)]
mod tests {
    extern crate std;

    use super::*;
    use crate::geom::PointM;
    use crate::geom::Pose;
    use crate::math::{cos, sin};
    use crate::mission::{MissionConfig, Pilot};
    use crate::plant::Plant;

    #[test]
    fn the_default_robot_bounds() {
        let r = RobotConfig::DEFAULT;
        assert!((r.max_safe_speed_m_s() - 0.3645).abs() < 5e-4);
        assert!((r.min_safe_planning_radius_m() - 0.31).abs() < 1e-6);
        assert!((r.max_safe_planning_radius_m() - 1.1).abs() < 1e-6);
        let six = RobotConfig {
            sonar_range_m: 6.0,
            ..r
        };
        assert!((six.max_safe_planning_radius_m() - 5.6).abs() < 1e-6);
        // The seed's 0.2 m/s and the bundled worlds' radii pass.
        assert!(check_speed_m_s(&r, 0.2).is_ok());
        assert!(check_speed_m_s(&r, 0.25).is_ok());
        assert!(check_planning_radius_m(&r, 0.35).is_ok());
        assert!(check_planning_radius_m(&r, 0.4).is_ok());
        for bad in [0.0, -0.1, 0.37, 10.0, f32::NAN, f32::INFINITY] {
            let e = check_speed_m_s(&r, bad).unwrap_err();
            assert!(e.max > 0.36 && e.max < 0.37, "{bad}");
        }
        for bad in [0.0, 0.3, 1.2, f32::NAN] {
            assert!(check_planning_radius_m(&r, bad).is_err(), "{bad}");
        }
        // A nonsense robot refuses every speed instead of dividing by zero.
        let broken = RobotConfig {
            point_offset_m: 0.0,
            ..r
        };
        assert_eq!(broken.max_safe_speed_m_s(), 0.0);
        assert!(check_speed_m_s(&broken, 0.1).is_err());
    }

    /// Follow 2 m, a vertex that turns by just under 30° (no turn in place), 2 m more, at
    /// `speed_m_s` with the pilot and the simulated plant. Returns the largest distance of the
    /// true centre from the path, the overshoot past the end along the path, and the number of
    /// periods with a clamped voltage.
    fn follow_corner(speed_m_s: f32) -> (f32, f32, u32) {
        let config = MissionConfig {
            speed_m_s,
            ..MissionConfig::IDLE
        };
        let robot = config.robot;
        let turn = 29.5f32.to_radians();
        let path = [
            PointM::new(0.0, 0.0),
            PointM::new(2.0, 0.0),
            PointM::new(2.0 + 2.0 * cos(turn), 2.0 * sin(turn)),
        ];
        let mut pilot = Pilot::new(&config);
        pilot.follow(&path).unwrap();
        let mut plant = Plant::new(&robot, Pose::new(0.0, 0.0, 0.0));
        let (mut voltages, mut counts) = ((0.0, 0.0), plant.encoder_counts());
        let (mut worst_m, mut overshoot_m, mut saturated) = (0.0f32, 0.0f32, 0);
        let end = path[2];
        let (ux, uy) = (cos(turn), sin(turn));
        for _ in 0..((8.0 / speed_m_s + 6.0) / robot.controller_period_s) as u32 {
            plant.step(robot.controller_period_s, voltages.0, voltages.1);
            let now = plant.encoder_counts();
            let report = pilot.tick(
                now.0.wrapping_sub(counts.0),
                now.1.wrapping_sub(counts.1),
                robot.controller_period_s,
            );
            counts = now;
            voltages = (report.left_voltage_v, report.right_voltage_v);
            saturated += u32::from(report.saturated);
            let p = plant.pose().position();
            let d = distance_to_polyline(&path, p);
            worst_m = worst_m.max(d);
            overshoot_m = overshoot_m.max((p.x_m - end.x_m) * ux + (p.y_m - end.y_m) * uy);
        }
        (worst_m, overshoot_m, saturated)
    }

    fn distance_to_polyline(path: &[PointM], p: PointM) -> f32 {
        let mut best = f32::MAX;
        for w in path.windows(2) {
            let (a, b) = (w[0], w[1]);
            let (dx, dy) = (b.x_m - a.x_m, b.y_m - a.y_m);
            let t = (((p.x_m - a.x_m) * dx + (p.y_m - a.y_m) * dy) / (dx * dx + dy * dy))
                .clamp(0.0, 1.0);
            let (qx, qy) = (a.x_m + t * dx - p.x_m, a.y_m + t * dy - p.y_m);
            best = best.min(crate::math::hypot(qx, qy));
        }
        best
    }

    /// The measurements behind the bound (printed with `--nocapture`): up to the bound the
    /// centre stays well inside the 0.10 m margin and stops within the stopping slack.
    #[test]
    fn tracking_at_the_bound_stays_within_the_margin() {
        let bound = RobotConfig::DEFAULT.max_safe_speed_m_s();
        for v in [0.1, 0.2, bound, 0.5, 0.63] {
            let (worst_m, overshoot_m, saturated) = follow_corner(v);
            std::println!(
                "{v:.3} m/s: off the path {worst_m:.4} m, overshoot {overshoot_m:.4} m, \
                 {saturated} saturated periods"
            );
            if v <= bound {
                assert!(worst_m < stop_slack_m(), "{v}: {worst_m}");
                assert!(overshoot_m < stop_slack_m(), "{v}: {overshoot_m}");
            }
        }
    }
}
