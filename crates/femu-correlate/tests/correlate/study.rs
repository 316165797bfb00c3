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
