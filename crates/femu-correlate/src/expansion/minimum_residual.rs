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

/// Tolerance of the a posteriori checks of the sensor-space projected expansion: residuals of its
/// optimality conditions relative to the size of the terms that cancel in them (sensor values
/// relative to the largest reading).
const PROJECTED_CHECK_TOL: f64 = 1e-8;

/// Tolerance of the check of the projected columns `P A` alone, looser than
/// [`PROJECTED_CHECK_TOL`]: `P A` only gives the direction of a Gauss-Newton step (the objective
/// that accepts or rejects it comes from `x`, checked at the tighter tolerance), and its residual
/// grows as an identified eigenvalue approaches a model one: measured 8e-9 to 4e-7 on the
/// 52,416-DOF block one step from convergence, where the saddle point costs ten times as much. On
/// a small bar at a relative distance of `1e-7` the columns then differ from a dense QR solution
/// by up to 3.4e-6 (docs/MATH.md; tests/correlate/expansion.rs bounds it by 1e-5).
const PROJECTED_COLUMNS_TOL: f64 = 1e-6;

/// Largest sum of the concurrent factors' values, in bytes, under which the modes of a projected
/// expansion are factored and solved concurrently, one per thread (the fronts of one factor keep
/// two threads busy less well than two factors do; measured 8 % off an SB-EBE trial at 52,416
/// DOF): above it, one mode after the other, so memory stays that of one factor.
const CONCURRENT_FACTORS_BYTES: usize = 1 << 30;

/// The columns a projected expansion's callback returned must have one row per DOF.
fn check_columns(a: &Mat<f64>, n: usize) -> Result<(), CorrelateError> {
    if a.nrows() != n {
        return Err(CorrelateError::DimensionMismatch {
            what: "projected columns against K",
            expected: n,
            got: a.nrows(),
        });
    }
    Ok(())
}

/// One mode's expanded shape (`n x 1`) and projected columns (`n x c`).
type ModeExpansion = (Mat<f64>, Mat<f64>);

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
    /// Up to [`SENSOR_SPACE_LIMIT`] measured DOFs each mode is computed in the sensor space (one
    /// `LDL^T` of `Z` on `K`'s pattern, on `symbolic` when given, a solve with `s` right-hand
    /// sides and one with one; docs/MATH.md, "Projected sensitivities in the sensor space"), checked
    /// against the optimality conditions and recomputed by
    /// [`Expander::minimum_residual_projected_saddle_point`] when `Z` cannot be factored or the
    /// check fails; beyond, by the saddle point. The modes are independent: in the sensor space
    /// they run concurrently, one per thread, while their factors together take at most 1 GiB;
    /// the modes that need the saddle point follow, on one analysis of its pattern.
    ///
    /// # Errors
    /// As [`Expander::minimum_residual_diagonal`], and the callback's errors.
    pub fn minimum_residual_projected<E: From<CorrelateError> + Send>(
        &self,
        lambdas: &[f64],
        ya: MatRef<'_, f64>,
        w_inv: &[f64],
        symbolic: Option<&SymbolicFactor>,
        columns: impl Fn(usize, &[f64]) -> Result<Mat<f64>, E> + Sync,
    ) -> Result<(Mat<f64>, Vec<Mat<f64>>), E> {
        use rayon::prelude::*;
        self.check_metric(w_inv)?;
        self.check_lambdas(lambdas, ya)?;
        if self.part.measured.len() > SENSOR_SPACE_LIMIT {
            return self.minimum_residual_projected_saddle_point(lambdas, ya, w_inv, columns);
        }
        let owned;
        let symbolic = match symbolic {
            Some(s) => s,
            None => {
                owned = SymbolicFactor::new(self.k, Ordering::NestedDissection)
                    .map_err(CorrelateError::from)?;
                &owned
            }
        };
        let n = self.k.rows();
        let sensor_space = |j: usize| -> Result<Option<ModeExpansion>, E> {
            self.projected_in_sensor_space(lambdas[j], ya.subcols(j, 1), w_inv, symbolic, &|xj| {
                columns(j, xj)
            })
        };
        let concurrent = rayon::current_num_threads().min(lambdas.len());
        let modes: Vec<Result<Option<ModeExpansion>, E>> = if concurrent > 1
            && symbolic.factor_len() * std::mem::size_of::<f64>() * concurrent
                <= CONCURRENT_FACTORS_BYTES
        {
            (0..lambdas.len())
                .into_par_iter()
                .map(sensor_space)
                .collect()
        } else {
            (0..lambdas.len()).map(sensor_space).collect()
        };
        let mut modes = modes.into_iter().collect::<Result<Vec<_>, E>>()?;
        // the modes the sensor space failed (Z not factorable without pivoting, or a check
        // missed): the saddle point, after the others and on one symbolic analysis (its factor
        // is several times Z's)
        let failed: Vec<usize> = (0..modes.len()).filter(|&j| modes[j].is_none()).collect();
        if !failed.is_empty() {
            self.fallbacks.add(failed.len());
            let lf: Vec<f64> = failed.iter().map(|&j| lambdas[j]).collect();
            let yf = Mat::from_fn(ya.nrows(), failed.len(), |i, k| ya[(i, failed[k])]);
            let one = |k: usize, xj: &[f64]| columns(failed[k], xj);
            let (xs, ps) =
                self.minimum_residual_projected_saddle_point(&lf, yf.as_ref(), w_inv, one)?;
            for (k, (&j, p)) in failed.iter().zip(ps).enumerate() {
                modes[j] = Some((xs.subcols(k, 1).to_owned(), p));
            }
        }
        let mut x = Mat::zeros(n, lambdas.len());
        let mut projected = Vec::with_capacity(lambdas.len());
        for (j, mode) in modes.into_iter().enumerate() {
            let (xj, pj) = mode.expect("every failed mode has its saddle point");
            x.col_mut(j).copy_from(xj.col(0));
            projected.push(pj);
        }
        Ok((x, projected))
    }

    /// One mode of [`Expander::minimum_residual_projected`] in the sensor space (docs/MATH.md,
    /// "Projected sensitivities in the sensor space"): with `E` the unit columns of the measured
    /// DOFs, `V = Z^-1 E` and the Householder QR `diag(sqrt(w_inv)) V = U R`, the expansion is
    /// `x = Z^-1 diag(sqrt(w_inv)) U R^-T y` (one more solve) and the `W`-orthogonal complement
    /// of the range of `Z_{:,o}` is the range of `diag(w_inv) V`, so `P A` is the orthogonal
    /// projection onto `U` in the variables scaled by `W^1/2`. (`x = B G^-1 y` with
    /// `B = Z^-1 diag(w_inv) V` and `G = V^T diag(w_inv) V = R^T R` is the same in exact
    /// arithmetic; near a model eigenvalue `G` squares `R`'s conditioning and its Cholesky breaks
    /// down where `R` still solves.) `None` when `Z` has a zero pivot, `R` a zero diagonal, or the
    /// result misses its optimality conditions (`(Z W Z x)_o = 0`, `C x = y`, `(Z W P A)_o = 0`)
    /// by more than [`PROJECTED_CHECK_TOL`] ([`PROJECTED_COLUMNS_TOL`] for `P A`).
    fn projected_in_sensor_space<E: From<CorrelateError>>(
        &self,
        lambda: f64,
        y: MatRef<'_, f64>,
        w_inv: &[f64],
        symbolic: &SymbolicFactor,
        columns: &impl Fn(&[f64]) -> Result<Mat<f64>, E>,
    ) -> Result<Option<ModeExpansion>, E> {
        let n = self.k.rows();
        let meas = &self.part.measured;
        let s = meas.len();
        let values: Vec<f64> = self
            .k
            .data()
            .iter()
            .zip(&self.m_on_k)
            .map(|(k, m)| k - lambda * m)
            .collect();
        let ldlt = match symbolic.ldlt_values(self.k, &values, "K - lambda M") {
            Ok(f) => f,
            Err(SparseError::Singular { .. }) => return Ok(None),
            Err(e) => return Err(CorrelateError::from(e).into()),
        };
        let mut v = Mat::<f64>::zeros(n, s);
        for (c, &d) in meas.iter().enumerate() {
            v[(d, c)] = 1.0;
        }
        ldlt.solve_in_place(v.as_mut());
        let finite = |a: &Mat<f64>| (0..a.ncols()).all(|c| a.col(c).iter().all(|v| v.is_finite()));
        if !finite(&v) {
            return Ok(None);
        }
        // In the scaled variables S = W^1/2 the residual r = Z x of the expansion is the
        // minimum-norm solution of V^T r = y (C Z^-1 = V^T): with the Householder QR
        // S^-1 V = diag(sqrt(w_inv)) V = U R, S r = U R^-T y. Near an eigenvalue the columns of V
        // are nearly parallel; R's conditioning is the square root of G = R^T R's, so this keeps
        // the digits G^-1 loses (and G's Cholesky breaks down where R still solves)
        let sv = Mat::from_fn(n, s, |i, c| w_inv[i].sqrt() * v[(i, c)]);
        let qr = sv.qr();
        let u = qr.compute_thin_Q();
        let r = qr.thin_R();
        // z = R^-T y (R^T is lower triangular)
        let mut z = y.to_owned();
        r.transpose().solve_lower_triangular_in_place(z.as_mut());
        if !finite(&z) {
            return Ok(None);
        }
        // x = Z^-1 r = Z^-1 S^-1 U z: one solve
        let uz = &u * &z;
        let mut x = Mat::from_fn(n, 1, |i, _| w_inv[i].sqrt() * uz[(i, 0)]);
        ldlt.solve_in_place(x.as_mut());
        if !finite(&x) {
            return Ok(None);
        }
        let xv: Vec<f64> = x.col(0).iter().copied().collect();
        let a = columns(&xv)?;
        check_columns(&a, n)?;
        // P A as the orthogonal projection, in the scaled variables, onto the range of U (the
        // W-orthogonal complement of the range of Z_{:,o} is the range of diag(w_inv) V)
        let sa = Mat::from_fn(n, a.ncols(), |i, c| a[(i, c)] / w_inv[i].sqrt());
        let proj = &u * (u.transpose() * &sa);
        let pa = Mat::from_fn(n, a.ncols(), |i, c| w_inv[i].sqrt() * proj[(i, c)]);
        // a posteriori: the optimality conditions in the original variables
        let kp = self.k.indptr();
        let kp = kp.raw_storage();
        let z_norm = (0..n)
            .map(|c| {
                values[kp[c]..kp[c + 1]]
                    .iter()
                    .map(|v| v.abs())
                    .sum::<f64>()
            })
            .fold(0.0, f64::max);
        // Z = K - lambda M on K's pattern (the factored values): one pass per product
        let z_times = |u: MatRef<'_, f64>| -> Result<Mat<f64>, CorrelateError> {
            let mut zu = Mat::zeros(n, u.ncols());
            sym_mul_mat_values_into(self.k, &values, u, zu.as_mut())?;
            Ok(zu)
        };
        let zx = z_times(x.as_ref()).map_err(E::from)?;
        // (Z u)_o must vanish for u = W Z x and u = W P A (one product for both), relative to
        // the size of the terms that cancel in it: ||Z|| ||u|| for u = W P A; for u = W Z x,
        // whose Z x is itself a cancellation (x is near an eigenvector), ||Z|| max(W) ||Z|| ||x||
        let c = pa.ncols();
        let wu = Mat::from_fn(n, 1 + c, |i, k| {
            if k == 0 {
                zx[(i, 0)] / w_inv[i]
            } else {
                pa[(i, k - 1)] / w_inv[i]
            }
        });
        let zwu = z_times(wu.as_ref()).map_err(E::from)?;
        let w_max = w_inv.iter().fold(0.0_f64, |m, v| m.max(1.0 / v));
        let scale: Vec<f64> = (0..=c)
            .map(|k| {
                if k == 0 {
                    PROJECTED_CHECK_TOL * z_norm * w_max * z_norm * x.norm_max()
                } else {
                    PROJECTED_COLUMNS_TOL * z_norm * wu.col(k).norm_max()
                }
            })
            .collect();
        let omitted_ok = self
            .part
            .omitted
            .iter()
            .all(|&d| (0..=c).all(|k| zwu[(d, k)].abs() <= scale[k]));
        let y_scale = y.norm_max().max(f64::MIN_POSITIVE);
        let imposed = meas
            .iter()
            .enumerate()
            .all(|(r, &d)| (x[(d, 0)] - y[(r, 0)]).abs() <= PROJECTED_CHECK_TOL * y_scale);
        if !(imposed && omitted_ok) {
            return Ok(None);
        }
        Ok(Some((x, pa)))
    }

    /// [`Expander::minimum_residual_projected`] by the saddle-point system of size `n + n_o` per
    /// mode (one factorization each, symbolic analysis shared by the modes): the formulation for
    /// many sensors, and the fallback of the sensor-space one.
    ///
    /// # Errors
    /// As [`Expander::minimum_residual_diagonal`], and the callback's errors.
    pub fn minimum_residual_projected_saddle_point<E: From<CorrelateError>>(
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
            check_columns(&a, n)?;
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
            check_columns(&a, n)?;
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
                // a massless DOF (its whole row of the semi-definite M is zero: a lumped beam's
                // rotations, a bar's torsion without inertia) would make the metric M^-1
                // infinite there; it takes the smallest positive mass instead, as
                // `residual_metric` does (docs/MATH.md, "The residual metric on massless DOFs")
                if let Ok(floored) = residual_metric(self.m) {
                    for (r, d) in mdiag.iter_mut().enumerate() {
                        if *d <= 0.0 {
                            *d = floored[r];
                            t.add_triplet(r, r, floored[r]);
                        }
                    }
                }
            }
        }
        let kp = self.k.indptr();
        let kp = kp.raw_storage();
        let mut norms = Vec::with_capacity(no);
        for (jo, &c) in self.part.omitted.iter().enumerate() {
            let mut s = 0.0;
            for p in kp[c]..kp[c + 1] {
                let r = self.k.indices()[p];
                let z = self.k.data()[p] - lambda * self.m_on_k[p];
                t.add_triplet(r, n + jo, -z);
                t.add_triplet(n + jo, r, -z);
                s += z * z / mdiag[r];
            }
            norms.push(s);
        }
        // each row regularised in proportion to its column's weighted norm (the Schur
        // complement's diagonal): a thin shell's rotation columns, weighted by the inverse of a
        // rotary inertia `(L/t)^2` smaller than the translations' mass, are that much larger
        let scale = norms.iter().copied().fold(0.0_f64, f64::max);
        let delta = norms.iter().map(|s| 1e-8 * s.max(1e-12 * scale)).collect();
        QuasiDefinite::from_triplets_per_row(n + no, n, delta, t)
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
