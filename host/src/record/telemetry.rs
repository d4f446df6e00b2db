//! What `twil mission` records from the device's telemetry: the same topics as the
//! simulator, from what the telemetry carries (poses at 5 Hz with the voltages, phases, each
//! sweep's hits, each plan), timestamps in the device's mission time.

use twil_core::control::Pose;
use twil_core::geom::PointM;
use twil_core::grid::Grid400;
use twil_core::link::MissionReport;
use twil_core::mission::{MissionPhase, MissionStatus};

use super::topics::{StatusMessage, WorldScene};
use super::Recorder;
use crate::sim::TrajectoryRow;
use twil_core::robot::RobotConfig;

/// A [`Recorder`] fed by `twil mission`'s follower.
pub struct TelemetryRecorder {
    recorder: Recorder,
    normal_half_rad: f32,
    full_half_rad: f32,
    range_m: f32,
}

impl TelemetryRecorder {
    /// Start recording a mission of `robot` in `scene`: `/world` and the first `/map`
    /// (`grid`: the known obstacles) at time 0.
    pub fn new(
        mut recorder: Recorder,
        scene: &WorldScene,
        robot: &RobotConfig,
        grid: &Grid400,
    ) -> Self {
        recorder.world(0.0, scene);
        recorder.map(0.0, grid);
        recorder.tick(0.0);
        Self {
            recorder,
            normal_half_rad: robot.normal_half_sweep_deg.to_radians(),
            full_half_rad: robot.full_half_sweep_deg.to_radians(),
            range_m: robot.sonar_range_m,
        }
    }

    /// The device's final report: no plan any more if it ended unreachable, and the last
    /// `/status`.
    pub fn finished(&mut self, report: &MissionReport) {
        let t_s = report.stats.time_s;
        if report.status == MissionStatus::Unreachable {
            self.recorder.plan(t_s, &[], &[]);
        }
        let counts = (report.stats.plans, report.stats.stops);
        let done = Some(MissionPhase::Done);
        self.status(t_s, done, report.status, "finished", counts);
    }

    /// A pose report, as its trajectory row.
    pub fn pose(&mut self, row: &TrajectoryRow) {
        self.recorder.tick(row.t_s);
        self.recorder.pose(row.t_s, &row.pose);
        self.recorder.control(row.t_s, &row.control);
    }

    /// A phase change: `/status`, and `/band` when a sweep starts (standing: the device
    /// reports no moving sweeps).
    pub fn phase(
        &mut self,
        t_s: f32,
        phase: MissionPhase,
        status: MissionStatus,
        pose: &Pose,
        counts: (u32, u32),
    ) {
        if let MissionPhase::Sweep { full } = phase {
            let half = if full {
                self.full_half_rad
            } else {
                self.normal_half_rad
            };
            self.recorder.band(t_s, pose, half, self.range_m);
        }
        self.status(t_s, Some(phase), status, "phase", counts);
    }

    /// A sweep's hits have all arrived: `/sonar` and the map they changed.
    pub fn sweep(&mut self, t_s: f32, hits: &[PointM], grid: &Grid400) {
        self.recorder.sonar(t_s, hits);
        self.recorder.map(t_s, grid);
    }

    /// A plan has all arrived (or will get no more): `/plan`, `/prefix`.
    pub fn plan(&mut self, t_s: f32, path: &[PointM], prefix: &[PointM]) {
        self.recorder.plan(t_s, path, prefix);
    }

    /// `/status` with `event`; `counts` are (plans, stops).
    pub fn status(
        &mut self,
        t_s: f32,
        phase: Option<MissionPhase>,
        status: MissionStatus,
        event: &str,
        counts: (u32, u32),
    ) {
        self.recorder.status(StatusMessage {
            t_s,
            phase: phase.map_or("starting", MissionPhase::as_str).into(),
            status: status.as_str().into(),
            event: event.into(),
            plans: counts.0,
            stops: counts.1,
        });
    }

    /// The recorder, to close it.
    pub fn into_recorder(self) -> Recorder {
        self.recorder
    }
}
