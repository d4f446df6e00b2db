//! The mission's state machine: setting a [`Mission`] up, its accessors, and
//! [`Mission::step`], which dispatches each input to its handler and keeps the phases
//! (sweep → plan → follow → settle → …, see the module documentation).
//!
//! Only the phase changes and the end conditions (goal, time limit, abort, interrupt) live
//! here; what a sweep does is in `sweep`, asking for and applying a plan in `planning`, and
//! how much of a plan is followed in `prefix`.

use heapless::Vec;

use crate::control::Pose;
use crate::geom::PointM;
use crate::grid::{Grid, GridError, GridGeometry};
use crate::math::hypot;
use crate::raster::mark_polygon;
use crate::sonar::SweepBuffer;
use crate::trajectory::{FrameTransform, SupplyEvent};

use super::evidence::EvidenceMap;

use super::messages::push;
use super::verdict::VisitedGaps;
use super::{
    pilot, Mission, MissionConfig, MissionError, MissionEvent, MissionInput, MissionMode,
    MissionOutput, MissionPath, MissionPhase, MissionStats, MissionStatus, PilotCommand,
    PilotReport,
};

impl<const W: usize, const E: usize> Mission<W, E> {
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
        let evidence = match EvidenceMap::<W, E>::new_const(geometry) {
            Ok(m) => m,
            Err(_) => panic!("the grid holds one cell"),
        };
        Self {
            config: MissionConfig::IDLE,
            grid,
            evidence,
            taken_back: Vec::new(),
            known_a_priori: false,
            path: Vec::new(),
            prefix: Vec::new(),
            frame: FrameTransform::identity(),
            expansion_cells: 0,
            readings: SweepBuffer::new(),
            blind_cells: super::swept::BlindCells::NONE,
            hits: Vec::new(),
            viewpoints: heapless::Deque::new(),
            repeated_viewpoint: false,
            step_table: super::swept::StepTable::new(),
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
            stall_sweep_at: None,
            suspect_replans: 0,
            last_stop_position: None,
            pending_plan: None,
            deferred_sweep_end: None,
            next_plan_id: 1,
            visit: None,
            gap_visits: 0,
            visited_gaps: VisitedGaps::new(),
            planes: heapless::Deque::new(),
        }
    };

    /// A mission on an empty map of `geometry`. Validates the config and checks that the grid fits
    /// the grid capacity and that start and goal are on the map. (The planner that serves its
    /// [`PlanRequest`](super::PlanRequest)s must cover `geometry`'s cells, or the first plan aborts
    /// the mission with [`PlanError::ScratchTooSmall`](crate::plan::PlanError::ScratchTooSmall).)
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
        // The evidence map needs its occupied plane: a build without room for it (the MCU's,
        // see `docs/mapping.md`) refuses the option rather than run without it.
        if config.evidence_map
            && geometry.cell_count() > EvidenceMap::<W, E>::OCCUPIED_CAPACITY_CELLS
        {
            return Err(MissionError::Grid(GridError::CapacityExceeded {
                cells: geometry.cell_count() as u32,
                capacity: EvidenceMap::<W, E>::OCCUPIED_CAPACITY_CELLS as u32,
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
        self.evidence.reset(geometry).map_err(MissionError::Grid)?;
        self.taken_back.clear();
        self.known_a_priori = false;
        self.expansion_cells = geometry.expansion_cells(config.robot.planning_radius_m);
        self.frame = FrameTransform::new(config.start, config.initial_heading_rad);
        self.config = config;
        self.path.clear();
        self.prefix.clear();
        self.readings.clear();
        self.blind_cells = super::swept::BlindCells::NONE;
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
        self.stall_sweep_at = None;
        self.suspect_replans = 0;
        self.last_stop_position = None;
        self.pending_plan = None;
        self.deferred_sweep_end = None;
        self.visit = None;
        self.gap_visits = 0;
        self.visited_gaps.clear();
        self.planes.clear();
        self.viewpoints.clear();
        self.repeated_viewpoint = false;
        self.next_plan_id = self.next_plan_id.wrapping_add(1).max(1);
        if config.evidence_map {
            self.assume_body_disc_clear();
        }
        Ok(())
    }

    /// What the planner of a [`PlanRequest`](super::PlanRequest) works on: the grid to plan on and
    /// the buffer its path goes to (the mission's [`Mission::path`]). Neither changes until the
    /// request's [`MissionInput::PlanDone`] is handed back.
    pub fn plan_workspace(&mut self) -> (&Grid<W>, &mut MissionPath) {
        (&self.grid, &mut self.path)
    }

    /// `true` while a [`PlanRequest`](super::PlanRequest) has not been answered.
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
        self.known_a_priori = true;
        self.grid.merge_from(known)
    }

    /// Rasterize an obstacle known a priori (a closed outline, world metres), grown by the
    /// planning radius. Call before the first step; later calls are allowed (the map only
    /// gains obstacles). With the evidence map (and its occupied plane) the outline's cells
    /// are confirmed marks too, so its proofs and take-backs, which redraw the grid from the
    /// marks, keep the obstacle; otherwise a redraw would lose it, and the mission neither
    /// proves nor takes back (before: with `--known` the evidence map's `unreachable` came
    /// from tentative marks, a false one on the office with its walls known).
    pub fn add_known_polygon(&mut self, vertices: &[PointM]) {
        mark_polygon(&mut self.grid, vertices, self.expansion_cells);
        if self.config.evidence_map && self.evidence.has_occupied_plane() {
            self.mark_known_outline(vertices);
        } else {
            self.known_a_priori = true;
        }
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
        self.evidence.free_plane()
    }

    /// The evidence map (its occupied plane is empty without
    /// [`MissionConfig::evidence_map`]).
    pub fn evidence(&self) -> &EvidenceMap<W, E> {
        &self.evidence
    }

    /// The latest full plan, world metres (empty before the first plan).
    pub fn path(&self) -> &[PointM] {
        &self.path
    }

    /// The kept prefix being followed, world metres.
    pub fn prefix(&self) -> &[PointM] {
        &self.prefix
    }

    /// The readings of the sweep under way or, between sweeps, of the last one (for logs).
    pub fn readings(&self) -> &[crate::sonar::Reading] {
        self.readings.as_slice()
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

    pub(super) fn reading_time_s(&self) -> f32 {
        self.config.robot.echo_wait_s + self.config.robot.neck_step_time_s
    }

    fn to_world(&self, pose_odom: Pose) -> Pose {
        pilot::pose_to_world(&self.frame, pose_odom)
    }

    pub(super) fn position_world(&self) -> PointM {
        let p = self.pose_world();
        PointM::new(p.x_m, p.y_m)
    }

    pub(super) fn finish(&mut self, status: MissionStatus, out: &mut MissionOutput) {
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
        // A gap visit is not ended on the way, even in continuous mode: its sweep must stand
        // (the visit's stand-off point ends the path, and `on_settled` ends the visit there).
        // Ended within the tolerance while still moving, the robot rolled 0.2 m on during its
        // "standing" sweep, which then vouched for nothing.
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
                    if self.config.mode == MissionMode::Continuous
                        && !self.settling_at_visit_target() =>
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

    /// Past the end of the path, at a gap visit's stand-off point: the robot waits to be
    /// settled for the visit's standing sweep, with no moving pass or replan to restart it.
    pub(super) fn settling_at_visit_target(&self) -> bool {
        matches!(self.phase, MissionPhase::Settle) && self.at_visit_target()
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
        if self.at_visit_target() {
            self.end_visit(out);
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

    /// Hold the robot and sweep standing.
    pub(super) fn begin_standing_sweep(&mut self, full: bool, out: &mut MissionOutput) {
        out.pilot_command = Some(PilotCommand::Hold);
        self.sweep = None;
        // Hold where the controller is heading now.
        self.phase = MissionPhase::Sweep { full };
    }
}
