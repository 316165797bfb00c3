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
        }
    }
}

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

/// `w += sum_i c_i v_i`, row chunks in parallel: each chunk of `w` stays in cache while the
/// vectors stream past once.
fn add_combination(w: &mut [f64], vs: &[&[f64]], cs: &[f64]) {
    const CHUNK: usize = 4096;
    w.par_chunks_mut(CHUNK).enumerate().for_each(|(k, wc)| {
        let off = k * CHUNK;
        let len = wc.len();
        for (v, c) in vs.iter().zip(cs) {
            if *c != 0.0 {
                wc.iter_mut()
                    .zip(&v[off..off + len])
                    .for_each(|(wi, vi)| *wi += c * vi);
            }
        }
    });
}

/// `w /= d`, on the rayon threads.
fn scale_in_place(w: &mut [f64], d: f64) {
    w.par_chunks_mut(1 << 15)
        .for_each(|c| c.iter_mut().for_each(|v| *v /= d));
}

/// Column `j` of a column-major matrix as a slice.
fn slice(a: &Mat<f64>, j: usize) -> &[f64] {
    a.col(j)
        .try_as_col_major()
        .expect("a column of a column-major matrix")
        .as_slice()
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The 1-norm (largest column sum of magnitudes) of a CSC matrix.
pub(crate) fn one_norm(a: &SparseMatrix) -> f64 {
    let p = a.indptr();
    let p = p.raw_storage();
    (0..a.cols())
        .map(|c| {
            a.data()[p[c]..p[c + 1]]
                .iter()
                .map(|v| v.abs())
                .sum::<f64>()
        })
        .fold(0.0, f64::max)
}

/// The residual of an eigenpair `(lambda, x)` with `mx = M x`, of the kind that means something
/// for it ([`ResidualKind`]); `k_norm`, `m_norm` are the 1-norms of `K` and `M`.
pub(crate) fn residual_of(
    k: &SparseMatrix,
    (k_norm, m_norm): (f64, f64),
    x: &[f64],
    mx: &[f64],
    lambda: f64,
) -> (f64, ResidualKind) {
    let mut kx = vec![0.0; x.len()];
    crate::csc::mul_vec(k, x, &mut kx).expect("sizes checked");
    residual_from(&kx, (k_norm, m_norm), x, mx, lambda)
}

/// [`residual_of`] from `kx = K x`.
fn residual_from(
    kx: &[f64],
    (k_norm, m_norm): (f64, f64),
    x: &[f64],
    mx: &[f64],
    lambda: f64,
) -> (f64, ResidualKind) {
    let r: Vec<f64> = kx.iter().zip(mx).map(|(k, m)| k - lambda * m).collect();
    let (rn, kn, xn) = (norm(&r), norm(kx), norm(x));
    if kn <= ZERO_ENERGY * k_norm * xn {
        let scale = (k_norm + lambda.abs() * m_norm) * xn;
        (rn / scale.max(f64::MIN_POSITIVE), ResidualKind::Backward)
    } else {
        (rn / kn, ResidualKind::Relative)
    }
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// The checks of a pencil `(K, M)` made ahead of its solves: square and of one size, finite,
/// symmetric, `M`'s pattern inside `K`'s, and the two 1-norms, with a fingerprint of both
/// matrices (their patterns and the bits of their values). [`Pencil::with_checks`] uses them only
/// for the matrices they were made on and checks any others again. An assembly makes them beside
/// its symbolic analysis, which keeps one thread busy after the values are done, so that they
/// are off the solve's critical path (docs/SCALING.md, "The analysis beside the assembly").
#[derive(Debug, Clone, PartialEq)]
pub struct PencilChecks {
    k_norm: f64,
    m_norm: f64,
    fingerprint: u64,
}

impl PencilChecks {
    /// Checks `(K, M)` as [`Pencil::new`] does.
    ///
    /// # Errors
    /// As [`Pencil::new`]'s checks.
    pub fn of(k: &SparseMatrix, m: &SparseMatrix) -> Result<Self, SparseError> {
        let (k_norm, m_norm) = check_pencil(k, m)?;
        Ok(Self {
            k_norm,
            m_norm,
            fingerprint: fingerprint(k, m)?,
        })
    }

    /// Whether these are the checks of `(k, m)`: the same fingerprint.
    pub fn are_for(&self, k: &SparseMatrix, m: &SparseMatrix) -> bool {
        fingerprint(k, m).is_ok_and(|f| f == self.fingerprint)
    }
}

/// The checks of a pencil (square, same size, finite, symmetric to 1e-10, `M`'s pattern inside
/// `K`'s) and its 1-norms `(||K||_1, ||M||_1)`.
fn check_pencil(k: &SparseMatrix, m: &SparseMatrix) -> Result<(f64, f64), SparseError> {
    crate::csc::check_symmetric(k, "K", 1e-10)?;
    crate::csc::check_symmetric(m, "M", 1e-10)?;
    if k.rows() != m.rows() {
        return Err(SparseError::DimensionMismatch {
            what: "M against K",
            expected: k.rows(),
            got: m.rows(),
        });
    }
    // M's pattern inside K's (the factorizations read both in place): checked, not stored
    crate::csc::for_entries_within(k, m, |_, _| {})?;
    Ok((one_norm(k), one_norm(m)))
}

/// A 64-bit fingerprint of `K` and `M`: each one's pattern ([`Pattern::fingerprint`]) and the
/// bits of its values ([`crate::ordering::hash_words`]).
///
/// # Errors
/// As [`Pattern::of`] (a non-square or CSR matrix).
fn fingerprint(k: &SparseMatrix, m: &SparseMatrix) -> Result<u64, SparseError> {
    use crate::ordering::{hash_mix, hash_words};
    let mut h = 2;
    for a in [k, m] {
        h = hash_mix(h, Pattern::of(a)?.fingerprint());
        h = hash_mix(h, hash_words(a.data(), |x| x.to_bits()));
    }
    Ok(h)
}

/// A pencil `(K, M)` with the symbolic analysis of `K`'s pattern, reused for every shift.
#[derive(Debug, Clone)]
pub struct Pencil<'a> {
    k: &'a SparseMatrix,
    m: &'a SparseMatrix,
    symbolic: SymbolicFactor,
    check_seconds: f64,
    symbolic_seconds: f64,
    k_norm: f64,
    m_norm: f64,
}

impl<'a> Pencil<'a> {
    /// Checks the pencil (square, same size, finite, `M`'s pattern inside `K`'s) and analyses the
    /// pattern of `K` once.
    ///
    /// # Errors
    /// [`SparseError::DimensionMismatch`], [`SparseError::NonFinite`], [`SparseError::NotSymmetric`]
    /// (relative asymmetry above 1e-10), or a failed analysis.
    pub fn new(
        k: &'a SparseMatrix,
        m: &'a SparseMatrix,
        ordering: Ordering,
    ) -> Result<Self, SparseError> {
        Self::build(k, m, Err(ordering))
    }

    /// As [`Pencil::new`] with the symbolic analysis of an earlier pencil on the same pattern
    /// (updating iterations change values, not the pattern): no new ordering, no new analysis.
    ///
    /// # Errors
    /// As [`Pencil::new`], and [`SparseError::DimensionMismatch`] when the analysis is for another
    /// dimension.
    pub fn with_symbolic(
        k: &'a SparseMatrix,
        m: &'a SparseMatrix,
        symbolic: SymbolicFactor,
    ) -> Result<Self, SparseError> {
        if symbolic.dim() != k.rows() {
            return Err(SparseError::DimensionMismatch {
                what: "symbolic analysis against K",
                expected: k.rows(),
                got: symbolic.dim(),
            });
        }
        Self::build(k, m, Ok(symbolic))
    }

    /// As [`Pencil::with_symbolic`] with the checks made ahead ([`PencilChecks`]): when they are
    /// `(k, m)`'s (the fingerprint, a pass over both matrices, agrees), they are not made again;
    /// else the pencil is checked as [`Pencil::with_symbolic`] checks it.
    ///
    /// # Errors
    /// As [`Pencil::with_symbolic`].
    pub fn with_checks(
        k: &'a SparseMatrix,
        m: &'a SparseMatrix,
        symbolic: SymbolicFactor,
        checks: &PencilChecks,
    ) -> Result<Self, SparseError> {
        let started = Instant::now();
        if symbolic.dim() != k.rows() || !checks.are_for(k, m) {
            return Self::with_symbolic(k, m, symbolic);
        }
        Ok(Self {
            k,
            m,
            symbolic,
            check_seconds: started.elapsed().as_secs_f64(),
            symbolic_seconds: 0.0,
            k_norm: checks.k_norm,
            m_norm: checks.m_norm,
        })
    }

    fn build(
        k: &'a SparseMatrix,
        m: &'a SparseMatrix,
        symbolic: Result<SymbolicFactor, Ordering>,
    ) -> Result<Self, SparseError> {
        let started = Instant::now();
        let checks = || check_pencil(k, m);
        // The analysis reads K's pattern only (its ordering graph made symmetric), so it runs
        // beside the checks of the values, which are parallel, while the ordering is one
        // thread's work; a failed check still wins over it.
        let (norms, symbolic, analysed) = match symbolic {
            Ok(s) => (checks(), Ok(s), false),
            Err(ordering) => {
                let (norms, s) = rayon::join(checks, || SymbolicFactor::new(k, ordering));
                (norms, s, true)
            }
        };
        let (k_norm, m_norm) = norms?;
        let symbolic = symbolic?;
        let both = started.elapsed().as_secs_f64();
        let symbolic_seconds = if analysed {
            symbolic.seconds().min(both)
        } else {
            0.0
        };
        let check_seconds = both - symbolic_seconds;
        Ok(Self {
            k,
            m,
            symbolic,
            check_seconds,
            symbolic_seconds,
            k_norm,
            m_norm,
        })
    }

    /// Dimension.
    pub fn dim(&self) -> usize {
        self.k.rows()
    }

    /// The symbolic analysis (ordering and fill).
    pub fn symbolic(&self) -> &SymbolicFactor {
        &self.symbolic
    }

    /// `LDL^T` of `K - sigma M`, on the shared symbolic analysis.
    ///
    /// # Errors
    /// [`SparseError::Singular`] when `sigma` is (numerically exactly) an eigenvalue.
    pub fn factor_shifted(&self, sigma: f64) -> Result<Ldlt, SparseError> {
        // K and M are read where they are (both triangles stored, M's pattern inside K's:
        // checked in `build`)
        self.symbolic.ldlt_sum(
            self.k,
            &[(self.k, 1.0), (self.m, -sigma)],
            || self.shifted_values(sigma),
            "K - sigma M",
        )
    }

    /// The values of `K - sigma M` on `K`'s pattern (what [`Pencil::factor_shifted`] factors).
    pub fn shifted_values(&self, sigma: f64) -> Vec<f64> {
        let mut values = self.k.data().to_vec();
        crate::csc::for_entries_within(self.k, self.m, |pm, pk| {
            values[pk] -= sigma * self.m.data()[pm];
        })
        .expect("M's pattern inside K's, checked by the pencil");
        values
    }

    /// `LDL^T` of `K - sigma M` with row and column `pinned` replaced by those of the identity
    /// (scaled by `|K_pp|`): the matrix of Nelson's method for eigenvector derivatives, which is
    /// nonsingular at a simple eigenvalue `sigma` when `pinned` is a DOF where the eigenvector is
    /// large. Same pattern, same symbolic analysis.
    ///
    /// # Errors
    /// [`SparseError::DimensionMismatch`] for `pinned` out of range, [`SparseError::Singular`]
    /// when the pinned matrix is still singular (a repeated eigenvalue).
    pub fn factor_shifted_pinned(&self, sigma: f64, pinned: usize) -> Result<Ldlt, SparseError> {
        let n = self.dim();
        if pinned >= n {
            return Err(SparseError::DimensionMismatch {
                what: "pinned DOF against the dimension",
                expected: n,
                got: pinned,
            });
        }
        let mut values = self.shifted_values(sigma);
        let scale = self
            .k
            .get(pinned, pinned)
            .map_or(1.0, |v| v.abs().max(f64::MIN_POSITIVE));
        let p = self.k.indptr();
        let p = p.raw_storage();
        for c in 0..n {
            for k in p[c]..p[c + 1] {
                let r = self.k.indices()[k];
                if r == pinned || c == pinned {
                    values[k] = if r == c { scale } else { 0.0 };
                }
            }
        }
        self.symbolic
            .ldlt_values(self.k, &values, "K - lambda M (pinned)")
    }

    /// The number of eigenvalues below `sigma` (Sturm count by inertia).
    ///
    /// # Errors
    /// As [`Pencil::factor_shifted`].
    pub fn count_below(&self, sigma: f64) -> Result<usize, SparseError> {
        // the inertia alone: no factor is kept (SymbolicFactor::inertia_values)
        Ok(self
            .symbolic
            .inertia_sum(
                self.k,
                &[(self.k, 1.0), (self.m, -sigma)],
                || self.shifted_values(sigma),
                "K - sigma M",
            )?
            .negative)
    }

    /// `mean_i |K_ii| / M_ii` (terms with `M_ii <= 0` count as zero): the pencil's typical
    /// eigenvalue scale in s^-2, from which thresholds for "zero" eigenvalues are set.
    pub fn diagonal_ratio(&self) -> f64 {
        let n = self.k.rows();
        (0..n)
            .map(|i| {
                let kd = self.k.get(i, i).copied().unwrap_or(0.0).abs();
                let md = self.m.get(i, i).copied().unwrap_or(0.0);
                if md > 0.0 { kd / md } else { 0.0 }
            })
            .sum::<f64>()
            / n.max(1) as f64
    }

    /// `(||K||_1, ||M||_1)`, the largest absolute column sums.
    pub fn norms(&self) -> (f64, f64) {
        (self.k_norm, self.m_norm)
    }

    /// A negative shift for the lowest modes: `-1e-10 mean(K_ii / M_ii)`, far below the first
    /// elastic eigenvalue of any practical structure yet well away from the rigid-body zeros.
    fn lowest_shift(&self) -> f64 {
        -(1e-10 * self.diagonal_ratio()).max(f64::MIN_POSITIVE)
    }

    /// The tolerance within which two computed eigenvalues near `v` are one repeated eigenvalue,
    /// `1e-8 |v| + 1e-12 ||K||_1 / ||M||_1`. The second term is the resolution of an inertia count
    /// (the `LDL^T` of `K - s M` is backward stable to round-off times `||K||`): an end of a counted
    /// interval is never placed closer than this to a computed eigenvalue.
    pub fn tie_tolerance(&self, v: f64) -> f64 {
        1e-8 * v.abs() + 1e-12 * self.k_norm / self.m_norm.max(f64::MIN_POSITIVE)
    }

    /// Computes the requested modes; see the module documentation.
    ///
    /// Repeated eigenvalues are handled whole: a cluster of eigenvalues equal within
    /// [`Pencil::tie_tolerance`] at the end of a `Lowest` or `Nearest` request is completed (the
    /// result then holds more than the requested count, [`Modes::requested`] says how many were
    /// asked for), and the ends of every counted interval lie in gaps of the spectrum, never inside
    /// a cluster. A `Band` is closed: its ends are widened by the tie tolerance, so an eigenvalue on
    /// an end (zero for a free-free model) is inside. A `Nearest` shift that falls exactly on an
    /// eigenvalue is factored a little off it; a `Nearest` shift at or below zero is a `Lowest`
    /// request (`K` is positive semi-definite).
    ///
    /// # Errors
    /// [`SparseError::TooManyModes`] for a count above the dimension,
    /// [`SparseError::InvalidRequest`] for a non-finite shift, an empty band, a block size
    /// outside `1..=`[`MAX_BLOCK`] or a tolerance outside `(0, 1)`,
    /// [`SparseError::NoConvergence`] (with the number converged) after `max_restarts`,
    /// [`SparseError::SturmMismatch`] when the count by inertia and the pairs found still disagree
    /// after the retries, and [`SparseError::NotPositiveDefinite`] when `K` has negative
    /// eigenvalues below the lowest-mode shift.
    pub fn solve(&self, which: Which, params: &EigenOptions) -> Result<Modes, SparseError> {
        let started = Instant::now();
        check_options(params)?;
        let mut stats = EigenStats {
            check_seconds: self.check_seconds,
            symbolic_seconds: self.symbolic_seconds,
            factor_len: self.symbolic.factor_len(),
            factor_flops: self.symbolic.flops(),
            ..Default::default()
        };
        let hint = params
            .lowest_shift_hint
            .filter(|h| h.is_finite() && *h < -self.tie_tolerance(0.0));
        if let (Which::Lowest(_), Some(hint)) = (which, hint) {
            let hinted = EigenOptions {
                max_restarts: params.max_restarts.min(HINTED_RESTARTS),
                ..params.clone()
            };
            match self.solve_counted(which, &hinted, Some(hint), &mut stats, started) {
                // a misplaced hint: start again as if none had been given; `stats` keeps the
                // work already done
                Err(
                    SparseError::NotPositiveDefinite { .. } | SparseError::NoConvergence { .. },
                ) => {}
                r => return r,
            }
        }
        self.solve_counted(which, params, None, &mut stats, started)
    }

    /// The zero-energy modes in the span of `hint`'s vectors, M-orthonormal:
    /// the Rayleigh-Ritz pairs of `(K, M)` on that span (docs/MATH.md, "Known null vectors")
    /// whose backward error is below [`BACKWARD_LOCK`], the test a pair locked by the iteration
    /// meets. Combinations the supports or constraints load are not zero-energy and are dropped.
    fn zero_energy_pairs(&self, hint: &NullSpaceHint) -> Result<Vec<Known>, SparseError> {
        let r = hint.vectors();
        if r.nrows() != self.dim() {
            return Err(SparseError::InvalidRequest {
                reason: format!(
                    "the null-space hint has {} rows, the pencil {} DOFs",
                    r.nrows(),
                    self.dim()
                ),
            });
        }
        if let Some((i, j)) = (0..r.ncols())
            .flat_map(|j| (0..r.nrows()).map(move |i| (i, j)))
            .find(|&(i, j)| !r[(i, j)].is_finite())
        {
            return Err(SparseError::InvalidRequest {
                reason: format!("the null-space hint's vector {j} is not finite at DOF {i}"),
            });
        }
        let c = r.ncols();
        if c == 0 {
            return Ok(vec![]);
        }
        let kr = crate::csc::sym_mul_mat(self.k, r)?;
        let mr = crate::csc::sym_mul_mat(self.m, r)?;
        let (kc, mc) = (r.transpose() * &kr, r.transpose() * &mr);
        // an M-orthonormal basis B of the span (dependent candidates dropped), then the
        // eigenpairs of B^T K_c B, ascending
        let (m_values, m_vectors) = crate::dense::symmetric_eigen(mc.as_ref())?;
        let top = m_values.last().copied().unwrap_or(0.0);
        let keep: Vec<usize> = (0..c).filter(|&i| m_values[i] > 1e-12 * top).collect();
        if keep.is_empty() {
            return Ok(vec![]);
        }
        let b = Mat::from_fn(c, keep.len(), |i, j| {
            m_vectors[(i, keep[j])] / m_values[keep[j]].sqrt()
        });
        let (_, y) = crate::dense::symmetric_eigen((b.transpose() * &kc * &b).as_ref())?;
        let coef = &b * &y;
        let (x, kx, mx) = (r * &coef, &kr * &coef, &mr * &coef);
        let mut pairs = Vec::new();
        for j in 0..coef.ncols() {
            let col = |a: &Mat<f64>| -> Vec<f64> { a.col(j).iter().copied().collect() };
            let (x, kx, mx) = (col(&x), col(&kx), col(&mx));
            let lambda = dot(&kx, &x) / dot(&mx, &x).max(f64::MIN_POSITIVE);
            let res: Vec<f64> = kx.iter().zip(&mx).map(|(k, m)| k - lambda * m).collect();
            let r_norm = norm(&res);
            let eta = r_norm
                / ((self.k_norm + lambda.abs() * self.m_norm) * norm(&x)).max(f64::MIN_POSITIVE);
            if eta < BACKWARD_LOCK {
                let (kk, km, mm) = (dot(&kx, &kx), dot(&kx, &mx), dot(&mx, &mx));
                pairs.push(Known {
                    x,
                    mx,
                    lambda,
                    r_norm,
                    kk,
                    km,
                    mm,
                });
            }
        }
        Ok(pairs)
    }

    /// [`Pencil::solve`] from the lowest-mode shift `hint` when given (the probe is then
    /// skipped, and a hint not below the spectrum is [`SparseError::NotPositiveDefinite`]). The
    /// work is added to `stats` whatever the outcome; the result's total time runs from
    /// `started`.
    fn solve_counted(
        &self,
        which: Which,
        params: &EigenOptions,
        hint: Option<f64>,
        stats: &mut EigenStats,
        started: Instant,
    ) -> Result<Modes, SparseError> {
        let n = self.dim();
        let requested = match which {
            Which::Lowest(k) => k,
            Which::Nearest { count, .. } => count,
            Which::Band { .. } => 0,
        };
        if requested > n {
            return Err(SparseError::TooManyModes { requested, dim: n });
        }
        if let Which::Nearest { shift, count } = which
            && shift.is_finite()
            && shift <= self.tie_tolerance(0.0)
        {
            // K is positive semi-definite: the eigenvalues nearest a shift at or below zero are the
            // lowest ones, found by the lowest-mode strategy (a shift below the spectrum, away from
            // the rigid-body zeros) instead of a shift on the zeros
            return self.solve(Which::Lowest(count), params);
        }
        let (mut sigma, band) = match which {
            Which::Lowest(_) => (hint.unwrap_or_else(|| self.lowest_shift()), None),
            Which::Nearest { shift, .. } => {
                if !shift.is_finite() {
                    return Err(SparseError::InvalidRequest {
                        reason: format!("the shift {shift} is not a finite number"),
                    });
                }
                (shift, None)
            }
            Which::Band { lo, hi } => {
                if !(lo.is_finite() && hi.is_finite() && lo < hi) {
                    return Err(SparseError::InvalidRequest {
                        reason: format!(
                            "the band [{lo:e}, {hi:e}] s^-2 needs finite ends with the lower below the upper"
                        ),
                    });
                }
                let (lo, hi) = (lo - self.tie_tolerance(lo), hi + self.tie_tolerance(hi));
                let t = Instant::now();
                let (nl, nh) = (self.count_below(lo)?, self.count_below(hi)?);
                stats.factor_seconds += t.elapsed().as_secs_f64();
                stats.factorizations += 2;
                (0.5 * (lo + hi), Some((lo, hi, nh - nl)))
            }
        };
        let mut want = band.map_or(requested, |b| b.2);
        // the nearest modes are chosen by their distance to the shift the user gave
        let target = sigma;
        if !matches!(which, Which::Lowest(_)) {
            // A shift given by the user is often a computed eigenvalue, and a band's midpoint can
            // be one: with K - sigma M singular to round-off, the solves amplify that eigenvector
            // by 1e16 and every other direction drowns in its round-off. Factor a little off it
            // (1e-3 relative, by an irrational factor so that no eigenvalue sits there by
            // symmetry); the modes are still chosen by their distance to the shift given.
            let scale = sigma
                .abs()
                .max(1e-3 * self.k_norm / self.m_norm.max(f64::MIN_POSITIVE));
            sigma += SHIFT_OFFSET * scale;
        }
        let t = Instant::now();
        let mut op = match self.factor_shifted(sigma) {
            Err(SparseError::Singular { .. }) if !matches!(which, Which::Lowest(_)) => {
                // the shift is numerically exactly an eigenvalue: step off it
                sigma += self.tie_tolerance(sigma);
                stats.factorizations += 1;
                self.factor_shifted(sigma)?
            }
            r => r?,
        };
        stats.factor_seconds += t.elapsed().as_secs_f64();
        stats.factorizations += 1;
        // the probe's Krylov basis, continued by the run when the shift stays
        let mut probed = None;
        // zero-energy modes given by the caller, locked before any solve
        let mut known = match (which, &params.null_space_hint) {
            (Which::Lowest(_), Some(h)) => {
                let t = Instant::now();
                let pairs = self.zero_energy_pairs(h)?;
                stats.ritz_seconds += t.elapsed().as_secs_f64();
                pairs
            }
            _ => vec![],
        };
        if matches!(which, Which::Lowest(_)) && op.inertia().negative > 0 {
            return Err(SparseError::NotPositiveDefinite {
                matrix: "K (eigenvalues below the negative lowest-mode shift)",
                index: op.inertia().negative,
            });
        }
        // where to refactor if a free-free run at the tiny shift does not converge
        let mut fallback: Option<f64> = None;
        // the pairs a run finds beyond a Lowest or Nearest request (none for a band)
        let guard = if band.is_some() { 0 } else { 3.min(n - want) };
        // a hinted shift is already placed: no probe; nor when the given zero-energy pairs already
        // hold every pair the run wants (the request and its guard pairs)
        let covered = known.len() >= want + guard;
        if matches!(which, Which::Lowest(_)) && hint.is_none() && !covered {
            // A short first Lanczos cycle at the tiny shift (the probe), continued by the run: it
            // tells whether the lowest eigenvalues are near zero (rigid-body modes). "Near zero"
            // is relative to the tiny shift itself (1e-10 mean(K_ii / M_ii)): rigid-body
            // eigenvalues come out at round-off (about 1e-16 lambda_max), elastic ones far above
            // 1e3 |sigma|. A probe that sees only near-zero values (as many rigid-body modes as
            // its better half holds) is repeated with a larger basis. The run stays at the tiny
            // shift: once it has locked the rigid-body modes it starts afresh deflated against
            // them ([`CLOSE_LOCK`]), so a free-free model factors twice (the run and the Sturm
            // count), not three times as when the shift was moved to half the first elastic
            // eigenvalue (docs/SCALING.md, "One shift for a free-free model").
            let zero_like = 1e3 * sigma.abs();
            let first_size = (3 * params.block_size.max(1))
                .max(12)
                .max((want + 3).min(24));
            for size in [first_size, 2 * first_size, 4 * first_size] {
                let mut probe = Lanczos::new(self, op, sigma, params, &known);
                let guess = probe.estimate((want + 3).max(size / 2), size, stats);
                // the fallback shift: half the first clearly nonzero eigenvalue
                fallback = guess
                    .iter()
                    .copied()
                    .find(|v| *v > zero_like)
                    .filter(|_| guess.iter().any(|v| v.abs() <= zero_like))
                    .map(|first| -0.5 * first)
                    .filter(|better| *better < sigma);
                if probe.stop {
                    return Err(SparseError::Interrupted {
                        solved_vectors: stats.solved_vectors,
                    });
                }
                op = probe.op.take().expect("the probe keeps its factor");
                probed = probe.probed.take();
                let zeros = guess.iter().filter(|v| v.abs() <= zero_like).count();
                if zeros == 0 || zeros < guess.len() || guess.len() >= n {
                    break;
                }
            }
            if let Some(better) = fallback {
                // Where the first elastic eigenvalue lies more than STAY_BELOW times the tiny
                // shift above it (a coarse model, whose largest eigenvalue, and so the tiny shift,
                // is close to the smallest), the rigid-body modes do not reach a backward error
                // of 1e-13 at the tiny shift: refactor at half the first elastic eigenvalue now.
                if -2.0 * better > STAY_BELOW * sigma.abs() {
                    // release the old factor first (peak memory: one factor)
                    drop(op);
                    (op, sigma) = self.refactor_below(better, sigma, stats)?;
                    probed = None;
                    fallback = None;
                }
            }
        }
        if want == 0 {
            return Ok(Modes {
                values: vec![],
                vectors: Mat::zeros(n, 0),
                residuals: vec![],
                residual_kinds: vec![],
                shifted_residuals: vec![],
                requested,
                shift: sigma,
                sturm: SturmCheck {
                    lower: band.map(|b| b.0),
                    upper: band.map_or(sigma, |b| b.1),
                    count: 0,
                    returned: 0,
                },
                stats: stats.clone(),
            });
        }
        let mut lanczos = Lanczos::new(self, op, sigma, params, &known);
        lanczos.probed = probed;
        if fallback.is_some() {
            // measured: 0 restarts on the free-free plates of 47,628 and 199,200 DOF; a run that
            // needs more is moved to the fallback shift before it wastes many cycles
            lanczos.params.max_restarts = params.max_restarts.min(TINY_SHIFT_RESTARTS);
        } else {
            // the run holds its own copy, and only a run moved to the fallback shift needs them
            // again (19 MB at 199,200 DOF)
            known = Vec::new();
        }
        let mut attempts = 0;
        loop {
            if lanczos.op.is_none() {
                // released for a Sturm check that found missed modes: factor the shift again
                let t = Instant::now();
                lanczos.op = Some(self.factor_shifted(sigma)?);
                stats.factor_seconds += t.elapsed().as_secs_f64();
                stats.factorizations += 1;
            }
            match lanczos.run((want + guard).min(n), stats) {
                Err(SparseError::NoConvergence { .. }) if fallback.is_some() => {
                    // The tiny shift did not work for this free-free model (a small one with
                    // repeated rigid-body modes did not converge): refactor at half the first
                    // elastic eigenvalue and start again, as a solve did before; the work of
                    // both runs is counted.
                    let better = fallback.take().expect("checked");
                    drop(lanczos);
                    let op;
                    (op, sigma) = self.refactor_below(better, sigma, stats)?;
                    lanczos = Lanczos::new(self, op, sigma, params, &known);
                    continue;
                }
                r => r?,
            }
            let (sel, check) = match band {
                Some((lo, hi, count)) => {
                    let sel: Vec<usize> = (0..lanczos.values.len())
                        .filter(|i| lanczos.values[*i] >= lo && lanczos.values[*i] <= hi)
                        .collect();
                    let returned = sel.len();
                    let check = SturmCheck {
                        lower: Some(lo),
                        upper: hi,
                        count,
                        returned,
                    };
                    (sel, check)
                }
                None => {
                    let nearest = matches!(which, Which::Nearest { .. });
                    let centre = if nearest { target } else { sigma };
                    let (sel, lower, upper) =
                        self.select(&lanczos.values, requested, centre, nearest);
                    // one factor alive at a time: release the iteration's before the check's
                    lanczos.op = None;
                    let t = Instant::now();
                    let count = self.count_below(upper)?
                        - lower.map(|l| self.count_below(l)).transpose()?.unwrap_or(0);
                    stats.factor_seconds += t.elapsed().as_secs_f64();
                    stats.factorizations += 1 + usize::from(lower.is_some());
                    let returned = sel.len();
                    let check = SturmCheck {
                        lower,
                        upper,
                        count,
                        returned,
                    };
                    (sel, check)
                }
            };
            if check.verified() {
                let mut modes = lanczos.finish(sel, sigma, check, requested, stats.clone());
                modes.stats.total_seconds =
                    self.check_seconds + self.symbolic_seconds + started.elapsed().as_secs_f64();
                return Ok(modes);
            }
            attempts += 1;
            if check.count < check.returned || attempts > 8 || lanczos.values.len() >= n {
                return Err(SparseError::SturmMismatch {
                    interval: check.interval(),
                    count: check.count,
                    returned: check.returned,
                });
            }
            // Missed modes (repeated eigenvalues): ask for more, restarting from random vectors
            // deflated against everything found.
            want = lanczos.values.len() + (check.count - check.returned);
            lanczos.force_random_start = true;
        }
    }

    /// The factor at `better` (half the first elastic eigenvalue of a free-free model) and that
    /// shift, or, in the rare case `better` is not below the spectrum, the factor at `sigma`
    /// again; the factorizations are counted in `stats`.
    fn refactor_below(
        &self,
        better: f64,
        sigma: f64,
        stats: &mut EigenStats,
    ) -> Result<(Ldlt, f64), SparseError> {
        let t = Instant::now();
        let candidate = self.factor_shifted(better)?;
        stats.factorizations += 1;
        let out = if candidate.inertia().negative == 0 {
            (candidate, better)
        } else {
            drop(candidate);
            stats.factorizations += 1;
            (self.factor_shifted(sigma)?, sigma)
        };
        stats.factor_seconds += t.elapsed().as_secs_f64();
        Ok(out)
    }

    /// From the locked `values`, the `requested` nearest `sigma` with any cluster at either end
    /// completed, and the ends of the interval to count: in the gaps to the nearest values found
    /// outside (or a step of `max(1e-6 scale, 2 tie)` beyond when none was found). `lower` is
    /// `None` (minus infinity) unless `nearest`.
    fn select(
        &self,
        values: &[f64],
        requested: usize,
        sigma: f64,
        nearest: bool,
    ) -> (Vec<usize>, Option<f64>, f64) {
        let mut order: Vec<usize> = (0..values.len()).collect();
        order.sort_by(|a, b| {
            (values[*a] - sigma)
                .abs()
                .total_cmp(&(values[*b] - sigma).abs())
        });
        let mut sel: Vec<usize> = order[..requested.min(order.len())].to_vec();
        let mut rest: Vec<usize> = order[sel.len()..].to_vec();
        let close = |a: f64, b: f64| (a - b).abs() <= self.tie_tolerance(a.abs().max(b.abs()));
        let ends = |sel: &[usize]| {
            sel.iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), i| {
                    (lo.min(values[*i]), hi.max(values[*i]))
                })
        };
        loop {
            let (bottom, top) = ends(&sel);
            let tied = rest
                .iter()
                .position(|&i| close(values[i], top) || (nearest && close(values[i], bottom)));
            match tied {
                Some(p) => sel.push(rest.remove(p)),
                None => break,
            }
        }
        let (bottom, top) = ends(&sel);
        let scale = values.iter().fold(sigma.abs(), |m, v| m.max(v.abs()));
        let step = |v: f64| (1e-6 * scale.max(v.abs())).max(2.0 * self.tie_tolerance(v));
        let above = rest
            .iter()
            .map(|i| values[*i])
            .filter(|v| *v > top)
            .fold(f64::INFINITY, f64::min);
        let upper = if above.is_finite() {
            0.5 * (top + above)
        } else {
            top + step(top)
        };
        let lower = nearest.then(|| {
            let below = rest
                .iter()
                .map(|i| values[*i])
                .filter(|v| *v < bottom)
                .fold(f64::NEG_INFINITY, f64::max);
            if below.is_finite() {
                0.5 * (bottom + below)
            } else {
                bottom - step(bottom)
            }
        });
        (sel, lower, upper)
    }
}

/// Computes modes of `(K, M)`: a one-call front end of [`Pencil`].
///
/// ```
/// use femu_sparse::eigen::{eigs, EigenOptions, Which};
/// use femu_sparse::SparseMatrix;
/// // A spring chain fixed at one end: K tridiagonal (2, -1), M = I.
/// let n = 50;
/// let mut t = sprs::TriMat::new((n, n));
/// for i in 0..n {
///     t.add_triplet(i, i, if i + 1 < n { 2.0 } else { 1.0 });
///     if i + 1 < n { t.add_triplet(i, i + 1, -1.0); t.add_triplet(i + 1, i, -1.0); }
/// }
/// let k: SparseMatrix = t.to_csc();
/// let m = SparseMatrix::eye(n);
/// let modes = eigs(&k, &m, Which::Lowest(3), &EigenOptions::default()).unwrap();
/// // lambda_j = 4 sin^2((2j - 1) pi / (2 (2n + 1)))
/// for (j, l) in modes.values.iter().enumerate() {
///     let x = ((2 * j + 1) as f64 * std::f64::consts::PI / (2.0 * (2 * n + 1) as f64)).sin();
///     assert!((l / (4.0 * x * x) - 1.0).abs() < 1e-10);
/// }
/// assert!(modes.sturm.verified());
/// ```
///
/// # Errors
/// As [`Pencil::new`] and [`Pencil::solve`].
pub fn eigs(
    k: &SparseMatrix,
    m: &SparseMatrix,
    which: Which,
    params: &EigenOptions,
) -> Result<Modes, SparseError> {
    match &params.engine {
        crate::slepc::Engine::Femu => Pencil::new(k, m, params.ordering)?.solve(which, params),
        crate::slepc::Engine::Slepc(opts) => crate::slepc::solve(k, m, which, params, opts),
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
fn check_options(params: &EigenOptions) -> Result<(), SparseError> {
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

/// Ritz values and vectors of the symmetrised projection, ordered by decreasing `|theta|`.
fn rayleigh_ritz(
    h: &[Vec<f64>],
    m: usize,
) -> (nalgebra::SymmetricEigen<f64, nalgebra::Dyn>, Vec<usize>) {
    let hs = nalgebra::DMatrix::<f64>::from_fn(m, m, |i, j| {
        let a = h[j].get(i).copied().unwrap_or(0.0);
        let b = h[i].get(j).copied().unwrap_or(0.0);
        0.5 * (a + b)
    });
    let eig = nalgebra::SymmetricEigen::new(hs);
    let mut order: Vec<usize> = (0..m).collect();
    order.sort_by(|a, b| {
        eig.eigenvalues[*b]
            .abs()
            .total_cmp(&eig.eigenvalues[*a].abs())
    });
    (eig, order)
}

/// A hook of [`with_interrupt`].
type Hook = Box<dyn FnMut(usize) -> bool>;

thread_local! {
    /// The hook of [`with_interrupt`] on this thread.
    static INTERRUPT: std::cell::RefCell<Option<Hook>> = const { std::cell::RefCell::new(None) };
}

/// Runs `f` with `check` called at the eigensolver's iteration boundaries on this thread (after
/// every block of solved vectors, with the number of vectors solved so far in that solve): when
/// it returns `true` the solve stops with [`SparseError::Interrupted`]. For progress reports and
/// Ctrl-C in bindings (the Python module); the previous hook is restored when `f` returns or
/// panics. Solves run from other threads (inside `f`'s own parallel work) are not affected.
pub fn with_interrupt<T>(check: impl FnMut(usize) -> bool + 'static, f: impl FnOnce() -> T) -> T {
    struct Restore(Option<Hook>);
    impl Drop for Restore {
        fn drop(&mut self) {
            let previous = self.0.take();
            INTERRUPT.with(|c| *c.borrow_mut() = previous);
        }
    }
    let previous = INTERRUPT.with(|c| c.borrow_mut().replace(Box::new(check)));
    let _restore = Restore(previous);
    f()
}

/// Whether the hook of [`with_interrupt`] asks to stop after `solved` vectors.
fn interrupted(solved: usize) -> bool {
    INTERRUPT.with(|c| c.borrow_mut().as_mut().is_some_and(|f| f(solved)))
}

/// Vectors of length `n` stored one after the other (column-major, contiguous), so that a set of
/// them is a matrix for GEMM (`faer`'s blocked, parallel kernels) and each one a slice.
#[derive(Debug, Clone, Default)]
struct Columns {
    n: usize,
    data: Vec<f64>,
}

impl Columns {
    fn new(n: usize) -> Self {
        Self { n, data: vec![] }
    }
    fn len(&self) -> usize {
        self.data.len().checked_div(self.n).unwrap_or(0)
    }
    fn col(&self, j: usize) -> &[f64] {
        &self.data[j * self.n..(j + 1) * self.n]
    }
    /// Appends a column, written on the rayon threads: the first write to the basis's reserved
    /// storage is where the operating system provides its pages (a page fault and a cleared 4 KiB
    /// page each), and page faults on different threads proceed in parallel (docs/SCALING.md,
    /// "The block within itself, the Ritz vectors' products and the input checks").
    fn push(&mut self, v: &[f64]) {
        self.data
            .par_extend(v.par_iter().with_min_len(1 << 15).copied());
    }
    /// Appends `v / d` (as [`Columns::push`]).
    fn push_divided(&mut self, v: &[f64], d: f64) {
        self.data
            .par_extend(v.par_iter().with_min_len(1 << 15).map(|x| x / d));
    }
    /// Appends the columns of `a` (as [`Columns::push`]).
    fn push_mat(&mut self, a: faer::MatRef<'_, f64>) {
        for j in 0..a.ncols() {
            let col = a.col(j).try_as_col_major().expect("contiguous").as_slice();
            self.push(col);
        }
    }
    /// Appends `cols` zero columns (as [`Columns::push`]).
    fn push_zeros(&mut self, cols: usize) {
        self.data
            .par_extend(rayon::iter::repeat_n(0.0, cols * self.n).with_min_len(1 << 15));
    }
    /// Drops the columns from `cols` on.
    fn truncate(&mut self, cols: usize) {
        self.data.truncate(cols * self.n);
    }
    /// The columns before `from`, and the columns from `from` on, writable.
    fn split_mut(&mut self, from: usize) -> (faer::MatRef<'_, f64>, faer::MatMut<'_, f64>) {
        let n = self.n;
        let (head, tail) = self.data.split_at_mut(from * n);
        let cols = tail.len() / n.max(1);
        (
            faer::MatRef::from_column_major_slice(head, n, from),
            faer::MatMut::from_column_major_slice_mut(tail, n, cols),
        )
    }
    /// Columns `a..b` as a matrix.
    fn range(&self, a: usize, b: usize) -> faer::MatRef<'_, f64> {
        faer::MatRef::from_column_major_slice(&self.data[a * self.n..b * self.n], self.n, b - a)
    }
    fn mat(&self) -> faer::MatRef<'_, f64> {
        self.range(0, self.len())
    }
    fn clear(&mut self) {
        self.data.clear();
    }
    /// Room for `cols` columns in all, allocated at once: a vector that doubles as it grows holds
    /// the old and the new storage together while it moves (glibc serves blocks below its mmap
    /// threshold, which rises to 32 MB, from the heap, where a reallocation copies).
    fn reserve(&mut self, cols: usize) {
        let total = cols * self.n;
        if total > self.data.capacity() {
            self.data.reserve_exact(total - self.data.len());
        }
    }
    /// Replaces the first `m` columns `V` by the `k` columns `V S` (`s` is `m x k`, `k <= m`);
    /// the columns after them follow. In place, by blocks of rows (each row of `V S` needs only
    /// that row of `V`), on the rayon threads: no copy of the basis is held (docs/SCALING.md,
    /// "Memory").
    fn rotate_front(&mut self, m: usize, s: faer::MatRef<'_, f64>) {
        let (n, k) = (self.n, s.ncols());
        debug_assert!(s.nrows() == m && k <= m && m <= self.len());
        right_multiply_in_place(
            faer::MatMut::from_column_major_slice_mut(&mut self.data[..m * n], n, m),
            s,
        );
        self.data.drain(k * n..m * n);
    }
}

/// `w -= v c` with `c = mv^T w`: one pass of block classical Gram-Schmidt of the columns of `w`
/// against the `M`-orthonormal columns of `v` (whose `M` images are `mv`), as two GEMMs; returns
/// `c` (by [`inner_products`]).
fn project_out(
    v: faer::MatRef<'_, f64>,
    mv: faer::MatRef<'_, f64>,
    w: faer::MatMut<'_, f64>,
) -> Mat<f64> {
    if v.ncols() == 0 {
        return Mat::<f64>::zeros(0, w.ncols());
    }
    let c = inner_products(mv, w.as_ref());
    let par = faer::get_global_parallelism();
    faer::linalg::matmul::matmul(w, faer::Accum::Add, v, c.as_ref(), -1.0, par);
    c
}

/// `a^T b` for two tall matrices of `n` rows and a few columns.
///
/// faer's GEMM does not split the long inner dimension (`n` rows against a few columns) between
/// threads, so the rows are split here, [`PROJECT_ROWS`] or more per thread, each part's
/// products computed on one thread and the parts added in order (the same sum for the same
/// number of threads). Coefficients of the 199,200-DOF plate's 20-mode solve 0.27-0.28 s ->
/// 0.15-0.17 s (docs/SCALING.md, "Sparse products by blocks of known width").
fn inner_products(a: faer::MatRef<'_, f64>, b: faer::MatRef<'_, f64>) -> Mat<f64> {
    use faer::Accum;
    use faer::linalg::matmul::matmul;
    let par = faer::get_global_parallelism();
    let n = b.nrows();
    let parts = rayon::current_num_threads().min(n / PROJECT_ROWS).max(1);
    let size = n.div_ceil(parts);
    let partial: Vec<Mat<f64>> = (0..parts)
        .into_par_iter()
        .map(|p| {
            let (lo, len) = (p * size, size.min(n - p * size));
            let mut part = Mat::<f64>::zeros(a.ncols(), b.ncols());
            matmul(
                part.as_mut(),
                Accum::Replace,
                a.subrows(lo, len).transpose(),
                b.subrows(lo, len),
                1.0,
                if parts == 1 { par } else { faer::Par::Seq },
            );
            part
        })
        .collect();
    let mut c = Mat::<f64>::zeros(a.ncols(), b.ncols());
    for part in partial {
        c += part;
    }
    c
}

/// `v <- v s` in place (`s` is `m x k` for `v`'s `m` columns, `k <= m`; the result is the first
/// `k` columns of `v`), by blocks of rows on the rayon threads: each row of `v s` needs only that
/// row of `v`, so no second copy of `v` is held.
fn right_multiply_in_place(v: faer::MatMut<'_, f64>, s: faer::MatRef<'_, f64>) {
    const ROWS: usize = 4096;
    if v.nrows() > ROWS {
        let half = v.nrows() / 2;
        let (top, bottom) = v.split_at_row_mut(half);
        rayon::join(
            || right_multiply_in_place(top, s),
            || right_multiply_in_place(bottom, s),
        );
        return;
    }
    right_multiply_rows(v, s);
}

/// [`right_multiply_in_place`] on the calling thread, through a copy of the product.
fn right_multiply_rows(v: faer::MatMut<'_, f64>, s: faer::MatRef<'_, f64>) {
    let mut t = Mat::<f64>::zeros(v.nrows(), s.ncols());
    leaf_product(t.as_mut(), false, v.as_ref(), s, 1.0);
    v.subcols_mut(0, s.ncols()).copy_from(&t);
}

/// The upper triangular `R` with `R^T R = g` (`g` symmetric, the mean of its two triangles), or
/// `None` when a pivot is not above `rel^2` times its diagonal entry of `g` (the column is
/// dependent on the ones before it to that measure) or `g` is not finite.
fn small_cholesky(g: &Mat<f64>, rel: f64) -> Option<Mat<f64>> {
    let k = g.nrows();
    let mut r = Mat::<f64>::zeros(k, k);
    for j in 0..k {
        let d = g[(j, j)] - (0..j).map(|i| r[(i, j)] * r[(i, j)]).sum::<f64>();
        if !(g[(j, j)] > 0.0 && g[(j, j)].is_finite() && d > rel * rel * g[(j, j)]) {
            return None;
        }
        r[(j, j)] = d.sqrt();
        for c in j + 1..k {
            let e =
                0.5 * (g[(j, c)] + g[(c, j)]) - (0..j).map(|i| r[(i, j)] * r[(i, c)]).sum::<f64>();
            r[(j, c)] = e / r[(j, j)];
        }
    }
    Some(r)
}

/// The inverse of an upper triangular matrix with a nonzero diagonal.
fn upper_inverse(r: &Mat<f64>) -> Mat<f64> {
    let k = r.nrows();
    let mut inv = Mat::<f64>::zeros(k, k);
    for c in 0..k {
        inv[(c, c)] = 1.0 / r[(c, c)];
        for i in (0..c).rev() {
            let s: f64 = (i + 1..=c).map(|l| r[(i, l)] * inv[(l, c)]).sum();
            inv[(i, c)] = -s / r[(i, i)];
        }
    }
    inv
}

/// The fewest rows of a leaf of [`fold_rows`] (a leaf has fewer than twice as many): a block of
/// four columns and its images take 128 to 256 KiB there, so that the several steps of one pass
/// find the leaf's rows of the block in the core's cache while the basis streams past once.
const LEAF_ROWS: usize = 2048;

/// `leaf(first, w_rows, mw_rows)` over the rows of a block `w` and of its images `mw`, cut into
/// leaves of [`LEAF_ROWS`] to `2 LEAF_ROWS` rows (`first` is a leaf's first row), on the rayon
/// threads; the leaves' matrices are added in a tree fixed by the number of rows, so the sums are
/// the same for any number of threads. One such pass reads each row of the block once for all
/// its steps (docs/SCALING.md, "Orthogonalisation by leaves of rows").
fn fold_rows(
    first: usize,
    w: faer::MatMut<'_, f64>,
    mw: faer::MatMut<'_, f64>,
    leaf: &(impl Fn(usize, faer::MatMut<'_, f64>, faer::MatMut<'_, f64>) -> Vec<Mat<f64>> + Sync),
) -> Vec<Mat<f64>> {
    let rows = w.nrows();
    if rows < 2 * LEAF_ROWS {
        return leaf(first, w, mw);
    }
    let half = rows / (2 * LEAF_ROWS) * LEAF_ROWS;
    let (wt, wb) = w.split_at_row_mut(half);
    let (mt, mb) = mw.split_at_row_mut(half);
    let (mut a, b) = rayon::join(
        || fold_rows(first, wt, mt, leaf),
        || fold_rows(first + half, wb, mb, leaf),
    );
    for (a, b) in a.iter_mut().zip(b) {
        *a += b;
    }
    a
}

/// `dst (= or +=) alpha a b` on the calling thread (a leaf of [`fold_rows`]).
fn leaf_product(
    dst: faer::MatMut<'_, f64>,
    add: bool,
    a: faer::MatRef<'_, f64>,
    b: faer::MatRef<'_, f64>,
    alpha: f64,
) {
    let accum = if add {
        faer::Accum::Add
    } else {
        faer::Accum::Replace
    };
    faer::linalg::matmul::matmul(dst, accum, a, b, alpha, faer::Par::Seq);
}

/// The Euclidean norms of the columns of `w` (a leaf of [`fold_rows`]), squared, as a row.
fn leaf_squared_norms(w: faer::MatRef<'_, f64>) -> Mat<f64> {
    Mat::<f64>::from_fn(1, w.ncols(), |_, j| {
        let col = w.col(j).try_as_col_major().expect("contiguous");
        let mut lanes = [0.0; 8];
        let chunks = col.as_slice().chunks_exact(8);
        let tail: f64 = chunks.remainder().iter().map(|x| x * x).sum();
        for c in chunks {
            for (l, x) in lanes.iter_mut().zip(c) {
                *l += x * x;
            }
        }
        lanes.iter().sum::<f64>() + tail
    })
}

/// The Gram matrix `G = mw^T w` of a block (already M-orthogonal to the basis and the locked
/// vectors) with its images `mw`, and its columns' Euclidean norms: what [`cholesky_qr2`] starts
/// from, summed in the pass that makes `mw` ([`crate::csc::sym_mul_mat_gram_into`]).
struct Gram {
    g: Mat<f64>,
    norms: Vec<f64>,
}

/// M-orthonormalises the columns of a block `w` (already M-orthogonal to the basis and the
/// locked vectors) with their `M` images `mw` by Cholesky QR, twice where once is not enough
/// (CholQR2): `G = mw^T w`, `G = R^T R`, `w <- w R^-1`, `mw <- mw R^-1` (the images follow by
/// linearity, no sparse product), then once more unless the first pass left `G` the identity to
/// [`SECOND_QR`]. Returns the upper triangular `R` of `w = Q R` (the product of the passes'),
/// which holds the coefficients a Gram-Schmidt of each column against the ones before it would
/// find (docs/MATH.md, "Selective reorthogonalisation"). `gram` is the block's [`Gram`] (from its
/// projection's `M` product); the first pass's `R^-1` and the second's Gram matrix are one pass
/// over the rows ([`fold_rows`]), the second's `R^-1` another.
///
/// `None`, with `w` and `mw` as they were, when the block is near dependence: a column whose
/// Euclidean norm fell below `1e-5` of its norm before the projection (`before`), or whose part
/// independent of the columns before it is below `1e-5` of its M-norm. A column kept is then
/// at least about `1e-10` of its norm before, the bound below which the vector-by-vector path
/// replaces a column by a random one (what is left of it is round-off, not a direction).
/// CholQR2 is accurate to round-off for blocks conditioned below about `1e7`; those nearer
/// breakdown take the vector-by-vector path.
fn cholesky_qr2(
    mut w: faer::MatMut<'_, f64>,
    mut mw: faer::MatMut<'_, f64>,
    before: &[f64],
    gram: &Gram,
) -> Option<Mat<f64>> {
    let k = w.ncols();
    if (0..k).any(|j| !(gram.norms[j] > 1e-5 * before[j])) {
        return None;
    }
    let r1 = small_cholesky(&gram.g, 1e-5)?;
    let inv1 = upper_inverse(&r1);
    let g2 = fold_rows(0, w.as_mut(), mw.as_mut(), &|_, mut w, mut mw| {
        right_multiply_rows(w.as_mut(), inv1.as_ref());
        right_multiply_rows(mw.as_mut(), inv1.as_ref());
        let mut g = Mat::<f64>::zeros(k, k);
        leaf_product(g.as_mut(), false, mw.as_ref().transpose(), w.as_ref(), 1.0);
        vec![g]
    });
    // the second pass only where the first left the block short of working precision: with
    // `G2` (the first pass's measure of what it left) the identity to `SECOND_QR`, `R2` is the
    // identity to about that, and `R2^-1` would move no entry of `w` by more (a NaN is kept, so
    // that it fails the test and the second pass's Cholesky declines the block)
    let off = (0..k)
        .flat_map(|j| (0..k).map(move |i| (i, j)))
        .map(|(i, j)| (g2[0][(i, j)] - if i == j { 1.0 } else { 0.0 }).abs())
        .fold(0.0f64, |m, e| if e.is_nan() || e > m { e } else { m });
    if off <= SECOND_QR {
        return Some(r1);
    }
    let (r, s) = match small_cholesky(&g2[0], 0.5) {
        Some(r2) => (Some(&r2 * &r1), upper_inverse(&r2)),
        // not reached after a first pass that met its bound (`g2` is then the identity to about
        // 1e-6); undone all the same, for the vector-by-vector path
        None => (None, r1),
    };
    let _ = fold_rows(0, w, mw, &|_, w, mw| {
        right_multiply_rows(w, s.as_ref());
        right_multiply_rows(mw, s.as_ref());
        vec![]
    });
    r
}

/// [`cholesky_qr2`] makes its second pass only where the first left the block's Gram matrix
/// further than this from the identity: 16 units of round-off, below the `8e-15` to `2e-14` to
/// which the basis is M-orthonormal across blocks (docs/MATH.md, "Selective
/// reorthogonalisation").
const SECOND_QR: f64 = 16.0 * f64::EPSILON;

/// The fewest rows of a thread's part in [`inner_products`].
const PROJECT_ROWS: usize = 4096;

/// A block projected by [`project_block`]: its coefficients on the basis, whether a second pass
/// was needed, its columns' Euclidean norms before the projection, and its [`Gram`] after.
struct Projected {
    coef: Mat<f64>,
    again: bool,
    before: Vec<f64>,
    gram: Gram,
}

/// Projects the block `w` out of the locked vectors `x` and the basis `v` (M-orthonormal, with
/// their M images), and writes `M w` into `mw`.
///
/// First the Lanczos recurrence: one pass of block classical Gram-Schmidt against the columns
/// `lo..` of `v`, the only ones that hold a large part of `OP V_j` ([`coupled_from`]). Then one
/// pass against `x` and all of `v`, which removes what the recurrence's round-off and the lost
/// orthogonality left. That pass is repeated only where it removed more than the fraction `1 -
/// REORTHOGONALIZE^2` of a column's squared M-norm (the criterion of Daniel, Gragg, Kaufman and
/// Stewart, with ARPACK's constant); where it removed less, Kahan and Parlett's bound makes the
/// column orthogonal to working precision (docs/MATH.md, "Selective reorthogonalisation"). The
/// squared M-norm before the pass is the one after it plus the squared coefficients removed
/// (Pythagoras in the M inner product), so the test costs no product beyond `M w`.
///
/// The steps that need only a row of the block are fused by rows ([`fold_rows`]): the
/// recurrence's coefficients with the norms before; the recurrence's subtraction with the full
/// pass's coefficients; the full pass's subtraction. The block's [`Gram`] is summed in the pass
/// that makes `M w` (docs/SCALING.md, "Orthogonalisation by leaves of rows").
fn project_block(
    m: &SparseMatrix,
    (x, mx): (faer::MatRef<'_, f64>, faer::MatRef<'_, f64>),
    (v, mv): (faer::MatRef<'_, f64>, faer::MatRef<'_, f64>),
    lo: usize,
    mut w: faer::MatMut<'_, f64>,
    mut mw: faer::MatMut<'_, f64>,
) -> Projected {
    let (len, k) = (v.ncols(), w.ncols());
    let local = len - lo;
    // the recurrence's coefficients and the norms before
    let first = fold_rows(0, w.as_mut(), mw.as_mut(), &|r, w, _| {
        let mut c = Mat::<f64>::zeros(local, k);
        let mvl = mv.subrows(r, w.nrows()).subcols(lo, local);
        leaf_product(c.as_mut(), false, mvl.transpose(), w.as_ref(), 1.0);
        vec![c, leaf_squared_norms(w.as_ref())]
    });
    let before: Vec<f64> = (0..k).map(|j| first[1][(0, j)].sqrt()).collect();
    let mut coef = Mat::<f64>::zeros(len, k);
    coef.subrows_mut(lo, local).copy_from(&first[0]);
    // one pass against the locked vectors and the whole basis (after the recurrence's, in the
    // same pass over the rows), twice where the first removed too much
    let mut recurrence = Some(&first[0]);
    let mut again = false;
    let gram = loop {
        let sums = fold_rows(0, w.as_mut(), mw.as_mut(), &|r, mut w, _| {
            let n = w.nrows();
            if let Some(c) = recurrence {
                let vl = v.subrows(r, n).subcols(lo, local);
                leaf_product(w.as_mut(), true, vl, c.as_ref(), -1.0);
            }
            let mut cv = Mat::<f64>::zeros(len, k);
            let mut cx = Mat::<f64>::zeros(x.ncols(), k);
            leaf_product(
                cv.as_mut(),
                false,
                mv.subrows(r, n).transpose(),
                w.as_ref(),
                1.0,
            );
            leaf_product(
                cx.as_mut(),
                false,
                mx.subrows(r, n).transpose(),
                w.as_ref(),
                1.0,
            );
            vec![cv, cx]
        });
        let (on_basis, on_locked) = (&sums[0], &sums[1]);
        let _ = fold_rows(0, w.as_mut(), mw.as_mut(), &|r, mut w, _| {
            let n = w.nrows();
            leaf_product(w.as_mut(), true, v.subrows(r, n), on_basis.as_ref(), -1.0);
            leaf_product(w.as_mut(), true, x.subrows(r, n), on_locked.as_ref(), -1.0);
            vec![]
        });
        coef += on_basis;
        let (g, squares) =
            crate::csc::sym_mul_mat_gram_into(m, w.as_ref(), mw.as_mut()).expect("sizes checked");
        let gram = Gram {
            g,
            norms: squares.iter().map(|s| s.sqrt()).collect(),
        };
        let short = (0..k).any(|j| {
            let kept = gram.g[(j, j)];
            let gone = on_locked.col(j).squared_norm_l2() + on_basis.col(j).squared_norm_l2();
            !(kept >= REORTHOGONALIZE * REORTHOGONALIZE * (kept + gone))
        });
        if again || !short {
            break gram;
        }
        again = true;
        recurrence = None;
    };
    Projected {
        coef,
        again,
        before,
        gram,
    }
}

/// A block's single pass of Gram-Schmidt against the basis is repeated when a column keeps less
/// than this fraction of its M-norm (ARPACK's `0.717`, about `1 / sqrt(2)`): Kahan and Parlett's
/// "twice is enough" bound then no longer makes one pass orthogonal to working precision.
const REORTHOGONALIZE: f64 = 0.717;

/// The first basis column whose stored projection couples it to the columns `applied..hi` about
/// to be expanded (`h[i][j]` nonzero, `i < applied <= j`), or `applied` when none does. By the
/// symmetry of the projection, `v_i^T M OP v_j = h[i][j]`, and `v_i^T M OP v_j = 0` where `v_j`
/// was made after `OP v_i` was (it is orthogonal to everything `OP v_i` spans): columns before
/// the returned one hold only round-off of `OP V_j` (docs/MATH.md, "Selective
/// reorthogonalisation"). After a thick restart the Ritz vectors all couple to the block: 0.
fn coupled_from(h: &[Vec<f64>], applied: usize, hi: usize) -> usize {
    (0..applied.min(h.len()))
        .find(|&i| (applied..hi).any(|j| h[i].get(j).is_some_and(|v| *v != 0.0)))
        .unwrap_or(applied)
}

/// A zero-energy pair locked before the iteration ([`Pencil::zero_energy_pairs`]): the
/// M-normalised vector, its M image, its Rayleigh quotient and what the shifted residual at any
/// shift needs (`||r||` with `r = K x - lambda M x`, and the inner products of `K x` and `M x`), so
/// that no `K` product is repeated for each Lanczos run.
struct Known {
    x: Vec<f64>,
    mx: Vec<f64>,
    lambda: f64,
    r_norm: f64,
    kk: f64,
    km: f64,
    mm: f64,
}

impl Known {
    /// `||K x - lambda M x|| / ||(K - sigma M) x||`.
    fn shifted_residual(&self, sigma: f64) -> f64 {
        let s2 = self.kk - 2.0 * sigma * self.km + sigma * sigma * self.mm;
        self.r_norm / s2.max(0.0).sqrt().max(f64::MIN_POSITIVE)
    }
}

/// A probe's Lanczos cycle: its basis, the basis's M images, the projection `h` (as in
/// [`Lanczos::run`]), the columns `OP` was applied to, and the random generator's state after it.
struct Probed {
    basis: Columns,
    mbasis: Columns,
    h: Vec<Vec<f64>>,
    applied: usize,
    rng: u64,
}

struct Lanczos<'p, 'a> {
    pencil: &'p Pencil<'a>,
    /// `LDL^T` of `K - sigma M`, owned so that it can be released while the Sturm check factors
    /// another shift: two factors alive at once set femu's peak memory (about 2x CalculiX's).
    op: Option<Ldlt>,
    sigma: f64,
    params: EigenOptions,
    n: usize,
    /// locked eigenvectors, their M images and eigenvalues
    x: Columns,
    mx: Columns,
    values: Vec<f64>,
    shifted_res: Vec<f64>,
    force_random_start: bool,
    /// How many of the locked pairs were given ([`Known`]): they take no room in the basis.
    known: usize,
    /// The probe's Krylov basis, kept for [`Lanczos::run`] to continue from when the shift stays
    /// where the probe ran.
    probed: Option<Probed>,
    /// Set when the hook of [`with_interrupt`] asked to stop.
    stop: bool,
    rng: u64,
}

impl<'p, 'a> Lanczos<'p, 'a> {
    /// A Lanczos iteration at `sigma` with the `known` zero-energy pairs locked from the start.
    fn new(
        pencil: &'p Pencil<'a>,
        op: Ldlt,
        sigma: f64,
        params: &EigenOptions,
        known: &[Known],
    ) -> Self {
        let mut lanczos = Self {
            pencil,
            op: Some(op),
            sigma,
            params: params.clone(),
            n: pencil.dim(),
            x: Columns::new(pencil.dim()),
            mx: Columns::new(pencil.dim()),
            values: vec![],
            shifted_res: vec![],
            force_random_start: false,
            known: 0,
            probed: None,
            stop: false,
            rng: params.seed,
        };
        for k in known {
            lanczos.x.push(&k.x);
            lanczos.mx.push(&k.mx);
            lanczos.values.push(k.lambda);
            lanczos.shifted_res.push(k.shifted_residual(sigma));
        }
        lanczos.known = known.len();
        lanczos
    }

    fn random_vector(&mut self) -> Vec<f64> {
        (0..self.n)
            .map(|_| {
                self.rng = self.rng.wrapping_add(0x9E37_79B9_7F4A_7C15);
                let mut z = self.rng;
                z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
                z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
                z ^= z >> 31;
                (z >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            })
            .collect()
    }

    fn m_times(&self, v: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; self.n];
        crate::csc::mul_vec(self.pencil.m, v, &mut out).expect("sizes checked");
        out
    }

    /// Two passes of classical Gram-Schmidt (CGS2) of `w` against the locked vectors and the
    /// basis columns `..upto`, M inner products through the stored M images; returns the
    /// coefficients on those basis columns.
    fn orthogonalize_upto(
        &self,
        w: &mut [f64],
        basis: &Columns,
        mbasis: &Columns,
        upto: usize,
    ) -> Vec<f64> {
        let nl = self.x.len();
        let vs: Vec<&[f64]> = (0..nl)
            .map(|j| self.x.col(j))
            .chain((0..upto).map(|j| basis.col(j)))
            .collect();
        let mvs: Vec<&[f64]> = (0..nl)
            .map(|j| self.mx.col(j))
            .chain((0..upto).map(|j| mbasis.col(j)))
            .collect();
        let mut coef = vec![0.0; upto];
        for _ in 0..2 {
            let cs: Vec<f64> = mvs.par_iter().map(|mv| dot(mv, w)).collect();
            let neg: Vec<f64> = cs.iter().map(|c| -c).collect();
            add_combination(w, &vs, &neg);
            coef.iter_mut().zip(&cs[nl..]).for_each(|(a, c)| *a += c);
        }
        coef
    }

    /// CGS2 of `w` against the locked vectors and the whole basis; the coefficients on `basis`.
    fn orthogonalize(&self, w: &mut [f64], basis: &Columns, mbasis: &Columns) -> Vec<f64> {
        self.orthogonalize_upto(w, basis, mbasis, basis.len())
    }

    /// The M-norm of `w` (already orthogonal to the locked vectors and the basis) with its image
    /// `mw`, or `None` when `w` vanished relative to `before` (the Krylov space is invariant).
    fn usable_norm(w: &[f64], mw: &[f64], before: f64) -> Option<f64> {
        if !(norm(w) > 1e-10 * before) {
            return None;
        }
        let nrm = dot(mw, w).max(0.0).sqrt();
        (nrm > 0.0).then_some(nrm)
    }

    /// Appends `w / nrm` and its image `mw / nrm`.
    fn push_scaled(
        mut w: Vec<f64>,
        mut mw: Vec<f64>,
        nrm: f64,
        basis: &mut Columns,
        mbasis: &mut Columns,
    ) {
        w.iter_mut().for_each(|v| *v /= nrm);
        mw.iter_mut().for_each(|v| *v /= nrm);
        basis.push(&w);
        mbasis.push(&mw);
    }

    /// Appends `w` to the basis after orthogonalisation; returns (coefficients, norm before the
    /// final normalisation). A vector that vanishes (invariant subspace found) is replaced by a
    /// random one, with zero coefficient.
    fn append(
        &mut self,
        mut w: Vec<f64>,
        basis: &mut Columns,
        mbasis: &mut Columns,
    ) -> (Vec<f64>, f64) {
        // Breakdown is judged on the Euclidean norm: no extra M product per vector.
        let before = norm(&w);
        let coef = self.orthogonalize(&mut w, basis, mbasis);
        (coef, self.push_or_replace(w, before, basis, mbasis))
    }

    /// Pushes the orthogonalised `w` with its M image, or on breakdown a random vector
    /// orthogonalised in its place; returns the norm of `w` (0 when replaced).
    fn push_or_replace(
        &mut self,
        w: Vec<f64>,
        before: f64,
        basis: &mut Columns,
        mbasis: &mut Columns,
    ) -> f64 {
        let mw = self.m_times(&w);
        if let Some(nrm) = Self::usable_norm(&w, &mw, before) {
            Self::push_scaled(w, mw, nrm, basis, mbasis);
            return nrm;
        }
        let (r, mr, nrm) = self.replacement(basis, mbasis, basis.len(), (w, mw));
        Self::push_scaled(r, mr, nrm, basis, mbasis);
        0.0
    }

    /// On breakdown (the Krylov space is invariant): a fresh random direction orthogonalised
    /// against the locked vectors and the basis columns `..upto`, with its M image and M-norm
    /// (the vector and image still to be divided by it). When no independent direction is found
    /// in five tries (the basis spans the space to round-off) the last one, so that the basis and
    /// its projection keep their size; `last` is the vector that broke down.
    fn replacement(
        &mut self,
        basis: &Columns,
        mbasis: &Columns,
        upto: usize,
        mut last: (Vec<f64>, Vec<f64>),
    ) -> (Vec<f64>, Vec<f64>, f64) {
        for _ in 0..5 {
            let mut r = self.random_vector();
            let b = norm(&r);
            let _ = self.orthogonalize_upto(&mut r, basis, mbasis, upto);
            let mr = self.m_times(&r);
            if let Some(nrm) = Self::usable_norm(&r, &mr, b) {
                return (r, mr, nrm);
            }
            last = (r, mr);
        }
        let nrm = dot(&last.1, &last.0).max(f64::MIN_POSITIVE).sqrt();
        (last.0, last.1, nrm)
    }

    /// Applies `OP` to the basis vectors `applied..` block by block until `max_basis` columns have
    /// their image, extending the basis; returns the new `applied`. Each block of solved vectors
    /// is projected out of the locked vectors and the basis by GEMMs ([`project_block`]), then
    /// orthonormalised within itself ([`cholesky_qr2`], or column by column near dependence).
    fn expand(
        &mut self,
        basis: &mut Columns,
        mbasis: &mut Columns,
        h: &mut Vec<Vec<f64>>,
        mut applied: usize,
        max_basis: usize,
        stats: &mut EigenStats,
    ) -> usize {
        let p = self.params.block_size.max(1);
        let cap = self.n - self.values.len();
        while applied < basis.len() && applied < max_basis {
            let hi = (applied + p).min(basis.len()).min(max_basis);
            let block = hi - applied;
            let len0 = basis.len();
            let t = Instant::now();
            // The block is solved where it will stay: its right-hand sides (the M images of the
            // columns it extends) are copied into the basis's reserved columns, and everything
            // below works there and in the M images' columns, with no copy of the block
            // (docs/SCALING.md, "The block in place").
            basis.push_mat(mbasis.range(applied, hi));
            self.op
                .as_ref()
                .expect("the factor is present while iterating")
                .solve_in_place(basis.split_mut(len0).1);
            stats.solve_seconds += t.elapsed().as_secs_f64();
            stats.solved_vectors += block;
            if interrupted(stats.solved_vectors) {
                basis.truncate(len0);
                self.stop = true;
                return applied;
            }
            let t = Instant::now();
            let (head, mut w) = basis.split_mut(len0);
            // the block against the locked vectors and the basis (the recurrence's columns, one
            // pass against all, a second only where needed), with its M images in the images'
            // reserved columns
            let lo = coupled_from(h, applied, hi);
            mbasis.push_zeros(block);
            let (mhead, mw) = mbasis.split_mut(len0);
            let projected = project_block(
                self.pencil.m,
                (self.x.mat(), self.mx.mat()),
                (head, mhead),
                lo,
                w.as_mut(),
                mw,
            );
            stats.reorthogonalized_blocks += usize::from(projected.again);
            // the block within itself: by CholQR2 when it is well conditioned and fits
            let qr = if len0 + block <= cap {
                let (_, w) = basis.split_mut(len0);
                let (_, mw) = mbasis.split_mut(len0);
                cholesky_qr2(w, mw, &projected.before, &projected.gram)
            } else {
                None
            };
            let (coef0, before) = (&projected.coef, &projected.before);
            match qr {
                Some(r) => {
                    for j in 0..block {
                        let mut coef: Vec<f64> = coef0.col(j).iter().copied().collect();
                        coef.extend((0..=j).map(|i| r[(i, j)]));
                        h.push(coef);
                    }
                }
                None => self.orthonormalise_by_columns(basis, mbasis, h, coef0, before),
            }
            applied = hi;
            stats.orthogonalization_seconds += t.elapsed().as_secs_f64();
        }
        applied
    }

    /// The block in the basis's columns from `len0 = coef0.nrows()` on (projected out of the
    /// locked vectors and the basis with coefficients `coef0`, its Euclidean norms before that
    /// `before`), near dependence: each column Gram-Schmidted twice against the block's columns
    /// before it and M-normalised, a vanished column replaced by a random one
    /// ([`Lanczos::replacement`]), a column beyond the space's dimension dropped; each column's
    /// coefficients pushed to `h`. The path of a block that [`cholesky_qr2`] declines.
    fn orthonormalise_by_columns(
        &mut self,
        basis: &mut Columns,
        mbasis: &mut Columns,
        h: &mut Vec<Vec<f64>>,
        coef0: &Mat<f64>,
        before: &[f64],
    ) {
        let (len0, block) = (coef0.nrows(), coef0.ncols());
        let cap = self.n - self.values.len();
        // near dependence: CGS2 of each column against the block's columns before it, then
        // M-normalised, a vanished column replaced
        let mut kept = 0;
        for j in 0..block {
            let mut coef: Vec<f64> = coef0.col(j).iter().copied().collect();
            let (_, mut w) = basis.split_mut(len0);
            let (_, mut mw) = mbasis.split_mut(len0);
            let (done, mut rest) = w.as_mut().split_at_col_mut(j);
            let mut inner = Mat::<f64>::zeros(kept, 1);
            for _ in 0..2 {
                inner += project_out(
                    done.as_ref().subcols(0, kept),
                    mw.as_ref().subcols(0, kept),
                    rest.as_mut().subcols_mut(0, 1),
                );
            }
            let (mdone, mut mrest) = mw.as_mut().split_at_col_mut(j);
            faer::linalg::matmul::matmul(
                mrest.as_mut().subcols_mut(0, 1),
                faer::Accum::Add,
                mdone.as_ref().subcols(0, kept),
                inner.as_ref(),
                -1.0,
                faer::get_global_parallelism(),
            );
            coef.extend(inner.col(0).iter().copied());
            if len0 + kept >= cap {
                // the basis spans the space: the column is not kept (nor any after it)
                h.push(coef);
                continue;
            }
            let col = rest.col_mut(0).try_as_col_major_mut().expect("contiguous");
            let mcol = mrest.col_mut(0).try_as_col_major_mut().expect("contiguous");
            let (col, mcol) = (col.as_slice_mut(), mcol.as_slice_mut());
            let nrm = match Self::usable_norm(col, mcol, before[j]) {
                Some(nrm) => {
                    scale_in_place(col, nrm);
                    scale_in_place(mcol, nrm);
                    nrm
                }
                None => {
                    let broken = (col.to_vec(), mcol.to_vec());
                    let (r, mr, nrm) = self.replacement(basis, mbasis, len0 + j, broken);
                    // in the broken column's place
                    let slot = (len0 + j) * self.n..(len0 + j + 1) * self.n;
                    for (to, from) in [(&mut basis.data, &r), (&mut mbasis.data, &mr)] {
                        to[slot.clone()]
                            .iter_mut()
                            .zip(from)
                            .for_each(|(t, v)| *t = v / nrm);
                    }
                    0.0
                }
            };
            coef.push(nrm);
            h.push(coef);
            kept += 1;
        }
        basis.truncate(len0 + kept);
        mbasis.truncate(len0 + kept);
    }

    /// One Lanczos cycle from random vectors, no locking: rough estimates of the `count`
    /// eigenvalues nearest the shift (to place a better shift), from a basis of `size` vectors.
    fn estimate(&mut self, count: usize, size: usize, stats: &mut EigenStats) -> Vec<f64> {
        let p = self.params.block_size.max(1);
        let (mut basis, mut mbasis, mut h) =
            (Columns::new(self.n), Columns::new(self.n), Vec::new());
        // the run that continues this basis for `count` pairs grows it to its own size: room for
        // that now, so that the basis is not moved (and held twice) when the run begins
        let room = self.basis_size(count).max(size) + p;
        basis.reserve(room);
        mbasis.reserve(room);
        for _ in 0..p.min(self.n) {
            let r = self.random_vector();
            self.append(r, &mut basis, &mut mbasis);
        }
        let max_basis = size.min(self.n);
        let m = self.expand(&mut basis, &mut mbasis, &mut h, 0, max_basis, stats);
        if self.stop {
            return Vec::new();
        }
        let (eig, order) = rayleigh_ritz(&h, m);
        // Only the better-converged half: the trailing Ritz values of a short cycle overestimate
        // their eigenvalues by orders of magnitude.
        let mut v: Vec<f64> = order
            .iter()
            .take(count.min(m / 2).max(1))
            .filter(|r| eig.eigenvalues[**r] != 0.0)
            .map(|r| self.sigma + 1.0 / eig.eigenvalues[*r])
            .collect();
        v.sort_by(f64::total_cmp);
        self.probed = Some(Probed {
            basis,
            mbasis,
            h,
            applied: m,
            rng: self.rng,
        });
        v
    }

    /// The largest basis of a run for `want` pairs ([`EigenOptions::max_basis`], or about three
    /// times the count the iteration must find: the given pairs are deflated, not in the basis),
    /// fixed for the whole run. Measured at 52,920 DOF: 163 solved vectors and 2 restarts against
    /// 207 and 10 at twice the count; on the free-free plate of 199,200 DOF with its six
    /// rigid-body modes given, 73 solved vectors and no restart at 59 columns, 75 at 77.
    fn basis_size(&self, want: usize) -> usize {
        let p = self.params.block_size.max(1);
        let cap = self.n - self.values.len();
        if self.params.max_basis > 0 {
            self.params.max_basis
        } else {
            let find = want.saturating_sub(self.known);
            (3 * find + 2 * p).max(find + 4 * p).max(24)
        }
        .min(cap)
    }

    /// Runs thick-restarted block Lanczos until `want` pairs are locked.
    ///
    /// Basis `V` (M-orthonormal, deflated against the locked vectors) and the projection
    /// `h[col][row] = v_row^T M OP v_col` for the columns where `OP` was applied. At a restart the
    /// best Ritz vectors `Y = V S` are kept with `OP Y = Y Theta + V_extra H_extra S` (thick
    /// restart), so no solve is repeated and no Krylov information is lost.
    fn run(&mut self, want: usize, stats: &mut EigenStats) -> Result<(), SparseError> {
        let p = self.params.block_size.max(1);
        // Continue from the probe's Krylov basis when it ran at this shift: its solves are not
        // repeated (a clamped model's probe was 23 of 154 solved vectors at 52,920 DOF).
        let (mut basis, mut mbasis, mut h, mut applied) = match self.probed.take() {
            Some(probed) => {
                // its random vectors are not drawn again
                self.rng = probed.rng;
                (probed.basis, probed.mbasis, probed.h, probed.applied)
            }
            None => (Columns::new(self.n), Columns::new(self.n), Vec::new(), 0),
        };
        // room for every pair the run locks, allocated at once: a locked set that doubled as it
        // grew copied itself (and cleared its new pages) at each doubling, 0.1 s of the 199,200-DOF
        // plate's Rayleigh-Ritz (docs/SCALING.md, "The locked set's room")
        self.x.reserve(want);
        self.mx.reserve(want);
        let mut restarts = 0;
        loop {
            let need = want.saturating_sub(self.values.len());
            if need == 0 {
                return Ok(());
            }
            let cap = self.n - self.values.len();
            let max_basis = self.basis_size(want);
            // the whole basis at once (measured: 50 MB of the peak at 47,628 DOF when the basis
            // and its images doubled from 64 to 128 columns)
            basis.reserve(max_basis + p);
            mbasis.reserve(max_basis + p);
            let t = Instant::now();
            if self.force_random_start || applied > max_basis {
                // Missed modes (or a probe's basis larger than this run's): discard the basis and
                // start afresh, deflated against the locked.
                basis.clear();
                mbasis.clear();
                h.clear();
                applied = 0;
                self.force_random_start = false;
            }
            while basis.len() < applied + p.min(cap - applied.min(cap)) && basis.len() < cap {
                let r = self.random_vector();
                self.append(r, &mut basis, &mut mbasis);
            }
            stats.orthogonalization_seconds += t.elapsed().as_secs_f64();
            // Convergence is checked after every block once the basis can hold the wanted pairs
            // (a Rayleigh-Ritz of at most max_basis columns costs far less than a solve), not
            // only when the basis is full: pairs lock as soon as they converge, and a cycle ends
            // early when every wanted pair has.
            let checkpoint = (applied + p).max((need + 2 * p).min(max_basis));
            applied = self.expand(
                &mut basis,
                &mut mbasis,
                &mut h,
                applied,
                checkpoint.min(max_basis),
                stats,
            );
            if self.stop {
                return Err(SparseError::Interrupted {
                    solved_vectors: stats.solved_vectors,
                });
            }
            let t = Instant::now();
            let full = applied >= max_basis || basis.len() >= cap;
            // Rayleigh-Ritz on the square part.
            let m = applied;
            let (eig, order) = rayleigh_ritz(&h, m);
            let extra = basis.len() - m;
            // coupling[e][r] = (H_extra S)[e, r]: the residual of Ritz pair r on extra vector e
            let coupling: Vec<Vec<f64>> = (0..extra)
                .map(|e| {
                    (0..m)
                        .map(|r| {
                            (0..m)
                                .map(|j| {
                                    h[j].get(m + e).copied().unwrap_or(0.0)
                                        * eig.eigenvectors[(j, r)]
                                })
                                .sum()
                        })
                        .collect()
                })
                .collect();
            let est_of = |r: usize| {
                (0..extra)
                    .map(|e| coupling[e][r] * coupling[e][r])
                    .sum::<f64>()
                    .sqrt()
                    / eig.eigenvalues[r].abs().max(f64::MIN_POSITIVE)
            };
            // The first `need` Ritz pairs are the wanted ones. `est` only screens them; the true
            // residual decides. The shifted residual of a Ritz pair is `est` times the spread of
            // the unconverged part (measured 100 to 1,000 times `est` at 52,920 DOF), so a pair
            // with `est` above `tol / 100` would fail the check anyway.
            let candidates: Vec<usize> = order
                .iter()
                .take(need)
                .copied()
                .filter(|&r| eig.eigenvalues[r] != 0.0 && est_of(r) < SCREEN * self.params.tol)
                .collect();
            if !full && candidates.len() < p.min(need) {
                // Before the basis is full, lock only a block's worth of pairs at once (or all
                // that are still needed): each locking ends in a restart that rewrites the basis
                // (two GEMMs over it), measured at 6.3 s of 27 s at 199,200 DOF when done for
                // every pair as it converged.
                stats.ritz_seconds += t.elapsed().as_secs_f64();
                continue;
            }
            // the candidates' Ritz vectors V_m S by one GEMM, their K and M images by one sparse
            // product each
            let mut locked = vec![false; m];
            if !candidates.is_empty() {
                let s_c = Mat::from_fn(m, candidates.len(), |j, c| {
                    eig.eigenvectors[(j, candidates[c])]
                });
                let y = basis.range(0, m) * &s_c;
                let ky = crate::csc::sym_mul_mat(self.pencil.k, y.as_ref())?;
                let my = crate::csc::sym_mul_mat(self.pencil.m, y.as_ref())?;
                // Ritz vectors of a basis deflated against the locked vectors are M-orthogonal to
                // them and to each other to round-off. One block projection (two GEMMs) makes the
                // first exact and the Gram matrix checks the second, so that a pair locks without
                // a Gram-Schmidt of its own against every locked vector (0.43 s of a 10 s solve
                // at 199,200 DOF). A candidate the projection moves, or a block that is not
                // orthogonal, takes the pair-by-pair path of `lock_with` from the unprojected
                // vector, whose images `ky`, `my` are.
                let mut projected = y.clone();
                let mut clean = self.project_locked(&mut projected, &my);
                let gram = my.transpose() * &projected;
                let nc = candidates.len();
                let diag = |i: usize| gram[(i, i)].abs().sqrt();
                if (0..nc).any(|i| (0..i).any(|j| gram[(i, j)].abs() > 1e-10 * diag(i) * diag(j))) {
                    clean.iter_mut().for_each(|c| *c = false);
                }
                for (c, &r) in candidates.iter().enumerate() {
                    let col = |a: &Mat<f64>| -> Vec<f64> { a.col(c).iter().copied().collect() };
                    let (yc, kyc, myc) = (slice(&y, c), slice(&ky, c), slice(&my, c));
                    let lambda = self.sigma + 1.0 / eig.eigenvalues[r];
                    let (rho, eta, relative) = self.residuals_of(yc, kyc, myc, 1.0, lambda);
                    // With the shift on (or within round-off of) an eigenvalue, `(K - sigma M) x`
                    // vanishes and the shifted residual cannot be small: the classical relative
                    // residual decides; rigid-body modes can only meet the backward error.
                    let converged =
                        rho < self.params.tol || eta < BACKWARD_LOCK || relative < self.params.tol;
                    locked[r] = converged
                        && if clean[c] {
                            self.push_normalised(slice(&projected, c), kyc, myc)
                        } else {
                            self.lock_with(col(&y), col(&ky), col(&my))
                        };
                }
            }
            let keep: Vec<usize> = order.iter().copied().filter(|&r| !locked[r]).collect();
            let locked_now = m - keep.len();
            if locked_now > 0 && !keep.is_empty() {
                // a mode far nearer the shift than the rest was just locked: the basis built
                // before carries its round-off into every other Ritz vector; start afresh,
                // deflated against it
                let next = 1.0 / eig.eigenvalues[keep[0]].abs().max(f64::MIN_POSITIVE);
                let fresh = &self.values[self.values.len() - locked_now..];
                if fresh
                    .iter()
                    .any(|v| (v - self.sigma).abs() < CLOSE_LOCK * next)
                {
                    self.force_random_start = true;
                }
            }
            if self.values.len() >= want {
                stats.ritz_seconds += t.elapsed().as_secs_f64();
                return Ok(());
            }
            if !full {
                if locked_now > 0 {
                    // deflate the pairs just locked: keep every other Ritz vector (the same
                    // subspace without the locked directions) and the unapplied block
                    self.thick_restart(
                        &mut basis,
                        &mut mbasis,
                        &mut h,
                        m,
                        keep.len(),
                        &keep,
                        &eig,
                        &coupling,
                    );
                    applied = keep.len();
                }
                stats.ritz_seconds += t.elapsed().as_secs_f64();
                continue;
            }
            stats.ritz_seconds += t.elapsed().as_secs_f64();
            restarts += 1;
            stats.restarts += 1;
            if restarts > self.params.max_restarts {
                return Err(SparseError::NoConvergence {
                    reason: format!(
                        "{} of {} eigenpairs converged after {} restarts: ask for fewer modes, or \
                         solve nearer the wanted ones (a shift), or allow more restarts",
                        self.values.len(),
                        want,
                        restarts - 1
                    ),
                });
            }
            // Thick restart: keep the best unlocked Ritz vectors and the extra (residual) vectors.
            let kk = keep
                .len()
                .min(((need + p).max(m / 2)).min(m.saturating_sub(p).max(1)));
            let t = Instant::now();
            self.thick_restart(
                &mut basis,
                &mut mbasis,
                &mut h,
                m,
                kk,
                &keep,
                &eig,
                &coupling,
            );
            applied = kk;
            stats.ritz_seconds += t.elapsed().as_secs_f64();
        }
    }

    /// Thick restart: the basis becomes the Ritz vectors `keep[..kk]` of its first `m` columns
    /// (GEMMs) followed by its unapplied columns, with the projection `diag(theta)` and the Ritz
    /// pairs' coupling to those columns.
    #[allow(clippy::too_many_arguments)]
    fn thick_restart(
        &self,
        basis: &mut Columns,
        mbasis: &mut Columns,
        h: &mut Vec<Vec<f64>>,
        m: usize,
        kk: usize,
        keep: &[usize],
        eig: &nalgebra::SymmetricEigen<f64, nalgebra::Dyn>,
        coupling: &[Vec<f64>],
    ) {
        let keep = &keep[..kk];
        let extra = basis.len() - m;
        let sk = Mat::from_fn(m, kk, |j, c| eig.eigenvectors[(j, keep[c])]);
        basis.rotate_front(m, sk.as_ref());
        mbasis.rotate_front(m, sk.as_ref());
        let mut nh: Vec<Vec<f64>> = Vec::with_capacity(kk);
        for (i, r) in keep.iter().enumerate() {
            let mut col = vec![0.0; kk + extra];
            col[i] = eig.eigenvalues[*r];
            for e in 0..extra {
                col[kk + e] = coupling[e][*r];
            }
            nh.push(col);
        }
        *h = nh;
        // The Rayleigh-Ritz phase's and the solves' temporaries (Ritz vectors and their images,
        // the sparse products' row-major copies) are freed into glibc's arenas by the threads
        // that used them and stay resident there, under the basis that grows until the next
        // restart: returned here, the peaks of the 52,920-DOF block and the 47,628-DOF plate fell
        // by 7-42 and 9-19 MB in four alternated pairs each, for about 10 ms (docs/SCALING.md,
        // "Memory the allocator keeps").
        crate::multifrontal::release_free_memory();
    }

    /// Locks a converged Ritz vector: M-orthonormalised against the locked set, eigenvalue from
    /// its Rayleigh quotient. Returns false if it was not independent of the locked vectors.
    /// [`Lanczos::lock`] of a Ritz vector whose `K` and `M` images are known: they are reused
    /// when the orthogonalisation against the locked vectors leaves the vector as it was (it is
    /// already orthogonal to them to round-off), and recomputed otherwise.
    fn lock_with(&mut self, mut y: Vec<f64>, ky: Vec<f64>, my: Vec<f64>) -> bool {
        let before: Vec<f64> = y.clone();
        let empty = Columns::new(self.n);
        let _ = self.orthogonalize(&mut y, &empty, &empty);
        let moved = norm(
            &y.iter()
                .zip(&before)
                .map(|(a, b)| a - b)
                .collect::<Vec<_>>(),
        );
        if moved > 1e-10 * norm(&before) {
            return self.lock(y);
        }
        self.push_normalised(&y, &ky, &my)
    }

    /// `w -= X c` with `c = (M X)^T w` against the locked vectors `X`, for the columns of `w`
    /// whose M images are `mw`; per column, whether the projection left it as it was (`||c||`,
    /// the M-norm of what was removed, at most `1e-10` of the column's M-norm), so that its images
    /// still hold.
    fn project_locked(&self, w: &mut Mat<f64>, mw: &Mat<f64>) -> Vec<bool> {
        let c = project_out(self.x.mat(), self.mx.mat(), w.as_mut());
        (0..w.ncols())
            .map(|j| {
                let m_norm = dot(slice(mw, j), slice(w, j)).abs().sqrt();
                c.col(j).norm_l2() <= 1e-10 * m_norm
            })
            .collect()
    }

    /// Locks `y` (M-orthogonal to the locked vectors) with its images `K y`, `M y`, normalised:
    /// the M-normalised vector and its M image are written into the locked set directly, and the
    /// Rayleigh quotient and residual are taken from the normalised values as they are made, with
    /// no copies. Returns false if its M-norm is below 0.5 (it was not independent of the locked
    /// vectors).
    fn push_normalised(&mut self, y: &[f64], ky: &[f64], my: &[f64]) -> bool {
        let nrm = dot(my, y).max(0.0).sqrt();
        if nrm.is_nan() || nrm <= 0.5 {
            return false;
        }
        let lambda = ky.iter().zip(y).map(|(k, x)| (k / nrm) * (x / nrm)).sum();
        let rho = self.residuals_of(y, ky, my, nrm, lambda).0;
        self.x.push_divided(y, nrm);
        self.mx.push_divided(my, nrm);
        self.values.push(lambda);
        self.shifted_res.push(rho);
        true
    }

    /// Stores a locked M-normalised vector with its images; eigenvalue from its Rayleigh quotient.
    fn push_locked(&mut self, x: Vec<f64>, kx: Vec<f64>, mx: Vec<f64>) {
        let lambda = dot(&kx, &x);
        let rho = self.residuals_of(&x, &kx, &mx, 1.0, lambda).0;
        self.x.push(&x);
        self.mx.push(&mx);
        self.values.push(lambda);
        self.shifted_res.push(rho);
    }

    fn lock(&mut self, mut y: Vec<f64>) -> bool {
        let empty = Columns::new(self.n);
        let _ = self.orthogonalize(&mut y, &empty, &empty);
        let my = self.m_times(&y);
        let nrm = dot(&my, &y).max(0.0).sqrt();
        if nrm.is_nan() || nrm <= 0.5 {
            return false;
        }
        let x: Vec<f64> = y.iter().map(|v| v / nrm).collect();
        let mx: Vec<f64> = my.iter().map(|v| v / nrm).collect();
        let mut kx = vec![0.0; self.n];
        crate::csc::mul_vec(self.pencil.k, &x, &mut kx).expect("sizes checked");
        self.push_locked(x, kx, mx);
        true
    }

    /// `(||K x - lambda M x|| / ||(K - sigma M) x||, backward error, ||K x - lambda M x|| / ||K x||)`
    /// from `K x` and `M x`, for `x`, `K x`, `M x` the given vectors divided by `scale` (1: as
    /// they are), in one pass without copies. A pair is converged when the first or the third
    /// is below `tol` or the backward error is at round-off (1e-13): rigid-body modes, with
    /// `K x` pure round-off, can only meet the latter.
    fn residuals_of(
        &self,
        x: &[f64],
        kx: &[f64],
        mx: &[f64],
        scale: f64,
        lambda: f64,
    ) -> (f64, f64, f64) {
        let (mut rr, mut ss, mut xx, mut kk) = (0.0, 0.0, 0.0, 0.0);
        for ((x, k), m) in x.iter().zip(kx).zip(mx) {
            let (x, k, m) = (x / scale, k / scale, m / scale);
            let (r, s) = (k - lambda * m, k - self.sigma * m);
            rr += r * r;
            ss += s * s;
            xx += x * x;
            kk += k * k;
        }
        let (rn, sn, xn, kn) = (rr.sqrt(), ss.sqrt(), xx.sqrt(), kk.sqrt());
        let eta = rn
            / ((self.pencil.k_norm + lambda.abs() * self.pencil.m_norm) * xn)
                .max(f64::MIN_POSITIVE);
        (
            rn / sn.max(f64::MIN_POSITIVE),
            eta,
            rn / kn.max(f64::MIN_POSITIVE),
        )
    }

    fn finish(
        &self,
        mut sel: Vec<usize>,
        sigma: f64,
        sturm: SturmCheck,
        requested: usize,
        mut stats: EigenStats,
    ) -> Modes {
        let t = Instant::now();
        sel.sort_by(|a, b| self.values[*a].total_cmp(&self.values[*b]));
        let vectors = Mat::from_fn(self.n, sel.len(), |i, j| self.x.col(sel[j])[i]);
        // K X for every returned mode in one product (K read once, not once per mode)
        let kx = crate::csc::sym_mul_mat(self.pencil.k, vectors.as_ref()).expect("sizes checked");
        let (residuals, residual_kinds): (Vec<f64>, Vec<ResidualKind>) = sel
            .iter()
            .enumerate()
            .map(|(j, &s)| {
                residual_from(
                    slice(&kx, j),
                    self.pencil.norms(),
                    self.x.col(s),
                    self.mx.col(s),
                    self.values[s],
                )
            })
            .unzip();
        stats.ritz_seconds += t.elapsed().as_secs_f64();
        Modes {
            values: sel.iter().map(|s| self.values[*s]).collect(),
            vectors,
            residuals,
            residual_kinds,
            shifted_residuals: sel.iter().map(|s| self.shifted_res[*s]).collect(),
            requested,
            shift: sigma,
            sturm,
            stats,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `mw^T w` and the Euclidean norms of `w`'s columns, summed here entry by entry.
    fn gram_of(w: &Mat<f64>, mw: &Mat<f64>) -> Gram {
        let (n, k) = (w.nrows(), w.ncols());
        Gram {
            g: Mat::<f64>::from_fn(k, k, |a, b| (0..n).map(|i| mw[(i, a)] * w[(i, b)]).sum()),
            norms: (0..k)
                .map(|j| (0..n).map(|i| w[(i, j)] * w[(i, j)]).sum::<f64>().sqrt())
                .collect(),
        }
    }

    /// `R` and `Q` of `w = Q R` by modified Gram-Schmidt, twice, in the M inner product of the
    /// diagonal `m`: the reference for [`cholesky_qr2`].
    fn gram_schmidt_m(w: &Mat<f64>, m: &[f64]) -> (Mat<f64>, Mat<f64>) {
        let (n, k) = (w.nrows(), w.ncols());
        let mut q = w.clone();
        let mut r = Mat::<f64>::zeros(k, k);
        let m_dot = |a: &Mat<f64>, i: usize, b: &Mat<f64>, j: usize| -> f64 {
            (0..n).map(|p| a[(p, i)] * m[p] * b[(p, j)]).sum()
        };
        for j in 0..k {
            // modified Gram-Schmidt, twice
            for _ in 0..2 {
                for i in 0..j {
                    let c = m_dot(&q, i, &q, j);
                    r[(i, j)] += c;
                    for p in 0..n {
                        q[(p, j)] -= c * q[(p, i)];
                    }
                }
            }
            let nrm = m_dot(&q, j, &q, j).sqrt();
            r[(j, j)] = nrm;
            for p in 0..n {
                q[(p, j)] /= nrm;
            }
        }
        (q, r)
    }

    /// [`cholesky_qr2`] against the Gram-Schmidt above: the same `R` and `Q`, `Q` M-orthonormal
    /// to round-off and its images `M Q`, on blocks conditioned from about 1 to about 1e4 (rows
    /// split between threads; the best conditioned takes one pass, its Gram matrix after it the
    /// identity to 6.7e-16, the others two, theirs 7.5e-11 and 2.3e-7 from it); and a dependent
    /// column, a vanished one and one that kept only 1e-6 of its norm through the projection
    /// declined with the block left as it was.
    #[test]
    fn cholesky_qr2_matches_an_m_gram_schmidt_and_declines_dependent_blocks() {
        let (n, k) = (2 * PROJECT_ROWS + 9, 4);
        let m: Vec<f64> = (0..n).map(|i| 1.0 + (i % 7) as f64 * 0.5).collect();
        let images = |w: &Mat<f64>| Mat::<f64>::from_fn(n, w.ncols(), |i, j| m[i] * w[(i, j)]);
        for closeness in [1.0, 1e-2, 1e-4] {
            let mut w = Mat::<f64>::from_fn(n, k, |i, j| {
                ((i * 5 + j * 13 + (i * j) % 11) % 17) as f64 - 8.0
            });
            // the last column near the first: the block's condition grows as 1 / closeness
            for i in 0..n {
                w[(i, k - 1)] = w[(i, 0)] + closeness * w[(i, k - 1)];
            }
            let (q_ref, r_ref) = gram_schmidt_m(&w, &m);
            let before: Vec<f64> = (0..k).map(|j| w.col(j).norm_l2()).collect();
            let mut q = w.clone();
            let mut mq = images(&w);
            let gram = gram_of(&q, &mq);
            let r = cholesky_qr2(q.as_mut(), mq.as_mut(), &before, &gram)
                .expect("a well-conditioned block");
            let scale = r_ref[(0, 0)];
            for i in 0..k {
                for j in 0..k {
                    let expected = if i <= j { r_ref[(i, j)] } else { 0.0 };
                    assert!(
                        (r[(i, j)] - expected).abs() <= 1e-12 * scale,
                        "closeness {closeness}: R[{i}, {j}] = {} against {expected}",
                        r[(i, j)]
                    );
                }
            }
            let exact_images = images(&q);
            for j in 0..k {
                // the images follow by linearity, so they carry round-off times the block's
                // condition (about 1 / closeness); measured about one eps of the column's largest
                // image entry times that
                let scale = (0..n)
                    .map(|p| exact_images[(p, j)].abs())
                    .fold(0.0, f64::max);
                for i in 0..k {
                    let g: f64 = (0..n).map(|p| q[(p, i)] * m[p] * q[(p, j)]).sum();
                    let expected = if i == j { 1.0 } else { 0.0 };
                    assert!(
                        (g - expected).abs() <= 1e-13,
                        "closeness {closeness}: (Q^T M Q)[{i}, {j}] = {g}"
                    );
                }
                for p in 0..n {
                    // Q agrees with the Gram-Schmidt's to the block's condition times round-off
                    assert!((q[(p, j)] - q_ref[(p, j)]).abs() <= 1e-15 / closeness * 1e3);
                    let err = (mq[(p, j)] - exact_images[(p, j)]).abs();
                    assert!(
                        err <= 8.0 * f64::EPSILON * scale / closeness,
                        "image ({p}, {j})"
                    );
                }
            }
        }
        // a well-conditioned block whose last column kept only 1e-6 of its norm through the
        // projection (what is left is round-off, not a direction): declined, untouched
        let w = Mat::<f64>::from_fn(n, k, |i, j| {
            ((i * 5 + j * 13 + (i * j) % 11) % 17) as f64 - 8.0
        });
        let mut before: Vec<f64> = (0..k).map(|j| w.col(j).norm_l2()).collect();
        before[k - 1] *= 1e6;
        let (mut q, mut mq) = (w.clone(), images(&w));
        let mq0 = mq.clone();
        let gram = gram_of(&q, &mq);
        assert!(cholesky_qr2(q.as_mut(), mq.as_mut(), &before, &gram).is_none());
        assert!(q == w && mq == mq0);
        // a dependent column, and a column that vanished in the projection: declined, untouched
        let w = Mat::<f64>::from_fn(n, k, |i, j| match j {
            2 => 2.0 * ((i % 13) as f64 - 6.0) - ((i % 5) as f64),
            0 => (i % 13) as f64 - 6.0,
            1 => -((i % 5) as f64),
            _ => ((i * 7) % 3) as f64,
        });
        for before in [vec![1.0; k], vec![1.0, 1.0, 1.0, 1e12]] {
            let (mut q, mut mq) = (w.clone(), images(&w));
            let mq0 = mq.clone();
            let gram = gram_of(&q, &mq);
            assert!(cholesky_qr2(q.as_mut(), mq.as_mut(), &before, &gram).is_none());
            assert!(q == w && mq == mq0);
        }
    }

    /// [`project_out`] on more rows than one thread's part (so that, with two or more threads,
    /// the coefficients are summed from parts): against the coefficients `v^T w` and the
    /// projected block computed here by hand, with `M = I` (`mv = v`).
    #[test]
    fn project_out_matches_the_hand_computed_projection() {
        let (n, m, k) = (3 * PROJECT_ROWS + 17, 7, 4);
        // orthonormal columns: disjoint supports, each scaled to unit length
        let v = Mat::<f64>::from_fn(n, m, |i, j| {
            if i % m == j {
                1.0 / ((n - j).div_ceil(m) as f64).sqrt()
            } else {
                0.0
            }
        });
        let w0 = Mat::<f64>::from_fn(n, k, |i, j| ((i * 7 + j * 11) % 23) as f64 - 11.0);
        let mut w = w0.clone();
        let c = project_out(v.as_ref(), v.as_ref(), w.as_mut());
        for a in 0..m {
            for b in 0..k {
                let expected: f64 = (0..n).map(|i| v[(i, a)] * w0[(i, b)]).sum();
                assert!(
                    (c[(a, b)] - expected).abs() <= 1e-12 * expected.abs().max(1.0),
                    "c[{a}, {b}] = {} against {expected}",
                    c[(a, b)]
                );
            }
        }
        for i in 0..n {
            for b in 0..k {
                let expected = w0[(i, b)] - (0..m).map(|a| v[(i, a)] * c[(a, b)]).sum::<f64>();
                assert!((w[(i, b)] - expected).abs() <= 1e-12 * w0[(i, b)].abs().max(1.0));
            }
        }
    }

    /// [`project_block`] with a diagonal `M` (not the identity), two locked columns and eight basis
    /// columns, M-orthonormal by construction (disjoint supports, each scaled here to unit
    /// M-norm), the local pass on the last two. A block nearly in the span of the basis (`1e-8`
    /// of it outside, as near an invariant subspace) loses about `eps / 1e-8` of orthogonality in
    /// one pass: the test must ask for the second pass and end orthogonal to working precision.
    /// A block whose large part lies on the local columns passes with one. In both, the
    /// coefficients are the M inner products computed here by hand and `mw` is `M w`.
    #[test]
    fn project_block_reprojects_only_when_one_pass_cannot_be_orthogonal() {
        let (n, classes) = (3 * PROJECT_ROWS + 17, 10);
        let mdiag: Vec<f64> = (0..n).map(|i| 1.0 + (i % 7) as f64).collect();
        let mut t = sprs::TriMat::new((n, n));
        for (i, d) in mdiag.iter().enumerate() {
            t.add_triplet(i, i, *d);
        }
        let m: SparseMatrix = t.to_csc();
        // column c of the ten lives on the rows i with i % 10 == c, with unit M-norm
        let unit: Vec<f64> = (0..classes)
            .map(|c| {
                let s: f64 = (0..n).filter(|i| i % classes == c).map(|i| mdiag[i]).sum();
                1.0 / s.sqrt()
            })
            .collect();
        let cols = |from: usize, k: usize| {
            Mat::<f64>::from_fn(n, k, |i, j| {
                if i % classes == from + j {
                    unit[from + j]
                } else {
                    0.0
                }
            })
        };
        let images =
            |a: &Mat<f64>| Mat::<f64>::from_fn(a.nrows(), a.ncols(), |i, j| mdiag[i] * a[(i, j)]);
        let (x, v) = (cols(0, 2), cols(2, 8));
        let (mx, mv) = (images(&x), images(&v));
        let generic = |i: usize, j: usize| ((i as f64) * 0.37 + (j as f64) * 1.3).sin();
        for (outside, on_all, expect_again) in [(1e-8, true, true), (1.0, false, false)] {
            // w0 = V C + X D + outside R: C on every basis column, or only on the local two
            let w0 = Mat::<f64>::from_fn(n, 3, |i, j| {
                let mut s = outside * generic(i, j);
                for a in 0..8 {
                    if on_all || a >= 6 {
                        s += (1.0 + a as f64 + 3.0 * j as f64) * v[(i, a)];
                    }
                }
                s + 0.5 * x[(i, 0)] - 0.25 * x[(i, 1)]
            });
            let mut w = w0.clone();
            let mut mw = Mat::<f64>::zeros(n, 3);
            let Projected {
                coef,
                again,
                before,
                gram,
            } = project_block(
                &m,
                (x.as_ref(), mx.as_ref()),
                (v.as_ref(), mv.as_ref()),
                6,
                w.as_mut(),
                mw.as_mut(),
            );
            assert_eq!(again, expect_again, "outside {outside:e}");
            // the norms before, and the Gram matrix and norms after, against sums written here
            for j in 0..3 {
                let b: f64 = (0..n).map(|i| w0[(i, j)] * w0[(i, j)]).sum::<f64>().sqrt();
                assert!((before[j] - b).abs() <= 1e-14 * b, "norm before {j}");
                let a: f64 = (0..n).map(|i| w[(i, j)] * w[(i, j)]).sum::<f64>().sqrt();
                assert!((gram.norms[j] - a).abs() <= 1e-13 * a, "norm after {j}");
                for c in 0..3 {
                    let g: f64 = (0..n).map(|i| mdiag[i] * w[(i, j)] * w[(i, c)]).sum();
                    let scale = gram.g[(j, j)].max(gram.g[(c, c)]);
                    assert!(
                        (gram.g[(j, c)] - g).abs() <= 1e-13 * scale,
                        "outside {outside:e}: G[{j}, {c}] = {} against {g}",
                        gram.g[(j, c)]
                    );
                }
            }
            for j in 0..3 {
                let m_norm = (0..n)
                    .map(|i| mdiag[i] * w[(i, j)] * w[(i, j)])
                    .sum::<f64>()
                    .sqrt();
                let scale = (0..n)
                    .map(|i| mdiag[i] * w0[(i, j)] * w0[(i, j)])
                    .sum::<f64>()
                    .sqrt();
                for (name, basis) in [("locked", &x), ("basis", &v)] {
                    for a in 0..basis.ncols() {
                        let ip: f64 = (0..n).map(|i| basis[(i, a)] * mdiag[i] * w[(i, j)]).sum();
                        assert!(
                            ip.abs() <= 1e-14 * m_norm,
                            "outside {outside:e}: column {j} against {name} {a}: {ip:e} of {m_norm:e}"
                        );
                    }
                }
                for a in 0..8 {
                    let exact: f64 = (0..n).map(|i| v[(i, a)] * mdiag[i] * w0[(i, j)]).sum();
                    assert!(
                        (coef[(a, j)] - exact).abs() <= 1e-13 * scale,
                        "outside {outside:e}: coefficient ({a}, {j}) {} against {exact}",
                        coef[(a, j)]
                    );
                }
                for i in 0..n {
                    assert!((mw[(i, j)] - mdiag[i] * w[(i, j)]).abs() <= 1e-15 * scale);
                }
            }
        }
    }
}
