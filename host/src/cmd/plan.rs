//! `twil plan` (not written yet).

/// Arguments of `twil plan`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Run `twil plan`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("`twil plan` is not implemented yet")
}
