//! The counters a mission keeps ([`MissionStats`]): stops, sweeps, plans, cuts, readings,
//! distance and time. They are what `twil simulate --json`, the recordings and the link's
//! status report; every one is bumped where its event happens (`machine`, `sweep`, `planning`,
//! `prefix`), never recomputed.

use crate::plan::PlanError;

use super::UnreachableReason;

/// Counters of a mission.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MissionStats {
    /// Places the robot stood to sweep (the seed's stops): a full sweep where the robot has
    /// just swept standing counts with that stop; `full_sweeps` counts full sweeps.
    pub stops: u32,
    /// Sweeps taken while moving (continuous mode).
    pub moving_sweeps: u32,
    /// Full ±180° sweeps (all standing).
    pub full_sweeps: u32,
    /// Planner runs.
    pub plans: u32,
    /// Planner runs after the first one.
    pub replans: u32,
    /// Continuous mode: replans whose new obstacles blocked the remaining path.
    pub blocked_replans: u32,
    /// Continuous mode: prefixes cut to the swept band instead of stopping for a full sweep.
    pub band_cuts: u32,
    /// Prefixes shortened so that the sonar's blind zone at their end is known (`blind`).
    pub blind_cuts: u32,
    /// Sonar readings taken.
    pub readings: u32,
    /// Hits marked in the grid.
    pub hits: u32,
    /// Distance travelled by the odometry, metres.
    pub odometry_distance_m: f32,
    /// Mission time, seconds.
    pub time_s: f32,
    /// Controller periods that overran.
    pub controller_overruns: u32,
    /// Controller periods with a saturated voltage.
    pub saturated_periods: u32,
    /// Set when the status is [`MissionStatus::Unreachable`](super::MissionStatus::Unreachable).
    pub unreachable_reason: Option<UnreachableReason>,
    /// Planner scratch/queue/path errors met (the mission aborts on them).
    pub plan_errors: u32,
    /// The last planner error, if any.
    #[serde(skip)]
    pub last_plan_error: Option<PlanError>,
}

impl MissionStats {
    /// Every counter 0 (`Default`, usable in `const` contexts).
    pub const ZERO: Self = Self {
        stops: 0,
        moving_sweeps: 0,
        full_sweeps: 0,
        plans: 0,
        replans: 0,
        blocked_replans: 0,
        band_cuts: 0,
        blind_cuts: 0,
        readings: 0,
        hits: 0,
        odometry_distance_m: 0.0,
        time_s: 0.0,
        controller_overruns: 0,
        saturated_periods: 0,
        unreachable_reason: None,
        plan_errors: 0,
        last_plan_error: None,
    };
}
