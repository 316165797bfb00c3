//! `femu update`: localisation, updating and the held-out truth check.

use crate::common::{MeshOptions, load_model, spinner, write_json};
use crate::error::CliError;
use clap::Args;
use femu::study::load::load_test;
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
    /// The model (`.inp`, or `.msh`/`.unv` with --young, --poisson, --density, --fix).
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
    let test = load_test(&a.test, &loaded)?;
    let n_test = test.data.modes.len();
    let tuned = a.tuned.unwrap_or((2 * n_test).div_ceil(3)).min(n_test);
    if tuned == 0 {
        return Err(CliError::Usage("--tuned must be at least 1".into()));
    }
    let names = resolve_sets(&loaded, &a.sets)?;
    let names: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
    let options = UpdateStudyOptions {
        method: a.method,
        all: a.all,
        ..UpdateStudyOptions::new(tuned, n_test)
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
        println!("{}", study.result);
        println!("{}", study.truth_check);
    }
    write_json(a.json.as_deref(), &study)
}
