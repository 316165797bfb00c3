//! Abaqus/CalculiX input decks (`.inp`): read a model (mesh, sets, materials, sections,
//! boundary conditions, the `*FREQUENCY` step) and write one that CalculiX runs.
//!
//! Supported keywords: `*HEADING`, `*NODE`, `*ELEMENT` (C3D4, C3D10, C3D8, C3D20, C3D6, C3D15; the
//! reduced-integration C3D8R and C3D20R are read as full integration, with a warning), `*NSET`,
//! `*ELSET` (lists of ids or set names, or `GENERATE`), `*MATERIAL`, `*ELASTIC` (isotropic),
//! `*DENSITY`, `*SOLID SECTION`, `*BOUNDARY` (DOFs 1-3, and 4-6 on coupling reference nodes;
//! zero values), `*ELEMENT, TYPE=MASS` with `*MASS`, `*EQUATION` (node ids; the first term's DOF
//! is dependent), `*KINEMATIC COUPLING` and `*COUPLING` with `*KINEMATIC` (rigid links: the
//! reference node gets rotations) or `*DISTRIBUTING` (weighted averages, with the weights of a
//! `*SURFACE, TYPE=NODE`), `*INCLUDE`, `*STEP`, `*FREQUENCY`, `*END STEP` (docs/MATH.md,
//! "Multipoint constraints").
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
//! - a keyword that would change `K` or `M` and that femu cannot model (shells, beams, springs,
//!   `*RIGID BODY`, `*TIE`, parts and instances, other materials) is an error;
//! - any other keyword is unknown: an error naming the nearest known spelling (`*BOUNDRY`: did you
//!   mean `*BOUNDARY`?), or a warning with [`InpOptions::lenient`].
//!
//! Names are case-insensitive (stored upper case); comments (`**`) and blank lines are ignored;
//! numbers may use Fortran `D` exponents. Node ordering is femu's (which is Abaqus's).

use crate::{IoError, Warning};
use femu_fem::element::ElementKind;
use femu_fem::material::{Elasticity, Material};
use femu_fem::mesh::Mesh;
use femu_fem::model::Model;
use std::collections::{BTreeMap, HashMap};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

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
    ("EQUATION", &[]),
    ("KINEMATIC COUPLING", &["REF NODE"]),
    (
        "COUPLING",
        &["REF NODE", "SURFACE", "CONSTRAINT NAME", "INFLUENCE RADIUS"],
    ),
    ("KINEMATIC", &[]),
    ("DISTRIBUTING", &["WEIGHTING METHOD"]),
    ("SURFACE", &["NAME", "TYPE"]),
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
    "DAMPING",
    "DASHPOT",
    "DLOAD",
    "DSLOAD",
    "EL FILE",
    "EL PRINT",
    "ELEMENT OUTPUT",
    "END PART",
    "ENERGY OUTPUT",
    "EXPANSION",
    "FILM",
    "HEAT TRANSFER",
    "INITIAL CONDITIONS",
    "MODAL DAMPING",
    "MODAL DYNAMIC",
    "NODE FILE",
    "NODE OUTPUT",
    "NODE PRINT",
    "OUTPUT",
    "PLASTIC",
    "PREPRINT",
    "RADIATE",
    "RESTART",
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
        "ASSEMBLY",
        "part/instance input: flatten the deck (nodes and elements at the top level)",
    ),
    (
        "BEAM SECTION",
        "beam elements are not supported (solids only)",
    ),
    (
        "BEAM GENERAL SECTION",
        "beam elements are not supported (solids only)",
    ),
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
        "only linear isotropic elasticity is supported",
    ),
    (
        "INSTANCE",
        "part/instance input: flatten the deck (nodes and elements at the top level)",
    ),
    (
        "MEMBRANE SECTION",
        "membrane elements are not supported (solids only)",
    ),
    ("MPC", "multi-point constraints are not supported yet"),
    (
        "NONSTRUCTURAL MASS",
        "non-structural mass is not supported yet",
    ),
    (
        "PART",
        "part/instance input: flatten the deck (nodes and elements at the top level)",
    ),
    ("RIGID BODY", "rigid bodies are not supported yet"),
    (
        "ROTARY INERTIA",
        "rotary inertia is not supported (solid elements have no rotations)",
    ),
    (
        "SHELL SECTION",
        "shell elements are not supported (solids only)",
    ),
    ("SPRING", "spring elements are not supported yet"),
    ("TIE", "tied surfaces are not supported yet"),
    (
        "TRANSFORM",
        "local nodal systems are not supported yet: constraints would act in the wrong directions",
    ),
    (
        "USER MATERIAL",
        "only linear isotropic elasticity is supported",
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

/// A `*SOLID SECTION`: the material of an element set.
#[derive(Debug, Clone, PartialEq)]
pub struct Section {
    /// Element set (upper case).
    pub elset: String,
    /// Material name (upper case).
    pub material: String,
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
    /// Solid sections in file order.
    pub sections: Vec<Section>,
    /// Boundary conditions in file order.
    pub boundaries: Vec<Boundary>,
    /// Point masses: node id, mass (kg) and the `*MASS` that gave it.
    pub point_masses: Vec<(u64, f64, Location)>,
    /// Multipoint constraints in file order.
    pub links: Vec<InpLink>,
    /// Node-based surfaces by upper-case name: targets and weights.
    pub surfaces: BTreeMap<String, Vec<(Target, f64)>>,
    /// The frequency step, if any.
    pub frequency: Option<FrequencyStep>,
    /// Non-fatal findings.
    pub warnings: Vec<Warning>,
    /// where each element was defined (for errors found later)
    element_lines: HashMap<u64, Location>,
    /// the file read (for errors that concern the whole deck)
    path: PathBuf,
}

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

/// The element kind of an Abaqus type name, and whether it was read as an approximation.
fn element_kind(name: &str) -> Option<(ElementKind, bool)> {
    Some(match name.to_ascii_uppercase().as_str() {
        "C3D4" => (ElementKind::Tet4, false),
        "C3D10" => (ElementKind::Tet10, false),
        "C3D8" => (ElementKind::Hex8, false),
        "C3D20" => (ElementKind::Hex20, false),
        "C3D6" => (ElementKind::Penta6, false),
        "C3D15" => (ElementKind::Penta15, false),
        "C3D8R" => (ElementKind::Hex8, true),
        "C3D20R" => (ElementKind::Hex20, true),
        _ => return None,
    })
}

#[derive(Default)]
struct PendingMaterial {
    name: String,
    young: Option<(f64, f64)>,
    density: Option<f64>,
    line: usize,
    path: PathBuf,
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

fn parse(lines: &[Line], path: &Path, options: &InpOptions) -> Result<InpDeck, IoError> {
    let mut warnings = Vec::new();
    parse_collecting(lines, path, options, &mut warnings).map_err(|e| e.after(&warnings))
}

#[allow(clippy::type_complexity)]
fn parse_collecting(
    lines: &[Line],
    path: &Path,
    options: &InpOptions,
    warnings: &mut Vec<Warning>,
) -> Result<InpDeck, IoError> {
    let err = |l: &Line, reason: String| IoError::Parse {
        path: l.path.clone(),
        line: l.number,
        reason,
    };
    let warn = |w: &mut Vec<Warning>, l: &Line, message: String| {
        w.push(Warning {
            path: l.path.clone(),
            line: l.number,
            message,
        })
    };
    // raw records first: elements may refer to nodes defined later in the file
    let mut nodes: Vec<(u64, [f64; 3], usize)> = Vec::new();
    let mut elements: Vec<(u64, ElementKind, Vec<u64>, usize)> = Vec::new();
    // set name -> (is_node_set, tokens, line index)
    let mut sets: Vec<(String, bool, Vec<String>, bool, usize)> = Vec::new();
    let mut node_set_of_block: Vec<(String, Vec<u64>)> = Vec::new();
    let mut elem_set_of_block: Vec<(String, Vec<u64>)> = Vec::new();
    // point masses: MASS elements (id, node, line index) by their ELSET, and *MASS cards
    let mut mass_elements: Vec<(u64, u64, usize)> = Vec::new();
    let mut mass_sets: BTreeMap<String, Vec<u64>> = BTreeMap::new();
    let mut mass_block: Option<String> = None;
    let mut mass_cards: Vec<MassCard> = Vec::new();
    let mut materials = BTreeMap::new();
    let mut pending: Option<PendingMaterial> = None;
    let mut sections = Vec::new();
    let mut boundaries = Vec::new();
    let mut frequency = None;
    let mut links: Vec<InpLink> = Vec::new();
    let mut surfaces: BTreeMap<String, Vec<(Target, f64)>> = BTreeMap::new();
    let mut surface_now: Option<String> = None;
    let mut coupling_now: Option<(u64, String)> = None;
    // an *EQUATION being read: number of terms, terms so far, keyword line
    let mut equation: Option<(usize, Vec<(u64, usize, f64)>, Location)> = None;
    let mut block = String::new();
    let mut block_params: HashMap<String, String> = HashMap::new();
    let mut element_kind_now: Option<(ElementKind, usize)> = None;
    let mut element_buffer: Vec<String> = Vec::new();
    let mut element_start = 0usize;
    let mut seen_keyword = false;
    let finish_material = |p: Option<PendingMaterial>,
                           materials: &mut BTreeMap<String, Material>|
     -> Result<(), IoError> {
        if let Some(p) = p {
            let (e, nu) = p.young.ok_or_else(|| IoError::Parse {
                path: p.path.clone(),
                line: p.line,
                reason: format!("material {} has no *ELASTIC", p.name),
            })?;
            let rho = p.density.ok_or_else(|| IoError::Parse {
                path: p.path.clone(),
                line: p.line,
                reason: format!(
                    "material {} has no *DENSITY (a frequency analysis needs it)",
                    p.name
                ),
            })?;
            let m = Material::isotropic(p.name.clone(), e, nu, rho).map_err(|source| {
                IoError::Model {
                    path: p.path.clone(),
                    line: p.line,
                    source,
                }
            })?;
            materials.insert(p.name, m);
        }
        Ok(())
    };
    for (li, l) in lines.iter().enumerate() {
        let t = l.text.trim();
        if t.is_empty() || t.starts_with("**") {
            continue;
        }
        if t.starts_with('*') {
            if !element_buffer.is_empty() {
                return Err(err(
                    &lines[element_start],
                    "element definition cut short by a keyword".into(),
                ));
            }
            if let Some((n, terms, at)) = &equation
                && terms.len() < *n
            {
                return Err(IoError::Parse {
                    path: at.path.clone(),
                    line: at.line,
                    reason: format!(
                        "*EQUATION announces {n} terms and gives {} before the next keyword",
                        terms.len()
                    ),
                });
            }
            equation = None;
            seen_keyword = true;
            let (name, params) = keyword(t);
            let mut sorted: Vec<(String, String)> = params.clone().into_iter().collect();
            sorted.sort();
            if !check_keyword(&name, &sorted, options, l, warnings)? {
                // skipped: its data lines are skipped with it
                finish_material(pending.take(), &mut materials)?;
                block = String::new();
                element_kind_now = None;
                continue;
            }
            let material_keyword = matches!(name.as_str(), "ELASTIC" | "DENSITY");
            if !material_keyword && name != "MATERIAL" {
                finish_material(pending.take(), &mut materials)?;
            }
            block = name.clone();
            block_params = params.clone();
            element_kind_now = None;
            mass_block = None;
            match name.as_str() {
                "HEADING" | "END STEP" | "STEP" => {}
                "KINEMATIC COUPLING" | "COUPLING" => {
                    let reference = params
                        .get("REF NODE")
                        .and_then(|v| v.parse::<u64>().ok())
                        .ok_or_else(|| err(l, format!("*{name} needs REF NODE=<node id>")))?;
                    coupling_now = None;
                    if name == "COUPLING" {
                        let surface = params.get("SURFACE").ok_or_else(|| {
                            err(l, "*COUPLING needs SURFACE=<node-based surface>".into())
                        })?;
                        coupling_now = Some((reference, surface.to_ascii_uppercase()));
                    }
                }
                "KINEMATIC" | "DISTRIBUTING" => {
                    let (reference, surface) = coupling_now
                        .clone()
                        .ok_or_else(|| err(l, format!("*{name} without a *COUPLING before it")))?;
                    if name == "DISTRIBUTING"
                        && params
                            .get("WEIGHTING METHOD")
                            .is_some_and(|w| !w.eq_ignore_ascii_case("UNIFORM"))
                    {
                        return Err(err(
                            l,
                            "*DISTRIBUTING: femu weights by the surface's node weights (WEIGHTING METHOD=UNIFORM)".into(),
                        ));
                    }
                    let nodes = LinkNodes::Surface(surface);
                    let kind = if name == "KINEMATIC" {
                        LinkKind::Kinematic {
                            reference,
                            nodes,
                            dofs: Vec::new(),
                        }
                    } else {
                        LinkKind::Distributing {
                            reference,
                            nodes,
                            dofs: Vec::new(),
                        }
                    };
                    links.push(InpLink {
                        kind,
                        line: Location {
                            path: l.path.clone(),
                            line: l.number,
                        },
                    });
                }
                "SURFACE" => {
                    let ty = params.get("TYPE").map(|t| t.to_ascii_uppercase());
                    if ty.as_deref() != Some("NODE") {
                        return Err(err(
                            l,
                            format!(
                                "*SURFACE, TYPE={}: femu reads node-based surfaces (TYPE=NODE) for couplings",
                                ty.unwrap_or_else(|| "ELEMENT".into())
                            ),
                        ));
                    }
                    let name = params
                        .get("NAME")
                        .ok_or_else(|| err(l, "*SURFACE without NAME=".into()))?
                        .to_ascii_uppercase();
                    surfaces.entry(name.clone()).or_default();
                    surface_now = Some(name);
                }
                "NODE" => {
                    if let Some(sys) = params
                        .get("SYSTEM")
                        .filter(|v| !v.eq_ignore_ascii_case("R"))
                    {
                        return Err(err(
                            l,
                            format!(
                                "*NODE, SYSTEM={sys}: only rectangular coordinates (SYSTEM=R) are supported"
                            ),
                        ));
                    }
                    if let Some(s) = params.get("NSET") {
                        node_set_of_block.push((s.to_ascii_uppercase(), Vec::new()));
                    }
                }
                "ELEMENT"
                    if params
                        .get("TYPE")
                        .is_some_and(|t| t.eq_ignore_ascii_case("MASS")) =>
                {
                    // one-node mass elements: their mass comes from the *MASS of their set
                    let set = params
                        .get("ELSET")
                        .map(|s| s.to_ascii_uppercase())
                        .ok_or_else(|| {
                            err(
                                l,
                                "*ELEMENT, TYPE=MASS needs ELSET= (the set its *MASS names)".into(),
                            )
                        })?;
                    mass_sets.entry(set.clone()).or_default();
                    mass_block = Some(set);
                }
                "MASS" => {
                    let set = params
                        .get("ELSET")
                        .ok_or_else(|| err(l, "*MASS without ELSET=".into()))?;
                    mass_cards.push(MassCard {
                        elset: set.to_ascii_uppercase(),
                        mass: f64::NAN,
                        line: Location {
                            path: l.path.clone(),
                            line: l.number,
                        },
                    });
                }
                "ELEMENT" => {
                    let ty = params
                        .get("TYPE")
                        .ok_or_else(|| err(l, "*ELEMENT without TYPE=".into()))?;
                    let (kind, approx) = element_kind(ty).ok_or_else(|| {
                        err(l, format!("element type {ty} is not supported (C3D4, C3D10, C3D8, C3D20, C3D6, C3D15, C3D8R, C3D20R, MASS)"))
                    })?;
                    if approx {
                        warn(
                            warnings,
                            l,
                            format!("{ty} read as {} with full integration", kind.abaqus_name()),
                        );
                    }
                    element_kind_now = Some((kind, kind.num_nodes()));
                    if let Some(s) = params.get("ELSET") {
                        elem_set_of_block.push((s.to_ascii_uppercase(), Vec::new()));
                    }
                }
                "NSET" | "ELSET" => {
                    let key = if name == "NSET" { "NSET" } else { "ELSET" };
                    let set = params
                        .get(key)
                        .ok_or_else(|| err(l, format!("*{name} without {key}=")))?;
                    sets.push((
                        set.to_ascii_uppercase(),
                        name == "NSET",
                        Vec::new(),
                        params.contains_key("GENERATE"),
                        li,
                    ));
                }
                "MATERIAL" => {
                    finish_material(pending.take(), &mut materials)?;
                    let mname = params
                        .get("NAME")
                        .ok_or_else(|| err(l, "*MATERIAL without NAME=".into()))?;
                    pending = Some(PendingMaterial {
                        name: mname.to_ascii_uppercase(),
                        line: l.number,
                        path: l.path.clone(),
                        ..Default::default()
                    });
                }
                "ELASTIC" | "DENSITY" => {
                    if pending.is_none() {
                        return Err(err(l, format!("*{name} outside a *MATERIAL")));
                    }
                    let unsupported = params.get("TYPE").filter(|ty| {
                        !ty.eq_ignore_ascii_case("ISOTROPIC") && !ty.eq_ignore_ascii_case("ISO")
                    });
                    if let (true, Some(ty)) = (name == "ELASTIC", unsupported) {
                        return Err(err(
                            l,
                            format!("*ELASTIC, TYPE={ty} is not supported yet (isotropic only)"),
                        ));
                    }
                }
                "SOLID SECTION" => {
                    let elset = params
                        .get("ELSET")
                        .ok_or_else(|| err(l, "*SOLID SECTION without ELSET=".into()))?;
                    let material = params
                        .get("MATERIAL")
                        .ok_or_else(|| err(l, "*SOLID SECTION without MATERIAL=".into()))?;
                    sections.push(Section {
                        elset: elset.to_ascii_uppercase(),
                        material: material.to_ascii_uppercase(),
                        line: Location {
                            path: l.path.clone(),
                            line: l.number,
                        },
                    });
                }
                "BOUNDARY" => {
                    if params
                        .get("OP")
                        .is_some_and(|v| v.eq_ignore_ascii_case("NEW"))
                    {
                        // OP=NEW removes every boundary condition defined before it
                        boundaries.clear();
                    }
                    if params.contains_key("TYPE") || params.contains_key("AMPLITUDE") {
                        warn(
                            warnings,
                            l,
                            "*BOUNDARY options ignored (homogeneous constraints only)".into(),
                        );
                    }
                }
                _ => {} // HEADING, FREQUENCY, INCLUDE: nothing to do at the keyword
            }
            continue;
        }
        if t.chars()
            .any(|c| c == '\u{FFFD}' || (c.is_control() && c != '\t'))
        {
            return Err(err(
                l,
                "binary data where a deck has text: is this an Abaqus/CalculiX .inp deck?".into(),
            ));
        }
        if !seen_keyword {
            return Err(err(
                l,
                format!(
                    "data line {:?} before any keyword: a deck starts with a *KEYWORD line",
                    t.chars().take(40).collect::<String>()
                ),
            ));
        }
        // data line of the current block
        let f = fields(t);
        match block.as_str() {
            "NODE" => {
                if f.len() < 3 {
                    return Err(err(
                        l,
                        format!("a node needs an id and coordinates, got {t:?}"),
                    ));
                }
                let id = f[0]
                    .parse::<u64>()
                    .map_err(|_| err(l, format!("node id {:?} is not a positive integer", f[0])))?;
                let mut x = [0.0; 3];
                for (c, s) in f[1..f.len().min(4)].iter().enumerate() {
                    x[c] = parse_f64(s).ok_or_else(|| {
                        err(
                            l,
                            format!("coordinate {s:?} of node {id} is not a finite number"),
                        )
                    })?;
                }
                nodes.push((id, x, li));
                if let Some(last) = node_set_of_block
                    .last_mut()
                    .filter(|_| block_params.contains_key("NSET"))
                {
                    last.1.push(id);
                }
            }
            "ELEMENT" if mass_block.is_some() => {
                let set = mass_block.as_ref().expect("checked");
                let ids: Vec<u64> = f
                    .iter()
                    .filter(|s| !s.is_empty())
                    .map(|s| s.parse::<u64>())
                    .collect::<Result<_, _>>()
                    .map_err(|_| {
                        err(
                            l,
                            format!("a MASS element line is an id and a node, got {t:?}"),
                        )
                    })?;
                let [id, node] = ids[..] else {
                    return Err(err(
                        l,
                        format!("a MASS element line is an id and a node, got {t:?}"),
                    ));
                };
                mass_elements.push((id, node, li));
                mass_sets
                    .get_mut(set)
                    .expect("created with the block")
                    .push(id);
            }
            "MASS" => {
                let card = mass_cards.last_mut().expect("set with the keyword");
                if card.mass.is_nan() {
                    card.mass = f
                        .first()
                        .and_then(|s| parse_f64(s))
                        .filter(|m| *m > 0.0)
                        .ok_or_else(|| err(l, format!("*MASS needs a positive mass, got {t:?}")))?;
                }
            }
            "ELEMENT" => {
                let (kind, nn) = element_kind_now.expect("set with the keyword");
                if element_buffer.is_empty() {
                    element_start = li;
                }
                element_buffer.extend(f.iter().map(|s| s.to_string()));
                if element_buffer.len() < nn + 1 {
                    continue; // continued on the next line
                }
                let start = &lines[element_start];
                if element_buffer.len() > nn + 1 {
                    return Err(err(
                        start,
                        format!(
                            "{} needs {nn} nodes, got {}",
                            kind.abaqus_name(),
                            element_buffer.len() - 1
                        ),
                    ));
                }
                let ids: Result<Vec<u64>, _> =
                    element_buffer.iter().map(|s| s.parse::<u64>()).collect();
                let ids = ids.map_err(|_| {
                    err(
                        start,
                        format!("element line has a non-integer entry: {element_buffer:?}"),
                    )
                })?;
                elements.push((ids[0], kind, ids[1..].to_vec(), element_start));
                if let Some(last) = elem_set_of_block
                    .last_mut()
                    .filter(|_| block_params.contains_key("ELSET"))
                {
                    last.1.push(ids[0]);
                }
                element_buffer.clear();
            }
            "NSET" | "ELSET" => {
                let last = sets.last_mut().expect("set with the keyword");
                last.2.extend(f.iter().map(|s| s.to_string()));
            }
            "ELASTIC" => {
                let p = pending.as_mut().expect("checked at the keyword");
                if f.len() < 2 {
                    return Err(err(l, "*ELASTIC needs E and nu".into()));
                }
                let e = parse_f64(f[0])
                    .ok_or_else(|| err(l, format!("E = {:?} is not a number", f[0])))?;
                let nu = parse_f64(f[1])
                    .ok_or_else(|| err(l, format!("nu = {:?} is not a number", f[1])))?;
                if f.len() > 2 {
                    warn(
                        warnings,
                        l,
                        "temperature-dependent elasticity: the first line is used".into(),
                    );
                }
                if p.young.is_none() {
                    p.young = Some((e, nu));
                }
            }
            "DENSITY" => {
                let p = pending.as_mut().expect("checked at the keyword");
                let rho = f
                    .first()
                    .and_then(|s| parse_f64(s))
                    .ok_or_else(|| err(l, format!("density {t:?} is not a number")))?;
                if p.density.is_none() {
                    p.density = Some(rho);
                }
            }
            "BOUNDARY" => {
                if f.len() < 2 {
                    return Err(err(
                        l,
                        format!("*BOUNDARY needs a node or set and a DOF, got {t:?}"),
                    ));
                }
                let target = match f[0].parse::<u64>() {
                    Ok(id) => Target::Node(id),
                    Err(_) => Target::Set(f[0].to_ascii_uppercase()),
                };
                let first = f[1]
                    .parse::<usize>()
                    .map_err(|_| err(l, format!("DOF {:?} is not an integer", f[1])))?;
                let last = match f.get(2) {
                    Some(s) if !s.is_empty() => s
                        .parse::<usize>()
                        .map_err(|_| err(l, format!("DOF {s:?} is not an integer")))?,
                    _ => first,
                };
                if let Some(v) = f.get(3).and_then(|s| parse_f64(s)).filter(|v| *v != 0.0) {
                    {
                        warn(
                            warnings,
                            l,
                            format!(
                                "prescribed value {v} read as 0 (femu's constraints are homogeneous)"
                            ),
                        );
                    }
                }
                if first == 0 || last < first {
                    return Err(err(l, format!("DOF range {first}..{last} is invalid")));
                }
                if last > 6 {
                    warn(
                        warnings,
                        l,
                        "DOFs above 6 (temperature, pressure) do not exist here: ignored".into(),
                    );
                }
                if last > 3 {
                    warn(warnings, l, "DOFs 4-6 (rotations) exist only on coupling reference nodes: ignored on other nodes".into());
                }
                if first <= 6 {
                    boundaries.push(Boundary {
                        target,
                        first,
                        last: last.min(6),
                        line: Location {
                            path: l.path.clone(),
                            line: l.number,
                        },
                    });
                }
            }
            "FREQUENCY" if frequency.is_none() => {
                let count = f
                    .first()
                    .and_then(|s| s.parse::<usize>().ok())
                    .filter(|c| *c > 0)
                    .ok_or_else(|| {
                        err(
                            l,
                            format!("*FREQUENCY needs a positive number of eigenvalues, got {t:?}"),
                        )
                    })?;
                let shift_cycles2 = f.get(2).and_then(|s| parse_f64(s));
                frequency = Some(FrequencyStep {
                    count,
                    shift_cycles2,
                });
            }
            "EQUATION" => {
                let at = Location {
                    path: l.path.clone(),
                    line: l.number,
                };
                match &mut equation {
                    None => {
                        let n = f
                            .first()
                            .and_then(|v| v.parse::<usize>().ok())
                            .filter(|n| *n > 0)
                            .ok_or_else(|| {
                                err(l, format!("*EQUATION needs its number of terms, got {t:?}"))
                            })?;
                        equation = Some((n, Vec::new(), at));
                    }
                    Some((n, terms, _)) => {
                        if !f.len().is_multiple_of(3) {
                            return Err(err(
                                l,
                                format!("*EQUATION terms come as node, DOF, coefficient: {t:?}"),
                            ));
                        }
                        for c in f.chunks(3) {
                            let node = c[0].parse::<u64>().map_err(|_| {
                                err(l, format!("*EQUATION: node {:?} is not a node id (node sets are not read in equations)", c[0]))
                            })?;
                            let dof = c[1]
                                .parse::<usize>()
                                .ok()
                                .filter(|d| (1..=6).contains(d))
                                .ok_or_else(|| {
                                    err(l, format!("*EQUATION: DOF {:?} is not 1-6", c[1]))
                                })?;
                            let a = parse_f64(c[2]).filter(|a| a.is_finite()).ok_or_else(|| {
                                err(
                                    l,
                                    format!("*EQUATION: coefficient {:?} is not a number", c[2]),
                                )
                            })?;
                            terms.push((node, dof, a));
                        }
                        if terms.len() > *n {
                            return Err(err(
                                l,
                                format!("*EQUATION announces {n} terms and gives {}", terms.len()),
                            ));
                        }
                        if terms.len() == *n {
                            let (_, terms, at) = equation.take().expect("some");
                            links.push(InpLink {
                                kind: LinkKind::Equation(terms),
                                line: at,
                            });
                        }
                    }
                }
            }
            "KINEMATIC COUPLING" => {
                let reference = block_params
                    .get("REF NODE")
                    .and_then(|v| v.parse::<u64>().ok())
                    .unwrap_or(0);
                let target = match f.first().map(|v| v.parse::<u64>()) {
                    Some(Ok(id)) => Target::Node(id),
                    Some(Err(_)) => Target::Set(f[0].to_ascii_uppercase()),
                    None => {
                        return Err(err(
                            l,
                            "*KINEMATIC COUPLING needs a node or node set".into(),
                        ));
                    }
                };
                let dofs = dof_range(f.get(1).copied(), f.get(2).copied())
                    .map_err(|reason| err(l, format!("*KINEMATIC COUPLING: {reason}")))?;
                links.push(InpLink {
                    kind: LinkKind::Kinematic {
                        reference,
                        nodes: LinkNodes::Targets(vec![target]),
                        dofs,
                    },
                    line: Location {
                        path: l.path.clone(),
                        line: l.number,
                    },
                });
            }
            "KINEMATIC" | "DISTRIBUTING" => {
                let more = dof_range(f.first().copied(), f.get(1).copied())
                    .map_err(|reason| err(l, format!("*{block}: {reason}")))?;
                if let Some(InpLink {
                    kind: LinkKind::Kinematic { dofs, .. } | LinkKind::Distributing { dofs, .. },
                    ..
                }) = links.last_mut()
                {
                    dofs.extend(more);
                }
            }
            "SURFACE" => {
                let target = match f.first().map(|v| v.parse::<u64>()) {
                    Some(Ok(id)) => Target::Node(id),
                    Some(Err(_)) => Target::Set(f[0].to_ascii_uppercase()),
                    None => continue,
                };
                let w = match f.get(1) {
                    Some(v) if !v.is_empty() => parse_f64(v)
                        .filter(|w| w.is_finite() && *w > 0.0)
                        .ok_or_else(|| {
                            err(
                                l,
                                format!("*SURFACE: weight {v:?} is not a positive number"),
                            )
                        })?,
                    _ => 1.0,
                };
                if let Some(name) = &surface_now {
                    surfaces.entry(name.clone()).or_default().push((target, w));
                }
            }
            "HEADING" | "SOLID SECTION" | "STEP" | "END STEP" => {}
            _ => {} // data of an ignored keyword
        }
    }
    if !element_buffer.is_empty() {
        return Err(err(
            &lines[element_start],
            "element definition cut short at the end of the file".into(),
        ));
    }
    if let Some((n, terms, at)) = &equation {
        return Err(IoError::Parse {
            path: at.path.clone(),
            line: at.line,
            reason: format!(
                "*EQUATION announces {n} terms and gives {} before the end of the file",
                terms.len()
            ),
        });
    }
    finish_material(pending.take(), &mut materials)?;
    if let Some(c) = mass_cards.iter().find(|c| c.mass.is_nan()) {
        return Err(IoError::Parse {
            path: c.line.path.clone(),
            line: c.line.line,
            reason: "*MASS without its data line (the mass)".into(),
        });
    }
    let whole = |reason: String| IoError::Content {
        path: path.to_path_buf(),
        reason,
    };
    // build the mesh
    let model_err = |li: usize, source| IoError::Model {
        path: lines[li].path.clone(),
        line: lines[li].number,
        source,
    };
    let mut mesh = Mesh::new();
    for (id, x, li) in &nodes {
        mesh.add_node(*id, *x).map_err(|e| model_err(*li, e))?;
    }
    let mut element_lines = HashMap::new();
    for (id, kind, ids, li) in &elements {
        mesh.add_element(*id, *kind, ids)
            .map_err(|e| model_err(*li, e))?;
        element_lines.insert(
            *id,
            Location {
                path: lines[*li].path.clone(),
                line: lines[*li].number,
            },
        );
    }
    let mut node_sets: BTreeMap<String, Vec<u64>> = BTreeMap::new();
    let mut elem_sets: BTreeMap<String, Vec<u64>> = BTreeMap::new();
    for (name, ids) in node_set_of_block {
        node_sets.entry(name).or_default().extend(ids);
    }
    for (name, ids) in elem_set_of_block {
        elem_sets.entry(name).or_default().extend(ids);
    }
    for (name, is_node, tokens, generate, li) in sets {
        let l = &lines[li];
        let (what, a_what) = if is_node {
            ("node", "a node")
        } else {
            ("element", "an element")
        };
        let mut ids = Vec::new();
        if generate {
            let nums: Result<Vec<u64>, _> = tokens.iter().map(|s| s.parse::<u64>()).collect();
            let nums =
                nums.map_err(|_| err(l, format!("GENERATE needs integers, got {tokens:?}")))?;
            if nums.len() % 3 != 0 && nums.len() != 2 {
                return Err(err(
                    l,
                    format!("GENERATE needs first, last[, increment], got {tokens:?}"),
                ));
            }
            for chunk in nums.chunks(3) {
                let (a, b, inc) = (chunk[0], chunk[1], chunk.get(2).copied().unwrap_or(1));
                if inc == 0 || b < a {
                    return Err(err(l, format!("GENERATE range {a}, {b}, {inc} is invalid")));
                }
                // every generated id must exist, so a range longer than the model is an error
                // before it is an allocation
                let (count, have, what) = if is_node {
                    ((b - a) / inc + 1, mesh.node_count(), "nodes")
                } else {
                    ((b - a) / inc + 1, mesh.element_count(), "elements")
                };
                if count > have as u64 {
                    return Err(err(
                        l,
                        format!(
                            "GENERATE range {a}, {b}, {inc} names {count} ids; the model has {have} {what}"
                        ),
                    ));
                }
                ids.extend((a..=b).step_by(inc as usize));
            }
        } else {
            for tok in &tokens {
                match tok.parse::<u64>() {
                    Ok(id) => ids.push(id),
                    Err(_) => {
                        let key = tok.to_ascii_uppercase();
                        let src = if is_node { &node_sets } else { &elem_sets };
                        let members = src.get(&key).ok_or_else(|| {
                            let hint = crate::spelling::suggestion(
                                &key,
                                src.keys().map(String::as_str),
                                "",
                            );
                            err(
                                l,
                                format!(
                                    "*{}SET {name} names {tok}, which is neither {a_what} id nor {a_what} set defined before it{hint}",
                                    if is_node { "N" } else { "EL" }
                                ),
                            )
                        })?;
                        ids.extend(members.iter().copied());
                    }
                }
            }
        }
        // every id listed here must exist: the error names this set and its line
        let exists = |id: &u64| {
            if is_node {
                mesh.node_index(*id).is_some()
            } else {
                mesh.element_index(*id).is_some()
            }
        };
        if let Some(bad) = ids.iter().find(|id| !exists(id)) {
            return Err(err(
                l,
                format!("{what} set {name} lists {what} {bad}, which the deck does not define"),
            ));
        }
        if is_node {
            &mut node_sets
        } else {
            &mut elem_sets
        }
        .entry(name)
        .or_default()
        .extend(ids);
    }
    if nodes.is_empty() {
        return Err(whole(if lines.iter().all(|l| l.text.trim().is_empty()) {
            "the deck is empty: an Abaqus/CalculiX deck needs *NODE, *ELEMENT, *MATERIAL and *SOLID SECTION".into()
        } else {
            "the deck defines no nodes (*NODE)".into()
        }));
    }
    if elements.is_empty() {
        return Err(whole(format!(
            "the deck defines {} nodes and no elements (*ELEMENT, TYPE=C3D8 and the other solids)",
            nodes.len()
        )));
    }
    // the ids were checked where each set was defined
    for (name, ids) in &node_sets {
        mesh.add_node_set(name.clone(), ids)
            .map_err(|e| whole(format!("node set {name}: {e}")))?;
    }
    for (name, ids) in &elem_sets {
        mesh.add_element_set(name.clone(), ids)
            .map_err(|e| whole(format!("element set {name}: {e}")))?;
    }
    // mass elements: their nodes exist, their ids are not those of solids
    let mut point_masses = Vec::new();
    for (id, node, li) in &mass_elements {
        if mesh.node_index(*node).is_none() {
            return Err(err(
                &lines[*li],
                format!("MASS element {id} is on node {node}, which the deck does not define"),
            ));
        }
        if mesh.element_index(*id).is_some() {
            return Err(err(
                &lines[*li],
                format!("MASS element {id} has the id of a solid element"),
            ));
        }
    }
    for c in &mass_cards {
        let members = mass_sets.get(&c.elset).ok_or_else(|| {
            let hint =
                crate::spelling::suggestion(&c.elset, mass_sets.keys().map(String::as_str), "");
            let solid = elem_sets.contains_key(&c.elset);
            IoError::Parse {
                path: c.line.path.clone(),
                line: c.line.line,
                reason: if solid {
                    format!(
                        "*MASS names element set {}, a set of solid elements: a *MASS gives the mass of the one-node elements of an *ELEMENT, TYPE=MASS set",
                        c.elset
                    )
                } else {
                    format!(
                        "*MASS names element set {}, which no *ELEMENT, TYPE=MASS defines{hint}",
                        c.elset
                    )
                },
            }
        })?;
        for id in members {
            let (_, node, _) = mass_elements.iter().find(|e| e.0 == *id).expect("listed");
            point_masses.push((*node, c.mass, c.line.clone()));
        }
    }
    Ok(InpDeck {
        mesh,
        materials,
        sections,
        boundaries,
        point_masses,
        links,
        surfaces,
        frequency,
        warnings: std::mem::take(warnings),
        element_lines,
        path: path.to_path_buf(),
    })
}

impl InpDeck {
    /// The model: mesh (validated), materials by section, fixed DOFs.
    ///
    /// # Errors
    /// [`IoError::Model`] naming the line of an invalid element (inverted, degenerate), a section
    /// on an unknown set or material, a boundary on an unknown node or set; elements without a
    /// section.
    pub fn to_model(&self) -> Result<Model, IoError> {
        self.build_model().map_err(|e| e.after(&self.warnings))
    }

    /// Where element `id` was defined, or the deck itself.
    fn at_element(&self, id: Option<u64>, source: femu_fem::FemError) -> IoError {
        match id.and_then(|id| self.element_lines.get(&id)) {
            Some(l) => IoError::Model {
                path: l.path.clone(),
                line: l.line,
                source,
            },
            None => IoError::Content {
                path: self.path.clone(),
                reason: source.to_string(),
            },
        }
    }

    fn build_model(&self) -> Result<Model, IoError> {
        let mut model = Model::new(self.mesh.clone())
            .map_err(|source| self.at_element(element_of(&source), source))?;
        for s in &self.sections {
            let material = self.materials.get(&s.material).ok_or_else(|| {
                let hint = crate::spelling::suggestion(
                    &s.material,
                    self.materials.keys().map(String::as_str),
                    "",
                );
                IoError::Parse {
                    path: s.line.path.clone(),
                    line: s.line.line,
                    reason: format!(
                        "*SOLID SECTION names material {}, which no *MATERIAL defines{hint}",
                        s.material
                    ),
                }
            })?;
            if self.mesh.element_sets().get(&s.elset).is_none() {
                let hint = crate::spelling::suggestion(
                    &s.elset,
                    self.mesh.element_sets().keys().map(String::as_str),
                    "",
                );
                return Err(IoError::Parse {
                    path: s.line.path.clone(),
                    line: s.line.line,
                    reason: format!(
                        "*SOLID SECTION names element set {}, which the deck does not define{hint}",
                        s.elset
                    ),
                });
            }
            model
                .set_material(Some(&s.elset), material.clone())
                .map_err(|source| IoError::Model {
                    path: s.line.path.clone(),
                    line: s.line.line,
                    source,
                })?;
        }
        self.apply_links(&mut model)?;
        for b in &self.boundaries {
            let all: Vec<usize> = (b.first - 1..b.last).collect();
            let comps: Vec<usize> = all.iter().copied().filter(|c| *c < 3).collect();
            // rotations: on the nodes that have them (coupling references)
            let rotations: Vec<usize> = all.iter().copied().filter(|c| *c >= 3).collect();
            if !rotations.is_empty() {
                let nodes: Vec<usize> = match &b.target {
                    Target::Node(id) => model.mesh().node_index(*id).into_iter().collect(),
                    Target::Set(s) => self.mesh.node_sets().get(s).cloned().unwrap_or_default(),
                };
                for n in nodes {
                    if model.rotation_nodes().contains(&n) {
                        let id = model.mesh().node_id(n);
                        model
                            .fix_node_dofs(id, &rotations)
                            .map_err(|source| IoError::Model {
                                path: b.line.path.clone(),
                                line: b.line.line,
                                source,
                            })?;
                    }
                }
            }
            if comps.is_empty() {
                continue;
            }
            let r = match &b.target {
                Target::Node(id) => model.fix_nodes(&[*id], &comps),
                Target::Set(s) => {
                    if self.mesh.node_sets().get(s).is_none() {
                        let hint = crate::spelling::suggestion(
                            s,
                            self.mesh.node_sets().keys().map(String::as_str),
                            "",
                        );
                        return Err(IoError::Parse {
                            path: b.line.path.clone(),
                            line: b.line.line,
                            reason: format!(
                                "*BOUNDARY names {s}, which is neither a node id nor a node set of the deck{hint}"
                            ),
                        });
                    }
                    model.fix_set(s, &comps)
                }
            };
            r.map_err(|source| IoError::Model {
                path: b.line.path.clone(),
                line: b.line.line,
                source,
            })?;
        }
        // point masses, on nodes that solid elements or constraints connect (a mass on a free
        // node would have no stiffness)
        let mut connected = model.constrained_nodes();
        for el in model.mesh().elements() {
            for n in el.nodes {
                connected[*n] = true;
            }
        }
        for (node, mass, at) in &self.point_masses {
            let located = |reason: String| IoError::Parse {
                path: at.path.clone(),
                line: at.line,
                reason,
            };
            let i = model.mesh().node_index(*node).ok_or_else(|| {
                located(format!(
                    "*MASS on node {node}, which the deck does not define"
                ))
            })?;
            if !connected[i] {
                return Err(located(format!(
                    "*MASS on node {node}, which no solid element or constraint connects: it would have no stiffness"
                )));
            }
            model
                .add_point_mass(*node, *mass)
                .map_err(|source| IoError::Model {
                    path: at.path.clone(),
                    line: at.line,
                    source,
                })?;
        }
        // every element needs a material
        for e in 0..model.mesh().element_count() {
            if let Err(source) = model.material_of(e) {
                let id = model.mesh().element(e).id;
                return Err(self.at_element(Some(id), source));
            }
        }
        // conflicts between constraints (a DOF dependent twice or also fixed, cycles) now
        model.dof_map().map_err(|source| IoError::Content {
            path: self.path.clone(),
            reason: source.to_string(),
        })?;
        Ok(model)
    }

    /// Node ids of a target (a node, or a node set of the deck).
    fn target_ids(&self, t: &Target, at: &Location, what: &str) -> Result<Vec<u64>, IoError> {
        match t {
            Target::Node(id) => Ok(vec![*id]),
            Target::Set(s) => match self.mesh.node_sets().get(s) {
                Some(nodes) => Ok(nodes.iter().map(|n| self.mesh.node_id(*n)).collect()),
                None => {
                    let hint = crate::spelling::suggestion(
                        s,
                        self.mesh.node_sets().keys().map(String::as_str),
                        "",
                    );
                    Err(IoError::Parse {
                        path: at.path.clone(),
                        line: at.line,
                        reason: format!(
                            "{what} names {s}, which is neither a node id nor a node set of the deck{hint}"
                        ),
                    })
                }
            },
        }
    }

    /// The coupled nodes and their weights.
    fn link_nodes(
        &self,
        nodes: &LinkNodes,
        at: &Location,
        what: &str,
    ) -> Result<Vec<(u64, f64)>, IoError> {
        let mut out = Vec::new();
        match nodes {
            LinkNodes::Targets(ts) => {
                for t in ts {
                    out.extend(self.target_ids(t, at, what)?.into_iter().map(|i| (i, 1.0)));
                }
            }
            LinkNodes::Surface(name) => {
                let list = self.surfaces.get(name).ok_or_else(|| IoError::Parse {
                    path: at.path.clone(),
                    line: at.line,
                    reason: format!(
                        "{what}: surface {name} is not defined (femu reads *SURFACE, TYPE=NODE){}",
                        crate::spelling::suggestion(
                            name,
                            self.surfaces.keys().map(String::as_str),
                            ""
                        )
                    ),
                })?;
                for (t, w) in list {
                    out.extend(self.target_ids(t, at, what)?.into_iter().map(|i| (i, *w)));
                }
            }
        }
        Ok(out)
    }

    /// The deck's couplings and equations into `model`: kinematic couplings first (their
    /// references get rotations), then distributing couplings, then equations (which may name
    /// the references' rotations, DOFs 4-6).
    fn apply_links(&self, model: &mut Model) -> Result<(), IoError> {
        for pass in 0..3 {
            for link in &self.links {
                let at = &link.line;
                let located = |source| IoError::Model {
                    path: at.path.clone(),
                    line: at.line,
                    source,
                };
                match (&link.kind, pass) {
                    (
                        LinkKind::Kinematic {
                            reference,
                            nodes,
                            dofs,
                        },
                        0,
                    ) => {
                        let label = format!(
                            "kinematic coupling to node {reference} ({} line {})",
                            at.path.display(),
                            at.line
                        );
                        let ids = self.link_nodes(nodes, at, "*KINEMATIC COUPLING")?;
                        let ids: Vec<u64> = ids.into_iter().map(|p| p.0).collect();
                        let all: &[usize] = if dofs.is_empty() {
                            &[1, 2, 3, 4, 5, 6]
                        } else {
                            dofs
                        };
                        let trans: Vec<usize> =
                            all.iter().filter(|d| **d <= 3).map(|d| d - 1).collect();
                        model
                            .add_rigid_link(*reference, &ids, &trans, &label)
                            .map_err(located)?;
                        // coupled nodes that carry rotations follow the reference's
                        for &id in &ids {
                            let has = model
                                .mesh()
                                .node_index(id)
                                .is_some_and(|n| model.rotation_nodes().contains(&n));
                            if has && id != *reference {
                                for d in all.iter().filter(|d| **d > 3) {
                                    model
                                        .add_constraint(
                                            (id, d - 1),
                                            &[((*reference, d - 1), 1.0)],
                                            &label,
                                        )
                                        .map_err(located)?;
                                }
                            }
                        }
                    }
                    (
                        LinkKind::Distributing {
                            reference,
                            nodes,
                            dofs,
                        },
                        1,
                    ) => {
                        let label = format!(
                            "distributing coupling of node {reference} ({} line {})",
                            at.path.display(),
                            at.line
                        );
                        let pairs = self.link_nodes(nodes, at, "*DISTRIBUTING")?;
                        let has_rot = model
                            .mesh()
                            .node_index(*reference)
                            .is_some_and(|n| model.rotation_nodes().contains(&n));
                        let all: &[usize] = if dofs.is_empty() {
                            &[1, 2, 3, 4, 5, 6]
                        } else {
                            dofs
                        };
                        let comps: Vec<usize> = all
                            .iter()
                            .filter(|d| **d <= 3 || has_rot)
                            .map(|d| d - 1)
                            .collect();
                        model
                            .add_weighted_average(*reference, &comps, &pairs, &label)
                            .map_err(located)?;
                    }
                    (LinkKind::Equation(terms), 2) => {
                        let label = format!("*EQUATION ({} line {})", at.path.display(), at.line);
                        let (n0, d0, a0) = terms[0];
                        if a0 == 0.0 {
                            return Err(IoError::Parse {
                                path: at.path.clone(),
                                line: at.line,
                                reason: "*EQUATION: the first coefficient (of the dependent DOF) is zero".into(),
                            });
                        }
                        let rest: Vec<((u64, usize), f64)> = terms[1..]
                            .iter()
                            .map(|(n, d, a)| ((*n, d - 1), -a / a0))
                            .collect();
                        model
                            .add_constraint((n0, d0 - 1), &rest, &label)
                            .map_err(located)?;
                    }
                    _ => {}
                }
            }
        }
        Ok(())
    }
}

fn element_of(e: &femu_fem::FemError) -> Option<u64> {
    use femu_fem::FemError as E;
    match e {
        E::InvertedElement { element, .. } | E::DegenerateElement { element, .. } => Some(*element),
        _ => None,
    }
}

/// A number for a deck field: the shortest representation that reads back exactly, or, when that
/// is longer than CalculiX's 20-character fields (17 digits with a sign or an exponent), 14
/// significant digits (relative error at most 5e-14).
fn number_field(v: f64) -> String {
    let exact = format!("{v:?}");
    if exact.len() <= 20 {
        exact
    } else {
        format!("{v:.13e}")
    }
}

/// A CalculiX deck for `model` (nodes, elements grouped by kind, the mesh's sets, one material and
/// section per distinct material, fixed DOFs, and a `*FREQUENCY` step when `step` is given).
/// Sets named `NALL`, `EALL` and `FEMU_MAT*` are the writer's own and are regenerated, so writing
/// a deck that was read gives the same deck.
///
/// # Errors
/// An element without material; an anisotropic material (not written yet).
pub fn inp_string(model: &Model, step: Option<&FrequencyStep>) -> Result<String, IoError> {
    let mesh = model.mesh();
    let unwritable = |reason: String| IoError::Content {
        path: PathBuf::from("<model>"),
        reason,
    };
    if let Some(e) = mesh
        .elements()
        .find(|e| matches!(e.kind, ElementKind::Pyramid5 | ElementKind::Pyramid13))
    {
        return Err(unwritable(format!(
            "element {} is a {}: Abaqus and CalculiX have no pyramid element (write the model as VTK, or keep its Nastran deck)",
            e.id, e.kind
        )));
    }
    let mut s = String::from("*HEADING\nwritten by femu\n*NODE, NSET=NALL\n");
    for i in 0..mesh.node_count() {
        let x = mesh.coords()[i];
        let _ = writeln!(
            s,
            "{}, {}, {}, {}",
            mesh.node_id(i),
            number_field(x[0]),
            number_field(x[1]),
            number_field(x[2])
        );
    }
    for kind in femu_fem::element::ALL_KINDS {
        let els: Vec<_> = mesh.elements().filter(|e| e.kind == kind).collect();
        if els.is_empty() {
            continue;
        }
        let _ = writeln!(s, "*ELEMENT, TYPE={}, ELSET=EALL", kind.abaqus_name());
        for el in els {
            let ids: Vec<String> = std::iter::once(el.id)
                .chain(el.nodes.iter().map(|n| mesh.node_id(*n)))
                .map(|v| v.to_string())
                .collect();
            // at most 16 entries per line; a trailing comma continues the definition
            for (c, chunk) in ids.chunks(16).enumerate() {
                let last = (c + 1) * 16 >= ids.len();
                let _ = writeln!(s, "{}{}", chunk.join(", "), if last { "" } else { "," });
            }
        }
    }
    let write_ids = |s: &mut String, ids: Vec<u64>| {
        for chunk in ids.chunks(16) {
            let t: Vec<String> = chunk.iter().map(|v| v.to_string()).collect();
            let _ = writeln!(s, "{}", t.join(", "));
        }
    };
    // the sets this writer generates itself are not copied (a read deck has them)
    let generated = |name: &str| {
        let u = name.to_ascii_uppercase();
        u == "NALL" || u == "EALL" || u.starts_with("FEMU_MAT")
    };
    for (name, nodes) in mesh.node_sets().iter().filter(|(n, _)| !generated(n)) {
        let _ = writeln!(s, "*NSET, NSET={name}");
        write_ids(&mut s, nodes.iter().map(|n| mesh.node_id(*n)).collect());
    }
    for (name, els) in mesh.element_sets().iter().filter(|(n, _)| !generated(n)) {
        let _ = writeln!(s, "*ELSET, ELSET={name}");
        write_ids(&mut s, els.iter().map(|e| mesh.element(*e).id).collect());
    }
    // distinct materials, in order of first use in the written element order (so that a deck read
    // back and written again is the same text)
    let mut distinct: Vec<(Material, Vec<u64>)> = Vec::new();
    let written_order = femu_fem::element::ALL_KINDS
        .iter()
        .flat_map(|k| {
            mesh.elements()
                .filter(move |e| e.kind == *k)
                .map(|e| e.index)
        })
        .collect::<Vec<_>>();
    for e in written_order {
        let m = model
            .material_of(e)
            .map_err(|e| unwritable(e.to_string()))?;
        let id = mesh.element(e).id;
        match distinct.iter_mut().find(|(d, _)| d == m) {
            Some(d) => d.1.push(id),
            None => distinct.push((m.clone(), vec![id])),
        }
    }
    for (i, (m, ids)) in distinct.iter().enumerate() {
        let Elasticity::Isotropic { e, nu } = &m.elasticity else {
            return Err(unwritable(format!(
                "material {} is anisotropic: not written yet",
                m.name
            )));
        };
        // the material's own name when it is a valid Abaqus name not used before
        let clean: String = m
            .name
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || c == '_' || c == '-' {
                    c
                } else {
                    '_'
                }
            })
            .collect();
        let taken = distinct[..i]
            .iter()
            .any(|(d, _)| d.name.eq_ignore_ascii_case(&m.name));
        let valid = clean.starts_with(|c: char| c.is_ascii_alphabetic()) && clean.len() <= 80;
        let name = if valid && !taken {
            clean
        } else {
            format!("FEMU_MAT{}", i + 1)
        };
        let _ = writeln!(s, "*ELSET, ELSET=FEMU_MAT{}", i + 1);
        write_ids(&mut s, ids.clone());
        let _ = writeln!(
            s,
            "*MATERIAL, NAME={name}\n*ELASTIC\n{}, {}\n*DENSITY\n{}",
            number_field(*e),
            number_field(*nu),
            number_field(m.density)
        );
        let _ = writeln!(
            s,
            "*SOLID SECTION, ELSET=FEMU_MAT{}, MATERIAL={name}",
            i + 1
        );
    }
    // point masses: one MASS element each (ids after the solids'), a *MASS per element; a rigid
    // mass without offset or inertia is one too
    let first_id = mesh.elements().map(|e| e.id).max().unwrap_or(0) + 1;
    let mut masses: Vec<femu_fem::model::PointMass> = model.point_masses().to_vec();
    for r in model.rigid_masses() {
        if r.offset
            .iter()
            .chain(r.inertia.iter().flatten())
            .any(|v| *v != 0.0)
        {
            return Err(unwritable(format!(
                "the rigid mass on node {} has an offset or rotary inertia, which CalculiX's *MASS cannot state",
                mesh.node_id(r.node)
            )));
        }
        let m = r.mass;
        masses.push(femu_fem::model::PointMass {
            node: r.node,
            mass: [[m, 0.0, 0.0], [0.0, m, 0.0], [0.0, 0.0, m]],
        });
    }
    for (k, p) in masses.iter().enumerate() {
        let m = p.mass[0][0];
        let isotropic =
            (0..3).all(|i| (0..3).all(|j| p.mass[i][j] == if i == j { m } else { 0.0 }));
        if !isotropic {
            return Err(IoError::Content {
                path: PathBuf::from("(deck being written)"),
                reason: format!(
                    "the point mass on node {} differs by direction ({:?}): *MASS gives one mass for all three",
                    mesh.node_id(p.node),
                    p.mass
                ),
            });
        }
        let id = first_id + k as u64;
        let _ = writeln!(
            s,
            "*ELEMENT, TYPE=MASS, ELSET=FEMU_MASS{id}\n{id}, {}\n*MASS, ELSET=FEMU_MASS{id}\n{}",
            mesh.node_id(p.node),
            number_field(m)
        );
    }
    // rotations of reference nodes: as CalculiX's rotational nodes, an extra node per reference
    // (ids after the mesh's) whose translations 1-3 are the reference's rotations 4-6
    let first_rot = (0..mesh.node_count())
        .map(|i| mesh.node_id(i))
        .max()
        .unwrap_or(0)
        + 1;
    let rot_id = |n: usize| -> Option<u64> {
        model
            .rotation_nodes()
            .iter()
            .position(|r| *r == n)
            .map(|k| first_rot + k as u64)
    };
    let dof = |n: usize, c: usize| -> (u64, usize) {
        if c < 3 {
            (mesh.node_id(n), c + 1)
        } else {
            (rot_id(n).expect("rotations on a rotation node"), c - 2)
        }
    };
    if !model.rotation_nodes().is_empty() {
        s.push_str("** rotational nodes: their DOFs 1-3 are the rotations of the node named\n*NODE, NSET=FEMU_ROT\n");
        for &n in model.rotation_nodes() {
            let x = mesh.coords()[n];
            let _ = writeln!(
                s,
                "{}, {}, {}, {}\n** rotations of node {}",
                rot_id(n).expect("listed"),
                number_field(x[0]),
                number_field(x[1]),
                number_field(x[2]),
                mesh.node_id(n)
            );
        }
    }
    let (rot_fixed, rot_constraints) = model.rotation_closure();
    for con in model.constraints().iter().chain(&rot_constraints) {
        let _ = writeln!(s, "** {}\n*EQUATION\n{}", con.label, 1 + con.terms.len());
        let mut terms = vec![(dof(con.dependent.0, con.dependent.1), 1.0)];
        terms.extend(con.terms.iter().map(|((n, c), w)| (dof(*n, *c), -w)));
        for chunk in terms.chunks(4) {
            let t: Vec<String> = chunk
                .iter()
                .map(|((id, d), a)| format!("{id}, {d}, {}", number_field(*a)))
                .collect();
            let _ = writeln!(s, "{}", t.join(", "));
        }
    }
    let fixed: Vec<(usize, usize)> = model.fixed_dofs().chain(rot_fixed).collect();
    if !fixed.is_empty() {
        s.push_str("*BOUNDARY\n");
        for (n, c) in fixed {
            let (id, d) = dof(n, c);
            let _ = writeln!(s, "{id}, {d}, {d}");
        }
    }
    if let Some(step) = step {
        s.push_str("*STEP\n*FREQUENCY\n");
        match step.shift_cycles2 {
            Some(shift) => {
                let _ = writeln!(s, "{}, , {}", step.count, number_field(shift));
            }
            None => {
                let _ = writeln!(s, "{}", step.count);
            }
        }
        s.push_str("*NODE FILE\nU\n*END STEP\n");
    }
    Ok(s)
}

/// Writes [`inp_string`] to `path`.
///
/// # Errors
/// As [`inp_string`], or [`IoError::Io`].
pub fn write_inp(
    model: &Model,
    step: Option<&FrequencyStep>,
    path: impl AsRef<Path>,
) -> Result<(), IoError> {
    let text = inp_string(model, step)?;
    std::fs::write(path.as_ref(), text).map_err(|e| IoError::io(path.as_ref(), e))
}
