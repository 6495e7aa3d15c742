//! What a command fails with: the typed errors of the libraries it calls (the live session, the
//! map loader, git), each saying where, and the command's own refusals.

use std::io;

use drivemap_live::link::LinkError;
use drivemap_live::session::{
    ConversionError, ReadError, SessionError, SettingError, UnknownNames,
};

use crate::git::GitError;
use crate::maps::MapError;

/// Why a command stopped (exit status 2); printed after `drivemap: `.
#[derive(Debug, thiserror::Error)]
pub(crate) enum Error {
    /// The drive's link cannot be opened.
    #[error(transparent)]
    Link(#[from] LinkError),
    /// A `--variant` or `--set` is not one of the map.
    #[error(transparent)]
    Setting(#[from] SettingError),
    /// Register names that are not the drive's.
    #[error(transparent)]
    Names(#[from] UnknownNames),
    /// The session cannot plan the reads.
    #[error(transparent)]
    Session(#[from] SessionError),
    /// A register could not be read.
    #[error(transparent)]
    Read(#[from] ReadError),
    /// A value does not convert.
    #[error(transparent)]
    Value(#[from] ConversionError),
    /// A map cannot be found or does not validate.
    #[error(transparent)]
    Map(#[from] MapError),
    /// Git could not give the maps of a revision.
    #[error(transparent)]
    Git(#[from] GitError),
    /// Reading or writing a file or a stream failed.
    #[error("{what}: {source}")]
    Io {
        /// The file or stream and what was done with it.
        what: String,
        /// The operating system's reason.
        source: io::Error,
    },
    /// JSON could not be written.
    #[error("writing JSON: {0}")]
    Json(#[from] serde_json::Error),
    /// CSV could not be written.
    #[error("writing CSV: {0}")]
    Csv(#[from] csv::Error),
    /// Text that should be UTF-8 is not.
    #[error("output is not UTF-8: {0}")]
    Utf8(#[from] std::string::FromUtf8Error),
    /// The simulator refuses its options.
    #[error(transparent)]
    Sim(#[from] drivemap_sim::SimError),
    /// The bridge cannot start (its options, a CA file, a listener, the registers asked).
    #[error(transparent)]
    Bridge(#[from] drivemap_bridge::Error),
    /// The drive cannot be exported for a tool on the link given.
    #[error(transparent)]
    Export(#[from] drivemap_bridge::ExportError),
    /// The command refuses, in its own words (what was given and why it cannot be done).
    #[error("{0}")]
    Refused(String),
}

impl Error {
    /// An I/O error on `what` ("writing standard output", a file's path).
    pub(crate) fn io(what: impl std::fmt::Display) -> impl FnOnce(io::Error) -> Error {
        let what = what.to_string();
        move |source| Error::Io { what, source }
    }
}

impl From<String> for Error {
    fn from(message: String) -> Error {
        Error::Refused(message)
    }
}

impl From<&str> for Error {
    fn from(message: &str) -> Error {
        Error::Refused(message.to_owned())
    }
}
