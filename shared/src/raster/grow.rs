//! Growing a line by a square, one run per row, in time bounded by the rows.
//!
//! Every cell of the walk marks a square of half-side `h`. Row `y` of the union is the union of
//! `[x − h, x + h]` over the walk cells whose row is within `h` of `y`. Those cells are
//! consecutive along the walk (its rows are monotone) and their `x` are monotone and
//! 8-connected, so the union is the single run from the smaller to the larger `x` of the first
//! and last of them, widened by `h`. Their step indices follow from the closed form of the walk
//! (see `clip.rs`): each is `floor((s·v + c) / d)` in the row number `v`, stepped from one row
//! to the next by additions ([`FloorStep`]), so a row costs a few additions and its words,
//! whatever the length of the edge or the size of `h`.

use super::clip::LineSteps;
use super::{clamp_cell, Work};
use crate::grid::Grid;

/// Mark cells `x0..=x1` of `row` (any integers: clipped to the grid here). Returns the words
/// written.
pub(super) fn fill_row<const W: usize>(grid: &mut Grid<W>, row: i64, x0: i64, x1: i64) -> Work {
    let g = grid.geometry();
    let (last_x, last_row) = (g.width() as i64 - 1, g.height() as i64 - 1);
    let (x0, x1) = (x0.max(0), x1.min(last_x));
    if x0 > x1 || !(0..=last_row).contains(&row) {
        return 0;
    }
    grid.fill_row(row as i32, x0 as i32, x1 as i32) as Work
}

/// `floor((s·t + c) / d)` for `t = t0, t0 + 1, …`, with `d > 0`: one division to start, then
/// additions (the firmware's 64-bit division is a library call; an addition is two
/// instructions).
struct FloorStep {
    quotient: i64,
    remainder: i64,
    step_quotient: i64,
    step_remainder: i64,
    divisor: i64,
}

impl FloorStep {
    fn new(s: i64, c: i64, d: i64, t0: i64) -> Self {
        let n = s * t0 + c;
        Self {
            quotient: n.div_euclid(d),
            remainder: n.rem_euclid(d),
            step_quotient: s.div_euclid(d),
            step_remainder: s.rem_euclid(d),
            divisor: d,
        }
    }

    fn value(&self) -> i64 {
        self.quotient
    }

    fn advance(&mut self) {
        self.quotient += self.step_quotient;
        self.remainder += self.step_remainder;
        if self.remainder >= self.divisor {
            self.remainder -= self.divisor;
            self.quotient += 1;
        }
    }
}

/// Mark the Bresenham line from `from` to `to` grown by `half_side` cells (see the module doc).
/// Work: one for the edge, then one per row visited (at most the grid's height) plus the words
/// written.
pub(super) fn mark_grown_line<const W: usize>(
    grid: &mut Grid<W>,
    from: (i32, i32),
    to: (i32, i32),
    half_side: u16,
) -> Work {
    let g = *grid.geometry();
    let h = half_side as i64;
    let (width, height) = (g.width() as i64, g.height() as i64);
    let line = LineSteps::new(clamp_cell(from), clamp_cell(to));
    // Only the steps whose square reaches the grid matter.
    let Some((k0, k1)) = line.steps_within((-h, width - 1 + h), (-h, height - 1 + h)) else {
        return 1;
    };
    let (first, last) = (line.cell(k0), line.cell(k1));
    let y0 = line.from.1;
    let sy = line.sign.1;
    let (adx, ady) = line.delta;
    // Rows in the walk's direction, as offsets `v` from the first cell's row (`y = y0 + sy·v`):
    // from the first cell's row − h to the last's + h, clipped to the grid.
    let offset = |y: i64| (y - y0) * sy;
    let (v_first, v_last) = if sy > 0 {
        (
            offset((first.1 - h).max(0)),
            offset((last.1 + h).min(height - 1)),
        )
    } else {
        (
            offset((first.1 + h).min(height - 1)),
            offset((last.1 - h).max(0)),
        )
    };
    let mut work: Work = 1;
    if v_first > v_last {
        return work;
    }
    // The window of row v: steps whose row offset is within [v − h, v + h].
    let (mut trail, mut lead) = if line.x_major() {
        // Row offset n(k) = floor((2·ady·k + adx) / (2·adx)); n(k) ≥ t ⇔ k ≥ ceil((2·adx·t −
        // adx) / (2·ady)), n(k) ≤ t ⇔ k ≤ floor((2·adx·t + adx − 1) / (2·ady)).
        let d = (2 * ady).max(1);
        (
            FloorStep::new(2 * adx, -2 * adx * h - adx + d - 1, d, v_first),
            FloorStep::new(2 * adx, 2 * adx * h + adx - 1, d, v_first),
        )
    } else {
        // Row offset k: the window is [v − h, v + h]; these step x, floor((2·adx·k + ady) /
        // (2·ady)) at k = v − h and v + h.
        (
            FloorStep::new(2 * adx, ady, 2 * ady, v_first - h),
            FloorStep::new(2 * adx, ady, 2 * ady, v_first + h),
        )
    };
    // Consecutive rows whose run is the whole row, not yet written: one fill for all of them.
    let mut full_rows: Option<(i64, i64)> = None;
    for v in v_first..=v_last {
        let run = window_run(&line, (k0, k1), (first.0, last.0), v, h, (&trail, &lead));
        trail.advance();
        lead.advance();
        work += 1;
        let Some((lo, hi)) = run else {
            continue;
        };
        let y = y0 + sy * v;
        if lo <= 0 && hi >= width - 1 {
            full_rows = Some(match full_rows {
                Some((a, b)) => (a.min(y), b.max(y)),
                None => (y, y),
            });
            continue;
        }
        if let Some((a, b)) = full_rows.take() {
            work += grid.fill_rows(a as i32, b as i32) as Work;
        }
        work += fill_row(grid, y, lo, hi);
    }
    if let Some((a, b)) = full_rows {
        work += grid.fill_rows(a as i32, b as i32) as Work;
    }
    work
}

/// The run of row offset `v`: from the smaller to the larger x of the first and last steps of
/// `steps` whose row offset is within `h` of `v`, widened by `h`; `None` when there is none.
/// `ends_x` are the x of the first and last step, `floors` the trail's and lead's
/// [`FloorStep`] at `v`.
fn window_run(
    line: &LineSteps,
    steps: (i64, i64),
    ends_x: (i64, i64),
    v: i64,
    h: i64,
    floors: (&FloorStep, &FloorStep),
) -> Option<(i64, i64)> {
    let (k0, k1) = steps;
    let (x0, sx) = (line.from.0, line.sign.0);
    let (xa, xb) = if line.x_major() {
        let (kt, kl) = if line.delta.1 == 0 {
            // A horizontal line: every step is on row offset 0.
            if v - h <= 0 && 0 <= v + h {
                (k0, k1)
            } else {
                return None;
            }
        } else {
            (floors.0.value().max(k0), floors.1.value().min(k1))
        };
        if kt > kl {
            return None;
        }
        (x0 + sx * kt, x0 + sx * kl)
    } else {
        // Steps are row offsets: the window is [v − h, v + h].
        let (kt, kl) = (v - h, v + h);
        if kt.max(k0) > kl.min(k1) {
            return None;
        }
        let x_at = |k: i64, step: &FloorStep| {
            if k < k0 {
                ends_x.0
            } else if k > k1 {
                ends_x.1
            } else {
                x0 + sx * step.value()
            }
        };
        (x_at(kt, floors.0), x_at(kl, floors.1))
    };
    Some((xa.min(xb) - h, xa.max(xb) + h))
}
