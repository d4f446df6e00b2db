//! The layered BFS's kernel: one layer's new cells of a word column, as vertical runs
//! ([`Layers::column`], a window of three rows sliding along the column slice, unrolled by three
//! so that rows change roles by name), single rows ([`Layers::single`]) and moves across word
//! edges, cell by cell and out of line ([`Layers::edge_side`]). Measured effect (branch
//! `bfs-colmajor`, `cargo xtask mcu-bench`): about 45 Cortex-M4 instructions per row, were 95;
//! see docs/planners-history.md, "BFS kernel on the MCU".

use super::layers::{layer_masks, side_masks, Layers, APART, GOAL_SIDE};
use super::FreeBits;

impl Layers<'_> {
    /// The edge bits of word `w`: bit 0 when a word lies before it, bit 31 when one follows.
    #[inline(always)]
    pub(super) fn edges(&self, w: usize) -> u32 {
        (if w > 0 { 1 } else { 0 })
            | (if w + 1 < self.layout.row_words {
                1 << 31
            } else {
                0
            })
    }

    /// Expand the frontier of row `y` in word `w` into the rows below, level and above (moves
    /// out of the word: [`Layers::edge_before`], [`Layers::edge_after`]).
    #[inline(never)]
    pub(super) fn single<const ODD: bool, const SIDE: u8>(
        &mut self,
        free: &impl FreeBits,
        y: usize,
        w: usize,
    ) {
        let layout = self.layout;
        let i = layout.node(y, w);
        let s0 = self.p0.get(i).copied().unwrap_or(0);
        let s1 = self.p1.get(i).copied().unwrap_or(0);
        let ss = self.side_word::<SIDE>(i);
        let ms = free.get(y, w, i);
        let f = (s0 ^ self.x0) & (s1 ^ self.x1) & (ss ^ side_masks::<SIDE>().0);
        let spread = (f << 1) | (f >> 1);
        let same = spread & ms & !(s0 | s1);
        if same != 0 {
            self.mark::<ODD, SIDE>(y, w, i, same);
        }
        let meet = spread & (s0 | s1) & !(ss ^ side_masks::<SIDE>().0);
        if meet != 0 {
            self.meet = Some((y, y, w));
        }
        // A diagonal step needs the straight step's target free (g) and the side cell in
        // row y (ms at the target column).
        if y > 0 {
            let j = i - 1;
            let m = free.get(y - 1, w, j);
            let g = f & m;
            if g != 0 {
                let r = self.p0.get(j).copied().unwrap_or(0) | self.p1.get(j).copied().unwrap_or(0);
                let reach = (g | (ms & ((g << 1) | (g >> 1)))) & m;
                let n = reach & !r;
                if n != 0 {
                    self.mark::<ODD, SIDE>(y - 1, w, j, n);
                }
                let meet = reach & r & !(self.side_word::<SIDE>(j) ^ side_masks::<SIDE>().0);
                if meet != 0 {
                    self.meet = Some((y - 1, y - 1, w));
                }
            }
        }
        if y + 1 < layout.height {
            let j = i + 1;
            let m = free.get(y + 1, w, j);
            let g = f & m;
            if g != 0 {
                let r = self.p0.get(j).copied().unwrap_or(0) | self.p1.get(j).copied().unwrap_or(0);
                let reach = (g | (ms & ((g << 1) | (g >> 1)))) & m;
                let n = reach & !r;
                if n != 0 {
                    self.mark::<ODD, SIDE>(y + 1, w, j, n);
                }
                let meet = reach & r & !(self.side_word::<SIDE>(j) ^ side_masks::<SIDE>().0);
                if meet != 0 {
                    self.meet = Some((y + 1, y + 1, w));
                }
            }
        }
    }

    /// Expand the frontier of rows `y0 ..= y1` in word `w`: targets row by row from `y0 - 1`
    /// to `y1 + 1`, each from the three source rows below, level and above, sliding up the
    /// column (moves out of the word: [`Layers::edge_before`], [`Layers::edge_after`]).
    // Not inlined: in its own function the window keeps more of its state in registers (1-2 %
    // fewer MCU instructions). About 140 lines for the same reason: the window slides up the
    // column in one loop; a split of it is not measured.
    #[inline(never)]
    #[allow(unused_assignments)] // the window's last shift is not read
    pub(super) fn column<const ODD: bool, const SIDE: u8, const PHASE: u32>(
        &mut self,
        free: &impl FreeBits,
        y0: usize,
        y1: usize,
        w: usize,
    ) {
        let layout = self.layout;
        // The layer's masks as constants (the layer mod 3 is a parameter): four registers
        // fewer in the loop.
        let (x0, x1, set0, set1) = layer_masks(PHASE);
        let (xs, sset) = side_masks::<SIDE>();
        let edges = self.edges(w);
        let first = y0.saturating_sub(1);
        let last = (y1 + 1).min(layout.height.saturating_sub(1));
        // The column's words from the first target row up to the row above the last one (when
        // on the map): consecutive plane words (the planes are stored column by column), so
        // the window slides along slices without index arithmetic or bounds tests.
        let rows = (last + 2).min(layout.height).saturating_sub(first);
        let base = layout.node(first, w);
        let range = base..base + rows;
        let (Some(p0), Some(p1)) = (
            self.p0.get_mut(range.clone()),
            self.p1.get_mut(range.clone()),
        ) else {
            return;
        };
        let p0 = core::cell::Cell::from_mut(p0).as_slice_of_cells();
        let p1 = core::cell::Cell::from_mut(p1).as_slice_of_cells();
        // `SIDE` is neither read nor written while the sides are apart (the loads of `p0`
        // standing in for it are dead code then).
        let ps = if SIDE == APART {
            p0
        } else {
            match self.ps.get_mut(range) {
                Some(ps) => core::cell::Cell::from_mut(ps).as_slice_of_cells(),
                None => return,
            }
        };
        let side = |c: &core::cell::Cell<u32>| if SIDE == APART { 0 } else { c.get() };
        let mut window = p0
            .iter()
            .zip(p1.iter())
            .zip(ps.iter())
            .zip(free.column(first, w, base, rows));
        let Some((((r0, r1), rs), m)) = window.next() else {
            return;
        };
        let mut pending = 0u32; // rows `first + k` with new cells
        let mut pending_edges = 0u32; // ... with new cells in bit 0 or 31
        let mut met = 0u32; // cells of the other side reached
        let mut bit = 1u32; // `1 << (t - first)`
        let end = 1u32 << (last - first); // the last target's bit

        // A row of the window: frontier `f`, free `m`, codes `c0`, `c1`, side `cs`, and its
        // words (to mark new cells). Row 0: the first target; the row below it has no frontier
        // and no free cell (a diagonal move needs both side cells free).
        macro_rules! row {
            ($item:expr) => {{
                let (((r0, r1), rs), m) = $item;
                let (c0, c1, cs) = (r0.get(), r1.get(), side(rs));
                ((c0 ^ x0) & (c1 ^ x1) & (cs ^ xs), m, c0, c1, cs, r0, r1, rs)
            }};
        }
        let (mut fb, mut mb) = (0u32, 0u32);
        let mut cur = row!((((r0, r1), rs), m));
        // Target `cur` from the rows below (`fb`, `mb`) and above (`a`: its frontier, free bits;
        // zeros above the map).
        macro_rules! step {
            ($cur:expr, $fa:expr, $ma:expr) => {{
                let (fc, mc, c0, c1, cs, t0, t1, ts) = $cur;
                let (fa, ma): (u32, u32) = ($fa, $ma);
                let gb = fb & mc;
                let ga = fa & mc;
                let reach = gb
                    | ga
                    | (fc << 1)
                    | (fc >> 1)
                    | (mb & ((gb << 1) | (gb >> 1)))
                    | (ma & ((ga << 1) | (ga >> 1)));
                let n = reach & mc & !(c0 | c1);
                if n != 0 {
                    t0.set(c0 | (n & set0));
                    t1.set(c1 | (n & set1));
                    if SIDE == GOAL_SIDE {
                        ts.set(cs | (n & sset));
                    }
                    pending |= bit;
                    if n & edges != 0 {
                        pending_edges |= bit;
                    }
                }
                met |= reach & (c0 | c1) & !(cs ^ xs);
                (fb, mb) = (fc, mc);
            }};
        }
        // Unrolled by three so that the window's rows change roles by name, not by moves.
        loop {
            let Some(a) = window.next() else {
                step!(cur, 0, 0);
                break;
            };
            let a = row!(a);
            step!(cur, a.0, a.1);
            if bit == end {
                break;
            }
            bit <<= 1;
            let Some(b) = window.next() else {
                step!(a, 0, 0);
                break;
            };
            let b = row!(b);
            step!(a, b.0, b.1);
            if bit == end {
                break;
            }
            bit <<= 1;
            let Some(c) = window.next() else {
                step!(b, 0, 0);
                break;
            };
            let c = row!(c);
            step!(b, c.0, c.1);
            if bit == end {
                break;
            }
            bit <<= 1;
            cur = c;
        }
        if met != 0 {
            self.meet = Some((first, last, w));
        }
        self.note_rows::<ODD, SIDE>(w, first, pending);
        if pending_edges != 0 {
            self.note_rows::<ODD, SIDE>(layout.row_words + w, first, pending_edges);
        }
    }

    /// The moves out of word `w` from its frontier cell at bit 0 in row `y` to bit 31 of the
    /// word before, into rows `y - 1 ..= y + 1`, with the same rule: target free and not
    /// reached; for a diagonal both side cells free. Rare (one pair of cells per 32 columns),
    /// so cell by cell; one function per direction, so that its four arguments stay in
    /// registers.
    #[inline(never)]
    pub(super) fn edge_before<const ODD: bool, const SIDE: u8>(
        &mut self,
        free: &impl FreeBits,
        y: usize,
        w: usize,
    ) {
        if w > 0 {
            self.edge_side::<ODD, SIDE>(free, y, w, 0, w - 1, 31);
        }
    }

    /// [`Layers::edge_before`] the other way: from bit 31 of word `w` to bit 0 of the word
    /// after.
    #[inline(never)]
    pub(super) fn edge_after<const ODD: bool, const SIDE: u8>(
        &mut self,
        free: &impl FreeBits,
        y: usize,
        w: usize,
    ) {
        if w + 1 < self.layout.row_words {
            self.edge_side::<ODD, SIDE>(free, y, w, 31, w + 1, 0);
        }
    }

    /// One side of [`Layers::edge_before`] or [`Layers::edge_after`]: from bit `src_bit` of word `w` in row `y` to bit
    /// `dst_bit` of word `dst_w` in rows `y - 1 ..= y + 1`.
    #[inline(always)]
    fn edge_side<const ODD: bool, const SIDE: u8>(
        &mut self,
        free: &impl FreeBits,
        y: usize,
        w: usize,
        src_bit: u32,
        dst_w: usize,
        dst_bit: u32,
    ) {
        let layout = self.layout;
        let j = layout.node(y, dst_w);
        // The target in row y is also the side cell of both diagonals (source row, target
        // column): nothing moves across this edge when it is occupied.
        if free.get(y, dst_w, j) >> dst_bit & 1 == 0 {
            return;
        }
        self.edge_target::<ODD, SIDE>(y, dst_w, j, dst_bit);
        // Diagonals: target free and not reached, side cell (target row, source column) free.
        if y > 0 {
            let (t, jt) = (y - 1, j - 1);
            if free.get(t, dst_w, jt) >> dst_bit & free.get(t, w, layout.node(t, w)) >> src_bit & 1
                != 0
            {
                self.edge_target::<ODD, SIDE>(t, dst_w, jt, dst_bit);
            }
        }
        if y + 1 < layout.height {
            let (t, jt) = (y + 1, j + 1);
            if free.get(t, dst_w, jt) >> dst_bit & free.get(t, w, layout.node(t, w)) >> src_bit & 1
                != 0
            {
                self.edge_target::<ODD, SIDE>(t, dst_w, jt, dst_bit);
            }
        }
    }

    /// A legal move across a word edge reaches bit `bit` of word `w` of row `t` (plane index
    /// `i`): mark it when not reached, note a meeting when the other side reached it.
    #[inline(always)]
    fn edge_target<const ODD: bool, const SIDE: u8>(
        &mut self,
        t: usize,
        w: usize,
        i: usize,
        bit: u32,
    ) {
        let reached = self.p0.get(i).copied().unwrap_or(0) | self.p1.get(i).copied().unwrap_or(0);
        if reached >> bit & 1 == 0 {
            self.mark::<ODD, SIDE>(t, w, i, 1 << bit);
        } else if !(self.side_word::<SIDE>(i) ^ side_masks::<SIDE>().0) >> bit & 1 != 0 {
            self.meet = Some((t, t, w));
        }
    }

    /// Mark the new cells `n` of word `w` of row `t` (plane index `i`) with the next layer's
    /// code and put the row in column `w`'s next row set (and its edge set when `n` holds an
    /// edge cell).
    #[inline(always)]
    pub(super) fn mark<const ODD: bool, const SIDE: u8>(
        &mut self,
        t: usize,
        w: usize,
        i: usize,
        n: u32,
    ) {
        if let Some(p0) = self.p0.get_mut(i) {
            *p0 |= n & self.set0;
        }
        if let Some(p1) = self.p1.get_mut(i) {
            *p1 |= n & self.set1;
        }
        if SIDE == GOAL_SIDE {
            if let Some(ps) = self.ps.get_mut(i) {
                *ps |= n;
            }
        }
        self.note_row::<ODD, SIDE>(w, t);
        if n & self.edges(w) != 0 {
            self.note_row::<ODD, SIDE>(self.layout.row_words + w, t);
        }
    }

    /// Put row `t` into column `w`'s row set for the next layer, and its word into the summary.
    #[inline(always)]
    fn note_row<const ODD: bool, const SIDE: u8>(&mut self, w: usize, t: usize) {
        let layout = &self.layout;
        let at = (w << layout.set_shift) + (t >> 5);
        let sets = usize::from(!ODD) * layout.layer_set_words() + at;
        if let Some(word) = self.sets.get_mut(sets) {
            *word |= 1 << (t & 31);
        }
        let summary = usize::from(!ODD) * layout.summary_words + (at >> 5);
        if let Some(word) = self.summary.get_mut(summary) {
            *word |= 1 << (at & 31);
        }
    }

    /// Put rows `t + j` for the bits `j` of `rows` into column `w`'s row set
    /// for the next layer (even when the layer being expanded is `ODD`), and its words into the
    /// summary.
    #[inline(always)]
    pub(super) fn note_rows<const ODD: bool, const SIDE: u8>(
        &mut self,
        w: usize,
        t: usize,
        rows: u32,
    ) {
        if rows == 0 {
            return;
        }
        let layout = &self.layout;
        let index = (w << layout.set_shift) + (t >> 5);
        let sets = usize::from(!ODD) * layout.layer_set_words();
        let summary = usize::from(!ODD) * layout.summary_words;
        let shift = (t & 31) as u32;
        let wide = u64::from(rows) << shift;
        for (j, part) in [wide as u32, (wide >> 32) as u32].into_iter().enumerate() {
            if part == 0 {
                continue;
            }
            let at = index + j;
            if let Some(word) = self.sets.get_mut(sets + at) {
                *word |= part;
            }
            if let Some(word) = self.summary.get_mut(summary + (at >> 5)) {
                *word |= 1 << (at & 31);
            }
        }
    }
}
