//! Meshes of mixed solid elements with the user's node and element ids.
//!
//! Files number nodes and elements with sparse, non-contiguous ids; femu keeps them and maps them
//! to dense internal indices (`0..node_count()`, `0..element_count()`) used by every array.
//! Errors and reports always speak in user ids.

use crate::FemError;
use crate::element::ElementKind;
use crate::kernel;
use std::collections::{BTreeMap, HashMap};

/// A mesh of solid elements: nodes, cells of mixed kinds, named node and element sets.
#[derive(Debug, Clone, Default)]
pub struct Mesh {
    coords: Vec<[f64; 3]>,
    node_ids: Vec<u64>,
    node_lookup: HashMap<u64, usize>,
    kinds: Vec<ElementKind>,
    offsets: Vec<usize>,
    conn: Vec<usize>,
    element_ids: Vec<u64>,
    element_lookup: HashMap<u64, usize>,
    node_sets: BTreeMap<String, Vec<usize>>,
    element_sets: BTreeMap<String, Vec<usize>>,
}

/// One element of a mesh, borrowed.
#[derive(Debug, Clone, Copy)]
pub struct ElementRef<'a> {
    /// Internal index.
    pub index: usize,
    /// The user's element id.
    pub id: u64,
    /// Element kind.
    pub kind: ElementKind,
    /// Internal node indices in the kind's ordering.
    pub nodes: &'a [usize],
}

impl Mesh {
    /// An empty mesh.
    pub fn new() -> Self {
        Self {
            offsets: vec![0],
            ..Default::default()
        }
    }

    /// Adds a node with the user's id and coordinates (m); returns its internal index.
    ///
    /// # Errors
    /// [`FemError::DuplicateNodeId`], or [`FemError::NonFiniteCoordinate`] for a NaN or infinity.
    pub fn add_node(&mut self, id: u64, x: [f64; 3]) -> Result<usize, FemError> {
        if x.iter().any(|v| !v.is_finite()) {
            return Err(FemError::NonFiniteCoordinate { node: id });
        }
        // Check before inserting: a rejected node must leave the mesh unchanged.
        if self.node_lookup.contains_key(&id) {
            return Err(FemError::DuplicateNodeId { id });
        }
        let index = self.coords.len();
        self.node_lookup.insert(id, index);
        self.coords.push(x);
        self.node_ids.push(id);
        Ok(index)
    }

    /// Adds an element given the user's node ids in the kind's ordering; returns its internal index.
    ///
    /// # Errors
    /// [`FemError::DuplicateElementId`], [`FemError::WrongNodeCount`], [`FemError::MissingNode`]
    /// or [`FemError::RepeatedNode`]. Geometry is checked by [`Mesh::validate`].
    pub fn add_element(
        &mut self,
        id: u64,
        kind: ElementKind,
        node_ids: &[u64],
    ) -> Result<usize, FemError> {
        if self.element_lookup.contains_key(&id) {
            return Err(FemError::DuplicateElementId { id });
        }
        if node_ids.len() != kind.num_nodes() {
            return Err(FemError::WrongNodeCount {
                element: id,
                kind,
                expected: kind.num_nodes(),
                got: node_ids.len(),
            });
        }
        let mut idx = Vec::with_capacity(node_ids.len());
        for n in node_ids {
            let i = *self.node_lookup.get(n).ok_or(FemError::MissingNode {
                element: id,
                node: *n,
            })?;
            if idx.contains(&i) {
                return Err(FemError::RepeatedNode {
                    element: id,
                    node: *n,
                });
            }
            idx.push(i);
        }
        Ok(self.push_element(id, kind, &idx))
    }

    /// Adds an element by internal node indices (generators); the caller guarantees validity.
    pub(crate) fn push_element(&mut self, id: u64, kind: ElementKind, nodes: &[usize]) -> usize {
        let index = self.kinds.len();
        self.element_lookup.insert(id, index);
        self.element_ids.push(id);
        self.kinds.push(kind);
        self.conn.extend_from_slice(nodes);
        self.offsets.push(self.conn.len());
        index
    }

    /// Defines (or replaces) a named node set from user node ids.
    ///
    /// # Errors
    /// [`FemError::UnknownNode`] for an id not in the mesh.
    pub fn add_node_set(
        &mut self,
        name: impl Into<String>,
        node_ids: &[u64],
    ) -> Result<(), FemError> {
        let idx = node_ids
            .iter()
            .map(|n| {
                self.node_index(*n)
                    .ok_or(FemError::UnknownNode { node: *n })
            })
            .collect::<Result<Vec<_>, _>>()?;
        self.node_sets.insert(name.into(), idx);
        Ok(())
    }

    /// Defines (or replaces) a named element set from user element ids.
    ///
    /// # Errors
    /// [`FemError::UnknownElement`] for an id not in the mesh.
    pub fn add_element_set(
        &mut self,
        name: impl Into<String>,
        element_ids: &[u64],
    ) -> Result<(), FemError> {
        let idx = element_ids
            .iter()
            .map(|e| {
                self.element_index(*e)
                    .ok_or(FemError::UnknownElement { element: *e })
            })
            .collect::<Result<Vec<_>, _>>()?;
        self.element_sets.insert(name.into(), idx);
        Ok(())
    }

    /// Defines a node set from internal indices (generators and tools).
    pub fn add_node_set_indices(&mut self, name: impl Into<String>, nodes: Vec<usize>) {
        self.node_sets.insert(name.into(), nodes);
    }

    /// Defines an element set from internal indices (generators and tools).
    pub fn add_element_set_indices(&mut self, name: impl Into<String>, elements: Vec<usize>) {
        self.element_sets.insert(name.into(), elements);
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.coords.len()
    }

    /// Number of elements.
    pub fn element_count(&self) -> usize {
        self.kinds.len()
    }

    /// All node coordinates by internal index.
    pub fn coords(&self) -> &[[f64; 3]] {
        &self.coords
    }

    /// The user's id of internal node `i`.
    pub fn node_id(&self, i: usize) -> u64 {
        self.node_ids[i]
    }

    /// Internal index of the node with user id `id`.
    pub fn node_index(&self, id: u64) -> Option<usize> {
        self.node_lookup.get(&id).copied()
    }

    /// Internal index of the element with user id `id`.
    pub fn element_index(&self, id: u64) -> Option<usize> {
        self.element_lookup.get(&id).copied()
    }

    /// Element `e` (internal index).
    pub fn element(&self, e: usize) -> ElementRef<'_> {
        ElementRef {
            index: e,
            id: self.element_ids[e],
            kind: self.kinds[e],
            nodes: &self.conn[self.offsets[e]..self.offsets[e + 1]],
        }
    }

    /// All elements in internal order.
    pub fn elements(&self) -> impl ExactSizeIterator<Item = ElementRef<'_>> + '_ {
        (0..self.element_count()).map(|e| self.element(e))
    }

    /// Coordinates of an element's nodes into `out` (cleared first).
    pub fn element_coords(&self, e: usize, out: &mut Vec<[f64; 3]>) {
        out.clear();
        out.extend(self.element(e).nodes.iter().map(|n| self.coords[*n]));
    }

    /// Named node sets (internal indices).
    pub fn node_sets(&self) -> &BTreeMap<String, Vec<usize>> {
        &self.node_sets
    }

    /// Named element sets (internal indices).
    pub fn element_sets(&self) -> &BTreeMap<String, Vec<usize>> {
        &self.element_sets
    }

    /// A node set by name.
    ///
    /// # Errors
    /// [`FemError::UnknownNodeSet`].
    pub fn node_set(&self, name: &str) -> Result<&[usize], FemError> {
        self.node_sets
            .get(name)
            .map(|v| v.as_slice())
            .ok_or_else(|| FemError::UnknownNodeSet { name: name.into() })
    }

    /// An element set by name.
    ///
    /// # Errors
    /// [`FemError::UnknownElementSet`].
    pub fn element_set(&self, name: &str) -> Result<&[usize], FemError> {
        self.element_sets
            .get(name)
            .map(|v| v.as_slice())
            .ok_or_else(|| FemError::UnknownElementSet { name: name.into() })
    }

    /// Number of elements of each kind.
    pub fn kind_counts(&self) -> BTreeMap<ElementKind, usize> {
        let mut m = BTreeMap::new();
        for k in &self.kinds {
            *m.entry(*k).or_insert(0) += 1;
        }
        m
    }

    /// Checks every element's geometry: the Jacobian determinant must be positive at every
    /// integration point (stiffness and mass rules) and node. An inverted element (negative
    /// determinant somewhere) and a degenerate one (determinant below `1e-10` of the element's
    /// size cubed, over the reference volume) are errors naming the element id.
    ///
    /// # Errors
    /// [`FemError::InvertedElement`] or [`FemError::DegenerateElement`] for the first bad element.
    pub fn validate(&self) -> Result<(), FemError> {
        let mut x = Vec::new();
        for e in 0..self.element_count() {
            self.element_coords(e, &mut x);
            let el = self.element(e);
            let worst = kernel::min_jacobian(el.kind, &x);
            let size = bounding_diagonal(&x);
            let scale = size * size * size / el.kind.reference_volume();
            if worst.det < 0.0 || worst.det.is_nan() {
                return Err(FemError::InvertedElement {
                    element: el.id,
                    det_j: worst.det,
                    point: worst.point,
                });
            }
            if worst.det <= 1e-10 * scale {
                return Err(FemError::DegenerateElement {
                    element: el.id,
                    det_j: worst.det,
                });
            }
        }
        Ok(())
    }

    /// The total volume (m^3), by the mass rule.
    ///
    /// # Errors
    /// [`FemError::InvertedElement`] for an element with a non-positive Jacobian.
    pub fn volume(&self) -> Result<f64, FemError> {
        let mut x = Vec::new();
        let mut v = 0.0;
        for e in 0..self.element_count() {
            self.element_coords(e, &mut x);
            let el = self.element(e);
            v += kernel::element_volume(el.kind, &x).map_err(|b| FemError::InvertedElement {
                element: el.id,
                det_j: b.det,
                point: b.point,
            })?;
        }
        Ok(v)
    }

    /// Checks that the mesh is conforming: every face is shared by at most two elements, an
    /// interior face's two elements use the same nodes on it (mid-edge nodes included), and no
    /// boundary face lies on another boundary face (a hanging face: a quadrilateral against two
    /// triangles, a refined neighbour, or coincident nodes with different ids).
    pub fn check_conformity(&self) -> ConformityReport {
        // sorted corner nodes -> (element, local face, sorted nodes of the face)
        type Owners = Vec<(usize, usize, Vec<usize>)>;
        let mut faces: HashMap<Vec<usize>, Owners> = HashMap::new();
        for el in self.elements() {
            for f in 0..el.kind.faces().len() {
                let mut corners: Vec<usize> =
                    el.kind.faces()[f].iter().map(|a| el.nodes[*a]).collect();
                corners.sort_unstable();
                let mut all: Vec<usize> =
                    el.kind.face_nodes(f).iter().map(|a| el.nodes[*a]).collect();
                all.sort_unstable();
                faces.entry(corners).or_default().push((el.index, f, all));
            }
        }
        let mut report = ConformityReport::default();
        let mut boundary = Vec::new();
        let mut keys: Vec<_> = faces.keys().cloned().collect();
        keys.sort_unstable();
        for key in keys {
            let owners = &faces[&key];
            match owners.len() {
                1 => boundary.push((owners[0].0, key.clone())),
                2 => {
                    report.interior_faces += 1;
                    if owners[0].2 != owners[1].2 {
                        report
                            .problems
                            .push(ConformityProblem::MismatchedFaceNodes {
                                elements: [
                                    self.element_ids[owners[0].0],
                                    self.element_ids[owners[1].0],
                                ],
                                nodes: key.iter().map(|n| self.node_ids[*n]).collect(),
                            });
                    }
                }
                _ => report.problems.push(ConformityProblem::OvershareFace {
                    elements: owners.iter().map(|o| self.element_ids[o.0]).collect(),
                    nodes: key.iter().map(|n| self.node_ids[*n]).collect(),
                }),
            }
        }
        report.boundary_faces = boundary.len();
        self.find_hanging_faces(&boundary, &mut report);
        report
    }

    /// Boundary faces whose centroid lies on another boundary face: internal cracks of a
    /// non-conforming mesh. Candidates come from a uniform grid over face bounding boxes.
    fn find_hanging_faces(&self, boundary: &[(usize, Vec<usize>)], report: &mut ConformityReport) {
        if boundary.is_empty() {
            return;
        }
        let pts = |f: &Vec<usize>| -> Vec<[f64; 3]> { f.iter().map(|n| self.coords[*n]).collect() };
        let mut lo = [f64::INFINITY; 3];
        let mut size = 0.0_f64;
        for (_, f) in boundary {
            let p = pts(f);
            size = size.max(bounding_diagonal(&p));
            for q in &p {
                for i in 0..3 {
                    lo[i] = lo[i].min(q[i]);
                }
            }
        }
        let h = size.max(1e-300);
        let cell = |x: &[f64; 3]| -> [i64; 3] {
            std::array::from_fn(|i| ((x[i] - lo[i]) / h).floor() as i64)
        };
        let mut grid: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
        for (k, (_, f)) in boundary.iter().enumerate() {
            let p = pts(f);
            let (mut a, mut b) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
            for q in &p {
                for i in 0..3 {
                    a[i] = a[i].min(q[i]);
                    b[i] = b[i].max(q[i]);
                }
            }
            let (ca, cb) = (cell(&a), cell(&b));
            for x in ca[0]..=cb[0] {
                for y in ca[1]..=cb[1] {
                    for z in ca[2]..=cb[2] {
                        grid.entry([x, y, z]).or_default().push(k);
                    }
                }
            }
        }
        let mut reported = std::collections::HashSet::new();
        for (k, (e, f)) in boundary.iter().enumerate() {
            let p = pts(f);
            let c: [f64; 3] =
                std::array::from_fn(|i| p.iter().map(|q| q[i]).sum::<f64>() / p.len() as f64);
            let tol = 1e-8 * bounding_diagonal(&p);
            for &other in grid.get(&cell(&c)).map(|v| v.as_slice()).unwrap_or(&[]) {
                if other == k || boundary[other].0 == *e {
                    continue;
                }
                let q = pts(&boundary[other].1);
                if point_on_polygon(&c, &q, tol) {
                    let pair = (k.min(other), k.max(other));
                    if reported.insert(pair) {
                        report.problems.push(ConformityProblem::HangingFace {
                            elements: [self.element_ids[*e], self.element_ids[boundary[other].0]],
                            nodes: f.iter().map(|n| self.node_ids[*n]).collect(),
                        });
                    }
                }
            }
        }
    }
}

/// Length of the bounding-box diagonal of a point set (infinite for an empty one).
pub fn bounding_diagonal(x: &[[f64; 3]]) -> f64 {
    let mut s = 0.0;
    for i in 0..3 {
        let (lo, hi) = x
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
                (l.min(p[i]), h.max(p[i]))
            });
        s += (hi - lo) * (hi - lo);
    }
    s.sqrt()
}

fn sub(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn cross(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Whether `c` lies on the (fan-triangulated) polygon `q` within distance `tol`.
fn point_on_polygon(c: &[f64; 3], q: &[[f64; 3]], tol: f64) -> bool {
    for t in 1..q.len() - 1 {
        let (a, b, d) = (q[0], q[t], q[t + 1]);
        let n = cross(&sub(&b, &a), &sub(&d, &a));
        let nn = dot(&n, &n).sqrt();
        if nn == 0.0 {
            continue;
        }
        if (dot(&sub(c, &a), &n) / nn).abs() > tol {
            continue;
        }
        // barycentric signs
        let s1 = dot(&cross(&sub(&b, &a), &sub(c, &a)), &n);
        let s2 = dot(&cross(&sub(&d, &b), &sub(c, &b)), &n);
        let s3 = dot(&cross(&sub(&a, &d), &sub(c, &d)), &n);
        let eps = -tol * nn;
        if s1 >= eps && s2 >= eps && s3 >= eps {
            return true;
        }
    }
    false
}

/// The outcome of [`Mesh::check_conformity`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ConformityReport {
    /// Faces shared by exactly two elements.
    pub interior_faces: usize,
    /// Faces on the boundary (one element).
    pub boundary_faces: usize,
    /// What is wrong, in user ids.
    pub problems: Vec<ConformityProblem>,
}

impl ConformityReport {
    /// Whether the mesh is conforming.
    pub fn is_conforming(&self) -> bool {
        self.problems.is_empty()
    }
}

/// A conformity defect, in user ids.
#[derive(Debug, Clone, PartialEq)]
pub enum ConformityProblem {
    /// Two elements share a face's corners but not its mid-edge nodes.
    MismatchedFaceNodes {
        /// The two elements.
        elements: [u64; 2],
        /// The face's corner nodes.
        nodes: Vec<u64>,
    },
    /// More than two elements share a face (overlapping elements).
    OvershareFace {
        /// The elements.
        elements: Vec<u64>,
        /// The face's corner nodes.
        nodes: Vec<u64>,
    },
    /// A boundary face lies on another element's boundary face: the elements touch without
    /// sharing nodes.
    HangingFace {
        /// The element owning the face, and the element it lies on.
        elements: [u64; 2],
        /// The face's nodes.
        nodes: Vec<u64>,
    },
}

impl std::fmt::Display for ConformityProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::MismatchedFaceNodes { elements, nodes } => {
                write!(
                    f,
                    "elements {} and {} share face {:?} with different mid-edge nodes",
                    elements[0], elements[1], nodes
                )
            }
            Self::OvershareFace { elements, nodes } => {
                write!(f, "face {nodes:?} is shared by elements {elements:?}")
            }
            Self::HangingFace { elements, nodes } => write!(
                f,
                "hanging face: face {:?} of element {} lies on element {} without sharing its nodes",
                nodes, elements[0], elements[1]
            ),
        }
    }
}
