//! The scenario and end-to-end tests of the `twil` host package, one module per subject, built
//! as one test binary: one link instead of seventeen, and the slow subjects (QEMU missions,
//! bad links, safe parameters) run beside the quick ones instead of one after the other.
//!
//! Run one subject with its module name as the filter, e.g.
//! `cargo test --release -p twil-host --test suite plan_scenarios::`.

mod common;

mod answers;
mod bounded_marking;
mod classic_bug;
mod classic_fields;
mod classic_geometric;
mod cspace_seed000;
mod device_params;
mod doc_examples;
mod doc_links;
mod evidence_map;
mod file_errors;
mod firmware_qemu;
mod firmware_requests;
mod formats_doc;
mod link_faults;
mod mission_remote;
mod plan_scenarios;
mod preset;
mod protocol_client;
mod recording;
mod robot_file;
mod safe_params;
mod serial_pty;
mod sim_scenarios;
mod sonar_beam;
mod sonar_grid;
mod virtual_board;
