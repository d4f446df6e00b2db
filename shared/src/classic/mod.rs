//! The seeds' classic planning methods (issue 15) that fit without a heap.

pub mod bug;
