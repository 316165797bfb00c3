//! SB-EBE: sensitivity-based element-by-element updating (the paper's refs \[4\]-\[5\]; docs/MATH.md,
//! "Updating", formulation (13)-(15)).
//!
//! The objective is `J(theta, x) = sum_i ||(K(p) - lambda_i M(q)) x_i||_W^2` over the test pairs,
//! with `x_i = [x_a; x_o]` holding the measured values `x_a` and `||x_i||_{M_0} = 1`, and
//! `W = diag(M_0)^-1` (the lumped stand-in for `M^-1`, diagonal so the parameter step stays
//! element by element). Each iteration alternates:
//! 1. **expansion** (parameters fixed): `x_o = argmin ||Z x||_W`, the minimum-residual expansion
//!    in the same metric (`Expander::minimum_residual_diagonal`);
//! 2. **correction** (shapes fixed): `R_i` is linear in `theta` with columns `K_g x_i` and
//!    `-lambda_i M_g x_i` (formed element by element, no eigenvector derivative); a bounded,
//!    column-scaled, Tikhonov-regularised least-squares problem gives the new `theta`, with the
//!    total-mass guard against the trivial `p = q = -1`.
//!
//! Both steps minimise the same `J` (the expansion after normalisation, which only rescales each
//! term), so `J` decreases; the iteration stops when it decreases by less than the tolerance.

use crate::UpdateError;
use crate::lsq::{UpdateOptions, bounded_step};
use crate::problem::{UpdateModel, dense_columns, expand_projected};
use faer::Mat;
use femu_correlate::expansion::Expander;
use femu_correlate::{SensorLayout, TestModes};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// One iteration of an updating method.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Iteration {
    /// 0 for the starting model.
    pub iteration: usize,
    /// The objective at `theta` (SB-EBE: `J`; inverse eigensensitivity: the sum of squared
    /// relative eigenvalue errors).
    pub objective: f64,
    /// The parameters the objective was evaluated at.
    pub theta: Vec<f64>,
    /// Wall time of the iteration, s.
    pub seconds: f64,
}

/// The result of an updating run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct UpdateResult {
    /// The updating method.
    pub method: UpdateMethod,
    /// Parameter names, in `theta` order.
    pub names: Vec<String>,
    /// The final parameters (applied to the model).
    pub theta: Vec<f64>,
    /// Every iteration, the starting model first.
    pub history: Vec<Iteration>,
    /// Whether the stopping test was met (otherwise the iteration limit was).
    pub converged: bool,
    /// Why the iteration stopped.
    pub stop_reason: StopReason,
    /// The parameters' uncertainty from the test's (inverse eigensensitivity), when computed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub confidence: Option<Confidence>,
}

/// Linearised confidence of identified parameters: with `J` the Jacobian of the residuals
/// weighted by the test's uncertainty at the solution, `Cov = s^2 (J^T J)^-1` with
/// `s^2 = max(1, chi^2 / (m - p))`: the test's uncertainty, inflated when the residual left is
/// larger than it explains (model-form error).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Confidence {
    /// Half-widths of the 95 % intervals (`1.96 sqrt(Cov_kk)`), `theta` order; infinite for a
    /// parameter the data do not determine.
    pub half_width_95: Vec<f64>,
    /// `chi^2`: the weighted residual left, `sum r_i^2`.
    pub chi_square: f64,
    /// Residual rows `m` (frequencies, and shape readings when fitted).
    pub residuals: usize,
    /// `s^2` applied (1 when the residual left is within the test's uncertainty).
    pub scale: f64,
    /// What the fit's residuals say of the test's uncertainty, when the rows are frequencies and
    /// shapes in units of it: `(frequency, shape)`, relative, the RMS of each block's rows times
    /// the uncertainty they were weighed with (after the fit, which absorbs part of the scatter:
    /// a lower estimate). `None` for SB-EBE.
    #[serde(default)]
    pub implied_uncertainty: Option<(f64, Option<f64>)>,
}

/// An updating method: SB-EBE ([`sb_ebe`]) or inverse eigensensitivity
/// ([`crate::inverse_eigensensitivity`]). Text form `sbebe` or `ies` (command line, study files).
///
/// ```
/// use femu_update::UpdateMethod;
/// assert_eq!("ies".parse::<UpdateMethod>().unwrap(), UpdateMethod::InverseEigensensitivity);
/// assert_eq!(UpdateMethod::SbEbe.to_string(), "SB-EBE");
/// assert!("newton".parse::<UpdateMethod>().is_err());
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum UpdateMethod {
    /// Sensitivity-based element-by-element updating (`docs/MATH.md`, "Updating", (13)-(15)).
    #[serde(rename = "sbebe")]
    SbEbe,
    /// Gauss-Newton (Levenberg-Marquardt) on relative eigenvalue errors.
    #[serde(rename = "ies")]
    InverseEigensensitivity,
}

impl std::fmt::Display for UpdateMethod {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            UpdateMethod::SbEbe => "SB-EBE",
            UpdateMethod::InverseEigensensitivity => "inverse eigensensitivity",
        })
    }
}

impl std::str::FromStr for UpdateMethod {
    type Err = UpdateError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "sbebe" => Ok(UpdateMethod::SbEbe),
            "ies" => Ok(UpdateMethod::InverseEigensensitivity),
            other => Err(UpdateError::Invalid {
                what: "updating method",
                reason: format!("'{other}': expected sbebe or ies"),
            }),
        }
    }
}

/// Why an updating iteration stopped.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum StopReason {
    /// The objective is exactly zero (SB-EBE).
    ZeroResidual,
    /// The eigenvalues match to round-off (inverse eigensensitivity).
    RoundOff,
    /// The objective decreased by less than the tolerance in the last step.
    Stalled,
    /// No step along the correction (halved or damped) decreased the objective; the last trial
    /// model's failure, if trials were rejected by an error.
    NoDescent {
        /// The error that rejected the last trial model.
        last_failure: Option<String>,
    },
    /// The iteration limit was reached.
    IterationLimit(usize),
}

impl std::fmt::Display for StopReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StopReason::ZeroResidual => f.write_str("zero residual"),
            StopReason::RoundOff => f.write_str("eigenvalues matched to round-off"),
            StopReason::Stalled => f.write_str("objective stopped decreasing"),
            StopReason::NoDescent { last_failure: None } => f.write_str(
                "objective stopped decreasing (no step along the correction reduces it)",
            ),
            StopReason::NoDescent {
                last_failure: Some(e),
            } => write!(
                f,
                "objective stopped decreasing (trial models rejected; last failure: {e})"
            ),
            StopReason::IterationLimit(n) => write!(f, "iteration limit {n} reached"),
        }
    }
}

impl std::fmt::Display for UpdateResult {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "{}: {} ({} iterations)",
            self.method,
            self.stop_reason,
            self.history.len().saturating_sub(1)
        )?;
        writeln!(f, "| iteration | objective | {} |", self.names.join(" | "))?;
        writeln!(f, "|---|---|{}", "---|".repeat(self.names.len()))?;
        for it in &self.history {
            let th: Vec<String> = it.theta.iter().map(|v| format!("{v:+.4}")).collect();
            writeln!(
                f,
                "| {} | {:.4e} | {} |",
                it.iteration,
                it.objective,
                th.join(" | ")
            )?;
        }
        let objective = match self.method {
            crate::UpdateMethod::SbEbe => {
                "sum over the tuned modes of ||(K(p) - lambda_i M) x_i||^2 in the diag(M)^-1 norm, \
                 each weighted by 1 / ||x_i||_M^2 of the first expansion (only its decrease matters)"
            }
            crate::UpdateMethod::InverseEigensensitivity => {
                "chi-square: the sum of squared residuals in units of the test's uncertainty \
                 (relative eigenvalue errors over 2 sigma_f, and with shapes the scaled model \
                 readings minus the test's over sigma_s)"
            }
        };
        if let Some(c) = &self.confidence {
            let w: Vec<String> = c
                .half_width_95
                .iter()
                .map(|v| {
                    if v.is_finite() {
                        format!("+-{v:.4}")
                    } else {
                        "not determined".into()
                    }
                })
                .collect();
            writeln!(f, "| 95 % interval | | {} |", w.join(" | "))?;
            writeln!(
                f,
                "\nchi-square {:.3e} over {} residuals; intervals scaled by {:.3}",
                c.chi_square,
                c.residuals,
                c.scale.sqrt()
            )?;
        }
        writeln!(
            f,
            "\nobjective: {objective}; k:G is the relative change of group G's stiffness \
             (-0.20 = 20 % softer), m:G of its mass."
        )?;
        Ok(())
    }
}

/// Settings of SB-EBE.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SbebeOptions {
    /// Iterations, tolerance, regularisation, mass guard.
    pub update: UpdateOptions,
    /// Project the sensitivity columns onto what the expansion cannot absorb (default `true`).
    /// The plain alternation (`false`) treats the expanded shapes as fixed in the correction: each
    /// step is cheap and element by element, but the expansion then absorbs most of the next
    /// correction and convergence is linear and slow (on the plate of the tests, 30 iterations
    /// recover a third of a 30 % stiffness loss). Projected columns `P K_g x_i` make the step a
    /// Gauss-Newton step on the expanded objective (Kaufman's variable projection): a few
    /// iterations, at one extra solve per column and mode with the expansion's factorization,
    /// and a dense `n x parameters` block per mode.
    pub projected: bool,
    /// Trust in the test: `None` (default) imposes the measured values in the expansion; `Some(g)`
    /// expands with test error (`||Z x||_W^2 + gamma ||C x - y||^2`, `gamma = g` times the mean
    /// squared column norm of `Z` at the sensors, see `Expander::test_error_projected`) and adds
    /// `gamma ||C x - y||^2` to the objective. With noisy data, imposing the measurements makes
    /// `K` multiply the noise, and the cheapest way to shrink that residual is to soften
    /// everything; a finite `gamma` lets the expansion discard noise the model cannot follow.
    /// Needs `projected`.
    pub test_error: Option<f64>,
}

impl Default for SbebeOptions {
    fn default() -> Self {
        Self {
            update: UpdateOptions::default(),
            projected: true,
            test_error: None,
        }
    }
}

/// The expanded shapes, residuals and (projected) sensitivities at the current parameters.
struct State {
    x: Mat<f64>,
    /// `Z x_i` per mode
    r: Mat<f64>,
    /// `sqrt(gamma_i) (C x_i - y_i)` per mode (no rows when the measurements are imposed)
    r2: Mat<f64>,
    /// unweighted objective term per mode
    terms: Vec<f64>,
    objective: f64,
    /// projected columns per mode: W-part and sensor part
    projected: Option<Vec<(Mat<f64>, Mat<f64>)>>,
}

/// Runs SB-EBE on `up` (updated in place) from test modes measured on `layout` (every sensor
/// along a global axis). `log` is called after each iteration (progress, logging).
///
/// Each mode's term is weighted by `1 / ||x_i||_{M_0}^2` of the starting model's expansion, so
/// modes count alike whatever the test's scaling and the objective is one fixed function of the
/// parameters; a step that does not decrease it is halved (up to 6 times) before the iteration
/// stops.
///
/// # Errors
/// Oblique sensors, test shapes that do not match the layout, expansion failures (a test
/// eigenvalue on an eigenvalue of the sensor-held structure), bad options, an unidentifiable
/// parameter set without regularisation.
pub fn sb_ebe(
    up: &mut UpdateModel<'_>,
    layout: &SensorLayout,
    test: &TestModes,
    options: &SbebeOptions,
    mut log: impl FnMut(&Iteration),
) -> Result<UpdateResult, UpdateError> {
    options.update.check()?;
    if up.has_thickness_or_mass_groups()
        && !matches!(
            options.update.mass_guard,
            crate::lsq::MassGuard::Measured(_)
        )
    {
        return Err(UpdateError::Invalid {
            what: "SB-EBE parameters",
            reason: "a thickness or a mass group moves stiffness and mass together, and SB-EBE's force residual shrinks with the whole model (its least value is the thinnest, lightest one): SB-EBE takes them only with the structure's measured total mass (MassGuard::Measured); the inverse eigensensitivity method (the default) compares frequencies and shapes and needs no guard".into(),
        });
    }
    if options.test_error.is_some() && !options.projected {
        return Err(UpdateError::Invalid {
            what: "SB-EBE options",
            reason: "expansion with test error needs projected sensitivities".into(),
        });
    }
    let measured = layout.measured_dofs().ok_or(UpdateError::Invalid {
        what: "sensor layout",
        reason: "SB-EBE expands the test shapes: every sensor must lie along a global axis".into(),
    })?;
    if test.shapes.nrows() != measured.len() {
        return Err(UpdateError::Invalid {
            what: "test shapes",
            reason: format!(
                "{} rows for {} sensors",
                test.shapes.nrows(),
                measured.len()
            ),
        });
    }
    let lambdas = test.eigenvalues();
    let m0 = up.nominal().m.clone();
    let n = m0.rows();
    let w_inv = femu_correlate::expansion::residual_metric(&m0)?;
    let w: Vec<f64> = w_inv.iter().map(|v| 1.0 / v).collect();
    // K's pattern does not change with the parameters: one symbolic analysis serves every
    // expansion of every iteration
    let symbolic = up.symbolic()?;
    let evaluate = |up: &UpdateModel<'_>| -> Result<State, UpdateError> {
        let sys = up.matrices();
        let exp = Expander::with_measured_dofs(&sys.k, &sys.m, &measured)?;
        let (x, r2, projected) = if options.projected {
            let e = expand_projected(
                &exp,
                &lambdas,
                test.shapes.as_ref(),
                &w_inv,
                options.test_error,
                Some(&symbolic),
                |j, xj| Ok(dense_columns(&up.columns(xj, lambdas[j])?, n)),
            )?;
            (e.x, e.r2, Some(e.blocks))
        } else {
            let x = exp.minimum_residual_diagonal(&lambdas, test.shapes.as_ref(), &w_inv)?;
            (x, Mat::zeros(0, lambdas.len()), None)
        };
        let r = femu_correlate::residues::force_residuals(&sys.k, &sys.m, &lambdas, x.as_ref())?;
        let terms = (0..lambdas.len())
            .map(|i| {
                (0..n).map(|d| r[(d, i)] * r[(d, i)] * w[d]).sum::<f64>()
                    + r2.col(i).iter().map(|v| v * v).sum::<f64>()
            })
            .collect();
        Ok(State {
            x,
            r,
            r2,
            terms,
            objective: 0.0,
            projected,
        })
    };
    let weighted = |mut s: State, weights: &[f64]| {
        s.objective = s.terms.iter().zip(weights).map(|(t, w)| t * w).sum();
        s
    };
    let t = Instant::now();
    let mut theta = up.theta();
    let np = theta.len();
    let state = evaluate(up)?;
    let weights = mode_weights(&m0, state.x.as_ref())?;
    let mut state = weighted(state, &weights);
    let mut history = vec![Iteration {
        iteration: 0,
        objective: state.objective,
        theta: theta.clone(),
        seconds: t.elapsed().as_secs_f64(),
    }];
    log(&history[0]);
    let (mut converged, mut stop_reason) = (
        false,
        StopReason::IterationLimit(options.update.max_iterations),
    );
    for it in 1..=options.update.max_iterations {
        let t = Instant::now();
        if state.objective == 0.0 {
            converged = true;
            stop_reason = StopReason::ZeroResidual;
            break;
        }
        // correction: min sum_i w_i ||R_i + B_i (theta' - theta)||_W^2
        let mut h = Mat::<f64>::zeros(np, np);
        let mut g = vec![0.0; np];
        for i in 0..lambdas.len() {
            let ri: Vec<f64> = state.r.col(i).iter().copied().collect();
            match &state.projected {
                Some(b) => {
                    let (b1, b2) = &b[i];
                    let wb = Mat::from_fn(n, np, |d, k| weights[i] * w[d] * b1[(d, k)]);
                    h += b1.transpose() * &wb;
                    h += b2.transpose() * b2 * weights[i];
                    for k in 0..np {
                        g[k] -= (0..n).map(|d| wb[(d, k)] * ri[d]).sum::<f64>()
                            + weights[i]
                                * (0..b2.nrows())
                                    .map(|s| b2[(s, k)] * state.r2[(s, i)])
                                    .sum::<f64>();
                    }
                }
                None => {
                    let xi: Vec<f64> = state.x.col(i).iter().copied().collect();
                    let cols = up.columns(&xi, lambdas[i])?;
                    let wi: Vec<f64> = w.iter().map(|v| v * weights[i]).collect();
                    accumulate_normal(&cols, &wi, n, &mut h);
                    for (k, c) in cols.iter().enumerate() {
                        g[k] -= c.weighted_dot_full(&ri, &wi);
                    }
                }
            }
        }
        for k in 0..np {
            g[k] += (0..np).map(|l| h[(k, l)] * theta[l]).sum::<f64>();
        }
        let mut trial = bounded_step(up, h, g, &theta, &options.update, true)?;
        let mut accepted = None;
        let mut failure = None;
        for _ in 0..7 {
            up.set_theta(&trial)?;
            // a trial model can put a test eigenvalue on an eigenvalue of the sensor-held
            // structure (singular expansion): a rejected trial, like a worse one
            match evaluate(up).map(|s| weighted(s, &weights)) {
                Ok(s) if s.objective < state.objective => {
                    accepted = Some(s);
                    break;
                }
                Ok(_) => {}
                Err(e) => failure = Some(e),
            }
            for k in 0..np {
                trial[k] = 0.5 * (trial[k] + theta[k]);
            }
        }
        let Some(next) = accepted else {
            up.set_theta(&theta)?;
            converged = true;
            stop_reason = StopReason::NoDescent {
                last_failure: failure.map(|e| e.to_string()),
            };
            break;
        };
        let decrease = state.objective - next.objective;
        let previous = state.objective;
        theta = trial;
        state = next;
        let entry = Iteration {
            iteration: it,
            objective: state.objective,
            theta: theta.clone(),
            seconds: t.elapsed().as_secs_f64(),
        };
        log(&entry);
        history.push(entry);
        if decrease <= options.update.tolerance * previous {
            converged = true;
            stop_reason = StopReason::Stalled;
            break;
        }
    }
    Ok(UpdateResult {
        confidence: None,
        method: UpdateMethod::SbEbe,
        names: up.parameters().iter().map(|p| p.name.clone()).collect(),
        theta,
        history,
        converged,
        stop_reason,
    })
}

/// `H += sum_cols A^T W A` for sparse columns, DOF by DOF: each DOF contributes the outer product
/// of the few columns that touch it (cost `sum_d (columns at d)^2`, not `columns^2`).
pub(crate) fn accumulate_normal(
    cols: &[crate::problem::SparseColumn],
    w: &[f64],
    n: usize,
    h: &mut Mat<f64>,
) {
    let mut start = vec![0usize; n + 1];
    for c in cols {
        for &d in c.dofs.iter() {
            start[d + 1] += 1;
        }
    }
    for d in 0..n {
        start[d + 1] += start[d];
    }
    let mut fill = start.clone();
    let mut entries = vec![(0usize, 0.0f64); start[n]];
    for (k, c) in cols.iter().enumerate() {
        for (&d, &v) in c.dofs.iter().zip(&c.values) {
            entries[fill[d]] = (k, v);
            fill[d] += 1;
        }
    }
    for d in 0..n {
        let at = &entries[start[d]..start[d + 1]];
        for &(k, a) in at {
            for &(l, b) in at {
                h[(k, l)] += a * b * w[d];
            }
        }
    }
}

/// Command-line values `sbebe` and `ies`.
#[cfg(feature = "clap")]
impl clap::ValueEnum for UpdateMethod {
    fn value_variants<'a>() -> &'a [Self] {
        &[UpdateMethod::SbEbe, UpdateMethod::InverseEigensensitivity]
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        use clap::builder::PossibleValue;
        Some(match self {
            UpdateMethod::SbEbe => PossibleValue::new("sbebe").help("SB-EBE (element by element)"),
            UpdateMethod::InverseEigensensitivity => {
                PossibleValue::new("ies").help("inverse eigensensitivity")
            }
        })
    }
}

/// The mode weights `1 / ||x_i||_{M_0}^2` of the starting expansion `x`.
///
/// # Errors
/// A test mode that expands to a zero (or non-finite) vector.
fn mode_weights(
    m0: &femu_sparse::SparseMatrix,
    x: faer::MatRef<'_, f64>,
) -> Result<Vec<f64>, UpdateError> {
    let mx = femu_sparse::csc::sym_mul_mat(m0, x)?;
    let weights: Vec<f64> = (0..x.ncols())
        .map(|j| {
            let s: f64 = (0..x.nrows()).map(|i| x[(i, j)] * mx[(i, j)]).sum();
            if s > 0.0 && s.is_finite() {
                1.0 / s
            } else {
                0.0
            }
        })
        .collect();
    if let Some(j) = weights.iter().position(|v| *v == 0.0) {
        return Err(UpdateError::Invalid {
            what: "test shapes",
            reason: format!("test mode {} expands to a zero vector", j + 1),
        });
    }
    Ok(weights)
}
