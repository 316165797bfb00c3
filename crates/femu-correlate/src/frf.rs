//! Frequency responses of the model at the test's DOFs, and their correlation with measured ones
//! (docs/MATH.md, "Frequency responses").
//!
//! The model's FRF between output sensors `C` and input (excitation) sensors `B` at the circular
//! frequency `w` is, by modal superposition of the mass-normalised modes `phi_r` with eigenvalues
//! `lambda_r`,
//!
//! `H(w) = sum_r (C phi_r)(B phi_r)^T / (lambda_r - w^2 + i g_r(w)) + R`,
//!
//! with the damping term `g_r` of [`Damping`] and, when given, the residual flexibility
//! `R = C K^-1 B^T - sum_r (C phi_r)(B phi_r)^T / lambda_r` of the modes left out (the static
//! response they would add; [`residual_flexibility`]). For damping proportional to the modes
//! (ratios, Rayleigh, a loss factor) and every mode kept this equals the direct solution
//! `C (K (1 + i eta) + i w C_v - w^2 M)^-1 B^T` exactly. Mobility and accelerance are the
//! receptance times `i w` and `-w^2`.
//!
//! The correlation of measured and model FRFs: FRAC per output and input over the lines (the
//! shape of one response curve), CSAC and CSF per line over the outputs (the shape of the
//! deflection at one frequency, and its amplitude).

use crate::{CorrelateError, SensorLayout};
use faer::{Mat, MatRef, c64};
use femu_sparse::SparseMatrix;
use serde::{Deserialize, Serialize};

/// The damping of the model's modes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Damping {
    /// One viscous damping ratio `zeta` for every mode: `g_r = 2 zeta omega_r w`.
    Ratio(f64),
    /// A viscous ratio per mode (for example the test's identified ratios of paired modes).
    Ratios(Vec<f64>),
    /// Rayleigh damping `C = alpha M + beta K`: `g_r = (alpha + beta lambda_r) w`.
    Rayleigh {
        /// The mass coefficient, s^-1.
        alpha: f64,
        /// The stiffness coefficient, s.
        beta: f64,
    },
    /// A structural loss factor `eta` (`K (1 + i eta)`): `g_r = eta lambda_r`.
    LossFactor(f64),
    /// A structural loss factor per mode, each mode's complex stiffness `lambda_r (1 + i eta_r)`:
    /// `g_r = eta_r lambda_r` (Nastran's modal damping table under `PARAM,KDAMP,-1`, Abaqus'
    /// `*MODAL DAMPING, STRUCTURAL`). The residual flexibility of the modes left out is not
    /// softened: their loss factors are not known.
    LossFactors(Vec<f64>),
}

impl std::fmt::Display for Damping {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Damping::Ratio(z) => write!(f, "viscous ratio {z} on every mode"),
            Damping::Ratios(z) => write!(f, "viscous ratios per mode {z:?}"),
            Damping::Rayleigh { alpha, beta } => {
                write!(f, "Rayleigh, C = {alpha:e} M + {beta:e} K")
            }
            Damping::LossFactor(eta) => write!(f, "structural loss factor {eta}"),
            Damping::LossFactors(eta) => write!(f, "structural loss factors per mode {eta:?}"),
        }
    }
}

impl Damping {
    /// `g_r(w)` of mode `r` with eigenvalue `lambda`.
    fn term(&self, r: usize, lambda: f64, w: f64) -> f64 {
        let omega = lambda.max(0.0).sqrt();
        match self {
            Damping::Ratio(z) => 2.0 * z * omega * w,
            Damping::Ratios(z) => 2.0 * z[r] * omega * w,
            Damping::Rayleigh { alpha, beta } => (alpha + beta * lambda) * w,
            Damping::LossFactor(eta) => eta * lambda,
            Damping::LossFactors(eta) => eta[r] * lambda,
        }
    }

    fn check(&self, modes: usize) -> Result<(), CorrelateError> {
        let bad = |reason: String| CorrelateError::Invalid {
            what: "damping",
            reason,
        };
        let values: Vec<f64> = match self {
            Damping::Ratio(z) => vec![*z],
            Damping::Ratios(z) | Damping::LossFactors(z) => {
                if z.len() != modes {
                    return Err(bad(format!(
                        "{} {} for {modes} modes: give one per mode",
                        z.len(),
                        if matches!(self, Damping::Ratios(_)) {
                            "ratios"
                        } else {
                            "loss factors"
                        }
                    )));
                }
                z.clone()
            }
            Damping::Rayleigh { alpha, beta } => vec![*alpha, *beta],
            Damping::LossFactor(eta) => vec![*eta],
        };
        match values.iter().find(|v| !(v.is_finite() && **v >= 0.0)) {
            Some(v) => Err(bad(format!("{v} is not a finite, non-negative value"))),
            None => Ok(()),
        }
    }
}

/// What an FRF relates the force to: displacement, velocity or acceleration.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ResponseKind {
    /// Displacement over force (m/N).
    Receptance,
    /// Velocity over force (m/(N s)): `i w` times the receptance.
    Mobility,
    /// Acceleration over force (m/(N s^2)): `-w^2` times the receptance.
    Accelerance,
}

impl ResponseKind {
    fn factor(self, w: f64) -> c64 {
        match self {
            ResponseKind::Receptance => c64::new(1.0, 0.0),
            ResponseKind::Mobility => c64::new(0.0, w),
            ResponseKind::Accelerance => c64::new(-w * w, 0.0),
        }
    }
}

/// How the model's FRFs are formed: the modes' damping and what the response is.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrfOptions {
    /// The modes' damping.
    pub damping: Damping,
    /// Receptance, mobility or accelerance.
    pub kind: ResponseKind,
}

/// The model's FRFs at frequency lines: `h[line]` is the `outputs x inputs` matrix.
#[derive(Debug, Clone)]
pub struct Frf {
    /// The frequency lines, Hz.
    pub lines_hz: Vec<f64>,
    /// What the responses are.
    pub kind: ResponseKind,
    /// One `outputs x inputs` matrix per line.
    pub h: Vec<Mat<c64>>,
}

/// The model's FRFs between `outputs` and `inputs` at `lines_hz` by modal superposition of the
/// mass-normalised `shapes` (free DOFs x modes) with eigenvalues `values` (s^-2), the damping
/// and response of `options`, and the residual flexibility `residual` (`outputs x inputs`,
/// receptance; [`residual_flexibility`]) of the modes left out when given (divided by `1 + i eta`
/// for a loss factor, which softens the static response of the modes left out as it does the
/// others').
///
/// # Errors
/// Sizes that do not match, negative or non-finite lines or damping, a line on an undamped
/// eigenvalue (an infinite response).
pub fn modal_frf(
    values: &[f64],
    shapes: MatRef<'_, f64>,
    residual: Option<MatRef<'_, f64>>,
    outputs: &SensorLayout,
    inputs: &SensorLayout,
    lines_hz: &[f64],
    options: &FrfOptions,
) -> Result<Frf, CorrelateError> {
    modal_frf_coupled(
        values, shapes, residual, outputs, inputs, lines_hz, options, None,
    )
}

/// A model's own dampers projected on its kept modes: `Phi^T K_4 Phi` (structural, entering as
/// `i Phi^T K_4 Phi`) and `Phi^T C_d Phi` (viscous, `i w Phi^T C_d Phi`), full `modes x modes`
/// matrices, which the modes do not diagonalise (docs/MATH.md, "Frequency responses, directly").
#[derive(Debug, Clone, PartialEq)]
pub struct ModalDampers {
    /// `Phi^T K_4 Phi`.
    pub structural: Option<Mat<f64>>,
    /// `Phi^T C_d Phi`.
    pub viscous: Option<Mat<f64>>,
}

impl ModalDampers {
    /// The projections of `structural` (`K_4`) and `viscous` (`C_d`) on the mass-normalised
    /// `shapes` (free DOFs x modes).
    ///
    /// # Errors
    /// Sizes that do not match.
    pub fn project(
        structural: Option<&SparseMatrix>,
        viscous: Option<&SparseMatrix>,
        shapes: MatRef<'_, f64>,
    ) -> Result<Self, CorrelateError> {
        let project = |a: Option<&SparseMatrix>| -> Result<Option<Mat<f64>>, CorrelateError> {
            let Some(a) = a else { return Ok(None) };
            let ap = femu_sparse::csc::sym_mul_mat(a, shapes)?;
            Ok(Some(shapes.transpose() * &ap))
        };
        Ok(Self {
            structural: project(structural)?,
            viscous: project(viscous)?,
        })
    }
}

/// [`modal_frf`] with the model's own dampers projected on the kept modes (`dampers`): at each line
/// the modal equations `(diag(lambda_r - w^2 + i d_r) + i Phi^T K_4 Phi + i w Phi^T C_d Phi) q =
/// Phi^T B^T` are solved together (a dense complex `LU` of `modes x modes`), as CalculiX's
/// steady-state dynamics does with a material's structural damping; `d_r` is the damping of
/// `options`. The residual flexibility of the modes left out is undamped by the dampers.
///
/// # Errors
/// As [`modal_frf`]; projections of another size than the modes; a singular modal system.
#[allow(clippy::too_many_arguments)]
pub fn modal_frf_coupled(
    values: &[f64],
    shapes: MatRef<'_, f64>,
    residual: Option<MatRef<'_, f64>>,
    outputs: &SensorLayout,
    inputs: &SensorLayout,
    lines_hz: &[f64],
    options: &FrfOptions,
    dampers: Option<&ModalDampers>,
) -> Result<Frf, CorrelateError> {
    let (damping, kind) = (&options.damping, options.kind);
    let dampers = dampers.filter(|d| d.structural.is_some() || d.viscous.is_some());
    if let Some(d) = dampers {
        for p in d.structural.iter().chain(&d.viscous) {
            if p.nrows() != values.len() || p.ncols() != values.len() {
                return Err(CorrelateError::DimensionMismatch {
                    what: "projected dampers (modes x modes)",
                    expected: values.len(),
                    got: p.nrows(),
                });
            }
        }
    }
    if values.len() != shapes.ncols() {
        return Err(CorrelateError::DimensionMismatch {
            what: "eigenvalues against mode shapes",
            expected: shapes.ncols(),
            got: values.len(),
        });
    }
    damping.check(values.len())?;
    if let Some(k) = lines_hz.iter().position(|f| !(f.is_finite() && *f >= 0.0)) {
        return Err(CorrelateError::NonFinite {
            what: "frequency line (Hz, finite and non-negative)",
            index: k,
        });
    }
    if let Some(r) = residual
        && (r.nrows() != outputs.len() || r.ncols() != inputs.len())
    {
        return Err(CorrelateError::DimensionMismatch {
            what: "residual flexibility (outputs x inputs)",
            expected: outputs.len() * inputs.len(),
            got: r.nrows() * r.ncols(),
        });
    }
    let co = outputs.measure_all(shapes)?;
    let bi = inputs.measure_all(shapes)?;
    let mut h = Vec::with_capacity(lines_hz.len());
    for (line, f) in lines_hz.iter().enumerate() {
        let w = 2.0 * std::f64::consts::PI * f;
        let mut hl = Mat::<c64>::zeros(outputs.len(), inputs.len());
        if let Some(d) = dampers {
            coupled_line(values, damping, d, w, (&co, &bi), &mut hl).map_err(|reason| {
                CorrelateError::Invalid {
                    what: "frequency line",
                    reason: format!("line {} ({f} Hz): {reason}", line + 1),
                }
            })?;
        }
        // (with dampers the modes are solved together above)
        for (r, lambda) in values.iter().enumerate().filter(|_| dampers.is_none()) {
            let den = c64::new(lambda - w * w, damping.term(r, *lambda, w));
            if den.re == 0.0 && den.im == 0.0 {
                return Err(CorrelateError::Invalid {
                    what: "frequency line",
                    reason: format!(
                        "line {} ({f} Hz) is on undamped mode {} : the response is infinite",
                        line + 1,
                        r + 1
                    ),
                });
            }
            let inv = c64::new(1.0, 0.0) / den;
            for i in 0..outputs.len() {
                let ci = co[(i, r)];
                for j in 0..inputs.len() {
                    hl[(i, j)] += inv * (ci * bi[(j, r)]);
                }
            }
        }
        if let Some(res) = residual {
            // the left-out modes' static response is softened by a loss factor as theirs:
            // `(K (1 + i eta))^-1 = K^-1 / (1 + i eta)`
            let soft = match damping {
                Damping::LossFactor(eta) => c64::new(1.0, 0.0) / c64::new(1.0, *eta),
                _ => c64::new(1.0, 0.0),
            };
            for i in 0..outputs.len() {
                for j in 0..inputs.len() {
                    hl[(i, j)] += soft * res[(i, j)];
                }
            }
        }
        let s = kind.factor(w);
        for i in 0..outputs.len() {
            for j in 0..inputs.len() {
                hl[(i, j)] *= s;
            }
        }
        h.push(hl);
    }
    Ok(Frf {
        lines_hz: lines_hz.to_vec(),
        kind,
        h,
    })
}

/// One line of [`modal_frf_coupled`]: `hl += C Phi Z^-1 (B Phi)^T` with the coupled modal
/// dynamic stiffness `Z`.
fn coupled_line(
    values: &[f64],
    damping: &Damping,
    d: &ModalDampers,
    w: f64,
    (co, bi): (&Mat<f64>, &Mat<f64>),
    hl: &mut Mat<c64>,
) -> Result<(), String> {
    use faer::linalg::solvers::Solve;
    let m = values.len();
    let z = Mat::<c64>::from_fn(m, m, |i, j| {
        let mut v = c64::new(0.0, 0.0);
        if i == j {
            v += c64::new(values[i] - w * w, damping.term(i, values[i], w));
        }
        if let Some(s) = &d.structural {
            v += c64::new(0.0, s[(i, j)]);
        }
        if let Some(c) = &d.viscous {
            v += c64::new(0.0, w * c[(i, j)]);
        }
        v
    });
    let rhs = Mat::<c64>::from_fn(m, bi.nrows(), |r, j| c64::new(bi[(j, r)], 0.0));
    let q = z.as_ref().partial_piv_lu().solve(&rhs);
    if q.col_iter()
        .any(|c| c.iter().any(|v| !(v.re.is_finite() && v.im.is_finite())))
    {
        return Err(
            "the damped modal equations are singular (an undamped mode at the line)".into(),
        );
    }
    for i in 0..co.nrows() {
        for j in 0..bi.nrows() {
            let mut v = c64::new(0.0, 0.0);
            for r in 0..m {
                v += q[(r, j)] * co[(i, r)];
            }
            hl[(i, j)] += v;
        }
    }
    Ok(())
}

/// The residual flexibility of the modes left out: `C K^-1 B^T - sum_r (C phi_r)(B phi_r)^T /
/// lambda_r` over the kept `values` and mass-normalised `shapes` (`outputs x inputs`).
///
/// # Errors
/// `K` not positive definite (a model with rigid-body motions has no static flexibility: its
/// residual flexibility needs inertia relief, which femu does not form), sizes, a zero eigenvalue
/// among the kept modes.
pub fn residual_flexibility(
    k: &SparseMatrix,
    values: &[f64],
    shapes: MatRef<'_, f64>,
    outputs: &SensorLayout,
    inputs: &SensorLayout,
) -> Result<Mat<f64>, CorrelateError> {
    residual_flexibility_analysed(k, None, values, shapes, outputs, inputs)
}

/// [`residual_flexibility`] on a symbolic analysis of `k`'s pattern already made (the one the
/// assembly made beside `K`, [`femu_fem::assembly::SystemMatrices::analysis`]): no second
/// ordering. An analysis of another pattern is not used.
///
/// # Errors
/// As [`residual_flexibility`].
pub fn residual_flexibility_analysed(
    k: &SparseMatrix,
    analysis: Option<femu_sparse::cholesky::SymbolicFactor>,
    values: &[f64],
    shapes: MatRef<'_, f64>,
    outputs: &SensorLayout,
    inputs: &SensorLayout,
) -> Result<Mat<f64>, CorrelateError> {
    use femu_sparse::cholesky::{Factorization, SymbolicFactor};
    if let Some(r) = values.iter().position(|l| !(*l > 0.0)) {
        return Err(CorrelateError::Invalid {
            what: "residual flexibility",
            reason: format!(
                "mode {} has eigenvalue {:e}: a model with rigid-body motions has no static flexibility",
                r + 1,
                values[r]
            ),
        });
    }
    let symbolic = match analysis.filter(|a| a.is_for(k)) {
        Some(a) => a,
        None => SymbolicFactor::new(k, Default::default())?,
    };
    let llt = symbolic.llt(k, "K")?;
    // K^-1 B^T: the inputs' rows as columns, solved together
    let mut cols = Mat::<f64>::zeros(k.rows(), inputs.len());
    for j in 0..inputs.len() {
        for (f, w) in inputs.row(j) {
            cols[(*f, j)] += w;
        }
    }
    llt.solve_in_place(cols.as_mut());
    let mut r = outputs.measure_all(cols.as_ref())?;
    let co = outputs.measure_all(shapes)?;
    let bi = inputs.measure_all(shapes)?;
    for (m, lambda) in values.iter().enumerate() {
        for i in 0..outputs.len() {
            for j in 0..inputs.len() {
                r[(i, j)] -= co[(i, m)] * bi[(j, m)] / lambda;
            }
        }
    }
    Ok(r)
}

/// [`residual_flexibility`] solved with a factorization of `K - sigma M` that the eigensolver
/// kept ([`femu_sparse::eigen::EigenOptions::keep_factor`]) instead of a factorization of `K`:
/// no factorization at all, and defined for a model with rigid-body motions, whose rigid-body
/// modes are among the kept ones (docs/MATH.md, "Residual flexibility from the eigensolver's
/// factor").
///
/// The loads are first cleared of the kept modes, `f' = (I - M Phi Phi^T) f`, so that what is
/// solved lies in the span of the modes left out, where `K` is definite; there
/// `x = sum_left phi_r phi_r^T f / lambda_r` is reached by refining `x <- x + (K - sigma M)^-1
/// (f' - K x)` (each step multiplies a mode's error by `-sigma / (lambda_r - sigma)`: `1e-10` at
/// the lowest-mode solve's tiny shift, a step or two), and `R = C x`. With rigid-body modes kept
/// this is the flexibility of the elastic modes left out under loads balanced by the rigid-body
/// inertia (inertia relief), the free structure's residual flexibility.
///
/// # Errors
/// A factor of another size, kept modes that are not every mode below the factor's shift
/// (its inertia counts others), refinement that stops converging above round-off (a null vector
/// of `K` the kept modes do not hold, such as a rigid-body mode left out, or a shift too close to
/// the modes left out), sizes. Loads the kept modes hold entirely give `R = 0`.
#[allow(clippy::too_many_arguments)]
pub fn residual_flexibility_factored(
    k: &SparseMatrix,
    m: &SparseMatrix,
    factor: &femu_sparse::eigen::KeptFactor,
    values: &[f64],
    shapes: MatRef<'_, f64>,
    outputs: &SensorLayout,
    inputs: &SensorLayout,
) -> Result<Mat<f64>, CorrelateError> {
    use femu_sparse::cholesky::Factorization;
    use femu_sparse::csc::sym_mul_mat;
    let n = k.rows();
    let invalid = |reason: String| CorrelateError::Invalid {
        what: "residual flexibility",
        reason,
    };
    if factor.ldlt.dim() != n || m.rows() != n || shapes.nrows() != n {
        return Err(invalid(format!(
            "K has {n} DOFs, M {}, the kept factor {}, the modes {}",
            m.rows(),
            factor.ldlt.dim(),
            shapes.nrows()
        )));
    }
    if values.len() != shapes.ncols() {
        return Err(invalid(format!(
            "{} eigenvalues for {} mode shapes",
            values.len(),
            shapes.ncols()
        )));
    }
    let below = values.iter().filter(|l| **l < factor.sigma).count();
    if factor.ldlt.inertia().negative != below {
        return Err(invalid(format!(
            "the factor at the shift {:e} s^-2 has {} eigenvalues below it, the kept modes {below}: the modes are not every mode below the shift",
            factor.sigma,
            factor.ldlt.inertia().negative
        )));
    }
    // x <- x - Phi Phi^T M x: clears a block of its components along the kept modes
    let clear = |x: &mut Mat<f64>| -> Result<(), CorrelateError> {
        let mx = sym_mul_mat(m, x.as_ref())?;
        let c = shapes.transpose() * &mx;
        *x -= shapes * &c;
        Ok(())
    };
    // f' = (I - M Phi Phi^T) f for the inputs' rows f
    let mut f = Mat::<f64>::zeros(n, inputs.len());
    for j in 0..inputs.len() {
        for (d, w) in inputs.row(j) {
            f[(*d, j)] += w;
        }
    }
    let c = shapes.transpose() * &f;
    let cleared = &f - sym_mul_mat(m, (shapes * &c).as_ref())?;
    let norm = |a: MatRef<'_, f64>| a.norm_max();
    if norm(cleared.as_ref()) <= 1e-12 * norm(f.as_ref()) {
        // the kept modes hold the loads to round-off: the modes left out carry nothing
        return Ok(Mat::zeros(outputs.len(), inputs.len()));
    }
    let f = cleared;
    let mut x = f.clone();
    factor.ldlt.solve_in_place(x.as_mut());
    clear(&mut x)?;
    // Refined until a step is below 1e-14 of the solution, or until the steps stop shrinking at
    // round-off (below 1e-10 of it: K's conditioning sets that floor); a step that stops
    // shrinking above it is a null vector of K the kept modes do not hold, or a shift too close
    // to the modes left out.
    let mut previous = f64::INFINITY;
    let mut converged = false;
    for _ in 0..60 {
        let mut dx = &f - sym_mul_mat(k, x.as_ref())?;
        factor.ldlt.solve_in_place(dx.as_mut());
        clear(&mut dx)?;
        x += &dx;
        let step = norm(dx.as_ref());
        let floor = norm(x.as_ref());
        if !step.is_finite() {
            break;
        }
        if step <= 1e-14 * floor || (step > 0.5 * previous && step <= 1e-10 * floor) {
            converged = true;
            break;
        }
        if step > 0.5 * previous {
            break;
        }
        previous = step;
    }
    if !converged {
        return Err(invalid(format!(
            "refinement with the factor at {:e} s^-2 did not converge: K has a null vector the kept modes do not hold (a rigid-body mode left out), or the shift is too close to the modes left out",
            factor.sigma
        )));
    }
    outputs.measure_all(x.as_ref())
}

/// The matrices of the direct route: `K` and `M` (free DOFs), and the model's own dampers when it
/// has them: discrete viscous dampers `C_d` (bushings' `B`) and element structural damping
/// `K_4 = sum_e GE_e K_e` (springs' and bushings' `GE`), Nastran's `B` and `K4`.
#[derive(Debug, Clone, Copy)]
pub struct DirectSystem<'a> {
    /// Stiffness.
    pub k: &'a SparseMatrix,
    /// Mass.
    pub m: &'a SparseMatrix,
    /// Discrete viscous damping `C_d` (N s/m), added to the damping's own.
    pub viscous: Option<&'a SparseMatrix>,
    /// Element structural damping `K_4` (N/m), entering as `i K_4`.
    pub structural: Option<&'a SparseMatrix>,
}

/// The model's FRFs by the direct route, and how well each line was solved.
#[derive(Debug, Clone)]
pub struct DirectFrf {
    /// The FRFs.
    pub frf: Frf,
    /// Per line, the normwise backward error of its solves after one step of iterative
    /// refinement ([`femu_sparse::complex::Factored::solve_in_place`]).
    pub backward_errors: Vec<f64>,
}

/// The model's FRFs between `outputs` and `inputs` at `lines_hz` by solving the dynamic stiffness
/// at each line (docs/MATH.md, "Frequency responses, directly"):
///
/// `H(w) = C (K (1 + i eta) + i K_4 + i w (alpha M + beta K + C_d) - w^2 M)^-1 B^T`,
///
/// one sparse complex `LU` per line on one symbolic analysis, several lines at once where the
/// threads and the memory allow ([`direct_frf_at_once`]). `options.damping` is a loss factor
/// `eta` or Rayleigh coefficients (or a zero ratio: none); modal ratios have no matrix and are
/// refused. `system`'s dampers are added to it: they are the route's reason to be, damping that
/// the modes do not diagonalise.
///
/// # Errors
/// Modal damping ratios, sizes, non-finite or negative lines and damping, a singular dynamic
/// stiffness (an undamped resonance on a line).
pub fn direct_frf(
    system: &DirectSystem<'_>,
    outputs: &SensorLayout,
    inputs: &SensorLayout,
    lines_hz: &[f64],
    options: &FrfOptions,
) -> Result<DirectFrf, CorrelateError> {
    direct_frf_at_once(system, outputs, inputs, lines_hz, options, None)
}

/// [`direct_frf`] with `at_once` lines factored and solved at the same time (each its own
/// factorization, all on the one symbolic analysis); `None`: as many as the threads, no more
/// than the lines, and no more than a quarter of the memory the system has available holds at
/// three times a factor's size each (docs/SCALING.md, "Frequency responses"). One line at a
/// time leaves each factorization all the threads (its supernodal tree and its fronts in
/// parallel); several lines at once use the threads that a small model's factorization leaves
/// idle. The results are the same either way.
///
/// # Errors
/// As [`direct_frf`]; the first line's error in line order.
pub fn direct_frf_at_once(
    system: &DirectSystem<'_>,
    outputs: &SensorLayout,
    inputs: &SensorLayout,
    lines_hz: &[f64],
    options: &FrfOptions,
    at_once: Option<usize>,
) -> Result<DirectFrf, CorrelateError> {
    use femu_sparse::complex::Combination;
    let (eta, alpha, beta) = match &options.damping {
        Damping::LossFactor(eta) => (*eta, 0.0, 0.0),
        Damping::Rayleigh { alpha, beta } => (0.0, *alpha, *beta),
        Damping::Ratio(z) if *z == 0.0 => (0.0, 0.0, 0.0),
        Damping::Ratio(_) | Damping::Ratios(_) | Damping::LossFactors(_) => {
            return Err(CorrelateError::Invalid {
                what: "damping",
                reason: "modal damping (ratios or loss factors per mode) has no damping matrix: the direct route takes a loss factor or Rayleigh coefficients (and the model's own dampers); modal damping is for the modal route".into(),
            });
        }
    };
    options.damping.check(0)?;
    if let Some(k) = lines_hz.iter().position(|f| !(f.is_finite() && *f >= 0.0)) {
        return Err(CorrelateError::NonFinite {
            what: "frequency line (Hz, finite and non-negative)",
            index: k,
        });
    }
    let n = system.k.rows();
    for (what, len) in [
        ("output sensors against K", outputs.dim()),
        ("input sensors against K", inputs.dim()),
    ] {
        if len != n {
            return Err(CorrelateError::DimensionMismatch {
                what,
                expected: n,
                got: len,
            });
        }
    }
    let mut mats = vec![system.k, system.m];
    let mut names = vec!["K", "M"];
    if let Some(c) = system.viscous {
        mats.push(c);
        names.push("the dampers' C");
    }
    if let Some(k4) = system.structural {
        mats.push(k4);
        names.push("the elements' structural damping K4");
    }
    let comb = Combination::new(&mats, &names)?;
    // `B^T`: the inputs' unit forces, the same at every line
    let mut forces = Mat::<c64>::zeros(n, inputs.len());
    for j in 0..inputs.len() {
        for (d, wgt) in inputs.row(j) {
            forces[(*d, j)] += c64::new(*wgt, 0.0);
        }
    }
    let at_once = at_once
        .unwrap_or_else(|| lines_at_once(comb.factor_len(), lines_hz.len()))
        .clamp(1, lines_hz.len().max(1));
    let solve_line = |line: usize| -> Result<(Mat<c64>, f64), CorrelateError> {
        let f = lines_hz[line];
        let w = 2.0 * std::f64::consts::PI * f;
        let mut c = vec![c64::new(1.0, eta + w * beta), c64::new(-w * w, w * alpha)];
        if system.viscous.is_some() {
            c.push(c64::new(0.0, w));
        }
        if system.structural.is_some() {
            c.push(c64::new(0.0, 1.0));
        }
        let singular = |e: femu_sparse::SparseError| match e {
            femu_sparse::SparseError::Singular { .. } => CorrelateError::Invalid {
                what: "frequency line",
                reason: format!(
                    "line {} ({f} Hz): the dynamic stiffness is singular there (an undamped resonance on the line)",
                    line + 1
                ),
            },
            other => other.into(),
        };
        let mut fac = comb.factor(&c).map_err(singular)?;
        let mut rhs = forces.clone();
        let backward = fac.solve_in_place(rhs.as_mut()).map_err(singular)?;
        let s = options.kind.factor(w);
        let mut hl = Mat::<c64>::zeros(outputs.len(), inputs.len());
        for i in 0..outputs.len() {
            for j in 0..inputs.len() {
                let v: c64 = outputs
                    .row(i)
                    .iter()
                    .map(|(d, wgt)| rhs[(*d, j)] * *wgt)
                    .sum();
                hl[(i, j)] = v * s;
            }
        }
        Ok((hl, backward))
    };
    let mut h = Vec::with_capacity(lines_hz.len());
    let mut backward_errors = Vec::with_capacity(lines_hz.len());
    for r in map_lines(lines_hz.len(), at_once, solve_line) {
        let (hl, b) = r?;
        h.push(hl);
        backward_errors.push(b);
    }
    Ok(DirectFrf {
        frf: Frf {
            lines_hz: lines_hz.to_vec(),
            kind: options.kind,
            h,
        },
        backward_errors,
    })
}

/// `f` of each line `0..lines`, in line order, `at_once` lines at the same time (one after the
/// other for 1; taken as the threads free up when `at_once` is the threads): the frequency-line
/// loops of the direct route and of updating from FRFs, each line holding a factorization of its
/// own while it runs.
pub fn map_lines<T: Send>(
    lines: usize,
    at_once: usize,
    f: impl Fn(usize) -> T + Sync + Send,
) -> Vec<T> {
    use rayon::prelude::*;
    if at_once >= rayon::current_num_threads() && at_once > 1 {
        // every thread may hold a line: no chunks, the lines stolen as threads free up
        return (0..lines).into_par_iter().map(f).collect();
    }
    let all: Vec<usize> = (0..lines).collect();
    let mut out = Vec::with_capacity(lines);
    for chunk in all.chunks(at_once.max(1)) {
        if chunk.len() == 1 {
            out.push(f(chunk[0]));
        } else {
            let done: Vec<T> = chunk.par_iter().map(|&l| f(l)).collect();
            out.extend(done);
        }
    }
    out
}

/// How many frequency lines to factor at the same time ([`map_lines`]): the threads, no more
/// than `lines`, and no more than a quarter of the available memory holds at three times a
/// factor of `factor_len` complex values each (the factor, and the fronts and updates of its
/// elimination). Without `/proc/meminfo`, 4 GiB are taken as available.
pub fn lines_at_once(factor_len: usize, lines: usize) -> usize {
    let available = std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("MemAvailable:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok())
        })
        .map_or(4.0 * 1024.0 * 1024.0 * 1024.0, |kb| kb * 1024.0);
    let each = 3.0 * 16.0 * factor_len.max(1) as f64;
    let by_memory = ((available / 4.0) / each).floor().max(1.0) as usize;
    rayon::current_num_threads()
        .min(lines)
        .min(by_memory)
        .max(1)
}

fn dot(a: &[c64], b: &[c64]) -> c64 {
    a.iter().zip(b).map(|(x, y)| x.conj() * y).sum()
}

fn norm2(a: &[c64]) -> f64 {
    a.iter().map(|x| x.re * x.re + x.im * x.im).sum()
}

/// The frequency response assurance criterion of one measured response curve `test` and the
/// model's `model` over the same lines: `|t^H m|^2 / ((t^H t)(m^H m))`, 1 for curves of the same
/// shape (any complex scale), 0 for orthogonal ones.
///
/// # Errors
/// Different lengths, or a curve that is zero.
pub fn frac(test: &[c64], model: &[c64]) -> Result<f64, CorrelateError> {
    assurance("FRAC", test, model).map(|(c, _, _)| c)
}

/// The cross-signature assurance criterion of the measured and model deflections `test` and
/// `model` at one line (over the outputs): `|t^H m|^2 / ((t^H t)(m^H m))`, as [`frac`].
///
/// # Errors
/// As [`frac`].
pub fn csac(test: &[c64], model: &[c64]) -> Result<f64, CorrelateError> {
    assurance("CSAC", test, model).map(|(c, _, _)| c)
}

/// The cross-signature scale factor at one line: `2 |t^H m| / (t^H t + m^H m)`, 1 only when the
/// deflections agree in shape and amplitude.
///
/// # Errors
/// As [`frac`].
pub fn csf(test: &[c64], model: &[c64]) -> Result<f64, CorrelateError> {
    let (_, tm, (tt, mm)) = assurance("CSF", test, model)?;
    Ok(2.0 * tm / (tt + mm))
}

/// `(|t^H m|^2 / (t^H t m^H m), |t^H m|, (t^H t, m^H m))`.
fn assurance(
    what: &'static str,
    test: &[c64],
    model: &[c64],
) -> Result<(f64, f64, (f64, f64)), CorrelateError> {
    if test.len() != model.len() {
        return Err(CorrelateError::DimensionMismatch {
            what,
            expected: test.len(),
            got: model.len(),
        });
    }
    let (tt, mm) = (norm2(test), norm2(model));
    if !(tt > 0.0 && mm > 0.0 && tt.is_finite() && mm.is_finite()) {
        return Err(CorrelateError::Invalid {
            what,
            reason: "a response that is zero or not finite has no shape to compare".into(),
        });
    }
    let tm = dot(test, model);
    let a = (tm.re * tm.re + tm.im * tm.im).sqrt();
    Ok((a * a / (tt * mm), a, (tt, mm)))
}
