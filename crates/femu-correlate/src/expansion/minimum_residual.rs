//! Minimum-residual expansion (`W = M^-1` or a diagonal metric) and its projected and
//! test-error forms for SB-EBE (`docs/MATH.md`, "Expansion" and "Updating").

use super::*;

/// The result of [`Expander::test_error_projected`].
#[derive(Debug, Clone)]
pub struct TestErrorExpansion {
    /// Expanded shapes (full length; the sensor values are estimates, not the data).
    pub x: Mat<f64>,
    /// `C x_j - y_j` per mode.
    pub misfit: Mat<f64>,
    /// `gamma_j` per mode.
    pub gammas: Vec<f64>,
    /// Projected columns per mode: (`W`-part, `sqrt(gamma)`-scaled sensor part).
    pub projected: Vec<(Mat<f64>, Mat<f64>)>,
}

impl Expander<'_> {
    pub(super) fn check_lambdas(
        &self,
        lambdas: &[f64],
        ya: MatRef<'_, f64>,
    ) -> Result<(), CorrelateError> {
        check_expansion_data(self.part.measured.len(), lambdas, ya)
    }

    /// Minimum-residual expansion: `x_o = argmin ||Z_{:,o} x_o + Z_{:,a} x_a||_{M^-1}` with
    /// `Z = K - lambda_id M` (docs/MATH.md, `W = M^-1`). Solved without `M^-1` as the saddle-point
    /// system `M mu - Z_{:,o} x_o = Z_{:,a} x_a`, `-Z_{:,o}^T mu = 0` (`mu = M^-1 r`), regularised by
    /// `-delta I` (delta = 1e-8 max_j sum_r Z_rj^2 / M_rr) and refined towards the unregularised
    /// solution by iterative refinement, which stops at a backward error of 1e-11 or reports
    /// [`femu_sparse::SparseError::NotRefined`]; the forward error stagnates near 1e-7 relative
    /// (the regularisation's conditioning), which is the accuracy to expect, not round-off.
    ///
    /// This is the formulation for many sensors; [`Expander::minimum_residual`] chooses.
    ///
    /// # Errors
    /// A singular problem (the refinement does not converge), sizes, NaN.
    pub fn minimum_residual_saddle_point(
        &self,
        lambdas: &[f64],
        ya: MatRef<'_, f64>,
    ) -> Result<Mat<f64>, CorrelateError> {
        self.minimum_residual_in(lambdas, ya, None)
    }

    /// Minimum-residual expansion: `x_o = argmin ||Z_{:,o} x_o + Z_{:,a} x_a||_{M^-1}` with
    /// `Z = K - lambda_id M` (docs/MATH.md, `W = M^-1`). Up to [`SENSOR_SPACE_LIMIT`] measured DOFs
    /// it is computed in the sensor space ([`SensorSpace`]: one `LDL^T` of `Z` per eigenvalue and
    /// `2 s` solves), beyond with [`Expander::minimum_residual_saddle_point`]; the sensor-space
    /// result is checked and recomputed by the saddle point when the check fails.
    ///
    /// # Errors
    /// As [`Expander::minimum_residual_saddle_point`].
    pub fn minimum_residual(
        &self,
        lambdas: &[f64],
        ya: MatRef<'_, f64>,
    ) -> Result<Mat<f64>, CorrelateError> {
        if self.part.measured.len() > SENSOR_SPACE_LIMIT {
            return self.minimum_residual_saddle_point(lambdas, ya);
        }
        self.sensor_space()?
            .minimum_residual(lambdas, &self.part.measured, ya)
    }

    /// Minimum-residual expansion in a diagonal metric: `x_o = argmin ||Z x||_W` with
    /// `W = diag(w_inv)^-1` (for example `w_inv = diag(M)`, the lumped stand-in for `M^-1` that
    /// SB-EBE's parameter step can use element by element, so both steps minimise one objective).
    ///
    /// # Errors
    /// A non-positive or non-finite `w_inv` entry (index), and as [`Expander::minimum_residual`].
    pub fn minimum_residual_diagonal(
        &self,
        lambdas: &[f64],
        ya: MatRef<'_, f64>,
        w_inv: &[f64],
    ) -> Result<Mat<f64>, CorrelateError> {
        self.check_metric(w_inv)?;
        self.minimum_residual_in(lambdas, ya, Some(w_inv))
    }

    /// [`Expander::minimum_residual_diagonal`] that also projects, for each mode `j`, the columns
    /// `A_j = columns(j, x_j)` (full length, computed from the expanded `x_j`) onto the
    /// `W`-orthogonal complement of the range of `Z_{:,o}`: `P A = A - Z_{:,o} argmin_y ||A -
    /// Z_{:,o} y||_W`, with the same factorization as the expansion (one extra solve per column).
    /// These are the sensitivities of the expanded residual to a parameter when the expansion
    /// follows the parameter (Kaufman's variable projection), which SB-EBE's correction uses.
    ///
    /// # Errors
    /// As [`Expander::minimum_residual_diagonal`], and the callback's errors.
    pub fn minimum_residual_projected<E: From<CorrelateError>>(
        &self,
        lambdas: &[f64],
        ya: MatRef<'_, f64>,
        w_inv: &[f64],
        mut columns: impl FnMut(usize, &[f64]) -> Result<Mat<f64>, E>,
    ) -> Result<(Mat<f64>, Vec<Mat<f64>>), E> {
        self.check_metric(w_inv)?;
        self.check_lambdas(lambdas, ya)?;
        let n = self.k.rows();
        let no = self.part.omitted.len();
        let mut x = self.scatter_measured(ya);
        let mut projected = Vec::with_capacity(lambdas.len());
        let mut symbolic = None;
        const WHAT: &str = "minimum-residual expansion with projected sensitivities";
        for j in 0..lambdas.len() {
            let kkt = self.minimum_residual_kkt(lambdas[j], Some(w_inv));
            let ldlt = kkt
                .factor(&mut symbolic, WHAT)
                .map_err(CorrelateError::from)?;
            let xj = x.as_ref().subcols(j, 1).to_owned();
            let (kx, mx) = (
                sym_mul_mat(self.k, xj.as_ref()).map_err(CorrelateError::from)?,
                sym_mul_mat(self.m, xj.as_ref()).map_err(CorrelateError::from)?,
            );
            let za = Mat::from_fn(n + no, 1, |i, _| {
                if i < n {
                    kx[(i, 0)] - lambdas[j] * mx[(i, 0)]
                } else {
                    0.0
                }
            });
            let z = kkt
                .solve_with(&ldlt, za.as_ref(), WHAT)
                .map_err(CorrelateError::from)?;
            for (i, &d) in self.part.omitted.iter().enumerate() {
                x[(d, j)] = z[(n + i, 0)];
            }
            let xj: Vec<f64> = x.col(j).iter().copied().collect();
            let a = columns(j, &xj)?;
            if a.nrows() != n {
                return Err(CorrelateError::DimensionMismatch {
                    what: "projected columns against K",
                    expected: n,
                    got: a.nrows(),
                }
                .into());
            }
            let b = Mat::from_fn(
                n + no,
                a.ncols(),
                |i, c| if i < n { a[(i, c)] } else { 0.0 },
            );
            let z = kkt
                .solve_with(&ldlt, b.as_ref(), WHAT)
                .map_err(CorrelateError::from)?;
            projected.push(Mat::from_fn(n, a.ncols(), |i, c| w_inv[i] * z[(i, c)]));
        }
        Ok((x, projected))
    }

    /// Expansion with test error in a diagonal metric, for noisy measurements: the full `x`
    /// minimises `||Z x||_W^2 + gamma_j ||C x - y||^2` (`W = diag(w_inv)^-1`, the measured values
    /// are not imposed), with `gamma_j = gamma_rel * mean_{d measured} ||Z e_d||_W^2`: at
    /// `gamma_rel = 1` moving one sensor's value by `t` costs as much as the dynamic residual of
    /// moving that DOF alone by `t`. As in [`Expander::minimum_residual_projected`], each mode's
    /// columns `A_j` are projected onto the complement of what the re-optimised `x` absorbs, in the
    /// joint residual space: returned as `(W`-part `n x c`, sensor part `s x c`, the latter already
    /// scaled by `sqrt(gamma_j)`). Also returns `gamma_j` and the sensor misfits `C x_j - y_j`.
    /// Solved as the saddle-point system `diag(w_inv) mu - Z x = 0`,
    /// `-Z mu - gamma C^T C x = -gamma C^T y`, regularised and refined; one factorization per mode.
    ///
    /// # Errors
    /// `gamma_rel` not positive, as [`Expander::minimum_residual_diagonal`], and the callback's.
    pub fn test_error_projected<E: From<CorrelateError>>(
        &self,
        lambdas: &[f64],
        ya: MatRef<'_, f64>,
        w_inv: &[f64],
        gamma_rel: f64,
        mut columns: impl FnMut(usize, &[f64]) -> Result<Mat<f64>, E>,
    ) -> Result<TestErrorExpansion, E> {
        if !(gamma_rel > 0.0 && gamma_rel.is_finite()) {
            return Err(CorrelateError::Invalid {
                what: "test-error weight",
                reason: format!("gamma = {gamma_rel} must be positive"),
            }
            .into());
        }
        self.check_metric(w_inv)?;
        self.check_lambdas(lambdas, ya)?;
        let n = self.k.rows();
        let meas = &self.part.measured;
        let kp = self.k.indptr();
        let kp = kp.raw_storage();
        let mut out = TestErrorExpansion {
            x: Mat::zeros(n, lambdas.len()),
            misfit: Mat::zeros(meas.len(), lambdas.len()),
            gammas: Vec::with_capacity(lambdas.len()),
            projected: Vec::with_capacity(lambdas.len()),
        };
        let mut symbolic = None;
        const WHAT: &str = "expansion with test error and projected sensitivities";
        for j in 0..lambdas.len() {
            let lambda = lambdas[j];
            let mut t = sprs::TriMat::new((2 * n, 2 * n));
            let mut colnorm = vec![0.0_f64; n];
            for (i, v) in w_inv.iter().enumerate() {
                t.add_triplet(i, i, *v);
            }
            for c in 0..n {
                for p in kp[c]..kp[c + 1] {
                    let r = self.k.indices()[p];
                    let z = self.k.data()[p] - lambda * self.m_on_k[p];
                    t.add_triplet(r, n + c, -z);
                    t.add_triplet(n + r, c, -z);
                    colnorm[c] += z * z / w_inv[r];
                }
            }
            let gamma =
                gamma_rel * meas.iter().map(|d| colnorm[*d]).sum::<f64>() / meas.len() as f64;
            for d in meas {
                t.add_triplet(n + d, n + d, -gamma);
            }
            let scale = colnorm.iter().copied().fold(gamma, f64::max);
            let kkt = QuasiDefinite::from_triplets(2 * n, n, 1e-8 * scale, t);
            let ldlt = kkt
                .factor(&mut symbolic, WHAT)
                .map_err(CorrelateError::from)?;
            let mut b = Mat::zeros(2 * n, 1);
            for (s, d) in meas.iter().enumerate() {
                b[(n + d, 0)] = -gamma * ya[(s, j)];
            }
            let z = kkt
                .solve_with(&ldlt, b.as_ref(), WHAT)
                .map_err(CorrelateError::from)?;
            for i in 0..n {
                out.x[(i, j)] = z[(n + i, 0)];
            }
            for (s, d) in meas.iter().enumerate() {
                out.misfit[(s, j)] = z[(n + d, 0)] - ya[(s, j)];
            }
            let xj: Vec<f64> = out.x.col(j).iter().copied().collect();
            let a = columns(j, &xj)?;
            if a.nrows() != n {
                return Err(CorrelateError::DimensionMismatch {
                    what: "projected columns against K",
                    expected: n,
                    got: a.nrows(),
                }
                .into());
            }
            let b = Mat::from_fn(2 * n, a.ncols(), |i, c| if i < n { a[(i, c)] } else { 0.0 });
            let z = kkt
                .solve_with(&ldlt, b.as_ref(), WHAT)
                .map_err(CorrelateError::from)?;
            let sg = gamma.sqrt();
            out.projected.push((
                Mat::from_fn(n, a.ncols(), |i, c| w_inv[i] * z[(i, c)]),
                Mat::from_fn(meas.len(), a.ncols(), |s, c| sg * z[(n + meas[s], c)]),
            ));
            out.gammas.push(gamma);
        }
        Ok(out)
    }

    /// The regularised saddle-point matrix of the minimum-residual expansion at `lambda`, in the
    /// metric `diag(w_inv)^-1` or `M^-1`.
    pub(super) fn minimum_residual_kkt(&self, lambda: f64, w_inv: Option<&[f64]>) -> QuasiDefinite {
        let n = self.k.rows();
        let no = self.part.omitted.len();
        let mut mdiag = vec![0.0; n];
        let mut t = sprs::TriMat::new((n + no, n + no));
        match w_inv {
            Some(w) => {
                mdiag.copy_from_slice(w);
                w.iter()
                    .enumerate()
                    .for_each(|(i, v)| t.add_triplet(i, i, *v));
            }
            None => {
                for (v, (r, c)) in self.m.iter() {
                    t.add_triplet(r, c, *v);
                    if r == c {
                        mdiag[r] = *v;
                    }
                }
            }
        }
        let kp = self.k.indptr();
        let kp = kp.raw_storage();
        let mut scale = 0.0_f64;
        for (jo, &c) in self.part.omitted.iter().enumerate() {
            let mut s = 0.0;
            for p in kp[c]..kp[c + 1] {
                let r = self.k.indices()[p];
                let z = self.k.data()[p] - lambda * self.m_on_k[p];
                t.add_triplet(r, n + jo, -z);
                t.add_triplet(n + jo, r, -z);
                s += z * z / mdiag[r];
            }
            scale = scale.max(s);
        }
        QuasiDefinite::from_triplets(n + no, n, 1e-8 * scale, t)
    }

    pub(super) fn minimum_residual_in(
        &self,
        lambdas: &[f64],
        ya: MatRef<'_, f64>,
        w_inv: Option<&[f64]>,
    ) -> Result<Mat<f64>, CorrelateError> {
        self.check_lambdas(lambdas, ya)?;
        let n = self.k.rows();
        let no = self.part.omitted.len();
        let mut x = self.scatter_measured(ya);
        let mut symbolic = None;
        for j in 0..lambdas.len() {
            let lambda = lambdas[j];
            let kkt = self.minimum_residual_kkt(lambda, w_inv);
            let xj = x.as_ref().subcols(j, 1).to_owned();
            let za = {
                let (kx, mx) = (
                    sym_mul_mat(self.k, xj.as_ref())?,
                    sym_mul_mat(self.m, xj.as_ref())?,
                );
                Mat::from_fn(n + no, 1, |i, _| {
                    if i < n {
                        kx[(i, 0)] - lambda * mx[(i, 0)]
                    } else {
                        0.0
                    }
                })
            };
            let z = kkt
                .solve(&mut symbolic, za.as_ref(), "minimum-residual expansion")
                .map_err(CorrelateError::from)?;
            for (i, &d) in self.part.omitted.iter().enumerate() {
                x[(d, j)] = z[(n + i, 0)];
            }
        }
        Ok(x)
    }
}
