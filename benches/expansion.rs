//! Modal expansion of 4 test modes from 30 sensors (10 triaxial nodes on the top face) against one
//! sparse factorization of the model's `K` (ordering, symbolic analysis and numeric Cholesky),
//! side by side in one run. Each expansion includes its own setup (`Expander::new`: extraction of
//! `K_oo`, `M_oo` and their symbolic analysis). Minimum residual and MDRE-WE go through the sensor
//! space (30 measured DOFs: one `LDL^T` of `Z` per mode and 60-90 solves). `sensor_sweep` is the
//! Figure 1 pattern: static, dynamic, minimum-residual and MDRE-WE expansion of the 4 modes for 7
//! sensor sets (10 down to 4 nodes) from one `SensorSpace` (5 factorizations of `Z` in all).
//!
//! Size: `FEMU_BENCH_CELLS=nx,ny,nz` (default `16,16,16`, 14,688 DOF; `40,40,40` gives 201,720
//! DOF). Run: `cargo bench --bench expansion`.

use criterion::{Criterion, criterion_group, criterion_main};
use femu::correlate::{Expander, SensorLayout, SensorSpace};
use femu::prelude::*;
use femu::sparse::cholesky::SymbolicFactor;
use femu::sparse::faer::Mat;
use femu::sparse::ordering::Ordering;
use std::time::Duration;

mod common;

fn bench(c: &mut Criterion) {
    let n = common::cells([16, 16, 16]);
    let spec = BoxSpec::new([1.0, 1.0, 1.0], n, BoxCells::Hex, false);
    let model = common::clamped(spec);
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let mesh = model.mesh();
    // 10 nodes spread over the top face, away from the clamped edge
    let top: Vec<usize> = mesh
        .node_set("zmax")
        .unwrap()
        .iter()
        .copied()
        .filter(|n| mesh.coords()[*n][0] > 1e-9)
        .collect();
    let nodes: Vec<u64> = (0..10)
        .map(|i| mesh.node_id(top[(i * top.len()) / 10 + top.len() / 20]))
        .collect();
    let layout = SensorLayout::triaxial(mesh, &sys.dofs, &nodes).unwrap();
    assert_eq!(layout.len(), 30);
    let ya = Mat::from_fn(30, 4, |i, j| ((i * (j + 1)) as f64 * 0.37).sin());
    let lambdas = [4.0e6, 1.1e7, 2.3e7, 3.7e7];
    let dofs = sys.k.rows();
    let mut group = c.benchmark_group(format!("expansion/{dofs}dof"));
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(5));
    group.bench_function("factor_k", |b| {
        b.iter(|| {
            let s = SymbolicFactor::new(&sys.k, Ordering::NestedDissection).unwrap();
            s.llt(&sys.k, "K").unwrap();
        })
    });
    group.bench_function("static", |b| {
        b.iter(|| {
            Expander::new(&sys.k, &sys.m, &layout)
                .unwrap()
                .static_(ya.as_ref())
                .unwrap()
        })
    });
    group.bench_function("dynamic", |b| {
        b.iter(|| {
            Expander::new(&sys.k, &sys.m, &layout)
                .unwrap()
                .dynamic(&lambdas, ya.as_ref())
                .unwrap()
        })
    });
    group.bench_function("minimum_residual", |b| {
        b.iter(|| {
            Expander::new(&sys.k, &sys.m, &layout)
                .unwrap()
                .minimum_residual(&lambdas, ya.as_ref())
                .unwrap()
        })
    });
    group.bench_function("mdre_we", |b| {
        b.iter(|| {
            Expander::new(&sys.k, &sys.m, &layout)
                .unwrap()
                .mdre(&lambdas, ya.as_ref(), 1e12, 0.0)
                .unwrap()
        })
    });
    let measured = layout.measured_dofs().unwrap();
    group.bench_function("sensor_sweep", |b| {
        b.iter(|| {
            let mut space = SensorSpace::new(&sys.k, &sys.m, &measured).unwrap();
            space
                .prepare(
                    &[lambdas[0], lambdas[1], lambdas[2], lambdas[3], 0.0],
                    &[0.0],
                )
                .unwrap();
            for nodes in (4..=10).rev() {
                let set = &measured[..3 * nodes];
                let y = ya.as_ref().subrows(0, 3 * nodes);
                space.dynamic(&[0.0; 4], set, y).unwrap();
                space.dynamic(&lambdas, set, y).unwrap();
                space.minimum_residual(&lambdas, set, y).unwrap();
                space.mdre(&lambdas, set, y, 1e12, 0.0).unwrap();
            }
            assert_eq!(space.factorizations(), 5);
            space.fallbacks()
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
