//! The robot's body on a board: what the firmware's board build does with the drivers,
//! written once over embedded-hal 1.0 traits (plus [`EchoCapture`], [`QuadratureCounter`] and
//! [`BatterySensor`], where embedded-hal has none), so the same code runs on the STM32F405 and,
//! in `tests/virtual_board.rs`, on pins driven by a scripted world.
//!
//! Two halves, as the firmware's tasks hold them:
//!
//! - [`Chassis`] (the control task, every 50 ms): the wheels' encoders, the two motors, the
//!   emergency-stop input and the battery;
//! - [`SonarHead`] (the sonar task): the neck stepper and the sonar ranger.
//!
//! The rules (issue 24, "first power-up"):
//!
//! - **power-up**: both motors at duty 0, the e-stop latched, the neck not homed. Nothing
//!   moves until a mission starts.
//! - **mission start** (after `RobotDevice::take_started`): [`SonarHead::restart`] takes the
//!   mission's [`RobotConfig`] (sonar window, neck geometry) and homes the neck;
//!   [`Chassis::restart`] takes its encoder limit and voltage limit, re-references the
//!   encoders and clears the e-stop, which only succeeds with the button released. The motors
//!   then get duty once the button has read released for
//!   [`RELEASED_POLLS_TO_RUN`](super::emergency_stop::RELEASED_POLLS_TO_RUN) periods in a row.
//! - **every control period**: [`Chassis::read_counts`] before the pilot's step,
//!   [`Chassis::drive`] after it. `drive` polls the e-stop *first*, so a press stops both
//!   motors at the next period (within 50 ms), and reads the battery.
//! - **faults end the mission, never silently**: every failure the body sees while a mission
//!   runs comes back once as a [`StopCause`]: [`StopCause::EmergencyStop`] for a press;
//!   [`StopCause::SensorFault`] with the [`Sensor`] for a homing that did not find the switch,
//!   a neck or trigger pin error, a sonar that stays silent for [`SILENT_PINGS_TO_FAULT`]
//!   pings, a battery that cannot be read or is below the minimum, a motor pin error, an
//!   unreadable e-stop input. The firmware hands it to `RobotDevice::fail`, which ends the
//!   mission `Aborted` with that cause (the host prints it); the body has already put the
//!   motors at duty 0 and stays disarmed until the next mission start.
//!
//! ## Wiring it (the firmware)
//!
//! ```text
//! init:            let chassis = Chassis::new(motor_l, motor_r, wheel_l, wheel_r, estop, battery);
//!                  let head = SonarHead::new(sonar, neck);
//! mission start:   if let Err(cause) = head.restart(&config.robot)    // or begin_restart + step
//!                      .and_then(|_| chassis.restart(&config.robot)) { device.fail(cause) }
//! control (50 ms): let (l, r) = chassis.read_counts();          // WheelCounts, .trusted()
//!                  let report = pilot.tick(l, r, dt);
//!                  let d = chassis.drive(report.left_voltage_v, report.right_voltage_v);
//!                  if let Some(cause) = d.stop { /* motors already 0 */ device.fail(cause) }
//! mission ended:   chassis.stop();
//! sonar request:   head.read(angle_rad)  -> Ok(range or None) | Err(cause) → device.fail(cause)
//! ```
//!
//! The head's blocking [`SonarHead::read`] waits out the neck's steps and one sonar cycle
//! (≥ 60 ms). An async sonar task uses the same pieces without blocking:
//! `head.neck_mut().begin_move_to_angle(deg)` then `step()` / `Mono::delay(ns)` until done;
//! `head.sonar_mut().fire()`, the capture's edges into the returned decoder until its
//! deadline, `sonar_mut().finish(outcome, tick_hz)`; then [`SonarHead::judge`] on the reading
//! (silence counting, faults) and [`neck_fault`] on a neck error.

use embedded_hal::delay::DelayNs;
use embedded_hal::digital::{InputPin, OutputPin};
use embedded_hal::pwm::SetDutyCycle;

use super::battery::BatterySensor;
use super::echo::EchoOutcome;
use super::emergency_stop::EmergencyStop;
use super::motor::{Motor, MotorError};
use super::neck_stepper::{NeckError, NeckGeometry, NeckStepper};
use super::sonar_ranger::{EchoCapture, SonarError, SonarRanger, SonarReading, SonarWindow};
use super::wheel_encoder::{max_counts_per_period, QuadratureCounter, WheelCounts, WheelEncoder};
use crate::failsafe::{Sensor, StopCause};
use crate::robot::RobotConfig;

/// Pings in a row with no edge at all on the echo line before the sonar counts as failed (an
/// HC-SR04 raises its echo line after every trigger it hears; one lost ping is tolerated).
pub const SILENT_PINGS_TO_FAULT: u32 = 3;

/// The cause for a neck error: the switch not found (or no homing yet) is
/// [`Sensor::NeckHome`], anything else [`Sensor::Neck`].
pub fn neck_fault(error: NeckError) -> StopCause {
    StopCause::SensorFault(match error {
        NeckError::HomeNotFound { .. } | NeckError::NotHomed => Sensor::NeckHome,
        NeckError::AngleOutOfRange { .. }
        | NeckError::BadStep { .. }
        | NeckError::BadLimit { .. }
        | NeckError::Pin { .. } => Sensor::Neck,
    })
}

/// The cause for a sonar error.
pub fn sonar_fault(error: SonarError) -> StopCause {
    match error {
        SonarError::TriggerPin | SonarError::TickRate { .. } => {
            StopCause::SensorFault(Sensor::SonarTrigger)
        }
    }
}

/// What one control period's [`Chassis::drive`] did.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Drive {
    /// Voltage applied to the left motor, volts (0 when stopped).
    pub left_v: f32,
    /// Voltage applied to the right motor, volts.
    pub right_v: f32,
    /// Set once, on the period the body stopped a running mission: why.
    pub stop: Option<StopCause>,
}

impl Drive {
    const fn off(stop: Option<StopCause>) -> Self {
        Self {
            left_v: 0.0,
            right_v: 0.0,
            stop,
        }
    }
}

/// The wheels: two motors, two encoders, the emergency stop, the battery.
pub struct Chassis<PWML, DIRL, PWMR, DIRR, QL, QR, ESTOP, BAT> {
    motor_left: Motor<PWML, DIRL>,
    motor_right: Motor<PWMR, DIRR>,
    wheel_left: WheelEncoder<QL>,
    wheel_right: WheelEncoder<QR>,
    estop: EmergencyStop<ESTOP>,
    battery: BAT,
    armed: bool,
    battery_v: f32,
    motor_errors: u32,
}

impl<PWML, DIRL, PWMR, DIRR, QL, QR, ESTOP, BAT> Chassis<PWML, DIRL, PWMR, DIRR, QL, QR, ESTOP, BAT>
where
    PWML: SetDutyCycle,
    DIRL: OutputPin,
    PWMR: SetDutyCycle,
    DIRR: OutputPin,
    QL: QuadratureCounter,
    QR: QuadratureCounter,
    ESTOP: InputPin,
    BAT: BatterySensor,
{
    /// The chassis at power-up: both motors at duty 0 now, disarmed (no duty until a mission
    /// starts), the e-stop as built (latched).
    pub fn new(
        motor_left: Motor<PWML, DIRL>,
        motor_right: Motor<PWMR, DIRR>,
        wheel_left: WheelEncoder<QL>,
        wheel_right: WheelEncoder<QR>,
        estop: EmergencyStop<ESTOP>,
        battery: BAT,
    ) -> Self {
        let mut chassis = Self {
            motor_left,
            motor_right,
            wheel_left,
            wheel_right,
            estop,
            battery,
            armed: false,
            battery_v: f32::NAN,
            motor_errors: 0,
        };
        chassis.motors_off();
        chassis
    }

    /// Both motors to duty 0 (errors are counted: there is nothing safer to do).
    fn motors_off(&mut self) {
        let left = self.motor_left.stop();
        let right = self.motor_right.stop();
        if left.is_err() || right.is_err() {
            self.motor_errors = self.motor_errors.wrapping_add(1);
        }
    }

    /// Stop and disarm with `cause`, for [`Drive::stop`].
    fn halt(&mut self, cause: StopCause) -> Drive {
        self.armed = false;
        self.motors_off();
        Drive::off(Some(cause))
    }

    /// A mission starts: its encoder limit (`max_counts_per_period`) and voltage limit, the
    /// encoders' reference, and the e-stop cleared. Errors: the button is pressed
    /// ([`StopCause::EmergencyStop`]) or unreadable
    /// ([`Sensor::EmergencyStopInput`]); the chassis then stays disarmed.
    pub fn restart(&mut self, config: &RobotConfig) -> Result<(), StopCause> {
        self.armed = false;
        self.motors_off();
        let limit = max_counts_per_period(config);
        self.wheel_left.restart(limit);
        self.wheel_right.restart(limit);
        self.motor_left.set_max_voltage_v(config.max_voltage_v);
        self.motor_right.set_max_voltage_v(config.max_voltage_v);
        match self.estop.clear() {
            Ok(()) => {
                self.armed = true;
                Ok(())
            }
            // A broken input is told from a press by the clear's own read.
            Err(_) if self.estop.last_read_failed() => {
                Err(StopCause::SensorFault(Sensor::EmergencyStopInput))
            }
            Err(_) => Err(StopCause::EmergencyStop),
        }
    }

    /// The mission is over (ended, aborted): motors to 0, disarmed until the next
    /// [`restart`](Self::restart).
    pub fn stop(&mut self) {
        self.armed = false;
        self.motors_off();
    }

    /// Whether the motors may get duty (a mission started, nothing stopped it). Duty also waits
    /// for the e-stop's released polls.
    pub fn is_armed(&self) -> bool {
        self.armed
    }

    /// The encoders' counts since the last call (positive = forward); implausible jumps are
    /// flagged (use [`WheelCounts::trusted`]).
    pub fn read_counts(&mut self) -> (WheelCounts, WheelCounts) {
        (self.wheel_left.read(), self.wheel_right.read())
    }

    /// One control period's output: poll the e-stop, then apply the voltages at the measured
    /// battery voltage. Disarmed, or while the e-stop waits for its released polls, both
    /// motors get duty 0. A press, a battery fault or a motor pin fault during a mission puts
    /// both motors at 0, disarms, and is returned once in [`Drive::stop`].
    pub fn drive(&mut self, left_v: f32, right_v: f32) -> Drive {
        let motors_off = self.estop.poll();
        if self.armed && self.estop.is_latched() {
            let cause = if self.estop.last_trip_was_read_error() {
                StopCause::SensorFault(Sensor::EmergencyStopInput)
            } else {
                StopCause::EmergencyStop
            };
            return self.halt(cause);
        }
        if !self.armed || motors_off {
            self.motors_off();
            return Drive::off(None);
        }
        let battery_v = match self.battery.read_battery_v() {
            Ok(v) => v,
            Err(_) => {
                self.battery_v = f32::NAN;
                return self.halt(StopCause::SensorFault(Sensor::Battery));
            }
        };
        self.battery_v = battery_v;
        let left = self.motor_left.set_voltage(left_v, battery_v);
        let right = self.motor_right.set_voltage(right_v, battery_v);
        match (left, right) {
            (Ok(l), Ok(r)) => Drive {
                left_v: l,
                right_v: r,
                stop: None,
            },
            (Err(MotorError::BatteryLow { .. }), _) | (_, Err(MotorError::BatteryLow { .. })) => {
                self.halt(StopCause::SensorFault(Sensor::Battery))
            }
            _ => {
                self.motor_errors = self.motor_errors.wrapping_add(1);
                self.halt(StopCause::SensorFault(Sensor::Motor))
            }
        }
    }

    /// Read the e-stop input now (the self-test): pressed or not; an unreadable input is
    /// [`Sensor::EmergencyStopInput`]. A press latches the stop as in [`drive`](Self::drive).
    pub fn read_estop(&mut self) -> Result<bool, StopCause> {
        let pressed = self.estop.read_pressed();
        if self.estop.last_read_failed() {
            Err(StopCause::SensorFault(Sensor::EmergencyStopInput))
        } else {
            Ok(pressed)
        }
    }

    /// Read the battery now (the self-test), volts; a failed read is [`Sensor::Battery`].
    pub fn read_battery_v(&mut self) -> Result<f32, StopCause> {
        match self.battery.read_battery_v() {
            Ok(v) => {
                self.battery_v = v;
                Ok(v)
            }
            Err(_) => {
                self.battery_v = f32::NAN;
                Err(StopCause::SensorFault(Sensor::Battery))
            }
        }
    }

    /// Drive the wheels at `left_v` / `right_v` for `on_periods` control periods of
    /// `period_ms` (counted from the first with duty: the e-stop's released polls come first),
    /// then at 0 V for `coast_periods`, waiting with `delay`: the self-test's pulse, blocking
    /// ([`begin_pulse`](Self::begin_pulse) and [`pulse_period`](Self::pulse_period) with the
    /// waits in between). Returns both wheels' counts over all of it (forward positive), or
    /// what stopped it (the e-stop, the battery, a motor pin).
    pub fn pulse(
        &mut self,
        config: &RobotConfig,
        volts: (f32, f32),
        (on_periods, coast_periods, period_ms): (u32, u32, u32),
        delay: &mut impl DelayNs,
    ) -> Result<(i32, i32), StopCause> {
        let mut pulse = self.begin_pulse(config, volts, on_periods, coast_periods)?;
        // Bounded: `pulse_period` ends the pulse after at most `WheelPulse::periods_max` calls.
        loop {
            if let Some(result) = self.pulse_period(&mut pulse) {
                return result;
            }
            delay.delay_ms(period_ms);
        }
    }

    /// Start the self-test's pulse (`volts` for `on_periods` periods with duty, then
    /// `coast_periods` at 0 V): armed as a mission start ([`restart`](Self::restart): refused
    /// while the e-stop is pressed or unreadable), the encoders re-referenced. Then call
    /// [`pulse_period`](Self::pulse_period) once per control period, in place of
    /// [`drive`](Self::drive), until it returns the result: a firmware whose control task
    /// cannot block runs the pulse that way, in its own periods.
    pub fn begin_pulse(
        &mut self,
        config: &RobotConfig,
        volts: (f32, f32),
        on_periods: u32,
        coast_periods: u32,
    ) -> Result<WheelPulse, StopCause> {
        self.restart(config)?;
        let _ = self.read_counts();
        Ok(WheelPulse {
            volts,
            on_periods,
            tries_left: on_periods
                .saturating_add(super::emergency_stop::RELEASED_POLLS_TO_RUN)
                .saturating_add(1),
            coast_left: coast_periods,
            driven: 0,
            counts: (0, 0),
            driving: true,
            result: Ok(()),
        })
    }

    /// One control period of `pulse`: the counts since the last period, then this period's
    /// output (the e-stop polled first, as in [`drive`](Self::drive)). `Some` at the end, with
    /// the counts over the whole pulse or what stopped it; the motors are then at 0 V and
    /// disarmed.
    pub fn pulse_period(
        &mut self,
        pulse: &mut WheelPulse,
    ) -> Option<Result<(i32, i32), StopCause>> {
        let (l, r) = self.read_counts();
        pulse.counts = (
            pulse.counts.0.saturating_add(l.counts),
            pulse.counts.1.saturating_add(r.counts),
        );
        if pulse.driving {
            if pulse.driven < pulse.on_periods && pulse.tries_left > 0 {
                pulse.tries_left -= 1;
                let drive = self.drive(pulse.volts.0, pulse.volts.1);
                match drive.stop {
                    Some(cause) => pulse.result = Err(cause),
                    None => {
                        if drive.left_v != 0.0 || drive.right_v != 0.0 {
                            pulse.driven += 1;
                        }
                        return None;
                    }
                }
            }
            self.stop();
            pulse.driving = false;
        }
        if pulse.coast_left == 0 {
            return Some(pulse.result.map(|()| pulse.counts));
        }
        pulse.coast_left -= 1;
        None
    }

    /// The battery voltage last read, volts (NaN before the first reading or after a failed
    /// one).
    pub fn battery_v(&self) -> f32 {
        self.battery_v
    }

    /// The e-stop input (its counts, its state).
    pub fn estop(&self) -> &EmergencyStop<ESTOP> {
        &self.estop
    }

    /// Times a motor refused duty 0 or a command.
    pub fn motor_errors(&self) -> u32 {
        self.motor_errors
    }

    /// The voltages the motors have now, volts.
    pub fn applied_v(&self) -> (f32, f32) {
        (self.motor_left.applied_v(), self.motor_right.applied_v())
    }
}

/// A self-test pulse under way ([`Chassis::begin_pulse`]); it ends after at most
/// [`periods_max`](Self::periods_max) calls of [`Chassis::pulse_period`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WheelPulse {
    volts: (f32, f32),
    on_periods: u32,
    /// Periods left to try for duty (the e-stop's released polls take the first ones).
    tries_left: u32,
    coast_left: u32,
    driven: u32,
    counts: (i32, i32),
    driving: bool,
    result: Result<(), StopCause>,
}

impl WheelPulse {
    /// Calls of [`Chassis::pulse_period`] this pulse takes at most.
    pub fn periods_max(&self) -> u32 {
        self.tries_left
            .saturating_add(self.coast_left)
            .saturating_add(2)
    }
}

/// The sonar head: the neck stepper and the sonar ranger on it.
pub struct SonarHead<TRIG, ECHO, SD, STEP, DIR, HOME, ND> {
    sonar: SonarRanger<TRIG, ECHO, SD>,
    neck: NeckStepper<STEP, DIR, HOME, ND>,
    silent_pings: u32,
}

impl<TRIG, ECHO, SD, STEP, DIR, HOME, ND> SonarHead<TRIG, ECHO, SD, STEP, DIR, HOME, ND>
where
    TRIG: OutputPin,
    ECHO: EchoCapture,
    SD: DelayNs,
    STEP: OutputPin,
    DIR: OutputPin,
    HOME: InputPin,
    ND: DelayNs,
{
    /// The head at power-up: the neck not homed.
    pub fn new(sonar: SonarRanger<TRIG, ECHO, SD>, neck: NeckStepper<STEP, DIR, HOME, ND>) -> Self {
        Self {
            sonar,
            neck,
            silent_pings: 0,
        }
    }

    /// A mission starts: its sonar window and neck geometry, then homing (blocking: at most
    /// `max_homing_steps` steps at the start rate, 1.07 s with the default config). Returns
    /// the homing steps; errors are [`Sensor::NeckHome`] (the switch never closed) or
    /// [`Sensor::Neck`] (a pin).
    pub fn restart(&mut self, config: &RobotConfig) -> Result<u32, StopCause> {
        self.configure(config);
        self.neck.home().map_err(neck_fault)
    }

    /// [`restart`](Self::restart) without the homing, for a task that homes stepwise itself
    /// (`neck_mut().begin_homing()`, then `step()` until done).
    pub fn configure(&mut self, config: &RobotConfig) {
        self.sonar.set_window(SonarWindow::from_config(config));
        self.neck.set_geometry(NeckGeometry::from_config(config));
        self.silent_pings = 0;
    }

    /// One reading at `neck_angle_rad` (blocking: the neck's steps, then one sonar cycle):
    /// `Ok(Some(range_m))`, `Ok(None)` for no echo, or the fault.
    pub fn read(&mut self, neck_angle_rad: f32) -> Result<Option<f32>, StopCause> {
        self.neck
            .move_to_angle(neck_angle_rad.to_degrees())
            .map_err(neck_fault)?;
        let reading = self.sonar.read();
        self.judge(reading)
    }

    /// One ping at `neck_angle_rad`, the neck moved there first when it is homed (else where
    /// it points), without the silence counting of [`judge`](Self::judge): the self-test's
    /// ping, which reports a silent echo line itself.
    pub fn ping(&mut self, neck_angle_rad: f32) -> Result<SonarReading, StopCause> {
        if self.neck.position_steps().is_some() {
            self.neck
                .move_to_angle(neck_angle_rad.to_degrees())
                .map_err(neck_fault)?;
        }
        self.sonar.read().map_err(sonar_fault)
    }

    /// The range of one ping's reading, counting silent pings: [`SILENT_PINGS_TO_FAULT`] in a
    /// row are [`Sensor::SonarSilent`]; a sonar error is [`Sensor::SonarTrigger`].
    pub fn judge(
        &mut self,
        reading: Result<SonarReading, SonarError>,
    ) -> Result<Option<f32>, StopCause> {
        let reading = reading.map_err(sonar_fault)?;
        if reading.outcome == EchoOutcome::Silent {
            self.silent_pings = self.silent_pings.saturating_add(1);
            if self.silent_pings >= SILENT_PINGS_TO_FAULT {
                return Err(StopCause::SensorFault(Sensor::SonarSilent));
            }
        } else {
            self.silent_pings = 0;
        }
        Ok(reading.range_m)
    }

    /// The non-blocking [`restart`](Self::restart): [`configure`](Self::configure), then
    /// begin homing; the caller steps `neck_mut().step()` until
    /// [`NeckProgress::Done`](super::NeckProgress::Done), sleeping each `Wait` (counted from
    /// the step's return), and maps an error with [`neck_fault`]. The blocking `restart`
    /// takes up to 214 × 5 ms = 1.07 s with the default config, longer than the watchdog gate
    /// allows the mission task (`WatchdogGate::MISSION_LIMIT_MS`, 1 s): a firmware homes this
    /// way, in a task that can sleep.
    pub fn begin_restart(&mut self, config: &RobotConfig) -> Result<(), StopCause> {
        self.configure(config);
        self.neck.begin_homing().map_err(neck_fault)
    }

    /// The neck (for a task that steps it itself).
    pub fn neck_mut(&mut self) -> &mut NeckStepper<STEP, DIR, HOME, ND> {
        &mut self.neck
    }

    /// The neck, read-only.
    pub fn neck(&self) -> &NeckStepper<STEP, DIR, HOME, ND> {
        &self.neck
    }

    /// The sonar (for a task that fires it and feeds its decoder itself).
    pub fn sonar_mut(&mut self) -> &mut SonarRanger<TRIG, ECHO, SD> {
        &mut self.sonar
    }

    /// The sonar, read-only.
    pub fn sonar(&self) -> &SonarRanger<TRIG, ECHO, SD> {
        &self.sonar
    }
}

#[cfg(test)]
mod tests {
    //! The fault paths the virtual board's infallible pins cannot reach: pins that fail.
    extern crate std;
    use std::cell::Cell;
    use std::rc::Rc;

    use super::*;
    use crate::drivers::battery::BatteryReadError;
    use crate::drivers::emergency_stop::ActiveLevel;
    use crate::drivers::wheel_encoder::Mounting;

    /// A pin (or PWM channel) that fails while its flag is set; as an input it reads `level`.
    #[derive(Clone)]
    struct Flaky {
        fail: Rc<Cell<bool>>,
        level: Rc<Cell<bool>>,
    }

    impl Flaky {
        fn new() -> Self {
            Self {
                fail: Rc::new(Cell::new(false)),
                level: Rc::new(Cell::new(false)),
            }
        }
        fn result(&self) -> Result<(), embedded_hal::digital::ErrorKind> {
            if self.fail.get() {
                Err(embedded_hal::digital::ErrorKind::Other)
            } else {
                Ok(())
            }
        }
    }

    impl embedded_hal::digital::ErrorType for Flaky {
        type Error = embedded_hal::digital::ErrorKind;
    }
    impl OutputPin for Flaky {
        fn set_low(&mut self) -> Result<(), Self::Error> {
            self.result()
        }
        fn set_high(&mut self) -> Result<(), Self::Error> {
            self.result()
        }
    }
    impl InputPin for Flaky {
        fn is_high(&mut self) -> Result<bool, Self::Error> {
            self.result().map(|_| self.level.get())
        }
        fn is_low(&mut self) -> Result<bool, Self::Error> {
            self.is_high().map(|h| !h)
        }
    }
    impl embedded_hal::pwm::ErrorType for Flaky {
        type Error = embedded_hal::pwm::ErrorKind;
    }
    impl SetDutyCycle for Flaky {
        fn max_duty_cycle(&self) -> u16 {
            1000
        }
        fn set_duty_cycle(&mut self, _duty: u16) -> Result<(), Self::Error> {
            self.result()
                .map_err(|_| embedded_hal::pwm::ErrorKind::Other)
        }
    }

    struct Still;
    impl QuadratureCounter for Still {
        fn count(&mut self) -> u16 {
            0
        }
    }

    struct Twelve;
    impl BatterySensor for Twelve {
        fn read_battery_v(&mut self) -> Result<f32, BatteryReadError> {
            Ok(12.0)
        }
    }

    type TestChassis = Chassis<Flaky, Flaky, Flaky, Flaky, Still, Still, Flaky, Twelve>;

    /// A chassis whose right direction pin is `dir` and e-stop input `estop`, armed.
    fn armed(dir: &Flaky, estop: &Flaky) -> TestChassis {
        let mut c = Chassis::new(
            Motor::new(Flaky::new(), Flaky::new(), 11.7, true),
            Motor::new(Flaky::new(), dir.clone(), 11.7, false),
            WheelEncoder::new(Still, Mounting::Normal, 224),
            WheelEncoder::new(Still, Mounting::Mirrored, 224),
            EmergencyStop::new(estop.clone(), ActiveLevel::High),
            Twelve,
        );
        for _ in 0..3 {
            assert_eq!(c.drive(1.0, 1.0), Drive::off(None), "disarmed: no duty");
        }
        c.restart(&RobotConfig::DEFAULT).unwrap();
        assert_eq!(c.drive(1.0, 1.0).left_v, 1.0);
        c
    }

    #[test]
    fn a_motor_pin_error_stops_both_and_is_a_motor_fault() {
        let (dir, estop) = (Flaky::new(), Flaky::new());
        let mut c = armed(&dir, &estop);
        dir.fail.set(true);
        let d = c.drive(1.0, 1.0);
        assert_eq!(d, Drive::off(Some(StopCause::SensorFault(Sensor::Motor))));
        assert_eq!(c.applied_v(), (0.0, 0.0));
        assert!(!c.is_armed());
        assert_eq!(c.drive(1.0, 1.0), Drive::off(None), "reported once");
    }

    #[test]
    fn an_unreadable_e_stop_is_told_from_a_press() {
        let (dir, estop) = (Flaky::new(), Flaky::new());
        let mut c = armed(&dir, &estop);
        estop.fail.set(true);
        assert_eq!(
            c.drive(1.0, 1.0),
            Drive::off(Some(StopCause::SensorFault(Sensor::EmergencyStopInput)))
        );
        // Still broken at the next start: refused with the same cause.
        assert_eq!(
            c.restart(&RobotConfig::DEFAULT),
            Err(StopCause::SensorFault(Sensor::EmergencyStopInput))
        );
        // A press is a press.
        estop.fail.set(false);
        let mut c = armed(&dir, &estop);
        estop.level.set(true);
        assert_eq!(
            c.drive(1.0, 1.0),
            Drive::off(Some(StopCause::EmergencyStop))
        );
        assert_eq!(
            c.restart(&RobotConfig::DEFAULT),
            Err(StopCause::EmergencyStop)
        );
    }

    /// The stepwise pulse, as a control task runs it: duty for exactly `on` periods, then `coast` periods at 0 V, within `periods_max` calls; a
    /// press during it ends it with that cause and the motors at 0, disarmed.
    #[test]
    fn a_stepwise_pulse_drives_its_periods_and_stops_on_a_press() {
        let (dir, estop) = (Flaky::new(), Flaky::new());
        let mut c = armed(&dir, &estop);
        c.stop();
        let mut pulse = c
            .begin_pulse(&RobotConfig::DEFAULT, (6.0, 0.0), 4, 2)
            .unwrap();
        let max = pulse.periods_max();
        let (mut calls, mut driven) = (0, 0);
        let result = loop {
            calls += 1;
            assert!(calls <= max, "{calls} calls, at most {max}");
            if let Some(result) = c.pulse_period(&mut pulse) {
                break result;
            }
            if c.applied_v().0 != 0.0 {
                driven += 1;
            }
        };
        assert_eq!(result, Ok((0, 0)), "the encoders stand still");
        assert_eq!(driven, 4);
        // The e-stop was released all along (no polls to wait): 4 periods with duty, the
        // period that stops, 2 coasting.
        assert_eq!(calls, 4 + 1 + 2);
        assert!(!c.is_armed());

        let mut pulse = c
            .begin_pulse(&RobotConfig::DEFAULT, (0.0, 6.0), 10, 3)
            .unwrap();
        for _ in 0..3 {
            assert_eq!(c.pulse_period(&mut pulse), None);
        }
        assert_eq!(c.applied_v().1, 6.0);
        estop.level.set(true);
        let mut calls = 0;
        let result = loop {
            calls += 1;
            assert!(calls <= 10, "ends after the coast");
            if let Some(result) = c.pulse_period(&mut pulse) {
                break result;
            }
            assert_eq!(c.applied_v(), (0.0, 0.0), "zeroed at the press's period");
        };
        assert_eq!(result, Err(StopCause::EmergencyStop));
        assert!(!c.is_armed());
        // Pressed: a new pulse is refused, as a mission start is.
        assert_eq!(
            c.begin_pulse(&RobotConfig::DEFAULT, (6.0, 0.0), 4, 2),
            Err(StopCause::EmergencyStop)
        );
    }

    #[test]
    fn neck_and_sonar_errors_name_their_part() {
        assert_eq!(
            neck_fault(NeckError::HomeNotFound { steps: 214 }),
            StopCause::SensorFault(Sensor::NeckHome)
        );
        assert_eq!(
            neck_fault(NeckError::NotHomed),
            StopCause::SensorFault(Sensor::NeckHome)
        );
        assert_eq!(
            neck_fault(NeckError::Pin { pin: "step" }),
            StopCause::SensorFault(Sensor::Neck)
        );
        assert_eq!(
            sonar_fault(SonarError::TriggerPin),
            StopCause::SensorFault(Sensor::SonarTrigger)
        );
    }
}
