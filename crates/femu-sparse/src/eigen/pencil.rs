//! The pencil `(K, M)`: its checks, its factorizations at a shift and the solves that drive
//! the Lanczos runs to a result with its Sturm proof ([`Pencil::solve`]), and the vector
//! helpers they share.

use super::*;

/// `w += sum_i c_i v_i`, row chunks in parallel: each chunk of `w` stays in cache while the
/// vectors stream past once.
pub(super) fn add_combination(w: &mut [f64], vs: &[&[f64]], cs: &[f64]) {
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
pub(super) fn scale_in_place(w: &mut [f64], d: f64) {
    w.par_chunks_mut(1 << 15)
        .for_each(|c| c.iter_mut().for_each(|v| *v /= d));
}

/// Column `j` of a column-major matrix as a slice.
pub(super) fn slice(a: &Mat<f64>, j: usize) -> &[f64] {
    a.col(j)
        .try_as_col_major()
        .expect("a column of a column-major matrix")
        .as_slice()
}

pub(super) fn dot(a: &[f64], b: &[f64]) -> f64 {
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
pub(super) fn residual_from(
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

pub(super) fn norm(v: &[f64]) -> f64 {
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
    pub(super) k_norm: f64,
    pub(super) m_norm: f64,
    pub(super) fingerprint: u64,
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
pub(super) fn check_pencil(k: &SparseMatrix, m: &SparseMatrix) -> Result<(f64, f64), SparseError> {
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
pub(super) fn fingerprint(k: &SparseMatrix, m: &SparseMatrix) -> Result<u64, SparseError> {
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
    pub(super) k: &'a SparseMatrix,
    pub(super) m: &'a SparseMatrix,
    pub(super) symbolic: SymbolicFactor,
    pub(super) check_seconds: f64,
    pub(super) symbolic_seconds: f64,
    pub(super) k_norm: f64,
    pub(super) m_norm: f64,
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

    pub(super) fn build(
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
    pub(super) fn lowest_shift(&self) -> f64 {
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
            match self.solve_counted(which, &hinted, Some(hint), false, &mut stats, started) {
                // a misplaced hint: start again as if none had been given; `stats` keeps the
                // work already done
                Err(
                    SparseError::NotPositiveDefinite { .. } | SparseError::NoConvergence { .. },
                ) => {}
                r => return r,
            }
        }
        match self.solve_counted(which, params, None, false, &mut stats, started) {
            // With massless DOFs the space the basis can span is the DOFs with mass; when the
            // request nearly fills a small one, blocks of several vectors can outrun it (18 DOF,
            // 10 with mass, 8 pairs in blocks of 4 did not converge): single vectors then, once;
            // `stats` keeps the work already done.
            Err(SparseError::NoConvergence { .. })
                if params.block_size > 1 && self.massless_dofs() > 0 && self.dim() <= 2_000 =>
            {
                let single = EigenOptions {
                    block_size: 1,
                    ..params.clone()
                };
                match self.solve_counted(which, &single, None, false, &mut stats, started) {
                    // still not: a small pencil's lowest pairs by the dense route, locked before
                    // the iteration, which then only confirms them (and the Sturm count checks)
                    Err(SparseError::NoConvergence { .. })
                        if matches!(which, Which::Lowest(_)) && self.dim() <= DENSE_PAIRS =>
                    {
                        self.solve_counted(which, params, None, true, &mut stats, started)
                    }
                    r => r,
                }
            }
            r => r,
        }
    }

    /// How many DOFs have no mass (a zero diagonal entry of `M`).
    fn massless_dofs(&self) -> usize {
        crate::csc::diagonal(self.m)
            .iter()
            .filter(|d| !(**d > 0.0))
            .count()
    }

    /// The zero-energy modes in the span of `hint`'s vectors, M-orthonormal:
    /// the Rayleigh-Ritz pairs of `(K, M)` on that span (docs/MATH.md, "Known null vectors")
    /// whose backward error is below [`BACKWARD_LOCK`], the test a pair locked by the iteration
    /// meets. Combinations the supports or constraints load are not zero-energy and are dropped.
    pub(super) fn zero_energy_pairs(
        &self,
        hint: &NullSpaceHint,
    ) -> Result<Vec<Known>, SparseError> {
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
        Ok((0..coef.ncols())
            .filter_map(|j| {
                let col = |a: &Mat<f64>| -> Vec<f64> { a.col(j).iter().copied().collect() };
                self.known_pair(col(&x), col(&kx), col(&mx))
            })
            .collect())
    }

    /// The pair of the M-normalised vector `x` (with `K x`, `M x`) and its Rayleigh quotient, if
    /// its backward error is below [`BACKWARD_LOCK`] (the test a pair the iteration locks meets).
    fn known_pair(&self, x: Vec<f64>, kx: Vec<f64>, mx: Vec<f64>) -> Option<Known> {
        let lambda = dot(&kx, &x) / dot(&mx, &x).max(f64::MIN_POSITIVE);
        let res: Vec<f64> = kx.iter().zip(&mx).map(|(k, m)| k - lambda * m).collect();
        let r_norm = norm(&res);
        let eta =
            r_norm / ((self.k_norm + lambda.abs() * self.m_norm) * norm(&x)).max(f64::MIN_POSITIVE);
        (eta < BACKWARD_LOCK).then(|| {
            let (kk, km, mm) = (dot(&kx, &kx), dot(&kx, &mx), dot(&mx, &mx));
            Known {
                x,
                mx,
                lambda,
                r_norm,
                kk,
                km,
                mm,
            }
        })
    }

    /// The `count` lowest pairs of a small pencil by the dense route, for a lowest-mode solve
    /// whose iteration did not converge because the request nearly fills the space the DOFs with
    /// mass span (a singular `M`; MSC's HA144D wing, 30 DOFs of which 21 have mass, did not
    /// converge for 15 modes). With `M = Q1 L1 Q1^T` (`Q0` its null space), a finite eigenvector
    /// is `x = Q1 a + Q0 b` with `Q0^T K x = 0` (no inertia force in the massless directions), so
    /// `b = -(Q0^T K Q0)^-1 Q0^T K Q1 a` and `a` solves the condensed pencil `(K_r, L1)`, `K_r`
    /// the Schur complement: no shift, so every pair is accurate to the round-off of `K`. The
    /// pairs, M-normalised, whose backward error passes [`BACKWARD_LOCK`], and the rank of `M`
    /// (how many eigenvalues are finite).
    fn dense_pairs(&self, count: usize) -> Result<(Vec<Known>, usize), SparseError> {
        let (kd, md) = (crate::csc::to_dense(self.k), crate::csc::to_dense(self.m));
        let (mv, mq) = crate::dense::symmetric_eigen(md.as_ref())?;
        let top = mv.last().copied().unwrap_or(0.0);
        let (range, null): (Vec<usize>, Vec<usize>) =
            (0..mv.len()).partition(|&i| mv[i] > 1e-12 * top);
        let cols = |idx: &[usize]| Mat::from_fn(mq.nrows(), idx.len(), |i, j| mq[(i, idx[j])]);
        let (q1, q0) = (cols(&range), cols(&null));
        let k11 = q1.transpose() * &kd * &q1;
        let k10 = q1.transpose() * &kd * &q0;
        let k00 = q0.transpose() * &kd * &q0;
        // Z = K00^-1 K01 (K00 is definite when every massless direction has stiffness)
        let z = if null.is_empty() {
            Mat::zeros(0, range.len())
        } else {
            let llt = k00
                .llt(faer::Side::Lower)
                .map_err(|_| SparseError::NotPositiveDefinite {
                    matrix: "K on the massless DOFs (a massless mechanism)",
                    index: 0,
                })?;
            let mut z = k10.transpose().to_owned();
            let l = llt.L();
            l.solve_lower_triangular_in_place(z.as_mut());
            l.transpose().solve_upper_triangular_in_place(z.as_mut());
            z
        };
        let kr = &k11 - &k10 * &z;
        let s: Vec<f64> = range.iter().map(|&i| 1.0 / mv[i].sqrt()).collect();
        let ks = Mat::from_fn(range.len(), range.len(), |i, j| {
            0.5 * (kr[(i, j)] + kr[(j, i)]) * s[i] * s[j]
        });
        let (_, v) = crate::dense::symmetric_eigen(ks.as_ref())?;
        let a = Mat::from_fn(v.nrows(), v.ncols(), |i, j| v[(i, j)] * s[i]);
        let x = &q1 * &a - &q0 * (&z * &a);
        let (kx, mx) = (&kd * &x, &md * &x);
        let pairs = (0..x.ncols().min(count))
            .filter_map(|j| {
                let col = |a: &Mat<f64>| -> Vec<f64> { a.col(j).iter().copied().collect() };
                self.known_pair(col(&x), col(&kx), col(&mx))
            })
            .collect();
        Ok((pairs, range.len()))
    }

    /// [`Pencil::solve`] from the lowest-mode shift `hint` when given (the probe is then
    /// skipped, and a hint not below the spectrum is [`SparseError::NotPositiveDefinite`]). The
    /// work is added to `stats` whatever the outcome; the result's total time runs from
    /// `started`.
    pub(super) fn solve_counted(
        &self,
        which: Which,
        params: &EigenOptions,
        hint: Option<f64>,
        dense: bool,
        stats: &mut EigenStats,
        started: Instant,
    ) -> Result<Modes, SparseError> {
        // the number of finite eigenvalues: the DOFs with mass (massless DOFs, a lumped beam's
        // rotations, have a zero row in M and an infinite eigenvalue)
        let mut n = crate::csc::diagonal(self.m)
            .iter()
            .filter(|d| **d > 0.0)
            .count();
        // the dense route's pairs, and the rank of M it finds (the finite eigenvalues exactly)
        let dense_known = if dense {
            let t = Instant::now();
            let (pairs, rank) = self.dense_pairs(n)?;
            stats.ritz_seconds += t.elapsed().as_secs_f64();
            n = n.min(rank);
            Some(pairs)
        } else {
            None
        };
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
        // a band reaching below zero with its lower end's factor to keep: that end is counted
        // after the iteration (no eigenvalue below it is assumed until then, and the check
        // corrects the count), so that its factor is never alive beside the iteration's
        let defer_lower = params.keep_factor
            && matches!(which, Which::Band { lo, .. } if lo - self.tie_tolerance(lo) < 0.0);
        let (mut sigma, mut band) = self.first_shift(which, hint, defer_lower, stats)?;
        let mut lower_pending = defer_lower;
        let mut kept: Option<Ldlt> = None;
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
        if let Some(mut pairs) = dense_known {
            pairs.truncate(want + guard);
            known = pairs;
        }
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
            // (a deferred lower count: none below the upper end, so none below the lower)
            return Ok(no_modes(self.dim(), requested, sigma, band, stats));
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
            if let (true, None, Some((lo, hi, count))) = (defer_lower, &kept, band) {
                // the band's lower end factored after the iteration's factor is released: its
                // count (the first time) and its factor, kept
                lanczos.op = None;
                let t = Instant::now();
                let low = self.factor_shifted(lo)?;
                stats.factor_seconds += t.elapsed().as_secs_f64();
                stats.factorizations += 1;
                if lower_pending {
                    band = Some((lo, hi, count - low.inertia().negative));
                    lower_pending = false;
                }
                kept = Some(low);
            }
            let (sel, check, op) =
                self.checked_selection(&mut lanczos, band, which, requested, target, stats)?;
            if op.is_some() {
                kept = op;
            }
            if check.verified() {
                let mut modes = lanczos.finish(sel, sigma, check, requested, stats.clone());
                modes.stats.total_seconds =
                    self.check_seconds + self.symbolic_seconds + started.elapsed().as_secs_f64();
                modes.factor = kept.map(|ldlt| super::KeptFactor {
                    sigma: band.map_or(sigma, |b| b.0),
                    ldlt: std::sync::Arc::new(ldlt),
                });
                return Ok(modes);
            }
            if matches!(which, Which::Lowest(_)) {
                // the iteration goes on at its shift: its factor back, if kept
                lanczos.op = kept.take();
            } else {
                // a band's lower factor is released while the iteration factors again (one
                // factor alive at a time), and made again after it
                kept = None;
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

    /// The first shift of a solve, and for a band its ends widened by the tie tolerance and the
    /// count of eigenvalues inside by two Sturm counts.
    fn first_shift(
        &self,
        which: Which,
        hint: Option<f64>,
        defer_lower: bool,
        stats: &mut EigenStats,
    ) -> Result<(f64, Option<Band>), SparseError> {
        Ok(match which {
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
                let nl = if defer_lower {
                    0
                } else {
                    stats.factorizations += 1;
                    self.count_below(lo)?
                };
                let nh = self.count_below(hi)?;
                stats.factor_seconds += t.elapsed().as_secs_f64();
                stats.factorizations += 1;
                (0.5 * (lo + hi), Some((lo, hi, nh - nl)))
            }
        })
    }

    /// The pairs of a finished run that answer the request, and the Sturm count that proves none
    /// was skipped: for a band, the values inside it against the count made at the start; else
    /// the `requested` nearest `target` (nearest) or lowest above the shift, counted now (the
    /// iteration's factor is released first, so that one factor is alive at a time, unless
    /// [`EigenOptions::keep_factor`] asks for it: it is then returned, and the count's inertia
    /// pass runs beside it).
    fn checked_selection(
        &self,
        lanczos: &mut Lanczos<'_, '_>,
        band: Option<Band>,
        which: Which,
        requested: usize,
        target: f64,
        stats: &mut EigenStats,
    ) -> Result<(Vec<usize>, SturmCheck, Option<Ldlt>), SparseError> {
        let sigma = lanczos.sigma;
        Ok(match band {
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
                (sel, check, None)
            }
            None => {
                let nearest = matches!(which, Which::Nearest { .. });
                let centre = if nearest { target } else { sigma };
                let (sel, lower, upper) = self.select(&lanczos.values, requested, centre, nearest);
                // one factor alive at a time: release the iteration's before the check's, or
                // hand it back when it is to be kept (a lowest-mode shift, below the spectrum)
                let op = lanczos
                    .op
                    .take()
                    .filter(|_| lanczos.params.keep_factor && !nearest);
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
                (sel, check, op)
            }
        })
    }

    /// The factor at `better` (half the first elastic eigenvalue of a free-free model) and that
    /// shift, or, in the rare case `better` is not below the spectrum, the factor at `sigma`
    /// again; the factorizations are counted in `stats`.
    pub(super) fn refactor_below(
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
    pub(super) fn select(
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

/// Ritz values and vectors of the symmetrised projection, ordered by decreasing `|theta|`.
pub(super) fn rayleigh_ritz(
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
pub(super) type Hook = Box<dyn FnMut(usize) -> bool>;

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
pub(super) fn interrupted(solved: usize) -> bool {
    INTERRUPT.with(|c| c.borrow_mut().as_mut().is_some_and(|f| f(solved)))
}
/// A band's ends, widened by the tie tolerance, and the Sturm count of the eigenvalues inside.
type Band = (f64, f64, usize);

/// The answer to a request for no modes (an empty band): the Sturm count that proves it.
fn no_modes(
    n: usize,
    requested: usize,
    sigma: f64,
    band: Option<Band>,
    stats: &EigenStats,
) -> Modes {
    Modes {
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
        factor: None,
    }
}
