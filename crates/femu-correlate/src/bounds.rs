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
//!
//! A model given as matrices has no elements: [`inertia_bounds`] proves the same two bounds from
//! the assembled pencil by Sylvester's law of inertia instead (docs/MATH.md, "The estimators").

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

/// `lambda_max(K, M)` bounded above and `mu_min(M)` below from the assembled matrices, each proven
/// by a Sturm count (Sylvester's law of inertia): `K - tau M` with `n` negative pivots has every
/// eigenvalue below `tau`; `M - mu I` with none has `mu_min(M) >= mu`. The first `tau` tried is
/// `max_i sum_j |k_ij| / m_ii` (Gershgorin's row sums over the mass diagonal), multiplied by 4
/// until the count proves it; `mu` is Gershgorin's lower bound when it is positive, otherwise
/// half the smallest mass diagonal, divided by 4 until proven. For models without elements (K
/// and M read from another solver), where [`element_bounds`] has nothing to sum over.
///
/// Returns `(lambda_max upper bound, mu_min lower bound)`: `lambda_max` is infinite when the
/// mass is singular (a DOF without mass, or no `tau` up to `4^30` times the first proves a
/// bound: the pencil has infinite eigenvalues), and `mu_min` is `None` then.
///
/// # Errors
/// The factorizations' errors (a non-finite or non-symmetric matrix).
pub fn inertia_bounds(
    k: &femu_sparse::SparseMatrix,
    m: &femu_sparse::SparseMatrix,
) -> Result<(f64, Option<f64>), CorrelateError> {
    use femu_sparse::eigen::Pencil;
    let n = k.rows();
    let diag = |a: &femu_sparse::SparseMatrix, i: usize| a.get(i, i).copied().unwrap_or(0.0);
    let mut row_abs = vec![0.0; n];
    let mut m_off = vec![0.0; n];
    for (v, (i, _)) in k.iter() {
        row_abs[i] += v.abs();
    }
    for (v, (i, j)) in m.iter() {
        if i != j {
            m_off[i] += v.abs();
        }
    }
    if n == 0 || (0..n).any(|i| !(diag(m, i) > 0.0)) {
        return Ok((f64::INFINITY, None));
    }
    let mut tau = (0..n)
        .map(|i| row_abs[i] / diag(m, i))
        .fold(0.0_f64, f64::max)
        .max(f64::MIN_POSITIVE);
    // K - tau M is factored on K's pattern: K with a stored zero wherever M has an entry K lacks
    let mut union = sprs::TriMat::with_capacity((n, n), k.nnz() + m.nnz());
    for (v, (i, j)) in k.iter() {
        union.add_triplet(i, j, *v);
    }
    for (_, (i, j)) in m.iter() {
        union.add_triplet(i, j, 0.0);
    }
    let k_union: femu_sparse::SparseMatrix = union.to_csc();
    let pencil = Pencil::new(&k_union, m, femu_sparse::ordering::Ordering::default())?;
    let mut lambda_max = f64::INFINITY;
    for _ in 0..=30 {
        if pencil.count_below(tau)? == n {
            lambda_max = tau;
            break;
        }
        tau *= 4.0;
    }
    if !lambda_max.is_finite() {
        return Ok((lambda_max, None));
    }
    let gershgorin = (0..n)
        .map(|i| diag(m, i) - m_off[i])
        .fold(f64::INFINITY, f64::min);
    if gershgorin > 0.0 {
        return Ok((lambda_max, Some(gershgorin)));
    }
    let identity: femu_sparse::SparseMatrix = sprs::CsMat::eye_csc(n);
    let mass = Pencil::new(m, &identity, femu_sparse::ordering::Ordering::default())?;
    let mut mu = 0.5 * (0..n).map(|i| diag(m, i)).fold(f64::INFINITY, f64::min);
    for _ in 0..=30 {
        if mass.count_below(mu)? == 0 {
            return Ok((lambda_max, Some(mu)));
        }
        mu *= 0.25;
    }
    Ok((lambda_max, None))
}
