//! Reading the seed's world files from disk, with errors that name the file.
//!
//! The parsers in [`twil_core::world`] work on text and report the line, the field and the value;
//! this module adds the file: it reads it through [`crate::files`] (refusing directories and
//! anything larger than the format's cap, so `/dev/zero` cannot make it hang; checking that text
//! files are UTF-8, naming the line and offset of the first bad byte), and turns every failure
//! into one [`FileError`] whose message reads `worlds/x.da: line 4: field ...`.
//!
//! Formats:
//!
//! - `.da` (environment) and `.par` (parameters): see [`twil_core::world`].
//! - Saved map (the seed's `-s` file, `carrega_amb_salvo`): a raw dump of
//!   `unsigned char mapa[MAXX][MAXY]`, **x-major** (byte `x * height + y` is cell (x, y)),
//!   exactly `width * height` bytes, 127 = obstacle; any nonzero byte is taken as occupied. The
//!   seed saved the map after growing the obstacles by the robot radius, so the cells are the
//!   configuration-space obstacles already and are not grown again.
//!
//! ```no_run
//! use std::path::Path;
//! let obstacles = twil_host::world_io::read_da(Path::new("worlds/office.da")).unwrap();
//! let params = twil_host::world_io::read_par(Path::new("worlds/office.par")).unwrap();
//! assert_eq!(obstacles.len(), 9);
//! assert_eq!(params.robot_radius_m, 0.4);
//! ```

use std::path::Path;

use twil_core::grid::Grid;
use twil_core::robot::RobotConfig;
use twil_core::world::{parse_da, parse_par, parse_par_for, Obstacles, Params, ParseError};

pub use crate::files::FileError;
use crate::files::{read_capped, read_text, DA, PAR, SAVED_MAP_DOC};

/// Value the seed wrote for an occupied cell in a saved map.
pub const SAVED_MAP_OCCUPIED: u8 = 127;

/// A parse error of `text`, named with the file (the line brought back onto the file's last
/// line when the text ended early).
fn parse_error(path: &Path, text: &str, error: &ParseError, doc: &'static str) -> FileError {
    FileError::at_line(path, text, error.line, &error.to_string()).see(doc)
}

/// Read a `.da` environment file.
pub fn read_da(path: &Path) -> Result<Obstacles, FileError> {
    let text = read_text(path, DA)?;
    let mut obstacles = Obstacles::new();
    parse_da(&text, &mut obstacles).map_err(|e| parse_error(path, &text, &e, DA.doc))?;
    Ok(obstacles)
}

/// Read a `.par` parameter file.
pub fn read_par(path: &Path) -> Result<Params, FileError> {
    let text = read_text(path, PAR)?;
    parse_par(&text).map_err(|e| parse_error(path, &text, &e, PAR.doc))
}

/// Read a `.par` file for a mission of `robot`: as [`read_par`], and the speed and the radius
/// within what `robot` can be trusted with ([`twil_core::limits`]); errors name the file, the
/// line, the field and the bound.
pub fn read_par_for(path: &Path, robot: &RobotConfig) -> Result<Params, FileError> {
    let text = read_text(path, PAR)?;
    parse_par_for(&text, robot).map_err(|e| parse_error(path, &text, &e, PAR.doc))
}

/// Mark in `grid` every cell that a saved map (see the module doc) marks occupied, for the
/// grid's geometry. Returns the number of occupied bytes. A file whose size is not exactly
/// `width * height` bytes is an error naming the file and both sizes; on error `grid` is
/// unchanged.
pub fn read_saved_map<const W: usize>(path: &Path, grid: &mut Grid<W>) -> Result<usize, FileError> {
    let g = *grid.geometry();
    let (w, h) = (g.width() as usize, g.height() as usize);
    let expected = w * h;
    let bytes = read_capped(
        path,
        &format!("a saved {w}x{h} map (one byte per cell, x-major); check --size and --resolution"),
        expected as u64,
    )
    .map_err(|e| e.see(SAVED_MAP_DOC))?;
    if bytes.len() != expected {
        return Err(FileError::new(
            path,
            None,
            format!(
                "saved map has {} bytes but a {w}x{h} map needs {expected} (one byte per cell, \
                 x-major); check --size and --resolution",
                bytes.len()
            ),
        )
        .see(SAVED_MAP_DOC));
    }
    let mut occupied = 0;
    for (i, b) in bytes.iter().enumerate() {
        if *b != 0 {
            grid.set_xy((i / h) as i32, (i % h) as i32, true);
            occupied += 1;
        }
    }
    Ok(occupied)
}

/// Write `grid` as a saved map (the inverse of [`read_saved_map`]: x-major, 127 = occupied).
pub fn write_saved_map<const W: usize>(path: &Path, grid: &Grid<W>) -> Result<(), FileError> {
    let g = *grid.geometry();
    let mut bytes = Vec::with_capacity(g.cell_count());
    for x in 0..g.width() as i32 {
        for y in 0..g.height() as i32 {
            bytes.push(if grid.is_occupied_xy(x, y) {
                SAVED_MAP_OCCUPIED
            } else {
                0
            });
        }
    }
    std::fs::write(path, bytes)
        .map_err(|e| FileError::new(path, None, format!("cannot write: {e}")))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;
    use twil_core::grid::{Grid400, GridGeometry};

    fn temp(name: &str, bytes: &[u8]) -> (tempfile::TempDir, PathBuf) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        (dir, path)
    }

    #[test]
    fn parse_errors_name_file_and_line() {
        let (_d, p) = temp("x.da", b"1\n3\n0 0\n1 zz\n");
        let e = read_da(&p).unwrap_err();
        assert_eq!(e.line, Some(4));
        let msg = e.to_string();
        assert!(
            msg.starts_with(&format!("{}: line 4: field `vertex y`", p.display())),
            "{msg}"
        );
        assert!(msg.contains("`zz`"), "{msg}");
    }

    #[test]
    fn binary_and_directories_are_errors() {
        let (_d, p) = temp("g.da", b"2\n\xff\xfe\x00garbage");
        let e = read_da(&p).unwrap_err();
        assert_eq!(e.line, Some(2));
        assert!(e.to_string().contains("not UTF-8"), "{e}");
        let (_d2, p2) = temp("c.par", b"0.4\x01\x02 0.2 0 1 1 2 2");
        let e = read_par(&p2).unwrap_err();
        assert!(!e.to_string().chars().any(char::is_control), "{e}");
        let dir = tempfile::tempdir().unwrap();
        let e = read_da(dir.path()).unwrap_err();
        assert!(e.to_string().contains("directory"), "{e}");
        let e = read_par(&dir.path().join("missing.par")).unwrap_err();
        assert!(e.to_string().contains("missing.par: cannot open"), "{e}");
    }

    #[test]
    fn saved_map_round_trip_is_x_major() {
        let g = GridGeometry::new(4, 3, 0.5).unwrap();
        let mut grid = Grid400::new(g).unwrap();
        grid.set_xy(1, 2, true);
        grid.set_xy(3, 0, true);
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("m.map");
        write_saved_map(&p, &grid).unwrap();
        let bytes = std::fs::read(&p).unwrap();
        assert_eq!(bytes.len(), 12);
        assert_eq!(bytes[3 + 2], SAVED_MAP_OCCUPIED); // x = 1, y = 2
        assert_eq!(bytes[3 * 3], SAVED_MAP_OCCUPIED); // x = 3, y = 0
        let mut back = Grid400::new(g).unwrap();
        assert_eq!(read_saved_map(&p, &mut back).unwrap(), 2);
        assert_eq!(back, grid);
    }

    #[test]
    fn saved_map_of_wrong_size_names_sizes_and_changes_nothing() {
        let g = GridGeometry::new(4, 3, 0.5).unwrap();
        let mut grid = Grid400::new(g).unwrap();
        for (len, word) in [
            (11, "has 11 bytes"),
            (13, "is 13 bytes, more than the 12 bytes"),
        ] {
            let (_d, p) = temp("m.map", &vec![1u8; len]);
            let e = read_saved_map(&p, &mut grid).unwrap_err();
            let msg = e.to_string();
            assert!(
                msg.contains("m.map") && msg.contains(word) && msg.contains("4x3"),
                "{msg}"
            );
        }
        assert_eq!(grid.count_occupied(), 0);
    }

    #[test]
    fn endless_files_are_cut_off() {
        let zero = Path::new("/dev/zero");
        if zero.exists() {
            let e = read_da(zero).unwrap_err();
            assert!(e.to_string().contains("more than the 4194304 bytes"), "{e}");
        }
    }

    #[test]
    fn missing_value_is_reported_on_the_last_line() {
        let (_d, p) = temp("m.par", b"0.4\n0.2\n90\n1 1\n2\n");
        let e = read_par(&p).unwrap_err();
        assert_eq!(e.line, Some(5), "{e}");
        assert!(e.to_string().contains("line 5: field `goal y`"), "{e}");
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(200))]
        #[test]
        fn any_bytes_give_a_result_or_one_line_error_naming_the_file(
            bytes in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..200),
            numeric in proptest::collection::vec(0u8..16, 0..200),
        ) {
            // Raw bytes, and bytes drawn from digits/space/newline/sign/dot that parse further.
            let alphabet = b"0123456789 \n-.9";
            let text: Vec<u8> = numeric.iter().map(|i| alphabet[*i as usize % alphabet.len()]).collect();
            for content in [&bytes, &text] {
                let (_d, p) = temp("p.da", content);
                if let Err(e) = read_da(&p) {
                    let msg = e.to_string();
                    proptest::prop_assert!(msg.starts_with(&p.display().to_string()));
                    proptest::prop_assert!(!msg.chars().any(char::is_control), "{}", msg);
                    if let Some(line) = e.line {
                        let lines = content.iter().filter(|b| **b == b'\n').count() as u32 + 1;
                        proptest::prop_assert!(line >= 1 && line <= lines);
                    }
                }
                let _ = read_par(&p);
            }
        }
    }
}
