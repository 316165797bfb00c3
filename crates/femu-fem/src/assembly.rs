//! Parallel assembly of the global stiffness `K` and mass `M` on a pattern computed once.
//!
//! With multipoint constraints the matrices are `K_r = T^T K T`, `M_r = T^T M T` on the free DOFs
//! (docs/MATH.md, "Multipoint constraints"): an element whose nodes have dependent DOFs is
//! scattered through their rows of `T`, so it reaches the points those rows name (its *effective
//! points*); the pattern and the colouring use the effective points, so the reduced matrices are
//! assembled directly, in parallel, on a pattern computed once (no unreduced `K` is formed).
//!
//! The pattern is the point graph (points sharing an element) expanded to the free DOFs; it is
//! stored in compressed sparse column form with both triangles, rows sorted. Elements are cut into
//! chunks of consecutive elements (about [`CHUNK_POINTS`] element nodes each: neighbouring
//! elements of a chunk share columns, which then stay in cache while the chunk is scattered), and
//! the chunks are coloured so that no two chunks of a colour share a node. The chunks of one colour
//! are computed and scattered in parallel (rayon), each writing only to the columns of its own
//! nodes, so the writes of a colour never overlap; every entry receives its contributions in the
//! same order on any number of threads, so the result does not depend on the thread count.

use crate::FemError;
use crate::dof::DofMap;
use crate::kernel::{self, BadJacobian};
use crate::model::Model;
use femu_sparse::cholesky::SymbolicFactor;
use femu_sparse::eigen::{EigenOptions, Modes, NullSpaceHint, Pencil, PencilChecks, Which};
use femu_sparse::ordering::{Ordering, Pattern};
use femu_sparse::slepc::Engine;
use femu_sparse::{SparseError, SparseMatrix};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Which mass matrix to assemble.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum MassKind {
    /// Consistent mass `int rho N^T N dV`, stored where it is not exactly zero (inside the
    /// stiffness pattern).
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
    /// Mass `M` (kg), its pattern inside `K`'s: consistent, the entries of the stiffness pattern
    /// that are not exactly zero (for solids a third of them, docs/SCALING.md "Memory"); lumped,
    /// diagonal, or on the stiffness pattern with multipoint constraints, whose `T^T M T` is not
    /// diagonal.
    pub m: SparseMatrix,
    /// The DOF map the matrices are numbered by.
    pub dofs: DofMap,
    /// Which mass `m` is.
    pub mass_kind: MassKind,
    /// The six rigid-body motions of the model on the free DOFs ([`DofMap::rigid_body_motions`]),
    /// for the eigensolver to lock the zero-energy modes in their span before it iterates
    /// ([`SystemMatrices::modes`], docs/MATH.md "Known null vectors").
    pub rigid_body: NullSpaceHint,
    /// The nested-dissection analysis of `k`'s pattern, made beside the assembly of the values
    /// ([`Assembler::assemble_analysed`]); lent by [`SystemMatrices::analysis`] while it is `k`'s.
    analysis: Option<SymbolicFactor>,
    /// The eigensolver's checks of `(k, m)`, made beside that analysis once the values were done
    /// ([`PencilChecks`]: used only while they are `k`'s and `m`'s).
    checks: Option<PencilChecks>,
}

impl SystemMatrices {
    /// Matrices assembled elsewhere (another solver's `K` and `M`), already numbered by `dofs`'
    /// free DOFs, with the rigid-body motions of the nodes at `coords` as the eigensolver's
    /// null-space hint (checked by it, so a supported model loses nothing by it).
    ///
    /// # Errors
    /// [`FemError::Constraint`] when a matrix is not square of `dofs.free_count()` rows.
    pub fn from_matrices(
        k: SparseMatrix,
        m: SparseMatrix,
        dofs: DofMap,
        mass_kind: MassKind,
        coords: &[[f64; 3]],
    ) -> Result<Self, FemError> {
        let n = dofs.free_count();
        for (name, a) in [("K", &k), ("M", &m)] {
            if a.rows() != n || a.cols() != n {
                return Err(FemError::Constraint {
                    label: format!("the matrix {name}"),
                    reason: format!(
                        "it is {} x {}, the DOF map has {n} free DOFs",
                        a.rows(),
                        a.cols()
                    ),
                });
            }
        }
        let rigid_body = NullSpaceHint::new(dofs.rigid_body_motions(coords));
        Ok(Self {
            k,
            m,
            dofs,
            mass_kind,
            rigid_body,
            analysis: None,
            checks: None,
        })
    }

    /// `params` with [`SystemMatrices::rigid_body`] as its null-space hint, unless it has one.
    pub fn eigen_options(&self, params: &EigenOptions) -> EigenOptions {
        EigenOptions {
            null_space_hint: params
                .null_space_hint
                .clone()
                .or_else(|| Some(self.rigid_body.clone())),
            ..params.clone()
        }
    }

    /// The eigenpairs `which` of `(K, M)` ([`femu_sparse::eigen::eigs`]) with the model's
    /// rigid-body motions as the null-space hint: a free or partly supported structure's
    /// zero-energy modes are verified and locked before the iteration instead of converged by it
    /// (on a free-free plate of 47,628 DOF, 75 solved vectors instead of 104).
    ///
    /// With femu's own engine and the nested-dissection ordering, the analysis made beside the
    /// assembly ([`SystemMatrices::analysis`]) is used: the solve does no ordering of its own;
    /// and so are the checks of `K` and `M` made beside it, while they are still `K`'s and `M`'s
    /// (a fingerprint of both: changed matrices are checked again).
    ///
    /// # Errors
    /// As [`femu_sparse::eigen::eigs`].
    pub fn modes(&self, which: Which, params: &EigenOptions) -> Result<Modes, SparseError> {
        let params = self.eigen_options(params);
        match (&params.engine, params.ordering) {
            (Engine::Femu, Ordering::NestedDissection) => match self.analysis() {
                Some(symbolic) => match &self.checks {
                    Some(checks) => Pencil::with_checks(&self.k, &self.m, symbolic, checks)?,
                    None => Pencil::with_symbolic(&self.k, &self.m, symbolic)?,
                }
                .solve(which, &params),
                None => femu_sparse::eigen::eigs(&self.k, &self.m, which, &params),
            },
            _ => femu_sparse::eigen::eigs(&self.k, &self.m, which, &params),
        }
    }

    /// The nested-dissection analysis of `k`'s pattern made by [`Assembler::assemble_analysed`]
    /// (and [`Model::assemble`]), if `k` still has the pattern it was made for
    /// ([`SymbolicFactor::is_for`]: `k` is a public field and may have been replaced). The copy
    /// keeps nothing of the factorizations done with it ([`SymbolicFactor::detached`]).
    pub fn analysis(&self) -> Option<SymbolicFactor> {
        self.analysis
            .as_ref()
            .filter(|a| a.is_for(&self.k))
            .map(SymbolicFactor::detached)
    }
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
    /// Chunk `c` is the elements `chunk_ptr[c]..chunk_ptr[c + 1]` (consecutive internal indices).
    chunk_ptr: Vec<usize>,
    /// Lists of chunks; the chunks of one colour share no effective point.
    colors: Vec<Vec<usize>>,
    /// Global assemblies made on this pattern, shared by the assembler's clones
    /// ([`Assembler::assemblies`]).
    assemblies: std::sync::Arc<std::sync::atomic::AtomicUsize>,
    /// Whether a concentrated mass couples DOFs (a rigid mass with an offset or products of
    /// inertia, a point mass with off-diagonal terms): the lumped mass then keeps it whole, on the
    /// stiffness pattern ([`Assembler::lumped_on_pattern`]).
    coupled_masses: bool,
}

/// Whether a concentrated mass of `model` couples two DOFs (its matrix has an entry off the
/// diagonal): Nastran adds a CONM2's whole 6 x 6 and a CMASS's whole matrix to the mass matrix
/// whatever the mass formulation, so the lumped mass keeps such masses whole
/// ([`Assembler::lumped_on_pattern`]). A scalar mass couples DOFs when it joins two, or acts
/// along a direction that is not a basic axis.
fn has_coupled_masses(model: &Model, dofs: &DofMap) -> bool {
    fn off_diagonal<const N: usize>(a: &[[f64; N]; N]) -> bool {
        (0..N).any(|i| (0..N).any(|j| i != j && a[i][j] != 0.0))
    }
    let scalar = |s: &crate::structural::Spring| {
        s.mass != 0.0 && (s.b.is_some() || s.a.direction.iter().filter(|v| **v != 0.0).count() > 1)
    };
    model
        .rigid_masses()
        .iter()
        .any(|r| dofs.rotation_point(r.node).is_some() && off_diagonal(&r.matrix))
        || model.point_masses().iter().any(|p| off_diagonal(&p.mass))
        || model.structural().iter().any(|e| match &e.kind {
            crate::structural::StructuralKind::Spring(s) => scalar(s),
            _ => false,
        })
        || model
            .direct_entries(crate::model::DirectMatrix::Mass)
            .iter()
            .any(|e| e.a != e.b)
}

/// A direct matrix entry as the row-major `nd x nd` block of its points ([`direct_points`]):
/// `value` at `(r, c)` and, off the diagonal, at `(c, r)`.
fn direct_block(nd: usize, (r, c): (usize, usize), value: f64) -> Vec<f64> {
    let mut local = vec![0.0; nd * nd];
    local[r * nd + c] += value;
    if r != c {
        local[c * nd + r] += value;
    }
    local
}

/// The points of a direct matrix entry's two DOFs and its local indices on them: `(points,
/// (row, column))` of a `3 points.len()` square block (one point when both DOFs are on it);
/// `None` when a rotation's node has lost its rotations (fixed: no element reaches them).
fn direct_points(
    dofs: &DofMap,
    e: &crate::model::DirectEntry,
) -> Option<(Vec<usize>, (usize, usize))> {
    let point = |(n, c): (usize, usize)| -> Option<usize> {
        if c < 3 {
            Some(n)
        } else {
            dofs.rotation_point(n)
        }
    };
    let (pa, pb) = (point(e.a)?, point(e.b)?);
    if pa == pb {
        Some((vec![pa], (e.a.1 % 3, e.b.1 % 3)))
    } else {
        Some((vec![pa, pb], (e.a.1 % 3, 3 + e.b.1 % 3)))
    }
}

/// How many element nodes (counted with repetition) a chunk of the colouring holds at least: a
/// chunk is the fewest consecutive elements reaching it (26 hex20, 52 tet10, 64 hex8). Re-assembly
/// of a hex20 block was 20-30 % faster with chunks of 512 than of one element, and no faster with
/// 2,048; models of 10^4 elements and more keep tens of chunks per colour for the threads.
pub const CHUNK_POINTS: usize = 512;

/// Entries per piece when large arrays are zeroed or copied in parallel (512 KiB of `f64`).
const ZERO_CHUNK: usize = 1 << 16;

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

/// The DOF map's points of a structural element's `(node, part)` blocks: the node itself for its
/// translations, its rotation point for its rotations.
///
/// # Panics
/// If a node the element turns has no rotations (the model gives them when it adds the element).
pub(crate) fn structural_points(
    dofs: &DofMap,
    parts: &[(usize, crate::structural::Part)],
) -> Vec<usize> {
    parts
        .iter()
        .map(|(n, p)| match p {
            crate::structural::Part::Translations => *n,
            crate::structural::Part::Rotations => dofs
                .rotation_point(*n)
                .expect("Model::add_structural gives the node rotations"),
        })
        .collect()
}

fn bad_jacobian(id: u64) -> impl Fn(BadJacobian) -> FemError {
    move |b| FemError::InvertedElement {
        element: id,
        det_j: b.det,
        point: b.point,
    }
}

impl Assembler {
    /// How many global assemblies of `K` and `M` from element matrices ([`Assembler::assemble`],
    /// [`Assembler::assemble_into`]) this assembler and its clones have made: a diagnostic for
    /// workflows that must assemble a model once (a counter, not a timer, so tests can assert
    /// it). Clones share the count: an updating model built on a workflow's assembler counts
    /// there.
    pub fn assemblies(&self) -> usize {
        self.assemblies.load(std::sync::atomic::Ordering::Relaxed)
    }

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
        for s in model.structural() {
            effective_points(&dofs, &structural_points(&dofs, &s.parts()), &mut buf);
            extra.push(buf.clone());
        }
        for which in crate::model::DirectMatrix::ALL {
            for e in model.direct_entries(which) {
                if let Some((pts, _)) = direct_points(&dofs, e) {
                    effective_points(&dofs, &pts, &mut buf);
                    extra.push(buf.clone());
                }
            }
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
        // chunks of consecutive elements, about CHUNK_POINTS effective points each
        let mut chunk_ptr = vec![0];
        let mut chunk_of = vec![0usize; ne_count];
        let mut filled = 0;
        for (e, c) in chunk_of.iter_mut().enumerate() {
            *c = chunk_ptr.len() - 1;
            filled += points_of(e).len();
            if filled >= CHUNK_POINTS {
                chunk_ptr.push(e + 1);
                filled = 0;
            }
        }
        if *chunk_ptr.last().unwrap_or(&0) != ne_count {
            chunk_ptr.push(ne_count);
        }
        // greedy colouring of the chunks: no two chunks of a colour share an effective point
        let n_chunks = chunk_ptr.len() - 1;
        let mut color_of = vec![usize::MAX; n_chunks];
        let mut stamp: Vec<usize> = Vec::new();
        let mut colors: Vec<Vec<usize>> = Vec::new();
        for ch in 0..n_chunks {
            for e in chunk_ptr[ch]..chunk_ptr[ch + 1] {
                for n in points_of(e) {
                    for other in &ne[ne_ptr[*n]..ne_ptr[*n + 1]] {
                        if *other >= ne_count {
                            continue;
                        }
                        let c = color_of[chunk_of[*other]];
                        if c != usize::MAX {
                            stamp[c] = ch + 1;
                        }
                    }
                }
            }
            let c = (0..colors.len())
                .find(|c| stamp[*c] != ch + 1)
                .unwrap_or_else(|| {
                    colors.push(Vec::new());
                    stamp.push(0);
                    colors.len() - 1
                });
            color_of[ch] = c;
            colors[c].push(ch);
        }
        let coupled_masses = has_coupled_masses(model, &dofs);
        Ok(Self {
            dofs,
            nbr_ptr,
            nbrs,
            nbr_off,
            col_ptr,
            row_idx,
            chunk_ptr,
            colors,
            assemblies: Default::default(),
            coupled_masses,
        })
    }

    /// The symbolic analysis (fill-reducing `ordering` and elimination structure) of the pattern
    /// of `K`, before any value is assembled.
    ///
    /// # Errors
    /// As [`SymbolicFactor::of_pattern`].
    pub fn analysis(&self, ordering: Ordering) -> Result<SymbolicFactor, SparseError> {
        let pattern = Pattern::new(self.dofs.free_count(), &self.col_ptr, &self.row_idx)?;
        SymbolicFactor::of_pattern(pattern, ordering)
    }

    /// Whether the lumped mass is stored on the stiffness pattern: with dependent DOFs, whose
    /// `T^T M T` couples the DOFs a dependent one is made of, and with a concentrated mass that
    /// couples DOFs (a CONM2 with an offset or products of inertia), which it keeps whole.
    pub fn lumped_on_pattern(&self) -> bool {
        self.dofs.has_dependents() || self.coupled_masses
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

    /// The colours of the element chunks: lists of chunk indices ([`Assembler::chunk`]); no two
    /// chunks of one colour share a node (or, with multipoint constraints, an effective point).
    pub fn colors(&self) -> &[Vec<usize>] {
        &self.colors
    }

    /// The internal element indices of chunk `c` (consecutive).
    ///
    /// # Panics
    /// If `c` is not a chunk index of [`Assembler::colors`].
    pub fn chunk(&self, c: usize) -> std::ops::Range<usize> {
        self.chunk_ptr[c]..self.chunk_ptr[c + 1]
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
        self.for_each_entry(nodes, |lb, j, la, i, p| {
            add(p, (3 * la + i) * nd + 3 * lb + j, 1.0)
        });
    }

    /// Calls `f(b, j, a, i, position)` for every entry `(3a+i, 3b+j)` of an element on `nodes`
    /// none of which has a dependent DOF, both DOFs free (fixed ones are skipped), with its
    /// position in the pattern's values, column by column. The offsets of the element's nodes in
    /// a column come from one merge of the element's sorted nodes with the column node's sorted
    /// neighbour list (not a binary search per node pair).
    #[inline]
    fn for_each_entry(
        &self,
        nodes: &[usize],
        mut f: impl FnMut(usize, usize, usize, usize, usize),
    ) {
        const MAX_NODES: usize = 20;
        let nn = nodes.len();
        assert!(nn <= MAX_NODES, "an element of {nn} nodes");
        // local node indices in increasing global node order
        let mut order = [0usize; MAX_NODES];
        for a in 0..nn {
            let mut k = a;
            while k > 0 && nodes[order[k - 1]] > nodes[a] {
                order[k] = order[k - 1];
                k -= 1;
            }
            order[k] = a;
        }
        for (lb, &nb) in nodes.iter().enumerate() {
            let db = self.dofs.node_dofs(nb);
            let lo = self.nbr_ptr[nb];
            let list = &self.nbrs[lo..self.nbr_ptr[nb + 1]];
            let mut p = 0;
            for &la in &order[..nn] {
                let na = nodes[la];
                // every element node is in the list (the pattern is built from the elements)
                while list[p] < na {
                    p += 1;
                }
                let base = self.nbr_off[lo + p];
                let da = self.dofs.node_dofs(na);
                for (j, cj) in db.iter().enumerate() {
                    let Some(c) = cj else { continue };
                    let start = self.col_ptr[*c] + base;
                    let mut rank = 0;
                    for (i, ri) in da.iter().enumerate() {
                        if ri.is_some() {
                            f(lb, j, la, i, start + rank);
                            rank += 1;
                        }
                    }
                }
            }
        }
    }

    /// Adds an element's stiffness `ke` (row-major `3 nn` square) and, when given, its scalar
    /// consistent mass `m` (`nn` square; `M_e[3a+i][3b+j] = m[a][b] delta_ij`) into `k` and `m`'s
    /// values on the pattern, for an element none of whose nodes has a dependent DOF (fixed DOFs
    /// are skipped). Both matrices must be exactly symmetric, as the kernels make them: column
    /// `(b, j)` of the global matrix is then fed from row `3 b + j` of `ke`, read contiguously,
    /// and the mass, zero off the `i = j` diagonal of each node block, is added only there.
    #[inline]
    pub(crate) fn scatter_element(
        &self,
        nodes: &[usize],
        ke: &[f64],
        me: Option<&[f64]>,
        kadd: impl Fn(usize, f64),
        madd: impl Fn(usize, f64),
    ) {
        let nn = nodes.len();
        let nd = 3 * nn;
        debug_assert_eq!(ke.len(), nd * nd);
        self.for_each_entry(nodes, |lb, j, la, i, p| {
            kadd(p, ke[(3 * lb + j) * nd + 3 * la + i]);
            if let (true, Some(m)) = (i == j, me) {
                madd(p, m[la * nn + lb]);
            }
        });
    }

    /// A matrix on the stiffness pattern with the given values.
    ///
    /// The row indices are copied in parallel into zeroed memory the operating system provides on
    /// first touch: on a large model that provisioning (a page fault per 4 KiB) costs more than
    /// the copy, and page faults on different threads proceed in parallel (the hex20 block of
    /// `benches/assembly.rs`: 1.6 GB of indices per matrix).
    pub(crate) fn pattern_matrix(&self, values: Vec<f64>) -> SparseMatrix {
        let n = self.dofs.free_count();
        let mut rows = vec![0usize; self.row_idx.len()];
        rows.par_chunks_mut(ZERO_CHUNK)
            .zip(self.row_idx.par_chunks(ZERO_CHUNK))
            .for_each(|(d, s)| d.copy_from_slice(s));
        SparseMatrix::new_csc((n, n), self.col_ptr.clone(), rows, values)
    }

    /// The matrix with `values` on this pattern, without the entries that are exactly zero off
    /// its diagonal ([`femu_sparse::csc::without_zeros_of`]): the consistent mass.
    pub(crate) fn without_zeros(&self, values: &[f64]) -> SparseMatrix {
        let n = self.dofs.free_count();
        femu_sparse::csc::without_zeros_of((n, n), &self.col_ptr, &self.row_idx, values)
    }

    /// A diagonal matrix (the lumped mass) with the given diagonal.
    pub(crate) fn diagonal_matrix(&self, diag: Vec<f64>) -> SparseMatrix {
        let n = diag.len();
        SparseMatrix::new_csc((n, n), (0..=n).collect(), (0..n).collect(), diag)
    }

    /// The model's own damping, on the stiffness pattern: the viscous damping `C_d` of its
    /// bushings (`B1..B6`, formed as their stiffness with `B` for `K`), of its scalar dampers
    /// (a spring's viscous coefficient, formed likewise) and of the elements with a
    /// Rayleigh damping of their material (`alpha M_e + beta K_e`, [`Model::set_element_rayleigh`],
    /// `M_e` of `mass`), and the structural damping `K_4 = sum_e GE_e K_e` of its springs and
    /// bushings and of the elements with a `GE` of their material ([`Model::set_element_damping`])
    /// (Nastran's `B` and `K4` matrices of a direct frequency response; docs/MATH.md, "Frequency
    /// responses, directly"). Each is `None` when no element has it.
    ///
    /// # Errors
    /// The elements' own errors (as in assembly).
    pub fn dampers(&self, model: &Model, mass: MassKind) -> Result<Dampers, FemError> {
        use crate::structural::StructuralKind;
        let coords = model.mesh().coords();
        let (mut c, mut k4) = (None::<Vec<f64>>, None::<Vec<f64>>);
        let rayleigh = model.element_rayleigh();
        for s in model.structural() {
            if let Some(&(alpha, beta)) = rayleigh.get(&s.id) {
                let sm = s.matrices(coords, mass)?;
                let pts = structural_points(&self.dofs, &sm.parts);
                let v = c.get_or_insert_with(|| vec![0.0; self.nnz()]);
                self.scatter(&pts, |at, l, w| {
                    v[at] += w * (alpha * sm.m[l] + beta * sm.k[l]);
                });
            }
            let (ge, viscous) = match &s.kind {
                // a scalar damper: its viscous coefficient in place of the stiffness
                StructuralKind::Spring(sp) => (
                    sp.ge,
                    (sp.viscous != 0.0).then(|| {
                        let mut d = s.clone();
                        if let StructuralKind::Spring(ds) = &mut d.kind {
                            ds.k = sp.viscous;
                        }
                        d
                    }),
                ),
                StructuralKind::Bushing(b) => (
                    b.ge,
                    b.b.iter().any(|v| *v != 0.0).then(|| {
                        let mut d = s.clone();
                        if let StructuralKind::Bushing(db) = &mut d.kind {
                            db.k = b.b;
                        }
                        d
                    }),
                ),
                _ => (
                    model.element_damping().get(&s.id).copied().unwrap_or(0.0),
                    None,
                ),
            };
            if ge != 0.0 {
                let sm = s.matrices(coords, MassKind::Lumped)?;
                let pts = structural_points(&self.dofs, &sm.parts);
                let v = k4.get_or_insert_with(|| vec![0.0; self.nnz()]);
                self.scatter(&pts, |at, l, w| v[at] += ge * w * sm.k[l]);
            }
            if let Some(d) = viscous {
                let sm = d.matrices(coords, MassKind::Lumped)?;
                let pts = structural_points(&self.dofs, &sm.parts);
                let v = c.get_or_insert_with(|| vec![0.0; self.nnz()]);
                self.scatter(&pts, |at, l, w| v[at] += w * sm.k[l]);
            }
        }
        // the solids with a GE of their material
        let mesh = model.mesh();
        for (&id, &ge) in model.element_damping() {
            let Some(e) = mesh.element_index(id) else {
                continue;
            };
            let (ke, _) = element_matrices(model, e, MassKind::Lumped)?;
            let v = k4.get_or_insert_with(|| vec![0.0; self.nnz()]);
            self.scatter(mesh.element(e).nodes, |at, l, w| v[at] += ge * w * ke[l]);
        }
        // a direct structural damping matrix (K42GG)
        for e in model.direct_entries(crate::model::DirectMatrix::StructuralDamping) {
            let Some((pts, (r, col))) = direct_points(&self.dofs, e) else {
                continue;
            };
            let local = direct_block(3 * pts.len(), (r, col), e.value);
            let v = k4.get_or_insert_with(|| vec![0.0; self.nnz()]);
            self.scatter(&pts, |at, l, w| v[at] += w * local[l]);
        }
        // the solids with a Rayleigh damping of their material
        for (&id, &(alpha, beta)) in rayleigh {
            let Some(e) = mesh.element_index(id) else {
                continue;
            };
            let (ke, me) = element_matrices(model, e, mass)?;
            let v = c.get_or_insert_with(|| vec![0.0; self.nnz()]);
            self.scatter(mesh.element(e).nodes, |at, l, w| {
                v[at] += w * (alpha * me[l] + beta * ke[l]);
            });
        }
        Ok(Dampers {
            viscous: c.map(|v| self.without_zeros(&v)),
            structural: k4.map(|v| self.without_zeros(&v)),
        })
    }

    /// Assembles `K` and `M` for the model this pattern was built from (same mesh and constraints).
    ///
    /// # Errors
    /// [`FemError::NoMaterial`] for an element without material, [`FemError::InvertedElement`] for
    /// a non-positive Jacobian, [`FemError::LengthMismatch`] if the model does not match the pattern.
    pub fn assemble(&self, model: &Model, mass: MassKind) -> Result<SystemMatrices, FemError> {
        self.assemble_with(model, mass, false)
    }

    /// As [`Assembler::assemble`], with the nested-dissection analysis of `K`'s pattern made on
    /// one thread while the others assemble the values ([`SystemMatrices::analysis`]): for
    /// matrices that will be factored (an eigensolve, an updating run), whose solve then does no
    /// ordering of its own. On two threads the 199,200-DOF plate of the peer benchmark was
    /// assembled and analysed in 1.1 s instead of 0.5 + 0.8 s (docs/SCALING.md, "The analysis
    /// beside the assembly").
    ///
    /// # Errors
    /// As [`Assembler::assemble`]. A failed analysis is not an error here: the solve analyses
    /// again and reports it.
    pub fn assemble_analysed(
        &self,
        model: &Model,
        mass: MassKind,
    ) -> Result<SystemMatrices, FemError> {
        self.assemble_with(model, mass, true)
    }

    fn assemble_with(
        &self,
        model: &Model,
        mass: MassKind,
        analyse: bool,
    ) -> Result<SystemMatrices, FemError> {
        let n = self.dofs.free_count();
        let m = match mass {
            MassKind::Lumped if !self.lumped_on_pattern() => self.diagonal_matrix(vec![0.0; n]),
            MassKind::Lumped => self.pattern_matrix(vec![0.0; self.nnz()]),
            // made by assemble_into, without its zeros
            MassKind::Consistent => self.diagonal_matrix(Vec::new()),
        };
        let mut sys = SystemMatrices {
            k: self.pattern_matrix(vec![0.0; self.nnz()]),
            m,
            dofs: self.dofs.clone(),
            mass_kind: mass,
            rigid_body: NullSpaceHint::new(faer::Mat::zeros(n, 0)),
            analysis: None,
            checks: None,
        };
        // The ordering and symbolic analysis need the pattern only: one thread makes them while
        // the others assemble the values, and then check them for the eigensolver (the analysis
        // takes longer: 0.84 s against 0.5 s on the 199,200-DOF plate).
        if analyse {
            let (analysis, checks) = rayon::join(
                || self.analysis(Ordering::NestedDissection),
                || -> Result<Option<PencilChecks>, FemError> {
                    self.assemble_into(model, &mut sys)?;
                    Ok(PencilChecks::of(&sys.k, &sys.m).ok())
                },
            );
            // checks that failed are made again, and reported, by the solve
            sys.checks = checks?;
            // an analysis that failed (out of memory) is made again, and reported, by the solve
            sys.analysis = analysis.ok();
        } else {
            self.assemble_into(model, &mut sys)?;
        }
        // after assemble_into has checked that the model is the pattern's
        sys.rigid_body = NullSpaceHint::new(self.dofs.rigid_body_motions(model.mesh().coords()));
        Ok(sys)
    }

    /// Re-assembles into existing matrices of this pattern (new material values, same mesh and
    /// constraints): `K` (and a lumped `M`) in place, no new pattern. `sys.mass_kind` selects the
    /// mass. The consistent `M` is assembled on `K`'s pattern and stored anew without its exact
    /// zeros ([`femu_sparse::csc::without_zeros_of`]): its pattern is inside `K`'s, as the
    /// eigensolver and the expansions require, but may differ from the one `sys.m` had.
    ///
    /// # Errors
    /// As [`Assembler::assemble`], and [`FemError::LengthMismatch`] if `sys` is not on this pattern.
    pub fn assemble_into(&self, model: &Model, sys: &mut SystemMatrices) -> Result<(), FemError> {
        self.assemblies
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
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
        // the consistent mass is made anew (below), the lumped one written in place
        let m_len = match mass {
            MassKind::Consistent => sys.m.nnz(),
            MassKind::Lumped if self.lumped_on_pattern() => self.nnz(),
            MassKind::Lumped => n,
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
        // Zeroed in parallel, in contiguous pieces, before any element is added: new matrices'
        // values are memory the operating system provides on first touch, and touching it here
        // page by page costs less than the scattered first touches of the elements would (on 2
        // threads less than half: scattered page faults of two threads contend).
        let kv = sys.k.data_mut();
        kv.par_chunks_mut(ZERO_CHUNK).for_each(|c| c.fill(0.0));
        let ks = shared::SharedSlice::new(kv);
        // The consistent mass is assembled on the stiffness pattern, then stored without the
        // entries that are exactly zero (two thirds of them for solids: an element couples a
        // node's x only to x; docs/SCALING.md, "Memory").
        let mut on_pattern = Vec::new();
        let mv = match mass {
            MassKind::Consistent => {
                on_pattern = vec![0.0; self.nnz()];
                &mut on_pattern[..]
            }
            MassKind::Lumped => sys.m.data_mut(),
        };
        mv.par_chunks_mut(ZERO_CHUNK).for_each(|c| c.fill(0.0));
        let ms = shared::SharedSlice::new(mv);
        for color in &self.colors {
            color.par_iter().try_for_each_init(
                ElementBuffers::default,
                |buf, &ch| -> Result<(), FemError> {
                    for e in self.chunk(ch) {
                        let el = mesh.element(e);
                        mesh.element_coords(e, &mut buf.x);
                        let material = materials[e];
                        let rho = &material.density;
                        let nd = 3 * el.kind.num_nodes();
                        buf.ke.resize(nd * nd, 0.0);
                        kernel::element_stiffness_for(
                            el.kind,
                            model.formulation(e),
                            &buf.x,
                            material,
                            &mut buf.ke,
                        )
                        .map_err(bad_jacobian(el.id))?;
                        // SAFETY of the shared writes (see `shared`): chunks of one colour share no
                        // node, and an element writes only to the columns of its own nodes.
                        let plain = !self.dofs.has_dependents()
                            || !el.nodes.iter().any(|n| self.dofs.has_dependent(*n));
                        match mass {
                            MassKind::Consistent if plain => {
                                let nn = el.kind.num_nodes();
                                buf.me.resize(nn * nn, 0.0);
                                kernel::scalar_mass(el.kind, &buf.x, *rho, &mut buf.me)
                                    .map_err(bad_jacobian(el.id))?;
                                self.scatter_element(
                                    el.nodes,
                                    &buf.ke,
                                    Some(&buf.me),
                                    |p, v| ks.add(p, v),
                                    |p, v| ms.add(p, v),
                                );
                            }
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
                                if plain {
                                    self.scatter_element(
                                        el.nodes,
                                        &buf.ke,
                                        None,
                                        |p, v| ks.add(p, v),
                                        |_, _| {},
                                    );
                                } else {
                                    self.scatter(el.nodes, |p, l, w| ks.add(p, w * buf.ke[l]));
                                }
                                buf.ml.resize(el.kind.num_nodes(), 0.0);
                                kernel::lumped_mass(el.kind, &buf.x, *rho, &mut buf.ml)
                                    .map_err(bad_jacobian(el.id))?;
                                let ml = &buf.ml;
                                self.scatter_lumped(el.nodes, |a, _| ml[a], |p, v| ms.add(p, v));
                            }
                        }
                    }
                    Ok(())
                },
            )?;
        }
        // rigid masses: the 6x6 block of the node's translations and rotations (kept whole with
        // the lumped mass too, which is then on the stiffness pattern when one couples DOFs)
        for r in model.rigid_masses() {
            let Some(rp) = self.dofs.rotation_point(r.node) else {
                continue;
            };
            if mass == MassKind::Lumped && !self.lumped_on_pattern() {
                // the diagonal: the mass on the translations, the inertia on the rotations
                self.scatter_lumped(
                    &[r.node, rp],
                    |a, c| r.matrix[3 * a + c][3 * a + c],
                    |at, v| ms.add(at, v),
                );
                continue;
            }
            let local: Vec<f64> = r.matrix.iter().flatten().copied().collect();
            self.scatter(&[r.node, rp], |at, l, w| ms.add(at, w * local[l]));
        }
        // beams, rods, springs and bushings, on their nodes' translations and rotations
        for s in model.structural() {
            let sm = s.matrices(mesh.coords(), mass)?;
            let pts = structural_points(&self.dofs, &sm.parts);
            // whole with the consistent mass, and with a lumped mass on the pattern, which keeps
            // a scalar mass's coupling (the other elements' lumped masses are diagonal: the same
            // either way)
            if mass == MassKind::Lumped && !self.lumped_on_pattern() {
                self.scatter(&pts, |at, l, w| ks.add(at, w * sm.k[l]));
                let nd = sm.k.len().isqrt();
                self.scatter_lumped(
                    &pts,
                    |a, i| sm.m[(3 * a + i) * nd + 3 * a + i],
                    |at, v| ms.add(at, v),
                );
            } else {
                self.scatter(&pts, |at, l, w| {
                    ks.add(at, w * sm.k[l]);
                    ms.add(at, w * sm.m[l]);
                });
            }
        }
        // direct input matrices: each entry at (a, b) and (b, a) of its points' block
        for (which, add) in [
            (crate::model::DirectMatrix::Stiffness, &ks),
            (crate::model::DirectMatrix::Mass, &ms),
        ] {
            for e in model.direct_entries(which) {
                let Some((pts, (r, c))) = direct_points(&self.dofs, e) else {
                    continue;
                };
                if which == crate::model::DirectMatrix::Mass
                    && mass == MassKind::Lumped
                    && !self.lumped_on_pattern()
                {
                    // a diagonal entry (an off-diagonal one puts the lumped mass on the pattern)
                    self.scatter_lumped(
                        &pts,
                        |_, i| if i == r { e.value } else { 0.0 },
                        |at, v| add.add(at, v),
                    );
                    continue;
                }
                let local = direct_block(3 * pts.len(), (r, c), e.value);
                self.scatter(&pts, |at, l, w| {
                    if local[l] != 0.0 {
                        add.add(at, w * local[l]);
                    }
                });
            }
        }
        // point masses: the 3x3 block of their node (whole; a diagonal one through the lumped
        // mass's own path when that is diagonal)
        for p in model.point_masses() {
            if mass == MassKind::Lumped && !self.lumped_on_pattern() {
                self.scatter_lumped(&[p.node], |_, c| p.mass[c][c], |at, v| ms.add(at, v));
            } else {
                let local: Vec<f64> = p.mass.iter().flatten().copied().collect();
                self.scatter(&[p.node], |at, l, w| ms.add(at, w * local[l]));
            }
        }
        if mass == MassKind::Consistent {
            sys.m = self.without_zeros(&on_pattern);
        }
        Ok(())
    }
}

/// The damping a model's elements carry ([`Assembler::dampers`]), on free DOFs.
#[derive(Debug, Clone, Default)]
pub struct Dampers {
    /// Viscous damping `C_d` (N s/m) of the bushings' `B`.
    pub viscous: Option<SparseMatrix>,
    /// Structural damping `K_4 = sum_e GE_e K_e` (N/m) of the springs and bushings and of the
    /// elements with a `GE` ([`Model::set_element_damping`]).
    pub structural: Option<SparseMatrix>,
}

impl Dampers {
    /// Whether the model has any damper.
    pub fn any(&self) -> bool {
        self.viscous.is_some() || self.structural.is_some()
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
    kernel::element_stiffness_for(el.kind, model.formulation(e), &x, mat, &mut ke)
        .map_err(bad_jacobian(el.id))?;
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
    // (chunk colouring), so no two threads access one element.
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

/// The one-call assembly of a model, here with the assembler it uses (the model itself knows
/// nothing of assembly).
impl Model {
    /// Assembles `K` and `M` (free DOFs) in one call, with the analysis of `K`'s pattern made
    /// beside it for the solves that follow ([`Assembler::assemble_analysed`]); see [`Assembler`]
    /// to reuse the pattern.
    ///
    /// # Errors
    /// [`FemError::NoMaterial`], [`FemError::NoFreeDofs`] or an element geometry error.
    pub fn assemble(&self, mass: MassKind) -> Result<SystemMatrices, FemError> {
        Assembler::new(self)?.assemble_analysed(self, mass)
    }
}
