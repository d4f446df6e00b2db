//! The robot and its sonar: `--robot FILE.toml`, `--seed`, `--sonar-range`, `--sonar-noise`
//! and the sonar model (`--sonar`, `--beam-half-angle`, `--incidence-limit`), shared by
//! `twil simulate` and `twil mission`, and the one way both build the run's `RobotConfig`
//! from them ([`RobotArgs::resolve`]).
//!
//! A robot configuration refused for a value the user gave as an option is said in the
//! user's words: the option, its value and the bound in numbers (`--sonar-range 100: at most
//! 6 m`, [`super::option_error`]), not the internal field name (`sonar_range_m`) and a rule
//! about another field; any other field (a constant of the robot) keeps the core's wording,
//! or the robot file's line.

use std::path::{Path, PathBuf};

use anyhow::Result;
use twil_core::robot::RobotConfig;
use twil_core::sonar::SweepLayout;
use twil_core::world::Params;

use super::preset::LoopChoices;
use crate::robot_file::{self, Explicit};

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
    /// its normal, degrees (0 to 90) [default: 15, the beam's half-angle (specular walls), or
    /// the --robot file's `sonar_incidence_limit_deg`].
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
                .unwrap_or(RobotConfig::SIMULATED.sonar_beam_half_angle_deg),
            sonar_incidence_limit_deg: self
                .incidence_limit
                .unwrap_or(RobotConfig::SIMULATED.sonar_incidence_limit_deg),
            ..robot
        }
    }
}

/// `--robot`, `--seed`, `--sonar-range`, `--sonar-noise` and the sonar model.
#[derive(clap::Args, Debug, Clone)]
pub struct RobotArgs {
    /// Robot file (`twil robot init`): the robot's constants; keys left out keep their
    /// defaults, an explicit option overrides the file, and its `planning_radius_m`, if set,
    /// replaces the `.par` radius. `twil mission`: until the device takes parameters, only
    /// the constants the mission set-up carries may differ from the device's defaults
    /// (`planning_radius_m`, the sonar's range, noise and beam, `sweep_layout`); any other is
    /// refused, naming its line.
    #[arg(long = "robot", value_name = "FILE.toml")]
    pub robot_file: Option<PathBuf>,
    /// Seed of the simulated sonar noise and faults (simulated devices).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Sonar range, metres (0.26 < range ≤ 6) [default: the seed's 1.5, or the --robot
    /// file's `sonar_range_m`].
    #[arg(long)]
    pub sonar_range: Option<f32>,
    /// Standard deviation of the simulated sonar noise, metres (simulated devices) [default:
    /// 0.005, a measured HC-SR04's (the ray: 0), or the --robot file's `sonar_noise_std_m`].
    #[arg(long)]
    pub sonar_noise: Option<f32>,
    /// Probability that a reading which would echo returns no echo (missed echo), 0 to 1
    /// (simulated devices) [default: 0.02 (the ray: 0), or the --robot file's
    /// `sonar_dropout_probability`].
    #[arg(long, value_name = "P")]
    pub sonar_dropout: Option<f32>,
    /// Probability of a spurious echo nearer than the true one (crosstalk, multipath), 0 to 1
    /// (simulated devices) [default: 0.01 (the ray: 0), or the --robot file's
    /// `sonar_spurious_probability`].
    #[arg(long, value_name = "P")]
    pub sonar_spurious: Option<f32>,
    /// The simulated sonar (simulated devices).
    #[command(flatten)]
    pub sonar_model: SonarArgs,
}

impl RobotArgs {
    /// The robot of a run ([`resolve`]) with these options and the loop's `choices` (the sweep
    /// layout, unless `sweep_layout_explicit` it is the preset's); `params` (read from
    /// `params_path`) takes the robot's planning radius.
    pub fn resolve(
        &self,
        choices: &LoopChoices,
        sweep_layout_explicit: bool,
        params_path: &Path,
        params: &mut Params,
    ) -> Result<RobotConfig> {
        resolve(
            &RobotOptions {
                file: self.robot_file.as_deref(),
                sonar_range_m: self.sonar_range,
                sonar_noise_std_m: self.sonar_noise,
                sonar_dropout_probability: self.sonar_dropout,
                sonar_spurious_probability: self.sonar_spurious,
                sonar: &self.sonar_model,
                noise_seed: self.seed,
                sweep_layout: choices.sweep_layout,
                sweep_layout_explicit,
                params_path,
            },
            params,
        )
    }
}

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
    // The single ray is the exact sensor (the ranger's noise and faults are the beam's): its
    // defaults read exact ranges; the options and the robot file may still add them.
    let ray = match options.sonar.sonar {
        Some(s) => s == SonarArg::Ray,
        None => file
            .as_ref()
            .and_then(|f| f.get("sonar_beam"))
            .is_some_and(|e| e.value == 0.0),
    };
    let default = if ray {
        RobotConfig {
            sonar_noise_std_m: 0.0,
            sonar_dropout_probability: 0.0,
            sonar_spurious_probability: 0.0,
            ..DEFAULT
        }
    } else {
        DEFAULT
    };
    let base = options
        .sonar
        .apply(RobotConfig {
            sonar_range_m: options.sonar_range_m.unwrap_or(default.sonar_range_m),
            sonar_noise_std_m: options
                .sonar_noise_std_m
                .unwrap_or(default.sonar_noise_std_m),
            sonar_dropout_probability: options
                .sonar_dropout_probability
                .unwrap_or(default.sonar_dropout_probability),
            sonar_spurious_probability: options
                .sonar_spurious_probability
                .unwrap_or(default.sonar_spurious_probability),
            noise_seed: options.noise_seed,
            sweep_layout: options.sweep_layout,
            ..default
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

/// The robot of an option left out and a key the robot file leaves out: the core's, with the
/// sensor-faithful simulated ranger ([`RobotConfig::SIMULATED`]; the range is the seed's
/// `ALCANCE_SONAR`).
const DEFAULT: RobotConfig = RobotConfig::SIMULATED;

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
