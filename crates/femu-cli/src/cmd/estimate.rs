//! `femu estimate`: the paper's a priori estimators for test modes, after expansion.

use crate::common::{Inputs, load_model, spinner, write_json};
use crate::error::CliError;
use clap::Args;
use femu::correlate::Method;
use femu::study::estimate::{EstimateOptions, estimate_loaded, table2_legend};
use femu::study::study_file::PairingSection;
use std::path::PathBuf;

/// The a priori estimators of the paper for test modes: rho_M, rho_2, the frequency interval
/// that holds a model mode, and every bound, after expanding the test shapes.
///
/// Examples:
///   femu estimate plate.inp test.unv
///   femu estimate plate.inp test.csv --expansion static --json estimate.json
#[derive(Args, Debug)]
#[command(verbatim_doc_comment)]
pub struct EstimateArgs {
    /// The model (`.inp`, Nastran `.bdf`/`.dat`/`.nas`, or `.msh`/`.unv` with --young, --poisson,
    /// --density, --fix).
    pub model: PathBuf,
    /// The test modes (`.unv`/`.uff`, `.json` or `.csv`).
    pub test: PathBuf,
    /// Expansion of the test shapes: static (Guyan), dynamic, serep:M (the model's lowest M
    /// modes), min-residual or mdre.
    #[arg(
        long,
        value_parser = crate::common::parse_method,
        default_value = "dynamic",
        value_name = "static|dynamic|serep:M|min-residual|mdre"
    )]
    pub expansion: Method,
    /// Model modes computed for the comparison (default: twice the test modes plus 4).
    #[arg(long)]
    pub count: Option<usize>,
    /// Lumped (diagonal) mass instead of consistent.
    #[arg(long)]
    pub lumped: bool,
    /// Write the assessments (norms, interval, bounds with what they bound) as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
    #[command(flatten)]
    pub pairing: PairingSection,
    #[command(flatten)]
    pub inputs: Inputs,
}

/// Runs `femu estimate`.
///
/// # Errors
/// Reading, assembly, expansion, eigensolver and estimator errors.
pub fn run(a: &EstimateArgs, quiet: bool) -> Result<(), CliError> {
    let pb = spinner(quiet, "reading the model");
    let options = EstimateOptions {
        expansion: a.expansion,
        pairing: a.pairing.options(),
        count: a.count,
        eigen: a.inputs.engine.eigen()?,
    };
    let loaded = load_model(&a.model, &a.inputs.model, a.lumped, quiet, &pb)?;
    let test = crate::common::load_test(&a.test, &loaded, &a.inputs.test, quiet)?;
    let run = estimate_loaded(&loaded, &test, &options, |line| {
        pb.set_message(line.to_string())
    })?;
    pb.finish_and_clear();
    let out = &run.result;
    if !quiet {
        println!(
            "{} test modes, {} sensors, {} expansion to {} DOF\n",
            test.data.modes.len(),
            test.layout.len(),
            a.expansion,
            loaded.sys.k.rows()
        );
        println!("{}", out.table2());
        println!("{}", table2_legend());
        for w in &out.correlation.pairing.warnings {
            println!("warning: {w}");
        }
    }
    write_json(a.json.as_deref(), &out.assessments)
}
