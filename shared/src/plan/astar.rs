//! The cell-by-cell A* (cluttered maps, and the fallback of jump point search): octile
//! heuristic, lazy deletion, *arrival pruning* of successors, immediate expansion of a
//! reduced-cost-0 target, corridor walks (`corridor.rs`), keys from step classes (`goal.rs`),
//! an open list by reduced-cost class (`class_queue.rs`, `ring_queue.rs`). The hot loop reads a
//! cell's 3 × 3 neighbourhood as three 12-bit nibble windows and turns them by
//! [`NIBBLE_WINDOWS`] into an 18-bit mask (the `Z_*` / `O_*` bits below); one arm per arrival
//! step pushes with constant offsets. Generic over the layout, the open list and two const
//! switches, so each instance tests nothing per cell that it could know at compile time.
//! Measured (`cargo xtask mcu-bench`, 300 × 300, 2026-12-03): 159 Cortex-M4 instructions per
//! expanded cell on 20 % random obstacles (4.59 M a plan), 158 in the maze (3.13 M, walked
//! corridor cells counted as expanded); the steps that got there: docs/planners-history.md,
//! "Cell-by-cell A\*: the expansion loop" and the sections before it.

use super::class_queue::ClassQueue;
use super::codes::{Dir, CODE_START, E, N, NE, NW, S, SE, STEPS, SW, W};
use super::corridor::{corridor_index, walk_corridor, CORRIDOR_SIDES, WALK_GIVE_UP_CREDIT};
use super::goal::{
    axis_region, goal_axis_entry, goal_region, AT_GOAL, CLASS_COSTS, GOAL_AXIS_CELLS,
    GOAL_TABLE_WORDS, STEP_CLASSES,
};
use super::layout::{CellMap, Flat, Framed, Interior, FRAMED_WORDS, NIBBLE_WINDOWS};
use super::open_list::{OpenEntry, OpenList, QueueState, NIL};
use super::planner::{Layout, Planner, Search};
use super::ring_queue::RingQueue;
use super::{scratch_words_for_cells, PlanError, DIAGONAL_COST, STRAIGHT_COST};
use crate::geom::Cell;
use crate::grid::Grid;

// The 18-bit neighbourhood mask of the cell-by-cell A*: three rows of [`NIBBLE_WINDOWS`]
// entries (below, same, above; 6 bits each). `Z_*`: the neighbour's nibble is 0 (a possible
// target); `O_*`: the neighbour is not blocked (a side cell a diagonal step may pass).
const Z_SW: u32 = 0;
const Z_S: u32 = 1;
const Z_SE: u32 = 2;
const Z_W: u32 = 6;
const Z_E: u32 = 8;
const Z_NW: u32 = 12;
const Z_N: u32 = 13;
const Z_NE: u32 = 14;
const O_SW: u32 = 3;
const O_S: u32 = 4;
const O_SE: u32 = 5;
const O_W: u32 = 9;
const O_E: u32 = 11;
const O_NW: u32 = 15;
const O_N: u32 = 16;
const O_NE: u32 = 17;

impl<const SCRATCH_WORDS: usize, const QUEUE: usize> Planner<SCRATCH_WORDS, QUEUE> {
    /// Cell-by-cell A* (see [`astar_search`]) on a copy of the map: in the [`Framed`] layout
    /// with the goal regions from the per-axis table when the framed map fits the first
    /// [`FRAMED_WORDS`] words of the scratch and the grid is at most [`GOAL_AXIS_CELLS`] a side,
    /// else in the [`Flat`] one with the regions computed per cell. `start`: the flat cell index.
    pub(super) fn astar<const GW: usize>(
        &mut self,
        grid: &Grid<GW>,
        start: usize,
        goal_cell: Cell,
    ) -> Result<Search, PlanError> {
        self.astar_in::<GW, FRAMED_WORDS>(grid, start, goal_cell, true)
    }

    /// [`Planner::astar`] with a framed view of `WORDS` words (`WORDS − 1` a power of two), or
    /// in the flat layout when `framed` is false or the framed map does not fit. Only the
    /// framed search reads the per-axis goal table ([`axis_region`]); the flat one, the
    /// fallback for grids the framed view cannot hold, computes the regions per cell
    /// ([`goal_region`]): one instance of the search less in flash (see "What each
    /// optimisation earns" in docs/planners-history.md; the tests run both on the same maps).
    pub(super) fn astar_in<const GW: usize, const WORDS: usize>(
        &mut self,
        grid: &Grid<GW>,
        start: usize,
        goal_cell: Cell,
        framed: bool,
    ) -> Result<Search, PlanError> {
        let geometry = *grid.geometry();
        let width = geometry.width() as usize;
        let start_xy = ((start % width) as u32, (start / width) as u32);
        let goal_xy = (goal_cell.x as u32, goal_cell.y as u32);
        let side = width.max(geometry.height() as usize);
        if framed && side <= GOAL_AXIS_CELLS {
            if let Some(mut map) = Framed::<WORDS>::new(&mut self.scratch, &geometry) {
                let (axis, classes) = self.goal_axis.split_at_mut(GOAL_AXIS_CELLS);
                for (i, entry) in (0u32..).zip(axis.iter_mut().take(side)) {
                    *entry = goal_axis_entry(i, goal_xy.0, goal_xy.1);
                }
                classes.copy_from_slice(&STEP_CLASSES);
                map.copy_map(grid);
                self.layout = Layout::Framed { stride: map.stride };
                // Rings first; when one stays full, again with the linked lists (exact
                // `QueueFull` semantics; the same pops in the same order).
                let ring = astar_search::<_, RingQueue, true>(
                    &mut map,
                    &mut self.queue,
                    &self.goal_axis,
                    start_xy,
                    goal_xy,
                    &mut self.queue_peak,
                );
                if !matches!(ring, Err(PlanError::QueueFull { .. })) {
                    return ring;
                }
                map.copy_map(grid);
                return astar_search::<_, ClassQueue, true>(
                    &mut map,
                    &mut self.queue,
                    &self.goal_axis,
                    start_xy,
                    goal_xy,
                    &mut self.queue_peak,
                );
            }
        }
        self.copy_map(grid);
        self.layout = Layout::Flat;
        let used_words = scratch_words_for_cells(geometry.cell_count());
        let mut map = Flat {
            scratch: self.scratch.get_mut(..used_words).unwrap_or(&mut []),
            interior: Interior::new(&geometry),
        };
        astar_search::<_, ClassQueue, false>(
            &mut map,
            &mut self.queue,
            &self.goal_axis,
            start_xy,
            goal_xy,
            &mut self.queue_peak,
        )
    }
}

/// Cell-by-cell A* with the octile heuristic, a lazy-deletion queue by reduced-cost class
/// ([`ClassQueue`]) and the
/// *arrival pruning* of successors (see docs/planners.md): a closed cell pushes only the
/// neighbours that no other cell covers with a key no larger. The scratch must hold the map
/// ([`Planner::copy_map`]).
///
/// Hot loop: the popped cell's 3 × 3 neighbourhood is read as three 12-bit windows (three
/// nibbles of a row from two scratch words) and turned by [`NIBBLE_WINDOWS`] into an 18-bit
/// mask ("nibble 0" and "not blocked" per cell); one arm per arrival step tests its
/// candidate targets in the mask and pushes them with constant offsets. Cells on the map
/// border read their neighbours one by one.
pub(super) fn astar_search<'p, M: CellMap, Q: OpenList<'p>, const AXIS_TABLE: bool>(
    map: &mut M,
    pool: &'p mut [OpenEntry],
    goal_axis: &[u32; GOAL_TABLE_WORDS],
    (sx, sy): (u32, u32),
    (gx, gy): (u32, u32),
    peak: &mut u32,
) -> Result<Search, PlanError> {
    // Octile distance to the goal; sides are at most 4096 cells, so no overflow.
    let h = |x: u32, y: u32| {
        let (dx, dy) = (x.abs_diff(gx), y.abs_diff(gy));
        let (lo, hi) = if dx < dy { (dx, dy) } else { (dy, dx) };
        DIAGONAL_COST * lo + STRAIGHT_COST * (hi - lo)
    };
    let goal = map.index(gx as usize, gy as usize);
    let (mut open, mut state) = Q::new(pool, h(sx, sy));
    let full = PlanError::QueueFull {
        capacity: open.capacity(),
    };
    let mut expanded = 0u32;

    // Entries carry `y << 16 | x << 4 | step code` (sides are at most 4096 cells), so the
    // loop never divides, and a neighbour's entry is the cell's plus a constant.
    if !open.push(&mut state, h(sx, sy), (sy << 16) | (sx << 4) | CODE_START) {
        return Err(full);
    }

    // A target whose key equals the key just popped (class 0) is the next pop anyway
    // (nothing in the queue is below it): one such target skips the queue and is expanded
    // next (`next_node`, NIL when none). The key of the cell being expanded is always
    // `state.last`; `g` is not carried: it is `state.last − h` where needed (at the goal
    // `h` is 0).
    let mut next_node = NIL;
    // With corridor walks until they are given up on this map (random clutter), then in a
    // second instance of the loop without them: its registers are not spent on the walks.
    match astar_loop::<M, Q, AXIS_TABLE, true>(
        map,
        &mut open,
        &mut state,
        &mut next_node,
        &mut expanded,
        goal_axis,
        (gx, gy),
        goal,
        peak,
    ) {
        Some(end) => end,
        None => astar_loop::<M, Q, AXIS_TABLE, false>(
            map,
            &mut open,
            &mut state,
            &mut next_node,
            &mut expanded,
            goal_axis,
            (gx, gy),
            goal,
            peak,
        )
        .unwrap_or(Err(full)),
    }
}

/// The expansion loop of [`astar_search`] from the queue `open` / `state`, the immediate
/// target `next_node` and the count `expanded`: the search's result, or with `WALKS` `None`
/// when the corridor walks are given up (the state is written back; the search goes on without
/// them). Without `WALKS` it never returns `None`.
///
/// One function of about 230 lines on purpose (issue 27, item 4): it is the hot loop of the
/// cell-by-cell A\*, and its parts share the queue state, the immediate target and the
/// neighbourhood mask in registers. Split into `#[inline(always)]` steps (closing the next
/// cell, the step classes, the pushes), it measured 4 677 476 instructions instead of 4 580 643
/// on 20 % random obstacles (+2.1 %) and +0.5 % in the maze (`cargo xtask mcu-bench`), over the
/// 1 % a refactor may cost.
#[allow(clippy::too_many_arguments)]
#[inline(never)]
pub(super) fn astar_loop<
    'p,
    M: CellMap,
    Q: OpenList<'p>,
    const AXIS_TABLE: bool,
    const WALKS: bool,
>(
    map: &mut M,
    open: &mut Q,
    queue_state: &mut QueueState,
    next_target: &mut u32,
    expanded_cells: &mut u32,
    goal_axis: &[u32; GOAL_TABLE_WORDS],
    (gx, gy): (u32, u32),
    goal: usize,
    peak: &mut u32,
) -> Option<Result<Search, PlanError>> {
    let h = |x: u32, y: u32| {
        let (dx, dy) = (x.abs_diff(gx), y.abs_diff(gy));
        let (lo, hi) = if dx < dy { (dx, dy) } else { (dy, dx) };
        DIAGONAL_COST * lo + STRAIGHT_COST * (hi - lo)
    };
    let full = PlanError::QueueFull {
        capacity: open.capacity(),
    };
    let (gxi, gyi) = (gx as i32, gy as i32);
    let (mut state, mut next_node, mut expanded) = (*queue_state, *next_target, *expanded_cells);
    // The balance of cells closed by corridor walks minus walks started.
    let mut walk_credit = 0i32;
    loop {
        // Close the cell: its nibble gets the arrival step (it was 0).
        let (node, x, y, index) = if next_node != NIL {
            // A target of the cell just expanded: not closed (its nibble was 0 then).
            let node = next_node;
            next_node = NIL;
            let (x, y) = (((node >> 4) & 0xFFF) as usize, (node >> 16) as usize);
            let index = map.index(x, y);
            map.mark(index, node & 0xF);
            (node, x, y, index)
        } else {
            let mut found = None;
            loop {
                let node = open.pop(&mut state);
                if node == NIL {
                    break;
                }
                let (x, y) = (((node >> 4) & 0xFFF) as usize, (node >> 16) as usize);
                let index = map.index(x, y);
                if map.close(index, node & 0xF) {
                    found = Some((node, x, y, index));
                    break;
                }
                // Otherwise already closed by a cheaper entry.
            }
            match found {
                Some(entry) => entry,
                None => break,
            }
        };
        let code = node & 0xF;
        expanded += 1;

        let (above, cur, below) = map.windows(index, x, y);
        let window = |w: u32| u32::from(NIBBLE_WINDOWS[(w & 0xFFF) as usize]);
        let m = window(below) | window(cur) << 6 | window(above) << 12;
        // The targets by arrival step (arrival pruning, see docs/planners.md), each tested
        // and pushed with constant offsets: straight on, plus the forced side and diagonal
        // neighbours after a side step; the two sides and the diagonal after a diagonal
        // step; all eight from the start.
        let base = node & !0xF;
        // The class of each step's reduced cost (its key is `state.last` plus the class's
        // reduced cost), 3 bits per step code.
        let classes = if AXIS_TABLE {
            // In range: a region is below 128 by construction (no bounds check emitted).
            let region = axis_region(goal_axis, x, node);
            goal_axis[GOAL_AXIS_CELLS + region]
        } else {
            let region = goal_region(x as i32 - gxi, y as i32 - gyi);
            STEP_CLASSES.get(region).copied().unwrap_or(0)
        };
        // The goal: the only cell of its region, flagged in the class word.
        if classes & AT_GOAL != 0 {
            *peak = open.peak(&state);
            // h(goal) = 0: the key is the cost.
            return Some(Ok(Search {
                found: true,
                expanded,
                cost: state.last,
            }));
        }
        // The pool is full: reclaim and push `(key, child)`, or end with QueueFull.
        macro_rules! reclaim {
            ($key:expr, $child:expr) => {{
                let closed = |n: u32| {
                    map.nibble(map.index(((n >> 4) & 0xFFF) as usize, (n >> 16) as usize)) != 0
                };
                match open.reclaim_and_push(state, closed, $key, $child) {
                    Some(after) => state = after,
                    None => {
                        *peak = open.peak(&state);
                        return Some(Err(full));
                    }
                }
            }};
        }
        macro_rules! visit {
            ($z:expr, $code:expr) => {{
                if m & (1 << $z) != 0 {
                    let (dx, dy) = STEPS[$code as usize - 1];
                    let child = base.wrapping_add(((dy << 16) + (dx << 4)) as u32 + $code);
                    let class = ((classes >> (3 * ($code - 1))) & 7) as usize;
                    if class != 0 {
                        if !open.push_class(&mut state, class, child) {
                            reclaim!(state.last.wrapping_add(CLASS_COSTS[class]), child);
                        }
                    } else if next_node == NIL {
                        next_node = child;
                    } else if !open.push_stack(&mut state, child) {
                        reclaim!(state.last, child);
                    }
                }
            }};
        }
        // Corridor contraction (see "Corridors" in docs/planners.md): a cell with one or
        // two legal neighbours, reached by a side step, has at most one continuation. Walk
        // along the chain of such cells, closing each with its step, up to the first cell
        // that is not one (pushed), the goal or a cell on the map border (pushed), a dead
        // end (closed, nothing pushed) or a closed cell (nothing pushed).
        let sides = if WALKS && code <= S {
            u32::from(CORRIDOR_SIDES[corridor_index(m)])
        } else {
            0
        };
        if sides != 0 {
            // Side bit `code - 1`; the side behind a step of code `c` is bit `(c + 1) & 3`.
            let rest = sides & !(1 << ((code + 1) & 3));
            let (end, steps, closed) = walk_corridor(map, goal, index, node, rest);
            expanded += closed;
            if end != NIL {
                // Plain adds: keys are u32 (see "Complexity" in docs/planners.md).
                let g = state.last.wrapping_sub(h(x as u32, y as u32));
                let wg = g.wrapping_add(steps.wrapping_mul(STRAIGHT_COST));
                let key = wg.wrapping_add(h((end >> 4) & 0xFFF, end >> 16));
                if key == state.last && next_node == NIL {
                    next_node = end;
                } else if !open.push_far(&mut state, key, end) {
                    reclaim!(key, end);
                }
            }
            // Walks that close (nearly) nothing cost more than the arms' pushes.
            walk_credit += closed as i32 - 1;
            if walk_credit < WALK_GIVE_UP_CREDIT {
                (*queue_state, *next_target, *expanded_cells) = (state, next_node, expanded);
                return None;
            }
            continue;
        }
        macro_rules! diagonal {
            ($z:expr, $code:expr, $o1:expr, $o2:expr) => {{
                if m & ((1 << $o1) | (1 << $o2)) == (1 << $o1) | (1 << $o2) {
                    visit!($z, $code);
                }
            }};
        }
        macro_rules! forced {
            ($o_back:expr, $z:expr, $code:expr, $zd:expr, $dcode:expr, $o1:expr, $o2:expr) => {{
                if m & (1 << $o_back) == 0 {
                    visit!($z, $code);
                    diagonal!($zd, $dcode, $o1, $o2);
                }
            }};
        }
        match Dir::from_code(code) {
            Some(Dir::E) => {
                visit!(Z_E, E);
                forced!(O_NW, Z_N, N, Z_NE, NE, O_N, O_E);
                forced!(O_SW, Z_S, S, Z_SE, SE, O_S, O_E);
            }
            Some(Dir::W) => {
                visit!(Z_W, W);
                forced!(O_NE, Z_N, N, Z_NW, NW, O_N, O_W);
                forced!(O_SE, Z_S, S, Z_SW, SW, O_S, O_W);
            }
            Some(Dir::N) => {
                visit!(Z_N, N);
                forced!(O_SE, Z_E, E, Z_NE, NE, O_E, O_N);
                forced!(O_SW, Z_W, W, Z_NW, NW, O_W, O_N);
            }
            Some(Dir::S) => {
                visit!(Z_S, S);
                forced!(O_NE, Z_E, E, Z_SE, SE, O_E, O_S);
                forced!(O_NW, Z_W, W, Z_SW, SW, O_W, O_S);
            }
            Some(Dir::NE) => {
                visit!(Z_E, E);
                visit!(Z_N, N);
                diagonal!(Z_NE, NE, O_N, O_E);
            }
            Some(Dir::NW) => {
                visit!(Z_W, W);
                visit!(Z_N, N);
                diagonal!(Z_NW, NW, O_N, O_W);
            }
            Some(Dir::SW) => {
                visit!(Z_W, W);
                visit!(Z_S, S);
                diagonal!(Z_SW, SW, O_S, O_W);
            }
            Some(Dir::SE) => {
                visit!(Z_E, E);
                visit!(Z_S, S);
                diagonal!(Z_SE, SE, O_S, O_E);
            }
            // The start (code 9): all eight neighbours.
            None => {
                visit!(Z_E, E);
                visit!(Z_N, N);
                visit!(Z_W, W);
                visit!(Z_S, S);
                diagonal!(Z_NE, NE, O_N, O_E);
                diagonal!(Z_NW, NW, O_N, O_W);
                diagonal!(Z_SW, SW, O_S, O_W);
                diagonal!(Z_SE, SE, O_S, O_E);
            }
        }
    }
    *peak = open.peak(&state);
    Some(Ok(Search {
        found: false,
        expanded,
        cost: 0,
    }))
}
