//! Sparse Cholesky `LL^T` and `LDL^T` factorizations, with the symbolic analysis (faer's) done
//! once per sparsity pattern and reused for new values and new shifts, and the inertia of
//! `LDL^T`. The numeric `LDL^T` of a supernodal analysis is femu's subtree-parallel multifrontal
//! one (docs/SCALING.md, "A subtree-parallel factorization"), stored in femu's layout (each
//! supernode's columns in chunks of 64, docs/SCALING.md "The factor's layout") and solved by
//! femu's subtree-parallel solve; `LL^T` and small (simplicial) analyses are faer's.
//!
//! By Sylvester's law of inertia, `K - sigma M = L D L^T` has as many negative pivots in `D` as
//! the pencil `(K, M)` has eigenvalues below `sigma` (M positive definite): the Sturm count that
//! proves an eigensolver skipped no mode.

use crate::ordering::{Ordering, Pattern, pattern_ordering};
use crate::{SparseError, SparseMatrix};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::ldlt::factor::LdltRegularization;
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::reborrow::Reborrow;
use faer::sparse::SparseColMatRef;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LdltRef, LltRef, SymbolicCholesky, SymbolicCholeskyRaw,
    SymmetricOrdering, factorize_symbolic_cholesky, supernodal::SupernodalLltRef,
};
use faer::{Conj, MatMut, Par, Side};
use rayon::prelude::*;
use std::sync::{Arc, Mutex};

/// A faer view of a [`SparseMatrix`] (CSC, `usize` indices): no copy.
///
/// # Errors
/// [`SparseError::DimensionMismatch`] if `a` is not square or not in CSC storage.
pub fn faer_view(a: &SparseMatrix) -> Result<SparseColMatRef<'_, usize, f64>, SparseError> {
    Ok(SparseColMatRef::new(Pattern::of(a)?.faer(), a.data()))
}

/// Below this ratio `L_jj^2 / A_jj` of a pivot to its diagonal entry, a Cholesky factorization
/// that succeeded is declared singular to working precision (`1e-12`, about `n eps` for the
/// models femu solves: a condition number above `1e12` leaves no correct digit in a solve, and a
/// free-free stiffness whose rigid-body pivots round-off left positive lands near `1e-14`).
pub const SINGULAR_PIVOT_RATIO: f64 = 1e-12;

/// The parallelism given to faer inside one triangular solve: sequential; solves use the threads
/// across right-hand sides instead ([`split_columns`]), or, for a large `LDL^T` of a supernodal
/// analysis, across subtrees (docs/SCALING.md, "A subtree-parallel solve"). Measured on two
/// cores (docs/SCALING.md, "Threads in the sparse kernels"): 4 right-hand sides of the
/// 199,200-DOF plate took 263 ms with faer's two threads inside, 189 ms sequential and 152 ms as
/// two sequential solves of two.
const KERNEL_PAR: Par = Par::Seq;

/// A factor with at least this many values (16 MB, beyond the last-level cache) is solved
/// subtree-parallel on several threads (docs/SCALING.md, "A subtree-parallel solve"); a smaller
/// one by faer's solve. Below it the solve is short and the tree's per-front work dominates:
/// `femu-update`'s tests (small models) took 43-48 s with every factor solved subtree-parallel
/// and 28-32 s with faer's solve.
const SUBTREE_SOLVE_VALUES: usize = 1 << 21;

/// Above this many flops per column (`flops / n`, a measure of the typical dense front), one of
/// faer's numeric factorizations (`LL^T`, and `LDL^T` where the subtree-parallel one does not
/// apply) gets the global parallelism; below it, one thread. faer walks the
/// supernodes one after another and parallelises only inside each supernode's dense kernels,
/// which pays only when the fronts are large. Measured on two cores (docs/SCALING.md): the
/// 199,200-DOF plate (3.1e5 flops per column) factors in 2.2 s on one thread and 2.8 s on two;
/// the clamped block of 52,920 DOF (8.6e5) in 1.25 s either way; that of 141,288 DOF (2.3e6) in
/// 7.6 s on one thread and 6.4 s on two.
const PARALLEL_FLOPS_PER_COLUMN: f64 = 1.5e6;

/// Applies `solve` to the columns of `rhs` split into one contiguous chunk per rayon thread (or
/// per column, when fewer), the chunks in parallel: each solve reads the whole factor once for
/// its chunk, so the threads share the memory traffic instead of faer's small dense kernels.
/// 4 right-hand sides of the 199,200-DOF plate: 152 ms (two chunks of two) against 263 ms with
/// faer's own two threads (docs/SCALING.md).
pub(crate) fn split_columns(
    rhs: MatMut<'_, f64>,
    parts: usize,
    solve: &(impl Fn(MatMut<'_, f64>) + Sync),
) {
    if parts <= 1 || rhs.ncols() <= 1 {
        solve(rhs);
        return;
    }
    let left = parts / 2;
    let cut = (rhs.ncols() * left / parts).max(1);
    let (l, r) = rhs.split_at_col_mut(cut);
    rayon::join(
        || split_columns(l, left, solve),
        || split_columns(r, parts - left, solve),
    );
}

/// The symbolic analysis of a symmetric sparsity pattern: fill-reducing ordering and elimination
/// structure. Shared (cheaply cloned) by every numeric factorization on the same pattern.
#[derive(Debug, Clone)]
pub struct SymbolicFactor {
    inner: Arc<SymbolicCholesky<usize>>,
    /// faer's parallelism for a numeric factorization (see [`PARALLEL_FLOPS_PER_COLUMN`])
    factor_par: Par,
    n: usize,
    nnz: usize,
    ordering: Ordering,
    /// the supernodal elimination tree for the subtree-parallel `LDL^T` (`None`: faer's own)
    tree: Option<Arc<crate::multifrontal::Tree>>,
    /// stored entries of the lower triangle (the permuted copy's size)
    lower_nnz: usize,
    /// the analysed pattern's [`Pattern::fingerprint`]
    fingerprint: u64,
    /// how long the ordering and the analysis took, seconds
    seconds: f64,
    /// the values of the last dropped factor on this analysis, reused by the next one: fresh
    /// memory costs a page fault per 4 KiB, 3.3 s for the 2.3 GB factor of the 209,088-DOF
    /// block (docs/SCALING.md, "A subtree-parallel factorization")
    spare: Arc<Spare>,
}

/// The values kept for reuse (`SymbolicFactor::spare`); its `Debug` shows their number only.
#[derive(Default)]
struct Spare(Mutex<Vec<f64>>);

impl std::fmt::Debug for Spare {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let len = self.0.lock().map_or(0, |v| v.len());
        write!(f, "Spare({len} values)")
    }
}

/// The inertia of a symmetric matrix: numbers of negative, zero and positive eigenvalues.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Inertia {
    /// Negative pivots of `D`: eigenvalues below the shift (Sturm count).
    pub negative: usize,
    /// Exactly zero pivots (the factorization fails on these, so normally 0).
    pub zero: usize,
    /// Positive pivots.
    pub positive: usize,
}

impl Inertia {
    /// No pivots.
    pub(crate) const NONE: Self = Self {
        negative: 0,
        zero: 0,
        positive: 0,
    };

    /// Counts the pivot `d` (NaN counts as zero: it is no evidence of a sign).
    pub(crate) fn count(&mut self, d: f64) {
        if d < 0.0 {
            self.negative += 1;
        } else if d > 0.0 {
            self.positive += 1;
        } else {
            self.zero += 1;
        }
    }

    /// The pivots of both.
    pub(crate) fn merged(self, other: Self) -> Self {
        Self {
            negative: self.negative + other.negative,
            zero: self.zero + other.zero,
            positive: self.positive + other.positive,
        }
    }
}

impl SymbolicFactor {
    /// Analyses the pattern of the symmetric matrix `a` (both triangles stored; the lower one is
    /// read) with the given fill-reducing ordering.
    ///
    /// # Errors
    /// [`SparseError::DimensionMismatch`] for a non-square or CSR matrix,
    /// [`SparseError::Factorization`] if the analysis fails (out of memory).
    pub fn new(a: &SparseMatrix, ordering: Ordering) -> Result<Self, SparseError> {
        Self::of_pattern(Pattern::of(a)?, ordering)
    }

    /// Analyses a symmetric pattern (both triangles stored; the lower one is read) before any
    /// values exist: an assembler's, while it assembles the values on the other threads
    /// (docs/SCALING.md, "The analysis beside the assembly"). A pattern that is not symmetric
    /// is analysed as its symmetric closure for the ordering.
    ///
    /// # Errors
    /// [`SparseError::Factorization`] if the analysis fails (out of memory).
    pub fn of_pattern(p: Pattern<'_>, ordering: Ordering) -> Result<Self, SparseError> {
        let started = std::time::Instant::now();
        let n = p.dim();
        let perm = pattern_ordering(p, ordering)?;
        let sym_ordering = match &perm {
            Some((fwd, inv)) => {
                SymmetricOrdering::Custom(faer::perm::PermRef::new_checked(fwd, inv, n))
            }
            None => SymmetricOrdering::Amd,
        };
        let view = p.faer();
        let (inner, fingerprint) = rayon::join(
            || {
                factorize_symbolic_cholesky(
                    view,
                    Side::Lower,
                    sym_ordering,
                    CholeskySymbolicParams::default(),
                )
            },
            || p.fingerprint(),
        );
        let inner = inner.map_err(|e| SparseError::Factorization {
            reason: format!("symbolic analysis: {e:?}"),
        })?;
        let tree = match inner.raw() {
            SymbolicCholeskyRaw::Supernodal(s) => crate::multifrontal::Tree::new(s),
            SymbolicCholeskyRaw::Simplicial(_) => None,
        };
        let mut symbolic = Self {
            inner: Arc::new(inner),
            factor_par: Par::Seq,
            tree: tree.map(Arc::new),
            lower_nnz: p.lower_nnz(),
            fingerprint,
            seconds: 0.0,
            spare: Arc::default(),
            n,
            nnz: p.nnz(),
            ordering,
        };
        if symbolic.flops() > PARALLEL_FLOPS_PER_COLUMN * symbolic.n.max(1) as f64 {
            symbolic.factor_par = faer::get_global_parallelism();
        }
        symbolic.seconds = started.elapsed().as_secs_f64();
        Ok(symbolic)
    }

    /// Whether this analysis is of `a`'s pattern: same dimension, number of entries and
    /// [`Pattern::fingerprint`]. An analysis kept beside a matrix (`SystemMatrices`) is used only
    /// when this holds, so a matrix changed after its analysis is analysed again, not factored on
    /// the wrong structure.
    pub fn is_for(&self, a: &SparseMatrix) -> bool {
        Pattern::of(a).is_ok_and(|p| {
            p.dim() == self.n && p.nnz() == self.nnz && p.fingerprint() == self.fingerprint
        })
    }

    /// Seconds the ordering and the analysis took (wall time of [`SymbolicFactor::of_pattern`]).
    pub fn seconds(&self) -> f64 {
        self.seconds
    }

    /// The same analysis with nothing kept from earlier factorizations: an analysis held beside
    /// its matrices lends copies of itself, so that the values of a factor it reused
    /// (`spare`, up to the size of a factor) are freed with the solve that used them.
    pub fn detached(&self) -> Self {
        Self {
            spare: Arc::default(),
            ..self.clone()
        }
    }

    /// Matrix dimension.
    pub fn dim(&self) -> usize {
        self.n
    }

    /// Number of stored values of the factor `L` (a measure of fill): in femu's layout, whose
    /// diagonal blocks store only their chunks' triangles square (docs/SCALING.md, "The factor's
    /// layout"), where the subtree-parallel factorization applies; else in faer's.
    pub fn factor_len(&self) -> usize {
        match &self.tree {
            Some(tree) => tree.len_val(),
            None => self.inner.len_val(),
        }
    }

    /// Floating-point operations of one numeric factorization with this analysis: the classical
    /// count `sum_j (b_j^2 + 2 b_j)` over the columns `j` of `L`, `b_j` the entries below the
    /// diagonal of column `j` (a multiply and an add for each entry of the rank-one update of the
    /// trailing triangle, one division per entry for the scaling), as CHOLMOD and PARDISO report
    /// it up to lower-order terms. Factorization rates in GFLOP/s (docs/SCALING.md) divide this
    /// count by the measured time.
    pub fn flops(&self) -> f64 {
        let count = |b: f64| b * b + 2.0 * b;
        match self.inner.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                let ptr = s.col_ptr();
                (0..s.nrows())
                    .map(|j| count((ptr[j + 1] - ptr[j]) as f64 - 1.0))
                    .sum()
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                let (begin, end) = (s.supernode_begin(), s.supernode_end());
                let below = s.nnz_per_super();
                (0..s.n_supernodes())
                    .map(|k| {
                        let c = end[k] - begin[k];
                        (0..c)
                            .map(|j| count((c - 1 - j + below[k]) as f64))
                            .sum::<f64>()
                    })
                    .sum()
            }
        }
    }

    /// The fill-reducing permutation the analysis factors with: entry `k` is the original index
    /// of the `k`-th pivot (`fwd[new] = old`, the ordering chosen by [`Ordering`] and the
    /// elimination tree's postorder); `None` for the identity. Another solver given this
    /// permutation factors the same `L` (docs/SCALING.md, "PARDISO's flop count").
    pub fn permutation(&self) -> Option<&[usize]> {
        self.inner.perm().map(|p| p.arrays().0)
    }

    /// Whether faer chose its supernodal (blocked) factorization for this pattern.
    pub fn is_supernodal(&self) -> bool {
        matches!(self.inner.raw(), SymbolicCholeskyRaw::Supernodal(_))
    }

    /// The ordering used.
    pub fn ordering(&self) -> Ordering {
        self.ordering
    }

    fn check(&self, a: &SparseMatrix) -> Result<(), SparseError> {
        if a.rows() != self.n || a.nnz() != self.nnz {
            return Err(SparseError::DimensionMismatch {
                what: "matrix against its symbolic analysis (n, nnz)",
                expected: self.n,
                got: a.rows(),
            });
        }
        Ok(())
    }

    /// Original (unpermuted) index of the failing pivot that faer reports as `k`: its simplicial
    /// path reports `k + 1` (one-based), its supernodal path `k`.
    fn original_index(&self, k: usize) -> usize {
        let k = match self.inner.raw() {
            SymbolicCholeskyRaw::Simplicial(_) => k.saturating_sub(1),
            SymbolicCholeskyRaw::Supernodal(_) => k,
        };
        self.permutation().map_or(k, |fwd| fwd[k])
    }

    /// Numeric `LL^T` of a symmetric positive definite matrix with this pattern.
    ///
    /// # Errors
    /// [`SparseError::NotPositiveDefinite`] with the original index of the failing pivot;
    /// [`SparseError::NumericallySingular`] when every pivot is positive but one is below
    /// [`SINGULAR_PIVOT_RATIO`] of its diagonal entry (a singular matrix that round-off made look
    /// definite: its solves would be dominated by the null space).
    pub fn llt(&self, a: &SparseMatrix, name: &'static str) -> Result<Llt, SparseError> {
        self.check(a)?;
        let view = faer_view(a)?;
        let par = self.factor_par;
        let mut values = vec![0.0; self.inner.len_val()];
        let mut mem = MemBuffer::new(
            self.inner
                .factorize_numeric_llt_scratch::<f64>(par, Default::default()),
        );
        self.inner
            .factorize_numeric_llt(
                &mut values,
                view,
                Side::Lower,
                LltRegularization::default(),
                par,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .map_err(|e| match e {
                faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index } => {
                    SparseError::NotPositiveDefinite {
                        matrix: name,
                        index: self.original_index(index),
                    }
                }
            })?;
        let (pivot_ratio, pivot_index) = min_pivot_ratio(&self.inner, &values, a);
        if pivot_ratio < SINGULAR_PIVOT_RATIO {
            return Err(SparseError::NumericallySingular {
                matrix: name,
                index: pivot_index,
                ratio: pivot_ratio,
            });
        }
        Ok(Llt {
            symbolic: self.clone(),
            values,
            pivot_ratio,
            pivot_index,
        })
    }

    /// Numeric `LDL^T` (no pivoting) of a symmetric matrix with this pattern, for example
    /// `K - sigma M`, with its [`Inertia`]: on a supernodal analysis by the subtree-parallel
    /// multifrontal factorization on the rayon threads (docs/SCALING.md, "A subtree-parallel
    /// factorization"), else by faer's. The values of the last dropped factor on this analysis
    /// are reused: an analysis keeps one factor's memory after its factors are dropped.
    ///
    /// # Errors
    /// [`SparseError::Singular`] on an exactly zero pivot (shift on an eigenvalue), with its
    /// original index.
    pub fn ldlt(&self, a: &SparseMatrix, name: &'static str) -> Result<Ldlt, SparseError> {
        self.ldlt_values(a, a.data(), name)
    }

    /// [`SymbolicFactor::ldlt`] of the matrix with `pattern`'s structure and the given values
    /// (for example `K - sigma M` on `K`'s pattern): no copy of the structure per shift.
    ///
    /// # Errors
    /// As [`SymbolicFactor::ldlt`], and [`SparseError::DimensionMismatch`] if `values` does not
    /// match the pattern.
    pub fn ldlt_values(
        &self,
        pattern: &SparseMatrix,
        values: &[f64],
        name: &'static str,
    ) -> Result<Ldlt, SparseError> {
        let view = self.values_view(pattern, values)?;
        match self.multifrontal(Input::Values(view), true, name) {
            Some(factor) => factor.map(|(values, inertia)| self.ldlt_of(values, inertia)),
            None => self.faer_ldlt(view, name),
        }
    }

    /// The inertia of the matrix with `pattern`'s structure and the given values, as
    /// [`SymbolicFactor::ldlt_values`] would give it, without keeping the factor: on the
    /// subtree-parallel factorization no factor is ever allocated (one front at a time per
    /// thread), and the values a dropped factor left for reuse are freed: a Sturm count holds
    /// less memory than a factorization to solve with.
    ///
    /// # Errors
    /// As [`SymbolicFactor::ldlt_values`].
    pub fn inertia_values(
        &self,
        pattern: &SparseMatrix,
        values: &[f64],
        name: &'static str,
    ) -> Result<Inertia, SparseError> {
        let view = self.values_view(pattern, values)?;
        match self.multifrontal(Input::Values(view), false, name) {
            Some(count) => count.map(|(_, inertia)| inertia),
            None => Ok(self.faer_ldlt(view, name)?.inertia),
        }
    }

    /// [`SymbolicFactor::ldlt_values`] of `sum_t scale_t A_t` (`terms`), where `pattern` is the
    /// analysed matrix and every `A_t` a symmetric matrix stored with both triangles whose pattern
    /// lies inside `pattern`'s (the caller checks both: `Pencil` does for `K - sigma M`). The
    /// subtree-parallel factorization reads the terms where they are, so neither the sum's
    /// values nor a permuted copy of the matrix is held; faer's factorization gets `values()`,
    /// the sum on `pattern`'s structure.
    pub(crate) fn ldlt_sum(
        &self,
        pattern: &SparseMatrix,
        terms: &[(&SparseMatrix, f64)],
        values: impl FnOnce() -> Vec<f64>,
        name: &'static str,
    ) -> Result<Ldlt, SparseError> {
        self.check(pattern)?;
        match self.multifrontal(Input::Sum(terms), true, name) {
            Some(factor) => factor.map(|(values, inertia)| self.ldlt_of(values, inertia)),
            None => self.ldlt_values(pattern, &values(), name),
        }
    }

    /// [`SymbolicFactor::inertia_values`] of `sum_t scale_t A_t`, as in
    /// [`SymbolicFactor::ldlt_sum`].
    pub(crate) fn inertia_sum(
        &self,
        pattern: &SparseMatrix,
        terms: &[(&SparseMatrix, f64)],
        values: impl FnOnce() -> Vec<f64>,
        name: &'static str,
    ) -> Result<Inertia, SparseError> {
        self.check(pattern)?;
        match self.multifrontal(Input::Sum(terms), false, name) {
            Some(count) => count.map(|(_, inertia)| inertia),
            None => self.inertia_values(pattern, &values(), name),
        }
    }

    /// faer's own left-looking supernodal `LDL^T` (one supernode after another, threads inside
    /// the dense kernels), which [`SymbolicFactor::ldlt_values`] replaced by the
    /// subtree-parallel one: kept to compare the two (`benches/factor.rs`, the tests).
    ///
    /// # Errors
    /// As [`SymbolicFactor::ldlt_values`].
    pub fn ldlt_left_looking(
        &self,
        pattern: &SparseMatrix,
        values: &[f64],
        name: &'static str,
    ) -> Result<Ldlt, SparseError> {
        self.faer_ldlt(self.values_view(pattern, values)?, name)
    }

    /// The supernodal analysis and its tree, when the subtree-parallel `LDL^T` applies.
    fn subtree_parallel(
        &self,
    ) -> Option<(
        &faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky<usize>,
        &crate::multifrontal::Tree,
    )> {
        match (self.inner.raw(), &self.tree) {
            (SymbolicCholeskyRaw::Supernodal(s), Some(tree)) => Some((s, tree)),
            _ => None,
        }
    }

    fn values_view<'v>(
        &self,
        pattern: &'v SparseMatrix,
        values: &'v [f64],
    ) -> Result<SparseColMatRef<'v, usize, f64>, SparseError> {
        self.check(pattern)?;
        if values.len() != pattern.nnz() {
            return Err(SparseError::DimensionMismatch {
                what: "values against the pattern",
                expected: pattern.nnz(),
                got: values.len(),
            });
        }
        Ok(SparseColMatRef::new(faer_view(pattern)?.symbolic(), values))
    }

    /// faer's own left-looking supernodal (or simplicial) `LDL^T` of `view`.
    fn faer_ldlt(
        &self,
        view: SparseColMatRef<'_, usize, f64>,
        name: &'static str,
    ) -> Result<Ldlt, SparseError> {
        let par = self.factor_par;
        let mut values = vec![0.0; self.inner.len_val()];
        let mut mem = MemBuffer::new(
            self.inner
                .factorize_numeric_ldlt_scratch::<f64>(par, Default::default()),
        );
        self.inner
            .factorize_numeric_ldlt(
                &mut values,
                view,
                Side::Lower,
                LdltRegularization::default(),
                par,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .map_err(|e| match e {
                faer::linalg::cholesky::ldlt::factor::LdltError::ZeroPivot { index } => {
                    SparseError::Singular {
                        matrix: name,
                        index: self.original_index(index),
                    }
                }
            })?;
        let inertia = inertia_of(&self.inner, &values);
        Ok(Ldlt {
            symbolic: self.clone(),
            values,
            inertia,
            femu_layout: false,
        })
    }

    /// An `LDL^T` of this analysis with its values (in femu's layout: the subtree-parallel
    /// factorization's) and inertia.
    fn ldlt_of(&self, values: Vec<f64>, inertia: Inertia) -> Ldlt {
        Ldlt {
            symbolic: self.clone(),
            values,
            inertia,
            femu_layout: true,
        }
    }

    /// The subtree-parallel multifrontal `LDL^T` of `input` on the rayon threads
    /// (docs/SCALING.md, "A subtree-parallel factorization"): the factor in femu's layout
    /// ([`crate::multifrontal::Layout`]) when `store` (else empty) and the inertia; `None` when
    /// the analysis is not supernodal with a tree (the caller then uses faer's). Without `store` (a count, which
    /// ends a solve: the Sturm check) the values a dropped factor left for reuse are freed first,
    /// so that the fronts do not add to them.
    fn multifrontal(
        &self,
        input: Input<'_>,
        store: bool,
        name: &'static str,
    ) -> Option<Result<(Vec<f64>, Inertia), SparseError>> {
        let (s, tree) = self.subtree_parallel()?;
        if !store && let Ok(mut spare) = self.spare.0.lock() {
            *spare = Vec::new();
        }
        Some(self.multifrontal_on(s, tree, input, store, name))
    }

    fn multifrontal_on(
        &self,
        s: &faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky<usize>,
        tree: &crate::multifrontal::Tree,
        input: Input<'_>,
        store: bool,
        name: &'static str,
    ) -> Result<(Vec<f64>, Inertia), SparseError> {
        let n = self.n;
        let (mut val, mut col_ptr, mut row_idx) = (Vec::new(), Vec::new(), Vec::new());
        let permuted;
        let entries = match (input, self.inner.perm()) {
            // read in place: no copy
            (Input::Sum(terms), perm) => crate::multifrontal::Entries::Sum {
                terms: terms.to_vec(),
                perm: perm.map(|p| p.arrays()),
            },
            (Input::Values(view), perm) => crate::multifrontal::Entries::Lower(match perm {
                Some(perm) => {
                    val.resize(self.lower_nnz, 0.0);
                    col_ptr.resize(n + 1, 0usize);
                    row_idx.resize(self.lower_nnz, 0usize);
                    let mut mem = MemBuffer::new(
                        faer::sparse::utils::permute_self_adjoint_scratch::<usize>(n),
                    );
                    permuted = faer::sparse::utils::permute_self_adjoint_to_unsorted(
                        &mut val,
                        &mut col_ptr,
                        &mut row_idx,
                        view,
                        perm,
                        Side::Lower,
                        Side::Lower,
                        MemStack::new(&mut mem),
                    );
                    permuted.rb()
                }
                // the full symmetric matrix: the factorization reads its lower triangle
                None => view,
            }),
        };
        let mut values = Vec::new();
        if store {
            let len = tree.len_val();
            values = self
                .spare
                .0
                .lock()
                .ok()
                .map(|mut spare| std::mem::take(&mut *spare))
                .filter(|v| v.len() == len)
                .unwrap_or_else(|| vec![0.0; len]);
            // zeroed in order, in parallel pieces: the fronts' scattered first touches of fresh
            // pages from two threads contend in the kernel
            values
                .par_chunks_mut(1 << 16)
                .for_each(|piece| piece.fill(0.0));
        }
        let threads = rayon::current_num_threads();
        let slot = store.then_some(&mut values[..]);
        let inertia = crate::multifrontal::factor(tree, s, &entries, slot, threads);
        if store {
            // the fronts' freed buffers back to the system before the factor's user allocates
            // (an eigensolve's basis): the command's peak is then the factorization's or the
            // basis's, not both with the allocator's kept memory on top
            crate::multifrontal::release_free_memory();
        }
        let inertia = inertia.map_err(|k| SparseError::Singular {
            matrix: name,
            index: self.original_index(k),
        })?;
        Ok((values, inertia))
    }
}

/// What `SymbolicFactor::multifrontal` factors.
enum Input<'a> {
    /// Values on the analysed pattern (a permuted copy of its lower triangle is made).
    Values(SparseColMatRef<'a, usize, f64>),
    /// `sum_t scale_t A_t`, read in place (`SymbolicFactor::ldlt_sum`).
    Sum(&'a [(&'a SparseMatrix, f64)]),
}

/// The diagonal of the factor `L` of an `LL^T` (or `D` of an `LDL^T`: the values are stored in
/// the same layout) in elimination order.
fn factor_diagonal(symbolic: &SymbolicCholesky<usize>, values: &[f64]) -> Vec<f64> {
    match symbolic.raw() {
        SymbolicCholeskyRaw::Simplicial(s) => {
            let col_ptr = s.col_ptr();
            // the diagonal is the first stored entry of each column of L
            (0..s.nrows()).map(|j| values[col_ptr[j]]).collect()
        }
        SymbolicCholeskyRaw::Supernodal(s) => {
            let l = SupernodalLltRef::new(s, values);
            let mut d = Vec::with_capacity(s.nrows());
            for k in 0..s.n_supernodes() {
                let v = l.supernode(k).val();
                d.extend((0..v.ncols()).map(|j| v[(j, j)]));
            }
            d
        }
    }
}

/// `min_j L_jj^2 / A_pp` over the pivots (`p` the original index of pivot `j`) and that `p`.
fn min_pivot_ratio(
    symbolic: &SymbolicCholesky<usize>,
    values: &[f64],
    a: &SparseMatrix,
) -> (f64, usize) {
    let diag = crate::csc::diagonal(a);
    let perm = symbolic.perm().map(|p| p.arrays().0);
    let mut best = (f64::INFINITY, 0);
    for (j, l) in factor_diagonal(symbolic, values).into_iter().enumerate() {
        let p = perm.map_or(j, |perm| perm[j]);
        let r = l * l / diag[p];
        if r < best.0 {
            best = (r, p);
        }
    }
    best
}

/// Signs of the pivots `D` of an `LDL^T` factor.
fn inertia_of(symbolic: &SymbolicCholesky<usize>, values: &[f64]) -> Inertia {
    let mut inertia = Inertia::NONE;
    for d in factor_diagonal(symbolic, values) {
        inertia.count(d);
    }
    inertia
}

/// A numeric factorization that solves `A x = b`.
pub trait Factorization {
    /// Matrix dimension.
    fn dim(&self) -> usize;
    /// Overwrites the columns of `rhs` with `A^-1 rhs`.
    fn solve_in_place(&self, rhs: MatMut<'_, f64>);
    /// `A^-1 b` for one vector.
    fn solve(&self, b: &mut [f64]) {
        let n = b.len();
        self.solve_in_place(faer::MatMut::from_column_major_slice_mut(b, n, 1));
    }
}

/// A numeric `LL^T` factorization.
#[derive(Debug, Clone)]
pub struct Llt {
    symbolic: SymbolicFactor,
    values: Vec<f64>,
    pivot_ratio: f64,
    pivot_index: usize,
}

impl Llt {
    /// The smallest ratio `L_jj^2 / A_jj` of a pivot to its matrix diagonal, and the original
    /// index of that pivot. It is 1 for a diagonal matrix and near the round-off (`1e-16`) when
    /// `A` is singular in exact arithmetic and the factorization succeeded only by round-off: for
    /// such a ratio, `A^-1 b` is dominated by the null space and means nothing.
    pub fn min_pivot_ratio(&self) -> (f64, usize) {
        (self.pivot_ratio, self.pivot_index)
    }
}

/// A numeric `LDL^T` factorization and its inertia.
#[derive(Debug, Clone)]
pub struct Ldlt {
    symbolic: SymbolicFactor,
    values: Vec<f64>,
    inertia: Inertia,
    /// whether `values` are in femu's layout (chunks, docs/SCALING.md "The factor's layout"),
    /// which only femu's solve reads, or in faer's
    femu_layout: bool,
}

impl Drop for Ldlt {
    /// Hands the values to the analysis for the next factorization (see `SymbolicFactor::spare`).
    fn drop(&mut self) {
        if let Ok(mut spare) = self.symbolic.spare.0.lock()
            && spare.len() < self.values.len()
        {
            *spare = std::mem::take(&mut self.values);
        }
    }
}

impl Ldlt {
    /// The inertia: `negative` is the number of eigenvalues of the factored pencil below the shift.
    pub fn inertia(&self) -> Inertia {
        self.inertia
    }
}

fn scratch_solve(symbolic: &SymbolicCholesky<usize>, ncols: usize) -> MemBuffer {
    MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(ncols, KERNEL_PAR))
}

impl Factorization for Llt {
    fn dim(&self) -> usize {
        self.symbolic.n
    }
    fn solve_in_place(&self, rhs: MatMut<'_, f64>) {
        let inner = &self.symbolic.inner;
        split_columns(rhs, rayon::current_num_threads(), &|rhs| {
            let mut mem = scratch_solve(inner, rhs.ncols());
            LltRef::new(inner, &self.values).solve_in_place_with_conj(
                Conj::No,
                rhs,
                KERNEL_PAR,
                MemStack::new(&mut mem),
            );
        });
    }
}

impl Factorization for Ldlt {
    fn dim(&self) -> usize {
        self.symbolic.n
    }
    fn solve_in_place(&self, mut rhs: MatMut<'_, f64>) {
        let inner = &self.symbolic.inner;
        let threads = rayon::current_num_threads();
        if let Some((s, tree)) = self.symbolic.subtree_parallel()
            && (self.femu_layout || threads > 1 && self.values.len() >= SUBTREE_SOLVE_VALUES)
        {
            // every right-hand side at once, the subtrees on different threads: the factor is
            // read once, not once per thread (docs/SCALING.md, "A subtree-parallel solve"); and
            // the only solve of femu's layout
            let layout = if self.femu_layout {
                tree.layout()
            } else {
                crate::multifrontal::Layout {
                    width: usize::MAX,
                    ptr: s.col_ptr_for_val(),
                }
            };
            let factor = (&self.values[..], layout);
            match self.symbolic.permutation() {
                Some(fwd) => {
                    let mut x = faer::Mat::from_fn(fwd.len(), rhs.ncols(), |i, j| rhs[(fwd[i], j)]);
                    crate::multifrontal::solve(tree, s, factor, x.as_mut(), threads);
                    for j in 0..x.ncols() {
                        for (i, &f) in fwd.iter().enumerate() {
                            rhs[(f, j)] = x[(i, j)];
                        }
                    }
                }
                None => {
                    crate::multifrontal::solve(tree, s, factor, rhs, threads);
                }
            }
            return;
        }
        split_columns(rhs, threads, &|rhs| {
            let mut mem = scratch_solve(inner, rhs.ncols());
            LdltRef::new(inner, &self.values).solve_in_place_with_conj(
                Conj::No,
                rhs,
                KERNEL_PAR,
                MemStack::new(&mut mem),
            );
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::multifrontal::{Tree, Tuning};

    /// femu's layout in chunks, with small sizes so that a 14^3 grid's fronts take every path:
    /// fronts factored where they are stored (at most one chunk), in a scratch copy written into
    /// their chunks, and in their chunks a super panel at a time, on one thread or with the
    /// chunks' updates and the update matrix's panels shared between threads. Against faer's
    /// left-looking factorization of faer's layout (an independent code) solved by faer's own
    /// solve: the same solutions to round-off times the condition number, for 3 right-hand
    /// sides (the solve's own kernels) and 10 (faer's GEMM and triangular solves chunk by
    /// chunk), dense and sparse (unit and zero columns, whose forward solve skips the fronts off
    /// their paths to the root); the inertia equal to the analytic count of eigenvalues below the shift, with the
    /// factor and without (a count).
    #[test]
    fn chunked_layouts_agree_with_faer_and_the_analytic_inertia() {
        let (a, spectrum) = (
            femu_testkit::laplacian_3d(14),
            femu_testkit::laplacian_3d_spectrum(14),
        );
        let n = a.rows();
        let sigma = 1.3;
        let mut values = a.data().to_vec();
        for (v, (_, (r, c))) in values.iter_mut().zip(a.iter()) {
            if r == c {
                *v -= sigma;
            }
        }
        let below = spectrum.iter().filter(|l| **l < sigma).count();
        let gap = spectrum
            .iter()
            .fold(f64::INFINITY, |m, l| m.min((l - sigma).abs()));
        let kappa = (12.0 + sigma) / gap;
        let sym = SymbolicFactor::new(&a, Ordering::NestedDissection).unwrap();
        let SymbolicCholeskyRaw::Supernodal(s) = sym.inner.raw() else {
            panic!("a supernodal analysis");
        };
        let widest = (0..s.n_supernodes())
            .map(|k| s.supernode_end()[k] - s.supernode_begin()[k])
            .max()
            .unwrap();
        assert!(widest > 32, "a front of several super panels: {widest}");
        // dense right-hand sides, or sparse ones: unit columns spread over the grid with every
        // third column zero (the forward solve skips the fronts off their paths to the root)
        let rhs = |(k, sparse): (usize, bool)| -> Vec<f64> {
            (0..k * n)
                .map(|i| {
                    let (j, r) = (i / n, i % n);
                    match sparse {
                        false => ((i * 37) % 101) as f64 - 50.0,
                        true if j % 3 != 2 && r == (j * 7919 + 11) % n => 1.0 + j as f64,
                        true => 0.0,
                    }
                })
                .collect()
        };
        let cases = [(3, false), (10, false), (3, true), (10, true)];
        let reference = sym.ldlt_left_looking(&a, &values, "A").unwrap();
        assert!(!reference.femu_layout);
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let solved = |f: &Ldlt, case: (usize, bool)| {
            let mut x = rhs(case);
            f.solve_in_place(faer::MatMut::from_column_major_slice_mut(&mut x, n, case.0));
            x
        };
        let want: Vec<Vec<f64>> = cases
            .iter()
            .map(|&case| one.install(|| solved(&reference, case)))
            .collect();
        let tunings = [
            // every front above 8 pivots in chunks, a super panel at a time, threads shared
            Tuning {
                chunk: 8,
                super_panel: 16,
                scratch_front: 0,
                parallel_front: 0.0,
            },
            // the same on one thread per front
            Tuning {
                chunk: 4,
                super_panel: 12,
                scratch_front: 0,
                parallel_front: f64::INFINITY,
            },
            // in a scratch copy
            Tuning {
                chunk: 8,
                super_panel: 16,
                scratch_front: usize::MAX,
                parallel_front: 0.0,
            },
            Tuning::DEFAULT,
        ];
        for tuning in tunings {
            let mut chunked = sym.clone();
            chunked.tree = Some(Arc::new(Tree::tuned(s, tuning).unwrap()));
            assert!(chunked.factor_len() < sym.inner.len_val());
            for threads in [1, 2, 3] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let (f, count) = pool.install(|| {
                    (
                        chunked.ldlt_values(&a, &values, "A").unwrap(),
                        chunked.inertia_values(&a, &values, "A").unwrap(),
                    )
                });
                assert!(f.femu_layout);
                assert_eq!(f.values.len(), chunked.factor_len());
                let what = format!("{tuning:?}, {threads} threads");
                assert_eq!(f.inertia().negative, below, "{what}");
                assert_eq!(f.inertia(), reference.inertia(), "{what}");
                assert_eq!(count, f.inertia(), "{what}: the count");
                for (case, want) in cases.into_iter().zip(&want) {
                    let got = pool.install(|| solved(&f, case));
                    let scale = want.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
                    let diff = got
                        .iter()
                        .zip(want)
                        .fold(0.0_f64, |m, (p, q)| m.max((p - q).abs()));
                    assert!(
                        diff < 100.0 * f64::EPSILON * kappa * scale,
                        "{what}, right-hand sides {case:?}: {diff:e} of {scale:e}"
                    );
                }
            }
        }
    }

    /// The permutation is one, and analysing the matrix permuted by it without reordering
    /// (`P A P^T`, built by hand, [`Ordering::Identity`]) gives the same factor: the same entries
    /// and the same flop count, to the last unit; for METIS's nested dissection and faer's AMD.
    #[test]
    fn permutation_reproduces_the_factor() {
        let a = femu_testkit::laplacian_3d(9);
        let n = a.rows();
        let natural = SymbolicFactor::new(&a, Ordering::Identity).unwrap().flops();
        for ordering in [Ordering::NestedDissection, Ordering::Amd] {
            let sym = SymbolicFactor::new(&a, ordering).unwrap();
            let fwd = sym
                .permutation()
                .expect("a fill-reducing ordering permutes");
            let mut inv = vec![usize::MAX; n];
            for (new, &old) in fwd.iter().enumerate() {
                assert_eq!(inv[old], usize::MAX, "{ordering:?}: {old} appears twice");
                inv[old] = new;
            }
            let mut t = sprs::TriMat::new((n, n));
            for (&v, (r, c)) in a.iter() {
                t.add_triplet(inv[r], inv[c], v);
            }
            let permuted: SparseMatrix = t.to_csc();
            let again = SymbolicFactor::new(&permuted, Ordering::Identity).unwrap();
            assert_eq!(again.factor_len(), sym.factor_len(), "{ordering:?}");
            assert_eq!(again.flops(), sym.flops(), "{ordering:?}");
            assert!(sym.flops() < natural / 2.0, "{ordering:?} reduces the work");
        }
    }
}
