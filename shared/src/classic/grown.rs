//! The configuration-space obstacles of the exact (polygon-based) planners: every `.da` polygon
//! grown by the robot, and the map border shrunk by it.
//!
//! Seeds: 003 §III (the obstacles `CB` of the configuration space, in which the robot is a
//! point) and the growth of its grid planner (`marca_pto` marks a square around every obstacle
//! point); 004 §2.1 (the C-obstacles).
//!
//! Design choices:
//! - **Square growth, like the seed and the grid planners.** The robot is a disc of radius `r`;
//!   each polygon is grown by the axis-aligned square of half-side `r` (its Minkowski sum). The
//!   square contains the disc, so a centre outside every grown polygon keeps the body off the
//!   obstacles, and all methods (grid or exact) see the same kind of free space. The price: near
//!   a convex corner the grown obstacle reaches `r·√2` instead of `r` (a little conservative).
//! - **Exact for convex polygons, conservative otherwise.** The Minkowski sum of a convex
//!   polygon and a square is the convex hull of the polygon's vertices shifted to the square's
//!   4 corners; we compute that hull (Andrew's monotone chain) for every polygon. For a
//!   non-convex polygon the hull also covers its pockets: still collision-free, but narrow
//!   passages inside a pocket are lost. Every bundled world is made of convex polygons.
//! - Grown polygons are stored counter-clockwise without collinear vertices, in a
//!   [`PolygonSet`] (capacities `V`, `P`), with their bounding boxes, so the tests below can
//!   skip polygons far from a segment. They may overlap (walls meeting at a corner): every test
//!   here looks at each polygon on its own, which is exactly right for a union.
//! - The map border: the centre must stay `r` inside the map, a box ([`Grown::free_box`]).
//! - Tolerance [`EPS_M`]: a point or a segment is "inside" a grown polygon only when it is deeper
//!   than 1 µm. So a segment grazing an edge, running along it or through a vertex is free,
//!   and f32 rounding of the vertices never blocks a tangent path. A path that penetrates less
//!   than 1 µm costs at most that much clearance (the tests allow 1e-4 m).
//!
//! The arithmetic of the tests is in f64 (exact enough for maps of kilometres); the points stay
//! `f32` [`PointM`] like the rest of the core.

use heapless::Vec;

use crate::geom::PointM;
use crate::math;
use crate::world::{PolygonSet, PolygonSetError};

/// How deep, metres, a point must be inside a grown polygon to count as inside.
pub const EPS_M: f64 = 1e-6;

/// An axis-aligned box, metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoxM {
    /// Left side.
    pub x_min_m: f32,
    /// Bottom side.
    pub y_min_m: f32,
    /// Right side.
    pub x_max_m: f32,
    /// Top side.
    pub y_max_m: f32,
}

impl BoxM {
    /// The bounding box of `points` (an empty, inverted box for no points).
    pub fn around(points: &[PointM]) -> Self {
        let mut b = BoxM {
            x_min_m: f32::INFINITY,
            y_min_m: f32::INFINITY,
            x_max_m: f32::NEG_INFINITY,
            y_max_m: f32::NEG_INFINITY,
        };
        for p in points {
            b.x_min_m = b.x_min_m.min(p.x_m);
            b.y_min_m = b.y_min_m.min(p.y_m);
            b.x_max_m = b.x_max_m.max(p.x_m);
            b.y_max_m = b.y_max_m.max(p.y_m);
        }
        b
    }

    /// Whether `p` lies in the box, sides included (with [`EPS_M`] of slack).
    pub fn contains(&self, p: PointM) -> bool {
        let e = EPS_M as f32;
        p.x_m >= self.x_min_m - e
            && p.x_m <= self.x_max_m + e
            && p.y_m >= self.y_min_m - e
            && p.y_m <= self.y_max_m + e
    }

    /// Whether the box has any area.
    pub fn is_empty(&self) -> bool {
        !(self.x_min_m < self.x_max_m && self.y_min_m < self.y_max_m)
    }

    /// Whether the box may meet segment `a`–`b`: their bounding boxes overlap and the
    /// segment's line does not leave all 4 corners strictly on one side (a cheap filter before
    /// the exact test; long diagonals cross many bounding boxes but few polygons).
    #[inline]
    fn may_meet_segment(&self, a: PointM, b: PointM) -> bool {
        if !(a.x_m.max(b.x_m) > self.x_min_m
            && a.x_m.min(b.x_m) < self.x_max_m
            && a.y_m.max(b.y_m) > self.y_min_m
            && a.y_m.min(b.y_m) < self.y_max_m)
        {
            return false;
        }
        let side = |x: f32, y: f32| cross(a, b, PointM::new(x, y));
        let corners = [
            side(self.x_min_m, self.y_min_m),
            side(self.x_max_m, self.y_min_m),
            side(self.x_max_m, self.y_max_m),
            side(self.x_min_m, self.y_max_m),
        ];
        !(corners.iter().all(|&c| c > 0.0) || corners.iter().all(|&c| c < 0.0))
    }
}

/// Why the grown obstacles could not be built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GrowError {
    /// The scratch buffer is shorter than [`scratch_len`] of the largest polygon.
    ScratchTooSmall {
        /// Points needed.
        needed: usize,
        /// Points given.
        given: usize,
    },
    /// The grown polygons do not fit the capacities.
    Capacity(PolygonSetError),
    /// The radius is negative or not a number, or a coordinate is not finite.
    NotFinite,
}

impl core::fmt::Display for GrowError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            GrowError::ScratchTooSmall { needed, given } => write!(
                f,
                "the scratch buffer holds {given} points, the largest polygon needs {needed}"
            ),
            GrowError::Capacity(e) => write!(f, "the grown polygons: {e}"),
            GrowError::NotFinite => write!(
                f,
                "the radius is negative or not a number, or a coordinate is not finite"
            ),
        }
    }
}

impl core::error::Error for GrowError {}

/// Scratch points [`Grown::build`] needs for polygons of up to `n` vertices.
pub const fn scratch_len(n: usize) -> usize {
    12 * n + 2
}

/// Where a point is relative to the free space.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PointPlace {
    /// The robot's centre may be there.
    Free,
    /// Outside the map itself.
    OutOfMap,
    /// Inside the map, but closer than the radius to its border.
    NearBorder,
    /// Inside grown polygon number `.0`.
    InObstacle(usize),
}

/// `(q - p) × (r - p)`, f64: positive when `r` is left of `p → q`.
fn cross(p: PointM, q: PointM, r: PointM) -> f64 {
    let (px, py) = (p.x_m as f64, p.y_m as f64);
    (q.x_m as f64 - px) * (r.y_m as f64 - py) - (q.y_m as f64 - py) * (r.x_m as f64 - px)
}

/// Convex hull of `points` (sorted in place) into `out`, counter-clockwise, without collinear or
/// repeated vertices; returns its vertex count (`0` when `out` is shorter than
/// `2 * points.len()`, the most the chains hold while they are built, which [`Grown::build`]
/// never lets happen).
pub fn convex_hull(points: &mut [PointM], out: &mut [PointM]) -> usize {
    let n = points.len();
    if n == 0 || out.len() < 2 * n {
        return 0;
    }
    points.sort_unstable_by(|a, b| a.x_m.total_cmp(&b.x_m).then(a.y_m.total_cmp(&b.y_m)));
    let mut k = 0usize;
    // Lower chain, then upper chain; a turn that is not strictly left is dropped.
    for &p in points.iter() {
        while k >= 2 && cross(out[k - 2], out[k - 1], p) <= 0.0 {
            k -= 1;
        }
        out[k] = p;
        k += 1;
    }
    let lower = k + 1;
    for &p in points.iter().rev().skip(1) {
        while k >= lower && cross(out[k - 2], out[k - 1], p) <= 0.0 {
            k -= 1;
        }
        out[k] = p;
        k += 1;
    }
    // The last point repeats the first (when there are at least two distinct points).
    let mut h = k.saturating_sub(1).max(1);
    if h == 2 && out[0] == out[1] {
        h = 1;
    }
    h
}

/// Whether segment `a`–`b` enters the interior of the convex counter-clockwise `polygon` deeper
/// than [`EPS_M`]. Grazing an edge, running along one, or passing through a vertex is not
/// entering. Polygons of fewer than 3 vertices have no interior.
///
/// Cyrus–Beck clipping: the points of the segment at least `EPS_M` inside every edge's line form
/// one interval of the parameter `t ∈ [0, 1]`; the segment enters iff it is not empty.
pub fn segment_enters(a: PointM, b: PointM, polygon: &[PointM]) -> bool {
    let n = polygon.len();
    segment_enters_scaled(a, b, polygon, |i| {
        let (p, q) = (polygon[i], polygon[(i + 1) % n]);
        1.0 / math::hypot(q.x_m - p.x_m, q.y_m - p.y_m) as f64
    })
}

/// [`segment_enters`] with the inverse length of edge `i` (from vertex `i`) given by `inv_len(i)` (a stored
/// value is much cheaper than a square root: this is the innermost loop of the visibility
/// graph). An infinite or NaN inverse length (an edge of length 0) makes that edge ignored.
fn segment_enters_scaled(
    a: PointM,
    b: PointM,
    polygon: &[PointM],
    inv_len: impl Fn(usize) -> f64,
) -> bool {
    let n = polygon.len();
    if n < 3 {
        return false;
    }
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    for i in 0..n {
        let (p, q) = (polygon[i], polygon[(i + 1) % n]);
        let (ca, cb) = (cross(p, q, a), cross(p, q, b));
        // Both ends outside this edge's line (or on it): the segment cannot enter.
        if ca <= 0.0 && cb <= 0.0 {
            return false;
        }
        let k = inv_len(i);
        if !k.is_finite() {
            continue;
        }
        // Signed distances of a and b inside this edge's line, less the tolerance.
        let da = ca * k - EPS_M;
        let db = cb * k - EPS_M;
        let slope = db - da;
        if slope == 0.0 {
            if da < 0.0 {
                return false;
            }
        } else if slope > 0.0 {
            lo = lo.max(-da / slope);
        } else {
            hi = hi.min(-da / slope);
        }
        if lo > hi {
            return false;
        }
    }
    true
}

/// Whether `p` is inside the convex counter-clockwise `polygon`, deeper than [`EPS_M`].
pub fn point_inside(p: PointM, polygon: &[PointM]) -> bool {
    segment_enters(p, p, polygon)
}

/// The grown obstacles and the free box of one world: up to `V` vertices in `P` polygons.
#[derive(Clone, Debug)]
pub struct Grown<const V: usize, const P: usize> {
    polygons: PolygonSet<V, P>,
    /// 1 / length of the edge that starts at each vertex, in the order of the vertices.
    inv_len: Vec<f32, V>,
    /// Index of each polygon's first vertex.
    firsts: Vec<u16, P>,
    boxes: Vec<BoxM, P>,
    free: BoxM,
    map: BoxM,
}

impl<const V: usize, const P: usize> Grown<V, P> {
    /// Grow every polygon of `obstacles` by the square of half-side `radius_m` in a map of
    /// `width_m` × `height_m` (origin at its lower-left corner). `scratch` holds at least
    /// [`scratch_len`] of the largest polygon's vertex count.
    pub fn build<'a>(
        obstacles: impl Iterator<Item = &'a [PointM]>,
        radius_m: f32,
        width_m: f32,
        height_m: f32,
        scratch: &mut [PointM],
    ) -> Result<Self, GrowError> {
        if !(radius_m.is_finite() && radius_m >= 0.0 && width_m.is_finite() && height_m.is_finite())
        {
            return Err(GrowError::NotFinite);
        }
        let mut polygons = PolygonSet::new();
        let mut inv_len = Vec::new();
        let mut firsts = Vec::new();
        let mut boxes = Vec::new();
        for polygon in obstacles {
            let n = polygon.len();
            let needed = scratch_len(n);
            if scratch.len() < needed {
                return Err(GrowError::ScratchTooSmall {
                    needed,
                    given: scratch.len(),
                });
            }
            if polygon.iter().any(|p| !p.is_finite()) {
                return Err(GrowError::NotFinite);
            }
            let (a, b) = scratch.split_at_mut(4 * n);
            // The hull of the polygon itself, then of its hull's vertices shifted to the corners.
            a[..n].copy_from_slice(polygon);
            let h = convex_hull(&mut a[..n], b);
            for (i, v) in b[..h].iter().enumerate() {
                for (j, (sx, sy)) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                    .into_iter()
                    .enumerate()
                {
                    a[4 * i + j] = PointM::new(v.x_m + sx * radius_m, v.y_m + sy * radius_m);
                }
            }
            let g = convex_hull(&mut a[..4 * h], b);
            let first = polygons.vertex_count() as u16;
            polygons.push(&b[..g]).map_err(GrowError::Capacity)?;
            // Same capacity as the polygons: cannot fail after their push succeeded.
            let _ = firsts.push(first);
            for i in 0..g {
                let (p, q) = (b[i], b[(i + 1) % g]);
                // Same capacity as the vertices: cannot fail after their push succeeded.
                let _ = inv_len.push(1.0 / math::hypot(q.x_m - p.x_m, q.y_m - p.y_m));
            }
            // Same capacity as the polygons: cannot fail after their push succeeded.
            let _ = boxes.push(BoxM::around(&b[..g]));
        }
        Ok(Self {
            polygons,
            inv_len,
            firsts,
            boxes,
            free: BoxM {
                x_min_m: radius_m,
                y_min_m: radius_m,
                x_max_m: width_m - radius_m,
                y_max_m: height_m - radius_m,
            },
            map: BoxM {
                x_min_m: 0.0,
                y_min_m: 0.0,
                x_max_m: width_m,
                y_max_m: height_m,
            },
        })
    }

    /// Number of grown polygons (one per `.da` polygon, same order).
    pub fn len(&self) -> usize {
        self.polygons.len()
    }

    /// `true` without polygons.
    pub fn is_empty(&self) -> bool {
        self.polygons.is_empty()
    }

    /// Grown polygon `i`: convex, counter-clockwise.
    pub fn polygon(&self, i: usize) -> Option<&[PointM]> {
        self.polygons.polygon(i)
    }

    /// All grown polygons.
    pub fn iter(&self) -> impl Iterator<Item = &[PointM]> + '_ {
        self.polygons.iter()
    }

    /// Bounding box of grown polygon `i`.
    pub fn bbox(&self, i: usize) -> Option<BoxM> {
        self.boxes.get(i).copied()
    }

    /// Where the robot's centre may be as far as the map border goes.
    pub fn free_box(&self) -> BoxM {
        self.free
    }

    /// Total vertices of the grown polygons.
    pub fn vertex_count(&self) -> usize {
        self.polygons.vertex_count()
    }

    /// Bytes these structures take for this world: 8 per vertex and 4 for its edge's inverse
    /// length, 2 per polygon end and 2 per polygon start, 16 per bounding box.
    pub fn memory_bytes(&self) -> usize {
        self.vertex_count() * (8 + 4) + self.len() * (2 + 2 + 16) + 2 * 16
    }

    /// Where `p` lies.
    pub fn place(&self, p: PointM) -> PointPlace {
        if !p.is_finite() || !self.map.contains(p) {
            return PointPlace::OutOfMap;
        }
        if self.free.is_empty() || !self.free.contains(p) {
            return PointPlace::NearBorder;
        }
        for (i, polygon) in self.polygons.iter().enumerate() {
            let inside_box = self.boxes.get(i).is_some_and(|b| b.contains(p));
            if inside_box && point_inside(p, polygon) {
                return PointPlace::InObstacle(i);
            }
        }
        PointPlace::Free
    }

    /// Whether `a` and `b` see each other: the segment enters no grown polygon. (Both ends are
    /// expected in the free box, which is convex, so the segment stays in it.)
    pub fn sees(&self, a: PointM, b: PointM) -> bool {
        let mut hint = 0;
        self.sees_from(a, b, &mut hint)
    }

    /// [`Grown::sees`], testing grown polygon `*hint` first and leaving in `*hint` the polygon
    /// that blocked the segment, if one did: segments from the same point are often blocked by
    /// the same polygon, so a search that keeps the hint between them rarely scans them all.
    pub fn sees_from(&self, a: PointM, b: PointM, hint: &mut usize) -> bool {
        if *hint < self.len() && self.blocks(*hint, a, b) {
            return false;
        }
        for i in 0..self.len() {
            if i != *hint && self.blocks(i, a, b) {
                *hint = i;
                return false;
            }
        }
        true
    }

    /// Whether grown polygon `i` blocks segment `a`–`b`.
    #[inline]
    fn blocks(&self, i: usize, a: PointM, b: PointM) -> bool {
        let (Some(polygon), Some(bx)) = (self.polygons.polygon(i), self.boxes.get(i)) else {
            return false;
        };
        if !bx.may_meet_segment(a, b) {
            return false;
        }
        let first = self.firsts.get(i).map_or(0, |&f| f as usize);
        let inv = self
            .inv_len
            .get(first..first + polygon.len())
            .unwrap_or(&[]);
        segment_enters_scaled(a, b, polygon, |e| {
            inv.get(e).map_or(f64::NAN, |&k| k as f64)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(x: f32, y: f32) -> PointM {
        PointM::new(x, y)
    }

    const SQUARE: [PointM; 4] = [
        PointM::new(0.0, 0.0),
        PointM::new(2.0, 0.0),
        PointM::new(2.0, 2.0),
        PointM::new(0.0, 2.0),
    ];

    #[test]
    fn segments_through_the_interior_enter_and_grazing_ones_do_not() {
        // Straight through.
        assert!(segment_enters(p(-1.0, 1.0), p(3.0, 1.0), &SQUARE));
        // Along the bottom edge, and beyond it on both sides (collinear overlap).
        assert!(!segment_enters(p(-1.0, 0.0), p(3.0, 0.0), &SQUARE));
        assert!(!segment_enters(p(0.5, 2.0), p(1.5, 2.0), &SQUARE));
        // Touching a vertex only (diagonal through the corner (2, 0) from outside).
        assert!(!segment_enters(p(1.0, -1.0), p(3.0, 1.0), &SQUARE));
        // From a vertex to the opposite vertex: the diagonal is interior.
        assert!(segment_enters(p(0.0, 0.0), p(2.0, 2.0), &SQUARE));
        // From a vertex to its neighbour: an edge, not interior.
        assert!(!segment_enters(p(2.0, 0.0), p(2.0, 2.0), &SQUARE));
        // From a vertex outwards.
        assert!(!segment_enters(p(2.0, 2.0), p(5.0, 4.0), &SQUARE));
        // Ending just inside (deeper than the tolerance) enters.
        assert!(segment_enters(p(-1.0, 1.0), p(0.01, 1.0), &SQUARE));
        // Far away.
        assert!(!segment_enters(p(5.0, 5.0), p(6.0, 9.0), &SQUARE));
        // Points.
        assert!(point_inside(p(1.0, 1.0), &SQUARE));
        assert!(!point_inside(p(2.0, 1.0), &SQUARE));
        assert!(!point_inside(p(2.0, 2.0), &SQUARE));
        // A degenerate polygon has no interior.
        assert!(!segment_enters(p(-1.0, 0.0), p(1.0, 0.0), &SQUARE[..2]));
    }

    #[test]
    fn the_hull_drops_collinear_and_repeated_points() {
        let mut pts = [
            p(0.0, 0.0),
            p(1.0, 0.0),
            p(2.0, 0.0),
            p(2.0, 2.0),
            p(1.0, 1.0),
            p(0.0, 2.0),
            p(2.0, 2.0),
        ];
        let mut out = [PointM::default(); 14];
        let h = convex_hull(&mut pts, &mut out);
        assert_eq!(h, 4);
        assert_eq!(
            &out[..4],
            &[p(0.0, 0.0), p(2.0, 0.0), p(2.0, 2.0), p(0.0, 2.0)]
        );
        let mut one = [p(1.0, 1.0), p(1.0, 1.0)];
        assert_eq!(convex_hull(&mut one, &mut out), 1);
        // Too short an output: nothing, no panic.
        assert_eq!(convex_hull(&mut pts, &mut out[..5]), 0);
    }

    #[test]
    fn growth_is_the_minkowski_sum_with_the_square() {
        let tri = [p(2.0, 2.0), p(4.0, 2.0), p(3.0, 4.0)];
        let mut scratch = [PointM::default(); 40];
        let g =
            Grown::<64, 4>::build([&tri[..]].into_iter(), 0.5, 10.0, 10.0, &mut scratch).unwrap();
        let poly = g.polygon(0).unwrap();
        // A triangle plus a square: each of the 3 vertices becomes 2 corners, but the bottom
        // corners of the horizontal base are collinear with it and merge.
        assert_eq!(poly.len(), 6, "{poly:?}");
        assert!(poly.contains(&p(1.5, 1.5)) && poly.contains(&p(4.5, 1.5)));
        assert!(poly.contains(&p(2.5, 4.5)) && poly.contains(&p(3.5, 4.5)));
        // Counter-clockwise.
        let area2: f64 = (0..poly.len())
            .map(|i| cross(p(0.0, 0.0), poly[i], poly[(i + 1) % poly.len()]))
            .sum();
        assert!(area2 > 0.0);
        assert_eq!(g.place(p(3.0, 1.6)), PointPlace::InObstacle(0));
        assert_eq!(g.place(p(3.0, 1.4)), PointPlace::Free);
        assert_eq!(g.place(p(0.3, 5.0)), PointPlace::NearBorder);
        assert_eq!(g.place(p(-0.3, 5.0)), PointPlace::OutOfMap);
        assert!(g.sees(p(1.0, 1.0), p(9.0, 1.0)));
        assert!(!g.sees(p(1.0, 3.0), p(9.0, 3.0)));
        // The hint: an out-of-range one is harmless, and it ends on the blocking polygon.
        let mut hint = 7;
        assert!(!g.sees_from(p(1.0, 3.0), p(9.0, 3.0), &mut hint));
        assert_eq!(hint, 0);
        assert!(g.sees_from(p(1.0, 1.0), p(9.0, 1.0), &mut hint));
        // Too little scratch is an error, not a panic.
        let mut small = [PointM::default(); 4];
        assert!(matches!(
            Grown::<64, 4>::build([&tri[..]].into_iter(), 0.5, 10.0, 10.0, &mut small),
            Err(GrowError::ScratchTooSmall { .. })
        ));
        assert!(matches!(
            Grown::<64, 4>::build([&tri[..]].into_iter(), f32::NAN, 10.0, 10.0, &mut scratch),
            Err(GrowError::NotFinite)
        ));
    }
}
