//! The options the host commands share, one `clap::Args` group per file, flattened into each
//! command's `Args`: the world ([`WorldArgs`]: `--params`, `--known`, `--size`; for `plan` and
//! `compare`, [`PlanningArgs`]: `--params`, `--size`, `--resolution`, `--robot`), the mission
//! loop ([`MissionArgs`]: `--mode`, `--preset` and its overrides, `--time-limit`), the robot
//! and its sonar ([`RobotArgs`]: `--robot`, `--seed`, `--sonar-range`, `--sonar`, …) and the
//! output ([`OutputArgs`]: `--out`, `--json`, `--gif-scale`, `--record`, `--live`, and the one
//! writer of `--out`). Here too: the `.da`/`.par` readers and the option-worded robot errors.
//!
//! Why a module of its own: `cmd/simulate.rs` used to be the shared-arguments library, so
//! `preset`, `mission` and `robot_options` imported a command, the commands repeated each
//! other's options and code, and `--size` had two grammars (issue 27, item 1). Each `cmd/`
//! file now holds its command; what two commands share is here.

use std::path::Path;

use anyhow::Result;
use twil_core::robot::{ConfigError, RobotConfig, SONAR_MAX_RANGE_LIMIT_M};
use twil_core::world::{Obstacles, Params};

use crate::world_io;

mod mission;
mod output;
pub mod preset;
mod robot;
mod world;

pub use mission::MissionArgs;
pub use output::OutputArgs;
pub use preset::{FollowArgs, LoopArgs, LoopChoices, Preset};
pub use robot::{resolve, RobotArgs, RobotOptions, SonarArg, SonarArgs};
pub use world::{parse_size, PlanningArgs, SizeM, WorldArgs};

/// Sonar use.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Stop, sweep, plan, follow the visible prefix, settle, repeat (the seed's way).
    Stop,
    /// Sweep while moving; replan on the fly.
    Continuous,
}

/// Planner choice.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlannerArg {
    /// Breadth-first search (the seed's).
    Bfs,
    /// A* with octile costs.
    Astar,
    /// A* plus line-of-sight shortcuts.
    Anyangle,
}

/// Read a `.da` file; errors name the file and the line (see [`crate::world_io`]).
pub fn read_da(path: &Path) -> Result<Obstacles> {
    Ok(world_io::read_da(path)?)
}

/// Read a `.par` file; errors name the file and the line.
pub fn read_par(path: &Path) -> Result<Params> {
    Ok(world_io::read_par(path)?)
}

/// The message for `e`, a validation error of `robot`, in the words of the option that set
/// the field (`--sonar-range 100: at most 6 m`); a field no option sets keeps the core's
/// wording.
pub fn option_error(e: &ConfigError, robot: &RobotConfig) -> String {
    let v = e.value;
    match e.field {
        "sonar_range_m" if v > SONAR_MAX_RANGE_LIMIT_M => {
            format!("--sonar-range {v}: at most {SONAR_MAX_RANGE_LIMIT_M} m")
        }
        "sonar_range_m" => format!(
            "--sonar-range {v}: above {} m, the sonar's shortest range, and at most \
             {SONAR_MAX_RANGE_LIMIT_M} m",
            robot.sonar_min_range_m
        ),
        "sonar_noise_std_m" => format!("--sonar-noise {v}: 0 to 1 m"),
        "sonar_dropout_probability" => format!("--sonar-dropout {v}: a probability, 0 to 1"),
        "sonar_spurious_probability" => format!("--sonar-spurious {v}: a probability, 0 to 1"),
        "sonar_beam_half_angle_deg" => format!("--beam-half-angle {v}: 0 to 45 degrees"),
        "sonar_incidence_limit_deg" => format!("--incidence-limit {v}: 0 to 90 degrees"),
        _ => format!("robot config: {e}"),
    }
}
