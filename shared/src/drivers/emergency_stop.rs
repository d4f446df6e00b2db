//! Emergency-stop input: a button (or a bumper chain) on one pin, latched until cleared.
//!
//! The seed's robot was stopped from its PC; a robot whose brain is a microcontroller needs a
//! button that stops the motors whatever the mission is doing. The rules, all fail-safe:
//!
//! - the active level is configurable ([`ActiveLevel`]): a normally-closed button to ground
//!   with a pull-up reads low while all is well and high when pressed *or when its wire
//!   breaks*, so `ActiveLevel::High` is the safe choice for that wiring;
//! - **power-up**: the stop starts latched, so a reset never starts the wheels;
//! - once seen pressed, the stop stays latched: releasing the button does not restart the
//!   motors, only [`EmergencyStop::clear`] does (the body calls it when a mission starts,
//!   after the host has cleared its own latch with `ClearEmergencyStop`), and only while the
//!   button is released;
//! - even then the motors get duty only once [`poll`](EmergencyStop::poll) has read the button
//!   released [`RELEASED_POLLS_TO_RUN`] times in a row (a bouncing contact or a hand still on
//!   the button does not start the wheels);
//! - a pin that cannot be read counts as pressed, and is told apart
//!   ([`EmergencyStop::last_trip_was_read_error`]) so it can be reported as a fault of the
//!   input rather than a press.
//!
//! The body ([`super::body::Chassis`]) polls it every control period, before the motors get
//! their duty, so a press stops them within one period; a press (or a read error) that latches
//! the stop while a mission runs is *reported* (`StopCause::EmergencyStop`).

use embedded_hal::digital::InputPin;

/// Which pin level means "active" (pressed, closed).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ActiveLevel {
    /// High = active.
    High,
    /// Low = active.
    Low,
}

/// Whether a pin reading means "active": `level_high` is `Ok(true)` for a high pin; a read
/// error counts as active (fail safe).
pub fn is_active<E>(level_high: Result<bool, E>, active: ActiveLevel) -> bool {
    match (level_high, active) {
        (Ok(high), ActiveLevel::High) => high,
        (Ok(high), ActiveLevel::Low) => !high,
        (Err(_), _) => true,
    }
}

/// Why the stop could not be cleared.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum EstopError {
    /// The button is still pressed (or its pin cannot be read): the stop stays latched.
    StillPressed,
}

impl core::fmt::Display for EstopError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            EstopError::StillPressed => write!(
                f,
                "the emergency stop button is still pressed (or its pin cannot be read)"
            ),
        }
    }
}

impl core::error::Error for EstopError {}

/// Polls in a row that must read the button released before the motors get duty (3 control
/// periods: 150 ms, far longer than a contact's bounce of a few milliseconds).
pub const RELEASED_POLLS_TO_RUN: u32 = 3;

/// The latched emergency-stop input.
pub struct EmergencyStop<P> {
    pin: P,
    active: ActiveLevel,
    latched: bool,
    released_polls: u32,
    last_read_failed: bool,
    last_trip_read_error: bool,
    read_errors: u32,
    trips: u32,
}

impl<P: InputPin> EmergencyStop<P> {
    /// A stop input on `pin`. It starts latched: the motors stay off until the button has
    /// been read released and the stop cleared (a reset must not start the wheels).
    pub fn new(pin: P, active: ActiveLevel) -> Self {
        Self {
            pin,
            active,
            latched: true,
            released_polls: 0,
            last_read_failed: false,
            last_trip_read_error: false,
            read_errors: 0,
            trips: 0,
        }
    }

    fn pressed_now(&mut self) -> bool {
        let level = self.pin.is_high();
        self.last_read_failed = level.is_err();
        if self.last_read_failed {
            self.read_errors = self.read_errors.wrapping_add(1);
        }
        is_active(level, self.active)
    }

    fn latch(&mut self, read_error: bool) {
        if !self.latched {
            self.latched = true;
            self.trips = self.trips.wrapping_add(1);
            self.last_trip_read_error = read_error;
        }
    }

    /// Read the pin; latch if pressed (or unreadable), count the released reads. Returns
    /// whether the motors must be off: latched, or released for fewer than
    /// [`RELEASED_POLLS_TO_RUN`] polls in a row.
    pub fn poll(&mut self) -> bool {
        if self.pressed_now() {
            self.released_polls = 0;
            self.latch(self.last_read_failed);
        } else {
            self.released_polls = self.released_polls.saturating_add(1);
        }
        !self.motors_allowed()
    }

    /// Whether the motors may have duty: not latched, and released for
    /// [`RELEASED_POLLS_TO_RUN`] polls in a row (does not read the pin).
    pub fn motors_allowed(&self) -> bool {
        !self.latched && self.released_polls >= RELEASED_POLLS_TO_RUN
    }

    /// Read the pin now, for the self-test: pressed (or unreadable, see
    /// [`last_read_failed`](Self::last_read_failed)). A press latches as in a poll; a release
    /// changes nothing.
    pub fn read_pressed(&mut self) -> bool {
        let pressed = self.pressed_now();
        if pressed {
            self.released_polls = 0;
            self.latch(self.last_read_failed);
        }
        pressed
    }

    /// Latch from software (an abort request), as if pressed.
    pub fn trip(&mut self) {
        self.latch(false);
    }

    /// Whether the stop is latched, without reading the pin.
    pub fn is_latched(&self) -> bool {
        self.latched
    }

    /// Whether the last latch came from a pin that could not be read (rather than a press).
    pub fn last_trip_was_read_error(&self) -> bool {
        self.last_trip_read_error
    }

    /// Whether the last read of the pin (poll or clear) failed.
    pub fn last_read_failed(&self) -> bool {
        self.last_read_failed
    }

    /// Unlatch, if the button is released now; otherwise stay latched and say why. The
    /// motors still wait for [`RELEASED_POLLS_TO_RUN`] released polls.
    pub fn clear(&mut self) -> Result<(), EstopError> {
        if self.pressed_now() {
            self.latched = true;
            self.released_polls = 0;
            Err(EstopError::StillPressed)
        } else {
            self.latched = false;
            Ok(())
        }
    }

    /// Times the stop latched (button or [`trip`](Self::trip)) and pin read errors, for
    /// telemetry.
    pub fn counts(&self) -> (u32, u32) {
        (self.trips, self.read_errors)
    }

    /// Give the pin back.
    pub fn release(self) -> P {
        self.pin
    }
}

#[cfg(test)]
mod tests {
    extern crate std;

    use super::*;
    use embedded_hal_mock::eh1::digital::{
        Mock as PinMock, State as PinState, Transaction as PinTx,
    };
    use embedded_hal_mock::eh1::MockError;

    fn err() -> MockError {
        MockError::Io(std::io::ErrorKind::Other)
    }

    #[test]
    fn active_level_and_errors() {
        assert!(is_active::<()>(Ok(true), ActiveLevel::High));
        assert!(!is_active::<()>(Ok(false), ActiveLevel::High));
        assert!(is_active::<()>(Ok(false), ActiveLevel::Low));
        assert!(!is_active::<()>(Ok(true), ActiveLevel::Low));
        assert!(is_active(Err(()), ActiveLevel::High));
        assert!(is_active(Err(()), ActiveLevel::Low));
    }

    /// `n` reads of the released level (active high: low).
    fn released(n: usize) -> std::vec::Vec<PinTx> {
        std::vec![PinTx::get(PinState::Low); n]
    }

    #[test]
    fn starts_latched_and_runs_only_after_a_clear_and_three_released_polls() {
        let mut tx = std::vec![
            PinTx::get(PinState::High), // poll: pressed at power-up
            PinTx::get(PinState::High), // clear: still pressed (active high)
        ];
        tx.extend(released(1)); // clear: released
        tx.extend(released(3)); // three polls
        let mut pin = PinMock::new(&tx);
        let mut stop = EmergencyStop::new(pin.clone(), ActiveLevel::High);
        assert!(stop.is_latched());
        assert!(stop.poll());
        assert_eq!(stop.counts(), (0, 0), "already latched: not a new trip");
        assert_eq!(stop.clear(), Err(EstopError::StillPressed));
        assert!(stop.is_latched());
        assert_eq!(stop.clear(), Ok(()));
        assert!(stop.poll(), "released once: not yet");
        assert!(stop.poll(), "released twice: not yet");
        assert!(!stop.poll(), "released three times: the motors may run");
        assert!(stop.motors_allowed());
        pin.done();
    }

    #[test]
    fn a_press_latches_until_cleared_even_after_release() {
        let mut tx = released(3); // polls
        tx.push(PinTx::get(PinState::Low)); // clear
        tx.push(PinTx::get(PinState::High)); // poll: pressed
        tx.extend(released(4)); // polls: released again, still latched
        tx.extend(released(1)); // clear
        let mut pin = PinMock::new(&tx);
        let mut stop = EmergencyStop::new(pin.clone(), ActiveLevel::High);
        for _ in 0..3 {
            stop.poll();
        }
        assert_eq!(stop.clear(), Ok(()));
        assert!(
            stop.motors_allowed(),
            "three released polls before the clear count"
        );
        assert!(stop.poll());
        assert_eq!(stop.counts(), (1, 0));
        assert!(!stop.last_trip_was_read_error());
        for _ in 0..4 {
            assert!(stop.poll(), "released button does not unlatch");
        }
        assert_eq!(stop.clear(), Ok(()));
        assert!(stop.motors_allowed());
        pin.done();
    }

    #[test]
    fn a_read_error_counts_as_pressed_and_is_told_apart() {
        let mut tx = released(3);
        tx.push(PinTx::get(PinState::Low)); // clear: released
        tx.push(PinTx::get(PinState::Low).with_error(err()));
        tx.push(PinTx::get(PinState::Low).with_error(err())); // clear fails too
        let mut pin = PinMock::new(&tx);
        let mut stop = EmergencyStop::new(pin.clone(), ActiveLevel::High);
        for _ in 0..3 {
            stop.poll();
        }
        assert_eq!(stop.clear(), Ok(()));
        assert!(stop.poll());
        assert!(stop.last_trip_was_read_error());
        assert_eq!(stop.clear(), Err(EstopError::StillPressed));
        assert_eq!(stop.counts(), (1, 2));
        pin.done();
    }

    #[test]
    fn software_trip_latches_without_reading() {
        let mut pin = PinMock::new(&[PinTx::get(PinState::Low)]);
        let mut stop = EmergencyStop::new(pin.clone(), ActiveLevel::High);
        assert_eq!(stop.clear(), Ok(()));
        stop.trip();
        assert!(stop.is_latched());
        assert!(!stop.motors_allowed());
        assert_eq!(stop.counts(), (1, 0));
        pin.done();
    }
}
