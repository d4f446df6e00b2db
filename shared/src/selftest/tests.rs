//! The self-test's judgement on scripted answers: each fault gives its row's failure and hint.
extern crate std;
use std::vec::Vec;

use super::*;

/// A body that answers from a script: the e-stop, the battery, the homing steps (first,
/// second, third), every ping, each wheel's counts.
struct Scripted {
    estop: Result<bool, StopCause>,
    battery: Result<f32, StopCause>,
    homings: Vec<u32>,
    echo: Result<Echo, StopCause>,
    counts: (i32, i32),
    probes: Vec<Probe>,
}

impl Scripted {
    fn healthy() -> Self {
        let predicted =
            predicted_pulse_counts(&RobotConfig::DEFAULT, PULSE_V, PULSE_ON_MS, COAST_MS);
        Self {
            estop: Ok(false),
            battery: Ok(12.6),
            homings: std::vec![40, 102, 102],
            echo: Ok(Echo::Range(0.8)),
            counts: (predicted as i32, predicted as i32),
            probes: Vec::new(),
        }
    }
}

impl CheckBody for Scripted {
    fn probe(&mut self, probe: Probe) -> Answer {
        self.probes.push(probe);
        match probe {
            Probe::EmergencyStop => Answer::EmergencyStop(self.estop),
            Probe::Battery => Answer::Battery(self.battery),
            Probe::NeckHome => Answer::Neck(Ok(self.homings.remove(0))),
            Probe::NeckTo(_) => Answer::Neck(Ok(100)),
            Probe::Sonar(_) => Answer::Sonar(self.echo),
            Probe::Pulse { side, .. } => Answer::Pulse(Ok(match side {
                Side::Left => self.counts.0,
                Side::Right => self.counts.1,
            })),
        }
    }
}

const BOARD: ClockFacts = ClockFacts {
    core_hz: CORE_CLOCK_HZ,
    source: ClockSource::Crystal,
};

fn run_on(body: &mut Scripted) -> SelfTestReport {
    let mut test = SelfTest::new(&RobotConfig::DEFAULT, BOARD);
    run(&mut test, body).clone()
}

fn row(report: &SelfTestReport, check: Check) -> CheckRow {
    *report
        .rows
        .iter()
        .find(|r| r.check == check)
        .unwrap_or_else(|| panic!("no {check:?} row in {report:?}"))
}

#[test]
fn a_healthy_robot_passes_every_row_in_order() {
    let mut body = Scripted::healthy();
    let report = run_on(&mut body);
    assert!(report.done);
    let names: Vec<_> = report.rows.iter().map(|r| r.check).collect();
    assert_eq!(
        names,
        [
            Check::Clock,
            Check::EmergencyStop,
            Check::Battery,
            Check::Neck,
            Check::Sonar,
            Check::LeftMotor,
            Check::RightMotor
        ]
    );
    assert!(
        report.rows.iter().all(|r| r.status == CheckStatus::Pass),
        "{report:?}"
    );
    assert_eq!(report.failures(), 0);
    assert_eq!(row(&report, Check::Sonar).detail, 0.8);
    // 1 + 1 + 8 neck + 5 pings + 2 pulses.
    assert_eq!(body.probes.len(), 17);
    assert!(body.probes.len() <= MAX_PROBES);
}

#[test]
fn each_fault_fails_its_row_with_its_hint() {
    let mut body = Scripted::healthy();
    body.counts.0 = -body.counts.0;
    let r = run_on(&mut body);
    assert_eq!(row(&r, Check::LeftMotor).status, CheckStatus::Fail);
    assert_eq!(row(&r, Check::LeftMotor).hint, Hint::EncoderBackwards);
    assert_eq!(row(&r, Check::RightMotor).status, CheckStatus::Pass);

    let mut body = Scripted::healthy();
    body.counts.1 *= 4;
    let r = run_on(&mut body);
    assert_eq!(row(&r, Check::RightMotor).hint, Hint::EncoderCountsOff);
    body = Scripted::healthy();
    body.counts.1 = 0;
    assert_eq!(
        row(&run_on(&mut body), Check::RightMotor).hint,
        Hint::EncoderStill
    );

    let mut body = Scripted::healthy();
    body.echo = Ok(Echo::Silent);
    let r = run_on(&mut body);
    assert_eq!(row(&r, Check::Sonar).status, CheckStatus::Fail);
    assert_eq!(row(&r, Check::Sonar).hint, Hint::SonarSilent);
    assert_eq!(row(&r, Check::Sonar).value, 0.0);

    let mut body = Scripted::healthy();
    body.echo = Ok(Echo::NoTarget);
    let r = run_on(&mut body);
    assert_eq!(row(&r, Check::Sonar).status, CheckStatus::Pass);
    assert_eq!(row(&r, Check::Sonar).hint, Hint::SonarNothingInRange);

    let mut body = Scripted::healthy();
    body.homings = std::vec![40, 102, 106];
    let r = run_on(&mut body);
    assert_eq!(row(&r, Check::Neck).status, CheckStatus::Fail);
    assert_eq!(row(&r, Check::Neck).hint, Hint::NeckLosesSteps);
    assert_eq!(row(&r, Check::Neck).value, 4.0);
}

#[test]
fn a_pressed_e_stop_or_a_low_battery_fails_and_skips_the_motors() {
    let mut body = Scripted::healthy();
    body.estop = Ok(true);
    let r = run_on(&mut body);
    assert_eq!(row(&r, Check::EmergencyStop).hint, Hint::EstopPressed);
    for check in [Check::LeftMotor, Check::RightMotor] {
        assert_eq!(row(&r, check).status, CheckStatus::Skip);
        assert_eq!(row(&r, check).hint, Hint::SkippedEstop);
    }
    assert!(
        !body.probes.iter().any(|p| matches!(p, Probe::Pulse { .. })),
        "no pulse"
    );

    let mut body = Scripted::healthy();
    body.battery = Ok(9.8);
    let r = run_on(&mut body);
    assert_eq!(row(&r, Check::Battery).status, CheckStatus::Fail);
    assert_eq!(row(&r, Check::Battery).hint, Hint::BatteryLow);
    assert_eq!(row(&r, Check::LeftMotor).hint, Hint::SkippedBattery);
    assert_eq!(r.failures(), 1);
}

#[test]
fn the_internal_oscillator_fails_the_clock_row() {
    let test = SelfTest::new(
        &RobotConfig::DEFAULT,
        ClockFacts {
            core_hz: CORE_CLOCK_HZ,
            source: ClockSource::Internal,
        },
    );
    assert_eq!(test.report().rows[0].hint, Hint::ClockInternal);
    assert_eq!(test.report().rows[0].status, CheckStatus::Fail);
}

#[test]
fn the_predicted_pulse_matches_the_plant() {
    let config = RobotConfig::DEFAULT;
    let mut plant = crate::plant::Plant::new(&config, crate::control::Pose::default());
    plant.step(PULSE_ON_MS as f32 / 1000.0, PULSE_V, 0.0);
    plant.step(COAST_MS as f32 / 1000.0, 0.0, 0.0);
    let simulated = plant.encoder_counts().0 as f32;
    let predicted = predicted_pulse_counts(&config, PULSE_V, PULSE_ON_MS, COAST_MS);
    assert!(
        (simulated / predicted - 1.0).abs() < 0.02,
        "{simulated} vs {predicted}"
    );
    // 6 V for 0.5 s then 0.3 s of coasting: about 760 counts of 2000 per turn.
    assert!((700.0..800.0).contains(&predicted), "{predicted}");
}

#[test]
fn the_simulated_robot_passes_with_skips_for_what_it_lacks() {
    let config = RobotConfig::DEFAULT;
    let plant = crate::plant::Plant::new(&config, crate::control::Pose::new(1.0, 1.0, 0.0));
    let world = crate::world::Obstacles::new();
    let mut body = simulated::SimulatedCheck::new(&plant, &world, 1.5);
    let clock = ClockFacts {
        core_hz: CORE_CLOCK_HZ,
        source: ClockSource::Emulated,
    };
    let mut test = SelfTest::new(&config, clock);
    let r = run(&mut test, &mut body).clone();
    assert!(r.done);
    assert_eq!(r.failures(), 0, "{r:?}");
    assert_eq!(row(&r, Check::EmergencyStop).status, CheckStatus::Skip);
    assert_eq!(row(&r, Check::Battery).hint, Hint::NotOnThisBuild);
    assert_eq!(row(&r, Check::Neck).status, CheckStatus::Pass);
    assert_eq!(row(&r, Check::Neck).detail, 102.0, "homing from ahead");
    assert_eq!(row(&r, Check::LeftMotor).status, CheckStatus::Pass);
    assert_eq!(
        plant.pose().x_m,
        1.0,
        "a pulse leaves the robot where it stands"
    );
}
