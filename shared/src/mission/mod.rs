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
//! - the [`Mission`] (`machine.rs`, `sweep.rs`, `planning.rs`, `prefix.rs`): the occupancy
//!   grid and the seen space, the sweep in progress, the full path and the kept prefix; it
//!   steers the pilot and asks for sonar readings and plans. It owns no planner: plans are
//!   asked for and handed back.
//!
//! The shell (the firmware, [`LocalRunner`] in `twil simulate` and the tests, the
//! [`DeviceShell`] of a device without hardware) calls [`Pilot::tick`] with the encoder counts
//! every period, and [`Mission::step`] with
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
//! - [`MissionConfig::max_stalled_plans`] plans in a row from (almost) the same place first
//!   stop the robot for a full standing sweep (plans made from moving or half sweeps can
//!   alternate between two ways round an obstacle, each sweep seeing the side the other hid);
//!   the same again from there ends in [`MissionStatus::Unreachable`]
//!   ([`UnreachableReason::NoProgress`]).
//! - [`MissionConfig::time_limit_s`] of mission time: [`MissionStatus::Timeout`].
//!
//! ## Memory
//!
//! No heap. The size is dominated by the two grids (map and seen space, 1 bit per cell each) and
//! two paths of [`MISSION_PATH_POINTS`] points (8 KiB each) plus the supplier's copy:
//! [`Mission300`] fits the MCU's 64 KiB CCM. The planner (4 bits per cell of scratch plus its
//! queue) belongs to the shell ([`MissionPlanner300`], [`HostMissionPlanner`]).
//! [`Mission::SIZE_BYTES`] gives the exact figure for an instantiation; see `docs/simulate.md` for
//! the numbers of [`Mission300`] and [`Mission400`].
//!
//! ## Files
//!
//! - `config.rs`: [`MissionConfig`], [`MissionMode`], [`MissionError`];
//! - `messages.rs`: the inputs and outputs of [`Mission::step`] and the status and phase;
//! - `stats.rs`: [`MissionStats`];
//! - `machine.rs`: setting up, accessors, [`Mission::step`] and the phase changes;
//! - `sweep.rs`: sweeps and their readings; `planning.rs`: plan requests and results;
//! - `prefix.rs`: how much of a plan is followed, with the rules of `trust.rs` (seen space),
//!   `corridor.rs` (the body beside the path), `swept.rs` (what the sweep saw through) and
//!   `blind.rs` (the sonar's blind zone);
//! - `pilot.rs`, `settle.rs`: the pilot and its settle rule; `local.rs`: [`LocalRunner`].

use heapless::Vec;

use crate::control::Pose;
use crate::geom::PointM;
use crate::grid::{words_for_cells, Grid};
use crate::plan::{Planner, SCRATCH_WORDS_300, SCRATCH_WORDS_400};
use crate::sonar::{SweepBuffer, SWEEP_CAPACITY};
use crate::trajectory::FrameTransform;

/// Most readings one sweep can hold: a full ±180° sweep at 1.8° per step (200 steps + 1).
pub const MAX_SWEEP_READINGS: usize = SWEEP_CAPACITY;

/// Most events one [`Mission::step`] can report.
pub const MAX_EVENTS_PER_STEP: usize = 8;

/// Plans in a row from one place that each went round a new suspect (evidence map, see
/// `prefix`) before they count as stalls. A suspect is grown by the planning radius (a disc
/// 0.8 m across at 0.4 m), so 16 of them can line about 13 m of silent wall beside the robot,
/// more than a 6 m sonar's circle holds.
pub const MAX_SUSPECT_REPLANS: u16 = 16;

/// Open-list capacity of [`MissionPlanner300`] (entries, 12 bytes each: 36 KiB), as
/// [`crate::plan::Planner300`]: the planner reclaims stale entries, and the bundled worlds
/// need at most 2122 live ones.
pub const MISSION_QUEUE: usize = 3072;

/// Open-list capacity of [`HostMissionPlanner`] (entries).
pub const HOST_MISSION_QUEUE: usize = 65536;

/// Vertices of the mission's plan and of its kept prefix. A path with more vertices (a 300 × 300
/// maze's needs up to 2 845) ends the mission with
/// [`PlanError::PathFull`](crate::plan::PlanError::PathFull); rooms need a few dozen. 8 KiB per
/// path: the three paths of the mission (plan, prefix, the supplier's copy) must fit the MCU's
/// 64 KiB CCM with the two grids.
pub const MISSION_PATH_POINTS: usize = crate::trajectory::MAX_TRAJECTORY_POINTS;

/// A plan or a prefix of the mission, world metres.
pub type MissionPath = Vec<PointM, MISSION_PATH_POINTS>;

/// A mission on a grid of at most 300 × 300 cells (15 m × 15 m at 0.05 m): the MCU size,
/// with both planes of the evidence map (11 250 B each).
pub type Mission300 = Mission<{ words_for_cells(300 * 300) }>;

/// A mission on a grid of at most 400 × 400 cells (20 m × 20 m at 0.05 m): the host size.
///
/// With the evidence map's occupied plane (another 20 000 B).
pub type Mission400 = Mission<{ words_for_cells(400 * 400) }>;

/// A planner for the plan requests of a [`Mission300`].
pub type MissionPlanner300 = Planner<SCRATCH_WORDS_300, MISSION_QUEUE>;

/// A planner for the plan requests of a [`Mission400`] (the simulator's).
pub type HostMissionPlanner = Planner<SCRATCH_WORDS_400, HOST_MISSION_QUEUE>;

/// The [`DeviceShell`] of a [`Mission300`] and its [`MissionPlanner300`]: the in-process
/// device's (`twil mission --remote sim`) and the link tests'.
pub type DeviceShell300 = DeviceShell<
    { words_for_cells(300 * 300) },
    { words_for_cells(300 * 300) },
    SCRATCH_WORDS_300,
    MISSION_QUEUE,
>;
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
    /// The evidence map's proof: planned on confirmed marks only (`verdict`).
    proof: bool,
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
pub struct Mission<const W: usize, const E: usize = W> {
    config: MissionConfig,
    grid: Grid<W>,
    /// Free evidence (the "seen" grid) and, with [`MissionConfig::evidence_map`], occupied
    /// evidence (`evidence.rs`).
    evidence: EvidenceMap<W, E>,
    /// Evidence map: cells whose tentative mark a ray took back since the last marking.
    taken_back: evidence_marking::TakeBacks,
    /// Marks known a priori are in the grid (not in the evidence map: never redrawn).
    known_a_priori: bool,
    path: MissionPath,
    prefix: MissionPath,
    frame: FrameTransform,
    expansion_cells: u16,
    readings: SweepBuffer,
    /// Evidence map: the marked cells of the blind disc where the last standing sweep was
    /// read (`swept::BlindCells`).
    blind_cells: swept::BlindCells,
    hits: Vec<PointM, MAX_SWEEP_READINGS>,
    /// Where the sonar stood for the last [`VIEWPOINT_MEMORY`] sweeps that marked
    /// (`evidence_marking::Viewpoints`), and whether this sweep's stands near one of them.
    viewpoints: evidence_marking::Viewpoints,
    /// This sweep's sonar stands within [`planes::MIN_VIEWPOINT_APART_M`] of an earlier one:
    /// its reflectors make marks but confirm none (one viewpoint, one step).
    repeated_viewpoint: bool,
    /// The majority rule's steps of the last standing sweep (`swept::StepTable`), built
    /// once for the cells it vouches for.
    step_table: swept::StepTable,
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
    /// Where a stall was last answered by a full standing sweep (world frame): a second stall
    /// there ends the mission.
    stall_sweep_at: Option<PointM>,
    /// Plans asked in a row from one place because the body corridor met a suspect (see
    /// `prefix`, evidence map): outside the stall count, up to [`MAX_SUSPECT_REPLANS`].
    suspect_replans: u16,
    /// Where the last standing sweep was taken (world frame).
    last_stop_position: Option<PointM>,
    pending_plan: Option<PendingPlan>,
    /// A sweep that ended while a plan was out: marked when the result is back.
    deferred_sweep_end: Option<SweepState>,
    next_plan_id: u32,
    /// Evidence map: the gap visit under way (`verdict`).
    visit: Option<verdict::GapVisit>,
    /// Evidence map: gap visits begun in this mission.
    gap_visits: u16,
    /// Evidence map: the gaps visited so far, drawn into later proof plans (`verdict`).
    visited_gaps: verdict::VisitedGaps,
    /// Evidence map: planes heard by earlier standing sweeps (`planes`).
    planes: planes::Planes,
}
mod blind;
mod config;
mod corridor;
mod device_shell;
mod edge_chains;
mod evidence;
mod evidence_marking;
mod local;
mod machine;
mod messages;
mod pilot;
mod planes;
mod planning;
mod prefix;
mod reflector;
mod settle;
mod stats;
mod sweep;
mod swept;
#[cfg(test)]
mod tests;
mod trust;
mod verdict;

pub use config::{MissionConfig, MissionError, MissionMode};
pub use device_shell::{DeviceShell, SimBody};
pub use evidence::{CellEvidence, Change, EvidenceMap};
pub use evidence_marking::VIEWPOINT_MEMORY;
pub use local::{LocalRunner, TickOutcome, MAX_EVENTS_PER_TICK, MAX_READINGS_PER_TICK};
pub use messages::{
    MissionEvent, MissionInput, MissionOutput, MissionPhase, MissionStatus, PlanRequest,
    SonarRequest, UnreachableReason,
};
pub use pilot::{Pilot, PilotCommand, PilotReport};
pub use settle::SettleRule;
pub use stats::MissionStats;
pub use trust::SEEN_NEAR_CELLS;
pub use verdict::MAX_GAP_VISITS;
