//! The protocol's promise, request kind by request kind: a request that fails changes nothing.
//!
//! For each of the 20 [`Request`] variants a refused case is sent to a device holding
//! something of everything (a map, obstacles, a polygon half uploaded, a last path, a mission
//! set up or running, a real world), and every stored thing is compared before and after. The
//! six requests that are never refused are checked the same way in a case where they must be
//! no-ops: the reads (`Ping`, `Status`, `MissionStatus`) and, with nothing to stop or clear,
//! `AbortMission`, `EmergencyStop` (already latched) and `ClearEmergencyStop` (not latched).
extern crate std;

use std::format;
use std::string::String;
use std::vec::Vec as StdVec;

use super::tests::{office, setup, Bench};
use super::*;
use crate::grid::words_for_cells;
use crate::mission::MissionMode;
use crate::plan::PlannerKind;

/// Everything a request may change, as comparable values.
#[derive(Debug, PartialEq)]
struct Stored {
    map_words: StdVec<u32>,
    geometry: String,
    params: MapParams,
    obstacles: StdVec<StdVec<PointM>>,
    pending: StdVec<PointM>,
    path: StdVec<crate::geom::Cell>,
    setup: Option<MissionSetup>,
    state: RunState,
    emergency_stop: bool,
    mission: String,
    world: StdVec<StdVec<PointM>>,
    world_pending: StdVec<PointM>,
}

fn stored(b: &Bench) -> Stored {
    let handler = &b.shell.device.handler;
    let n = handler.path_points() as usize;
    Stored {
        map_words: b.shell.mission.grid().words().to_vec(),
        geometry: format!("{:?}", b.shell.mission.grid().geometry()),
        params: handler.params(),
        obstacles: handler.obstacles().iter().map(|p| p.to_vec()).collect(),
        pending: handler.pending().to_vec(),
        path: b.shell.planner.path_cells()[..n.min(b.shell.planner.path_cells().len())].to_vec(),
        setup: b.shell.device.setup,
        state: b.shell.device.state,
        emergency_stop: b.shell.device.emergency_stop,
        mission: format!(
            "{:?} {:?} {:?}",
            b.shell.mission.phase(),
            b.shell.mission.status(),
            b.shell.mission.stats()
        ),
        world: b.shell.world.obstacles.iter().map(|p| p.to_vec()).collect(),
        world_pending: b.shell.world.pending.to_vec(),
    }
}

fn code(reply: &Reply) -> Option<ErrorCode> {
    match reply {
        Reply::Error(e) => Some(e.code),
        _ => None,
    }
}

/// Send `request`; it must be refused with `expected` (or, `None`, answered) and change
/// nothing. Returns the kind's variant index, to check that every kind was tried.
fn refused(b: &mut Bench, request: Request, expected: Option<ErrorCode>) -> u8 {
    let kind = variant_index(&request);
    let before = stored(b);
    let reply = b.call(request.clone());
    assert_eq!(code(&reply), expected, "{request:?}: {reply:?}");
    assert_eq!(
        stored(b),
        before,
        "{request:?} ({reply:?}) changed the device"
    );
    kind
}

/// The postcard variant index of a request (its first byte: indices are below 128).
fn variant_index(request: &Request) -> u8 {
    let mut buf = [0u8; 512];
    postcard::to_slice(request, &mut buf).unwrap()[0]
}

fn square(x: f32, y: f32) -> Vec<PointM, OBSTACLE_CHUNK_VERTICES> {
    Vec::from_slice(&[
        PointM::new(x, y),
        PointM::new(x + 0.5, y),
        PointM::new(x + 0.5, y + 0.5),
        PointM::new(x, y + 0.5),
    ])
    .unwrap()
}

/// A device with a map, obstacles, a last path, half a polygon pending (known and real) and a
/// mission set up.
fn loaded() -> (Bench, crate::world::Params) {
    let (real, params) = office();
    let mut b = Bench::new();
    let map = MapParams {
        robot_radius_m: params.robot_radius_m,
        ..MapParams::default()
    };
    assert_eq!(b.call(Request::SetParams(map)), Reply::Ack);
    let reply = b.call(Request::ObstacleChunk {
        first_vertex: 0,
        vertices: square(6.0, 6.0),
        last: true,
    });
    assert!(
        matches!(reply, Reply::Obstacles { polygons: 1, .. }),
        "{reply:?}"
    );
    b.upload_world(&real);
    match b.call(Request::Plan {
        kind: PlannerKind::AStar,
        start: params.start,
        goal: params.goal,
    }) {
        Reply::Plan(s) => assert!(s.points >= 2, "{s:?}"),
        other => panic!("{other:?}"),
    }
    let half = square(1.0, 1.0);
    for request in [
        Request::ObstacleChunk {
            first_vertex: 0,
            vertices: half.clone(),
            last: false,
        },
        Request::WorldChunk {
            first_vertex: 0,
            vertices: half,
            last: false,
        },
    ] {
        assert!(matches!(
            b.call(request),
            Reply::Obstacles {
                pending_vertices: 4,
                ..
            }
        ));
    }
    assert_eq!(
        b.call(Request::SetMission(setup(&params, MissionMode::Stop))),
        Reply::Ack
    );
    (b, params)
}

#[test]
fn every_refused_request_changes_nothing() {
    let (mut b, params) = loaded();
    assert!(b.shell.device.handler.path_points() >= 2);
    assert!(!b.shell.device.handler.pending().is_empty());
    let mut kinds = StdVec::new();
    let nan = PointM::new(f32::NAN, 1.0);
    let map = b.shell.device.handler.params();

    kinds.push(refused(
        &mut b,
        Request::Hello {
            protocol_version: 999,
        },
        Some(ErrorCode::VersionMismatch),
    ));
    kinds.push(refused(&mut b, Request::Ping { nonce: 1 }, None));
    for bad in [
        MapParams {
            robot_radius_m: f32::NAN,
            ..map
        },
        MapParams {
            width_cells: 0,
            ..map
        },
        MapParams {
            width_cells: 4000,
            height_cells: 4000,
            ..map
        },
        MapParams {
            resolution_m: -1.0,
            ..map
        },
    ] {
        let kind = variant_index(&Request::SetParams(bad));
        let before = stored(&b);
        let reply = b.call(Request::SetParams(bad));
        assert!(code(&reply).is_some(), "{bad:?}: {reply:?}");
        assert_eq!(stored(&b), before, "SetParams({bad:?})");
        kinds.push(kind);
    }
    // Out of order, not finite, too many vertices for one polygon, empty.
    kinds.push(refused(
        &mut b,
        Request::ObstacleChunk {
            first_vertex: 9,
            vertices: square(2.0, 2.0),
            last: true,
        },
        Some(ErrorCode::ChunkOutOfOrder),
    ));
    let mut with_nan = square(2.0, 2.0);
    with_nan[2] = nan;
    kinds.push(refused(
        &mut b,
        Request::ObstacleChunk {
            first_vertex: 4,
            vertices: with_nan.clone(),
            last: true,
        },
        Some(ErrorCode::BadArgument),
    ));
    kinds.push(refused(
        &mut b,
        Request::ObstacleChunk {
            first_vertex: 0,
            vertices: Vec::new(),
            last: true,
        },
        Some(ErrorCode::EmptyPolygon),
    ));
    kinds.push(refused(
        &mut b,
        Request::WriteMap {
            offset_words: 1_000_000,
            words: Vec::from_slice(&[1, 2]).unwrap(),
        },
        Some(ErrorCode::OutOfRange),
    ));
    kinds.push(refused(
        &mut b,
        Request::ReadPath { offset: 5000 },
        Some(ErrorCode::OutOfRange),
    ));
    kinds.push(refused(
        &mut b,
        Request::ReadMap {
            offset_words: 1_000_000,
        },
        Some(ErrorCode::OutOfRange),
    ));
    kinds.push(refused(&mut b, Request::Status, None));
    let mut bad = setup(&params, MissionMode::Stop);
    bad.speed_m_s = f32::NAN;
    kinds.push(refused(
        &mut b,
        Request::SetMission(bad),
        Some(ErrorCode::BadMission),
    ));
    bad = setup(&params, MissionMode::Stop);
    bad.goal = PointM::new(99.0, 1.0);
    kinds.push(refused(
        &mut b,
        Request::SetMission(bad),
        Some(ErrorCode::BadMission),
    ));
    kinds.push(refused(
        &mut b,
        Request::WorldChunk {
            first_vertex: 9,
            vertices: square(2.0, 2.0),
            last: true,
        },
        Some(ErrorCode::ChunkOutOfOrder),
    ));
    kinds.push(refused(
        &mut b,
        Request::WorldChunk {
            first_vertex: 4,
            vertices: with_nan,
            last: true,
        },
        Some(ErrorCode::BadArgument),
    ));
    kinds.push(refused(
        &mut b,
        Request::PauseMission,
        Some(ErrorCode::WrongState),
    ));
    kinds.push(refused(
        &mut b,
        Request::ResumeMission,
        Some(ErrorCode::WrongState),
    ));
    kinds.push(refused(&mut b, Request::MissionStatus, None));
    kinds.push(refused(&mut b, Request::ClearEmergencyStop, None)); // not latched: a no-op

    // Latched emergency stop: StartMission refused; a second EmergencyStop and an
    // AbortMission with nothing running change nothing.
    assert_eq!(b.call(Request::EmergencyStop), Reply::Ack);
    kinds.push(refused(
        &mut b,
        Request::StartMission,
        Some(ErrorCode::WrongState),
    ));
    kinds.push(refused(&mut b, Request::EmergencyStop, None));
    kinds.push(refused(&mut b, Request::AbortMission, None));
    assert_eq!(b.call(Request::ClearEmergencyStop), Reply::Ack);

    // While a mission runs: the map, world and planning requests are the mission's.
    assert_eq!(b.call(Request::StartMission), Reply::Ack);
    for _ in 0..40 {
        b.tick();
    }
    assert_eq!(b.shell.device.state(), RunState::Running);
    for request in [
        Request::SetParams(map),
        Request::ClearMap,
        Request::ObstacleChunk {
            first_vertex: 0,
            vertices: square(2.0, 2.0),
            last: true,
        },
        Request::WriteMap {
            offset_words: 0,
            words: Vec::from_slice(&[u32::MAX]).unwrap(),
        },
        Request::Plan {
            kind: PlannerKind::AStar,
            start: params.start,
            goal: params.goal,
        },
        Request::SetMission(setup(&params, MissionMode::Stop)),
        Request::WorldChunk {
            first_vertex: 0,
            vertices: square(2.0, 2.0),
            last: true,
        },
        Request::ClearWorld,
        Request::StartMission,
        Request::ResumeMission,
    ] {
        kinds.push(refused(&mut b, request, Some(ErrorCode::WrongState)));
    }
    kinds.sort_unstable();
    kinds.dedup();
    assert_eq!(
        kinds,
        (0..=19).collect::<StdVec<u8>>(),
        "every request kind"
    );
}

/// A plan refused for the path's capacity (more than `MAX_PATH_POINTS` vertices) keeps the
/// last path: its count, its cells and what `ReadPath` answers.
#[test]
fn a_plan_refused_for_path_capacity_keeps_the_last_path() {
    let mut b = Bench::new();
    // 4000 x 5 cells: two 2-row corridors joined at the east end whose walls leave openings in
    // alternate rows, so the path turns every two cells (about 4000 vertices).
    let (w, h) = (4000u16, 5u16);
    let map = MapParams {
        width_cells: w,
        height_cells: h,
        resolution_m: 0.05,
        robot_radius_m: 0.0,
    };
    assert_eq!(b.call(Request::SetParams(map)), Reply::Ack);
    let mut words = std::vec![0u32; words_for_cells(w as usize * h as usize)];
    let mut set = |x: usize, y: usize| {
        let i = y * w as usize + x;
        words[i / 32] |= 1 << (i % 32);
    };
    for x in 0..w as usize {
        match x % 4 {
            1 => {
                set(x, 1);
                set(x, 4);
            }
            3 => {
                set(x, 0);
                set(x, 3);
            }
            _ => {}
        }
        if x < w as usize - 2 {
            set(x, 2);
        }
    }
    for (i, chunk) in words.chunks(MAP_CHUNK_WORDS).enumerate() {
        let reply = b.call(Request::WriteMap {
            offset_words: (i * MAP_CHUNK_WORDS) as u32,
            words: Vec::from_slice(chunk).unwrap(),
        });
        assert_eq!(reply, Reply::Ack);
    }
    let at = |x: f32, y: f32| PointM::new(x * 0.05 + 0.025, y * 0.05 + 0.025);
    // A short path first: the last path.
    let short = b.call(Request::Plan {
        kind: PlannerKind::AStar,
        start: at(0.0, 0.0),
        goal: at(40.0, 0.0),
    });
    let points = match short {
        Reply::Plan(s) => s.points,
        other => panic!("{other:?}"),
    };
    assert!(points >= 2);
    let read = |b: &mut Bench| match b.call(Request::ReadPath { offset: 0 }) {
        Reply::PathChunk { total, points, .. } => (total, points),
        other => panic!("{other:?}"),
    };
    let path_before = read(&mut b);
    for kind in [PlannerKind::Bfs, PlannerKind::AStar, PlannerKind::AnyAngle] {
        let before = stored(&b);
        let reply = b.call(Request::Plan {
            kind,
            start: at(0.0, 0.0),
            goal: at(0.0, 3.0),
        });
        match reply {
            Reply::Error(e) => {
                assert_eq!(e.code, ErrorCode::PlannerCapacity, "{kind:?}: {e:?}");
                assert_eq!(e.detail, 2, "{kind:?}: the path's capacity: {e:?}");
            }
            other => panic!("{kind:?}: {other:?}"),
        }
        assert_eq!(stored(&b), before, "{kind:?}");
        assert_eq!(b.shell.device.handler.path_points(), points);
        assert_eq!(read(&mut b), path_before, "{kind:?}");
    }
}
