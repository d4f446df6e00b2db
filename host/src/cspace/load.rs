//! Reading the files of `twil cspace` (`.ROB`, `.MAP`, `.TRA`) with their size limits, errors
//! named with the file and line.
//!
//! They live below the command so that the picture code and its tests (`render.rs`) can read a
//! robot without importing `cmd`.

use std::path::Path;

use twil_core::cspace::{
    map::ConfigMap,
    rob::{parse_rob, Robot},
    text::FileError as TextError,
    tra::Trajectory,
};

use crate::files::{self, FileError};

/// A reader's error named with the file (escaped, on the file's last line at most).
fn file_error(path: &Path, text: &str, e: &TextError, format: files::Format) -> FileError {
    FileError::at_line(path, text, e.line, &e.to_string()).see(format.doc)
}

/// Read and check a `.ROB` file (at most [`files::ROB`] bytes); errors name the file, line,
/// field and value.
pub fn load_robot(path: &Path) -> Result<Robot, FileError> {
    let text = files::read_text(path, files::ROB)?;
    parse_rob(&text).map_err(|e| file_error(path, &text, &e, files::ROB))
}

/// Read a `.MAP` file (at most [`files::MAP`] bytes); which joints wrap comes from the robot.
pub fn load_map(path: &Path, robot: &Robot) -> Result<ConfigMap, FileError> {
    let text = files::read_text(path, files::MAP)?;
    let wraps = [robot.joints[0].wraps(), robot.joints[1].wraps()];
    let (_, map) =
        ConfigMap::parse_map(&text, wraps).map_err(|e| file_error(path, &text, &e, files::MAP))?;
    Ok(map)
}

/// Read a `.TRA` file (at most [`files::TRA`] bytes).
pub fn load_tra(path: &Path) -> Result<Trajectory, FileError> {
    let text = files::read_text(path, files::TRA)?;
    Trajectory::parse(&text).map_err(|e| file_error(path, &text, &e, files::TRA))
}
