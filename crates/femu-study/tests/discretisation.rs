//! The discretisation estimate compares a model with the same model on quadratic elements: that
//! comparison model must carry the model's masses and multipoint constraints. Checked against a
//! quadratic model built here by hand (every node of the end face, mid-edge nodes included,
//! rigidly linked to a 0.5 kg body with an offset and rotary inertia): the estimate's relative error of the first mode
//! equals the one computed from it.

use femu_correlate::modes::ModeSet;
use femu_fem::generate::to_quadratic;
use femu_fem::prelude::*;
use femu_sparse::eigen::{EigenOptions, Which, eigs};

fn lowest(model: &Model, count: usize) -> Vec<f64> {
    let sys = model.assemble(MassKind::Consistent).unwrap();
    eigs(
        &sys.k,
        &sys.m,
        Which::Lowest(count),
        &EigenOptions::default(),
    )
    .unwrap()
    .values
}

fn at_x(mesh: &Mesh, x: f64) -> Vec<u64> {
    (0..mesh.node_count())
        .filter(|i| (mesh.coords()[*i][0] - x).abs() < 1e-12)
        .map(|i| mesh.node_id(i))
        .collect()
}

#[test]
fn the_quadratic_comparison_keeps_masses_and_links() {
    let (l, b, h) = (0.2, 0.04, 0.02);
    let mut mesh = box_mesh(&BoxSpec::new([l, b, h], [10, 2, 1], BoxCells::Hex, false)).unwrap();
    mesh.add_node(9000, [l + 0.03, b / 2.0, h / 2.0]).unwrap();
    let build = |mesh: &Mesh| -> Model {
        let mut m = Model::new(mesh.clone()).unwrap();
        m.set_material(None, Material::steel()).unwrap();
        let clamped = at_x(mesh, 0.0);
        m.fix_nodes(&clamped, &[0, 1, 2]).unwrap();
        let end: Vec<u64> = at_x(mesh, l).into_iter().filter(|id| *id != 9000).collect();
        m.add_rigid_link(9000, &end, &[0, 1, 2], "end").unwrap();
        // a 0.5 kg body whose centre of gravity is 1 cm further out, with rotary inertia
        m.add_rigid_mass(
            9000,
            0.5,
            [0.01, 0.0, 0.0],
            [[1e-4, 0.0, 0.0], [0.0, 2e-4, 0.0], [0.0, 0.0, 2e-4]],
        )
        .unwrap();
        m
    };
    let model = build(&mesh);
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let modes = eigs(&sys.k, &sys.m, Which::Lowest(3), &EigenOptions::default()).unwrap();
    let est = femu_study::discretisation::estimate(
        &model,
        &ModeSet::from_modes(&modes),
        &Default::default(),
    )
    .unwrap()
    .expect("a linear mesh has a quadratic comparison");
    // by hand: the quadratic mesh, every end-face node linked, the same mass
    let reference = build(&to_quadratic(&mesh));
    let f_ref = lowest(&reference, 1)[0].sqrt();
    let f_model = modes.values[0].sqrt();
    let want = (f_model - f_ref) / f_ref;
    let got = est.relative[0].expect("the first mode pairs");
    assert!((got - want).abs() < 1e-8, "estimate {got}, by hand {want}");
    // and the mass matters: without it the first frequency is far higher
    let mut bare = Model::new(mesh.clone()).unwrap();
    bare.set_material(None, Material::steel()).unwrap();
    bare.fix_nodes(&at_x(&mesh, 0.0), &[0, 1, 2]).unwrap();
    bare.fix_nodes(&[9000], &[0, 1, 2]).unwrap();
    assert!(lowest(&bare, 1)[0] > 2.0 * modes.values[0]);
}
