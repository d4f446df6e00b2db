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
use crate::sonar::{Reading, SWEEP_CAPACITY};

use super::MissionConfig;

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

/// The slack (`asin(shift / min range)`) and the bearings of a sweep, the same for each of its
/// points.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Basis {
    slack: f32,
    first: f32,
    last: f32,
    step: f32,
    /// Where the sonar stood.
    sonar: PointM,
}

/// How the majority rule steps through a sweep's bearings: steps counted from `first` in the
/// readings' ascending order, `m` readings on each side of a step's centre.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Frame {
    first: f32,
    step: f32,
    all_round: bool,
    /// Steps in a whole turn, for a sweep all round whose step divides it (to a thousandth
    /// of a step): step `k` and step `k + period` are one bearing, read by the same readings.
    period: Option<i32>,
    ascending: bool,
    m: i32,
    heard_rad: f32,
}

impl Frame {
    /// The number of step `k` within a turn, for a periodic sweep (the table holds each
    /// bearing once); `k` otherwise.
    fn reduce(&self, k: i32) -> i32 {
        match self.period {
            Some(p) => k.rem_euclid(p),
            None => k,
        }
    }
}

/// What the majority rule reads from each step of one sweep, computed once instead of per
/// point: a standing sweep vouches cell by cell over the disc of its range (tens of thousands
/// of cells at 6 m), each reading up to a hundred steps of a whole cone, and on the MCU that
/// took 0.2 to 1.5 s a sweep (QEMU, `docs/firmware.md`). Whether most covering readings heard
/// nothing as near as a candidate at `f` is whether the `min(m + 1, covering)`-th farthest of
/// their ranges lies beyond `f`: one comparison. Exact: the same answer as counting.
#[derive(Clone, Debug)]
pub struct StepTable {
    frame: Option<Frame>,
    /// Steps tabled, 0 to `len − 1`: their majorities, or without a frame the first rule's
    /// clear distances.
    len: usize,
    /// Readings whose cones hold step `k` whole.
    covering: [u8; SWEEP_CAPACITY],
    /// The range the majority must all lie beyond (silence: infinity; no reading or a NaN
    /// among the majority: minus infinity).
    majority_m: [f32; SWEEP_CAPACITY],
    /// The steps from the first to the last covered one, when every step between is covered
    /// and tabled (see [`StepTable::build_clear_within`]).
    covered: Option<(usize, usize)>,
    /// Per bin of steps, see [`StepTable::build_clear_within`].
    clear_within: [f32; CLEAR_BINS],
    /// The sweep's [`Basis`].
    basis: Option<Basis>,
    /// Per bin, the step that set its clear distance: the first a point beyond it is likely
    /// heard too near in (read first by [`Candidates::window_verdict`]).
    limiting_step: [u8; CLEAR_BINS],
}

/// The middle bearing of bin `b` of a sweep's steps from `first`, `step` apart: bin `b` holds
/// the bearings of steps `CLEAR_BIN_STEPS·b` to `CLEAR_BIN_STEPS·b + CLEAR_BIN_STEPS − 1`.
fn bin_middle(first: f32, step: f32, b: usize) -> f32 {
    first + ((b * CLEAR_BIN_STEPS) as f32 - 0.5) * step + 0.5 * CLEAR_BIN_STEPS as f32 * step
}

/// A clear distance less 1 % and 1 cm: what the approximate cosine (off by up to 0.002) can
/// move it by; minus infinity for a NaN.
fn with_cosine_margin(clear_m: f32) -> f32 {
    if clear_m.is_nan() {
        f32::NEG_INFINITY
    } else {
        0.99 * clear_m - 0.01
    }
}

/// Steps per bin of [`StepTable::clear_within_m`].
const CLEAR_BIN_STEPS: usize = 2;
/// Bins of [`StepTable::clear_within_m`].
const CLEAR_BINS: usize = SWEEP_CAPACITY.div_ceil(CLEAR_BIN_STEPS);

/// Readings of one cone a table step counts (a wider cone is read reading by reading).
const MAX_CONE_READINGS: usize = 64;

impl StepTable {
    /// An empty table (used by no sweep).
    pub const fn new() -> Self {
        StepTable {
            frame: None,
            len: 0,
            covering: [0; SWEEP_CAPACITY],
            majority_m: [f32::NEG_INFINITY; SWEEP_CAPACITY],
            covered: None,
            clear_within: [f32::NEG_INFINITY; CLEAR_BINS],
            basis: None,
            limiting_step: [0; CLEAR_BINS],
        }
    }

    /// For a sweep without a majority cone: a distance nearer than which no reading
    /// contradicts a point on bearing `rel` (the first rule); minus infinity off the table.
    fn first_rule_clear_m(&self, rel: f32) -> f32 {
        match (self.basis, self.frame) {
            (Some(basis), None) => {
                self.clear_within_step(floor_i32((rel - basis.first) / basis.step + 0.5))
            }
            _ => f32::NEG_INFINITY,
        }
    }

    /// The clear distance of the bin of step `k`; minus infinity off the table.
    fn clear_within_step(&self, k: i32) -> f32 {
        usize::try_from(k)
            .ok()
            .filter(|&k| k < self.len)
            .and_then(|k| self.clear_within.get(k / CLEAR_BIN_STEPS))
            .copied()
            .unwrap_or(f32::NEG_INFINITY)
    }

    /// The first rule's clear distances of a sweep without a majority cone, per pair of
    /// steps: the least over the readings of `(range − cell − shift) / cos(nearest)`,
    /// `nearest` the reading's cone's least angle to the pair, less the cosine's margin
    /// ([`with_cosine_margin`]).
    fn build_first_rule_clear(&mut self, swept: &Swept<'_>) {
        let Some(basis) = self.basis else {
            return;
        };
        let beam = swept.thales_beam_rad + basis.slack;
        let n = swept.readings.len().min(SWEEP_CAPACITY);
        let half_width = 0.5 * CLEAR_BIN_STEPS as f32 * basis.step;
        for (b, slot) in self
            .clear_within
            .iter_mut()
            .enumerate()
            .take(n.div_ceil(CLEAR_BIN_STEPS))
        {
            let mid = bin_middle(basis.first, basis.step, b);
            let mut clear_m = f32::INFINITY;
            for r in swept.readings {
                let Some(range_m) = r.range_m.filter(|x| !x.is_nan()) else {
                    continue;
                };
                let off = abs(wrap_angle_rad(swept.bearing_rad(r) - mid));
                let nearest = ((off - half_width).max(0.0) - beam).max(0.0);
                if nearest >= core::f32::consts::FRAC_PI_2 {
                    continue;
                }
                let reach_m = (range_m - swept.cell_m - swept.reading_shift_m) / cos(nearest);
                clear_m = clear_m.min(reach_m);
            }
            *slot = with_cosine_margin(clear_m);
        }
        self.len = n;
    }

    /// A distance nearer than which every candidate of a point on the candidates' bearing is
    /// ruled out, when its window lies within the steps the table covers; minus infinity
    /// otherwise (see [`StepTable::build_clear_within`]).
    fn clear_within_m(&self, c: &Candidates<'_>) -> f32 {
        let Some((lo, hi)) = self.covered else {
            return f32::NEG_INFINITY;
        };
        let (step, first) = (c.frame.step, c.frame.first);
        let k_lo = floor_i32((c.rel - c.window - first) / step - 0.5);
        let k_hi = floor_i32((c.rel + c.window - first) / step + 0.5) + 1;
        // A periodic sweep's table holds every bearing once (its steps counted round).
        let whole_turn = c
            .frame
            .period
            .is_some_and(|p| lo == 0 && hi + 1 >= p as usize);
        if !whole_turn && (k_lo < lo as i32 || k_hi > hi as i32) {
            return f32::NEG_INFINITY;
        }
        self.clear_within_step(c.frame.reduce(c.own_step()))
    }

    /// Per bin of steps, a distance nearer than which every step's majority rules its
    /// candidate out for a point on a bearing of the bin: the least over the covered steps of
    /// `(majority − cell − shift) / cos(θ)`, `θ` the step's least angle to the bin less half a
    /// step (a candidate's angle), less 1 % and 1 cm for the approximate cosine. A point in a
    /// window of covered steps nearer than it is vouched for whatever the first rule says.
    fn build_clear_within(&mut self, frame: &Frame, swept: &Swept<'_>) {
        self.covered = None;
        let n = self.len;
        let covered = |k: usize| self.covering[k] > 0 && self.covering[k] != u8::MAX;
        let Some(lo) = (0..n).find(|&k| covered(k)) else {
            return;
        };
        let hi = (0..n).rev().find(|&k| covered(k)).unwrap_or(lo);
        if !(lo..=hi).all(covered) {
            return;
        }
        let step = frame.step;
        let bin_width = CLEAR_BIN_STEPS as f32 * step;
        for b in 0..n.div_ceil(CLEAR_BIN_STEPS).min(CLEAR_BINS) {
            let mid = bin_middle(frame.first, step, b);
            let mut clear_m = f32::INFINITY;
            let mut limiting = lo;
            for k in lo..=hi {
                let centre = frame.first + k as f32 * step;
                let off = abs(wrap_angle_rad(centre - mid));
                let theta = ((off - 0.5 * bin_width).max(0.0) - 0.5 * step).max(0.0);
                if theta >= core::f32::consts::FRAC_PI_2 {
                    continue;
                }
                let reach_m =
                    (self.majority_m[k] - swept.cell_m - swept.reading_shift_m) / cos(theta);
                if reach_m < clear_m {
                    (clear_m, limiting) = (reach_m, k);
                }
            }
            self.limiting_step[b] = limiting.min(u8::MAX as usize) as u8;
            self.clear_within[b] = with_cosine_margin(clear_m);
        }
        self.covered = Some((lo, hi));
    }

    /// The table of `swept`'s steps 0 to n − 1 (the window's steps past the sweep's ends are
    /// counted point by point).
    pub fn build(&mut self, swept: &Swept<'_>) {
        self.frame = None;
        self.len = 0;
        self.covered = None;
        self.basis = swept.basis();
        let Some(frame) = swept.frame(swept.heard_rad()) else {
            self.build_first_rule_clear(swept);
            return;
        };
        let n = swept.readings.len().min(SWEEP_CAPACITY);
        for k in 0..n {
            let mut ranges: heapless::Vec<f32, MAX_CONE_READINGS> = heapless::Vec::new();
            let mut fits = true;
            let covering = for_each_covering(swept, &frame, k as i32, |r| {
                // Silence is beyond every candidate, a NaN before every one (never clear).
                let v = match r.range_m {
                    None => f32::INFINITY,
                    Some(x) if x.is_nan() => f32::NEG_INFINITY,
                    Some(x) => x,
                };
                fits &= ranges.push(v).is_ok();
            });
            let need = (frame.m + 1).min(covering) as usize;
            let (cov, majority) = if !fits || covering > u8::MAX as i32 {
                // Not tabled: a point reads this step reading by reading.
                (u8::MAX, f32::NAN)
            } else if need == 0 {
                (0, f32::NEG_INFINITY)
            } else {
                (covering as u8, nth_farthest(&mut ranges, need - 1))
            };
            self.covering[k] = cov;
            self.majority_m[k] = majority;
        }
        self.len = n;
        self.build_clear_within(&frame, swept);
        self.frame = Some(frame);
    }
}

impl Default for StepTable {
    fn default() -> Self {
        Self::new()
    }
}

/// The `i`-th largest of `values` (0: the largest), sorting them in place (an insertion
/// sort: a cone holds a few dozen readings, and core's sort would add kilobytes of flash);
/// minus infinity past the end.
fn nth_farthest(values: &mut [f32], i: usize) -> f32 {
    for j in 1..values.len() {
        let mut k = j;
        while k > 0 && values[k - 1] < values[k] {
            values.swap(k - 1, k);
            k -= 1;
        }
    }
    values.get(i).copied().unwrap_or(f32::NEG_INFINITY)
}

/// A sweep all round (its two ends a step apart or overlapping) reads every bearing.
fn reads_all_round(first: f32, last: f32, step: f32) -> bool {
    last - first + 1.01 * step >= 2.0 * core::f32::consts::PI
}

/// The steps in a whole turn when a sweep all round has a step that divides it (a full sweep
/// of 201 readings from −180° to 180° has 200: its two ends are one bearing). Counting its
/// steps modulo that, every bearing has one number and one set of readings; modulo the
/// number of readings, a window across the ends read its readings one off.
fn periodic(all_round: bool, step: f32) -> Option<i32> {
    let turns = 2.0 * core::f32::consts::PI / step;
    let p = floor_i32(turns + 0.5);
    (all_round && p > 0 && abs(turns - p as f32) < 1.0e-3).then_some(p)
}

/// Call `f` with each reading whose cone holds step `k` whole; returns how many.
fn for_each_covering(swept: &Swept<'_>, frame: &Frame, k: i32, mut f: impl FnMut(&Reading)) -> i32 {
    let n = swept.readings.len() as i32;
    let centre = frame.first + k as f32 * frame.step;
    let mut covering = 0;
    for j in k - frame.m..=k + frame.m {
        let j = if frame.all_round {
            j.rem_euclid(frame.period.unwrap_or(n))
        } else {
            j
        };
        if !(0..n).contains(&j) {
            continue;
        }
        let at = if frame.ascending { j } else { n - 1 - j } as usize;
        let Some(r) = swept.readings.get(at) else {
            continue;
        };
        // Its cone must hold the whole step (an uneven sweep counts for less).
        let r_off = abs(wrap_angle_rad(swept.bearing_rad(r) - centre));
        if r_off.is_nan() || r_off + 0.5 * frame.step > frame.heard_rad + 1.0e-4 {
            continue;
        }
        covering += 1;
        f(r);
    }
    covering
}

/// The candidates of one point for [`Swept::candidates`].
struct Candidates<'a> {
    swept: &'a Swept<'a>,
    rel: f32,
    d_m: f32,
    window: f32,
    frame: Frame,
    table: Option<&'a StepTable>,
}

/// One step's candidate as the covering readings judge it.
enum StepVerdict {
    /// The step lies outside the window: no candidate there.
    Outside,
    /// Read by the readings whose cones hold it.
    Read {
        /// Most of them heard nothing as near as the candidate: it is ruled out.
        majority_clear: bool,
        /// Not ruled out even a margin nearer ([`HEARD_NEAR_MARGIN`]): some reading heard
        /// something that near, and then it also contradicts the point by the first rule,
        /// whatever the approximate cosines round to.
        heard_near: bool,
    },
}

/// How much nearer than a candidate a step must be heard for [`StepVerdict::Read::heard_near`]:
/// a fraction of the point's distance and a millimetre, above what the approximate cosines of
/// two nearby angles can differ by.
const HEARD_NEAR_MARGIN: (f32, f32) = (0.01, 0.001);

impl Candidates<'_> {
    /// The step that holds the point's own bearing.
    fn own_step(&self) -> i32 {
        floor_i32((self.rel - self.frame.first) / self.frame.step + 0.5)
    }

    /// Step `k`'s candidate, judged by the readings whose cones hold the whole step.
    fn verdict(&self, k: i32) -> StepVerdict {
        let k = self.frame.reduce(k);
        let step = self.frame.step;
        let centre = self.frame.first + k as f32 * step;
        let off = abs(wrap_angle_rad(centre - self.rel));
        if off - 0.5 * step > self.window {
            return StepVerdict::Outside;
        }
        let tabled = self.table.and_then(|t| {
            let i = usize::try_from(k).ok().filter(|&i| i < t.len)?;
            let covering = *t.covering.get(i)?;
            (covering != u8::MAX).then(|| (covering, t.majority_m[i]))
        });
        let base_m = self.swept.cell_m + self.swept.reading_shift_m;
        // The majority heard farther than any candidate can be (the cosine, approximate, is
        // below 1.002): ruled out without the cosine, as most steps in the open are.
        if tabled.is_some_and(|(covering, majority_m)| {
            covering > 0 && majority_m > 1.01 * self.d_m + base_m
        }) {
            return StepVerdict::Read {
                majority_clear: true,
                heard_near: false,
            };
        }
        let farthest_m = self.d_m * cos((off - 0.5 * step).max(0.0)) + base_m;
        let near_m = farthest_m - (HEARD_NEAR_MARGIN.0 * self.d_m + HEARD_NEAR_MARGIN.1);
        if let Some((covering, majority_m)) = tabled {
            return StepVerdict::Read {
                majority_clear: covering > 0 && majority_m > farthest_m,
                heard_near: covering > 0 && majority_m <= near_m,
            };
        }
        let (mut clear, mut clear_of_near) = (0, 0);
        let covering = for_each_covering(self.swept, &self.frame, k, |r| {
            clear += r.range_m.is_none_or(|range_m| range_m > farthest_m) as i32;
            clear_of_near += r.range_m.is_none_or(|range_m| range_m > near_m) as i32;
        });
        let need = (self.frame.m + 1).min(covering);
        StepVerdict::Read {
            majority_clear: covering > 0 && clear >= need,
            heard_near: covering > 0 && clear_of_near < need,
        }
    }

    /// Some reading whose cone holds step `k` heard something as near as its candidate, and
    /// too many did for the candidate to be ruled out. Such a reading also contradicts the
    /// point in [`Swept::any_contradicting`] (its cone holds the point's bearing to within
    /// the candidate's offset, so its test distance is at least the candidate's), so the point
    /// is not vouched for: the exact answer, without the pass over every reading.
    fn heard_near(&self, k: i32) -> bool {
        matches!(
            self.verdict(k),
            StepVerdict::Read {
                heard_near: true,
                ..
            }
        )
    }

    /// Every step of the window, the point's own first (behind a wall, the answer comes at
    /// once): the first heard too near decides.
    fn window_verdict(&self) -> WindowVerdict {
        let (step, first) = (self.frame.step, self.frame.first);
        let own = self.own_step();
        let k_lo = floor_i32((self.rel - self.window - first) / step - 0.5);
        let k_hi = floor_i32((self.rel + self.window - first) / step + 0.5) + 1;
        // The step that limits the own bin's clear distance next (`StepTable`): past that
        // distance, the one most likely heard too near.
        let limiting = self
            .table
            .filter(|t| t.covered.is_some())
            .and_then(|t| {
                let b = usize::try_from(own).ok()? / CLEAR_BIN_STEPS;
                t.limiting_step.get(b).map(|&k| k as i32)
            })
            // Steps are counted on from `first`: without a period one bearing all round may
            // have two numbers, with different readings, and only the window's own counts.
            .filter(|k| self.frame.period.is_some() || (k_lo..=k_hi).contains(k))
            .unwrap_or(own);
        let mut undecided = false;
        let first_two = [own, limiting];
        let rest = (k_lo..=k_hi).filter(|k| !first_two.contains(k));
        for k in first_two.into_iter().chain(rest) {
            match self.verdict(k) {
                StepVerdict::Outside
                | StepVerdict::Read {
                    majority_clear: true,
                    ..
                } => {}
                StepVerdict::Read {
                    heard_near: true, ..
                } => return WindowVerdict::HeardNear,
                // Not ruled out, but only just (or by no cone): the first rule decides.
                StepVerdict::Read { .. } => undecided = true,
            }
        }
        if undecided {
            WindowVerdict::Undecided
        } else {
            WindowVerdict::RuledOut
        }
    }
}

/// What the candidates of a point's window say.
enum WindowVerdict {
    /// Every candidate is ruled out: vouched for.
    RuledOut,
    /// Some candidate's covering readings heard something too near: not vouched for.
    HeardNear,
    /// No candidate was heard clearly too near, but some is not ruled out (no reading's cone
    /// covers its step, or it was heard within the margin): the first rule decides.
    Undecided,
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
