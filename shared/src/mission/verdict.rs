//! The evidence map's verdicts ([`MissionConfig::evidence_map`](super::MissionConfig)):
//! `unreachable` only with a proof, otherwise visit the gap the unsettled marks close, and
//! give up, saying so, after a bounded number of visits (issue 23, part 3; seed 003 §IV.5
//! ends on "no path on the map", which with one-bit marks is the same thing).
//!
//! Why: the planners read the grid grown from *every* occupied mark, tentative ones included
//! (they keep the body off a wall it has only partly heard: planning on confirmed marks alone
//! collided, see `docs/mapping.md`). So "no path" on that grid proves nothing: a doorway whose
//! jambs a wide beam placed reflectors across is shut on it. When a plan finds no path:
//!
//! 1. **The proof.** The grid is redrawn from the confirmed marks alone and planned on once
//!    more. No path there either: the goal is cut off by obstacles heard as regions of
//!    constant depth from two sweeps (`evidence_marking`), [`UnreachableReason::ConfirmedCut`].
//! 2. **The gap.** A path there crosses cells that only tentative marks block: its first such
//!    stretch is the gap they close. The robot plans (on the full map, every body rule in
//!    force) to a stand-off point in front of it, on the line through it along the path: the
//!    nearest free point (the planning radius's margin over the body kept clear around it, for
//!    the pilot's tracking), from a little past the sonar's minimum range out to the distance
//!    where a beam of half-angle β is as wide as the narrowest gap the robot can use
//!    (`w = 2·radius + 2 cells`): `d = w / (2·tan β)`, within the sonar's reach. Nearest,
//!    because the beam's footprint in the opening narrows as the sonar nears it. The line is
//!    turned by up to 45° either way when the marks known now would hide the gap from a point
//!    on it (`GapView`: a wall the robot would stand beside, met along its line towards the
//!    gap, has its foot nearer than the Thales bound for the gap, so the sweep there could
//!    vouch for nothing past the wall's end); only when every such point is hidden is the
//!    nearest free point on the line taken as before. There it
//!    takes a full standing sweep. A reading whose beam fits through the gap
//!    hears the room beyond, the jambs' run of constant depth puts its reflector on the jamb,
//!    and the Thales rule (`swept`) vouches for the gap's cells, taking their tentative marks
//!    back (active perception: Leonard & Durrant-Whyte's several viewpoints).
//! 3. **Bounded.** After [`MAX_GAP_VISITS`] visits the mission ends
//!    [`UnreachableReason::GapsUnsettled`] (`gave_up` on the host), which is not a proof.
//! 4. **A visit that took nothing back closes its gap** (`VisitedGap`): later proof plans
//!    draw its tentative marks in, so the next visit looks elsewhere rather than sweeping
//!    again from where the robot stands. Closing only orders the visits: when no way is
//!    left with the closed gaps drawn in, they open again and the proof is planned once
//!    more on the confirmed marks alone (its answer is then a proof or a gap). Before,
//!    that case ended `GapsUnsettled` after as few as two visits (`twil sonar-grid --worlds 8
//!    --evidence-map`: reopening reached 4 more goals and proved the first walled-in goal
//!    unreachable, with 0 false `unreachable`).
//!
//! Tried and taken out, measured on `twil sonar-grid --quick --evidence-map`: confirming
//! what a visit's full sweep left of the marks closing its gap (a second viewpoint that did
//! not take them back) closed 1 to 3 reachable goals (a visit whose gap lay beside a doorway
//! confirmed the ghosts across it); planning the next gap with *every* visited gap's marks
//! drawn in reached 19 goals of 40 against 22 for looking at the first gap again (rule 4
//! draws in only the gaps whose visit took nothing back). Standing at the nearest free point
//! collided until the blind disc was known by marks, a wall's free end echoed in every
//! simulated reading and the stand-off kept the tracking margin (`docs/mapping.md`).
//!
//! Cost: a redraw is one pass over the map plus a `(2e + 1)²` square per occupied cell (e:
//! the expansion in cells); the gap search walks the path's cells once.

use crate::geom::{distance_to_segment_m, PointM};
use crate::grid::{Grid, GridGeometry};
use crate::math::{abs, atan2, cos, hypot, sin, wrap_angle_rad};
use crate::plan::PlanStatus;
use crate::raster::{mark_point_m, BresenhamLine};

use super::evidence::CellEvidence;
use super::evidence_marking::centre as cell_centre;
use super::messages::push;
use super::{Mission, MissionEvent, MissionOutput, MissionStatus, UnreachableReason};

/// Gap visits per mission before it gives up ([`UnreachableReason::GapsUnsettled`]).
pub const MAX_GAP_VISITS: u16 = 24;

/// A gap visited: its middle, how far around it its visit looked, and how many tentative
/// marks lay there when the visit began. A visit that took none of them back closes the gap:
/// its tentative marks within that reach are drawn into later proof plans, so that the next
/// visit looks at another gap; one that took some back may be followed by another, nearer
/// (the marks it took back free the way in).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct VisitedGap {
    /// The middle of the blocked stretch, world metres.
    pub centre: PointM,
    /// How far around the middle the visit's marks are counted (and drawn in), metres.
    pub reach_m: f32,
    /// Tentative marks within the reach when the visit began (saturating).
    pub tentative_cells: u16,
    /// The visit took none of them back.
    pub closed: bool,
    /// Where the visit stood to sweep, world metres.
    pub stand_off: PointM,
    /// The visit took none of its marks back (kept when `closed` opens again): a later
    /// visit of the same gap stands elsewhere, since this sweep would only be read again.
    pub futile: bool,
}

/// The gaps visited in a mission, at most one per visit.
pub(super) type VisitedGaps = heapless::Vec<VisitedGap, { MAX_GAP_VISITS as usize }>;

/// A visit under way: where the robot goes to sweep again.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct GapVisit {
    /// The stand-off point, world metres.
    pub target: PointM,
}

impl<const W: usize, const E: usize> Mission<W, E> {
    /// The stand-off point of the gap visit under way, if any (for pictures and logs).
    pub fn gap_visit_target(&self) -> Option<PointM> {
        self.visit.map(|v| v.target)
    }

    /// Gap visits begun so far (at most [`MAX_GAP_VISITS`]).
    pub fn gap_visits(&self) -> u16 {
        self.gap_visits
    }

    /// The point plans go to: the stand-off point of a visit under way, else the goal.
    pub(super) fn plan_goal(&self) -> PointM {
        self.visit.map_or(self.config.goal, |v| v.target)
    }

    /// Can this mission prove its verdicts on confirmed marks (evidence map, its occupied
    /// plane, and no marks known a priori, which the evidence map does not hold)?
    pub(super) fn proves_verdicts(&self) -> bool {
        self.config.evidence_map && self.evidence.has_occupied_plane() && !self.known_a_priori
    }

    /// Redraw the grid from the evidence map: every occupied mark, or the confirmed ones only
    /// (and the tentative ones around the gaps already visited), grown by the planning radius.
    pub(super) fn redraw_grid(&mut self, confirmed_only: bool) {
        let g = *self.grid.geometry();
        let e = self.expansion_cells;
        self.grid.clear();
        for y in 0..g.height() as i32 {
            for x in 0..g.width() as i32 {
                let c = cell_centre(&g, x, y);
                let marked = match self.evidence.get_xy(x, y) {
                    CellEvidence::Confirmed => true,
                    CellEvidence::Tentative => {
                        !confirmed_only
                            || self.visited_gaps.iter().any(|v| {
                                v.closed
                                    && hypot(c.x_m - v.centre.x_m, c.y_m - v.centre.y_m)
                                        <= v.reach_m
                            })
                    }
                    CellEvidence::Unknown | CellEvidence::Free => false,
                };
                if marked {
                    mark_point_m(&mut self.grid, c, e);
                }
            }
        }
    }

    /// No path on the full map: plan on the confirmed marks alone (the proof), or, when visits
    /// are spent, give up.
    pub(super) fn seek_proof(&mut self, out: &mut MissionOutput) {
        if self.gap_visits >= MAX_GAP_VISITS {
            self.stats.unreachable_reason = Some(UnreachableReason::GapsUnsettled);
            self.finish(MissionStatus::Unreachable, out);
            return;
        }
        self.visit = None;
        if let Some(last) = self.visited_gaps.last().copied() {
            let now = saturate_u16(self.tentative_cells_within(last.centre, last.reach_m));
            let took_none_back = now >= last.tentative_cells;
            if let Some(v) = self.visited_gaps.last_mut() {
                v.closed |= took_none_back;
                v.futile |= took_none_back;
            }
        }
        self.redraw_grid(true);
        self.ask_plan(true, out);
    }

    /// Tentative marks whose cell centre lies within `reach_m` of `centre`.
    pub(super) fn tentative_cells_within(&self, centre: PointM, reach_m: f32) -> u32 {
        let g = *self.grid.geometry();
        let res_m = g.resolution_m();
        let cells = (reach_m.max(0.0) / res_m) as i32 + 1;
        let cx = (centre.x_m / res_m) as i32;
        let cy = (centre.y_m / res_m) as i32;
        let mut n = 0;
        for y in (cy - cells).max(0)..=(cy + cells).min(g.height() as i32 - 1) {
            for x in (cx - cells).max(0)..=(cx + cells).min(g.width() as i32 - 1) {
                let c = cell_centre(&g, x, y);
                if self.evidence.get_xy(x, y) == CellEvidence::Tentative
                    && hypot(c.x_m - centre.x_m, c.y_m - centre.y_m) <= reach_m
                {
                    n += 1;
                }
            }
        }
        n
    }

    /// The proof plan is back: its `status` says whether the confirmed marks leave a way (its
    /// path is [`Mission::path`]). Restores the full grid, then ends the mission with the
    /// proof (the goal inside a confirmed mark's grown disc is `GoalBlocked`, as without the
    /// evidence map) or sets off to the gap.
    pub(super) fn on_proof(&mut self, status: PlanStatus, out: &mut MissionOutput) {
        let found = status == PlanStatus::Found;
        if !found && self.visited_gaps.iter().any(|v| v.closed) {
            // The closed gaps only order the visits (others first): with every other gap
            // tried, open them again and plan the proof once more. Its answer then is a proof
            // or a gap to visit; the visits stay bounded by MAX_GAP_VISITS.
            for v in self.visited_gaps.iter_mut() {
                v.closed = false;
            }
            self.redraw_grid(true);
            self.ask_plan(true, out);
            return;
        }
        self.redraw_grid(false);
        if !found {
            self.stats.unreachable_reason = Some(if status == PlanStatus::GoalBlocked {
                UnreachableReason::GoalBlocked
            } else {
                UnreachableReason::ConfirmedCut
            });
            self.finish(MissionStatus::Unreachable, out);
            return;
        }
        self.gap_visits += 1;
        let robot = self.config.robot;
        let res_m = self.grid.geometry().resolution_m();
        let Some((gap, dir, stretch)) = first_blocked_stretch(&self.grid, &self.path) else {
            // The confirmed path is clear on the full map too (marks changed meanwhile):
            // sweep all round here and plan again.
            push(out, MissionEvent::FullSweepRequested);
            self.begin_standing_sweep(true, out);
            return;
        };
        let width_m = 2.0 * robot.planning_radius_m + 2.0 * res_m;
        let beam_rad = robot.sonar_beam_half_angle_deg.max(0.0) * (core::f32::consts::PI / 180.0);
        let reach_m = (robot.sonar_range_m - robot.planning_radius_m).max(res_m);
        let tan_beam = sin(beam_rad) / cos(beam_rad);
        let fits_m = if tan_beam > 1.0e-3 {
            width_m / (2.0 * tan_beam)
        } else {
            reach_m
        };
        let near_m = nearest_stand_off_m(&robot, res_m);
        let stand_off_m = fits_m.clamp(near_m, reach_m.max(near_m));
        // The body stops up to the planning radius's margin over its own radius off the path
        // (the pilot's tracking error): keep that margin clear around the stand-off point too.
        let margin_cells =
            ((robot.planning_radius_m - robot.physical_radius_m()).max(0.0) / res_m) as i32;
        let g = *self.grid.geometry();
        let own_reach_m = robot.planning_radius_m + res_m;
        let (first, last) = (
            cell_centre(&g, stretch[0].0, stretch[0].1),
            cell_centre(&g, stretch[1].0, stretch[1].1),
        );
        let view = GapView {
            gap,
            beam_rad,
            cell_m: res_m,
            marked: &|x, y| {
                let p = cell_centre(&g, x, y);
                self.evidence.is_occupied_xy(x, y)
                    && distance_to_segment_m(p, first, last) > own_reach_m
            },
        };
        // The viewpoints already swept in vain for a gap here: a visit stands elsewhere.
        let mut futile: heapless::Vec<PointM, { MAX_GAP_VISITS as usize }> = heapless::Vec::new();
        for v in self.visited_gaps.iter().filter(|v| {
            v.futile && hypot(v.centre.x_m - gap.x_m, v.centre.y_m - gap.y_m) <= stand_off_m
        }) {
            // At most one per visit: never full.
            let _ = futile.push(v.stand_off);
        }
        let line = (gap, dir);
        let reach = (near_m, stand_off_m);
        let target = stand_off_point(&self.grid, line, reach, margin_cells, Some(&view), &futile)
            .or_else(|| stand_off_point(&self.grid, line, reach, margin_cells, None, &futile))
            .or_else(|| stand_off_point(&self.grid, line, reach, margin_cells, None, &[]))
            .unwrap_or_else(|| {
                // No free point on the line: the last free path point before the gap.
                self.position_world()
            });
        self.visit = Some(GapVisit { target });
        let tentative_cells = saturate_u16(self.tentative_cells_within(gap, stand_off_m));
        // Full only past MAX_GAP_VISITS visits, which end the mission first.
        let _ = self.visited_gaps.push(VisitedGap {
            centre: gap,
            reach_m: stand_off_m,
            tentative_cells,
            closed: false,
            stand_off: target,
            futile: false,
        });
        if self.at_visit_target() {
            self.end_visit(out);
            return;
        }
        // A new target: plans from here are not stalled ones.
        self.last_plan_origin = None;
        self.plan_and_go(false, out);
    }

    /// At the stand-off point (or, standing, within the goal tolerance of it): the visit is
    /// done, sweep all round.
    pub(super) fn at_visit_target(&self) -> bool {
        self.visit.is_some_and(|v| {
            let p = self.position_world();
            hypot(p.x_m - v.target.x_m, p.y_m - v.target.y_m) <= self.config.goal_tolerance_m
        })
    }

    /// The visit is done: sweep all round, standing.
    pub(super) fn end_visit(&mut self, out: &mut MissionOutput) {
        self.visit = None;
        if let Some(pending) = &mut self.pending_plan {
            pending.cancelled = true;
        }
        push(out, MissionEvent::FullSweepRequested);
        self.begin_standing_sweep(true, out);
    }
}

/// `n` as a `u16`, at most `u16::MAX` (a visit's count of marks, kept small: the mission's
/// visits live in the MCU's core-coupled memory).
fn saturate_u16(n: u32) -> u16 {
    u16::try_from(n).unwrap_or(u16::MAX)
}

/// The nearest a visit stands from its gap's middle, centre to middle, metres: the sonar,
/// ahead of the centre by its offset when it faces the gap, out of its blind zone from the
/// gap by two cells. Nearer, the visit's sweep cannot hear the marks it came to settle, and a
/// visit from where the robot stands sweeps again what it swept.
fn nearest_stand_off_m(robot: &crate::robot::RobotConfig, res_m: f32) -> f32 {
    robot.sonar_min_range_m + robot.sonar_offset_m.max(0.0) + 2.0 * res_m
}

/// The first and the last blocked cell of a stretch of a path (`x`, `y`).
type Stretch = [(i32, i32); 2];

/// The first stretch of `path` whose cells are occupied on `grid`: its middle, the unit
/// direction of the path across it (world metres) and its first and last cells, or `None`
/// when the path is clear.
fn first_blocked_stretch<const W: usize>(
    grid: &Grid<W>,
    path: &[PointM],
) -> Option<(PointM, PointM, Stretch)> {
    let g = grid.geometry();
    let mut first: Option<(i32, i32)> = None;
    let mut last: Option<(i32, i32)> = None;
    let mut segment_dir = PointM::new(1.0, 0.0);
    'walk: for w in path.windows(2) {
        let (Some(a), Some(b)) = (g.cell_xy_of(w[0]), g.cell_xy_of(w[1])) else {
            continue;
        };
        let len_m = hypot(w[1].x_m - w[0].x_m, w[1].y_m - w[0].y_m);
        for (x, y) in BresenhamLine::new(a, b) {
            if grid.is_occupied_xy(x, y) && g.contains_xy(x, y) {
                if first.is_none() && len_m > 1.0e-6 {
                    segment_dir =
                        PointM::new((w[1].x_m - w[0].x_m) / len_m, (w[1].y_m - w[0].y_m) / len_m);
                }
                first.get_or_insert((x, y));
                last = Some((x, y));
            } else if first.is_some() {
                break 'walk;
            }
        }
    }
    let (f, l) = (first?, last?);
    let res_m = g.resolution_m();
    let (p, q) = (cell_centre(g, f.0, f.1), cell_centre(g, l.0, l.1));
    let len_m = hypot(q.x_m - p.x_m, q.y_m - p.y_m);
    let dir = if len_m > 0.5 * res_m {
        PointM::new((q.x_m - p.x_m) / len_m, (q.y_m - p.y_m) / len_m)
    } else {
        segment_dir
    };
    Some((
        PointM::new(0.5 * (p.x_m + q.x_m), 0.5 * (p.y_m + q.y_m)),
        dir,
        [f, l],
    ))
}

/// Directions tried for a stand-off point, radians off the line through the gap, in order.
const VIEW_FAN_RAD: [f32; 7] = [0.0, 0.26, -0.26, 0.52, -0.52, 0.79, -0.79];

/// What the marks known now say of a stand-off point: could a standing sweep from there vouch
/// for the gap's middle, or would a known reflector contradict it?
struct GapView<'a> {
    /// The gap's middle, world metres.
    gap: PointM,
    /// The beam's half-angle, radians.
    beam_rad: f32,
    /// One cell, metres.
    cell_m: f32,
    /// Marked cells other than the gap's own (those a sweep is sent to take back).
    marked: &'a dyn Fn(i32, i32) -> bool,
}

impl GapView<'_> {
    /// `true` when no mark but the gap's own lies where it would contradict the Thales rule
    /// (`swept`) for the gap's middle seen from `sonar`: within `d·cos(max(0, |Δφ| − β))` plus
    /// a cell of it, `d` the distance to the gap and `Δφ` the mark's bearing off the gap's.
    /// A wall the robot stands beside, met along its line towards the gap, is such a mark:
    /// its foot, near the sonar, is nearer than the bound, so the sweep could vouch for
    /// nothing past its end, and a visit made there settled nothing (world 5 of
    /// `twil sonar-grid`, 10°/10° beam, 6 m, continuous).
    ///
    /// Cost: the square of side `2d` around the sonar, in cells.
    fn clear_from(&self, g: &GridGeometry, sonar: PointM) -> bool {
        let d_m = hypot(self.gap.x_m - sonar.x_m, self.gap.y_m - sonar.y_m);
        let Some((sx, sy)) = g.cell_xy_of(sonar) else {
            return false;
        };
        let gap_rad = atan2(self.gap.y_m - sonar.y_m, self.gap.x_m - sonar.x_m);
        let h = (d_m / self.cell_m) as i32 + 1;
        for y in (sy - h).max(0)..=(sy + h).min(g.height() as i32 - 1) {
            for x in (sx - h).max(0)..=(sx + h).min(g.width() as i32 - 1) {
                if !(self.marked)(x, y) {
                    continue;
                }
                let p = cell_centre(g, x, y);
                let r_m = hypot(p.x_m - sonar.x_m, p.y_m - sonar.y_m);
                let off_rad = abs(wrap_angle_rad(
                    atan2(p.y_m - sonar.y_m, p.x_m - sonar.x_m) - gap_rad,
                ));
                let bound_m = d_m * cos((off_rad - self.beam_rad).max(0.0)) + self.cell_m;
                if off_rad <= core::f32::consts::FRAC_PI_2 + self.beam_rad && r_m <= bound_m {
                    return false;
                }
            }
        }
        true
    }
}

/// The nearest free cell's centre in front of `gap`, back along `-dir`, at least `near_m` and
/// at most `far_m` away (in steps of a cell), with `margin_cells` around it free too, or
/// `None`. Nearest, because the nearer the sonar stands to a gap, the narrower its beam's
/// footprint there: more readings pass through an opening and hear the room beyond. With a
/// `view`, the line is turned by up to 45° ([`VIEW_FAN_RAD`]) and a point counts only when
/// the marks known now do not hide the gap from it ([`GapView`]); without, only the line.
fn stand_off_point<const W: usize>(
    grid: &Grid<W>,
    (gap, dir): (PointM, PointM),
    (near_m, far_m): (f32, f32),
    margin_cells: i32,
    view: Option<&GapView<'_>>,
    avoid: &[PointM],
) -> Option<PointM> {
    let g = grid.geometry();
    let res_m = g.resolution_m();
    let fan_rad: &[f32] = if view.is_some() {
        &VIEW_FAN_RAD
    } else {
        &[0.0]
    };
    let mut d_m = near_m;
    while d_m <= far_m {
        for &a in fan_rad {
            let (c, s) = (cos(a), sin(a));
            let back = PointM::new(c * dir.x_m - s * dir.y_m, s * dir.x_m + c * dir.y_m);
            let p = PointM::new(gap.x_m - d_m * back.x_m, gap.y_m - d_m * back.y_m);
            let Some((x, y)) = g.cell_xy_on_map(p) else {
                continue;
            };
            let clear = (-margin_cells..=margin_cells).all(|dy| {
                (-margin_cells..=margin_cells).all(|dx| !grid.is_occupied_xy(x + dx, y + dy))
            });
            let centre = cell_centre(g, x, y);
            let fresh = avoid
                .iter()
                .all(|a| hypot(a.x_m - centre.x_m, a.y_m - centre.y_m) > 2.0 * res_m);
            if clear && fresh && view.is_none_or(|v| v.clear_from(g, centre)) {
                return Some(centre);
            }
        }
        d_m += res_m;
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{words_for_cells, GridGeometry};

    type G = Grid<{ words_for_cells(100 * 100) }>;

    fn wall_with_marks_across_a_doorway() -> G {
        // A wall along y = 2.5 m (row 50) with its doorway x 2.0..3.0 m shut by marks.
        let mut g = G::new_const(GridGeometry::new(100, 100, 0.05).unwrap()).unwrap();
        for x in 0..100 {
            for y in 48..53 {
                g.set_xy(x, y, true);
            }
        }
        g
    }

    #[test]
    fn the_gap_is_the_first_blocked_stretch_and_the_stand_off_faces_it() {
        let g = wall_with_marks_across_a_doorway();
        let path = [PointM::new(2.5, 0.5), PointM::new(2.5, 4.5)];
        let (gap, dir, stretch) = first_blocked_stretch(&g, &path).expect("blocked");
        assert_eq!(stretch, [(50, 48), (50, 52)]);
        assert!(
            (gap.x_m - 2.525).abs() < 0.03 && (gap.y_m - 2.525).abs() < 0.03,
            "{gap:?}"
        );
        assert!((dir.y_m - 1.0).abs() < 1.0e-3, "{dir:?}");
        // The nearest free point on the line through the gap: 0.3 m before it, past the marks
        // (rows 48..52).
        let s = stand_off_point(&g, (gap, dir), (0.3, 1.5), 0, None, &[]).expect("free");
        assert!(
            (s.y_m - 2.225).abs() < 0.03 && (s.x_m - 2.525).abs() < 0.03,
            "{s:?}"
        );
        // A clear path has no gap.
        let clear = [PointM::new(0.5, 0.5), PointM::new(4.5, 0.5)];
        assert!(first_blocked_stretch(&g, &clear).is_none());
    }

    #[test]
    fn the_nearest_stand_off_keeps_the_sonar_out_of_its_blind_zone_from_the_gap() {
        // The office mission that gave up 0.5 m from its goal: a lone mark beside the goal, the
        // robot already standing at the nearest clear point of the line through it. The
        // visit's point must put the sonar, facing the gap, beyond its minimum range.
        let robot = crate::robot::RobotConfig::DEFAULT;
        let g = wall_with_marks_across_a_doorway();
        let (gap, dir) = (PointM::new(2.525, 2.525), PointM::new(0.0, 1.0));
        let near_m = nearest_stand_off_m(&robot, 0.05);
        let s = stand_off_point(&g, (gap, dir), (near_m, 1.7), 0, None, &[]).expect("free");
        let sonar_y_m = s.y_m + robot.sonar_offset_m;
        assert!(
            gap.y_m - sonar_y_m >= robot.sonar_min_range_m + 0.05,
            "sonar {sonar_y_m:.3} m, gap {:.3} m",
            gap.y_m
        );
        // The sonar's minimum range alone (the rule before) left it 0.16 m from the gap.
        let old = stand_off_point(&g, (gap, dir), (0.36, 1.7), 0, None, &[]).expect("free");
        assert!(gap.y_m - (old.y_m + robot.sonar_offset_m) < robot.sonar_min_range_m);
    }

    #[test]
    fn a_visit_does_not_stand_where_a_visit_of_its_gap_swept_in_vain() {
        let g = wall_with_marks_across_a_doorway();
        let (gap, up) = (PointM::new(2.525, 2.525), PointM::new(0.0, 1.0));
        let first = stand_off_point(&g, (gap, up), (0.3, 1.5), 0, None, &[]).expect("free");
        // That viewpoint swept and took nothing back: the next visit stands over two cells
        // farther along the line.
        let next = stand_off_point(&g, (gap, up), (0.3, 1.5), 0, None, &[first]).expect("free");
        assert!(
            first.y_m - next.y_m > 0.1 - 1.0e-4,
            "{first:?} then {next:?}"
        );
    }

    #[test]
    fn a_stand_off_point_inside_marks_moves_farther_or_is_refused() {
        let mut g = wall_with_marks_across_a_doorway();
        // Marks from the wall's down to 1.0 m before the gap: the first free cell beyond.
        for y in 30..48 {
            g.set_xy(50, y, true);
        }
        let up = PointM::new(0.0, 1.0);
        let at = |g: &G, margin_cells| {
            stand_off_point(
                g,
                (PointM::new(2.525, 2.525), up),
                (0.3, 1.5),
                margin_cells,
                None,
                &[],
            )
        };
        let s = at(&g, 0).expect("a farther free cell");
        assert!((s.y_m - 1.475).abs() < 0.03, "{s:?}");
        // With a margin of two cells kept clear around it, two cells farther.
        let s = at(&g, 2).expect("a farther free cell");
        assert!((s.y_m - 1.375).abs() < 0.03, "{s:?}");
        // Everything marked up to the far limit: none.
        for y in 0..48 {
            g.set_xy(50, y, true);
        }
        assert!(at(&g, 0).is_none());
    }

    #[test]
    fn a_wall_met_along_its_line_hides_the_gap_and_the_stand_off_turns_away_from_it() {
        // A wall along y = 2.2 m ending 0.2 m short of the gap at (2.5, 2.5); the way crosses
        // the gap eastwards. The planning grid is empty (every point is free).
        let mut walls = G::new_const(GridGeometry::new(100, 100, 0.05).unwrap()).unwrap();
        for x in 0..=45 {
            walls.set_xy(x, 44, true);
        }
        let free = G::new_const(GridGeometry::new(100, 100, 0.05).unwrap()).unwrap();
        let g = *free.geometry();
        let marked = |x: i32, y: i32| walls.is_occupied_xy(x, y);
        let view = GapView {
            gap: PointM::new(2.525, 2.525),
            beam_rad: 15.0f32.to_radians(),
            cell_m: 0.05,
            marked: &marked,
        };
        // From 1 m straight back the sonar stands 0.3 m beside the wall: its foot, and the
        // wall between the sonar and the gap, are nearer than the Thales bound.
        assert!(!view.clear_from(&g, PointM::new(1.525, 2.525)));
        // From the side away from the wall at 45°, nothing is.
        assert!(view.clear_from(&g, PointM::new(1.825, 3.225)));
        let east = PointM::new(1.0, 0.0);
        let s = stand_off_point(&free, (view.gap, east), (1.0, 1.5), 0, Some(&view), &[])
            .expect("a point in view");
        assert!(s.y_m > 2.9, "{s:?}");
        assert!(
            (hypot(s.x_m - 2.525, s.y_m - 2.525) - 1.0).abs() < 0.05,
            "{s:?}"
        );
        // Without the wall the nearest point straight back will do.
        let nothing = |_: i32, _: i32| false;
        let open = GapView {
            marked: &nothing,
            ..view
        };
        let s = stand_off_point(&free, (open.gap, east), (1.0, 1.5), 0, Some(&open), &[])
            .expect("a point in view");
        assert!(
            (s.y_m - 2.525).abs() < 0.03 && (s.x_m - 1.525).abs() < 0.03,
            "{s:?}"
        );
    }
}
