//! `twil cspace`: plan for the two-joint manipulator of seed 000 in its configuration space.
//!
//! Reads a `.ROB` file, builds the configuration map for the given joint increments, runs the
//! any-angle A* from start to goal (joint values), and writes what was asked: the map (`.MAP`),
//! the path (`.TRA`, 1-based indices as in the thesis), a PNG of the map with the path beside
//! the workspace, a GIF of the arm moving along the path, and a JSON summary on stdout. All the
//! logic is `twil_core::cspace`; this file reads and writes files.
//!
//! The exit code (`crate::exit`) is 0 when a path was found and 3 when none was (`unreachable`,
//! `start_blocked`, ...); it is 1 for unreadable or malformed files and impossible increments.

use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context};
use serde::Serialize;
use twil_core::cspace::{
    map::{ConfigMap, MapError},
    rob::Robot,
    search::{path_is_free, path_length, NodeSet, Search, SearchReport, SearchStatus},
    tra::Trajectory,
};

use crate::cspace::load::{load_map, load_robot, load_tra};
use crate::cspace::render::{self, Scene};
use crate::files::{self, FileError};

/// Which cells become search nodes.
#[derive(clap::ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Nodes {
    /// Convex corners of the collision regions (the thesis' method).
    #[default]
    Corners,
    /// Every free cell next to a collision.
    Boundary,
    /// Every free cell (slow).
    All,
}

impl From<Nodes> for NodeSet {
    fn from(n: Nodes) -> Self {
        match n {
            Nodes::Corners => NodeSet::Corners,
            Nodes::Boundary => NodeSet::Boundary,
            Nodes::All => NodeSet::All,
        }
    }
}

/// Arguments of `twil cspace`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The robot and obstacles (`.ROB`, seed 000 appendix A.1/B.1).
    #[arg(long, value_name = "F.ROB")]
    pub rob: PathBuf,
    /// Increments of joint 1 and joint 2 (degrees for rotational joints, units for prismatic).
    #[arg(
        long,
        value_name = "D1,D2",
        value_parser = parse_pair,
        allow_hyphen_values = true,
        required_unless_present = "from_map"
    )]
    pub increments: Option<[f32; 2]>,
    /// Plan on this configuration map (`.MAP`, e.g. one edited by hand) instead of building it;
    /// the `.ROB` still gives the arm for the pictures and which joints wrap.
    #[arg(long, value_name = "F.MAP")]
    pub from_map: Option<PathBuf>,
    /// Start configuration, joint units (snapped to the nearest map values).
    #[arg(long, value_name = "A,B", value_parser = parse_pair, allow_hyphen_values = true)]
    pub start: [f32; 2],
    /// Goal configuration, joint units.
    #[arg(long, value_name = "C,D", value_parser = parse_pair, allow_hyphen_values = true)]
    pub goal: [f32; 2],
    /// Search nodes.
    #[arg(long, value_enum, default_value_t = Nodes::Corners)]
    pub nodes: Nodes,
    /// Write the configuration map here (`.MAP`).
    #[arg(long, value_name = "OUT.MAP")]
    pub map: Option<PathBuf>,
    /// Write the path here (`.TRA`, 1-based indices).
    #[arg(long, value_name = "OUT.TRA")]
    pub tra: Option<PathBuf>,
    /// Write a PNG of the map with the path and of the workspace.
    #[arg(long, value_name = "OUT.png")]
    pub png: Option<PathBuf>,
    /// Write a GIF of the arm moving along the path.
    #[arg(long, value_name = "OUT.gif")]
    pub gif: Option<PathBuf>,
    /// Frames of the GIF.
    #[arg(long, default_value_t = 60, value_parser = clap::value_parser!(u16).range(2..=1000))]
    pub frames: u16,
    /// A reference path (`.TRA`, e.g. the thesis' one): drawn in orange, checked against the map
    /// and its length reported.
    #[arg(long, value_name = "REF.TRA")]
    pub compare: Option<PathBuf>,
    /// Print a JSON summary on stdout instead of text.
    #[arg(long)]
    pub json: bool,
}

/// The JSON summary.
#[derive(Serialize, Debug)]
pub struct Summary {
    /// `found`, `unreachable`, `start_outside`, `goal_outside`, `start_blocked`, `goal_blocked`.
    pub status: &'static str,
    /// Path corners in joint units, start first.
    pub path: Vec<[f32; 2]>,
    /// Path length in joint units, `Σ √(Δq₁² + Δq₂²)`.
    pub length: f32,
    /// `[NC, NL]`: values of joint 1 and of joint 2 in the map.
    pub cells: [u16; 2],
    /// Free configurations in the map.
    pub free_cells: usize,
    /// Search nodes (start, goal and corners).
    pub nodes: u32,
    /// Nodes expanded by A*.
    pub expanded: u32,
    /// Line tests made.
    pub line_tests: u32,
    /// The reference path of `--compare`, if given.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub compare: Option<CompareSummary>,
}

/// The `--compare` part of the summary.
#[derive(Serialize, Debug)]
pub struct CompareSummary {
    /// Its length in joint units.
    pub length: f32,
    /// `true` when every segment passes the line test on our map.
    pub free: bool,
}

/// Parse `A,B` into two finite numbers.
pub fn parse_pair(s: &str) -> Result<[f32; 2], String> {
    let mut it = s.split(',').map(|t| t.trim().parse::<f32>());
    match (it.next(), it.next(), it.next()) {
        (Some(Ok(a)), Some(Ok(b)), None) if a.is_finite() && b.is_finite() => Ok([a, b]),
        _ => Err(format!(
            "expected two numbers separated by a comma, got `{s}`"
        )),
    }
}

/// Build the map of `robot` (read from `rob`). A map too large for its joint limits names the
/// `.ROB` file with the lines and fields of the limits; a bad increment names `--increments`.
pub fn build_map(rob: &Path, robot: &Robot, increments: [f32; 2]) -> anyhow::Result<ConfigMap> {
    ConfigMap::build(robot, increments).map_err(|e| match e {
        MapError::TooManyValues { line, .. } => anyhow::Error::new(
            FileError::new(rob, Some(line), e.to_string()).see(crate::files::ROB.doc),
        ),
        MapError::TooManyCells { .. } => {
            anyhow::Error::new(FileError::whole(rob, e).see(crate::files::ROB.doc))
        }
        MapError::BadIncrement { .. } | MapError::WrapIncrement { .. } => {
            anyhow::anyhow!("--increments: {e}")
        }
    })
}

/// Run `twil cspace`.
pub fn run(args: Args) -> anyhow::Result<crate::exit::Ending> {
    let (start, goal) = (args.start, args.goal);
    let robot = load_robot(&args.rob)?;
    let map = match (&args.from_map, args.increments) {
        (Some(path), increments) => {
            let map = load_map(path, &robot)?;
            let axes = map.axes();
            let own = [axes[0].increment, axes[1].increment];
            if let Some(inc) = increments.filter(|inc| *inc != own) {
                bail!(
                    "--increments {},{} disagree with {} ({},{})",
                    inc[0],
                    inc[1],
                    files::printable(&path.display().to_string()),
                    own[0],
                    own[1]
                );
            }
            map
        }
        (None, Some(increments)) => build_map(&args.rob, &robot, increments)?,
        (None, None) => bail!("--increments is needed unless --from-map is given"),
    };
    let increments = [map.axes()[0].increment, map.axes()[1].increment];
    let mut search = Box::new(Search::new());
    let report: SearchReport = search
        .run(&map, start, goal, args.nodes.into())
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    let axes = map.axes();
    let to_q = |p: &[i32; 2]| [axes[0].value(p[0]), axes[1].value(p[1])];
    let path_q: Vec<[f32; 2]> = report.path.iter().map(to_q).collect();
    let rob_name = args
        .rob
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();

    let compare = match &args.compare {
        Some(p) => {
            let t = load_tra(p)?;
            let idx = t.to_map_indices();
            let q: Vec<[f32; 2]> = (0..t.points.len()).filter_map(|k| t.value(k)).collect();
            let same_grid = t.min == [axes[0].min, axes[1].min]
                && t.increments == [axes[0].increment, axes[1].increment];
            let free = same_grid && path_is_free(&map, &idx);
            Some((
                q,
                CompareSummary {
                    length: path_length(&idx, t.increments),
                    free,
                },
            ))
        }
        None => None,
    };

    if let Some(out) = &args.map {
        let mut text = String::new();
        map.write_map(&rob_name, &mut text)?;
        std::fs::write(out, text).with_context(|| format!("writing {}", out.display()))?;
    }
    if let Some(out) = &args.tra {
        if report.status == SearchStatus::Found {
            let t = Trajectory::from_map_indices(
                &rob_name,
                [axes[0].min, axes[1].min],
                increments,
                &report.path,
            );
            let mut text = String::new();
            t.write(&mut text)?;
            std::fs::write(out, text).with_context(|| format!("writing {}", out.display()))?;
        } else {
            eprintln!("twil: no path, so no {} written", out.display());
        }
    }
    let result = if report.status == SearchStatus::Found {
        format!("found, length {:.2}", report.length)
    } else {
        report.status.as_str().replace('_', " ")
    };
    let scene = Scene {
        robot: &robot,
        map: &map,
        path: &path_q,
        start,
        goal,
        compare: compare.as_ref().map(|c| c.0.as_slice()),
        name: rob_name.clone(),
        result,
        compare_label: compare
            .as_ref()
            .map(|(_, c)| format!("compared path ({:.1})", c.length)),
    };
    if let Some(out) = &args.png {
        render::write_png(&scene, out)?;
    }
    if let Some(out) = &args.gif {
        render::write_gif(&scene, args.frames as usize, out)?;
    }

    let (nc, nl) = map.size();
    let summary = Summary {
        status: report.status.as_str(),
        path: path_q.clone(),
        length: report.length,
        cells: [nc, nl],
        free_cells: map.free_count(),
        nodes: report.nodes,
        expanded: report.expanded,
        line_tests: report.line_tests,
        compare: compare.map(|c| c.1),
    };
    let mut text = String::new();
    if args.json {
        text = serde_json::to_string(&summary)?;
        text.push('\n');
    } else {
        use std::fmt::Write as _;
        writeln!(
            text,
            "map {nc} x {nl} (joint 1 x joint 2), {} free of {}",
            summary.free_cells,
            nc as usize * nl as usize
        )?;
        writeln!(
            text,
            "status {}: {} points, length {:.3} (joint units); {} nodes, {} expanded, {} line tests",
            summary.status,
            summary.path.len(),
            summary.length,
            summary.nodes,
            summary.expanded,
            summary.line_tests
        )?;
        for q in &summary.path {
            writeln!(text, "  {:>9.3} {:>9.3}", q[0], q[1])?;
        }
        if let Some(c) = &summary.compare {
            writeln!(
                text,
                "reference path: length {:.3}, {} on this map",
                c.length,
                if c.free {
                    "collision-free"
                } else {
                    "NOT collision-free"
                }
            )?;
        }
    }
    // A closed pipe (`| head`) is not an error worth a panic.
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
            Err(anyhow::Error::new(e).context("writing to stdout"))
        }
        _ => Ok(crate::exit::Ending::of_plan_status(report.status.as_str())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use twil_core::cspace::rob::parse_rob;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]
        /// Any bytes given as a `.ROB`, `.MAP` or `.TRA` file give a value or one line of error
        /// that starts with the file, holds no control character and names a line of the file.
        #[test]
        fn any_bytes_give_a_value_or_a_clean_error_naming_the_file(
            bytes in proptest::collection::vec(any::<u8>(), 0..300),
            picks in proptest::collection::vec(0usize..24, 0..300),
        ) {
            // Raw bytes, and text from digits, separators, joint letters, ESC, BEL and C1 CSI.
            let alphabet = ["0", "1", "2", "9", " ", "\n", "-", ".", "%", "R", "P", "e", "\u{1b}",
                "\u{7}", "\u{9b}", "[", "A", " ", "\n", "4", "3", "\r", "\t", "x"];
            let text: String = picks.iter().map(|i| alphabet[*i]).collect();
            let robot = parse_rob("0 2 P 0 4 0 0 P 0 4 90 0").unwrap();
            let dir = tempfile::tempdir().unwrap();
            for content in [&bytes[..], text.as_bytes()] {
                let path = dir.path().join("in.ROB");
                std::fs::write(&path, content).unwrap();
                let errors = [
                    load_robot(&path).err(),
                    load_map(&path, &robot).err(),
                    load_tra(&path).err(),
                ];
                for e in errors.into_iter().flatten() {
                    let msg = e.to_string();
                    prop_assert!(msg.starts_with(&path.display().to_string()), "{}", msg);
                    prop_assert!(!msg.chars().any(char::is_control), "{:?}", msg);
                    prop_assert!(msg.len() < 400, "{}", msg);
                    let lines = content.iter().filter(|b| **b == b'\n').count() as u32 + 1;
                    if let Some(line) = e.line {
                        prop_assert!((1..=lines).contains(&line), "{} of {}: {}", line, lines, msg);
                    }
                }
            }
        }
    }
}
