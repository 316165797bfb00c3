//! The 8-node brick with incompatible modes (`kernel::hex8_incompatible_stiffness`) against
//! analytic references: the patch test on distorted bricks, six rigid-body modes, and pure
//! bending of a rectangular brick, which it represents exactly where the fully integrated brick
//! locks.

use super::common::*;
use femu_fem::element::{ElementKind, Formulation};
use femu_fem::kernel;
use femu_fem::material::Material;
use femu_sparse::dense::symmetric_eigen;

/// The brick's stiffness by both kernels: `B^T D B` with the material's `D`, and the isotropic
/// Gram-matrix form that the assembly uses for isotropic materials.
fn incompatible(x: &[[f64; 3]], mat: &Material) -> [Vec<f64>; 2] {
    let mut k = vec![0.0; 24 * 24];
    kernel::hex8_incompatible_stiffness(x, &mat.elasticity_matrix(), &mut k).unwrap();
    let mut iso = vec![0.0; 24 * 24];
    kernel::element_stiffness_for(
        ElementKind::Hex8,
        Formulation::IncompatibleModes,
        x,
        mat,
        &mut iso,
    )
    .unwrap();
    [k, iso]
}

fn energy(k: &[f64], u: &[f64]) -> f64 {
    let n = u.len();
    0.5 * (0..n)
        .map(|i| u[i] * (0..n).map(|j| k[i * n + j] * u[j]).sum::<f64>())
        .sum::<f64>()
}

/// A linear field `u = A x + b` on a distorted brick: the bubbles stay at rest (Taylor's
/// centre-Jacobian form), so the strain energy is `1/2 eps : D : eps V` exactly, as for the fully
/// integrated brick; the six rigid-body motions have zero energy and every other mode a positive
/// one.
#[test]
fn patch_test_and_rigid_modes_on_distorted_bricks() {
    let steel = Material::isotropic("steel", 2.1e11, 0.3, 7850.0).unwrap();
    let d = steel.elasticity_matrix();
    let a = [
        [1e-3, 2e-4, -3e-4],
        [5e-4, -2e-3, 1e-4],
        [-7e-4, 3e-4, 4e-3],
    ];
    // Voigt strain (11, 22, 33, 2*12, 2*13, 2*23) of sym(A)
    let eps = [
        a[0][0],
        a[1][1],
        a[2][2],
        a[0][1] + a[1][0],
        a[0][2] + a[2][0],
        a[1][2] + a[2][1],
    ];
    let exact_density: f64 = 0.5
        * (0..6)
            .map(|i| eps[i] * (0..6).map(|j| d[i][j] * eps[j]).sum::<f64>())
            .sum::<f64>();
    let mut rng = Rng(11);
    for distortion in [0.0, 0.1, 0.2] {
        let x = element_coords(ElementKind::Hex8, distortion, false, &mut rng);
        for k in incompatible(&x, &steel) {
            let volume = kernel::element_volume(ElementKind::Hex8, &x).unwrap();
            let u: Vec<f64> = x
                .iter()
                .flat_map(|p| {
                    (0..3).map(move |i| (0..3).map(|j| a[i][j] * p[j]).sum::<f64>() + 0.01)
                })
                .collect();
            let e = energy(&k, &u);
            let want = exact_density * volume;
            assert!(
                (e - want).abs() <= 1e-11 * want,
                "distortion {distortion}: energy {e} against {want}"
            );
            for r in rigid_modes(&x) {
                let kr: Vec<f64> = (0..24)
                    .map(|i| (0..24).map(|j| k[i * 24 + j] * r[j]).sum::<f64>())
                    .collect();
                let scale = k.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
                assert!(kr.iter().all(|v| v.abs() <= 1e-12 * scale), "{distortion}");
            }
            let (values, _) = symmetric_eigen(dense(&k, 24).as_ref()).unwrap();
            let top = values.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            let zero = values.iter().filter(|v| v.abs() <= 1e-10 * top).count();
            assert_eq!(zero, 6, "distortion {distortion}: {values:?}");
            assert!(values.iter().all(|v| *v > -1e-10 * top));
        }
    }
}

/// Pure bending of a rectangular brick `a x b x c` centred at the origin, `nu = 0`:
/// `u_x = kappa x z`, `u_z = -kappa x^2 / 2` is the exact solution (strain `kappa z` alone), with
/// energy `1/2 E kappa^2 a b c^3 / 12`. With the nodal values of that field the incompatible-mode
/// brick's energy is exact (its `x` bubble carries `u_z`'s parabola); the fully integrated brick,
/// which cannot bend without shear, stores more (the shear locking measured in
/// docs/VERIFICATION.md).
#[test]
fn pure_bending_of_a_rectangular_brick_is_exact() {
    let (a, b, c) = (0.4, 0.1, 0.05);
    let young = 7.0e10;
    let mat = Material::isotropic("aluminium", young, 0.0, 2700.0).unwrap();
    let d = mat.elasticity_matrix();
    let x: Vec<[f64; 3]> = ElementKind::Hex8
        .reference_nodes()
        .iter()
        .map(|p| [0.5 * a * p[0], 0.5 * b * p[1], 0.5 * c * p[2]])
        .collect();
    let kappa = 1e-3;
    let u: Vec<f64> = x
        .iter()
        .flat_map(|p| [kappa * p[0] * p[2], 0.0, -0.5 * kappa * p[0] * p[0]])
        .collect();
    let exact = 0.5 * young * kappa * kappa * a * b * c.powi(3) / 12.0;
    for k in incompatible(&x, &mat) {
        let e = energy(&k, &u);
        assert!((e - exact).abs() <= 1e-12 * exact, "{e} against {exact}");
    }
    let mut plain = vec![0.0; 24 * 24];
    kernel::element_stiffness(ElementKind::Hex8, &x, &d, &mut plain).unwrap();
    // the plain brick interpolates u_z as a constant, so the same nodal values strain it in
    // shear gamma_xz = kappa x: 1/2 G kappa^2 b c a^3 / 12 more, (G / E) (a / c)^2 = 32 times the
    // bending energy here (G = E / 2 at nu = 0; the 2x2x2 rule integrates x^2 exactly)
    let locked = energy(&plain, &u);
    let ratio = 1.0 + 0.5 * (a / c).powi(2);
    assert!(
        (locked - ratio * exact).abs() <= 1e-12 * locked,
        "{locked} against {}",
        ratio * exact
    );
}
