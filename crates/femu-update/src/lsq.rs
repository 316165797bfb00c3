//! Bound-constrained linear least squares, on the normal equations of a small problem.
//!
//! Both updating methods end each iteration with `min_theta 1/2 theta^T H theta - g^T theta`
//! subject to `lo <= theta <= hi`, where `H` (symmetric positive definite: the normal matrix of the
//! scaled sensitivity columns plus the Tikhonov term) has one row per parameter. The primal
//! active-set method below (as in Lawson and Hanson's BVLS) is exact in finitely many steps:
//! solve on the free variables, step back to the first bound crossed, release a bound whose
//! multiplier has the wrong sign, until the KKT conditions hold.

use crate::UpdateError;
use faer::linalg::solvers::Solve;
use faer::{Mat, MatRef, Side};

/// Solves the box-constrained quadratic program from the feasible start `clamp(start)`.
///
/// # Errors
/// Sizes, `lo > hi`, a non-finite entry, or `H` not positive definite on the free variables.
pub fn box_qp(
    h: MatRef<'_, f64>,
    g: &[f64],
    lo: &[f64],
    hi: &[f64],
    start: &[f64],
) -> Result<Vec<f64>, UpdateError> {
    let n = g.len();
    if h.nrows() != n || h.ncols() != n || lo.len() != n || hi.len() != n || start.len() != n {
        return Err(UpdateError::Invalid {
            what: "bounded least-squares sizes",
            reason: format!(
                "H is {}x{}, {} gradients, {} lower, {} upper, {} start values",
                h.nrows(),
                h.ncols(),
                n,
                lo.len(),
                hi.len(),
                start.len()
            ),
        });
    }
    if let Some(i) = (0..n).find(|&i| !(lo[i] <= hi[i])) {
        return Err(UpdateError::Invalid {
            what: "parameter bounds",
            reason: format!("parameter {i}: lower {} above upper {}", lo[i], hi[i]),
        });
    }
    let finite = g.iter().chain(start).all(|v| v.is_finite())
        && (0..n).all(|j| h.col(j).iter().all(|v| v.is_finite()));
    if !finite {
        return Err(UpdateError::Invalid {
            what: "bounded least-squares data",
            reason: "a normal-matrix, gradient or start entry is not finite".into(),
        });
    }
    #[derive(Clone, Copy, PartialEq)]
    enum State {
        Free,
        Lower,
        Upper,
    }
    let mut theta: Vec<f64> = (0..n).map(|i| start[i].clamp(lo[i], hi[i])).collect();
    let mut state: Vec<State> = (0..n)
        .map(|i| {
            if lo[i] == hi[i] || theta[i] == lo[i] {
                State::Lower
            } else if theta[i] == hi[i] {
                State::Upper
            } else {
                State::Free
            }
        })
        .collect();
    let scale = g.iter().map(|v| v.abs()).fold(0.0, f64::max)
        + (0..n).map(|i| h[(i, i)].abs()).fold(0.0, f64::max);
    let tol = 1e-13 * scale.max(f64::MIN_POSITIVE);
    for _ in 0..(20 * n + 100) {
        let free: Vec<usize> = (0..n).filter(|&i| state[i] == State::Free).collect();
        let z = if free.is_empty() {
            Vec::new()
        } else {
            let hff = Mat::from_fn(free.len(), free.len(), |a, b| h[(free[a], free[b])]);
            let rhs = Mat::from_fn(free.len(), 1, |a, _| {
                let i = free[a];
                g[i] - (0..n)
                    .filter(|&j| state[j] != State::Free)
                    .map(|j| h[(i, j)] * theta[j])
                    .sum::<f64>()
            });
            let llt = hff.llt(Side::Lower).map_err(|_| UpdateError::Invalid {
                what: "normal matrix",
                reason: "not positive definite on the free parameters (parameters not identifiable from the data: add Tikhonov regularisation or fewer groups)".into(),
            })?;
            let sol = llt.solve(&rhs);
            (0..free.len()).map(|a| sol[(a, 0)]).collect()
        };
        let inside = free.iter().zip(&z).all(|(&i, &v)| v >= lo[i] && v <= hi[i]);
        if inside {
            for (&i, &v) in free.iter().zip(&z) {
                theta[i] = v;
            }
            // multipliers of the bound variables: gradient of the objective
            let mut worst = (tol, usize::MAX);
            for i in 0..n {
                if state[i] == State::Free || lo[i] == hi[i] {
                    continue;
                }
                let grad: f64 = (0..n).map(|j| h[(i, j)] * theta[j]).sum::<f64>() - g[i];
                let violation = match state[i] {
                    State::Lower => -grad,
                    State::Upper => grad,
                    State::Free => 0.0,
                };
                if violation > worst.0 {
                    worst = (violation, i);
                }
            }
            if worst.1 == usize::MAX {
                return Ok(theta);
            }
            state[worst.1] = State::Free;
        } else {
            // step towards z, stopping at the first bound crossed
            let mut alpha = 1.0_f64;
            for (&i, &v) in free.iter().zip(&z) {
                let d = v - theta[i];
                if v < lo[i] && d < 0.0 {
                    alpha = alpha.min((lo[i] - theta[i]) / d);
                } else if v > hi[i] && d > 0.0 {
                    alpha = alpha.min((hi[i] - theta[i]) / d);
                }
            }
            let alpha = alpha.max(0.0);
            for (&i, &v) in free.iter().zip(&z) {
                theta[i] += alpha * (v - theta[i]);
                let span = (hi[i] - lo[i]).max(1.0);
                if theta[i] <= lo[i] + 1e-12 * span && v < lo[i] {
                    theta[i] = lo[i];
                    state[i] = State::Lower;
                } else if theta[i] >= hi[i] - 1e-12 * span && v > hi[i] {
                    theta[i] = hi[i];
                    state[i] = State::Upper;
                }
            }
        }
    }
    Err(UpdateError::Invalid {
        what: "bounded least squares",
        reason: "the active-set iteration did not terminate (cycling on a degenerate problem)"
            .into(),
    })
}

/// The pseudo-inverse of a small symmetric positive semi-definite matrix (a normal matrix
/// `J^T J`) by its eigendecomposition (`femu_sparse::dense::symmetric_eigen`), eigenvalues at or
/// below `1e-13` of the largest counted as zero; and, per index, whether it has a component
/// (above 1e-8) along that null space: such a parameter is not determined by the data.
///
/// # Errors
/// The dense eigensolver's non-convergence.
pub(crate) fn symmetric_pseudo_inverse(
    a: MatRef<'_, f64>,
) -> Result<(Mat<f64>, Vec<bool>), UpdateError> {
    let p = a.nrows();
    let (mu, v) = femu_sparse::dense::symmetric_eigen(a)?;
    let tiny = 1e-13 * mu.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let mut inverse = Mat::<f64>::zeros(p, p);
    let mut undetermined = vec![false; p];
    for (j, m) in mu.iter().enumerate() {
        if *m <= tiny {
            for (k, u) in undetermined.iter_mut().enumerate() {
                *u |= v[(k, j)].abs() > 1e-8;
            }
            continue;
        }
        for r in 0..p {
            for c in 0..p {
                inverse[(r, c)] += v[(r, j)] * v[(c, j)] / m;
            }
        }
    }
    Ok((inverse, undetermined))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Objective of the QP.
    fn f(h: &Mat<f64>, g: &[f64], x: &[f64]) -> f64 {
        let n = g.len();
        let mut v = 0.0;
        for i in 0..n {
            for j in 0..n {
                v += 0.5 * x[i] * h[(i, j)] * x[j];
            }
            v -= g[i] * x[i];
        }
        v
    }

    /// Against exhaustive enumeration of the active sets (each variable free, at its lower or at
    /// its upper bound): the optimum is the best feasible stationary point over all 3^n faces.
    #[test]
    fn matches_enumeration_of_faces() {
        let mut seed = 0x1234_5678_u64;
        let mut rnd = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        for case in 0..60 {
            let n = 1 + case % 5;
            let a = Mat::from_fn(n + 2, n, |_, _| rnd());
            let h = a.transpose() * &a + Mat::<f64>::identity(n, n) * 1e-3;
            let g: Vec<f64> = (0..n).map(|_| 2.0 * rnd()).collect();
            let lo: Vec<f64> = (0..n).map(|_| -0.5 + 0.3 * rnd()).collect();
            let hi: Vec<f64> = lo.iter().map(|l| l + 0.2 + 0.5 * rnd().abs()).collect();
            let x = box_qp(h.as_ref(), &g, &lo, &hi, &vec![0.0; n]).unwrap();
            let mut best = f64::INFINITY;
            for code in 0..3usize.pow(n as u32) {
                let mut c = code;
                let st: Vec<usize> = (0..n)
                    .map(|_| {
                        let s = c % 3;
                        c /= 3;
                        s
                    })
                    .collect();
                let free: Vec<usize> = (0..n).filter(|&i| st[i] == 0).collect();
                let mut y: Vec<f64> = (0..n)
                    .map(|i| match st[i] {
                        1 => lo[i],
                        2 => hi[i],
                        _ => 0.0,
                    })
                    .collect();
                if !free.is_empty() {
                    let hff = Mat::from_fn(free.len(), free.len(), |p, q| h[(free[p], free[q])]);
                    let rhs = Mat::from_fn(free.len(), 1, |p, _| {
                        let i = free[p];
                        g[i] - (0..n)
                            .filter(|j| st[*j] != 0)
                            .map(|j| h[(i, j)] * y[j])
                            .sum::<f64>()
                    });
                    let s = hff.llt(Side::Lower).unwrap().solve(&rhs);
                    for (p, &i) in free.iter().enumerate() {
                        y[i] = s[(p, 0)];
                    }
                }
                if (0..n).all(|i| y[i] >= lo[i] - 1e-12 && y[i] <= hi[i] + 1e-12) {
                    best = best.min(f(&h, &g, &y));
                }
            }
            assert!((0..n).all(|i| x[i] >= lo[i] && x[i] <= hi[i]));
            let fx = f(&h, &g, &x);
            assert!(
                (fx - best).abs() <= 1e-10 * (1.0 + best.abs()),
                "case {case}: {fx} vs {best}"
            );
        }
    }

    #[test]
    fn bad_input_is_an_error() {
        let h = Mat::<f64>::identity(2, 2);
        assert!(
            box_qp(
                h.as_ref(),
                &[1.0, 1.0],
                &[1.0, 0.0],
                &[0.0, 1.0],
                &[0.0, 0.0]
            )
            .is_err()
        );
        assert!(
            box_qp(
                h.as_ref(),
                &[f64::NAN, 1.0],
                &[0.0, 0.0],
                &[1.0, 1.0],
                &[0.0, 0.0]
            )
            .is_err()
        );
        let singular = Mat::<f64>::zeros(2, 2);
        let e = box_qp(
            singular.as_ref(),
            &[1.0, 1.0],
            &[-1.0, -1.0],
            &[1.0, 1.0],
            &[0.0, 0.0],
        );
        assert!(matches!(
            e,
            Err(UpdateError::Invalid {
                what: "normal matrix",
                ..
            })
        ));
    }
}

/// How the total mass is held when mass factors are estimated: without a guard, scaling `K` and `M`
/// together (`p = q = -1`) zeroes every residual, the trivial solution of (13)-(15).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub enum MassGuard {
    /// The total mass stays the nominal model's (`sum_g q_g m_g = 0`): mass may move, not appear.
    #[default]
    Fixed,
    /// The structure was weighed: `sum_g q_g m_g = measured - nominal` (kg).
    Measured(f64),
    /// No guard (only sensible with stiffness-only or mass-only corrections).
    Free,
}

/// Settings shared by the updating methods.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct UpdateOptions {
    /// Iterations at most (default 30).
    pub max_iterations: usize,
    /// Stop when the objective decreases by less than this fraction in an iteration (default 1e-6).
    pub tolerance: f64,
    /// Tikhonov weight `alpha` on `||theta||^2`, relative to the mean diagonal of the normal matrix
    /// (default 1e-10). It pulls every parameter towards zero (the nominal model), not towards its
    /// current value: an unidentifiable parameter is kept near zero, and a large weight biases
    /// every estimate towards the nominal model.
    pub tikhonov: f64,
    /// The total-mass guard.
    pub mass_guard: MassGuard,
}

impl Default for UpdateOptions {
    fn default() -> Self {
        Self {
            max_iterations: 30,
            tolerance: 1e-6,
            tikhonov: 1e-10,
            mass_guard: MassGuard::Fixed,
        }
    }
}

impl UpdateOptions {
    /// Checks the settings.
    ///
    /// # Errors
    /// A negative or non-finite tolerance or weight, a non-finite measured mass.
    pub fn check(&self) -> Result<(), UpdateError> {
        let ok = self.tolerance >= 0.0
            && self.tolerance.is_finite()
            && self.tikhonov >= 0.0
            && self.tikhonov.is_finite()
            && match self.mass_guard {
                MassGuard::Measured(m) => m.is_finite() && m > 0.0,
                _ => true,
            };
        if ok {
            Ok(())
        } else {
            Err(UpdateError::Invalid {
                what: "updating options",
                reason: format!(
                    "tolerance {}, tikhonov {}, mass guard {:?}: need finite non-negative values and a positive measured mass",
                    self.tolerance, self.tikhonov, self.mass_guard
                ),
            })
        }
    }
}

/// One bounded, regularised, nondimensionalised least-squares step:
/// `min 1/2 theta^T H theta - g^T theta + alpha/2 mean(diag H) ||theta||^2` subject to the bounds
/// and the mass guard, solved in the variables `D theta` with `D = sqrt(diag H)` so that stiffness
/// and mass columns of very different magnitudes weigh alike. `model_scaling`: the guard holds
/// thickness changes and mass groups too ([`crate::UpdateModel::guard_row`]; SB-EBE).
pub(crate) fn bounded_step(
    up: &crate::problem::UpdateModel<'_>,
    mut h: Mat<f64>,
    mut g: Vec<f64>,
    start: &[f64],
    options: &UpdateOptions,
    model_scaling: bool,
) -> Result<Vec<f64>, UpdateError> {
    let n = g.len();
    let mean_diag = (0..n).map(|i| h[(i, i)]).sum::<f64>() / n as f64;
    if !(mean_diag.is_finite() && mean_diag > 0.0) {
        return Err(UpdateError::Invalid {
            what: "sensitivities",
            reason: "every sensitivity column is zero or not finite (the test modes do not involve the parameter groups)".into(),
        });
    }
    let alpha = options.tikhonov * mean_diag;
    for i in 0..n {
        h[(i, i)] += alpha;
    }
    let c = up.guard_row(model_scaling);
    if c.iter().any(|v| *v != 0.0) {
        let target = match options.mass_guard {
            MassGuard::Fixed => Some(0.0),
            MassGuard::Measured(m) => Some(m - up.nominal_mass()),
            MassGuard::Free => None,
        };
        if let Some(target) = target {
            let cc: f64 = c.iter().map(|v| v * v).sum();
            let omega = 1e6 * mean_diag / cc;
            for i in 0..n {
                for j in 0..n {
                    h[(i, j)] += omega * c[i] * c[j];
                }
                g[i] += omega * c[i] * target;
            }
        }
    }
    let d: Vec<f64> = (0..n)
        .map(|i| {
            let v = h[(i, i)].sqrt();
            if v > 0.0 && v.is_finite() { v } else { 1.0 }
        })
        .collect();
    let hs = Mat::from_fn(n, n, |i, j| h[(i, j)] / (d[i] * d[j]));
    let gs: Vec<f64> = (0..n).map(|i| g[i] / d[i]).collect();
    let params = up.parameters();
    let lo: Vec<f64> = (0..n).map(|i| params[i].lower * d[i]).collect();
    let hi: Vec<f64> = (0..n).map(|i| params[i].upper * d[i]).collect();
    let st: Vec<f64> = (0..n).map(|i| start[i] * d[i]).collect();
    let phi = box_qp(hs.as_ref(), &gs, &lo, &hi, &st)?;
    Ok((0..n)
        .map(|i| (phi[i] / d[i]).clamp(params[i].lower, params[i].upper))
        .collect())
}
