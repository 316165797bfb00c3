//! `femu correlate`: test modes paired with the model's lowest modes.

use crate::common::{MeshOptions, load_model, spinner, write_json};
use crate::error::CliError;
use clap::Args;
use femu::correlate::{ModeSet, PairingOptions, correlate};
use femu::study::modes::lowest_for_test;
use std::path::PathBuf;

/// Pair test modes with the model's modes: MAC on the sensors, frequency errors, MSD, COMAC.
///
/// Examples:
///   femu correlate plate.inp test.unv
///   femu correlate plate.inp test.csv --mac-threshold 0.7 --json correlation.json
#[derive(Args, Debug)]
#[command(verbatim_doc_comment)]
pub struct CorrelateArgs {
    /// The model (`.inp`, Nastran `.bdf`/`.dat`/`.nas`, or `.msh`/`.unv` with --young, --poisson,
    /// --density, --fix).
    pub model: PathBuf,
    /// The test modes (`.unv`/`.uff`, `.json` or `.csv`: mode,frequency_hz,node,direction,value).
    pub test: PathBuf,
    /// Model modes to compute (default: twice the test modes plus 4).
    #[arg(long)]
    pub count: Option<usize>,
    /// Smallest MAC accepted for a pair.
    #[arg(long, default_value_t = 0.8)]
    pub mac_threshold: f64,
    /// Largest frequency error of a pair, percent (default: MAC alone decides, and pairs beyond
    /// 10 % are named in a warning).
    #[arg(long, value_name = "PERCENT")]
    pub max_frequency_error: Option<f64>,
    /// Lumped (diagonal) mass instead of consistent.
    #[arg(long)]
    pub lumped: bool,
    /// Write the correlation (MAC matrix, pairs, MSD, COMAC) as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

/// Runs `femu correlate`.
///
/// # Errors
/// Reading, assembly, eigensolver and pairing errors.
pub fn run(a: &CorrelateArgs, mesh: &MeshOptions, quiet: bool) -> Result<(), CliError> {
    let pb = spinner(quiet, "reading the model");
    let loaded = load_model(&a.model, mesh, a.lumped, quiet, &pb)?;
    let test = crate::common::load_test(&a.test, &loaded, mesh, quiet)?;
    pb.set_message("solving for the model's modes");
    let modes = lowest_for_test(&loaded, a.count, test.data.modes.len())?;
    pb.finish_and_clear();
    let options = PairingOptions {
        mac_threshold: a.mac_threshold,
        max_frequency_error: a.max_frequency_error.map(|p| p / 100.0),
    };
    let report = correlate(
        &ModeSet::from_modes(&modes),
        &test.data.modes,
        &test.layout,
        &options,
    )?;
    if !quiet {
        println!(
            "{} test modes at {} sensors against {} model modes (MAC threshold {})",
            test.data.modes.len(),
            test.layout.len(),
            modes.values.len(),
            a.mac_threshold
        );
        print!("{report}");
    }
    write_json(a.json.as_deref(), &report)
}
