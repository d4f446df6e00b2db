//! The fuzz targets on stable: every checked-in corpus and regression file through its target,
//! then a short mutation run per target seeded from those files (see `docs/reliability.md`).
//!
//! The target bodies are `shared/fuzz/src/targets.rs`, shared with the cargo-fuzz binaries
//! (`cargo xtask fuzz`, nightly). `cargo test -p twil-core --test fuzz_corpus -- --ignored
//! write_seed_corpus` rewrites the seed files (`seed-*`) from the bundled worlds and one frame of
//! every message kind.

// A test file, helpers included; the targets' oracles end a run with a panic by design.
#![allow(clippy::panic, clippy::expect_used, clippy::unwrap_used)]

#[path = "../fuzz/src/targets.rs"]
mod targets;

use std::path::{Path, PathBuf};

use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};

/// Mutated inputs per target in the normal test run.
const MUTATION_CASES: u32 = 300;

fn fuzz_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz")
}

/// The corpus and regression files of `target`, sorted by path.
fn inputs_of(target: &str) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    for dir in ["corpus", "regressions"] {
        let Ok(entries) = std::fs::read_dir(fuzz_dir().join(dir).join(target)) else {
            continue;
        };
        for entry in entries.flatten() {
            let path = entry.path();
            if path.is_file() {
                let bytes = std::fs::read(&path).unwrap();
                out.push((path, bytes));
            }
        }
    }
    out.sort();
    out
}

#[test]
fn every_corpus_file_passes_its_target() {
    let mut total = 0;
    for (target, run) in targets::TARGETS {
        let inputs = inputs_of(target);
        assert!(!inputs.is_empty(), "no corpus for target {target}");
        for (path, bytes) in &inputs {
            let result = std::panic::catch_unwind(|| run(bytes));
            assert!(
                result.is_ok(),
                "target {target} fails on {}",
                path.display()
            );
        }
        total += inputs.len();
    }
    println!("{total} corpus files replayed");
}

/// One change to an input, in the manner of libFuzzer's mutators.
#[derive(Clone, Debug)]
enum Mutation {
    /// Flip a bit at a position (taken modulo the length).
    Flip { at: usize, bit: u8 },
    /// Insert a byte.
    Insert { at: usize, byte: u8 },
    /// Delete up to `len` bytes.
    Delete { at: usize, len: usize },
    /// Overwrite with a byte that delimits frames or tokens.
    Special { at: usize, pick: usize },
    /// Insert a slice of another input.
    Splice {
        at: usize,
        other: usize,
        from: usize,
        len: usize,
    },
}

fn mutation() -> impl Strategy<Value = Mutation> {
    let at = any::<usize>();
    prop_oneof![
        (at, 0u8..8).prop_map(|(at, bit)| Mutation::Flip { at, bit }),
        (at, any::<u8>()).prop_map(|(at, byte)| Mutation::Insert { at, byte }),
        (at, 1usize..16).prop_map(|(at, len)| Mutation::Delete { at, len }),
        (at, any::<usize>()).prop_map(|(at, pick)| Mutation::Special { at, pick }),
        (at, any::<usize>(), any::<usize>(), 1usize..64).prop_map(|(at, other, from, len)| {
            Mutation::Splice {
                at,
                other,
                from,
                len,
            }
        }),
    ]
}

fn apply(input: &mut Vec<u8>, m: &Mutation, inputs: &[(PathBuf, Vec<u8>)]) {
    const SPECIAL: &[u8] = b"\x00\xff\x80\x7f\n -.e9%";
    let n = input.len();
    match *m {
        Mutation::Flip { at, bit } if n > 0 => input[at % n] ^= 1 << bit,
        Mutation::Insert { at, byte } => input.insert(at % (n + 1), byte),
        Mutation::Delete { at, len } if n > 0 => {
            let at = at % n;
            input.drain(at..(at + len).min(n));
        }
        Mutation::Special { at, pick } if n > 0 => input[at % n] = SPECIAL[pick % SPECIAL.len()],
        Mutation::Splice {
            at,
            other,
            from,
            len,
        } => {
            let other = &inputs[other % inputs.len()].1;
            if !other.is_empty() {
                let from = from % other.len();
                let piece = &other[from..(from + len).min(other.len())];
                let at = at % (n + 1);
                input.splice(at..at, piece.iter().copied());
            }
        }
        _ => {}
    }
}

#[test]
fn mutated_corpus_files_pass_their_targets() {
    for (target, run) in targets::TARGETS {
        let inputs = inputs_of(target);
        assert!(!inputs.is_empty(), "no corpus for target {target}");
        let config = Config {
            cases: MUTATION_CASES,
            failure_persistence: None,
            ..Config::default()
        };
        // A fixed seed: the same cases on every run (the fuzzer is where randomness pays).
        let mut runner =
            TestRunner::new_with_rng(config, TestRng::deterministic_rng(RngAlgorithm::ChaCha));
        let strategy = (any::<usize>(), proptest::collection::vec(mutation(), 1..8));
        let result = runner.run(&strategy, |(pick, mutations)| {
            let mut input = inputs[pick % inputs.len()].1.clone();
            for m in &mutations {
                apply(&mut input, m, &inputs);
            }
            let outcome = std::panic::catch_unwind(|| run(&input));
            prop_assert!(outcome.is_ok(), "target {} fails on {:?}", target, input);
            Ok(())
        });
        if let Err(e) = result {
            panic!("target {target}: {e}");
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Seed corpus.

mod seeds {
    use twil_core::cspace::{map::ConfigMap, rob::parse_rob};
    use twil_core::geom::PointM;
    use twil_core::link::frame::{encode, FrameDecoder, MAX_FRAME_BYTES};
    use twil_core::link::*;
    use twil_core::mission::{MissionMode, MissionPhase, MissionStats, MissionStatus};
    use twil_core::plan::{PlanStatus, Planner, PlannerKind};

    fn frame_of<T: serde::Serialize>(m: &T) -> Vec<u8> {
        let mut out = [0u8; MAX_FRAME_BYTES];
        encode(m, &mut out).unwrap().to_vec()
    }

    fn postcard_of<T: serde::Serialize>(m: &T) -> Vec<u8> {
        let mut out = [0u8; MAX_FRAME_BYTES];
        postcard::to_slice(m, &mut out).unwrap().to_vec()
    }

    fn chunk(points: &[(f32, f32)]) -> heapless::Vec<PointM, 32> {
        points.iter().map(|&(x, y)| PointM::new(x, y)).collect()
    }

    /// One of every request, in an order that makes a session on a 64 x 64 map.
    pub fn requests() -> Vec<Request> {
        let square = chunk(&[(2.0, 2.0), (3.0, 2.0), (3.0, 3.0), (2.0, 3.0)]);
        vec![
            Request::Hello {
                protocol_version: PROTOCOL_VERSION,
            },
            Request::Ping { nonce: 42 },
            Request::SetParams(MapParams {
                width_cells: 64,
                height_cells: 64,
                resolution_m: 0.1,
                robot_radius_m: 0.2,
            }),
            Request::ObstacleChunk {
                first_vertex: 0,
                vertices: square.clone(),
                last: true,
            },
            Request::WriteMap {
                offset_words: 3,
                words: heapless::Vec::from_slice(&[0xffff_0000, 7]).unwrap(),
            },
            Request::Plan {
                kind: PlannerKind::AStar,
                start: PointM::new(0.5, 0.5),
                goal: PointM::new(5.5, 5.0),
            },
            Request::ReadPath { offset: 0 },
            Request::ReadMap { offset_words: 0 },
            Request::Status,
            Request::SetMission(MissionSetup {
                mode: MissionMode::Stop,
                planner: PlannerKind::Bfs,
                start: PointM::new(0.5, 0.5),
                initial_heading_rad: 0.0,
                goal: PointM::new(5.5, 5.0),
                speed_m_s: 0.2,
                sonar_range_m: 3.0,
                time_limit_s: 60.0,
                constant_depth_filter: true,
                trust_seen_space: false,
                noise_seed: 1,
                sonar_noise_std_m: 0.01,
                link_loss: twil_core::failsafe::LinkLossPolicy {
                    timeout_ms: 2000,
                    reaction: twil_core::failsafe::LinkLossReaction::StopAndHold,
                },
                sonar_beam: true,
                beam_half_angle_deg: 15.0,
                incidence_limit_deg: 70.0,
                settle: twil_core::mission::SettleRule::SeedCode,
                reference_feed_forward: false,
                turn_in_place: false,
                sweep_layout: twil_core::sonar::SweepLayout::Seed,
                evidence_map: true,
                sonar_dropout_probability: 0.02,
                sonar_spurious_probability: 0.01,
            }),
            Request::WorldChunk {
                first_vertex: 0,
                vertices: square,
                last: true,
            },
            Request::ClearWorld,
            Request::StartMission,
            Request::PauseMission,
            Request::ResumeMission,
            Request::AbortMission,
            Request::EmergencyStop,
            Request::ClearEmergencyStop,
            Request::MissionStatus,
            Request::Plan {
                kind: PlannerKind::AnyAngle,
                start: PointM::new(0.5, 0.5),
                goal: PointM::new(5.5, 5.0),
            },
            Request::ClearMap,
        ]
    }

    fn request_frames() -> Vec<RequestFrame> {
        requests()
            .into_iter()
            .enumerate()
            .map(|(i, request)| RequestFrame {
                seq: i as u16 + 1,
                request,
            })
            .collect()
    }

    /// A `device` script: tag 0, then the postcard request frame, for each request.
    fn script(frames: &[RequestFrame]) -> Vec<u8> {
        let mut out = Vec::new();
        for f in frames {
            out.push(0);
            out.extend(postcard_of(f));
        }
        out
    }

    /// The device's answers to the session, and telemetry of every kind.
    fn device_frames() -> Vec<DeviceFrame> {
        let mut device: Device<{ twil_core::grid::words_for_cells(64 * 64) }> =
            Device::new(Default::default());
        let mut planner = Planner::<512, 256>::new();
        let mut wire = Vec::new();
        for f in request_frames() {
            device.receive(&frame_of(&f), &mut planner, &mut || 0, &mut |b: &[u8]| {
                wire.extend_from_slice(b)
            });
        }
        // A damaged frame's answer.
        device.receive(&[1, 2, 3, 0], &mut planner, &mut || 0, &mut |b: &[u8]| {
            wire.extend_from_slice(b)
        });
        let mut out = Vec::new();
        let mut decoder = FrameDecoder::new();
        let mut rest = &wire[..];
        while !rest.is_empty() {
            let (got, r) = decoder.feed::<DeviceFrame>(rest);
            if let Some(Ok(f)) = got {
                out.push(f);
            }
            rest = r;
        }
        let points = chunk(&[(1.0, 1.0), (1.5, 1.25), (2.0, 2.0)]);
        let report = MissionReport {
            state: RunState::Ended,
            status: MissionStatus::Reached,
            phase: MissionPhase::Follow,
            stats: MissionStats::default(),
            max_control_instructions: 12_000,
            max_plan_instructions: 3_000_000,
            max_turn_instructions: 60_000_000,
            stack_high_water_bytes: 9_000,
            stop_ticks: 1,
            stop_latency_us: 48_000,
            stop_cause: twil_core::failsafe::StopCause::Host,
            emergency_stop: false,
        };
        out.extend(
            [
                Telemetry::Boot {
                    protocol_version: PROTOCOL_VERSION,
                    reset_cause: twil_core::failsafe::ResetCause::IndependentWatchdog,
                },
                Telemetry::Pose(PoseReport {
                    t_ms: 1200,
                    position: PointM::new(1.0, 2.0),
                    heading_rad: 0.5,
                    left_voltage_v: 3.0,
                    right_voltage_v: -3.0,
                    controller_overruns: 0,
                }),
                Telemetry::Status(device.status()),
                Telemetry::Phase {
                    t_ms: 1500,
                    phase: MissionPhase::Sweep { full: true },
                    status: MissionStatus::Running,
                },
                Telemetry::SweepHits {
                    sweep: 1,
                    first: 0,
                    total: 3,
                    hits: points.clone(),
                },
                Telemetry::Planned {
                    t_ms: 1600,
                    plan: 1,
                    status: PlanStatus::Found,
                    path_points: 3,
                    prefix_points: 2,
                    instructions: 1_000_000,
                },
                Telemetry::Prefix {
                    plan: 1,
                    first: 0,
                    total: 3,
                    points: points.clone(),
                },
                Telemetry::Path {
                    plan: 1,
                    first: 0,
                    total: 3,
                    points,
                },
                Telemetry::Finished(report),
            ]
            .map(DeviceFrame::Telemetry),
        );
        out.push(DeviceFrame::Reply {
            seq: Some(9),
            reply: Reply::Mission(report),
        });
        out
    }

    /// Every seed file: (target, name, bytes).
    pub fn all() -> Vec<(&'static str, String, Vec<u8>)> {
        let worlds = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../worlds");
        let mut out = Vec::new();
        let frames = request_frames();
        for (i, f) in frames.iter().enumerate() {
            out.push(("frame_request", format!("seed-{i:02}"), frame_of(f)));
            out.push(("messages", format!("seed-request-{i:02}"), postcard_of(f)));
            // Each request after the session's SetParams.
            for target in ["device", "robot_device"] {
                out.push((
                    target,
                    format!("seed-{i:02}"),
                    script(&[frames[2].clone(), f.clone()]),
                ));
            }
        }
        out.push(("device", "seed-session".into(), script(&frames)));
        out.push(("robot_device", "seed-session".into(), script(&frames)));
        // A mission that runs for 40 steps (SetParams, SetMission, StartMission, pings).
        let mut mission = vec![frames[2].clone(), frames[9].clone(), frames[12].clone()];
        mission.extend((0..40).map(|i| RequestFrame {
            seq: 100 + i,
            request: Request::Ping { nonce: i as u32 },
        }));
        out.push(("robot_device", "seed-mission".into(), script(&mission)));
        for (i, f) in device_frames().iter().enumerate() {
            out.push(("frame_device", format!("seed-{i:02}"), frame_of(f)));
            out.push(("messages", format!("seed-device-{i:02}"), postcard_of(f)));
        }
        for entry in std::fs::read_dir(&worlds).unwrap() {
            let path = entry.unwrap().path();
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            let target = match path.extension().and_then(|e| e.to_str()) {
                Some("da") => "da",
                Some("par") => "par",
                Some("ROB") => "rob",
                Some("TRA") => "tra",
                _ => continue,
            };
            out.push((
                target,
                format!("seed-{name}"),
                std::fs::read(&path).unwrap(),
            ));
            if target == "rob" {
                // A .MAP of this robot (coarse, so the seed stays small); first byte: wraps.
                let robot = parse_rob(&std::fs::read_to_string(&path).unwrap()).unwrap();
                let map = ConfigMap::build(&robot, [10.0, 10.0]).unwrap();
                let mut text = String::new();
                map.write_map(&name, &mut text).unwrap();
                let wraps = robot.joints[0].wraps() as u8 | (robot.joints[1].wraps() as u8) << 1;
                let mut bytes = vec![wraps];
                bytes.extend(text.as_bytes());
                out.push(("map", format!("seed-{name}.MAP"), bytes));
            }
        }
        out
    }
}

#[test]
#[ignore = "writes the seed corpus files; run by hand after changing the messages or worlds"]
fn write_seed_corpus() {
    for (target, name, bytes) in seeds::all() {
        let dir = fuzz_dir().join("corpus").join(target);
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join(name), bytes).unwrap();
    }
}
