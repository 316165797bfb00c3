//! The expand workflow: measured shapes expanded to every free DOF by any [`Method`]
//! (`docs/MATH.md`, "Expansion"), their residual norms, and the sensor-removal study over the
//! test's nodes.

use crate::StudyError;
use crate::load::{LoadedModel, LoadedTest};
use crate::removal::{RemovalStudy, removal_over_test};
use faer::Mat;
use femu_correlate::expansion::Method;
pub use femu_correlate::expansion::expand_shapes;
use femu_correlate::{Estimator, ResidualNorms};
use serde::Serialize;

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
