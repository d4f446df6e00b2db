//! The `.ROB` file of seed 000 (appendices A.1 and B.1): obstacles and a two-joint arm.
//!
//! Values are whitespace separated; `%` starts a comment that runs to the end of the line. In
//! order:
//!
//! 1. the obstacle representation: a polygon count, then per polygon a vertex count and the
//!    vertices `x y` (world frame);
//! 2. the joint count (this planner takes exactly 2);
//! 3. per joint: its type (a word whose first letter is `R`/`r` for rotational or `P`/`p` for
//!    prismatic), its length and its angle, then the arm's representation (polygons in the
//!    arm's own frame, as for the obstacles; 0 polygons is allowed: an arm without volume).
//!    The varying value is given as its two limits `min max`, the fixed one as one number:
//!    a rotational joint has `length` then `min_deg max_deg`; a prismatic one has `min max`
//!    then `angle_deg`.
//!
//! Every polygon must be convex (§2.1); a non-convex shape is written as several polygons.
//!
//! ```
//! use twil_core::cspace::rob::{parse_rob, JointKind};
//! let text = "% one wall\n1\n2  -10 5  10 5\n2\nR 10 -90 90\n1\n2 0 0 -10 0\nP 0 4 0\n0\n";
//! let robot = parse_rob(text).unwrap();
//! assert_eq!(robot.joints[0].kind, JointKind::Rotational);
//! assert_eq!((robot.joints[1].min, robot.joints[1].max), (0.0, 4.0));
//! let err = parse_rob("1\n2 0 0 1 one\n").unwrap_err();
//! assert_eq!(err.to_string(), "line 2: field `vertex y` of obstacle polygon 1: `one` is not a number");
//! ```

use heapless::Vec;

use super::geometry::{is_convex, WorkPoint};
use super::text::{clip, clip_fmt, FileError, Lexer, Place};
use crate::world::ParseErrorKind;

/// Most vertices in one polygon.
pub const MAX_POLYGON_VERTICES: usize = 16;
/// Most polygons in the obstacle representation.
pub const MAX_OBSTACLE_POLYGONS: usize = 64;
/// Most polygons in one arm's representation.
pub const MAX_ARM_POLYGONS: usize = 8;

/// A convex polygon (or a segment, or a point): its vertices in order.
pub type Polygon = Vec<WorkPoint, MAX_POLYGON_VERTICES>;

/// Rotational or prismatic.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum JointKind {
    /// The joint turns the arm: the variable is the angle, degrees.
    Rotational,
    /// The joint slides the arm: the variable is the length, workspace units.
    Prismatic,
}

/// One joint and the arm it moves.
#[derive(Clone, Debug, PartialEq)]
pub struct Joint {
    /// Rotational or prismatic.
    pub kind: JointKind,
    /// Arm length for a rotational joint (for a prismatic one: unused, 0).
    pub length: f32,
    /// Fixed angle of a prismatic joint, degrees (for a rotational one: unused, 0).
    pub angle_deg: f32,
    /// Lower limit of the joint variable (degrees or workspace units).
    pub min: f32,
    /// Upper limit of the joint variable, above `min`.
    pub max: f32,
    /// The arm's polygons in its own frame (origin at the arm's far end, §2.2).
    pub polygons: Vec<Polygon, MAX_ARM_POLYGONS>,
    /// 1-based lines of `min` and `max` in the `.ROB` text (0 when not read from a file), so
    /// that a map too large for its limits can name them.
    pub limit_lines: [u32; 2],
}

impl Joint {
    /// `true` for a rotational joint whose limits span a whole turn: its map wraps around.
    pub fn wraps(&self) -> bool {
        self.kind == JointKind::Rotational && self.max - self.min >= 360.0 - 1e-3
    }

    /// The transform of this arm's frame for joint value `q` (degrees or units).
    pub fn frame(&self, q: f32) -> super::geometry::Frame {
        match self.kind {
            JointKind::Rotational => super::geometry::Frame::joint(q, self.length),
            JointKind::Prismatic => super::geometry::Frame::joint(self.angle_deg, q),
        }
    }

    /// Names of the `.ROB` fields of `min` and `max`, for messages.
    pub fn limit_fields(&self) -> [&'static str; 2] {
        match self.kind {
            JointKind::Rotational => ["minimum angle", "maximum angle"],
            JointKind::Prismatic => ["minimum length", "maximum length"],
        }
    }

    /// Unit of the joint variable, for messages and pictures.
    pub fn unit(&self) -> &'static str {
        match self.kind {
            JointKind::Rotational => "deg",
            JointKind::Prismatic => "units",
        }
    }
}

/// The whole `.ROB` content: obstacles and two joints.
#[derive(Clone, Debug, PartialEq)]
pub struct Robot {
    /// Obstacle polygons, world frame.
    pub obstacles: Vec<Polygon, MAX_OBSTACLE_POLYGONS>,
    /// Joint 1 (from the base) and joint 2.
    pub joints: [Joint; 2],
}

fn read_polygon(l: &mut Lexer<'_>, place: Place) -> Result<Polygon, FileError> {
    let n = l.count(
        "vertex count",
        place,
        1,
        MAX_POLYGON_VERTICES,
        "at least 1 vertex",
    )?;
    let count_line = l.line();
    let mut poly = Polygon::new();
    for _ in 0..n {
        let x = l.f32("vertex x", place)?;
        let y = l.f32("vertex y", place)?;
        // The count was checked against the capacity.
        let _ = poly.push(WorkPoint::new(x, y));
    }
    if !is_convex(&poly) {
        return Err(FileError {
            line: count_line,
            field: "vertex count",
            place,
            kind: ParseErrorKind::OutOfRange {
                value: clip_fmt(format_args!("{n} vertices")),
                expected: "a convex polygon; split it into convex ones",
            },
        });
    }
    Ok(poly)
}

fn read_limits(
    l: &mut Lexer<'_>,
    field_min: &'static str,
    field_max: &'static str,
    place: Place,
) -> Result<(f32, f32, [u32; 2]), FileError> {
    let min = l.f32(field_min, place)?;
    let min_line = l.line();
    let max = l.f32(field_max, place)?;
    let lines = [min_line, l.line()];
    if max <= min {
        return Err(l.error(
            field_max,
            place,
            ParseErrorKind::OutOfRange {
                value: clip_fmt(format_args!("{max}")),
                expected: "a maximum above the minimum",
            },
        ));
    }
    Ok((min, max, lines))
}

fn read_joint(l: &mut Lexer<'_>, number: u32) -> Result<Joint, FileError> {
    let place = Place::Joint(number);
    let Some((word, line)) = l.next_token() else {
        return Err(l.error("joint type", place, ParseErrorKind::Missing));
    };
    let kind = match word.chars().next() {
        Some('R' | 'r') => JointKind::Rotational,
        Some('P' | 'p') => JointKind::Prismatic,
        _ => {
            return Err(FileError {
                line,
                field: "joint type",
                place,
                kind: ParseErrorKind::OutOfRange {
                    value: clip(word),
                    expected: "a word starting with R (rotational) or P (prismatic)",
                },
            })
        }
    };
    let (length, angle_deg, min, max, limit_lines) = match kind {
        JointKind::Rotational => {
            let length = l.f32("length", place)?;
            let (min, max, lines) = read_limits(l, "minimum angle", "maximum angle", place)?;
            (length, 0.0, min, max, lines)
        }
        JointKind::Prismatic => {
            let (min, max, lines) = read_limits(l, "minimum length", "maximum length", place)?;
            let angle = l.f32("angle", place)?;
            (0.0, angle, min, max, lines)
        }
    };
    let count = l.count(
        "polygon count",
        place,
        0,
        MAX_ARM_POLYGONS,
        "0 or more polygons",
    )?;
    let mut polygons = Vec::new();
    for p in 0..count {
        let poly = read_polygon(
            l,
            Place::ArmPolygon {
                arm: number,
                polygon: p as u32 + 1,
            },
        )?;
        let _ = polygons.push(poly);
    }
    Ok(Joint {
        kind,
        length,
        angle_deg,
        min,
        max,
        polygons,
        limit_lines,
    })
}

/// Read a `.ROB` text. On error nothing is returned but the error, which names the line, the
/// field, the polygon or joint, and the offending value.
pub fn parse_rob(text: &str) -> Result<Robot, FileError> {
    let mut l = Lexer::new(text);
    let count = l.count(
        "obstacle polygon count",
        Place::Top,
        0,
        MAX_OBSTACLE_POLYGONS,
        "0 or more polygons",
    )?;
    let mut obstacles = Vec::new();
    for o in 0..count {
        let poly = read_polygon(&mut l, Place::Obstacle(o as u32 + 1))?;
        let _ = obstacles.push(poly);
    }
    let Some((token, line)) = l.next_token() else {
        return Err(l.error("joint count", Place::Top, ParseErrorKind::Missing));
    };
    if token != "2" {
        return Err(FileError {
            line,
            field: "joint count",
            place: Place::Top,
            kind: ParseErrorKind::OutOfRange {
                value: clip(token),
                expected: "2 (this planner handles two joints)",
            },
        });
    }
    let j1 = read_joint(&mut l, 1)?;
    let j2 = read_joint(&mut l, 2)?;
    l.finish("last polygon of arm 2")?;
    Ok(Robot {
        obstacles,
        joints: [j1, j2],
    })
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::string::ToString;

    const NAV: &str = include_str!("../../../worlds/seed000-nav.ROB");

    #[test]
    fn the_navigation_case_reads() {
        let r = parse_rob(NAV).unwrap();
        assert_eq!(r.obstacles.len(), 7);
        assert_eq!(r.obstacles[5].len(), 6);
        assert_eq!(r.joints[0].kind, JointKind::Prismatic);
        assert_eq!((r.joints[0].min, r.joints[0].max), (-180.0, 165.0));
        assert_eq!(r.joints[1].angle_deg, 90.0);
        assert!(r.joints[0].polygons.is_empty());
        assert_eq!(r.joints[1].polygons[0][1], WorkPoint::new(-24.0, 24.0));
        assert!(!r.joints[0].wraps());
    }

    #[test]
    fn errors_name_line_field_place_and_value() {
        let e = parse_rob("1\n3 0 0 1 0 0 1\n3\n").unwrap_err();
        assert_eq!(e.line, 3);
        assert_eq!(e.field, "joint count");
        let e = parse_rob("0\n2\nX 1 2 3\n").unwrap_err();
        assert_eq!(
            e.to_string(),
            "line 3: field `joint type` of joint 1: `X` is out of range (expected a word starting with R (rotational) or P (prismatic))"
        );
        let e = parse_rob("0\n2\nR 10\n 90 -90\n0\n").unwrap_err();
        assert_eq!((e.line, e.field), (4, "maximum angle"));
        let e = parse_rob("0 2 R 10 0 90 1 5 0 0 2 0 1 0.2 2 2 0 2 P 0 1 0 0").unwrap_err();
        assert_eq!(e.field, "vertex count");
        assert_eq!(e.place, Place::ArmPolygon { arm: 1, polygon: 1 });
        let e = parse_rob("0 2 R 10 0 90 0 P 0 1 0 0 junk").unwrap_err();
        assert!(matches!(e.kind, ParseErrorKind::Trailing(_)));
        let e = parse_rob("999999999999").unwrap_err();
        assert!(matches!(e.kind, ParseErrorKind::TooMany { .. }));
        let e = parse_rob("0 2 R 10 0 90 0 P 0 1 0").unwrap_err();
        assert!(matches!(e.kind, ParseErrorKind::Missing));
    }

    #[test]
    fn a_full_turn_wraps() {
        let r = parse_rob("0 2 Rot 10 -180 180 0 R 5 -90 90 0").unwrap();
        assert!(r.joints[0].wraps());
        assert!(!r.joints[1].wraps());
    }
}
