//! Host <-> firmware protocol: messages, postcard + COBS + CRC framing (issue 4).
//!
//! Status: not written yet.
