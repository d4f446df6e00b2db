//! The cell-by-cell A*: alone against `pathfinding`, reduced-cost classes, goal regions and
//! the per-axis goal table, corridor walks given up midway.

use super::*;
use crate::plan::class_queue::ClassQueue;
use crate::plan::codes::{nibble, octile, CODE_START, NE, STEPS};
use crate::plan::goal::{
    axis_region, goal_axis_entry, goal_region, reduced_cost_class, AT_GOAL, GOAL_AXIS_CELLS,
    GOAL_TABLE_WORDS, REDUCED_COSTS, STEP_CLASSES,
};
use crate::plan::layout::{CellMap, Framed, FRAMED_WORDS};
use crate::plan::open_list::{OpenEntry, OpenList, NIL};
use crate::plan::planner::{Layout, Search};

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2048))]

    /// The cell-by-cell A* on its own (whatever the clutter test would choose), with its arrival
    /// pruning and the queue's immediate expansion: the optimal cost, a path of that cost.
    #[test]
    fn cell_by_cell_astar_matches_pathfinding((mut g, s, t) in arb_grid()) {
        let mut p = Box::new(SmallPlanner::new());
        g.set(s, false);
        g.set(t, false);
        if s == t {
            return Ok(());
        }
        let si = g.geometry().index(s);
        let search = p.astar(&g, si, t).unwrap();
        let expected = oracle_astar(&g, s, t);
        prop_assert_eq!(search.found, expected.is_some());
        if let Some(cost) = expected {
            prop_assert_eq!(search.cost, cost);
            let (_, _, fits) = p.rebuild_merged(g.geometry(), t, false);
            prop_assert!(fits);
            prop_assert_eq!(steps_and_cost(p.path_cells()).1, cost);
            assert_collision_free(&g, p.path_cells());
            prop_assert_eq!(p.path_cells().first(), Some(&s));
        }
    }
}

/// Words of the framed view in [`astar_both_region_ways`] (`2^15 + 1`: sides of
/// [`GOAL_AXIS_CELLS`] cells fit it in narrow grids).
const BOTH_WAYS_WORDS: usize = (1 << 15) + 1;

/// The cell-by-cell A* from `s` to `t` framed, with the goal regions from the per-axis table
/// (when the grid fits the framed view and the table), and flat, with the regions computed
/// per cell: the same result (found, cells expanded, cost, or the same error). Returns the
/// flat search's result and whether the first search ran framed.
fn astar_both_region_ways<const GW: usize, const S: usize, const Q: usize>(
    p: &mut Planner<S, Q>,
    g: &Grid<GW>,
    s: Cell,
    t: Cell,
) -> (Result<Search, PlanError>, bool) {
    let si = g.geometry().index(s);
    let outcome = |r: &Result<Search, PlanError>| match r {
        Ok(s) => Ok((s.found, s.expanded, s.cost)),
        Err(e) => Err(*e),
    };
    let table = p.astar_in::<GW, BOTH_WAYS_WORDS>(g, si, t, true);
    let framed = matches!(p.layout, Layout::Framed { .. });
    let direct = p.astar_in::<GW, BOTH_WAYS_WORDS>(g, si, t, false);
    assert_eq!(p.layout, Layout::Flat);
    assert_eq!(outcome(&table), outcome(&direct), "{s:?} -> {t:?}");
    (direct, framed)
}

/// Grids at the per-axis goal table's limit (sides of [`GOAL_AXIS_CELLS`] cells) and just
/// beyond it (the search then computes the regions per cell), random obstacles (20 %, fewer in
/// narrow grids, which they would cut), searches
/// between corners, edges and the middle: the cell-by-cell A* finds `pathfinding`'s cost, the
/// same search both ways ([`astar_both_region_ways`]).
#[test]
fn cell_by_cell_astar_at_the_goal_table_limit_matches_pathfinding() {
    const CELLS: usize = (GOAL_AXIS_CELLS + 1) * (GOAL_AXIS_CELLS + 1);
    let n = GOAL_AXIS_CELLS as u16;
    let mut p = Box::new(Planner::<{ scratch_words_for_cells(CELLS) }, 16384>::new());
    let (mut found, mut framed) = (0, 0);
    let sizes = [
        (n, n, 20),
        (n + 1, n + 1, 20),
        (n, 9, 4),
        (9, n, 4),
        (n + 1, 7, 3),
        (5, n + 1, 2),
    ];
    for (w, h, density) in sizes {
        let seed = u64::from(w) * 7 + u64::from(h);
        let mut g = random_grid::<{ words_for_cells(CELLS) }>(w.into(), h.into(), density, seed);
        let (r, u) = (w - 1, h - 1);
        for (s, t) in [
            ((0, 0), (r, u)),
            ((r, u), (0, 0)),
            ((r, 0), (0, u)),
            ((w / 2, h / 2), (r, u / 3)),
            ((0, u / 2), (r, u / 2)),
        ] {
            let (s, t) = (Cell::new(s.0, s.1), Cell::new(t.0, t.1));
            g.set(s, false);
            g.set(t, false);
            let (search, was_framed) = astar_both_region_ways(&mut *p, &g, s, t);
            let search = search.unwrap();
            framed += usize::from(was_framed);
            let expected = oracle_astar(&g, s, t);
            assert_eq!(
                search.found.then_some(search.cost),
                expected,
                "{w} x {h}: {s:?} -> {t:?}"
            );
            found += usize::from(search.found);
        }
    }
    assert!(found >= 24, "{found} of 30 found");
    // 512 x 9 and 9 x 512 run framed with the table at its limit; the rest do not fit.
    assert_eq!(framed, 10);
}

/// Every move from every cell of a 13 × 11 grid, around goals in the corners, on the edges, in
/// the middle and off the centre (same row, column and diagonal as many cells): the reduced
/// cost `cost + h(child) − h(parent)` is always one of the six [`REDUCED_COSTS`] (0 included),
/// each occurs, [`STEP_CLASSES`] of the cell's [`goal_region`] names it for every step, and
/// [`reduced_cost_class`] recognises exactly the six values.
#[test]
fn reduced_costs_of_octile_moves_take_six_values() {
    let (w, hgt) = (13i32, 11i32);
    let mut seen = std::collections::BTreeSet::new();
    let goals = [
        (0, 0),
        (12, 0),
        (0, 10),
        (12, 10),
        (6, 5),
        (6, 0),
        (0, 5),
        (12, 7),
        (3, 10),
        (2, 8),
        (9, 1),
    ];
    for &(gx, gy) in &goals {
        let h = |x: i32, y: i32| octile(x.abs_diff(gx), y.abs_diff(gy));
        for y in 0..hgt {
            for x in 0..w {
                for (k, &(dx, dy)) in STEPS.iter().enumerate() {
                    let (cx, cy) = (x + dx, y + dy);
                    if !(0..w).contains(&cx) || !(0..hgt).contains(&cy) {
                        continue;
                    }
                    let cost = if k + 1 >= NE as usize {
                        DIAGONAL_COST
                    } else {
                        STRAIGHT_COST
                    };
                    let r = (cost + h(cx, cy)) as i64 - h(x, y) as i64;
                    assert!(
                        REDUCED_COSTS.contains(&(r as u32)),
                        "goal ({gx}, {gy}) cell ({x}, {y}) step {k}: r = {r}"
                    );
                    seen.insert(r as u32);
                    // The search's table gives the same class, with the region computed
                    // per cell and from the per-axis table alike.
                    let region = goal_region(x - gx, y - gy);
                    let table = goal_table(gx as u32, gy as u32);
                    let node = (y as u32) << 16 | (x as u32) << 4 | (k as u32 + 1);
                    assert_eq!(axis_region(&table, x as usize, node), region, "({x}, {y})");
                    assert_eq!(table[GOAL_AXIS_CELLS + region], STEP_CLASSES[region]);
                    // The goal flag: on the goal's region only (the search's goal test).
                    assert_eq!(
                        STEP_CLASSES[region] & AT_GOAL != 0,
                        (x, y) == (gx, gy),
                        "goal ({gx}, {gy}) cell ({x}, {y})"
                    );
                    let classes = STEP_CLASSES[region];
                    let class = (classes >> (3 * k)) & 7;
                    assert_eq!(
                        REDUCED_COSTS[class as usize] as i64, r,
                        "goal ({gx}, {gy}) cell ({x}, {y}) step {k}"
                    );
                }
            }
        }
    }
    assert_eq!(seen.into_iter().collect::<Vec<_>>(), REDUCED_COSTS);
    assert_eq!(REDUCED_COSTS, [0, 3363, 4756, 8119, 11482, 16238]);
    for r in 0..=3 * DIAGONAL_COST {
        let class = REDUCED_COSTS.iter().position(|&v| v == r);
        assert_eq!(reduced_cost_class(r), class, "r = {r}");
    }
    assert_eq!(reduced_cost_class(u32::MAX), None);
}

/// The goal table a search on a grid of at most [`GOAL_AXIS_CELLS`] a side fills for the goal
/// `(gx, gy)`: every per-axis entry, then [`STEP_CLASSES`].
fn goal_table(gx: u32, gy: u32) -> [u32; GOAL_TABLE_WORDS] {
    let mut table = [0u32; GOAL_TABLE_WORDS];
    for (i, entry) in (0u32..).zip(table.iter_mut()) {
        *entry = match i.checked_sub(GOAL_AXIS_CELLS as u32) {
            None => goal_axis_entry(i, gx, gy),
            Some(r) => STEP_CLASSES[r as usize],
        };
    }
    table
}

/// The per-axis goal table gives every cell's [`goal_region`]: every cell of a grid of
/// [`GOAL_AXIS_CELLS`] × [`GOAL_AXIS_CELLS`] (the largest the table serves: differences up to
/// ±511, the entries' largest values) around goals in the corners, on the edges, in the middle
/// and next to it, with every step code in the entry's low nibble; and both halves of every
/// entry stay below 2^14 (no carry between them).
#[test]
fn goal_axis_table_gives_every_cells_goal_region() {
    let last = GOAL_AXIS_CELLS as u32 - 1;
    let goals = [
        (0, 0),
        (last, 0),
        (0, last),
        (last, last),
        (1, last - 1),
        (255, 256),
        (256, 256),
        (300, 7),
        (last, 200),
        (17, 0),
    ];
    let mut regions = std::collections::BTreeSet::new();
    for (gx, gy) in goals {
        let table = goal_table(gx, gy);
        for &entry in &table[..GOAL_AXIS_CELLS] {
            assert!(
                entry >> 16 < 1 << 14 && entry & 0xFFFF < 1 << 14,
                "{entry:#x}"
            );
        }
        for y in 0..=last {
            for x in 0..=last {
                let node = y << 16 | x << 4 | (x ^ y) & 15;
                let region = goal_region(x as i32 - gx as i32, y as i32 - gy as i32);
                assert_eq!(
                    axis_region(&table, x as usize, node),
                    region,
                    "goal ({gx}, {gy}) cell ({x}, {y})"
                );
                regions.insert(region);
            }
        }
    }
    // Every sign code with every clamped difference it can have: off both axes 8 each, on
    // the column of the goal (`dx = 0`) −4 ..= −1, on its row 1 ..= 3, and the goal itself.
    assert_eq!(regions.len(), 4 * 8 + 2 * 4 + 2 * 3 + 1);
}

/// [`goal_region`] on the largest grids (sides of 4 096 cells: differences up to ±4 095, where
/// the search computes it per cell) and near the goal: for every step the class that
/// [`STEP_CLASSES`] gives is the step's reduced cost by the octile heuristic.
#[test]
fn goal_regions_give_reduced_costs_up_to_the_largest_grids() {
    let far = [
        -4095, -4094, -2049, -512, -511, -300, -5, -4, -3, -2, -1, 0, 1, 2, 3, 4, 5, 299, 511, 512,
        513, 2048, 4094, 4095,
    ];
    let h = |dx: i32, dy: i32| octile(dx.unsigned_abs(), dy.unsigned_abs()) as i64;
    for dx in far {
        for dy in far.iter().flat_map(|&v| [v, v + dx, v - dx]) {
            if (dx, dy) == (0, 0) {
                continue;
            }
            let classes = STEP_CLASSES[goal_region(dx, dy)];
            for (k, &(mx, my)) in STEPS.iter().enumerate() {
                let cost = if k + 1 >= NE as usize {
                    DIAGONAL_COST
                } else {
                    STRAIGHT_COST
                };
                let r = cost as i64 + h(dx + mx, dy + my) - h(dx, dy);
                let class = (classes >> (3 * k)) & 7;
                assert_eq!(
                    REDUCED_COSTS[class as usize] as i64, r,
                    "({dx}, {dy}) step {k}"
                );
            }
        }
    }
}

/// 20 % random obstacles on 300 × 300 cells (the benchmark's kind of map): the cell-by-cell A*
/// gives up its corridor walks midway (the instance of the loop with walks alone returns
/// `None` after some expansions) and goes on in the instance without them, handing over the
/// queue, the immediate target and the count: `pathfinding`'s cost, in both layouts with the
/// same cells expanded.
#[test]
fn astar_giving_up_corridor_walks_midway_keeps_the_optimal_cost() {
    const CELLS: usize = 300 * 300;
    let mut p = Box::new(Planner::<{ FRAMED_WORDS }, 3072>::new());
    for (seed, s, t) in [
        (7, Cell::new(0, 0), Cell::new(299, 299)),
        (11, Cell::new(299, 0), Cell::new(3, 296)),
        (13, Cell::new(150, 2), Cell::new(149, 297)),
    ] {
        let mut g = random_grid::<{ words_for_cells(CELLS) }>(300, 300, 20, seed);
        g.set(s, false);
        g.set(t, false);
        let geometry = *g.geometry();
        let si = geometry.index(s);
        let expected = oracle_astar(&g, s, t).unwrap();
        let framed = p.astar_in::<_, FRAMED_WORDS>(&g, si, t, true).unwrap();
        assert!(matches!(p.layout, Layout::Framed { .. }));
        let flat = p.astar_in::<_, FRAMED_WORDS>(&g, si, t, false).unwrap();
        assert!(matches!(p.layout, Layout::Flat));
        assert!(framed.found && flat.found);
        assert_eq!(
            (framed.cost, flat.cost),
            (expected, expected),
            "seed {seed}"
        );
        assert_eq!(framed.expanded, flat.expanded, "seed {seed}");
        // Every cell closed (by an expansion or a walk) is counted once.
        let closed = (0..CELLS)
            .filter(|&i| (1..=CODE_START).contains(&nibble(&p.scratch, i)))
            .count();
        assert_eq!(closed, flat.expanded as usize, "seed {seed}");

        // The instance with walks alone, from the start (the goal table is the search's).
        let mut words = std::vec![0u32; FRAMED_WORDS];
        let mut map = Framed::<FRAMED_WORDS>::new(&mut words, &geometry).unwrap();
        map.copy_map(&g);
        let (sx, sy) = (u32::from(s.x), u32::from(s.y));
        let mut pool = std::vec![OpenEntry { f: 0, node: 0, next: 0 }; 3072];
        let (mut open, mut state) = ClassQueue::new(&mut pool, 0);
        assert!(open.push(&mut state, 0, (sy << 16) | (sx << 4) | CODE_START));
        let (mut next, mut expanded, mut peak) = (NIL, 0, 0);
        let goal = map.index(usize::from(t.x), usize::from(t.y));
        let walks = astar_loop::<_, _, true, true>(
            &mut map,
            &mut open,
            &mut state,
            &mut next,
            &mut expanded,
            &p.goal_axis,
            (u32::from(t.x), u32::from(t.y)),
            goal,
            &mut peak,
        );
        assert!(walks.is_none(), "seed {seed}: walks not given up");
        assert!(0 < expanded && expanded < framed.expanded, "seed {seed}");
    }
}
