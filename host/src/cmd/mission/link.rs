//! `twil mission` on a lossy link: what the host does when telemetry is lost.
//!
//! Requests are retried by [`Remote::request`] (the device never executes one twice), but
//! telemetry is sent once and not acknowledged, so any of it may be lost:
//!
//! - `Finished` (the final report): when the device has been quiet for [`POLL_AFTER`], the
//!   host asks `MissionStatus`; a report with state `Ended` is the final report
//!   (`recover_final_report` in `follower.rs`). The mission's result (status, stops, distance
//!   by odometry, plans…) is the device's own report, whole, whatever telemetry was lost.
//! - `Pose`, `SweepHits`, `Prefix`, `Path`: what the host draws and writes (trajectory,
//!   pictures, the map rebuilt from the hits) misses the lost chunks. The host does not pretend
//!   otherwise: `summary.json` counts the chunks that arrived after a gap
//!   (`link.telemetry_gaps`), next to the retries and the damaged frames dropped.

use std::collections::BTreeSet;
use std::time::Duration;

use serde_json::json;
use twil_core::link::FrameFault;

use crate::remote::Remote;

/// Quiet time after which the host asks the device how the mission stands. A running mission
/// reports its pose every 200 ms, so a second of quiet means lost frames or an ended mission.
pub const POLL_AFTER: Duration = Duration::from_secs(1);

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

impl LinkReport {
    /// The figures as the live line and the summary print them (`link: 3 damaged frames
    /// dropped, 2 requests resent, 1 telemetry gap`), or `None` on a clean link.
    pub fn words(&self) -> Option<String> {
        if self.retries == 0 && self.damaged_frames == 0 && self.telemetry_gaps == 0 {
            return None;
        }
        let plural =
            |n: u32, one: &str, many: &str| format!("{n} {}", if n == 1 { one } else { many });
        Some(format!(
            "link: {} dropped, {} resent, {}",
            plural(self.damaged_frames, "damaged frame", "damaged frames"),
            plural(self.retries, "request", "requests"),
            plural(self.telemetry_gaps, "telemetry gap", "telemetry gaps"),
        ))
    }
}

/// Which damaged frames to report on stderr: the first of each kind (bad CRC, bad COBS, …),
/// with a word on where the rest are counted, or every one with `TWIL_LINK_DEBUG`. A noisy
/// link damages hundreds of frames in a mission that still reaches its goal: the count
/// belongs in the live line and the summary, not one line each in the terminal.
#[derive(Debug, Default)]
pub struct FaultNotes {
    seen: BTreeSet<&'static str>,
    every: bool,
}

impl FaultNotes {
    /// Notes for this process (`TWIL_LINK_DEBUG` set: every fault).
    pub fn from_env() -> Self {
        Self {
            seen: BTreeSet::new(),
            every: std::env::var_os("TWIL_LINK_DEBUG").is_some(),
        }
    }

    /// The line to print for `fault`, if any.
    pub fn line(&mut self, fault: &FrameFault) -> Option<String> {
        let kind = match fault {
            FrameFault::BadFrame => "BadFrame",
            FrameFault::BadCrc => "BadCrc",
            FrameFault::BadMessage { .. } => "BadMessage",
            FrameFault::TooLong => "TooLong",
        };
        if self.every {
            return Some(format!(
                "twil: dropped a damaged frame from the device: {fault:?}"
            ));
        }
        self.seen.insert(kind).then(|| {
            format!(
                "twil: dropped a damaged frame from the device ({kind}); further ones are \
                 counted in the status line and the summary (TWIL_LINK_DEBUG=1 prints each)"
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_line_per_kind_of_fault_unless_debugging() {
        let mut notes = FaultNotes::default();
        let lines: Vec<_> = [
            FrameFault::BadCrc,
            FrameFault::BadCrc,
            FrameFault::BadFrame,
            FrameFault::BadCrc,
            FrameFault::BadMessage { seq: Some(3) },
            FrameFault::BadMessage { seq: None },
        ]
        .iter()
        .filter_map(|f| notes.line(f))
        .collect();
        assert_eq!(lines.len(), 3, "{lines:#?}");
        assert!(lines[0].contains("(BadCrc)") && lines[1].contains("(BadFrame)"));
        let mut every = FaultNotes {
            every: true,
            ..FaultNotes::default()
        };
        assert!(every.line(&FrameFault::BadCrc).is_some());
        assert!(every.line(&FrameFault::BadCrc).is_some());
    }

    #[test]
    fn the_link_figures_in_words_only_when_something_happened() {
        assert_eq!(LinkReport::default().words(), None);
        let noisy = LinkReport {
            retries: 1,
            damaged_frames: 327,
            telemetry_gaps: 2,
        };
        assert_eq!(
            noisy.words().unwrap(),
            "link: 327 damaged frames dropped, 1 request resent, 2 telemetry gaps"
        );
    }
}
