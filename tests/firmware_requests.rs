//! The worst requests on the firmware under QEMU (`-icount shift=0`: instruction counts), issue
//! 12: after bounded marking, what does one request cost at most, and is a `Ping` answered
//! right after it?
//!
//! The heaviest requests mark obstacles: `SetParams` re-marks every stored vertex (at most
//! `MAX_VERTICES` = 1 024) grown by the new radius, and the `ObstacleChunk` that closes a polygon
//! (at most `MAX_PENDING_VERTICES` = 256) marks it. Their cost is the map's rows per edge (see
//! `twil_core::raster`), so the worst inputs are many long edges crossing every row, on the
//! seed's 300 × 300 map and on the tallest map the grid holds (21 × 4 096 cells), with the
//! largest radius `SetParams` accepts (10 m). `Plan` has its own budget (`mcu_bench` in
//! tests/firmware_qemu.rs). `cargo xtask mcu-bench` runs this test and prints the table.
//!
//! The device refuses marking that would visit more than `MAX_MARKING_ROWS` rows (vertices ×
//! map height: `ErrorCode::MarkingBudget`), so a tall map holds fewer vertices; the test fills
//! each map up to that budget and checks that one vertex more is refused.
//!
//! Budgets: on any map at most `REQUEST_BUDGET` instructions (a fraction of the watchdog's 1 s),
//! and at most `INSTRUCTIONS_PER_WORK_UNIT` per unit of the documented work bound
//! (`raster::polygon_work_bound`: rows and words).

use twil_core::geom::PointM;
use twil_core::grid::GridGeometry;
use twil_core::link::handler::MAX_MARKING_ROWS;
use twil_core::link::{MapParams, Reply, Request};
use twil_core::raster::polygon_work_bound;
use twil_core::world::MAX_VERTICES;
use twil_host::remote::{Remote, RemoteSpec};

/// Budget of one request (other than `Plan`) on any map, instructions (0.36 s at 168 MHz).
const REQUEST_BUDGET: u64 = 60_000_000;
/// Instructions per unit of `raster::polygon_work_bound` (a row visit or a word written) any
/// marking request may cost, on any map.
const INSTRUCTIONS_PER_WORK_UNIT: u64 = 100;
/// Vertices of one polygon over the link (`link::handler::MAX_PENDING_VERTICES`).
const POLYGON_VERTICES: usize = 256;
/// Core clock of the STM32F405 on the board, Hz.
const CORE_HZ: f64 = 168e6;

fn qemu() -> Remote {
    match Remote::connect(&RemoteSpec::Qemu) {
        Ok((r, _)) => r,
        Err(e) => panic!(
            "cannot run the firmware under QEMU: {e:#}\n\
             (run `cargo xtask test`, which installs qemu-system-arm and builds the firmware)"
        ),
    }
}

/// A polygon of `POLYGON_VERTICES` vertices zig-zagging between two far points (up to ±40 km,
/// inside the ±1e6-cell clamp) on the line of the map's diagonal: each edge is a long line
/// crossing every row of the map, shifted across it by its own offset (`number` picks them).
fn zigzag(map_m: (f32, f32), number: usize, vertices: usize) -> Vec<PointM> {
    let (w, h) = map_m;
    let far = 40_000.0 / w.max(h);
    (0..vertices)
        .map(|i| {
            let side = if i % 2 == 0 { -far } else { far };
            let t = ((i * 7 + number * 13) % 101) as f32 / 100.0 - 0.5;
            PointM::new(
                w / 2.0 + side * w + t * w / 2.0,
                h / 2.0 + side * h - t * h / 2.0,
            )
        })
        .collect()
}

fn params(width: u16, height: u16, radius_m: f32) -> MapParams {
    MapParams {
        width_cells: width,
        height_cells: height,
        resolution_m: 0.05,
        robot_radius_m: radius_m,
    }
}

/// Instructions of the request just answered (read with `Status`, which reports the one before).
fn last_request_instructions(remote: &mut Remote) -> u64 {
    match remote.call(Request::Status).expect("status") {
        Reply::Status(s) => s.last_request_instructions,
        other => panic!("{other:?}"),
    }
}

/// Send `request`, read its cost, check that a ping right after it is answered.
fn measure(remote: &mut Remote, request: Request) -> u64 {
    if let Reply::Error(e) = remote.request(request).expect("link") {
        panic!("refused: {e}");
    }
    let n = last_request_instructions(remote);
    remote
        .ping(0x5eed)
        .expect("a ping after the request is answered");
    n
}

#[test]
#[ignore = "QEMU: `cargo xtask mcu-bench` and `cargo xtask test` run it"]
fn worst_requests_stay_within_the_budget() {
    let mut remote = qemu();
    println!();
    println!("| request | map (cells) | radius | vertices | work bound | MCU instructions | per work unit | ms at 168 MHz (1 per cycle) |");
    println!("|---|---|---:|---:|---:|---:|---:|---:|");
    let mut worst = (String::new(), 0u64);
    let mut over = Vec::new();
    for (width, height) in [(300u16, 300u16), (21, 4096), (4096, 21)] {
        let map_m = (width as f32 * 0.05, height as f32 * 0.05);
        let map = format!("{width} x {height}");
        let geometry = GridGeometry::new(width as u32, height as u32, 0.05).unwrap();
        let mut record = |what: &str, radius_m: f32, vertices: usize, n: u64| {
            let bound = polygon_work_bound(&geometry, vertices);
            println!(
                "| {what} | {map} | {radius_m} m | {vertices} | {bound} | {n} | {:.1} | {:.1} |",
                n as f64 / bound as f64,
                n as f64 / CORE_HZ * 1e3
            );
            if n > INSTRUCTIONS_PER_WORK_UNIT * bound || n > REQUEST_BUDGET {
                over.push(format!("{what} on {map}, radius {radius_m} m: {n}"));
            }
            if n > worst.1 {
                worst = (format!("{what} on {map} cells, radius {radius_m} m"), n);
            }
        };
        // As many vertices as the marking budget lets this map hold.
        let budget_vertices = (MAX_MARKING_ROWS / height as u32).min(MAX_VERTICES as u32) as usize;
        let polygon_vertices = budget_vertices.min(POLYGON_VERTICES);
        // The closing chunk of one polygon, marked with the largest radius.
        remote.call(Request::ClearMap).expect("clear");
        remote
            .call(Request::SetParams(params(width, height, 10.0)))
            .expect("params");
        let polygon = zigzag(map_m, 0, polygon_vertices);
        remote.upload_polygon(&polygon).expect("upload");
        let n = last_request_instructions(&mut remote);
        remote.ping(1).expect("ping after the closing chunk");
        record("ObstacleChunk (closing)", 10.0, polygon_vertices, n);
        // Fill the store up to the budget with a small radius, then re-mark it all.
        remote.call(Request::ClearMap).expect("clear");
        remote
            .call(Request::SetParams(params(width, height, 0.0)))
            .expect("params");
        let mut stored = 0;
        for number in 0.. {
            let vertices = (budget_vertices - stored).min(POLYGON_VERTICES);
            if vertices == 0 {
                break;
            }
            remote
                .upload_polygon(&zigzag(map_m, number, vertices))
                .expect("upload");
            stored += vertices;
        }
        if budget_vertices < MAX_VERTICES {
            // One vertex more would go over the budget.
            let refused = remote.upload_polygon(&zigzag(map_m, 99, 1));
            let message = format!("{:#}", refused.expect_err("over the marking budget"));
            assert!(message.contains("map rows"), "{message}");
        }
        for radius_m in [0.4, 10.0] {
            let n = measure(
                &mut remote,
                Request::SetParams(params(width, height, radius_m)),
            );
            record("SetParams (re-mark)", radius_m, budget_vertices, n);
        }
    }
    println!();
    println!(
        "worst request: {}: {} instructions ({:.1} ms at 168 MHz, 1 instruction per cycle)",
        worst.0,
        worst.1,
        worst.1 as f64 / CORE_HZ * 1e3
    );
    assert!(
        over.is_empty(),
        "over {INSTRUCTIONS_PER_WORK_UNIT} instructions per unit of work bound, or over \
         {REQUEST_BUDGET} instructions: {over:?}"
    );
}
