//! Scenario tests for `twil plan` on the bundled worlds: every world with every planner, the JSON
//! shape, the picture, the saved map, the plan statuses and bad input files.
//!
//! The binary is run as a user would run it (`common::twil()`); the grid it planned on is rebuilt
//! in-process with `twil_host::cmd::plan::load` to check the returned paths independently.

use crate::common;

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::Output;

use serde_json::Value;
use twil_core::geom::{Cell, PointM};
use twil_core::grid::{Grid400, GridGeometry};
use twil_core::plan::{DIAGONAL_COST, STRAIGHT_COST};
use twil_core::raster::BresenhamLine;
use twil_core::world::{parse_da, parse_par, Obstacles};
use twil_host::cmd::plan::load;

const WORLDS: [&str; 3] = ["corridor", "office", "pillars"];
const PLANNERS: [&str; 3] = ["bfs", "astar", "anyangle"];
const KEYS: [&str; 6] = [
    "status",
    "planner",
    "path",
    "length_m",
    "expanded",
    "elapsed_us",
];

fn run(args: &[&str]) -> Output {
    common::twil()
        .arg("plan")
        .args(args)
        .output()
        .expect("the twil binary runs")
}

fn path_str(p: &Path) -> &str {
    p.to_str().expect("test paths are UTF-8")
}

/// `twil plan --json` on a world; the parsed object.
fn plan_json(da: &Path, par: &Path, planner: &str, extra: &[&str]) -> Value {
    let mut args = vec![
        "--world",
        path_str(da),
        "--params",
        path_str(par),
        "--planner",
        planner,
        "--json",
    ];
    args.extend_from_slice(extra);
    let out = run(&args);
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert_eq!(stdout.trim().lines().count(), 1, "one JSON line: {stdout}");
    let json: Value = serde_json::from_str(stdout.trim()).unwrap();
    // The exit status says whether a path was found (0) or not (3); the JSON says why.
    let expected = if json["status"] == "found" { 0 } else { 3 };
    assert_eq!(
        out.status.code(),
        Some(expected),
        "{}: stderr: {}",
        json["status"],
        String::from_utf8_lossy(&out.stderr)
    );
    json
}

fn path_of(json: &Value) -> Vec<PointM> {
    json["path"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| {
            let xy = p.as_array().unwrap();
            assert_eq!(xy.len(), 2);
            PointM::new(
                xy[0].as_f64().unwrap() as f32,
                xy[1].as_f64().unwrap() as f32,
            )
        })
        .collect()
}

/// Every Bresenham cell of the segment is free, and no diagonal step cuts between two occupied
/// side cells (the planners' rule). The walk runs in (y, x) order so that it does not depend on
/// the direction of the segment (an independent re-implementation of the planners' check).
fn segment_is_free(grid: &Grid400, a: Cell, b: Cell) -> bool {
    let (from, to) = if (a.y, a.x) <= (b.y, b.x) {
        (a, b)
    } else {
        (b, a)
    };
    let mut prev = (from.x as i32, from.y as i32);
    for (x, y) in BresenhamLine::new(prev, (to.x as i32, to.y as i32)) {
        if grid.is_occupied_xy(x, y) {
            return false;
        }
        if x != prev.0
            && y != prev.1
            && (grid.is_occupied_xy(x, prev.1) || grid.is_occupied_xy(prev.0, y))
        {
            return false;
        }
        prev = (x, y);
    }
    true
}

fn polyline_length_m(path: &[PointM]) -> f32 {
    path.windows(2)
        .map(|w| ((w[1].x_m - w[0].x_m).powi(2) + (w[1].y_m - w[0].y_m).powi(2)).sqrt())
        .sum()
}

/// Optimal 8-connected octile cost (seed neighbour rule) by the `pathfinding` crate.
fn reference_astar_cost(grid: &Grid400, start: Cell, goal: Cell) -> Option<u32> {
    let neighbours = |c: &(i32, i32)| {
        let (x, y) = *c;
        let free = |x: i32, y: i32| !grid.is_occupied_xy(x, y);
        let mut out = Vec::with_capacity(8);
        for (dx, dy) in [(1, 0), (-1, 0), (0, 1), (0, -1)] {
            if free(x + dx, y + dy) {
                out.push(((x + dx, y + dy), STRAIGHT_COST));
            }
        }
        for (dx, dy) in [(1, 1), (1, -1), (-1, 1), (-1, -1)] {
            if free(x + dx, y + dy) && free(x + dx, y) && free(x, y + dy) {
                out.push(((x + dx, y + dy), DIAGONAL_COST));
            }
        }
        out
    };
    let goal = (goal.x as i32, goal.y as i32);
    let h = |c: &(i32, i32)| {
        let (dx, dy) = ((c.0 - goal.0).unsigned_abs(), (c.1 - goal.1).unsigned_abs());
        let (lo, hi) = (dx.min(dy), dx.max(dy));
        DIAGONAL_COST * lo + STRAIGHT_COST * (hi - lo)
    };
    pathfinding::prelude::astar(&(start.x as i32, start.y as i32), neighbours, h, |c| {
        *c == goal
    })
    .map(|(_, cost)| cost)
}

/// Octile cost of a path of cell centres whose segments run along the 8 directions.
fn octile_cost(geometry: &GridGeometry, path: &[PointM]) -> u32 {
    let mut cost = 0;
    for w in path.windows(2) {
        let (a, b) = (
            geometry.cell_of(w[0]).unwrap(),
            geometry.cell_of(w[1]).unwrap(),
        );
        let dx = (a.x as i32 - b.x as i32).unsigned_abs();
        let dy = (a.y as i32 - b.y as i32).unsigned_abs();
        assert!(
            dx == 0 || dy == 0 || dx == dy,
            "8-connected run expected: {a:?} -> {b:?}"
        );
        let (lo, hi) = (dx.min(dy), dx.max(dy));
        cost += DIAGONAL_COST * lo + STRAIGHT_COST * (hi - lo);
    }
    cost
}

#[test]
fn every_bundled_world_parses() {
    for name in WORLDS {
        let da = std::fs::read_to_string(common::world(&format!("{name}.da"))).unwrap();
        let par = std::fs::read_to_string(common::world(&format!("{name}.par"))).unwrap();
        let mut obstacles = Obstacles::new();
        parse_da(&da, &mut obstacles).unwrap();
        assert!(!obstacles.is_empty(), "{name}");
        parse_par(&par).unwrap();
    }
}

#[test]
fn every_world_and_planner_gives_a_valid_collision_free_path() {
    for name in WORLDS {
        let da = common::world(&format!("{name}.da"));
        let par = common::world(&format!("{name}.par"));
        let world = load(&common::plan_args(Some(da.clone()), par.clone())).unwrap();
        let geometry = *world.grid.geometry();
        let res = geometry.resolution_m();
        let (start, goal) = (world.params.start, world.params.goal);
        let mut lengths = Vec::new();
        for planner in PLANNERS {
            let json = plan_json(&da, &par, planner, &[]);
            let what = format!("{name}/{planner}");
            assert_eq!(json["status"], "found", "{what}");
            assert_eq!(json["planner"], planner, "{what}");
            let path = path_of(&json);
            assert!(path.len() >= 2, "{what}");
            let (first, last) = (path[0], path[path.len() - 1]);
            assert!(
                (first.x_m - start.x_m).abs() <= res && (first.y_m - start.y_m).abs() <= res,
                "{what}: path starts at {first:?}, start is {start:?}"
            );
            assert!(
                (last.x_m - goal.x_m).abs() <= res && (last.y_m - goal.y_m).abs() <= res,
                "{what}: path ends at {last:?}, goal is {goal:?}"
            );
            for w in path.windows(2) {
                let a = geometry.cell_of(w[0]).unwrap();
                let b = geometry.cell_of(w[1]).unwrap();
                assert!(
                    segment_is_free(&world.grid, a, b),
                    "{what}: segment {a:?} -> {b:?} crosses an obstacle"
                );
            }
            let length_m = json["length_m"].as_f64().unwrap() as f32;
            assert!(
                (length_m - polyline_length_m(&path)).abs() < 1e-3,
                "{what}: length_m {length_m} is not the polyline's length"
            );
            assert!(json["expanded"].as_u64().unwrap() > 0, "{what}");
            if planner != "anyangle" {
                let cost = octile_cost(&geometry, &path);
                let reference = reference_astar_cost(
                    &world.grid,
                    geometry.cell_of(start).unwrap(),
                    geometry.cell_of(goal).unwrap(),
                )
                .unwrap();
                if planner == "astar" {
                    assert_eq!(cost, reference, "{what}: A* is optimal");
                } else {
                    assert!(cost >= reference, "{what}");
                }
            }
            lengths.push(length_m);
        }
        let (bfs, astar, anyangle) = (lengths[0], lengths[1], lengths[2]);
        assert!(astar <= bfs + 1e-3, "{name}: astar {astar} > bfs {bfs}");
        assert!(
            anyangle <= astar + 1e-3,
            "{name}: anyangle {anyangle} > astar {astar}"
        );
    }
}

#[test]
fn json_has_exactly_the_documented_shape() {
    let json = plan_json(
        &common::world("office.da"),
        &common::world("office.par"),
        "astar",
        &[],
    );
    let object = json.as_object().unwrap();
    let keys: BTreeSet<&str> = object.keys().map(String::as_str).collect();
    assert_eq!(keys, KEYS.into_iter().collect::<BTreeSet<_>>());
    assert!(json["status"].is_string());
    assert!(json["planner"].is_string());
    assert!(json["length_m"].is_f64());
    assert!(json["expanded"].is_u64());
    assert!(json["elapsed_us"].is_u64());
    for point in json["path"].as_array().unwrap() {
        let xy = point.as_array().unwrap();
        assert!(xy.len() == 2 && xy.iter().all(Value::is_number));
    }
}

#[test]
fn human_summary_and_picture() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("new-folder").join("office.png");
    let out = run(&[
        "--world",
        path_str(&common::world("office.da")),
        "--params",
        path_str(&common::world("office.par")),
        "--planner",
        "anyangle",
        "--png",
        path_str(&png),
    ]);
    assert_eq!(out.status.code(), Some(0));
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert!(stdout.contains("anyangle"), "{stdout}");
    assert!(stdout.contains("found"), "{stdout}");
    assert!(stdout.contains("300x300 cells"), "{stdout}");
    let image = image::open(&png).unwrap().to_rgb8();
    // 300 cells at 2 px (about 800 px for the map by default), plus axes, caption, legend.
    assert!(
        image.width() >= 600 && image.width() < 800,
        "{}",
        image.width()
    );
    assert!(image.height() > 600);
    let count = |c: image::Rgb<u8>| image.pixels().filter(|p| **p == c).count();
    use twil_host::picture::palette;
    for colour in [
        palette::OBSTACLE,
        palette::MAP,
        palette::PREFIX,
        palette::START,
        palette::GOAL,
        palette::ROBOT,
    ] {
        assert!(
            count(colour) > 0,
            "colour {colour:?} missing from the picture"
        );
    }
    // The scale bar: 1 m at 40 px per metre, 5 px thick, in a colour nothing else uses.
    assert_eq!(count(palette::SCALE_BAR), 40 * 5);
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

/// Run `twil plan` and expect exit 1 with one stderr line containing every `needle`.
fn expect_error(args: &[&str], needles: &[&str]) {
    let out = run(args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "args {args:?}: stderr {stderr}");
    assert!(out.stdout.is_empty(), "nothing on stdout on error");
    assert_eq!(stderr.trim_end().lines().count(), 1, "one line: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    for needle in needles {
        assert!(stderr.contains(needle), "`{needle}` not in: {stderr}");
    }
}

#[test]
fn bad_world_files_give_one_message_with_file_line_and_value() {
    let dir = tempfile::tempdir().unwrap();
    let par = common::world("office.par");
    let par = path_str(&par);
    let cases: [(&str, &[u8], &[&str]); 6] = [
        (
            "missing.da",
            b"1\n4\n0 0\n1 0\n1 1\n",
            &["missing.da: line 5", "vertex x", "ends"],
        ),
        (
            "absurd.da",
            b"999999999\n4\n",
            &["absurd.da: line 1", "obstacle count", "999999999"],
        ),
        (
            "absurd_vertices.da",
            b"1\n\n999999999 0 0\n",
            &["absurd_vertices.da: line 3", "vertex count", "999999999"],
        ),
        (
            "nan.da",
            b"1\n4\n0 0\n1 0\n1 one\n0 1\n",
            &["nan.da: line 5", "vertex y", "`one`"],
        ),
        (
            "garbage.da",
            b"1\n2\n\x00\x01\xff\xfe\x80garbage\n",
            &["garbage.da: line 3", "UTF-8"],
        ),
        (
            "latin1.da",
            b"1\n4 0 0 1 0 1 1 0 1 # caf\xe9\n",
            &["latin1.da: line 2"],
        ),
    ];
    for (name, bytes, needles) in cases {
        let da = write(dir.path(), name, bytes);
        expect_error(&["--world", path_str(&da), "--params", par], needles);
    }
    // Valid UTF-8 binary noise: the bad token is shown without control characters.
    let noise = write(dir.path(), "noise.da", b"1\n3\n0 0 \x01\x02\x1b[2J 5\n");
    expect_error(
        &["--world", path_str(&noise), "--params", par],
        &["noise.da: line 3", "not a number", "\\u{1}"],
    );
    expect_error(
        &[
            "--world",
            path_str(&dir.path().join("nope.da")),
            "--params",
            par,
        ],
        &["nope.da", "cannot open"],
    );
    expect_error(
        &["--world", path_str(dir.path()), "--params", par],
        &["directory"],
    );
}

#[test]
fn bad_par_files_give_one_message_with_file_line_and_value() {
    let dir = tempfile::tempdir().unwrap();
    let da = common::world("office.da");
    let da = path_str(&da);
    let cases: [(&str, &[u8], &[&str]); 4] = [
        (
            "short.par",
            b"0.4\n0.2\n90\n1.5 1.5\n13.5\n",
            &["short.par: line 5", "goal y"],
        ),
        (
            "word.par",
            b"0.4\nfast\n90\n1.5 1.5\n13.5 13\n",
            &["word.par: line 2", "speed", "`fast`"],
        ),
        (
            "radius.par",
            b"999999999\n0.2\n90\n1.5 1.5\n13.5 13\n",
            &["radius.par: line 1", "robot radius"],
        ),
        ("binary.par", &[0xff; 64], &["binary.par: line 1", "UTF-8"]),
    ];
    for (name, bytes, needles) in cases {
        let par = write(dir.path(), name, bytes);
        expect_error(&["--world", da, "--params", path_str(&par)], needles);
    }
}

/// A copy of office.par with another start and goal.
fn par_with(dir: &Path, start: (f32, f32), goal: (f32, f32)) -> PathBuf {
    write(
        dir,
        "mission.par",
        format!(
            "0.4 0.2 90\n{} {}\n{} {}\n",
            start.0, start.1, goal.0, goal.1
        )
        .as_bytes(),
    )
}

#[test]
fn statuses_other_than_found_exit_three() {
    let dir = tempfile::tempdir().unwrap();
    let office = common::world("office.da");
    // A closed box around (12, 7) m, well away from the other obstacles.
    let boxed = std::fs::read_to_string(&office).unwrap();
    let boxed = boxed.replacen("9\n", "10\n", 1) + "4\n11 6\n13 6\n13 8\n11 8\n";
    let boxed = write(dir.path(), "boxed.da", boxed.as_bytes());
    for (start, goal, status, world) in [
        ((1.5, 1.5), (12.0, 7.0), "unreachable", &boxed),
        ((4.15, 5.0), (13.5, 13.0), "start_blocked", &office),
        ((1.5, 1.5), (8.15, 10.0), "goal_blocked", &office),
        ((1.5, 1.5), (20.0, 13.0), "out_of_bounds", &office),
        ((-1.0, 1.5), (13.5, 13.0), "out_of_bounds", &office),
    ] {
        let par = par_with(dir.path(), start, goal);
        for planner in PLANNERS {
            let json = plan_json(world, &par, planner, &[]);
            assert_eq!(json["status"], status, "{planner} {start:?} -> {goal:?}");
            assert_eq!(json["path"].as_array().unwrap().len(), 0);
            assert_eq!(json["length_m"].as_f64(), Some(0.0));
        }
    }
}

#[test]
fn saved_map_replaces_or_complements_the_world() {
    let dir = tempfile::tempdir().unwrap();
    let da = common::world("office.da");
    let par = common::world("office.par");
    let world = load(&common::plan_args(Some(da.clone()), par.clone())).unwrap();
    let map = dir.path().join("office.map");
    twil_host::world_io::write_saved_map(&map, &world.grid).unwrap();
    assert_eq!(std::fs::metadata(&map).unwrap().len(), 300 * 300);

    let from_world = plan_json(&da, &par, "astar", &[]);
    let out = run(&[
        "--map",
        path_str(&map),
        "--params",
        path_str(&par),
        "--json",
    ]);
    assert_eq!(out.status.code(), Some(0));
    let from_map: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(from_map["path"], from_world["path"], "same grid, same path");

    // A saved map that walls off the goal's half, combined with the world: unreachable.
    let mut wall = Grid400::new(*world.grid.geometry()).unwrap();
    for y in 0..300 {
        wall.fill_row(y, 200, 202);
    }
    let wall_map = dir.path().join("wall.map");
    twil_host::world_io::write_saved_map(&wall_map, &wall).unwrap();
    let combined = plan_json(&da, &par, "bfs", &["--map", path_str(&wall_map)]);
    assert_eq!(combined["status"], "unreachable");

    // Wrong size: names the file and both sizes.
    let small = write(dir.path(), "small.map", &[0u8; 1000]);
    expect_error(
        &["--map", path_str(&small), "--params", path_str(&par)],
        &["small.map", "1000 bytes", "300x300", "90000"],
    );
}

#[test]
fn geometry_beyond_the_host_grid_is_an_error() {
    let da = common::world("office.da");
    let par = common::world("office.par");
    expect_error(
        &[
            "--world",
            path_str(&da),
            "--params",
            path_str(&par),
            "--size",
            "30x30",
        ],
        &["600x600 cells", "400x400"],
    );
    // A coarser grid covers the larger map.
    let json = plan_json(
        &da,
        &par,
        "astar",
        &["--size", "30x30", "--resolution", "0.1"],
    );
    assert_eq!(json["status"], "found");
}

#[test]
fn neither_world_nor_map_is_a_usage_error() {
    let par = common::world("office.par");
    let out = run(&["--params", path_str(&par)]);
    assert_eq!(out.status.code(), Some(2));
}
