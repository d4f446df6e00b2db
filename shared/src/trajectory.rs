//! Trajectory supplier: path to timed references in the robot frame (issue 3).
//!
//! Status: not written yet.
