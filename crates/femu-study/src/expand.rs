//! The expand workflow: measured shapes expanded to every free DOF by any [`Method`]
//! (`docs/MATH.md`, "Expansion"), their residual norms, and the sensor-removal study over the
//! test's nodes.

use crate::StudyError;
use crate::load::{LoadedModel, LoadedTest};
use crate::removal::{RemovalStudy, removal_over_test};
use faer::{Mat, MatRef};
use femu_correlate::expansion::{Expander, Method, SensorBasis, place_measured};
use femu_correlate::{Estimator, ResidualNorms, SensorLayout};
use femu_fem::assembly::SystemMatrices;
use serde::Serialize;

/// Expands measured shapes `ya` (one row per sensor of `layout`) to every free DOF by `method`.
/// When the sensors cover every free DOF, the readings are placed on their DOFs as they are.
/// SEREP uses `serep_basis`, or the model's lowest `M` modes when none is given.
///
/// # Errors
/// A test of frequencies alone (no reading to expand), sizes, NaN, two sensors too close for expansion ([`SensorBasis::new`]), and the method's
/// errors (a singular expansion).
pub fn expand_shapes(
    sys: &SystemMatrices,
    layout: &SensorLayout,
    lambdas: &[f64],
    ya: MatRef<'_, f64>,
    method: Method,
    serep_basis: Option<MatRef<'_, f64>>,
) -> Result<Mat<f64>, StudyError> {
    if ya.nrows() == 0 {
        return Err(StudyError::invalid(
            "test",
            "the test gives frequencies without mode shapes: expansion, the estimators and the sensor-removal study read the shapes at the sensors (correlation pairs by frequency, and updating fits the frequencies)",
        ));
    }
    // SEREP without a basis given: the model's lowest M modes, solved here (by femu's own
    // eigensolver, Sturm-verified); every front end's `serep:M` comes this way
    let solved;
    let serep_basis = match (method, serep_basis) {
        (Method::Serep(m), None) => {
            let modes = sys.modes(
                femu_sparse::eigen::Which::Lowest(m.min(sys.k.rows())),
                &femu_sparse::eigen::EigenOptions::default(),
            )?;
            solved = modes.vectors;
            Some(solved.as_ref())
        }
        (_, b) => b,
    };
    Ok(match layout.measured_dofs() {
        Some(dofs) if dofs.len() == sys.dofs.free_count() => {
            place_measured(sys.k.rows(), &dofs, ya)?
        }
        Some(_) => {
            Expander::new(&sys.k, &sys.m, layout)?.expand(method, lambdas, ya, serep_basis)?
        }
        // oblique sensors and sensors between nodes: expansion in the coordinates where every
        // reading is a DOF
        None => {
            SensorBasis::new(&sys.k, &sys.m, layout)?.expand(method, lambdas, ya, serep_basis)?
        }
    })
}

/// `rho_M` and `rho_2` of expanded test shapes, and the removal study when asked for.
#[derive(Debug, Clone, Serialize)]
pub struct ExpansionReport {
    /// The method.
    pub method: Method,
    /// Per test mode: `rho_M`, `rho_2`, the Rayleigh quotient (`docs/MATH.md`, (25)).
    pub norms: Vec<ResidualNorms>,
    /// The sensor-removal study.
    pub study: Option<RemovalStudy>,
}

/// Expands the test shapes by `method` and evaluates the residual norms; with `study`, runs the
/// sensor-removal study over the test's nodes (EfI order on the expanded shapes, down to 2 nodes).
/// Returns the expanded shapes with the report.
///
/// # Errors
/// As [`expand_shapes`] and [`removal_over_test`].
pub fn expansion_report(
    model: &LoadedModel,
    test: &LoadedTest,
    method: Method,
    study: bool,
) -> Result<(Mat<f64>, ExpansionReport), StudyError> {
    let sys = &model.sys;
    let lambdas = test.data.modes.eigenvalues();
    let x = expand_shapes(
        sys,
        &test.layout,
        &lambdas,
        test.data.modes.shapes.as_ref(),
        method,
        None,
    )?;
    let (norms, _) = Estimator::new(&sys.k, &sys.m)?.residual_norms(&lambdas, x.as_ref())?;
    let study = if study {
        Some(removal_over_test(model, test, x.as_ref())?)
    } else {
        None
    };
    Ok((
        x,
        ExpansionReport {
            method,
            norms,
            study,
        },
    ))
}

/// The VTK field names of expanded test shapes: `test mode J expanded (F Hz)`.
pub fn expanded_names(test: &femu_correlate::TestModes) -> Vec<String> {
    test.frequencies_hz
        .iter()
        .enumerate()
        .map(|(j, f)| format!("test mode {} expanded ({f:.2} Hz)", j + 1))
        .collect()
}
