//! A mission in one thread of control: the shell that `twil simulate` and the tests run.
//!
//! Each control period [`LocalRunner::tick`] calls, in this order:
//!
//! 1. the [`Pilot`] with the encoder counts (odometry, supplier, controller → voltages);
//! 2. the [`Mission`] with the pilot's report, then the pilot with the mission's command;
//! 3. the planner for a plan request, at once, on [`Mission::plan_workspace`]; the result is
//!    handed back `latency_ticks` periods later, after that period's controller step (with
//!    0, within this tick);
//! 4. a plan result whose latency has run out;
//! 5. every sonar request, answered by the caller's sonar (each answer is a step of its own,
//!    and may end a sweep and ask for a plan: back to 3).
//!
//! The firmware spreads the same calls over its tasks (the pilot in the control task, the
//! mission and the planner in the lowest-priority one), so a plan that takes up to a period
//! there is what `latency_ticks = 1` models here.

use heapless::Vec;

use crate::plan::{PlanError, PlanReport, Planner};
use crate::world::PolygonSet;

use super::{Mission, MissionEvent, MissionInput, MissionOutput, MissionStatus, Pilot, SimBody};

/// Most events one [`LocalRunner::tick`] collects (a tick is a handful of steps of at most
/// [`super::MAX_EVENTS_PER_STEP`] events each; more are dropped, the status still tells).
pub const MAX_EVENTS_PER_TICK: usize = 32;

/// Most sonar readings answered within one tick (the mission's own budget allows two at
/// the default timing; this only bounds a misbehaving configuration).
pub const MAX_READINGS_PER_TICK: usize = 64;

/// What one tick did.
#[derive(Clone, Debug, PartialEq)]
pub struct TickOutcome {
    /// Left motor voltage to apply until the next tick, volts (0 once the mission ended).
    pub left_voltage_v: f32,
    /// Right motor voltage, volts.
    pub right_voltage_v: f32,
    /// Everything the mission reported during the tick, in order.
    pub events: Vec<MissionEvent, MAX_EVENTS_PER_TICK>,
    /// A plan result was applied during the tick.
    pub planned: bool,
    /// The mission's status after the tick.
    pub status: MissionStatus,
}

/// A plan computed and not handed back yet.
#[derive(Clone, Copy, Debug)]
struct DuePlan {
    tick: u64,
    id: u32,
    result: Result<PlanReport, PlanError>,
}

/// The single-threaded shell: see the module documentation.
pub struct LocalRunner<'a, const W: usize, const S: usize, const Q: usize, const E: usize = W> {
    mission: &'a mut Mission<W, E>,
    planner: &'a mut Planner<S, Q>,
    pilot: Pilot,
    latency_ticks: u64,
    tick: u64,
    due: Option<DuePlan>,
}

impl<'a, const W: usize, const S: usize, const Q: usize, const E: usize>
    LocalRunner<'a, W, S, Q, E>
{
    /// A runner for `mission` (not started yet), its plans run by `planner` and handed back
    /// `latency_ticks` control periods after their request.
    pub fn new(
        mission: &'a mut Mission<W, E>,
        planner: &'a mut Planner<S, Q>,
        latency_ticks: u64,
    ) -> Self {
        let pilot = Pilot::new(mission.config());
        Self {
            mission,
            planner,
            pilot,
            latency_ticks,
            tick: 0,
            due: None,
        }
    }

    /// The mission.
    pub fn mission(&self) -> &Mission<W, E> {
        self.mission
    }

    /// The pilot.
    pub fn pilot(&self) -> &Pilot {
        &self.pilot
    }

    /// One control period; `sonar` answers a sonar request (neck angle, robot frame, radians)
    /// with a range in metres or `None` for no echo.
    pub fn tick(
        &mut self,
        left_delta_counts: i32,
        right_delta_counts: i32,
        elapsed_s: f32,
        sonar: &mut impl FnMut(f32) -> Option<f32>,
    ) -> TickOutcome {
        self.tick += 1;
        let mut outcome = TickOutcome {
            left_voltage_v: 0.0,
            right_voltage_v: 0.0,
            events: Vec::new(),
            planned: false,
            status: self.mission.status(),
        };
        let report = self
            .pilot
            .tick(left_delta_counts, right_delta_counts, elapsed_s);
        let out = self.mission.step(MissionInput::Tick(report));
        let mut sonar_request = self.settle(out, &mut outcome);
        let now = self.tick;
        if let Some(due) = self.due.take_if(|d| d.tick <= now) {
            let out = self.mission.step(MissionInput::PlanDone {
                id: due.id,
                result: due.result,
            });
            sonar_request = sonar_request.or(self.settle(out, &mut outcome));
        }
        let mut readings = 0;
        while let Some(request) = sonar_request.take() {
            if readings >= MAX_READINGS_PER_TICK {
                break;
            }
            readings += 1;
            let range_m = sonar(request.neck_angle_rad);
            let out = self.mission.step(MissionInput::SonarReading {
                neck_angle_rad: request.neck_angle_rad,
                range_m,
            });
            sonar_request = self.settle(out, &mut outcome);
        }
        let (left, right) = self.pilot.voltages_v();
        outcome.left_voltage_v = left;
        outcome.right_voltage_v = right;
        outcome.status = self.mission.status();
        outcome
    }

    /// Run the mission to its end on the simulated `body` in `world` (sonar readings up to
    /// `max_range_m`), `period_s` per tick; the last tick's outcome. The tests' reference run
    /// of a device's mission: no collision check and nothing recorded (`twil simulate` has its
    /// own loop). It ends: the mission's time limit ends every mission.
    pub fn run_on<const V: usize, const P: usize>(
        &mut self,
        body: &mut SimBody,
        world: &PolygonSet<V, P>,
        max_range_m: f32,
        period_s: f32,
    ) -> TickOutcome {
        loop {
            let (left, right) = body.encoder_deltas();
            let outcome = self.tick(left, right, period_s, &mut |angle_rad| {
                body.sonar_range_m(world, angle_rad, max_range_m)
            });
            if outcome.status != MissionStatus::Running {
                return outcome;
            }
            body.step(period_s, outcome.left_voltage_v, outcome.right_voltage_v);
        }
    }

    /// Stop the mission (e.g. the simulated robot hit something): `Aborted`, motors off.
    pub fn abort(&mut self) -> TickOutcome {
        let mut outcome = TickOutcome {
            left_voltage_v: 0.0,
            right_voltage_v: 0.0,
            events: Vec::new(),
            planned: false,
            status: self.mission.status(),
        };
        let out = self.mission.step(MissionInput::Abort);
        self.settle(out, &mut outcome);
        outcome.status = self.mission.status();
        outcome
    }

    /// Carry out what one step asked (the pilot's command, a plan request, repeatedly while
    /// plans are handed back at once); collect its events. Returns the sonar request left to
    /// answer.
    fn settle(
        &mut self,
        mut out: MissionOutput,
        outcome: &mut TickOutcome,
    ) -> Option<super::SonarRequest> {
        let mut sonar_request = None;
        loop {
            for e in out.events.iter() {
                outcome.planned |= matches!(e, MissionEvent::Planned { .. });
                let _ = outcome.events.push(*e);
            }
            if let Some(command) = out.pilot_command {
                // The mission checked the prefix before asking; a refusal leaves the pilot
                // holding, and the mission's stall and time limits end it.
                let _ = self.pilot.command(command, self.mission.prefix());
            }
            sonar_request = sonar_request.or(out.sonar_request);
            let Some(request) = out.plan_request else {
                return sonar_request;
            };
            let (grid, path) = self.mission.plan_workspace();
            let result = self
                .planner
                .plan(request.kind, grid, request.start, request.goal, path);
            if self.latency_ticks > 0 {
                self.due = Some(DuePlan {
                    tick: self.tick + self.latency_ticks,
                    id: request.id,
                    result,
                });
                return sonar_request;
            }
            out = self.mission.step(MissionInput::PlanDone {
                id: request.id,
                result,
            });
        }
    }
}
