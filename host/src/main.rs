//! `twil`: plan, simulate and talk to the Twil robot.

use clap::{Parser, Subcommand};

/// Host tools for the Twil robot: plan on a map, simulate a mission, talk to the firmware.
#[derive(Parser, Debug)]
#[command(name = "twil", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Plan a path on a known world (.da) for a mission (.par).
    Plan,
}

fn main() {
    let cli = Cli::parse();
    match cli.command {
        Command::Plan => {
            eprintln!("twil plan: not implemented yet");
            std::process::exit(2);
        }
    }
}
