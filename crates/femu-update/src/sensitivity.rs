//! Inverse eigensensitivity: the classical alternative to SB-EBE (FEMtools, Nastran SOL 200).
//!
//! Levenberg-Marquardt on `sum_i ((lambda_j(i)(theta) - lambda_id,i) / lambda_id,i)^2` over the
//! tuned test modes `i`, each paired (MAC on the sensors, optimal assignment) with a model mode
//! `j(i)` re-computed every iteration, with `d lambda_j / d p_g = phi_j^T K_g phi_j` and
//! `d lambda_j / d q_g = -lambda_j phi_j^T M_g phi_j` (docs/MATH.md, "Updating"; `phi_j` M-normalised).
//! Each eigen solve reuses the symbolic analysis of the nominal `K` (the pattern never changes);
//! every solve is Sturm-checked. Bounds, Tikhonov and the total-mass guard as in SB-EBE.

use crate::UpdateError;
use crate::lsq::{UpdateOptions, bounded_step};
use crate::problem::UpdateModel;
use crate::sbebe::{Iteration, StopReason, UpdateMethod, UpdateResult};
use faer::Mat;
use femu_correlate::correlation::mac_matrix;
use femu_correlate::{ModeSet, PairingOptions, SensorLayout, TestModes, pair_modes};
use femu_sparse::eigen::{EigenOptions, Pencil, Which};
use std::time::Instant;

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
}

impl Default for SensitivityOptions {
    fn default() -> Self {
        Self {
            update: UpdateOptions::default(),
            model_modes: None,
            pairing: PairingOptions::default(),
            damping: 1e-3,
            eigen: EigenOptions::default(),
        }
    }
}

/// The model's modes at the current parameters, paired with the test.
pub(crate) struct Evaluation {
    pub modes: ModeSet,
    /// model mode of each test mode
    pub pair: Vec<usize>,
    /// relative eigenvalue errors
    pub residual: Vec<f64>,
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
    let symbolic = up.symbolic()?;
    let sys = up.matrices();
    let pencil = Pencil::with_symbolic(&sys.k, &sys.m, symbolic)?;
    let modes = pencil.solve(Which::Lowest(count), params)?;
    Ok(ModeSet::from_modes(&modes))
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
    let mac = mac_matrix(test.shapes.as_ref(), at_sensors.as_ref())?;
    let pairing = pair_modes(
        mac.as_ref(),
        &test.frequencies_hz,
        &modes.frequencies_hz(),
        &options.pairing,
    )?;
    let lambdas = test.eigenvalues();
    let mut pair = Vec::with_capacity(test.len());
    let mut residual = Vec::with_capacity(test.len());
    for (t, lam) in lambdas.iter().enumerate() {
        let p = pairing.of_test(t).ok_or(UpdateError::LostPair {
            test: t + 1,
            f_test: test.frequencies_hz[t],
            iteration,
        })?;
        pair.push(p.model);
        residual.push((modes.values[p.model] - lam) / lam);
    }
    Ok(Evaluation {
        modes,
        pair,
        residual,
    })
}

/// Runs inverse eigensensitivity on `up` (updated in place) with the test modes `test` measured
/// on `layout` (used for pairing only). `log` is called after each accepted iteration.
///
/// `docs/MATH.md`, "Updating": inverse eigensensitivity.
///
/// # Errors
/// A tuned test mode that loses its pair, eigensolver errors, bad options.
pub fn inverse_eigensensitivity(
    up: &mut UpdateModel<'_>,
    layout: &SensorLayout,
    test: &TestModes,
    options: &SensitivityOptions,
    mut log: impl FnMut(&Iteration),
) -> Result<UpdateResult, UpdateError> {
    options.update.check()?;
    if !(options.damping > 0.0 && options.damping.is_finite()) {
        return Err(UpdateError::Invalid {
            what: "Levenberg-Marquardt damping",
            reason: format!("{} must be positive", options.damping),
        });
    }
    let lambdas = test.eigenvalues();
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
        // Jacobian rows: d lambda_j / d theta / lambda_id
        let mut jac = Mat::<f64>::zeros(test.len(), np);
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
                    / lambdas[i];
            }
        }
        let jtj = jac.transpose() * &jac;
        let current = cost(&eval);
        let mut accepted = None;
        for _ in 0..12 {
            // min ||r + J (theta' - theta)||^2 + mu sum_k (J^T J)_kk (theta'_k - theta_k)^2
            let mut h = jtj.clone();
            let mut g = vec![0.0; np];
            for k in 0..np {
                let damp = mu * jtj[(k, k)].max(f64::MIN_POSITIVE);
                h[(k, k)] += damp;
                g[k] = (0..np).map(|l| jtj[(k, l)] * theta[l]).sum::<f64>() + damp * theta[k]
                    - (0..test.len())
                        .map(|i| jac[(i, k)] * eval.residual[i])
                        .sum::<f64>();
            }
            let trial = bounded_step(up, h, g, &theta, &options.update)?;
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
    Ok(UpdateResult {
        method: UpdateMethod::InverseEigensensitivity,
        names: up.parameters().iter().map(|p| p.name.clone()).collect(),
        theta,
        history,
        converged,
        stop_reason,
    })
}
