//! Minimum dynamic residual expansion with test error (MDRE-WE), in the sensor space or as a
//! saddle-point system (`docs/MATH.md`, "Expansion").

use super::*;

impl Expander<'_> {
    /// Minimum dynamic residual expansion with test error (MDRE-WE):
    /// `x = argmin R^T K_s^-1 R + gamma ||C x - x_a||^2`, `R = (K - lambda_id M) x`, over the full
    /// `x` (the measured values are not imposed: `gamma` weighs trust in the test against trust in
    /// the model). `K_s = K + stiffness_shift M`: pass 0 for a restrained model; a free-free model
    /// needs a positive shift (its `K` is singular and the energy norm undefined on rigid-body
    /// motion), for example `1e-3 lambda_id`, which changes the weight of an elastic mode `j` by
    /// `lambda_j / (lambda_j + shift)`. Solved as the saddle-point system
    /// `K_s u - Z x = 0`, `-Z u - gamma C^T C x = -gamma C^T x_a`, regularised and refined.
    ///
    /// Up to [`SENSOR_SPACE_LIMIT`] measured DOFs it is computed in the sensor space
    /// ([`SensorSpace`], checked, with this saddle point as the fallback), beyond with
    /// [`Expander::mdre_saddle_point`]. In the sensor space (`x` from `Z^-1 K_s Z^-1`, no inverse
    /// of `K_s`) a zero shift is defined for a free-free model too: the limit of the shifted
    /// energy norm as the shift goes to 0 (the rigid-body part of the residual is penalised
    /// without bound); the shifted saddle point approaches it linearly in the shift (tested).
    ///
    /// # Errors
    /// `gamma` not positive, a negative shift, a singular problem, sizes, NaN.
    pub fn mdre(
        &self,
        lambdas: &[f64],
        ya: MatRef<'_, f64>,
        gamma: f64,
        stiffness_shift: f64,
    ) -> Result<Mat<f64>, CorrelateError> {
        if self.part.measured.len() > SENSOR_SPACE_LIMIT {
            return self.mdre_saddle_point(lambdas, ya, gamma, stiffness_shift);
        }
        self.sensor_space()?
            .mdre(lambdas, &self.part.measured, ya, gamma, stiffness_shift)
    }

    /// The sensor space of this expander's measured DOFs, sharing `M`'s values on `K`'s pattern.
    pub(super) fn sensor_space(&self) -> Result<SensorSpace<'_>, CorrelateError> {
        SensorSpace::with_m_on_k(
            self.k,
            self.m,
            &self.part.measured,
            std::borrow::Cow::Borrowed(&self.m_on_k),
        )
    }

    /// Checks MDRE-WE's weights.
    pub(crate) fn check_mdre_weights(
        gamma: f64,
        stiffness_shift: f64,
    ) -> Result<(), CorrelateError> {
        let valid = gamma > 0.0
            && gamma.is_finite()
            && stiffness_shift >= 0.0
            && stiffness_shift.is_finite();
        if valid {
            return Ok(());
        }
        Err(CorrelateError::Invalid {
            what: "MDRE-WE weights",
            reason: format!(
                "gamma = {gamma} must be positive, stiffness shift = {stiffness_shift} non-negative"
            ),
        })
    }

    /// [`Expander::mdre`] by its saddle-point system (size `2n`, one factorization per mode), the
    /// formulation for many sensors.
    ///
    /// # Errors
    /// As [`Expander::mdre`].
    pub fn mdre_saddle_point(
        &self,
        lambdas: &[f64],
        ya: MatRef<'_, f64>,
        gamma: f64,
        stiffness_shift: f64,
    ) -> Result<Mat<f64>, CorrelateError> {
        self.check_lambdas(lambdas, ya)?;
        Self::check_mdre_weights(gamma, stiffness_shift)?;
        let n = self.k.rows();
        let mut out = Mat::zeros(n, lambdas.len());
        let mut symbolic = None;
        for j in 0..lambdas.len() {
            let lambda = lambdas[j];
            let mut t = sprs::TriMat::new((2 * n, 2 * n));
            let kp = self.k.indptr();
            let kp = kp.raw_storage();
            let mut kdiag = vec![0.0; n];
            let mut zcols = vec![0.0_f64; n];
            for c in 0..n {
                for p in kp[c]..kp[c + 1] {
                    let r = self.k.indices()[p];
                    let m = self.m_on_k[p];
                    let ks = self.k.data()[p] + stiffness_shift * m;
                    let z = self.k.data()[p] - lambda * m;
                    t.add_triplet(r, c, ks);
                    t.add_triplet(r, n + c, -z);
                    t.add_triplet(n + r, c, -z);
                    if r == c {
                        kdiag[r] = ks;
                    }
                    zcols[c] += z * z;
                }
            }
            for d in &self.part.measured {
                t.add_triplet(n + d, n + d, -gamma);
            }
            let scale = (0..n)
                .map(|c| zcols[c] / kdiag[c].abs().max(f64::MIN_POSITIVE))
                .fold(gamma, f64::max);
            let kkt = QuasiDefinite::from_triplets(2 * n, n, 1e-8 * scale, t);
            let mut b = Mat::zeros(2 * n, 1);
            for (s, d) in self.part.measured.iter().enumerate() {
                b[(n + d, 0)] = -gamma * ya[(s, j)];
            }
            let z = kkt
                .solve(&mut symbolic, b.as_ref(), "MDRE-WE expansion")
                .map_err(CorrelateError::from)?;
            for i in 0..n {
                out[(i, j)] = z[(n + i, 0)];
            }
        }
        Ok(out)
    }
}
