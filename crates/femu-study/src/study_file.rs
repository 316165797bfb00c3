//! Study files (`femu run STUDY.toml`): correlation, estimation, expansion with the
//! sensor-removal study, and updating, described in one TOML file and run on one loaded model:
//! the model is read and assembled once and its modes are solved once for every step.
//!
//! ```toml
//! model = "plate.inp"            # or a .msh/.unv with [material] and fix (and [shells]:
//!                                # a .msh's surface groups with their thickness, [beams]: its
//!                                # line groups with their section, "rect:0.02,0.04")
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
//! select = "forward"             # the sets the data support (or "residual", "all")
//! method = "ies"                 # inverse eigensensitivity (or "sbebe", the paper's)
//! shapes = true                  # fit the shapes too (false: frequencies only)
//! frequency_uncertainty = 0.1    # percent, one standard deviation
//! shape_uncertainty = 1          # percent of each mode's largest reading
//! ```
//!
//! Paths in the file are relative to the file. Unknown keys are errors with their line.

use crate::StudyError;
use crate::estimate::{EstimateOptions, EstimateResult, estimate_loaded};
use crate::expand::{ExpansionReport, expanded_names};
use crate::load::{MaterialOptions, ModelOptions, TestOptions, load_model, load_test_with};
use crate::mapping::MapOptions;
use crate::removal::{removal_over_test, write_removal_study};
use crate::report::{create_dir, write_json, write_shapes_vtu, write_text};
use crate::updating::{UpdateRequest, UpdateStudy, update_loaded};
use femu_correlate::expansion::Method;
use femu_correlate::{ModeSet, PairingOptions};
use femu_sparse::eigen::EigenOptions;
use femu_sparse::slepc::{Engine, SlepcOptions};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
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
    /// `[shells]`: a Gmsh mesh's physical groups of surfaces made shells, by name, with their
    /// thickness (m).
    #[serde(default)]
    pub shells: std::collections::BTreeMap<String, f64>,
    /// `[beams]`: a Gmsh mesh's physical groups of lines made beams, by name, with their section
    /// (`"rect:A,B"`, `"circ:R"`, `"pipe:R,T"`, `@X,Y,Z` for `n1`).
    #[serde(default)]
    pub beams: std::collections::BTreeMap<String, String>,
    /// Lumped mass.
    #[serde(default)]
    pub lumped: bool,
    /// Unknown keywords of an `.inp` model are warnings instead of errors.
    #[serde(default)]
    pub lenient: bool,
    /// The 8-node bricks of a mesh-only model: `"full"` (the default) or `"incompatible_modes"`.
    #[serde(default)]
    pub bricks: femu_fem::element::Formulation,
    /// The node coordinates of a model given as another solver's matrices (relative to the study
    /// file): a deck's `*NODE` lines or a `node,x,y,z` table; by default the one beside them.
    #[serde(default)]
    pub nodes: Option<PathBuf>,
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
    pub update: Option<UpdateRequest>,
    /// `[frf]`: measured FRFs (`file`, a universal file with dataset 58) against the model's
    /// (`damping_ratio` or `loss_factor`, `modes_up_to`).
    #[serde(default)]
    pub frf: Option<crate::frf::FrfRequest>,
}

/// The eigensolver a study names (`[eigen] engine`, the `--engine` of the commands that solve).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum EngineName {
    /// femu's own shift-invert block Lanczos.
    #[default]
    Femu,
    /// SLEPc with MUMPS under MPI.
    Slepc,
}

/// `[eigen]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EigenSection {
    /// `femu` (default) or `slepc`.
    #[serde(default)]
    pub engine: EngineName,
    /// MPI ranks for SLEPc.
    #[serde(default = "default_ranks")]
    pub ranks: usize,
    /// An MPI hostfile for SLEPc (relative to the study file).
    #[serde(default)]
    pub hostfile: Option<PathBuf>,
}

impl EigenSection {
    /// The eigensolver settings the section asks for, a hostfile taken relative to `base` (the
    /// study file's folder).
    ///
    /// # Errors
    /// SLEPc with zero ranks.
    pub fn options(&self, base: &Path) -> Result<EigenOptions, StudyError> {
        engine_options(
            self.engine,
            self.ranks,
            self.hostfile.as_ref().map(|h| base.join(h)),
        )
    }
}

/// The eigensolver settings of an engine: femu's own, or SLEPc on `ranks` MPI ranks (with a
/// hostfile for a cluster); the other settings their defaults.
///
/// # Errors
/// SLEPc with zero ranks; ranks other than 1 or a hostfile for femu's engine, which would ignore
/// them.
pub fn engine_options(
    engine: EngineName,
    ranks: usize,
    hostfile: Option<PathBuf>,
) -> Result<EigenOptions, StudyError> {
    let engine = match engine {
        EngineName::Femu => {
            if ranks != 1 || hostfile.is_some() {
                return Err(StudyError::invalid(
                    "engine",
                    "ranks and a hostfile apply to the slepc engine (MPI), not to femu's",
                ));
            }
            Engine::Femu
        }
        EngineName::Slepc => {
            if ranks == 0 {
                return Err(StudyError::invalid(
                    "engine",
                    "SLEPc needs at least one MPI rank",
                ));
            }
            Engine::Slepc(SlepcOptions {
                ranks,
                hostfile,
                ..Default::default()
            })
        }
    };
    Ok(EigenOptions {
        engine,
        ..Default::default()
    })
}

fn default_ranks() -> usize {
    1
}

/// `[pairing]`, and the pairing arguments of `femu correlate` and `femu estimate` (with the
/// `clap` feature): one definition, one default.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[serde(deny_unknown_fields)]
pub struct PairingSection {
    /// Smallest MAC accepted for a pair.
    #[cfg_attr(feature = "clap", arg(long, default_value_t = 0.8))]
    #[serde(default = "default_mac_threshold")]
    pub mac_threshold: f64,
    /// Largest frequency error of a pair, percent (default: no limit).
    #[cfg_attr(feature = "clap", arg(long, value_name = "PERCENT"))]
    #[serde(default)]
    pub max_frequency_error: Option<f64>,
    /// Compare the complex test shapes with the model's damped (complex) modes of its
    /// structural and viscous damping: the complex MAC with both sides complex (docs/MATH.md, "Damped
    /// modes").
    #[cfg_attr(feature = "clap", arg(long))]
    #[serde(default)]
    pub damped: bool,
}

impl Default for PairingSection {
    fn default() -> Self {
        Self {
            mac_threshold: default_mac_threshold(),
            max_frequency_error: None,
            damped: false,
        }
    }
}

impl PairingSection {
    /// The pairing settings (the frequency error as a fraction).
    pub fn options(&self) -> PairingOptions {
        PairingOptions {
            mac_threshold: self.mac_threshold,
            max_frequency_error: self.max_frequency_error.map(|p| p / 100.0),
            damped: self.damped,
        }
    }
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

impl StudyFile {
    /// How the study's test is placed on the model: its `[map]` and `test_units`.
    ///
    /// # Errors
    /// A length unit femu does not know.
    fn test_options(&self) -> Result<TestOptions, StudyError> {
        Ok(TestOptions {
            map: self.map.clone(),
            test_units: self
                .test_units
                .as_deref()
                .map(crate::load::length_unit)
                .transpose()?,
        })
    }
}

/// What a study file produced.
#[derive(Debug, Clone, Serialize)]
pub struct StudyRun {
    /// The correlation (`correlation.json`).
    pub correlation: femu_correlate::CorrelationReport,
    /// The estimators (`estimate.json`); none for a model that is another solver's modes, which
    /// has no `K` and `M` to estimate with.
    pub estimate: Option<EstimateResult>,
    /// Expansion (`expansion.json`, `expanded.vtu`, `figure1/`).
    pub expansion: Option<ExpansionReport>,
    /// Updating (`update.json`).
    pub update: Option<UpdateStudy>,
    /// Measured FRFs against the model's (`frf.json`).
    pub frf: Option<crate::frf::FrfCorrelation>,
    /// The model's modes, solved once and used by every step.
    #[serde(skip)]
    pub modes: ModeSet,
    /// What the readers noticed.
    pub warnings: Vec<String>,
    /// Files written.
    pub files: Vec<PathBuf>,
    /// Global assemblies of the model's `K` and `M` during the study ([`Assembler::assemblies`]
    /// of the loaded model's assembler and its clones): 1, the study's promise.
    ///
    /// [`Assembler::assemblies`]: femu_fem::assembly::Assembler::assemblies
    pub model_assemblies: usize,
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
        shells: s.shells.iter().map(|(g, t)| (g.clone(), *t)).collect(),
        beams: s
            .beams
            .iter()
            .map(|(g, b)| (g.clone(), b.clone()))
            .collect(),
        lumped: s.lumped,
        lenient: s.lenient,
        bricks: s.bricks,
        nodes: s.nodes.as_ref().map(|n| base.join(n)),
    };
    progress("reading and assembling the model");
    // a file the study names that cannot be read: say which study file names it
    let named = |e: StudyError| match e {
        StudyError::Io(femu_io::IoError::Io { .. }) => StudyError::within(path, e),
        e => e,
    };
    let eigen = match &s.eigen {
        Some(e) => e.options(base).map_err(|e| StudyError::within(path, e))?,
        None => EigenOptions::default(),
    };
    if femu_io::Format::from_path(&base.join(&s.model)) == Some(femu_io::Format::Results) {
        return correlate_results(&s, path, base, out, &options, &mut progress);
    }
    let model = load_model(&base.join(&s.model), &options).map_err(named)?;
    let test = load_test_with(&base.join(&s.test), &model, &s.test_options()?).map_err(named)?;
    create_dir(out)?;
    let mut files = Vec::new();
    if let Some(m) = &test.mapping {
        write_mapping(out, m, &mut files)?;
    }
    let n_test = test.data.modes.len();
    let options = EstimateOptions {
        expansion: s.expansion.map_or(Method::Dynamic, |e| e.method),
        pairing: s.pairing.unwrap_or_default().options(),
        // one solve serves correlation (2 n + 4 modes), estimation and the truth check (n + 10)
        count: Some((2 * n_test + 4).max(n_test + 10)),
        eigen: eigen.clone(),
    };
    let run = estimate_loaded(&model, &test, &options, &mut progress)?;
    let (modes, x, estimate) = (run.modes, run.expanded, run.result);
    let modes_t = &test.data.modes;
    let method = options.expansion;
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
                &model.model,
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
            let st = update_loaded(&model, &test, u, &eigen, Some(&modes), |it| {
                progress(&format!(
                    "iteration {}: objective {:.4e}",
                    it.iteration, it.objective
                ))
            })?;
            let p = out.join("update.json");
            write_json(&p, &st)?;
            files.push(p);
            Some(st)
        }
        None => None,
    };
    let frf = match &s.frf {
        Some(r) => {
            progress("measured FRFs against the model's");
            let file = r.file.as_ref().ok_or_else(|| {
                StudyError::within(
                    path,
                    StudyError::invalid(
                        "[frf]",
                        "file = \"...\" names the universal file of measured FRFs",
                    ),
                )
            })?;
            let c = {
                let r = crate::frf::FrfRequest {
                    damping_from: r.damping_from.as_ref().map(|t| base.join(t)),
                    ..r.clone()
                };
                crate::frf::frf_correlation_with(
                    &model,
                    &base.join(file),
                    &r,
                    &eigen,
                    &mut progress,
                )
                .map_err(named)?
            };
            let p = out.join("frf.json");
            write_json(&p, &c)?;
            files.push(p);
            write_text(&out.join("frf_model.csv"), &c.model_csv(), &mut files)?;
            let p = out.join("frf_model.uff");
            femu_io::uff::write_uff(&p, &c.model_uff())?;
            files.push(p);
            files.extend(c.write_charts(&out.join("frf"))?);
            Some(c)
        }
        None => None,
    };
    let mut run = StudyRun {
        correlation: estimate.correlation.clone(),
        estimate: Some(estimate),
        expansion,
        update,
        frf,
        modes,
        model_assemblies: model.asm.assemblies(),
        warnings: model.warnings,
        files,
    };
    let p = out.join("report.md");
    let text = run.report();
    write_text(&p, &text, &mut run.files)?;
    Ok(run)
}

impl StudyRun {
    /// Every step's result in one text (Markdown): the modal correlation, the estimators, the
    /// expansion, the updating and the measured FRFs against the model's, as `femu run` prints
    /// them and writes them to `report.md`.
    pub fn report(&self) -> String {
        let mut s = format!("# correlation\n\n{}", self.correlation);
        if let Some(estimate) = &self.estimate {
            let _ = write!(
                s,
                "\n# estimators ({} expansion)\n\n{}\n{}\n",
                estimate.expansion,
                estimate.table2(),
                crate::estimate::table2_legend()
            );
        }
        if let Some(e) = &self.expansion {
            let _ = writeln!(
                s,
                "\n# expansion ({})\n\nrho_M (s^-2) per test mode: {:?}",
                e.method,
                e.norms
                    .iter()
                    .map(|n| format!("{:.4e}", n.rho_m))
                    .collect::<Vec<_>>()
            );
            if let Some(st) = &e.study {
                let _ = writeln!(s, "sensor-removal study: {} points", st.points.len());
            }
        }
        if let Some(u) = &self.update {
            let _ = writeln!(s, "\n# updating\n\n{u}");
        }
        if let Some(f) = &self.frf {
            let _ = writeln!(s, "\n# frequency responses\n\n{f}");
        }
        s
    }
}

/// The mapping table of a test on its own wireframe (`mapping.txt`, `mapping.json`).
fn write_mapping(
    out: &Path,
    m: &crate::mapping::Mapping,
    files: &mut Vec<PathBuf>,
) -> Result<(), StudyError> {
    write_text(&out.join("mapping.txt"), &m.to_string(), files)?;
    let p = out.join("mapping.json");
    write_json(&p, m)?;
    files.push(p);
    Ok(())
}

/// [`run_study_file`] for a model that is another solver's modes
/// ([`crate::external::load_result_modes`]): the test mapped onto its nodes and correlated
/// (`correlation.json`); a step that needs `K` and `M` is refused, not skipped.
fn correlate_results(
    s: &StudyFile,
    path: &Path,
    base: &Path,
    out: &Path,
    options: &ModelOptions,
    progress: &mut impl FnMut(&str),
) -> Result<StudyRun, StudyError> {
    let needs: Vec<&str> = [
        ("[expansion]", s.expansion.is_some()),
        ("[update]", s.update.is_some()),
        ("[frf]", s.frf.is_some()),
    ]
    .iter()
    .filter(|(_, given)| *given)
    .map(|(name, _)| *name)
    .collect();
    if !needs.is_empty() {
        return Err(StudyError::in_file(
            path,
            "study",
            format!(
                "the model is another solver's modes: a study of it correlates them with the test; {} need K and M (give the solver's matrices instead: CalculiX's job.sti, or MatrixMarket with a DOF table)",
                needs.join(", ")
            ),
        ));
    }
    progress("reading the modes");
    let results =
        crate::external::load_result_modes(&base.join(&s.model), options.nodes.as_deref())?;
    let test = crate::load::load_test_on(
        &base.join(&s.test),
        results.model.mesh(),
        &results.dofs,
        &s.test_options()?,
    )?;
    progress("correlating");
    let pairing = s.pairing.unwrap_or_default().options();
    let correlation =
        femu_correlate::correlate(&results.modes, &test.data.modes, &test.layout, &pairing)?;
    create_dir(out)?;
    let mut files = Vec::new();
    if let Some(m) = &test.mapping {
        write_mapping(out, m, &mut files)?;
    }
    let p = out.join("correlation.json");
    write_json(&p, &correlation)?;
    files.push(p);
    let mut warnings = results.warnings;
    warnings.extend(test.warnings);
    Ok(StudyRun {
        correlation,
        estimate: None,
        expansion: None,
        update: None,
        frf: None,
        modes: results.modes,
        model_assemblies: 0,
        warnings,
        files,
    })
}

#[cfg(test)]
mod tests {
    use super::StudyFile;
    use femu_fem::element::Formulation;

    /// `bricks` reads the two formulations by their snake-case names, defaults to the fully
    /// integrated brick, and refuses anything else by naming both.
    #[test]
    fn bricks_key() {
        let parse = |extra: &str| {
            toml::from_str::<StudyFile>(&format!("model = \"m.msh\"\ntest = \"t.csv\"\n{extra}"))
        };
        assert_eq!(parse("").unwrap().bricks, Formulation::Full);
        assert_eq!(
            parse("bricks = \"incompatible_modes\"").unwrap().bricks,
            Formulation::IncompatibleModes
        );
        let e = parse("bricks = \"C3D8I\"").unwrap_err().to_string();
        assert!(
            e.contains("full") && e.contains("incompatible_modes"),
            "{e}"
        );
    }
}
