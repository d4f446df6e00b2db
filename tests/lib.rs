//! Helpers shared by the scenario and end-to-end tests.

use std::path::PathBuf;

/// Path of a file in the repository's `worlds/` folder.
pub fn world(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("worlds")
        .join(name)
}
