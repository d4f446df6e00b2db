//! Scenario tests (not written yet).
