//! The 50 ms controller of seed `twlckin.cpp`: odometry, reference model, linearizing feedback
//! on a point ahead of the axle, one PID per wheel speed, saturation with anti-windup.
//!
//! # The loop, once per period
//!
//! 1. **Odometry** ([`Odometry`]): the encoder count deltas since the last step give each
//!    wheel's travel; the pose (axle midpoint, heading) advances along the circular arc they
//!    describe (seed `dr()`). Measured wheel speeds are the deltas divided by the period.
//! 2. **Control point**: `y = (x + d cos θ, y + d sin θ)` with `d =`
//!    [`RobotConfig::point_offset_m`]. Controlling a point *ahead* of the axle instead of the
//!    axle itself makes the kinematics invertible (a differential drive cannot move its axle
//!    sideways, but that point can move in any direction).
//! 3. **Reference model** (seed `g()`): a first-order filter `ẏm = (p − ym) / τ` of the
//!    reference `p` given by the caller, with `τ =`
//!    [`RobotConfig::reference_time_constant_s`] (seed `ALPHA0 = 1/s`). It turns a jumping or
//!    piecewise reference into a smooth one the robot can follow. It is integrated exactly
//!    (`ym += (p − ym)(1 − e^{−Δt/τ})`).
//! 4. **Linearizing feedback** (seed `invbeta()`): the desired control point velocity is
//!    `v = ẏm + k (ym − y)` (`k =` [`RobotConfig::tracking_gain_1_s`]); inverting
//!    `ẏ = [cos θ, −d sin θ; sin θ, d cos θ] (u, ω)` gives the forward speed `u` and turn rate
//!    `ω`, and `(u ± bω)/r` the right/left wheel speed references. With perfect wheel tracking
//!    the control point error then obeys `ė = −k e`: linear, decoupled, exponentially stable.
//!    When a reference asks for more than the motors can do, both wheel references are scaled
//!    by the same factor so the robot keeps the commanded direction instead of the sum.
//! 5. **Wheel PIDs** (seed gains 2.5 / 3.25 / 0.05): error = wheel speed reference − measured
//!    speed, in rad/s; output in volts, clamped to ±[`RobotConfig::max_voltage_v`] (11.7 V).
//!    Anti-windup by conditional integration: while the output is clamped and the error pushes
//!    further into the limit, the integral is frozen.
//! 6. **Overrun**: the caller says how long it really was since the last step; more than the
//!    period plus [`OVERRUN_TOLERANCE_S`] sets [`ControlOutput::overrun`] (the seed stopped the
//!    robot on an overrun; here the shell decides).
//!
//! Everything is `f32` through [`crate::math`], so host and MCU compute the same numbers.
//!
//! ```
//! use twil_core::control::{ControlInput, Controller, Pose};
//! use twil_core::geom::PointM;
//! use twil_core::robot::RobotConfig;
//!
//! let config = RobotConfig::default();
//! let mut controller = Controller::new(&config, Pose::new(1.0, 1.0, 0.0));
//! let out = controller.step(ControlInput {
//!     reference: PointM::new(2.0, 1.0),
//!     encoder_left_delta_counts: 0,
//!     encoder_right_delta_counts: 0,
//!     elapsed_since_last_step_s: 0.05,
//! });
//! // Ahead: both wheels forward, equally.
//! assert!(out.left_voltage_v > 0.0 && (out.left_voltage_v - out.right_voltage_v).abs() < 1e-4);
//! assert!(!out.overrun);
//! ```

use serde::{Deserialize, Serialize};

use crate::geom::PointM;
use crate::math::{abs, cos, exp, ln, sin, wrap_angle_rad};
use crate::robot::RobotConfig;

/// Slack on the period before a step counts as an overrun, seconds (timer jitter).
pub const OVERRUN_TOLERANCE_S: f32 = 0.0005;

/// Fraction of the motors' top speed (gain × saturation voltage) the wheel speed references
/// are limited to, so a wheel PID keeps some voltage headroom.
pub const WHEEL_SPEED_HEADROOM: f32 = 0.9;

// Pose lives in `geom` (sonar and robot use it without depending on the controller: issue 27
// removed the file cycle control -> robot -> sonar -> control); re-exported for the callers
// that know it here.
pub use crate::geom::Pose;

/// Dead reckoning from wheel encoder count deltas (seed `dr()`).
#[derive(Clone, Debug, PartialEq)]
pub struct Odometry {
    pose: Pose,
    metres_per_count: f32,
    half_axle_m: f32,
}

impl Odometry {
    /// Odometry starting at `initial_pose` (a non-finite pose starts at the origin).
    pub fn new(config: &RobotConfig, initial_pose: Pose) -> Self {
        Self {
            pose: if initial_pose.is_finite() {
                Pose::new(initial_pose.x_m, initial_pose.y_m, initial_pose.heading_rad)
            } else {
                Pose::default()
            },
            metres_per_count: config.rad_per_count() * config.wheel_radius_m,
            half_axle_m: config.half_axle_m,
        }
    }

    /// The current estimate.
    pub fn pose(&self) -> Pose {
        self.pose
    }

    /// Replace the estimate (e.g. after an external fix).
    pub fn set_pose(&mut self, pose: Pose) {
        if pose.is_finite() {
            self.pose = Pose::new(pose.x_m, pose.y_m, pose.heading_rad);
        }
    }

    /// Advance by the counts each wheel turned since the last update (positive = forward) and
    /// return the new pose. The motion is taken as a circular arc: travel `Δs = (Δl + Δr)/2`,
    /// turn `Δθ = (Δr − Δl)/2b`, chord `Δs · sin(Δθ/2)/(Δθ/2)` along `θ + Δθ/2`, which is exact
    /// for constant wheel speeds over the interval. Any input is accepted; should the result not
    /// be finite (only with an invalid config), the pose is left unchanged.
    ///
    /// ```
    /// use twil_core::control::{Odometry, Pose};
    /// use twil_core::robot::RobotConfig;
    /// let c = RobotConfig::default();
    /// let mut odo = Odometry::new(&c, Pose::new(0.0, 0.0, 0.0));
    /// let one_rev = c.encoder_pulses_per_rev as i32;
    /// let p = odo.update(one_rev, one_rev);
    /// assert!((p.x_m - 2.0 * core::f32::consts::PI * c.wheel_radius_m).abs() < 1e-4);
    /// ```
    pub fn update(&mut self, left_delta_counts: i32, right_delta_counts: i32) -> Pose {
        let left_m = left_delta_counts as f32 * self.metres_per_count;
        let right_m = right_delta_counts as f32 * self.metres_per_count;
        let travel_m = 0.5 * (left_m + right_m);
        let turn_rad = (right_m - left_m) / (2.0 * self.half_axle_m);
        let half = 0.5 * turn_rad;
        let chord_m = travel_m * sin_over_x(half);
        let mid = self.pose.heading_rad + half;
        let next = Pose::new(
            self.pose.x_m + chord_m * cos(mid),
            self.pose.y_m + chord_m * sin(mid),
            self.pose.heading_rad + turn_rad,
        );
        if next.is_finite() {
            self.pose = next;
        }
        self.pose
    }
}

/// `sin(x)/x`, accurate to 1e-6 for `|x| < 0.5` by its series (micromath's `sin` has an
/// absolute error near 1e-3, which would be a 1 % error on the short chords of odometry), and
/// through [`sin`] beyond.
fn sin_over_x(x: f32) -> f32 {
    if abs(x) < 0.5 {
        let x2 = x * x;
        1.0 - x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0))
    } else {
        sin(x) / x
    }
}

/// A PID on one wheel's speed: rad/s in, volts out, with saturation and anti-windup.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct WheelPid {
    kp: f32,
    ki: f32,
    kd: f32,
    limit_v: f32,
    integral_rad: f32,
    previous_error_rad_s: Option<f32>,
}

impl WheelPid {
    /// [`WheelPid::new`], in `const` contexts.
    pub const fn idle(config: &RobotConfig) -> Self {
        Self {
            kp: config.pid_kp_v_per_rad_s,
            ki: config.pid_ki_v_per_rad,
            kd: config.pid_kd_v_s2_per_rad,
            limit_v: config.max_voltage_v,
            integral_rad: 0.0,
            previous_error_rad_s: None,
        }
    }

    /// A PID with the gains and saturation of `config`.
    pub fn new(config: &RobotConfig) -> Self {
        Self {
            kp: config.pid_kp_v_per_rad_s,
            ki: config.pid_ki_v_per_rad,
            kd: config.pid_kd_v_s2_per_rad,
            limit_v: config.max_voltage_v,
            integral_rad: 0.0,
            previous_error_rad_s: None,
        }
    }

    /// Forget the integral and the derivative memory.
    pub fn reset(&mut self) {
        self.integral_rad = 0.0;
        self.previous_error_rad_s = None;
    }

    /// One step: `error_rad_s` = reference − measured speed, over `dt_s`. Returns the voltage,
    /// within ±limit, and whether it was clamped. A non-finite error counts as 0; a
    /// non-positive or non-finite `dt_s` skips the integral and derivative terms.
    pub fn step(&mut self, error_rad_s: f32, dt_s: f32) -> (f32, bool) {
        let e = if error_rad_s.is_finite() {
            error_rad_s
        } else {
            0.0
        };
        let dt_ok = dt_s.is_finite() && dt_s > 0.0;
        let derivative = match (self.previous_error_rad_s, dt_ok) {
            (Some(prev), true) => (e - prev) / dt_s,
            _ => 0.0,
        };
        self.previous_error_rad_s = Some(e);
        let candidate = if dt_ok {
            self.integral_rad + e * dt_s
        } else {
            self.integral_rad
        };
        let unclamped = self.kp * e + self.ki * candidate + self.kd * derivative;
        let limit = self.limit_v;
        let pushes_out = (unclamped > limit && e > 0.0) || (unclamped < -limit && e < 0.0);
        if !pushes_out && candidate.is_finite() {
            self.integral_rad = candidate;
        }
        let out = self.kp * e + self.ki * self.integral_rad + self.kd * derivative;
        let out = if out.is_finite() { out } else { 0.0 };
        if out > limit {
            (limit, true)
        } else if out < -limit {
            (-limit, true)
        } else {
            (out, false)
        }
    }
}

/// What the controller needs each period.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ControlInput {
    /// Desired position of the control point, world (odometry) frame, metres.
    pub reference: PointM,
    /// Left encoder counts since the previous step (positive = forward).
    pub encoder_left_delta_counts: i32,
    /// Right encoder counts since the previous step (positive = forward).
    pub encoder_right_delta_counts: i32,
    /// Time really elapsed since the previous step, seconds (the period when on time).
    pub elapsed_since_last_step_s: f32,
}

/// What the controller decided this period.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ControlOutput {
    /// Left motor voltage, volts, within ±max.
    pub left_voltage_v: f32,
    /// Right motor voltage, volts, within ±max.
    pub right_voltage_v: f32,
    /// Odometry pose after this step's counts.
    pub pose: Pose,
    /// The control point of that pose.
    pub control_point: PointM,
    /// Reference model output used this step (where the control point should be now).
    pub reference_model: PointM,
    /// Left wheel speed reference, rad/s.
    pub left_speed_ref_rad_s: f32,
    /// Right wheel speed reference, rad/s.
    pub right_speed_ref_rad_s: f32,
    /// Left wheel speed measured from the counts, rad/s.
    pub left_speed_rad_s: f32,
    /// Right wheel speed measured from the counts, rad/s.
    pub right_speed_rad_s: f32,
    /// The step came late: more than period + [`OVERRUN_TOLERANCE_S`] since the previous one.
    pub overrun: bool,
    /// At least one voltage was clamped to the saturation.
    pub saturated: bool,
}

/// Seconds the first-order reference model needs to come within
/// [`RobotConfig::settle_tolerance`] (seed: 2 %) of a constant reference:
/// `τ · ln(1 / tolerance)`, 3.91 s for the default τ = 1 s. The closed loop needs a little more
/// (its own error decays at the tracking gain); add a period or two of margin, or check
/// [`ControlOutput`] distances.
///
/// ```
/// use twil_core::{control::settle_time_s, robot::RobotConfig};
/// let t = settle_time_s(&RobotConfig::default());
/// assert!((t - 3.912).abs() < 0.01);
/// ```
pub fn settle_time_s(config: &RobotConfig) -> f32 {
    let tol = config.settle_tolerance;
    let tau = config.reference_time_constant_s;
    if !(tol.is_finite() && tol > 0.0 && tol < 1.0 && tau.is_finite() && tau > 0.0) {
        return 0.0;
    }
    -tau * ln(tol)
}

/// The controller: odometry + reference model + linearizing feedback + two wheel PIDs.
#[derive(Clone, Debug, PartialEq)]
pub struct Controller {
    config: RobotConfig,
    odometry: Odometry,
    model: PointM,
    left_pid: WheelPid,
    right_pid: WheelPid,
    last: ControlOutput,
}

impl Controller {
    /// A controller at the origin, heading +x, holding there (`const`: the firmware keeps its
    /// pilot in a `static`).
    pub const fn at_origin(config: &RobotConfig) -> Self {
        let pose = Pose {
            x_m: 0.0,
            y_m: 0.0,
            heading_rad: 0.0,
        };
        let point = PointM {
            x_m: config.point_offset_m,
            y_m: 0.0,
        };

        Self {
            config: *config,
            odometry: Odometry {
                pose,
                metres_per_count: config.rad_per_count() * config.wheel_radius_m,
                half_axle_m: config.half_axle_m,
            },
            model: point,
            left_pid: WheelPid::idle(config),
            right_pid: WheelPid::idle(config),
            last: ControlOutput {
                left_voltage_v: 0.0,
                right_voltage_v: 0.0,
                pose,
                control_point: point,
                reference_model: point,
                left_speed_ref_rad_s: 0.0,
                right_speed_ref_rad_s: 0.0,
                left_speed_rad_s: 0.0,
                right_speed_rad_s: 0.0,
                overrun: false,
                saturated: false,
            },
        }
    }

    /// A controller whose odometry starts at `initial_pose` and whose reference model starts
    /// at that pose's control point (so a first reference equal to it means "stay").
    pub fn new(config: &RobotConfig, initial_pose: Pose) -> Self {
        let odometry = Odometry::new(config, initial_pose);
        let pose = odometry.pose();
        let point = pose.point_ahead(config.point_offset_m);
        Self {
            config: *config,
            odometry,
            model: point,
            left_pid: WheelPid::new(config),
            right_pid: WheelPid::new(config),
            last: ControlOutput {
                pose,
                control_point: point,
                reference_model: point,
                ..ControlOutput::default()
            },
        }
    }

    /// The config in use.
    pub fn config(&self) -> &RobotConfig {
        &self.config
    }

    /// Current odometry pose.
    pub fn pose(&self) -> Pose {
        self.odometry.pose()
    }

    /// Control point of the current odometry pose.
    pub fn control_point(&self) -> PointM {
        self.odometry.pose().point_ahead(self.config.point_offset_m)
    }

    /// Current reference model output.
    pub fn reference_model(&self) -> PointM {
        self.model
    }

    /// The output of the last [`step`](Self::step) (zero voltages before the first).
    pub fn last_output(&self) -> ControlOutput {
        self.last
    }

    /// Restart the reference model at `point` (typically the current control point before a
    /// new path, so the model does not carry over a lag). A non-finite point restarts it at
    /// the current control point.
    pub fn reset_reference(&mut self, point: PointM) {
        self.model = if point.is_finite() {
            point
        } else {
            self.control_point()
        };
    }

    /// Replace the odometry pose (an external fix); the PIDs keep their state.
    pub fn set_pose(&mut self, pose: Pose) {
        self.odometry.set_pose(pose);
    }

    /// One control period. Never panics: a non-finite reference acts as a hold for this step, a
    /// non-finite or absurd elapsed time uses the nominal period for the speeds.
    pub fn step(&mut self, input: ControlInput) -> ControlOutput {
        let m = self.measure(&input);
        let c = &self.config;
        let target = if input.reference.is_finite() {
            input.reference
        } else {
            self.model
        };
        let tau = c.reference_time_constant_s;
        let k = c.tracking_gain_1_s;
        let model_dx = (target.x_m - self.model.x_m) / tau;
        let model_dy = (target.y_m - self.model.y_m) / tau;
        let vx = model_dx + k * (self.model.x_m - m.point.x_m);
        let vy = model_dy + k * (self.model.y_m - m.point.y_m);

        let (s, co) = (sin(m.pose.heading_rad), cos(m.pose.heading_rad));
        let forward_m_s = co * vx + s * vy;
        let turn_rad_s = (-s * vx + co * vy) / c.point_offset_m;

        let used_model = self.model;
        let blend = 1.0 - exp(-m.dt_s / tau);
        let next = PointM::new(
            self.model.x_m + (target.x_m - self.model.x_m) * blend,
            self.model.y_m + (target.y_m - self.model.y_m) * blend,
        );
        if next.is_finite() {
            self.model = next;
        }
        self.drive(&m, forward_m_s, turn_rad_s, used_model)
    }

    /// One control period of the turn-in-place mode: the input's counts and elapsed time are
    /// used, its reference is ignored, and the robot turns on the spot towards `heading_rad`
    /// (turn rate = [`RobotConfig::turn_gain_1_s`] × heading error, at most
    /// [`RobotConfig::max_turn_rate_rad_s`], forward speed 0). The reference model follows
    /// the control point as it swings round, so [`step`](Self::step) can take over without a
    /// jump. Use it to face a new path before following it, so the
    /// sonar looks where the robot goes. A non-finite heading means "stop turning".
    ///
    /// ```
    /// use twil_core::control::{ControlInput, Controller, Pose};
    /// use twil_core::robot::RobotConfig;
    /// let mut ctl = Controller::new(&RobotConfig::default(), Pose::new(0.0, 0.0, 0.0));
    /// let out = ctl.step_turn(
    ///     ControlInput { elapsed_since_last_step_s: 0.05, ..Default::default() },
    ///     1.0,
    /// );
    /// assert!(out.right_voltage_v > 0.0 && out.left_voltage_v < 0.0); // counter-clockwise
    /// ```
    pub fn step_turn(&mut self, input: ControlInput, heading_rad: f32) -> ControlOutput {
        let m = self.measure(&input);
        let c = &self.config;
        let error = if heading_rad.is_finite() {
            wrap_angle_rad(heading_rad - m.pose.heading_rad)
        } else {
            0.0
        };
        let limit = c.max_turn_rate_rad_s;
        let mut turn_rad_s = c.turn_gain_1_s * error;
        if turn_rad_s > limit {
            turn_rad_s = limit;
        } else if turn_rad_s < -limit {
            turn_rad_s = -limit;
        }
        self.model = m.point;
        self.drive(&m, 0.0, turn_rad_s, m.point)
    }

    /// Heading error to `heading_rad` from the current odometry pose, wrapped to `(-π, π]`.
    pub fn heading_error_rad(&self, heading_rad: f32) -> f32 {
        wrap_angle_rad(heading_rad - self.odometry.pose().heading_rad)
    }

    /// Odometry and measured wheel speeds for one step.
    fn measure(&mut self, input: &ControlInput) -> Measured {
        let c = &self.config;
        let period = c.controller_period_s;
        let elapsed = input.elapsed_since_last_step_s;
        let overrun = elapsed.is_finite() && elapsed > period + OVERRUN_TOLERANCE_S;
        // Counts accumulate over the real interval; trust it when it is plausible.
        let dt_s = if elapsed.is_finite() && elapsed >= 0.5 * period && elapsed <= 20.0 * period {
            elapsed
        } else {
            period
        };
        let rad_per_count = c.rad_per_count();
        let left_speed_rad_s = input.encoder_left_delta_counts as f32 * rad_per_count / dt_s;
        let right_speed_rad_s = input.encoder_right_delta_counts as f32 * rad_per_count / dt_s;
        let pose = self.odometry.update(
            input.encoder_left_delta_counts,
            input.encoder_right_delta_counts,
        );
        Measured {
            dt_s,
            overrun,
            left_speed_rad_s,
            right_speed_rad_s,
            pose,
            point: pose.point_ahead(c.point_offset_m),
        }
    }

    /// Wheel speed references from a body velocity, limited to what the motors can do, then
    /// the wheel PIDs.
    fn drive(
        &mut self,
        m: &Measured,
        forward_m_s: f32,
        turn_rad_s: f32,
        reference_model: PointM,
    ) -> ControlOutput {
        let c = &self.config;
        let r = c.wheel_radius_m;
        let b = c.half_axle_m;
        let mut right_ref = (forward_m_s + b * turn_rad_s) / r;
        let mut left_ref = (forward_m_s - b * turn_rad_s) / r;
        let top = WHEEL_SPEED_HEADROOM * c.motor_gain_rad_s_per_v * c.max_voltage_v;
        let biggest = if abs(right_ref) > abs(left_ref) {
            abs(right_ref)
        } else {
            abs(left_ref)
        };
        if biggest > top && top > 0.0 {
            let scale = top / biggest;
            right_ref *= scale;
            left_ref *= scale;
        }
        if !(right_ref.is_finite() && left_ref.is_finite()) {
            right_ref = 0.0;
            left_ref = 0.0;
        }
        let (right_v, right_sat) = self.right_pid.step(right_ref - m.right_speed_rad_s, m.dt_s);
        let (left_v, left_sat) = self.left_pid.step(left_ref - m.left_speed_rad_s, m.dt_s);
        self.last = ControlOutput {
            left_voltage_v: left_v,
            right_voltage_v: right_v,
            pose: m.pose,
            control_point: m.point,
            reference_model,
            left_speed_ref_rad_s: left_ref,
            right_speed_ref_rad_s: right_ref,
            left_speed_rad_s: m.left_speed_rad_s,
            right_speed_rad_s: m.right_speed_rad_s,
            overrun: m.overrun,
            saturated: left_sat || right_sat,
        };
        self.last
    }
}

/// What [`Controller::measure`] found.
struct Measured {
    dt_s: f32,
    overrun: bool,
    left_speed_rad_s: f32,
    right_speed_rad_s: f32,
    pose: Pose,
    point: PointM,
}

#[cfg(test)]
mod tests;
