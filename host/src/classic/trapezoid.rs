//! `twil plan --planner trapezoid`: the exact trapezoidal (vertical) cell decomposition of the
//! free space, by a sweep line over the square-grown polygons (`twil_core::classic::grown`, the
//! same obstacles as the visibility graph).
//!
//! Seeds: 003 §III.2.1 (exact cell decomposition, Fig. 7: vertical lines through every vertex
//! split the free space into trapezoids; the connectivity graph of the cells; the path through
//! the midpoints of the shared boundaries), 004 §2.2 (cell decomposition, crossing from a cell
//! to its neighbour through the middle of their common side).
//!
//! Design choices:
//! - **Slab-wise trapezoids, not the minimal set.** The events are the x of every grown vertex,
//!   the x where two edges of different (overlapping) grown polygons cross, where an edge
//!   crosses the free box's top or bottom, and the box's sides. Between two consecutive events
//!   nothing changes order, so each free interval of the vertical line at the slab's middle is
//!   one trapezoid bounded by two straight edges (of a grown polygon or of the box). The
//!   decomposition has more cells than the minimal one (a cell is cut at every event x even
//!   where nothing happens on its side), the connectivity is the same.
//! - Overlapping polygons: at each slab middle the covered intervals are merged (a union), so a
//!   free interval is always bounded by the edge that is outermost there.
//! - Adjacency: two cells of neighbouring slabs whose vertical sides at the shared x overlap by
//!   more than 1 µm; the node is the middle of that common piece.
//! - Path: start → the midpoints of the shared sides → goal; each leg lies inside one convex
//!   cell, so the path is collision-free exactly. The cells' centroids are not used (the seed's
//!   figure goes through them too; they only lengthen the path). Shortest path over those
//!   midpoints by Dijkstra (nodes = shared sides, joined when they border the same cell).
//! - On the host, with a heap: the number of cells is (events) × (free intervals per slab),
//!   O((vertices + crossings) × polygons); a fixed capacity for a full `.da` would be megabytes
//!   the device cannot hold, and its planner is the grid. [`MAX_CELLS`] bounds it.
//! - Arithmetic in f64; the path is rounded to `f32` [`PointM`] at the end.
//!
//! Measured: docs/classic.md.

use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::time::Instant;

use anyhow::bail;
use twil_core::classic::grown::PointPlace;
use twil_core::geom::PointM;

use super::visgraph::{grow, HostGrown};
use super::{Method, Overlay, Run, Status};
use crate::planning::World;

/// Most cells a decomposition may have (about 100 MB); beyond it the run is refused.
pub const MAX_CELLS: usize = 1_000_000;

/// Events closer than this, metres, are one.
const SAME_X_M: f64 = 1e-7;
/// A free interval or a shared side shorter than this, metres, is nothing.
const MIN_GAP_M: f64 = 1e-6;

/// A straight boundary `y = y0 + slope · x`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Line {
    y0: f64,
    slope: f64,
}

impl Line {
    fn flat(y: f64) -> Self {
        Self { y0: y, slope: 0.0 }
    }

    /// The line through `p`–`q` (`p.x != q.x`).
    fn through(p: (f64, f64), q: (f64, f64)) -> Self {
        let slope = (q.1 - p.1) / (q.0 - p.0);
        Self {
            y0: p.1 - slope * p.0,
            slope,
        }
    }

    fn at(&self, x: f64) -> f64 {
        self.y0 + self.slope * x
    }
}

/// One trapezoid: `x0 ≤ x ≤ x1`, `lower(x) ≤ y ≤ upper(x)`.
#[derive(Clone, Copy, Debug)]
struct Cell {
    x0: f64,
    x1: f64,
    lower: Line,
    upper: Line,
}

impl Cell {
    fn contains(&self, p: (f64, f64)) -> bool {
        p.0 >= self.x0 - SAME_X_M
            && p.0 <= self.x1 + SAME_X_M
            && p.1 >= self.lower.at(p.0) - MIN_GAP_M
            && p.1 <= self.upper.at(p.0) + MIN_GAP_M
    }

    fn corners(&self) -> Vec<PointM> {
        let pt = |x: f64, y: f64| PointM::new(x as f32, y as f32);
        vec![
            pt(self.x0, self.lower.at(self.x0)),
            pt(self.x1, self.lower.at(self.x1)),
            pt(self.x1, self.upper.at(self.x1)),
            pt(self.x0, self.upper.at(self.x0)),
        ]
    }
}

/// A side shared by two cells of neighbouring slabs.
#[derive(Clone, Copy, Debug)]
struct Shared {
    cells: [u32; 2],
    mid: (f64, f64),
}

/// The decomposition of one world.
#[derive(Debug, Default)]
struct Decomposition {
    cells: Vec<Cell>,
    shared: Vec<Shared>,
    /// Per cell, the shared sides it has (CSR: `sides_of[first[c]..first[c + 1]]`).
    first: Vec<u32>,
    sides_of: Vec<u32>,
    /// Slab `s` spans `events[s]..events[s + 1]` and holds cells `slab_first[s]..slab_first[s+1]`.
    events: Vec<f64>,
    slab_first: Vec<u32>,
}

impl Decomposition {
    fn memory_bytes(&self) -> usize {
        use std::mem::size_of;
        self.cells.len() * size_of::<Cell>()
            + self.shared.len() * size_of::<Shared>()
            + (self.first.len() + self.sides_of.len() + self.slab_first.len()) * 4
            + self.events.len() * 8
    }

    /// The cell holding `p` (the first one, when `p` is on a shared side).
    fn locate(&self, p: PointM) -> Option<usize> {
        let p = (p.x_m as f64, p.y_m as f64);
        // The slabs whose x-range holds p.x: at most two (p on an event).
        let s = self.events.partition_point(|&x| x < p.0 - SAME_X_M);
        let slabs = s.saturating_sub(1)..(s + 1).min(self.slab_first.len().saturating_sub(1));
        slabs
            .flat_map(|s| self.slab_first[s] as usize..self.slab_first[s + 1] as usize)
            .find(|&c| self.cells[c].contains(p))
    }

    fn sides(&self, cell: usize) -> &[u32] {
        &self.sides_of[self.first[cell] as usize..self.first[cell + 1] as usize]
    }
}

/// A segment, metres.
type Segment = ((f64, f64), (f64, f64));

/// The x of every event of `grown` inside the free box, sorted, merged within [`SAME_X_M`].
fn events(grown: &HostGrown) -> Vec<f64> {
    let b = grown.free_box();
    let (x_min, x_max) = (b.x_min_m as f64, b.x_max_m as f64);
    let (y_min, y_max) = (b.y_min_m as f64, b.y_max_m as f64);
    let mut xs = vec![x_min, x_max];
    let edges = |poly: &[PointM]| {
        let n = poly.len();
        let pts: Vec<(f64, f64)> = poly.iter().map(|p| (p.x_m as f64, p.y_m as f64)).collect();
        (0..n)
            .map(move |i| (pts[i], pts[(i + 1) % n]))
            .collect::<Vec<_>>()
    };
    let polys: Vec<Vec<Segment>> = grown.iter().map(edges).collect();
    for (i, pi) in polys.iter().enumerate() {
        for &(p, q) in pi {
            xs.push(p.0);
            // Crossings with the free box's bottom and top.
            for y in [y_min, y_max] {
                if (p.1 - y) * (q.1 - y) < 0.0 {
                    xs.push(p.0 + (y - p.1) * (q.0 - p.0) / (q.1 - p.1));
                }
            }
        }
        let bi = grown.bbox(i);
        for (j, pj) in polys.iter().enumerate().skip(i + 1) {
            let bj = grown.bbox(j);
            let overlap = match (bi, bj) {
                (Some(a), Some(b)) => {
                    a.x_min_m <= b.x_max_m
                        && b.x_min_m <= a.x_max_m
                        && a.y_min_m <= b.y_max_m
                        && b.y_min_m <= a.y_max_m
                }
                _ => false,
            };
            if !overlap {
                continue;
            }
            for &(a, b) in pi {
                for &(c, d) in pj {
                    if let Some(x) = crossing_x(a, b, c, d) {
                        xs.push(x);
                    }
                }
            }
        }
    }
    xs.retain(|&x| x.is_finite() && x >= x_min && x <= x_max);
    xs.sort_by(f64::total_cmp);
    let mut out: Vec<f64> = Vec::with_capacity(xs.len());
    for x in xs {
        if out.last().is_none_or(|&l| x - l > SAME_X_M) {
            out.push(x);
        }
    }
    out
}

/// The x where segments `a`–`b` and `c`–`d` cross properly (interiors meet at one point).
fn crossing_x(a: (f64, f64), b: (f64, f64), c: (f64, f64), d: (f64, f64)) -> Option<f64> {
    let r = (b.0 - a.0, b.1 - a.1);
    let s = (d.0 - c.0, d.1 - c.1);
    let den = r.0 * s.1 - r.1 * s.0;
    if den == 0.0 {
        return None;
    }
    let t = ((c.0 - a.0) * s.1 - (c.1 - a.1) * s.0) / den;
    let u = ((c.0 - a.0) * r.1 - (c.1 - a.1) * r.0) / den;
    ((0.0..=1.0).contains(&t) && (0.0..=1.0).contains(&u)).then_some(a.0 + t * r.0)
}

/// Cut the free space of `grown` into slab-wise trapezoids and join them.
fn decompose(grown: &HostGrown) -> anyhow::Result<Decomposition> {
    let b = grown.free_box();
    let (y_min, y_max) = (b.y_min_m as f64, b.y_max_m as f64);
    let mut dec = Decomposition {
        events: if b.is_empty() {
            Vec::new()
        } else {
            events(grown)
        },
        ..Default::default()
    };
    dec.slab_first.push(0);
    let boxes: Vec<_> = (0..grown.len()).filter_map(|i| grown.bbox(i)).collect();
    for s in 0..dec.events.len().saturating_sub(1) {
        let (x0, x1) = (dec.events[s], dec.events[s + 1]);
        let xm = 0.5 * (x0 + x1);
        // The covered interval of each grown polygon on the line x = xm: its lower edge goes
        // left to right, its upper edge right to left (counter-clockwise).
        let mut covered: Vec<(Line, Line)> = Vec::new();
        for (poly, bx) in grown.iter().zip(&boxes) {
            if poly.len() < 3 || !((bx.x_min_m as f64) < xm && xm < bx.x_max_m as f64) {
                continue;
            }
            let (mut lo, mut hi) = (None, None);
            for i in 0..poly.len() {
                let (p, q) = (poly[i], poly[(i + 1) % poly.len()]);
                let (p, q) = ((p.x_m as f64, p.y_m as f64), (q.x_m as f64, q.y_m as f64));
                if p.0 < xm && xm < q.0 {
                    lo = Some(Line::through(p, q));
                } else if q.0 < xm && xm < p.0 {
                    hi = Some(Line::through(p, q));
                }
            }
            if let (Some(lo), Some(hi)) = (lo, hi) {
                covered.push((lo, hi));
            }
        }
        covered.sort_by(|a, b| a.0.at(xm).total_cmp(&b.0.at(xm)));
        // Sweep the line upwards: `floor` is the top of what is covered so far.
        let mut floor = Line::flat(y_min);
        let top = Line::flat(y_max);
        let push = |lower: Line, upper: Line, dec: &mut Decomposition| {
            if upper.at(xm) - lower.at(xm) > MIN_GAP_M {
                dec.cells.push(Cell {
                    x0,
                    x1,
                    lower,
                    upper,
                });
            }
        };
        for (lo, hi) in covered {
            if floor.at(xm) >= y_max {
                break;
            }
            if lo.at(xm) > floor.at(xm) {
                let ceiling = if lo.at(xm) < y_max { lo } else { top };
                push(floor, ceiling, &mut dec);
            }
            if hi.at(xm) > floor.at(xm) {
                floor = hi;
            }
        }
        if floor.at(xm) < y_max {
            push(floor, top, &mut dec);
        }
        if dec.cells.len() > MAX_CELLS {
            bail!("trapezoidal decomposition: more than {MAX_CELLS} cells");
        }
        dec.slab_first.push(dec.cells.len() as u32);
    }
    // Shared sides between neighbouring slabs: both lists go bottom to top.
    for s in 0..dec.slab_first.len().saturating_sub(2) {
        let x = dec.events[s + 1];
        let (mut i, i_end) = (dec.slab_first[s] as usize, dec.slab_first[s + 1] as usize);
        let (mut j, j_end) = (i_end, dec.slab_first[s + 2] as usize);
        while i < i_end && j < j_end {
            let (l, r) = (&dec.cells[i], &dec.cells[j]);
            let lo = l.lower.at(x).max(r.lower.at(x));
            let hi = l.upper.at(x).min(r.upper.at(x));
            if hi - lo > MIN_GAP_M {
                dec.shared.push(Shared {
                    cells: [i as u32, j as u32],
                    mid: (x, 0.5 * (lo + hi)),
                });
            }
            if l.upper.at(x) < r.upper.at(x) {
                i += 1;
            } else {
                j += 1;
            }
        }
    }
    let mut count = vec![0u32; dec.cells.len() + 1];
    for sh in &dec.shared {
        for c in sh.cells {
            count[c as usize + 1] += 1;
        }
    }
    for c in 0..dec.cells.len() {
        count[c + 1] += count[c];
    }
    dec.first = count.clone();
    dec.sides_of = vec![0; dec.shared.len() * 2];
    for (k, sh) in dec.shared.iter().enumerate() {
        for c in sh.cells {
            dec.sides_of[count[c as usize] as usize] = k as u32;
            count[c as usize] += 1;
        }
    }
    Ok(dec)
}

/// What the search found.
struct Search {
    path: Vec<PointM>,
    cells_visited: usize,
}

/// Dijkstra over the shared sides' midpoints from `start` (in cell `sc`) to `goal` (in `gc`).
fn search(dec: &Decomposition, start: PointM, sc: usize, goal: PointM, gc: usize) -> Search {
    let sp = (start.x_m as f64, start.y_m as f64);
    let gp = (goal.x_m as f64, goal.y_m as f64);
    let dist = |a: (f64, f64), b: (f64, f64)| (a.0 - b.0).hypot(a.1 - b.1);
    let mut visited = vec![false; dec.cells.len()];
    visited[sc] = true;
    let mut cells_visited = 1;
    if sc == gc {
        return Search {
            path: vec![start, goal],
            cells_visited,
        };
    }
    // Node k < shared.len() is a shared side; node `goal_node` is the goal.
    let goal_node = dec.shared.len();
    let mut best = vec![f64::INFINITY; goal_node + 1];
    let mut prev = vec![u32::MAX; goal_node + 1];
    let mut done = vec![false; goal_node + 1];
    // Non-negative f64 order like their bit patterns.
    let mut open = BinaryHeap::new();
    for &k in dec.sides(sc) {
        let d = dist(sp, dec.shared[k as usize].mid);
        best[k as usize] = d;
        open.push(Reverse((d.to_bits(), k)));
    }
    while let Some(Reverse((bits, k))) = open.pop() {
        let k = k as usize;
        if done[k] || f64::from_bits(bits) > best[k] {
            continue;
        }
        done[k] = true;
        if k == goal_node {
            break;
        }
        let here = dec.shared[k].mid;
        for c in dec.shared[k].cells {
            let c = c as usize;
            if !visited[c] {
                visited[c] = true;
                cells_visited += 1;
            }
            let mut relax = |to: usize, at: (f64, f64), open: &mut BinaryHeap<_>| {
                let d = best[k] + dist(here, at);
                if d < best[to] {
                    best[to] = d;
                    prev[to] = k as u32;
                    open.push(Reverse((d.to_bits(), to as u32)));
                }
            };
            if c == gc {
                relax(goal_node, gp, &mut open);
            }
            for &k2 in dec.sides(c) {
                let k2 = k2 as usize;
                if !done[k2] {
                    relax(k2, dec.shared[k2].mid, &mut open);
                }
            }
        }
    }
    if !done[goal_node] {
        return Search {
            path: Vec::new(),
            cells_visited,
        };
    }
    let mut path = vec![goal];
    let mut at = prev[goal_node];
    while (at as usize) < goal_node {
        let m = dec.shared[at as usize].mid;
        path.push(PointM::new(m.0 as f32, m.1 as f32));
        at = prev[at as usize];
    }
    path.push(start);
    path.reverse();
    Search {
        path,
        cells_visited,
    }
}

/// Plan with the trapezoidal decomposition on `world`.
pub fn run(world: &World) -> anyhow::Result<Run> {
    let t0 = Instant::now();
    let grown = grow(world)?;
    let dec = decompose(&grown)?;
    let (start, goal) = (world.params.start, world.params.goal);
    let place = |p: PointM, blocked: Status| match grown.place(p) {
        PointPlace::Free => None,
        PointPlace::OutOfMap => Some(Status::OutOfBounds),
        PointPlace::NearBorder | PointPlace::InObstacle(_) => Some(blocked),
    };
    let mut status = place(start, Status::StartBlocked)
        .or_else(|| place(goal, Status::GoalBlocked))
        .unwrap_or(Status::Found);
    let (mut path, mut cells_visited) = (Vec::new(), 0);
    if status == Status::Found {
        match (dec.locate(start), dec.locate(goal)) {
            (None, _) => status = Status::StartBlocked,
            (_, None) => status = Status::GoalBlocked,
            (Some(sc), Some(gc)) => {
                let found = search(&dec, start, sc, goal, gc);
                cells_visited = found.cells_visited;
                path = found.path;
                if path.is_empty() {
                    status = Status::Unreachable;
                }
            }
        }
    }
    let elapsed_us = t0.elapsed().as_micros() as u64;
    let mut extra = serde_json::Map::new();
    extra.insert("cells".into(), dec.cells.len().into());
    extra.insert("adjacencies".into(), dec.shared.len().into());
    extra.insert(
        "slabs".into(),
        dec.slab_first.len().saturating_sub(1).into(),
    );
    let overlay = Overlay {
        cells: dec.cells.iter().map(Cell::corners).collect(),
        nodes: dec
            .shared
            .iter()
            .map(|s| PointM::new(s.mid.0 as f32, s.mid.1 as f32))
            .collect(),
        ..Default::default()
    };
    Ok(Run {
        method: Method::Trapezoid,
        status,
        // (The sum of no legs is -0.0 in f32: say 0.)
        length_m: if path.is_empty() {
            0.0
        } else {
            super::polyline_length_m(&path)
        },
        path,
        expanded: cells_visited as u64,
        expanded_unit: "cells",
        memory_bytes: grown.memory_bytes() + dec.memory_bytes(),
        elapsed_us: elapsed_us.max(1),
        overlay,
        extra,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crossings_are_found_where_segments_cross() {
        let x = crossing_x((0.0, 0.0), (2.0, 2.0), (0.0, 2.0), (2.0, 0.0));
        assert_eq!(x, Some(1.0));
        assert_eq!(
            crossing_x((0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)),
            None
        );
        assert_eq!(
            crossing_x((0.0, 0.0), (1.0, 1.0), (2.0, 0.0), (3.0, -5.0)),
            None
        );
    }

    #[test]
    fn a_cell_contains_its_inside_and_not_its_outside() {
        let c = Cell {
            x0: 0.0,
            x1: 2.0,
            lower: Line::through((0.0, 0.0), (2.0, 1.0)),
            upper: Line::flat(3.0),
        };
        assert!(c.contains((1.0, 1.0)));
        assert!(c.contains((1.0, 0.5)));
        assert!(!c.contains((1.0, 0.4)));
        assert!(!c.contains((2.5, 2.0)));
        assert_eq!(c.corners().len(), 4);
    }
}
