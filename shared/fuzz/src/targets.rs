//! Bodies of the fuzz targets: one function per decoder or parser of twil-core, each taking
//! arbitrary bytes. Each one panics (a finding) only when an invariant stated here fails;
//! beyond "no panic" they check what is cheap to check:
//!
//! - framed decoders: the same frames whatever the chunking of the stream, at most one result
//!   per `0x00`, and every decoded message re-encodes to a frame that decodes to the same bytes;
//! - message decoders: every decoded message fits a frame and re-encodes byte-stably;
//! - the devices (planning, mission): at most one reply per frame, every reply a valid frame, and a well-formed
//!   request frame answered by exactly one reply carrying its sequence number;
//! - text parsers: an error names a line of the text; a parsed file written back parses equal;
//!   a failing `.da` parse leaves the obstacles as they were.
//!
//! This file is compiled twice: as the `targets` module of the `twil-core-fuzz` crate
//! (cargo-fuzz, nightly) and by `shared/tests/fuzz_corpus.rs` through `#[path]` (stable replay
//! of the corpus and a short mutation run). It may use only `std`, `twil_core` and `postcard`.

use std::fmt::Write as _;
use std::string::String;
use std::vec::Vec;

use serde::{de::DeserializeOwned, Serialize};
use twil_core::cspace::{map::ConfigMap, rob::parse_rob, tra::Trajectory};
use twil_core::grid::words_for_cells;
use twil_core::link::frame::{self, FrameDecoder, FrameFault, MAX_FRAME_BYTES};
use twil_core::link::{
    Device, DeviceFrame, Reply, Request, RequestFrame, RobotDevice, RunState, Telemetry,
    WorldUpload,
};
use twil_core::mission::{Mission, Pilot};
use twil_core::plan::Planner;
use twil_core::world::{parse_da, parse_par, Obstacles, Params};

/// A target's body.
pub type Target = fn(&[u8]);

/// Every target, by the name of its cargo-fuzz binary and corpus directory.
pub const TARGETS: &[(&str, Target)] = &[
    ("frame_request", frame_request),
    ("frame_device", frame_device),
    ("messages", messages),
    ("device", device),
    ("robot_device", robot_device),
    ("da", da),
    ("par", par),
    ("rob", rob),
    ("map", map),
    ("tra", tra),
];

// ---------------------------------------------------------------------------------------------
// Link: frames and messages.

/// Decode a byte stream fed in chunks of `chunk` bytes; every result in order.
fn decode_stream<T: DeserializeOwned>(stream: &[u8], chunk: usize) -> Vec<Result<T, FrameFault>> {
    let mut decoder = FrameDecoder::new();
    let mut out = Vec::new();
    for piece in stream.chunks(chunk.max(1)) {
        let mut rest = piece;
        loop {
            let (got, r) = decoder.feed::<T>(rest);
            if let Some(g) = got {
                out.push(g);
            }
            if r.is_empty() {
                break;
            }
            rest = r;
        }
    }
    out
}

/// Bytes of `message` as postcard writes it (`None` if over `MAX_FRAME_BYTES`).
fn postcard_bytes<T: Serialize>(message: &T) -> Option<Vec<u8>> {
    let mut buf = [0u8; MAX_FRAME_BYTES];
    postcard::to_slice(message, &mut buf)
        .ok()
        .map(|b| b.to_vec())
}

/// A frame of `message`, terminator included.
fn frame_of<T: Serialize>(message: &T) -> Vec<u8> {
    let mut out = [0u8; MAX_FRAME_BYTES];
    match frame::encode(message, &mut out) {
        Ok(f) => f.to_vec(),
        Err(e) => panic!("a decoded message does not fit a frame: {e:?}"),
    }
}

/// The framed-decoder checks for messages of type `T`.
fn framed<T: DeserializeOwned + Serialize + core::fmt::Debug>(data: &[u8]) {
    let whole = decode_stream::<T>(data, data.len());
    // The first byte picks a chunk size: a frame split anywhere decodes the same.
    let chunk = 1 + data.first().map_or(0, |b| *b as usize % 61);
    let pieces = decode_stream::<T>(data, chunk);
    assert_eq!(
        format!("{whole:?}"),
        format!("{pieces:?}"),
        "chunks of {chunk} bytes decode differently"
    );
    let terminators = data.iter().filter(|b| **b == 0).count();
    assert!(
        whole.len() <= terminators,
        "{} results from {terminators} terminators",
        whole.len()
    );
    for message in whole.iter().flatten() {
        // Re-encode: one frame, which decodes to a message with the same bytes.
        let f = frame_of(message);
        assert!(f.len() <= MAX_FRAME_BYTES);
        assert_eq!(f.iter().filter(|b| **b == 0).count(), 1);
        let again = decode_stream::<T>(&f, f.len());
        assert_eq!(again.len(), 1, "{again:?}");
        match &again[0] {
            Ok(m) => assert_eq!(postcard_bytes(m), postcard_bytes(message)),
            Err(e) => panic!("re-encoded {message:?} does not decode: {e:?}"),
        }
    }
}

/// The device's request decoder: a byte stream split into `RequestFrame`s.
pub fn frame_request(data: &[u8]) {
    framed::<RequestFrame>(data);
}

/// The host's decoder: a byte stream split into `DeviceFrame`s (replies and telemetry).
pub fn frame_device(data: &[u8]) {
    framed::<DeviceFrame>(data);
}

/// One message decoder without the framing (the CRC keeps a fuzzer out of the frames' insides).
fn message<T: DeserializeOwned + Serialize + core::fmt::Debug>(data: &[u8]) {
    let Ok(m) = postcard::from_bytes::<T>(data) else {
        return;
    };
    // Every message fits a frame (the protocol's promise), and re-encodes byte-stably.
    let _ = frame_of(&m);
    let Some(bytes) = postcard_bytes(&m) else {
        panic!("{m:?} does not fit {MAX_FRAME_BYTES} bytes");
    };
    match postcard::from_bytes::<T>(&bytes) {
        Ok(again) => assert_eq!(postcard_bytes(&again).as_deref(), Some(&bytes[..])),
        Err(e) => panic!("re-encoded {m:?} does not decode: {e:?}"),
    }
}

/// Every message decoder of the protocol, on the same bytes.
pub fn messages(data: &[u8]) {
    message::<RequestFrame>(data);
    message::<Request>(data);
    message::<DeviceFrame>(data);
    message::<Reply>(data);
    message::<Telemetry>(data);
}

// ---------------------------------------------------------------------------------------------
// Link: the device.

/// Grid of the fuzzed device: 64 x 64 cells, small so that a run is fast.
const DEVICE_GRID_WORDS: usize = words_for_cells(64 * 64);
/// Requests and raw chunks per input (bounds one run).
const DEVICE_STEPS: usize = 64;
/// Tags at or above this feed raw bytes; below, a postcard `RequestFrame` follows.
const RAW_TAG: u8 = 0xc0;

/// Run a device script: a tag byte, then either a postcard `RequestFrame` (tag < 0xc0: framed
/// properly and sent after a `0x00`, so it must get exactly one reply with its sequence number)
/// or `1 + (tag & 0x3f)` raw bytes (at most one reply per `0x00` among them). `receive` feeds
/// the bytes to the device and returns the frames it sent, in order; `after_step` runs after
/// each step (the mission shell's work).
fn run_script(
    data: &[u8],
    mut receive: impl FnMut(&[u8]) -> Vec<Vec<u8>>,
    mut after_step: impl FnMut(),
) {
    let mut rest = data;
    for _ in 0..DEVICE_STEPS {
        let Some((&tag, tail)) = rest.split_first() else {
            break;
        };
        let (sent, expected_seq) = if tag >= RAW_TAG {
            let n = (1 + (tag & 0x3f) as usize).min(tail.len());
            let (raw, after) = tail.split_at(n);
            rest = after;
            (raw.to_vec(), None)
        } else {
            let Ok((request, after)) = postcard::take_from_bytes::<RequestFrame>(tail) else {
                break;
            };
            rest = after;
            let mut sent = vec![0u8];
            sent.extend(frame_of(&request));
            (sent, Some(request.seq))
        };
        let replies = receive(&sent);
        let terminators = sent.iter().filter(|b| **b == 0).count();
        assert!(
            replies.len() <= terminators,
            "{} replies to {terminators} frames",
            replies.len()
        );
        let mut last_seq = None;
        for reply in &replies {
            assert!(reply.len() <= MAX_FRAME_BYTES);
            let got = decode_stream::<DeviceFrame>(reply, reply.len());
            match got.as_slice() {
                [Ok(DeviceFrame::Reply { seq, .. })] => last_seq = Some(*seq),
                other => panic!("not one reply frame: {other:?}"),
            }
        }
        if let Some(seq) = expected_seq {
            // The 0x00 may end a partial frame (one fault reply), then the request's reply.
            assert!(
                !replies.is_empty() && replies.len() <= 2,
                "{} replies",
                replies.len()
            );
            assert_eq!(
                last_seq,
                Some(Some(seq)),
                "the reply carries the request's seq"
            );
        }
        after_step();
    }
}

/// The planning device's whole `Device::receive` path fed a script (see [`run_script`]).
pub fn device(data: &[u8]) {
    let mut device: Device<DEVICE_GRID_WORDS> = Device::new(Default::default());
    let mut planner = Planner::<512, 256>::new();
    run_script(
        data,
        |sent| {
            let mut replies = Vec::new();
            device.receive(sent, &mut planner, &mut || 0, &mut |out: &[u8]| {
                replies.push(out.to_vec())
            });
            replies
        },
        || {},
    );
    let _ = device.status();
}

/// Control period of the fuzzed mission shell, seconds (as `twil --remote sim`).
const PERIOD_S: f32 = 0.05;
/// Telemetry frames drained per step, at most.
const TELEMETRY_PER_STEP: usize = 64;

/// The mission device (`RobotDevice`, the firmware's): `RobotLink::receive` with a simulated
/// world fed a script (see [`run_script`]); after each step the shell's work as `twil --remote
/// sim` does it, without the plant: one pilot tick while a mission runs (the wheels do not
/// turn), plans run at once, sonar requests answered "no echo", telemetry drained. Every
/// telemetry frame must encode.
pub fn robot_device(data: &[u8]) {
    let mut device: RobotDevice<DEVICE_GRID_WORDS> = RobotDevice::new(Default::default());
    let mut mission = Box::new(Mission::<DEVICE_GRID_WORDS>::IDLE);
    let mut planner = Planner::<512, 256>::new();
    let mut world = WorldUpload::default();
    let mut pilot: Option<Pilot> = None;
    let state = core::cell::RefCell::new((&mut device, &mut *mission, &mut planner, &mut world));
    run_script(
        data,
        |sent| {
            let (device, mission, planner, world) = &mut *state.borrow_mut();
            let mut replies = Vec::new();
            device
                .link(mission)
                .receive(sent, *planner, &mut || 0, *world, &mut |out: &[u8]| {
                    replies.push(out.to_vec())
                });
            replies
        },
        || {
            let (device, mission, planner, _) = &mut *state.borrow_mut();
            if let Some(config) = device.link(mission).take_started() {
                pilot = Some(Pilot::new(&config));
            }
            if let (Some(p), RunState::Running | RunState::Paused) = (&mut pilot, device.state()) {
                let report = p.tick(0, 0, PERIOD_S);
                device.link(mission).tick(&report);
            }
            for _ in 0..TELEMETRY_PER_STEP {
                if let (Some(command), Some(p)) = (device.take_pilot_command(), &mut pilot) {
                    let _ = p.command(command, mission.prefix());
                }
                if device.plan_pending() {
                    device.link(mission).run_planner(*planner, &mut || 0);
                } else if let Some(request) = device.take_sonar_request() {
                    device.link(mission).reading(request.neck_angle_rad, None);
                } else {
                    break;
                }
            }
            for _ in 0..TELEMETRY_PER_STEP {
                let Some(t) = device.link(mission).next_telemetry() else {
                    break;
                };
                let _ = frame_of(&DeviceFrame::Telemetry(t));
            }
        },
    );
}

// ---------------------------------------------------------------------------------------------
// Text files.

/// Lines of `text` (a line number in an error must be one of them).
fn line_count(text: &str) -> u32 {
    text.bytes().filter(|b| *b == b'\n').count() as u32 + 1
}

fn check_line(line: u32, text: &str, message: &str) {
    assert!(
        line >= 1 && line <= line_count(text),
        "line {line} of a {}-line text: {message}",
        line_count(text)
    );
}

/// The text a host reader would hand over (it refuses non-UTF-8 before parsing; lossy
/// conversion keeps the fuzzer's mutations useful).
fn text_of(data: &[u8]) -> String {
    String::from_utf8_lossy(data).into_owned()
}

/// Write obstacles as a `.da` text.
fn write_da(obstacles: &Obstacles) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "{}", obstacles.len());
    for polygon in obstacles.iter() {
        let _ = writeln!(s, "{}", polygon.len());
        for p in polygon {
            // `{}` of an f32 is the shortest text that parses back to the same value.
            let _ = writeln!(s, "{} {}", p.x_m, p.y_m);
        }
    }
    s
}

/// `.da` reader: an error names a line and changes nothing; a parsed file written back parses
/// equal.
pub fn da(data: &[u8]) {
    let text = text_of(data);
    let mut obstacles = Obstacles::new();
    let before = [twil_core::geom::PointM::new(1.0, 2.0)];
    let _ = obstacles.push(&before);
    let kept = obstacles.clone();
    match parse_da(&text, &mut obstacles) {
        Err(e) => {
            let message = e.to_string();
            check_line(e.line, &text, &message);
            assert_eq!(obstacles, kept, "a failed parse changed the obstacles");
        }
        Ok(()) => {
            let written = write_da(&obstacles);
            let mut again = Obstacles::new();
            match parse_da(&written, &mut again) {
                Ok(()) => assert_eq!(again, obstacles, "written back:\n{written}"),
                Err(e) => panic!("written back does not parse: {e}\n{written}"),
            }
        }
    }
}

fn write_par(p: &Params) -> String {
    format!(
        "{}\n{}\n{}\n{} {}\n{} {}\n",
        p.robot_radius_m,
        p.speed_m_s,
        p.initial_heading_deg,
        p.start.x_m,
        p.start.y_m,
        p.goal.x_m,
        p.goal.y_m
    )
}

/// `.par` reader: an error names a line; a parsed file written back parses equal.
pub fn par(data: &[u8]) {
    let text = text_of(data);
    match parse_par(&text) {
        Err(e) => check_line(e.line, &text, &e.to_string()),
        Ok(p) => {
            let written = write_par(&p);
            match parse_par(&written) {
                Ok(again) => assert_eq!(again, p, "written back:\n{written}"),
                Err(e) => panic!("written back does not parse: {e}\n{written}"),
            }
        }
    }
}

/// `.ROB` reader: an error names a line of the text.
pub fn rob(data: &[u8]) {
    let text = text_of(data);
    if let Err(e) = parse_rob(&text) {
        check_line(e.line, &text, &e.to_string());
    }
}

/// `.MAP` reader: an error names a line; a parsed map written back parses equal. The first
/// byte's low bits say which joints wrap (the file does not say).
pub fn map(data: &[u8]) {
    let wraps = data
        .first()
        .map_or([false; 2], |b| [b & 1 != 0, b & 2 != 0]);
    let text = text_of(data.get(1..).unwrap_or(&[]));
    match ConfigMap::parse_map(&text, wraps) {
        Err(e) => check_line(e.line, &text, &e.to_string()),
        Ok((name, map)) => {
            let mut written = String::new();
            map.write_map(&name, &mut written)
                .expect("writing to a String cannot fail");
            match ConfigMap::parse_map(&written, wraps) {
                Ok((name2, map2)) => {
                    assert_eq!(name2, name, "name written back");
                    assert!(map2 == map, "map written back differs");
                }
                Err(e) => panic!("written back does not parse: {e}"),
            }
        }
    }
}

/// `.TRA` reader: an error names a line; a parsed path written back parses equal.
pub fn tra(data: &[u8]) {
    let text = text_of(data);
    match Trajectory::parse(&text) {
        Err(e) => check_line(e.line, &text, &e.to_string()),
        Ok(t) => {
            let mut written = String::new();
            t.write(&mut written)
                .expect("writing to a String cannot fail");
            match Trajectory::parse(&written) {
                Ok(again) => assert_eq!(again, t, "written back:\n{written}"),
                Err(e) => panic!("written back does not parse: {e}\n{written}"),
            }
        }
    }
}
