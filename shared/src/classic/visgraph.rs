//! The visibility graph of the grown obstacles, searched by A*: the shortest path for the
//! square-grown model of the robot, the continuous optimum the grid planners are measured
//! against.
//!
//! Seeds: 003 §III.1.1 (the visibility graph: the shortest free path is a polyline through
//! vertices of the configuration-space obstacles; build the graph, then search it), 004 §2.1.
//!
//! Design choices:
//! - Nodes: start, goal, and every vertex of the grown polygons ([`super::grown`]) that is
//!   free: inside the free box and not inside another grown polygon (walls that overlap at a
//!   corner bury each other's vertices). At most [`MAX_NODES`] for a full `.da`.
//! - **No edge storage: neighbours are found lazily.** When A* expands a node it tests the
//!   line of sight to every node not yet closed (and skips the test when the edge could not
//!   improve that node's cost). The seed builds the whole graph first (O(n² log n) with a
//!   sweep); here the graph is implicit, so the memory is O(n) (15 bytes a node) and only the
//!   part of the graph A* needs is computed. A visibility test costs O(polygons) bounding-box
//!   filters plus the exact test of the few polygons that pass (starting with the polygon that
//!   blocked the previous test from the same node): worst case O(n² · polygons) for the search.
//!   Measured at the `.da` capacity (128 octagons, 1518 nodes, goal walled off so that every
//!   node is expanded, 421 866 visibility tests): 0.3–0.45 s on the loaded 2-core build
//!   machine (1.1 s before the filters and the hint).
//! - A* with the Euclidean heuristic (consistent, so the first time the goal is popped its
//!   cost is optimal); the open list is a linear scan over the nodes: O(n) a pop, which the
//!   O(n) visibility tests of each expansion dominate anyway, and no heap to size.
//! - [`VisGraph::edges`] enumerates the full graph (for the pictures and the edge count); it is
//!   not part of the search.

use heapless::Vec;

use super::grown::{Grown, PointPlace};
use crate::geom::PointM;
use crate::plan::PlanStatus;
use crate::world::{MAX_POLYGONS, MAX_VERTICES};

/// Nodes of a graph for a full `.da`: every vertex can gain the 4 corners of the square per
/// polygon, plus start and goal.
pub const MAX_NODES: usize = MAX_VERTICES + 4 * MAX_POLYGONS + 2;

/// Why the search could not run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VisError {
    /// More free vertices than the node capacity `N`.
    TooManyNodes {
        /// The capacity.
        capacity: usize,
    },
}

impl core::fmt::Display for VisError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            VisError::TooManyNodes { capacity } => {
                write!(f, "more free vertices than the graph's {capacity} nodes")
            }
        }
    }
}

impl core::error::Error for VisError {}

/// What a search did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VisReport {
    /// How it ended (`Found`, `Unreachable`, `StartBlocked`, `GoalBlocked`, `OutOfBounds`).
    pub status: PlanStatus,
    /// Graph nodes expanded (closed) by A*.
    pub expanded: u32,
    /// Line-of-sight tests made.
    pub visibility_tests: u64,
    /// Length of the path, metres (0 without one).
    pub length_m: f32,
}

const UNSEEN: u8 = 0;
const OPEN: u8 = 1;
const CLOSED: u8 = 2;
const NO_PARENT: u16 = u16::MAX;

/// The nodes and the A* state for up to `N` nodes (`N` ≤ 65535).
#[derive(Clone, Debug)]
pub struct VisGraph<const N: usize> {
    nodes: Vec<PointM, N>,
    cost_m: [f32; N],
    parent: [u16; N],
    state: [u8; N],
}

impl<const N: usize> Default for VisGraph<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> VisGraph<N> {
    /// An empty graph.
    pub const fn new() -> Self {
        Self {
            nodes: Vec::new(),
            cost_m: [0.0; N],
            parent: [NO_PARENT; N],
            state: [UNSEEN; N],
        }
    }

    /// The nodes of the last [`VisGraph::plan`]: start, goal, then the free grown vertices.
    pub fn nodes(&self) -> &[PointM] {
        &self.nodes
    }

    /// Bytes of the graph as this world uses it: per node its point (8), cost (4), parent (2)
    /// and state (1).
    pub fn memory_bytes(&self) -> usize {
        self.nodes.len() * 15
    }

    /// Shortest path from `start` to `goal` among `grown`, written to `path` (start first).
    pub fn plan<const V: usize, const P: usize>(
        &mut self,
        grown: &Grown<V, P>,
        start: PointM,
        goal: PointM,
        path: &mut Vec<PointM, N>,
    ) -> Result<VisReport, VisError> {
        path.clear();
        self.nodes.clear();
        let mut report = VisReport {
            status: PlanStatus::Found,
            expanded: 0,
            visibility_tests: 0,
            length_m: 0.0,
        };
        let status_of = |p: PointM, blocked: PlanStatus| match grown.place(p) {
            PointPlace::Free => None,
            PointPlace::OutOfMap => Some(PlanStatus::OutOfBounds),
            PointPlace::NearBorder | PointPlace::InObstacle(_) => Some(blocked),
        };
        if let Some(s) = status_of(start, PlanStatus::StartBlocked) {
            report.status = s;
            return Ok(report);
        }
        if let Some(s) = status_of(goal, PlanStatus::GoalBlocked) {
            report.status = s;
            return Ok(report);
        }
        let too_many = VisError::TooManyNodes {
            capacity: N.min(u16::MAX as usize),
        };
        if N < 2 || N > u16::MAX as usize {
            return Err(too_many);
        }
        let _ = self.nodes.push(start);
        let _ = self.nodes.push(goal);
        for polygon in grown.iter() {
            for &v in polygon {
                if grown.place(v) == PointPlace::Free {
                    self.nodes.push(v).map_err(|_| too_many)?;
                }
            }
        }
        let n = self.nodes.len();
        self.cost_m[..n].fill(f32::INFINITY);
        self.parent[..n].fill(NO_PARENT);
        self.state[..n].fill(UNSEEN);
        self.cost_m[0] = 0.0;
        self.state[0] = OPEN;
        loop {
            // The open node of least cost + straight-line distance to the goal.
            let mut best: Option<(usize, f32)> = None;
            for i in 0..n {
                if self.state[i] == OPEN {
                    let f = self.cost_m[i] + self.nodes[i].distance_m(goal);
                    if best.is_none_or(|(_, bf)| f < bf) {
                        best = Some((i, f));
                    }
                }
            }
            let Some((u, _)) = best else {
                report.status = PlanStatus::Unreachable;
                return Ok(report);
            };
            if u == 1 {
                break;
            }
            self.state[u] = CLOSED;
            report.expanded += 1;
            let (pu, cu) = (self.nodes[u], self.cost_m[u]);
            let mut hint = 0;
            for v in 0..n {
                if self.state[v] == CLOSED {
                    continue;
                }
                let through = cu + pu.distance_m(self.nodes[v]);
                if through >= self.cost_m[v] {
                    continue;
                }
                report.visibility_tests += 1;
                if grown.sees_from(pu, self.nodes[v], &mut hint) {
                    self.cost_m[v] = through;
                    self.parent[v] = u as u16;
                    self.state[v] = OPEN;
                }
            }
        }
        report.expanded += 1;
        report.length_m = self.cost_m[1];
        // Walk the parents back from the goal (at most n steps: the tree has no cycle), then
        // reverse.
        let mut at = 1usize;
        for _ in 0..n {
            let _ = path.push(self.nodes[at]);
            if at == 0 {
                break;
            }
            at = self.parent[at] as usize;
            if at >= n {
                break;
            }
        }
        path.reverse();
        Ok(report)
    }

    /// Call `edge` for every pair of nodes of the last [`VisGraph::plan`] that see each other
    /// (the whole graph, O(n²) visibility tests); returns how many there are.
    pub fn edges<const V: usize, const P: usize>(
        &self,
        grown: &Grown<V, P>,
        mut edge: impl FnMut(PointM, PointM),
    ) -> usize {
        let mut count = 0;
        for (i, &a) in self.nodes.iter().enumerate() {
            let mut hint = 0;
            for &b in self.nodes.iter().skip(i + 1) {
                if grown.sees_from(a, b, &mut hint) {
                    edge(a, b);
                    count += 1;
                }
            }
        }
        count
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(x: f32, y: f32) -> PointM {
        PointM::new(x, y)
    }

    fn grown(polygons: &[&[PointM]], radius_m: f32) -> Grown<64, 8> {
        let mut scratch = [PointM::default(); 128];
        Grown::build(polygons.iter().copied(), radius_m, 10.0, 10.0, &mut scratch).unwrap()
    }

    #[test]
    fn the_path_bends_at_the_grown_corners_and_is_shortest() {
        // A wall from y = 2 to y = 8 at x = 5; growth 0.5 makes it x 4.5..5.5, y 1.5..8.5.
        let wall = [p(5.0, 2.0), p(5.0, 8.0)];
        let g = grown(&[&wall], 0.5);
        let mut vg = VisGraph::<16>::new();
        let mut path = Vec::new();
        let r = vg.plan(&g, p(2.0, 6.0), p(8.0, 6.0), &mut path).unwrap();
        assert_eq!(r.status, PlanStatus::Found);
        assert_eq!(
            path.as_slice(),
            &[p(2.0, 6.0), p(4.5, 8.5), p(5.5, 8.5), p(8.0, 6.0)]
        );
        let expected = 2.0 * crate::math::hypot(2.5, 2.5) + 1.0;
        assert!((r.length_m - expected).abs() < 1e-5, "{}", r.length_m);
        // The whole graph: 6 nodes; start and goal do not see each other.
        let mut edges = 0;
        let count = vg.edges(&g, |_, _| edges += 1);
        assert_eq!(count, edges);
        assert!(count > 0 && count < 15);
        assert!(vg.memory_bytes() == 6 * 15);
    }

    #[test]
    fn a_straight_line_when_nothing_is_in_the_way() {
        let g = grown(&[], 0.5);
        let mut vg = VisGraph::<4>::new();
        let mut path = Vec::new();
        let r = vg.plan(&g, p(1.0, 1.0), p(4.0, 5.0), &mut path).unwrap();
        assert_eq!(r.status, PlanStatus::Found);
        assert_eq!(path.len(), 2);
        assert!((r.length_m - 5.0).abs() < 1e-6);
    }

    #[test]
    fn blocked_unreachable_and_capacity_are_reported() {
        // A closed box of 4 walls around (5, 5): overlapping grown walls bury their corners.
        let walls: [&[PointM]; 4] = [
            &[p(3.0, 3.0), p(7.0, 3.0)],
            &[p(7.0, 3.0), p(7.0, 7.0)],
            &[p(7.0, 7.0), p(3.0, 7.0)],
            &[p(3.0, 7.0), p(3.0, 3.0)],
        ];
        let g = grown(&walls, 0.5);
        let mut vg = VisGraph::<64>::new();
        let mut path = Vec::new();
        let r = vg.plan(&g, p(1.0, 1.0), p(5.0, 5.0), &mut path).unwrap();
        assert_eq!(r.status, PlanStatus::Unreachable);
        assert!(path.is_empty());
        assert!(r.expanded > 0);
        let r = vg.plan(&g, p(3.2, 5.0), p(1.0, 1.0), &mut path).unwrap();
        assert_eq!(r.status, PlanStatus::StartBlocked);
        let r = vg.plan(&g, p(1.0, 1.0), p(0.2, 5.0), &mut path).unwrap();
        assert_eq!(r.status, PlanStatus::GoalBlocked);
        let r = vg.plan(&g, p(-1.0, 1.0), p(1.0, 1.0), &mut path).unwrap();
        assert_eq!(r.status, PlanStatus::OutOfBounds);
        let mut small = VisGraph::<4>::new();
        let mut path4 = Vec::new();
        assert_eq!(
            small.plan(&g, p(1.0, 1.0), p(9.0, 9.0), &mut path4),
            Err(VisError::TooManyNodes { capacity: 4 })
        );
    }
}
