//! The layered BFS (both ends, grid bits, narrow grids, the scalar restart in mazes) against
//! `pathfinding::bfs`.

use super::*;
use crate::grid::GridGeometry;
use crate::plan::codes::STEPS;

#[test]
fn bfs_open_300_floods_two_half_balls() {
    // Layers on an open floor are Chebyshev rings. From both ends, each side floods about half
    // the distance, 146 layers: 150 columns × 152 rows round (3, 5), 150 × 155 round
    // (296, 291), plus part of one more ring (at most 303 cells) in the round where they meet;
    // one-sided it was every cell within 293 steps of (3, 5) (297 × 299 = 88 803 cells).
    // Frontier runs span many 32-row words and the frontier crosses every word edge.
    // (The planner runs jump points on an open floor: `plan_cells_with(.., false)` forces the
    // layered search.)
    let g = crate::grid::Grid300::new(GridGeometry::new(300, 300, 0.05).unwrap()).unwrap();
    let mut p = Box::new(Planner300::new());
    let r = p
        .plan_cells_with(
            PlannerKind::Bfs,
            &g,
            Cell::new(3, 5),
            Cell::new(296, 291),
            false,
        )
        .unwrap();
    assert_eq!(r.cost, 293);
    let balls = 150 * 152 + 150 * 155;
    assert!(
        (balls..=balls + 303).contains(&r.expanded),
        "{}",
        r.expanded
    );
    // 7 steps east and 286 diagonal ones, in at most three runs (the two walks down the sides
    // put the east run between diagonal ones).
    assert!(p.path_cells().len() <= 4, "{:?}", p.path_cells());
    assert_eq!(steps_and_cost(p.path_cells()).0, 293);
    assert_collision_free(&g, p.path_cells());
    // By jump points: the same steps, a handful of jump points, a legal path.
    let r = p
        .plan_cells(PlannerKind::Bfs, &g, Cell::new(3, 5), Cell::new(296, 291))
        .unwrap();
    assert_eq!(r.cost, 293);
    assert!(r.expanded <= 4, "{}", r.expanded);
    assert_eq!(legal_moves(&g, p.path_cells()), 293);
}

#[test]
fn bfs_matches_pathfinding_on_wide_and_tall_grids() {
    // Rows of several words (moves across word edges), columns of several 32-row words (long
    // vertical runs), obstacles from none to many.
    const CELLS: usize = 130 * 110;
    let mut p = Box::new(Planner::<{ scratch_words_for_cells(CELLS) }, 4096>::new());
    for (density, seed) in [(0u64, 1u64), (5, 2), (15, 3), (25, 4), (35, 5)] {
        let mut g = random_grid::<{ words_for_cells(CELLS) }>(130, 110, density, seed);
        for (s, t) in [
            ((0, 0), (129, 109)),
            ((127, 3), (1, 100)),
            ((31, 64), (96, 33)),
            ((64, 0), (63, 109)),
        ] {
            let (s, t) = (Cell::new(s.0, s.1), Cell::new(t.0, t.1));
            g.set(s, false);
            g.set(t, false);
            let r = p.plan_cells(PlannerKind::Bfs, &g, s, t).unwrap();
            let expected = oracle_bfs(&g, s, t);
            assert_eq!(
                r.status == PlanStatus::Found,
                expected.is_some(),
                "{density} {s:?} {t:?}"
            );
            if let Some(steps) = expected {
                assert_eq!(r.cost, steps, "density {density} {s:?} -> {t:?}");
                assert_eq!(steps_and_cost(p.path_cells()).0, steps);
                assert_eq!(p.path_cells().first(), Some(&s));
                assert_eq!(p.path_cells().last(), Some(&t));
                assert_collision_free(&g, p.path_cells());
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    /// A planner with exactly `scratch_words_for_cells` words for a 33..40-wide grid: the free
    /// plane does not fit, BFS reads the grid's bits in place. Same steps as pathfinding.
    #[test]
    fn bfs_without_the_free_plane_matches_pathfinding(
        w in 33u32..=40, h in 2u32..=40, density in 0u64..=40, seed in any::<u64>(),
        sx in 0u32..33, sy in 0u32..40, tx in 0u32..33, ty in 0u32..40,
    ) {
        const CELLS: usize = 40 * 40;
        let mut g = random_grid::<{ words_for_cells(CELLS) }>(w, h, density, seed);
        let (s, t) = (Cell::new(sx as u16, (sy % h) as u16), Cell::new(tx as u16, (ty % h) as u16));
        g.set(s, false);
        g.set(t, false);
        let mut p = Box::new(Planner::<{ scratch_words_for_cells(CELLS) }, 1600>::new());
        prop_assume!(crate::plan::bfs::BfsLayout::new(g.geometry(), scratch_words_for_cells(CELLS)).is_ok());
        let r = p.plan_cells(PlannerKind::Bfs, &g, s, t).unwrap();
        let expected = oracle_bfs(&g, s, t);
        prop_assert_eq!(r.status == PlanStatus::Found, expected.is_some());
        if let Some(steps) = expected {
            prop_assert_eq!(r.cost, steps);
            prop_assert_eq!(steps_and_cost(p.path_cells()).0, steps);
        }
    }
}

#[test]
fn bfs_layout_uses_the_grid_bits_when_the_free_plane_does_not_fit() {
    let fits = |w: u32, h: u32, words: usize| {
        crate::plan::bfs::BfsLayout::new(&GridGeometry::new(w, h, 0.05).unwrap(), words)
            .map(|l| (l.copies_free(), l.two_sided()))
    };
    // 300 x 300 in the 20 000 words of a 400 x 400 planner: four planes (12 000) and the row
    // sets, from both ends.
    assert_eq!(fits(300, 300, SCRATCH_WORDS_400), Ok((true, true)));
    // 300 x 300 in the 11 250 words of Planner300: three planes (9 000) and the row sets (the
    // free bits come from the grid), from both ends.
    assert_eq!(fits(300, 300, SCRATCH_WORDS_300), Ok((false, true)));
    // 40 x 40 in 200 words: two planes of 80 words, from the start only.
    assert_eq!(
        fits(40, 40, scratch_words_for_cells(1600)),
        Ok((false, false))
    );
    // 8 x 8 in 8 words: not even two planes fit; the error names what is needed.
    assert_eq!(
        fits(8, 8, scratch_words_for_cells(64)),
        Err(PlanError::ScratchTooSmall {
            // 2 planes, 4 row sets (2 sides × 2 parities) of 2 words, 4 summaries
            cells: 8 * (2 * 8 + 4 * 2 + 4),
            capacity: 64
        })
    );
    let g = Grid::<{ words_for_cells(64) }>::new(GridGeometry::new(8, 8, 0.05).unwrap()).unwrap();
    let mut p = Planner::<{ scratch_words_for_cells(64) }, 16>::new();
    assert!(matches!(
        p.plan_cells_with(
            PlannerKind::Bfs,
            &g,
            Cell::new(0, 0),
            Cell::new(7, 7),
            false
        ),
        Err(PlanError::ScratchTooSmall { .. })
    ));
    // BFS by jump points (an empty map is not cluttered) needs only the nibbles too.
    let r = p
        .plan_cells(PlannerKind::Bfs, &g, Cell::new(0, 0), Cell::new(7, 7))
        .unwrap();
    assert_eq!((r.status, r.cost), (PlanStatus::Found, 7));
    // A map that jump points give up on (the queue is too small for them) falls back to the
    // layered search, which reports what it needs.
    let mut g = g;
    for x in 0..7 {
        g.set_xy(x, 3, true);
    }
    let mut tiny = Planner::<{ scratch_words_for_cells(64) }, 1>::new();
    assert!(matches!(
        tiny.plan_cells(PlannerKind::Bfs, &g, Cell::new(0, 0), Cell::new(0, 7)),
        Err(PlanError::ScratchTooSmall { .. })
    ));
    // A* needs only its nibbles.
    assert!(p
        .plan_cells(PlannerKind::AStar, &g, Cell::new(0, 0), Cell::new(7, 7))
        .is_ok());
}

#[test]
fn bfs_in_mazes_switches_to_the_scalar_search_with_the_same_steps() {
    // 1-cell corridors: a frontier of 1-3 cells for hundreds of layers, so after
    // NARROW_CHECK_LAYER layers BFS restarts cell by cell (it then needs queue entries).
    const CELLS: usize = 121 * 121;
    let mut p = Box::new(Planner::<{ scratch_words_for_cells(CELLS) }, 256>::new());
    for seed in [1u64, 2, 3] {
        let g = maze::<{ words_for_cells(CELLS) }>(121, seed);
        for (s, t) in [
            ((1, 1), (119, 119)),
            ((119, 1), (1, 119)),
            ((61, 61), (1, 1)),
        ] {
            let (s, t) = (Cell::new(s.0, s.1), Cell::new(t.0, t.1));
            let steps = oracle_bfs(&g, s, t).unwrap();
            assert!(steps > 4 * crate::plan::bfs::NARROW_CHECK_LAYER, "{steps}");
            let r = match p.plan_cells(PlannerKind::Bfs, &g, s, t) {
                Ok(r) => r,
                Err(PlanError::PathFull { .. }) => p.last_report().unwrap(),
                Err(e) => panic!("{e}"),
            };
            assert_eq!(r.cost, steps, "seed {seed} {s:?} -> {t:?}");
            if !p.path_cells().is_empty() {
                assert_eq!(steps_and_cost(p.path_cells()).0, steps);
                assert_collision_free(&g, p.path_cells());
            }
            // The scalar search's queue: a few entries in a maze.
            assert!(p.queue_peak() < 64, "{}", p.queue_peak());
        }
    }
    // With no queue at all the scalar restart reports QueueFull instead of a wrong answer.
    let g = maze::<{ words_for_cells(CELLS) }>(121, 1);
    let mut none = Box::new(Planner::<{ scratch_words_for_cells(CELLS) }, 0>::new());
    assert_eq!(
        none.plan_cells(PlannerKind::Bfs, &g, Cell::new(1, 1), Cell::new(119, 119)),
        Err(PlanError::QueueFull { capacity: 0 })
    );
}

/// Plan with BFS and check against `pathfinding::bfs`: same reachability, `cost` = fewest
/// steps, a path of legal moves from `s` to `t` with that many steps.
fn check_bfs<const W: usize, const S: usize, const Q: usize>(
    p: &mut Planner<S, Q>,
    g: &Grid<W>,
    s: Cell,
    t: Cell,
) -> Result<(), TestCaseError> {
    let expected = oracle_bfs(g, s, t);
    // As the planner chooses (jump points unless cluttered), then the layered search alone.
    for jump_points in [true, false] {
        let r = p
            .plan_cells_with(PlannerKind::Bfs, g, s, t, jump_points)
            .unwrap();
        prop_assert_eq!(r.status == PlanStatus::Found, expected.is_some(), "{:?}", r);
        if let Some(steps) = expected {
            prop_assert_eq!(r.cost, steps);
            prop_assert_eq!(p.path_cells().first(), Some(&s));
            prop_assert_eq!(p.path_cells().last(), Some(&t));
            prop_assert_eq!(legal_moves(g, p.path_cells()), steps);
        }
    }
    Ok(())
}

/// A 3 × 3 ring of walls round `c` (clipped to the map), leaving `c` free.
fn enclose<const W: usize>(g: &mut Grid<W>, c: Cell) {
    for dy in -1..=1 {
        for dx in -1..=1 {
            if dx != 0 || dy != 0 {
                g.set_xy(c.x as i32 + dx, c.y as i32 + dy, true);
            }
        }
    }
    g.set(c, false);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1024))]

    /// BFS from both ends on small random grids (up to 24 × 24: the planes fit, both sides
    /// run): fewest steps as pathfinding, a legal path.
    #[test]
    fn bfs_two_sided_matches_pathfinding((mut g, s, t) in arb_grid()) {
        g.set(s, false);
        g.set(t, false);
        let mut p = Box::new(SmallPlanner::new());
        check_bfs(&mut *p, &g, s, t)?;
    }

    /// Start and goal next to each other (straight or diagonal, a diagonal possibly blocked by
    /// its side cells): one step, or the way round.
    #[test]
    fn bfs_adjacent_start_and_goal((mut g, s, _) in arb_grid(), k in 0usize..8) {
        let (dx, dy) = STEPS[k];
        let (tx, ty) = (s.x as i32 + dx, s.y as i32 + dy);
        prop_assume!(g.geometry().contains_xy(tx, ty));
        let t = Cell::new(tx as u16, ty as u16);
        g.set(s, false);
        g.set(t, false);
        let mut p = Box::new(SmallPlanner::new());
        check_bfs(&mut *p, &g, s, t)?;
    }

    /// An enclosed start or goal (a ring of walls round it): unreachable, whichever side runs
    /// out first; with one ring cell opened again, the way through it.
    #[test]
    fn bfs_enclosed_start_or_goal((mut g, s, t) in arb_grid(), goal in any::<bool>(), open in 0usize..9) {
        let c = if goal { t } else { s };
        enclose(&mut g, c);
        g.set(s, false);
        g.set(t, false);
        if let Some(&(dx, dy)) = STEPS.get(open) {
            let (x, y) = (c.x as i32 + dx, c.y as i32 + dy);
            if g.geometry().contains_xy(x, y) {
                g.set_xy(x, y, false);
            }
        }
        let mut p = Box::new(SmallPlanner::new());
        check_bfs(&mut *p, &g, s, t)?;
    }

    /// Narrow grids (1 to 3 cells wide or high) with obstacles: long thin searches.
    #[test]
    fn bfs_narrow_grids(
        long in 2u32..=40, thin in 1u32..=3, tall in any::<bool>(), density in 0u64..=30,
        seed in any::<u64>(), a in 0u32..120, b in 0u32..120,
    ) {
        const CELLS: usize = 40 * 3;
        let (w, h) = if tall { (thin, long) } else { (long, thin) };
        let mut g = random_grid::<{ words_for_cells(CELLS) }>(w, h, density, seed);
        let cell = |k: u32| Cell::new((k % w) as u16, ((k / w) % h) as u16);
        let (s, t) = (cell(a), cell(b));
        g.set(s, false);
        g.set(t, false);
        let mut p = Box::new(Planner::<{ 4 * CELLS }, 256>::new());
        check_bfs(&mut *p, &g, s, t)?;
    }

    /// Perfect mazes of 1-cell corridors between random rooms (short searches meet in the
    /// layered search, long ones restart cell by cell).
    #[test]
    fn bfs_mazes_match_pathfinding(
        rooms in 2i32..=20, seed in any::<u64>(), a in 0i32..400, b in 0i32..400,
    ) {
        const CELLS: usize = 41 * 41;
        let side = 2 * rooms + 1;
        let g = maze::<{ words_for_cells(CELLS) }>(side, seed);
        let room = |k: i32| Cell::new((2 * (k % rooms) + 1) as u16, (2 * ((k / rooms) % rooms) + 1) as u16);
        let mut p = Box::new(Planner::<{ scratch_words_for_cells(CELLS) }, 1024>::new());
        check_bfs(&mut *p, &g, room(a), room(b))?;
    }

    /// 33..40-wide grids in a scratch where the `SIDE` plane fits but the `FREE` plane does
    /// not: both sides read the grid's bits.
    #[test]
    fn bfs_two_sided_from_the_grid_bits_matches_pathfinding(
        w in 33u32..=40, h in 36u32..=40, density in 0u64..=40, seed in any::<u64>(),
        sx in 0u32..33, sy in 0u32..40, tx in 0u32..33, ty in 0u32..40,
    ) {
        const CELLS: usize = 40 * 40;
        // 3 planes of 2 × 40 words and 4 × 9 words of row sets fit, 4 planes of 2 × 36 do not.
        const WORDS: usize = 280;
        let g0 = random_grid::<{ words_for_cells(CELLS) }>(w, h, density, seed);
        let layout = crate::plan::bfs::BfsLayout::new(g0.geometry(), WORDS).unwrap();
        prop_assert!(layout.two_sided() && !layout.copies_free());
        let mut g = g0;
        let (s, t) = (Cell::new(sx as u16, (sy % h) as u16), Cell::new(tx as u16, (ty % h) as u16));
        g.set(s, false);
        g.set(t, false);
        let mut p = Box::new(Planner::<WORDS, 1600>::new());
        check_bfs(&mut *p, &g, s, t)?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    /// Grids of 3–5 words × 3–4 row blocks with start and goal anywhere: the sides start apart
    /// (no `SIDE` bits kept) and switch to keeping them when their blocks come near, or start
    /// near.
    #[test]
    fn bfs_sides_apart_then_near_match_pathfinding(
        w in 70u32..=160, h in 66u32..=110, density in 0u64..=35, seed in any::<u64>(),
        a in any::<u32>(), b in any::<u32>(),
    ) {
        const CELLS: usize = 160 * 110;
        let mut g = random_grid::<{ words_for_cells(CELLS) }>(w, h, density, seed);
        let cell = |k: u32| Cell::new((k % w) as u16, ((k / w) % h) as u16);
        let (s, t) = (cell(a), cell(b));
        g.set(s, false);
        g.set(t, false);
        let mut p = Box::new(Planner::<{ scratch_words_for_cells(CELLS) }, 4096>::new());
        check_bfs(&mut *p, &g, s, t)?;
    }
}
