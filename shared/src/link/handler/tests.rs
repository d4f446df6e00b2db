//! Handler tests: requests as frames through a [`Device`], one reply each, and refused
//! requests that change nothing.
extern crate std;
use super::*;
use crate::grid::{words_for_cells, Grid300};
use crate::link::frame::{encode, FrameDecoder};
use crate::plan::{PlanStatus, PlannerKind};
use crate::raster::mark_polygon;
use std::vec::Vec as StdVec;

/// A 300 x 300 grid; a small planner (512 cells) unless a test brings its own.
type TestDevice = Device<{ words_for_cells(300 * 300) }>;
type SmallPlanner = Planner<64, 64>;

fn device() -> std::boxed::Box<TestDevice> {
    std::boxed::Box::new(Device::new(DeviceInfo::default()))
}

/// Send requests as frames through the device; decode every frame it sends back.
fn exchange(device: &mut TestDevice, stream: &[u8]) -> StdVec<DeviceFrame> {
    let mut out = StdVec::new();
    let mut planner = SmallPlanner::new();
    device.receive(stream, &mut planner, &mut || 0, &mut |b: &[u8]| {
        out.extend_from_slice(b)
    });
    let mut decoder = FrameDecoder::new();
    let mut frames = StdVec::new();
    let mut rest = &out[..];
    while !rest.is_empty() {
        let (got, r) = decoder.feed::<DeviceFrame>(rest);
        rest = r;
        if let Some(got) = got {
            frames.push(got.expect("the device sends valid frames"));
        }
    }
    frames
}

fn frame(seq: u16, request: Request) -> StdVec<u8> {
    let mut out = [0u8; MAX_FRAME_BYTES];
    encode(&RequestFrame { seq, request }, &mut out)
        .unwrap()
        .to_vec()
}

fn call(device: &mut TestDevice, seq: u16, request: Request) -> Reply {
    let frames = exchange(device, &frame(seq, request));
    assert_eq!(frames.len(), 1, "exactly one reply per request");
    match frames.into_iter().next() {
        Some(DeviceFrame::Reply { seq: s, reply }) => {
            assert_eq!(s, Some(seq));
            reply
        }
        other => panic!("not a reply: {other:?}"),
    }
}

fn error_code(reply: &Reply) -> Option<ErrorCode> {
    match reply {
        Reply::Error(e) => Some(e.code),
        _ => None,
    }
}

fn chunk(first_vertex: u16, vertices: &[PointM], last: bool) -> Request {
    Request::ObstacleChunk {
        first_vertex,
        vertices: Vec::from_slice(vertices).unwrap(),
        last,
    }
}

#[test]
fn marking_beyond_the_row_budget_is_refused_and_changes_nothing() {
    let mut d = device();
    let tall = |radius_m: f32| MapParams {
        width_cells: 21,
        height_cells: 4096,
        resolution_m: 0.05,
        robot_radius_m: radius_m,
    };
    assert_eq!(call(&mut d, 1, Request::SetParams(tall(0.1))), Reply::Ack);
    // 75 vertices × 4 096 rows = 307 200 = the budget: taken, in chunks.
    let fits = MAX_MARKING_ROWS as usize / 4096;
    let vertex = |i: usize| PointM::new((i % 2) as f32, i as f32 * 0.002);
    let polygon: StdVec<PointM> = (0..fits + 1).map(vertex).collect();
    for (seq, first) in [(2, 0), (12, 30)] {
        assert_eq!(
            call(
                &mut d,
                seq,
                chunk(first, &polygon[first as usize..first as usize + 30], false)
            ),
            Reply::Obstacles {
                polygons: 0,
                vertices: 0,
                pending_vertices: first + 30
            }
        );
    }
    let before = (d.grid().words().to_vec(), d.status());
    // One more vertex would go over: refused at once, with the rows and the budget.
    assert_eq!(
        call(&mut d, 3, chunk(60, &polygon[60..], true)),
        Reply::Error(ErrorReply::new(
            ErrorCode::MarkingBudget,
            (fits as u32 + 1) * 4096,
            MAX_MARKING_ROWS
        ))
    );
    let mut after = d.status();
    after.requests = before.1.requests;
    assert_eq!((d.grid().words().to_vec(), after), before);
    assert!(matches!(
        call(&mut d, 4, chunk(60, &polygon[60..fits], true)),
        Reply::Obstacles { polygons: 1, .. }
    ));
    // 76 vertices stored on a low map, then the tall map: refused before the grid changes.
    let low = MapParams {
        width_cells: 300,
        height_cells: 280,
        ..tall(0.1)
    };
    assert_eq!(call(&mut d, 5, Request::ClearMap), Reply::Ack);
    assert_eq!(call(&mut d, 6, Request::SetParams(low)), Reply::Ack);
    for (seq, first) in [(7u16, 0u16), (8, 30)] {
        let range = first as usize..first as usize + 30;
        call(&mut d, seq, chunk(first, &polygon[range], false));
    }
    assert!(matches!(
        call(&mut d, 9, chunk(60, &polygon[60..], true)),
        Reply::Obstacles {
            polygons: 1,
            vertices: 76,
            ..
        }
    ));
    let words = d.grid().words().to_vec();
    assert_eq!(
        error_code(&call(&mut d, 10, Request::SetParams(tall(0.1)))),
        Some(ErrorCode::MarkingBudget)
    );
    assert_eq!(d.grid().words(), &words[..]);
    assert_eq!(d.status().params, low);
    // The seed's map holds every vertex the device stores.
    assert!(marking_rows(MAX_VERTICES, 300) <= MAX_MARKING_ROWS);
}

#[test]
fn handshake_ping_and_version_mismatch() {
    let mut d = device();
    match call(
        &mut d,
        1,
        Request::Hello {
            protocol_version: PROTOCOL_VERSION,
        },
    ) {
        Reply::Hello(info) => {
            assert_eq!(info.protocol_version, PROTOCOL_VERSION);
            assert_eq!(info.grid_capacity_cells as usize, Grid300::CAPACITY_CELLS);
            assert_eq!(info.max_frame_bytes as usize, MAX_FRAME_BYTES);
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(
        call(&mut d, 2, Request::Ping { nonce: 0xdead_beef }),
        Reply::Pong { nonce: 0xdead_beef }
    );
    assert_eq!(
        call(
            &mut d,
            3,
            Request::Hello {
                protocol_version: 99
            }
        ),
        Reply::Error(ErrorReply::new(
            ErrorCode::VersionMismatch,
            99,
            PROTOCOL_VERSION as u32
        ))
    );
}

#[test]
fn uploaded_obstacles_mark_the_map_like_the_rasterizer() {
    let mut d = device();
    let params = MapParams {
        robot_radius_m: 0.4,
        ..MapParams::default()
    };
    assert_eq!(call(&mut d, 1, Request::SetParams(params)), Reply::Ack);
    // A 40-vertex polygon goes in two chunks.
    let polygon: StdVec<PointM> = (0..40)
        .map(|i| {
            let a = i as f32 * 0.157;
            PointM::new(
                7.0 + 3.0 * crate::math::cos(a),
                7.0 + 3.0 * crate::math::sin(a),
            )
        })
        .collect();
    let r = call(&mut d, 2, chunk(0, &polygon[..32], false));
    assert_eq!(
        r,
        Reply::Obstacles {
            polygons: 0,
            vertices: 0,
            pending_vertices: 32
        }
    );
    let r = call(&mut d, 3, chunk(32, &polygon[32..], true));
    assert_eq!(
        r,
        Reply::Obstacles {
            polygons: 1,
            vertices: 40,
            pending_vertices: 0
        }
    );
    let mut expected = Grid300::new(GridGeometry::seed_default()).unwrap();
    mark_polygon(&mut expected, &polygon, 8);
    assert_eq!(d.grid(), &expected);

    // The map read back in chunks equals the grid.
    let mut words = StdVec::new();
    loop {
        match call(
            &mut d,
            4,
            Request::ReadMap {
                offset_words: words.len() as u32,
            },
        ) {
            Reply::MapChunk {
                offset_words,
                total_words,
                width_cells,
                words: w,
                ..
            } => {
                assert_eq!(offset_words as usize, words.len());
                assert_eq!(width_cells, 300);
                words.extend_from_slice(&w);
                if words.len() == total_words as usize {
                    break;
                }
            }
            other => panic!("{other:?}"),
        }
    }
    assert_eq!(&words[..], expected.words());

    // A new radius marks the stored obstacles again.
    let params = MapParams {
        robot_radius_m: 0.1,
        ..params
    };
    assert_eq!(call(&mut d, 5, Request::SetParams(params)), Reply::Ack);
    let mut thin = Grid300::new(GridGeometry::seed_default()).unwrap();
    mark_polygon(&mut thin, &polygon, 2);
    assert_eq!(d.grid(), &thin);

    assert_eq!(call(&mut d, 6, Request::ClearMap), Reply::Ack);
    assert_eq!(d.grid().count_occupied(), 0);
    assert!(d.handler.obstacles().is_empty());
}

#[test]
fn failed_requests_change_nothing() {
    let mut d = device();
    call(
        &mut d,
        1,
        chunk(0, &[PointM::new(1.0, 1.0), PointM::new(2.0, 1.0)], true),
    );
    let before = d.grid().clone();
    let status_before = d.status();

    // Out of order, not finite, too large a map, bad radius, read beyond the end.
    let r = call(&mut d, 2, chunk(5, &[PointM::new(1.0, 1.0)], true));
    assert_eq!(
        r,
        Reply::Error(ErrorReply::new(ErrorCode::ChunkOutOfOrder, 5, 0))
    );
    let r = call(&mut d, 3, chunk(0, &[PointM::new(f32::NAN, 1.0)], true));
    assert_eq!(error_code(&r), Some(ErrorCode::BadArgument));
    let big = MapParams {
        width_cells: 400,
        height_cells: 400,
        ..MapParams::default()
    };
    let r = call(&mut d, 4, Request::SetParams(big));
    assert_eq!(
        r,
        Reply::Error(ErrorReply::new(
            ErrorCode::GridCapacity,
            160_000,
            Grid300::CAPACITY_CELLS as u32
        ))
    );
    let r = call(
        &mut d,
        5,
        Request::SetParams(MapParams {
            robot_radius_m: f32::INFINITY,
            ..MapParams::default()
        }),
    );
    assert_eq!(error_code(&r), Some(ErrorCode::BadArgument));
    let r = call(
        &mut d,
        6,
        Request::SetParams(MapParams {
            width_cells: 0,
            ..MapParams::default()
        }),
    );
    assert_eq!(error_code(&r), Some(ErrorCode::BadGeometry));
    let r = call(
        &mut d,
        7,
        Request::ReadMap {
            offset_words: 100_000,
        },
    );
    assert_eq!(error_code(&r), Some(ErrorCode::OutOfRange));
    let r = call(&mut d, 8, Request::ReadPath { offset: 1 });
    assert_eq!(error_code(&r), Some(ErrorCode::OutOfRange));
    let r = call(
        &mut d,
        9,
        Request::WriteMap {
            offset_words: 2813,
            words: Vec::from_slice(&[1]).unwrap(),
        },
    );
    assert_eq!(error_code(&r), Some(ErrorCode::OutOfRange));
    let r = call(&mut d, 10, chunk(0, &[], true));
    assert_eq!(error_code(&r), Some(ErrorCode::EmptyPolygon));

    assert_eq!(d.grid(), &before);
    let after = d.status();
    assert_eq!(
        (after.polygons, after.vertices, after.params),
        (
            status_before.polygons,
            status_before.vertices,
            status_before.params
        )
    );
}

#[test]
fn uploads_beyond_capacity_get_a_clear_error_and_keep_what_was_stored() {
    let mut d = device();
    let square = [
        PointM::new(1.0, 1.0),
        PointM::new(2.0, 1.0),
        PointM::new(2.0, 2.0),
        PointM::new(1.0, 2.0),
    ];
    let mut seq = 0;
    for _ in 0..MAX_POLYGONS {
        seq += 1;
        let r = call(&mut d, seq, chunk(0, &square, true));
        assert!(matches!(r, Reply::Obstacles { .. }), "{r:?}");
    }
    let r = call(&mut d, 999, chunk(0, &square, true));
    assert_eq!(
        r,
        Reply::Error(ErrorReply::new(
            ErrorCode::TooManyPolygons,
            MAX_POLYGONS as u32 + 1,
            MAX_POLYGONS as u32
        ))
    );
    assert_eq!(d.handler.obstacles().len(), MAX_POLYGONS);

    // One polygon larger than the pending buffer.
    let mut d = device();
    let many = [PointM::new(3.0, 3.0); OBSTACLE_CHUNK_VERTICES];
    let mut first = 0u16;
    let r = loop {
        let r = call(&mut d, 1, chunk(first, &many, false));
        if matches!(r, Reply::Error(_)) {
            break r;
        }
        first += OBSTACLE_CHUNK_VERTICES as u16;
    };
    assert_eq!(
        r,
        Reply::Error(ErrorReply::new(
            ErrorCode::TooManyVertices,
            (MAX_PENDING_VERTICES + OBSTACLE_CHUNK_VERTICES) as u32,
            MAX_PENDING_VERTICES as u32
        ))
    );
    let message = std::format!("{}", ErrorReply::new(ErrorCode::TooManyVertices, 288, 256));
    assert_eq!(
        message,
        "too many obstacle vertices: 288 needed but only 256 left on the device"
    );
}

#[test]
fn damaged_frames_get_one_error_each_and_the_link_keeps_working() {
    let mut d = device();
    let good = frame(40, Request::Ping { nonce: 1 });
    let mut stream = StdVec::new();
    // Garbage, a truncated frame, a corrupted frame, an oversized one, then a good one.
    stream.extend_from_slice(&[0x11, 0x22, 0x33, 0x00]);
    stream.extend_from_slice(&good[..good.len() / 2]);
    stream.push(0);
    let mut corrupt = good.clone();
    corrupt[2] ^= 0x01;
    stream.extend_from_slice(&corrupt);
    stream.extend(core::iter::repeat_n(0x42, 3 * MAX_FRAME_BYTES));
    stream.push(0);
    stream.extend_from_slice(&good);
    let frames = exchange(&mut d, &stream);
    let codes: StdVec<_> = frames
        .iter()
        .map(|f| match f {
            DeviceFrame::Reply { seq, reply } => (*seq, error_code(reply)),
            DeviceFrame::Telemetry(_) => panic!("no telemetry expected"),
        })
        .collect();
    assert_eq!(codes.len(), 5, "{codes:?}");
    assert!(codes[..4]
        .iter()
        .all(|(seq, code)| seq.is_none() && code.is_some()));
    assert_eq!(codes[3].1, Some(ErrorCode::FrameTooLong));
    assert_eq!(codes[4], (Some(40), None));
    assert_eq!(d.status().frame_errors, 4);
}

#[test]
fn a_well_formed_unknown_request_keeps_its_sequence_number() {
    let mut d = device();
    let mut out = [0u8; MAX_FRAME_BYTES];
    // seq 77, variant index 200 (no such request).
    let bytes = encode(&(77u16, 200u8), &mut out).unwrap().to_vec();
    let frames = exchange(&mut d, &bytes);
    assert_eq!(
        frames,
        std::vec![DeviceFrame::Reply {
            seq: Some(77),
            reply: Reply::Error(ErrorReply::new(ErrorCode::BadMessage, 0, 0))
        }]
    );
}

#[test]
fn the_largest_messages_fit_a_frame() {
    let mut out = [0u8; MAX_FRAME_BYTES];
    let big_point = PointM::new(f32::MAX, f32::MIN);
    let largest_requests = [
        Request::ObstacleChunk {
            first_vertex: u16::MAX,
            vertices: Vec::from_slice(&[big_point; OBSTACLE_CHUNK_VERTICES]).unwrap(),
            last: true,
        },
        Request::WriteMap {
            offset_words: u32::MAX,
            words: Vec::from_slice(&[u32::MAX; MAP_CHUNK_WORDS]).unwrap(),
        },
    ];
    for request in largest_requests {
        let f = RequestFrame {
            seq: u16::MAX,
            request,
        };
        assert!(encode(&f, &mut out).is_ok(), "{f:?}");
    }
    let largest_replies = [
        Reply::MapChunk {
            offset_words: u32::MAX,
            total_words: u32::MAX,
            width_cells: u16::MAX,
            height_cells: u16::MAX,
            words: Vec::from_slice(&[u32::MAX; MAP_CHUNK_WORDS]).unwrap(),
        },
        Reply::PathChunk {
            offset: u16::MAX,
            total: u16::MAX,
            points: Vec::from_slice(&[big_point; PATH_CHUNK_POINTS]).unwrap(),
        },
        Reply::Plan(PlanSummary {
            status: PlanStatus::Found,
            expanded: u32::MAX,
            cost: u32::MAX,
            length_m: 1.0,
            points: u16::MAX,
            mcu_instructions: u64::MAX,
        }),
    ];
    for reply in largest_replies {
        let f = DeviceFrame::Reply {
            seq: Some(u16::MAX),
            reply,
        };
        assert!(encode(&f, &mut out).is_ok(), "{f:?}");
    }
}

#[test]
fn plan_errors_and_results_are_replies() {
    // The planner of this test device covers 512 cells: the 300 x 300 map is refused with
    // the planner's capacity, and nothing is left in the path.
    let mut d = device();
    let r = call(
        &mut d,
        1,
        Request::Plan {
            kind: PlannerKind::AStar,
            start: PointM::new(1.0, 1.0),
            goal: PointM::new(2.0, 2.0),
        },
    );
    assert_eq!(error_code(&r), Some(ErrorCode::PlannerCapacity), "{r:?}");
    assert_eq!(d.handler.path_points(), 0);
    assert_eq!(d.status().last_plan_expanded, 0);
}

#[test]
fn a_plan_from_or_to_a_non_finite_point_is_a_bad_argument_naming_the_field() {
    // Not `OutOfBounds` (a status about a real point): the request itself is malformed.
    let mut d = device();
    let fine = PointM::new(1.0, 1.0);
    for (field, start, goal) in [
        (1, PointM::new(f32::NAN, 1.0), fine),
        (2, fine, PointM::new(1.0, f32::INFINITY)),
    ] {
        let r = call(
            &mut d,
            1,
            Request::Plan {
                kind: PlannerKind::Bfs,
                start,
                goal,
            },
        );
        assert_eq!(
            r,
            Reply::Error(ErrorReply::new(ErrorCode::BadArgument, field, 0)),
            "field {field}"
        );
    }
}

#[test]
fn a_plan_over_the_link_equals_the_planner_on_the_same_grid() {
    use crate::plan::SCRATCH_WORDS_300;
    let mut d = device();
    let params = MapParams {
        robot_radius_m: 0.3,
        ..MapParams::default()
    };
    call(&mut d, 1, Request::SetParams(params));
    let wall = [PointM::new(2.0, 7.0), PointM::new(12.0, 7.5)];
    call(&mut d, 2, chunk(0, &wall, true));
    let (start, goal) = (PointM::new(7.0, 2.0), PointM::new(7.0, 13.0));
    let mut planner = std::boxed::Box::new(Planner::<SCRATCH_WORDS_300, 4096>::new());
    for kind in [PlannerKind::Bfs, PlannerKind::AStar, PlannerKind::AnyAngle] {
        let mut out = StdVec::new();
        let mut t = 0u64;
        let request = frame(10, Request::Plan { kind, start, goal });
        d.receive(
            &request,
            &mut *planner,
            &mut || {
                t += 1000;
                t
            },
            &mut |b: &[u8]| out.extend_from_slice(b),
        );
        let mut decoder = FrameDecoder::new();
        let (got, _) = decoder.feed::<DeviceFrame>(&out);
        let summary = match got {
            Some(Ok(DeviceFrame::Reply {
                reply: Reply::Plan(s),
                ..
            })) => s,
            other => panic!("{other:?}"),
        };
        assert_eq!(
            summary.mcu_instructions, 1000,
            "the clock is read around the planner"
        );
        // The reference: the same planner type on a grid built directly.
        let mut grid = Grid300::new(GridGeometry::seed_default()).unwrap();
        mark_polygon(
            &mut grid,
            &wall,
            GridGeometry::seed_default().expansion_cells(0.3),
        );
        let mut path = crate::plan::PathM::new();
        let mut reference = std::boxed::Box::new(Planner::<SCRATCH_WORDS_300, 4096>::new());
        let report = reference.plan(kind, &grid, start, goal, &mut path).unwrap();
        assert_eq!(summary.status, PlanStatus::Found);
        assert_eq!(
            (
                summary.status,
                summary.expanded,
                summary.cost,
                summary.length_m
            ),
            (report.status, report.expanded, report.cost, report.length_m)
        );
        // Read the path in chunks.
        let mut points = StdVec::new();
        while points.len() < summary.points as usize {
            let offset = points.len() as u16;
            // Through the same planner: the path is its cell buffer.
            let mut out = StdVec::new();
            d.receive(
                &frame(11, Request::ReadPath { offset }),
                &mut *planner,
                &mut || 0,
                &mut |b: &[u8]| out.extend_from_slice(b),
            );
            let (got, _) = FrameDecoder::new().feed::<DeviceFrame>(&out);
            let Some(Ok(DeviceFrame::Reply { reply, .. })) = got else {
                panic!("{got:?}");
            };
            match reply {
                Reply::PathChunk {
                    points: p, total, ..
                } => {
                    assert_eq!(total, summary.points);
                    points.extend_from_slice(&p);
                }
                other => panic!("{other:?}"),
            }
        }
        assert_eq!(&points[..], &path[..]);
    }
}

fn any_request() -> impl proptest::strategy::Strategy<Value = Request> {
    use proptest::prelude::*;
    let point = (-1.0f32..16.0, -1.0f32..16.0).prop_map(|(x, y)| PointM::new(x, y));
    prop_oneof![
        any::<u32>().prop_map(|nonce| Request::Ping { nonce }),
        any::<u16>().prop_map(|v| Request::Hello {
            protocol_version: v
        }),
        Just(Request::Status),
        Just(Request::ClearMap),
        (1u16..400, 1u16..400, 0.01f32..1.0, -1.0f32..2.0).prop_map(|(w, h, r, radius)| {
            Request::SetParams(MapParams {
                width_cells: w,
                height_cells: h,
                resolution_m: r,
                robot_radius_m: radius,
            })
        }),
        (
            0u16..80,
            proptest::collection::vec(point.clone(), 0..OBSTACLE_CHUNK_VERTICES),
            any::<bool>()
        )
            .prop_map(|(first_vertex, v, last)| Request::ObstacleChunk {
                first_vertex,
                vertices: Vec::from_slice(&v).unwrap(),
                last,
            }),
        (
            0u32..3000,
            proptest::collection::vec(any::<u32>(), 0..MAP_CHUNK_WORDS)
        )
            .prop_map(|(offset_words, w)| Request::WriteMap {
                offset_words,
                words: Vec::from_slice(&w).unwrap(),
            }),
        (0u32..3000).prop_map(|offset_words| Request::ReadMap { offset_words }),
        (0u16..50).prop_map(|offset| Request::ReadPath { offset }),
        (point.clone(), point).prop_map(|(start, goal)| Request::Plan {
            kind: PlannerKind::Bfs,
            start,
            goal,
        }),
    ]
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]

    /// Whatever the requests, each gets exactly one reply with its sequence number, the
    /// map never has bits set past its last cell, and the state stays within capacity.
    #[test]
    fn every_request_gets_exactly_one_reply(
        requests in proptest::collection::vec(any_request(), 1..40)
    ) {
        let mut d = device();
        for (i, request) in requests.into_iter().enumerate() {
            let seq = i as u16;
            let frames = exchange(&mut d, &frame(seq, request));
            proptest::prop_assert_eq!(frames.len(), 1);
            let is_reply_to_seq =
                matches!(frames[0], DeviceFrame::Reply { seq: Some(s), .. } if s == seq);
            proptest::prop_assert!(is_reply_to_seq);
            let g = *d.grid().geometry();
            proptest::prop_assert!(d.grid().count_occupied() <= g.cell_count());
            proptest::prop_assert!(d.handler.obstacles().len() <= MAX_POLYGONS);
        }
    }

    /// Random bytes never panic the device and get at most one reply per frame terminator.
    #[test]
    fn random_bytes_get_at_most_one_reply_per_frame(
        bytes in proptest::collection::vec(proptest::num::u8::ANY, 0..3000)
    ) {
        let mut d = device();
        let frames = exchange(&mut d, &bytes);
        let zeros = bytes.iter().filter(|&&b| b == 0).count();
        proptest::prop_assert!(frames.len() <= zeros);
        // The link still works: a leading 0x00 (as the host sends) ends any partial frame,
        // which gets its own error reply; then the ping is answered.
        let mut resync = std::vec![0u8];
        resync.extend(frame(1, Request::Ping { nonce: 3 }));
        let frames = exchange(&mut d, &resync);
        proptest::prop_assert!(!frames.is_empty() && frames.len() <= 2, "{:?}", frames);
        if frames.len() == 2 {
            let is_error = matches!(
                frames[0],
                DeviceFrame::Reply { seq: None, reply: Reply::Error(_) }
            );
            proptest::prop_assert!(is_error, "{:?}", frames);
        }
        proptest::prop_assert_eq!(
            frames.last(),
            Some(&DeviceFrame::Reply { seq: Some(1), reply: Reply::Pong { nonce: 3 } })
        );
    }
}

/// Print the example frame of docs/protocol.md (`cargo test -p twil-core example_frame --
/// --nocapture`) and pin it so the document cannot go stale silently.
#[test]
fn example_frame_for_the_docs() {
    let mut out = [0u8; MAX_FRAME_BYTES];
    let f = RequestFrame {
        seq: 1,
        request: Request::Ping { nonce: 0x1234 },
    };
    let bytes = encode(&f, &mut out).unwrap();
    let hex: StdVec<std::string::String> = bytes.iter().map(|b| std::format!("{b:02x}")).collect();
    let hex = hex.join(" ");
    std::println!("Ping {{ nonce: 0x1234 }}, seq 1: {hex}");
    let docs = include_str!("../../../../docs/protocol.md");
    assert!(
        docs.contains(&hex),
        "docs/protocol.md lacks the frame {hex}"
    );
}
