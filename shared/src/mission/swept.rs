//! What a standing sweep vouches for between its rays.
//!
//! The rays of a sweep are 1.8° apart: at 1.5 m they leave 4.7 cm between them, at 6 m 19 cm,
//! so cells between two rays are crossed by neither, and the seen grid alone would call them
//! unknown. A point between two neighbouring readings is vouched for when it is no farther from
//! the sonar than what *both* readings prove free (an echo a cell short of itself, silence a
//! cell short of the range) and no nearer than the sonar's minimum range (inside it the
//! transducer is still ringing: a wall there reads as silence).
//!
//! With `echo_limited` off it answers only "was this bearing read?": what decides whether a
//! full sweep would show more (it cannot see behind an echo, nor farther, either).
//!
//! This replaced "anything inside the sweep's band is known", which trusted the band out to the
//! range whatever the rays met: a reading that echoed off a wall's near end at 0.9 m vouched for
//! the wall's unmarked far part at 1.6 m on the same bearing, and the robot (in-process device,
//! office, 6 m, stop mode) planned and drove through that part.

use crate::control::Pose;
use crate::geom::PointM;
use crate::math::{abs, atan2, cos, hypot, sin, sqrt, wrap_angle_rad};
use crate::sonar::Reading;

use super::MissionConfig;

mod steps;

pub use steps::StepTable;
use steps::{periodic, reads_all_round, Basis, Candidates, Frame, WindowVerdict};

/// A standing sweep, read from where it was taken.
#[derive(Clone, Copy)]
pub(super) struct Swept<'a> {
    /// Its readings in neck-angle order (each with the pose it was taken from).
    pub readings: &'a [Reading],
    /// Where the robot stood and faced.
    pub pose: Pose,
    /// Sonar ahead of the centre, metres.
    pub sonar_offset_m: f32,
    /// Only readings within this angle of the heading count, radians (0: none).
    pub half_band_rad: f32,
    /// The sonar's minimum range, metres.
    pub min_range_m: f32,
    /// The sonar's range, metres.
    pub range_m: f32,
    /// Grid resolution (what an echo or silence proves stops a cell short), metres.
    pub cell_m: f32,
    /// Limit each bearing by its readings' echoes, the range and the blind zone (`false`:
    /// ask only "was this bearing read?", the question a full sweep can answer).
    pub echo_limited: bool,
    /// The evidence map's rule (see [`Swept::vouches_thales`]) with this beam half-angle,
    /// radians; negative: the rule above (an echo limits only its own bearing).
    pub thales_beam_rad: f32,
    /// The cone within which a reading is sure to hear a reflector facing it, radians: the
    /// beam's half-angle for a beam sonar, negative for a ray (which hears only on its axis).
    /// It lets most readings of a candidate's cone outvote a few (see
    /// [`Swept::vouches_thales`]); a wider cone than the sensor's would vouch for walls.
    pub heard_beam_rad: f32,
    /// How far the sonar stood from where `pose` puts it in any reading, metres (0: every
    /// reading from `pose`; see [`reading_shift_m`]).
    pub reading_shift_m: f32,
    /// Marked cells of the sonar's blind disc (see [`BlindCells`]).
    pub blind_cells: &'a BlindCells,
    /// The majority rule's steps, read once for the sweep (see [`StepTable`]); `None`: counted
    /// point by point.
    pub steps: Option<&'a StepTable>,
}

/// Most marked cells of the blind disc a sweep may hold; with more, the evidence map's rule
/// vouches for nothing. A straight wall across a 0.26 m disc marks about 11 cells of 5 cm, a
/// corner about 21.
pub const MAX_BLIND_CELLS: usize = 24;

/// The marked cells (a reflector heard there) of the sonar's blind disc (its minimum range
/// around it, widened by the sweep's shift) when a sweep is read. The Thales rule
/// ([`Swept::vouches_thales`]) hears the nearest point of every wall through a point *unless*
/// that nearest point lies in the blind disc, where a wall reads as silence: a point is not
/// vouched for when a marked cell of the disc lies inside the circle whose diameter joins the
/// sonar and the point (a wall from that cell to the point would be silent). Without this a
/// robot that stopped with its sonar 0.257 m from a thin wall it had heard face-on vouched for
/// the cells behind the wall and drove into it (`twil sonar-grid --worlds 8 --evidence-map`,
/// world 7, 10° beam and incidence limit, 3 m, stop mode). Unknown cells of the disc are the
/// blind-zone rule's (`blind`); see `Mission::find_blind_cells` for why not here.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlindCells {
    /// Grid cells (x, y).
    cells: [(i16, i16); MAX_BLIND_CELLS],
    len: u8,
    /// More than [`MAX_BLIND_CELLS`] were found: vouch for nothing.
    overflow: bool,
}

impl BlindCells {
    /// None: no mark in the blind disc (or the rule not in use).
    pub const NONE: BlindCells = BlindCells {
        cells: [(0, 0); MAX_BLIND_CELLS],
        len: 0,
        overflow: false,
    };

    /// Too many to hold, or not to be trusted: nothing is vouched for.
    pub const OVERFLOWED: BlindCells = BlindCells {
        overflow: true,
        ..BlindCells::NONE
    };

    /// Add a cell; past the capacity (or off the `i16` range) the set overflows.
    pub fn push(&mut self, x: i32, y: i32) {
        let (Ok(x), Ok(y)) = (i16::try_from(x), i16::try_from(y)) else {
            self.overflow = true;
            return;
        };
        match self.cells.get_mut(self.len as usize) {
            Some(slot) => {
                *slot = (x, y);
                self.len += 1;
            }
            None => self.overflow = true,
        }
    }

    /// The cells found.
    pub fn cells(&self) -> &[(i16, i16)] {
        &self.cells[..self.len as usize]
    }

    /// Did more cells than [`MAX_BLIND_CELLS`] turn up?
    pub fn overflowed(&self) -> bool {
        self.overflow
    }

    /// Does one of the cells (`cell_m` wide, the grid's origin at 0) reach into the disc
    /// centred on `centre` of radius `radius_m`?
    fn reach_disc(&self, centre: PointM, radius_m: f32, cell_m: f32) -> bool {
        self.overflow
            || self.cells().iter().any(|&(x, y)| {
                let (x0, y0) = (x as f32 * cell_m, y as f32 * cell_m);
                let dx = abs(centre.x_m - centre.x_m.clamp(x0, x0 + cell_m));
                let dy = abs(centre.y_m - centre.y_m.clamp(y0, y0 + cell_m));
                let gap_m = hypot(dx, dy);
                gap_m.is_nan() || gap_m <= radius_m // a NaN blocks
            })
    }
}

/// How far the sonar (`sonar_offset_m` ahead of the centre) stood from where `pose` puts it
/// in any of `readings`, metres; infinite for a NaN.
pub(super) fn reading_shift_m(readings: &[Reading], pose: Pose, sonar_offset_m: f32) -> f32 {
    let here = pose.point_ahead(sonar_offset_m);
    let mut shift_m = 0.0f32;
    for r in readings {
        let there = r.pose.point_ahead(sonar_offset_m);
        let d_m = hypot(there.x_m - here.x_m, there.y_m - here.y_m);
        if d_m.is_nan() {
            return f32::INFINITY;
        }
        shift_m = shift_m.max(d_m);
    }
    shift_m
}

impl<'a> Swept<'a> {
    /// The last sweep (`readings`) of a mission configured by `config`, on a grid of
    /// `cell_m`, read from `pose`, vouching within `half_band_rad` of its heading, limited by
    /// echoes or not (`echo_limited`).
    pub fn of(
        config: &MissionConfig,
        readings: &'a [Reading],
        cell_m: f32,
        (pose, half_band_rad, echo_limited): (Pose, f32, bool),
    ) -> Self {
        let robot = &config.robot;
        let evidence = config.evidence_map;
        let thales_beam_rad = if evidence {
            robot.sonar_beam_half_angle_deg.max(0.0) * (core::f32::consts::PI / 180.0)
        } else {
            -1.0
        };
        Swept {
            readings,
            pose,
            sonar_offset_m: robot.sonar_offset_m,
            half_band_rad,
            min_range_m: robot.sonar_min_range_m,
            range_m: robot.sonar_range_m,
            cell_m,
            echo_limited,
            thales_beam_rad,
            heard_beam_rad: if evidence && robot.sonar_beam {
                thales_beam_rad
            } else {
                -1.0
            },
            reading_shift_m: if evidence {
                reading_shift_m(readings, pose, robot.sonar_offset_m)
            } else {
                0.0
            },
            blind_cells: &BlindCells::NONE,
            steps: None,
        }
    }

    /// The same sweep, reading the majority rule from `steps` (built for it with
    /// [`StepTable::build`]; a table built for another sweep is not used).
    pub fn with_steps(self, steps: &'a StepTable) -> Self {
        // Its basis (where the sonar stood, the bearings, the slack) and its frame.
        let built_for_it = steps.basis.is_some()
            && steps.basis == self.basis()
            && steps.frame == self.frame(self.heard_rad());
        Swept {
            steps: built_for_it.then_some(steps),
            ..self
        }
    }

    /// The same sweep, with the blind disc's marked cells.
    pub fn with_blind_cells(self, blind_cells: &'a BlindCells) -> Self {
        Swept {
            blind_cells,
            ..self
        }
    }

    /// Nothing: for moving passes, whose readings came from other poses.
    pub const NOTHING: Swept<'static> = Swept {
        readings: &[],
        pose: Pose {
            x_m: 0.0,
            y_m: 0.0,
            heading_rad: 0.0,
        },
        sonar_offset_m: 0.0,
        half_band_rad: 0.0,
        min_range_m: 0.0,
        range_m: 0.0,
        cell_m: 0.0,
        echo_limited: true,
        thales_beam_rad: -1.0,
        heard_beam_rad: -1.0,
        reading_shift_m: 0.0,
        blind_cells: &BlindCells::NONE,
        steps: None,
    };

    /// Does the sweep prove `q` free (see the module docs)?
    pub fn vouches(&self, q: PointM) -> bool {
        let n = self.readings.len();
        if n < 2 || self.half_band_rad.is_nan() || self.half_band_rad <= 0.0 {
            return false;
        }
        // The same for every point: from the table when the sweep has one (a sine and a
        // cosine less per point).
        let sonar = match self.steps.and_then(|t| t.basis) {
            Some(basis) => basis.sonar,
            None => self.pose.point_ahead(self.sonar_offset_m),
        };
        let d_m = hypot(q.x_m - sonar.x_m, q.y_m - sonar.y_m);
        let thales = self.echo_limited && self.thales_beam_rad >= 0.0;
        // Out of range vouches nothing (`vouches_thales`): known before the bearing.
        if thales && !(d_m >= self.min_range_m && d_m <= self.range_m - self.cell_m) {
            return false;
        }
        let rel =
            wrap_angle_rad(atan2(q.y_m - sonar.y_m, q.x_m - sonar.x_m) - self.pose.heading_rad);
        if abs(rel) > self.half_band_rad {
            return false;
        }
        if !self.echo_limited {
            return true;
        }
        if thales {
            return self.vouches_thales(rel, d_m);
        }
        if d_m.is_nan() || d_m < self.min_range_m {
            return false;
        }
        // The readings on each side of `rel`: the sweep's angles are evenly spaced, so the
        // index follows from the first and last (a sweep out of order vouches for less).
        let first = self.readings[0].neck_angle_rad;
        let last = self.readings[n - 1].neck_angle_rad;
        let step = (last - first) / (n - 1) as f32;
        if !(step.is_finite() && step > 0.0) {
            return false;
        }
        let at = (rel - first) / step;
        if !(at >= 0.0 && at <= (n - 1) as f32) {
            return false;
        }
        let below = (at as usize).min(n - 1);
        let above = (below + 1).min(n - 1);
        let mut proven_m = f32::MAX;
        for i in [below, above] {
            let r = &self.readings[i];
            // Each neighbour must lie within a step of `q`'s bearing.
            let off_rad = abs(r.neck_angle_rad - rel);
            if off_rad.is_nan() || off_rad > step * 1.001 {
                return false;
            }
            let free_m = r.range_m.unwrap_or(self.range_m) - self.cell_m;
            proven_m = proven_m.min(free_m);
        }
        d_m <= proven_m
    }
}

impl Swept<'_> {
    /// The evidence map's rule: does the sweep prove free the point at `rel` radians off the
    /// heading and `d_m` from the sonar?
    ///
    /// Thales: the nearest point to the sonar of any wall through the point lies on the circle
    /// whose diameter joins them, so at some bearing `φ` within 90° of `rel`, at
    /// `d·cos(φ − rel)` or nearer; and that nearest point echoes whatever the incidence limit:
    /// it is the perpendicular foot (met face-on) or the wall's end (which echoes at any
    /// angle). A reading at `φᵢ` hears anything in its cone (± the beam half-angle), so the
    /// point is vouched for when
    ///
    /// - it is outside the blind zone and a cell short of the range;
    /// - the sweep read every bearing where such a foot could be heard: `±acos(min range / d)`
    ///   around `rel` (nearer feet lie in the blind zone, next to the robot's own disc), within
    ///   the readings' bearings widened by the beam;
    /// - no echo contradicts it: no reading `i` heard something at `d·cos(max(0, |φᵢ − rel| −
    ///   beam)) + one cell` or nearer (the foot could be anywhere in its cone); or, with a beam
    ///   sonar, every candidate is ruled out by most of the readings whose cones hold it
    ///   ([`Swept::candidates`]);
    /// - no marked cell of the blind disc ([`BlindCells`]) lies inside the circle on the sonar
    ///   and the point: a wall from there to the point has its nearest point where the sonar
    ///   is deaf.
    ///
    /// Silence alone never vouches: a silent bearing counts only with every other bearing of the
    /// window read. A dropped echo on a wall face leaves the face's other readings (a face
    /// echoes over the beam's width plus the incidence limit, about 17 readings at 15°), and
    /// half a cone of them would have to drop to rule its foot out.
    ///
    /// Readings taken elsewhere (a robot that had not quite stopped, or turned while it held):
    /// each reading is read at its own heading, and the sonar's largest shift `δ` from `pose`
    /// ([`Swept::reading_shift_m`]) is added to every bound (a wall's distance from the sonar
    /// changes by at most `δ`) and taken off the cone in which a reading is sure to hear a
    /// reflector (`asin(δ / min range)`: a wall's end, seen from `δ` away, moves that far
    /// in bearing at worst). At `δ` ≥ the minimum range nothing is vouched for.
    ///
    /// Cost: one pass over the readings (at most 201); with a beam, when an echo contradicts,
    /// one more per bearing step of the window, each over one cone of readings.
    pub fn vouches_thales(&self, rel: f32, d_m: f32) -> bool {
        let Some((slack, window)) = self.thales_window(rel, d_m) else {
            return false;
        };
        self.thales_decision(rel, d_m, slack, window)
    }

    /// The conditions of [`Swept::vouches_thales`] that need no echo: in range, the window read,
    /// no mark of the blind disc in the way. Returns the slack and the window's half-angle.
    fn thales_window(&self, rel: f32, d_m: f32) -> Option<(f32, f32)> {
        let n = self.readings.len();
        if n < 2 || !(d_m >= self.min_range_m && d_m <= self.range_m - self.cell_m) {
            return None;
        }
        let shift_m = self.reading_shift_m;
        // The same for every point of the sweep: from its table when it has one.
        let Basis {
            slack,
            first,
            last,
            step,
            sonar,
        } = self.steps.and_then(|t| t.basis).or_else(|| self.basis())?;
        // The cone a foot may hide in, less the slack: what the window may be read with.
        let beam_rad = self.thales_beam_rad - slack;
        let c = (self.min_range_m / d_m).clamp(0.0, 1.0);
        // acos(min range / d)
        let window = atan2(sqrt(1.0 - c * c), c);
        let read = reads_all_round(first, last, step)
            || (rel - window >= first - beam_rad - 1.0e-4
                && rel + window <= last + beam_rad + 1.0e-4);
        if !read {
            return None;
        }
        // A wall whose nearest point lies in the blind disc is silent: none may pass through
        // a marked cell there inside the circle on the sonar and the point
        // (widened by half a cell for the point's cell and by the shift).
        if self.blind_cells.overflowed() || !self.blind_cells.cells().is_empty() {
            let heading = self.pose.heading_rad + rel;
            let centre = PointM::new(
                sonar.x_m + 0.5 * d_m * cos(heading),
                sonar.y_m + 0.5 * d_m * sin(heading),
            );
            let radius_m = 0.5 * d_m + 0.5 * self.cell_m + shift_m;
            if self.blind_cells.reach_disc(centre, radius_m, self.cell_m) {
                return None;
            }
        }
        Some((slack, window))
    }

    /// What the echoes say of a point that passed [`Swept::thales_window`]: the first rule
    /// (no reading contradicts) or, with a beam, the majority rule (every candidate ruled
    /// out), read in the cheapest order that gives the same answer.
    fn thales_decision(&self, rel: f32, d_m: f32, slack: f32, window: f32) -> bool {
        let candidates = self.candidates(rel, d_m, window, self.heard_beam_rad - slack);
        // Behind a wall the cone on the point's own bearing heard the wall: not vouched for,
        // known from one cone instead of every reading (most points of a 6 m sweep's square
        // lie behind some wall; `mark_vouched_free` asks for each).
        if candidates
            .as_ref()
            .is_some_and(|c| c.heard_near(c.own_step()))
        {
            return false;
        }
        let Some(candidates) = candidates else {
            // No majority cone (a ray, or a sweep read while the robot still moved): the
            // first rule alone, nearer than the table's clear distance without a reading.
            if self.steps.is_some_and(|t| d_m < t.first_rule_clear_m(rel)) {
                return true;
            }
            return !self.any_contradicting(rel, d_m, slack);
        };
        // Nearer than every candidate any step's majority could hear, and the whole window
        // covered: every candidate is ruled out, without looking at one.
        if candidates
            .table
            .is_some_and(|t| d_m < t.clear_within_m(&candidates))
        {
            return true;
        }
        // Candidate by candidate first (with the table, a comparison each): a step some
        // covering reading heard too near also contradicts the first rule, so the answer is
        // no; every step ruled out is yes whatever the first rule says. Only a step no cone
        // covers (past the ends of a sweep that is not all round) leaves it to the first rule.
        match candidates.window_verdict() {
            WindowVerdict::RuledOut => true,
            WindowVerdict::HeardNear => false,
            WindowVerdict::Undecided => !self.any_contradicting(rel, d_m, slack),
        }
    }

    /// A reading's bearing off `pose`'s heading: its neck angle, turned by how far the robot's
    /// heading was from `pose`'s when it was taken.
    fn bearing_rad(&self, r: &Reading) -> f32 {
        r.neck_angle_rad + wrap_angle_rad(r.pose.heading_rad - self.pose.heading_rad)
    }

    /// How far inside the farthest candidate reflector its cone could hold reading `r`
    /// heard something (the first rule: it contradicts the point at `0` or more); `None` when
    /// its cone cannot hold one.
    fn contradiction_m(&self, r: &Reading, rel: f32, d_m: f32, beam_rad: f32) -> Option<f32> {
        // No reading can contradict from beyond the point (the cosine is at most 1): skipped
        // before any trigonometry, which is most of them for a point in the open.
        let range_m = r
            .range_m
            .filter(|&range_m| range_m <= d_m + self.cell_m + self.reading_shift_m)?;
        let off = abs(wrap_angle_rad(self.bearing_rad(r) - rel));
        let nearest = (off - beam_rad).max(0.0);
        if nearest.is_nan() || nearest >= core::f32::consts::FRAC_PI_2 {
            return None;
        }
        Some(d_m * cos(nearest) + self.cell_m + self.reading_shift_m - range_m)
    }

    /// The first rule by its definition: the reading that heard something nearest inside the
    /// farthest candidate reflector its cone could hold (its index), or `None` when no reading
    /// did.
    #[cfg(test)]
    fn most_contradicting(&self, rel: f32, d_m: f32, slack_rad: f32) -> Option<usize> {
        let beam = self.thales_beam_rad + slack_rad;
        let mut worst: Option<(usize, f32)> = None;
        for (i, r) in self.readings.iter().enumerate() {
            let Some(inside_m) = self.contradiction_m(r, rel, d_m, beam) else {
                continue;
            };
            if inside_m >= 0.0 && worst.is_none_or(|(_, w)| inside_m > w) {
                worst = Some((i, inside_m));
            }
        }
        worst.map(|(i, _)| i)
    }

    /// Does some reading contradict the point by the first rule? The readings around the
    /// point's own bearing first: behind a wall they heard it, and the answer comes from a
    /// few instead of the whole sweep.
    fn any_contradicting(&self, rel: f32, d_m: f32, slack_rad: f32) -> bool {
        let beam = self.thales_beam_rad + slack_rad;
        let contradicts = |r: &Reading| {
            self.contradiction_m(r, rel, d_m, beam)
                .is_some_and(|inside_m| inside_m >= 0.0)
        };
        let n = self.readings.len();
        let (Some(a), Some(b)) = (self.readings.first(), self.readings.last()) else {
            return false;
        };
        let (a, b) = (self.bearing_rad(a), self.bearing_rad(b));
        let at = (rel - a) / (b - a) * n.saturating_sub(1) as f32;
        if at.is_finite() && at >= 0.0 && at < n as f32 {
            let i = at as usize;
            let near = self
                .readings
                .get(i.saturating_sub(4)..(i + 5).min(n))
                .unwrap_or(&[]);
            if near.iter().any(contradicts) {
                return true;
            }
        }
        self.readings.iter().any(contradicts)
    }

    /// The rule read candidate by candidate: every bearing `ψ` of the window is a candidate
    /// for the nearest point of a wall through the point, at `d·cos(ψ − rel)` or nearer. It
    /// is ruled out when most of the readings whose cones hold it (a majority of the
    /// `2m + 1` a whole cone spans) heard nothing that near: such a reflector would have
    /// echoed in every one of them. Bearings are taken a step wide, each with its farthest
    /// candidate and only the readings whose cones hold the whole step (conservative).
    /// `None` when no reading's cone holds a step (a ray: nothing is ruled out this way).
    ///
    /// Why a majority and not every reading: a spurious short echo (crosstalk) or a jamb's
    /// edge in one side of the cone contradicted the whole window before, and one such echo in
    /// a sweep (1 % of readings) took the vouching of everything behind it; a dropped echo on
    /// a real wall leaves the wall's other readings, and half a cone of them would have to
    /// drop to rule the wall out.
    fn candidates(
        &self,
        rel: f32,
        d_m: f32,
        window: f32,
        heard_rad: f32,
    ) -> Option<Candidates<'_>> {
        // A table is attached only to the sweep it was built for (`with_steps`), whose
        // frame it holds: not recomputed for every point.
        let (frame, table) = match self.steps.and_then(|t| Some((t.frame?, t))) {
            Some((frame, t)) if frame.heard_rad == heard_rad => (frame, Some(t)),
            _ => (self.frame(heard_rad)?, None),
        };
        Some(Candidates {
            swept: self,
            rel,
            d_m,
            window,
            table,
            frame,
        })
    }

    /// The bearing steps of the majority rule for cones of `heard_rad`; `None` when no cone
    /// holds a whole step.
    fn frame(&self, heard_rad: f32) -> Option<Frame> {
        let (a, b) = (
            self.bearing_rad(self.readings.first()?),
            self.bearing_rad(self.readings.last()?),
        );
        let (first, last, step) = self.bearing_span()?;
        let m = floor_i32((heard_rad - 0.5 * step) / step);
        if m < 0 {
            return None;
        }
        let all_round = reads_all_round(first, last, step);
        Some(Frame {
            first,
            step,
            all_round,
            period: periodic(all_round, step),
            ascending: a <= b,
            m,
            heard_rad,
        })
    }

    /// What [`Swept::thales_window`] reads the same for every point: `None` when the sweep
    /// vouches for nothing (read from nowhere in particular, or bearings out of order).
    fn basis(&self) -> Option<Basis> {
        // Readings from elsewhere: each is read at its own heading (exact), and the sonar's
        // shift from `pose` widens every bound.
        let x = self.reading_shift_m / self.min_range_m;
        if x.is_nan() || x >= 1.0 {
            return None;
        }
        let slack = atan2(x, sqrt(1.0 - x * x)); // asin(shift / min range)
        let (first, last, step) = self.bearing_span()?;
        Some(Basis {
            slack,
            first,
            last,
            step,
            sonar: self.pose.point_ahead(self.sonar_offset_m),
        })
    }

    /// The least and the greatest bearing of the sweep and the step between its readings
    /// (either direction: only the ends matter); `None` for fewer than two readings or
    /// bearings out of order.
    fn bearing_span(&self) -> Option<(f32, f32, f32)> {
        let n = self.readings.len();
        let (a, b) = (
            self.bearing_rad(self.readings.first()?),
            self.bearing_rad(self.readings.last()?),
        );
        let (first, last) = (a.min(b), a.max(b));
        let step = (last - first) / n.saturating_sub(1).max(1) as f32;
        (n >= 2 && step.is_finite() && step > 0.0).then_some((first, last, step))
    }

    /// The cone the majority rule reads with: the heard beam less the shift's slack.
    fn heard_rad(&self) -> f32 {
        let x = self.reading_shift_m / self.min_range_m;
        self.heard_beam_rad - atan2(x, sqrt(1.0 - x * x))
    }
}

/// `⌊x⌋` as an `i32` (saturating; NaN gives 0).
fn floor_i32(x: f32) -> i32 {
    let t = x as i32;
    if (t as f32) > x {
        t - 1
    } else {
        t
    }
}

#[cfg(test)]
mod tests {
    use super::steps::StepVerdict;
    use super::*;
    use heapless::Vec;

    const STEP: f32 = 1.8 * core::f32::consts::PI / 180.0;

    fn sweep(range_at: impl Fn(i32) -> Option<f32>) -> Vec<Reading, 201> {
        let mut v = Vec::new();
        for i in -52..=52 {
            let _ = v.push(Reading {
                neck_angle_rad: i as f32 * STEP,
                range_m: range_at(i),
                pose: Pose::new(0.0, 0.0, 0.0),
            });
        }
        v
    }

    fn swept(readings: &[Reading]) -> Swept<'_> {
        Swept {
            readings,
            pose: Pose::new(0.0, 0.0, 0.0),
            sonar_offset_m: 0.2,
            half_band_rad: 52.0 * STEP,
            min_range_m: 0.26,
            range_m: 1.5,
            cell_m: 0.05,
            echo_limited: true,
            thales_beam_rad: -1.0,
            heard_beam_rad: -1.0,
            reading_shift_m: 0.0,
            blind_cells: &BlindCells::NONE,
            steps: None,
        }
    }

    /// [`thales`], read from the origin: readings taken elsewhere widen its bounds.
    fn thales_shifted(readings: &[Reading]) -> Swept<'_> {
        Swept {
            reading_shift_m: reading_shift_m(readings, Pose::new(0.0, 0.0, 0.0), 0.2),
            ..thales(readings)
        }
    }

    fn thales(readings: &[Reading]) -> Swept<'_> {
        Swept {
            thales_beam_rad: 15.0f32.to_radians(),
            heard_beam_rad: 15.0f32.to_radians(),
            ..swept(readings)
        }
    }

    /// The rule as written in [`Swept::vouches_thales`]'s documentation, read the slow way:
    /// no reading contradicts, or every candidate of the window is ruled out, each step's
    /// readings counted one by one (no table, no shortcut).
    fn vouches_by_definition(s: &Swept<'_>, q: PointM) -> bool {
        let sonar = s.pose.point_ahead(s.sonar_offset_m);
        let rel = wrap_angle_rad(atan2(q.y_m - sonar.y_m, q.x_m - sonar.x_m) - s.pose.heading_rad);
        if s.readings.len() < 2 || abs(rel) > s.half_band_rad {
            return false;
        }
        let d_m = hypot(q.x_m - sonar.x_m, q.y_m - sonar.y_m);
        let Some((slack, window)) = s.thales_window(rel, d_m) else {
            return false;
        };
        let untabled = Swept { steps: None, ..*s };
        let no_contradiction = untabled.most_contradicting(rel, d_m, slack).is_none();
        let every_candidate_ruled_out = untabled
            .candidates(rel, d_m, window, s.heard_beam_rad - slack)
            .is_some_and(|c| {
                let (step, first) = (c.frame.step, c.frame.first);
                let k_lo = floor_i32((rel - window - first) / step - 0.5);
                let k_hi = floor_i32((rel + window - first) / step + 0.5) + 1;
                (k_lo..=k_hi).all(|k| {
                    matches!(
                        c.verdict(k),
                        StepVerdict::Outside
                            | StepVerdict::Read {
                                majority_clear: true,
                                ..
                            }
                    )
                })
            });
        no_contradiction || every_candidate_ruled_out
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]
        /// The shortcuts (the own step first, the table's clear distances and majorities, the
        /// window before the first rule) answer every point as the rule's definition does, for
        /// a normal sweep and one all round, whatever the readings heard.
        #[test]
        fn the_shortcuts_vouch_exactly_what_the_rule_does(
            ranges in proptest::collection::vec(
                proptest::option::of(0.0f32..1.0), 201),
            // The nearest echo: from cluttered (every distance) to open (all far), so that
            // the shortcuts' clear distances reach into the points tested.
            nearest_m in proptest::prop_oneof![proptest::strategy::Just(0.1f32), 0.1f32..1.4],
            all_round in proptest::bool::ANY,
            heard_deg in 4.0f32..25.0,
            shift_m in proptest::prop_oneof![proptest::strategy::Just(0.0f32), 0.0f32..0.1],
        ) {
            let (lo, hi, band) = if all_round {
                (-100, 100, core::f32::consts::PI)
            } else {
                (-52, 52, 52.0 * STEP)
            };
            let mut r: Vec<Reading, 201> = Vec::new();
            for (k, i) in (lo..=hi).enumerate() {
                let _ = r.push(Reading {
                    neck_angle_rad: i as f32 * STEP,
                    range_m: ranges[k].map(|u| nearest_m + u * (1.6 - nearest_m)),
                    pose: Pose::new(0.0, 0.0, 0.0),
                });
            }
            let counted = Swept {
                half_band_rad: band,
                thales_beam_rad: heard_deg.to_radians(),
                heard_beam_rad: heard_deg.to_radians(),
                reading_shift_m: shift_m,
                ..swept(&r)
            };
            let mut table = StepTable::new();
            table.build(&counted);
            proptest::prop_assert!(shift_m > 0.0 || table.frame.is_some());
            let tabled = counted.with_steps(&table);
            for y in -30..=30 {
                for x in -30..=30 {
                    let q = PointM::new(x as f32 * 0.05 + 0.025, y as f32 * 0.05 + 0.025);
                    let expected = vouches_by_definition(&counted, q);
                    proptest::prop_assert_eq!(counted.vouches(q), expected, "{:?}", q);
                    proptest::prop_assert_eq!(tabled.vouches(q), expected, "{:?}", q);
                }
            }
        }
    }

    #[test]
    fn thales_silence_vouches_only_with_the_whole_window_read() {
        let r = sweep(|_| None);
        let s = thales(&r);
        // Straight ahead, 1 m from the sonar: the window ±75° lies inside ±93.6° + 15°.
        assert!(s.vouches(PointM::new(0.2 + 1.0, 0.0)));
        // 60° off the heading: the window reaches 135°, beyond what was read.
        let a = 60.0f32.to_radians();
        assert!(!s.vouches(PointM::new(0.2 + cos_(a), sin_(a))));
        assert!(
            !s.vouches(PointM::new(0.2 + 1.46, 0.0)),
            "a cell short of the range"
        );
        assert!(!s.vouches(PointM::new(0.2 + 0.2, 0.0)), "blind zone");
    }

    #[test]
    fn thales_an_oblique_silent_wall_is_caught_by_its_foot() {
        // A smooth wall through (1.2, 0) from the sonar, its normal 50° off the heading: its foot
        // is at 1.2·cos 50° = 0.77 m on bearing 50°; with a 15° incidence limit only readings
        // within 15° + 15° of 50° hear it. Straight ahead is silent.
        let foot = 50.0f32.to_radians();
        let r = sweep(|i| {
            let phi = i as f32 * STEP;
            let off = abs(phi - foot);
            (off <= 30.0f32.to_radians()).then(|| 1.2 * cos_(foot) / cos_(off.min(0.26)))
        });
        let s = thales(&r);
        assert!(!s.vouches(PointM::new(0.2 + 1.25, 0.0)), "behind the wall");
        assert!(!s.vouches(PointM::new(0.2 + 1.1, 0.0)), "just before it");
        assert!(s.vouches(PointM::new(0.2 + 0.5, 0.0)), "well short of it");
        // The per-bearing rule trusts the silent bearing straight ahead out to the range.
        assert!(swept(&r).vouches(PointM::new(0.2 + 1.25, 0.0)));
    }

    #[test]
    fn thales_a_few_dropouts_on_a_face_vouch_nothing_through_it() {
        // A wall face-on at 1.0 m ahead, echoing within ±30° of its normal, two readings of
        // which dropped out (one of them straight ahead).
        let r = sweep(|i| {
            let phi = i as f32 * STEP;
            let echoes = abs(phi) <= 30.0f32.to_radians() && i != 0 && i != 3;
            echoes.then(|| 1.0 / cos_(phi))
        });
        let s = thales(&r);
        assert!(!s.vouches(PointM::new(0.2 + 1.1, 0.0)));
        assert!(s.vouches(PointM::new(0.2 + 0.85, 0.0)));
    }

    #[test]
    fn thales_one_spurious_short_echo_does_not_blind_the_sweep() {
        // Nothing within range but one spurious echo at 0.4 m, 36° off the heading.
        let r = sweep(|i| (i == 20).then_some(0.4));
        // With a beam, the other readings whose cones hold each candidate outvote it.
        assert!(thales(&r).vouches(PointM::new(0.2 + 1.0, 0.0)));
        // Even on its own bearing: a reflector there would echo in every reading whose cone
        // holds it (15 of them), not in one.
        let a = 36.0f32.to_radians();
        let behind = PointM::new(0.2 + 0.6 * cos_(a), 0.6 * sin_(a));
        assert!(thales(&r).vouches(behind));
        // A post that is really there echoes over the whole cone, and blocks it.
        let post = sweep(|i| (12..=28).contains(&i).then_some(0.4));
        assert!(!thales(&post).vouches(behind));
        // A ray hears only on its axis: one reading is all it has, and it contradicts.
        let ray = Swept {
            heard_beam_rad: -1.0,
            ..thales(&r)
        };
        assert!(!ray.vouches(PointM::new(0.2 + 1.0, 0.0)));
    }

    #[test]
    fn thales_under_half_a_cone_of_dropouts_on_a_face_vouches_nothing_through_it() {
        // A wall face-on at 1.0 m ahead, echoing within ±30° of its normal; seven readings in
        // a row dropped out (a 15° cone holds 15 readings; 8 clear ones rule a candidate out).
        let r = sweep(|i| {
            let phi = i as f32 * STEP;
            let echoes = abs(phi) <= 30.0f32.to_radians() && !(-6..=0).contains(&i);
            echoes.then(|| 1.0 / cos_(phi))
        });
        assert!(!thales(&r).vouches(PointM::new(0.2 + 1.1, 0.0)));
        assert!(thales(&r).vouches(PointM::new(0.2 + 0.85, 0.0)));
    }

    #[test]
    fn thales_readings_taken_elsewhere_widen_every_bound() {
        // The robot turned 3° while it swept a face-on wall 1.0 m ahead of the sonar: each
        // reading is read at its own heading.
        let turned = 3.0f32.to_radians();
        let mut r = sweep(|i| {
            let phi = i as f32 * STEP + turned;
            (abs(phi) <= 20.0f32.to_radians()).then(|| 1.0 / cos_(phi))
        });
        for x in r.iter_mut() {
            x.pose = Pose::new(0.2 - 0.2 * cos_(turned), -0.2 * sin_(turned), turned);
        }
        let s = thales_shifted(&r);
        assert!(s.reading_shift_m < 0.001, "it turned about the sonar");
        assert!(!s.vouches(PointM::new(0.2 + 1.05, 0.0)), "behind the wall");
        assert!(s.vouches(PointM::new(0.2 + 0.85, 0.0)));
        // Taken 5 cm back, the same readings prove 5 cm less.
        for x in r.iter_mut() {
            x.pose.x_m -= 0.05;
        }
        let s = thales_shifted(&r);
        assert!((s.reading_shift_m - 0.05).abs() < 0.001);
        assert!(!s.vouches(PointM::new(0.2 + 0.94, 0.0)));
        assert!(s.vouches(PointM::new(0.2 + 0.85, 0.0)));
        // Taken farther than the minimum range away, they prove nothing.
        for x in r.iter_mut() {
            x.pose.x_m -= 0.25;
        }
        let s = thales_shifted(&r);
        assert!(!s.vouches(PointM::new(0.2 + 0.5, 0.0)));
    }

    #[test]
    fn thales_a_wall_in_the_blind_disc_vouches_nothing_behind_it() {
        // Silent all round: a thin wall 0.23 m ahead of the sonar (at 0.2, 0), inside its
        // 0.26 m blind disc, reads as silence. Its two cells were marked from afar.
        let r = sweep(|_| None);
        let behind = PointM::new(1.2, 0.0);
        assert!(
            thales(&r).vouches(behind),
            "nothing known in the blind disc"
        );
        let mut ahead = BlindCells::NONE;
        ahead.push(8, -1);
        ahead.push(8, 0);
        assert!(!thales(&r).with_blind_cells(&ahead).vouches(behind));
        // A cell behind the sonar's side: no wall through it and the point hides its
        // nearest point there (the circle on the sonar and the point does not reach it).
        let mut aside = BlindCells::NONE;
        aside.push(1, 4);
        assert!(thales(&r).with_blind_cells(&aside).vouches(behind));
        // More cells than it holds: nothing is vouched for.
        let mut full = BlindCells::NONE;
        for i in 0..=MAX_BLIND_CELLS as i32 {
            full.push(-100 - i, -100);
        }
        assert!(full.overflowed());
        assert!(!thales(&r).with_blind_cells(&full).vouches(behind));
    }

    #[test]
    fn silence_vouches_out_to_a_cell_short_of_the_range_and_not_in_the_blind_zone() {
        let r = sweep(|_| None);
        let s = swept(&r);
        // Straight ahead of the sonar (0.2, 0).
        assert!(s.vouches(PointM::new(0.2 + 1.0, 0.0)));
        assert!(s.vouches(PointM::new(0.2 + 1.44, 0.0)));
        assert!(!s.vouches(PointM::new(0.2 + 1.47, 0.0)));
        assert!(!s.vouches(PointM::new(0.2 + 0.2, 0.0)), "blind zone");
        // Between two rays (0.9 steps off one of them).
        let a = 0.9 * STEP;
        assert!(s.vouches(PointM::new(0.2 + cos_(a), sin_(a))));
        // Outside the band (behind).
        assert!(!s.vouches(PointM::new(-1.0, 0.0)));
    }

    #[test]
    fn an_echo_vouches_only_short_of_itself_and_its_neighbours() {
        // An echo at 0.9 m on ray 10 only.
        let r = sweep(|i| (i == 10).then_some(0.9));
        let s = swept(&r);
        let a = 10.0 * STEP;
        assert!(s.vouches(PointM::new(0.2 + 0.8 * cos_(a), 0.8 * sin_(a))));
        assert!(
            !s.vouches(PointM::new(0.2 + 1.2 * cos_(a), 1.2 * sin_(a))),
            "behind the echo"
        );
        // Half-way to ray 11, which heard nothing: the echo still limits it.
        let b = 10.5 * STEP;
        assert!(!s.vouches(PointM::new(0.2 + 1.2 * cos_(b), 1.2 * sin_(b))));
        assert!(!Swept::NOTHING.vouches(PointM::new(1.0, 0.0)));
        // Asked only whether the bearing was read, the echo does not limit it.
        let read = Swept {
            echo_limited: false,
            ..s
        };
        assert!(read.vouches(PointM::new(0.2 + 1.2 * cos_(a), 1.2 * sin_(a))));
    }

    fn cos_(a: f32) -> f32 {
        crate::math::cos(a)
    }
    fn sin_(a: f32) -> f32 {
        crate::math::sin(a)
    }
}
