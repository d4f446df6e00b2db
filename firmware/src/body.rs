//! The robot's body behind one interface for both builds: the wheels (encoders in, motor
//! voltages out, the emergency-stop input) and the sonar head.
//!
//! - QEMU build: the simulated robot of `twil_core::plant` stands in for the drivers. The
//!   control task reads its encoder counts and steps it with the voltages for one period (that
//!   cost is measured apart from the control step's); the sonar task casts the sonar's ray on
//!   the real world the host uploaded (`WorldChunk`), from the plant's true pose.
//! - Board build: the drivers of `twil_core::drivers` on the pins of [`crate::board`].
//!
//! Wiring only: the rules live in `twil-core`.

use twil_core::mission::MissionConfig;

#[cfg(feature = "qemu")]
pub use sim::*;

#[cfg(feature = "hardware")]
pub use board_body::*;

#[cfg(feature = "qemu")]
mod sim {
    use super::MissionConfig;
    use twil_core::control::Pose;
    use twil_core::link::WorldUpload;
    use twil_core::plant::Plant;
    use twil_core::robot::RobotConfig;

    /// The simulated robot: its true pose, wheels and encoders.
    pub struct Body {
        plant: Plant,
        previous_counts: (i32, i32),
    }

    impl Body {
        /// A robot at the origin (until a mission puts it at its start).
        pub fn new() -> Self {
            let plant = Plant::new(&RobotConfig::DEFAULT, Pose::default());
            let previous_counts = plant.encoder_counts();
            Self {
                plant,
                previous_counts,
            }
        }

        /// Put the robot at the start of `config`'s mission, standing.
        pub fn restart(&mut self, config: &MissionConfig) {
            self.plant = Plant::new(
                &config.robot,
                Pose::new(
                    config.start.x_m,
                    config.start.y_m,
                    config.initial_heading_rad,
                ),
            );
            self.previous_counts = self.plant.encoder_counts();
        }

        /// Encoder counts since the previous call (left, right).
        pub fn encoder_deltas(&mut self) -> (i32, i32) {
            let counts = self.plant.encoder_counts();
            let deltas = (
                counts.0.wrapping_sub(self.previous_counts.0),
                counts.1.wrapping_sub(self.previous_counts.1),
            );
            self.previous_counts = counts;
            deltas
        }

        /// Apply the voltages for one period (the simulated robot moves).
        pub fn drive(&mut self, left_voltage_v: f32, right_voltage_v: f32, period_s: f32) {
            self.plant.step(period_s, left_voltage_v, right_voltage_v);
        }

        /// The emergency-stop input (none in the simulation).
        pub fn emergency_stop(&mut self) -> bool {
            false
        }

        /// A copy of the simulated robot, for the sonar's ray cast (the plant is small; the
        /// cast then runs without holding the control task's resource).
        pub fn snapshot(&self) -> Plant {
            self.plant.clone()
        }
    }

    impl Default for Body {
        fn default() -> Self {
            Self::new()
        }
    }

    /// The real world the simulated sonar sees.
    pub type World = &'static mut WorldUpload;

    /// The sonar head: nothing of its own in the simulation (the ray is cast from the body).
    pub struct Head;

    /// One sonar reading at `neck_angle_rad` from `body` in `world`, up to `range_m`.
    pub fn sonar_range_m(
        body: &mut Plant,
        world: &WorldUpload,
        neck_angle_rad: f32,
        range_m: f32,
    ) -> Option<f32> {
        body.sonar_range_m(&world.obstacles, neck_angle_rad, range_m)
    }
}

#[cfg(feature = "hardware")]
mod board_body {
    use super::MissionConfig;
    use crate::board::{Board, HeadPins, MotorLeft, MotorRight, SYSCLK_HZ};
    use crate::{instructions, note_worst, Mono};
    use core::sync::atomic::AtomicU32;
    use embedded_hal::digital::{InputPin, OutputPin};
    use rtic_monotonics::systick::prelude::*;
    use rtic_monotonics::Timebase;
    use stm32f4xx_hal::gpio;
    use twil_core::drivers::emergency_stop::{is_active, EmergencyStop};
    use twil_core::drivers::neck_stepper::{
        angle_to_steps, NeckError, NeckGeometry, StepDirection, STEP_PULSE_NS,
    };
    use twil_core::drivers::sonar_ranger::{range_from_echo_ticks, TRIGGER_PULSE_US};
    use twil_core::drivers::wheel_encoder::WheelEncoder;
    use twil_core::drivers::SonarWindow;

    /// The wheels: encoders, motors, the emergency stop and the battery.
    pub struct Body {
        wheel_left: WheelEncoder<crate::board::WheelCounter<stm32f4xx_hal::pac::TIM3>>,
        wheel_right: WheelEncoder<crate::board::WheelCounter<stm32f4xx_hal::pac::TIM4>>,
        motor_left: MotorLeft,
        motor_right: MotorRight,
        estop: EmergencyStop<gpio::PB5<gpio::Input>>,
        battery: crate::board::BatteryMonitor,
    }

    /// Split the board into the wheels and the sonar head.
    pub fn split(board: Board) -> (Body, Head) {
        (
            Body {
                wheel_left: board.wheel_left,
                wheel_right: board.wheel_right,
                motor_left: board.motor_left,
                motor_right: board.motor_right,
                estop: board.estop,
                battery: board.battery,
            },
            Head {
                pins: board.head,
                window: board.window,
                geometry: board.geometry,
                position_steps: None,
                last_trigger: None,
            },
        )
    }

    impl Body {
        /// A new mission: nothing to reset (the odometry starts afresh in the pilot).
        pub fn restart(&mut self, _config: &MissionConfig) {}

        /// Encoder counts since the previous call (left, right); implausible jumps count 0.
        pub fn encoder_deltas(&mut self) -> (i32, i32) {
            let l = self.wheel_left.read().trusted().unwrap_or(0);
            let r = self.wheel_right.read().trusted().unwrap_or(0);
            (l, r)
        }

        /// Apply the voltages until the next period, at the measured battery voltage (the
        /// conversion started one period ago: no wait); any error stops both motors.
        pub fn drive(&mut self, left_voltage_v: f32, right_voltage_v: f32, _period_s: f32) {
            let battery_v = self.battery.read_battery_v();
            let ok = self
                .motor_left
                .set_voltage(left_voltage_v, battery_v)
                .is_ok()
                && self
                    .motor_right
                    .set_voltage(right_voltage_v, battery_v)
                    .is_ok();
            if !ok {
                let _ = self.motor_left.stop();
                let _ = self.motor_right.stop();
            }
        }

        /// The emergency-stop input (latched by the driver).
        pub fn emergency_stop(&mut self) -> bool {
            self.estop.poll()
        }
    }

    /// A board has no simulated world.
    pub type World = ();

    /// Least time between two triggers, ms: the HC-SR04 holds its echo high up to 38 ms with
    /// no target and asks for at least 60 ms between pings (its data sheet, "we suggest to use
    /// over 60 ms measurement cycle"), so an echo of the previous ping cannot be timed.
    pub const PING_CYCLE_MS: u32 = 60;

    /// Set-up time of the direction input before a step edge, cycles at [`SYSCLK_HZ`]: 1 µs
    /// (DRV8825: 650 ns, A4988: 200 ns).
    const DIR_SETUP_CYCLES: u32 = SYSCLK_HZ / 1_000_000;

    /// The sonar head: the top sonar and the neck, driven asynchronously. Every wait of a
    /// millisecond or more is a `Mono` delay; the only waits in a loop are the 10 µs trigger
    /// pulse, the 2 µs step pulse and the 1 µs direction set-up, at the sonar task's priority
    /// (below the USART's and `link_rx`'s).
    pub struct Head {
        pins: HeadPins,
        window: SonarWindow,
        geometry: NeckGeometry,
        /// Steps from straight ahead; `None` until homed.
        position_steps: Option<i32>,
        /// When the last ping was triggered.
        last_trigger: Option<<Mono as Timebase>::Instant>,
    }

    impl Head {
        /// Step towards the home switch until it closes, at most
        /// `geometry.max_homing_steps` steps (a broken switch ends with `HomeNotFound`, never
        /// an endless turn). Returns the steps taken.
        pub async fn home(&mut self) -> Result<u32, NeckError> {
            self.position_steps = None;
            let direction = self.geometry.homing_direction;
            let mut next = Mono::now();
            let mut steps = 0;
            loop {
                let high = InputPin::is_high(&mut self.pins.home)
                    .map_err(|_| NeckError::Pin { pin: "home" })?;
                if is_active::<()>(Ok(high), self.geometry.home_active) {
                    self.position_steps = Some(self.geometry.home_offset_steps);
                    return Ok(steps);
                }
                if steps >= self.geometry.max_homing_steps {
                    return Err(NeckError::HomeNotFound { steps });
                }
                self.step(direction, steps == 0);
                steps += 1;
                next += step_period(&self.geometry);
                Mono::delay_until(next).await;
            }
        }

        /// Turn to the step nearest `angle_rad`, then ping; `Ok(None)` is no echo. The
        /// cycles spent in pulses are noted in `worst` (the waits are not work).
        pub async fn read(
            &mut self,
            angle_rad: f32,
            worst: &AtomicU32,
        ) -> Result<Option<f32>, NeckError> {
            let target = angle_to_steps(&self.geometry, angle_rad.to_degrees())?;
            let start = self.position_steps.ok_or(NeckError::NotHomed)?;
            let direction = if target > start {
                StepDirection::Positive
            } else {
                StepDirection::Negative
            };
            let mut next = Mono::now();
            let mut first = true;
            // Unknown while moving: a fault midway leaves it unknown.
            self.position_steps = None;
            for _ in 0..target.abs_diff(start) {
                let before = instructions();
                self.step(direction, first);
                note_worst(worst, instructions().saturating_sub(before));
                first = false;
                next += step_period(&self.geometry);
                Mono::delay_until(next).await;
            }
            self.position_steps = Some(target);

            // Ping: no sooner than PING_CYCLE_MS after the last one.
            if let Some(last) = self.last_trigger {
                Mono::delay_until(last + PING_CYCLE_MS.millis()).await;
            }
            self.pins.echo.arm();
            let before = instructions();
            let _ = OutputPin::set_high(&mut self.pins.trigger);
            cortex_m::asm::delay(TRIGGER_PULSE_US * (SYSCLK_HZ / 1_000_000));
            let _ = OutputPin::set_low(&mut self.pins.trigger);
            note_worst(worst, instructions().saturating_sub(before));
            let now = Mono::now();
            self.last_trigger = Some(now);
            // The echo window: both edges are latched by the timer meanwhile.
            let window_ms = self.window.timeout_us.div_ceil(1_000);
            Mono::delay_until(now + window_ms.millis()).await;
            let edges = self.pins.echo.edges();
            Ok(range_from_echo_ticks(
                &self.window,
                edges.width_ticks(),
                crate::board::ECHO_TICK_HZ,
            ))
        }

        /// One step pulse (direction first, with its set-up time when it may have changed).
        fn step(&mut self, direction: StepDirection, set_direction: bool) {
            if set_direction {
                let high =
                    (direction == StepDirection::Positive) == self.geometry.positive_dir_high;
                let _ = if high {
                    OutputPin::set_high(&mut self.pins.dir)
                } else {
                    OutputPin::set_low(&mut self.pins.dir)
                };
                cortex_m::asm::delay(DIR_SETUP_CYCLES);
            }
            let _ = OutputPin::set_high(&mut self.pins.step);
            cortex_m::asm::delay(STEP_PULSE_NS.div_ceil(1_000) * (SYSCLK_HZ / 1_000_000));
            let _ = OutputPin::set_low(&mut self.pins.step);
        }
    }

    /// Time per step as a `Mono` duration (whole milliseconds, at least one).
    fn step_period(geometry: &NeckGeometry) -> <Mono as Timebase>::Duration {
        geometry.step_period_ns.div_ceil(1_000_000).max(1).millis()
    }
}
