//! The virtual board: the board's body of `twil_core::drivers::body` (what the firmware's board
//! build runs) on the pins of a scripted world (`virtual_board/world.rs`), from power-up
//! through the start of a mission run by the real `RobotDevice`, mission and pilot.
//!
//! The rig schedules two tasks on the world's clock as the firmware does: the control task
//! every 50 ms (encoders → pilot → motors, the e-stop first) and the sonar task, which steps
//! the neck and fires the sonar with the non-blocking pieces an async task uses
//! (`begin_move_to_angle` / `step`, `fire` / decoder / `finish`, `judge`); plans run at once.
//! Each test runs in well under a second (a few simulated seconds of events).

mod selftest;
mod world;

use twil_core::drivers::body::{neck_fault, sonar_fault};
use twil_core::drivers::echo::{cycle_us, MIN_CYCLE_US};
use twil_core::drivers::neck_stepper::DIR_SETUP_NS;
use twil_core::drivers::{
    ActiveLevel, Chassis, EchoDecoder, EmergencyStop, Motor, Mounting, NeckGeometry, NeckProgress,
    NeckStepper, SonarHead, SonarRanger, SonarWindow, WheelEncoder,
};
use twil_core::failsafe::{Sensor, StopCause};
use twil_core::geom::PointM;
use twil_core::grid::words_for_cells;
use twil_core::link::frame::{encode, FrameDecoder, MAX_FRAME_BYTES};
use twil_core::link::{
    Build, DeviceFrame, DeviceInfo, MapParams, MissionSetup, Reply, Request, RequestFrame,
    RobotDevice, RunState, WorldUpload,
};
use twil_core::mission::{
    Mission300, MissionMode, MissionPhase, MissionPlanner300, MissionStatus, Pilot,
};
use twil_core::robot::RobotConfig;
use world::{Battery, Counter, Delay, Echo, Pin, PinKind, Pwm, World};

type Device = RobotDevice<{ words_for_cells(300 * 300) }>;
type TestChassis = Chassis<Pwm, Pin, Pwm, Pin, Counter, Counter, Pin, Battery>;
type TestHead = SonarHead<Pin, Echo, Delay, Pin, Pin, Pin, Delay>;

const PERIOD_NS: u64 = 50_000_000;
const MS: u64 = 1_000_000;

fn chassis(w: &World) -> TestChassis {
    let max_v = RobotConfig::DEFAULT.max_voltage_v;
    Chassis::new(
        Motor::new(Pwm(w.clone(), 0), w.pin(PinKind::MotorDir(0)), max_v, true),
        Motor::new(Pwm(w.clone(), 1), w.pin(PinKind::MotorDir(1)), max_v, false),
        WheelEncoder::new(Counter(w.clone(), 0), Mounting::Normal, 224),
        WheelEncoder::new(Counter(w.clone(), 1), Mounting::Mirrored, 224),
        EmergencyStop::new(w.pin(PinKind::Estop), ActiveLevel::High),
        Battery(w.clone()),
    )
}

fn head(w: &World) -> TestHead {
    let config = RobotConfig::DEFAULT;
    SonarHead::new(
        SonarRanger::new(
            w.pin(PinKind::Trigger),
            Echo::new(w.clone()),
            Delay(w.clone()),
            SonarWindow::from_config(&config),
        ),
        NeckStepper::new(
            w.pin(PinKind::Step),
            w.pin(PinKind::Dir),
            w.pin(PinKind::Home),
            Delay(w.clone()),
            NeckGeometry::from_config(&config),
        ),
    )
}

/// The sonar task's state: what it waits for, and until when.
enum SonarTask {
    Idle,
    /// A mission started: homing, then the chassis is armed.
    Homing {
        config: RobotConfig,
        wake_ns: u64,
    },
    Moving {
        angle_rad: f32,
        wake_ns: u64,
    },
    Listening {
        angle_rad: f32,
        decoder: EchoDecoder,
        tick_hz: u32,
        armed_ns: u64,
    },
    Settling {
        wake_ns: u64,
    },
}

/// The board, the device and the host's side of the link.
struct Rig {
    world: World,
    chassis: TestChassis,
    head: TestHead,
    device: Box<Device>,
    mission: Box<Mission300>,
    planner: Box<MissionPlanner300>,
    upload: Box<WorldUpload>,
    pilot: Option<Pilot>,
    sonar: SonarTask,
    next_tick_ns: u64,
    seq: u16,
    /// Readings handed to the mission: (neck angle, range).
    readings: Vec<(f32, Option<f32>)>,
    /// Causes the body reported.
    faults: Vec<(u64, StopCause)>,
}

impl Rig {
    fn new(world: World) -> Self {
        Self {
            chassis: chassis(&world),
            head: head(&world),
            world,
            device: Box::new(Device::new(DeviceInfo::for_build(Build::Host))),
            mission: Box::new(Mission300::IDLE),
            planner: Box::new(MissionPlanner300::new()),
            upload: Box::new(WorldUpload::new()),
            pilot: None,
            sonar: SonarTask::Idle,
            next_tick_ns: PERIOD_NS,
            seq: 0,
            readings: Vec::new(),
            faults: Vec::new(),
        }
    }

    /// One request through the wire format; its reply.
    fn call(&mut self, request: Request) -> Reply {
        self.seq += 1;
        let mut wire = [0u8; MAX_FRAME_BYTES];
        let frame = RequestFrame {
            seq: self.seq,
            request,
        };
        let bytes = encode(&frame, &mut wire).unwrap().to_vec();
        let mut out = Vec::new();
        self.device.link(&mut self.mission).receive(
            &bytes,
            &mut *self.planner,
            &mut || 0,
            &mut *self.upload,
            &mut |b: &[u8]| out.extend_from_slice(b),
        );
        let mut decoder = FrameDecoder::new();
        let mut rest = &out[..];
        let mut reply = None;
        while !rest.is_empty() {
            let (got, r) = decoder.feed::<DeviceFrame>(rest);
            rest = r;
            if let Some(Ok(DeviceFrame::Reply { reply: got, .. })) = got {
                reply = Some(got);
            }
        }
        self.serve();
        reply.expect("one reply")
    }

    /// Set up and start the mission across a 1 m wall straight ahead.
    fn start_mission(&mut self) -> Reply {
        let map = MapParams {
            robot_radius_m: 0.35,
            ..MapParams::default()
        };
        assert_eq!(self.call(Request::SetParams(map)), Reply::Ack);
        let params = twil_core::world::Params {
            robot_radius_m: 0.35,
            speed_m_s: 0.3,
            initial_heading_deg: 90.0,
            start: PointM::new(3.0, 1.5),
            goal: PointM::new(3.0, 5.0),
        };
        let setup = MissionSetup {
            initial_heading_rad: std::f32::consts::FRAC_PI_2,
            time_limit_s: 300.0,
            link_loss: twil_core::failsafe::LinkLossPolicy::default(),
            ..MissionSetup::from_params(&params, MissionMode::Stop)
        };
        assert_eq!(self.call(Request::SetMission(setup)), Reply::Ack);
        self.call(Request::StartMission)
    }

    fn fail(&mut self, cause: StopCause) {
        self.faults.push((self.world.now_ns(), cause));
        self.device.link(&mut self.mission).fail(cause);
    }

    /// The mission task's round: a mission that starts (the body takes its config and homes),
    /// the pilot's commands, plans, the next sonar request.
    fn serve(&mut self) {
        if let Some(config) = self.device.link(&mut self.mission).take_started() {
            self.pilot = Some(Pilot::new(&config));
            // The body takes the mission's config; the sonar task homes the neck without
            // blocking, then arms the chassis.
            self.chassis.stop();
            match self.head.begin_restart(&config.robot) {
                Ok(()) => {
                    self.sonar = SonarTask::Homing {
                        config: config.robot,
                        wake_ns: self.world.now_ns(),
                    }
                }
                Err(cause) => self.fail(cause),
            }
        }
        loop {
            if let Some(command) = self.device.take_pilot_command() {
                if let Some(pilot) = &mut self.pilot {
                    let _ = pilot.command(command, self.mission.prefix());
                }
            }
            if self.device.plan_pending() {
                self.device
                    .link(&mut self.mission)
                    .run_planner(&mut *self.planner, &mut || 0);
                continue;
            }
            break;
        }
        if self.device.state() != RunState::Running {
            self.chassis.stop();
        }
        if matches!(self.sonar, SonarTask::Idle) {
            if let Some(request) = self.device.take_sonar_request() {
                let angle_rad = request.neck_angle_rad;
                match self
                    .head
                    .neck_mut()
                    .begin_move_to_angle(angle_rad.to_degrees())
                {
                    Ok(()) => {
                        self.sonar = SonarTask::Moving {
                            angle_rad,
                            wake_ns: self.world.now_ns(),
                        }
                    }
                    Err(e) => self.fail(neck_fault(e)),
                }
            }
        }
    }

    /// When the sonar task wakes next.
    fn sonar_wake_ns(&self) -> u64 {
        match &self.sonar {
            SonarTask::Idle => u64::MAX,
            SonarTask::Moving { wake_ns, .. }
            | SonarTask::Settling { wake_ns }
            | SonarTask::Homing { wake_ns, .. } => *wake_ns,
            SonarTask::Listening {
                decoder, armed_ns, ..
            } => {
                let deadline = armed_ns + u64::from(decoder.deadline_ticks()) * 1_000;
                let edge = self.world.next_echo_edge_ns(*armed_ns).unwrap_or(u64::MAX);
                deadline.min(edge)
            }
        }
    }

    /// One wake of the sonar task.
    fn sonar_step(&mut self) {
        let now = self.world.now_ns();
        match std::mem::replace(&mut self.sonar, SonarTask::Idle) {
            SonarTask::Idle => {}
            SonarTask::Settling { .. } => {}
            SonarTask::Homing { config, .. } => match self.head.neck_mut().step() {
                Ok(NeckProgress::Wait { ns }) => {
                    self.sonar = SonarTask::Homing {
                        config,
                        // The wait counts from the end of the step (after its pulse).
                        wake_ns: self.world.now_ns() + u64::from(ns),
                    }
                }
                Ok(NeckProgress::Done { .. }) => {
                    if let Err(cause) = self.chassis.restart(&config) {
                        self.fail(cause);
                    }
                }
                Err(e) => self.fail(neck_fault(e)),
            },
            SonarTask::Moving { angle_rad, .. } => match self.head.neck_mut().step() {
                Ok(NeckProgress::Wait { ns }) => {
                    self.sonar = SonarTask::Moving {
                        angle_rad,
                        // The wait counts from the end of the step (after its pulse).
                        wake_ns: self.world.now_ns() + u64::from(ns),
                    }
                }
                Ok(NeckProgress::Done { .. }) => match self.head.sonar_mut().fire() {
                    Ok((decoder, tick_hz)) => {
                        self.sonar = SonarTask::Listening {
                            angle_rad,
                            decoder,
                            tick_hz,
                            armed_ns: now,
                        }
                    }
                    Err(e) => self.fail(sonar_fault(e)),
                },
                Err(e) => self.fail(neck_fault(e)),
            },
            SonarTask::Listening {
                angle_rad,
                mut decoder,
                tick_hz,
                armed_ns,
            } => {
                use twil_core::drivers::EchoCapture;
                let echo = self.head.sonar_mut().echo_mut();
                let outcome = match echo.next_edge(decoder.deadline_ticks()) {
                    Some(edge) => decoder.feed(edge),
                    None => Some(decoder.expire()),
                };
                let Some(outcome) = outcome else {
                    self.sonar = SonarTask::Listening {
                        angle_rad,
                        decoder,
                        tick_hz,
                        armed_ns,
                    };
                    return;
                };
                let reading = self.head.sonar_mut().finish(outcome, tick_hz);
                match self.head.judge(Ok(reading)) {
                    Ok(range_m) => {
                        self.readings.push((angle_rad, range_m));
                        self.device
                            .link(&mut self.mission)
                            .reading(angle_rad, range_m);
                    }
                    Err(cause) => self.fail(cause),
                }
                let window = self.head.sonar().window();
                self.sonar = SonarTask::Settling {
                    wake_ns: armed_ns + u64::from(cycle_us(&window)) * 1_000,
                };
            }
        }
    }

    /// One control period.
    fn control_tick(&mut self) {
        let (left, right) = self.chassis.read_counts();
        let mut volts = (0.0, 0.0);
        if self.device.state() == RunState::Running {
            if let Some(pilot) = &mut self.pilot {
                let report = pilot.tick(
                    left.trusted().unwrap_or(0),
                    right.trusted().unwrap_or(0),
                    PERIOD_NS as f32 * 1e-9,
                );
                volts = (report.left_voltage_v, report.right_voltage_v);
                self.device.link(&mut self.mission).tick(&report);
            }
        }
        let drive = self.chassis.drive(volts.0, volts.1);
        if let Some(cause) = drive.stop {
            self.fail(cause);
        }
    }

    /// Run the two tasks until `until_ns`, or until `stop` says so after an event.
    fn run_until(&mut self, until_ns: u64, mut stop: impl FnMut(&mut Rig) -> bool) -> bool {
        loop {
            let tick = self.next_tick_ns;
            let sonar = self.sonar_wake_ns();
            let next = tick.min(sonar);
            if next > until_ns {
                self.world.advance_to(until_ns);
                return false;
            }
            self.world.advance_to(next);
            if tick <= sonar {
                self.next_tick_ns += PERIOD_NS;
                self.control_tick();
            } else {
                self.sonar_step();
            }
            self.serve();
            if stop(self) {
                return true;
            }
        }
    }

    fn duty(&self) -> [u16; 2] {
        let s = self.world.0.borrow();
        [s.duty[0].0, s.duty[1].0]
    }

    fn report(&mut self) -> twil_core::link::MissionReport {
        match self.call(Request::MissionStatus) {
            Reply::Mission(r) => r,
            other => panic!("{other:?}"),
        }
    }
}

/// A wall 1 m ahead across ±20°, nothing elsewhere.
fn wall_ahead(angle_deg: f32) -> Option<f32> {
    (angle_deg.abs() <= 20.0).then_some(1.0)
}

#[test]
fn power_up_homing_sweep_duty_after_the_e_stop_then_a_trip_stops_within_a_period() {
    let world = World::new();
    {
        let mut s = world.0.borrow_mut();
        s.range_at_deg = Box::new(wall_ahead);
        // The button is held at power-up and released at 200 ms.
        s.estop_pressed_at_ns.push((0, 200 * MS));
    }
    let mut rig = Rig::new(world.clone());
    // Power-up: half a second of control periods with no mission: never any duty.
    rig.run_until(500 * MS, |_| false);
    assert!(rig.chassis.estop().is_latched(), "latched from power-up");
    assert!(world.0.borrow().duty_log.iter().all(|&(_, _, d)| d == 0));

    // The mission starts: the neck homes (from 30 steps to the switch at −102, at the start
    // rate), then the chassis is armed.
    assert_eq!(rig.start_mission(), Reply::Ack);
    assert!(!rig.chassis.is_armed(), "not before the neck is homed");
    assert!(rig.run_until(2_000 * MS, |r| r.chassis.is_armed()));
    let start_ns = world.now_ns();
    {
        let s = world.0.borrow();
        assert_eq!(s.neck_steps, -102);
        assert_eq!(s.step_times_ns.len(), 132);
        assert!(s.step_times_ns.windows(2).all(|w| w[1] - w[0] >= 5 * MS));
        // 132 steps of 5 ms, the direction set-up of homing and of the first sweep move.
        assert_eq!(
            start_ns - 500 * MS,
            132 * 5 * MS + 2 * u64::from(DIR_SETUP_NS)
        );
        assert!(s.pings.is_empty(), "no ping before homing");
    }
    assert!(rig.faults.is_empty(), "{:?}", rig.faults);

    // Until the motors get duty: the sweep, a plan, the first follow.
    let moved = rig.run_until(start_ns + 30_000 * MS, |r| r.duty() != [0, 0]);
    assert!(moved, "the motors never got duty");
    let first_duty_ns = world.now_ns();
    assert!(rig.faults.is_empty(), "{:?}", rig.faults);
    assert_eq!(rig.mission.phase(), MissionPhase::Follow);
    {
        let s = world.0.borrow();
        // Every ping the world answered at the angle the mission asked for, and every
        // reading is the scripted range.
        assert!(rig.readings.len() >= 100, "{} readings", rig.readings.len());
        assert_eq!(s.pings.len(), rig.readings.len());
        for ((angle_rad, range_m), &(_, world_deg, world_range)) in
            rig.readings.iter().zip(&s.pings)
        {
            let asked_deg = angle_rad.to_degrees();
            assert!(
                (asked_deg - world_deg).abs() <= 0.9,
                "{asked_deg} vs {world_deg}"
            );
            match (range_m, world_range) {
                (Some(r), Some(w)) => assert!((r - w).abs() < 0.002, "{r} vs {w}"),
                (None, None) => {}
                other => panic!("at {world_deg}°: {other:?}"),
            }
        }
        assert!(rig.readings.iter().any(|r| r.1.is_some()));
        assert!(rig.readings.iter().any(|r| r.1.is_none()));
        // The HC-SR04's cycle, and the drivers' timing.
        let triggers: Vec<u64> = s.pings.iter().map(|p| p.0).collect();
        assert!(triggers
            .windows(2)
            .all(|w| w[1] - w[0] >= u64::from(MIN_CYCLE_US) * 1_000));
        assert_eq!(s.ignored_triggers, 0);
        assert_eq!(s.setup_violations, 0);
        assert_eq!(s.short_step_pulses, 0);
    }

    // The button is pressed 17 ms into a period: the next period's drive puts both motors at
    // 0 and reports it; the mission ends with that cause.
    rig.run_until(first_duty_ns + 100 * MS, |_| false);
    assert_ne!(rig.duty(), [0, 0]);
    let press_ns = world.now_ns() + 17 * MS;
    world
        .0
        .borrow_mut()
        .estop_pressed_at_ns
        .push((press_ns, u64::MAX));
    let stopped = rig.run_until(press_ns + 200 * MS, |r| r.duty() == [0, 0]);
    assert!(stopped);
    let stopped_after_ns = world.now_ns() - press_ns;
    assert!(stopped_after_ns <= PERIOD_NS, "{stopped_after_ns} ns");
    println!(
        "virtual board: homed and armed in {} ms, {} readings in {} ms to the first duty, motors off {} ms after the press",
        (start_ns - 500 * MS) / MS,
        rig.readings.len(),
        (first_duty_ns - start_ns) / MS,
        stopped_after_ns / MS
    );
    assert_eq!(
        rig.faults.last().map(|f| f.1),
        Some(StopCause::EmergencyStop)
    );
    let report = rig.report();
    assert_eq!(report.status, MissionStatus::Aborted);
    assert_eq!(report.stop_cause, StopCause::EmergencyStop);
    assert!(report.emergency_stop);
    // Nothing drives again.
    let log_len = world.0.borrow().duty_log.len();
    rig.run_until(world.now_ns() + 300 * MS, |_| false);
    assert!(world.0.borrow().duty_log[log_len..]
        .iter()
        .all(|&(_, _, d)| d == 0));
}

#[test]
fn a_button_held_at_the_start_ends_the_mission_as_an_emergency_stop() {
    let world = World::new();
    world.0.borrow_mut().range_at_deg = Box::new(wall_ahead);
    world
        .0
        .borrow_mut()
        .estop_pressed_at_ns
        .push((0, 2_000 * MS));
    let mut rig = Rig::new(world.clone());
    assert_eq!(rig.start_mission(), Reply::Ack);
    assert!(rig.run_until(2_000 * MS, |r| !r.faults.is_empty()));
    // After homing (660 ms), the chassis refuses to arm.
    assert_eq!(
        rig.faults,
        vec![(660 * MS + 1_000, StopCause::EmergencyStop)]
    );
    assert!(!rig.chassis.is_armed());
    let report = rig.report();
    assert_eq!(report.stop_cause, StopCause::EmergencyStop);
    assert!(report.emergency_stop);
    // Released: the host clears the stop and starts again.
    rig.run_until(2_200 * MS, |_| false);
    assert!(matches!(rig.call(Request::StartMission), Reply::Error(_)));
    assert_eq!(rig.call(Request::ClearEmergencyStop), Reply::Ack);
    assert_eq!(rig.call(Request::StartMission), Reply::Ack);
    // Homed already: the switch is closed at once.
    assert!(rig.run_until(2_300 * MS, |r| r.chassis.is_armed()));
    assert!(rig.chassis.estop().motors_allowed());
}

#[test]
fn duty_waits_for_three_released_polls() {
    let world = World::new();
    let mut c = chassis(&world);
    // Started at once after power-up: armed, but the button has not been read released yet.
    c.restart(&RobotConfig::DEFAULT).unwrap();
    assert!(c.is_armed());
    for period in 1..=2 {
        world.advance_to(period * PERIOD_NS);
        assert_eq!(c.drive(3.0, 3.0).left_v, 0.0, "poll {period}");
    }
    world.advance_to(3 * PERIOD_NS);
    assert_eq!(c.drive(3.0, 3.0).left_v, 3.0);
    assert_ne!(world.0.borrow().duty[0].0, 0);
}

#[test]
fn a_neck_whose_home_switch_never_closes_ends_the_mission_with_a_sensor_fault() {
    let world = World::new();
    world.0.borrow_mut().home_switch_works = false;
    let mut rig = Rig::new(world.clone());
    rig.run_until(200 * MS, |_| false);
    assert_eq!(rig.start_mission(), Reply::Ack);
    assert!(rig.run_until(3_000 * MS, |r| !r.faults.is_empty()));
    assert_eq!(world.now_ns(), 200 * MS + 1_000 + 214 * 5 * MS);
    // Exactly the bounded travel, then the fault: never an endless turn, never silence.
    let geometry = NeckGeometry::from_config(&RobotConfig::DEFAULT);
    assert_eq!(
        world.0.borrow().step_times_ns.len(),
        geometry.max_homing_steps as usize
    );
    assert_eq!(
        rig.faults.last().map(|f| f.1),
        Some(StopCause::SensorFault(Sensor::NeckHome))
    );
    let report = rig.report();
    assert_eq!(report.state, RunState::Ended);
    assert_eq!(report.status, MissionStatus::Aborted);
    assert_eq!(report.stop_cause, StopCause::SensorFault(Sensor::NeckHome));
    // No sonar request is served and the wheels never move.
    rig.run_until(world.now_ns() + 1_000 * MS, |_| false);
    assert!(world.0.borrow().pings.is_empty());
    assert!(world.0.borrow().duty_log.iter().all(|&(_, _, d)| d == 0));
}

#[test]
fn a_sagging_battery_stops_the_motors_and_is_reported() {
    let world = World::new();
    world.0.borrow_mut().range_at_deg = Box::new(wall_ahead);
    let mut rig = Rig::new(world.clone());
    assert_eq!(rig.start_mission(), Reply::Ack);
    let moved = rig.run_until(30_000 * MS, |r| r.duty() != [0, 0]);
    assert!(moved);
    // 12.6 V sagging at 10 V/s from now: below 10.5 V after 210 ms.
    let sag_ns = world.now_ns();
    {
        let mut s = world.0.borrow_mut();
        s.sag_from_ns = Some(sag_ns);
        s.sag_v_per_s = 10.0;
    }
    let stopped = rig.run_until(sag_ns + 1_000 * MS, |r| !r.faults.is_empty());
    assert!(stopped);
    let after_ns = world.now_ns() - sag_ns;
    assert!(
        (210 * MS..210 * MS + PERIOD_NS).contains(&after_ns),
        "{after_ns}"
    );
    assert_eq!(rig.duty(), [0, 0]);
    assert!(rig.chassis.battery_v() < 10.5);
    assert_eq!(
        rig.report().stop_cause,
        StopCause::SensorFault(Sensor::Battery)
    );
}

#[test]
fn a_battery_that_cannot_be_read_is_a_fault_not_silence() {
    let world = World::new();
    let mut c = chassis(&world);
    for _ in 0..3 {
        c.drive(0.0, 0.0);
    }
    c.restart(&RobotConfig::DEFAULT).unwrap();
    let d = c.drive(3.0, 3.0);
    assert!(d.stop.is_none() && d.left_v == 3.0, "{d:?}");
    world.0.borrow_mut().battery_fails = true;
    let d = c.drive(3.0, 3.0);
    assert_eq!(d.stop, Some(StopCause::SensorFault(Sensor::Battery)));
    assert_eq!((d.left_v, d.right_v), (0.0, 0.0));
    assert_eq!(world.0.borrow().duty, [(0, true), (0, false)]);
    // Reported once; the chassis stays off.
    assert_eq!(c.drive(3.0, 3.0).stop, None);
    assert!(!c.is_armed());
}

#[test]
fn encoders_counting_backwards_across_zero() {
    let world = World::new();
    {
        let mut s = world.0.borrow_mut();
        // The left counter counts down through 0; the right (mirrored) counts up: both
        // wheels turn backwards at 800 counts/s, 40 counts per period.
        s.counts_per_s = (-800.0, 800.0);
        s.counter_start = (100, 65_500);
    }
    let mut c = chassis(&world);
    for period in 1..=6 {
        world.advance_to(period * PERIOD_NS);
        let (l, r) = c.read_counts();
        assert_eq!(
            (l.trusted(), r.trusted()),
            (Some(-40), Some(-40)),
            "{period}"
        );
    }
    // A mission's restart takes the config's limit (a slow motor: 14 counts per period) and
    // the counters' reference (what the wheels did before is not this mission's motion).
    let slow = RobotConfig {
        motor_gain_rad_s_per_v: 0.05,
        ..RobotConfig::DEFAULT
    };
    world.advance_to(60 * PERIOD_NS);
    c.restart(&slow).unwrap();
    world.advance_to(61 * PERIOD_NS);
    let (l, r) = c.read_counts();
    assert_eq!((l.counts, r.counts), (-40, -40));
    assert!(
        !l.plausible && !r.plausible,
        "40 counts exceed the slow motor's 14"
    );
}

#[test]
fn the_sonar_reads_through_pwm_noise_and_the_no_target_pulse_reads_no_echo() {
    let world = World::new();
    {
        let mut s = world.0.borrow_mut();
        s.range_at_deg = Box::new(|deg| (deg > 0.0).then_some(0.8));
        s.pwm_noise = true;
    }
    let mut h = head(&world);
    h.restart(&RobotConfig::DEFAULT).unwrap();
    let t0 = world.now_ns();
    let mut ranges = Vec::new();
    for deg in [-10.0f32, 10.0, -10.0, 10.0] {
        ranges.push(h.read(deg.to_radians()).unwrap());
    }
    assert_eq!(ranges[0], None);
    assert_eq!(ranges[2], None);
    for r in [ranges[1], ranges[3]] {
        assert!((r.unwrap() - 0.8).abs() < 0.002, "{r:?}");
    }
    let s = world.0.borrow();
    // Every trigger answered (none while the 38 ms pulse was high), a cycle apart.
    assert_eq!(s.pings.len(), 4);
    assert_eq!(s.ignored_triggers, 0);
    assert!(s
        .pings
        .windows(2)
        .all(|w| w[1].0 - w[0].0 >= u64::from(MIN_CYCLE_US) * 1_000));
    // Four cycles of at least 60 ms, and the neck's ramped moves.
    assert!((240 * MS..1_000 * MS).contains(&(world.now_ns() - t0)));
}

#[test]
fn a_silent_sonar_is_a_fault_on_the_third_ping() {
    let world = World::new();
    world.0.borrow_mut().sonar_answers = false;
    let mut h = head(&world);
    h.restart(&RobotConfig::DEFAULT).unwrap();
    assert_eq!(h.read(0.0), Ok(None));
    assert_eq!(h.read(0.0), Ok(None));
    assert_eq!(
        h.read(0.0),
        Err(StopCause::SensorFault(Sensor::SonarSilent))
    );
    // A mission's restart forgets the count.
    h.restart(&RobotConfig::DEFAULT).unwrap();
    assert_eq!(h.read(0.0), Ok(None));
}

#[test]
fn the_body_takes_the_missions_config() {
    let world = World::new();
    world.0.borrow_mut().range_at_deg = Box::new(|_| Some(2.5));
    let mut h = head(&world);
    h.restart(&RobotConfig::DEFAULT).unwrap();
    // 2.5 m is beyond the default 1.5 m window: no echo.
    assert_eq!(h.read(0.0), Ok(None));
    // A mission with a 3 m sonar and 0.9° neck steps: the window and the geometry follow.
    let config = RobotConfig {
        sonar_range_m: 3.0,
        neck_step_deg: 0.9,
        ..RobotConfig::DEFAULT
    };
    h.restart(&config).unwrap();
    assert_eq!(h.neck().geometry().step_deg, 0.9);
    assert_eq!(h.sonar().window().max_range_m, 3.0);
    let r = h.read(0.0).unwrap().unwrap();
    assert!((r - 2.5).abs() < 0.002, "{r}");
}
