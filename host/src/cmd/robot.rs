//! `twil robot`: write a robot file (`init`) and show the constants a run would use (`show`).
//!
//! Why: a user who builds their own robot starts from a file listing every constant with its
//! meaning and source, edits the values they measured, and checks what the tools will use
//! before a mission. The file's format and checks are in [`crate::robot_file`]; the constants
//! come from the core's parameter table ([`twil_core::params::PARAMS`]).
//!
//! Measured: `tests/robot_file.rs` runs `init`, edits the file, and checks `show --json`.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use twil_core::params::PARAMS;
use twil_core::robot::RobotConfig;

use crate::robot_file;

/// Arguments of `twil robot`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    #[command(subcommand)]
    pub action: Action,
}

/// What `twil robot` does.
#[derive(clap::Subcommand, Debug, Clone)]
pub enum Action {
    /// Write FILE.toml: every constant of the robot model at its default, one key each, with
    /// its meaning, unit, accepted values and the default's source.
    Init {
        /// The robot file to write.
        #[arg(value_name = "FILE.toml")]
        file: PathBuf,
        /// Replace the file if it exists.
        #[arg(long)]
        force: bool,
    },
    /// Print every constant's value: the defaults, or a robot file's with its other keys at
    /// their defaults.
    Show {
        /// The robot file (keys left out keep their defaults).
        #[arg(long, value_name = "FILE.toml")]
        robot: Option<PathBuf>,
        /// Print one JSON object, `{"robot": {KEY: VALUE, ...}}`.
        #[arg(long)]
        json: bool,
    },
}

/// Run `twil robot`.
pub fn run(args: Args) -> Result<crate::exit::Ending> {
    match args.action {
        Action::Init { file, force } => {
            if file.exists() && !force {
                bail!(
                    "{}: the file exists; pass --force to replace it",
                    file.display()
                );
            }
            std::fs::write(&file, robot_file::init_text())
                .with_context(|| format!("{}: cannot write", file.display()))?;
            println!(
                "wrote {}: {} constants of the robot model at their defaults",
                file.display(),
                PARAMS.len()
            );
        }
        Action::Show { robot, json } => {
            let file = robot.as_deref().map(robot_file::read).transpose()?;
            let config = robot_file::resolve(RobotConfig::SIMULATED, file.as_ref(), &[])?;
            if json {
                let v = serde_json::json!({ "robot": robot_file::robot_json(&config) });
                println!("{}", serde_json::to_string(&v)?);
            } else {
                print!("{}", show_text(&config, file.as_ref()));
            }
        }
    }
    Ok(crate::exit::Ending::Done)
}

/// One line per constant: key, value, unit, and where a value other than the default came from.
pub fn show_text(config: &RobotConfig, file: Option<&robot_file::RobotFile>) -> String {
    let width = PARAMS.iter().map(|p| p.name.len()).max().unwrap_or(0);
    let mut s = String::new();
    for p in PARAMS.iter() {
        let value = robot_file::toml_text(p, p.get(config));
        let from = match file.and_then(|f| f.get(p.name).map(|e| (f, e))) {
            Some((f, e)) => format!("  ({}:{})", f.path.display(), e.line),
            None => String::new(),
        };
        let line = format!("{:width$} = {value} {}{from}", p.name, p.unit);
        s.push_str(line.trim_end());
        s.push('\n');
    }
    s
}
