//! The output of a mission: `--out DIR`, `--json`, `--gif-scale` and the Foxglove
//! `--record`/`--live`, shared by `twil simulate` and `twil mission`, and the one writer of
//! `--out` ([`OutputArgs::write`]), so that both commands write the same files the same way.

use std::path::PathBuf;

use anyhow::{Context, Result};

use crate::record::RecordArgs;
use crate::sim::{output, SimResult, SimSetup};

/// `--out`, `--json`, `--gif-scale`, `--record`, `--live`.
#[derive(clap::Args, Debug, Clone)]
pub struct OutputArgs {
    /// Write trajectory.csv, plan PNGs, mission.gif and summary.json here.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Print exactly one JSON object on stdout and nothing else.
    #[arg(long)]
    pub json: bool,
    /// GIF scale, pixels per cell.
    #[arg(long, default_value_t = 2)]
    pub gif_scale: u32,
    /// `--record FILE.mcap`, `--live [ADDR]`: Foxglove recording and live view.
    #[command(flatten)]
    pub record: RecordArgs,
}

impl OutputArgs {
    /// With `--out DIR`: create `DIR` and write `trajectory.csv`, `plan-NNN.png`,
    /// `mission.gif` (at `--gif-scale`, 1 to 8) and `summary.json` (`summary`, pretty, one
    /// line feed at the end) of the run `result` of `setup`; without it, nothing.
    pub fn write(
        &self,
        setup: &SimSetup,
        result: &SimResult,
        summary: &serde_json::Value,
    ) -> Result<()> {
        let Some(dir) = &self.out else {
            return Ok(());
        };
        std::fs::create_dir_all(dir)
            .with_context(|| format!("{}: cannot create directory", dir.display()))?;
        output::write_trajectory_csv(&dir.join("trajectory.csv"), result)?;
        output::write_plan_pngs(dir, setup, result)?;
        output::write_gif(
            &dir.join("mission.gif"),
            setup,
            result,
            self.gif_scale.clamp(1, 8),
        )?;
        let path = dir.join("summary.json");
        std::fs::write(&path, serde_json::to_string_pretty(summary)? + "\n")
            .with_context(|| format!("{}: cannot write", path.display()))?;
        Ok(())
    }
}
