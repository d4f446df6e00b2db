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

/// Write `trajectory.csv`, one row per controller period (per pose report for
/// `twil mission`): time, true pose, then the controller's signals of the period that ended
/// at `t` (the reference point handed to the controller, wheel speed references, motor
/// voltages) and the mission's phase after it. A signal the source does not carry
/// (`twil mission` telemetry has no references) is an empty field.
pub fn write_trajectory_csv(path: &Path, result: &SimResult) -> Result<()> {
    use twil_core::mission::MissionPhase;
    /// A phase as one CSV word.
    fn phase_word(phase: MissionPhase) -> &'static str {
        match phase {
            MissionPhase::Sweep { full: true } => "full_sweep",
            MissionPhase::Sweep { full: false } => "sweep",
            MissionPhase::Follow => "follow",
            MissionPhase::Settle => "settle",
            MissionPhase::Plan => "plan",
            MissionPhase::Done => "done",
        }
    }
    let file =
        fs::File::create(path).with_context(|| format!("{}: cannot create", path.display()))?;
    let mut w = BufWriter::new(file);
    writeln!(
        w,
        "t,x,y,theta,ref_x,ref_y,left_speed_ref_rad_s,right_speed_ref_rad_s,left_v,right_v,phase"
    )?;
    let opt = |v: Option<f32>| v.map_or(String::new(), |v| format!("{v:.4}"));
    for row in &result.trajectory {
        let c = &row.control;
        writeln!(
            w,
            "{:.3},{:.4},{:.4},{:.4},{},{},{},{},{:.3},{:.3},{}",
            row.t_s,
            row.pose.x_m,
            row.pose.y_m,
            row.pose.heading_rad,
            opt(c.reference.map(|p| p.x_m)),
            opt(c.reference.map(|p| p.y_m)),
            opt(c.speed_ref_rad_s.map(|s| s.0)),
            opt(c.speed_ref_rad_s.map(|s| s.1)),
            c.left_voltage_v,
            c.right_voltage_v,
            row.phase.map_or("", phase_word),
        )?;
    }
    w.flush()
        .with_context(|| format!("{}: cannot write", path.display()))?;
    Ok(())
}
