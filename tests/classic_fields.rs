//! Issue 15, item 8 (Voronoi roadmap and potential field): collision-free paths on every
//! bundled world, the Voronoi path's clearance the largest of the methods that found a path,
//! Voronoi finding a path wherever A* does (the U-shaped trap included: its medial axis is
//! bridged to the rest of the roadmap), and the potential field's honest local minimum in the
//! trap (`worlds/trap`).

use twil_host::classic::{self, Method, Options, Status};
use twil_host::cmd::plan::{load, parse_size, Args};

fn world(name: &str, size: &str) -> twil_host::cmd::plan::World {
    load(&Args {
        world: Some(crate::common::world(&format!("{name}.da"))),
        planning: twil_host::cmd::args::PlanningArgs {
            params: crate::common::world(&format!("{name}.par")),
            size: parse_size(size).unwrap(),
            resolution: 0.05,
            robot: None,
        },
        map: None,
        planner: Method::Voronoi,
        json: false,
        png: None,
        record: None,
        scale: None,
        remote: None,
    })
    .unwrap()
}

const WORLDS: [(&str, &str); 6] = [
    ("office", "15x15"),
    ("corridor", "15x15"),
    ("pillars", "15x15"),
    ("enclosed", "15x15"),
    ("lab", "18x10"),
    ("trap", "15x15"),
];

#[test]
fn paths_are_collision_free_and_voronoi_keeps_the_largest_clearance() {
    for (name, size) in WORLDS {
        let w = world(name, size);
        let mut best_other = f32::NEG_INFINITY;
        let mut voronoi = None;
        for m in [
            Method::Bfs,
            Method::Astar,
            Method::Anyangle,
            Method::Voronoi,
            Method::Quadtree,
            Method::Potential,
        ] {
            let run = classic::run(m, &w, &Options::default()).unwrap();
            if run.status != Status::Found && run.status != Status::LocalMinimum {
                continue;
            }
            let c = classic::min_clearance_m(&w, &run).unwrap();
            assert!(c >= -0.05, "{name} {}: clearance {c}", m.as_str());
            if run.status != Status::Found {
                continue;
            }
            if m == Method::Voronoi {
                voronoi = Some(c);
            } else {
                best_other = best_other.max(c);
            }
        }
        if name == "enclosed" {
            // The goal is inside a closed box: nobody finds a path.
            assert!(voronoi.is_none());
            continue;
        }
        let v = voronoi.unwrap_or_else(|| panic!("{name}: voronoi found no path"));
        assert!(v + 1e-3 >= best_other, "{name}: voronoi {v} < {best_other}");
    }
}

#[test]
fn voronoi_finds_a_path_wherever_astar_does() {
    for (name, size) in WORLDS {
        let w = world(name, size);
        let astar = classic::run(Method::Astar, &w, &Options::default()).unwrap();
        let voronoi = classic::run(Method::Voronoi, &w, &Options::default()).unwrap();
        assert_eq!(voronoi.status, astar.status, "{name}");
        if astar.status != Status::Found {
            continue;
        }
        assert_eq!(voronoi.path.first(), Some(&w.params.start), "{name}");
        assert_eq!(voronoi.path.last(), Some(&w.params.goal), "{name}");
        let c = classic::min_clearance_m(&w, &voronoi).unwrap();
        assert!(c >= -0.05, "{name}: clearance {c}");
    }
    // In the trap the start is on the U's own axis, which the 60° rule cuts short of the
    // ridge around the U: only a bridge joins them.
    let trap = classic::run(
        Method::Voronoi,
        &world("trap", "15x15"),
        &Options::default(),
    );
    assert!(trap.unwrap().extra["bridge_cells"].as_u64().unwrap() > 0);
}

#[test]
fn potential_field_reports_the_u_trap_minimum() {
    let w = world("trap", "15x15");
    let run = classic::run(Method::Potential, &w, &Options::default()).unwrap();
    assert_eq!(run.status, Status::LocalMinimum);
    assert!(run.path.len() >= 2);
    // It stopped inside the U (x between 6 and 9.8 m), short of the goal at x = 13.5 m.
    let last = run.path.last().unwrap();
    assert!(last.x_m > 6.0 && last.x_m < 9.8, "{last:?}");
}
