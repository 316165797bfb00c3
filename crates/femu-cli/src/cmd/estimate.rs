//! `femu estimate`: the paper's a priori estimators for test modes, after expansion.

use crate::common::{MeshOptions, load_model, spinner, write_json};
use crate::error::CliError;
use clap::Args;
use femu::correlate::{Method, ModeSet};
use femu::study::estimate::{EstimateOptions, estimate_with_bounds};
use femu::study::expand::expand_shapes;
use femu::study::modes::lowest_for_test;
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
    /// Expansion of the test shapes.
    #[arg(long, value_enum, default_value = "dynamic")]
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
}

/// Runs `femu estimate`.
///
/// # Errors
/// Reading, assembly, expansion, eigensolver and estimator errors.
pub fn run(a: &EstimateArgs, mesh: &MeshOptions, quiet: bool) -> Result<(), CliError> {
    let pb = spinner(quiet, "reading the model");
    let loaded = load_model(&a.model, mesh, a.lumped, quiet, &pb)?;
    let test = crate::common::load_test(&a.test, &loaded, mesh, quiet)?;
    let modes_t = &test.data.modes;
    let lambdas = modes_t.eigenvalues();
    pb.set_message(format!(
        "expanding {} test modes ({})",
        lambdas.len(),
        a.expansion
    ));
    let x = expand_shapes(
        &loaded.sys,
        &test.layout,
        &lambdas,
        modes_t.shapes.as_ref(),
        a.expansion,
        None,
    )?;
    pb.set_message("solving for the model's modes");
    let modes = lowest_for_test(&loaded, a.count, modes_t.len())?;
    let set = ModeSet::from_modes(&modes);
    let out = estimate_with_bounds(
        &loaded.model,
        &loaded.sys,
        &test.layout,
        modes_t,
        &set,
        x.as_ref(),
        &EstimateOptions {
            expansion: a.expansion,
            ..Default::default()
        },
    )?;
    pb.finish_and_clear();
    if !quiet {
        println!(
            "{} test modes, {} sensors, {} expansion to {} DOF",
            lambdas.len(),
            test.layout.len(),
            a.expansion,
            loaded.sys.k.rows()
        );
        println!(
            "| test | f test (Hz) | rho_M (s^-2) | rho_2 (N/m) | a model mode lies in (Hz) | rho_M / gap | paired model (Hz) |"
        );
        println!("|---|---|---|---|---|---|---|");
        let f_model = set.frequencies_hz();
        for (e, row) in out.assessments.iter().zip(&out.rows) {
            let pm = e.paired_model.map_or("-".to_string(), |j| {
                format!("{} ({:.1})", j + 1, f_model[j])
            });
            let width = if row.informative {
                format!("{:.1}", row.width_over_gap)
            } else {
                format!("{:.0}: too wide to inform", row.width_over_gap)
            };
            println!(
                "| {} | {:.1} | {:.4e} | {:.4e} | {:.1} .. {:.1} | {width} | {pm} |",
                e.test + 1,
                modes_t.frequencies_hz[e.test],
                e.norms.rho_m,
                e.norms.rho_2,
                e.frequency_interval_hz.0,
                e.frequency_interval_hz.1
            );
        }
        println!(
            "\nrho_M = ||(K - lambda M) x||_M^-1 / ||x||_M: a model eigenvalue lies within rho_M of each test eigenvalue (Theorem 2); rho_2 is the paper's Euclidean ratio; gap = distance to the nearest model eigenvalue; a bound above {} times the gap is too wide to inform.",
            femu::study::estimate::TOO_WIDE
        );
        for w in &out.correlation.pairing.warnings {
            println!("warning: {w}");
        }
    }
    write_json(a.json.as_deref(), &out.assessments)
}
