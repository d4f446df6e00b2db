//! Lumelsky's Bug1 run in a kinematic simulator with the sonar: the host side of
//! `twil_core::classic::bug` (seed 004 §1.5.3).
//!
//! The robot knows no map. Each step the simulator reads the sonar at the Bug's nine bearings
//! with the project's beam model (`Plant::sonar_range_m` with `sonar_beam`: 15° half-angle,
//! specular walls, corners, 0.26 m blanking, range `Options::sonar_range_m`), hands the readings
//! to the core's step function, turns the robot in place to the heading it answers and moves it
//! straight by at most 0.02 m. The robot is a kinematic disc, not the 50 ms wheel controller:
//! Bug is a decision method, and the wheel dynamics would only blur what it decides. The true
//! world (the `.da` polygons plus the map's border, which the sonar sees as four walls) is used
//! only by the sensor and to check for collisions (the body's physical radius); a collision is
//! an error, never a status.
//!
//! - **Bound** (`bound_m`): the seed's `D + 1.5 Σ pᵢ` on C-obstacles, the polygons grown by the
//!   `.par` radius (`pᵢ + 2πr`, exact for convex ones, an upper bound otherwise), those within
//!   `D + r` of the start, plus the map's border (the free rectangle inside it, perimeter
//!   `2(W + H) − 8r`): the robot cannot leave the map, so its border is an obstacle the Bug may
//!   have to go round. Vertices are clamped to the map for this sum, so it is bounded by the
//!   map and the vertex count, not by the numbers in the file.
//! - **Step limit**: `3 × bound / step` (at most [`MAX_STEPS`]), then `gave_up`.
//! - **Path**: the driven track thinned on the fly: a vertex is kept where the track leaves the
//!   chord from the last vertex by more than [`THIN_TOLERANCE_M`], and at least every
//!   [`THIN_CHORD_M`]. `length_m` is the driven length (the thinned polyline is a hair shorter).
//! - **Counts**: `expanded` = sonar readings taken; `memory_bytes` = the Bug's state (echo
//!   memory included) plus the thinned path and the hit/leave lists, as allocated.

use std::f32::consts::PI;

use anyhow::bail;
use twil_core::classic::bug::{self as core_bug, Bug, BugConfig, Command, Event, Phase};
use twil_core::control::Pose;
use twil_core::geom::PointM;
use twil_core::plant::Plant;
use twil_core::robot::RobotConfig;
use twil_core::world::Obstacles;

use super::{clearance, Method, Options, Overlay, Run, Status};
use crate::planning::World;

/// Most steps any run may take (20 km at 0.02 m), whatever the bound says.
pub const MAX_STEPS: u32 = 1_000_000;

/// The thinned path stays this close to the driven track, metres.
pub const THIN_TOLERANCE_M: f32 = 0.01;

/// Longest chord between two kept vertices, metres.
pub const THIN_CHORD_M: f32 = 1.0;

/// What `expanded` counts.
const UNIT: &str = "sonar readings";

/// Run Bug1 on `world` with the sonar range of `options`.
pub fn run(world: &World, options: &Options) -> anyhow::Result<Run> {
    let params = &world.params;
    let g = world.grid.geometry();
    let (width_m, height_m) = (g.width_m(), g.height_m());
    let radius_m = params.robot_radius_m;
    let (start, goal) = (params.start, params.goal);
    let inside = |p: PointM| p.x_m >= 0.0 && p.y_m >= 0.0 && p.x_m <= width_m && p.y_m <= height_m;
    if !(inside(start) && inside(goal)) {
        return Ok(Run::empty(Method::Bug, Status::OutOfBounds, UNIT));
    }
    // The harness's checks (the Bug itself knows nothing of them): a start or goal the body
    // already overlaps.
    let clear = |p: PointM| {
        clearance::min_clearance_m(&[p], &world.obstacles, width_m, height_m, radius_m)
            .is_some_and(|c| c >= 0.0)
    };
    if !clear(start) {
        return Ok(Run::empty(Method::Bug, Status::StartBlocked, UNIT));
    }
    if !clear(goal) {
        return Ok(Run::empty(Method::Bug, Status::GoalBlocked, UNIT));
    }

    let sensed = with_border(&world.obstacles, width_m, height_m)?;
    let mut robot = RobotConfig {
        sonar_beam: true,
        sonar_range_m: options.sonar_range_m,
        ..RobotConfig::default().with_planning_radius_m(radius_m)
    };
    if robot.sonar_range_m <= robot.sonar_min_range_m {
        robot.sonar_range_m = robot.sonar_min_range_m + 0.01;
    }
    if let Err(e) = robot.validate() {
        bail!("planner bug: the simulated robot: {e:?}");
    }

    let bound_m = bound_m(world);
    let mut config = BugConfig::new(radius_m, 0);
    config.sonar_offset_m = robot.sonar_offset_m;
    config.beam_half_angle_deg = robot.sonar_beam_half_angle_deg;
    let steps = (3.0 * bound_m / config.step_m).ceil();
    config.max_steps = if steps.is_finite() && steps < MAX_STEPS as f32 {
        steps as u32
    } else {
        MAX_STEPS
    };
    let Some(mut bug) = Bug::new(config, goal) else {
        bail!("planner bug: no valid Bug for radius {radius_m} m and goal {goal:?}");
    };

    let mut pose = Pose::new(
        start.x_m,
        start.y_m,
        params.initial_heading_deg * PI / 180.0,
    );
    let mut plant = Plant::new(&robot, pose);
    let bearings = bug.bearings_rad();
    let mut thin = Thinner::new(start);
    let (mut hits, mut leaves) = (Vec::new(), Vec::new());
    let (mut readings, mut driven_m) = (0u64, 0.0f64);
    let phase = loop {
        let mut ranges = [None; core_bug::READINGS];
        for (r, &b) in ranges.iter_mut().zip(&bearings) {
            *r = plant.sonar_range_m(&sensed, b, robot.sonar_range_m);
            readings += 1;
        }
        let out = bug.step(pose, &ranges);
        match out.event {
            Event::Hit(p) => hits.push(p),
            Event::Leave(p) => leaves.push(p),
            Event::None => {}
        }
        match out.command {
            Command::Stop(phase) => break phase,
            Command::Move {
                heading_rad,
                distance_m,
            } => {
                pose = Pose::new(
                    pose.x_m + distance_m * heading_rad.cos(),
                    pose.y_m + distance_m * heading_rad.sin(),
                    heading_rad,
                );
                plant.set_pose(pose);
                driven_m += f64::from(distance_m);
                thin.push(pose.position());
                if plant.collides(&sensed) {
                    bail!(
                        "planner bug: collision at ({:.3}, {:.3}) m after {} steps",
                        pose.x_m,
                        pose.y_m,
                        bug.steps()
                    );
                }
            }
        }
    };
    let path = thin.finish();
    let status = match phase {
        Phase::Reached => Status::Found,
        Phase::Unreachable => Status::Unreachable,
        _ => Status::GaveUp,
    };
    let length_m = driven_m as f32;
    let memory_bytes = std::mem::size_of::<Bug>()
        + (path.capacity() + hits.capacity() + leaves.capacity()) * std::mem::size_of::<PointM>();
    let mut extra = serde_json::Map::new();
    let pts = |v: &[PointM]| {
        v.iter()
            .map(|p| {
                serde_json::json!([
                    crate::planning::round_m(p.x_m),
                    crate::planning::round_m(p.y_m)
                ])
            })
            .collect::<Vec<_>>()
    };
    extra.insert("bound_m".into(), crate::planning::round_m(bound_m).into());
    extra.insert("hit_points".into(), pts(&hits).into());
    extra.insert("leave_points".into(), pts(&leaves).into());
    extra.insert(
        "within_bound".into(),
        (status == Status::Found && length_m <= bound_m).into(),
    );
    extra.insert("steps".into(), bug.steps().into());
    extra.insert("max_steps".into(), config.max_steps.into());
    extra.insert("step_m".into(), config.step_m.into());
    extra.insert(
        "follow_m".into(),
        crate::planning::round_m(config.follow_m).into(),
    );
    extra.insert("sonar_range_m".into(), robot.sonar_range_m.into());
    let mut nodes = hits.clone();
    nodes.extend_from_slice(&leaves);
    Ok(Run {
        method: Method::Bug,
        status,
        path,
        length_m,
        expanded: readings,
        expanded_unit: UNIT,
        memory_bytes,
        elapsed_us: 0,
        overlay: Overlay {
            nodes,
            node_label: "hit / leave point",
            ..Overlay::default()
        },
        extra,
    })
}

/// The polygons plus the map's border as four walls (the sonar sees the border; the Bug has to
/// go round it like any obstacle).
fn with_border(obstacles: &Obstacles, width_m: f32, height_m: f32) -> anyhow::Result<Obstacles> {
    let mut all = obstacles.clone();
    let c = [
        PointM::new(0.0, 0.0),
        PointM::new(width_m, 0.0),
        PointM::new(width_m, height_m),
        PointM::new(0.0, height_m),
    ];
    for i in 0..4 {
        if all.push(&[c[i], c[(i + 1) % 4]]).is_err() {
            bail!("planner bug: no room for the map's border among the polygons");
        }
    }
    Ok(all)
}

/// The seed's bound on `world` (see the module doc), metres.
pub fn bound_m(world: &World) -> f32 {
    let p = &world.params;
    let g = world.grid.geometry();
    let (w, h) = (g.width_m(), g.height_m());
    let r = p.robot_radius_m;
    let d = p.start.distance_m(p.goal);
    let clamp = |q: &PointM| PointM::new(q.x_m.clamp(0.0, w), q.y_m.clamp(0.0, h));
    let s = (f64::from(p.start.x_m), f64::from(p.start.y_m));
    let mut sum_m = 0.0f32;
    for poly in world.obstacles.iter() {
        let pts: Vec<PointM> = poly.iter().map(clamp).collect();
        let n = pts.len();
        let edges = if n >= 3 { n } else { n.saturating_sub(1) };
        let near = (0..n.max(1)).any(|i| {
            let a = pts.get(i).copied();
            let b = pts.get((i + 1) % n.max(1)).copied();
            match (a, b) {
                (Some(a), Some(b)) => {
                    let dist = clearance::point_segment_m(
                        s,
                        (f64::from(a.x_m), f64::from(a.y_m)),
                        (f64::from(b.x_m), f64::from(b.y_m)),
                    );
                    dist <= f64::from(d + r)
                }
                _ => false,
            }
        }) || (n >= 3 && clearance::inside_polygon(s, &pts));
        if near {
            let perimeter: f32 = (0..edges)
                .map(|i| pts[i].distance_m(pts[(i + 1) % n]))
                .sum();
            sum_m += perimeter + 2.0 * PI * r;
        }
    }
    let to_border_m = p
        .start
        .x_m
        .min(p.start.y_m)
        .min(w - p.start.x_m)
        .min(h - p.start.y_m);
    if to_border_m <= d + r {
        sum_m += (2.0 * (w + h) - 8.0 * r).max(0.0);
    }
    d + 1.5 * sum_m
}

/// The driven track thinned on the fly (see the module doc).
struct Thinner {
    kept: Vec<PointM>,
    pending: Vec<PointM>,
}

impl Thinner {
    fn new(start: PointM) -> Self {
        Self {
            kept: vec![start],
            pending: Vec::new(),
        }
    }

    fn push(&mut self, q: PointM) {
        let anchor = *self.kept.last().expect("a start");
        let a = (f64::from(anchor.x_m), f64::from(anchor.y_m));
        let b = (f64::from(q.x_m), f64::from(q.y_m));
        let fits = anchor.distance_m(q) <= THIN_CHORD_M
            && self.pending.iter().all(|m| {
                clearance::point_segment_m((f64::from(m.x_m), f64::from(m.y_m)), a, b)
                    <= f64::from(THIN_TOLERANCE_M)
            });
        if !fits {
            if let Some(&last) = self.pending.last() {
                self.kept.push(last);
            }
            self.pending.clear();
        }
        self.pending.push(q);
    }

    fn finish(mut self) -> Vec<PointM> {
        if let Some(&last) = self.pending.last() {
            self.kept.push(last);
        }
        self.kept
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thinning_keeps_corners_and_drops_straight_runs() {
        let mut t = Thinner::new(PointM::new(0.0, 0.0));
        for i in 1..=40 {
            t.push(PointM::new(0.02 * i as f32, 0.0));
        }
        for i in 1..=40 {
            t.push(PointM::new(0.8, 0.02 * i as f32));
        }
        let path = t.finish();
        // Start, the corner, the end: no vertex in the straight runs.
        assert_eq!(path.len(), 3, "{path:?}");
        assert!((path[1].x_m - 0.8).abs() < 1e-5 && path[1].y_m.abs() < 1e-5);
        // A long straight run still gets a vertex every metre at most.
        let mut t = Thinner::new(PointM::new(0.0, 0.0));
        for i in 1..=250 {
            t.push(PointM::new(0.02 * i as f32, 0.0));
        }
        let path = t.finish();
        assert!(path
            .windows(2)
            .all(|w| w[0].distance_m(w[1]) <= THIN_CHORD_M + 1e-4));
        assert!(path.len() >= 6);
    }
}
