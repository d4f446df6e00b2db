//! `twil ping` (not written yet).

/// Arguments of `twil ping`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Run `twil ping`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("`twil ping` is not implemented yet")
}
