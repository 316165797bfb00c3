//! `femu correlate`: test modes paired with the model's lowest modes.

use crate::common::{Inputs, load_model, spinner, write_json};
use crate::error::CliError;
use clap::Args;
use femu::correlate::correlate;
use femu::study::modes::lowest_for_test;
use femu::study::study_file::PairingSection;
use std::path::PathBuf;

/// Pair test modes with the model's modes: MAC on the sensors, frequency errors, MSD, COMAC.
///
/// Examples:
///   femu correlate plate.inp test.unv
///   femu correlate plate.inp test.csv --mac-threshold 0.7 --json correlation.json
///   femu correlate job.frd test.unv        # CalculiX's modes (*NODE FILE, U in *FREQUENCY)
#[derive(Args, Debug)]
#[command(verbatim_doc_comment)]
pub struct CorrelateArgs {
    /// The model (`.inp`, Nastran `.bdf`/`.dat`/`.nas`, `.msh`/`.unv` with --young, --poisson,
    /// --density, --fix, another solver's K and M: `job.sti`, `job_STIF1.mtx`, `job.pch`, `job.op4`, `X_K.mtx`), or another solver's
    /// modes (CalculiX `.frd`), which are then the model's modes.
    pub model: PathBuf,
    /// The test modes (`.unv`/`.uff`, `.json` or `.csv`: mode,frequency_hz,node,direction,value).
    pub test: PathBuf,
    /// Model modes to compute (default: twice the test modes plus 4).
    #[arg(long)]
    pub count: Option<usize>,
    #[command(flatten)]
    pub pairing: PairingSection,
    /// Lumped (diagonal) mass instead of consistent.
    #[arg(long)]
    pub lumped: bool,
    /// Write the correlation (MAC matrix, pairs, MSD, COMAC) as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
    #[command(flatten)]
    pub inputs: Inputs,
}

/// Runs `femu correlate`.
///
/// # Errors
/// Reading, assembly, eigensolver and pairing errors.
pub fn run(a: &CorrelateArgs, quiet: bool) -> Result<(), CliError> {
    let pb = spinner(quiet, "reading the model");
    let eigen = a.inputs.engine.eigen()?;
    let (modes, test) = if femu::io::Format::from_path(&a.model) == Some(femu::io::Format::Results)
    {
        let results =
            femu::study::external::load_result_modes(&a.model, a.inputs.model.nodes.as_deref())?;
        pb.suspend(|| crate::common::warn(quiet, &results.warnings));
        if a.count.is_some() || a.lumped {
            crate::common::warn(
                quiet,
                &[format!(
                    "{}: the modes are the file's: --count and --lumped are not used",
                    a.model.display()
                )],
            );
        }
        let test = crate::common::load_test_on(
            &a.test,
            results.model.mesh(),
            &results.dofs,
            &a.inputs.test,
            quiet,
        )?;
        (results.modes, test)
    } else {
        let loaded = load_model(&a.model, &a.inputs.model, a.lumped, quiet, &pb)?;
        let test = crate::common::load_test(&a.test, &loaded, &a.inputs.test, quiet)?;
        pb.set_message("solving for the model's modes");
        let modes = lowest_for_test(&loaded, a.count, test.data.modes.len(), &eigen)?;
        (
            femu::study::modes::mode_set(&loaded, &modes, a.pairing.damped)?,
            test,
        )
    };
    pb.finish_and_clear();
    let options = a.pairing.options();
    let report = correlate(&modes, &test.data.modes, &test.layout, &options)?;
    if !quiet {
        println!(
            "{} test modes at {} sensors against {} model modes (MAC threshold {})",
            test.data.modes.len(),
            test.layout.len(),
            modes.len(),
            a.pairing.mac_threshold
        );
        print!("{report}");
    }
    write_json(a.json.as_deref(), &report)
}
