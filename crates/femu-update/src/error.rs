use femu_correlate::CorrelateError;
use femu_fem::FemError;
use femu_sparse::SparseError;
use thiserror::Error;

/// Errors of model updating. Each names the offending parameter, group or mode.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum UpdateError {
    /// From the sparse core (factorizations, eigensolver).
    #[error(transparent)]
    Sparse(#[from] SparseError),
    /// From the finite element core (groups, assembly).
    #[error(transparent)]
    Fem(#[from] FemError),
    /// From correlation and expansion.
    #[error(transparent)]
    Correlate(#[from] CorrelateError),
    /// An invalid setting or input.
    #[error("invalid {what}: {reason}")]
    Invalid {
        /// Which input.
        what: &'static str,
        /// Why.
        reason: String,
    },
    /// A test mode the model cannot pair any more (inverse eigensensitivity needs every tuned
    /// test mode paired in every iteration).
    #[error(
        "test mode {test} ({f_test:.2} Hz) has no model mode above the MAC threshold at iteration {iteration}"
    )]
    LostPair {
        /// Test mode (1-based).
        test: usize,
        /// Its frequency, Hz.
        f_test: f64,
        /// The iteration (0: the starting model).
        iteration: usize,
    },
}
