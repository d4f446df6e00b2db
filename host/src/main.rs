//! `twil`: plan, simulate and talk to the Twil robot.
//!
//! Each subcommand lives in its own module under `cmd/` of the `twil_host` library with an `Args` struct (clap) and a
//! `run` function; this file only dispatches. Each `run` says how the command ended
//! ([`twil_host::exit::Ending`]: 0 done, 3 no path, 4 collision, 5 timeout, 6 aborted,
//! 130 Ctrl-C); errors reach the user as one line on stderr and exit code 1 (2 for usage
//! errors, from clap).

use twil_host::cmd;

use clap::{Parser, Subcommand};

/// Host tools for the Twil robot: plan on a map, simulate a mission, talk to the firmware.
#[derive(Parser, Debug)]
#[command(name = "twil", version, about, after_help = twil_host::exit::HELP)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Plan a path on a known world (.da) for a mission (.par).
    Plan(cmd::plan::Args),
    /// Simulate a whole mission: sonar sweeps, planning, the 50 ms controller, a robot model.
    Simulate(cmd::simulate::Args),
    /// Missions over a grid of sonar models on generated worlds: how each ends against the truth.
    SonarGrid(cmd::sonar_grid::Args),
    /// Run a mission on the device (firmware, QEMU or `--remote sim`) and follow its telemetry.
    Mission(cmd::mission::Args),
    /// Run every planning method (grid and classic) on one world and compare them.
    Compare(cmd::compare::Args),
    /// Plan for the two-link manipulator of seed 000 in its configuration space.
    Cspace(cmd::cspace::Args),
    /// Draw what a recording (--record FILE.mcap) held at a mission time, without Foxglove.
    View(cmd::view::Args),
    /// Check the link to the firmware (QEMU, TCP or a serial port).
    Ping(cmd::ping::Args),
    /// Write a robot file (`init FILE.toml`) or show the robot constants in use (`show`).
    Robot(cmd::robot::Args),
    /// Read and set the device's parameters (`list`, `get NAME`, `set NAME VALUE`), kept in its flash.
    Param(cmd::param::Args),
    /// Bring-up self-test of the device: link, clock, e-stop, battery, neck, sonar, motors.
    Check(cmd::check::Args),
}

/// Exit status of a run whose reader closed its standard output (`twil … | head`): 128 + 13,
/// what a Unix tool killed by SIGPIPE reports.
const CLOSED_STDOUT_EXIT: i32 = 141;

/// `twil simulate … | head -1` closes the pipe after a line: the rest of the output has no
/// reader, and `println!` panics on the write ("failed printing to stdout: Broken pipe").
/// End quietly instead, as `head`'s other writers do; every other panic keeps the default
/// report.
fn quiet_when_stdout_is_closed() {
    let report = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let payload = info.payload();
        let message = payload
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| payload.downcast_ref::<&str>().copied())
            .unwrap_or("");
        if message.starts_with("failed printing to stdout") && message.contains("Broken pipe") {
            std::process::exit(CLOSED_STDOUT_EXIT);
        }
        report(info);
    }));
}

fn main() {
    quiet_when_stdout_is_closed();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Plan(args) => cmd::plan::run(args),
        Command::Simulate(args) => cmd::simulate::run(args),
        Command::SonarGrid(args) => cmd::sonar_grid::run(args),
        Command::Mission(args) => cmd::mission::run(args),
        Command::Compare(args) => cmd::compare::run(args),
        Command::Cspace(args) => cmd::cspace::run(args),
        Command::Ping(args) => cmd::ping::run(args),
        Command::View(args) => cmd::view::run(args),
        Command::Robot(args) => cmd::robot::run(args),
        Command::Param(args) => cmd::param::run(args),
        Command::Check(args) => cmd::check::run(args),
    };
    match result {
        Ok(ending) => std::process::exit(ending.code()),
        Err(error) => {
            eprintln!("twil: {error:#}");
            std::process::exit(1);
        }
    }
}
