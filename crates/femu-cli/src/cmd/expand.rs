//! `femu expand`: test shapes expanded to every model DOF, their estimators, and the
//! sensor-removal study.

use crate::common::{ModelArgs, TestArgs, load_model, spinner, write_json};
use crate::error::CliError;
use clap::Args;
use femu::correlate::Method;
use femu::study::expand::{expanded_names, expansion_report};
use femu::study::removal::write_removal_study;
use femu::study::report::{create_dir, write_shapes_vtu};
use std::path::PathBuf;

/// Expand test shapes to every model DOF: rho_M and rho_2 of the expanded shapes, a VTK file of
/// them, and optionally the sensor-removal study (the paper's Figure 1) over the test's nodes,
/// removed in Effective Independence order (triaxial sensors at each node).
///
/// Examples:
///   femu expand plate.inp test.unv --method dynamic --vtu expanded.vtu
///   femu expand plate.inp test.csv --method min-residual --study figure1
#[derive(Args, Debug)]
#[command(verbatim_doc_comment)]
pub struct ExpandArgs {
    /// The model (`.inp`, Nastran `.bdf`/`.dat`/`.nas`, or `.msh`/`.unv` with --young, --poisson,
    /// --density, --fix).
    pub model: PathBuf,
    /// The test modes (`.unv`/`.uff`, `.json` or `.csv`).
    pub test: PathBuf,
    /// The expansion method: static (Guyan), dynamic, serep:M (the model's lowest M modes),
    /// min-residual or mdre.
    #[arg(
        long,
        value_parser = crate::common::parse_method,
        default_value = "dynamic",
        value_name = "static|dynamic|serep:M|min-residual|mdre"
    )]
    pub method: Method,
    /// Lumped (diagonal) mass instead of consistent.
    #[arg(long)]
    pub lumped: bool,
    /// Write the expanded shapes for ParaView.
    #[arg(long)]
    pub vtu: Option<PathBuf>,
    /// Run the sensor-removal study and write study.csv, study.svg and study.png into this
    /// folder.
    #[arg(long)]
    pub study: Option<PathBuf>,
    /// Write rho_M, rho_2 and the study's points as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
    #[command(flatten)]
    pub model_args: ModelArgs,
    #[command(flatten)]
    pub test_args: TestArgs,
}

/// Runs `femu expand`.
///
/// # Errors
/// Reading, assembly and expansion errors; a study with fewer than 3 measured nodes.
pub fn run(a: &ExpandArgs, quiet: bool) -> Result<(), CliError> {
    let pb = spinner(quiet, "reading the model");
    let loaded = load_model(&a.model, &a.model_args, a.lumped, quiet, &pb)?;
    let test = crate::common::load_test(&a.test, &loaded, &a.test_args, quiet)?;
    let modes = &test.data.modes;
    pb.set_message(format!(
        "expanding {} test modes ({}){}",
        modes.len(),
        a.method,
        if a.study.is_some() {
            " and the sensor-removal study"
        } else {
            ""
        }
    ));
    let (x, report) = expansion_report(&loaded, &test, a.method, a.study.is_some())?;
    if let Some(path) = &a.vtu {
        write_shapes_vtu(
            path,
            &loaded.model,
            &loaded.sys.dofs,
            x.as_ref(),
            &expanded_names(modes),
            &[],
        )?;
    }
    if let (Some(dir), Some(st)) = (&a.study, &report.study) {
        create_dir(dir)?;
        write_removal_study(dir, "study", &st.points)?;
    }
    pb.finish_and_clear();
    if !quiet {
        println!(
            "{} test modes at {} sensors, {} expansion to {} DOF",
            modes.len(),
            test.layout.len(),
            a.method,
            loaded.sys.k.rows()
        );
        println!("| test | f (Hz) | rho_M (s^-2) | rho_2 | a model frequency within (Hz) |");
        println!("|---|---|---|---|---|");
        for (j, n) in report.norms.iter().enumerate() {
            let (lo, hi) = n.frequency_interval_hz();
            println!(
                "| {} | {:.2} | {:.4e} | {:.4e} | {lo:.1} .. {hi:.1} |",
                j + 1,
                modes.frequencies_hz[j],
                n.rho_m,
                n.rho_2
            );
        }
        if let (Some(dir), Some(st)) = (&a.study, &report.study) {
            println!(
                "sensor-removal study: {} points in {}",
                st.points.len(),
                dir.display()
            );
        }
    }
    #[derive(serde::Serialize)]
    struct Out<'a> {
        method: Method,
        rho_m: Vec<f64>,
        rho_2: Vec<f64>,
        study: &'a [femu::correlate::study::StudyPoint],
    }
    write_json(
        a.json.as_deref(),
        &Out {
            method: a.method,
            rho_m: report.norms.iter().map(|n| n.rho_m).collect(),
            rho_2: report.norms.iter().map(|n| n.rho_2).collect(),
            study: report.study.as_ref().map_or(&[], |s| &s.points),
        },
    )
}
