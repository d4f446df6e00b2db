//! Bit-parallel layered breadth-first search (see the module doc of [`super`], "BFS").
//!
//! The search works on whole 32-cell words: the layer-`k + 1` cells of a word are found from
//! the layer-`k` cells of the same word and of the rows below and above with a few shifts,
//! ANDs and ORs, instead of one queue entry per cell. Only the rows that hold frontier cells
//! are visited, and in them only the words that do.
//!
//! Scratch layout (rows padded to `row_words = ⌈width / 32⌉` words, `nodes = height ×
//! row_words`), bit `b` of word `y · row_words + w` of a plane is cell `(32 w + b, y)`:
//!
//! | words                     | plane / content                                            |
//! |---------------------------|------------------------------------------------------------|
//! | `0 .. nodes`              | `P0`: bit 0 of the cell's layer code                       |
//! | `nodes .. 2 nodes`        | `P1`: bit 1 of the cell's layer code                       |
//! | `2 nodes .. 3 nodes`      | `FREE`: the cell is free (only when it fits, see below)    |
//! | then `2 ⌈height / 32⌉`    | two row sets: rows with frontier cells, even / odd layers  |
//!
//! The layer code is 0 for a cell not reached, else `layer mod 3 + 1`. When `FREE` does not fit
//! in the scratch (narrow grids, where the padding wastes most), the free bits are read from
//! the grid's own packed bits instead (a funnel shift per word: slower, same result). Queue
//! entry `y` holds row `y`'s *word masks* (which words hold frontier cells) for even and odd
//! layers.

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
    /// Words per plane: `height × row_words`.
    nodes: usize,
    /// Whether the `FREE` plane fits (else the free bits come from the grid).
    copy_free: bool,
    /// Words of one row set (frontier rows of even / odd layers; two sets after the planes).
    row_set_words: usize,
    /// A bit of a row's word mask stands for `1 << group_shift` words (0 up to 1 024 columns).
    group_shift: u32,
}

impl BfsLayout {
    /// The layout for `geometry` in `capacity_words` words of scratch, with the `FREE` plane if
    /// it fits.
    ///
    /// Errors: [`PlanError::ScratchTooSmall`] when not even `P0`, `P1` and the row sets fit; its
    /// `cells` is then the scratch they need, in cells (8 per word).
    pub(super) fn new(geometry: &GridGeometry, capacity_words: usize) -> Result<Self, PlanError> {
        let width = geometry.width() as usize;
        let height = geometry.height() as usize;
        let row_words = width.div_ceil(32);
        let nodes = row_words * height;
        let row_set_words = height.div_ceil(32);
        let copy_free = nodes * 3 + 2 * row_set_words <= capacity_words;
        let planes = if copy_free { 3 } else { 2 };
        if nodes * planes + 2 * row_set_words > capacity_words {
            return Err(PlanError::ScratchTooSmall {
                cells: ((nodes * 2 + 2 * row_set_words) * 8) as u32,
                capacity: (capacity_words * 8) as u32,
            });
        }
        let mut group_shift = 0;
        while (32usize << group_shift) < row_words {
            group_shift += 1;
        }
        Ok(Self {
            width,
            height,
            row_words,
            nodes,
            copy_free,
            row_set_words,
            group_shift,
        })
    }

    /// Index of word `w` of row `y` in a plane.
    #[inline(always)]
    fn node(&self, y: usize, w: usize) -> usize {
        y * self.row_words + w
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

/// The free bits of a plane word: from the `FREE` plane, or computed from the grid.
trait FreeBits {
    fn get(&self, y: usize, w: usize, i: usize) -> u32;
}

/// The `FREE` plane in the scratch.
struct FreePlane<'a>(&'a [u32]);

impl FreeBits for FreePlane<'_> {
    #[inline(always)]
    fn get(&self, _y: usize, _w: usize, i: usize) -> u32 {
        self.0.get(i).copied().unwrap_or(0)
    }
}

/// The grid's own bits (narrow grids).
struct GridBits<'a> {
    words: &'a [u32],
    width: usize,
    height: usize,
}

impl FreeBits for GridBits<'_> {
    #[inline(always)]
    fn get(&self, y: usize, w: usize, _i: usize) -> u32 {
        if y < self.height {
            grid_free_word(self.words, self.width, y, w)
        } else {
            0
        }
    }
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
        if self.queue.len() < layout.height {
            return Err(PlanError::QueueFull {
                capacity: self.queue.len() as u32,
            });
        }
        let grid_words = grid.words();
        let (p0, rest) = self.scratch.split_at_mut(layout.nodes);
        let (p1, rest) = rest.split_at_mut(layout.nodes);
        let (free, sets) = if layout.copy_free {
            rest.split_at_mut(layout.nodes)
        } else {
            rest.split_at_mut(0)
        };
        let sets = sets.get_mut(..2 * layout.row_set_words).unwrap_or(&mut []);
        p0.fill(0);
        p1.fill(0);
        if layout.copy_free {
            for y in 0..layout.height {
                let row = free
                    .get_mut(y * layout.row_words..(y + 1) * layout.row_words)
                    .unwrap_or(&mut []);
                for (w, word) in row.iter_mut().enumerate() {
                    *word = grid_free_word(grid_words, layout.width, y, w);
                }
            }
        }
        let mut layers = Layers {
            p0,
            p1,
            sets,
            queue: &mut self.queue[..],
            layout,
            peak: 0,
            layer: 0,
            next_lo: usize::MAX,
            next_hi: 0,
            x0: 0,
            x1: 0,
            set0: 0,
            set1: 0,
        };
        let goal_node = layout.node(goal.y as usize, goal.x as usize >> 5);
        let goal_bit = 1u32 << (goal.x & 31);
        let found = if layout.copy_free {
            layers.run(&FreePlane(free), start, goal_node, goal_bit)
        } else {
            let bits = GridBits {
                words: grid_words,
                width: layout.width,
                height: layout.height,
            };
            layers.run(&bits, start, goal_node, goal_bit)
        };
        self.queue_peak = layers.peak as u32;
        let expanded = count_reached(&self.scratch, &layout);
        Ok(Search {
            found: found.is_some(),
            expanded,
            cost: found.unwrap_or(0),
        })
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
            let p1 = scratch.get(layout.nodes + i).copied().unwrap_or(0);
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
    p0: &'a mut [u32],
    p1: &'a mut [u32],
    /// The two row sets (even layers, then odd layers).
    sets: &'a mut [u32],
    /// Entry `y` holds the word masks of row `y`'s frontier: `f` for even layers, `next` for
    /// odd ones (bit `g`: words `g << group_shift ..`).
    queue: &'a mut [OpenEntry],
    layout: BfsLayout,
    /// Most frontier rows in one layer.
    peak: usize,
    /// Layer being expanded.
    layer: u32,
    /// Range of row-set words that the next layer's rows fall in.
    next_lo: usize,
    next_hi: usize,
    /// Frontier = `(P0 ^ x0) & (P1 ^ x1)`; new cells: `P0 |= n & set0`, `P1 |= n & set1`.
    x0: u32,
    x1: u32,
    set0: u32,
    set1: u32,
}

impl Layers<'_> {
    /// Take (read and clear) row `y`'s word mask for the layer being expanded.
    #[inline(always)]
    fn take_mask<const ODD: bool>(&mut self, y: usize) -> u32 {
        match self.queue.get_mut(y) {
            Some(e) if ODD => core::mem::take(&mut e.next),
            Some(e) => core::mem::take(&mut e.f),
            None => 0,
        }
    }

    /// Row `y`'s word mask for the layer being expanded, left in place.
    #[inline(always)]
    fn peek_mask<const ODD: bool>(&self, y: usize) -> u32 {
        match self.queue.get(y) {
            Some(e) if ODD => e.next,
            Some(e) => e.f,
            None => 0,
        }
    }

    /// Mark the start, then expand layer after layer until the goal's word bit is reached
    /// (`Some(layer)`) or a layer is empty (`None`).
    fn run(
        &mut self,
        free: &impl FreeBits,
        start: Cell,
        goal_node: usize,
        goal_bit: u32,
    ) -> Option<u32> {
        let layout = self.layout;
        self.sets.fill(0);
        for e in self.queue.iter_mut().take(layout.height) {
            (e.f, e.next) = (0, 0);
        }
        // Layer 0 is the start, code 1; it is noted as if found by layer -1 (odd).
        let (sx, sy) = (start.x as usize, start.y as usize);
        if let Some(p0) = self.p0.get_mut(layout.node(sy, sx >> 5)) {
            *p0 |= 1 << (sx & 31);
        }
        self.note::<true>(sy, sx >> 5, 1 << (sx & 31));
        self.layer = 0;
        loop {
            (self.x0, self.x1, self.set0, self.set1) = layer_masks(self.layer);
            let (lo, hi) = (self.next_lo, self.next_hi);
            (self.next_lo, self.next_hi) = (usize::MAX, 0);
            let rows = if self.layer & 1 != 0 {
                self.expand_layer::<true>(free, lo, hi)
            } else {
                self.expand_layer::<false>(free, lo, hi)
            };
            if rows == 0 {
                return None;
            }
            self.peak = self.peak.max(rows);
            self.layer += 1;
            let reached = self.p0.get(goal_node).copied().unwrap_or(0)
                | self.p1.get(goal_node).copied().unwrap_or(0);
            if reached & goal_bit != 0 {
                return Some(self.layer);
            }
        }
    }

    /// Expand every frontier row of the layer, in increasing row order; returns how many.
    fn expand_layer<const ODD: bool>(
        &mut self,
        free: &impl FreeBits,
        lo: usize,
        hi: usize,
    ) -> usize {
        let layout = self.layout;
        let set = usize::from(ODD) * layout.row_set_words;
        let mut rows = 0;
        for k in lo..=hi.min(layout.row_set_words.saturating_sub(1)) {
            let Some(word) = self.sets.get_mut(set + k) else {
                break;
            };
            let mut word = core::mem::take(word);
            while word != 0 {
                let b = word.trailing_zeros() as usize;
                let y0 = k * 32 + b;
                let mask = self.take_mask::<ODD>(y0);
                let mut y1 = y0;
                if layout.group_shift == 0 && mask.is_power_of_two() {
                    // One word and no frontier cell next to another word: merge the following
                    // rows of the same word into one vertical run.
                    while y1 - k * 32 < 31
                        && word & (2 << (y1 - k * 32)) != 0
                        && self.peek_mask::<ODD>(y1 + 1) == mask
                    {
                        y1 += 1;
                        self.take_mask::<ODD>(y1);
                    }
                    let w = mask.trailing_zeros() as usize;
                    if y1 == y0 {
                        self.single::<ODD>(free, y0, w);
                    } else {
                        self.column::<ODD>(free, y0, y1, w);
                    }
                } else {
                    self.row::<ODD>(free, y0, mask);
                }
                rows += y1 + 1 - y0;
                word &= !(mask_below(y1 - k * 32 + 1) & !mask_below(b));
            }
        }
        rows
    }

    /// Expand the frontier of row `y` in word `w` alone (no frontier cell next to another
    /// word) into the rows below, level and above.
    #[inline(always)]
    fn single<const ODD: bool>(&mut self, free: &impl FreeBits, y: usize, w: usize) {
        let layout = self.layout;
        let rw = layout.row_words;
        let i = layout.node(y, w);
        let s0 = self.p0.get(i).copied().unwrap_or(0);
        let s1 = self.p1.get(i).copied().unwrap_or(0);
        let ms = free.get(y, w, i);
        let f = (s0 ^ self.x0) & (s1 ^ self.x1);
        let same = ((f << 1) | (f >> 1)) & ms & !(s0 | s1);
        if same != 0 {
            self.mark::<ODD>(y, w, i, same);
        }
        // A diagonal step needs the straight step's target free (g) and the side cell in
        // row y (ms at the target column).
        if y > 0 {
            let j = i - rw;
            let m = free.get(y - 1, w, j);
            let g = f & m;
            if g != 0 {
                let r = self.p0.get(j).copied().unwrap_or(0) | self.p1.get(j).copied().unwrap_or(0);
                let n = (g | (ms & ((g << 1) | (g >> 1)))) & m & !r;
                if n != 0 {
                    self.mark::<ODD>(y - 1, w, j, n);
                }
            }
        }
        if y + 1 < layout.height {
            let j = i + rw;
            let m = free.get(y + 1, w, j);
            let g = f & m;
            if g != 0 {
                let r = self.p0.get(j).copied().unwrap_or(0) | self.p1.get(j).copied().unwrap_or(0);
                let n = (g | (ms & ((g << 1) | (g >> 1)))) & m & !r;
                if n != 0 {
                    self.mark::<ODD>(y + 1, w, j, n);
                }
            }
        }
    }

    /// Expand the frontier of rows `y0 ..= y1` in word `w` alone (none of them has frontier
    /// cells next to another word): targets row by row from `y0 - 1` to `y1 + 1`, each from
    /// the three source rows below, level and above, sliding up the column.
    #[inline(always)]
    fn column<const ODD: bool>(&mut self, free: &impl FreeBits, y0: usize, y1: usize, w: usize) {
        let layout = self.layout;
        let rw = layout.row_words;
        let (x0, x1, set0, set1) = (self.x0, self.x1, self.set0, self.set1);
        let shift = layout.group_shift;
        let first = y0.saturating_sub(1);
        let last = (y1 + 1).min(layout.height.saturating_sub(1));
        let mut i = layout.node(first, w);
        let load = |p: &[u32], i: usize| p.get(i).copied().unwrap_or(0);
        let (mut c0, mut c1) = (load(self.p0, i), load(self.p1, i));
        let mut mc = free.get(first, w, i);
        let mut fc = (c0 ^ x0) & (c1 ^ x1);
        // Row below the target: frontier and free bits (none below the first target).
        let (mut fb, mut mb) = (0u32, 0u32);
        let mut pending = 0u64; // rows `first + k` with new cells
        for t in first..=last {
            let j = i + rw;
            let (a0, a1, ma) = if t + 1 < layout.height {
                (load(self.p0, j), load(self.p1, j), free.get(t + 1, w, j))
            } else {
                (0, 0, 0)
            };
            let fa = (a0 ^ x0) & (a1 ^ x1);
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
                if let Some(p) = self.p0.get_mut(i) {
                    *p = c0 | (n & set0);
                }
                if let Some(p) = self.p1.get_mut(i) {
                    *p = c1 | (n & set1);
                }
                note_mask::<ODD>(self.queue, shift, t, w, n);
                pending |= 1 << (t - first);
            }
            (fb, mb, fc, mc, c0, c1) = (fc, mc, fa, ma, a0, a1);
            i = j;
        }
        self.note_rows::<ODD>(first, pending);
    }

    /// Expand the frontier of row `y` in the word groups of `mask`: per run of words, word by
    /// word with the carries between words, into the rows below, level and above.
    fn row<const ODD: bool>(&mut self, free: &impl FreeBits, y: usize, mut groups: u32) {
        let layout = self.layout;
        let rw = layout.row_words;
        let (x0, x1) = (self.x0, self.x1);
        let frontier = |p0: u32, p1: u32| (p0 ^ x0) & (p1 ^ x1);
        let (has_down, has_up) = (y > 0, y + 1 < layout.height);
        // (P0, P1, FREE) of word w of row r; zeros for rows off the map.
        let load = |p0: &[u32], p1: &[u32], r: usize, on_map: bool, w: usize| -> (u32, u32, u32) {
            if !on_map {
                return (0, 0, 0);
            }
            let i = layout.node(r, w);
            (
                p0.get(i).copied().unwrap_or(0),
                p1.get(i).copied().unwrap_or(0),
                free.get(r, w, i),
            )
        };
        let yd = y.wrapping_sub(1);
        while groups != 0 {
            let a = groups.trailing_zeros() as usize;
            let run = (!(groups >> a)).trailing_zeros() as usize; // groups in the run
            groups &= !(mask_below(a + run) & !mask_below(a));
            let first = a << layout.group_shift;
            let last = ((a + run) << layout.group_shift).min(rw).saturating_sub(1);
            if first > last {
                continue;
            }
            let mut d = load(self.p0, self.p1, yd, has_down, first);
            let mut s = load(self.p0, self.p1, y, true, first);
            let mut u = load(self.p0, self.p1, y + 1, has_up, first);
            // Carries from the word before (its bit 31, moved to bit 0).
            let (mut fc, mut gdc, mut guc) = (0u32, 0u32, 0u32);
            for w in first..=last {
                let (dn, sn, un) = if w < last {
                    (
                        load(self.p0, self.p1, yd, has_down, w + 1),
                        load(self.p0, self.p1, y, true, w + 1),
                        load(self.p0, self.p1, y + 1, has_up, w + 1),
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
                    self.mark::<ODD>(yd, w, layout.node(yd, w), down);
                }
                if same != 0 {
                    self.mark::<ODD>(y, w, layout.node(y, w), same);
                }
                if up != 0 {
                    self.mark::<ODD>(y + 1, w, layout.node(y + 1, w), up);
                }
                (fc, gdc, guc) = (f >> 31, gd >> 31, gu >> 31);
                (d, s, u) = (dn, sn, un);
            }
        }
    }

    /// Mark the new cells `n` of word `w` of row `t` (plane index `i`) with the next layer's
    /// code and note them.
    #[inline(always)]
    fn mark<const ODD: bool>(&mut self, t: usize, w: usize, i: usize, n: u32) {
        if let Some(p0) = self.p0.get_mut(i) {
            *p0 |= n & self.set0;
        }
        if let Some(p1) = self.p1.get_mut(i) {
            *p1 |= n & self.set1;
        }
        self.note::<ODD>(t, w, n);
    }

    /// Note new cells `n` of word `w` of row `t` for the next layer: the row in the next row
    /// set, the word (and the neighbour words `n`'s edge cells reach) in its word mask.
    #[inline(always)]
    fn note<const ODD: bool>(&mut self, t: usize, w: usize, n: u32) {
        note_mask::<ODD>(self.queue, self.layout.group_shift, t, w, n);
        let k = usize::from(!ODD) * self.layout.row_set_words + (t >> 5);
        if let Some(word) = self.sets.get_mut(k) {
            *word |= 1 << (t & 31);
        }
        self.next_lo = self.next_lo.min(t >> 5);
        self.next_hi = self.next_hi.max(t >> 5);
    }

    /// Put rows `t + j` for the bits `j` of `rows` (at most 34 bits) into the next layer's row
    /// set.
    #[inline(always)]
    fn note_rows<const ODD: bool>(&mut self, t: usize, rows: u64) {
        if rows == 0 {
            return;
        }
        let k = t >> 5;
        let set = usize::from(!ODD) * self.layout.row_set_words + k;
        let shift = (t & 31) as u32;
        let low = rows << shift; // bits past 64 (shift 31, 34 rows) come from `high`
        let high = if shift == 0 { 0 } else { rows >> (64 - shift) };
        for (j, part) in [low as u32, (low >> 32) as u32, high as u32]
            .into_iter()
            .enumerate()
        {
            if part != 0 {
                if let Some(word) = self.sets.get_mut(set + j) {
                    *word |= part;
                }
                self.next_lo = self.next_lo.min(k + j);
                self.next_hi = self.next_hi.max(k + j);
            }
        }
    }
}

/// The word-mask part of [`Layers::note`]: word `w` of row `t` (and the neighbour words that
/// `n`'s edge cells reach) into the row's mask for the next layer (even when the layer being
/// expanded is `ODD`).
#[inline(always)]
fn note_mask<const ODD: bool>(queue: &mut [OpenEntry], shift: u32, t: usize, w: usize, n: u32) {
    // Past the row's last word a bit only costs an empty pass; before word 0, none.
    let bits = (1u32 << (w >> shift))
        | ((n & 1) << (w.saturating_sub(1) >> shift))
        | (n >> 31).wrapping_shl(((w + 1) >> shift) as u32);
    match queue.get_mut(t) {
        Some(e) if ODD => e.f |= bits,
        Some(e) => e.next |= bits,
        None => {}
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
    let (p0, rest) = scratch.split_at(layout.nodes.min(scratch.len()));
    for (a, b) in p0.iter().zip(rest.iter().take(layout.nodes)) {
        n += (a | b).count_ones();
    }
    n
}
