//! Neck stepper: the sonar's neck on a step/direction driver, with a home switch.
//!
//! Seed 003 (`sonar.cpp`): `pmotor.reset()` puts the neck at its start, `pmotor.step(dir)` turns
//! it one step of 1.8° ([`RobotConfig::neck_step_deg`]) and a sweep steps from −95° to +95°
//! (±180° for a full look around), 1 ms per step ([`RobotConfig::neck_step_time_s`]).
//!
//! Here the driver (an A4988/DRV8825-style step/direction board) gets a step pulse of
//! [`STEP_PULSE_NS`] high per step, the rest of the step period low, and a direction level set
//! [`DIR_SETUP_NS`] before the first pulse. Position is counted in steps from straight ahead
//! (positive = counter-clockwise seen from above, the robot's positive angle). A stepper has no
//! position sensor, so the position is unknown (`None`) until homing has stepped towards the
//! home switch until it closes, bounded by [`NeckGeometry::max_homing_steps`] (a broken switch
//! gives [`NeckError::HomeNotFound`] after exactly that many steps, never an endless turn that
//! would wind up the sonar's cable); the switch's position is
//! [`NeckGeometry::home_offset_steps`].
//!
//! Timing (issue 24, finding 5), from the drivers' data sheets: DRV8825 (TI SLVSA73, timing
//! requirements: DIR set-up before the STEP rising edge t<sub>SU</sub> ≥ 650 ns, DIR hold
//! ≥ 650 ns, STEP high and low ≥ 1.9 µs); A4988 (Allegro, 200 ns set-up and hold, 1 µs
//! high and low). So: [`DIR_SETUP_NS`] = 1 µs after every direction change, the pulse
//! [`STEP_PULSE_NS`] = 2 µs high, and the direction only ever changes after a whole pulse and
//! its low time (hold: ≥ 2 µs). A stepper started at its full rate can stall and lose steps
//! with nothing to tell: a move starts at [`NeckGeometry::start_rate_steps_s`] and accelerates
//! at [`NeckGeometry::accel_steps_s2`] up to the configured rate (`1 / neck_step_time_s`), and
//! slows down the same way before its last step ([`ramp_period_ns`]); homing runs at the start
//! rate throughout, so the switch is met slowly. The start rate and acceleration
//! ([`START_RATE_STEPS_S`], [`ACCEL_STEPS_S2`]) are conservative guesses for a small 1.8°
//! motor carrying a sonar, to be checked on the robot: raise the start rate until the neck
//! misses the home switch's position after a sweep, then keep half.
//!
//! Two ways to drive it: the blocking [`NeckStepper::home`] / [`NeckStepper::move_to_angle`]
//! (over a [`DelayNs`]), or, for an async task, [`NeckStepper::begin_homing`] /
//! [`NeckStepper::begin_move_to_angle`] then [`NeckStepper::step`] until
//! [`NeckProgress::Done`], sleeping each [`NeckProgress::Wait`] in between (only the 1 µs
//! set-up and the 2 µs pulse are waited inside).
//!
//! Angles are limited to ±(180° + [`NECK_LIMIT_MARGIN_DEG`]): a full sweep needs ±180°, the
//! margin leaves room for the home switch just beyond it; a request outside is an error. An
//! angle goes to the nearest step (1.8° steps: 95° → 53 steps = 95.4°).

use embedded_hal::delay::DelayNs;
use embedded_hal::digital::{InputPin, OutputPin};

use super::emergency_stop::{is_active, ActiveLevel};
use crate::math::{floor, sqrt};
use crate::robot::RobotConfig;

/// Width of the step pulse, ns (A4988 needs 1 µs, DRV8825 1.9 µs).
pub const STEP_PULSE_NS: u32 = 2_000;

/// Wait between setting the direction and the next step's rising edge, ns (DRV8825 650 ns,
/// A4988 200 ns).
pub const DIR_SETUP_NS: u32 = 1_000;

/// Rate of the first step of a move and of homing, steps per second (see the module doc).
pub const START_RATE_STEPS_S: f32 = 200.0;

/// Acceleration of a move, steps per second² (200 → 1 000 steps/s in 120 steps, 0.2 s).
pub const ACCEL_STEPS_S2: f32 = 4_000.0;

/// Longest step period a ramp may ask for, ns (a start rate of 1 step/s).
pub const MAX_STEP_PERIOD_NS: u32 = 1_000_000_000;

/// How far past ±180° the neck may turn, degrees (two 1.8° steps): room for the home switch.
pub const NECK_LIMIT_MARGIN_DEG: f32 = 3.6;

/// Steps allowed beyond the full travel while homing, to tolerate a neck that starts slightly
/// past its limit.
pub const HOMING_EXTRA_STEPS: u32 = 10;

/// Shortest step period accepted, ns (a step pulse plus as much low time).
pub const MIN_STEP_PERIOD_NS: u32 = 2 * STEP_PULSE_NS;

/// Largest step count any geometry may describe (a 0.01° step over ±360°).
pub const MAX_LIMIT_STEPS: i32 = 36_000;

/// Which way a step turns the neck.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StepDirection {
    /// Towards positive angles (counter-clockwise from above).
    Positive,
    /// Towards negative angles.
    Negative,
}

/// The neck's geometry and timing.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct NeckGeometry {
    /// Angle per step, degrees.
    pub step_deg: f32,
    /// Largest |angle| a move may ask for, degrees.
    pub limit_deg: f32,
    /// Position of the home switch, steps from straight ahead.
    pub home_offset_steps: i32,
    /// Which way homing turns.
    pub homing_direction: StepDirection,
    /// Most steps homing may take before it gives up.
    pub max_homing_steps: u32,
    /// Time per step at full rate, ns (pulse high + low).
    pub step_period_ns: u32,
    /// Rate of the first step of a move, and of homing, steps per second.
    pub start_rate_steps_s: f32,
    /// Acceleration (and deceleration) of a move, steps per second².
    pub accel_steps_s2: f32,
    /// Level of the direction pin for [`StepDirection::Positive`] (`true` = high).
    pub positive_dir_high: bool,
    /// Level of the home switch when closed.
    pub home_active: ActiveLevel,
}

impl NeckGeometry {
    /// The geometry of `config`: its step angle and step time, limits ±(180° + margin), the
    /// home switch at the negative limit, homing towards negative angles over at most the full
    /// travel plus [`HOMING_EXTRA_STEPS`], direction high = positive, switch active low, the
    /// ramp of [`START_RATE_STEPS_S`] and [`ACCEL_STEPS_S2`].
    pub fn from_config(config: &RobotConfig) -> Self {
        let mut g = Self {
            step_deg: config.neck_step_deg,
            limit_deg: 180.0 + NECK_LIMIT_MARGIN_DEG,
            home_offset_steps: 0,
            homing_direction: StepDirection::Negative,
            max_homing_steps: 0,
            step_period_ns: seconds_to_ns(config.neck_step_time_s),
            start_rate_steps_s: START_RATE_STEPS_S,
            accel_steps_s2: ACCEL_STEPS_S2,
            positive_dir_high: true,
            home_active: ActiveLevel::Low,
        };
        let limit = g.limit_steps().unwrap_or(0);
        g.home_offset_steps = -limit;
        g.max_homing_steps = (2 * limit as u32).saturating_add(HOMING_EXTRA_STEPS);
        g
    }

    /// Largest |position| in steps: ⌊limit / step⌋. Error when the step or limit is not a
    /// finite positive number or gives more than [`MAX_LIMIT_STEPS`].
    pub fn limit_steps(&self) -> Result<i32, NeckError> {
        if !(self.step_deg.is_finite() && self.step_deg > 0.0) {
            return Err(NeckError::BadStep {
                step_deg: self.step_deg,
            });
        }
        if !(self.limit_deg.is_finite() && self.limit_deg >= 0.0) {
            return Err(NeckError::BadLimit {
                limit_deg: self.limit_deg,
            });
        }
        // The small epsilon keeps 183.6 / 1.8 = 101.99999 at 102.
        let n = floor(self.limit_deg / self.step_deg + 1e-4);
        if n > MAX_LIMIT_STEPS as f32 {
            return Err(NeckError::BadLimit {
                limit_deg: self.limit_deg,
            });
        }
        Ok(n as i32)
    }
}

fn seconds_to_ns(s: f32) -> u32 {
    let ns = s * 1e9;
    if ns.is_nan() || ns <= 0.0 {
        0
    } else if ns >= u32::MAX as f32 {
        u32::MAX
    } else {
        ns as u32
    }
}

/// The period of step `index` (0-based) of a move of `total` steps, ns: the rate
/// `√(start² + 2·accel·k)`, k the steps from the nearer end of the move, capped at the full
/// rate (`step_period_ns`), never shorter than [`MIN_STEP_PERIOD_NS`] nor longer than
/// [`MAX_STEP_PERIOD_NS`] (a start rate or acceleration that is not a positive number gives
/// the longest).
///
/// ```
/// use twil_core::drivers::neck_stepper::{ramp_period_ns, NeckGeometry};
/// use twil_core::robot::RobotConfig;
/// let g = NeckGeometry::from_config(&RobotConfig::default());
/// assert_eq!(ramp_period_ns(&g, 0, 1), 5_000_000); // one step: at the 200 steps/s start rate
/// assert_eq!(ramp_period_ns(&g, 150, 300), 1_000_000); // mid-way: at the full 1 000 steps/s
/// ```
pub fn ramp_period_ns(geometry: &NeckGeometry, index: u32, total: u32) -> u32 {
    let cruise_ns = geometry.step_period_ns.max(MIN_STEP_PERIOD_NS);
    let from_end = index.min(total.saturating_sub(1).saturating_sub(index));
    let start = geometry.start_rate_steps_s;
    let accel = geometry.accel_steps_s2;
    if !(start.is_finite() && start > 0.0 && accel.is_finite() && accel >= 0.0) {
        return MAX_STEP_PERIOD_NS.max(cruise_ns);
    }
    let rate = sqrt(start * start + 2.0 * accel * from_end as f32);
    let ns = 1e9 / rate;
    if ns.is_nan() || ns >= MAX_STEP_PERIOD_NS as f32 {
        MAX_STEP_PERIOD_NS.max(cruise_ns)
    } else {
        (ns as u32).max(cruise_ns)
    }
}

/// Where a stepwise move stands after [`NeckStepper::step`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum NeckProgress {
    /// A step was sent: wait this long, ns, then call [`NeckStepper::step`] again.
    Wait {
        /// Time to the next step, ns.
        ns: u32,
    },
    /// The move (or homing) is over: the position is known. Steps taken.
    Done {
        /// Steps sent by the move or homing.
        steps: u32,
    },
}

/// The move under way.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Motion {
    Idle,
    Homing { steps: u32 },
    Moving { target: i32, done: u32, total: u32 },
}

/// What went wrong with the neck.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum NeckError {
    /// The requested angle is beyond ±`limit_deg` or not a number.
    AngleOutOfRange {
        /// The request, degrees.
        angle_deg: f32,
        /// The limit, degrees.
        limit_deg: f32,
    },
    /// The step angle is not a finite positive number.
    BadStep {
        /// The step, degrees.
        step_deg: f32,
    },
    /// The limit is not a finite number ≥ 0 or too many steps.
    BadLimit {
        /// The limit, degrees.
        limit_deg: f32,
    },
    /// The home switch did not close within `steps` steps.
    HomeNotFound {
        /// Steps taken.
        steps: u32,
    },
    /// The position is unknown: home first.
    NotHomed,
    /// The named pin (`"step"`, `"dir"`, `"home"`) failed.
    Pin {
        /// Which pin.
        pin: &'static str,
    },
}

impl core::fmt::Display for NeckError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            NeckError::AngleOutOfRange {
                angle_deg,
                limit_deg,
            } => write!(f, "neck angle {angle_deg} deg is beyond ±{limit_deg} deg"),
            NeckError::BadStep { step_deg } => write!(
                f,
                "neck step {step_deg} deg is not a finite positive number"
            ),
            NeckError::BadLimit { limit_deg } => write!(
                f,
                "neck limit {limit_deg} deg is not a finite number ≥ 0, or too many steps"
            ),
            NeckError::HomeNotFound { steps } => {
                write!(
                    f,
                    "the neck's home switch did not close within {steps} steps"
                )
            }
            NeckError::NotHomed => write!(f, "the neck's position is unknown: home it first"),
            NeckError::Pin { pin } => write!(f, "the neck's {pin} pin failed"),
        }
    }
}

impl core::error::Error for NeckError {}

/// The nearest step to `angle_deg` within ±`limit_deg`, or an error naming the angle.
///
/// ```
/// use twil_core::drivers::neck_stepper::{angle_to_steps, NeckGeometry};
/// use twil_core::robot::RobotConfig;
/// let g = NeckGeometry::from_config(&RobotConfig::default());
/// assert_eq!(angle_to_steps(&g, 95.0), Ok(53)); // 95.4°
/// assert_eq!(angle_to_steps(&g, -180.0), Ok(-100));
/// assert!(angle_to_steps(&g, 200.0).is_err());
/// ```
pub fn angle_to_steps(geometry: &NeckGeometry, angle_deg: f32) -> Result<i32, NeckError> {
    let limit_steps = geometry.limit_steps()?;
    let out = NeckError::AngleOutOfRange {
        angle_deg,
        limit_deg: geometry.limit_deg,
    };
    if !(angle_deg.is_finite() && angle_deg.abs() <= geometry.limit_deg) {
        return Err(out);
    }
    let steps = floor(angle_deg / geometry.step_deg + 0.5) as i32;
    // Rounding may land one step past the limit when the limit is not a whole number of steps.
    Ok(steps.clamp(-limit_steps, limit_steps))
}

/// The angle of a position, degrees.
pub fn steps_to_angle_deg(geometry: &NeckGeometry, steps: i32) -> f32 {
    steps as f32 * geometry.step_deg
}

/// The neck driver: step and direction outputs, home switch input, a delay.
pub struct NeckStepper<STEP, DIR, HOME, D> {
    step: STEP,
    dir: DIR,
    home: HOME,
    delay: D,
    geometry: NeckGeometry,
    position_steps: Option<i32>,
    steps_taken: u32,
    motion: Motion,
}

impl<STEP, DIR, HOME, D> NeckStepper<STEP, DIR, HOME, D>
where
    STEP: OutputPin,
    DIR: OutputPin,
    HOME: InputPin,
    D: DelayNs,
{
    /// A neck with unknown position.
    pub fn new(step: STEP, dir: DIR, home: HOME, delay: D, geometry: NeckGeometry) -> Self {
        Self {
            step,
            dir,
            home,
            delay,
            geometry,
            position_steps: None,
            steps_taken: 0,
            motion: Motion::Idle,
        }
    }

    /// The geometry in use.
    pub fn geometry(&self) -> NeckGeometry {
        self.geometry
    }

    /// Use `geometry` from now on (a new mission's config). The position becomes unknown: home
    /// again (the step angle or the switch's place may have changed).
    pub fn set_geometry(&mut self, geometry: NeckGeometry) {
        self.geometry = geometry;
        self.position_steps = None;
        self.motion = Motion::Idle;
    }

    /// Position in steps from straight ahead; `None` until homed (or after a pin error, or
    /// during a move).
    pub fn position_steps(&self) -> Option<i32> {
        self.position_steps
    }

    /// Position as an angle, degrees; `None` until homed.
    pub fn angle_deg(&self) -> Option<f32> {
        self.position_steps
            .map(|s| steps_to_angle_deg(&self.geometry, s))
    }

    /// Step pulses sent since start (wrapping), for telemetry.
    pub fn steps_taken(&self) -> u32 {
        self.steps_taken
    }

    /// Set the direction level, then wait [`DIR_SETUP_NS`] before any step.
    fn set_direction(&mut self, direction: StepDirection) -> Result<(), NeckError> {
        let high = (direction == StepDirection::Positive) == self.geometry.positive_dir_high;
        let r = if high {
            self.dir.set_high()
        } else {
            self.dir.set_low()
        };
        r.map_err(|_| NeckError::Pin { pin: "dir" })?;
        self.delay.delay_ns(DIR_SETUP_NS);
        Ok(())
    }

    /// One step pulse: high for [`STEP_PULSE_NS`], then low.
    fn pulse(&mut self) -> Result<(), NeckError> {
        self.step
            .set_high()
            .map_err(|_| NeckError::Pin { pin: "step" })?;
        self.delay.delay_ns(STEP_PULSE_NS);
        let low = self.step.set_low();
        self.steps_taken = self.steps_taken.wrapping_add(1);
        low.map_err(|_| NeckError::Pin { pin: "step" })
    }

    /// Start homing: the position becomes unknown, the direction is set towards the switch.
    /// Then call [`step`](Self::step) until [`NeckProgress::Done`].
    pub fn begin_homing(&mut self) -> Result<(), NeckError> {
        self.position_steps = None;
        self.motion = Motion::Idle;
        self.set_direction(self.geometry.homing_direction)?;
        self.motion = Motion::Homing { steps: 0 };
        Ok(())
    }

    /// Start a move to the step nearest `angle_deg`. Errors: out of range, not homed (nothing
    /// moves), the direction pin.
    pub fn begin_move_to_angle(&mut self, angle_deg: f32) -> Result<(), NeckError> {
        let target = angle_to_steps(&self.geometry, angle_deg)?;
        self.begin_move_to_steps(target)
    }

    /// Start a move to `target_steps` (within the limits); same contract as
    /// [`begin_move_to_angle`](Self::begin_move_to_angle). The position is unknown until the
    /// move is done.
    pub fn begin_move_to_steps(&mut self, target_steps: i32) -> Result<(), NeckError> {
        let limit = self.geometry.limit_steps()?;
        if target_steps.unsigned_abs() > limit.unsigned_abs() {
            return Err(NeckError::AngleOutOfRange {
                angle_deg: steps_to_angle_deg(&self.geometry, target_steps),
                limit_deg: self.geometry.limit_deg,
            });
        }
        let start = self.position_steps.ok_or(NeckError::NotHomed)?;
        // In i64: a home offset set far outside the limits must not overflow.
        let delta = i64::from(target_steps) - i64::from(start);
        let total = u32::try_from(delta.unsigned_abs()).unwrap_or(u32::MAX);
        self.position_steps = None;
        self.motion = Motion::Idle;
        if total > 0 {
            self.set_direction(if delta > 0 {
                StepDirection::Positive
            } else {
                StepDirection::Negative
            })?;
        }
        self.motion = Motion::Moving {
            target: target_steps,
            done: 0,
            total,
        };
        Ok(())
    }

    /// The next step of the move or homing under way: sends one pulse and says how long to
    /// wait before the next call, or says it is done (then the position is known). With no
    /// move under way: `Done` with 0 steps. Errors end the move (position unknown):
    /// [`NeckError::HomeNotFound`] after [`NeckGeometry::max_homing_steps`], a pin error.
    pub fn step(&mut self) -> Result<NeckProgress, NeckError> {
        match self.motion {
            Motion::Idle => Ok(NeckProgress::Done { steps: 0 }),
            Motion::Homing { steps } => {
                self.motion = Motion::Idle;
                // A switch that cannot be read is an error, not "closed": homing would
                // otherwise stop at a wrong place.
                let high = self
                    .home
                    .is_high()
                    .map_err(|_| NeckError::Pin { pin: "home" })?;
                if is_active::<()>(Ok(high), self.geometry.home_active) {
                    self.position_steps = Some(self.geometry.home_offset_steps);
                    return Ok(NeckProgress::Done { steps });
                }
                if steps >= self.geometry.max_homing_steps {
                    return Err(NeckError::HomeNotFound { steps });
                }
                self.pulse()?;
                self.motion = Motion::Homing { steps: steps + 1 };
                // Homing runs at the start rate all the way.
                let period = ramp_period_ns(&self.geometry, 0, 1);
                Ok(NeckProgress::Wait {
                    ns: period.saturating_sub(STEP_PULSE_NS),
                })
            }
            Motion::Moving {
                target,
                done,
                total,
            } => {
                self.motion = Motion::Idle;
                if done >= total {
                    self.position_steps = Some(target);
                    return Ok(NeckProgress::Done { steps: total });
                }
                self.pulse()?;
                self.motion = Motion::Moving {
                    target,
                    done: done + 1,
                    total,
                };
                let period = ramp_period_ns(&self.geometry, done, total);
                Ok(NeckProgress::Wait {
                    ns: period.saturating_sub(STEP_PULSE_NS),
                })
            }
        }
    }

    /// Run the move (or homing) under way to its end, waiting with the delay (blocking).
    /// Returns the steps taken.
    pub fn finish(&mut self) -> Result<u32, NeckError> {
        loop {
            match self.step()? {
                NeckProgress::Wait { ns } => self.delay.delay_ns(ns),
                NeckProgress::Done { steps } => return Ok(steps),
            }
        }
    }

    /// Step towards the home switch until it closes (blocking); the position is then
    /// [`NeckGeometry::home_offset_steps`]. Returns the steps taken. At most
    /// [`NeckGeometry::max_homing_steps`] steps, then [`NeckError::HomeNotFound`].
    pub fn home(&mut self) -> Result<u32, NeckError> {
        self.begin_homing()?;
        self.finish()
    }

    /// Turn to the step nearest `angle_deg` (blocking). Returns the steps moved (signed).
    /// Errors: not homed, out of range (nothing moves), a pin error (the position becomes
    /// unknown).
    pub fn move_to_angle(&mut self, angle_deg: f32) -> Result<i32, NeckError> {
        let target = angle_to_steps(&self.geometry, angle_deg)?;
        self.move_to_steps(target)
    }

    /// Turn to `target_steps` (within the limits, blocking). Same contract as
    /// [`move_to_angle`](Self::move_to_angle).
    pub fn move_to_steps(&mut self, target_steps: i32) -> Result<i32, NeckError> {
        let start = self.position_steps;
        self.begin_move_to_steps(target_steps)?;
        self.finish()?;
        let delta = start.map_or(0, |s| i64::from(target_steps) - i64::from(s));
        Ok(i32::try_from(delta).unwrap_or(if delta > 0 { i32::MAX } else { i32::MIN }))
    }

    /// Give the pins back.
    pub fn release(self) -> (STEP, DIR, HOME, D) {
        (self.step, self.dir, self.home, self.delay)
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::vec::Vec;

    use super::*;
    use embedded_hal_mock::eh1::delay::{CheckedDelay, NoopDelay, Transaction as DelayTx};
    use embedded_hal_mock::eh1::digital::{
        Mock as PinMock, State as PinState, Transaction as PinTx,
    };
    use embedded_hal_mock::eh1::MockError;

    fn geometry() -> NeckGeometry {
        NeckGeometry::from_config(&RobotConfig::default())
    }

    fn step_pulses(n: usize) -> Vec<PinTx> {
        let mut v = Vec::new();
        for _ in 0..n {
            v.push(PinTx::set(PinState::High));
            v.push(PinTx::set(PinState::Low));
        }
        v
    }

    /// Home switch reads (active low): `open_checks` open, then one closed if `closes`.
    fn home_reads(open_checks: usize, closes: bool) -> Vec<PinTx> {
        let mut v = Vec::new();
        for _ in 0..open_checks {
            v.push(PinTx::get(PinState::High));
        }
        if closes {
            v.push(PinTx::get(PinState::Low));
        }
        v
    }

    #[test]
    fn geometry_from_the_default_config() {
        let g = geometry();
        assert_eq!(g.limit_steps(), Ok(102));
        assert_eq!(g.home_offset_steps, -102);
        assert_eq!(g.max_homing_steps, 214);
        assert_eq!(g.step_period_ns, 1_000_000);
        assert_eq!(g.start_rate_steps_s, 200.0);
        let bad = NeckGeometry { step_deg: 0.0, ..g };
        assert_eq!(bad.limit_steps(), Err(NeckError::BadStep { step_deg: 0.0 }));
        let tiny = NeckGeometry {
            step_deg: 1e-6,
            ..g
        };
        assert!(matches!(
            tiny.limit_steps(),
            Err(NeckError::BadLimit { .. })
        ));
    }

    #[test]
    fn moves_ramp_up_from_the_start_rate_and_down_again() {
        let g = geometry();
        let periods: Vec<u32> = (0..300).map(|i| ramp_period_ns(&g, i, 300)).collect();
        assert_eq!(periods[0], 5_000_000);
        assert_eq!(periods[299], 5_000_000);
        // √(200² + 2·4000·1) = 219.1 steps/s.
        assert_eq!(periods[1], 4_564_354);
        assert!(periods.windows(2).take(150).all(|w| w[1] <= w[0]));
        assert!(periods.windows(2).skip(150).all(|w| w[1] >= w[0]));
        // Full rate from (1000² − 200²) / (2·4000) = 120 steps on.
        assert_eq!(periods[121], 1_000_000);
        assert!(periods[118] > 1_000_000);
        assert_eq!(periods[150], 1_000_000);
        // A bad ramp is the slowest, never a division by zero.
        let stalled = NeckGeometry {
            start_rate_steps_s: 0.0,
            ..g
        };
        assert_eq!(ramp_period_ns(&stalled, 0, 1), MAX_STEP_PERIOD_NS);
        let nan = NeckGeometry {
            accel_steps_s2: f32::NAN,
            ..g
        };
        assert_eq!(ramp_period_ns(&nan, 5, 10), MAX_STEP_PERIOD_NS);
        assert_eq!(ramp_period_ns(&g, 0, 0), 5_000_000);
    }

    #[test]
    fn stepwise_moves_report_their_waits() {
        let mut step = PinMock::new(&step_pulses(2));
        let mut dir = PinMock::new(&[PinTx::set(PinState::Low), PinTx::set(PinState::High)]);
        let mut home = PinMock::new(&home_reads(0, true));
        let mut neck = NeckStepper::new(
            step.clone(),
            dir.clone(),
            home.clone(),
            NoopDelay::new(),
            geometry(),
        );
        neck.begin_homing().unwrap();
        assert_eq!(neck.step(), Ok(NeckProgress::Done { steps: 0 }));
        neck.begin_move_to_steps(-100).unwrap();
        assert_eq!(neck.position_steps(), None);
        assert_eq!(neck.step(), Ok(NeckProgress::Wait { ns: 4_998_000 }));
        assert_eq!(neck.step(), Ok(NeckProgress::Wait { ns: 4_998_000 }));
        assert_eq!(neck.step(), Ok(NeckProgress::Done { steps: 2 }));
        assert_eq!(neck.position_steps(), Some(-100));
        // Nothing under way: done at once.
        assert_eq!(neck.step(), Ok(NeckProgress::Done { steps: 0 }));
        step.done();
        dir.done();
        home.done();
    }

    #[test]
    fn angles_go_to_the_nearest_step_within_the_limits() {
        let g = geometry();
        assert_eq!(angle_to_steps(&g, 0.0), Ok(0));
        assert_eq!(angle_to_steps(&g, 0.8), Ok(0));
        assert_eq!(angle_to_steps(&g, 1.0), Ok(1));
        assert_eq!(angle_to_steps(&g, -95.0), Ok(-53));
        assert_eq!(angle_to_steps(&g, 180.0), Ok(100));
        assert_eq!(angle_to_steps(&g, 183.6), Ok(102));
        assert_eq!(
            angle_to_steps(&g, 183.7),
            Err(NeckError::AngleOutOfRange {
                angle_deg: 183.7,
                limit_deg: 183.6
            })
        );
        assert!(angle_to_steps(&g, f32::NAN).is_err());
        assert!(angle_to_steps(&g, f32::NEG_INFINITY).is_err());
        assert!((steps_to_angle_deg(&g, 53) - 95.4).abs() < 1e-4);
    }

    #[test]
    fn homing_finds_the_switch_and_sets_the_offset() {
        let g = NeckGeometry {
            max_homing_steps: 10,
            ..geometry()
        };
        let mut step = PinMock::new(&step_pulses(3));
        let mut dir = PinMock::new(&[PinTx::set(PinState::Low)]); // negative
        let mut home = PinMock::new(&home_reads(3, true));
        // Direction set-up, then three pulses at the 200 steps/s start rate.
        let mut delay = CheckedDelay::new(&[
            DelayTx::delay_ns(DIR_SETUP_NS),
            DelayTx::delay_ns(2_000),
            DelayTx::delay_ns(4_998_000),
            DelayTx::delay_ns(2_000),
            DelayTx::delay_ns(4_998_000),
            DelayTx::delay_ns(2_000),
            DelayTx::delay_ns(4_998_000),
        ]);
        let mut neck = NeckStepper::new(step.clone(), dir.clone(), home.clone(), delay.clone(), g);
        assert_eq!(neck.position_steps(), None);
        assert_eq!(neck.home(), Ok(3));
        assert_eq!(neck.position_steps(), Some(-102));
        assert_eq!(neck.steps_taken(), 3);
        step.done();
        dir.done();
        home.done();
        delay.done();
    }

    #[test]
    fn homing_without_a_switch_fails_after_exactly_n_steps() {
        let n = 5;
        let g = NeckGeometry {
            max_homing_steps: n,
            ..geometry()
        };
        let mut step = PinMock::new(&step_pulses(n as usize));
        let mut dir = PinMock::new(&[PinTx::set(PinState::Low)]);
        let mut home = PinMock::new(&home_reads(n as usize + 1, false));
        let mut neck =
            NeckStepper::new(step.clone(), dir.clone(), home.clone(), NoopDelay::new(), g);
        assert_eq!(neck.home(), Err(NeckError::HomeNotFound { steps: n }));
        assert_eq!(neck.steps_taken(), n);
        assert_eq!(neck.position_steps(), None);
        step.done();
        dir.done();
        home.done();
    }

    #[test]
    fn an_unreadable_home_switch_is_an_error_not_home() {
        let err = MockError::Io(std::io::ErrorKind::Other);
        let mut step = PinMock::new(&[]);
        let mut dir = PinMock::new(&[PinTx::set(PinState::Low)]);
        let mut home = PinMock::new(&[PinTx::get(PinState::Low).with_error(err)]);
        let mut neck = NeckStepper::new(
            step.clone(),
            dir.clone(),
            home.clone(),
            NoopDelay::new(),
            geometry(),
        );
        assert_eq!(neck.home(), Err(NeckError::Pin { pin: "home" }));
        assert_eq!(neck.position_steps(), None);
        step.done();
        dir.done();
        home.done();
    }

    #[test]
    fn moves_count_steps_and_set_direction() {
        let mut step = PinMock::new(&step_pulses(102 + 53 + 2));
        let mut dir = PinMock::new(&[
            PinTx::set(PinState::Low),  // homing: negative
            PinTx::set(PinState::High), // -102 -> 0: positive
            PinTx::set(PinState::High), // 0 -> +95°: positive again (set before every move)
            PinTx::set(PinState::Low),  // back 2 steps
        ]);
        let mut home = PinMock::new(&home_reads(0, true));
        let mut neck = NeckStepper::new(
            step.clone(),
            dir.clone(),
            home.clone(),
            NoopDelay::new(),
            geometry(),
        );
        assert_eq!(neck.move_to_angle(10.0), Err(NeckError::NotHomed));
        assert_eq!(neck.home(), Ok(0));
        assert_eq!(neck.move_to_angle(0.0), Ok(102));
        assert_eq!(neck.move_to_angle(95.0), Ok(53));
        assert!((neck.angle_deg().unwrap() - 95.4).abs() < 1e-4);
        assert_eq!(neck.move_to_angle(95.4), Ok(0));
        assert_eq!(neck.move_to_angle(91.8), Ok(-2));
        assert_eq!(neck.position_steps(), Some(51));
        assert_eq!(neck.steps_taken(), 157);
        // Out of range: nothing moves, position kept.
        assert!(matches!(
            neck.move_to_angle(-190.0),
            Err(NeckError::AngleOutOfRange { .. })
        ));
        assert!(matches!(
            neck.move_to_steps(103),
            Err(NeckError::AngleOutOfRange { .. })
        ));
        assert_eq!(neck.position_steps(), Some(51));
        step.done();
        dir.done();
        home.done();
    }

    #[test]
    fn a_step_pin_error_midway_makes_the_position_unknown() {
        let err = MockError::Io(std::io::ErrorKind::Other);
        let mut tx = step_pulses(1);
        tx.push(PinTx::set(PinState::High).with_error(err));
        let mut step = PinMock::new(&tx);
        let mut dir = PinMock::new(&[PinTx::set(PinState::Low), PinTx::set(PinState::High)]);
        let mut home = PinMock::new(&home_reads(0, true));
        let mut neck = NeckStepper::new(
            step.clone(),
            dir.clone(),
            home.clone(),
            NoopDelay::new(),
            geometry(),
        );
        assert_eq!(neck.home(), Ok(0));
        assert_eq!(
            neck.move_to_steps(-100),
            Err(NeckError::Pin { pin: "step" })
        );
        assert_eq!(neck.position_steps(), None);
        step.done();
        dir.done();
        home.done();
    }
}
