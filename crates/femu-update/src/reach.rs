//! Before updating, what updating can do (the use the paper gives its estimator): for the chosen
//! parameters, the best residual reachable in their span, and the a priori bound that follows on
//! each tuned mode's frequency (`docs/MATH.md`, "What the parameters can reach").
//!
//! The localisation's expanded objective (minimum-residual expansion with projected columns,
//! weights `diag(M)^-1`, shapes at unit M-norm) is quadratic in the stiffness factors to first
//! order; its least-squares minimum over the chosen groups `p*` and the fraction it removes say
//! how much of the residual these parameters can explain. The tuned shapes expanded at `K(p*)`
//! then give `rho_M,i`, and by Theorem 2 the model `K(p*)` has an eigenvalue within `rho_M,i` of
//! `lambda_i`: an interval that stays wide says that no value of these parameters brings the
//! model close to the test, whatever the updating method.

use crate::UpdateError;
use crate::{Localisation, UpdateModel};
use femu_correlate::expansion::expand_shapes;
use femu_correlate::{Estimator, Method, SensorLayout, TestModes};
use serde::Serialize;

/// One tuned mode before and at the best fit.
#[derive(Debug, Clone, Serialize)]
pub struct ReachMode {
    /// Test mode (1-based).
    pub test: usize,
    /// `rho_M` of the expanded shape at the nominal model, s^-2.
    pub rho_before: f64,
    /// `rho_M` at the best fit in the parameters' span, s^-2.
    pub rho_after: f64,
    /// The frequency interval (Hz) that then holds an eigenvalue of the fitted model.
    pub interval_hz: (f64, f64),
}

/// What the chosen parameters can reach.
#[derive(Debug, Clone, Serialize)]
pub struct Reach {
    /// The parameters' names and their least-squares values at the nominal expansion.
    pub parameters: Vec<(String, f64)>,
    /// The fraction of the (weighted) expanded residual the best fit removes, in `[0, 1]`.
    pub explained: f64,
    /// Per tuned mode.
    pub modes: Vec<ReachMode>,
}

impl Reach {
    /// Whether the parameters remove at least a fifth of the residual. Noise and expansion error
    /// keep the fraction well below 1 even for the right parameters (35 % for the demo's r3 at
    /// 0.5 % noise, 99 % without noise); below a fifth, most of the residual lies outside their
    /// span.
    pub fn can_explain(&self) -> bool {
        self.explained >= 0.2
    }
}

impl std::fmt::Display for Reach {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let names: Vec<String> = self
            .parameters
            .iter()
            .map(|(n, v)| format!("{n} {v:+.3}"))
            .collect();
        writeln!(
            f,
            "Before updating: the best fit in the span of {} removes {:.0} % of the expanded residual{}.",
            names.join(", "),
            100.0 * self.explained,
            if self.can_explain() {
                ""
            } else {
                ": most of the residual lies outside these parameters' span (noise, expansion error, or an error they cannot represent)"
            }
        )?;
        writeln!(
            f,
            "\n| test | rho_M nominal (s^-2) | rho_M best fit (s^-2) | an eigenvalue of the fitted model lies in (Hz) |\n|---|---|---|---|"
        )?;
        for m in &self.modes {
            writeln!(
                f,
                "| {} | {:.3e} | {:.3e} | {:.1} .. {:.1} |",
                m.test, m.rho_before, m.rho_after, m.interval_hz.0, m.interval_hz.1
            )?;
        }
        writeln!(
            f,
            "\nrho_M = ||(K - lambda M) x||_M^-1 / ||x||_M of the shapes expanded (minimum residual) at the nominal and at the fitted model (Theorem 2); the fit is the first least-squares step of the localisation's expanded objective."
        )
    }
}

/// The reach of the stiffness factors of `chosen` (a model on the chosen sets, at zero), whose
/// groups are `groups` in `localisation` (the candidates' localisation, with its normal
/// equations): the least-squares factors of the localisation's expanded objective (clamped to
/// the bounds), and the rigorous `rho_M` of the tuned shapes expanded (minimum residual) at the
/// nominal and at the fitted model.
///
/// # Errors
/// A localisation without normal equations, expansion and estimator errors.
pub fn reach(
    localisation: &Localisation,
    groups: &[usize],
    chosen: &mut UpdateModel<'_>,
    layout: &SensorLayout,
    tuned: &TestModes,
) -> Result<Reach, UpdateError> {
    let (theta, explained) = localisation.joint_fit(groups).ok_or_else(|| {
        UpdateError::Invalid {
            what: "reach",
            reason: "the localisation has no normal equations (it was not computed from expanded shapes)".into(),
        }
    })?;
    let theta: Vec<f64> = chosen
        .parameters()
        .iter()
        .zip(&theta)
        .map(|(p, v)| v.clamp(p.lower, p.upper))
        .collect();
    let lambdas = tuned.eigenvalues();
    let rho = |up: &UpdateModel<'_>| -> Result<Vec<f64>, UpdateError> {
        let sys = up.matrices();
        let x = expand_shapes(
            sys,
            layout,
            &lambdas,
            tuned.shapes.as_ref(),
            Method::MinimumResidual,
            None,
        )?;
        let (norms, _) = Estimator::new(&sys.k, &sys.m)?.residual_norms(&lambdas, x.as_ref())?;
        Ok(norms.iter().map(|n| n.rho_m).collect())
    };
    let start = chosen.theta();
    let before = rho(chosen)?;
    chosen.set_theta(&theta)?;
    let after = rho(chosen);
    chosen.set_theta(&start)?;
    let after = after?;
    let hz = |l: f64| l.max(0.0).sqrt() / (2.0 * std::f64::consts::PI);
    let modes = (0..lambdas.len())
        .map(|i| ReachMode {
            test: i + 1,
            rho_before: before[i],
            rho_after: after[i],
            interval_hz: (hz(lambdas[i] - after[i]), hz(lambdas[i] + after[i])),
        })
        .collect();
    let names = chosen
        .parameters()
        .iter()
        .zip(&theta)
        .map(|(p, v)| (p.name.clone(), *v))
        .collect();
    Ok(Reach {
        parameters: names,
        explained,
        modes,
    })
}
