//! The forced residue (4) of measured frequency responses: responses known on the measured DOFs
//! `a` under a known harmonic force, filled in on the omitted DOFs by the model's own equilibrium
//! at the line, and what is left out of balance on `a` (docs/MATH.md, "The FRF residue").
//!
//! At a line `w` the model's dynamic stiffness is `A = c_K K + c_M M` (undamped
//! `c_K = 1, c_M = -w^2`; a structural loss factor makes `c_K = 1 + i eta`; Rayleigh damping
//! `alpha M + beta K` adds `i w beta` to `c_K` and `i w alpha` to `c_M`), plus `c_D D` for a
//! structural damping matrix `D` on `K`'s pattern (per-group loss factors, `c_D = i`). The response `u_a` the
//! test measured under the force `f` is expanded by
//! `u_o = A_oo^-1 (f_o - A_oa u_a)` (the forced counterpart of dynamic expansion), so that the
//! residue `R_F = A u - f` (the paper's (4)) vanishes on `o` and is `R_a = A_aa u_a + A_ao u_o - f_a`
//! on the measured DOFs: zero when the model reproduces the measured response exactly.
//!
//! When `A` changes by `dA` (an updating parameter), the residue of the re-expanded response
//! changes by `P (dA u)`, with `P v = v_a - A_ao A_oo^-1 v_o` ([`ForcedLine::project`]): the exact
//! derivative SB-EBE on FRF data uses, with no eigenvector derivative.

use super::Expander;
use crate::CorrelateError;
use faer::{Mat, MatRef, c64};
use femu_sparse::complex::{Combination, Factored};
use femu_sparse::csc::sym_mul_mat;
use femu_sparse::{SparseError, SparseMatrix};

/// The dynamic stiffness `A = k K + m M + d D` at one line (complex coefficients; `D` the
/// structural damping matrix a [`ForcedExpander::with_damping_matrix`] holds, `d = 0` without).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DynamicStiffness {
    /// Coefficient of `K`.
    pub k: c64,
    /// Coefficient of `M`.
    pub m: c64,
    /// Coefficient of the structural damping matrix `D`.
    pub d: c64,
}

impl DynamicStiffness {
    /// `K (1 + i eta) - w^2 M`: a structural loss factor `eta` (0 for none) at `omega` rad/s.
    pub fn loss_factor(omega: f64, eta: f64) -> Self {
        Self {
            k: c64::new(1.0, eta),
            m: c64::new(-omega * omega, 0.0),
            d: c64::new(0.0, 0.0),
        }
    }

    /// `K + i w (alpha M + beta K) - w^2 M`: Rayleigh damping at `omega` rad/s.
    pub fn rayleigh(omega: f64, alpha: f64, beta: f64) -> Self {
        Self {
            k: c64::new(1.0, omega * beta),
            m: c64::new(-omega * omega, omega * alpha),
            d: c64::new(0.0, 0.0),
        }
    }

    /// `K + i D - w^2 M`: the structural damping of the matrix `D` (`sum_g eta_g K_g`, per-group
    /// loss factors) at `omega` rad/s.
    pub fn structural(omega: f64) -> Self {
        Self {
            k: c64::new(1.0, 0.0),
            m: c64::new(-omega * omega, 0.0),
            d: c64::new(0.0, 1.0),
        }
    }

    fn check(&self) -> Result<(), CorrelateError> {
        if [
            self.k.re, self.k.im, self.m.re, self.m.im, self.d.re, self.d.im,
        ]
        .iter()
        .all(|v| v.is_finite())
        {
            Ok(())
        } else {
            Err(CorrelateError::Invalid {
                what: "dynamic stiffness",
                reason: format!(
                    "coefficients {} (of K), {} (of M) and {} (of D) must be finite",
                    self.k, self.m, self.d
                ),
            })
        }
    }
}

/// `A x = c_K K x + c_M M x (+ c_D D x)` for complex `x` (full-length columns).
///
/// # Errors
/// `x` of another length than `K`.
pub fn dynamic_product(
    k: &SparseMatrix,
    m: &SparseMatrix,
    d: Option<&SparseMatrix>,
    a: DynamicStiffness,
    x: MatRef<'_, c64>,
) -> Result<Mat<c64>, CorrelateError> {
    let r = x.ncols();
    // real and imaginary parts side by side: one product with K and one with M
    let parts = Mat::from_fn(x.nrows(), 2 * r, |i, j| {
        if j < r {
            x[(i, j)].re
        } else {
            x[(i, j - r)].im
        }
    });
    let (kx, mx) = (
        sym_mul_mat(k, parts.as_ref())?,
        sym_mul_mat(m, parts.as_ref())?,
    );
    let dx = match d {
        Some(d) if a.d != c64::new(0.0, 0.0) => Some(sym_mul_mat(d, parts.as_ref())?),
        _ => None,
    };
    Ok(Mat::from_fn(x.nrows(), r, |i, j| {
        let kx = c64::new(kx[(i, j)], kx[(i, j + r)]);
        let mx = c64::new(mx[(i, j)], mx[(i, j + r)]);
        let mut v = a.k * kx + a.m * mx;
        if let Some(dx) = &dx {
            v += a.d * c64::new(dx[(i, j)], dx[(i, j + r)]);
        }
        v
    }))
}

/// Forced expansion on one model and one set of measured DOFs: `K_oo` and `M_oo` analysed once
/// (the complex symmetric factorization's ordering and tree), then one numeric factorization of
/// `A_oo` per line ([`ForcedExpander::line`]).
pub struct ForcedExpander<'a> {
    expander: Expander<'a>,
    combination: Combination,
    /// The structural damping matrix `D` on `K`'s pattern, when given.
    damping: Option<&'a SparseMatrix>,
}

impl std::fmt::Debug for ForcedExpander<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ForcedExpander")
            .field("measured", &self.expander.part.measured.len())
            .field("omitted", &self.expander.part.omitted.len())
            .finish()
    }
}

impl<'a> ForcedExpander<'a> {
    /// Prepares the forced expansion of responses measured on the free DOFs `measured` (in
    /// sensor order).
    ///
    /// # Errors
    /// `K` and `M` of other sizes, a measured DOF out of range or repeated, every DOF measured,
    /// an entry of `M` outside `K`'s pattern.
    pub fn new(
        k: &'a SparseMatrix,
        m: &'a SparseMatrix,
        measured: &[usize],
    ) -> Result<Self, CorrelateError> {
        let expander = Expander::with_measured_dofs(k, m, measured)?;
        let (k_oo, m_values) = expander.oo();
        let m_oo = SparseMatrix::new_csc(
            (k_oo.rows(), k_oo.cols()),
            k_oo.indptr().raw_storage().to_vec(),
            k_oo.indices().to_vec(),
            m_values.clone(),
        );
        let combination = Combination::new(&[k_oo, &m_oo], &["K_oo", "M_oo"])?;
        Ok(Self {
            expander,
            combination,
            damping: None,
        })
    }

    /// As [`ForcedExpander::new`], with a structural damping matrix `D` (real symmetric, on `K`'s
    /// pattern exactly: the values of `K`'s stored entries) that each line's
    /// [`DynamicStiffness::d`] multiplies.
    ///
    /// # Errors
    /// As [`ForcedExpander::new`]; `D` of another pattern than `K`'s.
    pub fn with_damping_matrix(
        k: &'a SparseMatrix,
        m: &'a SparseMatrix,
        d: &'a SparseMatrix,
        measured: &[usize],
    ) -> Result<Self, CorrelateError> {
        if d.rows() != k.rows()
            || d.nnz() != k.nnz()
            || d.indptr().raw_storage() != k.indptr().raw_storage()
            || d.indices() != k.indices()
        {
            return Err(CorrelateError::Invalid {
                what: "structural damping matrix",
                reason: format!(
                    "it has {} entries where K has {} (it must be stored on K's pattern)",
                    d.nnz(),
                    k.nnz()
                ),
            });
        }
        let expander = Expander::with_measured_dofs(k, m, measured)?;
        let (k_oo, m_values) = expander.oo();
        let on_pattern = |values: Vec<f64>| {
            SparseMatrix::new_csc(
                (k_oo.rows(), k_oo.cols()),
                k_oo.indptr().raw_storage().to_vec(),
                k_oo.indices().to_vec(),
                values,
            )
        };
        let m_oo = on_pattern(m_values.clone());
        let d_oo = on_pattern(expander.oo_values(d.data()));
        let combination = Combination::new(&[k_oo, &m_oo, &d_oo], &["K_oo", "M_oo", "D_oo"])?;
        Ok(Self {
            expander,
            combination,
            damping: Some(d),
        })
    }

    /// Complex values of one line's factor ([`Combination::factor_len`]).
    pub fn factor_len(&self) -> usize {
        self.combination.factor_len()
    }

    /// The measured DOFs, in sensor order.
    pub fn measured(&self) -> &[usize] {
        &self.expander.part.measured
    }

    /// Factors `A_oo` at one line.
    ///
    /// # Errors
    /// Non-finite coefficients; [`CorrelateError::Invalid`] when `A_oo` is singular (an undamped
    /// line at an eigenvalue of the structure with its measured DOFs held).
    pub fn line(&self, a: DynamicStiffness) -> Result<ForcedLine<'_>, CorrelateError> {
        a.check()?;
        if self.damping.is_none() && a.d != c64::new(0.0, 0.0) {
            return Err(CorrelateError::Invalid {
                what: "forced expansion",
                reason: format!(
                    "a coefficient {} of a structural damping matrix, and no such matrix (ForcedExpander::with_damping_matrix)",
                    a.d
                ),
            });
        }
        let factor = match self.damping {
            Some(_) => self.combination.factor(&[a.k, a.m, a.d]),
            None => self.combination.factor(&[a.k, a.m]),
        }
        .map_err(|e| singular(e, a))?;
        Ok(ForcedLine {
            owner: self,
            a,
            factor,
            backward_error: 0.0,
        })
    }
}

fn singular(e: SparseError, a: DynamicStiffness) -> CorrelateError {
    match e {
        SparseError::Singular { index, .. } => CorrelateError::Invalid {
            what: "forced expansion",
            reason: format!(
                "A_oo = {} K_oo + {} M_oo is singular (omitted DOF {index}): the line is an undamped eigenvalue of the structure with its measured DOFs held; give damping",
                a.k, a.m
            ),
        },
        other => other.into(),
    }
}

/// One line's factored `A_oo`: expansion of measured responses and projection of residue
/// derivatives.
pub struct ForcedLine<'f> {
    owner: &'f ForcedExpander<'f>,
    a: DynamicStiffness,
    factor: Factored<'f>,
    backward_error: f64,
}

impl std::fmt::Debug for ForcedLine<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ForcedLine")
            .field("a", &self.a)
            .field("backward_error", &self.backward_error)
            .finish()
    }
}

/// What [`ForcedLine::expand`] returns.
#[derive(Debug, Clone)]
pub struct ForcedExpansion {
    /// The expanded responses (full length, measured values kept).
    pub u: Mat<c64>,
    /// The residue (4) `R_F = A u - f` on the measured DOFs (sensor order); zero on the omitted
    /// ones by construction.
    pub residual: Mat<c64>,
}

impl ForcedLine<'_> {
    /// The dynamic stiffness of the line.
    pub fn stiffness(&self) -> DynamicStiffness {
        self.a
    }

    /// The largest backward error of this line's solves so far.
    pub fn backward_error(&self) -> f64 {
        self.backward_error
    }

    fn solve_o(&mut self, mut b: Mat<c64>) -> Result<Mat<c64>, CorrelateError> {
        let e = self.factor.solve_in_place(b.as_mut())?;
        self.backward_error = self.backward_error.max(e);
        Ok(b)
    }

    /// Expands the responses `ua` (one row per measured DOF, one column per load case) measured
    /// under the forces `f` (full length, one column per load case): `u_o = A_oo^-1 (f_o - A_oa
    /// u_a)`, and the residue (4) on the measured DOFs.
    ///
    /// # Errors
    /// Sizes, non-finite values.
    pub fn expand(
        &mut self,
        ua: MatRef<'_, c64>,
        f: MatRef<'_, c64>,
    ) -> Result<ForcedExpansion, CorrelateError> {
        let owner = self.owner;
        let (part, k, m) = (&owner.expander.part, owner.expander.k, owner.expander.m);
        let n = k.rows();
        check_complex(ua, part.measured.len(), "measured response")?;
        check_complex(f, n, "force")?;
        if f.ncols() != ua.ncols() {
            return Err(CorrelateError::DimensionMismatch {
                what: "force columns against measured responses",
                expected: ua.ncols(),
                got: f.ncols(),
            });
        }
        let r = ua.ncols();
        let mut u = Mat::<c64>::zeros(n, r);
        for (i, &d) in part.measured.iter().enumerate() {
            for j in 0..r {
                u[(d, j)] = ua[(i, j)];
            }
        }
        let au = dynamic_product(k, m, owner.damping, self.a, u.as_ref())?;
        let rhs = Mat::from_fn(part.omitted.len(), r, |i, j| {
            let d = part.omitted[i];
            f[(d, j)] - au[(d, j)]
        });
        let uo = self.solve_o(rhs)?;
        for (i, &d) in part.omitted.iter().enumerate() {
            for j in 0..r {
                u[(d, j)] = uo[(i, j)];
            }
        }
        let au = dynamic_product(k, m, owner.damping, self.a, u.as_ref())?;
        let residual = Mat::from_fn(part.measured.len(), r, |i, j| {
            let d = part.measured[i];
            au[(d, j)] - f[(d, j)]
        });
        Ok(ForcedExpansion { u, residual })
    }

    /// `P v = v_a - A_ao A_oo^-1 v_o` for full-length columns `v`: with `v = dA u`, the change of
    /// the residue of the re-expanded response when the dynamic stiffness changes by `dA`.
    ///
    /// # Errors
    /// Sizes, non-finite values.
    pub fn project(&mut self, v: MatRef<'_, c64>) -> Result<Mat<c64>, CorrelateError> {
        let owner = self.owner;
        let (part, k, m) = (&owner.expander.part, owner.expander.k, owner.expander.m);
        let n = k.rows();
        check_complex(v, n, "residue derivative")?;
        let r = v.ncols();
        let vo = Mat::from_fn(part.omitted.len(), r, |i, j| v[(part.omitted[i], j)]);
        let z = self.solve_o(vo)?;
        let mut full = Mat::<c64>::zeros(n, r);
        for (i, &d) in part.omitted.iter().enumerate() {
            for j in 0..r {
                full[(d, j)] = z[(i, j)];
            }
        }
        let az = dynamic_product(k, m, owner.damping, self.a, full.as_ref())?;
        Ok(Mat::from_fn(part.measured.len(), r, |i, j| {
            let d = part.measured[i];
            v[(d, j)] - az[(d, j)]
        }))
    }
}

fn check_complex(
    x: MatRef<'_, c64>,
    rows: usize,
    what: &'static str,
) -> Result<(), CorrelateError> {
    if x.nrows() != rows {
        return Err(CorrelateError::DimensionMismatch {
            what,
            expected: rows,
            got: x.nrows(),
        });
    }
    for j in 0..x.ncols() {
        if let Some(i) = x
            .col(j)
            .iter()
            .position(|v| !(v.re.is_finite() && v.im.is_finite()))
        {
            return Err(CorrelateError::NonFinite {
                what,
                index: j * rows + i,
            });
        }
    }
    Ok(())
}
