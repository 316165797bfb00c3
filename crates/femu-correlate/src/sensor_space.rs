//! Expansion in the space of the measured DOFs: one factorization of the full `Z = K - lambda M`
//! per identified eigenvalue serves every sensor set drawn from a set of candidate DOFs.
//!
//! With `E` the unit columns of the candidate DOFs and `S` a sensor set among them (`C = E_S^T`),
//! each method of docs/MATH.md's expansion table is a combination of the columns of one dense block
//! `B = Z^-1 W Z^-1 E` (or `Z^-1 E`), fitted to the data on the sensors:
//!
//! | method | block `B` | expansion |
//! |---|---|---|
//! | dynamic (static: `lambda = 0`) | `Z^-1 E` | `x = B_S (C B_S)^-1 y` |
//! | minimum residual, `W = M^-1` | `Z^-1 M Z^-1 E` | `x = B_S (C B_S)^-1 y` |
//! | MDRE-WE, `K_s = K + s M` | `Z^-1 K_s Z^-1 E` | `x = B_S (C B_S + I / gamma)^-1 y` |
//!
//! Why these are the same expansions: the dynamic expansion is the `x` with `C x = y` whose
//! dynamic residual vanishes on the omitted DOFs, so `Z x = C^T f` for some sensor forces `f`;
//! the minimum-residual expansion's stationarity conditions are `Z M^-1 Z x = C^T mu` and
//! `C x = y`, and `(Z M^-1 Z)^-1 = Z^-1 M Z^-1`; MDRE-WE's normal equations
//! `(Z K_s^-1 Z + gamma C^T C) x = gamma C^T y` give the form above by the push-through identity.
//! (`det(C Z^-1 C^T) = det(Z_oo) / det(Z)`: the sensor-space system is singular exactly when the
//! omitted-DOF one is.)
//!
//! Cost: per distinct eigenvalue one sparse `LDL^T` of `Z` on `K`'s pattern (whose symbolic
//! analysis is done once) and 2-3 solves with as many right-hand sides as candidate DOFs; then
//! per sensor set only dense `s x s` solves. The saddle-point formulations of [`Expander`]
//! factor a system of size `n + n_o` or `2n` per mode and sensor set instead.
//!
//! Every result is checked a posteriori against the method's own optimality conditions in the
//! original variables (sparse products only). When `Z` cannot be factored (`lambda` exactly on a
//! model eigenvalue, or `K` singular for the static case of a free-free model) or a check fails,
//! the expansion is recomputed with [`Expander`]'s omitted-DOF or saddle-point formulation, which
//! either succeeds or reports why the expansion is not unique.

use crate::expansion::{Expander, Method, check_expansion_data, m_on_pattern};
use crate::{CorrelateError, Partition};
use faer::linalg::solvers::Solve;
use faer::{Mat, MatRef};
use femu_sparse::SparseMatrix;
use femu_sparse::cholesky::{Factorization, SymbolicFactor};
use femu_sparse::csc::sym_mul_mat;
use femu_sparse::ordering::Ordering;
use std::borrow::Cow;

/// Backward-error tolerance of the a posteriori checks: residuals of the method's conditions
/// relative to the size of the terms that cancel in them.
const CHECK_TOL: f64 = 1e-8;

/// The forms of [`Method`] the sensor space computes (static is dynamic at `lambda = 0`; SEREP
/// needs no factorization and is not one of them).
#[derive(Debug, Clone, Copy, PartialEq)]
enum SpaceMethod {
    /// Dynamic at the identified eigenvalue (static when it is 0).
    Dynamic,
    /// Minimum residual in the `M^-1` norm (sensor values imposed).
    MinimumResidual,
    /// MDRE-WE with test weight `gamma` and `K_s = K + stiffness_shift M`.
    Mdre {
        /// Weight of the test error.
        gamma: f64,
        /// Shift of the energy norm (0 for a restrained model).
        stiffness_shift: f64,
    },
}

/// Dense blocks at one eigenvalue.
#[derive(Debug, Clone)]
struct Blocks {
    /// `Z^-1 E`
    v: Mat<f64>,
    /// `Z^-1 M Z^-1 E`
    u_m: Mat<f64>,
    /// `Z^-1 K_s Z^-1 E` per stiffness shift
    u_k: Vec<(f64, Mat<f64>)>,
}

#[derive(Debug, Clone)]
struct Entry {
    lambda: f64,
    /// `None` when `Z` could not be factored
    blocks: Option<Blocks>,
}

/// Expansion through factorizations of the full `Z = K - lambda M`, shared by every sensor set
/// drawn from the candidate DOFs (see the module documentation for the formulas).
///
/// ```
/// use femu_correlate::{Expander, SensorSpace};
/// use femu_fem::prelude::*;
/// use femu_sparse::faer::Mat;
///
/// let mesh = box_mesh(&BoxSpec::new([0.2, 0.02, 0.02], [10, 1, 1], BoxCells::Hex, false)).unwrap();
/// let mut model = Model::new(mesh).unwrap();
/// model.set_material(None, Material::steel()).unwrap();
/// model.fix_set("xmin", &[0, 1, 2]).unwrap();
/// let sys = model.assemble(MassKind::Consistent).unwrap();
/// // eight candidate DOFs; sensor sets are any subsets of them
/// let candidates: Vec<usize> = (0..8).map(|i| 10 + 7 * i).collect();
/// let mut space = SensorSpace::new(&sys.k, &sys.m, &candidates).unwrap();
/// let lambda = [3.0e6];
/// for count in [8, 5] {
///     let measured = &candidates[..count];
///     let y = Mat::from_fn(count, 1, |i, _| (i as f64 + 1.0).sqrt());
///     let x = space.dynamic(&lambda, measured, y.as_ref()).unwrap();
///     // the same expansion by the omitted-DOF formulation of this sensor set
///     let reference = Expander::with_measured_dofs(&sys.k, &sys.m, measured)
///         .unwrap()
///         .dynamic(&lambda, y.as_ref())
///         .unwrap();
///     let diff = (&x - &reference).norm_l2() / reference.norm_l2();
///     assert!(diff < 1e-10, "{diff:e}");
///     // minimum residual from the same factorization
///     space.minimum_residual(&lambda, measured, y.as_ref()).unwrap();
/// }
/// // one factorization of Z served both sets and both methods
/// assert_eq!(space.factorizations(), 1);
/// ```
#[derive(Debug)]
pub struct SensorSpace<'a> {
    k: &'a SparseMatrix,
    m: &'a SparseMatrix,
    candidates: Vec<usize>,
    /// for each free DOF, its position in `candidates` (usize::MAX when not a candidate)
    slot: Vec<usize>,
    /// `M`'s values on `K`'s pattern (borrowed from an [`Expander`] that has them)
    m_on_k: Cow<'a, [f64]>,
    symbolic: Option<SymbolicFactor>,
    cache: Vec<Entry>,
    fallbacks: usize,
    factorizations: usize,
}

impl<'a> SensorSpace<'a> {
    /// Prepares expansion from any subset of the `candidates` (free DOFs, no repeats).
    ///
    /// # Errors
    /// `K` and `M` of different sizes, a candidate out of range or repeated, an entry of `M`
    /// outside `K`'s pattern.
    pub fn new(
        k: &'a SparseMatrix,
        m: &'a SparseMatrix,
        candidates: &[usize],
    ) -> Result<Self, CorrelateError> {
        Self::with_m_on_k(k, m, candidates, Cow::Owned(m_on_pattern(k, m)?))
    }

    /// [`SensorSpace::new`] with `M`'s values on `K`'s pattern already at hand.
    pub(crate) fn with_m_on_k(
        k: &'a SparseMatrix,
        m: &'a SparseMatrix,
        candidates: &[usize],
        m_on_k: Cow<'a, [f64]>,
    ) -> Result<Self, CorrelateError> {
        let n = k.rows();
        Partition::new(n, candidates)?;
        let mut slot = vec![usize::MAX; n];
        for (i, d) in candidates.iter().enumerate() {
            slot[*d] = i;
        }
        Ok(Self {
            k,
            m,
            candidates: candidates.to_vec(),
            slot,
            m_on_k,
            symbolic: None,
            cache: Vec::new(),
            fallbacks: 0,
            factorizations: 0,
        })
    }

    /// The candidate DOFs.
    pub fn candidates(&self) -> &[usize] {
        &self.candidates
    }

    /// How many expansions (one mode, one sensor set) were recomputed by [`Expander`] because
    /// `Z` could not be factored or a check failed.
    pub fn fallbacks(&self) -> usize {
        self.fallbacks
    }

    /// How many numeric factorizations of `Z` were made (one per distinct eigenvalue when
    /// [`SensorSpace::prepare`] was given every eigenvalue and shift first).
    pub fn factorizations(&self) -> usize {
        self.factorizations
    }

    /// Factors `Z` at each distinct eigenvalue of `lambdas` not yet seen (and again where a
    /// stiffness shift of `shifts` is missing) and forms the blocks: call it once before a
    /// sweep over sensor sets so each eigenvalue costs one factorization.
    ///
    /// # Errors
    /// A non-finite eigenvalue or shift, or a failure of the symbolic analysis.
    pub fn prepare(&mut self, lambdas: &[f64], shifts: &[f64]) -> Result<(), CorrelateError> {
        for &lambda in lambdas {
            self.entry(lambda, shifts)?;
        }
        Ok(())
    }

    /// Dynamic expansion (static for `lambda = 0`) of `ya` measured at `measured` (a subset of
    /// the candidates, in the rows' order), one eigenvalue per column. Full-length results with
    /// the measured values kept.
    ///
    /// # Errors
    /// A DOF that is not a candidate, sizes, NaN, and [`Expander::dynamic`]'s errors when the
    /// expansion is not unique.
    pub fn dynamic(
        &mut self,
        lambdas: &[f64],
        measured: &[usize],
        ya: MatRef<'_, f64>,
    ) -> Result<Mat<f64>, CorrelateError> {
        self.expand(Method::Dynamic, lambdas, measured, ya)
    }

    /// Minimum-residual expansion (`W = M^-1`, values imposed); see [`SensorSpace::dynamic`].
    ///
    /// # Errors
    /// As [`SensorSpace::dynamic`].
    pub fn minimum_residual(
        &mut self,
        lambdas: &[f64],
        measured: &[usize],
        ya: MatRef<'_, f64>,
    ) -> Result<Mat<f64>, CorrelateError> {
        self.expand(Method::MinimumResidual, lambdas, measured, ya)
    }

    /// MDRE-WE expansion (test values weighed by `gamma`, energy norm of `K + stiffness_shift M`);
    /// see [`Expander::mdre`] for the choice of the shift.
    ///
    /// # Errors
    /// `gamma` not positive, a negative shift, and as [`SensorSpace::dynamic`].
    pub fn mdre(
        &mut self,
        lambdas: &[f64],
        measured: &[usize],
        ya: MatRef<'_, f64>,
        gamma: f64,
        stiffness_shift: f64,
    ) -> Result<Mat<f64>, CorrelateError> {
        let method = Method::Mdre {
            gamma,
            stiffness_shift: Some(stiffness_shift),
        };
        self.expand(method, lambdas, measured, ya)
    }

    /// Static, dynamic, minimum-residual or MDRE-WE expansion by `method` (static is the dynamic
    /// expansion at `lambda = 0`; MDRE-WE's automatic shift is [`Method::stiffness_shift`]).
    ///
    /// # Errors
    /// SEREP (it needs model modes, not this factorization: use [`Expander::serep`]), and as the
    /// method's own function.
    pub fn expand(
        &mut self,
        method: Method,
        lambdas: &[f64],
        measured: &[usize],
        ya: MatRef<'_, f64>,
    ) -> Result<Mat<f64>, CorrelateError> {
        let zeros;
        let (method, lambdas) = match method {
            Method::Static => {
                zeros = vec![0.0; lambdas.len()];
                (SpaceMethod::Dynamic, &zeros[..])
            }
            Method::Dynamic => (SpaceMethod::Dynamic, lambdas),
            Method::MinimumResidual => (SpaceMethod::MinimumResidual, lambdas),
            Method::Mdre { gamma, .. } => (
                SpaceMethod::Mdre {
                    gamma,
                    stiffness_shift: method.stiffness_shift(lambdas).unwrap_or(0.0),
                },
                lambdas,
            ),
            Method::Serep(_) => {
                return Err(CorrelateError::Invalid {
                    what: "sensor-space expansion",
                    reason:
                        "SEREP expands with model modes, not a factorization: use Expander::serep"
                            .into(),
                });
            }
        };
        let n = self.k.rows();
        Partition::new(n, measured)?;
        let sel: Vec<usize> = measured
            .iter()
            .map(|d| match self.slot[*d] {
                usize::MAX => Err(CorrelateError::Invalid {
                    what: "sensor set",
                    reason: format!("DOF {d} is not one of the candidate DOFs"),
                }),
                s => Ok(s),
            })
            .collect::<Result<_, _>>()?;
        check_expansion_data(measured.len(), lambdas, ya)?;
        let shifts: Vec<f64> = match method {
            SpaceMethod::Mdre {
                gamma,
                stiffness_shift,
            } => {
                Expander::check_mdre_weights(gamma, stiffness_shift)?;
                vec![stiffness_shift]
            }
            _ => Vec::new(),
        };
        let mut x = Mat::zeros(n, lambdas.len());
        let mut failed = Vec::new();
        for (j, &lambda) in lambdas.iter().enumerate() {
            let y: Vec<f64> = ya.col(j).iter().copied().collect();
            let e = self.entry(lambda, &shifts)?;
            let solved = match self.cache[e].blocks.as_ref() {
                Some(blocks) => self.solve_one(method, lambda, blocks, measured, &sel, &y)?,
                None => None,
            };
            match solved {
                Some(xj) => x.col_mut(j).iter_mut().zip(&xj).for_each(|(a, b)| *a = *b),
                None => failed.push(j),
            }
        }
        if !failed.is_empty() {
            // built only here: extracting K_oo is work the sensor space exists to avoid
            let fallback = Expander::with_measured_dofs(self.k, self.m, measured)?;
            self.fallbacks += failed.len();
            let lam: Vec<f64> = failed.iter().map(|j| lambdas[*j]).collect();
            let yf = Mat::from_fn(measured.len(), failed.len(), |i, c| ya[(i, failed[c])]);
            let xf = match method {
                SpaceMethod::Dynamic => fallback.dynamic(&lam, yf.as_ref())?,
                SpaceMethod::MinimumResidual => {
                    fallback.minimum_residual_saddle_point(&lam, yf.as_ref())?
                }
                SpaceMethod::Mdre {
                    gamma,
                    stiffness_shift,
                } => fallback.mdre_saddle_point(&lam, yf.as_ref(), gamma, stiffness_shift)?,
            };
            for (c, &j) in failed.iter().enumerate() {
                for i in 0..n {
                    x[(i, j)] = xf[(i, c)];
                }
            }
        }
        Ok(x)
    }

    /// The index of the cached entry of `lambda`, factoring `Z` when it or one of `shifts` is missing.
    fn entry(&mut self, lambda: f64, shifts: &[f64]) -> Result<usize, CorrelateError> {
        if !lambda.is_finite() || shifts.iter().any(|s| !s.is_finite()) {
            return Err(CorrelateError::Invalid {
                what: "sensor-space expansion",
                reason: format!("eigenvalue {lambda} or a stiffness shift is not finite"),
            });
        }
        let pos = self.cache.iter().position(|e| e.lambda == lambda);
        let complete = |e: &Entry| match &e.blocks {
            None => true,
            Some(b) => shifts.iter().all(|s| b.u_k.iter().any(|(t, _)| t == s)),
        };
        if let Some(p) = pos
            && complete(&self.cache[p])
        {
            return Ok(p);
        }
        let mut all_shifts: Vec<f64> = shifts.to_vec();
        if let Some(Blocks { u_k, .. }) = pos.and_then(|p| self.cache[p].blocks.as_ref()) {
            all_shifts.extend(u_k.iter().map(|(s, _)| *s));
        }
        all_shifts.sort_by(f64::total_cmp);
        all_shifts.dedup();
        let blocks = self.factor_blocks(lambda, &all_shifts)?;
        let entry = Entry { lambda, blocks };
        let p = match pos {
            Some(p) => {
                self.cache[p] = entry;
                p
            }
            None => {
                self.cache.push(entry);
                self.cache.len() - 1
            }
        };
        Ok(p)
    }

    /// One `LDL^T` of `Z` and the blocks; `None` when `Z` has an exactly zero pivot.
    fn factor_blocks(
        &mut self,
        lambda: f64,
        shifts: &[f64],
    ) -> Result<Option<Blocks>, CorrelateError> {
        if self.symbolic.is_none() {
            self.symbolic = Some(SymbolicFactor::new(self.k, Ordering::NestedDissection)?);
        }
        let symbolic = self.symbolic.as_ref().expect("just set");
        let values: Vec<f64> = self
            .k
            .data()
            .iter()
            .zip(self.m_on_k.iter())
            .map(|(k, m)| k - lambda * m)
            .collect();
        self.factorizations += 1;
        let ldlt = match symbolic.ldlt_values(self.k, &values, "Z = K - lambda M") {
            Ok(l) => l,
            Err(femu_sparse::SparseError::Singular { .. }) => return Ok(None),
            Err(e) => return Err(e.into()),
        };
        let n = self.k.rows();
        let mut v = Mat::zeros(n, self.candidates.len());
        for (c, d) in self.candidates.iter().enumerate() {
            v[(*d, c)] = 1.0;
        }
        ldlt.solve_in_place(v.as_mut());
        let mut u_m = sym_mul_mat(self.m, v.as_ref())?;
        ldlt.solve_in_place(u_m.as_mut());
        let mut u_k = Vec::with_capacity(shifts.len());
        if !shifts.is_empty() {
            let kv = sym_mul_mat(self.k, v.as_ref())?;
            let mv = sym_mul_mat(self.m, v.as_ref())?;
            for &s in shifts {
                let mut u = &kv + &mv * faer::Scale(s);
                ldlt.solve_in_place(u.as_mut());
                u_k.push((s, u));
            }
        }
        Ok(Some(Blocks { v, u_m, u_k }))
    }

    /// One mode on one sensor set; `None` when the a posteriori check fails.
    fn solve_one(
        &self,
        method: SpaceMethod,
        lambda: f64,
        blocks: &Blocks,
        measured: &[usize],
        sel: &[usize],
        y: &[f64],
    ) -> Result<Option<Vec<f64>>, CorrelateError> {
        let (block, reg, shift) = match method {
            SpaceMethod::Dynamic => (&blocks.v, 0.0, None),
            SpaceMethod::MinimumResidual => (&blocks.u_m, 0.0, None),
            SpaceMethod::Mdre {
                gamma,
                stiffness_shift,
            } => {
                let u = blocks
                    .u_k
                    .iter()
                    .find(|(s, _)| *s == stiffness_shift)
                    .map(|(_, u)| u)
                    .expect("entry() formed the block of this shift");
                (u, 1.0 / gamma, Some(stiffness_shift))
            }
        };
        let s = sel.len();
        let g = Mat::from_fn(s, s, |i, j| {
            block[(measured[i], sel[j])] + if i == j { reg } else { 0.0 }
        });
        let rhs = Mat::from_fn(s, 1, |i, _| y[i]);
        let mu = g.full_piv_lu().solve(&rhs);
        if mu.col(0).iter().any(|v| !v.is_finite()) {
            return Ok(None);
        }
        let combine = |b: &Mat<f64>| {
            let bs = Mat::from_fn(b.nrows(), s, |i, j| b[(i, sel[j])]);
            bs * &mu
        };
        let x = combine(block);
        let n = x.nrows();
        let (kx, mx) = (
            sym_mul_mat(self.k, x.as_ref())?,
            sym_mul_mat(self.m, x.as_ref())?,
        );
        let zx: Vec<f64> = (0..n).map(|i| kx[(i, 0)] - lambda * mx[(i, 0)]).collect();
        let xs: Vec<f64> = x.col(0).iter().copied().collect();
        let scale_x = self.abs_norm(1.0, lambda.abs(), &xs);
        let mut flag = vec![false; n];
        measured.iter().for_each(|d| flag[*d] = true);
        let is_measured = |i: usize| flag[i];
        let misfit: Vec<f64> = (0..s).map(|i| x[(measured[i], 0)] - y[i]).collect();
        let ok = match method {
            SpaceMethod::Dynamic => {
                // (Z x)_o = 0 and C x = y
                let r_o = norm((0..n).filter(|i| !is_measured(*i)).map(|i| &zx[i]));
                within(r_o, scale_x) && within(norm(misfit.iter()), norm(y.iter()))
            }
            _ => {
                // Z x = W^-1 v and Z v = C^T mu' (v = Z^-1 E_S mu), with mu' = mu for imposed
                // values and gamma (y - C x) = mu for MDRE-WE (its misfit is free)
                let v = combine(&blocks.v);
                let (kv, mv) = (
                    sym_mul_mat(self.k, v.as_ref())?,
                    sym_mul_mat(self.m, v.as_ref())?,
                );
                let wv: Vec<f64> = match shift {
                    None => mv.col(0).iter().copied().collect(),
                    Some(sh) => (0..n).map(|i| kv[(i, 0)] + sh * mv[(i, 0)]).collect(),
                };
                let r1 = norm((0..n).map(|i| zx[i] - wv[i]).collect::<Vec<_>>().iter());
                let vs: Vec<f64> = v.col(0).iter().copied().collect();
                let scale_v = self.abs_norm(1.0, lambda.abs(), &vs);
                let scale_wv = match shift {
                    None => self.abs_norm(0.0, 1.0, &vs),
                    Some(sh) => self.abs_norm(1.0, sh, &vs),
                };
                let zv: Vec<f64> = (0..n).map(|i| kv[(i, 0)] - lambda * mv[(i, 0)]).collect();
                let r2 = norm((0..n).filter(|i| !is_measured(*i)).map(|i| &zv[i]));
                let conditions = within(r1, scale_x + scale_wv) && within(r2, scale_v);
                let data = match shift {
                    None => within(norm(misfit.iter()), norm(y.iter())),
                    // mu = gamma (y - C x) holds by the dense solve: check it anyway
                    Some(_) => within(
                        norm(
                            (0..s)
                                .map(|i| misfit[i] + reg * mu[(i, 0)])
                                .collect::<Vec<_>>()
                                .iter(),
                        ),
                        norm(y.iter()),
                    ),
                };
                conditions && data
            }
        };
        if !ok {
            return Ok(None);
        }
        let mut out: Vec<f64> = x.col(0).iter().copied().collect();
        if shift.is_none() {
            // imposed values: keep the data exactly, as the omitted-DOF formulation does
            for (i, d) in measured.iter().enumerate() {
                out[*d] = y[i];
            }
        }
        Ok(Some(out))
    }
}

impl SensorSpace<'_> {
    /// `|| a |K| |x| + b |M| |x| ||`: the size of the terms that cancel in `K x - lambda M x`
    /// entry by entry, the scale of a componentwise backward error (for a low mode, `Z x` and
    /// even `K x` are far below `||K|| ||x||`, and a normwise check would reject round-off).
    fn abs_norm(&self, a: f64, b: f64, x: &[f64]) -> f64 {
        let mut acc = vec![0.0; x.len()];
        for (mat, w) in [(self.k, a), (self.m, b)] {
            if w == 0.0 {
                continue;
            }
            let ptr = mat.indptr();
            let ptr = ptr.raw_storage();
            for (c, xc) in x.iter().enumerate() {
                for p in ptr[c]..ptr[c + 1] {
                    acc[mat.indices()[p]] += w * mat.data()[p].abs() * xc.abs();
                }
            }
        }
        norm(acc.iter())
    }
}

fn norm<'b>(v: impl Iterator<Item = &'b f64>) -> f64 {
    v.map(|a| a * a).sum::<f64>().sqrt()
}

/// `r <= CHECK_TOL * scale`, false for NaN; a zero residual passes against a zero scale.
fn within(r: f64, scale: f64) -> bool {
    r == 0.0 || r <= CHECK_TOL * scale
}
