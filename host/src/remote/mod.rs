//! The host end of the link: open a device (`--remote qemu`, `--remote tcp:HOST:PORT`,
//! `--remote /dev/ttyUSB0`, or the in-process `--remote sim`), send requests, collect replies.
//!
//! The wire format and the messages are `twil_core::link`'s; this module only moves bytes.
//! [`Remote::request`] sends one request and waits for the reply with the same sequence number,
//! skipping telemetry and stale replies. `--remote qemu` starts `qemu-system-arm` with the QEMU
//! build of the firmware ([`Qemu`]); the process is killed when the [`Remote`] is dropped, on
//! success and on error alike.

use std::io::{Read, Write};
use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::str::FromStr;
use std::time::{Duration, Instant};

use anyhow::{anyhow, bail, Context, Result};
use twil_core::geom::PointM;
use twil_core::link::frame::{self, FrameDecoder, FrameFault, MAX_FRAME_BYTES};
use twil_core::link::{
    DeviceFrame, DeviceInfo, MapParams, PlanSummary, Reply, Request, RequestFrame, Telemetry,
    MAP_CHUNK_WORDS, OBSTACLE_CHUNK_VERTICES, PROTOCOL_VERSION,
};
use twil_core::plan::PlannerKind;
use twil_core::world::Obstacles;

/// Where the firmware is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum RemoteSpec {
    /// Start QEMU with the QEMU build of the firmware.
    Qemu,
    /// A TCP socket (`tcp:HOST:PORT`), e.g. `cargo xtask qemu`'s.
    Tcp(String),
    /// A serial port at 115200 8N1 (any other text: `/dev/ttyUSB0`, `COM3`).
    Serial(String),
    /// The mission device in this process, with a simulated robot (`--remote sim`, see
    /// [`crate::device_sim`]): as fast as it can (0), or `sim:N`, N times real time.
    Sim(u32),
}

impl FromStr for RemoteSpec {
    type Err = anyhow::Error;

    fn from_str(s: &str) -> Result<Self> {
        if s == "qemu" {
            Ok(RemoteSpec::Qemu)
        } else if s == "sim" {
            Ok(RemoteSpec::Sim(0))
        } else if let Some(n) = s.strip_prefix("sim:") {
            match n.parse::<u32>() {
                Ok(n) if n > 0 => Ok(RemoteSpec::Sim(n)),
                _ => bail!("`--remote {s}`: expected sim or sim:N, N (times real time) from 1"),
            }
        } else if let Some(addr) = s.strip_prefix("tcp:") {
            if !addr.contains(':') {
                bail!("`--remote {s}`: expected tcp:HOST:PORT");
            }
            Ok(RemoteSpec::Tcp(addr.to_string()))
        } else if s.is_empty() {
            bail!("`--remote` needs `qemu`, `sim`, `tcp:HOST:PORT` or a serial port path")
        } else if looks_like_a_port(s) {
            Ok(RemoteSpec::Serial(s.to_string()))
        } else {
            // Not a path either: most likely a misspelt keyword.
            let guess = ["qemu", "sim", "tcp:"]
                .into_iter()
                .map(|k| (strsim::damerau_levenshtein(&s.to_lowercase(), k), k))
                .min()
                .filter(|(d, _)| *d <= 2)
                .map(|(_, k)| format!("; did you mean `{k}`?"))
                .unwrap_or_default();
            bail!(
                "`--remote {s}`: expected `qemu`, `sim`, `sim:N`, `tcp:HOST:PORT` or a serial \
                 port (a path such as /dev/ttyACM0, or COM3){guess}"
            )
        }
    }
}

/// A serial port's name: a path (`/dev/ttyACM0`, `./pty`) or a Windows `COMn`.
fn looks_like_a_port(s: &str) -> bool {
    let com = s
        .strip_prefix("COM")
        .or_else(|| s.strip_prefix("com"))
        .is_some_and(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()));
    s.contains('/') || s.contains('\\') || com
}

/// How long to wait for a reply (QEMU plans in milliseconds; a board at 115200 baud moves a
/// frame in at most 45 ms).
pub const REPLY_TIMEOUT: Duration = Duration::from_secs(20);

/// Silence after which a request is sent again. The longest legitimate wait: a request frame
/// and its reply frame at 115200 baud (2 x 512 bytes x 10 bits = 89 ms) plus the slowest
/// request (a plan within the 5 M-instruction budget: 30 ms at 168 MHz, 40 ms under QEMU at
/// `-icount shift=3`), about 130 ms; 500 ms leaves room for a loaded host running QEMU. A
/// retry that comes too early only costs a repeated reply.
pub const RETRY_AFTER: Duration = Duration::from_millis(500);

/// Longest silence between two sends of one request (the wait doubles from [`RETRY_AFTER`]).
pub const RETRY_AFTER_MAX: Duration = Duration::from_secs(2);

/// Sends of one request at most. A resend follows at once every damaged frame, so this is
/// high: with 1 % of bytes damaged a 270-byte reply (a path or map chunk) arrives whole with
/// probability 0.99^270 = 6.6 %, and 200 tries all fail with probability 0.934^200 < 1e-5.
pub const MAX_ATTEMPTS: u32 = 200;

trait Io: Read + Write + Send {}
impl<T: Read + Write + Send> Io for T {}

/// A path planned by the device.
#[derive(Clone, Debug, PartialEq)]
pub struct RemotePlan {
    /// The device's report (status, cost, instructions…).
    pub summary: PlanSummary,
    /// The path, metres.
    pub path: Vec<PointM>,
}

/// An open link to a device.
pub struct Remote {
    io: Box<dyn Io>,
    decoder: FrameDecoder,
    backlog: Vec<u8>,
    seq: u16,
    timeout: Duration,
    /// Telemetry received while waiting for replies.
    pub telemetry: Vec<Telemetry>,
    /// Error replies to damaged frames (no sequence number) seen while waiting.
    pub unmatched_errors: Vec<Reply>,
    retries: u32,
    damaged_frames: u32,
    /// When the last frame from the device, whole or damaged, arrived.
    last_frame_at: Option<Instant>,
    /// Kept last so that the socket closes before QEMU is killed.
    qemu: Option<Qemu>,
}

impl Remote {
    /// Open the link and do the version handshake; a QEMU it starts counts instructions
    /// (`-icount shift=0`).
    pub fn connect(spec: &RemoteSpec) -> Result<(Self, DeviceInfo)> {
        Self::connect_paced(spec, 0)
    }

    /// [`Remote::connect`]; a QEMU it starts runs at `-icount shift=SHIFT` (missions: 3).
    pub fn connect_paced(spec: &RemoteSpec, shift: u8) -> Result<(Self, DeviceInfo)> {
        let mut remote = Self::open_paced(spec, shift)?;
        let info = remote.hello()?;
        Ok((remote, info))
    }

    /// Open the link without any exchange; a QEMU it starts counts instructions
    /// (`-icount shift=0`).
    pub fn open(spec: &RemoteSpec) -> Result<Self> {
        Self::open_paced(spec, 0)
    }

    /// [`Remote::open`]; a QEMU it starts runs at `-icount shift=SHIFT`.
    pub fn open_paced(spec: &RemoteSpec, shift: u8) -> Result<Self> {
        let (io, qemu): (Box<dyn Io>, Option<Qemu>) = match spec {
            RemoteSpec::Qemu => {
                let (qemu, stream) = Qemu::start_paced(&Qemu::elf_path()?, shift)?;
                stream.set_read_timeout(Some(Duration::from_millis(200)))?;
                stream.set_nodelay(true)?;
                (Box::new(stream), Some(qemu))
            }
            RemoteSpec::Tcp(addr) => {
                let stream = connect_tcp(addr, Duration::from_secs(5))?;
                stream.set_read_timeout(Some(Duration::from_millis(200)))?;
                stream.set_nodelay(true)?;
                (Box::new(stream), None)
            }
            RemoteSpec::Serial(path) => {
                let port = serialport::new(path, 115_200)
                    .data_bits(serialport::DataBits::Eight)
                    .parity(serialport::Parity::None)
                    .stop_bits(serialport::StopBits::One)
                    .timeout(Duration::from_millis(200))
                    .open()
                    .with_context(|| format!("cannot open serial port {path}"))?;
                (Box::new(port), None)
            }
            RemoteSpec::Sim(pace) => (Box::new(crate::device_sim::SimLink::spawn(*pace)?), None),
        };
        let started_qemu = qemu.is_some();
        let mut remote = Self::with_io(io, qemu);
        if started_qemu {
            // QEMU's USART drops bytes until the firmware has enabled it: wait for the boot
            // report before sending anything.
            remote.wait_for_boot(Duration::from_secs(15))?;
        }
        Ok(remote)
    }

    /// Wait for [`Telemetry::Boot`] (sent once by the firmware after reset).
    pub fn wait_for_boot(&mut self, patience: Duration) -> Result<()> {
        let deadline = Instant::now() + patience;
        loop {
            match self.next_frame(deadline) {
                Ok(Ok(DeviceFrame::Telemetry(t))) => {
                    let boot = matches!(t, Telemetry::Boot { .. });
                    self.telemetry.push(t);
                    if boot {
                        return Ok(());
                    }
                }
                Ok(_) => {}
                Err(e) => {
                    return Err(e).context("the firmware did not report its boot");
                }
            }
        }
    }

    /// A link over any byte stream (e.g. an in-process device in tests). Reads should time out
    /// (`WouldBlock` / `TimedOut`) rather than block forever.
    pub fn over(io: impl Read + Write + Send + 'static) -> Self {
        Self::with_io(Box::new(io), None)
    }

    fn with_io(io: Box<dyn Io>, qemu: Option<Qemu>) -> Self {
        Self {
            io,
            decoder: FrameDecoder::new(),
            backlog: Vec::new(),
            seq: 0,
            timeout: REPLY_TIMEOUT,
            telemetry: Vec::new(),
            unmatched_errors: Vec::new(),
            retries: 0,
            damaged_frames: 0,
            last_frame_at: None,
            qemu,
        }
    }

    /// How long [`Remote::request`] waits for a reply (default [`REPLY_TIMEOUT`]).
    pub fn set_timeout(&mut self, timeout: Duration) {
        self.timeout = timeout;
    }

    /// The QEMU process behind this link, if `--remote qemu`.
    pub fn qemu(&self) -> Option<&Qemu> {
        self.qemu.as_ref()
    }

    /// Version handshake: the device's description, or an error if the versions differ. Sent
    /// up to 3 times, 2 s apart (a board may still be starting when the port opens).
    pub fn hello(&mut self) -> Result<DeviceInfo> {
        let timeout = std::mem::replace(&mut self.timeout, Duration::from_secs(2));
        let mut result = Err(anyhow!("no attempt"));
        for _ in 0..3 {
            result = self.call(Request::Hello {
                protocol_version: PROTOCOL_VERSION,
            });
            if let Err(e) = &result {
                if e.to_string().starts_with("no reply") {
                    continue;
                }
            }
            break;
        }
        self.timeout = timeout;
        match result.context("version handshake")? {
            Reply::Hello(info) => Ok(info),
            other => bail!("unexpected reply to Hello: {other:?}"),
        }
    }

    /// Round trip of one ping.
    pub fn ping(&mut self, nonce: u32) -> Result<Duration> {
        let start = Instant::now();
        match self.call(Request::Ping { nonce })? {
            Reply::Pong { nonce: n } if n == nonce => Ok(start.elapsed()),
            other => bail!("unexpected reply to Ping: {other:?}"),
        }
    }

    /// Send raw bytes (tests use this to send damaged frames).
    pub fn send_raw(&mut self, bytes: &[u8]) -> Result<()> {
        self.io.write_all(bytes).context("writing to the device")?;
        self.io.flush().context("writing to the device")?;
        Ok(())
    }

    /// Send one request and return the device's reply to it (an error reply is returned as
    /// `Reply::Error`, not as `Err`). `Err` means the link failed: no reply within the timeout
    /// ([`Remote::set_timeout`]) after up to [`MAX_ATTEMPTS`] sends, or the link closed.
    ///
    /// The request is sent again under the same sequence number (the device answers a repeat
    /// from its replay cache and never executes it twice, see `twil_core::link::replay`) at
    /// once when the device reports a frame it could not read or a frame from the device
    /// arrives damaged (it may have been the reply), and after [`RETRY_AFTER`] of silence
    /// (doubling up to [`RETRY_AFTER_MAX`]). Each resend counts in [`Remote::retries`].
    pub fn request(&mut self, request: Request) -> Result<Reply> {
        self.seq = self.seq.wrapping_add(1);
        let seq = self.seq;
        let mut out = [0u8; MAX_FRAME_BYTES];
        let bytes = frame::encode(&RequestFrame { seq, request }, &mut out)
            .context("request does not fit a frame")?;
        // A leading 0x00 ends whatever partial frame the device may hold.
        let mut wire = Vec::with_capacity(bytes.len() + 1);
        wire.push(0);
        wire.extend_from_slice(bytes);
        let debug = std::env::var_os("TWIL_LINK_DEBUG").is_some();
        if debug {
            eprintln!("twil: link: -> seq {seq} ({} bytes)", wire.len());
        }
        self.send_raw(&wire)?;
        let deadline = Instant::now() + self.timeout;
        let mut attempts = 1u32;
        let mut quiet = RETRY_AFTER;
        let mut resend_at = Instant::now() + quiet;
        let mut last_error: Option<Reply> = None;
        loop {
            let now = Instant::now();
            if now >= resend_at && now < deadline {
                if attempts >= MAX_ATTEMPTS {
                    return Err(self.gave_up(seq, attempts, last_error.as_ref()));
                }
                attempts += 1;
                self.retries = self.retries.saturating_add(1);
                if debug {
                    eprintln!("twil: link: -> seq {seq} again (attempt {attempts})");
                }
                self.send_raw(&wire)?;
                quiet = (quiet * 2).min(RETRY_AFTER_MAX);
                resend_at = Instant::now() + quiet;
            }
            let frame = match self.next_frame(resend_at.min(deadline)) {
                Ok(frame) => frame,
                Err(_) if Instant::now() < deadline => continue, // quiet: resend
                Err(_) => return Err(self.gave_up(seq, attempts, last_error.as_ref())),
            };
            match frame {
                Ok(DeviceFrame::Reply {
                    seq: Some(s),
                    reply,
                }) if s == seq => return Ok(reply),
                Ok(DeviceFrame::Reply { seq: None, reply }) => {
                    // The device could not read a frame: perhaps this request's. Send it again
                    // now (a repeat is answered, not executed twice).
                    self.unmatched_errors.push(reply.clone());
                    last_error = Some(reply);
                    resend_at = Instant::now();
                }
                Ok(DeviceFrame::Reply { .. }) => {} // a stale reply to an earlier request
                Ok(DeviceFrame::Telemetry(t)) => self.telemetry.push(t),
                Err(fault) => {
                    // Perhaps the reply: ask again now rather than wait.
                    if debug {
                        eprintln!("twil: link: dropped a damaged frame: {fault:?}");
                    }
                    resend_at = Instant::now();
                }
            }
        }
    }

    fn gave_up(&self, seq: u16, attempts: u32, last_error: Option<&Reply>) -> anyhow::Error {
        let last = match last_error {
            Some(Reply::Error(last)) => format!("; the device last reported: {last}"),
            _ => String::new(),
        };
        anyhow!(
            "no reply from the device within {} s (request {seq} sent {attempts} times){last}",
            self.timeout.as_secs_f32()
        )
    }

    /// Requests sent again so far (see [`Remote::request`]).
    pub fn retries(&self) -> u32 {
        self.retries
    }

    /// When the last frame from the device arrived, whole or damaged (a damaged one still
    /// says the device is talking), by any call: [`Remote::request`] reads telemetry too.
    pub fn last_frame_at(&self) -> Option<Instant> {
        self.last_frame_at
    }

    /// Damaged frames from the device seen so far (dropped).
    pub fn damaged_frames(&self) -> u32 {
        self.damaged_frames
    }

    /// Like [`Remote::request`], but an error reply becomes `Err` with the device's message.
    pub fn call(&mut self, request: Request) -> Result<Reply> {
        match self.request(request)? {
            Reply::Error(e) => Err(anyhow!("{e}")),
            reply => Ok(reply),
        }
    }

    /// The next frame from the device (a decoded frame or a fault), waiting until `deadline`.
    pub fn next_frame(&mut self, deadline: Instant) -> Result<Result<DeviceFrame, FrameFault>> {
        let mut buf = [0u8; 512];
        loop {
            if !self.backlog.is_empty() {
                let backlog = std::mem::take(&mut self.backlog);
                let (got, rest) = self.decoder.feed::<DeviceFrame>(&backlog);
                self.backlog = rest.to_vec();
                if let Some(got) = got {
                    self.last_frame_at = Some(Instant::now());
                    if got.is_err() {
                        self.damaged_frames = self.damaged_frames.saturating_add(1);
                    }
                    return Ok(got);
                }
            }
            if Instant::now() > deadline {
                bail!(
                    "no reply from the device within {} s",
                    self.timeout.as_secs_f32()
                );
            }
            match self.io.read(&mut buf) {
                Ok(0) => bail!("the device closed the link"),
                Ok(n) => {
                    if std::env::var_os("TWIL_LINK_DEBUG").is_some() {
                        eprintln!("twil: link: <- {n} bytes");
                    }
                    self.backlog.extend_from_slice(&buf[..n])
                }
                Err(e)
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock
                            | std::io::ErrorKind::TimedOut
                            | std::io::ErrorKind::Interrupted
                    ) => {}
                Err(e) => return Err(e).context("reading from the device"),
            }
        }
    }

    /// Set the map and radius, forget old obstacles, upload `obstacles` in chunks.
    pub fn upload_world(&mut self, params: MapParams, obstacles: &Obstacles) -> Result<()> {
        self.call(Request::ClearMap)?;
        self.call(Request::SetParams(params))?;
        for (i, polygon) in obstacles.iter().enumerate() {
            self.upload_polygon(polygon)
                .with_context(|| format!("uploading obstacle {}", i + 1))?;
        }
        Ok(())
    }

    /// Upload one polygon in chunks of [`OBSTACLE_CHUNK_VERTICES`].
    pub fn upload_polygon(&mut self, polygon: &[PointM]) -> Result<()> {
        self.upload_chunks(polygon, false)
    }

    /// Upload one polygon of the real world of a simulated device (`WorldChunk`), in chunks of
    /// [`OBSTACLE_CHUNK_VERTICES`].
    pub fn upload_world_polygon(&mut self, polygon: &[PointM]) -> Result<()> {
        self.upload_chunks(polygon, true)
    }

    fn upload_chunks(&mut self, polygon: &[PointM], real_world: bool) -> Result<()> {
        let chunks = polygon.chunks(OBSTACLE_CHUNK_VERTICES);
        let n = chunks.len();
        for (i, chunk) in chunks.enumerate() {
            let first_vertex = u16::try_from(i * OBSTACLE_CHUNK_VERTICES)
                .map_err(|_| anyhow!("a polygon of {} vertices is too long", polygon.len()))?;
            let vertices = heapless::Vec::from_slice(chunk)
                .map_err(|_| anyhow!("chunk larger than its capacity"))?;
            let last = i + 1 == n;
            let request = if real_world {
                Request::WorldChunk {
                    first_vertex,
                    vertices,
                    last,
                }
            } else {
                Request::ObstacleChunk {
                    first_vertex,
                    vertices,
                    last,
                }
            };
            self.call(request)?;
        }
        Ok(())
    }

    /// Overwrite the whole map with packed words (row-major, 32 cells per word).
    pub fn write_map(&mut self, words: &[u32]) -> Result<()> {
        for (i, chunk) in words.chunks(MAP_CHUNK_WORDS).enumerate() {
            self.call(Request::WriteMap {
                offset_words: (i * MAP_CHUNK_WORDS) as u32,
                words: heapless::Vec::from_slice(chunk)
                    .map_err(|_| anyhow!("chunk larger than its capacity"))?,
            })?;
        }
        Ok(())
    }

    /// Read the whole map: (width, height, packed words).
    pub fn read_map(&mut self) -> Result<(u16, u16, Vec<u32>)> {
        let mut words = Vec::new();
        loop {
            match self.call(Request::ReadMap {
                offset_words: words.len() as u32,
            })? {
                Reply::MapChunk {
                    total_words,
                    width_cells,
                    height_cells,
                    words: chunk,
                    ..
                } => {
                    words.extend_from_slice(&chunk);
                    if words.len() >= total_words as usize || chunk.is_empty() {
                        return Ok((width_cells, height_cells, words));
                    }
                }
                other => bail!("unexpected reply to ReadMap: {other:?}"),
            }
        }
    }

    /// Plan on the device and read the whole path back.
    pub fn plan(&mut self, kind: PlannerKind, start: PointM, goal: PointM) -> Result<RemotePlan> {
        let summary = match self.call(Request::Plan { kind, start, goal })? {
            Reply::Plan(summary) => summary,
            other => bail!("unexpected reply to Plan: {other:?}"),
        };
        let mut path = Vec::with_capacity(summary.points as usize);
        while path.len() < summary.points as usize {
            match self.call(Request::ReadPath {
                offset: path.len() as u16,
            })? {
                Reply::PathChunk { points, .. } if !points.is_empty() => {
                    path.extend_from_slice(&points)
                }
                other => bail!("unexpected reply to ReadPath: {other:?}"),
            }
        }
        Ok(RemotePlan { summary, path })
    }
}

fn connect_tcp(addr: &str, patience: Duration) -> Result<TcpStream> {
    let deadline = Instant::now() + patience;
    loop {
        match TcpStream::connect(addr) {
            Ok(s) => return Ok(s),
            Err(e) if Instant::now() < deadline => {
                let _ = e;
                std::thread::sleep(Duration::from_millis(100));
            }
            Err(e) => return Err(e).with_context(|| format!("cannot connect to {addr}")),
        }
    }
}

/// A `qemu-system-arm` process running the firmware (`netduinoplus2`, USART1 on a TCP socket,
/// `-icount shift=0` so that one instruction is 1 ns of virtual time). Killed on drop.
pub struct Qemu {
    child: Child,
    /// The TCP port QEMU's USART1 is connected through.
    pub port: u16,
}

pub use crate::qemu_cmd::QEMU_ELF_NAME;

impl Qemu {
    /// Where the QEMU ELF is: `$TWIL_QEMU_ELF`, else
    /// `<target dir>/thumbv7em-none-eabihf/firmware/twil-firmware-qemu` (built by
    /// `cargo xtask firmware`).
    pub fn elf_path() -> Result<PathBuf> {
        if let Some(p) = std::env::var_os("TWIL_QEMU_ELF") {
            let p = PathBuf::from(p);
            if p.is_file() {
                return Ok(p);
            }
            bail!("TWIL_QEMU_ELF={} does not exist", p.display());
        }
        let mut target_dirs = Vec::new();
        if let Some(d) = std::env::var_os("CARGO_TARGET_DIR") {
            target_dirs.push(PathBuf::from(d));
        }
        // The running binary is target/<profile>/twil or target/<profile>/deps/test-….
        if let Ok(exe) = std::env::current_exe() {
            target_dirs.extend(exe.ancestors().skip(2).take(2).map(Path::to_path_buf));
        }
        target_dirs.push(Path::new(env!("CARGO_MANIFEST_DIR")).join("../target"));
        let candidates: Vec<PathBuf> = target_dirs
            .iter()
            .map(|d| {
                d.join("thumbv7em-none-eabihf")
                    .join("firmware")
                    .join(QEMU_ELF_NAME)
            })
            .collect();
        candidates
            .iter()
            .find(|p| p.is_file())
            .cloned()
            .ok_or_else(|| {
                anyhow!(
                "the QEMU firmware is not built (looked for {}): run `cargo xtask firmware` first",
                candidates
                    .first()
                    .map(|p| p.display().to_string())
                    .unwrap_or_default()
            )
            })
    }

    /// Start QEMU on `elf` and return it with the stream to its USART1. QEMU connects to a port
    /// this process listens on (port 0: the OS picks a free one, so parallel runs never clash).
    pub fn start(elf: &Path) -> Result<(Qemu, TcpStream)> {
        Self::start_paced(elf, 0)
    }

    /// [`Qemu::start`] at `-icount shift=SHIFT` (one instruction per 2^SHIFT ns); the log is
    /// kept in `$TWIL_QEMU_LOG` if set.
    pub fn start_paced(elf: &Path, shift: u8) -> Result<(Qemu, TcpStream)> {
        let log = std::env::var_os("TWIL_QEMU_LOG").map(PathBuf::from);
        Self::start_logged(elf, shift, log.as_deref())
    }

    /// [`Qemu::start_paced`] with the firmware's log (semihosting, defmt frames: `cargo xtask
    /// defmt-log FILE`) kept in `log`, and QEMU's own messages in `log` + `.stderr` (a fatal
    /// one, such as a core lockup, would otherwise be lost: nothing reads that pipe once QEMU
    /// has connected).
    pub fn start_logged(elf: &Path, shift: u8, log: Option<&Path>) -> Result<(Qemu, TcpStream)> {
        let listener =
            TcpListener::bind("127.0.0.1:0").context("cannot listen on a local TCP port")?;
        let port = listener.local_addr()?.port();
        let create = |path: &Path| {
            std::fs::File::create(path)
                .map(Stdio::from)
                .with_context(|| format!("cannot create {}", path.display()))
        };
        let (stdout, stderr) = match log {
            Some(path) => {
                let mut errors = path.as_os_str().to_owned();
                errors.push(".stderr");
                (create(path)?, create(Path::new(&errors))?)
            }
            None => (Stdio::null(), Stdio::piped()),
        };
        let child = Command::new("qemu-system-arm")
            .args(crate::qemu_cmd::qemu_args_paced(
                elf,
                &format!("tcp:127.0.0.1:{port},nodelay=on"),
                shift,
            ))
            .stdin(Stdio::null())
            .stdout(stdout)
            .stderr(stderr)
            .spawn()
            .map_err(|e| {
                if e.kind() == std::io::ErrorKind::NotFound {
                    anyhow!("qemu-system-arm is not installed (apt-get install qemu-system-arm, or run `cargo xtask test`, which installs it)")
                } else {
                    anyhow!("cannot start qemu-system-arm: {e}")
                }
            })?;
        let mut qemu = Qemu { child, port };
        listener.set_nonblocking(true)?;
        let deadline = Instant::now() + Duration::from_secs(15);
        let stream = loop {
            match listener.accept() {
                Ok((stream, _)) => break stream,
                Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {}
                Err(e) => return Err(e).context("waiting for QEMU to connect"),
            }
            if let Some(status) = qemu.child.try_wait()? {
                let mut err = String::new();
                if let Some(mut s) = qemu.child.stderr.take() {
                    let _ = s.read_to_string(&mut err);
                }
                bail!(
                    "qemu-system-arm exited ({status}) before connecting: {}",
                    err.trim()
                );
            }
            if Instant::now() > deadline {
                bail!("qemu-system-arm did not connect to port {port} within 15 s");
            }
            std::thread::sleep(Duration::from_millis(10));
        };
        stream.set_nonblocking(false)?;
        Ok((qemu, stream))
    }

    /// QEMU's exit status if it has exited (`None`: still running).
    pub fn exited(&mut self) -> Option<std::process::ExitStatus> {
        self.child.try_wait().ok().flatten()
    }
}

impl Drop for Qemu {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// `twil plan --remote DEVICE`: upload `world` to the device, let it plan the same request as
/// `local` (the host's outcome), and return the device's outcome. `extra` receives the JSON
/// fields `mcu_instructions`, `static_ram_bytes` and `matches_host`: the device's report
/// (status, expanded cells, cost, length) and path equal those of the same planner type run on
/// the host ([`twil_core::link::mcu::McuPlanner`]: the firmware's capacities; A*'s expanded
/// count depends on the open-list capacity, so the host tool's own larger planner may expand a
/// few cells more or less, for the same cost).
pub fn plan_on_device(
    device: &RemoteSpec,
    world: &crate::planning::World,
    local: &crate::planning::Outcome,
    extra: &mut serde_json::Map<String, serde_json::Value>,
) -> Result<crate::planning::Outcome> {
    let (mut remote, info) = Remote::connect(device)?;
    let geometry = *world.grid.geometry();
    if geometry.cell_count() as u64 > info.grid_capacity_cells as u64 {
        bail!(
            "the map has {}x{} cells but the device's grid holds {} cells",
            geometry.width(),
            geometry.height(),
            info.grid_capacity_cells
        );
    }
    let params = MapParams {
        width_cells: geometry.width(),
        height_cells: geometry.height(),
        resolution_m: geometry.resolution_m(),
        robot_radius_m: world.params.robot_radius_m,
    };
    remote
        .upload_world(params, &world.obstacles)
        .context("uploading the world to the device")?;
    if world.saved.is_some() {
        // A saved map has no polygons: send the host's map as it is.
        remote
            .write_map(world.grid.words())
            .context("uploading the saved map to the device")?;
    }
    let started = Instant::now();
    let planned = remote.plan(local.kind, world.params.start, world.params.goal)?;
    let elapsed_us = started.elapsed().as_micros() as u64;
    let s = planned.summary;
    let outcome = crate::planning::Outcome {
        kind: local.kind,
        report: twil_core::plan::PlanReport {
            status: s.status,
            expanded: s.expanded,
            cost: s.cost,
            length_m: s.length_m,
        },
        path: planned.path,
        elapsed_us,
        queue_peak: 0,
    };
    let reference = plan_like_the_mcu(world, local.kind)?;
    let matches = outcome.report == reference.report && outcome.path == reference.path;
    // Measured on the firmware only: the in-process device (`--remote sim`) counts nothing,
    // so its figures are absent (`null`), not 0.
    let measured = info.build != twil_core::link::Build::Host;
    let figure = |v: u64| {
        if measured {
            v.into()
        } else {
            serde_json::Value::Null
        }
    };
    extra.insert("mcu_instructions".into(), figure(s.mcu_instructions));
    extra.insert(
        "static_ram_bytes".into(),
        figure(info.static_ram_bytes.into()),
    );
    extra.insert("matches_host".into(), matches.into());
    Ok(outcome)
}

/// Run the firmware's planner type ([`twil_core::link::mcu::McuPlanner`]) on the host, on
/// `world`'s map: what the device must answer.
pub fn plan_like_the_mcu(
    world: &crate::planning::World,
    kind: PlannerKind,
) -> Result<crate::planning::Outcome> {
    let grid = &*world.grid;
    let (start, goal) = (world.params.start, world.params.goal);
    std::thread::scope(|scope| {
        std::thread::Builder::new()
            .name("mcu-planner".into())
            .stack_size(16 * 1024 * 1024)
            .spawn_scoped(scope, move || {
                let mut planner = Box::new(twil_core::link::mcu::McuPlanner::new());
                let mut path = twil_core::plan::PathM::new();
                let started = Instant::now();
                let report = planner
                    .plan(kind, grid, start, goal, &mut path)
                    .context("the firmware's planner on the host")?;
                Ok(crate::planning::Outcome {
                    kind,
                    report,
                    path: path.to_vec(),
                    elapsed_us: started.elapsed().as_micros() as u64,
                    queue_peak: 0,
                })
            })
            .context("cannot start the planner thread")?
            .join()
            .map_err(|_| anyhow!("the planner thread failed"))?
    })
}

mod params;
pub use params::SetOutcome;

#[cfg(test)]
mod tests;
