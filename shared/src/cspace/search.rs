//! Any-angle A* on the configuration map (seed 000 §3.3).
//!
//! **Graph.** A shortest path among the collision regions bends only at their corners (figure
//! 3.3), so the nodes are the start, the goal and the free cells at a convex corner of a collision
//! region: a free cell whose diagonal neighbour collides while the two cells beside that
//! diagonal are free (figure 3.4). [`NodeSet::Boundary`] takes every free cell next to a
//! collision and [`NodeSet::All`] every free cell, as the thesis allowed for testing.
//!
//! **Edges.** Two nodes are joined when the straight segment between them crosses no collision,
//! checked by [`line_free`], the thesis' `LINHA`: from one end, step to the horizontal or the
//! vertical neighbour whose distance to the ideal line is smaller; on a tie the line passes
//! exactly through a cell corner and steps diagonally, and then *both* cells beside the diagonal
//! must be free (no corner cutting). Every cell visited must be free.
//!
//! **Costs.** Edge cost is the joint motion `√(Δq₁² + Δq₂²)` in joint units (index differences
//! times the increments) and the heuristic is the same distance to the goal, which never
//! overestimates, so the search returns the shortest path of this graph. For a joint that wraps,
//! an edge may go either way round; path points are then given unwrapped (continuous), so
//! consecutive points are always joined by the straight motion that was checked.
//!
//! **Memory.** Nodes live in fixed arrays of [`MAX_NODES`] entries inside [`Search`] (about
//! 60 KiB; keep it in a `static` or on the heap of a host); the open list is a flag per node and
//! the best open node is found by a scan, so nothing can overflow during the search itself.
//!
//! ```
//! use twil_core::cspace::{map::ConfigMap, rob::parse_rob, search::{NodeSet, Search, SearchStatus}};
//! // A point sliding in x and y (two prismatic joints) around a square block.
//! let robot = parse_rob("1 4 4 4 6 4 6 6 4 6  2 P 0 10 0 0  P 0 10 90 1 1 0 0").unwrap();
//! let map = ConfigMap::build(&robot, [1.0, 1.0]).unwrap();
//! let mut search = Box::new(Search::new());
//! let report = search.run(&map, [2.0, 5.0], [8.0, 5.0], NodeSet::Corners).unwrap();
//! assert_eq!(report.status, SearchStatus::Found);
//! assert_eq!(report.path.first(), Some(&[2, 5]));
//! // Round the block: (2,5) → (3,7) → (7,7) → (8,5), 4 + 2·√5.
//! assert!((report.length - 8.472).abs() < 1e-3);
//! ```

use heapless::Vec;

use super::map::ConfigMap;
use crate::math;

/// Most nodes (start, goal and corner cells) one search can hold.
pub const MAX_NODES: usize = 4096;
/// Most points in a path.
pub const MAX_PATH_POINTS: usize = 512;

/// Which free cells become nodes of the search graph.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum NodeSet {
    /// Convex corners of the collision regions (the thesis' default).
    #[default]
    Corners,
    /// Every free cell with a colliding neighbour (8-neighbourhood).
    Boundary,
    /// Every free cell (slow: the search is quadratic in the node count).
    All,
}

/// How a search ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SearchStatus {
    /// A path was found.
    Found,
    /// Start and goal are free but no collision-free path joins them.
    Unreachable,
    /// The start lies outside the joint limits.
    StartOutside,
    /// The goal lies outside the joint limits.
    GoalOutside,
    /// The start configuration collides.
    StartBlocked,
    /// The goal configuration collides.
    GoalBlocked,
}

impl SearchStatus {
    /// The name used in JSON output: `found`, `unreachable`, `start_outside`, ...
    pub fn as_str(&self) -> &'static str {
        match self {
            SearchStatus::Found => "found",
            SearchStatus::Unreachable => "unreachable",
            SearchStatus::StartOutside => "start_outside",
            SearchStatus::GoalOutside => "goal_outside",
            SearchStatus::StartBlocked => "start_blocked",
            SearchStatus::GoalBlocked => "goal_blocked",
        }
    }
}

/// A capacity ran out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SearchError {
    /// The map has more candidate nodes than [`MAX_NODES`].
    TooManyNodes {
        /// The capacity.
        capacity: usize,
    },
    /// The path has more points than [`MAX_PATH_POINTS`].
    PathTooLong {
        /// The capacity.
        capacity: usize,
    },
}

impl core::fmt::Display for SearchError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            SearchError::TooManyNodes { capacity } => write!(
                f,
                "the map has more than {capacity} search nodes; use larger increments or the corner node set"
            ),
            SearchError::PathTooLong { capacity } => {
                write!(f, "the path has more than {capacity} points")
            }
        }
    }
}

impl core::error::Error for SearchError {}

/// The result of a search.
#[derive(Clone, Debug, PartialEq)]
pub struct SearchReport {
    /// How it ended.
    pub status: SearchStatus,
    /// The path's corner points as map indices `[i, j]`, start first (empty unless found).
    /// For a wrapping joint indices are unwrapped: they may leave `0..NC`.
    pub path: Vec<[i32; 2], MAX_PATH_POINTS>,
    /// Length of the path in joint units, `Σ √(Δq₁² + Δq₂²)`.
    pub length: f32,
    /// Nodes in the graph (start and goal included).
    pub nodes: u32,
    /// Nodes expanded.
    pub expanded: u32,
    /// Line tests made.
    pub line_tests: u32,
}

impl SearchReport {
    fn status(status: SearchStatus) -> Self {
        Self {
            status,
            path: Vec::new(),
            length: 0.0,
            nodes: 0,
            expanded: 0,
            line_tests: 0,
        }
    }
}

/// `true` when the straight segment from cell `from` to cell `to` (indices, possibly unwrapped)
/// crosses only free cells, diagonal steps needing both side cells free (the thesis' `LINHA`).
pub fn line_free(map: &ConfigMap, from: [i32; 2], to: [i32; 2]) -> bool {
    let mut free = true;
    trace_line(from, to, |x, y| {
        free = !map.blocked(x, y);
        free
    });
    free
}

/// Visit the cells of the thesis' line from `from` to `to`, both ends included, stopping early
/// when `visit` returns `false`. On a diagonal step the two side cells are visited first.
pub fn trace_line(from: [i32; 2], to: [i32; 2], mut visit: impl FnMut(i32, i32) -> bool) {
    let dx = (to[0] as i64 - from[0] as i64).abs();
    let dy = (to[1] as i64 - from[1] as i64).abs();
    let sx: i32 = if to[0] >= from[0] { 1 } else { -1 };
    let sy: i32 = if to[1] >= from[1] { 1 } else { -1 };
    let [mut x, mut y] = from;
    if !visit(x, y) {
        return;
    }
    // dist = (distance of the current cell to the line) × line length, signed.
    let mut dist: i64 = 0;
    let mut steps_left = dx + dy;
    while (x != to[0] || y != to[1]) && steps_left > 0 {
        let dix = (dist - dy).abs();
        let diy = (dist + dx).abs();
        if dix == diy {
            if !visit(x + sx, y) || !visit(x, y + sy) {
                return;
            }
            dist += dx - dy;
            x += sx;
            y += sy;
            steps_left -= 2;
        } else if diy < dix {
            dist += dx;
            y += sy;
            steps_left -= 1;
        } else {
            dist -= dy;
            x += sx;
            steps_left -= 1;
        }
        if !visit(x, y) {
            return;
        }
    }
}

const UNSEEN: u8 = 0;
const OPEN: u8 = 1;
const CLOSED: u8 = 2;

/// Scratch memory of the search (fixed capacity, reusable).
pub struct Search {
    cell: [[u16; 2]; MAX_NODES],
    g: [f32; MAX_NODES],
    parent: [u16; MAX_NODES],
    via: [[i16; 2]; MAX_NODES],
    state: [u8; MAX_NODES],
    count: usize,
}

impl Default for Search {
    fn default() -> Self {
        Self::new()
    }
}

fn is_corner(map: &ConfigMap, i: i32, j: i32) -> bool {
    [(-1, -1), (-1, 1), (1, -1), (1, 1)]
        .iter()
        .any(|&(dx, dy)| {
            map.blocked(i + dx, j + dy) && !map.blocked(i + dx, j) && !map.blocked(i, j + dy)
        })
}

fn is_boundary(map: &ConfigMap, i: i32, j: i32) -> bool {
    (-1..=1).any(|dx| (-1..=1).any(|dy| (dx, dy) != (0, 0) && map.blocked(i + dx, j + dy)))
}

impl Search {
    /// Empty scratch memory.
    pub const fn new() -> Self {
        Self {
            cell: [[0; 2]; MAX_NODES],
            g: [0.0; MAX_NODES],
            parent: [0; MAX_NODES],
            via: [[0; 2]; MAX_NODES],
            state: [UNSEEN; MAX_NODES],
            count: 0,
        }
    }

    fn push(&mut self, i: i32, j: i32) -> Result<(), SearchError> {
        let k = self.count;
        if k >= MAX_NODES {
            return Err(SearchError::TooManyNodes {
                capacity: MAX_NODES,
            });
        }
        self.cell[k] = [i as u16, j as u16];
        self.g[k] = f32::INFINITY;
        self.state[k] = UNSEEN;
        self.count += 1;
        Ok(())
    }

    /// Plan from joint values `start` to `goal` (snapped to the nearest map values).
    pub fn run(
        &mut self,
        map: &ConfigMap,
        start: [f32; 2],
        goal: [f32; 2],
        nodes: NodeSet,
    ) -> Result<SearchReport, SearchError> {
        let [a, b] = map.axes();
        let s = a.index_of(start[0]).zip(b.index_of(start[1]));
        let g = a.index_of(goal[0]).zip(b.index_of(goal[1]));
        let Some((si, sj)) = s else {
            return Ok(SearchReport::status(SearchStatus::StartOutside));
        };
        let Some((gi, gj)) = g else {
            return Ok(SearchReport::status(SearchStatus::GoalOutside));
        };
        self.run_cells(map, [si, sj], [gi, gj], nodes)
    }

    /// Plan between two map cells.
    pub fn run_cells(
        &mut self,
        map: &ConfigMap,
        start: [i32; 2],
        goal: [i32; 2],
        nodes: NodeSet,
    ) -> Result<SearchReport, SearchError> {
        let [ax, ay] = *map.axes();
        let (Some(si), Some(sj)) = (ax.normalize(start[0]), ay.normalize(start[1])) else {
            return Ok(SearchReport::status(SearchStatus::StartOutside));
        };
        let (Some(gi), Some(gj)) = (ax.normalize(goal[0]), ay.normalize(goal[1])) else {
            return Ok(SearchReport::status(SearchStatus::GoalOutside));
        };
        if map.blocked(si, sj) {
            return Ok(SearchReport::status(SearchStatus::StartBlocked));
        }
        if map.blocked(gi, gj) {
            return Ok(SearchReport::status(SearchStatus::GoalBlocked));
        }
        if (si, sj) == (gi, gj) {
            let mut report = SearchReport::status(SearchStatus::Found);
            let _ = report.path.push([si, sj]);
            report.nodes = 1;
            return Ok(report);
        }
        self.count = 0;
        self.push(si, sj)?;
        self.push(gi, gj)?;
        for j in 0..ay.cells as i32 {
            for i in 0..ax.cells as i32 {
                if map.blocked(i, j) || (i, j) == (si, sj) || (i, j) == (gi, gj) {
                    continue;
                }
                let take = match nodes {
                    NodeSet::Corners => is_corner(map, i, j),
                    NodeSet::Boundary => is_boundary(map, i, j),
                    NodeSet::All => true,
                };
                if take {
                    self.push(i, j)?;
                }
            }
        }
        let n = self.count;
        let (inc_x, inc_y) = (ax.increment, ay.increment);
        let (nx, ny) = (ax.cells as i32, ay.cells as i32);
        let cost = |d: [i32; 2]| math::hypot(d[0] as f32 * inc_x, d[1] as f32 * inc_y);
        // Index differences to try from a to b: direct, and the other way round a wrapping axis.
        let options = |from: i32, to: i32, wraps: bool, cells: i32| -> ([i32; 2], usize) {
            let d = to - from;
            if wraps && d != 0 {
                ([d, if d > 0 { d - cells } else { d + cells }], 2)
            } else {
                ([d, d], 1)
            }
        };
        let goal_cell = [gi, gj];
        let heuristic = |c: [u16; 2]| {
            let (dx, nx_opts) = options(c[0] as i32, goal_cell[0], ax.wraps, nx);
            let (dy, ny_opts) = options(c[1] as i32, goal_cell[1], ay.wraps, ny);
            let mx = dx[..nx_opts].iter().map(|d| d.abs()).min().unwrap_or(0);
            let my = dy[..ny_opts].iter().map(|d| d.abs()).min().unwrap_or(0);
            cost([mx, my])
        };
        let mut report = SearchReport::status(SearchStatus::Unreachable);
        report.nodes = n as u32;
        self.g[0] = 0.0;
        self.state[0] = OPEN;
        loop {
            // The open node with the least estimated total cost.
            let mut best: Option<(usize, f32)> = None;
            for k in 0..n {
                if self.state[k] == OPEN {
                    let f = self.g[k] + heuristic(self.cell[k]);
                    if best.is_none_or(|(_, bf)| f < bf) {
                        best = Some((k, f));
                    }
                }
            }
            let Some((cur, _)) = best else {
                return Ok(report);
            };
            if cur == 1 {
                break;
            }
            self.state[cur] = CLOSED;
            report.expanded += 1;
            let c = self.cell[cur];
            let from = [c[0] as i32, c[1] as i32];
            for m in 0..n {
                if self.state[m] == CLOSED {
                    continue;
                }
                let t = self.cell[m];
                let (dx, nxo) = options(from[0], t[0] as i32, ax.wraps, nx);
                let (dy, nyo) = options(from[1], t[1] as i32, ay.wraps, ny);
                // Up to four ways; try them cheapest first, keep the first clear one.
                let mut ways: Vec<([i32; 2], f32), 4> = Vec::new();
                for &ddx in &dx[..nxo] {
                    for &ddy in &dy[..nyo] {
                        let d = [ddx, ddy];
                        let _ = ways.push((d, self.g[cur] + cost(d)));
                    }
                }
                ways.sort_unstable_by(|p, q| p.1.total_cmp(&q.1));
                for (d, total) in ways {
                    if total >= self.g[m] {
                        break;
                    }
                    report.line_tests += 1;
                    if line_free(map, from, [from[0] + d[0], from[1] + d[1]]) {
                        self.g[m] = total;
                        self.parent[m] = cur as u16;
                        self.via[m] = [d[0] as i16, d[1] as i16];
                        self.state[m] = OPEN;
                        break;
                    }
                }
            }
        }
        // Walk back from the goal, then unwrap from the start.
        let mut rev: Vec<usize, MAX_PATH_POINTS> = Vec::new();
        let mut k = 1usize;
        loop {
            rev.push(k).map_err(|_| SearchError::PathTooLong {
                capacity: MAX_PATH_POINTS,
            })?;
            if k == 0 {
                break;
            }
            k = self.parent[k] as usize;
        }
        let mut p = [si, sj];
        let mut length = 0.0;
        for &k in rev.iter().rev() {
            if k != 0 {
                let d = self.via[k];
                let d = [d[0] as i32, d[1] as i32];
                length += cost(d);
                p = [p[0] + d[0], p[1] + d[1]];
            }
            // Same capacity as `rev`.
            let _ = report.path.push(p);
        }
        report.length = length;
        report.status = SearchStatus::Found;
        Ok(report)
    }
}

/// Length of a path of map indices in joint units, `Σ √((Δi·Δ₁)² + (Δj·Δ₂)²)`.
pub fn path_length(points: &[[i32; 2]], increments: [f32; 2]) -> f32 {
    points
        .windows(2)
        .map(|w| {
            math::hypot(
                (w[1][0] - w[0][0]) as f32 * increments[0],
                (w[1][1] - w[0][1]) as f32 * increments[1],
            )
        })
        .sum()
}

/// `true` when every segment of the path passes [`line_free`] (and every point is free).
pub fn path_is_free(map: &ConfigMap, points: &[[i32; 2]]) -> bool {
    match points {
        [] => true,
        [p] => !map.blocked(p[0], p[1]),
        _ => points.windows(2).all(|w| line_free(map, w[0], w[1])),
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::cspace::rob::parse_rob;
    use proptest::prelude::*;
    use std::boxed::Box;
    use std::vec::Vec as StdVec;

    fn cells(from: [i32; 2], to: [i32; 2]) -> StdVec<(i32, i32)> {
        let mut v = StdVec::new();
        trace_line(from, to, |x, y| {
            v.push((x, y));
            true
        });
        v
    }

    #[test]
    fn exact_diagonal_visits_both_side_cells() {
        assert_eq!(
            cells([0, 0], [2, 2]),
            [(0, 0), (1, 0), (0, 1), (1, 1), (2, 1), (1, 2), (2, 2)]
        );
        assert_eq!(cells([0, 0], [3, 0]), [(0, 0), (1, 0), (2, 0), (3, 0)]);
        assert_eq!(cells([0, 0], [0, -2]), [(0, 0), (0, -1), (0, -2)]);
    }

    /// A free map of `w` × `h` with blocked cells.
    fn grid_map(w: u32, h: u32, blocked: &[(i32, i32)]) -> ConfigMap {
        // A unit square object sliding on two prismatic joints; each blocked cell is a tiny
        // obstacle square at the cell's centre.
        let mut text = std::format!("{}\n", blocked.len());
        for &(x, y) in blocked {
            let (x, y) = (x as f32, y as f32);
            text += &std::format!(
                "4 {} {} {} {} {} {} {} {}\n",
                x - 0.1,
                y - 0.1,
                x + 0.1,
                y - 0.1,
                x + 0.1,
                y + 0.1,
                x - 0.1,
                y + 0.1
            );
        }
        text += &std::format!("2 P 0 {} 0 0  P 0 {} 90 1 1 0 0\n", w - 1, h - 1);
        let robot = parse_rob(&text).unwrap();
        ConfigMap::build(&robot, [1.0, 1.0]).unwrap()
    }

    #[test]
    fn no_corner_cutting_between_diagonal_cells() {
        let map = grid_map(4, 4, &[(1, 0), (0, 1)]);
        assert!(map.blocked(1, 0) && map.blocked(0, 1) && !map.blocked(0, 0));
        assert!(!line_free(&map, [0, 0], [1, 1]));
        let mut s = Box::new(Search::new());
        let r = s.run_cells(&map, [0, 0], [3, 3], NodeSet::Corners).unwrap();
        assert_eq!(r.status, SearchStatus::Unreachable);
    }

    #[test]
    fn straight_when_clear_and_bends_at_corners_otherwise() {
        let map = grid_map(10, 10, &[]);
        let mut s = Box::new(Search::new());
        let r = s.run_cells(&map, [0, 0], [9, 5], NodeSet::Corners).unwrap();
        assert_eq!(r.status, SearchStatus::Found);
        assert_eq!(r.path.as_slice(), &[[0, 0], [9, 5]]);
        assert!((r.length - (81.0f32 + 25.0).sqrt()).abs() < 1e-4);
        // A wall x = 5, y = 0..=7: the path goes round its top end.
        let wall: StdVec<(i32, i32)> = (0..=7).map(|y| (5, y)).collect();
        let map = grid_map(10, 10, &wall);
        let r = s.run_cells(&map, [0, 0], [9, 0], NodeSet::Corners).unwrap();
        assert_eq!(r.status, SearchStatus::Found);
        assert_eq!(r.path.as_slice(), &[[0, 0], [4, 8], [6, 8], [9, 0]]);
        assert!(path_is_free(&map, &r.path));
        // Start = goal: one point, length 0.
        let r = s.run_cells(&map, [2, 2], [2, 2], NodeSet::Corners).unwrap();
        assert_eq!(
            (r.status, r.path.as_slice(), r.length),
            (SearchStatus::Found, &[[2, 2]][..], 0.0)
        );
        // Blocked and outside ends.
        let r = s.run_cells(&map, [5, 3], [9, 0], NodeSet::Corners).unwrap();
        assert_eq!(r.status, SearchStatus::StartBlocked);
        let r = s.run_cells(&map, [0, 0], [5, 3], NodeSet::Corners).unwrap();
        assert_eq!(r.status, SearchStatus::GoalBlocked);
        let r = s
            .run(&map, [0.0, 0.0], [20.0, 0.0], NodeSet::Corners)
            .unwrap();
        assert_eq!(r.status, SearchStatus::GoalOutside);
        let r = s
            .run(&map, [-3.0, 0.0], [9.0, 0.0], NodeSet::Corners)
            .unwrap();
        assert_eq!(r.status, SearchStatus::StartOutside);
    }

    #[test]
    fn wrap_around_takes_the_short_way_through_the_seam() {
        // Joint 1 turns fully (36 values of 10°); nothing collides: going from 20° to 340°
        // the short way is 40° through 0°.
        let robot = parse_rob("0 2 R 10 0 360 0 R 5 -90 90 0").unwrap();
        let map = ConfigMap::build(&robot, [10.0, 10.0]).unwrap();
        let mut s = Box::new(Search::new());
        let r = s
            .run(&map, [20.0, 0.0], [340.0, 0.0], NodeSet::Corners)
            .unwrap();
        assert_eq!(r.status, SearchStatus::Found);
        assert!((r.length - 40.0).abs() < 1e-4, "{}", r.length);
        assert_eq!(r.path.as_slice(), &[[2, 9], [-2, 9]]);
    }

    #[test]
    fn wrap_around_goes_the_long_way_when_the_short_one_is_blocked() {
        // Arm 1 (a 10-unit segment) turns fully; a post at (0, 10) blocks it near 90°. From 45°
        // to 135° the direct way crosses 90°, so the path goes round through ±180°: 270°.
        let robot =
            parse_rob("1 4 -1 9 1 9 1 11 -1 11\n2\nR 10 -180 180 1 2 0 0 -10 0\nR 5 -10 10 0\n")
                .unwrap();
        let map = ConfigMap::build(&robot, [5.0, 5.0]).unwrap();
        assert!(map.axes()[0].wraps);
        let mut s = Box::new(Search::new());
        let r = s
            .run(&map, [45.0, 0.0], [135.0, 0.0], NodeSet::Corners)
            .unwrap();
        assert_eq!(r.status, SearchStatus::Found);
        assert!((r.length - 270.0).abs() < 1e-3, "{}", r.length);
        assert!(path_is_free(&map, &r.path));
        // Unwrapped: the path leaves the first turn (index < 0) instead of jumping across.
        assert!(r.path.iter().any(|p| p[0] < 0), "{:?}", r.path);
        for w in r.path.windows(2) {
            assert!((w[1][0] - w[0][0]).abs() <= 72 / 2 + 18);
        }
    }

    #[test]
    fn the_all_node_set_is_never_longer_than_corners() {
        let wall: StdVec<(i32, i32)> = (2..=9)
            .map(|y| (4, y))
            .chain((0..=6).map(|y| (7, y)))
            .collect();
        let map = grid_map(12, 12, &wall);
        let mut s = Box::new(Search::new());
        let a = s.run_cells(&map, [0, 0], [11, 11], NodeSet::All).unwrap();
        let c = s
            .run_cells(&map, [0, 0], [11, 11], NodeSet::Corners)
            .unwrap();
        let b = s
            .run_cells(&map, [0, 0], [11, 11], NodeSet::Boundary)
            .unwrap();
        assert_eq!(a.status, SearchStatus::Found);
        assert!(a.length <= b.length + 1e-4 && b.length <= c.length + 1e-4);
        assert!(c.nodes < b.nodes && b.nodes < a.nodes);
        for r in [&a, &b, &c] {
            assert!(path_is_free(&map, &r.path));
        }
    }

    proptest! {
        #[test]
        fn traced_lines_are_connected_and_end_at_the_target(
            x0 in -50i32..50, y0 in -50i32..50, x1 in -50i32..50, y1 in -50i32..50,
        ) {
            let v = cells([x0, y0], [x1, y1]);
            prop_assert_eq!(v.first(), Some(&(x0, y0)));
            prop_assert_eq!(v.last(), Some(&(x1, y1)));
            for w in v.windows(2) {
                let step = (w[1].0 - w[0].0).abs() + (w[1].1 - w[0].1).abs();
                // 4-connected, except the jump back from the first side cell of a diagonal.
                prop_assert!(step == 1 || step == 2);
            }
            // Never farther than one cell from the ideal line.
            let (dx, dy) = ((x1 - x0) as f64, (y1 - y0) as f64);
            let len = (dx * dx + dy * dy).sqrt().max(1.0);
            for &(x, y) in &v {
                let d = ((x - x0) as f64 * dy - (y - y0) as f64 * dx).abs() / len;
                prop_assert!(d <= 1.0 + 1e-9, "{:?} is {} from the line", (x, y), d);
            }
        }

        #[test]
        fn found_paths_are_free_and_no_shorter_than_the_straight_line(
            blocked in proptest::collection::vec((0i32..12, 0i32..12), 0..25),
            g in (0i32..12, 0i32..12),
        ) {
            let map = grid_map(12, 12, &blocked);
            let mut s = Box::new(Search::new());
            let r = s.run_cells(&map, [0, 0], [g.0, g.1], NodeSet::Corners).unwrap();
            if r.status == SearchStatus::Found {
                prop_assert!(path_is_free(&map, &r.path));
                let straight = ((g.0 * g.0 + g.1 * g.1) as f32).sqrt();
                prop_assert!(r.length + 1e-3 >= straight);
                prop_assert!((r.length - path_length(&r.path, [1.0, 1.0])).abs() < 1e-3);
                prop_assert_eq!(r.path.last().copied(), Some([g.0, g.1]));
                // Corner nodes never beat the exhaustive node set.
                let all = s.run_cells(&map, [0, 0], [g.0, g.1], NodeSet::All).unwrap();
                prop_assert_eq!(all.status, SearchStatus::Found);
                prop_assert!(all.length <= r.length + 1e-3);
            }
        }
    }
}
