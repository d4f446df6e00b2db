//! Files written by `twil simulate --out DIR`: `trajectory.csv`, one PNG per plan,
//! `mission.gif` and `summary.json`. The pictures are drawn in [`super::pictures`].

use std::fs;
use std::io::{BufWriter, Write};
use std::path::Path;

use anyhow::{Context, Result};

pub use super::pictures::{
    pick_frames, render_snapshot, write_gif, write_plan_pngs, MAX_GIF_FRAMES,
};
use super::SimResult;

/// Write `trajectory.csv`: header `t,x,y,theta`, one row per controller period, true pose.
pub fn write_trajectory_csv(path: &Path, result: &SimResult) -> Result<()> {
    let file =
        fs::File::create(path).with_context(|| format!("{}: cannot create", path.display()))?;
    let mut w = BufWriter::new(file);
    writeln!(w, "t,x,y,theta")?;
    for row in &result.trajectory {
        writeln!(
            w,
            "{:.3},{:.4},{:.4},{:.4}",
            row.t_s, row.pose.x_m, row.pose.y_m, row.pose.heading_rad
        )?;
    }
    w.flush()
        .with_context(|| format!("{}: cannot write", path.display()))?;
    Ok(())
}
