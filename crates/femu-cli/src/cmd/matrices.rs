//! `femu matrices`: `K` and `M` as MatrixMarket files with the DOF map.

use crate::common::{ModelArgs, load_model, spinner};
use crate::error::CliError;
use clap::Args;
use femu::study::StudyError;
use std::path::PathBuf;

/// Export the assembled stiffness and mass as MatrixMarket files (`PREFIX_K.mtx`, `PREFIX_M.mtx`,
/// symmetric, lower triangle, free DOFs in femu's numbering) and the DOF map (`PREFIX_dofs.csv`:
/// row, node, component).
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
    let sys = &loaded.sys;
    let name = |suffix: &str| {
        let mut p = a.out.as_os_str().to_owned();
        p.push(suffix);
        PathBuf::from(p)
    };
    let (k, m, d) = (name("_K.mtx"), name("_M.mtx"), name("_dofs.csv"));
    pb.set_message("writing MatrixMarket files");
    femu::sparse::mtx::write_matrix_market(&k, &sys.k, true)?;
    femu::sparse::mtx::write_matrix_market(&m, &sys.m, true)?;
    let mut csv = String::from("row,node,component\n");
    for f in 0..sys.dofs.free_count() {
        let (p, c) = sys.dofs.free_dof(f);
        let (node, rotation) = sys.dofs.point_node(p);
        csv.push_str(&format!(
            "{},{},{}\n",
            f + 1,
            loaded.model.mesh().node_id(node),
            if rotation {
                ["rx", "ry", "rz"][c]
            } else {
                ["x", "y", "z"][c]
            }
        ));
    }
    std::fs::write(&d, csv).map_err(|e| StudyError::file(&d, e))?;
    pb.finish_and_clear();
    if !quiet {
        println!(
            "{} DOF, nnz(K) = {}: {}, {}, {}",
            sys.k.rows(),
            sys.k.nnz(),
            k.display(),
            m.display(),
            d.display()
        );
    }
    Ok(())
}
