//! Drivers for Twil's boards: the logic between embedded-hal 1.0 pins and the robot's units.
//!
//! The seed's robot (seed 003, "placas de interface") had a PC with interface boards for two
//! sonars, the neck stepper, the two wheel motors and their encoders. Here one microcontroller
//! drives those signals directly; this module holds everything about them that is not a
//! register: pulse widths, unit conversions, limits, wrap-around, fail-safe defaults. The
//! firmware's board module (`firmware/src/board.rs`) only maps these drivers onto STM32F405
//! peripherals, so every rule below is unit-tested on the host with `embedded-hal-mock`.
//!
//! Traits: [`embedded_hal::digital::OutputPin`] / [`InputPin`](embedded_hal::digital::InputPin),
//! [`embedded_hal::pwm::SetDutyCycle`] and [`embedded_hal::delay::DelayNs`] where embedded-hal
//! has them; two small traits of ours where it has none: [`EchoCapture`] (time an echo pulse) and
//! [`QuadratureCounter`] (read a 16-bit hardware encoder counter).
//!
//! | driver | file | seed part it models | units |
//! |---|---|---|---|
//! | [`SonarRanger`] | `sonar_ranger.rs` | `le_sonar.c` / `sonar.cpp`: `trig()`, wait `DELAY`, echo → range, `DIST_MIN` … `ALCANCE_SONAR` | trigger µs, echo ticks at a stated tick rate, range m |
//! | [`NeckStepper`] | `neck_stepper.rs` | `pmotor.reset()` / `pmotor.step(dir)`, 1.8° per step | steps, degrees |
//! | [`Motor`] | `motor.rs` | `twlckin.cpp` `saturate(±11.7)`: the controller's volts become a PWM duty | V, duty fraction |
//! | [`WheelEncoder`] | `wheel_encoder.rs` | `twlckin.cpp` odometry input: counts per 50 ms period | counts |
//! | [`EmergencyStop`] | `emergency_stop.rs` | new: the seed's robot stopped from its PC; ours needs a button | latched bool |
//!
//! Every driver is a small struct around its pins plus pure functions that hold the logic, so
//! an async firmware task can call the pure parts itself (arm the capture, await the edge,
//! convert with [`sonar_ranger::range_from_echo_ticks`]) while tests and blocking code use the
//! struct. No driver panics on any input: bad numbers and pin errors are error values.

pub mod emergency_stop;
pub mod motor;
pub mod neck_stepper;
pub mod sonar_ranger;
pub mod wheel_encoder;

pub use emergency_stop::{ActiveLevel, EmergencyStop};
pub use motor::{Motor, MotorError};
pub use neck_stepper::{NeckError, NeckGeometry, NeckStepper};
pub use sonar_ranger::{EchoCapture, SonarError, SonarRanger, SonarWindow};
pub use wheel_encoder::{Mounting, QuadratureCounter, WheelCounts, WheelEncoder};
