//! The frf workflow: a test's measured frequency response functions (universal file dataset 58,
//! function type 4) against the model's at the same DOFs and frequency lines, by modal
//! superposition with the residual flexibility of the modes above (docs/MATH.md, "Frequency
//! responses") or by solving the dynamic stiffness at each line ("Frequency responses,
//! directly"): FRAC per function, CSAC and CSF per line and reference.

use crate::StudyError;
use crate::load::LoadedModel;
use faer::c64;
use femu_correlate::frf::{
    Damping, DirectSystem, Frf, FrfOptions, ModalDampers, ResponseKind, csac, csf, direct_frf,
    frac, modal_frf_coupled, residual_flexibility_analysed, residual_flexibility_factored,
};
use femu_correlate::{Sensor, SensorLayout};
use femu_io::uff::{Ordinate, UffDof, UffFunction};
use femu_sparse::eigen::{EigenOptions, Which};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::Path;

/// The options of [`frf_correlation`]: the study file's `[frf]`, `femu frf`'s flags and Python's
/// keywords.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[serde(deny_unknown_fields, default)]
pub struct FrfRequest {
    /// In a study file's `[frf]`, the universal file of measured FRFs (relative to the study
    /// file); `femu frf` and Python take it as an argument.
    #[cfg_attr(feature = "clap", arg(skip))]
    pub file: Option<std::path::PathBuf>,
    /// Viscous damping ratio of every model mode (default 0.01 when no damping is given and the
    /// deck states none: a Nastran deck's `PARAM,G` is its loss factor).
    #[cfg_attr(feature = "clap", arg(long, value_name = "ZETA"))]
    pub damping_ratio: Option<f64>,
    /// A structural loss factor instead of viscous damping (`K (1 + i eta)`).
    #[cfg_attr(
        feature = "clap",
        arg(long, value_name = "ETA", conflicts_with = "damping_ratio")
    )]
    pub loss_factor: Option<f64>,
    /// Rayleigh damping `C = alpha M + beta K` instead: the two coefficients (s^-1 and s).
    #[cfg_attr(
        feature = "clap",
        arg(
            long,
            value_name = "ALPHA,BETA",
            value_delimiter = ',',
            conflicts_with_all = ["damping_ratio", "loss_factor"]
        )
    )]
    pub rayleigh: Option<Vec<f64>>,
    /// Solve the dynamic stiffness `K (1 + i eta) + i K4 + i w C - w^2 M` at every line (one
    /// sparse complex factorization each) instead of superposing modes: the model's own dampers
    /// (bushings' B, the GE of springs, bushings and damped materials) act whole (modal
    /// superposition projects them on its modes), and no mode is left out. Takes a loss factor or Rayleigh damping (modal ratios have no matrix); default:
    /// the deck's `PARAM,G` as a loss factor, else a loss factor of 0.02 (1 % viscous at
    /// resonance) on a model without dampers, none on one with them.
    #[cfg_attr(feature = "clap", arg(long, conflicts_with_all = ["damping_ratio", "damping_from"]))]
    pub direct: bool,
    /// The test's identified modes with their damping ratios (CSV with a `damping` column,
    /// universal file dataset 55, JSON): each model mode paired with a test mode (MAC) takes its
    /// ratio, the others `damping_ratio` (default 0.01). In a study file relative to the study
    /// file.
    #[cfg_attr(
        feature = "clap",
        arg(long, value_name = "TEST", conflicts_with = "loss_factor")
    )]
    pub damping_from: Option<std::path::PathBuf>,
    /// Model modes up to this multiple of the highest line; those above enter by their residual
    /// flexibility.
    #[cfg_attr(
        feature = "clap",
        arg(long, value_name = "FACTOR", default_value_t = 2.0)
    )]
    pub modes_up_to: f64,
    /// Update the model from the FRFs: candidate element sets (comma-separated), ranked by the
    /// FRF residue (4) on the tuned lines; the selected sets' stiffness factors and the damping
    /// (a loss factor, or Rayleigh's two coefficients) are fitted (SB-EBE on FRFs, then the
    /// output error), and the model is checked on the held-out lines. Starts from
    /// `--loss-factor` or `--rayleigh` (default: a loss factor of 0.02).
    #[cfg_attr(
        feature = "clap",
        arg(long, value_name = "SETS", value_delimiter = ',', conflicts_with_all = ["damping_ratio", "damping_from"])
    )]
    pub update: Vec<String>,
    /// With `--update`: the lowest N lines are tuned and the others held out for the check
    /// (default: the lowest two-thirds).
    #[cfg_attr(feature = "clap", arg(long, value_name = "N", requires = "update"))]
    pub tuned_lines: Option<usize>,
    /// With `--update`: at most this many lines of each band (tuned, held out), evenly picked,
    /// enter the fit and the check (each line is one complex factorization per step).
    #[cfg_attr(
        feature = "clap",
        arg(long, value_name = "N", default_value_t = 24, requires = "update")
    )]
    pub update_lines: usize,
    /// With `--update`: fit every candidate set instead of those the residue selects.
    #[cfg_attr(feature = "clap", arg(long, requires = "update"))]
    pub update_all: bool,
    /// Where the file carries coherence (dataset 58, function type 6) for a function, its lines
    /// below this coherence are left out of its FRAC, of the line's CSAC and of updating (default
    /// 0.8; 0 keeps every line).
    #[cfg_attr(feature = "clap", arg(long, value_name = "GAMMA2"))]
    pub min_coherence: Option<f64>,
    /// With `--update`: stop after SB-EBE on FRFs (the paper's method alone; without the output
    /// error that follows it by default, it is biased by measurement noise).
    #[cfg_attr(feature = "clap", arg(long, requires = "update"))]
    pub sb_ebe_only: bool,
    /// With `--update`: fit a structural loss factor for each updated set and one for the rest
    /// of the model (each starting at `--loss-factor`, or the deck's, or 0.02), instead of one
    /// for the whole model: damping that differs from region to region, as a joint, a damped
    /// layer or another material gives it (docs/MATH.md, "Updating from frequency responses").
    /// A deck whose materials damp their elements is always updated so, from the deck's values.
    #[cfg_attr(
        feature = "clap",
        arg(long, requires = "update", conflicts_with = "rayleigh")
    )]
    pub loss_factor_per_set: bool,
}

fn default_update_lines() -> usize {
    24
}

impl Default for FrfRequest {
    fn default() -> Self {
        Self {
            file: None,
            damping_ratio: None,
            loss_factor: None,
            rayleigh: None,
            direct: false,
            damping_from: None,
            modes_up_to: 2.0,
            update: Vec::new(),
            tuned_lines: None,
            update_lines: default_update_lines(),
            update_all: false,
            sb_ebe_only: false,
            min_coherence: None,
            loss_factor_per_set: false,
        }
    }
}

impl FrfRequest {
    /// Whether the request names a damping of its own (a ratio, a loss factor, Rayleigh
    /// coefficients or the test's ratios), which the deck's then does not replace.
    fn names_damping(&self) -> bool {
        self.damping_ratio.is_some()
            || self.loss_factor.is_some()
            || self.rayleigh.is_some()
            || self.damping_from.is_some()
    }

    /// The damping this request asks for.
    ///
    /// # Errors
    /// More than one of a ratio, a loss factor and Rayleigh coefficients; Rayleigh coefficients
    /// that are not two.
    pub fn damping(&self) -> Result<Damping, StudyError> {
        let given = [
            self.damping_ratio.is_some(),
            self.loss_factor.is_some(),
            self.rayleigh.is_some(),
        ];
        if given.iter().filter(|g| **g).count() > 1 {
            return Err(StudyError::invalid(
                "damping",
                "give one of a damping ratio, a loss factor and Rayleigh coefficients",
            ));
        }
        if let Some(r) = &self.rayleigh {
            let [alpha, beta] = r[..] else {
                return Err(StudyError::invalid(
                    "rayleigh",
                    format!(
                        "{} values: give the two coefficients alpha (of M) and beta (of K)",
                        r.len()
                    ),
                ));
            };
            return Ok(Damping::Rayleigh { alpha, beta });
        }
        match self.loss_factor {
            Some(eta) => Ok(Damping::LossFactor(eta)),
            None => Ok(Damping::Ratio(self.damping_ratio.unwrap_or(0.01))),
        }
    }
}

/// The damping the deck gives the whole model (Nastran's `PARAM,G` or `PARAM,ALPHA1`/`ALPHA2`,
/// CalculiX's `*DAMPING, ALPHA=,
/// BETA=`: [`femu_fem::model::UniformDamping`]) when the request names none, with a note that
/// says so.
fn deck_damping(
    request: &FrfRequest,
    model: &femu_fem::model::Model,
    notes: &mut Vec<String>,
) -> Option<Damping> {
    if request.names_damping() {
        return None;
    }
    let (damping, what) = match model.uniform_damping()? {
        femu_fem::model::UniformDamping::LossFactor(g) => {
            (Damping::LossFactor(g), format!("a loss factor of {g}"))
        }
        femu_fem::model::UniformDamping::Rayleigh { alpha, beta } => (
            Damping::Rayleigh { alpha, beta },
            format!("Rayleigh alpha {alpha:e} s^-1, beta {beta:e} s"),
        ),
    };
    notes.push(format!(
        "damping: the deck's own ({what}: Nastran's PARAM,G or PARAM,ALPHA1/ALPHA2, or *MODAL DAMPING, RAYLEIGH); --damping-ratio, --loss-factor or --rayleigh give another"
    ));
    Some(damping)
}

/// The structural damping the deck gives its elements (`Model::element_damping`) as a loss factor
/// per group of `up` and one for the rest, each plus the whole model's loss factor of `base` (the
/// deck's `PARAM,G`; a base that is not a loss factor is refused): the elements of a group must
/// share one `GE`, and so must those of no group (springs and bushings apart).
///
/// # Errors
/// A group, or the rest, whose elements' `GE` differ (named); Rayleigh damping beside it.
fn deck_group_loss_factors(
    up: &femu_update::UpdateModel<'_>,
    base: &femu_update::FrfDamping,
) -> Result<femu_update::FrfDamping, StudyError> {
    use femu_fem::structural::StructuralKind;
    use femu_update::FrfDamping;
    let base = match base {
        FrfDamping::LossFactor(g) => *g,
        FrfDamping::GroupLossFactors { rest, .. } => *rest,
        FrfDamping::Rayleigh { .. } => {
            return Err(StudyError::invalid(
                "update",
                "the deck's materials damp their elements and the deck gives Rayleigh damping too: updating fits loss factors, not both",
            ));
        }
    };
    let model = up.model();
    let (mesh, structural) = (model.mesh(), model.structural());
    let ge = |id: u64| model.element_damping().get(&id).copied().unwrap_or(0.0);
    let one = |name: &str, ids: &mut dyn Iterator<Item = u64>| -> Result<f64, StudyError> {
        let mut value: Option<(u64, f64)> = None;
        for id in ids {
            let g = ge(id);
            match value {
                Some((first, v)) if v != g => {
                    return Err(StudyError::invalid(
                        "update",
                        format!(
                            "{name}: elements {first} and {id} are damped differently (GE {v} and {g}); a loss factor per set needs one GE per set: update sets that follow the materials"
                        ),
                    ));
                }
                None => value = Some((id, g)),
                _ => {}
            }
        }
        Ok(base + value.map_or(0.0, |v| v.1))
    };
    let mut in_group = (
        vec![false; mesh.element_count()],
        vec![false; structural.len()],
    );
    let mut groups = Vec::with_capacity(up.groups().len());
    for g in up.groups() {
        for &e in &g.elements {
            in_group.0[e] = true;
        }
        for &e in &g.structural {
            in_group.1[e] = true;
        }
        let mut ids = g
            .elements
            .iter()
            .map(|&e| mesh.element(e).id)
            .chain(g.structural.iter().map(|&e| structural[e].id));
        groups.push(one(&format!("set {}", g.name), &mut ids)?);
    }
    let mut rest_ids = (0..mesh.element_count())
        .filter(|e| !in_group.0[*e])
        .map(|e| mesh.element(e).id)
        .chain(
            structural
                .iter()
                .enumerate()
                .filter(|(i, s)| {
                    !in_group.1[*i]
                        && !matches!(
                            s.kind,
                            StructuralKind::Spring(_) | StructuralKind::Bushing(_)
                        )
                })
                .map(|(_, s)| s.id),
        );
    let rest = one("the elements in no updated set", &mut rest_ids)?;
    Ok(FrfDamping::GroupLossFactors { rest, groups })
}

/// The modes' damping the deck states, with a note: Nastran's `SDAMPING` table at each mode's
/// frequency (`hz`), or Abaqus' and CalculiX's `*MODAL DAMPING` by mode number (a mode in no
/// range undamped), as viscous ratios ([`Damping::Ratios`]) or, where the deck makes it each
/// mode's complex stiffness (`PARAM,KDAMP,-1`, `*MODAL DAMPING, STRUCTURAL`:
/// [`femu_fem::model::Model::modal_damping_structural`]), as loss factors `2 zeta`
/// ([`Damping::LossFactors`]); `None` when it states neither.
pub(crate) fn deck_modal_damping(
    model: &femu_fem::model::Model,
    hz: &[f64],
    notes: &mut Vec<String>,
) -> Option<Damping> {
    let (ratios, source) = if let Some(table) = model.modal_damping() {
        let ratios: Vec<f64> = hz.iter().map(|f| table.ratio_at(*f)).collect();
        (
            ratios,
            if table.hold_ends {
                "the deck's modal damping by frequency (*MODAL DAMPING, DEFINITION=FREQUENCY RANGE) at each mode's frequency"
            } else {
                "the deck's modal damping table (SDAMPING) at each mode's frequency"
            }
            .to_string(),
        )
    } else if model.mode_rayleigh_ratio(1, 0.0).is_some() {
        let ratios: Vec<f64> = hz
            .iter()
            .enumerate()
            .map(|(r, f)| {
                model
                    .mode_rayleigh_ratio(r + 1, 2.0 * std::f64::consts::PI * f)
                    .unwrap_or(0.0)
            })
            .collect();
        (
            ratios,
            format!(
                "the deck's Rayleigh damping by mode number (*MODAL DAMPING, RAYLEIGH) on modes 1 to {}, alpha / (2 omega) + beta omega / 2 of each mode it names and the others undamped",
                hz.len()
            ),
        )
    } else {
        model.mode_ratio(1)?;
        let ratios: Vec<f64> = (1..=hz.len())
            .map(|r| model.mode_ratio(r).unwrap_or(0.0))
            .collect();
        (
            ratios,
            format!(
                "the deck's modal damping (*MODAL DAMPING) on modes 1 to {}, those it names with their value and the others undamped",
                hz.len()
            ),
        )
    };
    let structural = model.modal_damping_structural();
    let values: Vec<f64> = if structural {
        ratios.iter().map(|z| 2.0 * z).collect()
    } else {
        ratios
    };
    let (lo, hi) = values
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), v| (a.min(*v), b.max(*v)));
    notes.push(if structural {
        format!("damping: {source}, as each mode's complex stiffness lambda (1 + i g) (KDAMP = -1, *MODAL DAMPING, STRUCTURAL), loss factors {lo:.4} to {hi:.4}")
    } else {
        format!("damping: {source}, as viscous ratios {lo:.4} to {hi:.4}")
    });
    Some(if structural {
        Damping::LossFactors(values)
    } else {
        Damping::Ratios(values)
    })
}

/// The test's identified damping on the model modes it pairs with (MAC pairing with the
/// defaults, [`femu_correlate::correlate`]), `request.damping_ratio` (default 0.01) on the others.
///
/// # Errors
/// A loss factor given too, a test without damping ratios, the test's and the pairing's errors.
fn test_damping(
    model: &LoadedModel,
    test: &Path,
    request: &FrfRequest,
    modes: &femu_sparse::eigen::Modes,
    notes: &mut Vec<String>,
) -> Result<Damping, StudyError> {
    if request.loss_factor.is_some() || request.rayleigh.is_some() {
        return Err(StudyError::invalid(
            "damping",
            "the test's damping ratios are per mode: give them, a loss factor or Rayleigh coefficients, not two",
        ));
    }
    let t = crate::load::load_test(test, model)?;
    let Some(ratios) = &t.data.modes.damping_ratios else {
        return Err(StudyError::in_file(
            test,
            "damping",
            "the test gives no damping ratios (a damping column in CSV, dataset 55's ratios)",
        ));
    };
    let report = femu_correlate::correlate(
        &femu_correlate::ModeSet::from_modes(modes),
        &t.data.modes,
        &t.layout,
        &femu_correlate::PairingOptions::default(),
    )?;
    let default = request.damping_ratio.unwrap_or(0.01);
    let mut z = vec![default; modes.values.len()];
    let mut paired = Vec::new();
    for p in &report.pairing.pairs {
        z[p.model] = ratios[p.test];
        paired.push(format!(
            "model {} <- test {} ({:.3} %)",
            p.model + 1,
            p.test + 1,
            100.0 * ratios[p.test]
        ));
    }
    notes.push(format!(
        "damping: the test's ratios on {} paired mode{} ({}), {default} on the other {}",
        paired.len(),
        if paired.len() == 1 { "" } else { "s" },
        paired.join(", "),
        z.len() - paired.len()
    ));
    Ok(Damping::Ratios(z))
}

/// One measured FRF and its FRAC with the model's.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FunctionCorrelation {
    /// Response DOF, as `node+x` (or `-x`).
    pub response: String,
    /// Reference (excitation) DOF.
    pub reference: String,
    /// The frequency response assurance criterion over the lines.
    pub frac: f64,
    /// Lines left out of it for their coherence (below [`FrfRequest::min_coherence`]).
    pub low_coherence_lines: usize,
    /// Its row among the model FRFs' outputs.
    #[serde(skip)]
    pub output: usize,
    /// Its column among the model FRFs' inputs.
    #[serde(skip)]
    pub input: usize,
}

/// The deflections at one line for one reference: CSAC and CSF.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LineCorrelation {
    /// The line, Hz.
    pub hz: f64,
    /// The reference DOF.
    pub reference: String,
    /// Cross-signature assurance criterion (shape).
    pub csac: f64,
    /// Cross-signature scale factor (shape and amplitude).
    pub csf: f64,
}

/// What [`frf_correlation`] found.
#[derive(Debug, Clone, Serialize)]
pub struct FrfCorrelation {
    /// Receptance, mobility or accelerance (from the file's ordinate).
    pub kind: ResponseKind,
    /// The model's damping.
    pub damping: Damping,
    /// Whether the FRFs were solved directly at each line instead of superposed from modes.
    pub direct: bool,
    /// Model modes superposed, and the highest one's frequency (Hz) (none for the direct route).
    pub modes: (usize, f64),
    /// The direct route's largest backward error over the lines (after one refinement step).
    pub backward_error: Option<f64>,
    /// Whether the residual flexibility of the modes above was added.
    pub residual_flexibility: bool,
    /// One row per measured FRF.
    pub functions: Vec<FunctionCorrelation>,
    /// One row per line and reference.
    pub lines: Vec<LineCorrelation>,
    /// The frequency scaling that best aligns the model's FRFs with the test's (the modal route;
    /// the direct route would solve every line again for each trial).
    pub alignment: Option<Alignment>,
    /// The update from the FRFs, when asked (`--update`).
    pub update: Option<FrfUpdateStudy>,
    /// What the reader and the workflow noticed.
    pub notes: Vec<String>,
    /// The model's FRFs at the test's lines (outputs x inputs per line), for the writers.
    #[serde(skip)]
    pub model: Option<Frf>,
    /// The measured FRFs as read, in the order of `functions` (for the writers).
    #[serde(skip)]
    pub measured: Vec<UffFunction>,
}

fn dof_name(d: &UffDof) -> String {
    let axis = ["x", "y", "z"][(d.direction.unsigned_abs() as usize).clamp(1, 3) - 1];
    format!(
        "{}{}{axis}",
        d.node,
        if d.direction < 0 { "-" } else { "+" }
    )
}

/// The sensor of a dataset 58 DOF (a translation, signed), or why not.
fn sensor_of(d: &UffDof, what: &str, f: &UffFunction) -> Result<(Sensor, f64), String> {
    match d.direction.unsigned_abs() {
        1..=3 => Ok((
            Sensor::axis(d.node, d.direction.unsigned_abs() as usize - 1),
            d.direction.signum() as f64,
        )),
        _ => Err(format!(
            "FRF {} ({}): its {what} DOF has direction {}: femu's models have translations (1-3) at the test's nodes",
            f.numbers[0],
            f.ids[0].trim(),
            d.direction
        )),
    }
}

/// The response kind of an FRF from its ordinate numerator's specific data type (record 9).
fn kind_of(f: &UffFunction) -> Result<ResponseKind, String> {
    match f.axes[1].data_type {
        8 => Ok(ResponseKind::Receptance),
        11 => Ok(ResponseKind::Mobility),
        12 => Ok(ResponseKind::Accelerance),
        other => Err(format!(
            "FRF {}: ordinate data type {other} (record 9): femu compares displacement (8), velocity (11) or acceleration (12) over force",
            f.numbers[0]
        )),
    }
}

/// The measured FRFs of the universal file `path` against the model's: the test's response and
/// reference DOFs are the model's node ids (translations), its lines the FRFs' abscissa (Hz, the
/// same for every function), their values in the model's units (SI: m, N, s). Model modes up to
/// `request.modes_up_to` times the highest line are superposed with the request's damping, with
/// the residual flexibility of those above (for a model with rigid-body motions, that of its
/// elastic modes under loads balanced by the rigid-body inertia).
///
/// # Errors
/// A file without FRFs, FRFs of different lines or kinds, rotations, nodes the model does not
/// have, and the eigensolver's errors.
pub fn frf_correlation(
    model: &LoadedModel,
    path: &Path,
    request: &FrfRequest,
    eigen: &EigenOptions,
) -> Result<FrfCorrelation, StudyError> {
    frf_correlation_with(model, path, request, eigen, |_| {})
}

/// [`frf_correlation`], with `progress` told of each step of a long run (a line each: the update's
/// steps with their objective).
///
/// # Errors
/// As [`frf_correlation`].
pub fn frf_correlation_with(
    model: &LoadedModel,
    path: &Path,
    request: &FrfRequest,
    eigen: &EigenOptions,
    mut progress: impl FnMut(&str),
) -> Result<FrfCorrelation, StudyError> {
    let in_file = |reason: String| StudyError::in_file(path, "FRF", reason);
    let uff = femu_io::uff::read_uff(path)?;
    let mut notes: Vec<String> = uff.warnings.iter().map(ToString::to_string).collect();
    let functions: Vec<&UffFunction> = uff
        .functions
        .iter()
        .filter(|f| f.function_type == 4)
        .collect();
    let Some(first) = functions.first() else {
        return Err(in_file(
            "no frequency response function (dataset 58 with function type 4)".into(),
        ));
    };
    let lines = first.abscissa_values();
    if let Some(l) = (0..lines.len()).find(|&l| {
        !(lines[l].is_finite() && lines[l] >= 0.0) || (l > 0 && lines[l] <= lines[l - 1])
    }) {
        return Err(in_file(format!(
            "FRF {}: line {} is {} Hz after {} Hz: the lines must be finite, at or above 0 Hz and strictly increasing",
            first.numbers[0],
            l + 1,
            lines[l],
            if l > 0 { lines[l - 1] } else { f64::NAN }
        )));
    }
    let kind = kind_of(first).map_err(in_file)?;
    let mut outputs: Vec<Sensor> = Vec::new();
    let mut inputs: Vec<Sensor> = Vec::new();
    let mut pairs = Vec::with_capacity(functions.len());
    for f in &functions {
        if f.abscissa_values() != lines {
            return Err(in_file(format!(
                "FRF {} has other frequency lines than FRF {}: femu compares FRFs on one set of lines",
                f.numbers[0], first.numbers[0]
            )));
        }
        if kind_of(f).map_err(in_file)? != kind {
            return Err(in_file(format!(
                "FRF {} is a {:?} and FRF {} a {kind:?}: one kind at a time",
                f.numbers[0],
                kind_of(f).map_err(in_file)?,
                first.numbers[0]
            )));
        }
        let (o, so) = sensor_of(&f.response, "response", f).map_err(in_file)?;
        let (i, si) = sensor_of(&f.reference, "reference", f).map_err(in_file)?;
        let index = |list: &mut Vec<Sensor>, s: Sensor| match list.iter().position(|x| *x == s) {
            Some(k) => k,
            None => {
                list.push(s);
                list.len() - 1
            }
        };
        let (oi, ii) = (index(&mut outputs, o), index(&mut inputs, i));
        let values: Vec<c64> = match &f.ordinate {
            Ordinate::Complex(v) => v
                .iter()
                .map(|(re, im)| c64::new(*re, *im) * (so * si))
                .collect(),
            Ordinate::Real(v) => v.iter().map(|re| c64::new(*re * so * si, 0.0)).collect(),
        };

        pairs.push((f, oi, ii, values));
    }
    let measured_functions: Vec<&UffFunction> = pairs.iter().map(|p| *p.0).collect();
    let coherent = coherence_masks(
        &uff.functions,
        &measured_functions,
        &lines,
        request,
        &mut notes,
    )
    .map_err(in_file)?;
    let mesh = model.model.mesh();
    let outputs = SensorLayout::new(mesh, &model.sys.dofs, outputs)
        .map_err(|e| StudyError::within(path, e))?;
    let inputs = SensorLayout::new(mesh, &model.sys.dofs, inputs)
        .map_err(|e| StudyError::within(path, e))?;
    let dampers = model.asm.dampers(&model.model, model.sys.mass_kind)?;
    let solved = if request.direct {
        direct_route(
            model, request, &dampers, &outputs, &inputs, &lines, kind, &mut notes,
        )?
    } else {
        modal_route(
            model, request, eigen, &dampers, &outputs, &inputs, &lines, kind, &mut notes,
        )?
    };
    let Solved {
        frf,
        damping,
        modes,
        residual,
        backward_error,
        synthesis,
    } = solved;
    let triples: Vec<(usize, usize, &[c64])> = pairs.iter().map(|p| (p.1, p.2, &p.3[..])).collect();
    let mut rows = Vec::with_capacity(pairs.len());
    for ((f, oi, ii, values), keep) in pairs.iter().zip(&coherent) {
        let (test_curve, model_curve) = coherent_curves(values, &frf, keep, *oi, *ii);
        if test_curve.is_empty() {
            return Err(in_file(format!(
                "FRF {}: every line's coherence is below {} (--min-coherence)",
                f.numbers[0],
                request.min_coherence.unwrap_or(DEFAULT_MIN_COHERENCE)
            )));
        }
        rows.push(FunctionCorrelation {
            response: dof_name(&f.response),
            reference: dof_name(&f.reference),
            frac: frac(&test_curve, &model_curve).map_err(|e| StudyError::within(path, e))?,
            low_coherence_lines: keep.iter().filter(|k| !**k).count(),
            output: *oi,
            input: *ii,
        });
    }
    // the unscaled mean FRAC is the rows' (the same model curves on the same coherent lines)
    let unscaled = rows.iter().map(|r| r.frac).sum::<f64>() / rows.len().max(1) as f64;
    let alignment = match &synthesis {
        Some(syn) => Some(align(
            syn, &outputs, &inputs, &lines, &triples, &coherent, unscaled,
        )?),
        None => None,
    };
    let mut line_rows = Vec::new();
    for ii in 0..inputs.len() {
        let of_ref: Vec<usize> = (0..pairs.len()).filter(|&k| pairs[k].2 == ii).collect();
        let reference = dof_name(&pairs[of_ref[0]].0.reference);
        for (l, hz) in lines.iter().enumerate() {
            let here: Vec<usize> = of_ref.iter().copied().filter(|&k| coherent[k][l]).collect();
            let t: Vec<c64> = here.iter().map(|&k| pairs[k].3[l]).collect();
            let m: Vec<c64> = here.iter().map(|&k| frf.h[l][(pairs[k].1, ii)]).collect();
            // a line where the measured deflection is zero (a 0 Hz line of a mobility) has no shape
            let (Ok(a), Ok(s)) = (csac(&t, &m), csf(&t, &m)) else {
                continue;
            };
            line_rows.push(LineCorrelation {
                hz: *hz,
                reference: reference.clone(),
                csac: a,
                csf: s,
            });
        }
    }
    let update = if request.update.is_empty() {
        None
    } else {
        Some(
            update_from_frfs(
                model,
                &mut progress,
                request,
                &outputs,
                &inputs,
                &triples,
                &lines,
                &(0..lines.len())
                    .map(|l| coherent.iter().all(|c| c[l]))
                    .collect::<Vec<_>>(),
                kind,
                &mut notes,
            )
            .map_err(|e| StudyError::within(path, e))?,
        )
    };
    Ok(FrfCorrelation {
        kind,
        damping,
        alignment,
        update,
        direct: request.direct,
        modes,
        backward_error,
        residual_flexibility: residual,
        functions: rows,
        lines: line_rows,
        notes,
        model: Some(frf),
        measured: pairs.iter().map(|p| (*p.0).clone()).collect(),
    })
}

/// What the update from FRFs found ([`FrfRequest::update`]).
#[derive(Debug, Clone, Serialize)]
pub struct FrfUpdateStudy {
    /// The candidate sets, ranked by the FRF residue on the tuned lines (explained fraction of the
    /// residue objective, residual force, strain energy of the displacement residual).
    pub ranking: Vec<femu_update::localise::GroupIndicator>,
    /// The sets updated.
    pub updated: Vec<String>,
    /// The tuned band (Hz) and the lines of it used.
    pub tuned: (f64, f64, usize),
    /// The held-out band (Hz) and the lines of it used (none when every line is tuned).
    pub held_out: Option<(f64, f64, usize)>,
    /// The fit: parameters, loss factor, objective and steps.
    pub result: femu_update::FrfUpdate,
    /// RMS over the tuned lines of the receptance error `||H_model - H_test|| / ||H_test||`,
    /// before and after.
    pub tuned_error: (f64, f64),
    /// The same over the held-out lines (the truth check), before and after.
    pub held_out_error: Option<(f64, f64)>,
}

impl std::fmt::Display for FrfUpdateStudy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "\nUpdating from FRFs: {} lines tuned ({:.2}-{:.2} Hz)",
            self.tuned.2, self.tuned.0, self.tuned.1
        )?;
        writeln!(
            f,
            "\n| set | explained | residual force | strain energy |\n|---|---|---|---|"
        )?;
        for r in &self.ranking {
            writeln!(
                f,
                "| {} | {:.3} | {:.3e} | {:.3e} |",
                r.name, r.explained, r.residual_force, r.strain_energy
            )?;
        }
        writeln!(f, "\n{}", self.result)?;
        writeln!(
            f,
            "receptance error on the tuned lines (RMS): {:.4} -> {:.4}",
            self.tuned_error.0, self.tuned_error.1
        )?;
        match (self.held_out, self.held_out_error) {
            (Some((lo, hi, n)), Some((before, after))) => writeln!(
                f,
                "on the {n} held-out lines ({lo:.2}-{hi:.2} Hz), the truth check: {before:.4} -> {after:.4}: {}",
                if after < before {
                    "the updated model predicts lines it was not tuned on better"
                } else {
                    "the updated model does NOT predict the held-out lines better: the change is not confirmed"
                }
            ),
            _ => writeln!(f, "no held-out line: the update is not checked"),
        }
    }
}

/// At most `count` of `lines` (indices), evenly picked, the ends kept.
fn pick(lines: &[usize], count: usize) -> Vec<usize> {
    if lines.len() <= count || count < 2 {
        return lines.iter().copied().take(count.max(1)).collect();
    }
    let mut out: Vec<usize> = (0..count)
        .map(|i| lines[(i * (lines.len() - 1) + (count - 1) / 2) / (count - 1)])
        .collect();
    out.dedup();
    out
}

/// The update of [`FrfRequest::update`]: the measured FRFs as receptances on the model's free
/// DOFs, the lines split into a tuned and a held-out band, the candidate sets ranked by the FRF
/// residue, the selected ones (or all) fitted with the loss factor, and the receptance error
/// on both bands before and after.
#[allow(clippy::too_many_arguments)]
fn update_from_frfs(
    model: &LoadedModel,
    progress: &mut dyn FnMut(&str),
    request: &FrfRequest,
    outputs: &SensorLayout,
    inputs: &SensorLayout,
    pairs: &[(usize, usize, &[c64])],
    lines: &[f64],
    coherent: &[bool],
    kind: ResponseKind,
    notes: &mut Vec<String>,
) -> Result<FrfUpdateStudy, StudyError> {
    use femu_update::{
        FrfDamping, FrfMethod, FrfTest, FrfUpdateOptions, SelectionRule, UpdateModel,
    };
    if request.damping_ratio.is_some() || request.damping_from.is_some() {
        return Err(StudyError::invalid(
            "update",
            "updating from FRFs fits a loss factor or Rayleigh coefficients: give --loss-factor or --rayleigh (their start), not modal damping ratios",
        ));
    }
    {
        use femu_fem::structural::StructuralKind;
        let own = model.model.structural().iter().find(|e| match &e.kind {
            StructuralKind::Spring(sp) => sp.ge != 0.0 || sp.viscous != 0.0,
            StructuralKind::Bushing(b) => b.ge != 0.0 || b.b.iter().any(|v| *v != 0.0),
            _ => false,
        });
        if let Some(e) = own {
            return Err(StudyError::invalid(
                "update",
                format!(
                    "element {} is a spring or bushing with its own damping (GE or B), which updating from FRFs does not model: remove it or correlate only",
                    e.id
                ),
            ));
        }
    }
    if !model
        .model
        .direct_entries(femu_fem::model::DirectMatrix::StructuralDamping)
        .is_empty()
    {
        return Err(StudyError::invalid(
            "update",
            "the deck adds a structural damping matrix (K42GG), which updating from FRFs does not model: remove it or correlate only",
        ));
    }
    if let Some((id, _)) = model.model.element_rayleigh().iter().next() {
        return Err(StudyError::invalid(
            "update",
            format!(
                "element {id}'s material has Rayleigh damping (*DAMPING, ALPHA=, BETA=), which updating from FRFs does not model: remove it (updating fits a loss factor or Rayleigh damping of the whole model) or correlate only"
            ),
        ));
    }
    // a deck whose materials damp their elements (GE, *DAMPING STRUCTURAL) is updated with a loss
    // factor per set, started from the deck's
    let materials_damp = !model.model.element_damping().is_empty();
    if materials_damp && (request.loss_factor.is_some() || request.rayleigh.is_some()) {
        return Err(StudyError::invalid(
            "update",
            "the deck's materials damp their elements (GE, *DAMPING, STRUCTURAL): updating fits a loss factor per set started from the deck's values, so --loss-factor and --rayleigh do not apply (remove the materials' damping to fit one for the whole model)",
        ));
    }
    if model.matrices.is_some() {
        return Err(StudyError::invalid(
            "update",
            "updating from FRFs needs element sets: this model is another solver's matrices",
        ));
    }
    // the measured DOFs: every sensor along a free axis
    // every sensor of a dataset 58 is along an axis, and a layout refuses one on a held DOF
    let axis_dofs = |layout: &SensorLayout, what: &str| {
        layout.measured_dofs().ok_or_else(|| {
            StudyError::invalid("update", format!("a {what} is not along a free DOF"))
        })
    };
    let measured = axis_dofs(outputs, "response")?;
    let references = axis_dofs(inputs, "reference")?;
    // the receptance matrix of every line: every response under every reference
    let mut seen = vec![vec![false; references.len()]; measured.len()];
    for (oi, ii, _) in pairs {
        seen[*oi][*ii] = true;
    }
    if let Some((o, i)) = (0..measured.len())
        .flat_map(|o| (0..references.len()).map(move |i| (o, i)))
        .find(|(o, i)| !seen[*o][*i])
    {
        return Err(StudyError::invalid(
            "update",
            format!(
                "response {} has no FRF for reference {}: updating fits the full matrix (every response under every reference)",
                o + 1,
                i + 1
            ),
        ));
    }
    let positive: Vec<usize> = (0..lines.len())
        .filter(|&l| lines[l] > 0.0 && coherent[l])
        .collect();
    let at_zero = lines.iter().filter(|f| **f <= 0.0).count();
    if at_zero > 0 {
        notes.push(format!(
            "updating: {at_zero} line(s) at 0 Hz left out (no dynamic response)"
        ));
    }
    let incoherent = coherent.iter().filter(|c| !**c).count();
    if incoherent > 0 {
        notes.push(format!(
            "updating: {incoherent} line(s) left out where a function's coherence is below the threshold"
        ));
    }
    if positive.is_empty() {
        return Err(StudyError::invalid(
            "update",
            "no line above 0 Hz with every function's coherence above the threshold",
        ));
    }
    let two_pi = 2.0 * std::f64::consts::PI;
    let receptance: Vec<faer::Mat<c64>> = positive
        .iter()
        .map(|&l| {
            let w = two_pi * lines[l];
            let to_u = match kind {
                ResponseKind::Receptance => c64::new(1.0, 0.0),
                ResponseKind::Mobility => c64::new(0.0, w),
                ResponseKind::Accelerance => c64::new(-w * w, 0.0),
            };
            let mut h = faer::Mat::<c64>::zeros(measured.len(), references.len());
            for (oi, ii, values) in pairs {
                h[(*oi, *ii)] = values[l] / to_u;
            }
            h
        })
        .collect();
    let all = FrfTest {
        omegas: positive.iter().map(|&l| two_pi * lines[l]).collect(),
        measured,
        references,
        receptance,
    };
    let count = all.omegas.len();
    let tuned_count = request
        .tuned_lines
        .unwrap_or((2 * count).div_ceil(3))
        .min(count);
    if tuned_count == 0 {
        return Err(StudyError::invalid("tuned lines", "must be at least 1"));
    }
    if request.update_lines == 0 {
        return Err(StudyError::invalid("update lines", "must be at least 1"));
    }
    let tuned_idx = pick(&(0..tuned_count).collect::<Vec<_>>(), request.update_lines);
    let held_idx = pick(
        &(tuned_count..count).collect::<Vec<_>>(),
        request.update_lines,
    );
    let tuned = all.lines(&tuned_idx);
    let held = (!held_idx.is_empty()).then(|| all.lines(&held_idx));
    let hz = |t: &FrfTest| {
        (
            t.omegas[0] / two_pi,
            t.omegas[t.omegas.len() - 1] / two_pi,
            t.omegas.len(),
        )
    };
    let start = match deck_damping(request, &model.model, notes) {
        Some(d) => d,
        None => request.damping()?,
    };
    if model.model.modal_damping().is_some() {
        notes.push("updating: the deck's modal damping table (SDAMPING, or *MODAL DAMPING by frequency) is not used: updating from FRFs fits loss factors or Rayleigh damping".into());
    }
    // with the materials' damping, the whole model's is the deck's PARAM,G alone (none: 0)
    let deck_base = match model.model.uniform_damping() {
        Some(femu_fem::model::UniformDamping::LossFactor(g)) => FrfDamping::LossFactor(g),
        Some(femu_fem::model::UniformDamping::Rayleigh { alpha, beta }) => {
            FrfDamping::Rayleigh { alpha, beta }
        }
        None => FrfDamping::LossFactor(0.0),
    };
    let damping = match start {
        Damping::Rayleigh { alpha, beta } => FrfDamping::Rayleigh { alpha, beta },
        Damping::LossFactor(eta) => FrfDamping::LossFactor(eta),
        _ if materials_damp => deck_base.clone(),
        _ => {
            notes.push("updating: the loss factor starts at 0.02 (--loss-factor or --rayleigh gives another start)".into());
            FrfDamping::LossFactor(0.02)
        }
    };
    damping.check()?;
    let sets = crate::updating::resolve_sets(model, &request.update)?;
    let set_refs: Vec<&str> = sets.iter().map(String::as_str).collect();
    let build = |names: &[&str]| -> Result<UpdateModel<'_>, StudyError> {
        let groups = femu_fem::groups::ParameterGroups::from_element_sets(
            &model.model,
            names,
            model.sys.mass_kind,
        )?;
        Ok(UpdateModel::from_assembly(
            &model.model,
            groups,
            femu_update::Corrections::Stiffness,
            model.asm.clone(),
            model.sys.clone(),
        )?)
    };
    let candidates = build(&set_refs)?;
    let damping = if materials_damp {
        deck_group_loss_factors(&candidates, &deck_base)?
    } else {
        damping
    };
    let localisation =
        femu_update::frf_localise(&candidates, &tuned, &damping, &SelectionRule::default())?;
    let updated: Vec<&str> = if request.update_all {
        set_refs.clone()
    } else {
        localisation.selected.iter().map(|&g| set_refs[g]).collect()
    };
    if updated.is_empty() {
        return Err(StudyError::invalid(
            "update",
            "the FRF residue selects no candidate set (none removes a share of it: the model already reproduces the tuned lines, or the sets cannot change it); --update-all fits every candidate",
        ));
    }
    let mut up = build(&updated)?;
    let damping = match (request.loss_factor_per_set, damping) {
        (_, FrfDamping::GroupLossFactors { .. }) => {
            let d = deck_group_loss_factors(&up, &deck_base)?;
            notes.push(format!(
                "updating: the deck's materials damp their elements: a loss factor for each of {} and one for the rest, started from the deck's ({d})",
                updated.join(", ")
            ));
            d
        }
        (false, d) => d,
        (true, FrfDamping::LossFactor(eta)) => {
            notes.push(format!(
                "updating: a loss factor for each of {} and one for the rest of the model, each starting at {eta}",
                updated.join(", ")
            ));
            FrfDamping::GroupLossFactors {
                rest: eta,
                groups: vec![eta; updated.len()],
            }
        }
        (true, _) => {
            return Err(StudyError::invalid(
                "loss factor per set",
                "per-set loss factors start from a loss factor (--loss-factor, or the deck's PARAM,G), not Rayleigh coefficients",
            ));
        }
    };
    damping.check_for(&up)?;
    let rms = |v: &[f64]| (v.iter().map(|e| e * e).sum::<f64>() / v.len().max(1) as f64).sqrt();
    let tuned_before = rms(&femu_update::frf_errors(&up, &tuned, &damping)?);
    let held_before = match &held {
        Some(h) => Some(rms(&femu_update::frf_errors(&up, h, &damping)?)),
        None => None,
    };
    let options = FrfUpdateOptions {
        damping,
        method: if request.sb_ebe_only {
            FrfMethod::SbEbe
        } else {
            FrfMethod::OutputError
        },
        ..Default::default()
    };
    let mut steps = 0;
    let result = femu_update::frf_update_logged(&mut up, &tuned, &options, |step| {
        steps += 1;
        progress(&format!(
            "updating from the FRFs ({}): step {steps}, objective {:.4e}",
            match step.method {
                FrfMethod::SbEbe => "SB-EBE",
                FrfMethod::OutputError => "output error",
            },
            step.objective
        ))
    })?;
    let tuned_after = rms(&femu_update::frf_errors(&up, &tuned, &result.damping)?);
    let held_out_error = match (&held, held_before) {
        (Some(h), Some(before)) => Some((
            before,
            rms(&femu_update::frf_errors(&up, h, &result.damping)?),
        )),
        _ => None,
    };
    Ok(FrfUpdateStudy {
        ranking: localisation.ranking,
        updated: updated.iter().map(|s| s.to_string()).collect(),
        tuned: hz(&tuned),
        held_out: held.as_ref().map(hz),
        result,
        tuned_error: (tuned_before, tuned_after),
        held_out_error,
    })
}

/// The measured values of one function and the model's (output `oi`, input `ii`) at the lines
/// `keep` marks.
fn coherent_curves(
    values: &[c64],
    frf: &Frf,
    keep: &[bool],
    oi: usize,
    ii: usize,
) -> (Vec<c64>, Vec<c64>) {
    values
        .iter()
        .zip(&frf.h)
        .zip(keep)
        .filter(|(_, k)| **k)
        .map(|((v, h), _)| (*v, h[(oi, ii)]))
        .unzip()
}

/// [`FrfRequest::min_coherence`]'s default.
const DEFAULT_MIN_COHERENCE: f64 = 0.8;

/// For each measured FRF, whether each line's coherence (the file's dataset 58 of function type
/// 6 with the same response and reference, if any) is at least the request's threshold.
fn coherence_masks(
    all: &[UffFunction],
    measured: &[&UffFunction],
    lines: &[f64],
    request: &FrfRequest,
    notes: &mut Vec<String>,
) -> Result<Vec<Vec<bool>>, String> {
    let threshold = request.min_coherence.unwrap_or(DEFAULT_MIN_COHERENCE);
    if !(0.0..=1.0).contains(&threshold) {
        return Err(format!(
            "a minimum coherence of {threshold}: coherence is between 0 and 1"
        ));
    }
    let coherence: Vec<&UffFunction> = all.iter().filter(|f| f.function_type == 6).collect();
    let mut masks = vec![vec![true; lines.len()]; measured.len()];
    if coherence.is_empty() {
        return Ok(masks);
    }
    let (mut without, mut low) = (Vec::new(), 0usize);
    for (f, mask) in measured.iter().zip(&mut masks) {
        let Some(c) = coherence
            .iter()
            .find(|c| c.response == f.response && c.reference == f.reference)
        else {
            without.push(f.numbers[0].to_string());
            continue;
        };
        if c.abscissa_values() != lines {
            return Err(format!(
                "coherence function {} has other lines than FRF {}",
                c.numbers[0], f.numbers[0]
            ));
        }
        let values: Vec<f64> = match &c.ordinate {
            Ordinate::Real(v) => v.clone(),
            Ordinate::Complex(v) => v.iter().map(|(re, _)| *re).collect(),
        };
        for (l, (gamma, keep)) in values.iter().zip(mask.iter_mut()).enumerate() {
            // round-off of an estimator may leave a coherence a little above 1
            if !(gamma.is_finite() && (-1e-6..=1.0 + 1e-6).contains(gamma)) {
                return Err(format!(
                    "coherence function {} at {} Hz is {gamma}: coherence is between 0 and 1",
                    c.numbers[0], lines[l]
                ));
            }
            *keep = *gamma >= threshold;
            low += usize::from(!*keep);
        }
    }
    if low > 0 {
        notes.push(format!(
            "{low} line(s) of the measured functions have a coherence below {threshold} and are left out (--min-coherence)"
        ));
    }
    if !without.is_empty() {
        notes.push(format!(
            "the file carries coherence, but not for FRF {}: all their lines are used",
            without.join(", ")
        ));
    }
    Ok(masks)
}

/// The model's FRFs and how they were formed.
struct Solved {
    frf: Frf,
    damping: Damping,
    modes: (usize, f64),
    residual: bool,
    backward_error: Option<f64>,
    /// The modal route's ingredients, to evaluate the model at other lines (the alignment).
    synthesis: Option<Synthesis>,
}

/// What modal superposition needs to evaluate the model's FRFs at any line.
struct Synthesis {
    values: Vec<f64>,
    vectors: faer::Mat<f64>,
    residual: Option<faer::Mat<f64>>,
    options: FrfOptions,
    /// The model's own dampers projected on the modes.
    dampers: Option<ModalDampers>,
}

/// The frequency scaling that best aligns the model's FRFs with the test's.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Alignment {
    /// `kappa`: the model's FRFs evaluated at `kappa f` match the test's at `f` best (mean FRAC
    /// over the functions); above 1 the model's resonances are high (the model is stiff).
    pub factor: f64,
    /// The mean FRAC at that scaling.
    pub mean_frac: f64,
    /// The mean FRAC unscaled.
    pub mean_frac_unscaled: f64,
}

/// The scaling `kappa` in `[0.8, 1.25]` that maximises the mean FRAC of the model's FRFs at
/// `kappa f` against the test's at `f` (coherent lines only): a geometric grid of 91 points, then
/// golden-section search between the best point's neighbours; `unscaled` is the mean FRAC at 1.
fn align(
    synthesis: &Synthesis,
    outputs: &SensorLayout,
    inputs: &SensorLayout,
    lines: &[f64],
    pairs: &[(usize, usize, &[c64])],
    coherent: &[Vec<bool>],
    unscaled: f64,
) -> Result<Alignment, StudyError> {
    let mean_frac = |kappa: f64| -> Result<f64, StudyError> {
        let shifted: Vec<f64> = lines.iter().map(|f| kappa * f).collect();
        let frf = modal_frf_coupled(
            &synthesis.values,
            synthesis.vectors.as_ref(),
            synthesis.residual.as_ref().map(|r| r.as_ref()),
            outputs,
            inputs,
            &shifted,
            &synthesis.options,
            synthesis.dampers.as_ref(),
        )?;
        let mut sum = 0.0;
        for ((oi, ii, values), keep) in pairs.iter().zip(coherent) {
            let (t, m) = coherent_curves(values, &frf, keep, *oi, *ii);
            sum += frac(&t, &m).unwrap_or(0.0);
        }
        Ok(sum / pairs.len().max(1) as f64)
    };
    let (lo, hi, n) = (0.8f64, 1.25f64, 91);
    let grid: Vec<f64> = (0..n)
        .map(|i| lo * (hi / lo).powf(i as f64 / (n - 1) as f64))
        .collect();
    let scores = grid
        .iter()
        .map(|k| mean_frac(*k))
        .collect::<Result<Vec<_>, _>>()?;
    let best = (0..n)
        .max_by(|a, b| scores[*a].total_cmp(&scores[*b]))
        .unwrap_or(0);
    let (mut a, mut b) = (grid[best.saturating_sub(1)], grid[(best + 1).min(n - 1)]);
    let g = (5f64.sqrt() - 1.0) / 2.0;
    let (mut c, mut d) = (b - g * (b - a), a + g * (b - a));
    let (mut fc, mut fd) = (mean_frac(c)?, mean_frac(d)?);
    while b - a > 1e-6 {
        if fc >= fd {
            b = d;
            d = c;
            fd = fc;
            c = b - g * (b - a);
            fc = mean_frac(c)?;
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + g * (b - a);
            fd = mean_frac(d)?;
        }
    }
    let (factor, score) = if fc.max(fd) >= scores[best] {
        if fc >= fd { (c, fc) } else { (d, fd) }
    } else {
        (grid[best], scores[best])
    };
    Ok(Alignment {
        factor,
        mean_frac: score,
        mean_frac_unscaled: unscaled,
    })
}

/// Modal superposition of the modes up to `request.modes_up_to` times the highest line, with the
/// residual flexibility of those above (for a model with rigid-body motions, of its elastic modes
/// under loads balanced by the rigid-body inertia).
#[allow(clippy::too_many_arguments)]
fn modal_route(
    model: &LoadedModel,
    request: &FrfRequest,
    eigen: &EigenOptions,
    dampers: &femu_fem::assembly::Dampers,
    outputs: &SensorLayout,
    inputs: &SensorLayout,
    lines: &[f64],
    kind: ResponseKind,
    notes: &mut Vec<String>,
) -> Result<Solved, StudyError> {
    // the model's modes up to the request's multiple of the highest line
    let f_max = lines.iter().copied().fold(0.0, f64::max);
    let w_top = 2.0 * std::f64::consts::PI * request.modes_up_to * f_max;
    if !(request.modes_up_to >= 1.0 && w_top.is_finite() && w_top > 0.0) {
        return Err(StudyError::invalid(
            "modes_up_to",
            format!(
                "{} times the highest line ({f_max} Hz): give a factor of at least 1 and lines above 0 Hz",
                request.modes_up_to
            ),
        ));
    }
    let hi = w_top * w_top;
    // the band's lower-end factor kept: the residual flexibility solves with it, no factorization
    // of K of its own (docs/MATH.md, "Residual flexibility from the eigensolver's factor")
    let keep = EigenOptions {
        keep_factor: true,
        ..eigen.clone()
    };
    let mut modes = model.sys.modes(Which::Band { lo: -1e-6 * hi, hi }, &keep)?;
    let top_hz = modes
        .values
        .last()
        .map_or(0.0, |l| l.max(0.0).sqrt() / (2.0 * std::f64::consts::PI));
    // rigid-body eigenvalues are round-off far below the first elastic one
    let rigid = modes.values.iter().filter(|l| **l < 1e-8 * hi).count();
    let residual = match modes.factor.take() {
        Some(factor) => {
            if rigid > 0 {
                notes.push(format!(
                    "residual flexibility of the elastic modes above the band, the loads balanced by the inertia of the {rigid} rigid-body modes (inertia relief)"
                ));
            }
            Some(residual_flexibility_factored(
                &model.sys.k,
                &model.sys.m,
                &factor,
                &modes.values,
                modes.vectors.as_ref(),
                outputs,
                inputs,
            )?)
        }
        // (an engine that keeps no factor)
        None if rigid > 0 => {
            notes.push(
                "no residual flexibility: the model has rigid-body motions and the engine kept no factor to balance them with; modes above the band are left out".into(),
            );
            None
        }
        None => Some(residual_flexibility_analysed(
            &model.sys.k,
            model.sys.analysis(),
            &modes.values,
            modes.vectors.as_ref(),
            outputs,
            inputs,
        )?),
    };
    let mut from_deck = deck_damping(request, &model.model, notes);
    if !request.names_damping()
        && let Some(modal) = deck_modal_damping(&model.model, &modes.frequencies_hz(), notes)
    {
        if from_deck.is_some() {
            return Err(StudyError::invalid(
                "damping",
                "the deck gives both a damping of the whole model (PARAM,G or ALPHA1/ALPHA2, or *MODAL DAMPING, RAYLEIGH) and modal damping ratios (SDAMPING's table, or *MODAL DAMPING): Nastran adds them, femu takes one; give --damping-ratio, --loss-factor or --rayleigh",
            ));
        }
        from_deck = Some(modal);
    }
    let by_default = from_deck.is_none() && !request.names_damping();
    let damping = match (&request.damping_from, from_deck) {
        (Some(test), _) => test_damping(model, test, request, &modes, notes)?,
        (None, Some(d)) => d,
        (None, None) => request.damping()?,
    };
    if by_default {
        notes.push("damping: 1 % viscous on every mode (the default; --damping-ratio, --loss-factor or --rayleigh give another)".into());
    }
    let options = FrfOptions {
        damping: damping.clone(),
        kind,
    };
    // the model's own dampers, which the modes do not diagonalise: projected on them and the
    // modal equations solved together at each line
    let projected = if dampers.any() {
        notes.push(format!(
            "the model's own dampers (bushings' B, the GE of springs, bushings and damped materials, the materials' Rayleigh damping) projected on the {} modes and the modal equations solved together at each line (--direct solves the whole model)",
            modes.values.len()
        ));
        Some(ModalDampers::project(
            dampers.structural.as_ref(),
            dampers.viscous.as_ref(),
            modes.vectors.as_ref(),
        )?)
    } else {
        None
    };
    let frf = modal_frf_coupled(
        &modes.values,
        modes.vectors.as_ref(),
        residual.as_ref().map(|r| r.as_ref()),
        outputs,
        inputs,
        lines,
        &options,
        projected.as_ref(),
    )?;
    Ok(Solved {
        frf,
        damping,
        modes: (modes.values.len(), top_hz),
        residual: residual.is_some(),
        backward_error: None,
        synthesis: Some(Synthesis {
            values: modes.values.clone(),
            vectors: modes.vectors.clone(),
            residual,
            options,
            dampers: projected,
        }),
    })
}

/// The dynamic stiffness solved at every line with the request's loss factor or Rayleigh damping
/// and the model's own dampers.
#[allow(clippy::too_many_arguments)]
fn direct_route(
    model: &LoadedModel,
    request: &FrfRequest,
    dampers: &femu_fem::assembly::Dampers,
    outputs: &SensorLayout,
    inputs: &SensorLayout,
    lines: &[f64],
    kind: ResponseKind,
    notes: &mut Vec<String>,
) -> Result<Solved, StudyError> {
    if request.damping_ratio.is_some() || request.damping_from.is_some() {
        return Err(StudyError::invalid(
            "damping",
            "modal damping ratios have no damping matrix: the direct route takes a loss factor or Rayleigh coefficients (and the model's own dampers)",
        ));
    }
    if model.model.modal_damping().is_some()
        || model.model.mode_ratio(1).is_some()
        || model.model.mode_rayleigh_ratio(1, 0.0).is_some()
    {
        notes.push("the deck's modal damping (SDAMPING, *MODAL DAMPING) acts in modal superposition, not in the direct route (as in Nastran's direct frequency response)".into());
    }
    let damping = if request.loss_factor.is_some() || request.rayleigh.is_some() {
        request.damping()?
    } else if let Some(d) = deck_damping(request, &model.model, notes) {
        d
    } else if dampers.any() {
        notes.push(
            "damping: the model's own dampers alone (--loss-factor or --rayleigh add more)".into(),
        );
        Damping::Ratio(0.0)
    } else {
        notes.push("damping: a loss factor of 0.02 (the default of the direct route on a model without dampers: 1 % viscous at resonance; --loss-factor or --rayleigh give another)".into());
        Damping::LossFactor(0.02)
    };
    let system = DirectSystem {
        k: &model.sys.k,
        m: &model.sys.m,
        viscous: dampers.viscous.as_ref(),
        structural: dampers.structural.as_ref(),
    };
    let options = FrfOptions {
        damping: damping.clone(),
        kind,
    };
    let d = direct_frf(&system, outputs, inputs, lines, &options)?;
    let worst = d.backward_errors.iter().copied().fold(0.0, f64::max);
    if worst > 1e-10 {
        notes.push(format!(
            "the direct solves reached a backward error of {worst:.1e} only (the dynamic stiffness is nearly singular at a line)"
        ));
    }
    Ok(Solved {
        frf: d.frf,
        damping,
        modes: (0, 0.0),
        residual: false,
        backward_error: Some(worst),
        synthesis: None,
    })
}

impl std::fmt::Display for FrfCorrelation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mut s = String::new();
        let what = match self.kind {
            ResponseKind::Receptance => "Receptance",
            ResponseKind::Mobility => "Mobility",
            ResponseKind::Accelerance => "Accelerance",
        };
        if self.direct {
            let _ = writeln!(
                s,
                "{what} solved directly at {} lines (largest backward error {:.1e}), damping: {}",
                self.model.as_ref().map_or(0, |m| m.lines_hz.len()),
                self.backward_error.unwrap_or(0.0),
                self.damping
            );
        } else {
            let _ = writeln!(
                s,
                "{what} of {} model modes (up to {:.2} Hz){}, damping: {}",
                self.modes.0,
                self.modes.1,
                if self.residual_flexibility {
                    " with the residual flexibility of those above"
                } else {
                    ""
                },
                self.damping
            );
        }
        let _ = writeln!(s, "\n| response | reference | FRAC |\n|---|---|---|");
        for r in &self.functions {
            let _ = writeln!(s, "| {} | {} | {:.4} |", r.response, r.reference, r.frac);
        }
        let mut refs: Vec<&str> = self.lines.iter().map(|l| l.reference.as_str()).collect();
        refs.dedup();
        let _ = writeln!(
            s,
            "\n| reference | lines | mean CSAC | lowest CSAC (Hz) | mean CSF |\n|---|---|---|---|---|"
        );
        for r in refs {
            let l: Vec<&LineCorrelation> = self.lines.iter().filter(|x| x.reference == r).collect();
            let n = l.len().max(1) as f64;
            let worst = l.iter().min_by(|a, b| a.csac.total_cmp(&b.csac));
            let _ = writeln!(
                s,
                "| {r} | {} | {:.4} | {} | {:.4} |",
                l.len(),
                l.iter().map(|x| x.csac).sum::<f64>() / n,
                worst.map_or("-".into(), |w| format!("{:.4} ({:.2})", w.csac, w.hz)),
                l.iter().map(|x| x.csf).sum::<f64>() / n
            );
        }
        if let Some(a) = &self.alignment {
            let _ = writeln!(
                s,
                "\nThe model's FRFs align best with the test's at {:.4} times the test's frequencies (mean FRAC {:.4}, unscaled {:.4}): its resonances are {:.1} % {}",
                a.factor,
                a.mean_frac,
                a.mean_frac_unscaled,
                100.0 * (a.factor - 1.0).abs(),
                if a.factor >= 1.0 { "high" } else { "low" }
            );
        }
        if let Some(u) = &self.update {
            let _ = write!(s, "{u}");
        }
        f.write_str(&s)
    }
}

impl FrfCorrelation {
    /// The model's FRF of measured function `k` over the lines.
    fn model_curve(&self, k: usize) -> Vec<c64> {
        let r = &self.functions[k];
        self.model
            .as_ref()
            .map(|m| m.h.iter().map(|h| h[(r.output, r.input)]).collect())
            .unwrap_or_default()
    }

    /// The measured FRF `k` over the lines (signed to the sensors' directions as compared).
    fn measured_curve(&self, k: usize) -> Vec<c64> {
        let f = &self.measured[k];
        let sign = (f.response.direction.signum() * f.reference.direction.signum()) as f64;
        match &f.ordinate {
            Ordinate::Complex(v) => v.iter().map(|(re, im)| c64::new(*re, *im) * sign).collect(),
            Ordinate::Real(v) => v.iter().map(|re| c64::new(re * sign, 0.0)).collect(),
        }
    }

    /// The model's FRFs as a universal file: each measured function's dataset 58 with the
    /// model's values (in the file's sense of its DOFs, the same abscissa, kinds and units; record
    /// 1 says "femu model").
    pub fn model_uff(&self) -> femu_io::uff::Universal {
        let functions = (0..self.measured.len())
            .map(|k| {
                let mut f = self.measured[k].clone();
                let sign = (f.response.direction.signum() * f.reference.direction.signum()) as f64;
                f.ordinate = Ordinate::Complex(
                    self.model_curve(k)
                        .iter()
                        .map(|v| (v.re * sign, v.im * sign))
                        .collect(),
                );
                f.double = true;
                f.ids[0] = format!("femu model {}", f.ids[0].trim());
                f
            })
            .collect();
        femu_io::uff::Universal {
            functions,
            ..Default::default()
        }
    }

    /// The model's FRFs as CSV: `hz,response,reference,re,im`, one row per line and function.
    pub fn model_csv(&self) -> String {
        let mut s = String::from("hz,response,reference,re,im\n");
        let curves: Vec<Vec<c64>> = (0..self.functions.len())
            .map(|k| self.model_curve(k))
            .collect();
        let lines = self.model.as_ref().map_or(&[][..], |m| &m.lines_hz[..]);
        for (l, hz) in lines.iter().enumerate() {
            for (r, c) in self.functions.iter().zip(&curves) {
                let _ = writeln!(
                    s,
                    "{hz},{},{},{:e},{:e}",
                    r.response, r.reference, c[l].re, c[l].im
                );
            }
        }
        s
    }

    /// Writes one chart per measured FRF into `dir` (`frf_K.svg` and `.png`: magnitude and phase,
    /// measured over model); the files written.
    ///
    /// # Errors
    /// A folder or file that cannot be written.
    pub fn write_charts(&self, dir: &Path) -> Result<Vec<std::path::PathBuf>, StudyError> {
        std::fs::create_dir_all(dir).map_err(|e| StudyError::file(dir, e))?;
        let lines = self.model.as_ref().map_or(&[][..], |m| &m.lines_hz[..]);
        let mut files = Vec::new();
        for (k, r) in self.functions.iter().enumerate() {
            let svg = crate::chart::frf_svg(
                &format!(
                    "FRF {} / {}: FRAC {:.4} ({:?})",
                    r.response, r.reference, r.frac, self.kind
                ),
                lines,
                &self.measured_curve(k),
                &self.model_curve(k),
            );
            let path = dir.join(format!("frf_{}.svg", k + 1));
            std::fs::write(&path, &svg).map_err(|e| StudyError::file(&path, e))?;
            files.push(path);
            let png = dir.join(format!("frf_{}.png", k + 1));
            crate::chart::write_png(&svg, 1.0, &png)?;
            files.push(png);
        }
        Ok(files)
    }
}
