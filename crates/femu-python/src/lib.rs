//! # femu-python
//!
//! The native module `femu._femu` behind the Python package `femu` (PyO3, one abi3 wheel for
//! CPython 3.9 and later, built by maturin: `pip install ./crates/femu-python`). It exposes femu's
//! workflows in Python's idiom: models read from every format femu reads, `K` and `M` as
//! `scipy.sparse.csc_matrix`, Sturm-verified modes, test modes from files or numpy arrays, MAC
//! matrices, expansion and the a priori estimators (docs/MATH.md; the paper's (3)-(12) and
//! Theorems 1-4). Results convert to dictionaries (`to_dict()`, the JSON the command line writes).
//! Long calls release the GIL. femu's errors become `femu.FemuError` with the same message, file,
//! line, node and element.

use faer::Mat;
use femu_correlate::TestModes;
use femu_correlate::expansion::Method;
use femu_io::TestData;
use femu_study::load::{
    LoadedModel, LoadedTest, MaterialOptions, ModelOptions, TestOptions, load_model, load_test_with,
};
use femu_study::modes::{ModesOptions, ModesReport, solve_modes};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

create_exception!(
    _femu,
    FemuError,
    PyException,
    "An error of femu: a malformed file (its name and line), an invalid model (the node or \
     element), a numerical failure (what and where). The message is femu's own."
);

fn err(e: impl std::fmt::Display) -> PyErr {
    FemuError::new_err(e.to_string())
}

/// A serialisable result as a Python dict, through the JSON the command line writes.
fn to_dict<'py>(py: Python<'py>, value: &impl serde::Serialize) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(value).map_err(err)?;
    py.import("json")?.call_method1("loads", (text,))
}

/// The payload that stops a long call at an iteration boundary (never shown: it is raised with
/// `resume_unwind`, which skips the panic hook, and caught by [`interruptible`]).
struct Interrupted;

/// What a checkpoint passes to the Python callback: built only when there is one, with the GIL.
type Arg<'a> = &'a dyn Fn(Python<'_>) -> PyResult<Py<PyAny>>;

/// Runs `work` with the GIL released, handing it a checkpoint to call at iteration boundaries:
/// the checkpoint takes the GIL back, checks for Ctrl-C (`KeyboardInterrupt`), calls `callback`
/// with the iteration's value, and stops `work` when either raises; that exception is then raised
/// to Python. Nothing of the stopped work is returned.
fn interruptible<T: Send>(
    py: Python<'_>,
    callback: Option<Py<PyAny>>,
    work: impl FnOnce(&mut dyn FnMut(Arg<'_>)) -> T + Send,
) -> PyResult<T> {
    let failed: std::sync::Mutex<Option<PyErr>> = std::sync::Mutex::new(None);
    let out = py.detach(|| {
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            let mut checkpoint = |arg: Arg<'_>| {
                let stop = Python::attach(|py| -> Option<PyErr> {
                    if let Err(e) = py.check_signals() {
                        return Some(e);
                    }
                    let cb = callback.as_ref()?;
                    arg(py).and_then(|a| cb.call1(py, (a,))).err()
                });
                if let Some(e) = stop {
                    if let Ok(mut f) = failed.lock() {
                        *f = Some(e);
                    }
                    std::panic::resume_unwind(Box::new(Interrupted));
                }
            };
            work(&mut checkpoint)
        }))
    });
    match out {
        Ok(v) => Ok(v),
        Err(payload) if payload.is::<Interrupted>() => Err(failed
            .into_inner()
            .ok()
            .flatten()
            .unwrap_or_else(|| FemuError::new_err("interrupted"))),
        Err(payload) => std::panic::resume_unwind(payload),
    }
}

/// A column-major faer matrix as a 2-D numpy array (rows x columns).
fn mat_to_py<'py>(py: Python<'py>, m: &Mat<f64>) -> Bound<'py, PyArray2<f64>> {
    let a = Array2::from_shape_fn((m.nrows(), m.ncols()), |(i, j)| m[(i, j)]);
    a.into_pyarray(py)
}

fn py_to_mat(a: &PyReadonlyArray2<'_, f64>) -> Mat<f64> {
    let v = a.as_array();
    Mat::from_fn(v.nrows(), v.ncols(), |i, j| v[(i, j)])
}

fn method(name: &str) -> PyResult<Method> {
    name.parse::<Method>().map_err(|e| {
        pyo3::exceptions::PyValueError::new_err(format!(
            "expansion {name:?}: {e} (static, dynamic, serep, min-residual, mdre-we)"
        ))
    })
}

/// A finite element model read from a file, checked and assembled once (`femu.read_model`).
#[pyclass(module = "femu", name = "Model", frozen)]
struct Model {
    loaded: LoadedModel,
    warnings: Vec<String>,
}

/// Reads a model: an Abaqus/CalculiX deck (`.inp`), Nastran bulk data (`.bdf`, `.dat`, `.nas`),
/// a Gmsh mesh (`.msh`) or universal file solids (`.unv`, `.uff`). A mesh-only file needs the
/// material (`young` Pa, `poisson`, `density` kg/m^3, and `structural_damping`, its `GE` for
/// `femu.frf`) and may clamp node sets (`fix`); a Gmsh
/// mesh's physical groups of surfaces become shells with `shells={"group": thickness}`, its groups
/// of lines beams with `beams={"group": "rect:A,B"}` (`circ:R`, `pipe:R,T`, `@X,Y,Z` for `n1`);
/// its 8-node
/// bricks are fully integrated unless `bricks="incompatible_modes"` (a deck states its own).
/// Another solver's matrices (CalculiX `job.sti`, Abaqus `job_STIF1.mtx` with `job_MASS1.mtx`,
/// Nastran DMIG `job.pch` or OUTPUT4 `job.op4`, MatrixMarket `X_K.mtx` with `X_M.mtx` and `X_dofs.csv`) are a model
/// too, with their nodes' coordinates from `nodes` (a deck or a
/// `node,x,y,z` table; by default `job.inp` or `X_nodes.csv` beside them).
#[pyfunction]
#[pyo3(signature = (path, *, lumped=false, lenient=false, young=None, poisson=None, density=None, fix=None, bricks="full", nodes=None, shells=None, beams=None, structural_damping=None))]
#[allow(clippy::too_many_arguments)]
fn read_model(
    py: Python<'_>,
    path: PathBuf,
    lumped: bool,
    lenient: bool,
    young: Option<f64>,
    poisson: Option<f64>,
    density: Option<f64>,
    fix: Option<Vec<String>>,
    bricks: &str,
    nodes: Option<PathBuf>,
    shells: Option<std::collections::BTreeMap<String, f64>>,
    beams: Option<std::collections::BTreeMap<String, String>>,
    structural_damping: Option<f64>,
) -> PyResult<Model> {
    let bricks = match bricks {
        "full" => femu_fem::element::Formulation::Full,
        "incompatible_modes" => femu_fem::element::Formulation::IncompatibleModes,
        other => {
            return Err(pyo3::exceptions::PyValueError::new_err(format!(
                "bricks={other:?}: give \"full\" or \"incompatible_modes\""
            )));
        }
    };
    let material = match (young, poisson, density) {
        (Some(young), Some(poisson), Some(density)) => Some(MaterialOptions {
            young,
            poisson,
            density,
            structural_damping: structural_damping.unwrap_or(0.0),
        }),
        (None, None, None) => None,
        _ => {
            return Err(pyo3::exceptions::PyValueError::new_err(
                "give young, poisson and density together",
            ));
        }
    };
    let options = ModelOptions {
        material,
        fix: fix.unwrap_or_default(),
        shells: shells.map(|m| m.into_iter().collect()).unwrap_or_default(),
        beams: beams.map(|m| m.into_iter().collect()).unwrap_or_default(),
        lumped,
        lenient,
        bricks,
        nodes,
    };
    let loaded = py.detach(|| load_model(&path, &options)).map_err(err)?;
    let warnings = loaded.warnings.clone();
    Ok(Model { loaded, warnings })
}

fn csc<'py>(py: Python<'py>, a: &femu_sparse::SparseMatrix) -> PyResult<Bound<'py, PyAny>> {
    let data = a.data().to_vec().into_pyarray(py);
    let indices: Vec<i64> = a.indices().iter().map(|v| *v as i64).collect();
    let indptr: Vec<i64> = a.indptr().raw_storage().iter().map(|v| *v as i64).collect();
    let shape = (a.rows(), a.cols());
    let kind = if a.is_csc() {
        "csc_matrix"
    } else {
        "csr_matrix"
    };
    py.import("scipy.sparse")?.getattr(kind)?.call1((
        (data, indices.into_pyarray(py), indptr.into_pyarray(py)),
        shape,
    ))
}

#[pymethods]
impl Model {
    /// The file the model was read from.
    #[getter]
    fn path(&self) -> String {
        self.loaded.path.display().to_string()
    }

    /// Number of free DOFs: the size of `K` and `M`.
    #[getter]
    fn free_count(&self) -> usize {
        self.loaded.sys.dofs.free_count()
    }

    /// The stiffness `K` (N/m) on the free DOFs, a `scipy.sparse.csc_matrix` (both triangles).
    #[getter(K)]
    fn stiffness<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        csc(py, &self.loaded.sys.k)
    }

    /// The mass `M` (kg) on the free DOFs, a `scipy.sparse.csc_matrix`.
    #[getter(M)]
    fn mass<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        csc(py, &self.loaded.sys.m)
    }

    /// The DOF map: one row per free DOF, `(node id, component)`, component 0-2 for x, y, z and
    /// 3-5 for the rotations of a rigid link's reference node.
    #[getter]
    fn dofs<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<i64>> {
        let d = &self.loaded.sys.dofs;
        let mesh = self.loaded.model.mesh();
        let a = Array2::from_shape_fn((d.free_count(), 2), |(f, k)| {
            let (p, c) = d.free_dof(f);
            let (n, rot) = d.point_node(p);
            if k == 0 {
                mesh.node_id(n) as i64
            } else {
                (c + if rot { 3 } else { 0 }) as i64
            }
        });
        a.into_pyarray(py)
    }

    /// Node ids, in the order of `coords`.
    #[getter]
    fn node_ids<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u64>> {
        let mesh = self.loaded.model.mesh();
        (0..mesh.node_count())
            .map(|i| mesh.node_id(i))
            .collect::<Vec<u64>>()
            .into_pyarray(py)
    }

    /// Node coordinates (m), one row per node.
    #[getter]
    fn coords<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let x = self.loaded.model.mesh().coords();
        Array2::from_shape_fn((x.len(), 3), |(i, k)| x[i][k]).into_pyarray(py)
    }

    /// Whether the mass matrix is lumped.
    #[getter]
    fn lumped(&self) -> bool {
        self.loaded.sys.mass_kind == femu_fem::assembly::MassKind::Lumped
    }

    /// Total mass (kg): the elements' `rho V` plus point and rigid masses. Not known for a model
    /// read as another solver's matrices (its `M` leaves out the mass at fixed DOFs): an error.
    #[getter]
    fn total_mass(&self) -> PyResult<f64> {
        if let Some(origin) = &self.loaded.matrices {
            return Err(FemuError::new_err(format!(
                "{}: the model is {}: its total mass is not known (M holds the free DOFs' mass only)",
                self.loaded.path.display(),
                origin.source.name()
            )));
        }
        self.loaded.model.total_mass().map_err(err)
    }

    /// What the reader noticed and did not refuse.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }

    /// The lowest `count` modes, those nearest `shift_hz`, or all in `band_hz = (lo, hi)`, by
    /// femu's shift-invert Lanczos, with the Sturm count that proves none was skipped
    /// (docs/MATH.md, "The eigensolver's evidence"). `progress` is called with the number of
    /// vectors solved so far after every block. `block_size` vectors are solved together (the
    /// default 4; docs/SCALING.md, "Block size and the count of solved vectors"), and
    /// `to_dict()["eigensolver"]` says where the time went. With `damped=True`,
    /// `to_dict()["damped"]` lists the complex modes of the model's damping, structural and
    /// viscous (each one's root `eigenvalue` `[re, im]` = `p`, `frequency_hz` `Im p / 2 pi`,
    /// Nastran's `damping` `-2 Re p / Im p`, `damping_ratio`, `mpc`, `mpd_degrees`; docs/MATH.md,
    /// "Damped modes"). Releases the GIL; Ctrl-C, or an exception raised by `progress`, stops the
    /// solve at the next block.
    #[pyo3(signature = (count=None, *, shift_hz=None, band_hz=None, block_size=None, progress=None, damped=false))]
    #[allow(clippy::too_many_arguments)]
    fn modes(
        &self,
        py: Python<'_>,
        count: Option<usize>,
        shift_hz: Option<f64>,
        band_hz: Option<(f64, f64)>,
        block_size: Option<usize>,
        progress: Option<Py<PyAny>>,
        damped: bool,
    ) -> PyResult<Modes> {
        let defaults = femu_sparse::eigen::EigenOptions::default();
        let options = ModesOptions {
            count,
            shift_hz,
            band_hz,
            eigen: femu_sparse::eigen::EigenOptions {
                block_size: block_size.unwrap_or(defaults.block_size),
                ..defaults
            },
            damped,
        };
        let stop: std::sync::Arc<std::sync::Mutex<Option<PyErr>>> = Default::default();
        let seen = stop.clone();
        let result = py.detach(|| {
            femu_sparse::eigen::with_interrupt(
                move |solved| {
                    Python::attach(|py| {
                        let e = py.check_signals().err().or_else(|| {
                            progress
                                .as_ref()
                                .and_then(|cb| cb.call1(py, (solved,)).err())
                        });
                        let halt = e.is_some();
                        if let (Some(e), Ok(mut slot)) = (e, seen.lock()) {
                            *slot = Some(e);
                        }
                        halt
                    })
                },
                || solve_modes(&self.loaded, &options),
            )
        });
        let pending = stop.lock().ok().and_then(|mut s| s.take());
        match (result, pending) {
            (Ok((modes, report)), _) => Ok(Modes { modes, report }),
            (Err(_), Some(e)) => Err(e),
            (Err(e), None) => Err(err(e)),
        }
    }

    /// Writes `modes` (of this model) as a universal file at `path`: every node (dataset 2411)
    /// and each mode's translations (dataset 55); with `damped=True` the damped modes, as complex
    /// data whose eigenvalue is each root (`femu modes --uff`; docs/MATH.md, "Damped modes").
    #[pyo3(signature = (modes, path, *, damped=false))]
    fn write_modes_uff(&self, modes: &Modes, path: PathBuf, damped: bool) -> PyResult<()> {
        let uff =
            femu_study::modes::modes_universal(&self.loaded, &modes.modes, damped).map_err(err)?;
        femu_io::uff::write_uff(&path, &uff).map_err(err)
    }

    fn __repr__(&self) -> String {
        let mesh = self.loaded.model.mesh();
        format!(
            "Model({:?}, {} free DOFs, {} nodes, {} elements, {} mass)",
            self.path(),
            self.free_count(),
            mesh.node_count(),
            mesh.element_count(),
            if self.lumped() {
                "lumped"
            } else {
                "consistent"
            }
        )
    }
}

/// Modes of a model: eigenvalues, M-normalised shapes, residuals and the Sturm proof.
#[pyclass(module = "femu", name = "Modes", frozen)]
struct Modes {
    modes: femu_sparse::eigen::Modes,
    report: ModesReport,
}

#[pymethods]
impl Modes {
    /// Eigenvalues `lambda = omega^2` (s^-2), ascending.
    #[getter]
    fn values<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.modes.values.clone().into_pyarray(py)
    }

    /// Natural frequencies (Hz).
    #[getter]
    fn frequencies_hz<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.modes.frequencies_hz().into_pyarray(py)
    }

    /// Shapes on the free DOFs, one M-normalised column per mode (`phi^T M phi = I`).
    #[getter]
    fn vectors<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        mat_to_py(py, &self.modes.vectors)
    }

    /// The residual of each mode: relative `||K x - lambda M x|| / ||K x||`, or the backward
    /// error for a rigid-body mode (see `residual_kinds`).
    #[getter]
    fn residuals<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.modes.residuals.clone().into_pyarray(py)
    }

    /// `"relative"` or `"backward"` per mode.
    #[getter]
    fn residual_kinds(&self) -> Vec<&'static str> {
        self.modes.residual_kinds.iter().map(|k| k.name()).collect()
    }

    /// The Sturm check: `count` eigenvalues in `(lower, upper]` by the inertia of
    /// `K - upper M`, `returned` of them computed, `verified` when equal.
    #[getter]
    fn sturm<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = &self.modes.sturm;
        let d = PyDict::new(py);
        d.set_item("lower", s.lower)?;
        d.set_item("upper", s.upper)?;
        d.set_item("count", s.count)?;
        d.set_item("returned", s.returned)?;
        d.set_item("verified", s.verified())?;
        Ok(d)
    }

    /// The summary `femu modes --json` writes, as a dict.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_dict(py, &self.report)
    }

    fn __len__(&self) -> usize {
        self.modes.values.len()
    }

    fn __repr__(&self) -> String {
        let f = self.modes.frequencies_hz();
        format!(
            "Modes({} modes, {:.4} .. {:.4} Hz, Sturm {})",
            f.len(),
            f.first().copied().unwrap_or(0.0),
            f.last().copied().unwrap_or(0.0),
            if self.modes.sturm.verified() {
                "verified"
            } else {
                "NOT verified"
            }
        )
    }
}

/// Test modes on sensors of a model: identified frequencies and shapes (`femu.read_test`,
/// `femu.Test.from_arrays`).
#[pyclass(module = "femu", name = "Test", frozen)]
struct Test {
    loaded: LoadedTest,
}

/// Another solver's modes with its nodes (`femu.read_results`): CalculiX's `.frd`. They are the
/// model side of `femu.correlate` (with no Sturm proof that none was skipped, and no `K` or `M`
/// for the estimators, expansion or updating).
#[pyclass(module = "femu", name = "Results", frozen)]
struct Results {
    results: femu_study::external::ResultModes,
}

#[pymethods]
impl Results {
    /// The file's warnings (result blocks skipped).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.results.warnings.clone()
    }

    /// The modes' frequencies, Hz.
    #[getter]
    fn frequencies_hz(&self) -> Vec<f64> {
        self.results.modes.frequencies_hz()
    }

    /// The node ids, in the order of the shapes' rows (three per node: x, y, z).
    #[getter]
    fn node_ids(&self) -> Vec<u64> {
        let mesh = self.results.model.mesh();
        (0..mesh.node_count()).map(|i| mesh.node_id(i)).collect()
    }

    /// The mode shapes, one column per mode, rows x, y, z of each node in turn.
    #[getter]
    fn shapes<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        mat_to_py(py, &self.results.modes.shapes)
    }

    fn __len__(&self) -> usize {
        self.results.modes.len()
    }
}

/// Reads another solver's modes: a CalculiX `.frd` (the displacements of its `*FREQUENCY` step,
/// asked for with `*NODE FILE` and `U`), with its nodes; or a Nastran `.f06` (its real
/// eigenvectors) with the grids of the run's deck (`nodes`, or the `.bdf`, `.dat` or `.nas` of the
/// same name beside it).
#[pyfunction]
#[pyo3(signature = (path, *, nodes=None))]
fn read_results(py: Python<'_>, path: PathBuf, nodes: Option<PathBuf>) -> PyResult<Results> {
    let results = py
        .detach(|| femu_study::external::load_result_modes(&path, nodes.as_deref()))
        .map_err(err)?;
    Ok(Results { results })
}

/// The model side of a test and a correlation: a model (its modes solved) or another solver's
/// modes.
#[derive(FromPyObject)]
enum ModelSide<'py> {
    Model(PyRef<'py, Model>),
    Results(PyRef<'py, Results>),
}

/// Reads test modes (`.unv`/`.uff`: datasets 15/2411 and 55 or 2414; `.json`; `.csv`) and puts
/// their sensors on `model` (a model or another solver's results; test node ids are its node
/// ids). `test_units` gives metres per unit where the file says nothing (0.001 for millimetres).
#[pyfunction]
#[pyo3(signature = (path, model, *, test_units=None))]
fn read_test(
    py: Python<'_>,
    path: PathBuf,
    model: ModelSide<'_>,
    test_units: Option<f64>,
) -> PyResult<Test> {
    let options = TestOptions {
        map: None,
        test_units,
    };
    let loaded = match &model {
        ModelSide::Model(m) => {
            let loaded = &m.loaded;
            py.detach(|| load_test_with(&path, loaded, &options))
        }
        ModelSide::Results(r) => {
            let r = &r.results;
            py.detach(|| femu_study::load::load_test_on(&path, r.model.mesh(), &r.dofs, &options))
        }
    }
    .map_err(err)?;
    Ok(Test { loaded })
}

#[pymethods]
impl Test {
    /// Test modes from numpy: sensor `i` reads node `nodes[i]` along `directions[i]` (any
    /// direction, normalised), `shapes[i, j]` is mode `j` at sensor `i`; for complex identified
    /// modes `shapes_imaginary` their imaginary parts (the real parts in `shapes`, the modes
    /// `shapes + i shapes_imaginary`), which give each pair its complex MAC in correlation.
    #[staticmethod]
    #[pyo3(signature = (model, nodes, directions, frequencies_hz, shapes, *, damping=None, shapes_imaginary=None))]
    fn from_arrays(
        model: &Model,
        nodes: Vec<u64>,
        directions: PyReadonlyArray2<'_, f64>,
        frequencies_hz: Vec<f64>,
        shapes: PyReadonlyArray2<'_, f64>,
        damping: Option<Vec<f64>>,
        shapes_imaginary: Option<PyReadonlyArray2<'_, f64>>,
    ) -> PyResult<Test> {
        let d = directions.as_array();
        if d.ncols() != 3 || d.nrows() != nodes.len() {
            return Err(pyo3::exceptions::PyValueError::new_err(format!(
                "directions must be {} x 3 (one row per node), got {:?}",
                nodes.len(),
                directions.shape()
            )));
        }
        let sensors: Vec<femu_correlate::sensors::Sensor> = nodes
            .iter()
            .enumerate()
            .map(|(i, n)| {
                femu_correlate::sensors::Sensor::new(*n, [d[(i, 0)], d[(i, 1)], d[(i, 2)]])
            })
            .collect();
        let mut modes = TestModes::new(frequencies_hz, damping, py_to_mat(&shapes)).map_err(err)?;
        if let Some(im) = &shapes_imaginary {
            modes = modes.with_imaginary(py_to_mat(im)).map_err(err)?;
        }
        let layout = femu_correlate::SensorLayout::new(
            model.loaded.model.mesh(),
            &model.loaded.sys.dofs,
            sensors.clone(),
        )
        .map_err(err)?;
        if layout.len() != modes.shapes.nrows() {
            return Err(pyo3::exceptions::PyValueError::new_err(format!(
                "shapes have {} rows for {} sensors",
                modes.shapes.nrows(),
                layout.len()
            )));
        }
        Ok(Test {
            loaded: LoadedTest {
                path: PathBuf::from("<arrays>"),
                data: TestData {
                    sensors,
                    modes,
                    coordinates: Default::default(),
                },
                layout,
                mapping: None,
                warnings: Vec::new(),
            },
        })
    }

    /// Identified frequencies (Hz).
    #[getter]
    fn frequencies_hz<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.loaded
            .data
            .modes
            .frequencies_hz
            .clone()
            .into_pyarray(py)
    }

    /// Shapes at the sensors, one column per mode.
    #[getter]
    fn shapes<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        mat_to_py(py, &self.loaded.data.modes.shapes)
    }

    /// For complex identified modes, the imaginary parts of the shapes (sensors x modes; the
    /// modes are `shapes + i shapes_imaginary`); `None` for real data.
    #[getter]
    fn shapes_imaginary<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray2<f64>>> {
        self.loaded
            .data
            .modes
            .imaginary
            .as_ref()
            .map(|m| mat_to_py(py, m))
    }

    /// Sensor `i`: its node id.
    #[getter]
    fn nodes(&self) -> Vec<u64> {
        self.loaded
            .layout
            .sensors()
            .iter()
            .map(|s| s.node)
            .collect()
    }

    /// Sensor `i`: its unit direction.
    #[getter]
    fn directions<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let s = self.loaded.layout.sensors();
        Array2::from_shape_fn((s.len(), 3), |(i, k)| s[i].direction[k]).into_pyarray(py)
    }

    /// The sensor matrix `C` (sensors x free DOFs, a `scipy.sparse.csr_matrix`): `y = C x`.
    #[getter(C)]
    fn sensor_matrix<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let c = self.loaded.layout.matrix();
        csc(py, &c)
    }

    fn __len__(&self) -> usize {
        self.loaded.data.modes.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "Test({:?}, {} modes, {} sensors)",
            self.loaded.path.display().to_string(),
            self.loaded.data.modes.len(),
            self.loaded.layout.len()
        )
    }
}

/// The MAC matrix `MAC_ij = (a_i . b_j)^2 / ((a_i . a_i)(b_j . b_j))` of the columns of `a` and
/// `b` (docs/MATH.md, "Correlation"); `b` defaults to `a` (the auto-MAC).
#[pyfunction]
#[pyo3(signature = (a, b=None))]
fn mac<'py>(
    py: Python<'py>,
    a: PyReadonlyArray2<'py, f64>,
    b: Option<PyReadonlyArray2<'py, f64>>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let a = py_to_mat(&a);
    let m = match b {
        Some(b) => femu_correlate::correlation::mac_matrix(a.as_ref(), py_to_mat(&b).as_ref()),
        None => femu_correlate::correlation::auto_mac(a.as_ref()),
    }
    .map_err(err)?;
    Ok(mat_to_py(py, &m))
}

/// The test shapes expanded to every free DOF of `model` by `method` (`static`, `dynamic`,
/// `serep`, `min-residual`, `mdre-we`; docs/MATH.md, "Expansion"), one column per test mode.
/// Releases the GIL.
#[pyfunction]
#[pyo3(signature = (model, test, *, method="dynamic"))]
fn expand<'py>(
    py: Python<'py>,
    model: &Model,
    test: &Test,
    method: &str,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let m = self::method(method)?;
    let t = &test.loaded.data.modes;
    let lambdas = t.eigenvalues();
    let x = py
        .detach(|| {
            femu_study::expand::expand_shapes(
                &model.loaded.sys,
                &test.loaded.layout,
                &lambdas,
                t.shapes.as_ref(),
                m,
                None,
            )
        })
        .map_err(err)?;
    Ok(mat_to_py(py, &x))
}

/// The a priori estimate of the paper: the test shapes expanded (`expansion`), the model's lowest
/// `count` modes paired with them (Table 1), and per test mode `rho_M`, `rho_2`, the frequency
/// interval that must hold a model frequency and every bound of Theorems 1-4 in the paper's and
/// the rigorous forms (Table 2), as a dict; `damped=True` as in `correlate`. Releases the GIL.
#[pyfunction]
#[pyo3(signature = (model, test, *, expansion="dynamic", count=None, mac_threshold=0.8, max_frequency_error=None, damped=false))]
#[allow(clippy::too_many_arguments)]
fn estimate<'py>(
    py: Python<'py>,
    model: &Model,
    test: &Test,
    expansion: &str,
    count: Option<usize>,
    mac_threshold: f64,
    max_frequency_error: Option<f64>,
    damped: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let options = femu_study::estimate::EstimateOptions {
        expansion: method(expansion)?,
        pairing: pairing(mac_threshold, max_frequency_error, damped),
        count,
        eigen: Default::default(),
    };
    let result = py
        .detach(|| {
            femu_study::estimate::estimate_loaded(&model.loaded, &test.loaded, &options, |_| {})
        })
        .map_err(err)?;
    to_dict(py, &result.result)
}

/// The pairing settings of `correlate` and `estimate`: the one definition of the command line's
/// and the study file's (a frequency error in percent).
fn pairing(
    mac_threshold: f64,
    max_frequency_error: Option<f64>,
    damped: bool,
) -> femu_correlate::PairingOptions {
    femu_study::study_file::PairingSection {
        mac_threshold,
        max_frequency_error,
        damped,
    }
    .options()
}

/// The paper's plate study end to end (what `femu demo` does): a plate with a modelling error is
/// "tested" (written as `test.unv`), correlated (Table 1), estimated (Table 2), studied under
/// sensor removal (Figure 1), localised, updated by SB-EBE and inverse eigensensitivity and
/// checked on held-out modes; files go to `out`. `quick` runs the smaller plate. `progress` is
/// called with each step's name. Returns the report as a dict. Releases the GIL; Ctrl-C, or an
/// exception raised by `progress`, stops the study at the next step.
#[pyfunction]
#[pyo3(signature = (out, *, quick=false, progress=None))]
fn run_demo<'py>(
    py: Python<'py>,
    out: PathBuf,
    quick: bool,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let mut opts = if quick {
        femu_study::demo::DemoOptions::quick()
    } else {
        femu_study::demo::DemoOptions::default()
    };
    opts.out = out;
    let report = interruptible(py, progress, |checkpoint| {
        femu_study::demo::run_demo(&opts, |msg| {
            checkpoint(&|py| Ok(pyo3::types::PyString::new(py, msg).into_any().unbind()))
        })
    })?
    .map_err(err)?;
    to_dict(py, &report)
}

/// Test-analysis correlation (the paper's Table 1): the model's lowest `count` modes (default
/// twice the test modes plus 4) paired with the test modes by MAC, frequency errors, MAC, MSD and
/// COMAC, as a dict. `damped=True` compares complex test shapes with the model's damped modes of
/// its damping (each pair's `complex_mac`; docs/MATH.md, "Damped modes"). Releases the
/// GIL.
#[pyfunction]
#[pyo3(signature = (model, test, *, count=None, mac_threshold=0.8, max_frequency_error=None, damped=false))]
fn correlate<'py>(
    py: Python<'py>,
    model: ModelSide<'py>,
    test: &Test,
    count: Option<usize>,
    mac_threshold: f64,
    max_frequency_error: Option<f64>,
    damped: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let t = &test.loaded.data.modes;
    let options = pairing(mac_threshold, max_frequency_error, damped);
    let report = match &model {
        ModelSide::Model(m) => {
            let loaded = &m.loaded;
            py.detach(|| -> Result<_, femu_study::StudyError> {
                let modes = femu_study::modes::lowest_for_test(
                    loaded,
                    count,
                    t.len(),
                    &Default::default(),
                )?;
                Ok(femu_correlate::correlate(
                    &femu_study::modes::mode_set(loaded, &modes, damped)?,
                    t,
                    &test.loaded.layout,
                    &options,
                )?)
            })
        }
        ModelSide::Results(r) => {
            let modes = &r.results.modes;
            py.detach(|| -> Result<_, femu_study::StudyError> {
                Ok(femu_correlate::correlate(
                    modes,
                    t,
                    &test.loaded.layout,
                    &options,
                )?)
            })
        }
    }
    .map_err(err)?;
    to_dict(py, &report)
}

/// Measured FRFs (a universal file with dataset 58, function type 4, at the model's node ids)
/// against the model's at the same DOFs and lines, by modal superposition of the modes up to
/// `modes_up_to` times the highest line with the residual flexibility of those above: FRAC per
/// function, CSAC and CSF per line, as a dict. Damping: `damping_ratio` (viscous, default 0.01
/// unless the deck states its own: a Nastran `PARAM,G` is its loss factor),
/// `loss_factor` or `rayleigh=(alpha, beta)`; `damping_from`, a test of identified modes with
/// damping ratios, gives each paired model mode its test's ratio (the others `damping_ratio`).
/// `direct=True` solves the dynamic stiffness at each line instead (docs/MATH.md, "Frequency
/// responses, directly"): the model's own dampers act, with a loss factor or Rayleigh damping.
/// `update`, candidate element sets, updates the model from the FRFs (docs/MATH.md, "Updating
/// from frequency responses"): the sets ranked by the FRF residue on the lowest `tuned_lines`
/// lines (default two-thirds), the selected ones (`update_all`: every one) and the damping (the
/// loss factor, or `rayleigh`'s two coefficients)
/// fitted (SB-EBE, then the output error; `sb_ebe_only` stops after SB-EBE;
/// `loss_factor_per_set=True`: a loss factor for each updated set and one for the rest) on at most
/// `update_lines` lines per band, and checked on the held-out lines (the dict's `update`).
/// Where the file carries coherence (function type 6), lines below `min_coherence` (default 0.8)
/// are left out.
/// Releases the GIL.
#[pyfunction]
#[pyo3(signature = (model, path, *, damping_ratio=None, loss_factor=None, rayleigh=None, direct=false, damping_from=None, modes_up_to=2.0, update=None, tuned_lines=None, update_lines=24, update_all=false, sb_ebe_only=false, min_coherence=None, loss_factor_per_set=false))]
#[allow(clippy::too_many_arguments)]
fn frf<'py>(
    py: Python<'py>,
    model: &Model,
    path: PathBuf,
    damping_ratio: Option<f64>,
    loss_factor: Option<f64>,
    rayleigh: Option<Vec<f64>>,
    direct: bool,
    damping_from: Option<PathBuf>,
    modes_up_to: f64,
    update: Option<Vec<String>>,
    tuned_lines: Option<usize>,
    update_lines: usize,
    update_all: bool,
    sb_ebe_only: bool,
    min_coherence: Option<f64>,
    loss_factor_per_set: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let request = femu_study::frf::FrfRequest {
        file: None,
        damping_ratio,
        loss_factor,
        rayleigh,
        direct,
        damping_from,
        modes_up_to,
        update: update.unwrap_or_default(),
        tuned_lines,
        update_lines,
        update_all,
        sb_ebe_only,
        min_coherence,
        loss_factor_per_set,
    };
    let result = py
        .detach(|| {
            femu_study::frf::frf_correlation(&model.loaded, &path, &request, &Default::default())
        })
        .map_err(err)?;
    to_dict(py, &result)
}

/// The sensor-removal study (the paper's Figure 1): from triaxial sensors at the test's nodes,
/// nodes removed one by one in Effective Independence order, the test shapes re-expanded (static,
/// dynamic, minimum residual) from every set and `rho_M`, `rho_2` evaluated, as a dict of points.
/// Releases the GIL.
#[pyfunction]
#[pyo3(signature = (model, test, *, expansion="dynamic"))]
fn removal_study<'py>(
    py: Python<'py>,
    model: &Model,
    test: &Test,
    expansion: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let m = method(expansion)?;
    let study = py
        .detach(|| -> Result<_, femu_study::StudyError> {
            let t = &test.loaded.data.modes;
            let x = femu_study::expand::expand_shapes(
                &model.loaded.sys,
                &test.loaded.layout,
                &t.eigenvalues(),
                t.shapes.as_ref(),
                m,
                None,
            )?;
            femu_study::removal::removal_over_test(&model.loaded, &test.loaded, x.as_ref())
        })
        .map_err(err)?;
    to_dict(py, &study)
}

/// Localisation, updating and the truth check (docs/MATH.md, "Localisation", "Updating", "The
/// truth check"): among the element sets `sets` (stiffness corrections; `"t:SET"` the thickness
/// of a set's shells, `"EA:SET"`, `"GJ:SET"`, `"EI1:SET"`, `"EI2:SET"` a part of its beams'
/// stiffness, a mass set such as `"CONM2_7"` its masses), the regions that explain
/// the residues of the first `tuned` test modes (default: all but the last third, as `femu update`
/// and study files) are selected by `select` (`"forward"`: those the data support, by forward
/// selection with an F-test; `"residual"`: the paper's residual ranking; `"all"`) and updated by
/// `method` (`"ies"`: inverse eigensensitivity, on frequencies and shapes unless
/// `shapes=False`; `"sbebe"`: the paper's SB-EBE); the updated
/// model is then checked on every test mode, the held-out ones included, and judged against the
/// test's uncertainty (`frequency_uncertainty`, `shape_uncertainty`, percent) and the model's
/// discretisation error (`discretisation=False` skips its estimate). `test_error` is SB-EBE's
/// trust in the shapes (default 1e-3). `progress` is called with each iteration (a dict: iteration, objective,
/// theta, seconds). Returns the study as a dict. Releases the GIL; Ctrl-C, or an exception raised
/// by `progress`, stops it at the next iteration.
#[pyfunction]
#[pyo3(signature = (model, test, sets, *, tuned=None, method="ies", select="forward", shapes=true, frequency_uncertainty=None, shape_uncertainty=None, test_error=None, discretisation=true, progress=None))]
#[allow(clippy::too_many_arguments)]
fn update<'py>(
    py: Python<'py>,
    model: &Model,
    test: &Test,
    sets: Vec<String>,
    tuned: Option<usize>,
    method: &str,
    select: &str,
    shapes: bool,
    frequency_uncertainty: Option<f64>,
    shape_uncertainty: Option<f64>,
    test_error: Option<f64>,
    discretisation: bool,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let m: femu_update::UpdateMethod = method.parse().map_err(|e| {
        pyo3::exceptions::PyValueError::new_err(format!("method {method:?}: {e} (sbebe or ies)"))
    })?;
    let select = match select {
        "forward" => femu_study::updating::Select::Forward,
        "residual" => femu_study::updating::Select::Residual,
        "all" => femu_study::updating::Select::All,
        other => {
            return Err(pyo3::exceptions::PyValueError::new_err(format!(
                "select {other:?}: expected forward, residual or all"
            )));
        }
    };
    // the request of `femu update` and of a study file's [update], with their defaults
    let request = femu_study::updating::UpdateRequest {
        sets,
        tuned,
        method: m,
        select,
        frequency_uncertainty,
        shape_uncertainty,
        shapes,
        test_error,
        discretisation,
    };
    let study = interruptible(py, progress, |checkpoint| {
        femu_study::updating::update_loaded(
            &model.loaded,
            &test.loaded,
            &request,
            &Default::default(),
            None,
            |it| checkpoint(&|py| to_dict(py, it).map(Bound::unbind)),
        )
    })?
    .map_err(err)?;
    to_dict(py, &study)
}

/// The Python module `femu._femu`.
#[pymodule]
fn _femu(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("FemuError", m.py().get_type::<FemuError>())?;
    m.add_class::<Model>()?;
    m.add_class::<Modes>()?;
    m.add_class::<Test>()?;
    m.add_class::<Results>()?;
    m.add_function(wrap_pyfunction!(read_results, m)?)?;
    m.add_function(wrap_pyfunction!(read_model, m)?)?;
    m.add_function(wrap_pyfunction!(read_test, m)?)?;
    m.add_function(wrap_pyfunction!(mac, m)?)?;
    m.add_function(wrap_pyfunction!(expand, m)?)?;
    m.add_function(wrap_pyfunction!(estimate, m)?)?;
    m.add_function(wrap_pyfunction!(run_demo, m)?)?;
    m.add_function(wrap_pyfunction!(correlate, m)?)?;
    m.add_function(wrap_pyfunction!(frf, m)?)?;
    m.add_function(wrap_pyfunction!(removal_study, m)?)?;
    m.add_function(wrap_pyfunction!(update, m)?)?;
    Ok(())
}
