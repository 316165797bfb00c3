//! Subtree-parallel multifrontal `LDL^T` on faer's supernodal symbolic analysis
//! (docs/SCALING.md, "A subtree-parallel factorization").
//!
//! faer's own supernodal `LDL^T` is left-looking: supernode `s` gathers the updates of all its
//! descendants when it is factored, one supernode after another, with threads only inside the
//! dense kernels. Here each supernode's front is factored as soon as its children's are, and its
//! update matrix `U_s = F_bb - L_b D L_b^T` is handed to its parent (multifrontal). Supernodes in
//! disjoint subtrees of the elimination tree share nothing, so the subtrees run on different
//! threads; the fronts near the root, which the subtrees all wait for, use the threads inside
//! their dense kernels instead.
//!
//! The factor is written in femu's layout: each supernode's columns (the first `c` columns of its
//! front) in chunks of [`CHUNK`], which only [`solve`] reads (docs/SCALING.md, "The factor's
//! layout"). In exact arithmetic it is faer's factor: only the order of the additions differs.

use crate::cholesky::Inertia;
use crate::skinny::{MAX_RHS, Panel};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::ldlt::factor::{
    LdltError, LdltRegularization, cholesky_in_place, cholesky_in_place_scratch,
};
use faer::linalg::matmul::matmul;
use faer::linalg::matmul::triangular::{BlockStructure, matmul as triangular_matmul};
use faer::linalg::triangular_solve::{
    solve_unit_lower_triangular_in_place, solve_unit_upper_triangular_in_place,
};
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::SparseColMatRef;
use faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky;
use faer::{Accum, Mat, MatMut, MatRef, Par};
use rayon::prelude::*;

mod solve;
pub(crate) use solve::solve;
use solve::*;

/// A front whose own work is above this many flops uses every thread: faer's dense `LDL^T` of
/// its pivot block gets them all, its triangular solve's rows and its update panels are shared
/// between them (`Fronts::front`). Below it, the threading overhead outweighs the gain; 5e7
/// instead measured no faster on the 50k and 200k models (docs/SCALING.md, "A subtree-parallel
/// factorization").
const PARALLEL_FRONT_FLOPS: f64 = 2e8;

/// Before a stored factorization's front above this many flops (outside the sequential subtrees,
/// so a few fronts near the root) the allocator's free memory is given back to the system
/// ([`release_free_memory`]): the subtrees below have freed their update matrices into glibc's
/// arenas (150-230 MB free there on the 209,088-DOF block), and these fronts' own update matrices
/// are the factorization's peak. Peak of that solve 3,095-3,109 MB -> 2,952-2,973 MB, the
/// factorization's time unchanged within its spread. Memory given back comes back as fresh pages,
/// a page fault each: on the 47,628-DOF plate, whose largest fronts are of 2e8-4e8 flops and
/// whose peak is its iteration's, trims before them took the run's factorization from 35 to
/// 60 thousand faults and the two factorizations from 0.411 to 0.446 s (medians of eight
/// alternated pairs) for a peak 5 MB lower; the 52,920-DOF block's eight and the 199,200-DOF
/// plate's ten largest fronts are above 1e9 (docs/SCALING.md, "Memory the allocator keeps").
const TRIM_FRONT: f64 = 1e9;

/// Columns of an update matrix computed at once (`Fronts::front`): the scratch is `b x 256`,
/// not `b x b`.
const UPDATE_PANEL: usize = 256;

/// Columns of a stored factor kept together (a *chunk*, docs/SCALING.md "The factor's layout"):
/// a supernode's columns are stored in chunks of this many, each chunk column-major from its
/// first pivot's row down, so that of a diagonal block only the chunks' own `64 x 64` triangles
/// are stored square. faer's layout stores every diagonal block square: 15 % of the 209,088-DOF
/// block's factor (42.8 million of 281.1 million values) and 12 % of the 199,200-DOF plate's were
/// their unread upper triangles; in chunks of 64 they are 3.9 and 3.4 million. Chunks of 128 or
/// 256 would leave 6.3 or 9.6 million on the block and 5.7 or 7.1 million on the plate, whose
/// supernodes are smaller.
pub(crate) const CHUNK: usize = 64;

/// Columns of a large front factored at once ([`Fronts::super_panels`]): a multiple of [`CHUNK`],
/// the inner dimension of the updates of the later chunks (GEMMs of `rows x 256` by `256 x 64`).
const SUPER_PANEL: usize = 256;

/// A stored front with more pivots than [`CHUNK`] is factored in a square scratch copy and then
/// written into its chunks when it has at most this many values (`(c + b) c`), else chunk by chunk
/// in place ([`Fronts::super_panels`]): a scratch copy of the 209,088-DOF block's root (6,435
/// pivots) would be 331 MB at the factorization's peak.
const SCRATCH_FRONT: usize = 1 << 21;

/// The sizes a factorization is organised by: femu's ([`Tuning::DEFAULT`]), or smaller ones with
/// which the tests take every path on small matrices.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Tuning {
    /// [`CHUNK`]
    pub(crate) chunk: usize,
    /// [`SUPER_PANEL`] (a multiple of `chunk`)
    pub(crate) super_panel: usize,
    /// [`SCRATCH_FRONT`]
    pub(crate) scratch_front: usize,
    /// [`PARALLEL_FRONT_FLOPS`]
    pub(crate) parallel_front: f64,
}

impl Tuning {
    /// femu's sizes.
    pub(crate) const DEFAULT: Tuning = Tuning {
        chunk: CHUNK,
        super_panel: SUPER_PANEL,
        scratch_front: SCRATCH_FRONT,
        parallel_front: PARALLEL_FRONT_FLOPS,
    };
}

/// Where chunk `q` of a supernode with `c` pivots and `b` rows below them starts in its storage
/// (chunks of `w` columns: each earlier chunk `q'` holds `w` columns of `c + b - q' w` rows).
fn chunk_start(c: usize, b: usize, w: usize, q: usize) -> usize {
    if q == 0 {
        0
    } else {
        w * (q * (c + b) - w * q * (q - 1) / 2)
    }
}

/// The values of a supernode with `c` pivots and `b` rows below them stored in chunks of `w`.
fn chunked_len(c: usize, b: usize, w: usize) -> usize {
    if c == 0 {
        return 0;
    }
    let last = (c - 1) / w;
    chunk_start(c, b, w, last) + (c + b - last * w) * (c - last * w)
}

/// A stored factor's layout: each supernode `s`'s values at `ptr[s]..ptr[s + 1]`, its columns in
/// chunks of `width` ([`CHUNK`]: femu's factorization; `usize::MAX`: one chunk, faer's layout).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Layout<'a> {
    pub(crate) width: usize,
    pub(crate) ptr: &'a [usize],
}

/// A supernode's columns of the factor in chunks of `w` ([`Layout`]) while its front is
/// assembled and factored: column `j` is held from front row `(j / w) w` down.
struct Chunks<'a> {
    data: &'a mut [f64],
    c: usize,
    b: usize,
    w: usize,
}

impl Chunks<'_> {
    /// Column `j` and the front row its first entry is in.
    fn col(&mut self, j: usize) -> (&mut [f64], usize) {
        let q = j / self.w;
        let base = q * self.w;
        let rows = self.c + self.b - base;
        let at = chunk_start(self.c, self.b, self.w, q) + (j - base) * rows;
        (&mut self.data[at..at + rows], base)
    }

    /// The chunks from `first` on, each a disjoint piece of the data, with its index.
    fn from(&mut self, first: usize) -> Vec<(usize, &mut [f64])> {
        let (c, b, w) = (self.c, self.b, self.w);
        let (_, mut rest) = self.data.split_at_mut(chunk_start(c, b, w, first));
        let mut pieces = Vec::new();
        for r in first..c.div_ceil(w) {
            let (piece, tail) = rest.split_at_mut((c + b - r * w) * w.min(c - r * w));
            pieces.push((r, piece));
            rest = tail;
        }
        pieces
    }
}

/// Where column `j` of a packed lower triangle of order `b` starts: column `j` holds its rows
/// `j..b`, after the `b - i` entries of every column `i < j`. An update matrix is stored so,
/// half the memory of a square one.
fn packed_start(j: usize, b: usize) -> usize {
    j * b - j * j.saturating_sub(1) / 2
}

/// Buffers a task keeps for reuse (`Workspace::give`).
const POOL: usize = 2;

/// A subtree with less than `1 / SUBTREE_SHARE` of the total work per thread runs as one
/// sequential task: enough tasks to balance two threads, few enough that a task's scratch
/// (one index per row of the matrix) is negligible.
const SUBTREE_SHARE: f64 = 8.0;

/// The supernodal elimination tree of a symbolic analysis with a postorder of it: the subtree
/// of `s` is `post[first[s]..=pos[s]]`, each child's subtree before its parent. (faer numbers
/// the supernodes in a topological order, not always in postorder.)
#[derive(Debug)]
pub(crate) struct Tree {
    child_ptr: Vec<usize>,
    child: Vec<usize>,
    roots: Vec<usize>,
    post: Vec<usize>,
    pos: Vec<usize>,
    first: Vec<usize>,
    own_flops: Vec<f64>,
    subtree_flops: Vec<f64>,
    total_flops: f64,
    /// [`Tree::places`], made by the first solve
    places: std::sync::OnceLock<Vec<u32>>,
    /// the sizes the factorization is organised by (smaller in the tests, so that small
    /// matrices take every path)
    tuning: Tuning,
    /// each supernode's values in femu's stored factor ([`Layout`]), in supernode order
    val_ptr: Vec<usize>,
}

impl Tree {
    /// The tree of `s`, or `None` when a supernode's parent does not follow it (not an
    /// elimination tree: the caller keeps faer's factorization).
    pub(crate) fn new(s: &SymbolicSupernodalCholesky<usize>) -> Option<Self> {
        Self::tuned(s, Tuning::DEFAULT)
    }

    /// [`Tree::new`] with other sizes than femu's ([`Tuning`]).
    pub(crate) fn tuned(s: &SymbolicSupernodalCholesky<usize>, tuning: Tuning) -> Option<Self> {
        let chunk = tuning.chunk;
        assert!(
            chunk > 0 && tuning.super_panel.is_multiple_of(chunk) && tuning.super_panel > 0,
            "super panels of whole chunks"
        );
        let ns = s.n_supernodes();
        let (begin, end) = (s.supernode_begin(), s.supernode_end());
        let (row_ptr, rows, below) = (s.col_ptr_for_row_idx(), s.row_idx(), s.nnz_per_super());
        let mut supernode_of = vec![0; s.nrows()];
        for k in 0..ns {
            supernode_of[begin[k]..end[k]].fill(k);
        }
        let mut parent = vec![usize::MAX; ns];
        let mut own_flops = vec![0.0; ns];
        let mut count = vec![0usize; ns + 1];
        let mut roots = Vec::new();
        for k in 0..ns {
            let (c, b) = (end[k] - begin[k], below[k]);
            own_flops[k] = front_flops(c, b);
            if b == 0 {
                roots.push(k);
                continue;
            }
            let p = supernode_of[rows[row_ptr[k]]];
            if p <= k {
                return None;
            }
            parent[k] = p;
            count[p + 1] += 1;
        }
        let mut subtree_flops = own_flops.clone();
        for k in 0..ns {
            // children come before their parent: their sums are complete here
            if parent[k] != usize::MAX {
                subtree_flops[parent[k]] += subtree_flops[k];
            }
            count[k + 1] += count[k];
        }
        let child_ptr = count.clone();
        let mut child = vec![0; child_ptr[ns]];
        for k in 0..ns {
            if parent[k] != usize::MAX {
                let p = parent[k];
                child[count[p]] = k;
                count[p] += 1;
            }
        }
        // postorder by depth-first search, children in increasing order
        let (mut post, mut pos, mut first) = (Vec::with_capacity(ns), vec![0; ns], vec![0; ns]);
        let mut walk: Vec<(usize, usize)> = Vec::new();
        for &r in &roots {
            walk.push((r, child_ptr[r]));
            first[r] = post.len();
            while let Some((k, next)) = walk.last_mut() {
                let k = *k;
                if *next < child_ptr[k + 1] {
                    let c = child[*next];
                    *next += 1;
                    first[c] = post.len();
                    walk.push((c, child_ptr[c]));
                } else {
                    pos[k] = post.len();
                    post.push(k);
                    walk.pop();
                }
            }
        }
        let total_flops = own_flops.iter().sum();
        let mut val_ptr = Vec::with_capacity(ns + 1);
        val_ptr.push(0);
        for k in 0..ns {
            let len = chunked_len(end[k] - begin[k], below[k], chunk);
            val_ptr.push(val_ptr[k] + len);
        }
        Some(Self {
            child_ptr,
            child,
            roots,
            post,
            pos,
            first,
            own_flops,
            subtree_flops,
            total_flops,
            places: std::sync::OnceLock::new(),
            tuning,
            val_ptr,
        })
    }

    /// The values of femu's stored factor ([`Layout`]).
    pub(crate) fn len_val(&self) -> usize {
        self.val_ptr.last().copied().unwrap_or(0)
    }

    /// femu's stored factor's layout: chunks of [`CHUNK`] columns.
    pub(crate) fn layout(&self) -> Layout<'_> {
        Layout {
            width: self.tuning.chunk,
            ptr: &self.val_ptr,
        }
    }

    /// For every row of every supernode's pattern (faer's `row_idx` layout), its place in its
    /// parent's front: `r - begin` for the parent's pivot rows, `c + i` for row `i` of the
    /// parent's pattern. The solves move each child's rows to and from its parent's front by
    /// them; found once, on the first solve, instead of through a map of all rows at every front
    /// of every pass (the map's zeroing and look-ups were 7-8 % of a pass on the 199,200-DOF
    /// plate). One `u32` per row index of the analysis, held with it.
    fn places(&self, s: &SymbolicSupernodalCholesky<usize>) -> &[u32] {
        self.places.get_or_init(|| {
            let (begin, end) = (s.supernode_begin(), s.supernode_end());
            let (row_ptr, rows, below) = (s.col_ptr_for_row_idx(), s.row_idx(), s.nnz_per_super());
            let mut places = vec![0u32; rows.len()];
            let mut map = vec![0u32; s.nrows()];
            let place = |i: usize| u32::try_from(i).expect("a front of fewer than 2^32 rows");
            for p in 0..s.n_supernodes() {
                let c = end[p] - begin[p];
                let pattern = &rows[row_ptr[p]..row_ptr[p] + below[p]];
                for (i, &r) in pattern.iter().enumerate() {
                    map[r] = place(c + i);
                }
                for &child in self.children(p) {
                    for q in row_ptr[child]..row_ptr[child] + below[child] {
                        let r = rows[q];
                        places[q] = if r < end[p] {
                            place(r - begin[p])
                        } else {
                            map[r]
                        };
                    }
                }
            }
            places
        })
    }

    fn children(&self, k: usize) -> &[usize] {
        &self.child[self.child_ptr[k]..self.child_ptr[k + 1]]
    }

    /// A subtree with at most this much work runs as one sequential task on `threads` threads.
    fn sequential_below(&self, threads: usize) -> f64 {
        if threads > 1 {
            self.total_flops / (SUBTREE_SHARE * threads as f64)
        } else {
            f64::INFINITY
        }
    }

    /// `buf` cut into one slot per supernode, `len(k)` values each, laid out in supernode order,
    /// and the slots listed in the tree's postorder: every subtree's slots are then one
    /// contiguous run, handed to the task that works on it.
    fn postorder_slots<'b>(
        &self,
        mut buf: &'b mut [f64],
        len: impl Fn(usize) -> usize,
    ) -> Vec<&'b mut [f64]> {
        let mut by_index: Vec<Option<&'b mut [f64]>> = Vec::with_capacity(self.pos.len());
        for k in 0..self.pos.len() {
            let (slot, tail) = buf.split_at_mut(len(k));
            by_index.push(Some(slot));
            buf = tail;
        }
        self.post
            .iter()
            .map(|&k| {
                by_index[k]
                    .take()
                    .expect("each supernode once in the postorder")
            })
            .collect()
    }

    /// `leaf(i, roots[i], its slots, its first postorder position)` for the subtrees of the
    /// siblings `roots` (consecutive in the postorder; `slots` theirs from position `base` on), in
    /// parallel halves; the results in the order of `roots`.
    fn forest<T: Send>(
        &self,
        roots: &[usize],
        slots: &mut [&mut [f64]],
        base: usize,
        leaf: &(impl Fn(usize, usize, &mut [&mut [f64]], usize) -> T + Sync),
    ) -> Vec<T> {
        self.forest_from(0, roots, slots, base, leaf)
    }

    fn forest_from<T: Send>(
        &self,
        offset: usize,
        roots: &[usize],
        slots: &mut [&mut [f64]],
        base: usize,
        leaf: &(impl Fn(usize, usize, &mut [&mut [f64]], usize) -> T + Sync),
    ) -> Vec<T> {
        match roots {
            [] => Vec::new(),
            [k] => vec![leaf(offset, *k, slots, base)],
            _ => {
                let mid = roots.len() / 2;
                let cut = self.first[roots[mid]];
                let (left, right) = slots.split_at_mut(cut - base);
                let (mut l, r) = rayon::join(
                    || self.forest_from(offset, &roots[..mid], left, base, leaf),
                    || self.forest_from(offset + mid, &roots[mid..], right, cut, leaf),
                );
                l.extend(r);
                l
            }
        }
    }
}

/// Flops of one front with `c` pivots and `b` rows below them: the classical count
/// `sum_j (b_j^2 + 2 b_j)` of `SymbolicFactor::flops` over its columns.
fn front_flops(c: usize, b: usize) -> f64 {
    (0..c)
        .map(|j| {
            let r = (c - 1 - j + b) as f64;
            r * r + 2.0 * r
        })
        .sum()
}

/// The matrix a factorization reads, column by column in the analysis's (permuted) order.
pub(crate) enum Entries<'a> {
    /// A permuted copy of its lower triangle (row indices unsorted).
    Lower(SparseColMatRef<'a, usize, f64>),
    /// `sum_t scale_t A_t` of symmetric matrices stored with both triangles in the original order
    /// (each pattern inside the analysed one), read where they are: column `j` of the permuted
    /// matrix's lower triangle is column `fwd[j]` of each `A_t` at the rows `i` with
    /// `inv[i] >= j`. No copy of the matrix, no values of the sum are ever held
    /// (`K - sigma M` of an eigensolve: docs/SCALING.md, "Memory").
    Sum {
        /// `(A_t, scale_t)`
        terms: Vec<(&'a crate::SparseMatrix, f64)>,
        /// the ordering, `fwd[new] = old` and `inv[old] = new` (`None`: the identity)
        perm: Option<(&'a [usize], &'a [usize])>,
    },
}

impl Entries<'_> {
    /// `add(i, v)` for the entries `(i, j)` with `i >= j` of column `j` (permuted indices); the
    /// entries of a sum come one term after another.
    fn lower_of_col(&self, j: usize, mut add: impl FnMut(usize, f64)) {
        match self {
            Entries::Lower(a) => {
                for (i, &v) in a.row_idx_of_col(j).zip(a.val_of_col(j)) {
                    if i >= j {
                        add(i, v);
                    }
                }
            }
            Entries::Sum { terms, perm } => {
                let old = perm.map_or(j, |(fwd, _)| fwd[j]);
                for (a, scale) in terms {
                    let ptr = a.indptr();
                    let range = ptr.outer_inds_sz(old);
                    let (rows, values) = (&a.indices()[range.clone()], &a.data()[range]);
                    for (&r, &v) in rows.iter().zip(values) {
                        let i = perm.map_or(r, |(_, inv)| inv[r]);
                        if i >= j {
                            add(i, scale * v);
                        }
                    }
                }
            }
        }
    }
}

struct Fronts<'a> {
    tree: &'a Tree,
    symbolic: &'a SymbolicSupernodalCholesky<usize>,
    /// the matrix
    a: &'a Entries<'a>,
    /// whether the factor is kept (else each front's columns are scratch: the inertia only)
    store: bool,
    /// a Sturm count's buffers kept between its tasks ([`Recycled`])
    recycled: Option<Recycled>,
    sequential_below: f64,
    threads: usize,
}

/// The numeric `LDL^T` of the matrix `a` on up to `threads` threads, with the
/// signs of its pivots. With `values` (femu's layout, [`Tree::layout`], zeroed) the factor is
/// stored there; without, only the signs are kept and no factor is ever held: the memory of one front
/// at a time per thread (a Sturm count).
///
/// # Errors
/// The permuted index of an exactly zero pivot.
pub(crate) fn factor(
    tree: &Tree,
    symbolic: &SymbolicSupernodalCholesky<usize>,
    a: &Entries<'_>,
    values: Option<&mut [f64]>,
    threads: usize,
) -> Result<Inertia, usize> {
    let store = values.is_some();
    // each supernode's slot of the factor (empty when not stored), in the tree's postorder
    let mut empty = [];
    let mut slots = match values {
        Some(values) => {
            assert_eq!(values.len(), tree.len_val(), "values in femu's layout");
            let ptr = &tree.val_ptr;
            tree.postorder_slots(values, |k| ptr[k + 1] - ptr[k])
        }
        None => tree.postorder_slots(&mut empty, |_| 0),
    };
    let fronts = Fronts {
        tree,
        symbolic,
        a,
        store,
        recycled: (!store).then(|| Recycled::new(symbolic.len_val() / RECYCLED_SHARE)),
        sequential_below: tree.sequential_below(threads),
        threads,
    };
    fronts
        .forest(&tree.roots, &mut slots, 0)
        .map(|(_, signs)| signs)
}

impl Fronts<'_> {
    /// The subtrees of the siblings `roots` (consecutive in the postorder), in parallel halves;
    /// their update matrices in order and their pivots' signs. `slots` are the subtrees' slots,
    /// from postorder position `base` on.
    fn forest(
        &self,
        roots: &[usize],
        slots: &mut [&mut [f64]],
        base: usize,
    ) -> Result<(Vec<Vec<f64>>, Inertia), usize> {
        let mut updates = Vec::with_capacity(roots.len());
        let mut signs = Inertia::NONE;
        for r in self.tree.forest(roots, slots, base, &|_, k, slots, base| {
            self.subtree(k, slots, base)
        }) {
            let (u, sg) = r?;
            updates.push(u);
            signs = signs.merged(sg);
        }
        Ok((updates, signs))
    }

    /// Factors the subtree of `k` (its slots start at postorder position `base`); returns `U_k`
    /// and the subtree's pivots' signs.
    fn subtree(
        &self,
        k: usize,
        slots: &mut [&mut [f64]],
        base: usize,
    ) -> Result<(Vec<f64>, Inertia), usize> {
        let tree = self.tree;
        let sequential = tree.subtree_flops[k] <= self.sequential_below;
        let mut work = Workspace::new(self.symbolic.nrows(), sequential, self.recycled.as_ref());
        if sequential {
            let mut stack: Vec<Vec<f64>> = Vec::new();
            let mut signs = Inertia::NONE;
            for (slot, &s) in slots.iter_mut().zip(&tree.post[base..=tree.pos[k]]) {
                let kids = tree.children(s).len();
                let updates = stack.split_off(stack.len() - kids);
                let (u, sg) = self.front(s, slot, updates, Par::Seq, &mut work)?;
                stack.push(u);
                signs = signs.merged(sg);
            }
            return Ok((stack.pop().unwrap_or_default(), signs));
        }
        let (below, own) = slots.split_at_mut(tree.pos[k] - base);
        let (updates, below_signs) = self.forest(tree.children(k), below, base)?;
        if self.store && tree.own_flops[k] > TRIM_FRONT {
            release_free_memory();
        }
        let par = if self.threads > 1 && tree.own_flops[k] > tree.tuning.parallel_front {
            Par::rayon(self.threads)
        } else {
            Par::Seq
        };
        let (u, signs) = self.front(k, own[0], updates, par, &mut work)?;
        work.recycle();
        Ok((u, below_signs.merged(signs)))
    }

    /// Assembles and factors the front of supernode `k` into `own` (its columns of `L` in femu's
    /// layout, [`Tree::layout`], zeroed; empty when the factor is not stored: then into scratch),
    /// adding the children's update matrices `updates`; returns its own update matrix `U_k` (its
    /// lower triangle, packed by columns: [`packed_start`]) and the signs of its pivots.
    ///
    /// The children's columns that land in the front's pivots' columns are added before the
    /// pivots are factored; `U_k = -L_b D L_b^T` is then written whole (no cleared buffer) and
    /// the children's columns that land in it added after: the parts of `F_bb` play no part in
    /// the pivots' factorization (docs/SCALING.md, "Scratch not cleared").
    ///
    /// A front of at most [`CHUNK`] pivots is one chunk: it is factored where it is stored. A
    /// larger one is factored in a square scratch copy written into its chunks after, or, above
    /// [`SCRATCH_FRONT`] values, [`SUPER_PANEL`] columns at a time in its chunks
    /// ([`Fronts::super_panels`]).
    fn front(
        &self,
        k: usize,
        own: &mut [f64],
        updates: Vec<Vec<f64>>,
        par: Par,
        work: &mut Workspace,
    ) -> Result<(Vec<f64>, Inertia), usize> {
        let s = self.symbolic;
        let (start, end) = (s.supernode_begin()[k], s.supernode_end()[k]);
        let pattern = |k: usize| {
            let p = s.col_ptr_for_row_idx()[k];
            &s.row_idx()[p..p + s.nnz_per_super()[k]]
        };
        let rows = pattern(k);
        let (c, b) = (end - start, rows.len());
        for (i, &r) in rows.iter().enumerate() {
            work.map[r] = c + i;
        }
        // written whole by the front's update (`U = -L_b D L_b^T`), the children's parts added after
        let mut u = work.take_uncleared(b * (b + 1) / 2);
        let chunk = self.tree.tuning.chunk;
        let in_chunks = self.store && c > chunk && (c + b) * c > self.tree.tuning.scratch_front;
        let copied = self.store && c > chunk && !in_chunks;
        let (mut panel, mut scratch) = (Vec::new(), Vec::new());
        if copied {
            scratch = std::mem::take(&mut work.front);
            Workspace::refill(&mut scratch, (c + b) * c, None);
        }
        let front: &mut [f64] = if !self.store {
            panel = work.take((c + b) * c);
            &mut panel[..]
        } else if copied {
            &mut scratch[..]
        } else {
            &mut *own
        };
        let mut cols = Chunks {
            data: front,
            c,
            b,
            w: if in_chunks { chunk } else { usize::MAX },
        };
        for j in start..end {
            let (col, base) = cols.col(j - start);
            let map = &work.map;
            self.a.lower_of_col(j, |i, v| {
                col[if i < end { i - start } else { map[i] } - base] += v;
            });
        }
        // extend-add, the pivots' columns first: each child's pattern lies in this front, in
        // the same order, so a column of a child's update lands in one column of the front, from
        // its diagonal down
        self.extend_add(k, &updates, work, |lc, locs, from| {
            if lc < c {
                let (to, base) = cols.col(lc);
                for (&li, &v) in locs.iter().zip(from) {
                    to[li - base] += v;
                }
            }
        });
        let signs = if in_chunks {
            self.super_panels(start, own, c, b, &mut u, par, work)?
        } else {
            let square = if copied {
                &mut scratch[..]
            } else if self.store {
                &mut *own
            } else {
                &mut panel[..]
            };
            let signs = self.dense(
                start,
                MatMut::from_column_major_slice_mut(square, c + b, c),
                &mut u,
                par,
                work,
            );
            if copied && signs.is_ok() {
                // into the chunks: column `j` from front row `(j / chunk) chunk` down
                let mut to = Chunks {
                    data: own,
                    c,
                    b,
                    w: chunk,
                };
                for (j, from) in scratch.chunks_exact(c + b).enumerate() {
                    let (col, base) = to.col(j);
                    col.copy_from_slice(&from[base..]);
                }
                work.front = scratch;
            }
            signs?
        };
        // the children's parts of the update matrix, added to `-L_b D L_b^T`
        self.extend_add(k, &updates, work, |lc, locs, from| {
            if lc >= c {
                let j = lc - c;
                let to = &mut u[packed_start(j, b)..packed_start(j + 1, b)];
                for (&li, &v) in locs.iter().zip(from) {
                    to[li - lc] += v;
                }
            }
        });
        for update in updates {
            work.give(update);
        }
        if !self.store {
            work.give(panel);
        }
        Ok((u, signs))
    }

    /// Hands each column of the children's update matrices `updates` (in the order of `k`'s
    /// children) to `add(lc, rows, values)`: the front column `lc` it lands in, the front rows of
    /// its entries (from its diagonal down, increasing) and their values. Rows map through
    /// `work.map` as [`Fronts::front`] set it for `k`.
    fn extend_add(
        &self,
        k: usize,
        updates: &[Vec<f64>],
        work: &mut Workspace,
        mut add: impl FnMut(usize, &[usize], &[f64]),
    ) {
        let s = self.symbolic;
        let (start, end) = (s.supernode_begin()[k], s.supernode_end()[k]);
        for (&child, update) in self.tree.children(k).iter().zip(updates) {
            let p = s.col_ptr_for_row_idx()[child];
            let rows = &s.row_idx()[p..p + s.nnz_per_super()[child]];
            let bc = rows.len();
            work.locs.clear();
            work.locs.extend(
                rows.iter()
                    .map(|&r| if r < end { r - start } else { work.map[r] }),
            );
            for (jj, &lc) in work.locs.iter().enumerate() {
                add(
                    lc,
                    &work.locs[jj..],
                    &update[packed_start(jj, bc)..packed_start(jj + 1, bc)],
                );
            }
        }
    }

    /// The dense work of a front held square (`l`, `c + b` rows, `c` columns, assembled):
    /// `L_11 D L_11^T` in its top, `L_b` below it (in a Sturm count, which stores no factor,
    /// `W = L_b D` is left there unscaled), `U = -L_b D L_b^T` written into `u` (the children's
    /// parts are added after, [`Fronts::front`]); the signs of the pivots. `start` is the first
    /// pivot's index (for a zero pivot's error).
    fn dense(
        &self,
        start: usize,
        l: MatMut<'_, f64>,
        u: &mut [f64],
        par: Par,
        work: &mut Workspace,
    ) -> Result<Inertia, usize> {
        let c = l.ncols();
        let b = l.nrows() - c;
        let parallel = !matches!(par, Par::Seq);
        let (mut top, mut bottom) = l.split_at_row_mut(c);
        let mut mem = MemBuffer::new(cholesky_in_place_scratch::<f64>(c, par, Default::default()));
        cholesky_in_place(
            top.rb_mut(),
            LdltRegularization::default(),
            par,
            MemStack::new(&mut mem),
            Default::default(),
        )
        .map_err(|LdltError::ZeroPivot { index }| start + index)?;
        let mut signs = Inertia::NONE;
        for j in 0..c {
            signs.count(top[(j, j)]);
            for i in 0..j {
                top[(i, j)] = 0.0;
            }
        }
        if b > 0 {
            // W = L_b D = A_b L^-T in the bottom rows; U -= W L_b^T by panels of columns; then
            // L_b = W D^-1 in place. On a front near the root the threads share the bottom
            // rows, and then the panels, each thread with one-thread kernels: faer's own two
            // threads inside each kernel did 78 GFLOP/s on the triangular solve of the
            // 209,088-DOF block's front of 1,824 x 5,148 where the rows split between two
            // one-thread solves did 98, and 77 on a panel's GEMM where two one-thread ones do
            // about 100 (docs/SCALING.md, "A subtree-parallel factorization").
            let top = top.rb();
            self.solve_rows(top, bottom.rb_mut(), parallel);
            let d_inv: Vec<f64> = (0..c).map(|j| top[(j, j)].recip()).collect();
            update_matrix(bottom.rb(), &d_inv, u, true, parallel, work);
            if !self.store {
                // a Sturm count keeps no factor: `L_b` itself is never read
                return Ok(signs);
            }
            for (j, d) in d_inv.iter().enumerate() {
                column_mut(bottom.rb_mut(), j)
                    .iter_mut()
                    .for_each(|x| *x *= d);
            }
        }
        Ok(signs)
    }

    /// `rows <- rows L^-T` for the unit lower triangle of `top`: the rows shared between the
    /// threads when `parallel`, each part by a one-thread solve.
    fn solve_rows(&self, top: MatRef<'_, f64>, mut rows: MatMut<'_, f64>, parallel: bool) {
        let solve = |rows: MatMut<'_, f64>| {
            solve_unit_lower_triangular_in_place(top, rows, Par::Seq);
        };
        if parallel {
            crate::cholesky::split_columns(rows.rb_mut().transpose_mut(), self.threads, &solve);
        } else {
            solve(rows.transpose_mut());
        }
    }

    /// The dense work of a large stored front in its chunks (`own`, femu's layout, assembled),
    /// [`SUPER_PANEL`] columns at a time (right-looking): the panel's columns are copied into a
    /// scratch of their rows, their pivot block factored and the rows below solved (as
    /// [`Fronts::dense`] does for a whole front); then every later chunk is updated by one GEMM
    /// (`rows x 256` by `256 x 64`, the chunks on different threads near the root), `U` by the
    /// panel's bottom rows, and the panel, scaled to `L`, written back. No square copy of the
    /// front is held: the scratch is the panel's `c + b - j0` rows by 256.
    #[allow(clippy::too_many_arguments)]
    fn super_panels(
        &self,
        start: usize,
        own: &mut [f64],
        c: usize,
        b: usize,
        u: &mut [f64],
        par: Par,
        work: &mut Workspace,
    ) -> Result<Inertia, usize> {
        let (w, width) = (self.tree.tuning.chunk, self.tree.tuning.super_panel);
        let parallel = !matches!(par, Par::Seq);
        let mut signs = Inertia::NONE;
        let mut scratch = std::mem::take(&mut work.front);
        let mut chunks = Chunks { data: own, c, b, w };
        for j0 in (0..c).step_by(width) {
            let wj = width.min(c - j0);
            let rows = c + b - j0;
            // each column from its diagonal down: above it, nothing is read (the pivot block's
            // factorization reads its lower triangle; its upper is zeroed below)
            let panel = Workspace::room(&mut scratch, rows * wj, None);
            for (jj, to) in panel.chunks_exact_mut(rows).enumerate() {
                let (col, base) = chunks.col(j0 + jj);
                to[jj..].copy_from_slice(&col[j0 + jj - base..]);
            }
            let sm = MatMut::from_column_major_slice_mut(panel, rows, wj);
            let (mut top, mut below) = sm.split_at_row_mut(wj);
            let mut mem = MemBuffer::new(cholesky_in_place_scratch::<f64>(
                wj,
                Par::Seq,
                Default::default(),
            ));
            let factored = cholesky_in_place(
                top.rb_mut(),
                LdltRegularization::default(),
                Par::Seq,
                MemStack::new(&mut mem),
                Default::default(),
            );
            if let Err(LdltError::ZeroPivot { index }) = factored {
                work.front = scratch;
                return Err(start + j0 + index);
            }
            for j in 0..wj {
                signs.count(top[(j, j)]);
                for i in 0..j {
                    top[(i, j)] = 0.0;
                }
            }
            if rows > wj {
                let top = top.rb();
                self.solve_rows(top, below.rb_mut(), parallel);
                let d_inv: Vec<f64> = (0..wj).map(|j| top[(j, j)].recip()).collect();
                let d_inv = &d_inv[..];
                let wr = below.rb();
                if j0 + wj < c {
                    let targets = chunks.from((j0 + wj) / w);
                    let later = |(r, t): (usize, &mut [f64]), lt: &mut Vec<f64>| {
                        let (cr, rr) = (w.min(c - r * w), c + b - r * w);
                        // the chunk's rows in the panel's rows below its pivots
                        let off = r * w - (j0 + wj);
                        let lt = Workspace::room(lt, wj * cr, None);
                        let mut ltm = MatMut::from_column_major_slice_mut(lt, wj, cr);
                        ltm.copy_from(wr.subrows(off, cr).transpose());
                        for jj in 0..cr {
                            let col = column_mut(ltm.rb_mut(), jj);
                            col.iter_mut().zip(d_inv).for_each(|(x, d)| *x *= d);
                        }
                        matmul(
                            MatMut::from_column_major_slice_mut(t, rr, cr),
                            Accum::Add,
                            wr.subrows(off, rr),
                            ltm.rb(),
                            -1.0,
                            Par::Seq,
                        );
                    };
                    if parallel {
                        targets
                            .into_par_iter()
                            .for_each_init(Vec::new, |lt, target| later(target, lt));
                    } else {
                        for target in targets {
                            later(target, &mut work.w);
                        }
                    }
                }
                if b > 0 {
                    let first = j0 == 0;
                    update_matrix(
                        wr.subrows(rows - wj - b, b),
                        d_inv,
                        u,
                        first,
                        parallel,
                        work,
                    );
                }
                for (j, d) in d_inv.iter().enumerate() {
                    column_mut(below.rb_mut(), j)
                        .iter_mut()
                        .for_each(|x| *x *= d);
                }
            }
            // back into the chunks, from each column's diagonal down (above it, in its chunk's
            // triangle, are what the updates from earlier panels wrote: nothing reads it)
            for (jj, from) in scratch[..rows * wj].chunks_exact(rows).enumerate() {
                let (col, base) = chunks.col(j0 + jj);
                col[j0 + jj - base..].copy_from_slice(&from[jj..]);
            }
        }
        work.front = scratch;
        Ok(signs)
    }
}

/// `U -= W D^-1 W^T` into the packed update matrix `u` (order `b`), or `U = -W D^-1 W^T` when
/// `first` (what `u` held is not read), `W` (`b x c`) the front's bottom rows before they are
/// scaled to `L_b`, by panels of [`UPDATE_PANEL`] columns ([`update_panel`]), the panels on
/// different threads when `parallel`.
fn update_matrix(
    w: MatRef<'_, f64>,
    d_inv: &[f64],
    u: &mut [f64],
    first: bool,
    parallel: bool,
    work: &mut Workspace,
) {
    let b = w.nrows();
    // each panel's columns of the packed `U`, one piece of it
    let mut pieces = Vec::with_capacity(b.div_ceil(UPDATE_PANEL));
    let mut rest = u;
    for j0 in (0..b).step_by(UPDATE_PANEL) {
        let width = UPDATE_PANEL.min(b - j0);
        let (piece, r) = rest.split_at_mut(packed_start(j0 + width, b) - packed_start(j0, b));
        pieces.push((j0, piece));
        rest = r;
    }
    if parallel {
        // each thread's scratch is its own and freed when its share is done: drawn from a
        // Sturm count's recycled buffers, it would be lost to them (no hook at that end)
        pieces.into_par_iter().for_each_init(
            || (Vec::new(), Vec::new()),
            |(lt, panel), (j0, piece)| {
                update_panel(w, d_inv, (j0, first), piece, lt, panel, None);
            },
        );
    } else {
        for (j0, piece) in pieces {
            update_panel(
                w,
                d_inv,
                (j0, first),
                piece,
                &mut work.w,
                &mut work.panel,
                work.recycled,
            );
        }
    }
}

/// `U -= W L_b^T` (or `U = -W L_b^T` when `first`) on the columns `j0..j0 + width` of a front's
/// update matrix (`piece`: those packed columns), from `W = L_b D` (`w`, `b x c`) and
/// `d_inv = D^-1`: computed as a lower-triangular block on top of a rectangle into scratch (`panel`) and subtracted, so that no
/// square `b x b` is ever held. The right operand `(L_b^T)[:, j0..j0 + width]` is made into `lt`,
/// `c x width` by columns (faer's GEMM multiplies a column-major right operand faster than the
/// transposed rows of `W`: 37 against 29 GFLOP/s on one thread, 209,088-DOF block), a panel at a
/// time: no `c x b` copy of `W` is held. Each of its entries is the product that scales the
/// stored `L_b`, bit for bit.
fn update_panel(
    w: MatRef<'_, f64>,
    d_inv: &[f64],
    (j0, first): (usize, bool),
    piece: &mut [f64],
    lt: &mut Vec<f64>,
    panel: &mut Vec<f64>,
    recycled: Option<&Recycled>,
) {
    let (b, c) = (w.nrows(), w.ncols());
    let (width, height) = (UPDATE_PANEL.min(b - j0), b - j0);
    let lt = Workspace::room(lt, c * width, recycled);
    let mut lt = MatMut::from_column_major_slice_mut(lt, c, width);
    lt.copy_from(w.subrows(j0, width).transpose());
    for jj in 0..width {
        let col = column_mut(lt.rb_mut(), jj);
        col.iter_mut().zip(d_inv).for_each(|(x, d)| *x *= d);
    }
    // the strict upper triangle of the panel's top is neither written nor read
    let panel = Workspace::room(panel, height * width, recycled);
    let mut t = MatMut::from_column_major_slice_mut(panel, height, width);
    let (diagonal, rest) = t.rb_mut().split_at_row_mut(width);
    let (w_top, w_rest) = w.subrows(j0, height).split_at_row(width);
    let lt = lt.rb();
    triangular_matmul(
        diagonal,
        BlockStructure::TriangularLower,
        Accum::Replace,
        w_top,
        BlockStructure::Rectangular,
        lt,
        BlockStructure::Rectangular,
        1.0,
        Par::Seq,
    );
    matmul(rest, Accum::Replace, w_rest, lt, 1.0, Par::Seq);
    let base = packed_start(j0, b);
    for jj in 0..width {
        let j = j0 + jj;
        let col = &mut piece[packed_start(j, b) - base..packed_start(j + 1, b) - base];
        let from = &panel[jj * height + jj..(jj + 1) * height];
        if first {
            col.iter_mut().zip(from).for_each(|(x, v)| *x = -v);
        } else {
            col.iter_mut().zip(from).for_each(|(x, v)| *x -= v);
        }
    }
}

/// One task's scratch, reused from front to front: freeing and allocating the large update
/// matrices of every front costs the kernel a TLB shootdown on every core each time (measured:
/// 30 % of a two-thread factorization in the kernel's inter-processor calls).
struct Workspace<'a> {
    /// global row -> its row in the current front
    map: Vec<usize>,
    /// the children's rows in the current front
    locs: Vec<usize>,
    /// a panel's `L_b^T` (`c x UPDATE_PANEL` by columns) of the current front
    w: Vec<f64>,
    /// a panel of `L_b D L_b^T`, before it is subtracted from the packed update matrix
    panel: Vec<f64>,
    /// a stored front's square scratch copy, or a large front's super panel
    /// ([`Fronts::front`])
    front: Vec<f64>,
    /// update matrices already added to their parent, for reuse
    pool: Vec<Vec<f64>>,
    /// whether more fronts follow (a sequential task): else nothing is kept
    reuse: bool,
    /// the Sturm count's buffers shared between tasks
    recycled: Option<&'a Recycled>,
}

impl<'a> Workspace<'a> {
    fn new(n: usize, reuse: bool, recycled: Option<&'a Recycled>) -> Self {
        Self {
            map: vec![0; n],
            locs: Vec::new(),
            w: Vec::new(),
            panel: Vec::new(),
            front: Vec::new(),
            pool: Vec::new(),
            reuse,
            recycled,
        }
    }

    /// `v` zeroed to `len` values, taking a recycled buffer in its place when it is too small.
    fn refill(v: &mut Vec<f64>, len: usize, recycled: Option<&Recycled>) {
        Self::hold(v, len, recycled);
        v.clear();
        v.resize(len, 0.0);
    }

    /// `v`, or a recycled buffer in its place when `v` cannot hold `len` values and one can.
    fn hold(v: &mut Vec<f64>, len: usize, recycled: Option<&Recycled>) {
        if v.capacity() < len
            && let Some(r) = recycled
            && let Some(b) = r.take(len)
        {
            r.give(std::mem::replace(v, b));
        }
    }

    /// The first `len` values of `v`, grown to hold them (taking a recycled buffer in its place
    /// when it is too small) but not cleared: for scratch that every caller overwrites before it
    /// reads it. Clearing it as [`Workspace::refill`] does was 3 % of the samples of a
    /// factorization of the 52,920-DOF block (the update panels' `L_b^T` and products,
    /// docs/SCALING.md, "Scratch not cleared").
    fn room<'v>(v: &'v mut Vec<f64>, len: usize, recycled: Option<&Recycled>) -> &'v mut [f64] {
        Self::hold(v, len, recycled);
        if v.len() < len {
            v.resize(len, 0.0);
        }
        if cfg!(debug_assertions) {
            // what a caller would read before writing it shows in every test (as NaN)
            v[..len].fill(f64::NAN);
        }
        &mut v[..len]
    }

    /// This task's buffers to the recycled ones (a task outside the sequential subtrees ends).
    fn recycle(&mut self) {
        if let Some(r) = self.recycled {
            for v in [std::mem::take(&mut self.w), std::mem::take(&mut self.panel)] {
                r.give(v);
            }
            self.pool.drain(..).for_each(|v| r.give(v));
        }
    }

    /// Keeps `v` for reuse, or frees it: a front takes at most two buffers (its update matrix,
    /// and its columns when the factor is not stored), so the pool keeps the two largest; the
    /// rest (a parent's children's update matrices) would only add to the peak memory.
    fn give(&mut self, v: Vec<f64>) {
        if !self.reuse {
            if let Some(r) = self.recycled {
                r.give(v);
            }
            return;
        }
        self.pool.push(v);
        if self.pool.len() > POOL {
            let smallest = (0..self.pool.len()).min_by_key(|&i| self.pool[i].capacity());
            if let Some(i) = smallest {
                let v = self.pool.swap_remove(i);
                if let Some(r) = self.recycled {
                    r.give(v);
                }
            }
        }
    }

    /// A zeroed buffer of `len` values, the pool's largest if there is one (else a recycled
    /// one that holds it).
    fn take(&mut self, len: usize) -> Vec<f64> {
        let mut v = self.largest();
        Self::refill(&mut v, len, self.recycled);
        v
    }

    /// [`Workspace::take`] without clearing: `len` values as earlier fronts left them, for a
    /// buffer written whole before it is read.
    fn take_uncleared(&mut self, len: usize) -> Vec<f64> {
        let mut v = self.largest();
        Self::room(&mut v, len, self.recycled);
        v.truncate(len);
        v
    }

    /// The pool's largest buffer, or an empty one.
    fn largest(&mut self) -> Vec<f64> {
        let best = (0..self.pool.len()).max_by_key(|&i| self.pool[i].capacity());
        best.map(|i| self.pool.swap_remove(i)).unwrap_or_default()
    }
}

/// A Sturm count's large buffers, kept when a front is done with them for the next fronts of any
/// task, up to `limit` values in all (the largest kept). The fronts near the root grow from one
/// to the next, and buffers freed to the system come back as fresh pages, each cleared by the
/// kernel on first touch: 0.79 million page faults in the count of the 209,088-DOF block
/// (docs/SCALING.md, "Fresh pages in the factorizations"). The count stores no factor, so its
/// memory stays far below the run's factorization's even with these kept; the run's own
/// factorization does not recycle (there the kept buffers would add to the command's peak).
struct Recycled {
    buffers: std::sync::Mutex<Vec<Vec<f64>>>,
    limit: usize,
}

/// The recycled buffers hold at most the factor's size over this (in values).
const RECYCLED_SHARE: usize = 4;

/// Buffers below this many values are not worth keeping (the allocator reuses them anyway).
const RECYCLED_SMALLEST: usize = 1 << 15;

impl Recycled {
    fn new(limit: usize) -> Self {
        Self {
            buffers: std::sync::Mutex::new(Vec::new()),
            limit,
        }
    }

    /// The smallest kept buffer that holds `len` values.
    fn take(&self, len: usize) -> Option<Vec<f64>> {
        let mut b = self.buffers.lock().unwrap_or_else(|e| e.into_inner());
        let best = (0..b.len())
            .filter(|&i| b[i].capacity() >= len)
            .min_by_key(|&i| b[i].capacity())?;
        Some(b.swap_remove(best))
    }

    /// Keeps `v` unless it is small; then drops the smallest kept buffers until the rest fit the
    /// limit.
    fn give(&self, v: Vec<f64>) {
        if v.capacity() < RECYCLED_SMALLEST {
            return;
        }
        let mut b = self.buffers.lock().unwrap_or_else(|e| e.into_inner());
        b.push(v);
        b.sort_unstable_by_key(|v| std::cmp::Reverse(v.capacity()));
        let mut total = 0;
        b.retain(|v| {
            total += v.capacity();
            total <= self.limit
        });
    }
}

/// Hands the memory the allocator holds free back to the system: called when a stored
/// factorization ends (docs/SCALING.md, "Memory the allocator keeps"). A factorization frees
/// thousands of update matrices of 0.1-32 MB from both threads; glibc's allocator keeps most of
/// them in its per-thread arenas (its threshold for giving a block its own mapping rises to 32 MB
/// as such blocks are freed), and memory freed inside an arena stays resident, under the
/// eigensolver's basis allocated next. `malloc_trim(0)` returns every arena's free pages in
/// 1-20 ms: the 52,920-DOF block's peak 676-690 MB -> 620-679 MB, the 47,628-DOF plate's
/// 354-363 MB -> 330-349 MB. Other allocators than glibc's: nothing is done.
pub(crate) fn release_free_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    trim::malloc_trim_all();
}

#[cfg(all(target_os = "linux", target_env = "gnu"))]
#[allow(unsafe_code)]
mod trim {
    //! The one call into glibc's allocator.
    unsafe extern "C" {
        fn malloc_trim(pad: usize) -> std::ffi::c_int;
    }

    pub(super) fn malloc_trim_all() {
        // SAFETY: malloc_trim takes no pointers and has no preconditions; it locks each arena
        // while it trims it, so it may run beside allocations on other threads.
        unsafe {
            malloc_trim(0);
        }
    }
}
