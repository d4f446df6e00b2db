//! Battery voltage: a small trait of ours, since embedded-hal 1.0 has no ADC trait.
//!
//! The motors' duty is `volts / battery volts` ([`super::motor`]), so the battery is read
//! every control period. A reading that fails, or one below
//! [`MIN_BATTERY_V`](super::motor::MIN_BATTERY_V), turns the motors off; the body reports it
//! as a sensor fault (`Sensor::Battery`) that ends the mission, never as silence (issue 24,
//! finding 7).

/// A reading could not be taken (ADC error, time-out, an implausible raw value).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BatteryReadError;

impl core::fmt::Display for BatteryReadError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "the battery voltage could not be read")
    }
}

impl core::error::Error for BatteryReadError {}

/// Reads the battery's voltage (an ADC channel behind a divider on the board).
pub trait BatterySensor {
    /// The battery's voltage now, volts.
    fn read_battery_v(&mut self) -> Result<f32, BatteryReadError>;
}
