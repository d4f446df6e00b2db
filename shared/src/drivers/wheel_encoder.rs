//! Wheel encoder: a 16-bit hardware quadrature counter read once per control period, turned into
//! signed counts per period for the odometry (`control::Odometry::update`).
//!
//! Seed 003 (`twlckin.cpp`): the controller reads both wheel encoders every 50 ms period and
//! integrates the counts into the pose. On the STM32F405 a timer in encoder mode counts both
//! edges of both channels (×4) into a 16-bit register that wraps, so:
//!
//! - **wrap-around**: the counts since the last read are the wrapping difference of two raw
//!   values read as a signed 16-bit number ([`counts_between`]): 65 530 → 4 is +10, 4 → 65 530
//!   is −10. That is right as long as the wheel turns less than 32 767 counts per period
//!   (16 wheel turns at 2000 counts/rev: never);
//! - **sign**: the two wheels are mounted mirrored, so one counter counts down when the robot
//!   drives forward; [`Mounting::Mirrored`] flips it, so positive = forward on both wheels;
//! - **plausibility**: more counts in one period than the wheel can turn at full voltage
//!   ([`max_counts_per_period`]: no-load speed `motor_gain × max_voltage` = 9.36 rad/s with the
//!   default config, times [`SPEED_MARGIN`]) means a glitch (noise on the encoder lines, a
//!   counter reset, a missed read), not motion. Such a reading is flagged
//!   ([`WheelCounts::plausible`] false, and counted); its counts are still reported, and the
//!   caller decides (the firmware skips that period's odometry and reports it), rather than
//!   teleporting the robot.

use crate::robot::RobotConfig;

/// Factor over the no-load wheel speed still counted as plausible: the motor model is
/// first-order, and a wheel can be pushed or run downhill faster than it drives itself.
pub const SPEED_MARGIN: f32 = 1.5;

/// Reads a hardware quadrature counter (a timer in encoder mode on the board).
pub trait QuadratureCounter {
    /// The raw counter value, 0 … 65 535, wrapping in both directions.
    fn count(&mut self) -> u16;
}

/// How the encoder is mounted relative to the robot's forward direction.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Mounting {
    /// The counter counts up when the wheel drives the robot forward.
    Normal,
    /// The counter counts down when the wheel drives the robot forward (the mirrored side).
    Mirrored,
}

/// Signed counts from `previous` to `current` of a wrapping 16-bit counter.
///
/// ```
/// use twil_core::drivers::wheel_encoder::counts_between;
/// assert_eq!(counts_between(65_530, 4), 10);
/// assert_eq!(counts_between(4, 65_530), -10);
/// ```
pub fn counts_between(previous: u16, current: u16) -> i16 {
    current.wrapping_sub(previous) as i16
}

/// Most counts per control period a wheel can plausibly turn under `config`:
/// `motor_gain × max_voltage / 2π × counts_per_rev × period × SPEED_MARGIN`, rounded up, at
/// least 1 and at most `i16::MAX` (beyond that the 16-bit difference is ambiguous anyway).
/// With the default config: 9.36 rad/s → 148.97 counts per 50 ms × 1.5 → 224.
pub fn max_counts_per_period(config: &RobotConfig) -> u32 {
    let rad_s = config.motor_gain_rad_s_per_v * config.max_voltage_v;
    let counts = rad_s / (2.0 * core::f32::consts::PI)
        * config.encoder_pulses_per_rev as f32
        * config.controller_period_s
        * SPEED_MARGIN;
    let ceiling = i16::MAX as u32;
    if counts.is_nan() || counts <= 1.0 {
        1
    } else if counts >= ceiling as f32 {
        ceiling
    } else {
        let whole = counts as u32;
        if (whole as f32) < counts {
            whole + 1
        } else {
            whole
        }
    }
}

/// One period's reading of a wheel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct WheelCounts {
    /// Counts since the last read, positive = forward.
    pub counts: i32,
    /// Whether |counts| is within the plausible limit.
    pub plausible: bool,
}

impl WheelCounts {
    /// The counts if plausible.
    pub fn trusted(&self) -> Option<i32> {
        self.plausible.then_some(self.counts)
    }
}

/// Signed, mounted, checked counts of one period, from two raw counter values.
pub fn wheel_counts(previous: u16, current: u16, mounting: Mounting, limit: u32) -> WheelCounts {
    let raw = i32::from(counts_between(previous, current));
    let counts = match mounting {
        Mounting::Normal => raw,
        Mounting::Mirrored => -raw,
    };
    WheelCounts {
        counts,
        plausible: counts.unsigned_abs() <= limit,
    }
}

/// A wheel's encoder: its counter, mounting and plausibility limit, and the last raw value.
pub struct WheelEncoder<Q> {
    counter: Q,
    mounting: Mounting,
    limit_counts: u32,
    last_raw: u16,
    total_counts: i64,
    implausible_reads: u32,
}

impl<Q: QuadratureCounter> WheelEncoder<Q> {
    /// An encoder; the counter's current value is the reference for the first period.
    pub fn new(mut counter: Q, mounting: Mounting, limit_counts: u32) -> Self {
        let last_raw = counter.count();
        Self {
            counter,
            mounting,
            limit_counts,
            last_raw,
            total_counts: 0,
            implausible_reads: 0,
        }
    }

    /// Read the counter: the counts since the last read (or since [`new`](Self::new)). Call
    /// once per control period.
    pub fn read(&mut self) -> WheelCounts {
        let raw = self.counter.count();
        let c = wheel_counts(self.last_raw, raw, self.mounting, self.limit_counts);
        // The hardware has moved on either way: the next period starts from here.
        self.last_raw = raw;
        if c.plausible {
            self.total_counts = self.total_counts.saturating_add(i64::from(c.counts));
        } else {
            self.implausible_reads = self.implausible_reads.wrapping_add(1);
        }
        c
    }

    /// A new mission: `limit_counts` from its config, and the counter's current value as the
    /// reference of the next period (what the wheels did between missions is not odometry).
    pub fn restart(&mut self, limit_counts: u32) {
        self.limit_counts = limit_counts;
        self.last_raw = self.counter.count();
    }

    /// The plausibility limit in use, counts per period.
    pub fn limit_counts(&self) -> u32 {
        self.limit_counts
    }

    /// Sum of the plausible counts since start, positive = forward.
    pub fn total_counts(&self) -> i64 {
        self.total_counts
    }

    /// Readings flagged implausible since start.
    pub fn implausible_reads(&self) -> u32 {
        self.implausible_reads
    }

    /// Give the counter back.
    pub fn release(self) -> Q {
        self.counter
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::vec::Vec;

    use super::*;

    /// A counter that returns scripted raw values.
    struct Script(Vec<u16>);

    impl QuadratureCounter for Script {
        fn count(&mut self) -> u16 {
            assert!(!self.0.is_empty(), "read more often than scripted");
            self.0.remove(0)
        }
    }

    #[test]
    fn wrap_around_both_ways() {
        assert_eq!(counts_between(65_530, 4), 10);
        assert_eq!(counts_between(4, 65_530), -10);
        assert_eq!(counts_between(100, 100), 0);
        assert_eq!(counts_between(0, 32_767), 32_767);
        assert_eq!(counts_between(0, 32_768), -32_768);
    }

    #[test]
    fn the_default_limit_is_the_full_speed_with_margin() {
        let c = RobotConfig::default();
        assert_eq!(max_counts_per_period(&c), 224);
        let nan = RobotConfig {
            motor_gain_rad_s_per_v: f32::NAN,
            ..c
        };
        assert_eq!(max_counts_per_period(&nan), 1);
        let huge = RobotConfig {
            encoder_pulses_per_rev: 1_000_000,
            ..c
        };
        assert_eq!(max_counts_per_period(&huge), 32_767);
    }

    #[test]
    fn mirrored_wheels_count_forward_as_positive() {
        let normal = wheel_counts(65_530, 4, Mounting::Normal, 224);
        let mirrored = wheel_counts(4, 65_530, Mounting::Mirrored, 224);
        assert_eq!(
            normal,
            WheelCounts {
                counts: 10,
                plausible: true
            }
        );
        assert_eq!(
            mirrored,
            WheelCounts {
                counts: 10,
                plausible: true
            }
        );
    }

    #[test]
    fn counts_beyond_the_limit_are_flagged_not_trusted() {
        let at = wheel_counts(0, 224, Mounting::Normal, 224);
        assert_eq!(at.trusted(), Some(224));
        let over = wheel_counts(0, 65_311, Mounting::Normal, 224);
        assert_eq!(over.counts, -225);
        assert!(!over.plausible);
        assert_eq!(over.trusted(), None);
    }

    #[test]
    fn the_driver_reads_periods_in_sequence() {
        let script = Script(std::vec![65_500, 65_530, 4, 4, 40_000, 40_010]);
        let mut enc = WheelEncoder::new(script, Mounting::Mirrored, 224);
        assert_eq!(enc.read().trusted(), Some(-30));
        assert_eq!(enc.read().trusted(), Some(-10));
        assert_eq!(enc.read().trusted(), Some(0));
        let glitch = enc.read();
        assert!(!glitch.plausible);
        // The next period starts from the glitch's raw value.
        assert_eq!(enc.read().trusted(), Some(-10));
        assert_eq!(enc.total_counts(), -50);
        assert_eq!(enc.implausible_reads(), 1);
        assert!(enc.release().0.is_empty());
    }

    #[test]
    fn a_restart_takes_the_new_limit_and_reference() {
        let script = Script(std::vec![0, 500, 500, 600]);
        let mut enc = WheelEncoder::new(script, Mounting::Normal, 224);
        // The wheels turned 500 counts between missions: not this mission's motion.
        enc.restart(50);
        assert_eq!(enc.limit_counts(), 50);
        assert_eq!(enc.read().trusted(), Some(0));
        assert!(
            !enc.read().plausible,
            "100 counts exceed the new limit of 50"
        );
    }
}
