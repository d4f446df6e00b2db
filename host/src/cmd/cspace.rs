//! `twil cspace` (not written yet).

/// Arguments of `twil cspace`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Run `twil cspace`.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("`twil cspace` is not implemented yet")
}
