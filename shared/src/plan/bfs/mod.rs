//! Bit-parallel layered breadth-first search (see `docs/planners.md`,
//! "BFS: layered, bit-parallel"). This file: the scratch layout, the free bits, and the
//! planner's entry points (layered search, the scalar restart in narrow frontiers, the path
//! rebuild); the search state is in `layers.rs`, the per-word kernel in `kernel.rs`.
//!
//! The search works on whole 32-cell words: the layer-`k + 1` cells of a word are found from
//! the layer-`k` cells of the same word and of the rows below and above with a few shifts,
//! ANDs and ORs, instead of one queue entry per cell. Only the rows that hold frontier cells
//! are visited, and in them only the words that do.
//!
//! Scratch layout (rows padded to `row_words = ⌈width / 32⌉` words, `nodes = height ×
//! row_words`, `set_words = ⌈height / 32⌉` rounded up to a power of two); the planes are
//! stored column by column: bit `b` of word `w · height + y` of a plane is cell `(32 w + b,
//! y)` (a word column's rows are consecutive words, which [`Layers::column`] walks as
//! slices):
//!
//! | words                              | content                                           |
//! |------------------------------------|---------------------------------------------------|
//! | `0 .. nodes`                       | `P0`: bit 0 of the cell's layer code              |
//! | `nodes .. 2 nodes`                 | `P1`: bit 1 of the cell's layer code              |
//! | `2 nodes .. 3 nodes`               | `SIDE`: reached from the goal (when it fits)      |
//! | `3 nodes .. 4 nodes`               | `FREE`: the cell is free (when it fits too)       |
//! | then `2 × 2 × 2 row_words × set_words` | per side (start's, goal's) and layer parity:  |
//! |                                    | per word column `w`, the rows with frontier cells |
//! |                                    | in word `w`; then per column the rows with        |
//! |                                    | frontier cells in bit 0 or 31                     |
//! | then `2 × 2 × ⌈2 row_words × set_words / 32⌉` | per side and parity: the non-empty     |
//! |                                    | row-set words                                     |
//!
//! The layer code is 0 for a cell not reached, else `layer mod 3 + 1` (the layer of the side
//! that reached it). The sides alternate, one layer each; a layer stops the search when it
//! reaches a cell of the other side (see `docs/planners.md`, "From both ends", for why that
//! gives the fewest steps). When `FREE` does not fit in the scratch, the free bits are read
//! from the grid's own packed bits instead (a funnel shift per word: slower, same result);
//! when `SIDE` does not fit either (narrow grids, where the padding wastes most), the search
//! runs from the start only, to the goal's layer. The layered search uses no queue entries;
//! the scalar BFS it falls back to in narrow maps ([`NARROW_CHECK_LAYER`]) uses the nibble
//! layout of `codes.rs` and the queue.

use super::codes::{set_nibble, CODE_START, E, N, NE, NW, S, SE, STEPS, SW, W};
use super::layout::{Interior, NIBBLE_WINDOWS};
use super::meet::Meet;
use super::path::PathOut;
use super::planner::{Planner, Search};
use super::{scratch_words_for_cells, PlanError};
use crate::geom::Cell;
use crate::grid::{Grid, GridGeometry};

mod kernel;
mod layers;

use layers::{count_reached, Layers, Outcome, PathBuilder};

/// Where the BFS planes and row sets live in the scratch.
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
    /// Whether the `SIDE` plane fits (else the search runs from the start only).
    two_sided: bool,
    /// Words of one column's row set: `⌈height / 32⌉` rounded up to a power of two,
    /// `1 << set_shift`.
    set_words: usize,
    set_shift: u32,
    /// Words of one layer's summary of non-empty row-set words: `⌈2 row_words × set_words /
    /// 32⌉`.
    summary_words: usize,
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
        let set_words = height.div_ceil(32).next_power_of_two();
        let set_shift = set_words.trailing_zeros();
        let summary_words = (2 * row_words * set_words).div_ceil(32);
        // Two sides, two layer parities each.
        let sets = 4 * (2 * row_words * set_words + summary_words);
        let copy_free = nodes * 4 + sets <= capacity_words;
        let two_sided = nodes * 3 + sets <= capacity_words;
        if nodes * 2 + sets > capacity_words {
            return Err(PlanError::ScratchTooSmall {
                cells: ((nodes * 2 + sets) * 8) as u32,
                capacity: (capacity_words * 8) as u32,
            });
        }
        Ok(Self {
            width,
            height,
            row_words,
            nodes,
            copy_free,
            two_sided,
            set_words,
            set_shift,
            summary_words,
        })
    }

    /// Whether the `FREE` plane is in the scratch (else BFS reads the grid's bits).
    #[cfg(test)]
    pub(super) fn copies_free(&self) -> bool {
        self.copy_free
    }

    /// Whether the `SIDE` plane is in the scratch (else BFS runs from the start only).
    #[cfg(test)]
    pub(super) fn two_sided(&self) -> bool {
        self.two_sided
    }

    /// Index of word `w` of row `y` in a plane.
    #[inline(always)]
    fn node(&self, y: usize, w: usize) -> usize {
        w * self.height + y
    }

    /// Words of one layer's row sets (frontier rows and edge rows of every word column).
    #[inline(always)]
    fn layer_set_words(&self) -> usize {
        2 * self.row_words * self.set_words
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

/// Fill the `FREE` plane from the grid's packed occupancy bits, row by row: word `w` of row
/// `y` is 32 consecutive bits of the grid from bit `y · width + 32 w` (a funnel shift of two
/// grid words, the second one carried to the next word), inverted; columns past the row's
/// end read as occupied. Same result as [`grid_free_word`] for every word, at a few
/// instructions per word.
fn copy_free(free: &mut [u32], words: &[u32], layout: &BfsLayout) {
    let (width, height) = (layout.width, layout.height);
    for y in 0..height {
        let bit = y * width;
        let (first, shift) = (bit >> 5, (bit & 31) as u32);
        let mut lo = words.get(first).copied().unwrap_or(u32::MAX);
        for w in 0..layout.row_words {
            let hi = words.get(first + w + 1).copied().unwrap_or(u32::MAX);
            // `hi << 1 << (31 - shift)` is 0 for shift 0 (no overshift).
            let mut occupied = (lo >> shift) | ((hi << 1) << (31 - shift));
            let valid = width - 32 * w;
            if valid < 32 {
                occupied |= u32::MAX << valid;
            }
            if let Some(word) = free.get_mut(layout.node(y, w)) {
                *word = !occupied;
            }
            lo = hi;
        }
    }
}

/// The free bits of a plane word: from the `FREE` plane, or computed from the grid.
trait FreeBits {
    /// The free bits of word `w` of row `y` (plane index `i`).
    fn get(&self, y: usize, w: usize, i: usize) -> u32;
    /// The free bits of rows `y .. y + n` of word column `w` (plane indices from `i`), in
    /// order (fewer when the planes end early: that cannot happen for a valid layout).
    fn column(&self, y: usize, w: usize, i: usize, n: usize) -> impl Iterator<Item = u32>;
}

/// The `FREE` plane in the scratch.
struct FreePlane<'a>(&'a [u32]);

impl FreeBits for FreePlane<'_> {
    #[inline(always)]
    fn get(&self, _y: usize, _w: usize, i: usize) -> u32 {
        self.0.get(i).copied().unwrap_or(0)
    }

    #[inline(always)]
    fn column(&self, _y: usize, _w: usize, i: usize, n: usize) -> impl Iterator<Item = u32> {
        self.0.get(i..i + n).unwrap_or(&[]).iter().copied()
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

    #[inline(always)]
    fn column(&self, y: usize, w: usize, _i: usize, n: usize) -> impl Iterator<Item = u32> {
        (y..y + n).map(move |y| self.get(y, w, 0))
    }
}

/// Runs of frontier rows of one word column at most this many rows apart are expanded by one
/// [`Layers::column`] call: the rows between cost a window step each, less than the set-up of
/// another call up to about 6 rows (measured on the MCU).
const RUN_JOIN_GAP: usize = 6;

/// The layered search checks after this many layers whether its frontier is narrow: fewer
/// than [`NARROW_PAIRS_PER_LAYER`] (row, word) pairs per layer on average. Then it restarts as
/// the scalar queue BFS, which costs less per cell there (corridors and mazes: 1–3 frontier
/// cells per layer, thousands of layers).
pub(super) const NARROW_CHECK_LAYER: u32 = 48;
/// See [`NARROW_CHECK_LAYER`].
pub(super) const NARROW_PAIRS_PER_LAYER: usize = 8;

impl<const SCRATCH_WORDS: usize, const QUEUE: usize> Planner<SCRATCH_WORDS, QUEUE> {
    /// BFS from both `start` and `goal` (`start != goal`, both free and on the map) until the
    /// two searches meet: the layered bit-parallel search, or, when its frontier turns out
    /// narrow after [`NARROW_CHECK_LAYER`] layers, the one-sided scalar queue BFS from the start
    /// again. Returns the search and, for the layered one when found, where the two sides met
    /// (rebuild the path with [`Planner::bfs_rebuild`]); `None` with a found search: the scalar
    /// one ran, its path is in the nibbles (rebuild it with `rebuild_merged`).
    ///
    /// `Search::cost` is 0 (the rebuilds count the steps). Layered: `expanded` is the number of
    /// cells reached by either side; scalar: the cells taken off the queue.
    pub(super) fn bfs<const GW: usize>(
        &mut self,
        grid: &Grid<GW>,
        start: Cell,
        goal: Cell,
    ) -> Result<(Search, Option<Meet>), PlanError> {
        let layout = BfsLayout::new(grid.geometry(), SCRATCH_WORDS)?;
        let grid_words = grid.words();
        // `BfsLayout::new` checked that the planes, row sets and summaries fit in the scratch,
        // so these splits are within it (the checked variants cost 7 % more instructions on
        // the MCU: they change how the expansion is compiled).
        let (p0, rest) = self.scratch.split_at_mut(layout.nodes);
        let (p1, rest) = rest.split_at_mut(layout.nodes);
        let (ps, rest) = rest.split_at_mut(if layout.two_sided { layout.nodes } else { 0 });
        let (free, sets) = if layout.copy_free {
            rest.split_at_mut(layout.nodes)
        } else {
            rest.split_at_mut(0)
        };
        let (sets, rest) = sets.split_at_mut(2 * layout.layer_set_words());
        let (other_sets, summary) = rest.split_at_mut(2 * layout.layer_set_words());
        let (summary, other_summary) = summary.split_at_mut(2 * layout.summary_words);
        let other_summary = other_summary
            .get_mut(..2 * layout.summary_words)
            .unwrap_or(&mut []);
        p0.fill(0);
        p1.fill(0);
        ps.fill(0);
        if layout.copy_free {
            copy_free(free, grid_words, &layout);
        }
        let mut layers = Layers {
            p0,
            p1,
            ps,
            sets,
            summary,
            other_sets,
            other_summary,
            layout,
            peak: 0,
            layer: 0,
            other_layer: 0,
            goal_side: false,
            x0: 0,
            x1: 0,
            set0: 0,
            set1: 0,
            meet: None,
        };
        let found = if layout.copy_free {
            layers.run(&FreePlane(free), start, goal)
        } else {
            let bits = GridBits {
                words: grid_words,
                width: layout.width,
                height: layout.height,
            };
            layers.run(&bits, start, goal)
        };
        self.queue_peak = layers.peak as u32;
        let meet = match found {
            Outcome::Met(meet) => Some(meet),
            Outcome::Unreachable => None,
            Outcome::Narrow => {
                self.copy_map(grid);
                let geometry = grid.geometry();
                let search = self.bfs_scalar(grid, geometry.index(start), geometry.index(goal))?;
                return Ok((search, None));
            }
        };
        let expanded = count_reached(&self.scratch, &layout);
        Ok((
            Search {
                found: meet.is_some(),
                expanded,
                cost: 0,
            },
            meet,
        ))
    }

    /// Breadth-first search from `start` until `goal` is discovered, cell by cell with a FIFO
    /// queue on the nibble copy of the map ([`Planner::copy_map`]): the narrow-frontier
    /// variant (see [`NARROW_CHECK_LAYER`]).
    ///
    /// Hot loop: a popped cell's 3 × 3 neighbourhood is read as three 12-bit windows (three
    /// nibbles of a row, from one pair of scratch words), so the side cells read for the side
    /// moves also decide the diagonal moves. [`NIBBLE_WINDOWS`] and a few operations turn the
    /// windows into a mask of the targets (nibble 0, and for a diagonal both side cells not
    /// [`BLOCKED`](crate::plan::codes::BLOCKED)), tested in the fixed order E, N, W, S, NE, NW, SW, SE with constant index
    /// offsets. Cells on the map border take a slower path that reads off-map cells as
    /// `BLOCKED` (and divides for y). Queue entries carry the index and x, so interior cells
    /// never divide; a new cell's nibble is 0, so marking it is a single OR.
    fn bfs_scalar<const GW: usize>(
        &mut self,
        grid: &Grid<GW>,
        start: usize,
        goal: usize,
    ) -> Result<Search, PlanError> {
        let geometry = grid.geometry();
        let width = geometry.width() as usize;
        let used_words = scratch_words_for_cells(geometry.cell_count());
        let scratch = self.scratch.get_mut(..used_words).unwrap_or(&mut []);
        let queue = &mut self.queue[..];
        let capacity = queue.len();
        let full = PlanError::QueueFull {
            capacity: capacity as u32,
        };
        // Entries ever pushed / popped: the ring slot is the count modulo the capacity (a
        // constant), the fill is their difference, and `popped` is the number expanded. Two
        // counters instead of head, tail, fill and expanded keep the loop in registers.
        let slot_of = |n: usize| n.checked_rem(capacity).unwrap_or(0);
        let (mut pushed, mut popped) = (0usize, 0usize);
        let mut peak = 1usize;

        let interior = Interior::new(geometry);

        set_nibble(scratch, start, CODE_START);
        match queue.get_mut(0) {
            Some(slot) => {
                slot.node = start as u32;
                slot.f = (start % width) as u32;
            }
            None => return Err(full),
        }
        pushed += 1;

        while popped != pushed {
            let (index, x) = match queue.get(slot_of(popped)) {
                Some(e) => (e.node as usize, e.f as usize),
                None => break,
            };
            popped += 1;

            let (above, cur, below) = interior.neighbourhood(scratch, index, x, || index / width);
            // Per row: bit `col` of the targets when that cell is 0 (free, not reached); a
            // diagonal also needs the side cell of its row (the middle one) and the side cell
            // of its column in the current row open.
            let m_cur = u32::from(NIBBLE_WINDOWS[(cur & 0xFFF) as usize]);
            let open_cur = (m_cur >> 3) & 5;
            let row_targets = |m: u32| m & (2 | (open_cur & ((m >> 4) & 1).wrapping_neg()));
            let targets = row_targets(u32::from(NIBBLE_WINDOWS[(below & 0xFFF) as usize]))
                | (m_cur & 5) << 3
                | row_targets(u32::from(NIBBLE_WINDOWS[(above & 0xFFF) as usize])) << 6;
            if targets == 0 {
                continue;
            }

            macro_rules! visit {
                ($bit:expr, $n:expr, $nx:expr, $code:expr) => {{
                    if targets & (1 << $bit) != 0 {
                        // Reached for the first time (nibble 0): mark with the step, queue it.
                        let n = $n;
                        if let Some(w) = scratch.get_mut(n >> 3) {
                            *w |= $code << ((n & 7) * 4);
                        }
                        if n == goal {
                            self.queue_peak = peak.max(pushed - popped) as u32;
                            return Ok(Search {
                                found: true,
                                expanded: popped as u32,
                                cost: 0,
                            });
                        }
                        if pushed - popped == capacity {
                            self.queue_peak = capacity as u32;
                            return Err(full);
                        }
                        if let Some(slot) = queue.get_mut(slot_of(pushed)) {
                            slot.node = n as u32;
                            slot.f = $nx as u32;
                        }
                        pushed += 1;
                    }
                }};
            }
            // Bit `row * 3 + col` (rows below, same, above; columns x - 1, x, x + 1), in the
            // order E, N, W, S, NE, NW, SW, SE. Target cells are on the map, so no wrapping.
            visit!(5, index + 1, x + 1, E);
            visit!(7, index + width, x, N);
            visit!(3, index - 1, x - 1, W);
            visit!(1, index - width, x, S);
            visit!(8, index + width + 1, x + 1, NE);
            visit!(6, index + width - 1, x - 1, NW);
            visit!(0, index - width - 1, x - 1, SW);
            visit!(2, index - width + 1, x + 1, SE);
            peak = peak.max(pushed - popped);
        }
        self.queue_peak = peak as u32;
        Ok(Search {
            found: false,
            expanded: popped as u32,
            cost: 0,
        })
    }

    /// Rebuild the path of a layered search that met at `meet`: from the start side's cell of
    /// the meeting move back to the start, and from the goal side's cell on to the goal, each
    /// step to a neighbour of the same side one layer lower that a legal move joins, preferring
    /// the previous step's direction, then E, N, W, S, NE, NW, SW, SE. Collinear cells are
    /// merged. Returns the length in cells, the steps and whether every vertex fitted.
    pub(super) fn bfs_rebuild<const GW: usize>(
        &mut self,
        grid: &Grid<GW>,
        goal: Cell,
        meet: Meet,
        count_only: bool,
    ) -> (f32, u32, bool) {
        if !count_only {
            self.cells.clear();
        }
        let layout = match BfsLayout::new(grid.geometry(), SCRATCH_WORDS) {
            Ok(layout) => layout,
            Err(_) => return (0.0, 0, false),
        };
        let scratch = &self.scratch[..];
        // (layer code, reached from the goal side) of a cell; code 0 off the map.
        let cell = |x: i32, y: i32| -> (u32, bool) {
            if x < 0 || y < 0 || x as usize >= layout.width || y as usize >= layout.height {
                return (0, false);
            }
            let (x, y) = (x as usize, y as usize);
            let i = layout.node(y, x >> 5);
            let bit = |plane: usize| {
                scratch.get(plane * layout.nodes + i).copied().unwrap_or(0) >> (x & 31) & 1
            };
            (bit(0) | bit(1) << 1, layout.two_sided && bit(2) != 0)
        };
        let free = |x: i32, y: i32| grid.geometry().contains_xy(x, y) && !grid.is_occupied_xy(x, y);
        // A legal move from (x, y) by (dx, dy) to a cell of `side` with `code`.
        let legal = |x: i32, y: i32, (dx, dy): (i32, i32), code: u32, side: bool| {
            let (px, py) = (x + dx, y + dy);
            cell(px, py) == (code, side) && (dx == 0 || dy == 0 || (free(x, py) && free(px, y)))
        };
        let code_of = |layer: u32| layer % 3 + 1;
        // Walk down the layers of `side` from `path.at` (layer `layer`) to its layer 0.
        let walk = |path: &mut PathBuilder, layer: u32, side: bool| {
            for layer in (1..=layer).rev() {
                let want = code_of(layer - 1);
                let (x, y) = path.at;
                let step = match path.dir {
                    Some(d) if legal(x, y, d, want, side) => Some(d),
                    _ => STEPS.iter().copied().find(|&d| legal(x, y, d, want, side)),
                };
                let Some(d) = step else {
                    break; // cannot happen with a consistent layering; the guard ends the walk
                };
                path.push(d);
            }
        };
        // The start side's cell `u` of the meeting move and its layer, and the goal side's `v`.
        let ((ux, uy, u_layer), v) = if meet.one_sided {
            ((goal.x as i32, goal.y as i32, meet.layer), None)
        } else {
            // A meeting cell `m` of the other side (of its last layer, or the one before) in
            // the rows and word noted, and the frontier cell `f` of the expanding side that
            // reaches it.
            let m_side = !meet.goal_side;
            let f_code = code_of(meet.layer);
            let mut found = None;
            'rows: for y in meet.rows.0..=meet.rows.1 {
                for b in 0..32 {
                    let (mx, my) = ((32 * meet.word + b) as i32, y as i32);
                    let m_layer = match cell(mx, my) {
                        (c, side) if side == m_side && c == code_of(meet.other_layer) => {
                            meet.other_layer
                        }
                        (c, side)
                            if side == m_side
                                && meet.other_layer > 0
                                && c == code_of(meet.other_layer - 1) =>
                        {
                            meet.other_layer - 1
                        }
                        _ => continue,
                    };
                    if let Some(&(dx, dy)) = STEPS
                        .iter()
                        .find(|&&d| legal(mx, my, d, f_code, meet.goal_side))
                    {
                        found = Some((mx, my, m_layer, mx + dx, my + dy));
                        break 'rows;
                    }
                }
            }
            let Some((mx, my, m_layer, fx, fy)) = found else {
                return (0.0, 0, false);
            };
            if meet.goal_side {
                ((mx, my, m_layer), Some((fx, fy, meet.layer)))
            } else {
                ((fx, fy, meet.layer), Some((mx, my, m_layer)))
            }
        };
        let mut path = PathBuilder {
            cells: &mut self.cells,
            out: PathOut::new(count_only),
            at: (ux, uy),
            dir: None,
            first_dir: None,
            fits: true,
            straight: 0,
            diagonal: 0,
        };
        path.fits &= path.out.push(path.cells, Cell::new(ux as u16, uy as u16));
        // Start side: from u back to the start, then turned round.
        walk(&mut path, u_layer, false);
        path.out.reverse(path.cells);
        path.dir = path.first_dir.map(|(dx, dy)| (-dx, -dy));
        path.at = (ux, uy);
        if let Some((vx, vy, v_layer)) = v {
            // The meeting move, then the goal side from v down to the goal.
            path.push((vx - ux, vy - uy));
            walk(&mut path, v_layer, true);
        }
        let length = path.straight as f32 + path.diagonal as f32 * core::f32::consts::SQRT_2;
        (length, path.straight + path.diagonal, path.fits)
    }
}

#[cfg(test)]
mod copy_tests {
    extern crate std;
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The row-streaming copy of the free bits gives what `grid_free_word` gives for every
        /// word (widths not a multiple of 32, one-word rows, the grid's last word).
        #[test]
        fn copy_free_equals_word_by_word(
            width in 1usize..=100,
            height in 1usize..=9,
            seed in any::<u64>(),
        ) {
            let geometry = GridGeometry::new(width as u32, height as u32, 0.05).unwrap();
            let layout = BfsLayout::new(&geometry, 4096).unwrap();
            let mut state = seed | 1;
            let words: std::vec::Vec<u32> = (0..(width * height).div_ceil(32))
                .map(|_| {
                    state ^= state << 13;
                    state ^= state >> 7;
                    state ^= state << 17;
                    state as u32
                })
                .collect();
            let mut free = std::vec![0xDEAD_BEEF_u32; layout.nodes];
            copy_free(&mut free, &words, &layout);
            for y in 0..height {
                for w in 0..layout.row_words {
                    prop_assert_eq!(
                        free[layout.node(y, w)],
                        grid_free_word(&words, width, y, w),
                        "row {} word {}", y, w
                    );
                }
            }
        }
    }
}
