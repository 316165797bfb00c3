use femu_correlate::CorrelateError;
use femu_fem::FemError;
use femu_io::IoError;
use femu_sparse::SparseError;
use femu_update::UpdateError;
use std::path::PathBuf;
use thiserror::Error;

/// Errors of a workflow: the library crates' errors, passed through with their place, and the
/// workflow's own (a file it cannot write, settings that do not fit the data).
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum StudyError {
    /// From the sparse-solver core.
    #[error(transparent)]
    Sparse(#[from] SparseError),
    /// From the finite element core.
    #[error(transparent)]
    Fem(#[from] FemError),
    /// From correlation, expansion or the estimators.
    #[error(transparent)]
    Correlate(#[from] CorrelateError),
    /// From updating.
    #[error(transparent)]
    Update(#[from] UpdateError),
    /// From reading or writing a file format.
    #[error(transparent)]
    Io(#[from] IoError),
    /// A file or folder that could not be read or written.
    #[error("{}: {source}", path.display())]
    File {
        /// The file or folder.
        path: PathBuf,
        /// The system's error.
        source: std::io::Error,
    },
    /// An error found while building a model or a sensor layout from a file, with the file.
    #[error("{}: {source}", path.display())]
    InFile {
        /// The model or test file.
        path: PathBuf,
        /// What went wrong.
        source: Box<StudyError>,
    },
    /// A model or test file, or a setting, that does not fit the workflow.
    #[error("{}{what}: {reason}", context.as_ref().map(|p| format!("{}: ", p.display())).unwrap_or_default())]
    Invalid {
        /// The file concerned, if any.
        context: Option<PathBuf>,
        /// The setting or input.
        what: String,
        /// What is wrong and what would fit.
        reason: String,
    },
    /// A study file that is not valid TOML or has unknown or missing keys.
    #[error("{}:{line}: {reason}", path.display())]
    StudyFile {
        /// The study file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// JSON output could not be formed.
    #[error("JSON: {0}")]
    Json(#[from] serde_json::Error),
}

impl StudyError {
    /// A setting that does not fit (no file concerned).
    pub fn invalid(what: impl Into<String>, reason: impl Into<String>) -> Self {
        StudyError::Invalid {
            context: None,
            what: what.into(),
            reason: reason.into(),
        }
    }

    /// An input file that does not fit.
    pub fn in_file(
        path: impl Into<PathBuf>,
        what: impl Into<String>,
        reason: impl Into<String>,
    ) -> Self {
        StudyError::Invalid {
            context: Some(path.into()),
            what: what.into(),
            reason: reason.into(),
        }
    }

    /// The warnings a reader collected before this error (print them before it).
    pub fn warnings(&self) -> Vec<String> {
        match self {
            StudyError::Io(e) => e.warnings().iter().map(ToString::to_string).collect(),
            StudyError::InFile { source, .. } => source.warnings(),
            _ => Vec::new(),
        }
    }

    /// `source` found while building something from the file `path`.
    pub fn within(path: impl Into<PathBuf>, source: impl Into<StudyError>) -> Self {
        StudyError::InFile {
            path: path.into(),
            source: Box::new(source.into()),
        }
    }

    /// The system's error on `path`.
    pub fn file(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        StudyError::File {
            path: path.into(),
            source,
        }
    }
}
