//! `femu frf`: a test's measured FRFs against the model's at the same DOFs and lines.

use crate::common::{EngineArgs, ModelArgs, load_model, spinner, write_json};
use crate::error::CliError;
use clap::Args;
use femu::study::frf::{FrfRequest, frf_correlation_with};
use std::path::PathBuf;

/// Correlate measured FRFs (universal file dataset 58) with the model's: FRAC per function, CSAC
/// and CSF per line, by modal superposition with damping and residual flexibility.
///
/// Examples:
///   femu frf beam.inp frf.uff
///   femu frf beam.inp frf.uff --loss-factor 0.02 --json frf.json --csv model_frf.csv
#[derive(Args, Debug)]
#[command(verbatim_doc_comment)]
pub struct FrfArgs {
    /// The model (`.inp`, Nastran `.bdf`/`.dat`/`.nas`, or `.msh`/`.unv` with --young, --poisson,
    /// --density, --fix).
    pub model: PathBuf,
    /// The measured FRFs: a universal file with dataset 58 (function type 4) whose response and
    /// reference nodes are the model's node ids.
    pub test: PathBuf,
    #[command(flatten)]
    pub request: FrfRequest,
    /// Lumped (diagonal) mass instead of consistent.
    #[arg(long)]
    pub lumped: bool,
    /// Write the correlation (FRAC per function, CSAC and CSF per line) as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Write the model's FRFs at the test's lines as CSV (hz, response, reference, re, im).
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// Write the model's FRFs as a universal file (dataset 58, the test's DOFs, lines and kinds).
    #[arg(long)]
    pub uff: Option<PathBuf>,
    /// Write one chart per FRF (magnitude and phase, measured over model; SVG and PNG) into this
    /// folder.
    #[arg(long, value_name = "DIR")]
    pub charts: Option<PathBuf>,
    #[command(flatten)]
    pub model_args: ModelArgs,
    #[command(flatten)]
    pub engine: EngineArgs,
}

/// Runs `femu frf`.
///
/// # Errors
/// Reading, assembly and eigensolver errors; a file without FRFs or with FRFs femu cannot
/// compare.
pub fn run(a: &FrfArgs, quiet: bool) -> Result<(), CliError> {
    let pb = spinner(quiet, "reading the model");
    let eigen = a.engine.eigen()?;
    let loaded = load_model(&a.model, &a.model_args, a.lumped, quiet, &pb)?;
    pb.set_message("solving for the model's modes and FRFs");
    let result = frf_correlation_with(&loaded, &a.test, &a.request, &eigen, |line| {
        pb.set_message(line.to_string())
    })?;
    pb.finish_and_clear();
    crate::common::warn(quiet, &result.notes);
    if !quiet {
        print!("{result}");
    }
    write_json(a.json.as_deref(), &result)?;
    if let Some(path) = &a.csv {
        std::fs::write(path, result.model_csv())
            .map_err(|e| femu::study::StudyError::file(path, e))?;
    }
    if let Some(path) = &a.uff {
        femu::io::uff::write_uff(path, &result.model_uff())?;
    }
    if let Some(dir) = &a.charts {
        result.write_charts(dir)?;
    }
    Ok(())
}
