//! Typed errors. Every error that comes from what the user gave (a file, an option) says which
//! file or option, where in it, and what is wrong; the CLI turns those into exit code 2.

use std::path::PathBuf;

/// Result with [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A bad input file: the file, the place in it, and the reason.
    #[error("{}: {place}: {reason}", file.display())]
    Input {
        /// The file.
        file: PathBuf,
        /// Where in it (`line 3 column 7`, `part[1].outer[4]`, …).
        place: String,
        /// What is wrong.
        reason: String,
    },
    /// A bad drawing (DXF, SVG).
    #[error(transparent)]
    Import(#[from] swarf_import::ImportError),
    /// A bad parameter or a job that cannot be machined as asked.
    #[error("{place}: {reason}")]
    Param {
        /// The parameter (`--stepover`, `tool.diameter`, …) or the job aspect.
        place: String,
        /// What is wrong.
        reason: String,
    },
    /// Reading or writing a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
}

impl Error {
    /// A parameter error.
    pub fn param(place: impl Into<String>, reason: impl Into<String>) -> Self {
        Error::Param { place: place.into(), reason: reason.into() }
    }
    /// An input-file error.
    pub fn input(file: impl Into<PathBuf>, place: impl Into<String>, reason: impl Into<String>) -> Self {
        Error::Input { file: file.into(), place: place.into(), reason: reason.into() }
    }
    /// True when the error is the user's input (exit code 2), false for I/O trouble.
    pub fn is_user_error(&self) -> bool {
        !matches!(self, Error::Io { .. })
    }
}
