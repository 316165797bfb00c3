//! Loading a model and a test the way every workflow does: read the file by its extension, build
//! and check the model, assemble `K` and `M` once, and map the test's sensors onto the model.

use crate::StudyError;
use femu_correlate::SensorLayout;
use femu_fem::assembly::{Assembler, MassKind, SystemMatrices};
use femu_fem::material::Material;
use femu_fem::model::Model;
use femu_io::csv::TestData;
use femu_io::inp::FrequencyStep;
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
}

/// How to turn a model file into a model.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ModelOptions {
    /// The material of a mesh-only model (required for `.msh`/`.unv`, not used for an `.inp`
    /// deck, which has its own).
    pub material: Option<MaterialOptions>,
    /// Node sets (Gmsh physical groups, UFF groups) to clamp in a mesh-only model.
    pub fix: Vec<String>,
    /// Lumped (row-sum/HRZ) instead of consistent mass.
    pub lumped: bool,
    /// Unknown keywords in an `.inp` deck are warnings instead of errors
    /// ([`femu_io::inp::InpOptions::lenient`]).
    pub lenient: bool,
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
    /// What the readers noticed and the options that did not apply, one line each.
    pub warnings: Vec<String>,
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
    /// Test node -> model node, when the test was mapped ([`TestOptions::map_nearest`]).
    pub mapping: Vec<NodeMapping>,
}

/// The extensions of the model files femu reads.
pub const MODEL_EXTENSIONS: &[&str] = &["inp", "msh", "unv", "uff"];

/// The extensions of the test files femu reads.
pub const TEST_EXTENSIONS: &[&str] = &["unv", "uff", "json", "csv", "txt"];

/// Whether `path` ends in one of `exts` (any case).
pub fn has_extension(path: &Path, exts: &[&str]) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| exts.iter().any(|x| e.eq_ignore_ascii_case(x)))
}

/// Reads a model: an Abaqus/CalculiX `.inp` deck (materials and constraints inside), or a mesh
/// (Gmsh `.msh`, universal file `.unv`/`.uff` with datasets 2411/2412) with the material and
/// clamped sets of `options`; then assembles `K` and `M`.
///
/// # Errors
/// The readers' errors (file and line), a mesh without a material, an unknown set to fix, and
/// assembly errors (naming the element).
pub fn load_model(path: &Path, options: &ModelOptions) -> Result<LoadedModel, StudyError> {
    let mut warnings = Vec::new();
    if !has_extension(path, MODEL_EXTENSIONS) {
        return Err(StudyError::in_file(
            path,
            "model",
            "femu reads models as Abaqus/CalculiX decks (.inp), Gmsh meshes (.msh) and universal files (.unv, .uff); the file's extension is none of them",
        ));
    }
    let (model, frequency) = if has_extension(path, &["msh", "unv", "uff"]) {
        let Some(mat) = options.material else {
            return Err(StudyError::in_file(
                path,
                "material",
                "a mesh file has no material: give Young's modulus, Poisson's ratio and the density (--young, --poisson, --density, or [material] in a study file)",
            ));
        };
        let mesh = if has_extension(path, &["unv", "uff"]) {
            let u = femu_io::uff::read_uff(path)?;
            let (mesh, w) = u.to_mesh(path)?;
            warnings.extend(u.warnings.iter().map(|w| w.to_string()));
            warnings.extend(w.iter().map(|w| w.to_string()));
            mesh
        } else {
            let g = femu_io::gmsh::read_msh(path)?;
            warnings.extend(g.warnings.iter().map(|w| w.to_string()));
            g.mesh
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
        for set in &options.fix {
            model
                .fix_set(set, &[0, 1, 2])
                .map_err(|e| StudyError::within(path, e))?;
        }
        (model, None)
    } else {
        let inp_options = femu_io::inp::InpOptions {
            lenient: options.lenient,
        };
        let deck = femu_io::inp::read_inp_with(path, &inp_options)?;
        warnings.extend(deck.warnings.iter().map(|w| w.to_string()));
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
        (deck.to_model()?, deck.frequency)
    };
    let mut model = model;
    leave_out_orphans(&mut model, path, &mut warnings)?;
    let asm = Assembler::new(&model).map_err(|e| StudyError::within(path, e))?;
    let sys = asm
        .assemble(&model, options.mass())
        .map_err(|e| StudyError::within(path, e))?;
    Ok(LoadedModel {
        path: path.to_path_buf(),
        model,
        sys,
        asm,
        frequency,
        warnings,
    })
}

/// Nodes that belong to no element have no stiffness and no mass: left free they make `K` and `M`
/// singular. As CalculiX does, they are left out (their DOFs are fixed), with a warning naming them.
fn leave_out_orphans(
    model: &mut Model,
    path: &Path,
    warnings: &mut Vec<String>,
) -> Result<(), StudyError> {
    let mesh = model.mesh();
    let mut used = vec![false; mesh.node_count()];
    for el in mesh.elements() {
        for n in el.nodes {
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
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TestOptions {
    /// Map every test node of a universal file (its own numbering, coordinates of dataset 15 or
    /// 2411, in the file's units) to the nearest model node within this distance (m), instead of
    /// taking test node ids as model node ids.
    pub map_nearest: Option<f64>,
    /// Metres per unit of the test's coordinates where the file says nothing (no dataset 164):
    /// 0.001 for millimetres. A file's own units win.
    pub test_units: Option<f64>,
}

/// Metres per unit of `name` (`m`, `cm`, `mm`, `in`, `ft`).
///
/// # Errors
/// Another name.
pub fn length_unit(name: &str) -> Result<f64, StudyError> {
    Ok(match name.to_ascii_lowercase().as_str() {
        "m" => 1.0,
        "cm" => 0.01,
        "mm" => 0.001,
        "in" => 0.0254,
        "ft" => 0.3048,
        other => {
            return Err(StudyError::invalid(
                "test units",
                format!("{other}: expected m, cm, mm, in or ft"),
            ));
        }
    })
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

/// [`load_test`] with `options`: with [`TestOptions::map_nearest`], each test node of a
/// universal file is moved to the nearest model node (the mapping is in
/// [`LoadedTest::mapping`]).
///
/// # Errors
/// As [`load_test`]; with mapping, a file without test node coordinates, a test node farther
/// than the tolerance from every model node, or two test nodes on one model node (each named with
/// its distance).
pub fn load_test_with(
    path: &Path,
    model: &LoadedModel,
    options: &TestOptions,
) -> Result<LoadedTest, StudyError> {
    if !has_extension(path, TEST_EXTENSIONS) {
        return Err(StudyError::in_file(
            path,
            "test",
            "femu reads test modes from universal files (.unv, .uff: datasets 15/2411 and 55), JSON (.json) and CSV (.csv, .txt); this extension is none of them",
        ));
    }
    let mut mapping = Vec::new();
    let data = if has_extension(path, &["unv", "uff"]) {
        let u = femu_io::uff::read_uff(path)?;
        let mut data = u.test_data(path)?;
        if let Some(tol) = options.map_nearest {
            // metres per file unit: the file's dataset 164, else the option, else metres
            let metres = match (&u.units, options.test_units) {
                (Some(_), _) => 1.0 / u.length_factor(path)?,
                (None, Some(m)) => m,
                (None, None) => 1.0,
            };
            mapping = map_nearest(&u, &mut data, model, tol, metres, path)?;
        }
        data
    } else if has_extension(path, &["json"]) {
        femu_io::json::read_test_json(path)?
    } else {
        femu_io::csv::read_test_csv(path)?
    };
    if options.map_nearest.is_some() && mapping.is_empty() {
        return Err(StudyError::in_file(
            path,
            "map",
            "mapping to the nearest model node needs the test nodes' coordinates: a universal file with dataset 15 or 2411",
        ));
    }
    let layout = SensorLayout::new(model.model.mesh(), &model.sys.dofs, data.sensors.clone())
        .map_err(|e| StudyError::within(path, e))?;
    Ok(LoadedTest {
        path: path.to_path_buf(),
        data,
        layout,
        mapping,
    })
}

/// One test node moved onto the model.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct NodeMapping {
    /// The test node's label.
    pub test: u64,
    /// The model node it measures.
    pub model: u64,
    /// Their distance, m.
    pub distance: f64,
}

/// Relabels `data`'s sensors from test nodes to the nearest model nodes (within `tol`).
fn map_nearest(
    u: &femu_io::uff::Universal,
    data: &mut TestData,
    model: &LoadedModel,
    tol: f64,
    metres: f64,
    path: &Path,
) -> Result<Vec<NodeMapping>, StudyError> {
    if !(tol.is_finite() && tol >= 0.0) {
        return Err(StudyError::invalid(
            "mapping tolerance",
            format!("{tol} m is not a non-negative distance"),
        ));
    }
    let mesh = model.model.mesh();
    let coords: std::collections::HashMap<u64, [f64; 3]> = u
        .nodes
        .iter()
        .map(|n| (n.id, n.x.map(|v| v * metres)))
        .collect();
    let mut test_nodes: Vec<u64> = data.sensors.iter().map(|s| s.node).collect();
    test_nodes.sort_unstable();
    test_nodes.dedup();
    let mut table = Vec::new();
    let mut taken: std::collections::HashMap<u64, u64> = std::collections::HashMap::new();
    for t in test_nodes {
        let x = coords.get(&t).ok_or_else(|| {
            StudyError::in_file(
                path,
                "map",
                format!("test node {t} has modes but no coordinates (dataset 15 or 2411)"),
            )
        })?;
        let (best, d) = (0..mesh.node_count())
            .map(|i| {
                let c = mesh.coords()[i];
                let d =
                    ((c[0] - x[0]).powi(2) + (c[1] - x[1]).powi(2) + (c[2] - x[2]).powi(2)).sqrt();
                (i, d)
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .ok_or_else(|| StudyError::invalid("map", "the model has no nodes"))?;
        let id = mesh.node_id(best);
        if d > tol {
            return Err(StudyError::in_file(
                path,
                "map",
                format!(
                    "test node {t} at ({:.6}, {:.6}, {:.6}) m is {d:.3e} m from the nearest model node ({id}), beyond the tolerance {tol:e} m",
                    x[0], x[1], x[2]
                ),
            ));
        }
        if let Some(other) = taken.insert(id, t) {
            return Err(StudyError::in_file(
                path,
                "map",
                format!(
                    "test nodes {other} and {t} both map to model node {id}: lower the tolerance or refine the mesh"
                ),
            ));
        }
        table.push(NodeMapping {
            test: t,
            model: id,
            distance: d,
        });
    }
    for s in &mut data.sensors {
        if let Some(m) = table.iter().find(|m| m.test == s.node) {
            s.node = m.model;
        }
    }
    Ok(table)
}
