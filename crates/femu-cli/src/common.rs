//! What several subcommands share: the model options, the progress spinner, warnings.

use clap::Args;
use femu::sparse::eigen::EigenOptions;
use femu::study::load::{LengthUnit, LoadedModel, MaterialOptions, ModelOptions};
use femu::study::mapping::{Align, MapMethod};
use femu::study::study_file::EngineName;
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::time::Duration;

use crate::error::CliError;

/// Material and constraints of a mesh-only model (`.msh`, `.unv`), and how a deck is read: the
/// arguments of every command that reads a model.
#[derive(Args, Debug, Clone, Default)]
#[command(next_help_heading = "Model")]
pub struct ModelArgs {
    /// Mesh-only models (Gmsh `.msh`, universal file `.unv` with datasets 2411/2412): Young's
    /// modulus in Pa (with --poisson and --density).
    #[arg(long, allow_negative_numbers = true)]
    pub young: Option<f64>,
    /// Mesh-only models: Poisson's ratio.
    #[arg(long, allow_negative_numbers = true)]
    pub poisson: Option<f64>,
    /// Mesh-only models: density in kg/m^3.
    #[arg(long, allow_negative_numbers = true)]
    pub density: Option<f64>,
    /// Mesh-only models: the material's structural damping coefficient GE (every element damped
    /// by `i GE K_e` in `femu frf`, as a Nastran MAT1's GE).
    #[arg(long, value_name = "GE", allow_negative_numbers = true)]
    pub structural_damping: Option<f64>,
    /// Mesh-only models: a node set (Gmsh physical group) to clamp (rotations too where shells
    /// give them); repeat for several.
    #[arg(long)]
    pub fix: Vec<String>,
    /// Gmsh meshes: a physical group of surfaces (3-node triangles, 4- and 8-node quadrangles) made
    /// shells of the given thickness in m, as GROUP=THICKNESS; repeat for several.
    #[arg(long, value_name = "GROUP=THICKNESS")]
    pub shell: Vec<String>,
    /// Gmsh meshes: a physical group of 2- or 3-node lines made Timoshenko beams of a section, as
    /// GROUP=rect:A,B (circ:R, pipe:R,T; Abaqus' *BEAM SECTION shapes), with @X,Y,Z for the
    /// section's 1-axis direction n1 (default 0,0,-1); repeat for several.
    #[arg(long, value_name = "GROUP=SECTION")]
    pub beam: Vec<String>,
    /// `.inp` decks: unknown keywords are warnings instead of errors (unknown parameters of known
    /// keywords stay errors).
    #[arg(long)]
    pub lenient: bool,
    /// Mesh-only models: how the 8-node bricks form their stiffness (incompatible-modes: the
    /// C3D8I brick, which bends without locking; a deck states its own).
    #[arg(long, value_enum, default_value = "full")]
    pub bricks: femu::fem::element::Formulation,
    /// Models given as another solver's matrices (CalculiX `job.sti`, Abaqus `job_STIF1.mtx`,
    /// Nastran DMIG `job.pch` or OUTPUT4 `job.op4`, MatrixMarket `X_K.mtx`): the nodes' coordinates, a deck's `*NODE`
    /// lines (`.inp`) or GRIDs (`.bdf`, `.dat`, `.nas`) or a table (`.csv`: node,x,y,z); by
    /// default the deck or `X_nodes.csv` beside the matrices.
    #[arg(long, value_name = "FILE")]
    pub nodes: Option<PathBuf>,
}

/// How a test is placed on the model: the arguments of every command that reads a test.
#[derive(Args, Debug, Clone, Default)]
#[command(next_help_heading = "Test")]
pub struct TestArgs {
    /// A test on its own wireframe (its node labels and coordinates): map every test node onto
    /// the model, to the nearest FE node or interpolated inside an element.
    #[arg(long, value_enum)]
    pub map: Option<MapMethod>,
    /// With --map: the largest distance from a test node to the model, m (default 1 % of the
    /// model's bounding-box diagonal).
    #[arg(long, value_name = "METRES", allow_negative_numbers = true)]
    pub tolerance: Option<f64>,
    /// With --map: bring the test's frame onto the model's first, from pairs of test and model
    /// nodes (`101:3,102:6,103:9`, at least three) or automatically (`auto`: best fit onto the
    /// model's surface).
    #[arg(long, value_name = "PAIRS|auto", value_parser = parse_align)]
    pub align: Option<Align>,
    /// With --align: fit a uniform scale too.
    #[arg(long)]
    pub align_scale: bool,
    /// The unit of a test file's coordinates when it does not say (CSV, JSON, a universal file
    /// without dataset 164).
    #[arg(long, value_enum, value_name = "UNIT")]
    pub test_units: Option<LengthUnit>,
}

/// An expansion method as the library spells it (`serep:M` takes its count of modes).
pub fn parse_method(s: &str) -> Result<femu::correlate::Method, String> {
    s.parse()
        .map_err(|e: femu::correlate::CorrelateError| e.to_string())
}

/// The model, test and eigensolver arguments of a command that reads a model and a test and
/// solves for modes (correlate, estimate, update).
#[derive(Args, Debug, Clone)]
pub struct Inputs {
    #[command(flatten)]
    pub model: ModelArgs,
    #[command(flatten)]
    pub test: TestArgs,
    #[command(flatten)]
    pub engine: EngineArgs,
}

fn parse_align(s: &str) -> Result<Align, String> {
    s.parse::<Align>().map_err(|e| e.to_string())
}

impl ModelArgs {
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
        // a deck has its own materials and constraints (the format table says which)
        let deck = femu::io::Format::from_path(path).is_some_and(|f| f.info().deck);
        let material = match (self.young, self.poisson, self.density) {
            (None, None, None) if self.structural_damping.is_some() && !deck => {
                return Err(CliError::Usage(
                    "--structural-damping is the mesh material's: give --young, --poisson and --density with it".into(),
                ));
            }
            (None, None, None) => None,
            // a deck has its own materials
            (y, p, d) if deck => {
                let given: Vec<&str> = [
                    ("--young", y),
                    ("--poisson", p),
                    ("--density", d),
                    ("--structural-damping", self.structural_damping),
                ]
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
                structural_damping: self.structural_damping.unwrap_or(0.0),
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
        let shells = self
            .shell
            .iter()
            .map(|s| {
                let (group, t) = s
                    .rsplit_once('=')
                    .ok_or_else(|| CliError::Usage(format!("--shell {s}: give GROUP=THICKNESS")))?;
                let t: f64 = t.trim().parse().map_err(|_| {
                    CliError::Usage(format!("--shell {s}: the thickness '{t}' is not a number"))
                })?;
                Ok((group.trim().to_string(), t))
            })
            .collect::<Result<Vec<_>, CliError>>()?;
        let beams = self
            .beam
            .iter()
            .map(|s| {
                let (group, section) = s.split_once('=').ok_or_else(|| {
                    CliError::Usage(format!("--beam {s}: give GROUP=SECTION (rect:A,B)"))
                })?;
                Ok((group.trim().to_string(), section.trim().to_string()))
            })
            .collect::<Result<Vec<_>, CliError>>()?;
        Ok(ModelOptions {
            material,
            fix: self.fix.clone(),
            shells,
            beams,
            lumped,
            lenient: self.lenient,
            bricks: self.bricks,
            nodes: self.nodes.clone(),
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
    mesh: &ModelArgs,
    lumped: bool,
    quiet: bool,
    pb: &ProgressBar,
) -> Result<LoadedModel, CliError> {
    pb.set_message(format!("reading and assembling {}", path.display()));
    let loaded = femu::study::load::load_model(path, &mesh.model_options(path, lumped, quiet)?)?;
    pb.suspend(|| warn(quiet, &loaded.warnings));
    Ok(loaded)
}

/// Reads the test and maps it onto the model (with `--map`, printing the mapping table).
///
/// # Errors
/// As [`femu::study::load::load_test_with`], and a bad --map or --align value.
pub fn load_test(
    path: &Path,
    loaded: &LoadedModel,
    args: &TestArgs,
    quiet: bool,
) -> Result<femu::study::load::LoadedTest, CliError> {
    load_test_on(path, loaded.model.mesh(), &loaded.sys.dofs, args, quiet)
}

/// [`load_test`] onto the nodes of `mesh` and the DOFs of `dofs` (another solver's modes).
///
/// # Errors
/// As [`load_test`].
pub fn load_test_on(
    path: &Path,
    mesh: &femu::fem::mesh::Mesh,
    dofs: &femu::fem::dof::DofMap,
    args: &TestArgs,
    quiet: bool,
) -> Result<femu::study::load::LoadedTest, CliError> {
    use femu::study::mapping::MapOptions;
    let map = match args.map {
        Some(method) => Some(MapOptions {
            method,
            tolerance: args.tolerance,
            align: args.align.clone().unwrap_or(Align::None),
            scale: args.align_scale,
        }),
        None => {
            let unused: Vec<String> = [
                ("--tolerance", args.tolerance.is_some()),
                ("--align", args.align.is_some()),
                ("--align-scale", args.align_scale),
            ]
            .iter()
            .filter(|(_, given)| *given)
            .map(|(name, _)| {
                format!("{name} applies with --map (a test on its own wireframe): not used")
            })
            .collect();
            warn(quiet, &unused);
            None
        }
    };
    let options = femu::study::load::TestOptions {
        map,
        test_units: args.test_units.map(LengthUnit::metres),
    };
    let test = femu::study::load::load_test_on(path, mesh, dofs, &options)?;
    warn(quiet, &test.warnings);
    if !quiet && let Some(m) = &test.mapping {
        println!("{m}");
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

/// The eigensolver every eigen solve of the command uses: the arguments of every command that
/// solves for modes.
#[derive(clap::Args, Debug, Clone)]
#[command(next_help_heading = "Eigensolver")]
pub struct EngineArgs {
    /// The eigensolver: femu's own (default) or SLEPc with MUMPS under MPI, for models whose
    /// factor outgrows one machine (docs/SCALING.md; install with scripts/setup-slepc.sh).
    #[arg(long, value_enum, default_value = "femu")]
    pub engine: EngineName,
    /// With --engine slepc: MPI ranks (mpirun -n).
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub np: usize,
    /// With --engine slepc: an MPI hostfile for a cluster.
    #[arg(long, value_name = "FILE")]
    pub hostfile: Option<std::path::PathBuf>,
}

impl EngineArgs {
    /// The eigensolver settings the arguments ask for, passed down to every solve of the command.
    ///
    /// # Errors
    /// Zero ranks, --np or --hostfile without --engine slepc.
    pub fn eigen(&self) -> Result<EigenOptions, CliError> {
        femu::study::study_file::engine_options(self.engine, self.np, self.hostfile.clone())
            .map_err(|_| {
                CliError::Usage(match self.engine {
                    EngineName::Femu => "--np and --hostfile apply with --engine slepc".into(),
                    EngineName::Slepc => "--np: SLEPc needs at least one MPI rank".into(),
                })
            })
    }
}
