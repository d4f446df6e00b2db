//! Corridor walks of the cell-by-cell A*: a popped cell reached by a side step with at most two
//! legal neighbours does not push its continuation; the chain of such cells is walked and
//! closed at once ([`walk_corridor`], out of line), and only the cell at its far end is pushed.
//! [`CORRIDOR_SIDES`] (512 bytes, built at compile time) tells from the nine "not blocked" bits
//! whether a cell is a corridor cell and which sides are open. Why A* stays optimal:
//! docs/planners.md, "Corridors". Measured effect (`cargo xtask mcu-bench`): the 300 × 300 maze
//! pops 2 760 cells instead of all it closes, 6.0 M → 3.7 M Cortex-M4 instructions; walks that
//! close almost nothing are given up after [`WALK_GIVE_UP_CREDIT`].

use super::layout::{CellMap, NIBBLE_WINDOWS};
use super::open_list::NIL;

/// Corridor test of the cell-by-cell A*, indexed by the nine "not blocked" bits of a 3 × 3
/// neighbourhood (bits 0..3: the row below, W to E; 3..6: the cell's row; 6..9: the row above;
/// see [`corridor_index`]): the side neighbours (bit 0 E, 1 N, 2 W, 3 S) when the centre has
/// one or two *legal* neighbours under the no-corner-cutting rule (a dead end or a corridor
/// cell), else 0. A legal diagonal needs both its side cells free, so a cell with at most two
/// legal neighbours has side neighbours only. 512 bytes of read-only data.
pub(super) static CORRIDOR_SIDES: [u8; 512] = {
    let mut table = [0u8; 512];
    let mut v = 0;
    while v < 512 {
        // Sides: E (row 1, col 2), N (row 2, col 1), W (row 1, col 0), S (row 0, col 1).
        let (e, n, w, s) = ((v >> 5) & 1, (v >> 7) & 1, (v >> 3) & 1, (v >> 1) & 1);
        let (ne, nw, sw, se) = ((v >> 8) & 1, (v >> 6) & 1, v & 1, (v >> 2) & 1);
        let legal = e + n + w + s + (ne & n & e) + (nw & n & w) + (sw & s & w) + (se & s & e);
        if legal == 1 || legal == 2 {
            table[v] = (e | n << 1 | w << 2 | s << 3) as u8;
        }
        v += 1;
    }
    table
};

/// The index into [`CORRIDOR_SIDES`] of an 18-bit neighbourhood mask (the `O_*` bits).
#[inline(always)]
pub(super) fn corridor_index(m: u32) -> usize {
    (((m >> 3) & 7) | ((m >> 6) & 0x38) | ((m >> 9) & 0x1C0)) as usize
}

/// The cell-by-cell A* stops starting corridor walks when they have closed this many cells
/// fewer than the walks started (short chains on cluttered, roomy maps: 20 % random obstacles
/// walk about 0.15 cells per walk, a maze of 1-cell corridors dozens).
pub(super) const WALK_GIVE_UP_CREDIT: i32 = -64;

/// Walk a chain of corridor cells (see "Corridors" in docs/planners.md) from the closed cell
/// `index` (entry `node`, interior) along its open side `rest` (bit `code - 1`, at most one
/// bit; 0 for a dead end): each corridor cell is closed with its step code. Returns the entry
/// of the cell to push at the end (`NIL` when nothing is to be pushed: a dead end or a closed
/// cell), the number of steps to it and the number of cells closed. Out of line so that the
/// search loop's registers are not spent on it.
#[inline(never)]
pub(super) fn walk_corridor<M: CellMap>(
    map: &mut M,
    goal: usize,
    mut wi: usize,
    mut wnode: u32,
    mut rest: u32,
) -> (u32, u32, u32) {
    let row = map.row_step();
    // Index and entry steps of the side codes E, N, W, S.
    let index_step = [1, row, usize::MAX, row.wrapping_neg()];
    const WALK_NODE_STEP: [u32; 4] = [
        1 << 4,
        1 << 16,
        (1u32 << 4).wrapping_neg(),
        (1u32 << 16).wrapping_neg(),
    ];
    let (mut steps, mut closed) = (0u32, 0u32);
    while rest != 0 {
        let c = rest.trailing_zeros() + 1;
        let k = (c - 1) as usize & 3;
        wi = wi.wrapping_add(index_step[k]);
        wnode = (wnode & !0xF).wrapping_add(WALK_NODE_STEP[k]) | c;
        steps += 1;
        let (wx, wy) = (((wnode >> 4) & 0xFFF) as usize, (wnode >> 16) as usize);
        if wi == goal || !map.interior(wi, wx, wy) {
            // Pushed, not walked (a closed cell must not be pushed: it could be expanded at
            // once by the immediate expansion).
            let end = if map.nibble(wi) == 0 { wnode } else { NIL };
            return (end, steps, closed);
        }
        let window = |w: u32| u32::from(NIBBLE_WINDOWS[w as usize & 0xFFF]);
        let (above, cur, below) = map.interior_windows(wi);
        let wc = window(cur);
        if wc & 2 == 0 {
            return (NIL, steps, closed); // closed already
        }
        let wm = window(below) | wc << 6 | window(above) << 12;
        let t = u32::from(CORRIDOR_SIDES[corridor_index(wm)]);
        if t == 0 {
            return (wnode, steps, closed); // not a corridor cell
        }
        map.mark(wi, c);
        closed += 1;
        rest = t & !(1 << ((c + 1) & 3));
    }
    (NIL, steps, closed) // a dead end
}
