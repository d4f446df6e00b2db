//! Why a mission ended, as one word: `twil simulate` and `twil mission` print it on every end,
//! in the human summary line (`; stop cause: link_lost`), as `stop_cause` in `--json` and in
//! `summary.json` (issue 25: a mission the device's link-loss failsafe aborted used to end with
//! no word on why).
//!
//! A stop from outside the mission's own logic (the device's failsafes, the host's abort,
//! Ctrl-C) names that cause; otherwise the end is the mission's status, with an
//! `unreachable` that came from too many plans without progress, or from gap visits that
//! settled nothing (`--evidence-map`, docs/mapping.md), said as `gave_up` (neither is a proof), and one
//! whose goal the sonar found inside an obstacle as `goal_blocked` (the status words of
//! crate::answer).

use twil_core::failsafe::StopCause;
use twil_core::mission::UnreachableReason;

/// The stop cause of a mission that ended with status word `status` (`reached`,
/// `unreachable`, `timeout`, `collision`, `aborted`), the planner's reason for an
/// `unreachable`, the device's [`StopCause`] and whether Ctrl-C stopped it.
pub fn name(
    status: &str,
    unreachable: Option<UnreachableReason>,
    device: StopCause,
    interrupted: bool,
) -> &'static str {
    if interrupted {
        return "interrupted";
    }
    match device {
        StopCause::Host => return "host_abort",
        StopCause::EmergencyStop => return "emergency_stop",
        StopCause::LinkLost => return "link_lost",
        StopCause::ControllerOverrun => return "controller_overrun",
        StopCause::SensorFault(_) => return "sensor_fault",
        StopCause::None => {}
    }
    match status {
        "reached" => "reached",
        "collision" => "collision",
        "timeout" => "timeout",
        "unreachable"
            if matches!(
                unreachable,
                Some(UnreachableReason::NoProgress | UnreachableReason::GapsUnsettled)
            ) =>
        {
            "gave_up"
        }
        "unreachable" if unreachable == Some(UnreachableReason::GoalBlocked) => "goal_blocked",
        "unreachable" => "unreachable",
        _ => "aborted",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_end_has_a_word_and_an_outside_stop_wins() {
        assert_eq!(name("reached", None, StopCause::None, false), "reached");
        // An `unreachable` is a proof only when the map says so; the rest is giving up.
        for (reason, word) in [
            (UnreachableReason::NoProgress, "gave_up"),
            (UnreachableReason::GapsUnsettled, "gave_up"),
            (UnreachableReason::ConfirmedCut, "unreachable"),
            (UnreachableReason::NoPath, "unreachable"),
        ] {
            let got = name("unreachable", Some(reason), StopCause::None, false);
            assert_eq!(got, word, "{reason:?}");
        }
        assert_eq!(
            name("aborted", None, StopCause::LinkLost, false),
            "link_lost"
        );
        assert_eq!(name("aborted", None, StopCause::Host, true), "interrupted");
        assert_eq!(name("collision", None, StopCause::None, false), "collision");
        assert_eq!(name("timeout", None, StopCause::None, false), "timeout");
    }
}
