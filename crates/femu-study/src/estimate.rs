//! The estimate workflow: test shapes expanded to every DOF ([`crate::expand`]), the model's lowest modes paired with
//! the test, and for each test mode the residual norms `rho_M` and `rho_2`, the frequency interval
//! that must hold a model frequency, and every bound of `docs/MATH.md` ("Estimators", Theorems
//! 1-4 of the paper, (26)-(29)) with what it bounds. The paper's Table 2 is its summary.

use crate::StudyError;
use crate::load::{LoadedModel, LoadedTest};
use crate::modes::lowest_for_test;
use faer::{Mat, MatRef};
use femu_correlate::expansion::Method;
use femu_correlate::expansion::expand_shapes;
use femu_correlate::{
    Assessment, BoundKind, CorrelationReport, Form, ModeSet, ModelSpectrum, PairingOptions,
    SensorLayout, TestModes, correlate, element_bounds, estimate,
};
use femu_fem::assembly::SystemMatrices;
use femu_fem::model::Model;
use femu_sparse::eigen::EigenOptions;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;

/// Settings of the estimate workflow ([`estimate_loaded`], [`expand_and_estimate`]): one
/// definition, and one set of defaults, for `femu estimate`, study files, the demo and Python.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EstimateOptions {
    /// How the measured shapes are expanded (default dynamic).
    pub expansion: Method,
    /// Pairing of test and model modes.
    pub pairing: PairingOptions,
    /// Model modes solved for the comparison by [`estimate_loaded`] (default: twice the test
    /// modes plus 4, at most the model's DOFs).
    #[serde(default)]
    pub count: Option<usize>,
    /// The eigensolver of the model's modes.
    #[serde(skip)]
    pub eigen: EigenOptions,
}

impl Default for EstimateOptions {
    fn default() -> Self {
        Self {
            expansion: Method::Dynamic,
            pairing: PairingOptions::default(),
            count: None,
            eigen: EigenOptions::default(),
        }
    }
}

/// What [`estimate_loaded`] computed: the model's modes, the expanded test shapes (full length,
/// one column per test mode) and the estimate.
#[derive(Debug, Clone)]
pub struct EstimateRun {
    /// The model's lowest modes, with their Sturm proof.
    pub modes: ModeSet,
    /// The test shapes expanded by [`EstimateOptions::expansion`].
    pub expanded: Mat<f64>,
    /// Tables 1 and 2 and every bound.
    pub result: EstimateResult,
}

/// The estimate workflow on a loaded model and test: the model's lowest modes
/// ([`EstimateOptions::count`], solved with [`EstimateOptions::eigen`]), then
/// [`expand_and_estimate`]. `progress` receives one line per step.
///
/// # Errors
/// The eigensolver's, the expansion's and the estimators' errors.
pub fn estimate_loaded(
    model: &LoadedModel,
    test: &LoadedTest,
    options: &EstimateOptions,
    mut progress: impl FnMut(&str),
) -> Result<EstimateRun, StudyError> {
    let n_test = test.data.modes.len();
    progress(&format!(
        "solving for the model's modes ({} DOF)",
        model.sys.k.rows()
    ));
    let modes = crate::modes::mode_set(
        model,
        &lowest_for_test(model, options.count, n_test, &options.eigen)?,
        options.pairing.damped,
    )?;
    progress(&format!(
        "expanding {n_test} test modes ({}) and estimating",
        options.expansion
    ));
    let (expanded, result) = expand_and_estimate(
        &model.model,
        &model.sys,
        &test.layout,
        &test.data.modes,
        &modes,
        options,
    )?;
    Ok(EstimateRun {
        modes,
        expanded,
        result,
    })
}

/// The test shapes expanded to every DOF by [`EstimateOptions::expansion`]
/// ([`crate::expand::expand_shapes`]) and assessed against the model modes `modes` by
/// [`estimate_with_bounds`]: the pipeline every front end runs. Returns the expanded shapes with
/// the estimate.
///
/// # Errors
/// As [`expand_shapes`] and [`estimate_with_bounds`].
pub fn expand_and_estimate(
    model: &Model,
    sys: &SystemMatrices,
    layout: &SensorLayout,
    test: &TestModes,
    modes: &ModeSet,
    options: &EstimateOptions,
) -> Result<(Mat<f64>, EstimateResult), StudyError> {
    let x = expand_shapes(
        sys,
        layout,
        &test.eigenvalues(),
        test.shapes.as_ref(),
        options.expansion,
        None,
    )?;
    let result = estimate_with_bounds(model, sys, layout, test, modes, x.as_ref(), options)?;
    Ok((x, result))
}

/// One row of the paper's Table 2 for one test mode.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EstimateRow {
    /// Test mode (1-based).
    pub test: usize,
    /// Smallest gap `min_j |lambda_id - lambda_j|` over the computed spectrum, s^-2. Exact when
    /// the test eigenvalue lies below the top computed eigenvalue by at least this gap (the
    /// uncomputed ones lie above the top); otherwise an upper bound, since an uncomputed
    /// eigenvalue may be nearer.
    pub min_gap: f64,
    /// Gap to the paired model mode, s^-2.
    pub paired_gap: Option<f64>,
    /// `rho_M = ||R_F||_{M^-1} / ||x||_M`, s^-2 (the rigorous ratio).
    pub rho_m: f64,
    /// `rho_2 = ||R_F||_2 / ||x||_2` (the paper's ratio; units of `K` when `M` has mass).
    pub rho_2: f64,
    /// Whether Theorem 2 holds in the paper's form (`min gap <= rho_2`).
    pub t2_paper_holds: bool,
    /// Whether it holds in the rigorous form (a theorem: always, to round-off).
    pub t2_rigorous_holds: bool,
    /// The frequency interval (Hz) Theorem 2 guarantees holds a model frequency.
    pub interval_hz: (f64, f64),
    /// `rho_M / min_gap`: how many times the rigorous bound overestimates the distance to the
    /// nearest model eigenvalue (1 is sharp).
    pub width_over_gap: f64,
    /// Whether the rigorous bound informs: it holds and is at most [`TOO_WIDE`] times the gap.
    /// A bound that holds but is wider says only that the spectrum is not empty near the test
    /// mode, and is labelled so.
    pub informative: bool,
}

/// A bound wider than this many times the distance it bounds is labelled "too wide to inform".
pub const TOO_WIDE: f64 = 10.0;

impl EstimateRow {
    /// The rigorous Theorem 2 verdict as the tables print it: `yes`, `**no**`, or
    /// `yes, 79x the gap: too wide to inform`.
    pub fn rigorous_verdict(&self) -> String {
        match (self.t2_rigorous_holds, self.informative) {
            (false, _) => "**no**".into(),
            (true, true) => format!("yes ({:.1}x the gap)", self.width_over_gap),
            (true, false) => format!(
                "yes, {:.0}x the gap: too wide to inform",
                self.width_over_gap
            ),
        }
    }
}

/// The legend of [`EstimateResult::table2`]: what its columns mean.
pub fn table2_legend() -> String {
    format!(
        "Eigenvalues are lambda = (2 pi f)^2 in s^-2; min gap = distance from the test eigenvalue to the nearest model eigenvalue; `rho_2 = ||R_F||_2 / ||x||_2` is the paper's Euclidean ratio (in the units of K, so a bound only when M = I), `rho_M = ||R_F||_M^-1 / ||x||_M` the mass-weighted one (Theorem 2 is a theorem for it: some model eigenvalue lies within rho_M of the test eigenvalue). A bound more than {TOO_WIDE:.0} times the gap it bounds holds but is too wide to inform."
    )
}

impl EstimateResult {
    /// The paper's Table 2 as a Markdown table ([`table2`]).
    pub fn table2(&self) -> String {
        table2(&self.rows)
    }
}

/// The paper's Table 2 as a Markdown table (header and one row per test mode): the one rendering
/// of every front end (`femu estimate`, `femu run`, the demo's report); [`table2_legend`] says
/// what its columns mean.
pub fn table2(rows: &[EstimateRow]) -> String {
    let mut s = String::from(
        "| test | min gap (s^-2) | paired gap (s^-2) | rho_2 (paper, N/m) | T2 paper holds | rho_M (rigorous, s^-2) | T2 rigorous holds | model frequency within (Hz) |\n|---|---|---|---|---|---|---|---|\n",
    );
    for row in rows {
        let _ = writeln!(
            s,
            "| {} | {:.3e} | {} | {:.3e} | {} | {:.3e} | {} | {:.1} .. {:.1} |",
            row.test,
            row.min_gap,
            row.paired_gap
                .map_or("unpaired".into(), |g| format!("{g:.3e}")),
            row.rho_2,
            if row.t2_paper_holds { "yes" } else { "**no**" },
            row.rho_m,
            row.rigorous_verdict(),
            row.interval_hz.0,
            row.interval_hz.1
        );
    }
    s
}

/// What [`estimate_with_bounds`] found.
#[derive(Debug, Clone, Serialize)]
pub struct EstimateResult {
    /// The expansion used.
    pub expansion: Method,
    /// Pairs, frequency errors and MAC (the paper's Table 1).
    pub correlation: CorrelationReport,
    /// Norms, interval and every bound per test mode.
    pub assessments: Vec<Assessment>,
    /// The paper's Table 2.
    pub rows: Vec<EstimateRow>,
}

/// Correlates `test` with the model modes `modes`, and assesses the expanded test shapes `x`
/// (full length, one column per test mode) against the spectrum: `rho_M`, `rho_2`, Theorems 1-4
/// in both forms with `lambda_max` and `mu_min(M)` bounded element by element, or by inertia for a
/// model without elements ([`femu_correlate::inertia_bounds`]; `docs/MATH.md`, "Estimators").
///
/// # Errors
/// Sizes, NaN, a pairing or estimator error.
pub fn estimate_with_bounds(
    model: &Model,
    sys: &SystemMatrices,
    layout: &SensorLayout,
    test: &TestModes,
    modes: &ModeSet,
    x: MatRef<'_, f64>,
    options: &EstimateOptions,
) -> Result<EstimateResult, StudyError> {
    let correlation = correlate(modes, test, layout, &options.pairing)?;
    let lambdas = test.eigenvalues();
    // element by element for solids; by inertia for a model without them (another solver's
    // matrices) or with beams, rods, springs or bushings, which the element bounds do not cover
    let (lambda_max, mu_min) = if model.mesh().element_count() > 0 && model.structural().is_empty()
    {
        let eb = element_bounds(model, sys.mass_kind)?;
        (eb.lambda_max_upper, Some(eb.mu_min_lower))
    } else {
        femu_correlate::inertia_bounds(&sys.k, &sys.m)?
    };
    // the mode set carries its Sturm proof: which bounds are theorems follows from it
    let spectrum = ModelSpectrum {
        values: modes.values.clone(),
        proof: modes.proof,
        lambda_max,
        mu_min,
    };
    let paired: Vec<Option<usize>> = (0..test.len())
        .map(|t| correlation.pairing.of_test(t).map(|p| p.model))
        .collect();
    let assessments = estimate(&sys.k, &sys.m, &lambdas, x, &spectrum, Some(modes), &paired)?;
    let top = *modes
        .values
        .last()
        .ok_or_else(|| StudyError::invalid("model modes", "none computed"))?;
    let rows = assessments
        .iter()
        .enumerate()
        .map(|(t, a)| {
            let lam = lambdas[t];
            let min_gap = modes
                .values
                .iter()
                .map(|l| (lam - l).abs())
                .fold(f64::INFINITY, f64::min)
                .min((top - lam).abs());
            let t2 = |form: Form| {
                a.bounds
                    .iter()
                    .find(|b| b.kind == BoundKind::T2 && b.form == form)
                    .and_then(|b| b.holds())
            };
            EstimateRow {
                test: t + 1,
                min_gap,
                paired_gap: correlation.pairing.of_test(t).map(|p| p.eigenvalue_gap),
                rho_m: a.norms.rho_m,
                rho_2: a.norms.rho_2,
                t2_paper_holds: t2(Form::Paper).unwrap_or(min_gap <= a.norms.rho_2),
                t2_rigorous_holds: t2(Form::Rigorous).unwrap_or(min_gap <= a.norms.rho_m),
                interval_hz: a.frequency_interval_hz,
                width_over_gap: a.norms.rho_m / min_gap.max(f64::MIN_POSITIVE),
                informative: t2(Form::Rigorous).unwrap_or(min_gap <= a.norms.rho_m)
                    && a.norms.rho_m <= TOO_WIDE * min_gap,
            }
        })
        .collect();
    Ok(EstimateResult {
        expansion: options.expansion,
        correlation,
        assessments,
        rows,
    })
}
