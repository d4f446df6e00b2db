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
    use crate::board::{Board, MotorLeft, MotorRight, Neck, SonarTop};
    use twil_core::drivers::emergency_stop::EmergencyStop;
    use twil_core::drivers::wheel_encoder::WheelEncoder;

    /// The wheels: encoders, motors, the emergency stop and the battery.
    pub struct Body {
        wheel_left: WheelEncoder<crate::board::WheelCounter<stm32f4xx_hal::pac::TIM3>>,
        wheel_right: WheelEncoder<crate::board::WheelCounter<stm32f4xx_hal::pac::TIM4>>,
        motor_left: MotorLeft,
        motor_right: MotorRight,
        estop: EmergencyStop<stm32f4xx_hal::gpio::PC11<stm32f4xx_hal::gpio::Input>>,
        battery: crate::board::BatteryMonitor,
    }

    /// The sonar head: the top sonar and the neck stepper.
    pub struct Head {
        /// The top sonar.
        pub sonar: SonarTop,
        /// The neck.
        pub neck: Neck,
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
                sonar: board.sonar_top,
                neck: board.neck,
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

        /// Apply the voltages until the next period, at the measured battery voltage; any
        /// error stops both motors.
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

    impl Head {
        /// Turn the neck to `neck_angle_rad` and take one reading (blocking: the neck's steps and
        /// the echo window); `None` for no echo or a driver fault.
        pub fn read(&mut self, neck_angle_rad: f32) -> Option<f32> {
            self.neck.move_to_angle(neck_angle_rad.to_degrees()).ok()?;
            self.sonar.read().ok().and_then(|r| r.range_m)
        }
    }
}
