//! Recordings (`--record FILE.mcap`) and the live view (`--live [ADDR]`): a mission as
//! Foxglove messages, written with the Foxglove SDK to an MCAP file and/or served by its
//! WebSocket server, timestamps in mission time. See `docs/recording.md`.
//!
//! [`Recorder`] owns the channels (one per topic, [`topics::TOPICS`]) and the sinks; what a
//! topic carries is built in [`topics`]; [`sim::SimRecorder`] feeds it from the simulator,
//! `twil mission` from the telemetry, `twil plan` from its one plan.

pub mod read;
pub mod sim;
pub mod telemetry;
pub mod topics;

use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use anyhow::{anyhow, Context as _, Result};
use foxglove::messages::{FrameTransform, Grid, PointCloud, PoseInFrame, SceneUpdate};
use foxglove::websocket::{Capability, ChannelView, Client, ServerListener};
use foxglove::WebSocketServerHandle;
use foxglove::{Channel, Context, Encode, McapWriterHandle, PartialMetadata, SinkId};
use twil_core::control::Pose;
use twil_core::geom::PointM;
use twil_core::grid::Grid400;

use crate::sim::ControlSample;
use topics::{ControlMessage, PathKind, StatusMessage, WorldScene};

/// The address `--live` serves on when given without one (the Foxglove app's default).
pub const DEFAULT_LIVE_ADDR: &str = "127.0.0.1:8765";

/// Parse `--live`'s address, `HOST:PORT`.
pub fn parse_live_addr(text: &str) -> Result<SocketAddr, String> {
    text.parse::<SocketAddr>()
        .map_err(|e| format!("expected HOST:PORT such as {DEFAULT_LIVE_ADDR}, got `{text}`: {e}"))
}

/// The recording and live options shared by `twil simulate` and `twil mission`.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct RecordArgs {
    /// Record the mission as Foxglove messages to this MCAP file (docs/recording.md).
    #[arg(long, value_name = "FILE.mcap")]
    pub record: Option<PathBuf>,
    /// Serve the mission live to the Foxglove app over its WebSocket protocol at this
    /// address while it runs (default 127.0.0.1:8765).
    #[arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = DEFAULT_LIVE_ADDR, value_parser = parse_live_addr)]
    pub live: Option<SocketAddr>,
}

impl RecordArgs {
    /// `true` when either option asks for messages.
    pub fn wanted(&self) -> bool {
        self.record.is_some() || self.live.is_some()
    }
}

/// Late subscribers: a client that subscribes after a stateful topic's last message (the
/// world, the map, the plan) gets that message again, sent to it alone, so it sees the scene
/// without the recording holding copies.
#[derive(Default)]
struct Subscriptions(Mutex<Vec<(SinkId, String)>>);

impl ServerListener for Subscriptions {
    fn on_subscribe(&self, client: Client, channel: ChannelView) {
        if let (Some(sink), Ok(mut pending)) = (client.sink_id(), self.0.lock()) {
            pending.push((sink, channel.topic().to_string()));
        }
    }
}

/// The last message of a stateful topic and its log time, nanoseconds.
type Latest<T> = Option<(T, u64)>;

/// One channel per topic.
struct Channels {
    map: Channel<Grid>,
    world: Channel<SceneUpdate>,
    plan: Channel<SceneUpdate>,
    prefix: Channel<SceneUpdate>,
    tf: Channel<FrameTransform>,
    pose: Channel<PoseInFrame>,
    sonar: Channel<PointCloud>,
    band: Channel<SceneUpdate>,
    status: Channel<StatusMessage>,
    control: Channel<ControlMessage>,
}

/// What a closed recorder wrote.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RecordSummary {
    /// The MCAP file and its size in bytes, if one was written.
    pub file: Option<(PathBuf, u64)>,
    /// Messages logged per topic.
    pub counts: BTreeMap<&'static str, u64>,
}

impl RecordSummary {
    /// Print [`RecordSummary::line`]: on stdout, or on stderr when `--json` keeps stdout to
    /// its one object.
    pub fn print(&self, json: bool) {
        if json {
            eprintln!("{}", self.line());
        } else {
            println!("{}", self.line());
        }
    }

    /// One line: file, size in MB, and the message count of every topic written.
    pub fn line(&self) -> String {
        let counts: Vec<String> = topics::TOPICS
            .iter()
            .filter_map(|t| self.counts.get(t).map(|n| format!("{t} {n}")))
            .collect();
        match &self.file {
            Some((path, bytes)) => format!(
                "recorded {}: {:.2} MB; messages: {}",
                path.display(),
                *bytes as f64 / 1e6,
                counts.join(", ")
            ),
            None => format!("served live; messages: {}", counts.join(", ")),
        }
    }
}

/// The channels and sinks of one run: see the module documentation.
pub struct Recorder {
    /// Kept so the channels stay attached to the sinks while the recorder lives.
    _context: Arc<Context>,
    channels: Channels,
    mcap: Option<(PathBuf, McapWriterHandle<BufWriter<File>>)>,
    server: Option<WebSocketServerHandle>,
    subscriptions: Arc<Subscriptions>,
    counts: BTreeMap<&'static str, u64>,
    last_map: Vec<u8>,
    latest_world: Latest<SceneUpdate>,
    latest_map: Latest<Grid>,
    latest_plan: Latest<SceneUpdate>,
    latest_prefix: Latest<SceneUpdate>,
    latest_status: Latest<StatusMessage>,
}

fn channel<T: Encode>(context: &Arc<Context>, topic: &str) -> Channel<T> {
    context.channel_builder(topic).build()
}

impl Recorder {
    /// Open the MCAP file (`record`, created or replaced) and/or start the WebSocket server at
    /// `live`. Errors name the file or the address.
    pub fn open(record: Option<&Path>, live: Option<SocketAddr>) -> Result<Self> {
        let context = Context::new();
        let mcap = match record {
            Some(path) => {
                if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
                    std::fs::create_dir_all(dir).with_context(|| {
                        format!("--record {}: cannot create its directory", path.display())
                    })?;
                }
                let file = File::create(path)
                    .with_context(|| format!("--record {}: cannot create", path.display()))?;
                let handle = context
                    .mcap_writer()
                    .create(BufWriter::new(file))
                    .map_err(|e| anyhow!("--record {}: {e}", path.display()))?;
                Some((path.to_path_buf(), handle))
            }
            None => None,
        };
        let subscriptions = Arc::new(Subscriptions::default());
        let server = match live {
            Some(addr) => Some(
                context
                    .websocket_server()
                    .name("twil")
                    .bind(addr.ip().to_string(), addr.port())
                    .capabilities([Capability::Time])
                    .listener(subscriptions.clone())
                    .start_blocking()
                    .map_err(|e| anyhow!("--live {addr}: {e}"))?,
            ),
            None => None,
        };
        let channels = Channels {
            map: channel(&context, "/map"),
            world: channel(&context, "/world"),
            plan: channel(&context, "/plan"),
            prefix: channel(&context, "/prefix"),
            tf: channel(&context, "/tf"),
            pose: channel(&context, "/pose"),
            sonar: channel(&context, "/sonar"),
            band: channel(&context, "/band"),
            status: channel(&context, "/status"),
            control: channel(&context, "/control"),
        };
        Ok(Self {
            _context: context,
            channels,
            mcap,
            server,
            subscriptions,
            counts: BTreeMap::new(),
            last_map: Vec::new(),
            latest_world: None,
            latest_map: None,
            latest_plan: None,
            latest_status: None,
            latest_prefix: None,
        })
    }

    /// The port the live server listens on (useful with port 0).
    pub fn live_port(&self) -> Option<u16> {
        self.server.as_ref().map(|s| s.port())
    }

    fn count(&mut self, topic: &'static str) {
        *self.counts.entry(topic).or_insert(0) += 1;
    }

    /// Tell live clients the mission time (the app's clock follows it) and resend the last
    /// world, map, plan and status to clients that subscribed since the last call.
    pub fn tick(&mut self, t_s: f32) {
        let Some(server) = &self.server else { return };
        server.broadcast_time(topics::nanos(t_s));
        let pending = match self.subscriptions.0.lock() {
            Ok(mut pending) => std::mem::take(&mut *pending),
            Err(_) => return,
        };
        for (sink, topic) in pending {
            let to = Some(sink);
            let meta = |t: u64| PartialMetadata { log_time: Some(t) };
            match topic.as_str() {
                "/world" => resend(&self.channels.world, &self.latest_world, to, meta),
                "/map" => resend(&self.channels.map, &self.latest_map, to, meta),
                "/plan" => resend(&self.channels.plan, &self.latest_plan, to, meta),
                "/prefix" => resend(&self.channels.prefix, &self.latest_prefix, to, meta),
                "/status" => resend(&self.channels.status, &self.latest_status, to, meta),
                _ => {}
            }
        }
    }

    /// `/world`: the real and known obstacles, start, goal and the robot's body.
    pub fn world(&mut self, t_s: f32, scene: &WorldScene) {
        let msg = topics::world_update(t_s, scene);
        self.channels.world.log_with_time(&msg, topics::nanos(t_s));
        self.latest_world = Some((msg, topics::nanos(t_s)));
        self.count("/world");
    }

    /// `/map`, only when the map differs from the last one sent.
    pub fn map(&mut self, t_s: f32, grid: &Grid400) {
        let cells = topics::grid_bytes(grid);
        if cells == self.last_map {
            return;
        }
        self.last_map.clone_from(&cells);
        let msg = topics::grid_message(t_s, grid, cells);
        self.channels.map.log_with_time(&msg, topics::nanos(t_s));
        self.latest_map = Some((msg, topics::nanos(t_s)));
        self.count("/map");
    }

    /// `/plan` and `/prefix` (empty slices clear them).
    pub fn plan(&mut self, t_s: f32, path: &[PointM], prefix: &[PointM]) {
        self.path(t_s, PathKind::Plan, path);
        self.path(t_s, PathKind::Prefix, prefix);
    }

    /// `/plan` or `/prefix` alone.
    pub fn path(&mut self, t_s: f32, kind: PathKind, points: &[PointM]) {
        let t = topics::nanos(t_s);
        let msg = topics::path_update(t_s, kind, points);
        let (channel, latest, topic) = match kind {
            PathKind::Plan => (&self.channels.plan, &mut self.latest_plan, "/plan"),
            PathKind::Prefix => (&self.channels.prefix, &mut self.latest_prefix, "/prefix"),
        };
        channel.log_with_time(&msg, t);
        *latest = Some((msg, t));
        self.count(topic);
    }

    /// `/tf` and `/pose`.
    pub fn pose(&mut self, t_s: f32, pose: &Pose) {
        let t = topics::nanos(t_s);
        self.channels
            .tf
            .log_with_time(&topics::transform(t_s, pose), t);
        self.channels
            .pose
            .log_with_time(&topics::pose_in_frame(t_s, pose), t);
        self.count("/tf");
        self.count("/pose");
    }

    /// `/control`.
    pub fn control(&mut self, t_s: f32, sample: &ControlSample) {
        self.channels
            .control
            .log_with_time(&topics::control_message(t_s, sample), topics::nanos(t_s));
        self.count("/control");
    }

    /// `/sonar`: the hits of one sweep.
    pub fn sonar(&mut self, t_s: f32, hits: &[PointM]) {
        self.channels
            .sonar
            .log_with_time(&topics::hits_cloud(t_s, hits), topics::nanos(t_s));
        self.count("/sonar");
    }

    /// `/band`: the band a sweep covers.
    pub fn band(&mut self, t_s: f32, pose: &Pose, half_angle_rad: f32, range_m: f32) {
        self.channels.band.log_with_time(
            &topics::band_update(t_s, pose, half_angle_rad, range_m),
            topics::nanos(t_s),
        );
        self.count("/band");
    }

    /// `/status`.
    pub fn status(&mut self, message: StatusMessage) {
        let t = topics::nanos(message.t_s);
        self.channels.status.log_with_time(&message, t);
        self.latest_status = Some((message, t));
        self.count("/status");
    }

    /// Finish the MCAP file (its summary and index) and stop the live server.
    pub fn close(self) -> Result<RecordSummary> {
        if let Some(server) = self.server {
            server.stop().wait_blocking();
        }
        let file = match self.mcap {
            Some((path, handle)) => {
                let writer = handle
                    .close()
                    .map_err(|e| anyhow!("--record {}: {e}", path.display()))?;
                let file = writer
                    .into_inner()
                    .map_err(|e| anyhow!("--record {}: {}", path.display(), e.error()))?;
                file.sync_all()
                    .with_context(|| format!("--record {}: cannot write", path.display()))?;
                let bytes = std::fs::metadata(&path).map_or(0, |m| m.len());
                Some((path, bytes))
            }
            None => None,
        };
        Ok(RecordSummary {
            file,
            counts: self.counts,
        })
    }
}

fn resend<T: Encode>(
    channel: &Channel<T>,
    latest: &Latest<T>,
    to: Option<SinkId>,
    meta: impl Fn(u64) -> PartialMetadata,
) {
    if let Some((message, t)) = latest {
        channel.log_with_meta_to_sink(message, meta(*t), to);
    }
}
