//! The simulated robot ("plant"): motors, differential drive, encoders, a ray-cast sonar and
//! collision checks against the *real* world's polygons.
//!
//! It lives in the core so that the host simulator, the tests and a firmware build under QEMU
//! drive the very same model.
//!
//! - **Motors**: first order, `ω̇ = (K·V − ω)/T` per wheel (`K =`
//!   [`RobotConfig::motor_gain_rad_s_per_v`], `T =` [`RobotConfig::motor_time_constant_s`]),
//!   voltages clamped to ±[`RobotConfig::max_voltage_v`], integrated exactly over each substep.
//! - **Kinematics**: differential drive, `v = r(ω_r + ω_l)/2`, `ω = r(ω_r − ω_l)/2b`, integrated
//!   with the midpoint heading in substeps of [`RobotConfig::plant_substep_s`].
//! - **Encoders**: cumulative integer counts; the fraction of a count is carried over, so
//!   quantization never drifts. Counts wrap like a hardware counter: take deltas with
//!   `i32::wrapping_sub`.
//! - **Sonar**: the nearest crossing of a ray from the sonar (0.20 m ahead of the centre) with
//!   any polygon edge; optionally the minimum over a cone of rays, or
//!   ([`RobotConfig::sonar_beam`]) the ultrasonic beam of [`echo`] (first echo within a cone,
//!   incidence limit, corners); and seeded noise (SplitMix64 and a 4-uniform approximation of
//!   a Gaussian: no `rand`, same numbers everywhere); optionally the ranger's faults of
//!   [`faults`] (missed echoes, spurious short echoes), drawn from the same generator.
//! - **Collision**: the body is a disc of [`RobotConfig::physical_radius_m`] around the pose.
//!
//! Polygons are closed outlines (last vertex joins the first); two-vertex polygons are single
//! segments; one-vertex polygons are points (seen by clearance, invisible to the sonar).
//!
//! ```
//! use twil_core::control::Pose;
//! use twil_core::geom::PointM;
//! use twil_core::plant::Plant;
//! use twil_core::robot::RobotConfig;
//! use twil_core::world::Obstacles;
//!
//! let mut walls = Obstacles::new();
//! walls.push(&[PointM::new(3.0, -5.0), PointM::new(3.0, 5.0)]).unwrap();
//! let plant = Plant::new(&RobotConfig::default(), Pose::new(1.0, 0.0, 0.0));
//! // Sonar at x = 1.2, wall at x = 3.0.
//! let range = plant.ray_cast_m(&walls, 0.0, 6.0).unwrap();
//! assert!((range - 1.8).abs() < 1e-4);
//! assert!((plant.clearance_m(&walls) - (2.0 - 0.30)).abs() < 1e-4);
//! ```

use crate::geom::PointM;
use crate::geom::Pose;
use crate::math::{abs, cos, exp, floor, hypot, sin, wrap_angle_rad};
use crate::robot::{RobotConfig, MAX_CONE_RAYS};
use crate::sonar::{Reading, SweepBuffer, SweepPlan};
use crate::world::PolygonSet;

pub mod echo;
pub mod faults;

/// Most substeps one [`Plant::step`] call integrates; a longer `dt_s` uses longer substeps.
pub const MAX_SUBSTEPS_PER_STEP: u32 = 100_000;

/// A tiny deterministic generator (SplitMix64): the same seed gives the same sequence on every
/// machine.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SplitMix64 {
    state: u64,
}

impl SplitMix64 {
    /// A generator started from `seed`.
    pub const fn new(seed: u64) -> Self {
        Self { state: seed }
    }

    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)`.
    pub fn next_unit(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }

    /// Approximately normal with mean 0 and standard deviation 1 (sum of four uniforms,
    /// rescaled; bounded by ±3.46).
    pub fn next_gaussian(&mut self) -> f32 {
        let sum = self.next_unit() + self.next_unit() + self.next_unit() + self.next_unit();
        // Sum of 4 uniforms: mean 2, variance 4/12.
        (sum - 2.0) * 1.732_050_8
    }
}

/// The simulated robot. See the module docs for the model.
#[derive(Clone, Debug, PartialEq)]
pub struct Plant {
    config: RobotConfig,
    pose: Pose,
    left_speed_rad_s: f32,
    right_speed_rad_s: f32,
    left_counts: i32,
    right_counts: i32,
    left_fraction: f32,
    right_fraction: f32,
    time_s: f32,
    rng: SplitMix64,
}

impl Plant {
    /// A robot at rest at `true_pose` (a non-finite pose becomes the origin), encoders at 0,
    /// noise generator seeded with [`RobotConfig::noise_seed`].
    pub fn new(config: &RobotConfig, true_pose: Pose) -> Self {
        let pose = if true_pose.is_finite() {
            Pose::new(true_pose.x_m, true_pose.y_m, true_pose.heading_rad)
        } else {
            Pose::default()
        };
        Self {
            config: *config,
            pose,
            left_speed_rad_s: 0.0,
            right_speed_rad_s: 0.0,
            left_counts: 0,
            right_counts: 0,
            left_fraction: 0.0,
            right_fraction: 0.0,
            time_s: 0.0,
            rng: SplitMix64::new(config.noise_seed),
        }
    }

    /// The config in use.
    pub fn config(&self) -> &RobotConfig {
        &self.config
    }

    /// The true pose (axle midpoint, heading).
    pub fn pose(&self) -> Pose {
        self.pose
    }

    /// Cumulative encoder counts `(left, right)`, wrapping.
    pub fn encoder_counts(&self) -> (i32, i32) {
        (self.left_counts, self.right_counts)
    }

    /// Wheel speeds `(left, right)`, rad/s.
    pub fn wheel_speeds_rad_s(&self) -> (f32, f32) {
        (self.left_speed_rad_s, self.right_speed_rad_s)
    }

    /// Forward speed of the axle midpoint, m/s.
    pub fn speed_m_s(&self) -> f32 {
        0.5 * self.config.wheel_radius_m * (self.left_speed_rad_s + self.right_speed_rad_s)
    }

    /// Simulated time integrated so far, seconds.
    pub fn time_s(&self) -> f32 {
        self.time_s
    }

    /// Add simulated time without motion of the wheels' voltages being applied (e.g. a sonar
    /// sweep while stopped): equivalent to `step(dt_s, 0.0, 0.0)`.
    pub fn idle(&mut self, dt_s: f32) {
        self.step(dt_s, 0.0, 0.0);
    }

    /// Apply the two voltages for `dt_s` seconds. Voltages are clamped to ±max (infinities
    /// included); `NaN` counts as 0 V; a non-finite or non-positive `dt_s` does nothing.
    pub fn step(&mut self, dt_s: f32, left_voltage_v: f32, right_voltage_v: f32) {
        if !(dt_s.is_finite() && dt_s > 0.0) {
            return;
        }
        let c = self.config;
        let limit = c.max_voltage_v;
        let clamp = |v: f32| {
            if v.is_nan() {
                0.0
            } else if v > limit {
                limit
            } else if v < -limit {
                -limit
            } else {
                v
            }
        };
        let left_target = c.motor_gain_rad_s_per_v * clamp(left_voltage_v);
        let right_target = c.motor_gain_rad_s_per_v * clamp(right_voltage_v);

        let wanted = if c.plant_substep_s > 0.0 {
            dt_s / c.plant_substep_s
        } else {
            1.0
        };
        let substeps = if !wanted.is_finite() || wanted >= MAX_SUBSTEPS_PER_STEP as f32 {
            MAX_SUBSTEPS_PER_STEP
        } else if wanted < 1.0 {
            1
        } else {
            let w = floor(wanted);
            // Round up when the division leaves a noticeable remainder.
            (if wanted - w > 1.0e-3 { w + 1.0 } else { w }) as u32
        };
        let h = dt_s / substeps as f32;
        let blend = 1.0 - exp(-h / c.motor_time_constant_s);
        let blend = if blend.is_finite() { blend } else { 1.0 };
        let r = c.wheel_radius_m;
        let b = c.half_axle_m;
        let counts_per_rad = 1.0 / c.rad_per_count();

        for _ in 0..substeps {
            let left_old = self.left_speed_rad_s;
            let right_old = self.right_speed_rad_s;
            self.left_speed_rad_s += (left_target - left_old) * blend;
            self.right_speed_rad_s += (right_target - right_old) * blend;
            let left_rad = 0.5 * (left_old + self.left_speed_rad_s) * h;
            let right_rad = 0.5 * (right_old + self.right_speed_rad_s) * h;

            let travel_m = 0.5 * r * (left_rad + right_rad);
            let turn_rad = r * (right_rad - left_rad) / (2.0 * b);
            let mid = self.pose.heading_rad + 0.5 * turn_rad;
            let next = Pose::new(
                self.pose.x_m + travel_m * cos(mid),
                self.pose.y_m + travel_m * sin(mid),
                self.pose.heading_rad + turn_rad,
            );
            if next.is_finite() {
                self.pose = next;
            }

            self.left_fraction += left_rad * counts_per_rad;
            self.right_fraction += right_rad * counts_per_rad;
            let lw = floor(self.left_fraction);
            let rw = floor(self.right_fraction);
            if lw.is_finite() && rw.is_finite() {
                self.left_counts = self.left_counts.wrapping_add(lw as i32);
                self.right_counts = self.right_counts.wrapping_add(rw as i32);
                self.left_fraction -= lw;
                self.right_fraction -= rw;
            } else {
                self.left_fraction = 0.0;
                self.right_fraction = 0.0;
            }
        }
        self.time_s += dt_s;
    }

    /// Put the robot somewhere else, at rest (test setup, scenario start).
    pub fn set_pose(&mut self, pose: Pose) {
        if pose.is_finite() {
            self.pose = Pose::new(pose.x_m, pose.y_m, pose.heading_rad);
            self.left_speed_rad_s = 0.0;
            self.right_speed_rad_s = 0.0;
        }
    }

    /// Where the sonar is: [`RobotConfig::sonar_offset_m`] ahead of the centre.
    pub fn sonar_position(&self) -> PointM {
        self.pose.point_ahead(self.config.sonar_offset_m)
    }

    /// Distance from the sonar to the nearest polygon edge along the direction
    /// `heading + neck_angle_rad`, if one is within `max_range_m` (one exact ray, no noise, no
    /// minimum range). `None` for non-finite inputs.
    pub fn ray_cast_m<const V: usize, const P: usize>(
        &self,
        obstacles: &PolygonSet<V, P>,
        neck_angle_rad: f32,
        max_range_m: f32,
    ) -> Option<f32> {
        if !(neck_angle_rad.is_finite() && max_range_m.is_finite() && max_range_m > 0.0) {
            return None;
        }
        let origin = self.sonar_position();
        let angle = wrap_angle_rad(self.pose.heading_rad + neck_angle_rad);
        ray_cast(obstacles, origin, cos(angle), sin(angle), max_range_m)
    }

    /// One simulated sonar reading, as the hardware would give it: with
    /// [`RobotConfig::sonar_beam`] the first echo of the beam ([`echo::Beam`]), otherwise the
    /// minimum over the legacy cone ([`RobotConfig::sonar_cone_deg`],
    /// [`RobotConfig::sonar_cone_rays`] rays, by default one exact ray); plus
    /// the ranger's faults ([`faults::RangerFaults`]: missed and spurious short echoes, off by
    /// default) and noise of [`RobotConfig::sonar_noise_std_m`]; `None` ("no echo") when nothing lies
    /// within `max_range_m` or the echo is nearer than [`RobotConfig::sonar_min_range_m`] (the
    /// receiver is still blanked). Draws from the noise generator only when noise is on, so a
    /// noiseless plant is a pure function of the pose.
    pub fn sonar_range_m<const V: usize, const P: usize>(
        &mut self,
        obstacles: &PolygonSet<V, P>,
        neck_angle_rad: f32,
        max_range_m: f32,
    ) -> Option<f32> {
        let c = self.config;
        let rays = c.sonar_cone_rays.clamp(1, MAX_CONE_RAYS);
        let cone_rad = if c.sonar_cone_deg.is_finite() && c.sonar_cone_deg > 0.0 {
            c.sonar_cone_deg * core::f32::consts::PI / 180.0
        } else {
            0.0
        };
        let mut best: Option<f32> = None;
        if c.sonar_beam {
            let beam = echo::Beam::from_deg(
                c.sonar_beam_half_angle_deg,
                c.sonar_incidence_limit_deg,
                c.sonar_corner_radius_m,
            );
            best = beam.first_echo_m(
                obstacles,
                self.sonar_position(),
                self.pose.heading_rad + neck_angle_rad,
                max_range_m,
            );
        } else if rays == 1 || cone_rad == 0.0 {
            best = self.ray_cast_m(obstacles, neck_angle_rad, max_range_m);
        } else {
            for i in 0..rays {
                let offset = cone_rad * (i as f32 / (rays - 1) as f32 - 0.5);
                if let Some(d) = self.ray_cast_m(obstacles, neck_angle_rad + offset, max_range_m) {
                    best = Some(match best {
                        Some(b) if b <= d => b,
                        _ => d,
                    });
                }
            }
        }
        let faults = faults::RangerFaults {
            dropout_probability: c.sonar_dropout_probability,
            spurious_probability: c.sonar_spurious_probability,
        };
        let best = faults.apply(&mut self.rng, best, c.sonar_min_range_m, max_range_m);
        let mut range = best?;
        if c.sonar_noise_std_m > 0.0 && c.sonar_noise_std_m.is_finite() {
            range += c.sonar_noise_std_m * self.rng.next_gaussian();
        }
        if range.is_finite() && range >= c.sonar_min_range_m && range <= max_range_m {
            Some(range)
        } else {
            None
        }
    }

    /// A whole sweep standing still (the seed's stop-and-sweep): `out` is cleared and gets one
    /// [`Reading`] per neck angle of `plan`, read with [`sonar_range_m`](Self::sonar_range_m)
    /// up to [`RobotConfig::sonar_range_m`] from the current pose; then the plant idles (0 V)
    /// for the sweep's duration ([`SweepPlan::timing`]). Returns that duration, seconds.
    pub fn sweep_in_place<const V: usize, const P: usize>(
        &mut self,
        obstacles: &PolygonSet<V, P>,
        plan: &SweepPlan,
        out: &mut SweepBuffer,
    ) -> f32 {
        out.clear();
        let range = self.config.sonar_range_m;
        let pose = self.pose;
        for angle in plan.angles_rad() {
            let range_m = self.sonar_range_m(obstacles, angle, range);
            // A plan never has more readings than a buffer holds.
            let _ = out.push(Reading {
                neck_angle_rad: angle,
                range_m,
                pose,
            });
        }
        let duration_s = plan.timing(&self.config).total_s();
        self.idle(duration_s);
        duration_s
    }

    /// Distance from the centre to the nearest polygon edge (or lone vertex) minus the
    /// physical radius, metres: negative means the body overlaps an obstacle. With no
    /// obstacle, `f32::INFINITY`. A centre inside a closed polygon also means collision: see
    /// [`centre_inside`](Self::centre_inside).
    pub fn clearance_m<const V: usize, const P: usize>(&self, obstacles: &PolygonSet<V, P>) -> f32 {
        let p = self.pose.position();
        let mut nearest = f32::INFINITY;
        for poly in obstacles.iter() {
            let d = polygon_distance_m(poly, p);
            if d < nearest {
                nearest = d;
            }
        }
        nearest - self.config.physical_radius_m()
    }

    /// `true` when the centre lies strictly inside a closed polygon (three or more vertices),
    /// by the even-odd rule.
    pub fn centre_inside<const V: usize, const P: usize>(
        &self,
        obstacles: &PolygonSet<V, P>,
    ) -> bool {
        let p = self.pose.position();
        obstacles
            .iter()
            .any(|poly| poly.len() >= 3 && point_in_polygon(poly, p))
    }

    /// `true` when the body touches or overlaps an obstacle: negative clearance or centre
    /// inside a polygon.
    pub fn collides<const V: usize, const P: usize>(&self, obstacles: &PolygonSet<V, P>) -> bool {
        self.clearance_m(obstacles) < 0.0 || self.centre_inside(obstacles)
    }
}

/// The edges of a polygon: consecutive pairs plus the closing edge (none extra for a segment).
fn edges(poly: &[PointM]) -> impl Iterator<Item = (PointM, PointM)> + '_ {
    let n = poly.len();
    let closing = if n >= 3 { n } else { n.saturating_sub(1) };
    (0..closing).filter_map(move |i| {
        let a = *poly.get(i)?;
        let b = *poly.get((i + 1) % n)?;
        Some((a, b))
    })
}

/// Nearest `t` in `[0, max]` at which `origin + t·(dx, dy)` (unit direction) crosses an edge.
fn ray_cast<const V: usize, const P: usize>(
    obstacles: &PolygonSet<V, P>,
    origin: PointM,
    dx: f32,
    dy: f32,
    max_range_m: f32,
) -> Option<f32> {
    let mut best: Option<f32> = None;
    for poly in obstacles.iter() {
        for (a, b) in edges(poly) {
            let ex = b.x_m - a.x_m;
            let ey = b.y_m - a.y_m;
            let denom = dx * ey - dy * ex;
            let wx = a.x_m - origin.x_m;
            let wy = a.y_m - origin.y_m;
            if abs(denom) < 1.0e-9 {
                continue; // parallel: a grazing ray sees the edge's ends through the neighbours
            }
            let t = (wx * ey - wy * ex) / denom;
            let u = (wx * dy - wy * dx) / denom;
            if t.is_finite()
                && t >= 0.0
                && t <= max_range_m
                && (-1.0e-6..=1.0 + 1.0e-6).contains(&u)
            {
                best = Some(match best {
                    Some(b) if b <= t => b,
                    _ => t,
                });
            }
        }
    }
    best
}

/// Distance from `p` to segment `a`–`b`.
fn segment_distance_m(a: PointM, b: PointM, p: PointM) -> f32 {
    let ex = b.x_m - a.x_m;
    let ey = b.y_m - a.y_m;
    let len2 = ex * ex + ey * ey;
    let t = if len2 > 0.0 {
        (((p.x_m - a.x_m) * ex + (p.y_m - a.y_m) * ey) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    hypot(a.x_m + t * ex - p.x_m, a.y_m + t * ey - p.y_m)
}

/// Distance from `p` to the outline of a polygon (a lone vertex counts as a point).
fn polygon_distance_m(poly: &[PointM], p: PointM) -> f32 {
    if poly.len() == 1 {
        return poly
            .first()
            .map_or(f32::INFINITY, |v| hypot(v.x_m - p.x_m, v.y_m - p.y_m));
    }
    let mut nearest = f32::INFINITY;
    for (a, b) in edges(poly) {
        let d = segment_distance_m(a, b, p);
        if d < nearest {
            nearest = d;
        }
    }
    nearest
}

/// Even-odd point in polygon.
fn point_in_polygon(poly: &[PointM], p: PointM) -> bool {
    let mut inside = false;
    for (a, b) in edges(poly) {
        if (a.y_m > p.y_m) != (b.y_m > p.y_m) {
            let x = a.x_m + (p.y_m - a.y_m) * (b.x_m - a.x_m) / (b.y_m - a.y_m);
            if p.x_m < x {
                inside = !inside;
            }
        }
    }
    inside
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::Obstacles;

    fn wall_at_x(x: f32) -> Obstacles {
        let mut o = Obstacles::new();
        o.push(&[PointM::new(x, -10.0), PointM::new(x, 10.0)])
            .unwrap();
        o
    }

    fn square(cx: f32, cy: f32, half: f32) -> Obstacles {
        let mut o = Obstacles::new();
        o.push(&[
            PointM::new(cx - half, cy - half),
            PointM::new(cx + half, cy - half),
            PointM::new(cx + half, cy + half),
            PointM::new(cx - half, cy + half),
        ])
        .unwrap();
        o
    }

    #[test]
    fn constant_voltage_reaches_the_motor_speed() {
        let c = RobotConfig::default();
        let mut plant = Plant::new(&c, Pose::new(0.0, 0.0, 0.0));
        for _ in 0..40 {
            plant.step(0.05, 5.0, 5.0);
        }
        let (l, r) = plant.wheel_speeds_rad_s();
        // 2 s = 20 time constants: at steady state K·V.
        assert!((l - 4.0).abs() < 1e-3 && (r - 4.0).abs() < 1e-3, "{l} {r}");
        let p = plant.pose();
        // Distance = K V r (t − T(1 − e^{−t/T})).
        let expected = 4.0 * c.wheel_radius_m * (2.0 - 0.1);
        assert!((p.x_m - expected).abs() < 1e-3, "{p:?} vs {expected}");
        assert!(p.y_m.abs() < 1e-5 && p.heading_rad.abs() < 1e-6);
        let (cl, cr) = plant.encoder_counts();
        let expected_counts = expected / c.wheel_radius_m / c.rad_per_count();
        assert!(
            (cl as f32 - expected_counts).abs() <= 1.5,
            "{cl} vs {expected_counts}"
        );
        assert_eq!(cl, cr);
        assert!((plant.time_s() - 2.0).abs() < 1e-4);
    }

    #[test]
    fn opposite_voltages_turn_in_place() {
        let c = RobotConfig::default();
        let mut plant = Plant::new(&c, Pose::new(1.0, 1.0, 0.0));
        for _ in 0..20 {
            plant.step(0.05, -3.0, 3.0);
        }
        let p = plant.pose();
        assert!(
            (p.x_m - 1.0).abs() < 1e-4 && (p.y_m - 1.0).abs() < 1e-4,
            "{p:?}"
        );
        assert!(p.heading_rad > 0.5, "{p:?}");
        let (l, r) = plant.encoder_counts();
        assert!(l < 0 && r > 0 && (l + r).abs() <= 1);
    }

    #[test]
    fn voltages_are_clamped_and_nan_ignored() {
        let c = RobotConfig::default();
        let mut a = Plant::new(&c, Pose::default());
        let mut b = Plant::new(&c, Pose::default());
        a.step(1.0, 1000.0, f32::INFINITY);
        b.step(1.0, 11.7, 11.7);
        assert_eq!(a.pose(), b.pose());
        let before = a.clone();
        a.step(f32::NAN, 1.0, 1.0);
        a.step(-1.0, 1.0, 1.0);
        a.step(0.0, 1.0, 1.0);
        assert_eq!(a, before);
        a.step(0.05, f32::NAN, f32::NAN);
        assert!(a.pose().is_finite());
        // An absurd dt is integrated in at most MAX_SUBSTEPS_PER_STEP substeps.
        a.step(1.0e30, 1.0, 1.0);
        assert!(a.pose().is_finite());
    }

    #[test]
    fn sonar_sees_a_wall_at_its_distance() {
        let c = RobotConfig::default();
        let walls = wall_at_x(2.5);
        let mut plant = Plant::new(&c, Pose::new(1.0, 0.0, 0.0));
        // Sonar at x = 1.2: wall 1.3 m ahead.
        let d = plant.sonar_range_m(&walls, 0.0, c.sonar_range_m).unwrap();
        assert!((d - 1.3).abs() < 0.01, "{d}");
        // At 60° off axis the slant range is 1.3 / cos 60° = 2.6 m: beyond 1.5 m, no echo.
        assert_eq!(
            plant.sonar_range_m(&walls, 60f32.to_radians(), c.sonar_range_m),
            None
        );
        let d = plant
            .sonar_range_m(&walls, 60f32.to_radians(), 6.0)
            .unwrap();
        assert!((d - 2.6).abs() < 0.01, "{d}");
        // Looking away: nothing.
        assert_eq!(
            plant.sonar_range_m(&walls, core::f32::consts::PI, 6.0),
            None
        );
        // Turned towards +y, a neck angle of −90° looks at the wall.
        plant.set_pose(Pose::new(1.0, 0.0, core::f32::consts::FRAC_PI_2));
        let d = plant
            .sonar_range_m(&walls, -core::f32::consts::FRAC_PI_2, 6.0)
            .unwrap();
        assert!((d - 1.5).abs() < 0.01, "{d}");
    }

    #[test]
    fn no_echo_below_the_minimum_range() {
        let c = RobotConfig::default();
        let walls = wall_at_x(1.4);
        let mut plant = Plant::new(&c, Pose::new(1.0, 0.0, 0.0));
        // Wall 0.2 m from the sonar: blanked.
        assert_eq!(plant.sonar_range_m(&walls, 0.0, 1.5), None);
        // The exact ray still sees it.
        let d = plant.ray_cast_m(&walls, 0.0, 1.5).unwrap();
        assert!((d - 0.2).abs() < 1e-4);
    }

    #[test]
    fn closed_polygons_are_hit_on_their_near_side() {
        let c = RobotConfig::default();
        let obstacles = square(3.0, 0.0, 0.5);
        let mut plant = Plant::new(&c, Pose::new(1.0, 0.0, 0.0));
        let d = plant.sonar_range_m(&obstacles, 0.0, 6.0).unwrap();
        assert!((d - 1.3).abs() < 1e-4, "{d}");
        // Just past the corner: miss.
        assert_eq!(plant.ray_cast_m(&obstacles, 0.45, 6.0), None);
    }

    #[test]
    fn cone_sees_off_axis_obstacles() {
        let c = RobotConfig {
            sonar_cone_deg: 20.0,
            sonar_cone_rays: 9,
            ..RobotConfig::default()
        };
        // A post 1 m ahead of the sonar, 0.12 m to the side: about 6.8° off axis.
        let mut post = Obstacles::new();
        post.push(&[PointM::new(2.2, 0.10), PointM::new(2.2, 0.14)])
            .unwrap();
        let mut plant = Plant::new(&c, Pose::new(1.0, 0.0, 0.0));
        let d = plant.sonar_range_m(&post, 0.0, 6.0).unwrap();
        assert!((d - 1.005).abs() < 0.01, "{d}");
        let narrow = RobotConfig::default();
        let mut plant = Plant::new(&narrow, Pose::new(1.0, 0.0, 0.0));
        assert_eq!(plant.sonar_range_m(&post, 0.0, 6.0), None);
    }

    #[test]
    fn the_plants_readings_carry_the_ranger_faults() {
        // A wall at 1.2 m from the sonar, read 2 000 times with 10 % dropouts and 10 %
        // spurious echoes: both show, within binomial bounds, and a spurious echo is shorter.
        let c = RobotConfig {
            sonar_dropout_probability: 0.1,
            sonar_spurious_probability: 0.1,
            ..RobotConfig::default()
        };
        let walls = wall_at_x(2.2);
        let mut plant = Plant::new(&c, Pose::new(0.8, 0.0, 0.0));
        let (mut missed, mut short) = (0, 0);
        for _ in 0..2000 {
            match plant.sonar_range_m(&walls, 0.0, 1.5) {
                None => missed += 1,
                Some(r) if r < 1.2 - 1e-4 => {
                    assert!(r >= c.sonar_min_range_m, "{r}");
                    short += 1;
                }
                Some(r) => assert!((r - 1.2).abs() < 1e-4, "{r}"),
            }
        }
        // Expected 2000 × 0.1 × 0.9 = 180 missed, 200 short; sd ≈ 13.4.
        assert!((120..=240).contains(&missed), "{missed}");
        assert!((140..=260).contains(&short), "{short}");
        // Without faults the same plant reads the wall every time.
        let mut exact = Plant::new(&RobotConfig::default(), Pose::new(0.8, 0.0, 0.0));
        assert!((0..100).all(|_| exact.sonar_range_m(&walls, 0.0, 1.5).is_some()));
    }

    #[test]
    fn noise_is_deterministic_per_seed() {
        let c = RobotConfig {
            sonar_noise_std_m: 0.02,
            noise_seed: 7,
            ..RobotConfig::default()
        };
        let walls = wall_at_x(2.2);
        let read = |config: &RobotConfig| {
            let mut plant = Plant::new(config, Pose::new(1.0, 0.0, 0.0));
            let mut out = [0.0f32; 50];
            for (i, o) in out.iter_mut().enumerate() {
                *o = plant
                    .sonar_range_m(&walls, (i as f32 - 25.0) * 0.01, 1.5)
                    .unwrap_or(-1.0);
            }
            out
        };
        let a = read(&c);
        assert_eq!(a, read(&c));
        let other = read(&RobotConfig { noise_seed: 8, ..c });
        assert_ne!(a, other);
        // Noise has about the asked spread around the true ranges.
        let plant = Plant::new(&c, Pose::new(1.0, 0.0, 0.0));
        let mut sum2 = 0.0;
        for (i, v) in a.iter().enumerate() {
            let truth = plant
                .ray_cast_m(&walls, (i as f32 - 25.0) * 0.01, 6.0)
                .unwrap();
            sum2 += (v - truth) * (v - truth);
        }
        let std = crate::math::sqrt(sum2 / 50.0);
        assert!(std > 0.01 && std < 0.03, "{std}");
    }

    #[test]
    fn beam_readings_and_their_noise_are_reproducible_per_seed() {
        let c = RobotConfig {
            sonar_beam: true,
            sonar_noise_std_m: 0.02,
            noise_seed: 7,
            ..RobotConfig::default()
        };
        let walls = square(3.0, 0.0, 0.5);
        let read = |config: &RobotConfig| {
            let mut plant = Plant::new(config, Pose::new(1.0, 0.3, 0.0));
            let mut out = [0.0f32; 40];
            for (i, o) in out.iter_mut().enumerate() {
                *o = plant
                    .sonar_range_m(&walls, (i as f32 - 20.0) * 0.05, 6.0)
                    .unwrap_or(-1.0);
            }
            out
        };
        let a = read(&c);
        assert_eq!(a, read(&c));
        assert_ne!(a, read(&RobotConfig { noise_seed: 8, ..c }));
        // Without noise the beam looking straight at the square's face reads its distance
        // (face at x = 2.5, sonar at x = 1.2), and differs from the single ray off-axis where
        // the ray glances off the face but the beam still holds the face's normal.
        let exact = RobotConfig {
            sonar_noise_std_m: 0.0,
            ..c
        };
        let mut plant = Plant::new(&exact, Pose::new(1.0, 0.3, 0.0));
        let d = plant.sonar_range_m(&walls, 0.0, 6.0).unwrap();
        assert!((d - 1.3).abs() < 1e-3, "{d}");
        let d = plant.sonar_range_m(&walls, 0.2, 6.0).unwrap();
        assert!((d - 1.3).abs() < 1e-3, "{d}");
    }

    #[test]
    fn clearance_and_inside() {
        let c = RobotConfig::default();
        let obstacles = square(3.0, 0.0, 0.5);
        let plant = Plant::new(&c, Pose::new(1.0, 0.0, 0.0));
        assert!((plant.clearance_m(&obstacles) - (1.5 - 0.3)).abs() < 1e-5);
        assert!(!plant.centre_inside(&obstacles));
        assert!(!plant.collides(&obstacles));
        let touching = Plant::new(&c, Pose::new(2.3, 0.0, 0.0));
        assert!(touching.clearance_m(&obstacles) < 0.0);
        assert!(touching.collides(&obstacles));
        // Deep inside: the outline is 0.5 m away (clearance positive!) but the centre is inside.
        let big = square(0.0, 0.0, 2.0);
        let inside = Plant::new(&c, Pose::new(0.0, 0.0, 0.0));
        assert!(inside.clearance_m(&big) > 0.0);
        assert!(inside.centre_inside(&big));
        assert!(inside.collides(&big));
        // Lone vertices are points for clearance.
        let mut point = Obstacles::new();
        point.push(&[PointM::new(0.0, 1.0)]).unwrap();
        assert!((inside.clearance_m(&point) - 0.7).abs() < 1e-5);
        assert_eq!(inside.clearance_m(&Obstacles::new()), f32::INFINITY);
    }

    #[test]
    fn sweep_in_place_reads_every_angle_and_takes_its_time() {
        use crate::sonar::SweepKind;
        let c = RobotConfig::default();
        let walls = wall_at_x(2.2);
        let mut plant = Plant::new(&c, Pose::new(1.0, 0.0, 0.0));
        let plan = SweepPlan::new(&c, SweepKind::Normal);
        let mut sweep = SweepBuffer::new();
        let t = plant.sweep_in_place(&walls, &plan, &mut sweep);
        assert_eq!(sweep.len(), 105);
        assert!((t - plan.timing(&c).total_s()).abs() < 1e-6);
        assert!((plant.time_s() - t).abs() < 1e-4);
        let ahead = sweep.as_slice()[52];
        assert_eq!(ahead.neck_angle_rad, 0.0);
        assert!((ahead.range_m.unwrap() - 1.0).abs() < 1e-4);
        // Readings beyond 1.5 m are no echo: the wall is at 1 m, so |angle| > 48° sees nothing.
        assert!(sweep.as_slice()[0].range_m.is_none());
        assert_eq!(plant.pose(), Pose::new(1.0, 0.0, 0.0));
    }

    #[test]
    fn encoder_counts_do_not_drift() {
        // Many tiny steps: the fractions carry over, so the count matches the wheel angle.
        let c = RobotConfig::default();
        let mut plant = Plant::new(&c, Pose::default());
        let mut angle = 0.0f64;
        for _ in 0..4000 {
            plant.step(0.005, 1.0, 1.0);
            angle += plant.wheel_speeds_rad_s().0 as f64 * 0.005;
        }
        let counts = plant.encoder_counts().0 as f64;
        let expected = angle / c.rad_per_count() as f64;
        assert!((counts - expected).abs() < 3.0, "{counts} vs {expected}");
    }

    proptest::proptest! {
        #[test]
        fn nonsense_configs_never_panic(
            a in proptest::num::f32::ANY,
            b in proptest::num::f32::ANY,
            d in proptest::num::f32::ANY,
            rays in proptest::num::u8::ANY,
            pulses in proptest::num::u32::ANY,
        ) {
            use crate::control::{ControlInput, Controller};
            let c = RobotConfig {
                wheel_radius_m: a,
                half_axle_m: b,
                point_offset_m: d,
                motor_time_constant_s: a,
                reference_time_constant_s: b,
                plant_substep_s: d,
                sonar_cone_deg: a,
                sonar_cone_rays: rays,
                sonar_noise_std_m: b,
                encoder_pulses_per_rev: pulses,
                max_voltage_v: d,
                ..RobotConfig::default()
            };
            let mut plant = Plant::new(&c, Pose::new(1.0, 0.0, 0.0));
            let mut ctl = Controller::new(&c, Pose::new(1.0, 0.0, 0.0));
            let obstacles = square(3.0, 0.0, 0.5);
            let mut last = plant.encoder_counts();
            for _ in 0..3 {
                let now = plant.encoder_counts();
                let out = ctl.step(ControlInput {
                    reference: PointM::new(2.0, 1.0),
                    encoder_left_delta_counts: now.0.wrapping_sub(last.0),
                    encoder_right_delta_counts: now.1.wrapping_sub(last.1),
                    elapsed_since_last_step_s: 0.05,
                });
                last = now;
                plant.step(0.05, out.left_voltage_v, out.right_voltage_v);
                let _ = ctl.step_turn(ControlInput::default(), a);
                let _ = plant.sonar_range_m(&obstacles, 0.1, 1.5);
                let _ = plant.clearance_m(&obstacles);
            }
            proptest::prop_assert!(plant.pose().is_finite());
            proptest::prop_assert!(ctl.pose().is_finite());
        }

        #[test]
        fn beam_never_panics(
            x in proptest::num::f32::ANY,
            heading in proptest::num::f32::ANY,
            half in proptest::num::f32::ANY,
            limit in proptest::num::f32::ANY,
            corner in proptest::num::f32::ANY,
            range in proptest::num::f32::ANY,
        ) {
            let c = RobotConfig {
                sonar_beam: true,
                sonar_beam_half_angle_deg: half,
                sonar_incidence_limit_deg: limit,
                sonar_corner_radius_m: corner,
                sonar_noise_std_m: 0.01,
                ..RobotConfig::default()
            };
            let obstacles = square(3.0, 0.0, 0.5);
            let mut plant = Plant::new(&c, Pose::new(x, 0.1, heading));
            if let Some(d) = plant.sonar_range_m(&obstacles, half, range) {
                proptest::prop_assert!(d.is_finite() && d >= c.sonar_min_range_m && d <= range);
            }
        }

        #[test]
        fn sonar_and_clearance_never_panic(
            x in proptest::num::f32::ANY,
            y in proptest::num::f32::ANY,
            heading in proptest::num::f32::ANY,
            neck in proptest::num::f32::ANY,
            range in proptest::num::f32::ANY,
        ) {
            let c = RobotConfig { sonar_noise_std_m: 0.01, sonar_cone_deg: 10.0, sonar_cone_rays: 3, ..RobotConfig::default() };
            let obstacles = square(3.0, 0.0, 0.5);
            let mut plant = Plant::new(&c, Pose::new(x, y, heading));
            if let Some(d) = plant.sonar_range_m(&obstacles, neck, range) {
                proptest::prop_assert!(d.is_finite() && d >= c.sonar_min_range_m && d <= range);
            }
            let _ = plant.clearance_m(&obstacles);
            let _ = plant.centre_inside(&obstacles);
            plant.step(0.05, x, y);
            proptest::prop_assert!(plant.pose().is_finite());
        }
    }
}
