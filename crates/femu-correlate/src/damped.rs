//! The complex modes of a model with structural damping (docs/MATH.md, "Damped modes"): the
//! eigenpairs of `(K + i K_4) phi = mu M phi`, `K_4 = sum_e GE_e K_e` (each material's `GE`, a
//! model-wide loss factor `g K`), found in the space of the real modes `Phi` (mass-normalised,
//! `Phi^T K Phi = Lambda`): `(Lambda + i Phi^T K_4 Phi) q = mu q`, `phi = Phi q`. The reduced
//! matrix is complex symmetric, so its eigenvectors are orthogonal without conjugation, `q_r^T q_s
//! = 0` for `r != s`, and each is scaled to `q^T q = 1` (then `phi^T M phi = 1`). With every mode
//! kept this is the full problem; with the lowest modes kept it is the Rayleigh-Ritz approximation
//! of the lowest damped modes, which the tests measure. `mu = omega^2 (1 + i eta)`: `omega` the
//! damped mode's circular frequency, `eta` its loss factor (twice its damping ratio).

use crate::CorrelateError;
use faer::{Mat, MatRef, c64};

/// Complex modes in the coordinates of the real ones.
#[derive(Debug, Clone)]
pub struct DampedModes {
    /// The eigenvalues `mu_r = omega_r^2 (1 + i eta_r)`, by ascending real part.
    pub values: Vec<c64>,
    /// The coordinates `q_r` in the real modes (real modes x complex modes), `q_r^T q_r = 1`,
    /// turned so that each one's largest component is real and positive.
    pub coordinates: Mat<c64>,
}

impl DampedModes {
    /// The damped mode's frequency `sqrt(Re mu) / (2 pi)`, Hz (0 for a rigid-body mode).
    pub fn frequency_hz(&self, r: usize) -> f64 {
        self.values[r].re.max(0.0).sqrt() / (2.0 * std::f64::consts::PI)
    }

    /// The loss factor `Im mu / Re mu` (0 where `Re mu` is 0: an undamped rigid-body mode).
    pub fn loss_factor(&self, r: usize) -> f64 {
        let v = self.values[r];
        if v.re == 0.0 { 0.0 } else { v.im / v.re }
    }
}

/// The complex modes of the real modes' eigenvalues `values` with the structural damping
/// `structural = Phi^T K_4 Phi` projected on them (modes x modes, symmetric).
///
/// # Errors
/// [`CorrelateError::DimensionMismatch`] for a projection of another size;
/// [`CorrelateError::Invalid`] for a non-finite value or an eigenvector that cannot be scaled
/// (`q^T q = 0`, a defective reduced matrix).
pub fn damped_modes(
    values: &[f64],
    structural: MatRef<'_, f64>,
) -> Result<DampedModes, CorrelateError> {
    let n = values.len();
    if structural.nrows() != n || structural.ncols() != n {
        return Err(CorrelateError::DimensionMismatch {
            what: "projected structural damping (modes x modes)",
            expected: n,
            got: structural.nrows(),
        });
    }
    let finite = values.iter().all(|v| v.is_finite())
        && (0..n).all(|j| (0..n).all(|i| structural[(i, j)].is_finite()));
    if !finite {
        return Err(CorrelateError::Invalid {
            what: "damped modes",
            reason: "an eigenvalue or a projected damping term is not a finite number".into(),
        });
    }
    // the symmetric part: the projection is symmetric up to round-off
    let a = Mat::<c64>::from_fn(n, n, |i, j| {
        c64::new(
            if i == j { values[i] } else { 0.0 },
            0.5 * (structural[(i, j)] + structural[(j, i)]),
        )
    });
    let evd = faer::linalg::solvers::Eigen::<f64>::new(a.as_ref()).map_err(|e| {
        CorrelateError::Invalid {
            what: "damped modes",
            reason: format!("the reduced eigenproblem did not converge ({e:?})"),
        }
    })?;
    let (s, u) = (evd.S(), evd.U());
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&x, &y| s[x].re.total_cmp(&s[y].re));
    let mut coordinates = Mat::<c64>::zeros(n, n);
    let mut out = Vec::with_capacity(n);
    for (k, &j) in order.iter().enumerate() {
        // q^T q without conjugation, and the column scaled by its square root
        let mut qq = c64::new(0.0, 0.0);
        for i in 0..n {
            qq += u[(i, j)] * u[(i, j)];
        }
        let norm: f64 = (0..n).map(|i| u[(i, j)].norm_sqr()).sum::<f64>().sqrt();
        if !(qq.norm() > 1e-10 * norm * norm) {
            return Err(CorrelateError::Invalid {
                what: "damped modes",
                reason: format!(
                    "damped mode {} has q^T q = {qq:?}: the reduced matrix is defective there",
                    k + 1
                ),
            });
        }
        let scale = qq.sqrt();
        let mut big = c64::new(0.0, 0.0);
        for i in 0..n {
            let v = u[(i, j)] / scale;
            coordinates[(i, k)] = v;
            if v.norm() > big.norm() {
                big = v;
            }
        }
        // turn by the largest component's phase (a sign, as q^T q = 1 fixes the rest)
        if big.re < 0.0 {
            for i in 0..n {
                coordinates[(i, k)] = -coordinates[(i, k)];
            }
        }
        out.push(s[j]);
    }
    Ok(DampedModes {
        values: out,
        coordinates,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Proportional damping `K_4 = g K` leaves the modes real: `mu_r = lambda_r (1 + i g)` and `q_r
    /// = e_r`, exactly (to round-off).
    #[test]
    fn proportional_damping_keeps_the_real_modes() {
        let values = [4.0, 9.0, 25.0, 100.0];
        let g = 0.03;
        let s = Mat::<f64>::from_fn(4, 4, |i, j| if i == j { g * values[i] } else { 0.0 });
        let d = damped_modes(&values, s.as_ref()).unwrap();
        for r in 0..4 {
            assert!((d.values[r] - c64::new(values[r], g * values[r])).norm() < 1e-12 * values[r]);
            assert!((d.loss_factor(r) - g).abs() < 1e-13);
            for i in 0..4 {
                let want = if i == r { 1.0 } else { 0.0 };
                assert!((d.coordinates[(i, r)] - c64::new(want, 0.0)).norm() < 1e-12);
            }
        }
    }

    /// A spring-mass chain of 30 masses (`K` tridiagonal, `M` of unequal masses) whose first ten
    /// springs have a loss factor of 0.1 and the rest 0.01 (non-proportional: the modes turn
    /// complex). With all 30 real modes, the damped modes equal the eigenpairs of the full
    /// pencil `(K + i K_4, M)` computed directly (its complex eigendecomposition in the
    /// coordinates `L^T x`, `M = L L^T`): eigenvalues to 1e-10 of the largest, shapes parallel to
    /// 1e-10. With the lowest 10, 15 and 20 kept, the three lowest damped eigenvalues approach the
    /// full ones (errors falling with the count kept).
    #[test]
    fn every_mode_kept_is_the_full_problem() {
        let n = 30;
        let mut k = Mat::<f64>::zeros(n, n);
        let mut k4 = Mat::<f64>::zeros(n, n);
        for e in 0..n {
            // spring e joins mass e - 1 (ground for e = 0) to mass e
            let ke = 1000.0 * (1.0 + 0.3 * (e % 3) as f64);
            let g = if e < 10 { 0.1 } else { 0.01 };
            for (mat, f) in [(&mut k, 1.0), (&mut k4, g)] {
                mat[(e, e)] += f * ke;
                if e >= 1 {
                    mat[(e - 1, e - 1)] += f * ke;
                    mat[(e - 1, e)] -= f * ke;
                    mat[(e, e - 1)] -= f * ke;
                }
            }
        }
        // M = diag(m), L = sqrt(M): the pencil in the coordinates L^T x
        let root: Vec<f64> = (0..n)
            .map(|i| (1.0 + 0.1 * (i % 4) as f64).sqrt())
            .collect();
        let a = Mat::<f64>::from_fn(n, n, |i, j| k[(i, j)] / (root[i] * root[j]));
        let b = Mat::<f64>::from_fn(n, n, |i, j| k4[(i, j)] / (root[i] * root[j]));
        let eig = a.self_adjoint_eigen(faer::Side::Lower).unwrap();
        let lambda: Vec<f64> = (0..n).map(|j| eig.S()[j]).collect();
        assert!(lambda.windows(2).all(|w| w[0] <= w[1]));
        let v = eig.U().to_owned();
        // Phi^T K_4 Phi = V^T B V
        let projected = v.transpose() * &b * &v;
        // the full pencil directly: L^-1 (K + i K_4) L^-T
        let full = Mat::<c64>::from_fn(n, n, |i, j| c64::new(a[(i, j)], b[(i, j)]));
        let evd = faer::linalg::solvers::Eigen::<f64>::new(full.as_ref()).unwrap();
        let mut direct: Vec<(c64, Vec<c64>)> = (0..n)
            .map(|j| (evd.S()[j], (0..n).map(|i| evd.U()[(i, j)]).collect()))
            .collect();
        direct.sort_by(|x, y| x.0.re.total_cmp(&y.0.re));
        let top = lambda[n - 1];
        let damped = |kept: usize| {
            let s = Mat::<f64>::from_fn(kept, kept, |i, j| projected[(i, j)]);
            damped_modes(&lambda[..kept], s.as_ref()).unwrap()
        };
        let all = damped(n);
        for r in 0..n {
            assert!((all.values[r] - direct[r].0).norm() < 1e-10 * top, "{r}");
            // V q against the direct eigenvector (both in the coordinates L^T x)
            let vq: Vec<c64> = (0..n)
                .map(|i| {
                    (0..n)
                        .map(|j| c64::new(v[(i, j)], 0.0) * all.coordinates[(j, r)])
                        .sum()
                })
                .collect();
            let y = &direct[r].1;
            let dot: c64 = vq.iter().zip(y).map(|(a, b)| a.conj() * b).sum();
            let na: f64 = vq.iter().map(|a| a.norm_sqr()).sum();
            let nb: f64 = y.iter().map(|b| b.norm_sqr()).sum();
            assert!((dot.norm_sqr() / (na * nb) - 1.0).abs() < 1e-10, "{r}");
        }
        // the modes are complex: the loss factors differ from mode to mode
        assert!((all.loss_factor(0) - all.loss_factor(5)).abs() > 1e-3);
        let mut previous = [f64::INFINITY; 3];
        for kept in [10, 15, 20] {
            let d = damped(kept);
            for r in 0..3 {
                let e = (d.values[r] - all.values[r]).norm() / all.values[r].norm();
                assert!(
                    e < previous[r] || e < 1e-14,
                    "{kept} {r}: {e} after {}",
                    previous[r]
                );
                previous[r] = e;
            }
        }
    }
}
