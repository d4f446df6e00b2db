//! A request retried by the host is answered again, never executed twice.
//!
//! The host resends a request under the same `seq` when its reply did not come back (lost,
//! damaged, late). The device keeps the last request it executed as `(seq, fingerprint)` and,
//! for the requests that change something, its reply. A frame that repeats both gets the stored
//! reply; any other frame replaces the entry. Only the immediately preceding request is matched,
//! so sequence numbers may wrap and a restarted host (which starts again from seq 1 with a
//! `Hello`, itself a new entry) never meets a stale reply; the fingerprint (CRC-32 of the
//! request's postcard bytes) keeps a different request that happens to reuse the last `seq`
//! from being mistaken for a retry.
//!
//! Which requests are replayed ([`is_replayed`]): the ones that change state or cost time
//! (`SetParams`, `ClearMap`, `ObstacleChunk`, `WriteMap`, `Plan`, `SetMission`, `WorldChunk`,
//! `ClearWorld`, `StartMission`, `PauseMission`, `ResumeMission`, `AbortMission`,
//! `EmergencyStop`, `ClearEmergencyStop`). Their replies are small (`Ack`, `Obstacles`,
//! `Plan`, `Error`: [`CachedReply`], 48 bytes). The pure reads (`Hello`, `Ping`, `ReadPath`,
//! `ReadMap`, `Status`, `MissionStatus`, `ParamList`, `ParamGet`) are executed again: harmless,
//! and their replies (up to 270 bytes) are not worth the RAM. `ParamSet`'s reply (a parameter
//! row, about 80 bytes) is not kept either: a retry sets the same value again, which changes
//! nothing and writes nothing (the store skips a value it already holds).

use serde::Serialize;

use super::frame::CRC;
use super::message::{ErrorReply, PlanSummary, Reply, Request};

/// The reply of a replayed request, kept for a retry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CachedReply {
    /// [`Reply::Ack`].
    Ack,
    /// [`Reply::Obstacles`].
    Obstacles {
        /// Polygons stored.
        polygons: u16,
        /// Vertices stored.
        vertices: u16,
        /// Vertices of the polygon being uploaded.
        pending_vertices: u16,
    },
    /// [`Reply::Plan`].
    Plan(PlanSummary),
    /// [`Reply::Error`].
    Error(ErrorReply),
}

impl CachedReply {
    fn of(reply: &Reply) -> Option<Self> {
        Some(match reply {
            Reply::Ack => CachedReply::Ack,
            Reply::Obstacles {
                polygons,
                vertices,
                pending_vertices,
            } => CachedReply::Obstacles {
                polygons: *polygons,
                vertices: *vertices,
                pending_vertices: *pending_vertices,
            },
            Reply::Plan(s) => CachedReply::Plan(*s),
            Reply::Error(e) => CachedReply::Error(*e),
            _ => return None,
        })
    }

    fn reply(self) -> Reply {
        match self {
            CachedReply::Ack => Reply::Ack,
            CachedReply::Obstacles {
                polygons,
                vertices,
                pending_vertices,
            } => Reply::Obstacles {
                polygons,
                vertices,
                pending_vertices,
            },
            CachedReply::Plan(s) => Reply::Plan(s),
            CachedReply::Error(e) => Reply::Error(e),
        }
    }
}

/// Whether a retry of `request` is answered from the cache (else executed again).
pub fn is_replayed(request: &Request) -> bool {
    !matches!(
        request,
        Request::Hello { .. }
            | Request::Ping { .. }
            | Request::ReadPath { .. }
            | Request::ReadMap { .. }
            | Request::Status
            | Request::MissionStatus
            | Request::ParamList { .. }
            | Request::ParamGet { .. }
    )
}

/// CRC-32 of the postcard bytes of `request`, computed as they are produced (no buffer).
pub fn fingerprint(request: &Request) -> u32 {
    struct Digest<'a>(crc::Digest<'a, u32>);
    impl postcard::ser_flavors::Flavor for Digest<'_> {
        type Output = u32;
        fn try_push(&mut self, data: u8) -> postcard::Result<()> {
            self.0.update(&[data]);
            Ok(())
        }
        fn try_extend(&mut self, data: &[u8]) -> postcard::Result<()> {
            self.0.update(data);
            Ok(())
        }
        fn finalize(self) -> postcard::Result<u32> {
            Ok(self.0.finalize())
        }
    }
    fn digest<T: Serialize>(value: &T) -> u32 {
        // Serializing into a digest cannot fail (no buffer to overflow).
        postcard::serialize_with_flavor(value, Digest(CRC.digest())).unwrap_or(0)
    }
    digest(request)
}

#[derive(Clone, Copy, Debug)]
struct Entry {
    seq: u16,
    fingerprint: u32,
    reply: Option<CachedReply>,
}

/// The last executed request and, if it is replayed, its reply (see the module docs).
#[derive(Clone, Copy, Debug, Default)]
pub struct ReplayCache {
    last: Option<Entry>,
    replays: u32,
}

impl ReplayCache {
    /// Nothing executed yet.
    pub const fn new() -> Self {
        Self {
            last: None,
            replays: 0,
        }
    }

    /// The stored reply if `seq` and `request` repeat the last executed request and it is
    /// replayed; else `None` (execute it, then [`ReplayCache::record`]).
    pub fn lookup(&mut self, seq: u16, request: &Request) -> Option<Reply> {
        let last = self.last?;
        if last.seq != seq || !is_replayed(request) {
            return None;
        }
        let reply = last.reply?;
        if last.fingerprint != fingerprint(request) {
            return None;
        }
        self.replays = self.replays.saturating_add(1);
        Some(reply.reply())
    }

    /// Note that `request` (`seq`) was executed and answered `reply`.
    pub fn record(&mut self, seq: u16, request: &Request, reply: &Reply) {
        let reply = if is_replayed(request) {
            CachedReply::of(reply)
        } else {
            None
        };
        self.last = Some(Entry {
            seq,
            fingerprint: if reply.is_some() {
                fingerprint(request)
            } else {
                0
            },
            reply,
        });
    }

    /// Requests answered from the cache so far.
    pub fn replays(&self) -> u32 {
        self.replays
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::link::message::{ErrorCode, MapParams};

    #[test]
    fn a_repeat_of_the_last_request_gets_its_reply_and_nothing_else_does() {
        let mut cache = ReplayCache::new();
        let clear = Request::ClearMap;
        assert_eq!(cache.lookup(5, &clear), None, "nothing executed yet");
        cache.record(5, &clear, &Reply::Ack);
        assert_eq!(cache.lookup(5, &clear), Some(Reply::Ack));
        assert_eq!(cache.replays(), 1);
        // Same seq, another request (a restarted host): executed.
        let params = Request::SetParams(MapParams {
            width_cells: 10,
            height_cells: 10,
            resolution_m: 0.05,
            robot_radius_m: 0.0,
        });
        assert_eq!(cache.lookup(5, &params), None);
        // Another seq: executed.
        assert_eq!(cache.lookup(6, &clear), None);
        // A read in between replaces the entry: the old seq is no longer matched.
        cache.record(6, &Request::Status, &Reply::Ack);
        assert_eq!(cache.lookup(5, &clear), None);
        assert_eq!(
            cache.lookup(6, &Request::Status),
            None,
            "reads are executed again"
        );
        // Errors are replayed too.
        let e = Reply::Error(ErrorReply::new(ErrorCode::WrongState, 2, 0));
        cache.record(7, &Request::StartMission, &e);
        assert_eq!(cache.lookup(7, &Request::StartMission), Some(e));
    }

    #[test]
    fn the_cache_is_small() {
        // The firmware's RAM is tight: no copy of a 270-byte reply.
        assert!(core::mem::size_of::<ReplayCache>() <= 64);
        assert!(core::mem::size_of::<CachedReply>() <= 48);
    }

    #[test]
    fn fingerprints_tell_requests_apart() {
        assert_ne!(
            fingerprint(&Request::ClearMap),
            fingerprint(&Request::ClearWorld)
        );
        assert_ne!(
            fingerprint(&Request::ReadPath { offset: 0 }),
            fingerprint(&Request::ReadPath { offset: 32 })
        );
        assert_eq!(
            fingerprint(&Request::ReadPath { offset: 32 }),
            fingerprint(&Request::ReadPath { offset: 32 })
        );
    }
}
