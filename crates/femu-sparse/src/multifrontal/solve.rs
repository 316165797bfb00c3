//! Forward and back substitution with the stored fronts, subtree-parallel, for blocks of
//! right-hand sides ([`solve`]).

use super::*;

/// Solves `L D L^T x = b` in place for the permuted right-hand sides `x` (`n x k`, in the
/// analysis's permuted order) with a factor in `layout` (femu's chunks, or faer's supernodal
/// layout for a factor of faer's left-looking factorization), the disjoint subtrees
/// of the elimination tree on different threads (docs/SCALING.md, "A subtree-parallel solve").
///
/// Each thread reads only its subtrees' part of the factor, for every right-hand side at once:
/// where splitting the right-hand sides between threads makes each thread read the whole factor,
/// this reads it once. The updates of a supernode to its ancestors' rows travel up the tree as
/// small dense vectors (multifrontal), and the solution at a supernode's rows comes down to its
/// children the same way, so the threads share nothing they write.
pub(crate) fn solve(
    tree: &Tree,
    symbolic: &SymbolicSupernodalCholesky<usize>,
    (values, layout): (&[f64], Layout<'_>),
    mut x: MatMut<'_, f64>,
    threads: usize,
) {
    let (n, k) = (x.nrows(), x.ncols());
    let ns = symbolic.n_supernodes();
    let (begin, end) = (symbolic.supernode_begin(), symbolic.supernode_end());
    // each supernode's rows of the solution, `c x k` column-major, in supernode order
    let mut z = vec![0.0; n * k];
    let mut slots = tree.postorder_slots(&mut z, |s| (end[s] - begin[s]) * k);
    let solver = Solver {
        tree,
        symbolic,
        values,
        layout,
        b: x.rb(),
        k,
        sequential_below: tree.sequential_below(threads),
        threads,
        places: tree.places(symbolic),
    };
    solver.forward_forest(&tree.roots, &mut slots, 0);
    let known: Vec<Mat<f64>> = tree.roots.iter().map(|_| Mat::zeros(0, k)).collect();
    solver.backward_forest(&tree.roots, &known, &mut slots, 0);
    drop(slots);
    // back into `x`
    let mut at = 0;
    for s in 0..ns {
        let c = end[s] - begin[s];
        let slot = MatRef::from_column_major_slice(&z[at..at + c * k], c, k);
        x.rb_mut().subrows_mut(begin[s], c).copy_from(slot);
        at += c * k;
    }
}

/// A `rows x cols` matrix from `pool` (a matrix an earlier front is done with, its storage
/// reused) or a new one; its entries are whatever they were: the caller writes every one. A
/// solve of a few right-hand sides takes and frees one small matrix per front and child, and
/// the allocator's own work was about 8 % of the 47,628-DOF plate's solve in a profile.
pub(super) fn recycled(pool: &mut Vec<Mat<f64>>, rows: usize, cols: usize) -> Mat<f64> {
    let mut m = pool.pop().unwrap_or_else(Mat::new);
    m.resize_with(rows, cols, |_, _| 0.0);
    m
}

/// Column `j` of a column-major matrix as a slice.
pub(super) fn column(m: MatRef<'_, f64>, j: usize) -> &[f64] {
    m.col(j)
        .try_as_col_major()
        .expect("column-major storage")
        .as_slice()
}

/// Column `j` of a column-major matrix as a mutable slice.
pub(super) fn column_mut(m: MatMut<'_, f64>, j: usize) -> &mut [f64] {
    m.col_mut(j)
        .try_as_col_major_mut()
        .expect("column-major storage")
        .as_slice_mut()
}

pub(super) struct Solver<'a> {
    tree: &'a Tree,
    symbolic: &'a SymbolicSupernodalCholesky<usize>,
    values: &'a [f64],
    /// where `values` holds each supernode's chunks
    layout: Layout<'a>,
    /// the right-hand sides (permuted), read by the forward pass
    b: MatRef<'a, f64>,
    k: usize,
    sequential_below: f64,
    threads: usize,
    /// [`Tree::places`]
    places: &'a [u32],
}

impl Solver<'_> {
    /// The threads for the dense kernels of a front outside the sequential subtrees: all of them
    /// for a large one (near the root, where the subtrees wait for it), else one.
    fn par(&self, s: usize) -> Par {
        if self.threads > 1 && self.tree.own_flops[s] > self.tree.tuning.parallel_front {
            Par::rayon(self.threads)
        } else {
            Par::Seq
        }
    }

    /// Supernode `s`'s pivots and its pattern (the rows below them).
    fn sizes(&self, s: usize) -> (usize, &[usize]) {
        let sym = self.symbolic;
        let c = sym.supernode_end()[s] - sym.supernode_begin()[s];
        let p = sym.col_ptr_for_row_idx()[s];
        (c, &sym.row_idx()[p..p + sym.nnz_per_super()[s]])
    }

    /// Supernode `s`'s chunks: the first pivot's place in the front of each.
    fn chunks(&self, s: usize) -> impl DoubleEndedIterator<Item = usize> + use<> {
        let c = self.sizes(s).0;
        let w = self.layout.width;
        (0..c.div_ceil(w)).map(move |q| q * w)
    }

    /// The chunk of supernode `s` from front row `r0` (a multiple of the layout's width): its
    /// columns of the factor, `[L11; L21]` from that row down.
    fn chunk(&self, s: usize, r0: usize) -> Panel<'_> {
        let (c, rows) = self.sizes(s);
        let (nb, w) = (rows.len(), self.layout.width);
        let (cols, ld) = (w.min(c - r0), c + nb - r0);
        let at = self.layout.ptr[s] + chunk_start(c, nb, w, r0 / w);
        Panel::new(&self.values[at..at + ld * cols], ld, ld, cols)
    }

    /// `D^-1`: the reciprocals of supernode `s`'s pivots.
    fn d_inv(&self, s: usize) -> Vec<f64> {
        let mut d = Vec::new();
        for r0 in self.chunks(s) {
            let l = self.chunk(s, r0);
            d.extend((0..l.cols()).map(|i| l.at(i, i).recip()));
        }
        d
    }

    /// Where each row of `child`'s pattern lies in its parent `s`'s front (`c` pivot rows, then
    /// its pattern: [`Tree::places`]), and how many of them are pivot rows. The places increase
    /// (the pattern is sorted, and its rows among `s`'s pivots come first).
    fn places(&self, s: usize, child: usize) -> (usize, &[u32]) {
        let sym = self.symbolic;
        let c = sym.supernode_end()[s] - sym.supernode_begin()[s];
        let p = sym.col_ptr_for_row_idx()[child];
        let places = &self.places[p..p + sym.nnz_per_super()[child]];
        (places.partition_point(|&l| (l as usize) < c), places)
    }

    fn forward_forest(
        &self,
        roots: &[usize],
        slots: &mut [&mut [f64]],
        base: usize,
    ) -> Vec<Mat<f64>> {
        self.tree.forest(roots, slots, base, &|_, s, slots, base| {
            self.forward_subtree(s, slots, base)
        })
    }

    /// `L z = b` and `z <- D^-1 z` on the subtree of `s`; returns `s`'s update to its pattern.
    fn forward_subtree(&self, s: usize, slots: &mut [&mut [f64]], base: usize) -> Mat<f64> {
        let tree = self.tree;
        if tree.subtree_flops[s] <= self.sequential_below {
            let mut stack: Vec<Mat<f64>> = Vec::new();
            let (mut w, mut pool) = (Vec::new(), Vec::new());
            for (slot, &t) in slots.iter_mut().zip(&tree.post[base..=tree.pos[s]]) {
                let kids = tree.children(t).len();
                let updates = stack.split_off(stack.len() - kids);
                stack.push(self.forward_front(t, slot, updates, &mut w, &mut pool, Par::Seq));
            }
            return stack.pop().unwrap_or_else(|| Mat::zeros(0, self.k));
        }
        let (below, own) = slots.split_at_mut(tree.pos[s] - base);
        let updates = self.forward_forest(tree.children(s), below, base);
        self.forward_front(
            s,
            own[0],
            updates,
            &mut Vec::new(),
            &mut Vec::new(),
            self.par(s),
        )
    }

    fn forward_front(
        &self,
        s: usize,
        slot: &mut [f64],
        updates: Vec<Mat<f64>>,
        w: &mut Vec<f64>,
        pool: &mut Vec<Mat<f64>>,
        par: Par,
    ) -> Mat<f64> {
        let (c, rows) = self.sizes(s);
        let (nb, k) = (rows.len(), self.k);
        let start = self.symbolic.supernode_begin()[s];
        // updates with no rows add nothing (a child without a pattern, or a zero update below)
        let zero_b = || (0..k).all(|j| (start..start + c).all(|i| self.b[(i, j)] == 0.0));
        if updates.iter().all(|u| u.nrows() == 0) && zero_b() {
            // nothing reaches this front: its forward solution is zero, and so is its update (a
            // sparse right-hand side, such as an expansion's unit columns at the sensors, solves
            // only the fronts on its paths to the root)
            slot.fill(0.0);
            return Mat::zeros(0, k);
        }
        let d_inv = self.d_inv(s);
        if k <= MAX_RHS {
            // the front's rows of the right-hand sides in one buffer, `c + nb` per column, for
            // the solve's own kernels (crate::skinny): the factor read once
            let ld = c + nb;
            // (scratch kept from front to front of a sequential subtree)
            w.clear();
            w.resize(ld * k, 0.0);
            for (j, wq) in w.chunks_exact_mut(ld).enumerate() {
                wq[..c].copy_from_slice(&column(self.b, j)[start..start + c]);
            }
            for (&child, update) in self.tree.children(s).iter().zip(updates) {
                if update.nrows() == 0 {
                    continue;
                }
                let (_, places) = self.places(s, child);
                for (j, wq) in w.chunks_exact_mut(ld).enumerate() {
                    for (&l, &v) in places.iter().zip(column(update.as_ref(), j)) {
                        wq[l as usize] += v;
                    }
                }
                pool.push(update);
            }
            for r0 in self.chunks(s) {
                crate::skinny::forward(self.chunk(s, r0), w, (ld, r0), k, par != Par::Seq);
            }
            for (j, wq) in w.chunks_exact(ld).enumerate() {
                let zc = &mut slot[j * c..(j + 1) * c];
                for ((z, &v), d) in zc.iter_mut().zip(&wq[..c]).zip(&d_inv) {
                    *z = v * d;
                }
            }
            // the update rows, copied by columns (a per-entry `Mat::from_fn` was 3 % of a pass)
            // into a matrix a child's update left behind
            let mut out = recycled(pool, nb, k);
            out.copy_from(MatRef::from_column_major_slice_with_stride(
                &w[c..],
                nb,
                k,
                ld,
            ));
            return out;
        }
        let mut zs = MatMut::from_column_major_slice_mut(slot, c, k);
        zs.copy_from(self.b.subrows(start, c));
        let mut u = Mat::<f64>::zeros(nb, k);
        for (&child, update) in self.tree.children(s).iter().zip(updates) {
            if update.nrows() == 0 {
                continue;
            }
            let (pivots, places) = self.places(s, child);
            let (to_pivots, to_pattern) = places.split_at(pivots);
            for j in 0..k {
                let from = column(update.as_ref(), j);
                let (from_p, from_b) = from.split_at(pivots);
                let zc = column_mut(zs.rb_mut(), j);
                for (&l, &v) in to_pivots.iter().zip(from_p) {
                    zc[l as usize] += v;
                }
                let uc = column_mut(u.as_mut(), j);
                for (&l, &v) in to_pattern.iter().zip(from_b) {
                    uc[l as usize - c] += v;
                }
            }
        }
        // chunk by chunk: its triangle, then the pivot rows after it and the pattern's rows
        for r0 in self.chunks(s) {
            let l = self.chunk(s, r0).mat();
            let cq = l.ncols();
            let (tri, below) = l.split_at_row(cq);
            let (mid, bottom) = below.split_at_row(c - r0 - cq);
            let (done, mut rest) = zs.rb_mut().split_at_row_mut(r0 + cq);
            let mut own = done.subrows_mut(r0, cq);
            solve_unit_lower_triangular_in_place(tri, own.rb_mut(), par);
            if mid.nrows() > 0 {
                matmul(rest.rb_mut(), Accum::Add, mid, own.rb(), -1.0, par);
            }
            if nb > 0 {
                matmul(u.as_mut(), Accum::Add, bottom, own.rb(), -1.0, par);
            }
        }
        for (i, d) in d_inv.iter().enumerate() {
            zs.rb_mut().row_mut(i).iter_mut().for_each(|v| *v *= d);
        }
        u
    }

    fn backward_forest(
        &self,
        roots: &[usize],
        known: &[Mat<f64>],
        slots: &mut [&mut [f64]],
        base: usize,
    ) {
        self.tree.forest(roots, slots, base, &|i, s, slots, base| {
            self.backward_subtree(s, known[i].clone(), slots, base)
        });
    }

    /// `L^T x = z` on the subtree of `s`, given `x` at `s`'s pattern (`known`).
    fn backward_subtree(&self, s: usize, known: Mat<f64>, slots: &mut [&mut [f64]], base: usize) {
        let tree = self.tree;
        if tree.subtree_flops[s] <= self.sequential_below {
            // parents before children: the postorder backwards
            let order = &tree.post[base..=tree.pos[s]];
            let mut pending: Vec<Option<Mat<f64>>> = vec![None; order.len()];
            pending[order.len() - 1] = Some(known);
            let (mut w, mut pool) = (Vec::new(), Vec::new());
            for (i, slot) in slots.iter_mut().enumerate().rev() {
                let t = order[i];
                let known = pending[i].take().expect("a parent passed it down");
                for (child, xr) in self.backward_front(t, slot, known, &mut w, &mut pool, Par::Seq)
                {
                    pending[tree.pos[child] - base] = Some(xr);
                }
            }
            return;
        }
        let (below, own) = slots.split_at_mut(tree.pos[s] - base);
        let passed = self.backward_front(
            s,
            own[0],
            known,
            &mut Vec::new(),
            &mut Vec::new(),
            self.par(s),
        );
        let known: Vec<Mat<f64>> = passed.into_iter().map(|(_, xr)| xr).collect();
        self.backward_forest(tree.children(s), &known, below, base);
    }

    /// `x_s = L_ss^-T (z_s - L_bs^T x_b)` in `slot`; returns each child's `x` at its pattern.
    fn backward_front(
        &self,
        s: usize,
        slot: &mut [f64],
        known: Mat<f64>,
        w: &mut Vec<f64>,
        pool: &mut Vec<Mat<f64>>,
        par: Par,
    ) -> Vec<(usize, Mat<f64>)> {
        let (c, rows) = self.sizes(s);
        let (nb, k) = (rows.len(), self.k);
        let children = self.tree.children(s);
        if k <= MAX_RHS {
            // as on the way up: the front's rows in one buffer for the solve's own kernels
            let ld = c + nb;
            w.clear();
            for j in 0..k {
                w.extend_from_slice(&slot[j * c..(j + 1) * c]);
                w.extend_from_slice(column(known.as_ref(), j));
            }
            for r0 in self.chunks(s).rev() {
                crate::skinny::backward(self.chunk(s, r0), w, (ld, r0), k, par != Par::Seq);
            }
            for (j, wq) in w.chunks_exact(ld).enumerate() {
                slot[j * c..(j + 1) * c].copy_from_slice(&wq[..c]);
            }
            pool.push(known);
            return children
                .iter()
                .map(|&child| {
                    let (_, places) = self.places(s, child);
                    // every entry written below
                    let mut xr = recycled(pool, places.len(), k);
                    for (j, wq) in w.chunks_exact(ld).enumerate() {
                        let to = column_mut(xr.as_mut(), j);
                        to.iter_mut()
                            .zip(places)
                            .for_each(|(t, &l)| *t = wq[l as usize]);
                    }
                    (child, xr)
                })
                .collect();
        }
        let mut xs = MatMut::from_column_major_slice_mut(slot, c, k);
        // chunk by chunk from the last: the pattern's rows and the pivot rows after the chunk,
        // then its triangle
        for r0 in self.chunks(s).rev() {
            let l = self.chunk(s, r0).mat();
            let cq = l.ncols();
            let (tri, below) = l.split_at_row(cq);
            let (mid, bottom) = below.split_at_row(c - r0 - cq);
            let (done, rest) = xs.rb_mut().split_at_row_mut(r0 + cq);
            let mut own = done.subrows_mut(r0, cq);
            if nb > 0 {
                matmul(
                    own.rb_mut(),
                    Accum::Add,
                    bottom.transpose(),
                    known.as_ref(),
                    -1.0,
                    par,
                );
            }
            if mid.nrows() > 0 {
                matmul(
                    own.rb_mut(),
                    Accum::Add,
                    mid.transpose(),
                    rest.rb(),
                    -1.0,
                    par,
                );
            }
            solve_unit_upper_triangular_in_place(tri.transpose(), own, par);
        }
        children
            .iter()
            .map(|&child| {
                let (pivots, places) = self.places(s, child);
                let (from_pivots, from_pattern) = places.split_at(pivots);
                let mut xr = Mat::<f64>::zeros(places.len(), k);
                for j in 0..k {
                    let (xc, kc) = (column(xs.rb(), j), column(known.as_ref(), j));
                    let (to_p, to_b) = column_mut(xr.as_mut(), j).split_at_mut(pivots);
                    for (t, &l) in to_p.iter_mut().zip(from_pivots) {
                        *t = xc[l as usize];
                    }
                    for (t, &l) in to_b.iter_mut().zip(from_pattern) {
                        *t = kc[l as usize - c];
                    }
                }
                (child, xr)
            })
            .collect()
    }
}
