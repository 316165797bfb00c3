//! The paper's claim, measured: the a priori estimator `rho_M` for 4 test modes against
//! extracting those 4 modes with femu's eigensolver, on one clamped hex8 block, side by side in
//! one run.
//!
//! - `eigs_lowest4`: `Pencil::new` (ordering, symbolic analysis) + `solve(Lowest(4))`, the cheapest
//!   eigen extraction femu offers (factorizations, Lanczos, Sturm check).
//! - `rho_m_consistent`: `Estimator::new` + `residual_norms` for 4 vectors with the consistent
//!   mass (Jacobi-preconditioned CG for `M^-1`).
//! - `rho_m_lumped`: the same with the lumped (diagonal) mass.
//! - `rho_m_cholesky`: the consistent mass through a sparse Cholesky of `M` instead of CG.
//!
//! Size: `FEMU_BENCH_CELLS=nx,ny,nz` (default `24,24,24`, 46,800 DOF; `40,40,40` gives 201,720 DOF,
//! the 200k). Run: `FEMU_BENCH_CELLS=40,40,40 cargo bench --bench estimators`.

use criterion::{Criterion, criterion_group, criterion_main};
use faer::Mat;
use femu::correlate::{Estimator, MassSolver};
use femu::prelude::*;
use femu::sparse::eigen::{EigenOptions, Pencil, Which};
use femu::sparse::ordering::Ordering;
use std::time::Duration;

mod common;

/// Smooth full-length "test" shapes: products of sines of the coordinates, one direction each.
fn test_shapes(model: &Model, dofs: &DofMap) -> Mat<f64> {
    let coords = model.mesh().coords();
    Mat::from_fn(dofs.free_count(), 4, |f, j| {
        let full = dofs.full_of_free(f);
        let p = coords[full / 3];
        let s = (std::f64::consts::PI * p[0] * (j + 1) as f64 / 2.0).sin() * (1.0 + 0.3 * p[1]);
        if full % 3 == (j + 2) % 3 {
            s
        } else {
            0.1 * s * p[2]
        }
    })
}

fn bench(c: &mut Criterion) {
    let n = common::cells([24, 24, 24]);
    let spec = BoxSpec::new([1.0, 1.0, 1.0], n, BoxCells::Hex, false);
    let model = common::clamped(spec);
    let cons = model.assemble(MassKind::Consistent).unwrap();
    let lump = model.assemble(MassKind::Lumped).unwrap();
    let dofs = cons.dofs.free_count();
    let x = test_shapes(&model, &cons.dofs);
    // identified eigenvalues near the model's lowest (their values do not change the cost)
    let lambdas = [4.0e6, 1.0e7, 2.0e7, 3.0e7];

    // One untimed pass of each for the record: iterations, accuracy, the eigen run's shape.
    let est = Estimator::new(&cons.k, &cons.m).unwrap();
    let (norms, report) = est.residual_norms(&lambdas, x.as_ref()).unwrap();
    let chol =
        Estimator::with_mass_solver(&cons.k, &cons.m, MassSolver::cholesky(&cons.m).unwrap())
            .unwrap();
    let (exact, _) = chol.residual_norms(&lambdas, x.as_ref()).unwrap();
    let worst = norms
        .iter()
        .zip(&exact)
        .map(|(a, b)| (a.rho_m / b.rho_m - 1.0).abs())
        .fold(0.0, f64::max);
    eprintln!(
        "{dofs} DOF: PCG {} iterations (residual {:.1e}), rho_M vs Cholesky of M: {worst:.1e} relative",
        report.iterations, report.residual
    );

    let mut group = c.benchmark_group(format!("estimator_vs_eigen/{dofs}dof"));
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(5));
    group.bench_function("eigs_lowest4", |b| {
        b.iter(|| {
            let pencil = Pencil::new(&cons.k, &cons.m, Ordering::NestedDissection).unwrap();
            let modes = pencil
                .solve(Which::Lowest(4), &EigenOptions::default())
                .unwrap();
            assert!(modes.sturm.verified());
            modes.values.len()
        })
    });
    group.bench_function("rho_m_consistent", |b| {
        b.iter(|| {
            let est = Estimator::new(&cons.k, &cons.m).unwrap();
            est.residual_norms(&lambdas, x.as_ref()).unwrap().0.len()
        })
    });
    group.bench_function("rho_m_lumped", |b| {
        b.iter(|| {
            let est = Estimator::new(&lump.k, &lump.m).unwrap();
            est.residual_norms(&lambdas, x.as_ref()).unwrap().0.len()
        })
    });
    group.bench_function("rho_m_cholesky", |b| {
        b.iter(|| {
            let solver = MassSolver::cholesky(&cons.m).unwrap();
            let est = Estimator::with_mass_solver(&cons.k, &cons.m, solver).unwrap();
            est.residual_norms(&lambdas, x.as_ref()).unwrap().0.len()
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
