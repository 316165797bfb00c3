//! A model given as another solver's `K` and `M` (docs/ARCHITECTURE.md, "Models solved
//! elsewhere"): the matrices with the node and component of each row
//! ([`femu_io::matrices::read_matrices`]) and the nodes' coordinates, made into a model of nodes
//! without elements whose free DOFs are exactly the matrices' rows. Every workflow that needs `K`,
//! `M` and the node positions runs on it: modes with their Sturm proof, correlation, the
//! estimators, expansion, sensor removal, FRFs, and updating over groups given as the same
//! model's matrices with the group's modulus and density doubled ([`matrix_groups`]).

use crate::StudyError;
use crate::load::LoadedModel;
use femu_fem::assembly::{MassKind, SystemMatrices};
use femu_fem::mesh::Mesh;
use femu_fem::model::Model;
use femu_io::matrices::{ExternalMatrices, MatrixSource, label};
use femu_sparse::SparseMatrix;
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

/// Another solver's modes as the model side of a correlation: its nodes (a model of nodes
/// without elements, three translations each, all free) and its mode shapes on them, with no
/// Sturm proof ([`femu_correlate::SpectrumProof::Unverified`]: nothing shows that no mode was
/// skipped) and no `K` or `M` (so no residue, estimator, expansion or updating).
#[derive(Debug, Clone)]
pub struct ResultModes {
    /// The file.
    pub path: PathBuf,
    /// The solver's nodes, without elements.
    pub model: Model,
    /// Three translations per node, every one free.
    pub dofs: femu_fem::dof::DofMap,
    /// The modes, eigenvalues `(2 pi f)^2` from the file's frequencies.
    pub modes: femu_correlate::ModeSet,
    /// What the reader noticed.
    pub warnings: Vec<String>,
}

/// Reads another solver's modes: CalculiX's `.frd` ([`femu_io::frd::read_frd`], its own nodes)
/// or printed `.dat` ([`femu_io::ccx_dat::read_calculix_dat`], with the nodes of the `.inp` beside
/// it or `nodes`), or Nastran's `.f06` or `.op2` ([`femu_io::f06::read_f06`], [`femu_io::op2::read_op2`]) with
/// the grids of its deck
/// ([`femu_io::nastran::read_grids`]: `nodes`, or the `.bdf`, `.dat` or `.nas` of the same name
/// beside it), each grid's printed translations turned from its displacement frame (CD) into the
/// basic frame. The model's nodes are the grids the modes print (a grid the output leaves out is
/// not there to be measured); rotations are not kept (a test measures translations).
///
/// # Errors
/// The readers' errors; a printed grid the deck does not define; no deck beside the results;
/// modes whose frequencies do not ascend (named).
pub fn load_result_modes(path: &Path, nodes: Option<&Path>) -> Result<ResultModes, StudyError> {
    let nastran = nastran_results(path);
    let dat = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("dat"));
    let (points, modes, mut warnings) = if nastran {
        nastran_modes(path, nodes)?
    } else if dat {
        calculix_dat_modes(path, nodes)?
    } else {
        let frd = femu_io::frd::read_frd(path)?;
        let warnings: Vec<String> = frd
            .skipped
            .iter()
            .map(|(name, count)| {
                format!(
                    "{}: {count} result block{} {name} skipped (femu reads the displacements of frequency steps)",
                    path.display(),
                    if *count == 1 { "" } else { "s" }
                )
            })
            .collect();
        let modes: Vec<(f64, usize, Vec<[f64; 3]>)> = frd
            .modes
            .into_iter()
            .map(|m| {
                (
                    (2.0 * std::f64::consts::PI * m.frequency_hz).powi(2),
                    m.line,
                    m.shape,
                )
            })
            .collect();
        (frd.nodes, modes, warnings)
    };
    if nodes.is_some() && !nastran && !dat {
        warnings.push(format!(
            "{}: the .frd holds its nodes: the given node file is not used",
            path.display()
        ));
    }
    let mut mesh = Mesh::new();
    for &(id, x) in &points {
        mesh.add_node(id, x)
            .map_err(|e| StudyError::within(path, e))?;
    }
    let model = Model::new(mesh).map_err(|e| StudyError::within(path, e))?;
    let n = points.len();
    let dofs = femu_fem::dof::DofMap::new(n, []);
    if let Some(w) = modes.windows(2).find(|w| w[1].0 < w[0].0) {
        return Err(StudyError::in_file(
            path,
            "modes",
            format!(
                "the mode at line {} (eigenvalue {:e}) is below the one before it ({:e}): femu reads the modes of one analysis, in ascending order",
                w[1].1, w[1].0, w[0].0
            ),
        ));
    }
    let shapes = faer::Mat::from_fn(3 * n, modes.len(), |r, j| modes[j].2[r / 3][r % 3]);
    let values: Vec<f64> = modes.iter().map(|m| m.0).collect();
    let modes = femu_correlate::ModeSet::new(values, shapes, false)?;
    Ok(ResultModes {
        path: path.to_path_buf(),
        model,
        dofs,
        modes,
        warnings,
    })
}

/// Nodes, modes `(eigenvalue, line, translations per node in the basic frame)` and warnings of a
/// Whether `path` is Nastran's results (`.f06`, `.op2` or a punch `.pch`), by its extension.
pub fn nastran_results(path: &Path) -> bool {
    path.extension().and_then(|e| e.to_str()).is_some_and(|e| {
        ["f06", "op2", "pch"]
            .iter()
            .any(|x| e.eq_ignore_ascii_case(x))
    })
}

/// The real modes of Nastran's results, by extension: an `.op2`'s ([`femu_io::op2::read_op2`]),
/// a punch file's ([`femu_io::punch::read_punch_modes`]) or an `.f06`'s
/// ([`femu_io::f06::read_f06`]).
///
/// # Errors
/// The readers' errors.
pub fn read_nastran_modes(path: &Path) -> Result<femu_io::f06::F06, StudyError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    Ok(match ext.as_deref() {
        Some("op2") => femu_io::op2::read_op2(path)?,
        Some("pch") => femu_io::punch::read_punch_modes(path)?,
        _ => femu_io::f06::read_f06(path)?,
    })
}

/// The run's deck beside Nastran's results: the `.bdf`, `.dat` or `.nas` of the same name.
pub fn nastran_deck_beside(path: &Path) -> Option<PathBuf> {
    ["bdf", "dat", "nas", "BDF", "DAT", "NAS"]
        .iter()
        .map(|e| path.with_extension(e))
        .find(|p| p.exists())
}

/// What a results reader gives [`load_result_modes`]: the nodes `(id, position)`, the modes
/// `(eigenvalue, line, translations per node)` and warnings.
type ReadModes = (
    Vec<(u64, [f64; 3])>,
    Vec<(f64, usize, Vec<[f64; 3]>)>,
    Vec<String>,
);

/// Nodes, modes `(eigenvalue, line, translations per node)` and warnings of CalculiX's printed
/// modes (`job.dat`, [`femu_io::ccx_dat`]) with the nodes of the run's deck (`nodes`, or the
/// `.inp` of the same name beside it): the nodes the modes print, in their order, and the
/// eigenvalues as the table prints them (seven digits).
fn calculix_dat_modes(path: &Path, nodes: Option<&Path>) -> Result<ReadModes, StudyError> {
    let dat = femu_io::ccx_dat::read_calculix_dat(path)?;
    let deck = match nodes {
        Some(p) => p.to_path_buf(),
        None => {
            let beside = path.with_extension("inp");
            if !beside.exists() {
                return Err(StudyError::in_file(
                    path,
                    "nodes",
                    "the modes need their nodes' positions: no .inp of the same name beside the .dat; name the run's deck with --nodes (nodes = \"...\" in a study file)",
                ));
            }
            beside
        }
    };
    let mesh = femu_io::inp::read_inp(&deck)?.mesh;
    let first = dat
        .modes
        .first()
        .ok_or_else(|| StudyError::in_file(path, "modes", "the eigenvalue table lists no mode"))?;
    let mut points = Vec::with_capacity(first.shape.len());
    for (id, _) in &first.shape {
        let i = mesh.node_index(*id).ok_or_else(|| {
            StudyError::in_file(
                path,
                "modes",
                format!(
                    "node {id} of mode {} is not a node of {}",
                    first.number,
                    deck.display()
                ),
            )
        })?;
        points.push((*id, mesh.coords()[i]));
    }
    let modes = dat
        .modes
        .iter()
        .map(|m| (m.eigenvalue, m.line, m.shape.iter().map(|s| s.1).collect()))
        .collect();
    let mut warnings: Vec<String> = dat
        .skipped
        .iter()
        .map(|(name, count)| {
            format!(
                "{}: {count} result block{} \"{name}\" skipped (femu reads the displacements of a frequency step)",
                path.display(),
                if *count == 1 { "" } else { "s" }
            )
        })
        .collect();
    if mesh.node_count() > points.len() {
        warnings.push(format!(
            "{}: {} of the deck's {} nodes are not printed in the modes: a test cannot be placed on them",
            path.display(),
            mesh.node_count() - points.len(),
            mesh.node_count()
        ));
    }
    Ok((points, modes, warnings))
}

/// Nodes, modes `(eigenvalue, line, translations per node in the basic frame)` and warnings of
/// Nastran's results with the grids of the run's deck.
fn nastran_modes(path: &Path, nodes: Option<&Path>) -> Result<ReadModes, StudyError> {
    let f06 = read_nastran_modes(path)?;
    let deck = match nodes {
        Some(p) => p.to_path_buf(),
        None => nastran_deck_beside(path).ok_or_else(|| {
                StudyError::in_file(
                    path,
                    "nodes",
                    "the modes need their grids' positions: no .bdf, .dat or .nas of the same name beside the results; name the run's deck with --nodes (nodes = \"...\" in a study file)",
                )
            })?,
    };
    let grids = femu_io::nastran::read_grids(&deck)?;
    let by_id: HashMap<u64, &femu_io::nastran::GridPoint> =
        grids.iter().map(|g| (g.id, g)).collect();
    // the grids every mode prints, in the first mode's order
    let printed: Vec<u64> = f06.modes[0].points.iter().map(|(id, _)| *id).collect();
    let mut points = Vec::with_capacity(printed.len());
    for id in &printed {
        let g = by_id.get(id).ok_or_else(|| {
            StudyError::in_file(
                path,
                "modes",
                format!(
                    "grid {id} of eigenvector {} is not a GRID of {}",
                    f06.modes[0].number,
                    deck.display()
                ),
            )
        })?;
        points.push((*id, g.position));
    }
    let mut modes = Vec::with_capacity(f06.modes.len());
    for m in &f06.modes {
        let values: HashMap<u64, [f64; 6]> = m.points.iter().copied().collect();
        let shape = printed
            .iter()
            .map(|id| {
                let v = values.get(id).ok_or_else(|| {
                    StudyError::in_file(
                        path,
                        "modes",
                        format!(
                            "eigenvector {} does not print grid {id}, which eigenvector {} prints",
                            m.number, f06.modes[0].number
                        ),
                    )
                })?;
                let a = by_id[id].axes;
                Ok(std::array::from_fn(|i| {
                    (0..3).map(|j| a[i][j] * v[j]).sum::<f64>()
                }))
            })
            .collect::<Result<Vec<[f64; 3]>, StudyError>>()?;
        modes.push((m.eigenvalue, m.line, shape));
    }
    let mut warnings = Vec::new();
    if f06.without_vectors > 0 {
        warnings.push(format!(
            "{}: {} eigenvalues of the table have no printed eigenvector: the modes are those printed",
            path.display(),
            f06.without_vectors
        ));
    }
    if grids.len() > printed.len() {
        warnings.push(format!(
            "{}: {} of the deck's {} grids are not printed in the eigenvectors: a test cannot be placed on them",
            path.display(),
            grids.len() - printed.len(),
            grids.len()
        ));
    }
    Ok((points, modes, warnings))
}

/// The matrix groups of a model read as another solver's matrices, from `sets` of the form
/// `NAME=FILE`: `FILE` (relative to the model's folder) is the same model's matrix set with the
/// group's Young's modulus and density doubled, so that `K_g = K_2 - K_0` and `M_g = M_2 - M_0`
/// exactly (stiffness is linear in the modulus, mass in the density), whatever elements the
/// solver used: `K(p) = K_0 + sum_g p_g K_g` as for element groups (docs/MATH.md, "Updating").
///
/// # Errors
/// A set without `=`; a file that does not read; a set whose rows are not the model's (labels or
/// order); a group that changes nothing.
#[allow(clippy::type_complexity)]
pub fn matrix_groups(
    model: &LoadedModel,
    sets: &[String],
) -> Result<Vec<(String, SparseMatrix, SparseMatrix)>, StudyError> {
    let Some(origin) = &model.matrices else {
        return Err(StudyError::invalid(
            "matrix groups",
            "the model is not a set of another solver's matrices",
        ));
    };
    let folder = model.path.parent().unwrap_or(Path::new("."));
    sets.iter()
        .map(|set| {
            let Some((name, file)) = set.split_once('=') else {
                return Err(StudyError::in_file(
                    &model.path,
                    "updating",
                    format!(
                        "{set:?}: a model of another solver's matrices is updated over groups given as NAME=FILE, FILE the same model's matrices with the group's Young's modulus and density doubled"
                    ),
                ));
            };
            let path = folder.join(file.trim());
            let ext = femu_io::matrices::read_matrices(&path)?;
            if ext.dofs != origin.labels {
                let first = ext
                    .dofs
                    .iter()
                    .zip(&origin.labels)
                    .position(|(a, b)| a != b)
                    .unwrap_or(ext.dofs.len().min(origin.labels.len()));
                return Err(StudyError::in_file(
                    &path,
                    "matrix group",
                    format!(
                        "its rows are not the model's: {} rows against {}, the first difference at row {}",
                        ext.dofs.len(),
                        origin.labels.len(),
                        first + 1
                    ),
                ));
            }
            let difference = |doubled: &SparseMatrix, nominal: &SparseMatrix| {
                let entries = femu_sparse::csc::entries(doubled)
                    .map(|(i, j, v)| (origin.order[i], origin.order[j], v))
                    .chain(femu_sparse::csc::entries(nominal).map(|(i, j, v)| (i, j, -v)));
                let summed =
                    femu_sparse::csc::from_entry_iter(nominal.rows(), nominal.cols(), entries);
                // what the group does not touch cancels exactly (the same digits in both files)
                femu_sparse::csc::from_entry_iter(
                    nominal.rows(),
                    nominal.cols(),
                    femu_sparse::csc::entries(&summed).filter(|e| e.2 != 0.0),
                )
            };
            let k = difference(&ext.k, &model.sys.k);
            let m = difference(&ext.m, &model.sys.m);
            Ok((name.trim().to_string(), k, m))
        })
        .collect()
}

/// Where a model read as matrices came from.
#[derive(Debug, Clone, PartialEq)]
pub struct MatrixOrigin {
    /// The solver's format.
    pub source: MatrixSource,
    /// The stiffness, mass and DOF files.
    pub files: [PathBuf; 3],
    /// The file of the node coordinates.
    pub nodes: PathBuf,
    /// The node and component of each row of the files.
    pub labels: Vec<femu_io::matrices::DofLabel>,
    /// Row `r` of the files is free DOF `order[r]` of the model.
    pub order: Vec<usize>,
}

/// Reads the matrix set named by `path` and the node coordinates (`nodes`, or the default beside
/// the matrices, [`femu_io::matrices::default_node_table`]) into a model without elements and
/// its system matrices on femu's numbering of the same DOFs.
///
/// # Errors
/// The readers' errors; a node of the DOF table missing from the coordinates; matrices whose
/// mass is not positive on its diagonal.
pub fn matrix_model(
    path: &Path,
    nodes: Option<&Path>,
    lumped: bool,
) -> Result<(Model, SystemMatrices, MatrixOrigin, Vec<String>), StudyError> {
    let ext = femu_io::matrices::read_matrices(path)?;
    model_of_matrices(ext, path, nodes, lumped)
}

/// [`matrix_model`] of a set already read.
///
/// # Errors
/// As [`matrix_model`].
pub fn model_of_matrices(
    ext: ExternalMatrices,
    path: &Path,
    nodes: Option<&Path>,
    lumped: bool,
) -> Result<(Model, SystemMatrices, MatrixOrigin, Vec<String>), StudyError> {
    let mut warnings = Vec::new();
    let node_file = match nodes {
        Some(p) => p.to_path_buf(),
        None => {
            femu_io::matrices::default_node_table(path)
                .filter(|p| p.exists())
                .ok_or_else(|| {
                    StudyError::in_file(
                        path,
                        "nodes",
                        format!(
                            "the matrices need their nodes' coordinates: none found at {}; name a deck (.inp) or a table (.csv: node,x,y,z) with --nodes (nodes = \"...\" in a study file)",
                            femu_io::matrices::default_node_table(path)
                                .map_or_else(|| "-".into(), |p| p.display().to_string())
                        ),
                    )
                })?
        }
    };
    let table = femu_io::matrices::read_node_table(&node_file)?;
    let (model, dofs_in_order) = model_of(&ext, &table, &node_file)?;
    if lumped {
        warnings.push(format!(
            "{}: the mass is the solver's: --lumped does not apply to matrices read from a file",
            path.display()
        ));
    }
    // the map of the model's supports and rotations, without the closure of Model::dof_map (which
    // fixes the rotations that no constraint reaches: here the matrices reach them)
    let dofs = femu_fem::dof::DofMap::with_constraints(
        model.mesh().node_count(),
        model.fixed_dofs(),
        model.rotation_nodes(),
        &[],
        |n| model.mesh().node_id(n),
    )
    .map_err(|e| StudyError::within(&node_file, e))?;
    // row r of the file is free DOF order[r] of femu's map
    let order: Vec<usize> = dofs_in_order
        .iter()
        .map(|&(n, c)| {
            let p = if c < 3 {
                n
            } else {
                dofs.rotation_point(n).expect("rotation point added above")
            };
            dofs.free_index(p, c % 3).expect("every listed DOF is free")
        })
        .collect();
    // the eigensolver factors K - sigma M on K's pattern: K stores (zeros where need be) every
    // entry M has
    let (k, m) = rayon::join(
        || permuted(&ext.k, &order, Some(&ext.m)),
        || permuted(&ext.m, &order, None),
    );
    if let Some(r) = (0..ext.m.rows()).find(|&r| !(ext.m.get(r, r).copied().unwrap_or(0.0) >= 0.0))
    {
        return Err(StudyError::in_file(
            &ext.files[1],
            "mass",
            format!(
                "the mass matrix has a negative diagonal entry at row {} ({}): a mass matrix is positive semi-definite",
                r + 1,
                label(ext.dofs[r])
            ),
        ));
    }
    let mass_kind = if is_diagonal(&m) {
        MassKind::Lumped
    } else {
        MassKind::Consistent
    };
    let sys = SystemMatrices::from_matrices(k, m, dofs, mass_kind, model.mesh().coords())
        .map_err(|e| StudyError::within(path, e))?;
    let origin = MatrixOrigin {
        source: ext.source,
        files: ext.files.clone(),
        nodes: node_file,
        labels: ext.dofs.clone(),
        order,
    };
    Ok((model, sys, origin, warnings))
}

/// The model of the nodes in `table` (every one, so that a test may name a node the matrices
/// hold no DOF of: a clamped one), with rotations where a row has one and every component no row
/// lists fixed; and the (node index, component) of each row.
fn model_of(
    ext: &ExternalMatrices,
    table: &[(u64, [f64; 3])],
    node_file: &Path,
) -> Result<(Model, Vec<(usize, usize)>), StudyError> {
    let mut mesh = Mesh::new();
    let mut index = HashMap::with_capacity(table.len());
    for &(id, x) in table {
        let i = mesh
            .add_node(id, x)
            .map_err(|e| StudyError::within(node_file, e))?;
        index.insert(id, i);
    }
    let mut rows = Vec::with_capacity(ext.dofs.len());
    let mut listed: BTreeMap<u64, [bool; 6]> = BTreeMap::new();
    for (r, d) in ext.dofs.iter().enumerate() {
        let Some(&i) = index.get(&d.node) else {
            return Err(StudyError::in_file(
                &ext.files[2],
                "nodes",
                format!(
                    "row {} is {}, which {} does not define",
                    r + 1,
                    label(*d),
                    node_file.display()
                ),
            ));
        };
        rows.push((i, d.component));
        listed.entry(d.node).or_default()[d.component] = true;
    }
    let mut model = Model::new(mesh).map_err(|e| StudyError::within(node_file, e))?;
    for (&id, comps) in &listed {
        if comps[3..].iter().any(|&c| c) {
            model
                .add_rotations(id)
                .map_err(|e| StudyError::within(node_file, e))?;
        }
    }
    for &(id, _) in table {
        let comps = listed.get(&id).copied().unwrap_or_default();
        let rotations = comps[3..].iter().any(|&c| c);
        let fixed: Vec<usize> = (0..if rotations { 6 } else { 3 })
            .filter(|&c| !comps[c])
            .collect();
        if !fixed.is_empty() {
            model
                .fix_node_dofs(id, &fixed)
                .map_err(|e| StudyError::within(node_file, e))?;
        }
    }
    Ok((model, rows))
}

/// `P A P^T`: entry `(i, j)` of `a` moved to `(order[i], order[j])`, with a stored zero wherever
/// `also` has an entry that `a` lacks.
fn permuted(a: &SparseMatrix, order: &[usize], also: Option<&SparseMatrix>) -> SparseMatrix {
    let Some(b) = also else {
        return femu_sparse::csc::permuted(a, order);
    };
    let entries = femu_sparse::csc::entries(a)
        .map(|(i, j, v)| (order[i], order[j], v))
        .chain(femu_sparse::csc::entries(b).map(|(i, j, _)| (order[i], order[j], 0.0)));
    femu_sparse::csc::from_entry_iter(a.rows(), a.cols(), entries)
}

/// The files [`write_matrices`] wrote.
#[derive(Debug, Clone)]
pub struct WrittenMatrices {
    /// `PREFIX_K.mtx`, `PREFIX_M.mtx`, `PREFIX_dofs.csv`, `PREFIX_nodes.csv`.
    pub files: [PathBuf; 4],
}

/// Writes a model's `K` and `M` as MatrixMarket files (`PREFIX_K.mtx`, `PREFIX_M.mtx`:
/// symmetric, lower triangle, femu's free DOFs), the node and component of each row
/// (`PREFIX_dofs.csv`: row, node, component x/y/z/rx/ry/rz) and the nodes' coordinates
/// (`PREFIX_nodes.csv`: node, x, y, z): the set [`matrix_model`] reads back, and what scipy,
/// MATLAB or another solver reads.
///
/// # Errors
/// File system errors, naming the file.
pub fn write_matrices(
    model: &Model,
    sys: &SystemMatrices,
    prefix: &Path,
) -> Result<WrittenMatrices, StudyError> {
    let name = |suffix: &str| {
        let mut p = prefix.as_os_str().to_owned();
        p.push(suffix);
        PathBuf::from(p)
    };
    let files = [
        name("_K.mtx"),
        name("_M.mtx"),
        name("_dofs.csv"),
        name("_nodes.csv"),
    ];
    let mesh = model.mesh();
    femu_sparse::mtx::write_matrix_market(&files[0], &sys.k, true)?;
    femu_sparse::mtx::write_matrix_market(&files[1], &sys.m, true)?;
    let mut csv = String::from("row,node,component\n");
    for f in 0..sys.dofs.free_count() {
        let (p, c) = sys.dofs.free_dof(f);
        let (node, rotation) = sys.dofs.point_node(p);
        csv.push_str(&format!(
            "{},{},{}\n",
            f + 1,
            mesh.node_id(node),
            ["x", "y", "z", "rx", "ry", "rz"][c + if rotation { 3 } else { 0 }]
        ));
    }
    std::fs::write(&files[2], csv).map_err(|e| StudyError::file(&files[2], e))?;
    let nodes: Vec<(u64, [f64; 3])> = mesh
        .coords()
        .iter()
        .enumerate()
        .map(|(i, x)| (mesh.node_id(i), *x))
        .collect();
    femu_io::matrices::write_node_table(&files[3], &nodes)?;
    Ok(WrittenMatrices { files })
}

fn is_diagonal(a: &SparseMatrix) -> bool {
    a.iter().all(|(v, (i, j))| i == j || *v == 0.0)
}
