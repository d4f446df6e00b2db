//! Wheel motor: the controller's voltage command as a PWM duty and a direction level.
//!
//! Seed 003 (`twlckin.cpp`): each wheel's PID output is saturated to ±11.7 V
//! ([`RobotConfig::max_voltage_v`](crate::robot::RobotConfig::max_voltage_v)) and sent to the
//! motor board. Here the bridge is a sign-magnitude one with a PWM input and a direction input
//! (Cytron MD10C / MD13S, Pololu DRV8838 / DRV8876 in phase-enable mode): one [`SetDutyCycle`]
//! channel sets the magnitude, one [`OutputPin`] the sign. That needs one timer channel per
//! motor and no dead-time handling in the firmware (the bridge does it).
//!
//! The bridge puts `duty × battery voltage` across the motor, so a command of `v` volts is
//! `duty = |v| / battery_v`, measured each period because the battery sags under load:
//!
//! - the command is clamped to ±`max_voltage_v`; NaN or ±∞ is 0 V (a broken controller output
//!   must not drive the wheels at full power);
//! - the duty is clamped to 100 % (a battery below 11.7 V cannot give 11.7 V);
//! - a battery reading below [`MIN_BATTERY_V`] (or NaN) turns the motor off and is an error:
//!   a flat battery, or a broken measurement, which would otherwise make every duty 100 %;
//! - [`Motor::stop`] forces 0 immediately (abort, emergency stop).
//!
//! Mirrored mounting: the two motors face each other, so "forward" is the opposite direction
//! level on one side; [`Motor::new`] takes the level that means forward.

use embedded_hal::digital::OutputPin;
use embedded_hal::pwm::SetDutyCycle;

use crate::math::floor;

/// Lowest battery voltage the motors run on, volts: a 12 V lead-acid battery (the seed robot's)
/// is flat at 10.5 V; below it the measurement is wrong or the battery is being damaged.
pub const MIN_BATTERY_V: f32 = 10.5;

/// Which way the motor turns.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Rotation {
    /// Positive voltage: the wheel drives the robot forward.
    Forward,
    /// Negative voltage.
    Reverse,
}

/// What went wrong with a motor.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum MotorError {
    /// The battery reading is below the minimum (or not a number): the motor was turned off.
    BatteryLow {
        /// The reading, volts.
        battery_v: f32,
        /// [`MIN_BATTERY_V`].
        min_battery_v: f32,
    },
    /// The PWM channel refused the duty.
    Pwm,
    /// The direction pin failed.
    DirectionPin,
}

impl core::fmt::Display for MotorError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            MotorError::BatteryLow {
                battery_v,
                min_battery_v,
            } => write!(
                f,
                "battery at {battery_v} V, below the motors' minimum {min_battery_v} V"
            ),
            MotorError::Pwm => write!(f, "the motor's PWM channel refused the duty"),
            MotorError::DirectionPin => write!(f, "the motor's direction pin failed"),
        }
    }
}

impl core::error::Error for MotorError {}

/// The command actually applied: clamped to ±`max_voltage_v`, 0 for NaN or ±∞ (and for a
/// `max_voltage_v` that is not a finite positive number).
pub fn clamp_command_v(command_v: f32, max_voltage_v: f32) -> f32 {
    if !(command_v.is_finite() && max_voltage_v.is_finite() && max_voltage_v > 0.0) {
        0.0
    } else {
        command_v.clamp(-max_voltage_v, max_voltage_v)
    }
}

/// Duty fraction (0 … 1) and rotation for `command_v` at `battery_v`, or
/// [`MotorError::BatteryLow`].
///
/// ```
/// use twil_core::drivers::motor::{duty_for_voltage, Rotation};
/// assert_eq!(duty_for_voltage(6.0, 12.0, 11.7), Ok((0.5, Rotation::Forward)));
/// assert_eq!(duty_for_voltage(-20.0, 11.0, 11.7), Ok((1.0, Rotation::Reverse)));
/// assert!(duty_for_voltage(6.0, 9.0, 11.7).is_err());
/// ```
pub fn duty_for_voltage(
    command_v: f32,
    battery_v: f32,
    max_voltage_v: f32,
) -> Result<(f32, Rotation), MotorError> {
    if battery_v.is_nan() || battery_v < MIN_BATTERY_V {
        return Err(MotorError::BatteryLow {
            battery_v,
            min_battery_v: MIN_BATTERY_V,
        });
    }
    let v = clamp_command_v(command_v, max_voltage_v);
    let rotation = if v < 0.0 {
        Rotation::Reverse
    } else {
        Rotation::Forward
    };
    // battery_v ≥ 10.5 here (∞ gives 0, harmlessly).
    let duty = (v.abs() / battery_v).clamp(0.0, 1.0);
    Ok((duty, rotation))
}

/// A duty fraction in the channel's counts (`max_duty` = 100 %), rounded to nearest; NaN is 0.
pub fn duty_to_counts(duty: f32, max_duty: u16) -> u16 {
    let d = if duty.is_nan() {
        0.0
    } else {
        duty.clamp(0.0, 1.0)
    };
    // `as` saturates; the clamp keeps it ≤ max_duty.
    (floor(d * max_duty as f32 + 0.5) as u16).min(max_duty)
}

/// Battery voltage from the millivolts at the ADC pin and the divider's ratio (battery volts
/// per pin volt). A ratio that is not a number gives NaN, which [`duty_for_voltage`] refuses
/// as a low battery.
///
/// ```
/// use twil_core::drivers::motor::battery_v_from_pin_mv;
/// assert!((battery_v_from_pin_mv(2_200, 5.7) - 12.54).abs() < 1e-4);
/// ```
pub fn battery_v_from_pin_mv(pin_mv: u16, divider_ratio: f32) -> f32 {
    f32::from(pin_mv) * 0.001 * divider_ratio
}

/// One motor on a sign-magnitude bridge.
pub struct Motor<PWM, DIR> {
    pwm: PWM,
    dir: DIR,
    max_voltage_v: f32,
    forward_high: bool,
    applied_v: f32,
}

impl<PWM: SetDutyCycle, DIR: OutputPin> Motor<PWM, DIR> {
    /// A motor; `forward_high` is the direction level that drives the robot forward (opposite
    /// on the mirrored side). The PWM is not touched until the first command: call
    /// [`stop`](Self::stop) at start-up.
    pub fn new(pwm: PWM, dir: DIR, max_voltage_v: f32, forward_high: bool) -> Self {
        Self {
            pwm,
            dir,
            max_voltage_v,
            forward_high,
            applied_v: 0.0,
        }
    }

    /// Clamp commands to ±`max_voltage_v` from now on (a new mission's config).
    pub fn set_max_voltage_v(&mut self, max_voltage_v: f32) {
        self.max_voltage_v = max_voltage_v;
    }

    /// The voltage last applied (after clamping), volts; 0 after a stop or an error.
    pub fn applied_v(&self) -> f32 {
        self.applied_v
    }

    /// Apply `command_v` at the measured `battery_v`. Returns the voltage applied (clamped).
    /// A low battery turns the motor off and returns [`MotorError::BatteryLow`].
    pub fn set_voltage(&mut self, command_v: f32, battery_v: f32) -> Result<f32, MotorError> {
        let (duty, rotation) = match duty_for_voltage(command_v, battery_v, self.max_voltage_v) {
            Ok(d) => d,
            Err(e) => {
                // Off first; the battery error is the one worth reporting.
                let _ = self.stop();
                return Err(e);
            }
        };
        let high = (rotation == Rotation::Forward) == self.forward_high;
        let dir = if high {
            self.dir.set_high()
        } else {
            self.dir.set_low()
        };
        if dir.is_err() {
            let _ = self.stop();
            return Err(MotorError::DirectionPin);
        }
        let counts = duty_to_counts(duty, self.pwm.max_duty_cycle());
        if self.pwm.set_duty_cycle(counts).is_err() {
            let _ = self.stop();
            return Err(MotorError::Pwm);
        }
        self.applied_v = clamp_command_v(command_v, self.max_voltage_v);
        Ok(self.applied_v)
    }

    /// Duty 0 now (abort, emergency stop, start-up). The direction pin is left as it is.
    pub fn stop(&mut self) -> Result<(), MotorError> {
        self.applied_v = 0.0;
        self.pwm
            .set_duty_cycle_fully_off()
            .map_err(|_| MotorError::Pwm)
    }

    /// Give the channel and pin back.
    pub fn release(self) -> (PWM, DIR) {
        (self.pwm, self.dir)
    }
}

#[cfg(test)]
mod tests {
    extern crate std;

    use super::*;
    use embedded_hal_mock::eh1::digital::{
        Mock as PinMock, State as PinState, Transaction as PinTx,
    };
    use embedded_hal_mock::eh1::pwm::{Mock as PwmMock, Transaction as PwmTx};
    use embedded_hal_mock::eh1::MockError;

    const MAX_V: f32 = 11.7;

    #[test]
    fn commands_are_clamped_and_non_numbers_are_zero() {
        assert_eq!(clamp_command_v(5.0, MAX_V), 5.0);
        assert_eq!(clamp_command_v(20.0, MAX_V), 11.7);
        assert_eq!(clamp_command_v(-20.0, MAX_V), -11.7);
        assert_eq!(clamp_command_v(f32::NAN, MAX_V), 0.0);
        assert_eq!(clamp_command_v(f32::INFINITY, MAX_V), 0.0);
        assert_eq!(clamp_command_v(f32::NEG_INFINITY, MAX_V), 0.0);
        assert_eq!(clamp_command_v(5.0, f32::NAN), 0.0);
        assert_eq!(clamp_command_v(5.0, -1.0), 0.0);
    }

    #[test]
    fn duty_is_volts_over_the_measured_battery() {
        let (d, r) = duty_for_voltage(11.7, 13.0, MAX_V).unwrap();
        assert!((d - 0.9).abs() < 1e-6);
        assert_eq!(r, Rotation::Forward);
        let (d, r) = duty_for_voltage(-3.0, 12.0, MAX_V).unwrap();
        assert!((d - 0.25).abs() < 1e-6);
        assert_eq!(r, Rotation::Reverse);
        // Sagging battery: 11.7 V cannot be given by 11 V: 100 %.
        assert_eq!(
            duty_for_voltage(11.7, 11.0, MAX_V),
            Ok((1.0, Rotation::Forward))
        );
        assert_eq!(
            duty_for_voltage(f32::NAN, 12.0, MAX_V),
            Ok((0.0, Rotation::Forward))
        );
    }

    #[test]
    fn a_low_or_missing_battery_reading_is_an_error() {
        for battery_v in [10.4, 0.0, -12.0, f32::NAN] {
            let e = duty_for_voltage(1.0, battery_v, MAX_V).unwrap_err();
            let MotorError::BatteryLow { min_battery_v, .. } = e else {
                panic!("{e:?} for {battery_v} V");
            };
            assert_eq!(min_battery_v, MIN_BATTERY_V);
        }
        assert!(duty_for_voltage(1.0, 10.5, MAX_V).is_ok());
    }

    #[test]
    fn battery_volts_from_the_divider() {
        assert!((battery_v_from_pin_mv(2_000, 5.7) - 11.4).abs() < 1e-5);
        assert_eq!(battery_v_from_pin_mv(0, 5.7), 0.0);
        assert!(battery_v_from_pin_mv(2_000, f32::NAN).is_nan());
        // A flat or unconnected divider reads as a low battery.
        assert!(duty_for_voltage(1.0, battery_v_from_pin_mv(1_800, 5.7), MAX_V).is_err());
    }

    #[test]
    fn duty_counts_round_and_clamp() {
        assert_eq!(duty_to_counts(0.5, 4199), 2100);
        assert_eq!(duty_to_counts(1.0, 4199), 4199);
        assert_eq!(duty_to_counts(1.5, 4199), 4199);
        assert_eq!(duty_to_counts(-0.5, 4199), 0);
        assert_eq!(duty_to_counts(f32::NAN, 4199), 0);
        assert_eq!(duty_to_counts(1.0, u16::MAX), u16::MAX);
    }

    #[test]
    fn forward_and_reverse_set_direction_then_duty() {
        let mut pwm = PwmMock::new(&[
            PwmTx::max_duty_cycle(1000),
            PwmTx::set_duty_cycle(500),
            PwmTx::max_duty_cycle(1000),
            PwmTx::set_duty_cycle(250),
        ]);
        let mut dir = PinMock::new(&[PinTx::set(PinState::High), PinTx::set(PinState::Low)]);
        let mut m = Motor::new(pwm.clone(), dir.clone(), MAX_V, true);
        assert_eq!(m.set_voltage(6.0, 12.0), Ok(6.0));
        assert_eq!(m.set_voltage(-3.0, 12.0), Ok(-3.0));
        assert_eq!(m.applied_v(), -3.0);
        pwm.done();
        dir.done();
    }

    #[test]
    fn a_mirrored_motor_inverts_the_direction_level() {
        let mut pwm = PwmMock::new(&[PwmTx::max_duty_cycle(1000), PwmTx::set_duty_cycle(1000)]);
        let mut dir = PinMock::new(&[PinTx::set(PinState::Low)]);
        let mut m = Motor::new(pwm.clone(), dir.clone(), MAX_V, false);
        assert_eq!(m.set_voltage(50.0, 11.0), Ok(11.7));
        pwm.done();
        dir.done();
    }

    #[test]
    fn a_low_battery_turns_the_motor_off() {
        let mut pwm = PwmMock::new(&[
            PwmTx::max_duty_cycle(1000),
            PwmTx::set_duty_cycle(500),
            PwmTx::set_duty_cycle(0),
        ]);
        let mut dir = PinMock::new(&[PinTx::set(PinState::High)]);
        let mut m = Motor::new(pwm.clone(), dir.clone(), MAX_V, true);
        assert_eq!(m.set_voltage(6.0, 12.0), Ok(6.0));
        assert_eq!(
            m.set_voltage(6.0, 9.0),
            Err(MotorError::BatteryLow {
                battery_v: 9.0,
                min_battery_v: MIN_BATTERY_V
            })
        );
        assert_eq!(m.applied_v(), 0.0);
        pwm.done();
        dir.done();
    }

    #[test]
    fn stop_forces_zero_and_pin_errors_stop_too() {
        let err = MockError::Io(std::io::ErrorKind::Other);
        let mut pwm = PwmMock::new(&[PwmTx::set_duty_cycle(0), PwmTx::set_duty_cycle(0)]);
        let mut dir = PinMock::new(&[PinTx::set(PinState::High).with_error(err)]);
        let mut m = Motor::new(pwm.clone(), dir.clone(), MAX_V, true);
        assert_eq!(m.stop(), Ok(()));
        assert_eq!(m.set_voltage(6.0, 12.0), Err(MotorError::DirectionPin));
        pwm.done();
        dir.done();
    }
}
