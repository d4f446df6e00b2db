//! The text conventions shared by the `.ROB`, `.MAP` and `.TRA` readers: `%` starts a comment
//! that runs to the end of the line, blank lines are ignored, values are whitespace separated.
//! Errors name the line, the field, where in the file the field belongs, and the offending value.

use core::fmt;

use heapless::String;

use crate::world::{ParseErrorKind, TOKEN_CAPACITY};

/// Where in a file a field belongs, for messages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Place {
    /// The header or a top-level value.
    Top,
    /// The `n`-th (1-based) polygon of the obstacle representation.
    Obstacle(u32),
    /// Joint / arm `n` (1-based), outside its polygons.
    Joint(u32),
    /// Polygon `polygon` of arm `arm` (both 1-based).
    ArmPolygon {
        /// Arm number, 1-based.
        arm: u32,
        /// Polygon number within the arm, 1-based.
        polygon: u32,
    },
    /// Row `n` (1-based, in file order) of a configuration map.
    MapRow(u32),
    /// Point `n` (1-based) of a path.
    PathPoint(u32),
}

impl fmt::Display for Place {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Place::Top => Ok(()),
            Place::Obstacle(n) => write!(f, " of obstacle polygon {n}"),
            Place::Joint(n) => write!(f, " of joint {n}"),
            Place::ArmPolygon { arm, polygon } => write!(f, " of polygon {polygon} of arm {arm}"),
            Place::MapRow(n) => write!(f, " of map row {n}"),
            Place::PathPoint(n) => write!(f, " of path point {n}"),
        }
    }
}

/// A reading error of a `.ROB`, `.MAP` or `.TRA` text: line, field, place and what was wrong.
///
/// The text readers do not know the file's name; the host prefixes it.
#[derive(Clone, Debug, PartialEq)]
pub struct FileError {
    /// 1-based line of the offending value (the last line when the text ended early).
    pub line: u32,
    /// Name of the field being read.
    pub field: &'static str,
    /// Which polygon, joint, row or point the field belongs to.
    pub place: Place,
    /// What went wrong.
    pub kind: ParseErrorKind,
}

impl fmt::Display for FileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "line {}: field `{}`{}",
            self.line, self.field, self.place
        )?;
        match &self.kind {
            ParseErrorKind::Missing => write!(f, ": the file ends before this value"),
            ParseErrorKind::NotANumber(t) => write!(f, ": `{}` is not a number", Escaped(t)),
            ParseErrorKind::OutOfRange { value, expected } => write!(
                f,
                ": `{}` is out of range (expected {expected})",
                Escaped(value)
            ),
            // A count too long for a u64 is stored as u64::MAX; its digits say nothing useful.
            ParseErrorKind::TooMany { count, capacity } if *count == u64::MAX => write!(
                f,
                ": the count is more than the {capacity} this build can hold"
            ),
            ParseErrorKind::TooMany { count, capacity } => write!(
                f,
                ": {count} is more than the {capacity} this build can hold"
            ),
            ParseErrorKind::Trailing(t) => {
                write!(f, ": unexpected `{}` after the last value", Escaped(t))
            }
        }
    }
}

impl core::error::Error for FileError {}

/// A value quoted from a file, written so that it cannot act on a terminal: control and other
/// non-printable characters (ESC, C1 controls, bidi overrides, ...) appear as `\u{1b}`-style
/// escapes, as [`char::escape_debug`] writes them. Quotes and backslashes stay as they are (a
/// Windows path such as `ex\nav.ROB` reads as written).
pub struct Escaped<'a>(pub &'a str);

impl fmt::Display for Escaped<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use fmt::Write as _;
        for c in self.0.chars() {
            if matches!(c, '\\' | '\'' | '"') {
                f.write_char(c)?;
            } else {
                for e in c.escape_debug() {
                    f.write_char(e)?;
                }
            }
        }
        Ok(())
    }
}

/// A number for a message: plain when of a readable size, otherwise in `1e30` notation, so
/// that a huge limit does not print as thirty digits.
pub(crate) fn readable(v: f32) -> Readable {
    Readable(v)
}

/// See [`readable`].
pub(crate) struct Readable(f32);

impl fmt::Display for Readable {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let a = self.0.abs();
        if a == 0.0 || (1e-3..1e7).contains(&a) {
            write!(f, "{}", self.0)
        } else {
            write!(f, "{:e}", self.0)
        }
    }
}

/// The first [`TOKEN_CAPACITY`] bytes of a token (cut at a character boundary), for messages.
pub(crate) fn clip(token: &str) -> String<TOKEN_CAPACITY> {
    let mut s = String::new();
    for c in token.chars() {
        if s.push(c).is_err() {
            break;
        }
    }
    s
}

/// A value formatted into a short string, for messages.
pub(crate) fn clip_fmt(args: fmt::Arguments<'_>) -> String<TOKEN_CAPACITY> {
    struct Clip(String<TOKEN_CAPACITY>);
    impl fmt::Write for Clip {
        fn write_str(&mut self, s: &str) -> fmt::Result {
            for c in s.chars() {
                if self.0.push(c).is_err() {
                    break;
                }
            }
            Ok(())
        }
    }
    let mut c = Clip(String::new());
    let _ = fmt::write(&mut c, args);
    c.0
}

/// A tokenizer that skips `%` comments and knows the line of each token.
#[derive(Clone, Debug)]
pub(crate) struct Lexer<'a> {
    text: &'a str,
    pos: usize,
    line: u32,
}

impl<'a> Lexer<'a> {
    pub(crate) fn new(text: &'a str) -> Self {
        Self {
            text,
            pos: 0,
            line: 1,
        }
    }

    fn rest(&self) -> &'a str {
        self.text.get(self.pos..).unwrap_or("")
    }

    /// Skip whitespace and comments, counting lines; stop before the next token (or at the end).
    fn skip_blank(&mut self) {
        loop {
            let rest = self.rest();
            let Some(c) = rest.chars().next() else {
                return;
            };
            if c == '\n' {
                self.line += 1;
                self.pos += 1;
            } else if c == '%' {
                self.pos += rest.find('\n').unwrap_or(rest.len());
            } else if c.is_whitespace() {
                self.pos += c.len_utf8();
            } else {
                return;
            }
        }
    }

    /// The next token and its line.
    pub(crate) fn next_token(&mut self) -> Option<(&'a str, u32)> {
        self.skip_blank();
        let rest = self.rest();
        if rest.is_empty() {
            return None;
        }
        let end = rest
            .find(|c: char| c.is_whitespace() || c == '%')
            .unwrap_or(rest.len());
        self.pos += end;
        Some((rest.get(..end).unwrap_or(""), self.line))
    }

    /// The rest of the next non-blank line, comment removed and trimmed (for a file name).
    pub(crate) fn next_line_text(&mut self) -> Option<(&'a str, u32)> {
        self.skip_blank();
        let rest = self.rest();
        if rest.is_empty() {
            return None;
        }
        let end = rest.find('\n').unwrap_or(rest.len());
        let line = rest.get(..end).unwrap_or("");
        self.pos += end;
        let text = line.split('%').next().unwrap_or("").trim();
        Some((text, self.line))
    }

    /// Drop what is left of the current line (normally a comment) and step to the next one.
    pub(crate) fn skip_to_next_line(&mut self) {
        let rest = self.rest();
        match rest.find('\n') {
            Some(i) => {
                self.pos += i + 1;
                self.line += 1;
            }
            None => self.pos = self.text.len(),
        }
    }

    /// The next raw line (without its end of line), and its number; `None` at the end.
    pub(crate) fn raw_line(&mut self) -> Option<(&'a str, u32)> {
        let rest = self.rest();
        if rest.is_empty() {
            return None;
        }
        let line = self.line;
        let (text, step) = match rest.find('\n') {
            Some(i) => (rest.get(..i).unwrap_or(""), i + 1),
            None => (rest, rest.len()),
        };
        self.pos += step;
        if step > text.len() {
            self.line += 1;
        }
        Some((text.strip_suffix('\r').unwrap_or(text), line))
    }

    /// The line the lexer is on.
    pub(crate) fn line(&self) -> u32 {
        self.line
    }

    pub(crate) fn error(
        &self,
        field: &'static str,
        place: Place,
        kind: ParseErrorKind,
    ) -> FileError {
        FileError {
            line: self.line,
            field,
            place,
            kind,
        }
    }

    /// The next token as a finite `f32`.
    pub(crate) fn f32(&mut self, field: &'static str, place: Place) -> Result<f32, FileError> {
        let Some((token, line)) = self.next_token() else {
            return Err(self.error(field, place, ParseErrorKind::Missing));
        };
        match token.parse::<f32>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(FileError {
                line,
                field,
                place,
                kind: ParseErrorKind::NotANumber(clip(token)),
            }),
        }
    }

    /// The next token as an `i32`.
    pub(crate) fn i32(&mut self, field: &'static str, place: Place) -> Result<i32, FileError> {
        let Some((token, line)) = self.next_token() else {
            return Err(self.error(field, place, ParseErrorKind::Missing));
        };
        match token.parse::<i32>() {
            Ok(v) => Ok(v),
            Err(_) => Err(FileError {
                line,
                field,
                place,
                kind: ParseErrorKind::NotANumber(clip(token)),
            }),
        }
    }

    /// The next token as a count in `min..=capacity`.
    pub(crate) fn count(
        &mut self,
        field: &'static str,
        place: Place,
        min: usize,
        capacity: usize,
        expected: &'static str,
    ) -> Result<usize, FileError> {
        let Some((token, line)) = self.next_token() else {
            return Err(self.error(field, place, ParseErrorKind::Missing));
        };
        let kind = match token.parse::<u64>() {
            Ok(n) if n as u128 > capacity as u128 => ParseErrorKind::TooMany { count: n, capacity },
            Ok(n) if (n as usize) < min => ParseErrorKind::OutOfRange {
                value: clip(token),
                expected,
            },
            Ok(n) => return Ok(n as usize),
            Err(_) if token.parse::<i64>().is_ok() => ParseErrorKind::OutOfRange {
                value: clip(token),
                expected,
            },
            // Digits beyond u64: a count, only far too large (see the Display of `TooMany`).
            Err(_) if !token.is_empty() && token.bytes().all(|b| b.is_ascii_digit()) => {
                ParseErrorKind::TooMany {
                    count: u64::MAX,
                    capacity,
                }
            }
            Err(_) => ParseErrorKind::NotANumber(clip(token)),
        };
        Err(FileError {
            line,
            field,
            place,
            kind,
        })
    }

    /// The header shared by `.MAP` and `.TRA` files: the input file name (line 1), the minima
    /// of both joints and their increments (each above 0).
    pub(crate) fn grid_header(&mut self) -> Result<(&'a str, [f32; 2], [f32; 2]), FileError> {
        let Some((name, _)) = self.next_line_text() else {
            return Err(self.error("input file name", Place::Top, ParseErrorKind::Missing));
        };
        let min = [
            self.f32("minimum of joint 1", Place::Top)?,
            self.f32("minimum of joint 2", Place::Top)?,
        ];
        let mut increments = [0.0; 2];
        for (k, field) in ["increment of joint 1", "increment of joint 2"]
            .into_iter()
            .enumerate()
        {
            let v = self.f32(field, Place::Top)?;
            if v <= 0.0 {
                return Err(self.error(
                    field,
                    Place::Top,
                    ParseErrorKind::OutOfRange {
                        value: clip_fmt(format_args!("{v}")),
                        expected: "a number above 0",
                    },
                ));
            }
            increments[k] = v;
        }
        Ok((name, min, increments))
    }

    /// Fail if any token is left.
    pub(crate) fn finish(&mut self, field: &'static str) -> Result<(), FileError> {
        match self.next_token() {
            None => Ok(()),
            Some((token, line)) => Err(FileError {
                line,
                field,
                place: Place::Top,
                kind: ParseErrorKind::Trailing(clip(token)),
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn comments_and_blank_lines_are_skipped_and_lines_counted() {
        let mut l = Lexer::new("% head\n\n 7 % seven\n8%x\n  9");
        assert_eq!(l.next_token(), Some(("7", 3)));
        assert_eq!(l.next_token(), Some(("8", 4)));
        assert_eq!(l.next_token(), Some(("9", 5)));
        assert_eq!(l.next_token(), None);
    }

    #[test]
    fn line_text_drops_the_comment() {
        let mut l = Lexer::new("\n  ex\\nav.ROB % name\n1");
        assert_eq!(l.next_line_text(), Some(("ex\\nav.ROB", 2)));
        assert_eq!(l.next_token(), Some(("1", 3)));
    }

    #[test]
    fn counts_are_checked() {
        let mut l = Lexer::new("3 -1 x 0");
        assert!(l.count("n", Place::Top, 1, 2, "1 to 2").is_err());
        let e = l.count("n", Place::Top, 1, 2, "1 to 2").unwrap_err();
        assert!(matches!(e.kind, ParseErrorKind::OutOfRange { .. }));
        let e = l.count("n", Place::Top, 1, 2, "1 to 2").unwrap_err();
        assert!(matches!(e.kind, ParseErrorKind::NotANumber(_)));
        let e = l.count("n", Place::Top, 1, 2, "1 to 2").unwrap_err();
        assert!(matches!(e.kind, ParseErrorKind::OutOfRange { .. }));
    }
}

#[cfg(test)]
mod message_tests {
    extern crate std;
    use crate::cspace::{map::ConfigMap, rob::parse_rob, tra::Trajectory};
    use std::string::ToString;

    /// No raw control character reaches a message, and the quoted value is escaped.
    fn assert_clean(msg: &str, escaped: &str) {
        assert!(!msg.chars().any(char::is_control), "{msg:?}");
        assert!(msg.contains(escaped), "{msg:?} lacks {escaped:?}");
    }

    #[test]
    fn values_quoted_from_files_are_escaped() {
        // ESC [ 2 J (clear screen) as a vertex count, a joint type and a path index.
        let e = parse_rob("1\n\u{1b}[2J\n").unwrap_err().to_string();
        assert_clean(&e, "`\\u{1b}[2J` is not a number");
        let e = parse_rob("0 2 \u{9b}31m 1 2 3").unwrap_err().to_string();
        assert_clean(&e, "`\\u{9b}31m` is out of range");
        let e = Trajectory::parse("n\n0 0\n1 1\n1 2\u{7}\n")
            .unwrap_err()
            .to_string();
        assert_clean(&e, "`2\\u{7}`");
        let e = ConfigMap::parse_map("n\n0 0\n1 1\n1 1\nx\n\u{202e}x\n", [false; 2])
            .unwrap_err()
            .to_string();
        assert_clean(&e, "\\u{202e}");
        assert!(!e.contains('\u{202e}'), "{e}");
        // Backslashes and quotes of ordinary values stay readable.
        let e = parse_rob("1 2 0 0 1 \"a\\b'").unwrap_err().to_string();
        assert!(e.contains("`\"a\\b'` is not a number"), "{e}");
    }

    #[test]
    fn a_long_value_is_clipped() {
        let long = "x".repeat(10_000);
        let e = parse_rob(&long).unwrap_err().to_string();
        assert!(e.len() < 120, "{e}");
    }

    #[test]
    fn a_count_beyond_u64_says_more_than() {
        let e = parse_rob("123456789012345678901234567890").unwrap_err();
        assert!(matches!(
            e.kind,
            crate::world::ParseErrorKind::TooMany { .. }
        ));
        assert_eq!(
            e.to_string(),
            "line 1: field `obstacle polygon count`: the count is more than the 64 this build can hold"
        );
    }
}

#[cfg(test)]
mod fuzz {
    use crate::cspace::{map::ConfigMap, rob::parse_rob, tra::Trajectory};
    use proptest::prelude::*;

    proptest! {
        /// No text makes a reader panic; it returns a value or an error.
        #[test]
        fn readers_never_panic(text in "[0-9 PRrpx%.\\n\\t-]{0,200}") {
            let _ = parse_rob(&text);
            let _ = Trajectory::parse(&text);
            let _ = ConfigMap::parse_map(&text, [false, true]);
        }

        #[test]
        fn readers_never_panic_on_any_unicode(text in "\\PC{0,120}") {
            let _ = parse_rob(&text);
            let _ = Trajectory::parse(&text);
            let _ = ConfigMap::parse_map(&text, [true, false]);
        }
    }
}
