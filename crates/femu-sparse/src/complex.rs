//! Complex linear combinations of real sparse matrices and their direct solution: the dynamic
//! stiffness `A(w) = (1 + i eta) K + i K_4 + i w C - w^2 M` of a frequency response, formed and
//! factored once per frequency line on one pattern (docs/MATH.md, "Frequency responses, directly").
//!
//! The matrices are stored once on the union of their patterns ([`Combination::new`]), which is
//! analysed once (the nested-dissection ordering and supernodal structure of femu's real
//! factorizations). Each line writes `sum_j c_j A_j` with its complex coefficients into that
//! pattern and factors it as `A = L D L^T` (complex symmetric: transposed, not conjugated, so
//! that neither faer's `LDL^H` nor a Hermitian solver applies) by a multifrontal elimination over
//! the supernodes, each front's pivot block factored by panels with faer's complex GEMM for the
//! trailing updates. There is no pivoting: the matrix is indefinite near and above the first
//! resonance, as `K - sigma M` is in the eigensolver's shifts, and a pivot of a damped dynamic
//! stiffness is zero only by accident. The normwise backward error of each solve is measured, and a
//! solve above a few units of round-off is refined once; where a pivot is zero, or the refined backward error
//! is above [`LDLT_BACKWARD_ERROR`], the line is factored again by faer's sparse `LU` with partial
//! pivoting (robust, an order of magnitude slower: its column ordering does not see the
//! symmetry), and the solve says so.
use crate::ordering::{Ordering, Pattern, pattern_ordering};
use crate::{SparseError, SparseMatrix};
use faer::linalg::matmul::matmul;
use faer::linalg::matmul::triangular::{BlockStructure, matmul as triangular_matmul};
use faer::linalg::solvers::SolveCore;
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Accum, Conj, Mat, MatMut, Par, Side, c64};
use std::sync::OnceLock;

/// Above this refined backward error an `LDL^T` solve is redone with the pivoted `LU`.
pub const LDLT_BACKWARD_ERROR: f64 = 1e-10;

/// A solve whose backward error is above this (a few units of round-off) is refined once.
pub const REFINED_BELOW: f64 = 1e-14;

/// Columns of a front's pivot block eliminated before their trailing update (a GEMM of this
/// inner dimension: wide enough that the update is not bound by memory).
const PANEL: usize = 256;

/// Columns of a panel eliminated one by one before the panel's later columns are updated by a
/// GEMM.
const BLOCK: usize = 32;

/// A trailing update of at least this many rows uses every thread in its GEMM.
const PARALLEL_ROWS: usize = 384;

const ZERO: c64 = c64 { re: 0.0, im: 0.0 };

/// Real square matrices on the union of their patterns, ready to be combined with complex
/// coefficients and factored, line after line, on one symbolic analysis.
pub struct Combination {
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// For each matrix, the union slot of each of its stored entries (in its CSC order).
    slots: Vec<Vec<usize>>,
    /// Each matrix's stored values, in its CSC order.
    values: Vec<Vec<f64>>,
    /// The supernodal analysis; `None` for a matrix whose factor has no entry below its diagonal
    /// (a diagonal matrix: faer makes no supernodal analysis of it), which the pivoted `LU` factors.
    tree: Option<Tree>,
    /// faer's `LU` analysis, made when a line first needs it.
    lu: OnceLock<Result<SymbolicLu<usize>, String>>,
}

/// The supernodal analysis of the union pattern, in femu's nested-dissection order.
struct Tree {
    symbolic: SymbolicCholesky<usize>,
    /// `fwd[new] = old`, `inv[old] = new`.
    fwd: Vec<usize>,
    inv: Vec<usize>,
    children: Vec<Vec<usize>>,
    /// The supernode of each (new) column.
    super_of: Vec<usize>,
    /// Roots of the subtrees factored in parallel ([`Tree::partition`]).
    tasks: Vec<usize>,
    /// The supernodes above them, increasing.
    top: Vec<usize>,
}

/// A supernode eliminated: its index, its `L` columns and its update for its parent.
type Eliminated = (usize, Mat<c64>, Option<Mat<c64>>);

/// How a line was factored.
enum Kind {
    /// Fronts of the supernodes: `front x pivots`, `D` on the diagonal, unit `L` below.
    Ldlt(Vec<Mat<c64>>),
    /// faer's pivoted `LU`.
    Lu(Box<Lu<usize, c64>>),
}

/// A factored combination: solves `A x = b` for complex right-hand sides.
pub struct Factored<'a> {
    owner: &'a Combination,
    values: Vec<c64>,
    kind: Kind,
}

impl Combination {
    /// The combination's matrices: square, of one size, in compressed sparse column form, finite,
    /// each symmetric (both triangles stored; the lower one is factored).
    ///
    /// # Errors
    /// [`SparseError::DimensionMismatch`] for a non-square matrix or sizes that differ,
    /// [`SparseError::NonFinite`] for a NaN or an infinity (naming the matrix by `names`),
    /// [`SparseError::Factorization`] when the analysis fails (out of memory).
    pub fn new(matrices: &[&SparseMatrix], names: &[&'static str]) -> Result<Self, SparseError> {
        let Some(first) = matrices.first() else {
            return Err(SparseError::DimensionMismatch {
                what: "matrices of a combination (at least one)",
                expected: 1,
                got: 0,
            });
        };
        let n = first.rows();
        for (a, name) in matrices
            .iter()
            .zip(names.iter().chain(std::iter::repeat(&"A")))
        {
            if a.rows() != n || a.cols() != n {
                return Err(SparseError::DimensionMismatch {
                    what: "a matrix of a combination (square, the size of the first)",
                    expected: n,
                    got: if a.rows() == n { a.cols() } else { a.rows() },
                });
            }
            if !a.is_csc() {
                return Err(SparseError::InvalidPattern {
                    reason: format!("{name} is not in compressed sparse column form"),
                });
            }
            if let Some((_, (r, c))) = a.iter().find(|(v, _)| !v.is_finite()) {
                return Err(SparseError::NonFinite {
                    matrix: name,
                    row: r,
                    col: c,
                });
            }
        }
        // the union pattern, column by column (rows sorted), with every diagonal entry
        let mut col_ptr = Vec::with_capacity(n + 1);
        col_ptr.push(0);
        let mut row_idx = Vec::new();
        let mut rows: Vec<usize> = Vec::new();
        for j in 0..n {
            rows.clear();
            rows.push(j);
            for a in matrices {
                if let Some(col) = a.outer_view(j) {
                    rows.extend_from_slice(col.indices());
                }
            }
            rows.sort_unstable();
            rows.dedup();
            row_idx.extend_from_slice(&rows);
            col_ptr.push(row_idx.len());
        }
        let mut slots = Vec::with_capacity(matrices.len());
        let mut values = Vec::with_capacity(matrices.len());
        for a in matrices {
            let mut s = Vec::with_capacity(a.nnz());
            for j in 0..n {
                let union = &row_idx[col_ptr[j]..col_ptr[j + 1]];
                if let Some(col) = a.outer_view(j) {
                    for r in col.indices() {
                        // present: the union holds every matrix's rows
                        let at = union.binary_search(r).unwrap_or(0);
                        s.push(col_ptr[j] + at);
                    }
                }
            }
            slots.push(s);
            values.push(a.data().to_vec());
        }
        let tree = Tree::new(n, &col_ptr, &row_idx)?;
        Ok(Self {
            n,
            col_ptr,
            row_idx,
            slots,
            values,
            tree,
            lu: OnceLock::new(),
        })
    }

    /// How many matrices it combines (one coefficient each in [`Combination::factor`]).
    pub fn matrices(&self) -> usize {
        self.values.len()
    }

    /// The dimension.
    pub fn dim(&self) -> usize {
        self.n
    }

    /// Stored entries of the union pattern.
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// Complex values of the factor `L` (with `D`) of one line's `LDL^T`.
    pub fn factor_len(&self) -> usize {
        self.tree.as_ref().map_or(self.n, Tree::factor_len)
    }

    /// `sum_j coefficients[j] A_j` on the union pattern.
    fn combine(&self, coefficients: &[c64]) -> Vec<c64> {
        let mut v = vec![ZERO; self.row_idx.len()];
        for ((slots, values), c) in self.slots.iter().zip(&self.values).zip(coefficients) {
            if c.re == 0.0 && c.im == 0.0 {
                continue;
            }
            for (s, a) in slots.iter().zip(values) {
                v[*s] += *c * *a;
            }
        }
        v
    }

    /// Factors `sum_j coefficients[j] A_j` (one coefficient per matrix): `LDL^T`, or the pivoted
    /// `LU` where a pivot of the `LDL^T` is zero.
    ///
    /// # Errors
    /// [`SparseError::DimensionMismatch`] for the wrong number of coefficients,
    /// [`SparseError::NonFinite`] for a non-finite coefficient, [`SparseError::Singular`] when
    /// the pivoted `LU` finds the combination singular too (an undamped eigenvalue at the line),
    /// [`SparseError::Factorization`] for faer's other failures.
    pub fn factor(&self, coefficients: &[c64]) -> Result<Factored<'_>, SparseError> {
        if coefficients.len() != self.values.len() {
            return Err(SparseError::DimensionMismatch {
                what: "coefficients of a combination (one per matrix)",
                expected: self.values.len(),
                got: coefficients.len(),
            });
        }
        if let Some(k) = coefficients
            .iter()
            .position(|c| !(c.re.is_finite() && c.im.is_finite()))
        {
            return Err(SparseError::NonFinite {
                matrix: "coefficient of a combination",
                row: k,
                col: 0,
            });
        }
        let values = self.combine(coefficients);
        let fronts = self
            .tree
            .as_ref()
            .and_then(|t| t.ldlt(&self.col_ptr, &self.row_idx, &values));
        let kind = match fronts {
            Some(fronts) => Kind::Ldlt(fronts),
            None => Kind::Lu(Box::new(self.lu_of(&values)?)),
        };
        Ok(Factored {
            owner: self,
            values,
            kind,
        })
    }

    /// faer's pivoted `LU` of `values` on the union pattern.
    fn lu_of(&self, values: &[c64]) -> Result<Lu<usize, c64>, SparseError> {
        let pattern = SymbolicSparseColMatRef::new_checked(
            self.n,
            self.n,
            &self.col_ptr,
            None,
            &self.row_idx,
        );
        let symbolic = self
            .lu
            .get_or_init(|| SymbolicLu::try_new(pattern).map_err(|e| format!("{e:?}")))
            .clone()
            .map_err(|e| SparseError::Factorization {
                reason: format!("the symbolic LU analysis failed: {e}"),
            })?;
        let a = SparseColMatRef::new(pattern, values);
        Lu::try_new_with_symbolic(symbolic, a).map_err(|e| SparseError::Factorization {
            reason: format!("the complex LU failed: {e:?}"),
        })
    }
}

impl Tree {
    /// The analysis of the pattern; `None` when faer makes no supernodal one (a factor with no
    /// entry below the diagonal).
    fn new(n: usize, col_ptr: &[usize], row_idx: &[usize]) -> Result<Option<Self>, SparseError> {
        let fail = |e: String| SparseError::Factorization {
            reason: format!("symbolic analysis of the dynamic stiffness: {e}"),
        };
        let pattern = Pattern::new(n, col_ptr, row_idx)?;
        let perm = pattern_ordering(pattern, Ordering::NestedDissection)?;
        let ordering = match &perm {
            Some((fwd, inv)) => {
                SymmetricOrdering::Custom(faer::perm::PermRef::new_checked(fwd, inv, n))
            }
            None => SymmetricOrdering::Amd,
        };
        let symbolic = factorize_symbolic_cholesky(
            pattern.faer(),
            Side::Lower,
            ordering,
            CholeskySymbolicParams {
                supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
                ..Default::default()
            },
        )
        .map_err(|e| fail(format!("{e:?}")))?;
        let (fwd, inv) = match symbolic.perm() {
            Some(p) => (p.arrays().0.to_vec(), p.arrays().1.to_vec()),
            None => ((0..n).collect(), (0..n).collect()),
        };
        let SymbolicCholeskyRaw::Supernodal(s) = symbolic.raw() else {
            return Ok(None);
        };
        let ns = s.n_supernodes();
        let (begin, end) = (s.supernode_begin(), s.supernode_end());
        let mut super_of = vec![0usize; n];
        for k in 0..ns {
            super_of[begin[k]..end[k]].fill(k);
        }
        let (rp, ri) = (s.col_ptr_for_row_idx(), s.row_idx());
        let mut children = vec![Vec::new(); ns];
        for k in 0..ns {
            if rp[k] < rp[k + 1] {
                children[super_of[ri[rp[k]]]].push(k);
            }
        }
        let mut tree = Self {
            symbolic,
            fwd,
            inv,
            children,
            super_of,
            tasks: Vec::new(),
            top: Vec::new(),
        };
        tree.partition();
        Ok(Some(tree))
    }

    fn supernodes(
        &self,
    ) -> &faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky<usize> {
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Supernodal(s) => s,
            SymbolicCholeskyRaw::Simplicial(_) => {
                unreachable!("Tree::new forces a supernodal analysis")
            }
        }
    }

    /// Supernode `k`'s columns and the rows below them (new indices).
    fn front(&self, k: usize) -> (usize, usize, &[usize]) {
        let s = self.supernodes();
        let rp = s.col_ptr_for_row_idx();
        (
            s.supernode_begin()[k],
            s.supernode_end()[k],
            &s.row_idx()[rp[k]..rp[k + 1]],
        )
    }

    fn factor_len(&self) -> usize {
        (0..self.children.len())
            .map(|k| {
                let (b0, b1, below) = self.front(k);
                (b1 - b0) * (b1 - b0 + below.len())
            })
            .sum()
    }

    /// Supernode `k`'s front eliminated: its `L` columns (`front x pivots`) and its update
    /// matrix for its parent (`None` for a root), from the values and its children's updates.
    /// `None` at a zero pivot. `par`: whether its GEMMs may use every thread.
    fn eliminate(
        &self,
        k: usize,
        (col_ptr, row_idx, values): (&[usize], &[usize], &[c64]),
        children: &[(usize, Mat<c64>)],
        par: bool,
    ) -> Option<(Mat<c64>, Option<Mat<c64>>)> {
        let (b0, b1, below) = self.front(k);
        let c = b1 - b0;
        let f = c + below.len();
        // the supernodal structure holds the pattern of every column it covers
        let pos = |r: usize| {
            if r < b1 {
                r - b0
            } else {
                c + below.binary_search(&r).unwrap_or(0)
            }
        };
        let mut fm = Mat::<c64>::zeros(f, f);
        for j in b0..b1 {
            let oj = self.fwd[j];
            for p in col_ptr[oj]..col_ptr[oj + 1] {
                let pi = self.inv[row_idx[p]];
                if pi >= j {
                    fm[(pos(pi), j - b0)] += values[p];
                }
            }
        }
        for (ch, u) in children {
            let (_, _, rows) = self.front(*ch);
            let map: Vec<usize> = rows.iter().map(|r| pos(*r)).collect();
            for (b, &mb) in map.iter().enumerate() {
                let uc = u.col_as_slice(b);
                let fc = fm.col_as_slice_mut(mb);
                for a in b..map.len() {
                    fc[map[a]] += uc[a];
                }
            }
        }
        factor_front(&mut fm, c, par)?;
        let update = (f > c).then(|| fm.as_ref().submatrix(c, c, f - c, f - c).to_owned());
        Some((fm.as_ref().subcols(0, c).to_owned(), update))
    }

    /// Splits the supernodal tree into disjoint subtrees of at most `1 / (8 threads)` of the
    /// work each (`tasks`, their roots) and the supernodes above them (`top`, increasing): the
    /// largest subtree is replaced by its children's until none is too large.
    fn partition(&mut self) {
        let ns = self.children.len();
        // work per subtree (complex multiply-adds of each front's elimination)
        let mut work = vec![0.0_f64; ns];
        for k in 0..ns {
            let (b0, b1, below) = self.front(k);
            let (c, f) = ((b1 - b0) as f64, (b1 - b0 + below.len()) as f64);
            work[k] += c * f * f - c * c * f + c * c * c / 3.0;
            if let Some(p) = self.parent(k) {
                let w = work[k];
                work[p] += w;
            }
        }
        let mut tasks: Vec<usize> = (0..ns).filter(|k| self.parent(*k).is_none()).collect();
        let total: f64 = tasks.iter().map(|k| work[*k]).sum();
        let limit = total / (8.0 * rayon::current_num_threads() as f64);
        while let Some((i, &k)) = tasks
            .iter()
            .enumerate()
            .filter(|(_, k)| !self.children[**k].is_empty())
            .max_by(|a, b| work[*a.1].total_cmp(&work[*b.1]))
        {
            if work[k] <= limit {
                break;
            }
            self.top.push(k);
            tasks.swap_remove(i);
            tasks.extend_from_slice(&self.children[k]);
        }
        self.top.sort_unstable();
        self.tasks = tasks;
    }

    /// The multifrontal `LDL^T` of the values on the union pattern (`None` at a zero pivot): the
    /// subtrees of [`Tree::partition`] on different threads (each front on one), then the
    /// supernodes above them one after another, with every thread in their GEMMs.
    fn ldlt(&self, col_ptr: &[usize], row_idx: &[usize], values: &[c64]) -> Option<Vec<Mat<c64>>> {
        use rayon::prelude::*;
        let ns = self.children.len();
        let data = (col_ptr, row_idx, values);
        // each task: its subtree in increasing order (children before parents)
        let done: Vec<Option<Vec<Eliminated>>> = self
            .tasks
            .par_iter()
            .map(|&root| {
                let mut nodes = vec![root];
                let mut at = 0;
                while at < nodes.len() {
                    nodes.extend_from_slice(&self.children[nodes[at]]);
                    at += 1;
                }
                nodes.sort_unstable();
                let mut pending: std::collections::HashMap<usize, Mat<c64>> =
                    std::collections::HashMap::new();
                let mut out = Vec::with_capacity(nodes.len());
                for k in nodes {
                    let kids: Vec<(usize, Mat<c64>)> = self.children[k]
                        .iter()
                        .map(|ch| Some((*ch, pending.remove(ch)?)))
                        .collect::<Option<_>>()?;
                    let (l, u) = self.eliminate(k, data, &kids, false)?;
                    if k == root {
                        out.push((k, l, u));
                    } else {
                        pending.insert(k, u?);
                        out.push((k, l, None));
                    }
                }
                Some(out)
            })
            .collect();
        let mut fronts: Vec<Option<Mat<c64>>> = (0..ns).map(|_| None).collect();
        let mut updates: Vec<Option<Mat<c64>>> = (0..ns).map(|_| None).collect();
        for task in done {
            for (k, l, u) in task? {
                fronts[k] = Some(l);
                updates[k] = u;
            }
        }
        for &k in &self.top {
            let kids: Vec<(usize, Mat<c64>)> = self.children[k]
                .iter()
                .map(|ch| Some((*ch, updates[*ch].take()?)))
                .collect::<Option<_>>()?;
            let (l, u) = self.eliminate(k, data, &kids, true)?;
            fronts[k] = Some(l);
            updates[k] = u;
        }
        fronts.into_iter().collect()
    }

    /// The supernode whose columns hold the first row below `k`'s (its parent), if any.
    fn parent(&self, k: usize) -> Option<usize> {
        let (_, _, below) = self.front(k);
        below.first().map(|r| self.super_of[*r])
    }

    /// `X <- A^-1 X` with the fronts of [`Tree::ldlt`] for the `r` columns of `x` (stored row by
    /// row: `x[i * r + t]` is row `i` of column `t`, in the original order): each column of `L`
    /// is read once for all of them.
    fn solve(&self, fronts: &[Mat<c64>], x: &mut [c64], r: usize) {
        let mut y = vec![ZERO; x.len()];
        for (new, o) in self.fwd.iter().enumerate() {
            y[new * r..(new + 1) * r].copy_from_slice(&x[o * r..(o + 1) * r]);
        }
        let mut v = vec![ZERO; r];
        for (k, l) in fronts.iter().enumerate() {
            let (b0, b1, below) = self.front(k);
            let c = b1 - b0;
            for j in 0..c {
                v.copy_from_slice(&y[(b0 + j) * r..(b0 + j + 1) * r]);
                if v.iter().all(|a| *a == ZERO) {
                    continue;
                }
                let col = l.col_as_slice(j);
                let rows = (b0 + j + 1..b1)
                    .zip(&col[j + 1..c])
                    .chain(below.iter().copied().zip(&col[c..]));
                for (row, lij) in rows {
                    for (a, vt) in y[row * r..(row + 1) * r].iter_mut().zip(&v) {
                        *a -= *lij * *vt;
                    }
                }
            }
            for j in 0..c {
                let inv = c64::new(1.0, 0.0) / l[(j, j)];
                for t in 0..r {
                    y[(b0 + j) * r + t] *= inv;
                }
            }
        }
        for (k, l) in fronts.iter().enumerate().rev() {
            let (b0, b1, below) = self.front(k);
            let c = b1 - b0;
            for j in (0..c).rev() {
                let col = l.col_as_slice(j);
                v.copy_from_slice(&y[(b0 + j) * r..(b0 + j + 1) * r]);
                let rows = (b0 + j + 1..b1)
                    .zip(&col[j + 1..c])
                    .chain(below.iter().copied().zip(&col[c..]));
                for (row, lij) in rows {
                    for (vt, a) in v.iter_mut().zip(&y[row * r..(row + 1) * r]) {
                        *vt -= *lij * *a;
                    }
                }
                y[(b0 + j) * r..(b0 + j + 1) * r].copy_from_slice(&v);
            }
        }
        for (new, o) in self.fwd.iter().enumerate() {
            x[o * r..(o + 1) * r].copy_from_slice(&y[new * r..(new + 1) * r]);
        }
    }
}

/// The complex symmetric `LDL^T` of a front's first `c` columns, in place (`D` on the diagonal,
/// the unit `L` below it), and the update `F_bb - L_b D L_b^T` of the rest (lower triangle).
/// `None` at a zero or non-finite pivot.
fn factor_front(fm: &mut Mat<c64>, c: usize, parallel: bool) -> Option<()> {
    let f = fm.nrows();
    let par_for = |rows: usize| {
        if parallel && rows >= PARALLEL_ROWS {
            Par::rayon(0)
        } else {
            Par::Seq
        }
    };
    let arch = pulp::Arch::new();
    let mut colj: Vec<c64> = Vec::with_capacity(f);
    let mut k0 = 0;
    while k0 < c {
        let k1 = (k0 + PANEL).min(c);
        let rest = f - k1;
        // `L D` of the panel's columns on the rows below it, for the trailing update
        let mut w = Mat::<c64>::zeros(rest, k1 - k0);
        let mut j0 = k0;
        while j0 < k1 {
            let j1 = (j0 + BLOCK).min(k1);
            // a block of columns, one after another, updating only each other
            for j in j0..j1 {
                let d = fm[(j, j)];
                if !(d.re.is_finite() && d.im.is_finite()) || d == ZERO {
                    return None;
                }
                let inv = c64::new(1.0, 0.0) / d;
                colj.clear();
                colj.extend_from_slice(&fm.col_as_slice(j)[j..]);
                for m in j + 1..j1 {
                    let t = colj[m - j] * inv;
                    if t == ZERO {
                        continue;
                    }
                    axpy(arch, &mut fm.col_as_slice_mut(m)[m..], &colj[m - j..], -t);
                }
            }
            // the block's `L D` below it, then its `L`
            let wi = fm.as_ref().submatrix(j1, j0, f - j1, j1 - j0).to_owned();
            w.as_mut()
                .submatrix_mut(0, j0 - k0, rest, j1 - j0)
                .copy_from(wi.as_ref().submatrix(k1 - j1, 0, rest, j1 - j0));
            for j in j0..j1 {
                let inv = c64::new(1.0, 0.0) / fm[(j, j)];
                for v in &mut fm.col_as_slice_mut(j)[j + 1..] {
                    *v *= inv;
                }
            }
            // the panel's later columns, all their rows below the block
            if j1 < k1 {
                let (_, bottom) = fm.as_mut().split_at_row_mut(j1);
                let (left, right) = bottom.split_at_col_mut(j1);
                let l = left.as_ref().submatrix(0, j0, k1 - j1, j1 - j0);
                matmul(
                    right.submatrix_mut(0, 0, f - j1, k1 - j1),
                    Accum::Add,
                    wi.as_ref(),
                    l.transpose(),
                    c64::new(-1.0, 0.0),
                    par_for(f - j1),
                );
            }
            j0 = j1;
        }
        if rest > 0 {
            let (_, bottom) = fm.as_mut().split_at_row_mut(k1);
            let (left, trailing) = bottom.split_at_col_mut(k1);
            let l = left.as_ref().subcols(k0, k1 - k0);
            triangular_matmul(
                trailing,
                BlockStructure::TriangularLower,
                Accum::Add,
                w.as_ref(),
                BlockStructure::Rectangular,
                l.transpose(),
                BlockStructure::Rectangular,
                c64::new(-1.0, 0.0),
                par_for(rest),
            );
        }
        k0 = k1;
    }
    Some(())
}

/// `y <- y + a x` with the machine's vector instructions (`pulp`'s dispatch): the column
/// updates inside a block of [`factor_front`], where most of a small front's work is.
fn axpy(arch: pulp::Arch, y: &mut [c64], x: &[c64], a: c64) {
    struct Axpy<'a> {
        y: &'a mut [c64],
        x: &'a [c64],
        a: c64,
    }
    impl pulp::WithSimd for Axpy<'_> {
        type Output = ();
        #[inline(always)]
        fn with_simd<S: pulp::Simd>(self, simd: S) {
            let Axpy { y, x, a } = self;
            let x = &x[..y.len()];
            let (yv, yt) = S::as_mut_simd_c64s(y);
            let (xv, xt) = S::as_simd_c64s(x);
            let av = simd.splat_c64s(a);
            for (yi, xi) in yv.iter_mut().zip(xv) {
                *yi = simd.mul_add_c64s(*xi, av, *yi);
            }
            for (yi, xi) in yt.iter_mut().zip(xt) {
                *yi += *xi * a;
            }
        }
    }
    arch.dispatch(Axpy { y, x, a });
}

impl Factored<'_> {
    /// The largest absolute entry of the factored matrix (the scale of backward errors).
    fn max_abs(&self) -> f64 {
        self.values.iter().map(|v| v.norm()).fold(0.0, f64::max)
    }

    /// Whether this line was factored by the pivoted `LU` (a zero pivot, or an `LDL^T` whose
    /// solve did not refine to [`LDLT_BACKWARD_ERROR`]).
    pub fn pivoted(&self) -> bool {
        matches!(self.kind, Kind::Lu(_))
    }

    /// `X <- A^-1 X` for `r` columns stored row by row.
    fn solve_rows(&self, x: &mut [c64], r: usize) {
        match &self.kind {
            Kind::Ldlt(fronts) => self
                .owner
                .tree
                .as_ref()
                .expect("fronts are made from the tree")
                .solve(fronts, x, r),
            Kind::Lu(lu) => {
                let n = self.owner.n;
                let mut m = Mat::<c64>::from_fn(n, r, |i, t| x[i * r + t]);
                lu.solve_in_place_with_conj(Conj::No, m.as_mut());
                for i in 0..n {
                    for t in 0..r {
                        x[i * r + t] = m[(i, t)];
                    }
                }
            }
        }
    }

    /// `b - A x` for `r` columns stored row by row.
    fn residual(&self, x: &[c64], b: &[c64], r: usize) -> Vec<c64> {
        let o = self.owner;
        let mut res = b.to_vec();
        for j in 0..o.n {
            for p in o.col_ptr[j]..o.col_ptr[j + 1] {
                let (i, a) = (o.row_idx[p], self.values[p]);
                for t in 0..r {
                    res[i * r + t] -= a * x[j * r + t];
                }
            }
        }
        res
    }

    /// The largest normwise backward error `||A x - b||_inf / (||A||_max ||x||_1 + ||b||_inf)`
    /// over the columns (infinite for a non-finite `x`).
    fn backward_error(&self, x: &[c64], b: &[c64], res: &[c64], r: usize) -> f64 {
        if x.iter().any(|v| !(v.re.is_finite() && v.im.is_finite())) {
            return f64::INFINITY;
        }
        let scale = self.max_abs();
        (0..r)
            .map(|t| {
                let col = |v: &[c64]| {
                    v.iter()
                        .skip(t)
                        .step_by(r)
                        .map(|a| a.norm())
                        .collect::<Vec<_>>()
                };
                let rn = col(res).into_iter().fold(0.0, f64::max);
                let bn = col(b).into_iter().fold(0.0, f64::max);
                let xn: f64 = col(x).into_iter().sum();
                let den = scale * xn + bn;
                if den > 0.0 { rn / den } else { 0.0 }
            })
            .fold(0.0, f64::max)
    }

    /// Solves `A X = B` in place for the columns of `b` and returns the largest normwise backward
    /// error `||A x - b||_inf / (||A||_max ||x||_1 + ||b||_inf)` over them. A solve above
    /// [`REFINED_BELOW`] takes one step of iterative refinement; an `LDL^T` whose refined solve
    /// stays above [`LDLT_BACKWARD_ERROR`] is replaced by the pivoted `LU` and the columns solved
    /// again.
    ///
    /// # Errors
    /// [`SparseError::DimensionMismatch`] for `b`'s rows, [`SparseError::Singular`] when the
    /// solution is not finite (the matrix is singular), faer's `LU` failures.
    pub fn solve_in_place(&mut self, mut b: MatMut<'_, c64>) -> Result<f64, SparseError> {
        let (n, r) = (self.owner.n, b.ncols());
        if b.nrows() != n {
            return Err(SparseError::DimensionMismatch {
                what: "right-hand sides of a complex solve (rows)",
                expected: n,
                got: b.nrows(),
            });
        }
        let mut rhs = vec![ZERO; n * r];
        for i in 0..n {
            for t in 0..r {
                rhs[i * r + t] = b[(i, t)];
            }
        }
        loop {
            let mut x = rhs.clone();
            self.solve_rows(&mut x, r);
            let mut res = self.residual(&x, &rhs, r);
            let mut worst = self.backward_error(&x, &rhs, &res, r);
            if worst.is_finite() && worst > REFINED_BELOW {
                self.solve_rows(&mut res, r);
                for (a, d) in x.iter_mut().zip(&res) {
                    *a += *d;
                }
                let res = self.residual(&x, &rhs, r);
                worst = self.backward_error(&x, &rhs, &res, r);
            }
            if worst <= LDLT_BACKWARD_ERROR || self.pivoted() {
                if !worst.is_finite() {
                    return Err(SparseError::Singular {
                        matrix: "the dynamic stiffness",
                        index: 0,
                    });
                }
                for i in 0..n {
                    for t in 0..r {
                        b[(i, t)] = x[i * r + t];
                    }
                }
                return Ok(worst);
            }
            self.kind = Kind::Lu(Box::new(self.owner.lu_of(&self.values)?));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::csc::from_entries;

    /// The vector `y + a x` equals the textbook complex arithmetic written out in real parts
    /// (`(x_r a_r - x_i a_i) + i (x_r a_i + x_i a_r)`) with every instruction set this machine
    /// runs and at lengths that leave every tail of a vector register.
    #[test]
    fn the_vector_axpy_is_complex_arithmetic() {
        let a = c64::new(0.75, -1.25);
        for arch in [pulp::Arch::new(), pulp::Arch::Scalar] {
            for n in 0..19 {
                let x: Vec<c64> = (0..n)
                    .map(|i| c64::new(i as f64 - 3.5, 0.5 * i as f64 + 1.0))
                    .collect();
                let y0: Vec<c64> = (0..n).map(|i| c64::new(2.0, -(i as f64))).collect();
                let mut y = y0.clone();
                axpy(arch, &mut y, &x, a);
                for i in 0..n {
                    let re = y0[i].re + x[i].re * a.re - x[i].im * a.im;
                    let im = y0[i].im + x[i].re * a.im + x[i].im * a.re;
                    assert!((y[i].re - re).abs() < 1e-14 && (y[i].im - im).abs() < 1e-14);
                }
            }
        }
    }

    /// By hand: `A = [[2, 1], [1, 3]] + i [[1, 0], [0, 0]]` with `b = (1, 0)`: `det = (2 + i) 3 -
    /// 1 = 5 + 3i`, `x = (3, -1) / (5 + 3i)`.
    #[test]
    fn a_two_by_two_complex_combination_by_hand() {
        let ar = from_entries(2, 2, &[(0, 0, 2.0), (0, 1, 1.0), (1, 0, 1.0), (1, 1, 3.0)]);
        let ai = from_entries(2, 2, &[(0, 0, 1.0)]);
        let comb = Combination::new(&[&ar, &ai], &["Ar", "Ai"]).unwrap();
        assert_eq!(comb.nnz(), 4);
        let mut f = comb
            .factor(&[c64::new(1.0, 0.0), c64::new(0.0, 1.0)])
            .unwrap();
        let mut b = Mat::<c64>::zeros(2, 1);
        b[(0, 0)] = c64::new(1.0, 0.0);
        let berr = f.solve_in_place(b.as_mut()).unwrap();
        let det = c64::new(5.0, 3.0);
        let want = [c64::new(3.0, 0.0) / det, c64::new(-1.0, 0.0) / det];
        for i in 0..2 {
            assert!((b[(i, 0)] - want[i]).norm() < 1e-15, "{:?}", b[(i, 0)]);
        }
        assert!(berr < 1e-15);
    }

    /// Uncoupled DOFs (a diagonal dynamic stiffness: springs to ground under point masses, one
    /// DOF alone), for which faer makes no supernodal analysis: solved, `x_i = b_i / a_ii` by
    /// hand, at 1 and at 3 DOFs.
    #[test]
    fn a_diagonal_combination_is_solved() {
        for n in [1usize, 3] {
            let k: Vec<(usize, usize, f64)> =
                (0..n).map(|i| (i, i, 3e4 * (i + 1) as f64)).collect();
            let m: Vec<(usize, usize, f64)> = (0..n).map(|i| (i, i, 10.0)).collect();
            let (k, m) = (from_entries(n, n, &k), from_entries(n, n, &m));
            let comb = Combination::new(&[&k, &m], &["K", "M"]).unwrap();
            let (ck, cm) = (c64::new(1.0, 0.05), c64::new(-2500.0, 0.0));
            let mut f = comb.factor(&[ck, cm]).unwrap();
            let mut b = Mat::<c64>::from_fn(n, 1, |i, _| c64::new(1.0 + i as f64, -0.5));
            f.solve_in_place(b.as_mut()).unwrap();
            for i in 0..n {
                let a = ck * 3e4 * (i + 1) as f64 + cm * 10.0;
                let want = c64::new(1.0 + i as f64, -0.5) / a;
                assert!((b[(i, 0)] - want).norm() < 1e-15 * want.norm(), "{n}: {i}");
            }
        }
    }

    /// A zero pivot (a singular real combination) is an error, not a NaN answer.
    #[test]
    fn a_singular_combination_is_refused() {
        let a = from_entries(2, 2, &[(0, 0, 1.0), (0, 1, 1.0), (1, 0, 1.0), (1, 1, 1.0)]);
        let comb = Combination::new(&[&a], &["A"]).unwrap();
        let f = comb.factor(&[c64::new(1.0, 0.0)]);
        let solved = f.and_then(|mut f| {
            let mut b = Mat::<c64>::zeros(2, 1);
            b[(0, 0)] = c64::new(1.0, 0.0);
            f.solve_in_place(b.as_mut())
        });
        assert!(
            matches!(
                solved,
                Err(SparseError::Singular { .. } | SparseError::Factorization { .. })
            ),
            "{solved:?}"
        );
    }

    /// A zero first pivot in a non-singular matrix (`[[0, 1], [1, 0]]`): the `LDL^T` cannot take
    /// it, the pivoted `LU` can; `x = (b_2, b_1)` by hand.
    #[test]
    fn a_zero_pivot_goes_to_the_pivoted_lu() {
        let a = from_entries(2, 2, &[(0, 1, 1.0), (1, 0, 1.0)]);
        let comb = Combination::new(&[&a], &["A"]).unwrap();
        let mut f = comb.factor(&[c64::new(1.0, 0.0)]).unwrap();
        assert!(f.pivoted());
        let mut b = Mat::<c64>::zeros(2, 1);
        b[(0, 0)] = c64::new(2.0, 1.0);
        b[(1, 0)] = c64::new(-3.0, 0.5);
        f.solve_in_place(b.as_mut()).unwrap();
        assert!((b[(0, 0)] - c64::new(-3.0, 0.5)).norm() < 1e-15);
        assert!((b[(1, 0)] - c64::new(2.0, 1.0)).norm() < 1e-15);
    }

    /// The five-point Laplacian of a 60 x 60 grid shifted by `-(0.05 + 0.1 i)` times the identity
    /// (indefinite real part, as a dynamic stiffness above its first resonances): the multifrontal
    /// `LDL^T` (many supernodes, children's updates added into their parents) solves it to a
    /// backward error below 1e-15 without pivoting, and the residual `A x - b` computed here,
    /// entry by entry from the stencil, is as small.
    #[test]
    fn a_shifted_grid_laplacian_by_the_multifrontal_ldlt() {
        let m = 60;
        let n = m * m;
        let id = |i: usize, j: usize| i * m + j;
        let mut lap = Vec::new();
        let mut eye = Vec::new();
        for i in 0..m {
            for j in 0..m {
                lap.push((id(i, j), id(i, j), 4.0));
                eye.push((id(i, j), id(i, j), 1.0));
                for (di, dj) in [(1usize, 0usize), (0, 1)] {
                    if i + di < m && j + dj < m {
                        lap.push((id(i, j), id(i + di, j + dj), -1.0));
                        lap.push((id(i + di, j + dj), id(i, j), -1.0));
                    }
                }
            }
        }
        let (l, e) = (from_entries(n, n, &lap), from_entries(n, n, &eye));
        let comb = Combination::new(&[&l, &e], &["L", "I"]).unwrap();
        let shift = c64::new(-0.05, -0.1);
        let mut f = comb.factor(&[c64::new(1.0, 0.0), shift]).unwrap();
        assert!(!f.pivoted());
        let rhs = Mat::<c64>::from_fn(n, 2, |i, k| {
            c64::new(
                ((i * 7 + k) % 11) as f64 - 5.0,
                ((i * 3 + 2 * k) % 5) as f64,
            )
        });
        let mut x = rhs.clone();
        let berr = f.solve_in_place(x.as_mut()).unwrap();
        assert!(berr < 1e-15, "{berr:e}");
        for k in 0..2 {
            let mut worst = 0.0_f64;
            for i in 0..m {
                for j in 0..m {
                    let mut ax = x[(id(i, j), k)] * (c64::new(4.0, 0.0) + shift);
                    for (a, b) in [
                        (i.wrapping_sub(1), j),
                        (i + 1, j),
                        (i, j.wrapping_sub(1)),
                        (i, j + 1),
                    ] {
                        if a < m && b < m {
                            ax -= x[(id(a, b), k)];
                        }
                    }
                    worst = worst.max((ax - rhs[(id(i, j), k)]).norm());
                }
            }
            assert!(worst < 1e-12, "column {k}: {worst:e}");
        }
        assert!(comb.factor_len() > n);
    }

    #[test]
    fn bad_inputs_are_named() {
        let a = from_entries(2, 2, &[(0, 0, f64::NAN)]);
        assert!(matches!(
            Combination::new(&[&a], &["K"]),
            Err(SparseError::NonFinite { matrix: "K", .. })
        ));
        let a = from_entries(2, 2, &[(0, 0, 1.0), (1, 1, 1.0)]);
        let b = from_entries(3, 3, &[(0, 0, 1.0)]);
        assert!(Combination::new(&[&a, &b], &["K", "M"]).is_err());
        let comb = Combination::new(&[&a], &["K"]).unwrap();
        assert!(comb.factor(&[]).is_err());
        assert!(comb.factor(&[c64::new(f64::NAN, 0.0)]).is_err());
    }
}
