//! The updating workflow of the paper: localise the error among candidate element sets from the
//! expanded residues, update the selected sets' stiffness (SB-EBE, or inverse eigensensitivity),
//! and check the updated model on held-out test modes it was not tuned on (the truth check).

use crate::StudyError;
use crate::discretisation::{DiscretisationEstimate, estimate as estimate_discretisation};
use crate::load::{LoadedModel, LoadedTest};
use crate::reach::{Reach, reach};
use femu_correlate::{ModeSet, SensorLayout, TestModes};
use femu_fem::assembly::{Assembler, MassKind, SystemMatrices};
use femu_fem::groups::ParameterGroups;
use femu_fem::model::Model;
use femu_sparse::eigen::EigenOptions;
use femu_update::{
    Corrections, Iteration, JudgeInputs, Localisation, ParameterFinding, SbebeOptions,
    SelectionRule, SensitivityOptions, TestUncertainty, TruthCheck, UpdateMethod, UpdateModel,
    UpdateResult, inverse_eigensensitivity, localise_expanded, model_modes, sb_ebe, truth_check,
};
use serde::{Deserialize, Serialize};

/// What a user asks of the updating workflow ([`update_loaded`]): the one definition behind
/// `femu update`'s arguments (with the `clap` feature), a study file's `[update]` section and the
/// Python binding's `update`, with the one set of defaults ([`UpdateRequest::options`]).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[serde(deny_unknown_fields)]
pub struct UpdateRequest {
    /// Candidate element sets (comma-separated); localisation selects among them.
    #[cfg_attr(feature = "clap", arg(long, value_delimiter = ',', required = true))]
    pub sets: Vec<String>,
    /// The first N test modes are tuned, the others held out (default: all but the last third).
    #[cfg_attr(feature = "clap", arg(long))]
    #[serde(default)]
    pub tuned: Option<usize>,
    /// The updating method.
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value = "sbebe"))]
    #[serde(default = "default_update_method")]
    pub method: UpdateMethod,
    /// Update every candidate set instead of the localised ones.
    #[cfg_attr(feature = "clap", arg(long))]
    #[serde(default)]
    pub all: bool,
    /// The test's frequency uncertainty, percent (one standard deviation; default: 0.1 %,
    /// assumed and said so). The truth check's tolerance is three of it.
    #[cfg_attr(feature = "clap", arg(long, value_name = "PERCENT"))]
    #[serde(default)]
    pub frequency_uncertainty: Option<f64>,
    /// The test's shape uncertainty, percent of each mode's largest reading (default: 1 %).
    #[cfg_attr(feature = "clap", arg(long, value_name = "PERCENT"))]
    #[serde(default)]
    pub shape_uncertainty: Option<f64>,
    /// Inverse eigensensitivity fits the shapes at the sensors as well as the frequencies
    /// (eigenvector derivatives); recommended when the model is not the structure.
    #[cfg_attr(feature = "clap", arg(long))]
    #[serde(default)]
    pub shapes: bool,
    /// SB-EBE's trust in the measured shapes: the weight of the test-error term of the expansion
    /// (default 1e-3; smaller trusts the test more).
    #[cfg_attr(feature = "clap", arg(long, value_name = "WEIGHT"))]
    #[serde(default)]
    pub test_error: Option<f64>,
    /// Estimate the model's discretisation error (the same mesh with quadratic elements, solved
    /// once) and weigh the verdict with it (default true; `--no-discretisation` skips it).
    #[cfg_attr(
        feature = "clap",
        arg(
            long = "no-discretisation",
            action = clap::ArgAction::SetFalse,
            help = "Skip the estimate of the model's discretisation error (the same mesh with quadratic elements, solved once)"
        )
    )]
    #[serde(default = "default_true")]
    pub discretisation: bool,
}

fn default_true() -> bool {
    true
}

fn default_update_method() -> UpdateMethod {
    UpdateMethod::SbEbe
}

impl UpdateRequest {
    /// The request with every default, for the candidate sets `sets`.
    pub fn new(sets: Vec<String>) -> Self {
        Self {
            sets,
            tuned: None,
            method: UpdateMethod::SbEbe,
            all: false,
            frequency_uncertainty: None,
            shape_uncertainty: None,
            shapes: false,
            test_error: None,
            discretisation: true,
        }
    }

    /// The tuned modes out of `test_modes`: the request's, at most `test_modes`, or by default
    /// all but the last third (`ceil(2 n / 3)`), so that a third of the test is held out for the
    /// truth check.
    pub fn tuned_of(&self, test_modes: usize) -> usize {
        self.tuned
            .unwrap_or((2 * test_modes).div_ceil(3))
            .min(test_modes)
    }

    /// The workflow's settings for a test of `test_modes` modes, solved with `eigen`.
    ///
    /// # Errors
    /// `tuned = 0`, an uncertainty that is not a positive percentage.
    pub fn options(
        &self,
        test_modes: usize,
        eigen: &EigenOptions,
    ) -> Result<UpdateStudyOptions, StudyError> {
        let tuned = self.tuned_of(test_modes);
        if tuned == 0 {
            return Err(StudyError::invalid(
                "tuned modes",
                "must be at least 1 (the first N test modes are tuned)",
            ));
        }
        let defaults = UpdateStudyOptions::new(tuned, test_modes);
        Ok(UpdateStudyOptions {
            method: self.method,
            all: self.all,
            shapes: self.shapes,
            uncertainty: TestUncertainty::from_percent(
                self.frequency_uncertainty,
                self.shape_uncertainty,
            )?,
            test_error: self.test_error.or(defaults.test_error),
            discretisation: self.discretisation,
            eigen: eigen.clone(),
            ..defaults
        })
    }

    /// What the request asks that its method will not use, one warning each (`shapes` with
    /// SB-EBE, which always uses the shapes).
    pub fn unused(&self) -> Vec<String> {
        let mut w = Vec::new();
        if self.shapes && self.method != UpdateMethod::InverseEigensensitivity {
            w.push(
                "shapes (--shapes) applies to the ies method: SB-EBE always uses the shapes".into(),
            );
        }
        w
    }
}

/// Localisation, updating and the truth check of a loaded model against a loaded test, as
/// `request` asks: the candidate sets resolved by name ([`resolve_sets`]), the defaults of
/// [`UpdateRequest::options`], and the model's assembly reused when its mass is consistent (the
/// updating's mass). `before` are the model's own modes when the caller has solved them
/// (consistent mass; ignored otherwise). Every front end (CLI, study file, Python) calls this.
///
/// # Errors
/// Unknown sets, `tuned = 0`, and those of [`localise_update_check`].
pub fn update_loaded(
    model: &LoadedModel,
    test: &LoadedTest,
    request: &UpdateRequest,
    eigen: &EigenOptions,
    before: Option<&ModeSet>,
    progress: impl FnMut(&Iteration),
) -> Result<UpdateStudy, StudyError> {
    let names = resolve_sets(model, &request.sets)?;
    let names: Vec<&str> = names.iter().map(String::as_str).collect();
    let options = request.options(test.data.modes.len(), eigen)?;
    let consistent = model.sys.mass_kind == MassKind::Consistent;
    localise_update_check(
        &model.model,
        &names,
        &test.layout,
        &test.data.modes,
        before.filter(|_| consistent),
        consistent.then_some((&model.asm, &model.sys)),
        &options,
        progress,
    )
}

/// Settings of [`localise_update_check`].
#[derive(Debug, Clone, PartialEq)]
pub struct UpdateStudyOptions {
    /// The updating method (default SB-EBE).
    pub method: UpdateMethod,
    /// The first `tuned` test modes are used for localisation and updating; the others are held
    /// out for the truth check.
    pub tuned: usize,
    /// Update every candidate set instead of the localised ones.
    pub all: bool,
    /// SB-EBE's trust in the test ([`SbebeOptions::test_error`]; default `Some(1e-3)`).
    pub test_error: Option<f64>,
    /// Also run the other method on the same sets, for comparison (default false).
    pub compare: bool,
    /// Model modes computed before and after updating for the truth check.
    pub check_modes: usize,
    /// The test's uncertainty: the truth check's tolerance, inverse eigensensitivity's weights.
    pub uncertainty: TestUncertainty,
    /// Inverse eigensensitivity fits the shapes at the sensors too (eigenvector derivatives).
    pub shapes: bool,
    /// Estimate the model's discretisation error (the same mesh with quadratic elements) and
    /// weigh the verdict with it (default true; skipped for quadratic meshes).
    pub discretisation: bool,
    /// The eigensolver of every solve of the workflow (the modes before and after, the
    /// eigensensitivities, the discretisation estimate's reference).
    pub eigen: EigenOptions,
}

impl UpdateStudyOptions {
    /// The defaults for `tuned` modes out of `test_modes`: SB-EBE with test error `1e-3`, the
    /// localised sets, `test_modes + 10` model modes for the check.
    pub fn new(tuned: usize, test_modes: usize) -> Self {
        Self {
            method: UpdateMethod::SbEbe,
            tuned,
            all: false,
            test_error: Some(1e-3),
            compare: false,
            check_modes: test_modes + 10,
            uncertainty: TestUncertainty::default(),
            shapes: false,
            discretisation: true,
            eigen: EigenOptions::default(),
        }
    }
}

/// What [`localise_update_check`] found.
#[derive(Debug, Clone, Serialize)]
pub struct UpdateStudy {
    /// The candidate element sets, in the localisation's group order.
    pub candidates: Vec<String>,
    /// Localisation among the candidates.
    pub localisation: Localisation,
    /// The sets updated.
    pub updated_sets: Vec<String>,
    /// The updating run.
    pub result: UpdateResult,
    /// The other method on the same sets, when asked for.
    pub comparison: Option<UpdateResult>,
    /// Held-out check of the updated model, judged against the test's uncertainty, the
    /// discretisation error and the parameters' plausibility.
    pub truth_check: TruthCheck,
    /// The model's discretisation error, when estimated.
    pub discretisation: Option<DiscretisationEstimate>,
    /// Before updating, what the chosen parameters can reach (best residual in their span and
    /// the Theorem 2 interval that follows on each tuned mode).
    pub reach: Reach,
    /// The updated model's modes (those of the check).
    #[serde(skip)]
    pub updated_modes: ModeSet,
}

/// Localises among the element sets `candidates` of `model` (stiffness corrections), updates the
/// selected ones (or all) from the first `options.tuned` test modes, and checks the updated model
/// on every test mode. `before` are the nominal model's modes when the caller has them (computed
/// otherwise); `assembly` the model's assembler and consistent-mass matrices when the caller has
/// them (the model is then not assembled again). `progress` receives each iteration.
///
/// # Errors
/// No candidate, `tuned` out of range, unknown sets, and the updating errors.
pub fn localise_update_check(
    model: &Model,
    candidates: &[&str],
    layout: &SensorLayout,
    test: &TestModes,
    before: Option<&ModeSet>,
    assembly: Option<(&Assembler, &SystemMatrices)>,
    options: &UpdateStudyOptions,
    mut progress: impl FnMut(&Iteration),
) -> Result<UpdateStudy, StudyError> {
    if options.tuned == 0 || options.tuned > test.len() {
        return Err(StudyError::invalid(
            "tuned modes",
            format!(
                "{} tuned modes: need 1 to the {} test modes",
                options.tuned,
                test.len()
            ),
        ));
    }
    let tuned = TestModes::new(
        test.frequencies_hz[..options.tuned].to_vec(),
        None,
        test.shapes.as_ref().subcols(0, options.tuned).to_owned(),
    )?;
    let build = |sets: &[&str]| -> Result<UpdateModel<'_>, StudyError> {
        Ok(match assembly {
            Some((asm, base)) if base.mass_kind == MassKind::Consistent => {
                let groups = ParameterGroups::from_element_sets(model, sets, MassKind::Consistent)?;
                UpdateModel::from_assembly(
                    model,
                    groups,
                    Corrections::Stiffness,
                    asm.clone(),
                    base.clone(),
                )?
            }
            _ => UpdateModel::from_element_sets(
                model,
                sets,
                MassKind::Consistent,
                Corrections::Stiffness,
            )?,
        })
    };
    let mut nominal = build(candidates)?;
    let localisation = localise_expanded(&nominal, layout, &tuned, &SelectionRule::default())?;
    let chosen: Vec<&str> = if options.all {
        candidates.to_vec()
    } else {
        localisation
            .selected
            .iter()
            .map(|g| candidates[*g])
            .collect()
    };
    let chosen_groups: Vec<usize> = chosen
        .iter()
        .filter_map(|c| candidates.iter().position(|k| k == c))
        .collect();
    // the model that will be updated serves the a priori reach first (left at zero)
    let mut up = build(&chosen)?;
    let reach = reach(&localisation, &chosen_groups, &mut up, layout, &tuned)?;
    let computed;
    let before = match before {
        Some(b) => b,
        None => {
            computed = model_modes(&mut nominal, options.check_modes, &options.eigen)?;
            &computed
        }
    };
    let run = |method: UpdateMethod,
               up: &mut UpdateModel<'_>,
               log: &mut dyn FnMut(&Iteration)|
     -> Result<UpdateResult, StudyError> {
        Ok(match method {
            UpdateMethod::SbEbe => {
                let o = SbebeOptions {
                    test_error: options.test_error,
                    ..Default::default()
                };
                sb_ebe(up, layout, &tuned, &o, log)?
            }
            UpdateMethod::InverseEigensensitivity => {
                let o = SensitivityOptions {
                    shapes: options.shapes,
                    uncertainty: options.uncertainty,
                    eigen: options.eigen.clone(),
                    ..Default::default()
                };
                inverse_eigensensitivity(up, layout, &tuned, &o, log)?
            }
        })
    };
    let result = run(options.method, &mut up, &mut progress)?;
    let after = model_modes(&mut up, options.check_modes, &options.eigen)?;
    let tuned_idx: Vec<usize> = (0..options.tuned).collect();
    let mut truth_check = truth_check(
        before,
        &after,
        test,
        layout,
        &tuned_idx,
        &Default::default(),
    )?;
    let discretisation = if options.discretisation {
        estimate_discretisation(model, before, &options.eigen)?
    } else {
        None
    };
    // the discretisation error of the model mode each test mode paired with before updating
    let per_test: Vec<Option<f64>> = match &discretisation {
        Some(d) => truth_check
            .modes
            .iter()
            .map(|m| m.f_before.and_then(|f| d.at_frequency(f)))
            .collect(),
        None => Vec::new(),
    };
    let parameters = up
        .parameters()
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let set = chosen[p.group];
            let group = candidates.iter().position(|c| *c == set);
            ParameterFinding {
                name: p.name.clone(),
                value: result.theta[k],
                bounds: (p.lower, p.upper),
                half_width_95: result
                    .confidence
                    .as_ref()
                    .and_then(|c| c.half_width_95.get(k).copied()),
                evidence: group.is_some_and(|g| localisation.selected.contains(&g)),
            }
        })
        .collect();
    truth_check.judge(&JudgeInputs {
        uncertainty: options.uncertainty,
        discretisation: per_test,
        parameters,
    });
    if options.discretisation && discretisation.is_none() {
        truth_check.judgement.reasons.push(
            "the model's discretisation error was not estimated: its mesh is already quadratic (refine it once and compare to know it)".into(),
        );
    }
    if !reach.can_explain() {
        truth_check.judgement.reasons.insert(
            0,
            format!(
                "before updating: the best fit of {} removes only {:.0} % of the expanded residual: most of it lies outside these parameters' span",
                chosen.join(", "),
                100.0 * reach.explained
            ),
        );
    }
    let comparison = if options.compare {
        let other = match options.method {
            UpdateMethod::SbEbe => UpdateMethod::InverseEigensensitivity,
            UpdateMethod::InverseEigensensitivity => UpdateMethod::SbEbe,
        };
        Some(run(other, &mut build(&chosen)?, &mut |_| {})?)
    } else {
        None
    };
    Ok(UpdateStudy {
        candidates: candidates.iter().map(|s| s.to_string()).collect(),
        localisation,
        updated_sets: chosen.iter().map(|s| s.to_string()).collect(),
        result,
        comparison,
        truth_check,
        discretisation,
        reach,
        updated_modes: after,
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
