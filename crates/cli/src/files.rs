//! The command line's readers of user files: helicon-config's bounded
//! readers with the toolkit's limits. Only regular files are read (a FIFO,
//! `/dev/zero` or a folder is refused before any read); a text file
//! (TOML, JSON, a matrix, readings) is read whole up to
//! [`MAX_TEXT_BYTES`]; a CSV log is streamed, up to [`MAX_DATA_BYTES`] in
//! all and [`MAX_LINE_BYTES`] a line. The errors name the file and the
//! limit.

use anyhow::Result;
use helicon_model::config_error::{
    Bounded, ConfigError, LineBounded, MAX_DATA_BYTES, MAX_LINE_BYTES, MAX_TEXT_BYTES,
    open_lines_bounded, read_text_bounded,
};
use std::fs::File;
use std::path::Path;

/// The text of the file at `path` (a configuration, a matrix, readings).
pub fn read_text(path: &Path) -> Result<String> {
    Ok(read_text_bounded(path, MAX_TEXT_BYTES)?)
}

/// The text of the file at `path` as [`read_text`] reads it, or `None`
/// when there is no such file (a file the toolkit left in its output
/// folder: a stamp, a plan, an exit status).
pub fn read_text_if_present(path: &Path) -> Result<Option<String>> {
    match read_text_bounded(path, MAX_TEXT_BYTES) {
        Ok(t) => Ok(Some(t)),
        Err(ConfigError::Io { source, .. }) if source.kind() == std::io::ErrorKind::NotFound => {
            Ok(None)
        }
        Err(e) => Err(e.into()),
    }
}

/// The file at `path` for a line reader (a CSV log, rows of numbers).
pub fn open_lines(path: &Path) -> Result<LineBounded<Bounded<File>>> {
    Ok(open_lines_bounded(path, MAX_DATA_BYTES, MAX_LINE_BYTES)?)
}
