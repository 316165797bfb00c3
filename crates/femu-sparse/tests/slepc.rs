//! SLEPc (Krylov-Schur, shift-and-invert, MUMPS) under MPI against femu's own eigensolver on
//! small solid models, clamped and free-free, hex8 and tet10, with 2 ranks: the same eigenvalues
//! and vectors to 1e-9, the same count by inertia, the solves and the factor's entries SLEPc
//! reports within what they must be; a skipped mode is caught by the count; a missing engine says
//! what to install. `.ci/run` installs SLEPc and sets `FEMU_REQUIRE_SLEPC=1`,
//! so in CI a missing SLEPc is a failure; elsewhere the tests say they were skipped.

use femu_fem::prelude::*;
use femu_sparse::SparseError;
use femu_sparse::eigen::{EigenOptions, Which, eigs};
use femu_sparse::slepc::{Engine, SlepcOptions, probe, run};

fn available() -> bool {
    match probe(&SlepcOptions::default()) {
        Ok(_) => true,
        Err(e) => {
            if std::env::var_os("FEMU_REQUIRE_SLEPC").is_some() {
                panic!("FEMU_REQUIRE_SLEPC is set but {e}");
            }
            eprintln!("skipped: {e}");
            false
        }
    }
}

fn two_ranks() -> EigenOptions {
    EigenOptions {
        engine: Engine::Slepc(SlepcOptions {
            ranks: 2,
            ..Default::default()
        }),
        ..Default::default()
    }
}

fn femu_engine() -> EigenOptions {
    EigenOptions {
        engine: Engine::Femu,
        ..Default::default()
    }
}

fn tet10_block(clamped: bool) -> Model {
    let mesh = box_mesh(&BoxSpec::new(
        [0.1, 0.05, 0.03],
        [4, 2, 2],
        BoxCells::Tet6,
        true,
    ))
    .unwrap();
    let mut model = Model::new(mesh).unwrap();
    model.set_material(None, Material::steel()).unwrap();
    if clamped {
        model.fix_set("xmin", &[0, 1, 2]).unwrap();
    }
    model
}

/// Eigenvalues equal to `1e-9` relative; each vector of a simple eigenvalue equal up to sign to
/// `1e-9` (in the `M` norm); the spaces of a repeated one (rigid-body modes) equal by projection.
fn agree(sys: &SystemMatrices, count: usize, name: &str) {
    let ours = eigs(&sys.k, &sys.m, Which::Lowest(count), &femu_engine()).unwrap();
    let theirs = eigs(&sys.k, &sys.m, Which::Lowest(count), &two_ranks()).unwrap();
    assert_eq!(ours.values.len(), theirs.values.len(), "{name}");
    assert!(theirs.sturm.verified(), "{name}: {:?}", theirs.sturm);
    assert_eq!(theirs.sturm.count, ours.values.len(), "{name}");
    // the work SLEPc reports: a solve for each vector of its basis, which holds the pairs it
    // converged; a factor holding at least the lower triangle of K - sigma M (the pattern of `L`
    // contains the permuted matrix's, M's pattern inside K's) and at most the dense triangle
    let (n, s) = (sys.k.rows(), &theirs.stats);
    assert!(s.solved_vectors >= theirs.values.len(), "{name}: {s:?}");
    assert!(
        (sys.k.nnz() + n) / 2 <= s.factor_len && s.factor_len <= n * (n + 1) / 2,
        "{name}: {} entries in MUMPS's factor of a {n} x {n} matrix with {} stored",
        s.factor_len,
        sys.k.nnz()
    );
    let scale = ours.values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for (j, (a, b)) in ours.values.iter().zip(&theirs.values).enumerate() {
        assert!((a - b).abs() <= 1e-9 * scale, "{name} mode {j}: {a} vs {b}");
    }
    // M-inner products between the two sets: block-diagonal orthogonal on repeated eigenvalues
    let mut mphi = faer::Mat::<f64>::zeros(n, theirs.values.len());
    for j in 0..theirs.values.len() {
        let x: Vec<f64> = (0..n).map(|i| theirs.vectors[(i, j)]).collect();
        let mut y = vec![0.0; n];
        femu_sparse::csc::mul_vec(&sys.m, &x, &mut y).unwrap();
        for i in 0..n {
            mphi[(i, j)] = y[i];
        }
    }
    let c = ours.vectors.transpose() * &mphi;
    for i in 0..ours.values.len() {
        // the part of our vector i in their vectors of (numerically) the same eigenvalue
        let same: f64 = (0..theirs.values.len())
            .filter(|&j| (ours.values[i] - theirs.values[j]).abs() <= 1e-6 * scale)
            .map(|j| c[(i, j)] * c[(i, j)])
            .sum();
        assert!(
            (same - 1.0).abs() < 1e-9,
            "{name} mode {i}: captured {same}"
        );
    }
    assert!(
        theirs.residuals.iter().all(|r| *r < 1e-8),
        "{name}: {:?}",
        theirs.residuals
    );
}

#[test]
fn slepc_equals_femu_on_clamped_and_free_models() {
    if !available() {
        return;
    }
    for (name, model, count) in [
        ("hex8 clamped", femu_testkit::bar([10, 2, 2], true), 8),
        ("hex8 free-free", femu_testkit::bar([10, 2, 2], false), 10),
        ("tet10 clamped", tet10_block(true), 8),
        ("tet10 free-free", tet10_block(false), 10),
    ] {
        let sys = model.assemble(MassKind::Consistent).unwrap();
        agree(&sys, count, name);
    }
}

#[test]
fn a_skipped_mode_is_caught_by_the_count() {
    if !available() {
        return;
    }
    let sys = femu_testkit::bar([10, 2, 2], true)
        .assemble(MassKind::Consistent)
        .unwrap();
    let params = two_ranks();
    let Engine::Slepc(opts) = &params.engine else {
        unreachable!()
    };
    let mut r = run(&sys.k, &sys.m, Which::Lowest(6), &params, opts).unwrap();
    // drop the third eigenpair, as a solver that skipped it would
    r.values.remove(2);
    let keep: Vec<usize> = (0..r.vectors.ncols()).filter(|&j| j != 2).collect();
    r.vectors = faer::Mat::from_fn(r.vectors.nrows(), keep.len(), |i, j| {
        r.vectors[(i, keep[j])]
    });
    match r.into_modes(&sys.k, &sys.m, Which::Lowest(6), &params) {
        Err(SparseError::SturmMismatch {
            count, returned, ..
        }) => {
            assert_eq!((count, returned), (6, 5));
        }
        other => panic!("a skipped mode passed: {:?}", other.map(|m| m.values)),
    }
    // the nearest modes around a shift in the spectrum: an interval counted at both ends
    let ours = eigs(
        &sys.k,
        &sys.m,
        Which::Nearest {
            shift: 4e8,
            count: 3,
        },
        &femu_engine(),
    )
    .unwrap();
    let theirs = eigs(
        &sys.k,
        &sys.m,
        Which::Nearest {
            shift: 4e8,
            count: 3,
        },
        &params,
    )
    .unwrap();
    assert!(theirs.sturm.lower.is_some() && theirs.sturm.verified());
    for (a, b) in ours.values.iter().zip(&theirs.values) {
        assert!((a / b - 1.0).abs() < 1e-9, "{a} vs {b}");
    }
    // every eigenvalue in a band (SLEPc's spectrum slicing), counted at both ends
    let band = Which::Band { lo: 1e8, hi: 3e9 };
    let ours = eigs(&sys.k, &sys.m, band, &femu_engine()).unwrap();
    let theirs = eigs(&sys.k, &sys.m, band, &params).unwrap();
    assert_eq!(ours.values.len(), theirs.values.len());
    assert!(!theirs.values.is_empty() && theirs.sturm.verified());
    // its solves counted, its slices' factors not reported
    let s = &theirs.stats;
    assert!(
        s.solved_vectors >= theirs.values.len() && s.factor_len == 0,
        "{s:?}"
    );
    for (a, b) in ours.values.iter().zip(&theirs.values) {
        assert!((a / b - 1.0).abs() < 1e-9, "{a} vs {b}");
    }
}

#[test]
fn a_missing_engine_says_what_to_install() {
    let opts = SlepcOptions {
        python: "/nonexistent/python3".into(),
        ..Default::default()
    };
    let e = probe(&opts).unwrap_err().to_string();
    assert!(
        e.starts_with("SLEPc is not available: cannot run /nonexistent/python3"),
        "{e}"
    );
    assert!(e.contains("python3-slepc4py-real"), "{e}");
    if !available() {
        return;
    }
    let sys = femu_testkit::bar([4, 1, 1], true)
        .assemble(MassKind::Consistent)
        .unwrap();
    // the error of a solve with these SLEPc options
    let error_with = |opts: SlepcOptions| {
        let params = EigenOptions {
            engine: Engine::Slepc(opts),
            ..Default::default()
        };
        eigs(&sys.k, &sys.m, Which::Lowest(2), &params)
            .unwrap_err()
            .to_string()
    };
    // MPI failing: a launcher that is not mpirun
    let e = error_with(SlepcOptions {
        mpirun: "false".into(),
        ..Default::default()
    });
    assert!(
        e.contains("SLEPc is not available: cannot run false"),
        "{e}"
    );
    // MPI failing: a hostfile that does not exist; the launcher's own message is passed on
    let e = error_with(SlepcOptions {
        hostfile: Some("/nonexistent/hosts".into()),
        ..Default::default()
    });
    assert!(
        e.starts_with("SLEPc failed: mpirun -n 1 exited with"),
        "{e}"
    );
    // SLEPc not converging: one restart allowed
    let e = error_with(SlepcOptions {
        petsc_options: vec![
            "-eps_max_it".into(),
            "1".into(),
            "-eps_ncv".into(),
            "8".into(),
        ],
        ..Default::default()
    });
    assert!(
        e.contains("SLEPc converged") && e.contains("of 6 eigenpairs in 1 iterations"),
        "{e}"
    );
}
