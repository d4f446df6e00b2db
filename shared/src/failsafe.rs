//! The robot's failsafes as pure step functions: the firmware wires them to the chip (IWDG,
//! RCC, SysTick), the host tests drive them directly (QEMU emulates neither the IWDG nor the
//! RCC, so this is where their logic is tested).
//!
//! - [`WatchdogGate`]: feed the independent watchdog only while the control task *and* the
//!   mission task both make progress.
//! - [`ResetCause`]: why the chip last reset, decoded from `RCC_CSR`.
//! - [`LinkLossPolicy`] and [`LinkWatch`]: what a running mission does when the host falls
//!   silent.
//! - [`control_period_missed`]: the control step overran its period (the firmware then zeroes
//!   the motors and ends the mission with [`StopCause::ControllerOverrun`]).
//! - [`StopCause`]: why a mission was stopped from outside its own logic.
//! - [`StopTiming`]: how long a stop took, from its request to the motors off.

use serde::{Deserialize, Serialize};

mod stop_timing;
pub use stop_timing::StopTiming;

/// Why the chip last reset (`RCC_CSR` flags of the STM32F4, RM0090 §7.3.21).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ResetCause {
    /// No flag set, or not readable (QEMU does not emulate the RCC).
    #[default]
    Unknown,
    /// Power on (`PORRSTF`).
    PowerOn,
    /// Supply brown-out without a power-on (`BORRSTF`).
    Brownout,
    /// The NRST pin only (`PINRSTF`).
    Pin,
    /// A software reset (`SFTRSTF`): `SCB::sys_reset`, e.g. after a HardFault.
    Software,
    /// The independent watchdog (`IWDGRSTF`): a task stopped making progress.
    IndependentWatchdog,
    /// The window watchdog (`WWDGRSTF`; not used by this firmware).
    WindowWatchdog,
    /// Entering standby or stop with the low-power reset option (`LPWRRSTF`).
    LowPower,
}

/// `RCC_CSR` bit: remove the reset flags (write 1).
pub const RCC_CSR_RMVF: u32 = 1 << 24;
/// `RCC_CSR` bit: POR/PDR or BOR reset.
pub const RCC_CSR_BORRSTF: u32 = 1 << 25;
/// `RCC_CSR` bit: NRST pin reset (also set by every internal reset, which pulses the pin).
pub const RCC_CSR_PINRSTF: u32 = 1 << 26;
/// `RCC_CSR` bit: POR/PDR reset.
pub const RCC_CSR_PORRSTF: u32 = 1 << 27;
/// `RCC_CSR` bit: software reset.
pub const RCC_CSR_SFTRSTF: u32 = 1 << 28;
/// `RCC_CSR` bit: independent watchdog reset.
pub const RCC_CSR_IWDGRSTF: u32 = 1 << 29;
/// `RCC_CSR` bit: window watchdog reset.
pub const RCC_CSR_WWDGRSTF: u32 = 1 << 30;
/// `RCC_CSR` bit: low-power reset.
pub const RCC_CSR_LPWRRSTF: u32 = 1 << 31;

impl ResetCause {
    /// The cause of the last reset from the value of `RCC_CSR`. Several flags are set at once
    /// (every internal reset also pulses NRST, a power-on also sets `BORRSTF`): the most
    /// specific wins, so the pin comes last.
    pub fn from_rcc_csr(csr: u32) -> Self {
        let order = [
            (RCC_CSR_IWDGRSTF, ResetCause::IndependentWatchdog),
            (RCC_CSR_WWDGRSTF, ResetCause::WindowWatchdog),
            (RCC_CSR_LPWRRSTF, ResetCause::LowPower),
            (RCC_CSR_SFTRSTF, ResetCause::Software),
            (RCC_CSR_PORRSTF, ResetCause::PowerOn),
            (RCC_CSR_BORRSTF, ResetCause::Brownout),
            (RCC_CSR_PINRSTF, ResetCause::Pin),
        ];
        order
            .iter()
            .find(|(bit, _)| csr & bit != 0)
            .map_or(ResetCause::Unknown, |&(_, cause)| cause)
    }
}

/// Decides, once per control period, whether to feed the independent watchdog: only while the
/// control task ticked and the mission task turned its loop within [`WatchdogGate::limit_ms`].
/// Once it has refused it refuses for good: the watchdog is meant to reset the chip, not to
/// recover a task that stalled for a while.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WatchdogGate {
    /// Longest time either task may go without a progress mark, milliseconds.
    pub limit_ms: u32,
    control_ms: u32,
    mission_ms: u32,
    starved: bool,
}

/// What [`WatchdogGate::check`] says.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum WatchdogDecision {
    /// Both tasks made progress: feed the watchdog.
    Feed,
    /// A task stalled: do not feed (the watchdog resets the chip when it runs out).
    Starve {
        /// The control task's silence, milliseconds.
        control_silent_ms: u32,
        /// The mission task's silence, milliseconds.
        mission_silent_ms: u32,
    },
}

impl WatchdogGate {
    /// Longest a mission-task loop may legitimately take on the board, milliseconds: a plan is
    /// budgeted at 5 M instructions (30 ms at 168 MHz); a 1 KB telemetry write at 115 200 baud
    /// takes 90 ms. A second leaves margin for the worst request.
    pub const MISSION_LIMIT_MS: u32 = 1_000;

    /// A gate with both tasks marked at `now_ms` (start-up).
    pub const fn new(limit_ms: u32, now_ms: u32) -> Self {
        Self {
            limit_ms,
            control_ms: now_ms,
            mission_ms: now_ms,
            starved: false,
        }
    }

    /// The control task completed a step at `now_ms`.
    pub fn control_ticked(&mut self, now_ms: u32) {
        self.control_ms = now_ms;
    }

    /// The mission task turned its loop at `now_ms`.
    pub fn mission_turned(&mut self, now_ms: u32) {
        self.mission_ms = now_ms;
    }

    /// Feed or not, at `now_ms` (milliseconds wrap with `u32`).
    pub fn check(&mut self, now_ms: u32) -> WatchdogDecision {
        let control_silent_ms = now_ms.wrapping_sub(self.control_ms);
        let mission_silent_ms = now_ms.wrapping_sub(self.mission_ms);
        // A mark "in the future" (read before `now_ms` was taken, across a tick) is fresh.
        let stale = |silent: u32| silent < u32::MAX / 2 && silent > self.limit_ms;
        if stale(control_silent_ms) || stale(mission_silent_ms) {
            self.starved = true;
        }
        if self.starved {
            WatchdogDecision::Starve {
                control_silent_ms,
                mission_silent_ms,
            }
        } else {
            WatchdogDecision::Feed
        }
    }
}

/// The control step that was due at `scheduled_ms` ended at `done_ms` after the next one was
/// due (`scheduled_ms + period_ms`): it woke late by a period or its work overran. Both are
/// monotonic milliseconds (wrapping).
pub fn control_period_missed(scheduled_ms: u32, done_ms: u32, period_ms: u32) -> bool {
    let late = done_ms.wrapping_sub(scheduled_ms);
    late < u32::MAX / 2 && late > period_ms
}

/// What a running mission does when the host says nothing for [`LinkLossPolicy::timeout_ms`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LinkLossReaction {
    /// Go on to the goal (the robot does not need the host to navigate).
    Continue,
    /// End the mission ([`StopCause::LinkLost`]), motors at zero, and hold.
    #[default]
    StopAndHold,
}

/// How a mission reacts to a silent host (part of `MissionSetup`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LinkLossPolicy {
    /// Silence (no well-formed frame from the host) that counts as a lost link, milliseconds;
    /// 0: never.
    pub timeout_ms: u32,
    /// What to do then.
    pub reaction: LinkLossReaction,
}

impl LinkLossPolicy {
    /// No reaction to silence (the default: a host that does not send heartbeats).
    pub const NEVER: Self = Self {
        timeout_ms: 0,
        reaction: LinkLossReaction::StopAndHold,
    };
    /// Shortest timeout accepted, milliseconds: four control periods, so that one late
    /// heartbeat is not a lost link.
    pub const MIN_TIMEOUT_MS: u32 = 200;
    /// Longest timeout accepted, milliseconds (an hour).
    pub const MAX_TIMEOUT_MS: u32 = 3_600_000;

    /// The timeout is 0 (never) or within [`Self::MIN_TIMEOUT_MS`] ..= [`Self::MAX_TIMEOUT_MS`].
    pub fn is_valid(&self) -> bool {
        self.timeout_ms == 0
            || (Self::MIN_TIMEOUT_MS..=Self::MAX_TIMEOUT_MS).contains(&self.timeout_ms)
    }
}

/// Tracks the host's silence during a mission: [`LinkWatch::heard`] on every well-formed frame,
/// [`LinkWatch::check`] as often as the shell likes, with the shell's monotonic milliseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LinkWatch {
    now_ms: u32,
    last_heard_ms: u32,
    reacted: bool,
}

impl LinkWatch {
    /// Nothing heard yet, time 0.
    pub const fn new() -> Self {
        Self {
            now_ms: 0,
            last_heard_ms: 0,
            reacted: false,
        }
    }

    /// The shell's clock, milliseconds (wrapping).
    pub fn set_now_ms(&mut self, now_ms: u32) {
        self.now_ms = now_ms;
    }

    /// A mission starts: the silence counts from now, and it may react once.
    pub fn start(&mut self) {
        self.last_heard_ms = self.now_ms;
        self.reacted = false;
    }

    /// A well-formed frame came from the host.
    pub fn heard(&mut self) {
        self.last_heard_ms = self.now_ms;
    }

    /// Milliseconds since the host was last heard.
    pub fn silent_ms(&self) -> u32 {
        let silent = self.now_ms.wrapping_sub(self.last_heard_ms);
        // A clock set back (not monotonic) counts as just heard.
        if silent >= u32::MAX / 2 {
            0
        } else {
            silent
        }
    }

    /// The reaction `policy` asks for now, once per mission: `Some` the first time the silence
    /// reaches the timeout.
    pub fn check(&mut self, policy: &LinkLossPolicy) -> Option<LinkLossReaction> {
        if policy.timeout_ms == 0 || self.reacted || self.silent_ms() < policy.timeout_ms {
            return None;
        }
        self.reacted = true;
        Some(policy.reaction)
    }

    /// Milliseconds until [`LinkWatch::check`] would react, if it still may (a timeout, not
    /// reacted yet): 0 when it would react now. A shell that sleeps between checks sleeps no
    /// longer than this, so that it reacts at the timeout.
    pub fn reaction_in_ms(&self, policy: &LinkLossPolicy) -> Option<u32> {
        if policy.timeout_ms == 0 || self.reacted {
            return None;
        }
        Some(policy.timeout_ms.saturating_sub(self.silent_ms()))
    }
}

/// Why a mission was stopped from outside its own logic (`MissionReport::stop_cause`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StopCause {
    /// Not stopped from outside (it ended by itself, or still runs).
    #[default]
    None,
    /// The host's `AbortMission`.
    Host,
    /// `EmergencyStop` (the request or the board's input).
    EmergencyStop,
    /// The host fell silent ([`LinkLossReaction::StopAndHold`]).
    LinkLost,
    /// A control step missed its period ([`control_period_missed`]).
    ControllerOverrun,
    /// A part of the robot's body failed (`twil_core::drivers::body`): the mission cannot
    /// trust what it senses or drives.
    SensorFault(Sensor),
}

/// Which part of the body failed ([`StopCause::SensorFault`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Sensor {
    /// The neck's home switch did not close within the homing travel (or the neck was asked
    /// to move before homing).
    NeckHome,
    /// A neck pin (step, direction, home switch) failed, or a move beyond its limits was asked.
    Neck,
    /// The sonar's trigger pin failed, or its capture has no clock.
    SonarTrigger,
    /// The sonar did not answer: no edge on its echo line for several pings in a row.
    SonarSilent,
    /// The battery could not be read, or reads below the motors' minimum.
    Battery,
    /// A motor's PWM channel or direction pin failed.
    Motor,
    /// The emergency-stop input could not be read (the motors stopped as if pressed).
    EmergencyStopInput,
}

impl Sensor {
    /// Words for messages.
    pub fn describe(self) -> &'static str {
        match self {
            Sensor::NeckHome => "the neck's home switch was not found",
            Sensor::Neck => "a neck pin failed",
            Sensor::SonarTrigger => "the sonar's trigger failed",
            Sensor::SonarSilent => "the sonar does not answer",
            Sensor::Battery => "the battery reading failed or is below the minimum",
            Sensor::Motor => "a motor's PWM or direction pin failed",
            Sensor::EmergencyStopInput => "the emergency-stop input cannot be read",
        }
    }

    /// A short name for JSON (`neck_home`, `battery`, …).
    pub fn name(self) -> &'static str {
        match self {
            Sensor::NeckHome => "neck_home",
            Sensor::Neck => "neck",
            Sensor::SonarTrigger => "sonar_trigger",
            Sensor::SonarSilent => "sonar_silent",
            Sensor::Battery => "battery",
            Sensor::Motor => "motor",
            Sensor::EmergencyStopInput => "emergency_stop_input",
        }
    }
}

/// Words for messages: a sensor fault names its sensor
/// (`sensor fault: the sonar does not answer`).
impl core::fmt::Display for StopCause {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            StopCause::None => f.write_str("none"),
            StopCause::Host => f.write_str("aborted by the host"),
            StopCause::EmergencyStop => f.write_str("emergency stop"),
            StopCause::LinkLost => f.write_str("link lost"),
            StopCause::ControllerOverrun => f.write_str("controller overrun"),
            StopCause::SensorFault(sensor) => write!(f, "sensor fault: {}", sensor.describe()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reset_causes_decode_with_the_most_specific_flag() {
        assert_eq!(ResetCause::from_rcc_csr(0), ResetCause::Unknown);
        // LSION / LSIRDY and RMVF are not causes.
        assert_eq!(ResetCause::from_rcc_csr(0b11), ResetCause::Unknown);
        // A power-on sets POR, BOR and PIN.
        let por = RCC_CSR_PORRSTF | RCC_CSR_BORRSTF | RCC_CSR_PINRSTF;
        assert_eq!(ResetCause::from_rcc_csr(por), ResetCause::PowerOn);
        assert_eq!(
            ResetCause::from_rcc_csr(RCC_CSR_BORRSTF | RCC_CSR_PINRSTF),
            ResetCause::Brownout
        );
        assert_eq!(ResetCause::from_rcc_csr(RCC_CSR_PINRSTF), ResetCause::Pin);
        // Internal resets pulse NRST too.
        assert_eq!(
            ResetCause::from_rcc_csr(RCC_CSR_IWDGRSTF | RCC_CSR_PINRSTF),
            ResetCause::IndependentWatchdog
        );
        assert_eq!(
            ResetCause::from_rcc_csr(RCC_CSR_SFTRSTF | RCC_CSR_PINRSTF | 0b11),
            ResetCause::Software
        );
        assert_eq!(
            ResetCause::from_rcc_csr(RCC_CSR_WWDGRSTF | RCC_CSR_PINRSTF),
            ResetCause::WindowWatchdog
        );
        assert_eq!(
            ResetCause::from_rcc_csr(RCC_CSR_LPWRRSTF | RCC_CSR_PINRSTF),
            ResetCause::LowPower
        );
    }

    /// Run the gate with the control task ticking every 50 ms and the mission task turning
    /// every `mission_every_ms` until `stall_at_ms` (then never again); the time of the first
    /// refusal.
    fn first_starve(mission_every_ms: u32, stall_at_ms: Option<u32>) -> Option<u32> {
        let mut gate = WatchdogGate::new(WatchdogGate::MISSION_LIMIT_MS, 0);
        for now in 1..=10_000u32 {
            if now % mission_every_ms == 0 && stall_at_ms.is_none_or(|s| now < s) {
                gate.mission_turned(now);
            }
            if now % 50 == 0 {
                gate.control_ticked(now);
                if let WatchdogDecision::Starve { .. } = gate.check(now) {
                    return Some(now);
                }
            }
        }
        None
    }

    #[test]
    fn both_tasks_alive_feed_the_watchdog() {
        assert_eq!(first_starve(1, None), None);
        // A mission task busy 900 ms at a time (a long request) still feeds.
        assert_eq!(first_starve(900, None), None);
    }

    #[test]
    fn a_stalled_mission_task_starves_the_watchdog_for_good() {
        // Last turn at 2 999 ms: refused at the first check more than a second later.
        assert_eq!(first_starve(1, Some(3_000)), Some(4_000));
        let mut gate = WatchdogGate::new(100, 0);
        gate.mission_turned(0);
        assert!(matches!(
            gate.check(150),
            WatchdogDecision::Starve {
                mission_silent_ms: 150,
                ..
            }
        ));
        // The mission task turning again does not bring the feed back: the chip must reset.
        gate.mission_turned(160);
        gate.control_ticked(160);
        assert_ne!(gate.check(170), WatchdogDecision::Feed);
    }

    #[test]
    fn a_stalled_control_task_starves_the_watchdog() {
        let mut gate = WatchdogGate::new(100, 0);
        gate.control_ticked(50);
        gate.mission_turned(200);
        assert_eq!(
            gate.check(200),
            WatchdogDecision::Starve {
                control_silent_ms: 150,
                mission_silent_ms: 0
            }
        );
    }

    #[test]
    fn the_gate_survives_the_millisecond_wrap() {
        let start = u32::MAX - 20;
        let mut gate = WatchdogGate::new(100, start);
        for k in 1..10u32 {
            let now = start.wrapping_add(k * 10);
            gate.control_ticked(now);
            gate.mission_turned(now);
            assert_eq!(gate.check(now), WatchdogDecision::Feed);
        }
    }

    #[test]
    fn a_missed_period_is_a_step_ending_after_the_next_deadline() {
        assert!(!control_period_missed(1_000, 1_000, 50));
        assert!(!control_period_missed(1_000, 1_050, 50));
        assert!(control_period_missed(1_000, 1_051, 50));
        // Woke two periods late.
        assert!(control_period_missed(1_000, 1_100, 50));
        // Across the wrap.
        assert!(control_period_missed(u32::MAX - 10, 45, 50));
        assert!(!control_period_missed(u32::MAX - 10, 30, 50));
        // A clock reading "before" the schedule is not an overrun.
        assert!(!control_period_missed(1_000, 990, 50));
    }

    #[test]
    fn link_watch_reacts_once_at_the_timeout() {
        let policy = LinkLossPolicy {
            timeout_ms: 2_000,
            reaction: LinkLossReaction::StopAndHold,
        };
        let mut watch = LinkWatch::new();
        watch.set_now_ms(10_000);
        watch.start();
        // Heartbeats every 500 ms: never.
        for k in 1..=20 {
            watch.set_now_ms(10_000 + 500 * k);
            watch.heard();
            assert_eq!(watch.check(&policy), None);
        }
        // Then silence.
        let last = 20_000;
        watch.set_now_ms(last + 1_999);
        assert_eq!(watch.reaction_in_ms(&policy), Some(1));
        assert_eq!(watch.check(&policy), None);
        watch.set_now_ms(last + 2_000);
        assert_eq!(watch.reaction_in_ms(&policy), Some(0));
        assert_eq!(watch.check(&policy), Some(LinkLossReaction::StopAndHold));
        assert_eq!(watch.reaction_in_ms(&policy), None, "reacted");
        watch.set_now_ms(last + 5_000);
        assert_eq!(watch.check(&policy), None, "once per mission");
        watch.start();
        watch.set_now_ms(last + 7_000);
        assert_eq!(watch.check(&policy), Some(LinkLossReaction::StopAndHold));
        // Timeout 0: never.
        assert_eq!(watch.check(&LinkLossPolicy::NEVER), None);
        assert_eq!(watch.reaction_in_ms(&LinkLossPolicy::NEVER), None);
    }

    #[test]
    fn link_loss_timeouts_are_zero_or_in_range() {
        let p = |timeout_ms| LinkLossPolicy {
            timeout_ms,
            reaction: LinkLossReaction::Continue,
        };
        assert!(p(0).is_valid());
        assert!(!p(199).is_valid());
        assert!(p(200).is_valid());
        assert!(p(3_600_000).is_valid());
        assert!(!p(3_600_001).is_valid());
        assert!(!p(u32::MAX).is_valid());
    }
}
