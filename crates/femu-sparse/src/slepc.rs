//! The eigen solve handed to SLEPc on PETSc with MUMPS, under MPI: for models whose factor
//! outgrows one machine (docs/SCALING.md).
//!
//! femu writes `K` and `M` in PETSc's binary format (big-endian; 32- or 64-bit indices as the
//! installed PETSc was built), runs its driver (`slepc/femu_slepc.py`, shipped inside femu and
//! written next to the matrices) under `mpirun`: Krylov-Schur with shift-and-invert, MUMPS
//! Cholesky (`LDL^T` for a shift inside the spectrum), then the count of eigenvalues below each
//! end of the interval by the inertia of `K - sigma M` factored by MUMPS. femu reads the
//! eigenpairs back, `M`-normalises them, computes every residual itself and returns the same
//! [`Modes`] as its own solver, with the count in [`SturmCheck`]: a count that disagrees with the
//! pairs returned is [`SparseError::SturmMismatch`], never a result.
//!
//! Select it with [`EigenOptions::engine`]: every eigen solve of femu takes it, and every workflow
//! carries the [`EigenOptions`] its solves use (there is no process-wide default to set).

use crate::eigen::{EigenOptions, EigenStats, Modes, SturmCheck, Which, one_norm, residual_of};
use crate::{SparseError, SparseMatrix};
use faer::Mat;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The driver run under MPI.
const DRIVER: &str = include_str!("../slepc/femu_slepc.py");

/// What to install when the engine is missing.
pub const INSTALL_HINT: &str = "install the Debian packages python3-slepc4py-real, python3-petsc4py-real and openmpi-bin (scripts/setup-slepc.sh does)";

/// How to run SLEPc.
#[derive(Debug, Clone, PartialEq)]
pub struct SlepcOptions {
    /// MPI ranks (`mpirun -n`).
    pub ranks: usize,
    /// An MPI hostfile for a cluster (`mpirun --hostfile`).
    pub hostfile: Option<PathBuf>,
    /// The launcher (default `mpirun`).
    pub mpirun: String,
    /// The Python that has `petsc4py` and `slepc4py` (default `/usr/bin/python3`, Debian's).
    pub python: String,
    /// More PETSc/SLEPc options for the driver (`-eps_ncv 64`, ...).
    pub petsc_options: Vec<String>,
    /// Eigenpairs computed beyond those asked for, to find the gap above them (default 4).
    pub extra: usize,
    /// Where to write the matrices and results, kept afterwards (default: the environment's
    /// `FEMU_SLEPC_WORKDIR`, else a new folder in the system's temporary folder, removed
    /// afterwards).
    pub workdir: Option<PathBuf>,
}

impl Default for SlepcOptions {
    fn default() -> Self {
        Self {
            ranks: 1,
            hostfile: None,
            mpirun: "mpirun".into(),
            python: "/usr/bin/python3".into(),
            petsc_options: Vec::new(),
            extra: 4,
            // FEMU_SLEPC_WORKDIR keeps the matrices, the driver and its answer for inspection
            workdir: std::env::var_os("FEMU_SLEPC_WORKDIR").map(PathBuf::from),
        }
    }
}

/// Which eigensolver runs an eigen solve.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum Engine {
    /// femu's own shift-invert block Lanczos ([`crate::eigen::Pencil`]).
    #[default]
    Femu,
    /// SLEPc with MUMPS under MPI.
    Slepc(SlepcOptions),
}

/// The driver's raw answer: the eigenpairs SLEPc converged and the counts by inertia.
#[derive(Debug, Clone)]
pub struct SlepcRun {
    /// Eigenvalues found, ascending (s^-2).
    pub values: Vec<f64>,
    /// Their eigenvectors (columns).
    pub vectors: Mat<f64>,
    /// The counted interval `(lower, upper]` (`lower` `None`: from minus infinity).
    pub lower: Option<f64>,
    /// Upper end.
    pub upper: f64,
    /// Eigenvalues below `lower` and below `upper` by inertia (negative pivots of MUMPS).
    pub below: (Option<usize>, usize),
    /// Outer iterations of Krylov-Schur.
    pub iterations: usize,
    /// Vectors solved with `K - sigma M` (PETSc's count of its `KSPSolve`s in the solve).
    pub solved_vectors: usize,
    /// Entries of MUMPS's factor of `K - sigma M` (its `INFOG(29)`); `None` for a band, which
    /// SLEPc factors by slices in its own sub-solvers.
    pub factor_entries: Option<usize>,
    /// Seconds: reading the matrices, the solve, the counts (the driver's clocks).
    pub seconds: [f64; 3],
    /// Versions, `petsc x.y.z / slepc x.y.z`.
    pub versions: String,
    /// The shift of shift-and-invert (s^-2; 0 for a band, which SLEPc slices itself).
    pub sigma: f64,
}

fn unavailable(reason: String) -> SparseError {
    SparseError::EngineUnavailable {
        engine: "SLEPc",
        reason: format!("{reason}; {INSTALL_HINT}"),
    }
}

fn failed(reason: String) -> SparseError {
    SparseError::EngineFailed {
        engine: "SLEPc",
        reason,
    }
}

/// PETSc's installation folders (Debian's layout) when the environment does not name them.
fn petsc_env(cmd: &mut Command) {
    let newest = |root: &str, prefix: &str| -> Option<PathBuf> {
        let mut dirs: Vec<PathBuf> = std::fs::read_dir(root)
            .ok()?
            .flatten()
            .map(|e| e.path())
            .filter(|p| {
                p.file_name()
                    .and_then(|n| n.to_str())
                    .is_some_and(|n| n.starts_with(prefix))
            })
            .collect();
        dirs.sort();
        let version = dirs.pop()?;
        std::fs::read_dir(&version)
            .ok()?
            .flatten()
            .map(|e| e.path())
            .find(|p| p.to_string_lossy().ends_with("-real"))
    };
    for (var, root, prefix) in [
        ("PETSC_DIR", "/usr/lib/petscdir", "petsc"),
        ("SLEPC_DIR", "/usr/lib/slepcdir", "slepc"),
    ] {
        if std::env::var_os(var).is_none()
            && let Some(dir) = newest(root, prefix)
        {
            cmd.env(var, dir);
        }
    }
    // Open MPI refuses root without these (containers, CI runners); one thread per rank
    cmd.env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .env("OMP_NUM_THREADS", "1")
        .env("OPENBLAS_NUM_THREADS", "1");
}

/// The size in bytes of PETSc's integers, asking the installed `petsc4py` (the engine is missing
/// if that fails).
///
/// # Errors
/// [`SparseError::EngineUnavailable`] naming what is missing and what to install.
pub fn probe(opts: &SlepcOptions) -> Result<usize, SparseError> {
    let mut cmd = Command::new(&opts.python);
    cmd.args([
        "-c",
        "from petsc4py import PETSc; from slepc4py import SLEPc; import numpy; print(PETSc.IntType(0).itemsize, PETSc.ScalarType(0).itemsize)",
    ]);
    petsc_env(&mut cmd);
    let out = cmd
        .output()
        .map_err(|e| unavailable(format!("cannot run {}: {e}", opts.python)))?;
    if !out.status.success() {
        let err = String::from_utf8_lossy(&out.stderr);
        let last = err.lines().last().unwrap_or("").to_string();
        return Err(unavailable(format!(
            "{} cannot import petsc4py and slepc4py ({last})",
            opts.python
        )));
    }
    let text = String::from_utf8_lossy(&out.stdout);
    let v: Vec<usize> = text
        .split_whitespace()
        .filter_map(|t| t.parse().ok())
        .collect();
    match v.as_slice() {
        [int @ (4 | 8), 8] => Ok(*int),
        _ => Err(unavailable(format!(
            "the installed PETSc is not a real double-precision build (integer and scalar sizes: {text})"
        ))),
    }
    .and_then(|int| {
        let which = Command::new(&opts.mpirun).arg("--version").output();
        match which {
            Ok(o) if o.status.success() => Ok(int),
            _ => Err(unavailable(format!("cannot run {}", opts.mpirun))),
        }
    })
}

/// Writes `a` (square, symmetric, CSC with both triangles: its columns are its rows) in PETSc's
/// binary AIJ format with `index_bytes`-byte integers.
///
/// # Errors
/// The file system's, and a matrix too large for 32-bit indices.
pub fn write_petsc_matrix(
    a: &SparseMatrix,
    path: &Path,
    index_bytes: usize,
) -> Result<(), SparseError> {
    const MAT_FILE_CLASSID: i64 = 1_211_216;
    let n = a.rows();
    let nnz = a.nnz();
    if index_bytes == 4 && nnz > i32::MAX as usize {
        return Err(failed(format!(
            "{nnz} stored entries exceed PETSc's 32-bit indices: a PETSc built with 64-bit indices is needed"
        )));
    }
    let io = |e: std::io::Error| failed(format!("cannot write {}: {e}", path.display()));
    let f = std::fs::File::create(path).map_err(io)?;
    let mut w = std::io::BufWriter::with_capacity(1 << 20, f);
    let int = |w: &mut std::io::BufWriter<std::fs::File>, v: i64| -> std::io::Result<()> {
        if index_bytes == 8 {
            w.write_all(&v.to_be_bytes())
        } else {
            w.write_all(&(v as i32).to_be_bytes())
        }
    };
    // the header's four integers are PetscInt-sized too
    for v in [MAT_FILE_CLASSID, n as i64, n as i64, nnz as i64] {
        int(&mut w, v).map_err(io)?;
    }
    let p = a.indptr();
    let p = p.raw_storage();
    for c in 0..n {
        int(&mut w, (p[c + 1] - p[c]) as i64).map_err(io)?;
    }
    for &r in a.indices() {
        int(&mut w, r as i64).map_err(io)?;
    }
    for &v in a.data() {
        w.write_all(&v.to_be_bytes()).map_err(io)?;
    }
    w.flush().map_err(io)
}

/// Runs the driver on `(K, M)` for `which` and returns its raw answer (not yet checked).
///
/// # Errors
/// The engine missing, the files, MPI or SLEPc failing (their message), non-convergence.
pub fn run(
    k: &SparseMatrix,
    m: &SparseMatrix,
    which: Which,
    params: &EigenOptions,
    opts: &SlepcOptions,
) -> Result<SlepcRun, SparseError> {
    let n = k.rows();
    if m.rows() != n || k.cols() != n || m.cols() != n {
        return Err(SparseError::DimensionMismatch {
            what: "M against K (square, same size)",
            expected: n,
            got: m.rows(),
        });
    }
    if opts.ranks == 0 {
        return Err(SparseError::InvalidRequest {
            reason: "SLEPc needs at least one MPI rank".into(),
        });
    }
    let index_bytes = probe(opts)?;
    let (dir, temporary) = match &opts.workdir {
        Some(d) => (d.clone(), false),
        None => {
            let stamp = std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_nanos());
            (
                std::env::temp_dir().join(format!("femu-slepc-{}-{stamp}", std::process::id())),
                true,
            )
        }
    };
    std::fs::create_dir_all(&dir)
        .map_err(|e| failed(format!("cannot create {}: {e}", dir.display())))?;
    let result = run_in(k, m, which, params, opts, &dir, index_bytes);
    if temporary {
        let _ = std::fs::remove_dir_all(&dir);
    }
    result
}

fn run_in(
    k: &SparseMatrix,
    m: &SparseMatrix,
    which: Which,
    params: &EigenOptions,
    opts: &SlepcOptions,
    dir: &Path,
    index_bytes: usize,
) -> Result<SlepcRun, SparseError> {
    let n = k.rows();
    write_petsc_matrix(k, &dir.join("K.petsc"), index_bytes)?;
    write_petsc_matrix(m, &dir.join("M.petsc"), index_bytes)?;
    let (k_norm, m_norm) = (one_norm(k), one_norm(m));
    // the lowest modes: a shift just below zero (K - sigma M is then positive definite, and
    // rigid-body zeros stay apart from it)
    let below_zero = -1e-8 * k_norm / m_norm.max(f64::MIN_POSITIVE);
    let request = match which {
        Which::Lowest(count) => serde_json::json!({
            "kind": "lowest", "count": count, "sigma": below_zero,
            "extra": opts.extra.min(n.saturating_sub(count)),
        }),
        Which::Nearest { shift, count } => serde_json::json!({
            "kind": "nearest", "count": count, "sigma": shift,
            "extra": opts.extra.min(n.saturating_sub(count)),
        }),
        Which::Band { lo, hi } => serde_json::json!({"kind": "band", "lo": lo, "hi": hi}),
    };
    let mut request = request;
    request["tol"] = serde_json::json!(params.tol.max(1e-14));
    request["max_it"] = serde_json::json!(params.max_restarts.max(1) * 20);
    std::fs::write(dir.join("request.json"), request.to_string())
        .map_err(|e| failed(format!("cannot write the request: {e}")))?;
    let driver = dir.join("femu_slepc.py");
    std::fs::write(&driver, DRIVER).map_err(|e| failed(format!("cannot write the driver: {e}")))?;
    let mut cmd = Command::new(&opts.mpirun);
    cmd.arg("-n").arg(opts.ranks.to_string());
    if let Some(h) = &opts.hostfile {
        cmd.arg("--hostfile").arg(h);
    } else {
        // one machine: as many ranks as asked, whatever the core count
        cmd.arg("--oversubscribe");
    }
    cmd.arg(&opts.python).arg(&driver).arg(dir);
    cmd.args(&opts.petsc_options);
    petsc_env(&mut cmd);
    let out = cmd
        .output()
        .map_err(|e| unavailable(format!("cannot run {}: {e}", opts.mpirun)))?;
    let error_file = dir.join("error.json");
    if error_file.exists() {
        let v: serde_json::Value = std::fs::read_to_string(&error_file)
            .ok()
            .and_then(|t| serde_json::from_str(&t).ok())
            .unwrap_or_default();
        return Err(failed(
            v["error"]
                .as_str()
                .unwrap_or("the driver failed")
                .to_string(),
        ));
    }
    if !out.status.success() {
        let err = String::from_utf8_lossy(&out.stderr);
        let tail: Vec<&str> = err.lines().rev().take(6).collect();
        return Err(failed(format!(
            "{} -n {} exited with {}: {}",
            opts.mpirun,
            opts.ranks,
            out.status,
            tail.into_iter().rev().collect::<Vec<_>>().join(" | ")
        )));
    }
    let text = std::fs::read_to_string(dir.join("result.json"))
        .map_err(|e| failed(format!("the driver wrote no result: {e}")))?;
    let r: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| failed(format!("unreadable result: {e}")))?;
    let values: Vec<f64> = r["values"]
        .as_array()
        .map(|a| a.iter().filter_map(serde_json::Value::as_f64).collect())
        .unwrap_or_default();
    let bytes = std::fs::read(dir.join("vectors.bin"))
        .map_err(|e| failed(format!("the driver wrote no vectors: {e}")))?;
    if bytes.len() != 8 * n * values.len() {
        return Err(failed(format!(
            "{} bytes of vectors for {} eigenpairs of size {n}",
            bytes.len(),
            values.len()
        )));
    }
    let vectors = Mat::from_fn(n, values.len(), |i, j| {
        let at = 8 * (j * n + i);
        f64::from_le_bytes(bytes[at..at + 8].try_into().expect("8 bytes"))
    });
    let end = |i: usize| r["ends"][i].as_f64();
    let count = |i: usize| -> Option<usize> { r["counts"][i][0].as_u64().map(|c| c as usize) };
    let upper = end(1).ok_or_else(|| failed("the result has no interval".into()))?;
    Ok(SlepcRun {
        values,
        vectors,
        lower: end(0),
        upper,
        below: (
            count(0),
            count(1).ok_or_else(|| failed("the result has no count".into()))?,
        ),
        iterations: r["iterations"].as_u64().unwrap_or(0) as usize,
        solved_vectors: r["solved"].as_u64().unwrap_or(0) as usize,
        factor_entries: r["factor_entries"].as_u64().map(|e| e as usize),
        seconds: [
            r["seconds"]["load"].as_f64().unwrap_or(0.0),
            r["seconds"]["solve"].as_f64().unwrap_or(0.0),
            r["seconds"]["count"].as_f64().unwrap_or(0.0),
        ],
        versions: format!(
            "petsc {} / slepc {}",
            r["petsc"].as_str().unwrap_or("?"),
            r["slepc"].as_str().unwrap_or("?")
        ),
        sigma: request["sigma"].as_f64().unwrap_or(0.0),
    })
}

impl SlepcRun {
    /// The checked [`Modes`]: the pairs in the counted interval, `M`-normalised, with femu's
    /// residuals and the count by inertia as the [`SturmCheck`].
    ///
    /// # Errors
    /// [`SparseError::SturmMismatch`] when the count by inertia differs from the pairs returned
    /// in the interval (a skipped mode), [`SparseError::NoConvergence`] when a returned pair's
    /// residual is far above the tolerance.
    pub fn into_modes(
        self,
        k: &SparseMatrix,
        m: &SparseMatrix,
        which: Which,
        params: &EigenOptions,
    ) -> Result<Modes, SparseError> {
        let n = k.rows();
        let inside = |v: f64| self.lower.is_none_or(|l| v > l) && v <= self.upper;
        let sel: Vec<usize> = (0..self.values.len())
            .filter(|&j| inside(self.values[j]))
            .collect();
        let count = self.below.1 - self.below.0.unwrap_or(0);
        let sturm = SturmCheck {
            lower: self.lower,
            upper: self.upper,
            count,
            returned: sel.len(),
        };
        if !sturm.verified() {
            return Err(SparseError::SturmMismatch {
                interval: sturm.interval(),
                count,
                returned: sel.len(),
            });
        }
        let norms = (one_norm(k), one_norm(m));
        let mut vectors = Mat::zeros(n, sel.len());
        let mut residuals = Vec::with_capacity(sel.len());
        let mut kinds = Vec::with_capacity(sel.len());
        for (c, &j) in sel.iter().enumerate() {
            let x: Vec<f64> = (0..n).map(|i| self.vectors[(i, j)]).collect();
            let mut mx = vec![0.0; n];
            crate::csc::mul_vec(m, &x, &mut mx)?;
            let s = x.iter().zip(&mx).map(|(a, b)| a * b).sum::<f64>();
            if !(s > 0.0 && s.is_finite()) {
                return Err(failed(format!(
                    "eigenvector {c} has x^T M x = {s}: not an eigenvector of a definite pencil"
                )));
            }
            let scale = 1.0 / s.sqrt();
            let x: Vec<f64> = x.iter().map(|v| v * scale).collect();
            let mx: Vec<f64> = mx.iter().map(|v| v * scale).collect();
            let (r, kind) = residual_of(k, norms, &x, &mx, self.values[j]);
            if r > 1e4 * params.tol.max(1e-12) {
                return Err(SparseError::NoConvergence {
                    reason: format!(
                        "SLEPc's eigenpair {c} (lambda = {:e} s^-2) has residual {r:.1e}, above the tolerance {:.0e}",
                        self.values[j], params.tol
                    ),
                });
            }
            for i in 0..n {
                vectors[(i, c)] = x[i];
            }
            residuals.push(r);
            kinds.push(kind);
        }
        let requested = match which {
            Which::Lowest(c) => c,
            Which::Nearest { count, .. } => count,
            Which::Band { .. } => count,
        };
        Ok(Modes {
            values: sel.iter().map(|&j| self.values[j]).collect(),
            vectors,
            shifted_residuals: residuals.clone(),
            residuals,
            residual_kinds: kinds,
            requested,
            shift: self.sigma,
            sturm,
            stats: EigenStats {
                symbolic_seconds: self.seconds[0],
                solve_seconds: self.seconds[1],
                factor_seconds: self.seconds[2],
                factorizations: 1 + usize::from(self.lower.is_some()) + 1,
                restarts: self.iterations,
                solved_vectors: self.solved_vectors,
                factor_len: self.factor_entries.unwrap_or(0),
                total_seconds: self.seconds.iter().sum(),
                ..Default::default()
            },
            factor: None,
        })
    }
}

/// SLEPc's solve of `(K, M)`, checked: [`run`] then [`SlepcRun::into_modes`].
///
/// # Errors
/// As both.
pub fn solve(
    k: &SparseMatrix,
    m: &SparseMatrix,
    which: Which,
    params: &EigenOptions,
    opts: &SlepcOptions,
) -> Result<Modes, SparseError> {
    run(k, m, which, params, opts)?.into_modes(k, m, which, params)
}
