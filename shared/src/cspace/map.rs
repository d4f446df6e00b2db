//! The configuration map (seed 000 §2.3, §3.2) and its `.MAP` text file.
//!
//! One bit per discretized pair of joint values, set when the arm collides there, kept in
//! twil-core's bit-packed [`Grid`]: column `i` (grid `x`) is joint 1's value
//! `min₁ + i·Δ₁`, line `j` (grid `y`) is joint 2's value `min₂ + j·Δ₂`.
//!
//! **Size.** A joint with limits `[min, max]` and increment `Δ` gets `floor((max - min)/Δ) + 1`
//! values: both limits are sampled when `Δ` divides the range, and no value beyond `max` is
//! ever used. A rotational joint whose limits span a whole turn wraps: it gets `360/Δ` values
//! (`Δ` must divide 360), and the last is the neighbour of the first.
//!
//! **Construction** (§2.3): for each value of joint 1, arm 1 alone is tested against the
//! obstacles; if it collides the whole column is marked (letter `A` in the file), otherwise arm 2
//! is tested for every value of joint 2 (letter `B`). Each polygon pair is first screened by its
//! bounding box (§4.3.1).
//!
//! **`.MAP` file**: line 1 the input file's name, line 2 the two minima, line 3 the two
//! increments, line 4 the number of values of joint 1 and of joint 2 (`NC NL`); `%` comments may
//! follow these values. Then `NL` lines of `NC` characters, the first for joint 2's minimum: a
//! space is a free configuration, any other character a collision (`A`: arm 1, `B`: arm 2).
//! Trailing spaces may be missing. After the rows only blank or `%` lines may follow.
//!
//! ```
//! use twil_core::cspace::{map::ConfigMap, rob::parse_rob};
//! // A one-unit arm sliding along x from 0 to 10 then along y; a wall at x = 5.
//! let robot = parse_rob("1 2 5 -1 5 1  2 P 0 10 0 0  P 0 2 90 1 1 0 0").unwrap();
//! let map = ConfigMap::build(&robot, [1.0, 1.0]).unwrap();
//! assert_eq!(map.size(), (11, 3));
//! assert!(map.blocked(5, 0) && !map.blocked(4, 0));
//! let mut text = String::new();
//! map.write_map("wall.ROB", &mut text).unwrap();
//! let (name, back) = ConfigMap::parse_map(&text, [false, false]).unwrap();
//! assert_eq!((name.as_str(), &back), ("wall.ROB", &map));
//! ```

use core::fmt;

use heapless::{String, Vec};

use super::geometry::{bounding_box, boxes_overlap, polygons_intersect, Frame, WorkPoint};
use super::rob::{Joint, Polygon, Robot, MAX_OBSTACLE_POLYGONS};
use super::text::{clip_fmt, readable, FileError, Lexer, Place};
use crate::grid::{words_for_cells, Grid, GridGeometry};
use crate::math;
use crate::world::ParseErrorKind;

/// Most cells in one configuration map (16 KiB of bits).
pub const MAX_MAP_CELLS: usize = 131_072;
/// Most values of one joint.
pub const MAX_AXIS_CELLS: usize = 4096;
/// Characters kept of the input file name written in `.MAP` and `.TRA` headers.
pub const NAME_CAPACITY: usize = 64;

/// The bit map type.
pub type MapBits = Grid<{ words_for_cells(MAX_MAP_CELLS) }>;

/// The sampling of one joint variable.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Axis {
    /// Value of index 0 (degrees or workspace units).
    pub min: f32,
    /// Step between consecutive indices, above 0.
    pub increment: f32,
    /// Number of values.
    pub cells: u16,
    /// `true` when index `cells` is index 0 again (a full-turn rotational joint).
    pub wraps: bool,
}

impl Axis {
    /// The sampling of `joint` with `increment` (see the module doc for the count).
    pub fn for_joint(joint: &Joint, increment: f32, number: u8) -> Result<Axis, MapError> {
        if !(increment.is_finite() && increment > 0.0) {
            return Err(MapError::BadIncrement {
                joint: number,
                increment,
            });
        }
        let wraps = joint.wraps();
        let steps = if wraps {
            360.0 / increment
        } else {
            (joint.max - joint.min) / increment
        };
        let too_many = |values: Option<u32>| MapError::TooManyValues {
            joint: number,
            values,
            min: joint.min,
            max: joint.max,
            increment,
            wraps,
            line: joint.limit_lines[1],
            field: joint.limit_fields()[1],
        };
        if steps.is_nan() || steps >= MAX_AXIS_CELLS as f32 {
            // Counted only while f32 holds every integer; beyond, "more than" says enough.
            return Err(too_many(if steps < 16_777_216.0 {
                Some(steps as u32 + u32::from(!wraps))
            } else {
                None
            }));
        }
        let cells = if wraps {
            let n = math::floor(steps + 0.5);
            if math::abs(n * increment - 360.0) > 1e-3 * increment || n < 2.0 {
                return Err(MapError::WrapIncrement {
                    joint: number,
                    increment,
                });
            }
            n as u32
        } else {
            math::floor(steps + 1e-4) as u32 + 1
        };
        if cells as usize > MAX_AXIS_CELLS {
            return Err(too_many(Some(cells)));
        }
        Ok(Axis {
            min: joint.min,
            increment,
            cells: cells as u16,
            wraps,
        })
    }

    /// The joint value of `index` (any integer: for a wrapping joint it may leave the first turn).
    pub fn value(&self, index: i32) -> f32 {
        self.min + index as f32 * self.increment
    }

    /// The index nearest to `value`, if it lies on the map (wrapped into the first turn for a
    /// wrapping joint). Values up to half an increment beyond the ends are accepted.
    pub fn index_of(&self, value: f32) -> Option<i32> {
        if !value.is_finite() {
            return None;
        }
        let k = math::floor((value - self.min) / self.increment + 0.5);
        if k.is_nan() || math::abs(k) >= 1.0e7 {
            return None;
        }
        let k = k as i32;
        let n = self.cells as i32;
        if self.wraps {
            Some(k.rem_euclid(n))
        } else if (0..n).contains(&k) {
            Some(k)
        } else {
            None
        }
    }

    /// `index` brought onto the map (wrapped for a wrapping joint), or `None` if outside.
    pub fn normalize(&self, index: i32) -> Option<i32> {
        let n = self.cells as i32;
        if self.wraps {
            Some(index.rem_euclid(n))
        } else if (0..n).contains(&index) {
            Some(index)
        } else {
            None
        }
    }
}

/// Why a map could not be made.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum MapError {
    /// An increment is not a finite number above 0.
    BadIncrement {
        /// Joint number, 1 or 2.
        joint: u8,
        /// The increment given.
        increment: f32,
    },
    /// The increment of a wrapping joint does not divide 360°.
    WrapIncrement {
        /// Joint number, 1 or 2.
        joint: u8,
        /// The increment given, degrees.
        increment: f32,
    },
    /// One joint would get more than [`MAX_AXIS_CELLS`] values.
    TooManyValues {
        /// Joint number, 1 or 2.
        joint: u8,
        /// Values it would need; `None` when too many to count exactly.
        values: Option<u32>,
        /// The joint's limits, as read.
        min: f32,
        /// Upper limit.
        max: f32,
        /// The increment given.
        increment: f32,
        /// `true` for a full-turn joint, whose count is `360 / increment`.
        wraps: bool,
        /// `.ROB` line of the upper limit (0: not from a file).
        line: u32,
        /// `.ROB` field of the upper limit.
        field: &'static str,
    },
    /// The map would have more than [`MAX_MAP_CELLS`] cells.
    TooManyCells {
        /// Values of joint 1 and of joint 2 (each within [`MAX_AXIS_CELLS`]).
        values: [u16; 2],
        /// `.ROB` lines of the upper limits of joint 1 and joint 2 (0: not from a file).
        lines: [u32; 2],
        /// `.ROB` fields of those limits.
        fields: [&'static str; 2],
    },
}

impl fmt::Display for MapError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            MapError::BadIncrement { joint, increment } => write!(
                f,
                "increment {} of joint {joint} is not a number above 0",
                readable(increment)
            ),
            MapError::WrapIncrement { joint, increment } => write!(
                f,
                "joint {joint} turns a full circle, so its increment must divide 360, not {}",
                readable(increment)
            ),
            MapError::TooManyValues {
                joint,
                values,
                min,
                max,
                increment,
                wraps,
                line,
                field,
            } => {
                if line > 0 {
                    write!(f, "line {line}: ")?;
                }
                write!(f, "field `{field}` of joint {joint}: ")?;
                if wraps {
                    write!(f, "a full turn ({} to {})", readable(min), readable(max))?;
                    write!(f, " in steps of {} needs ", readable(increment))?;
                } else {
                    write!(f, "the limits {} to {}", readable(min), readable(max))?;
                    write!(f, " in steps of {} need ", readable(increment))?;
                }
                match values {
                    Some(n) => write!(f, "{n} values, more than the {MAX_AXIS_CELLS}")?,
                    None => write!(f, "more than the {MAX_AXIS_CELLS} values")?,
                }
                write!(
                    f,
                    " this build holds; use a larger increment or narrower limits"
                )
            }
            MapError::TooManyCells {
                values,
                lines,
                fields,
            } => {
                if lines[0] > 0 && lines[1] > 0 {
                    write!(f, "lines {} and {}: ", lines[0], lines[1])?;
                }
                write!(
                    f,
                    "fields `{}` of joint 1 and `{}` of joint 2: the map would need {} x {} = {} cells, more than the {MAX_MAP_CELLS} this build holds; use larger increments or narrower limits",
                    fields[0],
                    fields[1],
                    values[0],
                    values[1],
                    values[0] as u32 * values[1] as u32
                )
            }
        }
    }
}

impl core::error::Error for MapError {}

/// What occupies a configuration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Occupancy {
    /// No collision.
    Free,
    /// Arm 1 collides (whatever joint 2 does).
    Arm1,
    /// Arm 2 collides.
    Arm2,
}

/// The configuration map: which joint-value pairs collide.
#[derive(Clone, Debug, PartialEq)]
pub struct ConfigMap {
    axes: [Axis; 2],
    bits: MapBits,
    arm1_columns: [u32; MAX_AXIS_CELLS / 32],
}

/// The input file name of a `.MAP` or `.TRA` header.
pub type Name = String<NAME_CAPACITY>;

/// `name` cut to [`NAME_CAPACITY`] bytes at a character boundary, without the whitespace the
/// cut may leave at its end (the readers trim the name, so it would not read back the same).
pub fn name_of(name: &str) -> Name {
    let mut s = Name::new();
    for c in name.chars() {
        if s.push(c).is_err() {
            break;
        }
    }
    while s.ends_with(char::is_whitespace) {
        s.pop();
    }
    s
}

/// The obstacles' polygons with their bounding boxes.
type Boxed = Vec<(WorkPoint, WorkPoint), MAX_OBSTACLE_POLYGONS>;

fn transformed(poly: &Polygon, frame: &Frame) -> Polygon {
    let mut out = Polygon::new();
    for &p in poly {
        // Same capacity as the input.
        let _ = out.push(frame.apply(p));
    }
    out
}

/// `true` when the arm's polygons, placed by `frame`, touch any obstacle.
pub fn arm_collides(robot: &Robot, joint: &Joint, frame: &Frame) -> bool {
    let mut boxes = Boxed::new();
    for o in &robot.obstacles {
        let _ = boxes.push(bounding_box(o).unwrap_or_default());
    }
    arm_collides_boxed(robot, &boxes, joint, frame)
}

fn arm_collides_boxed(robot: &Robot, boxes: &Boxed, joint: &Joint, frame: &Frame) -> bool {
    for poly in &joint.polygons {
        let world = transformed(poly, frame);
        let Some(bb) = bounding_box(&world) else {
            continue;
        };
        for (obstacle, obb) in robot.obstacles.iter().zip(boxes.iter()) {
            if !obstacle.is_empty()
                && boxes_overlap(bb, *obb)
                && polygons_intersect(&world, obstacle)
            {
                return true;
            }
        }
    }
    false
}

/// The frames of arm 1 and arm 2 for joint values `q`.
pub fn arm_frames(robot: &Robot, q: [f32; 2]) -> [Frame; 2] {
    let f1 = robot.joints[0].frame(q[0]);
    let f2 = f1.then_inner(&robot.joints[1].frame(q[1]));
    [f1, f2]
}

/// Where the configuration `q` collides (arm 1 first, as the map is built).
pub fn occupancy_at(robot: &Robot, q: [f32; 2]) -> Occupancy {
    let [f1, f2] = arm_frames(robot, q);
    if arm_collides(robot, &robot.joints[0], &f1) {
        Occupancy::Arm1
    } else if arm_collides(robot, &robot.joints[1], &f2) {
        Occupancy::Arm2
    } else {
        Occupancy::Free
    }
}

impl ConfigMap {
    /// An all-free map with the given sampling.
    pub fn empty(axes: [Axis; 2]) -> Result<Self, MapError> {
        let too_many = MapError::TooManyCells {
            values: [axes[0].cells, axes[1].cells],
            lines: [0, 0],
            fields: ["values of joint 1", "values of joint 2"],
        };
        let cells = axes[0].cells as u64 * axes[1].cells as u64;
        if cells > MAX_MAP_CELLS as u64 {
            return Err(too_many);
        }
        let geometry = GridGeometry::new(axes[0].cells as u32, axes[1].cells as u32, 1.0)
            .map_err(|_| too_many)?;
        let bits = MapBits::new(geometry).map_err(|_| too_many)?;
        Ok(Self {
            axes,
            bits,
            arm1_columns: [0; MAX_AXIS_CELLS / 32],
        })
    }

    /// Build the map of `robot` with joint increments `increments` (§2.3).
    pub fn build(robot: &Robot, increments: [f32; 2]) -> Result<Self, MapError> {
        let axes = [
            Axis::for_joint(&robot.joints[0], increments[0], 1)?,
            Axis::for_joint(&robot.joints[1], increments[1], 2)?,
        ];
        // Too many cells is the joints' limits' doing (with the increments): name them.
        let mut map = Self::empty(axes).map_err(|e| match e {
            MapError::TooManyCells { values, .. } => MapError::TooManyCells {
                values,
                lines: robot.joints.each_ref().map(|j| j.limit_lines[1]),
                fields: robot.joints.each_ref().map(|j| j.limit_fields()[1]),
            },
            e => e,
        })?;
        let mut boxes = Boxed::new();
        for o in &robot.obstacles {
            let _ = boxes.push(bounding_box(o).unwrap_or_default());
        }
        let [j1, j2] = &robot.joints;
        for i in 0..axes[0].cells as i32 {
            let f1 = j1.frame(axes[0].value(i));
            if arm_collides_boxed(robot, &boxes, j1, &f1) {
                map.mark_arm1_column(i);
                continue;
            }
            for j in 0..axes[1].cells as i32 {
                let f2 = f1.then_inner(&j2.frame(axes[1].value(j)));
                if arm_collides_boxed(robot, &boxes, j2, &f2) {
                    map.bits.set_xy(i, j, true);
                }
            }
        }
        Ok(map)
    }

    fn mark_arm1_column(&mut self, i: i32) {
        if let Some(w) = self.arm1_columns.get_mut(i as usize / 32) {
            *w |= 1 << (i as usize % 32);
        }
        for j in 0..self.axes[1].cells as i32 {
            self.bits.set_xy(i, j, true);
        }
    }

    /// The sampling of joint 1 and joint 2.
    pub fn axes(&self) -> &[Axis; 2] {
        &self.axes
    }

    /// `(NC, NL)`: the number of values of joint 1 and of joint 2.
    pub fn size(&self) -> (u16, u16) {
        (self.axes[0].cells, self.axes[1].cells)
    }

    /// `true` when configuration `(i, j)` collides. Indices of a wrapping joint are taken modulo
    /// its count; other indices outside the map count as collisions.
    pub fn blocked(&self, i: i32, j: i32) -> bool {
        match (self.axes[0].normalize(i), self.axes[1].normalize(j)) {
            (Some(i), Some(j)) => self.bits.is_occupied_xy(i, j),
            _ => true,
        }
    }

    /// What occupies `(i, j)` (outside the map: [`Occupancy::Arm1`]).
    pub fn occupancy(&self, i: i32, j: i32) -> Occupancy {
        if !self.blocked(i, j) {
            return Occupancy::Free;
        }
        match self.axes[0].normalize(i) {
            Some(i) => {
                let w = self.arm1_columns.get(i as usize / 32).copied().unwrap_or(0);
                if (w >> (i as usize % 32)) & 1 == 1 {
                    Occupancy::Arm1
                } else {
                    Occupancy::Arm2
                }
            }
            None => Occupancy::Arm1,
        }
    }

    /// Number of free configurations.
    pub fn free_count(&self) -> usize {
        self.bits.geometry().cell_count() - self.bits.count_occupied()
    }

    /// Write the `.MAP` text (see the module doc); `name` is the input file's name.
    pub fn write_map(&self, name: &str, out: &mut impl fmt::Write) -> fmt::Result {
        let [a, b] = &self.axes;
        writeln!(
            out,
            "{} % input file",
            name_of(name.lines().next().unwrap_or(""))
        )?;
        writeln!(out, "{} {} % minima of the joint variables", a.min, b.min)?;
        writeln!(out, "{} {} % increments", a.increment, b.increment)?;
        writeln!(
            out,
            "{} {} % values of joint 1 (columns) and joint 2 (lines)",
            a.cells, b.cells
        )?;
        for j in 0..b.cells as i32 {
            for i in 0..a.cells as i32 {
                let c = match self.occupancy(i, j) {
                    Occupancy::Free => ' ',
                    Occupancy::Arm1 => 'A',
                    Occupancy::Arm2 => 'B',
                };
                out.write_char(c)?;
            }
            out.write_char('\n')?;
        }
        writeln!(out, "% end of the map")
    }

    /// Read a `.MAP` text; `wraps` says which joints wrap around (the file does not). Returns
    /// the input file name of the header and the map.
    pub fn parse_map(text: &str, wraps: [bool; 2]) -> Result<(Name, ConfigMap), FileError> {
        let mut l = Lexer::new(text);
        let (name, min, inc) = l.grid_header()?;
        let nc = l.count(
            "values of joint 1",
            Place::Top,
            1,
            MAX_AXIS_CELLS,
            "1 or more",
        )?;
        let nl = l.count(
            "values of joint 2",
            Place::Top,
            1,
            MAX_AXIS_CELLS,
            "1 or more",
        )?;
        if nc * nl > MAX_MAP_CELLS {
            return Err(l.error(
                "values of joint 2",
                Place::Top,
                ParseErrorKind::TooMany {
                    count: (nc * nl) as u64,
                    capacity: MAX_MAP_CELLS,
                },
            ));
        }
        let axes = [
            Axis {
                min: min[0],
                increment: inc[0],
                cells: nc as u16,
                wraps: wraps[0],
            },
            Axis {
                min: min[1],
                increment: inc[1],
                cells: nl as u16,
                wraps: wraps[1],
            },
        ];
        let mut map = ConfigMap::empty(axes).map_err(|_| {
            l.error(
                "values of joint 2",
                Place::Top,
                ParseErrorKind::TooMany {
                    count: (nc * nl) as u64,
                    capacity: MAX_MAP_CELLS,
                },
            )
        })?;
        l.skip_to_next_line();
        let mut arm1_seen = [false; MAX_AXIS_CELLS];
        for j in 0..nl {
            let place = Place::MapRow(j as u32 + 1);
            let Some((row, line)) = l.raw_line() else {
                return Err(l.error("map row", place, ParseErrorKind::Missing));
            };
            for (i, c) in row.chars().enumerate() {
                if i >= nc {
                    if row.chars().skip(nc).all(|c| c == ' ') {
                        break;
                    }
                    return Err(FileError {
                        line,
                        field: "map row",
                        place,
                        kind: ParseErrorKind::OutOfRange {
                            value: clip_fmt(format_args!("{} characters", row.chars().count())),
                            expected: "at most NC characters",
                        },
                    });
                }
                if c != ' ' {
                    map.bits.set_xy(i as i32, j as i32, true);
                    if c == 'A' {
                        if let Some(s) = arm1_seen.get_mut(i) {
                            *s = true;
                        }
                    }
                }
            }
        }
        for (i, seen) in arm1_seen.iter().enumerate().take(nc) {
            if *seen {
                if let Some(w) = map.arm1_columns.get_mut(i / 32) {
                    *w |= 1 << (i % 32);
                }
            }
        }
        l.finish("end of the map")?;
        Ok((name_of(name), map))
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::cspace::rob::parse_rob;
    use std::string::String as StdString;
    use std::string::ToString;

    const NAV: &str = include_str!("../../../worlds/seed000-nav.ROB");

    #[test]
    fn navigation_map_size_and_known_cells() {
        let robot = parse_rob(NAV).unwrap();
        let map = ConfigMap::build(&robot, [2.0, 2.0]).unwrap();
        // floor(345/2)+1 and floor(220/2)+1 values.
        assert_eq!(map.size(), (173, 111));
        // The thesis' start (-60, -35) and goal (140, -5) are free.
        let s = [
            map.axes()[0].index_of(-60.0).unwrap(),
            map.axes()[1].index_of(-35.0).unwrap(),
        ];
        assert_eq!(s, [60, 20]);
        assert!(!map.blocked(s[0], s[1]));
        let g = [
            map.axes()[0].index_of(140.0).unwrap(),
            map.axes()[1].index_of(-5.0).unwrap(),
        ];
        assert!(!map.blocked(g[0], g[1]));
        // The object sitting on obstacle 5 (x -18..30, y -100..0) collides.
        let c = [
            map.axes()[0].index_of(0.0).unwrap(),
            map.axes()[1].index_of(-50.0).unwrap(),
        ];
        assert_eq!(map.occupancy(c[0], c[1]), Occupancy::Arm2);
        // Every map cell agrees with a direct collision test.
        for i in 0..173 {
            for j in 0..111 {
                let q = [map.axes()[0].value(i), map.axes()[1].value(j)];
                assert_eq!(
                    map.blocked(i, j),
                    occupancy_at(&robot, q) != Occupancy::Free
                );
            }
        }
        assert!(map.blocked(-1, 0) && map.blocked(173, 0) && map.blocked(0, 111));
    }

    #[test]
    fn arm1_columns_and_round_trip() {
        // Rotational arm 1 of length 10 along its x axis, a post at (0, 10): arm 1 hits it near 90°.
        let robot = parse_rob(
            "1 4 -1 9  1 9  1 11  -1 11\n2\nR 10 0 180 1 2 0 0 -10 0\nR 5 -90 90 1 2 0 0 -5 0\n",
        )
        .unwrap();
        let map = ConfigMap::build(&robot, [10.0, 30.0]).unwrap();
        assert_eq!(map.size(), (19, 7));
        assert_eq!(map.occupancy(9, 3), Occupancy::Arm1);
        assert_eq!(map.occupancy(0, 3), Occupancy::Free);
        let mut text = StdString::new();
        map.write_map("post.ROB", &mut text).unwrap();
        let (name, back) = ConfigMap::parse_map(&text, [false, false]).unwrap();
        assert_eq!(name.as_str(), "post.ROB");
        assert_eq!(back, map);
        // Trailing spaces may be dropped by an editor.
        let trimmed: StdString = text
            .lines()
            .map(|l| std::format!("{}\n", l.trim_end()))
            .collect();
        let (_, back) = ConfigMap::parse_map(&trimmed, [false, false]).unwrap();
        assert_eq!(back, map);
    }

    #[test]
    fn full_turn_wraps_and_needs_a_dividing_increment() {
        let robot = parse_rob("0 2 R 10 -180 180 0 R 5 -90 90 0").unwrap();
        let map = ConfigMap::build(&robot, [10.0, 10.0]).unwrap();
        assert_eq!(map.size(), (36, 19));
        assert!(map.axes()[0].wraps);
        assert!(!map.blocked(-1, 0) && !map.blocked(36, 0));
        assert_eq!(map.axes()[0].index_of(172.0), Some(35));
        assert_eq!(map.axes()[0].index_of(181.0), Some(0));
        assert_eq!(
            ConfigMap::build(&robot, [7.0, 10.0]).unwrap_err(),
            MapError::WrapIncrement {
                joint: 1,
                increment: 7.0
            }
        );
        assert!(matches!(
            ConfigMap::build(&robot, [0.001, 10.0]).unwrap_err(),
            MapError::TooManyValues { joint: 1, .. }
        ));
        assert!(matches!(
            ConfigMap::build(&robot, [0.1, 0.1]).unwrap_err(),
            MapError::TooManyCells { .. }
        ));
        assert!(matches!(
            ConfigMap::build(&robot, [f32::NAN, 1.0]).unwrap_err(),
            MapError::BadIncrement { joint: 1, .. }
        ));
    }

    #[test]
    fn huge_limits_name_the_line_and_field_and_print_no_absurd_number() {
        let robot = parse_rob("0\n2\nP -1e30\n 1e30 0\n0\n% arm 2\nR 1\n-90 90\n0\n").unwrap();
        assert_eq!(robot.joints[0].limit_lines, [3, 4]);
        assert_eq!(robot.joints[1].limit_lines, [8, 8]);
        let e = ConfigMap::build(&robot, [2.0, 2.0]).unwrap_err();
        assert!(matches!(e, MapError::TooManyValues { values: None, .. }));
        assert_eq!(
            e.to_string(),
            "line 4: field `maximum length` of joint 1: the limits -1e30 to 1e30 in steps of 2 \
             need more than the 4096 values this build holds; use a larger increment or \
             narrower limits"
        );
        // A countable excess is counted; a full turn names its increment.
        let robot = parse_rob("0 2 R 1 -180 180 0 P 0\n5000 0 0").unwrap();
        let e = ConfigMap::build(&robot, [10.0, 1.0])
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("line 2: field `maximum length` of joint 2:"),
            "{e}"
        );
        assert!(e.contains("need 5001 values, more than the 4096"), "{e}");
        let e = ConfigMap::build(&robot, [1e-9, 1.0])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("joint 1: a full turn (-180 to 180) in steps of 1e-9 needs more than"),
            "{e}"
        );
        // Too many cells in all: both upper limits named.
        let robot = parse_rob("0 2 P 0 1000 0 0\nP 0\n1000 90 0").unwrap();
        let e = ConfigMap::build(&robot, [1.0, 1.0]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "lines 1 and 3: fields `maximum length` of joint 1 and `maximum length` of joint 2: \
             the map would need 1001 x 1001 = 1002001 cells, more than the 131072 this build \
             holds; use larger increments or narrower limits"
        );
        for m in [f32::MAX, 1e38] {
            let robot = parse_rob(&std::format!("0 2 P {} {m} 0 0 P 0 1 0 0", -m)).unwrap();
            let e = ConfigMap::build(&robot, [1e-30, 1.0])
                .unwrap_err()
                .to_string();
            assert!(
                !e.contains("18446744073709551615") && e.contains("more than"),
                "{e}"
            );
        }
    }

    #[test]
    fn malformed_map_files() {
        let bad = "n\n0 0\n1 1\n2 2\nxxx\n  \n";
        let e = ConfigMap::parse_map(bad, [false, false]).unwrap_err();
        assert_eq!((e.line, e.place), (5, Place::MapRow(1)));
        let e = ConfigMap::parse_map("n\n0 0\n1 -1\n2 2\n", [false, false]).unwrap_err();
        assert_eq!((e.line, e.field), (3, "increment of joint 2"));
        let e = ConfigMap::parse_map("n\n0 0\n1 1\n2 2\nx\n", [false, false]).unwrap_err();
        assert_eq!(e.place, Place::MapRow(2));
        assert!(matches!(e.kind, ParseErrorKind::Missing));
        let e = ConfigMap::parse_map("n\n0 0\n1 1\n2 1\nx\nmore\n", [false, false]).unwrap_err();
        assert!(matches!(e.kind, ParseErrorKind::Trailing(_)));
        let e = ConfigMap::parse_map("n\n0 0\n1 1\n4096 4096\n", [false, false]).unwrap_err();
        assert!(matches!(e.kind, ParseErrorKind::TooMany { .. }));
    }
}
