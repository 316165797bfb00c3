//! The identities of docs/MATH.md on small models with a full dense eigendecomposition: the spectral
//! identity (25), the residue relations (5), (9), (12), and the free-free convention.

use super::common::*;
use faer::{Mat, MatRef};
use femu_correlate::correlation::mac_m_matrix;
use femu_correlate::estimators::spectral_terms;
use femu_correlate::residues::{eil_residuals, force_residuals, forced_residual};
use femu_correlate::{Estimator, MassSolver, StiffnessSolver};
use femu_fem::prelude::*;

fn one(x: &[f64]) -> MatRef<'_, f64> {
    MatRef::from_column_major_slice(x, x.len(), 1)
}

/// (25): rho_M^2 = sum_j (lambda_id - lambda_j)^2 MAC_M(x, phi_j), sum_j MAC_M = 1, for a test
/// vector from a model with a localised stiffness error; consistent and lumped mass, clamped and
/// free-free.
#[test]
fn spectral_identity_25_holds_to_machine_precision() {
    for (clamped, mass) in [
        (true, MassKind::Consistent),
        (true, MassKind::Lumped),
        (false, MassKind::Consistent),
    ] {
        let model = bar([6, 2, 1], clamped);
        let sys = model.assemble(mass).unwrap();
        let eig = full_eigen(&sys);
        // a test vector from the "real" structure (20 % softer near the root)
        let (lambda_true, x) = perturbed_mode(&model, 0.05, 0.8, if clamped { 0 } else { 6 });
        let lambda_id = lambda_true * 1.01;
        let est = Estimator::new(&sys.k, &sys.m).unwrap();
        let (norms, _) = est.residual_norms(&[lambda_id], one(&x)).unwrap();
        let terms =
            spectral_terms(&sys.m, lambda_id, &x, &eig.values, eig.vectors.as_ref()).unwrap();
        let sum: f64 = terms.iter().sum();
        let rho2 = norms[0].rho_m * norms[0].rho_m;
        assert!(
            (sum / rho2 - 1.0).abs() < 1e-11,
            "(25) clamped={clamped} {mass:?}: sum {sum:e} vs rho_M^2 {rho2:e}"
        );
        let mac = mac_m_matrix(&sys.m, one(&x), eig.vectors.as_ref()).unwrap();
        let mac_sum: f64 = (0..mac.ncols()).map(|j| mac[(0, j)]).sum();
        assert!((mac_sum - 1.0).abs() < 1e-12, "sum MAC_M = {mac_sum}");
        // Rayleigh residual: rho_R^2 = rho_M^2 - (lambda_id - lambda_R)^2, and by (25) with
        // lambda_R in place of lambda_id.
        let terms_r = spectral_terms(
            &sys.m,
            norms[0].rayleigh,
            &x,
            &eig.values,
            eig.vectors.as_ref(),
        )
        .unwrap();
        let sum_r: f64 = terms_r.iter().sum();
        let rr = norms[0].rho_rayleigh.powi(2);
        assert!(
            (sum_r / rr - 1.0).abs() < 1e-7,
            "rho_R^2 {rr:e} vs {sum_r:e}"
        );
        // rho_2 by hand
        let r = force_residuals(&sys.k, &sys.m, &[lambda_id], one(&x)).unwrap();
        let hand = (r.col(0).squared_norm_l2() / x.iter().map(|v| v * v).sum::<f64>()).sqrt();
        assert!((norms[0].rho_2 / hand - 1.0).abs() < 1e-14);
    }
}

/// (5), (9): K R_ECL = R_F and R_ECL = R_D; (12): -lambda_id M R_EIL = R_F. Clamped model.
#[test]
fn residue_relations_9_and_12_hold() {
    let model = bar([6, 2, 1], true);
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let (l0, x0) = perturbed_mode(&model, 0.06, 0.7, 0);
    let (l1, x1) = perturbed_mode(&model, 0.06, 0.7, 2);
    let n = x0.len();
    let x = Mat::from_fn(n, 2, |i, j| if j == 0 { x0[i] } else { x1[i] });
    let lambdas = [l0 * 0.97, l1 * 1.03];
    let rf = force_residuals(&sys.k, &sys.m, &lambdas, x.as_ref()).unwrap();
    let ks = StiffnessSolver::new(&sys.k, &sys.m).unwrap();
    assert!(ks.null_space().is_none());
    let rd = ks.displacement_residuals(rf.as_ref()).unwrap();
    let (psi, ecl) = ks.ecl_residuals(&lambdas, x.as_ref()).unwrap();
    let chol = MassSolver::cholesky(&sys.m).unwrap();
    let (psi_eil, eil) = eil_residuals(&sys.k, &chol, &lambdas, x.as_ref()).unwrap();
    for j in 0..2 {
        let (rfj, rdj, eclj, eilj) = (col(&rf, j), col(&rd, j), col(&ecl, j), col(&eil, j));
        // (5): K R_D = R_F
        assert!(rel(&mul(&sys.k, &rdj), &rfj) < 1e-10, "(5) mode {j}");
        // (9) and R_ECL = R_D
        assert!(rel(&mul(&sys.k, &eclj), &rfj) < 1e-10, "(9) mode {j}");
        assert!(rel(&eclj, &rdj) < 1e-10, "R_ECL = R_D mode {j}");
        // (8): K Psi = lambda M x
        let rhs: Vec<f64> = mul(&sys.m, &col(&x, j))
            .iter()
            .map(|v| v * lambdas[j])
            .collect();
        assert!(rel(&mul(&sys.k, &col(&psi, j)), &rhs) < 1e-10);
        // (12): -lambda M R_EIL = R_F
        let lhs: Vec<f64> = mul(&sys.m, &eilj).iter().map(|v| -lambdas[j] * v).collect();
        assert!(
            rel(&lhs, &rfj) < 1e-12,
            "(12) mode {j}: {:e}",
            rel(&lhs, &rfj)
        );
        // (11): lambda M Psi = K x
        let mpsi: Vec<f64> = mul(&sys.m, &col(&psi_eil, j))
            .iter()
            .map(|v| v * lambdas[j])
            .collect();
        assert!(rel(&mpsi, &mul(&sys.k, &col(&x, j))) < 1e-12);
    }
    // The default M^-1 path (Jacobi PCG) agrees with the Cholesky one.
    let pcg = MassSolver::new(&sys.m).unwrap();
    assert!(matches!(pcg, MassSolver::Pcg(_)));
    let (_, eil_pcg) = eil_residuals(&sys.k, &pcg, &lambdas, x.as_ref()).unwrap();
    for j in 0..2 {
        assert!(rel(&col(&eil_pcg, j), &col(&eil, j)) < 1e-8);
    }
    // Forced residual (4) with f = (K - w^2 M) u is zero; with f = 0 it is (3).
    let u = col(&x, 0);
    let w2 = lambdas[0];
    let f: Vec<f64> = mul(&sys.k, &u)
        .iter()
        .zip(mul(&sys.m, &u))
        .map(|(a, b)| a - w2 * b)
        .collect();
    let r0 = forced_residual(&sys.k, &sys.m, w2.sqrt(), &u, &f).unwrap();
    assert!(
        r0.iter().map(|v| v.abs()).fold(0.0, f64::max)
            < 1e-9 * f.iter().map(|v| v.abs()).fold(0.0, f64::max)
    );
    let r3 = forced_residual(&sys.k, &sys.m, w2.sqrt(), &u, &vec![0.0; n]).unwrap();
    assert!(rel(&r3, &col(&rf, 0)) < 1e-13);
}

/// Free-free: the null space is found (six rigid-body modes, equal to the dense solution's
/// subspace), K R_D = (I - M Phi_r Phi_r^T) R_F, Phi_r^T M R_D = 0, R_ECL = R_D; a geometric
/// rigid-body basis gives the same residues.
#[test]
fn free_free_convention() {
    let model = bar([5, 2, 1], false);
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let eig = full_eigen(&sys);
    let (lt, x) = perturbed_mode(&model, 0.08, 0.75, 6);
    let lambda = lt * 1.02;
    let rf = force_residuals(&sys.k, &sys.m, &[lambda], one(&x)).unwrap();
    let ks = StiffnessSolver::new(&sys.k, &sys.m).unwrap();
    let phi_r = ks.null_space().expect("singular K detected").to_owned();
    assert_eq!(phi_r.ncols(), 6);
    // Same subspace as the dense rigid modes: the projection of each dense rigid mode on
    // span(Phi_r) in the M inner product keeps its whole norm.
    let c = femu_correlate::correlation::cross_orthogonality(
        &sys.m,
        eig.vectors.as_ref().subcols(0, 6),
        phi_r.as_ref(),
    )
    .unwrap();
    for i in 0..6 {
        let kept: f64 = (0..6).map(|j| c[(i, j)] * c[(i, j)]).sum();
        assert!((kept - 1.0).abs() < 1e-9, "rigid mode {i}: {kept}");
    }
    let rd = ks.displacement_residuals(rf.as_ref()).unwrap();
    let rd0 = col(&rd, 0);
    // K R_D = (I - M Phi_r Phi_r^T) R_F
    let rf0 = col(&rf, 0);
    let mphi = femu_sparse::csc::sym_mul_mat(&sys.m, phi_r.as_ref()).unwrap();
    let coef = phi_r.transpose() * rf.as_ref();
    let load = rf.clone() - &mphi * &coef;
    assert!(
        rel(&mul(&sys.k, &rd0), &col(&load, 0)) < 1e-9,
        "{:e}",
        rel(&mul(&sys.k, &rd0), &col(&load, 0))
    );
    // the projected load is a small correction only (the test vector is nearly elastic)
    assert!(rel(&col(&load, 0), &rf0) < 1.0);
    // Phi_r^T M R_D = 0
    let orth = mphi.transpose() * rd.as_ref();
    let scale = rd0.iter().map(|v| v * v).sum::<f64>().sqrt() * mphi.norm_l2();
    for i in 0..6 {
        assert!(orth[(i, 0)].abs() < 1e-12 * scale);
    }
    // R_ECL = R_D
    let (_, ecl) = ks.ecl_residuals(&[lambda], one(&x)).unwrap();
    assert!(rel(&col(&ecl, 0), &rd0) < 1e-9);
    // Dense reference: R_D = sum over elastic modes of phi_j (phi_j^T R_F) / lambda_j.
    let mut reference = vec![0.0; x.len()];
    for j in 6..eig.values.len() {
        let pj = col(&eig.vectors, j);
        let a: f64 = pj.iter().zip(&rf0).map(|(p, r)| p * r).sum::<f64>() / eig.values[j];
        for (r, p) in reference.iter_mut().zip(&pj) {
            *r += a * p;
        }
    }
    assert!(rel(&rd0, &reference) < 1e-8, "{:e}", rel(&rd0, &reference));
    // Geometric rigid-body motions as the known null space give the same R_D.
    let mesh = model.mesh();
    let dofs = &sys.dofs;
    let geo = Mat::from_fn(x.len(), 6, |f, r| {
        let full = dofs.full_of_free(f);
        let (node, comp) = (full / 3, full % 3);
        let p = mesh.coords()[node];
        if r < 3 {
            if comp == r { 1.0 } else { 0.0 }
        } else {
            // rotation about axis r - 3: omega x p
            let mut w = [0.0; 3];
            w[r - 3] = 1.0;
            let v = [
                w[1] * p[2] - w[2] * p[1],
                w[2] * p[0] - w[0] * p[2],
                w[0] * p[1] - w[1] * p[0],
            ];
            v[comp]
        }
    });
    let ks2 = StiffnessSolver::with_null_space(&sys.k, &sys.m, geo.as_ref()).unwrap();
    let rd2 = ks2.displacement_residuals(rf.as_ref()).unwrap();
    assert!(rel(&col(&rd2, 0), &rd0) < 1e-9);
    // A basis K does not annihilate is refused.
    let wrong = Mat::from_fn(x.len(), 1, |i, _| (i as f64).sin());
    assert!(StiffnessSolver::with_null_space(&sys.k, &sys.m, wrong.as_ref()).is_err());
}

/// rho_M needs no eigenpair: the PCG, Cholesky and diagonal paths agree with a dense `M^-1`.
#[test]
fn mass_solvers_agree_with_dense_inverse() {
    let model = bar([8, 2, 2], true);
    for mass in [MassKind::Consistent, MassKind::Lumped] {
        let sys = model.assemble(mass).unwrap();
        let n = sys.m.rows();
        let mut rng = Rng(7);
        let r = Mat::from_fn(n, 3, |_, _| rng.sym());
        let md = dense(&sys.m);
        let eig = femu_sparse::dense::generalized_symmetric_eigen(
            md.as_ref(),
            Mat::<f64>::identity(n, n).as_ref(),
        )
        .unwrap();
        // M^-1 r = V diag(1/mu) V^T r
        let vt_r = eig.vectors.transpose() * &r;
        let scaled = Mat::from_fn(n, 3, |i, j| vt_r[(i, j)] / eig.values[i]);
        let reference = &eig.vectors * &scaled;
        let solvers = [
            MassSolver::new(&sys.m).unwrap(),
            MassSolver::cholesky(&sys.m).unwrap(),
        ];
        if mass == MassKind::Lumped {
            assert!(matches!(solvers[0], MassSolver::Diagonal(_)));
        }
        for s in &solvers {
            let (z, report) = s.solve(r.as_ref()).unwrap();
            for j in 0..3 {
                assert!(
                    rel(&col(&z, j), &col(&reference, j)) < 1e-8,
                    "{mass:?} {s:?}"
                );
            }
            if let MassSolver::Pcg(_) = s {
                assert!(
                    report.iterations > 0 && report.iterations < 80,
                    "{report:?}"
                );
            }
        }
    }
}

/// A free-free spring chain is singular, yet round-off often leaves every Cholesky pivot
/// positive (the last one about 1e-16 of its diagonal entry). Such a factor must not be taken as
/// definite: its solves return the rigid-body motion amplified by 1 / pivot. The displacement
/// residual must equal the dense spectral sum over the elastic modes
/// `sum_j phi_j phi_j^T b / lambda_j` (docs/MATH.md's free-free convention), on every chain.
#[test]
fn round_off_definite_free_free_stiffness_is_treated_as_singular() {
    use femu_sparse::SparseError;
    use femu_sparse::cholesky::SymbolicFactor;
    use femu_sparse::ordering::Ordering;
    let n = 24;
    let mut fooled = 0;
    for seed in 1..=40u64 {
        let mut rng = Rng(seed);
        let mut k = Mat::<f64>::zeros(n, n);
        for e in 0..n - 1 {
            let s = 0.5 + 1.5 * rng.next_f64();
            k[(e, e)] += s;
            k[(e + 1, e + 1)] += s;
            k[(e, e + 1)] -= s;
            k[(e + 1, e)] -= s;
        }
        let m = Mat::from_fn(n, n, |i, j| if i == j { 0.5 + rng.next_f64() } else { 0.0 });
        let (ks, ms) = (sparse(&k), sparse(&m));
        match SymbolicFactor::new(&ks, Ordering::NestedDissection)
            .unwrap()
            .llt(&ks, "K")
        {
            Err(SparseError::NumericallySingular { ratio, .. }) => {
                assert!(ratio < 1e-12);
                fooled += 1;
            }
            Err(SparseError::NotPositiveDefinite { .. }) => {}
            other => panic!("seed {seed}: a singular K factored as {other:?}"),
        }
        let solver = StiffnessSolver::new(&ks, &ms).unwrap();
        assert_eq!(
            solver.null_space().map(|q| q.ncols()),
            Some(1),
            "seed {seed}"
        );
        let b: Vec<f64> = (0..n).map(|_| rng.sym()).collect();
        let y = solver.solve(one(&b)).unwrap();
        let eig = femu_sparse::dense::generalized_symmetric_eigen(k.as_ref(), m.as_ref()).unwrap();
        let mut reference = vec![0.0; n];
        for j in 1..n {
            let phi = eig.vectors.col(j);
            let c: f64 = (0..n).map(|i| phi[i] * b[i]).sum::<f64>() / eig.values[j];
            for (r, p) in reference.iter_mut().zip(phi.iter()) {
                *r += c * p;
            }
        }
        let err = rel(&col(&y, 0), &reference);
        assert!(
            err < 1e-9,
            "seed {seed}: displacement residual off by {err:e}"
        );
    }
    // the case this test is about must occur among the chains
    assert!(fooled > 0, "no chain had round-off-positive pivots");
}
