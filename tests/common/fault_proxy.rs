//! A bad line between the host and a device, for the link-fault tests: bytes are dropped,
//! duplicated, bit-flipped and delayed, both ways, at configurable rates, from a seeded
//! generator (a failing run repeats with its seed).
//!
//! - [`FaultyIo`] wraps an in-process byte stream (`--remote sim`'s [`SimLink`]) for
//!   [`Remote::over`].
//! - [`FaultProxy`] is a TCP proxy in front of a device's stream (the firmware under QEMU):
//!   `twil … --remote tcp:ADDR` connects to it, once or many times in turn.
//!
//! [`SimLink`]: twil_host::device_sim::SimLink
//! [`Remote::over`]: twil_host::remote::Remote::over
#![allow(dead_code)]

use std::io::{Read, Write};
use std::net::{TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// Per-byte probabilities.
#[derive(Clone, Copy, Debug)]
pub struct Faults {
    /// One random bit flipped.
    pub corrupt: f64,
    /// The byte is lost.
    pub drop: f64,
    /// The byte is sent twice.
    pub duplicate: f64,
    /// The line stalls 1–20 ms before the byte (no damage).
    pub delay: f64,
    /// Seed of the generator.
    pub seed: u64,
}

impl Faults {
    /// `rate` of the bytes damaged: half flipped, a quarter lost, a quarter doubled; and as
    /// a tenth as many delayed.
    pub fn damaging(rate: f64, seed: u64) -> Self {
        Self {
            corrupt: rate / 2.0,
            drop: rate / 4.0,
            duplicate: rate / 4.0,
            delay: rate / 10.0,
            seed,
        }
    }
}

/// Bytes seen and damaged, both directions together.
#[derive(Default, Debug)]
pub struct Counts {
    pub bytes: AtomicU64,
    pub damaged: AtomicU64,
}

/// One direction of a bad line.
pub struct Line {
    faults: Faults,
    state: u64,
    counts: Arc<Counts>,
}

impl Line {
    pub fn new(faults: Faults, stream: u64, counts: Arc<Counts>) -> Self {
        Self {
            faults,
            state: faults.seed ^ stream.wrapping_mul(0x9e37_79b9_7f4a_7c15),
            counts,
        }
    }

    /// splitmix64: uniform in [0, 1).
    fn next(&mut self) -> f64 {
        self.state = self.state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }

    /// What arrives for `input`, and how long the line stalls before it.
    pub fn pass(&mut self, input: &[u8]) -> (Vec<u8>, Duration) {
        let f = self.faults;
        let mut out = Vec::with_capacity(input.len() + 4);
        let mut stall = Duration::ZERO;
        for &b in input {
            if self.next() < f.delay {
                stall += Duration::from_millis(1 + (self.next() * 20.0) as u64);
            }
            let r = self.next();
            let damaged = if r < f.corrupt {
                out.push(b ^ (1 << (self.next() * 8.0) as u32));
                true
            } else if r < f.corrupt + f.drop {
                true
            } else if r < f.corrupt + f.drop + f.duplicate {
                out.push(b);
                out.push(b);
                true
            } else {
                out.push(b);
                false
            };
            self.counts.bytes.fetch_add(1, Ordering::Relaxed);
            if damaged {
                self.counts.damaged.fetch_add(1, Ordering::Relaxed);
            }
        }
        (out, stall)
    }
}

/// An in-process byte stream behind a bad line.
pub struct FaultyIo<T> {
    inner: T,
    up: Line,
    down: Line,
    pub counts: Arc<Counts>,
}

impl<T> FaultyIo<T> {
    pub fn new(inner: T, faults: Faults) -> Self {
        let counts = Arc::new(Counts::default());
        Self {
            inner,
            up: Line::new(faults, 1, counts.clone()),
            down: Line::new(faults, 2, counts.clone()),
            counts,
        }
    }
}

impl<T: Write> Write for FaultyIo<T> {
    fn write(&mut self, bytes: &[u8]) -> std::io::Result<usize> {
        let (out, stall) = self.up.pass(bytes);
        std::thread::sleep(stall);
        self.inner.write_all(&out)?;
        Ok(bytes.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

impl<T: Read> Read for FaultyIo<T> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        // Read at most half a buffer: a duplicated byte makes the output longer.
        let half = (buf.len() / 2).max(1);
        let mut raw = vec![0u8; half];
        loop {
            let n = self.inner.read(&mut raw)?;
            if n == 0 {
                return Ok(0);
            }
            let (out, stall) = self.down.pass(&raw[..n]);
            std::thread::sleep(stall);
            if out.is_empty() {
                continue; // every byte dropped: read on
            }
            let m = out.len().min(buf.len());
            buf[..m].copy_from_slice(&out[..m]);
            return Ok(m);
        }
    }
}

/// What one forwarding thread of a [`FaultProxy`] is doing, and what it has moved: when a
/// test through the proxy fails, [`FaultProxy::report`] tells a silent device from a stuck or
/// ended thread.
#[derive(Default, Debug)]
pub struct Traffic {
    /// Bytes read from the source.
    bytes: AtomicU64,
    /// Milliseconds from the proxy's start to the last read that brought bytes.
    last_ms: AtomicU64,
    /// One of [`Traffic::STATES`].
    state: AtomicU64,
}

impl Traffic {
    const STATES: [&'static str; 6] = [
        "reading",
        "stalling (a delay fault)",
        "writing",
        "ended: the source closed",
        "ended: a read failed",
        "ended: a write failed",
    ];
    const READING: u64 = 0;
    const STALLING: u64 = 1;
    const WRITING: u64 = 2;
    const SOURCE_CLOSED: u64 = 3;
    const READ_FAILED: u64 = 4;
    const WRITE_FAILED: u64 = 5;

    fn set(&self, state: u64) {
        self.state.store(state, Ordering::Relaxed);
    }

    fn read(&self, n: usize, since: std::time::Instant) {
        self.bytes.fetch_add(n as u64, Ordering::Relaxed);
        self.last_ms
            .store(since.elapsed().as_millis() as u64, Ordering::Relaxed);
    }

    fn describe(&self, since: std::time::Instant) -> String {
        let state = self.state.load(Ordering::Relaxed) as usize;
        let idle_ms = (since.elapsed().as_millis() as u64)
            .saturating_sub(self.last_ms.load(Ordering::Relaxed));
        format!(
            "{} bytes, last read {idle_ms} ms ago, {}",
            self.bytes.load(Ordering::Relaxed),
            Self::STATES.get(state).unwrap_or(&"?")
        )
    }
}

/// A TCP proxy on 127.0.0.1 in front of `device`, damaging bytes both ways. Host connections
/// are served one at a time, in turn; the device's stream stays open between them.
pub struct FaultProxy {
    /// `HOST:PORT` to connect to (`--remote tcp:` + this).
    pub addr: String,
    pub counts: Arc<Counts>,
    stop: Arc<AtomicBool>,
    started: std::time::Instant,
    down: Arc<Traffic>,
    up: Arc<Traffic>,
}

/// One read's bytes through a direction of the proxy: counted, damaged and delayed by the
/// line, then handed to `write` (each state shown in `traffic` for a failure's report).
fn pass_on(
    traffic: &Traffic,
    line: &mut Line,
    bytes: &[u8],
    started: std::time::Instant,
    write: impl FnOnce(&[u8]) -> std::io::Result<()>,
) -> std::io::Result<()> {
    traffic.read(bytes.len(), started);
    let (out, stall) = line.pass(bytes);
    traffic.set(Traffic::STALLING);
    std::thread::sleep(stall);
    traffic.set(Traffic::WRITING);
    write(&out)
}

impl FaultProxy {
    pub fn start(device: TcpStream, faults: Faults) -> std::io::Result<Self> {
        let listener = TcpListener::bind("127.0.0.1:0")?;
        let addr = listener.local_addr()?.to_string();
        let counts = Arc::new(Counts::default());
        let stop = Arc::new(AtomicBool::new(false));
        let host: Arc<Mutex<Option<TcpStream>>> = Arc::new(Mutex::new(None));
        let started = std::time::Instant::now();
        let (down, up) = (Arc::new(Traffic::default()), Arc::new(Traffic::default()));
        device.set_read_timeout(Some(Duration::from_millis(50)))?;
        // Device -> host.
        {
            let mut device = device.try_clone()?;
            let host = host.clone();
            let stop = stop.clone();
            let traffic = down.clone();
            let mut line = Line::new(faults, 2, counts.clone());
            std::thread::spawn(move || {
                let mut buf = [0u8; 256];
                while !stop.load(Ordering::Relaxed) {
                    traffic.set(Traffic::READING);
                    match device.read(&mut buf) {
                        Ok(0) => return traffic.set(Traffic::SOURCE_CLOSED),
                        Ok(n) => {
                            // No host connected, or its write failed (it went): the device's
                            // bytes are dropped, as a serial line drops them.
                            let write = |out: &[u8]| match host.lock().unwrap().as_mut() {
                                Some(h) => h.write_all(out),
                                None => Ok(()),
                            };
                            let _ = pass_on(&traffic, &mut line, &buf[..n], started, write);
                        }
                        Err(e)
                            if matches!(
                                e.kind(),
                                std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                            ) => {}
                        Err(_) => return traffic.set(Traffic::READ_FAILED),
                    }
                }
            });
        }
        // Host connections, in turn -> device.
        {
            let stop = stop.clone();
            let traffic = up.clone();
            let mut line = Line::new(faults, 1, counts.clone());
            let mut device = device;
            std::thread::spawn(move || {
                for conn in listener.incoming() {
                    if stop.load(Ordering::Relaxed) {
                        return;
                    }
                    let Ok(mut conn) = conn else { continue };
                    let _ = conn.set_nodelay(true);
                    let Ok(writer) = conn.try_clone() else {
                        continue;
                    };
                    *host.lock().unwrap() = Some(writer);
                    let mut buf = [0u8; 256];
                    loop {
                        traffic.set(Traffic::READING);
                        match conn.read(&mut buf) {
                            Ok(0) | Err(_) => break,
                            Ok(n) => {
                                let write = |out: &[u8]| device.write_all(out);
                                if pass_on(&traffic, &mut line, &buf[..n], started, write).is_err()
                                {
                                    return traffic.set(Traffic::WRITE_FAILED);
                                }
                            }
                        }
                    }
                    *host.lock().unwrap() = None;
                }
            });
        }
        Ok(Self {
            addr,
            counts,
            stop,
            started,
            down,
            up,
        })
    }

    /// Each direction's traffic and what its thread is doing now, for a failure's message.
    pub fn report(&self) -> String {
        format!(
            "proxy: device -> host {}; host -> device {}",
            self.down.describe(self.started),
            self.up.describe(self.started)
        )
    }

    /// Share of the bytes damaged so far.
    pub fn damaged_share(&self) -> f64 {
        let bytes = self.counts.bytes.load(Ordering::Relaxed).max(1);
        self.counts.damaged.load(Ordering::Relaxed) as f64 / bytes as f64
    }
}

impl Drop for FaultProxy {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        // Wake the accept loop.
        let _ = TcpStream::connect(&self.addr);
    }
}
