//! `twil check --remote …`: the bring-up self-test (issue 25 part 3). The host checks the link
//! (protocol version, a round trip) and reads the reset cause; the device runs
//! `twil_core::selftest` on its body (the board's drivers, or the simulated robot under QEMU
//! and `--remote sim`) and the host polls its report. One row per check, `pass` / `fail` /
//! `skip`, with the measured value, the expected one and a hint; `--json` prints
//! `{"checks":[{"name","status","value","expected","hint"}]}`. Exit 0 when nothing fails, 1
//! (with a line naming the failed checks) otherwise. The device refuses the test while a
//! mission runs.
//!
//! Time: the board's probes take 5.5 s with the default robot (measured on the virtual board;
//! `twil_core::selftest` module docs); a simulated device answers at once. The host gives up
//! after [`CHECK_TIMEOUT`].

use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use twil_core::failsafe::ResetCause;
use twil_core::link::{Build, Reply, Request, PROTOCOL_VERSION};
use twil_core::selftest::{Check, CheckRow, CheckStatus, Hint, SelfTestReport};

use crate::remote::{Remote, RemoteSpec};

/// How long the host waits for the device's report.
pub const CHECK_TIMEOUT: Duration = Duration::from_secs(30);
/// Between two polls of the report.
const POLL_EVERY: Duration = Duration::from_millis(100);
/// QEMU at the chip's pace, as for missions.
const QEMU_ICOUNT_SHIFT: u8 = 3;

/// Arguments of `twil check`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The device: `qemu` (starts QEMU with the firmware), `sim` (in this process),
    /// `tcp:HOST:PORT`, or a serial port (`/dev/ttyUSB0`, 115200 8N1).
    #[arg(long)]
    pub remote: RemoteSpec,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
}

/// One printed row.
struct Line {
    name: &'static str,
    status: &'static str,
    value: String,
    expected: String,
    hint: Option<String>,
}

/// Run `twil check`.
pub fn run(args: Args) -> Result<crate::exit::Ending> {
    let (mut remote, info) = Remote::connect_paced(&args.remote, QEMU_ICOUNT_SHIFT)?;
    let round_trip = remote.ping(0x00c4_ec00)?;
    let mut lines = vec![Line {
        name: "link",
        status: "pass",
        value: format!("protocol v{}", info.protocol_version),
        expected: format!("protocol v{PROTOCOL_VERSION}"),
        // In the last column, which is not padded: a round trip of 10 ms or more (a loaded CI
        // machine) widened the value column and shifted every row after it.
        hint: Some(format!(
            "round trip {:.1} ms",
            round_trip.as_secs_f64() * 1e3
        )),
    }];
    let reset = match remote.call(Request::Status)? {
        Reply::Status(status) => status.reset_cause,
        other => bail!("unexpected reply to Status: {other:?}"),
    };
    lines.push(reset_line(reset));
    let report = self_test(&mut remote)?;
    lines.extend(report.rows.iter().map(line_of));
    let failed: Vec<&str> = lines
        .iter()
        .filter(|l| l.status == "fail")
        .map(|l| l.name)
        .collect();
    if args.json {
        let checks: Vec<_> = lines
            .iter()
            .map(|l| {
                serde_json::json!({
                    "name": l.name,
                    "status": l.status,
                    "value": l.value,
                    "expected": l.expected,
                    "hint": l.hint,
                })
            })
            .collect();
        println!("{}", serde_json::json!({ "checks": checks }));
    } else {
        let who = match info.build {
            Build::Hardware => "the board",
            Build::Qemu => "the firmware under QEMU (simulated robot)",
            Build::Host => "the in-process device (simulated robot)",
        };
        println!("twil check: {who}");
        print_table(&lines);
    }
    if !failed.is_empty() {
        bail!(
            "{} of {} checks failed: {}",
            failed.len(),
            lines.len(),
            failed.join(", ")
        );
    }
    Ok(crate::exit::Ending::Done)
}

/// Ask for the self-test and poll its report until done.
fn self_test(remote: &mut Remote) -> Result<SelfTestReport> {
    remote
        .call(Request::SelfTest)
        .context("the device refused the self-test")?;
    let deadline = Instant::now() + CHECK_TIMEOUT;
    loop {
        match remote.call(Request::SelfTestReport)? {
            Reply::SelfTest(report) if report.done => return Ok(report),
            Reply::SelfTest(_) => {}
            other => bail!("unexpected reply to SelfTestReport: {other:?}"),
        }
        if Instant::now() > deadline {
            bail!(
                "the device's self-test did not finish within {} s",
                CHECK_TIMEOUT.as_secs()
            );
        }
        std::thread::sleep(POLL_EVERY);
    }
}

fn print_table(lines: &[Line]) {
    let width = |f: &dyn Fn(&Line) -> usize| lines.iter().map(f).max().unwrap_or(0);
    let (wn, wv, we) = (
        width(&|l| l.name.len()).max(5),
        width(&|l| l.value.chars().count()).max(5),
        width(&|l| l.expected.chars().count()).max(8),
    );
    println!(
        "{:wn$}  {:6}  {:wv$}  {:we$}  hint",
        "check", "status", "value", "expected"
    );
    for l in lines {
        let row = format!(
            "{:wn$}  {:6}  {:wv$}  {:we$}  {}",
            l.name,
            l.status,
            l.value,
            l.expected,
            l.hint.as_deref().unwrap_or("")
        );
        println!("{}", row.trim_end());
    }
}

fn status_name(status: CheckStatus) -> &'static str {
    match status {
        CheckStatus::Pass => "pass",
        CheckStatus::Fail => "fail",
        CheckStatus::Skip => "skip",
    }
}

fn reset_line(cause: ResetCause) -> Line {
    let (status, hint) = match cause {
        ResetCause::Brownout => (
            "fail",
            Some("the supply sagged below 2.7 V: check the regulator and the battery's wiring"),
        ),
        ResetCause::IndependentWatchdog | ResetCause::WindowWatchdog => (
            "fail",
            Some("a task stopped making progress: read the device's log (cargo run) before the reset"),
        ),
        _ => ("pass", None),
    };
    Line {
        name: "reset_cause",
        status,
        value: format!("{cause:?}")
            .chars()
            .flat_map(|c| {
                // CamelCase to words: `PowerOn` -> `power on`.
                let lower = c.to_ascii_lowercase();
                if c.is_ascii_uppercase() {
                    vec![' ', lower]
                } else {
                    vec![c]
                }
            })
            .collect::<String>()
            .trim()
            .to_string(),
        expected: "not a watchdog or brown-out".into(),
        hint: hint.map(str::to_string),
    }
}

/// A number or a dash.
fn or_dash(value: f32, text: impl FnOnce(f32) -> String) -> String {
    if value.is_nan() {
        "—".into()
    } else {
        text(value)
    }
}

fn line_of(row: &CheckRow) -> Line {
    let v = row.value;
    let (value, expected) = match row.check {
        Check::Clock => (
            or_dash(v, |v| format!("{:.0} MHz", v / 1e6)),
            format!("{:.0} MHz", row.expected_min / 1e6),
        ),
        Check::EmergencyStop => (
            or_dash(v, |v| if v > 0.5 { "pressed" } else { "released" }.into()),
            "released".into(),
        ),
        Check::Battery => (
            or_dash(v, |v| format!("{v:.2} V")),
            format!("{} … {} V", row.expected_min, row.expected_max),
        ),
        Check::Neck => (
            or_dash(v, |v| {
                format!("{v:.0} steps lost, homing {:.0} steps", row.detail)
            }),
            format!("at most {:.0} step lost", row.expected_max),
        ),
        Check::Sonar => (
            or_dash(v, |v| {
                let nearest = or_dash(row.detail, |d| format!("nearest {d:.2} m"));
                let nearest = if row.detail.is_nan() {
                    "nothing in range".into()
                } else {
                    nearest
                };
                format!("{v:.0}/{:.0} answered, {nearest}", row.expected_max)
            }),
            format!("{:.0}/{:.0} answered", row.expected_max, row.expected_max),
        ),
        Check::LeftMotor | Check::RightMotor => (
            or_dash(v, |v| format!("{v:.0} counts")),
            or_dash(row.expected_min, |lo| {
                format!(
                    "{lo:.0} … {:.0} counts forward (predicted {:.0})",
                    row.expected_max, row.detail
                )
            }),
        ),
    };
    Line {
        name: row.check.name(),
        status: status_name(row.status),
        value,
        expected,
        hint: hint_text(row.check, row.hint),
    }
}

/// The words of a hint; motor rows name their side and pins (docs/firmware.md's wiring table).
pub fn hint_text(check: Check, hint: Hint) -> Option<String> {
    let (side, encoder_pins, motor_pins) = match check {
        Check::RightMotor => ("right", "PB6/PB7", "PB15 PWM, PB13 dir"),
        _ => ("left", "PA6/PA7", "PB14 PWM, PB12 dir"),
    };
    Some(match hint {
        Hint::None => return None,
        Hint::ClockInternal => "the 8 MHz crystal did not start: the PLL runs from the internal oscillator (±1 %); check the crystal and its capacitors".into(),
        Hint::EstopPressed => "release the e-stop button (PB5 reads high: pressed or a broken wire)".into(),
        Hint::EstopUnreadable => "the e-stop input (PB5) cannot be read".into(),
        Hint::BatteryLow => "charge the battery: the motors need at least 10.5 V".into(),
        Hint::BatteryHigh => "more than any pack gives: check the 47 kΩ / 10 kΩ divider on PC0".into(),
        Hint::BatteryUnreadable => "the battery's ADC (PC0) did not convert".into(),
        Hint::NeckHomeNotFound => "the home switch (PC10, closed = low) never closed: check its wiring and the stepper driver (PC8 step, PC9 dir)".into(),
        Hint::NeckFault => "a neck pin failed or a move was refused: check the stepper driver's wiring (PC8 step, PC9 dir)".into(),
        Hint::NeckLosesSteps => "the neck came back to a different place: lower its speed, check the driver's current and that nothing drags the neck".into(),
        Hint::SonarSilent => "no echo pulse: check the HC-SR04's 5 V, its echo line through the divider to PA1 and the trigger on PB0".into(),
        Hint::SonarTrigger => "the sonar's trigger (PB0) or its capture timer failed".into(),
        Hint::SonarNothingInRange => "every ping answered but nothing in range: put a box 0.5 m in front to check the range".into(),
        Hint::EncoderBackwards => format!("{side} encoder counts backwards: if the wheel turned forward, swap the encoder's A/B wires ({encoder_pins}); if it turned backwards, swap the motor's leads"),
        Hint::EncoderStill => format!("{side} encoder did not count: lift the wheels off the floor; check the motor ({motor_pins}) and the encoder ({encoder_pins}, pull-ups)"),
        Hint::EncoderCountsOff => format!("{side} wheel's counts are far from the robot's prediction: check `encoder_pulses_per_rev` (counted ×4), `motor_gain_rad_s_per_v` and `motor_time_constant_s` in the robot file"),
        Hint::MotorFault => format!("{side} motor's pins failed ({motor_pins})"),
        Hint::SkippedEstop => "not run: the e-stop is pressed".into(),
        Hint::SkippedBattery => "not run: the battery is not fit".into(),
        Hint::NotOnThisBuild => "not run on this build: the simulated robot has no such part".into(),
    })
}
