//! The updating workflow of the paper: localise the error among candidate element sets from the
//! expanded residues, update the selected sets' stiffness (SB-EBE, or inverse eigensensitivity),
//! and check the updated model on held-out test modes it was not tuned on (the truth check).

use crate::StudyError;
use crate::load::{LoadedModel, LoadedTest};
use femu_correlate::{ModeSet, SensorLayout, TestModes};
use femu_fem::assembly::{Assembler, MassKind, SystemMatrices};
use femu_fem::groups::ParameterGroups;
use femu_fem::model::Model;
use femu_sparse::eigen::EigenOptions;
use femu_update::discretisation::{DiscretisationEstimate, estimate as estimate_discretisation};
use femu_update::reach::{Reach, reach};
use femu_update::{
    Corrections, Iteration, JudgeInputs, Localisation, ParameterFinding, ParameterSelection,
    SbebeOptions, SelectionOptions, SelectionRule, SensitivityOptions, TestUncertainty, TruthCheck,
    UpdateMethod, UpdateModel, UpdateResult, forward_at, inverse_eigensensitivity,
    localise_expanded, model_modes, sb_ebe, select_parameters, truth_check,
};
use serde::{Deserialize, Serialize};

/// What a user asks of the updating workflow ([`update_loaded`]): the one definition behind
/// `femu update`'s arguments (with the `clap` feature), a study file's `[update]` section and the
/// Python binding's `update`, with the one set of defaults ([`UpdateRequest::options`]).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
#[serde(deny_unknown_fields)]
pub struct UpdateRequest {
    /// Candidate element sets (comma-separated); localisation selects among them. A set scales
    /// its elements' stiffness (`k:SET`); `t:SET` is the thickness of the set's shells (bending
    /// with its cube, membrane and mass linearly); `EA:SET`, `GJ:SET`, `EI1:SET`, `EI2:SET` a
    /// part of its beams' stiffness (axial, torsion, a bending plane with its shear); a mass set (a
    /// Nastran CONM2 as `CONM2_<EID>`) scales its masses (`m:SET`). For a model of another solver's matrices,
    /// groups as `NAME=FILE`: FILE the same model's matrices with the group's Young's modulus and
    /// density doubled (relative to the model's folder).
    #[cfg_attr(feature = "clap", arg(long, value_delimiter = ',', required = true))]
    pub sets: Vec<String>,
    /// The first N test modes are tuned, the others held out (default: all but the last third).
    #[cfg_attr(feature = "clap", arg(long))]
    #[serde(default)]
    pub tuned: Option<usize>,
    /// The updating method (default: inverse eigensensitivity on frequencies and shapes, the
    /// one that holds under noise and discretisation error; `sbebe` is the paper's).
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value = "ies"))]
    #[serde(default = "default_update_method")]
    pub method: UpdateMethod,
    /// Which candidate sets are updated: those the data support (`forward`: forward selection
    /// with an F-test on the weighted objective, the default), the paper's residual ranking
    /// (`residual`), or `all`.
    #[cfg_attr(feature = "clap", arg(long, value_enum, default_value = "forward"))]
    #[serde(default)]
    pub select: Select,
    /// The test's frequency uncertainty, percent (one standard deviation; default: 0.1 %,
    /// assumed and said so). The truth check's tolerance is three of it.
    #[cfg_attr(feature = "clap", arg(long, value_name = "PERCENT"))]
    #[serde(default)]
    pub frequency_uncertainty: Option<f64>,
    /// The test's shape uncertainty, percent of each mode's largest reading (default: 1 %).
    #[cfg_attr(feature = "clap", arg(long, value_name = "PERCENT"))]
    #[serde(default)]
    pub shape_uncertainty: Option<f64>,
    /// Inverse eigensensitivity and the selection fit the shapes at the sensors as well as the
    /// frequencies (eigenvector derivatives; default true: frequencies alone cannot tell a
    /// correction from a compensation; `--no-shapes` fits the frequencies only).
    #[cfg_attr(
        feature = "clap",
        arg(
            long = "no-shapes",
            action = clap::ArgAction::SetFalse,
            help = "Fit the frequencies only (the selection and inverse eigensensitivity); by default the shapes at the sensors are fitted too"
        )
    )]
    #[serde(default = "default_true")]
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
    UpdateMethod::InverseEigensensitivity
}

/// Which candidate sets the updating workflow updates ([`UpdateRequest::select`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Select {
    /// Those the data support: forward selection with an F-test on the weighted objective of
    /// frequencies and shapes, asked again after each fit (`docs/MATH.md`, "Selecting the
    /// parameters").
    #[default]
    Forward,
    /// The paper's residual ranking on expanded shapes (axis sensors only).
    Residual,
    /// Every candidate.
    All,
}

impl UpdateRequest {
    /// The request with every default, for the candidate sets `sets`.
    pub fn new(sets: Vec<String>) -> Self {
        Self {
            sets,
            tuned: None,
            method: UpdateMethod::InverseEigensensitivity,
            select: Select::Forward,
            frequency_uncertainty: None,
            shape_uncertainty: None,
            shapes: true,
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
            select: self.select,
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

    /// What the request asks that its method will not use, one warning each (frequencies only
    /// with SB-EBE, which always uses the shapes; a test error with inverse eigensensitivity).
    pub fn unused(&self) -> Vec<String> {
        let mut w = Vec::new();
        if !self.shapes && self.method == UpdateMethod::SbEbe {
            w.push("frequencies only (--no-shapes) applies to the selection: SB-EBE always uses the shapes".into());
        }
        if self.test_error.is_some() && self.method != UpdateMethod::SbEbe {
            w.push("the test error (--test-error) is SB-EBE's: inverse eigensensitivity weighs the shapes by the shape uncertainty".into());
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
/// A model read as another solver's matrices is updated over matrix groups: each of `sets` is
/// `NAME=FILE`, the same model's matrices with the group's Young's modulus and density doubled
/// ([`crate::external::matrix_groups`]).
///
/// # Errors
/// Unknown sets (or group files), `tuned = 0`, and those of [`localise_update_check`].
pub fn update_loaded(
    model: &LoadedModel,
    test: &LoadedTest,
    request: &UpdateRequest,
    eigen: &EigenOptions,
    before: Option<&ModeSet>,
    progress: impl FnMut(&Iteration),
) -> Result<UpdateStudy, StudyError> {
    if model.matrices.is_some() {
        let groups = crate::external::matrix_groups(model, &request.sets)?;
        let names: Vec<&str> = groups.iter().map(|g| g.0.as_str()).collect();
        let options = request.options(test.data.modes.len(), eigen)?;
        return localise_update_check_with(
            &model.model,
            &names,
            &test.layout,
            &test.data.modes,
            before,
            Candidates::Matrices {
                base: &model.sys,
                groups: &groups,
            },
            &options,
            progress,
        );
    }
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
    /// The updating method (default inverse eigensensitivity).
    pub method: UpdateMethod,
    /// The first `tuned` test modes are used for localisation and updating; the others are held
    /// out for the truth check.
    pub tuned: usize,
    /// Which candidates are updated (default: those the data support).
    pub select: Select,
    /// The forward selection's settings.
    pub selection: SelectionOptions,
    /// SB-EBE's trust in the test ([`SbebeOptions::test_error`]; default `Some(1e-3)`).
    pub test_error: Option<f64>,
    /// Also run the other method on the same sets, for comparison (default false).
    pub compare: bool,
    /// Model modes computed before and after updating for the truth check.
    pub check_modes: usize,
    /// The test's uncertainty: the truth check's tolerance, inverse eigensensitivity's weights.
    pub uncertainty: TestUncertainty,
    /// The selection and inverse eigensensitivity fit the shapes at the sensors too (eigenvector
    /// derivatives; default true).
    pub shapes: bool,
    /// Estimate the model's discretisation error (the same mesh with quadratic elements) and
    /// weigh the verdict with it (default true; skipped for quadratic meshes).
    pub discretisation: bool,
    /// The eigensolver of every solve of the workflow (the modes before and after, the
    /// eigensensitivities, the discretisation estimate's reference).
    pub eigen: EigenOptions,
}

impl UpdateStudyOptions {
    /// The defaults for `tuned` modes out of `test_modes`: inverse eigensensitivity on
    /// frequencies and shapes, the sets the forward selection supports, `test_modes + 10` model
    /// modes for the check (SB-EBE's test error `1e-3` when it is asked for).
    pub fn new(tuned: usize, test_modes: usize) -> Self {
        Self {
            method: UpdateMethod::InverseEigensensitivity,
            tuned,
            select: Select::Forward,
            selection: SelectionOptions::default(),
            test_error: Some(1e-3),
            compare: false,
            check_modes: test_modes + 10,
            uncertainty: TestUncertainty::default(),
            shapes: true,
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
    /// The paper's residual localisation among the candidates (`None` when a sensor does not lie
    /// along a global axis: it expands the shapes).
    pub localisation: Option<Localisation>,
    /// The parameters the data support (forward selection with an F-test), with its steps, its
    /// refits and its stability under resampling.
    pub selection: ParameterSelection,
    /// What the workflow decided and why, one sentence each (where the residual ranking and the
    /// selection disagree, a candidate added after a refit, ...).
    pub notes: Vec<String>,
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
    /// the Theorem 2 interval that follows on each tuned mode); with the residual localisation.
    pub reach: Option<Reach>,
    /// The updated model's modes (those of the check).
    #[serde(skip)]
    pub updated_modes: ModeSet,
}

impl std::fmt::Display for UpdateStudy {
    /// The study as `femu update` prints it: localisation, selection and its notes, reach, the
    /// updating, the model's own error and the truth check.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if let Some(l) = &self.localisation {
            writeln!(
                f,
                "Residual localisation ({} candidate sets):\n{l}",
                self.candidates.len()
            )?;
        }
        writeln!(f, "{}", self.selection)?;
        for n in &self.notes {
            writeln!(f, "- {n}")?;
        }
        writeln!(f, "\nUpdated: {}\n", self.updated_sets.join(", "))?;
        if let Some(r) = &self.reach {
            writeln!(f, "{r}")?;
        }
        writeln!(f, "{}", self.result)?;
        if let Some(c) = &self.comparison {
            writeln!(f, "For comparison:\n{c}")?;
        }
        if let Some(d) = &self.discretisation {
            writeln!(
                f,
                "{}",
                femu_update::discretisation::table(d, &self.truth_check)
            )?;
        }
        write!(f, "{}", self.truth_check)
    }
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
    progress: impl FnMut(&Iteration),
) -> Result<UpdateStudy, StudyError> {
    localise_update_check_with(
        model,
        candidates,
        layout,
        test,
        before,
        Candidates::ElementSets(assembly),
        options,
        progress,
    )
}

/// What the candidates of [`localise_update_check_with`] are.
#[derive(Clone, Copy)]
pub enum Candidates<'a> {
    /// Element sets of the model, by name; with the caller's assembler and consistent-mass
    /// matrices when it has them.
    ElementSets(Option<(&'a Assembler, &'a SystemMatrices)>),
    /// Groups given as assembled matrices on `base`'s DOFs (`name`, `K_g`, `M_g`), for a model of
    /// another solver's matrices.
    Matrices {
        /// The nominal matrices.
        base: &'a SystemMatrices,
        /// The groups, named as the candidates are.
        groups: &'a [(String, femu_sparse::SparseMatrix, femu_sparse::SparseMatrix)],
    },
}

/// [`localise_update_check`] over element sets or over matrix groups ([`Candidates`]).
///
/// # Errors
/// As [`localise_update_check`].
#[allow(clippy::too_many_arguments)]
pub fn localise_update_check_with(
    model: &Model,
    candidates: &[&str],
    layout: &SensorLayout,
    test: &TestModes,
    before: Option<&ModeSet>,
    groups: Candidates<'_>,
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
    let build = |sets: &[&str]| update_model(model, sets, groups);
    let mut nominal = build(candidates)?;
    // a test of frequencies alone: the selection and the fit use the frequencies; SB-EBE and the
    // residual ranking, which expand the shapes, cannot run
    let has_shapes = test.has_shapes();
    if !has_shapes && options.method == UpdateMethod::SbEbe {
        return Err(StudyError::invalid(
            "updating method",
            "SB-EBE expands the test's shapes, and the test gives frequencies alone: use the default (inverse eigensensitivity, which fits the frequencies)",
        ));
    }
    let sensitivity = SensitivityOptions {
        shapes: options.shapes && has_shapes,
        uncertainty: options.uncertainty,
        eigen: options.eigen.clone(),
        ..Default::default()
    };
    // the nominal modes first, before any solve leaves its shift as the next one's hint: the
    // same modes as a caller's own solve, bit for bit
    let computed;
    let before = match before {
        Some(b) => b,
        None => {
            computed = model_modes(&mut nominal, options.check_modes, &options.eigen)?;
            &computed
        }
    };
    nominal.forget_shift();
    let mut notes = Vec::new();
    // the paper's residual ranking expands the shapes: axis sensors only
    if !has_shapes {
        notes.push("the test gives frequencies alone: the modes are paired by frequency, the selection and the fit use the frequencies only (mirror-symmetric regions cannot be told apart), and the residual ranking, which expands the shapes, is not run".into());
    }
    let localisation = if !has_shapes {
        None
    } else if layout.measured_dofs().is_some() {
        match localise_expanded(&nominal, layout, &tuned, &SelectionRule::default()) {
            Ok(l) => Some(l),
            // the ranking is the paper's diagnosis beside the selection: a shape it cannot
            // expand stops the update only when the ranking is what selects
            Err(e) if options.select != Select::Residual => {
                notes.push(format!(
                    "the residual ranking could not expand the test shapes ({e}): only the forward selection and the fit were run"
                ));
                None
            }
            Err(e) => return Err(e.into()),
        }
    } else {
        notes.push("the residual ranking expands the shapes and needs every sensor along a global axis: only the forward selection was run".into());
        None
    };
    let mut selection = select_parameters(
        &mut nominal,
        layout,
        &tuned,
        &sensitivity,
        &options.selection,
    )?;
    let (mut chosen_groups, unsupported) = choose(
        options.select,
        candidates,
        localisation.as_ref(),
        &selection,
        &mut notes,
    )?;
    let run = |method: UpdateMethod,
               up: &mut UpdateModel<'_>,
               log: &mut dyn FnMut(&Iteration)|
     -> Result<UpdateResult, StudyError> {
        run_method(method, up, layout, &tuned, options, &sensitivity, log)
    };
    let names_of =
        |groups: &[usize]| -> Vec<&str> { groups.iter().map(|g| candidates[*g]).collect() };
    // fit the chosen sets; with the forward selection, ask again at the fit whether another
    // candidate is still needed (the first selection is linear at the nominal model)
    let (mut up, result) = loop {
        let mut up = build(&names_of(&chosen_groups))?;
        let result = run(options.method, &mut up, &mut progress)?;
        if options.select != Select::Forward
            || options.method != UpdateMethod::InverseEigensensitivity
            || chosen_groups.len() >= candidates.len()
        {
            break (up, result);
        }
        let mut at_fit = vec![0.0; candidates.len()];
        for (k, g) in chosen_groups.iter().enumerate() {
            at_fit[*g] = result.theta[k];
        }
        nominal.set_theta(&at_fit)?;
        let steps = forward_at(
            &mut nominal,
            layout,
            &tuned,
            &sensitivity,
            &chosen_groups,
            &options.selection,
        );
        nominal.set_theta(&vec![0.0; candidates.len()])?;
        let added: Vec<_> = steps?.steps.into_iter().filter(|s| s.kept).collect();
        if added.is_empty() {
            break (up, result);
        }
        let list: Vec<String> = added
            .iter()
            .map(|s| format!("{} (F = {:.3e})", s.parameter, s.f_statistic))
            .collect();
        notes.push(format!(
            "at the fit of {}, the selection adds {}: linearised at the nominal model it had not passed",
            names_of(&chosen_groups).join(", "),
            list.join(", ")
        ));
        for s in added {
            chosen_groups.push(s.index);
            selection.selected.push(s.index);
            selection.steps.push(s);
        }
    };
    let chosen = names_of(&chosen_groups);
    // what the chosen parameters can reach, from the residual localisation's expansion
    let reach = match &localisation {
        Some(loc) => {
            let mut fresh = build(&chosen)?;
            Some(reach(loc, &chosen_groups, &mut fresh, layout, &tuned)?)
        }
        None => None,
    };
    let after = model_modes(&mut up, options.check_modes, &options.eigen)?;
    let (truth_check, discretisation) = judge_update(
        model,
        test,
        layout,
        before,
        &after,
        options,
        Fitted {
            up: &up,
            result: &result,
            selection: &selection,
            localisation: localisation.as_ref(),
            chosen_groups: &chosen_groups,
            reach: reach.as_ref(),
            unsupported,
        },
    )?;
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
        selection,
        notes,
        updated_sets: chosen.iter().map(|s| s.to_string()).collect(),
        result,
        comparison,
        truth_check,
        discretisation,
        reach,
        updated_modes: after,
    })
}

/// The updating model of `model` over the element sets `sets` (stiffness factors, consistent
/// mass), on the caller's assembly when it has a consistent-mass one; or over the matrix groups
/// of those names.
fn update_model<'m>(
    model: &'m Model,
    sets: &[&str],
    candidates: Candidates<'_>,
) -> Result<UpdateModel<'m>, StudyError> {
    let assembly = match candidates {
        Candidates::ElementSets(assembly) => assembly,
        Candidates::Matrices { base, groups } => {
            let chosen =
                sets.iter()
                    .map(|s| {
                        groups.iter().find(|g| g.0 == *s).cloned().ok_or_else(|| {
                            StudyError::invalid("matrix group", format!("no group {s}"))
                        })
                    })
                    .collect::<Result<Vec<_>, _>>()?;
            let groups = ParameterGroups::from_matrices(base, chosen)?;
            // the assembler of a model without elements is never used by matrix groups
            let asm = Assembler::new(model)?;
            return Ok(UpdateModel::from_assembly(
                model,
                groups,
                Corrections::Stiffness,
                asm,
                base.clone(),
            )?);
        }
    };
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
}

/// One updating run of `method` on `up` from the tuned modes.
fn run_method(
    method: UpdateMethod,
    up: &mut UpdateModel<'_>,
    layout: &SensorLayout,
    tuned: &TestModes,
    options: &UpdateStudyOptions,
    sensitivity: &SensitivityOptions,
    log: &mut dyn FnMut(&Iteration),
) -> Result<UpdateResult, StudyError> {
    Ok(match method {
        UpdateMethod::SbEbe => {
            let o = SbebeOptions {
                test_error: options.test_error,
                ..Default::default()
            };
            sb_ebe(up, layout, tuned, &o, log)?
        }
        UpdateMethod::InverseEigensensitivity => {
            inverse_eigensensitivity(up, layout, tuned, sensitivity, log)?
        }
    })
}

/// The candidates to update by `select`, with the notes of the choice (where the residual
/// ranking and the selection disagree, candidates the data cannot tell apart), and why the data
/// support none when nothing passed (the best candidate is then chosen, for the record).
fn choose(
    select: Select,
    candidates: &[&str],
    localisation: Option<&Localisation>,
    selection: &ParameterSelection,
    notes: &mut Vec<String>,
) -> Result<(Vec<usize>, Option<String>), StudyError> {
    if let (Some(loc), Some(first)) = (localisation, selection.steps.first())
        && let Some(top) = loc.ranking.first()
        && first.index != top.group
    {
        notes.push(format!(
            "the residual ranking puts {} first ({:.0} % of the expanded residual), the forward selection {} (F = {:.3e}); the ranking reads expanded shapes, where the sensors' noise spreads over the model, the selection weighs each reading by its uncertainty",
            top.name,
            100.0 * top.explained,
            first.parameter,
            first.f_statistic
        ));
    }
    for (p, same) in &selection.equivalents {
        notes.push(format!(
            "{p} cannot be told from {} by these data (parallel sensitivities): the correction is in one of them, the data do not say which",
            same.join(", ")
        ));
    }
    let mut chosen_groups: Vec<usize> = match select {
        Select::All => (0..candidates.len()).collect(),
        Select::Residual => match localisation {
            Some(l) => l.selected.clone(),
            None => {
                return Err(StudyError::invalid(
                    "selection",
                    "the residual ranking needs every sensor along a global axis: use the forward selection",
                ));
            }
        },
        Select::Forward => selection.selected.clone(),
    };
    let mut unsupported = None;
    if chosen_groups.is_empty() {
        // nothing passed: the best candidate is fitted for the record, and the verdict says so
        let best = selection.steps.first();
        let why = match best {
            Some(s) => format!(
                "the tuned modes support no correction among the candidates: the best, {}, lowers the objective by F = {:.3e} (p = {:.2e} against the {:.2e} needed), selected in {:.0} % of the resamples; it is fitted for the record only",
                candidates[s.index],
                s.f_statistic,
                s.p_value,
                s.level,
                100.0 * s.stability.unwrap_or(0.0)
            ),
            None => "the tuned modes support no correction among the candidates (too few residuals to test one)".to_string(),
        };
        notes.push(why.clone());
        unsupported = Some(why);
        chosen_groups.push(best.map_or(0, |s| s.index));
    }
    Ok((chosen_groups, unsupported))
}

/// What the updating produced, for [`judge_update`].
struct Fitted<'a, 'm> {
    up: &'a UpdateModel<'m>,
    result: &'a UpdateResult,
    selection: &'a ParameterSelection,
    localisation: Option<&'a Localisation>,
    chosen_groups: &'a [usize],
    reach: Option<&'a Reach>,
    unsupported: Option<String>,
}

/// The truth check of the updated model (`after`) against every test mode, judged with the
/// test's uncertainty, the model's discretisation error (estimated here when asked) and the
/// identified parameters, and the reasons only the workflow knows.
fn judge_update(
    model: &Model,
    test: &TestModes,
    layout: &SensorLayout,
    before: &ModeSet,
    after: &ModeSet,
    options: &UpdateStudyOptions,
    fitted: Fitted<'_, '_>,
) -> Result<(TruthCheck, Option<DiscretisationEstimate>), StudyError> {
    let tuned_idx: Vec<usize> = (0..options.tuned).collect();
    let mut truth_check =
        truth_check(before, after, test, layout, &tuned_idx, &Default::default())?;
    // a model of another solver's matrices has no mesh to refine
    let discretisation = if options.discretisation && model.mesh().element_count() > 0 {
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
    let Fitted {
        up,
        result,
        selection,
        localisation,
        chosen_groups,
        reach,
        unsupported,
    } = fitted;
    let parameters = up
        .parameters()
        .iter()
        .enumerate()
        .map(|(k, p)| ParameterFinding {
            name: p.name.clone(),
            value: result.theta[k],
            bounds: (p.lower, p.upper),
            half_width_95: result
                .confidence
                .as_ref()
                .and_then(|c| c.half_width_95.get(k).copied()),
            evidence: selection.selected.contains(&chosen_groups[p.group])
                || (options.select == Select::Residual
                    && localisation.is_some_and(|l| l.selected.contains(&chosen_groups[p.group]))),
        })
        .collect();
    let fit_scale = result.confidence.as_ref().map(|c| c.scale.sqrt());
    truth_check.judge(&JudgeInputs {
        uncertainty: options.uncertainty,
        discretisation: per_test,
        parameters,
        fit_scale,
        unsupported,
        implied: result
            .confidence
            .as_ref()
            .and_then(|c| c.implied_uncertainty),
    });
    if options.discretisation
        && discretisation.is_none()
        && let Some(why) = femu_update::discretisation::not_estimated(model)
    {
        truth_check.judgement.reasons.push(format!(
            "the model's discretisation error was not estimated: {why}"
        ));
    }
    for (p, same) in &selection.equivalents {
        if result.names.contains(p) {
            truth_check.judgement.reasons.push(format!(
                "{p} cannot be told from {} by these data: the held-out predictions are the same either way, and only measurements that see the difference (shapes at sensors there) can say which region it is",
                same.join(", ")
            ));
        }
    }
    // the expanded residual holds the readings' noise spread over the model: a low fraction is a
    // finding only when the fit's chi-square also leaves more than the uncertainty explains
    if let Some(reach) = reach
        && !reach.can_explain()
        && fit_scale.is_none_or(|s| s > 1.5)
    {
        truth_check.judgement.reasons.insert(
            0,
            format!(
                "before updating: the best fit of {} removes only {:.0} % of the expanded residual: most of it lies outside these parameters' span",
                up.parameters()
                    .iter()
                    .map(|p| p.name.trim_start_matches("k:").to_string())
                    .collect::<Vec<_>>()
                    .join(", "),
                100.0 * reach.explained
            ),
        );
    }
    Ok((truth_check, discretisation))
}

/// The model's element sets named by `sets` (Abaqus names are case-insensitive; the reader keeps
/// them upper case); `t:SET` names the thickness of set `SET`'s shells
/// (`femu_fem::groups::GroupLaw::Thickness`), `EA:SET`, `GJ:SET`, `EI1:SET` and `EI2:SET` a part
/// of its beams' stiffness (`femu_fem::groups::GroupLaw::Section`).
///
/// # Errors
/// A set the model does not have, naming the model file and the sets it has.
pub fn resolve_sets(model: &LoadedModel, sets: &[String]) -> Result<Vec<String>, StudyError> {
    use femu_fem::groups::THICKNESS_PREFIX;
    let mut known = model.model.element_set_names();
    known.extend(model.model.mass_set_names());
    let prefixes: Vec<&str> = std::iter::once(THICKNESS_PREFIX)
        .chain(femu_fem::structural::SectionPart::ALL.map(|p| p.prefix()))
        .collect();
    sets.iter()
        .map(|s| {
            let (prefix, set) = prefixes
                .iter()
                .find_map(|p| {
                    s.get(..p.len())
                        .filter(|head| head.eq_ignore_ascii_case(p))
                        .map(|_| (*p, &s[p.len()..]))
                })
                .unwrap_or(("", s.as_str()));
            known
                .iter()
                .find(|k| k.eq_ignore_ascii_case(set))
                .map(|k| format!("{prefix}{k}"))
                .ok_or_else(|| {
                    StudyError::in_file(
                        &model.path,
                        "element sets",
                        format!("no element set {s} (the model has: {})", known.join(", ")),
                    )
                })
        })
        .collect()
}
