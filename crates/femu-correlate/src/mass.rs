//! Products with `M^-1`: the dual norm `||r||_{M^-1}` of force residuals (docs/MATH.md, "Norms") and
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
use std::borrow::Cow;

/// `a` without the zeros stored off its diagonal ([`femu_sparse::csc::without_zeros`]),
/// borrowed when it has few (femu's assembly stores none).
fn without_zeros(a: &SparseMatrix) -> Cow<'_, SparseMatrix> {
    let zeros = a.data().iter().filter(|v| **v == 0.0).count();
    if zeros * 10 < a.nnz() {
        return Cow::Borrowed(a);
    }
    Cow::Owned(femu_sparse::csc::without_zeros(a))
}

/// How `M^-1 r` is computed.
#[derive(Debug, Clone)]
pub enum MassSolver<'a> {
    /// `M` is diagonal (lumped): its inverse entries.
    Diagonal(Vec<f64>),
    /// Jacobi-preconditioned conjugate gradients on a consistent `M`.
    Pcg(Pcg<'a>),
    /// A sparse Cholesky factorization of `M`.
    Cholesky(Box<Llt>),
}

/// Settings and data of the preconditioned conjugate gradient solver.
#[derive(Debug, Clone)]
pub struct Pcg<'a> {
    /// `M` without its stored zeros: femu assembles a consistent `M` on the stiffness pattern,
    /// where two thirds of the entries (x-y, x-z, y-z couplings) are exact zeros; dropping them
    /// cuts the memory traffic of every CG product by three.
    m: Cow<'a, SparseMatrix>,
    /// The massless DOFs, each given the mass `floor` ([`MassSolver::new`]) in `M`'s products.
    massless: Vec<usize>,
    floor: f64,
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

/// `M`'s diagonal, whether `M` is diagonal, and its massless DOFs: a zero diagonal entry whose row
/// is zero (a lumped beam's rotations, a CBAR's torsion under Nastran's coupled mass) is given the
/// smallest positive diagonal entry, as the residual metric gives it (docs/MATH.md, "The residual
/// metric on massless DOFs"): a massless DOF has no inertia force, and its residual is weighed as
/// the most heavily weighted DOF's.
fn diagonal(m: &SparseMatrix) -> Result<(Vec<f64>, bool, Vec<usize>), CorrelateError> {
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
    let mut coupled = vec![false; n];
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
            coupled[r] = true;
            coupled[c] = true;
        }
    }
    let floor = d
        .iter()
        .copied()
        .filter(|v| *v > 0.0)
        .fold(f64::INFINITY, f64::min);
    let bad = |i: usize| SparseError::NotPositiveDefinite {
        matrix: "M (diagonal entry)",
        index: i,
    };
    if let Some(i) = d
        .iter()
        .enumerate()
        .position(|(i, v)| *v < 0.0 || (*v == 0.0 && (coupled[i] || !floor.is_finite())))
    {
        return Err(bad(i).into());
    }
    let massless: Vec<usize> = (0..n).filter(|i| d[*i] == 0.0).collect();
    for &i in &massless {
        d[i] = floor;
    }
    Ok((d, is_diagonal, massless))
}

impl<'a> MassSolver<'a> {
    /// The natural solver for `M`: [`MassSolver::Diagonal`] when `M` is diagonal, otherwise
    /// [`MassSolver::Pcg`] with `tol = 1e-9` (the quadratic form `r^T M^-1 r` is then exact to
    /// about `kappa(D^-1 M) 1e-18`, machine precision) and 1000 iterations.
    ///
    /// # Errors
    /// A non-square `M`, a non-finite entry, a negative diagonal entry, or a zero one whose row
    /// is not zero (`M` is not positive semi-definite).
    pub fn new(m: &'a SparseMatrix) -> Result<Self, CorrelateError> {
        let (d, is_diagonal, massless) = diagonal(m)?;
        let inv: Vec<f64> = d.iter().map(|v| 1.0 / v).collect();
        Ok(if is_diagonal {
            Self::Diagonal(inv)
        } else {
            let floor = massless.first().map_or(0.0, |i| d[*i]);
            Self::Pcg(Pcg {
                m: without_zeros(m),
                massless,
                floor,
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
        let (_, _, massless) = diagonal(m)?;
        if let Some(i) = massless.first() {
            return Err(SparseError::NotPositiveDefinite {
                matrix: "M (a massless DOF: its Cholesky factor does not exist)",
                index: *i,
            }
            .into());
        }
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

impl Pcg<'_> {
    /// Block PCG: the columns iterate independently (own step lengths, own convergence) but share
    /// one sparse product per iteration. Vectors are kept row-major so that the product reads
    /// each matrix entry once for all columns.
    fn solve(&self, b: MatRef<'_, f64>) -> Result<(Mat<f64>, SolveReport), CorrelateError> {
        let (n, k) = (b.nrows(), b.ncols());
        let d = &self.inv_diag;
        let mut x = vec![0.0; n * k];
        let mut r = vec![0.0; n * k];
        for j in 0..k {
            for (i, v) in b.col(j).iter().enumerate() {
                r[i * k + j] = *v;
            }
        }
        let mut z: Vec<f64> = r.iter().enumerate().map(|(p, v)| v * d[p / k]).collect();
        let mut p = z.clone();
        let mut q = vec![0.0; n * k];
        let col_dot = |a: &[f64], c: &[f64]| -> Vec<f64> {
            let mut s = vec![0.0; k];
            for (ra, rc) in a.chunks_exact(k).zip(c.chunks_exact(k)) {
                for j in 0..k {
                    s[j] += ra[j] * rc[j];
                }
            }
            s
        };
        let mut rz = col_dot(&r, &z);
        let rz0 = rz.clone();
        // converged (or zero) columns take no further steps
        let mut active: Vec<bool> = rz0.iter().map(|v| *v > 0.0).collect();
        let mut report = SolveReport::default();
        let (mut alpha, mut beta) = (vec![0.0; k], vec![0.0; k]);
        while active.iter().any(|a| *a) {
            if report.iterations == self.max_iterations {
                return Err(SparseError::NoConvergence {
                    reason: format!(
                        "Jacobi-preconditioned CG on M: {} of {k} right-hand sides above tolerance {:e} after {} iterations",
                        active.iter().filter(|a| **a).count(),
                        self.tol,
                        self.max_iterations
                    ),
                }
                .into());
            }
            report.iterations += 1;
            femu_sparse::csc::sym_mul_rows(&self.m, &p, k, &mut q)?;
            for &i in &self.massless {
                for j in 0..k {
                    q[i * k + j] += self.floor * p[i * k + j];
                }
            }
            let pq = col_dot(&p, &q);
            for j in 0..k {
                alpha[j] = 0.0;
                if active[j] {
                    if !(pq[j] > 0.0) {
                        return Err(SparseError::NotPositiveDefinite {
                            matrix: "M (conjugate gradient breakdown, p^T M p <= 0)",
                            index: j,
                        }
                        .into());
                    }
                    alpha[j] = rz[j] / pq[j];
                }
            }
            let mut rz_new = vec![0.0; k];
            for i in 0..n {
                let o = i * k;
                for j in 0..k {
                    x[o + j] += alpha[j] * p[o + j];
                    r[o + j] -= alpha[j] * q[o + j];
                    z[o + j] = r[o + j] * d[i];
                    rz_new[j] += r[o + j] * z[o + j];
                }
            }
            for j in 0..k {
                beta[j] = 0.0;
                if active[j] {
                    let rel = (rz_new[j].max(0.0) / rz0[j]).sqrt();
                    if rel <= self.tol {
                        active[j] = false;
                        report.residual = report.residual.max(rel);
                    } else {
                        beta[j] = rz_new[j] / rz[j];
                    }
                    rz[j] = rz_new[j];
                }
            }
            for i in 0..n {
                let o = i * k;
                for j in 0..k {
                    p[o + j] = if active[j] {
                        z[o + j] + beta[j] * p[o + j]
                    } else {
                        0.0
                    };
                }
            }
        }
        Ok((Mat::from_fn(n, k, |i, j| x[i * k + j]), report))
    }
}
