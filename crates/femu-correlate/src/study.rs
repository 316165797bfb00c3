//! The study of the paper's Figure 1: how the a priori estimators degrade as sensors are removed
//! and modal expansion fills the gaps.
//!
//! For each sensor set (triaxial sensors at the remaining nodes) and each expansion method, the
//! test shapes are restricted to the sensors, expanded to full length, and `rho_M` and `rho_2`
//! are computed at the identified eigenvalues, without any model eigenpair (except SEREP's basis).

use crate::expansion::{Expander, Method};
use crate::{CorrelateError, Estimator, SensorLayout, SensorSpace};
use faer::{Mat, MatRef};
use femu_fem::dof::DofMap;
use femu_fem::mesh::Mesh;
use femu_sparse::SparseMatrix;
use serde::{Deserialize, Serialize};

/// One point of the study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StudyPoint {
    /// Measured nodes.
    pub nodes: usize,
    /// Measured DOFs.
    pub sensors: usize,
    /// Expansion method; `None` when every free DOF is measured and nothing is expanded.
    pub method: Option<Method>,
    /// Test mode (0-based).
    pub mode: usize,
    /// `rho_M` of the expanded shape, s^-2.
    pub rho_m: f64,
    /// `rho_2` of the expanded shape.
    pub rho_2: f64,
}

/// Runs the sensor-removal study: starting from triaxial sensors at `start` (node ids), removes the
/// nodes of `removal` one at a time (every `stride`-th set is evaluated; the first and the last
/// always), expanding the test shapes `x` (full length, columns) with each method. When a set
/// covers every free DOF, the shapes are used as they are (method `None`).
///
/// # Errors
/// Unknown nodes, a removal node not in `start`, an expansion error (reported with the set size),
/// SEREP without a basis.
pub fn sensor_removal_study(
    k: &SparseMatrix,
    m: &SparseMatrix,
    mesh: &Mesh,
    dofs: &DofMap,
    lambdas: &[f64],
    x: MatRef<'_, f64>,
    start: &[u64],
    removal: &[u64],
    methods: &[Method],
    serep_basis: Option<MatRef<'_, f64>>,
    stride: usize,
) -> Result<Vec<StudyPoint>, CorrelateError> {
    if let Some(r) = removal.iter().find(|r| !start.contains(r)) {
        return Err(CorrelateError::Invalid {
            what: "sensor removal order",
            reason: format!("node {r} is not among the starting nodes"),
        });
    }
    let estimator = Estimator::new(k, m)?;
    let stride = stride.max(1);
    // Static, dynamic, minimum-residual and MDRE-WE expansions of every set come from one
    // factorization of Z per eigenvalue over the starting sensors' DOFs (sensor space); SEREP
    // and sets where a check fails use the per-set expander.
    let full_layout = SensorLayout::triaxial(mesh, dofs, start)?;
    let mut space = match full_layout.measured_dofs() {
        Some(c) if c.len() < dofs.free_count() => Some(SensorSpace::new(k, m, &c)?),
        _ => None,
    };
    if let Some(space) = space.as_mut() {
        let mut lams: Vec<f64> = lambdas.to_vec();
        let mut shifts = Vec::new();
        for method in methods {
            match method {
                Method::Static => lams.push(0.0),
                Method::Mdre { .. } => shifts.extend(method.stiffness_shift(lambdas)),
                _ => {}
            }
        }
        space.prepare(&lams, &shifts)?;
    }
    let mut out = Vec::new();
    let mut nodes: Vec<u64> = start.to_vec();
    for step in 0..=removal.len() {
        if step > 0 {
            nodes.retain(|n| *n != removal[step - 1]);
        }
        if nodes.is_empty() {
            break;
        }
        if step % stride != 0 && step != removal.len() {
            continue;
        }
        let layout = SensorLayout::triaxial(mesh, dofs, &nodes)?;
        let mut expanded: Vec<(Option<Method>, Mat<f64>)> = Vec::new();
        if layout.len() == dofs.free_count() {
            expanded.push((None, x.to_owned()));
        } else {
            let ya = layout.measure_all(x)?;
            let measured = layout.measured_dofs().ok_or(CorrelateError::Invalid {
                what: "sensor removal study",
                reason: "triaxial sensors without measured DOFs".into(),
            })?;
            // the per-set expander (extraction of K_oo) only where the sensor space does not serve
            let mut per_set: Option<Expander> = None;
            for method in methods {
                let context = |e: CorrelateError| CorrelateError::Invalid {
                    what: "sensor removal study",
                    reason: format!("{} with {} nodes: {e}", method.name(), nodes.len()),
                };
                let shared = space
                    .as_mut()
                    .and_then(|sp| in_space(sp, *method, lambdas, &measured, ya.as_ref()));
                let xe = match shared {
                    Some(result) => result,
                    None => {
                        let exp = match per_set {
                            Some(ref e) => e,
                            None => per_set.insert(Expander::new(k, m, &layout).map_err(context)?),
                        };
                        exp.expand(*method, lambdas, ya.as_ref(), serep_basis)
                    }
                }
                .map_err(context)?;
                expanded.push((Some(*method), xe));
            }
        }
        for (name, xe) in expanded {
            let (norms, _) = estimator.residual_norms(lambdas, xe.as_ref())?;
            for (mode, n) in norms.iter().enumerate() {
                out.push(StudyPoint {
                    nodes: nodes.len(),
                    sensors: layout.len(),
                    method: name,
                    mode,
                    rho_m: n.rho_m,
                    rho_2: n.rho_2,
                });
            }
        }
    }
    Ok(out)
}

/// `method` from the sensor space shared by every set (`None` for SEREP, which factors nothing).
fn in_space(
    sp: &mut SensorSpace<'_>,
    method: Method,
    lambdas: &[f64],
    measured: &[usize],
    ya: MatRef<'_, f64>,
) -> Option<Result<Mat<f64>, CorrelateError>> {
    match method {
        Method::Serep(_) => None,
        _ => Some(sp.expand(method, lambdas, measured, ya)),
    }
}
