//! Planner benchmark: our BFS and A* against the `pathfinding` crate's `bfs` / `astar` on the same
//! 300 × 300 grids (open floor, 20 % random obstacles, a maze, and the bundled seed worlds
//! `worlds/{office,corridor,pillars}` grown by the robot radius), same neighbour rule, same costs.
//!
//! Run: `cargo bench -p twil-core --bench planners` (optionally `-- REPEATS`, default 30).
//! For each case and algorithm it prints the fastest time of ours and theirs over the repeats
//! (interleaved), the ratios, the costs (which must be identical; the bench exits non-zero otherwise) and the
//! cells we expanded. Any-angle is timed too (ours only: pathfinding has none).

// A benchmark (a program, not the core) stops at the first surprise.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::hint::black_box;
use std::time::{Duration, Instant};

use twil_core::geom::Cell;
use twil_core::grid::Grid300;
use twil_core::plan::{
    PlanError, PlanReport, PlanStatus, Planner, PlannerKind, DIAGONAL_COST, SCRATCH_WORDS_300,
    STRAIGHT_COST,
};
use twil_core::raster::mark_polygon;
use twil_core::world::{parse_da, parse_par, Obstacles};

mod grids;

use grids::{empty, maze_case, open_case};
const QUEUE: usize = 32 * 1024;
type Bench300 = Planner<SCRATCH_WORDS_300, QUEUE>;

/// 20 % random obstacles, connected according to our BFS.
fn random_case(planner: &mut Bench300) -> (Grid300, Cell, Cell) {
    grids::random_case(|g, s, t| {
        let r = planner
            .plan_cells(PlannerKind::Bfs, g, s, t)
            .expect("capacity");
        r.status == PlanStatus::Found
    })
}

/// A bundled seed world (`worlds/NAME.da` + `.par`), obstacles grown by the robot radius as
/// the seed does, start and goal from the `.par`.
fn world_case(name: &str) -> (Grid300, Cell, Cell) {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../worlds/");
    let read = |ext: &str| {
        std::fs::read_to_string(format!("{dir}{name}.{ext}"))
            .unwrap_or_else(|e| panic!("{dir}{name}.{ext}: {e}"))
    };
    let params = parse_par(&read("par")).expect("par");
    let mut obstacles = Obstacles::new();
    parse_da(&read("da"), &mut obstacles).expect("da");
    let mut g = empty();
    let half_side = g.geometry().expansion_cells(params.robot_radius_m);
    for polygon in obstacles.iter() {
        mark_polygon(&mut g, polygon, half_side);
    }
    let geometry = *g.geometry();
    let s = geometry.cell_of(params.start).expect("start on the map");
    let t = geometry.cell_of(params.goal).expect("goal on the map");
    (g, s, t)
}

type Node = (u16, u16);

/// The neighbour rule for the oracle, without allocation: at most 8 successors.
fn successors(g: &Grid300, &(x, y): &Node) -> impl Iterator<Item = (Node, u32)> {
    let (x, y) = (x as i32, y as i32);
    let free = |x: i32, y: i32| !g.is_occupied_xy(x, y);
    let (e, w, n, s) = (
        free(x + 1, y),
        free(x - 1, y),
        free(x, y + 1),
        free(x, y - 1),
    );
    let node = |x: i32, y: i32| (x as u16, y as u16);
    [
        e.then(|| (node(x + 1, y), STRAIGHT_COST)),
        n.then(|| (node(x, y + 1), STRAIGHT_COST)),
        w.then(|| (node(x - 1, y), STRAIGHT_COST)),
        s.then(|| (node(x, y - 1), STRAIGHT_COST)),
        (n && e && free(x + 1, y + 1)).then(|| (node(x + 1, y + 1), DIAGONAL_COST)),
        (n && w && free(x - 1, y + 1)).then(|| (node(x - 1, y + 1), DIAGONAL_COST)),
        (s && w && free(x - 1, y - 1)).then(|| (node(x - 1, y - 1), DIAGONAL_COST)),
        (s && e && free(x + 1, y - 1)).then(|| (node(x + 1, y - 1), DIAGONAL_COST)),
    ]
    .into_iter()
    .flatten()
}

fn octile(a: &Node, b: &Node) -> u32 {
    let dx = a.0.abs_diff(b.0) as u32;
    let dy = a.1.abs_diff(b.1) as u32;
    let (lo, hi) = (dx.min(dy), dx.max(dy));
    DIAGONAL_COST * lo + STRAIGHT_COST * (hi - lo)
}

/// Fastest of `repeats` runs of each closure, interleaved (ours, theirs, theirs, ours, ...) so
/// that load from other processes hits all of them alike. The minimum is the least noisy
/// estimate of the cost of the code itself.
fn race<A, B, C>(
    repeats: usize,
    mut a: impl FnMut() -> A,
    mut b: impl FnMut() -> B,
    mut c: impl FnMut() -> C,
) -> ([Duration; 3], A, B, C) {
    let mut best = [Duration::MAX; 3];
    let once = |best: &mut Duration, f: &mut dyn FnMut()| {
        let t0 = Instant::now();
        f();
        *best = (*best).min(t0.elapsed());
    };
    let (mut ra, mut rb, mut rc) = (None, None, None);
    for _ in 0..repeats {
        once(&mut best[0], &mut || ra = Some(black_box(a())));
        once(&mut best[1], &mut || rb = Some(black_box(b())));
        once(&mut best[2], &mut || rc = Some(black_box(c())));
    }
    (best, ra.expect("ran"), rb.expect("ran"), rc.expect("ran"))
}

/// Plan and return the report; a path with more vertices than the output holds still counts
/// (the search ran to the goal; the report is kept by the planner).
fn run(planner: &mut Bench300, kind: PlannerKind, g: &Grid300, s: Cell, t: Cell) -> PlanReport {
    match planner.plan_cells(kind, g, s, t) {
        Ok(report) => report,
        Err(PlanError::PathFull { .. }) => planner.last_report().expect("report"),
        Err(e) => panic!("{kind:?}: {e}"),
    }
}

fn us(d: Duration) -> f64 {
    d.as_secs_f64() * 1e6
}

fn main() {
    let repeats: usize = std::env::args()
        .skip(1)
        .find_map(|a| a.parse().ok())
        .unwrap_or(30)
        .max(1);
    let mut planner: Box<Bench300> = Box::new(Planner::new());
    let cases = [
        ("open", open_case()),
        ("random20", random_case(&mut planner)),
        ("maze", maze_case()),
        ("office", world_case("office")),
        ("corridor", world_case("corridor")),
        ("pillars", world_case("pillars")),
    ];
    // `--only CASE:PLANNER` runs just our planner, `repeats` times, and prints nothing else: for
    // counting instructions (`perf stat -e instructions:u`, difference of two repeat counts).
    let args: Vec<String> = std::env::args().collect();
    if let Some(i) = args.iter().position(|a| a == "--only") {
        let spec = args.get(i + 1).map(String::as_str).unwrap_or("");
        let (case, algo) = spec.split_once(':').unwrap_or((spec, "astar"));
        let kind = match algo {
            "bfs" => PlannerKind::Bfs,
            "anyangle" => PlannerKind::AnyAngle,
            _ => PlannerKind::AStar,
        };
        let (_, (g, s, t)) = cases
            .iter()
            .find(|(name, _)| *name == case)
            .expect("case: open, random20, maze, office, corridor or pillars");
        for _ in 0..repeats {
            black_box(run(&mut planner, kind, g, *s, *t));
        }
        return;
    }
    println!(
        "300x300 grids, fastest of {repeats} interleaved runs; our scratch {} B + queue {} B",
        SCRATCH_WORDS_300 * 4,
        QUEUE * 12
    );
    println!("pf = pathfinding 4 with allocation-free successors, pf-vec = with Vec successors");
    println!(
        "{:<9} {:<9} {:>9} {:>9} {:>7} {:>9} {:>7} {:>10} {:>9} {:>6}",
        "case",
        "planner",
        "ours_us",
        "pf_us",
        "ratio",
        "pf-vec_us",
        "ratio",
        "cost",
        "expanded",
        "peak_q"
    );
    let mut ok = true;
    let mut row = |name: &str,
                   algo: &str,
                   t: [Duration; 3],
                   ours: PlanReport,
                   peak: u32,
                   theirs: [Option<u32>; 2]| {
        let same = ours.status == PlanStatus::Found && theirs.iter().all(|c| *c == Some(ours.cost));
        ok &= same;
        println!(
            "{:<9} {:<9} {:>9.0} {:>9.0} {:>6.1}x {:>9.0} {:>6.1}x {:>10} {:>9} {:>6}{}",
            name,
            algo,
            us(t[0]),
            us(t[1]),
            us(t[1]) / us(t[0]),
            us(t[2]),
            us(t[2]) / us(t[0]),
            ours.cost,
            ours.expanded,
            peak,
            if same { "" } else { "  COST MISMATCH" }
        );
    };
    let mut any_rows = Vec::new();
    for (name, (g, s, t)) in &cases {
        let (s, t) = (*s, *t);
        let (sn, tn) = ((s.x, s.y), (t.x, t.y));

        let (times, ours, theirs, theirs_vec) = race(
            repeats,
            || run(&mut planner, PlannerKind::Bfs, g, s, t),
            || pathfinding::prelude::bfs(&sn, |n| successors(g, n).map(|(m, _)| m), |n| *n == tn),
            || {
                pathfinding::prelude::bfs(
                    &sn,
                    |n| successors(g, n).map(|(m, _)| m).collect::<Vec<_>>(),
                    |n| *n == tn,
                )
            },
        );
        let steps = |p: Option<Vec<Node>>| p.map(|p| p.len() as u32 - 1);
        row(
            name,
            "bfs",
            times,
            ours,
            planner.queue_peak(),
            [steps(theirs), steps(theirs_vec)],
        );

        let (times, ours, theirs, theirs_vec) = race(
            repeats,
            || run(&mut planner, PlannerKind::AStar, g, s, t),
            || {
                pathfinding::prelude::astar(
                    &sn,
                    |n| successors(g, n),
                    |n| octile(n, &tn),
                    |n| *n == tn,
                )
            },
            || {
                pathfinding::prelude::astar(
                    &sn,
                    |n| successors(g, n).collect::<Vec<_>>(),
                    |n| octile(n, &tn),
                    |n| *n == tn,
                )
            },
        );
        let cost = |p: Option<(Vec<Node>, u32)>| p.map(|(_, c)| c);
        row(
            name,
            "astar",
            times,
            ours,
            planner.queue_peak(),
            [cost(theirs), cost(theirs_vec)],
        );

        let mut best = Duration::MAX;
        let mut any = None;
        for _ in 0..repeats {
            let t0 = Instant::now();
            any = Some(black_box(run(&mut planner, PlannerKind::AnyAngle, g, s, t)));
            best = best.min(t0.elapsed());
        }
        let any = any.expect("ran");
        any_rows.push((name, best, any, ours));
    }
    println!();
    println!(
        "{:<9} {:>12} {:>12} {:>12}",
        "case", "anyangle_us", "length_m", "astar_len_m"
    );
    for (name, best, any, astar) in any_rows {
        println!(
            "{:<9} {:>12.0} {:>12.2} {:>12.2}",
            name,
            us(best),
            any.length_m,
            astar.length_m
        );
    }
    if !ok {
        eprintln!("costs differ from pathfinding");
        std::process::exit(1);
    }
}
