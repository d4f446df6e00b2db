//! `cargo xtask fuzz [TARGET] [SECONDS]`: run the cargo-fuzz targets of `shared/fuzz` (nightly
//! only; the build and the CI stay on stable, where `shared/tests/fuzz_corpus.rs` replays the
//! corpus). See `docs/reliability.md`.

use std::path::Path;
use std::process::Command;

use anyhow::{bail, Context, Result};

/// Seconds per target when none is given.
const DEFAULT_SECONDS: u64 = 60;

/// `cargo +nightly …` in `shared/fuzz`, free of the stable toolchain that `cargo xtask` runs
/// under (rustup's proxies honour `RUSTUP_TOOLCHAIN` and cargo's `RUSTC` before `+nightly`).
fn nightly_cargo(fuzz_dir: &Path) -> Command {
    let mut c = Command::new("cargo");
    c.current_dir(fuzz_dir)
        .arg("+nightly")
        .env_remove("RUSTUP_TOOLCHAIN")
        .env_remove("RUSTC")
        .env_remove("RUSTDOC")
        .env_remove("CARGO");
    c
}

/// Fail with the install command when nightly or cargo-fuzz is missing.
fn check_tools(fuzz_dir: &Path) -> Result<()> {
    let nightly = nightly_cargo(fuzz_dir).arg("--version").output();
    if !matches!(nightly, Ok(ref o) if o.status.success()) {
        bail!(
            "fuzzing needs a nightly toolchain (the build itself stays on stable); install it \
             with `rustup toolchain install nightly`"
        );
    }
    let fuzz = nightly_cargo(fuzz_dir).args(["fuzz", "--version"]).output();
    if !matches!(fuzz, Ok(ref o) if o.status.success()) {
        bail!("fuzzing needs cargo-fuzz; install it with `cargo install cargo-fuzz`");
    }
    Ok(())
}

/// Run `target` (or every target, one after the other) for `seconds` each, on one core.
pub fn fuzz(root: &Path, target: Option<&str>, seconds: Option<&str>) -> Result<()> {
    let fuzz_dir = root.join("shared").join("fuzz");
    check_tools(&fuzz_dir)?;
    let seconds: u64 = match seconds {
        Some(s) => s
            .parse()
            .ok()
            .filter(|s| *s > 0)
            .with_context(|| format!("SECONDS must be a whole number above 0, not `{s}`"))?,
        None => DEFAULT_SECONDS,
    };
    let list = nightly_cargo(&fuzz_dir)
        .args(["fuzz", "list"])
        .output()
        .context("could not run `cargo +nightly fuzz list`")?;
    let all: Vec<String> = String::from_utf8_lossy(&list.stdout)
        .lines()
        .map(str::to_string)
        .collect();
    let targets: Vec<String> = match target {
        None | Some("all") => all,
        Some(t) if all.iter().any(|a| a == t) => vec![t.to_string()],
        Some(t) => bail!("no fuzz target `{t}`; the targets are: {}", all.join(", ")),
    };
    for t in &targets {
        let mut c = nightly_cargo(&fuzz_dir);
        c.args(["fuzz", "run", t, "--"])
            .arg(format!("-max_total_time={seconds}"))
            .args(["-timeout=10", "-rss_limit_mb=2048", "-print_final_stats=1"]);
        crate::run(c)?;
    }
    eprintln!(
        "xtask: fuzzed {} target(s) for {seconds} s each; new inputs are in shared/fuzz/corpus/ \
         (minimise with `cargo +nightly fuzz cmin TARGET` in shared/fuzz before committing)",
        targets.len()
    );
    Ok(())
}
