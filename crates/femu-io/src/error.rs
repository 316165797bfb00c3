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
    #[error("{}{}: {reason}", path.display(), at_line(*line))]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// Something about the file as a whole (empty, no mesh in it, a format femu does not read).
    #[error("{}: {reason}", path.display())]
    Content {
        /// The file.
        path: PathBuf,
        /// What is wrong and what femu expected.
        reason: String,
    },
    /// The content is well formed but does not make a valid model (for example an element on a
    /// missing node), with the line that defined the offender.
    #[error("{}{}: {source}", path.display(), at_line(*line))]
    Model {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// The model error.
        source: FemError,
    },
    /// An error found after the reader had collected warnings: `source` is the error, `warnings`
    /// what was noticed before it (an ignored keyword is often the cause of a later error). The
    /// message is the error's; print [`IoError::warnings`] before it.
    #[error("{source}")]
    AfterWarnings {
        /// What was noticed before the error.
        warnings: Vec<Warning>,
        /// The error.
        source: Box<IoError>,
    },
}

/// `":N"` for a line number, nothing for 0 (the file as a whole): a message never says "line 0".
fn at_line(line: usize) -> String {
    if line == 0 {
        String::new()
    } else {
        format!(":{line}")
    }
}

impl IoError {
    /// The warnings collected before this error (empty for most errors).
    pub fn warnings(&self) -> &[Warning] {
        match self {
            IoError::AfterWarnings { warnings, .. } => warnings,
            _ => &[],
        }
    }

    /// The error without the warnings collected before it.
    pub fn root(&self) -> &IoError {
        match self {
            IoError::AfterWarnings { source, .. } => source.root(),
            e => e,
        }
    }

    /// `self` with `warnings` attached (unchanged when there are none).
    pub(crate) fn after(self, warnings: &[Warning]) -> Self {
        if warnings.is_empty() {
            return self;
        }
        match self {
            IoError::AfterWarnings {
                warnings: mut w,
                source,
            } => {
                let mut all = warnings.to_vec();
                all.append(&mut w);
                IoError::AfterWarnings {
                    warnings: all,
                    source,
                }
            }
            e => IoError::AfterWarnings {
                warnings: warnings.to_vec(),
                source: Box::new(e),
            },
        }
    }

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
        write!(f, "{}:{}: {}", self.path.display(), self.line, self.message)
    }
}
