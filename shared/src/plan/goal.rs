//! Reduced-cost classes and goal regions of the cell-by-cell A*: with the octile heuristic a
//! child's key is its parent's plus one of six reduced costs ([`REDUCED_COSTS`]), and which one
//! a step gets depends only on the cell's *goal region* (signs of `dx`, `dy` and `|dx| − |dy|`
//! saturated to −4 ..= 3). [`STEP_CLASSES`] gives each region's 8 step classes (3 bits each);
//! on grids of at most [`GOAL_AXIS_CELLS`] a side the region comes from a per-axis table
//! ([`goal_axis_entry`]) with one subtraction and one saturation. So neither `h` nor `g` is
//! computed per cell. Measured effect (branch `astar-region`, `cargo xtask mcu-bench`): about 11
//! Cortex-M4 instructions per expanded cell for the region, was about 28; see
//! docs/planners-history.md, "Cell-by-cell A\*: goal regions from a per-axis table".

use super::codes::{octile, STEPS};
use super::{DIAGONAL_COST, STRAIGHT_COST};

/// The reduced costs `r = cost + h(child) − h(parent)` of an octile step under the octile
/// heuristic, in increasing order: 0, `2S − D`, `2D − 2S`, `D`, `2S`, `2D` (S =
/// [`STRAIGHT_COST`], D = [`DIAGONAL_COST`]); the index is the step's *class*. A child's key is
/// its parent's plus one of these, see [`ClassQueue`](crate::plan::class_queue::ClassQueue).
pub(super) const REDUCED_COSTS: [u32; CLASSES] = [
    0,
    2 * STRAIGHT_COST - DIAGONAL_COST,
    2 * DIAGONAL_COST - 2 * STRAIGHT_COST,
    DIAGONAL_COST,
    2 * STRAIGHT_COST,
    2 * DIAGONAL_COST,
];
/// Classes of reduced cost: 0 (the stack) and one FIFO list per non-zero value.
pub(super) const CLASSES: usize = 6;
/// [`REDUCED_COSTS`] padded to 8 entries, for class numbers read from 3-bit fields.
pub(super) const CLASS_COSTS: [u32; 8] = {
    let mut t = [0; 8];
    let mut c = 0;
    while c < CLASSES {
        t[c] = REDUCED_COSTS[c];
        c += 1;
    }
    t
};
/// The class of a reduced cost `r` by `r >> 10` (`r < 16 384`), `NO_CLASS` for none; the six
/// reduced costs fall into six different slots (0, 3, 4, 7, 11, 15).
const CLASS_BY_KILO: [u8; 16] = {
    let mut table = [NO_CLASS; 16];
    let mut c = 0;
    while c < CLASSES {
        table[(REDUCED_COSTS[c] >> 10) as usize] = c as u8;
        c += 1;
    }
    table
};
const NO_CLASS: u8 = 0xFF;

/// The class of reduced cost `r` (`key − last popped key`), `None` when `r` is not an octile
/// step's reduced cost.
#[inline(always)]
pub(super) fn reduced_cost_class(r: u32) -> Option<usize> {
    let c = *CLASS_BY_KILO.get((r >> 10) as usize)? as usize;
    (REDUCED_COSTS.get(c) == Some(&r)).then_some(c)
}

/// Regions of [`goal_region`].
const REGIONS: usize = 128;

/// The *region* of a cell relative to the goal, `(dx, dy)` = cell − goal, as `0 .. 128`: the
/// *sign code* `3 (sgn dx + 1) + (sgn dy + 1)` (`0 ..= 8`) in bits 0..4 and `|dx| − |dy|`
/// clamped to `−4 ..= 3`, plus 4, in bits 4..7. The octile heuristic is linear in
/// `(|dx|, |dy|)` on each side of `|dx| = |dy|`, a step changes `|dx|` and `|dy|` by at most
/// one each in a way the signs fix, and it crosses that line only from `|dx| − |dy| = ±1`; so
/// the reduced cost of every step from a cell depends on its region only (checked against
/// `h` for every cell and step around many goals in the tests). The search computes the same
/// number from two per-axis table entries ([`goal_axis_entry`], [`axis_region`]) on grids of
/// at most [`GOAL_AXIS_CELLS`] a side and with this function on larger ones.
#[inline(always)]
pub(super) fn goal_region(dx: i32, dy: i32) -> usize {
    let d = (dx.unsigned_abs().wrapping_sub(dy.unsigned_abs()) as i32).clamp(-4, 3) + 4;
    let code = 3 * (dx.signum() + 1) + dy.signum() + 1;
    ((code as u32 | (d as u32) << 4) & (REGIONS as u32 - 1)) as usize
}

/// Grid sides (cells) up to which the cell-by-cell A* takes each cell's [`goal_region`] from
/// a per-axis table of this many words filled once per search ([`goal_axis_entry`]; 2 KB in
/// the [`Planner`](crate::plan::planner::Planner)); larger grids compute it per cell.
pub(super) const GOAL_AXIS_CELLS: usize = 512;

/// Sign code of `i − g`: 0 below, 1 equal, 2 above.
#[inline(always)]
const fn axis_sign_code(i: u32, g: u32) -> u32 {
    (i > g) as u32 + (i >= g) as u32
}

/// Entry `i` of the per-axis goal table for the goal `(gx, gy)`, `i < GOAL_AXIS_CELLS`: in the
/// high half the column value `16 (|i − gx| + 4) + 3 sx + 2`, in the low half the row value
/// `16 |i − gy| + 2 − sy` (`sx`, `sy` the [`axis_sign_code`]s; both below 2^14). The column
/// value of `x` minus the row value of `y` is `16 (|dx| − |dy| + 4) + 3 sx + sy`: the sign
/// code in the low nibble (never a borrow: `3 sx + 2 ≥ 2 − sy`) and the unclamped difference
/// above it.
#[inline(always)]
pub(super) const fn goal_axis_entry(i: u32, gx: u32, gy: u32) -> u32 {
    let col = ((i.abs_diff(gx) + 4) << 4) + 3 * axis_sign_code(i, gx) + 2;
    let row = (i.abs_diff(gy) << 4) + 2 - axis_sign_code(i, gy);
    (col << 16) | row
}

/// The [`goal_region`] of the cell of queue entry `node` (`y << 16 | x << 4 | code`; its column
/// `x` is passed too, as the search holds it already; `x` and `y` below [`GOAL_AXIS_CELLS`])
/// from the per-axis table `axis` ([`goal_axis_entry`]): one subtraction of the two entries'
/// halves (`a − (b << 16)`: the column value of `x` minus the row value of `y` in the high half,
/// `16 (|dx| − |dy| + 4) + sign code`, with `|dx| − |dy| + 4` in `−507 ..= 515`), one
/// saturation (`usat`) and one insert. With the loads of the two entries and of the step
/// classes about 11 Cortex-M4 instructions (`STEP_CLASSES` sits at the end of the same table).
#[inline(always)]
pub(super) fn axis_region(axis: &[u32; GOAL_TABLE_WORDS], x: usize, node: u32) -> usize {
    // Masked indices into a fixed-size array: never out of range.
    let a = axis[x & (GOAL_AXIS_CELLS - 1)];
    let b = axis[(node >> 16) as usize & (GOAL_AXIS_CELLS - 1)];
    let v = a.wrapping_sub(b << 16) as i32;
    let d = (v >> 20).clamp(0, 7) as u32;
    (((v as u32 >> 16) & 15) | d << 4) as usize
}

/// Words of the [`Planner`](crate::plan::planner::Planner)'s goal table: the per-axis entries, then a copy of
/// [`STEP_CLASSES`] (in RAM next to them, the search addresses both from one base).
pub(super) const GOAL_TABLE_WORDS: usize = GOAL_AXIS_CELLS + REGIONS;

/// Flag of the [`STEP_CLASSES`] word of the goal's region (above the eight 3-bit classes).
pub(super) const AT_GOAL: u32 = 1 << 31;

/// Per [`goal_region`]: the class (index into [`REDUCED_COSTS`]) of each step, in bits
/// `3 (code − 1) ..` for step code `code` (1 ..= 8). 512 bytes of read-only data, built at
/// compile time from one cell of each region (0 for the sign codes 9 ..= 15, which do not
/// occur). The goal's own region (sign code 4: `dx = dy = 0`, no other cell) also has
/// [`AT_GOAL`] set, so that the search tests for the goal on the word it loads anyway.
pub(super) static STEP_CLASSES: [u32; REGIONS] = {
    let mut table = [0u32; REGIONS];
    let mut region = 0;
    while region < REGIONS {
        let d = (region >> 4) as i32 - 4;
        let code = (region & 15) as i32;
        let (sx, sy) = (code / 3 - 1, code % 3 - 1);
        // A cell of the region: |dx|, |dy| in 0..12 with those signs and that clamped
        // difference.
        let mut found = None;
        let mut a = 0;
        while a < 12 && found.is_none() && code < 9 {
            let mut b = 0;
            while b < 12 && found.is_none() {
                let diff = a - b;
                let dc = if diff < -4 {
                    -4
                } else if diff > 3 {
                    3
                } else {
                    diff
                };
                if (a == 0) == (sx == 0) && (b == 0) == (sy == 0) && dc == d {
                    found = Some((a * sx, b * sy));
                }
                b += 1;
            }
            a += 1;
        }
        if let Some((dx, dy)) = found {
            let mut word = 0u32;
            let mut k = 0;
            while k < 8 {
                let (mx, my) = STEPS[k];
                let cost = if k >= 4 { DIAGONAL_COST } else { STRAIGHT_COST };
                let r = cost + octile((dx + mx).unsigned_abs(), (dy + my).unsigned_abs())
                    - octile(dx.unsigned_abs(), dy.unsigned_abs());
                let mut c = 0;
                while c < CLASSES && REDUCED_COSTS[c] != r {
                    c += 1;
                }
                assert!(c < CLASSES, "not a reduced cost");
                word |= (c as u32) << (3 * k);
                k += 1;
            }
            if dx == 0 && dy == 0 {
                word |= AT_GOAL;
            }
            table[region] = word;
        }
        region += 1;
    }
    table
};
