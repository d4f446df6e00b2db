//! Scenario tests for planning on the bundled worlds.

mod common;

use twil_core::world::{parse_da, parse_par, Obstacles};

#[test]
fn every_bundled_world_parses() {
    for name in ["corridor", "office", "pillars"] {
        let da = std::fs::read_to_string(common::world(&format!("{name}.da"))).unwrap();
        let par = std::fs::read_to_string(common::world(&format!("{name}.par"))).unwrap();
        let mut obstacles = Obstacles::new();
        parse_da(&da, &mut obstacles).unwrap();
        assert!(!obstacles.is_empty(), "{name}");
        parse_par(&par).unwrap();
    }
}
