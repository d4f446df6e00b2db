//! Helpers shared by the scenario and end-to-end tests (modules of the one test binary,
//! `tests/suite.rs`).
#![allow(dead_code)]

use std::path::PathBuf;

/// The ranger of before issue 23's defaults at `incidence_limit_deg` (theirs was 70°): no
/// noise, missed or spurious echoes (docs/simulate.md, "The earlier defaults").
pub fn earlier_ranger(incidence_limit_deg: &str) -> Vec<&str> {
    vec![
        "--incidence-limit",
        incidence_limit_deg,
        "--sonar-noise",
        "0",
        "--sonar-dropout",
        "0",
        "--sonar-spurious",
        "0",
    ]
}

/// `argv` followed by `extra`, as one list of words.
pub fn with<'a>(argv: &[&'a str], extra: &[&'a str]) -> Vec<&'a str> {
    argv.iter().chain(extra).copied().collect()
}

/// The repository's root folder.
pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Path of a file in the repository's `worlds/` folder.
pub fn world(name: &str) -> PathBuf {
    repo().join("worlds").join(name)
}

/// The `twil` binary built for this test run.
pub fn twil() -> std::process::Command {
    std::process::Command::new(env!("CARGO_BIN_EXE_twil"))
}

/// Send Ctrl-C (SIGINT) to a child process, as a terminal does.
#[cfg(unix)]
pub fn ctrl_c(child: &std::process::Child) {
    let kill = std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .expect("run kill");
    assert!(kill.success(), "kill -INT {}", child.id());
}

/// `twil plan`'s options for `world` (`None`: no obstacles) and `params` as the command line
/// gives them by default (15 × 15 m, 0.05 m cells, A*), with `--json`.
pub fn plan_args(world: Option<PathBuf>, params: PathBuf) -> twil_host::cmd::plan::Args {
    twil_host::cmd::plan::Args {
        world,
        planning: twil_host::cmd::args::PlanningArgs {
            params,
            size: twil_host::cmd::plan::SizeM {
                width_m: 15.0,
                height_m: 15.0,
            },
            resolution: 0.05,
            robot: None,
        },
        map: None,
        planner: twil_host::classic::Method::Astar,
        json: true,
        png: None,
        record: None,
        scale: None,
        remote: None,
    }
}

/// Run `twil simulate` in process with the command line `argv` (without the program name) and
/// hand back the whole result.
pub fn simulate(argv: &[&str]) -> twil_host::sim::SimResult {
    #[derive(clap::Parser)]
    struct Cli {
        #[command(flatten)]
        args: twil_host::cmd::simulate::Args,
    }
    let cli =
        <Cli as clap::Parser>::parse_from(std::iter::once("twil").chain(argv.iter().copied()));
    let setup = twil_host::cmd::simulate::setup_from_args(&cli.args).expect("setup");
    twil_host::sim::run(&setup, &mut twil_host::sim::NoProgress).expect("simulation")
}
