//! The paper's plate study end to end (`femu demo`): the question of F. Hemez, "Can model updating
//! tell the truth?", asked of a plate like the paper's.
//!
//! 1. **Structure**: the free-free steel plate of [`PlateSpec::default`] (1,845 nodes, 5,535 DOFs,
//!    1,360 hex8/penta6/tet4 elements), split into ten regions along its length.
//! 2. **Test**: the "real" plate is the model with region `r3` 30 % stiffer (a modelling error the
//!    nominal model does not have); its first ten elastic modes at 15 upper-surface nodes in y and z
//!    (30 measurements), with deterministic noise (shapes and frequencies), written as a Universal
//!    File and read back like real test data.
//! 3. **Report**: Table 1 (pairs, frequency errors, MAC), Table 2 (gaps against the estimators in
//!    the paper's and the rigorous form, on the shapes expanded from the 30 measurements, and
//!    whether each bound holds), Figure 1 (estimators against the number of measured nodes, by
//!    expansion method), the element error map (VTK cell data and an SVG bar chart), SB-EBE on the
//!    localised regions with inverse eigensensitivity beside it, and the held-out check on modes
//!    5-10: does the updated model tell the truth?

use crate::StudyError;
use crate::chart::{error_map_svg, write_png};
use crate::estimate::{EstimateOptions, EstimateRow, expand_and_estimate};
use crate::removal::{RemovalOptions, removal_study, write_removal_study};
use crate::report::{create_dir, write_json, write_shapes_vtu, write_text};
use crate::updating::{UpdateStudyOptions, localise_update_check};
use femu_correlate::expansion::Method;
use femu_correlate::modes::hz_of_eigenvalue;
use femu_correlate::study::StudyPoint;
use femu_correlate::{CorrelationReport, Sensor, SensorLayout, TestModes};
use femu_fem::prelude::*;
use femu_io::uff::{UffMode, UffNode, UffUnits, Universal};
use femu_update::{
    Corrections, Localisation, ParameterCheck, TestUncertainty, TruthCheck, UpdateModel,
    UpdateResult, model_modes,
};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

/// Settings of the demo.
#[derive(Debug, Clone)]
pub struct DemoOptions {
    /// Output folder (created).
    pub out: PathBuf,
    /// The plate.
    pub plate: PlateSpec,
    /// The true stiffness correction of region `r3` (default +0.3: 30 % stiffer).
    pub truth: f64,
    /// Noise on the measured shapes, as a fraction of each mode's largest reading (default 0.5 %).
    pub shape_noise: f64,
    /// Noise on the identified frequencies, relative (default 0.05 %).
    pub frequency_noise: f64,
    /// Tuned test modes (the first ones; the others are held out). Default 4, as in the paper.
    pub tuned: usize,
    /// Test modes in all (default 10).
    pub modes: usize,
    /// Every `stride`-th sensor set of Figure 1 is evaluated (default 1).
    pub stride: usize,
    /// The eigensolver of every solve of the study (default femu's own).
    pub eigen: femu_sparse::eigen::EigenOptions,
}

impl Default for DemoOptions {
    fn default() -> Self {
        Self {
            out: PathBuf::from("femu-demo"),
            plate: PlateSpec::default(),
            truth: 0.3,
            shape_noise: 0.005,
            frequency_noise: 0.0005,
            tuned: 4,
            modes: 10,
            stride: 1,
            eigen: Default::default(),
        }
    }
}

impl DemoOptions {
    /// A smaller study for tests and a first look: the plate at half the resolution in x and y
    /// (10 mm cells, about 1,600 DOFs) and every third sensor set of Figure 1.
    pub fn quick() -> Self {
        Self {
            plate: PlateSpec {
                divisions: [20, 7, 2],
                ..PlateSpec::default()
            },
            stride: 3,
            ..Self::default()
        }
    }
}

/// What the demo found, also written as `report.json`.
#[derive(Debug, Clone, Serialize)]
pub struct DemoReport {
    /// DOFs of the model.
    pub dofs: usize,
    /// Table 1.
    pub table1: CorrelationReport,
    /// Table 2.
    pub table2: Vec<EstimateRow>,
    /// Every bound of every test mode behind Table 2 (Theorems 1-4 in both forms, the MAC, MSD,
    /// Kato-Temple and Davis-Kahan bounds).
    pub assessments: Vec<femu_correlate::Assessment>,
    /// Figure 1's points.
    pub figure1: Vec<StudyPoint>,
    /// The paper's residual localisation.
    pub localisation: Localisation,
    /// The regions the data support (forward selection with an F-test).
    pub selection: femu_update::ParameterSelection,
    /// What the workflow decided and why.
    pub notes: Vec<String>,
    /// The default updating (inverse eigensensitivity on frequencies and shapes) of the selected
    /// regions.
    pub updating: UpdateResult,
    /// The paper's SB-EBE on the same regions, for comparison.
    pub sbebe: UpdateResult,
    /// The held-out check of the updated model, judged.
    pub truth_check: TruthCheck,
    /// Before updating, what the selected regions can reach.
    pub reach: femu_update::reach::Reach,
    /// The nominal model's discretisation error (the same mesh with quadratic elements).
    pub discretisation: Option<femu_update::discretisation::DiscretisationEstimate>,
    /// The true correction and its region.
    pub true_parameter: (String, f64),
    /// Seconds per step.
    pub timings: Vec<(String, f64)>,
    /// Files written.
    pub files: Vec<PathBuf>,
}

fn noise(seed: &mut u64) -> f64 {
    *seed ^= *seed << 13;
    *seed ^= *seed >> 7;
    *seed ^= *seed << 17;
    // uniform with unit variance
    ((*seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0) * 3f64.sqrt()
}

/// The "real" plate (region r3 changed by the options' truth) and its modes, with its DOF map.
fn real_plate(
    model: &Model,
    sets: &[&str],
    opts: &DemoOptions,
    progress: &mut impl FnMut(&str),
) -> Result<(femu_correlate::ModeSet, femu_fem::dof::DofMap), StudyError> {
    let mut real =
        UpdateModel::from_element_sets(model, sets, MassKind::Consistent, Corrections::Stiffness)?;
    let mut theta = vec![0.0; 10];
    theta[3] = opts.truth;
    real.set_theta(&theta)?;
    let n = real.matrices().dofs.free_count();
    progress(&format!(
        "plate: {} nodes, {} elements {:?}, {n} DOF; the real plate has region r3 {:+.0} % stiffer",
        model.mesh().node_count(),
        model.mesh().element_count(),
        model.mesh().kind_counts(),
        100.0 * opts.truth
    ));
    let truth = model_modes(&mut real, 6 + opts.modes, &opts.eigen)?;
    Ok((truth, real.matrices().dofs.clone()))
}

/// The demo's maps: `plate.vtu` (the updated model's first four elastic modes, the error
/// indicator per element) and the error map as SVG and PNG.
fn write_maps(
    opts: &DemoOptions,
    model: &Model,
    dofs: &femu_fem::dof::DofMap,
    updated: &femu_correlate::ModeSet,
    density: &[f64],
    localisation: &Localisation,
    files: &mut Vec<PathBuf>,
) -> Result<(), StudyError> {
    let names: Vec<String> = (0..4)
        .map(|j| {
            format!(
                "updated model mode {} ({:.1} Hz)",
                j + 1,
                hz_of_eigenvalue(updated.values[6 + j])
            )
        })
        .collect();
    let vtu = opts.out.join("plate.vtu");
    write_shapes_vtu(
        &vtu,
        model,
        dofs,
        updated.shapes.as_ref().subcols(6, 4),
        &names,
        &[femu_io::vtk::CellField {
            name: "error indicator (explained residual density)",
            values: density,
        }],
    )?;
    files.push(vtu);
    let svg = error_map_svg(localisation);
    write_text(&opts.out.join("error_map.svg"), &svg, files)?;
    write_png(&svg, 2.0, opts.out.join("error_map.png"))?;
    files.push(opts.out.join("error_map.png"));
    Ok(())
}

/// The simulated test: the real plate's modes `truth` read on `layout` at `nodes` (y and z),
/// with the options' noise on shapes and frequencies, written as a universal file at `path`
/// (units, the sensor nodes' coordinates, dataset 55).
fn write_test_uff(
    opts: &DemoOptions,
    model: &Model,
    nodes: &[u64],
    layout: &SensorLayout,
    truth: &femu_correlate::ModeSet,
    path: &std::path::Path,
) -> Result<(), StudyError> {
    let x_true = truth.shapes.as_ref().subcols(6, opts.modes);
    let mut y = layout.measure_all(x_true)?;
    // the noise must not depend on the arbitrary sign of an eigenvector (round-off)
    femu_correlate::modes::canonical_signs(&mut y);
    let mut seed = 0x2545_F491_4F6C_DD1D_u64;
    for j in 0..y.ncols() {
        let peak = y.col(j).iter().fold(0.0_f64, |a, v| a.max(v.abs()));
        for i in 0..y.nrows() {
            y[(i, j)] += opts.shape_noise * peak * noise(&mut seed);
        }
    }
    let f_test: Vec<f64> = truth.values[6..6 + opts.modes]
        .iter()
        .map(|l| hz_of_eigenvalue(*l) * (1.0 + opts.frequency_noise * noise(&mut seed)))
        .collect();
    // as a universal file, then read back like real test data
    let mut uff = Universal {
        units: Some(UffUnits {
            code: 1,
            description: "SI".into(),
            factors: [1.0, 1.0, 1.0],
        }),
        ..Default::default()
    };
    for id in nodes {
        let i = model.mesh().node_index(*id).ok_or_else(|| {
            StudyError::invalid("sensor node", format!("{id} is not in the plate"))
        })?;
        uff.nodes.push(UffNode {
            id: *id,
            x: model.mesh().coords()[i],
        });
    }
    for (j, f) in f_test.iter().enumerate() {
        uff.modes.push(UffMode {
            number: j as i64 + 1,
            frequency_hz: *f,
            damping: 0.0,
            modal_mass: 0.0,
            values: nodes
                .iter()
                .enumerate()
                .map(|(k, id)| (*id, [0.0, y[(2 * k, j)], y[(2 * k + 1, j)]]))
                .collect(),
            complex: false,
            complexity: None,
            imaginary: None,
        });
    }
    femu_io::uff::write_uff(path, &uff)?;
    Ok(())
}

/// The plate of `spec` in steel, with ten regions along x as element sets `r0`..`r9`.
pub fn plate_with_regions(spec: &PlateSpec) -> Result<Model, StudyError> {
    let mut mesh = mixed_plate(spec)?;
    add_slab_sets(&mut mesh, 0, 10, "r")?;
    let mut model = Model::new(mesh)?;
    model.set_material(None, Material::steel())?;
    Ok(model)
}

/// Runs the study; `progress` receives one line per step.
///
/// # Errors
/// File system errors (naming the file) and the errors of the steps.
pub fn run_demo(
    opts: &DemoOptions,
    mut progress: impl FnMut(&str),
) -> Result<DemoReport, StudyError> {
    if opts.tuned == 0 || opts.tuned >= opts.modes {
        return Err(StudyError::invalid(
            "tuned modes",
            format!(
                "{} must be at least 1 and fewer than the {} test modes",
                opts.tuned, opts.modes
            ),
        ));
    }
    create_dir(&opts.out)?;
    let mut files = Vec::new();
    let mut timings = Vec::new();
    let mut clock = Instant::now();
    let mut lap = |name: &str, timings: &mut Vec<(String, f64)>| {
        timings.push((name.to_string(), clock.elapsed().as_secs_f64()));
        clock = Instant::now();
    };
    let model = plate_with_regions(&opts.plate)?;
    let inp = opts.out.join("plate.inp");
    femu_io::inp::write_inp(&model, None, &inp)?;
    files.push(inp);
    let regions: Vec<String> = (0..10).map(|r| format!("r{r}")).collect();
    let sets: Vec<&str> = regions.iter().map(|s| s.as_str()).collect();
    // the "real" plate and its test
    let (truth, dofs) = real_plate(&model, &sets, opts, &mut progress)?;
    let n = dofs.free_count();
    let nodes = femu_correlate::placement::grid_nodes(model.mesh(), "zmax", [5, 3])?;
    let sensors = nodes
        .iter()
        .flat_map(|id| [1, 2].map(|c| Sensor::axis(*id, c)));
    let layout = SensorLayout::new(model.mesh(), &dofs, sensors.collect())?;
    let x_true = truth.shapes.as_ref().subcols(6, opts.modes).to_owned();
    let uff_path = opts.out.join("test.unv");
    write_test_uff(opts, &model, &nodes, &layout, &truth, &uff_path)?;
    files.push(uff_path.clone());
    let data = femu_io::uff::read_uff(&uff_path)?.test_data(&uff_path)?;
    let layout = SensorLayout::new(model.mesh(), &dofs, data.sensors.clone())?;
    let test = data.modes;
    lap("simulate the test and write it as UFF", &mut timings);
    progress(&format!(
        "test: {} modes at {} measurements written to {} and read back",
        test.len(),
        layout.len(),
        uff_path.display()
    ));

    // the nominal model
    let mut nominal = UpdateModel::from_element_sets(
        &model,
        &sets,
        MassKind::Consistent,
        Corrections::Stiffness,
    )?;
    let model_set = model_modes(&mut nominal, 6 + opts.modes + 6, &opts.eigen)?;
    lap("nominal modes (Sturm-verified)", &mut timings);

    // Tables 1 and 2: correlation, and the estimators on the shapes expanded from the 30
    // measurements
    let sys = nominal.matrices().clone();
    let estimate_options = EstimateOptions {
        expansion: Method::MinimumResidual,
        eigen: opts.eigen.clone(),
        ..Default::default()
    };
    let (_, estimated) =
        expand_and_estimate(&model, &sys, &layout, &test, &model_set, &estimate_options)?;
    progress("Table 1: correlation done");
    let table1 = estimated.correlation;
    let table2 = estimated.rows;
    let assessments = estimated.assessments;
    lap("Table 2: expansion and estimators", &mut timings);
    progress("Table 2: estimators done");

    // Figure 1: sensor removal in EfI order, for the first `tuned` modes
    let k_modes = opts.tuned;
    let lambdas = test.eigenvalues();
    // down to 5 nodes: below that the minimum-residual problem of this free-free plate is too
    // ill-conditioned to refine (reported as an error, never a NaN)
    let removal_options = RemovalOptions {
        methods: Method::FIGURE1.to_vec(),
        keep: 5,
        stride: opts.stride,
    };
    let figure1 = removal_study(
        &sys,
        model.mesh(),
        &nodes,
        model_set.shapes.as_ref().subcols(6, k_modes),
        &lambdas[..k_modes],
        x_true.as_ref().subcols(0, k_modes),
        &removal_options,
    )?
    .points;
    files.extend(write_removal_study(&opts.out, "figure1", &figure1)?);
    lap("Figure 1: sensor-removal study", &mut timings);
    progress(&format!("Figure 1: {} points", figure1.len()));

    // localisation, updating on the tuned modes and the held-out check
    // the default workflow, with the paper's SB-EBE on the same regions for comparison
    let update_options = UpdateStudyOptions {
        compare: true,
        check_modes: 6 + opts.modes + 6,
        // the demo knows its test's noise: standard deviations of the uniform noise it adds
        uncertainty: TestUncertainty {
            frequency: opts.frequency_noise.max(1e-6),
            shape: opts.shape_noise.max(1e-6),
            given: true,
        },
        eigen: opts.eigen.clone(),
        ..UpdateStudyOptions::new(opts.tuned, opts.modes)
    };
    let study = localise_update_check(
        &model,
        &sets,
        &layout,
        &test,
        Some(&model_set),
        Some((nominal.assembler(), nominal.nominal())),
        &update_options,
        |it| {
            progress(&format!(
                "updating iteration {}: objective {:.4e}",
                it.iteration, it.objective
            ))
        },
    )?;
    let (Some(localisation), Some(reach), Some(sbebe)) =
        (study.localisation, study.reach, study.comparison)
    else {
        return Err(StudyError::invalid(
            "demo",
            "the residual localisation, its reach or the SB-EBE comparison did not run",
        ));
    };
    let updating = study.result;
    let mut truth_check = study.truth_check;
    let discretisation = study.discretisation;
    for (name, v) in updating.names.iter().zip(&updating.theta) {
        let t = if name == "k:r3" { opts.truth } else { 0.0 };
        truth_check.parameters.push(ParameterCheck {
            name: name.clone(),
            identified: *v,
            truth: t,
        });
    }
    let selected = study.updated_sets;
    lap(
        "localisation, selection, updating, held-out check and SB-EBE",
        &mut timings,
    );
    progress(&format!("localisation: selected {selected:?}"));
    progress(&format!(
        "does the updated model tell the truth? {}",
        truth_check.verdict()
    ));

    // VTK: error map and the updated model's first elastic modes
    write_maps(
        opts,
        &model,
        &dofs,
        &study.updated_modes,
        &localisation.density_by_element(&nominal),
        &localisation,
        &mut files,
    )?;

    let report = DemoReport {
        dofs: n,
        table1,
        table2,
        assessments,
        figure1,
        localisation,
        selection: study.selection,
        notes: study.notes,
        updating,
        sbebe,
        truth_check,
        reach,
        discretisation,
        true_parameter: ("k:r3".into(), opts.truth),
        timings,
        files: Vec::new(),
    };
    let md = markdown(&report, opts, &test);
    write_text(&opts.out.join("report.md"), &md, &mut files)?;
    let json_path = opts.out.join("report.json");
    files.push(json_path.clone());
    let mut report = report;
    report.files = files;
    write_json(&json_path, &report)?;
    Ok(report)
}

fn markdown(r: &DemoReport, o: &DemoOptions, test: &TestModes) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# femu demo: can model updating tell the truth?\n");
    let _ = writeln!(
        s,
        "Plate {:?} m, {} DOF, free-free steel. The real plate has region r3 {:+.0} % stiffer. Test: {} elastic modes at {} measurements (15 nodes, y and z), noise {:.2} % on shapes and {:.3} % on frequencies, read from `test.unv`. Modes 1-{} are tuned, the others held out.\n",
        o.plate.lengths,
        r.dofs,
        100.0 * o.truth,
        test.len(),
        test.shapes.nrows(),
        100.0 * o.shape_noise,
        100.0 * o.frequency_noise,
        o.tuned
    );
    let _ = writeln!(s, "## Table 1: test-analysis correlation\n\n{}", r.table1);
    let _ = write!(
        s,
        "## Table 2: eigenvalue gap against the estimators\n\nShapes expanded from the test's 30 readings (minimum residual). {}\n\n{}",
        crate::estimate::table2_legend(),
        crate::estimate::table2(&r.table2)
    );
    let _ = writeln!(
        s,
        "\n## Figure 1: estimators against the number of measured nodes\n\n![Figure 1](figure1.png)\n\nSensors: unlike Tables 1 and 2, which use the test's 30 readings (y and z at 15 nodes), Figure 1 measures x, y and z at each of the test's 15 nodes and removes whole nodes, one at a time in Effective Independence order, as the paper's Figure 1 does; `rho_M` in s^-2. Vector version `figure1.svg`; data: `figure1.csv`.\n"
    );
    let _ = writeln!(
        s,
        "## Where is the model wrong?\n\n![error map](error_map.png)\n\n{}\nElement map: cell data of `plate.vtu` (open in ParaView).\n",
        r.localisation
    );
    let _ = writeln!(
        s,
        "## Which regions do the data support?\n\n{}",
        r.selection
    );
    for n in &r.notes {
        let _ = writeln!(s, "- {n}");
    }
    let _ = writeln!(
        s,
        "\n## Updating\n\n{}\nThe default updating (inverse eigensensitivity on frequencies and shapes):\n\n{}\nThe paper's SB-EBE on the same regions, for comparison:\n\n{}",
        r.reach, r.updating, r.sbebe
    );
    if let Some(d) = &r.discretisation {
        let _ = writeln!(
            s,
            "## The model's own error\n\n{}",
            femu_update::discretisation::table(d, &r.truth_check)
        );
    }
    let _ = writeln!(
        s,
        "## Does the updated model tell the truth?\n\n{}",
        r.truth_check
    );
    let _ = writeln!(
        s,
        "The nominal model is `plate.inp` (element sets r0-r9): `femu update plate.inp test.unv --sets r0,r1,r2,r3,r4,r5,r6,r7,r8,r9 --tuned {}` repeats the updating from the files.\n",
        o.tuned
    );
    let _ = writeln!(s, "## Timings\n\n| step | s |\n|---|---|");
    for (k, v) in &r.timings {
        let _ = writeln!(s, "| {k} | {v:.2} |");
    }
    s
}
