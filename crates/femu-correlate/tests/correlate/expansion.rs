//! Modal expansion against dense implementations of docs/MATH.md's formulas, exactness properties and
//! bad input.

use super::common::*;
use faer::Mat;
use faer::linalg::solvers::{Solve, SolveLstsq};
use femu_correlate::{Expander, Method, Sensor, SensorLayout, SensorSpace};
use femu_fem::prelude::*;
use femu_sparse::dense::generalized_symmetric_eigen;

struct Case {
    model: Model,
    sys: SystemMatrices,
    layout: SensorLayout,
    a: Vec<usize>,
    o: Vec<usize>,
}

/// A clamped bar measured triaxially on its top face at every other station.
fn case() -> Case {
    let model = bar([8, 2, 2], true);
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let mesh = model.mesh();
    let nodes: Vec<u64> = mesh
        .node_set("zmax")
        .unwrap()
        .iter()
        .filter(|&&n| {
            let x = mesh.coords()[n][0];
            x > 1e-9 && ((x / 0.025).round() as i64) % 2 == 0
        })
        .map(|&n| mesh.node_id(n))
        .collect();
    let layout = SensorLayout::triaxial(mesh, &sys.dofs, &nodes).unwrap();
    let a = layout.measured_dofs().unwrap();
    let o: Vec<usize> = (0..sys.k.rows()).filter(|d| !a.contains(d)).collect();
    Case {
        model,
        sys,
        layout,
        a,
        o,
    }
}

fn sub(a: &Mat<f64>, rows: &[usize], cols: &[usize]) -> Mat<f64> {
    Mat::from_fn(rows.len(), cols.len(), |i, j| a[(rows[i], cols[j])])
}

/// Dense `x_o = -Z_oo^-1 Z_oa x_a` (LU with partial pivoting).
fn dense_dynamic(c: &Case, lambda: f64, xa: &[f64]) -> Vec<f64> {
    let z = dense(&c.sys.k) - dense(&c.sys.m) * faer::Scale(lambda);
    let zoo = sub(&z, &c.o, &c.o);
    let zoa = sub(&z, &c.o, &c.a);
    let xa = Mat::from_fn(xa.len(), 1, |i, _| xa[i]);
    let rhs = -(&zoa * &xa);
    let xo = zoo.partial_piv_lu().solve(&rhs);
    let mut x = vec![0.0; c.sys.k.rows()];
    for (i, d) in c.a.iter().enumerate() {
        x[*d] = xa[(i, 0)];
    }
    for (i, d) in c.o.iter().enumerate() {
        x[*d] = xo[(i, 0)];
    }
    x
}

#[test]
fn static_dynamic_and_serep_equal_dense_formulas() {
    let c = case();
    let eig = full_eigen(&c.sys);
    let exp = Expander::new(&c.sys.k, &c.sys.m, &c.layout).unwrap();
    assert_eq!(exp.partition().measured(), &c.a[..]);
    // a "test" shape from the real structure (softened root), at the sensors
    let (lt, xt) = perturbed_mode(&c.model, 0.05, 0.8, 1);
    let xa: Vec<f64> = c.a.iter().map(|d| xt[*d]).collect();
    let ya = Mat::from_fn(xa.len(), 2, |i, _| xa[i]);
    let got = exp.dynamic(&[lt, 0.0], ya.as_ref()).unwrap();
    let reference_dyn = dense_dynamic(&c, lt, &xa);
    let reference_static = dense_dynamic(&c, 0.0, &xa);
    assert!(
        rel(&col(&got, 0), &reference_dyn) < 1e-10,
        "dynamic {:e}",
        rel(&col(&got, 0), &reference_dyn)
    );
    assert!(rel(&col(&got, 1), &reference_static) < 1e-10);
    let st = exp.static_(ya.as_ref()).unwrap();
    assert!(rel(&col(&st, 0), &reference_static) < 1e-10);
    // SEREP with 5 model modes: dense pseudo-inverse by normal equations
    let phi = eig.vectors.as_ref().subcols(0, 5).to_owned();
    let phia = sub(&phi, &c.a, &(0..5).collect::<Vec<_>>());
    let ya1 = Mat::from_fn(xa.len(), 1, |i, _| xa[i]);
    let normal = phia.transpose() * &phia;
    let coef = normal.partial_piv_lu().solve(&(phia.transpose() * &ya1));
    let reference_serep = &phi * &coef;
    let serep = exp.serep(phi.as_ref(), ya1.as_ref()).unwrap();
    assert!(rel(&col(&serep, 0), &col(&reference_serep, 0)) < 1e-9);
}

/// An exact model mode at the sensors, expanded at its own eigenvalue, is recovered exactly by the
/// dynamic expansion; SEREP is exact when the mode is in its basis; Guyan is exact for a static
/// deflection under loads at the measured DOFs.
#[test]
fn exact_recoveries() {
    let c = case();
    let eig = full_eigen(&c.sys);
    let exp = Expander::new(&c.sys.k, &c.sys.m, &c.layout).unwrap();
    for j in [0, 2, 4] {
        let phi = col(&eig.vectors, j);
        let ya = Mat::from_fn(c.a.len(), 1, |i, _| phi[c.a[i]]);
        let x = exp.dynamic(&[eig.values[j]], ya.as_ref()).unwrap();
        assert!(
            rel(&col(&x, 0), &phi) < 1e-8,
            "mode {j}: {:e}",
            rel(&col(&x, 0), &phi)
        );
        let basis = eig.vectors.as_ref().subcols(0, 6);
        let s = exp.serep(basis, ya.as_ref()).unwrap();
        assert!(rel(&col(&s, 0), &phi) < 1e-10);
    }
    // static deflection under forces on the measured DOFs
    let mut f = vec![0.0; c.sys.k.rows()];
    for (i, d) in c.a.iter().enumerate() {
        f[*d] = ((i * 7) % 5) as f64 - 2.0;
    }
    let kd = dense(&c.sys.k);
    let u = kd
        .partial_piv_lu()
        .solve(&Mat::from_fn(f.len(), 1, |i, _| f[i]));
    let u = col(&u, 0);
    let ya = Mat::from_fn(c.a.len(), 1, |i, _| u[c.a[i]]);
    let x = exp.static_(ya.as_ref()).unwrap();
    assert!(rel(&col(&x, 0), &u) < 1e-10);
}

#[test]
fn bad_expansion_input() {
    let c = case();
    let exp = Expander::new(&c.sys.k, &c.sys.m, &c.layout).unwrap();
    let s = c.a.len();
    let eig = full_eigen(&c.sys);
    let ya = Mat::from_fn(s, 1, |i, _| (i as f64).sin() + 1.0);
    // more SEREP modes than sensors
    let too_many = eig.vectors.as_ref().subcols(0, s + 1);
    assert!(exp.serep(too_many, ya.as_ref()).is_err());
    // an expansion frequency on an eigenvalue of the structure with its sensors held: an error,
    // not a NaN
    let kd = dense(&c.sys.k);
    let md = dense(&c.sys.m);
    let held =
        generalized_symmetric_eigen(sub(&kd, &c.o, &c.o).as_ref(), sub(&md, &c.o, &c.o).as_ref())
            .unwrap();
    let err = exp.dynamic(&[held.values[0]], ya.as_ref()).unwrap_err();
    assert!(err.to_string().contains("singular"), "{err}");
    // sizes and NaN
    assert!(exp.dynamic(&[1.0, 2.0], ya.as_ref()).is_err());
    let short = Mat::from_fn(s - 1, 1, |_, _| 1.0);
    assert!(exp.static_(short.as_ref()).is_err());
    let mut nan = ya.clone();
    nan[(3, 0)] = f64::NAN;
    assert!(exp.static_(nan.as_ref()).is_err());
    assert!(exp.dynamic(&[f64::INFINITY], ya.as_ref()).is_err());
    // an oblique sensor has no measured DOF
    let tip = c
        .model
        .mesh()
        .node_id(c.model.mesh().node_set("xmax").unwrap()[0]);
    let oblique = SensorLayout::new(
        c.model.mesh(),
        &c.sys.dofs,
        vec![Sensor::new(tip, [1.0, 1.0, 0.0])],
    )
    .unwrap();
    assert!(Expander::new(&c.sys.k, &c.sys.m, &oblique).is_err());
    // every DOF measured
    let full = SensorLayout::full(c.model.mesh(), &c.sys.dofs);
    assert!(Expander::new(&c.sys.k, &c.sys.m, &full).is_err());
    // a free-free model with one measured node cannot be expanded statically (rigid rotation
    // about that node is free)
    let ff = bar([4, 1, 1], false);
    let sff = ff.assemble(MassKind::Consistent).unwrap();
    let one = SensorLayout::triaxial(ff.mesh(), &sff.dofs, &[ff.mesh().node_id(0)]).unwrap();
    let e = Expander::new(&sff.k, &sff.m, &one).unwrap();
    let y = Mat::from_fn(3, 1, |i, _| i as f64);
    let err = e.static_(y.as_ref()).unwrap_err();
    assert!(err.to_string().contains("rigid"), "{err}");
}

/// Minimum-residual and MDRE-WE expansions against dense solutions of their normal equations,
/// and exact recovery of a model mode at its own eigenvalue.
#[test]
fn minimum_residual_and_mdre_equal_dense_formulas() {
    let c = case();
    let exp = Expander::new(&c.sys.k, &c.sys.m, &c.layout).unwrap();
    let (kd, md) = (dense(&c.sys.k), dense(&c.sys.m));
    let (lt, xt) = perturbed_mode(&c.model, 0.05, 0.8, 1);
    let xa: Vec<f64> = c.a.iter().map(|d| xt[*d]).collect();
    let ya = Mat::from_fn(xa.len(), 1, |i, _| xa[i]);
    let z = &kd - &md * faer::Scale(lt);
    // minimum residual: (Z_o^T M^-1 Z_o) x_o = -Z_o^T M^-1 Z_a y
    let zo = sub(&z, &(0..z.nrows()).collect::<Vec<_>>(), &c.o);
    let za = sub(&z, &(0..z.nrows()).collect::<Vec<_>>(), &c.a);
    let mlu = md.partial_piv_lu();
    let minv_zo = mlu.solve(&zo);
    let normal = zo.transpose() * &minv_zo;
    let rhs = -(minv_zo.transpose() * (&za * &ya));
    let xo = normal.partial_piv_lu().solve(&rhs);
    let mut reference = vec![0.0; z.nrows()];
    for (i, d) in c.a.iter().enumerate() {
        reference[*d] = xa[i];
    }
    for (i, d) in c.o.iter().enumerate() {
        reference[*d] = xo[(i, 0)];
    }
    let got = exp.minimum_residual(&[lt], ya.as_ref()).unwrap();
    assert!(
        rel(&col(&got, 0), &reference) < 1e-9,
        "min-res {:e}",
        rel(&col(&got, 0), &reference)
    );
    // MDRE-WE: (Z K^-1 Z + gamma C^T C) x = gamma C^T y
    let gamma = 1e12;
    let kinv_z = kd.partial_piv_lu().solve(&z);
    let mut lhs = &z * &kinv_z;
    let mut r = Mat::zeros(z.nrows(), 1);
    for (i, d) in c.a.iter().enumerate() {
        lhs[(*d, *d)] += gamma;
        r[(*d, 0)] = gamma * xa[i];
    }
    let reference = lhs.partial_piv_lu().solve(&r);
    let got = exp.mdre(&[lt], ya.as_ref(), gamma, 0.0).unwrap();
    assert!(
        rel(&col(&got, 0), &col(&reference, 0)) < 1e-9,
        "MDRE {:e}",
        rel(&col(&got, 0), &col(&reference, 0))
    );
    // exact mode at its own eigenvalue: both recover it
    let eig = full_eigen(&c.sys);
    let phi = col(&eig.vectors, 2);
    let ya = Mat::from_fn(c.a.len(), 1, |i, _| phi[c.a[i]]);
    let x = exp.minimum_residual(&[eig.values[2]], ya.as_ref()).unwrap();
    assert!(
        rel(&col(&x, 0), &phi) < 1e-9,
        "{:e}",
        rel(&col(&x, 0), &phi)
    );
    let x = exp.mdre(&[eig.values[2]], ya.as_ref(), gamma, 0.0).unwrap();
    assert!(
        rel(&col(&x, 0), &phi) < 1e-9,
        "{:e}",
        rel(&col(&x, 0), &phi)
    );
    // bad weights
    assert!(exp.mdre(&[lt], ya.as_ref(), 0.0, 0.0).is_err());
    assert!(exp.mdre(&[lt], ya.as_ref(), 1.0, -1.0).is_err());
}

/// Dense minimum-residual expansion on the measured set `a`: `(Z_o^T M^-1 Z_o) x_o = -Z_o^T M^-1
/// Z_a y`, and dense MDRE-WE `(Z K^-1 Z + gamma C^T C) x = gamma C^T y`.
fn dense_min_res_and_mdre(
    c: &Case,
    a: &[usize],
    lambda: f64,
    y: &[f64],
    gamma: f64,
) -> [Vec<f64>; 2] {
    let (kd, md) = (dense(&c.sys.k), dense(&c.sys.m));
    let n = kd.nrows();
    let o: Vec<usize> = (0..n).filter(|d| !a.contains(d)).collect();
    let all: Vec<usize> = (0..n).collect();
    let z = &kd - &md * faer::Scale(lambda);
    let (zo, za) = (sub(&z, &all, &o), sub(&z, &all, a));
    let ya = Mat::from_fn(y.len(), 1, |i, _| y[i]);
    let minv_zo = md.partial_piv_lu().solve(&zo);
    let xo = (zo.transpose() * &minv_zo)
        .partial_piv_lu()
        .solve(&(-(minv_zo.transpose() * (&za * &ya))));
    let mut min_res = vec![0.0; n];
    a.iter().zip(y).for_each(|(d, v)| min_res[*d] = *v);
    o.iter()
        .enumerate()
        .for_each(|(i, d)| min_res[*d] = xo[(i, 0)]);
    let mut lhs = &z * &kd.partial_piv_lu().solve(&z);
    let mut r = Mat::zeros(n, 1);
    for (i, d) in a.iter().enumerate() {
        lhs[(*d, *d)] += gamma;
        r[(*d, 0)] = gamma * y[i];
    }
    [min_res, col(&lhs.partial_piv_lu().solve(&r), 0)]
}

/// The sensor-space formulation (one factorization of `Z` per eigenvalue for every sensor set)
/// against dense formulas on three nested sensor sets, with the factorization count that is its
/// point; and its fallbacks: a free-free model's singular `K` for the static case, an eigenvalue
/// of the held structure.
#[test]
fn sensor_space_equals_dense_formulas_on_every_set() {
    let c = case();
    let (lt, xt) = perturbed_mode(&c.model, 0.05, 0.8, 1);
    let gamma = 1e12;
    let mut space = SensorSpace::new(&c.sys.k, &c.sys.m, &c.a).unwrap();
    space.prepare(&[lt, 0.0], &[0.0]).unwrap();
    assert_eq!(space.factorizations(), 2);
    for keep in [c.a.len(), c.a.len() * 2 / 3, c.a.len() / 3] {
        // a sensor set of the candidates, in another order than theirs
        let a: Vec<usize> = c.a[..keep].iter().rev().copied().collect();
        let y: Vec<f64> = a.iter().map(|d| xt[*d]).collect();
        let ya = Mat::from_fn(a.len(), 2, |i, _| y[i]);
        let sub_case = Case {
            model: bar([1, 1, 1], true),
            sys: c.sys.clone(),
            layout: c.layout.clone(),
            o: (0..c.sys.k.rows()).filter(|d| !a.contains(d)).collect(),
            a: a.clone(),
        };
        let dynamic = space.dynamic(&[lt, 0.0], &a, ya.as_ref()).unwrap();
        let (rd, rs) = (
            dense_dynamic(&sub_case, lt, &y),
            dense_dynamic(&sub_case, 0.0, &y),
        );
        assert!(
            rel(&col(&dynamic, 0), &rd) < 1e-9,
            "dynamic {keep}: {:e}",
            rel(&col(&dynamic, 0), &rd)
        );
        assert!(rel(&col(&dynamic, 1), &rs) < 1e-9, "static {keep}");
        let [rm, rw] = dense_min_res_and_mdre(&sub_case, &a, lt, &y, gamma);
        let ya1 = ya.as_ref().subcols(0, 1);
        let mr = space.minimum_residual(&[lt], &a, ya1).unwrap();
        assert!(
            rel(&col(&mr, 0), &rm) < 1e-9,
            "min-res {keep}: {:e}",
            rel(&col(&mr, 0), &rm)
        );
        let md = space.mdre(&[lt], &a, ya1, gamma, 0.0).unwrap();
        assert!(
            rel(&col(&md, 0), &rw) < 1e-9,
            "MDRE {keep}: {:e}",
            rel(&col(&md, 0), &rw)
        );
        // the saddle-point formulations agree
        let exp = Expander::with_measured_dofs(&c.sys.k, &c.sys.m, &a).unwrap();
        let saddle = exp.minimum_residual_saddle_point(&[lt], ya1).unwrap();
        // measured: the regularised, refined saddle point stagnates near 1e-7 with 12 sensors
        // (the sensor space: 4e-11)
        assert!(rel(&col(&saddle, 0), &rm) < 1e-6);
        let saddle = exp.mdre_saddle_point(&[lt], ya1, gamma, 0.0).unwrap();
        assert!(rel(&col(&saddle, 0), &rw) < 1e-7);
    }
    // every set and method above came from the two factorizations
    assert_eq!(space.factorizations(), 2);
    assert_eq!(space.fallbacks(), 0);
    // a DOF that is not a candidate
    let outside = (0..c.sys.k.rows()).find(|d| !c.a.contains(d)).unwrap();
    let y1 = Mat::from_fn(1, 1, |_, _| 1.0);
    assert!(space.dynamic(&[lt], &[outside], y1.as_ref()).is_err());
    // an eigenvalue of the structure with its sensors held: the fallback reports it
    let (kd, md) = (dense(&c.sys.k), dense(&c.sys.m));
    let held =
        generalized_symmetric_eigen(sub(&kd, &c.o, &c.o).as_ref(), sub(&md, &c.o, &c.o).as_ref())
            .unwrap();
    let ya = Mat::from_fn(c.a.len(), 1, |i, _| (i as f64).sin() + 1.0);
    let err = space
        .dynamic(&[held.values[0]], &c.a, ya.as_ref())
        .unwrap_err();
    assert!(err.to_string().contains("singular"), "{err}");
    // free-free: K is singular, so the static case is recomputed on K_oo; equal to it
    let ff = bar([4, 1, 1], false);
    let sff = ff.assemble(MassKind::Consistent).unwrap();
    let nodes: Vec<u64> = (0..4).map(|i| ff.mesh().node_id(i * 3)).collect();
    let layout = SensorLayout::triaxial(ff.mesh(), &sff.dofs, &nodes).unwrap();
    let a = layout.measured_dofs().unwrap();
    let y = Mat::from_fn(a.len(), 1, |i, _| ((i * 3) % 7) as f64 - 3.0);
    let reference = Expander::new(&sff.k, &sff.m, &layout)
        .unwrap()
        .static_(y.as_ref())
        .unwrap();
    let mut space = SensorSpace::new(&sff.k, &sff.m, &a).unwrap();
    let got = space.dynamic(&[0.0], &a, y.as_ref()).unwrap();
    assert!(rel(&col(&got, 0), &col(&reference, 0)) < 1e-9);
    assert_eq!(space.fallbacks(), 1);
    // free-free MDRE-WE: the sensor space is defined at a zero stiffness shift too, as the limit
    // of the shifted energy norm (the saddle point with a small shift approaches it)
    let lambda = 4.0e6;
    let zero = space.mdre(&[lambda], &a, y.as_ref(), 1e12, 0.0).unwrap();
    let exp = Expander::new(&sff.k, &sff.m, &layout).unwrap();
    // measured: 7.9e-3, 8.0e-4, 8.7e-6 at shifts 1e-5, 1e-6, 1e-8 lambda (linear in the shift);
    // at the same shift both formulations agree to the saddle point's accuracy
    for sh in [1e-5, 1e-6, 1e-8] {
        let shifted = exp
            .mdre_saddle_point(&[lambda], y.as_ref(), 1e12, sh * lambda)
            .unwrap();
        let d = rel(&col(&shifted, 0), &col(&zero, 0));
        assert!(d < 1e3 * sh, "shift {sh:e}: {d:e}");
        let via = space
            .mdre(&[lambda], &a, y.as_ref(), 1e12, sh * lambda)
            .unwrap();
        // Both are sensitive to K's round-off at 1e-6 here (weight 1e12 on a free-free bar):
        // two summation orders of the same K gave 1.3e-7..5.3e-7 and 1.0e-6..2.4e-6 between
        // them, and moved the saddle point's own `d` at 1e-8 from 8.04e-6 to 8.71e-6. 1e-5 is 4x
        // the largest; the shifts of 1e-5 and 1e-6 still tell a shifted norm from an unshifted
        // one (`d` = 7.9e-3 and 8.0e-4).
        assert!(rel(&col(&shifted, 0), &col(&via, 0)) < 1e-5);
    }
}

/// An exact model mode expanded at its own eigenvalue, where `Z` is singular to round-off.
/// `Z^-1 E_S`'s columns are then the mode divided by a pivot of round-off size plus a bounded
/// rest, and whether that rest survives in the dense sensor-space system depends on the pivot's
/// last bits: at some eigenvalues a few ulps away the sensor-space solution is wrong (its
/// conditions' residual measured up to 0.19 of the terms' size) and at most it is right to 1e-11.
/// Whichever happens on a machine, the a posteriori check must send the wrong ones to the
/// omitted-DOF saddle point, so every result is the mode. The checks are componentwise (residuals
/// against `|K||x| + lambda |M||x|`): for a low mode `Z x`, and even `K x`, are far below
/// `||K|| ||x||`, and a normwise check rejected the first mode's round-off, 1.3e-7 of `||K x||`.
#[test]
fn sensor_space_at_model_eigenvalues() {
    let c = case();
    let eig = full_eigen(&c.sys);
    let (mut solves, mut fallbacks) = (0, 0);
    for j in [0, 2, 4] {
        let phi = col(&eig.vectors, j);
        let ya = Mat::from_fn(c.a.len(), 1, |i, _| phi[c.a[i]]);
        // the eigenvalue and its neighbours 40 ulps either side: the round-off a different CPU
        // or BLAS kernel would make (one of these failed on the CI machine at offset 0)
        for ulps in -40i64..=40 {
            let lambda = f64::from_bits(eig.values[j].to_bits().wrapping_add_signed(ulps));
            let mut space = SensorSpace::new(&c.sys.k, &c.sys.m, &c.a).unwrap();
            let x = space
                .minimum_residual(&[lambda], &c.a, ya.as_ref())
                .unwrap();
            let w = space.mdre(&[lambda], &c.a, ya.as_ref(), 1e12, 0.0).unwrap();
            // measured here: at most 7.9e-10 (mode 5, minimum residual, 19 ulps above), 6.7e-11
            // on mode 1, 6.9e-11 on mode 3; the fallback's results are the mode to 2e-13
            let (ex, ew) = (rel(&col(&x, 0), &phi), rel(&col(&w, 0), &phi));
            assert!(
                ex < 5e-9 && ew < 5e-9,
                "mode {j}, {ulps} ulps: {ex:e} {ew:e}"
            );
            solves += 2;
            fallbacks += space.fallbacks();
        }
    }
    // measured here: 25 of 486 solves fell back, all on mode 5; most must stay in the sensor
    // space, or the factorizations it exists to save are made anyway
    assert!(fallbacks * 4 < solves, "{fallbacks} of {solves} fell back");
}

/// Sensors between nodes (shape-function rows found by `femu_fem::locate`) and oblique ones on
/// the clamped bar.
fn between_nodes_case() -> (Model, SystemMatrices, SensorLayout) {
    let model = bar([8, 2, 2], true);
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let mesh = model.mesh();
    let locator = femu_fem::locate::Locator::new(mesh);
    let mut sensors = Vec::new();
    for (label, p) in [
        (1001, [0.031, 0.004, 0.02]),
        (1002, [0.087, 0.013, 0.02]),
        (1003, [0.142, 0.007, 0.011]),
        (1004, [0.19, 0.019, 0.003]),
    ] {
        let loc = locator.locate(mesh, p, 0.0).unwrap();
        let at: Vec<(u64, f64)> = loc
            .weights
            .iter()
            .map(|(a, w)| (mesh.node_id(*a), *w))
            .collect();
        for d in [[1.0, 0.0, 0.0], [0.0, 0.6, 0.8], [0.0, 0.0, 1.0]] {
            sensors.push(Sensor::between(label, d, at.clone()));
        }
    }
    let layout = SensorLayout::new(mesh, &sys.dofs, sensors).unwrap();
    (model, sys, layout)
}

/// Dense constrained expansion: `[Z C^T; C 0] [x; mu] = [0; y]` (`Z = K - lambda M`).
fn dense_constrained(
    sys: &SystemMatrices,
    layout: &SensorLayout,
    lambda: f64,
    y: &[f64],
) -> Vec<f64> {
    let n = sys.k.rows();
    let s = layout.len();
    let z = dense(&sys.k) - dense(&sys.m) * faer::Scale(lambda);
    let c = dense(&layout.matrix().to_csc());
    let kkt = Mat::from_fn(n + s, n + s, |i, j| match (i < n, j < n) {
        (true, true) => z[(i, j)],
        (true, false) => c[(j - n, i)],
        (false, true) => c[(i - n, j)],
        (false, false) => 0.0,
    });
    let rhs = Mat::from_fn(n + s, 1, |i, _| if i < n { 0.0 } else { y[i - n] });
    let sol = kkt.partial_piv_lu().solve(&rhs);
    (0..n).map(|i| sol[(i, 0)]).collect()
}

#[test]
fn sensors_between_nodes_expand_as_the_constrained_dense_formulas() {
    let (_model, sys, layout) = between_nodes_case();
    let eig = full_eigen(&sys);
    let basis = femu_correlate::SensorBasis::new(&sys.k, &sys.m, &layout).unwrap();
    // the congruence keeps the spectrum: the lowest eigenvalues of (K_z, M_z) are (K, M)'s
    let ez =
        generalized_symmetric_eigen(dense(basis.k()).as_ref(), dense(basis.m()).as_ref()).unwrap();
    for i in 0..6 {
        assert!(
            (ez.values[i] / eig.values[i] - 1.0).abs() < 1e-9,
            "eigenvalue {i}"
        );
    }
    // readings of a perturbed mode, expanded statically and dynamically
    let (lambda, phi) = super::common::perturbed_mode(&_model, 0.1, 0.8, 0);
    let y = layout.measure(&phi).unwrap();
    let ya = Mat::from_fn(y.len(), 1, |i, _| y[i]);
    for (method, shift) in [(Method::Static, 0.0), (Method::Dynamic, lambda)] {
        let x = basis.expand(method, &[lambda], ya.as_ref(), None).unwrap();
        let reference = dense_constrained(&sys, &layout, shift, &y);
        let got = col(&x, 0);
        assert!(
            rel(&got, &reference) < 1e-9,
            "{method}: {}",
            rel(&got, &reference)
        );
        // the expanded shape reproduces the readings exactly
        let back = layout.measure(&got).unwrap();
        assert!(rel(&back, &y) < 1e-12);
    }
    // SEREP: x = Phi (C Phi)^-1 y with 12 model modes on the 12 readings
    let basis_modes = Mat::from_fn(sys.k.rows(), 12, |i, j| eig.vectors[(i, j)]);
    let x = basis
        .expand(
            Method::Serep(12),
            &[lambda],
            ya.as_ref(),
            Some(basis_modes.as_ref()),
        )
        .unwrap();
    let cphi = layout.measure_all(basis_modes.as_ref()).unwrap();
    let q = cphi.partial_piv_lu().solve(&ya);
    let reference = &basis_modes * &q;
    assert!(rel(&col(&x, 0), &col(&reference, 0)) < 1e-8);
    // minimum residual imposes the readings too
    let x = basis
        .expand(Method::MinimumResidual, &[lambda], ya.as_ref(), None)
        .unwrap();
    assert!(rel(&layout.measure(&col(&x, 0)).unwrap(), &y) < 1e-10);
}

#[test]
fn two_sensors_on_one_point_cannot_be_expanded() {
    let model = bar([8, 2, 2], true);
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let mesh = model.mesh();
    let locator = femu_fem::locate::Locator::new(mesh);
    let loc = locator.locate(mesh, [0.05, 0.01, 0.01], 0.0).unwrap();
    let at: Vec<(u64, f64)> = loc
        .weights
        .iter()
        .map(|(a, w)| (mesh.node_id(*a), *w))
        .collect();
    let layout = SensorLayout::new(
        mesh,
        &sys.dofs,
        vec![
            Sensor::between(7, [1.0, 0.0, 0.0], at.clone()),
            Sensor::between(8, [1.0, 0.0, 0.0], at),
        ],
    )
    .unwrap();
    let err = femu_correlate::SensorBasis::new(&sys.k, &sys.m, &layout).unwrap_err();
    assert!(err.to_string().contains("sensor 1 (node 8)"), "{err}");
    assert!(err.to_string().contains("sensor 0 (node 7)"), "{err}");
}

/// SB-EBE's expansion with projected sensitivities in the diagonal metric `W = diag(M)^-1`, in the
/// sensor space and by the saddle point, against the dense formulas: `x_o = -(Z_o^T W Z_o)^-1
/// Z_o^T W Z_a y` and `P A = A - Z_o (Z_o^T W Z_o)^-1 Z_o^T W A`, for columns `A` that depend on
/// the expanded `x` (as the parameter sensitivities do), at two eigenvalues of a perturbed model.
#[test]
fn projected_expansion_in_the_sensor_space_equals_dense_formulas() {
    let c = case();
    let exp = Expander::new(&c.sys.k, &c.sys.m, &c.layout).unwrap();
    let (kd, md) = (dense(&c.sys.k), dense(&c.sys.m));
    let n = kd.nrows();
    let all: Vec<usize> = (0..n).collect();
    let w_inv: Vec<f64> = (0..n).map(|i| md[(i, i)]).collect();
    let (l1, x1) = perturbed_mode(&c.model, 0.05, 0.8, 1);
    let (l2, x2) = perturbed_mode(&c.model, 0.12, 1.3, 3);
    let lambdas = [l1, l2];
    let ya = Mat::from_fn(c.a.len(), 2, |i, j| [&x1, &x2][j][c.a[i]]);
    // three columns built from x: x itself, K x and x scaled DOF by DOF
    let columns = |x: &[f64]| -> Mat<f64> {
        let kx = mul(&c.sys.k, x);
        Mat::from_fn(n, 3, |i, k| match k {
            0 => x[i],
            1 => kx[i],
            _ => x[i] * (1.0 + (i as f64 * 0.7).sin()),
        })
    };
    let w = Mat::from_fn(n, n, |i, j| if i == j { 1.0 / w_inv[i] } else { 0.0 });
    let mut reference = Vec::new();
    for j in 0..2 {
        let z = &kd - &md * faer::Scale(lambdas[j]);
        let (zo, za) = (sub(&z, &all, &c.o), sub(&z, &all, &c.a));
        let normal = zo.transpose() * &w * &zo;
        let lu = normal.partial_piv_lu();
        let xo = lu.solve(&(-(zo.transpose() * &w * (&za * ya.subcols(j, 1)))));
        let mut x = vec![0.0; n];
        c.a.iter().enumerate().for_each(|(i, d)| x[*d] = ya[(i, j)]);
        c.o.iter().enumerate().for_each(|(i, d)| x[*d] = xo[(i, 0)]);
        let a = columns(&x);
        let pa = &a - &zo * lu.solve(&(zo.transpose() * &w * &a));
        reference.push((x, pa));
    }
    let calls = std::sync::atomic::AtomicUsize::new(0);
    let cols = |_: usize, x: &[f64]| -> Result<Mat<f64>, femu_correlate::CorrelateError> {
        calls.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        Ok(columns(x))
    };
    let (xs, ps) = exp
        .minimum_residual_projected(&lambdas, ya.as_ref(), &w_inv, None, cols)
        .unwrap();
    // one call of the columns per mode: the sensor-space path did not fall back
    assert_eq!(calls.load(std::sync::atomic::Ordering::Relaxed), 2);
    let (xk, pk) = exp
        .minimum_residual_projected_saddle_point(&lambdas, ya.as_ref(), &w_inv, cols)
        .unwrap();
    for j in 0..2 {
        let (x, pa) = &reference[j];
        let pa_norm = pa.norm_l2();
        for (name, got_x, got_p, tol) in [
            // sensor space: measured 2.2e-14 (x) and 4.2e-13 (P A) on mode 0, whose eigenvalue
            // lies near one of the model's (Z^-1 E's columns nearly parallel), 4.0e-14 and
            // 2.3e-13 on mode 1 (2.8e-12 and 1.4e-9 on mode 0 when x came from G^-1); the saddle
            // point measured 1.4e-12 here, 1e-7 documented for badly conditioned cases
            ("sensor space", &xs, &ps[j], 1e-10),
            ("saddle point", &xk, &pk[j], 1e-6),
        ] {
            let ex = rel(&col(got_x, j), x);
            let ep = (got_p - pa).norm_l2() / pa_norm;
            assert!(
                ex < tol && ep < tol,
                "{name}, mode {j}: x {ex:e}, P A {ep:e}"
            );
        }
    }
    // at a model eigenvalue Z is singular: the exact mode is still recovered (through the check
    // and, where it fails, the saddle point), with the saddle point's projected columns
    let eig = full_eigen(&c.sys);
    let phi = col(&eig.vectors, 2);
    let ya = Mat::from_fn(c.a.len(), 1, |i, _| phi[c.a[i]]);
    let (x, p) = exp
        .minimum_residual_projected(&[eig.values[2]], ya.as_ref(), &w_inv, None, cols)
        .unwrap();
    assert!(
        rel(&col(&x, 0), &phi) < 1e-8,
        "{:e}",
        rel(&col(&x, 0), &phi)
    );
    let (_, pk) = exp
        .minimum_residual_projected_saddle_point(&[eig.values[2]], ya.as_ref(), &w_inv, cols)
        .unwrap();
    let ep = (&p[0] - &pk[0]).norm_l2() / pk[0].norm_l2();
    assert!(ep < 1e-6, "P A at a model eigenvalue: {ep:e}");
    // the perturbed mode beside the model eigenvalue: the sensor space takes the first, the
    // saddle point the second, and each lands in its own column
    let mixed = Expander::new(&c.sys.k, &c.sys.m, &c.layout).unwrap();
    let y2 = Mat::from_fn(
        c.a.len(),
        2,
        |i, j| {
            if j == 0 { x2[c.a[i]] } else { phi[c.a[i]] }
        },
    );
    let (xm, pm) = mixed
        .minimum_residual_projected(&[l2, eig.values[2]], y2.as_ref(), &w_inv, None, cols)
        .unwrap();
    assert_eq!(mixed.projected_fallbacks(), 1);
    let (x, pa) = &reference[1];
    let (ex, ep) = (rel(&col(&xm, 0), x), (&pm[0] - pa).norm_l2() / pa.norm_l2());
    assert!(
        ex < 1e-10 && ep < 1e-10,
        "beside a model eigenvalue: {ex:e} {ep:e}"
    );
    let (ex, ep) = (
        rel(&col(&xm, 1), &phi),
        (&pm[1] - &pk[0]).norm_l2() / pk[0].norm_l2(),
    );
    assert!(
        ex < 1e-8 && ep < 1e-6,
        "at the model eigenvalue: {ex:e} {ep:e}"
    );
}

/// Near a model eigenvalue (relative offsets 1e-4 and 1e-7, where the columns of `Z^-1 E` are
/// nearly parallel and the sensor-space Gram matrix `G = V^T W^-1 V` squares their
/// conditioning), the projected expansion stays in the sensor space (no mode handed to the saddle
/// point) and equals the dense least-squares formulas, computed here by a dense QR of
/// `W^1/2 Z_{:,o}`: `x_o = argmin ||W^1/2 (Z_{:,o} x_o + Z_{:,a} y)||` and
/// `P A = A - Z_{:,o} argmin_t ||W^1/2 (A - Z_{:,o} t)||`; at 1e-10 it may hand over, and still
/// equals them.
#[test]
fn projected_expansion_near_a_model_eigenvalue_stays_in_the_sensor_space() {
    let c = case();
    let (kd, md) = (dense(&c.sys.k), dense(&c.sys.m));
    let n = kd.nrows();
    let all: Vec<usize> = (0..n).collect();
    let w_inv: Vec<f64> = (0..n).map(|i| md[(i, i)]).collect();
    let sw = Mat::from_fn(
        n,
        n,
        |i, j| if i == j { 1.0 / w_inv[i].sqrt() } else { 0.0 },
    );
    let eig = full_eigen(&c.sys);
    let columns = |x: &[f64]| -> Mat<f64> {
        let kx = mul(&c.sys.k, x);
        Mat::from_fn(n, 2, |i, k| {
            if k == 0 {
                kx[i]
            } else {
                x[i] * (1.5 + (i as f64).cos())
            }
        })
    };
    let cols = |_: usize, x: &[f64]| -> Result<Mat<f64>, femu_correlate::CorrelateError> {
        Ok(columns(x))
    };
    for mode in [0, 3] {
        let phi = col(&eig.vectors, mode);
        // the test shape: the model's mode with a smooth 1 % disturbance
        let ya = Mat::from_fn(c.a.len(), 1, |i, _| {
            phi[c.a[i]] * (1.0 + 0.01 * (c.a[i] as f64 * 0.3).sin())
        });
        for offset in [1e-4, 1e-7, 1e-10] {
            let lambda = eig.values[mode] * (1.0 + offset);
            let z = &kd - &md * faer::Scale(lambda);
            let (zo, za) = (sub(&z, &all, &c.o), sub(&z, &all, &c.a));
            let qr = (&sw * &zo).qr();
            let xo = qr.solve_lstsq(-(&sw * (&za * &ya)));
            let mut x = vec![0.0; n];
            c.a.iter().enumerate().for_each(|(i, d)| x[*d] = ya[(i, 0)]);
            c.o.iter().enumerate().for_each(|(i, d)| x[*d] = xo[(i, 0)]);
            let a = columns(&x);
            let pa = &a - &zo * qr.solve_lstsq(&sw * &a);
            let exp = Expander::new(&c.sys.k, &c.sys.m, &c.layout).unwrap();
            let (xs, ps) = exp
                .minimum_residual_projected(&[lambda], ya.as_ref(), &w_inv, None, cols)
                .unwrap();
            let what = format!("mode {mode}, offset {offset:e}");
            if offset > 1e-8 {
                assert_eq!(
                    exp.projected_fallbacks(),
                    0,
                    "{what}: handed to the saddle point"
                );
            }
            // measured: x 1.7e-11 and 1.0e-11 at 1e-4, 7.5e-9 and 5.6e-9 at 1e-7; P A 1.1e-8
            // and 7.2e-10 at 1e-4, 3.4e-6 and 4.2e-7 at 1e-7 (its check's looser tolerance)
            let ex = rel(&col(&xs, 0), &x);
            let ep = (&ps[0] - &pa).norm_l2() / pa.norm_l2();
            assert!(ex < 2e-8 && ep < 1e-5, "{what}: x {ex:e}, P A {ep:e}");
        }
    }
}

/// Minimum-residual expansion in the metric `M^-1` of a model with massless DOFs (a lumped beam's
/// rotations, a bar's torsion without inertia: `M` semi-definite): a chain of twelve unit springs
/// from a wall whose every other DOF has no mass. The exact modes come from the chain with the
/// massless DOFs condensed out (a dense eigenproblem written here, then `x_0 = -K_00^-1 K_0m
/// x_m`); measured at three massive DOFs, each has zero residual, so the expansion must return it
/// at every DOF, massless ones included (5e-7 relative: the saddle point's regularisation, see
/// `minimum_residual_saddle_point`). It failed as a singular saddle point before the massless rows
/// took the smallest positive mass.
#[test]
fn minimum_residual_expansion_with_massless_dofs_recovers_exact_modes() {
    let n = 12;
    let mut k = Mat::<f64>::zeros(n, n);
    let mut m = Mat::<f64>::zeros(n, n);
    for i in 0..n {
        k[(i, i)] += 1.0;
        if i + 1 < n {
            k[(i, i)] += 1.0;
            k[(i, i + 1)] -= 1.0;
            k[(i + 1, i)] -= 1.0;
        }
        if i % 2 == 1 {
            m[(i, i)] = 1.0 + 0.1 * i as f64;
        }
    }
    let massive: Vec<usize> = (0..n).filter(|i| i % 2 == 1).collect();
    let massless: Vec<usize> = (0..n).filter(|i| i % 2 == 0).collect();
    let k00 = sub(&k, &massless, &massless);
    let k0m = sub(&k, &massless, &massive);
    let kmm = sub(&k, &massive, &massive);
    let mmm = sub(&m, &massive, &massive);
    let lu = k00.partial_piv_lu();
    let s = lu.solve(&k0m);
    let kc = &kmm - k0m.transpose() * &s;
    let kc = Mat::from_fn(kc.nrows(), kc.ncols(), |i, j| {
        0.5 * (kc[(i, j)] + kc[(j, i)])
    });
    let eig = generalized_symmetric_eigen(kc.as_ref(), mmm.as_ref()).unwrap();
    let (ks, ms) = (sparse(&k), sparse(&m));
    let measured = vec![1, 5, 9];
    let exp = Expander::with_measured_dofs(&ks, &ms, &measured).unwrap();
    for j in [0, 1, 3] {
        let xm = col(&eig.vectors, j);
        let x0 = -&s * Mat::from_fn(xm.len(), 1, |i, _| xm[i]);
        let mut phi = vec![0.0; n];
        for (a, &d) in massive.iter().enumerate() {
            phi[d] = xm[a];
        }
        for (a, &d) in massless.iter().enumerate() {
            phi[d] = x0[(a, 0)];
        }
        let ya = Mat::from_fn(measured.len(), 1, |i, _| phi[measured[i]]);
        let x = exp
            .minimum_residual_saddle_point(&[eig.values[j]], ya.as_ref())
            .unwrap();
        assert!(
            rel(&col(&x, 0), &phi) < 5e-7,
            "mode {j}: {:e}",
            rel(&col(&x, 0), &phi)
        );
    }
}
