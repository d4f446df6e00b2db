//! Two-link manipulator configuration space and its planner (seed 000, issue 5).
//!
//! Status: not written yet.
