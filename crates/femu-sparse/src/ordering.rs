//! Fill-reducing orderings for the sparse Cholesky factorizations.
//!
//! FE matrices carry several DOFs per node with identical sparsity patterns. Nested dissection
//! runs on the compressed graph of supervariables (consecutive columns with identical patterns,
//! the nodes), as METIS is meant to be used on FE problems, and the node order is expanded back to
//! DOFs. SOLVERS.md measured METIS nested dissection 3-4x faster to factor, with half the memory,
//! than faer's AMD on hex8 patterns at 200k DOF.

use crate::{SparseError, SparseMatrix};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Which fill-reducing ordering to compute.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Ordering {
    /// METIS nested dissection on the supervariable (node) graph: the default for FE matrices.
    #[default]
    NestedDissection,
    /// faer's approximate minimum degree.
    Amd,
    /// No reordering (for tests and matrices that are already ordered).
    Identity,
}

/// A permutation as `(fwd, inv)` arrays with `fwd[new] = old` and `inv[old] = new`.
pub type Permutation = (Vec<usize>, Vec<usize>);

/// A square sparsity pattern in compressed sparse column form: column `j` holds the rows
/// `row_idx[col_ptr[j]..col_ptr[j + 1]]`, sorted and without repeats. The symbolic analysis needs
/// nothing else, so it can run on an assembler's pattern before the values exist
/// ([`crate::cholesky::SymbolicFactor::of_pattern`]).
#[derive(Debug, Clone, Copy)]
pub struct Pattern<'a> {
    n: usize,
    col_ptr: &'a [usize],
    row_idx: &'a [usize],
}

impl<'a> Pattern<'a> {
    /// The pattern of `n` columns from its arrays, checked: `col_ptr` of length `n + 1` from 0,
    /// non-decreasing, ending at `row_idx.len()`; each column's rows below `n`, strictly increasing.
    ///
    /// # Errors
    /// [`SparseError::InvalidPattern`] naming the first column that breaks a rule.
    pub fn new(n: usize, col_ptr: &'a [usize], row_idx: &'a [usize]) -> Result<Self, SparseError> {
        let bad = |reason: String| Err(SparseError::InvalidPattern { reason });
        if col_ptr.len() != n + 1 {
            return bad(format!(
                "{} column pointers for {n} columns (expected {})",
                col_ptr.len(),
                n + 1
            ));
        }
        if col_ptr[0] != 0 || col_ptr[n] != row_idx.len() {
            return bad(format!(
                "the column pointers run from {} to {}, the rows are {} (expected 0 to {})",
                col_ptr[0],
                col_ptr[n],
                row_idx.len(),
                row_idx.len()
            ));
        }
        for j in 0..n {
            let (lo, hi) = (col_ptr[j], col_ptr[j + 1]);
            if lo > hi {
                return bad(format!("column {j} ends before it starts ({lo} > {hi})"));
            }
            if hi > row_idx.len() {
                return bad(format!(
                    "column {j} ends at {hi}, beyond the {} rows given",
                    row_idx.len()
                ));
            }
            let rows = &row_idx[lo..hi];
            if let Some(&r) = rows.iter().find(|&&r| r >= n) {
                return bad(format!("column {j} has row {r}, beyond the {n} rows"));
            }
            if let Some(w) = rows.windows(2).find(|w| w[0] >= w[1]) {
                return bad(format!(
                    "column {j}: rows {} and {} are not strictly increasing",
                    w[0], w[1]
                ));
            }
        }
        Ok(Self {
            n,
            col_ptr,
            row_idx,
        })
    }

    /// The pattern of a square CSC matrix (sprs has checked its arrays).
    ///
    /// # Errors
    /// [`SparseError::DimensionMismatch`] for a non-square or CSR matrix.
    pub fn of(a: &'a SparseMatrix) -> Result<Self, SparseError> {
        if !a.is_csc() {
            return Err(SparseError::DimensionMismatch {
                what: "CSC storage (got CSR)",
                expected: 0,
                got: 1,
            });
        }
        if a.rows() != a.cols() {
            return Err(SparseError::DimensionMismatch {
                what: "square matrix",
                expected: a.rows(),
                got: a.cols(),
            });
        }
        Ok(Self {
            n: a.cols(),
            col_ptr: a.indptr().into_raw_storage(),
            row_idx: a.indices(),
        })
    }

    /// Number of rows and columns.
    pub fn dim(&self) -> usize {
        self.n
    }

    /// Stored entries.
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// The column pointers (`n + 1`).
    pub fn col_ptr(&self) -> &'a [usize] {
        self.col_ptr
    }

    /// The row indices, column after column.
    pub fn row_idx(&self) -> &'a [usize] {
        self.row_idx
    }

    /// faer's view of the pattern (no copy; the arrays were checked as faer checks them).
    pub(crate) fn faer(&self) -> faer::sparse::SymbolicSparseColMatRef<'a, usize> {
        faer::sparse::SymbolicSparseColMatRef::new_checked(
            self.n,
            self.n,
            self.col_ptr,
            None,
            self.row_idx,
        )
    }

    /// The rows of column `j`.
    pub fn col(&self, j: usize) -> &'a [usize] {
        &self.row_idx[self.col_ptr[j]..self.col_ptr[j + 1]]
    }

    /// Stored entries on and below the diagonal.
    pub fn lower_nnz(&self) -> usize {
        (0..self.n)
            .map(|j| self.col(j).iter().filter(|&&r| r >= j).count())
            .sum()
    }

    /// A fingerprint of the pattern (its dimension, column pointers and rows): two analyses are
    /// for the same pattern when their fingerprints agree
    /// ([`crate::cholesky::SymbolicFactor::is_for`]). Read in parallel, four lanes a piece of 65,536 words.
    pub fn fingerprint(&self) -> u64 {
        let (p, r) = rayon::join(
            || hash_words(self.col_ptr, |&x| x as u64),
            || hash_words(self.row_idx, |&x| x as u64),
        );
        [p, r].into_iter().fold(self.n as u64, hash_mix)
    }
}

/// One step of [`hash_words`]: a bijection of the state for each word.
pub(crate) fn hash_mix(h: u64, x: u64) -> u64 {
    (h.rotate_left(23) ^ x).wrapping_mul(0x9E37_79B9_7F4A_7C15)
}

/// A 64-bit hash of the words `word(w_i)`, in pieces of [`HASH_PIECE`] words on the threads
/// (four independent lanes a piece), the pieces' hashes combined in order: the same value on
/// any number of threads. For fingerprints ([`Pattern::fingerprint`], the eigensolver's checks
/// made ahead, `eigen::PencilChecks`), not against an adversary: a single changed word always
/// changes it (each step is a bijection), other changes with probability `1 - 2^-64`. The
/// 199,200-DOF plate's `K` and `M` (17.7 million entries, their patterns and values): 11 ms on
/// two threads.
pub(crate) fn hash_words<T: Sync>(w: &[T], word: impl Fn(&T) -> u64 + Sync) -> u64 {
    w.par_chunks(HASH_PIECE)
        .map(|piece| {
            let mut lanes = [1u64, 2, 3, 4];
            let mut quads = piece.chunks_exact(4);
            for q in &mut quads {
                for (l, x) in lanes.iter_mut().zip(q) {
                    *l = hash_mix(*l, word(x));
                }
            }
            for x in quads.remainder() {
                lanes[0] = hash_mix(lanes[0], word(x));
            }
            lanes
                .iter()
                .fold(piece.len() as u64, |h, &l| hash_mix(h, l))
        })
        .collect::<Vec<u64>>()
        .into_iter()
        .fold(w.len() as u64, hash_mix)
}

/// Words of a [`hash_words`] piece.
const HASH_PIECE: usize = 1 << 16;

/// Supervariables of a CSC pattern: maximal runs of consecutive columns with identical row
/// patterns. Returns the first column of each supervariable plus a final `n`.
pub fn supervariables(a: &SparseMatrix) -> Vec<usize> {
    match Pattern::of(a) {
        Ok(p) => pattern_supervariables(p),
        // a non-square matrix: no supervariables beyond its columns
        Err(_) => (0..=a.cols()).collect(),
    }
}

fn pattern_supervariables(p: Pattern<'_>) -> Vec<usize> {
    let n = p.dim();
    let mut starts = vec![0];
    for j in 1..n {
        if p.col(j - 1) != p.col(j) {
            starts.push(j);
        }
    }
    if n > 0 {
        starts.push(n);
    } else {
        starts.clear();
        starts.push(0);
    }
    starts
}

/// The forward and inverse permutations (`fwd[new] = old`) of the ordering, or `None` when faer
/// computes it itself (AMD).
///
/// # Errors
/// [`SparseError::DimensionMismatch`] for a non-square or CSR matrix,
/// [`SparseError::Factorization`] if METIS reports an error.
pub fn fill_reducing_ordering(
    a: &SparseMatrix,
    ordering: Ordering,
) -> Result<Option<Permutation>, SparseError> {
    pattern_ordering(Pattern::of(a)?, ordering)
}

/// As [`fill_reducing_ordering`], of a pattern.
///
/// # Errors
/// [`SparseError::Factorization`] if METIS reports an error.
pub fn pattern_ordering(
    p: Pattern<'_>,
    ordering: Ordering,
) -> Result<Option<Permutation>, SparseError> {
    match ordering {
        Ordering::Amd => Ok(None),
        // An explicit identity permutation: faer 0.24's `SymmetricOrdering::Identity` path gave
        // wrong solves in our tests (residual 0.5 on a random SPD matrix where AMD, nested
        // dissection and this explicit identity give 1e-15).
        Ordering::Identity => Ok(Some(((0..p.dim()).collect(), (0..p.dim()).collect()))),
        Ordering::NestedDissection => {
            let n = p.dim();
            if n < 2 {
                return Ok(None);
            }
            let starts = pattern_supervariables(p);
            let ns = starts.len() - 1;
            let mut sv_of = vec![0usize; n];
            for s in 0..ns {
                sv_of[starts[s]..starts[s + 1]]
                    .iter_mut()
                    .for_each(|v| *v = s);
            }
            // Compressed adjacency (no self loops), from each supervariable's first column. Rows
            // are sorted and supervariables are runs of columns, so each list is sorted.
            let mut xadj: Vec<usize> = Vec::with_capacity(ns + 1);
            let mut adjncy: Vec<usize> = Vec::new();
            xadj.push(0);
            let mut last = vec![usize::MAX; ns];
            for s in 0..ns {
                for &r in p.col(starts[s]) {
                    let t = sv_of[r];
                    if t != s && last[t] != s {
                        last[t] = s;
                        adjncy.push(t);
                    }
                }
                xadj.push(adjncy.len());
            }
            let (xadj, adjncy) = symmetric_graph(xadj, adjncy);
            let too_large = || SparseError::Factorization {
                reason: "graph too large for METIS's 32-bit indices".into(),
            };
            let xadj = xadj
                .into_iter()
                .map(|x| i32::try_from(x).map_err(|_| too_large()))
                .collect::<Result<Vec<i32>, _>>()?;
            let adjncy = adjncy
                .into_iter()
                .map(|t| i32::try_from(t).map_err(|_| too_large()))
                .collect::<Result<Vec<i32>, _>>()?;
            let node_perm = metis::node_nd(ns, &xadj, &adjncy)?;
            let mut fwd = Vec::with_capacity(n);
            for s in node_perm {
                fwd.extend(starts[s]..starts[s + 1]);
            }
            let mut inv = vec![0usize; n];
            for (new, old) in fwd.iter().enumerate() {
                inv[*old] = new;
            }
            Ok(Some((fwd, inv)))
        }
    }
}

/// The graph `(xadj, adjncy)` (sorted lists, no self loops) made symmetric, as METIS requires:
/// unchanged when every edge has its mirror (a symmetric pattern, checked by one binary search
/// per edge), else the union of each list with its mirrored edges. The ordering then never
/// depends on whether the values were checked first: an analysis may run beside the checks
/// ([`crate::eigen::Pencil::new`]).
fn symmetric_graph(xadj: Vec<usize>, adjncy: Vec<usize>) -> (Vec<usize>, Vec<usize>) {
    let ns = xadj.len() - 1;
    let list = |s: usize| &adjncy[xadj[s]..xadj[s + 1]];
    let mirrored = (0..ns).all(|s| list(s).iter().all(|&t| list(t).binary_search(&s).is_ok()));
    if mirrored {
        return (xadj, adjncy);
    }
    let mut lists: Vec<Vec<usize>> = (0..ns).map(|s| list(s).to_vec()).collect();
    for s in 0..ns {
        for &t in list(s) {
            lists[t].push(s);
        }
    }
    let mut x = Vec::with_capacity(ns + 1);
    let mut a = Vec::new();
    x.push(0);
    for mut l in lists {
        l.sort_unstable();
        l.dedup();
        a.extend(l);
        x.push(a.len());
    }
    (x, a)
}

#[allow(unsafe_code)]
mod metis {
    //! The one call into METIS.
    use crate::SparseError;
    use std::sync::Mutex;

    /// METIS draws its random numbers from one process-wide Mersenne twister (GKlib's `mt` and
    /// `mti` are plain statics) and reseeds it at the start of each call. Two calls at once race
    /// on it: each sees the other's draws, so the same graph got a different ordering, and a
    /// different round-off downstream, depending on what else was running (docs/VERIFICATION.md,
    /// "Determinism"). One call at a time makes every ordering a function of the graph alone.
    static METIS: Mutex<()> = Mutex::new(());

    /// `METIS_NodeND` on a symmetric graph without self loops; returns `perm` (`perm[new] = old`).
    pub(super) fn node_nd(
        n: usize,
        xadj: &[i32],
        adjncy: &[i32],
    ) -> Result<Vec<usize>, SparseError> {
        let mut nv = i32::try_from(n).map_err(|_| SparseError::Factorization {
            reason: "too many vertices for METIS".into(),
        })?;
        let mut xadj = xadj.to_vec();
        let mut adjncy = adjncy.to_vec();
        if adjncy.is_empty() {
            // No edges (a diagonal matrix): any order is fill-free, and METIS rejects empty graphs.
            return Ok((0..n).collect());
        }
        let mut options = vec![0i32; metis_sys::METIS_NOPTIONS as usize];
        let mut perm = vec![0i32; n];
        let mut iperm = vec![0i32; n];
        // A panic cannot happen while the lock is held (only the C call runs), so a poisoned lock
        // still guards nothing broken.
        let _one_at_a_time = METIS.lock().unwrap_or_else(|e| e.into_inner());
        // SAFETY: the arrays have the lengths METIS documents (xadj n + 1, adjncy xadj[n],
        // options METIS_NOPTIONS, perm and iperm n); METIS does not keep the pointers.
        let status = unsafe {
            metis_sys::METIS_SetDefaultOptions(options.as_mut_ptr());
            metis_sys::METIS_NodeND(
                &mut nv,
                xadj.as_mut_ptr(),
                adjncy.as_mut_ptr(),
                std::ptr::null_mut(),
                options.as_mut_ptr(),
                perm.as_mut_ptr(),
                iperm.as_mut_ptr(),
            )
        };
        if status != metis_sys::rstatus_et_METIS_OK {
            return Err(SparseError::Factorization {
                reason: format!("METIS_NodeND returned {status}"),
            });
        }
        Ok(perm.into_iter().map(|p| p as usize).collect())
    }
}
