//! Shared helpers: small models, dense references, random pencils.

use faer::Mat;
use femu_fem::prelude::*;
use femu_sparse::SparseMatrix;
use femu_sparse::dense::{GeneralizedEigen, generalized_symmetric_eigen};

pub use femu_testkit::{Rng, bar};

pub fn dense(a: &SparseMatrix) -> Mat<f64> {
    femu_sparse::csc::to_dense(a)
}

pub fn sparse(a: &Mat<f64>) -> SparseMatrix {
    let mut t = sprs::TriMat::new((a.nrows(), a.ncols()));
    for j in 0..a.ncols() {
        for i in 0..a.nrows() {
            if a[(i, j)] != 0.0 {
                t.add_triplet(i, j, a[(i, j)]);
            }
        }
    }
    t.to_csc()
}

/// Every eigenpair of the assembled pencil (dense reference).
pub fn full_eigen(sys: &SystemMatrices) -> GeneralizedEigen {
    generalized_symmetric_eigen(dense(&sys.k).as_ref(), dense(&sys.m).as_ref()).unwrap()
}

pub fn col(a: &Mat<f64>, j: usize) -> Vec<f64> {
    a.col(j).iter().copied().collect()
}

/// `||a - b|| / ||b||`.
pub fn rel(a: &[f64], b: &[f64]) -> f64 {
    let d: f64 = a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum();
    let n: f64 = b.iter().map(|y| y * y).sum();
    (d / n).sqrt()
}

pub fn mul(a: &SparseMatrix, x: &[f64]) -> Vec<f64> {
    let mut y = vec![0.0; a.rows()];
    femu_sparse::csc::mul_vec(a, x, &mut y).unwrap();
    y
}

/// A random symmetric positive definite `n x n` matrix `B B^T + shift I`.
pub fn random_spd(n: usize, shift: f64, rng: &mut Rng) -> Mat<f64> {
    let b = Mat::from_fn(n, n, |_, _| rng.sym());
    let mut a = &b * b.transpose();
    for i in 0..n {
        a[(i, i)] += shift;
    }
    // exact symmetry
    Mat::from_fn(n, n, |i, j| 0.5 * (a[(i, j)] + a[(j, i)]))
}

/// A "test" mode: mode `mode` of the same mesh with Young's modulus scaled by `factor` in the
/// elements whose centroid has `x < x_cut` (a localised modelling error), full length, on the
/// reference model's free DOFs.
pub fn perturbed_mode(model: &Model, x_cut: f64, factor: f64, mode: usize) -> (f64, Vec<f64>) {
    let mesh = model.mesh();
    let mut soft = Vec::new();
    let mut c = Vec::new();
    for e in 0..mesh.element_count() {
        mesh.element_coords(e, &mut c);
        if c.iter().map(|p| p[0]).sum::<f64>() / (c.len() as f64) < x_cut {
            soft.push(mesh.element(e).id);
        }
    }
    let mut mesh2 = mesh.clone();
    mesh2.add_element_set("soft", &soft).unwrap();
    let mut truth = Model::new(mesh2).unwrap();
    truth.set_material(None, Material::steel()).unwrap();
    let mut weak = Material::steel();
    if let femu_fem::material::Elasticity::Isotropic { e, .. } = &mut weak.elasticity {
        *e *= factor;
    }
    truth.set_material(Some("soft"), weak).unwrap();
    for (n, comp) in model.fixed_dofs() {
        truth.fix_nodes(&[mesh.node_id(n)], &[comp]).unwrap();
    }
    let eig = full_eigen(&truth.assemble(MassKind::Consistent).unwrap());
    (eig.values[mode], col(&eig.vectors, mode))
}
