//! Spectrum bounds computed element by element, without touching the assembled pencil.
//!
//! - Irons' element eigenvalue bound: for `K = sum_e K_e`, `M = sum_e M_e` with every `M_e`
//!   positive definite, the Rayleigh quotient gives
//!   `x^T K x = sum_e x_e^T K_e x_e <= sum_e lambda_max(K_e, M_e) x_e^T M_e x_e
//!   <= max_e lambda_max(K_e, M_e) x^T M x`, so `lambda_max(K, M) <= max_e lambda_max(K_e, M_e)`.
//!   This bounds `spread_k` of Theorems 1 and 3 (docs/MATH.md).
//! - The smallest eigenvalue of `M`: `x^T M x = sum_e x_e^T M_e x_e >= min_e mu_min(M_e)
//!   sum_e ||x_e||^2 >= min_e mu_min(M_e) ||x||^2`, since every DOF belongs to an element. It
//!   turns the paper's Euclidean ratio into a rigorous bound: `rho_M <= rho_2 / mu_min(M)`.
//!
//! Fixing DOFs restricts the Rayleigh quotients to a subspace, so both bounds hold for any
//! constraints.

use crate::CorrelateError;
use faer::Mat;
use femu_fem::FemError;
use femu_fem::assembly::MassKind;
use femu_fem::kernel::{element_stiffness_for, lumped_mass, scalar_mass};
use femu_fem::model::Model;
use femu_sparse::dense::{generalized_symmetric_eigenvalues, symmetric_eigen};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Bounds of the spectrum of the assembled pencil from element matrices.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ElementBounds {
    /// `max_e lambda_max(K_e, M_e) >= lambda_max(K, M)`, s^-2.
    pub lambda_max_upper: f64,
    /// The element (user id) attaining it.
    pub lambda_max_element: u64,
    /// `min_e mu_min(M_e) <= mu_min(M)`, kg.
    pub mu_min_lower: f64,
}

/// Per element: (lambda_max(K_e, M_e), mu_min(M_e)).
fn element_extremes(model: &Model, e: usize, mass: MassKind) -> Result<(f64, f64), CorrelateError> {
    let mesh = model.mesh();
    let el = mesh.element(e);
    let material = model.material_of(e)?;
    let mut coords = Vec::new();
    mesh.element_coords(e, &mut coords);
    let nn = el.kind.num_nodes();
    let nd = 3 * nn;
    let bad = |b: femu_fem::kernel::BadJacobian| -> CorrelateError {
        FemError::InvertedElement {
            element: el.id,
            det_j: b.det,
            point: b.point,
        }
        .into()
    };
    let mut ke = vec![0.0; nd * nd];
    element_stiffness_for(el.kind, model.formulation(e), &coords, material, &mut ke)
        .map_err(bad)?;
    let rho = material.density;
    let (me, mu_min) = match mass {
        MassKind::Consistent => {
            let mut ms = vec![0.0; nn * nn];
            scalar_mass(el.kind, &coords, rho, &mut ms).map_err(bad)?;
            let (vals, _) = symmetric_eigen(Mat::from_fn(nn, nn, |i, j| ms[i * nn + j]).as_ref())?;
            let me = Mat::from_fn(nd, nd, |i, j| {
                if i % 3 == j % 3 {
                    ms[(i / 3) * nn + j / 3]
                } else {
                    0.0
                }
            });
            (me, vals[0])
        }
        MassKind::Lumped => {
            let mut ml = vec![0.0; nn];
            lumped_mass(el.kind, &coords, rho, &mut ml).map_err(bad)?;
            let me = Mat::from_fn(nd, nd, |i, j| if i == j { ml[i / 3] } else { 0.0 });
            (me, ml.iter().copied().fold(f64::INFINITY, f64::min))
        }
    };
    if !(mu_min > 0.0) {
        return Err(CorrelateError::Invalid {
            what: "element mass",
            reason: format!(
                "element {} has a mass matrix that is not positive definite (smallest eigenvalue {mu_min:e})",
                el.id
            ),
        });
    }
    let ke = Mat::from_fn(nd, nd, |i, j| ke[i * nd + j]);
    let vals = generalized_symmetric_eigenvalues(ke.as_ref(), me.as_ref())?;
    Ok((*vals.last().unwrap_or(&0.0), mu_min))
}

/// Element-by-element bounds of `lambda_max(K, M)` and `mu_min(M)` for a model's mass kind.
///
/// `docs/MATH.md`, "The estimators": Irons' bound of `lambda_max` for `spread_k` and the lower bound of `mu_min(M)`.
///
/// # Errors
/// An element without material, an inverted element, an element mass that is not positive
/// definite, or an empty mesh.
pub fn element_bounds(model: &Model, mass: MassKind) -> Result<ElementBounds, CorrelateError> {
    let n = model.mesh().element_count();
    if n == 0 {
        return Err(CorrelateError::Invalid {
            what: "model",
            reason: "the mesh has no elements".into(),
        });
    }
    let extremes: Vec<(f64, f64)> = (0..n)
        .into_par_iter()
        .map(|e| element_extremes(model, e, mass))
        .collect::<Result<_, _>>()?;
    let (mut best, mut at, mut mu) = (f64::NEG_INFINITY, 0, f64::INFINITY);
    for (e, (l, m)) in extremes.iter().enumerate() {
        if *l > best {
            best = *l;
            at = e;
        }
        mu = mu.min(*m);
    }
    Ok(ElementBounds {
        lambda_max_upper: best,
        lambda_max_element: model.mesh().element(at).id,
        mu_min_lower: mu,
    })
}
