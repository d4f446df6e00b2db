//! End-to-end tests of `twil mission` against the in-process device (`--remote sim`): whole
//! missions on the bundled worlds agree with `twil simulate`, the JSON and the files have the
//! simulator's shape plus `mcu`, bad inputs are named, Ctrl-C aborts.

use crate::common;

use std::collections::BTreeSet;
use std::process::Output;

use serde_json::Value;

fn world(name: &str) -> String {
    common::world(name).display().to_string()
}

fn run(args: &[&str]) -> Output {
    common::twil().args(args).output().expect("run twil")
}

/// Run and parse the one JSON line on stdout.
fn json_of(args: &[&str]) -> Value {
    let out = run(args);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "twil {args:?}: {}\n{stdout}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(stdout.lines().count(), 1, "one line: {stdout}");
    serde_json::from_str(stdout.trim()).expect("valid JSON")
}

fn mission(name: &str, mode: &str, extra: &[&str]) -> Value {
    let (da, par) = (world(&format!("{name}.da")), world(&format!("{name}.par")));
    let mut args = vec![
        "mission",
        "--remote",
        "sim",
        "--real",
        &da,
        "--params",
        &par,
        "--mode",
        mode,
        "--planner",
        "astar",
        "--json",
    ];
    args.extend_from_slice(extra);
    json_of(&args)
}

fn simulate(name: &str, mode: &str) -> Value {
    let (da, par) = (world(&format!("{name}.da")), world(&format!("{name}.par")));
    json_of(&[
        "simulate",
        "--real",
        &da,
        "--params",
        &par,
        "--mode",
        mode,
        "--planner",
        "astar",
        "--plan-latency-ms",
        "0",
        "--json",
    ])
}

fn num(v: &Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} is not a number in {v}"))
}

#[test]
fn bundled_worlds_reach_the_goal_and_agree_with_the_simulator_in_both_modes() {
    for name in ["office", "corridor", "pillars"] {
        for mode in ["stop", "continuous"] {
            let device = mission(name, mode, &[]);
            let host = simulate(name, mode);
            let what = format!("{name} {mode}:\n device {device}\n simulate {host}");
            assert_eq!(device["status"], "reached", "{what}");
            assert_eq!(device["status"], host["status"], "{what}");
            let (ds, hs) = (num(&device, "stops"), num(&host, "stops"));
            assert!((ds - hs).abs() <= 0.1 * hs, "stops: {what}");
            let (dd, hd) = (num(&device, "distance_m"), num(&host, "distance_m"));
            assert!(dd > 1.0 && (dd - hd).abs() <= 0.05 * hd, "distance: {what}");
            // The clearance along the reported poses to the real world, body radius off.
            let clearance = num(&device, "min_clearance_m");
            assert!(
                clearance > 0.0 && (clearance - num(&host, "min_clearance_m")).abs() < 0.02,
                "clearance: {what}"
            );
        }
    }
}

/// Issue 26: with the default planner and no planning latency (the in-process device plans
/// at once), plans made from moving sweeps alternated between the two ways round a pillar and
/// the stall counter ended the mission `unreachable` after 3 m. A stall now first buys one
/// full standing sweep at that place.
#[test]
fn plans_that_alternate_round_a_pillar_are_settled_by_a_standing_sweep() {
    let (da, par) = (world("pillars.da"), world("pillars.par"));
    for seed in ["1", "2", "3"] {
        let device = json_of(&[
            "mission",
            "--remote",
            "sim",
            "--real",
            &da,
            "--params",
            &par,
            "--mode",
            "continuous",
            "--seed",
            seed,
            "--json",
        ]);
        assert_eq!(device["status"], "reached", "seed {seed}: {device}");
    }
    let host = json_of(&[
        "simulate",
        "--real",
        &da,
        "--params",
        &par,
        "--mode",
        "continuous",
        "--plan-latency-ms",
        "0",
        "--json",
    ]);
    assert_eq!(host["status"], "reached", "{host}");
}

#[test]
fn json_has_exactly_the_simulator_keys_plus_mcu() {
    let device = mission("pillars", "continuous", &[]);
    let host = simulate("pillars", "continuous");
    let keys = |v: &Value| -> BTreeSet<String> {
        v.as_object().expect("an object").keys().cloned().collect()
    };
    let mut expected = keys(&host);
    expected.insert("mcu".into());
    assert_eq!(keys(&device), expected);
    // The in-process device measures nothing: its figures are absent (`null`), not zeros
    // (the firmware's are checked under QEMU, tests/firmware_qemu.rs).
    assert!(device["mcu"].is_null(), "{}", device["mcu"]);
}

#[test]
fn plan_on_the_in_process_device_has_no_mcu_figures() {
    let (da, par) = (world("pillars.da"), world("pillars.par"));
    let o = run(&[
        "plan", "--remote", "sim", "--world", &da, "--params", &par, "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let json: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(json["matches_host"], true);
    assert!(json["mcu_instructions"].is_null(), "{json}");
    assert!(json["static_ram_bytes"].is_null(), "{json}");
    let o = run(&["plan", "--remote", "sim", "--world", &da, "--params", &par]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(!text.contains("mcu_instructions"), "{text}");
}

#[test]
fn out_writes_summary_trajectory_plan_pictures_and_the_gif() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let out_s = out.display().to_string();
    let (da, par) = (world("corridor.da"), world("corridor.par"));
    let o = run(&[
        "mission",
        "--remote",
        "sim",
        "--real",
        &da,
        "--params",
        &par,
        "--mode",
        "continuous",
        "--out",
        &out_s,
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.starts_with("reached: "), "{stdout}");
    // No line of zeros for figures the in-process device does not measure.
    assert!(!stdout.contains("mcu: "), "{stdout}");

    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "reached");
    assert_eq!(summary["build"], "host");
    assert_eq!(summary["remote"], "sim");
    assert!(summary["mcu"].is_null());
    assert!(summary["stop_latency_us"].is_null());

    let csv = std::fs::read_to_string(out.join("trajectory.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some("t,x,y,theta,ref_x,ref_y,left_speed_ref_rad_s,right_speed_ref_rad_s,left_v,right_v,phase")
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    // Poses at 5 Hz over the whole mission.
    let expected = num(&summary, "sim_time_s") * 5.0;
    assert!(
        (rows.len() as f64 - expected).abs() <= 3.0,
        "{} rows for {expected}",
        rows.len()
    );
    assert!(rows.iter().all(|r| r.len() == 11));
    // The telemetry carries pose, voltages and phase, not the references (empty fields).
    assert!(rows.iter().all(|r| r[..4]
        .iter()
        .chain(&r[8..10])
        .all(|f| f.parse::<f64>().is_ok())));
    assert!(rows.iter().all(|r| r[4].is_empty()));
    assert!(rows.iter().any(|r| r[10] == "follow"));

    // One picture per plan the device reported; it reports at most every plan it made.
    let plans = summary["plans_reported"].as_u64().unwrap() as usize;
    assert!(plans > 0 && plans as u64 <= summary["plans"].as_u64().unwrap());
    let pngs = std::fs::read_dir(&out)
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with("plan-") && n.ends_with(".png"))
        .count();
    assert_eq!(pngs, plans);
    let png = std::fs::read(out.join("plan-001.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    let gif = std::fs::read(out.join("mission.gif")).unwrap();
    assert_eq!(&gif[..6], b"GIF89a");
    assert!(gif.len() > 10_000);
}

#[test]
fn a_simulated_device_needs_the_real_world() {
    let par = world("office.par");
    let o = run(&["mission", "--remote", "sim", "--params", &par]);
    assert_eq!(o.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("--real R.da is required with --remote sim"),
        "{stderr}"
    );
    assert!(o.stdout.is_empty());
}

#[test]
fn bad_files_are_named_with_their_line() {
    let dir = tempfile::tempdir().unwrap();
    let par = dir.path().join("bad.par");
    std::fs::write(&par, "0.3\n0.3\n90\n1 1\n").unwrap();
    let par_s = par.display().to_string();
    let da = world("office.da");
    let o = run(&[
        "mission", "--remote", "sim", "--real", &da, "--params", &par_s,
    ]);
    assert_eq!(o.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains(&format!("{par_s}: line ")), "{stderr}");

    let bad_da = dir.path().join("bad.da");
    std::fs::write(&bad_da, "1 1\n2 x\n").unwrap();
    let bad_da_s = bad_da.display().to_string();
    let good_par = world("office.par");
    for flag in ["--real", "--known"] {
        let mut args = vec!["mission", "--remote", "sim", "--params", &good_par];
        if flag == "--known" {
            args.extend_from_slice(&["--real", &da]);
        }
        args.extend_from_slice(&[flag, &bad_da_s]);
        let o = run(&args);
        assert_eq!(o.status.code(), Some(1), "{flag}");
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(
            stderr.contains(&format!("{bad_da_s}: line 2")),
            "{flag}: {stderr}"
        );
    }
}

#[test]
fn the_heartbeat_keeps_a_short_link_timeout_from_firing() {
    // 200 ms of silence would stop the mission (it takes seconds of wall time): the host's
    // heartbeat every 50 ms keeps it going to the goal.
    let device = mission("office", "continuous", &["--link-timeout-ms", "200"]);
    assert_eq!(device["status"], "reached", "{device}");
}

#[test]
fn a_link_timeout_out_of_range_is_refused_naming_the_option() {
    let (da, par) = (world("office.da"), world("office.par"));
    for bad in ["50", "3600001"] {
        let o = run(&[
            "mission",
            "--remote",
            "sim",
            "--real",
            &da,
            "--params",
            &par,
            "--link-timeout-ms",
            bad,
        ]);
        assert_eq!(o.status.code(), Some(1));
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(
            stderr.contains("--link-timeout-ms") && stderr.contains(bad),
            "{stderr}"
        );
    }
}

#[test]
fn a_goal_off_the_map_is_answered_out_of_bounds_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let par = dir.path().join("far.par");
    std::fs::write(&par, "0.35\n0.3\n90\n1.5 1.5\n40 1\n").unwrap();
    let par_s = par.display().to_string();
    let o = run(&[
        "mission",
        "--remote",
        "sim",
        "--real",
        &world("office.da"),
        "--params",
        &par_s,
    ]);
    // As `twil plan` answers (issue 26: tests/answers.rs runs every command).
    assert_eq!(o.status.code(), Some(3));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(
        stdout.trim(),
        format!(
            "out_of_bounds: the goal (40.00, 1.00) lies off the 15 x 15 m map, as {par_s} gives \
             it; nothing ran"
        )
    );
}

#[cfg(unix)]
#[test]
fn ctrl_c_aborts_the_mission_and_waits_for_its_report() {
    use std::time::{Duration, Instant};
    let (da, par) = (world("office.da"), world("office.par"));
    // 20 times real time: the office mission takes about 20 s.
    let child = common::twil()
        .args([
            "mission", "--remote", "sim:20", "--real", &da, "--params", &par, "--json",
        ])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(1500));
    let started = Instant::now();
    common::ctrl_c(&child);
    let out = child.wait_with_output().unwrap();
    assert!(started.elapsed() < Duration::from_secs(10));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{stderr}");
    assert!(
        stderr.contains("the mission was aborted and the device stopped the motors"),
        "{stderr}"
    );
    let v: Value = serde_json::from_str(String::from_utf8_lossy(&out.stdout).trim()).unwrap();
    assert_eq!(v["status"], "aborted");
    let t = num(&v, "sim_time_s");
    assert!(t > 5.0 && t < 300.0, "{t}");
}

/// `twil ping --json` describes the device in one JSON object, and a misspelt `--remote` is a
/// usage error that suggests the keyword.
#[test]
fn ping_json_and_remote_suggestions() {
    let o = common::twil()
        .args(["ping", "--remote", "sim", "--count", "3", "--json"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["protocol_version"], twil_core::link::PROTOCOL_VERSION);
    assert_eq!(v["build"], "host");
    assert_eq!(v["param_store"], "empty");
    assert_eq!(v["round_trips_ms"].as_array().unwrap().len(), 3);
    let o = common::twil()
        .args(["ping", "--remote", "qmeu"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("did you mean `qemu`?"), "{err}");
}

/// One definition of a stop: the count the host keeps from the device's phases (the live line,
/// the pictures, the recording's `/status`) ends equal to the device's own (`stops` of the
/// summary), a full sweep at the place of the last sweep counting with that stop. Issue 26
/// saw `stops 6` live and `5 stops` at the end. About 5 s (a whole office mission in process).
#[test]
fn the_live_stop_count_ends_equal_to_the_devices() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("m.mcap");
    let (da, par) = (world("office.da"), world("office.par"));
    let o = run(&[
        "mission",
        "--remote",
        "sim",
        "--real",
        &da,
        "--params",
        &par,
        "--record",
        rec.to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let json: Value = serde_json::from_slice(&o.stdout).unwrap();
    let full_sweeps = json["full_sweeps"].as_u64().unwrap();
    assert!(full_sweeps > 0, "the case needs full sweeps: {json}");
    let state = twil_host::record::read::read(&rec, None).unwrap();
    let live = state.status.as_ref().expect("a /status message").stops;
    assert_eq!(u64::from(live), json["stops"].as_u64().unwrap(), "{json}");
}
