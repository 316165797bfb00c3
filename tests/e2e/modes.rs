//! FE models through the sparse eigensolver, against the dense reference.

use femu::prelude::*;
use femu::sparse::csc::to_dense;
use femu::sparse::dense::generalized_symmetric_eigen;
use femu::sparse::eigen::{EigenOptions, Which, eigs};

fn plate(quadratic: bool) -> Model {
    let spec = PlateSpec {
        lengths: [0.06, 0.04, 0.01],
        divisions: [6, 4, 2],
        tet_block: [2, 2],
        quadratic,
    };
    let mut model = Model::new(mixed_plate(&spec).unwrap()).unwrap();
    model.set_material(None, Material::steel()).unwrap();
    model
}

/// A free-free mixed plate: exactly six near-zero eigenvalues (found with the negative shift),
/// then elastic modes equal to the dense solution to 1e-10 relative, residuals below 1e-8, for
/// consistent and lumped mass, linear and quadratic elements; the Sturm check verified.
#[test]
fn free_free_fe_models_match_the_dense_reference() {
    for quadratic in [false, true] {
        for mass in [MassKind::Consistent, MassKind::Lumped] {
            let model = plate(quadratic);
            let sys = model.assemble(mass).unwrap();
            let dense =
                generalized_symmetric_eigen(to_dense(&sys.k).as_ref(), to_dense(&sys.m).as_ref())
                    .unwrap();
            let modes = eigs(&sys.k, &sys.m, Which::Lowest(16), &EigenOptions::default()).unwrap();
            assert!(modes.sturm.verified(), "{:?}", modes.sturm);
            assert!(modes.shift < 0.0);
            let first_elastic = dense.values[6];
            for j in 0..6 {
                assert!(
                    modes.values[j].abs() < 1e-8 * first_elastic,
                    "q={quadratic} {mass:?}: rigid {j} = {}",
                    modes.values[j]
                );
            }
            for j in 6..16 {
                let (l, d) = (modes.values[j], dense.values[j]);
                assert!(
                    (l / d - 1.0).abs() < 1e-10,
                    "q={quadratic} {mass:?} mode {j}: {l} vs {d}"
                );
                assert!(
                    modes.residuals[j] < 1e-8,
                    "q={quadratic} {mass:?} mode {j}: residual {}",
                    modes.residuals[j]
                );
            }
        }
    }
}

/// A clamped hex20 beam: the modes nearest a shift inside the spectrum and every mode in a band.
#[test]
fn clamped_beam_shift_and_band_match_the_dense_reference() {
    let mesh = box_mesh(&BoxSpec::new(
        [0.2, 0.02, 0.03],
        [8, 1, 2],
        BoxCells::Hex,
        true,
    ))
    .unwrap();
    let mut model = Model::new(mesh).unwrap();
    model.set_material(None, Material::steel()).unwrap();
    model.fix_set("xmin", &[0, 1, 2]).unwrap();
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let dense =
        generalized_symmetric_eigen(to_dense(&sys.k).as_ref(), to_dense(&sys.m).as_ref()).unwrap();
    let shift = 0.5 * (dense.values[9] + dense.values[10]) * 1.0003;
    let near = eigs(
        &sys.k,
        &sys.m,
        Which::Nearest { shift, count: 6 },
        &EigenOptions::default(),
    )
    .unwrap();
    let mut idx: Vec<usize> = (0..dense.values.len()).collect();
    idx.sort_by(|a, b| {
        (dense.values[*a] - shift)
            .abs()
            .total_cmp(&(dense.values[*b] - shift).abs())
    });
    let mut expect: Vec<f64> = idx[..6].iter().map(|i| dense.values[*i]).collect();
    expect.sort_by(f64::total_cmp);
    for (l, d) in near.values.iter().zip(&expect) {
        assert!((l / d - 1.0).abs() < 1e-10, "{l} vs {d}");
    }
    assert!(near.sturm.verified());
    let (lo, hi) = (dense.values[3] * 0.99, dense.values[12] * 1.01);
    let band = eigs(
        &sys.k,
        &sys.m,
        Which::Band { lo, hi },
        &EigenOptions::default(),
    )
    .unwrap();
    assert_eq!(band.values.len(), 10);
    for (l, d) in band.values.iter().zip(&dense.values[3..13]) {
        assert!((l / d - 1.0).abs() < 1e-10);
    }
}

/// Regression: asking a free-free model for fewer modes than its six rigid-body modes (1, 6 or 7)
/// once failed to converge: the probe that places the shift saw only rigid-body values and the
/// elastic modes stalled at a 1e-6 residual with the tiny shift. Each request now returns the
/// whole zero cluster (and the elastic modes asked for), Sturm-verified, equal to the dense
/// solution.
#[test]
fn free_free_requests_at_or_below_the_rigid_body_count() {
    for divisions in [[5, 2, 1], [6, 2, 1], [2, 1, 1]] {
        let mesh = box_mesh(&BoxSpec::new(
            [0.2, 0.04, 0.02],
            divisions,
            BoxCells::Hex,
            false,
        ))
        .unwrap();
        let mut model = Model::new(mesh).unwrap();
        model.set_material(None, Material::steel()).unwrap();
        let sys = model.assemble(MassKind::Consistent).unwrap();
        let dense =
            generalized_symmetric_eigen(to_dense(&sys.k).as_ref(), to_dense(&sys.m).as_ref())
                .unwrap();
        for k in [1, 6, 7] {
            let modes = eigs(&sys.k, &sys.m, Which::Lowest(k), &EigenOptions::default())
                .unwrap_or_else(|e| panic!("{divisions:?} k={k}: {e}"));
            assert!(modes.sturm.verified());
            assert_eq!(modes.values.len(), k.max(6), "{divisions:?} k={k}");
            if k == 7 {
                assert!((modes.values[6] / dense.values[6] - 1.0).abs() < 1e-10);
            }
            for j in 0..6 {
                assert!(modes.values[j].abs() < 1e-8 * dense.values[6]);
            }
        }
    }
}

/// A free-free model factors twice when the run can stay at the tiny shift below the rigid-body
/// modes: once it has locked them it starts afresh deflated against them (before, every free-free
/// solve refactored at half the first elastic eigenvalue: three factorizations). On a thin plate
/// (702 DOF, first elastic eigenvalue 3.7e4 times the tiny shift's distance from zero) the run
/// stays; on the coarse thick plate (1.9e7 times) its rigid-body modes cannot reach a backward
/// error of 1e-13 there, and the solve refactors as before. A hinted shift
/// (`EigenOptions::lowest_shift_hint`, an earlier solve's shift) skips the probe. Every
/// result has the dense solution's eigenvalues to 1e-10, also after the model changed (stiffness
/// scaled by 0.7, as between the solves of an updating run), and with a hint far closer to zero
/// than the first elastic eigenvalue (1e-9 of it); "to 1e-10" plus the dense solution's own
/// accuracy, `eps lambda_max / lambda_j` (6e-10 for the thin plate's first elastic mode).
#[test]
fn hinted_lowest_shift_saves_the_probe_and_stays_exact() {
    fn check(modes: &femu::sparse::eigen::Modes, dense: &[f64], scale: f64, what: &str) {
        assert!(modes.sturm.verified(), "{what}: {:?}", modes.sturm);
        for j in 0..6 {
            assert!(modes.values[j].abs() < 1e-8 * dense[6], "{what}: rigid {j}");
        }
        // The dense solver is backward stable: its eigenvalues are exact for a matrix within
        // eps ||K|| of K, so lambda_j is known to eps lambda_max / lambda_j relative, and the
        // round-off of K's own summation moves it by as much (the thin plate: 6e-10 for its first
        // elastic mode, measured differences 2.7e-10 and 1e-11 on two summation orders).
        let lmax = scale * dense[dense.len() - 1];
        for j in 6..14 {
            let (l, d) = (modes.values[j], scale * dense[j]);
            let tol = 1e-10 + f64::EPSILON * lmax / d;
            assert!((l / d - 1.0).abs() < tol, "{what} mode {j}: {l} vs {d}");
        }
    }
    let spec = PlateSpec {
        lengths: [0.12, 0.08, 0.002],
        divisions: [12, 8, 1],
        tet_block: [2, 2],
        quadratic: false,
    };
    let mut thin = Model::new(mixed_plate(&spec).unwrap()).unwrap();
    thin.set_material(None, Material::steel()).unwrap();
    let sys = thin.assemble(MassKind::Consistent).unwrap();
    let dense =
        generalized_symmetric_eigen(to_dense(&sys.k).as_ref(), to_dense(&sys.m).as_ref()).unwrap();
    let dense = &dense.values;
    let plain = eigs(&sys.k, &sys.m, Which::Lowest(14), &EigenOptions::default()).unwrap();
    check(&plain, dense, 1.0, "no hint");
    assert_eq!(plain.stats.factorizations, 2, "run, count");
    // the run stayed at the tiny shift, far below the first elastic eigenvalue
    assert!(plain.shift < 0.0 && plain.shift > -1e-3 * dense[6]);
    let hinted = EigenOptions {
        lowest_shift_hint: Some(plain.shift),
        ..EigenOptions::default()
    };
    let again = eigs(&sys.k, &sys.m, Which::Lowest(14), &hinted).unwrap();
    check(&again, dense, 1.0, "hinted");
    assert_eq!(again.stats.factorizations, 2, "run and count");
    assert_eq!(again.shift, plain.shift);
    // the model changed: K scaled by 0.7 scales every eigenvalue by 0.7
    let mut k = sys.k.clone();
    k.data_mut().iter_mut().for_each(|v| *v *= 0.7);
    let changed = eigs(&k, &sys.m, Which::Lowest(14), &hinted).unwrap();
    check(&changed, dense, 0.7, "changed model, old hint");
    assert_eq!(changed.stats.factorizations, 2);
    // a hint a billion times too close to zero
    let poor = EigenOptions {
        lowest_shift_hint: Some(-1e-9 * dense[6]),
        ..EigenOptions::default()
    };
    let recovered = eigs(&sys.k, &sys.m, Which::Lowest(14), &poor).unwrap();
    check(&recovered, dense, 1.0, "poor hint");
    assert!(recovered.stats.factorizations >= 2);
    // a hint that is not a negative number is no hint
    for bad in [f64::NAN, 0.0, 1e9] {
        let opts = EigenOptions {
            lowest_shift_hint: Some(bad),
            ..EigenOptions::default()
        };
        let modes = eigs(&sys.k, &sys.m, Which::Lowest(14), &opts).unwrap();
        check(&modes, dense, 1.0, &format!("hint {bad}"));
        assert_eq!(modes.stats.factorizations, 2, "hint {bad} ignored");
        assert_eq!(modes.shift, plain.shift, "hint {bad} ignored");
    }
    // the coarse thick plate: refactored at half the first elastic eigenvalue
    let sys = plate(false).assemble(MassKind::Consistent).unwrap();
    let dense =
        generalized_symmetric_eigen(to_dense(&sys.k).as_ref(), to_dense(&sys.m).as_ref()).unwrap();
    let coarse = eigs(&sys.k, &sys.m, Which::Lowest(14), &EigenOptions::default()).unwrap();
    check(&coarse, &dense.values, 1.0, "coarse plate");
    assert_eq!(coarse.stats.factorizations, 3, "probe, run, count");
    assert!(coarse.shift < -0.1 * dense.values[6]);
}
