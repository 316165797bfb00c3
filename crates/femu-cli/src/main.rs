//! The `femu` command: it parses the command line and dispatches to one module per subcommand
//! (`cmd/`), each of which calls a workflow of `femu::study` and prints its result. See
//! `femu --help` and `docs/ARCHITECTURE.md`.

mod cmd;
mod common;
mod error;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// femu: finite element model updating and test-analysis correlation.
#[derive(Parser)]
#[command(version, about, long_about = None)]
struct Cli {
    /// No progress and no table on stdout (errors still go to stderr).
    #[arg(long, global = true)]
    quiet: bool,
    // the model, test and eigensolver arguments belong to the subcommands that use them
    // (`common::{ModelArgs, TestArgs, EngineArgs}`): a flag a command cannot use is refused by name
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    Estimate(cmd::estimate::EstimateArgs),
    Correlate(cmd::correlate::CorrelateArgs),
    Modes(cmd::modes::ModesArgs),
    Expand(cmd::expand::ExpandArgs),
    Frf(cmd::frf::FrfArgs),
    Info(cmd::info::InfoArgs),
    Matrices(cmd::matrices::MatricesArgs),
    Run(cmd::run::RunArgs),
    Demo(cmd::demo::DemoArgs),
    Update(cmd::update::UpdateArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let q = cli.quiet;
    let result = match &cli.command {
        Command::Estimate(a) => cmd::estimate::run(a, q),
        Command::Correlate(a) => cmd::correlate::run(a, q),
        Command::Modes(a) => cmd::modes::run(a, q),
        Command::Expand(a) => cmd::expand::run(a, q),
        Command::Frf(a) => cmd::frf::run(a, q),
        Command::Info(a) => cmd::info::run(a),
        Command::Matrices(a) => cmd::matrices::run(a, q),
        Command::Run(a) => cmd::run::run(a, q),
        Command::Demo(a) => cmd::demo::run(a, q),
        Command::Update(a) => cmd::update::run(a, q),
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
