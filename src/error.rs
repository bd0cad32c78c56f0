//! One error type for everything a user can get wrong: a file that cannot be read, a scene that does not
//! parse, a setting out of range. It always says where (file, line and column when known) and what was
//! expected, in the one-line form `path:line:col: message` that editors and terminals make clickable.

use std::fmt;
use std::path::{Path, PathBuf};

/// Where in a file an error was found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Location {
    /// The whole file (it could not be opened, or it is empty).
    File,
    /// A 1-based line and column of a text file.
    LineCol(u64, u64),
    /// A byte offset into the (decompressed) data of a binary file.
    Byte(u64),
}

/// An error with its context: `path:line:col: message`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Error {
    /// The file the error is about, if any.
    pub path: Option<PathBuf>,
    /// Where in that file.
    pub location: Location,
    /// What was expected and what was found.
    pub message: String,
}

impl Error {
    /// An error that is not about a file (a bad command-line value, say).
    pub fn msg(message: impl Into<String>) -> Self {
        Error {
            path: None,
            location: Location::File,
            message: message.into(),
        }
    }

    /// An error about a whole file.
    pub fn file(path: &Path, message: impl Into<String>) -> Self {
        Error {
            path: Some(path.to_path_buf()),
            location: Location::File,
            message: message.into(),
        }
    }

    /// An error at a line and column of a text file.
    pub fn at(path: &Path, line: u64, col: u64, message: impl Into<String>) -> Self {
        Error {
            path: Some(path.to_path_buf()),
            location: Location::LineCol(line, col),
            message: message.into(),
        }
    }

    /// The line of a text-file error, if it has one (tests assert on it).
    pub fn line(&self) -> Option<u64> {
        match self.location {
            Location::LineCol(line, _) => Some(line),
            _ => None,
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(path) = &self.path {
            // A name with a line break or other control character, or that is not UTF-8, is
            // escaped (quoted, as `{:?}` writes it), so that the message stays one line that says
            // exactly which file.
            match path.to_str() {
                Some(s) if !s.chars().any(char::is_control) => write!(f, "{s}:")?,
                _ => write!(f, "{path:?}:")?,
            }
            match self.location {
                Location::File => {}
                Location::LineCol(line, col) => write!(f, "{line}:{col}:")?,
                Location::Byte(offset) => write!(f, " byte {offset}:")?,
            }
            f.write_str(" ")?;
        }
        f.write_str(&self.message)
    }
}

impl std::error::Error for Error {}

/// The crate's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;
