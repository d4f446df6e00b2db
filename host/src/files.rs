//! The one way the host reads an input file: a size cap per format, checked before reading, and
//! errors that name the file and quote nothing raw.
//!
//! Every reader of `twil` (`.da`, `.par`, saved map, `.ROB`, `.MAP`, `.TRA`) calls
//! [`read_bytes`] or [`read_text`] with the file's [`Format`]. The cap is checked twice: against
//! the length the file system reports, before anything is read, and while reading (at most
//! `cap + 1` bytes are read), since `/dev/zero`, pipes and other devices report no length.
//! The caps are a few times what the parsers' capacities can use, so a valid file never meets
//! them:
//!
//! | format | cap | what the parser can hold |
//! |---|---|---|
//! | `.da` | 4 MiB | 128 polygons, 1 024 vertices |
//! | `.par` | 64 KiB | 11 numbers |
//! | `.ROB` | 1 MiB | 80 polygons of 16 vertices (2 560 numbers) |
//! | `.MAP` | 4 MiB | 131 072 cells (each up to 4 UTF-8 bytes) in up to 4 096 rows |
//! | `.TRA` | 1 MiB | 512 points |
//! | robot file (`.toml`) | 256 KiB | 37 keys with comments (about 7 KiB) |
//! | saved map | `width × height` bytes | one byte per cell |
//!
//! A [`FileError`] reads `path: line N: ...` (or `path: ...` when the problem is the whole
//! file), then `; see docs/formats.md#da`, the section that describes the format; control and other non-printable characters, in the path or in the detail, appear as
//! `\u{1b}`-style escapes, so a hostile file cannot drive the terminal.

use std::fmt;
use std::io::Read;
use std::path::{Path, PathBuf};

/// What a file holds and the most bytes read of it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Format {
    /// The format's name in messages, with its article ("a .ROB file").
    pub name: &'static str,
    /// Largest accepted size, bytes.
    pub max_bytes: u64,
    /// Where the format is described, as errors cite it.
    pub doc: &'static str,
}

const MIB: u64 = 1024 * 1024;

/// `.da` environment (`twil plan`, `simulate`, `mission`).
pub const DA: Format = Format {
    name: "a .da file",
    max_bytes: 4 * MIB,
    doc: "docs/formats.md#da",
};
/// `.par` mission parameters.
pub const PAR: Format = Format {
    name: "a .par file",
    max_bytes: 64 * 1024,
    doc: "docs/formats.md#par",
};
/// `.ROB` obstacles and arm (`twil cspace --rob`).
pub const ROB: Format = Format {
    name: "a .ROB file",
    max_bytes: MIB,
    doc: "docs/formats.md#rob",
};
/// `.MAP` configuration map (`twil cspace --from-map`).
pub const MAP: Format = Format {
    name: "a .MAP file",
    max_bytes: 4 * MIB,
    doc: "docs/formats.md#map",
};
/// `.TRA` path (`twil cspace --compare`).
pub const TRA: Format = Format {
    name: "a .TRA file",
    max_bytes: MIB,
    doc: "docs/formats.md#tra",
};

/// Robot file (`--robot`, `twil robot init`): about 7 KiB when generated.
pub const ROBOT: Format = Format {
    name: "a robot file",
    max_bytes: 256 * 1024,
    doc: "docs/formats.md#robot-file",
};

/// Where the saved map (`twil plan --map`) is described.
pub const SAVED_MAP_DOC: &str = "docs/formats.md#saved-map";

/// A file could not be used: which file, which line (when known) and why.
#[derive(Debug, Clone, PartialEq)]
pub struct FileError {
    /// The file as given on the command line.
    pub path: PathBuf,
    /// 1-based line of the problem, when it is about a line.
    pub line: Option<u32>,
    /// What is wrong (already includes `line N: ` when `line` is set), escaped.
    pub detail: String,
    /// The description of the file's format (`docs/formats.md#da`), cited after the detail.
    pub see: Option<&'static str>,
}

impl fmt::Display for FileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: {}",
            printable(&self.path.display().to_string()),
            self.detail
        )?;
        match self.see {
            Some(doc) => write!(f, "; see {doc}"),
            None => Ok(()),
        }
    }
}

impl std::error::Error for FileError {}

impl FileError {
    /// An error about `path`; `detail` is escaped here.
    pub fn new(path: &Path, line: Option<u32>, detail: impl Into<String>) -> Self {
        Self {
            path: path.to_path_buf(),
            line,
            detail: printable(&detail.into()),
            see: None,
        }
    }

    /// This error, citing `doc` (e.g. [`DA`]`.doc`) as the description of the file's format.
    pub fn see(mut self, doc: &'static str) -> Self {
        self.see = Some(doc);
        self
    }

    /// A parse error at `line` of `text` (read from `path`); `detail` is the parser's message
    /// (`line N: field ...`). A parser that counts the newline ending the last line reports
    /// "the file ends before this value" one line after the last; such lines are brought back
    /// to the last line, in the number and in the message.
    pub fn at_line(path: &Path, text: &str, line: u32, detail: &str) -> Self {
        let last = text.lines().count().max(1) as u32;
        if line > last {
            let old = format!("line {line}:");
            let detail = match detail.strip_prefix(&old) {
                Some(rest) => format!("line {last}:{rest}"),
                None => detail.to_owned(),
            };
            return Self::new(path, Some(last), detail);
        }
        Self::new(path, Some(line), detail)
    }

    /// A problem not tied to a line of the file, e.g. a capacity its values exceed.
    pub fn whole(path: &Path, detail: impl fmt::Display) -> Self {
        Self::new(path, None, detail.to_string())
    }
}

/// `text` with control and other non-printable characters (ESC, C1 controls, bidi overrides,
/// ...) written as `\u{..}` escapes ([`char::escape_debug`]), so that a message is one readable
/// line that cannot act on a terminal. Backslashes and quotes stay as they are.
pub fn printable(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        if matches!(c, '\\' | '\'' | '"') {
            out.push(c);
        } else {
            out.extend(c.escape_debug());
        }
    }
    out
}

/// Read the bytes of `path`, at most `max_bytes` of them: a directory, an unreadable file or a
/// larger one is an error naming the file, its size (when the file system knows it) and the
/// cap, `what` naming the kind of file ("a .ROB file"). Nothing is read from a file whose
/// reported length is already too large.
pub fn read_capped(path: &Path, what: &str, max_bytes: u64) -> Result<Vec<u8>, FileError> {
    let too_large = |size: Option<u64>| {
        let size = match size {
            Some(n) => format!("is {n} bytes"),
            // A device or a pipe: its length is unknown, only that it goes on.
            None => "goes on beyond the cap".to_owned(),
        };
        FileError::new(
            path,
            None,
            format!("{size}, more than the {max_bytes} bytes allowed for {what}"),
        )
    };
    let meta = std::fs::metadata(path)
        .map_err(|e| FileError::new(path, None, format!("cannot open: {e}")))?;
    if meta.is_dir() {
        return Err(FileError::new(path, None, "is a directory, not a file"));
    }
    if meta.is_file() && meta.len() > max_bytes {
        return Err(too_large(Some(meta.len())));
    }
    let file = std::fs::File::open(path)
        .map_err(|e| FileError::new(path, None, format!("cannot open: {e}")))?;
    let mut bytes = Vec::new();
    file.take(max_bytes.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(|e| FileError::new(path, None, format!("cannot read: {e}")))?;
    if bytes.len() as u64 > max_bytes {
        // A regular file that grew while being read reports its new length.
        let size = std::fs::metadata(path)
            .ok()
            .filter(|m| m.is_file() && m.len() > max_bytes)
            .map(|m| m.len());
        return Err(too_large(size));
    }
    Ok(bytes)
}

/// [`read_capped`] with the cap of `format`.
pub fn read_bytes(path: &Path, format: Format) -> Result<Vec<u8>, FileError> {
    read_capped(path, format.name, format.max_bytes).map_err(|e| e.see(format.doc))
}

/// Read a UTF-8 text file of `format`. Invalid UTF-8 is an error naming the line and the byte
/// offset of the first bad byte.
pub fn read_text(path: &Path, format: Format) -> Result<String, FileError> {
    let bytes = read_bytes(path, format)?;
    String::from_utf8(bytes).map_err(|e| {
        let good = e.utf8_error().valid_up_to();
        let bytes = e.as_bytes();
        let line = bytes[..good].iter().filter(|b| **b == b'\n').count() as u32 + 1;
        let bad = bytes.get(good).copied().unwrap_or(0);
        FileError::new(
            path,
            Some(line),
            format!("line {line}: not text: byte 0x{bad:02x} at offset {good} is not UTF-8"),
        )
        .see(format.doc)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::{Duration, Instant};

    fn temp(name: &str, bytes: &[u8]) -> (tempfile::TempDir, PathBuf) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        (dir, path)
    }

    #[test]
    fn a_file_over_the_cap_is_refused_by_its_length_naming_size_and_cap() {
        let (_d, p) = temp("big.ROB", &vec![b' '; 2_000]);
        let e = read_capped(&p, "a .ROB file", 1_000).unwrap_err();
        assert_eq!(
            e.to_string(),
            format!(
                "{}: is 2000 bytes, more than the 1000 bytes allowed for a .ROB file",
                p.display()
            )
        );
        // At the cap exactly it is read.
        assert_eq!(read_capped(&p, "x", 2_000).unwrap().len(), 2_000);
    }

    #[test]
    fn an_endless_device_is_cut_off_at_the_cap_quickly() {
        let zero = Path::new("/dev/zero");
        if !zero.exists() {
            return;
        }
        for format in [DA, PAR, ROB, MAP, TRA] {
            let t = Instant::now();
            let e = read_text(zero, format).unwrap_err();
            assert!(t.elapsed() < Duration::from_secs(2), "{:?}", t.elapsed());
            assert_eq!(
                e.to_string(),
                format!(
                    "/dev/zero: goes on beyond the cap, more than the {} bytes allowed for {}; \
                     see {}",
                    format.max_bytes, format.name, format.doc
                )
            );
        }
    }

    #[test]
    fn non_utf8_names_line_and_offset() {
        let (_d, p) = temp("x.TRA", b"name\n0 0\n1 \xc3\x28 1\n");
        let e = read_text(&p, TRA).unwrap_err();
        assert_eq!(e.line, Some(3));
        assert!(
            e.to_string()
                .ends_with("x.TRA: line 3: not text: byte 0xc3 at offset 11 is not UTF-8; see docs/formats.md#tra"),
            "{e}"
        );
    }

    #[test]
    fn messages_escape_control_characters_in_detail_and_path() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a\u{1b}[31mb.ROB");
        let e = FileError::new(&p, Some(1), "line 1: `\u{1b}]0;x\u{7}` \u{9b}2J \u{202e}");
        let msg = e.to_string();
        assert!(
            !msg.chars().any(|c| c.is_control() || c == '\u{202e}'),
            "{msg:?}"
        );
        assert!(
            msg.contains("a\\u{1b}[31mb.ROB: line 1: `\\u{1b}]0;x\\u{7}` \\u{9b}2J \\u{202e}"),
            "{msg}"
        );
        assert_eq!(printable(r#"ex\nav.ROB 'a' "b""#), r#"ex\nav.ROB 'a' "b""#);
    }

    #[test]
    fn an_end_of_file_error_is_put_on_the_last_line() {
        let p = Path::new("m.par");
        let e = FileError::at_line(p, "1\n2\n", 3, "line 3: field `x`: the file ends");
        assert_eq!(e.line, Some(2));
        assert_eq!(e.to_string(), "m.par: line 2: field `x`: the file ends");
        let e = FileError::at_line(p, "1\n2\n", 2, "line 2: field `x`");
        assert_eq!(e.to_string(), "m.par: line 2: field `x`");
    }

    #[test]
    fn every_format_cites_a_section_of_formats_md_that_exists() {
        let doc = include_str!("../../docs/formats.md");
        // GitHub's anchors: the heading in lower case, without its punctuation but `-`.
        let anchors: Vec<String> = doc
            .lines()
            .filter_map(|l| l.strip_prefix("## "))
            .map(|h| {
                h.to_lowercase()
                    .chars()
                    .filter_map(|c| match c {
                        ' ' => Some('-'),
                        c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
                        _ => None,
                    })
                    .collect()
            })
            .collect();
        for doc_ref in [DA.doc, PAR.doc, ROB.doc, MAP.doc, TRA.doc, SAVED_MAP_DOC] {
            let anchor = doc_ref.strip_prefix("docs/formats.md#").unwrap();
            assert!(
                anchors.iter().any(|a| a == anchor),
                "{doc_ref}: no such section in {anchors:?}"
            );
        }
    }

    #[test]
    fn directories_and_missing_files_are_named() {
        let dir = tempfile::tempdir().unwrap();
        let e = read_text(dir.path(), ROB).unwrap_err();
        assert!(
            e.to_string()
                .ends_with("is a directory, not a file; see docs/formats.md#rob"),
            "{e}"
        );
        let e = read_text(&dir.path().join("none.MAP"), MAP).unwrap_err();
        assert!(e.to_string().contains("none.MAP: cannot open"), "{e}");
    }
}
