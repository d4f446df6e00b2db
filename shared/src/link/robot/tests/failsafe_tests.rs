//! The device's failsafes over the wire format: a silent host (link-loss policy), a failed
//! control step (controller overrun), the reset cause in `Status`.

use super::*;
use crate::failsafe::{LinkLossPolicy, LinkLossReaction, ResetCause, Sensor, StopCause};

/// A bench whose mission reacts to `timeout_ms` of silence with `reaction`, started.
fn started_with(timeout_ms: u32, reaction: LinkLossReaction) -> Bench {
    let (real, params) = office();
    let mut b = Bench::new();
    let map = MapParams {
        robot_radius_m: params.robot_radius_m,
        ..MapParams::default()
    };
    assert_eq!(b.call(Request::SetParams(map)), Reply::Ack);
    b.upload_world(&real);
    let mut setup = setup(&params, MissionMode::Continuous);
    setup.link_loss = LinkLossPolicy {
        timeout_ms,
        reaction,
    };
    assert_eq!(b.call(Request::SetMission(setup)), Reply::Ack);
    assert_eq!(b.call(Request::StartMission), Reply::Ack);
    b
}

/// Ticks until the mission is no longer running (at most `limit`); how many ran.
fn ticks_until_ended(b: &mut Bench, limit: u32) -> u32 {
    for n in 1..=limit {
        b.tick();
        if b.shell.device.state() != RunState::Running {
            return n;
        }
    }
    limit
}

#[test]
fn heartbeats_keep_the_mission_and_silence_stops_it_within_the_timeout_plus_a_period() {
    let mut b = started_with(2_000, LinkLossReaction::StopAndHold);
    // 20 s of mission with a heartbeat every 500 ms (10 periods): it keeps running.
    for k in 0..400 {
        if k % 10 == 0 {
            assert!(matches!(b.call(Request::MissionStatus), Reply::Mission(_)));
        }
        b.tick();
        assert_eq!(b.shell.device.state(), RunState::Running, "tick {k}");
    }
    // A last request, then the host falls silent: 2 000 ms are 40 periods; the stop comes at
    // the 40th tick.
    assert!(matches!(b.call(Request::MissionStatus), Reply::Mission(_)));
    let heard_at_ms = b.now_ms;
    // A shell that sleeps between turns is told how long it may.
    assert_eq!(b.shell.device.link_loss_in_ms(), Some(2_000));
    let n = ticks_until_ended(&mut b, 100);
    assert_eq!(n, 40, "stopped after {n} silent periods");
    assert_eq!(b.now_ms - heard_at_ms, 2_000);
    assert_eq!(b.shell.device.link_loss_in_ms(), None, "ended");
    let report = b.shell.link().report();
    assert_eq!(report.state, RunState::Ended);
    assert_eq!(report.status, MissionStatus::Aborted);
    assert_eq!(report.stop_cause, StopCause::LinkLost);
    // The pilot was told to stop in that tick: zero volts from the next one on.
    b.tick();
    assert_eq!(b.shell.pilot.as_ref().unwrap().voltages_v(), (0.0, 0.0));
    // The final report travels as telemetry with its cause.
    let finished = b.telemetry.iter().rev().find_map(|t| match t {
        Telemetry::Finished(r) => Some(*r),
        _ => None,
    });
    assert_eq!(finished.map(|r| r.stop_cause), Some(StopCause::LinkLost));
}

#[test]
fn continue_keeps_driving_through_the_silence() {
    let mut b = started_with(500, LinkLossReaction::Continue);
    let mut reactions = 0;
    for _ in 0..200 {
        b.tick();
        if b.shell.link().watch_link().is_some() {
            reactions += 1;
        }
    }
    assert_eq!(b.shell.device.state(), RunState::Running);
    assert_eq!(reactions, 0, "the bench's tick took the one reaction");
    assert!(b.shell.link().link_silent_ms() >= 200 * 50);
    assert_eq!(b.shell.link().report().stop_cause, StopCause::None);
}

#[test]
fn timeout_zero_never_reacts() {
    let mut b = started_with(0, LinkLossReaction::StopAndHold);
    for _ in 0..1_000 {
        b.tick();
    }
    assert_ne!(b.shell.device.state(), RunState::Ended);
}

#[test]
fn a_link_loss_policy_out_of_range_is_refused_by_field() {
    let (_, params) = office();
    let mut b = Bench::new();
    for timeout_ms in [1, 199, 3_600_001, u32::MAX] {
        let mut s = setup(&params, MissionMode::Stop);
        s.link_loss.timeout_ms = timeout_ms;
        assert_eq!(
            b.call(Request::SetMission(s)),
            Reply::Error(ErrorReply::new(ErrorCode::BadMission, 12, 0)),
            "{timeout_ms} ms"
        );
    }
    assert_eq!(b.shell.device.state(), RunState::Idle, "nothing was set up");
}

#[test]
fn a_controller_overrun_ends_the_mission_with_its_cause_and_stops_the_pilot() {
    let mut b = started_with(0, LinkLossReaction::StopAndHold);
    for _ in 0..20 {
        b.tick();
    }
    let _ = b.shell.device.take_pilot_command();
    b.shell.link().fail(StopCause::ControllerOverrun);
    assert_eq!(
        b.shell.device.take_pilot_command(),
        Some(PilotCommand::Stop)
    );
    let report = b.shell.link().report();
    assert_eq!(report.state, RunState::Ended);
    assert_eq!(report.status, MissionStatus::Aborted);
    assert_eq!(report.stop_cause, StopCause::ControllerOverrun);
    // A new mission starts clean.
    assert_eq!(b.call(Request::StartMission), Reply::Ack);
    assert_eq!(b.shell.link().report().stop_cause, StopCause::None);
}

#[test]
fn a_sensor_fault_ends_the_mission_and_crosses_the_wire_with_its_sensor() {
    let mut b = started_with(0, LinkLossReaction::StopAndHold);
    for _ in 0..5 {
        b.tick();
    }
    let _ = b.shell.device.take_pilot_command();
    b.shell
        .link()
        .fail(StopCause::SensorFault(Sensor::NeckHome));
    assert_eq!(
        b.shell.device.take_pilot_command(),
        Some(PilotCommand::Stop)
    );
    // Through the wire format (postcard, COBS, CRC) and back.
    let Reply::Mission(report) = b.call(Request::MissionStatus) else {
        panic!("a mission report");
    };
    assert_eq!(report.status, MissionStatus::Aborted);
    assert_eq!(report.stop_cause, StopCause::SensorFault(Sensor::NeckHome));
    for sensor in [
        Sensor::NeckHome,
        Sensor::Neck,
        Sensor::SonarTrigger,
        Sensor::SonarSilent,
        Sensor::Battery,
        Sensor::Motor,
        Sensor::EmergencyStopInput,
    ] {
        let cause = StopCause::SensorFault(sensor);
        let mut buf = [0u8; 8];
        let bytes = postcard::to_slice(&cause, &mut buf).unwrap();
        // docs/protocol.md: StopCause 5, then the sensor's index.
        assert_eq!(bytes[0], 5);
        assert_eq!(postcard::from_bytes::<StopCause>(bytes).unwrap(), cause);
    }
}

#[test]
fn the_emergency_stop_input_latches_like_the_request() {
    let mut b = started_with(0, LinkLossReaction::StopAndHold);
    b.tick();
    let _ = b.shell.device.take_pilot_command();
    b.shell.link().fail(StopCause::EmergencyStop);
    assert_eq!(
        b.shell.device.take_pilot_command(),
        Some(PilotCommand::Stop)
    );
    let report = b.shell.link().report();
    assert_eq!(report.stop_cause, StopCause::EmergencyStop);
    assert!(report.emergency_stop);
    // A new mission waits for the host to clear the stop.
    assert!(matches!(b.call(Request::StartMission), Reply::Error(_)));
    assert_eq!(b.call(Request::ClearEmergencyStop), Reply::Ack);
    assert_eq!(b.call(Request::StartMission), Reply::Ack);
}

#[test]
fn status_reports_the_reset_cause() {
    let mut b = Bench::new();
    let Reply::Status(before) = b.call(Request::Status) else {
        panic!("no status");
    };
    assert_eq!(before.reset_cause, ResetCause::Unknown);
    b.shell
        .device
        .handler
        .set_reset_cause(ResetCause::IndependentWatchdog);
    let Reply::Status(after) = b.call(Request::Status) else {
        panic!("no status");
    };
    assert_eq!(after.reset_cause, ResetCause::IndependentWatchdog);
}
