//! Symmetric quasi-definite saddle-point systems `[[A, B], [B^T, -C]]` with `A` positive definite
//! and `C` positive semi-definite (the optimality systems of femu's least-squares expansions,
//! `docs/MATH.md`, "Expansion").
//!
//! The matrix is regularised to `[[A, B], [B^T, -C - delta I]]` (`delta` one number, or one per
//! row when the rows differ by orders of magnitude), which is quasi-definite and so
//! factors stably by `LDL^T` in any symmetric order (Vanderbei 1995; Gill, Saunders and Shinnerl
//! 1996), then the system with `delta = 0` is solved by iterative refinement with the exact
//! matrix. Refinement stops at a normwise backward error of `1e-14`, or where it stagnates below
//! `1e-11`; on badly conditioned systems that is short of machine precision (femu's expansion
//! tests measure stagnation near `1e-7` relative to a dense solution), and a system that does not
//! reach `1e-11` is reported as singular.
//!
//! ```
//! use femu_sparse::kkt::QuasiDefinite;
//! use femu_sparse::faer::Mat;
//!
//! // min ||x||^2 subject to x0 + x1 = 2: [[I, b], [b^T, 0]] [x; mu] = [0; 2]
//! let mut t = sprs::TriMat::new((3, 3));
//! for (i, j, v) in [(0, 0, 1.0), (1, 1, 1.0), (0, 2, 1.0), (2, 0, 1.0), (1, 2, 1.0), (2, 1, 1.0)] {
//!     t.add_triplet(i, j, v);
//! }
//! let kkt = QuasiDefinite::from_triplets(3, 2, 1e-8, t);
//! let rhs = Mat::from_fn(3, 1, |i, _| if i == 2 { 2.0 } else { 0.0 });
//! let z = kkt.solve(&mut None, rhs.as_ref(), "example").unwrap();
//! assert!((z[(0, 0)] - 1.0).abs() < 1e-12 && (z[(1, 0)] - 1.0).abs() < 1e-12);
//! ```

use crate::cholesky::{Factorization, Ldlt, SymbolicFactor};
use crate::csc::sym_mul_mat;
use crate::ordering::Ordering;
use crate::{SparseError, SparseMatrix};
use faer::{Mat, MatRef};

/// A regularised quasi-definite matrix and the size of its positive definite block.
#[derive(Debug, Clone)]
pub struct QuasiDefinite {
    /// the regularised matrix
    a: SparseMatrix,
    /// size of the first block
    n1: usize,
    /// the regularisation of each row of the second block
    delta: Vec<f64>,
}

impl QuasiDefinite {
    /// The `n x n` matrix of the triplets `t` (both triangles, duplicates summed) with `-delta`
    /// added on the diagonal of the second block (rows `n1..n`).
    pub fn from_triplets(n: usize, n1: usize, delta: f64, t: sprs::TriMat<f64>) -> Self {
        Self::from_triplets_per_row(n, n1, vec![delta; n.saturating_sub(n1)], t)
    }

    /// As [`QuasiDefinite::from_triplets`] with `-delta[i]` on row `n1 + i`: a regularisation in
    /// proportion to each row's own scale, for a second block whose rows differ by orders of
    /// magnitude (one `delta` for all would be negligible on the largest rows and dominate the
    /// smallest, where iterative refinement then cannot remove it).
    ///
    /// # Panics
    /// If `delta` does not have `n - n1` entries.
    pub fn from_triplets_per_row(
        n: usize,
        n1: usize,
        delta: Vec<f64>,
        mut t: sprs::TriMat<f64>,
    ) -> Self {
        assert_eq!(
            delta.len(),
            n - n1,
            "one regularisation per row of the second block"
        );
        for (i, d) in delta.iter().enumerate() {
            t.add_triplet(n1 + i, n1 + i, -d);
        }
        Self {
            a: t.to_csc(),
            n1,
            delta,
        }
    }

    /// Solves `A_0 z = b` (the unregularised system) for the columns of `b`; `what` names the
    /// system in errors. `symbolic` is the analysis of an earlier system with the same pattern
    /// (computed and kept on first use), so one ordering serves a sequence of systems.
    ///
    /// # Errors
    /// As [`QuasiDefinite::factor`] and [`QuasiDefinite::solve_with`].
    pub fn solve(
        &self,
        symbolic: &mut Option<SymbolicFactor>,
        b: MatRef<'_, f64>,
        what: &'static str,
    ) -> Result<Mat<f64>, SparseError> {
        let ldlt = self.factor(symbolic, what)?;
        self.solve_with(&ldlt, b, what)
    }

    /// The `LDL^T` factor of the regularised matrix (analysing the pattern, nested dissection, on
    /// first use).
    ///
    /// # Errors
    /// A zero pivot ([`SparseError::Singular`]) or an ordering failure.
    pub fn factor(
        &self,
        symbolic: &mut Option<SymbolicFactor>,
        what: &'static str,
    ) -> Result<Ldlt, SparseError> {
        if symbolic.is_none() {
            *symbolic = Some(SymbolicFactor::new(&self.a, Ordering::NestedDissection)?);
        }
        symbolic.as_ref().expect("just set").ldlt(&self.a, what)
    }

    /// Solves with a factor of [`QuasiDefinite::factor`], refined to the unregularised system.
    ///
    /// # Errors
    /// [`SparseError::NotRefined`] when the refinement does not reach a backward error of `1e-11`
    /// (the system is singular or nearly so).
    pub fn solve_with(
        &self,
        ldlt: &Ldlt,
        b: MatRef<'_, f64>,
        what: &'static str,
    ) -> Result<Mat<f64>, SparseError> {
        let n = self.a.rows();
        let mut z = b.to_owned();
        ldlt.solve_in_place(z.as_mut());
        let bn: Vec<f64> = (0..b.ncols()).map(|j| b.col(j).norm_l2()).collect();
        // normwise backward error ||r|| / (||A|| ||z|| + ||b||): the refinement stops at round-off
        // (1e-14) or when it stagnates at a level that is still round-off for this matrix (1e-11)
        let a_norm = (0..n)
            .map(|c| {
                self.a
                    .outer_view(c)
                    .map_or(0.0, |v| v.iter().map(|(_, x)| x.abs()).sum::<f64>())
            })
            .fold(0.0, f64::max);
        let mut last = f64::INFINITY;
        for _ in 0..100 {
            // r = b - A_0 z, A_0 z = A_delta z + delta z_2
            let az = sym_mul_mat(&self.a, z.as_ref())?;
            let mut r = Mat::from_fn(n, b.ncols(), |i, j| {
                let a0 = az[(i, j)]
                    + if i >= self.n1 {
                        self.delta[i - self.n1] * z[(i, j)]
                    } else {
                        0.0
                    };
                b[(i, j)] - a0
            });
            let eta = (0..b.ncols())
                .map(|j| {
                    r.col(j).norm_l2()
                        / (a_norm * z.col(j).norm_l2() + bn[j]).max(f64::MIN_POSITIVE)
                })
                .fold(0.0, f64::max);
            if eta <= 1e-14 || (eta <= 1e-11 && eta > 0.5 * last) {
                return Ok(z);
            }
            last = eta;
            ldlt.solve_in_place(r.as_mut());
            if (0..r.ncols()).any(|j| r.col(j).iter().any(|v| !v.is_finite())) {
                break;
            }
            z += &r;
        }
        Err(SparseError::NotRefined { system: what })
    }
}
