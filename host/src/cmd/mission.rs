//! `twil mission`: the device runs the mission; the host uploads it, starts it, follows its
//! telemetry and writes what `twil simulate` writes.
//!
//! ```text
//! twil mission --remote sim --real worlds/office.da --params worlds/office.par --out out/m
//! twil mission --remote qemu --real R.da --params P.par --known K.da --mode continuous --json
//! twil mission --remote /dev/ttyUSB0 --params P.par --known K.da
//! ```
//!
//! The session: `Hello` (same protocol version), `ClearMap`, `SetParams` (the `--size` map at
//! 0.05 m cells, the `.par` radius), the known obstacles (`ObstacleChunk`), on a simulated
//! device the real world (`ClearWorld`, `WorldChunk`), `SetMission`, `StartMission`; then the
//! telemetry until `Finished`. The host rebuilds the robot's map from the known obstacles and
//! the hits of each sweep, marked as the device marks them, for the pictures. Ctrl-C sends
//! `AbortMission` and waits for `Finished` (the device has zeroed the motors by then). See
//! `docs/mission.md`.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use anyhow::{anyhow, bail, Context, Result};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde_json::json;
use twil_core::control::Pose;
use twil_core::failsafe::{LinkLossPolicy, LinkLossReaction, StopCause};
use twil_core::geom::PointM;
use twil_core::grid::{Grid400, GridGeometry, DEFAULT_RESOLUTION_M};
use twil_core::link::{
    Build, DeviceFrame, DeviceInfo, ErrorCode, ErrorReply, MapParams, MissionReport, MissionSetup,
    PoseReport, Reply, Request, Telemetry, PROTOCOL_VERSION,
};
use twil_core::mission::{MissionMode, MissionPhase, MissionStatus};
use twil_core::plant::Plant;
use twil_core::robot::RobotConfig;
use twil_core::world::{Obstacles, Params};

use super::preset::{FollowArgs, LoopArgs};
use super::simulate::{parse_size, read_da, read_par, Mode, SonarArg, SonarArgs};
use crate::record::telemetry::TelemetryRecorder;
use crate::record::{RecordArgs, Recorder};
use crate::remote::{Remote, RemoteSpec};
use crate::sim::{output, ControlSample, SimResult, SimSetup, SimStatus, Snapshot, TrajectoryRow};

/// Arguments of `twil mission`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// The device: `sim` (in this process), `qemu`, `tcp:HOST:PORT` or a serial port.
    #[arg(long, value_name = "DEVICE")]
    pub remote: RemoteSpec,
    /// The mission (.par): radius, speed, initial heading, start, goal.
    #[arg(long, value_name = "P.par")]
    pub params: PathBuf,
    /// Obstacles known before the first sweep (.da).
    #[arg(long, value_name = "K.da")]
    pub known: Option<PathBuf>,
    /// The real world (.da) of a simulated device (`sim`, `qemu`): required there, refused by
    /// a board.
    #[arg(long, value_name = "R.da")]
    pub real: Option<PathBuf>,
    /// Map size in metres, WIDTHxHEIGHT (0.05 m cells).
    #[arg(long, default_value = "15x15", value_name = "WxH")]
    pub size: String,
    /// Stop-and-sweep or continuous sweeping.
    #[arg(long, value_enum, default_value_t = Mode::Stop)]
    pub mode: Mode,
    /// Loop choices: `--preset`, `--planner`, `--rcd`, `--seed-prune`.
    #[command(flatten)]
    pub loop_args: LoopArgs,
    /// Following choices: `--settle`, `--feed-forward`, `--turn-in-place`, `--sweep-readings`
    /// (`SetMission` carries them all to the device).
    #[command(flatten)]
    pub follow: FollowArgs,
    /// Write trajectory.csv, plan PNGs, mission.gif and summary.json here.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Print exactly one JSON object on stdout and nothing else.
    #[arg(long)]
    pub json: bool,
    /// Seed of the simulated sonar noise (simulated devices).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Sonar range, metres (0.26 < range ≤ 6).
    #[arg(long, default_value_t = 1.5)]
    pub sonar_range: f32,
    /// Standard deviation of the simulated sonar noise, metres (simulated devices).
    #[arg(long, default_value_t = 0.0)]
    pub sonar_noise: f32,
    /// The simulated sonar (simulated devices).
    #[command(flatten)]
    pub sonar_model: SonarArgs,
    /// Mission time limit, seconds of mission time [default: the preset's: 900; seed: 1800, its
    /// 18.85 s settles].
    #[arg(long)]
    pub time_limit: Option<f32>,
    /// Give up when the device sends nothing for this many seconds.
    #[arg(long, default_value_t = 10.0, value_name = "S")]
    pub silence: f32,
    /// GIF scale, pixels per cell.
    #[arg(long, default_value_t = 2)]
    pub gif_scale: u32,
    /// `--record FILE.mcap`, `--live [ADDR]`: the telemetry as Foxglove messages.
    #[command(flatten)]
    pub record: RecordArgs,
    /// The device reacts (--on-link-loss) when it hears nothing from the host for this long,
    /// milliseconds: 0 (never) or 200 to 3 600 000. The host sends a heartbeat
    /// (`MissionStatus`) every quarter of it, at most every 500 ms.
    #[arg(long, default_value_t = 2_000, value_name = "MS")]
    pub link_timeout_ms: u32,
    /// What the device does when the link is lost: stop (end the mission, motors at zero, hold)
    /// or continue to the goal.
    #[arg(long, value_enum, default_value_t = LinkLossArg::Stop)]
    pub on_link_loss: LinkLossArg,
}

/// `--on-link-loss`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum LinkLossArg {
    /// End the mission (`aborted`, cause "link lost"), motors at zero.
    Stop,
    /// Go on to the goal.
    Continue,
}

impl Args {
    /// The link-loss policy of `--link-timeout-ms` and `--on-link-loss`.
    pub fn link_loss(&self) -> LinkLossPolicy {
        LinkLossPolicy {
            timeout_ms: self.link_timeout_ms,
            reaction: match self.on_link_loss {
                LinkLossArg::Stop => LinkLossReaction::StopAndHold,
                LinkLossArg::Continue => LinkLossReaction::Continue,
            },
        }
    }
}

/// Time between two heartbeats for a link timeout of `timeout_ms` (0: none): a quarter of it,
/// at most 500 ms, so that three may be lost before the device reacts.
pub fn heartbeat_period(timeout_ms: u32) -> Option<Duration> {
    (timeout_ms > 0).then(|| Duration::from_millis((timeout_ms / 4).min(500) as u64))
}

/// Set by the Ctrl-C handler while a mission runs; the main loop then aborts the mission.
static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// A mission runs: Ctrl-C aborts it (otherwise Ctrl-C ends the tool, exit code 130).
static FOLLOWING: AtomicBool = AtomicBool::new(false);

fn on_ctrl_c() {
    if FOLLOWING.load(Ordering::SeqCst) {
        INTERRUPTED.store(true, Ordering::SeqCst);
    } else {
        eprintln!("twil: interrupted");
        std::process::exit(130);
    }
}

/// What the files give, checked.
pub struct Inputs {
    /// The mission.
    pub params: Params,
    /// Obstacles known before the first sweep.
    pub known: Option<Obstacles>,
    /// The real world of a simulated device.
    pub real: Option<Obstacles>,
    /// The map.
    pub geometry: GridGeometry,
    /// The robot (its body radius measures the clearance).
    pub robot: RobotConfig,
}

/// Read and check the files and numbers of `args` (errors name the file and line, or the
/// option).
pub fn read_inputs(args: &Args) -> Result<Inputs> {
    let params = read_par(&args.params)?;
    let known = args.known.as_deref().map(read_da).transpose()?;
    let real = args.real.as_deref().map(read_da).transpose()?;
    let (w, h) = parse_size(&args.size)?;
    let geometry = GridGeometry::from_size_m(w, h, DEFAULT_RESOLUTION_M)
        .map_err(|e| anyhow!("--size {}: {e}", args.size))?;
    if geometry.cell_count() > 400 * 400 {
        bail!(
            "--size {}: {} x {} cells; at most 400 x 400",
            args.size,
            geometry.width(),
            geometry.height()
        );
    }
    let robot = args
        .sonar_model
        .apply(RobotConfig {
            sonar_range_m: args.sonar_range,
            sonar_noise_std_m: args.sonar_noise,
            noise_seed: args.seed,
            ..RobotConfig::default()
        })
        .with_planning_radius_m(params.robot_radius_m);
    if let Err(e) = robot.validate() {
        bail!("robot config: {e}");
    }
    // The speed and the radius against what this robot (its sonar range) can be trusted
    // with, naming the .par's line.
    crate::world_io::read_par_for(&args.params, &robot)?;
    let time_limit_s = args.time_limit_s();
    if !(time_limit_s.is_finite() && time_limit_s > 0.0) {
        bail!("--time-limit: must be a positive number of seconds, got {time_limit_s}");
    }
    if !(args.silence.is_finite() && args.silence > 0.0 && args.silence <= 3600.0) {
        bail!(
            "--silence: must be between 0 and 3600 seconds, got {}",
            args.silence
        );
    }
    if !args.link_loss().is_valid() {
        bail!(
            "--link-timeout-ms: must be 0 (never) or {} to {} milliseconds, got {}",
            LinkLossPolicy::MIN_TIMEOUT_MS,
            LinkLossPolicy::MAX_TIMEOUT_MS,
            args.link_timeout_ms
        );
    }
    for (which, p) in [("start", params.start), ("goal", params.goal)] {
        if geometry.cell_of(p).is_err() {
            bail!(
                "{}: the {which} ({}, {}) lies off the {} m map",
                args.params.display(),
                p.x_m,
                p.y_m,
                args.size
            );
        }
    }
    Ok(Inputs {
        params,
        known,
        real,
        geometry,
        robot,
    })
}

/// The `SetMission` of `args` and `params`.
impl Args {
    /// The loop choices of this run: `--preset`'s, with the explicit options applied.
    pub fn choices(&self) -> super::preset::LoopChoices {
        self.loop_args.resolve(Some(&self.follow))
    }

    /// `--time-limit`, or the preset's.
    pub fn time_limit_s(&self) -> f32 {
        self.time_limit
            .unwrap_or(self.loop_args.preset.time_limit_s())
    }
}

pub fn mission_setup(args: &Args, params: &Params) -> MissionSetup {
    MissionSetup {
        mode: mission_mode(args.mode),
        planner: args.choices().planner_kind(),
        start: params.start,
        initial_heading_rad: params.initial_heading_deg.to_radians(),
        goal: params.goal,
        speed_m_s: params.speed_m_s,
        sonar_range_m: args.sonar_range,
        time_limit_s: args.time_limit_s(),
        constant_depth_filter: args.choices().rcd,
        trust_seen_space: !args.choices().seed_prune,
        noise_seed: args.seed,
        sonar_noise_std_m: args.sonar_noise,
        link_loss: args.link_loss(),
        sonar_beam: args.sonar_model.sonar == SonarArg::Beam,
        beam_half_angle_deg: args.sonar_model.beam_half_angle,
        incidence_limit_deg: args.sonar_model.incidence_limit,
        settle: args.choices().settle,
        reference_feed_forward: args.choices().reference_feed_forward,
        turn_in_place: args.choices().turn_in_place,
        sweep_layout: args.choices().sweep_layout,
    }
}

fn mission_mode(mode: Mode) -> MissionMode {
    match mode {
        Mode::Stop => MissionMode::Stop,
        Mode::Continuous => MissionMode::Continuous,
    }
}

/// What the device says about a refused `SetMission`, naming the field and where it came from.
fn explain_bad_mission(args: &Args, error: &ErrorReply) -> String {
    if error.code != ErrorCode::BadMission {
        return format!("the device refused the mission: {error}");
    }
    if error.detail == 1 {
        return format!(
            "the device refused the mission: the start or the goal of {} lies off its map",
            args.params.display()
        );
    }
    let par = args.params.display();
    let field = match error.value {
        0 => "mode (--mode)".to_string(),
        1 => "planner (--planner)".to_string(),
        2 => format!("start ({par})"),
        3 => format!("initial heading ({par})"),
        4 => format!("goal ({par})"),
        5 if error.limit > 0 => format!(
            "speed ({par}; the robot's safe speed is at most {:.3} m/s)",
            error.limit as f32 / 1000.0
        ),
        5 => format!("speed ({par})"),
        6 => format!("sonar range (--sonar-range {})", args.sonar_range),
        7 => format!("time limit (--time-limit {})", args.time_limit_s()),
        11 => format!("sonar noise (--sonar-noise {})", args.sonar_noise),
        14 => format!(
            "beam half-angle (--beam-half-angle {})",
            args.sonar_model.beam_half_angle
        ),
        15 => format!(
            "incidence limit (--incidence-limit {})",
            args.sonar_model.incidence_limit
        ),
        12 => format!("link timeout (--link-timeout-ms {})", args.link_timeout_ms),
        100 => format!(
            "planning radius ({par}; at most the sonar range minus {} m)",
            twil_core::limits::MIN_PREFIX_M
        ),
        v if v >= 100 => format!("robot configuration field {} (see the device log)", v - 100),
        v => format!("field {v}"),
    };
    format!("the device refused the mission: its {field} is not a valid value")
}

/// A plan as its telemetry arrives.
struct PlanRecord {
    number: u32,
    t_ms: u32,
    prefix_total: Option<u16>,
    path_total: Option<u16>,
    prefix: Vec<PointM>,
    path: Vec<PointM>,
    pictured: bool,
}

impl PlanRecord {
    fn complete(&self) -> bool {
        matches!(self.prefix_total, Some(n) if self.prefix.len() >= n as usize)
            && matches!(self.path_total, Some(n) if self.path.len() >= n as usize)
    }
}

/// Everything gathered from the telemetry.
pub(super) struct Follower {
    half: u16,
    pictures: bool,
    grid: Box<Grid400>,
    poses: Vec<PoseReport>,
    trajectory: Vec<TrajectoryRow>,
    distance_m: f32,
    phase: Option<MissionPhase>,
    stops: u32,
    sweep: u32,
    hits: Vec<PointM>,
    plan: Option<PlanRecord>,
    plans: u32,
    plan_snapshots: Vec<Snapshot>,
    frames: Vec<Snapshot>,
    next_frame_s: f32,
    pub(super) finished: Option<MissionReport>,
    /// Telemetry chunks that arrived after a gap (a lost chunk before them): the pictured map
    /// and plans miss what was lost (see `mission_link`).
    telemetry_gaps: u32,
    /// Sweeps whose hits have all arrived.
    sweeps: u32,
    /// `--record` / `--live`.
    recorder: Option<TelemetryRecorder>,
    /// Why each plan happened and the band of the latest sweep, read from the device's phase
    /// and sweep reports (see [`Follower::observe_for_reasons`]).
    reasons: crate::sim::reason::ReasonTracker,
    /// Phase changes not yet used to explain a plan: mission time (ms) and phase.
    phases_to_explain: Vec<(u32, MissionPhase)>,
}

/// Seconds between two frames of `mission.gif`.
const FRAME_PERIOD_S: f32 = 0.5;

impl Follower {
    fn new(inputs: &Inputs, pictures: bool) -> Result<Self> {
        let mut grid =
            Box::new(Grid400::new(inputs.geometry).map_err(|e| anyhow!("the map: {e:?}"))?);
        let half = inputs
            .geometry
            .expansion_cells(inputs.params.robot_radius_m);
        if let Some(known) = &inputs.known {
            for polygon in known.iter() {
                twil_core::raster::mark_polygon(&mut grid, polygon, half);
            }
        }
        Ok(Self {
            half,
            pictures,
            grid,
            poses: Vec::new(),
            trajectory: Vec::new(),
            distance_m: 0.0,
            phase: None,
            stops: 0,
            sweep: 0,
            hits: Vec::new(),
            plan: None,
            plans: 0,
            plan_snapshots: Vec::new(),
            frames: Vec::new(),
            next_frame_s: 0.0,
            finished: None,
            telemetry_gaps: 0,
            sweeps: 0,
            recorder: None,
            // Stop mode whatever the mission's: the telemetry does not say whether a moving
            // sweep found the path blocked, so a replan while moving is told as a plain
            // "a sweep ended" rather than guessed (see `observe_for_reasons`).
            reasons: crate::sim::reason::ReasonTracker::new(
                twil_core::mission::MissionMode::Stop,
                inputs.robot.normal_half_sweep_deg,
                95.0,
            ),
            phases_to_explain: Vec::new(),
        })
    }

    /// Record (and/or serve) what arrives from now on.
    fn record_into(&mut self, recorder: Recorder, inputs: &Inputs) {
        let scene = crate::record::topics::WorldScene {
            real: inputs.real.as_ref(),
            known: inputs.known.as_ref(),
            start: inputs.params.start,
            goal: inputs.params.goal,
            body_radius_m: Some(
                (inputs.params.robot_radius_m - twil_core::robot::PLANNING_MARGIN_M).max(0.05),
            ),
        };
        self.recorder = Some(TelemetryRecorder::new(
            recorder,
            &scene,
            &inputs.robot,
            &self.grid,
        ));
    }

    fn pose(&self) -> Pose {
        self.poses.last().map_or(Pose::default(), |p| {
            Pose::new(p.position.x_m, p.position.y_m, p.heading_rad)
        })
    }

    /// The mission time of the latest pose, milliseconds.
    fn t_ms(&self) -> u32 {
        self.poses.last().map_or(0, |p| p.t_ms)
    }

    fn t_s(&self) -> f32 {
        self.poses.last().map_or(0.0, |p| p.t_ms as f32 / 1000.0)
    }

    fn snapshot(&self, t_s: f32, plan_number: u32) -> Snapshot {
        let (path, prefix) = self
            .plan
            .as_ref()
            .map(|p| (p.path.clone(), p.prefix.clone()))
            .unwrap_or_default();
        Snapshot {
            t_s,
            pose: self.pose(),
            grid: self.grid.clone(),
            path,
            prefix,
            hits: self.hits.clone(),
            trail_len: self.trajectory.len(),
            plan_number,
            // The device does not report the space it has seen.
            seen: None,
            stops: self.stops,
            plans: self.plans,
            reason: self.reasons.reason(),
            band: self.reasons.band(),
        }
    }

    /// Tell the reason tracker why the plan reported at `t_ms` happened, from the phases the
    /// device reported before it, as the mission events they stand for: a standing sweep starts
    /// a sweep (a full one after the first plan was asked for because the prefix left the
    /// band), settling means the prefix ended, and no standing sweep since the last plan means
    /// a sweep taken while moving. Phases stamped at `t_ms` or later are this plan's
    /// consequences (the device sends a phase change before the plan that caused it), so
    /// they wait for the next plan.
    fn explain_plan(&mut self, t_ms: u32, status: twil_core::plan::PlanStatus) {
        let first = self.reasons.reason().is_none();
        let events = crate::sim::reason::events_before_plan(
            &mut self.phases_to_explain,
            t_ms,
            status,
            first,
        );
        self.reasons.observe(&events);
    }

    /// Picture the current plan once it has all arrived (or will get no more).
    fn picture_plan(&mut self, force: bool) {
        let ready = match &self.plan {
            Some(p) => !p.pictured && (force || p.complete()),
            None => false,
        };
        if !ready {
            return;
        }
        if self.pictures {
            let (number, t_ms) = self.plan.as_ref().map_or((0, 0), |p| (p.number, p.t_ms));
            let snap = self.snapshot(t_ms as f32 / 1000.0, number);
            self.plan_snapshots.push(snap);
        }
        if let (Some(p), Some(r)) = (&self.plan, &mut self.recorder) {
            r.plan(p.t_ms as f32 / 1000.0, &p.path, &p.prefix);
        }
        if let Some(p) = &mut self.plan {
            p.pictured = true;
        }
    }

    pub(super) fn absorb(&mut self, telemetry: Telemetry) {
        match telemetry {
            Telemetry::Pose(report) => {
                if let Some(last) = self.poses.last() {
                    let d = ((report.position.x_m - last.position.x_m).powi(2)
                        + (report.position.y_m - last.position.y_m).powi(2))
                    .sqrt();
                    if d.is_finite() {
                        self.distance_m += d;
                    }
                }
                self.poses.push(report);
                let row = TrajectoryRow {
                    t_s: report.t_ms as f32 / 1000.0,
                    pose: self.pose(),
                    control: ControlSample {
                        left_voltage_v: report.left_voltage_v,
                        right_voltage_v: report.right_voltage_v,
                        ..ControlSample::default()
                    },
                    phase: self.phase,
                };
                if let Some(r) = &mut self.recorder {
                    r.pose(&row);
                }
                self.trajectory.push(row);
                let t_s = self.t_s();
                if self.pictures && t_s >= self.next_frame_s {
                    self.next_frame_s = t_s + FRAME_PERIOD_S;
                    let snap = self.snapshot(t_s, 0);
                    self.frames.push(snap);
                }
            }
            Telemetry::Phase {
                t_ms,
                phase,
                status,
            } => {
                if matches!(phase, MissionPhase::Sweep { .. }) && self.phase != Some(phase) {
                    self.stops += 1;
                }
                // Bounded: a device that never plans cannot grow it past a few minutes' worth.
                if self.phases_to_explain.len() >= 4096 {
                    self.phases_to_explain.remove(0);
                }
                self.phases_to_explain.push((t_ms, phase));
                self.phase = Some(phase);
                let (pose, counts) = (self.pose(), (self.plans, self.stops));
                if let Some(r) = &mut self.recorder {
                    r.phase(t_ms as f32 / 1000.0, phase, status, &pose, counts);
                }
            }
            Telemetry::SweepHits {
                sweep,
                first,
                total,
                hits,
            } => {
                if sweep != self.sweep || first == 0 {
                    self.sweep = sweep;
                    self.hits.clear();
                }
                if first as usize != self.hits.len() {
                    self.telemetry_gaps += 1;
                }
                for p in &hits {
                    twil_core::raster::mark_point_m(&mut self.grid, *p, self.half);
                }
                self.hits.extend_from_slice(&hits);
                if self.hits.len() == total as usize {
                    self.sweeps += 1;
                    let t_s = self.t_s();
                    if let Some(r) = &mut self.recorder {
                        r.sweep(t_s, &self.hits, &self.grid);
                    }
                }
            }
            Telemetry::Planned {
                t_ms, plan, status, ..
            } => {
                self.picture_plan(true);
                self.explain_plan(t_ms, status);
                self.plans = self.plans.max(plan);
                self.plan = Some(PlanRecord {
                    number: plan,
                    t_ms,
                    prefix_total: None,
                    path_total: None,
                    prefix: Vec::new(),
                    path: Vec::new(),
                    pictured: false,
                });
            }
            Telemetry::Prefix {
                plan,
                first,
                total,
                points,
            } => {
                if let Some(p) = self.plan.as_mut().filter(|p| p.number == plan) {
                    if !append_chunk(&mut p.prefix, &mut p.prefix_total, first, total, &points) {
                        self.telemetry_gaps += 1;
                    }
                }
                self.picture_plan(false);
            }
            Telemetry::Path {
                plan,
                first,
                total,
                points,
            } => {
                if let Some(p) = self.plan.as_mut().filter(|p| p.number == plan) {
                    if !append_chunk(&mut p.path, &mut p.path_total, first, total, &points) {
                        self.telemetry_gaps += 1;
                    }
                }
                self.picture_plan(false);
            }
            Telemetry::Finished(report) => {
                self.picture_plan(true);
                if report.status == MissionStatus::Unreachable {
                    // No plan any more (a stalled mission sends no last `Planned`): the final
                    // frame must not draw the previous plan as if it were followed.
                    if let Some(p) = &mut self.plan {
                        p.path.clear();
                        p.prefix.clear();
                    }
                }
                if self.pictures {
                    let snap = self.snapshot(report.stats.time_s, 0);
                    self.frames.push(snap);
                }
                if let Some(r) = &mut self.recorder {
                    r.finished(&report);
                }
                self.finished = Some(report);
            }
            Telemetry::Boot { .. } | Telemetry::Status(_) => {}
        }
    }

    /// One line for the live display.
    fn status_line(&self) -> String {
        let pose = self.pose();
        format!(
            "t {:6.1} s  {:<10}  x {:6.2} y {:6.2} heading {:4.0}°  stops {:3}  {:6.2} m",
            self.t_s(),
            self.phase.map_or("starting", MissionPhase::as_str),
            pose.x_m,
            pose.y_m,
            pose.heading_rad.to_degrees(),
            self.stops,
            self.distance_m
        )
    }
}

/// A short name of a phase.
/// Append a `Prefix` / `Path` chunk that starts at point `first` to `points` and note the
/// total; `false` (nothing appended) when an earlier chunk was lost.
fn append_chunk(
    points: &mut Vec<PointM>,
    total_points: &mut Option<u16>,
    first: u16,
    total: u16,
    chunk: &[PointM],
) -> bool {
    *total_points = Some(total);
    if first as usize != points.len() {
        return false;
    }
    points.extend_from_slice(chunk);
    true
}

/// The JSON name of a stop cause.
pub fn stop_cause_name(cause: StopCause) -> Option<&'static str> {
    match cause {
        StopCause::None => None,
        StopCause::Host => Some("host"),
        StopCause::EmergencyStop => Some("emergency_stop"),
        StopCause::LinkLost => Some("link_lost"),
        StopCause::ControllerOverrun => Some("controller_overrun"),
    }
}

fn round3(x: f32) -> f64 {
    ((x as f64) * 1000.0).round() / 1000.0
}

/// The outcome of a mission as the host saw it.
pub struct Outcome {
    /// The device's final report.
    pub report: MissionReport,
    /// Who answered.
    pub info: DeviceInfo,
    /// Distance along the reported poses, metres.
    pub distance_m: f32,
    /// Smallest clearance of the robot's body to the real polygons along the reported poses
    /// (`None` without a real world).
    pub min_clearance_m: Option<f32>,
    /// Poses reported.
    pub poses: usize,
    /// Ctrl-C aborted the mission.
    pub interrupted: bool,
    /// What the link lost and repaired (`summary.json`).
    pub link: super::mission_link::LinkReport,
}

/// The `--json` object: the keys of `twil simulate --json` plus `mcu`.
pub fn result_json(outcome: &Outcome) -> serde_json::Value {
    let s = &outcome.report.stats;
    json!({
        "status": outcome.report.status.as_str(),
        "stops": s.stops,
        "full_sweeps": s.full_sweeps,
        "replans": s.replans,
        "distance_m": round3(outcome.distance_m),
        "sim_time_s": round3(s.time_s),
        "min_clearance_m": outcome.min_clearance_m.map(round3),
        "controller_overruns": s.controller_overruns,
        "mcu": {
            "max_control_instructions": outcome.report.max_control_instructions,
            "max_plan_instructions": outcome.report.max_plan_instructions,
            "static_ram_bytes": outcome.info.static_ram_bytes,
            "stack_high_water_bytes": outcome.report.stack_high_water_bytes,
        },
    })
}

/// `summary.json`: the `--json` object plus details.
fn summary_json(args: &Args, outcome: &Outcome) -> serde_json::Value {
    let mut v = result_json(outcome);
    let s = &outcome.report.stats;
    let extra = json!({
        "remote": remote_name(&args.remote),
        "build": format!("{:?}", outcome.info.build).to_lowercase(),
        "mode": match args.mode { Mode::Stop => "stop", Mode::Continuous => "continuous" },
        "preset": args.loop_args.preset.name(),
        "planner": args.choices().planner_name(),
        "constant_depth_filter": args.choices().rcd,
        "trust_seen_space": !args.choices().seed_prune,
        "settle": args.choices().settle_name(),
        "reference_feed_forward": args.choices().reference_feed_forward,
        "turn_in_place": args.choices().turn_in_place,
        "sweep_readings": args.choices().sweep_readings_name(),
        "real": args.real.as_ref().map(|p| p.display().to_string()),
        "known": args.known.as_ref().map(|p| p.display().to_string()),
        "params": args.params.display().to_string(),
        "seed": args.seed,
        "sonar_range_m": args.sonar_range,
        "moving_sweeps": s.moving_sweeps,
        "plans": s.plans,
        "blocked_replans": s.blocked_replans,
        "band_cuts": s.band_cuts,
        "blind_cuts": s.blind_cuts,
        "readings": s.readings,
        "hits": s.hits,
        "odometry_distance_m": round3(s.odometry_distance_m),
        "saturated_periods": s.saturated_periods,
        "unreachable_reason": s.unreachable_reason.map(|r| format!("{r:?}")),
        "plan_errors": s.plan_errors,
        "poses_reported": outcome.poses,
        "stop_cause": stop_cause_name(outcome.report.stop_cause),
        "stop_latency_us": outcome.report.stop_latency_us,
        "interrupted": outcome.interrupted,
        "link": outcome.link.json(),
    });
    if let (Some(obj), Some(extra)) = (v.as_object_mut(), extra.as_object()) {
        for (k, val) in extra {
            obj.insert(k.clone(), val.clone());
        }
    }
    v
}

fn remote_name(spec: &RemoteSpec) -> String {
    match spec {
        RemoteSpec::Qemu => "qemu".into(),
        RemoteSpec::Sim(0) => "sim".into(),
        RemoteSpec::Sim(n) => format!("sim:{n}"),
        RemoteSpec::Tcp(addr) => format!("tcp:{addr}"),
        RemoteSpec::Serial(path) => path.clone(),
    }
}

/// Check that `--real` fits the device: required by a simulated one, refused by a board.
fn check_real(args: &Args, build: Build) -> Result<()> {
    let name = remote_name(&args.remote);
    match (build, &args.real) {
        (Build::Hardware, Some(real)) => bail!(
            "--real {}: `{name}` is a real robot, which drives in the real world; drop --real",
            real.display()
        ),
        (Build::Qemu | Build::Host, None) => bail!(
            "--real R.da is required with --remote {name}: the simulated robot needs a real world to drive in and its sonar to see"
        ),
        _ => Ok(()),
    }
}

/// Run `twil mission`.
pub fn run(args: Args) -> Result<crate::exit::Ending> {
    let inputs = read_inputs(&args)?;
    // A simulated device is known before connecting: refuse early.
    match args.remote {
        RemoteSpec::Sim(_) => check_real(&args, Build::Host)?,
        RemoteSpec::Qemu => check_real(&args, Build::Qemu)?,
        _ => {}
    }
    // A QEMU started here runs at -icount shift=3: 8 ns per instruction, no faster than the
    // 168 MHz chip, so a control period met under QEMU is met on the board.
    crate::remote::set_qemu_icount_shift(3);
    let (mut remote, info) = Remote::connect(&args.remote)
        .with_context(|| format!("--remote {}", remote_name(&args.remote)))?;
    if info.protocol_version != PROTOCOL_VERSION {
        bail!(
            "the device speaks protocol {}, this host {}",
            info.protocol_version,
            PROTOCOL_VERSION
        );
    }
    check_real(&args, info.build)?;
    if inputs.geometry.cell_count() as u64 > info.grid_capacity_cells as u64 {
        bail!(
            "--size {}: the map has {} x {} cells but the device's grid holds {} cells",
            args.size,
            inputs.geometry.width(),
            inputs.geometry.height(),
            info.grid_capacity_cells
        );
    }
    upload(&args, &inputs, &mut remote, info.build)?;

    let bar = if args.json || !std::io::stderr().is_terminal() {
        ProgressBar::with_draw_target(None, ProgressDrawTarget::hidden())
    } else {
        let b = ProgressBar::new_spinner();
        if let Ok(style) = ProgressStyle::with_template("{spinner} {msg}") {
            b.set_style(style);
        }
        b.enable_steady_tick(Duration::from_millis(200));
        b
    };
    // Ctrl-C from now on aborts the mission instead of killing the tool (a handler can only be
    // set once per process: a second run in the same process keeps the first).
    INTERRUPTED.store(false, Ordering::SeqCst);
    FOLLOWING.store(true, Ordering::SeqCst);
    let _ = ctrlc::set_handler(on_ctrl_c);
    let mut follower = Follower::new(&inputs, args.out.is_some())?;
    if args.record.wanted() {
        let recorder = Recorder::open(args.record.record.as_deref(), args.record.live)?;
        if let (Some(port), Some(addr)) = (recorder.live_port(), args.record.live) {
            note(
                &bar,
                &format!(
                    "twil: serving live on ws://{}:{port} (Foxglove: Open connection)",
                    addr.ip()
                ),
            );
        }
        follower.record_into(recorder, &inputs);
    }
    let followed = match remote.call(Request::StartMission) {
        Ok(Reply::Ack) => follow(&args, &mut remote, &mut follower, &bar),
        Ok(other) => Err(anyhow!("unexpected reply to StartMission: {other:?}")),
        Err(e) => Err(e.context("starting the mission")),
    };
    FOLLOWING.store(false, Ordering::SeqCst);
    if followed.is_err() {
        // The host gives up on a mission that may still be running: ask the device, once and
        // briefly, to stop the motors (useless if the link is dead, harmless otherwise).
        remote.set_timeout(Duration::from_secs(2));
        let _ = remote.request(Request::AbortMission);
    }
    bar.finish_and_clear();
    let link = super::mission_link::LinkReport::of(&remote, follower.telemetry_gaps);
    // Done with the device (QEMU, if any, ends here).
    drop(remote);
    // Close the recording even when following failed, so what arrived stays readable.
    let recorded = match follower.recorder.take() {
        Some(r) => Some(r.into_recorder().close()?),
        None => None,
    };
    let interrupted = followed?;
    let report = follower
        .finished
        .ok_or_else(|| anyhow!("the mission ended without a report"))?;

    let min_clearance_m = inputs.real.as_ref().map(|real| {
        follower
            .trajectory
            .iter()
            .map(|row| Plant::new(&inputs.robot, row.pose).clearance_m(real))
            .fold(f32::INFINITY, f32::min)
    });
    let outcome = Outcome {
        report,
        info,
        distance_m: follower.distance_m,
        min_clearance_m,
        poses: follower.poses.len(),
        interrupted,
        link,
    };
    if let Some(dir) = &args.out {
        write_outputs(dir, &args, &inputs, &outcome, follower)?;
    }
    if args.json {
        println!("{}", result_json(&outcome));
    } else {
        let s = &report.stats;
        println!(
            "{}: {:.2} m travelled in {:.1} s of mission time; {} stops ({} full sweeps, {} moving sweeps), {} plans, min clearance {}",
            report.status.as_str(),
            outcome.distance_m,
            s.time_s,
            s.stops,
            s.full_sweeps,
            s.moving_sweeps,
            s.plans,
            outcome
                .min_clearance_m
                .map_or("unknown (no --real)".to_string(), |c| format!("{c:.3} m"))
        );
        println!(
            "mcu: {} instructions per control step at most, {} per plan, {} B static RAM, {} B stack",
            report.max_control_instructions,
            report.max_plan_instructions,
            info.static_ram_bytes,
            report.stack_high_water_bytes
        );
        if report.stop_cause != StopCause::None {
            println!("stopped by the device: {}", report.stop_cause.describe());
        }
        if let Some(dir) = &args.out {
            println!("wrote {}", dir.display());
        }
    }
    if let Some(summary) = &recorded {
        summary.print(args.json);
    }
    if interrupted {
        eprintln!(
            "twil: interrupted (Ctrl-C): the mission was aborted and the device stopped the motors"
        );
        return Ok(crate::exit::Ending::Interrupted);
    }
    // A contact with the real world (`--real`) is a collision whatever the device reports.
    if outcome.min_clearance_m.is_some_and(|c| c < 0.0) {
        return Ok(crate::exit::Ending::Collision);
    }
    Ok(crate::exit::Ending::of_mission_status(
        report.status.as_str(),
    ))
}

/// Map, known obstacles, real world, mission setup.
fn upload(args: &Args, inputs: &Inputs, remote: &mut Remote, build: Build) -> Result<()> {
    let map = MapParams {
        width_cells: inputs.geometry.width(),
        height_cells: inputs.geometry.height(),
        resolution_m: inputs.geometry.resolution_m(),
        robot_radius_m: inputs.params.robot_radius_m,
    };
    remote
        .call(Request::ClearMap)
        .context("clearing the device's map")?;
    remote
        .call(Request::SetParams(map))
        .with_context(|| format!("setting the map (--size {})", args.size))?;
    if let (Some(known), Some(path)) = (&inputs.known, &args.known) {
        for (i, polygon) in known.iter().enumerate() {
            remote.upload_polygon(polygon).with_context(|| {
                format!("{}: uploading known obstacle {}", path.display(), i + 1)
            })?;
        }
    }
    if let (Some(real), Some(path)) = (&inputs.real, &args.real) {
        match remote
            .request(Request::ClearWorld)
            .context("clearing the device's real world")?
        {
            Reply::Ack => {}
            Reply::Error(e) if e.code == ErrorCode::NotOnThisBuild => bail!(
                "--remote {}: this device (build {build:?}) keeps no real world, so it cannot run a simulated mission (a firmware without mission support?)",
                remote_name(&args.remote)
            ),
            Reply::Error(e) => bail!("clearing the device's real world: {e}"),
            other => bail!("unexpected reply to ClearWorld: {other:?}"),
        }
        for (i, polygon) in real.iter().enumerate() {
            remote.upload_world_polygon(polygon).with_context(|| {
                format!("{}: uploading real obstacle {}", path.display(), i + 1)
            })?;
        }
    }
    match remote.request(Request::SetMission(mission_setup(args, &inputs.params)))? {
        Reply::Ack => Ok(()),
        Reply::Error(e) => bail!("{}", explain_bad_mission(args, &e)),
        other => bail!("unexpected reply to SetMission: {other:?}"),
    }
}

/// A line on stderr, above the live display if there is one.
fn note(bar: &ProgressBar, line: &str) {
    if bar.is_hidden() {
        eprintln!("{line}");
    } else {
        bar.println(line);
    }
}

/// The error when the device stays quiet for `--silence`.
fn went_silent(args: &Args, follower: &Follower) -> String {
    format!(
        "the device went silent: no telemetry for {} s (mission time {:.1} s)",
        args.silence,
        follower.t_s()
    )
}

/// Follow the telemetry until `Finished`; `true` if Ctrl-C aborted the mission.
fn follow(
    args: &Args,
    remote: &mut Remote,
    follower: &mut Follower,
    bar: &ProgressBar,
) -> Result<bool> {
    let silence = Duration::from_secs_f32(args.silence);
    remote.set_timeout(silence);
    let mut aborted = false;
    let mut last_draw = Instant::now();
    let heartbeat = heartbeat_period(args.link_timeout_ms);
    let mut last_beat = Instant::now();
    // The device measures the silence on its own clock, which under QEMU (`sleep=off`) runs
    // ahead of the host's: a heartbeat is also due when the mission time of its telemetry
    // has advanced by a period.
    let mut last_beat_mission_ms = 0u32;
    let mut last_heard = Instant::now();
    loop {
        for t in std::mem::take(&mut remote.telemetry) {
            follower.absorb(t);
        }
        if follower.finished.is_some() {
            return Ok(aborted);
        }
        if !aborted && INTERRUPTED.load(Ordering::SeqCst) {
            note(bar, "twil: Ctrl-C: aborting the mission…");
            aborted = true;
            match remote
                .request(Request::AbortMission)
                .context("Ctrl-C: sending AbortMission")?
            {
                Reply::Ack => {}
                other => bail!("Ctrl-C: the device did not accept AbortMission: {other:?}"),
            }
            continue;
        }
        // Ask `MissionStatus` when the heartbeat is due (the device's link-loss policy needs
        // to hear from the host) or when the device has been quiet for `POLL_AFTER` (its final
        // report may have been lost on the way, see mission_link). Under QEMU (`sleep=off`)
        // the device's clock runs ahead of the host's, so the heartbeat is also due when the
        // mission time of its telemetry has advanced by a period.
        use super::mission_link::{recover_final_report, Poll, POLL_AFTER};
        let mission_ms = follower.t_ms();
        let beat_due = heartbeat.is_some_and(|period| {
            last_beat.elapsed() >= period
                || u128::from(mission_ms.saturating_sub(last_beat_mission_ms)) >= period.as_millis()
        });
        let quiet = last_heard.elapsed() >= POLL_AFTER && last_beat.elapsed() >= POLL_AFTER;
        if beat_due || quiet {
            last_beat = Instant::now();
            last_beat_mission_ms = mission_ms;
            match recover_final_report(remote, follower) {
                Poll::Finished => continue,
                Poll::Alive => {
                    last_heard = Instant::now();
                    continue;
                }
                Poll::NoReply if last_heard.elapsed() < silence => {
                    note(bar, "twil: MissionStatus unanswered, still listening");
                    continue;
                }
                Poll::NoReply => bail!(went_silent(args, follower)),
            }
        }
        let mut deadline = (last_heard + silence).min(last_beat.max(last_heard) + POLL_AFTER);
        if let Some(period) = heartbeat {
            deadline = deadline.min(last_beat + period);
        }
        let frame = match remote.next_frame(deadline) {
            Ok(frame) => {
                last_heard = Instant::now();
                frame
            }
            // The wait ended for a heartbeat or a poll, not for the silence: go round.
            Err(_) if Instant::now() >= deadline && last_heard.elapsed() < silence => continue,
            Err(e) if Instant::now() >= deadline => {
                return Err(e).with_context(|| went_silent(args, follower));
            }
            Err(e) => return Err(e).context("reading the mission's telemetry"),
        };
        match frame {
            Ok(DeviceFrame::Telemetry(t)) => follower.absorb(t),
            Ok(DeviceFrame::Reply { .. }) => {} // a stale reply
            Err(fault) => note(
                bar,
                &format!("twil: dropped a damaged frame from the device: {fault:?}"),
            ),
        }
        if last_draw.elapsed() >= Duration::from_millis(50) {
            last_draw = Instant::now();
            bar.set_message(follower.status_line());
        }
    }
}

/// `summary.json`, `trajectory.csv`, `plan-NNN.png`, `mission.gif`.
fn write_outputs(
    dir: &std::path::Path,
    args: &Args,
    inputs: &Inputs,
    outcome: &Outcome,
    follower: Follower,
) -> Result<()> {
    std::fs::create_dir_all(dir)
        .with_context(|| format!("{}: cannot create directory", dir.display()))?;
    let setup = SimSetup {
        real: inputs.real.clone().unwrap_or_default(),
        known: inputs.known.clone(),
        params: inputs.params,
        geometry: inputs.geometry,
        mode: mission_mode(args.mode),
        planner: args.choices().planner_kind(),
        robot: inputs.robot,
        time_limit_s: args.time_limit_s(),
        constant_depth_filter: args.choices().rcd,
        trust_seen_space: !args.choices().seed_prune,
        moving_half_sweep_deg: 95.0,
        snapshot_period_s: FRAME_PERIOD_S,
        plan_latency_s: 0.0,
        settle: args.choices().settle,
        reference_feed_forward: args.choices().reference_feed_forward,
        turn_in_place: args.choices().turn_in_place,
        world_name: crate::sim::pictures::world_name(args.real.as_deref(), args.known.as_deref()),
    };
    let report = &outcome.report;
    let result = SimResult {
        status: match report.status {
            MissionStatus::Reached => SimStatus::Reached,
            MissionStatus::Unreachable => SimStatus::Unreachable,
            MissionStatus::Timeout => SimStatus::Timeout,
            MissionStatus::Aborted | MissionStatus::Running => SimStatus::Aborted,
        },
        stats: report.stats,
        distance_m: outcome.distance_m,
        sim_time_s: report.stats.time_s,
        min_clearance_m: outcome.min_clearance_m.unwrap_or(f32::NAN),
        sweeps: follower.sweeps,
        final_odometry_pose: follower.pose(),
        trajectory: follower.trajectory,
        plans: follower.plan_snapshots,
        frames: follower.frames,
        known_map_plan_length_m: None,
    };
    output::write_trajectory_csv(&dir.join("trajectory.csv"), &result)?;
    output::write_plan_pngs(dir, &setup, &result)?;
    output::write_gif(
        &dir.join("mission.gif"),
        &setup,
        &result,
        args.gif_scale.clamp(1, 8),
    )?;
    let path = dir.join("summary.json");
    std::fs::write(
        &path,
        serde_json::to_string_pretty(&summary_json(args, outcome))? + "\n",
    )
    .with_context(|| format!("{}: cannot write", path.display()))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: Args,
    }

    fn args(extra: &[&str]) -> Args {
        let par = concat!(env!("CARGO_MANIFEST_DIR"), "/../worlds/office.par");
        let mut argv = vec!["twil", "--remote", "sim", "--params", par];
        argv.extend_from_slice(extra);
        Cli::parse_from(argv).args
    }

    /// A device that never says anything.
    struct Silent;

    impl std::io::Read for Silent {
        fn read(&mut self, _: &mut [u8]) -> std::io::Result<usize> {
            std::thread::sleep(Duration::from_millis(20));
            Err(std::io::ErrorKind::TimedOut.into())
        }
    }

    impl std::io::Write for Silent {
        fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
            Ok(b.len())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn a_silent_device_is_a_clear_error_after_the_silence_time() {
        let args = args(&["--silence", "0.3"]);
        let inputs = read_inputs(&args).unwrap();
        let mut follower = Follower::new(&inputs, false).unwrap();
        let mut remote = Remote::over(Silent);
        let started = Instant::now();
        let e = follow(&args, &mut remote, &mut follower, &ProgressBar::hidden()).unwrap_err();
        assert!(started.elapsed() < Duration::from_secs(3));
        assert!(
            format!("{e:#}").contains("the device went silent: no telemetry for 0.3 s"),
            "{e:#}"
        );
    }

    /// A device whose mission has ended and whose `Finished` telemetry was lost: it answers
    /// every request with its report.
    struct Ended(Vec<u8>);
    impl std::io::Write for Ended {
        fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
            let mut decoder = twil_core::link::FrameDecoder::new();
            let mut rest = b;
            while !rest.is_empty() {
                let (got, r) = decoder.feed::<twil_core::link::RequestFrame>(rest);
                rest = r;
                if let Some(Ok(frame)) = got {
                    let report = MissionReport {
                        state: twil_core::link::RunState::Ended,
                        status: MissionStatus::Reached,
                        phase: MissionPhase::Done,
                        stats: Default::default(),
                        max_control_instructions: 0,
                        max_plan_instructions: 0,
                        stack_high_water_bytes: 0,
                        stop_ticks: 0,
                        stop_latency_us: 0,
                        stop_cause: twil_core::failsafe::StopCause::None,
                        emergency_stop: false,
                    };
                    let mut out = [0u8; twil_core::link::MAX_FRAME_BYTES];
                    let reply = DeviceFrame::Reply {
                        seq: Some(frame.seq),
                        reply: Reply::Mission(report),
                    };
                    let bytes = twil_core::link::frame::encode(&reply, &mut out).unwrap();
                    self.0.extend_from_slice(bytes);
                }
            }
            Ok(b.len())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }
    impl std::io::Read for Ended {
        fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
            if self.0.is_empty() {
                std::thread::sleep(Duration::from_millis(5));
                return Err(std::io::ErrorKind::WouldBlock.into());
            }
            let n = buf.len().min(self.0.len());
            buf[..n].copy_from_slice(&self.0[..n]);
            self.0.drain(..n);
            Ok(n)
        }
    }

    #[test]
    fn a_lost_final_report_is_asked_for_after_a_second_of_quiet() {
        // No heartbeat (it would ask sooner): the quiet poll alone must find the report.
        let args = args(&["--link-timeout-ms", "0"]);
        let inputs = read_inputs(&args).unwrap();
        let mut follower = Follower::new(&inputs, false).unwrap();
        let mut remote = Remote::over(Ended(Vec::new()));
        let started = Instant::now();
        follow(&args, &mut remote, &mut follower, &ProgressBar::hidden()).unwrap();
        let waited = started.elapsed();
        assert!(
            waited >= super::super::mission_link::POLL_AFTER && waited < Duration::from_secs(3),
            "{waited:?}"
        );
        assert_eq!(
            follower.finished.map(|r| r.status),
            Some(MissionStatus::Reached)
        );
    }

    #[test]
    fn real_is_required_by_simulated_devices_and_refused_by_a_board() {
        let without = args(&[]);
        let with = args(&["--real", "R.da"]);
        assert!(check_real(&without, Build::Host).is_err());
        assert!(check_real(&without, Build::Qemu).is_err());
        assert!(check_real(&with, Build::Host).is_ok());
        assert!(check_real(&without, Build::Hardware).is_ok());
        let e = check_real(&with, Build::Hardware).unwrap_err();
        assert!(e.to_string().contains("is a real robot"), "{e}");
    }

    #[test]
    fn refused_mission_fields_are_named() {
        let a = args(&[]);
        let speed = ErrorReply::new(ErrorCode::BadMission, 5, 0);
        assert!(explain_bad_mission(&a, &speed).contains("speed ("));
        let off = ErrorReply {
            code: ErrorCode::BadMission,
            value: 0,
            limit: 0,
            detail: 1,
        };
        assert!(explain_bad_mission(&a, &off).contains("lies off its map"));
    }
}
