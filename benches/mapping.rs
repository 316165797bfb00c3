//! Mapping test nodes onto large models (issue: 1,000 test nodes onto a 1M-element model with an
//! element search structure, not a scan of all elements per point): building the grids of
//! `femu_fem::locate::Locator`, locating 1,000 points inside elements (inverse isoparametric
//! map) and finding their nearest nodes, on a hex8 box of 1,000,000 elements and a tet10 box of
//! 1,053,696 elements; beside them, a scan of every node for 10 points, the cost the grid avoids.
//!
//! Run: `cargo bench --bench mapping`.

use criterion::{Criterion, criterion_group, criterion_main};
use femu::prelude::*;
use femu_fem::locate::Locator;
use femu_testkit::Rng;
use std::time::Duration;

fn points(n: usize, size: [f64; 3], rng: &mut Rng) -> Vec<[f64; 3]> {
    (0..n)
        .map(|_| std::array::from_fn(|i| size[i] * rng.next_f64()))
        .collect()
}

fn mapping(c: &mut Criterion) {
    let size = [1.0, 0.8, 0.6];
    let cases = [
        (
            "hex8_1M",
            BoxSpec::new(size, [100, 100, 100], BoxCells::Hex, false),
        ),
        (
            "tet10_1M",
            BoxSpec::new(size, [56, 56, 56], BoxCells::Tet6, true),
        ),
    ];
    let mut group = c.benchmark_group("mapping");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(10));
    for (name, spec) in cases {
        let mesh = box_mesh(&spec).unwrap();
        eprintln!(
            "{name}: {} elements, {} nodes",
            mesh.element_count(),
            mesh.node_count()
        );
        let mut rng = Rng(7);
        let pts = points(1000, size, &mut rng);
        group.bench_function(format!("{name}/build_locator"), |b| {
            b.iter(|| Locator::new(&mesh))
        });
        let locator = Locator::new(&mesh);
        group.bench_function(format!("{name}/locate_1000"), |b| {
            b.iter(|| {
                pts.iter()
                    .map(|p| locator.locate(&mesh, *p, 1e-3).expect("inside").distance)
                    .sum::<f64>()
            })
        });
        group.bench_function(format!("{name}/nearest_node_1000"), |b| {
            b.iter(|| {
                pts.iter()
                    .map(|p| locator.nearest_node(&mesh, *p, 0.05).expect("a node").1)
                    .sum::<f64>()
            })
        });
        group.bench_function(format!("{name}/scan_nodes_10"), |b| {
            b.iter(|| {
                pts[..10]
                    .iter()
                    .map(|p| {
                        mesh.coords()
                            .iter()
                            .map(|c| {
                                (c[0] - p[0]).powi(2)
                                    + (c[1] - p[1]).powi(2)
                                    + (c[2] - p[2]).powi(2)
                            })
                            .fold(f64::INFINITY, f64::min)
                    })
                    .sum::<f64>()
            })
        });
    }
    group.finish();
}

criterion_group!(benches, mapping);
criterion_main!(benches);
