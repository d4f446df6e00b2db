//! Seed 000's navigation case (thesis §4.2, appendices B.1 and B.3), end to end.
//!
//! The thesis plans for an object moved by two prismatic joints (x, then y) among three
//! obstacles in a walled room, with increments 2, 2, and prints its map size (174 × 112) and its
//! path as 1-based grid indices. We rebuild the map, plan between the same end points, and check
//! that our path is collision-free and no longer than the thesis' path, both measured in joint
//! units on our map.

use crate::common;

use twil_core::cspace::{
    map::{occupancy_at, ConfigMap, Occupancy},
    rob::parse_rob,
    search::{path_is_free, path_length, NodeSet, Search, SearchStatus},
    tra::Trajectory,
};

fn nav() -> (twil_core::cspace::rob::Robot, Trajectory) {
    let rob = std::fs::read_to_string(common::world("seed000-nav.ROB")).unwrap();
    let tra = std::fs::read_to_string(common::world("seed000-nav.TRA")).unwrap();
    (parse_rob(&rob).unwrap(), Trajectory::parse(&tra).unwrap())
}

/// Length of the thesis' path in joint units.
fn thesis_length(t: &Trajectory) -> f32 {
    path_length(&t.to_map_indices(), t.increments)
}

#[test]
fn map_size_is_the_thesis_size_less_one_per_axis() {
    let (robot, thesis) = nav();
    let map = ConfigMap::build(&robot, [2.0, 2.0]).unwrap();
    // Joint 1: -180..165 by 2 → floor(172.5)+1 = 173 values (-180..164); joint 2: -75..145 by 2
    // → 111 values. The thesis printed 174 × 112: one more per axis, as if index 0 existed
    // besides the 1-based indices 1..=N its path file uses (see docs/cspace.md).
    assert_eq!(map.size(), (173, 111));
    assert_eq!(thesis.min, [-180.0, -75.0]);
    assert_eq!(thesis.increments, [2.0, 2.0]);
    // The thesis' end points are round configurations only when read 1-based.
    assert_eq!(thesis.value(0), Some([-60.0, -35.0]));
    assert_eq!(thesis.value(thesis.points.len() - 1), Some([140.0, -5.0]));
}

#[test]
fn our_path_is_collision_free_and_no_longer_than_the_thesis_path() {
    let (robot, thesis) = nav();
    let map = ConfigMap::build(&robot, [2.0, 2.0]).unwrap();
    let start = thesis.value(0).unwrap();
    let goal = thesis.value(thesis.points.len() - 1).unwrap();
    let mut search = Box::new(Search::new());
    let report = search.run(&map, start, goal, NodeSet::Corners).unwrap();
    assert_eq!(report.status, SearchStatus::Found);
    assert_eq!(report.path.first(), Some(&[60, 20]));
    assert_eq!(report.path.last(), Some(&[160, 35]));

    // Collision-free on the map (the thesis' line test, no corner cutting) ...
    assert!(path_is_free(&map, &report.path));
    // ... and in the workspace, checked directly every 0.25 units of joint motion.
    let axes = map.axes();
    for w in report.path.windows(2) {
        let a = [axes[0].value(w[0][0]), axes[1].value(w[0][1])];
        let b = [axes[0].value(w[1][0]), axes[1].value(w[1][1])];
        let len = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
        let steps = (len / 0.25).ceil() as usize;
        for k in 0..=steps {
            let t = k as f32 / steps as f32;
            let q = [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t];
            assert_eq!(
                occupancy_at(&robot, q),
                Occupancy::Free,
                "collision at {q:?}"
            );
        }
    }

    // No longer than the thesis' path, which is itself collision-free on our map.
    let theirs = thesis_length(&thesis);
    assert!(
        (theirs - 371.263).abs() < 1e-2,
        "thesis path length {theirs}"
    );
    assert!(path_is_free(&map, &thesis.to_map_indices()));
    assert!(
        report.length <= theirs,
        "ours {} > thesis {theirs}",
        report.length
    );
    assert!((report.length - path_length(&report.path, [2.0, 2.0])).abs() < 1e-3);
    // A denser node set can only shorten it.
    let boundary = search.run(&map, start, goal, NodeSet::Boundary).unwrap();
    assert!(boundary.length <= report.length + 1e-3);
}

#[test]
fn the_command_line_reproduces_the_case_and_writes_every_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = |name: &str| dir.path().join(name);
    let result = common::twil()
        .args(["cspace", "--rob"])
        .arg(common::world("seed000-nav.ROB"))
        .args([
            "--increments",
            "2,2",
            "--start",
            "-60,-35",
            "--goal",
            "140,-5",
        ])
        .arg("--map")
        .arg(out("nav.MAP"))
        .arg("--tra")
        .arg(out("nav.TRA"))
        .arg("--png")
        .arg(out("nav.png"))
        .arg("--gif")
        .arg(out("nav.gif"))
        .args(["--frames", "8", "--json", "--compare"])
        .arg(common::world("seed000-nav.TRA"))
        .output()
        .unwrap();
    assert!(
        result.status.success(),
        "{}",
        String::from_utf8_lossy(&result.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&result.stdout).unwrap();
    assert_eq!(json["status"], "found");
    assert_eq!(json["cells"], serde_json::json!([173, 111]));
    let path = json["path"].as_array().unwrap();
    assert_eq!(path.first().unwrap(), &serde_json::json!([-60.0, -35.0]));
    assert_eq!(path.last().unwrap(), &serde_json::json!([140.0, -5.0]));
    let length = json["length"].as_f64().unwrap();
    let reference = json["compare"]["length"].as_f64().unwrap();
    assert!(length <= reference, "{length} > {reference}");
    assert_eq!(json["compare"]["free"], true);

    // The files read back: the map equals a fresh build, the path matches the JSON.
    let (robot, _) = nav();
    let map_text = std::fs::read_to_string(out("nav.MAP")).unwrap();
    let (name, map) = ConfigMap::parse_map(&map_text, [false, false]).unwrap();
    assert_eq!(name.as_str(), "seed000-nav.ROB");
    assert_eq!(map, ConfigMap::build(&robot, [2.0, 2.0]).unwrap());
    let tra = Trajectory::parse(&std::fs::read_to_string(out("nav.TRA")).unwrap()).unwrap();
    assert_eq!(tra.points.len(), path.len());
    assert_eq!(tra.points[0], [61, 21]);
    let png = image::open(out("nav.png")).unwrap();
    assert!(png.width() > 600 && png.height() >= 400);
    let gif = std::fs::read(out("nav.gif")).unwrap();
    assert_eq!(&gif[..6], b"GIF89a");
}

#[test]
fn malformed_input_names_file_line_and_value() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.ROB");
    std::fs::write(&bad, "% one wall\n1\n2\n0 0\n5 five\n2\n").unwrap();
    let result = common::twil()
        .args(["cspace", "--rob"])
        .arg(&bad)
        .args(["--increments", "2,2", "--start", "0,0", "--goal", "1,1"])
        .output()
        .unwrap();
    assert_eq!(result.status.code(), Some(1));
    let err = String::from_utf8_lossy(&result.stderr);
    assert!(err.contains("bad.ROB"), "{err}");
    assert!(err.contains("line 5"), "{err}");
    assert!(err.contains("`five`"), "{err}");

    // A goal inside an obstacle is a status, not an error.
    let result = common::twil()
        .args(["cspace", "--rob"])
        .arg(common::world("seed000-nav.ROB"))
        .args([
            "--increments",
            "2,2",
            "--start",
            "-60,-35",
            "--goal",
            "0,-50",
            "--json",
        ])
        .output()
        .unwrap();
    // No path: exit status 3 (crate::exit), the JSON says why.
    assert_eq!(result.status.code(), Some(3));
    let json: serde_json::Value = serde_json::from_slice(&result.stdout).unwrap();
    assert_eq!(json["status"], "goal_blocked");
    assert_eq!(json["path"], serde_json::json!([]));
}

#[test]
fn manipulator_case_with_the_reconstructed_second_arm() {
    // Section 4.1 / appendix A: obstacles and arm 1 from A.1, arm 2's polygon reconstructed
    // (A.1's transcription stops before it). The thesis' path (A.3) read 1-based goes from
    // (0°, -75°) to (184°, 36°).
    let rob = std::fs::read_to_string(common::world("seed000-arm.ROB")).unwrap();
    let tra = std::fs::read_to_string(common::world("seed000-arm.TRA")).unwrap();
    let robot = parse_rob(&rob).unwrap();
    let thesis = Trajectory::parse(&tra).unwrap();
    assert_eq!(thesis.value(0), Some([0.0, -75.0]));
    assert_eq!(thesis.value(thesis.points.len() - 1), Some([184.0, 36.0]));
    let map = ConfigMap::build(&robot, thesis.increments).unwrap();
    // -30..210 by 2 → 121 values; -120..120 by 3 → 81 values.
    assert_eq!(map.size(), (121, 81));
    let mut search = Box::new(Search::new());
    let report = search
        .run(&map, [0.0, -75.0], [184.0, 36.0], NodeSet::Corners)
        .unwrap();
    assert_eq!(report.status, SearchStatus::Found);
    assert!(path_is_free(&map, &report.path));
    let theirs = thesis_length(&thesis);
    assert!(path_is_free(&map, &thesis.to_map_indices()));
    assert!(report.length <= theirs, "{} > {theirs}", report.length);
}

/// A full-turn shoulder with a post straight above it: to swing from 60° to 120° the arm must
/// go round the back, through the seam of the map at ±180°.
const WRAP_ROB: &str = "% full-turn shoulder, post above
1
4  -5 40  5 40  5 50  -5 50
2
R 40 -180 180
1
4  0 -3  -40 -3  -40 3  0 3
R 25 -150 150
1
4  0 -2  -25 -2  -25 2  0 2
";

#[test]
fn a_full_turn_joint_wraps_through_the_seam() {
    let dir = tempfile::tempdir().unwrap();
    let rob = dir.path().join("wrap.ROB");
    std::fs::write(&rob, WRAP_ROB).unwrap();
    let result = common::twil()
        .args(["cspace", "--rob"])
        .arg(&rob)
        .args([
            "--increments",
            "5,5",
            "--start",
            "60,30",
            "--goal",
            "120,-30",
            "--json",
        ])
        .output()
        .unwrap();
    assert!(
        result.status.success(),
        "{}",
        String::from_utf8_lossy(&result.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&result.stdout).unwrap();
    assert_eq!(json["status"], "found");
    // 360/5 = 72 values of joint 1 (wrapping), 300/5 + 1 = 61 of joint 2.
    assert_eq!(json["cells"], serde_json::json!([72, 61]));
    // The direct way (Δq1 = +60°) is blocked; round the back it is Δq1 = -300°, Δq2 = -60°.
    let length = json["length"].as_f64().unwrap();
    assert!(
        (length - (300f64.powi(2) + 60f64.powi(2)).sqrt()).abs() < 1e-2,
        "{length}"
    );
    let path = json["path"].as_array().unwrap();
    assert_eq!(path.last().unwrap(), &serde_json::json!([-240.0, -30.0]));
    // The path is collision-free in the workspace (joint values taken modulo 360°).
    let robot = parse_rob(WRAP_ROB).unwrap();
    let q: Vec<[f32; 2]> = path
        .iter()
        .map(|p| [p[0].as_f64().unwrap() as f32, p[1].as_f64().unwrap() as f32])
        .collect();
    for w in q.windows(2) {
        for k in 0..=200 {
            let t = k as f32 / 200.0;
            let c = [
                w[0][0] + (w[1][0] - w[0][0]) * t,
                w[0][1] + (w[1][1] - w[0][1]) * t,
            ];
            assert_eq!(occupancy_at(&robot, c), Occupancy::Free, "at {c:?}");
        }
    }
    // And the arm does hit the post half way along the direct way.
    assert_ne!(occupancy_at(&robot, [90.0, 0.0]), Occupancy::Free);
}

#[test]
fn a_hand_edited_map_is_planned_on_and_a_broken_one_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let map_path = dir.path().join("nav.MAP");
    let plan = |extra: &[&str]| {
        common::twil()
            .args(["cspace", "--rob"])
            .arg(common::world("seed000-nav.ROB"))
            .args(["--start", "-60,-35", "--goal", "140,-5", "--json"])
            .args(extra)
            .output()
            .unwrap()
    };
    let map_arg = map_path.to_str().unwrap();
    let built = plan(&["--increments", "2,2", "--map", map_arg]);
    assert!(built.status.success());
    let built: serde_json::Value = serde_json::from_slice(&built.stdout).unwrap();

    // Unchanged, the file gives the same plan.
    let same = plan(&["--from-map", map_arg]);
    let same: serde_json::Value = serde_json::from_slice(&same.stdout).unwrap();
    assert_eq!(same["path"], built["path"]);

    // Wall off columns 100..=102 (q1 = 20..24) from top to bottom: no way across any more.
    let text = std::fs::read_to_string(&map_path).unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
    for line in lines.iter_mut().skip(4).take(111) {
        let mut chars: Vec<char> = format!("{line:173}").chars().collect();
        for c in &mut chars[100..=102] {
            *c = 'x';
        }
        *line = chars.into_iter().collect();
    }
    std::fs::write(&map_path, lines.join("\n") + "\n").unwrap();
    let edited = plan(&["--from-map", map_arg]);
    assert_eq!(
        edited.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&edited.stderr)
    );
    let edited: serde_json::Value = serde_json::from_slice(&edited.stdout).unwrap();
    assert_eq!(edited["status"], "unreachable");

    // Disagreeing increments and a broken row are errors naming the file.
    let wrong = plan(&["--from-map", map_arg, "--increments", "1,1"]);
    assert_eq!(wrong.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&wrong.stderr).contains("disagree"));
    lines[10] = "y".repeat(200);
    std::fs::write(&map_path, lines.join("\n") + "\n").unwrap();
    let broken = plan(&["--from-map", map_arg]);
    assert_eq!(broken.status.code(), Some(1));
    let err = String::from_utf8_lossy(&broken.stderr);
    assert!(err.contains("nav.MAP: line 11"), "{err}");
    assert!(err.contains("map row 7"), "{err}");
}
