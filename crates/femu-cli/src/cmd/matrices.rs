//! `femu matrices`: `K` and `M` as MatrixMarket files with the DOF map.

use crate::common::{ModelArgs, load_model, spinner};
use crate::error::CliError;
use clap::Args;
use std::path::PathBuf;

/// Export the assembled stiffness and mass as MatrixMarket files (`PREFIX_K.mtx`, `PREFIX_M.mtx`,
/// symmetric, lower triangle, free DOFs in femu's numbering), the DOF map (`PREFIX_dofs.csv`:
/// row, node, component) and the node coordinates (`PREFIX_nodes.csv`): a set femu reads back as
/// a model (`femu modes PREFIX_K.mtx`).
///
/// Examples:
///   femu matrices plate.inp --out plate
#[derive(Args, Debug)]
#[command(verbatim_doc_comment)]
pub struct MatricesArgs {
    /// The model (`.inp`, Nastran `.bdf`/`.dat`/`.nas`, or `.msh`/`.unv` with --young, --poisson,
    /// --density, --fix).
    pub model: PathBuf,
    /// Output prefix.
    #[arg(long)]
    pub out: PathBuf,
    /// Lumped (diagonal) mass instead of consistent.
    #[arg(long)]
    pub lumped: bool,
    #[command(flatten)]
    pub model_args: ModelArgs,
}

/// Runs `femu matrices`.
///
/// # Errors
/// Reading, assembly and file system errors.
pub fn run(a: &MatricesArgs, quiet: bool) -> Result<(), CliError> {
    let pb = spinner(quiet, "reading the model");
    let loaded = load_model(&a.model, &a.model_args, a.lumped, quiet, &pb)?;
    pb.set_message("writing MatrixMarket files");
    let written = femu::study::external::write_matrices(&loaded.model, &loaded.sys, &a.out)?;
    pb.finish_and_clear();
    if !quiet {
        let names: Vec<String> = written
            .files
            .iter()
            .map(|f| f.display().to_string())
            .collect();
        println!(
            "{} DOF, nnz(K) = {}: {}",
            loaded.sys.k.rows(),
            loaded.sys.k.nnz(),
            names.join(", ")
        );
    }
    Ok(())
}
