//! Sensor layouts: where the test measured, mapped onto the model's free DOFs.
//!
//! A sensor is a node and a unit direction (any direction, not only the axes). Its reading of a
//! model displacement `u` is `d . u(node)`; stacked over sensors this is the observation matrix
//! `C` (`s x n`, one row per sensor, at most three entries per row), so the model mode shapes at
//! the sensors are `C Phi`. Measured DOFs `a` of docs/MATH.md are the sensors of an axis-aligned layout.

use crate::CorrelateError;
use faer::{Mat, MatRef};
use femu_fem::dof::DofMap;
use femu_fem::mesh::Mesh;
use femu_sparse::SparseMatrix;
use serde::{Deserialize, Serialize};

/// One sensor: a node (the user's id) and a direction (normalised when the layout is built).
///
/// A sensor between FE nodes (a test node mapped into an element, docs/MATH.md "Mapping test
/// nodes") keeps the test's label in `node` and reads the shape-function combination `at` of
/// model nodes: `u(p) = sum_a w_a u(node_a)`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Sensor {
    /// Node id: a model node, or the test's label of a sensor with `at`.
    pub node: u64,
    /// Measuring direction (global axes); need not be unit length.
    pub direction: [f64; 3],
    /// Model node ids and weights a sensor between nodes reads; empty for a sensor on `node`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub at: Vec<(u64, f64)>,
}

impl Sensor {
    /// A sensor on model node `node` along `direction`.
    pub fn new(node: u64, direction: [f64; 3]) -> Self {
        Self {
            node,
            direction,
            at: Vec::new(),
        }
    }

    /// A sensor along a global axis (`0 = x, 1 = y, 2 = z`).
    pub fn axis(node: u64, component: usize) -> Self {
        let mut direction = [0.0; 3];
        direction[component.min(2)] = 1.0;
        Self::new(node, direction)
    }

    /// A sensor labelled `label` at a point between model nodes, reading `sum_a w_a u(node_a)`
    /// along `direction` (`at` holds `(model node id, w_a)`, the shape functions at the point).
    pub fn between(label: u64, direction: [f64; 3], at: Vec<(u64, f64)>) -> Self {
        Self {
            node: label,
            direction,
            at,
        }
    }
}

/// Sensors mapped to free DOFs: the observation matrix `C`.
#[derive(Debug, Clone, PartialEq)]
pub struct SensorLayout {
    sensors: Vec<Sensor>,
    /// Per sensor: (free DOF, weight) pairs, weights the unit direction's components.
    rows: Vec<Vec<(usize, f64)>>,
    dim: usize,
}

/// Direction components below this (relative to 1) are treated as zero.
const COMPONENT_EPS: f64 = 1e-12;

/// `row[f] += v` on a sparse row of `(free DOF, weight)` pairs.
fn add_term(row: &mut Vec<(usize, f64)>, f: usize, v: f64) {
    match row.iter_mut().find(|(g, _)| *g == f) {
        Some((_, acc)) => *acc += v,
        None => row.push((f, v)),
    }
}

impl SensorLayout {
    /// Maps `sensors` onto the free DOFs of `dofs` (numbered as the assembled `K` and `M`).
    ///
    /// # Errors
    /// [`CorrelateError::SensorOnMissingNode`], [`CorrelateError::BadDirection`] (zero or not
    /// finite), [`CorrelateError::SensorOnConstrainedDof`] (a direction component along a fixed
    /// DOF), [`CorrelateError::DuplicateSensor`] (same node, parallel directions).
    pub fn new(mesh: &Mesh, dofs: &DofMap, sensors: Vec<Sensor>) -> Result<Self, CorrelateError> {
        let mut rows = Vec::with_capacity(sensors.len());
        let mut normalised = Vec::with_capacity(sensors.len());
        for (s, sensor) in sensors.iter().enumerate() {
            let d = sensor.direction;
            let norm = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            if !(norm.is_finite() && norm > 0.0) {
                return Err(CorrelateError::BadDirection {
                    sensor: s,
                    node: sensor.node,
                    direction: d,
                });
            }
            let unit = [d[0] / norm, d[1] / norm, d[2] / norm];
            let mut row = Vec::with_capacity(3);
            if sensor.at.is_empty() {
                let node =
                    mesh.node_index(sensor.node)
                        .ok_or(CorrelateError::SensorOnMissingNode {
                            sensor: s,
                            node: sensor.node,
                        })?;
                for c in 0..3 {
                    if unit[c].abs() <= COMPONENT_EPS {
                        continue;
                    }
                    // a dependent DOF reads its row of T (a rigid link's node, say)
                    let terms = dofs.terms(node, c);
                    if terms.is_empty() {
                        return Err(CorrelateError::SensorOnConstrainedDof {
                            sensor: s,
                            node: sensor.node,
                            component: c,
                        });
                    }
                    for &(f, w) in terms {
                        add_term(&mut row, f, w * unit[c]);
                    }
                }
                row.sort_by_key(|(f, _)| *f);
            } else {
                // between nodes: fixed DOFs read zero and drop out of the row
                for &(id, w) in &sensor.at {
                    let node = mesh
                        .node_index(id)
                        .ok_or(CorrelateError::SensorOnMissingNode {
                            sensor: s,
                            node: id,
                        })?;
                    if !w.is_finite() {
                        return Err(CorrelateError::BadDirection {
                            sensor: s,
                            node: sensor.node,
                            direction: d,
                        });
                    }
                    for c in 0..3 {
                        let v = w * unit[c];
                        if v.abs() <= COMPONENT_EPS {
                            continue;
                        }
                        for &(f, t) in dofs.terms(node, c) {
                            add_term(&mut row, f, t * v);
                        }
                    }
                }
                row.sort_by_key(|(f, _)| *f);
                if row.is_empty() {
                    return Err(CorrelateError::SensorOnConstrainedDof {
                        sensor: s,
                        node: sensor.node,
                        component: unit
                            .iter()
                            .enumerate()
                            .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
                            .map_or(0, |(c, _)| c),
                    });
                }
            }
            for (t, (earlier, prev)) in normalised.iter().zip(&sensors).enumerate() {
                let e: &[f64; 3] = earlier;
                let cos = e[0] * unit[0] + e[1] * unit[1] + e[2] * unit[2];
                if prev.node == sensor.node && (cos.abs() - 1.0).abs() < 1e-9 {
                    return Err(CorrelateError::DuplicateSensor {
                        first: t,
                        second: s,
                        node: sensor.node,
                    });
                }
            }
            normalised.push(unit);
            rows.push(row);
        }
        let sensors = sensors
            .into_iter()
            .zip(normalised)
            .map(|(s, d)| Sensor { direction: d, ..s })
            .collect();
        Ok(Self {
            sensors,
            rows,
            dim: dofs.free_count(),
        })
    }

    /// Three axis sensors (x, y, z) at each listed node, skipping constrained components.
    ///
    /// # Errors
    /// As [`SensorLayout::new`].
    pub fn triaxial(mesh: &Mesh, dofs: &DofMap, nodes: &[u64]) -> Result<Self, CorrelateError> {
        let mut sensors = Vec::with_capacity(3 * nodes.len());
        for (s, &id) in nodes.iter().enumerate() {
            let n = mesh
                .node_index(id)
                .ok_or(CorrelateError::SensorOnMissingNode {
                    sensor: 3 * s,
                    node: id,
                })?;
            let free = dofs.node_dofs(n);
            for c in 0..3 {
                if free[c].is_some() {
                    sensors.push(Sensor::axis(id, c));
                }
            }
        }
        Self::new(mesh, dofs, sensors)
    }

    /// Every free translational DOF measured, in the order of the free DOFs: the paper's full
    /// measurement set (the rotations of rigid links' reference nodes, which no sensor reads, are
    /// left out).
    pub fn full(mesh: &Mesh, dofs: &DofMap) -> Self {
        let n = dofs.free_count();
        let mut sensors = Vec::with_capacity(n);
        let mut rows = Vec::with_capacity(n);
        for f in 0..n {
            let (p, c) = dofs.free_dof(f);
            let (node, rotation) = dofs.point_node(p);
            if rotation {
                continue;
            }
            sensors.push(Sensor::axis(mesh.node_id(node), c));
            rows.push(vec![(f, 1.0)]);
        }
        Self {
            sensors,
            rows,
            dim: n,
        }
    }

    /// Number of sensors `s`.
    pub fn len(&self) -> usize {
        self.sensors.len()
    }

    /// Whether there are no sensors.
    pub fn is_empty(&self) -> bool {
        self.sensors.is_empty()
    }

    /// Number of model DOFs `n` (columns of `C`).
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// The sensors, directions normalised.
    pub fn sensors(&self) -> &[Sensor] {
        &self.sensors
    }

    /// The free DOFs and weights a sensor reads.
    pub fn row(&self, s: usize) -> &[(usize, f64)] {
        &self.rows[s]
    }

    /// The measured DOF of each sensor when every sensor is along an axis (`None` otherwise):
    /// the set `a` of docs/MATH.md's expansion formulas.
    pub fn measured_dofs(&self) -> Option<Vec<usize>> {
        self.rows
            .iter()
            .map(|r| match r.as_slice() {
                [(f, w)] if (*w - 1.0).abs() < 1e-15 => Some(*f),
                _ => None,
            })
            .collect()
    }

    /// Readings `C u` of one model vector.
    ///
    /// # Errors
    /// [`CorrelateError::DimensionMismatch`] if `u` is not of the model's size.
    pub fn measure(&self, u: &[f64]) -> Result<Vec<f64>, CorrelateError> {
        if u.len() != self.dim {
            return Err(CorrelateError::DimensionMismatch {
                what: "model vector read by the sensors",
                expected: self.dim,
                got: u.len(),
            });
        }
        Ok(self
            .rows
            .iter()
            .map(|r| r.iter().map(|(f, w)| w * u[*f]).sum())
            .collect())
    }

    /// Readings `C U` of the columns of `U` (`s x m`).
    ///
    /// # Errors
    /// As [`SensorLayout::measure`].
    pub fn measure_all(&self, u: MatRef<'_, f64>) -> Result<Mat<f64>, CorrelateError> {
        if u.nrows() != self.dim {
            return Err(CorrelateError::DimensionMismatch {
                what: "model vectors read by the sensors",
                expected: self.dim,
                got: u.nrows(),
            });
        }
        Ok(Mat::from_fn(self.len(), u.ncols(), |s, j| {
            self.rows[s].iter().map(|(f, w)| w * u[(*f, j)]).sum()
        }))
    }

    /// The observation matrix `C` (`s x n`, CSR).
    pub fn matrix(&self) -> SparseMatrix {
        let mut tri = sprs::TriMat::new((self.len(), self.dim));
        for (s, r) in self.rows.iter().enumerate() {
            for (f, w) in r {
                tri.add_triplet(s, *f, *w);
            }
        }
        tri.to_csr()
    }
}
