//! The two-link manipulator planner of seed 000 (Heuberger, 1990): configuration map and A*.
//!
//! The thesis plans for an arm of two joints among fixed polygonal obstacles by turning the
//! obstacles into the arm's *configuration space*: a bit per pair of discretized joint values,
//! set where the arm would collide. A path is then a polyline in that plane that avoids the set
//! bits, and the shortest one (least joint motion, `√(Δq₁² + Δq₂²)`) bends only at corners of the
//! collision regions, so an A* over those corners with a straight-line visibility test finds it.
//! The same machinery plans for a moving object (two prismatic joints along x and y: the
//! thesis' navigation case).
//!
//! Pipeline, one module per step, each usable alone:
//!
//! - [`rob`]: the `.ROB` input (obstacles, joints R/P with limits, arm polygons).
//! - [`geometry`]: homogeneous transforms (§2.2) and convex-polygon collision (§2.1).
//! - [`map`]: the configuration map for given increments (§2.3, §3.2) and its `.MAP` text.
//! - [`search`]: the line test and the any-angle A* over corner nodes (§3.3).
//! - [`tra`]: the `.TRA` path text (§3, appendix B.3).
//!
//! Everything is `no_std` and allocation-free: polygons, maps, node lists and paths have the
//! capacities named in their modules, and running out is an error value. Text readers report
//! the line, field, polygon/joint and value of the first problem ([`text::FileError`]).
//!
//! ```
//! use twil_core::cspace::{map::ConfigMap, rob::parse_rob, search::{NodeSet, Search, SearchStatus}};
//! let robot = parse_rob(include_str!("../../worlds/seed000-nav.ROB")).unwrap();
//! let map = ConfigMap::build(&robot, [2.0, 2.0]).unwrap();
//! let mut search = Box::new(Search::new());
//! let report = search.run(&map, [-60.0, -35.0], [140.0, -5.0], NodeSet::Corners).unwrap();
//! assert_eq!(report.status, SearchStatus::Found);
//! ```

pub mod geometry;
pub mod map;
pub mod rob;
pub mod search;
pub mod text;
pub mod tra;
