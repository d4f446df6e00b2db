//! Corridor walks of the cell-by-cell A*: random mazes with loops and holes, carved maps,
//! the corridor table.

use super::*;
use crate::grid::GridGeometry;
use crate::plan::corridor::CORRIDOR_SIDES;

/// A corridor walked away from the goal ends far above the last popped key (here 18 208 above
/// it, beyond the buckets' 16 384): its end waits in the far list instead of wrapping around
/// to an early bucket (which popped it too soon and gave a path 14 845 units too long).
#[test]
fn corridor_walk_ending_far_above_the_last_key_keeps_the_optimal_cost() {
    let mut g = grid_from_rows(&[
        "....", "#.##", "...#", ".#..", "..#.", "....", "..##", "....", "....", "#...", "...#",
        "..#.", "..#.", "....", "#...", ".#..", ".#..", "..##", "....", "...#",
    ]);
    let (s, t) = (Cell::new(1, 3), Cell::new(3, 18));
    g.set(s, false);
    g.set(t, false);
    let mut p = Box::new(SmallPlanner::new());
    let si = g.geometry().index(s);
    let search = p.astar(&g, si, t).unwrap();
    assert_eq!(Some(search.cost), oracle_astar(&g, s, t));
    assert_eq!(search.cost, 125_317);
    p.rebuild_merged(g.geometry(), t, false);
    assert_eq!(steps_and_cost(p.path_cells()).1, search.cost);
    assert_collision_free(&g, p.path_cells());
}

/// A perfect maze (recursive backtracker) with 1-cell corridors on a `w × h` grid (rooms on odd
/// coordinates), then `loops` extra wall cells between rooms opened at random (cycles, so that
/// a corridor can be reached from both ends) and `holes` random cells freed anywhere (small
/// open patches, corridors with diagonal links, junctions next to each other).
fn maze_grid(w: u32, h: u32, seed: u64, loops: u32, holes: u32) -> SmallGrid {
    let mut g = SmallGrid::new(GridGeometry::new(w, h, 0.1).unwrap()).unwrap();
    for y in 0..h as i32 {
        g.fill_row(y, 0, w as i32 - 1);
    }
    let (rw, rh) = (((w - 1) / 2).max(1) as i32, ((h - 1) / 2).max(1) as i32);
    let mut state = seed | 1;
    let mut visited = std::vec![false; (rw * rh) as usize];
    let mut stack = std::vec![(0i32, 0i32)];
    visited[0] = true;
    g.set_xy(1, 1, false);
    while let Some(&(rx, ry)) = stack.last() {
        let mut options = Vec::new();
        for (dx, dy) in [(1, 0), (-1, 0), (0, 1), (0, -1)] {
            let (nx, ny) = (rx + dx, ry + dy);
            if nx >= 0 && ny >= 0 && nx < rw && ny < rh && !visited[(ny * rw + nx) as usize] {
                options.push((dx, dy));
            }
        }
        if options.is_empty() {
            stack.pop();
            continue;
        }
        let (dx, dy) = options[(next_random(&mut state) % options.len() as u64) as usize];
        let (nx, ny) = (rx + dx, ry + dy);
        visited[(ny * rw + nx) as usize] = true;
        g.set_xy(2 * rx + 1 + dx, 2 * ry + 1 + dy, false);
        g.set_xy(2 * nx + 1, 2 * ny + 1, false);
        stack.push((nx, ny));
    }
    for _ in 0..loops {
        // A wall cell with an odd coordinate between two rooms.
        let x = (next_random(&mut state) % w as u64) as i32;
        let y = (next_random(&mut state) % h as u64) as i32;
        if (x + y) % 2 == 1 && x > 0 && y > 0 && x < w as i32 - 1 && y < h as i32 - 1 {
            g.set_xy(x, y, false);
        }
    }
    for _ in 0..holes {
        let x = (next_random(&mut state) % w as u64) as i32;
        let y = (next_random(&mut state) % h as u64) as i32;
        g.set_xy(x, y, false);
    }
    g
}

/// A grid carved by `segments` random horizontal and vertical 1-cell-wide runs into a fully
/// blocked map: corridors, junctions, dead ends, cycles, and 2-wide strips where runs lie side
/// by side (with diagonal links).
fn carved_grid(w: u32, h: u32, seed: u64, segments: u32) -> SmallGrid {
    let mut g = SmallGrid::new(GridGeometry::new(w, h, 0.1).unwrap()).unwrap();
    for y in 0..h as i32 {
        g.fill_row(y, 0, w as i32 - 1);
    }
    let mut state = seed | 1;
    for _ in 0..segments {
        let x = (next_random(&mut state) % w as u64) as i32;
        let y = (next_random(&mut state) % h as u64) as i32;
        let len = (next_random(&mut state) % (w.max(h) as u64)) as i32;
        let horizontal = next_random(&mut state) & 1 == 0;
        for k in 0..=len {
            if horizontal {
                g.set_xy(x + k, y, false);
            } else {
                g.set_xy(x, y + k, false);
            }
        }
    }
    g
}

/// The `k`-th free cell of the grid in row-major order (wrapping), if any.
fn free_cell(g: &SmallGrid, k: u64) -> Option<Cell> {
    let (w, h) = (g.geometry().width(), g.geometry().height());
    let n = (w * h) as u64;
    (0..n)
        .map(|i| (k + i) % n)
        .map(|i| Cell::new((i % w as u64) as u16, (i / w as u64) as u16))
        .find(|&c| !g.is_occupied(c))
}

/// The cell-by-cell A* alone and every planner on `g` from `s` to `t` against `pathfinding`:
/// the same optimal cost, a legal path of that cost from `s` to `t`, any-angle never longer.
fn check_corridor_case(g: &SmallGrid, s: Cell, t: Cell) -> Result<(), TestCaseError> {
    let expected = oracle_astar(g, s, t);
    let mut p = Box::new(SmallPlanner::new());
    if s != t {
        let si = g.geometry().index(s);
        let search = p.astar(g, si, t).unwrap();
        prop_assert_eq!(search.found.then_some(search.cost), expected);
        if search.found {
            let (_, _, fits) = p.rebuild_merged(g.geometry(), t, false);
            prop_assert!(fits);
            prop_assert_eq!(steps_and_cost(p.path_cells()).1, search.cost);
            assert_collision_free(g, p.path_cells());
            prop_assert_eq!(p.path_cells().first(), Some(&s));
            prop_assert_eq!(p.path_cells().last(), Some(&t));
        }
    }
    let astar = p.plan_cells(PlannerKind::AStar, g, s, t).unwrap();
    prop_assert_eq!(
        (astar.status == PlanStatus::Found).then_some(astar.cost),
        expected
    );
    let astar_cells: Vec<Cell> = p.path_cells().to_vec();
    if expected.is_some() {
        prop_assert_eq!(steps_and_cost(&astar_cells).1, astar.cost);
        assert_collision_free(g, &astar_cells);
    }
    let any = p.plan_cells(PlannerKind::AnyAngle, g, s, t).unwrap();
    prop_assert_eq!(any.status, astar.status);
    prop_assert_eq!(any.cost, astar.cost);
    if expected.is_some() {
        let cells = p.path_cells();
        assert_collision_free(g, cells);
        prop_assert_eq!(cells.first(), Some(&s));
        prop_assert_eq!(cells.last(), Some(&t));
        prop_assert!(exact_length(cells) <= exact_length(&astar_cells) + 1e-9);
    }
    // A small queue reclaims stale entries (in the buckets and in the far list of walk ends):
    // the same cost, or `QueueFull`.
    let mut small = Box::new(Planner::<{ scratch_words_for_cells(SMALL_CELLS) }, 12>::new());
    match small.plan_cells(PlannerKind::AStar, g, s, t) {
        Ok(r) => {
            prop_assert_eq!((r.status == PlanStatus::Found).then_some(r.cost), expected);
            if expected.is_some() {
                prop_assert_eq!(steps_and_cost(small.path_cells()).1, r.cost);
            }
        }
        Err(e) => prop_assert_eq!(e, PlanError::QueueFull { capacity: 12 }),
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1024))]

    /// Mazes of 1-cell corridors, with loops and holes, start and goal anywhere free (inside
    /// corridors, at dead ends, at junctions): corridor walks keep A* optimal.
    #[test]
    fn corridor_walks_in_mazes_match_pathfinding(
        w in 3u32..=40, h in 3u32..=40, seed in any::<u64>(), loops in 0u32..40,
        holes in 0u32..12, ks in any::<u64>(), kt in any::<u64>(),
    ) {
        let g = maze_grid(w, h, seed, loops, holes);
        if let (Some(s), Some(t)) = (free_cell(&g, ks), free_cell(&g, kt)) {
            check_corridor_case(&g, s, t)?;
        }
    }

    /// Maps carved from random 1-cell runs (corridors, crossings, side-by-side runs).
    #[test]
    fn corridor_walks_in_carved_maps_match_pathfinding(
        w in 2u32..=40, h in 2u32..=40, seed in any::<u64>(), segments in 1u32..30,
        ks in any::<u64>(), kt in any::<u64>(),
    ) {
        let g = carved_grid(w, h, seed, segments);
        if let (Some(s), Some(t)) = (free_cell(&g, ks), free_cell(&g, kt)) {
            check_corridor_case(&g, s, t)?;
        }
    }
}

#[test]
fn corridor_table_counts_legal_neighbours() {
    // Index bits: 0..3 the row below (W to E), 3..6 the cell's row, 6..9 the row above.
    let row = |below: u32, cur: u32, above: u32| (below | cur << 3 | above << 6) as usize;
    // A straight corridor W-E: sides E and W.
    assert_eq!(CORRIDOR_SIDES[row(0b000, 0b111, 0b000)], 0b0101);
    // A turn W-N with the inner corner blocked: a corridor cell.
    assert_eq!(CORRIDOR_SIDES[row(0b000, 0b011, 0b010)], 0b0110);
    // The same turn with the inner corner free: three legal neighbours (NW diagonal).
    assert_eq!(CORRIDOR_SIDES[row(0b000, 0b011, 0b011)], 0);
    // A dead end (only S free) and a junction (E, W, N).
    assert_eq!(CORRIDOR_SIDES[row(0b010, 0b010, 0b000)], 0b1000);
    assert_eq!(CORRIDOR_SIDES[row(0b000, 0b111, 0b010)], 0);
    // Free diagonals without both side cells are not legal neighbours.
    assert_eq!(CORRIDOR_SIDES[row(0b101, 0b111, 0b101)], 0b0101);
}
