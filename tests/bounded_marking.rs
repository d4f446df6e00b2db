//! Bounded marking on hostile `.da` files (issue 12): obstacles far off the map cost the map,
//! not their coordinates. The tester's two cases (a 4-vertex polygon at x = ±1e9 m, radius
//! 10 m; a 16 KB `.da` holding one 1 024-vertex polygon of long diagonal edges) are built here and
//! read through `twil plan`'s own loader; the marking's work counter (`twil_core::raster::Work`)
//! must stay within `raster::polygon_work_bound`, and `twil plan` must answer.

use crate::common;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use twil_core::grid::{Grid400, GridGeometry};
use twil_core::raster::{mark_polygon, polygon_work_bound};
use twil_core::world::{parse_da, Obstacles};
use twil_host::cmd::plan::load;

/// The 4-vertex polygon at x = ±1e9 m: two long horizontal edges through the map.
const FAR_POLYGON: &str = "1\n4\n-1e9 5  1e9 5\n1e9 6  -1e9 6\n";

/// One polygon of 1 024 vertices zig-zagging between (−40 km, −40 km) and (40 km, 40 km) (cell
/// ±800 000, inside the ±1e6 clamp, so every edge is a distinct 1.6-million-cell diagonal),
/// each crossing the map at a different offset. About 16 KB.
fn zigzag_da() -> String {
    let mut text = String::from("1\n1024\n");
    for i in 0..1024 {
        let side = if i % 2 == 0 { -40000.0 } else { 40000.0 };
        let offset = (i % 301) as f32 * 0.05 - 7.5;
        writeln!(text, "{side} {}", side + offset).unwrap();
    }
    text
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// The grown and the thin marking together (what `load` does) may cost at most one bound each.
fn assert_within_bound(da: &Path, par: &Path, radius_m: f32) {
    let world = load(&common::plan_args(
        Some(da.to_path_buf()),
        par.to_path_buf(),
    ))
    .unwrap();
    let geometry = *world.grid.geometry();
    let vertices = world.obstacles.vertex_count();
    let half = geometry.expansion_cells(radius_m);
    assert_eq!(world.expansion_cells, half);
    let bound = polygon_work_bound(&geometry, vertices) + polygon_work_bound(&geometry, vertices);
    assert!(
        world.marking_work <= bound,
        "{}: work {} above the bound {bound}",
        da.display(),
        world.marking_work
    );
    // And `twil plan` itself answers (it reports the start blocked or a plan).
    let out = common::twil()
        .arg("plan")
        .args([
            "--world",
            da.to_str().unwrap(),
            "--params",
            par.to_str().unwrap(),
        ])
        .arg("--json")
        .output()
        .unwrap();
    assert!(
        out.status.code().is_some(),
        "twil plan ended by a signal: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn far_and_long_polygons_cost_the_map_through_twil_plan() {
    let dir = tempfile::tempdir().unwrap();
    let par = write(dir.path(), "r04.par", "0.4 0.2 90\n1.5 1.5\n13.5 13.0\n");
    let far = write(dir.path(), "far.da", FAR_POLYGON);
    let zigzag_text = zigzag_da();
    assert!(
        (15_000..17_500).contains(&zigzag_text.len()),
        "{} bytes",
        zigzag_text.len()
    );
    let zigzag = write(dir.path(), "zigzag.da", &zigzag_text);
    assert_within_bound(&far, &par, 0.4);
    assert_within_bound(&zigzag, &par, 0.4);
}

/// The tester's radius, 10 m (a growth of 200 cells on the seed's map), through the same
/// marking `twil plan` uses; the bound is the map's, and far below the old cost (the old
/// marking walked 2 million cells per edge, each grown to 401 rows).
#[test]
fn radius_ten_metres_costs_the_map() {
    let geometry = GridGeometry::seed_default();
    let half = geometry.expansion_cells(10.0);
    assert_eq!(half, 200);
    for (name, text) in [("far", FAR_POLYGON.to_string()), ("zigzag", zigzag_da())] {
        let mut obstacles = Obstacles::new();
        parse_da(&text, &mut obstacles).unwrap();
        let mut grid = Grid400::new(geometry).unwrap();
        let mut work = 0;
        for polygon in obstacles.iter() {
            work += mark_polygon(&mut grid, polygon, half);
        }
        let bound = polygon_work_bound(&geometry, obstacles.vertex_count());
        assert!(work <= bound, "{name}: work {work} above the bound {bound}");
        // Every edge crosses the map and grows by 200 cells: the whole map is marked.
        assert_eq!(grid.count_occupied(), geometry.cell_count(), "{name}");
        eprintln!(
            "{name}: {} vertices, work {work} (bound {bound})",
            obstacles.vertex_count()
        );
    }
}
