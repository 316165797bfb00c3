//! The study of the paper's Figure 1: how the a priori estimators degrade as sensors are removed
//! and modal expansion fills the gaps.
//!
//! For each sensor set (triaxial sensors at the remaining nodes) and each expansion method, the
//! test shapes are restricted to the sensors, expanded to full length, and `rho_M` and `rho_2`
//! are computed at the identified eigenvalues, without any model eigenpair (except SEREP's basis).

use crate::expansion::Expander;
use crate::{CorrelateError, Estimator, SensorLayout, SensorSpace};
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
                Method::Mdre {
                    stiffness_shift, ..
                } => shifts.push(*stiffness_shift),
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
        let mut expanded: Vec<(String, Mat<f64>)> = Vec::new();
        if layout.len() == dofs.free_count() {
            expanded.push(("full".into(), x.to_owned()));
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
                    .and_then(|sp| in_space(sp, method, lambdas, &measured, ya.as_ref()));
                let xe = match shared {
                    Some(result) => result,
                    None => {
                        let exp = match per_set {
                            Some(ref e) => e,
                            None => per_set.insert(Expander::new(k, m, &layout).map_err(context)?),
                        };
                        by_set(exp, method, lambdas, ya.as_ref(), serep_basis)
                    }
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

/// `method` from the sensor space shared by every set (`None` for SEREP, which factors nothing).
fn in_space(
    sp: &mut SensorSpace<'_>,
    method: &Method,
    lambdas: &[f64],
    measured: &[usize],
    ya: MatRef<'_, f64>,
) -> Option<Result<Mat<f64>, CorrelateError>> {
    Some(match method {
        Method::Static => sp.dynamic(&vec![0.0; lambdas.len()], measured, ya),
        Method::Dynamic => sp.dynamic(lambdas, measured, ya),
        Method::MinimumResidual => sp.minimum_residual(lambdas, measured, ya),
        Method::Mdre {
            gamma,
            stiffness_shift,
        } => sp.mdre(lambdas, measured, ya, *gamma, *stiffness_shift),
        Method::Serep(_) => return None,
    })
}

/// `method` by the expander of one sensor set.
fn by_set(
    exp: &Expander<'_>,
    method: &Method,
    lambdas: &[f64],
    ya: MatRef<'_, f64>,
    serep_basis: Option<MatRef<'_, f64>>,
) -> Result<Mat<f64>, CorrelateError> {
    match method {
        Method::Static => exp.static_(ya),
        Method::Dynamic => exp.dynamic(lambdas, ya),
        Method::Serep(count) => match serep_basis {
            Some(b) if *count <= b.ncols() => exp.serep(b.subcols(0, *count), ya),
            _ => Err(CorrelateError::Invalid {
                what: "SEREP",
                reason: format!(
                    "{count} modes requested, basis has {}",
                    serep_basis.map_or(0, |b| b.ncols())
                ),
            }),
        },
        Method::MinimumResidual => exp.minimum_residual(lambdas, ya),
        Method::Mdre {
            gamma,
            stiffness_shift,
        } => exp.mdre(lambdas, ya, *gamma, *stiffness_shift),
    }
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

/// The study as an SVG line chart in the manner of the paper's Figure 1: `rho_M` (log scale)
/// against the number of measured nodes, one line per (method, test mode). Self-contained SVG
/// (no fonts or libraries needed to view it).
pub fn study_svg(points: &[StudyPoint]) -> String {
    let (w, h, left, right, top, bottom) = (760.0, 480.0, 80.0, 200.0, 30.0, 50.0);
    let (pw, ph) = (w - left - right, h - top - bottom);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\" font-family=\"sans-serif\" font-size=\"12\">"
    );
    let _ = writeln!(s, "<rect width=\"{w}\" height=\"{h}\" fill=\"white\"/>");
    let finite: Vec<&StudyPoint> = points
        .iter()
        .filter(|p| p.rho_m > 0.0 && p.rho_m.is_finite())
        .collect();
    if finite.is_empty() {
        let _ = writeln!(
            s,
            "<text x=\"{}\" y=\"{}\">no data</text>\n</svg>",
            w / 2.0,
            h / 2.0
        );
        return s;
    }
    let xmin = finite.iter().map(|p| p.nodes).min().unwrap_or(0) as f64;
    let xmax = (finite.iter().map(|p| p.nodes).max().unwrap_or(1) as f64).max(xmin + 1.0);
    let ymin = finite
        .iter()
        .map(|p| p.rho_m.log10())
        .fold(f64::INFINITY, f64::min)
        .floor();
    let ymax = finite
        .iter()
        .map(|p| p.rho_m.log10())
        .fold(f64::NEG_INFINITY, f64::max)
        .ceil()
        .max(ymin + 1.0);
    let px = |x: f64| left + (x - xmin) / (xmax - xmin) * pw;
    let py = |y: f64| top + (ymax - y) / (ymax - ymin) * ph;
    // axes, decade grid and labels
    let _ = writeln!(
        s,
        "<rect x=\"{left}\" y=\"{top}\" width=\"{pw}\" height=\"{ph}\" fill=\"none\" stroke=\"black\"/>"
    );
    let mut d = ymin;
    while d <= ymax + 1e-9 {
        let y = py(d);
        let _ = writeln!(
            s,
            "<line x1=\"{left}\" y1=\"{y:.1}\" x2=\"{:.1}\" y2=\"{y:.1}\" stroke=\"#ddd\"/>",
            left + pw
        );
        let _ = writeln!(
            s,
            "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"end\">1e{}</text>",
            left - 6.0,
            y + 4.0,
            d as i64
        );
        d += 1.0;
    }
    for k in 0..=5 {
        let xv = xmin + (xmax - xmin) * k as f64 / 5.0;
        let _ = writeln!(
            s,
            "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">{:.0}</text>",
            px(xv),
            top + ph + 18.0,
            xv
        );
    }
    let _ = writeln!(
        s,
        "<text x=\"{:.1}\" y=\"{:.1}\" text-anchor=\"middle\">measured nodes</text>",
        left + pw / 2.0,
        h - 10.0
    );
    let _ = writeln!(
        s,
        "<text x=\"16\" y=\"{:.1}\" transform=\"rotate(-90 16 {:.1})\" text-anchor=\"middle\">rho_M (s^-2)</text>",
        top + ph / 2.0,
        top + ph / 2.0
    );
    // one polyline per (method, mode), in first-appearance order
    let colors = [
        "#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf",
    ];
    let mut series: Vec<(String, usize)> = Vec::new();
    for p in &finite {
        if !series.iter().any(|(m, k)| *m == p.method && *k == p.mode) {
            series.push((p.method.clone(), p.mode));
        }
    }
    let mut methods: Vec<&str> = Vec::new();
    for (m, _) in &series {
        if !methods.contains(&m.as_str()) {
            methods.push(m);
        }
    }
    for (i, (method, mode)) in series.iter().enumerate() {
        let mut pts: Vec<(f64, f64)> = finite
            .iter()
            .filter(|p| p.method == *method && p.mode == *mode)
            .map(|p| (px(p.nodes as f64), py(p.rho_m.log10())))
            .collect();
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        // colour by test mode, dash pattern by method
        let color = colors[*mode % colors.len()];
        let method_index = methods.iter().position(|m| m == method).unwrap_or(0);
        let dash = [
            "",
            " stroke-dasharray=\"6 3\"",
            " stroke-dasharray=\"2 3\"",
            " stroke-dasharray=\"8 3 2 3\"",
        ][method_index % 4];
        let coords: Vec<String> = pts.iter().map(|(x, y)| format!("{x:.1},{y:.1}")).collect();
        let _ = writeln!(
            s,
            "<polyline fill=\"none\" stroke=\"{color}\" stroke-width=\"1.5\"{dash} points=\"{}\"/>",
            coords.join(" ")
        );
        for (x, y) in &pts {
            let _ = writeln!(
                s,
                "<circle cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"2.5\" fill=\"{color}\"/>"
            );
        }
        let ly = top + 14.0 * i as f64 + 8.0;
        let _ = writeln!(
            s,
            "<line x1=\"{:.1}\" y1=\"{ly:.1}\" x2=\"{:.1}\" y2=\"{ly:.1}\" stroke=\"{color}\" stroke-width=\"1.5\"{dash}/>",
            left + pw + 10.0,
            left + pw + 34.0
        );
        let _ = writeln!(
            s,
            "<text x=\"{:.1}\" y=\"{:.1}\">mode {} {}</text>",
            left + pw + 40.0,
            ly + 4.0,
            mode + 1,
            method
        );
    }
    s.push_str("</svg>\n");
    s
}
