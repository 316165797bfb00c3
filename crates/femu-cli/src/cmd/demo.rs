//! `femu demo`: the paper's plate study end to end.

use crate::common::{EngineArgs, spinner};
use crate::error::CliError;
use clap::Args;
use femu::study::StudyError;
use femu::study::demo::{DemoOptions, run_demo};
use std::path::PathBuf;

/// The paper's plate study end to end: a plate with a modelling error is "tested" (UFF),
/// correlated (Table 1), estimated (Table 2), studied under sensor removal (Figure 1),
/// localised, updated by SB-EBE and checked on held-out modes. About 25 s on 2 cores.
///
/// Examples:
///   femu demo
///   femu demo --out report --shape-noise 0.01
#[derive(Args, Debug)]
#[command(verbatim_doc_comment)]
pub struct DemoArgs {
    /// Output folder for report.md, report.json, figure1.svg/png/csv, error_map.svg/png,
    /// plate.vtu, plate.inp and test.unv.
    #[arg(long, default_value = "femu-demo")]
    pub out: PathBuf,
    /// Noise on the test shapes, fraction of each mode's largest reading.
    #[arg(long, default_value_t = 0.005, allow_negative_numbers = true)]
    pub shape_noise: f64,
    /// Noise on the test frequencies, relative.
    #[arg(long, default_value_t = 0.0005, allow_negative_numbers = true)]
    pub frequency_noise: f64,
    /// The smaller study (plate at half resolution, every third sensor set): seconds.
    #[arg(long)]
    pub quick: bool,
    #[command(flatten)]
    pub engine: EngineArgs,
}

/// Runs `femu demo`.
///
/// # Errors
/// Noise out of `[0, 0.5)`, and the demo's errors.
pub fn run(a: &DemoArgs, quiet: bool) -> Result<(), CliError> {
    for (what, v) in [
        ("--shape-noise", a.shape_noise),
        ("--frequency-noise", a.frequency_noise),
    ] {
        if !(0.0..0.5).contains(&v) {
            return Err(CliError::Usage(format!("{what} {v} must be in [0, 0.5)")));
        }
    }
    let base = if a.quick {
        DemoOptions::quick()
    } else {
        DemoOptions::default()
    };
    let opts = DemoOptions {
        out: a.out.clone(),
        shape_noise: a.shape_noise,
        frequency_noise: a.frequency_noise,
        eigen: a.engine.eigen()?,
        ..base
    };
    let pb = spinner(quiet, "building the plate");
    let report = run_demo(&opts, |line| pb.set_message(line.to_string()))?;
    pb.finish_and_clear();
    if !quiet {
        let md = opts.out.join("report.md");
        print!(
            "{}",
            std::fs::read_to_string(&md).map_err(|e| StudyError::file(&md, e))?
        );
        println!("\nreport written to {}:", opts.out.display());
        for f in &report.files {
            println!("  {}", f.display());
        }
    }
    Ok(())
}
