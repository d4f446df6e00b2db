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
//! has them; three small traits of ours where it has none: [`EchoCapture`] (the echo line's
//! edges, with their polarity), [`QuadratureCounter`] (read a 16-bit hardware encoder counter)
//! and [`BatterySensor`] (the battery's voltage: embedded-hal 1.0 has no ADC trait).
//!
//! [`body`] puts them together as the firmware's board build uses them: [`Chassis`] (motors,
//! encoders, e-stop, battery) and [`SonarHead`] (neck and sonar), with the power-up, mission
//! start and fault rules; `tests/virtual_board.rs` runs it on pins driven by a scripted world.
//!
//! | driver | file | seed part it models | units |
//! |---|---|---|---|
//! | [`EchoDecoder`] | `echo.rs` | the echo line's edges → a pulse width or why none (HC-SR04 timing) | ticks |
//! | [`SonarRanger`] | `sonar_ranger.rs` | `le_sonar.c` / `sonar.cpp`: `trig()`, wait `DELAY`, echo → range, `DIST_MIN` … `ALCANCE_SONAR` | trigger µs, echo ticks at a stated tick rate, range m |
//! | [`NeckStepper`] | `neck_stepper.rs` | `pmotor.reset()` / `pmotor.step(dir)`, 1.8° per step | steps, degrees |
//! | [`Motor`] | `motor.rs` | `twlckin.cpp` `saturate(±11.7)`: the controller's volts become a PWM duty | V, duty fraction |
//! | [`WheelEncoder`] | `wheel_encoder.rs` | `twlckin.cpp` odometry input: counts per 50 ms period | counts |
//! | [`EmergencyStop`] | `emergency_stop.rs` | new: the seed's robot stopped from its PC; ours needs a button | latched bool |
//! | [`BatterySensor`] | `battery.rs` | new: the duty is volts over the measured battery | V |
//! | [`Chassis`], [`SonarHead`] | `body.rs` | the board's body: power-up, mission start, faults as stop causes | |
//!
//! Every driver is a small struct around its pins plus pure functions that hold the logic, so
//! an async firmware task can call the pure parts itself (arm the capture, await the edge,
//! convert with [`sonar_ranger::range_from_echo_ticks`]) while tests and blocking code use the
//! struct. No driver panics on any input: bad numbers and pin errors are error values.

pub mod battery;
pub mod body;
pub mod echo;
pub mod emergency_stop;
pub mod motor;
pub mod neck_stepper;
pub mod sonar_ranger;
pub mod wheel_encoder;

pub use battery::{BatteryReadError, BatterySensor};
pub use body::{Chassis, Drive, SonarHead, WheelPulse};
pub use echo::{EchoDecoder, EchoEdge, EchoOutcome};
pub use emergency_stop::{ActiveLevel, EmergencyStop};
pub use motor::{Motor, MotorError};
pub use neck_stepper::{NeckError, NeckGeometry, NeckProgress, NeckStepper};
pub use sonar_ranger::{EchoCapture, SonarError, SonarRanger, SonarReading, SonarWindow};
pub use wheel_encoder::{Mounting, QuadratureCounter, WheelCounts, WheelEncoder};
