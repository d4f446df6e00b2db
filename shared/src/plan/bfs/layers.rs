//! The layered BFS's search state ([`Layers`]): seeding, the two sides (start's and goal's)
//! taking turns one layer each, the `SIDE` plane only once the sides' 32 × 32 blocks come near
//! ([`Blocks`]), the layer loop ([`Layers::run`], [`Layers::expand_layer`]) and the walk back
//! from a meeting ([`PathBuilder`]). The per-word kernel is in `kernel.rs`. Measured effect
//! (branch `bfs-bidir`, `cargo bench -p twil-core --bench planners`): on the 300 × 300 open
//! floor each side floods 146 layers, 46 345 cells instead of 88 803.

use super::{BfsLayout, FreeBits, NARROW_CHECK_LAYER, NARROW_PAIRS_PER_LAYER, RUN_JOIN_GAP};
use crate::geom::Cell;
use crate::plan::meet::Meet;
use crate::plan::path::PathOut;
use crate::plan::PathCells;

/// A merged polyline built move by move: a move in the previous move's direction moves the
/// last vertex, any other adds one.
pub(super) struct PathBuilder<'c> {
    pub(super) cells: &'c mut PathCells,
    /// Writes to `cells`, or only counts.
    pub(super) out: PathOut,
    pub(super) at: (i32, i32),
    pub(super) dir: Option<(i32, i32)>,
    /// Direction of the first move.
    pub(super) first_dir: Option<(i32, i32)>,
    pub(super) fits: bool,
    pub(super) straight: u32,
    pub(super) diagonal: u32,
}

impl PathBuilder<'_> {
    pub(super) fn push(&mut self, (dx, dy): (i32, i32)) {
        self.at = (self.at.0 + dx, self.at.1 + dy);
        let c = Cell::new(self.at.0 as u16, self.at.1 as u16);
        // A move in the same direction moves the last vertex (counting: the count stays).
        if self.dir == Some((dx, dy)) && self.out.count() > 0 {
            if let Some(last) = self.cells.last_mut().filter(|_| !self.out.is_counting()) {
                *last = c;
            }
        } else {
            self.fits &= self.out.push(self.cells, c);
        }
        if self.first_dir.is_none() {
            self.first_dir = Some((dx, dy));
        }
        self.dir = Some((dx, dy));
        if dx != 0 && dy != 0 {
            self.diagonal += 1;
        } else {
            self.straight += 1;
        }
    }
}

/// A rectangle of blocks (word column `w0 ..= w1`, 32-row block `k0 ..= k1`) that holds all
/// cells of one side; empty when `w0 > w1`.
#[derive(Clone, Copy, Debug)]
struct Blocks {
    pub(super) w0: usize,
    pub(super) w1: usize,
    k0: usize,
    k1: usize,
}

impl Blocks {
    const EMPTY: Self = Self {
        w0: usize::MAX,
        w1: 0,
        k0: usize::MAX,
        k1: 0,
    };

    fn add(&mut self, w: usize, k: usize) {
        self.w0 = self.w0.min(w);
        self.w1 = self.w1.max(w);
        self.k0 = self.k0.min(k);
        self.k1 = self.k1.max(k);
    }

    /// Whether a layer of one side can touch a word of the other: their rectangles, one grown
    /// by a block each way (a move goes one row or one word further), meet.
    fn near(&self, other: &Self) -> bool {
        self.w0 <= self.w1
            && other.w0 <= other.w1
            && self.w0 <= other.w1.saturating_add(1)
            && other.w0 <= self.w1.saturating_add(1)
            && self.k0 <= other.k1.saturating_add(1)
            && other.k0 <= self.k1.saturating_add(1)
    }
}

/// How a layered search ended.
pub(super) enum Outcome {
    /// The two sides met.
    Met(Meet),
    Unreachable,
    /// The frontier is narrow: better searched cell by cell.
    Narrow,
}

/// The state of one layered search from both ends: the planes, the row sets and their
/// summaries. The fields name the side being expanded and the other one; switching sides swaps
/// them.
pub(super) struct Layers<'a> {
    pub(super) p0: &'a mut [u32],
    pub(super) p1: &'a mut [u32],
    /// `SIDE`: the cell was reached from the goal.
    pub(super) ps: &'a mut [u32],
    /// Per layer parity (even, odd), per word column `w`, a bit set of the rows whose word `w`
    /// holds frontier cells (word `k` of column `w` at `parity · 2 row_words · set_words +
    /// w · set_words + k`), then per word column `w` (as column `row_words + w`) the rows
    /// whose word `w` holds frontier cells in bit 0 or 31 (next to another word).
    pub(super) sets: &'a mut [u32],
    /// Per layer parity, bit `w · set_words + k` set when that row-set word is not empty.
    pub(super) summary: &'a mut [u32],
    /// The other side's row sets and summaries.
    pub(super) other_sets: &'a mut [u32],
    pub(super) other_summary: &'a mut [u32],
    pub(super) layout: BfsLayout,
    /// Most frontier (row, word) pairs in one layer.
    pub(super) peak: usize,
    /// Layer being expanded (of the side being expanded).
    pub(super) layer: u32,
    /// The other side's last layer.
    pub(super) other_layer: u32,
    /// The side being expanded is the goal's.
    pub(super) goal_side: bool,
    /// Frontier = `(P0 ^ x0) & (P1 ^ x1) & (SIDE ^ xs)`; new cells: `P0 |= n & set0`,
    /// `P1 |= n & set1`, `SIDE |= n & sset`. Cells of the other side: `(P0 | P1) & !(SIDE ^
    /// xs)`.
    pub(super) x0: u32,
    pub(super) x1: u32,
    pub(super) set0: u32,
    pub(super) set1: u32,
    /// A meeting found in this layer: rows `y0 ..= y1` of word `w` hold a cell of the other
    /// side that a frontier cell reaches.
    pub(super) meet: Option<(usize, usize, usize)>,
}

impl Layers<'_> {
    /// The `SIDE` word of node `i`; 0 when the sides are [`APART`].
    #[inline(always)]
    pub(super) fn side_word<const SIDE: u8>(&self, i: usize) -> u32 {
        if SIDE == APART {
            0
        } else {
            self.ps.get(i).copied().unwrap_or(0)
        }
    }

    /// Mark `cell` as layer 0 of the side being expanded and note it as if found by layer -1
    /// (odd).
    pub(super) fn seed(&mut self, cell: Cell) {
        let layout = self.layout;
        let (x, y) = (cell.x as usize, cell.y as usize);
        let i = layout.node(y, x >> 5);
        if let Some(p0) = self.p0.get_mut(i) {
            *p0 |= 1 << (x & 31);
        }
        if self.goal_side {
            if let Some(ps) = self.ps.get_mut(i) {
                *ps |= 1 << (x & 31);
            }
        }
        self.note_rows::<true, APART>(x >> 5, y, 1);
        if (1u32 << (x & 31)) & self.edges(x >> 5) != 0 {
            self.note_rows::<true, APART>(layout.row_words + (x >> 5), y, 1);
        }
    }

    /// Add the blocks of the side's row sets of `parity` (from their summary) to `blocks`.
    fn grow_blocks(&self, parity: usize, blocks: &mut Blocks) {
        let layout = self.layout;
        let at = parity * layout.summary_words;
        let words = self
            .summary
            .get(at..at + layout.summary_words)
            .unwrap_or(&[]);
        for (si, &word) in words.iter().enumerate() {
            let mut word = word;
            while word != 0 {
                let index = si * 32 + word.trailing_zeros() as usize;
                word &= word - 1;
                let w = index >> layout.set_shift;
                let w = if w >= layout.row_words {
                    w - layout.row_words
                } else {
                    w
                };
                blocks.add(w, index & (layout.set_words - 1));
            }
        }
    }

    /// Set `SIDE` to the reached cells of `blocks` (the goal side's, apart from the start's).
    fn mark_goal_side(&mut self, blocks: &Blocks) {
        let layout = self.layout;
        for k in blocks.k0..=blocks.k1 {
            for y in 32 * k..(32 * k + 32).min(layout.height) {
                for w in blocks.w0..=blocks.w1 {
                    let i = layout.node(y, w);
                    let reached =
                        self.p0.get(i).copied().unwrap_or(0) | self.p1.get(i).copied().unwrap_or(0);
                    if let Some(side) = self.ps.get_mut(i) {
                        *side = reached;
                    }
                }
            }
        }
    }

    /// Switch to the other side.
    fn switch(&mut self) {
        core::mem::swap(&mut self.sets, &mut self.other_sets);
        core::mem::swap(&mut self.summary, &mut self.other_summary);
        core::mem::swap(&mut self.layer, &mut self.other_layer);
        self.goal_side = !self.goal_side;
    }

    /// Mark the start and the goal, then expand layer after layer, alternating between the
    /// sides (the start's first), until a layer
    /// reaches a cell of the other side, or adds no cell (unreachable), or the frontier turns
    /// out narrow (see [`NARROW_CHECK_LAYER`]).
    #[inline(never)]
    pub(super) fn run(&mut self, free: &impl FreeBits, start: Cell, goal: Cell) -> Outcome {
        self.sets.fill(0);
        self.summary.fill(0);
        self.other_sets.fill(0);
        self.other_summary.fill(0);
        self.goal_side = false;
        self.seed(start);
        let two_sided = self.layout.two_sided;
        // Per side, the blocks (word column, 32 rows) its cells lie in.
        let (mut bounds, mut other_bounds) = (Blocks::EMPTY, Blocks::EMPTY);
        self.grow_blocks(0, &mut bounds);
        if two_sided {
            self.switch();
            core::mem::swap(&mut bounds, &mut other_bounds);
            self.seed(goal);
            self.grow_blocks(0, &mut bounds);
            self.switch();
            core::mem::swap(&mut bounds, &mut other_bounds);
        }
        // Whether `SIDE` is kept: from the first layer whose words may hold cells of both sides
        // (the seeds set it; while the sides are apart, the goal side's new cells do not).
        let mut mixed = two_sided && bounds.near(&other_bounds);
        let goal_node = self.layout.node(goal.y as usize, goal.x as usize >> 5);
        let goal_bit = 1u32 << (goal.x & 31);
        (self.layer, self.other_layer) = (0, 0);
        let mut pairs = 0usize;
        let mut layers = 0u32;
        loop {
            if two_sided && layers > 0 {
                self.switch();
                core::mem::swap(&mut bounds, &mut other_bounds);
            }
            if two_sided && !mixed && bounds.near(&other_bounds) {
                // The blocks of the two sides are still apart: `SIDE` is the reached cells in
                // the goal side's blocks.
                let goal_bounds = if self.goal_side { bounds } else { other_bounds };
                self.mark_goal_side(&goal_bounds);
                mixed = true;
            }
            (self.x0, self.x1, self.set0, self.set1) = layer_masks(self.layer);
            let odd = self.layer & 1 != 0;
            let side = match (mixed, self.goal_side) {
                (false, _) => APART,
                (true, false) => START_SIDE,
                (true, true) => GOAL_SIDE,
            };
            let rows = match (odd, side) {
                (false, START_SIDE) => self.expand_layer::<false, START_SIDE>(free),
                (true, START_SIDE) => self.expand_layer::<true, START_SIDE>(free),
                (false, GOAL_SIDE) => self.expand_layer::<false, GOAL_SIDE>(free),
                (true, GOAL_SIDE) => self.expand_layer::<true, GOAL_SIDE>(free),
                (false, _) => self.expand_layer::<false, APART>(free),
                (true, _) => self.expand_layer::<true, APART>(free),
            };
            self.grow_blocks(usize::from(!odd), &mut bounds);
            if let Some((y0, y1, w)) = self.meet {
                return Outcome::Met(Meet {
                    rows: (y0, y1),
                    word: w,
                    goal_side: self.goal_side,
                    layer: self.layer,
                    other_layer: self.other_layer,
                    one_sided: false,
                });
            }
            // No cell in the next layer (its summary is empty): this side's region is all
            // reached and holds no cell of the other side.
            let next = usize::from(!odd) * self.layout.summary_words;
            let grew = self
                .summary
                .get(next..next + self.layout.summary_words)
                .is_some_and(|s| s.iter().any(|&w| w != 0));
            if !grew {
                return Outcome::Unreachable;
            }
            self.peak = self.peak.max(rows);
            pairs += rows;
            self.layer += 1;
            layers += 1;
            if !two_sided {
                let reached = self.p0.get(goal_node).copied().unwrap_or(0)
                    | self.p1.get(goal_node).copied().unwrap_or(0);
                if reached & goal_bit != 0 {
                    return Outcome::Met(Meet {
                        rows: (goal.y as usize, goal.y as usize),
                        word: goal.x as usize >> 5,
                        goal_side: false,
                        layer: self.layer,
                        other_layer: 0,
                        one_sided: true,
                    });
                }
            }
            if layers == NARROW_CHECK_LAYER
                && pairs < NARROW_PAIRS_PER_LAYER * NARROW_CHECK_LAYER as usize
            {
                return Outcome::Narrow;
            }
        }
    }

    /// Expand every frontier (row, word) of the layer, column by column, in runs of consecutive
    /// rows; returns how many (row, word) pairs.
    fn expand_layer<const ODD: bool, const SIDE: u8>(&mut self, free: &impl FreeBits) -> usize {
        let layout = self.layout;
        let set_words = layout.set_words;
        let sets = usize::from(ODD) * layout.layer_set_words();
        let summary = usize::from(ODD) * layout.summary_words;
        let mut pairs = 0;
        for si in 0..layout.summary_words {
            let Some(s) = self.summary.get_mut(summary + si) else {
                break;
            };
            let mut nonempty = core::mem::take(s);
            while nonempty != 0 {
                let index = si * 32 + nonempty.trailing_zeros() as usize;
                nonempty &= nonempty - 1;
                let (w, k) = (index >> layout.set_shift, index & (set_words - 1));
                let Some(word) = self.sets.get_mut(sets + index) else {
                    continue;
                };
                let mut word = core::mem::take(word);
                if w >= layout.row_words {
                    // Rows with frontier cells at the edges of word `w - row_words`.
                    let w = w - layout.row_words;
                    let edges = self.edges(w);
                    while word != 0 {
                        let y = k * 32 + word.trailing_zeros() as usize;
                        word &= word - 1;
                        let i = layout.node(y, w);
                        let p0 = self.p0.get(i).copied().unwrap_or(0);
                        let p1 = self.p1.get(i).copied().unwrap_or(0);
                        let side = self.side_word::<SIDE>(i);
                        let f = (p0 ^ self.x0)
                            & (p1 ^ self.x1)
                            & (side ^ side_masks::<SIDE>().0)
                            & edges;
                        if f & 1 != 0 {
                            self.edge_before::<ODD, SIDE>(free, y, w);
                        }
                        if f >> 31 != 0 {
                            self.edge_after::<ODD, SIDE>(free, y, w);
                        }
                    }
                    continue;
                }
                while word != 0 {
                    let b = word.trailing_zeros() as usize;
                    // At most 30 rows per run (`column` keeps its rows in a u32).
                    let run = ((!(word >> b)).trailing_zeros() as usize).min(30);
                    word &= !(mask_below(b + run) & !mask_below(b));
                    let y0 = k * 32 + b;
                    let mut y1 = y0 + run - 1;
                    let mut rows = run;
                    // Runs of the word one or two rows apart go together: the rows between
                    // are targets of both anyway (frontier rows only count once).
                    while word != 0 {
                        let nb = word.trailing_zeros() as usize;
                        let nrun = (!(word >> nb)).trailing_zeros() as usize;
                        if k * 32 + nb > y1 + RUN_JOIN_GAP + 1 || k * 32 + nb + nrun - 1 - y0 > 29 {
                            break;
                        }
                        word &= !(mask_below(nb + nrun) & !mask_below(nb));
                        y1 = k * 32 + nb + nrun - 1;
                        rows += nrun;
                    }
                    // A run that reaches the word's last row goes on in the next word of the
                    // column (up to 30 rows, so that `column` keeps its rows in a u32).
                    let mut next = index + 1;
                    while y1 & 31 == 31 && y1 - y0 < 29 && next & (set_words - 1) != 0 {
                        let Some(more) = self.sets.get_mut(sets + next) else {
                            break;
                        };
                        let take = ((!*more).trailing_zeros() as usize).min(29 - (y1 - y0));
                        if take == 0 {
                            break;
                        }
                        *more &= !mask_below(take);
                        y1 += take;
                        rows += take;
                        next += 1;
                    }
                    pairs += rows;
                    if y1 == y0 {
                        self.single::<ODD, SIDE>(free, y0, w);
                    } else {
                        match self.layer % 3 {
                            0 => self.column::<ODD, SIDE, 0>(free, y0, y1, w),
                            1 => self.column::<ODD, SIDE, 1>(free, y0, y1, w),
                            _ => self.column::<ODD, SIDE, 2>(free, y0, y1, w),
                        }
                    }
                }
            }
        }
        pairs
    }
}

/// The 32-bit mask of bits `0 .. n` (all bits for `n >= 32`).
#[inline(always)]
fn mask_below(n: usize) -> u32 {
    if n >= 32 {
        u32::MAX
    } else {
        (1u32 << n) - 1
    }
}

/// The side expanded (`SIDE` parameter of the expansion): the start's, the goal's, or either
/// while no word can hold cells of both ([`APART`]: `SIDE` is neither read nor written).
const START_SIDE: u8 = 0;
/// See [`START_SIDE`].
pub(super) const GOAL_SIDE: u8 = 1;
/// See [`START_SIDE`].
pub(super) const APART: u8 = 2;

/// `(xs, sset)` for expanding a layer of side `SIDE`: the side's cells are `SIDE ^ xs`, new
/// cells get `SIDE |= n & sset` (apart: the `SIDE` word reads as 0, so every reached cell is
/// the side's own and none is the other's).
#[inline(always)]
pub(super) const fn side_masks<const SIDE: u8>() -> (u32, u32) {
    if SIDE == GOAL_SIDE {
        (0, u32::MAX)
    } else {
        (u32::MAX, 0)
    }
}

/// `(x0, x1, set0, set1)` for expanding `layer`: its frontier is `(P0 ^ x0) & (P1 ^ x1)`
/// (code `layer mod 3 + 1`), new cells get `P0 |= n & set0`, `P1 |= n & set1` (the next code).
#[inline(always)]
pub(super) fn layer_masks(layer: u32) -> (u32, u32, u32, u32) {
    let code = layer % 3 + 1;
    let next = (layer + 1) % 3 + 1;
    let all = |bit: bool| if bit { u32::MAX } else { 0 };
    (
        all(code & 1 == 0),
        all(code & 2 == 0),
        all(next & 1 != 0),
        all(next & 2 != 0),
    )
}

/// Cells reached (layer code not 0) in the planes.
pub(super) fn count_reached(scratch: &[u32], layout: &BfsLayout) -> u32 {
    let mut n = 0u32;
    let (p0, rest) = scratch.split_at(layout.nodes.min(scratch.len()));
    for (a, b) in p0.iter().zip(rest.iter().take(layout.nodes)) {
        n += (a | b).count_ones();
    }
    n
}
