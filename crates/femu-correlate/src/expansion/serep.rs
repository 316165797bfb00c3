//! SEREP: the measured shapes fitted by model modes, `x = Phi_m (Phi_{m,a})^+ x_a`
//! (`docs/MATH.md`, "Expansion").

use super::*;

impl Expander<'_> {
    /// SEREP: `x = Phi_m (Phi_{m,a})^+ x_a` with the model modes `phi` (`n x m`, `m <=` number of
    /// measured DOFs), by a thin SVD of `Phi_{m,a}`. The measured part is smoothed too: it becomes
    /// the least-squares fit of `x_a` by the model modes.
    ///
    /// # Errors
    /// More modes than measured DOFs, modes that the sensors cannot tell apart (condition of
    /// `Phi_{m,a}` above 1e10), sizes, NaN.
    pub fn serep(
        &self,
        phi: MatRef<'_, f64>,
        ya: MatRef<'_, f64>,
    ) -> Result<Mat<f64>, CorrelateError> {
        self.check_measured(ya)?;
        let s = self.part.measured.len();
        if phi.nrows() != self.k.rows() {
            return Err(CorrelateError::DimensionMismatch {
                what: "SEREP modes against K",
                expected: self.k.rows(),
                got: phi.nrows(),
            });
        }
        let nm = phi.ncols();
        if nm == 0 || nm > s {
            return Err(CorrelateError::Invalid {
                what: "SEREP",
                reason: format!(
                    "{nm} model modes for {s} measured DOFs: need 1 <= modes <= measured DOFs"
                ),
            });
        }
        let phi_a = Mat::from_fn(s, nm, |i, j| phi[(self.part.measured[i], j)]);
        let svd = phi_a.thin_svd().map_err(|e| SparseError::NoConvergence {
            reason: format!("SVD of the modes at the sensors: {e:?}"),
        })?;
        let sv: Vec<f64> = (0..nm).map(|i| svd.S()[i]).collect();
        let (smax, smin) = sv
            .iter()
            .fold((0.0_f64, f64::INFINITY), |(a, b), v| (a.max(*v), b.min(*v)));
        if !(smin > 1e-10 * smax) {
            return Err(CorrelateError::Invalid {
                what: "SEREP",
                reason: format!(
                    "the {nm} model modes are linearly dependent at the sensors (singular values {smax:e} .. {smin:e}); use fewer modes or more sensors"
                ),
            });
        }
        // c = V diag(1/s) U^T y
        let uty = svd.U().transpose() * ya;
        let scaled = Mat::from_fn(nm, ya.ncols(), |i, j| uty[(i, j)] / sv[i]);
        let c = svd.V() * &scaled;
        Ok(phi * &c)
    }
}
