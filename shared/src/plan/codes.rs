//! The scratch's nibble codes: one nibble per cell, 8 cells per word, row-major like the grid
//! (or framed, see `layout.rs`): 0 free and not reached, 1 ..= 8 the step *from* the parent
//! ([`STEPS`], E N W S NE NW SW SE), 9 the start, 15 occupied. One nibble read answers both
//! "free?" and "reached?", and the path is rebuilt by walking the codes back from the goal.
//! Also the octile distance and the 12-bit nibble windows the hot loops read. The map is copied
//! in 8 cells per word from a 1 KB table built at compile time ([`BLOCKED_NIBBLES`]). See
//! docs/planners.md, "Memory layout".

use super::{DIAGONAL_COST, STRAIGHT_COST};

/// Nibble code of the start cell.
pub(super) const CODE_START: u32 = 9;
/// Nibble code of an occupied cell (copied from the map before a search).
pub(super) const BLOCKED: u32 = 0xF;

/// Spread the 8 bits of `byte` to the low bit of 8 nibbles (bit k -> bit 4k).
#[inline(always)]
pub(super) fn spread_bits_to_nibbles(byte: u32) -> u32 {
    let mut x = byte & 0xFF;
    x = (x | (x << 12)) & 0x000F_000F;
    x = (x | (x << 6)) & 0x0303_0303;
    (x | (x << 3)) & 0x1111_1111
}

/// [`BLOCKED`] in the nibble of each set bit of a byte (bit k -> nibble k): one table read
/// per 8 cells when [`Planner::copy_map`](crate::plan::planner::Planner::copy_map) copies the map. 1 KB of read-only data.
pub(super) static BLOCKED_NIBBLES: [u32; 256] = {
    let mut table = [0u32; 256];
    let mut b = 0;
    while b < 256 {
        let mut k = 0;
        while k < 8 {
            if b & (1 << k) != 0 {
                table[b] |= BLOCKED << (4 * k);
            }
            k += 1;
        }
        b += 1;
    }
    table
};

/// Step of each code 1..=8 (index = code - 1): E, N, W, S, NE, NW, SW, SE.
pub(super) const STEPS: [(i32, i32); 8] = [
    (1, 0),
    (0, 1),
    (-1, 0),
    (0, -1),
    (1, 1),
    (-1, 1),
    (-1, -1),
    (1, -1),
];

/// The eight moves, each with its nibble code (1 ..= 8, the index of [`STEPS`] plus one). A
/// `match` on a `Dir` is checked by the compiler: every move has its arm, and an arm names a
/// move by its path (`Dir::E`), which cannot silently become a catch-all binding the way a
/// glob-imported `u32` constant can when its import goes missing (issue 27, item 4).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub(super) enum Dir {
    E = 1,
    N = 2,
    W = 3,
    S = 4,
    NE = 5,
    NW = 6,
    SW = 7,
    SE = 8,
}

impl Dir {
    /// The move's nibble code.
    #[inline(always)]
    pub(super) const fn code(self) -> u32 {
        self as u32
    }

    /// The move of a nibble code; `None` for 0 (not reached), [`CODE_START`] and [`BLOCKED`].
    #[inline(always)]
    pub(super) const fn from_code(code: u32) -> Option<Dir> {
        match code {
            1 => Some(Dir::E),
            2 => Some(Dir::N),
            3 => Some(Dir::W),
            4 => Some(Dir::S),
            5 => Some(Dir::NE),
            6 => Some(Dir::NW),
            7 => Some(Dir::SW),
            8 => Some(Dir::SE),
            _ => None,
        }
    }
}

// The codes as numbers, for the arithmetic on them (step tables, comparisons, entries).
pub(super) const E: u32 = Dir::E.code();
pub(super) const N: u32 = Dir::N.code();
pub(super) const W: u32 = Dir::W.code();
pub(super) const S: u32 = Dir::S.code();
pub(super) const NE: u32 = Dir::NE.code();
pub(super) const NW: u32 = Dir::NW.code();
pub(super) const SW: u32 = Dir::SW.code();
pub(super) const SE: u32 = Dir::SE.code();

#[inline(always)]
pub(super) fn nibble(scratch: &[u32], index: usize) -> u32 {
    match scratch.get(index >> 3) {
        Some(w) => (w >> ((index & 7) * 4)) & 0xF,
        None => 0xF,
    }
}

#[inline(always)]
pub(super) fn set_nibble(scratch: &mut [u32], index: usize, code: u32) {
    if let Some(w) = scratch.get_mut(index >> 3) {
        let shift = (index & 7) * 4;
        *w = (*w & !(0xF << shift)) | (code << shift);
    }
}

/// The step code (1..=8) of the unit step `(dx, dy)`; 0 for `(0, 0)` or a non-unit step.
#[inline(always)]
pub(super) const fn step_code(dx: i32, dy: i32) -> u32 {
    match (dx, dy) {
        (1, 0) => E,
        (0, 1) => N,
        (-1, 0) => W,
        (0, -1) => S,
        (1, 1) => NE,
        (-1, 1) => NW,
        (-1, -1) => SW,
        (1, -1) => SE,
        _ => 0,
    }
}

/// Octile distance in A* cost units (also used by the tables built at compile time).
#[inline(always)]
pub(super) const fn octile(dx: u32, dy: u32) -> u32 {
    let (lo, hi) = if dx < dy { (dx, dy) } else { (dy, dx) };
    DIAGONAL_COST
        .saturating_mul(lo)
        .saturating_add(STRAIGHT_COST.saturating_mul(hi - lo))
}

/// Nibbles `j`, `j + 1`, `j + 2` of the scratch in bits 0..12 (beyond it: [`BLOCKED`]).
#[inline(always)]
pub(super) fn nibble_window(scratch: &[u32], j: usize) -> u32 {
    let w = j >> 3;
    match scratch.get(w..w.wrapping_add(2)) {
        Some(&[lo, hi]) => {
            let shift = ((j & 7) * 4) as u32;
            ((lo >> shift) | ((hi << 1) << (31 - shift))) & 0xFFF
        }
        _ => nibble(scratch, j) | nibble(scratch, j + 1) << 4 | nibble(scratch, j + 2) << 8,
    }
}
