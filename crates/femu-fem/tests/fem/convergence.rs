//! Convergence to an exact 3D elasticity spectrum under mesh refinement, for every element kind.
//!
//! Reference: the unit cube with sliding walls (normal displacement zero, tangential traction zero
//! on all six faces). The Navier equation separates exactly: with `k = pi (l, m, n)`, the fields
//! `u_i = a_i sin(k_i x_i) prod_{d != i} cos(k_d x_d)` are eigenmodes with `a` along `k`
//! (P wave, `omega^2 = (lambda + 2 mu) |k|^2 / rho`) or orthogonal to `k` within the axes where
//! `k_d != 0` (S waves, `mu |k|^2 / rho`, multiplicity `nnz(k) - 1`).
//!
//! With consistent mass and exactly integrated elements on the undistorted cube, every discrete
//! eigenvalue is an upper bound of the exact one of the same rank (Rayleigh-Ritz), and the error
//! falls as `h^2` for linear and `h^4` for quadratic elements.

use femu_fem::assembly::MassKind;
use femu_fem::generate::{BoxCells, BoxSpec, box_mesh};
use femu_fem::material::{Material, lame_parameters};
use femu_fem::model::Model;
use femu_sparse::csc::to_dense;
use femu_sparse::dense::generalized_symmetric_eigenvalues;

const E: f64 = 1.0e6;
const NU: f64 = 0.25;
const RHO: f64 = 1.0;

fn exact_spectrum(count: usize) -> Vec<f64> {
    let (l, mu) = lame_parameters(E, NU);
    let pi2 = std::f64::consts::PI.powi(2);
    let mut v = Vec::new();
    for a in 0..6usize {
        for b in 0..6usize {
            for c in 0..6usize {
                let nnz = [a, b, c].iter().filter(|x| **x > 0).count();
                if nnz == 0 {
                    continue;
                }
                let k2 = pi2 * (a * a + b * b + c * c) as f64;
                v.push((l + 2.0 * mu) * k2 / RHO);
                for _ in 1..nnz {
                    v.push(mu * k2 / RHO);
                }
            }
        }
    }
    v.sort_by(f64::total_cmp);
    v.truncate(count);
    v
}

fn discrete_spectrum(cells: BoxCells, quadratic: bool, n: usize, count: usize) -> Vec<f64> {
    let mesh = box_mesh(&BoxSpec::new([1.0; 3], [n; 3], cells, quadratic)).unwrap();
    let mut model = Model::new(mesh).unwrap();
    model
        .set_material(None, Material::isotropic("m", E, NU, RHO).unwrap())
        .unwrap();
    for (i, (lo, hi)) in [("xmin", "xmax"), ("ymin", "ymax"), ("zmin", "zmax")]
        .iter()
        .enumerate()
    {
        model.fix_set(lo, &[i]).unwrap();
        model.fix_set(hi, &[i]).unwrap();
    }
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let e = generalized_symmetric_eigenvalues(to_dense(&sys.k).as_ref(), to_dense(&sys.m).as_ref())
        .unwrap();
    e[..count].to_vec()
}

/// Relative error of the lowest cluster (three-fold S mode (1,1,0)), averaged over the cluster
/// so that a mesh which splits the multiplicity is measured fairly.
fn cluster_error(d: &[f64], x: &[f64]) -> f64 {
    (d[..3].iter().sum::<f64>() / x[..3].iter().sum::<f64>()) - 1.0
}

#[test]
fn eigenvalues_converge_at_the_expected_rate_for_every_element_kind() {
    let count = 12;
    let exact = exact_spectrum(count);
    // (cells, quadratic, coarse n, fine n, minimum observed order)
    let cases = [
        (BoxCells::Hex, false, 3, 6, 1.8),
        (BoxCells::Wedge, false, 3, 6, 1.8),
        (BoxCells::Tet6, false, 3, 6, 1.8),
        (BoxCells::Hex, true, 2, 3, 3.5),
        (BoxCells::Wedge, true, 2, 3, 3.5),
        (BoxCells::Tet6, true, 3, 4, 3.5),
    ];
    let mut table = String::new();
    for (cells, quadratic, n1, n2, min_order) in cases {
        let d1 = discrete_spectrum(cells, quadratic, n1, count);
        let d2 = discrete_spectrum(cells, quadratic, n2, count);
        for (d, n) in [(&d1, n1), (&d2, n2)] {
            for i in 0..count {
                assert!(
                    d[i] >= exact[i] * (1.0 - 1e-10),
                    "{cells:?} q={quadratic} n={n}: mode {i} below exact: {} < {}",
                    d[i],
                    exact[i]
                );
            }
        }
        let (e1, e2) = (cluster_error(&d1, &exact), cluster_error(&d2, &exact));
        let order = (e1 / e2).ln() / (n2 as f64 / n1 as f64).ln();
        table.push_str(&format!("{cells:?} quadratic={quadratic}: err(n={n1}) = {e1:.3e}, err(n={n2}) = {e2:.3e}, order {order:.2}\n"));
        assert!(
            order > min_order,
            "{cells:?} q={quadratic}: observed order {order:.2} (errors {e1:e}, {e2:e})"
        );
        assert!(
            order < min_order + 1.5,
            "{cells:?} q={quadratic}: order {order:.2} implausibly high"
        );
    }
    println!("{table}");
}
