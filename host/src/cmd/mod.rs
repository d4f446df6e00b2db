//! One module per `twil` subcommand (a file, or a folder for `mission`), and [`args`], the
//! options the commands share.

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
