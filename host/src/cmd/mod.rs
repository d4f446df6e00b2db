//! One module per `twil` subcommand.

pub mod args;
pub mod check;
pub mod compare;
pub mod cspace;
pub mod mission;
pub mod param;
pub mod ping;
pub mod plan;
pub mod robot;
pub mod simulate;
pub mod sonar_grid;
pub mod view;
