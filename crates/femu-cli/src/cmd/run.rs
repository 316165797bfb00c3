//! `femu run STUDY.toml`: a whole study from one file, the model read and assembled once.

use crate::common::{spinner, warn};
use crate::error::CliError;
use clap::Args;
use femu::study::study_file::run_study_file;
use std::path::PathBuf;

/// Run a whole study described in a TOML file: correlation, estimation, expansion with the
/// sensor-removal study, and updating, with every result written to the output folder. The model
/// is read and assembled once and its modes solved once. Paths in the file are relative to the
/// file; unknown keys are errors.
///
/// Example study.toml:
///   model = "plate.inp"            # or a .bdf; or a .msh/.unv with [material], fix = ["set"]
///   test = "test.unv"              # .unv, .csv or .json
///   [material]                     # mesh-only models
///   young = 2.1e11
///   poisson = 0.3
///   density = 7850
///   test_units = "mm"              # where the test file does not say
///   [map]                          # a test on its own wireframe
///   method = "interpolate"         # or "nearest"
///   tolerance = 0.002              # m (default 1 % of the model's size)
///   align = "101:3,102:6,103:9"    # test:model node pairs, or "auto"
///   [pairing]
///   mac_threshold = 0.8
///   damped = false                 # complex MAC against the model's damped modes
///   [expansion]
///   method = "dynamic"             # static, dynamic, serep:M, min-residual, mdre
///   study = true                   # the sensor-removal study (Figure 1)
///   [eigen]
///   engine = "femu"                # or "slepc", with ranks = N and hostfile = "hosts"
///   [update]
///   sets = ["r0", "r1", "r2", "r3"]
///   tuned = 4
///   method = "sbebe"               # or "ies"
///
/// Examples:
///   femu run study.toml --out results
#[derive(Args, Debug)]
#[command(verbatim_doc_comment)]
pub struct RunArgs {
    /// The study file.
    pub study: PathBuf,
    /// Output folder.
    #[arg(long, default_value = "femu-study")]
    pub out: PathBuf,
}

/// Runs `femu run`.
///
/// # Errors
/// The study file's errors (with their line) and those of each step.
pub fn run(a: &RunArgs, quiet: bool) -> Result<(), CliError> {
    let pb = spinner(quiet, "reading the study file");
    let r = run_study_file(&a.study, &a.out, |line| pb.set_message(line.to_string()))?;
    pb.finish_and_clear();
    warn(quiet, &r.warnings);
    if quiet {
        return Ok(());
    }
    println!("{}", r.report());
    println!("results written to {}:", a.out.display());
    for f in &r.files {
        println!("  {}", f.display());
    }
    Ok(())
}
