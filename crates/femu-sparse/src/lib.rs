//! # femu-sparse
//!
//! The sparse-solver core of femu: the sparse matrix type used at every crate boundary
//! ([`SparseMatrix`], an alias of [`sprs::CsMat<f64>`] in compressed sparse column form), helpers on
//! it, and the dense generalized symmetric eigensolver that serves small problems and cross-checks
//! the sparse path.
//!
//! ```
//! use femu_sparse::dense::generalized_symmetric_eigen;
//! use faer::Mat;
//!
//! // K = diag(2, 8), M = diag(2, 2): eigenvalues 1 and 4, M-normalised vectors.
//! let k = Mat::from_fn(2, 2, |i, j| if i == j { [2.0, 8.0][i] } else { 0.0 });
//! let m = Mat::from_fn(2, 2, |i, j| if i == j { 2.0 } else { 0.0 });
//! let eig = generalized_symmetric_eigen(k.as_ref(), m.as_ref()).unwrap();
//! assert!((eig.values[0] - 1.0).abs() < 1e-14 && (eig.values[1] - 4.0).abs() < 1e-14);
//! // phi^T M phi = 1
//! let phi0 = eig.vectors.col(0);
//! assert!((2.0 * phi0[0] * phi0[0] + 2.0 * phi0[1] * phi0[1] - 1.0).abs() < 1e-14);
//! ```

pub mod cholesky;
pub mod complex;
pub mod csc;
pub mod dense;
pub mod eigen;
mod error;
pub mod kkt;
pub mod mtx;
mod multifrontal;
pub mod ordering;
mod skinny;
pub mod slepc;

pub use error::SparseError;

/// The sparse matrix type at femu's crate boundaries: compressed sparse column, `f64` values,
/// `usize` indices. Symmetric matrices are stored with both triangles.
pub type SparseMatrix = sprs::CsMat<f64>;

pub use faer;
pub use sprs;
