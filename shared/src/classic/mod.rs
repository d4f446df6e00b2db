//! The seeds' classic planning methods (issue 15) that fit the core: no heap, fixed capacities.

pub mod bug;
pub mod grown;
pub mod visgraph;
