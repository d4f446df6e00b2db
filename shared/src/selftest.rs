//! The bring-up self-test (`twil check`, issue 25 part 3): one pure step function that asks the
//! body for a fixed list of probes and turns the answers into rows `pass` / `fail` / `skip`,
//! each with the measured value, the expected range and a [`Hint`] the host prints.
//!
//! ## Shape
//!
//! [`SelfTest::step`] takes the answer to the last [`Probe`] and returns the next probe, or
//! `None` when the report is complete; it never waits and never touches a pin. A body that can
//! answer a probe at once implements [`CheckBody`] and calls [`run`]: the board's drivers
//! (`selftest::board`, the virtual board's tests too), the simulated plant of the QEMU build
//! and of `--remote sim` (`selftest::simulated`). A shell whose waits are `async` (the board
//! firmware) answers the same probes itself, one at a time. Every body therefore runs the same
//! judgement.
//!
//! ## The checks, in order
//!
//! 1. **clock**: given by the shell at [`SelfTest::new`] ([`ClockFacts`]): 168 MHz from the
//!    crystal on a board (the HSI fallback fails: timing off by up to 1 %); emulated under QEMU.
//! 2. **emergency stop**: read once; pressed fails (and the motors are skipped).
//! 3. **battery**: read once; below [`crate::drivers::motor::MIN_BATTERY_V`] or unreadable
//!    fails (and the motors are skipped); above [`MAX_BATTERY_V`] fails too (a wrong divider).
//! 4. **neck**: home, go to 0°, home again (steps `a`), then out to both limits
//!    (±`full_half_sweep_deg`) and back to 0°, home again (steps `b`): `|b − a|` is the steps
//!    lost on the way (expected at most [`MAX_LOST_STEPS`]).
//! 5. **sonar**: [`SWEEP_ANGLES_DEG`].len() pings over a short sweep: every ping must be
//!    answered (an echo pulse, even the no-target one); the nearest range is reported and a
//!    sweep with nothing in the window passes with a hint to put a target in front.
//! 6. **left motor, right motor**: a [`PULSE_V`] pulse of [`PULSE_ON_MS`] on one wheel, then
//!    [`COAST_MS`] at 0 V, counting its encoder: the count must move forward and lie within
//!    [`COUNT_RATIO_MIN`] … [`COUNT_RATIO_MAX`] of what the robot config predicts (the first-order
//!    motor model: gain, time constant, `encoder_pulses_per_rev`). The wheels must be off the
//!    floor.
//!
//! Bounded: at most [`MAX_PROBES`] probes, and each probe is bounded by its driver (a homing
//! by `max_homing_steps`, a ping by its window). With the default robot the board's probes take
//! 5.5 s (measured on the virtual board: three homings, the neck's trip to both limits, five
//! pings, two pulses of 0.8 s plus the e-stop's 150 ms of released polls each; `cargo test
//! --release -p twil-host --test suite virtual_board::selftest -- --nocapture` prints it).

use serde::{Deserialize, Serialize};

use crate::drivers::motor::MIN_BATTERY_V;
use crate::failsafe::{Sensor, StopCause};
use crate::math::exp;
use crate::robot::RobotConfig;

pub mod board;
pub mod simulated;

/// Rows a report holds (one per [`Check`] the device runs).
pub const MAX_CHECK_ROWS: usize = 8;
/// Probes one self-test asks at most.
pub const MAX_PROBES: usize = 32;
/// Neck angles of the sonar's short sweep, degrees.
pub const SWEEP_ANGLES_DEG: [f32; 5] = [-60.0, -30.0, 0.0, 30.0, 60.0];
/// Volts of a motor's test pulse (about half the 11.7 V limit: the wheel turns briskly, not
/// at full speed).
pub const PULSE_V: f32 = 6.0;
/// Length of the pulse, milliseconds.
pub const PULSE_ON_MS: u32 = 500;
/// Counting on after the pulse while the wheel coasts, milliseconds (three time constants of
/// the default motor).
pub const COAST_MS: u32 = 300;
/// Least measured / predicted counts of a pulse that passes.
pub const COUNT_RATIO_MIN: f32 = 0.5;
/// Most measured / predicted counts of a pulse that passes.
pub const COUNT_RATIO_MAX: f32 = 2.0;
/// Steps the neck may lose on its way out and back.
pub const MAX_LOST_STEPS: f32 = 1.0;
/// Highest plausible battery voltage, volts (a 4S pack full; more means a wrong divider).
pub const MAX_BATTERY_V: f32 = 16.8;
/// The core clock a board runs at, Hz.
pub const CORE_CLOCK_HZ: u32 = 168_000_000;

/// What a row checks.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Check {
    /// The core clock and its source.
    Clock,
    /// The emergency-stop input.
    EmergencyStop,
    /// The battery voltage.
    Battery,
    /// The neck: homing, limits, steps out and back.
    Neck,
    /// The sonar over a short sweep.
    Sonar,
    /// The left motor with its encoder.
    LeftMotor,
    /// The right motor with its encoder.
    RightMotor,
}

impl Check {
    /// The row's name (JSON and the table).
    pub fn name(self) -> &'static str {
        match self {
            Check::Clock => "clock",
            Check::EmergencyStop => "emergency_stop",
            Check::Battery => "battery",
            Check::Neck => "neck",
            Check::Sonar => "sonar",
            Check::LeftMotor => "left_motor",
            Check::RightMotor => "right_motor",
        }
    }
}

/// How a row ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CheckStatus {
    /// As expected.
    Pass,
    /// Not as expected: see the hint.
    Fail,
    /// Not run (another row's failure makes it unsafe or meaningless): see the hint.
    Skip,
}

/// What the user should look at; the host words it (with the side of a motor row).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Hint {
    /// Nothing to say.
    None,
    /// The core runs on the internal oscillator: the crystal did not start.
    ClockInternal,
    /// The e-stop reads pressed.
    EstopPressed,
    /// The e-stop input cannot be read.
    EstopUnreadable,
    /// The battery is below the motors' minimum.
    BatteryLow,
    /// The battery reads above any pack's voltage.
    BatteryHigh,
    /// The battery's ADC failed.
    BatteryUnreadable,
    /// The neck's home switch never closed.
    NeckHomeNotFound,
    /// A neck pin failed or a move beyond the limits was refused.
    NeckFault,
    /// The neck came back to a different place: lost steps.
    NeckLosesSteps,
    /// The sonar's echo line never rose.
    SonarSilent,
    /// The sonar's trigger failed.
    SonarTrigger,
    /// Every ping answered, nothing within the window.
    SonarNothingInRange,
    /// The encoder counted backwards while the motor was driven forward.
    EncoderBackwards,
    /// The encoder did not count.
    EncoderStill,
    /// The count is far from what the robot config predicts.
    EncoderCountsOff,
    /// A motor pin failed.
    MotorFault,
    /// Not run: the e-stop is pressed (or unreadable).
    SkippedEstop,
    /// Not run: the battery is not fit.
    SkippedBattery,
    /// Not run: this build has no such part.
    NotOnThisBuild,
}

/// One row of the report.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CheckRow {
    /// What was checked.
    pub check: Check,
    /// How it ended.
    pub status: CheckStatus,
    /// The measured value (unit by check: Hz, 1 pressed / 0 released, V, steps lost, pings
    /// answered, counts); NaN when not measured.
    pub value: f32,
    /// Lowest expected value.
    pub expected_min: f32,
    /// Highest expected value.
    pub expected_max: f32,
    /// A second measurement: the sonar's nearest range (m), a pulse's predicted counts, the
    /// neck's homing steps; NaN when none.
    pub detail: f32,
    /// What to look at.
    pub hint: Hint,
}

/// The self-test's report ([`crate::link::Reply::SelfTest`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SelfTestReport {
    /// Every row is in (false while the test runs).
    pub done: bool,
    /// The rows so far, in the order of the module documentation.
    pub rows: heapless::Vec<CheckRow, MAX_CHECK_ROWS>,
}

impl SelfTestReport {
    /// No row yet.
    pub const fn new() -> Self {
        Self {
            done: false,
            rows: heapless::Vec::new(),
        }
    }

    /// Rows that failed.
    pub fn failures(&self) -> usize {
        self.rows
            .iter()
            .filter(|r| r.status == CheckStatus::Fail)
            .count()
    }
}

impl Default for SelfTestReport {
    fn default() -> Self {
        Self::new()
    }
}

/// Where the core clock comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ClockSource {
    /// The board's crystal through the PLL.
    Crystal,
    /// The internal RC oscillator through the PLL (the crystal did not start).
    Internal,
    /// QEMU or the host: virtual time.
    Emulated,
}

/// What the shell knows of its clock.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClockFacts {
    /// The core clock, Hz.
    pub core_hz: u32,
    /// Its source.
    pub source: ClockSource,
}

/// A wheel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Side {
    /// The left wheel.
    Left,
    /// The right wheel.
    Right,
}

impl Side {
    /// `(left, right)` volts with `voltage_v` on this wheel and 0 on the other.
    pub fn volts(self, voltage_v: f32) -> (f32, f32) {
        match self {
            Side::Left => (voltage_v, 0.0),
            Side::Right => (0.0, voltage_v),
        }
    }

    /// This wheel's value of a `(left, right)` pair.
    pub fn of<T>(self, (left, right): (T, T)) -> T {
        match self {
            Side::Left => left,
            Side::Right => right,
        }
    }
}

/// What the self-test asks the body.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Probe {
    /// Read the emergency-stop input.
    EmergencyStop,
    /// Read the battery.
    Battery,
    /// Home the neck: the steps it took.
    NeckHome,
    /// Turn the neck to an angle, degrees (0 ahead).
    NeckTo(f32),
    /// One ping at a neck angle, degrees (the neck is moved first when it is homed).
    Sonar(f32),
    /// Drive one wheel at `voltage_v` for `on_ms`, then 0 V for `coast_ms`: its encoder's
    /// counts over both (positive forward). Both motors end at 0 V and disarmed.
    Pulse {
        /// Which wheel.
        side: Side,
        /// Volts.
        voltage_v: f32,
        /// Milliseconds driven.
        on_ms: u32,
        /// Milliseconds counted after.
        coast_ms: u32,
    },
}

/// One ping's outcome.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Echo {
    /// An echo within the window, metres.
    Range(f32),
    /// The module answered with its no-target pulse (or an echo outside the window).
    NoTarget,
    /// No edge at all on the echo line.
    Silent,
}

/// The body's answer to a [`Probe`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Answer {
    /// [`Probe::EmergencyStop`]: pressed, or the input's fault.
    EmergencyStop(Result<bool, StopCause>),
    /// [`Probe::Battery`]: volts, or the fault.
    Battery(Result<f32, StopCause>),
    /// [`Probe::NeckHome`] (the steps) and [`Probe::NeckTo`] (0).
    Neck(Result<u32, StopCause>),
    /// [`Probe::Sonar`].
    Sonar(Result<Echo, StopCause>),
    /// [`Probe::Pulse`]: the counts.
    Pulse(Result<i32, StopCause>),
    /// This body has no such part (a probe it cannot answer).
    Absent,
}

/// A body that answers probes at once (blocking): drivers with a delay, a simulated plant.
pub trait CheckBody {
    /// Answer one probe.
    fn probe(&mut self, probe: Probe) -> Answer;
}

/// Where the test stands: the next probe to ask, and what it has gathered.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Stage {
    Estop,
    Battery,
    /// Index into the neck's script.
    Neck(u8),
    /// Index into [`SWEEP_ANGLES_DEG`].
    Sonar(u8),
    Motor(Side),
    Done,
}

/// The neck's script (see the module documentation).
const NECK_SCRIPT: usize = 8;

/// The self-test: see the module documentation.
#[derive(Clone, Debug)]
pub struct SelfTest {
    config: RobotConfig,
    stage: Stage,
    report: SelfTestReport,
    probes: u32,
    motors_skip: Option<Hint>,
    neck_homed: bool,
    homing_a: u32,
    sonar_answered: u32,
    sonar_silent: u32,
    nearest_m: f32,
}

impl SelfTest {
    /// A test of a robot built as `config`, on a clock described by `clock` (its row is
    /// judged at once).
    pub fn new(config: &RobotConfig, clock: ClockFacts) -> Self {
        let mut test = Self {
            config: *config,
            stage: Stage::Estop,
            report: SelfTestReport::new(),
            probes: 0,
            motors_skip: None,
            neck_homed: false,
            homing_a: 0,
            sonar_answered: 0,
            sonar_silent: 0,
            nearest_m: f32::NAN,
        };
        let hz = clock.core_hz as f32;
        let (status, hint) = match clock.source {
            ClockSource::Internal => (CheckStatus::Fail, Hint::ClockInternal),
            _ if clock.core_hz == CORE_CLOCK_HZ => (CheckStatus::Pass, Hint::None),
            _ => (CheckStatus::Fail, Hint::None),
        };
        let target = CORE_CLOCK_HZ as f32;
        test.push(Check::Clock, status, hz, target, target, f32::NAN, hint);
        test
    }

    /// The report so far.
    pub fn report(&self) -> &SelfTestReport {
        &self.report
    }

    #[allow(clippy::too_many_arguments)]
    fn push(
        &mut self,
        check: Check,
        status: CheckStatus,
        value: f32,
        expected_min: f32,
        expected_max: f32,
        detail: f32,
        hint: Hint,
    ) {
        // Capacity: one row per check, MAX_CHECK_ROWS > the checks.
        let _ = self.report.rows.push(CheckRow {
            check,
            status,
            value,
            expected_min,
            expected_max,
            detail,
            hint,
        });
    }

    /// Take the answer to the last probe (`None` at the first call) and return the next probe,
    /// or `None` when the report is done. An answer of the wrong kind counts as [`Answer::Absent`].
    pub fn step(&mut self, answer: Option<Answer>) -> Option<Probe> {
        if let Some(answer) = answer {
            self.absorb(answer);
        }
        self.probes = self.probes.saturating_add(1);
        if self.probes as usize > MAX_PROBES {
            self.stage = Stage::Done;
        }
        let probe = self.probe_of(self.stage);
        if probe.is_none() {
            self.report.done = true;
        }
        probe
    }

    fn probe_of(&self, stage: Stage) -> Option<Probe> {
        let limit = self.config.full_half_sweep_deg;
        Some(match stage {
            Stage::Estop => Probe::EmergencyStop,
            Stage::Battery => Probe::Battery,
            Stage::Neck(i) => match i {
                0 | 2 | 6 => Probe::NeckHome,
                3 => Probe::NeckTo(limit),
                4 => Probe::NeckTo(-limit),
                _ => Probe::NeckTo(0.0),
            },
            Stage::Sonar(i) => Probe::Sonar(*SWEEP_ANGLES_DEG.get(i as usize)?),
            Stage::Motor(side) => Probe::Pulse {
                side,
                voltage_v: PULSE_V,
                on_ms: PULSE_ON_MS,
                coast_ms: COAST_MS,
            },
            Stage::Done => return None,
        })
    }

    fn absorb(&mut self, answer: Answer) {
        match (self.stage, answer) {
            (Stage::Estop, Answer::EmergencyStop(result)) => {
                let (status, value, hint) = match result {
                    Ok(false) => (CheckStatus::Pass, 0.0, Hint::None),
                    Ok(true) => (CheckStatus::Fail, 1.0, Hint::EstopPressed),
                    Err(_) => (CheckStatus::Fail, f32::NAN, Hint::EstopUnreadable),
                };
                if status == CheckStatus::Fail {
                    self.motors_skip = Some(Hint::SkippedEstop);
                }
                self.push(
                    Check::EmergencyStop,
                    status,
                    value,
                    0.0,
                    0.0,
                    f32::NAN,
                    hint,
                );
                self.stage = Stage::Battery;
            }
            (Stage::Battery, Answer::Battery(result)) => {
                let (status, value, hint) = match result {
                    Ok(v) if v < MIN_BATTERY_V => (CheckStatus::Fail, v, Hint::BatteryLow),
                    Ok(v) if v > MAX_BATTERY_V => (CheckStatus::Fail, v, Hint::BatteryHigh),
                    Ok(v) if v.is_finite() => (CheckStatus::Pass, v, Hint::None),
                    _ => (CheckStatus::Fail, f32::NAN, Hint::BatteryUnreadable),
                };
                if status == CheckStatus::Fail && self.motors_skip.is_none() {
                    self.motors_skip = Some(Hint::SkippedBattery);
                }
                let (lo, hi) = (MIN_BATTERY_V, MAX_BATTERY_V);
                self.push(Check::Battery, status, value, lo, hi, f32::NAN, hint);
                self.stage = Stage::Neck(0);
            }
            (Stage::Neck(i), Answer::Neck(result)) => self.neck(i, result),
            (Stage::Sonar(i), Answer::Sonar(result)) => self.sonar(i, result),
            (Stage::Motor(side), Answer::Pulse(result)) => self.pulse(side, result),
            (stage, _) => self.absent(stage),
        }
        self.skip_motors_if_needed();
    }

    /// The body cannot answer the stage's probe: its row is skipped.
    fn absent(&mut self, stage: Stage) {
        let nan = f32::NAN;
        let skip = CheckStatus::Skip;
        let hint = Hint::NotOnThisBuild;
        self.stage = match stage {
            Stage::Estop => {
                self.push(Check::EmergencyStop, skip, nan, 0.0, 0.0, nan, hint);
                Stage::Battery
            }
            Stage::Battery => {
                self.push(
                    Check::Battery,
                    skip,
                    nan,
                    MIN_BATTERY_V,
                    MAX_BATTERY_V,
                    nan,
                    hint,
                );
                Stage::Neck(0)
            }
            Stage::Neck(_) => {
                self.push(Check::Neck, skip, nan, 0.0, MAX_LOST_STEPS, nan, hint);
                Stage::Sonar(0)
            }
            Stage::Sonar(_) => {
                let pings = SWEEP_ANGLES_DEG.len() as f32;
                self.push(Check::Sonar, skip, nan, pings, pings, nan, hint);
                Stage::Motor(Side::Left)
            }
            Stage::Motor(side) => {
                self.push(motor_check(side), skip, nan, nan, nan, nan, hint);
                next_motor(side)
            }
            Stage::Done => Stage::Done,
        };
    }

    fn skip_motors_if_needed(&mut self) {
        if let (Stage::Motor(_), Some(hint)) = (self.stage, self.motors_skip) {
            let nan = f32::NAN;
            for side in [Side::Left, Side::Right] {
                self.push(
                    motor_check(side),
                    CheckStatus::Skip,
                    nan,
                    nan,
                    nan,
                    nan,
                    hint,
                );
            }
            self.stage = Stage::Done;
        }
    }

    fn neck(&mut self, i: u8, result: Result<u32, StopCause>) {
        let expected = (0.0, MAX_LOST_STEPS);
        let steps = match result {
            Ok(steps) => steps,
            Err(cause) => {
                let hint = match cause {
                    StopCause::SensorFault(Sensor::NeckHome) => Hint::NeckHomeNotFound,
                    _ => Hint::NeckFault,
                };
                let (lo, hi) = expected;
                self.push(
                    Check::Neck,
                    CheckStatus::Fail,
                    f32::NAN,
                    lo,
                    hi,
                    f32::NAN,
                    hint,
                );
                self.stage = Stage::Sonar(0);
                return;
            }
        };
        match i {
            0 => self.neck_homed = true,
            2 => self.homing_a = steps,
            6 => {
                let lost = (steps as f32 - self.homing_a as f32).abs();
                let (status, hint) = if lost <= MAX_LOST_STEPS {
                    (CheckStatus::Pass, Hint::None)
                } else {
                    (CheckStatus::Fail, Hint::NeckLosesSteps)
                };
                let (lo, hi) = expected;
                let homing = self.homing_a as f32;
                self.push(Check::Neck, status, lost, lo, hi, homing, hint);
            }
            _ => {}
        }
        self.stage = if (i as usize) + 1 < NECK_SCRIPT {
            Stage::Neck(i + 1)
        } else {
            Stage::Sonar(0)
        };
    }

    fn sonar(&mut self, i: u8, result: Result<Echo, StopCause>) {
        let pings = SWEEP_ANGLES_DEG.len() as f32;
        match result {
            Ok(Echo::Range(range_m)) => {
                self.sonar_answered += 1;
                if self.nearest_m.is_nan() || range_m < self.nearest_m {
                    self.nearest_m = range_m;
                }
            }
            Ok(Echo::NoTarget) => self.sonar_answered += 1,
            Ok(Echo::Silent) => self.sonar_silent += 1,
            Err(cause) => {
                let hint = match cause {
                    StopCause::SensorFault(Sensor::SonarSilent) => Hint::SonarSilent,
                    StopCause::SensorFault(Sensor::SonarTrigger) => Hint::SonarTrigger,
                    _ => Hint::NeckFault,
                };
                let answered = self.sonar_answered as f32;
                let nearest = self.nearest_m;
                self.push(
                    Check::Sonar,
                    CheckStatus::Fail,
                    answered,
                    pings,
                    pings,
                    nearest,
                    hint,
                );
                self.stage = Stage::Motor(Side::Left);
                return;
            }
        }
        if (i as usize) + 1 < SWEEP_ANGLES_DEG.len() {
            self.stage = Stage::Sonar(i + 1);
            return;
        }
        let answered = self.sonar_answered as f32;
        let (status, hint) = if self.sonar_silent > 0 {
            (CheckStatus::Fail, Hint::SonarSilent)
        } else if self.nearest_m.is_nan() {
            (CheckStatus::Pass, Hint::SonarNothingInRange)
        } else {
            (CheckStatus::Pass, Hint::None)
        };
        let nearest = self.nearest_m;
        self.push(Check::Sonar, status, answered, pings, pings, nearest, hint);
        self.stage = Stage::Motor(Side::Left);
    }

    fn pulse(&mut self, side: Side, result: Result<i32, StopCause>) {
        let predicted = predicted_pulse_counts(&self.config, PULSE_V, PULSE_ON_MS, COAST_MS);
        let (lo, hi) = (predicted * COUNT_RATIO_MIN, predicted * COUNT_RATIO_MAX);
        let (status, value, hint) = match result {
            Ok(counts) => {
                let c = counts as f32;
                if counts < 0 {
                    (CheckStatus::Fail, c, Hint::EncoderBackwards)
                } else if counts == 0 {
                    (CheckStatus::Fail, c, Hint::EncoderStill)
                } else if c < lo || c > hi {
                    (CheckStatus::Fail, c, Hint::EncoderCountsOff)
                } else {
                    (CheckStatus::Pass, c, Hint::None)
                }
            }
            Err(StopCause::SensorFault(Sensor::Battery)) => {
                (CheckStatus::Fail, f32::NAN, Hint::BatteryLow)
            }
            Err(StopCause::EmergencyStop) => (CheckStatus::Fail, f32::NAN, Hint::EstopPressed),
            Err(StopCause::SensorFault(Sensor::EmergencyStopInput)) => {
                (CheckStatus::Fail, f32::NAN, Hint::EstopUnreadable)
            }
            Err(_) => (CheckStatus::Fail, f32::NAN, Hint::MotorFault),
        };
        self.push(motor_check(side), status, value, lo, hi, predicted, hint);
        self.stage = next_motor(side);
    }
}

fn motor_check(side: Side) -> Check {
    match side {
        Side::Left => Check::LeftMotor,
        Side::Right => Check::RightMotor,
    }
}

fn next_motor(side: Side) -> Stage {
    match side {
        Side::Left => Stage::Motor(Side::Right),
        Side::Right => Stage::Done,
    }
}

/// Encoder counts the robot config predicts for a pulse of `voltage_v` for `on_ms`, then
/// `coast_ms` at 0 V, from rest: the first-order motor (gain K, time constant τ) turns the
/// wheel `K·V·(T − τ(1 − e^(−T/τ)))` radians while driven and `ω(T)·τ(1 − e^(−Tc/τ))` while it
/// coasts.
pub fn predicted_pulse_counts(
    config: &RobotConfig,
    voltage_v: f32,
    on_ms: u32,
    coast_ms: u32,
) -> f32 {
    let v = voltage_v.clamp(-config.max_voltage_v, config.max_voltage_v);
    let tau = config.motor_time_constant_s.max(1e-6);
    let on_s = on_ms as f32 / 1000.0;
    let coast_s = coast_ms as f32 / 1000.0;
    let speed = config.motor_gain_rad_s_per_v * v;
    let driven_rad = speed * (on_s - tau * (1.0 - exp(-on_s / tau)));
    let end_speed = speed * (1.0 - exp(-on_s / tau));
    let coast_rad = end_speed * tau * (1.0 - exp(-coast_s / tau));
    (driven_rad + coast_rad) / config.rad_per_count()
}

/// Run `test` to its end on a body that answers at once; the report.
pub fn run<'a>(test: &'a mut SelfTest, body: &mut impl CheckBody) -> &'a SelfTestReport {
    let mut answer = None;
    for _ in 0..=MAX_PROBES {
        match test.step(answer) {
            Some(probe) => answer = Some(body.probe(probe)),
            None => break,
        }
    }
    test.report()
}

#[cfg(test)]
mod tests;
