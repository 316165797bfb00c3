//! `femu info`: what a file contains and what femu would do with it.

use crate::error::CliError;
use clap::Args;
use std::path::PathBuf;

/// What a file contains (nodes, elements, sets, materials, modes, units, trace lines) and what
/// femu would do with it.
///
/// Examples:
///   femu info plate.inp
///   femu info test.unv
#[derive(Args, Debug)]
#[command(verbatim_doc_comment)]
pub struct InfoArgs {
    /// Any file femu reads: `.inp`, `.bdf`/`.dat`/`.nas`, `.msh`, `.unv`/`.uff`, `.csv`, `.json`.
    pub file: PathBuf,
}

/// Runs `femu info`.
///
/// # Errors
/// The readers' errors and an extension femu does not read.
pub fn run(a: &InfoArgs) -> Result<(), CliError> {
    print!("{}", femu::study::info::describe(&a.file)?);
    Ok(())
}
