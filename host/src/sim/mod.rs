//! The simulator behind `twil simulate`: a [`twil_core::mission::Mission`] driven against a
//! [`twil_core::plant::Plant`] (the simulated robot, in the core's [`SimBody`], which the
//! in-process device and the firmware's QEMU build use too) on the real world's polygons.
//!
//! The loop, once per controller period:
//!
//! 1. read the plant's encoder counts and hand their deltas to the mission's
//!    [`LocalRunner`] (the pilot, the mission, the planner with its latency; see its docs),
//!    which answers every sonar request by ray casting from the plant's true pose on the real
//!    polygons (the mission only knows its odometry);
//! 2. apply the pilot's wheel voltages to the plant for one period;
//! 3. record the true pose, the clearance to the real polygons (negative = collision, which
//!    aborts the mission with status `collision`) and, for the pictures, snapshots;
//! 4. with [`run_observed`], show the tick and the new trajectory row to an [`Observer`]
//!    (`--record`, `--live`: messages as the mission goes), which may stop the mission
//!    (Ctrl-C: status `aborted`).
//!
//! **Latency model** (`--plan-latency-ms`, [`SimSetup::plan_latency_s`]): the planner runs at
//! once on the mission's grid (which does not change until the result is back) and its result
//! is kept until its latency has run out. A plan asked for during period `k` is handed back in period
//! `k + ceil(latency / period)`, after that period's controller step, so the new trajectory
//! starts at the tick after. With the default latency of one period (50 ms) the controller
//! holds (or follows the old prefix) for one more tick than without latency: the firmware's
//! worst case, whose planner runs in its lowest-priority task and needs up to 5 M instructions
//! (30 ms at 168 MHz, 40 ms at QEMU's `-icount shift=3` pace), so a plan asked for late in a
//! period misses the next tick. A latency of 0 applies each plan within the step that asked
//! for it (the simulator before the split).
//!
//! Everything is deterministic: the plant's noise generator is seeded, and the mission is pure.

pub mod output;
pub mod pictures;
pub mod reason;
pub mod start;
pub mod worldgen;

use std::ops::ControlFlow;

use anyhow::{bail, Context, Result};
use twil_core::control::Pose;
use twil_core::geom::PointM;
use twil_core::grid::{Grid400, GridGeometry};
use twil_core::mission::{
    HostMissionPlanner, LocalRunner, Mission400, MissionConfig, MissionEvent, MissionMode,
    MissionPhase, MissionStats, MissionStatus, Pilot, SimBody,
};
use twil_core::plan::{PlanStatus, PlannerKind};
use twil_core::robot::RobotConfig;
use twil_core::world::{Obstacles, Params};

use reason::{PlanReason, ReasonTracker, SweepBand};

/// Everything a simulation run needs.
#[derive(Clone, Debug)]
pub struct SimSetup {
    /// The real world: what the simulated sonar sees and what the robot can hit.
    pub real: Obstacles,
    /// Obstacles known a priori (rasterized before the first sweep).
    pub known: Option<Obstacles>,
    /// The mission parameters (.par).
    pub params: Params,
    /// The map geometry.
    pub geometry: GridGeometry,
    /// Stop-and-sweep or continuous.
    pub mode: MissionMode,
    /// Planner.
    pub planner: PlannerKind,
    /// Robot constants (planning radius is taken from `params`).
    pub robot: RobotConfig,
    /// Mission time limit, seconds.
    pub time_limit_s: f32,
    /// Filter sweeps with the regions-of-constant-depth filter.
    pub constant_depth_filter: bool,
    /// Let the prefix go on through space seen free by earlier sweeps.
    pub trust_seen_space: bool,
    /// Map with the evidence map ([`MissionConfig::evidence_map`]).
    pub evidence_map: bool,
    /// Continuous mode: half-width of moving sweeps, degrees.
    pub moving_half_sweep_deg: f32,
    /// Take a picture snapshot every this many seconds of simulated time (0: none).
    pub snapshot_period_s: f32,
    /// How long after its request a plan is handed back, seconds (see the module docs).
    pub plan_latency_s: f32,
    /// How long a stop waits after each prefix.
    pub settle: twil_core::mission::SettleRule,
    /// Feed `τ × velocity` forward into the controller's reference.
    pub reference_feed_forward: bool,
    /// Turn in place at the start of a prefix and at sharp vertices; `false` never does (the
    /// seed: the supplier hands out the time-stamped path points only).
    pub turn_in_place: bool,
    /// The world's name for the pictures' captions (e.g. the real world's file name).
    pub world_name: String,
}

/// How a simulation ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SimStatus {
    /// At the goal.
    Reached,
    /// The map proves the goal unreachable, or the robot could not make progress.
    Unreachable,
    /// The robot's body touched a real obstacle.
    Collision,
    /// The time limit ran out.
    Timeout,
    /// Stopped from outside (`twil mission`: Ctrl-C, an abort from another host); the
    /// simulator itself never ends so.
    Aborted,
}

impl SimStatus {
    /// The lowercase name used in the JSON.
    pub fn name(self) -> &'static str {
        match self {
            SimStatus::Reached => "reached",
            SimStatus::Unreachable => "unreachable",
            SimStatus::Collision => "collision",
            SimStatus::Timeout => "timeout",
            SimStatus::Aborted => "aborted",
        }
    }
}

/// One row of `trajectory.csv`: true pose at a controller period, and what drove the robot
/// there.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TrajectoryRow {
    /// Simulated time, seconds.
    pub t_s: f32,
    /// True pose, world frame.
    pub pose: Pose,
    /// The controller's signals of the period that ended at `t_s` (zero voltages and no
    /// references in the first row).
    pub control: ControlSample,
    /// The mission's phase after that period (`None` where the telemetry has not told it).
    pub phase: Option<MissionPhase>,
}

/// The controller's signals of one period, for the CSV and the `/control` plot. `None`
/// marks a signal the source does not carry (`twil mission` telemetry has the voltages only).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ControlSample {
    /// Reference handed to the controller (where the control point should go), world metres.
    pub reference: Option<PointM>,
    /// The reference model's output (where the control point should be now), world metres.
    pub reference_model: Option<PointM>,
    /// The control point of the odometry pose, world metres.
    pub control_point: Option<PointM>,
    /// Wheel speed references, rad/s (left, right).
    pub speed_ref_rad_s: Option<(f32, f32)>,
    /// Wheel speeds measured from the encoder counts, rad/s (left, right).
    pub speed_rad_s: Option<(f32, f32)>,
    /// Left motor voltage, volts.
    pub left_voltage_v: f32,
    /// Right motor voltage, volts.
    pub right_voltage_v: f32,
}

impl ControlSample {
    /// The signals of the pilot's last tick, with the voltages actually applied.
    pub fn of_pilot(pilot: &Pilot, left_voltage_v: f32, right_voltage_v: f32) -> Self {
        let out = pilot.last_control();
        Self {
            reference: Some(pilot.reference_world()),
            reference_model: Some(pilot.odom_to_world(out.reference_model)),
            control_point: Some(pilot.odom_to_world(out.control_point)),
            speed_ref_rad_s: Some((out.left_speed_ref_rad_s, out.right_speed_ref_rad_s)),
            speed_rad_s: Some((out.left_speed_rad_s, out.right_speed_rad_s)),
            left_voltage_v,
            right_voltage_v,
        }
    }
}

/// What the simulator shows an [`Observer`] after each controller tick.
pub struct TickView<'a> {
    /// Mission time of the tick, seconds.
    pub t_s: f32,
    /// True pose at the tick.
    pub pose: Pose,
    /// The mission after the tick.
    pub mission: &'a Mission400,
    /// What the mission reported during the tick.
    pub events: &'a [MissionEvent],
}

/// Watches a run as it goes (recordings, the live view): called from the simulation thread.
pub trait Observer: Send {
    /// Before the first tick, with the mission set up (its map holds the known obstacles).
    fn start(&mut self, mission: &Mission400);
    /// After every tick; `Break` stops the mission (status [`SimStatus::Aborted`]).
    fn tick(&mut self, view: &TickView) -> ControlFlow<()>;
    /// Every trajectory row, as it is added.
    fn row(&mut self, row: &TrajectoryRow);
}

/// An [`Observer`] that watches nothing.
pub struct NoObserver;

impl Observer for NoObserver {
    fn start(&mut self, _: &Mission400) {}
    fn tick(&mut self, _: &TickView) -> ControlFlow<()> {
        ControlFlow::Continue(())
    }
    fn row(&mut self, _: &TrajectoryRow) {}
}

/// The state of the mission at one instant, for the pictures.
#[derive(Clone, Debug)]
pub struct Snapshot {
    /// Simulated time, seconds.
    pub t_s: f32,
    /// True pose.
    pub pose: Pose,
    /// The robot's map.
    pub grid: Box<Grid400>,
    /// The full plan (empty once the mission ended unreachable).
    pub path: Vec<PointM>,
    /// The kept prefix (empty once the mission ended unreachable).
    pub prefix: Vec<PointM>,
    /// Hits of the latest sweep.
    pub hits: Vec<PointM>,
    /// Rows of the trajectory so far (the trail is `trajectory[..trail_len]`).
    pub trail_len: usize,
    /// Plan number (1 = first plan) when this snapshot was taken at a plan, else 0.
    pub plan_number: u32,
    /// Cells the sonar has seen free, when known (not from a device).
    pub seen: Option<Box<Grid400>>,
    /// Stops so far.
    pub stops: u32,
    /// Plans so far.
    pub plans: u32,
    /// Why the latest plan was made, when known.
    pub reason: Option<PlanReason>,
    /// The band the latest sweep covered, when known.
    pub band: Option<SweepBand>,
}

/// What a simulation produced.
#[derive(Debug)]
pub struct SimResult {
    /// How it ended.
    pub status: SimStatus,
    /// The mission's counters.
    pub stats: MissionStats,
    /// True distance travelled, metres.
    pub distance_m: f32,
    /// Simulated time, seconds.
    pub sim_time_s: f32,
    /// Smallest clearance between the robot's body and a real obstacle, metres.
    pub min_clearance_m: f32,
    /// Sweeps finished (standing and moving).
    pub sweeps: u32,
    /// True pose per controller period.
    pub trajectory: Vec<TrajectoryRow>,
    /// One snapshot per plan.
    pub plans: Vec<Snapshot>,
    /// Snapshots every `snapshot_period_s`, plus the final state.
    pub frames: Vec<Snapshot>,
    /// Final odometry pose, world frame.
    pub final_odometry_pose: Pose,
    /// Length of the plan on the fully known real map from the start (the reference), if
    /// found.
    pub known_map_plan_length_m: Option<f32>,
}

fn snapshot(
    mission: &Mission400,
    reasons: &ReasonTracker,
    t_s: f32,
    pose: Pose,
    trail_len: usize,
    plan_number: u32,
    found: bool,
) -> Snapshot {
    // A mission that ended unreachable, or a plan that found no path (the evidence map then
    // seeks its proof), has no plan: the mission still holds the previous plan's path and
    // prefix, which a picture must not show as if they were followed.
    let has_plan = found && mission.status() != MissionStatus::Unreachable;
    let plan_points = |points: &[PointM]| {
        if has_plan {
            points.to_vec()
        } else {
            Vec::new()
        }
    };
    Snapshot {
        t_s,
        pose,
        grid: Box::new(mission.grid().clone()),
        path: plan_points(mission.path()),
        prefix: plan_points(mission.prefix()),
        hits: mission.last_hits().to_vec(),
        trail_len,
        plan_number,
        seen: Some(Box::new(mission.seen().clone())),
        stops: mission.stats().stops,
        plans: mission.stats().plans,
        reason: reasons.reason(),
        band: reasons.band(),
    }
}

/// Progress reports during a run: simulated time and status text.
pub trait Progress: Send {
    /// Called about once per simulated second.
    fn update(&mut self, sim_time_s: f32, time_limit_s: f32, stats: &MissionStats);
}

/// A [`Progress`] that ignores everything.
pub struct NoProgress;

impl Progress for NoProgress {
    fn update(&mut self, _: f32, _: f32, _: &MissionStats) {}
}

/// Build the mission configuration of a setup.
pub fn mission_config(setup: &SimSetup) -> MissionConfig {
    let mut config = MissionConfig::from_params(&setup.params, setup.robot);
    config.mode = setup.mode;
    config.planner = setup.planner;
    config.time_limit_s = setup.time_limit_s;
    config.constant_depth_filter = setup.constant_depth_filter;
    config.trust_seen_space = setup.trust_seen_space;
    config.evidence_map = setup.evidence_map;
    config.moving_half_sweep_deg = setup.moving_half_sweep_deg;
    config.settle = setup.settle;
    config.reference_feed_forward = setup.reference_feed_forward;
    if !setup.turn_in_place {
        // Direction changes are wrapped to ±π: none is larger.
        config.turn_in_place_above_rad = core::f32::consts::PI;
    }
    config
}

/// Stack for the simulation thread: the mission and the planner are large values (about 1 MB
/// each for the 400 × 400 host size) and are built before they are boxed.
const SIM_STACK_BYTES: usize = 64 << 20;

/// Run a whole mission. Errors are setup errors (bad config, start off the map…); every
/// mission outcome is a [`SimResult`]. Runs on its own thread with a large stack.
pub fn run(setup: &SimSetup, progress: &mut dyn Progress) -> Result<SimResult> {
    run_observed(setup, progress, &mut NoObserver)
}

/// [`run`], showing every tick and trajectory row to `observer` as the mission goes.
pub fn run_observed(
    setup: &SimSetup,
    progress: &mut dyn Progress,
    observer: &mut dyn Observer,
) -> Result<SimResult> {
    std::thread::scope(|scope| {
        std::thread::Builder::new()
            .name("twil-sim".into())
            .stack_size(SIM_STACK_BYTES)
            .spawn_scoped(scope, || run_on_this_thread(setup, progress, observer))
            .map_err(|e| anyhow::anyhow!("cannot start the simulation thread: {e}"))?
            .join()
            .map_err(|_| anyhow::anyhow!("the simulation thread panicked"))?
    })
}

fn run_on_this_thread(
    setup: &SimSetup,
    progress: &mut dyn Progress,
    observer: &mut dyn Observer,
) -> Result<SimResult> {
    let config = mission_config(setup);
    let robot = config.robot;
    let mut mission = Box::new(Mission400::new(config, setup.geometry).context("mission")?);
    if let Some(known) = &setup.known {
        for polygon in known.iter() {
            mission.add_known_polygon(polygon);
        }
    }
    let mut planner = Box::new(HostMissionPlanner::new());
    let start_pose = Pose {
        x_m: setup.params.start.x_m,
        y_m: setup.params.start.y_m,
        heading_rad: config.initial_heading_rad,
    };
    let mut body = SimBody::new(&robot, start_pose);
    let period_s = robot.controller_period_s;
    let latency_ticks = plan_latency_ticks(setup.plan_latency_s, period_s);
    let mut runner = LocalRunner::new(&mut mission, &mut planner, latency_ticks);
    let mut trajectory = Vec::new();
    let mut plans = Vec::new();
    let mut frames = Vec::new();
    let mut t_s = 0.0f32;
    let mut distance_m = 0.0f32;
    let mut min_clearance_m = body.plant().clearance_m(&setup.real);
    let mut collision = min_clearance_m < 0.0;
    let mut next_snapshot_s = 0.0f32;
    let mut next_progress_s = 0.0f32;
    observer.start(runner.mission());
    let first = TrajectoryRow {
        t_s,
        pose: body.plant().pose(),
        control: ControlSample::default(),
        phase: Some(runner.mission().phase()),
    };
    observer.row(&first);
    trajectory.push(first);
    let mut stopped = false;
    let mut sweeps = 0u32;
    // A hard cap on loop iterations in case the mission never returns a final status.
    let max_ticks = ((setup.time_limit_s / period_s) as u64).saturating_add(100);
    let mut ticks = 0u64;
    let debug = std::env::var_os("TWIL_SIM_DEBUG").is_some();
    let mut reasons = ReasonTracker::new(
        setup.mode,
        robot.normal_half_sweep_deg,
        setup.moving_half_sweep_deg,
    );
    while !collision {
        ticks += 1;
        if ticks > max_ticks {
            bail!("the mission did not end within its time limit (internal error)");
        }
        let deltas = body.encoder_deltas();
        let outcome = runner.tick(deltas.0, deltas.1, period_s, &mut |angle| {
            body.sonar_range_m(&setup.real, angle, robot.sonar_range_m)
        });
        reasons.observe(&outcome.events);
        if debug && !outcome.events.is_empty() {
            let m = runner.mission();
            eprintln!("{t_s:8.2} {:?} pose {:?}", outcome.events, m.pose_world());
            eprintln!("         prefix {:?}", m.prefix());
            if let Ok(probe) = std::env::var("TWIL_PROBE") {
                let v: Vec<f32> = probe.split(',').filter_map(|t| t.parse().ok()).collect();
                if v.len() == 2 {
                    eprintln!(
                        "         PROBE {:?}",
                        m.evidence().get(twil_core::geom::PointM::new(v[0], v[1]))
                    );
                }
                if std::env::var_os("TWIL_PROBE_READINGS").is_some() {
                    eprintln!("         READINGS {:?}", m.readings());
                }
            }
            if let Ok(probe) = std::env::var("TWIL_PROBE_BOX") {
                let v: Vec<f32> = probe.split(',').filter_map(|t| t.parse().ok()).collect();
                let swept = outcome
                    .events
                    .iter()
                    .any(|e| matches!(e, MissionEvent::SweepDone { .. }));
                if let ([x0, y0, x1, y1], true) = (v.as_slice(), swept) {
                    eprintln!(
                        "         BOX {}",
                        marked_cells(m.evidence(), (*x0, *y0), (*x1, *y1)).join(" ")
                    );
                }
            }
            if let Some(target) = m.gap_visit_target() {
                eprintln!("         gap visit {} to {target:?}", m.gap_visits());
            }
        }
        if outcome.planned {
            let m = runner.mission();
            plans.push(snapshot(
                m,
                &reasons,
                t_s,
                body.plant().pose(),
                trajectory.len(),
                m.stats().plans,
                // The plan's own status: a plan that found no path draws none.
                !outcome.events.iter().any(|e| {
                    matches!(e, MissionEvent::Planned { status, .. } if *status != PlanStatus::Found)
                }),
            ));
        }
        sweeps += outcome
            .events
            .iter()
            .filter(|e| matches!(e, MissionEvent::SweepDone { .. }))
            .count() as u32;
        let view = TickView {
            t_s,
            pose: body.plant().pose(),
            mission: runner.mission(),
            events: &outcome.events,
        };
        if observer.tick(&view).is_break() {
            stopped = true;
            runner.abort();
            break;
        }
        if outcome.status != MissionStatus::Running {
            break;
        }
        let before = body.plant().pose();
        body.step(period_s, outcome.left_voltage_v, outcome.right_voltage_v);
        t_s += period_s;
        let after = body.plant().pose();
        let d = ((after.x_m - before.x_m).powi(2) + (after.y_m - before.y_m).powi(2)).sqrt();
        if d.is_finite() {
            distance_m += d;
        }
        let row = TrajectoryRow {
            t_s,
            pose: after,
            control: ControlSample::of_pilot(
                runner.pilot(),
                outcome.left_voltage_v,
                outcome.right_voltage_v,
            ),
            phase: Some(runner.mission().phase()),
        };
        observer.row(&row);
        trajectory.push(row);
        let clearance = body.plant().clearance_m(&setup.real);
        if clearance < min_clearance_m {
            min_clearance_m = clearance;
        }
        if clearance < 0.0 {
            collision = true;
            runner.abort();
        }
        if setup.snapshot_period_s > 0.0 && t_s >= next_snapshot_s {
            next_snapshot_s += setup.snapshot_period_s;
            frames.push(snapshot(
                runner.mission(),
                &reasons,
                t_s,
                after,
                trajectory.len(),
                0,
                true,
            ));
        }
        if t_s >= next_progress_s {
            next_progress_s += 1.0;
            progress.update(t_s, setup.time_limit_s, &runner.mission().stats());
        }
    }
    frames.push(snapshot(
        runner.mission(),
        &reasons,
        t_s,
        body.plant().pose(),
        trajectory.len(),
        0,
        true,
    ));
    let mission = runner.mission();
    let status = if collision {
        SimStatus::Collision
    } else if stopped {
        SimStatus::Aborted
    } else {
        match mission.status() {
            MissionStatus::Reached => SimStatus::Reached,
            MissionStatus::Unreachable => SimStatus::Unreachable,
            MissionStatus::Timeout => SimStatus::Timeout,
            MissionStatus::Aborted => {
                bail!(
                    "the mission aborted: planner error {:?}",
                    mission.stats().last_plan_error
                )
            }
            MissionStatus::Running => bail!("the mission stopped while running (internal error)"),
        }
    };
    Ok(SimResult {
        status,
        stats: mission.stats(),
        distance_m,
        sim_time_s: t_s,
        min_clearance_m,
        sweeps,
        trajectory,
        plans,
        frames,
        final_odometry_pose: mission.pose_world(),
        known_map_plan_length_m: known_map_plan_length_m(setup),
    })
}

/// Plan latency in whole control periods (rounded up).
fn plan_latency_ticks(latency_s: f32, period_s: f32) -> u64 {
    let positive = |x: f32| x.is_finite() && x > 0.0;
    if !positive(latency_s) || !positive(period_s) {
        return 0;
    }
    // A few ppm of slack so that 0.05 / 0.05 is one period, not two.
    ((latency_s / period_s) * (1.0 - 1.0e-6)).ceil().min(1.0e9) as u64
}

/// The length of the plan from start to goal on the real world fully known (the yardstick the
/// mission's travelled distance is compared with).
pub fn known_map_plan_length_m(setup: &SimSetup) -> Option<f32> {
    use twil_core::plan::{PathM, Planner};
    let mut grid = Box::new(Grid400::new(setup.geometry).ok()?);
    let half = setup.geometry.expansion_cells(setup.params.robot_radius_m);
    for polygon in setup.real.iter() {
        twil_core::raster::mark_polygon(&mut grid, polygon, half);
    }
    let mut planner: Box<
        Planner<{ twil_core::plan::SCRATCH_WORDS_400 }, { twil_core::mission::HOST_MISSION_QUEUE }>,
    > = Box::new(Planner::new());
    let mut path = Box::new(PathM::new());
    let report = planner
        .plan(
            setup.planner,
            &grid,
            setup.params.start,
            setup.params.goal,
            &mut path,
        )
        .ok()?;
    (report.status == twil_core::plan::PlanStatus::Found).then_some(report.length_m)
}

/// The cells of `evidence` whose centres lie in the box from `lo` to `hi` (metres) and that
/// are marked occupied, as `(x, y)t` (tentative) or `(x, y)C` (confirmed) at their centres
/// (`TWIL_PROBE_BOX`, a debugging aid).
fn marked_cells<const W: usize, const E: usize>(
    evidence: &twil_core::mission::EvidenceMap<W, E>,
    lo: (f32, f32),
    hi: (f32, f32),
) -> Vec<String> {
    use twil_core::mission::CellEvidence;
    let g = *evidence.geometry();
    let res_m = g.resolution_m();
    // Cell indices from `from_m` to `to_m`, kept on the map: the box costs at most the map.
    let cells = |from_m: f32, to_m: f32, count: u16| {
        let last = count as i32 - 1;
        let index = |m: f32| ((m / res_m).floor() as i32).clamp(0, last);
        index(from_m)..=index(to_m)
    };
    let mut marked = Vec::new();
    for y in cells(lo.1, hi.1, g.height()) {
        for x in cells(lo.0, hi.0, g.width()) {
            let tag = match evidence.get_xy(x, y) {
                CellEvidence::Tentative => "t",
                CellEvidence::Confirmed => "C",
                CellEvidence::Unknown | CellEvidence::Free => continue,
            };
            let (cx, cy) = ((x as f32 + 0.5) * res_m, (y as f32 + 0.5) * res_m);
            marked.push(format!("({cx:.3},{cy:.3}){tag}"));
        }
    }
    marked
}
