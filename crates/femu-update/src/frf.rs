//! Localisation and updating from measured frequency responses: the paper's FRF residue (4) on
//! responses expanded at each line, and SB-EBE on FRF data (docs/MATH.md, "The FRF residue" and
//! "Updating from frequency responses").
//!
//! At each line `w` the test measured the receptance `H_a` (measured DOFs `a`) under a unit force
//! at each reference DOF. The model's dynamic stiffness `A(w) = K(p) (1 + i eta) - w^2 M(q)` (or,
//! with Rayleigh damping, `K(p) (1 + i w beta) - w^2 M(q) + i w alpha M(q)`)
//! expands each column on the omitted DOFs by its own equilibrium
//! ([`femu_correlate::expansion::ForcedExpander`]) and leaves the residue
//! `R_a = A_aa u_a + A_ao u_o - f_a` on the measured DOFs. The objective is
//! `J = sum_lines sum_refs ||R_a||_W^2` with `W = diag(M)^-1` on the measured DOFs (the residual
//! force's metric of the modal localisation). Its exact derivative with respect to a parameter
//! `theta_k` (the re-expansion included) is `P (dA/dtheta_k u)`, with
//! `dA/dtheta_k = c_K dK/dtheta_k + c_M dM/dtheta_k` formed element by element, `dA/deta = i K(p)`
//! for a loss factor, `dA/dalpha = i w M(q)` and `dA/dbeta = i w K(p)` for Rayleigh damping: no
//! eigenvector and no mode enters.
//!
//! - [`frf_localise`]: each group's explained fraction of `J` (the fraction its own factor removes,
//!   bounded), the residual force on its DOFs and the strain energy of the displacement residual
//!   `K R_D = R_F`, ranked and selected by the modal localisation's rule.
//! - [`frf_update`]: Gauss-Newton on `J` over the model's parameters and, optionally, the loss
//!   factor, within their bounds, with a backtracking line search.
//! - [`frf_errors`]: the model's receptance against the measured one at each line (the truth check
//!   on lines the fit did not use).

use crate::UpdateError;
use crate::localise::{Localisation, SelectionRule};
use crate::problem::{SparseColumn, UpdateModel};
use faer::{Mat, c64};
use femu_correlate::expansion::{DynamicStiffness, ForcedExpander};
use femu_correlate::frf::{lines_at_once, map_lines};
use femu_sparse::complex::Combination;
use serde::{Deserialize, Serialize};

/// Measured receptances at a model's free DOFs.
#[derive(Debug, Clone, PartialEq)]
pub struct FrfTest {
    /// The lines, rad/s (positive).
    pub omegas: Vec<f64>,
    /// The free DOFs of the responses (sensor order, no repeats).
    pub measured: Vec<usize>,
    /// The free DOF of each reference's unit force.
    pub references: Vec<usize>,
    /// At each line, the receptance (m/N): one row per measured DOF, one column per reference.
    pub receptance: Vec<Mat<c64>>,
}

impl FrfTest {
    /// Checks the sizes and values against a model of `n` free DOFs.
    ///
    /// # Errors
    /// [`UpdateError::Invalid`] naming the line, DOF or value.
    pub fn check(&self, n: usize) -> Result<(), UpdateError> {
        let invalid = |reason: String| UpdateError::Invalid {
            what: "measured FRFs",
            reason,
        };
        if self.omegas.is_empty() {
            return Err(invalid("no frequency line".into()));
        }
        if self.receptance.len() != self.omegas.len() {
            return Err(invalid(format!(
                "{} receptance matrices for {} lines",
                self.receptance.len(),
                self.omegas.len()
            )));
        }
        if let Some(l) = self
            .omegas
            .iter()
            .position(|w| !(w.is_finite() && *w > 0.0))
        {
            return Err(invalid(format!(
                "line {} is {} rad/s: lines must be finite and above 0 Hz",
                l + 1,
                self.omegas[l]
            )));
        }
        if self.references.is_empty() || self.measured.is_empty() {
            return Err(invalid("no response or no reference DOF".into()));
        }
        if let Some(d) = self
            .measured
            .iter()
            .chain(&self.references)
            .find(|d| **d >= n)
        {
            return Err(invalid(format!(
                "DOF {d} is not a free DOF of the model ({n})"
            )));
        }
        for (l, h) in self.receptance.iter().enumerate() {
            if h.nrows() != self.measured.len() || h.ncols() != self.references.len() {
                return Err(invalid(format!(
                    "line {}: {} x {} values for {} responses and {} references",
                    l + 1,
                    h.nrows(),
                    h.ncols(),
                    self.measured.len(),
                    self.references.len()
                )));
            }
            for j in 0..h.ncols() {
                if let Some(i) = h
                    .col(j)
                    .iter()
                    .position(|v| !(v.re.is_finite() && v.im.is_finite()))
                {
                    return Err(invalid(format!(
                        "line {} ({} rad/s), response {} of reference {}: {} is not finite",
                        l + 1,
                        self.omegas[l],
                        i + 1,
                        j + 1,
                        h[(i, j)]
                    )));
                }
            }
        }
        Ok(())
    }

    /// The lines `keep` of this test (in that order).
    pub fn lines(&self, keep: &[usize]) -> FrfTest {
        FrfTest {
            omegas: keep.iter().map(|&l| self.omegas[l]).collect(),
            measured: self.measured.clone(),
            references: self.references.clone(),
            receptance: keep.iter().map(|&l| self.receptance[l].clone()).collect(),
        }
    }

    /// Unit forces at the references (full length `n`, one column per reference).
    fn forces(&self, n: usize) -> Mat<c64> {
        let mut f = Mat::<c64>::zeros(n, self.references.len());
        for (j, &d) in self.references.iter().enumerate() {
            f[(d, j)] = c64::new(1.0, 0.0);
        }
        f
    }
}

/// The model's damping in updating from FRFs: the values are a start when they are fitted.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FrfDamping {
    /// A structural loss factor: `K (1 + i eta)`.
    LossFactor(f64),
    /// Rayleigh damping `C = alpha M + beta K` (s^-1 and s).
    Rayleigh {
        /// The mass coefficient, s^-1.
        alpha: f64,
        /// The stiffness coefficient, s.
        beta: f64,
    },
    /// A structural loss factor per parameter group and one for the rest of the model:
    /// `A = K_rest (1 + i rest) + sum_g K_g(p) (1 + i eta_g) - w^2 M`, `K_g(p)` each group's own
    /// stiffness at its current parameter and `K_rest = K(p) - sum_g K_g(p)` (docs/MATH.md,
    /// "Updating from frequency responses"). The groups must not share an element; a mass
    /// group has no stiffness, and its value acts on nothing.
    GroupLossFactors {
        /// The loss factor of the elements in no group.
        rest: f64,
        /// One loss factor per group, in the model's group order.
        groups: Vec<f64>,
    },
}

impl FrfDamping {
    /// The dynamic stiffness's coefficients at `omega` rad/s.
    /// (per-group loss factors: `K + i D - w^2 M`, `D` from [`FrfDamping::matrix`]).
    pub fn stiffness(&self, omega: f64) -> DynamicStiffness {
        match *self {
            FrfDamping::LossFactor(eta) => DynamicStiffness::loss_factor(omega, eta),
            FrfDamping::Rayleigh { alpha, beta } => DynamicStiffness::rayleigh(omega, alpha, beta),
            FrfDamping::GroupLossFactors { .. } => DynamicStiffness::structural(omega),
        }
    }

    /// The structural damping matrix of per-group loss factors on `K`'s pattern,
    /// `D = rest K(p) + sum_g (eta_g - rest) K_g(p)`; `None` for the other forms.
    ///
    /// # Errors
    /// A number of loss factors other than the model's groups.
    pub fn matrix(
        &self,
        up: &UpdateModel<'_>,
    ) -> Result<Option<femu_sparse::SparseMatrix>, UpdateError> {
        match self {
            FrfDamping::GroupLossFactors { rest, groups } => {
                let c: Vec<f64> = groups.iter().map(|g| g - rest).collect();
                Ok(Some(up.group_stiffness_matrix(*rest, &c)?))
            }
            _ => Ok(None),
        }
    }

    /// The values, in the order of the fit's damping parameters.
    fn values(&self) -> Vec<f64> {
        match self {
            FrfDamping::LossFactor(eta) => vec![*eta],
            FrfDamping::Rayleigh { alpha, beta } => vec![*alpha, *beta],
            FrfDamping::GroupLossFactors { rest, groups } => std::iter::once(*rest)
                .chain(groups.iter().copied())
                .collect(),
        }
    }

    /// The same form with `v` (as [`FrfDamping::values`]).
    fn with_values(&self, v: &[f64]) -> Self {
        match self {
            FrfDamping::LossFactor(_) => FrfDamping::LossFactor(v[0]),
            FrfDamping::Rayleigh { .. } => FrfDamping::Rayleigh {
                alpha: v[0],
                beta: v[1],
            },
            FrfDamping::GroupLossFactors { .. } => FrfDamping::GroupLossFactors {
                rest: v[0],
                groups: v[1..].to_vec(),
            },
        }
    }

    /// The bounds of the values: a loss factor in `[0, 1]`, Rayleigh coefficients at least 0.
    fn bounds(&self) -> Vec<(f64, f64)> {
        match self {
            FrfDamping::LossFactor(_) => vec![(0.0, 1.0)],
            FrfDamping::Rayleigh { .. } => vec![(0.0, f64::INFINITY); 2],
            FrfDamping::GroupLossFactors { groups, .. } => vec![(0.0, 1.0); 1 + groups.len()],
        }
    }

    /// Checks the values ([`FrfDamping::check`]) and, for per-group loss factors, that they are
    /// one per group of `up` and that no two groups share an element or a structural element.
    ///
    /// # Errors
    /// [`UpdateError::Invalid`] naming the value or the two groups.
    pub fn check_for(&self, up: &UpdateModel<'_>) -> Result<(), UpdateError> {
        self.check()?;
        let FrfDamping::GroupLossFactors { groups, .. } = self else {
            return Ok(());
        };
        let all = up.groups();
        if groups.len() != all.len() {
            return Err(UpdateError::Invalid {
                what: "damping",
                reason: format!(
                    "{} per-group loss factors for {} groups",
                    groups.len(),
                    all.len()
                ),
            });
        }
        let mut owner: std::collections::HashMap<(bool, usize), usize> =
            std::collections::HashMap::new();
        for (g, group) in all.iter().enumerate() {
            let items = group
                .elements
                .iter()
                .map(|e| (false, *e))
                .chain(group.structural.iter().map(|e| (true, *e)));
            for item in items {
                if let Some(h) = owner.insert(item, g)
                    && h != g
                {
                    return Err(UpdateError::Invalid {
                        what: "damping",
                        reason: format!(
                            "groups {} and {} share an element: a loss factor per group needs groups apart",
                            all[h].name, group.name
                        ),
                    });
                }
            }
        }
        Ok(())
    }

    /// Checks the values.
    ///
    /// # Errors
    /// [`UpdateError::Invalid`]: a loss factor outside `[0, 1]`, a negative or non-finite
    /// Rayleigh coefficient.
    pub fn check(&self) -> Result<(), UpdateError> {
        let ok = self
            .values()
            .iter()
            .zip(self.bounds())
            .all(|(v, (lo, hi))| v.is_finite() && *v >= lo && *v <= hi);
        if ok {
            Ok(())
        } else {
            Err(UpdateError::Invalid {
                what: "damping",
                reason: match self {
                    FrfDamping::LossFactor(eta) => {
                        format!("a loss factor of {eta}: a structural loss factor is in [0, 1]")
                    }
                    FrfDamping::Rayleigh { alpha, beta } => format!(
                        "Rayleigh coefficients {alpha}, {beta}: both must be finite and at least 0"
                    ),
                    FrfDamping::GroupLossFactors { rest, groups } => format!(
                        "loss factors {rest} (the rest) and {groups:?} (the groups): each is in [0, 1]"
                    ),
                },
            })
        }
    }

    /// `dA/dd u` for each damping value `d` at `omega`: `i K u` for a loss factor, `i w M u` and
    /// `i w K u` for Rayleigh's `alpha` and `beta`.
    fn columns(
        &self,
        up: &UpdateModel<'_>,
        omega: f64,
        u: &[c64],
    ) -> Result<Vec<Vec<c64>>, UpdateError> {
        let sys = up.matrices();
        let n = u.len();
        let re: Vec<f64> = u.iter().map(|v| v.re).collect();
        let im: Vec<f64> = u.iter().map(|v| v.im).collect();
        // i s A u for a real matrix A and a real factor s
        let times = |a: &femu_sparse::SparseMatrix, s: f64| -> Result<Vec<c64>, UpdateError> {
            let (mut ar, mut ai) = (vec![0.0; n], vec![0.0; n]);
            femu_sparse::csc::mul_vec(a, &re, &mut ar)?;
            femu_sparse::csc::mul_vec(a, &im, &mut ai)?;
            Ok(ar
                .iter()
                .zip(&ai)
                .map(|(r, i)| c64::new(-s * i, s * r))
                .collect())
        };
        Ok(match self {
            FrfDamping::LossFactor(_) => vec![times(&sys.k, 1.0)?],
            FrfDamping::Rayleigh { .. } => vec![times(&sys.m, omega)?, times(&sys.k, omega)?],
            FrfDamping::GroupLossFactors { .. } => {
                // i K_g(p) u per group, and i (K(p) - sum_g K_g(p)) u for the rest
                let mut rest = times(&sys.k, 1.0)?;
                let (cr, ci) = (
                    up.group_stiffness_columns(&re)?,
                    up.group_stiffness_columns(&im)?,
                );
                let mut out = vec![Vec::new()];
                for (r, i) in cr.iter().zip(&ci) {
                    let mut v = vec![c64::new(0.0, 0.0); n];
                    for (idx, &d) in r.dofs.iter().enumerate() {
                        let kv = c64::new(-i.values[idx], r.values[idx]);
                        v[d] = kv;
                        rest[d] -= kv;
                    }
                    out.push(v);
                }
                out[0] = rest;
                out
            }
        })
    }
}

impl std::fmt::Display for FrfDamping {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FrfDamping::LossFactor(eta) => write!(f, "loss factor {eta:.5}"),
            FrfDamping::Rayleigh { alpha, beta } => {
                write!(f, "Rayleigh alpha {alpha:.5e} s^-1, beta {beta:.5e} s")
            }
            FrfDamping::GroupLossFactors { rest, groups } => {
                write!(f, "loss factors per group")?;
                for (g, eta) in groups.iter().enumerate() {
                    write!(f, " {}: {eta:.5}", g + 1)?;
                }
                write!(f, ", the rest {rest:.5}")
            }
        }
    }
}

/// What the FRF fit minimises.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FrfMethod {
    /// SB-EBE on FRF data (the paper's): the residue (4) of the responses expanded at each line,
    /// `sum ||R_a||_W^2`. Quadratic in a stiffness factor's effect on each line (no resonance
    /// has to be matched first), exact without noise; measurement noise enters multiplied by
    /// the dynamic stiffness, which biases it when many groups are fitted from noisy data.
    SbEbe,
    /// The output error: the model's receptance against the measured one,
    /// `sum |H_model - H_test|^2 / max(|H_test|, 1 % of the function's peak)^2` (relative, with a
    /// floor at anti-resonances), its derivative `-[A^-1 (dA/dtheta) u]_a` from the line's
    /// factorization. Unbiased under relative noise; needs a start whose resonances are within
    /// a few bandwidths of the test's (the default starts it from SB-EBE).
    #[default]
    OutputError,
}

/// Which derivative columns an evaluation of the objective forms.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Columns {
    /// None: the objective alone.
    None,
    /// One per parameter of the model (and the damping's values when they are fitted).
    Parameters { damping: bool },
    /// One per group (the localisation's).
    Groups,
}

/// The objective, its normal equations and what localisation needs, summed over the lines.
struct Evaluation {
    objective: f64,
    /// `sum Re(B^H W B)` over the lines and references.
    gram: Vec<Vec<f64>>,
    /// `sum Re(B^H W R)`.
    num: Vec<f64>,
    /// The residues on the measured DOFs, per line (measured x references).
    residuals: Vec<Mat<c64>>,
    /// The largest backward error of the lines' solves.
    backward_error: f64,
}

/// `dA/dtheta u` for each column family at one line: `c_K K' u + c_M M' u`, with `K' x`
/// and `M' x` from the model's element-by-element columns at `lambda = 0` and `lambda = 1`.
fn derivative_columns(
    up: &UpdateModel<'_>,
    which: Columns,
    damping: &FrfDamping,
    omega: f64,
    u: &[c64],
) -> Result<Vec<Vec<c64>>, UpdateError> {
    let a = damping.stiffness(omega);
    let n = u.len();
    let re: Vec<f64> = u.iter().map(|v| v.re).collect();
    let im: Vec<f64> = u.iter().map(|v| v.im).collect();
    let cols = |x: &[f64], lambda: f64| -> Result<Vec<SparseColumn>, UpdateError> {
        match which {
            Columns::Groups => up.group_columns(x, lambda),
            _ => up.columns(x, lambda),
        }
    };
    let (k_re, k_im) = (cols(&re, 0.0)?, cols(&im, 0.0)?);
    let (l_re, l_im) = (cols(&re, 1.0)?, cols(&im, 1.0)?);
    // per-group loss factors damp each group's stiffness change by its own factor:
    // dA/dp_g = (1 + i eta_g) K_g'
    let group_of = |c: usize| match which {
        Columns::Groups => c,
        _ => up.parameters()[c].group,
    };
    let k_coefficient = |c: usize| match damping {
        FrfDamping::GroupLossFactors { groups, .. } => c64::new(1.0, groups[group_of(c)]),
        _ => a.k,
    };
    let mut out = Vec::with_capacity(k_re.len() + 1);
    for c in 0..k_re.len() {
        let ck = k_coefficient(c);
        let mut v = vec![c64::new(0.0, 0.0); n];
        // K' u and M' u = (col(0) - col(1)) u, real and imaginary parts on the group's DOFs
        for (idx, &d) in k_re[c].dofs.iter().enumerate() {
            let ku = c64::new(k_re[c].values[idx], k_im[c].values[idx]);
            let mu = c64::new(
                k_re[c].values[idx] - l_re[c].values[idx],
                k_im[c].values[idx] - l_im[c].values[idx],
            );
            v[d] = ck * ku + a.m * mu;
        }
        out.push(v);
    }
    if let Columns::Parameters { damping: true } = which {
        out.extend(damping.columns(up, omega, u)?);
    }
    Ok(out)
}

/// The objective (and, with `which`, its normal equations) at the model's current parameters and
/// the damping `damping`.
fn evaluate(
    up: &UpdateModel<'_>,
    test: &FrfTest,
    damping: &FrfDamping,
    which: Columns,
    method: FrfMethod,
) -> Result<Evaluation, UpdateError> {
    match method {
        FrfMethod::SbEbe => evaluate_residue(up, test, damping, which),
        FrfMethod::OutputError => evaluate_output(up, test, damping, which),
    }
}

/// Sums per-line evaluations.
fn total(per_line: Vec<Result<Evaluation, UpdateError>>) -> Result<Evaluation, UpdateError> {
    let mut total = Evaluation {
        objective: 0.0,
        gram: Vec::new(),
        num: Vec::new(),
        residuals: Vec::with_capacity(per_line.len()),
        backward_error: 0.0,
    };
    for e in per_line {
        let e = e?;
        total.objective += e.objective;
        total.backward_error = total.backward_error.max(e.backward_error);
        if total.gram.is_empty() {
            total.gram = e.gram;
            total.num = e.num;
        } else {
            for (a, b) in total.num.iter_mut().zip(&e.num) {
                *a += b;
            }
            for (ra, rb) in total.gram.iter_mut().zip(&e.gram) {
                for (a, b) in ra.iter_mut().zip(rb) {
                    *a += b;
                }
            }
        }
        total.residuals.extend(e.residuals);
    }
    Ok(total)
}

/// Adds `Re(B^H W B)` and `Re(B^H W r)` of one load case to `gram` and `num` (sized on first
/// use).
fn accumulate(gram: &mut Vec<Vec<f64>>, num: &mut Vec<f64>, b: &Mat<c64>, r: &[c64], w: &[f64]) {
    let p = b.ncols();
    if gram.is_empty() {
        *gram = vec![vec![0.0; p]; p];
        *num = vec![0.0; p];
    }
    for c in 0..p {
        num[c] += (0..w.len())
            .map(|i| w[i] * (b[(i, c)].conj() * r[i]).re)
            .sum::<f64>();
        for c2 in c..p {
            let g: f64 = (0..w.len())
                .map(|i| w[i] * (b[(i, c)].conj() * b[(i, c2)]).re)
                .sum();
            gram[c][c2] += g;
            if c2 != c {
                gram[c2][c] += g;
            }
        }
    }
}

/// The output error's weights: `1 / max(|H_test|, 1 % of the function's peak over the lines)^2`,
/// per line, response and reference.
fn output_weights(test: &FrfTest) -> Vec<Mat<f64>> {
    let (rows, cols) = (test.measured.len(), test.references.len());
    let peak = Mat::from_fn(rows, cols, |i, j| {
        test.receptance
            .iter()
            .map(|h| h[(i, j)].norm())
            .fold(0.0, f64::max)
    });
    test.receptance
        .iter()
        .map(|h| {
            Mat::from_fn(rows, cols, |i, j| {
                let s = h[(i, j)].norm().max(0.01 * peak[(i, j)]);
                if s > 0.0 { 1.0 / (s * s) } else { 0.0 }
            })
        })
        .collect()
}

/// The output error at the model's current parameters (see [`FrfMethod::OutputError`]).
fn evaluate_output(
    up: &UpdateModel<'_>,
    test: &FrfTest,
    damping: &FrfDamping,
    which: Columns,
) -> Result<Evaluation, UpdateError> {
    let sys = up.matrices();
    let n = sys.dofs.free_count();
    test.check(n)?;
    let weights = output_weights(test);
    let d = damping.matrix(up)?;
    let combination = combination_of(&sys.k, &sys.m, d.as_ref())?;
    let f = test.forces(n);
    let lines = test.omegas.len();
    let at_once = lines_at_once(combination.factor_len(), lines);
    let per_line: Vec<Result<Evaluation, UpdateError>> = map_lines(lines, at_once, |l| {
        let omega = test.omegas[l];
        let a = damping.stiffness(omega);
        let mut factor = factor_line(&combination, a).map_err(|e| at_line(e.into(), l, omega))?;
        let mut u = f.clone();
        let mut backward_error = factor
            .solve_in_place(u.as_mut())
            .map_err(|e| at_line(e.into(), l, omega))?;
        let h = &test.receptance[l];
        let r = Mat::from_fn(h.nrows(), h.ncols(), |i, j| {
            u[(test.measured[i], j)] - h[(i, j)]
        });
        let mut objective = 0.0;
        for j in 0..r.ncols() {
            for i in 0..r.nrows() {
                objective += weights[l][(i, j)] * r[(i, j)].norm_sqr();
            }
        }
        let (mut gram, mut num) = (Vec::new(), Vec::new());
        if which != Columns::None {
            for j in 0..r.ncols() {
                let uj: Vec<c64> = u.col(j).iter().copied().collect();
                let v = derivative_columns(up, which, damping, omega, &uj)?;
                let mut z = Mat::from_fn(n, v.len(), |i, c| v[c][i]);
                backward_error = backward_error.max(
                    factor
                        .solve_in_place(z.as_mut())
                        .map_err(|e| at_line(e.into(), l, omega))?,
                );
                // dH/dtheta = -[A^-1 (dA/dtheta) u]_a
                let b = Mat::from_fn(r.nrows(), v.len(), |i, c| -z[(test.measured[i], c)]);
                let rj: Vec<c64> = r.col(j).iter().copied().collect();
                let w: Vec<f64> = (0..r.nrows()).map(|i| weights[l][(i, j)]).collect();
                accumulate(&mut gram, &mut num, &b, &rj, &w);
            }
        }
        Ok(Evaluation {
            objective,
            gram,
            num,
            residuals: vec![r],
            backward_error,
        })
    });
    total(per_line)
}

/// The residue objective at the model's current parameters (see [`FrfMethod::SbEbe`]).
fn evaluate_residue(
    up: &UpdateModel<'_>,
    test: &FrfTest,
    damping: &FrfDamping,
    which: Columns,
) -> Result<Evaluation, UpdateError> {
    let sys = up.matrices();
    let n = sys.dofs.free_count();
    test.check(n)?;
    let w_inv = femu_correlate::expansion::residual_metric(&sys.m)?;
    let w: Vec<f64> = test.measured.iter().map(|&d| 1.0 / w_inv[d]).collect();
    let d = damping.matrix(up)?;
    let forced = match &d {
        Some(d) => ForcedExpander::with_damping_matrix(&sys.k, &sys.m, d, &test.measured)?,
        None => ForcedExpander::new(&sys.k, &sys.m, &test.measured)?,
    };
    let f = test.forces(n);
    let lines = test.omegas.len();
    let at_once = lines_at_once(forced.factor_len(), lines);
    let per_line: Vec<Result<Evaluation, UpdateError>> = map_lines(lines, at_once, |l| {
        let a = damping.stiffness(test.omegas[l]);
        let mut line = forced.line(a).map_err(|e| at_line(e, l, test.omegas[l]))?;
        let e = line
            .expand(test.receptance[l].as_ref(), f.as_ref())
            .map_err(|e| at_line(e, l, test.omegas[l]))?;
        let r = e.residual;
        let mut objective = 0.0;
        for j in 0..r.ncols() {
            for (i, wi) in w.iter().enumerate() {
                objective += wi * r[(i, j)].norm_sqr();
            }
        }
        let (mut gram, mut num) = (Vec::new(), Vec::new());
        if which != Columns::None {
            for j in 0..r.ncols() {
                let u: Vec<c64> = e.u.col(j).iter().copied().collect();
                let v = derivative_columns(up, which, damping, test.omegas[l], &u)?;
                let vm = Mat::from_fn(n, v.len(), |i, c| v[c][i]);
                let b = line.project(vm.as_ref())?;
                let rj: Vec<c64> = r.col(j).iter().copied().collect();
                accumulate(&mut gram, &mut num, &b, &rj, &w);
            }
        }
        Ok(Evaluation {
            objective,
            gram,
            num,
            residuals: vec![r],
            backward_error: line.backward_error(),
        })
    });
    total(per_line)
}

/// `K` and `M` (and the structural damping matrix `D` of per-group loss factors) analysed once for
/// the lines' complex factorizations.
fn combination_of(
    k: &femu_sparse::SparseMatrix,
    m: &femu_sparse::SparseMatrix,
    d: Option<&femu_sparse::SparseMatrix>,
) -> Result<Combination, UpdateError> {
    Ok(match d {
        Some(d) => Combination::new(&[k, m, d], &["K", "M", "D"])?,
        None => Combination::new(&[k, m], &["K", "M"])?,
    })
}

/// One line's dynamic stiffness factored on [`combination_of`]'s analysis.
fn factor_line(
    combination: &Combination,
    a: DynamicStiffness,
) -> Result<femu_sparse::complex::Factored<'_>, femu_sparse::SparseError> {
    if combination.matrices() == 3 {
        combination.factor(&[a.k, a.m, a.d])
    } else {
        combination.factor(&[a.k, a.m])
    }
}

fn at_line(e: femu_correlate::CorrelateError, l: usize, omega: f64) -> UpdateError {
    UpdateError::Invalid {
        what: "FRF residue",
        reason: format!(
            "line {} ({:.6} Hz): {e}",
            l + 1,
            omega / (2.0 * std::f64::consts::PI)
        ),
    }
}

/// Localisation from measured FRFs: every group's indicators from the residues (4) of the
/// responses expanded at each line with the damping `damping`, ranked and selected by `rule`
/// (its `test_error` does not apply: the measured values are imposed). The explained fraction
/// (the default indicator) is the fraction of `J` the group's own factor removes within its
/// bounds; [`Localisation::joint_fit`] fits several together from the same normal equations.
///
/// # Errors
/// The test's sizes and values, a bad rule, a singular line (undamped, at an eigenvalue of the
/// structure with its measured DOFs held), the static solve of the strain energy.
pub fn frf_localise(
    up: &UpdateModel<'_>,
    test: &FrfTest,
    damping: &FrfDamping,
    rule: &SelectionRule,
) -> Result<Localisation, UpdateError> {
    crate::localise::check_rule(rule)?;
    damping.check_for(up)?;
    let e = evaluate_residue(up, test, damping, Columns::Groups)?;
    let sys = up.matrices();
    let n = sys.dofs.free_count();
    let w_inv = femu_correlate::expansion::residual_metric(&sys.m)?;
    let groups = up.groups().len();
    // residual force on each group's DOFs, and the strain energy of K R_D = R_F
    let mut force = vec![0.0; groups];
    let mut r_f = Mat::<f64>::zeros(n, 2 * e.residuals.iter().map(|r| r.ncols()).sum::<usize>());
    let mut c = 0;
    let mut on_dof = vec![0.0; n];
    for r in &e.residuals {
        for j in 0..r.ncols() {
            for (i, &d) in test.measured.iter().enumerate() {
                r_f[(d, c)] = r[(i, j)].re;
                r_f[(d, c + 1)] = r[(i, j)].im;
                on_dof[d] += r[(i, j)].norm_sqr() / w_inv[d];
            }
            c += 2;
        }
    }
    for (g, f) in force.iter_mut().enumerate() {
        *f = up.group_dofs(g).iter().map(|&d| on_dof[d]).sum();
    }
    let solver = femu_correlate::StiffnessSolver::new(&sys.k, &sys.m)?;
    let r_d = solver.displacement_residuals(r_f.as_ref())?;
    let ones = vec![1.0; n];
    let mut energy = vec![0.0; groups];
    for j in 0..r_d.ncols() {
        let rd: Vec<f64> = r_d.col(j).iter().copied().collect();
        for (g, col) in up.group_columns(&rd, 0.0)?.iter().enumerate() {
            energy[g] += col.weighted_dot_full(&rd, &ones);
        }
    }
    let bounds = crate::localise::stiffness_bounds(up);
    let explained = (0..groups)
        .map(|g| {
            crate::localise::explained_fraction(
                e.num.get(g).copied().unwrap_or(0.0),
                e.gram.get(g).map_or(0.0, |row| row[g]),
                e.objective,
                bounds[g],
            )
        })
        .collect();
    let mut loc = crate::localise::rank(up, energy, force, explained, rule);
    loc.normal = Some((e.gram, e.num, e.objective));
    Ok(loc)
}

/// The settings of [`frf_update`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrfUpdateOptions {
    /// The model's damping (the start when it is fitted; default a loss factor of 0.02).
    pub damping: FrfDamping,
    /// Fit the damping's values with the parameters (default true).
    pub fit_damping: bool,
    /// At most this many Gauss-Newton steps (default 30).
    pub max_iterations: usize,
    /// Stop when a step lowers the objective by less than this fraction (default 1e-8).
    pub tolerance: f64,
    /// What is minimised (default: the output error, started from SB-EBE's solution).
    pub method: FrfMethod,
}

impl Default for FrfUpdateOptions {
    fn default() -> Self {
        Self {
            damping: FrfDamping::LossFactor(0.02),
            fit_damping: true,
            max_iterations: 30,
            tolerance: 1e-8,
            method: FrfMethod::OutputError,
        }
    }
}

/// One step of [`frf_update`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrfIteration {
    /// The objective minimised by the step.
    pub method: FrfMethod,
    /// The objective before the step.
    pub objective: f64,
    /// The parameters before the step.
    pub theta: Vec<f64>,
    /// The damping before the step.
    pub damping: FrfDamping,
}

/// What [`frf_update`] found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrfUpdate {
    /// Parameter names (the model's).
    pub names: Vec<String>,
    /// The model's group names (those of per-group loss factors, in their order).
    pub groups: Vec<String>,
    /// The updated parameters.
    pub theta: Vec<f64>,
    /// The updated (or given) damping.
    pub damping: FrfDamping,
    /// The objective minimised last.
    pub method: FrfMethod,
    /// That objective at the start and at the end.
    pub objective: (f64, f64),
    /// Every step's starting point.
    pub history: Vec<FrfIteration>,
    /// Whether the steps stopped by the tolerance (not by the iteration limit).
    pub converged: bool,
    /// The largest backward error of the lines' complex solves at the end.
    pub backward_error: f64,
}

impl std::fmt::Display for FrfUpdate {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "{} on FRFs: objective {:.4e} -> {:.4e} in {} steps{}",
            match self.method {
                FrfMethod::SbEbe => "SB-EBE",
                FrfMethod::OutputError => "SB-EBE, then the output error,",
            },
            self.objective.0,
            self.objective.1,
            self.history.len(),
            if self.converged {
                ""
            } else {
                " (iteration limit)"
            }
        )?;
        for (n, t) in self.names.iter().zip(&self.theta) {
            writeln!(f, "  {n:<16} {t:+.4}")?;
        }
        match &self.damping {
            FrfDamping::GroupLossFactors { rest, groups } => {
                for (n, eta) in self.groups.iter().zip(groups) {
                    writeln!(f, "  loss factor of {n}: {eta:.5}")?;
                }
                write!(f, "  loss factor of the rest: {rest:.5}")
            }
            other => write!(f, "  damping: {other}"),
        }
    }
}

/// Updating from FRF data: Gauss-Newton over the model's parameters (stiffness, mass or
/// thickness of its groups, as built) and, when asked, the damping (a loss factor or Rayleigh's
/// two coefficients), each step the
/// least-squares solution of the linearised objective (the re-expansion included for SB-EBE)
/// clamped to the bounds, shortened by halves until the objective decreases. With
/// [`FrfMethod::OutputError`] (the default) SB-EBE runs first and the output error continues
/// from its solution: SB-EBE needs no resonance matched to start, the output error is unbiased
/// under noise. The model is left at the updated parameters.
///
/// # Errors
/// The test's sizes and values, damping out of its bounds ([`FrfDamping::check`]), a singular
/// line.
pub fn frf_update(
    up: &mut UpdateModel<'_>,
    test: &FrfTest,
    options: &FrfUpdateOptions,
) -> Result<FrfUpdate, UpdateError> {
    frf_update_logged(up, test, options, |_| {})
}

/// [`frf_update`], with `log` told of every step before it is taken (progress on long runs).
///
/// # Errors
/// As [`frf_update`].
pub fn frf_update_logged(
    up: &mut UpdateModel<'_>,
    test: &FrfTest,
    options: &FrfUpdateOptions,
    mut log: impl FnMut(&FrfIteration),
) -> Result<FrfUpdate, UpdateError> {
    options.damping.check_for(up)?;
    test.check(up.matrices().dofs.free_count())?;
    let stages: &[FrfMethod] = match options.method {
        FrfMethod::SbEbe => &[FrfMethod::SbEbe],
        FrfMethod::OutputError => &[FrfMethod::SbEbe, FrfMethod::OutputError],
    };
    let start = evaluate(up, test, &options.damping, Columns::None, options.method)?.objective;
    let mut damping = options.damping.clone();
    let mut history = Vec::new();
    let mut end = (start, 0.0, true);
    for &method in stages {
        end = gauss_newton(
            up,
            test,
            options,
            method,
            &mut damping,
            &mut history,
            &mut log,
        )?;
    }
    let (objective, backward_error, converged) = end;
    Ok(FrfUpdate {
        names: up.parameters().iter().map(|p| p.name.clone()).collect(),
        groups: up.groups().iter().map(|g| g.name.clone()).collect(),
        theta: up.theta(),
        damping,
        method: options.method,
        objective: (start, objective),
        history,
        converged,
        backward_error,
    })
}

/// Gauss-Newton steps of `method` from the model's parameters and `damping`; returns the final
/// objective, the largest backward error at the end and whether the tolerance stopped it.
fn gauss_newton(
    up: &mut UpdateModel<'_>,
    test: &FrfTest,
    options: &FrfUpdateOptions,
    method: FrfMethod,
    damping: &mut FrfDamping,
    history: &mut Vec<FrfIteration>,
    log: &mut dyn FnMut(&FrfIteration),
) -> Result<(f64, f64, bool), UpdateError> {
    let fit = options.fit_damping;
    let which = Columns::Parameters { damping: fit };
    let mut bounds: Vec<(f64, f64)> = up.parameters().iter().map(|p| (p.lower, p.upper)).collect();
    if fit {
        bounds.extend(damping.bounds());
    }
    let mut theta = up.theta();
    let mut e = evaluate(up, test, damping, which, method)?;
    for _ in 0..options.max_iterations {
        let step = FrfIteration {
            method,
            objective: e.objective,
            theta: theta.clone(),
            damping: damping.clone(),
        };
        log(&step);
        history.push(step);
        if e.objective == 0.0 {
            return Ok((0.0, e.backward_error, true));
        }
        // the step of the Jacobi-scaled normal equations: the parameters' columns differ in
        // scale by orders of magnitude (a stiffness factor, a loss factor, Rayleigh's alpha in
        // s^-1 and beta in s)
        let p = e.num.len();
        let d: Vec<f64> = (0..p)
            .map(|a| {
                let g = e.gram[a][a];
                if g > 0.0 { 1.0 / g.sqrt() } else { 0.0 }
            })
            .collect();
        let g = Mat::from_fn(p, p, |a, b| d[a] * e.gram[a][b] * d[b]);
        let (inverse, _) = crate::lsq::symmetric_pseudo_inverse(g.as_ref())?;
        let step: Vec<f64> = (0..p)
            .map(|a| {
                -d[a]
                    * (0..p)
                        .map(|b| inverse[(a, b)] * d[b] * e.num[b])
                        .sum::<f64>()
            })
            .collect();
        let mut current: Vec<f64> = theta.clone();
        if fit {
            current.extend(damping.values());
        }
        let mut accepted = None;
        let mut s = 1.0;
        for _ in 0..8 {
            let trial: Vec<f64> = current
                .iter()
                .zip(&step)
                .zip(&bounds)
                .map(|((c, d), (lo, hi))| (c + s * d).clamp(*lo, *hi))
                .collect();
            let (t, et) = split(&trial, theta.len(), damping);
            up.set_theta(&t)?;
            // the trial with its normal equations: accepted (the usual case, at the full step),
            // it is the next step's evaluation, and its lines are factored once
            let at_trial = evaluate(up, test, &et, which, method)?;
            if at_trial.objective < e.objective {
                accepted = Some((t, et, at_trial));
                break;
            }
            s *= 0.5;
        }
        let Some((t, et, at_trial)) = accepted else {
            up.set_theta(&theta)?;
            return Ok((e.objective, e.backward_error, true));
        };
        let decrease = (e.objective - at_trial.objective) / e.objective;
        theta = t;
        *damping = et;
        e = at_trial;
        if decrease < options.tolerance {
            return Ok((e.objective, e.backward_error, true));
        }
    }
    Ok((e.objective, e.backward_error, false))
}

/// The parameters and the damping of a stacked vector.
fn split(v: &[f64], params: usize, damping: &FrfDamping) -> (Vec<f64>, FrfDamping) {
    let d = if v.len() > params {
        damping.with_values(&v[params..])
    } else {
        damping.clone()
    };
    (v[..params].to_vec(), d)
}

/// The model's receptance at the test's DOFs against the measured one, per line:
/// `||H_model - H_test||_F / ||H_test||_F`, the model solved directly with the damping (one
/// complex factorization per line). The truth check of an FRF update on lines it did not
/// use.
///
/// # Errors
/// The test's sizes and values, a loss factor outside `[0, 1]`, a singular line.
pub fn frf_errors(
    up: &UpdateModel<'_>,
    test: &FrfTest,
    damping: &FrfDamping,
) -> Result<Vec<f64>, UpdateError> {
    damping.check_for(up)?;
    let sys = up.matrices();
    let n = sys.dofs.free_count();
    test.check(n)?;
    let d = damping.matrix(up)?;
    let combination = combination_of(&sys.k, &sys.m, d.as_ref())?;
    let f = test.forces(n);
    let lines = test.omegas.len();
    let at_once = lines_at_once(combination.factor_len(), lines);
    map_lines(lines, at_once, |l| {
        let a = damping.stiffness(test.omegas[l]);
        let mut factor = factor_line(&combination, a)?;
        let mut u = f.clone();
        factor.solve_in_place(u.as_mut())?;
        let h = &test.receptance[l];
        let (mut diff, mut norm) = (0.0, 0.0);
        for j in 0..h.ncols() {
            for (i, &d) in test.measured.iter().enumerate() {
                diff += (u[(d, j)] - h[(i, j)]).norm_sqr();
                norm += h[(i, j)].norm_sqr();
            }
        }
        Ok((diff / norm).sqrt())
    })
    .into_iter()
    .collect()
}
