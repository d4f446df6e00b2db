//! The messages of the link: what the host asks ([`Request`]), what the device answers
//! ([`Reply`]) and what it reports unasked ([`Telemetry`]).
//!
//! Every type here is plain data with serde derives; postcard encodes enums as a varint variant
//! index followed by the fields, integers as varints and `f32` as 4 little-endian bytes
//! (`docs/protocol.md` lists the indices). Collections are heapless vectors whose capacity is a
//! named constant, so the largest message has a known size (checked against
//! [`MAX_FRAME_BYTES`](super::frame::MAX_FRAME_BYTES) by a test).

use heapless::Vec;
use serde::{Deserialize, Serialize};

use crate::failsafe::{LinkLossPolicy, ResetCause, StopCause};
use crate::geom::PointM;
use crate::mission::{MissionMode, MissionPhase, MissionStats, MissionStatus};
use crate::params_store::StoreStatus;
use crate::plan::{PlanStatus, PlannerKind};

/// Version of this protocol. A host and a device only talk when their versions are equal
/// ([`Request::Hello`]). 2: missions (requests 10–19, telemetry 3–8, the pose report). 3:
/// failsafes (`MissionSetup::link_loss`, `MissionReport::stop_cause` / `stop_latency_us`,
/// the reset cause in `DeviceStatus` and `Telemetry::Boot`). 4: the plant's sonar model and the
/// following choices of `--preset` in `SetMission` (fields 13–19), `MissionStats::blind_cuts`.
/// 5: `StopCause::SensorFault` (the board's body: homing, sonar, battery, motors, e-stop input).
/// 6: the device's parameters (requests `ParamList`, `ParamGet`, `ParamSet`; replies `Param`,
/// `ParamRefused`; error codes `UnknownParam`, `StoreFailed`) and the bring-up self-test
/// (`Request::SelfTest`, `Request::SelfTestReport`, `Reply::SelfTest`). 7: the evidence map
/// (`MissionSetup::evidence_map`, field 20) and `MissionReport::max_turn_instructions`. 8: the
/// simulated ranger's missed and spurious echoes (`MissionSetup` fields 21, 22).
pub const PROTOCOL_VERSION: u16 = 8;

/// Points carried by one telemetry chunk of hits, prefix or path.
pub const TELEMETRY_CHUNK_POINTS: usize = 32;

/// Most plan vertices sent as telemetry after a plan (the prefix is sent whole): 8 chunks, so
/// a plan costs at most about 2.3 KB of the link's 11.5 KB/s.
pub const TELEMETRY_PATH_POINTS: usize = 256;

/// Vertices carried by one [`Request::ObstacleChunk`].
pub const OBSTACLE_CHUNK_VERTICES: usize = 32;
/// Path points carried by one [`Reply::PathChunk`].
pub const PATH_CHUNK_POINTS: usize = 32;
/// Grid words (32 cells each) carried by one [`Reply::MapChunk`] or [`Request::WriteMap`].
pub const MAP_CHUNK_WORDS: usize = 64;
/// Bytes of a parameter's name on the wire (the longest, `sonar_spurious_probability`, has 26).
pub const PARAM_NAME_BYTES: usize = 32;
/// Bytes of a parameter's unit on the wire (the longest, `V s^2 per rad`, has 13).
pub const PARAM_UNIT_BYTES: usize = 16;
/// Bytes of the rule a refused parameter broke (the longest of `RobotConfig::validate` has 77;
/// a longer one is cut at a character boundary).
pub const PARAM_RULE_BYTES: usize = 96;

/// A request as it travels: the host's sequence number and the request.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RequestFrame {
    /// Chosen by the host (usually incremented per request); echoed in the reply.
    pub seq: u16,
    /// What is asked.
    pub request: Request,
}

/// What the device sends.
// Replies are the big variant and the common one; there is no heap to box them into.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum DeviceFrame {
    /// The one answer to a request.
    Reply {
        /// The request's sequence number; `None` when the request frame was too damaged to read
        /// it (bad COBS, bad CRC, too long).
        seq: Option<u16>,
        /// The answer.
        reply: Reply,
    },
    /// A report the host did not ask for.
    Telemetry(Telemetry),
}

/// Map size and robot radius (`SetParams`). Obstacles are grown by the radius when marked.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MapParams {
    /// Width, cells.
    pub width_cells: u16,
    /// Height, cells.
    pub height_cells: u16,
    /// Side of a cell, metres.
    pub resolution_m: f32,
    /// Planning radius of the robot, metres (0 to 10).
    pub robot_radius_m: f32,
}

impl Default for MapParams {
    /// The seed's map (300 x 300 cells of 0.05 m) and a point robot.
    fn default() -> Self {
        Self {
            width_cells: crate::grid::DEFAULT_SIDE_CELLS,
            height_cells: crate::grid::DEFAULT_SIDE_CELLS,
            resolution_m: crate::grid::DEFAULT_RESOLUTION_M,
            robot_radius_m: 0.0,
        }
    }
}

/// What the host can ask.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Request {
    /// Version handshake: answered by [`Reply::Hello`] when the versions match, by
    /// [`ErrorCode::VersionMismatch`] otherwise.
    Hello {
        /// The host's [`PROTOCOL_VERSION`].
        protocol_version: u16,
    },
    /// Answered by [`Reply::Pong`] with the same nonce.
    Ping {
        /// Any value.
        nonce: u32,
    },
    /// Set the map size and the robot radius: clears the map, keeps the obstacles and marks them
    /// again with the new radius. Answered by [`Reply::Ack`].
    SetParams(MapParams),
    /// Forget every obstacle and the last path; clear the map. Answered by [`Reply::Ack`].
    ClearMap,
    /// Part of an obstacle polygon. A polygon is sent in chunks of at most
    /// [`OBSTACLE_CHUNK_VERTICES`]; `first_vertex` is the index of the chunk's first vertex in
    /// the polygon (0 starts a new polygon, dropping an unfinished one); the chunk with `last`
    /// set closes the polygon, which is then stored and marked on the map. Answered by
    /// [`Reply::Obstacles`].
    ObstacleChunk {
        /// Index of `vertices[0]` within the polygon.
        first_vertex: u16,
        /// The vertices, metres.
        vertices: Vec<PointM, OBSTACLE_CHUNK_VERTICES>,
        /// This chunk ends the polygon.
        last: bool,
    },
    /// Overwrite packed map words from `offset_words` (cell `i` is bit `i % 32` of word
    /// `i / 32`, rows first). Answered by [`Reply::Ack`].
    WriteMap {
        /// Index of `words[0]`.
        offset_words: u32,
        /// The words.
        words: Vec<u32, MAP_CHUNK_WORDS>,
    },
    /// Plan on the current map. Answered by [`Reply::Plan`]; the path is then read with
    /// [`Request::ReadPath`].
    Plan {
        /// Which planner.
        kind: PlannerKind,
        /// Start, metres.
        start: PointM,
        /// Goal, metres.
        goal: PointM,
    },
    /// Read the last path from point `offset`. Answered by [`Reply::PathChunk`].
    ReadPath {
        /// First point wanted.
        offset: u16,
    },
    /// Read the packed map from word `offset_words`. Answered by [`Reply::MapChunk`].
    ReadMap {
        /// First word wanted.
        offset_words: u32,
    },
    /// Answered by [`Reply::Status`].
    Status,
    /// Set up the next mission (on the map of `SetParams`, with the obstacles uploaded so far
    /// as what the robot knows). Refused while a mission runs. Answered by [`Reply::Ack`].
    SetMission(MissionSetup),
    /// Part of a polygon of the *real* world, in which the simulated sonar casts its rays and
    /// the simulated robot drives (QEMU and host builds only; a board answers
    /// [`ErrorCode::NotOnThisBuild`]). Chunks as [`Request::ObstacleChunk`]. Answered by
    /// [`Reply::Obstacles`] with the world's counts.
    WorldChunk {
        /// Index of `vertices[0]` within the polygon.
        first_vertex: u16,
        /// The vertices, metres.
        vertices: Vec<PointM, OBSTACLE_CHUNK_VERTICES>,
        /// This chunk ends the polygon.
        last: bool,
    },
    /// Forget the real world's polygons. Answered by [`Reply::Ack`].
    ClearWorld,
    /// Start the mission set up by [`Request::SetMission`] (the simulated robot, if any, is put
    /// at its start pose). Answered by [`Reply::Ack`]; then telemetry streams.
    StartMission,
    /// Hold the robot where it is; the mission's clock stops. Answered by [`Reply::Ack`].
    PauseMission,
    /// Go on after a pause: the robot sweeps and plans afresh from where it stands.
    ResumeMission,
    /// End the mission: zero volts on both motors within one control period, status
    /// `Aborted`. Answered by [`Reply::Ack`] (the firmware acts on it before it answers).
    AbortMission,
    /// As [`Request::AbortMission`], and no mission starts again until
    /// [`Request::ClearEmergencyStop`].
    EmergencyStop,
    /// Allow missions again after [`Request::EmergencyStop`] (a board also needs its e-stop
    /// input released).
    ClearEmergencyStop,
    /// Answered by [`Reply::Mission`].
    MissionStatus,
    /// Row `index` of the device's parameter table (0 first; read them all by counting up to
    /// [`ParamEntry::count`]). Answered by [`Reply::Param`]; [`ErrorCode::OutOfRange`] past the
    /// end.
    ParamList {
        /// The row.
        index: u16,
    },
    /// The parameter `name`. Answered by [`Reply::Param`]; [`ErrorCode::UnknownParam`].
    ParamGet {
        /// Its name (the robot file's key).
        name: heapless::String<PARAM_NAME_BYTES>,
    },
    /// Set the parameter `name` to `value` in the robot config of the next mission, validated
    /// with the rest of that config, and store it (when the device has a store). Answered by
    /// [`Reply::Param`] with the new value; a value the model refuses by
    /// [`Reply::ParamRefused`] (nothing changed); [`ErrorCode::UnknownParam`],
    /// [`ErrorCode::WrongState`] while a mission runs, [`ErrorCode::StoreFailed`].
    ParamSet {
        /// Its name (the robot file's key).
        name: heapless::String<PARAM_NAME_BYTES>,
        /// The new value (a whole number, 0 / 1, a choice's index: see `twil_core::params`).
        value: f32,
    },
    /// Start the bring-up self-test ([`crate::selftest`]): the motors pulse one wheel at a
    /// time, the neck homes and turns, the sonar pings. Refused while a mission runs or is
    /// paused, or a self-test runs. Answered by [`Reply::Ack`]; then poll
    /// [`Request::SelfTestReport`].
    SelfTest,
    /// Answered by [`Reply::SelfTest`]: the rows so far, `done` once all are in.
    SelfTestReport,
}

/// One row of the device's parameter table ([`Reply::Param`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ParamEntry {
    /// The row's index in the device's table.
    pub index: u16,
    /// Rows in the device's table.
    pub count: u16,
    /// The name (the robot file's key).
    pub name: heapless::String<PARAM_NAME_BYTES>,
    /// The unit, in words (empty: none).
    pub unit: heapless::String<PARAM_UNIT_BYTES>,
    /// The value the next mission uses.
    pub value: f32,
    /// The firmware's default.
    pub default: f32,
    /// Lower limit (see `twil_core::params::Param::min`).
    pub min: f32,
    /// Upper limit (infinite: none).
    pub max: f32,
    /// What the device's store held at boot, `Ok` once a value has been stored since; `None`:
    /// the device has no store (values last until it resets).
    pub store: Option<StoreStatus>,
}

/// Why a [`Request::ParamSet`] was refused: nothing changed ([`Reply::ParamRefused`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ParamRefusal {
    /// The parameter whose rule the new config breaks (the one set, or one it depends on:
    /// `sonar_range_m` for a `sonar_min_range_m` above it).
    pub name: heapless::String<PARAM_NAME_BYTES>,
    /// That parameter's value in the refused config.
    pub value: f32,
    /// What is accepted, in words.
    pub rule: heapless::String<PARAM_RULE_BYTES>,
}

/// What a mission needs beyond the map (`SetParams`: size, resolution, planning radius) and
/// the known obstacles (`ObstacleChunk`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MissionSetup {
    /// Stop-and-sweep or continuous.
    pub mode: MissionMode,
    /// Planner.
    pub planner: PlannerKind,
    /// Start position, metres.
    pub start: PointM,
    /// Initial heading, radians counter-clockwise from +x.
    pub initial_heading_rad: f32,
    /// Goal, metres.
    pub goal: PointM,
    /// Cruise speed, m/s.
    pub speed_m_s: f32,
    /// Sonar range, metres (0.26 < range <= 6).
    pub sonar_range_m: f32,
    /// Mission time limit, seconds.
    pub time_limit_s: f32,
    /// Filter sweeps with the regions-of-constant-depth filter.
    pub constant_depth_filter: bool,
    /// Trust space seen free by earlier sweeps.
    pub trust_seen_space: bool,
    /// Seed of the simulated sonar's noise (simulated builds).
    pub noise_seed: u64,
    /// Standard deviation of the simulated sonar's noise, metres (simulated builds).
    pub sonar_noise_std_m: f32,
    /// What the mission does when the host falls silent (timeout 0: nothing).
    pub link_loss: LinkLossPolicy,
    /// Simulated sonar: the ultrasonic beam instead of one ray ([`crate::robot::RobotConfig::sonar_beam`];
    /// simulated builds).
    pub sonar_beam: bool,
    /// The beam's half-angle, degrees (simulated builds).
    pub beam_half_angle_deg: f32,
    /// The beam's incidence limit, degrees (simulated builds).
    pub incidence_limit_deg: f32,
    /// How long a stop settles (`--settle`).
    pub settle: crate::mission::SettleRule,
    /// Add τ × velocity to the controller's reference (`--feed-forward`).
    pub reference_feed_forward: bool,
    /// Turn in place at the start of a prefix and at sharp vertices (`--turn-in-place`).
    pub turn_in_place: bool,
    /// Which neck positions a sweep reads (`--sweep-readings`).
    pub sweep_layout: crate::sonar::SweepLayout,
    /// Map with the evidence map (`--evidence-map`, [`crate::mission::MissionConfig::evidence_map`]).
    pub evidence_map: bool,
    /// Probability of a missed echo per reading (`--sonar-dropout`, [`crate::plant::faults`];
    /// simulated builds).
    pub sonar_dropout_probability: f32,
    /// Probability of a spurious short echo per reading (`--sonar-spurious`; simulated builds).
    pub sonar_spurious_probability: f32,
}

impl MissionSetup {
    /// The mission of a `.par` (start, heading, goal, speed) in `mode` with the test benches'
    /// choices: A*, a 1.5 m noiseless, faultless single-ray sonar (seed 1), 900 s, no filter, trusted seen
    /// space, no link-loss reaction, the reference-model settle, feed-forward, turns in place,
    /// the symmetric sweep. Change a field with struct-update syntax.
    pub fn from_params(params: &crate::world::Params, mode: MissionMode) -> Self {
        MissionSetup {
            mode,
            planner: PlannerKind::AStar,
            start: params.start,
            initial_heading_rad: params.initial_heading_deg.to_radians(),
            goal: params.goal,
            speed_m_s: params.speed_m_s,
            sonar_range_m: 1.5,
            time_limit_s: 900.0,
            constant_depth_filter: false,
            trust_seen_space: true,
            noise_seed: 1,
            sonar_noise_std_m: 0.0,
            link_loss: LinkLossPolicy::NEVER,
            sonar_beam: false,
            beam_half_angle_deg: 15.0,
            incidence_limit_deg: 70.0,
            settle: crate::mission::SettleRule::ReferenceModel,
            reference_feed_forward: true,
            turn_in_place: true,
            sweep_layout: crate::sonar::SweepLayout::Symmetric,
            evidence_map: false,
            sonar_dropout_probability: 0.0,
            sonar_spurious_probability: 0.0,
        }
    }
}

/// How the device's mission stands ([`Reply::Mission`], [`Telemetry::Finished`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MissionReport {
    /// Set up, running, paused, ended.
    pub state: RunState,
    /// The mission's status.
    pub status: MissionStatus,
    /// Its phase.
    pub phase: MissionPhase,
    /// Its counters.
    pub stats: MissionStats,
    /// Most instructions one control step took (firmware: measured; 0 elsewhere).
    pub max_control_instructions: u64,
    /// Most instructions one plan took (firmware: measured; 0 elsewhere).
    pub max_plan_instructions: u64,
    /// Most instructions one turn of the mission task took, preemptions included (the
    /// watchdog gate's limit is per turn; firmware: measured; 0 elsewhere).
    pub max_turn_instructions: u64,
    /// Deepest stack use seen (painted stack), bytes (firmware; 0 elsewhere).
    pub stack_high_water_bytes: u32,
    /// Control periods from the last `AbortMission` / `EmergencyStop` frame's arrival to the
    /// tick that put zero volts on the motors, that tick included (1: the next tick; firmware,
    /// 0 when none came or elsewhere).
    pub stop_ticks: u32,
    /// The emergency stop is latched.
    pub emergency_stop: bool,
    /// Why the mission was stopped from outside its own logic (abort, e-stop, link lost,
    /// controller overrun, a sensor fault); `None` when it ended by itself.
    pub stop_cause: StopCause,
    /// Time from the receive interrupt that saw the last stop frame to the control step that
    /// put zero volts on the motors, microseconds (firmware, SysTick at 168 MHz; 0 elsewhere).
    pub stop_latency_us: u32,
}

/// The device's mission, as a whole.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RunState {
    /// No mission set up.
    Idle,
    /// Set up, not started.
    Ready,
    /// Running.
    Running,
    /// Paused: the robot holds.
    Paused,
    /// Ended (see the status).
    Ended,
}

/// The robot's pose as the mission believes it (odometry), five times a second.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PoseReport {
    /// Mission time, milliseconds.
    pub t_ms: u32,
    /// Position, metres.
    pub position: PointM,
    /// Heading, radians counter-clockwise from +x.
    pub heading_rad: f32,
    /// Left motor voltage, volts.
    pub left_voltage_v: f32,
    /// Right motor voltage, volts.
    pub right_voltage_v: f32,
    /// Controller periods that overran so far.
    pub controller_overruns: u32,
}

/// Which program answers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Build {
    /// The firmware on a board.
    Hardware,
    /// The firmware under QEMU (`netduinoplus2`, instruction counting).
    Qemu,
    /// The handler running on the host (tests, loopback).
    Host,
}

/// Who the device is and what it can hold ([`Reply::Hello`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DeviceInfo {
    /// The device's [`PROTOCOL_VERSION`].
    pub protocol_version: u16,
    /// Which program this is.
    pub build: Build,
    /// Cells the grid can hold.
    pub grid_capacity_cells: u32,
    /// Cells the planner's scratch memory covers.
    pub planner_capacity_cells: u32,
    /// Obstacle polygons the device can store.
    pub max_polygons: u16,
    /// Obstacle vertices the device can store, all polygons together.
    pub max_vertices: u16,
    /// Largest frame, bytes on the wire.
    pub max_frame_bytes: u16,
    /// Statically allocated RAM of the firmware (`.data` + `.bss` + `.uninit`), bytes; 0 on the
    /// host.
    pub static_ram_bytes: u32,
}

impl DeviceInfo {
    /// The information of a `build` before the handler fills in its capacities: version
    /// [`PROTOCOL_VERSION`], every capacity 0. `const`, so the firmware can put it in a static.
    pub const fn for_build(build: Build) -> Self {
        Self {
            protocol_version: PROTOCOL_VERSION,
            build,
            grid_capacity_cells: 0,
            planner_capacity_cells: 0,
            max_polygons: 0,
            max_vertices: 0,
            max_frame_bytes: 0,
            static_ram_bytes: 0,
        }
    }
}

impl Default for DeviceInfo {
    /// A host-side device: [`DeviceInfo::for_build`] of [`Build::Host`].
    fn default() -> Self {
        Self::for_build(Build::Host)
    }
}

/// The outcome of [`Request::Plan`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlanSummary {
    /// How planning ended.
    pub status: PlanStatus,
    /// Cells expanded.
    pub expanded: u32,
    /// BFS steps or A* cost (see [`crate::plan::PlanReport`]).
    pub cost: u32,
    /// Length of the path, metres.
    pub length_m: f32,
    /// Points in the path (read them with [`Request::ReadPath`]).
    pub points: u16,
    /// Instructions the device spent in the planner (firmware: measured with SysTick; under
    /// QEMU with `-icount shift=0` exactly the instructions executed; 0 on the host).
    pub mcu_instructions: u64,
}

/// State counters of the device ([`Reply::Status`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DeviceStatus {
    /// Map size and robot radius in use.
    pub params: MapParams,
    /// Obstacle polygons stored.
    pub polygons: u16,
    /// Obstacle vertices stored.
    pub vertices: u16,
    /// Vertices of the polygon being uploaded (not yet closed).
    pub pending_vertices: u16,
    /// Occupied cells of the map.
    pub occupied_cells: u32,
    /// Requests answered (errors included).
    pub requests: u32,
    /// Frames that could not be decoded.
    pub frame_errors: u32,
    /// Bytes the receiver had to drop (its queue was full); always 0 unless the firmware's
    /// interrupt could not keep up.
    pub rx_dropped_bytes: u32,
    /// Instructions spent by the last `Plan` request, also when it failed (e.g. a path longer
    /// than the planner's buffer).
    pub last_plan_instructions: u64,
    /// Cells the last search expanded, also when the plan failed afterwards (0 if unknown).
    pub last_plan_expanded: u32,
    /// Largest number of open-list entries the last search used.
    pub last_plan_queue_peak: u32,
    /// Why the chip last reset (firmware on a board; `Unknown` under QEMU and on the host).
    pub reset_cause: ResetCause,
    /// Instructions spent answering the request before this `Status` (any kind: `SetParams`
    /// re-marking every obstacle, the `ObstacleChunk` that closes a polygon, `Plan`, …), as
    /// `last_plan_instructions` measures them (0 on the host). A `Ping` waits at most this long
    /// behind the worst request.
    pub last_request_instructions: u64,
}

/// What the device answers.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Reply {
    /// Handshake accepted.
    Hello(DeviceInfo),
    /// Answer to [`Request::Ping`].
    Pong {
        /// The request's nonce.
        nonce: u32,
    },
    /// Done.
    Ack,
    /// Obstacle upload state after a chunk.
    Obstacles {
        /// Polygons stored.
        polygons: u16,
        /// Vertices stored.
        vertices: u16,
        /// Vertices of the unfinished polygon.
        pending_vertices: u16,
    },
    /// Planning finished.
    Plan(PlanSummary),
    /// Part of the last path.
    PathChunk {
        /// Index of `points[0]`.
        offset: u16,
        /// Points in the whole path.
        total: u16,
        /// The points, metres.
        points: Vec<PointM, PATH_CHUNK_POINTS>,
    },
    /// Part of the packed map.
    MapChunk {
        /// Index of `words[0]`.
        offset_words: u32,
        /// Words in the whole map.
        total_words: u32,
        /// Map width, cells (to unpack the words).
        width_cells: u16,
        /// Map height, cells.
        height_cells: u16,
        /// The words.
        words: Vec<u32, MAP_CHUNK_WORDS>,
    },
    /// Device state.
    Status(DeviceStatus),
    /// The request failed and changed nothing.
    Error(ErrorReply),
    /// The mission's state ([`Request::MissionStatus`]).
    Mission(MissionReport),
    /// A parameter ([`Request::ParamList`], [`Request::ParamGet`], [`Request::ParamSet`]).
    Param(ParamEntry),
    /// A [`Request::ParamSet`] refused by the model: nothing changed.
    ParamRefused(ParamRefusal),
    /// The self-test's rows ([`Request::SelfTestReport`]).
    SelfTest(crate::selftest::SelfTestReport),
}

/// Why a request failed. The variant index is the code on the wire (postcard varint).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ErrorCode {
    /// 0: the frame is not valid COBS or not a length-prefixed byte string.
    BadFrame,
    /// 1: the frame's CRC does not match its contents.
    BadCrc,
    /// 2: the frame was longer than `value` = `limit` = [`MAX_FRAME_BYTES`](super::MAX_FRAME_BYTES).
    FrameTooLong,
    /// 3: the CRC is good but the contents are not a request (unknown variant, short fields).
    BadMessage,
    /// 4: protocol versions differ: `value` = the host's, `limit` = the device's.
    VersionMismatch,
    /// 5: the map size or resolution is refused (`value` = width, `limit` = height, cells).
    BadGeometry,
    /// 6: the map needs `value` cells but the grid holds `limit`.
    GridCapacity,
    /// 7: no room for another polygon (`limit` = polygons the device stores).
    TooManyPolygons,
    /// 8: no room for the vertices: `value` = vertices needed, `limit` = vertices left.
    TooManyVertices,
    /// 9: an obstacle chunk starts at vertex `value` but `limit` were received so far.
    ChunkOutOfOrder,
    /// 10: a number is not finite or out of range (`value` = index of the offending field or
    /// vertex; `Plan`: 1 start, 2 goal).
    BadArgument,
    /// 11: the planner ran out of memory: `value` = what it needed (cells), `limit` = its
    /// capacity (`detail` tells which: 0 scratch, 1 queue, 2 path).
    PlannerCapacity,
    /// 12: a read starts at `value`, beyond the `limit` items there are.
    OutOfRange,
    /// 13: an obstacle chunk closes a polygon that has no vertex.
    EmptyPolygon,
    /// 14: the request is for a simulated build (the real world); this is a board.
    NotOnThisBuild,
    /// 15: not now: `value` is the [`RunState`] index that refuses it (e.g. `SetMission` while
    /// running, `StartMission` without a setup: 0), `detail` 1 when the emergency stop is
    /// latched, 2 when the self-test runs.
    WrongState,
    /// 16: the mission setup is refused: `value` is the index of the offending field of
    /// [`MissionSetup`] (or 100 + the robot config's, see the device log; 100 is the planning
    /// radius of `SetParams`), `detail` 1 when that field (2 start, 4 goal) lies off the map. For the
    /// speed (5), `limit` is the robot's safe speed in mm/s.
    BadMission,
    /// 17: marking the obstacles would visit `value` map rows (stored and new vertices × map
    /// height), more than the `limit` one request may
    /// ([`MAX_MARKING_ROWS`](super::handler::MAX_MARKING_ROWS)): fewer vertices or a lower map.
    MarkingBudget,
    /// 18: no parameter has the name asked for (`value` = the name's length in bytes).
    UnknownParam,
    /// 19: the value was valid but the store could not write it, so nothing changed (`value`:
    /// 0 flash error, 1 store full, 2 damaged store, 3 other).
    StoreFailed,
}

/// An error answer: a code and up to three numbers whose meaning the code documents.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ErrorReply {
    /// What went wrong.
    pub code: ErrorCode,
    /// The offending value (see [`ErrorCode`]).
    pub value: u32,
    /// The limit it broke (see [`ErrorCode`]).
    pub limit: u32,
    /// Extra detail (see [`ErrorCode`]).
    pub detail: u32,
}

impl ErrorReply {
    /// An error with a code and two numbers (`detail` = 0).
    pub const fn new(code: ErrorCode, value: u32, limit: u32) -> Self {
        Self {
            code,
            value,
            limit,
            detail: 0,
        }
    }
}

impl core::fmt::Display for ErrorReply {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let (v, l) = (self.value, self.limit);
        match self.code {
            ErrorCode::BadFrame => write!(f, "the device received a damaged frame (bad COBS)"),
            ErrorCode::BadCrc => write!(f, "the device received a frame with a bad CRC"),
            ErrorCode::FrameTooLong => {
                write!(f, "the device received a frame longer than {l} bytes")
            }
            ErrorCode::BadMessage => write!(f, "the device could not read the request"),
            ErrorCode::VersionMismatch => write!(
                f,
                "protocol version mismatch: host speaks {v}, device speaks {l}"
            ),
            ErrorCode::BadGeometry => write!(f, "map size {v}x{l} cells is refused"),
            ErrorCode::GridCapacity => write!(
                f,
                "the map needs {v} cells but the device's grid holds {l} cells"
            ),
            ErrorCode::TooManyPolygons => {
                write!(
                    f,
                    "too many obstacles: the device stores at most {l} polygons"
                )
            }
            ErrorCode::TooManyVertices => write!(
                f,
                "too many obstacle vertices: {v} needed but only {l} left on the device"
            ),
            ErrorCode::ChunkOutOfOrder => write!(
                f,
                "obstacle chunk out of order: starts at vertex {v}, expected {l}"
            ),
            ErrorCode::BadArgument => write!(f, "argument {v} is not a valid number"),
            ErrorCode::PlannerCapacity => {
                let what = match self.detail {
                    0 => "scratch cells",
                    1 => "queue entries",
                    _ => "path points",
                };
                write!(f, "the planner ran out of {what}: needs {v}, holds {l}")
            }
            ErrorCode::OutOfRange => write!(f, "read from {v} but there are only {l} items"),
            ErrorCode::EmptyPolygon => write!(f, "an obstacle polygon needs at least one vertex"),
            ErrorCode::NotOnThisBuild => {
                write!(f, "the real world is for simulated builds; this is a board")
            }
            ErrorCode::WrongState => {
                if self.detail == 1 {
                    write!(f, "the emergency stop is latched (clear it first)")
                } else if self.detail == 2 {
                    write!(f, "not now: the self-test runs")
                } else {
                    let state = match v {
                        0 => "no mission is set up",
                        1 => "the mission has not started",
                        2 => "a mission is running",
                        3 => "the mission is paused",
                        _ => "the mission has ended",
                    };
                    write!(f, "not now: {state}")
                }
            }
            ErrorCode::BadMission => {
                if self.detail == 1 {
                    let which = match v {
                        2 => "start",
                        4 => "goal",
                        _ => "start or goal",
                    };
                    write!(f, "the mission's {which} lies off the map")
                } else {
                    write!(f, "mission setup field {v} is not a valid value")
                }
            }
            ErrorCode::MarkingBudget => write!(
                f,
                "marking the obstacles would visit {v} map rows (vertices x map height), \
                 more than the {l} one request may: fewer vertices or a lower map"
            ),
            ErrorCode::UnknownParam => write!(f, "the device has no parameter of that name"),
            ErrorCode::StoreFailed => {
                let why = match v {
                    0 => "the flash reported an error",
                    1 => "the store is full",
                    2 => "the store is damaged",
                    _ => "an internal error",
                };
                write!(
                    f,
                    "the device could not store the value ({why}): nothing changed"
                )
            }
        }
    }
}

/// Reports the device sends unasked.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Telemetry {
    /// The firmware has started (sent once after reset).
    Boot {
        /// Its [`PROTOCOL_VERSION`].
        protocol_version: u16,
        /// Why the chip reset (`Unknown` under QEMU).
        reset_cause: ResetCause,
    },
    /// The robot's pose estimate, five times a second while a mission runs.
    Pose(PoseReport),
    /// The device state changed.
    Status(DeviceStatus),
    /// The mission's phase or status changed.
    Phase {
        /// Mission time, milliseconds.
        t_ms: u32,
        /// The new phase.
        phase: MissionPhase,
        /// The status.
        status: MissionStatus,
    },
    /// Hits of a finished sweep (marked on the map grown by the planning radius: the host
    /// marks the same points and has the same map), in chunks.
    SweepHits {
        /// Sweep number, from 1.
        sweep: u32,
        /// Index of `hits[0]`.
        first: u16,
        /// Hits of the sweep.
        total: u16,
        /// The hits, metres.
        hits: Vec<PointM, TELEMETRY_CHUNK_POINTS>,
    },
    /// A plan came back and was applied.
    Planned {
        /// Mission time, milliseconds.
        t_ms: u32,
        /// Plan number, from 1.
        plan: u32,
        /// The planner's verdict.
        status: PlanStatus,
        /// Vertices of the plan.
        path_points: u16,
        /// Vertices of the kept prefix.
        prefix_points: u16,
        /// Instructions the planner took (firmware; 0 elsewhere).
        instructions: u64,
    },
    /// Part of the kept prefix of plan `plan`.
    Prefix {
        /// Plan number.
        plan: u32,
        /// Index of `points[0]`.
        first: u16,
        /// Points of the prefix.
        total: u16,
        /// The points, metres.
        points: Vec<PointM, TELEMETRY_CHUNK_POINTS>,
    },
    /// Part of plan `plan` (its first [`TELEMETRY_PATH_POINTS`] vertices).
    Path {
        /// Plan number.
        plan: u32,
        /// Index of `points[0]`.
        first: u16,
        /// Points sent of the path (at most [`TELEMETRY_PATH_POINTS`]).
        total: u16,
        /// The points, metres.
        points: Vec<PointM, TELEMETRY_CHUNK_POINTS>,
    },
    /// The mission ended.
    Finished(MissionReport),
}
