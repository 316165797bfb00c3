//! The `femu` command: it parses the command line and dispatches to one module per subcommand
//! (`cmd/`), each of which calls a workflow of `femu::study` and prints its result. See
//! `femu --help` and `docs/ARCHITECTURE.md`.

mod cmd;
mod common;
mod error;

use clap::{Parser, Subcommand};
use common::MeshOptions;
use std::process::ExitCode;

/// femu: finite element model updating and test-analysis correlation.
#[derive(Parser)]
#[command(version, about, long_about = None)]
struct Cli {
    /// No progress and no table on stdout (errors still go to stderr).
    #[arg(long, global = true)]
    quiet: bool,
    #[command(flatten)]
    mesh: MeshOptions,
    #[command(flatten)]
    engine: common::EngineOptions,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    Estimate(cmd::estimate::EstimateArgs),
    Correlate(cmd::correlate::CorrelateArgs),
    Modes(cmd::modes::ModesArgs),
    Expand(cmd::expand::ExpandArgs),
    Info(cmd::info::InfoArgs),
    Matrices(cmd::matrices::MatricesArgs),
    Run(cmd::run::RunArgs),
    Demo(cmd::demo::DemoArgs),
    Update(cmd::update::UpdateArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let (q, mesh) = (cli.quiet, &cli.mesh);
    if let Err(e) = cli.engine.install() {
        eprintln!("error: {e}");
        return ExitCode::FAILURE;
    }
    let result = match &cli.command {
        Command::Estimate(a) => cmd::estimate::run(a, mesh, q),
        Command::Correlate(a) => cmd::correlate::run(a, mesh, q),
        Command::Modes(a) => cmd::modes::run(a, mesh, q),
        Command::Expand(a) => cmd::expand::run(a, mesh, q),
        Command::Info(a) => cmd::info::run(a),
        Command::Matrices(a) => cmd::matrices::run(a, mesh, q),
        Command::Run(a) => cmd::run::run(a, q),
        Command::Demo(a) => cmd::demo::run(a, q),
        Command::Update(a) => cmd::update::run(a, mesh, q),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // what the reader noticed before the error is often its cause
            common::warn(false, &e.warnings());
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
