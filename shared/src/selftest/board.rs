//! The self-test's probes on the board's drivers ([`Chassis`] and [`SonarHead`] of
//! `drivers::body`), blocking: every wait is the given delay. The virtual board's tests run it
//! on scripted pins; a firmware whose tasks cannot block answers the same probes stepwise.
//!
//! A motor pulse arms the chassis as a mission start does ([`Chassis::restart`]: refused while
//! the e-stop is pressed), drives one wheel every control period (the e-stop polled first, the
//! battery read, as in a mission), then 0 V while the wheel coasts, and disarms; the counts are
//! the wheel's encoder over all of it, forward positive (the mounting applied).

use embedded_hal::delay::DelayNs;
use embedded_hal::digital::{InputPin, OutputPin};
use embedded_hal::pwm::SetDutyCycle;

use super::{Answer, CheckBody, Echo, Probe};
use crate::drivers::body::{neck_fault, Chassis, SonarHead};
use crate::drivers::echo::EchoOutcome;
use crate::drivers::sonar_ranger::SonarReading;
use crate::drivers::{BatterySensor, EchoCapture, QuadratureCounter};
use crate::robot::RobotConfig;

/// The board's body for [`super::run`]: the chassis, the head, a delay for the control
/// periods of a pulse, and the robot they were built for.
pub struct BoardCheck<'a, C, H, D> {
    /// The wheels, the e-stop and the battery.
    pub chassis: &'a mut C,
    /// The neck and the sonar.
    pub head: &'a mut H,
    /// Waits between a pulse's control periods.
    pub delay: D,
    /// The robot (control period, voltage limit).
    pub config: RobotConfig,
}

impl<PWML, DIRL, PWMR, DIRR, QL, QR, ESTOP, BAT, TRIG, ECHO, SD, STEP, DIR, HOME, ND, D> CheckBody
    for BoardCheck<
        '_,
        Chassis<PWML, DIRL, PWMR, DIRR, QL, QR, ESTOP, BAT>,
        SonarHead<TRIG, ECHO, SD, STEP, DIR, HOME, ND>,
        D,
    >
where
    PWML: SetDutyCycle,
    DIRL: OutputPin,
    PWMR: SetDutyCycle,
    DIRR: OutputPin,
    QL: QuadratureCounter,
    QR: QuadratureCounter,
    ESTOP: InputPin,
    BAT: BatterySensor,
    TRIG: OutputPin,
    ECHO: EchoCapture,
    SD: DelayNs,
    STEP: OutputPin,
    DIR: OutputPin,
    HOME: InputPin,
    ND: DelayNs,
    D: DelayNs,
{
    fn probe(&mut self, probe: Probe) -> Answer {
        match probe {
            Probe::EmergencyStop => Answer::EmergencyStop(self.chassis.read_estop()),
            Probe::Battery => Answer::Battery(self.chassis.read_battery_v()),
            Probe::NeckHome => {
                self.head.configure(&self.config);
                Answer::Neck(self.head.neck_mut().home().map_err(neck_fault))
            }
            Probe::NeckTo(angle_deg) => Answer::Neck(
                self.head
                    .neck_mut()
                    .move_to_angle(angle_deg)
                    .map(|steps| steps.unsigned_abs())
                    .map_err(neck_fault),
            ),
            Probe::Sonar(angle_deg) => {
                Answer::Sonar(self.head.ping(angle_deg.to_radians()).map(|r| echo_of(&r)))
            }
            Probe::Pulse {
                side,
                voltage_v,
                on_ms,
                coast_ms,
            } => {
                let period_ms = ((self.config.controller_period_s * 1000.0) as u32).max(1);
                let periods = (
                    on_ms.div_ceil(period_ms),
                    coast_ms.div_ceil(period_ms),
                    period_ms,
                );
                let counts = self.chassis.pulse(
                    &self.config,
                    side.volts(voltage_v),
                    periods,
                    &mut self.delay,
                );
                Answer::Pulse(counts.map(|counts| side.of(counts)))
            }
        }
    }
}

/// A ping's reading as the self-test judges it: an echo line that never rose is
/// [`Echo::Silent`], the module's no-target pulse (or an echo outside the window)
/// [`Echo::NoTarget`].
pub fn echo_of(reading: &SonarReading) -> Echo {
    match (reading.outcome, reading.range_m) {
        (EchoOutcome::Silent, _) => Echo::Silent,
        (_, Some(range_m)) => Echo::Range(range_m),
        (_, None) => Echo::NoTarget,
    }
}
