//! Simulated robot: differential drive, motors, encoders, ray-cast sonar, collision (issue 3).
//!
//! Status: not written yet.
