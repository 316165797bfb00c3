//! `femu modes`: the lowest modes of a model (or those nearest a frequency, or in a band), with
//! their Sturm evidence.

use crate::common::{EngineArgs, ModelArgs, load_model, spinner, write_json};
use crate::error::CliError;
use clap::Args;
use femu::study::modes::{ModesOptions, solve_modes};
use femu::study::report::write_shapes_vtu;
use std::path::PathBuf;

/// Lowest modes of a model, verified by a Sturm count.
///
/// Examples:
///   femu modes plate.inp --count 20
///   femu modes plate.inp --shift 1500 --count 6 --json modes.json
///   femu modes plate.inp --band 1000 3000 --vtu modes.vtu
///   femu modes plate.inp --count 20 --block-size 2
#[derive(Args, Debug)]
#[command(verbatim_doc_comment)]
pub struct ModesArgs {
    /// The model: an Abaqus/CalculiX `.inp` deck, Nastran bulk data (`.bdf`, `.dat`, `.nas`),
    /// or a `.msh`/`.unv` mesh with --young, --poisson, --density (and --fix).
    pub model: PathBuf,
    /// How many modes (lowest, or nearest the shift). Default: the deck's *FREQUENCY count, or 10.
    #[arg(long)]
    pub count: Option<usize>,
    /// Modes nearest this frequency (Hz).
    #[arg(long, conflicts_with = "band", allow_negative_numbers = true)]
    pub shift: Option<f64>,
    /// Every mode between two frequencies (Hz).
    #[arg(long, num_args = 2, value_names = ["LO", "HI"], allow_negative_numbers = true)]
    pub band: Option<Vec<f64>>,
    /// Lumped (diagonal) mass instead of consistent.
    #[arg(long)]
    pub lumped: bool,
    /// Write the result as JSON to this file.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Write the mesh and the mode shapes (point vectors, mass-normalised) for ParaView.
    #[arg(long)]
    pub vtu: Option<PathBuf>,
    /// Vectors the eigensolver solves together (default 4). Narrower blocks solve fewer vectors
    /// in all but read the factor more often; on large models 4 is the faster.
    #[arg(long, value_name = "N")]
    pub block_size: Option<usize>,
    /// Also the complex modes of the model's damping (structural: each material's GE, PARAM,G,
    /// *DAMPING, STRUCTURAL=; viscous: a bushing's B, Rayleigh, modal ratios), each one's root p,
    /// frequency, damping and phase collinearity as Nastran's complex eigenvalue output.
    #[arg(long)]
    pub damped: bool,
    /// Writes the modes (the damped ones with --damped, as complex data) as a universal file:
    /// every node (dataset 2411) and each mode's translations (dataset 55).
    #[arg(long, value_name = "FILE")]
    pub uff: Option<PathBuf>,
    #[command(flatten)]
    pub model_args: ModelArgs,
    #[command(flatten)]
    pub engine: EngineArgs,
}

/// Runs `femu modes`.
///
/// # Errors
/// Reading, assembly and eigensolver errors; bad counts, shifts and bands.
pub fn run(a: &ModesArgs, quiet: bool) -> Result<(), CliError> {
    let pb = spinner(quiet, "reading the model");
    let mut eigen = a.engine.eigen()?;
    if let Some(b) = a.block_size {
        eigen.block_size = b;
    }
    let loaded = load_model(&a.model, &a.model_args, a.lumped, quiet, &pb)?;
    pb.set_message(format!("solving ({} DOF)", loaded.sys.k.rows()));
    let options = ModesOptions {
        count: a.count,
        shift_hz: a.shift,
        band_hz: a.band.as_ref().map(|b| (b[0], b[1])),
        eigen,
        damped: a.damped,
    };
    let (result, report) = solve_modes(&loaded, &options)?;
    pb.finish_and_clear();
    let f = &report.frequencies_hz;
    if !quiet {
        let engine = match &options.eigen.engine {
            femu::sparse::slepc::Engine::Femu => "femu's shift-invert Lanczos".to_string(),
            femu::sparse::slepc::Engine::Slepc(o) => format!(
                "SLEPc Krylov-Schur with MUMPS, {} MPI rank{}",
                o.ranks,
                if o.ranks == 1 { "" } else { "s" }
            ),
        };
        println!(
            "{} DOF, {} mass, {} modes ({engine})",
            report.dofs,
            report.mass,
            f.len()
        );
        if let Some(m) = &report.matrices {
            println!(
                "Matrices: {} ({}), node coordinates from {}",
                m.format,
                m.files.join(", "),
                m.nodes
            );
        }
        println!("| mode | f (Hz) | lambda (s^-2) | residual | residual kind |");
        println!("|---|---|---|---|---|");
        for (j, fj) in f.iter().enumerate() {
            println!(
                "| {} | {:.6} | {:.6e} | {:.1e} | {} |",
                j + 1,
                fj,
                result.values[j],
                result.residuals[j],
                report.residual_kinds[j]
            );
        }
        for note in &report.notes {
            println!("note: {note}");
        }
        if !report.damped.is_empty() {
            println!(
                "Damped modes (complex eigenvalues p, u = phi e^(p t); in the space of the {} real modes):",
                f.len()
            );
            println!(
                "| mode | Re p (1/s) | Im p (1/s) | f (Hz) | damping g | ratio | MPC | MPD (deg) |"
            );
            println!("|---|---|---|---|---|---|---|---|");
            for (j, d) in report.damped.iter().enumerate() {
                println!(
                    "| {} | {:.6e} | {:.6e} | {:.6} | {:.4e} | {:.4e} | {:.4} | {:.2} |",
                    j + 1,
                    d.eigenvalue[0],
                    d.eigenvalue[1],
                    d.frequency_hz,
                    d.damping,
                    d.damping_ratio,
                    d.mpc,
                    d.mpd_degrees
                );
            }
        }
        println!(
            "Sturm check: {} eigenvalues in {} by inertia, {} returned: {}",
            result.sturm.count,
            result.sturm.interval(),
            result.sturm.returned,
            if result.sturm.verified() {
                "verified"
            } else {
                "FAILED"
            }
        );
        let l = &report.load;
        println!(
            "Model: read {:.2} s, checks {:.2} s, pattern {:.2} s, assembly {:.2} s (ordering and symbolic analysis beside it)",
            l.read_seconds, l.checks_seconds, l.pattern_seconds, l.assembly_seconds
        );
        println!("Eigensolver: {}", report.eigensolver.summary());
    }
    if let Some(path) = &a.vtu {
        let names: Vec<String> = f
            .iter()
            .enumerate()
            .map(|(j, fj)| format!("model mode {} ({fj:.3} Hz)", j + 1))
            .collect();
        write_shapes_vtu(
            path,
            &loaded.model,
            &loaded.sys.dofs,
            result.vectors.as_ref(),
            &names,
            &[],
        )?;
    }
    if let Some(path) = &a.uff {
        let uff = femu::study::modes::modes_universal(&loaded, &result, a.damped)?;
        femu::io::uff::write_uff(path, &uff)?;
    }
    write_json(a.json.as_deref(), &report)
}
