//! Errors of the robot-interface reader and runner.

use std::fmt;
use std::path::PathBuf;
use std::sync::Arc;
use thiserror::Error;

/// Where an element was read: file and 1-based line.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Location {
    pub file: Arc<str>,
    pub line: u32,
}

impl Location {
    pub fn new(file: &Arc<str>, line: u32) -> Self {
        Location {
            file: file.clone(),
            line,
        }
    }
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}", self.file, self.line)
    }
}

/// Why a robot description could not be loaded.
#[derive(Debug, Error)]
pub enum XmlError {
    #[error("cannot read {path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    /// Not well-formed XML, as TinyXML would refuse it (file and line of the fault).
    #[error("{file}:{line}: malformed XML: {message}")]
    Malformed {
        file: String,
        line: u32,
        message: String,
    },
    /// Well-formed XML that breaks the yarprobotinterface DTD.
    #[error("{at}: {message}")]
    Syntax { at: Location, message: String },
    #[error("{file}: DTD yarprobotinterface {version} is not supported (C++ YARP 3.12 reads 3.x only; V1 files need updating)")]
    UnsupportedDtd { file: String, version: String },
    #[error("{at}: include cycle: {path} includes itself")]
    IncludeCycle { at: Location, path: PathBuf },
    #[error("{at}: includes nested deeper than {limit}")]
    IncludeTooDeep { at: Location, limit: usize },
    /// C++ `mergeDuplicateGroups` aborts the program on this.
    #[error("{at}: device `{device}`: duplicate parameter `{param}` and at least one of them is not a group")]
    DuplicateParam {
        at: Location,
        device: String,
        param: String,
    },
}

impl XmlError {
    pub(crate) fn syntax(at: &Location, message: impl Into<String>) -> Self {
        XmlError::Syntax {
            at: at.clone(),
            message: message.into(),
        }
    }
}
