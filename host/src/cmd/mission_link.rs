//! `twil mission` on a lossy link: what the host does when telemetry is lost.
//!
//! Requests are retried by [`Remote::request`] (the device never executes one twice), but
//! telemetry is sent once and not acknowledged, so any of it may be lost:
//!
//! - `Finished` (the final report): when the device has been quiet for [`POLL_AFTER`], the
//!   host asks `MissionStatus`; a report with state `Ended` is the final report
//!   ([`recover_final_report`]). The mission's result (status, stops, distance by odometry,
//!   plans…) is the device's own report, whole, whatever telemetry was lost.
//! - `Pose`, `SweepHits`, `Prefix`, `Path`: what the host draws and writes (trajectory,
//!   pictures, the map rebuilt from the hits) misses the lost chunks. The host does not pretend
//!   otherwise: `summary.json` counts the chunks that arrived after a gap
//!   (`link.telemetry_gaps`), next to the retries and the damaged frames dropped.

use std::time::Duration;

use serde_json::json;
use twil_core::link::{Reply, Request, RunState, Telemetry};

use crate::remote::Remote;

/// Quiet time after which the host asks the device how the mission stands. A running mission
/// reports its pose every 200 ms, so a second of quiet means lost frames or an ended mission.
pub const POLL_AFTER: Duration = Duration::from_secs(1);

/// What [`recover_final_report`] learnt.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Poll {
    /// The mission has ended: the follower has its final report.
    Finished,
    /// The device answered: the mission goes on (the link is alive, only quiet).
    Alive,
    /// No reply within the timeout: the caller's silence limit decides.
    NoReply,
}

/// Ask `MissionStatus`; if the mission has ended, hand its report to `follower` as the final
/// report (the `Finished` telemetry was lost).
pub(super) fn recover_final_report(
    remote: &mut Remote,
    follower: &mut super::mission::Follower,
) -> Poll {
    let reply = remote.request(Request::MissionStatus);
    // Telemetry that came in meanwhile goes first, in order.
    for t in std::mem::take(&mut remote.telemetry) {
        follower.absorb(t);
    }
    if follower.finished.is_some() {
        return Poll::Finished;
    }
    match reply {
        Ok(Reply::Mission(report)) if report.state == RunState::Ended => {
            follower.absorb(Telemetry::Finished(report));
            Poll::Finished
        }
        Ok(_) => Poll::Alive,
        Err(_) => Poll::NoReply,
    }
}

/// What the link lost and repaired during a mission.
#[derive(Clone, Copy, Debug, Default)]
pub struct LinkReport {
    /// Requests sent again.
    pub retries: u32,
    /// Damaged frames from the device dropped.
    pub damaged_frames: u32,
    /// Telemetry chunks that arrived after a lost one.
    pub telemetry_gaps: u32,
}

impl LinkReport {
    /// The figures of `remote` and the follower's gaps.
    pub fn of(remote: &Remote, telemetry_gaps: u32) -> Self {
        Self {
            retries: remote.retries(),
            damaged_frames: remote.damaged_frames(),
            telemetry_gaps,
        }
    }

    /// As `summary.json` writes it.
    pub fn json(&self) -> serde_json::Value {
        json!({
            "retries": self.retries,
            "damaged_frames": self.damaged_frames,
            "telemetry_gaps": self.telemetry_gaps,
        })
    }
}
