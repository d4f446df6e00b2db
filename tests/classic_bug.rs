//! Issue 15, item 8 (Bug): Lumelsky's Bug1 run in the kinematic simulator with the sonar
//! reaches the goal on every bundled world where a path exists, never comes nearer the
//! obstacles than the robot's radius (less 0.02 m), stays within the seed's bound, and reports
//! a goal walled in as unreachable. In-process through `twil_host::classic::run`, plus one run
//! of the binary for the JSON.

use twil_host::classic::{self, Method, Options, Status};
use twil_host::cmd::plan::{load, SizeM};

use crate::common;

fn world(name: &str, size: Option<(f32, f32)>) -> twil_host::cmd::plan::World {
    let dir = common::repo().join("worlds");
    let mut args = common::plan_args(
        Some(dir.join(format!("{name}.da"))),
        dir.join(format!("{name}.par")),
    );
    if let Some((width_m, height_m)) = size {
        args.planning.size = SizeM { width_m, height_m };
    }
    load(&args).unwrap()
}

fn extra_f64(run: &classic::Run, key: &str) -> f64 {
    run.extra.get(key).and_then(|v| v.as_f64()).unwrap()
}

#[test]
fn bug_reaches_the_goal_on_every_bundled_world_with_a_path() {
    for (name, size) in [
        ("office", None),
        ("corridor", None),
        ("pillars", None),
        ("lab", Some((18.0, 10.0))),
    ] {
        let w = world(name, size);
        let run = classic::run(Method::Bug, &w, &Options::default()).unwrap();
        assert_eq!(run.status, Status::Found, "{name}");
        let end = *run.path.last().unwrap();
        assert!(
            end.distance_m(w.params.goal) <= 0.011,
            "{name}: ends at {end:?}"
        );
        assert_eq!(*run.path.first().unwrap(), w.params.start, "{name}");
        let clearance_m = classic::min_clearance_m(&w, &run).unwrap();
        assert!(clearance_m >= -0.02, "{name}: clearance {clearance_m}");
        let bound_m = extra_f64(&run, "bound_m");
        assert!(
            f64::from(run.length_m) <= bound_m,
            "{name}: {} m > bound {bound_m} m",
            run.length_m
        );
        assert_eq!(
            run.extra["within_bound"],
            serde_json::Value::Bool(true),
            "{name}"
        );
        // It had to go round something, and it counted its sonar readings (nine a step).
        let hits = run.extra["hit_points"].as_array().unwrap().len();
        let leaves = run.extra["leave_points"].as_array().unwrap().len();
        assert!(
            hits >= 1 && leaves == hits,
            "{name}: {hits} hits, {leaves} leaves"
        );
        let steps = extra_f64(&run, "steps") as u64;
        assert_eq!(run.expanded, 9 * steps, "{name}");
        assert_eq!(run.expanded_unit, "sonar readings");
        // The thinned track is still the driven one, give or take the thinning.
        let poly_m = classic::polyline_length_m(&run.path);
        assert!(
            poly_m <= run.length_m + 1e-3 && poly_m > 0.98 * run.length_m,
            "{name}"
        );
    }
}

#[test]
fn bug_reports_a_walled_in_goal_as_unreachable() {
    // The bundled enclosed world (box round the goal inside the border walls) and a smaller
    // one without border walls, in a temporary folder.
    let w = world("enclosed", None);
    let run = classic::run(Method::Bug, &w, &Options::default()).unwrap();
    assert_eq!(run.status, Status::Unreachable);
    assert!(classic::min_clearance_m(&w, &run).unwrap() >= -0.02);

    let dir = tempfile::tempdir().unwrap();
    let da = dir.path().join("box.da");
    let par = dir.path().join("box.par");
    std::fs::write(
        &da,
        "4\n\
         4\n5 5\n9 5\n9 5.2\n5 5.2\n\
         4\n5 8.8\n9 8.8\n9 9\n5 9\n\
         4\n5 5\n5.2 5\n5.2 9\n5 9\n\
         4\n8.8 5\n9 5\n9 9\n8.8 9\n",
    )
    .unwrap();
    std::fs::write(&par, "0.4\n0.2\n0.0\n1.5 12.0\n7.0 7.0\n").unwrap();
    let w = load(&common::plan_args(Some(da), par)).unwrap();
    let run = classic::run(Method::Bug, &w, &Options::default()).unwrap();
    assert_eq!(run.status, Status::Unreachable);
    assert!(classic::min_clearance_m(&w, &run).unwrap() >= -0.02);
    // One loop round the box (about 4 × 4 m + 2π·0.55), the way back and the approach:
    // well inside the step limit.
    assert!(run.length_m < 60.0, "{}", run.length_m);
    assert_eq!(run.extra["within_bound"], serde_json::Value::Bool(false));
}

#[test]
fn twil_plan_prints_the_bug_fields() {
    let dir = common::repo().join("worlds");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_twil"))
        .args(["plan", "--planner", "bug", "--json", "--world"])
        .arg(dir.join("pillars.da"))
        .arg("--params")
        .arg(dir.join("pillars.par"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(json["status"], "found");
    assert_eq!(json["planner"], "bug");
    assert_eq!(json["expanded_unit"], "sonar readings");
    for key in ["bound_m", "steps", "min_clearance_m", "memory_bytes"] {
        assert!(json[key].as_f64().unwrap() > 0.0, "{key}");
    }
    // The pillars on the diagonal: three hits, three leaves.
    assert_eq!(json["hit_points"].as_array().unwrap().len(), 3);
    assert_eq!(json["leave_points"].as_array().unwrap().len(), 3);
    assert_eq!(json["within_bound"], true);
    // The thinned path keeps the JSON small.
    assert!(json["path"].as_array().unwrap().len() < 400);
}
