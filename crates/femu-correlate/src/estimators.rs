//! The a priori error estimators (docs/MATH.md, "The spectral identity (25)" and "The estimators";
//! the paper's Theorems 1-4, (26)-(29)).
//!
//! From a test pair `(lambda_id, x)` and the model's `K`, `M` alone, [`Estimator`] computes
//! `rho_M = ||R_F||_{M^-1} / ||x||_M` (the rigorous form) and `rho_2 = ||R_F||_2 / ||x||_2` (the
//! paper's form), without extracting any eigenpair. By (25), `rho_M` is a weighted RMS of the gaps
//! `|lambda_id - lambda_j|`, weighted by `MAC_M(x, phi_j)` (which sum to one), so some model
//! eigenvalue lies within `rho_M` of `lambda_id` (Theorem 2). The paper's Euclidean statements are
//! theorems only when `M = I`; [`assess`] reports both forms, each bound next to the quantity it
//! bounds when the model's eigenpairs are at hand, and whether it held.

use crate::CorrelateError;
use crate::correlation::{mac_m, msd, msd_m};
use crate::mass::{MassSolver, SolveReport};
use faer::{Mat, MatRef};
use femu_sparse::SparseMatrix;
use femu_sparse::csc::sym_mul_mat;
use serde::{Deserialize, Serialize};

/// Norms of the force residual of one test pair.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ResidualNorms {
    /// `lambda_id`, s^-2.
    pub lambda_id: f64,
    /// `rho_M = ||R_F||_{M^-1} / ||x||_M`, s^-2 (rigorous form).
    pub rho_m: f64,
    /// `rho_2 = ||R_F||_2 / ||x||_2` (the paper's form). Its units are those of `K` (N/m for
    /// displacement shapes) whenever `M` has mass; it is an eigenvalue (s^-2) only when `M = I`,
    /// which is why its theorems hold only then.
    pub rho_2: f64,
    /// Rayleigh quotient `lambda_R = x^T K x / x^T M x`, s^-2.
    pub rayleigh: f64,
    /// `||(K - lambda_R M) x||_{M^-1} / ||x||_M`, s^-2: the residual at the Rayleigh quotient,
    /// the smallest over all shifts; `rho_R^2 = rho_M^2 - (lambda_id - lambda_R)^2`.
    pub rho_rayleigh: f64,
    /// `||x||_M`.
    pub x_norm_m: f64,
    /// `||x||_2`.
    pub x_norm_2: f64,
}

impl ResidualNorms {
    /// `[lambda_id - rho_M, lambda_id + rho_M]` (s^-2): by Theorem 2 (27) in its rigorous form,
    /// it holds at least one eigenvalue of the model.
    pub fn eigenvalue_interval(&self) -> (f64, f64) {
        (self.lambda_id - self.rho_m, self.lambda_id + self.rho_m)
    }

    /// The same interval in Hz (lower end clipped at 0).
    pub fn frequency_interval_hz(&self) -> (f64, f64) {
        let (lo, hi) = self.eigenvalue_interval();
        (
            crate::hz::hz_of_eigenvalue(lo),
            crate::hz::hz_of_eigenvalue(hi),
        )
    }
}

/// Computes residual norms for test pairs on a model: one product with `K` and `M`, one
/// `M^-1` solve for all modes at once.
#[derive(Debug, Clone)]
pub struct Estimator<'a> {
    k: &'a SparseMatrix,
    m: &'a SparseMatrix,
    mass: MassSolver<'a>,
}

impl<'a> Estimator<'a> {
    /// An estimator with [`MassSolver::new`] (diagonal for a lumped `M`, Jacobi PCG otherwise).
    ///
    /// # Errors
    /// `K` and `M` of different sizes; `M` with a non-positive diagonal or a non-finite entry.
    pub fn new(k: &'a SparseMatrix, m: &'a SparseMatrix) -> Result<Self, CorrelateError> {
        Self::with_mass_solver(k, m, MassSolver::new(m)?)
    }

    /// An estimator with a given `M^-1` solver.
    ///
    /// # Errors
    /// `K`, `M` and the solver of different sizes.
    pub fn with_mass_solver(
        k: &'a SparseMatrix,
        m: &'a SparseMatrix,
        mass: MassSolver<'a>,
    ) -> Result<Self, CorrelateError> {
        for (what, got) in [
            ("M against K", m.rows()),
            ("M^-1 solver against K", mass.dim()),
        ] {
            if got != k.rows() || k.cols() != k.rows() {
                return Err(CorrelateError::DimensionMismatch {
                    what,
                    expected: k.rows(),
                    got,
                });
            }
        }
        Ok(Self { k, m, mass })
    }

    /// The `M^-1` solver.
    pub fn mass_solver(&self) -> &MassSolver<'a> {
        &self.mass
    }

    /// Residual norms of the pairs `(lambdas[i], x[:, i])`, full-length `x` (every free DOF).
    ///
    /// `docs/MATH.md`, "The spectral identity (25)": `rho_M` and the paper's `rho_2`.
    ///
    /// # Errors
    /// Sizes, non-finite input, a zero shape, a failed `M^-1` solve.
    pub fn residual_norms(
        &self,
        lambdas: &[f64],
        x: MatRef<'_, f64>,
    ) -> Result<(Vec<ResidualNorms>, SolveReport), CorrelateError> {
        crate::residues::check_lambdas(lambdas, x, self.k.rows())?;
        let (kx, mx) = (sym_mul_mat(self.k, x)?, sym_mul_mat(self.m, x)?);
        // R_F (3) from the same products
        let r = Mat::from_fn(x.nrows(), x.ncols(), |i, j| {
            kx[(i, j)] - lambdas[j] * mx[(i, j)]
        });
        let (z, report) = self.mass.solve(r.as_ref())?;
        let dot = |a: MatRef<'_, f64>, b: MatRef<'_, f64>, j: usize| -> f64 {
            a.col(j)
                .iter()
                .zip(b.col(j).iter())
                .map(|(u, v)| u * v)
                .sum()
        };
        let mut out = Vec::with_capacity(lambdas.len());
        for (j, &lambda_id) in lambdas.iter().enumerate() {
            let xmx = dot(x, mx.as_ref(), j);
            let x2 = x.col(j).squared_norm_l2();
            if !(xmx > 0.0 && x2 > 0.0) {
                return Err(CorrelateError::ZeroVector {
                    what: "identified shape",
                    index: j,
                });
            }
            let rr = dot(r.as_ref(), z.as_ref(), j).max(0.0);
            let rayleigh = dot(x, kx.as_ref(), j) / xmx;
            // r_R = R_F + (lambda_id - lambda_R) M x, so M^-1 r_R = z + (lambda_id - lambda_R) x:
            // no second solve and no cancellation of rho_M^2 - (lambda_id - lambda_R)^2.
            let d = lambda_id - rayleigh;
            let rr_r: f64 = (0..x.nrows())
                .map(|i| (r[(i, j)] + d * mx[(i, j)]) * (z[(i, j)] + d * x[(i, j)]))
                .sum();
            out.push(ResidualNorms {
                lambda_id,
                rho_m: (rr / xmx).sqrt(),
                rho_2: (r.col(j).squared_norm_l2() / x2).sqrt(),
                rayleigh,
                rho_rayleigh: (rr_r.max(0.0) / xmx).sqrt(),
                x_norm_m: xmx.sqrt(),
                x_norm_2: x2.sqrt(),
            });
        }
        Ok((out, report))
    }
}

/// Which norm a bound is stated in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Form {
    /// The paper's Euclidean statement (`rho_2`, Euclidean MSD): a theorem only when `M = I`.
    Paper,
    /// The mass-weighted statement (`rho_M`, `sin theta_M`): a theorem for every model.
    Rigorous,
}

/// The statement a [`Bound`] instantiates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum BoundKind {
    /// Theorem 1 (26): `max_j |lambda_id - lambda_j| >= rho`.
    T1,
    /// Theorem 2 (27): `min_j |lambda_id - lambda_j| <= rho`.
    T2,
    /// Theorem 3 (28): `|lambda_id - lambda_k| + s_k spread_k >= rho`.
    T3,
    /// Theorem 4 (29): `s_k <= (|lambda_id - lambda_k| + rho) / gap_k`.
    T4,
    /// A priori MAC: `MAC_M(x, phi_k) >= 1 - T4^2`.
    Mac,
    /// A priori MSD: `MSD_M <= sqrt(2) T4`.
    Msd,
    /// Kato-Temple lower bound: `lambda_k >= lambda_R - rho_R^2 / (b - lambda_R)`.
    KatoTempleLower,
    /// Kato-Temple upper bound: `lambda_k <= lambda_R + rho_R^2 / (lambda_R - a)`.
    KatoTempleUpper,
    /// The paper's ratio made rigorous: `min_j |lambda_id - lambda_j| <= rho_2 / mu_min(M)`.
    EuclideanScaled,
    /// Davis-Kahan (beyond the paper): `sin theta_M(x, phi_k) <= rho_M / delta_k` with
    /// `delta_k = min_{j != k} |lambda_id - lambda_j|`; often tighter than T4.
    DavisKahan,
}

/// How the quantity relates to the bound.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Relation {
    /// `quantity <= bound`.
    AtMost,
    /// `quantity >= bound`.
    AtLeast,
}

/// One instance of a theorem: the bound (computable a priori, or from eigenvalues only), the
/// quantity it bounds (needs the model's eigenpairs), and whether it held.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Bound {
    /// Which statement.
    pub kind: BoundKind,
    /// Paper (Euclidean) or rigorous (mass-weighted) form.
    pub form: Form,
    /// The bound's value.
    pub bound: f64,
    /// `quantity <= bound` or `quantity >= bound`.
    pub relation: Relation,
    /// The bounded quantity when the needed eigenpairs are known.
    pub quantity: Option<f64>,
    /// Whether the statement is a theorem for this model (always for the rigorous form; for the
    /// paper's form only when `M = I`).
    pub theorem: bool,
}

impl Bound {
    /// Whether the bound held (`None` when the quantity is unknown). A relative slack of `1e-10`
    /// absorbs round-off in cases of equality.
    pub fn holds(&self) -> Option<bool> {
        let q = self.quantity?;
        let slack = 1e-10 * q.abs().max(self.bound.abs());
        Some(match self.relation {
            Relation::AtMost => q <= self.bound + slack,
            Relation::AtLeast => q >= self.bound - slack,
        })
    }
}

/// What proves that the known eigenvalues are what they are said to be: the bounds that need
/// neighbours or the whole spectrum are theorems only with such a proof ([`assess`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum SpectrumProof {
    /// `values` is the whole spectrum (a dense solution).
    Complete,
    /// `values` are the lowest eigenvalues, none skipped: a Sturm count says that every
    /// eigenvalue up to `upper` (s^-2) is among them.
    Lowest {
        /// The end of the counted interval; every other eigenvalue lies above it.
        upper: f64,
    },
    /// `values` are every eigenvalue in `(lo, hi]` (s^-2), by a Sturm count over the band.
    Band {
        /// Lower end.
        lo: f64,
        /// Upper end.
        hi: f64,
    },
    /// Nothing proves that no eigenvalue was skipped.
    Unverified,
}

impl SpectrumProof {
    /// The proof a result of femu's eigensolver carries: its Sturm check.
    pub fn of(modes: &femu_sparse::eigen::Modes) -> Self {
        let s = &modes.sturm;
        match (s.verified(), s.lower) {
            (false, _) => SpectrumProof::Unverified,
            (true, None) => SpectrumProof::Lowest { upper: s.upper },
            (true, Some(lo)) => SpectrumProof::Band { lo, hi: s.upper },
        }
    }
}

/// What is known of the model's spectrum.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModelSpectrum {
    /// Known eigenvalues (s^-2), ascending.
    pub values: Vec<f64>,
    /// What proves them complete where they claim to be.
    pub proof: SpectrumProof,
    /// An upper bound of `lambda_max` (see [`element_bounds`](crate::element_bounds) and
    /// [`inertia_bounds`](crate::inertia_bounds); infinite for a singular mass, when Theorem 3
    /// is not formed); with a complete spectrum its largest value is used instead.
    pub lambda_max: f64,
    /// A lower bound of the smallest eigenvalue of `M`, for [`BoundKind::EuclideanScaled`].
    pub mu_min: Option<f64>,
}

impl ModelSpectrum {
    /// The spectrum of an eigensolver result, with its proof.
    pub fn from_modes(
        modes: &femu_sparse::eigen::Modes,
        lambda_max: f64,
        mu_min: Option<f64>,
    ) -> Self {
        Self {
            values: modes.values.clone(),
            proof: SpectrumProof::of(modes),
            lambda_max,
            mu_min,
        }
    }

    /// Whether `values` is the whole spectrum.
    pub fn complete(&self) -> bool {
        self.proof == SpectrumProof::Complete
    }
}

/// Whether `m` is the identity (the paper's Euclidean forms are then theorems): computed, never
/// taken from the caller.
pub fn is_identity(m: &SparseMatrix) -> bool {
    let p = m.indptr();
    let p = p.raw_storage();
    (0..m.cols()).all(|c| {
        let rows = &m.indices()[p[c]..p[c + 1]];
        let vals = &m.data()[p[c]..p[c + 1]];
        let mut diagonal = false;
        rows.iter().zip(vals).all(|(&r, &v)| {
            if r == c {
                diagonal = v == 1.0;
                diagonal
            } else {
                v == 0.0
            }
        }) && diagonal
    }) && m.rows() == m.cols()
}

/// The model mode paired with a test mode, for Theorems 3-4 and the derived bounds.
#[derive(Debug, Clone, Copy)]
pub struct PairedModel<'a> {
    /// Index of the mode in [`ModelSpectrum::values`].
    pub index: usize,
    /// Its shape (full length, any scaling), when extracted.
    pub shape: Option<&'a [f64]>,
}

/// All bounds for one test pair.
///
/// `x` is the full-length test vector (needed only for the quantities that compare it with a
/// model shape), `norms` its [`ResidualNorms`].
///
/// `docs/MATH.md`, "The estimators": Theorems 1-4, the paper's (26)-(29), in both forms, with the MAC, MSD and Kato-Temple bounds.
///
/// # Errors
/// A paired index outside the known spectrum, or sizes that do not match `M`.
pub fn assess(
    m: &SparseMatrix,
    x: &[f64],
    norms: &ResidualNorms,
    spectrum: &ModelSpectrum,
    paired: Option<PairedModel<'_>>,
) -> Result<Vec<Bound>, CorrelateError> {
    let lam = norms.lambda_id;
    let vals = &spectrum.values;
    let proof = spectrum.proof;
    let identity_mass = is_identity(m);
    let mut bounds = Vec::new();
    let gaps: Vec<f64> = vals.iter().map(|l| (lam - l).abs()).collect();
    // min_j |lambda_id - lambda_j| is exact when no unknown eigenvalue can be nearer than the
    // nearest known one: unknown ones lie outside the proven interval
    let nearest = gaps.iter().copied().fold(f64::INFINITY, f64::min);
    let unknown_at_least = match proof {
        SpectrumProof::Complete => Some(f64::INFINITY),
        SpectrumProof::Lowest { upper } => Some((upper - lam).max(0.0)),
        SpectrumProof::Band { lo, hi } => Some(if lo <= lam && lam <= hi {
            (lam - lo).min(hi - lam)
        } else {
            0.0
        }),
        SpectrumProof::Unverified => None,
    };
    let min_gap = unknown_at_least
        .filter(|u| !vals.is_empty() && nearest <= *u)
        .map(|_| nearest);
    // with the whole spectrum, its own largest value, not the caller's bound
    let max_gap = match (proof, vals.first(), vals.last()) {
        (SpectrumProof::Complete, Some(first), Some(last)) => {
            Some((lam - first).abs().max((last - lam).abs()))
        }
        _ => None,
    };
    for (form, rho, theorem) in [
        (Form::Rigorous, norms.rho_m, true),
        (Form::Paper, norms.rho_2, identity_mass),
    ] {
        bounds.push(Bound {
            kind: BoundKind::T1,
            form,
            bound: rho,
            relation: Relation::AtLeast,
            quantity: max_gap,
            theorem,
        });
        bounds.push(Bound {
            kind: BoundKind::T2,
            form,
            bound: rho,
            relation: Relation::AtMost,
            quantity: min_gap,
            theorem,
        });
    }
    if let Some(mu) = spectrum.mu_min {
        bounds.push(Bound {
            kind: BoundKind::EuclideanScaled,
            form: Form::Rigorous,
            bound: norms.rho_2 / mu,
            relation: Relation::AtMost,
            quantity: min_gap,
            theorem: true,
        });
    }
    let Some(p) = paired else {
        return Ok(bounds);
    };
    let k = p.index;
    let Some(&lk) = vals.get(k) else {
        return Err(CorrelateError::Invalid {
            what: "paired model mode",
            reason: format!("index {k} is beyond the {} known eigenvalues", vals.len()),
        });
    };
    let dk = (lam - lk).abs();
    let (below, above) = neighbours(vals, k, proof);
    // spread_k = max(lambda_k - lambda_1, lambda_max - lambda_k): lambda_1 is vals[0] for the
    // lowest values, otherwise bounded below by 0 (K is positive semi-definite); a larger
    // spread keeps T3 a theorem
    let lowest_known = match proof {
        SpectrumProof::Complete | SpectrumProof::Lowest { .. } => vals[0],
        _ => vals[0].min(0.0),
    };
    let top = if spectrum.complete() {
        *vals.last().unwrap_or(&spectrum.lambda_max)
    } else {
        spectrum.lambda_max
    };
    let spread = (lk - lowest_known).max(top - lk);
    // gap_k from the neighbours (a lower bound at the end of a proven interval: T4 stays a
    // theorem); none when unproven or when lambda_k is alone
    let gap = match (below, above) {
        (Some(a), Some(b)) => Some((lk - a).min(b - lk)).filter(|g| g.is_finite()),
        _ => None,
    };
    let (sin_m, msd_2, msd_mm) = match p.shape {
        Some(phi) => {
            let c2 = mac_m(m, x, phi)?;
            (
                Some((1.0 - c2).max(0.0).sqrt()),
                Some(msd(x, phi)?),
                Some(msd_m(m, x, phi)?),
            )
        }
        None => (None, None, None),
    };
    let mac = sin_m.map(|s| 1.0 - s * s);
    for (form, rho, s, theorem) in [
        (Form::Rigorous, norms.rho_m, sin_m, true),
        (Form::Paper, norms.rho_2, msd_2, identity_mass),
    ] {
        bounds.push(Bound {
            kind: BoundKind::T3,
            form,
            bound: rho,
            relation: Relation::AtLeast,
            // an unbounded spread (a singular mass: infinite eigenvalues) leaves T3 nothing to say
            quantity: s.filter(|_| spread.is_finite()).map(|s| dk + s * spread),
            theorem,
        });
        if let Some(g) = gap.filter(|g| *g > 0.0) {
            let t4 = (dk + rho) / g;
            bounds.push(Bound {
                kind: BoundKind::T4,
                form,
                bound: t4,
                relation: Relation::AtMost,
                quantity: s,
                theorem,
            });
            if form == Form::Rigorous {
                bounds.push(Bound {
                    kind: BoundKind::Mac,
                    form,
                    bound: 1.0 - t4 * t4,
                    relation: Relation::AtLeast,
                    quantity: mac,
                    theorem,
                });
                bounds.push(Bound {
                    kind: BoundKind::Msd,
                    form,
                    bound: std::f64::consts::SQRT_2 * t4,
                    relation: Relation::AtMost,
                    quantity: msd_mm,
                    theorem,
                });
            }
        }
    }
    // Davis-Kahan: every eigenvalue but lambda_k is at least delta_k from lambda_id; unknown ones
    // lie outside the proven interval
    let others = vals
        .iter()
        .enumerate()
        .filter(|(j, _)| *j != k)
        .map(|(_, l)| (lam - l).abs())
        .fold(f64::INFINITY, f64::min);
    if let Some(u) = unknown_at_least {
        let delta = others.min(u);
        if delta > 0.0 && delta.is_finite() {
            bounds.push(Bound {
                kind: BoundKind::DavisKahan,
                form: Form::Rigorous,
                bound: norms.rho_m / delta,
                relation: Relation::AtMost,
                quantity: sin_m,
                theorem: true,
            });
        }
    }
    bounds.extend(kato_temple(norms, below, above, lk));
    Ok(bounds)
}

/// The nearest eigenvalues below and above `vals[k]`, or the ends of the proven interval (no
/// eigenvalue lies between them and `lambda_k`); `None` when nothing proves it.
fn neighbours(vals: &[f64], k: usize, proof: SpectrumProof) -> (Option<f64>, Option<f64>) {
    let below: Option<f64> = match (k.checked_sub(1), proof) {
        (_, SpectrumProof::Unverified) => None,
        (Some(i), _) => Some(vals[i]),
        (None, SpectrumProof::Complete | SpectrumProof::Lowest { .. }) => Some(f64::NEG_INFINITY),
        (None, SpectrumProof::Band { lo, .. }) => Some(lo),
    };
    let above: Option<f64> = match (vals.get(k + 1), proof) {
        (_, SpectrumProof::Unverified) => None,
        (Some(b), _) => Some(*b),
        (None, SpectrumProof::Complete) => Some(f64::INFINITY),
        (None, SpectrumProof::Lowest { upper }) => Some(upper),
        (None, SpectrumProof::Band { hi, .. }) => Some(hi),
    };
    (below, above)
}

/// Kato-Temple's two-sided enclosure of `lambda_k` from the Rayleigh quotient and its residual
/// on `(a, b) = (lambda_{k-1}, lambda_{k+1})` or the ends of the proven interval, which holds
/// `lambda_k` alone; none without a proof.
fn kato_temple(
    norms: &ResidualNorms,
    below: Option<f64>,
    above: Option<f64>,
    lk: f64,
) -> Vec<Bound> {
    let mut out = Vec::new();
    let lr = norms.rayleigh;
    let rr2 = norms.rho_rayleigh * norms.rho_rayleigh;
    let (a, b) = match (below, above) {
        (Some(a), Some(b)) => (a, b),
        _ => (f64::NAN, f64::NAN),
    };
    if a < lr && lr < b {
        out.push(Bound {
            kind: BoundKind::KatoTempleLower,
            form: Form::Rigorous,
            bound: if b.is_finite() {
                lr - rr2 / (b - lr)
            } else {
                f64::NEG_INFINITY
            },
            relation: Relation::AtLeast,
            quantity: Some(lk),
            theorem: true,
        });
        out.push(Bound {
            kind: BoundKind::KatoTempleUpper,
            form: Form::Rigorous,
            bound: if a.is_finite() {
                lr + rr2 / (lr - a)
            } else {
                lr
            },
            relation: Relation::AtMost,
            quantity: Some(lk),
            theorem: true,
        });
    }
    out
}

/// The smaller of the theorems that bound `sin theta_M(x, phi_k)`: rigorous T4 and Davis-Kahan,
/// with its source (`bound.kind`).
pub fn sin_theta_bound(bounds: &[Bound]) -> Option<&Bound> {
    bounds
        .iter()
        .filter(|b| {
            b.theorem
                && b.form == Form::Rigorous
                && matches!(b.kind, BoundKind::T4 | BoundKind::DavisKahan)
        })
        .min_by(|a, b| a.bound.total_cmp(&b.bound))
}

/// `rho_M` for each column as a plain vector (convenience for studies and plots).
///
/// # Errors
/// As [`Estimator::residual_norms`].
pub fn rho_m(
    k: &SparseMatrix,
    m: &SparseMatrix,
    lambdas: &[f64],
    x: MatRef<'_, f64>,
) -> Result<Vec<f64>, CorrelateError> {
    let (norms, _) = Estimator::new(k, m)?.residual_norms(lambdas, x)?;
    Ok(norms.iter().map(|n| n.rho_m).collect())
}

/// The terms of the spectral identity (25), `(lambda_id - lambda_j)^2 MAC_M(x, phi_j)`, one per
/// given model mode. Over a complete eigenbasis they sum to `rho_M^2`; over a partial one they
/// show which model modes the residual comes from.
///
/// # Errors
/// Mismatched sizes or zero vectors.
pub fn spectral_terms(
    m: &SparseMatrix,
    lambda_id: f64,
    x: &[f64],
    values: &[f64],
    phi: MatRef<'_, f64>,
) -> Result<Vec<f64>, CorrelateError> {
    if values.len() != phi.ncols() {
        return Err(CorrelateError::DimensionMismatch {
            what: "model eigenvalues against shapes",
            expected: phi.ncols(),
            got: values.len(),
        });
    }
    let xm = MatRef::from_column_major_slice(x, x.len(), 1);
    let mac: Mat<f64> = crate::correlation::mac_m_matrix(m, xm, phi)?;
    Ok((0..values.len())
        .map(|j| (lambda_id - values[j]).powi(2) * mac[(0, j)])
        .collect())
}
