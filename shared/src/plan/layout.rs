//! Where a cell's nibble lives in the scratch: [`CellMap`], with [`Flat`] (row-major like the
//! grid, border cells read their neighbours one by one) and [`Framed`] (rows padded to whole
//! words with a blocked frame, so every cell's 3 × 3 neighbourhood is three windows at one
//! shift, indexed through a mask instead of a bounds test). The cell-by-cell A* uses `Framed`
//! when it fits the first [`FRAMED_WORDS`] words (300 × 300: 11 477 words), else `Flat`; both
//! give the same search (tested for widths 1–40 and 63–65 and on 1 024 random grids). Also
//! [`NIBBLE_WINDOWS`], the 4 KB table that turns a window into "nibble 0" / "not blocked" bits.
//! Measured effect of the frame (branch `astar-mem`, `cargo xtask mcu-bench`): see
//! docs/planners-history.md, "Cell-by-cell A\*: framed layout".

use super::codes::{nibble, nibble_window, BLOCKED, BLOCKED_NIBBLES};
use crate::grid::{Grid, GridGeometry};

/// The map's interior for the nibble searches (scalar BFS, cell-by-cell A*): cells whose 3 × 3
/// neighbourhood lies on the map, i.e. `x` in `1 .. width - 1` and `index` in
/// `width .. cells - width`. Their neighbourhood is three [`nibble_window`]s at constant
/// offsets; border cells read nibble by nibble.
#[derive(Clone, Copy)]
pub(super) struct Interior {
    pub(super) width: usize,
    pub(super) height: usize,
    inner_x: usize,
    inner_span: usize,
}

impl Interior {
    pub(super) fn new(geometry: &GridGeometry) -> Self {
        let width = geometry.width() as usize;
        Self {
            width,
            height: geometry.height() as usize,
            inner_x: width.saturating_sub(2),
            inner_span: geometry.cell_count().saturating_sub(2 * width),
        }
    }

    /// Whether cell `index` (column `x`) is an interior cell.
    #[inline(always)]
    pub(super) fn contains(&self, index: usize, x: usize) -> bool {
        x.wrapping_sub(1) < self.inner_x && index.wrapping_sub(self.width) < self.inner_span
    }

    /// The 3 × 3 neighbourhood of cell `index` (column `x`) as three 12-bit windows, (row
    /// above, same row, row below), column `x - 1` in bits 0..4 of each. Off-map cells read as
    /// [`BLOCKED`]. `y` is called on border cells only (so a caller without the row at hand
    /// divides there only).
    #[inline(always)]
    pub(super) fn neighbourhood(
        &self,
        scratch: &[u32],
        index: usize,
        x: usize,
        y: impl FnOnce() -> usize,
    ) -> (u32, u32, u32) {
        let width = self.width;
        if self.contains(index, x) {
            return (
                nibble_window(scratch, index + width - 1),
                nibble_window(scratch, index - 1),
                nibble_window(scratch, index - width - 1),
            );
        }
        let y = y();
        // Nibble of (x + sx - 1, y + sy - 1), BLOCKED off the map.
        let at = |sx: usize, sy: usize| -> u32 {
            let (nx, ny) = ((x + sx).wrapping_sub(1), (y + sy).wrapping_sub(1));
            if nx < width && ny < self.height {
                nibble(scratch, ny * width + nx)
            } else {
                BLOCKED
            }
        };
        let row = |sy: usize| at(0, sy) | at(1, sy) << 4 | at(2, sy) << 8;
        (row(2), row(1), row(0))
    }
}

/// The nibble scratch as the cell-by-cell A* and its corridor walks read it. Two layouts with
/// the same contents and the same search on top ([`Flat`], [`Framed`]): a search gives the same
/// result, expansions and path in either.
pub(super) trait CellMap {
    /// Scratch index of cell `(x, y)` (a cell of the map).
    fn index(&self, x: usize, y: usize) -> usize;
    /// Index step of one row up.
    fn row_step(&self) -> usize;
    /// The nibble at `index` ([`BLOCKED`] beyond the scratch).
    fn nibble(&self, index: usize) -> u32;
    /// OR `code` into the nibble at `index` (a nibble known to be 0).
    fn mark(&mut self, index: usize, code: u32);
    /// Close the cell at `index` with `code` if its nibble is 0 (free, not closed); whether it
    /// was.
    fn close(&mut self, index: usize, code: u32) -> bool;
    /// Whether cell `(x, y)` at `index` is an interior cell: its 3 × 3 neighbourhood lies on
    /// the map (corridor walks stop at the others, in both layouts).
    fn interior(&self, index: usize, x: usize, y: usize) -> bool;
    /// The 3 × 3 neighbourhood of an interior cell as three 12-bit windows (row above, same
    /// row, row below), column `x - 1` in bits 0..4 of each.
    fn interior_windows(&self, index: usize) -> (u32, u32, u32);
    /// The same for any cell of the map (off-map cells read as [`BLOCKED`]).
    fn windows(&self, index: usize, x: usize, y: usize) -> (u32, u32, u32);
}

/// The flat layout: one nibble per cell, row-major like the grid (as the scalar BFS and jump
/// point search use the scratch). Cells on the map border read their neighbours one by one.
pub(super) struct Flat<'a> {
    pub(super) scratch: &'a mut [u32],
    pub(super) interior: Interior,
}

impl CellMap for Flat<'_> {
    #[inline(always)]
    fn index(&self, x: usize, y: usize) -> usize {
        y * self.interior.width + x
    }
    #[inline(always)]
    fn row_step(&self) -> usize {
        self.interior.width
    }
    #[inline(always)]
    fn nibble(&self, index: usize) -> u32 {
        nibble(self.scratch, index)
    }
    #[inline(always)]
    fn mark(&mut self, index: usize, code: u32) {
        if let Some(word) = self.scratch.get_mut(index >> 3) {
            *word |= code << ((index & 7) * 4);
        }
    }
    #[inline(always)]
    fn close(&mut self, index: usize, code: u32) -> bool {
        let Some(word) = self.scratch.get_mut(index >> 3) else {
            return false;
        };
        let shift = (index & 7) * 4;
        let open = (*word >> shift) & 0xF == 0;
        if open {
            *word |= code << shift;
        }
        open
    }
    #[inline(always)]
    fn interior(&self, index: usize, x: usize, _y: usize) -> bool {
        self.interior.contains(index, x)
    }
    #[inline(always)]
    fn interior_windows(&self, index: usize) -> (u32, u32, u32) {
        let width = self.interior.width;
        (
            nibble_window(self.scratch, index + width - 1),
            nibble_window(self.scratch, index - 1),
            nibble_window(self.scratch, index - width - 1),
        )
    }
    #[inline(always)]
    fn windows(&self, index: usize, x: usize, y: usize) -> (u32, u32, u32) {
        self.interior.neighbourhood(self.scratch, index, x, || y)
    }
}

/// Words of the [`Framed`] layout's view of the MCU-sized scratch: `2^14` words a mask can
/// index, plus one so that the second word of a window needs no bounds test either.
pub(super) const FRAMED_WORDS: usize = (1 << 14) + 1;

/// The least scratch (32-bit words) with which the cell-by-cell A* uses its framed layout
/// (grids up to about 360 × 360 cells; see docs/planners.md): the MCU's planner size.
pub const FRAMED_SCRATCH_WORDS: usize = FRAMED_WORDS;

/// The framed layout: rows padded to whole words with at least one [`BLOCKED`] nibble (the
/// row stride is `width + 1` rounded up to 8 nibbles), cell `(x, y)` at nibble `(y + 1) ·
/// stride + x + 1`, and a row of blocked nibbles below and above the map. So every cell, on
/// the border too, has its 3 × 3 neighbourhood in three windows at the same shift in three
/// words a row apart, and the words are indexed through a mask (the view is `WORDS` words,
/// `WORDS − 1` a power of two) instead of bounds tests. 300 × 300 cells take 304 / 8 × 302 =
/// 11 477 words.
pub(super) struct Framed<'a, const WORDS: usize> {
    pub(super) words: &'a mut [u32; WORDS],
    /// Row stride, nibbles (a multiple of 8) and words.
    pub(super) stride: usize,
    pub(super) row_words: usize,
    pub(super) width: usize,
    pub(super) height: usize,
}

impl<'a, const WORDS: usize> Framed<'a, WORDS> {
    /// Word indices are masked with this (`WORDS − 2`: `WORDS − 1` is a power of two).
    const MASK: usize = {
        assert!(WORDS > 2 && (WORDS - 1).is_power_of_two());
        WORDS - 2
    };

    /// Scratch words the layout needs for `geometry`: the rows, the frame rows and one more
    /// blocked word (the north-east neighbour of the last cell when `width + 1` is a multiple
    /// of 8 lies just past the upper frame row).
    const fn words_for(geometry: &GridGeometry) -> usize {
        Self::row_words(geometry) * (geometry.height() as usize + 2) + 1
    }

    /// Words of a padded row: `width + 1` nibbles (at least one blocked) rounded up.
    pub(super) const fn row_words(geometry: &GridGeometry) -> usize {
        (geometry.width() as usize + 1).div_ceil(8)
    }

    /// The layout over the first `WORDS` words of `scratch`, when they hold the framed map of
    /// `geometry` (`None`: use [`Flat`]).
    pub(super) fn new(scratch: &'a mut [u32], geometry: &GridGeometry) -> Option<Self> {
        if Self::words_for(geometry) > Self::MASK + 1 {
            return None;
        }
        let words = scratch.first_chunk_mut::<WORDS>()?;
        let row_words = Self::row_words(geometry);
        Some(Self {
            words,
            stride: row_words * 8,
            row_words,
            width: geometry.width() as usize,
            height: geometry.height() as usize,
        })
    }

    /// Copy the map into the layout: occupied cells and the frame [`BLOCKED`], free cells 0.
    /// Per row, 32 cells (four scratch words) per funnel shift of two grid words, then the
    /// row's padding nibbles are set.
    pub(super) fn copy_map<const GW: usize>(&mut self, grid: &Grid<GW>) {
        let bits = grid.words();
        let (width, row_words) = (self.width, self.row_words);
        for y in [0, self.height + 1] {
            for w in 0..row_words {
                self.words[(y * row_words + w) & Self::MASK] = u32::MAX;
            }
        }
        self.words[((self.height + 2) * row_words) & Self::MASK] = u32::MAX;
        // The nibbles past the row's last cell in its last word (none when `width + 1` is a
        // multiple of 8: the next row's left padding follows at once).
        let right_padding = match (width + 1) % 8 {
            0 => 0,
            n => u32::MAX << (4 * n),
        };
        for y in 0..self.height {
            let row = (y + 1) * row_words;
            let Some(dst) = self.words.get_mut(row..row + row_words) else {
                continue;
            };
            // Nibble n of the row is cell x = n − 1, grid bit y · width + n − 1. Counted from
            // 32 bits earlier, with a word of set bits before the grid's first, that is bit
            // `at` of the sequence (set word, grid words…, set words).
            let at = y * width + 31;
            let (k, shift) = (at / 32, (at % 32) as u32);
            let nibbles =
                |cells: u32, j: u32| BLOCKED_NIBBLES[((cells >> (8 * j)) & 0xFF) as usize];
            let funnel = |lo: u32, hi: u32| (lo >> shift) | ((hi << 1) << (31 - shift));
            let chunks = row_words.div_ceil(4);
            // Grid words k − 1 ..= k − 1 + chunks, when they are all on the grid (every row
            // but the first and the last, usually): a slice, read in pairs without tests.
            match k.checked_sub(1).and_then(|i| bits.get(i..=i + chunks)) {
                Some(source) => {
                    let mut quads = dst.chunks_exact_mut(4);
                    let mut pairs = source.windows(2);
                    for (quad, pair) in (&mut quads).zip(&mut pairs) {
                        if let ([a, b, c, d], &[lo, hi]) = (quad, pair) {
                            // Written out: the compiler does not unroll at opt-level "s".
                            let cells = funnel(lo, hi);
                            (*a, *b, *c, *d) = (
                                nibbles(cells, 0),
                                nibbles(cells, 1),
                                nibbles(cells, 2),
                                nibbles(cells, 3),
                            );
                        }
                    }
                    if let Some(&[lo, hi]) = pairs.next() {
                        let cells = funnel(lo, hi);
                        for (j, word) in quads.into_remainder().iter_mut().enumerate() {
                            *word = nibbles(cells, j as u32);
                        }
                    }
                }
                None => {
                    // The first or last row: word by word, a set word before and past the grid.
                    let word = |i: usize| match i.checked_sub(1) {
                        Some(i) => bits.get(i).copied().unwrap_or(u32::MAX),
                        None => u32::MAX,
                    };
                    for (j, out) in dst.iter_mut().enumerate() {
                        let cells = funnel(word(k + j / 4), word(k + j / 4 + 1));
                        *out = nibbles(cells, (j % 4) as u32);
                    }
                }
            }
            if let Some(word) = dst.first_mut() {
                *word |= BLOCKED; // the left padding
            }
            if let Some(word) = dst.last_mut() {
                *word |= right_padding;
            }
        }
    }

    /// Nibbles `j ..= j + 2` in bits 0..12 (higher bits: garbage), `j` not past the map.
    #[inline(always)]
    fn window_at(&self, w: usize, shift: u32) -> u32 {
        let w = w & Self::MASK;
        let (lo, hi) = (self.words[w], self.words[w + 1]);
        (lo >> shift) | ((hi << 1) << (31 - shift))
    }
}

impl<const WORDS: usize> CellMap for Framed<'_, WORDS> {
    #[inline(always)]
    fn index(&self, x: usize, y: usize) -> usize {
        (y + 1) * self.stride + x + 1
    }
    #[inline(always)]
    fn row_step(&self) -> usize {
        self.stride
    }
    #[inline(always)]
    fn nibble(&self, index: usize) -> u32 {
        (self.words[(index >> 3) & Self::MASK] >> ((index & 7) * 4)) & 0xF
    }
    #[inline(always)]
    fn mark(&mut self, index: usize, code: u32) {
        self.words[(index >> 3) & Self::MASK] |= code << ((index & 7) * 4);
    }
    #[inline(always)]
    fn close(&mut self, index: usize, code: u32) -> bool {
        let word = &mut self.words[(index >> 3) & Self::MASK];
        let shift = (index & 7) * 4;
        let open = (*word >> shift) & 0xF == 0;
        if open {
            *word |= code << shift;
        }
        open
    }
    #[inline(always)]
    fn interior(&self, _index: usize, x: usize, y: usize) -> bool {
        x.wrapping_sub(1) < self.width.wrapping_sub(2)
            && y.wrapping_sub(1) < self.height.wrapping_sub(2)
    }
    #[inline(always)]
    fn interior_windows(&self, index: usize) -> (u32, u32, u32) {
        let j = index.wrapping_sub(1);
        let (w, shift) = (j >> 3, ((j & 7) * 4) as u32);
        (
            self.window_at(w.wrapping_add(self.row_words), shift) & 0xFFF,
            self.window_at(w, shift) & 0xFFF,
            self.window_at(w.wrapping_sub(self.row_words), shift) & 0xFFF,
        )
    }
    #[inline(always)]
    fn windows(&self, index: usize, _x: usize, _y: usize) -> (u32, u32, u32) {
        self.interior_windows(index)
    }
}

/// For each 12-bit window of three nibbles (a row of a 3 × 3 neighbourhood, for the scalar BFS
/// and the cell-by-cell A*): bit `k` (k = 0, 1, 2) set when nibble `k` is 0 (free, not reached
/// or closed), bit `3 + k` when it is not [`BLOCKED`]. 4 KB of read-only data, built at compile
/// time.
pub(super) static NIBBLE_WINDOWS: [u8; 4096] = {
    let mut table = [0u8; 4096];
    let mut v = 0;
    while v < 4096 {
        let mut m = 0u8;
        let mut k = 0;
        while k < 3 {
            let code = (v >> (4 * k)) & 0xF;
            if code == 0 {
                m |= 1 << k;
            }
            if code != BLOCKED as usize {
                m |= 8 << k;
            }
            k += 1;
        }
        table[v] = m;
        v += 1;
    }
    table
};
