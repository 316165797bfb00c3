//! Eigenpair derivatives by Nelson's method against central finite differences of the dense
//! generalized eigensolver (an independent path: no Lanczos, no Nelson system), for stiffness and
//! mass parameters, on a clamped bar with a rectangular section (simple eigenvalues).

use femu_fem::prelude::*;
use femu_sparse::csc::to_dense;
use femu_sparse::dense::generalized_symmetric_eigen;
use femu_sparse::eigen::Pencil;
use femu_update::prelude::*;
use femu_update::{Corrections, eigenpair_derivatives};

fn model() -> Model {
    let mut mesh = box_mesh(&BoxSpec::new(
        [0.2, 0.04, 0.02],
        [8, 2, 1],
        BoxCells::Hex,
        false,
    ))
    .unwrap();
    for g in 0..4 {
        let ids: Vec<u64> = mesh
            .elements()
            .filter(|e| (e.index % 8) / 2 == g)
            .map(|e| e.id)
            .collect();
        mesh.add_element_set(format!("g{g}"), &ids).unwrap();
    }
    let mut model = Model::new(mesh).unwrap();
    model.set_material(None, Material::steel()).unwrap();
    model.fix_set("xmin", &[0, 1, 2]).unwrap();
    model
}

/// The dense eigenpairs of `up` at `theta`, vectors M-normalised.
fn dense(up: &mut UpdateModel<'_>, theta: &[f64]) -> (Vec<f64>, faer::Mat<f64>) {
    up.set_theta(theta).unwrap();
    let sys = up.matrices();
    let e =
        generalized_symmetric_eigen(to_dense(&sys.k).as_ref(), to_dense(&sys.m).as_ref()).unwrap();
    (e.values, e.vectors)
}

#[test]
fn nelson_matches_central_differences_of_the_dense_solver() {
    let model = model();
    let sets = ["g0", "g1", "g2", "g3"];
    for corrections in [Corrections::Stiffness, Corrections::StiffnessAndMass] {
        let mut up =
            UpdateModel::from_element_sets(&model, &sets, MassKind::Consistent, corrections)
                .unwrap();
        let np = up.parameters().len();
        let theta0: Vec<f64> = (0..np).map(|k| 0.05 * k as f64 - 0.1).collect();
        let (values, vectors) = dense(&mut up, &theta0);

        up.set_theta(&theta0).unwrap();
        let symbolic = up.symbolic().unwrap();
        let sys = up.matrices().clone();
        let pencil = Pencil::with_symbolic(&sys.k, &sys.m, symbolic).unwrap();
        // the step balances truncation (h^2) against the dense solver's round-off (1e-11 / h);
        // vectors agree to 1e-4 of the larger of d phi and phi (the differences' noise floor)
        let h = 1e-4;
        for mode in [0, 2, 5] {
            let phi: Vec<f64> = vectors.col(mode).iter().copied().collect();
            up.set_theta(&theta0).unwrap();
            let d = eigenpair_derivatives(&up, &pencil, &phi, values[mode]).unwrap();
            for k in 0..np {
                let mut plus = theta0.clone();
                plus[k] += h;
                let mut minus = theta0.clone();
                minus[k] -= h;
                let (vp, xp) = dense(&mut up, &plus);
                let (vm, xm) = dense(&mut up, &minus);
                let dl = (vp[mode] - vm[mode]) / (2.0 * h);
                let scale = d.values.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
                assert!(
                    (d.values[k] - dl).abs() <= 1e-6 * scale,
                    "{corrections:?} mode {mode} parameter {k}: {} vs {dl}",
                    d.values[k]
                );
                // align the signs of the perturbed vectors with phi
                let sign = |x: &faer::Mat<f64>| {
                    let s: f64 = (0..phi.len()).map(|i| x[(i, mode)] * phi[i]).sum();
                    s.signum()
                };
                let (sp, sm) = (sign(&xp), sign(&xm));
                let norm: f64 = phi.iter().map(|v| v * v).sum::<f64>().sqrt();
                let err: f64 = (0..phi.len())
                    .map(|i| {
                        let fd = (sp * xp[(i, mode)] - sm * xm[(i, mode)]) / (2.0 * h);
                        (d.vectors[k][i] - fd).powi(2)
                    })
                    .sum::<f64>()
                    .sqrt();
                let dnorm: f64 = d.vectors[k].iter().map(|v| v * v).sum::<f64>().sqrt();
                assert!(
                    err <= 1e-4 * dnorm.max(norm),
                    "{corrections:?} mode {mode} parameter {k}: |error| {err:e}, |d phi| {dnorm:e}"
                );
            }
        }
        up.set_theta(&theta0).unwrap();
    }
}
