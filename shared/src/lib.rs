//! # twil-core
//!
//! Every algorithm of the Twil navigation stack, as plain data and pure step functions.
//! `no_std`, no heap, no `unsafe`: the firmware, the host simulator and the tests all drive
//! this same code.
//!
//! ## Layers
//!
//! - [`geom`]: points in world metres and grid cells (two types, so they cannot be mixed up),
//!   the robot's pose and the length of a polyline.
//! - [`grid`]: the bit-packed occupancy grid with a capacity fixed at compile time.
//! - [`raster`]: Bresenham lines and obstacle expansion (marking with the robot's radius).
//! - [`world`]: obstacle polygons and the seed's `.da` / `.par` text formats.
//! - [`plan`]: BFS, A* and any-angle planners with static queues and 4-bit scratch cells, and the
//!   pruning of a path to what the sonar has just seen.
//! - [`robot`]: the robot's physical constants, in one validated, serializable struct.
//! - [`params`]: the same constants as a table of named parameters (robot file, docs, device).
//! - [`sonar`], [`plant`], [`control`], [`trajectory`], [`mission`]: the navigation loop and
//!   the simulated robot it can drive.
//! - [`link`]: the host <-> firmware protocol.
//! - [`cspace`]: the two-link manipulator planner of seed 000.
//! - [`params_store`]: parameter values kept in flash (id → `f32`), power-fail safe, over any
//!   `embedded-storage` NOR flash.
//! - [`failsafe`]: the robot's failsafes (watchdog gate, reset cause, link loss, overrun) as
//!   pure step functions the firmware wires.
//! - [`selftest`]: the bring-up self-test (`twil check`) as a pure step function over probes
//!   that the board's drivers and the simulated robot answer alike.
//! - [`drivers`]: the logic of the drivers for Twil's boards (sonar, neck, motors, encoders,
//!   emergency stop) over embedded-hal 1.0 traits.
//!
//! Every buffer has a named capacity; running out of it is an error value, never a panic.
#![no_std]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod classic;
pub mod control;
pub mod cspace;
pub mod drivers;
pub mod failsafe;
pub mod geom;
pub mod grid;
pub mod limits;
pub mod link;
pub mod math;
pub mod mission;
pub mod params;
pub mod params_store;
pub mod plan;
pub mod plant;
pub mod raster;
pub mod robot;
pub mod selftest;
pub mod sonar;
pub mod trajectory;
pub mod world;

// Beside its `Display` once the mission folder's rewrite (the `evidence` branch) has landed;
// here so that every core error is a `core::error::Error` today.
impl core::error::Error for mission::MissionError {}
