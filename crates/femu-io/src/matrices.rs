//! Stiffness and mass matrices that another solver assembled, with the node and component of each
//! row (docs/ARCHITECTURE.md, "Models solved elsewhere"):
//!
//! - **CalculiX** `*FREQUENCY, SOLVER=MATRIXSTORAGE` writes `job.sti` (stiffness), `job.mas`
//!   (mass), one entry `row column value` per line for the upper triangle, 1-based, and `job.dof`,
//!   the `node.direction` of each row (`12.3`: node 12, z). The matrices are on the free DOFs,
//!   after the boundary conditions. A model whose shells or beams CalculiX expanded to solids
//!   stores the expanded nodes, whose labels repeat or name nodes the deck does not have: refused.
//! - **MatrixMarket with a DOF table**: `X_K.mtx` and `X_M.mtx` (coordinate, real, symmetric or
//!   general) and `X_dofs.csv` (`row,node,component`, component `x`, `y`, `z`, `rx`, `ry`, `rz` or
//!   1-6), as `femu matrices` writes them and as any solver's matrices can be written by a short
//!   script.
//! - **Abaqus** `*MATRIX GENERATE, STIFFNESS, MASS` with `*MATRIX OUTPUT, FORMAT=MATRIX INPUT`
//!   (the default) writes `job_STIF<n>.mtx` and `job_MASS<n>.mtx`, one entry `row node, row DOF,
//!   column node, column DOF, value` per line (the Keywords Reference's `*MATRIX INPUT` data
//!   lines), a symmetric matrix by one triangle or both; the rows are the labels the two files
//!   use. A DOF Abaqus constrained is written as a unit diagonal stiffness without mass: such a
//!   row is left out. Internal nodes (negative numbers: Lagrange multipliers, internal element
//!   nodes) and DOFs beyond 6 are refused.
//! - **Nastran** `DMIG` matrices in a punch file (`job.pch`, as `PARAM,EXTOUT,DMIGPCH` writes
//!   them): the stiffness `KAAX` and the mass `MAAX` (or the one matrix whose name starts with K,
//!   and with M), each entry labelled by grid and component ([`crate::nastran::read_dmig`]). The
//!   grids come from the deck beside it (`job.bdf`, `.dat` or `.nas`); components in a turned
//!   displacement frame (CD) are refused, as femu's rows are in the basic frame.
//! - **Nastran** `OUTPUT4` files (`job.op4`, text or binary, [`crate::op4`]) holding a stiffness
//!   and a mass (`KAA`/`MAA`, `KFF`/`MFF`, `KLL`/`MLL`, `KGG`/`MGG`, or one matrix named `K...`
//!   and one `M...`). OP4 rows carry no labels: a DOF table `job_dofs.csv` beside it labels any
//!   set; without one, the deck beside it labels the g-set (`KGG`, `MGG`: each grid's six
//!   components, grids by id, [`crate::nastran::read_gset`]), less the components the deck
//!   constrains (`PS`, the selected SPC set) and those with neither stiffness nor mass (Nastran's
//!   AUTOSPC fixes them); a deck with multipoint constraints or rigid elements, which a g-set
//!   matrix does not hold, or scalar points is refused.
//!
//! The node coordinates come from a separate table ([`read_node_table`]): the deck's `*NODE` lines
//! (`job.inp`), or `X_nodes.csv` (`node,x,y,z`).

use crate::IoError;
use femu_sparse::SparseMatrix;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// One row (and column) of the matrices: a node and one of its six components.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct DofLabel {
    /// The node id.
    pub node: u64,
    /// 0-5: x, y, z, rx, ry, rz.
    pub component: usize,
}

/// Which solver's files the matrices came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MatrixSource {
    /// CalculiX's `.sti`, `.mas` and `.dof`.
    Calculix,
    /// MatrixMarket `_K.mtx`, `_M.mtx` with `_dofs.csv`.
    MatrixMarket,
    /// Abaqus's `_STIF<n>.mtx` and `_MASS<n>.mtx` (labelled entries).
    Abaqus,
    /// Nastran's DMIG punch file (`KAAX`, `MAAX`).
    NastranDmig,
    /// Nastran's OUTPUT4 file (`.op4`, text or binary) of a stiffness and a mass, its rows the
    /// g-set of the deck beside it or a DOF table.
    NastranOp4,
}

impl MatrixSource {
    /// The name users know it by.
    pub fn name(self) -> &'static str {
        match self {
            MatrixSource::Calculix => "CalculiX's stored matrices",
            MatrixSource::MatrixMarket => "MatrixMarket matrices with a DOF table",
            MatrixSource::Abaqus => "Abaqus's generated matrices (*MATRIX OUTPUT)",
            MatrixSource::NastranDmig => "Nastran's DMIG matrices (KAAX, MAAX)",
            MatrixSource::NastranOp4 => "Nastran's OUTPUT4 matrices (.op4)",
        }
    }
}

/// `K` and `M` from another solver, on the same rows, each row labelled.
#[derive(Debug, Clone)]
pub struct ExternalMatrices {
    /// Stiffness, both triangles stored.
    pub k: SparseMatrix,
    /// Mass, both triangles stored.
    pub m: SparseMatrix,
    /// The node and component of each row.
    pub dofs: Vec<DofLabel>,
    /// The solver's format.
    pub source: MatrixSource,
    /// The files read: stiffness, mass, DOF table (for Abaqus, whose entries carry their labels,
    /// the stiffness file again).
    pub files: [PathBuf; 3],
}

/// The files of a matrix set named by one of them: `job.sti` (CalculiX), `job_STIF1.mtx`
/// (Abaqus) or `X_K.mtx` (MatrixMarket with a DOF table); `None` for any other name.
pub fn matrix_files(path: &Path) -> Option<(MatrixSource, [PathBuf; 3])> {
    let name = path.file_name()?.to_str()?;
    let lower = name.to_ascii_lowercase();
    if lower.ends_with(".pch") {
        let p = path.to_path_buf();
        return Some((MatrixSource::NastranDmig, [p.clone(), p.clone(), p]));
    }
    if let Some(stem) = lower.strip_suffix(".op4").map(|s| &name[..s.len()]) {
        let p = path.to_path_buf();
        let table = path.with_file_name(format!("{stem}_dofs.csv"));
        let rows = if table.exists() {
            table
        } else {
            nastran_deck_beside(path)
        };
        return Some((MatrixSource::NastranOp4, [p.clone(), p, rows]));
    }
    if let Some((job, step)) = abaqus_name(&lower) {
        let stem = &name[..job.len()];
        let stif = path.with_file_name(format!("{stem}_STIF{step}.mtx"));
        let mass = path.with_file_name(format!("{stem}_MASS{step}.mtx"));
        // the names as Abaqus writes them, or as given when the case differs
        let given = |p: PathBuf, tag: &str| {
            if p.exists() || !lower.contains(tag) {
                p
            } else {
                path.to_path_buf()
            }
        };
        let stif = given(stif, "_stif");
        return Some((MatrixSource::Abaqus, [stif.clone(), mass, stif]));
    }
    if let Some(stem) = lower.strip_suffix(".sti").map(|s| &name[..s.len()]) {
        let sibling = |ext: &str| path.with_file_name(format!("{stem}.{ext}"));
        return Some((
            MatrixSource::Calculix,
            [sibling("sti"), sibling("mas"), sibling("dof")],
        ));
    }
    let stem = lower.strip_suffix("_k.mtx").map(|s| &name[..s.len()])?;
    let sibling = |suffix: &str| path.with_file_name(format!("{stem}{suffix}"));
    Some((
        MatrixSource::MatrixMarket,
        [path.to_path_buf(), sibling("_M.mtx"), sibling("_dofs.csv")],
    ))
}

/// Where the node coordinates of a matrix set are looked for when none is named: the CalculiX
/// deck `job.inp` beside `job.sti`, or `X_nodes.csv` beside `X_K.mtx`.
pub fn default_node_table(path: &Path) -> Option<PathBuf> {
    let (source, files) = matrix_files(path)?;
    Some(match source {
        MatrixSource::Calculix => files[0].with_extension("inp"),
        MatrixSource::MatrixMarket => {
            let name = files[2].file_name()?.to_str()?;
            files[2].with_file_name(format!("{}_nodes.csv", name.strip_suffix("_dofs.csv")?))
        }
        MatrixSource::NastranDmig | MatrixSource::NastranOp4 => nastran_deck_beside(&files[0]),
        MatrixSource::Abaqus => {
            let name = files[0].file_name()?.to_str()?;
            let lower = name.to_ascii_lowercase();
            let job = abaqus_name(&lower)?.0.len();
            files[0].with_file_name(format!("{}.inp", &name[..job]))
        }
    })
}

/// The Nastran deck beside `path`: `job.bdf`, `.dat` or `.nas` (any case), `job.bdf` when none
/// is there.
fn nastran_deck_beside(path: &Path) -> PathBuf {
    ["bdf", "dat", "nas", "BDF", "DAT", "NAS"]
        .iter()
        .map(|e| path.with_extension(e))
        .find(|p| p.exists())
        .unwrap_or_else(|| path.with_extension("bdf"))
}

/// `(job, step)` of an Abaqus matrix file name `job_STIF<step>.mtx` or `job_MASS<step>.mtx`
/// (lower case given).
fn abaqus_name(lower: &str) -> Option<(&str, &str)> {
    let stem = lower.strip_suffix(".mtx")?;
    let (job, tail) = stem
        .rsplit_once("_stif")
        .or_else(|| stem.rsplit_once("_mass"))?;
    (!tail.is_empty() && tail.bytes().all(|b| b.is_ascii_digit())).then_some((job, tail))
}

/// Reads the matrix set named by `path` ([`matrix_files`]).
///
/// # Errors
/// [`IoError::Content`] for a name that is neither; [`IoError::Io`] for a missing companion file;
/// [`IoError::Parse`] with file and line for a malformed entry, an index outside the DOF table, a
/// label given twice, an entry in both triangles of a CalculiX file, or a non-symmetric matrix.
pub fn read_matrices(path: &Path) -> Result<ExternalMatrices, IoError> {
    let Some((source, files)) = matrix_files(path) else {
        return Err(IoError::Content {
            path: path.to_path_buf(),
            reason: "femu reads matrices as CalculiX's job.sti (with job.mas and job.dof beside it), Abaqus's job_STIF1.mtx (with job_MASS1.mtx beside it), Nastran's DMIG punch job.pch or OUTPUT4 job.op4 (with the deck job.bdf or the table job_dofs.csv beside it) or MatrixMarket X_K.mtx (with X_M.mtx and X_dofs.csv beside it)".into(),
        });
    };
    let (k, m, dofs) = match source {
        MatrixSource::Calculix => {
            let dofs = read_calculix_dofs(&files[2])?;
            // the two files at once: each one's column sort is sequential
            // the stiffness keeps the entries that are exactly zero: its pattern is where other
            // matrices of the model (the mass, a group's stiffness) may have entries
            let (k, m) = rayon::join(
                || read_calculix_matrix(&files[0], dofs.len(), true),
                || read_calculix_matrix(&files[1], dofs.len(), false),
            );
            (k?, m?, dofs)
        }
        MatrixSource::MatrixMarket => {
            let dofs = read_dof_csv(&files[2])?;
            let read = |p: &Path| {
                let a = femu_sparse::mtx::read_matrix_market(p).map_err(|e| IoError::Content {
                    path: p.to_path_buf(),
                    reason: e.to_string(),
                })?;
                if a.rows() != dofs.len() || a.cols() != dofs.len() {
                    return Err(IoError::Content {
                        path: p.to_path_buf(),
                        reason: format!(
                            "the matrix is {} x {}, the DOF table {} has {} rows",
                            a.rows(),
                            a.cols(),
                            files[2].display(),
                            dofs.len()
                        ),
                    });
                }
                symmetric(p, &a, &dofs)?;
                Ok(a)
            };
            (read(&files[0])?, read(&files[1])?, dofs)
        }
        MatrixSource::Abaqus => read_abaqus_pair(&files[0], &files[1])?,
        MatrixSource::NastranDmig => read_dmig_pair(&files[0])?,
        MatrixSource::NastranOp4 => read_op4_pair(&files[0], &files[2])?,
    };
    Ok(ExternalMatrices {
        k,
        m,
        dofs,
        source,
        files,
    })
}

/// Refuses a matrix that is not symmetric to round-off (`1e-10` of its largest entry), naming the
/// worst pair by its DOF labels.
fn symmetric(path: &Path, a: &SparseMatrix, dofs: &[DofLabel]) -> Result<(), IoError> {
    let (defect, i, j) = femu_sparse::csc::symmetry_defect(a);
    if defect > 1e-10 {
        return Err(IoError::Content {
            path: path.to_path_buf(),
            reason: format!(
                "the matrix is not symmetric: the entries of rows {} and {} ({} and {}) differ by {defect:.1e} of its largest entry",
                i + 1,
                j + 1,
                label(dofs[i]),
                label(dofs[j])
            ),
        });
    }
    Ok(())
}

/// `node 12 z`.
pub fn label(d: DofLabel) -> String {
    format!(
        "node {} {}",
        d.node,
        ["x", "y", "z", "rx", "ry", "rz"][d.component]
    )
}

fn read_text(path: &Path) -> Result<String, IoError> {
    std::fs::read(path)
        .map(|b| String::from_utf8_lossy(&b).into_owned())
        .map_err(|e| IoError::io(path, e))
}

fn parse_error(path: &Path, line: usize, reason: String) -> IoError {
    IoError::Parse {
        path: path.to_path_buf(),
        line,
        reason,
    }
}

/// Refuses a label seen before, saying where.
fn unique(
    seen: &mut HashMap<DofLabel, usize>,
    d: DofLabel,
    path: &Path,
    line: usize,
    hint: &str,
) -> Result<(), IoError> {
    if let Some(first) = seen.insert(d, line) {
        return Err(parse_error(
            path,
            line,
            format!("{} is listed again (first at line {first}){hint}", label(d)),
        ));
    }
    Ok(())
}

/// CalculiX's `.dof`: one `node.direction` per row.
fn read_calculix_dofs(path: &Path) -> Result<Vec<DofLabel>, IoError> {
    let text = read_text(path)?;
    let mut dofs = Vec::new();
    let mut seen = HashMap::new();
    for (i, raw) in text.lines().enumerate() {
        let t = raw.trim();
        if t.is_empty() {
            continue;
        }
        let parsed = t.split_once('.').and_then(|(n, c)| {
            let node = n.parse::<u64>().ok()?;
            let c = c.parse::<usize>().ok().filter(|c| (1..=6).contains(c))?;
            Some(DofLabel {
                node,
                component: c - 1,
            })
        });
        let d = parsed.ok_or_else(|| {
            parse_error(
                path,
                i + 1,
                format!("expected node.direction (direction 1-6), got {t:?}"),
            )
        })?;
        unique(
            &mut seen,
            d,
            path,
            i + 1,
            ": CalculiX stores the DOFs of the solids it expands shells and beams into, which femu cannot map to the deck's nodes; export the matrices of a model of solids, or the modes (.frd) instead",
        )?;
        dofs.push(d);
    }
    if dofs.is_empty() {
        return Err(IoError::Content {
            path: path.to_path_buf(),
            reason: "no DOF in the file".into(),
        });
    }
    Ok(dofs)
}

/// CalculiX's `.sti` or `.mas`: `row column value`, 1-based, one triangle. The file is parsed in
/// chunks of whole lines on every thread and the entries are sorted into columns by counting
/// ([`femu_sparse::csc::from_entries`]): a 105,840-DOF set (two files of 133 MB) reads in a
/// fraction of the time the `TriMat` route took (docs/SCALING.md, "Reading another solver's
/// matrices").
fn read_calculix_matrix(path: &Path, n: usize, keep_zeros: bool) -> Result<SparseMatrix, IoError> {
    use rayon::prelude::*;
    let bytes = std::fs::read(path).map_err(|e| IoError::io(path, e))?;
    let chunks = line_chunks(&bytes, 8 * rayon::current_num_threads());
    let parts: Vec<Result<Chunk, IoError>> = chunks
        .par_iter()
        .map(|&(start, end, first_line)| {
            parse_chunk(&bytes[start..end], first_line, n, keep_zeros, path)
        })
        .collect();
    let mut entries = Vec::new();
    let (mut upper, mut lower): (Option<usize>, Option<usize>) = (None, None);
    for part in parts {
        let part = part?;
        upper = upper.or(part.upper);
        lower = lower.or(part.lower);
        entries.extend(part.entries);
    }
    if let (Some(u), Some(l)) = (upper, lower) {
        return Err(parse_error(
            path,
            u.max(l),
            format!(
                "entries in both triangles (upper at line {u}, lower at line {l}): CalculiX stores one"
            ),
        ));
    }
    let mirrored = entries.iter().copied().chain(
        entries
            .iter()
            .filter(|e| e.0 != e.1)
            .map(|&(r, c, v)| (c, r, v)),
    );
    Ok(femu_sparse::csc::from_entry_iter(n, n, mirrored))
}

/// `(start, end, first line number)` of about `count` pieces of `bytes` cut after a newline.
fn line_chunks(bytes: &[u8], count: usize) -> Vec<(usize, usize, usize)> {
    let size = bytes.len().div_ceil(count.max(1)).max(1);
    let mut chunks = Vec::new();
    let (mut start, mut line) = (0, 1);
    while start < bytes.len() {
        let mut end = (start + size).min(bytes.len());
        while end < bytes.len() && bytes[end - 1] != b'\n' {
            end += 1;
        }
        chunks.push((start, end, line));
        line += bytes[start..end].iter().filter(|b| **b == b'\n').count();
        start = end;
    }
    chunks
}

/// The entries of a chunk of a CalculiX matrix file, and the first line of each triangle in it.
struct Chunk {
    entries: Vec<(usize, usize, f64)>,
    upper: Option<usize>,
    lower: Option<usize>,
}

fn parse_chunk(
    text: &[u8],
    first_line: usize,
    n: usize,
    keep_zeros: bool,
    path: &Path,
) -> Result<Chunk, IoError> {
    let mut chunk = Chunk {
        entries: Vec::with_capacity(text.len() / 30),
        upper: None,
        lower: None,
    };
    for (k, raw) in text.split(|b| *b == b'\n').enumerate() {
        let line = first_line + k;
        let mut fields = [&raw[..0]; 3];
        let mut count = 0;
        let mut i = 0;
        while i < raw.len() {
            while i < raw.len() && raw[i].is_ascii_whitespace() {
                i += 1;
            }
            let start = i;
            while i < raw.len() && !raw[i].is_ascii_whitespace() {
                i += 1;
            }
            if i > start {
                if count < 3 {
                    fields[count] = &raw[start..i];
                }
                count += 1;
            }
        }
        if count == 0 {
            continue;
        }
        if count != 3 {
            return Err(parse_error(
                path,
                line,
                format!(
                    "expected 'row column value', got {:?}",
                    String::from_utf8_lossy(raw).trim()
                ),
            ));
        }
        let [a, b, v] = fields;
        let index = |s: &[u8], what: &str| {
            let mut value: usize = 0;
            let digits = !s.is_empty()
                && s.iter().all(|d| {
                    value = value
                        .saturating_mul(10)
                        .saturating_add(usize::from(d.wrapping_sub(b'0')));
                    d.is_ascii_digit()
                });
            if digits && (1..=n).contains(&value) {
                Ok(value - 1)
            } else {
                Err(parse_error(
                    path,
                    line,
                    format!(
                        "{what} {:?} is not in 1..={n} (the rows of the .dof file)",
                        String::from_utf8_lossy(s)
                    ),
                ))
            }
        };
        let (r, c) = (index(a, "row")?, index(b, "column")?);
        let value = std::str::from_utf8(v)
            .ok()
            .and_then(|s| {
                s.parse::<f64>()
                    .ok()
                    .or_else(|| s.replace(['D', 'd'], "e").parse().ok())
            })
            .filter(|v| v.is_finite())
            .ok_or_else(|| {
                parse_error(
                    path,
                    line,
                    format!(
                        "value {:?} is not a finite number",
                        String::from_utf8_lossy(v)
                    ),
                )
            })?;
        if r < c {
            chunk.upper.get_or_insert(line);
        } else if r > c {
            chunk.lower.get_or_insert(line);
        }
        if keep_zeros || value != 0.0 || r == c {
            chunk.entries.push((r, c, value));
        }
    }
    Ok(chunk)
}

/// The rows of a CSV table: `(line, trimmed text, fields)`, without blank and `#` lines and
/// without a first line whose first field is `header`.
fn csv_rows<'a>(
    text: &'a str,
    header: &'a str,
) -> impl Iterator<Item = (usize, &'a str, Vec<&'a str>)> + 'a {
    let mut first = true;
    text.lines().enumerate().filter_map(move |(i, raw)| {
        let t = raw.trim();
        if t.is_empty() || t.starts_with('#') {
            return None;
        }
        let f: Vec<&str> = t.split(',').map(str::trim).collect();
        let is_header = first && f.first().is_some_and(|s| s.eq_ignore_ascii_case(header));
        first = false;
        (!is_header).then_some((i + 1, t, f))
    })
}

/// `X_dofs.csv`: `row,node,component`, rows 1..n in order.
fn read_dof_csv(path: &Path) -> Result<Vec<DofLabel>, IoError> {
    let text = read_text(path)?;
    let mut dofs = Vec::new();
    let mut seen = HashMap::new();
    for (line, t, f) in csv_rows(&text, "row") {
        let bad = || {
            parse_error(
                path,
                line,
                format!(
                    "expected 'row,node,component' (component x, y, z, rx, ry, rz or 1-6), got {t:?}"
                ),
            )
        };
        if f.len() != 3 {
            return Err(bad());
        }
        let row = f[0].parse::<usize>().map_err(|_| bad())?;
        if row != dofs.len() + 1 {
            return Err(parse_error(
                path,
                line,
                format!(
                    "row {row} where row {} was expected: list the rows in order",
                    dofs.len() + 1
                ),
            ));
        }
        let node = f[1].parse::<u64>().map_err(|_| bad())?;
        let names = ["x", "y", "z", "rx", "ry", "rz"];
        let component = names
            .iter()
            .position(|n| f[2].eq_ignore_ascii_case(n))
            .or_else(|| {
                f[2].parse::<usize>()
                    .ok()
                    .filter(|c| (1..=6).contains(c))
                    .map(|c| c - 1)
            })
            .ok_or_else(bad)?;
        let d = DofLabel { node, component };
        unique(&mut seen, d, path, line, "")?;
        dofs.push(d);
    }
    if dofs.is_empty() {
        return Err(IoError::Content {
            path: path.to_path_buf(),
            reason: "no DOF in the table".into(),
        });
    }
    Ok(dofs)
}

/// Node coordinates for a matrix set: the `*NODE` lines of an Abaqus/CalculiX deck (`.inp`,
/// whatever its elements), or a CSV table `node,x,y,z` (a header line is allowed).
///
/// # Errors
/// [`IoError::Content`] for another extension or a table without nodes; [`IoError::Parse`] with
/// file and line for a malformed line or a node given twice.
pub fn read_node_table(path: &Path) -> Result<Vec<(u64, [f64; 3])>, IoError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("inp") => crate::inp::read_nodes(path),
        Some("csv") => read_node_csv(path),
        Some("bdf" | "dat" | "nas") => {
            let grids = crate::nastran::read_grids(path)?;
            if let Some(g) = grids.iter().find(|g| g.cd != 0) {
                return Err(IoError::Content {
                    path: path.to_path_buf(),
                    reason: format!(
                        "GRID {} has its displacements in frame CD = {}: another solver's matrices on it are in that frame, and femu's rows are in the basic one (give the grids CD = 0, or the matrices in the basic frame)",
                        g.id, g.cd
                    ),
                });
            }
            Ok(grids.iter().map(|g| (g.id, g.position)).collect())
        }
        _ => Err(IoError::Content {
            path: path.to_path_buf(),
            reason: "node coordinates are read from an Abaqus/CalculiX deck (.inp, its *NODE lines), a Nastran deck's GRIDs (.bdf, .dat, .nas) or a CSV table (.csv: node,x,y,z)".into(),
        }),
    }
}

fn read_node_csv(path: &Path) -> Result<Vec<(u64, [f64; 3])>, IoError> {
    let text = read_text(path)?;
    let mut nodes = Vec::new();
    let mut seen = HashMap::new();
    for (line, t, f) in csv_rows(&text, "node") {
        let bad = || parse_error(path, line, format!("expected 'node,x,y,z', got {t:?}"));
        if f.len() != 4 {
            return Err(bad());
        }
        let id = f[0].parse::<u64>().map_err(|_| bad())?;
        let mut x = [0.0; 3];
        for c in 0..3 {
            x[c] = f[c + 1]
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(bad)?;
        }
        if let Some(first) = seen.insert(id, line) {
            return Err(parse_error(
                path,
                line,
                format!("node {id} is listed again (first at line {first})"),
            ));
        }
        nodes.push((id, x));
    }
    if nodes.is_empty() {
        return Err(IoError::Content {
            path: path.to_path_buf(),
            reason: "no node in the table".into(),
        });
    }
    Ok(nodes)
}

/// Writes the node table `node,x,y,z` that [`read_node_table`] reads.
///
/// # Errors
/// [`IoError::Io`] if the file cannot be written.
pub fn write_node_table(path: &Path, nodes: &[(u64, [f64; 3])]) -> Result<(), IoError> {
    let mut s = String::from("node,x,y,z\n");
    for (id, x) in nodes {
        s.push_str(&format!("{id},{:e},{:e},{:e}\n", x[0], x[1], x[2]));
    }
    std::fs::write(path, s).map_err(|e| IoError::io(path, e))
}

/// One labelled entry of an Abaqus matrix file, with its line.
type LabelledEntry = (DofLabel, DofLabel, f64, usize);

/// The entries of an Abaqus `*MATRIX INPUT` text file: `row node, row DOF, column node, column
/// DOF, value` per line; `**` comments and blank lines skipped.
fn read_abaqus_entries(path: &Path) -> Result<Vec<LabelledEntry>, IoError> {
    let text = read_text(path)?;
    let mut out = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let t = raw.trim();
        if t.is_empty() || t.starts_with("**") {
            continue;
        }
        let f: Vec<&str> = t
            .split(|c: char| c == ',' || c.is_whitespace())
            .filter(|s| !s.is_empty())
            .collect();
        if f.len() != 5 {
            return Err(parse_error(
                path,
                line,
                format!(
                    "expected `node, DOF, node, DOF, value` (Abaqus's FORMAT=MATRIX INPUT), got {} fields in {t:?}{}",
                    f.len(),
                    if f.len() == 3 {
                        ": FORMAT=COORDINATE has no node labels; write the matrices with FORMAT=MATRIX INPUT"
                    } else {
                        ""
                    }
                ),
            ));
        }
        let dof = |n: &str, c: &str| -> Result<DofLabel, IoError> {
            let node: i64 = n
                .parse()
                .map_err(|_| parse_error(path, line, format!("node {n:?} is not an integer")))?;
            if node <= 0 {
                return Err(parse_error(
                    path,
                    line,
                    format!(
                        "node {node} is an Abaqus internal node (a Lagrange multiplier or an element's internal node), which has no place in the model: generate the matrices of a model without them"
                    ),
                ));
            }
            let c: usize = c
                .parse()
                .ok()
                .filter(|c| (1..=6).contains(c))
                .ok_or_else(|| {
                    parse_error(
                        path,
                        line,
                        format!(
                            "DOF {c:?} of node {node} is not 1 to 6 (displacements and rotations)"
                        ),
                    )
                })?;
            Ok(DofLabel {
                node: node as u64,
                component: c - 1,
            })
        };
        let (r, c) = (dof(f[0], f[1])?, dof(f[2], f[3])?);
        let v = f[4]
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| parse_error(path, line, format!("value {:?} is not a number", f[4])))?;
        out.push((r, c, v, line));
    }
    Ok(out)
}

/// Abaqus's stiffness and mass files: the rows are the labels either uses, sorted by node and
/// component, less the DOFs Abaqus constrained (a unit diagonal stiffness alone, no mass).
fn read_abaqus_pair(
    stif: &Path,
    mass: &Path,
) -> Result<(SparseMatrix, SparseMatrix, Vec<DofLabel>), IoError> {
    let (k, m) = rayon::join(|| read_abaqus_entries(stif), || read_abaqus_entries(mass));
    labelled_pair((stif, &k?), (mass, &m?), true)
}

/// A punch file's DMIG stiffness and mass: `KAAX` and `MAAX`, or the one matrix whose name starts
/// with K and the one with M.
fn read_dmig_pair(path: &Path) -> Result<(SparseMatrix, SparseMatrix, Vec<DofLabel>), IoError> {
    let all = crate::nastran::read_dmig(path)?;
    let names: Vec<&String> = all.keys().collect();
    let pick = |exact: &str, first: char| -> Result<&crate::nastran::Dmig, IoError> {
        if let Some(m) = all.get(exact) {
            return Ok(m);
        }
        let mut like = all.values().filter(|m| m.name.starts_with(first));
        match (like.next(), like.next()) {
            (Some(m), None) => Ok(m),
            _ => Err(IoError::Content {
                path: path.to_path_buf(),
                reason: format!(
                    "no DMIG {exact} (and not one matrix named {first}...): the file has {names:?}; PARAM,EXTOUT,DMIGPCH writes KAAX and MAAX"
                ),
            }),
        }
    };
    let labelled = |m: &crate::nastran::Dmig| -> Vec<LabelledEntry> {
        m.entries
            .iter()
            .map(|&(g, c, gj, cj, v, line)| {
                (
                    DofLabel {
                        node: g,
                        component: c - 1,
                    },
                    DofLabel {
                        node: gj,
                        component: cj - 1,
                    },
                    v,
                    line,
                )
            })
            .collect()
    };
    let (k, m) = (pick("KAAX", 'K')?, pick("MAAX", 'M')?);
    labelled_pair((path, &labelled(k)), (path, &labelled(m)), false)
}

/// The names an OP4's stiffness and mass are looked for by, in order: the a-set's (after every
/// constraint and reduction), the f-set's, the l-set's, the g-set's.
const OP4_PAIRS: &[(&str, &str)] = &[
    ("KAA", "MAA"),
    ("KFF", "MFF"),
    ("KLL", "MLL"),
    ("KGG", "MGG"),
];

/// An OP4 file's stiffness and mass ([`OP4_PAIRS`], or the one matrix whose name starts with K
/// and the one with M), labelled by `rows`: a DOF table (`job_dofs.csv`, any set), or the deck
/// beside them, whose g-set ([`crate::nastran::read_gset`]) labels `KGG` and `MGG`, less the
/// components the deck constrains and those with neither stiffness nor mass (Nastran's AUTOSPC
/// would fix them: the rotations of grids only solids touch).
fn read_op4_pair(
    path: &Path,
    rows: &Path,
) -> Result<(SparseMatrix, SparseMatrix, Vec<DofLabel>), IoError> {
    let all = crate::op4::read_op4(path)?;
    let content = |reason: String| IoError::Content {
        path: path.to_path_buf(),
        reason,
    };
    let find = |n: &str| all.iter().position(|m| m.name.eq_ignore_ascii_case(n));
    let one = |first: char| {
        let mut like = all
            .iter()
            .enumerate()
            .filter(|(_, m)| m.name.to_ascii_uppercase().starts_with(first));
        match (like.next(), like.next()) {
            (Some((i, _)), None) => Some(i),
            _ => None,
        }
    };
    let Some((ik, im)) = OP4_PAIRS
        .iter()
        .find_map(|(k, m)| Some((find(k)?, find(m)?)))
        .or_else(|| Some((one('K')?, one('M')?)))
    else {
        let names: Vec<&str> = all.iter().map(|m| m.name.as_str()).collect();
        return Err(content(format!(
            "no stiffness and mass pair (KAA and MAA, KFF and MFF, KLL and MLL, KGG and MGG, or one matrix named K... and one M...): the file has {names:?}"
        )));
    };
    let (k, m) = (&all[ik], &all[im]);
    for a in [k, m] {
        if a.is_complex() {
            return Err(content(format!(
                "matrix {} ({}) is complex: a stiffness or mass is real",
                a.name,
                a.kind_name()
            )));
        }
        if a.rows != a.cols || a.rows != k.rows {
            return Err(content(format!(
                "{} is {} x {} and {} is {} x {}: a stiffness and a mass are square, of one size",
                k.name, k.rows, k.cols, m.name, m.rows, m.cols
            )));
        }
    }
    let (n, names) = (k.rows, format!("{} and {}", k.name, m.name));
    // the two matrices moved out of the file's list into compressed columns, not copied
    let mut slots: Vec<Option<crate::op4::Op4Matrix>> = all.into_iter().map(Some).collect();
    let csc =
        |a: crate::op4::Op4Matrix| SparseMatrix::new_csc((n, n), a.col_start, a.row_index, a.re);
    let (kc, mc) = (
        csc(slots[ik].take().expect("chosen once")),
        csc(slots[im].take().expect("K and M are two matrices")),
    );
    let table = path.with_file_name(format!(
        "{}_dofs.csv",
        path.file_stem().and_then(|s| s.to_str()).unwrap_or("job")
    ));
    let is_table = rows
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"));
    if is_table {
        let dofs = read_dof_csv(rows)?;
        if dofs.len() != n {
            return Err(content(format!(
                "{names} have {n} rows, the DOF table {} has {}",
                rows.display(),
                dofs.len()
            )));
        }
        symmetric(path, &kc, &dofs)?;
        symmetric(path, &mc, &dofs)?;
        return Ok((kc, mc, dofs));
    }
    if !rows.exists() {
        return Err(content(format!(
            "no DOF table {} and no deck {} beside the matrices: OP4 rows carry no labels; give the deck whose g-set KGG and MGG are on, or a table row,node,component",
            table.display(),
            rows.display()
        )));
    }
    let gset = crate::nastran::read_gset(rows)?;
    if n != 6 * gset.grids.len() {
        return Err(content(format!(
            "{names} have {n} rows; the g-set of the deck {} has {} ({} grids x 6): a matrix of another set (KAA, KFF: after constraints or reductions) needs its DOF table {}",
            rows.display(),
            6 * gset.grids.len(),
            gset.grids.len(),
            table.display()
        )));
    }
    let all_dofs: Vec<DofLabel> = gset
        .grids
        .iter()
        .flat_map(|&node| (0..6).map(move |component| DofLabel { node, component }))
        .collect();
    symmetric(path, &kc, &all_dofs)?;
    symmetric(path, &mc, &all_dofs)?;
    // kept: not constrained, and with stiffness or mass
    let mut touched = vec![false; n];
    for a in [&kc, &mc] {
        for (r, c, v) in femu_sparse::csc::entries(a) {
            if v != 0.0 {
                touched[r] = true;
                touched[c] = true;
            }
        }
    }
    let mut new_index = vec![usize::MAX; n];
    let mut dofs = Vec::new();
    for (i, d) in all_dofs.iter().enumerate() {
        if touched[i] && !gset.constrained.contains(&(d.node, d.component)) {
            new_index[i] = dofs.len();
            dofs.push(*d);
        }
    }
    if dofs.is_empty() {
        return Err(content("no unconstrained DOF in the matrices".into()));
    }
    if dofs.len() == n {
        return Ok((kc, mc, dofs));
    }
    let keep = |a: &SparseMatrix| {
        femu_sparse::csc::from_entry_iter(
            dofs.len(),
            dofs.len(),
            femu_sparse::csc::entries(a).filter_map(|(r, c, v)| {
                let (i, j) = (new_index[r], new_index[c]);
                (i != usize::MAX && j != usize::MAX).then_some((i, j, v))
            }),
        )
    };
    Ok((keep(&kc), keep(&mc), dofs))
}

/// The stiffness and mass of labelled entries: the rows are the labels either uses, sorted by
/// node and component; with `constrained_rule`, less the DOFs whose only stiffness entry is a
/// unit diagonal and which have no mass (Abaqus's constrained DOFs). Each unordered pair is given
/// once, or twice (both triangles) with one value.
fn labelled_pair(
    (stif, k): (&Path, &[LabelledEntry]),
    (mass, m): (&Path, &[LabelledEntry]),
    constrained_rule: bool,
) -> Result<(SparseMatrix, SparseMatrix, Vec<DofLabel>), IoError> {
    // a constrained DOF: its only stiffness entry the unit diagonal, and no mass
    let mut stiff_rows: HashMap<DofLabel, (usize, bool)> = HashMap::new();
    for &(r, c, v, _) in k {
        for d in [r, c] {
            let e = stiff_rows.entry(d).or_insert((0, true));
            e.0 += 1;
            e.1 &= r == c && v == 1.0;
        }
    }
    let with_mass: std::collections::HashSet<DofLabel> = m
        .iter()
        .flat_map(|&(r, c, v, _)| [(r, v), (c, v)])
        .filter(|(_, v)| *v != 0.0)
        .map(|(d, _)| d)
        .collect();
    let constrained = |d: &DofLabel| {
        constrained_rule
            && !with_mass.contains(d)
            && stiff_rows.get(d).is_some_and(|&(_, unit)| unit)
    };
    let mut dofs: Vec<DofLabel> = k
        .iter()
        .chain(m)
        .flat_map(|&(r, c, _, _)| [r, c])
        .filter(|d| !constrained(d))
        .collect();
    dofs.sort_unstable_by_key(|d| (d.node, d.component));
    dofs.dedup();
    if dofs.is_empty() {
        return Err(IoError::Content {
            path: stif.to_path_buf(),
            reason: "no unconstrained DOF in the matrices".into(),
        });
    }
    let index: HashMap<DofLabel, usize> = dofs.iter().enumerate().map(|(i, d)| (*d, i)).collect();
    let n = dofs.len();
    let assemble = |path: &Path, entries: &[LabelledEntry], keep_zeros: bool| {
        // each unordered pair once, or twice (both triangles) with the same value to round-off of
        // the largest entry (kept as their mean)
        let scale = entries.iter().fold(0.0f64, |m, e| m.max(e.2.abs()));
        let mut pairs: HashMap<(usize, usize), (f64, usize, bool)> =
            HashMap::with_capacity(entries.len());
        for &(r, c, v, line) in entries {
            let (Some(&i), Some(&j)) = (index.get(&r), index.get(&c)) else {
                // a constrained DOF's unit diagonal
                continue;
            };
            let key = (i.min(j), i.max(j));
            let lower = i >= j;
            match pairs.get(&key) {
                None => {
                    pairs.insert(key, (v, line, lower));
                }
                Some(&(w, first, was_lower)) => {
                    let first_lower = was_lower;
                    if i == j || was_lower == lower {
                        return Err(parse_error(
                            path,
                            line,
                            format!(
                                "the entry of {} and {} is given again (first at line {first})",
                                label(r),
                                label(c)
                            ),
                        ));
                    }
                    if (v - w).abs() > 1e-10 * scale {
                        return Err(parse_error(
                            path,
                            line,
                            format!(
                                "the matrix is not symmetric: the entry of {} and {} is {v:e} here and {w:e} at line {first} ({:.1e} of its largest entry apart)",
                                label(r),
                                label(c),
                                (v - w).abs() / scale
                            ),
                        ));
                    }
                    pairs.insert(key, (0.5 * (v + w), first, first_lower));
                }
            }
        }
        let entries: Vec<(usize, usize, f64)> = pairs
            .into_iter()
            .filter(|(_, (v, _, _))| keep_zeros || *v != 0.0)
            .flat_map(|((i, j), (v, _, _))| {
                let mirror = (i != j).then_some((j, i, v));
                std::iter::once((i, j, v)).chain(mirror)
            })
            .collect();
        Ok(femu_sparse::csc::from_entry_iter(n, n, entries.into_iter()))
    };
    let km = assemble(stif, k, true)?;
    let mm = assemble(mass, m, false)?;
    Ok((km, mm, dofs))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("femu-matrices-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    /// The companions of each name, in the case the user wrote.
    #[test]
    fn companion_files() {
        let (s, f) = matrix_files(Path::new("/a/Job.STI")).unwrap();
        assert_eq!(s, MatrixSource::Calculix);
        assert_eq!(f[1], Path::new("/a/Job.mas"));
        assert_eq!(f[2], Path::new("/a/Job.dof"));
        assert_eq!(
            default_node_table(Path::new("/a/Job.sti")).unwrap(),
            Path::new("/a/Job.inp")
        );
        let (s, f) = matrix_files(Path::new("/a/plate_K.mtx")).unwrap();
        assert_eq!(s, MatrixSource::MatrixMarket);
        assert_eq!(f[1], Path::new("/a/plate_M.mtx"));
        assert_eq!(f[2], Path::new("/a/plate_dofs.csv"));
        assert_eq!(
            default_node_table(Path::new("/a/plate_K.mtx")).unwrap(),
            Path::new("/a/plate_nodes.csv")
        );
        // Abaqus: named by either file; its labels are in the entries (no DOF table)
        for name in ["/a/Job_STIF2.mtx", "/a/Job_MASS2.mtx"] {
            let (s, f) = matrix_files(Path::new(name)).unwrap();
            assert_eq!(s, MatrixSource::Abaqus);
            assert_eq!(f[0], Path::new("/a/Job_STIF2.mtx"));
            assert_eq!(f[1], Path::new("/a/Job_MASS2.mtx"));
        }
        assert_eq!(
            default_node_table(Path::new("/a/Job_MASS2.mtx")).unwrap(),
            Path::new("/a/Job.inp")
        );
        assert!(matrix_files(Path::new("/a/job_STIFF.mtx")).is_none());
    }

    /// A 2-DOF CalculiX set written by hand: the upper triangle mirrored, labels read.
    #[test]
    fn calculix_set_by_hand() {
        let d = dir("ccx");
        std::fs::write(d.join("j.dof"), "7.1\n7.3\n").unwrap();
        std::fs::write(
            d.join("j.sti"),
            "1 1  4.0e+00\n1 2 -1.0e+00\n2 2  3.0e+00\n",
        )
        .unwrap();
        std::fs::write(d.join("j.mas"), "1 1 2.0\n1 2 0.0\n2 2 1.0\n").unwrap();
        let e = read_matrices(&d.join("j.sti")).unwrap();
        assert_eq!(e.source, MatrixSource::Calculix);
        assert_eq!(
            e.dofs,
            [
                DofLabel {
                    node: 7,
                    component: 0
                },
                DofLabel {
                    node: 7,
                    component: 2
                }
            ]
        );
        assert_eq!(e.k.get(1, 0), Some(&-1.0));
        assert_eq!(e.k.get(0, 1), Some(&-1.0));
        assert_eq!(e.m.get(0, 1), None);
        assert_eq!(e.m.get(1, 1), Some(&1.0));
    }

    /// Each malformed CalculiX set is refused with its file and line.
    #[test]
    fn calculix_refusals() {
        let d = dir("ccxbad");
        let cases: [(&str, &str, &str); 5] = [
            ("2.1\n2.1\n", "1 1 1\n", "j.dof:2: node 2 x is listed again"),
            ("2.7\n", "1 1 1\n", "j.dof:1: expected node.direction"),
            (
                "2.1\n3.1\n",
                "1 3 1\n",
                "j.sti:1: column \"3\" is not in 1..=2",
            ),
            (
                "2.1\n3.1\n",
                "1 2 1\n2 1 1\n",
                "j.sti:2: entries in both triangles",
            ),
            (
                "2.1\n",
                "1 1 nan\n",
                "j.sti:1: value \"nan\" is not a finite",
            ),
        ];
        for (dof, sti, want) in cases {
            std::fs::write(d.join("j.dof"), dof).unwrap();
            std::fs::write(d.join("j.sti"), sti).unwrap();
            std::fs::write(d.join("j.mas"), "1 1 1\n").unwrap();
            let e = read_matrices(&d.join("j.sti")).unwrap_err().to_string();
            assert!(e.contains(want), "{e}\nwanted {want}");
        }
        std::fs::remove_file(d.join("j.mas")).unwrap();
        std::fs::write(d.join("j.dof"), "2.1\n").unwrap();
        std::fs::write(d.join("j.sti"), "1 1 1\n").unwrap();
        let e = read_matrices(&d.join("j.sti")).unwrap_err().to_string();
        assert!(e.contains("j.mas"), "{e}");
    }

    /// A MatrixMarket set: DOF table by names and numbers; a non-symmetric general matrix and a
    /// size that disagrees with the table refused, naming the DOFs.
    #[test]
    fn matrix_market_set() {
        let d = dir("mm");
        std::fs::write(
            d.join("a_dofs.csv"),
            "row,node,component\n1,4,x\n2,4,RZ\n3,9,2\n",
        )
        .unwrap();
        let sym =
            "%%MatrixMarket matrix coordinate real symmetric\n3 3 4\n1 1 2\n2 2 2\n3 3 2\n3 1 -1\n";
        std::fs::write(d.join("a_K.mtx"), sym).unwrap();
        std::fs::write(d.join("a_M.mtx"), sym).unwrap();
        let e = read_matrices(&d.join("a_K.mtx")).unwrap();
        assert_eq!(e.dofs[1].component, 5);
        assert_eq!(e.dofs[2].component, 1);
        assert_eq!(e.k.get(0, 2), Some(&-1.0));
        std::fs::write(
            d.join("a_M.mtx"),
            "%%MatrixMarket matrix coordinate real general\n3 3 4\n1 1 2\n2 2 2\n3 3 2\n3 1 -1\n",
        )
        .unwrap();
        let e = read_matrices(&d.join("a_K.mtx")).unwrap_err().to_string();
        assert!(e.contains("not symmetric") && e.contains("node 9 y"), "{e}");
        std::fs::write(
            d.join("a_M.mtx"),
            "%%MatrixMarket matrix coordinate real symmetric\n2 2 1\n1 1 2\n",
        )
        .unwrap();
        let e = read_matrices(&d.join("a_K.mtx")).unwrap_err().to_string();
        assert!(e.contains("is 2 x 2, the DOF table"), "{e}");
        std::fs::write(d.join("a_dofs.csv"), "1,4,x\n3,4,y\n").unwrap();
        let e = read_matrices(&d.join("a_K.mtx")).unwrap_err().to_string();
        assert!(e.contains("a_dofs.csv:2: row 3 where row 2"), "{e}");
    }

    /// Node tables: a deck's `*NODE` lines (its elements ignored, whatever they are) and CSV.
    #[test]
    fn node_tables() {
        let d = dir("nodes");
        std::fs::write(
            d.join("n.inp"),
            "** shells\n*NODE, NSET=ALL\n1, 0., 0., 0.\n2, 1.5D0, 0, 0\n*ELEMENT, TYPE=S4R\n1, 1, 2, 2, 1\n*NODE\n3, 0, 2, 1\n",
        )
        .unwrap();
        let n = read_node_table(&d.join("n.inp")).unwrap();
        assert_eq!(
            n,
            [(1, [0.0; 3]), (2, [1.5, 0.0, 0.0]), (3, [0.0, 2.0, 1.0])]
        );
        write_node_table(&d.join("n.csv"), &n).unwrap();
        assert_eq!(read_node_table(&d.join("n.csv")).unwrap(), n);
        std::fs::write(d.join("b.csv"), "node,x,y,z\n1,0,0,0\n1,1,0,0\n").unwrap();
        let e = read_node_table(&d.join("b.csv")).unwrap_err().to_string();
        assert!(e.contains("b.csv:3: node 1 is listed again"), "{e}");
        std::fs::write(d.join("b.inp"), "*NODE, SYSTEM=S\n1, 1, 0, 0\n").unwrap();
        let e = read_node_table(&d.join("b.inp")).unwrap_err().to_string();
        assert!(e.contains("b.inp:1: *NODE, SYSTEM=S"), "{e}");
        assert!(read_node_table(&d.join("n.bdf")).is_err());
    }
}
