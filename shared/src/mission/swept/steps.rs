//! The step table of a standing sweep: what the Thales rule's candidates and its first rule
//! read the same for every point of the sweep, computed once (see [`StepTable`]), and the
//! candidates of one point read from it.

use crate::geom::PointM;
use crate::math::{abs, cos, wrap_angle_rad};
use crate::sonar::{Reading, SWEEP_CAPACITY};

use super::{floor_i32, Swept};

/// The slack (`asin(shift / min range)`) and the bearings of a sweep, the same for each of its
/// points.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Basis {
    pub(super) slack: f32,
    pub(super) first: f32,
    pub(super) last: f32,
    pub(super) step: f32,
    /// Where the sonar stood.
    pub(super) sonar: PointM,
}

/// How the majority rule steps through a sweep's bearings: steps counted from `first` in the
/// readings' ascending order, `m` readings on each side of a step's centre.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Frame {
    pub(super) first: f32,
    pub(super) step: f32,
    pub(super) all_round: bool,
    /// Steps in a whole turn, for a sweep all round whose step divides it (to a thousandth
    /// of a step): step `k` and step `k + period` are one bearing, read by the same readings.
    pub(super) period: Option<i32>,
    pub(super) ascending: bool,
    pub(super) m: i32,
    pub(super) heard_rad: f32,
}

impl Frame {
    /// The number of step `k` within a turn, for a periodic sweep (the table holds each
    /// bearing once); `k` otherwise.
    pub(super) fn reduce(&self, k: i32) -> i32 {
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
    pub(super) frame: Option<Frame>,
    /// Steps tabled, 0 to `len − 1`: their majorities, or without a frame the first rule's
    /// clear distances.
    pub(super) len: usize,
    /// Readings whose cones hold step `k` whole.
    pub(super) covering: [u8; SWEEP_CAPACITY],
    /// The range the majority must all lie beyond (silence: infinity; no reading or a NaN
    /// among the majority: minus infinity).
    pub(super) majority_m: [f32; SWEEP_CAPACITY],
    /// The steps from the first to the last covered one, when every step between is covered
    /// and tabled (see [`StepTable::build_clear_within`]).
    pub(super) covered: Option<(usize, usize)>,
    /// Per bin of steps, see [`StepTable::build_clear_within`].
    pub(super) clear_within: [f32; CLEAR_BINS],
    /// The sweep's [`Basis`].
    pub(super) basis: Option<Basis>,
    /// Per bin, the step that set its clear distance: the first a point beyond it is likely
    /// heard too near in (read first by [`Candidates::window_verdict`]).
    pub(super) limiting_step: [u8; CLEAR_BINS],
}

/// The middle bearing of bin `b` of a sweep's steps from `first`, `step` apart: bin `b` holds
/// the bearings of steps `CLEAR_BIN_STEPS·b` to `CLEAR_BIN_STEPS·b + CLEAR_BIN_STEPS − 1`.
pub(super) fn bin_middle(first: f32, step: f32, b: usize) -> f32 {
    first + ((b * CLEAR_BIN_STEPS) as f32 - 0.5) * step + 0.5 * CLEAR_BIN_STEPS as f32 * step
}

/// A clear distance less 1 % and 1 cm: what the approximate cosine (off by up to 0.002) can
/// move it by; minus infinity for a NaN.
pub(super) fn with_cosine_margin(clear_m: f32) -> f32 {
    if clear_m.is_nan() {
        f32::NEG_INFINITY
    } else {
        0.99 * clear_m - 0.01
    }
}

/// Steps per bin of [`StepTable::clear_within_m`].
pub(super) const CLEAR_BIN_STEPS: usize = 2;
/// Bins of [`StepTable::clear_within_m`].
pub(super) const CLEAR_BINS: usize = SWEEP_CAPACITY.div_ceil(CLEAR_BIN_STEPS);

/// Readings of one cone a table step counts (a wider cone is read reading by reading).
pub(super) const MAX_CONE_READINGS: usize = 64;

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
    pub(super) fn first_rule_clear_m(&self, rel: f32) -> f32 {
        match (self.basis, self.frame) {
            (Some(basis), None) => {
                self.clear_within_step(floor_i32((rel - basis.first) / basis.step + 0.5))
            }
            _ => f32::NEG_INFINITY,
        }
    }

    /// The clear distance of the bin of step `k`; minus infinity off the table.
    pub(super) fn clear_within_step(&self, k: i32) -> f32 {
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
    pub(super) fn build_first_rule_clear(&mut self, swept: &Swept<'_>) {
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
    pub(super) fn clear_within_m(&self, c: &Candidates<'_>) -> f32 {
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
    pub(super) fn build_clear_within(&mut self, frame: &Frame, swept: &Swept<'_>) {
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
pub(super) fn nth_farthest(values: &mut [f32], i: usize) -> f32 {
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
pub(super) fn reads_all_round(first: f32, last: f32, step: f32) -> bool {
    last - first + 1.01 * step >= 2.0 * core::f32::consts::PI
}

/// The steps in a whole turn when a sweep all round has a step that divides it (a full sweep
/// of 201 readings from −180° to 180° has 200: its two ends are one bearing). Counting its
/// steps modulo that, every bearing has one number and one set of readings; modulo the
/// number of readings, a window across the ends read its readings one off.
pub(super) fn periodic(all_round: bool, step: f32) -> Option<i32> {
    let turns = 2.0 * core::f32::consts::PI / step;
    let p = floor_i32(turns + 0.5);
    (all_round && p > 0 && abs(turns - p as f32) < 1.0e-3).then_some(p)
}

/// Call `f` with each reading whose cone holds step `k` whole; returns how many.
pub(super) fn for_each_covering(
    swept: &Swept<'_>,
    frame: &Frame,
    k: i32,
    mut f: impl FnMut(&Reading),
) -> i32 {
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
pub(super) struct Candidates<'a> {
    pub(super) swept: &'a Swept<'a>,
    pub(super) rel: f32,
    pub(super) d_m: f32,
    pub(super) window: f32,
    pub(super) frame: Frame,
    pub(super) table: Option<&'a StepTable>,
}

/// One step's candidate as the covering readings judge it.
pub(super) enum StepVerdict {
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
pub(super) const HEARD_NEAR_MARGIN: (f32, f32) = (0.01, 0.001);

impl Candidates<'_> {
    /// The step that holds the point's own bearing.
    pub(super) fn own_step(&self) -> i32 {
        floor_i32((self.rel - self.frame.first) / self.frame.step + 0.5)
    }

    /// Step `k`'s candidate, judged by the readings whose cones hold the whole step.
    pub(super) fn verdict(&self, k: i32) -> StepVerdict {
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
    pub(super) fn heard_near(&self, k: i32) -> bool {
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
    pub(super) fn window_verdict(&self) -> WindowVerdict {
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
pub(super) enum WindowVerdict {
    /// Every candidate is ruled out: vouched for.
    RuledOut,
    /// Some candidate's covering readings heard something too near: not vouched for.
    HeardNear,
    /// No candidate was heard clearly too near, but some is not ruled out (no reading's cone
    /// covers its step, or it was heard within the margin): the first rule decides.
    Undecided,
}
