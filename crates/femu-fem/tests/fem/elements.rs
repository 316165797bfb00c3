//! Element-level evidence: patch tests, rigid-body modes, mass, a closed-form hex8, snapshots.

use super::common::*;
use femu_fem::element::{ALL_KINDS, ElementKind};
use femu_fem::kernel;
use femu_fem::material::Material;
use femu_sparse::dense::generalized_symmetric_eigen;
use proptest::prelude::*;

fn matrices(kind: ElementKind, x: &[[f64; 3]], mat: &Material) -> (Vec<f64>, Vec<f64>) {
    let nd = 3 * kind.num_nodes();
    let (mut k, mut m) = (vec![0.0; nd * nd], vec![0.0; nd * nd]);
    kernel::element_stiffness(kind, x, &mat.elasticity_matrix(), &mut k).unwrap();
    kernel::element_mass(kind, x, mat.density, &mut m).unwrap();
    (k, m)
}

fn mat_vec(a: &[f64], x: &[f64]) -> Vec<f64> {
    let n = x.len();
    (0..n)
        .map(|i| (0..n).map(|j| a[i * n + j] * x[j]).sum())
        .collect()
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Patch test, strain form: nodal values of a linear field u = A x + b give the constant strain
/// sym(A) at any point of any (distorted, curved) isoparametric element.
#[test]
fn linear_field_gives_constant_strain_in_every_element() {
    let mut rng = Rng(7);
    let a = [
        [1e-3, 2e-4, -3e-4],
        [5e-4, -2e-3, 1e-4],
        [-7e-4, 3e-4, 4e-3],
    ];
    let expect = [
        a[0][0],
        a[1][1],
        a[2][2],
        a[0][1] + a[1][0],
        a[0][2] + a[2][0],
        a[1][2] + a[2][1],
    ];
    for kind in ALL_KINDS {
        let x = element_coords(kind, 0.08, true, &mut rng);
        let u: Vec<f64> = x
            .iter()
            .flat_map(|p| {
                (0..3).map(move |i| 0.01 * i as f64 + (0..3).map(|k| a[i][k] * p[k]).sum::<f64>())
            })
            .collect();
        for xi in [[0.2, 0.3, 0.1], [0.1, 0.1, 0.6], [0.25, 0.25, -0.5]] {
            let xi = if matches!(kind, ElementKind::Tet4 | ElementKind::Tet10) && xi[2] < 0.0 {
                [0.1, 0.2, 0.3]
            } else {
                xi
            };
            let e = kernel::strain_at(kind, &x, &u, xi).unwrap();
            for c in 0..6 {
                assert!(
                    (e[c] - expect[c]).abs() < 1e-15 + 1e-12 * 4e-3,
                    "{kind} at {xi:?}: strain[{c}] {} vs {}",
                    e[c],
                    expect[c]
                );
            }
        }
    }
}

/// Each free element has exactly six zero eigenvalues of (K_e, M_e): rigid-body motions, no
/// spurious (hourglass) mode; and K_e annihilates the six rigid motions.
#[test]
fn free_element_has_exactly_six_rigid_body_modes() {
    let mut rng = Rng(11);
    let steel = Material::steel();
    for kind in ALL_KINDS {
        let x = element_coords(kind, 0.06, true, &mut rng);
        let nd = 3 * kind.num_nodes();
        let (k, m) = matrices(kind, &x, &steel);
        let knorm = norm(&k);
        for r in rigid_modes(&x) {
            let kr = mat_vec(&k, &r);
            assert!(
                norm(&kr) < 1e-12 * knorm * norm(&r),
                "{kind}: |K r| = {}",
                norm(&kr)
            );
        }
        let eig =
            generalized_symmetric_eigen(dense(&k, nd).as_ref(), dense(&m, nd).as_ref()).unwrap();
        let lmax = *eig.values.last().unwrap();
        let zeros = eig.values.iter().filter(|l| l.abs() < 1e-9 * lmax).count();
        assert_eq!(zeros, 6, "{kind}: eigenvalues {:?}", &eig.values[..8]);
        assert!(
            eig.values[6] > 1e-4 * lmax,
            "{kind}: seventh eigenvalue {} vs max {lmax}",
            eig.values[6]
        );
    }
}

/// u^T M u for a unit rigid translation equals rho * volume (the volume of an affinely mapped
/// reference cell is det(A) times the reference volume), for consistent and lumped mass, and
/// both masses are positive definite.
#[test]
fn mass_of_rigid_translation_is_rho_times_volume() {
    let mut rng = Rng(3);
    let rho = 2700.0;
    let mat = Material::isotropic("al", 70e9, 0.33, rho).unwrap();
    for kind in ALL_KINDS {
        let x = element_coords(kind, 0.0, false, &mut rng);
        let volume = det3(&AFFINE) * kind.reference_volume();
        let nd = 3 * kind.num_nodes();
        let (_, m) = matrices(kind, &x, &mat);
        for i in 0..3 {
            let u: Vec<f64> = (0..nd)
                .map(|d| if d % 3 == i { 1.0 } else { 0.0 })
                .collect();
            let mu = mat_vec(&m, &u);
            let um: f64 = u.iter().zip(&mu).map(|(a, b)| a * b).sum();
            assert!(
                (um / (rho * volume) - 1.0).abs() < 1e-13,
                "{kind}: {um} vs {}",
                rho * volume
            );
        }
        let mut lumped = vec![0.0; kind.num_nodes()];
        kernel::lumped_mass(kind, &x, rho, &mut lumped).unwrap();
        assert!(lumped.iter().all(|v| *v > 0.0), "{kind}: lumped {lumped:?}");
        assert!((lumped.iter().sum::<f64>() / (rho * volume) - 1.0).abs() < 1e-13);
        // positive definite: the dense Cholesky succeeds (eigen of (M, I))
        let eye = faer::Mat::<f64>::identity(nd, nd);
        let e = generalized_symmetric_eigen(dense(&m, nd).as_ref(), eye.as_ref()).unwrap();
        assert!(
            e.values[0] > 1e-6 * e.values[nd - 1],
            "{kind}: consistent mass not definite: {}",
            e.values[0]
        );
    }
    // Exact integration matters: the row sums of a quadratic element's consistent mass include
    // non-positive corner masses (hence HRZ).
    let x = element_coords(ElementKind::Tet10, 0.0, false, &mut rng);
    let mut s = vec![0.0; 100];
    kernel::scalar_mass(ElementKind::Tet10, &x, 1.0, &mut s).unwrap();
    assert!(
        (0..4).all(|a| s[a * 10..a * 10 + 10].iter().sum::<f64>() <= 1e-15),
        "tet10 corner row sums are not positive"
    );
}

/// The unit-cube hex8 against closed forms built from 1D linear-element integrals (exact, since
/// 2x2x2 Gauss integrates the cube's polynomials exactly):
/// `S_ij(a, b) = int dN_a/dx_i dN_b/dx_j = prod_d (K1 | G1 | M1)`,
/// `K_ab,ij = lambda S_ij + mu S_ji + mu delta_ij sum_k S_kk`, `M_ab = rho prod_d M1`.
#[test]
fn hex8_cube_equals_tensor_product_closed_form() {
    let h = 0.5;
    let (e, nu, rho) = (1.0e6, 0.3, 1000.0);
    let (l, mu) = femu_fem::material::lame_parameters(e, nu);
    let bits: Vec<[usize; 3]> = ElementKind::Hex8
        .reference_nodes()
        .iter()
        .map(|p| p.map(|c| if c > 0.0 { 1 } else { 0 }))
        .collect();
    let x: Vec<[f64; 3]> = bits.iter().map(|b| b.map(|c| h * c as f64)).collect();
    let m1 = |a: usize, b: usize| h / 6.0 * if a == b { 2.0 } else { 1.0 };
    let k1 = |a: usize, b: usize| if a == b { 1.0 / h } else { -1.0 / h };
    let g1 = |a: usize, _b: usize| if a == 0 { -0.5 } else { 0.5 }; // int N_a' N_b
    let s = |i: usize, j: usize, a: usize, b: usize| -> f64 {
        (0..3)
            .map(|d| {
                let (ad, bd) = (bits[a][d], bits[b][d]);
                if i == j && d == i {
                    k1(ad, bd)
                } else if d == i {
                    g1(ad, bd)
                } else if d == j {
                    g1(bd, ad)
                } else {
                    m1(ad, bd)
                }
            })
            .product()
    };
    let mat = Material::isotropic("m", e, nu, rho).unwrap();
    let (k, m) = matrices(ElementKind::Hex8, &x, &mat);
    let kmax = k.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
    for a in 0..8 {
        for b in 0..8 {
            for i in 0..3 {
                for j in 0..3 {
                    let trace: f64 = (0..3).map(|q| s(q, q, a, b)).sum();
                    let expect = l * s(i, j, a, b)
                        + mu * s(j, i, a, b)
                        + if i == j { mu * trace } else { 0.0 };
                    let got = k[(3 * a + i) * 24 + 3 * b + j];
                    assert!(
                        (got - expect).abs() < 1e-13 * kmax,
                        "K[{a}{i},{b}{j}] = {got} vs {expect}"
                    );
                    let mexp = if i == j {
                        rho * (0..3).map(|d| m1(bits[a][d], bits[b][d])).product::<f64>()
                    } else {
                        0.0
                    };
                    assert!(
                        (m[(3 * a + i) * 24 + 3 * b + j] - mexp).abs() < 1e-13 * rho * h * h * h
                    );
                }
            }
        }
    }
}

/// The quadratic elements' rules are exact for undistorted elements: a richer rule gives the same
/// matrices (hex20: 3x3x3 against 5x5x5; wedge15: degree 4 against an 8x8x4 collapsed rule).
#[test]
fn quadratic_rules_are_exact_on_undistorted_elements() {
    use femu_fem::quadrature::{QuadratureRule, hex_gauss};
    let mut rng = Rng(5);
    let mat = Material::steel();
    let d = mat.elasticity_matrix();
    // Reference integration with an arbitrary rule, written out independently of the kernel.
    let reference =
        |kind: ElementKind, x: &[[f64; 3]], rule: &QuadratureRule| -> (Vec<f64>, Vec<f64>) {
            let nn = kind.num_nodes();
            let nd = 3 * nn;
            let (mut k, mut m) = (vec![0.0; nd * nd], vec![0.0; nd * nd]);
            let (mut n, mut dn) = (vec![0.0; nn], vec![0.0; 3 * nn]);
            for (p, w) in rule.points.iter().zip(&rule.weights) {
                kind.shape(*p, &mut n);
                kind.shape_gradients(*p, &mut dn);
                let j = nalgebra::Matrix3::from_fn(|i, c| {
                    (0..nn).map(|a| x[a][i] * dn[3 * a + c]).sum::<f64>()
                });
                let det = j.determinant();
                let jinv = j.try_inverse().unwrap();
                let mut b = nalgebra::DMatrix::<f64>::zeros(6, nd);
                for a in 0..nn {
                    let g = jinv.transpose()
                        * nalgebra::Vector3::new(dn[3 * a], dn[3 * a + 1], dn[3 * a + 2]);
                    let c = 3 * a;
                    b[(0, c)] = g[0];
                    b[(1, c + 1)] = g[1];
                    b[(2, c + 2)] = g[2];
                    b[(3, c)] = g[1];
                    b[(3, c + 1)] = g[0];
                    b[(4, c)] = g[2];
                    b[(4, c + 2)] = g[0];
                    b[(5, c + 1)] = g[2];
                    b[(5, c + 2)] = g[1];
                }
                let dm = nalgebra::DMatrix::from_fn(6, 6, |r, c| d[r][c]);
                let kq = b.transpose() * dm * &b * (w * det);
                for r in 0..nd {
                    for c in 0..nd {
                        k[r * nd + c] += kq[(r, c)];
                        if r % 3 == c % 3 {
                            m[r * nd + c] += mat.density * n[r / 3] * n[c / 3] * w * det;
                        }
                    }
                }
            }
            (k, m)
        };
    let wedge_rich = {
        // collapsed-square triangle rule (8x8) times 8 Gauss points in zeta
        let (gx, gw) = femu_fem::quadrature::gauss_legendre(8);
        let mut r = QuadratureRule {
            points: vec![],
            weights: vec![],
        };
        for (u, wu) in gx.iter().zip(&gw) {
            for (v, wv) in gx.iter().zip(&gw) {
                for (z, wz) in gx.iter().zip(&gw) {
                    let (uu, vv) = (0.5 * (u + 1.0), 0.5 * (v + 1.0));
                    r.points.push([uu, (1.0 - uu) * vv, *z]);
                    r.weights.push(0.25 * wu * wv * wz * (1.0 - uu));
                }
            }
        }
        r
    };
    let pyramid_rich = {
        // the collapsed cube with 8 Gauss points per direction, written out here
        let (gx, gw) = femu_fem::quadrature::gauss_legendre(8);
        let mut r = QuadratureRule {
            points: vec![],
            weights: vec![],
        };
        for (a, wa) in gx.iter().zip(&gw) {
            for (b, wb) in gx.iter().zip(&gw) {
                for (t, wt) in gx.iter().zip(&gw) {
                    let c = 0.5 * (t + 1.0);
                    r.points.push([a * (1.0 - c), b * (1.0 - c), c]);
                    r.weights.push(wa * wb * 0.5 * wt * (1.0 - c) * (1.0 - c));
                }
            }
        }
        r
    };
    for (kind, rule) in [
        (ElementKind::Pyramid13, pyramid_rich.clone()),
        (ElementKind::Pyramid5, pyramid_rich),
        (ElementKind::Hex20, hex_gauss(5)),
        (ElementKind::Hex8, hex_gauss(4)),
        (ElementKind::Penta15, wedge_rich.clone()),
        (ElementKind::Penta6, wedge_rich),
        (ElementKind::Tet10, femu_fem::quadrature::tet_conical(6)),
    ] {
        let x = element_coords(kind, 0.0, false, &mut rng);
        let (k, m) = matrices(kind, &x, &mat);
        let (kr, mr) = reference(kind, &x, &rule);
        let (ks, ms) = (norm(&kr), norm(&mr));
        let dk = norm(&k.iter().zip(&kr).map(|(a, b)| a - b).collect::<Vec<_>>()) / ks;
        let dm = norm(&m.iter().zip(&mr).map(|(a, b)| a - b).collect::<Vec<_>>()) / ms;
        assert!(
            dk < 1e-13 && dm < 1e-13,
            "{kind}: stiffness differs by {dk:e}, mass by {dm:e}"
        );
    }
}

/// Snapshots of one element's K_e and M_e per kind (reference geometry under the test's affine
/// map, E = 1, nu = 0.3, rho = 1), upper triangles, 6 significant digits.
#[test]
fn element_matrix_snapshots() {
    let mat = Material::isotropic("unit", 1.0, 0.3, 1.0).unwrap();
    let mut rng = Rng(0);
    for kind in ALL_KINDS {
        let x = element_coords(kind, 0.0, false, &mut rng);
        let (k, m) = matrices(kind, &x, &mat);
        let nd = 3 * kind.num_nodes();
        let fmt = |a: &[f64]| -> String {
            let mut s = String::new();
            for r in 0..nd {
                let row: Vec<String> = (r..nd)
                    .map(|c| {
                        let v = a[r * nd + c];
                        if v.abs() < 1e-12 {
                            "0".to_string()
                        } else {
                            format!("{v:.5e}")
                        }
                    })
                    .collect();
                s.push_str(&row.join(" "));
                s.push('\n');
            }
            s
        };
        insta::assert_snapshot!(format!("{kind}_stiffness"), fmt(&k));
        insta::assert_snapshot!(format!("{kind}_mass"), fmt(&m));
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    /// For random distorted elements: K_e symmetric, rigid motions in its null space, consistent
    /// mass symmetric positive definite.
    #[test]
    fn random_elements_keep_their_invariants(seed in 0u64..1_000_000, kind_i in 0usize..6, dist in 0.0f64..0.1) {
        let kind = ALL_KINDS[kind_i];
        let mut rng = Rng(seed);
        let x = element_coords(kind, dist, true, &mut rng);
        let mat = Material::isotropic("p", 1e9 * (1.0 + rng.next_f64()), 0.45 * rng.sym(), 1000.0).unwrap();
        let nd = 3 * kind.num_nodes();
        let (k, m) = matrices(kind, &x, &mat);
        let kn = norm(&k);
        for r in 0..nd {
            for c in 0..nd {
                prop_assert!((k[r * nd + c] - k[c * nd + r]).abs() <= 1e-14 * kn);
                prop_assert!(m[r * nd + c] == m[c * nd + r]);
            }
        }
        for rm in rigid_modes(&x) {
            prop_assert!(norm(&mat_vec(&k, &rm)) < 1e-11 * kn * norm(&rm));
        }
        let eye = faer::Mat::<f64>::identity(nd, nd);
        let e = generalized_symmetric_eigen(dense(&m, nd).as_ref(), eye.as_ref()).unwrap();
        prop_assert!(e.values[0] > 0.0);
    }
}

/// The isotropic kernel (Gram matrix of the gradients) equals `B^T D B` with the isotropic `D` on
/// distorted and curved elements of every kind, for a compressible and a nearly incompressible
/// material.
#[test]
fn isotropic_kernel_equals_the_general_one() {
    let mut rng = Rng(17);
    for nu in [0.3, 0.499] {
        let mat = Material::isotropic("m", 2.1e11, nu, 7850.0).unwrap();
        let (lambda, mu) = femu_fem::material::lame_parameters(2.1e11, nu);
        for kind in ALL_KINDS {
            let x = element_coords(kind, 0.1, true, &mut rng);
            let nd = 3 * kind.num_nodes();
            let (mut k1, mut k2) = (vec![0.0; nd * nd], vec![0.0; nd * nd]);
            kernel::element_stiffness(kind, &x, &mat.elasticity_matrix(), &mut k1).unwrap();
            kernel::element_stiffness_isotropic(kind, &x, lambda, mu, &mut k2).unwrap();
            let scale = norm(&k1);
            let diff = norm(&k1.iter().zip(&k2).map(|(a, b)| a - b).collect::<Vec<_>>());
            assert!(diff < 1e-14 * scale, "{kind} nu {nu}: {:e}", diff / scale);
        }
    }
}
