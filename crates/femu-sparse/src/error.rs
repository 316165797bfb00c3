use thiserror::Error;

/// Errors of the sparse-solver core. Each variant names where the problem was found.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum SparseError {
    /// Two operands do not have compatible shapes.
    #[error("dimension mismatch: {what} (expected {expected}, got {got})")]
    DimensionMismatch {
        /// Which operand or relation.
        what: &'static str,
        /// The size required.
        expected: usize,
        /// The size given.
        got: usize,
    },
    /// A matrix that must be symmetric is not.
    #[error(
        "{matrix} is not symmetric: entry ({row}, {col}) differs from its transpose by {defect:e}"
    )]
    NotSymmetric {
        /// Which matrix (`"K"`, `"M"`, ...).
        matrix: &'static str,
        /// Row of the worst entry.
        row: usize,
        /// Column of the worst entry.
        col: usize,
        /// Relative difference `|a_ij - a_ji| / max|a|`.
        defect: f64,
    },
    /// A matrix that must be positive definite has a non-positive pivot.
    #[error("{matrix} is not positive definite: non-positive pivot at index {index}")]
    NotPositiveDefinite {
        /// Which matrix.
        matrix: &'static str,
        /// Index (in the factorization's order) of the first non-positive pivot.
        index: usize,
    },
    /// A Cholesky factorization succeeded only by round-off: a pivot fell below
    /// [`crate::cholesky::SINGULAR_PIVOT_RATIO`] times its diagonal entry, so the matrix is
    /// singular to working precision (a free-free stiffness, a mechanism) and its solves would be
    /// dominated by the null space.
    #[error(
        "{matrix} is singular to working precision: the pivot at index {index} is {ratio:.1e} of its diagonal entry (a mechanism or an unconstrained rigid-body motion)"
    )]
    NumericallySingular {
        /// Which matrix.
        matrix: &'static str,
        /// Original index of the smallest pivot.
        index: usize,
        /// `L_jj^2 / A_jj` of that pivot.
        ratio: f64,
    },
    /// A NaN or infinity in an input.
    #[error("{matrix} has a non-finite entry at ({row}, {col})")]
    NonFinite {
        /// Which matrix.
        matrix: &'static str,
        /// Row of the entry.
        row: usize,
        /// Column of the entry.
        col: usize,
    },
    /// A zero pivot in an `LDL^T`: the matrix is singular (a shift on an eigenvalue).
    #[error("{matrix} is singular: zero pivot at index {index}")]
    Singular {
        /// Which matrix.
        matrix: &'static str,
        /// Original index of the zero pivot.
        index: usize,
    },
    /// A sparsity pattern given by its arrays is not a valid compressed-column pattern.
    #[error("invalid sparsity pattern: {reason}")]
    InvalidPattern {
        /// What is wrong, and where (the column).
        reason: String,
    },
    /// A factorization or ordering failed for another reason.
    #[error("factorization failed: {reason}")]
    Factorization {
        /// What failed.
        reason: String,
    },
    /// A file could not be read or written.
    #[error("{file}: {reason}")]
    Io {
        /// The file.
        file: String,
        /// The system's message.
        reason: String,
    },
    /// A malformed file.
    #[error("{file}:{line}: {reason}")]
    Parse {
        /// The file.
        file: String,
        /// One-based line number (0 when the whole file is concerned).
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// More eigenpairs were requested than the pencil has.
    #[error(
        "{requested} modes requested, but the model has only {dim} free degrees of freedom (at most {dim} modes): ask for fewer"
    )]
    TooManyModes {
        /// How many were requested.
        requested: usize,
        /// The dimension of the pencil.
        dim: usize,
    },
    /// An eigenvalue interval or shift that cannot be used.
    #[error("invalid eigenvalue request: {reason}")]
    InvalidRequest {
        /// What is wrong and what to do.
        reason: String,
    },
    /// The count of eigenvalues by inertia disagrees with the eigenpairs found, after the solver's
    /// retries: no result is returned rather than an unverified one.
    #[error(
        "Sturm check failed: the inertia of K - s M counts {count} eigenvalues in {interval}, the solver found {returned}; try another shift or ask for more modes"
    )]
    SturmMismatch {
        /// The interval, written `(a, b]` in s^-2.
        interval: String,
        /// Eigenvalues counted by inertia.
        count: usize,
        /// Eigenpairs found in it.
        returned: usize,
    },
    /// An external eigen engine is not installed or cannot start.
    #[error("{engine} is not available: {reason}")]
    EngineUnavailable {
        /// The engine.
        engine: &'static str,
        /// What is missing, and what to install.
        reason: String,
    },
    /// An external eigen engine failed (MPI, the solver, its files).
    #[error("{engine} failed: {reason}")]
    EngineFailed {
        /// The engine.
        engine: &'static str,
        /// Its message.
        reason: String,
    },
    /// A solve stopped at an iteration boundary because the caller's hook asked it to
    /// ([`crate::eigen::with_interrupt`]: Ctrl-C in a binding, a progress callback).
    #[error("the eigensolver was interrupted after {solved_vectors} solved vectors")]
    Interrupted {
        /// Vectors solved before it stopped.
        solved_vectors: usize,
    },
    /// An iterative or dense eigensolver did not converge.
    #[error("eigensolver did not converge: {reason}")]
    NoConvergence {
        /// What failed.
        reason: String,
    },
    /// Iterative refinement of a regularised saddle-point system did not reach a backward error
    /// of `1e-11`.
    #[error(
        "invalid {system}: the regularised saddle-point system did not refine to a backward error of 1e-11: the problem is singular or nearly so (an expansion eigenvalue on an eigenvalue of the constrained structure, or too few sensors)"
    )]
    NotRefined {
        /// Which system.
        system: &'static str,
    },
}
