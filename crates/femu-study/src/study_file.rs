//! Study files (`femu run STUDY.toml`): correlation, estimation, expansion with the
//! sensor-removal study, and updating, described in one TOML file and run on one loaded model:
//! the model is read and assembled once and its modes are solved once for every step.
//!
//! ```toml
//! model = "plate.inp"            # or a .msh/.unv with [material] and fix
//! test = "test.unv"              # .unv, .csv or .json
//! [pairing]
//! mac_threshold = 0.8
//! [expansion]
//! method = "dynamic"             # static, dynamic, serep:M, min-residual, mdre
//! study = true                   # the sensor-removal study (Figure 1)
//! [update]
//! sets = ["r0", "r1", "r2", "r3"]
//! tuned = 4
//! method = "sbebe"               # or "ies"
//! ```
//!
//! Paths in the file are relative to the file. Unknown keys are errors with their line.

use crate::StudyError;
use crate::estimate::{EstimateOptions, EstimateResult, estimate_with_bounds, expand_shapes};
use crate::load::{LoadedModel, LoadedTest, MaterialOptions, ModelOptions, load_model, load_test};
use crate::modes::lowest_for_test;
use crate::removal::{
    RemovalOptions, RemovalStudy, removal_study, sensor_nodes, write_removal_study,
};
use crate::report::{create_dir, full_fields, write_json};
use crate::updating::{UpdateStudy, UpdateStudyOptions, localise_update_check};
use femu_correlate::ResidualNorms;
use femu_correlate::expansion::Method;
use femu_correlate::{CorrelationReport, Estimator, ModeSet, PairingOptions};
use femu_update::UpdateMethod;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// A study file.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudyFile {
    /// The model file (relative to the study file).
    pub model: PathBuf,
    /// The test file (relative to the study file).
    pub test: PathBuf,
    /// The material of a mesh-only model.
    #[serde(default)]
    pub material: Option<MaterialOptions>,
    /// Node sets to clamp in a mesh-only model.
    #[serde(default)]
    pub fix: Vec<String>,
    /// Lumped mass.
    #[serde(default)]
    pub lumped: bool,
    /// Pairing settings.
    #[serde(default)]
    pub pairing: Option<PairingSection>,
    /// Expansion (and the sensor-removal study).
    #[serde(default)]
    pub expansion: Option<ExpansionSection>,
    /// Updating.
    #[serde(default)]
    pub update: Option<UpdateSection>,
}

/// `[pairing]`.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PairingSection {
    /// Smallest MAC accepted for a pair.
    pub mac_threshold: f64,
}

/// `[expansion]`.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExpansionSection {
    /// The expansion method.
    pub method: Method,
    /// Run the sensor-removal study.
    #[serde(default)]
    pub study: bool,
}

/// `[update]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UpdateSection {
    /// Candidate element sets.
    pub sets: Vec<String>,
    /// Tuned test modes (default: all but the last third).
    #[serde(default)]
    pub tuned: Option<usize>,
    /// `sbebe` (default) or `ies`.
    #[serde(default = "default_update_method")]
    pub method: UpdateMethod,
    /// Update every candidate set instead of the localised ones.
    #[serde(default)]
    pub all: bool,
}

fn default_update_method() -> UpdateMethod {
    UpdateMethod::SbEbe
}

impl StudyFile {
    /// Reads and checks a study file.
    ///
    /// # Errors
    /// [`StudyError::File`] when it cannot be read, [`StudyError::StudyFile`] with the line of a
    /// syntax error, an unknown or missing key, or a value of the wrong kind.
    pub fn read(path: &Path) -> Result<Self, StudyError> {
        let text = std::fs::read_to_string(path).map_err(|e| StudyError::file(path, e))?;
        toml::from_str(&text).map_err(|e| StudyError::StudyFile {
            path: path.to_path_buf(),
            line: e
                .span()
                .map_or(1, |sp| text[..sp.start].matches('\n').count() + 1),
            reason: e.message().to_string(),
        })
    }
}

/// `rho_M` and `rho_2` of expanded test shapes, and the removal study when asked for.
#[derive(Debug, Clone, Serialize)]
pub struct ExpansionReport {
    /// The method.
    pub method: Method,
    /// Per test mode: `rho_M`, `rho_2`, the Rayleigh quotient (`docs/MATH.md`, (25)).
    pub norms: Vec<ResidualNorms>,
    /// The sensor-removal study.
    pub study: Option<RemovalStudy>,
}

/// Expands the test shapes by `method` and evaluates the residual norms; with `study`, runs the
/// sensor-removal study over the test's nodes (EfI order on the expanded shapes, down to 2 nodes).
/// Returns the expanded shapes with the report.
///
/// # Errors
/// As [`expand_shapes`] and [`removal_study`].
pub fn expansion_report(
    model: &LoadedModel,
    test: &LoadedTest,
    method: Method,
    study: bool,
) -> Result<(faer::Mat<f64>, ExpansionReport), StudyError> {
    let sys = &model.sys;
    let lambdas = test.data.modes.eigenvalues();
    let x = expand_shapes(
        sys,
        &test.layout,
        &lambdas,
        test.data.modes.shapes.as_ref(),
        method,
        None,
    )?;
    let (norms, _) = Estimator::new(&sys.k, &sys.m)?.residual_norms(&lambdas, x.as_ref())?;
    let study = if study {
        let nodes = sensor_nodes(&test.layout);
        Some(removal_study(
            sys,
            model.model.mesh(),
            &nodes,
            x.as_ref(),
            &lambdas,
            x.as_ref(),
            &RemovalOptions::default(),
        )?)
    } else {
        None
    };
    Ok((
        x,
        ExpansionReport {
            method,
            norms,
            study,
        },
    ))
}

/// What a study file produced.
#[derive(Debug, Clone, Serialize)]
pub struct StudyRun {
    /// Pairs, MAC, frequency errors (`correlation.json`).
    pub correlation: CorrelationReport,
    /// The estimators (`estimate.json`).
    pub estimate: EstimateResult,
    /// Expansion (`expansion.json`, `expanded.vtu`, `figure1/`).
    pub expansion: Option<ExpansionReport>,
    /// Updating (`update.json`).
    pub update: Option<UpdateStudy>,
    /// The model's modes used by every step (count and Sturm evidence in `modes.json`).
    #[serde(skip)]
    pub modes: Option<ModeSet>,
    /// What the readers noticed.
    pub warnings: Vec<String>,
    /// Files written.
    pub files: Vec<PathBuf>,
}

/// Runs the study file `path`, writing every result into `out`. `progress` receives one line per
/// step.
///
/// # Errors
/// The study file's errors (with their line), and those of each step.
pub fn run_study_file(
    path: &Path,
    out: &Path,
    mut progress: impl FnMut(&str),
) -> Result<StudyRun, StudyError> {
    let s = StudyFile::read(path)?;
    let base = path.parent().unwrap_or(Path::new("."));
    let options = ModelOptions {
        material: s.material,
        fix: s.fix.clone(),
        lumped: s.lumped,
    };
    progress("reading and assembling the model");
    let model = load_model(&base.join(&s.model), &options)?;
    let test = load_test(&base.join(&s.test), &model)?;
    create_dir(out)?;
    let mut files = Vec::new();
    let n_test = test.data.modes.len();
    // one solve serves correlation (2 n + 4 modes), estimation and the truth check (n + 10)
    let count = (2 * n_test + 4).max(n_test + 10);
    progress(&format!(
        "solving {count} modes ({} DOF)",
        model.sys.k.rows()
    ));
    let modes = ModeSet::from_modes(&lowest_for_test(&model, Some(count), n_test)?);
    let pairing = PairingOptions {
        mac_threshold: s.pairing.map_or(0.8, |p| p.mac_threshold),
    };
    let method = s.expansion.map_or(Method::Dynamic, |e| e.method);
    progress(&format!("expanding the test shapes ({method})"));
    let (x, expansion) =
        expansion_report(&model, &test, method, s.expansion.is_some_and(|e| e.study))?;
    let estimate = estimate_with_bounds(
        &model.model,
        &model.sys,
        model.mass,
        &test.layout,
        &test.data.modes,
        &modes,
        x.as_ref(),
        &EstimateOptions {
            expansion: method,
            pairing,
        },
    )?;
    let correlation = estimate.correlation.clone();
    for (name, value) in [
        ("correlation.json", serde_json::to_value(&correlation)?),
        ("estimate.json", serde_json::to_value(&estimate)?),
    ] {
        let p = out.join(name);
        write_json(&p, &value)?;
        files.push(p);
    }
    let expansion = if s.expansion.is_some() {
        let fields = full_fields(&model.sys.dofs, model.model.mesh().node_count(), x.as_ref());
        let names: Vec<String> = (0..x.ncols())
            .map(|j| {
                format!(
                    "test mode {} expanded ({:.2} Hz)",
                    j + 1,
                    test.data.modes.frequencies_hz[j]
                )
            })
            .collect();
        let points: Vec<femu_io::vtk::PointField<'_>> = fields
            .iter()
            .zip(&names)
            .map(|(v, name)| femu_io::vtk::PointField {
                name,
                components: 3,
                values: v,
            })
            .collect();
        let vtu = out.join("expanded.vtu");
        femu_io::vtk::write_vtu(model.model.mesh(), &points, &[], &vtu)?;
        files.push(vtu);
        if let Some(st) = &expansion.study {
            let dir = out.join("figure1");
            create_dir(&dir)?;
            files.extend(write_removal_study(&dir, "study", &st.points)?);
        }
        let p = out.join("expansion.json");
        write_json(&p, &expansion)?;
        files.push(p);
        Some(expansion)
    } else {
        None
    };
    let update = match &s.update {
        Some(u) => {
            progress("localising and updating");
            let names = resolve_sets(&model, &u.sets)?;
            let tuned = u.tuned.unwrap_or((2 * n_test).div_ceil(3)).min(n_test);
            let opts = UpdateStudyOptions {
                method: u.method,
                all: u.all,
                ..UpdateStudyOptions::new(tuned, n_test)
            };
            let nominal = (!s.lumped).then_some((&model.asm, &model.sys));
            let names: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
            let before = (!s.lumped).then_some(&modes);
            let st = localise_update_check(
                &model.model,
                &names,
                &test.layout,
                &test.data.modes,
                before,
                nominal,
                &opts,
                |it| {
                    progress(&format!(
                        "iteration {}: objective {:.4e}",
                        it.iteration, it.objective
                    ))
                },
            )?;
            let p = out.join("update.json");
            write_json(&p, &st)?;
            files.push(p);
            Some(st)
        }
        None => None,
    };
    Ok(StudyRun {
        correlation,
        estimate,
        expansion,
        update,
        modes: Some(modes),
        warnings: model.warnings,
        files,
    })
}

/// The model's element sets named by `sets` (Abaqus names are case-insensitive; the reader keeps
/// them upper case).
///
/// # Errors
/// A set the model does not have, naming the model file and the sets it has.
pub fn resolve_sets(model: &LoadedModel, sets: &[String]) -> Result<Vec<String>, StudyError> {
    let known = model.model.mesh().element_sets();
    sets.iter()
        .map(|s| {
            known
                .keys()
                .find(|k| k.eq_ignore_ascii_case(s))
                .cloned()
                .ok_or_else(|| {
                    StudyError::in_file(
                        &model.path,
                        "element sets",
                        format!(
                            "no element set {s} (the model has: {})",
                            known.keys().cloned().collect::<Vec<_>>().join(", ")
                        ),
                    )
                })
        })
        .collect()
}
