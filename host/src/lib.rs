//! The `twil` host tool as a library: each subcommand's logic, so that the binary, the tests and
//! other tools share it.

pub mod answer;
pub mod classic;
pub mod cmd;
pub mod cspace;
pub mod device_sim;
pub mod exit;
pub mod files;
pub mod picture;
pub mod planning;
pub mod qemu_cmd;
pub mod record;
pub mod remote;
pub mod robot_file;
pub mod sim;
pub mod stop_cause;
pub mod world_io;
