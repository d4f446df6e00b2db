//! How `twil` tells a script how a command ended: its exit status.
//!
//! | status | meaning |
//! |---|---|
//! | 0 | done: the plan was found, the mission reached the goal, the command did its work |
//! | 1 | error: a file, an option's value, the link or the device failed; one line on stderr |
//! | 2 | usage: the command line itself is wrong (from clap) |
//! | 3 | no path: the plan or the mission ended `unreachable` (also `start_blocked`, `goal_blocked`, `out_of_bounds`, a potential field's `local_minimum`, a Bug that `gave_up`) |
//! | 4 | collision: the robot's body touched an obstacle |
//! | 5 | timeout: the mission's time limit ran out |
//! | 6 | aborted: the device or another host stopped the mission |
//! | 130 | interrupted: Ctrl-C |
//!
//! `--json` output is printed whatever the status, so a script can read the details.

/// The text `twil --help` shows after its commands (the table above, and the environment).
pub const HELP: &str = "Exit status:
  0    done: plan found, goal reached, command did its work
  1    error (file, option value, link, device); one line on stderr
  2    usage error (command line)
  3    no path: unreachable (or start/goal blocked, out of bounds, local minimum, gave up)
  4    collision: the robot's body touched an obstacle
  5    timeout: the mission's time limit ran out
  6    aborted: the device or another host stopped the mission
  130  interrupted (Ctrl-C)
  141  standard output closed by its reader (`twil … | head`)

Environment:
  TWIL_QEMU_ELF     the firmware ELF that --remote qemu runs (default: the one cargo xtask firmware built)
  CARGO_TARGET_DIR  where to look for that ELF (default: target/ of the workspace)
  TWIL_QEMU_LOG     save the QEMU firmware's defmt log to this file (decode: cargo xtask defmt-log FILE)
  TWIL_LINK_DEBUG   print every frame sent to and received from the device on stderr
  TWIL_SIM_DEBUG    print the simulator's mission events on stderr";

/// How a command ended, when it ran (errors are `Err` and exit with 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ending {
    /// Done: found, reached, or a command without such an outcome did its work.
    Done,
    /// No path: unreachable, blocked start or goal, out of bounds, local minimum, gave up.
    NoPath,
    /// The robot's body touched an obstacle.
    Collision,
    /// The mission's time limit ran out.
    Timeout,
    /// The device or another host stopped the mission.
    Aborted,
    /// Ctrl-C stopped the command (after it closed its files and stopped the motors).
    Interrupted,
}

impl Ending {
    /// The process exit status.
    pub fn code(self) -> i32 {
        match self {
            Ending::Done => 0,
            Ending::NoPath => 3,
            Ending::Collision => 4,
            Ending::Timeout => 5,
            Ending::Aborted => 6,
            Ending::Interrupted => 130,
        }
    }

    /// The ending of a plan or search status as the JSON names it (`found`, `unreachable`, …).
    pub fn of_plan_status(status: &str) -> Self {
        if status == "found" {
            Ending::Done
        } else {
            Ending::NoPath
        }
    }

    /// The ending of a mission status as the JSON names it (`reached`, `start_blocked`,
    /// `goal_blocked`, `out_of_bounds`, `unreachable`, `gave_up`, `collision`, `timeout`,
    /// `aborted`: crate::answer).
    pub fn of_mission_status(status: &str) -> Self {
        match status {
            "reached" => Ending::Done,
            "unreachable" | "start_blocked" | "goal_blocked" | "out_of_bounds" | "gave_up" => {
                Ending::NoPath
            }
            "collision" => Ending::Collision,
            "timeout" => Ending::Timeout,
            _ => Ending::Aborted,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_ending_has_its_own_code_and_the_help_lists_it() {
        let all = [
            Ending::Done,
            Ending::NoPath,
            Ending::Collision,
            Ending::Timeout,
            Ending::Aborted,
            Ending::Interrupted,
        ];
        let mut codes: Vec<i32> = all.iter().map(|e| e.code()).collect();
        codes.sort();
        codes.dedup();
        assert_eq!(codes.len(), all.len());
        for e in all {
            let code = e.code().to_string();
            assert!(
                HELP.lines()
                    .any(|l| l.trim_start().starts_with(&format!("{code} "))),
                "{code}"
            );
        }
        assert_eq!(Ending::of_mission_status("timeout"), Ending::Timeout);
        assert_eq!(Ending::of_mission_status("gave_up"), Ending::NoPath);
        assert_eq!(Ending::of_mission_status("goal_blocked"), Ending::NoPath);
        assert_eq!(Ending::of_plan_status("local_minimum"), Ending::NoPath);
    }
}
