//! Modal expansion: test shapes known on the measured DOFs `a` filled in on the omitted DOFs `o`
//! (MATH.md, "Incomplete instrumentation: modal expansion"), with sparse factorizations only.
//!
//! | method | omitted part |
//! |---|---|
//! | static (Guyan) | `x_o = -K_oo^-1 K_oa x_a` |
//! | dynamic | `x_o = -Z_oo^-1 Z_oa x_a`, `Z = K - lambda_id M` (residual zero on `o`) |
//! | SEREP | `x = Phi_m (Phi_{m,a})^+ x_a` with `m <=` sensors model modes |
//!
//! The partition comes from an axis-aligned [`SensorLayout`]. `K_oo` and `M_oo` are extracted once
//! on `K_oo`'s pattern with its symbolic analysis; every identified eigenvalue then costs one
//! numeric factorization of `Z_oo`, shared by the modes that have the same eigenvalue.

use crate::{CorrelateError, SensorLayout, SensorSpace};

/// Above this many measured DOFs, [`Expander::minimum_residual`] and [`Expander::mdre`] use their
/// saddle-point systems instead of the sensor space (whose cost grows with `2 s` solves and dense
/// `n x s` blocks).
pub const SENSOR_SPACE_LIMIT: usize = 300;
use faer::{Mat, MatRef};
use femu_sparse::cholesky::{Factorization, SymbolicFactor};
use femu_sparse::csc::sym_mul_mat;
use femu_sparse::ordering::Ordering;
use femu_sparse::{SparseError, SparseMatrix};

/// Measured and omitted free DOFs.
#[derive(Debug, Clone, PartialEq)]
pub struct Partition {
    measured: Vec<usize>,
    omitted: Vec<usize>,
    /// for each free DOF, its position in `omitted` (usize::MAX when measured)
    omitted_pos: Vec<usize>,
}

impl Partition {
    /// A partition of `n` DOFs with the given measured ones (any order, no repeats).
    ///
    /// # Errors
    /// A DOF out of range or repeated, or no omitted DOF left.
    pub fn new(n: usize, measured: &[usize]) -> Result<Self, CorrelateError> {
        let mut is_measured = vec![false; n];
        for &d in measured {
            if d >= n || is_measured[d] {
                return Err(CorrelateError::Invalid {
                    what: "measured DOFs",
                    reason: format!("DOF {d} is out of range (n = {n}) or repeated"),
                });
            }
            is_measured[d] = true;
        }
        let omitted: Vec<usize> = (0..n).filter(|d| !is_measured[*d]).collect();
        let mut omitted_pos = vec![usize::MAX; n];
        for (i, d) in omitted.iter().enumerate() {
            omitted_pos[*d] = i;
        }
        Ok(Self {
            measured: measured.to_vec(),
            omitted,
            omitted_pos,
        })
    }

    /// The measured DOFs, in sensor order.
    pub fn measured(&self) -> &[usize] {
        &self.measured
    }

    /// The omitted DOFs, ascending.
    pub fn omitted(&self) -> &[usize] {
        &self.omitted
    }
}

/// Full-length vectors (`n` rows) with the rows of `ya` on the `measured` DOFs and zero elsewhere:
/// the test shapes themselves when every DOF is measured (no expansion needed).
///
/// # Errors
/// `ya` with another row count than `measured`, a DOF out of range or repeated.
pub fn place_measured(
    n: usize,
    measured: &[usize],
    ya: MatRef<'_, f64>,
) -> Result<Mat<f64>, CorrelateError> {
    Partition::new(n, measured)?;
    if ya.nrows() != measured.len() {
        return Err(CorrelateError::DimensionMismatch {
            what: "measured shapes against the measured DOFs",
            expected: measured.len(),
            got: ya.nrows(),
        });
    }
    Ok(place(n, measured, ya))
}

fn place(n: usize, measured: &[usize], ya: MatRef<'_, f64>) -> Mat<f64> {
    let mut x = Mat::zeros(n, ya.ncols());
    for j in 0..ya.ncols() {
        for (s, &d) in measured.iter().enumerate() {
            x[(d, j)] = ya[(s, j)];
        }
    }
    x
}

/// `M`'s values on `K`'s pattern (0 where `M` stores nothing), so that `Z = K - lambda M` is formed
/// entry by entry on that pattern.
///
/// # Errors
/// An entry of `M` outside `K`'s pattern.
pub(crate) fn m_on_pattern(k: &SparseMatrix, m: &SparseMatrix) -> Result<Vec<f64>, CorrelateError> {
    let n = k.rows();
    let (kp, mp) = (k.indptr(), m.indptr());
    let (kp, mp) = (kp.raw_storage(), mp.raw_storage());
    let mut m_on_k = vec![0.0; k.nnz()];
    for c in 0..n {
        let mrows = &m.indices()[mp[c]..mp[c + 1]];
        let krows = &k.indices()[kp[c]..kp[c + 1]];
        for (q, r) in mrows.iter().enumerate() {
            let pos = krows
                .binary_search(r)
                .map_err(|_| SparseError::DimensionMismatch {
                    what: "pattern of M inside the pattern of K (entry of M missing from K)",
                    expected: c,
                    got: *r,
                })?;
            m_on_k[kp[c] + pos] = m.data()[mp[c] + q];
        }
    }
    Ok(m_on_k)
}

/// Measured shapes: one row per measured DOF, finite values.
fn check_measured(measured: usize, ya: MatRef<'_, f64>) -> Result<(), CorrelateError> {
    if ya.nrows() != measured {
        return Err(CorrelateError::DimensionMismatch {
            what: "measured shapes against the measured DOFs",
            expected: measured,
            got: ya.nrows(),
        });
    }
    for j in 0..ya.ncols() {
        if let Some(i) = ya.col(j).iter().position(|v| !v.is_finite()) {
            return Err(CorrelateError::NonFinite {
                what: "measured shape",
                index: j * ya.nrows() + i,
            });
        }
    }
    Ok(())
}

/// Measured shapes as [`check_measured`] and one finite eigenvalue per shape.
pub(crate) fn check_expansion_data(
    measured: usize,
    lambdas: &[f64],
    ya: MatRef<'_, f64>,
) -> Result<(), CorrelateError> {
    check_measured(measured, ya)?;
    if lambdas.len() != ya.ncols() {
        return Err(CorrelateError::DimensionMismatch {
            what: "eigenvalues against measured shapes",
            expected: ya.ncols(),
            got: lambdas.len(),
        });
    }
    match lambdas.iter().position(|l| !l.is_finite()) {
        Some(index) => Err(CorrelateError::NonFinite {
            what: "expansion eigenvalue",
            index,
        }),
        None => Ok(()),
    }
}

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

/// Expansion of measured shapes on one model and one sensor set.
#[derive(Debug, Clone)]
pub struct Expander<'a> {
    k: &'a SparseMatrix,
    m: &'a SparseMatrix,
    part: Partition,
    /// `M`'s values on `K`'s pattern (0 where `M` stores nothing), found once: every expansion
    /// forms `Z = K - lambda M` entry by entry on that pattern
    m_on_k: Vec<f64>,
    /// `K_oo` (CSC, both triangles) and `M_oo`'s values on its pattern
    k_oo: SparseMatrix,
    m_oo: Vec<f64>,
    /// analysed on first use: only static and dynamic expansion factor `K_oo - lambda M_oo`, and
    /// SB-EBE builds an expander per iteration for the saddle-point methods alone
    symbolic: std::sync::OnceLock<SymbolicFactor>,
}

impl<'a> Expander<'a> {
    /// Prepares expansion for the sensors of `layout` (every sensor along a global axis).
    ///
    /// # Errors
    /// An oblique sensor (expansion needs measured DOFs), `K` and `M` of other sizes than the
    /// layout's model, every DOF measured, or an entry of `M` outside `K`'s pattern.
    pub fn new(
        k: &'a SparseMatrix,
        m: &'a SparseMatrix,
        layout: &SensorLayout,
    ) -> Result<Self, CorrelateError> {
        let measured = layout.measured_dofs().ok_or(CorrelateError::Invalid {
            what: "sensor layout",
            reason: "expansion needs every sensor along a global axis (measured DOFs)".into(),
        })?;
        Self::with_measured_dofs(k, m, &measured)
    }

    /// As [`Expander::new`] with the measured free DOFs given directly.
    ///
    /// # Errors
    /// As [`Expander::new`].
    pub fn with_measured_dofs(
        k: &'a SparseMatrix,
        m: &'a SparseMatrix,
        measured: &[usize],
    ) -> Result<Self, CorrelateError> {
        let n = k.rows();
        if m.rows() != n || k.cols() != n || m.cols() != n {
            return Err(CorrelateError::DimensionMismatch {
                what: "M against K (square, same size)",
                expected: n,
                got: m.rows(),
            });
        }
        let part = Partition::new(n, measured)?;
        if part.omitted.is_empty() {
            return Err(CorrelateError::Invalid {
                what: "sensor layout",
                reason: "every DOF is measured: nothing to expand".into(),
            });
        }
        let m_on_k = m_on_pattern(k, m)?;
        let kp = k.indptr();
        let kp = kp.raw_storage();
        let no = part.omitted.len();
        let mut ptr = Vec::with_capacity(no + 1);
        let mut idx = Vec::new();
        let mut kv = Vec::new();
        let mut mv = Vec::new();
        ptr.push(0);
        for &c in &part.omitted {
            for p in kp[c]..kp[c + 1] {
                let o = part.omitted_pos[k.indices()[p]];
                if o != usize::MAX {
                    idx.push(o);
                    kv.push(k.data()[p]);
                    mv.push(m_on_k[p]);
                }
            }
            ptr.push(idx.len());
        }
        let k_oo = SparseMatrix::new_csc((no, no), ptr, idx, kv);
        Ok(Self {
            k,
            m,
            part,
            m_on_k,
            k_oo,
            m_oo: mv,
            symbolic: std::sync::OnceLock::new(),
        })
    }

    /// The partition.
    pub fn partition(&self) -> &Partition {
        &self.part
    }

    /// The symbolic analysis of `K_oo`, computed on first use.
    fn symbolic_oo(&self) -> Result<&SymbolicFactor, CorrelateError> {
        if let Some(s) = self.symbolic.get() {
            return Ok(s);
        }
        let s = SymbolicFactor::new(&self.k_oo, Ordering::NestedDissection)?;
        Ok(self.symbolic.get_or_init(|| s))
    }

    /// Checks a diagonal metric `w_inv` (one positive finite entry per DOF).
    fn check_metric(&self, w_inv: &[f64]) -> Result<(), CorrelateError> {
        if w_inv.len() != self.k.rows() {
            return Err(CorrelateError::DimensionMismatch {
                what: "diagonal metric against K",
                expected: self.k.rows(),
                got: w_inv.len(),
            });
        }
        match w_inv.iter().position(|w| !(w.is_finite() && *w > 0.0)) {
            Some(index) => Err(CorrelateError::Invalid {
                what: "diagonal metric",
                reason: format!("entry {index} = {} must be positive", w_inv[index]),
            }),
            None => Ok(()),
        }
    }

    fn check_measured(&self, ya: MatRef<'_, f64>) -> Result<(), CorrelateError> {
        check_measured(self.part.measured.len(), ya)
    }

    /// Full-length vectors with `ya` on the measured DOFs and zero elsewhere.
    fn scatter_measured(&self, ya: MatRef<'_, f64>) -> Mat<f64> {
        place(self.k.rows(), &self.part.measured, ya)
    }

    /// `(Z x)_o` for full vectors `x` and `Z = K - lambda M` (one lambda per column).
    fn z_times_on_o(
        &self,
        lambdas: &[f64],
        x: MatRef<'_, f64>,
    ) -> Result<Mat<f64>, CorrelateError> {
        let (kx, mx) = (sym_mul_mat(self.k, x)?, sym_mul_mat(self.m, x)?);
        Ok(Mat::from_fn(self.part.omitted.len(), x.ncols(), |i, j| {
            let d = self.part.omitted[i];
            kx[(d, j)] - lambdas[j] * mx[(d, j)]
        }))
    }

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
            if lambda == 0.0 {
                let llt = symbolic.llt(&self.k_oo, "K_oo").map_err(|e| match e {
                    SparseError::NotPositiveDefinite { index, .. } => singular(index),
                    other => other.into(),
                })?;
                llt.solve_in_place(b.as_mut());
            } else {
                let values: Vec<f64> = self
                    .k_oo
                    .data()
                    .iter()
                    .zip(&self.m_oo)
                    .map(|(k, m)| k - lambda * m)
                    .collect();
                let ldlt =
                    symbolic
                        .ldlt_values(&self.k_oo, &values, "Z_oo")
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

/// A symmetric quasi-definite saddle-point system `[[A, B], [B^T, -C - delta I]]`, factored by
/// `LDL^T` without pivoting (quasi-definite matrices factor stably in any symmetric order), then
/// solved for `delta = 0` by iterative refinement with the exact matrix.
struct Kkt {
    /// the regularised matrix
    a: SparseMatrix,
    /// size of the first block
    n1: usize,
    delta: f64,
}

impl Kkt {
    fn from_triplets(n: usize, n1: usize, delta: f64, mut t: sprs::TriMat<f64>) -> Self {
        for i in n1..n {
            t.add_triplet(i, i, -delta);
        }
        Self {
            a: t.to_csc(),
            n1,
            delta,
        }
    }

    /// Solves `A_0 z = b` for the columns of `b`; `what` names the system in errors.
    /// `symbolic` is the analysis of an earlier system with the same pattern (computed and kept on
    /// first use): the pattern does not depend on `lambda_id`, so one ordering serves every mode.
    fn solve(
        &self,
        symbolic: &mut Option<SymbolicFactor>,
        b: MatRef<'_, f64>,
        what: &'static str,
    ) -> Result<Mat<f64>, CorrelateError> {
        let ldlt = self.factor(symbolic, what)?;
        self.solve_with(&ldlt, b, what)
    }

    /// The `LDL^T` factor of the regularised matrix (analysing the pattern on first use).
    fn factor(
        &self,
        symbolic: &mut Option<SymbolicFactor>,
        what: &'static str,
    ) -> Result<femu_sparse::cholesky::Ldlt, CorrelateError> {
        if symbolic.is_none() {
            *symbolic = Some(SymbolicFactor::new(&self.a, Ordering::NestedDissection)?);
        }
        Ok(symbolic.as_ref().expect("just set").ldlt(&self.a, what)?)
    }

    /// Solves with a factor of [`Kkt::factor`], refined to the unregularised system.
    fn solve_with(
        &self,
        ldlt: &femu_sparse::cholesky::Ldlt,
        b: MatRef<'_, f64>,
        what: &'static str,
    ) -> Result<Mat<f64>, CorrelateError> {
        let n = self.a.rows();
        let mut z = b.to_owned();
        ldlt.solve_in_place(z.as_mut());
        let bn: Vec<f64> = (0..b.ncols()).map(|j| b.col(j).norm_l2()).collect();
        // normwise backward error ||r|| / (||A|| ||z|| + ||b||): the refinement stops at round-off
        // (1e-14) or when it stagnates at a level that is still round-off for this matrix (1e-11)
        let a_norm = (0..n)
            .map(|c| {
                self.a
                    .outer_view(c)
                    .map_or(0.0, |v| v.iter().map(|(_, x)| x.abs()).sum::<f64>())
            })
            .fold(0.0, f64::max);
        let mut last = f64::INFINITY;
        for _ in 0..100 {
            // r = b - A_0 z, A_0 z = A_delta z + delta z_2
            let az = sym_mul_mat(&self.a, z.as_ref())?;
            let mut r = Mat::from_fn(n, b.ncols(), |i, j| {
                let a0 = az[(i, j)]
                    + if i >= self.n1 {
                        self.delta * z[(i, j)]
                    } else {
                        0.0
                    };
                b[(i, j)] - a0
            });
            let eta = (0..b.ncols())
                .map(|j| {
                    r.col(j).norm_l2()
                        / (a_norm * z.col(j).norm_l2() + bn[j]).max(f64::MIN_POSITIVE)
                })
                .fold(0.0, f64::max);
            if eta <= 1e-14 || (eta <= 1e-11 && eta > 0.5 * last) {
                return Ok(z);
            }
            last = eta;
            ldlt.solve_in_place(r.as_mut());
            if (0..r.ncols()).any(|j| r.col(j).iter().any(|v| !v.is_finite())) {
                break;
            }
            z += &r;
        }
        Err(CorrelateError::Invalid {
            what,
            reason: "the regularised saddle-point system did not refine to a backward error of 1e-11: the problem is singular or nearly so (an expansion eigenvalue on an eigenvalue of the constrained structure, or too few sensors)".into(),
        })
    }
}

impl Expander<'_> {
    fn check_lambdas(&self, lambdas: &[f64], ya: MatRef<'_, f64>) -> Result<(), CorrelateError> {
        check_expansion_data(self.part.measured.len(), lambdas, ya)
    }

    /// Minimum-residual expansion: `x_o = argmin ||Z_{:,o} x_o + Z_{:,a} x_a||_{M^-1}` with
    /// `Z = K - lambda_id M` (MATH.md, `W = M^-1`). Solved without `M^-1` as the saddle-point
    /// system `M mu - Z_{:,o} x_o = Z_{:,a} x_a`, `-Z_{:,o}^T mu = 0` (`mu = M^-1 r`), regularised by
    /// `-delta I` (delta = 1e-8 max_j sum_r Z_rj^2 / M_rr) and refined to the exact solution.
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
    /// `Z = K - lambda_id M` (MATH.md, `W = M^-1`). Up to [`SENSOR_SPACE_LIMIT`] measured DOFs
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
            let ldlt = kkt.factor(&mut symbolic, WHAT)?;
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
            let z = kkt.solve_with(&ldlt, za.as_ref(), WHAT)?;
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
            let z = kkt.solve_with(&ldlt, b.as_ref(), WHAT)?;
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
            let kkt = Kkt::from_triplets(2 * n, n, 1e-8 * scale, t);
            let ldlt = kkt.factor(&mut symbolic, WHAT)?;
            let mut b = Mat::zeros(2 * n, 1);
            for (s, d) in meas.iter().enumerate() {
                b[(n + d, 0)] = -gamma * ya[(s, j)];
            }
            let z = kkt.solve_with(&ldlt, b.as_ref(), WHAT)?;
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
            let z = kkt.solve_with(&ldlt, b.as_ref(), WHAT)?;
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
    fn minimum_residual_kkt(&self, lambda: f64, w_inv: Option<&[f64]>) -> Kkt {
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
        Kkt::from_triplets(n + no, n, 1e-8 * scale, t)
    }

    fn minimum_residual_in(
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
            let z = kkt.solve(&mut symbolic, za.as_ref(), "minimum-residual expansion")?;
            for (i, &d) in self.part.omitted.iter().enumerate() {
                x[(d, j)] = z[(n + i, 0)];
            }
        }
        Ok(x)
    }

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
    fn sensor_space(&self) -> Result<SensorSpace<'_>, CorrelateError> {
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
            let kkt = Kkt::from_triplets(2 * n, n, 1e-8 * scale, t);
            let mut b = Mat::zeros(2 * n, 1);
            for (s, d) in self.part.measured.iter().enumerate() {
                b[(n + d, 0)] = -gamma * ya[(s, j)];
            }
            let z = kkt.solve(&mut symbolic, b.as_ref(), "MDRE-WE expansion")?;
            for i in 0..n {
                out[(i, j)] = z[(n + i, 0)];
            }
        }
        Ok(out)
    }
}
