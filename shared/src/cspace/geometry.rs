//! Planar geometry of seed 000 §2.1 and §2.2: convex polygons, their collision test, and the
//! homogeneous transforms that place each arm.
//!
//! **Collision** (§2.1): two polygons collide when a vertex of one lies inside the other, or when
//! an edge of one crosses an edge of the other. The inside test is the thesis' vector method (the
//! point lies on the same side of every edge), so it needs convex polygons; a non-convex shape is
//! written as several convex ones. The edge test solves the two segments' parametric equations and
//! accepts `0 ≤ α, β ≤ 1`. Both tests include the boundary: touching counts as a collision, so the
//! map errs on the safe side. Polygons of two vertices are segments (walls), of one a point.
//!
//! **Kinematics** (§2.2, "altered" frames of figure 2.14): the frame of arm `i` sits at the far
//! end of the arm, so a point `p` written in arm `i`'s frame is, in arm `i - 1`'s frame,
//! `R(θᵢ) p + Lᵢ (cos θᵢ, sin θᵢ)`. A rotational joint varies `θᵢ` (degrees) with `Lᵢ` fixed, a
//! prismatic one varies `Lᵢ` with `θᵢ` fixed; the same matrix serves both.
//!
//! ```
//! use twil_core::cspace::geometry::{polygons_intersect, Frame, WorkPoint};
//! let square = [
//!     WorkPoint::new(0.0, 0.0),
//!     WorkPoint::new(2.0, 0.0),
//!     WorkPoint::new(2.0, 2.0),
//!     WorkPoint::new(0.0, 2.0),
//! ];
//! let wall = [WorkPoint::new(1.0, -1.0), WorkPoint::new(1.0, 3.0)];
//! assert!(polygons_intersect(&square, &wall));
//! // A prismatic joint at 90°: the frame moves 5 units up and turns a quarter.
//! let f = Frame::joint(90.0, 5.0);
//! assert_eq!(f.apply(WorkPoint::new(1.0, 0.0)), WorkPoint::new(0.0, 6.0));
//! ```

/// A point of the workspace plane, in the units of the `.ROB` file (the thesis used cm).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct WorkPoint {
    /// Abscissa, workspace units.
    pub x: f32,
    /// Ordinate, workspace units.
    pub y: f32,
}

impl WorkPoint {
    /// The point (`x`, `y`).
    pub const fn new(x: f32, y: f32) -> Self {
        Self { x, y }
    }
}

/// `(sin, cos)` of an angle in degrees, to about 1e-7: the angle is reduced to ±45° around a
/// multiple of 90° and fed to Taylor polynomials (only `+ - * /`, so host and MCU agree). Whole
/// multiples of 90° are exact, so axis-aligned joints (the navigation case) place polygons
/// exactly. Non-finite angles give `(0, 1)`.
pub fn sin_cos_deg(angle_deg: f32) -> (f32, f32) {
    if !angle_deg.is_finite() {
        return (0.0, 1.0);
    }
    let mut r = angle_deg % 360.0;
    if r < 0.0 {
        r += 360.0;
    }
    // r in [0, 360]: quadrant 0..=4 (4 is quadrant 0 again).
    let quadrant = ((r + 45.0) / 90.0) as i32;
    let x = (r - 90.0 * quadrant as f32) * (core::f32::consts::PI / 180.0);
    let x2 = x * x;
    let s = x * (1.0 - x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0)));
    let c = 1.0 - x2 / 2.0 * (1.0 - x2 / 12.0 * (1.0 - x2 / 30.0 * (1.0 - x2 / 56.0)));
    match quadrant % 4 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// A planar homogeneous transform `[[c, -s, tx], [s, c, ty], [0, 0, 1]]` (a rotation by the angle
/// whose cosine and sine are `c`, `s`, then a translation).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Frame {
    c: f32,
    s: f32,
    tx: f32,
    ty: f32,
}

impl Default for Frame {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Frame {
    /// The identity (the base frame).
    pub const IDENTITY: Frame = Frame {
        c: 1.0,
        s: 0.0,
        tx: 0.0,
        ty: 0.0,
    };

    /// The transform from an arm's frame to the previous one for joint angle `angle_deg` and arm
    /// length `length` (seed 000 §2.2): rotate by the angle, then move `length` along the turned
    /// x axis.
    pub fn joint(angle_deg: f32, length: f32) -> Frame {
        let (s, c) = sin_cos_deg(angle_deg);
        Frame {
            c,
            s,
            tx: length * c,
            ty: length * s,
        }
    }

    /// `self × inner`: first `inner`, then `self`.
    pub fn then_inner(&self, inner: &Frame) -> Frame {
        Frame {
            c: self.c * inner.c - self.s * inner.s,
            s: self.s * inner.c + self.c * inner.s,
            tx: self.c * inner.tx - self.s * inner.ty + self.tx,
            ty: self.s * inner.tx + self.c * inner.ty + self.ty,
        }
    }

    /// Transform a point.
    pub fn apply(&self, p: WorkPoint) -> WorkPoint {
        WorkPoint::new(
            self.c * p.x - self.s * p.y + self.tx,
            self.s * p.x + self.c * p.y + self.ty,
        )
    }

    /// The frame's origin in the outer frame (for a joint frame: the far end of the arm).
    pub fn origin(&self) -> WorkPoint {
        WorkPoint::new(self.tx, self.ty)
    }
}

/// `(b - a) × (c - a)`: positive when `c` lies to the left of the line `a → b`.
fn cross(a: WorkPoint, b: WorkPoint, c: WorkPoint) -> f32 {
    (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x)
}

/// `true` when the segments `a1 a2` and `b1 b2` share a point (thesis §2.1: `D ≠ 0` and both
/// parameters in `[0, 1]`). Parallel segments count as not crossing: other edges of the
/// polygons catch those contacts.
pub fn segments_intersect(a1: WorkPoint, a2: WorkPoint, b1: WorkPoint, b2: WorkPoint) -> bool {
    let (dxa, dya) = (a2.x - a1.x, a2.y - a1.y);
    let (dxb, dyb) = (b2.x - b1.x, b2.y - b1.y);
    let d = dxa * dyb - dxb * dya;
    if d == 0.0 || !d.is_finite() {
        return false;
    }
    let (dx31, dy31) = (b1.x - a1.x, b1.y - a1.y);
    // a1 + α·da = b1 + β·db  ⇒  α = (d31 × db) / d, β = (d31 × da) / d; compare without dividing.
    let alpha_n = dx31 * dyb - dy31 * dxb;
    let beta_n = dx31 * dya - dy31 * dxa;
    let within = |n: f32| {
        if d > 0.0 {
            n >= 0.0 && n <= d
        } else {
            n <= 0.0 && n >= d
        }
    };
    within(alpha_n) && within(beta_n)
}

/// `true` when `p` lies on the segment `a b` (end points included).
pub fn point_on_segment(p: WorkPoint, a: WorkPoint, b: WorkPoint) -> bool {
    cross(a, b, p) == 0.0
        && p.x >= a.x.min(b.x)
        && p.x <= a.x.max(b.x)
        && p.y >= a.y.min(b.y)
        && p.y <= a.y.max(b.y)
}

/// `true` when `p` lies inside or on the convex polygon `poly` (either orientation). Polygons of
/// fewer than three vertices contain nothing.
pub fn point_in_convex(p: WorkPoint, poly: &[WorkPoint]) -> bool {
    if poly.len() < 3 {
        return false;
    }
    let (mut pos, mut neg) = (false, false);
    let mut prev = poly[poly.len() - 1];
    for &v in poly {
        let c = cross(prev, v, p);
        if c > 0.0 {
            pos = true;
        } else if c < 0.0 {
            neg = true;
        }
        if pos && neg {
            return false;
        }
        prev = v;
    }
    true
}

/// `true` when `poly` (three or more vertices) turns the same way at every vertex; collinear
/// vertices are allowed. Fewer than three vertices are trivially convex.
pub fn is_convex(poly: &[WorkPoint]) -> bool {
    let n = poly.len();
    if n < 3 {
        return true;
    }
    let (mut pos, mut neg) = (false, false);
    for i in 0..n {
        let a = poly[i];
        let b = poly[(i + 1) % n];
        let c = poly[(i + 2) % n];
        let k = cross(a, b, c);
        if k > 0.0 {
            pos = true;
        } else if k < 0.0 {
            neg = true;
        }
    }
    !(pos && neg)
}

/// `true` when two convex polygons (or segments, or points) overlap or touch (thesis §3.2,
/// `INTERSEÇÃO`): a vertex of one inside the other, or two crossing edges.
pub fn polygons_intersect(a: &[WorkPoint], b: &[WorkPoint]) -> bool {
    // A point touches a segment or an outline when it lies on one of its edges.
    if a.len() == 1 || b.len() == 1 {
        let (point, other) = if a.len() == 1 { (a[0], b) } else { (b[0], a) };
        if other.len() == 1 {
            return other[0] == point;
        }
        let edges = if other.len() == 2 { 1 } else { other.len() };
        return point_in_convex(point, other)
            || (0..edges).any(|i| point_on_segment(point, other[i], other[(i + 1) % other.len()]));
    }
    if a.iter().any(|&p| point_in_convex(p, b)) || b.iter().any(|&p| point_in_convex(p, a)) {
        return true;
    }
    if a.len() < 2 || b.len() < 2 {
        return false;
    }
    // A two-vertex polygon has one edge, not the same edge twice.
    let edges_a = if a.len() == 2 { 1 } else { a.len() };
    let edges_b = if b.len() == 2 { 1 } else { b.len() };
    for i in 0..edges_a {
        let (a1, a2) = (a[i], a[(i + 1) % a.len()]);
        for j in 0..edges_b {
            if segments_intersect(a1, a2, b[j], b[(j + 1) % b.len()]) {
                return true;
            }
        }
    }
    false
}

/// Axis-aligned bounding box `(min, max)` of a non-empty point list (thesis §4.3.1).
pub fn bounding_box(points: &[WorkPoint]) -> Option<(WorkPoint, WorkPoint)> {
    let first = *points.first()?;
    let mut lo = first;
    let mut hi = first;
    for p in points {
        lo.x = lo.x.min(p.x);
        lo.y = lo.y.min(p.y);
        hi.x = hi.x.max(p.x);
        hi.y = hi.y.max(p.y);
    }
    Some((lo, hi))
}

/// `true` when two boxes from [`bounding_box`] overlap or touch.
pub fn boxes_overlap(a: (WorkPoint, WorkPoint), b: (WorkPoint, WorkPoint)) -> bool {
    a.0.x <= b.1.x && b.0.x <= a.1.x && a.0.y <= b.1.y && b.0.y <= a.1.y
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use proptest::prelude::*;

    fn p(x: f32, y: f32) -> WorkPoint {
        WorkPoint::new(x, y)
    }

    fn square(x: f32, y: f32, side: f32) -> [WorkPoint; 4] {
        [
            p(x, y),
            p(x + side, y),
            p(x + side, y + side),
            p(x, y + side),
        ]
    }

    #[test]
    fn crossing_touching_and_parallel_segments() {
        assert!(segments_intersect(
            p(0., 0.),
            p(2., 2.),
            p(0., 2.),
            p(2., 0.)
        ));
        // Touching at an end point counts.
        assert!(segments_intersect(
            p(0., 0.),
            p(1., 1.),
            p(1., 1.),
            p(2., 0.)
        ));
        // Apart.
        assert!(!segments_intersect(
            p(0., 0.),
            p(1., 0.),
            p(0., 1.),
            p(1., 2.)
        ));
        // The lines cross, the segments do not.
        assert!(!segments_intersect(
            p(0., 0.),
            p(1., 1.),
            p(3., 0.),
            p(2., 1.)
        ));
        // Parallel.
        assert!(!segments_intersect(
            p(0., 0.),
            p(1., 0.),
            p(0., 0.),
            p(2., 0.)
        ));
    }

    #[test]
    fn inside_outside_and_edge_of_a_convex_polygon_either_orientation() {
        let mut sq = square(0., 0., 2.);
        for _ in 0..2 {
            assert!(point_in_convex(p(1., 1.), &sq));
            assert!(point_in_convex(p(2., 1.), &sq));
            assert!(!point_in_convex(p(3., 1.), &sq));
            assert!(!point_in_convex(p(-0.1, 1.), &sq));
            sq.reverse();
        }
        assert!(!point_in_convex(p(0., 0.), &sq[..2]));
    }

    #[test]
    fn polygon_collision_cases_of_figure_2_2() {
        // Contained.
        assert!(polygons_intersect(
            &square(0., 0., 10.),
            &square(4., 4., 1.)
        ));
        assert!(polygons_intersect(
            &square(4., 4., 1.),
            &square(0., 0., 10.)
        ));
        // Crossing with no vertex inside the other: a cross made of two thin rectangles.
        let h = [p(-5., -1.), p(5., -1.), p(5., 1.), p(-5., 1.)];
        let v = [p(-1., -5.), p(1., -5.), p(1., 5.), p(-1., 5.)];
        assert!(polygons_intersect(&h, &v));
        // Apart.
        assert!(!polygons_intersect(
            &square(0., 0., 1.),
            &square(3., 0., 1.)
        ));
        // A wall (segment) through a polygon, and one beside it.
        assert!(polygons_intersect(
            &[p(-5., 0.5), p(5., 0.5)],
            &square(0., 0., 1.)
        ));
        assert!(!polygons_intersect(
            &[p(-5., 2.), p(5., 2.)],
            &square(0., 0., 1.)
        ));
        // A single point, also on a wall.
        assert!(polygons_intersect(&[p(5., 0.)], &[p(5., -1.), p(5., 1.)]));
        assert!(!polygons_intersect(&[p(5., 2.)], &[p(5., -1.), p(5., 1.)]));
        assert!(polygons_intersect(&[p(1., 0.5)], &square(0., 0., 1.)));
        assert!(polygons_intersect(&[p(0.5, 0.5)], &square(0., 0., 1.)));
        assert!(!polygons_intersect(&[p(1.5, 0.5)], &square(0., 0., 1.)));
        // Empty polygons collide with nothing.
        assert!(!polygons_intersect(&[], &square(0., 0., 1.)));
    }

    #[test]
    fn convexity() {
        assert!(is_convex(&square(0., 0., 1.)));
        assert!(!is_convex(&[
            p(0., 0.),
            p(2., 0.),
            p(1., 0.5),
            p(2., 2.),
            p(0., 2.)
        ]));
    }

    #[test]
    fn frames_compose_like_the_thesis_matrices() {
        // Two rotational arms of length 10 and 5 at 90° and -90°: the second frame ends at
        // (5, 10), pointing along +x.
        let f1 = Frame::joint(90.0, 10.0);
        let f2 = f1.then_inner(&Frame::joint(-90.0, 5.0));
        let o = f2.origin();
        assert!(
            (o.x - 5.0).abs() < 1e-5 && (o.y - 10.0).abs() < 1e-5,
            "{o:?}"
        );
        let q = f2.apply(p(1.0, 0.0));
        assert!(
            (q.x - 6.0).abs() < 1e-5 && (q.y - 10.0).abs() < 1e-5,
            "{q:?}"
        );
    }

    #[test]
    fn right_angles_are_exact() {
        assert_eq!(sin_cos_deg(90.0), (1.0, 0.0));
        assert_eq!(sin_cos_deg(-90.0), (-1.0, 0.0));
        assert_eq!(sin_cos_deg(540.0), (0.0, -1.0));
        for k in -720..=720 {
            let deg = k as f32 * 0.5;
            let (s, c) = sin_cos_deg(deg);
            let rad = (deg as f64).to_radians();
            assert!((s as f64 - rad.sin()).abs() < 5e-7, "sin {deg}");
            assert!(
                (c as f64 - rad.cos()).abs() < 5e-7,
                "cos {deg} {c} {}",
                rad.cos()
            );
        }
    }

    proptest! {
        #[test]
        fn collision_is_symmetric_and_boxes_are_necessary(
            ax in -20f32..20., ay in -20f32..20., sa in 0.5f32..10.,
            bx in -20f32..20., by in -20f32..20., sb in 0.5f32..10.,
        ) {
            let a = square(ax, ay, sa);
            let b = square(bx, by, sb);
            let hit = polygons_intersect(&a, &b);
            prop_assert_eq!(hit, polygons_intersect(&b, &a));
            // Axis-aligned squares overlap exactly when their boxes do.
            let boxes = boxes_overlap(bounding_box(&a).unwrap(), bounding_box(&b).unwrap());
            prop_assert_eq!(hit, boxes);
        }
    }
}
