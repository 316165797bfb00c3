//! Error localisation: element (group) indicators from the residues (docs/MATH.md, "Updating").
//!
//! For test pairs `(lambda_i, x_i)` with full-length (measured or expanded) shapes, scaled to
//! `||x_i||_M = 1`, and the force residual (3) `R_F,i = (K - lambda_i M) x_i`:
//! - the **strain energy of the displacement residual** (5) in group `g`:
//!   `e_g = sum_i R_D,i^T K_g R_D,i` with `K R_D,i = R_F,i` (free-free: the representative of
//!   docs/MATH.md, M-orthogonal to the rigid-body modes);
//! - the **residual force** on the group's DOFs: `f_g = sum_i sum_{d in g} R_F,i[d]^2 / M_dd`.
//!
//! Why both: if the truth is `K_0 + p_d K_d` and `x_i` its exact mode, `R_F,i = -p_d K_d x_i` lives
//! on group `d`'s DOFs only, so `f_g` is sharp (only `d` and its neighbours sharing nodes light up);
//! `R_D` spreads that force through the structure, but its energy is largest where the force acts
//! and it is insensitive to the local mesh size. Groups of different sizes are compared by their
//! indicator share divided by their mass share (`1` = the average group).
//!
//! With few sensors the shapes are expanded, and the minimum-residual expansion leaves a residual
//! that is `W`-orthogonal to what the omitted DOFs can absorb: it gathers near the sensors, and
//! both indicators above then point at the sensors' neighbourhood as much as at the error. The
//! third indicator accounts for that: the **explained residual** of group `g` is the fraction of
//! the expanded objective `J = sum_i ||R_i||_W^2` that the group's stiffness factor alone removes,
//! `(sum_i b_gi^T W R_i)^2 / (J sum_i b_gi^T W b_gi)`, with `b_gi = P K_g x_i` the sensitivity
//! column projected as in SB-EBE (so the expansion's re-adjustment is accounted for). It is the
//! default of [`localise_expanded`].

use crate::UpdateError;
use crate::problem::UpdateModel;
use faer::{Mat, MatRef};
use femu_correlate::StiffnessSolver;
use serde::{Deserialize, Serialize};

/// Which indicator ranks the groups.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Indicator {
    /// Residual force on the group's DOFs (sharp for exact or well-expanded shapes).
    ResidualForce,
    /// Strain energy of the displacement residual in the group.
    StrainEnergy,
    /// Fraction of the residual objective the group's stiffness factor alone removes (default:
    /// reliable with expanded shapes, see the module docs).
    #[default]
    ExplainedResidual,
}

/// The rule that selects the suspicious groups from the ranking.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SelectionRule {
    /// The ranking indicator.
    pub indicator: Indicator,
    /// A group is selected when its density is at least this fraction of the largest (default 0.5).
    pub fraction: f64,
    /// At most this many groups (default 3).
    pub max_groups: usize,
    /// For [`localise_expanded`]: `None` imposes the measured values in the expansion; `Some(g)`
    /// expands with test error (as `SbebeOptions::test_error`), which keeps measurement noise
    /// from dominating the residual (default `Some(1e-3)`).
    pub test_error: Option<f64>,
}

impl Default for SelectionRule {
    fn default() -> Self {
        Self {
            indicator: Indicator::ExplainedResidual,
            fraction: 0.5,
            max_groups: 3,
            test_error: Some(1e-3),
        }
    }
}

/// Indicators of one group.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GroupIndicator {
    /// Group name.
    pub name: String,
    /// Group index.
    pub group: usize,
    /// `e_g`, the strain energy of the displacement residual (J for unit-M-norm shapes).
    pub strain_energy: f64,
    /// `f_g`, the squared residual force in the `diag(M)^-1` norm.
    pub residual_force: f64,
    /// Fraction of the objective the group's stiffness factor alone removes, in `[0, 1]`.
    pub explained: f64,
    /// Share of the ranking indicator divided by the group's share of the mass (1 = average).
    pub density: f64,
}

/// The localisation: every group's indicators, ranked, and the selected groups.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Localisation {
    /// Groups in decreasing order of `density`.
    pub ranking: Vec<GroupIndicator>,
    /// Indices (into the model's groups) of the selected groups, most suspicious first.
    pub selected: Vec<usize>,
    /// The rule used.
    pub rule: SelectionRule,
    /// The normal equations of the explained residual over every group (projected columns):
    /// `(B^T W B, B^T W r, r^T W r)`, for [`Localisation::joint_fit`]; present after
    /// [`localise_expanded`].
    #[serde(skip)]
    pub normal: Option<(Vec<Vec<f64>>, Vec<f64>, f64)>,
    /// Each group's stiffness-factor bounds (the model's parameters'), within which the
    /// explained fractions and [`Localisation::joint_fit`] are computed.
    #[serde(skip)]
    pub bounds: Vec<(f64, f64)>,
}

impl Localisation {
    /// The least-squares stiffness factors of `groups` together, at the expansion of the
    /// localisation (the first Gauss-Newton step of the expanded objective), within the groups'
    /// bounds ([`Localisation::bounds`]), and the fraction of the objective they remove at those
    /// factors; `None` without the normal equations. The fraction is that of the bounded factors:
    /// a factor the data would take past its bound (a stiffness below 10 % of nominal) is held at
    /// the bound, and what it removes there is what is reported, not what the unbounded fit
    /// would remove.
    pub fn joint_fit(&self, groups: &[usize]) -> Option<(Vec<f64>, f64)> {
        let (gram, num, objective) = self.normal.as_ref()?;
        let n = groups.len();
        let g = faer::Mat::from_fn(n, n, |a, b| gram[groups[a]][groups[b]]);
        // the minimum-norm least-squares factors: groups the data do not see stay at zero
        let (inverse, _) = crate::lsq::symmetric_pseudo_inverse(g.as_ref()).ok()?;
        let bound = |a: usize| {
            self.bounds
                .get(groups[a])
                .copied()
                .unwrap_or((f64::NEG_INFINITY, f64::INFINITY))
        };
        let mut theta: Vec<f64> = (0..n)
            .map(|a| {
                let v = -(0..n)
                    .map(|b| inverse[(a, b)] * num[groups[b]])
                    .sum::<f64>();
                v.clamp(bound(a).0, bound(a).1)
            })
            .collect();
        // the box-constrained minimum of the convex quadratic
        // f(theta) = r^T W r + 2 num . theta + theta^T G theta: cyclic coordinate minimisation
        // from the clamped unconstrained minimum (each step exact; convergent for a convex
        // quadratic), groups the data do not see (G_aa = 0) left where they are
        let unconstrained = (0..n).all(|a| {
            let (lo, hi) = bound(a);
            theta[a] > lo && theta[a] < hi
        });
        if !unconstrained {
            for _ in 0..10_000 {
                let mut moved = 0.0f64;
                for a in 0..n {
                    if g[(a, a)] <= 0.0 {
                        continue;
                    }
                    let rest: f64 = (0..n)
                        .filter(|b| *b != a)
                        .map(|b| g[(a, b)] * theta[b])
                        .sum();
                    let (lo, hi) = bound(a);
                    let v = (-(num[groups[a]] + rest) / g[(a, a)]).clamp(lo, hi);
                    moved = moved.max((v - theta[a]).abs());
                    theta[a] = v;
                }
                if moved <= 1e-14 * theta.iter().fold(1.0f64, |m, t| m.max(t.abs())) {
                    break;
                }
            }
        }
        // removed = r^T W r - f(theta) = -2 num . theta - theta^T G theta
        let linear: f64 = (0..n).map(|a| num[groups[a]] * theta[a]).sum();
        let quadratic: f64 = (0..n)
            .map(|a| (0..n).map(|b| theta[a] * g[(a, b)] * theta[b]).sum::<f64>())
            .sum();
        let removed = -2.0 * linear - quadratic;
        let explained = if *objective > 0.0 {
            (removed / objective).clamp(0.0, 1.0)
        } else {
            0.0
        };
        Some((theta, explained))
    }

    /// The density of each group in group order (for VTK cell data and plots).
    pub fn density_by_group(&self, groups: usize) -> Vec<f64> {
        let mut d = vec![0.0; groups];
        for r in &self.ranking {
            d[r.group] = r.density;
        }
        d
    }

    /// The density of each element (0 for elements in no group), for VTK cell data.
    pub fn density_by_element(&self, up: &UpdateModel<'_>) -> Vec<f64> {
        let mut d = vec![0.0; up.model().mesh().element_count()];
        for r in &self.ranking {
            for &e in &up.groups()[r.group].elements {
                d[e] = r.density;
            }
        }
        d
    }
}

impl std::fmt::Display for Localisation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "| rank | group | residual force | strain energy | explained | density | selected |"
        )?;
        writeln!(f, "|---|---|---|---|---|---|---|")?;
        for (r, g) in self.ranking.iter().enumerate().take(10) {
            writeln!(
                f,
                "| {} | {} | {:.3e} | {:.3e} | {:.3} | {:.2} | {} |",
                r + 1,
                g.name,
                g.residual_force,
                g.strain_energy,
                g.explained,
                g.density,
                if self.selected.contains(&g.group) {
                    "yes"
                } else {
                    ""
                }
            )?;
        }
        writeln!(
            f,
            "\nresidual force: sum over the tuned modes of the squared residual force (K - lambda M) x on \
             the group's DOFs in the diag(M)^-1 norm; strain energy: e_g = sum_i R_D,i^T K_g R_D,i of \
             the displacement residual (J for mass-normalised shapes); explained: the fraction (0 to 1) \
             of the objective a change of the group's stiffness alone removes; density: the group's \
             share of the ranking divided by its share of the mass (1 = average); ranked by density."
        )?;
        Ok(())
    }
}

/// Computes the indicators of every group of `up` at its current parameters from full-length
/// shapes `x` (columns; measured or expanded) and identified eigenvalues `lambdas` (s^-2).
///
/// `docs/MATH.md`, "Localisation" (residues (3), (5)).
///
/// # Errors
/// Sizes, NaN, zero shapes, a bad rule, and the stiffness solver's errors.
pub fn localise(
    up: &UpdateModel<'_>,
    x: MatRef<'_, f64>,
    lambdas: &[f64],
    rule: &SelectionRule,
) -> Result<Localisation, UpdateError> {
    let sys = up.matrices();
    let n = sys.dofs.free_count();
    if x.nrows() != n || x.ncols() != lambdas.len() || lambdas.is_empty() {
        return Err(UpdateError::Invalid {
            what: "localisation data",
            reason: format!(
                "{} x {} shapes and {} eigenvalues for a model with {n} free DOFs",
                x.nrows(),
                x.ncols(),
                lambdas.len()
            ),
        });
    }
    check_rule(rule)?;
    let xs = normalise(&sys.m, x)?;
    let r_f = femu_correlate::residues::force_residuals(&sys.k, &sys.m, lambdas, xs.as_ref())?;
    let solver = StiffnessSolver::new(&sys.k, &sys.m)?;
    let r_d = solver.displacement_residuals(r_f.as_ref())?;
    let w: Vec<f64> = femu_correlate::expansion::residual_metric(&sys.m)?
        .iter()
        .map(|m| 1.0 / m)
        .collect();
    let ones = vec![1.0; n];
    let groups = up.groups();
    let mut energy = vec![0.0; groups.len()];
    let mut force = vec![0.0; groups.len()];
    let mut num = vec![0.0; groups.len()];
    let mut den = vec![0.0; groups.len()];
    let mut objective = 0.0;
    for i in 0..lambdas.len() {
        let ri: Vec<f64> = r_f.col(i).iter().copied().collect();
        objective += ri.iter().zip(&w).map(|(r, w)| r * r * w).sum::<f64>();
        let xi: Vec<f64> = xs.col(i).iter().copied().collect();
        for (g, c) in up.group_columns(&xi, lambdas[i])?.iter().enumerate() {
            num[g] += c.weighted_dot_full(&ri, &w);
            den[g] += c.weighted_dot(c, &w);
        }
        let rd: Vec<f64> = r_d.col(i).iter().copied().collect();
        let kg_rd = up.group_columns(&rd, 0.0)?;
        for g in 0..groups.len() {
            energy[g] += kg_rd[g].weighted_dot_full(&rd, &ones);
            force[g] += up
                .group_dofs(g)
                .iter()
                .map(|&d| r_f[(d, i)] * r_f[(d, i)] * w[d])
                .sum::<f64>();
        }
    }
    let bounds = stiffness_bounds(up);
    let explained: Vec<f64> = (0..groups.len())
        .map(|g| explained_fraction(num[g], den[g], objective, bounds[g]))
        .collect();
    Ok(rank(up, energy, force, explained, rule))
}

/// The fraction of the objective one group's stiffness factor removes, the factor held within
/// its bounds `(lo, hi)`: `f(theta) = objective + 2 num theta + den theta^2` is least at
/// `-num / den`, clamped to the bounds, where it has removed `-2 num theta - den theta^2` (the
/// unbounded fit removed `num^2 / den` even where its factor left the physical range).
pub(crate) fn explained_fraction(num: f64, den: f64, objective: f64, (lo, hi): (f64, f64)) -> f64 {
    if den > 0.0 && objective > 0.0 {
        let theta = (-num / den).clamp(lo, hi);
        ((-2.0 * num * theta - den * theta * theta) / objective).clamp(0.0, 1.0)
    } else {
        0.0
    }
}

/// Each group's own parameter's bounds (a stiffness factor's, a thickness's, a mass group's
/// factor's), unbounded where it has none.
pub(crate) fn stiffness_bounds(up: &UpdateModel<'_>) -> Vec<(f64, f64)> {
    (0..up.groups().len())
        .map(|g| {
            let masses = up.groups()[g].law == femu_fem::groups::GroupLaw::Mass;
            up.parameters()
                .iter()
                .find(|p| p.group == g && (!p.mass || masses))
                .map_or((f64::NEG_INFINITY, f64::INFINITY), |p| (p.lower, p.upper))
        })
        .collect()
}

pub(crate) fn check_rule(rule: &SelectionRule) -> Result<(), UpdateError> {
    if !(rule.fraction > 0.0 && rule.fraction <= 1.0) || rule.max_groups == 0 {
        return Err(UpdateError::Invalid {
            what: "selection rule",
            reason: format!(
                "fraction {} must be in (0, 1], max_groups {} at least 1",
                rule.fraction, rule.max_groups
            ),
        });
    }
    Ok(())
}

/// Localisation from test modes measured on `layout` (few sensors): the shapes are expanded by
/// the minimum-residual expansion in the `diag(M)^-1` metric at the current parameters, and the
/// three indicators computed on the expansion, the explained residual with projected columns
/// (see the module docs). Use [`SelectionRule`] with [`Indicator::ExplainedResidual`] (the
/// recommended ranking here).
///
/// # Errors
/// Oblique sensors, sizes, expansion and solver errors, a bad rule.
pub fn localise_expanded(
    up: &UpdateModel<'_>,
    layout: &femu_correlate::SensorLayout,
    test: &femu_correlate::TestModes,
    rule: &SelectionRule,
) -> Result<Localisation, UpdateError> {
    check_rule(rule)?;
    let measured = layout.measured_dofs().ok_or(UpdateError::Invalid {
        what: "sensor layout",
        reason: "localisation expands the test shapes: every sensor must lie along a global axis"
            .into(),
    })?;
    let sys = up.matrices();
    let n = sys.dofs.free_count();
    let w_inv = femu_correlate::expansion::residual_metric(&sys.m)?;
    let w: Vec<f64> = w_inv.iter().map(|v| 1.0 / v).collect();
    let lambdas = test.eigenvalues();
    let groups = up.groups().len();
    let exp = femu_correlate::Expander::with_measured_dofs(&sys.k, &sys.m, &measured)?;
    let e = crate::problem::expand_projected(
        &exp,
        &lambdas,
        test.shapes.as_ref(),
        &w_inv,
        rule.test_error,
        None,
        |j, xj| {
            Ok(crate::problem::dense_columns(
                &up.group_columns(xj, lambdas[j])?,
                n,
            ))
        },
    )?;
    let (x, projected, r2) = (e.x, e.blocks, e.r2);
    // scale every mode to unit M-norm (the projection is linear in x)
    let xs = normalise(&sys.m, x.as_ref())?;
    let scale: Vec<f64> = (0..x.ncols())
        .map(|j| {
            let i = (0..n)
                .max_by(|a, b| x[(*a, j)].abs().total_cmp(&x[(*b, j)].abs()))
                .unwrap_or(0);
            if x[(i, j)] != 0.0 {
                xs[(i, j)] / x[(i, j)]
            } else {
                0.0
            }
        })
        .collect();
    let r_f = femu_correlate::residues::force_residuals(&sys.k, &sys.m, &lambdas, xs.as_ref())?;
    let solver = StiffnessSolver::new(&sys.k, &sys.m)?;
    let r_d = solver.displacement_residuals(r_f.as_ref())?;
    let ones = vec![1.0; n];
    let (mut energy, mut force) = (vec![0.0; groups], vec![0.0; groups]);
    let (mut num, mut den, mut objective) = (vec![0.0; groups], vec![0.0; groups], 0.0);
    let mut gram = vec![vec![0.0; groups]; groups];
    for i in 0..lambdas.len() {
        let ri: Vec<f64> = r_f.col(i).iter().copied().collect();
        objective += ri.iter().zip(&w).map(|(r, w)| r * r * w).sum::<f64>();
        let (b, b2) = &projected[i];
        for g in 0..groups {
            for h in g..groups {
                let mut v = 0.0;
                for d in 0..n {
                    v += b[(d, g)] * b[(d, h)] * w[d];
                }
                for t in 0..b2.nrows() {
                    v += b2[(t, g)] * b2[(t, h)];
                }
                v *= scale[i] * scale[i];
                gram[g][h] += v;
                if h != g {
                    gram[h][g] += v;
                }
            }
        }
        objective += scale[i] * scale[i] * r2.col(i).iter().map(|v| v * v).sum::<f64>();
        for g in 0..groups {
            let (mut bn, mut bb) = (0.0, 0.0);
            for d in 0..n {
                let v = scale[i] * b[(d, g)];
                bn += v * ri[d] * w[d];
                bb += v * v * w[d];
            }
            for s in 0..b2.nrows() {
                let v = scale[i] * b2[(s, g)];
                bn += v * scale[i] * r2[(s, i)];
                bb += v * v;
            }
            num[g] += bn;
            den[g] += bb;
            force[g] += up
                .group_dofs(g)
                .iter()
                .map(|&d| ri[d] * ri[d] * w[d])
                .sum::<f64>();
        }
        let rd: Vec<f64> = r_d.col(i).iter().copied().collect();
        for (g, c) in up.group_columns(&rd, 0.0)?.iter().enumerate() {
            energy[g] += c.weighted_dot_full(&rd, &ones);
        }
    }
    let bounds = stiffness_bounds(up);
    let explained = (0..groups)
        .map(|g| explained_fraction(num[g], den[g], objective, bounds[g]))
        .collect();
    let mut loc = rank(up, energy, force, explained, rule);
    loc.normal = Some((gram, num, objective));
    Ok(loc)
}

pub(crate) fn rank(
    up: &UpdateModel<'_>,
    energy: Vec<f64>,
    force: Vec<f64>,
    explained: Vec<f64>,
    rule: &SelectionRule,
) -> Localisation {
    let groups = up.groups();
    let total_mass: f64 = up.group_masses().iter().sum();
    let key = match rule.indicator {
        Indicator::ResidualForce => &force,
        Indicator::StrainEnergy => &energy,
        Indicator::ExplainedResidual => &explained,
    };
    // the explained fraction is already per parameter: no mass normalisation
    let per_mass = rule.indicator != Indicator::ExplainedResidual;
    let total_key: f64 = key.iter().sum();
    let mut ranking: Vec<GroupIndicator> = (0..groups.len())
        .map(|g| GroupIndicator {
            name: groups[g].name.clone(),
            group: g,
            strain_energy: energy[g],
            residual_force: force[g],
            explained: explained[g],
            density: if total_key <= 0.0 {
                0.0
            } else if per_mass {
                (key[g] / total_key) / (up.group_masses()[g] / total_mass)
            } else {
                key[g] / total_key * groups.len() as f64
            },
        })
        .collect();
    ranking.sort_by(|a, b| b.density.total_cmp(&a.density));
    let top = ranking.first().map_or(0.0, |r| r.density);
    let selected = ranking
        .iter()
        .take(rule.max_groups)
        .filter(|r| top > 0.0 && r.density >= rule.fraction * top)
        .map(|r| r.group)
        .collect();
    Localisation {
        bounds: stiffness_bounds(up),
        ranking,
        selected,
        rule: rule.clone(),
        normal: None,
    }
}

/// Shapes scaled to `||x||_M = 1`.
pub(crate) fn normalise(
    m: &femu_sparse::SparseMatrix,
    x: MatRef<'_, f64>,
) -> Result<Mat<f64>, UpdateError> {
    let mx = femu_sparse::csc::sym_mul_mat(m, x)?;
    let mut out = x.to_owned();
    for j in 0..x.ncols() {
        let s: f64 = (0..x.nrows()).map(|i| x[(i, j)] * mx[(i, j)]).sum();
        if !(s.is_finite() && s > 0.0) {
            return Err(UpdateError::Invalid {
                what: "shape",
                reason: format!("shape {} has M-norm^2 {s} (zero or not finite)", j + 1),
            });
        }
        let s = 1.0 / s.sqrt();
        for i in 0..x.nrows() {
            out[(i, j)] *= s;
        }
    }
    Ok(out)
}
