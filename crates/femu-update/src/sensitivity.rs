//! Inverse eigensensitivity: the classical alternative to SB-EBE (FEMtools, Nastran SOL 200).
//!
//! Levenberg-Marquardt on the tuned test modes `i`, each paired (MAC on the sensors, optimal
//! assignment) with a model mode `j(i)` re-computed every iteration (`docs/MATH.md`, "Updating"):
//! - frequencies: `(lambda_j(i)(theta) - lambda_id,i) / (2 sigma_f lambda_id,i)`, with
//!   `d lambda_j / d p_g = phi_j^T K_g phi_j` and `d lambda_j / d q_g = -lambda_j phi_j^T M_g phi_j`;
//! - optionally shapes: at each sensor, `(MSF a - y / max|y|) / sigma_s` with `a = C phi_j` and the
//!   modal scale factor `MSF`, differentiated through the eigenvector derivatives of Nelson's method
//!   ([`crate::derivatives`]). Frequencies alone cannot tell a correction from a compensation with
//!   the same eigenvalues; the shapes can.
//!
//! `sigma_f`, `sigma_s` are the test's uncertainty ([`TestUncertainty`]): the residuals are in its
//! units, the objective is a chi-square, and the identified parameters get linearised 95 %
//! intervals ([`Confidence`]). Each eigen solve reuses the symbolic analysis of the nominal `K`;
//! every solve is Sturm-checked. Bounds, Tikhonov and the total-mass guard as in SB-EBE.

use crate::UpdateError;
use crate::derivatives::eigenpair_derivatives;
use crate::lsq::{UpdateOptions, bounded_step};
use crate::problem::UpdateModel;
use crate::sbebe::{Confidence, Iteration, StopReason, UpdateMethod, UpdateResult};
use faer::Mat;
use femu_correlate::correlation::mac_matrix;
use femu_correlate::{
    ModeSet, PairingOptions, SensorLayout, TestModes, pair_by_frequency, pair_modes,
};
use femu_sparse::eigen::{EigenOptions, Pencil, Which};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// The test's uncertainty, one standard deviation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TestUncertainty {
    /// Of a frequency, relative (default 0.001: 0.1 %).
    pub frequency: f64,
    /// Of a shape reading, relative to the mode's largest reading (default 0.01: 1 %).
    pub shape: f64,
    /// Whether the user gave these values (`false`: femu's defaults, said so in reports).
    pub given: bool,
}

impl Default for TestUncertainty {
    fn default() -> Self {
        Self {
            frequency: 1e-3,
            shape: 1e-2,
            given: false,
        }
    }
}

impl TestUncertainty {
    /// From percentages given by a user (each optional: the default where absent; `given` when
    /// either is).
    ///
    /// # Errors
    /// A value that is not a positive percentage.
    pub fn from_percent(frequency: Option<f64>, shape: Option<f64>) -> Result<Self, UpdateError> {
        let d = Self::default();
        let u = Self {
            frequency: frequency.map_or(d.frequency, |p| p / 100.0),
            shape: shape.map_or(d.shape, |p| p / 100.0),
            given: frequency.is_some() || shape.is_some(),
        };
        u.check()?;
        Ok(u)
    }

    /// Checks that both are positive and finite.
    ///
    /// # Errors
    /// [`UpdateError::Invalid`] naming the bad value.
    pub fn check(&self) -> Result<(), UpdateError> {
        for (what, v) in [
            ("frequency uncertainty", self.frequency),
            ("shape uncertainty", self.shape),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(UpdateError::Invalid {
                    what,
                    reason: format!("{v} must be a positive fraction"),
                });
            }
        }
        Ok(())
    }
}

/// Settings of inverse eigensensitivity.
#[derive(Debug, Clone, PartialEq)]
pub struct SensitivityOptions {
    /// Iterations, tolerance, regularisation, mass guard.
    pub update: UpdateOptions,
    /// Model modes computed each iteration (`Lowest(count)`; default: tuned test modes + 10,
    /// enough for six rigid-body modes and the neighbours of the tuned ones).
    pub model_modes: Option<usize>,
    /// Pairing of test and model modes.
    pub pairing: PairingOptions,
    /// Initial Levenberg-Marquardt damping, relative to the diagonal of `J^T J` (default 1e-3).
    pub damping: f64,
    /// Eigensolver settings.
    pub eigen: EigenOptions,
    /// Fit the shapes at the sensors as well as the frequencies (default false).
    pub shapes: bool,
    /// The test's uncertainty (weights and confidence intervals).
    pub uncertainty: TestUncertainty,
}

impl Default for SensitivityOptions {
    fn default() -> Self {
        Self {
            update: UpdateOptions::default(),
            model_modes: None,
            pairing: PairingOptions::default(),
            damping: 1e-3,
            eigen: EigenOptions::default(),
            shapes: false,
            uncertainty: TestUncertainty::default(),
        }
    }
}

/// The model's modes at the current parameters, paired with the test.
pub(crate) struct Evaluation {
    pub modes: ModeSet,
    /// model mode of each test mode
    pub pair: Vec<usize>,
    /// weighted residuals: one frequency row per test mode, then (with shapes) the readings of
    /// each test mode in turn
    pub residual: Vec<f64>,
    /// per test mode: the model's readings `a` and the modal scale factor (with shapes)
    readings: Vec<(Vec<f64>, f64)>,
}

/// Model modes of `up` at its current parameters (reusing the symbolic analysis).
///
/// # Errors
/// Eigensolver errors.
pub fn model_modes(
    up: &mut UpdateModel<'_>,
    count: usize,
    params: &EigenOptions,
) -> Result<ModeSet, UpdateError> {
    if let femu_sparse::slepc::Engine::Slepc(opts) = &params.engine {
        // another engine: its own factorization, the same checked modes
        let sys = up.matrices();
        let modes = femu_sparse::slepc::solve(&sys.k, &sys.m, Which::Lowest(count), params, opts)?;
        return Ok(ModeSet::from_modes(&modes));
    }
    let symbolic = up.symbolic()?;
    let sys = up.matrices();
    let pencil = Pencil::with_symbolic(&sys.k, &sys.m, symbolic)?;
    // the last solve's shift, unless the caller gave one (docs/SCALING.md, "A hinted shift")
    // and the model's rigid-body motions as its null-space hint
    let hinted = EigenOptions {
        lowest_shift_hint: params.lowest_shift_hint.or(up.last_shift()),
        ..sys.eigen_options(params)
    };
    let modes = pencil.solve(Which::Lowest(count), &hinted)?;
    up.set_last_shift(modes.shift);
    Ok(ModeSet::from_modes(&modes))
}

/// `y / max|y|` of each test mode.
fn normalised_test(test: &TestModes) -> Vec<Vec<f64>> {
    (0..test.len())
        .map(|i| {
            let y: Vec<f64> = test.shapes.col(i).iter().copied().collect();
            let peak = y
                .iter()
                .fold(0.0_f64, |a, v| a.max(v.abs()))
                .max(f64::MIN_POSITIVE);
            y.iter().map(|v| v / peak).collect()
        })
        .collect()
}

pub(crate) fn evaluate(
    up: &mut UpdateModel<'_>,
    layout: &SensorLayout,
    test: &TestModes,
    options: &SensitivityOptions,
    iteration: usize,
) -> Result<Evaluation, UpdateError> {
    let count = options.model_modes.unwrap_or(test.len() + 10);
    let modes = model_modes(up, count, &options.eigen)?;
    let at_sensors = layout.measure_all(modes.shapes.as_ref())?;
    // a test of frequencies alone is paired by frequency
    let pairing = if test.has_shapes() {
        let mac = mac_matrix(test.shapes.as_ref(), at_sensors.as_ref())?;
        pair_modes(
            mac.as_ref(),
            &test.frequencies_hz,
            &modes.frequencies_hz(),
            &options.pairing,
        )?
    } else {
        pair_by_frequency(
            &test.frequencies_hz,
            &modes.frequencies_hz(),
            &options.pairing,
        )?
    };
    let lambdas = test.eigenvalues();
    let sf = 2.0 * options.uncertainty.frequency;
    let mut pair = Vec::with_capacity(test.len());
    let mut residual = Vec::with_capacity(test.len());
    for (t, lam) in lambdas.iter().enumerate() {
        let p = pairing.of_test(t).ok_or(UpdateError::LostPair {
            test: t + 1,
            f_test: test.frequencies_hz[t],
            iteration,
        })?;
        pair.push(p.model);
        residual.push((modes.values[p.model] - lam) / lam / sf);
    }
    let mut readings = Vec::new();
    if options.shapes {
        let targets = normalised_test(test);
        for (t, &j) in pair.iter().enumerate() {
            let a: Vec<f64> = at_sensors.col(j).iter().copied().collect();
            let aa: f64 = a.iter().map(|v| v * v).sum::<f64>().max(f64::MIN_POSITIVE);
            let msf = a.iter().zip(&targets[t]).map(|(x, y)| x * y).sum::<f64>() / aa;
            residual.extend(
                a.iter()
                    .zip(&targets[t])
                    .map(|(x, y)| (msf * x - y) / options.uncertainty.shape),
            );
            readings.push((a, msf));
        }
    }
    Ok(Evaluation {
        modes,
        pair,
        residual,
        readings,
    })
}

/// The Jacobian of the weighted residuals with respect to `theta` at `eval`.
pub(crate) fn jacobian(
    up: &mut UpdateModel<'_>,
    layout: &SensorLayout,
    test: &TestModes,
    options: &SensitivityOptions,
    eval: &Evaluation,
) -> Result<Mat<f64>, UpdateError> {
    let lambdas = test.eigenvalues();
    let np = up.parameters().len();
    let sf = 2.0 * options.uncertainty.frequency;
    let mut jac = Mat::<f64>::zeros(eval.residual.len(), np);
    if !options.shapes {
        for (i, &j) in eval.pair.iter().enumerate() {
            let phi: Vec<f64> = eval.modes.shapes.col(j).iter().copied().collect();
            let cols = up.columns(&phi, eval.modes.values[j])?;
            for (k, c) in cols.iter().enumerate() {
                jac[(i, k)] = c
                    .dofs
                    .iter()
                    .zip(&c.values)
                    .map(|(&d, v)| v * phi[d])
                    .sum::<f64>()
                    / lambdas[i]
                    / sf;
            }
        }
        return Ok(jac);
    }
    let symbolic = up.symbolic()?;
    let sys = up.matrices().clone();
    let pencil = Pencil::with_symbolic(&sys.k, &sys.m, symbolic)?;
    let targets = normalised_test(test);
    let ns = layout.len();
    for (i, &j) in eval.pair.iter().enumerate() {
        let phi: Vec<f64> = eval.modes.shapes.col(j).iter().copied().collect();
        let d = eigenpair_derivatives(up, &pencil, &phi, eval.modes.values[j])?;
        let (a, msf) = &eval.readings[i];
        let aa: f64 = a.iter().map(|v| v * v).sum::<f64>().max(f64::MIN_POSITIVE);
        for k in 0..np {
            jac[(i, k)] = d.values[k] / lambdas[i] / sf;
            let da = layout.measure(&d.vectors[k])?;
            let da_y: f64 = da.iter().zip(&targets[i]).map(|(x, y)| x * y).sum();
            let a_da: f64 = a.iter().zip(&da).map(|(x, y)| x * y).sum();
            let dmsf = (da_y - 2.0 * msf * a_da) / aa;
            for s in 0..ns {
                let row = test.len() + i * ns + s;
                jac[(row, k)] = (msf * da[s] + a[s] * dmsf) / options.uncertainty.shape;
            }
        }
    }
    Ok(jac)
}

/// `Cov = s^2 (J^T J)^-1`: the 95 % half-widths (infinite for a parameter the data do not
/// determine).
fn confidence(jac: &Mat<f64>, residual: &[f64]) -> Confidence {
    let (m, p) = (jac.nrows(), jac.ncols());
    let chi: f64 = residual.iter().map(|r| r * r).sum();
    let scale = if m > p {
        (chi / (m - p) as f64).max(1.0)
    } else {
        f64::INFINITY
    };
    let jtj = jac.transpose() * jac;
    // a parameter along a null direction of J^T J is not determined: an infinite interval
    let half_width_95 = match crate::lsq::symmetric_pseudo_inverse(jtj.as_ref()) {
        Ok((inverse, undetermined)) => (0..p)
            .map(|k| {
                let var = inverse[(k, k)];
                if undetermined[k] || !(var.is_finite() && var >= 0.0) {
                    f64::INFINITY
                } else {
                    1.96 * (scale * var).sqrt()
                }
            })
            .collect(),
        Err(_) => vec![f64::INFINITY; p],
    };
    Confidence {
        half_width_95,
        chi_square: chi,
        residuals: m,
        scale,
        implied_uncertainty: None,
    }
}

/// Runs inverse eigensensitivity on `up` (updated in place) with the test modes `test` measured
/// on `layout` (pairing, and the shape residuals when asked for). `log` is called after each
/// accepted iteration.
///
/// `docs/MATH.md`, "Updating": inverse eigensensitivity.
///
/// # Errors
/// A tuned test mode that loses its pair, eigensolver errors (a repeated eigenvalue among the
/// paired modes when shapes are fitted), bad options.
pub fn inverse_eigensensitivity(
    up: &mut UpdateModel<'_>,
    layout: &SensorLayout,
    test: &TestModes,
    options: &SensitivityOptions,
    mut log: impl FnMut(&Iteration),
) -> Result<UpdateResult, UpdateError> {
    options.update.check()?;
    options.uncertainty.check()?;
    if options.shapes && !test.has_shapes() {
        return Err(UpdateError::Invalid {
            what: "inverse eigensensitivity options",
            reason: "shapes are to be fitted, but the test gives frequencies alone".into(),
        });
    }
    if !(options.damping > 0.0 && options.damping.is_finite()) {
        return Err(UpdateError::Invalid {
            what: "Levenberg-Marquardt damping",
            reason: format!("{} must be positive", options.damping),
        });
    }
    let mut theta = up.theta();
    let np = theta.len();
    let t = Instant::now();
    let mut eval = evaluate(up, layout, test, options, 0)?;
    let cost = |e: &Evaluation| e.residual.iter().map(|r| r * r).sum::<f64>();
    let mut history = vec![Iteration {
        iteration: 0,
        objective: cost(&eval),
        theta: theta.clone(),
        seconds: t.elapsed().as_secs_f64(),
    }];
    log(&history[0]);
    let mut mu = options.damping;
    let (mut converged, mut stop_reason) = (
        false,
        StopReason::IterationLimit(options.update.max_iterations),
    );
    for it in 1..=options.update.max_iterations {
        let t = Instant::now();
        if cost(&eval) < 1e-28 {
            converged = true;
            stop_reason = StopReason::RoundOff;
            break;
        }
        let jac = jacobian(up, layout, test, options, &eval)?;
        let jtj = jac.transpose() * &jac;
        let current = cost(&eval);
        let rows = eval.residual.len();
        let mut accepted = None;
        for _ in 0..12 {
            // min ||r + J (theta' - theta)||^2 + mu sum_k (J^T J)_kk (theta'_k - theta_k)^2
            let mut h = jtj.clone();
            let mut g = vec![0.0; np];
            for k in 0..np {
                let damp = mu * jtj[(k, k)].max(f64::MIN_POSITIVE);
                h[(k, k)] += damp;
                g[k] = (0..np).map(|l| jtj[(k, l)] * theta[l]).sum::<f64>() + damp * theta[k]
                    - (0..rows)
                        .map(|i| jac[(i, k)] * eval.residual[i])
                        .sum::<f64>();
            }
            let trial = bounded_step(up, h, g, &theta, &options.update, false)?;
            up.set_theta(&trial)?;
            let e = evaluate(up, layout, test, options, it)?;
            if cost(&e) < current {
                accepted = Some((trial, e));
                mu = (mu / 3.0).max(1e-12);
                break;
            }
            mu *= 4.0;
        }
        let Some((trial, e)) = accepted else {
            up.set_theta(&theta)?;
            converged = true;
            stop_reason = StopReason::NoDescent { last_failure: None };
            break;
        };
        let decrease = current - cost(&e);
        theta = trial;
        eval = e;
        let entry = Iteration {
            iteration: it,
            objective: cost(&eval),
            theta: theta.clone(),
            seconds: t.elapsed().as_secs_f64(),
        };
        log(&entry);
        history.push(entry);
        if decrease <= options.update.tolerance * current {
            converged = true;
            stop_reason = StopReason::Stalled;
            break;
        }
    }
    let jac = jacobian(up, layout, test, options, &eval)?;
    let mut confidence = confidence(&jac, &eval.residual);
    // each block's RMS in units of its uncertainty, back in relative terms
    let rms = |r: &[f64]| (r.iter().map(|v| v * v).sum::<f64>() / r.len().max(1) as f64).sqrt();
    let nt = test.len().min(eval.residual.len());
    confidence.implied_uncertainty = Some((
        rms(&eval.residual[..nt]) * options.uncertainty.frequency,
        (eval.residual.len() > nt).then(|| rms(&eval.residual[nt..]) * options.uncertainty.shape),
    ));
    Ok(UpdateResult {
        method: UpdateMethod::InverseEigensensitivity,
        names: up.parameters().iter().map(|p| p.name.clone()).collect(),
        theta,
        history,
        converged,
        stop_reason,
        confidence: Some(confidence),
    })
}
