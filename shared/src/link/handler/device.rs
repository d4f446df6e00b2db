//! [`Device`]: a [`Handler`] behind a [`FrameDecoder`], bytes in and reply frames out, with
//! the replay cache that answers a retried request without running it twice.
//!
//! This is the whole planning service as the firmware runs it (the mission firmware wraps the
//! handler in `RobotDevice` instead); its map lives here, its planner is passed in.

use super::Handler;
use crate::grid::Grid;
use crate::link::frame::{encode, FrameDecoder, MAX_FRAME_BYTES};
use crate::link::message::{
    DeviceFrame, DeviceInfo, DeviceStatus, ErrorCode, ErrorReply, Reply, RequestFrame,
};
use crate::plan::Planner;

/// A [`Handler`] behind a [`FrameDecoder`]: bytes in, reply frames out.
pub struct Device<const GRID_WORDS: usize> {
    decoder: FrameDecoder,
    /// The handler (public so the firmware can set its build and RAM figures).
    pub handler: Handler<GRID_WORDS>,
    grid: Grid<GRID_WORDS>,
    replay: crate::link::replay::ReplayCache,
}

impl<const GRID_WORDS: usize> Device<GRID_WORDS> {
    /// A device with an empty map (see [`Handler::new`]).
    pub const fn new(info: DeviceInfo) -> Self {
        Self {
            decoder: FrameDecoder::new(),
            handler: Handler::new(info),
            grid: Handler::<GRID_WORDS>::initial_grid(),
            replay: crate::link::replay::ReplayCache::new(),
        }
    }

    /// The map.
    pub fn grid(&self) -> &Grid<GRID_WORDS> {
        &self.grid
    }

    /// The device state counters.
    pub fn status(&self) -> DeviceStatus {
        self.handler.status(&self.grid)
    }

    /// Feed received bytes; for every complete frame, call `send` once with the encoded reply
    /// frame (terminator included). `planner` and `clock` are passed to [`Handler::handle`].
    pub fn receive<const SCRATCH_WORDS: usize, const QUEUE: usize>(
        &mut self,
        bytes: &[u8],
        planner: &mut Planner<SCRATCH_WORDS, QUEUE>,
        clock: &mut impl FnMut() -> u64,
        send: &mut impl FnMut(&[u8]),
    ) {
        let mut rest = bytes;
        while !rest.is_empty() {
            let (got, r) = self.decoder.feed::<RequestFrame>(rest);
            rest = r;
            let (seq, reply) = match got {
                None => continue,
                Some(Ok(frame)) => match self.replay.lookup(frame.seq, &frame.request) {
                    // A retry of the last request: its reply again, not a second execution.
                    Some(reply) => {
                        self.handler.count_request();
                        (Some(frame.seq), reply)
                    }
                    None => {
                        let reply =
                            self.handler
                                .handle(&frame.request, &mut self.grid, planner, clock);
                        self.replay.record(frame.seq, &frame.request, &reply);
                        (Some(frame.seq), reply)
                    }
                },
                Some(Err(fault)) => self.handler.fault_reply(fault),
            };
            self.send_frame(&DeviceFrame::Reply { seq, reply }, send);
        }
    }

    /// Encode and send a frame (a reply or telemetry).
    pub fn send_frame(&mut self, frame: &DeviceFrame, send: &mut impl FnMut(&[u8])) {
        Self::send_encoded(frame, send);
    }

    /// Encode `frame` and pass the bytes to `send` (for shells that keep no `Device`).
    pub fn send_encoded(frame: &DeviceFrame, send: &mut impl FnMut(&[u8])) {
        let mut out = [0u8; MAX_FRAME_BYTES];
        match encode(frame, &mut out) {
            Ok(bytes) => send(bytes),
            Err(_) => {
                // Cannot happen: every message fits (tested). Say so rather than stay silent.
                let error = DeviceFrame::Reply {
                    seq: None,
                    reply: Reply::Error(ErrorReply::new(
                        ErrorCode::FrameTooLong,
                        MAX_FRAME_BYTES as u32 + 1,
                        MAX_FRAME_BYTES as u32,
                    )),
                };
                if let Ok(bytes) = encode(&error, &mut out) {
                    send(bytes);
                }
            }
        }
    }
}
