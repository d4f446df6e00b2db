//! Planes heard from several viewpoints (Leonard & Durrant-Whyte 1991): a region of constant
//! depth whose both ends were left by the reflector is the foot of a plane, the plane the line
//! through its reflector square to its bearing. A smooth wall echoes at its foot, which moves
//! with the viewpoint, so two sweeps rarely place their reflectors on the same cell and the
//! old rule (two sweeps, one cell) left walls mostly tentative. When a later sweep's plane
//! lies on a line an earlier sweep heard from elsewhere (the same orientation, each foot on
//! the other's line), the later sweep's reflectors are confirmed: two viewpoints agree that a
//! wall passes there.
//!
//! Bounded: the last [`MAX_PLANES`] planes are kept (the oldest goes first).

use heapless::Deque;

use crate::geom::PointM;
use crate::math::{abs, cos, hypot, sin, wrap_angle_rad};

/// Planes kept per mission.
pub const MAX_PLANES: usize = 24;

/// One plane as a sweep heard it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct PlaneSeen {
    /// The reflector at the run's middle bearing, world metres.
    pub foot: PointM,
    /// The bearing from the sonar to the foot (the plane's normal, pointing away from the
    /// sonar), world radians.
    pub normal_rad: f32,
    /// Where the sonar stood, world metres.
    pub sonar: PointM,
}

/// How far two viewpoints, and two feet, must lie apart to count as two looks (metres), and
/// how far a foot may lie off the other plane's line (one cell, passed in).
pub(super) const MIN_VIEWPOINT_APART_M: f32 = 0.2;

impl PlaneSeen {
    /// Distance of `p` from this plane's line, metres.
    fn off_line_m(&self, p: PointM) -> f32 {
        abs((p.x_m - self.foot.x_m) * cos(self.normal_rad)
            + (p.y_m - self.foot.y_m) * sin(self.normal_rad))
    }

    /// Does `other`, heard from another viewpoint, lie on this plane: its normal within
    /// `angle_rad`, each foot within `cell_m` of the other's line, the feet and the sonars at
    /// least [`MIN_VIEWPOINT_APART_M`] apart (a second look from the same place repeats the
    /// first, ghosts included)?
    pub fn agrees_with(&self, other: &PlaneSeen, angle_rad: f32, cell_m: f32) -> bool {
        let apart = |a: PointM, b: PointM| hypot(a.x_m - b.x_m, a.y_m - b.y_m);
        abs(wrap_angle_rad(self.normal_rad - other.normal_rad)) <= angle_rad
            && self.off_line_m(other.foot) <= cell_m
            && other.off_line_m(self.foot) <= cell_m
            && apart(self.sonar, other.sonar) >= MIN_VIEWPOINT_APART_M
            && apart(self.foot, other.foot) >= MIN_VIEWPOINT_APART_M
    }
}

/// The planes of earlier sweeps.
pub(super) type Planes = Deque<PlaneSeen, MAX_PLANES>;

/// Keep `plane`, dropping the oldest when full.
pub(super) fn remember(planes: &mut Planes, plane: PlaneSeen) {
    if planes.is_full() {
        let _ = planes.pop_front();
    }
    let _ = planes.push_back(plane);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn wall_y2_seen_from(x_m: f32) -> PlaneSeen {
        // A wall along y = 2 m, the sonar at (x, 0.5): its foot straight ahead.
        PlaneSeen {
            foot: PointM::new(x_m, 2.0),
            normal_rad: core::f32::consts::FRAC_PI_2,
            sonar: PointM::new(x_m, 0.5),
        }
    }

    #[test]
    fn one_wall_from_two_places_agrees_a_second_look_from_the_same_place_does_not() {
        let (a, b) = (wall_y2_seen_from(1.0), wall_y2_seen_from(2.0));
        assert!(a.agrees_with(&b, 0.06, 0.05));
        assert!(!a.agrees_with(&wall_y2_seen_from(1.05), 0.06, 0.05));
    }

    #[test]
    fn a_parallel_wall_a_tilted_wall_and_a_corner_do_not_agree() {
        let a = wall_y2_seen_from(1.0);
        let parallel = PlaneSeen {
            foot: PointM::new(2.0, 2.1),
            ..wall_y2_seen_from(2.0)
        };
        assert!(!a.agrees_with(&parallel, 0.06, 0.05));
        let tilted = PlaneSeen {
            normal_rad: core::f32::consts::FRAC_PI_2 + 0.2,
            ..wall_y2_seen_from(2.0)
        };
        assert!(!a.agrees_with(&tilted, 0.06, 0.05));
        // A corner at (1, 2) seen from two places: two bearings through one point, no plane.
        let corner = PlaneSeen {
            foot: PointM::new(1.0, 2.0),
            normal_rad: 1.2,
            sonar: PointM::new(0.4, 0.7),
        };
        assert!(!a.agrees_with(&corner, 0.06, 0.05));
    }

    #[test]
    fn the_oldest_plane_goes_first() {
        let mut planes = Planes::new();
        for i in 0..MAX_PLANES + 3 {
            remember(&mut planes, wall_y2_seen_from(i as f32));
        }
        assert_eq!(planes.len(), MAX_PLANES);
        assert_eq!(planes.front().map(|p| p.foot.x_m), Some(3.0));
    }
}
