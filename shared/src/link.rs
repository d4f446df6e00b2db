//! Host <-> firmware protocol: the messages, their framing, and the request handler that both the
//! firmware and the host tests run.
//!
//! ## Layers
//!
//! - [`message`]: what is said. The host sends a [`RequestFrame`] (a sequence number and a
//!   [`Request`]); the device answers every request with exactly one [`DeviceFrame::Reply`]
//!   carrying the same sequence number, and may send [`DeviceFrame::Telemetry`] unasked.
//! - [`frame`]: how it travels. A message is serialized with postcard, followed by a CRC-32
//!   computed by postcard's CRC flavor, wrapped as a postcard byte string and COBS-encoded by
//!   postcard (`0x00` ends every frame). The receiver splits frames with postcard's
//!   [`CobsAccumulator`](postcard::accumulator::CobsAccumulator). Nothing here is hand-written:
//!   COBS, CRC and the varints are postcard's and the `crc` crate's.
//! - [`handler`]: what the device does. [`Handler`] owns the grid, the obstacles being uploaded
//!   and the last path; [`Handler::handle`] turns one request into one reply, using the planner
//!   it is given.
//!   [`Device`] adds the framing: bytes in, frames out. The firmware is a thin shell around a
//!   `Device` in static memory; the host tests drive the same `Device` in a loopback.
//!
//! ## Guarantees
//!
//! - Every frame is at most [`MAX_FRAME_BYTES`] bytes on the wire, terminator included.
//! - Decoding never panics: garbage, truncated, oversized or corrupted frames become a
//!   [`FrameFault`], which the device answers with a [`Reply::Error`] (its sequence number is
//!   `None` unless the CRC was good and the sequence number could be read).
//! - A request that fails changes nothing: the map, the obstacles and the last path stay as they
//!   were.
//! - A request sent again under the same sequence number (its reply was lost) is answered
//!   again and never executed twice ([`replay`]).
//!
//! ```
//! use twil_core::link::{frame, Device, DeviceFrame, Reply, Request, RequestFrame};
//! use twil_core::link::frame::{FrameDecoder, MAX_FRAME_BYTES};
//!
//! // A small device (grid of 64 x 64 cells) on the host, driven through the wire format.
//! use twil_core::plan::Planner;
//! let mut device: Device<128> = Device::new(Default::default());
//! let mut planner = Planner::<512, 256>::new();
//! let mut wire = [0u8; MAX_FRAME_BYTES];
//! let request = RequestFrame { seq: 7, request: Request::Ping { nonce: 42 } };
//! let bytes = frame::encode(&request, &mut wire).unwrap();
//!
//! let mut answer = Vec::new();
//! device.receive(bytes, &mut planner, &mut || 0, &mut |out: &[u8]| answer.extend_from_slice(out));
//!
//! let mut decoder = FrameDecoder::new();
//! let (got, _rest) = decoder.feed::<DeviceFrame>(&answer);
//! assert_eq!(
//!     got,
//!     Some(Ok(DeviceFrame::Reply { seq: Some(7), reply: Reply::Pong { nonce: 42 } }))
//! );
//! ```

pub mod frame;
pub mod handler;
pub mod message;
pub mod params;
pub mod replay;
pub mod robot;

#[cfg(test)]
mod wire_doc;

pub use frame::{FrameDecoder, FrameFault, MAX_FRAME_BYTES};

/// Capacities of the firmware's device (the STM32F405 build). They live here so that the host
/// can run the very same planner type and check the device's results exactly (the order in
/// which A* pops equal keys, hence its expanded count, depends on the open-list capacity).
pub mod mcu {
    use crate::grid::words_for_cells;
    use crate::plan::{Planner, FRAMED_SCRATCH_WORDS};

    /// Grid capacity, cells: the seed's 300 x 300 map. One map serves the planning service and
    /// the mission (the mission's, lent to the service while no mission runs), so that the
    /// mission fits the chip: see `docs/firmware.md`, "Memory map".
    pub const GRID_CELLS: usize = 300 * 300;
    /// Grid capacity, 32-bit words.
    pub const GRID_WORDS: usize = words_for_cells(GRID_CELLS);
    /// Planner scratch, 32-bit words: the least the cell-by-cell A*'s framed layout needs
    /// (2^14 + 1 words, 4 bits per cell for up to 131 080 cells); without it A* on cluttered
    /// 300 x 300 maps would go over the 5 M-instruction budget.
    pub const PLANNER_SCRATCH_WORDS: usize = FRAMED_SCRATCH_WORDS;
    /// Planner open-list capacity, entries (12 bytes each). A* needs at most 782 on the 300 x
    /// 300 benchmark grids (20 % random obstacles; 43 on the bundled worlds) and reclaims stale
    /// entries when the list fills; BFS needs none (its scalar restart in corridors, a few
    /// dozen).
    pub const PLANNER_QUEUE: usize = 1024;
    /// The firmware's planner.
    pub type McuPlanner = Planner<PLANNER_SCRATCH_WORDS, PLANNER_QUEUE>;
    /// The planning service alone, with a map of its own (host tests of the protocol).
    pub type McuDevice = super::Device<GRID_WORDS>;
    /// The firmware's device: the planning service and the mission requests.
    pub type McuRobotDevice = super::RobotDevice<GRID_WORDS>;
    /// The firmware's mission (its map is the device's map), with the evidence map's two
    /// planes (`docs/mapping.md`; the memory it took is in `docs/firmware.md`).
    pub type McuMission = crate::mission::Mission<GRID_WORDS>;
}
pub use handler::{Device, Handler};
pub use message::*;
pub use robot::{NoWorld, RobotDevice, RobotLink, WorldAccess, WorldUpload};
