//! How the mission writes the evidence map ([`MissionConfig::evidence_map`](crate::mission::MissionConfig::evidence_map)): rays, reflectors,
//! taken-back marks and suspects, and the grown 1-bit grid the planners read, derived from the
//! occupied evidence.
//!
//! Why each rule (see `docs/mapping.md` for the argument and its sources):
//!
//! - **Free evidence** comes only from what a whole standing sweep vouches for (the Thales rule,
//!   `swept`), not from the empty region of each reading (Moravec & Elfes 1985): a smooth wall
//!   that crosses a ray's axis obliquely is silent while something else in the cone echoes
//!   beyond it (measured: the office at 6 m, 30°, drove its body onto such a wall when the
//!   axis of echoing rays was free evidence). A vouched cell takes a tentative mark back.
//! - **Silence** marks nothing: a smooth wall met at more than the incidence limit is silent
//!   (Kuc & Siegel 1987), so silence is never proof that a cell is free for the body.
//! - **One viewpoint, one step**: a sweep's reflectors move a cell at most once, so a mark is
//!   confirmed only by two sweeps (two viewpoints): on one cell, or on one plane (`planes`:
//!   a smooth wall's foot moves with the viewpoint).
//! - **A sloping run's foot**: a wall heard at wide angles makes a long run whose range rises
//!   on both sides of its nearest point; the readings within a cell of the least range, at
//!   least β wide and inside the run, are its region of constant depth (standing sweeps).
//! - **Only a region of constant depth confirms**: a run at least the beam's half-angle wide
//!   and level within a cell. A shorter or sloping run (an oblique wall's arc) marks its
//!   reflector tentative and never confirms it: its echo came from somewhere on the arc.
//!   (A wall heard at its cone edges, `edge_chains`, says where on the arc: its cells are
//!   stepped once per sweep and confirmed by a second one.)
//! - **A run of constant depth** (Leonard & Durrant-Whyte 1991) has its reflectors at its
//!   mean depth, not the whole arc: one at the middle bearing of a run 2β wide (for a plane
//!   the foot of the perpendicular, for a corner the corner), β inside an end whose neighbour
//!   heard farther or nothing (the reflector left the cone there), two for a run wider than
//!   2β (a doorway's jambs seen from its axis, not a mark in the doorway): `reflector`.
//! - **Faults** (beam sensors, `sonar_beam`): a reflector is heard by about 2m + 1 readings
//!   (m the steps in β), so one missed echo inside a run, or one echo nearer than the two
//!   agreeing readings around it, is the ranger's fault and the run goes on across it; one
//!   echo whose neighbours both heard farther or nothing marks nothing.
//! - **Suspects**: after a full standing sweep, unknown cells that no reading vouched for in a
//!   ring just outside the planning radius are tentative occupied, so the planner does not
//!   route the body through silent space beside it.
//!
//! - **Marks grow as the seed's squares**, not as discs (tried in commit fb63004), though the body
//!   is round: after a full sweep the body corridor (`corridor`) counts only occupied cells
//!   of the grid as unknown, and a wall heard only at its feet is then covered between them by
//!   the squares' corners alone. With discs a robot in a 0.70 m slot planned out through the
//!   wall between two feet and grazed it (`tests/answers.rs`, the stall), though the discs
//!   proved 99 walled-in goals of 192 on `twil sonar-grid` against 86 (`docs/mapping.md`).
//!
//! Bounded work: a sweep's reflectors at most its
//! readings; a take-back redraws a `(4e + 1)²` window (e: the expansion in cells), at most
//! [`TAKE_BACK_CAPACITY`] per sweep; suspects read a `(2e + 7)²` square.

use heapless::Vec;

use crate::control::Pose;
use crate::geom::PointM;
use crate::math::{abs, cos, hypot, sin, wrap_angle_rad};
use crate::raster::{mark_point_m, BresenhamLine};
use crate::sonar::hit_to_world;

use super::evidence::{CellEvidence, Change, EvidenceMap};
use super::planes::{remember, PlaneSeen};
use super::reflector::{reflector_bearings, RunEnd, RunSide};
use super::swept::{reading_shift_m, BlindCells, Swept};
use super::Mission;

/// Sweeps whose sonar positions a mission remembers (`Mission::note_viewpoint`), 64 B.
pub const VIEWPOINT_MEMORY: usize = 8;

/// The sonar positions of the last [`VIEWPOINT_MEMORY`] sweeps that marked, oldest first.
pub(super) type Viewpoints = heapless::Deque<PointM, VIEWPOINT_MEMORY>;

/// Take-backs redrawn in the grid per sweep; more are kept marked in the grid (the safe side)
/// though the evidence map has taken them back.
pub const TAKE_BACK_CAPACITY: usize = 32;

/// Cells whose tentative mark a ray took back, for the grid to be redrawn around them.
pub(super) type TakeBacks = Vec<(u16, u16), TAKE_BACK_CAPACITY>;

impl<const W: usize, const E: usize> Mission<W, E> {
    /// At a (re)start the robot stands on its own disc: that and half a cell more is free. So
    /// is the sonar's blind disc (its minimum range around it): no sweep from here can hear
    /// it, and every later stop's blind disc is known before the robot stops there (`blind`),
    /// so this is the one thing the user vouches for by placing the robot.
    pub(super) fn assume_body_disc_clear(&mut self) {
        let g = *self.grid.geometry();
        let robot = self.config.robot;
        let c = self.config.start;
        let half_cell_m = 0.5 * g.resolution_m();
        let body_m = robot.physical_radius_m() + half_cell_m;
        let heading = self.config.initial_heading_rad;
        let sonar = PointM::new(
            c.x_m + robot.sonar_offset_m * cos(heading),
            c.y_m + robot.sonar_offset_m * sin(heading),
        );
        let blind_m = robot.sonar_min_range_m + half_cell_m;
        self.mark_disc_free(c, body_m);
        self.mark_disc_free(sonar, blind_m);
    }

    fn mark_disc_free(&mut self, c: PointM, reach_m: f32) {
        let g = *self.grid.geometry();
        let Some((cx, cy)) = g.cell_xy_of(c) else {
            return;
        };
        if !(reach_m.is_finite() && reach_m >= 0.0) {
            return;
        }
        let h = (reach_m / g.resolution_m()) as i32 + 1;
        for y in cy - h..=cy + h {
            for x in cx - h..=cx + h {
                let p = centre(&g, x, y);
                if hypot(p.x_m - c.x_m, p.y_m - c.y_m) <= reach_m {
                    self.evidence.observe_free_xy(x, y);
                }
            }
        }
    }

    /// The cells of a known obstacle's outline (the vertices' cells joined in order and back
    /// to the first, as [`crate::raster::mark_polygon`] draws it, not grown) become confirmed
    /// marks. Bounded by the outline's length in cells.
    pub(super) fn mark_known_outline(&mut self, vertices: &[PointM]) {
        let g = *self.grid.geometry();
        let mut cells = vertices.iter().filter_map(|v| g.cell_xy_of(*v));
        let Some(first) = cells.next() else {
            return;
        };
        // Closed back to the first cell; a single vertex is the line from its cell to itself.
        let mut previous = first;
        for cell in cells.chain(core::iter::once(first)) {
            for (x, y) in BresenhamLine::new(previous, cell) {
                self.evidence.known_xy(x, y);
            }
            previous = cell;
        }
    }

    /// Note where this sweep's sonar stood (its first reading's pose) and whether an earlier
    /// sweep of the last [`VIEWPOINT_MEMORY`] stood within
    /// [`MIN_VIEWPOINT_APART_M`](super::planes::MIN_VIEWPOINT_APART_M) of it: then its
    /// reflectors step no tentative mark up to confirmed. Two sweeps from one place hear the
    /// same ghost in the same cell (the beam's geometry is deterministic), so they are one
    /// viewpoint, not two: a moving sweep ending where the full standing sweep then stood
    /// confirmed a ghost in the middle of a 1.5 m doorway, and the goal beyond it was
    /// reported `unreachable` (`twil sonar-grid --worlds 8 --world-seed 4`, world 4, 25°/25°,
    /// 3 m, continuous, with 30 gap visits).
    fn note_viewpoint(&mut self) {
        let offset_m = self.config.robot.sonar_offset_m;
        let Some(sonar) = self
            .readings
            .as_slice()
            .first()
            .map(|r| r.pose.point_ahead(offset_m))
        else {
            self.repeated_viewpoint = false;
            return;
        };
        self.repeated_viewpoint = self.viewpoints.iter().any(|p| {
            hypot(p.x_m - sonar.x_m, p.y_m - sonar.y_m) < super::planes::MIN_VIEWPOINT_APART_M
        });
        if self.viewpoints.is_full() {
            let _ = self.viewpoints.pop_front();
        }
        // Room was made just above.
        let _ = self.viewpoints.push_back(sonar);
    }

    /// One evidence step of a reflector on (`x`, `y`) from this sweep (the free function of the
    /// same name: confirmed only from a new viewpoint).
    pub(super) fn step_occupied(&mut self, x: i32, y: i32) {
        step_occupied(&mut self.evidence, (x, y), !self.repeated_viewpoint);
    }

    /// Has a reflector of this sweep already fallen on `cell`?
    pub(super) fn seen_this_sweep(&self, cell: Option<(i32, i32)>) -> bool {
        let g = self.grid.geometry();
        self.hits.iter().any(|q| g.cell_xy_on_map(*q) == cell)
    }

    /// Redraw the grid around the cells whose tentative marks were taken back (unless marks
    /// known a priori are in the grid: those are not in the evidence map and would be lost).
    pub(super) fn apply_take_backs(&mut self) {
        if self.known_a_priori {
            self.taken_back.clear();
            return;
        }
        let g = *self.grid.geometry();
        let e = self.expansion_cells as i32;
        for &(tx, ty) in self.taken_back.iter() {
            let (tx, ty) = (tx as i32, ty as i32);
            for y in ty - e..=ty + e {
                for x in tx - e..=tx + e {
                    self.grid.set_xy(x, y, false);
                }
            }
            for y in ty - 2 * e..=ty + 2 * e {
                for x in tx - 2 * e..=tx + 2 * e {
                    if self.evidence.is_occupied_xy(x, y) {
                        mark_point_m(&mut self.grid, centre(&g, x, y), e as u16);
                    }
                }
            }
        }
        self.taken_back.clear();
    }

    /// One reflector per run of constant depth (see the module docs), marked in the evidence
    /// map and grown into the grid. Returns the reflectors marked.
    pub(super) fn mark_reflectors(&mut self) -> u16 {
        self.hits.clear();
        let g = *self.grid.geometry();
        let e = self.expansion_cells;
        let robot = self.config.robot;
        self.note_viewpoint();
        // Neighbours of one run agree to half a cell (the seed's 1 cm is finer than a cell,
        // and noise splits runs that one reflector made).
        let tolerance_m = robot.rcd_depth_tolerance_m.max(0.5 * g.resolution_m());
        let readings = self.readings.as_slice();
        let beam_rad = robot.sonar_beam_half_angle_deg.max(0.0) * (core::f32::consts::PI / 180.0);
        let sweep_step_rad = match readings {
            [a, b, ..] => abs(b.neck_angle_rad - a.neck_angle_rad),
            _ => 0.0,
        };
        // The cone the readings were heard through: the beam's, or none for a ray sensor
        // (`sonar_beam` false), whose echo lies on its axis.
        let cone_rad = if robot.sonar_beam { beam_rad } else { 0.0 };
        let bridges_one_reading = cone_rad > 0.0 && sweep_step_rad <= cone_rad;
        // A point reflector is heard by every reading within β of it, about 2m + 1 of them
        // (m the steps in β); the vouching rule (`swept`) outvotes fewer. Unless the sonar
        // moved during the sweep far enough that the readings which missed a reflector had it
        // in their blind disc or out of range.
        let sweep_shift_m = match readings.first() {
            Some(r) => reading_shift_m(readings, r.pose, robot.sonar_offset_m),
            None => 0.0,
        };
        // Planes and sloping runs' feet are read only through a beam, from a sweep read standing
        // (within a cell of one place).
        let read_standing = cone_rad > 0.0 && sweep_shift_m <= g.resolution_m();
        let mut start = 0;
        while start < readings.len() {
            let Some(first_m) = readings[start].range_m else {
                start += 1;
                continue;
            };
            let (mut end, mut sum_m, mut previous_m) = (start, first_m, first_m);
            let (mut least_m, mut most_m, mut echoes) = (first_m, first_m, 1u16);
            loop {
                // The reading past the next one, when the run may go on across one reading.
                let bridge_m = readings
                    .get(end + 2)
                    .and_then(|r| r.range_m)
                    .filter(|_| bridges_one_reading);
                let (next_m, skipped) = match (readings.get(end + 1).map(|r| r.range_m), bridge_m) {
                    // One short echo inside a run: the reflector the readings on both sides
                    // heard was in its cone too, so it heard something nearer that no
                    // neighbour heard, which no reflector in the beam does (it would be in
                    // about 2m + 1 cones): a spurious echo (crosstalk, multipath). Skipped,
                    // and not marked.
                    (Some(Some(m)), Some(after_m))
                        if m < previous_m - tolerance_m
                            && abs(after_m - previous_m) <= tolerance_m =>
                    {
                        (after_m, 1)
                    }
                    (Some(Some(m)), _) => (m, 0),
                    // One missed echo inside a run: a reflector within β of the readings on
                    // both sides of it is within β of it too (the beam is wider than a step),
                    // so its silence was the ranger's fault, not the reflector leaving.
                    (Some(None), Some(after_m)) => (after_m, 1),
                    _ => break,
                };
                if abs(next_m - previous_m) > tolerance_m {
                    break;
                }
                sum_m += next_m;
                previous_m = next_m;
                least_m = least_m.min(next_m);
                most_m = most_m.max(next_m);
                echoes += 1;
                end += 1 + skipped;
            }
            let count = f32::from(echoes);
            let (a, b) = (&readings[start], &readings[end]);
            let middle = &readings[(start + end) / 2];
            // A region of constant depth: as wide as the beam's half-angle at least (a plane's,
            // a corner's or an edge's spans about twice that) and level within a cell. Shorter
            // or sloping runs are the arcs of a wall met obliquely: their reflector is somewhere
            // on the arc, not on the axis, so they mark but never confirm.
            let constant_depth = abs(b.neck_angle_rad - a.neck_angle_rad) + 1.0e-4 >= beam_rad
                && most_m - least_m <= g.resolution_m();
            // Bearings in the middle reading's frame: a reading's bearing is its neck angle
            // plus how far the body had turned from the middle one's heading.
            let bearing = |i: usize| {
                let r = &readings[i];
                r.neck_angle_rad + wrap_angle_rad(r.pose.heading_rad - middle.pose.heading_rad)
            };
            // What the reading just past an end heard, and how far its sonar stood from that
            // end's (a moving sweep): a reflector at `end_m` may have come that much nearer or
            // farther for it, into the blind disc or out of range, where silence says nothing.
            let window = (robot.sonar_min_range_m, robot.sonar_range_m);
            let neighbour = |i: Option<usize>, end: usize| {
                i.and_then(|i| readings.get(i)).map(|r| {
                    let (here, there) = (
                        readings[end].pose.point_ahead(robot.sonar_offset_m),
                        r.pose.point_ahead(robot.sonar_offset_m),
                    );
                    let moved_m = hypot(there.x_m - here.x_m, there.y_m - here.y_m);
                    (r.range_m, moved_m, window)
                })
            };
            let (before, after) = (
                neighbour(start.checked_sub(1), start),
                neighbour(Some(end + 1), end),
            );
            let first = RunEnd {
                bearing_rad: bearing(start),
                side: RunSide::of_neighbour(before, first_m),
            };
            let last = RunEnd {
                bearing_rad: bearing(end),
                side: RunSide::of_neighbour(after, previous_m),
            };
            let step_rad = match (start.checked_sub(1), readings.get(start + 1)) {
                (_, Some(_)) => bearing(start + 1) - bearing(start),
                (Some(before), None) => bearing(start) - bearing(before),
                (None, None) => 0.0,
            };
            let depth_m = sum_m / count;
            // A sloping run (a wall heard diffusely, its range growing on both sides of its
            // nearest point) holds a region of constant depth too: the readings within a cell
            // of its least range, when they are at least β wide and inside the run (the range
            // rises on both sides). That is the wall's foot; the rest of the run is its arc.
            let sloping_foot = if constant_depth || !read_standing {
                None
            } else {
                nearest_stretch(readings, (start, end), least_m, g.resolution_m())
                    .filter(|&(a, b)| {
                        a > start && b < end && abs(bearing(b) - bearing(a)) + 1.0e-4 >= beam_rad
                    })
                    .map(|(a, b)| (0.5 * (bearing(a) + bearing(b)), least_m))
            };
            // A plane's foot: a region of constant depth that the reflector left at both
            // ends, or a sloping run's, read standing. Confirmed when an earlier sweep heard
            // the same plane from elsewhere (`planes`).
            let plane_foot =
                if constant_depth && first.side == RunSide::Open && last.side == RunSide::Open {
                    Some((0.5 * (first.bearing_rad + last.bearing_rad), depth_m))
                } else {
                    sloping_foot
                };
            let plane = plane_foot
                .filter(|_| read_standing)
                .map(|(mid_rad, foot_m)| PlaneSeen {
                    foot: hit_to_world(middle.pose, robot.sonar_offset_m, mid_rad, foot_m),
                    normal_rad: middle.pose.heading_rad + mid_rad,
                    sonar: middle.pose.point_ahead(robot.sonar_offset_m),
                });
            let on_a_known_plane = plane.is_some_and(|p| {
                self.planes
                    .iter()
                    .any(|q| q.agrees_with(&p, 2.0 * sweep_step_rad, g.resolution_m()))
            });
            if let Some(p) = plane {
                remember(&mut self.planes, p);
            }
            let run_start = start;
            start = end + 1;
            // One echo whose neighbours on both sides heard farther, or nothing well inside the
            // window (both sides open): no reflector in the beam is heard by one reading alone
            // (see above), so it is a spurious echo, and marks nothing. The vouching outvotes
            // it too (`swept`).
            if run_start == end
                && bridges_one_reading
                && first.side == RunSide::Open
                && last.side == RunSide::Open
            {
                continue;
            }
            for bearing_rad in reflector_bearings(first, last, step_rad, cone_rad) {
                let p = hit_to_world(middle.pose, robot.sonar_offset_m, bearing_rad, depth_m);
                if !p.is_finite() {
                    continue;
                }
                // One sweep is one viewpoint: its reflectors move a cell once (neighbouring
                // short runs along an oblique wall, 1.8° apart, fall in one cell at short
                // range, and used to confirm their own ghost in free space in front of a
                // doorway).
                let cell = g.cell_xy_on_map(p);
                if let (Some(xy), false) = (cell, self.seen_this_sweep(cell)) {
                    observe_reflector(
                        &mut self.evidence,
                        xy,
                        (true, !self.repeated_viewpoint),
                        constant_depth,
                        on_a_known_plane,
                    );
                }
                mark_point_m(&mut self.grid, p, e);
                let _ = self.hits.push(p);
            }
            if let Some((mid_rad, foot_m)) = sloping_foot {
                let p = hit_to_world(middle.pose, robot.sonar_offset_m, mid_rad, foot_m);
                let cell = g.cell_xy_on_map(p).filter(|_| p.is_finite());
                if let Some(xy) = cell {
                    // One sweep, one step (above), unless a second viewpoint agrees.
                    let first_look = !self.seen_this_sweep(cell);
                    let look = (first_look, !self.repeated_viewpoint);
                    observe_reflector(&mut self.evidence, xy, look, true, on_a_known_plane);
                    mark_point_m(&mut self.grid, p, e);
                    let _ = self.hits.push(p);
                }
            }
        }
        self.stats.hits += self.hits.len() as u32;
        self.hits.len() as u16
    }

    /// After a standing sweep: every cell within range that the sweep vouches for (the Thales
    /// rule, `swept`) steps down one state (`EvidenceMap::observe_vouched_xy`): an unknown or
    /// tentative one becomes free evidence, so the next stop need not read it again, a
    /// confirmed one tentative (a reflector placed off its wall, e.g. on the axis of a reading
    /// whose cone met the wall obliquely, confirmed by a second such reading, is not kept for
    /// ever: it cut a doorway off in `evidence_map::doorway`).
    ///
    /// Exact rays (`--sonar ray`, not a beam) take no mark back: their echoes lie on real
    /// surfaces, and the Thales rule's premise, that a wall's end echoes at any angle, holds
    /// for a cone but not between two rays 1.8° apart. Measured: a thin wall seen edge-on
    /// from 0.44 m lay between two rays along 0.45 m of its length; the sweep vouched for its
    /// cells, its marks went, and with marks grown as discs the body grazed its end (`twil
    /// sonar-grid --quick --evidence-map`, world 2, ray, 1.5 m, stop; the square growth had
    /// covered the end with its corner). Asking a beam's sweep to vouch for the whole cell too
    /// (the point half a diagonal beyond the centre) cost 2 proofs of 192 on `twil
    /// sonar-grid` and 11 of 640 on `--world-seed` 1 to 5, and changed no collision: not
    /// done, the rule's one-cell slack already covers the cell.
    ///
    /// Cost: the cells of the disc
    /// of the range, each asking [`Swept::vouches`]; behind a wall one cone answers, in the
    /// open one pass over the readings without trigonometry (measured on the MCU under QEMU:
    /// `docs/firmware.md`).
    pub(super) fn mark_vouched_free(&mut self, full: bool) {
        let g = *self.grid.geometry();
        let pose = self.pose_world();
        let robot = self.config.robot;
        let sonar = pose.point_ahead(robot.sonar_offset_m);
        let Some((sx, sy)) = g.cell_xy_of(sonar) else {
            return;
        };
        let h = (robot.sonar_range_m / g.resolution_m()) as i32 + 1;
        let band_rad = if full {
            core::f32::consts::PI
        } else {
            crate::sonar::SweepPlan::new(&robot, crate::sonar::SweepKind::Normal)
                .covered_half_angle_rad()
        };
        // Built once, from the fields it reads, so the loop may write the map.
        let swept = Swept::of(
            &self.config,
            self.readings.as_slice(),
            g.resolution_m(),
            (pose, band_rad, true),
        )
        .with_blind_cells(&self.blind_cells);
        self.step_table.build(&swept);
        let swept = swept.with_steps(&self.step_table);
        for y in (sy - h).max(0)..=(sy + h).min(g.height() as i32 - 1) {
            for x in (sx - h).max(0)..=(sx + h).min(g.width() as i32 - 1) {
                if self.evidence.get_xy(x, y) == CellEvidence::Free {
                    continue;
                }
                if swept.vouches(centre(&g, x, y))
                    && (robot.sonar_beam || !self.evidence.is_occupied_xy(x, y))
                    && self.evidence.observe_vouched_xy(x, y) == Change::TakenBack
                {
                    // Full: the grid keeps the mark (the safe side).
                    let _ = self.taken_back.push((x as u16, y as u16));
                }
            }
        }
    }

    /// The marked cells (tentative or confirmed) of the sonar's blind disc at `pose` (see
    /// [`BlindCells`]): the disc is the minimum range, widened by how far the last sweep's
    /// readings were taken from `pose`; a cell stands for its centre. None without the
    /// evidence map (its rule is not in use).
    ///
    /// Only marks: unknown cells there are left to the blind-zone rule (`blind`), which ends
    /// a prefix only where the disc is known (free, vouched for, or marked). Asking
    /// for every cell of the disc to be free on the evidence map (unknown ones blocking too,
    /// and the blind-zone rule reading the map cell by cell) also took the beam collisions of
    /// `twil sonar-grid --worlds 8 --evidence-map` to 0, but reached 163 goals there instead
    /// of 193, and 39 instead of 66 on the bundled worlds (`evidence_map::grid`): most
    /// stops near a wall hold an unknown cell in the disc, and each takes the half-plane
    /// beyond it from the sweep.
    ///
    /// Cost: the square around the disc, about 150 cells at 0.26 m and 5 cm.
    pub(super) fn find_blind_cells(&self, pose: Pose) -> BlindCells {
        if !self.config.evidence_map {
            return BlindCells::NONE;
        }
        let robot = &self.config.robot;
        let g = *self.grid.geometry();
        let res_m = g.resolution_m();
        let shift_m = reading_shift_m(self.readings.as_slice(), pose, robot.sonar_offset_m);
        let radius_m = robot.sonar_min_range_m + shift_m;
        // Readings from nowhere in particular (a NaN): nothing can be vouched for.
        if !(radius_m.is_finite() && radius_m < robot.sonar_range_m && res_m > 0.0) {
            return BlindCells::OVERFLOWED;
        }
        let sonar = pose.point_ahead(robot.sonar_offset_m);
        let body_at = pose.position();
        let body_m = robot.physical_radius_m();
        let n = (radius_m / res_m) as i32 + 2;
        let mut cells = BlindCells::NONE;
        let (sx, sy) = ((sonar.x_m / res_m) as i32, (sonar.y_m / res_m) as i32);
        for y in sy - n..=sy + n {
            for x in sx - n..=sx + n {
                let c = centre(&g, x, y);
                if hypot(c.x_m - sonar.x_m, c.y_m - sonar.y_m) >= radius_m
                    || !self.evidence.is_occupied_xy(x, y)
                {
                    continue;
                }
                let (x0, y0) = (x as f32 * res_m, y as f32 * res_m);
                let far_x = abs(body_at.x_m - x0).max(abs(body_at.x_m - (x0 + res_m)));
                let far_y = abs(body_at.y_m - y0).max(abs(body_at.y_m - (y0 + res_m)));
                if hypot(far_x, far_y) <= body_m {
                    continue; // the body stands there
                }
                cells.push(x, y);
            }
        }
        cells
    }

    /// A point the body would reach that no sweep could vouch for, after a full standing sweep
    /// (`prefix`): an unknown cell becomes tentative and is grown into the grid, so the next
    /// plan goes round it. Anything else is left as it is. Returns whether the map changed.
    pub(super) fn mark_suspect_m(&mut self, p: PointM) -> bool {
        match self.grid.geometry().cell_xy_on_map(p) {
            Some((x, y)) => self.mark_suspect_xy(x, y),
            None => false,
        }
    }

    /// An unknown cell becomes a suspect: tentative on the evidence map, grown into the grid.
    /// Returns whether it was unknown.
    fn mark_suspect_xy(&mut self, x: i32, y: i32) -> bool {
        if self.evidence.suspect_xy(x, y) != Change::NowOccupied {
            return false;
        }
        let g = *self.grid.geometry();
        mark_point_m(&mut self.grid, centre(&g, x, y), self.expansion_cells);
        true
    }

    /// After a full standing sweep: unknown cells no reading vouched for, in the ring from one
    /// to three cells outside the planning radius, become suspects (tentative, grown into the
    /// grid). The ring starts outside the radius so the robot's own cell stays free.
    pub(super) fn mark_suspects(&mut self) {
        let g = *self.grid.geometry();
        let e = self.expansion_cells as i32;
        let pose = self.pose_world();
        let Some((cx, cy)) = g.cell_xy_of(pose.position()) else {
            return;
        };
        let (inner, outer) = (e + 1, e + 3);
        let mut suspects: Vec<(i32, i32), 256> = Vec::new();
        {
            let swept = self.swept(pose, core::f32::consts::PI, true);
            for y in cy - outer..=cy + outer {
                for x in cx - outer..=cx + outer {
                    let (dx, dy) = (x - cx, y - cy);
                    let d2 = dx * dx + dy * dy;
                    if d2 < inner * inner || d2 > outer * outer || !g.contains_xy(x, y) {
                        continue;
                    }
                    if self.evidence.get_xy(x, y) != CellEvidence::Unknown
                        || swept.vouches(centre(&g, x, y))
                    {
                        continue;
                    }
                    // Full: the rest of the ring stays unknown (the corridor rule still keeps
                    // the body out of it).
                    let _ = suspects.push((x, y));
                }
            }
        }
        for &(x, y) in suspects.iter() {
            self.mark_suspect_xy(x, y);
        }
    }
}

/// Centre of the cell at signed indices (on the map or not), metres.
pub(super) fn centre(g: &crate::grid::GridGeometry, x: i32, y: i32) -> PointM {
    PointM::new(
        (x as f32 + 0.5) * g.resolution_m(),
        (y as f32 + 0.5) * g.resolution_m(),
    )
}

/// One evidence step of a reflector on its cell, unknown or free → tentative → confirmed; a
/// tentative mark is confirmed only from a new viewpoint (`Mission::note_viewpoint`), so a
/// mark from a viewpoint met before is made but never confirmed.
fn step_occupied<const W: usize, const E: usize>(
    evidence: &mut EvidenceMap<W, E>,
    (x, y): (i32, i32),
    new_viewpoint: bool,
) {
    if new_viewpoint || evidence.get_xy(x, y) != CellEvidence::Tentative {
        evidence.observe_occupied_xy(x, y);
    }
}

/// A reflector's evidence on its cell: on the sweep's first look at the cell one step
/// (occupied for a region of constant depth, an arc's mark otherwise; up to confirmed only
/// from a new viewpoint, `new_viewpoint`), and a second step for a region of constant depth
/// on a plane that another viewpoint heard (`planes`).
fn observe_reflector<const W: usize, const E: usize>(
    evidence: &mut EvidenceMap<W, E>,
    (x, y): (i32, i32),
    (first_look, new_viewpoint): (bool, bool),
    constant_depth: bool,
    on_a_known_plane: bool,
) {
    if first_look {
        if constant_depth {
            step_occupied(evidence, (x, y), new_viewpoint);
        } else {
            evidence.observe_arc_xy(x, y);
        }
    }
    if constant_depth && on_a_known_plane && evidence.get_xy(x, y) == CellEvidence::Tentative {
        evidence.observe_occupied_xy(x, y);
    }
}

/// The readings of `run` (first and last index) within `cell_m` of `least_m`, the run's least
/// range: the first and the last of them when no reading between them is farther (silences,
/// bridged dropouts, pass), else `None`.
fn nearest_stretch(
    readings: &[crate::sonar::Reading],
    (start, end): (usize, usize),
    least_m: f32,
    cell_m: f32,
) -> Option<(usize, usize)> {
    let near = |i: usize| {
        readings
            .get(i)
            .and_then(|r| r.range_m)
            .is_some_and(|m| m >= least_m - 1.0e-3 && m <= least_m + cell_m)
    };
    let a = (start..=end).find(|&i| near(i))?;
    let b = (start..=end).rev().find(|&i| near(i))?;
    let unbroken = (a..=b).all(|i| near(i) || readings.get(i).is_some_and(|r| r.range_m.is_none()));
    unbroken.then_some((a, b))
}
