//! Shared by the benchmarks: the clamped steel block they time, and its size from the
//! environment.

use femu::prelude::*;

/// A steel box meshed by `spec`, clamped on its `x = 0` face.
#[allow(dead_code)] // not every benchmark uses a plain box
pub fn clamped(spec: BoxSpec) -> Model {
    clamped_mesh(box_mesh(&spec).unwrap())
}

/// A steel model of `mesh` (a box of the generator, with its face sets), clamped at `x = 0`.
pub fn clamped_mesh(mesh: Mesh) -> Model {
    let mut model = Model::new(mesh).unwrap();
    model.set_material(None, Material::steel()).unwrap();
    model.fix_set("xmin", &[0, 1, 2]).unwrap();
    model
}

/// Cells along x, y, z from `FEMU_BENCH_CELLS=nx,ny,nz`, or `default`.
#[allow(dead_code)] // not every benchmark reads the size from the environment
pub fn cells(default: [usize; 3]) -> [usize; 3] {
    std::env::var("FEMU_BENCH_CELLS")
        .ok()
        .and_then(|s| {
            let v: Vec<usize> = s.split(',').filter_map(|t| t.trim().parse().ok()).collect();
            (v.len() == 3).then(|| [v[0], v[1], v[2]])
        })
        .unwrap_or(default)
}

/// Model kinds and sizes `kind:n,kind:n` from the environment variable `var`, or `default`.
#[allow(dead_code)] // not every benchmark takes a list of models
pub fn cases(var: &str, default: &str) -> Vec<(String, usize)> {
    let spec = std::env::var(var).unwrap_or_else(|_| default.into());
    spec.split(',')
        .filter_map(|c| {
            let (kind, n) = c.split_once(':')?;
            Some((kind.trim().to_string(), n.trim().parse().ok()?))
        })
        .collect()
}
