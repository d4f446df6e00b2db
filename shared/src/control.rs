//! The 50 ms controller: odometry, reference model, linearizing feedback, wheel PIDs (issue 3).
//!
//! Status: not written yet.
