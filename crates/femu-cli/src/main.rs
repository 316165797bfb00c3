//! The `femu` command. See `femu --help`.

use clap::{Parser, Subcommand};
use femu_fem::assembly::MassKind;
use femu_sparse::eigen::{EigenParams, Which, eigs};
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

/// femu: finite element model updating and test-analysis correlation.
#[derive(Parser)]
#[command(version, about, long_about = None)]
struct Cli {
    /// No progress and no table on stdout (errors still go to stderr).
    #[arg(long, global = true)]
    quiet: bool,
    /// Mesh-only models (Gmsh `.msh`, universal file `.unv` with datasets 2411/2412): Young's
    /// modulus in Pa (with --poisson and --density).
    #[arg(long, global = true)]
    young: Option<f64>,
    /// Mesh-only models: Poisson's ratio.
    #[arg(long, global = true)]
    poisson: Option<f64>,
    /// Mesh-only models: density in kg/m^3.
    #[arg(long, global = true)]
    density: Option<f64>,
    /// Mesh-only models: a node set (Gmsh physical group) to clamp; repeat for several.
    #[arg(long, global = true)]
    fix: Vec<String>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// The a priori estimators of the paper for CSV test modes: rho_M, rho_2, the frequency
    /// interval that holds a model mode, and every bound, after expanding the test shapes.
    ///
    /// Examples:
    ///   femu estimate plate.inp test.csv
    ///   femu estimate plate.inp test.csv --expansion static --json estimate.json
    #[command(verbatim_doc_comment)]
    Estimate {
        /// The model (`.inp`, or `.msh`/`.unv` with --young, --poisson, --density, --fix).
        model: PathBuf,
        /// The test modes (`.csv`).
        test: PathBuf,
        /// Expansion of the test shapes: static, dynamic or min-residual.
        #[arg(long, default_value = "dynamic")]
        expansion: String,
        /// Model modes computed for the comparison (default: twice the test modes plus 4).
        #[arg(long)]
        count: Option<usize>,
        /// Lumped (diagonal) mass instead of consistent.
        #[arg(long)]
        lumped: bool,
        /// Write the assessments (norms, interval, bounds with what they bound) as JSON.
        #[arg(long)]
        json: Option<PathBuf>,
    },
    /// Pair test modes (CSV: mode,frequency_hz,node,direction,value) with the model's modes:
    /// MAC on the sensors, frequency errors, MSD, COMAC.
    ///
    /// Examples:
    ///   femu correlate plate.inp test.csv
    ///   femu correlate plate.inp test.csv --mac-threshold 0.7 --json correlation.json
    #[command(verbatim_doc_comment)]
    Correlate {
        /// The model (`.inp`, or `.msh`/`.unv` with --young, --poisson, --density, --fix).
        model: PathBuf,
        /// The test modes (`.csv`).
        test: PathBuf,
        /// Model modes to compute (default: twice the test modes plus 4).
        #[arg(long)]
        count: Option<usize>,
        /// Smallest MAC accepted for a pair.
        #[arg(long, default_value_t = 0.8)]
        mac_threshold: f64,
        /// Lumped (diagonal) mass instead of consistent.
        #[arg(long)]
        lumped: bool,
        /// Write the correlation (MAC matrix, pairs, MSD, COMAC) as JSON.
        #[arg(long)]
        json: Option<PathBuf>,
    },
    /// Lowest modes of a model, verified by a Sturm count.
    ///
    /// Examples:
    ///   femu modes plate.inp --count 20
    ///   femu modes plate.inp --shift 1500 --count 6 --json modes.json
    ///   femu modes plate.inp --band 1000 3000 --vtu modes.vtu
    #[command(verbatim_doc_comment)]
    Modes {
        /// The model: an Abaqus/CalculiX `.inp` deck (materials and constraints inside).
        model: PathBuf,
        /// How many modes (lowest, or nearest the shift). Default: the deck's *FREQUENCY count, or 10.
        #[arg(long)]
        count: Option<usize>,
        /// Modes nearest this frequency (Hz).
        #[arg(long, conflicts_with = "band")]
        shift: Option<f64>,
        /// Every mode between two frequencies (Hz).
        #[arg(long, num_args = 2, value_names = ["LO", "HI"])]
        band: Option<Vec<f64>>,
        /// Lumped (diagonal) mass instead of consistent.
        #[arg(long)]
        lumped: bool,
        /// Write the result as JSON to this file.
        #[arg(long)]
        json: Option<PathBuf>,
        /// Write the mesh and the mode shapes (point vectors, mass-normalised) for ParaView.
        #[arg(long)]
        vtu: Option<PathBuf>,
    },
    /// Expand test shapes (CSV, JSON or UFF) to every model DOF: rho_M and rho_2 of the expanded
    /// shapes, a VTK file of them, and optionally the sensor-removal study (the paper's Figure 1)
    /// over the test's nodes, removed in Effective Independence order.
    ///
    /// Examples:
    ///   femu expand plate.inp test.unv --method dynamic --vtu expanded.vtu
    ///   femu expand plate.inp test.csv --method min-residual --study figure1
    #[command(verbatim_doc_comment)]
    Expand {
        /// The model (`.inp`, or `.msh`/`.unv` with --young, --poisson, --density, --fix).
        model: PathBuf,
        /// The test modes (`.csv`, `.json`, `.unv`).
        test: PathBuf,
        /// static, dynamic, min-residual or mdre.
        #[arg(long, default_value = "dynamic")]
        method: String,
        /// Lumped (diagonal) mass instead of consistent.
        #[arg(long)]
        lumped: bool,
        /// Write the expanded shapes for ParaView.
        #[arg(long)]
        vtu: Option<PathBuf>,
        /// Run the sensor-removal study and write study.csv and study.svg into this folder.
        #[arg(long)]
        study: Option<PathBuf>,
        /// Write rho_M, rho_2 and the study's points as JSON.
        #[arg(long)]
        json: Option<PathBuf>,
    },
    /// Export the assembled stiffness and mass as MatrixMarket files (`PREFIX_K.mtx`,
    /// `PREFIX_M.mtx`, symmetric, lower triangle, free DOFs in femu's numbering) and the DOF map
    /// (`PREFIX_dofs.csv`: row, node, component).
    ///
    /// Examples:
    ///   femu matrices plate.inp --out plate
    #[command(verbatim_doc_comment)]
    Matrices {
        /// The model (`.inp`, or `.msh`/`.unv` with --young, --poisson, --density, --fix).
        model: PathBuf,
        /// Output prefix.
        #[arg(long)]
        out: PathBuf,
        /// Lumped (diagonal) mass instead of consistent.
        #[arg(long)]
        lumped: bool,
    },
    /// Run a whole study described in a TOML file: correlation, estimation, expansion with the
    /// sensor-removal study, and updating, with every result written to the output folder.
    /// Paths in the file are relative to the file.
    ///
    /// Example study.toml:
    ///   model = "plate.inp"            # or a .msh with [material] and fix
    ///   test = "test.unv"              # .unv, .csv or .json
    ///   [pairing]
    ///   mac_threshold = 0.8
    ///   [expansion]
    ///   method = "dynamic"             # static, dynamic, min-residual, mdre
    ///   study = true                   # the sensor-removal study (Figure 1)
    ///   [update]
    ///   sets = ["r0", "r1", "r2", "r3"]
    ///   tuned = 4
    ///   method = "sbebe"               # or "ies"
    ///
    /// Examples:
    ///   femu run study.toml --out results
    #[command(verbatim_doc_comment)]
    Run {
        /// The study file.
        study: PathBuf,
        /// Output folder.
        #[arg(long, default_value = "femu-study")]
        out: PathBuf,
    },
    /// The paper's plate study end to end: a plate with a modelling error is "tested" (UFF),
    /// correlated (Table 1), estimated (Table 2), studied under sensor removal (Figure 1),
    /// localised, updated by SB-EBE and checked on held-out modes. About 45 s on 2 cores.
    ///
    /// Examples:
    ///   femu demo
    ///   femu demo --out report --shape-noise 0.01
    #[command(verbatim_doc_comment)]
    Demo {
        /// Output folder for report.md, report.json, figure1.svg/csv, error_map.svg, plate.vtu
        /// and test.unv.
        #[arg(long, default_value = "femu-demo")]
        out: PathBuf,
        /// Noise on the test shapes, fraction of each mode's largest reading.
        #[arg(long, default_value_t = 0.005)]
        shape_noise: f64,
        /// Noise on the test frequencies, relative.
        #[arg(long, default_value_t = 0.0005)]
        frequency_noise: f64,
        /// The smaller study (plate at half resolution, every third sensor set): seconds.
        #[arg(long)]
        quick: bool,
    },
    /// Update stiffness factors of element sets from test modes (CSV or UFF): localisation,
    /// then SB-EBE (or inverse eigensensitivity) on the selected sets, and the held-out check.
    ///
    /// Examples:
    ///   femu update plate.inp test.unv --sets r0,r1,r2,r3 --tuned 4
    ///   femu update plate.inp test.csv --sets left,right --method ies --json update.json
    #[command(verbatim_doc_comment)]
    Update {
        /// The model (`.inp`, or `.msh`/`.unv` with --young, --poisson, --density, --fix).
        model: PathBuf,
        /// The test modes (`.csv`, `.unv`).
        test: PathBuf,
        /// Candidate element sets (comma-separated); localisation selects among them.
        #[arg(long, value_delimiter = ',', required = true)]
        sets: Vec<String>,
        /// The first N test modes are tuned, the others held out (default: all but the last
        /// third).
        #[arg(long)]
        tuned: Option<usize>,
        /// sbebe or ies (inverse eigensensitivity).
        #[arg(long, default_value = "sbebe")]
        method: String,
        /// Update every candidate set instead of the localised ones.
        #[arg(long)]
        all: bool,
        /// Write localisation, iterations and the held-out check as JSON.
        #[arg(long)]
        json: Option<PathBuf>,
    },
}

/// A deck read, checked and assembled.
struct Loaded {
    model: femu_fem::model::Model,
    sys: femu_fem::assembly::SystemMatrices,
    mass: MassKind,
    /// The deck's `*FREQUENCY` step, if any.
    frequency: Option<femu_io::inp::FrequencyStep>,
}

/// Reads `path` (warnings to stderr unless quiet), builds the model and assembles `K` and `M`.
/// Whether `path` ends in one of `exts` (any case).
fn has_extension(path: &Path, exts: &[&str]) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| exts.iter().any(|x| e.eq_ignore_ascii_case(x)))
}

/// Material and constraints of a mesh-only model, from the command line.
#[derive(Clone, Default)]
struct MshOptions {
    young: Option<f64>,
    poisson: Option<f64>,
    density: Option<f64>,
    fix: Vec<String>,
}

static MSH: std::sync::OnceLock<MshOptions> = std::sync::OnceLock::new();

/// A Gmsh mesh (`.msh`) or the solids of a universal file (`.unv`/`.uff`, datasets 2411/2412)
/// with the command line's material and clamped sets.
fn load_msh(
    path: &Path,
    quiet: bool,
) -> Result<(femu_fem::model::Model, Option<femu_io::inp::FrequencyStep>), String> {
    let o = MSH.get().cloned().unwrap_or_default();
    let (Some(e), Some(nu), Some(rho)) = (o.young, o.poisson, o.density) else {
        return Err(format!(
            "{}: a mesh file has no material: give --young, --poisson and --density",
            path.display()
        ));
    };
    let (mesh, warnings) = if has_extension(path, &["unv", "uff"]) {
        let u = femu_io::uff::read_uff(path).map_err(|e| e.to_string())?;
        let (mesh, mut w) = u.to_mesh(path).map_err(|e| e.to_string())?;
        w.splice(0..0, u.warnings);
        (mesh, w)
    } else {
        let g = femu_io::gmsh::read_msh(path).map_err(|e| e.to_string())?;
        (g.mesh, g.warnings)
    };
    if !quiet {
        warnings.iter().for_each(|w| eprintln!("{w}"));
    }
    let mut model =
        femu_fem::model::Model::new(mesh).map_err(|e| format!("{}: {e}", path.display()))?;
    let mat = femu_fem::material::Material::isotropic("command line", e, nu, rho)
        .map_err(|e| e.to_string())?;
    model.set_material(None, mat).map_err(|e| e.to_string())?;
    for set in &o.fix {
        model
            .fix_set(set, &[0, 1, 2])
            .map_err(|e| format!("{}: --fix {set}: {e}", path.display()))?;
    }
    Ok((model, None))
}

fn load(path: &Path, lumped: bool, quiet: bool, pb: &ProgressBar) -> Result<Loaded, String> {
    let is_msh = has_extension(path, &["msh", "unv", "uff"]);
    let (model, frequency) = if is_msh {
        load_msh(path, quiet)?
    } else {
        let deck = femu_io::inp::read_inp(path).map_err(|e| e.to_string())?;
        if !quiet {
            deck.warnings.iter().for_each(|w| eprintln!("{w}"));
        }
        (deck.to_model().map_err(|e| e.to_string())?, deck.frequency)
    };
    pb.set_message("assembling K and M");
    let mass = if lumped {
        MassKind::Lumped
    } else {
        MassKind::Consistent
    };
    let sys = model.assemble(mass).map_err(|e| e.to_string())?;
    Ok(Loaded {
        model,
        sys,
        mass,
        frequency,
    })
}

/// Reads test modes (CSV, or a universal file `.unv`/`.uff`) and maps their sensors onto the model (errors name the test file).
fn load_test(
    path: &Path,
    loaded: &Loaded,
) -> Result<(femu_io::csv::TestData, femu_correlate::SensorLayout), String> {
    let is_uff = has_extension(path, &["unv", "uff"]);
    let is_json = has_extension(path, &["json"]);
    let test = if is_uff {
        femu_io::uff::read_uff(path)
            .and_then(|u| u.test_data(path))
            .map_err(|e| e.to_string())?
    } else if is_json {
        femu_io::json::read_test_json(path).map_err(|e| e.to_string())?
    } else {
        femu_io::csv::read_test_csv(path).map_err(|e| e.to_string())?
    };
    let layout = femu_correlate::SensorLayout::new(
        loaded.model.mesh(),
        &loaded.sys.dofs,
        test.sensors.clone(),
    )
    .map_err(|e| format!("{}: {e}", path.display()))?;
    Ok((test, layout))
}

/// The lowest `count` modes (default: twice the test modes plus 4, at most the DOFs).
fn lowest_for_test(
    loaded: &Loaded,
    count: Option<usize>,
    test_modes: usize,
    pb: &ProgressBar,
) -> Result<femu_sparse::eigen::Modes, String> {
    let sys = &loaded.sys;
    let count = count.unwrap_or(2 * test_modes + 4).min(sys.k.rows());
    pb.set_message(format!("solving {count} modes ({} DOF)", sys.k.rows()));
    eigs(
        &sys.k,
        &sys.m,
        Which::Lowest(count),
        &EigenParams::default(),
    )
    .map_err(|e| e.to_string())
}

/// Writes `value` as pretty JSON when a path is given.
fn write_json<T: Serialize>(path: Option<PathBuf>, value: &T) -> Result<(), String> {
    if let Some(path) = path {
        let text = serde_json::to_string_pretty(value).map_err(|e| e.to_string())?;
        std::fs::write(&path, text).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    Ok(())
}

/// Test modes from CSV (see `femu_io::csv`), correlated with the model's lowest modes.
fn correlate_cmd(
    model_path: &Path,
    test_path: &Path,
    count: Option<usize>,
    mac_threshold: f64,
    lumped: bool,
    json: Option<PathBuf>,
    quiet: bool,
) -> Result<(), String> {
    let pb = spinner(quiet, "reading the model");
    let loaded = load(model_path, lumped, quiet, &pb)?;
    let (test, layout) = load_test(test_path, &loaded)?;
    let modes = lowest_for_test(&loaded, count, test.modes.len(), &pb)?;
    pb.finish_and_clear();
    let options = femu_correlate::PairingOptions { mac_threshold };
    let report = femu_correlate::correlate(
        &femu_correlate::ModeSet::from_modes(&modes),
        &test.modes,
        &layout,
        &options,
    )
    .map_err(|e| e.to_string())?;
    if !quiet {
        println!(
            "{} test modes at {} sensors against {} model modes (MAC threshold {mac_threshold})",
            test.modes.len(),
            layout.len(),
            modes.values.len()
        );
        print!("{report}");
    }
    write_json(json, &report)
}

/// The a priori estimators for CSV test modes, expanded to the model's DOFs.
/// Expands measured shapes `ya` by `method` (the readings placed as they are when every DOF is
/// measured).
fn expand_test(
    sys: &femu_fem::assembly::SystemMatrices,
    layout: &femu_correlate::SensorLayout,
    lambdas: &[f64],
    ya: femu_sparse::faer::MatRef<'_, f64>,
    method: &str,
) -> Result<femu_sparse::faer::Mat<f64>, String> {
    use femu_correlate::expansion::{Expander, place_measured};
    Ok(match layout.measured_dofs() {
        // every DOF measured: the readings placed on their DOFs, nothing to expand
        Some(dofs) if dofs.len() == sys.dofs.free_count() => {
            place_measured(sys.k.rows(), &dofs, ya).map_err(|e| e.to_string())?
        }
        _ => {
            let exp = Expander::new(&sys.k, &sys.m, layout).map_err(|e| e.to_string())?;
            match method {
                "static" => exp.static_(ya),
                "dynamic" => exp.dynamic(lambdas, ya),
                "min-residual" => exp.minimum_residual(lambdas, ya),
                "mdre" => {
                    // free-free models need the shift (MATH.md); harmless when restrained
                    let shift = 1e-3 * lambdas.iter().copied().fold(0.0, f64::max);
                    exp.mdre(lambdas, ya, 1.0, shift)
                }
                other => {
                    return Err(format!(
                        "expansion {other}: use static, dynamic, min-residual or mdre"
                    ));
                }
            }
            .map_err(|e| e.to_string())?
        }
    })
}

#[allow(clippy::too_many_arguments)]
fn expand_cmd(
    model_path: &Path,
    test_path: &Path,
    method: &str,
    lumped: bool,
    vtu: Option<PathBuf>,
    study: Option<PathBuf>,
    json: Option<PathBuf>,
    quiet: bool,
) -> Result<(), String> {
    let pb = spinner(quiet, "reading the model");
    let loaded = load(model_path, lumped, quiet, &pb)?;
    let (test, layout) = load_test(test_path, &loaded)?;
    let sys = &loaded.sys;
    let lambdas = test.modes.eigenvalues();
    pb.set_message(format!("expanding {} test modes ({method})", lambdas.len()));
    let x = expand_test(sys, &layout, &lambdas, test.modes.shapes.as_ref(), method)?;
    let est = femu_correlate::Estimator::new(&sys.k, &sys.m).map_err(|e| e.to_string())?;
    let (norms, _) = est
        .residual_norms(&lambdas, x.as_ref())
        .map_err(|e| e.to_string())?;
    if let Some(path) = &vtu {
        let nn = loaded.model.mesh().node_count();
        let fields: Vec<(String, Vec<f64>)> = (0..x.ncols())
            .map(|j| {
                let mut v = vec![0.0; 3 * nn];
                for f in 0..x.nrows() {
                    v[sys.dofs.full_of_free(f)] = x[(f, j)];
                }
                (
                    format!(
                        "test mode {} expanded ({:.2} Hz)",
                        j + 1,
                        test.modes.frequencies_hz[j]
                    ),
                    v,
                )
            })
            .collect();
        let points: Vec<femu_io::vtk::PointField<'_>> = fields
            .iter()
            .map(|(name, v)| femu_io::vtk::PointField {
                name,
                components: 3,
                values: v,
            })
            .collect();
        femu_io::vtk::write_vtu(loaded.model.mesh(), &points, &[], path)
            .map_err(|e| e.to_string())?;
    }
    let mut points = Vec::new();
    if let Some(dir) = &study {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        let mut nodes: Vec<u64> = layout.sensors().iter().map(|s| s.node).collect();
        nodes.sort_unstable();
        nodes.dedup();
        if nodes.len() < 3 {
            return Err("--study needs sensors on at least 3 nodes".into());
        }
        let tri = femu_correlate::SensorLayout::triaxial(loaded.model.mesh(), &sys.dofs, &nodes)
            .map_err(|e| e.to_string())?;
        let order = femu_correlate::placement::efi_removal_order(&tri, x.as_ref())
            .map_err(|e| e.to_string())?;
        let removal: Vec<u64> = order.into_iter().take(nodes.len() - 2).collect();
        pb.set_message(format!("sensor-removal study over {} nodes", nodes.len()));
        use femu_correlate::study::Method;
        points = femu_correlate::study::sensor_removal_study(
            &sys.k,
            &sys.m,
            loaded.model.mesh(),
            &sys.dofs,
            &lambdas,
            x.as_ref(),
            &nodes,
            &removal,
            &[Method::Static, Method::Dynamic, Method::MinimumResidual],
            None,
            1,
        )
        .map_err(|e| e.to_string())?;
        let svg = femu_correlate::study::study_svg(&points);
        for (name, text) in [
            ("study.csv", femu_correlate::study::study_csv(&points)),
            ("study.svg", svg.clone()),
        ] {
            let p = dir.join(name);
            std::fs::write(&p, text).map_err(|e| format!("{}: {e}", p.display()))?;
        }
        femu_io::png::write_png(&svg, 2.0, dir.join("study.png")).map_err(|e| e.to_string())?;
    }
    pb.finish_and_clear();
    if !quiet {
        println!(
            "{} test modes at {} sensors, {method} expansion to {} DOF",
            lambdas.len(),
            layout.len(),
            sys.k.rows()
        );
        println!("| test | f (Hz) | rho_M (s^-2) | rho_2 | a model frequency within (Hz) |");
        println!("|---|---|---|---|---|");
        for (j, n) in norms.iter().enumerate() {
            let (lo, hi) = n.frequency_interval_hz();
            println!(
                "| {} | {:.2} | {:.4e} | {:.4e} | {lo:.1} .. {hi:.1} |",
                j + 1,
                test.modes.frequencies_hz[j],
                n.rho_m,
                n.rho_2
            );
        }
        if let Some(dir) = &study {
            println!(
                "sensor-removal study: {} points in {}",
                points.len(),
                dir.display()
            );
        }
    }
    #[derive(Serialize)]
    struct Out<'a> {
        method: &'a str,
        rho_m: Vec<f64>,
        rho_2: Vec<f64>,
        study: &'a [femu_correlate::study::StudyPoint],
    }
    write_json(
        json,
        &Out {
            method,
            rho_m: norms.iter().map(|n| n.rho_m).collect(),
            rho_2: norms.iter().map(|n| n.rho_2).collect(),
            study: &points,
        },
    )
}

fn estimate_cmd(
    model_path: &Path,
    test_path: &Path,
    expansion: &str,
    count: Option<usize>,
    lumped: bool,
    json: Option<PathBuf>,
    quiet: bool,
) -> Result<(), String> {
    let pb = spinner(quiet, "reading the model");
    let loaded = load(model_path, lumped, quiet, &pb)?;
    let (test, layout) = load_test(test_path, &loaded)?;
    let sys = &loaded.sys;
    let lambdas = test.modes.eigenvalues();
    pb.set_message(format!(
        "expanding {} test modes ({expansion})",
        lambdas.len()
    ));
    let x = expand_test(
        sys,
        &layout,
        &lambdas,
        test.modes.shapes.as_ref(),
        expansion,
    )?;
    let modes = lowest_for_test(&loaded, count, test.modes.len(), &pb)?;
    let set = femu_correlate::ModeSet::from_modes(&modes);
    let report = femu_correlate::correlate(&set, &test.modes, &layout, &Default::default())
        .map_err(|e| e.to_string())?;
    let eb =
        femu_correlate::element_bounds(&loaded.model, loaded.mass).map_err(|e| e.to_string())?;
    let spectrum = femu_correlate::ModelSpectrum {
        values: modes.values.clone(),
        complete: false,
        lambda_max: eb.lambda_max_upper,
        mu_min: Some(eb.mu_min_lower),
        identity_mass: false,
    };
    let paired: Vec<Option<usize>> = (0..test.modes.len())
        .map(|t| report.pairing.of_test(t).map(|p| p.model))
        .collect();
    let out = femu_correlate::estimate(
        &sys.k,
        &sys.m,
        &lambdas,
        x.as_ref(),
        &spectrum,
        Some(&set),
        &paired,
    )
    .map_err(|e| e.to_string())?;
    pb.finish_and_clear();
    if !quiet {
        println!(
            "{} test modes, {} sensors, {expansion} expansion to {} DOF",
            lambdas.len(),
            layout.len(),
            sys.k.rows()
        );
        println!(
            "| test | f test (Hz) | rho_M (s^-2) | rho_2 | a model mode lies in (Hz) | paired model (Hz) |"
        );
        println!("|---|---|---|---|---|---|");
        let f_model = set.frequencies_hz();
        for a in &out {
            let pm = a.paired_model.map_or("-".to_string(), |j| {
                format!("{} ({:.1})", j + 1, f_model[j])
            });
            println!(
                "| {} | {:.1} | {:.4e} | {:.4e} | {:.1} .. {:.1} | {pm} |",
                a.test + 1,
                test.modes.frequencies_hz[a.test],
                a.norms.rho_m,
                a.norms.rho_2,
                a.frequency_interval_hz.0,
                a.frequency_interval_hz.1
            );
        }
    }
    write_json(json, &out)
}

/// What `femu modes --json` writes.
#[derive(Serialize)]
struct ModesJson {
    model: String,
    dofs: usize,
    mass: &'static str,
    frequencies_hz: Vec<f64>,
    eigenvalues: Vec<f64>,
    residuals: Vec<f64>,
    sturm_verified: bool,
    sturm_count: usize,
    sturm_upper: f64,
    seconds: f64,
}

fn spinner(quiet: bool, msg: &str) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::new_spinner();
    pb.set_style(
        ProgressStyle::with_template("{spinner} {msg} ({elapsed})").expect("valid template"),
    );
    pb.set_message(msg.to_string());
    pb.enable_steady_tick(Duration::from_millis(200));
    pb
}

fn modes(
    model_path: &Path,
    count: Option<usize>,
    shift: Option<f64>,
    band: Option<Vec<f64>>,
    lumped: bool,
    json: Option<PathBuf>,
    vtu: Option<PathBuf>,
    quiet: bool,
) -> Result<(), String> {
    use femu_correlate::modes::eigenvalue_of_hz;
    let start = std::time::Instant::now();
    let pb = spinner(quiet, "reading the model");
    let loaded = load(model_path, lumped, quiet, &pb)?;
    let (model, sys) = (&loaded.model, &loaded.sys);
    pb.set_message(format!("solving ({} DOF)", sys.k.rows()));
    let count = count.or(loaded.frequency.map(|f| f.count)).unwrap_or(10);
    if count == 0 {
        return Err("--count must be at least 1".into());
    }
    let which = match (shift, band) {
        (Some(hz), _) => {
            if !(hz.is_finite() && hz >= 0.0) {
                return Err(format!("--shift {hz} Hz must be a non-negative frequency"));
            }
            Which::Nearest {
                shift: eigenvalue_of_hz(hz),
                count,
            }
        }
        (None, Some(b)) => {
            if !(b[0].is_finite() && b[1].is_finite() && 0.0 <= b[0] && b[0] < b[1]) {
                return Err(format!("--band {} {}: need 0 <= LO < HI (Hz)", b[0], b[1]));
            }
            Which::Band {
                lo: eigenvalue_of_hz(b[0]),
                hi: eigenvalue_of_hz(b[1]),
            }
        }
        (None, None) => Which::Lowest(count),
    };
    let result = eigs(&sys.k, &sys.m, which, &EigenParams::default()).map_err(|e| e.to_string())?;
    pb.finish_and_clear();
    let f = result.frequencies_hz();
    let mass_name = if lumped { "lumped" } else { "consistent" };
    if !quiet {
        println!("{} DOF, {mass_name} mass, {} modes", sys.k.rows(), f.len());
        println!("| mode | f (Hz) | lambda (s^-2) | residual |");
        println!("|---|---|---|---|");
        for (j, (fj, (l, r))) in f
            .iter()
            .zip(result.values.iter().zip(&result.residuals))
            .enumerate()
        {
            println!("| {} | {:.6} | {:.6e} | {:.1e} |", j + 1, fj, l, r);
        }
        println!(
            "Sturm check: {} eigenvalues below {:.6e} s^-2, {} returned: {}",
            result.sturm.count,
            result.sturm.upper,
            result.sturm.returned,
            if result.sturm.verified() {
                "verified"
            } else {
                "FAILED"
            }
        );
    }
    if let Some(path) = vtu {
        let mut shapes = Vec::with_capacity(f.len());
        for j in 0..f.len() {
            let col: Vec<f64> = result.vectors.col(j).iter().copied().collect();
            shapes.push(sys.dofs.expand(&col).map_err(|e| e.to_string())?);
        }
        let names: Vec<String> = f
            .iter()
            .enumerate()
            .map(|(j, fj)| format!("mode {} ({fj:.3} Hz)", j + 1))
            .collect();
        let fields: Vec<femu_io::vtk::PointField<'_>> = shapes
            .iter()
            .zip(&names)
            .map(|(v, n)| femu_io::vtk::PointField {
                name: n,
                components: 3,
                values: v,
            })
            .collect();
        femu_io::vtk::write_vtu(model.mesh(), &fields, &[], &path).map_err(|e| e.to_string())?;
    }
    write_json(
        json,
        &ModesJson {
            model: model_path.display().to_string(),
            dofs: sys.k.rows(),
            mass: mass_name,
            frequencies_hz: f,
            eigenvalues: result.values.clone(),
            residuals: result.residuals.clone(),
            sturm_verified: result.sturm.verified(),
            sturm_count: result.sturm.count,
            sturm_upper: result.sturm.upper,
            seconds: start.elapsed().as_secs_f64(),
        },
    )
}

fn demo_cmd(
    out: PathBuf,
    shape_noise: f64,
    frequency_noise: f64,
    quick: bool,
    quiet: bool,
) -> Result<(), String> {
    for (what, v) in [
        ("shape noise", shape_noise),
        ("frequency noise", frequency_noise),
    ] {
        if !(0.0..0.5).contains(&v) {
            return Err(format!("{what} {v} must be in [0, 0.5)"));
        }
    }
    let base = if quick {
        femu::demo::DemoOptions::quick()
    } else {
        femu::demo::DemoOptions::default()
    };
    let opts = femu::demo::DemoOptions {
        out,
        shape_noise,
        frequency_noise,
        ..base
    };
    let pb = spinner(quiet, "building the plate");
    let report = femu::demo::run_demo(&opts, |line| pb.set_message(line.to_string()))
        .map_err(|e| e.to_string())?;
    pb.finish_and_clear();
    if !quiet {
        let md = opts.out.join("report.md");
        print!(
            "{}",
            std::fs::read_to_string(&md).map_err(|e| format!("{}: {e}", md.display()))?
        );
        println!("\nreport written to {}:", opts.out.display());
        for f in &report.files {
            println!("  {}", f.display());
        }
    }
    Ok(())
}

#[derive(Serialize)]
struct UpdateJson<'a> {
    localisation: &'a femu_update::Localisation,
    result: &'a femu_update::UpdateResult,
    truth_check: &'a femu_update::TruthCheck,
}

#[allow(clippy::too_many_arguments)]
fn update_cmd(
    model_path: &Path,
    test_path: &Path,
    sets: &[String],
    tuned: Option<usize>,
    method: &str,
    all: bool,
    json: Option<PathBuf>,
    quiet: bool,
) -> Result<(), String> {
    use femu_update::prelude::*;
    if !matches!(method, "sbebe" | "ies") {
        return Err(format!("--method {method}: expected sbebe or ies"));
    }
    let pb = spinner(quiet, "reading the model");
    let loaded = load(model_path, false, quiet, &pb)?;
    let (data, layout) = load_test(test_path, &loaded)?;
    let n_test = data.modes.len();
    let tuned = tuned.unwrap_or((2 * n_test).div_ceil(3)).min(n_test);
    if tuned == 0 {
        return Err("--tuned must be at least 1".into());
    }
    let model = &loaded.model;
    // Abaqus names are case-insensitive (the reader keeps them upper case)
    let names: Vec<&str> = sets
        .iter()
        .map(|s| {
            model
                .mesh()
                .element_sets()
                .keys()
                .find(|k| k.eq_ignore_ascii_case(s))
                .map(|k| k.as_str())
                .ok_or_else(|| format!("{}: no element set {s}", model_path.display()))
        })
        .collect::<Result<_, _>>()?;
    let subset = femu_correlate::TestModes::new(
        data.modes.frequencies_hz[..tuned].to_vec(),
        None,
        data.modes.shapes.as_ref().subcols(0, tuned).to_owned(),
    )
    .map_err(|e| e.to_string())?;
    pb.set_message("localising");
    let candidates =
        UpdateModel::from_element_sets(model, &names, MassKind::Consistent, Corrections::Stiffness)
            .map_err(|e| e.to_string())?;
    let loc = localise_expanded(&candidates, &layout, &subset, &SelectionRule::default())
        .map_err(|e| e.to_string())?;
    let chosen: Vec<&str> = if all {
        names.clone()
    } else {
        loc.selected.iter().map(|g| names[*g]).collect()
    };
    let mut nominal = candidates;
    let count = n_test + 10;
    let before =
        model_modes(&mut nominal, count, &Default::default()).map_err(|e| e.to_string())?;
    let mut up = UpdateModel::from_element_sets(
        model,
        &chosen,
        MassKind::Consistent,
        Corrections::Stiffness,
    )
    .map_err(|e| e.to_string())?;
    let log = |it: &femu_update::Iteration| {
        pb.set_message(format!(
            "iteration {}: objective {:.4e}",
            it.iteration, it.objective
        ))
    };
    let result = if method == "sbebe" {
        let o = SbebeOptions {
            test_error: Some(1e-3),
            ..Default::default()
        };
        sb_ebe(&mut up, &layout, &subset, &o, log)
    } else {
        inverse_eigensensitivity(&mut up, &layout, &subset, &Default::default(), log)
    }
    .map_err(|e| e.to_string())?;
    let after = model_modes(&mut up, count, &Default::default()).map_err(|e| e.to_string())?;
    let tuned_idx: Vec<usize> = (0..tuned).collect();
    let check = truth_check(
        &before,
        &after,
        &data.modes,
        &layout,
        &tuned_idx,
        &Default::default(),
    )
    .map_err(|e| e.to_string())?;
    pb.finish_and_clear();
    if !quiet {
        println!(
            "Localisation ({} candidate sets, tuned on test modes 1-{tuned}):\n{loc}",
            names.len()
        );
        println!("{result}");
        println!("{check}");
    }
    write_json(
        json,
        &UpdateJson {
            localisation: &loc,
            result: &result,
            truth_check: &check,
        },
    )
}

fn matrices_cmd(model_path: &Path, out: &Path, lumped: bool, quiet: bool) -> Result<(), String> {
    let pb = spinner(quiet, "reading the model");
    let loaded = load(model_path, lumped, quiet, &pb)?;
    let sys = &loaded.sys;
    let name = |suffix: &str| {
        let mut p = out.as_os_str().to_owned();
        p.push(suffix);
        PathBuf::from(p)
    };
    let (k, m, d) = (name("_K.mtx"), name("_M.mtx"), name("_dofs.csv"));
    pb.set_message("writing MatrixMarket files");
    femu_sparse::mtx::write_matrix_market(&k, &sys.k, true).map_err(|e| e.to_string())?;
    femu_sparse::mtx::write_matrix_market(&m, &sys.m, true).map_err(|e| e.to_string())?;
    let mut csv = String::from("row,node,component\n");
    for f in 0..sys.dofs.free_count() {
        let full = sys.dofs.full_of_free(f);
        csv.push_str(&format!(
            "{},{},{}\n",
            f + 1,
            loaded.model.mesh().node_id(full / 3),
            ["x", "y", "z"][full % 3]
        ));
    }
    std::fs::write(&d, csv).map_err(|e| format!("{}: {e}", d.display()))?;
    pb.finish_and_clear();
    if !quiet {
        println!(
            "{} DOF, nnz(K) = {}: {}, {}, {}",
            sys.k.rows(),
            sys.k.nnz(),
            k.display(),
            m.display(),
            d.display()
        );
    }
    Ok(())
}

/// A study file (`femu run`).
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct StudyFile {
    model: PathBuf,
    test: PathBuf,
    #[serde(default)]
    material: Option<StudyMaterial>,
    #[serde(default)]
    fix: Vec<String>,
    #[serde(default)]
    lumped: bool,
    #[serde(default)]
    pairing: Option<StudyPairing>,
    #[serde(default)]
    expansion: Option<StudyExpansion>,
    #[serde(default)]
    update: Option<StudyUpdate>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct StudyMaterial {
    young: f64,
    poisson: f64,
    density: f64,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct StudyPairing {
    mac_threshold: f64,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct StudyExpansion {
    method: String,
    #[serde(default)]
    study: bool,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct StudyUpdate {
    sets: Vec<String>,
    #[serde(default)]
    tuned: Option<usize>,
    #[serde(default = "default_update_method")]
    method: String,
    #[serde(default)]
    all: bool,
}

fn default_update_method() -> String {
    "sbebe".into()
}

fn run_cmd(study: &Path, out: &Path, quiet: bool) -> Result<(), String> {
    let text = std::fs::read_to_string(study).map_err(|e| format!("{}: {e}", study.display()))?;
    let s: StudyFile = toml::from_str(&text).map_err(|e| {
        let line = e
            .span()
            .map_or(0, |sp| text[..sp.start].matches('\n').count() + 1);
        format!("{}:{line}: {}", study.display(), e.message())
    })?;
    let base = study.parent().unwrap_or(Path::new("."));
    let model = base.join(&s.model);
    let test = base.join(&s.test);
    if let Some(m) = &s.material {
        // a .msh model takes its material and constraints from the study file
        let _ = MSH.set(MshOptions {
            young: Some(m.young),
            poisson: Some(m.poisson),
            density: Some(m.density),
            fix: s.fix.clone(),
        });
    }
    std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    let threshold = s.pairing.as_ref().map_or(0.8, |p| p.mac_threshold);
    if !quiet {
        println!("# correlation");
    }
    correlate_cmd(
        &model,
        &test,
        None,
        threshold,
        s.lumped,
        Some(out.join("correlation.json")),
        quiet,
    )?;
    let method = s
        .expansion
        .as_ref()
        .map_or("dynamic".to_string(), |e| e.method.clone());
    if !quiet {
        println!("\n# estimators ({method} expansion)");
    }
    estimate_cmd(
        &model,
        &test,
        &method,
        None,
        s.lumped,
        Some(out.join("estimate.json")),
        quiet,
    )?;
    if let Some(e) = &s.expansion {
        if !quiet {
            println!("\n# expansion");
        }
        let study_dir = e.study.then(|| out.join("figure1"));
        expand_cmd(
            &model,
            &test,
            &e.method,
            s.lumped,
            Some(out.join("expanded.vtu")),
            study_dir,
            Some(out.join("expansion.json")),
            quiet,
        )?;
    }
    if let Some(u) = &s.update {
        if !quiet {
            println!("\n# updating");
        }
        update_cmd(
            &model,
            &test,
            &u.sets,
            u.tuned,
            &u.method,
            u.all,
            Some(out.join("update.json")),
            quiet,
        )?;
    }
    if !quiet {
        println!("\nresults written to {}", out.display());
    }
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    if cli.young.is_some() || cli.poisson.is_some() || cli.density.is_some() || !cli.fix.is_empty()
    {
        let _ = MSH.set(MshOptions {
            young: cli.young,
            poisson: cli.poisson,
            density: cli.density,
            fix: cli.fix.clone(),
        });
    }
    let result = match cli.command {
        Command::Estimate {
            model,
            test,
            expansion,
            count,
            lumped,
            json,
        } => estimate_cmd(&model, &test, &expansion, count, lumped, json, cli.quiet),
        Command::Correlate {
            model,
            test,
            count,
            mac_threshold,
            lumped,
            json,
        } => correlate_cmd(&model, &test, count, mac_threshold, lumped, json, cli.quiet),
        Command::Modes {
            model,
            count,
            shift,
            band,
            lumped,
            json,
            vtu,
        } => modes(&model, count, shift, band, lumped, json, vtu, cli.quiet),
        Command::Expand {
            model,
            test,
            method,
            lumped,
            vtu,
            study,
            json,
        } => expand_cmd(&model, &test, &method, lumped, vtu, study, json, cli.quiet),
        Command::Run { study, out } => run_cmd(&study, &out, cli.quiet),
        Command::Matrices { model, out, lumped } => matrices_cmd(&model, &out, lumped, cli.quiet),
        Command::Demo {
            out,
            shape_noise,
            frequency_noise,
            quick,
        } => demo_cmd(out, shape_noise, frequency_noise, quick, cli.quiet),
        Command::Update {
            model,
            test,
            sets,
            tuned,
            method,
            all,
            json,
        } => update_cmd(&model, &test, &sets, tuned, &method, all, json, cli.quiet),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
