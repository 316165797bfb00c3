//! `femu update`: localisation, updating and the held-out truth check.

use crate::common::{Inputs, load_model, spinner, write_json};
use crate::error::CliError;
use clap::Args;
use femu::study::updating::{UpdateRequest, update_loaded};
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
    #[command(flatten)]
    pub request: UpdateRequest,
    /// Write localisation, iterations and the held-out check as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
    #[command(flatten)]
    pub inputs: Inputs,
}

/// Runs `femu update`.
///
/// # Errors
/// Reading, unknown sets, `--tuned 0`, and the updating errors.
pub fn run(a: &UpdateArgs, quiet: bool) -> Result<(), CliError> {
    let pb = spinner(quiet, "reading the model");
    let eigen = a.inputs.engine.eigen()?;
    let loaded = load_model(&a.model, &a.inputs.model, false, quiet, &pb)?;
    let test = crate::common::load_test(&a.test, &loaded, &a.inputs.test, quiet)?;
    crate::common::warn(quiet, &a.request.unused());
    let tuned = a.request.tuned_of(test.data.modes.len());
    pb.set_message("localising and updating");
    let study = update_loaded(&loaded, &test, &a.request, &eigen, None, |it| {
        pb.set_message(format!(
            "iteration {}: objective {:.4e}",
            it.iteration, it.objective
        ))
    })?;
    pb.finish_and_clear();
    if !quiet {
        println!("Tuned on test modes 1-{tuned}.\n\n{study}");
    }
    write_json(a.json.as_deref(), &study)
}
