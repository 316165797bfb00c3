//! Blocks of vectors as matrices: contiguous columns, products with them, block
//! orthogonalisation (projection against a basis, Cholesky QR twice).

use super::*;

/// Vectors of length `n` stored one after the other (column-major, contiguous), so that a set of
/// them is a matrix for GEMM (`faer`'s blocked, parallel kernels) and each one a slice.
#[derive(Debug, Clone, Default)]
pub(super) struct Columns {
    pub(super) n: usize,
    pub(super) data: Vec<f64>,
}

impl Columns {
    pub(super) fn new(n: usize) -> Self {
        Self { n, data: vec![] }
    }
    pub(super) fn len(&self) -> usize {
        self.data.len().checked_div(self.n).unwrap_or(0)
    }
    pub(super) fn col(&self, j: usize) -> &[f64] {
        &self.data[j * self.n..(j + 1) * self.n]
    }
    /// Appends a column, written on the rayon threads: the first write to the basis's reserved
    /// storage is where the operating system provides its pages (a page fault and a cleared 4 KiB
    /// page each), and page faults on different threads proceed in parallel (docs/SCALING.md,
    /// "The block within itself, the Ritz vectors' products and the input checks").
    pub(super) fn push(&mut self, v: &[f64]) {
        self.data
            .par_extend(v.par_iter().with_min_len(1 << 15).copied());
    }
    /// Appends `v / d` (as [`Columns::push`]).
    pub(super) fn push_divided(&mut self, v: &[f64], d: f64) {
        self.data
            .par_extend(v.par_iter().with_min_len(1 << 15).map(|x| x / d));
    }
    /// Appends the columns of `a` (as [`Columns::push`]).
    pub(super) fn push_mat(&mut self, a: faer::MatRef<'_, f64>) {
        for j in 0..a.ncols() {
            let col = a.col(j).try_as_col_major().expect("contiguous").as_slice();
            self.push(col);
        }
    }
    /// Appends `cols` zero columns (as [`Columns::push`]).
    pub(super) fn push_zeros(&mut self, cols: usize) {
        self.data
            .par_extend(rayon::iter::repeat_n(0.0, cols * self.n).with_min_len(1 << 15));
    }
    /// Drops the columns from `cols` on.
    pub(super) fn truncate(&mut self, cols: usize) {
        self.data.truncate(cols * self.n);
    }
    /// The columns before `from`, and the columns from `from` on, writable.
    pub(super) fn split_mut(
        &mut self,
        from: usize,
    ) -> (faer::MatRef<'_, f64>, faer::MatMut<'_, f64>) {
        let n = self.n;
        let (head, tail) = self.data.split_at_mut(from * n);
        let cols = tail.len() / n.max(1);
        (
            faer::MatRef::from_column_major_slice(head, n, from),
            faer::MatMut::from_column_major_slice_mut(tail, n, cols),
        )
    }
    /// Columns `a..b` as a matrix.
    pub(super) fn range(&self, a: usize, b: usize) -> faer::MatRef<'_, f64> {
        faer::MatRef::from_column_major_slice(&self.data[a * self.n..b * self.n], self.n, b - a)
    }
    pub(super) fn mat(&self) -> faer::MatRef<'_, f64> {
        self.range(0, self.len())
    }
    pub(super) fn clear(&mut self) {
        self.data.clear();
    }
    /// Room for `cols` columns in all, allocated at once: a vector that doubles as it grows holds
    /// the old and the new storage together while it moves (glibc serves blocks below its mmap
    /// threshold, which rises to 32 MB, from the heap, where a reallocation copies).
    pub(super) fn reserve(&mut self, cols: usize) {
        let total = cols * self.n;
        if total > self.data.capacity() {
            self.data.reserve_exact(total - self.data.len());
        }
    }
    /// Replaces the first `m` columns `V` by the `k` columns `V S` (`s` is `m x k`, `k <= m`);
    /// the columns after them follow. In place, by blocks of rows (each row of `V S` needs only
    /// that row of `V`), on the rayon threads: no copy of the basis is held (docs/SCALING.md,
    /// "Memory").
    pub(super) fn rotate_front(&mut self, m: usize, s: faer::MatRef<'_, f64>) {
        let (n, k) = (self.n, s.ncols());
        debug_assert!(s.nrows() == m && k <= m && m <= self.len());
        right_multiply_in_place(
            faer::MatMut::from_column_major_slice_mut(&mut self.data[..m * n], n, m),
            s,
        );
        self.data.drain(k * n..m * n);
    }
}

/// `w -= v c` with `c = mv^T w`: one pass of block classical Gram-Schmidt of the columns of `w`
/// against the `M`-orthonormal columns of `v` (whose `M` images are `mv`), as two GEMMs; returns
/// `c` (by [`inner_products`]).
pub(super) fn project_out(
    v: faer::MatRef<'_, f64>,
    mv: faer::MatRef<'_, f64>,
    w: faer::MatMut<'_, f64>,
) -> Mat<f64> {
    if v.ncols() == 0 {
        return Mat::<f64>::zeros(0, w.ncols());
    }
    let c = inner_products(mv, w.as_ref());
    let par = faer::get_global_parallelism();
    faer::linalg::matmul::matmul(w, faer::Accum::Add, v, c.as_ref(), -1.0, par);
    c
}

/// `a^T b` for two tall matrices of `n` rows and a few columns.
///
/// faer's GEMM does not split the long inner dimension (`n` rows against a few columns) between
/// threads, so the rows are split here, [`PROJECT_ROWS`] or more per thread, each part's
/// products computed on one thread and the parts added in order (the same sum for the same
/// number of threads). Coefficients of the 199,200-DOF plate's 20-mode solve 0.27-0.28 s ->
/// 0.15-0.17 s (docs/SCALING.md, "Sparse products by blocks of known width").
pub(super) fn inner_products(a: faer::MatRef<'_, f64>, b: faer::MatRef<'_, f64>) -> Mat<f64> {
    use faer::Accum;
    use faer::linalg::matmul::matmul;
    let par = faer::get_global_parallelism();
    let n = b.nrows();
    let parts = rayon::current_num_threads().min(n / PROJECT_ROWS).max(1);
    let size = n.div_ceil(parts);
    let partial: Vec<Mat<f64>> = (0..parts)
        .into_par_iter()
        .map(|p| {
            let (lo, len) = (p * size, size.min(n - p * size));
            let mut part = Mat::<f64>::zeros(a.ncols(), b.ncols());
            matmul(
                part.as_mut(),
                Accum::Replace,
                a.subrows(lo, len).transpose(),
                b.subrows(lo, len),
                1.0,
                if parts == 1 { par } else { faer::Par::Seq },
            );
            part
        })
        .collect();
    let mut c = Mat::<f64>::zeros(a.ncols(), b.ncols());
    for part in partial {
        c += part;
    }
    c
}

/// `v <- v s` in place (`s` is `m x k` for `v`'s `m` columns, `k <= m`; the result is the first
/// `k` columns of `v`), by blocks of rows on the rayon threads: each row of `v s` needs only that
/// row of `v`, so no second copy of `v` is held.
pub(super) fn right_multiply_in_place(v: faer::MatMut<'_, f64>, s: faer::MatRef<'_, f64>) {
    const ROWS: usize = 4096;
    if v.nrows() > ROWS {
        let half = v.nrows() / 2;
        let (top, bottom) = v.split_at_row_mut(half);
        rayon::join(
            || right_multiply_in_place(top, s),
            || right_multiply_in_place(bottom, s),
        );
        return;
    }
    right_multiply_rows(v, s);
}

/// [`right_multiply_in_place`] on the calling thread, through a copy of the product.
pub(super) fn right_multiply_rows(v: faer::MatMut<'_, f64>, s: faer::MatRef<'_, f64>) {
    let mut t = Mat::<f64>::zeros(v.nrows(), s.ncols());
    leaf_product(t.as_mut(), false, v.as_ref(), s, 1.0);
    v.subcols_mut(0, s.ncols()).copy_from(&t);
}

/// The upper triangular `R` with `R^T R = g` (`g` symmetric, the mean of its two triangles), or
/// `None` when a pivot is not above `rel^2` times its diagonal entry of `g` (the column is
/// dependent on the ones before it to that measure) or `g` is not finite.
pub(super) fn small_cholesky(g: &Mat<f64>, rel: f64) -> Option<Mat<f64>> {
    let k = g.nrows();
    let mut r = Mat::<f64>::zeros(k, k);
    for j in 0..k {
        let d = g[(j, j)] - (0..j).map(|i| r[(i, j)] * r[(i, j)]).sum::<f64>();
        if !(g[(j, j)] > 0.0 && g[(j, j)].is_finite() && d > rel * rel * g[(j, j)]) {
            return None;
        }
        r[(j, j)] = d.sqrt();
        for c in j + 1..k {
            let e =
                0.5 * (g[(j, c)] + g[(c, j)]) - (0..j).map(|i| r[(i, j)] * r[(i, c)]).sum::<f64>();
            r[(j, c)] = e / r[(j, j)];
        }
    }
    Some(r)
}

/// The inverse of an upper triangular matrix with a nonzero diagonal.
pub(super) fn upper_inverse(r: &Mat<f64>) -> Mat<f64> {
    let k = r.nrows();
    let mut inv = Mat::<f64>::zeros(k, k);
    for c in 0..k {
        inv[(c, c)] = 1.0 / r[(c, c)];
        for i in (0..c).rev() {
            let s: f64 = (i + 1..=c).map(|l| r[(i, l)] * inv[(l, c)]).sum();
            inv[(i, c)] = -s / r[(i, i)];
        }
    }
    inv
}

/// The fewest rows of a leaf of [`fold_rows`] (a leaf has fewer than twice as many): a block of
/// four columns and its images take 128 to 256 KiB there, so that the several steps of one pass
/// find the leaf's rows of the block in the core's cache while the basis streams past once.
pub(super) const LEAF_ROWS: usize = 2048;

/// `leaf(first, w_rows, mw_rows)` over the rows of a block `w` and of its images `mw`, cut into
/// leaves of [`LEAF_ROWS`] to `2 LEAF_ROWS` rows (`first` is a leaf's first row), on the rayon
/// threads; the leaves' matrices are added in a tree fixed by the number of rows, so the sums are
/// the same for any number of threads. One such pass reads each row of the block once for all
/// its steps (docs/SCALING.md, "Orthogonalisation by leaves of rows").
pub(super) fn fold_rows(
    first: usize,
    w: faer::MatMut<'_, f64>,
    mw: faer::MatMut<'_, f64>,
    leaf: &(impl Fn(usize, faer::MatMut<'_, f64>, faer::MatMut<'_, f64>) -> Vec<Mat<f64>> + Sync),
) -> Vec<Mat<f64>> {
    let rows = w.nrows();
    if rows < 2 * LEAF_ROWS {
        return leaf(first, w, mw);
    }
    let half = rows / (2 * LEAF_ROWS) * LEAF_ROWS;
    let (wt, wb) = w.split_at_row_mut(half);
    let (mt, mb) = mw.split_at_row_mut(half);
    let (mut a, b) = rayon::join(
        || fold_rows(first, wt, mt, leaf),
        || fold_rows(first + half, wb, mb, leaf),
    );
    for (a, b) in a.iter_mut().zip(b) {
        *a += b;
    }
    a
}

/// `dst (= or +=) alpha a b` on the calling thread (a leaf of [`fold_rows`]).
pub(super) fn leaf_product(
    dst: faer::MatMut<'_, f64>,
    add: bool,
    a: faer::MatRef<'_, f64>,
    b: faer::MatRef<'_, f64>,
    alpha: f64,
) {
    let accum = if add {
        faer::Accum::Add
    } else {
        faer::Accum::Replace
    };
    faer::linalg::matmul::matmul(dst, accum, a, b, alpha, faer::Par::Seq);
}

/// The Euclidean norms of the columns of `w` (a leaf of [`fold_rows`]), squared, as a row.
pub(super) fn leaf_squared_norms(w: faer::MatRef<'_, f64>) -> Mat<f64> {
    Mat::<f64>::from_fn(1, w.ncols(), |_, j| {
        let col = w.col(j).try_as_col_major().expect("contiguous");
        let mut lanes = [0.0; 8];
        let chunks = col.as_slice().chunks_exact(8);
        let tail: f64 = chunks.remainder().iter().map(|x| x * x).sum();
        for c in chunks {
            for (l, x) in lanes.iter_mut().zip(c) {
                *l += x * x;
            }
        }
        lanes.iter().sum::<f64>() + tail
    })
}

/// The Gram matrix `G = mw^T w` of a block (already M-orthogonal to the basis and the locked
/// vectors) with its images `mw`, and its columns' Euclidean norms: what [`cholesky_qr2`] starts
/// from, summed in the pass that makes `mw` ([`crate::csc::sym_mul_mat_gram_into`]).
pub(super) struct Gram {
    pub(super) g: Mat<f64>,
    pub(super) norms: Vec<f64>,
}

/// M-orthonormalises the columns of a block `w` (already M-orthogonal to the basis and the
/// locked vectors) with their `M` images `mw` by Cholesky QR, twice where once is not enough
/// (CholQR2): `G = mw^T w`, `G = R^T R`, `w <- w R^-1`, `mw <- mw R^-1` (the images follow by
/// linearity, no sparse product), then once more unless the first pass left `G` the identity to
/// [`SECOND_QR`]. Returns the upper triangular `R` of `w = Q R` (the product of the passes'),
/// which holds the coefficients a Gram-Schmidt of each column against the ones before it would
/// find (docs/MATH.md, "Selective reorthogonalisation"). `gram` is the block's [`Gram`] (from its
/// projection's `M` product); the first pass's `R^-1` and the second's Gram matrix are one pass
/// over the rows ([`fold_rows`]), the second's `R^-1` another.
///
/// `None`, with `w` and `mw` as they were, when the block is near dependence: a column whose
/// Euclidean norm fell below `1e-5` of its norm before the projection (`before`), or whose part
/// independent of the columns before it is below `1e-5` of its M-norm. A column kept is then
/// at least about `1e-10` of its norm before, the bound below which the vector-by-vector path
/// replaces a column by a random one (what is left of it is round-off, not a direction).
/// CholQR2 is accurate to round-off for blocks conditioned below about `1e7`; those nearer
/// breakdown take the vector-by-vector path.
pub(super) fn cholesky_qr2(
    mut w: faer::MatMut<'_, f64>,
    mut mw: faer::MatMut<'_, f64>,
    before: &[f64],
    gram: &Gram,
) -> Option<Mat<f64>> {
    let k = w.ncols();
    if (0..k).any(|j| !(gram.norms[j] > 1e-5 * before[j])) {
        return None;
    }
    let r1 = small_cholesky(&gram.g, 1e-5)?;
    let inv1 = upper_inverse(&r1);
    let g2 = fold_rows(0, w.as_mut(), mw.as_mut(), &|_, mut w, mut mw| {
        right_multiply_rows(w.as_mut(), inv1.as_ref());
        right_multiply_rows(mw.as_mut(), inv1.as_ref());
        let mut g = Mat::<f64>::zeros(k, k);
        leaf_product(g.as_mut(), false, mw.as_ref().transpose(), w.as_ref(), 1.0);
        vec![g]
    });
    // the second pass only where the first left the block short of working precision: with
    // `G2` (the first pass's measure of what it left) the identity to `SECOND_QR`, `R2` is the
    // identity to about that, and `R2^-1` would move no entry of `w` by more (a NaN is kept, so
    // that it fails the test and the second pass's Cholesky declines the block)
    let off = (0..k)
        .flat_map(|j| (0..k).map(move |i| (i, j)))
        .map(|(i, j)| (g2[0][(i, j)] - if i == j { 1.0 } else { 0.0 }).abs())
        .fold(0.0f64, |m, e| if e.is_nan() || e > m { e } else { m });
    if off <= SECOND_QR {
        return Some(r1);
    }
    let (r, s) = match small_cholesky(&g2[0], 0.5) {
        Some(r2) => (Some(&r2 * &r1), upper_inverse(&r2)),
        // not reached after a first pass that met its bound (`g2` is then the identity to about
        // 1e-6); undone all the same, for the vector-by-vector path
        None => (None, r1),
    };
    let _ = fold_rows(0, w, mw, &|_, w, mw| {
        right_multiply_rows(w, s.as_ref());
        right_multiply_rows(mw, s.as_ref());
        vec![]
    });
    r
}

/// [`cholesky_qr2`] makes its second pass only where the first left the block's Gram matrix
/// further than this from the identity: 16 units of round-off, below the `8e-15` to `2e-14` to
/// which the basis is M-orthonormal across blocks (docs/MATH.md, "Selective
/// reorthogonalisation").
pub(super) const SECOND_QR: f64 = 16.0 * f64::EPSILON;

/// The fewest rows of a thread's part in [`inner_products`].
pub(super) const PROJECT_ROWS: usize = 4096;

/// A block projected by [`project_block`]: its coefficients on the basis, whether a second pass
/// was needed, its columns' Euclidean norms before the projection, and its [`Gram`] after.
pub(super) struct Projected {
    pub(super) coef: Mat<f64>,
    pub(super) again: bool,
    pub(super) before: Vec<f64>,
    pub(super) gram: Gram,
}

/// Projects the block `w` out of the locked vectors `x` and the basis `v` (M-orthonormal, with
/// their M images), and writes `M w` into `mw`.
///
/// First the Lanczos recurrence: one pass of block classical Gram-Schmidt against the columns
/// `lo..` of `v`, the only ones that hold a large part of `OP V_j` ([`coupled_from`]). Then one
/// pass against `x` and all of `v`, which removes what the recurrence's round-off and the lost
/// orthogonality left. That pass is repeated only where it removed more than the fraction `1 -
/// REORTHOGONALIZE^2` of a column's squared M-norm (the criterion of Daniel, Gragg, Kaufman and
/// Stewart, with ARPACK's constant); where it removed less, Kahan and Parlett's bound makes the
/// column orthogonal to working precision (docs/MATH.md, "Selective reorthogonalisation"). The
/// squared M-norm before the pass is the one after it plus the squared coefficients removed
/// (Pythagoras in the M inner product), so the test costs no product beyond `M w`.
///
/// The steps that need only a row of the block are fused by rows ([`fold_rows`]): the
/// recurrence's coefficients with the norms before; the recurrence's subtraction with the full
/// pass's coefficients; the full pass's subtraction. The block's [`Gram`] is summed in the pass
/// that makes `M w` (docs/SCALING.md, "Orthogonalisation by leaves of rows").
pub(super) fn project_block(
    m: &SparseMatrix,
    (x, mx): (faer::MatRef<'_, f64>, faer::MatRef<'_, f64>),
    (v, mv): (faer::MatRef<'_, f64>, faer::MatRef<'_, f64>),
    lo: usize,
    mut w: faer::MatMut<'_, f64>,
    mut mw: faer::MatMut<'_, f64>,
) -> Projected {
    let (len, k) = (v.ncols(), w.ncols());
    let local = len - lo;
    // the recurrence's coefficients and the norms before
    let first = fold_rows(0, w.as_mut(), mw.as_mut(), &|r, w, _| {
        let mut c = Mat::<f64>::zeros(local, k);
        let mvl = mv.subrows(r, w.nrows()).subcols(lo, local);
        leaf_product(c.as_mut(), false, mvl.transpose(), w.as_ref(), 1.0);
        vec![c, leaf_squared_norms(w.as_ref())]
    });
    let before: Vec<f64> = (0..k).map(|j| first[1][(0, j)].sqrt()).collect();
    let mut coef = Mat::<f64>::zeros(len, k);
    coef.subrows_mut(lo, local).copy_from(&first[0]);
    // one pass against the locked vectors and the whole basis (after the recurrence's, in the
    // same pass over the rows), twice where the first removed too much
    let mut recurrence = Some(&first[0]);
    let mut again = false;
    let gram = loop {
        let sums = fold_rows(0, w.as_mut(), mw.as_mut(), &|r, mut w, _| {
            let n = w.nrows();
            if let Some(c) = recurrence {
                let vl = v.subrows(r, n).subcols(lo, local);
                leaf_product(w.as_mut(), true, vl, c.as_ref(), -1.0);
            }
            let mut cv = Mat::<f64>::zeros(len, k);
            let mut cx = Mat::<f64>::zeros(x.ncols(), k);
            leaf_product(
                cv.as_mut(),
                false,
                mv.subrows(r, n).transpose(),
                w.as_ref(),
                1.0,
            );
            leaf_product(
                cx.as_mut(),
                false,
                mx.subrows(r, n).transpose(),
                w.as_ref(),
                1.0,
            );
            vec![cv, cx]
        });
        let (on_basis, on_locked) = (&sums[0], &sums[1]);
        let _ = fold_rows(0, w.as_mut(), mw.as_mut(), &|r, mut w, _| {
            let n = w.nrows();
            leaf_product(w.as_mut(), true, v.subrows(r, n), on_basis.as_ref(), -1.0);
            leaf_product(w.as_mut(), true, x.subrows(r, n), on_locked.as_ref(), -1.0);
            vec![]
        });
        coef += on_basis;
        let (g, squares) =
            crate::csc::sym_mul_mat_gram_into(m, w.as_ref(), mw.as_mut()).expect("sizes checked");
        let gram = Gram {
            g,
            norms: squares.iter().map(|s| s.sqrt()).collect(),
        };
        let short = (0..k).any(|j| {
            let kept = gram.g[(j, j)];
            let gone = on_locked.col(j).squared_norm_l2() + on_basis.col(j).squared_norm_l2();
            !(kept >= REORTHOGONALIZE * REORTHOGONALIZE * (kept + gone))
        });
        if again || !short {
            break gram;
        }
        again = true;
        recurrence = None;
    };
    Projected {
        coef,
        again,
        before,
        gram,
    }
}
