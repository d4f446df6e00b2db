//! stub
use super::Run;
use crate::cmd::plan::World;
/// stub
pub fn run(_world: &World) -> anyhow::Result<Run> {
    anyhow::bail!("not implemented yet")
}
