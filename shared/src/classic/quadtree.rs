//! Approximate cell decomposition by a quadtree (seed 001, map models: quadtrees; seed 004 §2.2,
//! approximate decomposition with EMPTY / FULL / MIXED cells and the E- and M-channels).
//!
//! Design:
//! - **The same free space as the grid planners.** A leaf is a square of grid cells of the
//!   map of grown obstacles; the root covers the map padded to a power of two cells a side.
//!   A leaf is [`LeafKind::Empty`] when all its cells are free, [`LeafKind::Full`] when all are
//!   blocked or outside the map, [`LeafKind::Mixed`] otherwise. The resolution limit is one
//!   grid cell, so a 1-cell leaf is never MIXED and the refinement always ends.
//! - **Only the leaves are stored** (no inner nodes): the decomposition is a pool of
//!   [`Leaf`]s (8 bytes each) in the caller's slice; a split reuses the parent's slot and appends
//!   three. A full pool is [`QuadError::LeavesFull`], never a panic.
//! - **Adjacency** (leaves sharing a piece of a side) is read off `owner`, the leaf of every
//!   map cell, by walking the cells just outside a leaf's four sides: O(perimeter).
//! - **Search**: A* on leaves, the cost of a step being the distance between the two leaves'
//!   centres (heuristic: centre to the goal leaf's centre). The path itself goes start → the
//!   midpoints of the shared sides → goal ([`shared_side_mid2`]): each leg lies in one
//!   (convex) EMPTY leaf, so the path stays in free cells.
//! - **The seed's iteration**: search the E-channel (EMPTY leaves only); if none joins start
//!   and goal, search the M-channel (EMPTY and MIXED); if there is none either, the goal is
//!   unreachable at any resolution; else split every MIXED leaf of the M-channel in four and
//!   start again. Each round splits at least one leaf, so the rounds end.
//!
//! Distances are integers: leaf centres in half cells, costs in 1/16 of a half cell.

use super::cell_heap::CellHeap;
use super::distance::isqrt;
use crate::grid::Grid;
use crate::plan::PlanStatus;

/// What a leaf holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LeafKind {
    /// Every cell free.
    #[default]
    Empty,
    /// Every cell blocked or outside the map.
    Full,
    /// Some free, some blocked (only leaves larger than one cell).
    Mixed,
}

/// A square leaf of the decomposition: its lowest-x, lowest-y cell and its side, in cells.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Leaf {
    /// Column of its first cell.
    pub x: u16,
    /// Row of its first cell.
    pub y: u16,
    /// Side, cells (a power of two).
    pub side: u16,
    /// EMPTY, FULL or MIXED.
    pub kind: LeafKind,
}

impl Leaf {
    /// Centre, in half cells.
    fn centre2(&self) -> (i64, i64) {
        (
            2 * self.x as i64 + self.side as i64,
            2 * self.y as i64 + self.side as i64,
        )
    }
}

/// Why the decomposition or the search could not go on (no path is a status, not an error).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum QuadError {
    /// The leaf pool is full.
    LeavesFull {
        /// Its capacity, leaves.
        capacity: usize,
    },
    /// The search's priority queue is full.
    HeapFull {
        /// Its capacity, entries.
        capacity: usize,
    },
    /// `owner` is not one entry per map cell, or `cost` / `parent` shorter than `leaves`.
    BufferTooShort,
    /// The path does not fit the `path` buffer.
    PathTooLong,
}

impl core::fmt::Display for QuadError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            QuadError::LeavesFull { capacity } => {
                write!(f, "the leaf pool is full ({capacity} leaves)")
            }
            QuadError::HeapFull { capacity } => {
                write!(
                    f,
                    "the search's priority queue is full ({capacity} entries)"
                )
            }
            QuadError::BufferTooShort => write!(
                f,
                "the owner buffer is not one entry per map cell, or the cost/parent buffers are \
                 shorter than the leaves"
            ),
            QuadError::PathTooLong => write!(f, "the path does not fit the path buffer"),
        }
    }
}

impl core::error::Error for QuadError {}

/// The caller's buffers.
#[derive(Debug)]
pub struct QuadBuffers<'a> {
    /// The leaf pool (its length is the capacity).
    pub leaves: &'a mut [Leaf],
    /// The leaf of every map cell (row-major, one entry per cell).
    pub owner: &'a mut [u32],
    /// Search cost per leaf (as long as `leaves`).
    pub cost: &'a mut [u32],
    /// Search parent per leaf (as long as `leaves`).
    pub parent: &'a mut [u32],
    /// The priority queue.
    pub heap: &'a mut [u64],
    /// Output: the leaves of the path, start leaf first.
    pub path: &'a mut [u32],
}

/// What a run found and did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct QuadReport {
    /// How it ended.
    pub status: PlanStatus,
    /// Leaves of the path written to `path`.
    pub path_leaves: usize,
    /// Leaves of the final decomposition (stored in `leaves[..leaves]`).
    pub leaves: usize,
    /// MIXED leaves split into four.
    pub refinements: usize,
    /// Rounds of E-channel / M-channel search.
    pub rounds: usize,
    /// Leaves popped by all the searches.
    pub expanded: u64,
    /// Side of the root, cells.
    pub root_side: u16,
    /// Most entries the heap held.
    pub heap_peak: usize,
}

/// The midpoint of the side piece that leaves `a` and `b` share, in half cells (`None` when
/// they share no piece of a side).
pub fn shared_side_mid2(a: &Leaf, b: &Leaf) -> Option<(i64, i64)> {
    let span = |l: &Leaf| {
        (
            l.x as i64,
            l.x as i64 + l.side as i64,
            l.y as i64,
            l.y as i64 + l.side as i64,
        )
    };
    let (ax0, ax1, ay0, ay1) = span(a);
    let (bx0, bx1, by0, by1) = span(b);
    let overlap = |lo0: i64, hi0: i64, lo1: i64, hi1: i64| {
        let (lo, hi) = (lo0.max(lo1), hi0.min(hi1));
        (lo < hi).then_some(lo + hi)
    };
    if ax1 == bx0 || bx1 == ax0 {
        let x = if ax1 == bx0 { ax1 } else { ax0 };
        return overlap(ay0, ay1, by0, by1).map(|y2| (2 * x, y2));
    }
    if ay1 == by0 || by1 == ay0 {
        let y = if ay1 == by0 { ay1 } else { ay0 };
        return overlap(ax0, ax1, bx0, bx1).map(|x2| (x2, 2 * y));
    }
    None
}

/// Classify the square at (`x`, `y`) of side `side` on `grid` (outside the map is blocked).
pub fn classify<const W: usize>(grid: &Grid<W>, x: u16, y: u16, side: u16) -> LeafKind {
    let (mut free, mut blocked) = (false, false);
    for cy in y as i32..y as i32 + side as i32 {
        for cx in x as i32..x as i32 + side as i32 {
            if grid.is_occupied_xy(cx, cy) {
                blocked = true;
            } else {
                free = true;
            }
            if free && blocked {
                return LeafKind::Mixed;
            }
        }
    }
    if free {
        LeafKind::Empty
    } else {
        LeafKind::Full
    }
}

struct Tree<'g, 'b, const W: usize> {
    grid: &'g Grid<W>,
    w: i32,
    h: i32,
    leaves: &'b mut [Leaf],
    len: usize,
    owner: &'b mut [u32],
}

impl<const W: usize> Tree<'_, '_, W> {
    fn set_owner(&mut self, id: usize) {
        let l = self.leaves[id];
        let x1 = (l.x as i32 + l.side as i32).min(self.w);
        let y1 = (l.y as i32 + l.side as i32).min(self.h);
        for y in l.y as i32..y1 {
            for x in l.x as i32..x1 {
                if let Some(o) = self.owner.get_mut((y * self.w + x) as usize) {
                    *o = id as u32;
                }
            }
        }
    }

    /// Split leaf `id` (MIXED, side ≥ 2) into four classified children.
    fn split(&mut self, id: usize) -> Result<(), QuadError> {
        let capacity = self.leaves.len();
        if self.len + 3 > capacity {
            return Err(QuadError::LeavesFull { capacity });
        }
        let l = self.leaves[id];
        let half = l.side / 2;
        let corners = [
            (l.x, l.y),
            (l.x + half, l.y),
            (l.x, l.y + half),
            (l.x + half, l.y + half),
        ];
        for (k, (x, y)) in corners.into_iter().enumerate() {
            let slot = if k == 0 { id } else { self.len + k - 1 };
            self.leaves[slot] = Leaf {
                x,
                y,
                side: half,
                kind: classify(self.grid, x, y, half),
            };
        }
        self.len += 3;
        for slot in [id, self.len - 3, self.len - 2, self.len - 1] {
            self.set_owner(slot);
        }
        Ok(())
    }

    fn leaf_of(&self, x: i32, y: i32) -> Option<usize> {
        if x < 0 || y < 0 || x >= self.w || y >= self.h {
            return None;
        }
        self.owner
            .get((y * self.w + x) as usize)
            .map(|&o| o as usize)
    }

    /// Call `f` once per leaf that shares a piece of a side with leaf `id`.
    fn neighbours(
        &self,
        id: usize,
        f: &mut impl FnMut(usize) -> Result<(), QuadError>,
    ) -> Result<(), QuadError> {
        let l = self.leaves[id];
        let (x0, y0, s) = (l.x as i32, l.y as i32, l.side as i32);
        // The cells just outside each side; a neighbour shows as one run of equal owners.
        let sides = [
            (x0 - 1, y0, 0, 1),
            (x0 + s, y0, 0, 1),
            (x0, y0 - 1, 1, 0),
            (x0, y0 + s, 1, 0),
        ];
        for (sx, sy, dx, dy) in sides {
            let mut last = None;
            for k in 0..s {
                let Some(n) = self.leaf_of(sx + k * dx, sy + k * dy) else {
                    continue;
                };
                if last != Some(n) {
                    last = Some(n);
                    f(n)?;
                }
            }
        }
        Ok(())
    }
}

/// Distance between the centres of two leaves, 1/16 half cell.
fn step_cost(a: &Leaf, b: &Leaf) -> u32 {
    let ((ax, ay), (bx, by)) = (a.centre2(), b.centre2());
    let (dx, dy) = (ax - bx, ay - by);
    isqrt(((dx * dx + dy * dy) as u64) * 256).min(u32::MAX as u64) as u32
}

/// The searches' scratch: a cost and a parent per leaf, the queue, the leaves popped.
struct Scratch<'b> {
    cost: &'b mut [u32],
    parent: &'b mut [u32],
    heap: CellHeap<'b>,
    expanded: u64,
}

/// A* over the leaves whose kind `allowed` accepts, from leaf `s` to leaf `t`; parents in
/// `sc.parent`. `true` when `t` was reached.
fn search<const W: usize>(
    tree: &Tree<'_, '_, W>,
    s: usize,
    t: usize,
    allowed: impl Fn(LeafKind) -> bool,
    sc: &mut Scratch<'_>,
) -> Result<bool, QuadError> {
    let n = tree.len;
    let (heap, expanded) = (&mut sc.heap, &mut sc.expanded);
    let (cost, parent) = match (sc.cost.get_mut(..n), sc.parent.get_mut(..n)) {
        (Some(c), Some(p)) => (c, p),
        _ => return Err(QuadError::BufferTooShort),
    };
    cost.fill(u32::MAX);
    heap.clear();
    let goal = tree.leaves[t];
    let h = |l: &Leaf| step_cost(l, &goal);
    cost[s] = 0;
    parent[s] = s as u32;
    let full = |e: super::cell_heap::HeapFull| QuadError::HeapFull {
        capacity: e.capacity,
    };
    heap.push(h(&tree.leaves[s]), s as u32).map_err(full)?;
    while let Some((key, item)) = heap.pop() {
        let i = item as usize;
        let g = cost[i];
        if key != g.saturating_add(h(&tree.leaves[i])) {
            continue; // stale entry
        }
        *expanded += 1;
        if i == t {
            return Ok(true);
        }
        let li = tree.leaves[i];
        tree.neighbours(i, &mut |j| {
            let lj = tree.leaves[j];
            if !allowed(lj.kind) {
                return Ok(());
            }
            let ng = g.saturating_add(step_cost(&li, &lj));
            if ng < cost[j] {
                cost[j] = ng;
                parent[j] = i as u32;
                heap.push(ng.saturating_add(h(&lj)), j as u32)
                    .map_err(full)?;
            }
            Ok(())
        })?;
    }
    Ok(false)
}

/// Plan from `start` to `goal` on `grid` (grown obstacles) by the quadtree's E- and M-channels.
/// The final decomposition is left in `bufs.leaves[..report.leaves]`, the path's leaves in
/// `bufs.path[..report.path_leaves]`.
pub fn plan<const W: usize>(
    grid: &Grid<W>,
    start: crate::geom::PointM,
    goal: crate::geom::PointM,
    bufs: QuadBuffers<'_>,
) -> Result<QuadReport, QuadError> {
    let geo = *grid.geometry();
    let (w, h) = (geo.width() as i32, geo.height() as i32);
    let capacity = bufs.leaves.len();
    if bufs.owner.len() < geo.cell_count()
        || bufs.cost.len() < capacity
        || bufs.parent.len() < capacity
    {
        return Err(QuadError::BufferTooShort);
    }
    let root_side = (w.max(h) as u32)
        .next_power_of_two()
        .min(u16::MAX as u32 / 2 + 1) as u16;
    let mut report = QuadReport {
        status: PlanStatus::Unreachable,
        path_leaves: 0,
        leaves: 0,
        refinements: 0,
        rounds: 0,
        expanded: 0,
        root_side,
        heap_peak: 0,
    };
    let Some(root) = bufs.leaves.first_mut() else {
        return Err(QuadError::LeavesFull { capacity: 0 });
    };
    *root = Leaf {
        x: 0,
        y: 0,
        side: root_side,
        kind: classify(grid, 0, 0, root_side),
    };
    bufs.owner.fill(0);
    let mut tree = Tree {
        grid,
        w,
        h,
        leaves: bufs.leaves,
        len: 1,
        owner: bufs.owner,
    };
    report.leaves = 1;
    let (s_cell, t_cell) = match super::voronoi::endpoints(grid, start, goal) {
        Ok(st) => st,
        Err(status) => {
            report.status = status;
            return Ok(report);
        }
    };
    let mut sc = Scratch {
        cost: bufs.cost,
        parent: bufs.parent,
        heap: CellHeap::new(bufs.heap),
        expanded: 0,
    };
    let path = bufs.path;
    let leaf_at = |tree: &Tree<'_, '_, W>, c: crate::geom::Cell| {
        tree.leaf_of(c.x as i32, c.y as i32)
            .ok_or(QuadError::BufferTooShort)
    };
    let (s, t) = loop {
        report.rounds += 1;
        let (s, t) = (leaf_at(&tree, s_cell)?, leaf_at(&tree, t_cell)?);
        let (ks, kt) = (tree.leaves[s].kind, tree.leaves[t].kind);
        if ks == LeafKind::Empty && kt == LeafKind::Empty {
            let empty = |k| k == LeafKind::Empty;
            if search(&tree, s, t, empty, &mut sc)? {
                break (s, t);
            }
        }
        let not_full = |k| k != LeafKind::Full;
        if !search(&tree, s, t, not_full, &mut sc)? {
            report.leaves = tree.len;
            report.heap_peak = sc.heap.peak();
            report.expanded = sc.expanded;
            return Ok(report);
        }
        // Split the MIXED leaves of the M-channel (a split keeps the parent's slot for its
        // first child, so walk the channel first and split after).
        let mut i = t;
        let mut split_any = false;
        loop {
            let p = *sc.parent.get(i).ok_or(QuadError::BufferTooShort)? as usize;
            if tree.leaves[i].kind == LeafKind::Mixed {
                // Splitting `i` only appends leaves: the parents of the channel still hold.
                tree.split(i)?;
                report.refinements += 1;
                split_any = true;
            }
            if i == s {
                break;
            }
            i = p;
        }
        if !split_any {
            // Cannot happen (an all-EMPTY M-channel is an E-channel); never loop forever.
            return Err(QuadError::PathTooLong);
        }
    };
    // The path's leaves, start first.
    let mut count = 1;
    let mut i = t;
    while i != s {
        i = sc.parent[i] as usize;
        count += 1;
        if count > tree.len {
            return Err(QuadError::PathTooLong);
        }
    }
    let out = path.get_mut(..count).ok_or(QuadError::PathTooLong)?;
    let mut i = t;
    for slot in out.iter_mut().rev() {
        *slot = i as u32;
        i = sc.parent[i] as usize;
    }
    report.path_leaves = count;
    report.expanded = sc.expanded;
    report.leaves = tree.len;
    report.heap_peak = sc.heap.peak();
    report.status = PlanStatus::Found;
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::PointM;
    use crate::grid::{Grid300, GridGeometry};

    /// A `w` x `h` grid of 1 m cells with `blocked` cells set.
    fn grid(w: f32, h: f32, blocked: &[(i32, i32)]) -> Grid300 {
        let mut g = Grid300::new(GridGeometry::from_size_m(w, h, 1.0).unwrap()).unwrap();
        for &(x, y) in blocked {
            g.set_xy(x, y, true);
        }
        g
    }

    struct Bufs {
        leaves: [Leaf; 256],
        owner: [u32; 256],
        cost: [u32; 256],
        parent: [u32; 256],
        heap: [u64; 1024],
        path: [u32; 256],
    }

    impl Bufs {
        fn new() -> Self {
            Self {
                leaves: [Leaf::default(); 256],
                owner: [0; 256],
                cost: [0; 256],
                parent: [0; 256],
                heap: [0; 1024],
                path: [0; 256],
            }
        }

        fn run(&mut self, g: &Grid300, s: (f32, f32), t: (f32, f32), cap: usize) -> QuadResult {
            plan(
                g,
                PointM::new(s.0, s.1),
                PointM::new(t.0, t.1),
                QuadBuffers {
                    leaves: &mut self.leaves[..cap],
                    owner: &mut self.owner,
                    cost: &mut self.cost,
                    parent: &mut self.parent,
                    heap: &mut self.heap,
                    path: &mut self.path,
                },
            )
        }
    }

    type QuadResult = Result<QuadReport, QuadError>;

    #[test]
    fn classification_reads_every_cell_and_the_outside_is_blocked() {
        let g = grid(4.0, 4.0, &[(3, 3)]);
        assert_eq!(classify(&g, 0, 0, 2), LeafKind::Empty);
        assert_eq!(classify(&g, 2, 2, 2), LeafKind::Mixed);
        assert_eq!(classify(&g, 3, 3, 1), LeafKind::Full);
        assert_eq!(classify(&g, 0, 0, 4), LeafKind::Mixed);
        // Beyond the 4 x 4 map everything is blocked.
        assert_eq!(classify(&g, 4, 0, 4), LeafKind::Full);
        assert_eq!(classify(&g, 2, 0, 4), LeafKind::Mixed);
    }

    #[test]
    fn an_empty_map_is_split_only_down_to_the_map() {
        // 4 x 4 free: the root is EMPTY, one round, no split, start and goal in one leaf.
        let g = grid(4.0, 4.0, &[]);
        let r = Bufs::new().run(&g, (0.5, 0.5), (3.5, 3.5), 256).unwrap();
        assert_eq!(r.status, PlanStatus::Found);
        assert_eq!(
            (r.leaves, r.refinements, r.rounds, r.path_leaves),
            (1, 0, 1, 1)
        );
        // 6 x 6 free: the 8 x 8 root sticks out of the map, so it is MIXED and split.
        let g = grid(6.0, 6.0, &[]);
        let mut b = Bufs::new();
        let r = b.run(&g, (0.5, 0.5), (5.5, 5.5), 256).unwrap();
        assert_eq!(r.status, PlanStatus::Found);
        assert!(r.refinements >= 1 && r.rounds >= 2, "{r:?}");
        for id in &b.path[..r.path_leaves] {
            assert_eq!(b.leaves[*id as usize].kind, LeafKind::Empty);
        }
    }

    #[test]
    fn refinement_opens_a_door_one_cell_wide() {
        // A wall at x = 4 of an 8 x 8 map with a one-cell door at y = 5.
        let wall = [(4, 0), (4, 1), (4, 2), (4, 3), (4, 4), (4, 6), (4, 7)];
        let g = grid(8.0, 8.0, &wall);
        let mut b = Bufs::new();
        let r = b.run(&g, (1.5, 1.5), (6.5, 1.5), 256).unwrap();
        assert_eq!(r.status, PlanStatus::Found, "{r:?}");
        assert!(r.refinements >= 3, "{r:?}");
        // The path passes through the door cell, a 1-cell leaf.
        let door = b.path[..r.path_leaves]
            .iter()
            .map(|&i| b.leaves[i as usize])
            .find(|l| l.x == 4);
        assert_eq!(
            door,
            Some(Leaf {
                x: 4,
                y: 5,
                side: 1,
                kind: LeafKind::Empty
            })
        );
        // Consecutive path leaves share a side.
        for pair in b.path[..r.path_leaves].windows(2) {
            let (a, c) = (b.leaves[pair[0] as usize], b.leaves[pair[1] as usize]);
            assert!(shared_side_mid2(&a, &c).is_some(), "{a:?} {c:?}");
        }
    }

    #[test]
    fn a_walled_goal_is_unreachable_and_blocked_ends_are_said() {
        let wall = [
            (4, 0),
            (4, 1),
            (4, 2),
            (4, 3),
            (4, 4),
            (4, 5),
            (4, 6),
            (4, 7),
        ];
        let g = grid(8.0, 8.0, &wall);
        let r = Bufs::new().run(&g, (1.5, 1.5), (6.5, 1.5), 256).unwrap();
        assert_eq!(r.status, PlanStatus::Unreachable);
        let r = Bufs::new().run(&g, (4.5, 1.5), (6.5, 1.5), 256).unwrap();
        assert_eq!(r.status, PlanStatus::StartBlocked);
        let r = Bufs::new().run(&g, (1.5, 1.5), (4.5, 7.5), 256).unwrap();
        assert_eq!(r.status, PlanStatus::GoalBlocked);
        let r = Bufs::new().run(&g, (1.5, 1.5), (9.5, 1.5), 256).unwrap();
        assert_eq!(r.status, PlanStatus::OutOfBounds);
    }

    #[test]
    fn a_full_pool_is_an_error() {
        let wall = [(4, 0), (4, 1), (4, 2), (4, 3), (4, 4), (4, 6), (4, 7)];
        let g = grid(8.0, 8.0, &wall);
        let r = Bufs::new().run(&g, (1.5, 1.5), (6.5, 1.5), 6);
        assert_eq!(r, Err(QuadError::LeavesFull { capacity: 6 }));
        assert_eq!(
            Bufs::new().run(&g, (1.5, 1.5), (6.5, 1.5), 0),
            Err(QuadError::LeavesFull { capacity: 0 })
        );
    }

    #[test]
    fn shared_sides_meet_in_their_middle() {
        let a = Leaf {
            x: 0,
            y: 0,
            side: 4,
            kind: LeafKind::Empty,
        };
        let b = Leaf {
            x: 4,
            y: 2,
            side: 2,
            kind: LeafKind::Empty,
        };
        assert_eq!(shared_side_mid2(&a, &b), Some((8, 6)));
        let c = Leaf {
            x: 1,
            y: 4,
            side: 1,
            kind: LeafKind::Empty,
        };
        assert_eq!(shared_side_mid2(&c, &a), Some((3, 8)));
        // Touching at a corner only is no side.
        let d = Leaf {
            x: 4,
            y: 4,
            side: 1,
            kind: LeafKind::Empty,
        };
        assert_eq!(shared_side_mid2(&a, &d), None);
    }
}
