//! Sensor layouts and bad input: every mistake is an error that names the offender.

use super::common::*;
use faer::{Mat, MatRef};
use femu_correlate::{
    CorrelateError, Estimator, MassSolver, Sensor, SensorLayout, StiffnessSolver, TestModes,
};
use femu_fem::prelude::*;

#[test]
fn sensor_layout_maps_directions_to_dofs() {
    let model = bar([4, 1, 1], true);
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let mesh = model.mesh();
    let tip = mesh.node_set("xmax").unwrap()[0];
    let tip_id = mesh.node_id(tip);
    let d = [1.0, 2.0, -2.0]; // |d| = 3
    let layout = SensorLayout::new(
        mesh,
        &sys.dofs,
        vec![Sensor::new(tip_id, d), Sensor::axis(tip_id, 2)],
    )
    .unwrap();
    assert_eq!(layout.len(), 2);
    assert_eq!(
        layout.sensors()[0].direction,
        [1.0 / 3.0, 2.0 / 3.0, -2.0 / 3.0]
    );
    let n = sys.dofs.free_count();
    let u: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
    let f = sys.dofs.node_dofs(tip).map(|f| f.unwrap());
    let hand = (u[f[0]] + 2.0 * u[f[1]] - 2.0 * u[f[2]]) / 3.0;
    let r = layout.measure(&u).unwrap();
    assert!((r[0] - hand).abs() < 1e-15 && r[1] == u[f[2]]);
    // C as a sparse matrix gives the same readings
    let c = layout.matrix();
    let mut y = vec![0.0; 2];
    femu_sparse::csc::mul_vec(&c, &u, &mut y).unwrap();
    assert!((y[0] - hand).abs() < 1e-15);
    assert_eq!(layout.measured_dofs(), None);
    // triaxial on a root node skips nothing only where free; the full layout is the identity
    let full = SensorLayout::full(mesh, &sys.dofs);
    assert_eq!(full.len(), n);
    assert_eq!(full.measured_dofs().unwrap(), (0..n).collect::<Vec<_>>());
    let tri = SensorLayout::triaxial(mesh, &sys.dofs, &[tip_id]).unwrap();
    assert_eq!(tri.measured_dofs().unwrap(), f.to_vec());
    let xm = MatRef::from_column_major_slice(&u, n, 1);
    assert_eq!(tri.measure_all(xm).unwrap()[(1, 0)], u[f[1]]);
}

#[test]
fn bad_sensors_are_named() {
    let model = bar([4, 1, 1], true);
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let mesh = model.mesh();
    let root = mesh.node_id(mesh.node_set("xmin").unwrap()[0]);
    let tip = mesh.node_id(mesh.node_set("xmax").unwrap()[0]);
    let layout = |s: Vec<Sensor>| SensorLayout::new(mesh, &sys.dofs, s).unwrap_err();
    assert_eq!(
        layout(vec![Sensor::axis(tip, 0), Sensor::axis(999_999, 1)]),
        CorrelateError::SensorOnMissingNode {
            sensor: 1,
            node: 999_999
        }
    );
    assert_eq!(
        layout(vec![Sensor::axis(root, 1)]),
        CorrelateError::SensorOnConstrainedDof {
            sensor: 0,
            node: root,
            component: 1
        }
    );
    assert!(matches!(
        layout(vec![Sensor::new(tip, [0.0; 3])]),
        CorrelateError::BadDirection { sensor: 0, .. }
    ));
    assert!(matches!(
        layout(vec![Sensor::new(tip, [f64::NAN, 0.0, 1.0])]),
        CorrelateError::BadDirection { .. }
    ));
    assert_eq!(
        layout(vec![
            Sensor::axis(tip, 0),
            Sensor::new(tip, [-2.0, 0.0, 0.0])
        ]),
        CorrelateError::DuplicateSensor {
            first: 0,
            second: 1,
            node: tip
        }
    );
    assert!(SensorLayout::triaxial(mesh, &sys.dofs, &[42_424_242]).is_err());
    let u = vec![0.0; 5];
    assert!(SensorLayout::full(mesh, &sys.dofs).measure(&u).is_err());
    // the error message names the node, the direction and the sensor by its 1-based position
    let msg = layout(vec![Sensor::axis(root, 2)]).to_string();
    assert_eq!(
        msg,
        format!(
            "sensor 1 on node {root} measures along z, which the model clamps (its motion there is zero by the boundary conditions; is the node id right?)"
        )
    );
}

#[test]
fn bad_test_modes_and_estimator_inputs() {
    let shapes = Mat::from_fn(3, 2, |i, j| (i + j) as f64 + 1.0);
    assert!(TestModes::new(vec![10.0, 20.0], Some(vec![0.01, 0.02]), shapes.clone()).is_ok());
    assert!(matches!(
        TestModes::new(vec![10.0], None, shapes.clone()),
        Err(CorrelateError::DimensionMismatch { .. })
    ));
    assert!(matches!(
        TestModes::new(vec![10.0, f64::NAN], None, shapes.clone()),
        Err(CorrelateError::NonFinite { index: 1, .. })
    ));
    assert!(matches!(
        TestModes::new(vec![10.0, -3.0], None, shapes.clone()),
        Err(CorrelateError::Invalid { .. })
    ));
    assert!(TestModes::new(vec![10.0, 20.0], Some(vec![0.01, 1.5]), shapes.clone()).is_err());
    let zero = Mat::from_fn(3, 2, |i, j| if j == 1 { 0.0 } else { i as f64 + 1.0 });
    assert_eq!(
        TestModes::new(vec![10.0, 20.0], None, zero).unwrap_err(),
        CorrelateError::ZeroVector {
            what: "test mode shape",
            index: 1
        }
    );
    let mut nan_shape = shapes.clone();
    nan_shape[(2, 1)] = f64::INFINITY;
    assert!(matches!(
        TestModes::new(vec![10.0, 20.0], None, nan_shape),
        Err(CorrelateError::NonFinite { index: 5, .. })
    ));

    let model = bar([4, 1, 1], true);
    let sys = model.assemble(MassKind::Lumped).unwrap();
    let n = sys.k.rows();
    let est = Estimator::new(&sys.k, &sys.m).unwrap();
    let x = vec![1.0; n];
    let xm = MatRef::from_column_major_slice(&x, n, 1);
    assert!(est.residual_norms(&[f64::NAN], xm).is_err());
    assert!(est.residual_norms(&[1.0, 2.0], xm).is_err());
    let short = vec![1.0; n - 1];
    assert!(
        est.residual_norms(&[1.0], MatRef::from_column_major_slice(&short, n - 1, 1))
            .is_err()
    );
    let z = vec![0.0; n];
    assert!(matches!(
        est.residual_norms(&[1.0], MatRef::from_column_major_slice(&z, n, 1)),
        Err(CorrelateError::ZeroVector { .. })
    ));
    let mut xn = x.clone();
    xn[3] = f64::NAN;
    assert!(matches!(
        est.residual_norms(&[1.0], MatRef::from_column_major_slice(&xn, n, 1)),
        Err(CorrelateError::NonFinite { index: 3, .. })
    ));
    // A mass with a negative diagonal entry is not positive definite.
    let mut bad_m = sys.m.clone();
    bad_m.data_mut()[4] = -1.0;
    assert!(matches!(
        MassSolver::new(&bad_m),
        Err(CorrelateError::Sparse(
            femu_sparse::SparseError::NotPositiveDefinite { index: 4, .. }
        ))
    ));
    // An indefinite consistent mass breaks CG or Cholesky with an error, not a NaN.
    let sysc = model.assemble(MassKind::Consistent).unwrap();
    // Off-diagonal entries x10: D^-1 M of a hex8 mass has eigenvalues in [1/8, 27/8], so the
    // scaled matrix has eigenvalues down to 1 + 10 (1/8 - 1) < 0.
    let mut ind = sysc.m.clone();
    let ptr = ind.indptr().raw_storage().to_vec();
    let rows = ind.indices().to_vec();
    for c in 0..n {
        for p in ptr[c]..ptr[c + 1] {
            if rows[p] != c {
                ind.data_mut()[p] *= 10.0;
            }
        }
    }
    assert!(MassSolver::cholesky(&ind).is_err());
    let pcg = MassSolver::new(&ind).unwrap();
    let r = Mat::from_fn(n, 1, |i, _| (i as f64).cos());
    assert!(pcg.solve(r.as_ref()).is_err());
    // An indefinite K is refused by the stiffness solver.
    let mut kneg = sysc.k.clone();
    for v in kneg.data_mut() {
        *v = -*v;
    }
    assert!(StiffnessSolver::new(&kneg, &sysc.m).is_err());
    // lambda_id = 0 makes the inertia law empty
    let lumped = MassSolver::new(&sys.m).unwrap();
    assert!(femu_correlate::residues::eil_residuals(&sys.k, &lumped, &[0.0], xm).is_err());
}

/// A massless DOF (a zero row of a positive semi-definite `M`: a lumped beam's rotation, a
/// CBAR's torsion under Nastran's coupled mass) weighs its residual by the smallest positive
/// diagonal entry, the residual metric's rule: by hand, `M = [[2, 1, 0], [1, 2, 0], [0, 0, 0]]`
/// (CG) gives `M^-1 (1, 0, 4) = (2/3, -1/3, 4/2)`, and the diagonal `diag(3, 0, 5)` gives
/// `(3, 1, 5) -> (1, 1/3, 1)`. A zero diagonal entry whose row is not zero (not positive
/// semi-definite), and a mass with no positive entry, are refused.
#[test]
fn massless_dofs_take_the_smallest_mass() {
    use femu_sparse::csc::from_entries;
    let m = from_entries(
        3,
        3,
        &[
            (0, 0, 2.0),
            (0, 1, 1.0),
            (1, 0, 1.0),
            (1, 1, 2.0),
            (2, 2, 0.0),
        ],
    );
    let (x, _) = MassSolver::new(&m)
        .unwrap()
        .solve(MatRef::from_column_major_slice(&[1.0, 0.0, 4.0], 3, 1))
        .unwrap();
    for (got, want) in x.col(0).iter().zip([2.0 / 3.0, -1.0 / 3.0, 2.0]) {
        assert!((got - want).abs() < 1e-9, "{got} {want}");
    }
    let d = from_entries(3, 3, &[(0, 0, 3.0), (1, 1, 0.0), (2, 2, 5.0)]);
    let (x, _) = MassSolver::new(&d)
        .unwrap()
        .solve(MatRef::from_column_major_slice(&[3.0, 1.0, 5.0], 3, 1))
        .unwrap();
    for (got, want) in x.col(0).iter().zip([1.0, 1.0 / 3.0, 1.0]) {
        assert!((got - want).abs() < 1e-15, "{got} {want}");
    }
    assert!(MassSolver::cholesky(&m).is_err());
    let coupled = from_entries(2, 2, &[(0, 0, 0.0), (0, 1, 1.0), (1, 0, 1.0), (1, 1, 2.0)]);
    assert!(matches!(
        MassSolver::new(&coupled),
        Err(CorrelateError::Sparse(
            femu_sparse::SparseError::NotPositiveDefinite { index: 0, .. }
        ))
    ));
    let none = from_entries(2, 2, &[(0, 0, 0.0), (1, 1, 0.0)]);
    assert!(MassSolver::new(&none).is_err());
}
