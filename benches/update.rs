//! One updating iteration of SB-EBE and of inverse eigensensitivity, side by side, on a clamped
//! steel block in 10 stiffness regions (default 64 x 20 x 12 hex8 cells: 52,416 DOF), with the
//! test simulated from the block with region 3 30 % softer: its 4 lowest modes at 30 sensors (15
//! top-surface nodes, y and z).
//!
//! A run with `max_iterations = 1` contains, for SB-EBE, the starting expansion with projected
//! columns and one trial (each an `LDL^T` of `Z = K - lambda M` per mode in the sensor space, on
//! one symbolic analysis of `K`'s pattern; docs/MATH.md, "Projected sensitivities in the sensor
//! space"); for inverse eigensensitivity, the starting eigen solve and one trial (2 Sturm-checked
//! solves of 14 modes on the reused symbolic analysis). Measured on 2 cores, one after the other,
//! at an earlier build: SB-EBE 8.1 + 8.4 s, inverse eigensensitivity 9.2 + 8.8 s (start +
//! iteration); with the saddle-point systems SB-EBE took 41 + 79 s. At a later build, whose
//! eigensolver is faster: SB-EBE 3.53 s to start, then 3.68 s for an iteration of one trial and
//! 13.3 s, 41.4 s for the next two (near convergence the sensor-space Gram matrix lost its
//! definiteness and modes went to the saddle point); inverse eigensensitivity 2.56 s, then
//! 2.90 s and 2.71 s. At this build (the shape from the QR of the scaled `Z^-1 E` with one solve,
//! the modes two at a time, a forward solve that skips what the sensors' unit columns do not
//! reach; `FEMU_BENCH_ITERATIONS=4`, two runs): SB-EBE 2.59 and 2.62 s to start, then 2.57-2.79 s
//! for each of three iterations of one trial, and 33-35 s for a fourth whose test eigenvalues
//! equal the model's to round-off (the saddle point again, peak 2.1 GB); inverse
//! eigensensitivity 2.75 and 2.68 s, then 2.52-3.03 s for iterations of one trial. Criterion's runs of the start and one iteration:
//! SB-EBE 5.68 s, inverse eigensensitivity 5.82 s.
//!
//! `cargo bench --bench update` (`FEMU_BENCH_CELLS=nx,ny,nz` to change the size;
//! `FEMU_BENCH_ITERATIONS=3` instead runs each method once for up to 3 iterations and prints the
//! seconds of each, the figures above)

mod common;

use criterion::{Criterion, criterion_group, criterion_main};
use femu::prelude::*;
use std::time::Duration;

fn setup() -> (Model, SensorLayout, TestModes, Vec<String>) {
    let [nx, ny, nz] = common::cells([64, 20, 12]);
    let spec = BoxSpec::new([0.48, 0.16, 0.06], [nx, ny, nz], BoxCells::Hex, false);
    let mut mesh = box_mesh(&spec).unwrap();
    let names = add_slab_sets(&mut mesh, 0, 10, "r").unwrap();
    let model = common::clamped_mesh(mesh);
    let set_refs: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
    let mut truth = UpdateModel::from_element_sets(
        &model,
        &set_refs,
        MassKind::Consistent,
        Corrections::Stiffness,
    )
    .unwrap();
    let mut th = vec![0.0; 10];
    th[3] = -0.3;
    truth.set_theta(&th).unwrap();
    let modes = model_modes(&mut truth, 4, &Default::default()).unwrap();
    let mesh = model.mesh();
    let sensors = femu::correlate::placement::grid_nodes(mesh, "zmax", [5, 3])
        .unwrap()
        .into_iter()
        .flat_map(|id| [Sensor::axis(id, 1), Sensor::axis(id, 2)])
        .collect();
    let layout = SensorLayout::new(mesh, &truth.matrices().dofs, sensors).unwrap();
    let y = layout.measure_all(modes.shapes.as_ref()).unwrap();
    let test = TestModes::new(modes.frequencies_hz(), None, y).unwrap();
    println!(
        "update benchmark: {} DOF, 10 stiffness regions, 4 test modes at 30 sensors",
        truth.matrices().dofs.free_count()
    );
    (model, layout, test, names)
}

/// Each method once, for up to `iterations`, printing the seconds of the start and of each
/// iteration (from the history's `seconds`).
fn timeline(
    model: &Model,
    sets: &[&str],
    layout: &SensorLayout,
    test: &TestModes,
    iterations: usize,
) {
    let update = UpdateOptions {
        max_iterations: iterations,
        ..Default::default()
    };
    let fresh = || {
        UpdateModel::from_element_sets(model, sets, MassKind::Consistent, Corrections::Stiffness)
            .unwrap()
    };
    let print = |name: &str, r: &UpdateResult| {
        let each = |f: &dyn Fn(&femu::update::Iteration) -> String| {
            r.history.iter().map(f).collect::<Vec<_>>().join(" ")
        };
        println!(
            "{name}: seconds (start, iterations) {}",
            each(&|h| format!("{:.2}", h.seconds))
        );
        println!(
            "{name}: objective {}",
            each(&|h| format!("{:.6e}", h.objective))
        );
    };
    let opts = SbebeOptions {
        update: update.clone(),
        ..Default::default()
    };
    print(
        "SB-EBE",
        &sb_ebe(&mut fresh(), layout, test, &opts, |_| {}).unwrap(),
    );
    let opts = SensitivityOptions {
        update: UpdateOptions {
            tikhonov: 1e-3,
            ..update
        },
        ..Default::default()
    };
    let r = inverse_eigensensitivity(&mut fresh(), layout, test, &opts, |_| {}).unwrap();
    print("inverse eigensensitivity", &r);
}

fn bench(c: &mut Criterion) {
    let (model, layout, test, names) = setup();
    let sets: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
    if let Some(n) = std::env::var("FEMU_BENCH_ITERATIONS")
        .ok()
        .and_then(|s| s.parse().ok())
    {
        timeline(&model, &sets, &layout, &test, n);
        return;
    }
    let one = UpdateOptions {
        max_iterations: 1,
        ..Default::default()
    };
    let mut g = c.benchmark_group("update");
    g.sample_size(10)
        .measurement_time(Duration::from_secs(1))
        .warm_up_time(Duration::from_millis(1));
    g.bench_function("sb-ebe one iteration", |b| {
        b.iter(|| {
            let mut up = UpdateModel::from_element_sets(
                &model,
                &sets,
                MassKind::Consistent,
                Corrections::Stiffness,
            )
            .unwrap();
            let opts = SbebeOptions {
                update: one.clone(),
                ..Default::default()
            };
            sb_ebe(&mut up, &layout, &test, &opts, |_| {}).unwrap()
        })
    });
    g.bench_function("inverse eigensensitivity one iteration", |b| {
        b.iter(|| {
            let mut up = UpdateModel::from_element_sets(
                &model,
                &sets,
                MassKind::Consistent,
                Corrections::Stiffness,
            )
            .unwrap();
            let opts = SensitivityOptions {
                update: UpdateOptions {
                    tikhonov: 1e-3,
                    ..one.clone()
                },
                ..Default::default()
            };
            inverse_eigensensitivity(&mut up, &layout, &test, &opts, |_| {}).unwrap()
        })
    });
    g.bench_function("setup: assemble and group element matrices", |b| {
        b.iter(|| {
            UpdateModel::from_element_sets(
                &model,
                &sets,
                MassKind::Consistent,
                Corrections::Stiffness,
            )
            .unwrap()
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
