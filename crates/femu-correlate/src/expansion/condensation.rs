//! Static (Guyan) and dynamic expansion: the omitted DOFs condensed on the measured ones,
//! `x_o = -Z_oo^-1 Z_oa x_a` with `Z = K - lambda_id M` (`lambda_id = 0` for static;
//! `docs/MATH.md`, "Expansion").

use super::*;

impl Expander<'_> {
    /// Dynamic expansion at each mode's identified eigenvalue: `x_o = -Z_oo^-1 Z_oa x_a` with
    /// `Z = K - lambda_id M`; `lambda_id = 0` is the static (Guyan) expansion. Returns full-length
    /// vectors (measured values kept).
    ///
    /// # Errors
    /// [`CorrelateError::Invalid`] when `Z_oo` is singular (`lambda_id` is an eigenvalue of the
    /// structure with its measured DOFs held: no unique expansion) or, for the static case, when
    /// `K_oo` is singular (the measured DOFs do not restrain rigid-body motion); size or NaN errors.
    pub fn dynamic(
        &self,
        lambdas: &[f64],
        ya: MatRef<'_, f64>,
    ) -> Result<Mat<f64>, CorrelateError> {
        self.check_lambdas(lambdas, ya)?;
        let mut x = self.scatter_measured(ya);
        let rhs = self.z_times_on_o(lambdas, x.as_ref())?;
        let mut done = vec![false; lambdas.len()];
        for j in 0..lambdas.len() {
            if done[j] {
                continue;
            }
            let lambda = lambdas[j];
            let group: Vec<usize> = (j..lambdas.len())
                .filter(|&i| !done[i] && lambdas[i] == lambda)
                .collect();
            let singular = |index: usize| CorrelateError::Invalid {
                what: "expansion",
                reason: if lambda == 0.0 {
                    format!(
                        "K_oo is singular (mode {}, omitted DOF {index}): the measured DOFs do not restrain every rigid-body motion",
                        j + 1
                    )
                } else {
                    format!(
                        "Z_oo = K_oo - lambda M_oo is singular at lambda = {lambda:e} s^-2 (mode {}; pivot at omitted DOF {index}): lambda is an eigenvalue of the structure with its measured DOFs held, so the expansion is not unique",
                        j + 1
                    )
                },
            };
            let mut b = Mat::from_fn(rhs.nrows(), group.len(), |i, g| -rhs[(i, group[g])]);
            let symbolic = self.symbolic_oo()?;
            let (k_oo, m_oo) = self.oo();
            if lambda == 0.0 {
                let llt = symbolic.llt(k_oo, "K_oo").map_err(|e| match e {
                    SparseError::NotPositiveDefinite { index, .. }
                    | SparseError::NumericallySingular { index, .. } => singular(index),
                    other => other.into(),
                })?;
                llt.solve_in_place(b.as_mut());
            } else {
                let values: Vec<f64> = k_oo
                    .data()
                    .iter()
                    .zip(m_oo)
                    .map(|(k, m)| k - lambda * m)
                    .collect();
                let ldlt = symbolic
                    .ldlt_values(k_oo, &values, "Z_oo")
                    .map_err(|e| match e {
                        SparseError::Singular { index, .. } => singular(index),
                        other => other.into(),
                    })?;
                ldlt.solve_in_place(b.as_mut());
            }
            for (g, &c) in group.iter().enumerate() {
                for (i, &d) in self.part.omitted.iter().enumerate() {
                    x[(d, c)] = b[(i, g)];
                }
                done[c] = true;
            }
            // A nearly singular Z_oo gives a solution that does not solve its system: check the
            // residual on o (zero by construction of the dynamic expansion).
            let cols = Mat::from_fn(x.nrows(), group.len(), |i, g| x[(i, group[g])]);
            let lam: Vec<f64> = vec![lambda; group.len()];
            let r = self.z_times_on_o(&lam, cols.as_ref())?;
            for (g, &c) in group.iter().enumerate() {
                let rn = r.col(g).norm_l2();
                let bn = rhs.col(c).norm_l2();
                let solved = rn.is_finite() && rn <= 1e-6 * bn.max(f64::MIN_POSITIVE);
                if !(solved || (bn == 0.0 && rn == 0.0)) {
                    return Err(singular(usize::MAX));
                }
            }
        }
        Ok(x)
    }

    /// Static (Guyan) expansion `x_o = -K_oo^-1 K_oa x_a`.
    ///
    /// # Errors
    /// As [`Expander::dynamic`].
    pub fn static_(&self, ya: MatRef<'_, f64>) -> Result<Mat<f64>, CorrelateError> {
        self.dynamic(&vec![0.0; ya.ncols()], ya)
    }
}
