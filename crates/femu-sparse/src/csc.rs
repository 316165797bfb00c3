//! Helpers on [`SparseMatrix`]: products, symmetry checks, conversion to dense.

use crate::{SparseError, SparseMatrix};
use faer::Mat;
use rayon::prelude::*;

/// `y = A x` for a CSC or CSR matrix.
///
/// # Errors
/// [`SparseError::DimensionMismatch`] if `x` or `y` do not match `A`.
pub fn mul_vec(a: &SparseMatrix, x: &[f64], y: &mut [f64]) -> Result<(), SparseError> {
    if x.len() != a.cols() {
        return Err(SparseError::DimensionMismatch {
            what: "x in A x",
            expected: a.cols(),
            got: x.len(),
        });
    }
    if y.len() != a.rows() {
        return Err(SparseError::DimensionMismatch {
            what: "y in y = A x",
            expected: a.rows(),
            got: y.len(),
        });
    }
    y.iter_mut().for_each(|v| *v = 0.0);
    for (v, (r, c)) in a.iter() {
        y[r] += v * x[c];
    }
    Ok(())
}

/// The `rows x cols` matrix of `entries` `(row, column, value)`, duplicates summed, rows sorted
/// in each column: a counting sort by column and a sort within each column, linear in the entries
/// for the short columns of FE matrices (sprs' `TriMat::to_csc` sorts them all). Indices must be
/// in range.
///
/// # Panics
/// If an index is out of range.
pub fn from_entries(rows: usize, cols: usize, entries: &[(usize, usize, f64)]) -> SparseMatrix {
    from_entry_iter(rows, cols, entries.iter().copied())
}

/// [`from_entries`] from an iterator that is walked twice (once to count the columns, once to
/// place the entries), so that a mirrored or permuted set of entries need not be stored.
///
/// # Panics
/// If an index is out of range.
pub fn from_entry_iter(
    rows: usize,
    cols: usize,
    entries: impl Iterator<Item = (usize, usize, f64)> + Clone,
) -> SparseMatrix {
    let mut ptr = vec![0usize; cols + 1];
    for (r, c, _) in entries.clone() {
        assert!(
            r < rows && c < cols,
            "entry ({r}, {c}) outside {rows} x {cols}"
        );
        ptr[c + 1] += 1;
    }
    for c in 0..cols {
        ptr[c + 1] += ptr[c];
    }
    let mut next = ptr.clone();
    let mut placed = vec![(0usize, 0.0f64); ptr[cols]];
    for (r, c, v) in entries {
        placed[next[c]] = (r, v);
        next[c] += 1;
    }
    let mut indptr = Vec::with_capacity(cols + 1);
    let mut indices = Vec::with_capacity(placed.len());
    let mut data = Vec::with_capacity(placed.len());
    indptr.push(0);
    for c in 0..cols {
        let column = &mut placed[ptr[c]..ptr[c + 1]];
        column.sort_unstable_by_key(|e| e.0);
        for &(r, v) in column.iter() {
            if indices.len() > indptr[c] && indices.last() == Some(&r) {
                *data.last_mut().expect("an entry was pushed") += v;
            } else {
                indices.push(r);
                data.push(v);
            }
        }
        indptr.push(indices.len());
    }
    SparseMatrix::new_csc((rows, cols), indptr, indices, data)
}

/// `P A P^T` for a square `a`: entry `(i, j)` moved to `(order[i], order[j])`
/// ([`from_entries`]).
///
/// # Panics
/// If `order` is shorter than `a` or maps outside it.
pub fn permuted(a: &SparseMatrix, order: &[usize]) -> SparseMatrix {
    from_entry_iter(
        a.rows(),
        a.cols(),
        entries(a).map(|(i, j, v)| (order[i], order[j], v)),
    )
}

/// The stored entries `(row, column, value)` of a CSC matrix, column by column: an iterator that
/// can be walked again ([`from_entry_iter`]).
pub fn entries(a: &SparseMatrix) -> impl Iterator<Item = (usize, usize, f64)> + Clone + '_ {
    let (ptr, rows, data) = (a.indptr().into_raw_storage(), a.indices(), a.data());
    (0..a.cols()).flat_map(move |j| (ptr[j]..ptr[j + 1]).map(move |k| (rows[k], j, data[k])))
}

/// `x^T A y` (for `A = M`, the mass inner product of docs/MATH.md).
///
/// # Errors
/// [`SparseError::DimensionMismatch`] if the vectors do not match `A`.
pub fn bilinear(a: &SparseMatrix, x: &[f64], y: &[f64]) -> Result<f64, SparseError> {
    if x.len() != a.rows() || y.len() != a.cols() {
        return Err(SparseError::DimensionMismatch {
            what: "x^T A y",
            expected: a.rows(),
            got: x.len().min(y.len()),
        });
    }
    Ok(a.iter().map(|(v, (r, c))| x[r] * v * y[c]).sum())
}

/// The largest relative asymmetry `max |a_ij - a_ji| / max |a_ij|` and where it occurs.
/// Returns `(0.0, 0, 0)` for a symmetric (or empty) matrix.
pub fn symmetry_defect(a: &SparseMatrix) -> (f64, usize, usize) {
    let scale = a
        .data()
        .par_iter()
        .fold(|| 0.0_f64, |m, v| m.max(v.abs()))
        .reduce(|| 0.0, f64::max);
    if scale == 0.0 || a.rows() != a.cols() {
        return (0.0, 0, 0);
    }
    // Each strictly lower entry against its mirror compares every pair once. When each of them
    // has a stored mirror and the strictly upper entries are as many, those mirrors are all of
    // them, and the worst pair is the answer; otherwise (an upper entry whose mirror is not
    // stored) every entry is compared with its mirror, a missing one counting as zero.
    let (worst, mirrored, upper) = mirror_walk(a, scale, true);
    if mirrored == upper {
        return worst;
    }
    mirror_walk(a, scale, false).0
}

/// The walk of [`symmetry_defect`] over the entries below the diagonal (`lower_only`) or all of
/// them: the worst relative difference to the mirror and where, how many of the walked entries
/// had a stored mirror, and how many entries lie above the diagonal.
fn mirror_walk(
    a: &SparseMatrix,
    scale: f64,
    lower_only: bool,
) -> ((f64, usize, usize), usize, usize) {
    let (ptr, idx, val) = (a.indptr(), a.indices(), a.data());
    let ptr = ptr.raw_storage();
    let n = a.outer_dims();
    // The mirror of (o, i) is entry o of outer vector i. Outer vectors are walked in order, so the
    // rows asked of one outer vector increase: one cursor per vector replaces a binary search per
    // entry. Pieces of outer vectors run in parallel, each with its own cursors.
    let piece = n.div_ceil(4 * rayon::current_num_threads()).max(1024);
    (0..n.div_ceil(piece))
        .into_par_iter()
        .map(|p| {
            let (lo, hi) = (p * piece, ((p + 1) * piece).min(n));
            let mut cursor = vec![usize::MAX; n];
            let mut worst = (0.0, 0, 0);
            let (mut mirrored, mut upper) = (0, 0);
            for o in lo..hi {
                for (&i, &v) in idx[ptr[o]..ptr[o + 1]].iter().zip(&val[ptr[o]..ptr[o + 1]]) {
                    if i < o {
                        upper += 1;
                    }
                    if lower_only && i <= o {
                        continue;
                    }
                    let inner = &idx[ptr[i]..ptr[i + 1]];
                    let c = &mut cursor[i];
                    if *c == usize::MAX {
                        *c = inner.partition_point(|&r| r < o);
                    }
                    while *c < inner.len() && inner[*c] < o {
                        *c += 1;
                    }
                    let t = if *c < inner.len() && inner[*c] == o {
                        mirrored += 1;
                        val[ptr[i] + *c]
                    } else {
                        0.0
                    };
                    let d = (v - t).abs() / scale;
                    if d > worst.0 {
                        worst = if a.is_csc() { (d, i, o) } else { (d, o, i) };
                    }
                }
            }
            (worst, mirrored, upper)
        })
        .reduce(
            || ((0.0, 0, 0), 0, 0),
            |x, y| {
                let worst = if y.0.0 > x.0.0 { y.0 } else { x.0 };
                (worst, x.1 + y.1, x.2 + y.2)
            },
        )
}

/// Checks that `A` is square, finite and symmetric to `tol` (relative to its largest entry).
///
/// # Errors
/// [`SparseError::DimensionMismatch`], [`SparseError::NonFinite`] or [`SparseError::NotSymmetric`].
pub fn check_symmetric(a: &SparseMatrix, name: &'static str, tol: f64) -> Result<(), SparseError> {
    if a.rows() != a.cols() {
        return Err(SparseError::DimensionMismatch {
            what: "square matrix",
            expected: a.rows(),
            got: a.cols(),
        });
    }
    // the first non-finite entry in storage order, by chunks on the threads (rayon's
    // `position_first` item by item ran at 1 GB/s)
    const CHUNK: usize = 1 << 16;
    let not_finite = |v: &f64| !v.is_finite();
    let first = a
        .data()
        .par_chunks(CHUNK)
        .enumerate()
        .find_first(|(_, c)| c.iter().any(not_finite))
        .and_then(|(i, c)| c.iter().position(not_finite).map(|q| i * CHUNK + q));
    if let Some(p) = first {
        let ptr = a.indptr();
        let outer = ptr.raw_storage().partition_point(|&q| q <= p) - 1;
        let inner = a.indices()[p];
        let (row, col) = if a.is_csc() {
            (inner, outer)
        } else {
            (outer, inner)
        };
        return Err(SparseError::NonFinite {
            matrix: name,
            row,
            col,
        });
    }
    let (defect, row, col) = symmetry_defect(a);
    if defect > tol {
        return Err(SparseError::NotSymmetric {
            matrix: name,
            row,
            col,
            defect,
        });
    }
    Ok(())
}

/// `f(position in a's values, position in pattern's values)` for every stored entry of `a`, or
/// [`SparseError::DimensionMismatch`] (its column and row) at the first entry of `a` that
/// `pattern` does not store: `M` on `K`'s pattern, for `K - sigma M` formed or read entry by
/// entry. Both in CSC with sorted row indices and the same number of columns. The eigensolver
/// finds the positions again each time instead of keeping them (a `usize` per entry of `M`,
/// 129 MB on the 199,200-DOF plate; docs/SCALING.md, "Memory").
///
/// # Errors
/// As above.
pub fn for_entries_within(
    pattern: &SparseMatrix,
    a: &SparseMatrix,
    mut f: impl FnMut(usize, usize),
) -> Result<(), SparseError> {
    let (kp, mp) = (pattern.indptr(), a.indptr());
    let (kp, mp) = (kp.raw_storage(), mp.raw_storage());
    for c in 0..pattern.cols().min(a.cols()) {
        let krows = &pattern.indices()[kp[c]..kp[c + 1]];
        let arows = &a.indices()[mp[c]..mp[c + 1]];
        if arows == krows {
            // the same column pattern (femu's consistent mass on the stiffness pattern)
            (0..arows.len()).for_each(|q| f(mp[c] + q, kp[c] + q));
            continue;
        }
        // both sorted: one walk through the pattern's column
        let mut pos = 0;
        for (pm, &r) in (mp[c]..mp[c + 1]).zip(arows) {
            while pos < krows.len() && krows[pos] < r {
                pos += 1;
            }
            if pos == krows.len() || krows[pos] != r {
                return Err(SparseError::DimensionMismatch {
                    what: "pattern of M inside the pattern of K (entry of M missing from K)",
                    expected: c,
                    got: r,
                });
            }
            f(pm, kp[c] + pos);
        }
    }
    Ok(())
}

/// The CSC matrix of the parts `(col_ptr, rows, values)` (sorted rows in each column) without
/// its off-diagonal entries that are exactly zero: femu's consistent mass, assembled on the
/// stiffness pattern, where an element's mass couples a node's `x` only to its neighbours' `x`,
/// so that two thirds of that pattern are zeros for solids (docs/SCALING.md, "Memory"). The
/// diagonal is kept whatever its value, and so is a NaN (the checks that read the matrix report
/// it). Columns are filled in parallel.
///
/// # Panics
/// If the parts are inconsistent (`col_ptr` not `cols + 1` nondecreasing offsets into `rows`
/// and `values` of equal length): they come from a valid pattern.
pub fn without_zeros_of(
    shape: (usize, usize),
    col_ptr: &[usize],
    rows: &[usize],
    values: &[f64],
) -> SparseMatrix {
    let (ptr, rows, values) = kept_entries(shape.1, col_ptr, rows, values);
    SparseMatrix::new_csc(shape, ptr, rows, values)
}

/// The compressed parts (pointers, inner indices, values) of `outer` compressed vectors without
/// their entries that are exactly zero off the diagonal ([`without_zeros_of`]).
fn kept_entries(
    outer: usize,
    col_ptr: &[usize],
    rows: &[usize],
    values: &[f64],
) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
    let cols = outer;
    assert!(col_ptr.len() == cols + 1 && rows.len() == values.len());
    let keep = |c: usize, q: usize| rows[q] == c || values[q] != 0.0;
    let counts: Vec<usize> = (0..cols)
        .into_par_iter()
        .map(|c| (col_ptr[c]..col_ptr[c + 1]).filter(|&q| keep(c, q)).count())
        .collect();
    let mut ptr = Vec::with_capacity(cols + 1);
    ptr.push(0);
    for n in &counts {
        ptr.push(ptr.last().copied().unwrap_or(0) + n);
    }
    let nnz = ptr[cols];
    let (mut out_rows, mut out_values) = (vec![0usize; nnz], vec![0.0; nnz]);
    // pieces of about CHUNK kept entries, each filling its own slices of the output
    const CHUNK: usize = 1 << 16;
    let mut pieces = Vec::new();
    let (mut r_rest, mut v_rest) = (&mut out_rows[..], &mut out_values[..]);
    let mut first = 0;
    while first < cols {
        let mut last = first + 1;
        while last < cols && ptr[last] - ptr[first] < CHUNK {
            last += 1;
        }
        let len = ptr[last] - ptr[first];
        let (r, rr) = std::mem::take(&mut r_rest).split_at_mut(len);
        let (v, vr) = std::mem::take(&mut v_rest).split_at_mut(len);
        (r_rest, v_rest) = (rr, vr);
        pieces.push((first..last, r, v));
        first = last;
    }
    pieces.into_par_iter().for_each(|(range, r, v)| {
        let mut at = 0;
        for c in range {
            for q in col_ptr[c]..col_ptr[c + 1] {
                if keep(c, q) {
                    r[at] = rows[q];
                    v[at] = values[q];
                    at += 1;
                }
            }
        }
    });
    (ptr, out_rows, out_values)
}

/// `a` without its entries that are exactly zero off the diagonal ([`without_zeros_of`]), stored
/// as `a` is (CSC or CSR).
pub fn without_zeros(a: &SparseMatrix) -> SparseMatrix {
    let ptr = a.indptr();
    let (ptr, idx, val) = kept_entries(a.outer_dims(), ptr.raw_storage(), a.indices(), a.data());
    if a.is_csc() {
        SparseMatrix::new_csc(a.shape(), ptr, idx, val)
    } else {
        SparseMatrix::new(a.shape(), ptr, idx, val)
    }
}

/// The diagonal of a square matrix (zeros where nothing is stored).
pub fn diagonal(a: &SparseMatrix) -> Vec<f64> {
    let mut d = vec![0.0; a.rows().min(a.cols())];
    for (v, (r, c)) in a.iter() {
        if r == c {
            d[r] = *v;
        }
    }
    d
}

/// A dense copy of a sparse matrix, for small problems and cross-checks.
pub fn to_dense(a: &SparseMatrix) -> Mat<f64> {
    let mut d = Mat::zeros(a.rows(), a.cols());
    for (v, (r, c)) in a.iter() {
        d[(r, c)] += *v;
    }
    d
}

/// `Y = A X` for a symmetric `A` stored in CSC with both triangles (as femu's `K` and `M` are),
/// for a block of vectors `X` (`n x k`), in parallel over rows.
///
/// Symmetry lets column `i` of the CSC storage serve as row `i`, so every output entry is an
/// independent dot product: no scatter, no atomics, and one pass over `A` for all `k` vectors.
///
/// # Errors
/// [`SparseError::DimensionMismatch`] if `A` is not square or `X` does not match it.
pub fn sym_mul_mat(a: &SparseMatrix, x: faer::MatRef<'_, f64>) -> Result<Mat<f64>, SparseError> {
    let mut y = Mat::zeros(a.rows(), x.ncols());
    sym_mul_mat_into(a, x, y.as_mut())?;
    Ok(y)
}

/// [`sym_mul_mat`] into the columns of `y` (`n x k`, overwritten): for a caller that keeps the
/// products where they are used.
///
/// # Errors
/// [`SparseError::DimensionMismatch`] if `A` is not square or `X`, `Y` do not match it.
pub fn sym_mul_mat_into(
    a: &SparseMatrix,
    x: faer::MatRef<'_, f64>,
    y: faer::MatMut<'_, f64>,
) -> Result<(), SparseError> {
    sym_mul_mat_values_into(a, a.data(), x, y)
}

/// [`sym_mul_mat_into`] for the symmetric matrix with `a`'s pattern and the values `values`
/// (one per stored entry, in `a`'s order): a matrix formed entry by entry on another's pattern,
/// such as `Z = K - lambda M` on `K`'s, multiplied in one pass instead of one per term.
///
/// # Errors
/// [`SparseError::DimensionMismatch`] if `A` is not square, `values` is not one per stored entry,
/// or `X`, `Y` do not match `A`.
pub fn sym_mul_mat_values_into(
    a: &SparseMatrix,
    values: &[f64],
    x: faer::MatRef<'_, f64>,
    y: faer::MatMut<'_, f64>,
) -> Result<(), SparseError> {
    check_block(a, values, x, y.as_ref())?;
    block_product(a, values, x, y, false);
    Ok(())
}

/// [`sym_mul_mat_into`] that also returns, from the same pass, `Y^T X` (`k x k`) and the squared
/// Euclidean norms of `X`'s columns: for the eigensolver, whose block's Gram matrix `(M W)^T W`
/// is the next thing it needs (docs/SCALING.md, "Orthogonalisation by leaves of rows"). The
/// sums are added in a tree fixed by the number of rows (the same for any number of threads).
/// Blocks wider than eight vectors take a second pass for them.
///
/// # Errors
/// [`SparseError::DimensionMismatch`] if `A` is not square or `X`, `Y` do not match it.
pub fn sym_mul_mat_gram_into(
    a: &SparseMatrix,
    x: faer::MatRef<'_, f64>,
    mut y: faer::MatMut<'_, f64>,
) -> Result<(Mat<f64>, Vec<f64>), SparseError> {
    check_block(a, a.data(), x, y.as_ref())?;
    let k = x.ncols();
    if let Some(sums) = block_product(a, a.data(), x, y.as_mut(), true) {
        let g = Mat::<f64>::from_fn(k, k, |r, c| sums[r * k + c]);
        return Ok((g, sums[k * k..].to_vec()));
    }
    let mut g = Mat::<f64>::zeros(k, k);
    faer::linalg::matmul::matmul(
        g.as_mut(),
        faer::Accum::Replace,
        y.as_ref().transpose(),
        x,
        1.0,
        faer::get_global_parallelism(),
    );
    let squares = (0..k).map(|j| x.col(j).squared_norm_l2()).collect();
    Ok((g, squares))
}

/// The checks of [`sym_mul_mat_values_into`]: one value per stored entry, `A` square, `X` and
/// `Y` with `A`'s rows and as many columns.
fn check_block(
    a: &SparseMatrix,
    values: &[f64],
    x: faer::MatRef<'_, f64>,
    y: faer::MatRef<'_, f64>,
) -> Result<(), SparseError> {
    let n = a.rows();
    if values.len() != a.nnz() {
        return Err(SparseError::DimensionMismatch {
            what: "values on the pattern of A (one per stored entry)",
            expected: a.nnz(),
            got: values.len(),
        });
    }
    if a.cols() != n || x.nrows() != n || y.nrows() != n || y.ncols() != x.ncols() {
        return Err(SparseError::DimensionMismatch {
            what: "X and Y in Y = A X (A square, X and Y with A's rows and as many columns)",
            expected: n,
            got: if a.cols() != n {
                a.cols()
            } else if x.nrows() != n {
                x.nrows()
            } else if y.nrows() != n {
                y.nrows()
            } else {
                y.ncols()
            },
        });
    }
    Ok(())
}

/// `Y = A X` (sizes checked by the callers); with `gram` and at most `WIDEST_KERNEL` columns,
/// also the sums of [`sym_mul_mat_gram_into`] (`Y^T X` row by row, then the squared norms).
fn block_product(
    a: &SparseMatrix,
    values: &[f64],
    x: faer::MatRef<'_, f64>,
    mut y: faer::MatMut<'_, f64>,
    gram: bool,
) -> Option<Vec<f64>> {
    let (n, k) = (a.rows(), x.ncols());
    let gram = gram && k <= WIDEST_KERNEL;
    if k == 0 || n == 0 {
        return gram.then(|| vec![0.0; k * k + k]);
    }
    // Each piece of the block is copied row-major (the values of one row of `X` together, so
    // that an entry of `A` reads them from one cache line), on the rayon threads; the products
    // are written straight into `Y`'s columns. Blocks wider than `WIDEST_KERNEL` are taken that
    // many columns at a time, so that every piece has a kernel of known width (`A` is read once
    // per piece).
    let owned_x = (x.row_stride() != 1).then(|| x.to_owned());
    let x = owned_x.as_ref().map_or(x, |o| o.as_ref());
    let mut owned_y = (y.row_stride() != 1).then(|| Mat::<f64>::zeros(n, k));
    let (ptr, idx) = (a.indptr(), a.indices());
    let ptr = ptr.raw_storage();
    let mut xt = vec![0.0; if k > 1 { n * k.min(WIDEST_KERNEL) } else { 0 }];
    let mut sums = None;
    {
        let mut out = match &mut owned_y {
            Some(o) => o.as_mut(),
            None => y.as_mut(),
        };
        for first in (0..k).step_by(WIDEST_KERNEL) {
            let w = (k - first).min(WIDEST_KERNEL);
            let xs: Vec<&[f64]> = (first..first + w)
                .map(|j| {
                    x.col(j)
                        .try_as_col_major()
                        .expect("unit row stride")
                        .as_slice()
                })
                .collect();
            const ROWS: usize = 1024;
            let xt = if w == 1 {
                xs[0]
            } else {
                let xt = &mut xt[..n * w];
                xt.par_chunks_mut(w * ROWS)
                    .enumerate()
                    .for_each(|(c, chunk)| {
                        for (i, row) in chunk.chunks_exact_mut(w).enumerate() {
                            for (v, col) in row.iter_mut().zip(&xs) {
                                *v = col[c * ROWS + i];
                            }
                        }
                    });
                &xt[..]
            };
            let part = out.as_mut().subcols_mut(first, w);
            let a = (ptr, idx, values);
            sums = match w {
                1 => sym_mul_rows_into_cols::<1>(a, xt, 0, part, gram),
                2 => sym_mul_rows_into_cols::<2>(a, xt, 0, part, gram),
                3 => sym_mul_rows_into_cols::<3>(a, xt, 0, part, gram),
                4 => sym_mul_rows_into_cols::<4>(a, xt, 0, part, gram),
                5 => sym_mul_rows_into_cols::<5>(a, xt, 0, part, gram),
                6 => sym_mul_rows_into_cols::<6>(a, xt, 0, part, gram),
                7 => sym_mul_rows_into_cols::<7>(a, xt, 0, part, gram),
                _ => sym_mul_rows_into_cols::<8>(a, xt, 0, part, gram),
            };
        }
    }
    if let Some(o) = owned_y {
        y.copy_from(&o);
    }
    sums
}

/// The rows `first..` of `Y = A X` for a symmetric `A` (its column pointers, row indices and
/// values; CSC with both triangles, so column `i` serves as row `i`) and `K` vectors stored
/// row-major in `xt`, into the column-major `y` (`K` columns), by halves of the rows on the
/// rayon threads down to 4096 rows, each row by [`row_sums`] (docs/SCALING.md, "Sparse products
/// by blocks of known width"), as [`sym_mul_rows`] does: the two give the same bits. With
/// `gram`, also these rows' part
/// of `Y^T X` (row by row) and of the squared norms of `X`'s columns, the halves' parts added.
fn sym_mul_rows_into_cols<const K: usize>(
    (ptr, idx, val): (&[usize], &[usize], &[f64]),
    xt: &[f64],
    first: usize,
    y: faer::MatMut<'_, f64>,
    gram: bool,
) -> Option<Vec<f64>> {
    const LEAF: usize = 4096;
    let rows = y.nrows();
    if rows > LEAF {
        let half = rows / 2;
        let (top, bottom) = y.split_at_row_mut(half);
        let (a, b) = rayon::join(
            || sym_mul_rows_into_cols::<K>((ptr, idx, val), xt, first, top, gram),
            || sym_mul_rows_into_cols::<K>((ptr, idx, val), xt, first + half, bottom, gram),
        );
        return a.zip(b).map(|(mut a, b)| {
            a.iter_mut().zip(b).for_each(|(a, b)| *a += b);
            a
        });
    }
    let mut out: Vec<&mut [f64]> = y
        .col_iter_mut()
        .map(|c| {
            c.try_as_col_major_mut()
                .expect("unit row stride")
                .as_slice_mut()
        })
        .collect();
    let mut g = [[0.0; K]; K];
    let mut squares = [0.0; K];
    for i in 0..rows {
        let acc = row_sums::<K>((ptr, idx, val), xt, first + i);
        for (o, a) in out.iter_mut().zip(acc) {
            o[i] = a;
        }
        if gram {
            let own: &[f64; K] = xt[(first + i) * K..(first + i + 1) * K]
                .try_into()
                .expect("K values per row");
            for r in 0..K {
                for c in 0..K {
                    g[r][c] += acc[r] * own[c];
                }
                squares[r] += own[r] * own[r];
            }
        }
    }
    gram.then(|| g.iter().flatten().chain(&squares).copied().collect())
}

/// Row `i` of `A X` for a symmetric `A` (its column pointers, row indices and values; column `i`
/// serves as row `i`) and `K` vectors stored row-major in `x`: each entry of `A` updates `K`
/// accumulators held in registers, in the order the entries are stored. The one loop of both
/// kernels, [`sym_mul_rows_of`] and [`sym_mul_rows_into_cols`], so that they give the same bits.
#[inline(always)]
fn row_sums<const K: usize>(
    (ptr, idx, val): (&[usize], &[usize], &[f64]),
    x: &[f64],
    i: usize,
) -> [f64; K] {
    let mut acc = [0.0; K];
    let (lo, hi) = (ptr[i], ptr[i + 1]);
    for (&c, &v) in idx[lo..hi].iter().zip(&val[lo..hi]) {
        let xr: &[f64; K] = x[c * K..(c + 1) * K].try_into().expect("K values per row");
        for r in 0..K {
            acc[r] += v * xr[r];
        }
    }
    acc
}

/// The widest block [`sym_mul_rows`] has a kernel of known width for (every width up to it has
/// one).
const WIDEST_KERNEL: usize = 8;

/// `Y = A X` for a symmetric `A` (CSC, both triangles) and `k` vectors stored row-major
/// (`x[i * k + j]` is entry `i` of vector `j`), in parallel over rows: the kernel of
/// [`sym_mul_mat`] for iterative solvers that keep their vectors row-major.
///
/// # Errors
/// [`SparseError::DimensionMismatch`] if `A` is not square or the buffers are not `n k` long.
pub fn sym_mul_rows(
    a: &SparseMatrix,
    x: &[f64],
    k: usize,
    y: &mut [f64],
) -> Result<(), SparseError> {
    let n = a.rows();
    if a.cols() != n || x.len() != n * k || y.len() != n * k {
        return Err(SparseError::DimensionMismatch {
            what: "row-major block in A X (A square, n k values)",
            expected: n * k,
            got: if a.cols() != n {
                a.cols() * k
            } else {
                x.len().min(y.len())
            },
        });
    }
    rows_with(a, a.data(), x, k, y);
    Ok(())
}

/// [`sym_mul_rows`] with the values `val` on `a`'s pattern (sizes checked by the callers).
fn rows_with(a: &SparseMatrix, val: &[f64], x: &[f64], k: usize, y: &mut [f64]) {
    match k {
        0 => {}
        1 => sym_mul_rows_of::<1>(a, val, x, y),
        2 => sym_mul_rows_of::<2>(a, val, x, y),
        3 => sym_mul_rows_of::<3>(a, val, x, y),
        4 => sym_mul_rows_of::<4>(a, val, x, y),
        5 => sym_mul_rows_of::<5>(a, val, x, y),
        6 => sym_mul_rows_of::<6>(a, val, x, y),
        7 => sym_mul_rows_of::<7>(a, val, x, y),
        8 => sym_mul_rows_of::<8>(a, val, x, y),
        _ => {
            let (ptr, idx) = (a.indptr(), a.indices());
            let ptr = ptr.raw_storage();
            y.par_chunks_mut(k)
                .enumerate()
                .with_min_len(512)
                .for_each(|(i, row)| {
                    row.fill(0.0);
                    for p in ptr[i]..ptr[i + 1] {
                        let (c, v) = (idx[p], val[p]);
                        let xr = &x[c * k..(c + 1) * k];
                        for (r, xv) in row.iter_mut().zip(xr) {
                            *r += v * xv;
                        }
                    }
                });
        }
    }
}

/// [`sym_mul_rows`] for a block width `K` known at compile time (the eigensolver's blocks, a
/// few vectors): each entry of `A` updates `K` accumulators held in registers, where a width
/// known only at run time loops over them. 3.1x faster for `K = 4` on the 199,200-DOF plate's
/// `M` (docs/SCALING.md, "Sparse products by blocks of known width").
fn sym_mul_rows_of<const K: usize>(a: &SparseMatrix, val: &[f64], x: &[f64], y: &mut [f64]) {
    let (ptr, idx) = (a.indptr(), a.indices());
    let ptr = ptr.raw_storage();
    y.par_chunks_mut(K)
        .enumerate()
        .with_min_len(512)
        .for_each(|(i, row)| {
            row.copy_from_slice(&row_sums::<K>((ptr, idx, val), x, i));
        });
}

#[cfg(test)]
mod tests {
    use super::*;
    use sprs::TriMat;

    /// An `n x n` CSC matrix from its `(row, column, value)` entries.
    fn from_entries(n: usize, entries: &[(usize, usize, f64)]) -> SparseMatrix {
        let mut t = TriMat::new((n, n));
        for &(r, c, v) in entries {
            t.add_triplet(r, c, v);
        }
        t.to_csc()
    }

    /// The counting-sort builder against sprs' `TriMat::to_csc` (duplicates summed, rows sorted)
    /// on scattered entries with repeats, and `permuted` against the dense permutation.
    #[test]
    fn counting_builder_and_permutation() {
        let n = 9;
        let mut entries = Vec::new();
        let mut x: u64 = 7;
        for k in 0..200 {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let (r, c) = ((x >> 33) as usize % n, (x >> 17) as usize % n);
            entries.push((r, c, k as f64 * 0.5 - 3.0));
        }
        let ours = super::from_entries(n, n, &entries);
        let reference = from_entries(n, &entries);
        assert_eq!(
            ours.indptr().raw_storage(),
            reference.indptr().raw_storage()
        );
        assert_eq!(ours.indices(), reference.indices());
        for (a, b) in ours.data().iter().zip(reference.data()) {
            assert!((a - b).abs() < 1e-12);
        }
        let order = [3, 0, 8, 1, 7, 2, 6, 4, 5];
        let p = super::permuted(&ours, &order);
        let (d, dp) = (to_dense(&ours), to_dense(&p));
        for i in 0..n {
            for j in 0..n {
                assert_eq!(dp[(order[i], order[j])], d[(i, j)]);
            }
        }
    }

    fn sample() -> SparseMatrix {
        let mut t = TriMat::new((3, 3));
        t.add_triplet(0, 0, 4.0);
        t.add_triplet(1, 0, 1.0);
        t.add_triplet(0, 1, 1.0);
        t.add_triplet(2, 2, 2.0);
        t.to_csc()
    }

    #[test]
    fn products_match_hand_computation() {
        let a = sample();
        let mut y = [0.0; 3];
        mul_vec(&a, &[1.0, 2.0, 3.0], &mut y).unwrap();
        assert_eq!(y, [6.0, 1.0, 6.0]);
        // x^T A x = 4 + 2*1*2 + 2*9 = 26
        assert_eq!(
            bilinear(&a, &[1.0, 2.0, 3.0], &[1.0, 2.0, 3.0]).unwrap(),
            4.0 + 4.0 + 18.0
        );
        assert!(mul_vec(&a, &[1.0], &mut y).is_err());
    }

    #[test]
    fn symmetry_checks_find_the_offending_entry() {
        let a = sample();
        assert_eq!(symmetry_defect(&a).0, 0.0);
        let mut t = TriMat::new((3, 3));
        t.add_triplet(0, 0, 4.0);
        t.add_triplet(2, 1, 1.0);
        let b: SparseMatrix = t.to_csc();
        match check_symmetric(&b, "K", 1e-12) {
            Err(SparseError::NotSymmetric {
                row: 2,
                col: 1,
                defect,
                ..
            }) => assert_eq!(defect, 0.25),
            other => panic!("unexpected {other:?}"),
        }
        // an entry above the diagonal without its mirror (the walk below the diagonal alone
        // would not see it), beside a mismatched pair and a matched one
        let pairs = [
            (0, 0, 8.0),
            (1, 0, 2.0),
            (0, 1, 2.0),
            (3, 1, 1.0),
            (1, 3, 1.5),
        ];
        let u = from_entries(4, &[&pairs[..], &[(0, 3, -3.0)]].concat());
        assert_eq!(symmetry_defect(&u), (3.0 / 8.0, 0, 3));
        // without it, the mismatched pair, where its entry below the diagonal is
        assert_eq!(symmetry_defect(&from_entries(4, &pairs)), (0.5 / 8.0, 3, 1));
        // a NaN, found where it is stored, after a finite entry
        let c = from_entries(3, &[(0, 0, 1.0), (2, 1, f64::NAN), (1, 2, f64::NAN)]);
        assert!(matches!(
            check_symmetric(&c, "M", 1e-12),
            Err(SparseError::NonFinite { row: 2, col: 1, .. })
        ));
    }

    /// Positions of `M`'s entries in `K`'s pattern: identical columns, a sub-pattern, and an
    /// entry `K` lacks (named by its column and row).
    #[test]
    fn entries_within_a_pattern_are_found_or_named() {
        let ones = |at: &[(usize, usize)]| -> Vec<(usize, usize, f64)> {
            at.iter().map(|&(r, c)| (r, c, 1.0)).collect()
        };
        let k = from_entries(
            3,
            &ones(&[(0, 0), (1, 0), (2, 0), (0, 1), (1, 1), (2, 2), (0, 2)]),
        );
        let m = from_entries(3, &ones(&[(0, 0), (1, 0), (2, 0), (1, 1), (2, 2)]));
        let mut pairs = vec![];
        for_entries_within(&k, &m, |pm, pk| pairs.push((pm, pk))).unwrap();
        // k's values: col 0 rows 0,1,2 at 0..3; col 1 rows 0,1 at 3,4; col 2 rows 0,2 at 5,6
        assert_eq!(pairs, [(0, 0), (1, 1), (2, 2), (3, 4), (4, 6)]);
        let bad = from_entries(3, &[(1, 2, 1.0)]);
        assert!(matches!(
            for_entries_within(&k, &bad, |_, _| {}),
            Err(SparseError::DimensionMismatch {
                expected: 2,
                got: 1,
                ..
            })
        ));
    }

    /// The matrix without its off-diagonal zeros, against a filter of its entries written here:
    /// enough entries for several parallel pieces, one column longer than a piece, zeros on the
    /// diagonal (kept), a NaN (kept), an empty column.
    #[test]
    fn zeros_off_the_diagonal_are_dropped_and_nothing_else() {
        let n = 3000;
        let mut entries = vec![];
        for c in 0..n {
            if c == 17 {
                continue; // an empty column
            }
            let len = if c == 5 { n } else { 100 };
            for q in 1..len {
                let r = (c + q * 37) % n; // never c: 37 and n coprime
                let v = match (r * 7 + c * 3) % 4 {
                    0 => 0.0,
                    1 => -(q as f64) - 0.5,
                    _ => 1.0 + r as f64,
                };
                entries.push((r, c, if r == 11 && c == 5 { f64::NAN } else { v }));
            }
            entries.push((c, c, if c % 10 == 0 { 0.0 } else { 2.0 }));
        }
        entries.sort_by_key(|&(r, c, _)| (c, r));
        entries.dedup_by_key(|e| (e.0, e.1));
        let a = from_entries(n, &entries);
        assert_eq!(a.nnz(), entries.len(), "the zeros stored");
        assert!(a.nnz() > 3 * (1 << 16), "several pieces of kept entries");
        let kept: Vec<&(usize, usize, f64)> = entries
            .iter()
            .filter(|(r, c, v)| r == c || *v != 0.0)
            .collect();
        assert!(kept.len() < a.nnz() * 4 / 5, "zeros to drop");
        let b = without_zeros(&a);
        assert_eq!(b.shape(), (n, n));
        assert_eq!(b.nnz(), kept.len());
        for (q, (&&(r, c, v), (bv, (br, bc)))) in kept.iter().zip(b.iter()).enumerate() {
            assert_eq!((br, bc), (r, c), "entry {q}");
            assert!(*bv == v || (v.is_nan() && bv.is_nan()), "entry {q}");
        }
        assert!(b.get(17, 17).is_none() && b.get(20, 20) == Some(&0.0));
        // the same matrix stored by rows: the same entries kept, still by rows
        let c = without_zeros(&a.to_csr());
        assert!(c.is_csr() && c.nnz() == kept.len());
        for (q, (&&(r, col, v), (cv, rc))) in kept.iter().zip(c.to_csc().iter()).enumerate() {
            assert_eq!(rc, (r, col), "entry {q} by rows");
            assert!(*cv == v || (v.is_nan() && cv.is_nan()), "entry {q} by rows");
        }
    }

    /// [`sym_mul_mat_gram_into`] on more rows than one leaf (so that the halves' sums are
    /// added), for widths with a kernel (1, 4, 8) and a wider one (11, the second pass), with
    /// `X` as a column-major block and as a strided view: `Y = A X`, `Y^T X` and the squared
    /// norms against sums over the band written here.
    #[test]
    fn block_product_with_its_gram_matches_the_sums_by_hand() {
        let n = 9001;
        // a symmetric band: a_ii = 4 + i % 3, a_ij = -1 / (1 + |i - j|) for 0 < |i - j| <= 3
        let entry = |i: usize, j: usize| {
            let d = i.abs_diff(j);
            if d == 0 {
                4.0 + (i % 3) as f64
            } else {
                -1.0 / (1.0 + d as f64)
            }
        };
        let mut t = TriMat::new((n, n));
        for i in 0..n {
            for j in i.saturating_sub(3)..(i + 4).min(n) {
                t.add_triplet(i, j, entry(i, j));
            }
        }
        let a: SparseMatrix = t.to_csc();
        for k in [1, 4, 8, 11] {
            let value = |i: usize, j: usize| ((i * 7 + j * 5) % 23) as f64 - 11.0;
            let x = Mat::<f64>::from_fn(n, k, value);
            let strided = Mat::<f64>::from_fn(k, n, |j, i| value(i, j));
            let y_ref = Mat::<f64>::from_fn(n, k, |i, j| {
                (i.saturating_sub(3)..(i + 4).min(n))
                    .map(|c| entry(i, c) * x[(c, j)])
                    .sum()
            });
            for (form, xv) in [("columns", x.as_ref()), ("strided", strided.transpose())] {
                let mut y = Mat::<f64>::from_fn(n, k, |_, _| f64::NAN);
                let (g, squares) = sym_mul_mat_gram_into(&a, xv, y.as_mut()).unwrap();
                for i in 0..n {
                    for j in 0..k {
                        let e = y_ref[(i, j)];
                        assert!(
                            (y[(i, j)] - e).abs() <= 1e-13 * e.abs().max(1.0),
                            "{form} {k}"
                        );
                    }
                }
                for r in 0..k {
                    let sq: f64 = (0..n).map(|i| x[(i, r)] * x[(i, r)]).sum();
                    assert!(
                        (squares[r] - sq).abs() <= 1e-12 * sq,
                        "{form} {k}: norm {r}"
                    );
                    for c in 0..k {
                        let expected: f64 = (0..n).map(|i| y_ref[(i, r)] * x[(i, c)]).sum();
                        let scale: f64 = (0..n).map(|i| (y_ref[(i, r)] * x[(i, c)]).abs()).sum();
                        assert!(
                            (g[(r, c)] - expected).abs() <= 1e-13 * scale,
                            "{form} {k}: G[{r}, {c}] = {} against {expected}",
                            g[(r, c)]
                        );
                    }
                }
            }
        }
        let (x, mut y) = (Mat::<f64>::zeros(n, 2), Mat::<f64>::zeros(n, 3));
        assert!(sym_mul_mat_gram_into(&a, x.as_ref(), y.as_mut()).is_err());
    }

    /// Every block width, those with a kernel of their own (1 to 8) and the wider ones, taken 8
    /// columns at a time by `sym_mul_mat` and in one loop by `sym_mul_rows`, against the dense
    /// product computed here by hand, on a symmetric matrix with both triangles and rows of
    /// different lengths.
    #[test]
    fn block_products_match_the_dense_product_for_every_width() {
        let n = 37;
        let mut t = TriMat::new((n, n));
        for i in 0..n {
            t.add_triplet(i, i, 3.0 + i as f64);
            for j in 0..i {
                if (i * 7 + j * 3) % 5 == 0 {
                    let v = ((i * 13 + j * 5) % 11) as f64 - 5.0;
                    t.add_triplet(i, j, v);
                    t.add_triplet(j, i, v);
                }
            }
        }
        let a: SparseMatrix = t.to_csc();
        let dense = to_dense(&a);
        for k in 1..=19 {
            let x = Mat::<f64>::from_fn(n, k, |i, j| ((i * 3 + j * 17) % 19) as f64 - 9.0);
            let y = sym_mul_mat(&a, x.as_ref()).unwrap();
            let xt: Vec<f64> = (0..n * k).map(|p| x[(p / k, p % k)]).collect();
            let mut yt = vec![f64::NAN; n * k];
            sym_mul_rows(&a, &xt, k, &mut yt).unwrap();
            for i in 0..n {
                for j in 0..k {
                    let expected: f64 = (0..n).map(|c| dense[(i, c)] * x[(c, j)]).sum();
                    for (path, got) in [("sym_mul_mat", y[(i, j)]), ("sym_mul_rows", yt[i * k + j])]
                    {
                        assert!(
                            (got - expected).abs() <= 1e-12 * expected.abs().max(1.0),
                            "{path}, width {k}: ({i}, {j}) {got} against {expected}"
                        );
                    }
                }
            }
        }
        let x = Mat::<f64>::zeros(n + 1, 4);
        assert!(sym_mul_mat(&a, x.as_ref()).is_err());
        // other values on the same pattern: A - 0.7 B for B = the pattern with values 1, 2, 3,
        // ... in storage order (symmetric, as both triangles hold the same index sums), against
        // the dense A - 0.7 B by hand
        let b: Vec<f64> = a
            .iter()
            .map(|(_, (r, c))| 1.0 + ((r + c) % 7) as f64)
            .collect();
        let values: Vec<f64> = a.data().iter().zip(&b).map(|(v, w)| v - 0.7 * w).collect();
        let mut bd = Mat::<f64>::zeros(n, n);
        for (&w, (_, (r, c))) in b.iter().zip(a.iter()) {
            bd[(r, c)] = w;
        }
        for k in [1, 4, 11] {
            let x = Mat::<f64>::from_fn(n, k, |i, j| ((i * 5 + j * 3) % 13) as f64 - 6.0);
            let mut y = Mat::<f64>::from_fn(n, k, |_, _| f64::NAN);
            sym_mul_mat_values_into(&a, &values, x.as_ref(), y.as_mut()).unwrap();
            for i in 0..n {
                for j in 0..k {
                    let expected: f64 = (0..n)
                        .map(|c| (dense[(i, c)] - 0.7 * bd[(i, c)]) * x[(c, j)])
                        .sum();
                    assert!(
                        (y[(i, j)] - expected).abs() <= 1e-12 * expected.abs().max(1.0),
                        "values, width {k}: ({i}, {j}) {} against {expected}",
                        y[(i, j)]
                    );
                }
            }
        }
        let (x, mut y) = (Mat::<f64>::zeros(n, 2), Mat::<f64>::zeros(n, 2));
        let err = sym_mul_mat_values_into(&a, &values[1..], x.as_ref(), y.as_mut()).unwrap_err();
        assert!(err.to_string().contains("one per stored entry"), "{err}");
    }
}
