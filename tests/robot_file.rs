//! The robot file (issue 25): `twil robot init` → edit → `--robot` on plan, simulate, mission
//! and compare changes what they do; every kind of mistake is one line naming file:line, key
//! and value; `summary.json`'s `robot` object holds the file's values; the constants table of
//! docs/robot-model.md is the one the parameter table generates.

use std::path::{Path, PathBuf};
use std::process::Output;

use serde_json::Value;

use crate::common::{self, repo};

fn run(args: &[&str]) -> Output {
    common::twil().args(args).output().expect("run twil")
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A 15 x 15 m room cut by a wall at y = 5 with a 1.2 m doorway (x 6.9 to 8.1): a 0.40 m
/// planning radius leaves 0.40 m of free width, a 0.70 m one closes it.
fn doorway(dir: &Path) -> (PathBuf, PathBuf) {
    let da = dir.join("doorway.da");
    std::fs::write(
        &da,
        "2\n4\n0.0 5.0\n6.9 5.0\n6.9 5.3\n0.0 5.3\n4\n8.1 5.0\n15.0 5.0\n15.0 5.3\n8.1 5.3\n",
    )
    .unwrap();
    let par = dir.join("doorway.par");
    std::fs::write(&par, "0.4\n0.2\n90.0\n7.5 2.0\n7.5 9.0\n").unwrap();
    (da, par)
}

/// `twil robot init` into `dir`, then each `(key, value)` replaced in the file.
fn robot_file(dir: &Path, edits: &[(&str, &str)]) -> PathBuf {
    let path = dir.join("robot.toml");
    let _ = std::fs::remove_file(&path);
    let out = run(&["robot", "init", s(&path)]);
    assert!(out.status.success(), "{out:?}");
    let mut text = std::fs::read_to_string(&path).unwrap();
    for (key, value) in edits {
        let start = text
            .find(&format!("\n{key} = "))
            .unwrap_or_else(|| panic!("{key} not in the generated file"))
            + 1;
        let end = start + text[start..].find('\n').unwrap();
        text.replace_range(start..end, &format!("{key} = {value}"));
    }
    std::fs::write(&path, text).unwrap();
    path
}

/// `twil plan` on `da`/`par` with the robot file `robot`.
fn plan_argv<'a>(da: &'a Path, par: &'a Path, robot: &'a Path) -> Vec<&'a str> {
    vec![
        "plan",
        "--world",
        s(da),
        "--params",
        s(par),
        "--robot",
        s(robot),
    ]
}

/// `twil simulate` on `da`/`par` with the robot file `robot` and `extra` options.
fn simulate(da: &Path, par: &Path, robot: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "simulate",
        "--real",
        s(da),
        "--params",
        s(par),
        "--robot",
        s(robot),
    ];
    args.extend_from_slice(extra);
    run(&args)
}

/// `summary.json` of `dir`.
fn read_summary(dir: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

fn stdout_json(out: &Output) -> Value {
    let stdout = String::from_utf8_lossy(&out.stdout);
    serde_json::from_str(stdout.trim()).unwrap_or_else(|e| {
        panic!(
            "{e}: {stdout}\nstderr: {}",
            String::from_utf8_lossy(&out.stderr)
        )
    })
}

/// The one stderr line of a run that must fail with exit code 1.
fn error_line(args: &[&str]) -> String {
    let out = run(args);
    assert_eq!(out.status.code(), Some(1), "{args:?}: {out:?}");
    assert!(out.stdout.is_empty(), "{args:?} printed on stdout");
    let err = String::from_utf8(out.stderr).unwrap();
    assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
    err.trim_end().to_string()
}

#[test]
fn init_writes_every_constant_and_show_reads_it_back() {
    let dir = tempfile::tempdir().unwrap();
    let path = robot_file(dir.path(), &[]);
    let text = std::fs::read_to_string(&path).unwrap();
    for p in twil_core::params::PARAMS.iter() {
        assert!(text.contains(&format!("\n{} = ", p.name)), "{}", p.name);
    }
    assert!(text.contains("# Default: seed `ST`."), "{text}");
    // An existing file is not replaced by mistake.
    let e = error_line(&["robot", "init", s(&path)]);
    assert!(e.contains("pass --force"), "{e}");
    let shown = stdout_json(&run(&["robot", "show", "--robot", s(&path), "--json"]));
    let defaults = stdout_json(&run(&["robot", "show", "--json"]));
    assert_eq!(shown, defaults);
    assert_eq!(shown["robot"]["wheel_radius_m"], 0.075);
    let edited = robot_file(dir.path(), &[("wheel_radius_m", "0.08")]);
    let out = run(&["robot", "show", "--robot", s(&edited)]);
    let text = String::from_utf8(out.stdout).unwrap();
    let line = text
        .lines()
        .find(|l| l.starts_with("wheel_radius_m"))
        .unwrap();
    assert!(line.contains("= 0.08 m"), "{line}");
    assert!(line.contains("robot.toml:"), "{line}");
}

#[test]
fn a_larger_planning_radius_closes_a_narrow_doorway() {
    let dir = tempfile::tempdir().unwrap();
    let (da, par) = doorway(dir.path());
    let plan = |robot: &Path| {
        let mut argv = plan_argv(&da, &par, robot);
        argv.push("--json");
        let out = run(&argv);
        (out.status.code(), stdout_json(&out)["status"].clone())
    };
    let same = robot_file(dir.path(), &[]);
    assert_eq!(plan(&same), (Some(0), Value::from("found")));
    let wide = robot_file(dir.path(), &[("planning_radius_m", "0.7")]);
    assert_eq!(plan(&wide), (Some(3), Value::from("unreachable")));
    // compare grows by the same radius: no method finds a path.
    let out = run(&[
        "compare",
        "--world",
        s(&da),
        "--params",
        s(&par),
        "--planners",
        "astar",
        "--robot",
        s(&wide),
        "--json",
    ]);
    let text = stdout_json(&out).to_string();
    assert!(!text.contains("\"found\""), "{text}");
    // And the simulated mission cannot pass it either.
    let out = simulate(&da, &par, &wide, &["--json"]);
    let v = stdout_json(&out);
    // Walled in, or a stall in front of the gap (issue 26: each its own word).
    assert!(
        v["status"] == "unreachable" || v["status"] == "gave_up",
        "{v}"
    );
    assert_eq!(v["stop_cause"], v["status"], "{v}");
    assert_eq!(out.status.code(), Some(3));
}

#[test]
fn summary_json_holds_the_files_values_and_an_option_overrides_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let (da, par) = doorway(dir.path());
    let path = robot_file(
        dir.path(),
        &[
            ("wheel_radius_m", "0.08"),
            ("sonar_range_m", "2.0"),
            ("encoder_pulses_per_rev", "1024"),
            ("sonar_beam", "false"),
            // The exact ray: the generated file keeps the beam's faults otherwise.
            ("sonar_noise_std_m", "0.0"),
            ("sonar_dropout_probability", "0.0"),
            ("sonar_spurious_probability", "0.0"),
            ("sweep_layout", "\"seed\""),
        ],
    );
    let out_dir = dir.path().join("out");
    let out = simulate(&da, &par, &path, &["--out", s(&out_dir), "--json"]);
    let v = stdout_json(&out);
    assert_eq!(v["status"], "reached", "{v}");
    assert_eq!(v["stop_cause"], "reached");
    let summary = read_summary(&out_dir);
    let file: toml::Table = std::fs::read_to_string(&path).unwrap().parse().unwrap();
    let robot = summary["robot"].as_object().unwrap();
    assert_eq!(robot.len(), file.len());
    for (key, value) in &file {
        let expected = serde_json::to_value(value).unwrap();
        assert_eq!(robot[key], expected, "{key}");
    }
    assert_eq!(summary["stop_cause"], "reached");
    // An explicit option wins over the file, and summary.json says what the run used.
    let out = simulate(
        &da,
        &par,
        &path,
        &[
            "--sonar-range",
            "1.2",
            "--sonar",
            "beam",
            "--out",
            s(&out_dir),
            "--json",
        ],
    );
    // A 1.2 m beam sonar may or may not find the doorway: either end is an answer here.
    assert!(matches!(out.status.code(), Some(0 | 3)), "{out:?}");
    let summary = read_summary(&out_dir);
    assert_eq!(summary["robot"]["sonar_range_m"], 1.2);
    assert_eq!(summary["robot"]["sonar_beam"], true);
    assert_eq!(summary["robot"]["wheel_radius_m"], 0.08);
}

#[test]
fn each_mistake_is_one_line_naming_file_line_key_and_value() {
    let dir = tempfile::tempdir().unwrap();
    let (da, par) = doorway(dir.path());
    let path = dir.path().join("robot.toml");
    let plan = |text: &str| {
        std::fs::write(&path, text).unwrap();
        error_line(&plan_argv(&da, &par, &path))
    };
    let p = path.display();
    assert_eq!(
        plan("# my robot\nwheel_radius_m = 0.08\nhalf_axel_m = 0.2\n"),
        format!("twil: {p}:3: unknown key `half_axel_m` = 0.2; did you mean `half_axle_m`?")
    );
    assert_eq!(
        plan("wheel_radius_m = \"large\"\n"),
        format!("twil: {p}:1: `wheel_radius_m` = \"large\": expected a number (m)")
    );
    assert_eq!(
        plan("\nwheel_radius_m = 0.08\nsonar_range_m = 9\n"),
        format!("twil: {p}:3: `sonar_range_m` = 9: above sonar_min_range_m and at most 6 m")
    );
    assert!(plan("wheel_radius_m = \n").starts_with(&format!("twil: {p}:1: ")));
    // The same checks on simulate.
    std::fs::write(&path, "neck_step_deg = 0.5\n").unwrap();
    let e = error_line(&[
        "simulate",
        "--real",
        s(&da),
        "--params",
        s(&par),
        "--robot",
        s(&path),
    ]);
    assert!(
        e.starts_with(&format!("twil: {p}:1: `neck_step_deg` = 0.5: ")),
        "{e}"
    );
}

#[test]
fn mission_sends_the_files_values_and_says_why_it_ended() {
    let dir = tempfile::tempdir().unwrap();
    let (da, par) = doorway(dir.path());
    let args = |robot: &Path| {
        [
            "mission",
            "--remote",
            "sim",
            "--real",
            s(&da),
            "--params",
            s(&par),
            "--robot",
            s(robot),
            "--json",
        ]
        .map(str::to_owned)
    };
    // A constant SetMission does not carry goes over as a parameter (ParamSet) first.
    let path = robot_file(dir.path(), &[("wheel_radius_m", "0.08")]);
    let a = args(&path);
    let out = run(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let v = stdout_json(&out);
    assert_eq!(v["status"], "reached", "{v}");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        // The wheel, and the simulated ranger's five constants the host tools default
        // otherwise than the device (`RobotConfig::SIMULATED`).
        stderr.contains("6 of 39 values set on the device"),
        "{stderr}"
    );
    // Values that depend on each other go in an order the device accepts: a neck step too
    // fine for the full sweep only after the narrower full sweep.
    let path = robot_file(
        dir.path(),
        &[("neck_step_deg", "1.0"), ("full_half_sweep_deg", "90.0")],
    );
    let a = args(&path);
    let out = run(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("7 of 39 values set on the device"),
        "{stderr}"
    );
    assert!(stdout_json(&out)["status"].is_string(), "{out:?}");
    let path = robot_file(dir.path(), &[("planning_radius_m", "0.7")]);
    let a = args(&path);
    let out = run(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let v = stdout_json(&out);
    // Walled in, or a stall in front of the gap (issue 26: each its own word).
    assert!(
        v["status"] == "unreachable" || v["status"] == "gave_up",
        "{v}"
    );
    assert_eq!(v["stop_cause"], v["status"], "{v}");
}

#[test]
fn the_docs_constants_table_is_the_generated_one() {
    let doc = std::fs::read_to_string(repo().join("docs/robot-model.md")).unwrap();
    let generated = twil_host::robot_file::docs_table();
    let start = doc
        .find("| Key | Default |")
        .expect("docs/robot-model.md has the constants table");
    let end = doc[start..]
        .find("\n\n")
        .map_or(doc.len(), |i| start + i + 1);
    assert!(
        doc[start..end] == generated,
        "docs/robot-model.md's constants table differs from the parameter table; replace it with:\n{generated}"
    );
}
