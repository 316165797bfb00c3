//! Assembly throughput (elements per second) of K and M for hex8, hex20 and tet10 models of about
//! 100k elements, with 1 and 2 rayon threads side by side. The pattern is built once outside the
//! timed loop (it is reused by every later assembly); its cost is a separate benchmark.
//!
//! Run: `cargo bench --bench assembly`.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use femu::prelude::*;
use std::time::Duration;

mod common;

fn assembly(c: &mut Criterion) {
    let cases = [
        (
            "hex8",
            BoxSpec::new([1.0, 1.0, 0.8], [50, 50, 40], BoxCells::Hex, false),
        ),
        (
            "tet10",
            BoxSpec::new([1.0, 1.0, 1.0], [26, 26, 25], BoxCells::Tet6, true),
        ),
        (
            "hex20",
            BoxSpec::new([1.0, 1.0, 1.0], [47, 47, 46], BoxCells::Hex, true),
        ),
    ];
    let pools: Vec<_> = [1, 2]
        .iter()
        .map(|t| {
            (
                *t,
                rayon::ThreadPoolBuilder::new()
                    .num_threads(*t)
                    .build()
                    .unwrap(),
            )
        })
        .collect();
    let mut group = c.benchmark_group("assembly");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(20));
    for (name, spec) in cases {
        let model = common::clamped(spec);
        let asm = Assembler::new(&model).unwrap();
        let ne = model.mesh().element_count() as u64;
        group.throughput(Throughput::Elements(ne));
        for (threads, pool) in &pools {
            let id = BenchmarkId::new(
                format!("{name}/{}dof", asm.dofs().free_count()),
                format!("{threads}thr"),
            );
            group.bench_function(id, |b| {
                b.iter(|| pool.install(|| asm.assemble(&model, MassKind::Consistent).unwrap()))
            });
        }
        let id = BenchmarkId::new(
            format!("{name}/{}dof", asm.dofs().free_count()),
            "pattern+colouring",
        );
        group.bench_function(id, |b| b.iter(|| Assembler::new(&model).unwrap()));
    }
    group.finish();
}

/// The cost of multipoint constraints: the hex8 block of `assembly` (100k elements) with its free
/// end face (2,091 nodes, 2,000 elements) rigidly linked to a reference node beyond it, against
/// the same block without the link, 2 threads; and the pattern with the link.
fn linked(c: &mut Criterion) {
    let spec = BoxSpec::new([1.0, 1.0, 0.8], [50, 50, 40], BoxCells::Hex, false);
    let plain = common::clamped(spec);
    let mut mesh = plain.mesh().clone();
    mesh.add_node(u64::MAX - 1, [1.1, 0.5, 0.4]).unwrap();
    let mut model = Model::new(mesh.clone()).unwrap();
    model.set_material(None, Material::steel()).unwrap();
    model.fix_set("xmin", &[0, 1, 2]).unwrap();
    let top: Vec<u64> = mesh
        .node_set("xmax")
        .unwrap()
        .iter()
        .map(|i| mesh.node_id(*i))
        .collect();
    model
        .add_rigid_link(u64::MAX - 1, &top, &[0, 1, 2], "end")
        .unwrap();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let mut group = c.benchmark_group("assembly_linked");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(10));
    group.throughput(Throughput::Elements(model.mesh().element_count() as u64));
    for (name, m) in [("plain", &plain), ("rigid end face", &model)] {
        let asm = Assembler::new(m).unwrap();
        group.bench_function(BenchmarkId::new("hex8 100k elements, 2thr", name), |b| {
            b.iter(|| pool.install(|| asm.assemble(m, MassKind::Consistent).unwrap()))
        });
        group.bench_function(BenchmarkId::new("pattern+colouring", name), |b| {
            b.iter(|| Assembler::new(m).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, assembly, linked);
criterion_main!(benches);
