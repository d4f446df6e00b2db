//! The device that runs missions: the link's planning service ([`Handler`]: the known map and
//! the planner on request) with a [`Mission`], the mission requests of protocol 2 and the
//! telemetry a running mission streams.
//!
//! ## Shape
//!
//! [`RobotDevice`] is sans-IO like the rest of the core. The firmware's lowest-priority task
//! owns one (in a `static`) with the planner; the simulator and the tests drive one on the host.
//! The shell borrows it with its [`Mission`] as a [`RobotLink`] and calls
//!
//! - [`RobotLink::receive`] with the bytes of the link (replies go to `send`);
//! - [`RobotLink::tick`] with each [`PilotReport`] of the control task;
//! - [`RobotLink::reading`] with each sonar reading;
//! - [`RobotLink::run_planner`] when [`RobotDevice::plan_pending`] says a plan is asked for;
//!
//! and takes from it what the other tasks must do: [`RobotDevice::take_pilot_command`] (with
//! [`RobotLink::prefix`] for `Follow`), [`RobotDevice::take_sonar_request`],
//! [`RobotLink::take_started`] (a mission started: reset the pilot, and a simulated robot, to
//! its start) and [`RobotLink::next_telemetry`] (pull, so a slow link delays telemetry, never
//! the mission).
//!
//! ## Telemetry
//!
//! While a mission runs: the pose every [`POSE_EVERY_TICKS`] control periods (5 Hz), every
//! change of phase or status, each finished sweep's hits, each applied plan with its kept
//! prefix and its first [`TELEMETRY_PATH_POINTS`] vertices, and the final report. Chunks of
//! [`TELEMETRY_CHUNK_POINTS`] points; a newer sweep or plan replaces one not yet sent in full.
//! The map travels as the hits: the host marks them with the same expansion.
//!
//! ## Memory
//!
//! The handler's grid is the known map (obstacles uploaded with `ObstacleChunk`); at the start
//! the mission's map is set to it. The real world of the simulated builds is not here: the
//! shell keeps it where its simulated sonar can read it and routes `WorldChunk` / `ClearWorld`
//! to [`RobotLink::handle_world`].

use heapless::Vec;

use super::frame::{FrameDecoder, FrameFault};
use super::handler::{upload_chunk, Handler};
use super::message::*;
use super::params::{DeviceParams, ParamSave};
use super::replay::ReplayCache;
use super::Device;
use crate::failsafe::{LinkLossReaction, LinkWatch, StopCause};
use crate::geom::PointM;
use crate::mission::{
    Mission, MissionConfig, MissionError, MissionEvent, MissionInput, MissionOutput, MissionPhase,
    MissionStatus, PilotCommand, PilotReport, PlanRequest, SonarRequest,
};
use crate::plan::{PlanStatus, Planner};

use crate::robot::RobotConfig;
use crate::world::{Params, PolygonSet};

/// The pose is reported every this many control periods (5 Hz at 50 ms).
pub const POSE_EVERY_TICKS: u32 = 4;

/// Vertices the real world of a simulated build holds ([`WorldUpload`]). The host's own
/// simulator holds [`crate::world::MAX_VERTICES`]; a simulated device gives its RAM to the
/// mission's evidence map instead (the bundled worlds have at most 64 vertices in 16 polygons;
/// `docs/firmware.md`).
pub const WORLD_VERTICES: usize = 192;
/// Polygons the real world of a simulated build holds.
pub const WORLD_POLYGONS: usize = 64;
/// Vertices of the one polygon being uploaded to the real world.
pub const WORLD_PENDING_VERTICES: usize = 64;

/// The real world of a simulated build, uploaded with [`Request::WorldChunk`]: at most
/// [`WORLD_VERTICES`] vertices in [`WORLD_POLYGONS`] polygons; a chunk beyond them is refused
/// with `TooManyVertices` / `TooManyPolygons` and changes nothing.
pub struct WorldUpload {
    /// The closed polygons.
    pub obstacles: PolygonSet<WORLD_VERTICES, WORLD_POLYGONS>,
    /// The polygon being uploaded.
    pub pending: Vec<PointM, WORLD_PENDING_VERTICES>,
}

impl WorldUpload {
    /// No polygon.
    pub const fn new() -> Self {
        Self {
            obstacles: PolygonSet::new(),
            pending: Vec::new(),
        }
    }
}

impl Default for WorldUpload {
    fn default() -> Self {
        Self::new()
    }
}

/// Where the shell keeps the real world: [`RobotLink::receive`] reaches it only for
/// `WorldChunk` and `ClearWorld` (the firmware locks it just for that).
pub trait WorldAccess {
    /// Call `f` with the world, if this build has one.
    fn with_world(&mut self, f: &mut dyn FnMut(&mut WorldUpload));
}

impl WorldAccess for WorldUpload {
    fn with_world(&mut self, f: &mut dyn FnMut(&mut WorldUpload)) {
        f(self)
    }
}

/// A build without a real world (a board): world requests get [`ErrorCode::NotOnThisBuild`].
pub struct NoWorld;

impl WorldAccess for NoWorld {
    fn with_world(&mut self, _f: &mut dyn FnMut(&mut WorldUpload)) {}
}

/// What is left to send of a list of points (hits, prefix, path).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Cursor {
    /// Sweep or plan number.
    number: u32,
    /// Next point to send.
    next: u16,
    /// Points to send.
    total: u16,
    /// Something is left.
    active: bool,
}

impl Cursor {
    fn start(number: u32, total: usize, cap: usize) -> Self {
        Self {
            number,
            next: 0,
            total: total.min(cap).min(u16::MAX as usize) as u16,
            active: true,
        }
    }

    /// The next chunk of `points` (at most `total`), or `None` when all went.
    fn chunk(
        &mut self,
        points: &[PointM],
    ) -> Option<(u32, u16, u16, Vec<PointM, TELEMETRY_CHUNK_POINTS>)> {
        if !self.active {
            return None;
        }
        let total = (self.total as usize).min(points.len());
        let first = self.next as usize;
        if first >= total && !(first == 0 && total == 0) {
            self.active = false;
            return None;
        }
        let end = (first + TELEMETRY_CHUNK_POINTS).min(total);
        let mut out = Vec::new();
        for p in points.get(first..end).unwrap_or(&[]) {
            let _ = out.push(*p); // at most TELEMETRY_CHUNK_POINTS
        }
        self.next = end as u16;
        if end >= total {
            self.active = false;
        }
        Some((self.number, first as u16, total as u16, out))
    }
}

/// Telemetry items waiting, one slot each (a newer one replaces an older of its kind).
#[derive(Clone, Copy, Debug, Default)]
struct Pending {
    finished: bool,
    phase: bool,
    pose: Option<PoseReport>,
    planned: Option<PlannedNote>,
    hits: Cursor,
    prefix: Cursor,
    path: Cursor,
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct PlannedNote {
    t_ms: u32,
    plan: u32,
    status: PlanStatus,
    path_points: u16,
    prefix_points: u16,
    instructions: u64,
}

/// The mission device: see the module documentation.
pub struct RobotDevice<const W: usize> {
    decoder: FrameDecoder,
    /// The planning service and the known map (public so the firmware can set its build and
    /// RAM figures).
    pub handler: Handler<W>,
    setup: Option<MissionSetup>,
    state: RunState,
    emergency_stop: bool,
    plan_request: Option<PlanRequest>,
    pilot_command: Option<PilotCommand>,
    sonar_request: Option<SonarRequest>,
    started: bool,
    ticks: u32,
    sweeps: u32,
    plans: u32,
    last_plan_instructions: u64,
    max_plan_instructions: u64,
    max_turn_instructions: u64,
    max_control_instructions: u64,
    stack_high_water_bytes: u32,
    stop_ticks: u32,
    stop_latency_us: u32,
    stop_cause: StopCause,
    link_watch: LinkWatch,
    reported: (MissionPhase, MissionStatus),
    pending: Pending,
    replay: ReplayCache,
    /// The robot config of the next mission and the store's status (`ParamList` / `Get` /
    /// `Set`, see [`super::params`]).
    params: DeviceParams,
    check_state: CheckState,
    check_report: crate::selftest::SelfTestReport,
}

impl<const W: usize> RobotDevice<W> {
    /// A device with an empty known map and no mission (`const`: it lives in a `static`).
    pub const fn new(info: DeviceInfo) -> Self {
        Self {
            decoder: FrameDecoder::new(),
            handler: Handler::new(info),
            setup: None,
            state: RunState::Idle,
            emergency_stop: false,
            plan_request: None,
            pilot_command: None,
            sonar_request: None,
            started: false,
            ticks: 0,
            sweeps: 0,
            plans: 0,
            last_plan_instructions: 0,
            max_plan_instructions: 0,
            max_turn_instructions: 0,
            max_control_instructions: 0,
            stack_high_water_bytes: 0,
            stop_ticks: 0,
            stop_latency_us: 0,
            stop_cause: StopCause::None,
            link_watch: LinkWatch::new(),
            reported: (MissionPhase::Done, MissionStatus::Aborted),
            pending: Pending {
                finished: false,
                phase: false,
                pose: None,
                planned: None,
                hits: Cursor {
                    number: 0,
                    next: 0,
                    total: 0,
                    active: false,
                },
                prefix: Cursor {
                    number: 0,
                    next: 0,
                    total: 0,
                    active: false,
                },
                path: Cursor {
                    number: 0,
                    next: 0,
                    total: 0,
                    active: false,
                },
            },
            replay: ReplayCache::new(),
            params: DeviceParams::DEFAULT,
            check_state: CheckState::Idle,
            check_report: crate::selftest::SelfTestReport::new(),
        }
    }

    /// The robot config the next mission starts from (the defaults until the shell calls
    /// [`RobotDevice::set_params`] or the host sets a parameter).
    pub fn params(&self) -> &DeviceParams {
        &self.params
    }

    /// Set the robot config and the store's status (the firmware's boot: the defaults with
    /// the stored values applied). `params.robot` is trusted to be valid
    /// ([`crate::params_store::robot::load_robot_config`] validates it).
    pub fn set_params(&mut self, params: DeviceParams) {
        self.params = params;
    }

    /// This device with `mission` (kept apart so the firmware can place it in its own memory
    /// region): what every call about the link or the mission goes through.
    pub fn link<'a, const E: usize>(
        &'a mut self,
        mission: &'a mut Mission<W, E>,
    ) -> RobotLink<'a, W, E> {
        RobotLink {
            d: self,
            mission,
            store: None,
        }
    }

    /// As [`RobotDevice::link`], with the store an accepted `ParamSet` is written to.
    pub fn link_with_store<'a, const E: usize>(
        &'a mut self,
        mission: &'a mut Mission<W, E>,
        store: &'a mut dyn ParamSave,
    ) -> RobotLink<'a, W, E> {
        RobotLink {
            d: self,
            mission,
            store: Some(store),
        }
    }

    /// Where the mission stands.
    pub fn state(&self) -> RunState {
        self.state
    }

    /// The latest command for the pilot, if any since the last call.
    pub fn take_pilot_command(&mut self) -> Option<PilotCommand> {
        self.pilot_command.take()
    }

    /// The sonar reading the mission asks for, if any since the last call.
    pub fn take_sonar_request(&mut self) -> Option<SonarRequest> {
        self.sonar_request.take()
    }

    /// A plan is asked for: call [`RobotLink::run_planner`].
    pub fn plan_pending(&self) -> bool {
        self.plan_request.is_some()
    }

    /// The firmware's measurements, for the mission report.
    pub fn note_timing(
        &mut self,
        max_control_instructions: u64,
        stack_high_water_bytes: u32,
        stop_ticks: u32,
    ) {
        self.max_control_instructions = max_control_instructions;
        self.stack_high_water_bytes = stack_high_water_bytes;
        self.stop_ticks = stop_ticks;
    }

    /// The firmware's measurement of one turn of its mission task, instructions: the report
    /// keeps the most since the mission started.
    pub fn note_turn_instructions(&mut self, instructions: u64) {
        self.max_turn_instructions = self.max_turn_instructions.max(instructions);
    }

    /// The firmware's measured stop latency (receive interrupt to motors off), microseconds.
    pub fn note_stop_latency_us(&mut self, stop_latency_us: u32) {
        self.stop_latency_us = stop_latency_us;
    }

    /// The shell's monotonic clock, milliseconds (wrapping): call it before
    /// [`RobotLink::receive`] and [`RobotLink::watch_link`]. Frames are stamped with it to
    /// measure the host's silence; a shell that never calls it never sees a lost link.
    pub fn set_now_ms(&mut self, now_ms: u32) {
        self.link_watch.set_now_ms(now_ms);
    }

    /// Milliseconds from the time of [`RobotDevice::set_now_ms`] until
    /// [`RobotLink::watch_link`] would act on the host's silence, while it still may (a
    /// running or paused mission whose link-loss policy has a timeout, not acted on yet). A
    /// shell that sleeps between turns sleeps no longer than this.
    pub fn link_loss_in_ms(&self) -> Option<u32> {
        if !matches!(self.state, RunState::Running | RunState::Paused) {
            return None;
        }
        let policy = self.setup.map(|s| s.link_loss)?;
        self.link_watch.reaction_in_ms(&policy)
    }

    /// Encode a telemetry message as a frame and pass the bytes to `send`.
    pub fn send_telemetry(telemetry: &Telemetry, send: &mut impl FnMut(&[u8])) {
        Device::<W>::send_encoded(&DeviceFrame::Telemetry(telemetry.clone()), send);
    }
}

/// A [`RobotDevice`] with its mission: see the module documentation.
pub struct RobotLink<'a, const W: usize, const E: usize = W> {
    d: &'a mut RobotDevice<W>,
    mission: &'a mut Mission<W, E>,
    store: Option<&'a mut dyn ParamSave>,
}

impl<const W: usize, const E: usize> RobotLink<'_, W, E> {
    /// The mission (its map, paths, stats).
    pub fn mission(&self) -> &Mission<W, E> {
        self.mission
    }

    /// The kept prefix, for [`PilotCommand::Follow`].
    pub fn prefix(&self) -> &[PointM] {
        self.mission.prefix()
    }

    /// The configuration of a mission that has just started (once): the shell resets its
    /// pilot (`Pilot::new`) and, simulated, the robot to the start pose.
    pub fn take_started(&mut self) -> Option<MissionConfig> {
        if core::mem::take(&mut self.d.started) {
            Some(*self.mission.config())
        } else {
            None
        }
    }

    /// Feed received bytes; for every complete frame, call `send` with the encoded reply.
    /// `planner` serves `Plan` requests; `clock` counts instructions (firmware) or returns 0;
    /// `world` is the real world of a simulated build ([`NoWorld`] on a board).
    pub fn receive<const S: usize, const Q: usize>(
        &mut self,
        bytes: &[u8],
        planner: &mut Planner<S, Q>,
        clock: &mut impl FnMut() -> u64,
        world: &mut impl WorldAccess,
        send: &mut impl FnMut(&[u8]),
    ) {
        let mut rest = bytes;
        while !rest.is_empty() {
            let (got, r) = self.d.decoder.feed::<RequestFrame>(rest);
            rest = r;
            let (seq, reply) = match got {
                None => continue,
                Some(Ok(frame)) => {
                    self.d.link_watch.heard();
                    if let Some(reply) = self.d.replay.lookup(frame.seq, &frame.request) {
                        // A retry of the last request: its reply again, not a second
                        // execution (see [`super::replay`]).
                        self.d.handler.count_request();
                        Device::<W>::send_encoded(
                            &DeviceFrame::Reply {
                                seq: Some(frame.seq),
                                reply,
                            },
                            send,
                        );
                        continue;
                    }
                    let reply = if matches!(
                        frame.request,
                        Request::WorldChunk { .. } | Request::ClearWorld
                    ) {
                        let mut reply = None;
                        world.with_world(&mut |w| {
                            reply = Some(self.handle_world(&frame.request, w));
                        });
                        reply.unwrap_or_else(|| {
                            self.d.handler.count_request();
                            Reply::Error(ErrorReply::new(ErrorCode::NotOnThisBuild, 0, 0))
                        })
                    } else {
                        self.handle(&frame.request, planner, clock)
                    };
                    self.d.replay.record(frame.seq, &frame.request, &reply);
                    (Some(frame.seq), reply)
                }
                Some(Err(fault)) => self.fault(fault),
            };
            Device::<W>::send_encoded(&DeviceFrame::Reply { seq, reply }, send);
        }
    }

    fn fault(&mut self, fault: FrameFault) -> (Option<u16>, Reply) {
        self.d.handler.fault_reply(fault)
    }

    /// Answer one request (the real world's are refused: the shell routes them to
    /// [`RobotLink::handle_world`]).
    pub fn handle<const S: usize, const Q: usize>(
        &mut self,
        request: &Request,
        planner: &mut Planner<S, Q>,
        clock: &mut impl FnMut() -> u64,
    ) -> Reply {
        match self.try_handle_mission(request) {
            Some(Ok(reply)) => {
                self.d.handler.count_request();
                reply
            }
            Some(Err(error)) => {
                self.d.handler.count_request();
                Reply::Error(error)
            }
            None => {
                let map_request = matches!(
                    request,
                    Request::SetParams(_)
                        | Request::ClearMap
                        | Request::ObstacleChunk { .. }
                        | Request::WriteMap { .. }
                        | Request::Plan { .. }
                );
                if map_request && matches!(self.d.state, RunState::Running | RunState::Paused) {
                    // The planner and the map are the mission's while it runs.
                    self.d.handler.count_request();
                    return Reply::Error(ErrorReply::new(
                        ErrorCode::WrongState,
                        state_index(self.d.state),
                        0,
                    ));
                }
                match self.mission.service_map() {
                    Some(grid) => self.d.handler.handle(request, grid, planner, clock),
                    // Refused above while a mission runs; an ended one gives its map back.
                    None => Reply::Error(ErrorReply::new(
                        ErrorCode::WrongState,
                        state_index(self.d.state),
                        0,
                    )),
                }
            }
        }
    }

    /// Answer a request about the real world ([`Request::WorldChunk`], [`Request::ClearWorld`])
    /// on `world` (simulated builds). Refused while a mission runs.
    pub fn handle_world(&mut self, request: &Request, world: &mut WorldUpload) -> Reply {
        self.d.handler.count_request();
        if matches!(self.d.state, RunState::Running | RunState::Paused) {
            return Reply::Error(ErrorReply::new(
                ErrorCode::WrongState,
                state_index(self.d.state),
                0,
            ));
        }
        match request {
            Request::ClearWorld => {
                world.obstacles.clear();
                world.pending.clear();
                Reply::Ack
            }
            Request::WorldChunk {
                first_vertex,
                vertices,
                last,
            } => match upload_chunk(
                &mut world.obstacles,
                &mut world.pending,
                *first_vertex,
                vertices,
                *last,
            ) {
                Ok(_) => Reply::Obstacles {
                    polygons: world.obstacles.len() as u16,
                    vertices: world.obstacles.vertex_count() as u16,
                    pending_vertices: world.pending.len() as u16,
                },
                Err(e) => Reply::Error(e),
            },
            _ => Reply::Error(ErrorReply::new(ErrorCode::BadMessage, 0, 0)),
        }
    }

    /// The mission requests; `None` for the others.
    fn try_handle_mission(&mut self, request: &Request) -> Option<Result<Reply, ErrorReply>> {
        let wrong = |state: RunState| ErrorReply::new(ErrorCode::WrongState, state_index(state), 0);
        let running = matches!(self.d.state, RunState::Running | RunState::Paused);
        let store = self.store.as_mut().map(|s| &mut **s as &mut dyn ParamSave);
        if let Some(reply) =
            self.d
                .params
                .handle(request, running.then(|| state_index(self.d.state)), store)
        {
            return Some(reply);
        }
        Some(match request {
            Request::SetMission(setup) => {
                if running {
                    Err(wrong(self.d.state))
                } else {
                    self.mission_config(setup).map(|_| {
                        self.d.setup = Some(*setup);
                        self.d.state = RunState::Ready;
                        Reply::Ack
                    })
                }
            }
            Request::WorldChunk { .. } | Request::ClearWorld => {
                Err(ErrorReply::new(ErrorCode::NotOnThisBuild, 0, 0))
            }
            Request::StartMission => self.start(),
            Request::PauseMission => {
                if self.d.state == RunState::Running {
                    self.d.state = RunState::Paused;
                    self.d.pilot_command = Some(PilotCommand::Hold);
                    Ok(Reply::Ack)
                } else {
                    Err(wrong(self.d.state))
                }
            }
            Request::ResumeMission => {
                if self.d.state == RunState::Paused {
                    self.d.state = RunState::Running;
                    let out = self.mission.step(MissionInput::Interrupt);
                    self.absorb(out);
                    Ok(Reply::Ack)
                } else {
                    Err(wrong(self.d.state))
                }
            }
            Request::AbortMission => {
                self.stop_mission_for(StopCause::Host);
                Ok(Reply::Ack)
            }
            Request::EmergencyStop => {
                self.d.emergency_stop = true;
                self.stop_mission_for(StopCause::EmergencyStop);
                Ok(Reply::Ack)
            }
            Request::ClearEmergencyStop => {
                self.d.emergency_stop = false;
                Ok(Reply::Ack)
            }
            Request::MissionStatus => Ok(Reply::Mission(self.report())),
            Request::SelfTest => self.d.start_self_test(),
            Request::SelfTestReport => Ok(Reply::SelfTest(self.d.check_report.clone())),
            _ => return None,
        })
    }

    /// The mission configuration of `setup` on the current map and radius; errors name the
    /// field.
    fn mission_config(&self, setup: &MissionSetup) -> Result<MissionConfig, ErrorReply> {
        let params = self.d.handler.params();
        let bad = |field: u32| ErrorReply::new(ErrorCode::BadMission, field, 0);
        let robot = RobotConfig {
            sonar_range_m: setup.sonar_range_m,
            sonar_noise_std_m: setup.sonar_noise_std_m,
            noise_seed: setup.noise_seed,
            sonar_beam: setup.sonar_beam,
            sonar_beam_half_angle_deg: setup.beam_half_angle_deg,
            sonar_incidence_limit_deg: setup.incidence_limit_deg,
            sonar_dropout_probability: setup.sonar_dropout_probability,
            sonar_spurious_probability: setup.sonar_spurious_probability,
            sweep_layout: setup.sweep_layout,
            // The device's parameters (the stored values, `ParamSet`) for the rest.
            ..self.d.params.robot
        };
        let par = Params {
            robot_radius_m: params.robot_radius_m,
            speed_m_s: setup.speed_m_s,
            initial_heading_deg: setup.initial_heading_rad.to_degrees(),
            start: setup.start,
            goal: setup.goal,
        };
        let mut config = MissionConfig::from_params(&par, robot);
        config.initial_heading_rad = setup.initial_heading_rad;
        config.mode = setup.mode;
        config.planner = setup.planner;
        config.time_limit_s = setup.time_limit_s;
        config.constant_depth_filter = setup.constant_depth_filter;
        config.trust_seen_space = setup.trust_seen_space;
        config.settle = setup.settle;
        config.reference_feed_forward = setup.reference_feed_forward;
        config.evidence_map = setup.evidence_map;
        if !setup.turn_in_place {
            // Direction changes are wrapped to ±π: none is larger.
            config.turn_in_place_above_rad = core::f32::consts::PI;
        }
        // Field indices of MissionSetup: 2 start, 3 heading, 4 goal, 5 speed, 6 sonar range,
        // 7 time limit, 11 noise, 12 link-loss policy, 14 beam half-angle, 15 incidence limit,
        // 21 dropout, 22 spurious echoes.
        if !setup.link_loss.is_valid() {
            return Err(bad(12));
        }
        if !setup.start.is_finite() {
            return Err(bad(2));
        }
        if !setup.initial_heading_rad.is_finite() {
            return Err(bad(3));
        }
        if !setup.goal.is_finite() {
            return Err(bad(4));
        }
        if let Err(e) = config.validate() {
            return Err(match e {
                MissionError::BadValue { field, .. } => match field {
                    // The safe bound in mm/s, so the host can say it.
                    "speed_m_s" => ErrorReply::new(
                        ErrorCode::BadMission,
                        5,
                        (config.robot.max_safe_speed_m_s() * 1000.0) as u32,
                    ),
                    // Robot config field 0 (the radius comes from `SetParams`).
                    "planning_radius_m" => bad(100),
                    "time_limit_s" => bad(7),
                    _ => bad(100),
                },
                MissionError::Robot(r) => match r.field {
                    "sonar_range_m" => bad(6),
                    "sonar_noise_std_m" => bad(11),
                    "sonar_beam_half_angle_deg" => bad(14),
                    "sonar_incidence_limit_deg" => bad(15),
                    "sonar_dropout_probability" => bad(21),
                    "sonar_spurious_probability" => bad(22),
                    _ => bad(100),
                },
                _ => bad(100),
            });
        }
        // Off the map: the field's index (2 start, 4 goal) with detail 1, so a client can
        // say which.
        let geometry = *self.mission.grid().geometry();
        for (field, point) in [(2, setup.start), (4, setup.goal)] {
            if geometry.cell_of(point).is_err() {
                return Err(ErrorReply {
                    code: ErrorCode::BadMission,
                    value: field,
                    limit: 0,
                    detail: 1,
                });
            }
        }
        Ok(config)
    }

    fn start(&mut self) -> Result<Reply, ErrorReply> {
        if self.d.emergency_stop {
            return Err(ErrorReply {
                code: ErrorCode::WrongState,
                value: state_index(self.d.state),
                limit: 0,
                detail: 1,
            });
        }
        if self.d.self_test_busy() {
            return Err(check::self_test_busy(self.d.state));
        }
        let Some(setup) = self.d.setup else {
            return Err(ErrorReply::new(ErrorCode::WrongState, 0, 0));
        };
        if matches!(self.d.state, RunState::Running | RunState::Paused) {
            return Err(ErrorReply::new(
                ErrorCode::WrongState,
                state_index(self.d.state),
                0,
            ));
        }
        // The map may have changed since SetMission: check again.
        let config = self.mission_config(&setup)?;
        let geometry = *self.mission.grid().geometry();
        self.mission.restart(config, geometry).map_err(|_| {
            ErrorReply::new(ErrorCode::GridCapacity, geometry.cell_count() as u32, 0)
        })?;
        // What the robot knows: the uploaded obstacles, grown by the same radius (the map of
        // the previous mission, with what its sonar found, is forgotten).
        for polygon in self.d.handler.obstacles().iter() {
            self.mission.add_known_polygon(polygon);
        }
        self.d.state = RunState::Running;
        self.d.started = true;
        self.d.stop_cause = StopCause::None;
        self.d.stop_latency_us = 0;
        self.d.link_watch.start();
        self.d.ticks = 0;
        self.d.sweeps = 0;
        self.d.plans = 0;
        self.d.max_plan_instructions = 0;
        self.d.max_turn_instructions = 0;
        self.d.plan_request = None;
        self.d.sonar_request = None;
        self.d.pilot_command = Some(PilotCommand::Hold);
        self.d.pending = Pending::default();
        self.d.reported = (self.mission.phase(), self.mission.status());
        self.d.pending.phase = true;
        Ok(Reply::Ack)
    }

    /// Stop the mission (if one runs: `cause` is reported) and the motors.
    fn stop_mission_for(&mut self, cause: StopCause) {
        if matches!(self.d.state, RunState::Running | RunState::Paused) {
            self.d.stop_cause = cause;
            let out = self.mission.step(MissionInput::Abort);
            self.absorb(out);
        }
        self.d.pilot_command = Some(PilotCommand::Stop);
        self.d.sonar_request = None;
    }

    /// A failsafe of the shell fired (e.g. [`StopCause::ControllerOverrun`], a
    /// [`StopCause::SensorFault`] of the body): a running mission ends `Aborted` with `cause`,
    /// the pilot is told to stop. [`StopCause::EmergencyStop`] (the board's input, reported by
    /// `drivers::body::Chassis`) also latches the device's stop as the `EmergencyStop` request
    /// does: a new mission needs `ClearEmergencyStop` first.
    pub fn fail(&mut self, cause: StopCause) {
        if cause == StopCause::EmergencyStop {
            self.d.emergency_stop = true;
        }
        self.stop_mission_for(cause);
    }

    /// Apply the mission's link-loss policy (`MissionSetup::link_loss`) to the host's silence
    /// at the time of [`RobotDevice::set_now_ms`]: `StopAndHold` ends a running or paused
    /// mission with [`StopCause::LinkLost`]. Returns the reaction taken, once per mission.
    pub fn watch_link(&mut self) -> Option<LinkLossReaction> {
        if !matches!(self.d.state, RunState::Running | RunState::Paused) {
            return None;
        }
        let policy = self.d.setup.map(|s| s.link_loss)?;
        let reaction = self.d.link_watch.check(&policy)?;
        if reaction == LinkLossReaction::StopAndHold {
            self.stop_mission_for(StopCause::LinkLost);
        }
        Some(reaction)
    }

    /// Milliseconds since the host was last heard (see [`RobotDevice::set_now_ms`]).
    pub fn link_silent_ms(&self) -> u32 {
        self.d.link_watch.silent_ms()
    }

    /// One control period of the pilot.
    pub fn tick(&mut self, report: &PilotReport) {
        if self.d.state != RunState::Running {
            return;
        }
        self.d.ticks = self.d.ticks.wrapping_add(1);
        let out = self.mission.step(MissionInput::Tick(*report));
        if self.d.ticks.is_multiple_of(POSE_EVERY_TICKS) {
            let pose = self.mission.pose_world();
            self.d.pending.pose = Some(PoseReport {
                t_ms: self.t_ms(),
                position: PointM::new(pose.x_m, pose.y_m),
                heading_rad: pose.heading_rad,
                left_voltage_v: report.left_voltage_v,
                right_voltage_v: report.right_voltage_v,
                controller_overruns: self.mission.stats().controller_overruns,
            });
        }
        self.absorb(out);
    }

    /// The answer to the last sonar request.
    pub fn reading(&mut self, neck_angle_rad: f32, range_m: Option<f32>) {
        if self.d.state != RunState::Running {
            return;
        }
        let out = self.mission.step(MissionInput::SonarReading {
            neck_angle_rad,
            range_m,
        });
        self.absorb(out);
    }

    /// Run the planner for the plan asked for, on the mission's map, and hand the result back
    /// (also while paused: the mission is not changed meanwhile). `clock` counts instructions.
    pub fn run_planner<const S: usize, const Q: usize>(
        &mut self,
        planner: &mut Planner<S, Q>,
        clock: &mut impl FnMut() -> u64,
    ) {
        let Some(request) = self.d.plan_request.take() else {
            return;
        };
        let before = clock();
        let (grid, path) = self.mission.plan_workspace();
        let result = planner.plan(request.kind, grid, request.start, request.goal, path);
        let instructions = clock().saturating_sub(before);
        // The planner's cell buffer now holds the mission's path, not the service's.
        self.d.handler.forget_path();
        self.d.last_plan_instructions = instructions;
        self.d.max_plan_instructions = self.d.max_plan_instructions.max(instructions);
        let out = self.mission.step(MissionInput::PlanDone {
            id: request.id,
            result,
        });
        self.absorb(out);
    }

    /// Take what a mission step asked for and note its telemetry.
    fn absorb(&mut self, out: MissionOutput) {
        if let Some(command) = out.pilot_command {
            // Stop is final for this mission; the latest of the others wins.
            if self.d.pilot_command != Some(PilotCommand::Stop) {
                self.d.pilot_command = Some(command);
            }
        }
        if out.sonar_request.is_some() {
            self.d.sonar_request = out.sonar_request;
        }
        if out.plan_request.is_some() {
            self.d.plan_request = out.plan_request;
        }
        let t_ms = self.t_ms();
        for event in out.events.iter() {
            match *event {
                MissionEvent::SweepDone { .. } => {
                    self.d.sweeps += 1;
                    let hits = self.mission.last_hits().len();
                    self.d.pending.hits = Cursor::start(self.d.sweeps, hits, usize::MAX);
                }
                MissionEvent::Planned {
                    status,
                    prefix_points,
                    ..
                } => {
                    self.d.plans += 1;
                    let path_points = self.mission.path().len();
                    self.d.pending.planned = Some(PlannedNote {
                        t_ms,
                        plan: self.d.plans,
                        status,
                        path_points: path_points.min(u16::MAX as usize) as u16,
                        prefix_points,
                        instructions: self.d.last_plan_instructions,
                    });
                    self.d.pending.prefix =
                        Cursor::start(self.d.plans, self.mission.prefix().len(), usize::MAX);
                    self.d.pending.path =
                        Cursor::start(self.d.plans, path_points, TELEMETRY_PATH_POINTS);
                }
                MissionEvent::Finished(_) => {
                    self.d.state = RunState::Ended;
                    self.d.plan_request = None;
                    self.d.sonar_request = None;
                    self.d.pending.finished = true;
                }
                _ => {}
            }
        }
        let now = (self.mission.phase(), self.mission.status());
        if now != self.d.reported {
            self.d.reported = now;
            self.d.pending.phase = true;
        }
    }

    fn t_ms(&self) -> u32 {
        let t = self.mission.stats().time_s * 1000.0;
        if t.is_finite() && t >= 0.0 {
            (t + 0.5) as u32
        } else {
            0
        }
    }

    /// The mission report.
    pub fn report(&self) -> MissionReport {
        MissionReport {
            state: self.d.state,
            status: self.mission.status(),
            phase: self.mission.phase(),
            stats: self.mission.stats(),
            max_control_instructions: self.d.max_control_instructions,
            max_plan_instructions: self.d.max_plan_instructions,
            max_turn_instructions: self.d.max_turn_instructions,
            stack_high_water_bytes: self.d.stack_high_water_bytes,
            stop_ticks: self.d.stop_ticks,
            emergency_stop: self.d.emergency_stop,
            stop_cause: self.d.stop_cause,
            stop_latency_us: self.d.stop_latency_us,
        }
    }

    /// The next telemetry message to send, most urgent first: the phase, the pose, the plan,
    /// its prefix, the sweep's hits, the plan's vertices, and last the final report (after
    /// everything the mission produced before it ended).
    pub fn next_telemetry(&mut self) -> Option<Telemetry> {
        let p = &mut self.d.pending;
        if core::mem::take(&mut p.phase) {
            return Some(Telemetry::Phase {
                t_ms: self.t_ms(),
                phase: self.d.reported.0,
                status: self.d.reported.1,
            });
        }
        if let Some(pose) = self.d.pending.pose.take() {
            return Some(Telemetry::Pose(pose));
        }
        if let Some(n) = self.d.pending.planned.take() {
            return Some(Telemetry::Planned {
                t_ms: n.t_ms,
                plan: n.plan,
                status: n.status,
                path_points: n.path_points,
                prefix_points: n.prefix_points,
                instructions: n.instructions,
            });
        }
        if let Some((plan, first, total, points)) =
            self.d.pending.prefix.chunk(self.mission.prefix())
        {
            return Some(Telemetry::Prefix {
                plan,
                first,
                total,
                points,
            });
        }
        if let Some((sweep, first, total, hits)) =
            self.d.pending.hits.chunk(self.mission.last_hits())
        {
            return Some(Telemetry::SweepHits {
                sweep,
                first,
                total,
                hits,
            });
        }
        if let Some((plan, first, total, points)) = self.d.pending.path.chunk(self.mission.path()) {
            return Some(Telemetry::Path {
                plan,
                first,
                total,
                points,
            });
        }
        if core::mem::take(&mut self.d.pending.finished) {
            return Some(Telemetry::Finished(self.report()));
        }
        None
    }
}

/// [`RunState`]'s index, as [`ErrorCode::WrongState`] reports it.
fn state_index(state: RunState) -> u32 {
    match state {
        RunState::Idle => 0,
        RunState::Ready => 1,
        RunState::Running => 2,
        RunState::Paused => 3,
        RunState::Ended => 4,
    }
}

mod check;
pub use check::CheckState;

#[cfg(test)]
mod tests;

#[cfg(test)]
mod promise_tests;
