//! Modal expansion: test shapes known on the measured DOFs `a` filled in on the omitted DOFs `o`
//! (docs/MATH.md, "Expansion"), with sparse factorizations only.
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
use femu_sparse::csc::{sym_mul_mat, sym_mul_mat_values_into};
use femu_sparse::kkt::QuasiDefinite;
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
    let mut m_on_k = vec![0.0; k.nnz()];
    femu_sparse::csc::for_entries_within(k, m, |pm, pk| m_on_k[pk] = m.data()[pm])?;
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

/// Expansion of measured shapes on one model and one sensor set.
#[derive(Debug, Clone)]
pub struct Expander<'a> {
    k: &'a SparseMatrix,
    m: &'a SparseMatrix,
    part: Partition,
    /// `M`'s values on `K`'s pattern (0 where `M` stores nothing), found once: every expansion
    /// forms `Z = K - lambda M` entry by entry on that pattern
    m_on_k: Vec<f64>,
    /// `K_oo` (CSC, both triangles) and `M_oo`'s values on its pattern, built on first use: only
    /// static and dynamic expansion use them, and SB-EBE builds an expander per trial
    oo: std::sync::OnceLock<(SparseMatrix, Vec<f64>)>,
    /// `K_oo`'s analysis, made on first use for the same reason
    symbolic: std::sync::OnceLock<SymbolicFactor>,
    /// modes of projected expansions the sensor space handed to the saddle point
    fallbacks: Counter,
}

/// A count shared by concurrent modes; a clone starts from the count so far.
#[derive(Debug, Default)]
struct Counter(std::sync::atomic::AtomicUsize);

impl Clone for Counter {
    fn clone(&self) -> Self {
        Self(self.get().into())
    }
}

impl Counter {
    fn get(&self) -> usize {
        self.0.load(std::sync::atomic::Ordering::Relaxed)
    }

    fn add(&self, n: usize) {
        self.0.fetch_add(n, std::sync::atomic::Ordering::Relaxed);
    }
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
        Ok(Self {
            k,
            m,
            part,
            m_on_k,
            oo: std::sync::OnceLock::new(),
            symbolic: std::sync::OnceLock::new(),
            fallbacks: Counter::default(),
        })
    }

    /// How many modes of [`Expander::minimum_residual_projected`] this expander computed by the
    /// saddle point after the sensor space failed them (`Z` with a zero pivot, or a check
    /// missed): each costs several times a sensor-space mode.
    pub fn projected_fallbacks(&self) -> usize {
        self.fallbacks.get()
    }

    /// The partition.
    pub fn partition(&self) -> &Partition {
        &self.part
    }

    /// `K_oo` and `M_oo`'s values on its pattern, built on first use.
    fn oo(&self) -> &(SparseMatrix, Vec<f64>) {
        self.oo.get_or_init(|| {
            let (k, part) = (self.k, &self.part);
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
                        mv.push(self.m_on_k[p]);
                    }
                }
                ptr.push(idx.len());
            }
            (SparseMatrix::new_csc((no, no), ptr, idx, kv), mv)
        })
    }

    /// A matrix's values on `K`'s pattern (`on_k`, one per stored entry of `K`) restricted to the
    /// omitted DOFs, in the order of `K_oo`'s entries.
    fn oo_values(&self, on_k: &[f64]) -> Vec<f64> {
        let (k, part) = (self.k, &self.part);
        let kp = k.indptr();
        let kp = kp.raw_storage();
        let mut v = Vec::with_capacity(self.oo().0.nnz());
        for &c in &part.omitted {
            for p in kp[c]..kp[c + 1] {
                if part.omitted_pos[k.indices()[p]] != usize::MAX {
                    v.push(on_k[p]);
                }
            }
        }
        v
    }

    /// The symbolic analysis of `K_oo`, computed on first use.
    fn symbolic_oo(&self) -> Result<&SymbolicFactor, CorrelateError> {
        if let Some(s) = self.symbolic.get() {
            return Ok(s);
        }
        let s = SymbolicFactor::new(&self.oo().0, Ordering::NestedDissection)?;
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
}

/// Expands measured shapes `ya` (one row per sensor of `layout`) to every free DOF by `method`.
/// When the sensors cover every free DOF, the readings are placed on their DOFs as they are.
/// SEREP uses `serep_basis`, or the model's lowest `M` modes when none is given.
///
/// # Errors
/// A test of frequencies alone (no reading to expand), sizes, NaN, two sensors too close for expansion ([`SensorBasis::new`]), and the method's
/// errors (a singular expansion).
pub fn expand_shapes(
    sys: &femu_fem::assembly::SystemMatrices,
    layout: &SensorLayout,
    lambdas: &[f64],
    ya: MatRef<'_, f64>,
    method: Method,
    serep_basis: Option<MatRef<'_, f64>>,
) -> Result<Mat<f64>, CorrelateError> {
    if ya.nrows() == 0 {
        return Err(CorrelateError::Invalid {
            what: "test",
            reason: "the test gives frequencies without mode shapes: expansion, the estimators and the sensor-removal study read the shapes at the sensors (correlation pairs by frequency, and updating fits the frequencies)".into(),
        });
    }
    // SEREP without a basis given: the model's lowest M modes, solved here (by femu's own
    // eigensolver, Sturm-verified); every front end's `serep:M` comes this way
    let solved;
    let serep_basis = match (method, serep_basis) {
        (Method::Serep(m), None) => {
            let modes = sys.modes(
                femu_sparse::eigen::Which::Lowest(m.min(sys.k.rows())),
                &femu_sparse::eigen::EigenOptions::default(),
            )?;
            solved = modes.vectors;
            Some(solved.as_ref())
        }
        (_, b) => b,
    };
    Ok(match layout.measured_dofs() {
        Some(dofs) if dofs.len() == sys.dofs.free_count() => {
            place_measured(sys.k.rows(), &dofs, ya)?
        }
        Some(_) => {
            Expander::new(&sys.k, &sys.m, layout)?.expand(method, lambdas, ya, serep_basis)?
        }
        // oblique sensors and sensors between nodes: expansion in the coordinates where every
        // reading is a DOF
        None => {
            SensorBasis::new(&sys.k, &sys.m, layout)?.expand(method, lambdas, ya, serep_basis)?
        }
    })
}

mod basis;
mod condensation;
pub mod forced;
mod mdre;
mod minimum_residual;
mod serep;

pub use basis::SensorBasis;
pub use forced::{DynamicStiffness, ForcedExpander, ForcedExpansion, ForcedLine};
pub use minimum_residual::TestErrorExpansion;

/// An expansion method: the one name for it in the expander, the sensor space, the
/// sensor-removal study, study files and the command line (`docs/MATH.md`, "Expansion").
///
/// The text form (for [`std::str::FromStr`], [`std::fmt::Display`] and serde) is `static`,
/// `dynamic`, `serep:M` (`M` model modes), `min-residual` and `mdre` (MDRE-WE with `gamma = 1` and
/// the automatic stiffness shift of [`Method::stiffness_shift`]).
///
/// ```
/// use femu_correlate::expansion::Method;
/// let m: Method = "min-residual".parse().unwrap();
/// assert_eq!(m, Method::MinimumResidual);
/// assert_eq!("serep:6".parse::<Method>().unwrap(), Method::Serep(6));
/// assert_eq!(Method::Dynamic.to_string(), "dynamic");
/// assert!("guyan".parse::<Method>().is_err());
/// ```
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(try_from = "String", into = "String")]
pub enum Method {
    /// Static (Guyan): `x_o = -K_oo^-1 K_oa x_a`.
    Static,
    /// Dynamic at the identified eigenvalue: `x_o = -Z_oo^-1 Z_oa x_a`.
    Dynamic,
    /// SEREP with the given number of model modes.
    Serep(usize),
    /// Minimum residual in the `M^-1` norm (sensor values imposed).
    MinimumResidual,
    /// MDRE-WE with test weight `gamma` and `K_s = K + stiffness_shift M`.
    Mdre {
        /// Weight of the test error.
        gamma: f64,
        /// The shift of the energy norm in s^-2 (0 for a restrained model); `None` for the
        /// automatic choice of [`Method::stiffness_shift`].
        stiffness_shift: Option<f64>,
    },
}

impl Method {
    /// The methods that need neither model modes nor settings, in the order of the paper's
    /// Figure 1 legend.
    pub const FIGURE1: [Method; 3] = [Method::Static, Method::Dynamic, Method::MinimumResidual];

    /// A short name for tables and legends (the text form without settings: `serep6`,
    /// `mdre-we`).
    pub fn name(&self) -> String {
        match self {
            Method::Static => "static".into(),
            Method::Dynamic => "dynamic".into(),
            Method::Serep(m) => format!("serep{m}"),
            Method::MinimumResidual => "min-residual".into(),
            Method::Mdre { .. } => "mdre-we".into(),
        }
    }

    /// MDRE-WE's stiffness shift for eigenvalues `lambdas`: the given one, or by default
    /// `1e-3 max lambda_id`, which a free-free model needs (its `K` is singular) and which changes
    /// the weight of an elastic mode `j` by `lambda_j / (lambda_j + shift)` in a restrained one.
    /// `None` for the other methods.
    pub fn stiffness_shift(&self, lambdas: &[f64]) -> Option<f64> {
        match self {
            Method::Mdre {
                stiffness_shift, ..
            } => Some(
                stiffness_shift
                    .unwrap_or_else(|| 1e-3 * lambdas.iter().copied().fold(0.0, f64::max)),
            ),
            _ => None,
        }
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Method::Serep(m) => write!(f, "serep:{m}"),
            Method::Mdre { .. } => f.write_str("mdre"),
            other => f.write_str(&other.name()),
        }
    }
}

impl std::str::FromStr for Method {
    type Err = CorrelateError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Ok(match s {
            "static" => Method::Static,
            "dynamic" => Method::Dynamic,
            "min-residual" => Method::MinimumResidual,
            "mdre" => Method::Mdre {
                gamma: 1.0,
                stiffness_shift: None,
            },
            other => match other.strip_prefix("serep:").map(str::parse::<usize>) {
                Some(Ok(m)) if m > 0 => Method::Serep(m),
                _ => {
                    return Err(CorrelateError::Invalid {
                        what: "expansion method",
                        reason: format!(
                            "'{other}': expected static, dynamic, serep:M (M >= 1 model modes), min-residual or mdre"
                        ),
                    });
                }
            },
        })
    }
}

impl TryFrom<String> for Method {
    type Error = CorrelateError;
    fn try_from(s: String) -> Result<Self, Self::Error> {
        s.parse()
    }
}

impl From<Method> for String {
    fn from(m: Method) -> String {
        m.to_string()
    }
}

impl Expander<'_> {
    /// Expands `ya` by `method` (a dispatcher over [`Expander::static_`], [`Expander::dynamic`],
    /// [`Expander::serep`] with the first `M` columns of `serep_basis`,
    /// [`Expander::minimum_residual`] and [`Expander::mdre`]).
    ///
    /// # Errors
    /// SEREP without a basis of enough modes, and the method's own errors.
    pub fn expand(
        &self,
        method: Method,
        lambdas: &[f64],
        ya: MatRef<'_, f64>,
        serep_basis: Option<MatRef<'_, f64>>,
    ) -> Result<Mat<f64>, CorrelateError> {
        match method {
            Method::Static => self.static_(ya),
            Method::Dynamic => self.dynamic(lambdas, ya),
            Method::Serep(count) => match serep_basis {
                Some(b) if count <= b.ncols() => self.serep(b.subcols(0, count), ya),
                _ => Err(CorrelateError::Invalid {
                    what: "SEREP",
                    reason: format!(
                        "{count} modes requested, basis has {}",
                        serep_basis.map_or(0, |b| b.ncols())
                    ),
                }),
            },
            Method::MinimumResidual => self.minimum_residual(lambdas, ya),
            Method::Mdre { gamma, .. } => {
                let shift = method.stiffness_shift(lambdas).unwrap_or(0.0);
                self.mdre(lambdas, ya, gamma, shift)
            }
        }
    }
}

/// Command-line values `static`, `dynamic`, `min-residual` and `mdre` (SEREP needs model modes,
/// which a command computes itself, so it is not offered).
#[cfg(feature = "clap")]
impl clap::ValueEnum for Method {
    fn value_variants<'a>() -> &'a [Self] {
        &[
            Method::Static,
            Method::Dynamic,
            Method::MinimumResidual,
            Method::Mdre {
                gamma: 1.0,
                stiffness_shift: None,
            },
        ]
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        use clap::builder::PossibleValue;
        match self {
            Method::Static => Some(PossibleValue::new("static").help("Guyan condensation")),
            Method::Dynamic => Some(
                PossibleValue::new("dynamic").help("dynamic condensation at the test eigenvalue"),
            ),
            Method::MinimumResidual => Some(
                PossibleValue::new("min-residual").help("least M^-1-norm residual, values imposed"),
            ),
            Method::Mdre { .. } => Some(
                PossibleValue::new("mdre")
                    .help("MDRE-WE: residual and test error weighed (gamma 1)"),
            ),
            Method::Serep(_) => None,
        }
    }
}

/// The diagonal metric `W^-1 = diag(M)` of the minimum-residual expansion, SB-EBE and the
/// localisation, with each DOF that has no mass (a shell's drilling rotation, a lumped beam's
/// rotations) given the smallest positive diagonal entry instead: a massless DOF has no inertia
/// force, so its residual is held to zero as strongly as the stiffest-weighted DOF's
/// (docs/MATH.md, "The residual metric on massless DOFs").
///
/// # Errors
/// [`CorrelateError::Invalid`] when no diagonal entry is positive, or one is negative or not
/// finite (a mass that is not positive semi-definite), with its index.
pub fn residual_metric(m: &SparseMatrix) -> Result<Vec<f64>, CorrelateError> {
    let mut d = femu_sparse::csc::diagonal(m);
    if let Some(i) = d.iter().position(|v| !(v.is_finite() && *v >= 0.0)) {
        return Err(CorrelateError::Invalid {
            what: "mass diagonal",
            reason: format!("entry {i} = {} must be zero or positive", d[i]),
        });
    }
    let floor = d
        .iter()
        .copied()
        .filter(|v| *v > 0.0)
        .fold(f64::INFINITY, f64::min);
    if !floor.is_finite() {
        return Err(CorrelateError::Invalid {
            what: "mass diagonal",
            reason: "no DOF has mass".into(),
        });
    }
    for v in &mut d {
        if *v == 0.0 {
            *v = floor;
        }
    }
    Ok(d)
}
