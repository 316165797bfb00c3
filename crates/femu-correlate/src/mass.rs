//! Products with `M^-1`: the dual norm `||r||_{M^-1}` of force residuals (MATH.md, "Norms") and
//! the error-in-inertia-law residue (10)-(12).
//!
//! A lumped `M` is diagonal and is inverted entry by entry. A consistent `M` is spectrally
//! equivalent to its diagonal `D` with constants that depend on the element kinds only (for a
//! trilinear hex, the eigenvalues of `D^-1 M` lie in `[1/8, 27/8]` whatever the mesh size), so
//! Jacobi-preconditioned conjugate gradients converge in a mesh-independent number of iterations,
//! each one a sparse product: far cheaper than the factorization an eigen extraction needs. A
//! sparse Cholesky of `M` is offered for repeated solves on small models.

use crate::CorrelateError;
use faer::{Mat, MatRef};
use femu_sparse::cholesky::{Factorization, Llt, SymbolicFactor};
use femu_sparse::ordering::Ordering;
use femu_sparse::{SparseError, SparseMatrix};

/// How `M^-1 r` is computed.
#[derive(Debug, Clone)]
pub enum MassSolver {
    /// `M` is diagonal (lumped): its inverse entries.
    Diagonal(Vec<f64>),
    /// Jacobi-preconditioned conjugate gradients on a consistent `M`.
    Pcg(Pcg),
    /// A sparse Cholesky factorization of `M`.
    Cholesky(Box<Llt>),
}

/// Settings and data of the preconditioned conjugate gradient solver.
#[derive(Debug, Clone)]
pub struct Pcg {
    m: SparseMatrix,
    inv_diag: Vec<f64>,
    /// Stop when `sqrt(r^T D^-1 r / b^T D^-1 b) <= tol` for every right-hand side.
    pub tol: f64,
    /// Iterations allowed.
    pub max_iterations: usize,
}

/// What a solve with `M` did.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SolveReport {
    /// Conjugate gradient iterations (0 for the direct paths).
    pub iterations: usize,
    /// Largest final relative preconditioned residual (0 for the direct paths).
    pub residual: f64,
}

fn diagonal(m: &SparseMatrix) -> Result<(Vec<f64>, bool), CorrelateError> {
    let n = m.rows();
    if m.cols() != n {
        return Err(SparseError::DimensionMismatch {
            what: "M must be square",
            expected: n,
            got: m.cols(),
        }
        .into());
    }
    let mut d = vec![0.0; n];
    let mut is_diagonal = true;
    for (v, (r, c)) in m.iter() {
        if !v.is_finite() {
            return Err(SparseError::NonFinite {
                matrix: "M",
                row: r,
                col: c,
            }
            .into());
        }
        if r == c {
            d[r] = *v;
        } else if *v != 0.0 {
            is_diagonal = false;
        }
    }
    if let Some(i) = d.iter().position(|v| *v <= 0.0) {
        return Err(SparseError::NotPositiveDefinite {
            matrix: "M (diagonal entry)",
            index: i,
        }
        .into());
    }
    Ok((d, is_diagonal))
}

impl MassSolver {
    /// The natural solver for `M`: [`MassSolver::Diagonal`] when `M` is diagonal, otherwise
    /// [`MassSolver::Pcg`] with `tol = 1e-9` (the quadratic form `r^T M^-1 r` is then exact to
    /// about `kappa(D^-1 M) 1e-18`, machine precision) and 1000 iterations.
    ///
    /// # Errors
    /// A non-square `M`, a non-finite entry, or a diagonal entry `<= 0` (not positive definite).
    pub fn new(m: &SparseMatrix) -> Result<Self, CorrelateError> {
        let (d, is_diagonal) = diagonal(m)?;
        let inv: Vec<f64> = d.iter().map(|v| 1.0 / v).collect();
        Ok(if is_diagonal {
            Self::Diagonal(inv)
        } else {
            Self::Pcg(Pcg {
                m: m.clone(),
                inv_diag: inv,
                tol: 1e-9,
                max_iterations: 1000,
            })
        })
    }

    /// A sparse Cholesky factorization of `M` (nested dissection ordering).
    ///
    /// # Errors
    /// [`SparseError::NotPositiveDefinite`] with the failing pivot, or a malformed `M`.
    pub fn cholesky(m: &SparseMatrix) -> Result<Self, CorrelateError> {
        diagonal(m)?;
        let symbolic = SymbolicFactor::new(m, Ordering::NestedDissection)?;
        Ok(Self::Cholesky(Box::new(symbolic.llt(m, "M")?)))
    }

    /// `M^-1 R` for the columns of `R`.
    ///
    /// # Errors
    /// A dimension mismatch; for PCG, [`SparseError::NoConvergence`] or a breakdown
    /// (`p^T M p <= 0`: `M` is not positive definite).
    pub fn solve(&self, r: MatRef<'_, f64>) -> Result<(Mat<f64>, SolveReport), CorrelateError> {
        let n = self.dim();
        if r.nrows() != n {
            return Err(CorrelateError::DimensionMismatch {
                what: "right-hand side of M^-1 r",
                expected: n,
                got: r.nrows(),
            });
        }
        match self {
            Self::Diagonal(inv) => Ok((
                Mat::from_fn(n, r.ncols(), |i, j| r[(i, j)] * inv[i]),
                SolveReport::default(),
            )),
            Self::Cholesky(llt) => {
                let mut x = r.to_owned();
                llt.solve_in_place(x.as_mut());
                Ok((x, SolveReport::default()))
            }
            Self::Pcg(pcg) => pcg.solve(r),
        }
    }

    /// `||r_i||_{M^-1}^2 = r_i^T M^-1 r_i` for every column.
    ///
    /// # Errors
    /// As [`MassSolver::solve`].
    pub fn dual_norms_squared(
        &self,
        r: MatRef<'_, f64>,
    ) -> Result<(Vec<f64>, SolveReport), CorrelateError> {
        let (z, report) = self.solve(r)?;
        let norms = (0..r.ncols())
            .map(|j| {
                r.col(j)
                    .iter()
                    .zip(z.col(j).iter())
                    .map(|(a, b)| a * b)
                    .sum()
            })
            .collect();
        Ok((norms, report))
    }

    /// Dimension of `M`.
    pub fn dim(&self) -> usize {
        match self {
            Self::Diagonal(d) => d.len(),
            Self::Pcg(p) => p.inv_diag.len(),
            Self::Cholesky(l) => l.dim(),
        }
    }
}

impl Pcg {
    /// Block PCG: the columns iterate independently but share one sparse product per iteration.
    fn solve(&self, b: MatRef<'_, f64>) -> Result<(Mat<f64>, SolveReport), CorrelateError> {
        let (n, k) = (b.nrows(), b.ncols());
        let mut x = Mat::<f64>::zeros(n, k);
        let mut r = b.to_owned();
        let mut z = Mat::from_fn(n, k, |i, j| r[(i, j)] * self.inv_diag[i]);
        let mut p = z.clone();
        let dot = |a: &Mat<f64>, c: &Mat<f64>, j: usize| -> f64 {
            a.col(j)
                .iter()
                .zip(c.col(j).iter())
                .map(|(u, v)| u * v)
                .sum()
        };
        let mut rz: Vec<f64> = (0..k).map(|j| dot(&r, &z, j)).collect();
        let rz0 = rz.clone();
        let mut active: Vec<usize> = (0..k).filter(|&j| rz0[j] > 0.0).collect();
        let mut report = SolveReport::default();
        while !active.is_empty() {
            if report.iterations == self.max_iterations {
                return Err(SparseError::NoConvergence {
                    reason: format!(
                        "Jacobi-preconditioned CG on M: {} of {k} right-hand sides above tolerance {:e} after {} iterations",
                        active.len(),
                        self.tol,
                        self.max_iterations
                    ),
                }
                .into());
            }
            report.iterations += 1;
            let pa = Mat::from_fn(n, active.len(), |i, a| p[(i, active[a])]);
            let mp = femu_sparse::csc::sym_mul_mat(&self.m, pa.as_ref())?;
            let mut still = Vec::with_capacity(active.len());
            for (a, &j) in active.iter().enumerate() {
                let pmp: f64 = p
                    .col(j)
                    .iter()
                    .zip(mp.col(a).iter())
                    .map(|(u, v)| u * v)
                    .sum();
                if !(pmp > 0.0) {
                    return Err(SparseError::NotPositiveDefinite {
                        matrix: "M (conjugate gradient breakdown, p^T M p <= 0)",
                        index: j,
                    }
                    .into());
                }
                let alpha = rz[j] / pmp;
                for i in 0..n {
                    x[(i, j)] += alpha * p[(i, j)];
                    r[(i, j)] -= alpha * mp[(i, a)];
                    z[(i, j)] = r[(i, j)] * self.inv_diag[i];
                }
                let rz_new = dot(&r, &z, j);
                let rel = (rz_new.max(0.0) / rz0[j]).sqrt();
                if rel <= self.tol {
                    report.residual = report.residual.max(rel);
                    continue;
                }
                let beta = rz_new / rz[j];
                rz[j] = rz_new;
                for i in 0..n {
                    p[(i, j)] = z[(i, j)] + beta * p[(i, j)];
                }
                still.push(j);
            }
            active = still;
        }
        Ok((x, report))
    }
}
