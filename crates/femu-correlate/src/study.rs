//! The study of the paper's Figure 1: how the a priori estimators degrade as sensors are removed
//! and modal expansion fills the gaps.
//!
//! For each sensor set (triaxial sensors at the remaining nodes) and each expansion method, the
//! test shapes are restricted to the sensors, expanded to full length, and `rho_M` and `rho_2`
//! are computed at the identified eigenvalues, without any model eigenpair (except SEREP's basis).

use crate::expansion::Expander;
use crate::{CorrelateError, Estimator, SensorLayout};
use faer::{Mat, MatRef};
use femu_fem::dof::DofMap;
use femu_fem::mesh::Mesh;
use femu_sparse::SparseMatrix;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;

/// An expansion method of [`Expander`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Method {
    /// Guyan: `x_o = -K_oo^-1 K_oa x_a`.
    Static,
    /// Dynamic at the identified eigenvalue.
    Dynamic,
    /// SEREP with the given number of model modes (taken from the study's basis).
    Serep(usize),
    /// Minimum residual in the `M^-1` norm.
    MinimumResidual,
    /// MDRE-WE with test weight `gamma` and stiffness shift.
    Mdre {
        /// Weight of the test error.
        gamma: f64,
        /// `K + shift M` for free-free models (0 when restrained).
        stiffness_shift: f64,
    },
}

impl Method {
    /// A short name for tables and legends.
    pub fn name(&self) -> String {
        match self {
            Method::Static => "static".into(),
            Method::Dynamic => "dynamic".into(),
            Method::Serep(m) => format!("serep{m}"),
            Method::MinimumResidual => "min-residual".into(),
            Method::Mdre { .. } => "mdre-we".into(),
        }
    }
}

/// One point of the study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StudyPoint {
    /// Measured nodes.
    pub nodes: usize,
    /// Measured DOFs.
    pub sensors: usize,
    /// Expansion method (`"full"` when every DOF is measured).
    pub method: String,
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
/// covers every free DOF, the shapes are used as they are (method `"full"`).
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
        let mut expanded: Vec<(String, Mat<f64>)> = Vec::new();
        if layout.len() == dofs.free_count() {
            expanded.push(("full".into(), x.to_owned()));
        } else {
            let exp = Expander::new(k, m, &layout)?;
            let ya = layout.measure_all(x)?;
            for method in methods {
                let context = |e: CorrelateError| CorrelateError::Invalid {
                    what: "sensor removal study",
                    reason: format!("{} with {} nodes: {e}", method.name(), nodes.len()),
                };
                let xe = match method {
                    Method::Static => exp.static_(ya.as_ref()),
                    Method::Dynamic => exp.dynamic(lambdas, ya.as_ref()),
                    Method::Serep(count) => match serep_basis {
                        Some(b) if *count <= b.ncols() => {
                            exp.serep(b.subcols(0, *count), ya.as_ref())
                        }
                        _ => Err(CorrelateError::Invalid {
                            what: "SEREP",
                            reason: format!(
                                "{count} modes requested, basis has {}",
                                serep_basis.map_or(0, |b| b.ncols())
                            ),
                        }),
                    },
                    Method::MinimumResidual => exp.minimum_residual(lambdas, ya.as_ref()),
                    Method::Mdre {
                        gamma,
                        stiffness_shift,
                    } => exp.mdre(lambdas, ya.as_ref(), *gamma, *stiffness_shift),
                }
                .map_err(context)?;
                expanded.push((method.name(), xe));
            }
        }
        for (name, xe) in expanded {
            let (norms, _) = estimator.residual_norms(lambdas, xe.as_ref())?;
            for (mode, n) in norms.iter().enumerate() {
                out.push(StudyPoint {
                    nodes: nodes.len(),
                    sensors: layout.len(),
                    method: name.clone(),
                    mode,
                    rho_m: n.rho_m,
                    rho_2: n.rho_2,
                });
            }
        }
    }
    Ok(out)
}

/// The study as CSV (`nodes,sensors,method,mode,rho_m,rho_2`, one row per point).
pub fn study_csv(points: &[StudyPoint]) -> String {
    let mut s = String::from("nodes,sensors,method,mode,rho_m,rho_2\n");
    for p in points {
        let _ = writeln!(
            s,
            "{},{},{},{},{:e},{:e}",
            p.nodes,
            p.sensors,
            p.method,
            p.mode + 1,
            p.rho_m,
            p.rho_2
        );
    }
    s
}
