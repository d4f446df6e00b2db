//! Sonar ranger: a trigger pulse out, an echo timed back, a range in metres or *no echo*.
//!
//! Seed 003 (`le_sonar.c`, `sonar.cpp`): for each neck step the reader thread calls `trig()` on
//! one of the two sonars, waits a fixed time sized for the farthest echo it cares about (so that
//! an old echo cannot spill into the next reading), converts the time of flight to a distance
//! and keeps it only inside `DIST_MIN` … `ALCANCE_SONAR`. Here:
//!
//! 1. the trigger pin goes high for [`TRIGGER_PULSE_US`] µs (the minimum of the common
//!    HC-SR04-style rangers; longer is harmless);
//! 2. an [`EchoCapture`] (a timer's input capture on the board) returns the round-trip time in
//!    ticks of its stated rate, or `None` when nothing came back within the window's time-out
//!    ([`RobotConfig::echo_wait_s`], 35 ms: the round trip of 6 m);
//! 3. [`range_from_echo_ticks`] converts ticks → seconds → metres with
//!    [`sonar::time_of_flight_to_range_m`](crate::sonar::time_of_flight_to_range_m) (343.2 m/s)
//!    and applies the window ([`RobotConfig::sonar_min_range_m`] 0.26 m …
//!    [`RobotConfig::sonar_range_m`] 1.5 m): outside it, or a time-out, is `None` = no echo;
//! 4. the blocking [`SonarRanger::read`] then waits out the rest of the echo window
//!    ([`settle_delay_us`]), so consecutive readings are at least one window apart, as in the seed.
//!
//! An async firmware task does the same with the pure functions: arm, pulse, await the capture
//! with [`timeout_ticks`], convert with [`range_from_echo_ticks`], sleep [`settle_delay_us`].

use embedded_hal::delay::DelayNs;
use embedded_hal::digital::OutputPin;

use crate::robot::RobotConfig;
use crate::sonar::{time_of_flight_to_range_m, valid_range_m};

/// Width of the trigger pulse, µs (HC-SR04-style rangers need at least 10 µs).
pub const TRIGGER_PULSE_US: u32 = 10;

/// Longest echo time-out accepted, µs (1 s: far beyond any sonar's range; keeps tick arithmetic
/// in range and a bad config from stalling the reader for long).
pub const MAX_ECHO_TIMEOUT_US: u32 = 1_000_000;

/// Times an echo. Implemented on the board by a timer in input-capture mode (or a timer plus an
/// edge interrupt); in tests by a script.
pub trait EchoCapture {
    /// Rate of the ticks returned by [`wait_echo_ticks`](Self::wait_echo_ticks), Hz.
    fn tick_hz(&self) -> u32;
    /// Forget any earlier edge and start watching the echo line. Called just before the
    /// trigger pulse, so the time of flight counts from the pulse.
    fn arm(&mut self);
    /// Wait until the echo has been timed or `timeout_ticks` have passed since
    /// [`arm`](Self::arm). Returns the round-trip time of flight in ticks, or `None` on time-out.
    fn wait_echo_ticks(&mut self, timeout_ticks: u32) -> Option<u32>;
}

/// The validity window and time-out of one sonar, from a [`RobotConfig`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SonarWindow {
    /// Nearer echoes are no echo, metres.
    pub min_range_m: f32,
    /// Farther echoes are no echo, metres.
    pub max_range_m: f32,
    /// Time allowed for the echo (and the least time between two triggers), µs.
    pub timeout_us: u32,
}

impl SonarWindow {
    /// The window of `config`: `sonar_min_range_m` … `sonar_range_m`, time-out `echo_wait_s`
    /// (clamped to 0 … [`MAX_ECHO_TIMEOUT_US`]; NaN gives 0).
    pub fn from_config(config: &RobotConfig) -> Self {
        let us = config.echo_wait_s * 1e6;
        let timeout_us = if us.is_nan() || us <= 0.0 {
            0
        } else if us >= MAX_ECHO_TIMEOUT_US as f32 {
            MAX_ECHO_TIMEOUT_US
        } else {
            us as u32
        };
        Self {
            min_range_m: config.sonar_min_range_m,
            max_range_m: config.sonar_range_m,
            timeout_us,
        }
    }
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

/// `us` microseconds in ticks of `tick_hz`, saturating at `u32::MAX`.
pub fn us_to_ticks(us: u32, tick_hz: u32) -> u32 {
    let ticks = u64::from(us) * u64::from(tick_hz) / 1_000_000;
    u32::try_from(ticks).unwrap_or(u32::MAX)
}

/// `ticks` of `tick_hz` in microseconds, rounded down, saturating; 0 Hz gives `u32::MAX`.
pub fn ticks_to_us(ticks: u32, tick_hz: u32) -> u32 {
    if tick_hz == 0 {
        return u32::MAX;
    }
    let us = u64::from(ticks) * 1_000_000 / u64::from(tick_hz);
    u32::try_from(us).unwrap_or(u32::MAX)
}

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

/// Time left of the echo window after an echo came back after `echo_ticks`, µs: waited after
/// each reading so that the next trigger is at least one window after this one. A time-out
/// used the whole window already (0 left).
pub fn settle_delay_us(window: &SonarWindow, echo_ticks: Option<u32>, tick_hz: u32) -> u32 {
    match echo_ticks {
        None => 0,
        Some(ticks) => window
            .timeout_us
            .saturating_sub(ticks_to_us(ticks, tick_hz)),
    }
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

    /// Take one reading, blocking for at most one echo window: `Ok(Some(range_m))`, or
    /// `Ok(None)` for no echo (time-out, too near, too far).
    pub fn read(&mut self) -> Result<Option<f32>, SonarError> {
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
        let echo_ticks = self
            .echo
            .wait_echo_ticks(timeout_ticks(&self.window, tick_hz));
        let settle_us = settle_delay_us(&self.window, echo_ticks, tick_hz);
        if settle_us > 0 {
            self.delay.delay_us(settle_us);
        }
        let range_m = range_from_echo_ticks(&self.window, echo_ticks, tick_hz);
        self.readings = self.readings.wrapping_add(1);
        if range_m.is_some() {
            self.echoes = self.echoes.wrapping_add(1);
        }
        Ok(range_m)
    }

    /// Give the pins back.
    pub fn release(self) -> (TRIG, ECHO, D) {
        (self.trigger, self.echo, self.delay)
    }
}

#[cfg(test)]
mod tests {
    extern crate std;

    use super::*;
    use embedded_hal_mock::eh1::delay::{CheckedDelay, NoopDelay, Transaction as DelayTx};
    use embedded_hal_mock::eh1::digital::{
        Mock as PinMock, State as PinState, Transaction as PinTx,
    };
    use embedded_hal_mock::eh1::MockError;

    /// An echo capture that returns a scripted echo and records how it was used.
    struct ScriptedEcho {
        tick_hz: u32,
        echo_ticks: Option<u32>,
        armed: u32,
        timeout_seen: Option<u32>,
    }

    impl ScriptedEcho {
        fn new(tick_hz: u32, echo_ticks: Option<u32>) -> Self {
            Self {
                tick_hz,
                echo_ticks,
                armed: 0,
                timeout_seen: None,
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
        fn wait_echo_ticks(&mut self, timeout_ticks: u32) -> Option<u32> {
            assert_eq!(self.armed, 1, "the capture is armed once, before waiting");
            self.timeout_seen = Some(timeout_ticks);
            // A real capture never reports an echo after its time-out.
            self.echo_ticks.filter(|&t| t <= timeout_ticks)
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
    fn settle_delay_fills_the_rest_of_the_window() {
        let w = window();
        assert_eq!(settle_delay_us(&w, Some(5_830), 1_000_000), 35_000 - 5_830);
        assert_eq!(settle_delay_us(&w, None, 1_000_000), 0);
        assert_eq!(settle_delay_us(&w, Some(40_000), 1_000_000), 0);
    }

    #[test]
    fn read_pulses_the_trigger_then_times_the_echo() {
        let mut trigger = PinMock::new(&pulse());
        let mut delay = CheckedDelay::new(&[
            DelayTx::delay_us(TRIGGER_PULSE_US),
            DelayTx::delay_us(35_000 - 5_830),
        ]);
        let echo = ScriptedEcho::new(1_000_000, Some(5_830));
        let mut ranger = SonarRanger::new(trigger.clone(), echo, delay.clone(), window());
        let r = ranger.read().unwrap().unwrap();
        assert!((r - 1.0004).abs() < 1e-3);
        assert_eq!(ranger.counts(), (1, 1));
        let (_, echo, _) = ranger.release();
        assert_eq!(echo.timeout_seen, Some(35_000));
        trigger.done();
        delay.done();
    }

    #[test]
    fn a_time_out_is_no_echo_and_waits_nothing_more() {
        let mut trigger = PinMock::new(&pulse());
        let mut delay = CheckedDelay::new(&[DelayTx::delay_us(TRIGGER_PULSE_US)]);
        let echo = ScriptedEcho::new(1_000_000, None);
        let mut ranger = SonarRanger::new(trigger.clone(), echo, delay.clone(), window());
        assert_eq!(ranger.read(), Ok(None));
        assert_eq!(ranger.counts(), (1, 0));
        trigger.done();
        delay.done();
    }

    #[test]
    fn an_echo_nearer_than_the_minimum_is_no_echo() {
        let mut trigger = PinMock::new(&pulse());
        let echo = ScriptedEcho::new(1_000_000, Some(1_000)); // 0.17 m
        let mut ranger = SonarRanger::new(trigger.clone(), echo, NoopDelay::new(), window());
        assert_eq!(ranger.read(), Ok(None));
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
        let echo = ScriptedEcho::new(1_000_000, Some(5_830));
        let mut ranger = SonarRanger::new(trigger.clone(), echo, NoopDelay::new(), window());
        assert_eq!(ranger.read(), Err(SonarError::TriggerPin));
        assert_eq!(ranger.counts(), (0, 0));
        trigger.done();
    }

    #[test]
    fn a_zero_tick_rate_is_an_error_before_any_pin_moves() {
        let mut trigger = PinMock::new(&[]);
        let echo = ScriptedEcho::new(0, Some(5_830));
        let mut ranger = SonarRanger::new(trigger.clone(), echo, NoopDelay::new(), window());
        assert_eq!(ranger.read(), Err(SonarError::TickRate { tick_hz: 0 }));
        trigger.done();
    }
}
