//! Jump point search (A* octile, BFS unit costs): the clutter count, the fallbacks, and the
//! search alone against `pathfinding`.

use super::*;
use crate::grid::GridGeometry;
use crate::plan::choice::{cluttered, JPS_STEPS_MAX_EXPANSIONS};

#[test]
fn jump_point_search_needs_few_entries_on_room_maps() {
    // Cell-by-cell A* with lazy deletion peaked above 8 000 entries on the office world; jump
    // point search uses a few dozen (heap and closed jump point records together).
    let (g, params) = world("office");
    let mut path = PathM::new();
    let mut small = Box::new(Planner::<SCRATCH_WORDS_300, 64>::new());
    let r = small
        .plan(PlannerKind::AStar, &g, params.start, params.goal, &mut path)
        .unwrap();
    assert_eq!(r.status, PlanStatus::Found);
    let (s, t) = (
        g.geometry().cell_of(params.start).unwrap(),
        g.geometry().cell_of(params.goal).unwrap(),
    );
    assert_eq!(Some(r.cost), oracle_astar(&g, s, t));
    assert!(small.queue_peak() <= 64);
    assert!(r.expanded < 100, "expanded {}", r.expanded);
}

#[test]
fn cluttered_maps_fall_back_to_cell_by_cell_astar_with_the_same_cost() {
    // 20 % random obstacles on 300 x 300 cells: nearly every free cell would be a jump point, so
    // the clutter count sends A* cell by cell at once (with reclaiming when a small queue
    // fills). Same optimal cost either way; the MCU's 2 300 entries, and even 1 024, suffice.
    let mut g = crate::grid::Grid300::new(GridGeometry::new(300, 300, 0.05).unwrap()).unwrap();
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    for y in 0..300 {
        for x in 0..300 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            if state % 100 < 20 {
                g.set_xy(x, y, true);
            }
        }
    }
    let (s, t) = (Cell::new(2, 2), Cell::new(297, 297));
    g.set(s, false);
    g.set(t, false);
    let expected = oracle_astar(&g, s, t);
    assert!(cluttered(g.words(), g.geometry(), s, t));
    for queue in [0usize, 1, 2] {
        let r = if queue == 2 {
            let mut p = Box::new(Planner::<SCRATCH_WORDS_300, 1024>::new());
            let r = p.plan_cells(PlannerKind::AStar, &g, s, t).unwrap();
            assert_eq!(steps_and_cost(p.path_cells()).1, r.cost);
            // 804 entries at most in use on this grid (no reclaiming needed).
            assert!(p.queue_peak() <= 900, "queue peak {}", p.queue_peak());
            r
        } else if queue == 0 {
            let mut big = Box::new(Planner::<SCRATCH_WORDS_300, 32768>::new());
            let r = big.plan_cells(PlannerKind::AStar, &g, s, t).unwrap();
            assert_eq!(steps_and_cost(big.path_cells()).1, r.cost);
            assert_collision_free(&g, big.path_cells());
            r
        } else {
            let mut p = Box::new(Planner300::new());
            let r = p.plan_cells(PlannerKind::AStar, &g, s, t).unwrap();
            assert_eq!(steps_and_cost(p.path_cells()).1, r.cost);
            assert_collision_free(&g, p.path_cells());
            r
        };
        assert_eq!(r.status == PlanStatus::Found, expected.is_some());
        if let Some(cost) = expected {
            assert_eq!(r.cost, cost);
            // About 28 800 cells, no jump points.
            assert!(r.expanded > 20_000, "expanded {}", r.expanded);
        }
    }
}

#[test]
fn the_clutter_count_keeps_jump_points_on_room_maps_and_open_floors() {
    // The seed's room worlds and an empty floor keep jump point search (a few dozen jump points
    // at most); a maze of 1-cell corridors is cluttered.
    for name in ["office", "corridor", "pillars"] {
        let (g, params) = world(name);
        let cell = |p| g.geometry().cell_of(p).unwrap();
        let (s, t) = (cell(params.start), cell(params.goal));
        assert!(!cluttered(g.words(), g.geometry(), s, t), "{name}");
        let mut p = Box::new(Planner300::new());
        let r = p.plan_cells(PlannerKind::AStar, &g, s, t).unwrap();
        assert!(r.expanded < 100, "{name}: expanded {}", r.expanded);
    }
    let open = crate::grid::Grid300::new(GridGeometry::new(300, 300, 0.05).unwrap()).unwrap();
    assert!(!cluttered(
        open.words(),
        open.geometry(),
        Cell::new(3, 5),
        Cell::new(296, 291)
    ));
    // Walls on even rows and columns, a gap in every wall: rooms of one cell.
    let mut maze = crate::grid::Grid300::new(GridGeometry::new(300, 300, 0.05).unwrap()).unwrap();
    for y in 0..300 {
        for x in 0..300 {
            if (x % 2 == 0 || y % 2 == 0) && (x + 3 * y) % 7 != 0 {
                maze.set_xy(x, y, true);
            }
        }
    }
    assert!(cluttered(
        maze.words(),
        maze.geometry(),
        Cell::new(1, 1),
        Cell::new(297, 297)
    ));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1024))]

    /// Jump point search on its own at every density (the planner only runs it on uncluttered
    /// maps): when it does not give up, the optimal cost and a path of that cost.
    #[test]
    fn jump_point_search_alone_matches_pathfinding((mut g, s, t) in arb_grid()) {
        g.set(s, false);
        g.set(t, false);
        if s == t {
            return Ok(());
        }
        let mut p = Box::new(SmallPlanner::new());
        if let Some(found) = jump_point_search_alone(&mut *p, &g, s, t) {
            prop_assert_eq!(found, oracle_astar(&g, s, t));
        }
    }
}

/// Unit-cost jump point search alone ([`Planner::jps_steps`], whatever the clutter count would
/// choose, with no limit on the jump points), on cleared scratch: `None` when it gave up (out
/// of entries), else the steps found (`None` inside when unreachable) after checking the
/// rebuilt path: from `s` to `t`, legal unit moves, as many as the search's cost.
fn jump_point_steps_alone<const W: usize, const S: usize, const Q: usize>(
    p: &mut Planner<S, Q>,
    g: &Grid<W>,
    s: Cell,
    t: Cell,
) -> Option<Option<u32>> {
    let geometry = *g.geometry();
    p.scratch.fill(0);
    p.cells.clear();
    let search = p
        .jps_steps(g, geometry.index(s), t, geometry.index(t), u32::MAX)
        .ok()?;
    if !search.found {
        return Some(None);
    }
    let (_, steps, fits) = p.rebuild_merged(&geometry, t, false);
    assert!(fits);
    assert_eq!(steps, search.cost);
    assert_eq!(legal_moves(g, p.path_cells()), search.cost);
    assert_eq!(p.path_cells().first(), Some(&s));
    assert_eq!(p.path_cells().last(), Some(&t));
    Some(Some(search.cost))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2048))]

    /// Unit-cost jump point search on its own at every density 0–45 % (the planner runs it
    /// for BFS on uncluttered maps only), with no limit on the jump points: pathfinding's
    /// fewest steps and a legal path of that many moves; unreachable exactly when pathfinding
    /// finds nothing. (A one-off run of 300 000 cases on grids up to 40 × 40 passed too.)
    /// (The pruning rules leave ties with unit costs, e.g. a diagonal step then the side step
    /// away from it costs 2, like the two side steps from the parent: this checks them.)
    #[test]
    fn jump_point_steps_alone_match_pathfinding_bfs((mut g, s, t) in arb_grid()) {
        g.set(s, false);
        g.set(t, false);
        if s == t {
            return Ok(());
        }
        let mut p = Box::new(SmallPlanner::new());
        // 4 096 entries: heap and records never run out on 24 × 24 cells here.
        let found = jump_point_steps_alone(&mut *p, &g, s, t);
        prop_assert!(found.is_some());
        prop_assert_eq!(found.unwrap(), oracle_bfs(&g, s, t));
    }
}

#[test]
fn bfs_on_the_bundled_worlds_runs_few_jump_points_with_pathfindings_steps() {
    // The room worlds are not cluttered: BFS runs jump points (8–15 of them instead of 46 000
    // – 65 000 cells reached by the layered search) for the same fewest steps. Ties on `f`
    // pop the larger `g` first: without that, pillars expands 22 jump points (queue peak 40).
    for (name, most) in [("office", 15), ("corridor", 8), ("pillars", 12)] {
        let (g, params) = world(name);
        let cell = |p| g.geometry().cell_of(p).unwrap();
        let (s, t) = (cell(params.start), cell(params.goal));
        let steps = oracle_bfs(&g, s, t).unwrap();
        let mut p = Box::new(Planner300::new());
        let r = p.plan_cells(PlannerKind::Bfs, &g, s, t).unwrap();
        assert_eq!(r.status, PlanStatus::Found, "{name}");
        assert_eq!(r.cost, steps, "{name}");
        assert!(r.expanded <= most, "{name}: expanded {}", r.expanded);
        assert!(
            p.queue_peak() <= 32,
            "{name}: queue peak {}",
            p.queue_peak()
        );
        assert_eq!(p.path_cells().first(), Some(&s));
        assert_eq!(p.path_cells().last(), Some(&t));
        assert_eq!(legal_moves(&g, p.path_cells()), steps, "{name}");
        // The layered search agrees.
        let layered = p
            .plan_cells_with(PlannerKind::Bfs, &g, s, t, false)
            .unwrap();
        assert_eq!(layered.cost, steps, "{name}");
        assert!(layered.expanded > 10_000, "{name}: {}", layered.expanded);
    }
}

#[test]
fn unit_cost_keys_hold_the_largest_grids() {
    // 4 096 cells long (the largest side): the heuristic reaches 4 095, all 12 bits of the
    // key's low part; jump points must not give up and must count the steps exactly.
    const CELLS: usize = 4096 * 2;
    for (w, h, s, t) in [
        (4096u32, 2u32, (0u16, 0u16), (4095u16, 1u16)),
        (2, 4096, (1, 4095), (0, 0)),
    ] {
        let mut g = Grid::<{ words_for_cells(CELLS) }>::new(GridGeometry::new(w, h, 0.05).unwrap())
            .unwrap();
        // A few walls across the long side, alternating sides, so the path turns.
        for k in 1..40i32 {
            let along = k * 100;
            let across = k % 2;
            if w > h {
                g.set_xy(along, across, true);
            } else {
                g.set_xy(across, along, true);
            }
        }
        let (s, t) = (Cell::new(s.0, s.1), Cell::new(t.0, t.1));
        let mut p = Box::new(Planner::<{ scratch_words_for_cells(CELLS) }, 256>::new());
        let steps = jump_point_steps_alone(&mut *p, &g, s, t);
        assert_eq!(steps, Some(oracle_bfs(&g, s, t)), "{w}x{h}");
        assert_eq!(steps, Some(Some(4095)), "{w}x{h}");
    }
}

#[test]
fn bfs_jump_points_fall_back_to_the_layered_search_counting_both() {
    // Random obstacles at 3 %: not cluttered by the count (about one run in 35 cells, the
    // limit is one in 32), yet more than JPS_STEPS_MAX_EXPANSIONS jump points with a wide open
    // list, so the search gives up and the layered BFS finds the steps; `expanded` counts both.
    let mut g = random_grid::<{ words_for_cells(300 * 300) }>(300, 300, 3, 7);
    let (s, t) = (Cell::new(2, 2), Cell::new(297, 297));
    g.set(s, false);
    g.set(t, false);
    let steps = oracle_bfs(&g, s, t).unwrap();
    let mut p = Box::new(Planner300::new());
    let geometry = *g.geometry();
    assert!(!cluttered(g.words(), &geometry, s, t));
    p.scratch.fill(0);
    let gave_up = p
        .jps_steps(
            &g,
            geometry.index(s),
            t,
            geometry.index(t),
            JPS_STEPS_MAX_EXPANSIONS,
        )
        .err();
    let r = p.plan_cells(PlannerKind::Bfs, &g, s, t).unwrap();
    assert_eq!(r.cost, steps);
    assert_eq!(legal_moves(&g, p.path_cells()), steps);
    let layered = p
        .plan_cells_with(PlannerKind::Bfs, &g, s, t, false)
        .unwrap();
    assert_eq!(gave_up, Some(JPS_STEPS_MAX_EXPANSIONS + 1));
    assert_eq!(r.expanded, layered.expanded + JPS_STEPS_MAX_EXPANSIONS + 1);
    // A queue of 8 entries: jump points run out of entries, the layered search needs none.
    let mut small = Box::new(Planner::<SCRATCH_WORDS_300, 8>::new());
    let r = small.plan_cells(PlannerKind::Bfs, &g, s, t).unwrap();
    assert_eq!(r.cost, steps);
    assert!(
        r.expanded > layered.expanded,
        "{} {}",
        r.expanded,
        layered.expanded
    );
}

#[test]
fn one_cell_wide_grids_match_pathfinding_cell_by_cell_and_by_jump_points() {
    // Every cell of a 1-wide or 1-high grid is on the border (the slow neighbourhood path).
    for (w, h) in [(1u32, 30u32), (30, 1), (2, 30), (30, 2)] {
        let mut g = SmallGrid::new(GridGeometry::new(w, h, 0.1).unwrap()).unwrap();
        for k in [5i32, 11, 17] {
            // A few blocked cells that leave a way round on 2-wide grids only.
            let (x, y) = if w <= 2 { (0, k) } else { (k, 0) };
            g.set_xy(x, y, true);
        }
        let (s, t) = (Cell::new(0, 0), Cell::new(w as u16 - 1, h as u16 - 1));
        let expected = oracle_astar(&g, s, t);
        let mut p = Box::new(SmallPlanner::new());
        let r = p.plan_cells(PlannerKind::AStar, &g, s, t).unwrap();
        assert_eq!(r.status == PlanStatus::Found, expected.is_some(), "{w}x{h}");
        if let Some(cost) = expected {
            assert_eq!(r.cost, cost, "{w}x{h}");
        }
        let si = g.geometry().index(s);
        let search = p.astar(&g, si, t).unwrap();
        assert_eq!(search.found.then_some(search.cost), expected, "{w}x{h}");
        if let Some(found) = jump_point_search_alone(&mut *p, &g, s, t) {
            assert_eq!(found, expected, "{w}x{h}");
        }
        let steps = jump_point_steps_alone(&mut *p, &g, s, t);
        assert_eq!(steps, Some(oracle_bfs(&g, s, t)), "{w}x{h}");
    }
}
