//! The simulator's [`Observer`] that records and serves a mission as it runs, paced to the
//! wall clock for the live view.

use std::ops::ControlFlow;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use twil_core::mission::{Mission400, MissionEvent, MissionPhase, MissionStatus};

use super::topics::{StatusMessage, WorldScene};
use super::Recorder;
use crate::sim::{Observer, SimSetup, TickView, TrajectoryRow};

/// Runs mission time at `speed` times the wall clock.
#[derive(Clone, Copy, Debug)]
pub struct Pace {
    start: Instant,
    speed: f64,
}

impl Pace {
    /// Mission time 0 is now; `speed` > 0 (2 = twice as fast as real time).
    pub fn new(speed: f64) -> Self {
        Self {
            start: Instant::now(),
            speed,
        }
    }

    /// Sleep until mission time `t_s` is due on the wall clock.
    pub fn wait_for(&self, t_s: f32) {
        let due_s = (t_s.max(0.0) as f64) / self.speed;
        if !due_s.is_finite() {
            return;
        }
        let due = self.start + Duration::from_secs_f64(due_s.min(1.0e9));
        let now = Instant::now();
        if due > now {
            std::thread::sleep(due - now);
        }
    }
}

/// The sweep half-angles and range a setup's sweeps use, for `/band`.
#[derive(Clone, Copy, Debug)]
struct SweepShape {
    normal_half_rad: f32,
    full_half_rad: f32,
    moving_half_rad: f32,
    range_m: f32,
}

/// Records (and serves) a simulated mission: see the module documentation.
pub struct SimRecorder {
    recorder: Recorder,
    scene: SceneParts,
    shape: SweepShape,
    pace: Option<Pace>,
    stop: &'static AtomicBool,
    last: Option<(MissionPhase, MissionStatus)>,
}

/// What `/world` needs from the setup (owned: the observer outlives no borrow).
struct SceneParts {
    real: twil_core::world::Obstacles,
    known: Option<twil_core::world::Obstacles>,
    start: twil_core::geom::PointM,
    goal: twil_core::geom::PointM,
    body_radius_m: f32,
}

impl SimRecorder {
    /// Record `setup`'s mission into `recorder`; `pace` paces it to the wall clock; a set
    /// `stop` (Ctrl-C) ends the mission at the next tick.
    pub fn new(
        recorder: Recorder,
        setup: &SimSetup,
        pace: Option<Pace>,
        stop: &'static AtomicBool,
    ) -> Self {
        let robot = &setup.robot;
        Self {
            recorder,
            scene: SceneParts {
                real: setup.real.clone(),
                known: setup.known.clone(),
                start: setup.params.start,
                goal: setup.params.goal,
                body_radius_m: (setup.params.robot_radius_m - twil_core::robot::PLANNING_MARGIN_M)
                    .max(0.05),
            },
            shape: SweepShape {
                normal_half_rad: robot.normal_half_sweep_deg.to_radians(),
                full_half_rad: robot.full_half_sweep_deg.to_radians(),
                moving_half_rad: setup.moving_half_sweep_deg.to_radians(),
                range_m: robot.sonar_range_m,
            },
            pace,
            stop,
            last: None,
        }
    }

    /// The recorder, to close it once the run is over.
    pub fn into_recorder(self) -> Recorder {
        self.recorder
    }

    fn status(&mut self, t_s: f32, mission: &Mission400, event: &str) {
        let stats = mission.stats();
        self.recorder.status(StatusMessage {
            t_s,
            phase: mission.phase().as_str().into(),
            status: mission.status().as_str().into(),
            event: event.into(),
            plans: stats.plans,
            stops: stats.stops,
        });
        self.last = Some((mission.phase(), mission.status()));
    }
}

/// A short name of an event for `/status`.
pub fn event_name(event: &MissionEvent) -> &'static str {
    match event {
        MissionEvent::SweepStarted { full: true, .. } => "full sweep started",
        MissionEvent::SweepStarted { moving: true, .. } => "moving sweep started",
        MissionEvent::SweepStarted { .. } => "sweep started",
        MissionEvent::SweepDone { .. } => "sweep done",
        MissionEvent::Planned { blocked: true, .. } => "planned (path blocked)",
        MissionEvent::Planned { .. } => "planned",
        MissionEvent::FullSweepRequested => "full sweep requested (prefix leaves the band)",
        MissionEvent::EndOfTrajectory => "end of prefix",
        MissionEvent::Settled => "settled",
        MissionEvent::Finished(_) => "finished",
    }
}

impl Observer for SimRecorder {
    fn start(&mut self, mission: &Mission400) {
        let scene = WorldScene {
            real: Some(&self.scene.real),
            known: self.scene.known.as_ref(),
            start: self.scene.start,
            goal: self.scene.goal,
            body_radius_m: Some(self.scene.body_radius_m),
        };
        self.recorder.world(0.0, &scene);
        self.recorder.map(0.0, mission.grid());
        self.status(0.0, mission, "start");
        self.recorder.tick(0.0);
    }

    fn tick(&mut self, view: &TickView) -> ControlFlow<()> {
        let (t_s, mission) = (view.t_s, view.mission);
        self.recorder.tick(t_s);
        for event in view.events {
            match *event {
                MissionEvent::SweepStarted { full, moving } => {
                    let half = if full {
                        self.shape.full_half_rad
                    } else if moving {
                        self.shape.moving_half_rad
                    } else {
                        self.shape.normal_half_rad
                    };
                    let pose = mission.pose_world();
                    self.recorder.band(t_s, &pose, half, self.shape.range_m);
                }
                MissionEvent::SweepDone { .. } => {
                    self.recorder.sonar(t_s, mission.last_hits());
                    self.recorder.map(t_s, mission.grid());
                }
                MissionEvent::Planned { .. } => {
                    self.recorder.plan(t_s, mission.path(), mission.prefix());
                }
                MissionEvent::Finished(MissionStatus::Unreachable) => {
                    // The mission still holds the last plan; it is not followed any more.
                    self.recorder.plan(t_s, &[], &[]);
                }
                _ => {}
            }
            self.status(t_s, mission, event_name(event));
        }
        if view.events.is_empty() && self.last != Some((mission.phase(), mission.status())) {
            self.status(t_s, mission, "");
        }
        if let Some(pace) = &self.pace {
            pace.wait_for(t_s);
        }
        if self.stop.load(Ordering::SeqCst) {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    }

    fn row(&mut self, row: &TrajectoryRow) {
        self.recorder.pose(row.t_s, &row.pose);
        self.recorder.control(row.t_s, &row.control);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pace_waits_for_mission_time_at_its_speed() {
        let pace = Pace::new(100.0);
        let started = Instant::now();
        // 2 s of mission time at 100 times the wall clock: 20 ms.
        pace.wait_for(2.0);
        let waited = started.elapsed();
        assert!(waited >= Duration::from_millis(19), "{waited:?}");
        assert!(waited < Duration::from_millis(500), "{waited:?}");
        // Mission time already due: no wait.
        let again = Instant::now();
        pace.wait_for(1.0);
        assert!(again.elapsed() < Duration::from_millis(5));
    }
}
