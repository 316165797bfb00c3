//! The updating workflow of the paper: localise the error among candidate element sets from the
//! expanded residues, update the selected sets' stiffness (SB-EBE, or inverse eigensensitivity),
//! and check the updated model on held-out test modes it was not tuned on (the truth check).

use crate::StudyError;
use crate::load::LoadedModel;
use femu_correlate::{ModeSet, SensorLayout, TestModes};
use femu_fem::assembly::{Assembler, MassKind, SystemMatrices};
use femu_fem::groups::ParameterGroups;
use femu_fem::model::Model;
use femu_update::{
    Corrections, Iteration, Localisation, SbebeOptions, SelectionRule, TruthCheck, UpdateMethod,
    UpdateModel, UpdateResult, inverse_eigensensitivity, localise_expanded, model_modes, sb_ebe,
    truth_check,
};
use serde::Serialize;

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
    /// Held-out check of the updated model.
    pub truth_check: TruthCheck,
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
    let computed;
    let before = match before {
        Some(b) => b,
        None => {
            computed = model_modes(&mut nominal, options.check_modes, &Default::default())?;
            &computed
        }
    };
    let run = |method: UpdateMethod,
               log: &mut dyn FnMut(&Iteration)|
     -> Result<(UpdateModel<'_>, UpdateResult), StudyError> {
        let mut up = build(&chosen)?;
        let result = match method {
            UpdateMethod::SbEbe => {
                let o = SbebeOptions {
                    test_error: options.test_error,
                    ..Default::default()
                };
                sb_ebe(&mut up, layout, &tuned, &o, log)?
            }
            UpdateMethod::InverseEigensensitivity => {
                inverse_eigensensitivity(&mut up, layout, &tuned, &Default::default(), log)?
            }
        };
        Ok((up, result))
    };
    let (mut up, result) = run(options.method, &mut progress)?;
    let after = model_modes(&mut up, options.check_modes, &Default::default())?;
    let tuned_idx: Vec<usize> = (0..options.tuned).collect();
    let truth_check = truth_check(
        before,
        &after,
        test,
        layout,
        &tuned_idx,
        &Default::default(),
    )?;
    let comparison = if options.compare {
        let other = match options.method {
            UpdateMethod::SbEbe => UpdateMethod::InverseEigensensitivity,
            UpdateMethod::InverseEigensensitivity => UpdateMethod::SbEbe,
        };
        Some(run(other, &mut |_| {})?.1)
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
