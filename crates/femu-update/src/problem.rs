//! The parameterised model `K(p) = K_0 + sum_g p_g K_g`, `M(q) = M_0 + sum_g q_g M_g` (docs/MATH.md,
//! "Updating") with its parameters, bounds and the element-by-element sensitivity columns.

use crate::UpdateError;
use faer::{Mat, MatRef};
use femu_correlate::expansion::Expander;
use femu_fem::assembly::{Assembler, MassKind, SystemMatrices};
use femu_fem::groups::{GroupLaw, ParameterGroup, ParameterGroups};
use femu_fem::model::Model;
use femu_sparse::cholesky::SymbolicFactor;
use femu_sparse::ordering::Ordering;
use serde::{Deserialize, Serialize};

/// Which corrections are estimated per group.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Corrections {
    /// Stiffness factors `p_g` only (the usual case: stiffness is what models get wrong).
    #[default]
    Stiffness,
    /// Mass factors `q_g` only.
    Mass,
    /// Both; the trivial solution `p = q = -1` (all of `K` and `M` scaled to zero together) is
    /// excluded by the total-mass guard of the updating options.
    StiffnessAndMass,
}

/// One updating parameter: a stiffness or mass factor of a group, or the relative thickness
/// change of a group of shells.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Parameter {
    /// `"k:<group>"` or `"m:<group>"`; a thickness group's own name, `"t:<set>"`.
    pub name: String,
    /// Group index.
    pub group: usize,
    /// `true` for a mass factor `q_g`, `false` for a stiffness factor `p_g` or a thickness change
    /// (which moves both the group's stiffness and its mass).
    pub mass: bool,
    /// Lower bound (default -0.9: a group keeps at least 10 % of its stiffness or mass).
    pub lower: f64,
    /// Upper bound (default 2: at most three times the nominal value).
    pub upper: f64,
}

/// A sensitivity column restricted to the DOFs where it can be non-zero.
#[derive(Debug, Clone, PartialEq)]
pub struct SparseColumn {
    /// Free DOFs (sorted), shared with the group.
    pub dofs: std::sync::Arc<[usize]>,
    /// Values on those DOFs.
    pub values: Vec<f64>,
}

impl SparseColumn {
    /// `sum_d a_d b_d w_d` over the common DOFs of two columns of the same group set, with
    /// weights `w` indexed by DOF.
    pub fn weighted_dot(&self, other: &SparseColumn, w: &[f64]) -> f64 {
        let (mut i, mut j, mut s) = (0, 0, 0.0);
        while i < self.dofs.len() && j < other.dofs.len() {
            match self.dofs[i].cmp(&other.dofs[j]) {
                std::cmp::Ordering::Less => i += 1,
                std::cmp::Ordering::Greater => j += 1,
                std::cmp::Ordering::Equal => {
                    s += self.values[i] * other.values[j] * w[self.dofs[i]];
                    i += 1;
                    j += 1;
                }
            }
        }
        s
    }

    /// `sum_d a_d v_d w_d` with a full vector `v`.
    pub fn weighted_dot_full(&self, v: &[f64], w: &[f64]) -> f64 {
        self.dofs
            .iter()
            .zip(&self.values)
            .map(|(&d, a)| a * v[d] * w[d])
            .sum()
    }
}

/// A model with updating parameters: the nominal matrices, the groups' element matrices, the
/// current parameter values and `K(p)`, `M(q)` on the fixed pattern (no new pattern, no new
/// symbolic analysis when the parameters change).
#[derive(Debug, Clone)]
pub struct UpdateModel<'m> {
    model: &'m Model,
    asm: Assembler,
    base: SystemMatrices,
    groups: ParameterGroups,
    group_dofs: Vec<std::sync::Arc<[usize]>>,
    group_mass: Vec<f64>,
    params: Vec<Parameter>,
    p: Vec<f64>,
    q: Vec<f64>,
    current: SystemMatrices,
    symbolic: Option<SymbolicFactor>,
    /// The shift of the last eigen solve, the next one's hint (a model that changed little).
    last_shift: Option<f64>,
    nominal_mass: f64,
}

impl<'m> UpdateModel<'m> {
    /// Assembles the nominal model and the groups' element matrices.
    ///
    /// # Errors
    /// Assembly errors (missing material, inverted element), empty or out-of-range groups, no
    /// group.
    pub fn new(
        model: &'m Model,
        groups: Vec<ParameterGroup>,
        mass: MassKind,
        corrections: Corrections,
    ) -> Result<Self, UpdateError> {
        Self::with_groups(
            model,
            ParameterGroups::new(model, groups, mass)?,
            corrections,
        )
    }

    /// The model with groups whose element matrices are already computed (their mass kind is the
    /// model's).
    ///
    /// # Errors
    /// Assembly errors, no group.
    pub fn with_groups(
        model: &'m Model,
        groups: ParameterGroups,
        corrections: Corrections,
    ) -> Result<Self, UpdateError> {
        let asm = Assembler::new(model)?;
        let base = asm.assemble_analysed(model, groups.mass_kind())?;
        Self::from_assembly(model, groups, corrections, asm, base)
    }

    /// The model with groups, from an assembler and nominal matrices the caller already has (a
    /// workflow that assembled the model once reuses them here). `base` must be `asm`'s assembly
    /// of `model` with the groups' mass kind.
    ///
    /// # Errors
    /// No group, a mass kind or size that does not match, and the groups' errors.
    pub fn from_assembly(
        model: &'m Model,
        groups: ParameterGroups,
        corrections: Corrections,
        asm: Assembler,
        base: SystemMatrices,
    ) -> Result<Self, UpdateError> {
        if groups.is_empty() {
            return Err(UpdateError::Invalid {
                what: "parameter groups",
                reason: "no group to update".into(),
            });
        }
        // groups given as matrices carry their own numbering (the base's), not an assembler's
        let matrices = groups.from_assembled_matrices();
        if base.mass_kind != groups.mass_kind()
            || (!matrices && base.k.rows() != asm.dofs().free_count())
        {
            return Err(UpdateError::Invalid {
                what: "nominal matrices",
                reason: "not the assembler's assembly with the groups' mass kind".into(),
            });
        }
        let mut group_dofs = Vec::with_capacity(groups.len());
        let mut group_mass = Vec::with_capacity(groups.len());
        for g in 0..groups.len() {
            group_dofs.push(groups.group_dofs(model, &asm, g)?.into());
            group_mass.push(groups.group_mass(model, g)?);
        }
        let mut params = Vec::new();
        for (g, group) in groups.groups().iter().enumerate() {
            if group.law == GroupLaw::Thickness {
                // one parameter whatever the corrections: the thickness moves stiffness and mass
                params.push(Parameter {
                    name: group.name.clone(),
                    group: g,
                    mass: false,
                    lower: -0.9,
                    upper: 2.0,
                });
                continue;
            }
            if let GroupLaw::Section(_) = group.law {
                // a beam section's stiffness: one parameter, whatever the corrections
                params.push(Parameter {
                    name: group.name.clone(),
                    group: g,
                    mass: false,
                    lower: -0.9,
                    upper: 2.0,
                });
                continue;
            }
            if group.law == GroupLaw::Mass {
                // a set of concentrated masses: its mass factor, whatever the corrections
                params.push(Parameter {
                    name: format!("m:{}", group.name),
                    group: g,
                    mass: true,
                    lower: -0.9,
                    upper: 2.0,
                });
                continue;
            }
            for (flag, prefix) in [(false, "k"), (true, "m")] {
                let wanted = match corrections {
                    Corrections::Stiffness => !flag,
                    Corrections::Mass => flag,
                    Corrections::StiffnessAndMass => true,
                };
                if wanted {
                    params.push(Parameter {
                        name: format!("{prefix}:{}", group.name),
                        group: g,
                        mass: flag,
                        lower: -0.9,
                        upper: 2.0,
                    });
                }
            }
        }
        let n_groups = groups.len();
        let nominal_mass = if matrices {
            femu_fem::groups::translational_mass(&base.m, &base.dofs)
        } else {
            model.total_mass()?
        };
        Ok(Self {
            model,
            asm,
            current: base.clone(),
            base,
            groups,
            group_dofs,
            group_mass,
            params,
            p: vec![0.0; n_groups],
            q: vec![0.0; n_groups],
            symbolic: None,
            last_shift: None,
            nominal_mass,
        })
    }

    /// One group per named element set.
    ///
    /// # Errors
    /// An unknown set, and as [`UpdateModel::new`].
    pub fn from_element_sets(
        model: &'m Model,
        sets: &[&str],
        mass: MassKind,
        corrections: Corrections,
    ) -> Result<Self, UpdateError> {
        let groups = ParameterGroups::from_element_sets(model, sets, mass)?;
        Self::with_groups(model, groups, corrections)
    }

    /// One group per element (element-by-element updating).
    ///
    /// # Errors
    /// As [`UpdateModel::new`].
    pub fn elementwise(
        model: &'m Model,
        mass: MassKind,
        corrections: Corrections,
    ) -> Result<Self, UpdateError> {
        Self::with_groups(
            model,
            ParameterGroups::elementwise(model, mass)?,
            corrections,
        )
    }

    /// The finite element model.
    pub fn model(&self) -> &'m Model {
        self.model
    }

    /// The assembler (pattern and DOF map).
    pub fn assembler(&self) -> &Assembler {
        &self.asm
    }

    /// The groups.
    pub fn groups(&self) -> &[ParameterGroup] {
        self.groups.groups()
    }

    /// The nominal model's total mass `rho V`, kg.
    pub fn nominal_mass(&self) -> f64 {
        self.nominal_mass
    }

    /// Each group's mass, kg.
    pub fn group_masses(&self) -> &[f64] {
        &self.group_mass
    }

    /// The free DOFs each group touches.
    pub fn group_dofs(&self, g: usize) -> &[usize] {
        &self.group_dofs[g]
    }

    /// `sum_g c_g K_g(p)` on `K`'s pattern: each group's own stiffness at its current parameter
    /// ([`femu_fem::groups::ParameterGroups::stiffness_now_product`]) weighted by `c_g` (a
    /// structural damping matrix of per-group loss factors), `c_K K(p)` added.
    ///
    /// # Errors
    /// A wrong number of coefficients.
    pub fn group_stiffness_matrix(
        &self,
        c_k: f64,
        coefficients: &[f64],
    ) -> Result<femu_sparse::SparseMatrix, UpdateError> {
        if coefficients.len() != self.groups.len() {
            return Err(UpdateError::Invalid {
                what: "group coefficients",
                reason: format!(
                    "{} values for {} groups",
                    coefficients.len(),
                    self.groups.len()
                ),
            });
        }
        let k = &self.current.k;
        let mut values: Vec<f64> = k.data().iter().map(|v| c_k * v).collect();
        for (g, &c) in coefficients.iter().enumerate() {
            if c != 0.0 {
                self.groups
                    .add_stiffness_now(&self.asm, g, self.p[g], c, &mut values)?;
            }
        }
        Ok(femu_sparse::SparseMatrix::new_csc(
            (k.rows(), k.cols()),
            k.indptr().raw_storage().to_vec(),
            k.indices().to_vec(),
            values,
        ))
    }

    /// Each group's own stiffness at its current parameter times `x`, `K_g(p) x`, on the group's
    /// DOFs.
    ///
    /// # Errors
    /// A wrong length of `x`.
    pub fn group_stiffness_columns(&self, x: &[f64]) -> Result<Vec<SparseColumn>, UpdateError> {
        let mut y = vec![0.0; self.base.dofs.free_count()];
        (0..self.groups.len())
            .map(|g| {
                self.groups
                    .stiffness_now_product(&self.asm, g, self.p[g], x, &mut y)?;
                let dofs = &self.group_dofs[g];
                let values = dofs
                    .iter()
                    .map(|&d| std::mem::replace(&mut y[d], 0.0))
                    .collect();
                Ok(SparseColumn {
                    dofs: dofs.clone(),
                    values,
                })
            })
            .collect()
    }

    /// The parameters (in the order of [`UpdateModel::theta`]).
    pub fn parameters(&self) -> &[Parameter] {
        &self.params
    }

    /// Sets every parameter's bounds.
    ///
    /// # Errors
    /// `lower > upper`, `lower <= -1` (a group with no stiffness or negative mass), non-finite.
    pub fn set_bounds(&mut self, lower: f64, upper: f64) -> Result<(), UpdateError> {
        if !(lower > -1.0 && lower <= upper && upper.is_finite()) {
            return Err(UpdateError::Invalid {
                what: "parameter bounds",
                reason: format!("[{lower}, {upper}]: need -1 < lower <= upper < infinity"),
            });
        }
        for p in &mut self.params {
            p.lower = lower;
            p.upper = upper;
        }
        Ok(())
    }

    /// The nominal matrices `K_0`, `M_0`.
    pub fn nominal(&self) -> &SystemMatrices {
        &self.base
    }

    /// The current `K(p)`, `M(q)`.
    pub fn matrices(&self) -> &SystemMatrices {
        &self.current
    }

    /// Stiffness factors `p_g` per group.
    pub fn stiffness_factors(&self) -> &[f64] {
        &self.p
    }

    /// Mass factors `q_g` per group.
    pub fn mass_factors(&self) -> &[f64] {
        &self.q
    }

    /// The current parameter vector, one entry per [`Parameter`].
    pub fn theta(&self) -> Vec<f64> {
        self.params
            .iter()
            .map(|p| {
                if p.mass {
                    self.q[p.group]
                } else {
                    self.p[p.group]
                }
            })
            .collect()
    }

    /// Sets the parameters and rewrites `K(p)`, `M(q)` in place.
    ///
    /// # Errors
    /// A wrong length, a non-finite value, or a value outside the parameter's bounds (name).
    pub fn set_theta(&mut self, theta: &[f64]) -> Result<(), UpdateError> {
        if theta.len() != self.params.len() {
            return Err(UpdateError::Invalid {
                what: "parameter vector",
                reason: format!(
                    "{} values for {} parameters",
                    theta.len(),
                    self.params.len()
                ),
            });
        }
        for (par, &v) in self.params.iter().zip(theta) {
            if !(v >= par.lower - 1e-12 && v <= par.upper + 1e-12) {
                return Err(UpdateError::Invalid {
                    what: "parameter value",
                    reason: format!("{} = {v} outside [{}, {}]", par.name, par.lower, par.upper),
                });
            }
        }
        for (par, &v) in self.params.iter().zip(theta) {
            if par.mass {
                self.q[par.group] = v;
            } else {
                self.p[par.group] = v;
            }
        }
        self.groups.write_parameterized(
            self.model,
            &self.asm,
            &self.base,
            &self.p,
            &self.q,
            &mut self.current,
        )?;
        Ok(())
    }

    /// The symbolic analysis of `K`'s pattern, reused by every eigen solve of the updating
    /// iterations: the one made beside the nominal assembly (`SystemMatrices::analysis`), or
    /// computed on first use.
    ///
    /// # Errors
    /// A failed analysis.
    pub fn symbolic(&mut self) -> Result<SymbolicFactor, UpdateError> {
        if self.symbolic.is_none() {
            self.symbolic = Some(match self.base.analysis() {
                Some(made) => made,
                None => SymbolicFactor::new(&self.base.k, Ordering::NestedDissection)?,
            });
        }
        Ok(self.symbolic.clone().expect("just computed"))
    }

    /// The shift of the last eigen solve of this model (`Modes::shift`), given to the next as
    /// `EigenOptions::lowest_shift_hint`: the parameters change little between the solves of an
    /// updating run, so the shift placed for the first stays well placed, and each later solve
    /// skips the probe; for a free-free model whose solve moved the shift (the 52,416-DOF block of
    /// `examples/hinted_shift.rs`), also one factorization (docs/SCALING.md, "A hinted shift").
    pub(crate) fn last_shift(&self) -> Option<f64> {
        self.last_shift
    }

    /// Forgets the last solve's shift: the next solve finds its own. A workflow whose results
    /// must not depend on whether it solved this model before (the same bits from every front
    /// end) calls it.
    pub fn forget_shift(&mut self) {
        self.last_shift = None;
    }

    /// Records the shift of an eigen solve of this model (see [`UpdateModel::last_shift`]).
    pub(crate) fn set_last_shift(&mut self, shift: f64) {
        self.last_shift = Some(shift);
    }

    /// The sensitivity columns of every parameter for one vector `x` at eigenvalue `lambda`:
    /// `K_g x` for a stiffness factor, `-lambda M_g x` for a mass factor, `(K_g' - lambda M_g')
    /// x` at the current thickness for a thickness change (the derivative of `R = (K(p) - lambda
    /// M(q)) x`), formed element by element (SB-EBE: no eigenvector derivative, no assembled
    /// `K_g`).
    ///
    /// # Errors
    /// A wrong length of `x`.
    pub fn columns(&self, x: &[f64], lambda: f64) -> Result<Vec<SparseColumn>, UpdateError> {
        let n = self.base.dofs.free_count();
        let mut y = vec![0.0; n];
        self.params
            .iter()
            .map(|par| {
                if self.is_thickness(par.group) {
                    return self.thickness_column(par.group, lambda, x, &mut y);
                }
                let s = if par.mass { -lambda } else { 1.0 };
                self.group_column(par.group, par.mass, s, x, &mut y)
            })
            .collect()
    }

    fn is_thickness(&self, g: usize) -> bool {
        self.groups.groups()[g].law == GroupLaw::Thickness
    }

    /// `(dK/dp - lambda dM/dp) x` of a thickness group at its current thickness; `y` is zero on
    /// entry and on return.
    fn thickness_column(
        &self,
        g: usize,
        lambda: f64,
        x: &[f64],
        y: &mut [f64],
    ) -> Result<SparseColumn, UpdateError> {
        let at = self.p[g];
        self.groups
            .stiffness_derivative_product(&self.asm, g, at, x, y)?;
        let mut z = vec![0.0; y.len()];
        self.groups
            .mass_derivative_product(&self.asm, g, at, x, &mut z)?;
        let dofs = &self.group_dofs[g];
        let values = dofs
            .iter()
            .map(|&d| {
                let v = y[d] - lambda * z[d];
                y[d] = 0.0;
                v
            })
            .collect();
        Ok(SparseColumn {
            dofs: dofs.clone(),
            values,
        })
    }

    /// `phi^T (dM/dtheta_k) phi` for each parameter: 0 for a stiffness factor, `phi^T M_g phi`
    /// for a mass factor, `phi^T M_g' phi` at the current thickness for a thickness change (the
    /// eigenvector derivative's normalisation term).
    ///
    /// # Errors
    /// A wrong length of `phi`.
    pub fn mass_quadratics(&self, phi: &[f64]) -> Result<Vec<f64>, UpdateError> {
        let mut y = vec![0.0; self.base.dofs.free_count()];
        self.params
            .iter()
            .map(|par| {
                if !par.mass && !self.is_thickness(par.group) {
                    return Ok(0.0);
                }
                y.iter_mut().for_each(|v| *v = 0.0);
                self.groups.mass_derivative_product(
                    &self.asm,
                    par.group,
                    self.p[par.group],
                    phi,
                    &mut y,
                )?;
                Ok(y.iter().zip(phi).map(|(a, b)| a * b).sum())
            })
            .collect()
    }

    /// Each group's own sensitivity column at eigenvalue `lambda`, whatever the corrections (the
    /// localisation's): `K_g v` for a group that scales its elements, `(K' - lambda M') v` at
    /// the current thickness for a thickness group, `-lambda M_g v` for a mass group. With
    /// `lambda = 0`, the stiffness part alone (the strain energies of a displacement residual).
    ///
    /// # Errors
    /// A wrong length of `v`.
    pub fn group_columns(&self, v: &[f64], lambda: f64) -> Result<Vec<SparseColumn>, UpdateError> {
        let mut y = vec![0.0; self.base.dofs.free_count()];
        (0..self.groups.len())
            .map(|g| match self.groups.groups()[g].law {
                GroupLaw::Scale | GroupLaw::Section(_) => {
                    self.group_column(g, false, 1.0, v, &mut y)
                }
                GroupLaw::Thickness => self.thickness_column(g, lambda, v, &mut y),
                GroupLaw::Mass => self.group_column(g, true, -lambda, v, &mut y),
            })
            .collect()
    }

    /// `s K_g x` or `s M_g x` on the group's DOFs; `y` is zero on entry and on return.
    fn group_column(
        &self,
        g: usize,
        mass: bool,
        s: f64,
        x: &[f64],
        y: &mut [f64],
    ) -> Result<SparseColumn, UpdateError> {
        let at = self.p[g];
        if mass {
            self.groups
                .mass_derivative_product(&self.asm, g, at, x, y)?;
        } else {
            self.groups
                .stiffness_derivative_product(&self.asm, g, at, x, y)?;
        }
        let dofs = &self.group_dofs[g];
        let values = dofs
            .iter()
            .map(|&d| {
                let v = s * y[d];
                y[d] = 0.0;
                v
            })
            .collect();
        Ok(SparseColumn {
            dofs: dofs.clone(),
            values,
        })
    }

    /// The total-mass constraint row: `c^T theta` is the mass the parameters add (`c_i = m_g` for
    /// a mass factor of group `g`, a mass group's factor, or a thickness change, whose `rho t`
    /// mass is linear in it; 0 for a stiffness factor).
    pub fn mass_row(&self) -> Vec<f64> {
        self.params
            .iter()
            .map(|p| {
                if self.moves_mass(p) {
                    self.group_mass[p.group]
                } else {
                    0.0
                }
            })
            .collect()
    }

    /// Whether any parameter is a mass factor of a group of elements (what the total-mass guard
    /// holds for both methods).
    pub fn has_mass_parameters(&self) -> bool {
        self.params
            .iter()
            .any(|p| p.mass && self.groups.groups()[p.group].law == GroupLaw::Scale)
    }

    /// The total-mass guard's row: [`UpdateModel::mass_row`] for the mass factors of element
    /// groups, and, when `model_scaling` (SB-EBE, whose residual shrinks with the whole model),
    /// for thickness changes and mass groups' factors too; 0 elsewhere. Inverse eigensensitivity
    /// guards only the mass factors, whose common scaling with the stiffness leaves every
    /// eigenvalue unchanged.
    pub fn guard_row(&self, model_scaling: bool) -> Vec<f64> {
        self.mass_row()
            .into_iter()
            .zip(&self.params)
            .map(|(c, p)| {
                let scale_law = self.groups.groups()[p.group].law == GroupLaw::Scale;
                if (p.mass && scale_law) || (model_scaling && !scale_law) {
                    c
                } else {
                    0.0
                }
            })
            .collect()
    }

    /// Whether any parameter is a thickness change or a mass group's factor: parameters that move
    /// mass without a mass factor's name, and with which the SB-EBE residual shrinks as the model
    /// does (docs/MATH.md, "Thickness parameters").
    pub fn has_thickness_or_mass_groups(&self) -> bool {
        self.params.iter().any(|p| {
            matches!(
                self.groups.groups()[p.group].law,
                GroupLaw::Thickness | GroupLaw::Mass
            )
        })
    }

    /// Whether a parameter moves the model's mass: a mass factor, a mass group's factor, a
    /// thickness change.
    fn moves_mass(&self, p: &Parameter) -> bool {
        p.mass || self.is_thickness(p.group)
    }
}

/// Sparse columns as a dense `n x columns` block (the form the projected expansions take).
pub(crate) fn dense_columns(cols: &[SparseColumn], n: usize) -> Mat<f64> {
    let mut a = Mat::zeros(n, cols.len());
    for (k, c) in cols.iter().enumerate() {
        for (&d, &v) in c.dofs.iter().zip(&c.values) {
            a[(d, k)] = v;
        }
    }
    a
}

/// Expanded shapes with projected sensitivity columns, as SB-EBE and localisation use them.
pub(crate) struct ProjectedExpansion {
    /// Expanded shapes (full length).
    pub x: Mat<f64>,
    /// `sqrt(gamma_j) (C x_j - y_j)` per mode; no rows when the measurements are imposed.
    pub r2: Mat<f64>,
    /// Per mode: the projected columns' `W` part (`n x c`) and sensor part (`s x c`, no rows when
    /// the measurements are imposed).
    pub blocks: Vec<(Mat<f64>, Mat<f64>)>,
}

/// Minimum-residual expansion in the metric `diag(w_inv)^-1` with the projected columns of
/// `columns(j, x_j)`: measured values imposed (`test_error = None`, in the sensor space on
/// `symbolic`, the analysis of `K`'s pattern) or expansion with test error.
pub(crate) fn expand_projected(
    exp: &Expander<'_>,
    lambdas: &[f64],
    ya: MatRef<'_, f64>,
    w_inv: &[f64],
    test_error: Option<f64>,
    symbolic: Option<&SymbolicFactor>,
    columns: impl Fn(usize, &[f64]) -> Result<Mat<f64>, UpdateError> + Sync,
) -> Result<ProjectedExpansion, UpdateError> {
    match test_error {
        Some(gamma) => {
            let e = exp.test_error_projected(lambdas, ya, w_inv, gamma, columns)?;
            let r2 = Mat::from_fn(e.misfit.nrows(), e.misfit.ncols(), |s, j| {
                e.gammas[j].sqrt() * e.misfit[(s, j)]
            });
            Ok(ProjectedExpansion {
                x: e.x,
                r2,
                blocks: e.projected,
            })
        }
        None => {
            let (x, b) = exp.minimum_residual_projected(lambdas, ya, w_inv, symbolic, columns)?;
            let blocks = b
                .into_iter()
                .map(|b| {
                    let c = b.ncols();
                    (b, Mat::zeros(0, c))
                })
                .collect();
            Ok(ProjectedExpansion {
                x,
                r2: Mat::zeros(0, lambdas.len()),
                blocks,
            })
        }
    }
}
