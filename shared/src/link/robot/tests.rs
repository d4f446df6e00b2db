//! RobotDevice tests: whole missions over the wire format against the simulated robot, and
//! requests in the wrong state.
extern crate std;

use std::boxed::Box;
use std::vec::Vec as StdVec;

use super::*;
use crate::grid::{words_for_cells, Grid, GridGeometry};
use crate::link::frame::{encode, FrameDecoder, MAX_FRAME_BYTES};
use crate::mission::{
    DeviceShell300, LocalRunner, Mission300, MissionMode, MissionPlanner300, SimBody,
};
use crate::plan::PlannerKind;
use crate::raster::mark_point_m;
use crate::world::Obstacles;

type TestDevice = RobotDevice<{ words_for_cells(300 * 300) }>;

/// The host side of the link around the core's [`DeviceShell300`] (the in-process device's
/// shell), on a simulated clock: one control period of 50 ms per tick.
pub(super) struct Bench {
    pub(super) shell: Box<DeviceShell300>,
    pub(super) decoder: FrameDecoder,
    pub(super) seq: u16,
    pub(super) telemetry: StdVec<Telemetry>,
    /// The shell's clock, milliseconds: one control period per tick.
    pub(super) now_ms: u32,
}

impl Bench {
    pub(super) fn new() -> Self {
        Self {
            shell: Box::new(DeviceShell300::new(DeviceInfo::default())),
            decoder: FrameDecoder::new(),
            seq: 0,
            telemetry: StdVec::new(),
            now_ms: 0,
        }
    }

    /// One request through the wire format; its reply (telemetry on the way is kept). The
    /// pilot command a request leads to stays with the device (the tests take it).
    pub(super) fn call(&mut self, request: Request) -> Reply {
        self.seq = self.seq.wrapping_add(1);
        let mut wire = [0u8; MAX_FRAME_BYTES];
        let bytes = encode(
            &RequestFrame {
                seq: self.seq,
                request,
            },
            &mut wire,
        )
        .unwrap()
        .to_vec();
        let mut out = StdVec::new();
        self.shell
            .receive(&bytes, None, &mut |b: &[u8]| out.extend_from_slice(b));
        let mut replies = StdVec::new();
        for frame in self.decode(&out) {
            match frame {
                DeviceFrame::Reply { seq, reply } => {
                    assert_eq!(seq, Some(self.seq));
                    replies.push(reply);
                }
                DeviceFrame::Telemetry(t) => self.telemetry.push(t),
            }
        }
        assert_eq!(replies.len(), 1, "one reply per request");
        replies.pop().unwrap()
    }

    fn decode(&mut self, bytes: &[u8]) -> StdVec<DeviceFrame> {
        let mut frames = StdVec::new();
        let mut rest = bytes;
        while !rest.is_empty() {
            let (got, r) = self.decoder.feed::<DeviceFrame>(rest);
            rest = r;
            if let Some(got) = got {
                frames.push(got.expect("the device sends valid frames"));
            }
        }
        frames
    }

    pub(super) fn upload_world(&mut self, world: &Obstacles) {
        for polygon in world.iter() {
            let chunks: StdVec<&[PointM]> = polygon.chunks(OBSTACLE_CHUNK_VERTICES).collect();
            for (i, chunk) in chunks.iter().enumerate() {
                let reply = self.call(Request::WorldChunk {
                    first_vertex: (i * OBSTACLE_CHUNK_VERTICES) as u16,
                    vertices: Vec::from_slice(chunk).unwrap(),
                    last: i + 1 == chunks.len(),
                });
                assert!(matches!(reply, Reply::Obstacles { .. }), "{reply:?}");
            }
        }
    }

    /// One control period (the link watched first, its reaction left to the shell's serve);
    /// the telemetry it produced goes through the wire format.
    pub(super) fn tick(&mut self) {
        self.now_ms += 50;
        self.shell.device.set_now_ms(self.now_ms);
        self.shell.link().watch_link();
        self.shell.tick(0.05);
        let mut out = StdVec::new();
        self.shell
            .send_telemetry(&mut |b: &[u8]| out.extend_from_slice(b));
        for frame in self.decode(&out) {
            match frame {
                DeviceFrame::Telemetry(t) => self.telemetry.push(t),
                other => panic!("unasked reply {other:?}"),
            }
        }
    }
}

pub(super) fn office() -> (Obstacles, crate::world::Params) {
    let mut real = Obstacles::new();
    crate::world::parse_da(include_str!("../../../../worlds/office.da"), &mut real).unwrap();
    let params = crate::world::parse_par(include_str!("../../../../worlds/office.par")).unwrap();
    (real, params)
}

pub(super) fn setup(params: &crate::world::Params, mode: MissionMode) -> MissionSetup {
    MissionSetup::from_params(params, mode)
}

/// A ready bench: map, radius, real world, the mission set up.
pub(super) fn ready(mode: MissionMode) -> (Bench, Obstacles, crate::world::Params) {
    let (real, params) = office();
    let mut b = Bench::new();
    let map = MapParams {
        robot_radius_m: params.robot_radius_m,
        ..MapParams::default()
    };
    assert_eq!(b.call(Request::SetParams(map)), Reply::Ack);
    b.upload_world(&real);
    assert_eq!(
        b.call(Request::SetMission(setup(&params, mode))),
        Reply::Ack
    );
    (b, real, params)
}

#[test]
fn a_mission_over_the_link_runs_exactly_like_the_simulator_and_its_telemetry_rebuilds_the_map() {
    for mode in [MissionMode::Stop, MissionMode::Continuous] {
        let (mut b, real, params) = ready(mode);
        assert_eq!(b.call(Request::StartMission), Reply::Ack);
        for _ in 0..40_000 {
            b.tick();
            if b.shell.device.state() == RunState::Ended {
                break;
            }
        }
        let report = b.shell.link().report();
        assert_eq!(report.status, MissionStatus::Reached, "{mode:?} {report:?}");

        // The same mission in the simulator's shell.
        let config = *b.shell.mission.config();
        let mut mission = Box::new(Mission300::new(config, GridGeometry::seed_default()).unwrap());
        let mut planner = Box::new(MissionPlanner300::new());
        let mut runner = LocalRunner::new(&mut mission, &mut planner, 0);
        runner.run_on(&mut SimBody::at_start(&config), &real, 1.5, 0.05);
        assert_eq!(runner.mission().stats(), report.stats, "{mode:?}");

        // The telemetry: phases in order, a final report, poses at 5 Hz, and the hits of every
        // sweep, which marked with the planning radius give the device's map.
        let finished: StdVec<_> = b
            .telemetry
            .iter()
            .filter_map(|t| match t {
                Telemetry::Finished(r) => Some(*r),
                _ => None,
            })
            .collect();
        assert_eq!(finished.len(), 1);
        assert_eq!(finished[0].stats, report.stats);
        assert!(matches!(b.telemetry.last(), Some(Telemetry::Finished(_))));
        let poses = b
            .telemetry
            .iter()
            .filter(|t| matches!(t, Telemetry::Pose(_)))
            .count() as f32;
        let expected = report.stats.time_s * 5.0;
        assert!(
            (poses - expected).abs() <= 2.0,
            "{poses} poses in {} s",
            report.stats.time_s
        );
        let mut map = Box::new(
            Grid::<{ words_for_cells(300 * 300) }>::new(GridGeometry::seed_default()).unwrap(),
        );
        let half = GridGeometry::seed_default().expansion_cells(params.robot_radius_m);
        let mut sweeps = 0;
        for t in &b.telemetry {
            if let Telemetry::SweepHits { hits, first, .. } = t {
                if *first == 0 {
                    sweeps += 1;
                }
                for p in hits {
                    mark_point_m(&mut map, *p, half);
                }
            }
        }
        // Every sweep started was reported, but one still under way when the goal was reached.
        // A full sweep where the robot just swept counts with that stop, so the sweeps started
        // lie between one per stop and one more per full sweep.
        let least = report.stats.stops + report.stats.moving_sweeps;
        let most = least + report.stats.full_sweeps;
        assert!(
            sweeps + 1 >= least && sweeps <= most,
            "{mode:?}: {sweeps} sweeps, stops and moving sweeps {least}, full {}",
            report.stats.full_sweeps
        );
        assert_eq!(&*map, b.shell.mission.grid(), "{mode:?}");
        let planned = b
            .telemetry
            .iter()
            .filter(|t| matches!(t, Telemetry::Planned { .. }))
            .count() as u32;
        assert_eq!(planned, report.stats.plans, "{mode:?}");
    }
}

#[test]
fn abort_and_emergency_stop_put_zero_volts_on_the_motors_at_the_next_tick() {
    for request in [Request::AbortMission, Request::EmergencyStop] {
        let (mut b, _, _) = ready(MissionMode::Continuous);
        assert_eq!(b.call(Request::StartMission), Reply::Ack);
        // Run until the robot drives.
        let mut driving = false;
        for _ in 0..2_000 {
            b.tick();
            let (l, r) = b.shell.pilot.as_ref().unwrap().voltages_v();
            if l.abs() > 1.0 && r.abs() > 1.0 {
                driving = true;
                break;
            }
        }
        assert!(driving);
        let stop_requested = request.clone();
        assert_eq!(b.call(request), Reply::Ack);
        // The shell hands the command to the pilot before its next tick.
        assert_eq!(
            b.shell.device.take_pilot_command(),
            Some(PilotCommand::Stop)
        );
        b.shell.pilot.as_mut().unwrap().stop();
        b.tick();
        assert_eq!(b.shell.pilot.as_ref().unwrap().voltages_v(), (0.0, 0.0));
        assert_eq!(b.shell.device.state(), RunState::Ended);
        let report = b.shell.link().report();
        assert_eq!(report.status, MissionStatus::Aborted);
        let cause = if stop_requested == Request::EmergencyStop {
            crate::failsafe::StopCause::EmergencyStop
        } else {
            crate::failsafe::StopCause::Host
        };
        assert_eq!(report.stop_cause, cause);
        // A new start is allowed after an abort, not after an emergency stop until cleared.
        let again = b.call(Request::StartMission);
        if stop_requested == Request::EmergencyStop {
            assert!(
                matches!(
                    again,
                    Reply::Error(ErrorReply {
                        code: ErrorCode::WrongState,
                        detail: 1,
                        ..
                    })
                ),
                "{again:?}"
            );
            assert_eq!(b.call(Request::ClearEmergencyStop), Reply::Ack);
            assert_eq!(b.call(Request::StartMission), Reply::Ack);
        } else {
            assert_eq!(again, Reply::Ack);
        }
    }
}

#[test]
fn requests_in_the_wrong_state_are_refused_and_change_nothing() {
    let (real, params) = office();
    let mut b = Bench::new();
    let code = |r: Reply| match r {
        Reply::Error(e) => Some(e.code),
        _ => None,
    };
    assert_eq!(
        code(b.call(Request::StartMission)),
        Some(ErrorCode::WrongState)
    );
    assert_eq!(
        code(b.call(Request::PauseMission)),
        Some(ErrorCode::WrongState)
    );
    // No SetParams yet: a radius of 0 is below the safe radius (robot config field 0).
    assert_eq!(
        b.call(Request::SetMission(setup(&params, MissionMode::Stop))),
        Reply::Error(ErrorReply::new(ErrorCode::BadMission, 100, 0))
    );
    let map = MapParams {
        robot_radius_m: params.robot_radius_m,
        ..MapParams::default()
    };
    assert_eq!(b.call(Request::SetParams(map)), Reply::Ack);
    // A goal off the map, a NaN speed, a speed above the safe bound: refused, naming the
    // field (and for the speed, the bound in mm/s).
    // Off the map: `value` names the field (2 start, 4 goal), `detail` 1.
    for (field, start, goal) in [
        (4, params.start, PointM::new(99.0, 1.0)),
        (2, PointM::new(-1.0, 1.0), params.goal),
    ] {
        let mut bad = setup(&params, MissionMode::Stop);
        bad.start = start;
        bad.goal = goal;
        assert_eq!(
            b.call(Request::SetMission(bad)),
            Reply::Error(ErrorReply {
                code: ErrorCode::BadMission,
                value: field,
                limit: 0,
                detail: 1
            })
        );
    }
    let mut bad = setup(&params, MissionMode::Stop);
    bad.speed_m_s = f32::NAN;
    assert_eq!(
        b.call(Request::SetMission(bad)),
        Reply::Error(ErrorReply::new(ErrorCode::BadMission, 5, 364))
    );
    bad.speed_m_s = 0.5;
    assert_eq!(
        b.call(Request::SetMission(bad)),
        Reply::Error(ErrorReply::new(ErrorCode::BadMission, 5, 364))
    );
    assert_eq!(b.shell.device.state(), RunState::Idle);
    b.upload_world(&real);
    assert_eq!(
        b.call(Request::SetMission(setup(&params, MissionMode::Stop))),
        Reply::Ack
    );
    assert_eq!(b.call(Request::StartMission), Reply::Ack);
    // While it runs: no new setup, no map change, no planning service, no world upload.
    let occupied = b.shell.mission.grid().count_occupied();
    for request in [
        Request::SetMission(setup(&params, MissionMode::Stop)),
        Request::ClearMap,
        Request::Plan {
            kind: PlannerKind::AStar,
            start: params.start,
            goal: params.goal,
        },
        Request::ClearWorld,
        Request::StartMission,
        Request::ResumeMission,
    ] {
        assert_eq!(code(b.call(request)), Some(ErrorCode::WrongState));
    }
    assert_eq!(b.shell.mission.grid().count_occupied(), occupied);
    assert_eq!(b.shell.world.obstacles.len(), real.len());
    // Pause holds the robot and stops the mission's clock; resume sweeps afresh.
    for _ in 0..100 {
        b.tick();
    }
    assert_eq!(b.call(Request::PauseMission), Reply::Ack);
    assert_eq!(
        b.shell.device.take_pilot_command(),
        Some(PilotCommand::Hold)
    );
    b.shell.pilot.as_mut().unwrap().hold();
    let t = b.shell.mission.stats().time_s;
    for _ in 0..50 {
        b.tick();
    }
    assert_eq!(b.shell.mission.stats().time_s, t);
    assert_eq!(b.call(Request::ResumeMission), Reply::Ack);
    assert_eq!(
        b.shell.mission.phase(),
        crate::mission::MissionPhase::Sweep { full: false }
    );
    match b.call(Request::MissionStatus) {
        Reply::Mission(r) => assert_eq!(r.state, RunState::Running),
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_board_refuses_the_real_world() {
    let mut device = Box::new(TestDevice::new(DeviceInfo::default()));
    let mut mission = Box::new(Mission300::IDLE);
    let mut planner = Box::new(MissionPlanner300::new());
    let mut wire = [0u8; MAX_FRAME_BYTES];
    let bytes = encode(
        &RequestFrame {
            seq: 9,
            request: Request::ClearWorld,
        },
        &mut wire,
    )
    .unwrap()
    .to_vec();
    let mut out = StdVec::new();
    device.link(&mut mission).receive(
        &bytes,
        &mut *planner,
        &mut || 0,
        &mut NoWorld,
        &mut |b: &[u8]| out.extend_from_slice(b),
    );
    let (got, _) = FrameDecoder::new().feed::<DeviceFrame>(&out);
    assert_eq!(
        got,
        Some(Ok(DeviceFrame::Reply {
            seq: Some(9),
            reply: Reply::Error(ErrorReply::new(ErrorCode::NotOnThisBuild, 0, 0))
        }))
    );
}

#[test]
fn the_largest_mission_messages_fit_a_frame() {
    let full: Vec<PointM, TELEMETRY_CHUNK_POINTS> =
        Vec::from_slice(&[PointM::new(-1.0e9, 1.0e9); TELEMETRY_CHUNK_POINTS]).unwrap();
    let report = MissionReport {
        state: RunState::Ended,
        status: MissionStatus::Unreachable,
        phase: crate::mission::MissionPhase::Sweep { full: true },
        stats: crate::mission::MissionStats {
            stops: u32::MAX,
            moving_sweeps: u32::MAX,
            full_sweeps: u32::MAX,
            plans: u32::MAX,
            replans: u32::MAX,
            blocked_replans: u32::MAX,
            band_cuts: u32::MAX,
            blind_cuts: u32::MAX,
            readings: u32::MAX,
            hits: u32::MAX,
            odometry_distance_m: f32::MAX,
            time_s: f32::MAX,
            controller_overruns: u32::MAX,
            saturated_periods: u32::MAX,
            unreachable_reason: Some(crate::mission::UnreachableReason::NoProgress),
            plan_errors: u32::MAX,
            last_plan_error: None,
        },
        max_control_instructions: u64::MAX,
        max_plan_instructions: u64::MAX,
        max_turn_instructions: u64::MAX,
        stack_high_water_bytes: u32::MAX,
        stop_ticks: u32::MAX,
        emergency_stop: true,
        stop_cause: crate::failsafe::StopCause::ControllerOverrun,
        stop_latency_us: u32::MAX,
    };
    let frames = [
        DeviceFrame::Telemetry(Telemetry::SweepHits {
            sweep: u32::MAX,
            first: u16::MAX,
            total: u16::MAX,
            hits: full.clone(),
        }),
        DeviceFrame::Telemetry(Telemetry::Path {
            plan: u32::MAX,
            first: u16::MAX,
            total: u16::MAX,
            points: full,
        }),
        DeviceFrame::Telemetry(Telemetry::Finished(report)),
        DeviceFrame::Reply {
            seq: Some(u16::MAX),
            reply: Reply::Mission(report),
        },
    ];
    for frame in frames {
        let mut out = [0u8; MAX_FRAME_BYTES];
        assert!(encode(&frame, &mut out).is_ok(), "{frame:?}");
    }
    let setup = MissionSetup {
        mode: MissionMode::Continuous,
        planner: PlannerKind::AnyAngle,
        start: PointM::new(f32::MAX, f32::MAX),
        initial_heading_rad: f32::MAX,
        goal: PointM::new(f32::MAX, f32::MAX),
        speed_m_s: f32::MAX,
        sonar_range_m: f32::MAX,
        time_limit_s: f32::MAX,
        constant_depth_filter: true,
        trust_seen_space: true,
        noise_seed: u64::MAX,
        sonar_noise_std_m: f32::MAX,
        link_loss: crate::failsafe::LinkLossPolicy {
            timeout_ms: u32::MAX,
            reaction: crate::failsafe::LinkLossReaction::StopAndHold,
        },
        sonar_beam: true,
        beam_half_angle_deg: f32::MAX,
        incidence_limit_deg: f32::MAX,
        settle: crate::mission::SettleRule::SeedCode,
        reference_feed_forward: true,
        turn_in_place: true,
        sweep_layout: crate::sonar::SweepLayout::Seed,
        evidence_map: true,
        sonar_dropout_probability: f32::MAX,
        sonar_spurious_probability: f32::MAX,
    };
    let mut out = [0u8; MAX_FRAME_BYTES];
    assert!(encode(
        &RequestFrame {
            seq: u16::MAX,
            request: Request::SetMission(setup)
        },
        &mut out
    )
    .is_ok());
}

mod failsafe_tests;
