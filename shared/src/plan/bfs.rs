//! Bit-parallel layered breadth-first search (see the module doc of [`super`], "BFS").
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
//! reaches a cell of the other side (see the module doc of [`super`] for why that gives the
//! fewest steps). When `FREE` does not fit in the scratch, the free bits are read from the
//! grid's own packed bits instead (a funnel shift per word: slower, same result); when `SIDE`
//! does not fit either (narrow grids, where the padding wastes most), the search runs from the
//! start only, to the goal's layer. The layered search uses no queue entries; the scalar BFS
//! it falls back to in narrow maps ([`NARROW_CHECK_LAYER`]) uses the nibble layout of
//! [`super`] and the queue.

use super::{
    scratch_words_for_cells, set_nibble, PathCells, PathOut, PlanError, Planner, Search,
    CODE_START, E, N, NE, NIBBLE_WINDOWS, NW, S, SE, STEPS, SW, W,
};
use crate::geom::Cell;
use crate::grid::{Grid, GridGeometry};

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
    /// [`BLOCKED`]), tested in the fixed order E, N, W, S, NE, NW, SW, SE with constant index
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

        let interior = super::Interior::new(geometry);

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

/// Where the two sides of a layered search met: rows `rows.0 ..= rows.1` of word `word` hold
/// a cell of the other side that is a legal move away from a cell of the side that was
/// expanding its layer `layer`. One-sided: the goal's row and word.
#[derive(Clone, Copy, Debug)]
pub(super) struct Meet {
    rows: (usize, usize),
    word: usize,
    /// The expanding side was the goal's.
    goal_side: bool,
    /// The expanding side's frontier layer.
    layer: u32,
    /// The other side's last layer.
    other_layer: u32,
    /// The search ran from the start only (no `SIDE` plane): `layer` is the goal's layer.
    one_sided: bool,
}

/// A merged polyline built move by move: a move in the previous move's direction moves the
/// last vertex, any other adds one.
struct PathBuilder<'c> {
    cells: &'c mut PathCells,
    /// Writes to `cells`, or only counts.
    out: PathOut,
    at: (i32, i32),
    dir: Option<(i32, i32)>,
    /// Direction of the first move.
    first_dir: Option<(i32, i32)>,
    fits: bool,
    straight: u32,
    diagonal: u32,
}

impl PathBuilder<'_> {
    fn push(&mut self, (dx, dy): (i32, i32)) {
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
    w0: usize,
    w1: usize,
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
enum Outcome {
    /// The two sides met.
    Met(Meet),
    Unreachable,
    /// The frontier is narrow: better searched cell by cell.
    Narrow,
}

/// The state of one layered search from both ends: the planes, the row sets and their
/// summaries. The fields name the side being expanded and the other one; switching sides swaps
/// them.
struct Layers<'a> {
    p0: &'a mut [u32],
    p1: &'a mut [u32],
    /// `SIDE`: the cell was reached from the goal.
    ps: &'a mut [u32],
    /// Per layer parity (even, odd), per word column `w`, a bit set of the rows whose word `w`
    /// holds frontier cells (word `k` of column `w` at `parity · 2 row_words · set_words +
    /// w · set_words + k`), then per word column `w` (as column `row_words + w`) the rows
    /// whose word `w` holds frontier cells in bit 0 or 31 (next to another word).
    sets: &'a mut [u32],
    /// Per layer parity, bit `w · set_words + k` set when that row-set word is not empty.
    summary: &'a mut [u32],
    /// The other side's row sets and summaries.
    other_sets: &'a mut [u32],
    other_summary: &'a mut [u32],
    layout: BfsLayout,
    /// Most frontier (row, word) pairs in one layer.
    peak: usize,
    /// Layer being expanded (of the side being expanded).
    layer: u32,
    /// The other side's last layer.
    other_layer: u32,
    /// The side being expanded is the goal's.
    goal_side: bool,
    /// Frontier = `(P0 ^ x0) & (P1 ^ x1) & (SIDE ^ xs)`; new cells: `P0 |= n & set0`,
    /// `P1 |= n & set1`, `SIDE |= n & sset`. Cells of the other side: `(P0 | P1) & !(SIDE ^
    /// xs)`.
    x0: u32,
    x1: u32,
    set0: u32,
    set1: u32,
    /// A meeting found in this layer: rows `y0 ..= y1` of word `w` hold a cell of the other
    /// side that a frontier cell reaches.
    meet: Option<(usize, usize, usize)>,
}

impl Layers<'_> {
    /// The `SIDE` word of node `i`; 0 when the sides are [`APART`].
    #[inline(always)]
    fn side_word<const SIDE: u8>(&self, i: usize) -> u32 {
        if SIDE == APART {
            0
        } else {
            self.ps.get(i).copied().unwrap_or(0)
        }
    }

    /// Mark `cell` as layer 0 of the side being expanded and note it as if found by layer -1
    /// (odd).
    fn seed(&mut self, cell: Cell) {
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
    fn run(&mut self, free: &impl FreeBits, start: Cell, goal: Cell) -> Outcome {
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

    /// The edge bits of word `w`: bit 0 when a word lies before it, bit 31 when one follows.
    #[inline(always)]
    fn edges(&self, w: usize) -> u32 {
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
    fn single<const ODD: bool, const SIDE: u8>(
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
    // fewer MCU instructions).
    #[inline(never)]
    #[allow(unused_assignments)] // the window's last shift is not read
    fn column<const ODD: bool, const SIDE: u8, const PHASE: u32>(
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
    fn edge_before<const ODD: bool, const SIDE: u8>(
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
    fn edge_after<const ODD: bool, const SIDE: u8>(
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
    fn mark<const ODD: bool, const SIDE: u8>(&mut self, t: usize, w: usize, i: usize, n: u32) {
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
    fn note_rows<const ODD: bool, const SIDE: u8>(&mut self, w: usize, t: usize, rows: u32) {
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
const GOAL_SIDE: u8 = 1;
/// See [`START_SIDE`].
const APART: u8 = 2;

/// `(xs, sset)` for expanding a layer of side `SIDE`: the side's cells are `SIDE ^ xs`, new
/// cells get `SIDE |= n & sset` (apart: the `SIDE` word reads as 0, so every reached cell is
/// the side's own and none is the other's).
#[inline(always)]
const fn side_masks<const SIDE: u8>() -> (u32, u32) {
    if SIDE == GOAL_SIDE {
        (0, u32::MAX)
    } else {
        (u32::MAX, 0)
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
