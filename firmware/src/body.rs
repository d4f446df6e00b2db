//! The robot's body behind one interface for both builds: the wheels (encoders in, motor
//! voltages out, the emergency-stop input) and the sonar head.
//!
//! - QEMU build: the core's simulated body (`twil_core::mission::SimBody`, the plant of
//!   `twil_core::plant` with its encoder deltas) stands in for the drivers. The control task
//!   reads its encoder counts and steps it with the voltages for one period (that cost is
//!   measured apart from the control step's); the sonar task casts the sonar's ray on the real
//!   world the host uploaded (`WorldChunk`), from the plant's true pose.
//!
//!   Only the body, not the core's whole `DeviceShell` (which the in-process device and the
//!   link tests run): that shell runs a period in one thread of control, the pilot, the
//!   mission, every plan and every reading in a row, while the firmware spreads them over its
//!   tasks by priority (the pilot in the control task, readings in the sonar task, the mission
//!   and its plans in the lowest-priority task, each plan deferred while the control task goes
//!   on). That order, and its timing, are the firmware's to keep, so it wires the device itself
//!   (`mission_task.rs`) and shares the simulated robot only.
//! - Board build: `twil_core::drivers::body`'s `Chassis` (control task) and `SonarHead`
//!   (sonar task) on the pins of [`crate::board`]. The head is driven stepwise, every wait a
//!   `Mono` delay, so the sonar task never holds the core for more than a pulse.
//!
//! Both report why they stopped the motors (an e-stop press, a sensor fault) as a
//! `StopCause`, which the mission task hands to the device. Wiring only: the rules live in
//! `twil-core`.

use twil_core::mission::MissionConfig;

#[cfg(feature = "qemu")]
pub use sim::*;

#[cfg(feature = "hardware")]
pub use board_body::*;

#[cfg(feature = "qemu")]
mod sim {
    use super::MissionConfig;
    use twil_core::control::Pose;
    use twil_core::failsafe::StopCause;
    use twil_core::link::WorldUpload;
    use twil_core::mission::SimBody;
    use twil_core::plant::Plant;
    use twil_core::robot::RobotConfig;

    /// The simulated robot: the core's [`SimBody`] (its true pose, wheels and encoders).
    pub struct Body {
        body: SimBody,
    }

    impl Body {
        /// A robot at the origin (until a mission puts it at its start).
        pub fn new() -> Self {
            Self {
                body: SimBody::new(&RobotConfig::DEFAULT, Pose::default()),
            }
        }

        /// Put the robot at the start of `config`'s mission, standing.
        pub fn restart(&mut self, config: &MissionConfig) -> Result<(), StopCause> {
            self.body = SimBody::at_start(config);
            Ok(())
        }

        /// The mission is over (the simulated robot just stands).
        pub fn stop(&mut self) {}

        /// Encoder counts since the previous call (left, right).
        pub fn encoder_deltas(&mut self) -> (i32, i32) {
            self.body.encoder_deltas()
        }

        /// Apply the voltages for one period (the simulated robot moves). No e-stop input and
        /// no sensor to fail in the simulation: never a stop cause.
        pub fn drive(
            &mut self,
            left_voltage_v: f32,
            right_voltage_v: f32,
            period_s: f32,
        ) -> Option<StopCause> {
            self.body.step(period_s, left_voltage_v, right_voltage_v);
            None
        }

        /// A copy of the simulated robot, for the sonar's ray cast (the plant is small; the
        /// cast then runs without holding the control task's resource).
        pub fn snapshot(&self) -> Plant {
            self.body.plant().clone()
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
    use crate::board::{Board, BoardChassis, BoardHead};
    use crate::{instructions, note_worst, Mono};
    use core::sync::atomic::AtomicU32;
    use rtic_monotonics::systick::prelude::*;
    use rtic_monotonics::Timebase;
    use rtic_sync::channel::Sender;
    use twil_core::drivers::body::{neck_fault, sonar_fault};
    use twil_core::drivers::echo::{cycle_us, listen_us};
    use twil_core::drivers::{EchoCapture, NeckProgress, SonarReading, WheelPulse};
    use twil_core::failsafe::StopCause;
    use twil_core::robot::RobotConfig;
    use twil_core::selftest::SelfTestReport;

    /// The wheels, the e-stop and the battery, for the control task; between missions, the
    /// self-test's wheel pulse, which the control task runs in its own periods.
    pub struct Body {
        chassis: BoardChassis,
        pulse: Option<WheelPulse>,
        pulse_result: Option<Result<(i32, i32), StopCause>>,
    }

    /// Split the board into the wheels and the sonar head.
    pub fn split(board: Board) -> (Body, Head) {
        (
            Body {
                chassis: board.chassis,
                pulse: None,
                pulse_result: None,
            },
            Head {
                head: board.head,
                last_fire: None,
            },
        )
    }

    impl Body {
        /// A mission starts: its encoder and voltage limits, the encoders' reference, the
        /// e-stop cleared (refused while pressed: the mission then ends with that cause).
        pub fn restart(&mut self, config: &MissionConfig) -> Result<(), StopCause> {
            self.pulse = None;
            self.chassis.restart(&config.robot)
        }

        /// The mission is over: motors at 0, disarmed until the next start.
        pub fn stop(&mut self) {
            self.pulse = None;
            self.chassis.stop();
        }

        /// The self-test: read the e-stop input now.
        pub fn read_estop(&mut self) -> Result<bool, StopCause> {
            self.chassis.read_estop()
        }

        /// The self-test: read the battery now, volts.
        pub fn read_battery_v(&mut self) -> Result<f32, StopCause> {
            self.chassis.read_battery_v()
        }

        /// The self-test: start a wheel pulse (`volts` for `on_periods` control periods with
        /// duty, then `coast_periods` at 0 V), which [`idle_period`](Self::idle_period) runs;
        /// its end comes from [`take_pulse_result`](Self::take_pulse_result). Returns the most
        /// control periods it takes.
        pub fn begin_pulse(
            &mut self,
            robot: &RobotConfig,
            volts: (f32, f32),
            on_periods: u32,
            coast_periods: u32,
        ) -> u32 {
            self.pulse_result = None;
            match self
                .chassis
                .begin_pulse(robot, volts, on_periods, coast_periods)
            {
                Ok(pulse) => {
                    let periods = pulse.periods_max();
                    self.pulse = Some(pulse);
                    periods
                }
                Err(cause) => {
                    self.pulse = None;
                    self.pulse_result = Some(Err(cause));
                    0
                }
            }
        }

        /// The end of the pulse: the counts (left, right) over all of it, or what stopped it;
        /// `None` while it runs.
        pub fn take_pulse_result(&mut self) -> Option<Result<(i32, i32), StopCause>> {
            self.pulse_result.take()
        }

        /// A control period with no mission: the self-test's pulse when one runs (its
        /// e-stop, battery and motor faults end the pulse, not a mission: never a stop
        /// cause), else both motors at 0 (the chassis is disarmed).
        pub fn idle_period(&mut self) -> Option<StopCause> {
            match self.pulse.as_mut() {
                Some(pulse) => {
                    if let Some(result) = self.chassis.pulse_period(pulse) {
                        self.pulse = None;
                        self.pulse_result = Some(result);
                    }
                    None
                }
                None => self.chassis.drive(0.0, 0.0).stop,
            }
        }

        /// Encoder counts since the previous call (left, right); implausible jumps count 0.
        pub fn encoder_deltas(&mut self) -> (i32, i32) {
            let (l, r) = self.chassis.read_counts();
            (l.trusted().unwrap_or(0), r.trusted().unwrap_or(0))
        }

        /// One period's output: the e-stop polled first, then the voltages at the battery's
        /// voltage (the conversion started one period ago: no wait). Disarmed (no mission) the
        /// motors stay at 0. A press or a sensor fault during a mission zeroes both motors
        /// and comes back once, as the cause that ends the mission.
        pub fn drive(
            &mut self,
            left_voltage_v: f32,
            right_voltage_v: f32,
            _period_s: f32,
        ) -> Option<StopCause> {
            self.chassis.drive(left_voltage_v, right_voltage_v).stop
        }
    }

    /// A board has no simulated world.
    pub type World = ();

    /// The sonar head (`twil_core::drivers::body::SonarHead`) driven asynchronously: every
    /// wait of a millisecond or more is a `Mono` delay; the only waits in a loop are the
    /// drivers' 1 µs direction set-up, 2 µs step pulse and 10 µs trigger pulse
    /// (`board::SpinDelay`), at the sonar task's priority, below the USART's and `link_rx`'s.
    pub struct Head {
        head: BoardHead,
        /// When the last ping was fired (the HC-SR04 wants 60 ms between pings).
        last_fire: Option<<Mono as Timebase>::Instant>,
    }

    impl Head {
        /// A mission starts: its sonar window and neck geometry, then homing, stepwise.
        /// Returns the homing steps; a switch not found or a pin error is the sensor fault.
        pub async fn restart(
            &mut self,
            config: &RobotConfig,
            worst: &AtomicU32,
        ) -> Result<u32, StopCause> {
            self.head.begin_restart(config)?;
            self.run_neck(worst).await
        }

        /// Turn to `angle_rad`, then ping: `Ok(None)` is no echo (silent pings counted: three
        /// in a row are a fault). The cycles spent in pulses are noted in `worst` (the waits
        /// are not work).
        pub async fn read(
            &mut self,
            angle_rad: f32,
            worst: &AtomicU32,
        ) -> Result<Option<f32>, StopCause> {
            self.turn(angle_rad, worst).await?;
            let reading = self.ping(worst).await?;
            self.head.judge(Ok(reading))
        }

        /// Turn the neck to `angle_rad`: the steps it took.
        pub async fn turn(&mut self, angle_rad: f32, worst: &AtomicU32) -> Result<u32, StopCause> {
            self.head
                .neck_mut()
                .begin_move_to_angle(angle_rad.to_degrees())
                .map_err(neck_fault)?;
            self.run_neck(worst).await
        }

        /// The self-test's ping at `angle_rad`: the neck turned there first when it is homed
        /// (else the ping goes where it points), the reading as it came (no silence counting:
        /// the self-test judges a silent line itself).
        pub async fn check_ping(
            &mut self,
            angle_rad: f32,
            worst: &AtomicU32,
        ) -> Result<SonarReading, StopCause> {
            if self.head.neck().position_steps().is_some() {
                self.turn(angle_rad, worst).await?;
            }
            self.ping(worst).await
        }

        /// One sonar cycle where the neck points: fire (at least the module's cycle after the
        /// last), listen out the window, decode the latched edges.
        async fn ping(&mut self, worst: &AtomicU32) -> Result<SonarReading, StopCause> {
            let window = self.head.sonar().window();
            if let Some(last) = self.last_fire {
                Mono::delay_until(last + cycle_us(&window).div_ceil(1_000).millis()).await;
            }
            let before = instructions();
            let fired = self.head.sonar_mut().fire();
            note_worst(worst, instructions().saturating_sub(before));
            let (mut decoder, tick_hz) = fired.map_err(sonar_fault)?;
            let fired_at = Mono::now();
            self.last_fire = Some(fired_at);
            // The timer latches both edges meanwhile.
            Mono::delay_until(fired_at + listen_us(&window).div_ceil(1_000).millis()).await;
            let echo = self.head.sonar_mut().echo_mut();
            let outcome = loop {
                match echo.next_edge(decoder.deadline_ticks()) {
                    Some(edge) => {
                        if let Some(outcome) = decoder.feed(edge) {
                            break outcome;
                        }
                    }
                    None => break decoder.expire(),
                }
            };
            Ok(self.head.sonar_mut().finish(outcome, tick_hz))
        }

        /// The self-test on the board, probe by probe (`SelfTest::step`): the e-stop and the
        /// battery read from the chassis at once; the neck's homing and moves and the sonar's
        /// pings by the head, every wait a `Mono` delay; each wheel pulse run by the control
        /// task in its own periods ([`Body::idle_period`]) while this task sleeps a period at a
        /// time. Every report with a new row goes to the mission task, the last one `done`.
        pub async fn self_test(
            &mut self,
            body: &mut impl rtic::Mutex<T = Body>,
            robot: &twil_core::robot::RobotConfig,
            clock: twil_core::selftest::ClockFacts,
            checks: &mut Sender<'static, SelfTestReport, { crate::SELF_TEST_REPORTS }>,
            // The mission task's wake signal (`mission_task::Wake`, named here by its
            // `rtic-sync` type: the mission task's module uses this one).
            wake: &mut rtic_sync::signal::SignalWriter<'static, ()>,
        ) {
            use twil_core::failsafe::Sensor;
            use twil_core::selftest::board::echo_of;
            use twil_core::selftest::{Answer, Probe, SelfTest, MAX_PROBES};
            let worst = &crate::WORST_SONAR_INSTRUCTIONS;
            let mut test = SelfTest::new(robot, clock);
            let mut answer = None;
            let mut rows = 0;
            for _ in 0..=MAX_PROBES {
                let Some(probe) = test.step(answer.take()) else {
                    break;
                };
                // The rows so far, when the mission task has taken the last ones (it is woken for
                // each; a report skipped here is in the next one). Not held across a wait: this
                // task's future stays small (static SRAM).
                if test.report().rows.len() != rows
                    && checks.try_send(test.report().clone()).is_ok()
                {
                    rows = test.report().rows.len();
                    wake.write(());
                }
                answer = Some(match probe {
                    Probe::EmergencyStop => Answer::EmergencyStop(body.lock(|b| b.read_estop())),
                    Probe::Battery => Answer::Battery(body.lock(|b| b.read_battery_v())),
                    Probe::NeckHome => Answer::Neck(self.restart(robot, worst).await),
                    Probe::NeckTo(angle_deg) => {
                        Answer::Neck(self.turn(angle_deg.to_radians(), worst).await)
                    }
                    Probe::Sonar(angle_deg) => Answer::Sonar(
                        self.check_ping(angle_deg.to_radians(), worst)
                            .await
                            .map(|reading| echo_of(&reading)),
                    ),
                    Probe::Pulse {
                        side,
                        voltage_v,
                        on_ms,
                        coast_ms,
                    } => {
                        let periods = body.lock(|b| {
                            b.begin_pulse(
                                robot,
                                side.volts(voltage_v),
                                on_ms.div_ceil(crate::PERIOD_MS),
                                coast_ms.div_ceil(crate::PERIOD_MS),
                            )
                        });
                        // The control task ends the pulse within `periods` of its periods; one
                        // more is slack. A pulse that does not end (a control task that stopped)
                        // is the motor's fault, and the motors are put at 0.
                        let mut result = body.lock(|b| b.take_pulse_result());
                        for _ in 0..=periods {
                            if result.is_some() {
                                break;
                            }
                            Mono::delay(crate::PERIOD_MS.millis()).await;
                            result = body.lock(|b| b.take_pulse_result());
                        }
                        let result = result.unwrap_or_else(|| {
                            body.lock(|b| b.stop());
                            Err(StopCause::SensorFault(Sensor::Motor))
                        });
                        Answer::Pulse(result.map(|counts| side.of(counts)))
                    }
                });
            }
            // The last report, `done`: waits for room (the mission task, woken for the report
            // before, takes it within a turn).
            for _ in 0..1_000 {
                if checks.try_send(test.report().clone()).is_ok() {
                    wake.write(());
                    return;
                }
                Mono::delay(1.millis()).await;
            }
        }

        /// Step the move (or homing) under way to its end, each wait a `Mono` delay (whole
        /// milliseconds: the monotonic's tick).
        async fn run_neck(&mut self, worst: &AtomicU32) -> Result<u32, StopCause> {
            let mut next = Mono::now();
            loop {
                let before = instructions();
                let progress = self.head.neck_mut().step();
                note_worst(worst, instructions().saturating_sub(before));
                match progress.map_err(neck_fault)? {
                    NeckProgress::Wait { ns } => {
                        next += ns.div_ceil(1_000_000).max(1).millis();
                        Mono::delay_until(next).await;
                    }
                    NeckProgress::Done { steps } => return Ok(steps),
                }
            }
        }
    }
}
