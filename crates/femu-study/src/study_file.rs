//! Study files (`femu run STUDY.toml`): correlation, estimation, expansion with the
//! sensor-removal study, and updating, described in one TOML file and run on one loaded model:
//! the model is read and assembled once and its modes are solved once for every step.
//!
//! ```toml
//! model = "plate.inp"            # or a .msh/.unv with [material] and fix
//! test = "test.unv"              # .unv, .csv or .json
//! lenient = false               # true: unknown .inp keywords are warnings
//! [pairing]
//! mac_threshold = 0.8
//! max_frequency_error = 10       # percent (optional frequency window)
//! [expansion]
//! method = "dynamic"             # static, dynamic, serep:M, min-residual, mdre
//! study = true                   # the sensor-removal study (Figure 1)
//! [update]
//! sets = ["r0", "r1", "r2", "r3"]
//! tuned = 4
//! method = "sbebe"               # or "ies"
//! shapes = true                  # ies: fit the shapes too
//! frequency_uncertainty = 0.1    # percent, one standard deviation
//! shape_uncertainty = 1          # percent of each mode's largest reading
//! ```
//!
//! Paths in the file are relative to the file. Unknown keys are errors with their line.

use crate::StudyError;
use crate::estimate::{EstimateOptions, EstimateResult, estimate_with_bounds};
use crate::expand::{ExpansionReport, expand_shapes, expanded_names};
use crate::load::{MaterialOptions, ModelOptions, TestOptions, load_model, load_test_with};
use crate::mapping::MapOptions;
use crate::modes::lowest_for_test;
use crate::removal::{removal_over_test, write_removal_study};
use crate::report::{create_dir, write_json, write_shapes_vtu, write_text};
use crate::updating::{UpdateStudy, UpdateStudyOptions, localise_update_check, resolve_sets};
use femu_correlate::expansion::Method;
use femu_correlate::{ModeSet, PairingOptions};
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
    /// Unknown keywords of an `.inp` model are warnings instead of errors.
    #[serde(default)]
    pub lenient: bool,
    /// `[map]`: a test on its own wireframe, aligned and mapped onto the model
    /// (`method = "nearest" | "interpolate"`, `tolerance` in m, `align = "auto" | "T:M,T:M,T:M"`,
    /// `scale`).
    #[serde(default)]
    pub map: Option<MapOptions>,
    /// The unit of the test's coordinates where the file does not say: m, cm, mm, in or ft.
    #[serde(default)]
    pub test_units: Option<String>,
    /// `[eigen]`: the eigensolver of every solve of the study (`engine = "femu" | "slepc"`,
    /// `ranks`, `hostfile`).
    #[serde(default)]
    pub eigen: Option<EigenSection>,
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

/// `[eigen]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EigenSection {
    /// `femu` (default) or `slepc`.
    #[serde(default = "default_engine_name")]
    pub engine: String,
    /// MPI ranks for SLEPc.
    #[serde(default = "default_ranks")]
    pub ranks: usize,
    /// An MPI hostfile for SLEPc (relative to the study file).
    #[serde(default)]
    pub hostfile: Option<PathBuf>,
}

fn default_engine_name() -> String {
    "femu".into()
}

fn default_ranks() -> usize {
    1
}

/// `[pairing]`.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PairingSection {
    /// Smallest MAC accepted for a pair.
    #[serde(default = "default_mac_threshold")]
    pub mac_threshold: f64,
    /// Largest frequency error of a pair, percent.
    #[serde(default)]
    pub max_frequency_error: Option<f64>,
}

fn default_mac_threshold() -> f64 {
    0.8
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
    /// The test's frequency uncertainty, percent (default 0.1, assumed and said so).
    #[serde(default)]
    pub frequency_uncertainty: Option<f64>,
    /// The test's shape uncertainty, percent of each mode's largest reading (default 1).
    #[serde(default)]
    pub shape_uncertainty: Option<f64>,
    /// Inverse eigensensitivity fits the shapes too.
    #[serde(default)]
    pub shapes: bool,
    /// SB-EBE's test-error weight (default 1e-3).
    #[serde(default)]
    pub test_error: Option<f64>,
    /// Estimate the model's discretisation error (default true).
    #[serde(default = "default_true")]
    pub discretisation: bool,
}

fn default_true() -> bool {
    true
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

/// What a study file produced.
#[derive(Debug, Clone, Serialize)]
pub struct StudyRun {
    /// The correlation (`estimate.correlation`, also written as `correlation.json`) and the
    /// estimators (`estimate.json`).
    pub estimate: EstimateResult,
    /// Expansion (`expansion.json`, `expanded.vtu`, `figure1/`).
    pub expansion: Option<ExpansionReport>,
    /// Updating (`update.json`).
    pub update: Option<UpdateStudy>,
    /// The model's modes, solved once and used by every step.
    #[serde(skip)]
    pub modes: ModeSet,
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
        lenient: s.lenient,
    };
    progress("reading and assembling the model");
    // a file the study names that cannot be read: say which study file names it
    let named = |e: StudyError| match e {
        StudyError::Io(femu_io::IoError::Io { .. }) => StudyError::within(path, e),
        e => e,
    };
    if let Some(e) = &s.eigen {
        use femu_sparse::slepc::{Engine, SlepcOptions, set_default_engine};
        match e.engine.as_str() {
            "femu" => set_default_engine(Engine::Femu),
            "slepc" if e.ranks > 0 => set_default_engine(Engine::Slepc(SlepcOptions {
                ranks: e.ranks,
                hostfile: e.hostfile.as_ref().map(|h| base.join(h)),
                ..Default::default()
            })),
            other => {
                return Err(StudyError::within(
                    path,
                    StudyError::invalid(
                        "[eigen]",
                        format!(
                            "engine {other:?} with {} ranks: expected femu, or slepc with at least one rank",
                            e.ranks
                        ),
                    ),
                ));
            }
        }
    }
    let model = load_model(&base.join(&s.model), &options).map_err(named)?;
    let test = load_test_with(
        &base.join(&s.test),
        &model,
        &TestOptions {
            map: s.map.clone(),
            test_units: s
                .test_units
                .as_deref()
                .map(crate::load::length_unit)
                .transpose()?,
        },
    )
    .map_err(named)?;
    create_dir(out)?;
    let mut files = Vec::new();
    if let Some(m) = &test.mapping {
        write_text(&out.join("mapping.txt"), &m.to_string(), &mut files)?;
        let p = out.join("mapping.json");
        write_json(&p, m)?;
        files.push(p);
    }
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
        max_frequency_error: s
            .pairing
            .and_then(|p| p.max_frequency_error)
            .map(|p| p / 100.0),
    };
    let method = s.expansion.map_or(Method::Dynamic, |e| e.method);
    progress(&format!("expanding the test shapes ({method})"));
    let modes_t = &test.data.modes;
    let x = expand_shapes(
        &model.sys,
        &test.layout,
        &modes_t.eigenvalues(),
        modes_t.shapes.as_ref(),
        method,
        None,
    )?;
    let estimate = estimate_with_bounds(
        &model.model,
        &model.sys,
        &test.layout,
        modes_t,
        &modes,
        x.as_ref(),
        &EstimateOptions {
            expansion: method,
            pairing,
        },
    )?;
    for (name, value) in [
        (
            "correlation.json",
            serde_json::to_value(&estimate.correlation)?,
        ),
        ("estimate.json", serde_json::to_value(&estimate)?),
    ] {
        let p = out.join(name);
        write_json(&p, &value)?;
        files.push(p);
    }
    let expansion = match s.expansion {
        Some(e) => {
            let vtu = out.join("expanded.vtu");
            write_shapes_vtu(
                &vtu,
                model.model.mesh(),
                &model.sys.dofs,
                x.as_ref(),
                &expanded_names(modes_t),
                &[],
            )?;
            files.push(vtu);
            let study = if e.study {
                progress("sensor-removal study");
                let st = removal_over_test(&model, &test, x.as_ref())?;
                let dir = out.join("figure1");
                create_dir(&dir)?;
                files.extend(write_removal_study(&dir, "study", &st.points)?);
                Some(st)
            } else {
                None
            };
            // the estimate's residual norms are those of the expanded shapes
            let expansion = ExpansionReport {
                method,
                norms: estimate.assessments.iter().map(|a| a.norms).collect(),
                study,
            };
            let p = out.join("expansion.json");
            write_json(&p, &expansion)?;
            files.push(p);
            Some(expansion)
        }
        None => None,
    };
    let update = match &s.update {
        Some(u) => {
            progress("localising and updating");
            let names = resolve_sets(&model, &u.sets)?;
            let tuned = u.tuned.unwrap_or((2 * n_test).div_ceil(3)).min(n_test);
            let defaults = UpdateStudyOptions::new(tuned, n_test);
            let opts = UpdateStudyOptions {
                method: u.method,
                all: u.all,
                shapes: u.shapes,
                uncertainty: femu_update::TestUncertainty::from_percent(
                    u.frequency_uncertainty,
                    u.shape_uncertainty,
                )?,
                test_error: u.test_error.or(defaults.test_error),
                discretisation: u.discretisation,
                ..defaults
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
        estimate,
        expansion,
        update,
        modes,
        warnings: model.warnings,
        files,
    })
}
