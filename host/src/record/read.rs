//! Reading a twil recording back: what an MCAP file written by [`super::Recorder`] held at a
//! given mission time, decoded with the Foxglove SDK's own message types (`foxglove::Decode`).
//!
//! This is the inverse of [`super::topics`] for what a picture needs (`twil view`) and what the
//! tests check: the last map, world, plan, prefix, sweep and band before the time, every pose
//! up to it (the trail) and the last status. A file that is not an MCAP, or a message that does
//! not decode, is an error naming the topic and the log time; topics twil does not write are
//! skipped.

use std::path::Path;

use anyhow::{anyhow, bail, Context, Result};
use foxglove::messages::{Grid, PointCloud, PoseInFrame, SceneUpdate};
use foxglove::Decode;
use twil_core::control::Pose;
use twil_core::geom::PointM;
use twil_core::grid::{Grid400, GridGeometry};

use super::topics::{StatusMessage, OCCUPIED_VALUE};

/// Largest recording `twil view` reads, bytes (a 900 s office mission is about 2 MB).
pub const MAX_RECORDING_BYTES: u64 = 512 * 1024 * 1024;

/// What a recording showed at one mission time.
#[derive(Debug, Default)]
pub struct RecordedState {
    /// Mission time of the last message read, seconds.
    pub t_s: f32,
    /// Mission time of the recording's last message, seconds.
    pub end_s: f32,
    /// The robot's map (grown), from the last `/map`.
    pub map: Option<Box<Grid400>>,
    /// Real obstacles (`/world`, entity `real`), as polygons.
    pub real: Vec<Vec<PointM>>,
    /// Known obstacles (`/world`, entity `known`), as polygons.
    pub known: Vec<Vec<PointM>>,
    /// Start and goal.
    pub start: Option<PointM>,
    /// Goal.
    pub goal: Option<PointM>,
    /// The robot's body radius, metres (`/world`, entity `robot`).
    pub body_radius_m: Option<f32>,
    /// The last plan and kept prefix (empty after a deletion).
    pub plan: Vec<PointM>,
    /// The kept prefix.
    pub prefix: Vec<PointM>,
    /// Every pose up to the time (`/pose`).
    pub trail: Vec<Pose>,
    /// Hits of the last sweep (`/sonar`).
    pub last_hits: Vec<PointM>,
    /// Every hit up to the time.
    pub hits: Vec<PointM>,
    /// Outline of the last swept band (`/band`).
    pub band: Vec<PointM>,
    /// The last `/status`.
    pub status: Option<StatusMessage>,
    /// Messages read, all topics.
    pub messages: u64,
}

fn decode<T: Decode>(topic: &str, t_ns: u64, data: &[u8]) -> Result<T>
where
    T::Error: std::fmt::Display,
{
    T::decode(data).map_err(|e| {
        anyhow!(
            "{topic} at {:.3} s: not a twil message: {e}",
            t_ns as f64 / 1e9
        )
    })
}

fn point(p: &foxglove::messages::Point3) -> PointM {
    PointM::new(p.x as f32, p.y as f32)
}

fn heading(q: Option<&foxglove::messages::Quaternion>) -> f32 {
    q.map(|q| (2.0 * q.z.atan2(q.w)) as f32).unwrap_or(0.0)
}

/// The first line of entity `id` in `update` as points (None when the entity is absent).
fn entity_lines(update: &SceneUpdate, id: &str) -> Option<Vec<Vec<PointM>>> {
    update.entities.iter().find(|e| e.id == id).map(|e| {
        e.lines
            .iter()
            .map(|l| l.points.iter().map(point).collect())
            .collect()
    })
}

fn deleted(update: &SceneUpdate, id: &str) -> bool {
    update.deletions.iter().any(|d| d.id == id)
}

fn grid_of(grid: &Grid) -> Result<Box<Grid400>> {
    let width = grid.column_count as usize;
    let stride = grid.row_stride as usize;
    let resolution_m = grid.cell_size.as_ref().map(|c| c.x as f32).unwrap_or(0.0);
    if width == 0 || stride < width || grid.cell_stride != 1 {
        bail!("/map: a grid of {width} columns, row stride {stride}, cell stride {}: not twil's layout", grid.cell_stride);
    }
    let height = grid.data.len() / stride;
    let geometry = GridGeometry::new(width as u32, height as u32, resolution_m)
        .with_context(|| format!("/map: {width}x{height} cells of {resolution_m} m"))?;
    let mut map = Box::new(Grid400::new(geometry).context("/map")?);
    for y in 0..height {
        for x in 0..width {
            if grid.data.get(y * stride + x) == Some(&OCCUPIED_VALUE) {
                map.set_xy(x as i32, y as i32, true);
            }
        }
    }
    Ok(map)
}

fn cloud_points(cloud: &PointCloud) -> Vec<PointM> {
    let stride = cloud.point_stride as usize;
    if stride < 8 {
        return Vec::new();
    }
    cloud
        .data
        .chunks_exact(stride)
        .map(|c| {
            let f = |i: usize| f32::from_le_bytes([c[i], c[i + 1], c[i + 2], c[i + 3]]);
            PointM::new(f(0), f(4))
        })
        .collect()
}

/// Read `path` up to mission time `at_s` (the whole file when `None`).
pub fn read(path: &Path, at_s: Option<f32>) -> Result<RecordedState> {
    let bytes = crate::files::read_capped(path, "recording", MAX_RECORDING_BYTES)?;
    let until_ns = at_s.map(super::topics::nanos);
    let mut state = RecordedState::default();
    // The MCAP magic: `\x89MCAP` and the major version.
    if !bytes.starts_with(b"\x89MCAP") {
        bail!(
            "{}: not an MCAP file (it does not start with the MCAP magic)",
            path.display()
        );
    }
    let stream = mcap::MessageStream::new(&bytes)
        .with_context(|| format!("{}: not an MCAP file", path.display()))?;
    for message in stream {
        let m = message.with_context(|| format!("{}: unreadable message", path.display()))?;
        let t_ns = m.log_time;
        state.end_s = state.end_s.max(t_ns as f32 / 1e9);
        if until_ns.is_some_and(|u| t_ns > u) {
            continue;
        }
        state.t_s = state.t_s.max(t_ns as f32 / 1e9);
        state.messages += 1;
        let topic = m.channel.topic.as_str();
        let data = &m.data[..];
        let context = || format!("{}", path.display());
        match topic {
            "/map" => {
                let grid: Grid = decode(topic, t_ns, data).with_context(context)?;
                state.map = Some(grid_of(&grid).with_context(context)?);
            }
            "/world" => {
                let u: SceneUpdate = decode(topic, t_ns, data).with_context(context)?;
                if let Some(real) = entity_lines(&u, "real") {
                    state.real = real;
                }
                if let Some(known) = entity_lines(&u, "known") {
                    state.known = known;
                }
                for e in &u.entities {
                    let at = e.cylinders.first().and_then(|c| c.pose.as_ref());
                    let at = at
                        .and_then(|p| p.position.as_ref())
                        .map(|v| PointM::new(v.x as f32, v.y as f32));
                    match e.id.as_str() {
                        "start" => state.start = at,
                        "goal" => state.goal = at,
                        "robot" => {
                            state.body_radius_m = e
                                .cylinders
                                .first()
                                .and_then(|c| c.size.as_ref())
                                .map(|s| (s.x / 2.0) as f32)
                        }
                        _ => {}
                    }
                }
            }
            "/plan" | "/prefix" => {
                let id = &topic[1..];
                let u: SceneUpdate = decode(topic, t_ns, data).with_context(context)?;
                let points = if deleted(&u, id) {
                    Vec::new()
                } else {
                    entity_lines(&u, id)
                        .and_then(|l| l.into_iter().next())
                        .unwrap_or_default()
                };
                if topic == "/plan" {
                    state.plan = points;
                } else {
                    state.prefix = points;
                }
            }
            "/pose" => {
                let p: PoseInFrame = decode(topic, t_ns, data).with_context(context)?;
                if let Some(pose) = p.pose {
                    let v = pose.position.unwrap_or_default();
                    state.trail.push(Pose::new(
                        v.x as f32,
                        v.y as f32,
                        heading(pose.orientation.as_ref()),
                    ));
                }
            }
            "/sonar" => {
                let c: PointCloud = decode(topic, t_ns, data).with_context(context)?;
                state.last_hits = cloud_points(&c);
                state.hits.extend_from_slice(&state.last_hits);
            }
            "/band" => {
                let u: SceneUpdate = decode(topic, t_ns, data).with_context(context)?;
                state.band = entity_lines(&u, "band")
                    .and_then(|l| l.into_iter().next())
                    .unwrap_or_default();
            }
            "/status" => {
                if let Ok(s) = serde_json::from_slice::<serde_json::Value>(data) {
                    let text = |k: &str| s[k].as_str().unwrap_or("").to_string();
                    let number = |k: &str| s[k].as_u64().unwrap_or(0) as u32;
                    state.status = Some(StatusMessage {
                        t_s: s["t_s"].as_f64().unwrap_or(0.0) as f32,
                        phase: text("phase"),
                        status: text("status"),
                        event: text("event"),
                        plans: number("plans"),
                        stops: number("stops"),
                    });
                }
            }
            _ => {}
        }
    }
    if state.messages == 0 {
        bail!(
            "{}: no message before {:.1} s",
            path.display(),
            at_s.unwrap_or(0.0)
        );
    }
    Ok(state)
}
