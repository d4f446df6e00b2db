//! Bit-parallel layered breadth-first search (see the module doc of [`super`], "BFS").
//!
//! The search works on whole 32-cell words: the layer-`k + 1` cells of a word are found from
//! the layer-`k` cells of the same word and its row neighbours with a few shifts, ANDs and ORs,
//! instead of one queue entry per cell. The queue holds the *frontier rows* (one entry per row
//! that gained cells in a layer), so rows the frontier does not touch cost nothing.
//!
//! Scratch layout (rows padded to `row_words = ⌈width / 32⌉` words), one *node* of `stride`
//! words per (row, word), row-major:
//!
//! | word of the node | bit `b` of word `w` in row `y` tells about cell `(32 w + b, y)` |
//! |------------------|------------------------------------------------------------------|
//! | 0 (`P0`)         | bit 0 of the cell's layer code                                   |
//! | 1 (`P1`)         | bit 1 of the cell's layer code                                   |
//! | 2 (`FREE`)       | the cell is on the map and free (stride 3 only)                  |
//!
//! followed by one *tag* word per row. The layer code is 0 for a cell not reached, else
//! `layer mod 3 + 1`. When the three planes do not fit in the scratch (narrow grids, where the
//! padding wastes most), the stride is 2 and the free bits are read from the grid's own packed
//! bits (a funnel shift per word: slower, same result).

use super::{OpenEntry, PlanError, Planner, Search, STEPS};
use crate::geom::Cell;
use crate::grid::{Grid, GridGeometry};

/// Where the BFS planes live in the scratch.
#[derive(Clone, Copy, Debug)]
pub(super) struct BfsLayout {
    width: usize,
    height: usize,
    /// Words per padded row.
    row_words: usize,
    /// Words per node: 3 (`P0`, `P1`, `FREE`) or 2 (`P0`, `P1`; free bits read from the grid).
    stride: usize,
    /// Index of the two row bit sets (frontier rows of even / odd layers), `row_set_words`
    /// words each.
    row_sets: usize,
    row_set_words: usize,
    /// A bit of a row's word mask stands for `1 << group_shift` words (0 up to 1 024 columns).
    group_shift: u32,
}

impl BfsLayout {
    /// The layout for `geometry` in `capacity_words` words of scratch, three planes if they fit.
    ///
    /// Errors: [`PlanError::ScratchTooSmall`] when not even two planes fit; its `cells` is then
    /// the scratch two planes and the row sets need, in cells (8 per word).
    pub(super) fn new(geometry: &GridGeometry, capacity_words: usize) -> Result<Self, PlanError> {
        let width = geometry.width() as usize;
        let height = geometry.height() as usize;
        let row_words = width.div_ceil(32);
        let nodes = row_words * height;
        let row_set_words = height.div_ceil(32);
        let stride = if nodes * 3 + 2 * row_set_words <= capacity_words {
            3
        } else if nodes * 2 + 2 * row_set_words <= capacity_words {
            2
        } else {
            return Err(PlanError::ScratchTooSmall {
                cells: ((nodes * 2 + 2 * row_set_words) * 8) as u32,
                capacity: (capacity_words * 8) as u32,
            });
        };
        let mut group_shift = 0;
        while (32usize << group_shift) < row_words {
            group_shift += 1;
        }
        Ok(Self {
            width,
            height,
            row_words,
            stride,
            row_sets: nodes * stride,
            row_set_words,
            group_shift,
        })
    }

    /// Index of the node of word `w` of row `y`.
    #[inline(always)]
    fn node(&self, y: usize, w: usize) -> usize {
        (y * self.row_words + w) * self.stride
    }
}

/// Free bits (1 = free) of word `w` of row `y`, read from the grid's packed occupancy bits:
/// columns past the row's end and anything off the grid read as occupied.
#[inline(always)]
fn grid_free_word(words: &[u32], width: usize, y: usize, w: usize) -> u32 {
    let bit = y * width + 32 * w;
    let i = bit >> 5;
    let lo = words.get(i).copied().unwrap_or(u32::MAX) as u64;
    let hi = words.get(i + 1).copied().unwrap_or(u32::MAX) as u64;
    let mut occupied = ((lo | (hi << 32)) >> (bit & 31)) as u32;
    let valid = width.saturating_sub(32 * w);
    if valid < 32 {
        occupied |= u32::MAX << valid;
    }
    !occupied
}

impl<const SCRATCH_WORDS: usize, const QUEUE: usize> Planner<SCRATCH_WORDS, QUEUE> {
    /// Layered bit-parallel BFS from `start` until the layer that reaches `goal` (`start !=
    /// goal`, both free and on the map). `Search::cost` is the goal's layer (the number of
    /// steps), `expanded` the number of cells reached.
    pub(super) fn bfs<const GW: usize>(
        &mut self,
        grid: &Grid<GW>,
        start: Cell,
        goal: Cell,
    ) -> Result<Search, PlanError> {
        let layout = BfsLayout::new(grid.geometry(), SCRATCH_WORDS)?;
        let mut layers = Layers {
            scratch: &mut self.scratch[..],
            queue: &mut self.queue[..],
            grid_words: grid.words(),
            layout,
            peak: 0,
            layer: 0,
            x0: 0,
            x1: 0,
            set0: 0,
            set1: 0,
            goal_node: layout.node(goal.y as usize, goal.x as usize >> 5),
            goal_bit: 1 << (goal.x & 31),
        };
        let result = if layout.stride == 3 {
            layers.run::<true>(start)
        } else {
            layers.run::<false>(start)
        };
        self.queue_peak = layers.peak as u32;
        result
    }

    /// Rebuild the BFS path from the layer codes: from the goal (layer `layers`) back to the
    /// start, each step goes to a neighbour of the previous layer that a legal move joins,
    /// preferring the previous step's direction, then E, N, W, S, NE, NW, SW, SE. Collinear
    /// cells are merged. Returns the length in cells, the steps and whether every vertex fitted.
    pub(super) fn bfs_rebuild<const GW: usize>(
        &mut self,
        grid: &Grid<GW>,
        goal: Cell,
        layers: u32,
    ) -> (f32, u32, bool) {
        let mut fits = self.cells.push(goal).is_ok();
        let layout = match BfsLayout::new(grid.geometry(), SCRATCH_WORDS) {
            Ok(layout) => layout,
            Err(_) => return (0.0, 0, fits),
        };
        let scratch = &self.scratch[..];
        let code = |x: i32, y: i32| -> u32 {
            if x < 0 || y < 0 || x as usize >= layout.width || y as usize >= layout.height {
                return 0;
            }
            let (x, y) = (x as usize, y as usize);
            let i = layout.node(y, x >> 5);
            let p0 = scratch.get(i).copied().unwrap_or(0);
            let p1 = scratch.get(i + 1).copied().unwrap_or(0);
            ((p0 >> (x & 31)) & 1) | (((p1 >> (x & 31)) & 1) << 1)
        };
        let free = |x: i32, y: i32| grid.geometry().contains_xy(x, y) && !grid.is_occupied_xy(x, y);
        let (mut straight, mut diagonal) = (0u32, 0u32);
        let mut previous: Option<usize> = None;
        let (mut x, mut y) = (goal.x as i32, goal.y as i32);
        for layer in (1..=layers).rev() {
            let want = (layer - 1) % 3 + 1;
            let legal = |k: usize| -> bool {
                let Some(&(dx, dy)) = STEPS.get(k) else {
                    return false;
                };
                let (px, py) = (x - dx, y - dy);
                code(px, py) == want && (dx == 0 || dy == 0 || (free(x, py) && free(px, y)))
            };
            let step = match previous {
                Some(k) if legal(k) => Some(k),
                _ => (0..STEPS.len()).find(|&k| legal(k)),
            };
            let Some(k) = step else {
                break; // cannot happen with a consistent layering; the guard ends the walk
            };
            if previous.is_some_and(|p| p != k) {
                fits &= self.cells.push(Cell::new(x as u16, y as u16)).is_ok();
            }
            let Some(&(dx, dy)) = STEPS.get(k) else {
                break;
            };
            if dx != 0 && dy != 0 {
                diagonal += 1;
            } else {
                straight += 1;
            }
            x -= dx;
            y -= dy;
            previous = Some(k);
        }
        let start = Cell::new(x as u16, y as u16);
        if start != goal {
            fits &= self.cells.push(start).is_ok();
        }
        self.cells.reverse();
        let length = straight as f32 + diagonal as f32 * core::f32::consts::SQRT_2;
        (length, straight + diagonal, fits)
    }
}

/// The state of one layered search: the planes and row sets in the scratch, the rows' word
/// masks in the queue.
struct Layers<'a> {
    scratch: &'a mut [u32],
    /// Entry `y` holds the word masks of row `y`'s frontier: `f` for even layers, `next` for
    /// odd ones (bit `g`: words `g << group_shift ..`).
    queue: &'a mut [OpenEntry],
    grid_words: &'a [u32],
    layout: BfsLayout,
    /// Most frontier rows in one layer.
    peak: usize,
    /// Layer being expanded.
    layer: u32,
    /// Frontier = `(P0 ^ x0) & (P1 ^ x1)`; new cells: `P0 |= n & set0`, `P1 |= n & set1`.
    x0: u32,
    x1: u32,
    set0: u32,
    set1: u32,
    goal_node: usize,
    goal_bit: u32,
}

impl Layers<'_> {
    fn result(&self, found: bool) -> Search {
        Search {
            found,
            expanded: count_reached(self.scratch, &self.layout),
            cost: if found { self.layer } else { 0 },
        }
    }

    /// `(P0, P1, FREE)` of the node at `i` (word `w` of row `y`); zeros out of range.
    #[inline(always)]
    fn load<const COPY: bool>(&self, i: usize, y: usize, w: usize) -> (u32, u32, u32) {
        if COPY {
            match self.scratch.get(i..i.wrapping_add(3)) {
                Some(&[p0, p1, free]) => (p0, p1, free),
                _ => (0, 0, 0),
            }
        } else {
            match self.scratch.get(i..i.wrapping_add(2)) {
                Some(&[p0, p1]) => (
                    p0,
                    p1,
                    grid_free_word(self.grid_words, self.layout.width, y, w),
                ),
                _ => (0, 0, 0),
            }
        }
    }

    /// Take (read and clear) row `y`'s word mask for the layer being expanded.
    #[inline(always)]
    fn take_mask(&mut self, y: usize) -> u32 {
        let odd = self.layer & 1 != 0;
        match self.queue.get_mut(y) {
            Some(e) if odd => core::mem::take(&mut e.next),
            Some(e) => core::mem::take(&mut e.f),
            None => 0,
        }
    }

    /// Row `y`'s word mask for the layer being expanded, left in place.
    #[inline(always)]
    fn peek_mask(&self, y: usize) -> u32 {
        match self.queue.get(y) {
            Some(e) if self.layer & 1 != 0 => e.next,
            Some(e) => e.f,
            None => 0,
        }
    }

    /// Set up the planes and the start, then expand layer after layer.
    fn run<const COPY: bool>(&mut self, start: Cell) -> Result<Search, PlanError> {
        let layout = self.layout;
        if self.queue.len() < layout.height {
            return Err(PlanError::QueueFull {
                capacity: self.queue.len() as u32,
            });
        }
        for y in 0..layout.height {
            for w in 0..layout.row_words {
                let i = layout.node(y, w);
                if COPY {
                    let free = grid_free_word(self.grid_words, layout.width, y, w);
                    if let Some(node) = self.scratch.get_mut(i..i + 3) {
                        node.copy_from_slice(&[0, 0, free]);
                    }
                } else if let Some(node) = self.scratch.get_mut(i..i + 2) {
                    node.fill(0);
                }
            }
        }
        self.scratch
            .get_mut(layout.row_sets..layout.row_sets + 2 * layout.row_set_words)
            .unwrap_or(&mut [])
            .fill(0);
        for e in self.queue.iter_mut().take(layout.height) {
            (e.f, e.next) = (0, 0);
        }
        // Layer 0 is the start, code 1; it is marked "by" layer -1 (an odd layer).
        (self.set0, self.set1) = (u32::MAX, 0);
        self.layer = 1;
        let (sx, sy) = (start.x as usize, start.y as usize);
        self.mark(sy, layout.node(sy, sx >> 5), sx >> 5, 1 << (sx & 31));
        self.layer = 0;
        loop {
            (self.x0, self.x1, self.set0, self.set1) = layer_masks(self.layer);
            let rows = self.expand_layer::<COPY>();
            if rows == 0 {
                return Ok(self.result(false));
            }
            self.peak = self.peak.max(rows);
            self.layer += 1;
            let reached = self.scratch.get(self.goal_node).copied().unwrap_or(0)
                | self.scratch.get(self.goal_node + 1).copied().unwrap_or(0);
            if reached & self.goal_bit != 0 {
                return Ok(self.result(true));
            }
        }
    }

    /// Expand every frontier row of the layer, in increasing row order; returns how many.
    fn expand_layer<const COPY: bool>(&mut self) -> usize {
        let layout = self.layout;
        let set = layout.row_sets + (self.layer as usize & 1) * layout.row_set_words;
        let mut rows = 0;
        for k in 0..layout.row_set_words {
            let Some(word) = self.scratch.get_mut(set + k) else {
                break;
            };
            let mut word = core::mem::take(word);
            while word != 0 {
                let b = word.trailing_zeros() as usize;
                let y0 = k * 32 + b;
                let mask = self.take_mask(y0);
                let mut y1 = y0;
                if layout.group_shift == 0 && mask.is_power_of_two() {
                    // One word and no frontier cell next to another word: merge the following
                    // rows of the same word into one vertical run.
                    while y1 - k * 32 < 31
                        && word & (2 << (y1 - k * 32)) != 0
                        && self.peek_mask(y1 + 1) == mask
                    {
                        y1 += 1;
                        self.take_mask(y1);
                    }
                    self.column::<COPY>(y0, y1, mask.trailing_zeros() as usize);
                } else {
                    self.row::<COPY>(y0, mask);
                }
                rows += y1 + 1 - y0;
                word &= !(mask_below(y1 - k * 32 + 1) & !mask_below(b));
            }
        }
        rows
    }

    /// Expand the frontier of rows `y0 ..= y1` in word `w` alone (none of them has frontier
    /// cells next to another word): targets row by row from `y0 - 1` to `y1 + 1`, each from
    /// the three source rows below, level and above, sliding up the column.
    #[inline(always)]
    fn column<const COPY: bool>(&mut self, y0: usize, y1: usize, w: usize) {
        let layout = self.layout;
        let row_len = layout.row_words * layout.stride;
        let (x0, x1) = (self.x0, self.x1);
        let first = y0.saturating_sub(1);
        let last = (y1 + 1).min(layout.height.saturating_sub(1));
        let mut i = layout.node(first, w);
        // Row below the target: frontier and free bits (none below the first target).
        let (mut fb, mut mb) = (0u32, 0u32);
        let (p0, p1, mut mc) = self.load::<COPY>(i, first, w);
        let mut fc = (p0 ^ x0) & (p1 ^ x1);
        let mut rc = p0 | p1;
        for t in first..=last {
            let (p0, p1, ma) = if t + 1 < layout.height {
                self.load::<COPY>(i.wrapping_add(row_len), t + 1, w)
            } else {
                (0, 0, 0)
            };
            let fa = (p0 ^ x0) & (p1 ^ x1);
            let gb = fb & mc;
            let ga = fa & mc;
            let reach = gb
                | ga
                | (fc << 1)
                | (fc >> 1)
                | (mb & ((gb << 1) | (gb >> 1)))
                | (ma & ((ga << 1) | (ga >> 1)));
            let n = reach & mc & !rc;
            if n != 0 {
                self.mark(t, i, w, n);
            }
            (fb, mb) = (fc, mc);
            (fc, mc, rc) = (fa, ma, p0 | p1);
            i = i.wrapping_add(row_len);
        }
    }

    /// Expand the frontier of row `y` in the word groups of `mask`: per run of words, word by
    /// word with the carries between words, into the rows below, level and above.
    fn row<const COPY: bool>(&mut self, y: usize, mut groups: u32) {
        let layout = self.layout;
        let row_len = layout.row_words * layout.stride;
        let (x0, x1) = (self.x0, self.x1);
        let frontier = |p0: u32, p1: u32| (p0 ^ x0) & (p1 ^ x1);
        let base = y * row_len;
        // Off the map: an index past the scratch, which loads as zeros (no free cell).
        let base_d = if y > 0 {
            base - row_len
        } else {
            usize::MAX / 2
        };
        let base_u = if y + 1 < layout.height {
            base + row_len
        } else {
            usize::MAX / 2
        };
        while groups != 0 {
            let a = groups.trailing_zeros() as usize;
            let run = (!(groups >> a)).trailing_zeros() as usize; // groups in the run
            groups &= !(mask_below(a + run) & !mask_below(a));
            let first = a << layout.group_shift;
            let last = ((a + run) << layout.group_shift)
                .min(layout.row_words)
                .saturating_sub(1);
            if first > last {
                continue;
            }
            let at = |b: usize, w: usize| b.wrapping_add(w * layout.stride);
            let mut d = self.load::<COPY>(at(base_d, first), y.wrapping_sub(1), first);
            let mut s = self.load::<COPY>(at(base, first), y, first);
            let mut u = self.load::<COPY>(at(base_u, first), y + 1, first);
            // Carries from the word before (its bit 31, moved to bit 0).
            let (mut fc, mut gdc, mut guc) = (0u32, 0u32, 0u32);
            for w in first..=last {
                let (dn, sn, un) = if w < last {
                    (
                        self.load::<COPY>(at(base_d, w + 1), y.wrapping_sub(1), w + 1),
                        self.load::<COPY>(at(base, w + 1), y, w + 1),
                        self.load::<COPY>(at(base_u, w + 1), y + 1, w + 1),
                    )
                } else {
                    ((0, 0, 0), (0, 0, 0), (0, 0, 0))
                };
                let f = frontier(s.0, s.1);
                let f_next = frontier(sn.0, sn.1);
                // Straight steps down / up (target free): the sources of the diagonals.
                let gd = f & d.2;
                let gu = f & u.2;
                let gd_next = f_next & dn.2;
                let gu_next = f_next & un.2;
                let same = ((f << 1) | fc | (f >> 1) | (f_next << 31)) & s.2 & !(s.0 | s.1);
                let down = (gd | (s.2 & ((gd << 1) | gdc | (gd >> 1) | (gd_next << 31))))
                    & d.2
                    & !(d.0 | d.1);
                let up = (gu | (s.2 & ((gu << 1) | guc | (gu >> 1) | (gu_next << 31))))
                    & u.2
                    & !(u.0 | u.1);
                if down != 0 {
                    self.mark(y - 1, at(base_d, w), w, down);
                }
                if same != 0 {
                    self.mark(y, at(base, w), w, same);
                }
                if up != 0 {
                    self.mark(y + 1, at(base_u, w), w, up);
                }
                (fc, gdc, guc) = (f >> 31, gd >> 31, gu >> 31);
                (d, s, u) = (dn, sn, un);
            }
        }
    }

    /// Mark the new cells `n` of word `w` of row `t` (node `i`) with the next layer's code, and
    /// record the row and word (plus the neighbour words that `n`'s edge cells reach) for the
    /// next layer.
    #[inline(always)]
    fn mark(&mut self, t: usize, i: usize, w: usize, n: u32) {
        if let Some(node) = self.scratch.get_mut(i..i.wrapping_add(2)) {
            node[0] |= n & self.set0;
            node[1] |= n & self.set1;
        }
        let layout = &self.layout;
        let mut bits = 1u32 << (w >> layout.group_shift);
        if n & 1 != 0 && w > 0 {
            bits |= 1 << ((w - 1) >> layout.group_shift);
        }
        if n >> 31 != 0 && w + 1 < layout.row_words {
            bits |= 1 << ((w + 1) >> layout.group_shift);
        }
        let set = layout.row_sets + (!self.layer as usize & 1) * layout.row_set_words;
        if let Some(word) = self.scratch.get_mut(set + (t >> 5)) {
            *word |= 1 << (t & 31);
        }
        match self.queue.get_mut(t) {
            Some(e) if self.layer & 1 != 0 => e.f |= bits,
            Some(e) => e.next |= bits,
            None => {}
        }
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

/// `(x0, x1, set0, set1)` for expanding `layer`: its frontier is `(P0 ^ x0) & (P1 ^ x1)`
/// (code `layer mod 3 + 1`), new cells get `P0 |= n & set0`, `P1 |= n & set1` (the next code).
#[inline(always)]
fn layer_masks(layer: u32) -> (u32, u32, u32, u32) {
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
fn count_reached(scratch: &[u32], layout: &BfsLayout) -> u32 {
    let mut n = 0u32;
    for y in 0..layout.height {
        for w in 0..layout.row_words {
            let i = layout.node(y, w);
            let p0 = scratch.get(i).copied().unwrap_or(0);
            let p1 = scratch.get(i + 1).copied().unwrap_or(0);
            n += (p0 | p1).count_ones();
        }
    }
    n
}
