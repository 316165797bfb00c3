//! The model's FRFs against the direct solution `C (K (1 + i eta) + i w (alpha M + beta K) - w^2
//! M)^-1 B^T` of a clamped bar, formed densely in complex arithmetic here; FRAC, CSAC and CSF
//! against hand computations.

use super::common::*;
use faer::linalg::solvers::Solve;
use faer::{Mat, c64};
use femu_correlate::frf::{
    Damping, FrfOptions, ResponseKind, csac, csf, frac, modal_frf, residual_flexibility,
};
use femu_correlate::{Sensor, SensorLayout};
use femu_fem::prelude::*;

/// `C A(w)^-1 B^T` with `A = K (1 + i eta) + i w (alpha M + beta K) - w^2 M`, dense.
fn direct(
    sys: &SystemMatrices,
    outputs: &SensorLayout,
    inputs: &SensorLayout,
    w: f64,
    (eta, alpha, beta): (f64, f64, f64),
) -> Mat<c64> {
    let (k, m) = (dense(&sys.k), dense(&sys.m));
    let n = k.nrows();
    let a = Mat::<c64>::from_fn(n, n, |i, j| {
        c64::new(
            k[(i, j)] - w * w * m[(i, j)],
            eta * k[(i, j)] + w * (alpha * m[(i, j)] + beta * k[(i, j)]),
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
