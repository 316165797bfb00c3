//! Assembly throughput (elements per second) of K and M for hex8, hex20 and tet10 models of about
//! 100k elements, with 1 and 2 rayon threads side by side:
//! - `assembly/<kind>/<dofs>/<threads>`: `Assembler::assemble`, new matrices (what a first solve
//!   pays; at 100k hex20 elements it provisions 6.8 GB of fresh memory, which the operating
//!   system's page faults dominate);
//! - `reassembly/...`: `Assembler::assemble_into`, the element work into existing storage (what
//!   every updating step and every later assembly pays);
//! - `kernel/...`: the element kernels alone, `K_e` and the scalar consistent mass of every
//!   element, one thread, nothing scattered.
//!
//! The pattern is built once outside the timed loops (it is reused by every later assembly); its
//! cost is a separate benchmark.
//!
//! Run: `cargo bench --bench assembly` (`cargo bench --bench assembly -- hex20` for one kind).

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use femu::fem::kernel;
use femu::prelude::*;
use std::time::Duration;

mod common;

/// The three models of about 100k elements.
fn cases() -> [(&'static str, BoxSpec); 3] {
    [
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
    ]
}

/// Rayon pools of 1 and 2 threads, with their sizes.
fn pools() -> Vec<(usize, rayon::ThreadPool)> {
    [1, 2]
        .iter()
        .map(|t| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(*t).build();
            (*t, pool.unwrap())
        })
        .collect()
}

/// Ten samples of up to 20 s: a hex20 assembly of 100k elements takes 10-20 s.
fn slow(group: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>) {
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(20));
}

fn assembly(c: &mut Criterion) {
    let pools = pools();
    let mut group = c.benchmark_group("assembly");
    slow(&mut group);
    for (name, spec) in cases() {
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

/// Re-assembly into existing matrices, and the element kernels alone (see the file's doc).
fn reassembly(c: &mut Criterion) {
    let pools = pools();
    let mut group = c.benchmark_group("reassembly");
    slow(&mut group);
    for (name, spec) in cases() {
        let model = common::clamped(spec);
        let asm = Assembler::new(&model).unwrap();
        let mut sys = asm.assemble(&model, MassKind::Consistent).unwrap();
        let ne = model.mesh().element_count();
        group.throughput(Throughput::Elements(ne as u64));
        let dofs = asm.dofs().free_count();
        for (threads, pool) in &pools {
            let id = BenchmarkId::new(format!("{name}/{dofs}dof"), format!("{threads}thr"));
            group.bench_function(id, |b| {
                b.iter(|| pool.install(|| asm.assemble_into(&model, &mut sys).unwrap()))
            });
        }
        drop(sys);
        let mesh = model.mesh();
        let steel = Material::steel();
        let id = BenchmarkId::new(format!("{name}/{dofs}dof"), "kernels 1thr");
        group.bench_function(id, |b| {
            let (mut x, mut ke, mut m) = (Vec::new(), vec![0.0; 3600], vec![0.0; 400]);
            b.iter(|| {
                for e in 0..ne {
                    let kind = mesh.element(e).kind;
                    let nn = kind.num_nodes();
                    mesh.element_coords(e, &mut x);
                    kernel::element_stiffness_for(
                        kind,
                        Default::default(),
                        &x,
                        &steel,
                        &mut ke[..9 * nn * nn],
                    )
                    .unwrap();
                    kernel::scalar_mass(kind, &x, steel.density, &mut m[..nn * nn]).unwrap();
                    std::hint::black_box((&ke, &m));
                }
            })
        });
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

criterion_group!(benches, assembly, reassembly, linked);
criterion_main!(benches);
