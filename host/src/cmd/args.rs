//! The options and readers the host commands share: the simulated sonar's options, the
//! mission mode, the planner choice, the `.da`/`.par` readers and the `--size` grammar.
//!
//! Why a module of its own: these were in `cmd/simulate.rs`, so `preset`, `mission` and
//! `robot_options` imported a command to get them and the command layer had import cycles
//! (issue 27). Each `cmd/` file now holds its command; what two commands share is here.

use std::path::Path;

use anyhow::{bail, Context, Result};
use twil_core::robot::{ConfigError, RobotConfig, SONAR_MAX_RANGE_LIMIT_M};
use twil_core::world::{Obstacles, Params};

use crate::world_io;

/// The simulated sonar model.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum SonarArg {
    /// One exact ray along the neck's direction (the earlier model).
    Ray,
    /// An ultrasonic beam: cone, first echo, incidence limit, corners (the default).
    Beam,
}

/// The simulated sonar's options, shared by `twil simulate` and `twil mission` (whose
/// simulated devices use them).
#[derive(clap::Args, Debug, Clone, Copy)]
pub struct SonarArgs {
    /// Simulated sonar: `ray` one exact ray; `beam` an ultrasonic beam (cone, first echo,
    /// smooth walls echo only near face-on, corners at any angle; docs/robot-model.md).
    /// [default: beam, or the --robot file's `sonar_beam`]
    #[arg(long, value_enum)]
    pub sonar: Option<SonarArg>,
    /// Half-angle of the beam's cone, degrees (0 to 45; the HC-SR04 data sheet's 15°)
    /// [default: 15, or the --robot file's `sonar_beam_half_angle_deg`].
    #[arg(long, value_name = "DEG")]
    pub beam_half_angle: Option<f32>,
    /// Beam: a smooth wall echoes only when the ray is within this angle of
    /// its normal, degrees (0 to 90) [default: 70, or the --robot file's
    /// `sonar_incidence_limit_deg`].
    #[arg(long, value_name = "DEG")]
    pub incidence_limit: Option<f32>,
}

impl SonarArgs {
    /// `robot` with this sonar model (an option left out: the command's default).
    pub fn apply(&self, robot: RobotConfig) -> RobotConfig {
        RobotConfig {
            sonar_beam: self.sonar.unwrap_or(SonarArg::Beam) == SonarArg::Beam,
            sonar_beam_half_angle_deg: self
                .beam_half_angle
                .unwrap_or(RobotConfig::DEFAULT.sonar_beam_half_angle_deg),
            sonar_incidence_limit_deg: self
                .incidence_limit
                .unwrap_or(RobotConfig::DEFAULT.sonar_incidence_limit_deg),
            ..robot
        }
    }
}

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

/// Parse `WxH` in metres.
pub fn parse_size(text: &str) -> Result<(f32, f32)> {
    let (w, h) = text
        .split_once(['x', 'X'])
        .with_context(|| format!("--size: expected WIDTHxHEIGHT in metres, got `{text}`"))?;
    let w: f32 = w
        .trim()
        .parse()
        .with_context(|| format!("--size: bad width `{w}`"))?;
    let h: f32 = h
        .trim()
        .parse()
        .with_context(|| format!("--size: bad height `{h}`"))?;
    if !(w.is_finite() && h.is_finite() && w > 0.0 && h > 0.0) {
        bail!("--size: width and height must be positive, got `{text}`");
    }
    Ok((w, h))
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
