//! Placeholder: the planner benchmark (issue 2) goes here.
fn main() {}
