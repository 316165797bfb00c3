//! The dense path: generalized symmetric eigenproblems `K x = lambda M x` with `M` positive
//! definite, for small problems and as the reference the sparse solvers are checked against.

use crate::SparseError;
use faer::{Mat, MatRef, Side};

/// All eigenpairs of a symmetric-definite pencil `(K, M)`.
#[derive(Debug, Clone)]
pub struct GeneralizedEigen {
    /// Eigenvalues `lambda_j` in nondecreasing order (s^-2 when `K`, `M` are in SI units).
    pub values: Vec<f64>,
    /// Eigenvectors in the columns, M-normalised: `phi_i^T M phi_j = delta_ij` (docs/MATH.md notation).
    pub vectors: Mat<f64>,
}

fn check_square_finite(
    a: MatRef<'_, f64>,
    name: &'static str,
    n: usize,
) -> Result<(), SparseError> {
    if a.nrows() != n || a.ncols() != n {
        return Err(SparseError::DimensionMismatch {
            what: name,
            expected: n,
            got: a.nrows().max(a.ncols()),
        });
    }
    for j in 0..n {
        for i in 0..n {
            if !a[(i, j)].is_finite() {
                return Err(SparseError::NonFinite {
                    matrix: name,
                    row: i,
                    col: j,
                });
            }
        }
    }
    Ok(())
}

/// All eigenpairs of a dense symmetric matrix (lower triangle read), eigenvalues ascending.
///
/// Uses nalgebra's Householder tridiagonalisation and implicit QR. faer 0.24's
/// `self_adjoint_eigen` (eigenvectors requested, with either its divide and conquer or its QR
/// path) lost about eight digits on assembled FE pencils: on a free-free plate with
/// `lambda_max = 3.5e13` it returned rigid-body eigenvalues of -3.5e6 where the eigenvalues-only
/// path and nalgebra return 1e-3, and the first elastic eigenvalue 5e-10 off.
///
/// # Errors
/// [`SparseError::NoConvergence`] if the QR iteration fails.
pub fn symmetric_eigen(a: MatRef<'_, f64>) -> Result<(Vec<f64>, Mat<f64>), SparseError> {
    let n = a.nrows();
    let m =
        nalgebra::DMatrix::<f64>::from_fn(n, n, |i, j| if i >= j { a[(i, j)] } else { a[(j, i)] });
    let eig = nalgebra::SymmetricEigen::try_new(m, f64::EPSILON, 0).ok_or_else(|| {
        SparseError::NoConvergence {
            reason: "dense symmetric QR iteration".into(),
        }
    })?;
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|i, j| eig.eigenvalues[*i].total_cmp(&eig.eigenvalues[*j]));
    let values = order.iter().map(|i| eig.eigenvalues[*i]).collect();
    let vectors = Mat::from_fn(n, n, |i, j| eig.eigenvectors[(i, order[j])]);
    Ok((values, vectors))
}

/// `C = L^-1 K L^-T` with `M = L L^T`, and the Cholesky factor.
fn reduce_to_standard(
    k: MatRef<'_, f64>,
    m: MatRef<'_, f64>,
) -> Result<(Mat<f64>, faer::linalg::solvers::Llt<f64>), SparseError> {
    let n = k.nrows();
    check_square_finite(k, "K", n)?;
    check_square_finite(m, "M", n)?;
    let llt = m.llt(Side::Lower).map_err(|e| match e {
        faer::linalg::solvers::LltError::NonPositivePivot { index } => {
            SparseError::NotPositiveDefinite { matrix: "M", index }
        }
    })?;
    let l = llt.L();
    // C = L^-1 K L^-T, formed from the symmetrised lower triangle of K.
    let mut c = Mat::from_fn(n, n, |i, j| if i >= j { k[(i, j)] } else { k[(j, i)] });
    l.solve_lower_triangular_in_place(c.as_mut());
    let mut ct = c.transpose().to_owned();
    l.solve_lower_triangular_in_place(ct.as_mut());
    // Symmetrise against round-off before the symmetric eigensolver.
    let c = Mat::from_fn(n, n, |i, j| 0.5 * (ct[(i, j)] + ct[(j, i)]));
    Ok((c, llt))
}

/// Solves `K x = lambda M x` densely: `M = L L^T` (Cholesky), the standard symmetric problem
/// `L^-1 K L^-T y = lambda y`, then `x = L^-T y`, which is M-normalised because `y` is
/// orthonormal. Only the lower triangles of `K` and `M` are read.
///
/// Cost `O(n^3)`: meant for `n` up to a few thousand.
///
/// # Errors
/// [`SparseError::NotPositiveDefinite`] if `M` is not positive definite (with the pivot index),
/// [`SparseError::NonFinite`] for a NaN or infinity, [`SparseError::DimensionMismatch`] for shapes,
/// [`SparseError::NoConvergence`] if the symmetric eigensolver fails.
pub fn generalized_symmetric_eigen(
    k: MatRef<'_, f64>,
    m: MatRef<'_, f64>,
) -> Result<GeneralizedEigen, SparseError> {
    let (c, llt) = reduce_to_standard(k, m)?;
    let l = llt.L();
    let (values, mut vectors) = symmetric_eigen(c.as_ref())?;
    l.transpose()
        .solve_upper_triangular_in_place(vectors.as_mut());
    Ok(GeneralizedEigen { values, vectors })
}

/// The eigenvalues only of `K x = lambda M x`, ascending: the same reduction as
/// [`generalized_symmetric_eigen`], then faer's eigenvalues-only tridiagonal QR, which is accurate
/// (agrees with nalgebra to 2e-13 relative on assembled FE pencils) and about five times faster
/// than computing eigenvectors.
///
/// # Errors
/// As [`generalized_symmetric_eigen`].
pub fn generalized_symmetric_eigenvalues(
    k: MatRef<'_, f64>,
    m: MatRef<'_, f64>,
) -> Result<Vec<f64>, SparseError> {
    let c = reduce_to_standard(k, m)?.0;
    c.self_adjoint_eigenvalues(Side::Lower)
        .map_err(|e| SparseError::NoConvergence {
            reason: format!("dense symmetric eigenvalues: {e:?}"),
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 2-DOF spring-mass chain with a hand-computed spectrum:
    /// K = [[2k, -k], [-k, k]], M = m I, lambda = (3 -+ sqrt 5)/2 * k/m.
    #[test]
    fn two_dof_chain_matches_closed_form() {
        let (kk, mm) = (1000.0, 2.0);
        let k = Mat::from_fn(2, 2, |i, j| [[2.0 * kk, -kk], [-kk, kk]][i][j]);
        let m = Mat::from_fn(2, 2, |i, j| if i == j { mm } else { 0.0 });
        let e = generalized_symmetric_eigen(k.as_ref(), m.as_ref()).unwrap();
        let s5 = 5.0_f64.sqrt();
        assert!((e.values[0] / ((3.0 - s5) / 2.0 * kk / mm) - 1.0).abs() < 1e-13);
        assert!((e.values[1] / ((3.0 + s5) / 2.0 * kk / mm) - 1.0).abs() < 1e-13);
        // M-orthonormality and residuals.
        let x = &e.vectors;
        let g = x.transpose() * &m * x;
        let r = &k * x
            - &m * x * faer::Mat::from_fn(2, 2, |i, j| if i == j { e.values[i] } else { 0.0 });
        for i in 0..2 {
            for j in 0..2 {
                assert!((g[(i, j)] - if i == j { 1.0 } else { 0.0 }).abs() < 1e-13);
                assert!(r[(i, j)].abs() < 1e-9);
            }
        }
    }

    #[test]
    fn indefinite_mass_is_an_error_with_the_pivot() {
        let k = Mat::<f64>::identity(3, 3);
        let m = Mat::from_fn(3, 3, |i, j| if i == j { [1.0, 1.0, -1.0][i] } else { 0.0 });
        assert_eq!(
            generalized_symmetric_eigen(k.as_ref(), m.as_ref()).unwrap_err(),
            SparseError::NotPositiveDefinite {
                matrix: "M",
                index: 2
            }
        );
        let mut kn = Mat::<f64>::identity(3, 3);
        kn[(1, 0)] = f64::NAN;
        assert!(matches!(
            generalized_symmetric_eigen(kn.as_ref(), Mat::<f64>::identity(3, 3).as_ref()),
            Err(SparseError::NonFinite {
                matrix: "K",
                row: 1,
                col: 0
            })
        ));
    }
}
