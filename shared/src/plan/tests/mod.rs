//! Unit and property tests of the planners, by subject; the `pathfinding` crate is the oracle.
//! This file holds what several subjects share: the small grids, the oracles, the random maps.

extern crate std;

use std::boxed::Box;
use std::vec::Vec;

use proptest::prelude::*;

use super::astar::{astar_loop, astar_search};
use super::*;
use crate::grid::GridGeometry;
use crate::grid::{words_for_cells, Grid};
use crate::plan::codes::octile;

mod astar;
mod bfs;
mod corridor;
mod jump;
mod layouts;
mod open_list;
mod planners;
mod prune;

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

/// xorshift64 step for the grid generators below.
fn next_random(state: &mut u64) -> u64 {
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    *state
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

/// Words of the framed view the tests use on small grids (the planner's is 2^14 + 1).
const SMALL_FRAMED: usize = 1025;
