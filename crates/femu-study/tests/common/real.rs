//! "Real" structures for the truth tests, built independently of the model a user would update:
//! the same plate geometry on another mesh (finer, or with quadratic elements), one region
//! softer, measured at the model's 15 upper-surface sensor nodes in y and z (the paper's 30
//! readings), with noise. Only the geometry and the sensor coordinates are shared with the model.

#![allow(dead_code)]

use faer::Mat;
use femu_correlate::prelude::*;
use femu_fem::prelude::*;
use femu_update::prelude::*;

/// Regions along x, as element sets `r0`..`r9`.
pub const REGIONS: usize = 10;
/// The plate: 200 x 70 x 10 mm, steel, free-free.
pub const LENGTHS: [f64; 3] = [0.2, 0.07, 0.01];

/// The plate meshed with `divisions` hex cells (hex20 when `quadratic`), regions `r0`..`r9`.
pub fn plate(divisions: [usize; 3], quadratic: bool) -> Model {
    plate_of(divisions, BoxCells::Hex, quadratic)
}

/// The plate meshed with `divisions` cells of the given kind, regions `r0`..`r9`.
pub fn plate_of(divisions: [usize; 3], cells: BoxCells, quadratic: bool) -> Model {
    let mut mesh = box_mesh(&BoxSpec::new(LENGTHS, divisions, cells, quadratic)).unwrap();
    add_slab_sets(&mut mesh, 0, REGIONS, "r").unwrap();
    let mut model = Model::new(mesh).unwrap();
    model.set_material(None, Material::steel()).unwrap();
    model
}

/// `r0`..`r9`.
pub fn regions() -> Vec<String> {
    (0..REGIONS).map(|r| format!("r{r}")).collect()
}

/// The model's sensor nodes: a 5 x 3 grid of the upper surface.
pub fn sensor_nodes(model: &Model) -> Vec<u64> {
    femu_correlate::placement::grid_nodes(model.mesh(), "zmax", [5, 3]).unwrap()
}

/// The node of `mesh` at `x` (the meshes share the sensor positions).
fn node_at(mesh: &Mesh, x: [f64; 3]) -> u64 {
    let (i, d) = (0..mesh.node_count())
        .map(|i| {
            let c = mesh.coords()[i];
            (
                i,
                ((c[0] - x[0]).powi(2) + (c[1] - x[1]).powi(2) + (c[2] - x[2]).powi(2)).sqrt(),
            )
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap();
    assert!(d < 1e-9, "no node of the real mesh at {x:?} ({d})");
    mesh.node_id(i)
}

/// `real` over its regions with the stiffness factors `theta`.
fn with_factors<'a>(real: &'a Model, theta: &[f64]) -> UpdateModel<'a> {
    let names = regions();
    let sets: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
    let mut up =
        UpdateModel::from_element_sets(real, &sets, MassKind::Consistent, Corrections::Stiffness)
            .unwrap();
    up.set_theta(theta).unwrap();
    up
}

/// A test: the first `count` elastic modes of `real` with region stiffness factors `theta`,
/// read at `model`'s sensor nodes in y and z, noise `shape_noise` times each mode's largest
/// reading (uniform, unit variance) and `frequency_noise` relative on the frequencies.
pub fn measure(
    real: &Model,
    theta: &[f64],
    model: &Model,
    count: usize,
    shape_noise: f64,
    frequency_noise: f64,
    seed: u64,
) -> (TestModes, Vec<Sensor>) {
    measure_along(
        real,
        theta,
        model,
        count,
        (shape_noise, frequency_noise),
        seed,
        &[[0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
    )
}

/// As [`measure`], with the sensors of each node along `directions` (unit vectors).
pub fn measure_along(
    real: &Model,
    theta: &[f64],
    model: &Model,
    count: usize,
    (shape_noise, frequency_noise): (f64, f64),
    seed: u64,
    directions: &[[f64; 3]],
) -> (TestModes, Vec<Sensor>) {
    let mut up = with_factors(real, theta);
    let modes = model_modes(&mut up, 6 + count, &Default::default()).unwrap();
    let nodes = sensor_nodes(model);
    let mut real_sensors = Vec::new();
    let mut sensors = Vec::new();
    for id in &nodes {
        let x = model.mesh().coords()[model.mesh().node_index(*id).unwrap()];
        let rid = node_at(real.mesh(), x);
        for d in directions {
            real_sensors.push(Sensor::new(rid, *d));
            sensors.push(Sensor::new(*id, *d));
        }
    }
    let layout = SensorLayout::new(real.mesh(), &up.matrices().dofs, real_sensors).unwrap();
    let shapes = modes.shapes.as_ref().subcols(6, count).to_owned();
    let mut y: Mat<f64> = layout.measure_all(shapes.as_ref()).unwrap();
    femu_correlate::modes::canonical_signs(&mut y);
    let mut rng = femu_testkit::Rng(seed);
    for j in 0..count {
        let peak = y.col(j).iter().fold(0.0_f64, |a, v| a.max(v.abs()));
        for i in 0..y.nrows() {
            y[(i, j)] += shape_noise * peak * 3f64.sqrt() * rng.sym();
        }
    }
    let f: Vec<f64> = modes.frequencies_hz()[6..6 + count]
        .iter()
        .map(|f| f * (1.0 + frequency_noise * 3f64.sqrt() * rng.sym()))
        .collect();
    (TestModes::new(f, None, y).unwrap(), sensors)
}

/// Measured receptances: `real` with region stiffness factors `theta` and the damping
/// `damping`, solved directly at each of `hz` (one sparse complex factorization per line), a
/// unit force along z at the model's sensor node `reference` (an index into
/// [`sensor_nodes`]), read at the model's sensor nodes in y and z, each value with complex
/// noise of relative size `noise` (uniform, unit variance per part). Returns the response sensors
/// (the model's node ids), the reference sensor and one `30 x 1` receptance per line.
#[allow(clippy::too_many_arguments)]
pub fn measure_frf(
    real: &Model,
    theta: &[f64],
    damping: &femu_update::FrfDamping,
    model: &Model,
    reference: usize,
    hz: &[f64],
    noise: f64,
    seed: u64,
) -> (Vec<Sensor>, Sensor, Vec<Mat<faer::c64>>) {
    let up = with_factors(real, theta);
    let sys = up.matrices();
    let (sensors, dofs, force_dof) = frf_dofs(real, sys, model, reference);
    let combination =
        femu_sparse::complex::Combination::new(&[&sys.k, &sys.m], &["K", "M"]).unwrap();
    let mut rng = femu_testkit::Rng(seed);
    let h = hz
        .iter()
        .map(|f| {
            let w = 2.0 * std::f64::consts::PI * f;
            let a = damping.stiffness(w);
            let factor = combination.factor(&[a.k, a.m]).unwrap();
            read_noisy(factor, sys.k.rows(), force_dof, &dofs, noise, &mut rng)
        })
        .collect();
    (sensors, Sensor::axis(sensor_nodes(model)[reference], 2), h)
}

/// Measured receptances of `real` as it is built, its materials and their structural damping
/// included: `(K + i K_4 - w^2 M) u = f` solved at each of `hz` with `K_4 = sum_e GE_e K_e` of
/// its elements (`Assembler::dampers`), read as [`measure_frf`] reads them.
pub fn measure_frf_damped(
    real: &Model,
    model: &Model,
    reference: usize,
    hz: &[f64],
    noise: f64,
    seed: u64,
) -> (Vec<Sensor>, Sensor, Vec<Mat<faer::c64>>) {
    use faer::c64;
    let asm = femu_fem::assembly::Assembler::new(real).unwrap();
    let sys = asm.assemble(real, MassKind::Consistent).unwrap();
    let k4 = asm
        .dampers(real, femu_fem::assembly::MassKind::Consistent)
        .unwrap()
        .structural
        .unwrap();
    let (sensors, dofs, force_dof) = frf_dofs(real, &sys, model, reference);
    let combination =
        femu_sparse::complex::Combination::new(&[&sys.k, &sys.m, &k4], &["K", "M", "K4"]).unwrap();
    let mut rng = femu_testkit::Rng(seed);
    let h = hz
        .iter()
        .map(|f| {
            let w = 2.0 * std::f64::consts::PI * f;
            let factor = combination
                .factor(&[
                    c64::new(1.0, 0.0),
                    c64::new(-w * w, 0.0),
                    c64::new(0.0, 1.0),
                ])
                .unwrap();
            read_noisy(factor, sys.k.rows(), force_dof, &dofs, noise, &mut rng)
        })
        .collect();
    (sensors, Sensor::axis(sensor_nodes(model)[reference], 2), h)
}

/// The response under a unit force at `force_dof`, read at `dofs` with complex noise of relative
/// size `noise`.
fn read_noisy(
    mut factor: femu_sparse::complex::Factored<'_>,
    n: usize,
    force_dof: usize,
    dofs: &[usize],
    noise: f64,
    rng: &mut femu_testkit::Rng,
) -> Mat<faer::c64> {
    use faer::c64;
    let mut u = Mat::<c64>::zeros(n, 1);
    u[(force_dof, 0)] = c64::new(1.0, 0.0);
    factor.solve_in_place(u.as_mut()).unwrap();
    Mat::from_fn(dofs.len(), 1, |i, _| {
        let e = c64::new(
            noise * 3f64.sqrt() * rng.sym(),
            noise * 3f64.sqrt() * rng.sym(),
        );
        u[(dofs[i], 0)] * (c64::new(1.0, 0.0) + e)
    })
}

/// The model's sensors (its sensor nodes in y and z), the real structure's DOFs at the same
/// points, and the real DOF of the force (z at sensor node `reference`).
fn frf_dofs(
    real: &Model,
    sys: &SystemMatrices,
    model: &Model,
    reference: usize,
) -> (Vec<Sensor>, Vec<usize>, usize) {
    let nodes = sensor_nodes(model);
    let real_dof = |id: u64, axis: usize| {
        let x = model.mesh().coords()[model.mesh().node_index(id).unwrap()];
        let layout = SensorLayout::new(
            real.mesh(),
            &sys.dofs,
            vec![Sensor::axis(node_at(real.mesh(), x), axis)],
        )
        .unwrap();
        layout.measured_dofs().unwrap()[0]
    };
    let mut sensors = Vec::new();
    let mut dofs = Vec::new();
    for id in &nodes {
        for axis in [1, 2] {
            sensors.push(Sensor::axis(*id, axis));
            dofs.push(real_dof(*id, axis));
        }
    }
    let force_dof = real_dof(nodes[reference], 2);
    (sensors, dofs, force_dof)
}
