//! Unit and property tests of the planners; the `pathfinding` crate is the oracle.

extern crate std;

use std::boxed::Box;
use std::vec::Vec;

use proptest::prelude::*;

use super::*;
use crate::grid::{words_for_cells, Grid};

const SMALL_CELLS: usize = 40 * 40;
type SmallGrid = Grid<{ words_for_cells(SMALL_CELLS) }>;
type SmallPlanner = Planner<{ scratch_words_for_cells(SMALL_CELLS) }, 4096>;

fn grid_from_rows(rows: &[&str]) -> SmallGrid {
    // rows[0] is the top row (largest y), as drawn.
    let h = rows.len() as u32;
    let w = rows[0].len() as u32;
    let mut g = SmallGrid::new(GridGeometry::new(w, h, 0.1).unwrap()).unwrap();
    for (r, row) in rows.iter().enumerate() {
        let y = h as i32 - 1 - r as i32;
        for (x, ch) in row.chars().enumerate() {
            if ch == '#' {
                g.set_xy(x as i32, y, true);
            }
        }
    }
    g
}

/// The neighbour rule, written independently for the oracle.
fn successors<const W: usize>(g: &Grid<W>, c: (i32, i32)) -> Vec<((i32, i32), u32)> {
    let free = |x: i32, y: i32| !g.is_occupied_xy(x, y);
    let mut out = Vec::new();
    for dx in -1..=1 {
        for dy in -1..=1 {
            if dx == 0 && dy == 0 {
                continue;
            }
            let (nx, ny) = (c.0 + dx, c.1 + dy);
            if !free(nx, ny) {
                continue;
            }
            if dx != 0 && dy != 0 {
                if free(c.0 + dx, c.1) && free(c.0, c.1 + dy) {
                    out.push(((nx, ny), DIAGONAL_COST));
                }
            } else {
                out.push(((nx, ny), STRAIGHT_COST));
            }
        }
    }
    out
}

fn oracle_astar<const W: usize>(g: &Grid<W>, s: Cell, t: Cell) -> Option<u32> {
    let goal = (t.x as i32, t.y as i32);
    pathfinding::prelude::astar(
        &(s.x as i32, s.y as i32),
        |&c| successors(g, c),
        |&(x, y)| octile(x.abs_diff(goal.0), y.abs_diff(goal.1)),
        |&c| c == goal,
    )
    .map(|(_, cost)| cost)
}

fn oracle_bfs<const W: usize>(g: &Grid<W>, s: Cell, t: Cell) -> Option<u32> {
    let goal = (t.x as i32, t.y as i32);
    pathfinding::prelude::bfs(
        &(s.x as i32, s.y as i32),
        |&c| successors(g, c).into_iter().map(|(n, _)| n),
        |&c| c == goal,
    )
    .map(|p| p.len() as u32 - 1)
}

/// Every segment of the polyline is free by the line-of-sight rule, and consecutive vertices
/// differ.
fn assert_collision_free<const W: usize>(g: &Grid<W>, cells: &[Cell]) {
    for pair in cells.windows(2) {
        assert_ne!(pair[0], pair[1], "repeated vertex in {cells:?}");
        assert!(
            line_of_sight(g, pair[0], pair[1]),
            "segment {:?} -> {:?} blocked",
            pair[0],
            pair[1]
        );
    }
}

/// Exact (f64) Euclidean length of a cell polyline, in cells.
fn exact_length(cells: &[Cell]) -> f64 {
    cells
        .windows(2)
        .map(|p| {
            let dx = p[0].x as f64 - p[1].x as f64;
            let dy = p[0].y as f64 - p[1].y as f64;
            (dx * dx + dy * dy).sqrt()
        })
        .sum()
}

/// A merged BFS/A* polyline: segments are straight or 45° runs; returns (steps, octile cost).
fn steps_and_cost(cells: &[Cell]) -> (u32, u32) {
    let (mut steps, mut cost) = (0, 0);
    for p in cells.windows(2) {
        let dx = p[0].x.abs_diff(p[1].x) as u32;
        let dy = p[0].y.abs_diff(p[1].y) as u32;
        assert!(
            dx == 0 || dy == 0 || dx == dy,
            "not an 8-direction run: {p:?}"
        );
        steps += dx.max(dy);
        cost += octile(dx, dy);
    }
    (steps, cost)
}

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

// ---------------------------------------------------------------------------------------------
// Property tests against the oracle.

fn arb_grid() -> impl Strategy<Value = (SmallGrid, Cell, Cell)> {
    (2u32..=24, 2u32..=24, 0u32..=45, any::<u64>())
        .prop_flat_map(|(w, h, density, seed)| {
            (Just((w, h, density, seed)), 0..w, 0..h, 0..w, 0..h)
        })
        .prop_map(|((w, h, density, seed), sx, sy, tx, ty)| {
            let mut g = SmallGrid::new(GridGeometry::new(w, h, 0.1).unwrap()).unwrap();
            let mut state = seed | 1;
            for y in 0..h as i32 {
                for x in 0..w as i32 {
                    // xorshift64
                    state ^= state << 13;
                    state ^= state >> 7;
                    state ^= state << 17;
                    if (state % 100) < density as u64 {
                        g.set_xy(x, y, true);
                    }
                }
            }
            (
                g,
                Cell::new(sx as u16, sy as u16),
                Cell::new(tx as u16, ty as u16),
            )
        })
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

// ---------------------------------------------------------------------------------------------
// Pruning and the band check.

fn along_path_length(path: &[PointM]) -> f64 {
    path.windows(2)
        .map(|p| ((p[1].x_m - p[0].x_m) as f64).hypot((p[1].y_m - p[0].y_m) as f64))
        .sum()
}

#[test]
fn prune_cuts_at_range_mid_segment() {
    let g = SmallGrid::new(GridGeometry::new(40, 40, 0.1).unwrap()).unwrap();
    let path = [
        PointM::new(0.55, 0.55),
        PointM::new(2.55, 0.55),
        PointM::new(2.55, 3.55),
    ];
    let mut out = PathM::new();
    let pruned = prune_visible_prefix(&g, &path, 3.0, &mut out);
    assert_eq!(pruned.end, PruneEnd::Range);
    assert_eq!(out.len(), 3);
    assert_eq!(&out[..2], &path[..2]);
    assert!((out[2].x_m - 2.55).abs() < 1e-5);
    assert!((out[2].y_m - 1.55).abs() < 1e-4, "{:?}", out[2]);
    assert!((pruned.length_m - 3.0).abs() < 1e-5);

    let pruned = prune_visible_prefix(&g, &path, 100.0, &mut out);
    assert_eq!(pruned.end, PruneEnd::PathEnd);
    assert_eq!(out.as_slice(), &path);
    assert!((pruned.length_m - 5.0).abs() < 1e-4);
}

#[test]
fn prune_stops_where_a_wall_hides_the_path() {
    // A wall along x = 2.0 m from y = 1.5 m upwards; the path runs south, east below the wall's
    // end, then north behind it. The part behind the wall is hidden from the start.
    let mut g = SmallGrid::new(GridGeometry::new(40, 40, 0.1).unwrap()).unwrap();
    for y in 15..40 {
        g.set_xy(20, y, true);
    }
    let path = [
        PointM::new(0.55, 2.55),
        PointM::new(0.55, 0.55),
        PointM::new(2.55, 0.55),
        PointM::new(2.55, 3.55),
    ];
    let mut out = PathM::new();
    let pruned = prune_visible_prefix(&g, &path, 100.0, &mut out);
    assert_eq!(pruned.end, PruneEnd::Hidden);
    assert_eq!(&out[..3], &path[..3]);
    assert_eq!(out.len(), 4);
    let cut = out[3];
    assert!((cut.x_m - 2.55).abs() < 1e-5);
    assert!(cut.y_m > 0.55 && cut.y_m < 3.55, "{cut:?}");
    for p in out.iter() {
        assert!(line_of_sight_m(&g, out[0], *p), "{p:?} not visible");
    }
    // A little further along the last segment is no longer visible.
    let beyond = PointM::new(2.55, cut.y_m + 0.1);
    assert!(!line_of_sight_m(&g, out[0], beyond));
    assert!((pruned.length_m as f64 - along_path_length(&out)).abs() < 1e-4);
}

#[test]
fn prune_degenerate_inputs() {
    let mut g = SmallGrid::new(GridGeometry::new(10, 10, 0.1).unwrap()).unwrap();
    let mut out = PathM::new();
    let p = prune_visible_prefix(&g, &[], 3.0, &mut out);
    assert_eq!((p.end, out.len()), (PruneEnd::PathEnd, 0));
    let path = [PointM::new(0.15, 0.15), PointM::new(0.85, 0.15)];
    for range in [0.0, -1.0, f32::NAN, f32::NEG_INFINITY] {
        let p = prune_visible_prefix(&g, &path, range, &mut out);
        assert_eq!((p.end, out.as_slice()), (PruneEnd::Range, &path[..1]));
    }
    let p = prune_visible_prefix(&g, &[PointM::new(-1.0, 0.0), path[1]], 3.0, &mut out);
    assert_eq!((p.end, out.len()), (PruneEnd::Hidden, 1));
    let p = prune_visible_prefix(&g, &[path[0], PointM::new(f32::NAN, 0.1)], 3.0, &mut out);
    assert_eq!((p.end, out.len()), (PruneEnd::Hidden, 1));
    // Repeated points are skipped, not emitted twice.
    let p = prune_visible_prefix(&g, &[path[0], path[0], path[1]], 3.0, &mut out);
    assert_eq!((p.end, out.as_slice()), (PruneEnd::PathEnd, &path[..]));
    g.set_xy(1, 1, true);
    let p = prune_visible_prefix(&g, &path, 3.0, &mut out);
    assert_eq!((p.end, out.len()), (PruneEnd::Hidden, 1));
    // An absurd range on a long path cannot hang: samples are capped.
    let far = [PointM::new(0.15, 0.15), PointM::new(0.15, 1.0e30)];
    let p = prune_visible_prefix(&g, &far, f32::MAX, &mut out);
    assert_eq!(p.end, PruneEnd::Hidden);
}

#[test]
fn band_check_matches_the_seed_rule() {
    let pose = PointM::new(5.0, 5.0);
    let at = |deg: f32| {
        let r = deg.to_radians();
        PointM::new(5.0 + r.cos(), 5.0 + r.sin())
    };
    let band = NORMAL_HALF_BAND_RAD;
    assert!(!needs_full_sweep(
        &[pose, at(0.0), at(90.0), at(-94.0)],
        pose,
        0.0,
        band
    ));
    assert!(needs_full_sweep(
        &[pose, at(0.0), at(96.0)],
        pose,
        0.0,
        band
    ));
    assert!(needs_full_sweep(&[at(-170.0)], pose, 0.0, band));
    // Heading 180°: behind is now ahead; wrap-around at ±π.
    assert!(!needs_full_sweep(
        &[at(170.0), at(-170.0)],
        pose,
        core::f32::consts::PI,
        band
    ));
    assert!(needs_full_sweep(
        &[at(0.0)],
        pose,
        core::f32::consts::PI,
        band
    ));
    // The robot's own position has no direction.
    assert!(!needs_full_sweep(&[pose], pose, 0.0, band));
    assert!(!needs_full_sweep(&[], pose, 0.0, band));
    assert!(needs_full_sweep(&[at(0.0)], pose, f32::NAN, band));
    assert!(needs_full_sweep(
        &[PointM::new(f32::NAN, 0.0)],
        pose,
        0.0,
        band
    ));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn pruned_prefix_is_visible_and_in_range((g, s, t) in arb_grid(), range_m in 0.05f32..3.0) {
        let mut p = Box::new(SmallPlanner::new());
        let mut path = PathM::new();
        let geometry = *g.geometry();
        let r = p.plan(PlannerKind::AnyAngle, &g, geometry.center_of(s), geometry.center_of(t), &mut path).unwrap();
        prop_assume!(r.status == PlanStatus::Found);
        let mut out = PathM::new();
        let pruned = prune_visible_prefix(&g, &path, range_m, &mut out);
        prop_assert!(!out.is_empty());
        prop_assert_eq!(out[0], path[0]);
        // A prefix: all but the last kept point are path vertices, in order.
        let n = out.len();
        prop_assert_eq!(&out[..n - 1], &path[..n - 1]);
        for q in out.iter() {
            prop_assert!(line_of_sight_m(&g, out[0], *q), "{:?} hidden", q);
        }
        let along = along_path_length(&out);
        prop_assert!(along <= range_m as f64 + 1e-4, "{} > {}", along, range_m);
        prop_assert!((pruned.length_m as f64 - along).abs() < 1e-3);
        if pruned.end == PruneEnd::PathEnd {
            prop_assert_eq!(out.as_slice(), path.as_slice());
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

/// A bundled world (`worlds/NAME`), obstacles grown by the robot radius.
fn world(name: &str) -> (crate::grid::Grid300, crate::world::Params) {
    use crate::world::{parse_da, parse_par, Obstacles};
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../worlds/");
    let read = |ext: &str| std::fs::read_to_string(std::format!("{dir}{name}.{ext}")).unwrap();
    let params = parse_par(&read("par")).unwrap();
    let mut obstacles = Obstacles::new();
    parse_da(&read("da"), &mut obstacles).unwrap();
    let mut g = crate::grid::Grid300::new(GridGeometry::seed_default()).unwrap();
    let half_side = g.geometry().expansion_cells(params.robot_radius_m);
    for polygon in obstacles.iter() {
        crate::raster::mark_polygon(&mut g, polygon, half_side);
    }
    (g, params)
}

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

/// The cell-by-cell A* from `s` to `t` (after [`Planner::copy_map`]) with the goal regions
/// from the per-axis table and computed per cell: the same result (found, cells expanded,
/// cost, or the same error and queue peak) and the same nibbles (closed cells and their
/// parent codes) afterwards; the scratch is left as the second search left it.
fn astar_both_region_ways<const GW: usize, const S: usize, const Q: usize>(
    p: &mut Planner<S, Q>,
    g: &Grid<GW>,
    s: Cell,
    t: Cell,
) -> Result<Search, PlanError> {
    let si = g.geometry().index(s);
    let used = scratch_words_for_cells(g.geometry().cell_count());
    let outcome = |r: &Result<Search, PlanError>| match r {
        Ok(s) => Ok((s.found, s.expanded, s.cost)),
        Err(e) => Err(*e),
    };
    let table = p.astar_in::<GW, SMALL_FRAMED, true>(g, si, t, false);
    let (table_nibbles, table_peak) = (p.scratch[..used].to_vec(), p.queue_peak);
    let direct = p.astar_in::<GW, SMALL_FRAMED, false>(g, si, t, false);
    assert_eq!(outcome(&table), outcome(&direct), "{s:?} -> {t:?}");
    assert_eq!(table_peak, p.queue_peak, "{s:?} -> {t:?}");
    assert!(table_nibbles == p.scratch[..used], "{s:?} -> {t:?}");
    direct
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
    let mut found = 0;
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
            let search = astar_both_region_ways(&mut *p, &g, s, t).unwrap();
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
}

/// The line of sight walked with [`crate::raster::BresenhamLine`] and the grid's checked
/// accessors, cell by cell: the reference for the index-stepping [`line_of_sight`].
fn line_of_sight_reference<const W: usize>(grid: &Grid<W>, a: Cell, b: Cell) -> bool {
    let (from, to) = if (a.y, a.x) <= (b.y, b.x) {
        (a, b)
    } else {
        (b, a)
    };
    let (mut px, mut py) = (from.x as i32, from.y as i32);
    for (x, y) in crate::raster::BresenhamLine::new((px, py), (to.x as i32, to.y as i32)) {
        if grid.is_occupied_xy(x, y) {
            return false;
        }
        if x != px && y != py && (grid.is_occupied_xy(x, py) || grid.is_occupied_xy(px, y)) {
            return false;
        }
        px = x;
        py = y;
    }
    true
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1024))]

    #[test]
    fn line_of_sight_equals_the_cell_by_cell_walk(
        (g, s, t) in arb_grid(),
        off in 0u16..3,
    ) {
        // `off` moves the far end off the map now and then.
        let t = Cell::new(t.x + off * 20, t.y);
        prop_assert_eq!(line_of_sight(&g, s, t), line_of_sight_reference(&g, s, t));
        prop_assert_eq!(line_of_sight(&g, t, s), line_of_sight_reference(&g, s, t));
    }
}

/// A grid of `w` × `h` cells with `density` % occupied cells (xorshift from `seed`).
fn random_grid<const W: usize>(w: u32, h: u32, density: u64, seed: u64) -> Grid<W> {
    let mut g = Grid::<W>::new(GridGeometry::new(w, h, 0.05).unwrap()).unwrap();
    let mut state = seed | 1;
    for y in 0..h as i32 {
        for x in 0..w as i32 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            if state % 100 < density {
                g.set_xy(x, y, true);
            }
        }
    }
    g
}

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
        prop_assume!(super::bfs::BfsLayout::new(g.geometry(), scratch_words_for_cells(CELLS)).is_ok());
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

/// Jump point search alone (whatever the clutter count would choose), on cleared scratch:
/// `None` when it gave up (cluttered or out of entries), else the cost found (`None` inside when
/// unreachable) after checking the rebuilt path's cost and collisions.
fn jump_point_search_alone<const W: usize, const S: usize, const Q: usize>(
    p: &mut Planner<S, Q>,
    g: &Grid<W>,
    s: Cell,
    t: Cell,
) -> Option<Option<u32>> {
    let geometry = *g.geometry();
    p.scratch.fill(0);
    p.cells.clear();
    let search = p.jps(g, geometry.index(s), t, geometry.index(t)).ok()?;
    if !search.found {
        return Some(None);
    }
    let (_, _, fits) = p.rebuild_merged(&geometry, t, false);
    assert!(fits);
    assert_eq!(steps_and_cost(p.path_cells()).1, search.cost);
    assert_collision_free(g, p.path_cells());
    assert_eq!(p.path_cells().first(), Some(&s));
    Some(Some(search.cost))
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

#[test]
fn bfs_layout_uses_the_grid_bits_when_the_free_plane_does_not_fit() {
    let fits = |w: u32, h: u32, words: usize| {
        super::bfs::BfsLayout::new(&GridGeometry::new(w, h, 0.05).unwrap(), words)
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

/// A perfect maze (recursive backtracker, xorshift from `seed`) of `side` × `side` cells with
/// 1-cell corridors: rooms on odd coordinates.
fn maze<const W: usize>(side: i32, seed: u64) -> Grid<W> {
    let mut g = Grid::<W>::new(GridGeometry::new(side as u32, side as u32, 0.05).unwrap()).unwrap();
    for y in 0..side {
        g.fill_row(y, 0, side - 1);
    }
    let rooms = (side - 1) / 2;
    let mut visited = std::vec![false; (rooms * rooms) as usize];
    let mut stack = std::vec![(0i32, 0i32)];
    visited[0] = true;
    g.set_xy(1, 1, false);
    let mut state = seed | 1;
    while let Some(&(rx, ry)) = stack.last() {
        let options: Vec<(i32, i32)> = [(1, 0), (-1, 0), (0, 1), (0, -1)]
            .into_iter()
            .filter(|&(dx, dy)| {
                let (nx, ny) = (rx + dx, ry + dy);
                nx >= 0
                    && ny >= 0
                    && nx < rooms
                    && ny < rooms
                    && !visited[(ny * rooms + nx) as usize]
            })
            .collect();
        if options.is_empty() {
            stack.pop();
            continue;
        }
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        let (dx, dy) = options[(state % options.len() as u64) as usize];
        let (nx, ny) = (rx + dx, ry + dy);
        visited[(ny * rooms + nx) as usize] = true;
        g.set_xy(2 * rx + 1 + dx, 2 * ry + 1 + dy, false);
        g.set_xy(2 * nx + 1, 2 * ny + 1, false);
        stack.push((nx, ny));
    }
    g
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
            assert!(steps > 4 * super::bfs::NARROW_CHECK_LAYER, "{steps}");
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

// ---------------------------------------------------------------------------------------------
// Corridor contraction of the cell-by-cell A*.

/// xorshift64 step for the grid generators below.
fn next_random(state: &mut u64) -> u64 {
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    *state
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

/// Walks a merged BFS polyline unit move by unit move: every move is legal (target free, a
/// diagonal's two side cells free). Returns the number of moves.
fn legal_moves<const W: usize>(g: &Grid<W>, cells: &[Cell]) -> u32 {
    let free = |x: i32, y: i32| g.geometry().contains_xy(x, y) && !g.is_occupied_xy(x, y);
    let mut moves = 0;
    for pair in cells.windows(2) {
        let (mut x, mut y) = (pair[0].x as i32, pair[0].y as i32);
        let (tx, ty) = (pair[1].x as i32, pair[1].y as i32);
        let (dx, dy) = ((tx - x).signum(), (ty - y).signum());
        assert!(
            (tx - x).abs() == 0 || (ty - y).abs() == 0 || (tx - x).abs() == (ty - y).abs(),
            "not an 8-direction run: {pair:?}"
        );
        assert!(free(x, y), "vertex {pair:?} occupied");
        while (x, y) != (tx, ty) {
            assert!(free(x + dx, y + dy), "move into ({}, {})", x + dx, y + dy);
            if dx != 0 && dy != 0 {
                assert!(
                    free(x + dx, y) && free(x, y + dy),
                    "corner cut at ({x}, {y})"
                );
            }
            x += dx;
            y += dy;
            moves += 1;
        }
    }
    moves
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
        let layout = super::bfs::BfsLayout::new(g0.geometry(), WORDS).unwrap();
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

// ---------------------------------------------------------------------------------------------
// The open list of the cell-by-cell A* by reduced-cost class.

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

/// The queue alone against a reference (an ordered set of `(key, node)`): random
/// interleavings of pushes (keys the last popped key plus 0 or a reduced cost, or any larger
/// key, also through the far list), pops and reclaims (`collect` of a random subset of nodes)
/// pop the reference's smallest key every time, each live node exactly once; a push is refused
/// exactly when the 64 entries are all live.
#[test]
fn class_queue_pops_keys_in_order_like_a_reference() {
    use std::collections::BTreeSet;
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    for round in 0..500 {
        let mut pool = std::vec![OpenEntry::ZERO; 64];
        let first = (next_random(&mut state) % 100_000) as u32;
        let (mut q, mut s) = ClassQueue::new(&mut pool, first);
        let mut reference = BTreeSet::new();
        let mut next_node = 0u32;
        let mut last = first;
        let steps = 20 + next_random(&mut state) % 400;
        for _ in 0..steps {
            let roll = next_random(&mut state) % 100;
            if roll < 55 {
                let r = match next_random(&mut state) % 8 {
                    0 | 1 => 0,
                    7 => 1 + (next_random(&mut state) % 40_000) as u32,
                    k => REDUCED_COSTS[(k - 2) as usize],
                };
                let key = last + r;
                let ok = if next_random(&mut state).is_multiple_of(4) {
                    q.push_far(&mut s, key, next_node)
                } else {
                    q.push(&mut s, key, next_node)
                };
                assert_eq!(ok, reference.len() < 64, "round {round}");
                if ok {
                    reference.insert((key, next_node));
                }
                next_node += 1;
            } else if roll < 97 {
                let got = Some(q.pop(&mut s))
                    .filter(|&n| n != NIL)
                    .map(|n| (s.last, n));
                let want = reference.first().map(|&(k, _)| k);
                assert_eq!(got.map(|(k, _)| k), want, "round {round}");
                if let Some((k, n)) = got {
                    assert!(
                        reference.remove(&(k, n)),
                        "round {round}: node {n} not live"
                    );
                    assert_eq!(s.last, k);
                    last = k;
                }
            } else {
                let m = 2 + (next_random(&mut state) % 3) as u32;
                let before = reference.len();
                let (after, freed) = q.collect(s, |n| n % m == 0);
                s = after;
                reference.retain(|&(_, n)| n % m != 0);
                assert_eq!(freed, before - reference.len(), "round {round}");
            }
        }
        // Drain: the rest comes out in order too.
        while let Some(&(k, _)) = reference.first() {
            let n = q.pop(&mut s);
            let gk = s.last;
            assert_eq!(gk, k, "round {round}");
            assert!(reference.remove(&(gk, n)));
        }
        assert_eq!(q.pop(&mut s), NIL);
        assert!(s.bump <= 64);
    }
}

/// The ring queue against the linked class queue, fed the same random interleavings of
/// pushes (all classes, the far list), pops and reclaims: while the rings accept the pushes,
/// every pop returns the same node with the same key (the same order, ties included), and a
/// reclaim drops the same number of entries. A push is refused only when its ring (or the far
/// array, or the stack) is full.
#[test]
fn ring_queue_pops_like_class_queue() {
    let mut state = 0x2545_F491_4F6C_DD1Du64;
    let mut refused = 0;
    for round in 0..500 {
        // Tiny pools too: some rings get no slot at all (always full).
        let size = [64usize, 200, 1024, 3, 6][round % 5];
        let mut ring_pool = std::vec![OpenEntry::ZERO; size];
        let mut list_pool = std::vec![OpenEntry::ZERO; 4 * size];
        let first = (next_random(&mut state) % 100_000) as u32;
        let (mut rq, mut rs) = <RingQueue as OpenList>::new(&mut ring_pool, first);
        let (mut lq, mut ls) = ClassQueue::new(&mut list_pool, first);
        let mut live = 0usize;
        let mut next_node = 0u32;
        let mut last = first;
        let steps = 20 + next_random(&mut state) % 2000;
        for _ in 0..steps {
            let roll = next_random(&mut state) % 100;
            if roll < 55 {
                let r = match next_random(&mut state) % 8 {
                    0 | 1 => 0,
                    7 => 1 + (next_random(&mut state) % 40_000) as u32,
                    k => REDUCED_COSTS[(k - 2) as usize],
                };
                let key = last + r;
                let far = next_random(&mut state).is_multiple_of(4);
                let ok = if far {
                    OpenList::push_far(&mut rq, &mut rs, key, next_node)
                } else {
                    OpenList::push(&mut rq, &mut rs, key, next_node)
                };
                if ok {
                    let pushed = if far {
                        lq.push_far(&mut ls, key, next_node)
                    } else {
                        lq.push(&mut ls, key, next_node)
                    };
                    assert!(pushed, "round {round}");
                    live += 1;
                } else {
                    refused += 1;
                    let full = match reduced_cost_class(key - last) {
                        _ if far => rq.far_len == rq.far_cap,
                        None => rq.far_len == rq.far_cap,
                        Some(0) => rs.stack as usize == size,
                        Some(c) => {
                            let (len, cap) = rq.ring_fill(c);
                            len == cap
                        }
                    };
                    assert!(full, "round {round}: refused while not full");
                }
                next_node += 1;
            } else if roll < 97 {
                let got = OpenList::pop(&mut rq, &mut rs);
                let want = lq.pop(&mut ls);
                assert_eq!((got, rs.last), (want, ls.last), "round {round}");
                if got != NIL {
                    live -= 1;
                    last = rs.last;
                }
            } else {
                let m = 2 + (next_random(&mut state) % 3) as u32;
                let freed = rq.collect(&mut rs, |n| n % m == 0);
                let (after, list_freed) = lq.collect(ls, |n| n % m == 0);
                ls = after;
                assert_eq!(freed, list_freed, "round {round}");
                live -= freed;
            }
        }
        for _ in 0..=live {
            let got = OpenList::pop(&mut rq, &mut rs);
            let want = lq.pop(&mut ls);
            assert_eq!((got, rs.last), (want, ls.last), "round {round}");
        }
        assert_eq!(OpenList::pop(&mut rq, &mut rs), NIL);
        assert!(OpenList::peak(&rq, &rs) as usize <= size);
    }
    // The small pools do fill their rings (the refusal test above ran).
    assert!(refused > 100, "{refused}");
}

/// The framed A* on rings and on the linked lists, run directly on the same maps with a
/// large and a small pool: when the rings do not give up, the same result, queue-independent
/// nibbles (every closed cell with the same parent step, i.e. the same pops in the same
/// order); when they do (`QueueFull`), the planner's answer (which then runs the linked
/// lists) is the linked lists' one. Both cases occur.
#[test]
fn ring_and_linked_astar_agree_and_fall_back() {
    let mut state = 0x1234_5678_9ABC_DEF1u64;
    let (mut ring_ok, mut ring_gave_up) = (0, 0);
    for round in 0..300 {
        let (w, h) = (
            8 + next_random(&mut state) % 24,
            8 + next_random(&mut state) % 24,
        );
        let mut g = SmallGrid::new(GridGeometry::new(w as u32, h as u32, 0.1).unwrap()).unwrap();
        let density = next_random(&mut state) % 40;
        for y in 0..h as u16 {
            for x in 0..w as u16 {
                if next_random(&mut state) % 100 < density {
                    g.set(Cell::new(x, y), true);
                }
            }
        }
        let s = Cell::new(0, 0);
        let t = Cell::new(w as u16 - 1, h as u16 - 1);
        g.set(s, false);
        g.set(t, false);
        let si = g.geometry().index(s);
        let used = scratch_words_for_cells(g.geometry().cell_count());
        let outcome = |r: &Result<Search, PlanError>| match r {
            Ok(s) => Ok((s.found, s.expanded, s.cost)),
            Err(e) => Err(*e),
        };
        let small = round % 2 == 1;
        let mut p = Box::new(Planner::<SMALL_FRAMED, 4096>::new());
        let pool = if small { 24 } else { 4096 };
        // The planner's answer (rings, else linked lists), which also fills the goal table.
        let planned = if small {
            let mut q = Box::new(Planner::<SMALL_FRAMED, 24>::new());
            let r = q.astar_in::<_, SMALL_FRAMED, true>(&g, si, t, true);
            assert!(matches!(q.layout, Layout::Framed { .. }));
            r
        } else {
            p.astar_in::<_, SMALL_FRAMED, true>(&g, si, t, true)
        };
        p.astar_in::<_, SMALL_FRAMED, true>(&g, si, t, true).ok();
        assert!(matches!(p.layout, Layout::Framed { .. }));
        let runs = |p: &mut Planner<SMALL_FRAMED, 4096>, ring: bool| {
            let mut map = Framed::<SMALL_FRAMED>::new(&mut p.scratch, g.geometry()).unwrap();
            map.copy_map(&g);
            let mut peak = 0;
            let queue = &mut p.queue[..pool];
            let r = if ring {
                astar_search::<_, RingQueue, true>(
                    &mut map,
                    queue,
                    &p.goal_axis,
                    (0, 0),
                    (t.x as u32, t.y as u32),
                    &mut peak,
                )
            } else {
                astar_search::<_, ClassQueue, true>(
                    &mut map,
                    queue,
                    &p.goal_axis,
                    (0, 0),
                    (t.x as u32, t.y as u32),
                    &mut peak,
                )
            };
            (r, p.scratch[..used].to_vec())
        };
        let (ring, ring_nibbles) = runs(&mut p, true);
        let (linked, linked_nibbles) = runs(&mut p, false);
        if matches!(ring, Err(PlanError::QueueFull { .. })) {
            ring_gave_up += 1;
        } else {
            ring_ok += 1;
            assert_eq!(outcome(&ring), outcome(&linked), "round {round}");
            assert!(ring_nibbles == linked_nibbles, "round {round}");
        }
        assert_eq!(outcome(&planned), outcome(&linked), "round {round}");
    }
    assert!(
        ring_ok > 50 && ring_gave_up > 10,
        "{ring_ok} {ring_gave_up}"
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1024))]

    /// The cell-by-cell A* alone with a queue of 16 entries: reclaiming stale entries reorders
    /// the lists (a FIFO keeps its order, so its keys stay sorted), and the search finds the
    /// optimal cost or reports `QueueFull`, never another cost.
    #[test]
    fn cell_by_cell_astar_with_a_tiny_queue_is_exact_or_full((mut g, s, t) in arb_grid()) {
        let mut p = Box::new(Planner::<{ scratch_words_for_cells(SMALL_CELLS) }, 16>::new());
        g.set(s, false);
        g.set(t, false);
        if s == t {
            return Ok(());
        }
        let si = g.geometry().index(s);
        let expected = oracle_astar(&g, s, t);
        match p.astar(&g, si, t) {
            Ok(search) => {
                prop_assert_eq!(search.found, expected.is_some());
                if let Some(cost) = expected {
                    prop_assert_eq!(search.cost, cost);
                    p.rebuild_merged(g.geometry(), t, false);
                    prop_assert_eq!(steps_and_cost(p.path_cells()).1, cost);
                    assert_collision_free(&g, p.path_cells());
                }
                prop_assert!(p.queue_peak() <= 16);
            }
            Err(e) => prop_assert_eq!(e, PlanError::QueueFull { capacity: 16 }),
        }
    }
}

/// A tiny queue does run out and reclaim: corner to corner on 24 × 24 grids with 20 % random
/// obstacles, a few searches fill all 32 entries and still find the optimal cost (after a
/// reclaim), most end with `QueueFull`.
#[test]
fn tiny_queue_reclaims_and_runs_out_on_random_grids() {
    let (mut reclaimed, mut full) = (0, 0);
    for seed in 1..200u64 {
        let mut g: SmallGrid = random_grid(24, 24, 20, seed);
        let (s, t) = (Cell::new(0, 0), Cell::new(23, 23));
        g.set(s, false);
        g.set(t, false);
        let mut p = Box::new(Planner::<{ scratch_words_for_cells(SMALL_CELLS) }, 32>::new());
        let si = g.geometry().index(s);
        match p.astar(&g, si, t) {
            Ok(search) => {
                let expected = oracle_astar(&g, s, t);
                assert_eq!(search.found, expected.is_some(), "seed {seed}");
                if let Some(cost) = expected {
                    assert_eq!(search.cost, cost, "seed {seed}");
                    if p.queue_peak() == 32 {
                        reclaimed += 1;
                    }
                }
            }
            Err(e) => {
                assert_eq!(e, PlanError::QueueFull { capacity: 32 });
                full += 1;
            }
        }
    }
    assert!(
        reclaimed > 0 && full > 0,
        "reclaimed {reclaimed}, full {full}"
    );
}

/// Words of the framed view the tests use on small grids (the planner's is 2^14 + 1).
const SMALL_FRAMED: usize = 1025;

/// The framed copy of the map (rows padded to whole words, a frame of blocked cells): every
/// cell's nibble is the map's, and every cell's three windows, on the border too, equal the
/// flat layout's (which reads off-map neighbours as blocked), for all widths around the
/// multiples of 8 where the padding changes, with garbage in the scratch beforehand.
#[test]
fn framed_map_reads_like_the_flat_one() {
    let mut state = 0x2545_F491_4F6C_DD1Du64;
    for w in (1..=40u32).chain([63, 64, 65]) {
        for h in [1u32, 2, 3, 7, 24] {
            if (w * h) as usize > SMALL_CELLS {
                continue;
            }
            let seed = next_random(&mut state);
            let g: SmallGrid = random_grid(w, h, 30, seed);
            let geometry = *g.geometry();
            let mut framed_words = std::vec![0xA5A5_A5A5u32; SMALL_FRAMED];
            let mut framed = Framed::<SMALL_FRAMED>::new(&mut framed_words, &geometry).unwrap();
            framed.copy_map(&g);
            let mut p = Box::new(SmallPlanner::new());
            p.scratch.fill(0x5A5A_5A5A);
            p.copy_map(&g);
            let used = scratch_words_for_cells(geometry.cell_count());
            let flat = Flat {
                scratch: &mut p.scratch[..used],
                interior: Interior::new(&geometry),
            };
            for y in 0..h as usize {
                for x in 0..w as usize {
                    let (fi, ti) = (framed.index(x, y), flat.index(x, y));
                    assert_eq!(framed.nibble(fi), flat.nibble(ti), "{w}x{h} ({x}, {y})");
                    let mask = |(a, c, b): (u32, u32, u32)| {
                        let t = |v: u32| NIBBLE_WINDOWS[(v & 0xFFF) as usize];
                        (t(a), t(c), t(b))
                    };
                    assert_eq!(
                        mask(framed.windows(fi, x, y)),
                        mask(flat.windows(ti, x, y)),
                        "{w}x{h} ({x}, {y})"
                    );
                    assert_eq!(framed.interior(fi, x, y), flat.interior(ti, x, y));
                    if framed.interior(fi, x, y) {
                        assert_eq!(
                            mask(framed.interior_windows(fi)),
                            mask(flat.interior_windows(ti))
                        );
                    }
                }
            }
        }
    }
    // A map too large for the view is not framed.
    let g = SmallGrid::new(GridGeometry::new(40, 40, 0.1).unwrap()).unwrap();
    let mut words = std::vec![0u32; 129];
    assert!(Framed::<129>::new(&mut words, g.geometry()).is_none());
    assert!(Framed::<SMALL_FRAMED>::new(&mut words, g.geometry()).is_none());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1024))]

    /// The cell-by-cell A* in the framed layout and in the flat one: the same search (cost,
    /// expansions, queue peak) and the same path, both of pathfinding's optimal cost.
    #[test]
    fn framed_and_flat_astar_agree((mut g, s, t) in arb_grid()) {
        g.set(s, false);
        g.set(t, false);
        if s == t {
            return Ok(());
        }
        let si = g.geometry().index(s);
        let mut framed = Box::new(Planner::<SMALL_FRAMED, 4096>::new());
        let a = framed.astar_in::<_, SMALL_FRAMED, true>(&g, si, t, true).unwrap();
        let is_framed = matches!(framed.layout, Layout::Framed { .. });
        prop_assert!(is_framed);
        let mut flat = Box::new(SmallPlanner::new());
        let b = flat.astar_in::<_, SMALL_FRAMED, true>(&g, si, t, false).unwrap();
        prop_assert_eq!(flat.layout, Layout::Flat);
        prop_assert_eq!((a.found, a.cost, a.expanded), (b.found, b.cost, b.expanded));
        // The framed search runs on rings: a different measure of the pool used.
        prop_assert!(framed.queue_peak() <= 4096);
        prop_assert_eq!(a.found.then_some(a.cost), oracle_astar(&g, s, t));
        if a.found {
            framed.rebuild_merged(g.geometry(), t, false);
            flat.rebuild_merged(g.geometry(), t, false);
            prop_assert_eq!(framed.path_cells(), flat.path_cells());
            prop_assert_eq!(steps_and_cost(framed.path_cells()).1, a.cost);
            assert_collision_free(&g, framed.path_cells());
        }
    }
}

/// The ring capacities ([`RING_SHARES`]) fit the 20 % random benchmark grids with the MCU's
/// pool of 1 024 entries: on the benchmark's grid (seed 1) and three more seeds the rings
/// never give up (no second search), and they find what the linked lists find.
#[test]
fn rings_fit_random_grids_with_the_mcu_pool() {
    std::thread::Builder::new()
        .stack_size(256 << 20)
        .spawn(rings_fit_random_grids)
        .unwrap()
        .join()
        .unwrap();
}

fn rings_fit_random_grids() {
    use crate::grid::Grid300;
    const WORDS: usize = 16385;
    let (s, t) = (Cell::new(2, 2), Cell::new(297, 297));
    for seed in 1u64..5 {
        // The generator of shared/benches/grids (xorshift64).
        let mut rng = 0x9E37_79B9_7F4A_7C15 ^ seed;
        let mut g = Grid300::new(GridGeometry::new(300, 300, 0.05).unwrap()).unwrap();
        for y in 0..300 {
            for x in 0..300 {
                rng ^= rng << 13;
                rng ^= rng >> 7;
                rng ^= rng << 17;
                if rng % 100 < 20 {
                    g.set_xy(x, y, true);
                }
            }
        }
        g.set(s, false);
        g.set(t, false);
        let mut p = Box::new(Planner::<{ scratch_words_for_cells(160_000) }, 1024>::new());
        let planned = p
            .astar_in::<_, WORDS, true>(&g, g.geometry().index(s), t, true)
            .unwrap();
        assert!(matches!(p.layout, Layout::Framed { .. }));
        let mut map = Framed::<WORDS>::new(&mut p.scratch, g.geometry()).unwrap();
        map.copy_map(&g);
        let mut peak = 0;
        let ring = astar_search::<_, RingQueue, true>(
            &mut map,
            &mut p.queue,
            &p.goal_axis,
            (s.x as u32, s.y as u32),
            (t.x as u32, t.y as u32),
            &mut peak,
        );
        let ring = ring.unwrap_or_else(|e| panic!("seed {seed}: the rings gave up: {e:?}"));
        assert!(ring.found, "seed {seed}");
        assert_eq!(
            (ring.expanded, ring.cost),
            (planned.expanded, planned.cost),
            "seed {seed}"
        );
        if seed == 1 {
            assert_eq!(ring.expanded, 28_823);
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
        let framed = p
            .astar_in::<_, FRAMED_WORDS, true>(&g, si, t, true)
            .unwrap();
        assert!(matches!(p.layout, Layout::Framed { .. }));
        let flat = p
            .astar_in::<_, FRAMED_WORDS, true>(&g, si, t, false)
            .unwrap();
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
