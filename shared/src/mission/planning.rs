//! Plan handling: ask for a plan ([`PlanRequest`]) from where the robot is, with the stall
//! check that ends a mission making no progress, and take the result back: end the mission
//! on a verdict, or keep a prefix (`prefix`) and follow it.
//!
//! The mission never runs the planner (see the module documentation): a request is a
//! [`PendingPlan`] until its result comes back, and nothing the planner reads changes
//! meanwhile.

use crate::geom::{Cell, PointM};
use crate::grid::Grid;
use crate::math::hypot;
use crate::plan::{PlanError, PlanReport, PlanStatus};
use crate::raster::BresenhamLine;

use super::messages::{push, push_planned};
use super::{
    Mission, MissionEvent, MissionMode, MissionOutput, MissionPhase, MissionStatus, PendingPlan,
    PilotCommand, PlanRequest, UnreachableReason, MAX_SUSPECT_REPLANS,
};

impl<const W: usize, const E: usize> Mission<W, E> {
    /// Continuous mode: does an occupied cell lie on what remains of the path?
    pub(super) fn remaining_path_blocked(&self) -> bool {
        let from = (self.supply_segment as usize).min(self.path.len());
        let g = *self.grid.geometry();
        let Some(rest) = self.path.get(from..) else {
            return false;
        };
        for w in rest.windows(2) {
            let (Some(a), Some(b)) = (g.cell_xy_of(w[0]), g.cell_xy_of(w[1])) else {
                continue;
            };
            if BresenhamLine::new(a, b).any(|(x, y)| self.grid.is_occupied_xy(x, y)) {
                return true;
            }
        }
        false
    }

    /// Ask for a plan from where the robot is (or, moving, from where it is told to be); its
    /// result is handled by [`Self::on_plan_done`].
    pub(super) fn plan_and_go(&mut self, blocked: bool, out: &mut MissionOutput) {
        let moving = matches!(self.phase, MissionPhase::Follow | MissionPhase::Settle)
            && self.config.mode == MissionMode::Continuous;
        let origin = self.plan_origin(moving);

        // Stall detection.
        match self.last_plan_origin {
            Some(prev)
                if hypot(origin.x_m - prev.x_m, origin.y_m - prev.y_m)
                    < self.config.stall_distance_m =>
            {
                self.stalled_plans = self.stalled_plans.saturating_add(1)
            }
            _ => {
                self.stalled_plans = 0;
                self.suspect_replans = 0;
            }
        }
        self.last_plan_origin = Some(origin);
        if self.stalled_plans >= self.config.max_stalled_plans {
            // Plans from moving or half sweeps can alternate between two ways round an
            // obstacle (each sweep sees the side the other hid): look all round, standing,
            // once per place before giving up.
            let looked_here = self.stall_sweep_at.is_some_and(|p| {
                hypot(origin.x_m - p.x_m, origin.y_m - p.y_m) < self.config.stall_distance_m
            });
            if !looked_here {
                self.stall_sweep_at = Some(origin);
                self.stalled_plans = 0;
                self.last_plan_origin = None;
                push(out, MissionEvent::FullSweepRequested);
                self.begin_standing_sweep(true, out);
                return;
            }
            self.stats.unreachable_reason = Some(UnreachableReason::NoProgress);
            self.finish(MissionStatus::Unreachable, out);
            return;
        }

        self.ask_plan_from(origin, moving, blocked, false, out);
    }

    /// Plan again from where the robot stands after marking a suspect (`prefix`): each such
    /// plan changes the map, so it is not a stall, but a place gets at most
    /// [`MAX_SUSPECT_REPLANS`] of them before they count as stalls again.
    pub(super) fn replan_round_suspect(&mut self, out: &mut MissionOutput) {
        if self.suspect_replans >= MAX_SUSPECT_REPLANS {
            self.plan_and_go(true, out);
            return;
        }
        self.suspect_replans += 1;
        let origin = self.plan_origin(false);
        self.last_plan_origin = Some(origin);
        self.ask_plan_from(origin, false, true, false, out);
    }

    /// The evidence map's proof (`verdict`): a standing plan on the grid as it is now (redrawn
    /// from confirmed marks), outside the stall count.
    pub(super) fn ask_plan(&mut self, proof: bool, out: &mut MissionOutput) {
        let origin = self.plan_origin(false);
        self.ask_plan_from(origin, false, false, proof, out);
    }

    fn ask_plan_from(
        &mut self,
        origin: PointM,
        moving: bool,
        blocked: bool,
        proof: bool,
        out: &mut MissionOutput,
    ) {
        // The planner starts from the nearest free cell (the robot may stand in the expansion
        // of an obstacle it has just seen: the body is smaller than the planning radius).
        let g = *self.grid.geometry();
        let start_point = match g.cell_xy_of(origin) {
            Some((x, y)) => match nearest_free(&self.grid, x, y, self.expansion_cells as i32) {
                Some(c) => g.center_of(c),
                None => origin,
            },
            None => origin,
        };
        // A proof plan (on the confirmed marks alone, `verdict`) is no plan the robot follows:
        // the counts, and the pictures drawn per plan, leave it out.
        if !proof {
            self.stats.plans += 1;
            if self.stats.plans > 1 {
                self.stats.replans += 1;
            }
        }
        let id = self.next_plan_id;
        self.next_plan_id = self.next_plan_id.wrapping_add(1).max(1);
        let asked_at = self.position_world();
        let pass_spread_m = if moving {
            self.readings
                .as_slice()
                .iter()
                .map(|r| hypot(r.pose.x_m - asked_at.x_m, r.pose.y_m - asked_at.y_m))
                .filter(|d| d.is_finite())
                .fold(0.0, f32::max)
        } else {
            0.0
        };
        self.pending_plan = Some(PendingPlan {
            id,
            blocked,
            moving,
            proof,
            cancelled: false,
            asked_at,
            pass_spread_m,
        });
        if !moving {
            // Hold where the controller is heading now until the result is back.
            out.pilot_command = Some(PilotCommand::Hold);
            self.phase = MissionPhase::Plan;
        }
        out.plan_request = Some(PlanRequest {
            id,
            kind: self.config.planner,
            start: start_point,
            goal: self.plan_goal(),
        });
    }

    /// Where a new trajectory starts: the robot, or while moving the point the supplier hands
    /// out now (the reference model is a little behind it), so motion is continuous.
    fn plan_origin(&self, moving: bool) -> PointM {
        if moving && self.phase == MissionPhase::Follow {
            self.frame.odom_to_world(self.supply_point_odom)
        } else {
            self.position_world()
        }
    }

    /// A plan is back: prune it, then follow, ask for a full sweep, or end. Then mark a sweep
    /// that ended meanwhile.
    pub(super) fn on_plan_done(
        &mut self,
        id: u32,
        result: Result<PlanReport, PlanError>,
        out: &mut MissionOutput,
    ) {
        let Some(pending) = self.pending_plan else {
            return; // Nobody asked: ignored.
        };
        if pending.id != id {
            return;
        }
        self.pending_plan = None;
        if pending.cancelled {
            if pending.proof {
                // The grid holds the confirmed marks only: back to the full map.
                self.redraw_grid(false);
            }
        } else if pending.proof {
            match result {
                Ok(r) => self.on_proof(r.status, out),
                Err(e) => {
                    self.redraw_grid(false);
                    self.stats.plan_errors += 1;
                    self.stats.last_plan_error = Some(e);
                    self.finish(MissionStatus::Aborted, out);
                }
            }
        } else {
            self.apply_plan(pending, result, out);
        }
        if let Some(sweep) = self.deferred_sweep_end.take() {
            if self.pending_plan.is_some() {
                // The result asked for another plan (the evidence map's verdicts): the grid
                // is the planner's again until that one is back.
                self.deferred_sweep_end = Some(sweep);
            } else if self.status == MissionStatus::Running {
                self.end_of_sweep(sweep, out);
            }
        }
    }

    fn apply_plan(
        &mut self,
        pending: PendingPlan,
        result: Result<PlanReport, PlanError>,
        out: &mut MissionOutput,
    ) {
        let blocked = pending.blocked;
        let moving = pending.moving;
        // The robot went on while the planner ran (moving) or drifted a little (holding): the
        // trajectory starts where it is now.
        let origin = self.plan_origin(moving);
        let report = match result {
            Ok(r) => r,
            Err(e) => {
                self.stats.plan_errors += 1;
                self.stats.last_plan_error = Some(e);
                self.finish(MissionStatus::Aborted, out);
                return;
            }
        };
        match report.status {
            PlanStatus::Found => {}
            PlanStatus::Unreachable | PlanStatus::GoalBlocked if self.proves_verdicts() => {
                // Tentative marks may be what blocks: prove it or visit the gap (`verdict`).
                push_planned(out, report.status, blocked, 0);
                self.seek_proof(out);
                return;
            }
            PlanStatus::Unreachable => {
                push_planned(out, report.status, blocked, 0);
                self.stats.unreachable_reason = Some(UnreachableReason::NoPath);
                self.finish(MissionStatus::Unreachable, out);
                return;
            }
            PlanStatus::GoalBlocked => {
                push_planned(out, report.status, blocked, 0);
                self.stats.unreachable_reason = Some(UnreachableReason::GoalBlocked);
                self.finish(MissionStatus::Unreachable, out);
                return;
            }
            PlanStatus::StartBlocked => {
                // No free cell near the robot: stand, sweep all round and try again (the stall
                // counter ends this if it never frees up).
                push_planned(out, report.status, blocked, 0);
                self.path.clear();
                self.begin_standing_sweep(true, out);
                return;
            }
            PlanStatus::OutOfBounds => {
                push_planned(out, report.status, blocked, 0);
                self.finish(MissionStatus::Aborted, out);
                return;
            }
        }

        self.keep_prefix(&pending, origin);
        push_planned(out, report.status, blocked, self.prefix.len() as u16);
        if !self.fit_prefix_to_sweep(moving, out) {
            return; // A full sweep comes first.
        }

        // Follow (the pilot turns in place first when the prefix starts elsewhere). What the
        // supplier would refuse ends the mission here instead of leaving the robot holding.
        let followable = self.pose_odom.heading_rad.is_finite()
            && self.prefix.len() <= crate::trajectory::MAX_TRAJECTORY_POINTS
            && self.prefix.iter().all(|p| p.is_finite());
        if followable {
            self.phase = MissionPhase::Follow;
            out.pilot_command = Some(PilotCommand::Follow);
        } else {
            self.finish(MissionStatus::Aborted, out);
        }
    }

    /// How far the robot may be from where the readings behind a plan were taken, metres: 0
    /// for a standing sweep; for a moving pass, the farthest reading pose from where the plan
    /// was asked plus how far the trajectory's origin has moved since (triangle inequality).
    /// The seed's prefix rule (within `sonar range − planning radius` of the robot, visible)
    /// assumes the sweep was taken where the prefix starts; a moving pass's readings are up to
    /// `speed × (pass time + plan latency)` behind (0.77 m at 0.2 m/s, 3.8 s passes), so the
    /// rule's distance is shortened by this much. Without it the robot drove into a wall ahead
    /// that the pass had not reached: `worlds/corridor` in continuous mode at 0.25 m/s.
    /// Space seen free (the seen-space rule) stays trusted however old the reading.
    pub(super) fn stale_m(pending: &PendingPlan, origin: PointM) -> f32 {
        if !pending.moving {
            return 0.0;
        }
        let moved_m = hypot(
            origin.x_m - pending.asked_at.x_m,
            origin.y_m - pending.asked_at.y_m,
        );
        let stale_m = pending.pass_spread_m + moved_m;
        if stale_m.is_finite() {
            stale_m
        } else {
            f32::MAX
        }
    }
}

/// The free cell nearest to (`x`, `y`) in growing square rings up to `max_ring`, or `None`.
fn nearest_free<const W: usize>(grid: &Grid<W>, x: i32, y: i32, max_ring: i32) -> Option<Cell> {
    let g = grid.geometry();
    if !grid.is_occupied_xy(x, y) {
        return g.cell_xy(x, y);
    }
    for r in 1..=max_ring.max(1) {
        let mut best: Option<(i32, Cell)> = None;
        for dy in -r..=r {
            for dx in -r..=r {
                if dx.abs() != r && dy.abs() != r {
                    continue;
                }
                let (cx, cy) = (x + dx, y + dy);
                if let Some(c) = g.cell_xy(cx, cy) {
                    if !grid.is_occupied(c) {
                        let d2 = dx * dx + dy * dy;
                        if best.is_none_or(|(b, _)| d2 < b) {
                            best = Some((d2, c));
                        }
                    }
                }
            }
        }
        if let Some((_, c)) = best {
            return Some(c);
        }
    }
    None
}
