//! Pyramids beyond the checks every kind passes (nodal values, gradients against finite
//! differences, the patch test, rigid-body modes, exact mass, exact rules): the 13-node pyramid
//! reproduces every quadratic field, and a cube cut into six pyramids (linear and quadratic) is a
//! conforming mesh of volume 1 that passes the patch test as an assembly: under a linear
//! displacement field the interior nodes carry no force.

use femu_fem::prelude::*;
use femu_sparse::csc::mul_vec;
use std::collections::HashMap;

#[test]
fn pyramid13_reproduces_quadratic_fields() {
    let kind = ElementKind::Pyramid13;
    let nodes = kind.reference_nodes();
    let quad = |p: [f64; 3]| -> [f64; 6] {
        [
            p[0] * p[0],
            p[1] * p[1],
            p[2] * p[2],
            p[0] * p[1],
            p[1] * p[2],
            p[0] * p[2],
        ]
    };
    let mut rng = femu_testkit::Rng(3);
    let mut n = vec![0.0; 13];
    for _ in 0..200 {
        // a random point of the pyramid
        let z = 0.5 * (rng.sym() + 1.0) * 0.98;
        let (x, y) = (rng.sym() * (1.0 - z), rng.sym() * (1.0 - z));
        kind.shape([x, y, z], &mut n);
        let want = quad([x, y, z]);
        for k in 0..6 {
            let got: f64 = nodes.iter().zip(&n).map(|(p, w)| w * quad(*p)[k]).sum();
            assert!((got - want[k]).abs() < 1e-13, "monomial {k} at {x} {y} {z}");
        }
    }
}

/// The unit cube as six pyramids with their apex at its centre (mid-edge nodes shared by
/// coordinates when `quadratic`).
fn six_pyramids(quadratic: bool) -> Mesh {
    let mut ids: HashMap<[i64; 3], u64> = HashMap::new();
    let mut mesh = Mesh::new();
    let mut node = |mesh: &mut Mesh, p: [f64; 3]| -> u64 {
        let key = p.map(|v| (v * 1e6).round() as i64);
        if let Some(id) = ids.get(&key) {
            return *id;
        }
        let id = ids.len() as u64 + 1;
        mesh.add_node(id, p).unwrap();
        ids.insert(key, id);
        id
    };
    let c = [0.5, 0.5, 0.5];
    // each face's corners counter-clockwise seen from inside (normal towards the apex)
    let faces: [[[f64; 3]; 4]; 6] = [
        [[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]],
        [[0., 0., 1.], [0., 1., 1.], [1., 1., 1.], [1., 0., 1.]],
        [[0., 0., 0.], [0., 0., 1.], [1., 0., 1.], [1., 0., 0.]],
        [[1., 0., 0.], [1., 0., 1.], [1., 1., 1.], [1., 1., 0.]],
        [[1., 1., 0.], [1., 1., 1.], [0., 1., 1.], [0., 1., 0.]],
        [[0., 1., 0.], [0., 1., 1.], [0., 0., 1.], [0., 0., 0.]],
    ];
    let kind = if quadratic {
        ElementKind::Pyramid13
    } else {
        ElementKind::Pyramid5
    };
    for (e, f) in faces.iter().enumerate() {
        let corners: Vec<[f64; 3]> = f.iter().copied().chain([c]).collect();
        let mut list: Vec<u64> = corners.iter().map(|p| node(&mut mesh, *p)).collect();
        if quadratic {
            for [a, b] in kind.edges() {
                let m = std::array::from_fn(|i| 0.5 * (corners[*a][i] + corners[*b][i]));
                list.push(node(&mut mesh, m));
            }
        }
        mesh.add_element(e as u64 + 1, kind, &list).unwrap();
    }
    mesh
}

#[test]
fn a_cube_of_six_pyramids_conforms_and_passes_the_patch_test() {
    for quadratic in [false, true] {
        let mesh = six_pyramids(quadratic);
        mesh.validate().unwrap();
        let report = mesh.check_conformity();
        assert!(report.is_conforming(), "{:?}", report.problems);
        assert_eq!(report.interior_faces, 12);
        assert!((mesh.volume().unwrap() - 1.0).abs() < 1e-14);
        let mut model = Model::new(mesh.clone()).unwrap();
        model.set_material(None, Material::steel()).unwrap();
        let sys = model.assemble(MassKind::Consistent).unwrap();
        let a = [
            [1e-3, 2e-4, -3e-4],
            [5e-4, -2e-3, 1e-4],
            [-1e-4, 3e-4, 7e-4],
        ];
        let u: Vec<f64> = (0..sys.dofs.free_count())
            .map(|f| {
                let (p, c) = sys.dofs.free_dof(f);
                let x = mesh.coords()[p];
                (0..3).map(|k| a[c][k] * x[k]).sum::<f64>()
            })
            .collect();
        let mut ku = vec![0.0; u.len()];
        mul_vec(&sys.k, &u, &mut ku).unwrap();
        let scale = ku.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (f, v) in ku.iter().enumerate() {
            let p = mesh.coords()[sys.dofs.free_dof(f).0];
            let interior = p.iter().all(|x| *x > 1e-9 && *x < 1.0 - 1e-9);
            if interior {
                assert!(
                    v.abs() < 1e-12 * scale,
                    "quadratic {quadratic}: force {v} inside"
                );
            }
        }
        assert!((model.total_mass().unwrap() - 7850.0).abs() < 1e-9);
    }
}
