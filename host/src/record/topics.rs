//! What twil's data looks like as Foxglove messages: pure conversions, no I/O.
//!
//! Frames: `map` is the world frame of the `.da` / `.par` files (metres, x right, y up, the
//! grid's corner at the origin); `robot` is the robot's body frame (x ahead), placed in `map`
//! by `/tf`. Timestamps are mission time: `t_s` seconds after the start map to `t_s`
//! seconds after the Unix epoch (a recording starts on 1 January 1970, 00:00:00).

use foxglove::messages::{line_primitive, packed_element_field, scene_entity_deletion};
use foxglove::messages::{ArrowPrimitive, Point3};
use foxglove::messages::{
    Color, CylinderPrimitive, FrameTransform, Grid, LinePrimitive, PackedElementField, PointCloud,
    Pose as FgPose, PoseInFrame, Quaternion, SceneEntity, SceneEntityDeletion, SceneUpdate,
    Timestamp, Vector2, Vector3,
};
use schemars::JsonSchema;
use serde::Serialize;
use twil_core::control::Pose;
use twil_core::geom::PointM;
use twil_core::grid::Grid400;
use twil_core::world::Obstacles;

use crate::sim::ControlSample;

/// The world frame.
pub const MAP_FRAME: &str = "map";
/// The robot's body frame.
pub const ROBOT_FRAME: &str = "robot";

/// Every topic twil writes, in the order the docs list them.
pub const TOPICS: [&str; 10] = [
    "/map", "/world", "/plan", "/prefix", "/tf", "/pose", "/sonar", "/band", "/status", "/control",
];

/// Mission time as a Foxglove timestamp (negative or non-finite times clamp to 0).
pub fn timestamp(t_s: f32) -> Timestamp {
    let t = if t_s.is_finite() { t_s.max(0.0) } else { 0.0 };
    Timestamp::saturating_from_epoch_secs_f64(t as f64)
}

/// Mission time in nanoseconds (the log time of a message).
pub fn nanos(t_s: f32) -> u64 {
    let t = if t_s.is_finite() { t_s.max(0.0) } else { 0.0 };
    // Whole microseconds: an f32 time carries no more (0.05 is 0.0500000007 as f32, which
    // would stamp the first period 50 000 001 ns).
    ((t as f64) * 1e6).round() as u64 * 1000
}

fn rgba(r: f64, g: f64, b: f64, a: f64) -> Color {
    Color { r, g, b, a }
}

fn point3(p: PointM, z_m: f64) -> Point3 {
    Point3 {
        x: p.x_m as f64,
        y: p.y_m as f64,
        z: z_m,
    }
}

/// A rotation about +z by `heading_rad`.
fn yaw(heading_rad: f32) -> Quaternion {
    let half = heading_rad as f64 / 2.0;
    Quaternion {
        x: 0.0,
        y: 0.0,
        z: half.sin(),
        w: half.cos(),
    }
}

fn identity_pose() -> FgPose {
    FgPose {
        position: Some(Vector3::default()),
        orientation: Some(yaw(0.0)),
    }
}

fn pose_of(pose: &Pose) -> FgPose {
    FgPose {
        position: Some(Vector3 {
            x: pose.x_m as f64,
            y: pose.y_m as f64,
            z: 0.0,
        }),
        orientation: Some(yaw(pose.heading_rad)),
    }
}

/// Cell values of `/map`: the 3D panel's default colour map shows 0 as free and 100 as
/// occupied (the ROS occupancy convention).
pub const OCCUPIED_VALUE: u8 = 100;

/// One byte per cell, row-major from the grid's corner at the origin: [`OCCUPIED_VALUE`]
/// where the robot's map (known obstacles and hits, grown by the planning radius) is
/// occupied, 0 elsewhere.
pub fn grid_bytes(grid: &Grid400) -> Vec<u8> {
    let count = grid.geometry().cell_count();
    (0..count)
        .map(|i| if grid.bit(i) { OCCUPIED_VALUE } else { 0 })
        .collect()
}

/// `/map`: the robot's map as a `foxglove.Grid` of the bytes of [`grid_bytes`].
pub fn grid_message(t_s: f32, grid: &Grid400, cells: Vec<u8>) -> Grid {
    let g = grid.geometry();
    let resolution_m = g.resolution_m() as f64;
    Grid {
        timestamp: Some(timestamp(t_s)),
        frame_id: MAP_FRAME.into(),
        pose: Some(identity_pose()),
        column_count: g.width() as u32,
        cell_size: Some(Vector2 {
            x: resolution_m,
            y: resolution_m,
        }),
        row_stride: g.width() as u32,
        cell_stride: 1,
        fields: vec![PackedElementField {
            name: "occupied".into(),
            offset: 0,
            r#type: packed_element_field::NumericType::Uint8 as i32,
        }],
        data: cells.into(),
    }
}

fn line(
    points: Vec<Point3>,
    kind: line_primitive::Type,
    thickness_m: f64,
    color: Color,
) -> LinePrimitive {
    LinePrimitive {
        r#type: kind as i32,
        pose: Some(identity_pose()),
        thickness: thickness_m,
        scale_invariant: false,
        points,
        color: Some(color),
        ..Default::default()
    }
}

fn entity(t_s: f32, id: &str, frame: &str) -> SceneEntity {
    SceneEntity {
        timestamp: Some(timestamp(t_s)),
        frame_id: frame.into(),
        id: id.into(),
        ..Default::default()
    }
}

/// Polygons as closed outlines, `z_m` above the map (so they draw over the grid).
fn polygon_lines(
    obstacles: &Obstacles,
    z_m: f64,
    thickness_m: f64,
    color: Color,
) -> Vec<LinePrimitive> {
    obstacles
        .iter()
        .map(|polygon| {
            let points = polygon.iter().map(|&p| point3(p, z_m)).collect();
            line(points, line_primitive::Type::LineLoop, thickness_m, color)
        })
        .collect()
}

/// What `/world` shows: the real obstacles (grey outlines), the known ones (black), start and
/// goal, and the robot's body (a disc of `body_radius_m` with a heading arrow, locked to the
/// `robot` frame so it moves with `/tf`).
pub struct WorldScene<'a> {
    /// The real world (the simulator's, or a simulated device's), if known.
    pub real: Option<&'a Obstacles>,
    /// Obstacles known before the first sweep.
    pub known: Option<&'a Obstacles>,
    /// The mission's start.
    pub start: PointM,
    /// The mission's goal.
    pub goal: PointM,
    /// The robot's body radius, metres; `None` draws no robot (`twil plan` has no `/tf`).
    pub body_radius_m: Option<f32>,
}

/// `/world`: see [`WorldScene`].
pub fn world_update(t_s: f32, scene: &WorldScene) -> SceneUpdate {
    let mut entities = Vec::new();
    if let Some(real) = scene.real {
        let mut e = entity(t_s, "real", MAP_FRAME);
        e.lines = polygon_lines(real, 0.01, 0.03, rgba(0.45, 0.45, 0.5, 1.0));
        entities.push(e);
    }
    if let Some(known) = scene.known {
        let mut e = entity(t_s, "known", MAP_FRAME);
        e.lines = polygon_lines(known, 0.02, 0.04, rgba(0.1, 0.1, 0.1, 1.0));
        entities.push(e);
    }
    let marker = |id: &str, p: PointM, color: Color| {
        let mut e = entity(t_s, id, MAP_FRAME);
        e.cylinders = vec![CylinderPrimitive {
            pose: Some(pose_of(&Pose::new(p.x_m, p.y_m, 0.0))),
            size: Some(Vector3 {
                x: 0.2,
                y: 0.2,
                z: 0.05,
            }),
            bottom_scale: 1.0,
            top_scale: 1.0,
            color: Some(color),
        }];
        e
    };
    entities.push(marker("start", scene.start, rgba(0.0, 0.63, 0.0, 1.0)));
    entities.push(marker("goal", scene.goal, rgba(0.78, 0.0, 0.78, 1.0)));
    if let Some(radius_m) = scene.body_radius_m {
        entities.push(robot_entity(t_s, radius_m));
    }
    SceneUpdate {
        deletions: Vec::new(),
        entities,
    }
}

/// The robot's body, a disc of `radius_m` with a heading arrow, locked to the robot frame.
fn robot_entity(t_s: f32, radius_m: f32) -> SceneEntity {
    let r = radius_m.max(0.05) as f64;
    let mut robot = entity(t_s, "robot", ROBOT_FRAME);
    robot.frame_locked = true;
    robot.cylinders = vec![CylinderPrimitive {
        pose: Some(FgPose {
            position: Some(Vector3 {
                x: 0.0,
                y: 0.0,
                z: 0.05,
            }),
            orientation: Some(yaw(0.0)),
        }),
        size: Some(Vector3 {
            x: 2.0 * r,
            y: 2.0 * r,
            z: 0.1,
        }),
        bottom_scale: 1.0,
        top_scale: 1.0,
        color: Some(rgba(1.0, 0.59, 0.0, 0.8)),
    }];
    robot.arrows = vec![ArrowPrimitive {
        pose: Some(FgPose {
            position: Some(Vector3 {
                x: 0.0,
                y: 0.0,
                z: 0.12,
            }),
            orientation: Some(yaw(0.0)),
        }),
        shaft_length: r,
        shaft_diameter: 0.03,
        head_length: 0.08,
        head_diameter: 0.08,
        color: Some(rgba(0.2, 0.1, 0.0, 1.0)),
    }];
    robot
}

/// Which polyline a path update carries.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PathKind {
    /// The whole plan, start to goal (`/plan`, light blue).
    Plan,
    /// The kept prefix the robot follows (`/prefix`, dark blue, thicker).
    Prefix,
}

/// `/plan` or `/prefix`: a line strip of `points` (world metres). An empty path deletes the
/// entity, so that a mission that ends unreachable shows no plan.
///
/// A `SceneUpdate` line rather than `PosesInFrame`: the points have no orientation, the 3D
/// panel draws a line in the colour and width given here, and a deletion clears it.
pub fn path_update(t_s: f32, kind: PathKind, points: &[PointM]) -> SceneUpdate {
    let (id, z_m, thickness_m, color) = match kind {
        PathKind::Plan => ("plan", 0.03, 0.03, rgba(0.47, 0.63, 1.0, 1.0)),
        PathKind::Prefix => ("prefix", 0.04, 0.06, rgba(0.0, 0.35, 0.9, 1.0)),
    };
    if points.is_empty() {
        return SceneUpdate {
            deletions: vec![SceneEntityDeletion {
                timestamp: Some(timestamp(t_s)),
                r#type: scene_entity_deletion::Type::MatchingId as i32,
                id: id.into(),
            }],
            entities: Vec::new(),
        };
    }
    let mut e = entity(t_s, id, MAP_FRAME);
    e.lines = vec![line(
        points.iter().map(|&p| point3(p, z_m)).collect(),
        line_primitive::Type::LineStrip,
        thickness_m,
        color,
    )];
    SceneUpdate {
        deletions: Vec::new(),
        entities: vec![e],
    }
}

/// `/tf`: the robot frame in the map frame.
pub fn transform(t_s: f32, pose: &Pose) -> FrameTransform {
    let p = pose_of(pose);
    FrameTransform {
        timestamp: Some(timestamp(t_s)),
        parent_frame_id: MAP_FRAME.into(),
        child_frame_id: ROBOT_FRAME.into(),
        translation: p.position,
        rotation: p.orientation,
    }
}

/// `/pose`: the robot's pose in the map frame.
pub fn pose_in_frame(t_s: f32, pose: &Pose) -> PoseInFrame {
    PoseInFrame {
        timestamp: Some(timestamp(t_s)),
        frame_id: MAP_FRAME.into(),
        pose: Some(pose_of(pose)),
    }
}

/// `/sonar`: the hits of one sweep, map frame, as a point cloud of `x`, `y` (f32 each).
pub fn hits_cloud(t_s: f32, hits: &[PointM]) -> PointCloud {
    let mut data = Vec::with_capacity(hits.len() * 8);
    for p in hits {
        data.extend_from_slice(&p.x_m.to_le_bytes());
        data.extend_from_slice(&p.y_m.to_le_bytes());
    }
    let field = |name: &str, offset: u32| PackedElementField {
        name: name.into(),
        offset,
        r#type: packed_element_field::NumericType::Float32 as i32,
    };
    PointCloud {
        timestamp: Some(timestamp(t_s)),
        frame_id: MAP_FRAME.into(),
        pose: Some(identity_pose()),
        point_stride: 8,
        fields: vec![field("x", 0), field("y", 4)],
        data: data.into(),
    }
}

/// Points of the outline of the band a sweep covers: from the robot's position out to
/// `range_m` at `-half_angle_rad`, along the arc to `+half_angle_rad` (about every 5°) and
/// back (a full circle for a ±180° sweep).
pub fn band_outline(pose: &Pose, half_angle_rad: f32, range_m: f32) -> Vec<PointM> {
    let half = half_angle_rad.clamp(0.0, core::f32::consts::PI);
    let steps = ((2.0 * half).to_degrees() / 5.0).ceil().max(1.0) as usize;
    let centre = PointM::new(pose.x_m, pose.y_m);
    let mut points = vec![centre];
    for k in 0..=steps {
        let a = pose.heading_rad - half + 2.0 * half * k as f32 / steps as f32;
        points.push(PointM::new(
            centre.x_m + range_m * a.cos(),
            centre.y_m + range_m * a.sin(),
        ));
    }
    points.push(centre);
    points
}

/// `/band`: the band a sweep covers (±`half_angle_rad` about the heading at `pose`, out to
/// the sonar's `range_m`): what the mission may trust when it keeps a prefix.
pub fn band_update(t_s: f32, pose: &Pose, half_angle_rad: f32, range_m: f32) -> SceneUpdate {
    let mut e = entity(t_s, "band", MAP_FRAME);
    let points = band_outline(pose, half_angle_rad, range_m)
        .into_iter()
        .map(|p| point3(p, 0.015))
        .collect();
    e.lines = vec![line(
        points,
        line_primitive::Type::LineStrip,
        0.02,
        rgba(0.9, 0.6, 0.0, 0.9),
    )];
    SceneUpdate {
        deletions: Vec::new(),
        entities: vec![e],
    }
}

/// `/status`: the mission's phase and status, and the counters, on every change.
#[derive(Clone, Debug, PartialEq, Serialize, JsonSchema)]
pub struct StatusMessage {
    /// Mission time, seconds.
    pub t_s: f32,
    /// `sweep`, `full sweep`, `follow`, `settle`, `plan`, `done` (or `starting`).
    pub phase: String,
    /// `running`, `reached`, `unreachable`, `timeout`, `aborted`.
    pub status: String,
    /// What just happened (`planned`, `sweep done`, `full sweep requested`, …), or empty.
    pub event: String,
    /// Plans so far.
    pub plans: u32,
    /// Stops so far.
    pub stops: u32,
}

/// `/control`: the controller's signals of one period, plottable (`null` where the source
/// does not carry a signal: `twil mission` telemetry has the voltages only).
#[derive(Clone, Debug, PartialEq, Serialize, JsonSchema)]
pub struct ControlMessage {
    /// Mission time, seconds.
    pub t_s: f32,
    /// Reference handed to the controller, world metres.
    pub reference_x_m: Option<f32>,
    /// Reference handed to the controller, world metres.
    pub reference_y_m: Option<f32>,
    /// Distance from the control point to the reference model's output, metres.
    pub tracking_error_m: Option<f32>,
    /// Left wheel speed reference, rad/s.
    pub left_speed_ref_rad_s: Option<f32>,
    /// Right wheel speed reference, rad/s.
    pub right_speed_ref_rad_s: Option<f32>,
    /// Left wheel speed error (reference − measured), rad/s.
    pub left_speed_error_rad_s: Option<f32>,
    /// Right wheel speed error (reference − measured), rad/s.
    pub right_speed_error_rad_s: Option<f32>,
    /// Left motor voltage, volts.
    pub left_voltage_v: f32,
    /// Right motor voltage, volts.
    pub right_voltage_v: f32,
}

/// The `/control` message of one trajectory row's signals.
pub fn control_message(t_s: f32, c: &ControlSample) -> ControlMessage {
    let tracking_error_m = match (c.reference_model, c.control_point) {
        (Some(m), Some(p)) => Some(((m.x_m - p.x_m).powi(2) + (m.y_m - p.y_m).powi(2)).sqrt()),
        _ => None,
    };
    let error = |pick: fn((f32, f32)) -> f32| match (c.speed_ref_rad_s, c.speed_rad_s) {
        (Some(r), Some(m)) => Some(pick(r) - pick(m)),
        _ => None,
    };
    ControlMessage {
        t_s,
        reference_x_m: c.reference.map(|p| p.x_m),
        reference_y_m: c.reference.map(|p| p.y_m),
        tracking_error_m,
        left_speed_ref_rad_s: c.speed_ref_rad_s.map(|s| s.0),
        right_speed_ref_rad_s: c.speed_ref_rad_s.map(|s| s.1),
        left_speed_error_rad_s: error(|s| s.0),
        right_speed_error_rad_s: error(|s| s.1),
        left_voltage_v: c.left_voltage_v,
        right_voltage_v: c.right_voltage_v,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use twil_core::grid::GridGeometry;

    #[test]
    fn mission_time_maps_to_nanoseconds_after_the_epoch() {
        assert_eq!(nanos(0.05), 50_000_000);
        assert_eq!(nanos(-1.0), 0);
        assert_eq!(nanos(f32::NAN), 0);
        let t = timestamp(476.0);
        assert_eq!((t.sec(), t.nsec()), (476, 0));
    }

    #[test]
    fn grid_bytes_mark_occupied_cells_row_major() {
        let geometry = GridGeometry::from_size_m(1.0, 0.5, 0.05).unwrap();
        let mut grid = Grid400::new(geometry).unwrap();
        grid.set_xy(3, 2, true);
        let bytes = grid_bytes(&grid);
        assert_eq!(bytes.len(), 20 * 10);
        assert_eq!(bytes[2 * 20 + 3], OCCUPIED_VALUE);
        assert_eq!(bytes.iter().filter(|&&b| b != 0).count(), 1);
        let msg = grid_message(1.0, &grid, bytes);
        assert_eq!(
            (msg.column_count, msg.row_stride, msg.cell_stride),
            (20, 20, 1)
        );
        assert_eq!(msg.data.len(), 200);
    }

    #[test]
    fn yaw_of_a_quarter_turn() {
        let q = yaw(core::f32::consts::FRAC_PI_2);
        assert!((q.z - 0.5f64.sqrt()).abs() < 1e-6 && (q.w - 0.5f64.sqrt()).abs() < 1e-6);
    }

    #[test]
    fn band_outline_spans_the_half_angle_at_the_range() {
        let pose = Pose::new(1.0, 2.0, 0.0);
        let points = band_outline(&pose, 95f32.to_radians(), 1.5);
        assert_eq!(points.first(), points.last());
        let first_arc = points[1];
        let angle = (first_arc.y_m - 2.0)
            .atan2(first_arc.x_m - 1.0)
            .to_degrees();
        assert!((angle + 95.0).abs() < 0.01, "{angle}");
        for p in &points[1..points.len() - 1] {
            let r = ((p.x_m - 1.0).powi(2) + (p.y_m - 2.0).powi(2)).sqrt();
            assert!((r - 1.5).abs() < 1e-4);
        }
    }

    #[test]
    fn an_empty_path_deletes_its_entity() {
        let update = path_update(3.0, PathKind::Prefix, &[]);
        assert!(update.entities.is_empty());
        assert_eq!(update.deletions[0].id, "prefix");
        let update = path_update(
            3.0,
            PathKind::Plan,
            &[PointM::new(0.0, 0.0), PointM::new(1.0, 1.0)],
        );
        assert_eq!(update.entities[0].lines[0].points.len(), 2);
    }

    #[test]
    fn hits_pack_as_two_floats_each() {
        let cloud = hits_cloud(0.0, &[PointM::new(1.5, -2.0)]);
        assert_eq!(cloud.data.len(), 8);
        assert_eq!(
            f32::from_le_bytes(cloud.data[4..8].try_into().unwrap()),
            -2.0
        );
    }

    #[test]
    fn control_errors_need_both_reference_and_measure() {
        let sample = ControlSample {
            speed_ref_rad_s: Some((2.0, 3.0)),
            speed_rad_s: Some((1.5, 3.5)),
            left_voltage_v: 4.0,
            ..Default::default()
        };
        let m = control_message(1.0, &sample);
        assert_eq!(m.left_speed_error_rad_s, Some(0.5));
        assert_eq!(m.right_speed_error_rad_s, Some(-0.5));
        assert_eq!(m.tracking_error_m, None);
        let voltages_only = control_message(1.0, &ControlSample::default());
        assert_eq!(voltages_only.left_speed_error_rad_s, None);
    }
}
