//! The discretisation estimate compares a model with the same model on quadratic elements (a
//! quadratic model: the same mesh split once): that comparison model must carry the model's
//! masses and multipoint constraints. Checked against a finer model built here by hand (every
//! node of the end face, mid-edge nodes included, rigidly linked to a 0.5 kg body with an offset
//! and rotary inertia): the estimate's relative error of the first mode equals the one computed
//! from it.

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

const L: f64 = 0.2;

/// The model's three lowest modes and the estimate of their discretisation error.
fn estimated(
    model: &Model,
) -> (
    femu_sparse::eigen::Modes,
    femu_study::discretisation::DiscretisationEstimate,
) {
    let sys = model.assemble(MassKind::Consistent).unwrap();
    let modes = eigs(&sys.k, &sys.m, Which::Lowest(3), &EigenOptions::default()).unwrap();
    let est = femu_study::discretisation::estimate(
        model,
        &ModeSet::from_modes(&modes),
        &Default::default(),
    )
    .unwrap()
    .expect("a reference is built");
    (modes, est)
}

/// The cantilever with its end face rigidly linked to a 0.5 kg body (node 9000).
fn build(mesh: &Mesh) -> Model {
    let l = L;
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
}

#[test]
fn the_quadratic_comparison_keeps_masses_and_links() {
    let (l, b, h) = (L, 0.04, 0.02);
    let mut mesh = box_mesh(&BoxSpec::new([l, b, h], [10, 2, 1], BoxCells::Hex, false)).unwrap();
    mesh.add_node(9000, [l + 0.03, b / 2.0, h / 2.0]).unwrap();
    let (modes, est) = estimated(&build(&mesh));
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

/// A quadratic model (hex20) is compared with itself split once: the reference built here by
/// hand is the hex20 box of twice the divisions with the same link and mass, and the estimate's
/// relative error of the first mode equals the one computed from it; the split reference is
/// softer (its trial space contains the model's).
#[test]
fn a_quadratic_model_is_compared_with_itself_split_once() {
    let (l, b, h) = (L, 0.04, 0.02);
    let with_body = |divisions: [usize; 3]| -> Mesh {
        let mut mesh = box_mesh(&BoxSpec::new([l, b, h], divisions, BoxCells::Hex, true)).unwrap();
        mesh.add_node(9000, [l + 0.03, b / 2.0, h / 2.0]).unwrap();
        mesh
    };
    let (modes, est) = estimated(&build(&with_body([5, 1, 1])));
    assert!(est.reference.contains("split once"), "{}", est.reference);
    let reference = build(&with_body([10, 2, 2]));
    let f_ref = lowest(&reference, 1)[0].sqrt();
    let f_model = modes.values[0].sqrt();
    let want = (f_model - f_ref) / f_ref;
    let got = est.relative[0].expect("the first mode pairs");
    assert!(want > 0.0, "{want}");
    assert!((got - want).abs() < 1e-8, "estimate {got}, by hand {want}");
}

/// A model whose reference would be too large is not estimated, and says so: a hex20 plate of
/// about 164,000 nodes would split into about 3.9 million DOFs; a small one is estimated.
#[test]
fn a_reference_too_large_is_skipped_and_said() {
    let mesh = box_mesh(&BoxSpec::new(
        [1.0, 1.0, 0.02],
        [60, 60, 10],
        BoxCells::Hex,
        true,
    ))
    .unwrap();
    let mut big = Model::new(mesh).unwrap();
    big.set_material(None, Material::steel()).unwrap();
    let why = femu_study::discretisation::not_estimated(&big).expect("too large");
    assert!(
        why.contains("DOFs") && why.contains("--no-discretisation"),
        "{why}"
    );
    let small = build(&{
        let mut m = box_mesh(&BoxSpec::new(
            [L, 0.04, 0.02],
            [5, 1, 1],
            BoxCells::Hex,
            true,
        ))
        .unwrap();
        m.add_node(9000, [L + 0.03, 0.02, 0.01]).unwrap();
        m
    });
    assert_eq!(femu_study::discretisation::not_estimated(&small), None);
}
