//! What goes into and out of [`Mission::step`](super::Mission::step): the inputs, the requests the
//! shell must serve (a sonar reading, a plan), the events and the status and phase they report.
//!
//! These are the whole interface between the mission and its shell (the firmware,
//! [`super::LocalRunner`], the link's robot): plain `Copy` values, no references into the
//! mission, so that a shell can queue them or send them over the link.

use heapless::Vec;

use crate::geom::PointM;
use crate::plan::{PlanError, PlanReport, PlanStatus, PlannerKind};

use super::{PilotCommand, PilotReport, MAX_EVENTS_PER_STEP};

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
    /// Evidence map: the goal is cut off by confirmed marks alone (a plan on them found no
    /// way): the proof.
    ConfirmedCut,
    /// Evidence map: tentative marks cut the goal off and the bounded visits to the gaps they
    /// close did not settle them (no proof: the host says `gave_up`).
    GapsUnsettled,
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
    /// Ended; see [`Mission::status`](super::Mission::status).
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

/// One input of [`Mission::step`](super::Mission::step).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum MissionInput {
    /// A controller period went by: what the [`Pilot`](super::Pilot) did in it.
    Tick(PilotReport),
    /// The answer to the last [`SonarRequest`].
    SonarReading {
        /// Neck angle the reading was taken at, robot frame, radians.
        neck_angle_rad: f32,
        /// Measured range from the sonar, metres, or `None` for no echo.
        range_m: Option<f32>,
    },
    /// The result of the [`PlanRequest`] with this `id`: the planner ran on
    /// [`Mission::plan_workspace`](super::Mission::plan_workspace)'s grid and wrote its path there.
    /// Results of other ids, or when no request is out, are ignored.
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
/// The planner must run on the grid and write into the path of
/// [`Mission::plan_workspace`](super::Mission::plan_workspace): the mission does not change either
/// until the result is handed back (a sweep that ends meanwhile is marked afterwards).
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

/// What one [`Mission::step`](super::Mission::step) asks of the shell.
#[derive(Clone, Debug, PartialEq)]
pub struct MissionOutput {
    /// What the [`Pilot`](super::Pilot) must do from now on (the latest command wins; `Stop` once
    /// ended).
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

/// Record `event` in `out`.
pub(super) fn push(out: &mut MissionOutput, event: MissionEvent) {
    // Full: the oldest events are kept; the status field still tells the outcome.
    let _ = out.events.push(event);
}

/// Record a [`MissionEvent::Planned`] in `out`.
pub(super) fn push_planned(
    out: &mut MissionOutput,
    status: PlanStatus,
    blocked: bool,
    prefix_points: u16,
) {
    push(
        out,
        MissionEvent::Planned {
            status,
            blocked,
            prefix_points,
        },
    );
}
