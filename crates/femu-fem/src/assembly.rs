//! Parallel assembly of the global stiffness `K` and mass `M` on a pattern computed once.
//!
//! With multipoint constraints the matrices are `K_r = T^T K T`, `M_r = T^T M T` on the free DOFs
//! (docs/MATH.md, "Multipoint constraints"): an element whose nodes have dependent DOFs is
//! scattered through their rows of `T`, so it reaches the points those rows name (its *effective
//! points*); the pattern and the colouring use the effective points, so the reduced matrices are
//! assembled directly, in parallel, on a pattern computed once (no unreduced `K` is formed).
//!
//! The pattern is the point graph (points sharing an element) expanded to the free DOFs; it is
//! stored in compressed sparse column form with both triangles, rows sorted. Elements are
//! coloured so that no two elements of a colour share a node; the elements of one colour are
//! computed and scattered in parallel (rayon), each writing only to the columns of its own nodes,
//! so the writes of a colour never overlap and the result does not depend on the thread count
//! beyond round-off order.

use crate::FemError;
use crate::dof::DofMap;
use crate::kernel::{self, BadJacobian};
use crate::model::Model;
use femu_sparse::SparseMatrix;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Which mass matrix to assemble.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum MassKind {
    /// Consistent mass `int rho N^T N dV`, on the stiffness pattern.
    #[default]
    Consistent,
    /// Lumped (diagonal) mass: row sums for linear elements, HRZ for quadratic ones.
    Lumped,
}

/// Assembled system matrices on the free DOFs.
#[derive(Debug, Clone)]
pub struct SystemMatrices {
    /// Stiffness `K` (N/m), symmetric, both triangles stored.
    pub k: SparseMatrix,
    /// Mass `M` (kg): on the stiffness pattern (consistent, or lumped with multipoint
    /// constraints, whose `T^T M T` is not diagonal) or diagonal (lumped).
    pub m: SparseMatrix,
    /// The DOF map the matrices are numbered by.
    pub dofs: DofMap,
    /// Which mass `m` is.
    pub mass_kind: MassKind,
}

static ASSEMBLIES: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// How many global assemblies of `K` and `M` from element matrices ([`Assembler::assemble`],
/// [`Assembler::assemble_into`]) this process has done: a diagnostic for workflows that must
/// assemble a model once (a counter, not a timer, so tests can assert it).
pub fn assemblies_so_far() -> usize {
    ASSEMBLIES.load(std::sync::atomic::Ordering::Relaxed)
}

/// The sparsity pattern and element colouring of a model, computed once and reused for every
/// assembly with new values (updating iterations, parameter groups).
#[derive(Debug, Clone)]
pub struct Assembler {
    dofs: DofMap,
    nbr_ptr: Vec<usize>,
    nbrs: Vec<usize>,
    /// For neighbour slot `nbr_ptr[b] + k`, the number of rows in a column of node `b` before the
    /// rows of node `nbrs[nbr_ptr[b] + k]`.
    nbr_off: Vec<usize>,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    colors: Vec<Vec<usize>>,
}

/// The points an element on `nodes` reaches through `T`: its nodes and the points of the rows of
/// their dependent DOFs, sorted, without repeats (appended to `out` after clearing it).
fn effective_points(dofs: &DofMap, nodes: &[usize], out: &mut Vec<usize>) {
    out.clear();
    out.extend_from_slice(nodes);
    for &n in nodes {
        if dofs.has_dependent(n) {
            for c in 0..3 {
                out.extend(dofs.terms(n, c).iter().map(|(f, _)| dofs.free_dof(*f).0));
            }
        }
    }
    out.sort_unstable();
    out.dedup();
}

fn bad_jacobian(id: u64) -> impl Fn(BadJacobian) -> FemError {
    move |b| FemError::InvertedElement {
        element: id,
        det_j: b.det,
        point: b.point,
    }
}

impl Assembler {
    /// Computes the pattern of `model`'s free DOFs and the element colouring.
    ///
    /// # Errors
    /// [`FemError::NoFreeDofs`] when nothing is free.
    pub fn new(model: &Model) -> Result<Self, FemError> {
        let mesh = model.mesh();
        let dofs = model.dof_map()?;
        if dofs.free_count() == 0 {
            return Err(FemError::NoFreeDofs);
        }
        let nn = dofs.point_count();
        let ne_count = mesh.element_count();
        // effective points of elements, and of point masses on nodes with dependent DOFs (these
        // need the pattern only: they are added serially)
        let (mut eff_ptr, mut eff) = (Vec::new(), Vec::new());
        let mut extra: Vec<Vec<usize>> = Vec::new();
        let mut buf = Vec::new();
        for r in model.rigid_masses() {
            let mut pts = vec![r.node];
            pts.extend(dofs.rotation_point(r.node));
            effective_points(&dofs, &pts, &mut buf);
            extra.push(buf.clone());
        }
        if dofs.has_dependents() {
            eff_ptr.push(0);
            let mut buf = Vec::new();
            for el in mesh.elements() {
                effective_points(&dofs, el.nodes, &mut buf);
                eff.extend_from_slice(&buf);
                eff_ptr.push(eff.len());
            }
            for p in model.point_masses() {
                effective_points(&dofs, &[p.node], &mut buf);
                extra.push(buf.clone());
            }
        }
        let points_of = |e: usize| -> &[usize] {
            if eff_ptr.is_empty() {
                mesh.element(e).nodes
            } else {
                &eff[eff_ptr[e]..eff_ptr[e + 1]]
            }
        };
        // point -> items (elements, then the extra point-mass sets)
        let item_points = |i: usize| -> &[usize] {
            if i < ne_count {
                points_of(i)
            } else {
                &extra[i - ne_count]
            }
        };
        let items = ne_count + extra.len();
        let mut ne_ptr = vec![0usize; nn + 1];
        for i in 0..items {
            for n in item_points(i) {
                ne_ptr[n + 1] += 1;
            }
        }
        for i in 0..nn {
            ne_ptr[i + 1] += ne_ptr[i];
        }
        let mut ne = vec![0usize; ne_ptr[nn]];
        let mut fill = ne_ptr.clone();
        for i in 0..items {
            for n in item_points(i) {
                ne[fill[*n]] = i;
                fill[*n] += 1;
            }
        }
        // point graph, sorted neighbour lists (each point is its own neighbour)
        let lists: Vec<Vec<usize>> = (0..nn)
            .into_par_iter()
            .map(|b| {
                let mut v: Vec<usize> = vec![b];
                for e in &ne[ne_ptr[b]..ne_ptr[b + 1]] {
                    v.extend_from_slice(item_points(*e));
                }
                v.sort_unstable();
                v.dedup();
                v
            })
            .collect();
        let nfree: Vec<usize> = (0..nn)
            .map(|n| dofs.node_dofs(n).iter().flatten().count())
            .collect();
        let mut nbr_ptr = Vec::with_capacity(nn + 1);
        nbr_ptr.push(0);
        let mut nbrs = Vec::with_capacity(lists.iter().map(Vec::len).sum());
        let mut nbr_off = Vec::with_capacity(nbrs.capacity());
        let mut col_ptr = Vec::with_capacity(dofs.free_count() + 1);
        col_ptr.push(0);
        let mut row_idx = Vec::new();
        for (b, list) in lists.iter().enumerate() {
            let mut off = 0;
            for a in list {
                nbrs.push(*a);
                nbr_off.push(off);
                off += nfree[*a];
            }
            nbr_ptr.push(nbrs.len());
            for _ in 0..nfree[b] {
                for a in list {
                    row_idx.extend(dofs.node_dofs(*a).iter().flatten());
                }
                col_ptr.push(row_idx.len());
            }
        }
        // greedy colouring: no two elements of a colour share an effective point
        let mut color_of = vec![usize::MAX; ne_count];
        let mut stamp: Vec<usize> = Vec::new();
        let mut colors: Vec<Vec<usize>> = Vec::new();
        for e in 0..ne_count {
            for n in points_of(e) {
                for other in &ne[ne_ptr[*n]..ne_ptr[*n + 1]] {
                    if *other >= ne_count {
                        continue;
                    }
                    let c = color_of[*other];
                    if c != usize::MAX {
                        stamp[c] = e + 1;
                    }
                }
            }
            let c = (0..colors.len())
                .find(|c| stamp[*c] != e + 1)
                .unwrap_or_else(|| {
                    colors.push(Vec::new());
                    stamp.push(0);
                    colors.len() - 1
                });
            color_of[e] = c;
            colors[c].push(e);
        }
        Ok(Self {
            dofs,
            nbr_ptr,
            nbrs,
            nbr_off,
            col_ptr,
            row_idx,
            colors,
        })
    }

    /// Whether the lumped mass is stored on the stiffness pattern: with dependent DOFs, whose
    /// `T^T M T` couples the DOFs a dependent one is made of.
    pub fn lumped_on_pattern(&self) -> bool {
        self.dofs.has_dependents()
    }

    /// Position of entry `(r, c)` in the pattern's values.
    fn position(&self, r: usize, c: usize) -> usize {
        let (lo, hi) = (self.col_ptr[c], self.col_ptr[c + 1]);
        match self.row_idx[lo..hi].binary_search(&r) {
            Ok(k) => lo + k,
            Err(_) => unreachable!("rows reached through T are in the pattern"),
        }
    }

    /// Calls `add(position, value)` for a node-diagonal (lumped) element mass: `ml[a]` on the
    /// three translations of `nodes[a]`, through `T` when the pattern holds the lumped mass.
    pub(crate) fn scatter_lumped(
        &self,
        nodes: &[usize],
        ml: impl Fn(usize, usize) -> f64,
        mut add: impl FnMut(usize, f64),
    ) {
        for (a, &n) in nodes.iter().enumerate() {
            for i in 0..3 {
                let v = ml(a, i);
                if !self.lumped_on_pattern() {
                    if let Some(f) = self.dofs.free_index(n, i) {
                        add(f, v);
                    }
                    continue;
                }
                let t = self.dofs.terms(n, i);
                for (s, ws) in t {
                    for (r, wr) in t {
                        add(self.position(*r, *s), wr * ws * v);
                    }
                }
            }
        }
    }

    /// The DOF map of the pattern.
    pub fn dofs(&self) -> &DofMap {
        &self.dofs
    }

    /// Number of stored entries of `K` (both triangles).
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// The element colours (lists of internal element indices); elements of one colour share no node.
    pub fn colors(&self) -> &[Vec<usize>] {
        &self.colors
    }

    /// Calls `add(position, local, weight)` for every entry `(3a+i, 3b+j)` of an element matrix
    /// on `nodes`: `position` indexes the values of the stiffness pattern, `local` the row-major
    /// element matrix, `weight` the product of the two DOFs' weights in `T` (1 for free DOFs;
    /// fixed DOFs are skipped). One walk serves `K_e` and `M_e` together.
    #[inline]
    pub(crate) fn scatter(&self, nodes: &[usize], mut add: impl FnMut(usize, usize, f64)) {
        let nd = 3 * nodes.len();
        if self.dofs.has_dependents() && nodes.iter().any(|n| self.dofs.has_dependent(*n)) {
            for (lb, &nb) in nodes.iter().enumerate() {
                for j in 0..3 {
                    for (s, ws) in self.dofs.terms(nb, j) {
                        for (la, &na) in nodes.iter().enumerate() {
                            for i in 0..3 {
                                for (r, wr) in self.dofs.terms(na, i) {
                                    add(
                                        self.position(*r, *s),
                                        (3 * la + i) * nd + 3 * lb + j,
                                        wr * ws,
                                    );
                                }
                            }
                        }
                    }
                }
            }
            return;
        }
        for (lb, &nb) in nodes.iter().enumerate() {
            let db = self.dofs.node_dofs(nb);
            let (lo, hi) = (self.nbr_ptr[nb], self.nbr_ptr[nb + 1]);
            for (la, &na) in nodes.iter().enumerate() {
                let da = self.dofs.node_dofs(na);
                let k = match self.nbrs[lo..hi].binary_search(&na) {
                    Ok(k) => k,
                    Err(_) => unreachable!("element nodes are neighbours in the pattern"),
                };
                let base = self.nbr_off[lo + k];
                for (j, cj) in db.iter().enumerate() {
                    let Some(c) = cj else { continue };
                    let start = self.col_ptr[*c] + base;
                    let mut rank = 0;
                    for (i, ri) in da.iter().enumerate() {
                        if ri.is_some() {
                            add(start + rank, (3 * la + i) * nd + 3 * lb + j, 1.0);
                            rank += 1;
                        }
                    }
                }
            }
        }
    }

    /// A matrix on the stiffness pattern with the given values.
    pub(crate) fn pattern_matrix(&self, values: Vec<f64>) -> SparseMatrix {
        let n = self.dofs.free_count();
        SparseMatrix::new_csc((n, n), self.col_ptr.clone(), self.row_idx.clone(), values)
    }

    /// A diagonal matrix (the lumped mass) with the given diagonal.
    pub(crate) fn diagonal_matrix(&self, diag: Vec<f64>) -> SparseMatrix {
        let n = diag.len();
        SparseMatrix::new_csc((n, n), (0..=n).collect(), (0..n).collect(), diag)
    }

    /// Assembles `K` and `M` for the model this pattern was built from (same mesh and constraints).
    ///
    /// # Errors
    /// [`FemError::NoMaterial`] for an element without material, [`FemError::InvertedElement`] for
    /// a non-positive Jacobian, [`FemError::LengthMismatch`] if the model does not match the pattern.
    pub fn assemble(&self, model: &Model, mass: MassKind) -> Result<SystemMatrices, FemError> {
        let n = self.dofs.free_count();
        let m = match mass {
            MassKind::Lumped if !self.lumped_on_pattern() => self.diagonal_matrix(vec![0.0; n]),
            _ => self.pattern_matrix(vec![0.0; self.nnz()]),
        };
        let mut sys = SystemMatrices {
            k: self.pattern_matrix(vec![0.0; self.nnz()]),
            m,
            dofs: self.dofs.clone(),
            mass_kind: mass,
        };
        self.assemble_into(model, &mut sys)?;
        Ok(sys)
    }

    /// Re-assembles into existing matrices of this pattern (new material values, same mesh and
    /// constraints): no allocation, no new pattern. `sys.mass_kind` selects the mass.
    ///
    /// # Errors
    /// As [`Assembler::assemble`], and [`FemError::LengthMismatch`] if `sys` is not on this pattern.
    pub fn assemble_into(&self, model: &Model, sys: &mut SystemMatrices) -> Result<(), FemError> {
        ASSEMBLIES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let mesh = model.mesh();
        let n = self.dofs.free_count();
        let model_dofs = model.dof_map()?;
        if model_dofs != self.dofs || sys.dofs != self.dofs {
            return Err(FemError::LengthMismatch {
                what: "model DOFs against the assembler's",
                expected: n,
                got: model_dofs.free_count(),
            });
        }
        let mass = sys.mass_kind;
        let m_len = if mass == MassKind::Consistent || self.lumped_on_pattern() {
            self.nnz()
        } else {
            n
        };
        if sys.k.nnz() != self.nnz() || sys.m.nnz() != m_len {
            return Err(FemError::LengthMismatch {
                what: "matrix storage against the pattern",
                expected: self.nnz(),
                got: sys.k.nnz(),
            });
        }
        let materials: Vec<&crate::material::Material> = (0..mesh.element_count())
            .map(|e| model.material_of(e))
            .collect::<Result<_, _>>()?;
        let kv = sys.k.data_mut();
        kv.iter_mut().for_each(|v| *v = 0.0);
        let ks = shared::SharedSlice::new(kv);
        let mv = sys.m.data_mut();
        mv.iter_mut().for_each(|v| *v = 0.0);
        let ms = shared::SharedSlice::new(mv);
        for color in &self.colors {
            color.par_iter().try_for_each_init(
                ElementBuffers::default,
                |buf, &e| -> Result<(), FemError> {
                    let el = mesh.element(e);
                    mesh.element_coords(e, &mut buf.x);
                    let material = materials[e];
                    let rho = &material.density;
                    let nd = 3 * el.kind.num_nodes();
                    buf.ke.resize(nd * nd, 0.0);
                    kernel::element_stiffness_for(el.kind, &buf.x, material, &mut buf.ke)
                        .map_err(bad_jacobian(el.id))?;
                    // SAFETY of the shared writes (see `shared`): elements of one colour share no
                    // node, and an element writes only to the columns of its own nodes.
                    match mass {
                        MassKind::Consistent => {
                            buf.me.resize(nd * nd, 0.0);
                            kernel::element_mass(el.kind, &buf.x, *rho, &mut buf.me)
                                .map_err(bad_jacobian(el.id))?;
                            self.scatter(el.nodes, |p, l, w| {
                                ks.add(p, w * buf.ke[l]);
                                ms.add(p, w * buf.me[l]);
                            });
                        }
                        MassKind::Lumped => {
                            self.scatter(el.nodes, |p, l, w| ks.add(p, w * buf.ke[l]));
                            buf.ml.resize(el.kind.num_nodes(), 0.0);
                            kernel::lumped_mass(el.kind, &buf.x, *rho, &mut buf.ml)
                                .map_err(bad_jacobian(el.id))?;
                            let ml = &buf.ml;
                            self.scatter_lumped(el.nodes, |a, _| ml[a], |p, v| ms.add(p, v));
                        }
                    }
                    Ok(())
                },
            )?;
        }
        // rigid masses: the 6x6 block of the node's translations and rotations (kept whole with
        // the lumped mass too, which is then on the stiffness pattern whenever rotations exist)
        for r in model.rigid_masses() {
            let Some(rp) = self.dofs.rotation_point(r.node) else {
                continue;
            };
            if mass == MassKind::Lumped && !self.lumped_on_pattern() {
                self.scatter_lumped(&[r.node], |_, c| r.matrix[c][c], |at, v| ms.add(at, v));
                continue;
            }
            let local: Vec<f64> = r.matrix.iter().flatten().copied().collect();
            self.scatter(&[r.node, rp], |at, l, w| ms.add(at, w * local[l]));
        }
        // point masses: the 3x3 block of their node (the lumped mass keeps its diagonal; an
        // off-diagonal coupling needs the consistent pattern)
        for p in model.point_masses() {
            match mass {
                MassKind::Consistent => {
                    let local: Vec<f64> = p.mass.iter().flatten().copied().collect();
                    self.scatter(&[p.node], |at, l, w| ms.add(at, w * local[l]));
                }
                MassKind::Lumped => {
                    self.scatter_lumped(&[p.node], |_, c| p.mass[c][c], |at, v| ms.add(at, v));
                }
            }
        }
        Ok(())
    }
}

/// Per-thread scratch for element matrices.
#[derive(Default)]
pub(crate) struct ElementBuffers {
    pub(crate) x: Vec<[f64; 3]>,
    pub(crate) ke: Vec<f64>,
    pub(crate) me: Vec<f64>,
    pub(crate) ml: Vec<f64>,
}

/// Element matrices of one element: `(K_e, M_e)` row-major, `M_e` diagonal when lumped.
pub(crate) fn element_matrices(
    model: &Model,
    e: usize,
    mass: MassKind,
) -> Result<(Vec<f64>, Vec<f64>), FemError> {
    let mesh = model.mesh();
    let el = mesh.element(e);
    let mat = model.material_of(e)?;
    let mut x = Vec::new();
    mesh.element_coords(e, &mut x);
    let nn = el.kind.num_nodes();
    let nd = 3 * nn;
    let mut ke = vec![0.0; nd * nd];
    let mut me = vec![0.0; nd * nd];
    kernel::element_stiffness_for(el.kind, &x, mat, &mut ke).map_err(bad_jacobian(el.id))?;
    match mass {
        MassKind::Consistent => {
            kernel::element_mass(el.kind, &x, mat.density, &mut me).map_err(bad_jacobian(el.id))?
        }
        MassKind::Lumped => {
            let mut ml = vec![0.0; nn];
            kernel::lumped_mass(el.kind, &x, mat.density, &mut ml).map_err(bad_jacobian(el.id))?;
            for a in 0..nn {
                for i in 0..3 {
                    me[(3 * a + i) * nd + 3 * a + i] = ml[a];
                }
            }
        }
    }
    Ok((ke, me))
}

#[allow(unsafe_code)]
mod shared {
    //! A slice written concurrently at indices that the caller guarantees to be disjoint between
    //! threads: the element colouring makes the writes of one colour touch disjoint columns.
    use std::marker::PhantomData;

    pub(crate) struct SharedSlice<'a> {
        ptr: *mut f64,
        len: usize,
        _borrow: PhantomData<&'a mut [f64]>,
    }

    // SAFETY: the slice is exclusively borrowed for 'a; concurrent `add`s target disjoint indices
    // (element colouring), so no two threads access one element.
    unsafe impl Send for SharedSlice<'_> {}
    unsafe impl Sync for SharedSlice<'_> {}

    impl<'a> SharedSlice<'a> {
        pub(crate) fn new(s: &'a mut [f64]) -> Self {
            Self {
                ptr: s.as_mut_ptr(),
                len: s.len(),
                _borrow: PhantomData,
            }
        }

        /// `s[i] += v`. Bounds are always checked; disjointness between threads is the caller's
        /// contract (the colouring).
        #[inline]
        pub(crate) fn add(&self, i: usize, v: f64) {
            assert!(i < self.len, "index {i} out of bounds {}", self.len);
            // SAFETY: in bounds (checked above); no other thread writes index i concurrently.
            unsafe { *self.ptr.add(i) += v }
        }
    }
}
