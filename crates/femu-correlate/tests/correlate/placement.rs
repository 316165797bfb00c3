//! Effective Independence against brute-force determinants.

use super::common::*;
use faer::Mat;
use femu_correlate::SensorLayout;
use femu_correlate::placement::{effective_independence, efi_addition_order, efi_removal_order};
use femu_fem::prelude::*;

fn det_fisher(phi_s: &Mat<f64>, rows: &[usize]) -> f64 {
    let m = phi_s.ncols();
    let a = Mat::from_fn(m, m, |i, j| {
        rows.iter()
            .map(|r| phi_s[(*r, i)] * phi_s[(*r, j)])
            .sum::<f64>()
    });
    femu_sparse::dense::symmetric_eigen(a.as_ref())
        .unwrap()
        .0
        .iter()
        .product()
}

#[test]
fn efi_matches_brute_force_determinants() {
    let model = bar([6, 2, 1], true);
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let eig = full_eigen(&sys);
    let phi = eig.vectors.as_ref().subcols(0, 4);
    let mesh = model.mesh();
    let nodes: Vec<u64> = mesh
        .node_set("zmax")
        .unwrap()
        .iter()
        .map(|&n| mesh.node_id(n))
        .filter(|id| {
            let i = mesh.node_index(*id).unwrap();
            mesh.coords()[i][0] > 1e-9
        })
        .collect();
    let layout = SensorLayout::triaxial(mesh, &sys.dofs, &nodes).unwrap();
    let phi_s = layout.measure_all(phi).unwrap();
    let all: Vec<usize> = (0..layout.len()).collect();
    // E_i = 1 - det(A - phi_i phi_i^T) / det(A); sum E = m
    let e = effective_independence(phi_s.as_ref()).unwrap();
    assert!((e.iter().sum::<f64>() - 4.0).abs() < 1e-10);
    let d0 = det_fisher(&phi_s, &all);
    for i in [0, 5, 11] {
        let rest: Vec<usize> = all.iter().copied().filter(|r| *r != i).collect();
        assert!((e[i] - (1.0 - det_fisher(&phi_s, &rest) / d0)).abs() < 1e-9);
    }
    // removal: the first node removed keeps the largest determinant
    let order = efi_removal_order(&layout, phi).unwrap();
    let rows_of = |id: u64| -> Vec<usize> {
        (0..layout.len())
            .filter(|s| layout.sensors()[*s].node == id)
            .collect()
    };
    let best = nodes
        .iter()
        .map(|id| {
            let drop = rows_of(*id);
            let rest: Vec<usize> = all.iter().copied().filter(|r| !drop.contains(r)).collect();
            (*id, det_fisher(&phi_s, &rest))
        })
        .fold((0, f64::NEG_INFINITY), |b, c| if c.1 > b.1 { c } else { b });
    assert_eq!(order[0], best.0);
    // it stops while the remaining sensors can still see 4 independent modes
    let kept: Vec<usize> = all
        .iter()
        .copied()
        .filter(|r| !order.contains(&layout.sensors()[*r].node))
        .collect();
    assert!(kept.len() >= 4 && det_fisher(&phi_s, &kept) > 0.0);
    // addition: the first node added gives the largest det(eps I + V^T V)
    let add = efi_addition_order(&layout, phi).unwrap();
    assert_eq!(add.len(), nodes.len());
    let trace: f64 = phi_s.squared_norm_l2();
    let eps = 1e-10 * trace / 4.0;
    let det_with = |id: &u64| {
        let r = rows_of(*id);
        let a = Mat::from_fn(4, 4, |i, j| {
            (if i == j { eps } else { 0.0 })
                + r.iter()
                    .map(|s| phi_s[(*s, i)] * phi_s[(*s, j)])
                    .sum::<f64>()
        });
        (
            *id,
            femu_sparse::dense::symmetric_eigen(a.as_ref())
                .unwrap()
                .0
                .iter()
                .product::<f64>(),
        )
    };
    let first = nodes
        .iter()
        .map(det_with)
        .fold((0, f64::NEG_INFINITY), |b, c| if c.1 > b.1 { c } else { b });
    // symmetric nodes tie: the node chosen has the largest determinant to round-off, which for
    // these nearly singular 4x4 matrices (one node's 3 readings of 4 modes, regularised by
    // eps = 1e-10 of the trace) is about 1e-16 / 1e-10 = 1e-6 relative
    let chosen = det_with(&add[0]).1;
    assert!(
        (chosen - first.1).abs() <= 1e-6 * first.1.abs(),
        "node {} (det {chosen:e}) against node {} (det {:e})",
        add[0],
        first.0,
        first.1
    );
    // too few sensors for the modes
    let two = SensorLayout::triaxial(mesh, &sys.dofs, &nodes[..1]).unwrap();
    assert!(
        effective_independence(
            two.measure_all(eig.vectors.as_ref().subcols(0, 5))
                .unwrap()
                .as_ref()
        )
        .is_err()
    );
}
