//! The command's one error type: the workflows' errors with their sources, and usage errors that
//! the argument parser cannot see (a combination of options that does not fit the files).

use femu::study::StudyError;

/// An error of a `femu` command.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// From a workflow or a library crate (file and line, element or node, what to do).
    #[error(transparent)]
    Study(#[from] StudyError),
    /// Options that do not fit the inputs.
    #[error("{0}")]
    Usage(String),
}

impl CliError {
    /// The warnings a reader collected before the error.
    pub fn warnings(&self) -> Vec<String> {
        match self {
            CliError::Study(e) => e.warnings(),
            CliError::Usage(_) => Vec::new(),
        }
    }
}

macro_rules! via_study {
    ($($t:ty),*) => {$(
        impl From<$t> for CliError {
            fn from(e: $t) -> Self {
                CliError::Study(StudyError::from(e))
            }
        }
    )*};
}

via_study!(
    femu::io::IoError,
    femu::sparse::SparseError,
    femu::fem::FemError,
    femu::correlate::CorrelateError,
    femu::update::UpdateError
);
