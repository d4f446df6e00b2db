//! The mission state machine: sweep → mark → plan → prune → (full sweep) → follow → settle → …
//! → reached | unreachable | timeout | aborted (seed 003 §IV.5: the obstacle detector,
//! trajectory generator, trajectory supplier, sonar reader and controller threads, as one
//! sans-IO state machine).
//!
//! ## Shape
//!
//! Two halves, each a plain value with step functions and no I/O:
//!
//! - the [`Pilot`] (`pilot.rs`): odometry, the trajectory supplier and the controller, run
//!   once per 50 ms control period; cheap, and its cost does not depend on the map;
//! - the [`Mission`] (this file): the occupancy grid and the seen space, the sweep in progress,
//!   the full path and the kept prefix; it steers the pilot and asks for sonar readings and
//!   plans. It owns no planner: plans are asked for and handed back.
//!
//! The shell (the firmware, [`LocalRunner`] in `twil simulate` and the tests) calls
//! [`Pilot::tick`] with the encoder counts every period, and [`Mission::step`] with
//!
//! - [`MissionInput::Tick`] with the pilot's [`PilotReport`] of that period; the output may
//!   carry a [`PilotCommand`] (follow the new prefix, hold, stop) and, when the sonar is
//!   sweeping and the sweep's time budget allows, a [`SonarRequest`] (a neck angle);
//! - [`MissionInput::SonarReading`] with the answer to each request; the output may carry the
//!   next request (several readings fit in one period when the echo wait is short);
//! - [`MissionInput::PlanDone`] with the result of a [`PlanRequest`];
//! - [`MissionInput::Abort`] when the shell must stop (e.g. a collision).
//!
//! ## The control period never waits for the planner
//!
//! A plan costs up to 5 M instructions (30 ms at 168 MHz), so the mission does not run it: it
//! asks for it ([`MissionOutput::plan_request`]) and goes on. The shell runs the planner on
//! [`Mission::plan_workspace`] (the grid, and the path buffer the result goes to) at a lower
//! priority than the control period and hands the result back as [`MissionInput::PlanDone`].
//! Meanwhile every tick still runs the controller: standing, the robot holds its place
//! ([`MissionPhase::Plan`]); moving (continuous mode), it goes on along the old prefix, and the
//! new one starts from where the supplier is when the result comes back. Until then the grid
//! and the path do not change: a sweep that ends meanwhile is marked after the result. The
//! firmware runs the planner in its lowest-priority task; `twil simulate` hands the result back
//! after a stated latency (one control period by default, see `docs/simulate.md`).
//!
//! Every output's [`MissionOutput::pilot_command`] goes to the pilot at once (the firmware:
//! before the pilot's next tick). The wheel voltages are the pilot's.
//!
//! Simulated and real time are the same thing here: the mission's clock advances by one
//! controller period per tick, and a sonar reading costs `echo_wait_s + neck_step_time_s` of
//! that budget, so a ±95° sweep of 105 readings takes ≈ 3.8 s of mission time with the default
//! 35 ms echo wait.
//!
//! ## State machine
//!
//! ```text
//!            ┌──────────────────────────────────────────────────────────────┐
//!            v                                                              │
//!  start ─> Sweep (robot held; ±95°, or ±180° when asked)                   │
//!            │ last reading                                                 │
//!            v                                                              │
//!           Mark (filter the sweep, hits -> grid with expansion)            │
//!            v                                                              │
//!           Plan (ask; the shell plans from the current pose) ── no path ──> Unreachable
//!            │ result handed back                                           │
//!            v                                                              │
//!           Prune (prefix within sonar range and visible)                   │
//!            │ a kept point outside the ±95° band and last sweep not full   │
//!            ├──────────────> Sweep (full) ───────────────────────────────> Mark …
//!            v                                                              │
//!           Follow (supplier -> controller, 50 ms)                          │
//!            │ end of trajectory                                            │
//!            v                                                              │
//!           Settle (reference model within 2 %) ── at the goal ──> Reached  │
//!            └──────────────────────────────────────────────────────────────┘
//!  any state: time limit -> Timeout; Abort input -> Aborted;
//!             N plans in a row without moving -> Unreachable (no progress)
//! ```
//!
//! **Stop mode** is exactly the loop above (the seed's stop-and-sweep).
//!
//! **Continuous mode** keeps the sonar sweeping (±95°, alternating direction) while the robot
//! follows the prefix. Each reading is placed in the world with the odometry pose *at that
//! reading*. At the end of every pass the hits are marked and the mission replans from the
//! point the supplier is handing out (so the motion does not restart from rest), prunes, and
//! hands the new prefix to the supplier without stopping. A pass whose new obstacles block the
//! remaining path counts as a *blocked* replan. When the band check fails it does not stop for
//! a full sweep: it follows only the part of the prefix inside the band (at least one cell, so
//! the supplier turns in place towards the path) and the next pass replans. The robot only
//! stops to sweep at the start and when it ran to the end of a prefix short of the goal.
//!
//! ## What the robot trusts
//!
//! - The seed's rule: the prefix within `sonar range − planning radius` along the path and
//!   visible from its first point (the body must stay inside the swept disc, sideways too).
//! - Seen space ([`MissionConfig::trust_seen_space`], on by default): a second bit grid records
//!   every cell a sonar ray crossed before its echo. The prefix may go on while the path
//!   crosses cells whose whole neighbourhood within the planning radius has been seen (within
//!   a cell, for the gaps between rays) or is occupied: no unseen obstacle can be within reach.
//! - The band check (seed `traj_fora_faixa_leit`) looks at the prefix points within sonar range.
//!
//! ## It always ends
//!
//! - The map only ever gains obstacles, so when the planner says the goal is unreachable (or the
//!   goal cell is occupied) on the current map, it stays so: [`MissionStatus::Unreachable`].
//! - [`MissionConfig::max_stalled_plans`] plans in a row from (almost) the same place also end
//!   in [`MissionStatus::Unreachable`] ([`UnreachableReason::NoProgress`]).
//! - [`MissionConfig::time_limit_s`] of mission time: [`MissionStatus::Timeout`].
//!
//! ## Memory
//!
//! No heap. The size is dominated by the two grids (map and seen space, 1 bit per cell each)
//! and two paths of [`MISSION_PATH_POINTS`] points (8 KiB each) plus the supplier's copy:
//! [`Mission300`] fits the MCU's 64 KiB CCM. The planner (4 bits per cell of scratch plus its queue) belongs
//! to the shell ([`MissionPlanner300`], [`HostMissionPlanner`]). [`Mission::SIZE_BYTES`] gives
//! the exact figure for an instantiation; see `docs/simulate.md` for the numbers of
//! [`Mission300`] and [`Mission400`].

use heapless::Vec;

use crate::control::Pose;
use crate::geom::{Cell, PointM};
use crate::grid::{words_for_cells, Grid, GridError, GridGeometry};
use crate::math::{cos, hypot, sin};
use crate::plan::{
    needs_full_sweep, prune_visible_prefix, PlanError, PlanReport, PlanStatus, Planner,
    PlannerKind, SCRATCH_WORDS_300, SCRATCH_WORDS_400,
};
use crate::raster::{mark_point_m, mark_polygon, BresenhamLine};
use crate::robot::RobotConfig;
use crate::sonar::{
    filter_constant_depth, HitBuffer, RcdParams, Reading, SweepBuffer, SweepKind, SweepPlan,
    SWEEP_CAPACITY,
};
use crate::trajectory::{FrameTransform, SupplierConfig, SupplyEvent};
use crate::world::Params;

/// Most readings one sweep can hold: a full ±180° sweep at 1.8° per step (200 steps + 1).
pub const MAX_SWEEP_READINGS: usize = SWEEP_CAPACITY;

/// Most events one [`Mission::step`] can report.
pub const MAX_EVENTS_PER_STEP: usize = 8;

/// Open-list capacity of [`MissionPlanner300`] (entries, 12 bytes each: 36 KiB), as
/// [`crate::plan::Planner300`]: the planner reclaims stale entries, and the bundled worlds
/// need at most 2122 live ones.
pub const MISSION_QUEUE: usize = 3072;

/// Open-list capacity of [`HostMissionPlanner`] (entries).
pub const HOST_MISSION_QUEUE: usize = 65536;

/// Vertices of the mission's plan and of its kept prefix. A path with more vertices (a
/// 300 × 300 maze's needs up to 2 845) ends the mission with [`PlanError::PathFull`]; rooms
/// need a few dozen. 8 KiB per path: the three paths of the mission (plan, prefix, the
/// supplier's copy) must fit the MCU's 64 KiB CCM with the two grids.
pub const MISSION_PATH_POINTS: usize = crate::trajectory::MAX_TRAJECTORY_POINTS;

/// A plan or a prefix of the mission, world metres.
pub type MissionPath = Vec<PointM, MISSION_PATH_POINTS>;

/// A mission on a grid of at most 300 × 300 cells (15 m × 15 m at 0.05 m): the MCU size.
pub type Mission300 = Mission<{ words_for_cells(300 * 300) }>;

/// A mission on a grid of at most 400 × 400 cells (20 m × 20 m at 0.05 m): the host size.
pub type Mission400 = Mission<{ words_for_cells(400 * 400) }>;

/// A planner for the plan requests of a [`Mission300`].
pub type MissionPlanner300 = Planner<SCRATCH_WORDS_300, MISSION_QUEUE>;

/// A planner for the plan requests of a [`Mission400`] (the simulator's).
pub type HostMissionPlanner = Planner<SCRATCH_WORDS_400, HOST_MISSION_QUEUE>;

/// How the robot uses its sonar.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum MissionMode {
    /// Stop, sweep, plan, follow the prefix, settle, repeat (the seed).
    #[default]
    Stop,
    /// Sweep while moving and replan on the fly.
    Continuous,
}

/// Everything a mission needs to know before it starts.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MissionConfig {
    /// Stop-and-sweep or continuous.
    pub mode: MissionMode,
    /// Which planner to run.
    pub planner: PlannerKind,
    /// Robot constants (its `planning_radius_m` grows obstacles, its `sonar_range_m` prunes).
    pub robot: RobotConfig,
    /// Start position, world metres.
    pub start: PointM,
    /// Initial heading, world radians, counter-clockwise from +x.
    pub initial_heading_rad: f32,
    /// Goal position, world metres.
    pub goal: PointM,
    /// Cruise speed along the path, metres per second.
    pub speed_m_s: f32,
    /// Turn rate when turning in place, radians per second.
    pub turn_rate_rad_s: f32,
    /// Direction changes larger than this are done as turns in place, radians.
    pub turn_in_place_above_rad: f32,
    /// Mission time after which it ends in [`MissionStatus::Timeout`], seconds.
    pub time_limit_s: f32,
    /// Reached when the odometry position is this close to the goal (stop mode: checked after
    /// the settle time; continuous mode: every period), metres.
    pub goal_tolerance_m: f32,
    /// Plans in a row that start within [`Self::stall_distance_m`] of the previous plan's start
    /// before the mission gives up as unreachable.
    pub max_stalled_plans: u16,
    /// A plan that starts closer than this to the previous one counts as stalled, metres.
    pub stall_distance_m: f32,
    /// Filter each sweep with the regions-of-constant-depth filter of [`crate::sonar`] (the
    /// seed's); `false` marks every valid reading.
    pub constant_depth_filter: bool,
    /// Also trust the path through space seen free by *earlier* sweeps (see
    /// [`Mission::seen`]); `false` keeps the seed's rule only (within range of the robot and
    /// visible from it).
    pub trust_seen_space: bool,
    /// Longest prefix kept through seen space, measured along the path, metres.
    pub max_trusted_path_m: f32,
    /// Continuous mode: half-width of the sweeps taken while moving, degrees (narrower sweeps
    /// come round to each direction more often).
    pub moving_half_sweep_deg: f32,
    /// How long a stop waits after the end of a prefix (see [`SettleRule`]).
    pub settle: SettleRule,
    /// Add `τ × velocity` to the controller's reference so the first-order reference model
    /// does not lag the path (ours); `false` feeds the path point alone, as the seed did.
    pub reference_feed_forward: bool,
}

impl MissionConfig {
    /// A placeholder for missions that have not been set up ([`Mission::IDLE`]): the default
    /// robot at the origin, facing +x, with the goal there too.
    pub const IDLE: Self = Self {
        mode: MissionMode::Stop,
        planner: PlannerKind::AStar,
        robot: RobotConfig::DEFAULT,
        start: PointM { x_m: 0.0, y_m: 0.0 },
        initial_heading_rad: 0.0,
        goal: PointM { x_m: 0.0, y_m: 0.0 },
        speed_m_s: 0.2,
        turn_rate_rad_s: 0.8,
        turn_in_place_above_rad: core::f32::consts::FRAC_PI_6,
        time_limit_s: 600.0,
        goal_tolerance_m: 0.10,
        max_stalled_plans: 6,
        stall_distance_m: 0.10,
        constant_depth_filter: false,
        trust_seen_space: true,
        max_trusted_path_m: 30.0,
        moving_half_sweep_deg: 95.0,
        settle: SettleRule::ReferenceModel,
        reference_feed_forward: true,
    };

    /// A configuration from a `.par` file's parameters and a robot config (whose planning
    /// radius is replaced by the `.par` radius), stop mode, A*, a 600 s time limit.
    pub fn from_params(params: &Params, robot: RobotConfig) -> Self {
        let robot = robot.with_planning_radius_m(params.robot_radius_m);
        // Every other value is the mission defaults of [`MissionConfig::IDLE`].
        Self {
            robot,
            start: params.start,
            initial_heading_rad: params.initial_heading_deg * (core::f32::consts::PI / 180.0),
            goal: params.goal,
            speed_m_s: params.speed_m_s,
            ..Self::IDLE
        }
    }

    /// Check every value the mission relies on; the error names the field and its value.
    pub fn validate(&self) -> Result<(), MissionError> {
        if let Err(e) = self.robot.validate() {
            return Err(MissionError::Robot(e));
        }
        let positive = [
            ("speed_m_s", self.speed_m_s),
            ("turn_rate_rad_s", self.turn_rate_rad_s),
            ("time_limit_s", self.time_limit_s),
            ("goal_tolerance_m", self.goal_tolerance_m),
        ];
        for (field, value) in positive {
            if !(value.is_finite() && value > 0.0) {
                return Err(MissionError::BadValue { field, value });
            }
        }
        // Beyond these the robot cannot be trusted to stay clear (see `crate::limits`).
        if crate::limits::check_speed_m_s(&self.robot, self.speed_m_s).is_err() {
            return Err(MissionError::BadValue {
                field: "speed_m_s",
                value: self.speed_m_s,
            });
        }
        let radius_m = self.robot.planning_radius_m;
        if crate::limits::check_planning_radius_m(&self.robot, radius_m).is_err() {
            return Err(MissionError::BadValue {
                field: "planning_radius_m",
                value: radius_m,
            });
        }
        let finite = [
            ("start x", self.start.x_m),
            ("start y", self.start.y_m),
            ("goal x", self.goal.x_m),
            ("goal y", self.goal.y_m),
            ("initial_heading_rad", self.initial_heading_rad),
            ("turn_in_place_above_rad", self.turn_in_place_above_rad),
            ("stall_distance_m", self.stall_distance_m),
        ];
        for (field, value) in finite {
            if !value.is_finite() {
                return Err(MissionError::BadValue { field, value });
            }
        }
        Ok(())
    }

    fn supplier_config(&self) -> SupplierConfig {
        SupplierConfig {
            speed_m_s: self.speed_m_s,
            turn_rate_rad_s: self.turn_rate_rad_s,
            turn_in_place_above_rad: self.turn_in_place_above_rad,
            settle_time_s: self.settle.settle_time_s(&self.robot),
        }
    }
}

/// Why a mission could not be set up.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum MissionError {
    /// The robot config is invalid.
    Robot(crate::robot::ConfigError),
    /// A mission value is out of range.
    BadValue {
        /// Field name.
        field: &'static str,
        /// Its value.
        value: f32,
    },
    /// The grid geometry does not fit the mission's grid capacity.
    Grid(GridError),
    /// The start or the goal lies off the map.
    OffMap {
        /// `"start"` or `"goal"`.
        which: &'static str,
    },
}

impl core::fmt::Display for MissionError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            MissionError::Robot(e) => write!(f, "robot config: {e}"),
            MissionError::BadValue { field, value } => write!(f, "{field}: bad value {value}"),
            MissionError::Grid(e) => write!(f, "grid: {e}"),
            MissionError::OffMap { which } => write!(f, "the {which} lies off the map"),
        }
    }
}

/// How the mission stands.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum MissionStatus {
    /// Still going.
    #[default]
    Running,
    /// The robot is at the goal.
    Reached,
    /// The map proves the goal cannot be reached, or the robot cannot make progress.
    Unreachable,
    /// The time limit ran out.
    Timeout,
    /// Stopped from outside ([`MissionInput::Abort`]) or by an internal capacity limit.
    Aborted,
}

impl MissionStatus {
    /// The status as the JSON and the recordings name it: `running`, `reached`,
    /// `unreachable`, `timeout`, `aborted`.
    pub const fn as_str(self) -> &'static str {
        match self {
            MissionStatus::Running => "running",
            MissionStatus::Reached => "reached",
            MissionStatus::Unreachable => "unreachable",
            MissionStatus::Timeout => "timeout",
            MissionStatus::Aborted => "aborted",
        }
    }
}

/// Why the mission ended unreachable.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum UnreachableReason {
    /// Start and goal are not connected on the map.
    NoPath,
    /// The goal cell is occupied on the map.
    GoalBlocked,
    /// Too many plans in a row without moving.
    NoProgress,
}

/// The phase the state machine is in (for displays and logs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum MissionPhase {
    /// Standing, sweeping the sonar.
    Sweep {
        /// `true` for a ±180° sweep.
        full: bool,
    },
    /// Following a prefix (in continuous mode the sonar sweeps meanwhile).
    Follow,
    /// Holding the last point for the settle time.
    Settle,
    /// Standing, waiting for the result of a [`PlanRequest`] (stop mode, and every standing
    /// sweep; while moving the robot goes on following during a plan).
    Plan,
    /// Ended; see [`Mission::status`].
    Done,
}

impl MissionPhase {
    /// The phase as the JSON and the recordings name it: `sweep`, `full sweep`, `follow`,
    /// `settle`, `plan`, `done`.
    pub const fn as_str(self) -> &'static str {
        match self {
            MissionPhase::Sweep { full: true } => "full sweep",
            MissionPhase::Sweep { full: false } => "sweep",
            MissionPhase::Follow => "follow",
            MissionPhase::Settle => "settle",
            MissionPhase::Plan => "plan",
            MissionPhase::Done => "done",
        }
    }
}

/// One input of [`Mission::step`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum MissionInput {
    /// A controller period went by: what the [`Pilot`] did in it.
    Tick(PilotReport),
    /// The answer to the last [`SonarRequest`].
    SonarReading {
        /// Neck angle the reading was taken at, robot frame, radians.
        neck_angle_rad: f32,
        /// Measured range from the sonar, metres, or `None` for no echo.
        range_m: Option<f32>,
    },
    /// The result of the [`PlanRequest`] with this `id`: the planner ran on
    /// [`Mission::plan_workspace`]'s grid and wrote its path there. Results of other ids, or
    /// when no request is out, are ignored.
    PlanDone {
        /// The request's id.
        id: u32,
        /// What the planner returned.
        result: Result<PlanReport, PlanError>,
    },
    /// The robot was held from outside (a pause): stop following, stand, and sweep and plan
    /// afresh from where it is. A plan still out is dropped when it comes back.
    Interrupt,
    /// Stop the mission now ([`MissionStatus::Aborted`]).
    Abort,
}

/// Run the planner and answer with [`MissionInput::PlanDone`] (the mission goes on meanwhile).
///
/// The planner must run on the grid and write into the path of [`Mission::plan_workspace`]:
/// the mission does not change either until the result is handed back (a sweep that ends
/// meanwhile is marked afterwards).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PlanRequest {
    /// Echoed by [`MissionInput::PlanDone`].
    pub id: u32,
    /// Which planner.
    pub kind: PlannerKind,
    /// Where the path starts, world metres (a free cell near the robot).
    pub start: PointM,
    /// The goal, world metres.
    pub goal: PointM,
}

/// Take one sonar reading at this neck angle and answer with [`MissionInput::SonarReading`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SonarRequest {
    /// Neck angle, robot frame (0 = straight ahead, counter-clockwise positive), radians.
    pub neck_angle_rad: f32,
}

/// Something that happened during a step.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum MissionEvent {
    /// A sweep started.
    SweepStarted {
        /// ±180° sweep.
        full: bool,
        /// Taken while moving (continuous mode).
        moving: bool,
    },
    /// A sweep ended and its hits were marked.
    SweepDone {
        /// Hits marked.
        hits: u16,
    },
    /// The planner ran.
    Planned {
        /// Its verdict.
        status: PlanStatus,
        /// Continuous mode: the new obstacles blocked the remaining path.
        blocked: bool,
        /// Points in the kept prefix.
        prefix_points: u16,
    },
    /// The kept prefix leaves the ±95° band: a full sweep comes first.
    FullSweepRequested,
    /// The end of the prefix was handed to the controller.
    EndOfTrajectory,
    /// The settle time after the end went by.
    Settled,
    /// The mission ended.
    Finished(MissionStatus),
}

/// What one [`Mission::step`] asks of the shell.
#[derive(Clone, Debug, PartialEq)]
pub struct MissionOutput {
    /// What the [`Pilot`] must do from now on (the latest command wins; `Stop` once ended).
    pub pilot_command: Option<PilotCommand>,
    /// Take this sonar reading now (before the next tick).
    pub sonar_request: Option<SonarRequest>,
    /// Run the planner (at the lowest priority) and answer with [`MissionInput::PlanDone`].
    pub plan_request: Option<PlanRequest>,
    /// What happened.
    pub events: Vec<MissionEvent, MAX_EVENTS_PER_STEP>,
    /// Status after the step.
    pub status: MissionStatus,
}

/// Counters of a mission.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MissionStats {
    /// Places the robot stood to sweep (the seed's stops): a full sweep where the robot has
    /// just swept standing counts with that stop; `full_sweeps` counts full sweeps.
    pub stops: u32,
    /// Sweeps taken while moving (continuous mode).
    pub moving_sweeps: u32,
    /// Full ±180° sweeps (all standing).
    pub full_sweeps: u32,
    /// Planner runs.
    pub plans: u32,
    /// Planner runs after the first one.
    pub replans: u32,
    /// Continuous mode: replans whose new obstacles blocked the remaining path.
    pub blocked_replans: u32,
    /// Continuous mode: prefixes cut to the swept band instead of stopping for a full sweep.
    pub band_cuts: u32,
    /// Prefixes shortened so that the sonar's blind zone at their end is known (`blind`).
    pub blind_cuts: u32,
    /// Sonar readings taken.
    pub readings: u32,
    /// Hits marked in the grid.
    pub hits: u32,
    /// Distance travelled by the odometry, metres.
    pub odometry_distance_m: f32,
    /// Mission time, seconds.
    pub time_s: f32,
    /// Controller periods that overran.
    pub controller_overruns: u32,
    /// Controller periods with a saturated voltage.
    pub saturated_periods: u32,
    /// Set when the status is [`MissionStatus::Unreachable`].
    pub unreachable_reason: Option<UnreachableReason>,
    /// Planner scratch/queue/path errors met (the mission aborts on them).
    pub plan_errors: u32,
    /// The last planner error, if any.
    #[serde(skip)]
    pub last_plan_error: Option<PlanError>,
}

impl MissionStats {
    /// Every counter 0 (`Default`, usable in `const` contexts).
    pub const ZERO: Self = Self {
        stops: 0,
        moving_sweeps: 0,
        full_sweeps: 0,
        plans: 0,
        replans: 0,
        blocked_replans: 0,
        band_cuts: 0,
        blind_cuts: 0,
        readings: 0,
        hits: 0,
        odometry_distance_m: 0.0,
        time_s: 0.0,
        controller_overruns: 0,
        saturated_periods: 0,
        unreachable_reason: None,
        plan_errors: 0,
        last_plan_error: None,
    };
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct SweepState {
    full: bool,
    moving: bool,
    /// Index of the next reading to request, 0 ..= count.
    next: u16,
    /// Readings in this sweep.
    count: u16,
    /// Sweep from +half to −half instead.
    reversed: bool,
    /// A request is out and not answered yet.
    waiting: bool,
}

/// A plan asked for and not handed back yet.
#[derive(Clone, Copy, Debug, PartialEq)]
struct PendingPlan {
    id: u32,
    /// Continuous mode: the new obstacles blocked the remaining path.
    blocked: bool,
    /// Asked while following (continuous mode).
    moving: bool,
    /// The mission no longer wants the result (a settle ended the moving pass it was for); it
    /// still waits for it before it changes the grid.
    cancelled: bool,
    /// Moving plans: where the robot was when it asked, world metres.
    asked_at: PointM,
    /// Moving plans: farthest the robot was, during the pass that led to this plan, from
    /// `asked_at`, metres (0 standing). See [`Mission::stale_m`].
    pass_spread_m: f32,
}

/// The mission: see the module documentation.
pub struct Mission<const W: usize> {
    config: MissionConfig,
    grid: Grid<W>,
    seen: Grid<W>,
    path: MissionPath,
    prefix: MissionPath,
    frame: FrameTransform,
    expansion_cells: u16,
    readings: SweepBuffer,
    filtered: HitBuffer,
    hits: Vec<PointM, MAX_SWEEP_READINGS>,
    sweep: Option<SweepState>,
    next_sweep_reversed: bool,
    last_sweep_full: bool,
    sonar_budget_s: f32,
    phase: MissionPhase,
    status: MissionStatus,
    stats: MissionStats,
    /// The odometry pose of the latest tick.
    pose_odom: Pose,
    /// Where the supplier stood at the latest tick (odometry frame) and on which segment.
    supply_point_odom: PointM,
    supply_segment: u16,
    last_plan_origin: Option<PointM>,
    stalled_plans: u16,
    /// Where the last standing sweep was taken (world frame).
    last_stop_position: Option<PointM>,
    pending_plan: Option<PendingPlan>,
    /// A sweep that ended while a plan was out: marked when the result is back.
    deferred_sweep_end: Option<SweepState>,
    next_plan_id: u32,
}

impl<const W: usize> Mission<W> {
    /// Size of this mission type in bytes (it is meant to live in a `static` on the MCU).
    pub const SIZE_BYTES: usize = core::mem::size_of::<Self>();

    /// A mission that has ended before it began ([`MissionStatus::Aborted`], phase
    /// [`MissionPhase::Done`]) on the seed's 300 × 300 map, or a one-cell map when the grid
    /// holds less: what a `static` holds until [`Mission::restart`] sets it up in place.
    pub const IDLE: Self = {
        let geometry = match Grid::<W>::new_const(GridGeometry::seed_default()) {
            Ok(_) => GridGeometry::seed_default(),
            Err(_) => match GridGeometry::new(1, 1, crate::grid::DEFAULT_RESOLUTION_M) {
                Ok(g) => g,
                Err(_) => panic!("a 1 x 1 geometry is valid"),
            },
        };
        let grid = match Grid::<W>::new_const(geometry) {
            Ok(g) => g,
            Err(_) => panic!("the grid holds one cell"),
        };
        let seen = match Grid::<W>::new_const(geometry) {
            Ok(g) => g,
            Err(_) => panic!("the grid holds one cell"),
        };
        Self {
            config: MissionConfig::IDLE,
            grid,
            seen,
            path: Vec::new(),
            prefix: Vec::new(),
            frame: FrameTransform::identity(),
            expansion_cells: 0,
            readings: SweepBuffer::new(),
            filtered: HitBuffer::new(),
            hits: Vec::new(),
            sweep: None,
            next_sweep_reversed: false,
            last_sweep_full: false,
            sonar_budget_s: 0.0,
            phase: MissionPhase::Done,
            status: MissionStatus::Aborted,
            stats: MissionStats::ZERO,
            pose_odom: Pose {
                x_m: 0.0,
                y_m: 0.0,
                heading_rad: 0.0,
            },
            supply_point_odom: PointM { x_m: 0.0, y_m: 0.0 },
            supply_segment: 0,
            last_plan_origin: None,
            stalled_plans: 0,
            last_stop_position: None,
            pending_plan: None,
            deferred_sweep_end: None,
            next_plan_id: 1,
        }
    };

    /// A mission on an empty map of `geometry`. Validates the config and checks that the grid
    /// fits the grid capacity and that start and goal are on the map. (The planner that serves
    /// its [`PlanRequest`]s must cover `geometry`'s cells, or the first plan aborts the mission
    /// with [`PlanError::ScratchTooSmall`].)
    ///
    /// The value is large ([`Mission::SIZE_BYTES`]): on the MCU keep one in a `static`
    /// ([`Mission::IDLE`]) and set it up with [`Mission::restart`] instead.
    pub fn new(config: MissionConfig, geometry: GridGeometry) -> Result<Self, MissionError> {
        Self::check(&config, geometry)?;
        let mut mission = Self::IDLE;
        mission.restart(config, geometry)?;
        Ok(mission)
    }

    fn check(config: &MissionConfig, geometry: GridGeometry) -> Result<(), MissionError> {
        config.validate()?;
        if geometry.cell_count() > Grid::<W>::CAPACITY_CELLS {
            return Err(MissionError::Grid(GridError::CapacityExceeded {
                cells: geometry.cell_count() as u32,
                capacity: Grid::<W>::CAPACITY_CELLS as u32,
            }));
        }
        if geometry.cell_of(config.start).is_err() {
            return Err(MissionError::OffMap { which: "start" });
        }
        if geometry.cell_of(config.goal).is_err() {
            return Err(MissionError::OffMap { which: "goal" });
        }
        Ok(())
    }

    /// Set this mission up afresh, in place (no large temporary): an empty map of `geometry`,
    /// the sweep about to start. Checks as [`Mission::new`]; on error nothing changes. A plan
    /// still out for the previous mission is ignored when it comes back (its id is not
    /// reused).
    pub fn restart(
        &mut self,
        config: MissionConfig,
        geometry: GridGeometry,
    ) -> Result<(), MissionError> {
        Self::check(&config, geometry)?;
        self.grid.reset(geometry).map_err(MissionError::Grid)?;
        self.seen.reset(geometry).map_err(MissionError::Grid)?;
        self.expansion_cells = geometry.expansion_cells(config.robot.planning_radius_m);
        self.frame = FrameTransform::new(config.start, config.initial_heading_rad);
        self.config = config;
        self.path.clear();
        self.prefix.clear();
        self.readings.clear();
        self.filtered.clear();
        self.hits.clear();
        self.sweep = None;
        self.next_sweep_reversed = false;
        self.last_sweep_full = false;
        self.sonar_budget_s = 0.0;
        self.phase = MissionPhase::Sweep { full: false };
        self.status = MissionStatus::Running;
        self.stats = MissionStats::ZERO;
        self.pose_odom = Pose::default();
        self.supply_point_odom = PointM::new(0.0, 0.0);
        self.supply_segment = 0;
        self.last_plan_origin = None;
        self.stalled_plans = 0;
        self.last_stop_position = None;
        self.pending_plan = None;
        self.deferred_sweep_end = None;
        self.next_plan_id = self.next_plan_id.wrapping_add(1).max(1);
        Ok(())
    }

    /// What the planner of a [`PlanRequest`] works on: the grid to plan on and the buffer its
    /// path goes to (the mission's [`Mission::path`]). Neither changes until the request's
    /// [`MissionInput::PlanDone`] is handed back.
    pub fn plan_workspace(&mut self) -> (&Grid<W>, &mut MissionPath) {
        (&self.grid, &mut self.path)
    }

    /// `true` while a [`PlanRequest`] has not been answered.
    pub fn plan_pending(&self) -> bool {
        self.pending_plan.is_some()
    }

    /// The map, to change from outside while no mission runs (the link's planning service
    /// keeps its known map here); `None` while one runs.
    pub fn service_map(&mut self) -> Option<&mut Grid<W>> {
        (self.status != MissionStatus::Running).then_some(&mut self.grid)
    }

    /// Mark every occupied cell of `known` (a map of the same geometry, obstacles grown by the
    /// same radius: what the robot knows a priori). Errors, changing nothing, when the
    /// geometries differ.
    pub fn add_known_map<const V: usize>(&mut self, known: &Grid<V>) -> Result<(), GridError> {
        self.grid.merge_from(known)
    }

    /// Rasterize an obstacle known a priori (a closed outline, world metres), grown by the
    /// planning radius. Call before the first step; later calls are allowed (the map only
    /// gains obstacles).
    pub fn add_known_polygon(&mut self, vertices: &[PointM]) {
        mark_polygon(&mut self.grid, vertices, self.expansion_cells);
    }

    /// The configuration.
    pub fn config(&self) -> &MissionConfig {
        &self.config
    }

    /// The map as the robot knows it (obstacles grown by the planning radius).
    pub fn grid(&self) -> &Grid<W> {
        &self.grid
    }

    /// Cells some sonar reading has seen free (set bit = seen): every cell a ray crossed
    /// before its echo (or up to the range without one).
    ///
    /// With [`MissionConfig::trust_seen_space`] the kept prefix may go on beyond the seed's
    /// limit (sonar range, visible from the robot) while the path crosses cells seen free
    /// whose whole neighbourhood within the planning radius has been seen or is occupied, so
    /// no unseen obstacle can lie within reach of the path.
    pub fn seen(&self) -> &Grid<W> {
        &self.seen
    }

    /// The latest full plan, world metres (empty before the first plan).
    pub fn path(&self) -> &[PointM] {
        &self.path
    }

    /// The kept prefix being followed, world metres.
    pub fn prefix(&self) -> &[PointM] {
        &self.prefix
    }

    /// Hits of the latest completed sweep, world metres.
    pub fn last_hits(&self) -> &[PointM] {
        &self.hits
    }

    /// Current status.
    pub fn status(&self) -> MissionStatus {
        self.status
    }

    /// Current phase.
    pub fn phase(&self) -> MissionPhase {
        self.phase
    }

    /// Counters.
    pub fn stats(&self) -> MissionStats {
        self.stats
    }

    /// The robot's pose in the world frame, as the odometry believes it.
    pub fn pose_world(&self) -> Pose {
        self.to_world(self.pose_odom)
    }

    /// Advance the mission by one input; see the module documentation.
    pub fn step(&mut self, input: MissionInput) -> MissionOutput {
        let mut out = MissionOutput {
            pilot_command: None,
            sonar_request: None,
            plan_request: None,
            events: Vec::new(),
            status: self.status,
        };
        if self.status != MissionStatus::Running {
            out.pilot_command = Some(PilotCommand::Stop);
            return out;
        }
        match input {
            MissionInput::Tick(report) => self.on_tick(&report, &mut out),
            MissionInput::SonarReading {
                neck_angle_rad,
                range_m,
            } => self.on_reading(neck_angle_rad, range_m, &mut out),
            MissionInput::PlanDone { id, result } => self.on_plan_done(id, result, &mut out),
            MissionInput::Interrupt => self.interrupt(&mut out),
            MissionInput::Abort => self.finish(MissionStatus::Aborted, &mut out),
        }
        if self.status != MissionStatus::Running {
            out.pilot_command = Some(PilotCommand::Stop);
            out.sonar_request = None;
            out.plan_request = None;
        }
        out.status = self.status;
        out
    }

    fn period_s(&self) -> f32 {
        self.config.robot.controller_period_s
    }

    fn reading_time_s(&self) -> f32 {
        self.config.robot.echo_wait_s + self.config.robot.neck_step_time_s
    }

    fn to_world(&self, pose_odom: Pose) -> Pose {
        pilot::pose_to_world(&self.frame, pose_odom)
    }

    fn position_world(&self) -> PointM {
        let p = self.pose_world();
        PointM::new(p.x_m, p.y_m)
    }

    fn finish(&mut self, status: MissionStatus, out: &mut MissionOutput) {
        self.status = status;
        self.phase = MissionPhase::Done;
        self.sweep = None;
        out.pilot_command = Some(PilotCommand::Stop);
        push(out, MissionEvent::Finished(status));
    }

    fn on_tick(&mut self, report: &PilotReport, out: &mut MissionOutput) {
        self.stats.time_s += self.period_s();
        self.pose_odom = report.pose_odom;
        self.supply_point_odom = report.supply_point_odom;
        self.supply_segment = report.segment;
        if report.overrun {
            self.stats.controller_overruns += 1;
        }
        if report.saturated {
            self.stats.saturated_periods += 1;
        }
        if report.moved_m.is_finite() {
            self.stats.odometry_distance_m += report.moved_m;
        }
        // The supplier's events drive the phases (it only supplies while following or
        // settling; an event of a pass the mission already left is stale).
        if matches!(self.phase, MissionPhase::Follow | MissionPhase::Settle) {
            match report.event {
                Some(SupplyEvent::EndOfTrajectory) => {
                    push(out, MissionEvent::EndOfTrajectory);
                    self.phase = MissionPhase::Settle;
                }
                Some(SupplyEvent::Settled) => {
                    push(out, MissionEvent::Settled);
                    self.on_settled(out);
                }
                None => {}
            }
        }

        if self.status != MissionStatus::Running {
            return;
        }
        // Continuous mode: reached as soon as the robot is within the tolerance of the goal.
        if self.config.mode == MissionMode::Continuous
            && matches!(self.phase, MissionPhase::Follow | MissionPhase::Settle)
            && self.at_goal()
        {
            self.finish(MissionStatus::Reached, out);
            return;
        }
        if self.stats.time_s >= self.config.time_limit_s {
            self.finish(MissionStatus::Timeout, out);
            return;
        }

        // Start a sweep when none runs (and none waits to be marked): standing in the Sweep
        // phase, or moving in continuous mode.
        if self.sweep.is_none() && self.deferred_sweep_end.is_none() {
            match self.phase {
                MissionPhase::Sweep { full } => self.start_sweep(full, false, out),
                MissionPhase::Follow | MissionPhase::Settle
                    if self.config.mode == MissionMode::Continuous =>
                {
                    self.start_sweep(false, true, out)
                }
                _ => {}
            }
        }
        if self.sweep.is_some() {
            self.sonar_budget_s += self.period_s();
            self.request_next(out);
        } else {
            self.sonar_budget_s = 0.0;
        }
    }

    fn interrupt(&mut self, out: &mut MissionOutput) {
        if let Some(pending) = &mut self.pending_plan {
            pending.cancelled = true;
        }
        // A sweep half done was taken from poses the robot has left: start it again.
        self.begin_standing_sweep(false, out);
    }

    fn at_goal(&self) -> bool {
        hypot(
            self.position_world().x_m - self.config.goal.x_m,
            self.position_world().y_m - self.config.goal.y_m,
        ) <= self.config.goal_tolerance_m
    }

    fn on_settled(&mut self, out: &mut MissionOutput) {
        if self.at_goal() {
            self.finish(MissionStatus::Reached, out);
            return;
        }
        // Stand and sweep again. In continuous mode a moving pass may be under way: it is
        // dropped and a standing sweep starts; so is the replan it asked for.
        out.pilot_command = Some(PilotCommand::Hold);
        self.sweep = None;
        if let Some(pending) = &mut self.pending_plan {
            pending.cancelled = true;
        }
        self.phase = MissionPhase::Sweep { full: false };
    }

    fn start_sweep(&mut self, full: bool, moving: bool, out: &mut MissionOutput) {
        let plan = SweepPlan::new(
            &self.sweep_robot(moving),
            if full {
                SweepKind::Full
            } else {
                SweepKind::Normal
            },
        );
        let count = plan.readings().min(MAX_SWEEP_READINGS) as u16;
        self.readings.clear();
        let reversed = self.next_sweep_reversed;
        self.next_sweep_reversed = !reversed;
        self.sweep = Some(SweepState {
            full,
            moving,
            next: 0,
            count,
            reversed,
            waiting: false,
        });
        if moving {
            self.stats.moving_sweeps += 1;
        } else {
            // A stop is a place the robot stood to sweep: a full sweep right where the last
            // standing sweep was (the band or the body corridor asked for it) is the same stop.
            let here = self.position_world();
            let same_place = self.last_stop_position.is_some_and(|p| {
                hypot(here.x_m - p.x_m, here.y_m - p.y_m) < self.config.stall_distance_m
            });
            if !same_place {
                self.stats.stops += 1;
            }
            self.last_stop_position = Some(here);
            if full {
                self.stats.full_sweeps += 1;
            }
        }
        push(out, MissionEvent::SweepStarted { full, moving });
    }

    /// The robot config a sweep is planned with: moving sweeps use
    /// [`MissionConfig::moving_half_sweep_deg`].
    fn sweep_robot(&self, moving: bool) -> RobotConfig {
        let mut robot = self.config.robot;
        if moving {
            robot.normal_half_sweep_deg = self.config.moving_half_sweep_deg;
        }
        robot
    }

    fn sweep_angle_rad(&self, sweep: &SweepState, index: u16) -> f32 {
        let plan = SweepPlan::new(
            &self.sweep_robot(sweep.moving),
            if sweep.full {
                SweepKind::Full
            } else {
                SweepKind::Normal
            },
        );
        let last = sweep.count.saturating_sub(1);
        let i = if sweep.reversed {
            last.saturating_sub(index)
        } else {
            index
        };
        plan.neck_angle_rad(i as usize).unwrap_or(0.0)
    }

    /// Hand out the next reading of the sweep if its time budget allows.
    fn request_next(&mut self, out: &mut MissionOutput) {
        let reading_time = self.reading_time_s();
        let Some(mut sweep) = self.sweep else {
            return;
        };
        if sweep.waiting || sweep.next >= sweep.count || self.sonar_budget_s < reading_time {
            return;
        }
        self.sonar_budget_s -= reading_time;
        let angle = self.sweep_angle_rad(&sweep, sweep.next);
        sweep.waiting = true;
        self.sweep = Some(sweep);
        out.sonar_request = Some(SonarRequest {
            neck_angle_rad: angle,
        });
    }

    fn on_reading(&mut self, neck_angle_rad: f32, range_m: Option<f32>, out: &mut MissionOutput) {
        let Some(mut sweep) = self.sweep else {
            return; // Nobody asked: ignored.
        };
        if !sweep.waiting {
            return;
        }
        sweep.waiting = false;
        sweep.next += 1;
        self.stats.readings += 1;
        let robot = &self.config.robot;
        let range_m = range_m.filter(|r| {
            r.is_finite() && *r >= robot.sonar_min_range_m && *r <= robot.sonar_range_m
        });
        let neck_angle_rad = if neck_angle_rad.is_finite() {
            neck_angle_rad
        } else {
            self.sweep_angle_rad(&sweep, sweep.next - 1)
        };
        let pose = self.pose_world();
        self.mark_seen(pose, neck_angle_rad, range_m);
        // Capacity is the largest sweep: cannot fail.
        let _ = self.readings.push(Reading {
            neck_angle_rad,
            range_m,
            pose,
        });
        self.sweep = Some(sweep);
        if sweep.next >= sweep.count {
            self.sweep = None;
            if self.pending_plan.is_some() {
                // The planner may be reading the grid: mark when its result is back.
                self.deferred_sweep_end = Some(sweep);
            } else {
                self.end_of_sweep(sweep, out);
            }
        } else {
            self.request_next(out);
        }
    }

    /// Mark the cells the ray of one reading crossed as seen, stopping a cell short of the
    /// echo.
    fn mark_seen(&mut self, pose: Pose, neck_angle_rad: f32, range_m: Option<f32>) {
        let robot = &self.config.robot;
        let g = *self.grid.geometry();
        // Silence proves free space a cell short of the range, as an echo a cell short of
        // itself: a surface on the range limit may have been heard on some readings and not
        // on others.
        let length_m = match range_m {
            Some(r) => r - g.resolution_m(),
            None => robot.sonar_range_m - g.resolution_m(),
        };
        let sonar = pose.point_ahead(robot.sonar_offset_m);
        let angle = pose.heading_rad + neck_angle_rad;
        let end = PointM::new(
            sonar.x_m + length_m * cos(angle),
            sonar.y_m + length_m * sin(angle),
        );
        if let Some(centre) = g.cell_xy_of(pose.position()) {
            self.seen.set_xy(centre.0, centre.1, true);
        }
        if length_m.is_nan() || length_m <= 0.0 {
            return;
        }
        // A sonar off the map (a runaway odometry) marks nothing: the ray could be a million
        // cells long.
        if let (Some(a), Some(b)) = (g.cell_xy_of(sonar), g.cell_xy_of(end)) {
            if !g.contains_xy(a.0, a.1) {
                return;
            }
            for (x, y) in BresenhamLine::new(a, b) {
                self.seen.set_xy(x, y, true);
            }
        }
    }

    fn end_of_sweep(&mut self, sweep: SweepState, out: &mut MissionOutput) {
        // Mark.
        let hits = self.mark_readings();
        push(out, MissionEvent::SweepDone { hits });
        self.last_sweep_full = sweep.full;
        if sweep.moving {
            // Continuous: only replan if still following (a settle may have ended the pass).
            if matches!(self.phase, MissionPhase::Follow | MissionPhase::Settle) {
                let blocked = self.remaining_path_blocked();
                if blocked {
                    self.stats.blocked_replans += 1;
                }
                self.plan_and_go(blocked, out);
            }
        } else {
            self.plan_and_go(false, out);
        }
    }

    /// Filter the sweep (regions of constant depth, unless turned off), turn the kept readings
    /// into world points with the pose of each reading, mark them. Returns the hits marked.
    fn mark_readings(&mut self) -> u16 {
        self.hits.clear();
        let mut params = RcdParams::from_config(&self.config.robot);
        if !self.config.constant_depth_filter {
            params.min_pairs = 0;
        }
        filter_constant_depth(&self.readings, &params, &mut self.filtered);
        let offset_m = self.config.robot.sonar_offset_m;
        for hit in self.filtered.iter() {
            let p = hit.world_point(offset_m);
            if !p.is_finite() {
                continue;
            }
            mark_point_m(&mut self.grid, p, self.expansion_cells);
            let _ = self.hits.push(p);
        }
        self.stats.hits += self.hits.len() as u32;
        self.hits.len() as u16
    }

    /// Continuous mode: does an occupied cell lie on what remains of the path?
    fn remaining_path_blocked(&self) -> bool {
        let from = (self.supply_segment as usize).min(self.path.len());
        let g = *self.grid.geometry();
        let Some(rest) = self.path.get(from..) else {
            return false;
        };
        for w in rest.windows(2) {
            let (Some(a), Some(b)) = (g.cell_xy_of(w[0]), g.cell_xy_of(w[1])) else {
                continue;
            };
            if BresenhamLine::new(a, b).any(|(x, y)| self.grid.is_occupied_xy(x, y)) {
                return true;
            }
        }
        false
    }

    /// Ask for a plan from where the robot is (or, moving, from where it is told to be); its
    /// result is handled by [`Self::on_plan_done`].
    fn plan_and_go(&mut self, blocked: bool, out: &mut MissionOutput) {
        let moving = matches!(self.phase, MissionPhase::Follow | MissionPhase::Settle)
            && self.config.mode == MissionMode::Continuous;
        let origin = self.plan_origin(moving);

        // Stall detection.
        match self.last_plan_origin {
            Some(prev)
                if hypot(origin.x_m - prev.x_m, origin.y_m - prev.y_m)
                    < self.config.stall_distance_m =>
            {
                self.stalled_plans = self.stalled_plans.saturating_add(1)
            }
            _ => self.stalled_plans = 0,
        }
        self.last_plan_origin = Some(origin);
        if self.stalled_plans >= self.config.max_stalled_plans {
            self.stats.unreachable_reason = Some(UnreachableReason::NoProgress);
            self.finish(MissionStatus::Unreachable, out);
            return;
        }

        // The planner starts from the nearest free cell (the robot may stand in the expansion
        // of an obstacle it has just seen: the body is smaller than the planning radius).
        let g = *self.grid.geometry();
        let start_point = match g.cell_xy_of(origin) {
            Some((x, y)) => match nearest_free(&self.grid, x, y, self.expansion_cells as i32) {
                Some(c) => g.center_of(c),
                None => origin,
            },
            None => origin,
        };
        self.stats.plans += 1;
        if self.stats.plans > 1 {
            self.stats.replans += 1;
        }
        let id = self.next_plan_id;
        self.next_plan_id = self.next_plan_id.wrapping_add(1).max(1);
        let asked_at = self.position_world();
        let pass_spread_m = if moving {
            self.readings
                .as_slice()
                .iter()
                .map(|r| hypot(r.pose.x_m - asked_at.x_m, r.pose.y_m - asked_at.y_m))
                .filter(|d| d.is_finite())
                .fold(0.0, f32::max)
        } else {
            0.0
        };
        self.pending_plan = Some(PendingPlan {
            id,
            blocked,
            moving,
            cancelled: false,
            asked_at,
            pass_spread_m,
        });
        if !moving {
            // Hold where the controller is heading now until the result is back.
            out.pilot_command = Some(PilotCommand::Hold);
            self.phase = MissionPhase::Plan;
        }
        out.plan_request = Some(PlanRequest {
            id,
            kind: self.config.planner,
            start: start_point,
            goal: self.config.goal,
        });
    }

    /// Where a new trajectory starts: the robot, or while moving the point the supplier hands
    /// out now (the reference model is a little behind it), so motion is continuous.
    fn plan_origin(&self, moving: bool) -> PointM {
        if moving && self.phase == MissionPhase::Follow {
            self.frame.odom_to_world(self.supply_point_odom)
        } else {
            self.position_world()
        }
    }

    /// A plan is back: prune it, then follow, ask for a full sweep, or end. Then mark a sweep
    /// that ended meanwhile.
    fn on_plan_done(
        &mut self,
        id: u32,
        result: Result<PlanReport, PlanError>,
        out: &mut MissionOutput,
    ) {
        let Some(pending) = self.pending_plan else {
            return; // Nobody asked: ignored.
        };
        if pending.id != id {
            return;
        }
        self.pending_plan = None;
        if !pending.cancelled {
            self.apply_plan(pending, result, out);
        }
        if let Some(sweep) = self.deferred_sweep_end.take() {
            if self.status == MissionStatus::Running {
                self.end_of_sweep(sweep, out);
            }
        }
    }

    fn apply_plan(
        &mut self,
        pending: PendingPlan,
        result: Result<PlanReport, PlanError>,
        out: &mut MissionOutput,
    ) {
        let blocked = pending.blocked;
        let moving = pending.moving;
        // The robot went on while the planner ran (moving) or drifted a little (holding): the
        // trajectory starts where it is now.
        let origin = self.plan_origin(moving);
        let g = *self.grid.geometry();
        let report = match result {
            Ok(r) => r,
            Err(e) => {
                self.stats.plan_errors += 1;
                self.stats.last_plan_error = Some(e);
                self.finish(MissionStatus::Aborted, out);
                return;
            }
        };
        match report.status {
            PlanStatus::Found => {}
            PlanStatus::Unreachable => {
                push_planned(out, report.status, blocked, 0);
                self.stats.unreachable_reason = Some(UnreachableReason::NoPath);
                self.finish(MissionStatus::Unreachable, out);
                return;
            }
            PlanStatus::GoalBlocked => {
                push_planned(out, report.status, blocked, 0);
                self.stats.unreachable_reason = Some(UnreachableReason::GoalBlocked);
                self.finish(MissionStatus::Unreachable, out);
                return;
            }
            PlanStatus::StartBlocked => {
                // No free cell near the robot: stand, sweep all round and try again (the stall
                // counter ends this if it never frees up).
                push_planned(out, report.status, blocked, 0);
                self.path.clear();
                self.begin_standing_sweep(true, out);
                return;
            }
            PlanStatus::OutOfBounds => {
                push_planned(out, report.status, blocked, 0);
                self.finish(MissionStatus::Aborted, out);
                return;
            }
        }

        // Prune: keep what the sonar has just seen. The seed's rule looks from the first path
        // vertex; the first steps of a path often go to a neighbouring cell, and seen from the
        // start cell the next segment may graze an obstacle corner (the no-corner-cutting
        // rule) although it is clear from its own first cell. So the prune starts from the
        // last vertex within 1.5 cells of the start, and if that keeps nothing beyond a cell,
        // from each later vertex within 3 cells in turn.
        let res_m = g.resolution_m();
        let first = self.path.first().copied().unwrap_or(origin);
        let from_first = |p: &PointM| hypot(p.x_m - first.x_m, p.y_m - first.y_m);
        let skip = self
            .path
            .iter()
            .take_while(|p| from_first(p) <= 1.5 * res_m)
            .count()
            .saturating_sub(1);
        let last_try = self
            .path
            .iter()
            .take_while(|p| from_first(p) <= 3.0 * res_m)
            .count()
            .saturating_sub(1)
            .max(skip);
        // Each try writes the seed's prefix into `self.prefix`; the seen-space rule is measured
        // first and written over it only when it keeps more (no second path buffer: on the MCU
        // this runs on a task's stack).
        let range_m = (self.prune_range_m() - Self::stale_m(&pending, origin)).max(res_m);
        let cap_m = self.config.max_trusted_path_m;
        for k in skip..=last_try {
            let rest = self.path.get(k..).unwrap_or(&[]);
            let mut pruned_m =
                prune_visible_prefix(&self.grid, rest, range_m, &mut self.prefix).length_m;
            if self.config.trust_seen_space {
                let seen = SeenSpace {
                    grid: &self.grid,
                    seen: &self.seen,
                    expansion_cells: self.expansion_cells as i32,
                };
                let length_m = seen.prune_through_seen::<MISSION_PATH_POINTS>(rest, cap_m, None);
                if length_m > pruned_m + 1.0e-3 {
                    seen.prune_through_seen(rest, cap_m, Some(&mut self.prefix));
                    pruned_m = length_m;
                }
            }
            if pruned_m > res_m {
                break;
            }
        }
        // The trajectory starts where the robot is (or where it is told to be). Path points
        // within a cell of the origin are dropped: a cell centre a few centimetres behind the
        // robot would otherwise make it turn round for nothing.
        let near_m = g.resolution_m();
        let dropped = self
            .prefix
            .iter()
            .take_while(|p| hypot(p.x_m - origin.x_m, p.y_m - origin.y_m) < near_m)
            .count();
        start_with(&mut self.prefix, dropped, origin);
        push_planned(out, report.status, blocked, self.prefix.len() as u16);

        // Band check (seed traj_fora_faixa_leit): a kept point more than the normal half sweep
        // off the heading needs a full sweep first, unless the last sweep was one.
        let pose = self.pose_world();
        // The band is what the sweep actually read: its outermost readings (±93.6° for the
        // ±95° sweep at 1.8° steps), not the nominal half-width, which the stepper never
        // reaches (the 1.4° beyond the last reading were never looked at).
        let band_rad =
            SweepPlan::new(&self.sweep_robot(moving), SweepKind::Normal).covered_half_angle_rad();
        // Only the part within sonar range is the last sweep's business: farther points were
        // trusted through space seen earlier.
        let range_m = self.config.robot.sonar_range_m;
        let near = self
            .prefix
            .iter()
            .take_while(|p| hypot(p.x_m - pose.x_m, p.y_m - pose.y_m) <= range_m)
            .count()
            .max(1);
        // The body is wider than the path: what lies within the planning radius of the near
        // part must be known too (see `corridor`).
        // A pass taken while moving read each bearing from another pose and heading: its band
        // around the heading now proves nothing, only the rays' cells do.
        let trusted_band_rad = if moving { 0.0 } else { band_rad };
        let mut unknown_at_m = if self.last_sweep_full {
            None
        } else {
            self.first_unknown_beside_prefix_m(pose, trusted_band_rad, false)
        };
        let mut path_outside_band = needs_full_sweep(
            self.prefix.get(..near).unwrap_or(&[]),
            PointM::new(pose.x_m, pose.y_m),
            pose.heading_rad,
            band_rad,
        );
        if self.last_sweep_full {
            // A full sweep saw all it could from here. What it could not see beside a known
            // obstacle (its end in the sonar's blind zone, or behind it) may reach further:
            // follow only up to where the body would meet it, when that is a move at all.
            let beside_known = Corridor {
                grid: &self.grid,
                seen: &self.seen,
                pose,
                swept: Swept::NOTHING,
                radius_m: self.config.robot.planning_radius_m,
                body_radius_m: self.config.robot.physical_radius_m(),
                occupied_only: true,
            }
            .first_unknown_m(&self.prefix, range_m);
            if let Some(m) = beside_known.filter(|m| *m > 2.0 * g.resolution_m()) {
                self.truncate_prefix_m(m);
                self.stats.band_cuts += 1;
            }
        } else {
            let continuous = self.config.mode == MissionMode::Continuous;
            if continuous && path_outside_band {
                // Sweeping while moving: instead of stopping for a full sweep, follow only the
                // part inside the band (at least one cell towards the path, which makes the
                // supplier turn in place first); the sonar keeps sweeping around the new
                // heading and the next pass replans. The body corridor is then the cut
                // prefix's (a cut that turns beside an unseen wall end must stop short of it).
                self.cut_prefix_to_band(
                    PointM::new(pose.x_m, pose.y_m),
                    pose.heading_rad,
                    band_rad,
                );
                self.stats.band_cuts += 1;
                path_outside_band = false;
                let length_m = polyline_length_m(&self.prefix);
                unknown_at_m = self
                    .first_unknown_beside_prefix_m(pose, trusted_band_rad, false)
                    .filter(|m| *m < length_m);
            }
            // Continuous mode may follow a prefix cut short; a cut of two cells or less would
            // stall it (the sonar, 0.20 m ahead, never sees beside the centre while moving),
            // so it stops for a full sweep like stop mode.
            let cut_m = unknown_at_m.filter(|m| *m > 2.0 * g.resolution_m());
            if continuous && cut_m.is_some() {
                // Follow only up to where the body would reach unknown space; the sonar keeps
                // sweeping and the next pass replans.
                self.truncate_prefix_m(unknown_at_m.unwrap_or(0.0));
                self.stats.band_cuts += 1;
            } else if path_outside_band || unknown_at_m.is_some() {
                push(out, MissionEvent::FullSweepRequested);
                self.begin_standing_sweep(true, out);
                return;
            }
        }

        // What the sweep read but could not see through (behind an echo, or in the sonar's
        // blind zone) is no business of a full sweep: follow only up to where the body would
        // reach it, when that is a move at all, and look again from there (see `swept`).
        if !self.last_sweep_full {
            let hidden_at_m = self
                .first_unknown_beside_prefix_m(pose, trusted_band_rad, true)
                .filter(|m| *m > 2.0 * res_m);
            if let Some(m) = hidden_at_m {
                self.truncate_prefix_m(m);
                self.stats.band_cuts += 1;
            }
        }

        // Where the prefix ends the sonar reads again, deaf within its minimum range: end it
        // where that zone is known (see `blind`).
        let swept_half_band_rad = if self.last_sweep_full && !moving {
            core::f32::consts::PI
        } else {
            trusted_band_rad
        };
        let blind = BlindZone {
            grid: &self.grid,
            seen: &self.seen,
            pose,
            sonar_offset_m: self.config.robot.sonar_offset_m,
            blind_radius_m: self.config.robot.sonar_min_range_m,
            radius_m: self.config.robot.planning_radius_m,
            body_radius_m: self.config.robot.physical_radius_m(),
            swept: self.swept(pose, swept_half_band_rad, true),
        };
        // A moving pass's prefix is replaced by the next pass's long before its end.
        let blind_cut = if moving {
            None
        } else {
            blind.keep_m(&self.prefix)
        };
        if let Some(m) = blind_cut {
            self.truncate_prefix_m(m);
            self.stats.blind_cuts += 1;
        }

        // Follow (the pilot turns in place first when the prefix starts elsewhere). What the
        // supplier would refuse ends the mission here instead of leaving the robot holding.
        let followable = self.pose_odom.heading_rad.is_finite()
            && self.prefix.len() <= crate::trajectory::MAX_TRAJECTORY_POINTS
            && self.prefix.iter().all(|p| p.is_finite());
        if followable {
            self.phase = MissionPhase::Follow;
            out.pilot_command = Some(PilotCommand::Follow);
        } else {
            self.finish(MissionStatus::Aborted, out);
        }
    }

    /// Keep the first `length_m` of the prefix (cut inside a segment where needed).
    /// How far along the prefix the body may go before it reaches space not known to be free
    /// (see [`Corridor`]), within sonar range of `pose`.
    fn first_unknown_beside_prefix_m(
        &self,
        pose: Pose,
        band_rad: f32,
        echo_limited: bool,
    ) -> Option<f32> {
        Corridor {
            grid: &self.grid,
            seen: &self.seen,
            pose,
            swept: self.swept(pose, band_rad, echo_limited),
            radius_m: self.config.robot.planning_radius_m,
            body_radius_m: self.config.robot.physical_radius_m(),
            occupied_only: false,
        }
        .first_unknown_m(&self.prefix, self.config.robot.sonar_range_m)
    }

    fn truncate_prefix_m(&mut self, length_m: f32) {
        let mut along_m = 0.0;
        for i in 1..self.prefix.len() {
            let (a, b) = (self.prefix[i - 1], self.prefix[i]);
            let len_m = hypot(b.x_m - a.x_m, b.y_m - a.y_m);
            if along_m + len_m > length_m && len_m > 0.0 {
                let t = ((length_m - along_m) / len_m).clamp(0.0, 1.0);
                self.prefix.truncate(i);
                let _ = self.prefix.push(PointM::new(
                    a.x_m + t * (b.x_m - a.x_m),
                    a.y_m + t * (b.y_m - a.y_m),
                ));
                return;
            }
            along_m += len_m;
        }
    }

    /// Keep the prefix up to its last vertex inside the ±`band_rad` band around `heading_rad`
    /// seen from `position`; when the first vertex after the origin is already outside, keep
    /// one cell of the first segment.
    fn cut_prefix_to_band(&mut self, position: PointM, heading_rad: f32, band_rad: f32) {
        let Some(&origin) = self.prefix.first() else {
            return;
        };
        let mut keep = 1;
        for p in self.prefix.iter().skip(1) {
            if needs_full_sweep(&[*p], position, heading_rad, band_rad) {
                break;
            }
            keep += 1;
        }
        if keep >= 2 {
            self.prefix.truncate(keep);
            return;
        }
        let Some(&next) = self.prefix.get(1) else {
            return;
        };
        let d = hypot(next.x_m - origin.x_m, next.y_m - origin.y_m);
        let step_m = self.grid.geometry().resolution_m().min(d);
        self.prefix.truncate(1);
        if d > 0.0 {
            let _ = self.prefix.push(PointM::new(
                origin.x_m + (next.x_m - origin.x_m) * (step_m / d),
                origin.y_m + (next.y_m - origin.y_m) * (step_m / d),
            ));
        }
    }

    /// How far along the path the seed's rule may keep: the sonar range minus the planning
    /// radius. An obstacle just beyond the range is not seen, and the robot's disc must stay
    /// clear of it wherever the path goes, also sideways where the sonar's 0.20 m offset ahead
    /// of the centre does not help: with the full range (the seed's rule; the seed's cell
    /// count came to 1.06 m) the robot drove its body into a wall 3.0 m to its side with a
    /// 3 m sonar. At least one cell.
    /// The last sweep as seen from `pose`, vouching within `half_band_rad` of the heading
    /// (see `swept`).
    fn swept(&self, pose: Pose, half_band_rad: f32, echo_limited: bool) -> Swept<'_> {
        let robot = &self.config.robot;
        Swept {
            readings: self.readings.as_slice(),
            pose,
            sonar_offset_m: robot.sonar_offset_m,
            half_band_rad,
            min_range_m: robot.sonar_min_range_m,
            range_m: robot.sonar_range_m,
            cell_m: self.grid.geometry().resolution_m(),
            echo_limited,
        }
    }

    fn prune_range_m(&self) -> f32 {
        let r = &self.config.robot;
        (r.sonar_range_m - r.planning_radius_m).max(self.grid.geometry().resolution_m())
    }

    /// How far the robot may be from where the readings behind a plan were taken, metres: 0
    /// for a standing sweep; for a moving pass, the farthest reading pose from where the plan
    /// was asked plus how far the trajectory's origin has moved since (triangle inequality).
    /// The seed's prefix rule (within `sonar range − planning radius` of the robot, visible)
    /// assumes the sweep was taken where the prefix starts; a moving pass's readings are up to
    /// `speed × (pass time + plan latency)` behind (0.77 m at 0.2 m/s, 3.8 s passes), so the
    /// rule's distance is shortened by this much. Without it the robot drove into a wall ahead
    /// that the pass had not reached: `worlds/corridor` in continuous mode at 0.25 m/s.
    /// Space seen free (the seen-space rule) stays trusted however old the reading.
    fn stale_m(pending: &PendingPlan, origin: PointM) -> f32 {
        if !pending.moving {
            return 0.0;
        }
        let moved_m = hypot(
            origin.x_m - pending.asked_at.x_m,
            origin.y_m - pending.asked_at.y_m,
        );
        let stale_m = pending.pass_spread_m + moved_m;
        if stale_m.is_finite() {
            stale_m
        } else {
            f32::MAX
        }
    }

    /// Hold the robot and sweep standing.
    fn begin_standing_sweep(&mut self, full: bool, out: &mut MissionOutput) {
        out.pilot_command = Some(PilotCommand::Hold);
        self.sweep = None;
        // Hold where the controller is heading now.
        self.phase = MissionPhase::Sweep { full };
    }
}

/// Length of a polyline, metres.
fn polyline_length_m(points: &[PointM]) -> f32 {
    points
        .windows(2)
        .map(|w| hypot(w[1].x_m - w[0].x_m, w[1].y_m - w[0].y_m))
        .sum()
}

fn push(out: &mut MissionOutput, event: MissionEvent) {
    // Full: the oldest events are kept; the status field still tells the outcome.
    let _ = out.events.push(event);
}

fn push_planned(out: &mut MissionOutput, status: PlanStatus, blocked: bool, prefix_points: u16) {
    push(
        out,
        MissionEvent::Planned {
            status,
            blocked,
            prefix_points,
        },
    );
}

/// Replace the first `dropped` points of `path` by `first` (shifting the rest; when `dropped`
/// is 0 and `path` is full, its last point falls off).
fn start_with<const P: usize>(path: &mut Vec<PointM, P>, dropped: usize, first: PointM) {
    let n = path.len();
    if dropped == 0 {
        if path.push(first).is_err() {
            // Full: drop the last point to make room.
            path.truncate(n.saturating_sub(1));
            let _ = path.push(first);
        }
        // Rotate the new point to the front.
        path.rotate_right(1);
        return;
    }
    // Keep path[dropped..], preceded by `first`.
    path.rotate_left(dropped - 1);
    path.truncate(n - (dropped - 1));
    if let Some(p) = path.first_mut() {
        *p = first;
    }
}

/// The free cell nearest to (`x`, `y`) in growing square rings up to `max_ring`, or `None`.
fn nearest_free<const W: usize>(grid: &Grid<W>, x: i32, y: i32, max_ring: i32) -> Option<Cell> {
    let g = grid.geometry();
    if !grid.is_occupied_xy(x, y) {
        return g.cell_xy(x, y);
    }
    for r in 1..=max_ring.max(1) {
        let mut best: Option<(i32, Cell)> = None;
        for dy in -r..=r {
            for dx in -r..=r {
                if dx.abs() != r && dy.abs() != r {
                    continue;
                }
                let (cx, cy) = (x + dx, y + dy);
                if let Some(c) = g.cell_xy(cx, cy) {
                    if !grid.is_occupied(c) {
                        let d2 = dx * dx + dy * dy;
                        if best.is_none_or(|(b, _)| d2 < b) {
                            best = Some((d2, c));
                        }
                    }
                }
            }
        }
        if let Some((_, c)) = best {
            return Some(c);
        }
    }
    None
}

mod blind;
mod corridor;
mod local;
mod pilot;
mod settle;
mod swept;
#[cfg(test)]
mod tests;
mod trust;

pub use local::{LocalRunner, TickOutcome, MAX_EVENTS_PER_TICK, MAX_READINGS_PER_TICK};
pub use pilot::{Pilot, PilotCommand, PilotReport};
pub use settle::SettleRule;

use blind::BlindZone;
use corridor::Corridor;
use swept::Swept;
use trust::SeenSpace;
pub use trust::SEEN_NEAR_CELLS;
