//! The device shell: a [`RobotDevice`] with the simulated robot around it, in one thread of
//! control. What `twil mission --remote sim` runs (`host/src/device_sim.rs`) and what the link
//! tests drive (`link/robot/tests.rs`), beside [`LocalRunner`](super::LocalRunner), which is
//! the same loop without the device (`twil simulate`).
//!
//! ## What it owns, and why here
//!
//! A device without hardware needs the same parts wired the same way wherever it runs: the
//! device and its [`Mission`], the mission planner, the real world the host uploads
//! ([`WorldUpload`]), the [`Pilot`], and a [`SimBody`] for the wheels and the sonar. Written
//! once per shell they had drifted apart in small ways (wrapping or plain encoder deltas, a
//! pilot command taken here and not there), so the wiring lives here once and each shell keeps
//! only what is its own: its clock (simulated milliseconds in the tests, wall time in the
//! in-process device), its parameter store, when it reads the link and when it ticks.
//!
//! [`DeviceShell::tick`] runs one control period in the order of [`LocalRunner`](super::LocalRunner):
//!
//! 1. a mission just started: a new pilot and the body put at the mission's start;
//! 2. the pilot with the body's encoder deltas, then the mission with the pilot's report;
//! 3. [`DeviceShell::serve`]: the pilot's command, every plan at once, every sonar request
//!    answered by the body on the real world (each reading may ask for a plan: back to the
//!    command);
//! 4. the body stepped with the pilot's voltages for the period.
//!
//! The shell owns its parts by value (no allocation in the core): a host boxes the whole
//! shell; its size is the firmware's statics (device, mission, planner) plus the world.
//!
//! The firmware's QEMU build uses [`SimBody`] only: it keeps its own task order (the pilot in
//! the control task, readings in the sonar task, the mission and its plans in the
//! lowest-priority task), which is what a one-thread shell cannot be (see `firmware/src/body.rs`).

use crate::geom::Pose;
use crate::link::params::ParamSave;
use crate::link::{DeviceInfo, RobotDevice, RobotLink, WorldUpload};
use crate::plan::Planner;
use crate::robot::RobotConfig;
use crate::world::PolygonSet;

use super::{Mission, MissionConfig, Pilot};

/// The simulated body of a device without hardware: the [`Plant`](crate::plant::Plant) (the
/// robot's true pose, wheels, encoders and the sonar's ray on the real world) and the
/// encoder counts last read, for the deltas the pilot takes.
#[derive(Clone, Debug)]
pub struct SimBody {
    plant: crate::plant::Plant,
    previous_counts: (i32, i32),
}

impl SimBody {
    /// A robot of `robot` standing at `pose`.
    pub fn new(robot: &RobotConfig, pose: Pose) -> Self {
        let plant = crate::plant::Plant::new(robot, pose);
        let previous_counts = plant.encoder_counts();
        Self {
            plant,
            previous_counts,
        }
    }

    /// The robot of `config` standing at the mission's start, facing its initial heading.
    pub fn at_start(config: &MissionConfig) -> Self {
        Self::new(
            &config.robot,
            Pose::new(
                config.start.x_m,
                config.start.y_m,
                config.initial_heading_rad,
            ),
        )
    }

    /// Encoder counts since the previous call (left, right), wrapping as the counters do.
    pub fn encoder_deltas(&mut self) -> (i32, i32) {
        let counts = self.plant.encoder_counts();
        let deltas = (
            counts.0.wrapping_sub(self.previous_counts.0),
            counts.1.wrapping_sub(self.previous_counts.1),
        );
        self.previous_counts = counts;
        deltas
    }

    /// Apply the motor voltages for `period_s` seconds: the robot moves.
    pub fn step(&mut self, period_s: f32, left_voltage_v: f32, right_voltage_v: f32) {
        self.plant.step(period_s, left_voltage_v, right_voltage_v);
    }

    /// One sonar reading at `neck_angle_rad` (robot frame) on `world`, from the true pose, up
    /// to `max_range_m`; `None` is no echo.
    pub fn sonar_range_m<const V: usize, const P: usize>(
        &mut self,
        world: &PolygonSet<V, P>,
        neck_angle_rad: f32,
        max_range_m: f32,
    ) -> Option<f32> {
        self.plant.sonar_range_m(world, neck_angle_rad, max_range_m)
    }

    /// The simulated robot (its true pose, clearance, a copy for a self-test).
    pub fn plant(&self) -> &crate::plant::Plant {
        &self.plant
    }
}

/// The device and the simulated robot around it: see the module documentation. `W` is the
/// map's words, `E` the evidence map's, `S` and `Q` the planner's scratch words and queue.
pub struct DeviceShell<const W: usize, const E: usize, const S: usize, const Q: usize> {
    /// The mission device (link, planning service, mission requests, telemetry).
    pub device: RobotDevice<W>,
    /// The device's mission.
    pub mission: Mission<W, E>,
    /// The planner of the device's plans and of the planning service.
    pub planner: Planner<S, Q>,
    /// The real world the host uploaded: what the simulated sonar sees.
    pub world: WorldUpload,
    /// The pilot of the mission under way (`None` before the first start).
    pub pilot: Option<Pilot>,
    /// The simulated robot of the mission under way (`None` before the first start).
    pub body: Option<SimBody>,
}

impl<const W: usize, const E: usize, const S: usize, const Q: usize> DeviceShell<W, E, S, Q> {
    /// A device reporting `info`, with no mission, no world and no robot yet (`const`: a host
    /// may build it in place).
    pub const fn new(info: DeviceInfo) -> Self {
        Self {
            device: RobotDevice::new(info),
            mission: Mission::IDLE,
            planner: Planner::new(),
            world: WorldUpload::new(),
            pilot: None,
            body: None,
        }
    }

    /// The device with its mission: every call about the link or the mission.
    pub fn link(&mut self) -> RobotLink<'_, W, E> {
        self.device.link(&mut self.mission)
    }

    /// Feed bytes received from the host; `send` gets the encoded replies. An accepted
    /// `ParamSet` is written to `store` when there is one. Plans of the planning service run
    /// at once, uncounted (the clock reads 0: no instruction counter on a host).
    pub fn receive(
        &mut self,
        bytes: &[u8],
        store: Option<&mut dyn ParamSave>,
        send: &mut impl FnMut(&[u8]),
    ) {
        let mut link = match store {
            Some(store) => self.device.link_with_store(&mut self.mission, store),
            None => self.device.link(&mut self.mission),
        };
        link.receive(bytes, &mut self.planner, &mut || 0, &mut self.world, send);
    }

    /// Hand the device's latest pilot command, if any, to the pilot (with the kept prefix for
    /// `Follow`). The mission checked the prefix before asking; a refusal leaves the pilot
    /// holding, and the mission's own limits end it.
    pub fn command_pilot(&mut self) {
        if let Some(command) = self.device.take_pilot_command() {
            if let Some(pilot) = &mut self.pilot {
                let _ = pilot.command(command, self.mission.prefix());
            }
        }
    }

    /// Carry out what the device asks: the pilot's command, plans (at once), sonar readings
    /// (from the body, on the real world), until it asks for nothing more.
    pub fn serve(&mut self) {
        loop {
            self.command_pilot();
            if self.device.plan_pending() {
                self.device
                    .link(&mut self.mission)
                    .run_planner(&mut self.planner, &mut || 0);
                continue;
            }
            let Some(request) = self.device.take_sonar_request() else {
                return;
            };
            let Some(body) = &mut self.body else {
                return;
            };
            let range = self.mission.config().robot.sonar_range_m;
            let range_m = body.sonar_range_m(&self.world.obstacles, request.neck_angle_rad, range);
            self.device
                .link(&mut self.mission)
                .reading(request.neck_angle_rad, range_m);
        }
    }

    /// One control period of `period_s` seconds, in the order of the module documentation.
    /// Nothing happens before the first mission starts.
    pub fn tick(&mut self, period_s: f32) {
        if let Some(config) = self.link().take_started() {
            self.pilot = Some(Pilot::new(&config));
            self.body = Some(SimBody::at_start(&config));
        }
        let (Some(body), Some(pilot)) = (&mut self.body, &mut self.pilot) else {
            return;
        };
        let (left, right) = body.encoder_deltas();
        let report = pilot.tick(left, right, period_s);
        self.link().tick(&report);
        self.serve();
        if let (Some(pilot), Some(body)) = (&self.pilot, &mut self.body) {
            let (left, right) = pilot.voltages_v();
            body.step(period_s, left, right);
        }
    }

    /// Every telemetry message the device has ready, encoded as frames, to `send`.
    pub fn send_telemetry(&mut self, send: &mut impl FnMut(&[u8])) {
        while let Some(t) = self.link().next_telemetry() {
            RobotDevice::<W>::send_telemetry(&t, send);
        }
    }
}
