//! Jump point search (JPS) without corner cutting, for A* (octile costs) and for BFS on
//! uncluttered maps (unit costs, `jump_points::<UNIT>`): A* over jump points only, each reached
//! by a side or 45° scan ([`JumpScan`], on the grid's packed bits: 32 cells per step along a
//! row, diagonal runs scan their columns together). Closed jump points take *records* from the
//! back of the queue, whose chain gives the path exactly. Before searching, [`cluttered`](super::choice::cluttered)
//! counts obstacle runs in a sample of the grid's words: cluttered maps go cell by cell at once,
//! and a search that finds too many jump points gives up ([`JPS_MAX_EXPANSIONS_PER_CELLS`],
//! [`JPS_STEPS_MAX_EXPANSIONS`](super::choice::JPS_STEPS_MAX_EXPANSIONS)). Measured effect (`cargo xtask mcu-bench` and `twil plan
//! --remote qemu --json` on the bundled worlds): a room-map plan takes 0.9–2.9 M Cortex-M4
//! instructions for 9–22 jump points (A*), 0.76–1.76 M for 8–15 (BFS); see docs/planners.md,
//! "A\*: jump point search", and docs/planners-history.md, "BFS by jump points".

use super::codes::{
    nibble, octile, set_nibble, step_code, Dir, CODE_START, E, N, NE, NW, S, SE, STEPS, SW, W,
};
use super::heap::{heap_sift_down, heap_sift_up};
use super::open_list::{OpenEntry, NIL};
use super::planner::{Planner, Search};
use super::{DIAGONAL_COST, STRAIGHT_COST};
use crate::geom::Cell;
use crate::grid::Grid;

/// The jump scans of [`Planner::jps`], on the grid's packed occupancy bits (1 = occupied):
/// side scans along a row test 32 cells per step with a few word operations; scans along a
/// column read 3 bits per row. Cells off the map count as occupied.
struct JumpScan<'a> {
    pub(super) words: &'a [u32],
    pub(super) width: i32,
    pub(super) height: i32,
    goal_x: i32,
    goal_y: i32,
}

impl JumpScan<'_> {
    /// Occupancy of the 32 cells `c0 .. c0 + 32` of row `y` (bit k = column `c0 + k`), cells off
    /// the map set.
    #[inline(always)]
    fn row_bits(&self, y: i32, c0: i32) -> u32 {
        if (y as u32) >= self.height as u32 || c0 >= self.width || c0 <= -32 {
            return u32::MAX;
        }
        let from = c0.max(0);
        let i = (y * self.width + from) as usize;
        let lo = self.words.get(i >> 5).copied().unwrap_or(u32::MAX) as u64;
        let hi = self.words.get((i >> 5) + 1).copied().unwrap_or(u32::MAX) as u64;
        let mut bits = ((lo | (hi << 32)) >> (i & 31)) as u32;
        let valid = self.width - from; // columns of the row from `from` on
        if valid < 32 {
            bits |= u32::MAX << valid;
        }
        if c0 < 0 {
            let s = (-c0) as u32;
            bits = (bits << s) | ((1u32 << s) - 1);
        }
        bits
    }

    #[inline(always)]
    pub(super) fn free(&self, x: i32, y: i32) -> bool {
        (x as u32) < self.width as u32
            && (y as u32) < self.height as u32
            && self.row_bits(y, x) & 1 == 0
    }

    /// Scan from `(x, y)` in the side direction `(dx, dy)` (one of them 0). Returns the first
    /// jump point `(x, y, steps)`: the goal, or a cell with a forced neighbour (a side cell
    /// that is free while the cell behind it, next to the previous cell of the scan, is
    /// occupied). `None` when the scan runs into an obstacle or off the map first.
    #[inline]
    pub(super) fn straight(&self, x: i32, y: i32, dx: i32, dy: i32) -> Option<(i32, i32, u32)> {
        if dy == 0 {
            self.along_row(x, y, dx)
        } else {
            self.along_column(x, y, dy)
        }
    }

    fn along_row(&self, x: i32, y: i32, dx: i32) -> Option<(i32, i32, u32)> {
        let goal_in_row = self.goal_y == y;
        // The cells behind each side cell (one column back) come from shifting the side rows'
        // words, with the bit carried over from the previous word.
        let mut up_carry = self.row_bits(y + 1, x) & 1;
        let mut down_carry = self.row_bits(y - 1, x) & 1;
        if dx > 0 {
            let mut c0 = x + 1;
            loop {
                let cur = self.row_bits(y, c0);
                let up = self.row_bits(y + 1, c0);
                let down = self.row_bits(y - 1, c0);
                let up_back = (up << 1) | up_carry;
                let down_back = (down << 1) | down_carry;
                let mut hit = (!up & up_back) | (!down & down_back);
                if goal_in_row && self.goal_x >= c0 && self.goal_x < c0 + 32 {
                    hit |= 1 << (self.goal_x - c0);
                }
                if cur | hit != 0 {
                    let stop = cur.trailing_zeros();
                    let jump = hit.trailing_zeros();
                    if jump < stop {
                        let jx = c0 + jump as i32;
                        return Some((jx, y, (jx - x) as u32));
                    }
                    return None;
                }
                up_carry = up >> 31;
                down_carry = down >> 31;
                c0 += 32;
            }
        } else {
            // Columns c0 .. c0 + 32 with the scan going down from c0 + 31.
            let mut c0 = x - 32;
            loop {
                let cur = self.row_bits(y, c0);
                let up = self.row_bits(y + 1, c0);
                let down = self.row_bits(y - 1, c0);
                let up_back = (up >> 1) | (up_carry << 31);
                let down_back = (down >> 1) | (down_carry << 31);
                let mut hit = (!up & up_back) | (!down & down_back);
                if goal_in_row && self.goal_x >= c0 && self.goal_x < c0 + 32 {
                    hit |= 1 << (self.goal_x - c0);
                }
                if cur | hit != 0 {
                    let stop = cur.leading_zeros();
                    let jump = hit.leading_zeros();
                    if jump < stop {
                        let jx = c0 + 31 - jump as i32;
                        return Some((jx, y, (x - jx) as u32));
                    }
                    return None;
                }
                up_carry = up & 1;
                down_carry = down & 1;
                c0 -= 32;
            }
        }
    }

    /// Occupancy of cells `j - 1`, `j`, `j + 1` (bits 0, 1, 2) of the row-major bit array.
    /// `j ≥ 1`; words past the end read as occupied.
    #[inline(always)]
    fn three_bits(&self, j: usize) -> u32 {
        let i = j - 1;
        let lo = self.words.get(i >> 5).copied().unwrap_or(u32::MAX) as u64;
        let hi = self.words.get((i >> 5) + 1).copied().unwrap_or(u32::MAX) as u64;
        (((lo | (hi << 32)) >> (i & 31)) as u32) & 7
    }

    fn along_column(&self, x: i32, mut y: i32, dy: i32) -> Option<(i32, i32, u32)> {
        // Bits 0, 1, 2 = columns x - 1, x, x + 1; columns off the map read as occupied.
        let width = self.width as usize;
        let edge = u32::from(x == 0) | (u32::from(x == self.width - 1) << 2);
        // In column 0, read from index j (not j - 1) and shift: column -1 is `edge`.
        let read = |j: usize| -> u32 {
            if x == 0 {
                ((self.three_bits(j + 1) << 1) & 7) | edge
            } else {
                self.three_bits(j) | edge
            }
        };
        let mut j = (y * self.width + x) as usize;
        let mut behind = read(j);
        let mut steps = 0u32;
        loop {
            y += dy;
            if (y as u32) >= self.height as u32 {
                return None;
            }
            j = if dy > 0 { j + width } else { j - width };
            let here = read(j);
            if here & 2 != 0 {
                return None;
            }
            steps += 1;
            if (!here & behind) & 5 != 0 || (x == self.goal_x && y == self.goal_y) {
                return Some((x, y, steps));
            }
            behind = here;
        }
    }

    /// Scan from `(x, y)` in the diagonal direction `(dx, dy)`, each step only between two
    /// free side cells (no corner cutting). Returns the first diagonal cell that is the goal or
    /// from which a side scan along `dx` or `dy` finds a jump point; `None` when blocked first.
    ///
    /// The row scans run step by step (32 cells per word operation); the column scans of all
    /// steps are run together, row by row over a bit set of the columns still scanning
    /// ([`JumpScan::diagonal_columns`]), so an open floor costs a few word operations per row
    /// instead of one read per cell.
    #[inline]
    pub(super) fn diagonal(&self, x: i32, y: i32, dx: i32, dy: i32) -> Option<(i32, i32, u32)> {
        let (mut cx, mut cy) = (x, y);
        let mut steps = 0u32;
        let mut row_hit = None;
        while self.free(cx + dx, cy) && self.free(cx, cy + dy) && self.free(cx + dx, cy + dy) {
            cx += dx;
            cy += dy;
            steps += 1;
            if (cx == self.goal_x && cy == self.goal_y) || self.along_row(cx, cy, dx).is_some() {
                row_hit = Some(steps);
                break;
            }
        }
        let last = match row_hit {
            Some(i) => i - 1,
            None => steps,
        };
        let i = self.diagonal_columns(x, y, dx, dy, last).or(row_hit)?;
        Some((x + dx * i as i32, y + dy * i as i32, i))
    }

    /// The smallest step `i` in `1..=last` of the diagonal from `(x, y)` whose column scan
    /// (from `(x + dx·i, y + dy·i)` along `dy`) finds a jump point; all diagonal cells up to
    /// `last` are free. About 130 lines, not split: one pass over the columns' words whose
    /// masks stay in registers (a split is not measured).
    fn diagonal_columns(&self, x: i32, y: i32, dx: i32, dy: i32, last: u32) -> Option<u32> {
        // Up to 512 columns (the 300 and 400 cell grids); wider grids scan column by column.
        const MAX_WORDS: usize = 16;
        if last == 0 {
            return None;
        }
        if (self.width as usize).div_ceil(32) > MAX_WORDS {
            return (1..=last).find(|&i| {
                self.along_column(x + dx * i as i32, y + dy * i as i32, dy)
                    .is_some()
            });
        }
        let mut alive = [0u32; MAX_WORDS];
        // Occupancy words of the current row and the row behind it, at index `word + 1` (so
        // the words just outside the columns in play fit), valid over `cached`.
        let mut rows = [[u32::MAX; MAX_WORDS + 2]; 2];
        let mut cached: Option<(i32, i32)> = None;
        let mut best = last + 1; // steps at or beyond `best` no longer matter
        let mut any_alive = false;
        let mut k = 1u32;
        loop {
            let row = y + dy * k as i32;
            if any_alive {
                if (row as u32) >= self.height as u32 {
                    break;
                }
                let behind = row - dy;
                // Columns of the steps joined so far: 1 ..= min(k - 1, last).
                let span = (k - 1).min(last) as i32;
                let (lo, hi) = if dx > 0 {
                    (x + 1, x + span)
                } else {
                    (x - span, x - 1)
                };
                let (wlo, whi) = ((lo >> 5) - 1, (hi >> 5) + 1);
                let (cur_rows, behind_rows) = rows.split_at_mut(1);
                let (cur, back) = (&mut cur_rows[0], &mut behind_rows[0]);
                // `back` holds the previous row over `cached`; fill the rest of the range.
                for w in wlo..=whi {
                    let fresh = match cached {
                        Some((a, b)) => w < a || w > b,
                        None => true,
                    };
                    if fresh {
                        if let Some(slot) = back.get_mut((w + 1) as usize) {
                            *slot = self.row_bits(behind, w * 32);
                        }
                    }
                    if let Some(slot) = cur.get_mut((w + 1) as usize) {
                        *slot = self.row_bits(row, w * 32);
                    }
                }
                let at = |v: &[u32; MAX_WORDS + 2], w: i32| -> u32 {
                    v.get((w + 1) as usize).copied().unwrap_or(u32::MAX)
                };
                let mut any = false;
                let mut hit_step = None::<u32>;
                for w in wlo + 1..whi {
                    let Some(a) = alive.get_mut(w as usize) else {
                        break;
                    };
                    if *a == 0 {
                        continue;
                    }
                    let c0 = w * 32;
                    let (c_prev, c_here, c_next) = (at(cur, w - 1), at(cur, w), at(cur, w + 1));
                    let (b_prev, b_here, b_next) = (at(back, w - 1), at(back, w), at(back, w + 1));
                    *a &= !c_here;
                    let right_c = (c_here >> 1) | (c_next << 31);
                    let right_b = (b_here >> 1) | (b_next << 31);
                    let left_c = (c_here << 1) | (c_prev >> 31);
                    let left_b = (b_here << 1) | (b_prev >> 31);
                    let mut hit = *a & ((!right_c & right_b) | (!left_c & left_b));
                    if row == self.goal_y && self.goal_x >= c0 && self.goal_x < c0 + 32 {
                        hit |= *a & (1 << (self.goal_x - c0));
                    }
                    if hit != 0 {
                        // The step nearest the start among this word's hits.
                        let c = if dx > 0 {
                            c0 + hit.trailing_zeros() as i32
                        } else {
                            c0 + 31 - hit.leading_zeros() as i32
                        };
                        let i = ((c - x) * dx) as u32;
                        hit_step = Some(hit_step.map_or(i, |h| h.min(i)));
                    }
                    any |= *a != 0;
                }
                rows.swap(0, 1);
                cached = Some((wlo, whi));
                if let Some(i) = hit_step {
                    best = best.min(i);
                    // Drop the columns of steps at or beyond `best`.
                    any = false;
                    for w in (lo >> 5) as usize..=(hi >> 5) as usize {
                        let Some(a) = alive.get_mut(w) else {
                            break;
                        };
                        let c0 = (w * 32) as i32;
                        for bit in 0..32 {
                            let i = (c0 + bit - x) * dx;
                            if i >= best as i32 {
                                *a &= !(1u32 << bit);
                            }
                        }
                        any |= *a != 0;
                    }
                }
                any_alive = any;
            } else {
                cached = None; // rows were skipped: the cached row is not the one behind
            }
            // The column of step k starts scanning from its diagonal cell.
            if k <= last && k < best {
                let c = x + dx * k as i32;
                if let Some(a) = alive.get_mut((c >> 5) as usize) {
                    *a |= 1 << (c & 31);
                    any_alive = true;
                }
            } else if !any_alive {
                break;
            }
            k += 1;
        }
        (best <= last).then_some(best)
    }
}

/// Jump point search gives up (and A* runs cell by cell) when more than one cell in this many
/// (at least 256 cells) became a jump point: on cluttered maps such as 20 % random obstacles
/// nearly every free cell is one, and scanning costs more than the cell-by-cell search ...
const JPS_MAX_EXPANSIONS_PER_CELLS: usize = 256;
/// ... but only while the open list holds more than one entry per this many jump points
/// expanded (a wide frontier: 269 open entries after 1 024 jump points on 20 % random
/// obstacles, 2 in a maze of 1-cell corridors, where jump point search stays 3x ahead).
const JPS_WIDE_FRONTIER: usize = 16;

/// Unit-cost jump point search ([`Planner::jps_steps`]): the heap key is
/// `f << UNIT_KEY_SHIFT | h`.
const UNIT_KEY_SHIFT: u32 = 12;
/// The heuristic's bits in a unit-cost key (at most 4 095 on grids of at most 4 096 a side).
const UNIT_H_MASK: u32 = (1 << UNIT_KEY_SHIFT) - 1;
/// The largest `f` a unit-cost key holds.
const UNIT_MAX_F: u32 = u32::MAX >> UNIT_KEY_SHIFT;

impl<const SCRATCH_WORDS: usize, const QUEUE: usize> Planner<SCRATCH_WORDS, QUEUE> {
    /// A* by Jump Point Search (no corner cutting) with the octile heuristic and a
    /// lazy-deletion binary heap of jump points. Optimal octile cost, same as plain A*.
    ///
    /// The queue's entries are shared by the heap (from the front) and the records of the
    /// closed jump points (from the back: the cell, its step code and the record of the jump
    /// point it was reached from), so that on success the path is rebuilt exactly, segment by
    /// segment, by [`Planner::write_jump_chain`]. `Err(expanded)` when the entries run out or
    /// the map is cluttered (see [`JPS_MAX_EXPANSIONS_PER_CELLS`] and [`JPS_WIDE_FRONTIER`]):
    /// the caller then falls back to cell-by-cell A*.
    pub(super) fn jps<const GW: usize>(
        &mut self,
        grid: &Grid<GW>,
        start: usize,
        goal_cell: Cell,
        goal: usize,
    ) -> Result<Search, u32> {
        let max_expanded = (grid.geometry().cell_count() / JPS_MAX_EXPANSIONS_PER_CELLS).max(256);
        self.jump_points::<GW, false>(grid, start, goal_cell, goal, max_expanded as u32)
    }

    /// Jump point search with unit costs (a side step and a diagonal step both cost 1, the
    /// Chebyshev heuristic): BFS's fewest steps on uncluttered maps. `Search::cost` is the
    /// number of steps. `Err(expanded)` (the caller then runs the layered BFS) when the entries
    /// run out, when more than `max_expanded` jump points were expanded with a wide open list
    /// (the planner passes [`JPS_STEPS_MAX_EXPANSIONS`](super::choice::JPS_STEPS_MAX_EXPANSIONS)), or when a key would not fit (`f ≥ 2²⁰`
    /// steps).
    pub(super) fn jps_steps<const GW: usize>(
        &mut self,
        grid: &Grid<GW>,
        start: usize,
        goal_cell: Cell,
        goal: usize,
        max_expanded: u32,
    ) -> Result<Search, u32> {
        self.jump_points::<GW, true>(grid, start, goal_cell, goal, max_expanded)
    }

    /// The jump point search of [`Planner::jps`] (`UNIT = false`: octile costs and heuristic)
    /// and [`Planner::jps_steps`] (`UNIT = true`: unit costs, Chebyshev heuristic). With unit
    /// costs many entries share one `f`, so the heap key is `f << 12 | h` ([`UNIT_KEY_SHIFT`]):
    /// equal `f` pops the smallest `h`, i.e. the largest `g`, first (towards the goal); `h` is at
    /// most 4 095 on grids of at most [`crate::grid::MAX_SIDE_CELLS`] a side, and `f` must stay
    /// below 2²⁰ (else the search gives up).
    ///
    /// About 200 lines, not split: one loop whose pop, record, goal test, direction rules and
    /// scans share the heap's length, the record count and the goal in registers, like
    /// [`astar_loop`](super::astar::astar_loop) (whose split cost 2 %); a split of this one is
    /// not measured.
    pub(super) fn jump_points<const GW: usize, const UNIT: bool>(
        &mut self,
        grid: &Grid<GW>,
        start: usize,
        goal_cell: Cell,
        goal: usize,
        max_expanded: u32,
    ) -> Result<Search, u32> {
        let geometry = grid.geometry();
        let width = geometry.width() as i32;
        let height = geometry.height() as i32;
        let (gx, gy) = (goal_cell.x as i32, goal_cell.y as i32);
        let h = |x: i32, y: i32| {
            if UNIT {
                x.abs_diff(gx).max(y.abs_diff(gy))
            } else {
                octile(x.abs_diff(gx), y.abs_diff(gy))
            }
        };
        // Heap key of an entry with cost `g` to the cell of heuristic `hc`; `None` when a unit
        // key does not fit.
        let key = |g: u32, hc: u32| -> Option<u32> {
            if UNIT {
                let f = g.checked_add(hc)?;
                (f <= UNIT_MAX_F && hc <= UNIT_H_MASK).then_some(f << UNIT_KEY_SHIFT | hc)
            } else {
                Some(g.saturating_add(hc))
            }
        };
        // `g` of a popped key at a cell of heuristic `hc`.
        let g_of = |k: u32, hc: u32| {
            if UNIT {
                (k >> UNIT_KEY_SHIFT).wrapping_sub(hc)
            } else {
                k.wrapping_sub(hc)
            }
        };
        let (straight_cost, diagonal_cost) = if UNIT {
            (1, 1)
        } else {
            (STRAIGHT_COST, DIAGONAL_COST)
        };
        let pack = |x: i32, y: i32, code: u32| ((y as u32) << 16) | ((x as u32) << 4) | code;
        let pool = &mut self.queue[..];
        let capacity = pool.len();
        let (sx, sy) = (start as i32 % width, start as i32 / width);
        let mut len = match pool.first_mut() {
            Some(slot) => {
                *slot = OpenEntry {
                    f: match key(0, h(sx, sy)) {
                        Some(k) => k,
                        None => return Err(0),
                    },
                    node: pack(sx, sy, CODE_START),
                    next: NIL,
                };
                1usize
            }
            None => return Err(0),
        };
        // Closed jump points: record r lives at `pool[capacity - 1 - r]`.
        let mut records = 0usize;
        let mut peak = len;
        let mut expanded = 0u32;

        while len > 0 {
            let top = pool[0];
            len -= 1;
            pool[0] = pool[len];
            heap_sift_down(&mut pool[..len], 0);

            let x = ((top.node >> 4) & 0xFFF) as i32;
            let y = (top.node >> 16) as i32;
            let index = (y * width + x) as usize;
            if nibble(&self.scratch, index) != 0 {
                continue; // already closed by a cheaper entry
            }
            let code = top.node & 0xF;
            set_nibble(&mut self.scratch, index, code);
            expanded += 1;
            if expanded > max_expanded && len * JPS_WIDE_FRONTIER > expanded as usize {
                self.queue_peak = peak as u32;
                return Err(expanded);
            }
            // The popped entry freed a slot, so the record always fits.
            let record = records as u32;
            pool[capacity - 1 - records] = OpenEntry {
                f: 0,
                node: top.node,
                next: top.next,
            };
            records += 1;
            let g = g_of(top.f, h(x, y));
            if index == goal {
                self.queue_peak = peak as u32;
                self.write_jump_chain(width, record as usize);
                return Ok(Search {
                    found: true,
                    expanded,
                    cost: g,
                });
            }
            let scan = JumpScan {
                words: grid.words(),
                width,
                height,
                goal_x: gx,
                goal_y: gy,
            };
            // Directions to scan, by the step that reached this jump point: from the start all
            // 8; after a diagonal step its two sides and itself; after a side step itself and,
            // for each forced side cell, that side and the forward diagonal next to it.
            let mut dirs = [0u32; 8];
            let n = match Dir::from_code(code) {
                Some(Dir::E | Dir::N | Dir::W | Dir::S) => {
                    let (dx, dy) = STEPS[(code - 1) as usize];
                    dirs[0] = code;
                    let mut n = 1;
                    for (px, py) in [(dy, dx), (-dy, -dx)] {
                        // Forced: the side cell is free, the one behind it occupied.
                        if scan.free(x + px, y + py) && !scan.free(x + px - dx, y + py - dy) {
                            dirs[n] = step_code(px, py);
                            dirs[n + 1] = step_code(dx + px, dy + py);
                            n += 2;
                        }
                    }
                    n
                }
                Some(Dir::NE | Dir::NW | Dir::SW | Dir::SE) => {
                    let (dx, dy) = STEPS[(code - 1) as usize];
                    dirs[..3].copy_from_slice(&[code, step_code(dx, 0), step_code(0, dy)]);
                    3
                }
                // The start (code 9): all eight.
                None => {
                    dirs = [E, N, W, S, NE, NW, SW, SE];
                    8
                }
            };
            for &d in &dirs[..n] {
                let Some(&(dx, dy)) = STEPS.get((d as usize).wrapping_sub(1)) else {
                    continue;
                };
                let found = if dx == 0 || dy == 0 {
                    scan.straight(x, y, dx, dy)
                        .map(|(jx, jy, k)| (jx, jy, k * straight_cost))
                } else {
                    scan.diagonal(x, y, dx, dy)
                        .map(|(jx, jy, k)| (jx, jy, k * diagonal_cost))
                };
                let Some((jx, jy, cost)) = found else {
                    continue;
                };
                if nibble(&self.scratch, (jy * width + jx) as usize) != 0 {
                    continue; // closed already
                }
                let Some(f) = key(g.saturating_add(cost), h(jx, jy)) else {
                    self.queue_peak = peak as u32;
                    return Err(expanded);
                };
                let entry = OpenEntry {
                    f,
                    node: pack(jx, jy, d),
                    next: record,
                };
                if len + records == capacity {
                    // Full: drop the entries of cells closed meanwhile, unless that frees too
                    // little to be worth it (no thrashing).
                    let before = len;
                    let mut kept = 0usize;
                    for i in 0..len {
                        let e = pool[i];
                        let cell = (e.node >> 16) as i32 * width + ((e.node >> 4) & 0xFFF) as i32;
                        if nibble(&self.scratch, cell as usize) == 0 {
                            pool[kept] = e;
                            kept += 1;
                        }
                    }
                    len = kept;
                    for i in (0..len / 2).rev() {
                        heap_sift_down(&mut pool[..len], i);
                    }
                    if before - len < (capacity / 16).max(1) {
                        self.queue_peak = peak as u32;
                        return Err(expanded);
                    }
                }
                pool[len] = entry;
                len += 1;
                heap_sift_up(&mut pool[..len], len - 1);
                peak = peak.max(len + records);
            }
        }
        self.queue_peak = peak as u32;
        Ok(Search {
            found: false,
            expanded,
            cost: 0,
        })
    }

    /// Write the step codes along the chain of jump point records that ends at `record` (the
    /// goal's), so that the path can be rebuilt cell by cell from the goal. Each segment between
    /// two jump points is a straight or 45° scan, so every cell strictly between them gets the
    /// segment's step code (the path is a shortest one, so it crosses no cell twice).
    fn write_jump_chain(&mut self, width: i32, mut record: usize) {
        let capacity = self.queue.len();
        // Each record's parent was closed before it, so indices fall; the bound is a guard.
        for _ in 0..capacity {
            let Some(&child) = self.queue.get(capacity.wrapping_sub(1 + record)) else {
                return;
            };
            let Some(&parent) = self
                .queue
                .get(capacity.wrapping_sub(1 + child.next as usize))
            else {
                return; // the start
            };
            if child.next as usize >= record {
                return;
            }
            let code = child.node & 0xF;
            let Some(&(dx, dy)) = STEPS.get((code as usize).wrapping_sub(1)) else {
                return;
            };
            let (mut x, mut y) = (
                ((child.node >> 4) & 0xFFF) as i32,
                (child.node >> 16) as i32,
            );
            let (px, py) = (
                ((parent.node >> 4) & 0xFFF) as i32,
                (parent.node >> 16) as i32,
            );
            for _ in 0..4096 {
                x -= dx;
                y -= dy;
                if (x, y) == (px, py) || x < 0 || y < 0 {
                    break;
                }
                set_nibble(&mut self.scratch, (y * width + x) as usize, code);
            }
            record = child.next as usize;
        }
    }
}
