//! Derivatives of an eigenpair with respect to the updating parameters (`docs/MATH.md`,
//! "Updating"): `d lambda / d theta_k = phi^T (K_k - lambda M_k) phi` and the eigenvector
//! derivative by Nelson's method, exact for a simple eigenvalue, with one factorization of
//! `K - lambda M` (a pinned row and column) per mode and one solve per parameter.

use crate::UpdateError;
use crate::problem::UpdateModel;
use faer::Mat;
use femu_sparse::cholesky::Factorization;
use femu_sparse::eigen::Pencil;

/// The derivatives of one M-normalised eigenpair `(lambda, phi)` of `up`'s current model.
#[derive(Debug, Clone, PartialEq)]
pub struct EigenpairDerivatives {
    /// `d lambda / d theta_k`, s^-2 per unit parameter.
    pub values: Vec<f64>,
    /// `d phi / d theta_k` (full length, the M-normalisation kept to first order).
    pub vectors: Vec<Vec<f64>>,
}

/// Nelson's method: with `c_k = (K_k - lambda M_k) phi` (the sensitivity columns of
/// [`UpdateModel::columns`]), `d lambda_k = phi^T c_k`, and `v_k` solving
/// `(K - lambda M) v_k = -(c_k - d lambda_k M phi)` with the DOF where `|phi|` is largest pinned to
/// zero (the system is singular along `phi` only, and consistent); then
/// `d phi_k = v_k + a_k phi` with `a_k = -phi^T M v_k - phi^T M_k phi / 2` from the derivative of
/// `phi^T M phi = 1`.
///
/// # Errors
/// A wrong length of `phi`, and [`femu_sparse::SparseError::Singular`] (through
/// [`UpdateError`]) when `lambda` is a repeated eigenvalue, whose eigenvectors have no derivative.
pub fn eigenpair_derivatives(
    up: &UpdateModel<'_>,
    pencil: &Pencil<'_>,
    phi: &[f64],
    lambda: f64,
) -> Result<EigenpairDerivatives, UpdateError> {
    let sys = up.matrices();
    let n = phi.len();
    let cols = up.columns(phi, lambda)?;
    let mut m_phi = vec![0.0; n];
    femu_sparse::csc::mul_vec(&sys.m, phi, &mut m_phi)?;
    let pinned = (0..n)
        .max_by(|a, b| phi[*a].abs().total_cmp(&phi[*b].abs()))
        .unwrap_or(0);
    let factor = pencil.factor_shifted_pinned(lambda, pinned)?;
    let np = cols.len();
    let mut rhs = Mat::<f64>::zeros(n, np);
    let mut d_values = Vec::with_capacity(np);
    for (k, c) in cols.iter().enumerate() {
        let dl: f64 = c.dofs.iter().zip(&c.values).map(|(&d, v)| v * phi[d]).sum();
        d_values.push(dl);
        for (i, mp) in m_phi.iter().enumerate() {
            rhs[(i, k)] = dl * mp;
        }
        for (&d, v) in c.dofs.iter().zip(&c.values) {
            rhs[(d, k)] -= v;
        }
        rhs[(pinned, k)] = 0.0;
    }
    factor.solve_in_place(rhs.as_mut());
    let quadratics = up.mass_quadratics(phi)?;
    let vectors = (0..np)
        .map(|k| {
            let v: Vec<f64> = rhs.col(k).iter().copied().collect();
            let a = -v.iter().zip(&m_phi).map(|(x, y)| x * y).sum::<f64>() - 0.5 * quadratics[k];
            v.iter().zip(phi).map(|(x, p)| x + a * p).collect()
        })
        .collect();
    Ok(EigenpairDerivatives {
        values: d_values,
        vectors,
    })
}
