//! The model's FRFs against the direct solution `C (K (1 + i eta) + i w (alpha M + beta K) - w^2
//! M)^-1 B^T` of a clamped bar, formed densely in complex arithmetic here; FRAC, CSAC and CSF
//! against hand computations.

use super::common::*;
use faer::linalg::solvers::Solve;
use faer::{Mat, c64};
use femu_correlate::frf::{
    Damping, DirectSystem, FrfOptions, ResponseKind, csac, csf, direct_frf, frac, modal_frf,
    residual_flexibility,
};
use femu_correlate::{Sensor, SensorLayout};
use femu_fem::prelude::*;

/// `C A(w)^-1 B^T` with `A = K (1 + i eta) + i w (alpha M + beta K) - w^2 M`, dense.
fn direct(
    sys: &SystemMatrices,
    outputs: &SensorLayout,
    inputs: &SensorLayout,
    w: f64,
    coefficients: (f64, f64, f64),
) -> Mat<c64> {
    direct_with(sys, None, outputs, inputs, w, coefficients)
}

/// [`direct`] with dampers `(C_d, K_4)` added: `A + i w C_d + i K_4`, dense.
fn direct_with(
    sys: &SystemMatrices,
    dampers: Option<(&Mat<f64>, &Mat<f64>)>,
    outputs: &SensorLayout,
    inputs: &SensorLayout,
    w: f64,
    (eta, alpha, beta): (f64, f64, f64),
) -> Mat<c64> {
    let (k, m) = (dense(&sys.k), dense(&sys.m));
    let n = k.nrows();
    let zero = Mat::<f64>::zeros(n, n);
    let (cd, k4) = dampers.unwrap_or((&zero, &zero));
    let a = Mat::<c64>::from_fn(n, n, |i, j| {
        c64::new(
            k[(i, j)] - w * w * m[(i, j)],
            eta * k[(i, j)] + w * (alpha * m[(i, j)] + beta * k[(i, j)] + cd[(i, j)]) + k4[(i, j)],
        )
    });
    let b = Mat::<c64>::from_fn(n, inputs.len(), |f, j| {
        let v: f64 = inputs
            .row(j)
            .iter()
            .filter(|(g, _)| *g == f)
            .map(|(_, w)| w)
            .sum();
        c64::new(v, 0.0)
    });
    let x = a.as_ref().partial_piv_lu().solve(&b);
    Mat::<c64>::from_fn(outputs.len(), inputs.len(), |i, j| {
        outputs
            .row(i)
            .iter()
            .map(|(f, w)| x[(*f, j)] * c64::new(*w, 0.0))
            .sum()
    })
}

fn layouts(model: &Model, sys: &SystemMatrices) -> (SensorLayout, SensorLayout) {
    let mesh = model.mesh();
    let tip = mesh.node_set("xmax").unwrap()[0];
    let mid = mesh
        .coords()
        .iter()
        .position(|x| (x[0] - 0.1).abs() < 1e-12)
        .unwrap();
    let outputs = SensorLayout::new(
        mesh,
        &sys.dofs,
        vec![
            Sensor::axis(mesh.node_id(tip), 2),
            Sensor::new(mesh.node_id(mid), [0.0, 0.6, 0.8]),
            Sensor::axis(mesh.node_id(mid), 0),
        ],
    )
    .unwrap();
    let inputs = SensorLayout::new(
        mesh,
        &sys.dofs,
        vec![
            Sensor::axis(mesh.node_id(tip), 2),
            Sensor::axis(mesh.node_id(tip), 1),
        ],
    )
    .unwrap();
    (outputs, inputs)
}

fn max_rel(a: &Mat<c64>, b: &Mat<c64>) -> f64 {
    let scale = (0..b.nrows())
        .flat_map(|i| (0..b.ncols()).map(move |j| (i, j)))
        .map(|(i, j)| b[(i, j)].norm())
        .fold(0.0, f64::max);
    (0..b.nrows())
        .flat_map(|i| (0..b.ncols()).map(move |j| (i, j)))
        .map(|(i, j)| (a[(i, j)] - b[(i, j)]).norm() / scale)
        .fold(0.0, f64::max)
}

/// With every mode kept, modal superposition is the direct solution for Rayleigh damping and for a
/// loss factor (1e-9 relative over lines below, between and above the modes); receptance, mobility
/// and accelerance differ by `i w` and `-w^2` exactly.
#[test]
fn every_mode_kept_is_the_direct_solution() {
    let model = bar([4, 1, 1], true);
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let (outputs, inputs) = layouts(&model, &sys);
    let e = full_eigen(&sys);
    let f1 = e.values[0].sqrt() / (2.0 * std::f64::consts::PI);
    let lines = [0.3 * f1, f1, 2.7 * f1, 40.0 * f1];
    for (damping, coefficients) in [
        (
            Damping::Rayleigh {
                alpha: 3.0,
                beta: 2e-6,
            },
            (0.0, 3.0, 2e-6),
        ),
        (Damping::LossFactor(0.02), (0.02, 0.0, 0.0)),
    ] {
        let options = FrfOptions {
            damping: damping.clone(),
            kind: ResponseKind::Receptance,
        };
        let frf = modal_frf(
            &e.values,
            e.vectors.as_ref(),
            None,
            &outputs,
            &inputs,
            &lines,
            &options,
        )
        .unwrap();
        for (l, f) in lines.iter().enumerate() {
            let w = 2.0 * std::f64::consts::PI * f;
            let d = direct(&sys, &outputs, &inputs, w, coefficients);
            let err = max_rel(&frf.h[l], &d);
            assert!(err < 1e-9, "{damping:?} line {l}: {err:e}");
        }
        let mobility = |w: f64| c64::new(0.0, w);
        let accelerance = |w: f64| c64::new(-w * w, 0.0);
        let factors: [(ResponseKind, &dyn Fn(f64) -> c64); 2] = [
            (ResponseKind::Mobility, &mobility),
            (ResponseKind::Accelerance, &accelerance),
        ];
        for (kind, factor) in factors {
            let other = modal_frf(
                &e.values,
                e.vectors.as_ref(),
                None,
                &outputs,
                &inputs,
                &lines,
                &FrfOptions {
                    damping: damping.clone(),
                    kind,
                },
            )
            .unwrap();
            for (l, f) in lines.iter().enumerate() {
                let s = factor(2.0 * std::f64::consts::PI * f);
                let want =
                    Mat::<c64>::from_fn(outputs.len(), inputs.len(), |i, j| frf.h[l][(i, j)] * s);
                assert!(max_rel(&other.h[l], &want) < 1e-14);
            }
        }
    }
}

/// Six of the bar's modes kept: the truncated sum misses the response of the modes left out;
/// their residual flexibility (a static solve) puts back its static part. Against the sum over
/// every mode, the error falls by more than 1000 times at zero and at half the first frequency,
/// and by more than 10 times between the third and fourth modes, where the left-out modes' own
/// dynamics (not static any more) is what remains; at zero frequency the corrected receptance is
/// the static flexibility `C K^-1 B^T` exactly (1e-10).
#[test]
fn residual_flexibility_corrects_truncation() {
    let model = bar([6, 1, 1], true);
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let (outputs, inputs) = layouts(&model, &sys);
    let e = full_eigen(&sys);
    let kept = 6;
    let values = &e.values[..kept];
    let shapes = e.vectors.subcols(0, kept);
    let r = residual_flexibility(&sys.k, values, shapes, &outputs, &inputs).unwrap();
    let f = |l: f64| l.sqrt() / (2.0 * std::f64::consts::PI);
    let lines = [0.0, 0.5 * f(values[0]), 0.5 * (f(values[2]) + f(values[3]))];
    let options = FrfOptions {
        damping: Damping::Ratio(0.01),
        kind: ResponseKind::Receptance,
    };
    let truncated = modal_frf(values, shapes, None, &outputs, &inputs, &lines, &options).unwrap();
    let corrected = modal_frf(
        values,
        shapes,
        Some(r.as_ref()),
        &outputs,
        &inputs,
        &lines,
        &options,
    )
    .unwrap();
    let every = modal_frf(
        &e.values,
        e.vectors.as_ref(),
        None,
        &outputs,
        &inputs,
        &lines,
        &FrfOptions {
            damping: Damping::Ratios(vec![0.01; e.values.len()]),
            kind: ResponseKind::Receptance,
        },
    )
    .unwrap();
    for l in 0..lines.len() {
        let (a, b) = (
            max_rel(&truncated.h[l], &every.h[l]),
            max_rel(&corrected.h[l], &every.h[l]),
        );
        // measured: 1.5e-2 -> 1.3e-11, 1.1e-2 -> 8.0e-6, 8.4e-2 -> 6.5e-3
        let gain = if l < 2 { 1000.0 } else { 10.0 };
        assert!(b < a / gain, "line {l}: truncated {a:e}, corrected {b:e}");
    }
    // zero frequency: C K^-1 B^T by a dense solve
    let static_flex = direct(&sys, &outputs, &inputs, 0.0, (0.0, 0.0, 0.0));
    assert!(max_rel(&corrected.h[0], &static_flex) < 1e-10);
    // a free-free model has no static flexibility: refused, not approximated
    let free = bar([4, 1, 1], false);
    let fsys = free.assemble(MassKind::Consistent).unwrap();
    let fe = full_eigen(&fsys);
    let (o, i) = layouts(&free, &fsys);
    let err = residual_flexibility(&fsys.k, &fe.values[..8], fe.vectors.subcols(0, 8), &o, &i)
        .unwrap_err()
        .to_string();
    assert!(err.contains("rigid-body"), "{err}");
}

/// The residual flexibility solved with the factor the eigensolver kept (no factorization of
/// `K`), against the sum over the modes left out of a dense eigendecomposition,
/// `sum_{r > kept} (C phi_r)(B phi_r)^T / lambda_r`: on a clamped bar from a lowest-mode solve
/// (tiny negative shift) and from a band solve (the factor of the band's lower end), and on the
/// free bar, whose six rigid-body modes are kept and whose loads are then balanced by their
/// inertia (the elastic modes left out only). Without the rigid-body modes among the kept ones the
/// refinement cannot converge, and says so.
#[test]
fn residual_flexibility_from_the_eigensolver_factor() {
    use femu_correlate::frf::residual_flexibility_factored;
    use femu_sparse::eigen::{EigenOptions, Which};
    let keep = EigenOptions {
        keep_factor: true,
        ..Default::default()
    };
    let reference = |e: &femu_sparse::dense::GeneralizedEigen,
                     kept: usize,
                     o: &SensorLayout,
                     i: &SensorLayout| {
        let rest = e.vectors.subcols(kept, e.values.len() - kept);
        let (co, bi) = (o.measure_all(rest).unwrap(), i.measure_all(rest).unwrap());
        Mat::<c64>::from_fn(o.len(), i.len(), |a, b| {
            let v: f64 = (0..rest.ncols())
                .map(|r| co[(a, r)] * bi[(b, r)] / e.values[kept + r])
                .sum();
            c64::new(v, 0.0)
        })
    };
    let complex =
        |r: &Mat<f64>| Mat::<c64>::from_fn(r.nrows(), r.ncols(), |a, b| c64::new(r[(a, b)], 0.0));
    for (clamped, divisions) in [(true, [40, 2, 2]), (false, [8, 1, 1])] {
        let model = bar(divisions, clamped);
        let sys = model.assemble(MassKind::Consistent).unwrap();
        let (outputs, inputs) = layouts(&model, &sys);
        let e = full_eigen(&sys);
        let lowest = sys.modes(Which::Lowest(9), &keep).unwrap();
        let hi = 0.5 * (e.values[11] + e.values[12]);
        let band = sys
            .modes(Which::Band { lo: -1e-6 * hi, hi }, &keep)
            .unwrap();
        for (what, modes) in [("lowest", &lowest), ("band", &band)] {
            let kept = modes.values.len();
            assert!(
                e.values[kept] > 1.001 * e.values[kept - 1].max(1.0),
                "{what}: the cut falls between distinct eigenvalues"
            );
            let factor = modes.factor.as_ref().expect("the factor is kept");
            assert!(factor.sigma < 0.0, "{what}: shift {}", factor.sigma);
            let r = residual_flexibility_factored(
                &sys.k,
                &sys.m,
                factor,
                &modes.values,
                modes.vectors.as_ref(),
                &outputs,
                &inputs,
            )
            .unwrap();
            let err = max_rel(&complex(&r), &reference(&e, kept, &outputs, &inputs));
            // measured: 1.5e-13 and 1.3e-13 clamped (1,080 DOF; the subtraction from a
            // factorization of K, `residual_flexibility`, 3.8e-11 and 1.9e-10 with the same
            // modes: it cancels the kept modes' whole static response against their sum), 3.0e-14
            // and 2.1e-14 free
            assert!(err < 1e-11, "clamped {clamped}, {what}: {err:e}");
        }
        if !clamped {
            // the elastic modes alone: the rigid-body loads are not balanced
            let elastic = 6..lowest.values.len();
            let err = residual_flexibility_factored(
                &sys.k,
                &sys.m,
                lowest.factor.as_ref().unwrap(),
                &lowest.values[elastic.clone()],
                lowest.vectors.subcols(6, elastic.len()),
                &outputs,
                &inputs,
            )
            .unwrap_err()
            .to_string();
            assert!(err.contains("did not converge"), "{err}");
        }
    }
    // no factor unless asked for
    let model = bar([4, 1, 1], true);
    let sys = model.assemble(MassKind::Consistent).unwrap();
    assert!(
        sys.modes(Which::Lowest(3), &EigenOptions::default())
            .unwrap()
            .factor
            .is_none()
    );
}

/// FRAC, CSAC and CSF by hand: a curve against a complex multiple of itself (FRAC = CSAC = 1,
/// CSF = 2 |c| / (1 + |c|^2)), against an orthogonal one (0), and a worked pair.
#[test]
fn assurance_criteria_by_hand() {
    let t = [c64::new(1.0, 0.0), c64::new(0.0, 2.0), c64::new(-1.0, 1.0)];
    let c = c64::new(0.6, -0.8) * 2.0; // |c| = 2
    let m: Vec<c64> = t.iter().map(|x| c * x).collect();
    assert!((frac(&t, &m).unwrap() - 1.0).abs() < 1e-15);
    assert!((csac(&t, &m).unwrap() - 1.0).abs() < 1e-15);
    assert!((csf(&t, &m).unwrap() - 2.0 * 2.0 / (1.0 + 4.0)).abs() < 1e-15);
    assert!((csf(&t, &t).unwrap() - 1.0).abs() < 1e-15);
    // o = (2i, 1, 0): t^H o = 1 (2i) + (-2i) 1 + 0 = 0
    let o = [c64::new(0.0, 2.0), c64::new(1.0, 0.0), c64::new(0.0, 0.0)];
    assert!(frac(&t, &o).unwrap().abs() < 1e-15);
    // t = (1, i), m = (1, 1): t^H m = 1 - i, |.|^2 = 2; t^H t = 2, m^H m = 2: CSAC = 1/2,
    // CSF = 2 sqrt(2) / 4
    let (t2, m2) = (
        [c64::new(1.0, 0.0), c64::new(0.0, 1.0)],
        [c64::new(1.0, 0.0), c64::new(1.0, 0.0)],
    );
    assert!((csac(&t2, &m2).unwrap() - 0.5).abs() < 1e-15);
    assert!((csf(&t2, &m2).unwrap() - 2f64.sqrt() / 2.0).abs() < 1e-15);
    assert!(frac(&t2, &[c64::new(0.0, 0.0); 2]).is_err());
    assert!(frac(&t2, &t).is_err());
}

/// A dashpot `c (e_a - e_b)(e_a - e_b)^T` between free DOFs `a` and `b`, dense.
fn dashpot(n: usize, a: usize, b: usize, c: f64) -> Mat<f64> {
    let mut d = Mat::<f64>::zeros(n, n);
    d[(a, a)] += c;
    d[(b, b)] += c;
    d[(a, b)] -= c;
    d[(b, a)] -= c;
    d
}

/// The clamped bar with damping the modes do not diagonalise: a dashpot `C_d` between the tip and
/// the middle and structural damping `K_4` of a spring to ground at the middle (dense), lines below,
/// on, between and far above the modes, and every mode.
struct DampedBar {
    sys: SystemMatrices,
    outputs: SensorLayout,
    inputs: SensorLayout,
    cd: Mat<f64>,
    k4: Mat<f64>,
    lines: [f64; 5],
    eigen: femu_sparse::dense::GeneralizedEigen,
}

fn damped_bar() -> DampedBar {
    let model = bar([4, 1, 1], true);
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let (outputs, inputs) = layouts(&model, &sys);
    let n = sys.k.rows();
    let (a, b) = (outputs.row(0)[0].0, outputs.row(2)[0].0);
    let kmax = dense(&sys.k)[(a, a)];
    let cd = dashpot(n, a, b, 2e-4 * kmax);
    let mut k4 = Mat::<f64>::zeros(n, n);
    k4[(b, b)] = 0.05 * kmax;
    let eigen = full_eigen(&sys);
    let f1 = eigen.values[0].sqrt() / (2.0 * std::f64::consts::PI);
    DampedBar {
        sys,
        outputs,
        inputs,
        cd,
        k4,
        lines: [0.0, 0.3 * f1, f1, 2.7 * f1, 40.0 * f1],
        eigen,
    }
}

/// The request's damping with the `(eta, alpha, beta)` of [`direct_with`]: Rayleigh damping, a
/// loss factor, none.
fn damping_cases() -> [(Damping, (f64, f64, f64)); 3] {
    [
        (
            Damping::Rayleigh {
                alpha: 3.0,
                beta: 2e-6,
            },
            (0.0, 3.0, 2e-6),
        ),
        (Damping::LossFactor(0.02), (0.02, 0.0, 0.0)),
        (Damping::Ratio(0.0), (0.0, 0.0, 0.0)),
    ]
}

/// The direct route (a sparse complex `LU` per line) against the dense complex solve of the same
/// dynamic stiffness, with damping the modes do not diagonalise: a dashpot between the tip and
/// the middle of the bar and structural damping of a spring to ground, on top of Rayleigh
/// damping or a loss factor, at lines below, on, between and far above the modes (1e-10
/// relative; each line's backward error below 1e-14).
#[test]
fn the_direct_route_is_the_dense_solve_with_dampers() {
    let DampedBar {
        sys,
        outputs,
        inputs,
        cd,
        k4,
        lines,
        ..
    } = damped_bar();
    let (cd_s, k4_s) = (sparse(&cd), sparse(&k4));
    for (damping, coefficients) in damping_cases() {
        let options = FrfOptions {
            damping: damping.clone(),
            kind: ResponseKind::Receptance,
        };
        let system = DirectSystem {
            k: &sys.k,
            m: &sys.m,
            viscous: Some(&cd_s),
            structural: Some(&k4_s),
        };
        let got = direct_frf(&system, &outputs, &inputs, &lines, &options).unwrap();
        for (l, f) in lines.iter().enumerate() {
            let w = 2.0 * std::f64::consts::PI * f;
            let want = direct_with(&sys, Some((&cd, &k4)), &outputs, &inputs, w, coefficients);
            let err = max_rel(&got.frf.h[l], &want);
            assert!(err < 1e-10, "{damping:?} line {l}: {err:e}");
            assert!(
                got.backward_errors[l] < 1e-14,
                "{:e}",
                got.backward_errors[l]
            );
        }
    }
}

/// Modal superposition with the model's dampers projected on every mode and the modal equations
/// solved together (`modal_frf_coupled`) is the dense complex solve of the whole damped system:
/// the dashpot and the grounded spring's structural damping of the test above, with Rayleigh
/// damping, a loss factor or none of the request's, at lines below, on, between and far above the
/// modes (1e-9 relative).
#[test]
fn every_mode_with_projected_dampers_is_the_dense_solve() {
    use femu_correlate::frf::{ModalDampers, modal_frf_coupled};
    let DampedBar {
        sys,
        outputs,
        inputs,
        cd,
        k4,
        lines,
        eigen: e,
    } = damped_bar();
    let (cd_s, k4_s) = (sparse(&cd), sparse(&k4));
    let projected = ModalDampers::project(Some(&k4_s), Some(&cd_s), e.vectors.as_ref()).unwrap();
    for (damping, coefficients) in damping_cases() {
        let options = FrfOptions {
            damping: damping.clone(),
            kind: ResponseKind::Receptance,
        };
        let got = modal_frf_coupled(
            &e.values,
            e.vectors.as_ref(),
            None,
            &outputs,
            &inputs,
            &lines,
            &options,
            Some(&projected),
        )
        .unwrap();
        for (l, f) in lines.iter().enumerate() {
            let w = 2.0 * std::f64::consts::PI * f;
            let want = direct_with(&sys, Some((&cd, &k4)), &outputs, &inputs, w, coefficients);
            let err = max_rel(&got.h[l], &want);
            assert!(err < 1e-9, "{damping:?} line {l}: {err:e}");
        }
    }
    // projections of another size are refused
    let wrong = ModalDampers {
        structural: Some(Mat::zeros(2, 2)),
        viscous: None,
    };
    assert!(
        modal_frf_coupled(
            &e.values,
            e.vectors.as_ref(),
            None,
            &outputs,
            &inputs,
            &lines,
            &FrfOptions {
                damping: Damping::Ratio(0.0),
                kind: ResponseKind::Receptance,
            },
            Some(&wrong),
        )
        .is_err()
    );
}

/// Without the model's dampers the direct route is modal superposition over every mode (the
/// identity of docs/MATH.md, "Frequency responses"), to 1e-9; accelerance is `-w^2` times the
/// receptance.
#[test]
fn the_direct_route_is_every_mode_superposed() {
    let model = bar([4, 1, 1], true);
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let (outputs, inputs) = layouts(&model, &sys);
    let e = full_eigen(&sys);
    let f1 = e.values[0].sqrt() / (2.0 * std::f64::consts::PI);
    let lines = [0.5 * f1, 1.01 * f1, 5.0 * f1];
    let system = DirectSystem {
        k: &sys.k,
        m: &sys.m,
        viscous: None,
        structural: None,
    };
    for kind in [ResponseKind::Receptance, ResponseKind::Accelerance] {
        let options = FrfOptions {
            damping: Damping::LossFactor(0.03),
            kind,
        };
        let d = direct_frf(&system, &outputs, &inputs, &lines, &options).unwrap();
        let m = modal_frf(
            &e.values,
            e.vectors.as_ref(),
            None,
            &outputs,
            &inputs,
            &lines,
            &options,
        )
        .unwrap();
        for l in 0..lines.len() {
            let err = max_rel(&d.frf.h[l], &m.h[l]);
            assert!(err < 1e-9, "{kind:?} line {l}: {err:e}");
        }
    }
}

/// The residual flexibility's gain measured against the direct route on a 12 x 2 x 2 clamped
/// bar with 10 modes kept and a loss factor of 0.02 (the residual softened by `1 + i eta` as the
/// modes are): at half the first frequency the truncation error falls from 5.3e-3 to 3.1e-7
/// (17,000 times), between the fifth and sixth modes from 7.1e-1 to 2.4e-2 (30 times), where the
/// left-out modes' dynamics is what is left. Without the softening the first gain was 50 (the
/// loss factor's 2 % of the static part).
#[test]
fn residual_flexibility_against_the_direct_route() {
    let model = bar([12, 2, 2], true);
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let (outputs, inputs) = layouts(&model, &sys);
    let e = full_eigen(&sys);
    let kept = 10;
    let (values, shapes) = (&e.values[..kept], e.vectors.subcols(0, kept));
    let r = residual_flexibility(&sys.k, values, shapes, &outputs, &inputs).unwrap();
    let f = |l: f64| l.sqrt() / (2.0 * std::f64::consts::PI);
    let lines = [0.5 * f(values[0]), 0.5 * (f(values[4]) + f(values[5]))];
    let options = FrfOptions {
        damping: Damping::LossFactor(0.02),
        kind: ResponseKind::Receptance,
    };
    let system = DirectSystem {
        k: &sys.k,
        m: &sys.m,
        viscous: None,
        structural: None,
    };
    let exact = direct_frf(&system, &outputs, &inputs, &lines, &options).unwrap();
    let truncated = modal_frf(values, shapes, None, &outputs, &inputs, &lines, &options).unwrap();
    let corrected = modal_frf(
        values,
        shapes,
        Some(r.as_ref()),
        &outputs,
        &inputs,
        &lines,
        &options,
    )
    .unwrap();
    for (l, gain) in [(0, 1e4), (1, 20.0)] {
        let (a, b) = (
            max_rel(&truncated.h[l], &exact.frf.h[l]),
            max_rel(&corrected.h[l], &exact.frf.h[l]),
        );
        assert!(b < a / gain, "line {l}: truncated {a:e}, corrected {b:e}");
    }
}

/// Modal ratios have no damping matrix and are refused by the direct route; a line on an
/// undamped eigenvalue (`K = M = I` at `w = 1`) is a singular dynamic stiffness, named by its line;
/// negative damping and lines are refused.
#[test]
fn the_direct_route_refuses_what_it_cannot_solve() {
    let model = bar([2, 1, 1], true);
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let (outputs, inputs) = layouts(&model, &sys);
    let system = DirectSystem {
        k: &sys.k,
        m: &sys.m,
        viscous: None,
        structural: None,
    };
    let opts = |damping| FrfOptions {
        damping,
        kind: ResponseKind::Receptance,
    };
    let err = direct_frf(
        &system,
        &outputs,
        &inputs,
        &[1.0],
        &opts(Damping::Ratio(0.01)),
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("no damping matrix"), "{err}");
    let err = direct_frf(
        &system,
        &outputs,
        &inputs,
        &[1.0],
        &opts(Damping::LossFactor(-0.1)),
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("-0.1"), "{err}");
    let err = direct_frf(
        &system,
        &outputs,
        &inputs,
        &[-1.0],
        &opts(Damping::LossFactor(0.1)),
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("frequency line"), "{err}");
    let n = sys.k.rows();
    let eye = sparse(&Mat::<f64>::identity(n, n));
    let unit = DirectSystem {
        k: &eye,
        m: &eye,
        viscous: None,
        structural: None,
    };
    let err = direct_frf(
        &unit,
        &outputs,
        &inputs,
        &[0.5, 1.0 / (2.0 * std::f64::consts::PI)],
        &opts(Damping::Ratio(0.0)),
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("line 2") && err.contains("singular"), "{err}");
}

/// A 10 kg rigid mass on a grounded bushing whose axes are turned 30 degrees about z, with
/// viscous damping `B` and structural damping `GE` (Nastran's CBUSH with PBUSH `K`, `B`, `GE`):
/// along the bushing's first axis the receptance is the single-DOF oscillator's
/// `1 / (k_1 (1 + i GE) - w^2 m + i w b_1)`, by hand, below, at and above its resonance (1e-12).
/// The dampers are the model's own ([`Assembler::dampers`]); a model without any has none.
#[test]
fn a_damped_bushing_is_a_single_dof_oscillator() {
    use femu_fem::structural::{Bushing, StructuralElement, StructuralKind};
    let (c, s) = (
        (std::f64::consts::PI / 6.0).cos(),
        (std::f64::consts::PI / 6.0).sin(),
    );
    let axes = [[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]];
    let k = [1.0e4, 2.0e4, 3.0e4, 500.0, 700.0, 900.0];
    let b = [15.0, 9.0, 4.0, 0.5, 0.2, 0.1];
    let ge = 0.04;
    let mut mesh = Mesh::new();
    mesh.add_node(7, [0.2, 0.1, 0.0]).unwrap();
    let mut model = Model::new(mesh).unwrap();
    model
        .add_structural(StructuralElement {
            id: 5,
            nodes: vec![0],
            kind: StructuralKind::Bushing(Bushing {
                k,
                b,
                ge,
                axes,
                point: None,
            }),
        })
        .unwrap();
    let jd = [0.5, 0.7, 0.9];
    let mut jb = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            jb[i][j] = (0..3).map(|a| axes[a][i] * jd[a] * axes[a][j]).sum();
        }
    }
    let mass = 10.0;
    model.add_rigid_mass(7, mass, [0.0; 3], jb).unwrap();
    let asm = Assembler::new(&model).unwrap();
    let sys = asm.assemble(&model, MassKind::Consistent).unwrap();
    let dampers = asm
        .dampers(&model, femu_fem::assembly::MassKind::Consistent)
        .unwrap();
    let along = SensorLayout::new(model.mesh(), &sys.dofs, vec![Sensor::new(7, axes[0])]).unwrap();
    let system = DirectSystem {
        k: &sys.k,
        m: &sys.m,
        viscous: dampers.viscous.as_ref(),
        structural: dampers.structural.as_ref(),
    };
    let f0 = (k[0] / mass).sqrt() / (2.0 * std::f64::consts::PI);
    let lines = [0.2 * f0, f0, 3.0 * f0];
    let got = direct_frf(
        &system,
        &along,
        &along,
        &lines,
        &FrfOptions {
            damping: Damping::Ratio(0.0),
            kind: ResponseKind::Receptance,
        },
    )
    .unwrap();
    for (l, f) in lines.iter().enumerate() {
        let w = 2.0 * std::f64::consts::PI * f;
        let want = c64::new(1.0, 0.0) / c64::new(k[0] - w * w * mass, k[0] * ge + w * b[0]);
        let err = (got.frf.h[l][(0, 0)] - want).norm() / want.norm();
        assert!(
            err < 1e-12,
            "line {l}: {:?} against {want:?}",
            got.frf.h[l][(0, 0)]
        );
    }
    let plain = bar([2, 1, 1], true);
    let pasm = Assembler::new(&plain).unwrap();
    let none = pasm
        .dampers(&plain, femu_fem::assembly::MassKind::Consistent)
        .unwrap();
    assert!(none.viscous.is_none() && none.structural.is_none());
}

/// The forced residue (4) of a response measured on a few DOFs of a clamped bar, against the
/// dense Schur complement `R_a = (A_aa - A_ao A_oo^-1 A_oa) u_a - (f_a - A_ao A_oo^-1 f_o)`
/// formed here (1e-10 relative, loss factor and Rayleigh, a force on a measured and on an omitted
/// DOF); the bar's own response (the dense solve of `A u = f`) leaves no residue (1e-10 of
/// `||f||`); the projection of a change `dA u` is the derivative of the re-expanded residue
/// (central difference of the dense residue, 1e-6).
#[test]
fn forced_residue_against_the_dense_schur_complement() {
    use femu_correlate::expansion::{DynamicStiffness, ForcedExpander};
    let model = bar([4, 1, 1], true);
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let (k, m) = (dense(&sys.k), dense(&sys.m));
    let n = k.nrows();
    let measured: Vec<usize> = (0..n).filter(|d| d % 5 == 2 || d % 7 == 0).collect();
    let omitted: Vec<usize> = (0..n).filter(|d| !measured.contains(d)).collect();
    let forced = ForcedExpander::new(&sys.k, &sys.m, &measured).unwrap();
    let e = full_eigen(&sys);
    let w1 = e.values[0].sqrt();
    // a stiffness change of the bar's first elements, for the derivative
    let dk = {
        let mut d = Mat::<f64>::zeros(n, n);
        for i in 0..n {
            for j in 0..n {
                if i % 3 == 0 && j % 3 == 0 {
                    d[(i, j)] = 0.1 * k[(i, j)];
                }
            }
        }
        d
    };
    for a in [
        DynamicStiffness::loss_factor(0.7 * w1, 0.03),
        DynamicStiffness::rayleigh(2.3 * w1, 4.0, 1e-6),
        // undamped, below the first mode (at a mode, the bar's own response is not defined)
        DynamicStiffness::loss_factor(0.45 * w1, 0.0),
    ] {
        let dense_a = |extra: f64| {
            Mat::<c64>::from_fn(n, n, |i, j| {
                a.k * c64::new(k[(i, j)] + extra * dk[(i, j)], 0.0) + a.m * c64::new(m[(i, j)], 0.0)
            })
        };
        let amat = dense_a(0.0);
        // two load cases: a force on a measured DOF and one on an omitted DOF
        let f = Mat::<c64>::from_fn(n, 2, |i, j| match (i, j) {
            (i, 0) if i == measured[3] => c64::new(1.0, 0.0),
            (i, 1) if i == omitted[5] => c64::new(0.0, 2.0),
            _ => c64::new(0.0, 0.0),
        });
        // a response that is not the bar's: smooth, complex
        let ua = Mat::<c64>::from_fn(measured.len(), 2, |i, j| {
            c64::new(
                1e-6 * (i as f64 + 1.0).sin(),
                1e-7 * (j as f64 + i as f64).cos(),
            )
        });
        let sub = |a: &Mat<c64>, r: &[usize], c: &[usize]| {
            Mat::<c64>::from_fn(r.len(), c.len(), |i, j| a[(r[i], c[j])])
        };
        let residue = |amat: &Mat<c64>, ua: &Mat<c64>| {
            let (aaa, aao, aoa, aoo) = (
                sub(amat, &measured, &measured),
                sub(amat, &measured, &omitted),
                sub(amat, &omitted, &measured),
                sub(amat, &omitted, &omitted),
            );
            let fa = sub(&f, &measured, &[0, 1]);
            let fo = sub(&f, &omitted, &[0, 1]);
            let lu = aoo.as_ref().partial_piv_lu();
            let rhs = &fo - &aoa * ua;
            let uo = lu.solve(&rhs);
            &aaa * ua + &aao * &uo - &fa
        };
        let reference = residue(&amat, &ua);
        let mut line = forced.line(a).unwrap();
        let got = line.expand(ua.as_ref(), f.as_ref()).unwrap();
        assert!(max_rel(&got.residual, &reference) < 1e-10, "{a:?}");
        // measured values kept
        for (i, &d) in measured.iter().enumerate() {
            assert_eq!(got.u[(d, 1)], ua[(i, 1)]);
        }
        // the bar's own response has no residue
        let own = amat.as_ref().partial_piv_lu().solve(&f);
        let own_a = sub(&own, &measured, &[0, 1]);
        let none = line.expand(own_a.as_ref(), f.as_ref()).unwrap();
        let worst = none
            .residual
            .col_iter()
            .map(|c| c.norm_l2())
            .fold(0.0, f64::max);
        assert!(worst < 1e-10 * f.norm_l2(), "{worst}");
        // the projection is the derivative of the residue of the re-expanded response
        let du = {
            let mut v = Mat::<c64>::zeros(n, 2);
            for j in 0..2 {
                for i in 0..n {
                    v[(i, j)] = (0..n)
                        .map(|l| a.k * c64::new(dk[(i, l)], 0.0) * got.u[(l, j)])
                        .sum();
                }
            }
            v
        };
        let projected = line.project(du.as_ref()).unwrap();
        let h = 1e-4;
        let fd = Mat::<c64>::from_fn(measured.len(), 2, |i, j| {
            (residue(&dense_a(h), &ua)[(i, j)] - residue(&dense_a(-h), &ua)[(i, j)])
                / c64::new(2.0 * h, 0.0)
        });
        assert!(
            max_rel(&projected, &fd) < 1e-6,
            "{}",
            max_rel(&projected, &fd)
        );
        assert!(line.backward_error() < 1e-13);
    }
}

/// The frequency-line loop keeps line order whatever the lines at once (1, a chunk of 3, every
/// thread), and the default count is held to one line when a factor would not fit in memory
/// (a factor of 2^58 complex values: 4 EiB each) and to the lines there are.
#[test]
fn lines_are_mapped_in_order_within_memory() {
    use femu_correlate::frf::{lines_at_once, map_lines};
    let squares: Vec<usize> = (0..10).map(|l| l * l).collect();
    for at_once in [1, 3, 64] {
        assert_eq!(map_lines(10, at_once, |l| l * l), squares, "{at_once}");
    }
    assert!(map_lines(0, 2, |l| l).is_empty());
    assert_eq!(lines_at_once(1 << 58, 8), 1);
    assert_eq!(lines_at_once(1, 1), 1);
    let threads = rayon::current_num_threads();
    assert_eq!(lines_at_once(1, 1000), threads);
}
