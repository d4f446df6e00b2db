//! Why each plan happened, read from the mission's events (for the pictures' captions), and
//! the band the latest sweep covered.
//!
//! The mission asks for a plan after every sweep; what led to that sweep is in the events
//! before it: the first sweep at the start, the end of a prefix (the robot stopped there and
//! swept), a full sweep asked for because the kept prefix left the ±band, or (continuous mode)
//! the end of a moving pass, whose new obstacles may block the path.

use twil_core::mission::{MissionEvent, MissionMode, MissionPhase};
use twil_core::plan::PlanStatus;

/// Why a plan was made.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlanReason {
    /// The first plan, after the first sweep at the start.
    First,
    /// The robot reached the end of its prefix short of the goal, stopped and swept.
    PrefixEnd,
    /// The kept prefix left the swept band: a full ±180° sweep, then this plan.
    BandFullSweep,
    /// A moving sweep found new obstacles on the rest of the path.
    Blocked,
    /// A moving sweep pass ended (continuous mode replans after every pass).
    MovingPass,
    /// A sweep ended (no more specific cause seen).
    Sweep,
}

impl PlanReason {
    /// A short sentence for a caption.
    pub fn text(self) -> &'static str {
        match self {
            PlanReason::First => "first plan, after the first sweep at the start",
            PlanReason::PrefixEnd => "prefix end reached: the robot stopped, swept and replanned",
            PlanReason::BandFullSweep => {
                "the kept prefix left the swept band: full ±180° sweep, then replan"
            }
            PlanReason::Blocked => "the moving sweep found an obstacle on the path: replan",
            PlanReason::MovingPass => "a moving sweep pass ended: routine replan",
            PlanReason::Sweep => "a sweep ended: replan",
        }
    }
}

/// The band the latest sweep covered, either side of the robot's heading.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SweepBand {
    /// Half-angle, degrees (180 for a full sweep).
    pub half_angle_deg: f32,
    /// Taken while moving.
    pub moving: bool,
}

/// Follows the events of a mission; see the module documentation.
#[derive(Clone, Debug)]
pub struct ReasonTracker {
    standing_half_deg: f32,
    moving_half_deg: f32,
    plans: u32,
    prefix_ended: bool,
    full_requested: bool,
    last_sweep: Option<SweepBand>,
    last_reason: Option<PlanReason>,
    last_status: Option<PlanStatus>,
    mode: MissionMode,
}

impl ReasonTracker {
    /// A tracker for sweeps of `standing_half_deg` (stopped) and `moving_half_deg` (moving).
    pub fn new(mode: MissionMode, standing_half_deg: f32, moving_half_deg: f32) -> Self {
        Self {
            standing_half_deg,
            moving_half_deg,
            plans: 0,
            prefix_ended: false,
            full_requested: false,
            last_sweep: None,
            last_reason: None,
            last_status: None,
            mode,
        }
    }

    /// Take the events of one tick, in order.
    pub fn observe(&mut self, events: &[MissionEvent]) {
        for e in events {
            match *e {
                MissionEvent::SweepStarted { full, moving } => {
                    let half_angle_deg = if full {
                        180.0
                    } else if moving {
                        self.moving_half_deg
                    } else {
                        self.standing_half_deg
                    };
                    self.last_sweep = Some(SweepBand {
                        half_angle_deg,
                        moving,
                    });
                }
                MissionEvent::EndOfTrajectory => self.prefix_ended = true,
                MissionEvent::FullSweepRequested => self.full_requested = true,
                MissionEvent::Planned {
                    status, blocked, ..
                } => {
                    self.plans += 1;
                    let reason = if self.plans == 1 {
                        PlanReason::First
                    } else if blocked {
                        PlanReason::Blocked
                    } else if self.full_requested {
                        PlanReason::BandFullSweep
                    } else if self.prefix_ended {
                        PlanReason::PrefixEnd
                    } else if self.last_sweep.is_some_and(|s| s.moving)
                        && self.mode == MissionMode::Continuous
                    {
                        PlanReason::MovingPass
                    } else {
                        PlanReason::Sweep
                    };
                    self.last_reason = Some(reason);
                    self.last_status = Some(status);
                    self.prefix_ended = false;
                    self.full_requested = false;
                }
                _ => {}
            }
        }
    }

    /// Why the latest plan was made (`None` before the first).
    pub fn reason(&self) -> Option<PlanReason> {
        self.last_reason
    }

    /// The planner's verdict on the latest plan.
    pub fn status(&self) -> Option<PlanStatus> {
        self.last_status
    }

    /// The band of the latest sweep (`None` before the first).
    pub fn band(&self) -> Option<SweepBand> {
        self.last_sweep
    }
}

/// The mission events that the phases a device reported before its plan at `t_ms` stand for
/// (`twil mission` has the device's phase changes, not its events), taken out of `phases`
/// (mission time in ms, phase; in arrival order), followed by the plan itself.
///
/// A standing sweep starts a sweep (a full one after the first plan was asked for because
/// the prefix left the band), settling means the prefix ended, and no standing sweep since
/// the last plan means a sweep taken while moving. Phases stamped at `t_ms` or later are the
/// plan's consequences (the device reports the phase change before the plan that caused it),
/// so they stay in `phases` for the next plan. The telemetry does not say whether a moving
/// sweep found the path blocked: `blocked` is always `false`.
pub fn events_before_plan(
    phases: &mut Vec<(u32, MissionPhase)>,
    t_ms: u32,
    status: PlanStatus,
    first_plan: bool,
) -> Vec<MissionEvent> {
    let mut events = Vec::new();
    let mut swept = false;
    let causes = phases.iter().take_while(|(t, _)| *t < t_ms).count();
    for (_, phase) in phases.drain(..causes) {
        match phase {
            MissionPhase::Sweep { full } => {
                if full && !first_plan {
                    events.push(MissionEvent::FullSweepRequested);
                }
                events.push(MissionEvent::SweepStarted {
                    full,
                    moving: false,
                });
                swept = true;
            }
            MissionPhase::Settle => events.push(MissionEvent::EndOfTrajectory),
            _ => {}
        }
    }
    if !swept && !first_plan {
        events.push(MissionEvent::SweepStarted {
            full: false,
            moving: true,
        });
    }
    events.push(MissionEvent::Planned {
        status,
        blocked: false,
        prefix_points: 0,
    });
    events
}

#[cfg(test)]
mod tests {
    use super::*;

    fn planned(blocked: bool) -> MissionEvent {
        MissionEvent::Planned {
            status: PlanStatus::Found,
            blocked,
            prefix_points: 3,
        }
    }

    #[test]
    fn stop_mode_reasons_follow_the_events_before_each_plan() {
        let mut t = ReasonTracker::new(MissionMode::Stop, 95.0, 60.0);
        assert_eq!(t.reason(), None);
        t.observe(&[MissionEvent::SweepStarted {
            full: false,
            moving: false,
        }]);
        assert_eq!(t.band().unwrap().half_angle_deg, 95.0);
        t.observe(&[planned(false)]);
        assert_eq!(t.reason(), Some(PlanReason::First));
        t.observe(&[MissionEvent::FullSweepRequested]);
        t.observe(&[MissionEvent::SweepStarted {
            full: true,
            moving: false,
        }]);
        assert_eq!(t.band().unwrap().half_angle_deg, 180.0);
        t.observe(&[planned(false)]);
        assert_eq!(t.reason(), Some(PlanReason::BandFullSweep));
        t.observe(&[MissionEvent::EndOfTrajectory, MissionEvent::Settled]);
        t.observe(&[planned(false)]);
        assert_eq!(t.reason(), Some(PlanReason::PrefixEnd));
        t.observe(&[planned(false)]);
        assert_eq!(t.reason(), Some(PlanReason::Sweep));
    }

    #[test]
    fn continuous_mode_tells_blocked_from_routine_passes() {
        let mut t = ReasonTracker::new(MissionMode::Continuous, 95.0, 60.0);
        t.observe(&[planned(false)]);
        t.observe(&[MissionEvent::SweepStarted {
            full: false,
            moving: true,
        }]);
        assert_eq!(t.band().unwrap().half_angle_deg, 60.0);
        t.observe(&[planned(true)]);
        assert_eq!(t.reason(), Some(PlanReason::Blocked));
        t.observe(&[planned(false)]);
        assert_eq!(t.reason(), Some(PlanReason::MovingPass));
    }

    /// The phases `twil mission --remote sim` reports on the office (stop mode), and the
    /// reasons they give: each plan explained by what came before it, not by its consequences.
    #[test]
    fn device_phases_explain_each_plan() {
        use MissionPhase::{Follow, Settle, Sweep};
        let mut phases = Vec::new();
        let mut t = ReasonTracker::new(MissionMode::Stop, 95.0, 95.0);
        let mut plan = |phases: &mut Vec<(u32, MissionPhase)>, t_ms: u32| {
            let first = t.reason().is_none();
            t.observe(&events_before_plan(phases, t_ms, PlanStatus::Found, first));
            (t.reason().unwrap(), t.band().unwrap().half_angle_deg)
        };
        phases.extend([(50, Sweep { full: false }), (3800, Sweep { full: true })]);
        assert_eq!(plan(&mut phases, 3800), (PlanReason::First, 95.0));
        phases.push((11050, Follow));
        assert_eq!(plan(&mut phases, 11050), (PlanReason::BandFullSweep, 180.0));
        phases.extend([
            (16300, Settle),
            (20350, Sweep { full: false }),
            (24100, Follow),
        ]);
        assert_eq!(plan(&mut phases, 24100), (PlanReason::PrefixEnd, 95.0));
        phases.extend([(30050, Settle), (34100, Sweep { full: false })]);
        phases.push((37850, Sweep { full: true }));
        assert_eq!(plan(&mut phases, 37850), (PlanReason::PrefixEnd, 95.0));
        phases.push((45100, Follow));
        assert_eq!(plan(&mut phases, 45100), (PlanReason::BandFullSweep, 180.0));
        // Continuous mode: a plan with no standing sweep since the last one came from a
        // sweep taken while moving.
        assert_eq!(plan(&mut phases, 47000), (PlanReason::Sweep, 95.0));
        assert!(t.band().unwrap().moving);
        assert!(phases.is_empty());
    }
}
