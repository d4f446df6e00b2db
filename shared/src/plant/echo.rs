//! The simulated ultrasonic ranger's beam: what one ping of a real sonar (Polaroid-style
//! electrostatic transducer) returns, as opposed to one exact ray.
//!
//! - **Cone**: rays fan out over ±[`Beam::half_angle_rad`] around the axis, at most
//!   [`MAX_BEAM_RAYS`] of them (spaced [`BEAM_RAY_SPACING_DEG`] or wider), plus one ray aimed at
//!   each polygon vertex inside the cone (so a corner is never missed between two rays).
//! - **Specular reflection**: a ray stops at the first edge it meets. The edge sends an echo
//!   back only when the angle between the ray and the edge's normal is below
//!   [`Beam::incidence_limit_rad`]; otherwise the sound glances off and this ray returns nothing
//!   (the wall still hides what lies behind it; multiple-bounce echoes are not modelled).
//! - **Corners**: a hit within [`Beam::corner_radius_m`] of a polygon vertex echoes at any
//!   angle (a concave corner is a retro-reflector, a convex one diffracts).
//! - **First echo**: the reading is the nearest range among the rays that echo: the receiver
//!   stops its clock at the first echo strong enough, wherever in the cone it came from.
//!
//! Work per reading is bounded: `(MAX_BEAM_RAYS + vertices) × edges` segment tests.

use crate::geom::PointM;
use crate::math::{abs, atan2, cos, hypot, sin, sqrt, wrap_angle_rad};
use crate::world::PolygonSet;

use super::edges;

/// Most evenly spaced rays cast across the cone of one reading (vertex rays come on top).
pub const MAX_BEAM_RAYS: usize = 31;

/// Widest spacing wanted between neighbouring cone rays, degrees: at 1.5 m one degree is
/// 2.6 cm, finer than the seed's 2 cm grid cells are worth resolving.
pub const BEAM_RAY_SPACING_DEG: f32 = 1.0;

/// The beam's parameters, in radians and metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Beam {
    /// Half-angle of the cone (0: a single ray along the axis).
    pub half_angle_rad: f32,
    /// A smooth edge echoes only when the ray is within this angle of its normal.
    pub incidence_limit_rad: f32,
    /// A hit this close to a polygon vertex echoes at any incidence.
    pub corner_radius_m: f32,
}

impl Beam {
    /// From degrees and metres; non-finite or negative values become 0 (one ray, only
    /// face-on echoes, no corner allowance), angles are capped at 90°.
    pub fn from_deg(half_angle_deg: f32, incidence_limit_deg: f32, corner_radius_m: f32) -> Self {
        let rad = |deg: f32| {
            if deg.is_finite() && deg > 0.0 {
                deg.min(90.0) * core::f32::consts::PI / 180.0
            } else {
                0.0
            }
        };
        Self {
            half_angle_rad: rad(half_angle_deg),
            incidence_limit_rad: rad(incidence_limit_deg),
            corner_radius_m: if corner_radius_m.is_finite() && corner_radius_m > 0.0 {
                corner_radius_m
            } else {
                0.0
            },
        }
    }

    /// Range of the first echo from `origin` for a beam whose axis points at `axis_rad`
    /// (world frame), if one comes back from within `max_range_m`. `None` for non-finite
    /// inputs.
    pub fn first_echo_m<const V: usize, const P: usize>(
        &self,
        obstacles: &PolygonSet<V, P>,
        origin: PointM,
        axis_rad: f32,
        max_range_m: f32,
    ) -> Option<f32> {
        if !(origin.x_m.is_finite()
            && origin.y_m.is_finite()
            && axis_rad.is_finite()
            && max_range_m.is_finite()
            && max_range_m > 0.0)
        {
            return None;
        }
        let axis = wrap_angle_rad(axis_rad);
        let half = if self.half_angle_rad.is_finite() {
            self.half_angle_rad.clamp(0.0, core::f32::consts::FRAC_PI_2)
        } else {
            0.0
        };
        let cos_limit = if self.incidence_limit_rad.is_finite() {
            cos(self
                .incidence_limit_rad
                .clamp(0.0, core::f32::consts::FRAC_PI_2))
        } else {
            1.0
        };
        let corner_m = if self.corner_radius_m.is_finite() {
            self.corner_radius_m.max(0.0)
        } else {
            0.0
        };
        let rays = cone_rays(half);
        let mut best: Option<f32> = None;
        let mut keep = |d: Option<f32>| {
            if let Some(d) = d {
                if best.is_none_or(|b| d < b) {
                    best = Some(d);
                }
            }
        };
        for i in 0..rays {
            let offset = if rays == 1 {
                0.0
            } else {
                half * (2.0 * i as f32 / (rays - 1) as f32 - 1.0)
            };
            let angle = axis + offset;
            let hit = nearest_hit(
                obstacles,
                origin,
                cos(angle),
                sin(angle),
                max_range_m,
                cos_limit,
                corner_m,
            );
            // The first edge met echoes, or the ray returns nothing (it glanced off).
            keep(hit.and_then(|(t, echoes)| echoes.then_some(t)));
        }
        if half > 0.0 {
            // One ray at each vertex inside the cone and the range: corners echo even when
            // they fall between two cone rays.
            for poly in obstacles.iter() {
                if poly.len() < 2 {
                    continue; // a lone point is invisible to the sonar
                }
                for v in poly {
                    let vx = v.x_m - origin.x_m;
                    let vy = v.y_m - origin.y_m;
                    let dist = hypot(vx, vy);
                    if !(dist > 0.0 && dist <= max_range_m) {
                        continue;
                    }
                    if abs(wrap_angle_rad(atan2(vy, vx) - axis)) > half {
                        continue;
                    }
                    // The vertex itself echoes unless something nearer is met on the way. A
                    // ray aimed at a wall's free end, seen nearly along the wall, may pass it
                    // by a rounding error and glance off the wall's line beyond (a jamb
                    // vanished from some readings of a sweep and not others).
                    let hit = nearest_hit(
                        obstacles,
                        origin,
                        vx / dist,
                        vy / dist,
                        max_range_m,
                        cos_limit,
                        corner_m,
                    );
                    keep(match hit {
                        Some((t, echoes)) if t < dist - corner_m => echoes.then_some(t),
                        _ => Some(dist),
                    });
                }
            }
        }
        best
    }
}

/// Evenly spaced rays for a cone of half-angle `half_rad`: 1 for no cone, else an odd count
/// (one on the axis) spaced at most [`BEAM_RAY_SPACING_DEG`], capped at [`MAX_BEAM_RAYS`].
fn cone_rays(half_rad: f32) -> usize {
    if half_rad <= 0.0 {
        return 1;
    }
    let spacing_rad = BEAM_RAY_SPACING_DEG * core::f32::consts::PI / 180.0;
    let per_side = half_rad / spacing_rad;
    let per_side = if per_side.is_finite() && per_side < MAX_BEAM_RAYS as f32 {
        per_side as usize + 1
    } else {
        MAX_BEAM_RAYS
    };
    (2 * per_side + 1).min(MAX_BEAM_RAYS)
}

/// The first edge one ray (unit direction `(dx, dy)`) meets within `max_range_m`: its range
/// and whether it sends the sound back (incidence cosine at least `cos_limit`, or the hit
/// within `corner_m` of one of the edge's ends).
fn nearest_hit<const V: usize, const P: usize>(
    obstacles: &PolygonSet<V, P>,
    origin: PointM,
    dx: f32,
    dy: f32,
    max_range_m: f32,
    cos_limit: f32,
    corner_m: f32,
) -> Option<(f32, bool)> {
    // Nearest hit and whether it echoes; an echoing edge wins a tie (two edges meeting at a
    // vertex are hit at the same range).
    let mut nearest: Option<(f32, bool)> = None;
    for poly in obstacles.iter() {
        for (a, b) in edges(poly) {
            let ex = b.x_m - a.x_m;
            let ey = b.y_m - a.y_m;
            let denom = dx * ey - dy * ex;
            if abs(denom) < 1.0e-9 {
                continue; // parallel: a grazing ray meets the edge's ends through neighbours
            }
            let wx = a.x_m - origin.x_m;
            let wy = a.y_m - origin.y_m;
            let t = (wx * ey - wy * ex) / denom;
            let u = (wx * dy - wy * dx) / denom;
            let on_edge = (-1.0e-6..=1.0 + 1.0e-6).contains(&u);
            if !(t.is_finite() && t >= 0.0 && t <= max_range_m && on_edge) {
                continue;
            }
            let len = sqrt(ex * ex + ey * ey);
            // |d × e| / |e| = |cos| of the angle between the ray and the edge's normal.
            let face_on = len > 0.0 && abs(denom) / len >= cos_limit;
            let from_end_m = len * u.clamp(0.0, 1.0);
            let at_corner = from_end_m <= corner_m || len - from_end_m <= corner_m;
            let echoes = face_on || at_corner;
            nearest = match nearest {
                Some((n, e)) if n < t - 1.0e-5 || (abs(n - t) <= 1.0e-5 && e) => Some((n, e)),
                _ => Some((t, echoes)),
            };
        }
    }
    nearest
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::Obstacles;

    fn segment(a: (f32, f32), b: (f32, f32)) -> Obstacles {
        let mut o = Obstacles::new();
        o.push(&[PointM::new(a.0, a.1), PointM::new(b.0, b.1)])
            .unwrap();
        o
    }

    fn beam(half_deg: f32, limit_deg: f32) -> Beam {
        Beam::from_deg(half_deg, limit_deg, 0.05)
    }

    const ORIGIN: PointM = PointM::new(0.0, 0.0);

    #[test]
    fn a_walls_free_end_seen_nearly_along_the_wall_echoes_in_every_reading() {
        // A jamb of `twil sonar-grid` world 1: the wall's line passes 0.01 m from the sonar,
        // 0.52 m from the end. Before, the ray aimed at the end passed it by rounding for
        // some sonar positions a few micrometres apart, and the cone's rays glanced off.
        let wall = segment((11.871, 5.944), (3.754, 7.702));
        let b = beam(25.0, 25.0);
        let mut missed = 0;
        for i in 0..200 {
            let jitter_m = i as f32 * 1.0e-6;
            let origin = PointM::new(3.2437 + jitter_m, 7.8105 - jitter_m);
            let axis = (7.702f32 - origin.y_m).atan2(3.754 - origin.x_m);
            let expected = (3.754f32 - origin.x_m).hypot(7.702 - origin.y_m);
            match b.first_echo_m(&wall, origin, axis, 6.0) {
                Some(d) if (d - expected).abs() < 0.01 => {}
                _ => missed += 1,
            }
        }
        assert_eq!(missed, 0);
    }

    #[test]
    fn a_wall_face_on_echoes_at_its_perpendicular_distance() {
        let wall = segment((1.2, -5.0), (1.2, 5.0));
        // Axis straight at it, and axis 10° off (the normal still inside the 15° cone).
        for axis_deg in [0.0f32, 10.0, -10.0] {
            let d = beam(15.0, 15.0)
                .first_echo_m(&wall, ORIGIN, axis_deg.to_radians(), 6.0)
                .unwrap();
            assert!((d - 1.2).abs() < 1e-4, "axis {axis_deg}°: {d}");
        }
        // A single ray 10° off the normal sees the slant range.
        let d = beam(0.0, 15.0)
            .first_echo_m(&wall, ORIGIN, 10f32.to_radians(), 6.0)
            .unwrap();
        assert!((d - 1.2 / 10f32.to_radians().cos()).abs() < 1e-3, "{d}");
    }

    #[test]
    fn a_wall_beyond_the_incidence_limit_returns_nothing() {
        let wall = segment((1.2, -5.0), (1.2, 5.0));
        let ray = beam(0.0, 15.0);
        assert_eq!(
            ray.first_echo_m(&wall, ORIGIN, 30f32.to_radians(), 6.0),
            None
        );
        // The same ray with a wider limit echoes: the limit is what silences it.
        assert!(beam(0.0, 40.0)
            .first_echo_m(&wall, ORIGIN, 30f32.to_radians(), 6.0)
            .is_some());
        // The cone too, once the normal is outside it (axis 40°, half-angle 15°).
        assert_eq!(
            beam(15.0, 15.0).first_echo_m(&wall, ORIGIN, 40f32.to_radians(), 6.0),
            None
        );
        // And the silent wall still hides what is behind it.
        let mut o = segment((1.2, -5.0), (1.2, 5.0));
        o.push(&[PointM::new(3.0, 1.0), PointM::new(3.0, 3.0)])
            .unwrap();
        assert_eq!(ray.first_echo_m(&o, ORIGIN, 30f32.to_radians(), 6.0), None);
    }

    #[test]
    fn a_corner_echoes_at_any_angle() {
        // An L-shaped corner at (2, 1): seen obliquely along the diagonal from the origin.
        let mut o = segment((-1.0, 1.0), (2.0, 1.0));
        o.push(&[PointM::new(2.0, 1.0), PointM::new(2.0, -2.0)])
            .unwrap();
        let axis = 1f32.atan2(2.0);
        let expected = 5f32.sqrt();
        for b in [beam(0.0, 10.0), beam(15.0, 10.0)] {
            let d = b.first_echo_m(&o, ORIGIN, axis, 6.0).unwrap();
            assert!((d - expected).abs() < 0.05, "{b:?}: {d}");
        }
        // A wall's free end (convex edge) echoes too, seen almost along the wall.
        let wall = segment((1.0, 0.5), (5.0, 0.6));
        let axis = 0.5f32.atan2(1.0);
        // (A hair inside the end: a ray aimed exactly at it may pass by rounding.)
        let d = beam(0.0, 10.0)
            .first_echo_m(&wall, ORIGIN, axis - 0.002, 6.0)
            .unwrap();
        assert!((d - 1.25f32.sqrt()).abs() < 0.01, "{d}");
        // Further along the wall, the same ray glances off: nothing.
        assert_eq!(
            beam(0.0, 10.0).first_echo_m(&wall, ORIGIN, axis - 0.2, 6.0),
            None
        );
        // A cone whose rays all miss the vertex still finds it (vertex ray), but only inside
        // the cone.
        let d = beam(15.0, 10.0)
            .first_echo_m(&wall, ORIGIN, axis + 12f32.to_radians(), 6.0)
            .unwrap();
        assert!((d - 1.25f32.sqrt()).abs() < 1e-3, "{d}");
        assert_eq!(
            beam(15.0, 10.0).first_echo_m(&wall, ORIGIN, axis + 60f32.to_radians(), 6.0),
            None
        );
    }

    #[test]
    fn the_cone_returns_the_nearest_echo() {
        // A far wall ahead and a near post 10° to the left, inside the 15° cone.
        let mut o = segment((3.0, -5.0), (3.0, 5.0));
        let post = (
            1.5 * 10f32.to_radians().cos(),
            1.5 * 10f32.to_radians().sin(),
        );
        o.push(&[
            PointM::new(post.0, post.1 - 0.05),
            PointM::new(post.0, post.1 + 0.05),
        ])
        .unwrap();
        let d = beam(15.0, 15.0).first_echo_m(&o, ORIGIN, 0.0, 6.0).unwrap();
        assert!(d < 1.55 && d > 1.4, "{d}");
        // The single ray on the axis sees only the wall.
        let d = beam(0.0, 15.0).first_echo_m(&o, ORIGIN, 0.0, 6.0).unwrap();
        assert!((d - 3.0).abs() < 1e-4, "{d}");
        // Nothing within range: no echo.
        assert_eq!(beam(15.0, 15.0).first_echo_m(&o, ORIGIN, 0.0, 1.0), None);
    }

    #[test]
    fn the_ray_count_is_bounded() {
        assert_eq!(cone_rays(0.0), 1);
        assert_eq!(cone_rays(15f32.to_radians()), 31);
        assert!(cone_rays(5f32.to_radians()) <= 13);
        assert_eq!(cone_rays(core::f32::consts::FRAC_PI_2), MAX_BEAM_RAYS);
        assert_eq!(cone_rays(f32::INFINITY), MAX_BEAM_RAYS);
    }

    #[test]
    fn no_panic_and_no_echo_on_non_finite_inputs() {
        let wall = segment((1.2, -5.0), (1.2, 5.0));
        let good = beam(15.0, 15.0);
        for (origin, axis, range) in [
            (PointM::new(f32::NAN, 0.0), 0.0, 6.0),
            (ORIGIN, f32::NAN, 6.0),
            (ORIGIN, f32::INFINITY, 6.0),
            (ORIGIN, 0.0, f32::NAN),
            (ORIGIN, 0.0, f32::INFINITY),
            (ORIGIN, 0.0, -1.0),
        ] {
            assert_eq!(good.first_echo_m(&wall, origin, axis, range), None);
        }
        // Nonsense parameters fall back to one face-on ray.
        let odd = Beam::from_deg(f32::NAN, f32::INFINITY, f32::NEG_INFINITY);
        assert_eq!(odd.half_angle_rad, 0.0);
        let d = odd.first_echo_m(&wall, ORIGIN, 0.0, 6.0).unwrap();
        assert!((d - 1.2).abs() < 1e-4);
        let raw = Beam {
            half_angle_rad: f32::NAN,
            incidence_limit_rad: f32::NAN,
            corner_radius_m: f32::NAN,
        };
        assert!(raw.first_echo_m(&wall, ORIGIN, 0.0, 6.0).is_some());
    }
}
