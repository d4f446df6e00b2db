//! The bring-up self-test (`twil check`, `twil_core::selftest`) on the board's drivers over the
//! scripted world: a healthy robot passes every row within a bounded time, and each wiring
//! fault (an encoder's A/B swapped, a dead sonar, the e-stop pressed, a low battery) fails its
//! row with the hint a user acts on.

use twil_core::robot::RobotConfig;
use twil_core::selftest::board::BoardCheck;
use twil_core::selftest::{
    run, Check, CheckRow, CheckStatus, ClockFacts, ClockSource, Hint, SelfTest, SelfTestReport,
    CORE_CLOCK_HZ,
};
use twil_host::cmd::check::hint_text;

use super::world::{Delay, World};
use super::{chassis, head};

/// Forward counts per second per volt of the default robot's wheel: 0.8 rad/s per volt at
/// 2000 counts per turn.
const COUNTS_PER_S_PER_V: f64 = 0.8 * 2000.0 / (2.0 * std::f64::consts::PI);

/// A room with a wall 0.8 m ahead (seen within ±70°), wheels lifted and driven by their motors.
fn healthy_world() -> World {
    let w = World::new();
    {
        let mut s = w.0.borrow_mut();
        s.range_at_deg = Box::new(|deg| (deg.abs() < 70.0).then_some(0.8));
        s.counts_per_s_per_v = [COUNTS_PER_S_PER_V; 2];
    }
    w
}

/// The self-test on the board's chassis and head in `w`; its report and the seconds it took.
fn check(w: &World) -> (SelfTestReport, f64) {
    let config = RobotConfig::DEFAULT;
    let (mut chassis, mut head) = (chassis(w), head(w));
    let mut body = BoardCheck {
        chassis: &mut chassis,
        head: &mut head,
        delay: Delay(w.clone()),
        config,
    };
    let clock = ClockFacts {
        core_hz: CORE_CLOCK_HZ,
        source: ClockSource::Crystal,
    };
    let start_ns = w.now_ns();
    let mut test = SelfTest::new(&config, clock);
    let report = run(&mut test, &mut body).clone();
    assert!(report.done);
    // Both motors off at the end.
    assert_eq!(w.0.borrow().duty[0].0, 0);
    assert_eq!(w.0.borrow().duty[1].0, 0);
    (report, (w.now_ns() - start_ns) as f64 * 1e-9)
}

fn row(report: &SelfTestReport, check: Check) -> CheckRow {
    *report
        .rows
        .iter()
        .find(|r| r.check == check)
        .unwrap_or_else(|| panic!("no {check:?} in {report:?}"))
}

#[test]
fn a_healthy_board_passes_every_check_within_seven_seconds() {
    let w = healthy_world();
    let (report, took_s) = check(&w);
    assert!(
        report.rows.iter().all(|r| r.status == CheckStatus::Pass),
        "{report:#?}"
    );
    let nearest_m = row(&report, Check::Sonar).detail;
    assert!((nearest_m - 0.8).abs() < 0.005, "the wall: {nearest_m} m");
    assert_eq!(
        row(&report, Check::Neck).detail,
        102.0,
        "homing from 0° to the switch"
    );
    let left = row(&report, Check::LeftMotor);
    assert!(
        (left.value / left.detail - 1.0).abs() < 0.1,
        "measured {} vs predicted {}",
        left.value,
        left.detail
    );
    // The neck ends at the sweep's last angle (60° = 33 steps), no step lost on the way, none
    // refused by the driver's timing.
    let s = w.0.borrow();
    assert_eq!(s.neck_steps, 33);
    assert_eq!((s.setup_violations, s.short_step_pulses), (0, 0));
    assert_eq!(s.pings.len(), 5);
    println!("the board's self-test took {took_s:.2} s of the world's time");
    assert!((3.0..7.0).contains(&took_s), "{took_s} s");
}

#[test]
fn a_swapped_encoder_fails_its_wheel_with_the_swap_hint() {
    let w = healthy_world();
    w.0.borrow_mut().encoder_swapped[0] = true;
    let (report, _) = check(&w);
    let left = row(&report, Check::LeftMotor);
    assert_eq!(
        (left.status, left.hint),
        (CheckStatus::Fail, Hint::EncoderBackwards)
    );
    assert!(left.value < 0.0, "{left:?}");
    let text = hint_text(Check::LeftMotor, left.hint).unwrap();
    assert!(
        text.starts_with("left encoder counts backwards: ")
            && text.contains("swap the encoder's A/B wires (PA6/PA7)"),
        "{text}"
    );
    assert_eq!(row(&report, Check::RightMotor).status, CheckStatus::Pass);
    assert_eq!(report.failures(), 1);
}

#[test]
fn a_dead_sonar_fails_the_sonar_with_its_wiring_hint() {
    let w = healthy_world();
    w.0.borrow_mut().sonar_answers = false;
    let (report, _) = check(&w);
    let sonar = row(&report, Check::Sonar);
    assert_eq!(
        (sonar.status, sonar.hint),
        (CheckStatus::Fail, Hint::SonarSilent)
    );
    assert_eq!(sonar.value, 0.0, "no ping answered");
    assert!(hint_text(Check::Sonar, sonar.hint)
        .unwrap()
        .contains("echo line"));
    assert_eq!(report.failures(), 1);
}

#[test]
fn a_pressed_e_stop_fails_and_no_wheel_turns() {
    let w = healthy_world();
    w.0.borrow_mut().estop_pressed_at_ns = vec![(0, u64::MAX)];
    let (report, _) = check(&w);
    let estop = row(&report, Check::EmergencyStop);
    assert_eq!(
        (estop.status, estop.hint),
        (CheckStatus::Fail, Hint::EstopPressed)
    );
    for side in [Check::LeftMotor, Check::RightMotor] {
        assert_eq!(row(&report, side).status, CheckStatus::Skip);
        assert_eq!(row(&report, side).hint, Hint::SkippedEstop);
    }
    assert!(
        w.0.borrow().duty_log.iter().all(|&(_, _, duty)| duty == 0),
        "no duty while pressed"
    );
    assert!(hint_text(Check::EmergencyStop, estop.hint)
        .unwrap()
        .contains("release"));
}

#[test]
fn a_low_battery_fails_and_skips_the_wheels() {
    let w = healthy_world();
    w.0.borrow_mut().battery_v = 9.8;
    let (report, _) = check(&w);
    let battery = row(&report, Check::Battery);
    assert_eq!(
        (battery.status, battery.hint),
        (CheckStatus::Fail, Hint::BatteryLow)
    );
    assert!((battery.value - 9.8).abs() < 1e-4);
    assert_eq!(row(&report, Check::LeftMotor).hint, Hint::SkippedBattery);
    assert!(hint_text(Check::Battery, battery.hint)
        .unwrap()
        .contains("10.5 V"));
    assert_eq!(report.failures(), 1);
}
