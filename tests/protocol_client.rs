//! A client in another language, written from docs/protocol.md alone
//! (`tests/protocol_client.py`), runs a session with the device: its request frames, encoded
//! from the document's wire tables, drive the device's real receive path, and its decoding of
//! the device's reply frames must equal what the device meant. If the document leaves a field,
//! a type or an index out, this fails. Python 3 only (CI has CPython 3.11); under a second.

use std::process::Command;

use twil_core::geom::PointM;
use twil_core::link::{frame::FrameDecoder, Device, DeviceFrame, MapParams, Request, RequestFrame};
use twil_core::plan::{Planner, PlannerKind};

use crate::common::repo;

/// A session that touches every reply a planning service gives, an error included.
fn session() -> Vec<RequestFrame> {
    let square = [(2.0, 2.0), (3.0, 2.0), (3.0, 3.0), (2.0, 3.0)];
    let requests = vec![
        Request::Hello {
            protocol_version: twil_core::link::PROTOCOL_VERSION,
        },
        Request::Ping { nonce: 0x1234_5678 },
        Request::SetParams(MapParams {
            width_cells: 64,
            height_cells: 64,
            resolution_m: 0.1,
            robot_radius_m: 0.3,
        }),
        Request::ObstacleChunk {
            first_vertex: 0,
            vertices: square.iter().map(|&(x, y)| PointM::new(x, y)).collect(),
            last: true,
        },
        Request::Plan {
            kind: PlannerKind::AStar,
            start: PointM::new(0.55, 0.55),
            goal: PointM::new(5.55, 5.05),
        },
        Request::ReadPath { offset: 0 },
        Request::ReadMap { offset_words: 40 },
        Request::Status,
        // Off the map: an error reply, with its code and numbers.
        Request::ReadPath { offset: 999 },
        Request::MissionStatus,
    ];
    requests
        .into_iter()
        .enumerate()
        .map(|(i, request)| RequestFrame {
            seq: i as u16 + 1,
            request,
        })
        .collect()
}

fn python(mode: &str, input: &std::path::Path) -> Vec<String> {
    let out = Command::new("python3")
        .arg(repo().join("tests/protocol_client.py"))
        .arg(repo().join("docs/protocol.md"))
        .arg(mode)
        .arg(input)
        .output()
        .expect("python3 runs (CI has CPython 3.11)");
    assert!(
        out.status.success(),
        "protocol_client.py {mode}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(str::to_owned)
        .collect()
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

fn unhex(text: &str) -> Vec<u8> {
    (0..text.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&text[i..i + 2], 16).unwrap())
        .collect()
}

#[test]
fn a_client_written_from_protocol_md_alone_talks_to_the_device() {
    let dir = tempfile::tempdir().unwrap();
    let requests = session();
    let requests_json = dir.path().join("requests.json");
    std::fs::write(&requests_json, serde_json::to_string(&requests).unwrap()).unwrap();

    // The client encodes the requests from the document; the device reads them as they are.
    let frames = python("encode", &requests_json);
    assert_eq!(frames.len(), requests.len());
    let mut device: Device<128> = Device::new(Default::default());
    let mut planner = Planner::<512, 256>::new();
    let mut replies = Vec::new();
    for (wire, sent) in frames.iter().zip(&requests) {
        let bytes = unhex(wire);
        let (read, _) = FrameDecoder::new().feed::<RequestFrame>(&bytes);
        assert_eq!(read, Some(Ok(sent.clone())), "the client's frame {wire}");
        let mut answer = Vec::new();
        device.receive(&bytes, &mut planner, &mut || 0, &mut |out: &[u8]| {
            answer.extend_from_slice(out)
        });
        replies.push(answer);
    }

    // The client decodes the device's frames from the document: the same values.
    let replies_hex = dir.path().join("replies.hex");
    let lines: Vec<String> = replies.iter().map(|r| hex(r)).collect();
    std::fs::write(&replies_hex, lines.join("\n") + "\n").unwrap();
    let decoded = python("decode", &replies_hex);
    assert_eq!(decoded.len(), replies.len());
    let mut kinds = Vec::new();
    for (text, wire) in decoded.iter().zip(&replies) {
        let (frame, _) = FrameDecoder::new().feed::<DeviceFrame>(wire);
        let frame = frame.unwrap().unwrap();
        let meant = serde_json::to_value(&frame).unwrap();
        let got: serde_json::Value = serde_json::from_str(text).unwrap();
        assert!(same(&got, &meant), "decoded {got}\nthe device sent {meant}");
        if let Some(kind) = meant["Reply"]["reply"]
            .as_object()
            .and_then(|o| o.keys().next())
        {
            kinds.push(kind.clone());
        }
    }
    // The session reached the replies it was written for.
    for kind in [
        "Hello",
        "Pong",
        "Obstacles",
        "Plan",
        "PathChunk",
        "MapChunk",
        "Status",
        "Error",
    ] {
        assert!(kinds.iter().any(|k| k == kind), "no {kind} in {kinds:?}");
    }
}

/// JSON equality with `f32` compared as `f32` (Python prints the double it widened to).
fn same(a: &serde_json::Value, b: &serde_json::Value) -> bool {
    use serde_json::Value::*;
    match (a, b) {
        (Number(x), Number(y)) => match (x.as_u64(), y.as_u64()) {
            (Some(x), Some(y)) => x == y,
            _ => x.as_f64().map(|v| v as f32) == y.as_f64().map(|v| v as f32),
        },
        (Array(x), Array(y)) => x.len() == y.len() && x.iter().zip(y).all(|(a, b)| same(a, b)),
        (Object(x), Object(y)) => {
            x.len() == y.len() && x.iter().all(|(k, v)| y.get(k).is_some_and(|w| same(v, w)))
        }
        _ => a == b,
    }
}
