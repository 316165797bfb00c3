//! The verified eigensolver: the 20 lowest modes of the clamped steel block of the peer
//! comparison (`benches/peers`, 2 x 1 x 1 m, `2n x n x n` cells), hex8 and tet10, from the
//! assembled `K` and `M` (ordering, symbolic analysis, factorizations, Lanczos, Sturm check).
//!
//! Sizes: `FEMU_BENCH_EIGEN=hex8:20,tet10:10` (default; 52,920 DOF each, the peers' 50k case).
//! `hex8:32,tet10:16` gives the 200k case. Run: `cargo bench --bench eigen`.

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use femu::prelude::*;
use femu::sparse::eigen::{EigenOptions, Which, eigs};
use std::time::Duration;

mod common;

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("eigen_lowest20");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(5));
    for (kind, n) in common::cases("FEMU_BENCH_EIGEN", "hex8:20,tet10:10") {
        let (cells, quadratic) = match kind.as_str() {
            "hex8" => (BoxCells::Hex, false),
            "hex20" => (BoxCells::Hex, true),
            "tet10" => (BoxCells::Tet6, true),
            other => panic!("FEMU_BENCH_EIGEN: unknown kind {other}"),
        };
        let spec = BoxSpec::new([2.0, 1.0, 1.0], [2 * n, n, n], cells, quadratic);
        let model = common::clamped(spec);
        let sys = model.assemble(MassKind::Consistent).unwrap();
        let id = BenchmarkId::new(kind.clone(), format!("{}dof", sys.k.rows()));
        group.bench_function(id, |b| {
            b.iter(|| {
                let modes =
                    eigs(&sys.k, &sys.m, Which::Lowest(20), &EigenOptions::default()).unwrap();
                assert!(modes.sturm.verified());
                modes.values.len()
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
