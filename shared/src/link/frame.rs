//! Framing: postcard + CRC-32 + COBS, all done by postcard and the `crc` crate.
//!
//! ## Wire format
//!
//! ```text
//! frame   = COBS( bytes ) 0x00                      (postcard::to_slice_cobs)
//! bytes   = varint(len) body                        (a postcard byte string, len = |body|)
//! body    = postcard(message) crc32_le(postcard(message))   (postcard::to_slice_crc32)
//! ```
//!
//! The CRC is CRC-32/ISO-HDLC (the Ethernet / zlib CRC, [`CRC`]) over the postcard bytes of the
//! message, appended little-endian by postcard's CRC flavor. The byte-string wrapper is what lets
//! postcard's [`CobsAccumulator`] hand the receiver the raw body, so the CRC can be checked by
//! postcard's CRC de-flavor ([`postcard::from_bytes_crc32`]).
//!
//! A lone `0x00` is an empty frame and is ignored: a sender may start with one to end whatever
//! partial frame the receiver holds (the host does, before every request).
//!
//! [`FrameDecoder::feed`] never panics: every malformed input ends as a [`FrameFault`], and a
//! frame longer than [`MAX_FRAME_BYTES`] is dropped up to its terminator and reported once.

use crc::{Crc, CRC_32_ISO_HDLC};
use postcard::accumulator::{CobsAccumulator, FeedResult};
use serde::{de::DeserializeOwned, Serialize};

/// Largest frame on the wire, bytes, the `0x00` terminator included. Every message of
/// [`super::message`] fits (a test checks the largest ones).
pub const MAX_FRAME_BYTES: usize = 512;

/// The CRC of the link: CRC-32/ISO-HDLC.
pub const CRC: Crc<u32> = Crc::<u32>::new(&CRC_32_ISO_HDLC);

/// Bytes of the CRC at the end of a body.
const CRC_BYTES: usize = 4;

/// Why a message could not be encoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum EncodeError {
    /// The encoded frame would exceed the buffer ([`MAX_FRAME_BYTES`]).
    TooLong,
}

impl core::fmt::Display for EncodeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            EncodeError::TooLong => {
                write!(f, "the encoded frame exceeds {MAX_FRAME_BYTES} bytes")
            }
        }
    }
}

impl core::error::Error for EncodeError {}

/// Why a received frame was dropped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FrameFault {
    /// Not valid COBS, or not a byte string, or shorter than a CRC.
    BadFrame,
    /// The CRC does not match.
    BadCrc,
    /// The CRC matches but the contents are not a message of the expected type. `seq` is the
    /// leading varint `u16` of the contents when there is one (requests start with their
    /// sequence number).
    BadMessage {
        /// The sequence number, if readable.
        seq: Option<u16>,
    },
    /// The frame was longer than [`MAX_FRAME_BYTES`]; it was dropped up to its terminator.
    TooLong,
}

/// Encode `message` as one frame into `out`; returns the frame, terminator included.
///
/// ```
/// use twil_core::link::frame::{encode, MAX_FRAME_BYTES};
/// let mut out = [0u8; MAX_FRAME_BYTES];
/// let frame = encode(&(1u16, 2u8), &mut out).unwrap();
/// assert_eq!(*frame.last().unwrap(), 0);
/// assert!(!frame[..frame.len() - 1].contains(&0));
/// ```
pub fn encode<'a, T: Serialize + ?Sized>(
    message: &T,
    out: &'a mut [u8; MAX_FRAME_BYTES],
) -> Result<&'a [u8], EncodeError> {
    let mut body_buf = [0u8; MAX_FRAME_BYTES];
    let body = postcard::to_slice_crc32(message, &mut body_buf, CRC.digest())
        .map_err(|_| EncodeError::TooLong)?;
    let body: &[u8] = body;
    let frame = postcard::to_slice_cobs(&body, out).map_err(|_| EncodeError::TooLong)?;
    Ok(frame)
}

/// Splits a byte stream into frames and decodes them (postcard's [`CobsAccumulator`] inside).
pub struct FrameDecoder {
    accumulator: CobsAccumulator<MAX_FRAME_BYTES>,
    /// Bytes of the current frame seen so far (0: at a frame boundary).
    pending: usize,
    /// Dropping an oversized frame up to its terminator.
    skipping: bool,
}

impl Default for FrameDecoder {
    fn default() -> Self {
        Self::new()
    }
}

impl FrameDecoder {
    /// A decoder at a frame boundary.
    pub const fn new() -> Self {
        Self {
            accumulator: CobsAccumulator::new(),
            pending: 0,
            skipping: false,
        }
    }

    /// `true` when no partial frame is held.
    pub fn is_idle(&self) -> bool {
        self.pending == 0 && !self.skipping
    }

    /// Feed received bytes. Returns the first complete frame found (a message or a fault), or
    /// `None` when `input` ended inside a frame, and the bytes after that frame, which the caller
    /// feeds again. Empty frames (a `0x00` at a frame boundary) are skipped.
    ///
    /// ```
    /// use twil_core::link::frame::{encode, FrameDecoder, FrameFault, MAX_FRAME_BYTES};
    /// let mut out = [0u8; MAX_FRAME_BYTES];
    /// let frame = encode(&7u32, &mut out).unwrap().to_vec();
    /// let mut decoder = FrameDecoder::new();
    /// // Split anywhere: the decoder waits for the terminator.
    /// assert_eq!(decoder.feed::<u32>(&frame[..2]), (None, &[][..]));
    /// assert_eq!(decoder.feed::<u32>(&frame[2..]), (Some(Ok(7)), &[][..]));
    /// // A flipped bit is caught by the CRC.
    /// let mut bad = frame.clone();
    /// bad[2] ^= 0x10;
    /// assert_eq!(decoder.feed::<u32>(&bad).0, Some(Err(FrameFault::BadCrc)));
    /// ```
    pub fn feed<'a, T: DeserializeOwned>(
        &mut self,
        mut input: &'a [u8],
    ) -> (Option<Result<T, FrameFault>>, &'a [u8]) {
        loop {
            if input.is_empty() {
                return (None, input);
            }
            if self.skipping {
                match input.iter().position(|&b| b == 0) {
                    Some(n) => {
                        self.skipping = false;
                        self.pending = 0;
                        return (
                            Some(Err(FrameFault::TooLong)),
                            input.get(n + 1..).unwrap_or(&[]),
                        );
                    }
                    None => return (None, &[]),
                }
            }
            if self.pending == 0 && input.first() == Some(&0) {
                // An empty frame: a separator, not a message.
                input = input.get(1..).unwrap_or(&[]);
                continue;
            }
            let zero = input.iter().position(|&b| b == 0);
            let before = self.pending;
            match self.accumulator.feed_ref::<&[u8]>(input) {
                FeedResult::Consumed => {
                    self.pending = before.saturating_add(input.len());
                    return (None, &[]);
                }
                FeedResult::OverFull(rest) => {
                    self.pending = 0;
                    if zero.is_some() {
                        // The terminator was in `input`: the oversized frame is over.
                        return (Some(Err(FrameFault::TooLong)), rest);
                    }
                    self.skipping = true;
                    input = rest;
                }
                FeedResult::DeserError(rest) => {
                    self.pending = 0;
                    return (Some(Err(FrameFault::BadFrame)), rest);
                }
                FeedResult::Success { data, remaining } => {
                    self.pending = 0;
                    return (Some(decode_body(data)), remaining);
                }
            }
        }
    }
}

/// Check the CRC of a body (message then CRC) and decode the message.
fn decode_body<T: DeserializeOwned>(body: &[u8]) -> Result<T, FrameFault> {
    if body.len() < CRC_BYTES {
        return Err(FrameFault::BadFrame);
    }
    match postcard::from_bytes_crc32::<T>(body, CRC.digest()) {
        Ok(message) => Ok(message),
        Err(postcard::Error::DeserializeBadCrc) => Err(FrameFault::BadCrc),
        Err(_) => {
            // The message did not decode, so postcard never reached the CRC: check it here to
            // tell a damaged frame from a well-formed frame we do not understand.
            let (contents, crc) = body.split_at(body.len() - CRC_BYTES);
            let mut crc_le = [0u8; CRC_BYTES];
            crc_le.copy_from_slice(crc);
            if CRC.checksum(contents) != u32::from_le_bytes(crc_le) {
                return Err(FrameFault::BadCrc);
            }
            let seq = postcard::take_from_bytes::<u16>(contents)
                .ok()
                .map(|(seq, _)| seq);
            Err(FrameFault::BadMessage { seq })
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::vec::Vec;

    fn frame_of<T: Serialize>(message: &T) -> Vec<u8> {
        let mut out = [0u8; MAX_FRAME_BYTES];
        encode(message, &mut out).unwrap().to_vec()
    }

    fn decode_all<T: DeserializeOwned>(stream: &[u8]) -> Vec<Result<T, FrameFault>> {
        let mut decoder = FrameDecoder::new();
        let mut out = Vec::new();
        let mut rest = stream;
        loop {
            let (got, r) = decoder.feed::<T>(rest);
            if let Some(g) = got {
                out.push(g);
            }
            if r.is_empty() {
                return out;
            }
            rest = r;
        }
    }

    #[test]
    fn frames_have_one_terminator_and_round_trip() {
        let long: heapless::Vec<u32, 64> = (0..64).map(|i| i * 1000).collect();
        let f = frame_of(&(513u16, -2.5f32, long.clone()));
        assert_eq!(f.iter().filter(|&&b| b == 0).count(), 1);
        assert_eq!(f.last(), Some(&0));
        let got = decode_all::<(u16, f32, heapless::Vec<u32, 64>)>(&f);
        assert_eq!(got, std::vec![Ok((513, -2.5, long))]);
    }

    #[test]
    fn several_frames_in_one_chunk_and_empty_frames() {
        let mut stream = std::vec![0u8, 0];
        stream.extend(frame_of(&1u32));
        stream.push(0);
        stream.extend(frame_of(&2u32));
        let got = decode_all::<u32>(&stream);
        assert_eq!(got, std::vec![Ok(1), Ok(2)]);
    }

    #[test]
    fn too_long_frames_are_reported_once_and_the_next_frame_decodes() {
        // 2000 non-zero bytes then a terminator, fed in pieces, then a good frame.
        let mut stream = std::vec![0x55u8; 2000];
        stream.push(0);
        stream.extend(frame_of(&77u32));
        for piece in [1usize, 7, 300, 5000] {
            let mut decoder = FrameDecoder::new();
            let mut got = Vec::new();
            for chunk in stream.chunks(piece) {
                let mut rest = chunk;
                loop {
                    let (g, r) = decoder.feed::<u32>(rest);
                    if let Some(g) = g {
                        got.push(g);
                    }
                    if r.is_empty() {
                        break;
                    }
                    rest = r;
                }
            }
            assert_eq!(
                got,
                std::vec![Err(FrameFault::TooLong), Ok(77)],
                "piece {piece}"
            );
            assert!(decoder.is_idle());
        }
    }

    #[test]
    fn truncated_and_garbage_frames_are_faults() {
        let f = frame_of(&(5u16, 123456u32));
        // Truncated: a terminator in the middle.
        let mut cut = f[..f.len() / 2].to_vec();
        cut.push(0);
        let got = decode_all::<(u16, u32)>(&cut);
        assert_eq!(got.len(), 1);
        assert!(got[0].is_err());
        // Garbage.
        let got = decode_all::<(u16, u32)>(&[1, 2, 3, 0]);
        assert_eq!(got.len(), 1);
        assert!(got[0].is_err());
    }

    #[test]
    fn good_crc_but_wrong_type_keeps_the_sequence_number() {
        // (seq, an unknown enum variant index)
        let f = frame_of(&(300u16, 200u8));
        let got = decode_all::<(u16, bool)>(&f);
        assert_eq!(
            got,
            std::vec![Err(FrameFault::BadMessage { seq: Some(300) })]
        );
    }

    proptest::proptest! {
        #[test]
        fn decoding_arbitrary_bytes_never_panics(bytes in proptest::collection::vec(proptest::num::u8::ANY, 0..1500)) {
            let got = decode_all::<super::super::RequestFrame>(&bytes);
            // At most one result per terminator.
            proptest::prop_assert!(got.len() <= bytes.iter().filter(|&&b| b == 0).count());
        }

        #[test]
        fn any_bit_flip_is_detected(seq in 0u16.., nonce in 0u32.., bit in 0usize..64) {
            use super::super::{Request, RequestFrame};
            let good = frame_of(&RequestFrame { seq, request: Request::Ping { nonce } });
            let mut bad = good.clone();
            let i = (bit / 8) % (bad.len() - 1);
            bad[i] ^= 1 << (bit % 8);
            let got = decode_all::<RequestFrame>(&bad);
            proptest::prop_assert!(got.iter().all(|g| g.is_err()), "{:?}", got);
        }
    }
}
