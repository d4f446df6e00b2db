//! The mission state machine: sweep, mark, plan, prune, follow, settle (issue 3).
//!
//! Status: not written yet.
