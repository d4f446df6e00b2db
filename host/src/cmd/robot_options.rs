//! A robot configuration refused for a value the user gave as an option, said in the user's
//! words: the option, its value and the bound in numbers (`--sonar-range 100: at most 6 m`),
//! not the internal field name (`sonar_range_m`) and a rule about another field.
//!
//! `twil simulate` and `twil mission` build a `RobotConfig` from their options and a robot
//! file ([`resolve`]) and validate it; only the fields an option sets are translated, any
//! other (a constant of the robot) keeps the core's wording, or the robot file's line.

use std::path::Path;

use anyhow::Result;
use twil_core::robot::RobotConfig;
use twil_core::sonar::SweepLayout;
use twil_core::world::Params;

use crate::cmd::args::{SonarArg, SonarArgs};
use crate::robot_file::{self, Explicit};

/// The options of `twil simulate` and `twil mission` that set robot constants.
pub struct RobotOptions<'a> {
    /// `--robot FILE.toml`.
    pub file: Option<&'a Path>,
    /// `--sonar-range`, if given.
    pub sonar_range_m: Option<f32>,
    /// `--sonar-noise`, if given.
    pub sonar_noise_std_m: Option<f32>,
    /// `--sonar-dropout`, if given.
    pub sonar_dropout_probability: Option<f32>,
    /// `--sonar-spurious`, if given.
    pub sonar_spurious_probability: Option<f32>,
    /// `--sonar`, `--beam-half-angle`, `--incidence-limit`.
    pub sonar: &'a SonarArgs,
    /// `--seed` (no constant of the robot file: the run's noise).
    pub noise_seed: u64,
    /// The preset's sweep layout, or `--sweep-readings`'.
    pub sweep_layout: SweepLayout,
    /// `--sweep-readings` was given.
    pub sweep_layout_explicit: bool,
    /// The `.par` file (its radius is the robot's unless the robot file sets one).
    pub params_path: &'a Path,
}

/// The robot of a run: the defaults with the command's own defaults and the `.par` radius,
/// then the robot file's keys, then the explicit options; validated once. `params`'s radius
/// becomes the robot's, and the `.par`'s speed and radius are checked against this robot
/// (errors name the `.par` line, the option, or the robot file's line).
pub fn resolve(options: &RobotOptions, params: &mut Params) -> Result<RobotConfig> {
    let file = options.file.map(robot_file::read).transpose()?;
    let base = options
        .sonar
        .apply(RobotConfig {
            sonar_range_m: options.sonar_range_m.unwrap_or(DEFAULT_SONAR_RANGE_M),
            sonar_noise_std_m: options.sonar_noise_std_m.unwrap_or(0.0),
            sonar_dropout_probability: options.sonar_dropout_probability.unwrap_or(0.0),
            sonar_spurious_probability: options.sonar_spurious_probability.unwrap_or(0.0),
            noise_seed: options.noise_seed,
            sweep_layout: options.sweep_layout,
            ..RobotConfig::default()
        })
        .with_planning_radius_m(params.robot_radius_m);
    let mut explicit = Vec::new();
    let mut given = |name, value: Option<f32>| {
        if let Some(value) = value {
            explicit.push(Explicit { name, value });
        }
    };
    given("sonar_range_m", options.sonar_range_m);
    given("sonar_noise_std_m", options.sonar_noise_std_m);
    given(
        "sonar_dropout_probability",
        options.sonar_dropout_probability,
    );
    given(
        "sonar_spurious_probability",
        options.sonar_spurious_probability,
    );
    given(
        "sonar_beam",
        options
            .sonar
            .sonar
            .map(|s| if s == SonarArg::Beam { 1.0 } else { 0.0 }),
    );
    given("sonar_beam_half_angle_deg", options.sonar.beam_half_angle);
    given("sonar_incidence_limit_deg", options.sonar.incidence_limit);
    given(
        "sweep_layout",
        options
            .sweep_layout_explicit
            .then_some(match options.sweep_layout {
                SweepLayout::Symmetric => 0.0,
                SweepLayout::Seed => 1.0,
            }),
    );
    let robot = robot_file::resolve(base, file.as_ref(), &explicit)?;
    // The speed and the radius against what this robot (its sonar range) can be trusted
    // with, naming the .par's line.
    crate::world_io::read_par_for(options.params_path, &robot)?;
    if let Some((f, entry)) = file
        .as_ref()
        .and_then(|f| f.get("planning_radius_m").map(|e| (f, e)))
    {
        if let Err(e) = twil_core::limits::check_planning_radius_m(&robot, entry.value) {
            anyhow::bail!(
                "{}:{}: `planning_radius_m` = {}: {e}; see docs/simulate.md",
                f.path.display(),
                entry.line,
                entry.value
            );
        }
    }
    params.robot_radius_m = robot.planning_radius_m;
    Ok(robot)
}

/// `--sonar-range` left out and no robot file: the seed's `ALCANCE_SONAR`.
const DEFAULT_SONAR_RANGE_M: f32 = RobotConfig::DEFAULT.sonar_range_m;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cmd::args::option_error as message;

    fn refused(robot: RobotConfig) -> String {
        message(&robot.validate().unwrap_err(), &robot)
    }

    #[test]
    fn an_option_error_names_the_option_its_value_and_the_bound() {
        let d = RobotConfig::default();
        let range = |r| RobotConfig {
            sonar_range_m: r,
            ..d
        };
        assert_eq!(refused(range(100.0)), "--sonar-range 100: at most 6 m");
        assert_eq!(
            refused(range(0.1)),
            "--sonar-range 0.1: above 0.26 m, the sonar's shortest range, and at most 6 m"
        );
        let noise = RobotConfig {
            sonar_noise_std_m: -1.0,
            ..d
        };
        assert_eq!(refused(noise), "--sonar-noise -1: 0 to 1 m");
        let beam = RobotConfig {
            sonar_beam_half_angle_deg: 50.0,
            ..d
        };
        assert_eq!(refused(beam), "--beam-half-angle 50: 0 to 45 degrees");
        let incidence = RobotConfig {
            sonar_incidence_limit_deg: 91.0,
            ..d
        };
        assert_eq!(refused(incidence), "--incidence-limit 91: 0 to 90 degrees");
        let dropout = RobotConfig {
            sonar_dropout_probability: 1.5,
            ..d
        };
        assert_eq!(
            refused(dropout),
            "--sonar-dropout 1.5: a probability, 0 to 1"
        );
        let spurious = RobotConfig {
            sonar_spurious_probability: -0.1,
            ..d
        };
        assert_eq!(
            refused(spurious),
            "--sonar-spurious -0.1: a probability, 0 to 1"
        );
    }

    #[test]
    fn a_field_no_option_sets_keeps_the_core_wording() {
        let robot = RobotConfig {
            wheel_radius_m: 0.0,
            ..RobotConfig::default()
        };
        assert!(refused(robot).starts_with("robot config: robot config field `wheel_radius_m`"));
    }
}
