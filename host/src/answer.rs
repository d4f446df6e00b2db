//! One answer per situation (issue 26, items 2 and 3): how `twil plan`, `twil simulate` and
//! `twil mission` (every `--remote`) say that they did not reach the goal. Each situation has
//! one status word (`status` in `--json` and `summary.json`, the first word of the summary
//! line), one exit status ([`Ending`]) and one sentence that says why (`why` in the JSON, after
//! the word on the summary line), whose opening is the same whichever command met it.
//!
//! Before this, a goal inside an obstacle was `goal_blocked` to `twil plan` and `unreachable`
//! to a mission; a start off the map was `out_of_bounds` (exit 3) to `twil plan` and an error
//! (exit 1) to the others; a stall said only `stop cause: gave_up`. The table below is the one
//! in docs/mission.md ("One answer per situation"); `twil --help` lists the exit statuses.
//! A found plan or a reached goal has no `why` (nothing went wrong), so their lines are as
//! before.

use std::fmt;

use twil_core::failsafe::StopCause;
use twil_core::geom::PointM;
use twil_core::mission::UnreachableReason;

use crate::exit::Ending;

/// A situation in which a command does not reach the goal.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Situation {
    /// The robot at the start overlaps an obstacle.
    StartBlocked,
    /// The goal lies in an obstacle (grown by the planning radius).
    GoalBlocked,
    /// The start or the goal lies off the map.
    OutOfBounds,
    /// No path joins the robot to the goal on the map: the goal is walled in.
    Unreachable,
    /// Too many plans in a row from the same place (a mission only).
    GaveUp,
    /// The robot's body touched an obstacle (a mission only).
    Collision,
    /// The mission's time limit ran out (a mission only).
    Timeout,
    /// Something stopped the mission: a host's abort, a device failsafe, Ctrl-C (a mission
    /// only; Ctrl-C exits 130).
    Aborted,
}

impl Situation {
    /// Every situation, in the order of the table.
    pub const ALL: [Situation; 8] = [
        Situation::StartBlocked,
        Situation::GoalBlocked,
        Situation::OutOfBounds,
        Situation::Unreachable,
        Situation::GaveUp,
        Situation::Collision,
        Situation::Timeout,
        Situation::Aborted,
    ];

    /// The status word.
    pub fn word(self) -> &'static str {
        match self {
            Situation::StartBlocked => "start_blocked",
            Situation::GoalBlocked => "goal_blocked",
            Situation::OutOfBounds => "out_of_bounds",
            Situation::Unreachable => "unreachable",
            Situation::GaveUp => "gave_up",
            Situation::Collision => "collision",
            Situation::Timeout => "timeout",
            Situation::Aborted => "aborted",
        }
    }

    /// The situation of a status word (`None` for `found`, `reached` and unknown words).
    pub fn of_word(word: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|s| s.word() == word)
    }

    /// The exit status (an abort by Ctrl-C is [`Ending::Interrupted`] instead).
    pub fn ending(self) -> Ending {
        match self {
            Situation::StartBlocked
            | Situation::GoalBlocked
            | Situation::OutOfBounds
            | Situation::Unreachable
            | Situation::GaveUp => Ending::NoPath,
            Situation::Collision => Ending::Collision,
            Situation::Timeout => Ending::Timeout,
            Situation::Aborted => Ending::Aborted,
        }
    }

    /// How every sentence of this situation opens (`X`, `Y` stand for coordinates, `…` for
    /// the rest), as docs/mission.md's table shows it.
    pub fn shape(self) -> &'static str {
        match self {
            Situation::StartBlocked => "the start (X, Y) lies in an obstacle …",
            Situation::GoalBlocked => "the goal (X, Y) lies in an obstacle …",
            Situation::OutOfBounds => "the start|goal (X, Y) lies off the W x H m map",
            Situation::Unreachable => "no path leads from (X, Y) to the goal (X, Y) …",
            Situation::GaveUp => "gave up at (X, Y) after N plans from the same place: …",
            Situation::Collision => "the robot's body touched an obstacle of FILE at (X, Y) …",
            Situation::Timeout => "the time limit of T s ran out at (X, Y), D m from the goal",
            Situation::Aborted => "the mission was aborted at (X, Y): …",
        }
    }
}

/// `(x, y)` with centimetres.
pub fn at(p: PointM) -> String {
    format!("({:.2}, {:.2})", p.x_m, p.y_m)
}

/// The name of a file for a sentence (its last component).
pub fn file_name(path: &std::path::Path) -> String {
    path.file_name()
        .unwrap_or(path.as_os_str())
        .to_string_lossy()
        .into_owned()
}

/// A start or goal off the map, found before anything ran: the setup's error, which
/// `twil simulate` and `twil mission` turn into the answer `out_of_bounds` (other users of
/// the setup see an error naming the file).
#[derive(Clone, Debug, PartialEq)]
pub struct OffMap {
    /// The `.par` file.
    pub params: String,
    /// `start` or `goal`.
    pub which: &'static str,
    /// The point.
    pub point: PointM,
    /// The `--size` as given.
    pub size: String,
}

impl OffMap {
    /// `Err` for the first of the start and goal of `par` (read from the file `params`) off
    /// `geometry` (the map of `--size size`).
    pub fn check(
        params: &std::path::Path,
        size: &str,
        geometry: &twil_core::grid::GridGeometry,
        par: &twil_core::world::Params,
    ) -> Result<(), OffMap> {
        for (which, point) in [("start", par.start), ("goal", par.goal)] {
            if geometry.cell_of(point).is_err() {
                return Err(OffMap {
                    params: params.display().to_string(),
                    which,
                    point,
                    size: size.to_string(),
                });
            }
        }
        Ok(())
    }

    /// The sentence.
    pub fn why(&self) -> String {
        off_map(self.which, self.point, &self.size)
    }
}

impl fmt::Display for OffMap {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: the {} ({}, {}) lies off the {} m map",
            self.params, self.which, self.point.x_m, self.point.y_m, self.size
        )
    }
}

impl std::error::Error for OffMap {}

/// `out_of_bounds`.
pub fn off_map(which: &str, p: PointM, size: &str) -> String {
    let size = size.replace('x', " x ");
    format!("the {which} {} lies off the {size} m map", at(p))
}

/// `start_blocked` of `twil plan`: the start cell is occupied on the grown map.
pub fn start_blocked_on_map(start: PointM, source: &str, radius_m: f32) -> String {
    format!(
        "the start {} lies in an obstacle of {source} grown by the robot radius {radius_m:.2} m",
        at(start)
    )
}

/// `goal_blocked` of `twil plan`.
pub fn goal_blocked_on_map(goal: PointM, source: &str, radius_m: f32) -> String {
    format!(
        "the goal {} lies in an obstacle of {source} grown by the robot radius {radius_m:.2} m",
        at(goal)
    )
}

/// `unreachable` of `twil plan`.
pub fn walled_in_on_map(start: PointM, goal: PointM, source: &str) -> String {
    format!(
        "no path leads from {} to the goal {} on the map of {source}: the goal is walled in",
        at(start),
        at(goal)
    )
}

/// What a mission that did not reach its goal knows of its end.
#[derive(Clone, Debug)]
pub struct MissionEnd<'a> {
    /// The mission's status word (`reached`, `unreachable`, `timeout`, `aborted`; a
    /// `collision` seen by the host).
    pub status: &'a str,
    /// The mission's reason for an `unreachable`.
    pub unreachable: Option<UnreachableReason>,
    /// The device's stop cause.
    pub device: StopCause,
    /// Ctrl-C stopped it.
    pub interrupted: bool,
    /// Where the robot was at the end (at the first contact for a collision).
    pub at: PointM,
    /// The goal.
    pub goal: PointM,
    /// The planning radius, metres.
    pub radius_m: f32,
    /// Plans in a row asked for from within `stall_distance_m` of `at`.
    pub plans_here: u32,
    /// The stall distance, metres.
    pub stall_distance_m: f32,
    /// The body's clearance at a collision, metres (negative).
    pub clearance_m: f32,
    /// The real world's file, for a collision.
    pub real: Option<String>,
    /// The time limit, seconds.
    pub time_limit_s: f32,
    /// The device's last planner error, for an abort without a stop cause.
    pub plan_error: Option<String>,
    /// The last plan found no free cell near the robot to start from (`start_blocked`).
    pub no_start: bool,
}

impl MissionEnd<'_> {
    /// The situation, or `None` for a reached goal.
    pub fn situation(&self) -> Option<Situation> {
        if self.status == "collision" {
            return Some(Situation::Collision);
        }
        if self.interrupted || self.device != StopCause::None {
            return Some(Situation::Aborted);
        }
        match self.status {
            "reached" => None,
            "timeout" => Some(Situation::Timeout),
            "unreachable" => Some(match self.unreachable {
                Some(UnreachableReason::NoProgress | UnreachableReason::GapsUnsettled) => {
                    Situation::GaveUp
                }
                Some(UnreachableReason::GoalBlocked) => Situation::GoalBlocked,
                _ => Situation::Unreachable,
            }),
            _ => Some(Situation::Aborted),
        }
    }

    /// The status word: the situation's, or `reached`.
    pub fn word(&self) -> &'static str {
        self.situation().map_or("reached", Situation::word)
    }

    /// The sentence, or `None` for a reached goal.
    pub fn why(&self) -> Option<String> {
        let here = at(self.at);
        let to_goal_m = (self.goal.x_m - self.at.x_m).hypot(self.goal.y_m - self.at.y_m);
        Some(match self.situation()? {
            Situation::GaveUp if self.unreachable == Some(UnreachableReason::GapsUnsettled) => {
                format!(
                    "gave up at {here} after {} plans: the gaps that tentative marks close were \
                     visited and swept without settling whether the way is open \
                     (the evidence map: docs/mapping.md)",
                    self.plans_here
                )
            }
            Situation::GaveUp if self.no_start => format!(
                "gave up at {here} after {} plans from the same place: obstacles lie within the \
                 robot radius ({:.2} m) all round, so no plan could start there, even after a \
                 full standing sweep",
                self.plans_here, self.radius_m
            ),
            Situation::GaveUp => format!(
                "gave up at {here} after {} plans from the same place: none took the robot more \
                 than {:.2} m away, even after a full standing sweep there",
                self.plans_here, self.stall_distance_m
            ),
            Situation::GoalBlocked => format!(
                "the goal {} lies in an obstacle the sonar found, grown by the robot radius \
                 {:.2} m (seen from {here})",
                at(self.goal),
                self.radius_m
            ),
            Situation::Unreachable => format!(
                "no path leads from {here} to the goal {} on the map the sonar built: the goal \
                 is walled in",
                at(self.goal)
            ),
            Situation::Collision => format!(
                "the robot's body touched an obstacle of {} at {here} (overlap up to {:.3} m)",
                self.real.as_deref().unwrap_or("the real world"),
                -self.clearance_m
            ),
            Situation::Timeout => format!(
                "the time limit of {} s ran out at {here}, {to_goal_m:.2} m from the goal",
                self.time_limit_s
            ),
            Situation::Aborted => {
                let by = if self.interrupted {
                    "Ctrl-C on this host".to_string()
                } else {
                    match self.device {
                        StopCause::None => match &self.plan_error {
                            Some(e) => format!("the device: its planner failed ({e})"),
                            None => "the device".to_string(),
                        },
                        StopCause::Host => "a host's AbortMission".to_string(),
                        cause => format!("the device's failsafe ({cause})"),
                    }
                };
                format!("the mission was aborted at {here}: stopped by {by}")
            }
            // Found before anything ran (crate::sim::start, OffMap): not a mission's end.
            Situation::StartBlocked | Situation::OutOfBounds => return None,
        })
    }
}

/// Plans in a row, counting back from the last, asked for within `radius_m` of `at`.
pub fn plans_here(plan_positions: &[PointM], at: PointM, radius_m: f32) -> u32 {
    plan_positions
        .iter()
        .rev()
        .take_while(|p| (p.x_m - at.x_m).hypot(p.y_m - at.y_m) < radius_m)
        .count() as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    fn end(status: &str) -> MissionEnd<'_> {
        MissionEnd {
            status,
            unreachable: None,
            device: StopCause::None,
            interrupted: false,
            at: PointM::new(3.1, 4.25),
            goal: PointM::new(6.1, 8.25),
            radius_m: 0.4,
            plans_here: 12,
            stall_distance_m: 0.1,
            clearance_m: -0.012,
            real: Some("b.da".into()),
            time_limit_s: 30.0,
            plan_error: None,
            no_start: false,
        }
    }

    #[test]
    fn every_situation_has_one_word_one_exit_status_and_the_help_lists_both() {
        let mut words: Vec<_> = Situation::ALL.iter().map(|s| s.word()).collect();
        words.sort();
        words.dedup();
        assert_eq!(words.len(), Situation::ALL.len());
        for s in Situation::ALL {
            assert_eq!(Situation::of_word(s.word()), Some(s));
            let code = s.ending().code();
            let line = crate::exit::HELP
                .lines()
                .find(|l| l.trim_start().starts_with(&format!("{code} ")))
                .unwrap_or_else(|| panic!("no help line for {code}"));
            // The help's words for it (README shows the help: its wording stays).
            let spaced = s.word().replace('_', " ");
            let said = match s {
                Situation::StartBlocked | Situation::GoalBlocked => "start/goal blocked",
                _ => spaced.as_str(),
            };
            assert!(line.contains(said), "{s:?} ({said}): {line}");
        }
    }

    #[test]
    fn a_mission_end_has_the_word_and_the_sentence_of_its_situation() {
        let mut e = end("unreachable");
        e.unreachable = Some(UnreachableReason::NoProgress);
        assert_eq!(e.word(), "gave_up");
        assert_eq!(
            e.why().unwrap(),
            "gave up at (3.10, 4.25) after 12 plans from the same place: none took the robot \
             more than 0.10 m away, even after a full standing sweep there"
        );
        e.no_start = true;
        assert_eq!(
            e.why().unwrap(),
            "gave up at (3.10, 4.25) after 12 plans from the same place: obstacles lie within \
             the robot radius (0.40 m) all round, so no plan could start there, even after a \
             full standing sweep"
        );
        e.no_start = false;
        e.unreachable = Some(UnreachableReason::GoalBlocked);
        assert_eq!(e.word(), "goal_blocked");
        assert!(e
            .why()
            .unwrap()
            .starts_with("the goal (6.10, 8.25) lies in an obstacle"));
        e.unreachable = Some(UnreachableReason::NoPath);
        assert_eq!(e.word(), "unreachable");
        let t = end("timeout");
        assert_eq!(
            t.why().unwrap(),
            "the time limit of 30 s ran out at (3.10, 4.25), 5.00 m from the goal"
        );
        let c = end("collision");
        assert_eq!(
            c.why().unwrap(),
            "the robot's body touched an obstacle of b.da at (3.10, 4.25) (overlap up to 0.012 m)"
        );
        let mut a = end("aborted");
        a.device = StopCause::LinkLost;
        assert_eq!(a.word(), "aborted");
        assert_eq!(
            a.why().unwrap(),
            "the mission was aborted at (3.10, 4.25): stopped by the device's failsafe (link lost)"
        );
        a.interrupted = true;
        assert!(a.why().unwrap().ends_with("stopped by Ctrl-C on this host"));
        assert_eq!(end("reached").why(), None);
        assert_eq!(end("reached").word(), "reached");
        // An outside stop wins over the mission's own status.
        let mut r = end("reached");
        r.device = StopCause::Host;
        assert_eq!(r.word(), "aborted");
    }

    #[test]
    fn plans_from_the_same_place_are_counted_back_from_the_last() {
        let p = |x, y| PointM::new(x, y);
        let plans = [p(0.0, 0.0), p(3.0, 4.0), p(3.05, 4.0), p(3.0, 4.05)];
        assert_eq!(plans_here(&plans, p(3.0, 4.0), 0.1), 3);
        assert_eq!(plans_here(&plans, p(9.0, 9.0), 0.1), 0);
        let off = OffMap {
            params: "g.par".into(),
            which: "goal",
            point: p(7.0, 7.0),
            size: "5x5".into(),
        };
        assert_eq!(off.why(), "the goal (7.00, 7.00) lies off the 5 x 5 m map");
        assert_eq!(
            off.to_string(),
            "g.par: the goal (7, 7) lies off the 5x5 m map"
        );
    }
}
