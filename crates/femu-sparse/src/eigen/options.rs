//! What a solve is asked for ([`Which`]) and how it runs ([`EigenOptions`]), refused before any
//! work when no solve can run with it.

use super::*;

/// Which eigenpairs to compute.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Which {
    /// The `k` lowest eigenvalues (extended to complete a cluster of equal eigenvalues at the top).
    Lowest(usize),
    /// The `count` eigenvalues nearest `shift` (s^-2).
    Nearest {
        /// The shift `sigma` in s^-2.
        shift: f64,
        /// How many.
        count: usize,
    },
    /// Every eigenvalue in `[lo, hi]` (s^-2).
    Band {
        /// Lower end in s^-2.
        lo: f64,
        /// Upper end in s^-2.
        hi: f64,
    },
}

/// Settings of the eigensolver.
#[derive(Debug, Clone, PartialEq)]
pub struct EigenOptions {
    /// Convergence tolerance on the shifted relative residual
    /// `||K x - lambda M x|| / ||(K - sigma M) x||`.
    pub tol: f64,
    /// Right-hand sides solved together.
    pub block_size: usize,
    /// Largest Krylov basis before a restart (0: automatic, `max(3 want + 2 block, want + 4 block, 24)`).
    pub max_basis: usize,
    /// Restarts allowed before giving up.
    pub max_restarts: usize,
    /// Fill-reducing ordering of the factorizations.
    pub ordering: Ordering,
    /// Seed of the random start vectors (results are deterministic for a seed).
    pub seed: u64,
    /// The eigensolver: femu's own (the default), or SLEPc under MPI ([`crate::slepc`]).
    pub engine: crate::slepc::Engine,
    /// For [`Which::Lowest`]: a negative shift known to be well placed, the [`Modes::shift`] of
    /// an earlier solve of a model that changed little since (an updating loop). The run starts
    /// there and skips the probe; for a coarse free-free model, whose solve moves the shift to
    /// half the first elastic eigenvalue, that is one factorization and the probe's solves fewer
    /// (docs/SCALING.md, "A hinted shift"). A hint that is not below the spectrum, or with which
    /// the run does not converge within 8 restarts, is dropped and the solve starts again
    /// without it. `None` (the default): no hint.
    pub lowest_shift_hint: Option<f64>,
    /// For [`Which::Lowest`]: vectors whose span is expected to hold null vectors of `K`, such as
    /// a free structure's six rigid-body motions ([`NullSpaceHint`]). The zero-energy modes in
    /// their span are verified and locked before the iteration starts, so the Lanczos run never
    /// has to converge them at the tiny shift. `None` (the default): the run finds them itself.
    pub null_space_hint: Option<NullSpaceHint>,
    /// Keep a factorization of `K - sigma M` at a shift below every returned eigenvalue in
    /// [`Modes::factor`](super::Modes::factor) ([`KeptFactor`](super::KeptFactor)): for [`Which::Lowest`], the iteration's own (kept
    /// through the Sturm count, whose inertia pass then runs beside it); for a [`Which::Band`]
    /// whose lower end is below zero, the Sturm count's at that end, made after the iteration
    /// instead of before it, so that no two factors are alive at once. No factorization is
    /// added. The frequency responses' residual flexibility solves with it instead of factoring
    /// `K` (docs/MATH.md, "Residual flexibility from the eigensolver's factor"). `false` (the
    /// default): every factor is released.
    pub keep_factor: bool,
}

/// Candidate null vectors of `K` for [`EigenOptions::null_space_hint`]: the columns of an
/// `n x c` matrix (`c` small), shared, not copied, between the options that hold it.
///
/// Nothing is assumed of them: the solver keeps only the combinations that pass the backward-error
/// test of a converged zero-energy mode (`||K x - lambda M x|| <= 1e-13 (||K||_1 + |lambda|
/// ||M||_1) ||x||`), so a support, a constraint or a mechanism that the candidates do not describe
/// costs nothing but the test, and the Sturm count still proves the result complete.
#[derive(Clone)]
pub struct NullSpaceHint(std::sync::Arc<Mat<f64>>);

impl NullSpaceHint {
    /// The hint of the columns of `vectors`.
    pub fn new(vectors: Mat<f64>) -> Self {
        Self(std::sync::Arc::new(vectors))
    }

    /// The candidate vectors, one per column.
    pub fn vectors(&self) -> faer::MatRef<'_, f64> {
        self.0.as_ref().as_ref()
    }
}

impl std::fmt::Debug for NullSpaceHint {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "NullSpaceHint({} x {})", self.0.nrows(), self.0.ncols())
    }
}

impl PartialEq for NullSpaceHint {
    fn eq(&self, other: &Self) -> bool {
        std::sync::Arc::ptr_eq(&self.0, &other.0) || *self.0 == *other.0
    }
}

impl Default for EigenOptions {
    fn default() -> Self {
        Self {
            tol: 1e-10,
            block_size: 4,
            max_basis: 0,
            max_restarts: 60,
            ordering: Ordering::NestedDissection,
            seed: 0x5EED,
            engine: crate::slepc::Engine::Femu,
            lowest_shift_hint: None,
            null_space_hint: None,
            keep_factor: false,
        }
    }
}

/// The widest block [`EigenOptions::block_size`] may ask for. The basis holds about twice as
/// many columns as the blocks are wide beyond the wanted pairs (`Lanczos::basis_size`), so a
/// block of thousands would ask for terabytes on a large model; and beyond a few vectors a
/// wider block only adds vectors: 4 is the fastest measured (docs/SCALING.md, "Block size and
/// the count of solved vectors").
pub const MAX_BLOCK: usize = 64;

/// The settings no solve can run with, refused before any work: a block size outside
/// `1..=MAX_BLOCK`, a tolerance that is not in `(0, 1)` (NaN included).
pub(super) fn check_options(params: &EigenOptions) -> Result<(), SparseError> {
    let default = EigenOptions::default();
    if !(1..=MAX_BLOCK).contains(&params.block_size) {
        return Err(SparseError::InvalidRequest {
            reason: format!(
                "block size {}: it must be between 1 and {MAX_BLOCK} (the default is {})",
                params.block_size, default.block_size
            ),
        });
    }
    if !(params.tol > 0.0 && params.tol < 1.0) {
        return Err(SparseError::InvalidRequest {
            reason: format!(
                "tolerance {}: it must be a relative residual between 0 and 1 (the default is \
                 {:e})",
                params.tol, default.tol
            ),
        });
    }
    Ok(())
}
