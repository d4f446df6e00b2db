//! Host-side helpers of `twil cspace`: pictures of the configuration map and the arm.

pub mod load;
pub mod render;
