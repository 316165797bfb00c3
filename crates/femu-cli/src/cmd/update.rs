//! `femu update`: localisation, updating and the held-out truth check.

use crate::common::{MeshOptions, load_model, spinner, write_json};
use crate::error::CliError;
use clap::Args;
use femu::study::updating::{UpdateStudyOptions, localise_update_check, resolve_sets};
use femu::update::UpdateMethod;
use std::path::PathBuf;

/// Update stiffness factors of element sets from test modes: localisation, then SB-EBE (or
/// inverse eigensensitivity) on the selected sets, and the held-out check.
///
/// Examples:
///   femu update plate.inp test.unv --sets r0,r1,r2,r3 --tuned 4
///   femu update plate.inp test.csv --sets left,right --method ies --json update.json
#[derive(Args, Debug)]
#[command(verbatim_doc_comment)]
pub struct UpdateArgs {
    /// The model (`.inp`, Nastran `.bdf`/`.dat`/`.nas`, or `.msh`/`.unv` with --young, --poisson,
    /// --density, --fix).
    pub model: PathBuf,
    /// The test modes (`.unv`/`.uff`, `.json` or `.csv`).
    pub test: PathBuf,
    /// Candidate element sets (comma-separated); localisation selects among them.
    #[arg(long, value_delimiter = ',', required = true)]
    pub sets: Vec<String>,
    /// The first N test modes are tuned, the others held out (default: all but the last third).
    #[arg(long)]
    pub tuned: Option<usize>,
    /// The updating method.
    #[arg(long, value_enum, default_value = "sbebe")]
    pub method: UpdateMethod,
    /// Update every candidate set instead of the localised ones.
    #[arg(long)]
    pub all: bool,
    /// The test's frequency uncertainty, percent (one standard deviation; default: 0.1 %,
    /// assumed and said so). The truth check's tolerance is three of it.
    #[arg(long, value_name = "PERCENT")]
    pub frequency_uncertainty: Option<f64>,
    /// The test's shape uncertainty, percent of each mode's largest reading (default: 1 %).
    #[arg(long, value_name = "PERCENT")]
    pub shape_uncertainty: Option<f64>,
    /// Inverse eigensensitivity fits the shapes at the sensors as well as the frequencies
    /// (eigenvector derivatives); recommended when the model is not the structure.
    #[arg(long)]
    pub shapes: bool,
    /// SB-EBE's trust in the measured shapes: the weight of the test-error term of the expansion
    /// (default 1e-3; smaller trusts the test more).
    #[arg(long, value_name = "WEIGHT")]
    pub test_error: Option<f64>,
    /// Skip the estimate of the model's discretisation error (the same mesh with quadratic
    /// elements, solved once).
    #[arg(long)]
    pub no_discretisation: bool,
    /// Write localisation, iterations and the held-out check as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

/// Runs `femu update`.
///
/// # Errors
/// Reading, unknown sets, `--tuned 0`, and the updating errors.
pub fn run(a: &UpdateArgs, mesh: &MeshOptions, quiet: bool) -> Result<(), CliError> {
    let pb = spinner(quiet, "reading the model");
    let loaded = load_model(&a.model, mesh, false, quiet, &pb)?;
    let test = crate::common::load_test(&a.test, &loaded, mesh, quiet)?;
    let n_test = test.data.modes.len();
    let tuned = a.tuned.unwrap_or((2 * n_test).div_ceil(3)).min(n_test);
    if tuned == 0 {
        return Err(CliError::Usage("--tuned must be at least 1".into()));
    }
    let names = resolve_sets(&loaded, &a.sets)?;
    let names: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
    if a.shapes && a.method != UpdateMethod::InverseEigensensitivity {
        crate::common::warn(
            quiet,
            &["--shapes applies to --method ies: SB-EBE always uses the shapes".into()],
        );
    }
    let uncertainty =
        femu::update::TestUncertainty::from_percent(a.frequency_uncertainty, a.shape_uncertainty)?;
    let defaults = UpdateStudyOptions::new(tuned, n_test);
    let options = UpdateStudyOptions {
        method: a.method,
        all: a.all,
        shapes: a.shapes,
        uncertainty,
        test_error: a.test_error.or(defaults.test_error),
        discretisation: !a.no_discretisation,
        ..defaults
    };
    pb.set_message("localising and updating");
    let study = localise_update_check(
        &loaded.model,
        &names,
        &test.layout,
        &test.data.modes,
        None,
        Some((&loaded.asm, &loaded.sys)),
        &options,
        |it| {
            pb.set_message(format!(
                "iteration {}: objective {:.4e}",
                it.iteration, it.objective
            ))
        },
    )?;
    pb.finish_and_clear();
    if !quiet {
        println!(
            "Localisation ({} candidate sets, tuned on test modes 1-{tuned}):\n{}",
            names.len(),
            study.localisation
        );
        println!("{}", study.reach);
        println!("{}", study.result);
        if let Some(d) = &study.discretisation {
            println!(
                "{}",
                femu::study::discretisation::table(d, &study.truth_check)
            );
        }
        println!("{}", study.truth_check);
    }
    write_json(a.json.as_deref(), &study)
}
