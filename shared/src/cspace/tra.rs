//! The `.TRA` path file of seed 000 (appendices A.3 and B.3).
//!
//! Line 1: the input `.ROB` file's name; line 2: the minima of the two joint variables; line 3:
//! their increments; then one line `i j` per corner point of the path, start first, as map
//! indices. `%` starts a comment.
//!
//! **Indices are 1-based**, as in the thesis: index 1 is the minimum. The thesis' navigation
//! path (B.3) starts at `61 21` and ends at `161 36` with minima `-180 -75` and increments
//! `2 2`; read 1-based these are the round configurations (-60, -35) and (140, -5), read
//! 0-based they would be (-58, -33) and (142, -3). [`Trajectory::to_map_indices`] converts to
//! the 0-based indices of [`super::map::ConfigMap`].
//!
//! ```
//! use twil_core::cspace::tra::Trajectory;
//! let t = Trajectory::parse("nav.ROB\n-180 -75\n2 2\n61 21 % start\n161 36\n").unwrap();
//! assert_eq!(t.value(0), Some([-60.0, -35.0]));
//! let mut text = String::new();
//! t.write(&mut text).unwrap();
//! assert_eq!(Trajectory::parse(&text).unwrap(), t);
//! ```

use core::fmt;

use heapless::Vec;

use super::map::{name_of, Name, MAX_AXIS_CELLS};
use super::search::MAX_PATH_POINTS;
use super::text::{clip_fmt, FileError, Lexer, Place};
use crate::world::ParseErrorKind;

// The step bound's message spells the number out (a `&'static str`).
const _: () = assert!(MAX_AXIS_CELLS == 4096);

/// A path in map indices with the header that gives them meaning.
#[derive(Clone, Debug, PartialEq)]
pub struct Trajectory {
    /// Name of the input `.ROB` file.
    pub name: Name,
    /// Value of index 1 of each joint.
    pub min: [f32; 2],
    /// Increment of each joint, above 0.
    pub increments: [f32; 2],
    /// Corner points, 1-based indices as written in the file.
    pub points: Vec<[i32; 2], MAX_PATH_POINTS>,
}

impl Trajectory {
    /// A trajectory from 0-based map indices (as [`super::search::SearchReport::path`]).
    pub fn from_map_indices(
        name: &str,
        min: [f32; 2],
        increments: [f32; 2],
        path: &[[i32; 2]],
    ) -> Self {
        let mut points = Vec::new();
        for p in path.iter().take(MAX_PATH_POINTS) {
            let _ = points.push([p[0].saturating_add(1), p[1].saturating_add(1)]);
        }
        Self {
            name: name_of(name),
            min,
            increments,
            points,
        }
    }

    /// The points as 0-based map indices.
    pub fn to_map_indices(&self) -> Vec<[i32; 2], MAX_PATH_POINTS> {
        self.points
            .iter()
            .map(|p| [p[0].saturating_sub(1), p[1].saturating_sub(1)])
            .collect()
    }

    /// Joint values of point `k`.
    pub fn value(&self, k: usize) -> Option<[f32; 2]> {
        let p = self.points.get(k)?;
        Some([
            self.min[0] + (p[0] as i64 - 1) as f32 * self.increments[0],
            self.min[1] + (p[1] as i64 - 1) as f32 * self.increments[1],
        ])
    }

    /// Read a `.TRA` text. At least one point is required.
    pub fn parse(text: &str) -> Result<Self, FileError> {
        let mut l = Lexer::new(text);
        let (name, min, increments) = l.grid_header()?;
        let mut points: Vec<[i32; 2], MAX_PATH_POINTS> = Vec::new();
        loop {
            let place = Place::PathPoint(points.len() as u32 + 1);
            let mut probe = l.clone();
            if probe.next_token().is_none() {
                break;
            }
            let i = l.i32("index of joint 1", place)?;
            let i_line = l.line();
            let j = l.i32("index of joint 2", place)?;
            // A step longer than a map axis is no path of ours (a wrapping joint's steps stay
            // within one turn), and checking it would trace billions of cells: refuse it.
            if let Some(prev) = points.last() {
                for (k, (field, v)) in [("index of joint 1", i), ("index of joint 2", j)]
                    .into_iter()
                    .enumerate()
                {
                    if (v as i64 - prev[k] as i64).abs() > MAX_AXIS_CELLS as i64 {
                        return Err(FileError {
                            line: if k == 0 { i_line } else { l.line() },
                            field,
                            place,
                            kind: ParseErrorKind::OutOfRange {
                                value: clip_fmt(format_args!("{v}")),
                                expected: "at most 4096 cells from the previous point",
                            },
                        });
                    }
                }
            }
            if points.push([i, j]).is_err() {
                return Err(l.error(
                    "index of joint 1",
                    place,
                    ParseErrorKind::TooMany {
                        count: MAX_PATH_POINTS as u64 + 1,
                        capacity: MAX_PATH_POINTS,
                    },
                ));
            }
        }
        if points.is_empty() {
            return Err(l.error(
                "index of joint 1",
                Place::PathPoint(1),
                ParseErrorKind::Missing,
            ));
        }
        Ok(Self {
            name: name_of(name),
            min,
            increments,
            points,
        })
    }

    /// Write the `.TRA` text.
    pub fn write(&self, out: &mut impl fmt::Write) -> fmt::Result {
        writeln!(out, "{} % input file", self.name)?;
        writeln!(out, "{} {} % minima (index 1)", self.min[0], self.min[1])?;
        writeln!(
            out,
            "{} {} % increments",
            self.increments[0], self.increments[1]
        )?;
        for (k, p) in self.points.iter().enumerate() {
            let note = if k == 0 {
                " % start"
            } else if k + 1 == self.points.len() {
                " % goal"
            } else {
                ""
            };
            writeln!(out, "{} {}{note}", p[0], p[1])?;
        }
        writeln!(out, "% end of the path")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const NAV_TRA: &str = include_str!("../../../worlds/seed000-nav.TRA");

    #[test]
    fn the_thesis_path_reads() {
        let t = Trajectory::parse(NAV_TRA).unwrap();
        assert_eq!(t.name.as_str(), "ex\\nav.ROB");
        assert_eq!(t.points.len(), 14);
        assert_eq!(t.value(13), Some([140.0, -5.0]));
        assert_eq!(t.to_map_indices()[0], [60, 20]);
    }

    #[test]
    fn malformed_paths() {
        let e = Trajectory::parse("n\n0 0\n1 1\n3 x\n").unwrap_err();
        assert_eq!((e.line, e.field), (4, "index of joint 2"));
        assert_eq!(e.place, Place::PathPoint(1));
        let e = Trajectory::parse("n\n0 0\n1 1\n3 4\n5\n").unwrap_err();
        assert_eq!(e.place, Place::PathPoint(2));
        assert!(matches!(e.kind, ParseErrorKind::Missing));
        let e = Trajectory::parse("n\n0 0\n1 0\n").unwrap_err();
        assert_eq!(e.field, "increment of joint 2");
        let e = Trajectory::parse("n\n0 0\n1 1\n").unwrap_err();
        assert!(matches!(e.kind, ParseErrorKind::Missing));
        assert!(Trajectory::parse("").is_err());
    }

    #[test]
    fn far_steps_are_refused_and_extreme_indices_do_not_overflow() {
        // Checking a 4-billion-cell step would take seconds: refused with its line and field.
        let e = Trajectory::parse("n\n0 0\n1 1\n1 1\n2 1\n% far\n3 -2147483648\n").unwrap_err();
        assert_eq!(
            (e.line, e.field, e.place),
            (7, "index of joint 2", Place::PathPoint(3))
        );
        assert!(matches!(e.kind, ParseErrorKind::OutOfRange { .. }));
        let e = Trajectory::parse("n\n0 0 1 1 1 1 4098 1").unwrap_err();
        assert_eq!(e.field, "index of joint 1");
        assert!(Trajectory::parse("n\n0 0 1 1 1 1 4097 1").is_ok());
        let t = Trajectory::parse("n\n0 0 1 1 -2147483648 2147483647").unwrap();
        assert_eq!(t.value(0), Some([-2147483649.0, 2147483646.0]));
        assert_eq!(t.to_map_indices()[0], [i32::MIN, 2147483646]);
    }
}
