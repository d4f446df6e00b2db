//! Sweep handling: start a sweep, hand out its readings as the sonar's time budget allows,
//! take each answer (marking the cells its ray crossed as seen), and at the end filter the
//! readings, mark the hits in the grid and ask for a plan.
//!
//! A sweep is a [`SweepState`] (a cursor over a [`SweepPlan`]), not a list of angles: the
//! angle of each reading is recomputed from the plan, so a sweep costs a few bytes in the
//! mission whatever its size. Readings keep the pose they were taken from, so a sweep taken
//! while moving marks each hit where it was.

use crate::control::Pose;
use crate::geom::PointM;
use crate::math::{cos, hypot, sin};
use crate::raster::{mark_point_m, BresenhamLine};
use crate::robot::RobotConfig;
use crate::sonar::{for_each_constant_depth_hit, RcdParams, Reading, SweepKind, SweepPlan};

use super::messages::push;
use super::{
    Mission, MissionEvent, MissionOutput, MissionPhase, SonarRequest, SweepState,
    MAX_SWEEP_READINGS,
};

const SUSPECTS: bool = false;

impl<const W: usize, const E: usize> Mission<W, E> {
    pub(super) fn start_sweep(&mut self, full: bool, moving: bool, out: &mut MissionOutput) {
        let plan = SweepPlan::new(
            &self.sweep_robot(moving),
            if full {
                SweepKind::Full
            } else {
                SweepKind::Normal
            },
        );
        let count = plan.readings().min(MAX_SWEEP_READINGS) as u16;
        self.readings.clear();
        self.blind_cells = super::swept::BlindCells::NONE;
        let reversed = self.next_sweep_reversed;
        self.next_sweep_reversed = !reversed;
        self.sweep = Some(SweepState {
            full,
            moving,
            next: 0,
            count,
            reversed,
            waiting: false,
        });
        if moving {
            self.stats.moving_sweeps += 1;
        } else {
            // A stop is a place the robot stood to sweep: a full sweep right where the last
            // standing sweep was (the band or the body corridor asked for it) is the same stop.
            let here = self.position_world();
            let same_place = self.last_stop_position.is_some_and(|p| {
                hypot(here.x_m - p.x_m, here.y_m - p.y_m) < self.config.stall_distance_m
            });
            if !same_place {
                self.stats.stops += 1;
            }
            self.last_stop_position = Some(here);
            if full {
                self.stats.full_sweeps += 1;
            }
        }
        push(out, MissionEvent::SweepStarted { full, moving });
    }

    /// The robot config a sweep is planned with: moving sweeps use
    /// [`MissionConfig::moving_half_sweep_deg`](crate::mission::MissionConfig::moving_half_sweep_deg).
    pub(super) fn sweep_robot(&self, moving: bool) -> RobotConfig {
        let mut robot = self.config.robot;
        if moving {
            robot.normal_half_sweep_deg = self.config.moving_half_sweep_deg;
        }
        robot
    }

    fn sweep_angle_rad(&self, sweep: &SweepState, index: u16) -> f32 {
        let plan = SweepPlan::new(
            &self.sweep_robot(sweep.moving),
            if sweep.full {
                SweepKind::Full
            } else {
                SweepKind::Normal
            },
        );
        let last = sweep.count.saturating_sub(1);
        let i = if sweep.reversed {
            last.saturating_sub(index)
        } else {
            index
        };
        plan.neck_angle_rad(i as usize).unwrap_or(0.0)
    }

    /// Hand out the next reading of the sweep if its time budget allows.
    pub(super) fn request_next(&mut self, out: &mut MissionOutput) {
        let reading_time = self.reading_time_s();
        let Some(mut sweep) = self.sweep else {
            return;
        };
        if sweep.waiting || sweep.next >= sweep.count || self.sonar_budget_s < reading_time {
            return;
        }
        self.sonar_budget_s -= reading_time;
        let angle = self.sweep_angle_rad(&sweep, sweep.next);
        sweep.waiting = true;
        self.sweep = Some(sweep);
        out.sonar_request = Some(SonarRequest {
            neck_angle_rad: angle,
        });
    }

    pub(super) fn on_reading(
        &mut self,
        neck_angle_rad: f32,
        range_m: Option<f32>,
        out: &mut MissionOutput,
    ) {
        let Some(mut sweep) = self.sweep else {
            return; // Nobody asked: ignored.
        };
        if !sweep.waiting {
            return;
        }
        sweep.waiting = false;
        sweep.next += 1;
        self.stats.readings += 1;
        let robot = &self.config.robot;
        let range_m = range_m.filter(|r| {
            r.is_finite() && *r >= robot.sonar_min_range_m && *r <= robot.sonar_range_m
        });
        let neck_angle_rad = if neck_angle_rad.is_finite() {
            neck_angle_rad
        } else {
            self.sweep_angle_rad(&sweep, sweep.next - 1)
        };
        let pose = self.pose_world();
        // The evidence map takes free evidence only from what a whole standing sweep vouches
        // for (`evidence_marking`): a ray's axis proves nothing in a specular world.
        if !self.config.evidence_map {
            self.mark_seen(pose, neck_angle_rad, range_m);
        }
        // Capacity is the largest sweep: cannot fail.
        let _ = self.readings.push(Reading {
            neck_angle_rad,
            range_m,
            pose,
        });
        self.sweep = Some(sweep);
        if sweep.next >= sweep.count {
            self.sweep = None;
            if self.pending_plan.is_some() {
                // The planner may be reading the grid: mark when its result is back.
                self.deferred_sweep_end = Some(sweep);
            } else {
                self.end_of_sweep(sweep, out);
            }
        } else {
            self.request_next(out);
        }
    }

    /// Mark the cells the ray of one reading crossed as seen, stopping a cell short of the
    /// echo.
    fn mark_seen(&mut self, pose: Pose, neck_angle_rad: f32, range_m: Option<f32>) {
        let robot = &self.config.robot;
        let g = *self.grid.geometry();
        // Silence proves free space a cell short of the range, as an echo a cell short of
        // itself: a surface on the range limit may have been heard on some readings and not
        // on others.
        let length_m = match range_m {
            Some(r) => r - g.resolution_m(),
            None => robot.sonar_range_m - g.resolution_m(),
        };
        let sonar = pose.point_ahead(robot.sonar_offset_m);
        let angle = pose.heading_rad + neck_angle_rad;
        let end = PointM::new(
            sonar.x_m + length_m * cos(angle),
            sonar.y_m + length_m * sin(angle),
        );
        if let Some(centre) = g.cell_xy_of(pose.position()) {
            self.evidence
                .free_plane_mut()
                .set_xy(centre.0, centre.1, true);
        }
        if length_m.is_nan() || length_m <= 0.0 {
            return;
        }
        // A sonar off the map (a runaway odometry) marks nothing: the ray could be a million
        // cells long.
        if let (Some(a), Some(b)) = (g.cell_xy_of(sonar), g.cell_xy_of(end)) {
            if !g.contains_xy(a.0, a.1) {
                return;
            }
            for (x, y) in BresenhamLine::new(a, b) {
                self.evidence.free_plane_mut().set_xy(x, y, true);
            }
        }
    }

    pub(super) fn end_of_sweep(&mut self, sweep: SweepState, out: &mut MissionOutput) {
        // Mark.
        let hits = if self.config.evidence_map {
            let hits = self.mark_reflectors();
            if !sweep.moving {
                self.mark_edge_chains();
            }
            if !sweep.moving {
                self.blind_cells = self.find_blind_cells(self.pose_world());
                self.mark_vouched_free(sweep.full);
            }
            self.apply_take_backs();
            if sweep.full && !sweep.moving && SUSPECTS {
                self.mark_suspects();
            }
            hits
        } else {
            self.mark_readings()
        };
        push(out, MissionEvent::SweepDone { hits });
        self.last_sweep_full = sweep.full;
        if sweep.moving {
            // Continuous: only replan if still following (a settle may have ended the pass).
            if matches!(self.phase, MissionPhase::Follow | MissionPhase::Settle)
                && !self.settling_at_visit_target()
            {
                let blocked = self.remaining_path_blocked();
                if blocked {
                    self.stats.blocked_replans += 1;
                }
                self.plan_and_go(blocked, out);
            }
        } else {
            self.plan_and_go(false, out);
        }
    }

    /// Filter the sweep (regions of constant depth, unless turned off), turn the kept readings
    /// into world points with the pose of each reading, mark them. Returns the hits marked.
    fn mark_readings(&mut self) -> u16 {
        self.hits.clear();
        let mut params = RcdParams::from_config(&self.config.robot);
        if !self.config.constant_depth_filter {
            params.min_pairs = 0;
        }
        let offset_m = self.config.robot.sonar_offset_m;
        let (grid, hits, e) = (&mut self.grid, &mut self.hits, self.expansion_cells);
        for_each_constant_depth_hit(&self.readings, &params, |hit| {
            let p = hit.world_point(offset_m);
            if p.is_finite() {
                mark_point_m(grid, p, e);
                // As many hits as readings: cannot overflow.
                let _ = hits.push(p);
            }
        });
        self.stats.hits += self.hits.len() as u32;
        self.hits.len() as u16
    }
}
