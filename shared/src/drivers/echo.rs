//! Echo pulse decoding: from timestamped edges of the sonar's echo line to a pulse width, or to
//! the reason there is none. A small state machine fed one edge at a time, so the blocking
//! [`SonarRanger::read`](super::SonarRanger::read) and an async firmware task (capture
//! interrupt → channel → `feed`, `Mono::delay_until(deadline)` → `expire`) share every rule.
//!
//! The ranger is an HC-SR04 (or the seed's SRF04-style module). From its data sheet (ElecFreaks
//! "Ultrasonic Ranging Module HC-SR04"; Devantech SRF04 technical page): a trigger of at least
//! 10 µs starts a burst of eight 40 kHz cycles, then the echo line goes **high** and falls when
//! the echo comes back, so the *width* of the high pulse is the round trip (range = width × c
//! / 2); with no target it falls anyway after about **38 ms** (36 ms on the SRF04), and the
//! data sheet asks for a measurement cycle of at least **60 ms** so that a late echo of one ping
//! is not heard by the next. Hence the rules here (issue 24, finding 4):
//!
//! - **polarity and order decide**, not "the first edge is the rise": a falling edge before any
//!   rise is the tail of an earlier pulse (the line was high when the capture was armed) and is
//!   ignored; the pulse is rise → fall;
//! - **glitch filter**: a high pulse narrower than [`MIN_ECHO_PULSE_US`] is noise (switching
//!   spikes coupled from the 20 kHz motor PWM are far shorter; a real echo is at least 117 µs,
//!   the HC-SR04's 2 cm minimum range), and a low dip narrower than it inside a pulse is noise
//!   too: the fall is only final after [`MIN_ECHO_PULSE_US`] without a new rise. This is the
//!   logic half; the board adds the timer's digital input filter for sub-microsecond spikes;
//! - **the listen time covers the no-target pulse**: [`listen_us`] is the longer of the
//!   window's time-out and [`NO_TARGET_PULSE_US`], plus [`LISTEN_MARGIN_US`]; a 38 ms pulse is
//!   then seen whole and reads as no echo (it is beyond any range window), instead of spilling
//!   into the next reading;
//! - **the cycle** between two triggers is at least [`MIN_CYCLE_US`];
//! - a line with **no edge at all** is [`EchoOutcome::Silent`]: the module did not answer
//!   (unplugged, unpowered, a broken echo wire). The body turns repeated silence into a sensor
//!   fault rather than "no obstacle" ([`super::body`]).
//!
//! The sonar's window ([`SonarWindow`]) and the µs ↔ tick conversions are here too: the decoder
//! sizes its listen time from them, and the ranger (`sonar_ranger.rs`) re-exports them.

use crate::robot::RobotConfig;

/// Pulses (and dips inside a pulse) narrower than this are noise, µs.
pub const MIN_ECHO_PULSE_US: u32 = 100;

/// The HC-SR04's echo pulse with no target, µs (data sheet: 38 ms).
pub const NO_TARGET_PULSE_US: u32 = 38_000;

/// Listening time beyond the longest pulse expected, µs: the echo rises only after the
/// 0.2 ms burst, and clones' time-outs vary by a few milliseconds.
pub const LISTEN_MARGIN_US: u32 = 10_000;

/// Least time from one trigger to the next, µs (HC-SR04 data sheet: a cycle of at least 60 ms).
pub const MIN_CYCLE_US: u32 = 60_000;

/// Longest echo time-out accepted, µs (1 s: far beyond any sonar's range; keeps tick arithmetic
/// in range and a bad config from stalling the reader for long).
pub const MAX_ECHO_TIMEOUT_US: u32 = 1_000_000;

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

/// How long to listen for the echo after arming, µs: the window's time-out or the no-target
/// pulse, whichever is longer, plus [`LISTEN_MARGIN_US`].
pub fn listen_us(window: &SonarWindow) -> u32 {
    window
        .timeout_us
        .max(NO_TARGET_PULSE_US)
        .saturating_add(LISTEN_MARGIN_US)
}

/// Least time between two triggers, µs: [`MIN_CYCLE_US`], or the listen time if longer.
pub fn cycle_us(window: &SonarWindow) -> u32 {
    listen_us(window).max(MIN_CYCLE_US)
}

/// One edge of the echo line, as the capture saw it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EchoEdge {
    /// `true` for low → high, `false` for high → low (the board reads the pin's level right
    /// after the capture, or uses a rising and a falling capture channel).
    pub rising: bool,
    /// When, in ticks of the capture since it was armed.
    pub at_ticks: u32,
}

impl EchoEdge {
    /// A rising edge at `at_ticks`.
    pub const fn rise(at_ticks: u32) -> Self {
        Self {
            rising: true,
            at_ticks,
        }
    }
    /// A falling edge at `at_ticks`.
    pub const fn fall(at_ticks: u32) -> Self {
        Self {
            rising: false,
            at_ticks,
        }
    }
}

/// What one ping's echo line did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum EchoOutcome {
    /// A high pulse of this width, ticks: the round trip (a range when inside the window; a
    /// no-target pulse of 38 ms is beyond every window and reads as no echo).
    Pulse {
        /// Rise to fall, ticks.
        width_ticks: u32,
    },
    /// The line rose and stayed high for the whole listen time: no echo.
    StillHigh,
    /// Only the tail of an earlier pulse (a fall, then nothing): the module was still busy with
    /// the previous ping. No reading, not a fault.
    Busy,
    /// No edge at all: the module did not answer.
    Silent,
}

/// The decoder of one ping (make a new one per ping).
#[derive(Clone, Copy, Debug)]
pub struct EchoDecoder {
    listen_ticks: u32,
    min_pulse_ticks: u32,
    rise_at: Option<u32>,
    fall_at: Option<u32>,
    saw_edge: bool,
    last_at: u32,
    glitches: u32,
    outcome: Option<EchoOutcome>,
}

impl EchoDecoder {
    /// A decoder for `window` with a capture counting at `tick_hz`.
    pub fn new(window: &SonarWindow, tick_hz: u32) -> Self {
        Self {
            listen_ticks: us_to_ticks(listen_us(window), tick_hz),
            min_pulse_ticks: us_to_ticks(MIN_ECHO_PULSE_US, tick_hz).max(1),
            rise_at: None,
            fall_at: None,
            saw_edge: false,
            last_at: 0,
            glitches: 0,
            outcome: None,
        }
    }

    /// Ticks since arming until which to wait for the next edge; at that time, without an
    /// edge, call [`expire`](Self::expire).
    pub fn deadline_ticks(&self) -> u32 {
        match self.fall_at {
            Some(fall) => fall
                .saturating_add(self.min_pulse_ticks)
                .min(self.listen_ticks),
            None => self.listen_ticks,
        }
    }

    /// The decision, once made.
    pub fn outcome(&self) -> Option<EchoOutcome> {
        self.outcome
    }

    /// Pulses and dips rejected as noise.
    pub fn glitches(&self) -> u32 {
        self.glitches
    }

    /// One edge. Returns the outcome once decided (then every later edge is ignored).
    pub fn feed(&mut self, edge: EchoEdge) -> Option<EchoOutcome> {
        if self.outcome.is_some() {
            return self.outcome;
        }
        // An edge reported after the deadline (interrupt latency): the deadline decides first.
        if edge.at_ticks > self.deadline_ticks() {
            self.expire();
            return self.outcome;
        }
        // Time never runs backwards: an edge older than the last one is a capture fault.
        if edge.at_ticks < self.last_at {
            self.glitches = self.glitches.saturating_add(1);
            return None;
        }
        self.last_at = edge.at_ticks;
        self.saw_edge = true;
        match (edge.rising, self.rise_at, self.fall_at) {
            // A rise soon after a fall: the fall was a dip inside the pulse.
            (true, Some(_), Some(_)) => {
                self.fall_at = None;
                self.glitches = self.glitches.saturating_add(1);
            }
            // A rise (or a second rise whose fall was lost): the pulse starts here.
            (true, _, None) => self.rise_at = Some(edge.at_ticks),
            (true, None, Some(_)) => {
                self.fall_at = None;
                self.rise_at = Some(edge.at_ticks);
            }
            // A fall before any rise: the tail of an earlier pulse.
            (false, None, _) => {}
            // A second fall: keep the first.
            (false, Some(_), Some(_)) => {}
            (false, Some(rise), None) => {
                if edge.at_ticks.wrapping_sub(rise) < self.min_pulse_ticks {
                    self.rise_at = None;
                    self.glitches = self.glitches.saturating_add(1);
                } else {
                    self.fall_at = Some(edge.at_ticks);
                }
            }
        }
        None
    }

    /// The deadline passed without an edge: decide.
    pub fn expire(&mut self) -> EchoOutcome {
        if let Some(o) = self.outcome {
            return o;
        }
        let o = match (self.rise_at, self.fall_at) {
            (Some(rise), Some(fall)) => EchoOutcome::Pulse {
                width_ticks: fall.wrapping_sub(rise),
            },
            (Some(_), None) => EchoOutcome::StillHigh,
            (None, _) if self.saw_edge => EchoOutcome::Busy,
            (None, _) => EchoOutcome::Silent,
        };
        self.outcome = Some(o);
        o
    }
}

/// The edges of a two-channel capture latch, in time order: the board latches the echo's rise
/// on one capture channel and its fall on another channel fed by the same input (RM0090's
/// PWM-input arrangement), each holding its latest capture, and reads them once the listen
/// time is over. `rise_at` / `fall_at` are the captured counter values (`None`: no such edge),
/// `armed_at` the counter when the ping was armed; all wrap at 2^32. A fall captured before the
/// rise (the line was still high when armed) comes first, so [`EchoDecoder`] treats it as the
/// tail of an earlier pulse.
///
/// ```
/// use twil_core::drivers::echo::{latched_edges, EchoEdge};
/// assert_eq!(
///     latched_edges(100, Some(1_100), Some(6_930)),
///     [Some(EchoEdge::rise(1_000)), Some(EchoEdge::fall(6_830))]
/// );
/// ```
pub fn latched_edges(
    armed_at: u32,
    rise_at: Option<u32>,
    fall_at: Option<u32>,
) -> [Option<EchoEdge>; 2] {
    let rise = rise_at.map(|at| EchoEdge::rise(at.wrapping_sub(armed_at)));
    let fall = fall_at.map(|at| EchoEdge::fall(at.wrapping_sub(armed_at)));
    match (rise, fall) {
        (Some(r), Some(f)) if f.at_ticks < r.at_ticks => [Some(f), Some(r)],
        (None, Some(f)) => [Some(f), None],
        (r, f) => [r, f],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::RobotConfig;

    #[test]
    fn a_latched_rise_then_fall_decodes_as_the_pulse_between_them() {
        let edges = latched_edges(100, Some(1_100), Some(6_930));
        assert_eq!(
            edges,
            [Some(EchoEdge::rise(1_000)), Some(EchoEdge::fall(6_830))]
        );
        let mut d = decoder();
        for e in edges.into_iter().flatten() {
            assert_eq!(d.feed(e), None);
        }
        assert_eq!(d.expire(), EchoOutcome::Pulse { width_ticks: 5_830 });
    }

    #[test]
    fn a_latched_fall_before_the_rise_is_an_earlier_pulse_s_tail() {
        // The line was high at arming: it fell at 200, then rose at 3 000 and stayed high.
        let edges = latched_edges(0, Some(3_000), Some(200));
        assert_eq!(
            edges,
            [Some(EchoEdge::fall(200)), Some(EchoEdge::rise(3_000))]
        );
        assert_eq!(
            run(&[EchoEdge::fall(200), EchoEdge::rise(3_000)]),
            EchoOutcome::StillHigh
        );
    }

    #[test]
    fn latched_edges_count_from_the_arming_across_the_counter_s_wrap() {
        let armed_at = u32::MAX - 9;
        let edges = latched_edges(armed_at, Some(u32::MAX - 4), Some(5_000));
        assert_eq!(
            edges,
            [Some(EchoEdge::rise(5)), Some(EchoEdge::fall(5_010))]
        );
        assert_eq!(
            latched_edges(armed_at, None, Some(20)),
            [Some(EchoEdge::fall(30)), None]
        );
        assert_eq!(
            latched_edges(armed_at, Some(20), None),
            [Some(EchoEdge::rise(30)), None]
        );
        assert_eq!(latched_edges(armed_at, None, None), [None, None]);
    }

    const HZ: u32 = 1_000_000;

    fn decoder() -> EchoDecoder {
        EchoDecoder::new(&SonarWindow::from_config(&RobotConfig::default()), HZ)
    }

    fn run(edges: &[EchoEdge]) -> EchoOutcome {
        let mut d = decoder();
        for &e in edges {
            if let Some(o) = d.feed(e) {
                return o;
            }
        }
        d.expire()
    }

    #[test]
    fn listen_and_cycle_cover_the_no_target_pulse() {
        let w = SonarWindow::from_config(&RobotConfig::default());
        assert_eq!(listen_us(&w), 48_000);
        assert_eq!(cycle_us(&w), 60_000);
        let long = SonarWindow {
            timeout_us: 70_000,
            ..w
        };
        assert_eq!(listen_us(&long), 80_000);
        assert_eq!(cycle_us(&long), 80_000);
    }

    #[test]
    fn a_pulse_is_rise_then_fall() {
        let o = run(&[EchoEdge::rise(450), EchoEdge::fall(450 + 5_830)]);
        assert_eq!(o, EchoOutcome::Pulse { width_ticks: 5_830 });
    }

    #[test]
    fn a_leading_fall_is_the_tail_of_an_earlier_pulse() {
        // Armed while the previous 38 ms pulse was still high: its fall comes first.
        let o = run(&[
            EchoEdge::fall(3_000),
            EchoEdge::rise(3_450),
            EchoEdge::fall(3_450 + 2_000),
        ]);
        assert_eq!(o, EchoOutcome::Pulse { width_ticks: 2_000 });
        assert_eq!(run(&[EchoEdge::fall(3_000)]), EchoOutcome::Busy);
    }

    #[test]
    fn the_no_target_pulse_is_seen_whole() {
        let o = run(&[EchoEdge::rise(450), EchoEdge::fall(450 + 38_000)]);
        assert_eq!(
            o,
            EchoOutcome::Pulse {
                width_ticks: 38_000
            }
        );
        // Longer than the listen time: still high.
        assert_eq!(run(&[EchoEdge::rise(450)]), EchoOutcome::StillHigh);
        assert_eq!(run(&[]), EchoOutcome::Silent);
    }

    #[test]
    fn narrow_pulses_and_dips_are_noise() {
        let mut d = decoder();
        // A 2 µs spike, then the real pulse with a 3 µs dip in it.
        assert_eq!(d.feed(EchoEdge::rise(100)), None);
        assert_eq!(d.feed(EchoEdge::fall(102)), None);
        assert_eq!(d.feed(EchoEdge::rise(500)), None);
        assert_eq!(d.feed(EchoEdge::fall(1_500)), None);
        assert_eq!(d.deadline_ticks(), 1_600);
        assert_eq!(d.feed(EchoEdge::rise(1_503)), None);
        assert_eq!(d.feed(EchoEdge::fall(3_500)), None);
        assert_eq!(d.expire(), EchoOutcome::Pulse { width_ticks: 3_000 });
        assert_eq!(d.glitches(), 2);
        // Decided: later edges change nothing.
        assert_eq!(
            d.feed(EchoEdge::rise(5_000)),
            Some(EchoOutcome::Pulse { width_ticks: 3_000 })
        );
    }

    #[test]
    fn an_edge_after_the_deadline_decides_by_the_deadline() {
        let mut d = decoder();
        d.feed(EchoEdge::rise(400));
        assert_eq!(d.feed(EchoEdge::fall(60_000)), Some(EchoOutcome::StillHigh));
    }

    #[test]
    fn any_edge_sequence_decides_within_bounds() {
        // Every order of a few edges decides, and a pulse is never wider than the listen time.
        let times = [0u32, 50, 99, 100, 5_000, 47_999, 48_000, 48_001, u32::MAX];
        for &a in &times {
            for &b in &times {
                for ra in [false, true] {
                    for rb in [false, true] {
                        let o = run(&[
                            EchoEdge {
                                rising: ra,
                                at_ticks: a,
                            },
                            EchoEdge {
                                rising: rb,
                                at_ticks: b,
                            },
                        ]);
                        if let EchoOutcome::Pulse { width_ticks } = o {
                            assert!(width_ticks <= 48_000, "{a} {b} {ra} {rb}: {o:?}");
                        }
                    }
                }
            }
        }
    }
}
