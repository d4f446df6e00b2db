//! Whole planners (BFS, A*, any-angle) against the contract and the `pathfinding` oracle:
//! statuses, errors, path capacity, corner cutting, the bundled worlds, wide and sparse grids.

use super::*;
use crate::grid::GridGeometry;
use crate::plan::goal::GOAL_TABLE_WORDS;

const MAZE: &[&str] = &[
    "..........",
    ".########.",
    ".#......#.",
    ".#.####.#.",
    ".#.#..#.#.",
    ".#.#.##.#.",
    ".#.#....#.",
    ".#.######.",
    ".#........",
    "##########",
];

#[test]
fn maze_all_planners_agree_with_oracle() {
    let g = grid_from_rows(MAZE);
    let mut p = Box::new(SmallPlanner::new());
    let (s, t) = (Cell::new(4, 5), Cell::new(9, 1));
    let bfs = p.plan_cells(PlannerKind::Bfs, &g, s, t).unwrap();
    assert_eq!(bfs.status, PlanStatus::Found);
    assert_eq!(Some(bfs.cost), oracle_bfs(&g, s, t));
    assert_eq!(steps_and_cost(p.path_cells()).0, bfs.cost);
    assert_eq!(p.path_cells().first(), Some(&s));
    assert_eq!(p.path_cells().last(), Some(&t));
    assert_collision_free(&g, p.path_cells());

    let astar = p.plan_cells(PlannerKind::AStar, &g, s, t).unwrap();
    assert_eq!(Some(astar.cost), oracle_astar(&g, s, t));
    assert_eq!(steps_and_cost(p.path_cells()).1, astar.cost);
    assert_collision_free(&g, p.path_cells());
    let astar_len = exact_length(p.path_cells());
    assert!((astar.length_m as f64 - astar_len * 0.1).abs() < 1e-4);

    let any = p.plan_cells(PlannerKind::AnyAngle, &g, s, t).unwrap();
    assert_eq!(any.cost, astar.cost);
    assert_collision_free(&g, p.path_cells());
    assert!(exact_length(p.path_cells()) <= astar_len + 1e-9);
    assert!(any.length_m <= astar.length_m + 1e-5);
}

#[test]
fn corner_cutting_is_refused() {
    // The centre is blocked: no diagonal step may clip its corner, so the way round costs
    // four side steps, not 2 side + 1 diagonal.
    let g = grid_from_rows(&["...", ".#.", "..."]);
    let mut p = Box::new(SmallPlanner::new());
    let (s, t) = (Cell::new(0, 0), Cell::new(2, 2));
    let r = p.plan_cells(PlannerKind::AStar, &g, s, t).unwrap();
    assert_eq!(r.status, PlanStatus::Found);
    assert_eq!(r.cost, 4 * STRAIGHT_COST);
    let g2 = grid_from_rows(&[".#.", "#..", "..."]);
    // The top-left cell is reachable only diagonally between two occupied cells.
    let r2 = p
        .plan_cells(PlannerKind::Bfs, &g2, Cell::new(1, 1), Cell::new(0, 2))
        .unwrap();
    assert_eq!(r2.status, PlanStatus::Unreachable);
}

#[test]
fn statuses() {
    let g = grid_from_rows(&["...", ".#.", "..."]);
    let mut p = Box::new(SmallPlanner::new());
    let mut path = PathM::new();
    for kind in [PlannerKind::Bfs, PlannerKind::AStar, PlannerKind::AnyAngle] {
        let r = p
            .plan(
                kind,
                &g,
                PointM::new(0.15, 0.15),
                PointM::new(0.05, 0.05),
                &mut path,
            )
            .unwrap();
        assert_eq!(r.status, PlanStatus::StartBlocked);
        assert!(path.is_empty());
        let r = p
            .plan(
                kind,
                &g,
                PointM::new(0.05, 0.05),
                PointM::new(0.15, 0.15),
                &mut path,
            )
            .unwrap();
        assert_eq!(r.status, PlanStatus::GoalBlocked);
        for bad in [
            PointM::new(-0.01, 0.1),
            PointM::new(0.3, 0.1),
            PointM::new(f32::NAN, 0.1),
            PointM::new(0.1, f32::INFINITY),
        ] {
            let r = p
                .plan(kind, &g, bad, PointM::new(0.05, 0.05), &mut path)
                .unwrap();
            assert_eq!(r.status, PlanStatus::OutOfBounds);
            let r = p
                .plan(kind, &g, PointM::new(0.05, 0.05), bad, &mut path)
                .unwrap();
            assert_eq!(r.status, PlanStatus::OutOfBounds);
        }
        let r = p
            .plan(
                kind,
                &g,
                PointM::new(0.01, 0.01),
                PointM::new(0.09, 0.02),
                &mut path,
            )
            .unwrap();
        assert_eq!(r.status, PlanStatus::Found);
        assert_eq!(r.cost, 0);
        assert_eq!(path.as_slice(), &[PointM::new(0.05, 0.05)]);
        let r = p
            .plan(
                kind,
                &g,
                PointM::new(0.05, 0.05),
                PointM::new(0.25, 0.25),
                &mut path,
            )
            .unwrap();
        assert_eq!(r.status, PlanStatus::Found);
        assert_eq!(path.first(), Some(&PointM::new(0.05, 0.05)));
        assert_eq!(path.last(), Some(&PointM::new(0.25, 0.25)));
    }
    let walled = grid_from_rows(&[".#.", ".#.", ".#."]);
    for kind in [PlannerKind::Bfs, PlannerKind::AStar, PlannerKind::AnyAngle] {
        let r = p
            .plan_cells(kind, &walled, Cell::new(0, 0), Cell::new(2, 2))
            .unwrap();
        assert_eq!(r.status, PlanStatus::Unreachable);
        // BFS expands the 3 free cells of the left column; jump point search only the start
        // (its scans find no jump point).
        let least = if kind == PlannerKind::Bfs { 3 } else { 1 };
        assert!(r.expanded >= least, "{kind:?} expanded {}", r.expanded);
        assert!(p.path_cells().is_empty());
    }
}

#[test]
fn open_grid_path_is_one_segment_and_merged() {
    let g = SmallGrid::new(GridGeometry::new(40, 40, 0.05).unwrap()).unwrap();
    let mut p = Box::new(SmallPlanner::new());
    let r = p
        .plan_cells(PlannerKind::AStar, &g, Cell::new(0, 0), Cell::new(39, 0))
        .unwrap();
    assert_eq!(p.path_cells(), &[Cell::new(0, 0), Cell::new(39, 0)]);
    assert_eq!(r.cost, 39 * STRAIGHT_COST);
    assert!((r.length_m - 39.0 * 0.05).abs() < 1e-4);
    // Tie-breaking on larger g walks straight: few expansions.
    assert!(r.expanded <= 40, "expanded {}", r.expanded);
    let r = p
        .plan_cells(
            PlannerKind::AnyAngle,
            &g,
            Cell::new(0, 0),
            Cell::new(39, 10),
        )
        .unwrap();
    assert_eq!(p.path_cells(), &[Cell::new(0, 0), Cell::new(39, 10)]);
    assert!((r.length_m as f64 - (39f64.hypot(10.0)) * 0.05).abs() < 1e-4);
}

#[test]
fn scratch_too_small_and_queue_full_are_errors() {
    let g = SmallGrid::new(GridGeometry::new(40, 40, 0.05).unwrap()).unwrap();
    let mut tiny = Planner::<10, 4096>::new();
    assert_eq!(
        tiny.plan_cells(PlannerKind::AStar, &g, Cell::new(0, 0), Cell::new(1, 1)),
        Err(PlanError::ScratchTooSmall {
            cells: 1600,
            capacity: 80
        })
    );
    let mut short = Box::new(Planner::<{ scratch_words_for_cells(SMALL_CELLS) }, 4>::new());
    // BFS keeps its frontier in the scratch (bit planes and row sets), not in the queue.
    let r = short
        .plan_cells(PlannerKind::Bfs, &g, Cell::new(20, 20), Cell::new(0, 39))
        .unwrap();
    assert_eq!(
        Some(r.cost),
        oracle_bfs(&g, Cell::new(20, 20), Cell::new(0, 39))
    );
    assert_eq!(r.cost, 20);
    // On an open floor jump point search needs two entries (the start, then the jump point
    // next to the goal, plus its record): 4 are enough.
    let r = short
        .plan_cells(PlannerKind::AStar, &g, Cell::new(20, 20), Cell::new(0, 39))
        .unwrap();
    assert_eq!(r.cost, 19 * DIAGONAL_COST + STRAIGHT_COST);
    // Pillars on every other cell make every free cell a jump point: the 4 entries run out,
    // the cell-by-cell fallback too.
    let mut pillars = SmallGrid::new(GridGeometry::new(40, 40, 0.05).unwrap()).unwrap();
    for y in (1..40).step_by(2) {
        for x in (1..40).step_by(2) {
            pillars.set_xy(x, y, true);
        }
    }
    // An error keeps the last path (the open floor's).
    let kept = short.path_cells().to_vec();
    assert!(kept.len() >= 2);
    for kind in [PlannerKind::AStar, PlannerKind::AnyAngle] {
        assert_eq!(
            short.plan_cells(kind, &pillars, Cell::new(20, 20), Cell::new(0, 38)),
            Err(PlanError::QueueFull { capacity: 4 })
        );
        assert_eq!(short.path_cells(), &kept[..]);
    }
    let r = short
        .plan_cells(
            PlannerKind::Bfs,
            &pillars,
            Cell::new(20, 20),
            Cell::new(0, 38),
        )
        .unwrap();
    assert_eq!(
        Some(r.cost),
        oracle_bfs(&pillars, Cell::new(20, 20), Cell::new(0, 38))
    );
    assert_collision_free(&pillars, short.path_cells());
    let mut none = Box::new(Planner::<{ scratch_words_for_cells(SMALL_CELLS) }, 0>::new());
    let r = none
        .plan_cells(PlannerKind::Bfs, &g, Cell::new(20, 20), Cell::new(0, 39))
        .unwrap();
    assert_eq!(r.cost, 20);
    assert_eq!(
        none.plan_cells(PlannerKind::AStar, &g, Cell::new(20, 20), Cell::new(0, 39)),
        Err(PlanError::QueueFull { capacity: 0 })
    );
}

#[test]
fn path_full_keeps_the_report() {
    // A serpentine fits; a corridor that turns every two cells does not.
    const CELLS: usize = 200 * 200;
    let geometry = GridGeometry::new(200, 200, 0.05).unwrap();
    let mut g = Grid::<{ words_for_cells(CELLS) }>::new(geometry).unwrap();
    // Columns of walls with alternating gaps: a serpentine with 2 turns per column.
    for x in (1..200).step_by(2) {
        let gap_top = (x / 2) % 2 == 0;
        for y in 0..200 {
            let gap = if gap_top { y == 199 } else { y == 0 };
            if !gap {
                g.set_xy(x, y, true);
            }
        }
    }
    let mut p = Box::new(Planner::<{ scratch_words_for_cells(CELLS) }, 8192>::new());
    let mut path = PathM::new();
    let r = p.plan(
        PlannerKind::AStar,
        &g,
        geometry.center_of(Cell::new(0, 0)),
        geometry.center_of(Cell::new(198, 0)),
        &mut path,
    );
    // 100 columns of free cells, 2+ vertices each: about 300 vertices. Fits.
    let r = r.unwrap();
    assert_eq!(r.status, PlanStatus::Found);
    assert!(path.len() > 150, "{} vertices", path.len());
    let serpentine = p.path_cells().to_vec();
    // Two 2-row corridors 4000 cells long, joined at the east end, whose odd columns are open
    // in alternate rows: the path turns every two cells, about 4000 vertices (> MAX_PATH_POINTS).
    let long = GridGeometry::new(4000, 5, 0.05).unwrap();
    let mut g2 = Grid::<{ words_for_cells(CELLS) }>::new(long).unwrap();
    for x in 0..4000 {
        match x % 4 {
            1 => {
                g2.set_xy(x, 1, true);
                g2.set_xy(x, 4, true);
            }
            3 => {
                g2.set_xy(x, 0, true);
                g2.set_xy(x, 3, true);
            }
            _ => {}
        }
        if x < 3998 {
            g2.set_xy(x, 2, true);
        }
    }
    let err = p.plan(
        PlannerKind::Bfs,
        &g2,
        long.center_of(Cell::new(0, 0)),
        long.center_of(Cell::new(0, 3)),
        &mut path,
    );
    assert_eq!(
        err,
        Err(PlanError::PathFull {
            capacity: MAX_PATH_POINTS as u32
        })
    );
    assert!(path.is_empty());
    let last = p.last_report().unwrap();
    assert_eq!(last.status, PlanStatus::Found);
    // At least 3999 steps east and 3999 back west.
    assert!(last.cost >= 2 * 3999, "{}", last.cost);
    // The error kept the last path (the serpentine's), for every planner.
    assert_eq!(p.path_cells(), &serpentine[..]);
    assert!(last.expanded > 100);
    for kind in [PlannerKind::AStar, PlannerKind::AnyAngle] {
        let err = p.plan_at(
            kind,
            &g2,
            long.center_of(Cell::new(0, 0)),
            long.center_of(Cell::new(0, 3)),
        );
        assert!(
            matches!(err, Err(PlanError::PathFull { .. })),
            "{kind:?}: {err:?}"
        );
        assert_eq!(p.path_cells(), &serpentine[..], "{kind:?}");
    }
    // A planner whose queue cannot hold the last path counts the new one before writing it.
    let mut small = Box::new(Planner::<{ scratch_words_for_cells(CELLS) }, 32>::new());
    small
        .plan_at(
            PlannerKind::Bfs,
            &g,
            geometry.center_of(Cell::new(0, 0)),
            geometry.center_of(Cell::new(198, 0)),
        )
        .unwrap();
    let small_path = small.path_cells().to_vec();
    assert!(small_path.len() > 3 * 32, "{} vertices", small_path.len());
    let err = small.plan_at(
        PlannerKind::Bfs,
        &g2,
        long.center_of(Cell::new(0, 0)),
        long.center_of(Cell::new(0, 3)),
    );
    assert!(matches!(err, Err(PlanError::PathFull { .. })), "{err:?}");
    assert_eq!(small.path_cells(), &small_path[..]);
    // With no last path the overflowing one is not kept either.
    let mut fresh = Box::new(Planner::<{ scratch_words_for_cells(CELLS) }, 8192>::new());
    let err = fresh.plan_at(
        PlannerKind::AStar,
        &g2,
        long.center_of(Cell::new(0, 0)),
        long.center_of(Cell::new(0, 3)),
    );
    assert!(matches!(err, Err(PlanError::PathFull { .. })), "{err:?}");
    assert!(fresh.path_cells().is_empty());
}

#[test]
fn line_of_sight_is_symmetric_and_blocks() {
    let g = grid_from_rows(&["....", "..#.", "....", "...."]);
    let a = Cell::new(0, 0);
    let b = Cell::new(3, 3);
    assert!(!line_of_sight(&g, a, b));
    assert!(!line_of_sight(&g, b, a));
    assert!(
        line_of_sight(&g, Cell::new(0, 3), Cell::new(3, 0))
            == line_of_sight(&g, Cell::new(3, 0), Cell::new(0, 3))
    );
    assert!(!line_of_sight(&g, a, Cell::new(4, 0)), "off the grid");
    assert!(line_of_sight(&g, a, a));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn planners_match_pathfinding((g, s, t) in arb_grid()) {
        let mut p = Box::new(SmallPlanner::new());
        let bfs = p.plan_cells(PlannerKind::Bfs, &g, s, t).unwrap();
        let blocked = g.is_occupied(s) || g.is_occupied(t);
        if g.is_occupied(s) {
            prop_assert_eq!(bfs.status, PlanStatus::StartBlocked);
        } else if g.is_occupied(t) {
            prop_assert_eq!(bfs.status, PlanStatus::GoalBlocked);
        }
        if !blocked {
            let expected = oracle_bfs(&g, s, t);
            prop_assert_eq!(bfs.status == PlanStatus::Found, expected.is_some());
            if let Some(steps) = expected {
                prop_assert_eq!(bfs.cost, steps);
                prop_assert_eq!(steps_and_cost(p.path_cells()).0, steps);
                prop_assert_eq!(p.path_cells().first(), Some(&s));
                prop_assert_eq!(p.path_cells().last(), Some(&t));
                assert_collision_free(&g, p.path_cells());
            }
        }

        let astar = p.plan_cells(PlannerKind::AStar, &g, s, t).unwrap();
        prop_assert_eq!(astar.status, bfs.status);
        let astar_cells: Vec<Cell> = p.path_cells().to_vec();
        if astar.status == PlanStatus::Found {
            prop_assert_eq!(Some(astar.cost), oracle_astar(&g, s, t));
            prop_assert_eq!(steps_and_cost(&astar_cells).1, astar.cost);
            assert_collision_free(&g, &astar_cells);
            prop_assert_eq!(astar_cells.first(), Some(&s));
            prop_assert_eq!(astar_cells.last(), Some(&t));
        } else {
            prop_assert!(astar_cells.is_empty());
        }

        let any = p.plan_cells(PlannerKind::AnyAngle, &g, s, t).unwrap();
        prop_assert_eq!(any.status, astar.status);
        prop_assert_eq!(any.cost, astar.cost);
        prop_assert_eq!(any.expanded, astar.expanded);
        if any.status == PlanStatus::Found {
            let cells = p.path_cells();
            assert_collision_free(&g, cells);
            prop_assert_eq!(cells.first(), Some(&s));
            prop_assert_eq!(cells.last(), Some(&t));
            prop_assert!(exact_length(cells) <= exact_length(&astar_cells) + 1e-9);
            prop_assert!(any.length_m <= astar.length_m * (1.0 + 1e-5) + 1e-6);
            prop_assert!(cells.len() <= astar_cells.len());
        }
    }

    #[test]
    fn tiny_queues_never_panic((g, s, t) in arb_grid(), kind in 0u8..3) {
        let kind = [PlannerKind::Bfs, PlannerKind::AStar, PlannerKind::AnyAngle][kind as usize];
        let mut p = Box::new(Planner::<{ scratch_words_for_cells(SMALL_CELLS) }, 3>::new());
        match p.plan_cells(kind, &g, s, t) {
            Ok(r) => {
                if r.status == PlanStatus::Found {
                    assert_collision_free(&g, p.path_cells());
                }
            }
            Err(e) => prop_assert_eq!(e, PlanError::QueueFull { capacity: 3 }),
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// A small open list reclaims stale entries when it fills: it either finds exactly what a
    /// large one finds, or reports QueueFull; never a different cost.
    #[test]
    fn small_open_list_is_exact_or_full((g, s, t) in arb_grid()) {
        let mut big = Box::new(SmallPlanner::new());
        let mut small = Box::new(Planner::<{ scratch_words_for_cells(SMALL_CELLS) }, 48>::new());
        let expected = big.plan_cells(PlannerKind::AStar, &g, s, t).unwrap();
        match small.plan_cells(PlannerKind::AStar, &g, s, t) {
            Ok(r) => {
                // Equal-cost paths may differ: reclaiming reorders entries of equal f.
                prop_assert_eq!((r.status, r.cost), (expected.status, expected.cost));
                if r.status == PlanStatus::Found {
                    prop_assert_eq!(steps_and_cost(small.path_cells()).1, r.cost);
                    assert_collision_free(&g, small.path_cells());
                }
                prop_assert!(small.queue_peak() <= 48);
            }
            Err(e) => prop_assert_eq!(e, PlanError::QueueFull { capacity: 48 }),
        }
    }
}

#[test]
fn names_and_sizes() {
    assert_eq!(PlannerKind::AnyAngle.as_str(), "anyangle");
    assert_eq!(PlanStatus::StartBlocked.as_str(), "start_blocked");
    assert_eq!(PlanStatus::OutOfBounds.as_str(), "out_of_bounds");
    // 4 bits per cell for 300 x 300 cells, 12 bytes per queue entry, 4 bytes per vertex, the
    // A* goal table (512 axis entries, 128 step-class words).
    assert_eq!(SCRATCH_WORDS_300 * 4, 45_000);
    assert_eq!(GOAL_TABLE_WORDS * 4, 2_560);
    assert!(
        core::mem::size_of::<Planner300>()
            <= 45_000 + 3072 * 12 + MAX_PATH_POINTS * 4 + GOAL_TABLE_WORDS * 4 + 64
    );
}

#[test]
fn planner300_runs_every_bundled_world() {
    for name in ["office", "corridor", "pillars"] {
        let (g, params) = world(name);
        let mut big = Box::new(Planner::<SCRATCH_WORDS_300, 32768>::new());
        let mut p = Box::new(Planner300::new());
        let mut path = PathM::new();
        for kind in [PlannerKind::Bfs, PlannerKind::AStar, PlannerKind::AnyAngle] {
            let expected = big
                .plan(kind, &g, params.start, params.goal, &mut path)
                .unwrap();
            let r = p
                .plan(kind, &g, params.start, params.goal, &mut path)
                .unwrap();
            assert_eq!(r.status, PlanStatus::Found, "{name} {kind:?}");
            assert_eq!(r.cost, expected.cost, "{name} {kind:?}");
            if kind == PlannerKind::AStar {
                let cell = |p| g.geometry().cell_of(p).unwrap();
                let oracle = oracle_astar(&g, cell(params.start), cell(params.goal));
                assert_eq!(Some(r.cost), oracle, "{name}");
            }
            for pair in p.path_cells().windows(2) {
                assert!(line_of_sight(&g, pair[0], pair[1]), "{name} {kind:?}");
            }
        }
    }
}

#[test]
fn wide_grids_scan_columns_one_by_one_with_the_same_cost() {
    // More than 512 columns: the diagonal scans test their columns one at a time instead of
    // as a bit set. Same optimal cost as pathfinding on random obstacles and on a bare floor.
    const CELLS: usize = 700 * 24;
    let geometry = GridGeometry::new(700, 24, 0.05).unwrap();
    for density in [0u64, 12, 25] {
        let mut g = Grid::<{ words_for_cells(CELLS) }>::new(geometry).unwrap();
        let mut state = 0x2545_F491_4F6C_DD1Du64 ^ density;
        for y in 0..24 {
            for x in 0..700 {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                if state % 100 < density {
                    g.set_xy(x, y, true);
                }
            }
        }
        let mut p = Box::new(Planner::<{ scratch_words_for_cells(CELLS) }, 8192>::new());
        for (s, t) in [
            ((0, 0), (699, 23)),
            ((650, 3), (20, 20)),
            ((5, 23), (400, 0)),
        ] {
            let (s, t) = (Cell::new(s.0, s.1), Cell::new(t.0, t.1));
            g.set(s, false);
            g.set(t, false);
            let r = p.plan_cells(PlannerKind::AStar, &g, s, t).unwrap();
            let expected = oracle_astar(&g, s, t);
            assert_eq!(r.status == PlanStatus::Found, expected.is_some());
            if let Some(cost) = expected {
                assert_eq!(r.cost, cost, "density {density} {s:?} -> {t:?}");
                assert_eq!(steps_and_cost(p.path_cells()).1, cost);
                assert_collision_free(&g, p.path_cells());
            }
            // The planner runs the cluttered cases cell by cell: jump point search (its
            // column-by-column diagonal scans) on its own, too, up to where it gives up.
            if let Some(found) = jump_point_search_alone(&mut *p, &g, s, t) {
                assert_eq!(found, expected, "density {density} {s:?} -> {t:?}");
            }
        }
    }
}

#[test]
fn sparse_obstacles_on_many_words_match_pathfinding() {
    // Rows of several words (the diagonal scans' column bit sets span up to 7 words here),
    // sparse obstacles so that jump point search does not fall back: same optimal cost.
    const CELLS: usize = 210 * 90;
    let geometry = GridGeometry::new(210, 90, 0.05).unwrap();
    let mut p = Box::new(Planner::<{ scratch_words_for_cells(CELLS) }, 8192>::new());
    for density in [0u64, 2, 5, 9] {
        let mut g = Grid::<{ words_for_cells(CELLS) }>::new(geometry).unwrap();
        let mut state = 0x9E37_79B9_7F4A_7C15u64 ^ (density << 7);
        for y in 0..90 {
            for x in 0..210 {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                if state % 100 < density {
                    g.set_xy(x, y, true);
                }
            }
        }
        let pairs = [
            ((0, 0), (209, 89)),
            ((209, 0), (0, 89)),
            ((100, 45), (3, 2)),
            ((31, 88), (180, 1)),
            ((64, 10), (96, 80)),
        ];
        for (s, t) in pairs {
            let (s, t) = (Cell::new(s.0, s.1), Cell::new(t.0, t.1));
            g.set(s, false);
            g.set(t, false);
            let r = p.plan_cells(PlannerKind::AStar, &g, s, t).unwrap();
            let expected = oracle_astar(&g, s, t);
            assert_eq!(r.status == PlanStatus::Found, expected.is_some());
            if let Some(cost) = expected {
                assert_eq!(r.cost, cost, "density {density} {s:?} -> {t:?}");
                assert_eq!(steps_and_cost(p.path_cells()).1, cost);
                assert_collision_free(&g, p.path_cells());
            }
        }
    }
}
