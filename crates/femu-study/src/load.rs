//! Loading a model and a test the way every workflow does: read the file by its extension, build
//! and check the model, assemble `K` and `M` once, and map the test's sensors onto the model.

use crate::StudyError;
use femu_correlate::mapping::{MapOptions, Mapping};
use femu_correlate::{CorrelateError, SensorLayout};
use femu_fem::assembly::{Assembler, MassKind, SystemMatrices};
use femu_fem::element::Formulation;
use femu_fem::material::Material;
use femu_fem::model::Model;
use femu_io::inp::FrequencyStep;
use femu_io::{Format, TestData};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// An isotropic material for a mesh-only model (Gmsh `.msh`, universal file solids).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialOptions {
    /// Young's modulus, Pa.
    pub young: f64,
    /// Poisson's ratio.
    pub poisson: f64,
    /// Density, kg/m^3.
    pub density: f64,
    /// The structural damping coefficient `GE` of every element (solids, shells, beams): `i GE
    /// K_e` in a frequency response, as a Nastran MAT1's `GE` or an Abaqus `*DAMPING,
    /// STRUCTURAL` (docs/MATH.md, "Frequency responses, directly"); 0, the default: none.
    #[serde(default)]
    pub structural_damping: f64,
}

/// How to turn a model file into a model.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ModelOptions {
    /// The material of a mesh-only model (required for `.msh`/`.unv`, not used for an `.inp`
    /// deck, which has its own).
    pub material: Option<MaterialOptions>,
    /// Node sets (Gmsh physical groups, UFF groups) to clamp in a mesh-only model (their
    /// rotations too where shells give them rotations).
    pub fix: Vec<String>,
    /// Shell sections of a Gmsh mesh: each named physical group of surfaces (3- and 6-node
    /// triangles, 4- and 8-node quadrangles) becomes shells of this thickness (m) in the model's
    /// material.
    pub shells: Vec<(String, f64)>,
    /// Beam sections of a Gmsh mesh: each named physical group of 2- or 3-node lines becomes
    /// Timoshenko beams of this section in the model's material, written as Abaqus' `*BEAM
    /// SECTION` shapes: `rect:A,B`, `circ:R` or `pipe:R,T`, with `@X,Y,Z` for the direction of
    /// the section's 1-axis (`n1`; default `0,0,-1`, Abaqus' default).
    pub beams: Vec<(String, String)>,
    /// Lumped (row-sum/HRZ) instead of consistent mass.
    pub lumped: bool,
    /// Unknown keywords in an `.inp` deck are warnings instead of errors
    /// ([`femu_io::inp::InpOptions::lenient`]).
    pub lenient: bool,
    /// How the 8-node bricks of a mesh-only model form their stiffness (a deck states its own:
    /// C3D8 or C3D8I, or the PSOLID's `IN` and `ISOP`; docs/MATH.md, "The brick with
    /// incompatible modes").
    pub bricks: Formulation,
    /// The node coordinates of a model read as another solver's matrices (a deck's `*NODE`
    /// lines or a `node,x,y,z` table); by default the deck or table beside the matrices
    /// ([`femu_io::matrices::default_node_table`]).
    pub nodes: Option<PathBuf>,
}

impl ModelOptions {
    /// The mass kind.
    pub fn mass(&self) -> MassKind {
        if self.lumped {
            MassKind::Lumped
        } else {
            MassKind::Consistent
        }
    }
}

/// Physical groups of a Gmsh mesh made structural elements in the material `mat`: the shells of
/// `options.shells` (group, thickness) on its surfaces (MITC4 and 8-node quadrangles, MITC3 triangles,
/// a solid section: `12I/T^3 = 1`, `TS/T = 5/6`) and the beams of `options.beams` (group,
/// section) on its lines; each group an element set of its name. A mesh without volume elements
/// needs one or the other.
///
/// # Errors
/// A group that is not a physical group of surfaces or lines (the groups it has named), a
/// thickness that is not positive, a section that is not read, an element type femu does not
/// build (named with its line), a bad element (its id).
fn add_sections(
    model: &mut Model,
    (surfaces, curves): (&Groups, &Groups),
    options: &ModelOptions,
    mat: &MaterialOptions,
    path: &Path,
) -> Result<(), StudyError> {
    use femu_fem::structural::{Beam, BeamSection, StructuralKind};
    let names = |g: &Groups| {
        if g.is_empty() {
            "none".to_string()
        } else {
            g.keys().cloned().collect::<Vec<_>>().join(", ")
        }
    };
    if options.shells.is_empty() && options.beams.is_empty() && model.mesh().element_count() == 0 {
        return Err(StudyError::in_file(
            path,
            "sections",
            format!(
                "no volume elements: give the surface groups a shell thickness (--shell GROUP=THICKNESS, [shells] in a study file) or the line groups a beam section (--beam GROUP=rect:A,B, [beams]); the physical groups of surfaces: {}; of lines: {}",
                names(surfaces),
                names(curves)
            ),
        ));
    }
    for (group, t) in &options.shells {
        if !(t.is_finite() && *t > 0.0) {
            return Err(StudyError::invalid(
                "shell thickness",
                format!("{group} = {t}: a shell's thickness is a positive length (m)"),
            ));
        }
        let shell = femu_fem::shell::Shell {
            e: mat.young,
            nu: mat.poisson,
            rho: mat.density,
            t: *t,
            bending: 1.0,
            shear: Some(5.0 / 6.0),
            nsm: 0.0,
            material: None,
            offset: 0.0,
            membrane: femu_fem::shell::Membrane::Incompatible,
        };
        add_group(
            model,
            surfaces,
            (group, "surfaces", &[2, 3, 9, 16]),
            path,
            StructuralKind::Shell(shell),
        )?;
    }
    for (group, spec) in &options.beams {
        let (shape, dims, n1) = beam_spec(spec)
            .map_err(|r| StudyError::invalid("beam section", format!("{group} = {spec}: {r}")))?;
        let (area, i1, i2, j, shear) = femu_io::inp::section_shape(&shape, &dims)
            .map_err(|r| StudyError::invalid("beam section", format!("{group} = {spec}: {r}")))?;
        let beam = Beam {
            e: mat.young,
            g: mat.young / (2.0 * (1.0 + mat.poisson)),
            rho: mat.density,
            section: BeamSection {
                area,
                i1,
                i2,
                j,
                shear: Some(shear),
                nsm: 0.0,
            },
            taper: None,
            orientation: n1,
            offsets: [[0.0; 3]; 2],
            lumped_torsion: false,
            coupled_torsion: true,
            releases: [[false; 6]; 2],
        };
        add_group(
            model,
            curves,
            (group, "lines", &[1, 8]),
            path,
            StructuralKind::Beam(beam),
        )?;
    }
    Ok(())
}

/// A Gmsh mesh's physical groups of surfaces or lines, by name.
type Groups = std::collections::BTreeMap<String, Vec<femu_io::gmsh::GroupElement>>;

/// `SHAPE:D1,D2[@X,Y,Z]` as (the shape in capitals, its dimensions, `n1`).
fn beam_spec(spec: &str) -> Result<(String, Vec<f64>, [f64; 3]), String> {
    let (section, n1) = match spec.split_once('@') {
        Some((s, v)) => (s, Some(v)),
        None => (spec, None),
    };
    let (shape, dims) = section
        .split_once(':')
        .ok_or("give SHAPE:DIMENSIONS (rect:A,B, circ:R or pipe:R,T)")?;
    let numbers = |s: &str| -> Result<Vec<f64>, String> {
        s.split(',')
            .map(|v| {
                v.trim()
                    .parse::<f64>()
                    .map_err(|_| format!("'{}' is not a number", v.trim()))
            })
            .collect()
    };
    let n1 = match n1 {
        Some(v) => {
            let v = numbers(v)?;
            let [x, y, z] = v[..] else {
                return Err(format!("n1 needs three components, got {}", v.len()));
            };
            [x, y, z]
        }
        None => [0.0, 0.0, -1.0],
    };
    Ok((shape.trim().to_uppercase(), numbers(dims)?, n1))
}

/// The elements of the physical group `group` of `groups` (of `what`, Gmsh types `types`) added
/// as structural elements of the kind `kind`, and an element set of the group's name.
fn add_group(
    model: &mut Model,
    groups: &Groups,
    (group, what, types): (&str, &str, &[i64]),
    path: &Path,
    kind: femu_fem::structural::StructuralKind,
) -> Result<(), StudyError> {
    use femu_fem::structural::StructuralElement;
    let Some(elements) = groups.get(group) else {
        return Err(StudyError::in_file(
            path,
            "sections",
            format!(
                "no physical group of {what} {group} (the mesh's: {})",
                if groups.is_empty() {
                    "none".to_string()
                } else {
                    groups.keys().cloned().collect::<Vec<_>>().join(", ")
                }
            ),
        ));
    };
    let mut ids = Vec::with_capacity(elements.len());
    for f in elements {
        if !types.contains(&f.gmsh_type) {
            return Err(StudyError::in_file(
                path,
                "sections",
                format!(
                    "line {}: element {} of {group} is of Gmsh type {}: femu builds {what} of type{} {:?} (3-node triangles 2, 4-node quadrangles 3, 6-node triangles 9, 8-node quadrangles 16, 2-node lines 1, 3-node lines 8)",
                    f.line,
                    f.tag,
                    f.gmsh_type,
                    if types.len() == 1 { "" } else { "s" },
                    types
                ),
            ));
        }
        let nodes = f
            .nodes
            .iter()
            .map(|n| {
                model.mesh().node_index(*n).ok_or_else(|| {
                    StudyError::in_file(
                        path,
                        "sections",
                        format!("line {}: element {} has no node {n}", f.line, f.tag),
                    )
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        model
            .add_structural(StructuralElement {
                id: f.tag,
                nodes,
                kind,
            })
            .map_err(|e| StudyError::within(path, e))?;
        ids.push(f.tag);
    }
    model
        .add_structural_set(group.to_string(), &ids)
        .map_err(|e| StudyError::within(path, e))?;
    Ok(())
}

/// Where loading a model spent its time, s (what `femu modes` prints and writes under `load`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct LoadTimings {
    /// Reading the file and building the model (mesh checks, materials, constraints).
    pub read_seconds: f64,
    /// The model's checks before assembly (nodes without elements, units).
    pub checks_seconds: f64,
    /// The sparsity pattern and the element colouring.
    pub pattern_seconds: f64,
    /// The parallel assembly of `K` and `M`, with the ordering and the symbolic analysis of `K`
    /// made on one thread beside it.
    pub assembly_seconds: f64,
}

/// A model read, checked and assembled once.
#[derive(Debug, Clone)]
pub struct LoadedModel {
    /// The file it came from.
    pub path: PathBuf,
    /// The model.
    pub model: Model,
    /// `K` and `M` on the free DOFs, with the DOF map.
    pub sys: SystemMatrices,
    /// The pattern and colouring `sys` was assembled with (reused by updating).
    pub asm: Assembler,
    /// The deck's `*FREQUENCY` step, if any.
    pub frequency: Option<FrequencyStep>,
    /// The Nastran deck's `EIGRL` (the one its case control's `METHOD` selects): `V1`, `V2` in Hz
    /// and `ND`, which `femu modes` honours unless told otherwise.
    pub eigrl: Option<femu_io::nastran::Eigrl>,
    /// What the readers noticed and the options that did not apply, one line each.
    pub warnings: Vec<String>,
    /// Where loading spent its time.
    pub timings: LoadTimings,
    /// For a model read as another solver's `K` and `M`: where they came from (the model then has
    /// nodes and no elements).
    pub matrices: Option<crate::external::MatrixOrigin>,
}

/// A test read and mapped onto a model.
#[derive(Debug, Clone)]
pub struct LoadedTest {
    /// The file it came from.
    pub path: PathBuf,
    /// The sensors and the modes, as read.
    pub data: TestData,
    /// The sensors on the model's DOFs.
    pub layout: SensorLayout,
    /// The mapping table, when the test was mapped ([`TestOptions::map`]).
    pub mapping: Option<Mapping>,
    /// What the reader noticed (a complex mode made real although it is far from real).
    pub warnings: Vec<String>,
}

/// A warning when `path` is read as `format` by its content rather than its extension (a Nastran
/// deck named `.inp`, as MSC names its examples).
pub(crate) fn read_by_content(path: &Path, format: Format) -> Option<String> {
    let inp = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("inp"));
    (inp && format == Format::Nastran).then(|| {
        format!(
            "{}: read as Nastran bulk data: its first lines are a Nastran deck's (SOL, CEND, BEGIN BULK or a card), though it is named .inp",
            path.display()
        )
    })
}

/// Reads a model: an Abaqus/CalculiX `.inp` deck or Nastran bulk data (`.bdf`, `.dat`, `.nas`;
/// materials, constraints and point masses inside), or a mesh
/// (Gmsh `.msh`, universal file `.unv`/`.uff` with datasets 2411/2412) with the material and
/// clamped sets of `options`; then assembles `K` and `M`.
///
/// # Errors
/// The readers' errors (file and line), a mesh without a material, an unknown set to fix, and
/// assembly errors (naming the element).
pub fn load_model(path: &Path, options: &ModelOptions) -> Result<LoadedModel, StudyError> {
    let start = std::time::Instant::now();
    let mut warnings = Vec::new();
    let format = Format::from_path(path)
        .filter(|f| f.info().model)
        .ok_or_else(|| {
            StudyError::in_file(
                path,
                "model",
                format!(
                    "femu reads models as {}; the file's extension is none of them",
                    femu_io::format::described(true)
                ),
            )
        })?;
    warnings.extend(read_by_content(path, format));
    if format == Format::Matrices {
        return load_matrices(path, options, start);
    }
    if format == Format::Results {
        return Err(StudyError::in_file(
            path,
            "model",
            "the file holds another solver's modes, not its stiffness and mass: femu correlate compares them with a test; estimate, expand, frf and update need K and M (CalculiX writes them with *FREQUENCY, SOLVER=MATRIXSTORAGE: give femu the job.sti; Abaqus with *MATRIX OUTPUT: job_STIF1.mtx; Nastran's DMIG punch: job.pch, or OUTPUT4: job.op4; any solver's as MatrixMarket with a DOF table: X_K.mtx)",
        ));
    }
    let mut mass = options.mass();
    let mut eigrl = None;
    let (model, frequency) = if !format.info().deck {
        let Some(mat) = options.material else {
            return Err(StudyError::in_file(
                path,
                "material",
                "a mesh file has no material: give Young's modulus, Poisson's ratio and the density (--young, --poisson, --density, or [material] in a study file)",
            ));
        };
        let (mesh, surfaces, curves) = if format == Format::Universal {
            let u = femu_io::uff::read_uff(path)?;
            let (mesh, w) = u.to_mesh(path)?;
            warnings.extend(u.warnings.iter().map(|w| w.to_string()));
            warnings.extend(w.iter().map(|w| w.to_string()));
            if !options.shells.is_empty() || !options.beams.is_empty() {
                return Err(StudyError::in_file(
                    path,
                    "sections",
                    "shell and beam sections apply to a Gmsh mesh's physical groups of surfaces and lines: a universal file's mesh has solids only",
                ));
            }
            (mesh, Default::default(), Default::default())
        } else {
            let g = femu_io::gmsh::read_msh(path)?;
            warnings.extend(g.warnings.iter().map(|w| w.to_string()));
            (g.mesh, g.surfaces, g.curves)
        };
        if options.lenient {
            warnings.push(format!(
                "{}: lenient reading applies to .inp decks: not used for this mesh",
                path.display()
            ));
        }
        let mut model = Model::new(mesh).map_err(|e| StudyError::within(path, e))?;
        let material = Material::isotropic("command line", mat.young, mat.poisson, mat.density)?;
        model.set_material(None, material)?;
        set_bricks(&mut model, options.bricks, path, &mut warnings)?;
        add_sections(&mut model, (&surfaces, &curves), options, &mat, path)?;
        if mat.structural_damping != 0.0 {
            let ids: Vec<u64> = (0..model.mesh().element_count())
                .map(|e| model.mesh().element(e).id)
                .chain(model.structural().iter().map(|s| s.id))
                .collect();
            for id in ids {
                model
                    .set_element_damping(id, mat.structural_damping)
                    .map_err(|e| StudyError::within(path, e))?;
            }
        }
        for set in &options.fix {
            model
                .fix_set(set, &[0, 1, 2])
                .map_err(|e| StudyError::within(path, e))?;
            let with_rotations: Vec<u64> = model
                .mesh()
                .node_set(set)
                .map_err(|e| StudyError::within(path, e))?
                .iter()
                .filter(|n| model.has_rotations(**n))
                .map(|n| model.mesh().node_id(*n))
                .collect();
            for id in with_rotations {
                model
                    .fix_node_dofs(id, &[3, 4, 5])
                    .map_err(|e| StudyError::within(path, e))?;
            }
        }
        (model, None)
    } else if format == Format::Nastran {
        let deck = femu_io::nastran::read_bdf(
            path,
            &femu_io::nastran::BdfOptions {
                lenient: options.lenient,
            },
        )?;
        warnings.extend(deck.warnings.iter().map(|w| w.to_string()));
        // the deck's mass formulation, as Nastran reads it, unless lumped mass is asked for
        if !options.lumped {
            mass = deck.mass;
            if deck.mass == MassKind::Lumped {
                warnings.push(format!(
                    "{}: lumped mass: {} (MSC Nastran's mass for solids unless PARAM,COUPMASS is positive; femu lumps by row sums for linear elements and by the scaled diagonal for quadratic ones)",
                    path.display(),
                    match deck.coupmass {
                        Some(v) => format!("the deck sets PARAM,COUPMASS,{v}"),
                        None => "the deck has no PARAM,COUPMASS".to_string(),
                    }
                ));
            }
        }
        eigrl = deck.eigrl;
        bricks_of_deck(
            options.bricks,
            path,
            "the PSOLID's IN and ISOP",
            &mut warnings,
        );
        if options.material.is_some() || !options.fix.is_empty() {
            warnings.push(format!(
                "{}: the deck has its own materials and constraints: the given material and sets to fix are not used",
                path.display()
            ));
        }
        (deck.model, None)
    } else {
        let inp_options = femu_io::inp::InpOptions {
            lenient: options.lenient,
        };
        let deck = femu_io::inp::read_inp_with(path, &inp_options)?;
        warnings.extend(deck.warnings.iter().map(|w| w.to_string()));
        bricks_of_deck(options.bricks, path, "C3D8 or C3D8I", &mut warnings);
        if options.material.is_some() {
            warnings.push(format!(
                "{}: the deck has its own materials: the given Young's modulus, Poisson's ratio and density are not used",
                path.display()
            ));
        }
        if !options.fix.is_empty() {
            warnings.push(format!(
                "{}: the deck has its own boundary conditions: the sets to fix ({}) are not used",
                path.display(),
                options.fix.join(", ")
            ));
        }
        let (model, built) = deck.to_model_with_warnings()?;
        warnings.extend(built.iter().map(|w| w.to_string()));
        (model, deck.frequency)
    };
    let mut model = model;
    let mut timings = LoadTimings {
        read_seconds: start.elapsed().as_secs_f64(),
        ..Default::default()
    };
    let mark = std::time::Instant::now();
    leave_out_orphans(&mut model, path, &mut warnings)?;
    warnings.extend(units_hint(&model, path));
    timings.checks_seconds = mark.elapsed().as_secs_f64();
    let mark = std::time::Instant::now();
    let asm = Assembler::new(&model).map_err(|e| StudyError::within(path, e))?;
    timings.pattern_seconds = mark.elapsed().as_secs_f64();
    let mark = std::time::Instant::now();
    let sys = asm
        .assemble_analysed(&model, mass)
        .map_err(|e| StudyError::within(path, e))?;
    timings.assembly_seconds = mark.elapsed().as_secs_f64();
    Ok(LoadedModel {
        path: path.to_path_buf(),
        model,
        sys,
        asm,
        frequency,
        eigrl,
        warnings,
        timings,
        matrices: None,
    })
}

/// [`load_model`] for another solver's matrices ([`crate::external::matrix_model`]).
fn load_matrices(
    path: &Path,
    options: &ModelOptions,
    start: std::time::Instant,
) -> Result<LoadedModel, StudyError> {
    let (model, sys, origin, mut warnings) =
        crate::external::matrix_model(path, options.nodes.as_deref(), options.lumped)?;
    if options.material.is_some() || !options.fix.is_empty() {
        warnings.push(format!(
            "{}: the matrices hold their own material and supports: the given material and sets to fix are not used",
            path.display()
        ));
    }
    let read_seconds = start.elapsed().as_secs_f64();
    let mark = std::time::Instant::now();
    let asm = Assembler::new(&model).map_err(|e| StudyError::within(path, e))?;
    Ok(LoadedModel {
        path: path.to_path_buf(),
        model,
        sys,
        asm,
        frequency: None,
        eigrl: None,
        warnings,
        timings: LoadTimings {
            read_seconds,
            pattern_seconds: mark.elapsed().as_secs_f64(),
            ..Default::default()
        },
        matrices: Some(origin),
    })
}

/// femu computes in SI units (m, kg, s, N, Pa). A material whose modulus and density are those of
/// a structural material in another consistent system (mm, t, s with MPa; in, lbf s^2/in, s with
/// psi) solves without complaint and gives frequencies in no unit at all that the user expects:
/// named here, once, with the likely system. Frequencies scale with `sqrt(E / rho) / L`, so a
/// consistent system gives the right frequencies; femu's SI labels (Pa, kg/m^3, m) do not apply.
pub(crate) fn units_hint(model: &Model, path: &Path) -> Option<String> {
    let mesh = model.mesh();
    let mut seen = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY);
    for e in 0..mesh.element_count() {
        let Ok(m) = model.material_of(e) else {
            continue;
        };
        let stiffness = match &m.elasticity {
            femu_fem::material::Elasticity::Isotropic { e, .. } => *e,
            femu_fem::material::Elasticity::Anisotropic(d) => d[0][0].max(d[1][1]).max(d[2][2]),
        };
        seen = (
            seen.0.min(stiffness),
            seen.1.max(stiffness),
            seen.2.min(m.density),
        );
    }
    for st in model.structural() {
        let (e, rho) = match &st.kind {
            femu_fem::structural::StructuralKind::Beam(b) => (b.e, b.rho),
            femu_fem::structural::StructuralKind::Rod(r) => (r.e, r.rho),
            _ => continue,
        };
        seen = (seen.0.min(e), seen.1.max(e), seen.2.min(rho));
    }
    let (e_min, _, rho) = seen;
    if !e_min.is_finite() || !rho.is_finite() {
        return None;
    }
    // structural solids: E from about 1e8 Pa (polymers) to 1.2e12 (diamond), density from about
    // 10 kg/m^3 (foams) to 2.3e4 (osmium)
    let system = if (1e2..1e6).contains(&e_min) && (1e-11..1e-7).contains(&rho) {
        "millimetres, tonnes and seconds (E in MPa, density in t/mm^3)"
    } else if (1e4..1e8).contains(&e_min) && (1e-6..1e-2).contains(&rho) {
        "inches, lbf s^2/in and seconds (E in psi, density in lbf s^2/in^4)"
    } else if e_min < 1e7 || rho < 1.0 {
        "a system other than SI"
    } else {
        return None;
    };
    Some(format!(
        "{}: a modulus of {e_min:.4e} and a density of {rho:.4e} are not those of a structural solid in SI units (Pa, kg/m^3); they look like {system}: femu computes with the numbers as given, so frequencies are right in a consistent system, but its labels (Pa, kg/m^3, m) are not",
        path.display()
    ))
}

/// Nodes that belong to no element and no multipoint constraint have no stiffness and no mass:
/// left free they make `K` and `M` singular. As CalculiX does, they are left out (their DOFs are fixed), with a warning naming them.
fn leave_out_orphans(
    model: &mut Model,
    path: &Path,
    warnings: &mut Vec<String>,
) -> Result<(), StudyError> {
    let mesh = model.mesh();
    // a node in a multipoint constraint is connected through it (a rigid link's reference)
    let mut used = model.constrained_nodes();
    for el in mesh.elements() {
        for n in el.nodes {
            used[*n] = true;
        }
    }
    for s in model.structural() {
        for n in &s.nodes {
            used[*n] = true;
        }
    }
    let orphans: Vec<u64> = (0..mesh.node_count())
        .filter(|i| !used[*i])
        .map(|i| mesh.node_id(i))
        .collect();
    if orphans.is_empty() {
        return Ok(());
    }
    let shown: Vec<String> = orphans.iter().take(8).map(u64::to_string).collect();
    warnings.push(format!(
        "{}: {} node(s) belong to no element and are left out (no stiffness, no mass): {}{}",
        path.display(),
        orphans.len(),
        shown.join(", "),
        if orphans.len() > 8 { ", ..." } else { "" }
    ));
    model
        .fix_nodes(&orphans, &[0, 1, 2])
        .map_err(|e| StudyError::within(path, e))?;
    Ok(())
}

/// How a test's sensors find their model nodes.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TestOptions {
    /// Map the test's own wireframe (its node labels and coordinates) onto the model
    /// ([`crate::mapping`]); without it, test node ids are model node ids.
    pub map: Option<MapOptions>,
    /// Metres per unit of the test's coordinates where the file says nothing (no dataset 164;
    /// CSV and JSON): 0.001 for millimetres. A file's own units win.
    pub test_units: Option<f64>,
}

/// A unit of length a test file's coordinates may be in (`--test-units`, a study file's
/// `test_units`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum LengthUnit {
    /// Metres.
    M,
    /// Centimetres.
    Cm,
    /// Millimetres.
    Mm,
    /// Inches.
    In,
    /// Feet.
    Ft,
}

impl LengthUnit {
    /// The unit in metres.
    pub fn metres(self) -> f64 {
        match self {
            Self::M => 1.0,
            Self::Cm => 0.01,
            Self::Mm => 0.001,
            Self::In => 0.0254,
            Self::Ft => 0.3048,
        }
    }
}

/// Metres per unit of `name` (`m`, `cm`, `mm`, `in`, `ft`).
///
/// # Errors
/// Another name.
pub fn length_unit(name: &str) -> Result<f64, StudyError> {
    Ok(match name.to_ascii_lowercase().as_str() {
        "m" => LengthUnit::M,
        "cm" => LengthUnit::Cm,
        "mm" => LengthUnit::Mm,
        "in" => LengthUnit::In,
        "ft" => LengthUnit::Ft,
        other => {
            return Err(StudyError::invalid(
                "test units",
                format!("{other}: expected m, cm, mm, in or ft"),
            ));
        }
    }
    .metres())
}

/// Without `--map`, a test's labels are the model's node ids: where the file also gives its
/// nodes' coordinates, they must be where the model's nodes of those ids are (within 1 % of the
/// model's bounding-box diagonal, the mapping's default tolerance), or the labels are the test's
/// own and the sensors would read other nodes than those measured.
fn check_coordinates(
    data: &TestData,
    mesh: &femu_fem::mesh::Mesh,
    metres: f64,
    path: &Path,
) -> Result<(), StudyError> {
    if data.coordinates.is_empty() || mesh.node_count() == 0 {
        return Ok(());
    }
    let tolerance = 0.01 * femu_fem::mesh::bounding_diagonal(mesh.coords());
    let mut off: Vec<(f64, u64, [f64; 3], [f64; 3])> = Vec::new();
    for s in &data.sensors {
        let (Some(x), Some(i)) = (data.coordinates.get(&s.node), mesh.node_index(s.node)) else {
            continue;
        };
        let x = x.map(|v| v * metres);
        let y = mesh.coords()[i];
        let d = (0..3).map(|k| (x[k] - y[k]).powi(2)).sum::<f64>().sqrt();
        if d > tolerance && !off.iter().any(|o| o.1 == s.node) {
            off.push((d, s.node, x, y));
        }
    }
    let Some(worst) = off.iter().max_by(|a, b| a.0.total_cmp(&b.0)) else {
        return Ok(());
    };
    let labelled = data
        .sensors
        .iter()
        .map(|s| s.node)
        .collect::<std::collections::BTreeSet<_>>()
        .len();
    Err(StudyError::in_file(
        path,
        "test",
        format!(
            "{} of its {labelled} nodes are not where the model's nodes of the same ids are (test node {} at ({:.6}, {:.6}, {:.6}) m, model node {} at ({:.6}, {:.6}, {:.6}) m, {:.3e} m apart; 1 % of the model's size is {tolerance:.3e} m): without --map the labels are taken as model node ids; map the test's own wireframe with --map nearest or --map interpolate ([map] in a study file), or give its units (--test-units) or frame (--align)",
            off.len(),
            worst.1,
            worst.2[0],
            worst.2[1],
            worst.2[2],
            worst.1,
            worst.3[0],
            worst.3[1],
            worst.3[2],
            worst.0
        ),
    ))
}

/// Reads test modes (`.unv`/`.uff` universal file, `.json`, or CSV) and maps their sensors onto
/// `model` (test node ids are model node ids).
///
/// # Errors
/// The readers' errors, and sensors on nodes or DOFs the model does not have (naming the test
/// file).
pub fn load_test(path: &Path, model: &LoadedModel) -> Result<LoadedTest, StudyError> {
    load_test_with(path, model, &TestOptions::default())
}

/// [`load_test`] with `options`: with [`TestOptions::map`], the test's wireframe is aligned and
/// mapped onto the model ([`femu_correlate::mapping::map_test`]; the table is in [`LoadedTest::mapping`]).
///
/// # Errors
/// As [`load_test`]; with mapping, the errors of [`femu_correlate::mapping::map_test`].
pub fn load_test_with(
    path: &Path,
    model: &LoadedModel,
    options: &TestOptions,
) -> Result<LoadedTest, StudyError> {
    load_test_on(path, model.model.mesh(), &model.sys.dofs, options)
}

/// [`load_test_with`] onto the nodes of `mesh` and the DOFs of `dofs`: a model's, or another
/// solver's modes' ([`crate::external::ResultModes`]).
///
/// # Errors
/// As [`load_test_with`].
pub fn load_test_on(
    path: &Path,
    mesh: &femu_fem::mesh::Mesh,
    dofs: &femu_fem::dof::DofMap,
    options: &TestOptions,
) -> Result<LoadedTest, StudyError> {
    let format = Format::from_path(path)
        .filter(|f| f.info().test)
        .ok_or_else(|| {
            StudyError::in_file(
                path,
                "test",
                format!(
                    "femu reads test modes from {}; this extension is none of them",
                    femu_io::format::described(false)
                ),
            )
        })?;
    // metres per file unit: a universal file's dataset 164, else the option, else metres
    let mut warnings = Vec::new();
    let (mut data, metres) = if format == Format::Universal {
        let u = femu_io::uff::read_uff(path)?;
        let data = u.test_data(path)?;
        warnings.extend(complex_mode_warnings(&u, path));
        let metres = match (&u.units, options.test_units) {
            (Some(_), _) => 1.0 / u.length_factor(path)?,
            (None, Some(m)) => m,
            (None, None) => 1.0,
        };
        (data, metres)
    } else if format == Format::Json {
        (
            femu_io::json::read_test_json(path)?,
            options.test_units.unwrap_or(1.0),
        )
    } else {
        (
            femu_io::csv::read_test_csv(path)?,
            options.test_units.unwrap_or(1.0),
        )
    };
    let mapping = options
        .map
        .as_ref()
        .map(|m| map_test(&mut data, mesh, m, metres, path))
        .transpose()?;
    if mapping.is_none() {
        check_coordinates(&data, mesh, metres, path)?;
    }
    let layout = SensorLayout::new(mesh, dofs, data.sensors.clone())
        .map_err(|e| match e {
            femu_correlate::CorrelateError::SensorOnMissingNode { .. }
                if mapping.is_none() && !data.coordinates.is_empty() =>
            {
                StudyError::in_file(
                    path,
                    "test",
                    format!(
                        "{e}; the file gives its nodes' coordinates: map its own wireframe onto the model with --map nearest or --map interpolate ([map] in a study file)"
                    ),
                )
            }
            e => StudyError::within(path, e),
        })?;
    Ok(LoadedTest {
        path: path.to_path_buf(),
        data,
        layout,
        mapping,
        warnings,
    })
}

/// One warning per complex mode of a universal file whose MPC is below
/// [`femu_correlate::complexity::MPC_WARNING`]: femu uses its real part after turning it by the
/// phase of its largest component, and that part stands for the mode only as far as the mode is
/// real (`docs/MATH.md`, "Complex modes").
pub fn complex_mode_warnings(u: &femu_io::uff::Universal, path: &Path) -> Vec<String> {
    u.modes
        .iter()
        .filter_map(|m| {
            let c = m.complexity?;
            (c.mpc < femu_correlate::complexity::MPC_WARNING).then(|| {
                format!(
                    "{}: mode {} ({:.2} Hz) is far from real (MPC {:.3}, MPD {:.1} degrees): femu uses its real part after turning it by the phase of its largest component, which stands for the mode only as far as it is real",
                    path.display(),
                    m.number,
                    m.frequency_hz,
                    c.mpc,
                    c.mpd_degrees
                )
            })
        })
        .collect()
}

/// Every 8-node brick of a mesh-only model with the formulation asked for.
fn set_bricks(
    model: &mut Model,
    bricks: Formulation,
    path: &Path,
    warnings: &mut Vec<String>,
) -> Result<(), StudyError> {
    if bricks == Formulation::Full {
        return Ok(());
    }
    let hexes: Vec<usize> = model
        .mesh()
        .elements()
        .filter(|e| e.kind == femu_fem::element::ElementKind::Hex8)
        .map(|e| e.index)
        .collect();
    if hexes.is_empty() {
        warnings.push(format!(
            "{}: the mesh has no 8-node bricks: incompatible modes are not used",
            path.display()
        ));
    }
    for e in hexes {
        model.set_formulation(e, bricks)?;
    }
    Ok(())
}

/// A deck states its bricks' formulation itself (`how`): a formulation asked for is not used.
fn bricks_of_deck(bricks: Formulation, path: &Path, how: &str, warnings: &mut Vec<String>) {
    if bricks != Formulation::Full {
        warnings.push(format!(
            "{}: the deck states its bricks' formulation ({how}): the one asked for is not used",
            path.display()
        ));
    }
}

/// [`femu_correlate::mapping::map_test`] onto `model`'s mesh; an error names the test file `path`.
fn map_test(
    data: &mut TestData,
    mesh: &femu_fem::mesh::Mesh,
    options: &MapOptions,
    metres: f64,
    path: &Path,
) -> Result<Mapping, StudyError> {
    femu_correlate::mapping::map_test(data, mesh, options, metres).map_err(|e| match e {
        // the file's wireframe; a setting's error (the tolerance) names no file
        CorrelateError::Mapping { what, reason } => StudyError::in_file(path, what, reason),
        other => other.into(),
    })
}

#[cfg(test)]
mod tests {
    /// A complex mode far from real (MPC 0.75 by hand: two equal components 30 degrees apart)
    /// is named with its indicators; a nearly real one (3 degrees: MPC 0.997) is not.
    #[test]
    fn a_complex_mode_far_from_real_is_named() {
        let text = |deg: f64| {
            let (c, s) = (deg.to_radians().cos(), deg.to_radians().sin());
            format!(
                "    -1\n    55\nid1\nid2\nid3\nid4\nid5\n         1         3         2         8         5         3\n         2         6         1         4\n -3.5D+00  6.28318D+03  0.0D+00  0.0D+00  0.0D+00  0.0D+00\n         3\n  0.0D+00  0.0D+00  1.0D+00  0.0D+00  0.0D+00  0.0D+00\n         5\n  0.0D+00  0.0D+00  {c:.15E}  {s:.15E}  0.0D+00  0.0D+00\n    -1\n"
            )
        };
        let path = std::path::Path::new("c.unv");
        let u = femu_io::uff::parse_uff(&text(30.0), path).unwrap();
        let w = super::complex_mode_warnings(&u, path);
        assert_eq!(w.len(), 1);
        assert!(
            w[0].contains("mode 4") && w[0].contains("MPC 0.750") && w[0].contains("MPD 15.0"),
            "{w:?}"
        );
        let u = femu_io::uff::parse_uff(&text(3.0), path).unwrap();
        assert!(super::complex_mode_warnings(&u, path).is_empty());
    }
}
