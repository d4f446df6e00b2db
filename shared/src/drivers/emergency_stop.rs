//! Emergency-stop input: a button (or a bumper chain) on one pin, latched until cleared.
//!
//! The seed's robot was stopped from its PC; a robot whose brain is a microcontroller needs a
//! button that stops the motors whatever the mission is doing. The rules, all fail-safe:
//!
//! - the active level is configurable ([`ActiveLevel`]): a normally-closed button to ground
//!   with a pull-up reads low while all is well and high when pressed *or when its wire
//!   breaks*, so `ActiveLevel::High` is the safe choice for that wiring;
//! - once seen pressed, the stop stays latched: releasing the button does not restart the
//!   motors, only [`EmergencyStop::clear`] does, and only while the button is released;
//! - a pin that cannot be read counts as pressed.
//!
//! The firmware polls it every control period (or from the pin's interrupt) and, while
//! [`EmergencyStop::is_latched`], forces both motors to zero with
//! [`Motor::stop`](super::Motor::stop).

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

/// The latched emergency-stop input.
pub struct EmergencyStop<P> {
    pin: P,
    active: ActiveLevel,
    latched: bool,
    read_errors: u32,
    trips: u32,
}

impl<P: InputPin> EmergencyStop<P> {
    /// A stop input on `pin`. It starts latched: the motors stay off until the firmware has
    /// seen the button released and cleared it once (a reset must not start the wheels).
    pub fn new(pin: P, active: ActiveLevel) -> Self {
        Self {
            pin,
            active,
            latched: true,
            read_errors: 0,
            trips: 0,
        }
    }

    fn pressed_now(&mut self) -> bool {
        let level = self.pin.is_high();
        if level.is_err() {
            self.read_errors = self.read_errors.wrapping_add(1);
        }
        is_active(level, self.active)
    }

    /// Read the pin; latch if pressed. Returns whether the stop is latched (motors must be off).
    pub fn poll(&mut self) -> bool {
        if self.pressed_now() && !self.latched {
            self.latched = true;
            self.trips = self.trips.wrapping_add(1);
        }
        self.latched
    }

    /// Latch from software (an abort request), as if pressed.
    pub fn trip(&mut self) {
        if !self.latched {
            self.latched = true;
            self.trips = self.trips.wrapping_add(1);
        }
    }

    /// Whether the stop is latched, without reading the pin.
    pub fn is_latched(&self) -> bool {
        self.latched
    }

    /// Unlatch, if the button is released now; otherwise stay latched and say why.
    pub fn clear(&mut self) -> Result<(), EstopError> {
        if self.pressed_now() {
            self.latched = true;
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

    #[test]
    fn starts_latched_and_clears_only_when_released() {
        let mut pin = PinMock::new(&[
            PinTx::get(PinState::High), // clear: still pressed (active high)
            PinTx::get(PinState::Low),  // clear: released
            PinTx::get(PinState::Low),  // poll: released
        ]);
        let mut stop = EmergencyStop::new(pin.clone(), ActiveLevel::High);
        assert!(stop.is_latched());
        assert_eq!(stop.clear(), Err(EstopError::StillPressed));
        assert!(stop.is_latched());
        assert_eq!(stop.clear(), Ok(()));
        assert!(!stop.poll());
        pin.done();
    }

    #[test]
    fn a_press_latches_until_cleared_even_after_release() {
        let mut pin = PinMock::new(&[
            PinTx::get(PinState::High), // clear at start-up: released (active low)
            PinTx::get(PinState::High), // poll: released
            PinTx::get(PinState::Low),  // poll: pressed
            PinTx::get(PinState::High), // poll: released again, still latched
            PinTx::get(PinState::High), // clear
            PinTx::get(PinState::High), // poll
        ]);
        let mut stop = EmergencyStop::new(pin.clone(), ActiveLevel::Low);
        assert_eq!(stop.clear(), Ok(()));
        assert!(!stop.poll());
        assert!(stop.poll());
        assert!(stop.poll(), "released button does not unlatch");
        assert_eq!(stop.clear(), Ok(()));
        assert!(!stop.poll());
        assert_eq!(stop.counts(), (1, 0));
        pin.done();
    }

    #[test]
    fn a_read_error_counts_as_pressed() {
        let mut pin = PinMock::new(&[
            PinTx::get(PinState::Low), // clear: released (active high)
            PinTx::get(PinState::Low).with_error(err()),
            PinTx::get(PinState::Low).with_error(err()), // clear fails too
        ]);
        let mut stop = EmergencyStop::new(pin.clone(), ActiveLevel::High);
        assert_eq!(stop.clear(), Ok(()));
        assert!(stop.poll());
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
        assert_eq!(stop.counts(), (1, 0));
        pin.done();
    }
}
