//! Clearance of a path: how far the robot's body stays from the obstacles.
//!
//! Measured on the `.da` polygons themselves (not on a grid), so that it is the same ruler for
//! every method: the smallest distance from any point of the path (the robot's centre) to any
//! polygon edge or to the map's border, less the robot radius. Positive: a gap between body and
//! obstacle; negative: the body overlaps one. A centre inside a polygon counts as the negative
//! of its distance to the nearest edge.

use twil_core::geom::PointM;
use twil_core::world::Obstacles;

/// Distance from point `p` to segment `a`–`b`, metres (f64 so that long maps keep precision).
pub fn point_segment_m(p: (f64, f64), a: (f64, f64), b: (f64, f64)) -> f64 {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p.0 - a.0) * dx + (p.1 - a.1) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (cx, cy) = (a.0 + t * dx, a.1 + t * dy);
    ((p.0 - cx).powi(2) + (p.1 - cy).powi(2)).sqrt()
}

/// Whether segments `a`–`b` and `c`–`d` cross or touch.
fn segments_intersect(a: (f64, f64), b: (f64, f64), c: (f64, f64), d: (f64, f64)) -> bool {
    let orient = |p: (f64, f64), q: (f64, f64), r: (f64, f64)| {
        (q.0 - p.0) * (r.1 - p.1) - (q.1 - p.1) * (r.0 - p.0)
    };
    let (d1, d2) = (orient(c, d, a), orient(c, d, b));
    let (d3, d4) = (orient(a, b, c), orient(a, b, d));
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
    {
        return true;
    }
    let on = |p: (f64, f64), q: (f64, f64), r: (f64, f64), o: f64| {
        o == 0.0
            && r.0 >= p.0.min(q.0)
            && r.0 <= p.0.max(q.0)
            && r.1 >= p.1.min(q.1)
            && r.1 <= p.1.max(q.1)
    };
    on(c, d, a, d1) || on(c, d, b, d2) || on(a, b, c, d3) || on(a, b, d, d4)
}

/// Distance between segments `a`–`b` and `c`–`d`, metres (0 when they cross).
pub fn segment_segment_m(a: (f64, f64), b: (f64, f64), c: (f64, f64), d: (f64, f64)) -> f64 {
    if segments_intersect(a, b, c, d) {
        return 0.0;
    }
    point_segment_m(a, c, d)
        .min(point_segment_m(b, c, d))
        .min(point_segment_m(c, a, b))
        .min(point_segment_m(d, a, b))
}

/// Whether `p` lies inside `polygon` (even-odd rule).
pub fn inside_polygon(p: (f64, f64), polygon: &[PointM]) -> bool {
    let mut inside = false;
    let n = polygon.len();
    for i in 0..n {
        let (a, b) = (polygon[i], polygon[(i + 1) % n]);
        let (ax, ay, bx, by) = (a.x_m as f64, a.y_m as f64, b.x_m as f64, b.y_m as f64);
        if (ay > p.1) != (by > p.1) && p.0 < ax + (p.1 - ay) * (bx - ax) / (by - ay) {
            inside = !inside;
        }
    }
    inside
}

/// Smallest clearance of `path` (the robot's centre) among `obstacles` inside a map of
/// `width_m` × `height_m` (origin at its lower-left corner), for a robot of `radius_m`:
/// distance to the nearest polygon edge or map border less the radius, metres. `None` for an
/// empty path.
pub fn min_clearance_m(
    path: &[PointM],
    obstacles: &Obstacles,
    width_m: f32,
    height_m: f32,
    radius_m: f32,
) -> Option<f32> {
    let pt = |p: PointM| (p.x_m as f64, p.y_m as f64);
    let segments: Vec<((f64, f64), (f64, f64))> = match path {
        [] => return None,
        [only] => vec![(pt(*only), pt(*only))],
        _ => path.windows(2).map(|w| (pt(w[0]), pt(w[1]))).collect(),
    };
    let (w, h) = (width_m as f64, height_m as f64);
    let border = [
        ((0.0, 0.0), (w, 0.0)),
        ((w, 0.0), (w, h)),
        ((w, h), (0.0, h)),
        ((0.0, h), (0.0, 0.0)),
    ];
    let mut best = f64::INFINITY;
    for &(a, b) in &segments {
        for &(c, d) in &border {
            best = best.min(segment_segment_m(a, b, c, d));
        }
        for polygon in obstacles.iter() {
            let n = polygon.len();
            for i in 0..n {
                let (c, d) = (pt(polygon[i]), pt(polygon[(i + 1) % n]));
                best = best.min(segment_segment_m(a, b, c, d));
            }
            // A segment wholly inside a polygon touches no edge: its distance is negative.
            if n >= 3 && inside_polygon(a, polygon) {
                let depth = (0..n)
                    .map(|i| point_segment_m(a, pt(polygon[i]), pt(polygon[(i + 1) % n])))
                    .fold(f64::INFINITY, f64::min);
                best = best.min(-depth);
            }
        }
    }
    Some((best - radius_m as f64) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use twil_core::world::parse_da;

    fn square() -> Obstacles {
        let mut o = Obstacles::new();
        parse_da("1\n4 4 4 6 4 6 6 4 6\n", &mut o).unwrap();
        o
    }

    #[test]
    fn clearance_is_the_gap_between_body_and_nearest_edge() {
        let o = square();
        let path = [PointM::new(1.0, 3.0), PointM::new(9.0, 3.0)];
        // The square's bottom edge is 1 m above the path; the border 3 m below.
        let c = min_clearance_m(&path, &o, 10.0, 10.0, 0.25).unwrap();
        assert!((c - 0.75).abs() < 1e-6, "{c}");
        // A path through the square: its centre line touches an edge, so the body overlaps
        // the square by at least its radius.
        let through = [PointM::new(1.0, 5.0), PointM::new(9.0, 5.0)];
        assert!(min_clearance_m(&through, &o, 10.0, 10.0, 0.25).unwrap() <= -0.25);
        // A point inside the square, 0.5 m from its nearest edge.
        let inside = [PointM::new(4.5, 5.0)];
        let c = min_clearance_m(&inside, &o, 10.0, 10.0, 0.0).unwrap();
        assert!((c + 0.5).abs() < 1e-6, "{c}");
        assert_eq!(min_clearance_m(&[], &o, 10.0, 10.0, 0.25), None);
    }
}
