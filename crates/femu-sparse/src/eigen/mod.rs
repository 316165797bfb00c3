//! The verified generalized eigensolver for `K x = lambda M x` (`K` symmetric positive
//! semi-definite, `M` symmetric positive definite, consistent or lumped).
//!
//! Shift-invert block Lanczos in the `M` inner product: the operator `OP = (K - sigma M)^-1 M` is
//! self-adjoint in `<x, y>_M = x^T M y`, its eigenvalues `theta = 1 / (lambda - sigma)` are
//! largest for the `lambda` nearest `sigma`. The Krylov basis is kept `M`-orthonormal by two
//! passes of classical Gram-Schmidt (full reorthogonalisation), done for each block of solved
//! vectors at once as matrix products (GEMM) against the locked vectors and the basis, stored
//! contiguously; converged Ritz pairs are checked after every block, locked as soon as they
//! converge, and every later vector is deflated against them; when the basis is full the
//! iteration restarts from the best unconverged Ritz vectors (thick restart, the Ritz vectors
//! formed by GEMM). Block solves (`block_size` right-hand sides at once) are cheaper per vector
//! than single ones. [`EigenStats`] accounts for the time of every phase.
//!
//! Evidence carried by every result: the relative residual of each mode, and a Sturm check: the
//! inertia of `K - s M = L D L^T` at a shift `s` in a gap above the returned modes counts the
//! eigenvalues below `s` (Sylvester), which must equal the number returned. A Krylov method can
//! miss copies of repeated eigenvalues; when the count says so, the solver restarts from random
//! vectors deflated against everything found, until the count agrees.

use crate::cholesky::{Factorization, Ldlt, SymbolicFactor};
use crate::ordering::{Ordering, Pattern};
use crate::{SparseError, SparseMatrix};
use faer::Mat;
use rayon::prelude::*;
use std::time::Instant;

mod block;
mod lanczos;
mod options;
mod pencil;
#[cfg(test)]
mod tests;

use block::*;
use lanczos::*;
use options::check_options;
pub use options::{EigenOptions, MAX_BLOCK, NullSpaceHint, Which};
use pencil::*;
pub use pencil::{Pencil, PencilChecks, eigs, with_interrupt};
pub(crate) use pencil::{one_norm, residual_of};

/// The Sturm check of a result.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SturmCheck {
    /// Lower end of the checked interval (`None`: from minus infinity).
    pub lower: Option<f64>,
    /// Upper end of the checked interval (s^-2), in a gap of the spectrum.
    pub upper: f64,
    /// Eigenvalues of the pencil in the interval, by inertia.
    pub count: usize,
    /// Eigenvalues returned in the interval.
    pub returned: usize,
}

impl SturmCheck {
    /// Whether no eigenvalue in the interval was missed.
    pub fn verified(&self) -> bool {
        self.count == self.returned
    }
}

impl SturmCheck {
    /// The counted interval as text, `(a, b] s^-2` (`-inf` for an unbounded lower end).
    pub fn interval(&self) -> String {
        match self.lower {
            Some(l) => format!("({l:.6e}, {:.6e}] s^-2", self.upper),
            None => format!("(-inf, {:.6e}] s^-2", self.upper),
        }
    }
}

/// The relative offset of a factored shift from the shift asked for (`1e-3 (sqrt 2 - 1)`). At
/// `1e-4` the eigenvalue under the shift dominated `OP` by a factor of 4,000 over its
/// neighbours on a small square, and the solves' round-off along it held a second copy of a
/// neighbouring double eigenvalue at a residual of `1.8e-10`, above the tolerance, for good.
const SHIFT_OFFSET: f64 = 1e-3 * (std::f64::consts::SQRT_2 - 1.0);

/// Restarts allowed to a run from a hinted shift ([`EigenOptions::lowest_shift_hint`]) before the
/// hint is dropped: a well-placed shift needed at most 2 on the models measured (docs/SCALING.md).
const HINTED_RESTARTS: usize = 8;

/// A basis built before a mode this much nearer the shift than the nearest unconverged one was
/// locked is discarded (see [`Lanczos::run`]): `OP` amplified that mode's part of every vector by
/// `1 / |lambda - sigma|`, and the factorization's round-off on that large part left the other
/// Ritz vectors with a relative residual of about `eps lambda_max / |lambda - sigma|`. On a free-free
/// plate of 47,628 DOF at the tiny shift (rigid-body modes 200 from the shift, the first elastic
/// one 4.8e5) that was 3e-7 to 1.4e-6 for every elastic pair, which then never converged.
const CLOSE_LOCK: f64 = 1e-2;

/// A free-free run stays at the tiny shift when the first elastic eigenvalue (the probe's
/// estimate) is at most this many times the shift's distance from zero. Measured: 2,400 on the
/// 47,628-DOF plate, where the rigid-body modes lock at once; 1.9e7 on a 6 x 4 x 2 plate,
/// where their backward error stays at 4e-12 to 2e-11 and the run cannot lock them.
const STAY_BELOW: f64 = 1e5;

/// Restarts a free-free run at the tiny shift may take before it is moved to half the first
/// elastic eigenvalue.
const TINY_SHIFT_RESTARTS: usize = 1;

/// Ritz pairs whose Krylov residual estimate is above this fraction of the tolerance are not
/// checked for convergence.
const SCREEN: f64 = 1e-2;

/// A pair is converged when its normwise backward error
/// `||K x - lambda M x|| / ((||K||_1 + |lambda| ||M||_1) ||x||)` is below this, whatever its other
/// residuals: a zero-energy mode can only meet this test, its `K x` being round-off.
const BACKWARD_LOCK: f64 = 1e-13;

/// A lowest-mode solve of a pencil of at most this many DOFs whose iteration does not converge
/// (a request that nearly fills the space the DOFs with mass span) finds its pairs by the dense
/// route instead (`O(n^3)`: about a second at this size), then locks and checks them as the
/// iteration's.
const DENSE_PAIRS: usize = 2000;

/// A mode is zero-energy when `||K x|| <= ZERO_ENERGY ||K||_1 ||x||`: `K x` is then round-off.
const ZERO_ENERGY: f64 = 1e-11;

/// Which residual a mode reports in [`Modes::residuals`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ResidualKind {
    /// `||K x - lambda M x|| / ||K x||`, the relative residual of a mode with strain energy.
    Relative,
    /// `||K x - lambda M x|| / ((||K||_1 + |lambda| ||M||_1) ||x||)`, the normwise backward error,
    /// for a zero-energy (rigid-body or mechanism) mode: its `K x` is round-off
    /// (`||K x|| <= 1e-11 ||K||_1 ||x||`), so a residual relative to it compares round-off with
    /// round-off and says nothing.
    Backward,
}

impl ResidualKind {
    /// `"relative"` or `"backward"`.
    pub fn name(self) -> &'static str {
        match self {
            ResidualKind::Relative => "relative",
            ResidualKind::Backward => "backward",
        }
    }
}

/// Where the time went and how much work was done.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct EigenStats {
    /// Checks of the input (square, finite, symmetric, `M`'s pattern inside `K`'s) and the
    /// 1-norms of `K` and `M`, done once by [`Pencil::new`], seconds (docs/SCALING.md, "The
    /// block within itself, the Ritz vectors' products and the input checks"). Where the
    /// symbolic analysis runs beside them, only the time they last beyond it; with the checks
    /// made beside an assembly ([`PencilChecks`]), the fingerprint's comparison only.
    pub check_seconds: f64,
    /// Symbolic analyses (ordering included) done by this solve, seconds; 0 when the pencil was
    /// given one (`Pencil::with_symbolic`: an analysis made beside the assembly, docs/SCALING.md,
    /// "The analysis beside the assembly").
    pub symbolic_seconds: f64,
    /// Numeric factorizations, seconds.
    pub factor_seconds: f64,
    /// Triangular solves, seconds.
    pub solve_seconds: f64,
    /// Orthogonalisation and `M` products, seconds.
    pub orthogonalization_seconds: f64,
    /// Rayleigh-Ritz, convergence checks, locking, restarts and the final residuals, seconds.
    pub ritz_seconds: f64,
    /// The whole solve, the pencil's checks and symbolic analysis included, seconds: the phases
    /// above and what they leave out (shift placement, random start vectors, bookkeeping).
    pub total_seconds: f64,
    /// Numeric factorizations done (the solve shift and the Sturm checks).
    pub factorizations: usize,
    /// Vectors solved with `K - sigma M` (from the SLEPc engine, the solves of its
    /// shift-and-invert as PETSc counts them).
    pub solved_vectors: usize,
    /// Restarts of the Lanczos iteration.
    pub restarts: usize,
    /// Blocks of solved vectors in which a column kept less than `0.717` of its M-norm in the
    /// single pass of Gram-Schmidt against the basis, and that were projected a second time
    /// (docs/MATH.md, "Selective reorthogonalisation").
    pub reorthogonalized_blocks: usize,
    /// Values stored in each factor `L` (fill); from the SLEPc engine, the entries of MUMPS's
    /// factor (its `INFOG(29)`), or 0 for a band, which SLEPc factors by slices.
    pub factor_len: usize,
    /// Floating-point operations of one numeric factorization (the symbolic count,
    /// [`crate::cholesky::SymbolicFactor::flops`]): `factorizations * factor_flops /
    /// factor_seconds` is the factorizations' rate (0 from the SLEPc engine, whose MUMPS
    /// analysis femu does not see).
    pub factor_flops: f64,
}

impl EigenStats {
    /// The time of the solve outside its phases (shift placement, random start vectors,
    /// bookkeeping): `total_seconds` less the phases' seconds. Negative only if two phases'
    /// clocks overlapped, which would be an accounting error.
    pub fn other_seconds(&self) -> f64 {
        self.total_seconds
            - self.check_seconds
            - self.symbolic_seconds
            - self.factor_seconds
            - self.solve_seconds
            - self.orthogonalization_seconds
            - self.ritz_seconds
    }
}

/// Computed modes with their evidence.
#[derive(Debug, Clone)]
pub struct Modes {
    /// Eigenvalues `lambda_j = omega_j^2` in s^-2, ascending.
    pub values: Vec<f64>,
    /// Mode shapes in the columns, M-normalised (`phi_i^T M phi_j = delta_ij`).
    pub vectors: Mat<f64>,
    /// The residual of each mode, of the kind given in `residual_kinds`: the relative residual
    /// `||K x - lambda M x|| / ||K x||` for a mode with strain energy, the backward error for a
    /// zero-energy (rigid-body) mode, whose `K x` is round-off.
    pub residuals: Vec<f64>,
    /// Which residual `residuals` holds for each mode.
    pub residual_kinds: Vec<ResidualKind>,
    /// How many modes were asked for (`Lowest` and `Nearest`; the count by inertia for a `Band`).
    /// `values` is longer when the request ended inside a cluster of equal eigenvalues, which is
    /// returned whole.
    pub requested: usize,
    /// `||K x - lambda M x|| / ||(K - sigma M) x||` per mode, the converged quantity.
    pub shifted_residuals: Vec<f64>,
    /// The shift `sigma` used (s^-2).
    pub shift: f64,
    /// The Sturm check.
    pub sturm: SturmCheck,
    /// Work and time.
    pub stats: EigenStats,
    /// The factorization kept when [`EigenOptions::keep_factor`] asked for it and the solve had
    /// one below every returned eigenvalue; `None` otherwise.
    pub factor: Option<KeptFactor>,
}

/// A factorization of `K - sigma M` kept from a solve ([`EigenOptions::keep_factor`]), with
/// `sigma` below every eigenvalue the solve returned and no eigenvalue between `sigma` and the
/// lowest of them (`inertia().negative` of them below `sigma`, none for a semi-definite `K`).
#[derive(Debug, Clone)]
pub struct KeptFactor {
    /// The shift `sigma` (s^-2).
    pub sigma: f64,
    /// `LDL^T` of `K - sigma M`, shared by the clones of the modes.
    pub ldlt: std::sync::Arc<crate::cholesky::Ldlt>,
}

impl Modes {
    /// Frequencies in Hz, `f = sqrt(max(lambda, 0)) / (2 pi)`.
    pub fn frequencies_hz(&self) -> Vec<f64> {
        self.values
            .iter()
            .map(|l| l.max(0.0).sqrt() / (2.0 * std::f64::consts::PI))
            .collect()
    }
}
