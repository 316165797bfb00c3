use femu_fem::FemError;
use std::path::PathBuf;
use thiserror::Error;

/// Errors reading or writing files. Each names the file and, for content errors, the line.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum IoError {
    /// The operating system refused (missing file, permissions, disk full).
    #[error("{}: {reason}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The system's message.
        reason: String,
    },
    /// Malformed content.
    #[error("{}:{line}: {reason}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// The content is well formed but does not make a valid model (for example an element on a
    /// missing node), with the line that defined the offender.
    #[error("{}:{line}: {source}", path.display())]
    Model {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// The model error.
        source: FemError,
    },
}

impl IoError {
    /// The system's error `e` on `path`.
    pub(crate) fn io(path: &std::path::Path, e: std::io::Error) -> Self {
        IoError::Io {
            path: path.to_path_buf(),
            reason: e.to_string(),
        }
    }
}

/// A non-fatal finding (an unknown keyword, an approximation made while reading).
#[derive(Debug, Clone, PartialEq)]
pub struct Warning {
    /// The file.
    pub path: PathBuf,
    /// 1-based line number.
    pub line: usize,
    /// What was noticed.
    pub message: String,
}

impl std::fmt::Display for Warning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}:{}: warning: {}",
            self.path.display(),
            self.line,
            self.message
        )
    }
}
