//! How long a stop took on the device: from the request (a stop frame's arrival, an e-stop
//! press) to the first control tick that put zero volts on the motors, in control periods
//! (`MissionReport::stop_ticks`) and in microseconds (`MissionReport::stop_latency_us`).
//!
//! Why a type: three tasks of the firmware touch it (the link's receive task asks, the control
//! task counts its ticks and sees the motors off, the mission task starts missions and reports),
//! and it used to be six global atomics whose writers and readers one had to search for. Here
//! it is one value with its rules, an RTIC resource in the firmware, tested on the host.
//!
//! The clock is the caller's free-running counter (`counts`, low 32 bits, wrapping); the
//! latency divides by its rate (`counts_per_us`).

/// The stop's timing (see the module documentation).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StopTiming {
    /// A stop was asked since the mission started: the control task zeroes the motors.
    asked: bool,
    /// Control ticks so far.
    ticks: u32,
    /// [`Self::ticks`] when the stop was asked.
    asked_at_tick: u32,
    /// The counter when the stop was asked.
    asked_at_counts: u32,
    /// Control periods from the request to the tick with the motors off (0: not yet).
    stop_ticks: u32,
    /// Microseconds from the request to that tick.
    latency_us: u32,
}

impl StopTiming {
    /// Nothing asked, nothing measured.
    pub const NEW: Self = Self {
        asked: false,
        ticks: 0,
        asked_at_tick: 0,
        asked_at_counts: 0,
        stop_ticks: 0,
        latency_us: 0,
    };

    /// A mission starts: no stop asked, no latency measured (the periods of the last stop
    /// stay until the next request, as the report has always carried them).
    pub fn restart(&mut self) {
        self.asked = false;
        self.latency_us = 0;
    }

    /// A stop is asked at `counts`: true the first time since the mission started (only the
    /// first request is timed).
    pub fn ask(&mut self, counts: u32) -> bool {
        if self.asked {
            return false;
        }
        self.asked = true;
        self.asked_at_tick = self.ticks;
        self.asked_at_counts = counts;
        self.stop_ticks = 0;
        true
    }

    /// Whether a stop was asked since the mission started.
    pub fn asked(&self) -> bool {
        self.asked
    }

    /// A control tick begins: its number.
    pub fn tick(&mut self) -> u32 {
        self.ticks = self.ticks.wrapping_add(1);
        self.ticks
    }

    /// At control tick `tick`, at `counts`, with zero volts on the motors (`motors_off`): the
    /// first such tick after the request fixes the stop's periods and latency.
    pub fn motors_at(&mut self, tick: u32, motors_off: bool, counts: u32, counts_per_us: u32) {
        if motors_off && self.asked && self.stop_ticks == 0 {
            self.stop_ticks = tick.wrapping_sub(self.asked_at_tick);
            self.latency_us = counts.wrapping_sub(self.asked_at_counts) / counts_per_us.max(1);
        }
    }

    /// Control periods from the request to the motors off (0 until measured).
    pub fn stop_ticks(&self) -> u32 {
        self.stop_ticks
    }

    /// Microseconds from the request to the motors off (0 until measured).
    pub fn latency_us(&self) -> u32 {
        self.latency_us
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stop_is_timed_from_its_request_to_the_first_tick_with_the_motors_off() {
        let mut s = StopTiming::NEW;
        s.restart();
        assert_eq!(s.tick(), 1);
        s.motors_at(1, true, 100, 168);
        assert_eq!((s.stop_ticks(), s.latency_us()), (0, 0), "nothing asked");
        assert!(s.ask(1_000));
        assert!(!s.ask(5_000), "only the first request is timed");
        assert!(s.asked());
        let t = s.tick();
        s.motors_at(t, false, 2_000, 168);
        assert_eq!(s.stop_ticks(), 0, "the motors still run");
        let t = s.tick();
        s.motors_at(t, true, 1_000 + 168 * 70_000, 168);
        assert_eq!((s.stop_ticks(), s.latency_us()), (2, 70_000));
        let t = s.tick();
        s.motors_at(t, true, 1_000 + 168 * 90_000, 168);
        assert_eq!(s.latency_us(), 70_000, "the first tick counts");
        s.restart();
        assert!(!s.asked());
        assert_eq!(s.latency_us(), 0);
    }

    #[test]
    fn the_counter_wraps_and_a_zero_rate_does_not_divide_by_zero() {
        let mut s = StopTiming::NEW;
        assert!(s.ask(u32::MAX - 9));
        let t = s.tick();
        s.motors_at(t, true, 10, 0);
        assert_eq!((s.stop_ticks(), s.latency_us()), (1, 20));
    }
}
