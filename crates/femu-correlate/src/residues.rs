//! Modal residues (docs/MATH.md, "Residues"; the paper's (3)-(12)).
//!
//! All residues follow from the force residual `R_F = (K - lambda_id M) x` (3):
//! the displacement residual solves `K R_D = R_F` (5); the error in constitutive law
//! `R_ECL = x - Psi` with `K Psi = lambda_id M x` (7)-(8) satisfies `K R_ECL = R_F` (9), so it
//! equals `R_D`; the error in inertia law `R_EIL = x - Psi` with `lambda_id M Psi = K x`
//! (10)-(11) satisfies `-lambda_id M R_EIL = R_F` (12).
//!
//! Free-free models (`K` singular, rigid-body modes `Phi_r`): `R_D` and `R_ECL` are defined up
//! to rigid-body motion. femu returns the representative M-orthogonal to `Phi_r` after removing
//! the rigid-body part of the load: `K R_D = (I - M Phi_r Phi_r^T) R_F`, `Phi_r^T M R_D = 0`.

use crate::{CorrelateError, MassSolver};
use faer::{Mat, MatRef};
use femu_sparse::cholesky::{Factorization, Ldlt, Llt};
use femu_sparse::csc::sym_mul_mat;
use femu_sparse::eigen::{EigenOptions, Pencil, Which};
use femu_sparse::ordering::Ordering;
use femu_sparse::{SparseError, SparseMatrix};

pub(crate) fn check_lambdas(
    lambdas: &[f64],
    x: MatRef<'_, f64>,
    n: usize,
) -> Result<(), CorrelateError> {
    if x.nrows() != n {
        return Err(CorrelateError::DimensionMismatch {
            what: "identified shapes against K (full-length vectors needed)",
            expected: n,
            got: x.nrows(),
        });
    }
    if lambdas.len() != x.ncols() {
        return Err(CorrelateError::DimensionMismatch {
            what: "identified eigenvalues against shapes",
            expected: x.ncols(),
            got: lambdas.len(),
        });
    }
    if let Some(index) = lambdas.iter().position(|l| !l.is_finite()) {
        return Err(CorrelateError::NonFinite {
            what: "identified eigenvalue",
            index,
        });
    }
    for j in 0..x.ncols() {
        if let Some(i) = x.col(j).iter().position(|v| !v.is_finite()) {
            return Err(CorrelateError::NonFinite {
                what: "identified shape",
                index: j * n + i,
            });
        }
    }
    Ok(())
}

/// Force residuals (3) `R_F,i = (K - lambda_id,i M) x_i` for the columns of `x`.
///
/// # Errors
/// Mismatched sizes or non-finite input.
pub fn force_residuals(
    k: &SparseMatrix,
    m: &SparseMatrix,
    lambdas: &[f64],
    x: MatRef<'_, f64>,
) -> Result<Mat<f64>, CorrelateError> {
    check_lambdas(lambdas, x, k.rows())?;
    let (kx, mx) = (sym_mul_mat(k, x)?, sym_mul_mat(m, x)?);
    Ok(Mat::from_fn(x.nrows(), x.ncols(), |i, j| {
        kx[(i, j)] - lambdas[j] * mx[(i, j)]
    }))
}

/// Forced (FRF) residual (4): `R_F = (K - omega_s^2 M) u_id - f` for a response `u_id` measured
/// under a harmonic force `f` at `omega_s` (rad/s).
///
/// # Errors
/// Mismatched sizes or non-finite input.
pub fn forced_residual(
    k: &SparseMatrix,
    m: &SparseMatrix,
    omega_s: f64,
    u: &[f64],
    f: &[f64],
) -> Result<Vec<f64>, CorrelateError> {
    if f.len() != k.rows() {
        return Err(CorrelateError::DimensionMismatch {
            what: "force against K",
            expected: k.rows(),
            got: f.len(),
        });
    }
    if let Some(index) = f.iter().position(|v| !v.is_finite()) {
        return Err(CorrelateError::NonFinite {
            what: "force",
            index,
        });
    }
    let um = MatRef::from_column_major_slice(u, u.len(), 1);
    let r = force_residuals(k, m, &[omega_s * omega_s], um)?;
    Ok(r.col(0).iter().zip(f).map(|(a, b)| a - b).collect())
}

/// Error-in-inertia-law residues (10)-(11): `Psi_i = M^-1 K x_i / lambda_id,i` and
/// `R_EIL,i = x_i - Psi_i`. Returns `(Psi, R_EIL)`.
///
/// # Errors
/// `lambda_id = 0` (the inertia law is empty), mismatched sizes, a failed `M^-1` solve.
pub fn eil_residuals(
    k: &SparseMatrix,
    mass: &MassSolver<'_>,
    lambdas: &[f64],
    x: MatRef<'_, f64>,
) -> Result<(Mat<f64>, Mat<f64>), CorrelateError> {
    check_lambdas(lambdas, x, k.rows())?;
    if let Some(i) = lambdas.iter().position(|l| *l == 0.0) {
        return Err(CorrelateError::Invalid {
            what: "identified eigenvalue",
            reason: format!(
                "mode {} has lambda_id = 0: the error in inertia law needs lambda_id != 0",
                i + 1
            ),
        });
    }
    let kx = sym_mul_mat(k, x)?;
    let (mut psi, _) = mass.solve(kx.as_ref())?;
    for j in 0..x.ncols() {
        psi.col_mut(j).iter_mut().for_each(|v| *v /= lambdas[j]);
    }
    let r = Mat::from_fn(x.nrows(), x.ncols(), |i, j| x[(i, j)] - psi[(i, j)]);
    Ok((psi, r))
}

/// How the singular case is handled.
#[derive(Debug, Clone)]
enum Inner {
    Definite(Llt),
    Singular {
        /// `LDL^T` of `K - sigma M`, `sigma < 0` just below the rigid-body zeros.
        factor: Ldlt,
        /// M-orthonormal rigid-body (null space) modes `Phi_r`.
        rigid: Mat<f64>,
        /// `M Phi_r`.
        m_rigid: Mat<f64>,
    },
}

/// Static solves with `K` for the displacement and ECL residues, including free-free models.
#[derive(Debug, Clone)]
pub struct StiffnessSolver<'a> {
    k: &'a SparseMatrix,
    m: &'a SparseMatrix,
    inner: Inner,
}

/// `1e-11 mean(K_ii / M_ii)`: far above round-off zeros of rigid-body modes (about
/// `1e-16 lambda_max`) and far below the first elastic eigenvalue of practical structures.
fn zero_threshold(pencil: &Pencil<'_>) -> f64 {
    1e-11 * pencil.diagonal_ratio()
}

/// A Cholesky factor of `K` with a pivot below this fraction of its diagonal entry is confirmed
/// by a Sturm count before it is trusted as definite (`1e-8`: far above the `1e-16`-`1e-12` pivots
/// round-off leaves for the rigid-body motions of a free-free model, far below the pivots of a
/// well-supported one).
const SUSPECT_PIVOT_RATIO: f64 = 1e-8;

impl<'a> StiffnessSolver<'a> {
    /// Factors `K` (Cholesky). When `K` is singular (a free-free or under-constrained model), its
    /// null space is found by the verified eigensolver: the Sturm count below a threshold
    /// (`1e-11 mean(K_ii / M_ii)`) gives its dimension, the eigensolver its M-orthonormal basis.
    /// A Cholesky factorization that succeeds is not proof that `K` is definite: round-off can
    /// keep the pivots of rigid-body motions positive (about `1e-14` of their diagonal entries).
    /// A factor with a pivot below `1e-8` of its diagonal is trusted only when the Sturm count
    /// finds no eigenvalue below the threshold.
    ///
    /// # Errors
    /// `K` indefinite (eigenvalues below minus the threshold), a failed factorization or
    /// eigensolve.
    pub fn new(k: &'a SparseMatrix, m: &'a SparseMatrix) -> Result<Self, CorrelateError> {
        if k.rows() != m.rows() {
            return Err(SparseError::DimensionMismatch {
                what: "M against K",
                expected: k.rows(),
                got: m.rows(),
            }
            .into());
        }
        // one ordering and symbolic analysis of K's pattern serves the Cholesky attempt and, for
        // a singular K, the Sturm counts, the null-space eigensolve and the shifted factor
        let pencil = Pencil::new(k, m, Ordering::NestedDissection)?;
        let thr = zero_threshold(&pencil);
        match pencil.symbolic().llt(k, "K") {
            // A pivot far below its diagonal entry: K may be singular with round-off having kept
            // every pivot positive (a free-free model), and solving with that factor would return
            // its null space amplified by 1 / pivot. The Sturm count decides.
            Ok(llt)
                if llt.min_pivot_ratio().0 >= SUSPECT_PIVOT_RATIO
                    || pencil.count_below(thr)? == 0 =>
            {
                return Ok(Self {
                    k,
                    m,
                    inner: Inner::Definite(llt),
                });
            }
            Ok(_)
            | Err(SparseError::NotPositiveDefinite { .. })
            | Err(SparseError::NumericallySingular { .. }) => {}
            Err(e) => return Err(e.into()),
        }
        let negative = pencil.count_below(-thr)?;
        if negative > 0 {
            return Err(CorrelateError::Invalid {
                what: "K",
                reason: format!(
                    "K is indefinite: {negative} eigenvalue(s) of (K, M) below -{thr:e} s^-2; a stiffness must be positive semi-definite"
                ),
            });
        }
        let zeros = pencil.count_below(thr)?;
        if zeros == 0 {
            return Err(CorrelateError::Invalid {
                what: "K",
                reason: format!(
                    "Cholesky of K failed but no eigenvalue of (K, M) lies below {thr:e} s^-2: K is too ill-conditioned to be treated as singular or definite"
                ),
            });
        }
        let modes = pencil.solve(Which::Lowest(zeros), &EigenOptions::default())?;
        let count = modes.values.iter().filter(|v| v.abs() < thr).count();
        let rigid = modes.vectors.subcols(0, count).to_owned();
        Self::singular(k, m, rigid, &pencil, thr)
    }

    /// As [`StiffnessSolver::new`] for a singular `K` whose null space is known (for example the
    /// six rigid-body motions of a free-free solid, built from node coordinates).
    /// The basis is M-orthonormalised here.
    ///
    /// # Errors
    /// A basis that `K` does not annihilate (`||K r|| > 1e-8 ||K||_1 ||r||`), a dependent basis, a
    /// failed factorization.
    pub fn with_null_space(
        k: &'a SparseMatrix,
        m: &'a SparseMatrix,
        basis: MatRef<'_, f64>,
    ) -> Result<Self, CorrelateError> {
        let n = k.rows();
        if basis.nrows() != n {
            return Err(CorrelateError::DimensionMismatch {
                what: "null-space basis against K",
                expected: n,
                got: basis.nrows(),
            });
        }
        let pencil = Pencil::new(k, m, Ordering::NestedDissection)?;
        let mut q = basis.to_owned();
        // unit M-norm first, so that "dependent" below is relative
        crate::correlation::mass_normalise(m, q.as_mut())?;
        // Two passes of modified Gram-Schmidt in the M inner product; `M q_i` is formed once per
        // column when it is final for the pass.
        for _ in 0..2 {
            let mut mq: Vec<Mat<f64>> = Vec::with_capacity(q.ncols());
            for j in 0..q.ncols() {
                for (i, mqi) in mq.iter().enumerate() {
                    let c: f64 = q
                        .col(j)
                        .iter()
                        .zip(mqi.col(0).iter())
                        .map(|(a, b)| a * b)
                        .sum();
                    for r in 0..n {
                        let v = q[(r, i)];
                        q[(r, j)] -= c * v;
                    }
                }
                let mut mqj = sym_mul_mat(m, q.as_ref().subcols(j, 1))?;
                let nrm: f64 = q
                    .col(j)
                    .iter()
                    .zip(mqj.col(0).iter())
                    .map(|(a, b)| a * b)
                    .sum();
                if !(nrm > 1e-20) {
                    return Err(CorrelateError::Invalid {
                        what: "null-space basis",
                        reason: format!("vector {j} depends on the others"),
                    });
                }
                let s = 1.0 / nrm.sqrt();
                q.col_mut(j).iter_mut().for_each(|v| *v *= s);
                mqj.col_mut(0).iter_mut().for_each(|v| *v *= s);
                mq.push(mqj);
            }
        }
        let knorm = pencil.norms().0;
        let kq = sym_mul_mat(k, q.as_ref())?;
        for j in 0..q.ncols() {
            let r = kq.col(j).norm_l2();
            if r > 1e-8 * knorm * q.col(j).norm_l2() {
                return Err(CorrelateError::Invalid {
                    what: "null-space basis",
                    reason: format!(
                        "K does not annihilate vector {j}: ||K r|| = {r:e}, ||K||_1 ||r|| = {:e}",
                        knorm * q.col(j).norm_l2()
                    ),
                });
            }
        }
        let thr = zero_threshold(&pencil);
        Self::singular(k, m, q, &pencil, thr)
    }

    fn singular(
        k: &'a SparseMatrix,
        m: &'a SparseMatrix,
        rigid: Mat<f64>,
        pencil: &Pencil<'_>,
        thr: f64,
    ) -> Result<Self, CorrelateError> {
        let factor = pencil.factor_shifted(-thr)?;
        let m_rigid = sym_mul_mat(m, rigid.as_ref())?;
        Ok(Self {
            k,
            m,
            inner: Inner::Singular {
                factor,
                rigid,
                m_rigid,
            },
        })
    }

    /// The M-orthonormal null-space (rigid-body) modes, when `K` is singular.
    pub fn null_space(&self) -> Option<MatRef<'_, f64>> {
        match &self.inner {
            Inner::Definite(_) => None,
            Inner::Singular { rigid, .. } => Some(rigid.as_ref()),
        }
    }

    /// `x - Phi_r Phi_r^T M x`: removes the rigid-body part (identity when `K` is definite).
    pub fn project(&self, x: MatRef<'_, f64>) -> Mat<f64> {
        let mut y = x.to_owned();
        if let Inner::Singular { rigid, m_rigid, .. } = &self.inner {
            let c = m_rigid.transpose() * x;
            y -= rigid * &c;
        }
        y
    }

    /// Solves `K Y = B` column by column. For a singular `K`, solves
    /// `K Y = (I - M Phi_r Phi_r^T) B` with `Phi_r^T M Y = 0` (docs/MATH.md's free-free convention) by
    /// iterative refinement on `K - sigma M` (`sigma` just below zero): each step divides the
    /// error of elastic mode `j` by `(lambda_j - sigma) / |sigma|`, about 10^9 or more.
    ///
    /// # Errors
    /// A dimension mismatch.
    pub fn solve(&self, b: MatRef<'_, f64>) -> Result<Mat<f64>, CorrelateError> {
        let n = self.k.rows();
        if b.nrows() != n {
            return Err(CorrelateError::DimensionMismatch {
                what: "right-hand side of K y = b",
                expected: n,
                got: b.nrows(),
            });
        }
        match &self.inner {
            Inner::Definite(llt) => {
                let mut y = b.to_owned();
                llt.solve_in_place(y.as_mut());
                Ok(y)
            }
            Inner::Singular {
                factor,
                rigid,
                m_rigid,
            } => {
                // Load with its rigid-body part removed: (I - M Phi_r Phi_r^T) b.
                let c = rigid.transpose() * b;
                let load = b.to_owned() - m_rigid * &c;
                let load_norm = load.norm_l2();
                let mut y = Mat::<f64>::zeros(n, b.ncols());
                let mut r = load.clone();
                let mut last = f64::INFINITY;
                for _ in 0..12 {
                    factor.solve_in_place(r.as_mut());
                    y += self.project(r.as_ref());
                    r = &load - sym_mul_mat(self.k, y.as_ref())?;
                    let rn = r.norm_l2();
                    if rn <= 1e-15 * load_norm || rn >= 0.5 * last {
                        break;
                    }
                    last = rn;
                }
                Ok(y)
            }
        }
    }

    /// Displacement residuals (5): `R_D = K^-1 R_F` column by column (free-free convention above).
    ///
    /// # Errors
    /// As [`StiffnessSolver::solve`].
    pub fn displacement_residuals(&self, r_f: MatRef<'_, f64>) -> Result<Mat<f64>, CorrelateError> {
        self.solve(r_f)
    }

    /// Error-in-constitutive-law residues (7)-(8): `K Psi_i = lambda_id,i M x_i`,
    /// `R_ECL,i = x_i - Psi_i` (for a singular `K`, `x_i` with its rigid-body part removed, so
    /// that `R_ECL = R_D` as in (9)). Returns `(Psi, R_ECL)`.
    ///
    /// # Errors
    /// Mismatched sizes or non-finite input.
    pub fn ecl_residuals(
        &self,
        lambdas: &[f64],
        x: MatRef<'_, f64>,
    ) -> Result<(Mat<f64>, Mat<f64>), CorrelateError> {
        check_lambdas(lambdas, x, self.k.rows())?;
        let mut load = sym_mul_mat(self.m, x)?;
        for j in 0..x.ncols() {
            load.col_mut(j).iter_mut().for_each(|v| *v *= lambdas[j]);
        }
        let psi = self.solve(load.as_ref())?;
        let r = self.project(x) - &psi;
        Ok((psi, r))
    }
}
