//! Abaqus/CalculiX input decks (`.inp`): read a model (mesh, sets, materials, sections,
//! boundary conditions, the `*FREQUENCY` step) and write one that CalculiX runs.
//!
//! Decks in parts and an assembly (`*PART`, `*ASSEMBLY`, `*INSTANCE` with its translation and
//! rotation, Abaqus/CAE's layout) are placed into one flat deck first (`parts.rs`).
//!
//! Supported keywords: `*HEADING`, `*NODE` (rectangular, or cylindrical with `SYSTEM=C`), `*ELEMENT` (C3D4, C3D10, C3D8, C3D20, C3D6, C3D15, and
//! C3D8I, the brick with incompatible modes; the reduced-integration C3D8R and C3D20R are read as
//! full integration, with a warning), `*NSET`,
//! `*ELSET` (lists of ids or set names, or `GENERATE`), `*MATERIAL`, `*ELASTIC` (isotropic,
//! `ENGINEERING CONSTANTS`, `ORTHOTROPIC`, `ANISOTROPIC`; `LAMINA` for shells), `*DENSITY`,
//! `*ORIENTATION` (rectangular or cylindrical; `orientation.rs`, docs/MATH.md, "Material
//! orientations"), `*SOLID SECTION`, `*BOUNDARY` (DOFs 1-3, and 4-6 on coupling reference nodes;
//! zero values; the named types `ENCASTRE`, `PINNED`, `XSYMM`, `YSYMM`, `ZSYMM`, `XASYMM`,
//! `YASYMM`, `ZASYMM`), `*ELEMENT, TYPE=MASS` with `*MASS`, `TYPE=ROTARYI` with `*ROTARY
//! INERTIA` (on nodes with rotations), `*NONSTRUCTURAL MASS` (per area of shells, per length
//! of beams, or a total), `*EQUATION` (node ids; the first term's DOF
//! is dependent), `*RIGID BODY` (`ELSET`, `TIE NSET` or CalculiX's `NSET`: rigid links; `PIN
//! NSET`: their translations), `*TIE` (slave nodes on master faces of solids, `tie.rs`),
//! `*KINEMATIC COUPLING` and `*COUPLING` with `*KINEMATIC` (rigid links: the
//! reference node gets rotations) or `*DISTRIBUTING` (weighted averages, with the weights of a
//! `*SURFACE, TYPE=NODE`), `*INCLUDE`, `*STEP`, `*FREQUENCY`, `*END STEP` (docs/MATH.md,
//! "Multipoint constraints"); trusses `T3D2` with `*SOLID SECTION` (the area on its data line);
//! beams `B31`, `B32` and `B33` with `*BEAM SECTION` (`RECT`, `CIRC`, `PIPE`)
//! or `*BEAM GENERAL SECTION` (`GENERAL`), springs `SPRING1`, `SPRING2`, `SPRINGA` with `*SPRING`
//! (`structural.rs`; their nodes get rotations, which `*BOUNDARY` DOFs 4-6 then fix), and shells
//! `S4`, `S4R`, `S3`, `S3R`, `S6`, `STRI65` (as four three-node triangles), `S8R`, `S8` with
//! `*SHELL SECTION` (or `*SHELL GENERAL SECTION` of a material) and membranes `M3D3`, `M3D4`,
//! `M3D4R`, `M3D6`,
//! `M3D8`, `M3D8R` with `*MEMBRANE SECTION` (a material, its thickness, its `OFFSET`, its
//! `ORIENTATION`).
//!
//! The writer states multipoint constraints as `*EQUATION`s; the rotations of a rigid link's
//! reference are the DOFs 1-3 of an extra node (set `FEMU_ROT`), as CalculiX's rotational nodes.
//!
//! The deck is checked as strictly as CalculiX and Abaqus check it, so that a typo never changes
//! the model silently:
//! - a keyword femu reads accepts only its known parameters: an unknown one (`*NSET, NSET=A,
//!   GENERTE`) is an error naming the nearest known spelling;
//! - a keyword that cannot change `K` or `M` (output requests, loads, amplitudes, other steps) is
//!   skipped with a warning;
//! - a keyword that would change `K` or `M` and that femu cannot model (contact, connectors,
//!   nonlinear materials) is an error;
//! - any other keyword is unknown: an error naming the nearest known spelling (`*BOUNDRY`: did you
//!   mean `*BOUNDARY`?), or a warning with [`InpOptions::lenient`].
//!
//! Names are case-insensitive (stored upper case); comments (`**`) and blank lines are ignored;
//! numbers may use Fortran `D` exponents. Node ordering is femu's (which is Abaqus's).

use crate::{IoError, Warning};
use femu_fem::element::{ElementKind, Formulation};
use femu_fem::material::{Elasticity, Material};
use femu_fem::mesh::Mesh;
use femu_fem::model::Model;
use std::collections::{BTreeMap, HashMap};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

mod model;
mod nonstructural;
mod orientation;
mod parse;
mod parts;
mod structural;
mod tie;
pub use structural::section_shape;
mod write;

use parse::*;
pub use write::{inp_string, write_inp};

/// How strictly a deck is read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct InpOptions {
    /// Unknown keywords are warnings instead of errors (unknown parameters of known keywords stay
    /// errors: they change what a known keyword means).
    pub lenient: bool,
}

/// The keywords femu reads, with the parameters each accepts.
const READ: &[(&str, &[&str])] = &[
    ("HEADING", &[]),
    ("NODE", &["NSET", "SYSTEM"]),
    ("ELEMENT", &["TYPE", "ELSET"]),
    ("MASS", &["ELSET"]),
    ("NSET", &["NSET", "GENERATE", "UNSORTED", "INTERNAL"]),
    ("ELSET", &["ELSET", "GENERATE", "UNSORTED", "INTERNAL"]),
    ("MATERIAL", &["NAME"]),
    ("ELASTIC", &["TYPE", "DEPENDENCIES", "MODULI"]),
    ("DENSITY", &["DEPENDENCIES"]),
    ("DAMPING", &["STRUCTURAL", "ALPHA", "BETA", "COMPOSITE"]),
    (
        "MODAL DAMPING",
        &["RAYLEIGH", "MODAL", "DEFINITION", "STRUCTURAL", "VISCOUS"],
    ),
    ("ORIENTATION", &["NAME", "SYSTEM", "DEFINITION"]),
    ("ROTARY INERTIA", &["ELSET"]),
    ("NONSTRUCTURAL MASS", &["ELSET", "UNITS", "DISTRIBUTION"]),
    (
        "TIE",
        &[
            "NAME",
            "ADJUST",
            "POSITION TOLERANCE",
            "TYPE",
            "NO ROTATION",
        ],
    ),
    (
        "RIGID BODY",
        &[
            "REF NODE",
            "ELSET",
            "TIE NSET",
            "PIN NSET",
            "NSET",
            "ROT NODE",
            "POSITION",
            "ISOTHERMAL",
        ],
    ),
    // parts and the assembly: placed before the keywords are read (`parts.rs`)
    ("PART", &["NAME"]),
    ("END PART", &[]),
    ("ASSEMBLY", &["NAME"]),
    ("END ASSEMBLY", &[]),
    ("INSTANCE", &["NAME", "PART"]),
    ("END INSTANCE", &[]),
    (
        "SOLID SECTION",
        &[
            "ELSET",
            "MATERIAL",
            "ORIENTATION",
            "CONTROLS",
            "SECTION CONTROLS",
        ],
    ),
    (
        "BOUNDARY",
        &[
            "OP",
            "TYPE",
            "AMPLITUDE",
            "FIXED",
            "USER",
            "SUBMODEL",
            "LOAD CASE",
        ],
    ),
    ("INCLUDE", &["INPUT"]),
    // TEMPERATURE (how temperatures are given) and POISSON (the section's change of shape under
    // large axial strain) do not change the linear stiffness or the mass
    (
        "BEAM SECTION",
        &[
            "ELSET",
            "MATERIAL",
            "SECTION",
            "LUMPED",
            "TEMPERATURE",
            "POISSON",
        ],
    ),
    (
        "BEAM GENERAL SECTION",
        &[
            "ELSET",
            "SECTION",
            "DENSITY",
            "LUMPED",
            "TEMPERATURE",
            "POISSON",
        ],
    ),
    ("SPRING", &["ELSET"]),
    ("DASHPOT", &["ELSET"]),
    (
        "MEMBRANE SECTION",
        &["ELSET", "MATERIAL", "POISSON", "ORIENTATION"],
    ),
    (
        "SHELL SECTION",
        &[
            "ELSET",
            "MATERIAL",
            "SECTION INTEGRATION",
            "OFFSET",
            "COMPOSITE",
            "SYMMETRIC",
            "ORIENTATION",
            "LAYUP",
            "POISSON",
            "TEMPERATURE",
            "CONTROLS",
        ],
    ),
    // with MATERIAL=, a linear elastic homogeneous shell as *SHELL SECTION's (its pre-integration
    // is the same for a linear material); without, a general stiffness, refused
    (
        "SHELL GENERAL SECTION",
        &[
            "ELSET",
            "MATERIAL",
            "OFFSET",
            "ORIENTATION",
            "POISSON",
            "TEMPERATURE",
            "CONTROLS",
        ],
    ),
    ("EQUATION", &[]),
    ("KINEMATIC COUPLING", &["REF NODE"]),
    (
        "COUPLING",
        &["REF NODE", "SURFACE", "CONSTRAINT NAME", "INFLUENCE RADIUS"],
    ),
    ("KINEMATIC", &[]),
    ("DISTRIBUTING", &["WEIGHTING METHOD"]),
    ("SURFACE", &["NAME", "TYPE", "INTERNAL"]),
    (
        "STEP",
        &[
            "NAME",
            "NLGEOM",
            "INC",
            "INCF",
            "PERTURBATION",
            "AMPLITUDE",
            "UNSYMM",
            "EXTRAPOLATION",
            "THERMAL NETWORK",
        ],
    ),
    (
        "FREQUENCY",
        &[
            "SOLVER",
            "STORAGE",
            "GLOBAL",
            "CYCMPC",
            "MATRIXSTORAGE",
            "EIGENSOLVER",
            "NORMALIZATION",
            "ACOUSTIC COUPLING",
            "SIM",
            "PROPERTY EVALUATION",
            "RESIDUAL MODES",
        ],
    ),
    ("END STEP", &[]),
];

/// Keywords that cannot change `K` or `M` of an undamped frequency analysis: skipped, with a
/// warning.
const NO_EFFECT: &[&str] = &[
    "AMPLITUDE",
    "BUCKLE",
    "CLOAD",
    "CONTACT FILE",
    "CONTACT OUTPUT",
    "CONTACT PRINT",
    "CONDUCTIVITY",
    "DASHPOT",
    "DLOAD",
    "DSLOAD",
    "EL FILE",
    "EL PRINT",
    "ELEMENT OUTPUT",
    "ENERGY OUTPUT",
    "EXPANSION",
    "FILM",
    "HEAT TRANSFER",
    "INITIAL CONDITIONS",
    "MODAL DYNAMIC",
    "NODE FILE",
    "NODE OUTPUT",
    "NODE PRINT",
    "OUTPUT",
    "PLASTIC",
    "PREPRINT",
    "RADIATE",
    "RESTART",
    "SECTION CONTROLS",
    "SPECIFIC HEAT",
    "STATIC",
    "STEADY STATE DYNAMICS",
    "SURFACE",
    "TEMPERATURE",
    "TIME POINTS",
];

/// Keywords that would change `K` or `M` and that femu cannot model: errors.
const UNSUPPORTED: &[(&str, &str)] = &[
    (
        "CONTACT PAIR",
        "contact changes the stiffness and is not supported",
    ),
    (
        "DISTRIBUTING COUPLING",
        "element-based distributing coupling is not supported (use *COUPLING with *DISTRIBUTING)",
    ),
    ("GAP", "gap elements are not supported"),
    (
        "HYPERELASTIC",
        "femu reads linear elasticity (*ELASTIC) alone",
    ),
    (
        "MEMBRANE SECTION",
        "membrane elements are not supported (solids only)",
    ),
    ("MPC", "multi-point constraints are not supported yet"),
    (
        "TRANSFORM",
        "local nodal systems are not supported yet: constraints would act in the wrong directions",
    ),
    (
        "USER MATERIAL",
        "femu reads linear elasticity (*ELASTIC) alone",
    ),
];

/// Every keyword femu knows, for "did you mean".
fn known_keywords() -> impl Iterator<Item = &'static str> {
    READ.iter()
        .map(|(k, _)| *k)
        .chain(NO_EFFECT.iter().copied())
        .chain(UNSUPPORTED.iter().map(|(k, _)| *k))
}

/// What to do with the keyword `name` with `params` on line `l`: `Ok(true)` when femu reads it,
/// `Ok(false)` when it is skipped (with a warning pushed), or the error.
fn check_keyword(
    name: &str,
    params: &[(String, String)],
    options: &InpOptions,
    l: &Line,
    warnings: &mut Vec<Warning>,
) -> Result<bool, IoError> {
    let err = |reason: String| IoError::Parse {
        path: l.path.clone(),
        line: l.number,
        reason,
    };
    if let Some((_, accepted)) = READ.iter().find(|(k, _)| *k == name) {
        for (p, _) in params {
            if !accepted.contains(&p.as_str()) {
                let hint = crate::spelling::suggestion(p, accepted.iter().copied(), "");
                let list = if accepted.is_empty() {
                    "none".to_string()
                } else {
                    accepted.join(", ")
                };
                return Err(err(format!(
                    "unknown parameter {p} of *{name}{hint}; *{name} accepts: {list}"
                )));
            }
        }
        return Ok(true);
    }
    if NO_EFFECT.contains(&name) {
        warnings.push(Warning {
            path: l.path.clone(),
            line: l.number,
            message: format!("*{name} skipped: it does not change the stiffness or the mass"),
        });
        return Ok(false);
    }
    if let Some((_, why)) = UNSUPPORTED.iter().find(|(k, _)| *k == name) {
        return Err(err(format!("*{name}: {why}")));
    }
    let hint = crate::spelling::suggestion(name, known_keywords(), "*");
    if options.lenient {
        warnings.push(Warning {
            path: l.path.clone(),
            line: l.number,
            message: format!("unknown keyword *{name}{hint} skipped (--lenient)"),
        });
        return Ok(false);
    }
    Err(err(format!(
        "unknown keyword *{name}{hint}; a misspelt keyword would change the model silently, so it \
         is an error (--lenient makes unknown keywords warnings)"
    )))
}

/// The `*FREQUENCY` step: how many modes, and the shift (s^-2) when given.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrequencyStep {
    /// Number of eigenvalues requested.
    pub count: usize,
    /// Shift point in (cycles/time)^2 as Abaqus writes it, when given.
    pub shift_cycles2: Option<f64>,
}

/// A constraint target: one node or a node set.
#[derive(Debug, Clone, PartialEq)]
pub enum Target {
    /// A node id.
    Node(u64),
    /// A node set name (upper case).
    Set(String),
}

/// A `*BOUNDARY` line: DOFs `first..=last` (1-based, 1-3) of the target fixed.
#[derive(Debug, Clone, PartialEq)]
pub struct Boundary {
    /// What is fixed.
    pub target: Target,
    /// First DOF (1 = x).
    pub first: usize,
    /// Last DOF.
    pub last: usize,
    /// Where it was defined.
    pub line: Location,
}

/// A material's `*DAMPING` (Abaqus' material damping): `STRUCTURAL=` the structural damping
/// coefficient `GE` of its elements (`i GE K_e`), `ALPHA=` and `BETA=` their Rayleigh damping
/// `alpha M_e + beta K_e`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MaterialDamping {
    /// `STRUCTURAL=`.
    pub structural: f64,
    /// `ALPHA=` (s^-1).
    pub alpha: f64,
    /// `BETA=` (s).
    pub beta: f64,
}

impl MaterialDamping {
    /// Gives element `id` of `model` this damping ([`Model::set_element_damping`],
    /// [`Model::set_element_rayleigh`]).
    ///
    /// # Errors
    /// Those of the two.
    pub fn apply(&self, model: &mut Model, id: u64) -> Result<(), femu_fem::FemError> {
        if self.structural != 0.0 {
            model.set_element_damping(id, self.structural)?;
        }
        if self.alpha != 0.0 || self.beta != 0.0 {
            model.set_element_rayleigh(id, self.alpha, self.beta)?;
        }
        Ok(())
    }
}

/// A `*SOLID SECTION`: the material of an element set (and a truss's cross-sectional area).
#[derive(Debug, Clone, PartialEq)]
pub struct Section {
    /// Element set (upper case).
    pub elset: String,
    /// Material name (upper case).
    pub material: String,
    /// The first field of its first data line: a truss's cross-sectional area (Abaqus assumes
    /// 1 where none is given).
    pub area: Option<String>,
    /// `ORIENTATION=`: the `*ORIENTATION` (upper case) that gives an anisotropic material's axes.
    pub orientation: Option<String>,
    /// Where it was defined.
    pub line: Location,
}

/// The nodes of a coupling: data-line targets, or a node-based `*SURFACE` by name.
#[derive(Debug, Clone, PartialEq)]
pub enum LinkNodes {
    /// Nodes and node sets.
    Targets(Vec<Target>),
    /// A `*SURFACE, TYPE=NODE` (upper-case name), whose lines may give weights.
    Surface(String),
    /// The nodes of an element set's elements (upper-case name; a `*RIGID BODY`'s `ELSET`).
    Elements(String),
}

/// A multipoint constraint of the deck (docs/MATH.md, "Multipoint constraints").
#[derive(Debug, Clone, PartialEq)]
pub enum LinkKind {
    /// `*EQUATION`: `sum_k a_k u_k = 0` over `(node, DOF 1-6, a_k)`; the first DOF is dependent.
    Equation(Vec<(u64, usize, f64)>),
    /// `*KINEMATIC COUPLING` or `*COUPLING` with `*KINEMATIC`: the DOFs (1-6; none listed = all)
    /// of the nodes follow the reference node rigidly.
    Kinematic {
        /// Reference node id.
        reference: u64,
        /// The coupled nodes.
        nodes: LinkNodes,
        /// DOFs 1-6 (empty: all).
        dofs: Vec<usize>,
    },
    /// `*COUPLING` with `*DISTRIBUTING`: the reference's DOFs follow the weighted least-squares
    /// rigid motion of the nodes.
    Distributing {
        /// Reference node id.
        reference: u64,
        /// The surface's nodes and weights.
        nodes: LinkNodes,
        /// DOFs 1-6 (empty: all).
        dofs: Vec<usize>,
    },
}

/// A constraint and where it was defined.
#[derive(Debug, Clone, PartialEq)]
pub struct InpLink {
    /// What it is.
    pub kind: LinkKind,
    /// Its keyword line.
    pub line: Location,
}

/// A `*TIE`: the slave surface's nodes follow the master surface's faces.
#[derive(Debug, Clone, PartialEq)]
struct Tie {
    name: String,
    slave: String,
    master: String,
    /// `POSITION TOLERANCE`: slave nodes farther from the master are not tied (Abaqus's default:
    /// 5 % of the master faces' typical diagonal)
    tolerance: Option<f64>,
    /// `ADJUST` (Abaqus's default YES): the slave nodes are moved onto the master surface
    adjust: bool,
    line: Location,
}

/// A `*NONSTRUCTURAL MASS`: a mass per area (shells, membranes), per length (beams, trusses), or
/// in total, spread over a set's shells and beams in proportion to their mass or their size.
#[derive(Debug, Clone, PartialEq)]
struct NonstructuralMass {
    elset: String,
    units: NsmUnits,
    /// `DISTRIBUTION=VOLUME PROPORTIONAL` (a total mass spread by area or length rather than by
    /// the elements' own mass)
    by_volume: bool,
    value: Option<f64>,
    line: Location,
}

/// A `*NONSTRUCTURAL MASS`'s `UNITS`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum NsmUnits {
    PerArea,
    PerLength,
    Total,
}

/// A `*MASS` card: the mass of every MASS element of a set.
#[derive(Debug, Clone, PartialEq)]
struct MassCard {
    elset: String,
    mass: f64,
    line: Location,
}

/// A file and 1-based line.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Location {
    /// The file.
    pub path: PathBuf,
    /// The line.
    pub line: usize,
}

/// A parsed deck.
#[derive(Debug, Clone)]
pub struct InpDeck {
    /// Nodes, elements and sets.
    pub mesh: Mesh,
    /// Materials by upper-case name.
    pub materials: BTreeMap<String, Material>,
    /// The damping of each material with a `*DAMPING` (by upper-case name): the `GE` and the
    /// Rayleigh damping of the elements of its sections.
    pub material_damping: BTreeMap<String, MaterialDamping>,
    /// `*MODAL DAMPING` ranges: modes `first..=last` with a viscous damping ratio (with
    /// `STRUCTURAL`, half the structural damping factor: see `modal_structural`).
    pub mode_ratios: Vec<(usize, usize, f64)>,
    /// Whether the `*MODAL DAMPING` ranges are `STRUCTURAL` (each mode's complex stiffness).
    pub modal_structural: bool,
    /// `*MODAL DAMPING, DEFINITION=FREQUENCY RANGE`: `(frequency, value)` points in order, the
    /// values fractions of critical damping (or structural damping factors with `STRUCTURAL`).
    pub modal_frequency_points: Vec<(f64, f64)>,
    /// `*MODAL DAMPING, RAYLEIGH`: the modes' Rayleigh damping `(alpha, beta)`.
    pub modal_rayleigh: Option<(f64, f64)>,
    /// `*MODAL DAMPING, RAYLEIGH` by ranges of modes: `(first, last, alpha, beta)`.
    pub modal_rayleigh_ranges: Vec<(usize, usize, f64, f64)>,
    /// Plane-stress ply materials (`*ELASTIC, TYPE=LAMINA`) by upper-case name: for composite
    /// shell sections only.
    pub(crate) laminae: BTreeMap<String, structural::Lamina>,
    /// `*ORIENTATION`s by upper-case name, resolved per element as the model is built.
    orientations: BTreeMap<String, orientation::OrientationCard>,
    /// Solid sections in file order.
    pub sections: Vec<Section>,
    /// Boundary conditions in file order.
    pub boundaries: Vec<Boundary>,
    /// Point masses: node id, mass (kg) and the `*MASS` that gave it.
    pub point_masses: Vec<(u64, f64, Location)>,
    /// The element set of each point mass (its `*MASS`'s `ELSET`), in the same order: a mass set
    /// of the model for updating.
    pub point_mass_sets: Vec<String>,
    /// Rotary inertias (ROTARYI elements with their `*ROTARY INERTIA`): node id, inertia about
    /// the basic axes (kg m^2) and the card that gave it.
    pub rotary_inertias: Vec<(u64, [[f64; 3]; 3], Location)>,
    /// Multipoint constraints in file order.
    pub links: Vec<InpLink>,
    /// Node-based surfaces by upper-case name: targets and weights.
    pub surfaces: BTreeMap<String, Vec<(Target, f64)>>,
    /// element-based surfaces: an element or element set and a face label a line
    element_surfaces: BTreeMap<String, Vec<(Target, String, Location)>>,
    /// `*TIE`s in file order
    ties: Vec<Tie>,
    /// `*NONSTRUCTURAL MASS` cards in file order
    nonstructural: Vec<NonstructuralMass>,
    /// The frequency step, if any.
    pub frequency: Option<FrequencyStep>,
    /// The ids of the elements read as C3D8I (incompatible modes).
    pub incompatible_modes: Vec<u64>,
    /// Non-fatal findings.
    pub warnings: Vec<Warning>,
    /// where each element was defined (for errors found later)
    element_lines: HashMap<u64, Location>,
    /// beams and springs, their sections and sets
    structural: structural::StructuralRecords,
    /// the file read (for errors that concern the whole deck)
    path: PathBuf,
}

#[derive(Clone)]
struct Line {
    path: PathBuf,
    number: usize,
    text: String,
}

/// Reads the lines of `path` with its `*INCLUDE`s expanded in place (depth limited to 16).
fn load(path: &Path, depth: usize, out: &mut Vec<Line>) -> Result<(), IoError> {
    let text = std::fs::read(path).map_err(|e| IoError::io(path, e))?;
    push_lines(&String::from_utf8_lossy(&text), path, depth, out)
}

/// Appends the lines of `text` (from `path`) to `out`, expanding `*INCLUDE`s relative to `path`.
fn push_lines(text: &str, path: &Path, depth: usize, out: &mut Vec<Line>) -> Result<(), IoError> {
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    for (i, raw) in text.lines().enumerate() {
        let t = raw.trim_end_matches('\r');
        if t.trim_start().to_ascii_uppercase().starts_with("*INCLUDE") {
            let (_, params) = keyword(t);
            let Some(file) = params.get("INPUT") else {
                return Err(IoError::Parse {
                    path: path.to_path_buf(),
                    line: i + 1,
                    reason: "*INCLUDE without INPUT=".into(),
                });
            };
            if depth >= 16 {
                return Err(IoError::Parse {
                    path: path.to_path_buf(),
                    line: i + 1,
                    reason: "*INCLUDE nested more than 16 deep (a cycle?)".into(),
                });
            }
            let target = dir.join(file.trim_matches('"'));
            load(&target, depth + 1, out).map_err(|e| match e {
                IoError::Io { reason, .. } => IoError::Parse {
                    path: path.to_path_buf(),
                    line: i + 1,
                    reason: format!(
                        "*INCLUDE, INPUT={file}: cannot read {}: {reason}",
                        target.display()
                    ),
                },
                e => e,
            })?;
            continue;
        }
        out.push(Line {
            path: path.to_path_buf(),
            number: i + 1,
            text: t.to_string(),
        });
    }
    Ok(())
}

/// `*KEYWORD, A=b, FLAG` -> ("KEYWORD", {A: b, FLAG: ""}); keys upper case, values as written.
fn keyword(line: &str) -> (String, HashMap<String, String>) {
    let mut parts = line.trim().trim_start_matches('*').split(',');
    let name = parts
        .next()
        .unwrap_or("")
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
        .to_ascii_uppercase();
    let mut params = HashMap::new();
    for p in parts {
        let p = p.trim();
        if p.is_empty() {
            continue;
        }
        match p.split_once('=') {
            Some((k, v)) => params.insert(k.trim().to_ascii_uppercase(), v.trim().to_string()),
            None => params.insert(p.to_ascii_uppercase(), String::new()),
        };
    }
    (name, params)
}

/// DOFs `first..=last` (1-6; `last` defaults to `first`), or all six when neither is given.
fn dof_range(first: Option<&str>, last: Option<&str>) -> Result<Vec<usize>, String> {
    let parse = |v: &str| {
        v.parse::<usize>()
            .ok()
            .filter(|d| (1..=6).contains(d))
            .ok_or_else(|| format!("DOF {v:?} is not 1-6"))
    };
    let first = match first.filter(|v| !v.is_empty()) {
        Some(v) => parse(v)?,
        None => return Ok((1..=6).collect()),
    };
    let last = match last.filter(|v| !v.is_empty()) {
        Some(v) => parse(v)?,
        None => first,
    };
    if last < first {
        return Err(format!("DOF range {first}..{last} is empty"));
    }
    Ok((first..=last).collect())
}

fn fields(line: &str) -> Vec<&str> {
    let mut f: Vec<&str> = line.split(',').map(str::trim).collect();
    while f.last().is_some_and(|s| s.is_empty()) {
        f.pop();
    }
    f
}

fn parse_f64(s: &str) -> Option<f64> {
    s.parse::<f64>()
        .ok()
        .or_else(|| s.replace(['D', 'd'], "E").parse().ok())
        .filter(|v: &f64| v.is_finite())
}

/// The element kind and formulation of an Abaqus type name, and whether it was read as an
/// approximation.
fn element_kind(name: &str) -> Option<(ElementKind, Formulation, bool)> {
    let full = Formulation::Full;
    Some(match name.to_ascii_uppercase().as_str() {
        "C3D4" => (ElementKind::Tet4, full, false),
        "C3D10" => (ElementKind::Tet10, full, false),
        "C3D8" => (ElementKind::Hex8, full, false),
        "C3D8I" => (ElementKind::Hex8, Formulation::IncompatibleModes, false),
        "C3D20" => (ElementKind::Hex20, full, false),
        "C3D6" => (ElementKind::Penta6, full, false),
        "C3D15" => (ElementKind::Penta15, full, false),
        "C3D8R" => (ElementKind::Hex8, full, true),
        "C3D20R" => (ElementKind::Hex20, full, true),
        _ => return None,
    })
}

#[derive(Default)]
struct PendingMaterial {
    name: String,
    young: Option<(f64, f64)>,
    /// `*ELASTIC, TYPE=LAMINA` was given: the data line is `E1 E2 NU12 G12 G13 G23`.
    lamina_type: bool,
    lamina: Option<[f64; 6]>,
    /// `*ELASTIC, TYPE=ENGINEERING CONSTANTS`, `ORTHOTROPIC` or `ANISOTROPIC`: the type, and its
    /// constants as read so far (they run over several data lines).
    aniso: Option<AnisoType>,
    aniso_values: Vec<f64>,
    /// the line of that `*ELASTIC`
    aniso_line: usize,
    density: Option<f64>,
    /// `*DAMPING, STRUCTURAL=`: the material's structural damping coefficient.
    structural: Option<f64>,
    /// `*DAMPING, ALPHA=, BETA=`: the material's Rayleigh damping.
    alpha: Option<f64>,
    beta: Option<f64>,
    line: usize,
    path: PathBuf,
}

/// An anisotropic `*ELASTIC`'s type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum AnisoType {
    /// `E1 E2 E3 NU12 NU13 NU23 G12 G13 G23`.
    EngineeringConstants,
    /// `D1111 D1122 D2222 D1133 D2233 D3333 D1212 D1313 D2323`.
    Orthotropic,
    /// The 21 `D` of the upper triangle, column by column in the order 11, 22, 33, 12, 13, 23.
    Anisotropic,
}

impl AnisoType {
    /// How many constants it takes.
    fn count(self) -> usize {
        match self {
            AnisoType::Anisotropic => 21,
            _ => 9,
        }
    }

    fn name(self) -> &'static str {
        match self {
            AnisoType::EngineeringConstants => "ENGINEERING CONSTANTS",
            AnisoType::Orthotropic => "ORTHOTROPIC",
            AnisoType::Anisotropic => "ANISOTROPIC",
        }
    }
}

/// Reads a deck from a file (with its includes).
///
/// # Errors
/// [`IoError::Io`] for unreadable files, [`IoError::Parse`] with file and line for malformed
/// content, [`IoError::Model`] for a valid deck that does not make a valid mesh.
pub fn read_inp(path: impl AsRef<Path>) -> Result<InpDeck, IoError> {
    read_inp_with(path, &InpOptions::default())
}

/// Reads a deck from a file (with its includes) as `options` say.
///
/// # Errors
/// As [`read_inp`]; errors found after warnings carry them ([`IoError::warnings`]).
pub fn read_inp_with(path: impl AsRef<Path>, options: &InpOptions) -> Result<InpDeck, IoError> {
    let mut lines = Vec::new();
    load(path.as_ref(), 0, &mut lines)?;
    parse(&lines, path.as_ref(), options)
}

/// Parses a deck held in memory (`path` names it in messages; `*INCLUDE` is resolved against the
/// file system relative to `path`).
///
/// # Errors
/// As [`read_inp`].
pub fn parse_inp(text: &str, path: impl AsRef<Path>) -> Result<InpDeck, IoError> {
    let mut lines = Vec::new();
    push_lines(text, path.as_ref(), 0, &mut lines)?;
    parse(&lines, path.as_ref(), &InpOptions::default())
}

/// The nodes of a deck (its `*NODE` blocks, with its includes) and nothing else: the coordinates
/// of a model whose matrices another solver made (CalculiX's `*FREQUENCY, SOLVER=MATRIXSTORAGE`
/// beside its deck), whatever elements the deck holds. Each node with the line that defined it.
///
/// # Errors
/// [`IoError::Io`] for unreadable files; [`IoError::Parse`] with file and line for a malformed
/// node line, a node defined twice, or `*NODE, SYSTEM=` other than rectangular;
/// [`IoError::Content`] for a deck without nodes.
pub fn read_nodes(path: impl AsRef<Path>) -> Result<Vec<(u64, [f64; 3])>, IoError> {
    let path = path.as_ref();
    let mut lines = Vec::new();
    load(path, 0, &mut lines)?;
    let bad = |l: &Line, reason: String| IoError::Parse {
        path: l.path.clone(),
        line: l.number,
        reason,
    };
    let mut nodes = Vec::new();
    let mut seen: HashMap<u64, usize> = HashMap::new();
    let mut in_node = false;
    let mut cylindrical_block = false;
    for l in &lines {
        let t = l.text.trim();
        if t.is_empty() || t.starts_with("**") {
            continue;
        }
        if t.starts_with('*') {
            let (name, params) = keyword(t);
            in_node = name == "NODE";
            if in_node {
                cylindrical_block = parse::node_system(&params).map_err(|r| bad(l, r))?;
            }
            continue;
        }
        if !in_node {
            continue;
        }
        let f = fields(t);
        let id = f
            .first()
            .and_then(|s| s.parse::<u64>().ok())
            .ok_or_else(|| bad(l, format!("a node needs an id and coordinates, got {t:?}")))?;
        let mut x = [0.0; 3];
        for (c, s) in f.iter().skip(1).take(3).enumerate() {
            x[c] = parse_f64(s).ok_or_else(|| {
                bad(
                    l,
                    format!("coordinate {s:?} of node {id} is not a finite number"),
                )
            })?;
        }
        if cylindrical_block {
            x = parse::cylindrical(x);
        }
        if let Some(first) = seen.insert(id, l.number) {
            return Err(bad(
                l,
                format!("node {id} is defined again (first at line {first})"),
            ));
        }
        nodes.push((id, x));
    }
    if nodes.is_empty() {
        return Err(IoError::Content {
            path: path.to_path_buf(),
            reason: "the deck has no *NODE block".into(),
        });
    }
    Ok(nodes)
}

fn parse(lines: &[Line], path: &Path, options: &InpOptions) -> Result<InpDeck, IoError> {
    let mut warnings = Vec::new();
    let flat = parts::flatten(lines, &mut warnings).map_err(|e| e.after(&warnings))?;
    let lines = flat.as_deref().unwrap_or(lines);
    parse_collecting(lines, path, options, &mut warnings).map_err(|e| e.after(&warnings))
}
