//! Obstacle polygons and the seed's text formats: `.da` (environment) and `.par` (parameters).
//!
//! Both formats are whitespace-separated numbers read with `fscanf` in the seed, so tokens may
//! share lines or be spread over several. The readers here take the text as `&str`, keep line
//! numbers for errors, and never trust a count: a count larger than the capacity is refused
//! before anything is read, so an absurd file cannot make them loop or allocate.
//!
//! `.par`: robot radius (m), speed (m/s), initial heading (degrees), start x y, goal x y.
//!
//! `.da`: number of obstacles; then per obstacle its number of vertices and the vertices x y in
//! metres.
//!
//! ```
//! use twil_core::world::{parse_da, parse_par, Obstacles};
//! let params = parse_par("0.4 0.2 90\n1.5 1.5\n13.5 13.0\n").unwrap();
//! assert_eq!(params.goal.x_m, 13.5);
//! let mut obstacles = Obstacles::new();
//! parse_da("1\n3 0 0  1 0\n0.5 1\n", &mut obstacles).unwrap();
//! assert_eq!(obstacles.len(), 1);
//! assert_eq!(obstacles.polygon(0).unwrap().len(), 3);
//! let err = parse_da("1\n3 0 0 1 zero 0.5 1\n", &mut obstacles).unwrap_err();
//! assert_eq!(err.line, 2);
//! assert_eq!(err.to_string(), "line 2: field `vertex y` of obstacle 1: `zero` is not a number");
//! ```

use core::fmt;

use heapless::{String, Vec};

use crate::geom::PointM;
use crate::robot::RobotConfig;

/// Largest number of obstacle polygons in one [`Obstacles`] set.
pub const MAX_POLYGONS: usize = 128;
/// Largest number of vertices, all polygons together, in one [`Obstacles`] set.
pub const MAX_VERTICES: usize = 1024;
/// Characters of an offending token kept in a [`ParseError`].
pub const TOKEN_CAPACITY: usize = 24;

/// What was wrong with a value.
#[derive(Clone, Debug, PartialEq)]
pub enum ParseErrorKind {
    /// The text ended where a value was expected.
    Missing,
    /// The token is not a number (or not a finite one).
    NotANumber(String<TOKEN_CAPACITY>),
    /// The number is outside the accepted range.
    OutOfRange {
        /// The token as written.
        value: String<TOKEN_CAPACITY>,
        /// What the range is, in words.
        expected: &'static str,
    },
    /// A count asks for more than the capacity.
    TooMany {
        /// The count read.
        count: u64,
        /// The capacity left.
        capacity: usize,
    },
    /// Extra tokens after the last expected value.
    Trailing(String<TOKEN_CAPACITY>),
}

/// A reading error: where (line, field, obstacle) and what.
#[derive(Clone, Debug, PartialEq)]
pub struct ParseError {
    /// 1-based line of the offending token (the last line when the text ended early).
    pub line: u32,
    /// Name of the field being read.
    pub field: &'static str,
    /// 1-based obstacle number, for `.da` fields inside an obstacle.
    pub obstacle: Option<u32>,
    /// What went wrong.
    pub kind: ParseErrorKind,
}

impl fmt::Display for ParseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "line {}: field `{}`", self.line, self.field)?;
        if let Some(o) = self.obstacle {
            write!(f, " of obstacle {o}")?;
        }
        match &self.kind {
            ParseErrorKind::Missing => write!(f, ": the file ends before this value"),
            ParseErrorKind::NotANumber(t) => write!(f, ": `{t}` is not a number"),
            ParseErrorKind::OutOfRange { value, expected } => {
                write!(f, ": `{value}` is out of range (expected {expected})")
            }
            ParseErrorKind::TooMany { count, capacity } => {
                write!(
                    f,
                    ": {count} is more than the {capacity} this build can hold"
                )
            }
            ParseErrorKind::Trailing(t) => write!(f, ": unexpected `{t}` after the last value"),
        }
    }
}

impl core::error::Error for ParseError {}

/// A whitespace tokenizer that knows the line of each token.
#[derive(Clone, Debug)]
pub struct Tokens<'a> {
    rest: &'a str,
    line: u32,
}

impl<'a> Tokens<'a> {
    /// Tokens of `text`, starting at line 1.
    pub fn new(text: &'a str) -> Self {
        Self {
            rest: text,
            line: 1,
        }
    }

    /// The line of the last token returned (or where the text ended).
    pub fn line(&self) -> u32 {
        self.line
    }

    /// The next token and its line.
    pub fn next_token(&mut self) -> Option<(&'a str, u32)> {
        // Newlines count only when a token follows them, so that "the file ends here" errors
        // name the last line of the file, not the empty one after its final newline.
        let mut newlines = 0;
        loop {
            let c = self.rest.chars().next()?;
            if c == '\n' {
                newlines += 1;
            }
            if c.is_whitespace() {
                self.rest = &self.rest[c.len_utf8()..];
            } else {
                break;
            }
        }
        self.line += newlines;
        let end = self
            .rest
            .find(char::is_whitespace)
            .unwrap_or(self.rest.len());
        let (token, rest) = self.rest.split_at(end);
        self.rest = rest;
        Some((token, self.line))
    }

    fn error(
        &self,
        field: &'static str,
        obstacle: Option<u32>,
        kind: ParseErrorKind,
    ) -> ParseError {
        ParseError {
            line: self.line,
            field,
            obstacle,
            kind,
        }
    }

    /// The next token as a finite `f32`.
    pub fn f32(&mut self, field: &'static str, obstacle: Option<u32>) -> Result<f32, ParseError> {
        let Some((token, _)) = self.next_token() else {
            return Err(self.error(field, obstacle, ParseErrorKind::Missing));
        };
        match token.parse::<f32>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(self.error(field, obstacle, ParseErrorKind::NotANumber(clip(token)))),
        }
    }

    /// The next token as a count no larger than `capacity`.
    pub fn count(
        &mut self,
        field: &'static str,
        obstacle: Option<u32>,
        capacity: usize,
    ) -> Result<usize, ParseError> {
        let Some((token, _)) = self.next_token() else {
            return Err(self.error(field, obstacle, ParseErrorKind::Missing));
        };
        match token.parse::<u64>() {
            Ok(n) if n as u128 <= capacity as u128 => Ok(n as usize),
            Ok(n) => Err(self.error(
                field,
                obstacle,
                ParseErrorKind::TooMany { count: n, capacity },
            )),
            Err(_) if token.parse::<i64>().is_ok() => Err(self.error(
                field,
                obstacle,
                ParseErrorKind::OutOfRange {
                    value: clip(token),
                    expected: "a count of 0 or more",
                },
            )),
            Err(_) => Err(self.error(field, obstacle, ParseErrorKind::NotANumber(clip(token)))),
        }
    }

    /// Fail if any token is left.
    pub fn finish(&mut self, field: &'static str) -> Result<(), ParseError> {
        match self.next_token() {
            None => Ok(()),
            Some((token, _)) => Err(self.error(field, None, ParseErrorKind::Trailing(clip(token)))),
        }
    }
}

/// The first [`TOKEN_CAPACITY`] bytes of a token (cut at a character boundary), for messages.
fn clip(token: &str) -> String<TOKEN_CAPACITY> {
    let mut s = String::new();
    for c in token.chars() {
        if s.push(c).is_err() {
            break;
        }
    }
    s
}

/// The mission parameters of a `.par` file.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Params {
    /// Planning radius of the robot, metres (obstacles are grown by it).
    pub robot_radius_m: f32,
    /// Cruise speed, metres per second.
    pub speed_m_s: f32,
    /// Initial heading, degrees, counter-clockwise from +x.
    pub initial_heading_deg: f32,
    /// Start position, metres.
    pub start: PointM,
    /// Goal position, metres.
    pub goal: PointM,
}

/// Read a `.par` text.
///
/// The radius must lie in `[0, 10]` m and the speed above 0 and at most the default robot's
/// safe speed ([`crate::robot::RobotConfig::max_safe_speed_m_s`], 0.365 m/s); anything after
/// the seven values is an error. [`parse_par_for`] also checks the radius against a robot's
/// sonar.
pub fn parse_par(text: &str) -> Result<Params, ParseError> {
    parse_par_inner(text, None)
}

/// [`parse_par`] for a mission of `robot`: the speed at most `robot.max_safe_speed_m_s()`,
/// the radius within [`crate::limits::check_planning_radius_m`] (0.31 m to the sonar
/// range minus 0.4 m); the error names the line and the bound.
pub fn parse_par_for(text: &str, robot: &RobotConfig) -> Result<Params, ParseError> {
    parse_par_inner(text, Some(robot))
}

/// The safe speed rule in words (see [`RobotConfig::max_safe_speed_m_s`]).
const SPEED_RULE: &str =
    "above 0 and at most the robot's safe speed, 0.364 m/s for the Twil robot; see docs/simulate.md";
/// The safe radius rule in words (see [`RobotConfig::max_safe_planning_radius_m`]).
const RADIUS_RULE: &str = "the sonar's shortest range plus 0.05 m up to its range minus 0.4 m: 0.31 to 1.1 m with the seed's sonar; see docs/simulate.md";

fn parse_par_inner(text: &str, robot: Option<&RobotConfig>) -> Result<Params, ParseError> {
    let mut t = Tokens::new(text);
    let robot_radius_m = ranged(&mut t, "robot radius", 0.0, 10.0, "0 to 10 m")?;
    if let Some(robot) = robot {
        if let Err(e) = crate::limits::check_planning_radius_m(robot, robot_radius_m) {
            return Err(t.error("robot radius", None, unsafe_kind(e, RADIUS_RULE)));
        }
    }
    let speed_m_s = t.f32("speed", None)?;
    let speed_robot = robot.unwrap_or(&RobotConfig::DEFAULT);
    if let Err(e) = crate::limits::check_speed_m_s(speed_robot, speed_m_s) {
        return Err(t.error("speed", None, unsafe_kind(e, SPEED_RULE)));
    }
    let initial_heading_deg = t.f32("initial angle", None)?;
    let start = PointM::new(t.f32("start x", None)?, t.f32("start y", None)?);
    let goal = PointM::new(t.f32("goal x", None)?, t.f32("goal y", None)?);
    t.finish("goal y")?;
    Ok(Params {
        robot_radius_m,
        speed_m_s,
        initial_heading_deg,
        start,
        goal,
    })
}

/// The value (as `f32` prints it) with the safe range in words: the bound is a property of the
/// robot (see [`crate::limits`]), so the words give the rule and the default robot's figure.
fn unsafe_kind(e: crate::limits::LimitError, expected: &'static str) -> ParseErrorKind {
    let mut value = String::new();
    let _ = core::fmt::write(&mut value, format_args!("{}", e.value));
    ParseErrorKind::OutOfRange { value, expected }
}

fn ranged(
    t: &mut Tokens<'_>,
    field: &'static str,
    min: f32,
    max: f32,
    expected: &'static str,
) -> Result<f32, ParseError> {
    let v = t.f32(field, None)?;
    if v < min || v > max {
        let mut value = String::new();
        let _ = core::fmt::write(&mut value, format_args!("{v}"));
        return Err(t.error(field, None, ParseErrorKind::OutOfRange { value, expected }));
    }
    Ok(v)
}

/// A set of obstacle polygons in one flat vertex pool: up to `V` vertices and `P` polygons.
///
/// A polygon is a closed outline (the last vertex joins the first). Two-vertex polygons are
/// segments (walls), as in seed 000's files.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PolygonSet<const V: usize, const P: usize> {
    vertices: Vec<PointM, V>,
    /// End (exclusive) of each polygon in `vertices`.
    ends: Vec<u16, P>,
}

/// The obstacle set used by the host tools and the `.da` reader.
pub type Obstacles = PolygonSet<MAX_VERTICES, MAX_POLYGONS>;

/// Why a polygon could not be added.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PolygonSetError {
    /// No room for another polygon.
    TooManyPolygons {
        /// Polygon capacity.
        capacity: usize,
    },
    /// No room for the vertices.
    TooManyVertices {
        /// Vertex capacity left.
        capacity_left: usize,
    },
    /// A polygon needs at least one vertex.
    Empty,
}

impl core::fmt::Display for PolygonSetError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            PolygonSetError::TooManyPolygons { capacity } => {
                write!(f, "no room for another polygon (capacity {capacity})")
            }
            PolygonSetError::TooManyVertices { capacity_left } => write!(
                f,
                "no room for the vertices ({capacity_left} vertices left)"
            ),
            PolygonSetError::Empty => write!(f, "a polygon needs at least one vertex"),
        }
    }
}

impl core::error::Error for PolygonSetError {}

impl<const V: usize, const P: usize> PolygonSet<V, P> {
    /// An empty set.
    pub const fn new() -> Self {
        Self {
            vertices: Vec::new(),
            ends: Vec::new(),
        }
    }

    /// Number of polygons.
    pub fn len(&self) -> usize {
        self.ends.len()
    }

    /// `true` when there is no polygon.
    pub fn is_empty(&self) -> bool {
        self.ends.is_empty()
    }

    /// Total vertices stored.
    pub fn vertex_count(&self) -> usize {
        self.vertices.len()
    }

    /// Remove every polygon.
    pub fn clear(&mut self) {
        self.vertices.clear();
        self.ends.clear();
    }

    /// Vertices of polygon `i`.
    pub fn polygon(&self, i: usize) -> Option<&[PointM]> {
        let end = *self.ends.get(i)? as usize;
        let start = if i == 0 { 0 } else { self.ends[i - 1] as usize };
        self.vertices.get(start..end)
    }

    /// All polygons in order.
    pub fn iter(&self) -> impl Iterator<Item = &[PointM]> + '_ {
        (0..self.len()).filter_map(move |i| self.polygon(i))
    }

    /// Append a polygon. On error the set is unchanged.
    pub fn push(&mut self, vertices: &[PointM]) -> Result<(), PolygonSetError> {
        if vertices.is_empty() {
            return Err(PolygonSetError::Empty);
        }
        if self.ends.is_full() {
            return Err(PolygonSetError::TooManyPolygons { capacity: P });
        }
        let left = V - self.vertices.len();
        if vertices.len() > left || self.vertices.len() + vertices.len() > u16::MAX as usize {
            return Err(PolygonSetError::TooManyVertices {
                capacity_left: left,
            });
        }
        // Both checks passed: these cannot fail.
        let _ = self.vertices.extend_from_slice(vertices);
        let _ = self.ends.push(self.vertices.len() as u16);
        Ok(())
    }
}

/// Read a `.da` text into `obstacles`, replacing what it held. On error `obstacles` is left as
/// it was before the call.
pub fn parse_da<const V: usize, const P: usize>(
    text: &str,
    obstacles: &mut PolygonSet<V, P>,
) -> Result<(), ParseError> {
    let mut t = Tokens::new(text);
    let mut out = PolygonSet::<V, P>::new();
    let count = t.count("obstacle count", None, P)?;
    for o in 0..count {
        let number = Some(o as u32 + 1);
        let left = V - out.vertex_count();
        let n = t.count("vertex count", number, left)?;
        if n == 0 {
            return Err(t.error(
                "vertex count",
                number,
                ParseErrorKind::OutOfRange {
                    value: clip("0"),
                    expected: "at least 1 vertex",
                },
            ));
        }
        let first = out.vertex_count();
        for _ in 0..n {
            let x = t.f32("vertex x", number)?;
            let y = t.f32("vertex y", number)?;
            // Capacity was checked against the count above.
            let _ = out.vertices.push(PointM::new(x, y));
        }
        let _ = first;
        let _ = out.ends.push(out.vertices.len() as u16);
    }
    t.finish("last vertex")?;
    *obstacles = out;
    Ok(())
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::string::ToString;

    #[test]
    fn reads_the_office_world() {
        let text = include_str!("../../worlds/office.da");
        let mut o = Obstacles::new();
        parse_da(text, &mut o).unwrap();
        assert_eq!(o.len(), 9);
        assert_eq!(o.polygon(8).unwrap()[1], PointM::new(7.0, 2.5));
    }

    #[test]
    fn tokens_may_share_or_split_lines() {
        let mut a = Obstacles::new();
        let mut b = Obstacles::new();
        parse_da("1 2 0 0 1 1", &mut a).unwrap();
        parse_da("1\n2\n0\n0\n\n1\r\n1\n", &mut b).unwrap();
        assert_eq!(a, b);
    }

    #[test]
    fn absurd_counts_are_refused_at_once() {
        let mut o = Obstacles::new();
        parse_da("1 1 5 5", &mut o).unwrap();
        let e = parse_da("99999999999999999999", &mut o).unwrap_err();
        assert!(matches!(
            e.kind,
            ParseErrorKind::NotANumber(_) | ParseErrorKind::TooMany { .. }
        ));
        let e = parse_da("2\n1000000 0 0", &mut o).unwrap_err();
        assert_eq!((e.line, e.obstacle), (2, Some(1)));
        assert!(matches!(
            e.kind,
            ParseErrorKind::TooMany { count: 1000000, .. }
        ));
        let e = parse_da("-3", &mut o).unwrap_err();
        assert!(matches!(e.kind, ParseErrorKind::OutOfRange { .. }));
        // Nothing already stored was lost.
        assert_eq!(o.len(), 1);
    }

    #[test]
    fn errors_name_line_field_and_value() {
        let mut o = Obstacles::new();
        let e = parse_da("1\n2\n0 0\n1 nan\n", &mut o).unwrap_err();
        assert_eq!(
            e.to_string(),
            "line 4: field `vertex y` of obstacle 1: `nan` is not a number"
        );
        let e = parse_da("2\n2\n0 0\n1 1\n", &mut o).unwrap_err();
        assert_eq!(e.kind, ParseErrorKind::Missing);
        assert_eq!(e.field, "vertex count");
        let e = parse_par("0.4 0.2 0 1 1 2").unwrap_err();
        assert_eq!(
            (e.field, e.kind.clone()),
            ("goal y", ParseErrorKind::Missing)
        );
        let e = parse_par("0.4 0.2 0\n1 1\n2\n").unwrap_err();
        assert_eq!(
            (e.line, e.field),
            (3, "goal y"),
            "the last line, not the one after it"
        );
        let e = parse_par("-0.4 0.2 0 1 1 2 2").unwrap_err();
        assert!(e.to_string().contains("robot radius"), "{e}");
        let e = parse_par("0.4 0.2 0 1 1 2 2 7").unwrap_err();
        assert!(matches!(e.kind, ParseErrorKind::Trailing(_)));
        let long = "x".repeat(100);
        let e = parse_par(&long).unwrap_err();
        assert!(matches!(e.kind, ParseErrorKind::NotANumber(ref t) if t.len() == TOKEN_CAPACITY));
    }

    #[test]
    fn polygon_set_keeps_contents_on_overflow() {
        let mut s = PolygonSet::<4, 2>::new();
        s.push(&[PointM::new(0.0, 0.0), PointM::new(1.0, 0.0)])
            .unwrap();
        assert_eq!(
            s.push(&[PointM::default(); 3]),
            Err(PolygonSetError::TooManyVertices { capacity_left: 2 })
        );
        s.push(&[PointM::default(); 2]).unwrap();
        assert_eq!(
            s.push(&[PointM::default()]),
            Err(PolygonSetError::TooManyPolygons { capacity: 2 })
        );
        assert_eq!(s.len(), 2);
        assert_eq!(s.vertex_count(), 4);
    }
}
