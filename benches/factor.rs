//! The sparse kernels under the eigensolver, with rates: the numeric `LDL^T` of `K - sigma M`
//! (GFLOP/s from the symbolic flop count, `SymbolicFactor::flops`) by the subtree-parallel
//! multifrontal factorization (`numeric`), by faer's left-looking one (`left-looking`) and for
//! the inertia alone (`inertia`, the Sturm count), a solve of 1, 2 and 4 right-hand
//! sides (`rhs1`, `rhs2`, `rhs4`: the eigensolver's block sizes; docs/SCALING.md, "Block size and
//! the count of solved vectors"), the product `M X` for 1, 4 and 20 vectors (`sym_mul_mat`,
//! bytes of `M` read per second; docs/SCALING.md, "Sparse products by blocks of known width"),
//! and faer's dense GEMM on one and on all threads (the limit
//! the factorization's rate is compared with, measured in the same run).
//!
//! Models: the free-free plate and the clamped block of the peer comparison
//! (`examples/peer_modes.rs`): `FEMU_BENCH_FACTOR=plate:16,hex8:20` (default; 47,628 and 52,920
//! DOF), `plate:33,hex8:32` for the 200k cases. Criterion's "elem/s" are flop/s for the
//! factorization and the GEMM, and right-hand sides per second for the solve.
//!
//! Run: `cargo bench --bench factor`; `bash benches/baseline.sh` compares with the committed
//! baseline.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use femu::prelude::*;
use femu::sparse::cholesky::Factorization;
use femu::sparse::eigen::Pencil;
use femu::sparse::faer::{self, Mat, Par};
use femu::sparse::ordering::Ordering;
use std::time::Duration;

mod common;

fn model(kind: &str, n: usize) -> Model {
    if kind == "plate" {
        let spec = BoxSpec::new([1.0, 0.6, 0.02], [5 * n, 3 * n, 3], BoxCells::Hex, false);
        let mut model = Model::new(box_mesh(&spec).unwrap()).unwrap();
        model.set_material(None, Material::steel()).unwrap();
        return model;
    }
    let quadratic = match kind {
        "hex8" => false,
        "hex20" => true,
        other => panic!("FEMU_BENCH_FACTOR: unknown kind {other} (plate, hex8, hex20)"),
    };
    common::clamped(BoxSpec::new(
        [2.0, 1.0, 1.0],
        [2 * n, n, n],
        BoxCells::Hex,
        quadratic,
    ))
}

fn bench(c: &mut Criterion) {
    let mut factor = c.benchmark_group("ldlt");
    factor
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(5));
    let mut systems = Vec::new();
    for (kind, n) in common::cases("FEMU_BENCH_FACTOR", "plate:16,hex8:20") {
        let sys = model(&kind, n).assemble(MassKind::Consistent).unwrap();
        let pencil = Pencil::new(&sys.k, &sys.m, Ordering::NestedDissection).unwrap();
        // K - sigma M at the peers' shift, 10 Hz below zero: definite, as the eigensolver's
        let sigma = -(2.0 * std::f64::consts::PI * 10.0_f64).powi(2);
        let symbolic = pencil.symbolic();
        let id = format!("{kind}-{}dof", sys.k.rows());
        println!(
            "{id}: factor {} entries, {:.3e} flop",
            symbolic.factor_len(),
            symbolic.flops()
        );
        factor.throughput(Throughput::Elements(symbolic.flops() as u64));
        factor.bench_function(BenchmarkId::new("numeric", &id), |b| {
            b.iter(|| pencil.factor_shifted(sigma).unwrap())
        });
        // faer's left-looking factorization, which the subtree-parallel one replaced, and the
        // inertia alone (a Sturm count: no factor kept)
        let values = pencil.shifted_values(sigma);
        factor.bench_function(BenchmarkId::new("left-looking", &id), |b| {
            b.iter(|| symbolic.ldlt_left_looking(&sys.k, &values, "A").unwrap())
        });
        factor.bench_function(BenchmarkId::new("inertia", &id), |b| {
            b.iter(|| pencil.count_below(sigma).unwrap())
        });
        systems.push((id, pencil.factor_shifted(sigma).unwrap(), sys.m.clone()));
    }
    factor.finish();

    let mut solve = c.benchmark_group("solve");
    solve
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));
    for (id, f, m) in &systems {
        let n = m.rows();
        for k in [1, 2, 4] {
            let mut x = Mat::<f64>::from_fn(n, k, |i, j| ((i * 7 + j * 13) % 17) as f64 - 8.0);
            solve.throughput(Throughput::Elements(k as u64));
            solve.bench_function(BenchmarkId::new(format!("rhs{k}"), id), |b| {
                b.iter(|| f.solve_in_place(x.as_mut()))
            });
        }
    }
    solve.finish();

    // `M X` for the blocks the eigensolver multiplies (its block of 4, the 20 Ritz vectors);
    // "B/s" are the bytes of `M`'s values and row indices read per product
    let mut product = c.benchmark_group("sym_mul_mat");
    product
        .sample_size(20)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2));
    for (id, _, m) in &systems {
        let n = m.rows();
        let bytes = (m.nnz() * (size_of::<f64>() + size_of::<usize>())) as u64;
        for k in [1, 4, 20] {
            let x = Mat::<f64>::from_fn(n, k, |i, j| ((i * 7 + j * 13) % 17) as f64 - 8.0);
            let mut y = Mat::<f64>::zeros(n, k);
            product.throughput(Throughput::Bytes(bytes * k.div_ceil(8) as u64));
            product.bench_function(BenchmarkId::new(format!("cols{k}"), id), |b| {
                b.iter(|| femu::sparse::csc::sym_mul_mat_into(m, x.as_ref(), y.as_mut()).unwrap())
            });
        }
    }
    product.finish();

    let mut gemm = c.benchmark_group("gemm");
    gemm.sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));
    let n = 1536;
    let a = Mat::<f64>::from_fn(n, n, |i, j| ((i * 3 + j * 5) % 11) as f64);
    let bm = Mat::<f64>::from_fn(n, n, |i, j| ((i * 7 + j * 2) % 13) as f64);
    let mut out = Mat::<f64>::zeros(n, n);
    gemm.throughput(Throughput::Elements(2 * (n as u64).pow(3)));
    for (name, par) in [("one-thread", Par::Seq), ("all-threads", Par::rayon(0))] {
        gemm.bench_function(BenchmarkId::new(name, format!("{n}")), |b| {
            b.iter(|| {
                faer::linalg::matmul::matmul(
                    out.as_mut(),
                    faer::Accum::Replace,
                    a.as_ref(),
                    bm.as_ref(),
                    1.0,
                    par,
                )
            })
        });
    }
    gemm.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
