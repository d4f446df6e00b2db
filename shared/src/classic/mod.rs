//! The seeds' classic planning methods (issue 15) that fit the core: no heap, fixed capacities
//! or buffers the caller provides, one file per method.

pub mod bug;
pub mod cell_heap;
pub mod distance;
pub mod grown;
pub mod potential;
pub mod quadtree;
pub mod visgraph;
pub mod voronoi;
