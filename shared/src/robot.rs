//! The robot's physical constants: geometry, motors, encoders, controller gains and sonar.
//!
//! Seed 003 lists the controller (`twlckin.cpp`) but not the robot constants file it includes
//! (`twlparam.h`: wheel radius, axle, pulses per revolution). [`RobotConfig::default`] therefore
//! holds *plausible* Twil values, chosen to be consistent with what the seed does state (the
//! planning radius of its `.par` files, the 11.7 V saturation, the PID gains, the sonar
//! constants of `defs.h` and `sonar.cpp`). Every value is a field, so a real robot only needs a
//! different config; `docs/robot-model.md` explains each choice.
//!
//! A config read from a file or a command line must pass [`RobotConfig::validate`] before use:
//! the controller, the plant and the sonar code never panic on a bad config, but they only give
//! meaningful numbers for a valid one.
//!
//! ```
//! use twil_core::robot::RobotConfig;
//! let config = RobotConfig::default();
//! assert!(config.validate().is_ok());
//! assert!((config.physical_radius_m() - 0.30).abs() < 1e-6); // 0.40 m planning - 0.10 m
//! let bad = RobotConfig { sonar_range_m: 7.0, ..RobotConfig::default() };
//! let err = bad.validate().unwrap_err();
//! assert_eq!(err.field, "sonar_range_m");
//! ```

use core::fmt;

use serde::{Deserialize, Serialize};

/// Largest sonar range accepted, metres (seed `sonar.cpp` `DIST_MAX`: the echo wait is sized for
/// it, so farther echoes would spill into the next reading).
pub const SONAR_MAX_RANGE_LIMIT_M: f32 = 6.0;

/// Speed of sound used for time of flight, metres per second (seed `sonar.cpp`).
pub const SPEED_OF_SOUND_M_S: f32 = 343.2;

/// The seed's difference between the planning radius and the physical radius, metres
/// (`RAIO_REAL = raio - 0.10`): obstacles are grown by the planning radius, the body is 0.10 m
/// smaller, which is the safety margin.
pub const PLANNING_MARGIN_M: f32 = 0.10;

/// Most rays a simulated sonar cone may cast per reading.
pub const MAX_CONE_RAYS: u8 = 31;

/// Which neck positions a sweep reads.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SweepLayout {
    /// `2n + 1` readings from `−n` to `+n` steps: straight ahead and both ends read (105 for
    /// ±95°, 201 for ±180°).
    #[default]
    Symmetric,
    /// The seed's `sonar_rpc`: the neck goes `n` steps to one side and reads `2n` times,
    /// stepping after each reading, so the last position (`+n`) is never read: 104 readings
    /// from −93.6° to +91.8° for ±95°, 200 from −180° to +178.2° for ±180°.
    Seed,
}

/// Every constant of the robot model. Units are in the field names.
///
/// The pose of the robot is the midpoint of the wheel axle; the body is a disc of
/// [`physical_radius_m`](Self::physical_radius_m) centred there.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct RobotConfig {
    /// Radius the planner grows obstacles by, metres (the `.par` file's radius; seed 0.40).
    pub planning_radius_m: f32,
    /// Wheel radius, metres.
    pub wheel_radius_m: f32,
    /// Half the distance between the two wheel contact points, metres.
    pub half_axle_m: f32,
    /// Distance of the controlled point ahead of the axle midpoint, metres (must be > 0: the
    /// linearizing feedback divides by it).
    pub point_offset_m: f32,
    /// Encoder counts per wheel revolution (after gearing and quadrature).
    pub encoder_pulses_per_rev: u32,
    /// Steady-state wheel speed per volt, rad/s per V (first-order motor model).
    pub motor_gain_rad_s_per_v: f32,
    /// Motor + wheel mechanical time constant, seconds.
    pub motor_time_constant_s: f32,
    /// Motor voltage saturation, volts (seed: ±11.7 V).
    pub max_voltage_v: f32,
    /// Controller period, seconds (seed `ST = 0.05`).
    pub controller_period_s: f32,
    /// Wheel-speed PID proportional gain, V per rad/s (seed 2.5).
    pub pid_kp_v_per_rad_s: f32,
    /// Wheel-speed PID integral gain, V per rad (seed 3.25).
    pub pid_ki_v_per_rad: f32,
    /// Wheel-speed PID derivative gain, V·s² per rad (seed 0.05).
    pub pid_kd_v_s2_per_rad: f32,
    /// Time constant of the first-order reference model, seconds (seed `ALPHA0 = 1` 1/s).
    pub reference_time_constant_s: f32,
    /// Gain of the linearizing feedback on the control point error, 1/s (seed `ALPHA0 = 1`).
    pub tracking_gain_1_s: f32,
    /// Gain of the turn-in-place mode on the heading error, 1/s.
    pub turn_gain_1_s: f32,
    /// Largest turn rate of the turn-in-place mode, rad/s.
    pub max_turn_rate_rad_s: f32,
    /// Relative error at which the reference model counts as settled (seed: 2 %).
    pub settle_tolerance: f32,
    /// Distance of the sonar ahead of the centre, along the heading, metres (seed 0.20).
    pub sonar_offset_m: f32,
    /// Shortest range the sonar reports; nearer echoes count as none, metres (seed 0.26).
    pub sonar_min_range_m: f32,
    /// Longest range trusted; farther echoes count as none, metres (seed `ALCANCE_SONAR` 1.5,
    /// at most [`SONAR_MAX_RANGE_LIMIT_M`]).
    pub sonar_range_m: f32,
    /// Neck stepper angle per step, degrees (seed 1.8).
    pub neck_step_deg: f32,
    /// Half-width of a normal sweep, degrees (seed 95). The readings go out to the last whole
    /// neck step inside it (±93.6° at 1.8°), and the band checks trust only that far
    /// ([`crate::sonar::SweepPlan::covered_half_angle_rad`]).
    pub normal_half_sweep_deg: f32,
    /// Half-width of a full sweep, degrees (seed 180).
    pub full_half_sweep_deg: f32,
    /// Wait for the echo of one reading, seconds: the round trip for
    /// [`SONAR_MAX_RANGE_LIMIT_M`] (seed `DELAY`, 35 ms).
    pub echo_wait_s: f32,
    /// Time for one neck step, seconds (seed `TEMPO_MOV_PASSO_MOTOR_SONAR` 0.001).
    pub neck_step_time_s: f32,
    /// Which neck positions a sweep reads (symmetric `2n + 1`; the seed's `2n`).
    pub sweep_layout: SweepLayout,
    /// Full angle of the simulated sonar beam, degrees (0: one ray).
    pub sonar_cone_deg: f32,
    /// Rays cast across the simulated beam (1 ..= [`MAX_CONE_RAYS`]).
    pub sonar_cone_rays: u8,
    /// Standard deviation of the simulated range noise, metres (0: exact).
    pub sonar_noise_std_m: f32,
    /// Simulated sonar model: `false` the exact ray (or the legacy minimum over
    /// [`sonar_cone_deg`](Self::sonar_cone_deg)), `true` the ultrasonic beam of
    /// [`crate::plant::echo`] (cone, first echo, incidence limit, corners).
    pub sonar_beam: bool,
    /// Beam model: half-angle of the cone, degrees (the HC-SR04 data sheet's 15°, half of
    /// Moravec & Elfes' 30° sonar cone: see `docs/robot-model.md`).
    pub sonar_beam_half_angle_deg: f32,
    /// Beam model: a wall echoes only when the angle between the ray and the wall's normal is
    /// below this, degrees (specular reflection; 70 in [`Self::DEFAULT`], the beam's half-angle
    /// in [`Self::SIMULATED`], why in `docs/robot-model.md`).
    pub sonar_incidence_limit_deg: f32,
    /// Beam model: a ray hitting within this distance of a polygon vertex echoes at any angle
    /// (corner reflector, edge diffraction), metres.
    pub sonar_corner_radius_m: f32,
    /// Simulated ranger: probability that a reading which would echo returns "no echo"
    /// ([`crate::plant::faults`]; 0: never).
    pub sonar_dropout_probability: f32,
    /// Simulated ranger: probability of a spurious echo nearer than the true one (crosstalk,
    /// multipath; [`crate::plant::faults`]; 0: never).
    pub sonar_spurious_probability: f32,
    /// Seed of the simulated noise generator.
    pub noise_seed: u64,
    /// Regions of constant depth: largest depth difference between neighbouring readings of
    /// one region, metres (seed `PRECISION` 0.5 px at 50 px/m = 0.01 m).
    pub rcd_depth_tolerance_m: f32,
    /// Regions of constant depth: neighbour pairs that make a region trusted (seed `PADROES` 4).
    pub rcd_min_pairs: u8,
    /// Regions of constant depth: arc length that makes a region trusted even with fewer pairs,
    /// metres (seed `ARC` 2π px at 50 px/m ≈ 0.126 m).
    pub rcd_min_arc_m: f32,
    /// Integration step of the simulated plant, seconds.
    pub plant_substep_s: f32,
}

impl Default for RobotConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

impl RobotConfig {
    /// The defaults (see `docs/robot-model.md` for their sources), usable in `const` contexts.
    pub const DEFAULT: Self = Self {
        planning_radius_m: 0.40,
        wheel_radius_m: 0.075,
        half_axle_m: 0.22,
        point_offset_m: 0.15,
        encoder_pulses_per_rev: 2000,
        motor_gain_rad_s_per_v: 0.8,
        motor_time_constant_s: 0.10,
        max_voltage_v: 11.7,
        controller_period_s: 0.05,
        pid_kp_v_per_rad_s: 2.5,
        pid_ki_v_per_rad: 3.25,
        pid_kd_v_s2_per_rad: 0.05,
        reference_time_constant_s: 1.0,
        tracking_gain_1_s: 1.0,
        turn_gain_1_s: 2.0,
        max_turn_rate_rad_s: 0.8,
        settle_tolerance: 0.02,
        sonar_offset_m: 0.20,
        sonar_min_range_m: 0.26,
        sonar_range_m: 1.5,
        neck_step_deg: 1.8,
        normal_half_sweep_deg: 95.0,
        full_half_sweep_deg: 180.0,
        echo_wait_s: 0.035,
        neck_step_time_s: 0.001,
        sweep_layout: SweepLayout::Symmetric,
        sonar_cone_deg: 0.0,
        sonar_cone_rays: 1,
        sonar_noise_std_m: 0.0,
        sonar_beam: false,
        sonar_beam_half_angle_deg: 15.0,
        sonar_incidence_limit_deg: 70.0,
        sonar_corner_radius_m: 0.05,
        sonar_dropout_probability: 0.0,
        sonar_spurious_probability: 0.0,
        noise_seed: 1,
        rcd_depth_tolerance_m: 0.01,
        rcd_min_pairs: 4,
        rcd_min_arc_m: 0.126,
        plant_substep_s: 0.001,
    };

    /// Half-angle of the beam, degrees, at which a smooth wall stops echoing in the simulated
    /// ranger the host tools default to: the beam's own half-angle. A mirror-smooth wall sends
    /// the sound back to the transducer only while its normal lies within the beam (Kuc &
    /// Siegel 1987; Leonard & Durrant-Whyte 1992), and the beam model's rays, each tested
    /// against this limit, then hear the wall over twice the beam's width of neck angles:
    /// the specular end of issue 23's range, why in `docs/robot-model.md`.
    pub const SPECULAR_INCIDENCE_LIMIT_DEG: f32 = Self::DEFAULT.sonar_beam_half_angle_deg;

    /// The robot the host tools simulate unless told otherwise (`twil simulate`, `twil
    /// mission`, `twil sonar-grid`'s passed options, `twil robot init`): [`Self::DEFAULT`] with a
    /// sensor-faithful ranger: the ultrasonic beam, smooth walls echoing only near face-on
    /// ([`Self::SPECULAR_INCIDENCE_LIMIT_DEG`]), a measured HC-SR04's range noise and judged
    /// missed and spurious echoes ([`crate::plant::faults::MEASURED_NOISE_STD_M`],
    /// [`crate::plant::faults::JUDGED`]). [`Self::DEFAULT`] keeps
    /// the exact single ray the unit tests drive.
    pub const SIMULATED: Self = Self {
        sonar_beam: true,
        sonar_incidence_limit_deg: Self::SPECULAR_INCIDENCE_LIMIT_DEG,
        // A measured HC-SR04's spread of repeated readings, 1 to 5 mm, the worse end (R.
        // Gonzalez, Arduino forum, 2014).
        sonar_noise_std_m: 0.005,
        // Judged: about two missed echoes and one spurious echo in a 105-reading sweep.
        sonar_dropout_probability: 0.02,
        sonar_spurious_probability: 0.01,
        ..Self::DEFAULT
    };
}

/// A config field with a value that makes no sense.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ConfigError {
    /// The field's name, as in [`RobotConfig`].
    pub field: &'static str,
    /// The offending value (integers converted to `f32`).
    pub value: f32,
    /// What is accepted, in words.
    pub expected: &'static str,
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "robot config field `{}` = {} is invalid (expected {})",
            self.field, self.value, self.expected
        )
    }
}

impl core::error::Error for ConfigError {}

fn check(
    field: &'static str,
    value: f32,
    ok: bool,
    expected: &'static str,
) -> Result<(), ConfigError> {
    if value.is_finite() && ok {
        Ok(())
    } else {
        Err(ConfigError {
            field,
            value,
            expected,
        })
    }
}

impl RobotConfig {
    /// The body's radius for collisions, metres: planning radius − [`PLANNING_MARGIN_M`]
    /// (seed `RAIO_REAL`), never below 0.
    pub fn physical_radius_m(&self) -> f32 {
        let r = self.planning_radius_m - PLANNING_MARGIN_M;
        if r.is_finite() && r > 0.0 {
            r
        } else {
            0.0
        }
    }

    /// This config with another planning radius (the `.par` file's), keeping the rest.
    pub fn with_planning_radius_m(self, planning_radius_m: f32) -> Self {
        Self {
            planning_radius_m,
            ..self
        }
    }

    /// Check every field; the first nonsense found is returned, naming the field and value.
    ///
    /// Rules: lengths, times and gains finite and positive (gains ≥ 0 where 0 makes sense);
    /// `sonar_min_range_m < sonar_range_m ≤ 6 m`; half sweeps in `(0, 180]`; tolerance in
    /// `(0, 1)`; `1 ≤ sonar_cone_rays ≤ 31`; cone in `[0, 90]`°; beam half-angle in `[0, 45]`°,
    /// incidence limit in `[0, 90]`°, corner radius in `[0, 1]` m; dropout and spurious
    /// probabilities in `[0, 1]`; substep ≤ period.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let c = self;
        check(
            "planning_radius_m",
            c.planning_radius_m,
            c.planning_radius_m >= 0.0 && c.planning_radius_m <= 10.0,
            "0 to 10 m",
        )?;
        check(
            "wheel_radius_m",
            c.wheel_radius_m,
            c.wheel_radius_m > 0.0 && c.wheel_radius_m <= 1.0,
            "above 0 and at most 1 m",
        )?;
        check(
            "half_axle_m",
            c.half_axle_m,
            c.half_axle_m > 0.0 && c.half_axle_m <= 5.0,
            "above 0 and at most 5 m",
        )?;
        check(
            "point_offset_m",
            c.point_offset_m,
            c.point_offset_m > 0.0 && c.point_offset_m <= 5.0,
            "above 0 and at most 5 m",
        )?;
        check(
            "encoder_pulses_per_rev",
            c.encoder_pulses_per_rev as f32,
            c.encoder_pulses_per_rev > 0 && c.encoder_pulses_per_rev <= 1_000_000,
            "1 to 1000000 counts",
        )?;
        check(
            "motor_gain_rad_s_per_v",
            c.motor_gain_rad_s_per_v,
            c.motor_gain_rad_s_per_v > 0.0,
            "above 0 rad/s per V",
        )?;
        check(
            "motor_time_constant_s",
            c.motor_time_constant_s,
            c.motor_time_constant_s > 0.0,
            "above 0 s",
        )?;
        check(
            "max_voltage_v",
            c.max_voltage_v,
            c.max_voltage_v > 0.0 && c.max_voltage_v <= 1000.0,
            "above 0 and at most 1000 V",
        )?;
        check(
            "controller_period_s",
            c.controller_period_s,
            c.controller_period_s >= 1.0e-4 && c.controller_period_s <= 1.0,
            "0.0001 to 1 s",
        )?;
        check(
            "pid_kp_v_per_rad_s",
            c.pid_kp_v_per_rad_s,
            c.pid_kp_v_per_rad_s >= 0.0,
            "0 or more",
        )?;
        check(
            "pid_ki_v_per_rad",
            c.pid_ki_v_per_rad,
            c.pid_ki_v_per_rad >= 0.0,
            "0 or more",
        )?;
        check(
            "pid_kd_v_s2_per_rad",
            c.pid_kd_v_s2_per_rad,
            c.pid_kd_v_s2_per_rad >= 0.0,
            "0 or more",
        )?;
        check(
            "reference_time_constant_s",
            c.reference_time_constant_s,
            c.reference_time_constant_s > 0.0 && c.reference_time_constant_s <= 100.0,
            "above 0 and at most 100 s",
        )?;
        check(
            "tracking_gain_1_s",
            c.tracking_gain_1_s,
            c.tracking_gain_1_s > 0.0 && c.tracking_gain_1_s <= 100.0,
            "above 0 and at most 100 1/s",
        )?;
        check(
            "turn_gain_1_s",
            c.turn_gain_1_s,
            c.turn_gain_1_s > 0.0 && c.turn_gain_1_s <= 100.0,
            "above 0 and at most 100 1/s",
        )?;
        check(
            "max_turn_rate_rad_s",
            c.max_turn_rate_rad_s,
            c.max_turn_rate_rad_s > 0.0 && c.max_turn_rate_rad_s <= 100.0,
            "above 0 and at most 100 rad/s",
        )?;
        check(
            "settle_tolerance",
            c.settle_tolerance,
            c.settle_tolerance > 0.0 && c.settle_tolerance < 1.0,
            "between 0 and 1, exclusive",
        )?;
        check(
            "sonar_offset_m",
            c.sonar_offset_m,
            c.sonar_offset_m >= 0.0 && c.sonar_offset_m <= 5.0,
            "0 to 5 m",
        )?;
        check(
            "sonar_min_range_m",
            c.sonar_min_range_m,
            c.sonar_min_range_m >= 0.0 && c.sonar_min_range_m < SONAR_MAX_RANGE_LIMIT_M,
            "0 m or more, below 6 m",
        )?;
        check(
            "sonar_range_m",
            c.sonar_range_m,
            c.sonar_range_m > c.sonar_min_range_m && c.sonar_range_m <= SONAR_MAX_RANGE_LIMIT_M,
            "above sonar_min_range_m and at most 6 m",
        )?;
        check(
            "neck_step_deg",
            c.neck_step_deg,
            c.neck_step_deg >= 0.1 && c.neck_step_deg <= 90.0,
            "0.1 to 90 degrees",
        )?;
        check(
            "normal_half_sweep_deg",
            c.normal_half_sweep_deg,
            c.normal_half_sweep_deg > 0.0 && c.normal_half_sweep_deg <= 180.0,
            "above 0 and at most 180 degrees",
        )?;
        check(
            "full_half_sweep_deg",
            c.full_half_sweep_deg,
            c.full_half_sweep_deg > 0.0 && c.full_half_sweep_deg <= 180.0,
            "above 0 and at most 180 degrees",
        )?;
        // The widest sweep must fit a sweep buffer: 2·⌊half/step⌋ + 1 ≤ 201 readings.
        let widest = c.normal_half_sweep_deg.max(c.full_half_sweep_deg);
        let per_side = widest / c.neck_step_deg + 1.0e-4;
        check(
            "neck_step_deg",
            c.neck_step_deg,
            per_side < 101.0,
            "large enough for the widest sweep to fit 201 readings (1.8 degrees for ±180)",
        )?;
        check(
            "echo_wait_s",
            c.echo_wait_s,
            c.echo_wait_s >= 0.0 && c.echo_wait_s <= 10.0,
            "0 to 10 s",
        )?;
        check(
            "neck_step_time_s",
            c.neck_step_time_s,
            c.neck_step_time_s >= 0.0 && c.neck_step_time_s <= 10.0,
            "0 to 10 s",
        )?;
        check(
            "sonar_cone_deg",
            c.sonar_cone_deg,
            c.sonar_cone_deg >= 0.0 && c.sonar_cone_deg <= 90.0,
            "0 to 90 degrees",
        )?;
        check(
            "sonar_cone_rays",
            c.sonar_cone_rays as f32,
            c.sonar_cone_rays >= 1 && c.sonar_cone_rays <= MAX_CONE_RAYS,
            "1 to 31 rays",
        )?;
        check(
            "sonar_noise_std_m",
            c.sonar_noise_std_m,
            c.sonar_noise_std_m >= 0.0 && c.sonar_noise_std_m <= 1.0,
            "0 to 1 m",
        )?;
        check(
            "sonar_beam_half_angle_deg",
            c.sonar_beam_half_angle_deg,
            c.sonar_beam_half_angle_deg >= 0.0 && c.sonar_beam_half_angle_deg <= 45.0,
            "0 to 45 degrees",
        )?;
        check(
            "sonar_incidence_limit_deg",
            c.sonar_incidence_limit_deg,
            c.sonar_incidence_limit_deg >= 0.0 && c.sonar_incidence_limit_deg <= 90.0,
            "0 to 90 degrees",
        )?;
        check(
            "sonar_dropout_probability",
            c.sonar_dropout_probability,
            (0.0..=1.0).contains(&c.sonar_dropout_probability),
            "a probability, 0 to 1",
        )?;
        check(
            "sonar_spurious_probability",
            c.sonar_spurious_probability,
            (0.0..=1.0).contains(&c.sonar_spurious_probability),
            "a probability, 0 to 1",
        )?;
        check(
            "sonar_corner_radius_m",
            c.sonar_corner_radius_m,
            c.sonar_corner_radius_m >= 0.0 && c.sonar_corner_radius_m <= 1.0,
            "0 to 1 m",
        )?;
        check(
            "rcd_depth_tolerance_m",
            c.rcd_depth_tolerance_m,
            c.rcd_depth_tolerance_m >= 0.0 && c.rcd_depth_tolerance_m <= 1.0,
            "0 to 1 m",
        )?;
        check(
            "rcd_min_arc_m",
            c.rcd_min_arc_m,
            c.rcd_min_arc_m >= 0.0,
            "0 m or more",
        )?;
        check(
            "plant_substep_s",
            c.plant_substep_s,
            c.plant_substep_s >= 1.0e-5 && c.plant_substep_s <= c.controller_period_s,
            "1e-5 s up to controller_period_s",
        )?;
        Ok(())
    }

    /// Wheel angle per encoder count, radians.
    pub const fn rad_per_count(&self) -> f32 {
        let pulses = if self.encoder_pulses_per_rev > 1 {
            self.encoder_pulses_per_rev
        } else {
            1
        };
        2.0 * core::f32::consts::PI / pulses as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_is_valid_and_matches_the_seed() {
        let c = RobotConfig::default();
        assert_eq!(c.validate(), Ok(()));
        assert_eq!(c.max_voltage_v, 11.7);
        assert_eq!(c.controller_period_s, 0.05);
        assert_eq!(
            (
                c.pid_kp_v_per_rad_s,
                c.pid_ki_v_per_rad,
                c.pid_kd_v_s2_per_rad
            ),
            (2.5, 3.25, 0.05)
        );
        assert!((c.physical_radius_m() - 0.30).abs() < 1e-6);
    }

    #[test]
    fn validate_names_the_field_and_value() {
        let c = RobotConfig {
            wheel_radius_m: f32::NAN,
            ..RobotConfig::default()
        };
        let e = c.validate().unwrap_err();
        assert_eq!(e.field, "wheel_radius_m");
        assert!(e.value.is_nan());
        let c = RobotConfig {
            half_axle_m: -0.2,
            ..RobotConfig::default()
        };
        assert_eq!(c.validate().unwrap_err().field, "half_axle_m");
        let c = RobotConfig {
            sonar_range_m: 6.5,
            ..RobotConfig::default()
        };
        let e = c.validate().unwrap_err();
        assert_eq!((e.field, e.value), ("sonar_range_m", 6.5));
        let c = RobotConfig {
            sonar_range_m: 6.0,
            ..RobotConfig::default()
        };
        assert_eq!(c.validate(), Ok(()));
        let c = RobotConfig {
            encoder_pulses_per_rev: 0,
            ..RobotConfig::default()
        };
        assert_eq!(c.validate().unwrap_err().field, "encoder_pulses_per_rev");
        let c = RobotConfig {
            sonar_cone_rays: 0,
            ..RobotConfig::default()
        };
        assert_eq!(c.validate().unwrap_err().field, "sonar_cone_rays");
    }

    #[test]
    fn physical_radius_never_negative() {
        let c = RobotConfig::default().with_planning_radius_m(0.05);
        assert_eq!(c.physical_radius_m(), 0.0);
        let c = RobotConfig::default().with_planning_radius_m(f32::INFINITY);
        assert_eq!(c.physical_radius_m(), 0.0);
    }
}
