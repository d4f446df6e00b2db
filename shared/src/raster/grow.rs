//! Growing a line by a square, one run per row, in time bounded by the rows.
//!
//! Every cell of the walk marks a square of half-side `h`. Row `y` of the union is the union of
//! `[x − h, x + h]` over the walk cells whose row is within `h` of `y`. Those cells are
//! consecutive along the walk (its rows are monotone) and their `x` are monotone and
//! 8-connected, so the union is the single run from the smaller to the larger `x` of the first
//! and last of them, widened by `h`. Their step indices follow from the closed form of the walk
//! (see `clip.rs`), stepped from one row to the next by additions ([`FloorStep`]), so a row
//! costs a few additions and its words, whatever the length of the edge or the size of `h`.
//! The per-row arithmetic is `i32` (the MCU is 32-bit; `i64` doubles its cost): each quotient
//! is only evaluated on the rows and steps of the clipped walk, whose values fit.

use super::clip::LineSteps;
use super::{clamp_cell, Work};
use crate::grid::Grid;

/// Mark cells `x0..=x1` of `row` (any integers: clipped to the grid here). Returns the words
/// written.
#[inline]
fn fill_row<const W: usize>(grid: &mut Grid<W>, row: i32, x0: i32, x1: i32) -> u32 {
    grid.fill_row(row, x0, x1) as u32
}

/// `floor((s·t + c) / d)` for `t = t0, t0 + 1, …`, with `d > 0`: one division to start, then
/// additions. Started in `i64`, stepped in `i32`: callers only step it over values that fit.
struct FloorStep {
    quotient: i32,
    remainder: i32,
    step_quotient: i32,
    step_remainder: i32,
    divisor: i32,
}

impl FloorStep {
    fn new(s: i64, c: i64, d: i64, t0: i64) -> Self {
        let n = s * t0 + c;
        Self {
            quotient: n.div_euclid(d) as i32,
            remainder: n.rem_euclid(d) as i32,
            step_quotient: s.div_euclid(d) as i32,
            step_remainder: s.rem_euclid(d) as i32,
            divisor: d as i32,
        }
    }

    #[inline]
    fn value(&self) -> i32 {
        self.quotient
    }

    #[inline]
    fn advance(&mut self) {
        self.quotient += self.step_quotient;
        self.remainder += self.step_remainder;
        if self.remainder >= self.divisor {
            self.remainder -= self.divisor;
            self.quotient += 1;
        }
    }
}

/// One end of the window (the trail or the lead): an index `t` clamped to `[lo, hi]` that moves
/// by at most one per row, and the [`FloorStep`] evaluated at `t` (plus `offset`).
struct WindowEnd {
    t: i32,
    lo: i32,
    hi: i32,
    floor: FloorStep,
}

impl WindowEnd {
    /// The end at index `t` (clamped), for `floor((s·(t + offset) + c) / d)`.
    fn new(t: i64, lo: i64, hi: i64, f: (i64, i64, i64), offset: i64) -> Self {
        let t = t.clamp(lo, hi);
        Self {
            t: t as i32,
            lo: lo as i32,
            hi: hi as i32,
            floor: FloorStep::new(f.0, f.1, f.2, t + offset),
        }
    }

    /// Move to index `t` (clamped), one more than before at most.
    #[inline]
    fn move_to(&mut self, t: i32) {
        // `max` then `min`, not `clamp`: no panic path (lo ≤ hi holds by construction).
        let t = t.max(self.lo).min(self.hi);
        if t > self.t {
            self.t = t;
            self.floor.advance();
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
    let (x0, y0) = line.from;
    let (sx, sy) = line.sign;
    let (adx, ady) = line.delta;
    // Rows in the walk's direction, as offsets `v` from the start's row (`y = y0 + sy·v`): from
    // the first cell's row − h to the last's + h, clipped to the grid. All fit an `i32`.
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
    let mut work: u32 = 1;
    if v_first > v_last {
        return work as Work;
    }
    // The clipped walk's rows, as offsets.
    let (r_a, r_b) = (offset(first.1), offset(last.1));
    // The window of row v holds the walk's steps on rows v − h ..= v + h. Its ends' x:
    let horizontal = ady == 0;
    let (mut trail, mut lead) = if line.x_major() {
        // One row holds many steps. K(r) = ceil((2·adx·r − adx) / (2·ady)) is the first step
        // on row offset r; the trail is K(row), the lead K(row + 1) − 1.
        let d = (2 * ady).max(1);
        let k_of_row = (2 * adx, -adx + d - 1, d);
        (
            WindowEnd::new(v_first - h, r_a, r_b, k_of_row, 0),
            WindowEnd::new(v_first + h, r_a, r_b, k_of_row, 1),
        )
    } else {
        // Steps are row offsets; x moves floor((2·adx·k + ady) / (2·ady)) after step k.
        let x_moves = (2 * adx, ady, 2 * ady);
        (
            WindowEnd::new(v_first - h, k0, k1, x_moves, 0),
            WindowEnd::new(v_first + h, k0, k1, x_moves, 0),
        )
    };
    let (k0, k1) = (k0 as i32, k1 as i32);
    let (x0, sx, h) = (x0 as i32, sx as i32, h as i32);
    let x_major = line.x_major();
    let (width, sy) = (width as i32, sy as i32);
    let y0 = y0 as i32;
    // Consecutive rows whose run is the whole row, not yet written: one fill for all of them.
    let mut full_rows: Option<(i32, i32)> = None;
    for v in v_first as i32..=v_last as i32 {
        work += 1;
        trail.move_to(v - h);
        lead.move_to(v + h);
        let (xa, xb) = if x_major {
            let (kt, kl) = if horizontal {
                if v - h > 0 || v + h < 0 {
                    continue;
                }
                (k0, k1)
            } else {
                (
                    trail.floor.value().max(k0),
                    (lead.floor.value() - 1).min(k1),
                )
            };
            (x0 + sx * kt, x0 + sx * kl)
        } else {
            (x0 + sx * trail.floor.value(), x0 + sx * lead.floor.value())
        };
        let (lo, hi) = (xa.min(xb) - h, xa.max(xb) + h);
        let y = y0 + sy * v;
        if lo <= 0 && hi >= width - 1 {
            full_rows = Some(match full_rows {
                Some((a, b)) => (a.min(y), b.max(y)),
                None => (y, y),
            });
            continue;
        }
        if let Some((a, b)) = full_rows.take() {
            work += grid.fill_rows(a, b) as u32;
        }
        work += fill_row(grid, y, lo, hi);
    }
    if let Some((a, b)) = full_rows {
        work += grid.fill_rows(a, b) as u32;
    }
    work as Work
}
