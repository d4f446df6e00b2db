//! Sonar ranger: a trigger pulse out, an echo timed back, a range in metres or *no echo*.
//!
//! Seed 003 (`le_sonar.c`, `sonar.cpp`): for each neck step the reader thread calls `trig()` on
//! one of the two sonars, waits a fixed time sized for the farthest echo it cares about (so that
//! an old echo cannot spill into the next reading), converts the time of flight to a distance
//! and keeps it only inside `DIST_MIN` … `ALCANCE_SONAR`. Here:
//!
//! 1. an [`EchoCapture`] (a timer's input capture on the board) is armed, then the trigger pin
//!    goes high for [`TRIGGER_PULSE_US`] µs (HC-SR04: at least 10 µs);
//! 2. the capture hands over the echo line's edges with their polarity, and an
//!    [`EchoDecoder`] turns them into a pulse width or the reason
//!    there is none (`echo.rs`: polarity and order, the glitch filter, the 38 ms no-target
//!    pulse, the listen time);
//! 3. [`range_from_echo_ticks`] converts the width → seconds → metres with
//!    [`sonar::time_of_flight_to_range_m`](crate::sonar::time_of_flight_to_range_m) (343.2 m/s)
//!    and applies the window ([`RobotConfig::sonar_min_range_m`] 0.26 m …
//!    [`RobotConfig::sonar_range_m`] 1.5 m, and the time-out [`RobotConfig::echo_wait_s`]):
//!    outside it is `None` = no echo;
//! 4. the blocking [`SonarRanger::read`] then waits out the rest of the cycle
//!    ([`cycle_us`], at least the HC-SR04's 60 ms), so a late echo of
//!    one ping is not heard by the next.
//!
//! **Departure from the seed and from the mission's model**: the seed waited one fixed window
//! per reading and the mission's timing model charges `echo_wait_s + neck_step_time_s` (36 ms)
//! per reading; an HC-SR04 needs a 60 ms cycle, so on the board a reading takes at least 60 ms
//! (a 105-reading sweep 6.3 s instead of 3.8 s). The model is left as it is (changing
//! `RobotConfig::DEFAULT` changes every simulated mission); a ranger with a shorter cycle
//! (the seed's) would match it.
//!
//! An async firmware task does the same with the pure parts: arm, pulse, feed the decoder with
//! the capture's edges and `Mono::delay_until` its [`deadline_ticks`](super::echo::EchoDecoder::deadline_ticks),
//! convert with [`range_from_echo_ticks`], sleep the rest of [`cycle_us`].
//!
//! [`RobotConfig::sonar_min_range_m`]: crate::robot::RobotConfig::sonar_min_range_m
//! [`RobotConfig::sonar_range_m`]: crate::robot::RobotConfig::sonar_range_m
//! [`RobotConfig::echo_wait_s`]: crate::robot::RobotConfig::echo_wait_s

use embedded_hal::delay::DelayNs;
use embedded_hal::digital::OutputPin;

use super::echo::{cycle_us, EchoDecoder, EchoEdge, EchoOutcome};
// The window and the tick conversions live in `echo.rs`, which needs them (so that echo.rs
// does not import this file: issue 27, no cycle between files); here for their callers.
pub use super::echo::{ticks_to_us, us_to_ticks, SonarWindow, MAX_ECHO_TIMEOUT_US};
use crate::sonar::{time_of_flight_to_range_m, valid_range_m};

/// Width of the trigger pulse, µs (HC-SR04-style rangers need at least 10 µs).
pub const TRIGGER_PULSE_US: u32 = 10;

/// Watches the echo line. Implemented on the board by a timer in input-capture mode on both
/// edges (the pin's level read after each capture gives the polarity) or by an edge interrupt
/// and a free-running timer; in tests by a scripted world.
pub trait EchoCapture {
    /// Rate of the ticks of [`EchoEdge::at_ticks`] and [`elapsed_ticks`](Self::elapsed_ticks), Hz.
    fn tick_hz(&self) -> u32;
    /// Forget any earlier edge and start watching the echo line: time 0 of the edges. Called
    /// just before the trigger pulse.
    fn arm(&mut self);
    /// The next edge since [`arm`](Self::arm), in time order, waiting until `deadline_ticks`
    /// after it at most; `None` when the deadline passed without one.
    fn next_edge(&mut self, deadline_ticks: u32) -> Option<EchoEdge>;
    /// Ticks since [`arm`](Self::arm) (saturating).
    fn elapsed_ticks(&mut self) -> u32;
}

/// What went wrong with a reading (an echo outside the window is not an error: it is `Ok(None)`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SonarError {
    /// The trigger pin could not be driven.
    TriggerPin,
    /// The echo capture reports a tick rate of 0 Hz: no time can be measured.
    TickRate {
        /// The reported rate, Hz.
        tick_hz: u32,
    },
}

impl core::fmt::Display for SonarError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            SonarError::TriggerPin => write!(f, "the sonar's trigger pin could not be driven"),
            SonarError::TickRate { tick_hz } => write!(
                f,
                "the echo capture reports a tick rate of {tick_hz} Hz: no time can be measured"
            ),
        }
    }
}

impl core::error::Error for SonarError {}

/// The window's time-out in ticks of `tick_hz`.
pub fn timeout_ticks(window: &SonarWindow, tick_hz: u32) -> u32 {
    us_to_ticks(window.timeout_us, tick_hz)
}

/// Round-trip time of `echo_ticks` at `tick_hz`, seconds; `None` for a rate of 0 Hz.
pub fn echo_ticks_to_time_of_flight_s(echo_ticks: u32, tick_hz: u32) -> Option<f32> {
    if tick_hz == 0 {
        None
    } else {
        // f32 holds 24 bits exactly: at 1 MHz that is every tick up to 16.7 s.
        Some(echo_ticks as f32 / tick_hz as f32)
    }
}

/// The range of one ping's outcome: a [`EchoOutcome::Pulse`] through
/// [`range_from_echo_ticks`]; anything else is `None` (no echo).
pub fn range_from_outcome(window: &SonarWindow, outcome: EchoOutcome, tick_hz: u32) -> Option<f32> {
    match outcome {
        EchoOutcome::Pulse { width_ticks } => {
            range_from_echo_ticks(window, Some(width_ticks), tick_hz)
        }
        EchoOutcome::StillHigh | EchoOutcome::Busy | EchoOutcome::Silent => None,
    }
}

/// The reading of a captured echo: `None` (no echo) on a time-out, a tick rate of 0 Hz, an echo
/// later than the time-out, or a range outside `min_range_m … max_range_m`.
///
/// ```
/// use twil_core::drivers::sonar_ranger::{range_from_echo_ticks, SonarWindow};
/// use twil_core::robot::RobotConfig;
/// let window = SonarWindow::from_config(&RobotConfig::default());
/// let range_m = range_from_echo_ticks(&window, Some(5_830), 1_000_000).unwrap();
/// assert!((range_m - 1.0).abs() < 0.001); // 5.83 ms at 343.2 m/s
/// assert_eq!(range_from_echo_ticks(&window, None, 1_000_000), None);
/// ```
pub fn range_from_echo_ticks(
    window: &SonarWindow,
    echo_ticks: Option<u32>,
    tick_hz: u32,
) -> Option<f32> {
    let ticks = echo_ticks?;
    if ticks > timeout_ticks(window, tick_hz) {
        return None;
    }
    let time_of_flight_s = echo_ticks_to_time_of_flight_s(ticks, tick_hz)?;
    valid_range_m(
        time_of_flight_to_range_m(time_of_flight_s),
        window.min_range_m,
        window.max_range_m,
    )
}

/// Time left of the cycle ([`cycle_us`]) after `elapsed_us` since the
/// capture was armed, µs: waited after each reading so that the next trigger is at least one
/// cycle after this one.
pub fn settle_delay_us(window: &SonarWindow, elapsed_us: u32) -> u32 {
    cycle_us(window).saturating_sub(elapsed_us)
}

/// One reading: the range (or no echo) and what the echo line did.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SonarReading {
    /// The range inside the window, metres; `None` for no echo.
    pub range_m: Option<f32>,
    /// What the echo line did.
    pub outcome: EchoOutcome,
}

/// One ultrasonic ranger: trigger pin, echo capture, a delay, its window.
pub struct SonarRanger<TRIG, ECHO, D> {
    trigger: TRIG,
    echo: ECHO,
    delay: D,
    window: SonarWindow,
    readings: u32,
    echoes: u32,
}

impl<TRIG: OutputPin, ECHO: EchoCapture, D: DelayNs> SonarRanger<TRIG, ECHO, D> {
    /// A ranger with the given pins and window (see [`SonarWindow::from_config`]).
    pub fn new(trigger: TRIG, echo: ECHO, delay: D, window: SonarWindow) -> Self {
        Self {
            trigger,
            echo,
            delay,
            window,
            readings: 0,
            echoes: 0,
        }
    }

    /// The window in use.
    pub fn window(&self) -> SonarWindow {
        self.window
    }

    /// Readings taken and, of them, echoes inside the window (for telemetry).
    pub fn counts(&self) -> (u32, u32) {
        (self.readings, self.echoes)
    }

    /// Use `window` from now on (a new mission's config).
    pub fn set_window(&mut self, window: SonarWindow) {
        self.window = window;
    }

    /// The echo capture (an async task feeds the decoder from it itself).
    pub fn echo_mut(&mut self) -> &mut ECHO {
        &mut self.echo
    }

    /// Start a ping: arm the capture, pulse the trigger for [`TRIGGER_PULSE_US`]. Returns the
    /// decoder to feed with the capture's edges (until its deadline) and the capture's tick
    /// rate. Errors: the trigger pin (left low), a capture without a clock.
    pub fn fire(&mut self) -> Result<(EchoDecoder, u32), SonarError> {
        let tick_hz = self.echo.tick_hz();
        if tick_hz == 0 {
            return Err(SonarError::TickRate { tick_hz });
        }
        self.trigger.set_low().map_err(|_| SonarError::TriggerPin)?;
        self.echo.arm();
        if self.trigger.set_high().is_err() {
            // Best effort: never leave the trigger high; the error reported is the first one.
            let _ = self.trigger.set_low();
            return Err(SonarError::TriggerPin);
        }
        self.delay.delay_us(TRIGGER_PULSE_US);
        self.trigger.set_low().map_err(|_| SonarError::TriggerPin)?;
        Ok((EchoDecoder::new(&self.window, tick_hz), tick_hz))
    }

    /// End a ping with the decoder's `outcome`: the reading (counted for telemetry).
    pub fn finish(&mut self, outcome: EchoOutcome, tick_hz: u32) -> SonarReading {
        let range_m = range_from_outcome(&self.window, outcome, tick_hz);
        self.readings = self.readings.wrapping_add(1);
        if range_m.is_some() {
            self.echoes = self.echoes.wrapping_add(1);
        }
        SonarReading { range_m, outcome }
    }

    /// Take one reading, blocking for one cycle ([`cycle_us`]):
    /// `Ok(reading)` whose `range_m` is `None` for no echo (no pulse, too near, too far, the
    /// no-target pulse). Errors: the trigger pin, a capture without a clock.
    pub fn read(&mut self) -> Result<SonarReading, SonarError> {
        let (mut decoder, tick_hz) = self.fire()?;
        let outcome = loop {
            match self.echo.next_edge(decoder.deadline_ticks()) {
                Some(edge) => {
                    if let Some(o) = decoder.feed(edge) {
                        break o;
                    }
                }
                None => break decoder.expire(),
            }
        };
        let elapsed_us = ticks_to_us(self.echo.elapsed_ticks(), tick_hz);
        let settle_us = settle_delay_us(&self.window, elapsed_us);
        if settle_us > 0 {
            self.delay.delay_us(settle_us);
        }
        Ok(self.finish(outcome, tick_hz))
    }

    /// Give the pins back.
    pub fn release(self) -> (TRIG, ECHO, D) {
        (self.trigger, self.echo, self.delay)
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::vec::Vec;

    use super::*;
    use crate::robot::RobotConfig;
    use embedded_hal_mock::eh1::delay::{CheckedDelay, NoopDelay, Transaction as DelayTx};
    use embedded_hal_mock::eh1::digital::{
        Mock as PinMock, State as PinState, Transaction as PinTx,
    };
    use embedded_hal_mock::eh1::MockError;

    /// An echo capture that hands out scripted edges and records how it was used. Its clock
    /// stands at the last edge handed out, or at the deadline of a wait without one.
    struct ScriptedEcho {
        tick_hz: u32,
        edges: Vec<EchoEdge>,
        armed: u32,
        now_ticks: u32,
    }

    impl ScriptedEcho {
        fn new(tick_hz: u32, edges: &[EchoEdge]) -> Self {
            Self {
                tick_hz,
                edges: edges.to_vec(),
                armed: 0,
                now_ticks: 0,
            }
        }
    }

    impl EchoCapture for ScriptedEcho {
        fn tick_hz(&self) -> u32 {
            self.tick_hz
        }
        fn arm(&mut self) {
            self.armed += 1;
        }
        fn next_edge(&mut self, deadline_ticks: u32) -> Option<EchoEdge> {
            assert_eq!(self.armed, 1, "the capture is armed once, before waiting");
            match self.edges.first() {
                Some(e) if e.at_ticks <= deadline_ticks => {
                    self.now_ticks = e.at_ticks;
                    Some(self.edges.remove(0))
                }
                _ => {
                    self.now_ticks = deadline_ticks;
                    None
                }
            }
        }
        fn elapsed_ticks(&mut self) -> u32 {
            self.now_ticks
        }
    }

    fn window() -> SonarWindow {
        SonarWindow::from_config(&RobotConfig::default())
    }

    fn pulse() -> [PinTx; 3] {
        [
            PinTx::set(PinState::Low),
            PinTx::set(PinState::High),
            PinTx::set(PinState::Low),
        ]
    }

    #[test]
    fn window_comes_from_the_config() {
        let w = window();
        assert_eq!(w.min_range_m, 0.26);
        assert_eq!(w.max_range_m, 1.5);
        assert_eq!(w.timeout_us, 35_000);
        let nan = RobotConfig {
            echo_wait_s: f32::NAN,
            ..RobotConfig::default()
        };
        assert_eq!(SonarWindow::from_config(&nan).timeout_us, 0);
        let huge = RobotConfig {
            echo_wait_s: 1e9,
            ..RobotConfig::default()
        };
        assert_eq!(
            SonarWindow::from_config(&huge).timeout_us,
            MAX_ECHO_TIMEOUT_US
        );
    }

    #[test]
    fn time_of_flight_5_83_ms_is_one_metre() {
        let r = range_from_echo_ticks(&window(), Some(5_830), 1_000_000).unwrap();
        assert!((r - 1.0004).abs() < 1e-3, "{r}");
        // The same time at another tick rate (84 MHz timer clock).
        let r84 = range_from_echo_ticks(&window(), Some(489_720), 84_000_000).unwrap();
        assert!((r84 - r).abs() < 1e-5, "{r84} vs {r}");
    }

    #[test]
    fn time_out_too_near_too_far_and_bad_rate_are_no_echo() {
        let w = window();
        assert_eq!(range_from_echo_ticks(&w, None, 1_000_000), None);
        // 0.25 m: 1.457 ms, below the 0.26 m minimum.
        assert_eq!(range_from_echo_ticks(&w, Some(1_457), 1_000_000), None);
        // 0.27 m: 1.573 ms, inside.
        assert!(range_from_echo_ticks(&w, Some(1_573), 1_000_000).is_some());
        // 1.6 m: 9.324 ms, beyond the 1.5 m range.
        assert_eq!(range_from_echo_ticks(&w, Some(9_324), 1_000_000), None);
        // Later than the 35 ms time-out even if the window were wider.
        let wide = SonarWindow {
            max_range_m: 100.0,
            ..w
        };
        assert!(range_from_echo_ticks(&wide, Some(34_999), 1_000_000).is_some());
        assert_eq!(range_from_echo_ticks(&wide, Some(35_001), 1_000_000), None);
        assert_eq!(range_from_echo_ticks(&w, Some(5_830), 0), None);
        // The HC-SR04's no-target pulse is no echo whatever the range window.
        let no_target = EchoOutcome::Pulse {
            width_ticks: 38_000,
        };
        assert_eq!(range_from_outcome(&wide, no_target, 1_000_000), None);
        assert_eq!(range_from_outcome(&w, EchoOutcome::Silent, 1_000_000), None);
    }

    #[test]
    fn tick_conversions_saturate_instead_of_overflowing() {
        assert_eq!(us_to_ticks(35_000, 1_000_000), 35_000);
        assert_eq!(us_to_ticks(35_000, 84_000_000), 2_940_000);
        assert_eq!(us_to_ticks(u32::MAX, u32::MAX), u32::MAX);
        assert_eq!(ticks_to_us(84, 84_000_000), 1);
        assert_eq!(ticks_to_us(u32::MAX, 1), u32::MAX);
        assert_eq!(ticks_to_us(1, 0), u32::MAX);
    }

    #[test]
    fn settle_delay_fills_the_rest_of_the_cycle() {
        let w = window();
        assert_eq!(settle_delay_us(&w, 6_100), 60_000 - 6_100);
        assert_eq!(settle_delay_us(&w, 48_000), 12_000);
        assert_eq!(settle_delay_us(&w, 70_000), 0);
    }

    #[test]
    fn read_pulses_the_trigger_then_times_the_echo() {
        let mut trigger = PinMock::new(&pulse());
        // Echo rises 450 µs after arming and lasts 5.83 ms; the fall is final 100 µs later.
        let fall_final = 450 + 5_830 + 100;
        let mut delay = CheckedDelay::new(&[
            DelayTx::delay_us(TRIGGER_PULSE_US),
            DelayTx::delay_us(60_000 - fall_final),
        ]);
        let echo = ScriptedEcho::new(
            1_000_000,
            &[EchoEdge::rise(450), EchoEdge::fall(450 + 5_830)],
        );
        let mut ranger = SonarRanger::new(trigger.clone(), echo, delay.clone(), window());
        let reading = ranger.read().unwrap();
        assert!((reading.range_m.unwrap() - 1.0004).abs() < 1e-3);
        assert_eq!(reading.outcome, EchoOutcome::Pulse { width_ticks: 5_830 });
        assert_eq!(ranger.counts(), (1, 1));
        trigger.done();
        delay.done();
    }

    #[test]
    fn the_no_target_pulse_is_no_echo_and_the_cycle_is_60_ms() {
        let mut trigger = PinMock::new(&pulse());
        let mut delay = CheckedDelay::new(&[
            DelayTx::delay_us(TRIGGER_PULSE_US),
            DelayTx::delay_us(60_000 - (450 + 38_000 + 100)),
        ]);
        let echo = ScriptedEcho::new(
            1_000_000,
            &[EchoEdge::rise(450), EchoEdge::fall(450 + 38_000)],
        );
        let mut ranger = SonarRanger::new(trigger.clone(), echo, delay.clone(), window());
        let reading = ranger.read().unwrap();
        assert_eq!(reading.range_m, None);
        assert_eq!(ranger.counts(), (1, 0));
        trigger.done();
        delay.done();
    }

    #[test]
    fn silence_is_reported_as_such() {
        let mut trigger = PinMock::new(&pulse());
        let mut delay = CheckedDelay::new(&[
            DelayTx::delay_us(TRIGGER_PULSE_US),
            DelayTx::delay_us(60_000 - 48_000),
        ]);
        let echo = ScriptedEcho::new(1_000_000, &[]);
        let mut ranger = SonarRanger::new(trigger.clone(), echo, delay.clone(), window());
        assert_eq!(
            ranger.read(),
            Ok(SonarReading {
                range_m: None,
                outcome: EchoOutcome::Silent
            })
        );
        trigger.done();
        delay.done();
    }

    #[test]
    fn an_echo_nearer_than_the_minimum_is_no_echo() {
        let mut trigger = PinMock::new(&pulse());
        // 0.17 m.
        let echo = ScriptedEcho::new(1_000_000, &[EchoEdge::rise(450), EchoEdge::fall(1_450)]);
        let mut ranger = SonarRanger::new(trigger.clone(), echo, NoopDelay::new(), window());
        assert_eq!(ranger.read().unwrap().range_m, None);
        trigger.done();
    }

    #[test]
    fn a_trigger_pin_error_is_reported_and_the_pin_left_low() {
        let err = MockError::Io(std::io::ErrorKind::Other);
        let mut trigger = PinMock::new(&[
            PinTx::set(PinState::Low),
            PinTx::set(PinState::High).with_error(err),
            PinTx::set(PinState::Low),
        ]);
        let echo = ScriptedEcho::new(1_000_000, &[]);
        let mut ranger = SonarRanger::new(trigger.clone(), echo, NoopDelay::new(), window());
        assert_eq!(ranger.read(), Err(SonarError::TriggerPin));
        assert_eq!(ranger.counts(), (0, 0));
        trigger.done();
    }

    #[test]
    fn a_zero_tick_rate_is_an_error_before_any_pin_moves() {
        let mut trigger = PinMock::new(&[]);
        let echo = ScriptedEcho::new(0, &[]);
        let mut ranger = SonarRanger::new(trigger.clone(), echo, NoopDelay::new(), window());
        assert_eq!(ranger.read(), Err(SonarError::TickRate { tick_hz: 0 }));
        trigger.done();
    }
}
