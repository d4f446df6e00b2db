//! `twil simulate` (not written yet).

/// Arguments of `twil simulate`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Run `twil simulate`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("`twil simulate` is not implemented yet")
}
