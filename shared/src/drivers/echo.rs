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

use super::sonar_ranger::{us_to_ticks, SonarWindow};

/// Pulses (and dips inside a pulse) narrower than this are noise, µs.
pub const MIN_ECHO_PULSE_US: u32 = 100;

/// The HC-SR04's echo pulse with no target, µs (data sheet: 38 ms).
pub const NO_TARGET_PULSE_US: u32 = 38_000;

/// Listening time beyond the longest pulse expected, µs: the echo rises only after the
/// 0.2 ms burst, and clones' time-outs vary by a few milliseconds.
pub const LISTEN_MARGIN_US: u32 = 10_000;

/// Least time from one trigger to the next, µs (HC-SR04 data sheet: a cycle of at least 60 ms).
pub const MIN_CYCLE_US: u32 = 60_000;

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::RobotConfig;

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
