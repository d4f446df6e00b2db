//! The mission loop's options: `--mode`, `--preset` with the choices that override it one by
//! one ([`LoopArgs`], [`FollowArgs`]) and `--time-limit`, shared by `twil simulate` and
//! `twil mission` (`SetMission` carries them all to a device).

use anyhow::{bail, Result};
use twil_core::mission::MissionMode;

use super::preset::{FollowArgs, LoopArgs, LoopChoices};
use super::Mode;

/// `--mode`, the loop choices, `--time-limit`.
#[derive(clap::Args, Debug, Clone)]
pub struct MissionArgs {
    /// Stop-and-sweep or continuous sweeping.
    #[arg(long, value_enum, default_value_t = Mode::Stop)]
    pub mode: Mode,
    /// Loop choices: `--preset`, `--planner`, `--rcd`, `--seed-prune`, `--evidence-map`.
    #[command(flatten)]
    pub loop_args: LoopArgs,
    /// Following choices: `--settle`, `--feed-forward`, `--turn-in-place`, `--sweep-readings`.
    #[command(flatten)]
    pub follow: FollowArgs,
    /// Mission time limit, seconds of mission time (simulated time in `twil simulate`)
    /// [default: 1800, both presets].
    #[arg(long)]
    pub time_limit: Option<f32>,
}

impl MissionArgs {
    /// The loop choices of this run: `--preset`'s, with the explicit options applied.
    pub fn choices(&self) -> LoopChoices {
        self.loop_args.resolve(Some(&self.follow))
    }

    /// `--time-limit`, or the preset's.
    pub fn time_limit_s(&self) -> f32 {
        self.time_limit
            .unwrap_or(self.loop_args.preset.time_limit_s())
    }

    /// [`Self::time_limit_s`], refused unless a positive number of seconds.
    pub fn checked_time_limit_s(&self) -> Result<f32> {
        let time_limit_s = self.time_limit_s();
        if !(time_limit_s.is_finite() && time_limit_s > 0.0) {
            bail!("--time-limit: must be a positive number of seconds, got {time_limit_s}");
        }
        Ok(time_limit_s)
    }

    /// The core's mission mode of `--mode`.
    pub fn mission_mode(&self) -> MissionMode {
        match self.mode {
            Mode::Stop => MissionMode::Stop,
            Mode::Continuous => MissionMode::Continuous,
        }
    }

    /// `--mode`'s word in `summary.json`.
    pub fn mode_name(&self) -> &'static str {
        match self.mode {
            Mode::Stop => "stop",
            Mode::Continuous => "continuous",
        }
    }
}
