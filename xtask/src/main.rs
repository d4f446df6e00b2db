//! `cargo xtask …`: firmware builds, QEMU runs and the CI entry point.

use std::process::Command;

use anyhow::{bail, Context, Result};

const USAGE: &str = "usage: cargo xtask <test|firmware>
  test       run every test (host, scenarios, firmware build); what .ci/run calls
  firmware   build the firmware ELF for thumbv7em-none-eabihf";

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("test") => test(),
        Some("firmware") => firmware(),
        _ => {
            eprintln!("{USAGE}");
            std::process::exit(2);
        }
    }
}

fn cargo() -> Command {
    let mut c = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()));
    c.current_dir(workspace_root());
    c
}

fn workspace_root() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask lives in the workspace")
        .to_path_buf()
}

fn run(mut c: Command) -> Result<()> {
    eprintln!("xtask: running {c:?}");
    let status = c
        .status()
        .with_context(|| format!("could not start {c:?}"))?;
    if !status.success() {
        bail!("{c:?} failed with {status}");
    }
    Ok(())
}

/// Make sure the thumb target of `rust-toolchain.toml` is installed (rustup does not add the
/// file's targets to a toolchain that is already there).
fn ensure_thumb_target() -> Result<()> {
    let out = Command::new("rustc")
        .current_dir(workspace_root())
        .args([
            "--print",
            "target-libdir",
            "--target",
            "thumbv7em-none-eabihf",
        ])
        .output()
        .context("could not run rustc")?;
    let libdir = String::from_utf8_lossy(&out.stdout).trim().to_string();
    if out.status.success() && std::path::Path::new(&libdir).exists() {
        return Ok(());
    }
    let mut c = Command::new("rustup");
    c.current_dir(workspace_root())
        .args(["toolchain", "install"]);
    run(c)
}

fn firmware() -> Result<()> {
    ensure_thumb_target()?;
    let mut c = cargo();
    c.args([
        "build",
        "--package",
        "twil-firmware",
        "--target",
        "thumbv7em-none-eabihf",
        "--profile",
        "firmware",
    ]);
    run(c)
}

fn test() -> Result<()> {
    firmware()?;
    let mut c = cargo();
    c.args([
        "test",
        "--release",
        "--workspace",
        "--exclude",
        "twil-firmware",
    ]);
    run(c)
}
