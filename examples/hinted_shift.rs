//! What the hinted lowest-mode shift saves in an updating run: the 16 lowest modes of a free-free
//! steel block of 52,416 DOF (ten stiffness regions, region r3 softened step by step), solved by a
//! fresh `UpdateModel` (no hint: the probe, then a shift moved to half the first elastic
//! eigenvalue, three factorizations) and by one that carries the last solve's shift (two), one
//! after the other, with the eigenvalues compared.
//!
//! Run: `cargo run --release --example hinted_shift`.

use femu::prelude::*;
use std::time::Instant;
fn main() {
    let spec = BoxSpec::new([0.48, 0.16, 0.06], [64, 20, 12], BoxCells::Hex, false);
    let mut mesh = box_mesh(&spec).unwrap();
    let names = add_slab_sets(&mut mesh, 0, 10, "r").unwrap();
    let mut model = Model::new(mesh).unwrap();
    model.set_material(None, Material::steel()).unwrap();
    let sets: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
    let mut up =
        UpdateModel::from_element_sets(&model, &sets, MassKind::Consistent, Corrections::Stiffness)
            .unwrap();
    up.symbolic().unwrap();
    let _ = model_modes(&mut up, 16, &Default::default()).unwrap();
    for i in 1..4 {
        let mut th = vec![0.0; 10];
        th[3] = -0.1 * i as f64;
        let mut fresh = UpdateModel::from_element_sets(
            &model,
            &sets,
            MassKind::Consistent,
            Corrections::Stiffness,
        )
        .unwrap();
        fresh.set_theta(&th).unwrap();
        fresh.symbolic().unwrap();
        let t = Instant::now();
        let a = model_modes(&mut fresh, 16, &Default::default()).unwrap();
        let ta = t.elapsed().as_secs_f64();
        up.set_theta(&th).unwrap();
        let t = Instant::now();
        let b = model_modes(&mut up, 16, &Default::default()).unwrap();
        let tb = t.elapsed().as_secs_f64();
        let dmax = a
            .values
            .iter()
            .zip(&b.values)
            .skip(6)
            .map(|(x, y)| (x / y - 1.0).abs())
            .fold(0.0, f64::max);
        println!(
            "theta3 {:.1}: no hint {ta:.2} s, hinted {tb:.2} s, eigenvalues equal to {dmax:.1e}",
            th[3]
        );
    }
}
