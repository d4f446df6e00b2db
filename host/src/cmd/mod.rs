//! One module per `twil` subcommand.

pub mod cspace;
pub mod ping;
pub mod plan;
pub mod simulate;
