//! The sensor-removal study (the paper's Figure 1) on a small bar.

use super::common::*;
use faer::Mat;
use femu_correlate::Method;
use femu_correlate::study::sensor_removal_study;
use femu_correlate::{Estimator, Expander, SensorLayout};
use femu_fem::prelude::*;

#[test]
fn removal_study_points_equal_direct_computations() {
    let model = bar([6, 2, 1], true);
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let mesh = model.mesh();
    let eig = full_eigen(&sys);
    // every node with a free DOF: the full measurement set
    let all: Vec<u64> = (0..mesh.node_count())
        .filter(|n| sys.dofs.node_dofs(*n).iter().any(|d| d.is_some()))
        .map(|n| mesh.node_id(n))
        .collect();
    let truth: Vec<(f64, Vec<f64>)> = (0..2)
        .map(|j| perturbed_mode(&model, 0.05, 0.8, j))
        .collect();
    let n = sys.k.rows();
    let x = Mat::from_fn(n, 2, |i, j| truth[j].1[i]);
    let lambdas: Vec<f64> = truth.iter().map(|t| t.0).collect();
    // remove all but the last 5 nodes, every 10th set evaluated
    let removal: Vec<u64> = all[..all.len() - 5].to_vec();
    let methods = [
        Method::Static,
        Method::Dynamic,
        Method::Serep(3),
        Method::MinimumResidual,
    ];
    let basis = eig.vectors.as_ref().subcols(0, 6);
    let points = sensor_removal_study(
        &sys.k,
        &sys.m,
        mesh,
        &sys.dofs,
        &lambdas,
        x.as_ref(),
        &all,
        &removal,
        &methods,
        Some(basis),
        10,
    )
    .unwrap();
    // the full set: rho_M of the test shapes themselves
    let est = Estimator::new(&sys.k, &sys.m).unwrap();
    let (direct, _) = est.residual_norms(&lambdas, x.as_ref()).unwrap();
    let full: Vec<_> = points.iter().filter(|p| p.method.is_none()).collect();
    assert_eq!(full.len(), 2);
    for p in &full {
        assert_eq!(p.nodes, all.len());
        assert!((p.rho_m / direct[p.mode].rho_m - 1.0).abs() < 1e-12);
    }
    // the last set (5 nodes): dynamic expansion recomputed directly
    let last: Vec<u64> = all[all.len() - 5..].to_vec();
    let layout = SensorLayout::triaxial(mesh, &sys.dofs, &last).unwrap();
    let exp = Expander::new(&sys.k, &sys.m, &layout).unwrap();
    let xe = exp
        .dynamic(&lambdas, layout.measure_all(x.as_ref()).unwrap().as_ref())
        .unwrap();
    let (norms, _) = est.residual_norms(&lambdas, xe.as_ref()).unwrap();
    for mode in 0..2 {
        let p = points
            .iter()
            .find(|p| p.nodes == 5 && p.method == Some(Method::Dynamic) && p.mode == mode)
            .unwrap();
        assert!((p.rho_m / norms[mode].rho_m - 1.0).abs() < 1e-12);
        // (no monotonicity is asserted: dynamic expansion zeroes the residual on the omitted
        // DOFs, so with few sensors it can report a smaller rho_M than the full set does)
    }
    // sets evaluated: full, then every 10th removal, and the last
    let sets: std::collections::BTreeSet<usize> = points.iter().map(|p| p.nodes).collect();
    let expected = (0..=removal.len())
        .filter(|s| s % 10 == 0 || *s == removal.len())
        .count();
    assert_eq!(sets.len(), expected);
    assert_eq!(points.len(), 2 + (expected - 1) * methods.len() * 2);
    // (the chart and the CSV of these points are tested in femu-study)
    // a perfect model: its own modes as the test give rho_M ~ 0 after dynamic expansion
    let exact = eig.vectors.as_ref().subcols(0, 2).to_owned();
    let pts = sensor_removal_study(
        &sys.k,
        &sys.m,
        mesh,
        &sys.dofs,
        &eig.values[..2],
        exact.as_ref(),
        &last,
        &[],
        &[Method::Dynamic],
        None,
        1,
    )
    .unwrap();
    for p in pts {
        assert!(p.rho_m < 1e-6 * eig.values[p.mode], "{p:?}");
    }
    // a removal node that is not measured is refused
    assert!(
        sensor_removal_study(
            &sys.k,
            &sys.m,
            mesh,
            &sys.dofs,
            &lambdas,
            x.as_ref(),
            &last,
            &[all[0]],
            &methods,
            None,
            1
        )
        .is_err()
    );
}

/// Dense `A^-1 B` by LU with partial pivoting (faer).
fn solve(a: &Mat<f64>, b: &Mat<f64>) -> Mat<f64> {
    use faer::linalg::solvers::Solve;
    a.partial_piv_lu().solve(b)
}

/// The study's sensor-space branch (a start set that is a proper subset of the nodes, as the demo
/// and the command use), value by value against dense formulas written here: static
/// `x_o = -K_oo^-1 K_oa x_a`, dynamic `x_o = -Z_oo^-1 Z_oa x_a`, minimum residual from its normal
/// equations `(Z_:o^T M^-1 Z_:o) x_o = -Z_:o^T M^-1 Z_:a x_a`, and `rho_M^2 = r^T M^-1 r / x^T M x`
/// with `r = Z x`, for every evaluated set and mode, to 1e-10 (measured below 1e-11).
#[test]
fn sensor_space_branch_equals_dense_normal_equations() {
    let model = bar([6, 2, 1], true);
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let mesh = model.mesh();
    let n = sys.k.rows();
    // the upper face's free nodes: a proper subset of the nodes
    let start: Vec<u64> = mesh
        .node_set("zmax")
        .unwrap()
        .iter()
        .filter(|i| sys.dofs.node_dofs(**i).iter().all(|d| d.is_some()))
        .map(|i| mesh.node_id(*i))
        .collect();
    assert!(start.len() >= 8 && 3 * start.len() < n);
    let removal: Vec<u64> = start[..4].to_vec();
    let truth: Vec<(f64, Vec<f64>)> = (0..2)
        .map(|j| perturbed_mode(&model, 0.05, 0.8, j))
        .collect();
    let x = Mat::from_fn(n, 2, |i, j| truth[j].1[i]);
    let lambdas: Vec<f64> = truth.iter().map(|t| t.0).collect();
    let methods = [Method::Static, Method::Dynamic, Method::MinimumResidual];
    let points = sensor_removal_study(
        &sys.k,
        &sys.m,
        mesh,
        &sys.dofs,
        &lambdas,
        x.as_ref(),
        &start,
        &removal,
        &methods,
        None,
        1,
    )
    .unwrap();
    let (kd, md) = (dense(&sys.k), dense(&sys.m));
    let minv = solve(&md, &Mat::identity(n, n));
    let mut nodes = start.clone();
    let mut checked = 0;
    for step in 0..=removal.len() {
        if step > 0 {
            nodes.retain(|v| *v != removal[step - 1]);
        }
        let layout = SensorLayout::triaxial(mesh, &sys.dofs, &nodes).unwrap();
        let a = layout.measured_dofs().unwrap();
        let o: Vec<usize> = (0..n).filter(|d| !a.contains(d)).collect();
        let pick = |m: &Mat<f64>, rows: &[usize], cols: &[usize]| {
            Mat::from_fn(rows.len(), cols.len(), |i, j| m[(rows[i], cols[j])])
        };
        let all: Vec<usize> = (0..n).collect();
        for method in methods {
            for mode in 0..2 {
                let lam = match method {
                    Method::Static => 0.0,
                    _ => lambdas[mode],
                };
                let z = Mat::from_fn(n, n, |i, j| kd[(i, j)] - lam * md[(i, j)]);
                let xa = Mat::from_fn(a.len(), 1, |i, _| x[(a[i], mode)]);
                let xo = match method {
                    Method::MinimumResidual => {
                        let zo = pick(&z, &all, &o);
                        let za = pick(&z, &all, &a);
                        let lhs = zo.transpose() * &minv * &zo;
                        let rhs = -(zo.transpose() * &minv * &za * &xa);
                        solve(&lhs, &rhs)
                    }
                    _ => {
                        let rhs = -(pick(&z, &o, &a) * &xa);
                        solve(&pick(&z, &o, &o), &rhs)
                    }
                };
                let mut xe = Mat::<f64>::zeros(n, 1);
                for (i, d) in a.iter().enumerate() {
                    xe[(*d, 0)] = xa[(i, 0)];
                }
                for (i, d) in o.iter().enumerate() {
                    xe[(*d, 0)] = xo[(i, 0)];
                }
                let zl = Mat::from_fn(n, n, |i, j| kd[(i, j)] - lambdas[mode] * md[(i, j)]);
                let r = &zl * &xe;
                let num = (r.transpose() * &minv * &r)[(0, 0)];
                let den = (xe.transpose() * &md * &xe)[(0, 0)];
                let rho = (num / den).sqrt();
                let p = points
                    .iter()
                    .find(|p| p.nodes == nodes.len() && p.method == Some(method) && p.mode == mode)
                    .unwrap_or_else(|| {
                        panic!("{method} {} nodes mode {mode} missing", nodes.len())
                    });
                assert!(
                    (p.rho_m / rho - 1.0).abs() < 1e-10,
                    "{method} {} nodes mode {mode}: study {} dense {rho}",
                    nodes.len(),
                    p.rho_m
                );
                checked += 1;
            }
        }
    }
    assert_eq!(checked, 5 * 3 * 2);
}
