//! `twil simulate`: run a whole mission against a simulated robot in a real world.
//!
//! ```text
//! twil simulate --real worlds/office.da --params worlds/office.par --out out/office
//! twil simulate --real R.da --params P.par --known K.da --mode continuous --json
//! ```
//!
//! The robot starts knowing only `--known` (if given); the sonar discovers the `--real`
//! obstacles. See `docs/simulate.md`.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};

use anyhow::{bail, Result};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde_json::json;
use twil_core::control::Pose;
use twil_core::geom::PointM;
use twil_core::mission::{MissionMode, MissionStats};

use crate::answer::MissionEnd;
use crate::record::sim::{Pace, SimRecorder};
use crate::record::topics::StatusMessage;
use crate::record::Recorder;

use super::args::{read_da, LoopChoices, MissionArgs, OutputArgs, RobotArgs, WorldArgs};

use crate::sim::{self, SimResult, SimSetup};

/// Arguments of `twil simulate`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// The real world (.da): what the simulated sonar sees and the robot can hit.
    #[arg(long, value_name = "R.da")]
    pub real: PathBuf,
    /// `--params`, `--known`, `--size`.
    #[command(flatten)]
    pub world: WorldArgs,
    /// Grid resolution, metres per cell.
    #[arg(long, default_value_t = 0.05)]
    pub resolution: f32,
    /// `--mode`, the loop choices (`--preset`, `--planner`, `--settle`, …), `--time-limit`.
    #[command(flatten)]
    pub mission: MissionArgs,
    /// `--robot`, `--seed`, `--sonar-range`, `--sonar-noise`, `--sonar`, ….
    #[command(flatten)]
    pub robot: RobotArgs,
    /// Continuous mode: half-width of the sweeps taken while moving, degrees (narrower sweeps
    /// come round more often but see less to the sides; experimental).
    #[arg(long, default_value_t = 95.0)]
    pub moving_sweep: f32,
    /// How long the planner takes to hand a plan back, milliseconds of mission time: the
    /// robot holds (or, moving, goes on along the old prefix) meanwhile. The default, one
    /// control period, is what the firmware guarantees (a plan is at most 5 M instructions,
    /// 30 ms at 168 MHz); 0 applies every plan at once.
    #[arg(long, default_value_t = 50.0, value_name = "MS")]
    pub plan_latency_ms: f32,
    /// `--out`, `--json`, `--gif-scale`, `--record`, `--live`.
    #[command(flatten)]
    pub output: OutputArgs,
    /// With `--live`: run mission time this many times faster than the wall clock.
    #[arg(long, default_value_t = 1.0, value_name = "X", requires = "live")]
    pub speed: f64,
}

/// Turn the arguments into a simulation setup (reads and checks every file).
pub fn setup_from_args(args: &Args) -> Result<SimSetup> {
    let real = read_da(&args.real)?;
    let (mut params, known) = args.world.read()?;
    let geometry = args.world.geometry(args.resolution)?;
    let choices = args.choices();
    let robot = args.robot.resolve(
        &choices,
        args.mission.follow.sweep_readings.is_some(),
        &args.world.params,
        &mut params,
    )?;
    if !(args.plan_latency_ms.is_finite() && (0.0..=60_000.0).contains(&args.plan_latency_ms)) {
        bail!(
            "--plan-latency-ms: must be between 0 and 60000, got {}",
            args.plan_latency_ms
        );
    }
    let time_limit_s = args.mission.checked_time_limit_s()?;
    // `run` answers `out_of_bounds` (crate::answer); other callers see the error.
    args.world.check_on_map(&geometry, &params)?;
    Ok(SimSetup {
        real,
        known,
        params,
        geometry,
        mode: args.mission.mission_mode(),
        planner: choices.planner_kind(),
        robot,
        time_limit_s,
        snapshot_period_s: if args.output.out.is_some() { 0.5 } else { 0.0 },
        constant_depth_filter: choices.rcd,
        trust_seen_space: !choices.seed_prune,
        evidence_map: args.mission.loop_args.evidence_map_for(robot.sonar_beam),
        moving_half_sweep_deg: args.moving_sweep,
        plan_latency_s: args.plan_latency_ms / 1000.0,
        settle: choices.settle,
        reference_feed_forward: choices.reference_feed_forward,
        turn_in_place: choices.turn_in_place,
        world_name: crate::sim::pictures::world_name(Some(&args.real), args.world.known.as_deref()),
    })
}

impl Args {
    /// The loop choices of this run: `--preset`'s, with the explicit options applied.
    pub fn choices(&self) -> LoopChoices {
        self.mission.choices()
    }
}

/// The `--json` object: exactly the keys of the issue, and why the mission ended (`why` only
/// when it did not reach the goal: crate::answer).
pub fn result_json(result: &SimResult, end: &MissionEnd) -> serde_json::Value {
    let mut v = json!({
        "status": end.word(),
        "stop_cause": stop_cause(result),
        "stops": result.stats.stops,
        "full_sweeps": result.stats.full_sweeps,
        "replans": result.stats.replans,
        "distance_m": round3(result.distance_m),
        "sim_time_s": round3(result.sim_time_s),
        "min_clearance_m": round3(result.min_clearance_m),
        "controller_overruns": result.stats.controller_overruns,
    });
    if let (Some(why), Some(obj)) = (end.why(), v.as_object_mut()) {
        obj.insert("why".into(), why.into());
    }
    v
}

/// How the simulated mission ended, for its word and sentence (crate::answer).
pub fn mission_end<'a>(args: &Args, setup: &SimSetup, result: &'a SimResult) -> MissionEnd<'a> {
    let pose = result.trajectory.last().map_or(
        Pose::new(setup.params.start.x_m, setup.params.start.y_m, 0.0),
        |r| r.pose,
    );
    let at = PointM::new(pose.x_m, pose.y_m);
    let config = sim::mission_config(setup);
    let plan_positions: Vec<PointM> = result
        .plans
        .iter()
        .map(|s| PointM::new(s.pose.x_m, s.pose.y_m))
        .collect();
    MissionEnd {
        status: result.status.name(),
        unreachable: result.stats.unreachable_reason,
        device: twil_core::failsafe::StopCause::None,
        interrupted: result.status == sim::SimStatus::Aborted,
        at,
        goal: setup.params.goal,
        radius_m: setup.params.robot_radius_m,
        plans_here: crate::answer::plans_here(&plan_positions, at, config.stall_distance_m),
        stall_distance_m: config.stall_distance_m,
        clearance_m: result.min_clearance_m,
        real: Some(crate::answer::file_name(&args.real)),
        time_limit_s: setup.time_limit_s,
        plan_error: None,
        // A plan that found no start leaves no path (the mission clears it).
        no_start: result.plans.last().is_some_and(|p| p.path.is_empty()),
    }
}

/// `summary.json`: the `--json` object plus details.
pub fn summary_json(args: &Args, setup: &SimSetup, result: &SimResult) -> serde_json::Value {
    let mut v = result_json(result, &mission_end(args, setup, result));
    let stats: &MissionStats = &result.stats;
    let extra = json!({
        "mode": match setup.mode { MissionMode::Stop => "stop", MissionMode::Continuous => "continuous" },
        "preset": args.mission.loop_args.preset.name(),
        "planner": args.choices().planner_name(),
        "settle": args.choices().settle_name(),
        "settle_time_s": round3(mission_config_settle_s(setup)),
        "reference_feed_forward": setup.reference_feed_forward,
        // The layout used: the preset's, `--sweep-readings`' or the robot file's.
        "sweep_readings": LoopChoices { sweep_layout: setup.robot.sweep_layout, ..args.choices() }.sweep_readings_name(),
        "turn_in_place": setup.turn_in_place,
        "real": args.real.display().to_string(),
        "known": args.world.known.as_ref().map(|p| p.display().to_string()),
        "params": args.world.params.display().to_string(),
        "seed": args.robot.seed,
        "sonar_range_m": setup.robot.sonar_range_m,
        "robot": crate::robot_file::robot_json(&setup.robot),
        "moving_sweeps": stats.moving_sweeps,
        "sweeps": result.sweeps,
        "plans": stats.plans,
        "blocked_replans": stats.blocked_replans,
        "band_cuts": stats.band_cuts,
        "blind_cuts": stats.blind_cuts,
        "trust_seen_space": setup.trust_seen_space,
        "evidence_map": setup.evidence_map,
        "constant_depth_filter": setup.constant_depth_filter,
        "readings": stats.readings,
        "hits": stats.hits,
        "odometry_distance_m": round3(stats.odometry_distance_m),
        "saturated_periods": stats.saturated_periods,
        "unreachable_reason": stats.unreachable_reason.map(|r| format!("{r:?}")),
        "known_map_plan_length_m": result.known_map_plan_length_m.map(round3),
        "final_true_pose": [round3(result.trajectory.last().map_or(0.0, |r| r.pose.x_m)),
                            round3(result.trajectory.last().map_or(0.0, |r| r.pose.y_m))],
        "final_odometry_pose": [round3(result.final_odometry_pose.x_m), round3(result.final_odometry_pose.y_m)],
        "goal": [setup.params.goal.x_m, setup.params.goal.y_m],
    });
    if let (Some(obj), Some(extra)) = (v.as_object_mut(), extra.as_object()) {
        for (k, val) in extra {
            obj.insert(k.clone(), val.clone());
        }
    }
    v
}

/// Why the simulated mission ended ([`crate::stop_cause`]).
pub fn stop_cause(result: &SimResult) -> &'static str {
    crate::stop_cause::name(
        result.status.name(),
        result.stats.unreachable_reason,
        twil_core::failsafe::StopCause::None,
        result.status == sim::SimStatus::Aborted,
    )
}

fn mission_config_settle_s(setup: &SimSetup) -> f32 {
    let config = sim::mission_config(setup);
    config.settle.settle_time_s(&config.robot)
}

fn round3(x: f32) -> f64 {
    ((x as f64) * 1000.0).round() / 1000.0
}

struct Bar(ProgressBar);

impl sim::Progress for Bar {
    fn update(&mut self, sim_time_s: f32, time_limit_s: f32, stats: &MissionStats) {
        self.0.set_length(time_limit_s as u64);
        self.0.set_position(sim_time_s as u64);
        self.0.set_message(format!(
            "stops {} replans {} hits {}",
            stats.stops, stats.replans, stats.hits
        ));
    }
}

/// Run `twil simulate`.
pub fn run(args: Args) -> Result<crate::exit::Ending> {
    let setup = match setup_from_args(&args) {
        Ok(setup) => setup,
        Err(e) => match e.downcast_ref::<crate::answer::OffMap>() {
            Some(off) => return Ok(sim::start::answer_off_map(off, args.output.json)),
            None => return Err(e),
        },
    };
    let robot = sim::mission_config(&setup).robot;
    if let Some(blocked) = sim::start::start_blocked(&robot, setup.params.start, &setup.real) {
        if args.output.json {
            println!("{}", blocked.json(&args.real));
        } else {
            println!("{}", blocked.words(&args.real));
        }
        return Ok(crate::exit::Ending::NoPath);
    }
    let bar = if args.output.json || !std::io::stderr().is_terminal() {
        ProgressBar::with_draw_target(None, ProgressDrawTarget::hidden())
    } else {
        let b = ProgressBar::new(setup.time_limit_s as u64);
        if let Ok(style) =
            ProgressStyle::with_template("{spinner} simulated {pos:>4}/{len} s  {msg}")
        {
            b.set_style(style);
        }
        b
    };
    let mut progress = Bar(bar);
    let (result, recorded) = if args.output.record.wanted() {
        run_recorded(&args, &setup, &mut progress)?
    } else {
        (sim::run(&setup, &mut progress)?, None)
    };
    progress.0.finish_and_clear();

    args.output
        .write(&setup, &result, &summary_json(&args, &setup, &result))?;
    let end = mission_end(&args, &setup, &result);
    if args.output.json {
        println!("{}", result_json(&result, &end));
    } else {
        let s = &result.stats;
        println!(
            "{}: {}{:.2} m travelled in {:.1} s simulated; {} stops ({} full sweeps, {} moving sweeps), {} plans, min clearance {:.3} m; stop cause: {}",
            end.word(),
            end.why().map_or(String::new(), |why| format!("{why}; ")),
            result.distance_m,
            result.sim_time_s,
            s.stops,
            s.full_sweeps,
            s.moving_sweeps,
            s.plans,
            result.min_clearance_m,
            stop_cause(&result)
        );
        if let Some(len) = result.known_map_plan_length_m {
            println!("known-map plan length: {len:.2} m");
        }
        if let Some(dir) = &args.output.out {
            println!("wrote {}", dir.display());
        }
    }
    if let Some(summary) = &recorded {
        summary.print(args.output.json);
    }
    if result.status == sim::SimStatus::Aborted {
        eprintln!("twil: interrupted (Ctrl-C): the simulation was stopped");
        return Ok(crate::exit::Ending::Interrupted);
    }
    Ok(crate::exit::Ending::of_mission_status(end.word()))
}

/// Set by Ctrl-C while a recorded or live simulation runs: the mission stops at the next tick
/// and the recording is closed properly.
static STOP: AtomicBool = AtomicBool::new(false);

/// Run the simulation with `--record` / `--live`: messages as the mission goes, paced to the
/// wall clock when live.
fn run_recorded(
    args: &Args,
    setup: &SimSetup,
    progress: &mut Bar,
) -> Result<(SimResult, Option<crate::record::RecordSummary>)> {
    if !(args.speed.is_finite() && args.speed > 0.0 && args.speed <= 1.0e6) {
        bail!(
            "--speed: must be a positive factor up to 1e6, got {}",
            args.speed
        );
    }
    let recorder = Recorder::open(
        args.output.record.record.as_deref(),
        args.output.record.live,
    )?;
    if let (Some(port), Some(addr)) = (recorder.live_port(), args.output.record.live) {
        eprintln!(
            "twil: serving live on ws://{}:{port} (Foxglove: Open connection; layout docs/foxglove-layout.json); Ctrl-C stops",
            addr.ip()
        );
    }
    STOP.store(false, Ordering::SeqCst);
    // A handler can be set once per process; a second run keeps the first (same flag).
    let _ = ctrlc::set_handler(|| STOP.store(true, Ordering::SeqCst));
    let pace = args.output.record.live.map(|_| Pace::new(args.speed));
    let mut observer = SimRecorder::new(recorder, setup, pace, &STOP);
    let run = sim::run_observed(setup, progress, &mut observer);
    let mut recorder = observer.into_recorder();
    if let Ok(result) = &run {
        // The end as the run saw it (a collision is no mission status), in the word of the
        // summary line (crate::answer: `gave_up`, `goal_blocked`, …).
        recorder.status(StatusMessage {
            t_s: result.sim_time_s,
            phase: "done".into(),
            status: mission_end(args, setup, result).word().into(),
            event: "end of run".into(),
            plans: result.stats.plans,
            stops: result.stats.stops,
        });
    }
    // Close the file even when the run failed, so what was recorded stays readable.
    let summary = recorder.close()?;
    Ok((run?, Some(summary)))
}

#[cfg(test)]
#[path = "simulate_pictures.rs"]
mod pictures_tests;
