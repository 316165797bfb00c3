//! What several subcommands share: the model options, the progress spinner, warnings.

use clap::Args;
use femu::study::load::{LoadedModel, MaterialOptions, ModelOptions};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::Path;
use std::time::Duration;

use crate::error::CliError;

/// Material and constraints of a mesh-only model (`.msh`, `.unv`); an `.inp` deck has its own.
#[derive(Args, Debug, Clone, Default)]
pub struct MeshOptions {
    /// Mesh-only models (Gmsh `.msh`, universal file `.unv` with datasets 2411/2412): Young's
    /// modulus in Pa (with --poisson and --density).
    #[arg(long, global = true, allow_negative_numbers = true)]
    pub young: Option<f64>,
    /// Mesh-only models: Poisson's ratio.
    #[arg(long, global = true, allow_negative_numbers = true)]
    pub poisson: Option<f64>,
    /// Mesh-only models: density in kg/m^3.
    #[arg(long, global = true, allow_negative_numbers = true)]
    pub density: Option<f64>,
    /// Mesh-only models: a node set (Gmsh physical group) to clamp; repeat for several.
    #[arg(long, global = true)]
    pub fix: Vec<String>,
    /// `.inp` decks: unknown keywords are warnings instead of errors (unknown parameters of known
    /// keywords stay errors).
    #[arg(long, global = true)]
    pub lenient: bool,
    /// Universal-file tests with their own node numbering: map each test node to the nearest
    /// model node within this distance (m; coordinates in the file's units, dataset 164).
    #[arg(long, global = true, value_name = "METRES")]
    pub map_nearest: Option<f64>,
    /// The unit of a test file's coordinates when it does not say (no dataset 164): m, cm, mm,
    /// in or ft. Used with --map-nearest.
    #[arg(long, global = true, value_name = "UNIT")]
    pub test_units: Option<String>,
}

impl MeshOptions {
    /// The model options, with `lumped` mass or not.
    ///
    /// # Errors
    /// Some but not all of --young, --poisson and --density, naming the missing ones.
    pub fn model_options(
        &self,
        path: &Path,
        lumped: bool,
        quiet: bool,
    ) -> Result<ModelOptions, CliError> {
        let deck = femu::study::load::has_extension(path, &["inp"]);
        let material = match (self.young, self.poisson, self.density) {
            (None, None, None) => None,
            // a deck has its own materials
            (y, p, d) if deck => {
                let given: Vec<&str> = [("--young", y), ("--poisson", p), ("--density", d)]
                    .iter()
                    .filter(|(_, v)| v.is_some())
                    .map(|(n, _)| *n)
                    .collect();
                warn(
                    quiet,
                    &[format!(
                        "{}: the deck has its own materials: {} not used",
                        path.display(),
                        given.join(", ")
                    )],
                );
                None
            }
            (Some(young), Some(poisson), Some(density)) => Some(MaterialOptions {
                young,
                poisson,
                density,
            }),
            (y, p, d) => {
                let missing: Vec<&str> = [("--young", y), ("--poisson", p), ("--density", d)]
                    .iter()
                    .filter(|(_, v)| v.is_none())
                    .map(|(n, _)| *n)
                    .collect();
                return Err(CliError::Usage(format!(
                    "a mesh material needs --young, --poisson and --density: {} missing",
                    missing.join(" and ")
                )));
            }
        };
        Ok(ModelOptions {
            material,
            fix: self.fix.clone(),
            lumped,
            lenient: self.lenient,
        })
    }
}

/// A spinner on stderr with the elapsed time (hidden when quiet).
pub fn spinner(quiet: bool, msg: &str) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::new_spinner();
    pb.set_style(
        ProgressStyle::with_template("{spinner} {msg} ({elapsed})").expect("valid template"),
    );
    pb.set_message(msg.to_string());
    pb.enable_steady_tick(Duration::from_millis(200));
    pb
}

/// Prints the readers' warnings to stderr unless quiet.
pub fn warn(quiet: bool, warnings: &[String]) {
    if !quiet {
        warnings.iter().for_each(|w| eprintln!("warning: {w}"));
    }
}

/// Reads and assembles the model, prints its warnings.
///
/// # Errors
/// As [`femu::study::load::load_model`].
pub fn load_model(
    path: &Path,
    mesh: &MeshOptions,
    lumped: bool,
    quiet: bool,
    pb: &ProgressBar,
) -> Result<LoadedModel, CliError> {
    pb.set_message(format!("reading and assembling {}", path.display()));
    let loaded = femu::study::load::load_model(path, &mesh.model_options(path, lumped, quiet)?)?;
    pb.suspend(|| warn(quiet, &loaded.warnings));
    Ok(loaded)
}

/// Reads the test and maps it onto the model (with `--map-nearest`, printing the mapping).
///
/// # Errors
/// As [`femu::study::load::load_test_with`].
pub fn load_test(
    path: &Path,
    loaded: &LoadedModel,
    mesh: &MeshOptions,
    quiet: bool,
) -> Result<femu::study::load::LoadedTest, CliError> {
    let options = femu::study::load::TestOptions {
        map_nearest: mesh.map_nearest,
        test_units: mesh
            .test_units
            .as_deref()
            .map(femu::study::load::length_unit)
            .transpose()?,
    };
    if mesh.test_units.is_some() && mesh.map_nearest.is_none() {
        warn(
            quiet,
            &["--test-units applies with --map-nearest (test coordinates): not used".into()],
        );
    }
    let test = femu::study::load::load_test_with(path, loaded, &options)?;
    if !quiet && !test.mapping.is_empty() {
        eprintln!("test node -> model node (distance, m):");
        for m in &test.mapping {
            eprintln!("  {} -> {} ({:.3e})", m.test, m.model, m.distance);
        }
    }
    Ok(test)
}

/// Writes `value` as pretty JSON when a path is given.
///
/// # Errors
/// The file system's error, naming the file.
pub fn write_json<T: serde::Serialize>(path: Option<&Path>, value: &T) -> Result<(), CliError> {
    if let Some(path) = path {
        femu::study::report::write_json(path, value)?;
    }
    Ok(())
}
