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

use super::{Answer, CheckBody, Echo, Probe, Side};
use crate::drivers::body::{neck_fault, sonar_fault, Chassis, SonarHead};
use crate::drivers::echo::EchoOutcome;
use crate::drivers::{BatterySensor, EchoCapture, QuadratureCounter};
use crate::failsafe::StopCause;
use crate::robot::RobotConfig;

/// Control periods a pulse may take beyond its own (the e-stop's released polls before duty).
const EXTRA_PERIODS: u32 = crate::drivers::emergency_stop::RELEASED_POLLS_TO_RUN + 1;

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
            Probe::Sonar(angle_deg) => Answer::Sonar(self.ping(angle_deg)),
            Probe::Pulse {
                side,
                voltage_v,
                on_ms,
                coast_ms,
            } => Answer::Pulse(self.pulse(side, voltage_v, on_ms, coast_ms)),
        }
    }
}

impl<PWML, DIRL, PWMR, DIRR, QL, QR, ESTOP, BAT, TRIG, ECHO, SD, STEP, DIR, HOME, ND, D>
    BoardCheck<
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
    /// One ping at `angle_deg` (the neck moved there first when it is homed).
    fn ping(&mut self, angle_deg: f32) -> Result<Echo, StopCause> {
        if self.head.neck().position_steps().is_some() {
            self.head
                .neck_mut()
                .move_to_angle(angle_deg)
                .map_err(neck_fault)?;
        }
        let reading = self.head.sonar_mut().read().map_err(sonar_fault)?;
        Ok(match (reading.outcome, reading.range_m) {
            (EchoOutcome::Silent, _) => Echo::Silent,
            (_, Some(range_m)) => Echo::Range(range_m),
            (_, None) => Echo::NoTarget,
        })
    }

    /// Drive one wheel for `on_ms` (counted from its first period with duty), then coast for
    /// `coast_ms`; the wheel's counts over all of it.
    fn pulse(
        &mut self,
        side: Side,
        voltage_v: f32,
        on_ms: u32,
        coast_ms: u32,
    ) -> Result<i32, StopCause> {
        let period_ms = ((self.config.controller_period_s * 1000.0) as u32).max(1);
        let on_periods = on_ms.div_ceil(period_ms);
        let coast_periods = coast_ms.div_ceil(period_ms);
        self.chassis.restart(&self.config)?;
        let _ = self.chassis.read_counts();
        let (left_v, right_v) = match side {
            Side::Left => (voltage_v, 0.0),
            Side::Right => (0.0, voltage_v),
        };
        let mut counts = 0i32;
        let mut driven = 0;
        let mut result = Ok(());
        for _ in 0..on_periods + EXTRA_PERIODS {
            let drive = self.chassis.drive(left_v, right_v);
            if let Some(cause) = drive.stop {
                result = Err(cause);
                break;
            }
            self.delay.delay_ms(period_ms);
            counts = counts.saturating_add(self.side_counts(side));
            if drive.left_v != 0.0 || drive.right_v != 0.0 {
                driven += 1;
                if driven >= on_periods {
                    break;
                }
            }
        }
        self.chassis.stop();
        for _ in 0..coast_periods {
            self.delay.delay_ms(period_ms);
            counts = counts.saturating_add(self.side_counts(side));
        }
        result.map(|()| counts)
    }

    fn side_counts(&mut self, side: Side) -> i32 {
        let (left, right) = self.chassis.read_counts();
        match side {
            Side::Left => left.counts,
            Side::Right => right.counts,
        }
    }
}

/// The chassis alone (a shell whose neck, sonar and wheel pulses are not wired for the test):
/// the e-stop and the battery are read, every other probe is [`Answer::Absent`] (its row
/// `skip`).
pub struct ChassisCheck<'a, C> {
    /// The wheels, the e-stop and the battery.
    pub chassis: &'a mut C,
}

impl<PWML, DIRL, PWMR, DIRR, QL, QR, ESTOP, BAT> CheckBody
    for ChassisCheck<'_, Chassis<PWML, DIRL, PWMR, DIRR, QL, QR, ESTOP, BAT>>
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
    fn probe(&mut self, probe: Probe) -> Answer {
        match probe {
            Probe::EmergencyStop => Answer::EmergencyStop(self.chassis.read_estop()),
            Probe::Battery => Answer::Battery(self.chassis.read_battery_v()),
            _ => Answer::Absent,
        }
    }
}
