//! A mission whose start puts the robot's body inside an obstacle of the real world gets the
//! same answer from every command: `start_blocked`, exit status 3, as `twil plan` says of a
//! start inside a grown obstacle (issue 26), with the sentence of crate::answer; a start or
//! goal off the map likewise gets `out_of_bounds` ([`answer_off_map`]), where it used to be
//! an error (exit 1). Nothing runs: before this check `twil simulate` reported a `collision`
//! after 0.00 m and `twil mission --remote sim` printed `unreachable` and exited 4.

use std::path::Path;

use serde_json::json;
use twil_core::control::Pose;
use twil_core::geom::PointM;
use twil_core::plant::Plant;
use twil_core::robot::RobotConfig;
use twil_core::world::Obstacles;

/// The body at the start, when it overlaps an obstacle of `real`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StartBlocked {
    /// Where the centre is, metres.
    pub start: PointM,
    /// The body's clearance there, metres (negative: overlap).
    pub clearance_m: f32,
}

/// `Some` when the robot's body (its physical radius) at `start` overlaps an edge of an
/// obstacle of `real`. A polygon is its outline, as for `twil plan` and the simulator's
/// collision test: a start inside a closed polygon is a robot in a room drawn as one polygon
/// (docs/formats.md), not a blocked start.
pub fn start_blocked(robot: &RobotConfig, start: PointM, real: &Obstacles) -> Option<StartBlocked> {
    let plant = Plant::new(
        robot,
        Pose {
            x_m: start.x_m,
            y_m: start.y_m,
            heading_rad: 0.0,
        },
    );
    let clearance_m = plant.clearance_m(real);
    (clearance_m < 0.0).then_some(StartBlocked { start, clearance_m })
}

impl StartBlocked {
    /// The sentence that says why (crate::answer: `the start (X, Y) lies in an obstacle …`).
    pub fn why(&self, real: &Path) -> String {
        format!(
            "the start {} lies in an obstacle of {}: the robot's body overlaps it by {:.3} m; \
             nothing ran",
            crate::answer::at(self.start),
            crate::answer::file_name(real),
            -self.clearance_m
        )
    }

    /// The summary line: the status word first, as every mission's line.
    pub fn words(&self, real: &Path) -> String {
        format!("start_blocked: {}", self.why(real))
    }

    /// The `--json` line.
    pub fn json(&self, real: &Path) -> serde_json::Value {
        json!({
            "status": "start_blocked",
            // Every end says why (crate::stop_cause); here nothing ran.
            "stop_cause": "start_blocked",
            "distance_m": 0.0,
            "min_clearance_m": ((self.clearance_m as f64) * 1000.0).round() / 1000.0,
            "why": self.why(real),
        })
    }
}

/// A start or goal off the map, the answer of `twil simulate` and `twil mission`:
/// `out_of_bounds`, exit status 3, nothing ran (as `twil plan` says `out_of_bounds`). Prints
/// the summary line or the `--json` line and returns the ending.
pub fn answer_off_map(off: &crate::answer::OffMap, as_json: bool) -> crate::exit::Ending {
    let why = format!("{}, as {} gives it; nothing ran", off.why(), off.params);
    if as_json {
        println!(
            "{}",
            json!({
                "status": "out_of_bounds",
                "stop_cause": "out_of_bounds",
                "distance_m": 0.0,
                "why": why,
            })
        );
    } else {
        println!("out_of_bounds: {why}");
    }
    crate::exit::Ending::NoPath
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(x0: f32, y0: f32, side_m: f32) -> Obstacles {
        let mut o = Obstacles::new();
        o.push(&[
            PointM::new(x0, y0),
            PointM::new(x0 + side_m, y0),
            PointM::new(x0 + side_m, y0 + side_m),
            PointM::new(x0, y0 + side_m),
        ])
        .unwrap();
        o
    }

    #[test]
    fn a_body_over_an_edge_is_blocked_and_one_inside_a_room_is_not() {
        let robot = RobotConfig::default(); // body radius 0.30 m
        let block = square(1.0, 1.0, 1.0);
        // Inside the outline, 0.5 m from every edge: a room drawn as one polygon.
        assert_eq!(start_blocked(&robot, PointM::new(1.5, 1.5), &block), None);
        let over = start_blocked(&robot, PointM::new(0.8, 1.5), &block).unwrap();
        assert!((over.clearance_m + 0.1).abs() < 1e-4, "{over:?}");
        let b = Path::new("worlds/b.da");
        assert_eq!(
            over.words(b),
            "start_blocked: the start (0.80, 1.50) lies in an obstacle of b.da: the robot's \
             body overlaps it by 0.100 m; nothing ran"
        );
        assert_eq!(over.json(b)["status"], "start_blocked");
        assert_eq!(over.json(b)["min_clearance_m"], -0.1);
        assert_eq!(over.json(b)["why"], over.why(b));
        assert_eq!(start_blocked(&robot, PointM::new(0.5, 1.5), &block), None);
    }
}
