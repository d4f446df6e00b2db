//! The seeds' classic planning methods (issue 15) that fit without a heap: each works on the
//! grid and on buffers the caller provides, one file per method.

pub mod cell_heap;
pub mod distance;
pub mod potential;
pub mod voronoi;
