//! Helpers shared by the scenario and end-to-end tests (compiled into each test target).
#![allow(dead_code)]

use std::path::PathBuf;

/// Path of a file in the repository's `worlds/` folder.
pub fn world(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("worlds")
        .join(name)
}

/// The `twil` binary built for this test run.
pub fn twil() -> std::process::Command {
    std::process::Command::new(env!("CARGO_BIN_EXE_twil"))
}
