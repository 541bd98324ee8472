//! One typed error for everything that reads models: where in the file, and what
//! was expected there.

use std::fmt;
use std::path::PathBuf;

/// Where in a file a problem was found.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Location {
    /// The file as a whole (e.g. it is empty).
    File,
    /// 1-based line of a text format.
    Line(usize),
    /// Byte offset into the (decompressed) data.
    Byte(u64),
    /// A named part of a structured format (a glTF accessor, a PLY element).
    Item(String),
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::File => Ok(()),
            Location::Line(n) => write!(f, "line {n}: "),
            Location::Byte(b) => write!(f, "byte {b}: "),
            Location::Item(s) => write!(f, "{s}: "),
        }
    }
}

/// A format reader's error, before the file name is attached.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParseError {
    pub at: Location,
    pub expected: String,
}

impl ParseError {
    pub fn new(at: Location, expected: impl Into<String>) -> Self {
        Self {
            at,
            expected: expected.into(),
        }
    }
    pub fn line(line: usize, expected: impl Into<String>) -> Self {
        Self::new(Location::Line(line), expected)
    }
    pub fn byte(offset: u64, expected: impl Into<String>) -> Self {
        Self::new(Location::Byte(offset), expected)
    }
    pub fn file(expected: impl Into<String>) -> Self {
        Self::new(Location::File, expected)
    }
    pub fn item(item: impl Into<String>, expected: impl Into<String>) -> Self {
        Self::new(Location::Item(item.into()), expected)
    }
}

pub type ParseResult<T> = Result<T, ParseError>;

/// Why a model could not be loaded. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    #[error("{}: cannot read: {source}", file.display())]
    Io {
        file: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: {at}{expected}", file.display())]
    Malformed {
        file: PathBuf,
        at: Location,
        expected: String,
    },
    #[error("{}: unknown format: {why}", file.display())]
    UnknownFormat { file: PathBuf, why: String },
    #[error("{}: no geometry left: {why}", file.display())]
    Empty { file: PathBuf, why: String },
    #[error("{name}: unknown built-in model (see `lodstudio info --builtins`)")]
    UnknownBuiltin { name: String },
    /// Refused before parsing: not a regular file, over the budget, or a
    /// reference outside the asset folder (the message names it).
    #[error("{0}")]
    Refused(String),
    #[error("loading cancelled")]
    Cancelled,
}

impl LoadError {
    pub fn malformed(file: impl Into<PathBuf>, e: ParseError) -> Self {
        LoadError::Malformed {
            file: file.into(),
            at: e.at,
            expected: e.expected,
        }
    }
}

impl From<crate::progress::Cancelled> for LoadError {
    fn from(_: crate::progress::Cancelled) -> Self {
        LoadError::Cancelled
    }
}
