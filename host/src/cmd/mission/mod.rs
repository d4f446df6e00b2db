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
//!
//! Files: this one (arguments, the session, Ctrl-C), `inputs.rs` (the files read and the
//! mission set-up), `follower.rs` (the telemetry followed into a trajectory, plans and
//! pictures), `link.rs` (what the host does when telemetry is lost), `report.rs` (the JSON
//! result and the files written).

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
use twil_core::mission::{MissionPhase, MissionStatus};
use twil_core::plant::Plant;
use twil_core::robot::RobotConfig;
use twil_core::world::{Obstacles, Params};

use super::args::{read_da, MissionArgs, OutputArgs, RobotArgs, WorldArgs};
use crate::record::telemetry::TelemetryRecorder;
use crate::record::Recorder;
use crate::remote::{Remote, RemoteSpec};
use crate::sim::{ControlSample, SimResult, SimSetup, SimStatus, Snapshot, TrajectoryRow};

mod follower;
mod inputs;
pub mod link;
mod report;

pub(crate) use follower::Follower;
use follower::*;
pub use inputs::*;
pub use report::*;

/// Arguments of `twil mission`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// The device: `sim` (in this process), `qemu`, `tcp:HOST:PORT` or a serial port.
    #[arg(long, value_name = "DEVICE")]
    pub remote: RemoteSpec,
    /// The real world (.da) of a simulated device (`sim`, `qemu`): required there, refused by
    /// a board.
    #[arg(long, value_name = "R.da")]
    pub real: Option<PathBuf>,
    /// `--params`, `--known`, `--size` (0.05 m cells).
    #[command(flatten)]
    pub world: WorldArgs,
    /// `--mode`, the loop choices (`--preset`, `--planner`, `--settle`, …; `SetMission`
    /// carries them all to the device), `--time-limit`.
    #[command(flatten)]
    pub mission: MissionArgs,
    /// `--robot`, `--seed`, `--sonar-range`, `--sonar-noise`, `--sonar`, ….
    #[command(flatten)]
    pub robot: RobotArgs,
    /// Give up when the device sends nothing for this many seconds.
    #[arg(long, default_value_t = 10.0, value_name = "S")]
    pub silence: f32,
    /// `--out`, `--json`, `--gif-scale`, `--record`, `--live` (the telemetry as Foxglove
    /// messages).
    #[command(flatten)]
    pub output: OutputArgs,
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

/// The `-icount shift` of a QEMU that `twil mission --remote qemu` starts: 8 ns per
/// instruction (125 M instructions per second), no faster than the 168 MHz chip.
pub const MISSION_QEMU_ICOUNT_SHIFT: u8 = 3;

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
    let inputs = match read_inputs(&args) {
        Ok(inputs) => inputs,
        Err(e) => match e.downcast_ref::<crate::answer::OffMap>() {
            Some(off) => return Ok(crate::sim::start::answer_off_map(off, args.output.json)),
            None => return Err(e),
        },
    };
    if let (Some(real), Some(path)) = (&inputs.real, &args.real) {
        let start = inputs.params.start;
        if let Some(blocked) = crate::sim::start::start_blocked(&inputs.robot, start, real) {
            if args.output.json {
                println!("{}", blocked.json(path));
            } else {
                println!("{}", blocked.words(path));
            }
            return Ok(crate::exit::Ending::NoPath);
        }
    }
    // A simulated device is known before connecting: refuse early.
    match args.remote {
        RemoteSpec::Sim(_) => check_real(&args, Build::Host)?,
        RemoteSpec::Qemu => check_real(&args, Build::Qemu)?,
        _ => {}
    }
    // A QEMU started here runs at -icount shift=3: 8 ns per instruction, no faster than the
    // 168 MHz chip, so a control period met under QEMU is met on the board.
    let (mut remote, info) = Remote::connect_paced(&args.remote, MISSION_QEMU_ICOUNT_SHIFT)
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
            args.world.size,
            inputs.geometry.width(),
            inputs.geometry.height(),
            info.grid_capacity_cells
        );
    }
    upload(&args, &inputs, &mut remote, info.build)?;

    let bar = if args.output.json || !std::io::stderr().is_terminal() {
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
    let mut follower = Follower::new(&inputs, args.output.out.is_some())?;
    if args.output.record.wanted() {
        let recorder = Recorder::open(
            args.output.record.record.as_deref(),
            args.output.record.live,
        )?;
        if let (Some(port), Some(addr)) = (recorder.live_port(), args.output.record.live) {
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
    let link = link::LinkReport::of(&remote, follower.telemetry_gaps);
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

    let clearances: Vec<f32> = match &inputs.real {
        Some(real) => follower
            .trajectory
            .iter()
            .map(|row| Plant::new(&inputs.robot, row.pose).clearance_m(real))
            .collect(),
        None => Vec::new(),
    };
    let min_clearance_m = inputs
        .real
        .as_ref()
        .map(|_| clearances.iter().copied().fold(f32::INFINITY, f32::min));
    // Where the mission ended: at the first contact for a collision, else the last pose.
    let end_pose = clearances
        .iter()
        .position(|c| *c < 0.0)
        .and_then(|i| follower.trajectory.get(i))
        .map_or(follower.pose(), |row| row.pose);
    let at = PointM::new(end_pose.x_m, end_pose.y_m);
    let place = EndPlace {
        at,
        plans_here: crate::answer::plans_here(&follower.plan_positions, at, follower.same_stop_m),
        stall_distance_m: follower.same_stop_m,
        goal: inputs.params.goal,
        radius_m: inputs.params.robot_radius_m,
        time_limit_s: args.mission.time_limit_s(),
        real: args.real.as_deref().map(crate::answer::file_name),
        last_plan: follower.reasons.status(),
    };
    let outcome = Outcome {
        report,
        info,
        distance_m: follower.distance_m,
        min_clearance_m,
        poses: follower.poses.len(),
        interrupted,
        link,
        place,
    };
    write_outputs(&args, &inputs, &outcome, follower)?;
    if args.output.json {
        println!("{}", result_json(&outcome));
    } else {
        let s = &report.stats;
        println!(
            "{}: {}{:.2} m travelled in {:.1} s of mission time; {} stops ({} full sweeps, {} moving sweeps), {} plans, min clearance {}; stop cause: {}",
            report::status_word(&outcome),
            report::mission_end(&outcome)
                .why()
                .map_or(String::new(), |why| format!("{why}; ")),
            outcome.distance_m,
            s.time_s,
            s.stops,
            s.full_sweeps,
            s.moving_sweeps,
            s.plans,
            outcome
                .min_clearance_m
                .map_or("unknown (no --real)".to_string(), |c| format!("{c:.3} m")),
            report::stop_cause(&outcome)
        );
        // The in-process device (`--remote sim`) measures nothing: no line of zeros.
        if report::measured(&outcome) {
            println!(
                "mcu: {} instructions per control step at most, {} per plan, {} per mission turn, {} B static RAM, {} B stack",
                report.max_control_instructions,
                report.max_plan_instructions,
                report.max_turn_instructions,
                info.static_ram_bytes,
                report.stack_high_water_bytes
            );
        }
        if let Some(words) = outcome.link.words() {
            println!("{words}");
        }
        if report.stop_cause != StopCause::None {
            println!("stopped by the device: {}", report.stop_cause);
        }
        if let Some(dir) = &args.output.out {
            println!("wrote {}", dir.display());
        }
    }
    if let Some(summary) = &recorded {
        summary.print(args.output.json);
    }
    if interrupted {
        eprintln!(
            "twil: interrupted (Ctrl-C): the mission was aborted and the device stopped the motors"
        );
        return Ok(crate::exit::Ending::Interrupted);
    }
    // One word and one status: a contact with the real world is a collision in both.
    Ok(crate::exit::Ending::of_mission_status(report::status_word(
        &outcome,
    )))
}

/// The robot file's values, map, known obstacles, real world, mission setup.
fn upload(args: &Args, inputs: &Inputs, remote: &mut Remote, build: Build) -> Result<()> {
    if !inputs.robot_file_values.is_empty() {
        let set = remote.send_params(&inputs.robot_file_values)?;
        {
            eprintln!(
                "twil: robot file: {set} of {} values set on the device (the others it had)",
                inputs.robot_file_values.len()
            );
        }
    }
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
        .with_context(|| format!("setting the map (--size {})", args.world.size))?;
    if let (Some(known), Some(path)) = (&inputs.known, &args.world.known) {
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
    match remote.request(Request::SetMission(mission_setup(args, inputs)))? {
        Reply::Ack => Ok(()),
        Reply::Error(e) => bail!("{}", explain_bad_mission(args, &inputs.robot, &e)),
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

    /// The final report of a mission that ended with `status` and `cause` (every count zero);
    /// `report`'s tests build their outcomes on it too.
    pub(super) fn ended_report(status: MissionStatus, cause: StopCause) -> MissionReport {
        MissionReport {
            state: twil_core::link::RunState::Ended,
            status,
            phase: MissionPhase::Done,
            stats: Default::default(),
            max_control_instructions: 0,
            max_plan_instructions: 0,
            max_turn_instructions: 0,
            stack_high_water_bytes: 0,
            stop_ticks: 0,
            stop_latency_us: 0,
            stop_cause: cause,
            emergency_stop: false,
        }
    }

    /// The final report of a mission that reached its goal.
    fn reached_report() -> MissionReport {
        ended_report(MissionStatus::Reached, StopCause::None)
    }

    /// A device on a line that loses everything the host sends: it never answers, but its
    /// telemetry (a phase every 50 ms) arrives, and after `until` the final report.
    struct Deaf {
        started: Instant,
        until: Duration,
        sent_final: bool,
    }
    impl std::io::Read for Deaf {
        fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
            if self.sent_final {
                std::thread::sleep(Duration::from_millis(20));
                return Err(std::io::ErrorKind::TimedOut.into());
            }
            std::thread::sleep(Duration::from_millis(50));
            let t_ms = self.started.elapsed().as_millis() as u32;
            let telemetry = if self.started.elapsed() >= self.until {
                self.sent_final = true;
                Telemetry::Finished(reached_report())
            } else {
                Telemetry::Phase {
                    t_ms,
                    phase: MissionPhase::Follow,
                    status: MissionStatus::Running,
                }
            };
            let mut out = [0u8; twil_core::link::MAX_FRAME_BYTES];
            let frame = DeviceFrame::Telemetry(telemetry);
            let bytes = twil_core::link::frame::encode(&frame, &mut out).unwrap();
            let n = bytes.len().min(buf.len());
            buf[..n].copy_from_slice(&bytes[..n]);
            Ok(n)
        }
    }
    impl std::io::Write for Deaf {
        fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
            Ok(b.len())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn telemetry_heard_while_a_poll_goes_unanswered_is_not_silence() {
        // Seen in CI through a bad line: each heartbeat's `MissionStatus` went unanswered for
        // the whole silence time while telemetry flowed, and the mission ended "went silent".
        let args = args(&["--silence", "0.5"]);
        let inputs = read_inputs(&args).unwrap();
        let mut follower = Follower::new(&inputs, false).unwrap();
        let until = Duration::from_millis(2500);
        let mut remote = Remote::over(Deaf {
            started: Instant::now(),
            until,
            sent_final: false,
        });
        follow(&args, &mut remote, &mut follower, &ProgressBar::hidden()).unwrap();
        assert_eq!(
            follower.finished.map(|r| r.status),
            Some(MissionStatus::Reached)
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
                    let report = reached_report();
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
            waited >= link::POLL_AFTER && waited < Duration::from_secs(3),
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
        assert!(explain_bad_mission(&a, &RobotConfig::DEFAULT, &speed).contains("speed ("));
        let off = ErrorReply {
            code: ErrorCode::BadMission,
            value: 4,
            limit: 0,
            detail: 1,
        };
        assert!(explain_bad_mission(&a, &RobotConfig::DEFAULT, &off).contains("the goal of"));
        assert!(explain_bad_mission(&a, &RobotConfig::DEFAULT, &off).contains("lies off its map"));
    }
}
