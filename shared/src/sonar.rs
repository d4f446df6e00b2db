//! Sonar: sweep plan, time of flight, regions-of-constant-depth filter, hits to grid marks (issue 3).
//!
//! Status: not written yet.
