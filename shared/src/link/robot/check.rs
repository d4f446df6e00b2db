//! The self-test on the mission device ([`Request::SelfTest`](crate::link::Request::SelfTest), [`Request::SelfTestReport`](crate::link::Request::SelfTestReport)):
//! the device only keeps where the test stands and its latest report; the shell, which owns
//! the body, runs [`crate::selftest::SelfTest`] when [`RobotDevice::take_self_test`] says so
//! and hands each report back with [`RobotDevice::note_self_test`]. While the test runs no
//! mission starts (the wheels pulse), and while a mission runs no test starts.

use super::{state_index, RobotDevice};
use crate::link::message::{ErrorCode, ErrorReply, Reply, RunState};
use crate::selftest::SelfTestReport;

/// Where the self-test stands on the device.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CheckState {
    /// None asked for (or the last one is done).
    Idle,
    /// Asked for; the shell has not taken it yet.
    Asked,
    /// The shell runs it.
    Running,
}

impl<const W: usize> RobotDevice<W> {
    /// A self-test was asked for: the shell runs it now (true once per request).
    pub fn take_self_test(&mut self) -> bool {
        if self.check_state == CheckState::Asked {
            self.check_state = CheckState::Running;
            true
        } else {
            false
        }
    }

    /// The shell's report so far; a report with `done` ends the test.
    pub fn note_self_test(&mut self, report: &SelfTestReport) {
        self.check_report = report.clone();
        if report.done {
            self.check_state = CheckState::Idle;
        }
    }

    /// Whether a self-test is asked for or running.
    pub fn self_test_busy(&self) -> bool {
        self.check_state != CheckState::Idle
    }

    /// [`Request::SelfTest`](crate::link::Request::SelfTest): refused while a mission runs or
    /// is paused, or a test is under way.
    pub(super) fn start_self_test(&mut self) -> Result<Reply, ErrorReply> {
        if matches!(self.state, RunState::Running | RunState::Paused) {
            return Err(ErrorReply::new(
                ErrorCode::WrongState,
                state_index(self.state),
                0,
            ));
        }
        if self.self_test_busy() {
            return Err(self_test_busy(self.state));
        }
        self.check_state = CheckState::Asked;
        self.check_report = SelfTestReport::new();
        Ok(Reply::Ack)
    }
}

/// The refusal of a request while the self-test runs.
pub(super) fn self_test_busy(state: RunState) -> ErrorReply {
    ErrorReply {
        code: ErrorCode::WrongState,
        value: state_index(state),
        limit: 0,
        detail: 2,
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::ready;
    use crate::link::frame::{encode, MAX_FRAME_BYTES};
    use crate::link::message::{ErrorCode, Reply, Request};
    use crate::link::DeviceFrame;
    use crate::mission::MissionMode;
    extern crate std;
    use crate::selftest::{Check, CheckRow, CheckStatus, Hint, SelfTestReport, MAX_CHECK_ROWS};
    use std::string::ToString;

    #[test]
    fn a_self_test_runs_between_missions_and_keeps_missions_out() {
        let (mut b, _, _) = ready(MissionMode::Stop);
        assert!(!b.shell.device.take_self_test(), "none asked");
        assert_eq!(b.call(Request::SelfTest), Reply::Ack);
        // A second request, or a mission, waits for its end.
        for request in [Request::SelfTest, Request::StartMission] {
            match b.call(request) {
                Reply::Error(e) => {
                    assert_eq!((e.code, e.detail), (ErrorCode::WrongState, 2), "{e}");
                    assert_eq!(e.to_string(), "not now: the self-test runs");
                }
                other => panic!("{other:?}"),
            }
        }
        assert!(b.shell.device.take_self_test());
        assert!(!b.shell.device.take_self_test(), "taken once");
        let mut report = SelfTestReport::new();
        assert_eq!(
            b.call(Request::SelfTestReport),
            Reply::SelfTest(report.clone())
        );
        report.done = true;
        b.shell.device.note_self_test(&report);
        assert_eq!(b.call(Request::SelfTestReport), Reply::SelfTest(report));
        assert_eq!(b.call(Request::StartMission), Reply::Ack);
        // And no test while the mission runs.
        match b.call(Request::SelfTest) {
            Reply::Error(e) => {
                assert_eq!((e.code, e.value, e.detail), (ErrorCode::WrongState, 2, 0))
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn a_full_report_fits_a_frame() {
        let row = CheckRow {
            check: Check::RightMotor,
            status: CheckStatus::Skip,
            value: f32::MAX,
            expected_min: f32::MAX,
            expected_max: f32::MAX,
            detail: f32::MAX,
            hint: Hint::NotOnThisBuild,
        };
        let report = SelfTestReport {
            done: true,
            rows: heapless::Vec::from_slice(&[row; MAX_CHECK_ROWS]).unwrap(),
        };
        let frame = DeviceFrame::Reply {
            seq: Some(u16::MAX),
            reply: Reply::SelfTest(report),
        };
        let mut out = [0u8; MAX_FRAME_BYTES];
        assert!(encode(&frame, &mut out).is_ok());
    }
}
