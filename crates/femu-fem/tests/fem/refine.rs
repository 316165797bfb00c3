//! Splitting a mesh once (`generate::refine`), checked against independent constructions:
//! - a hex20 box split once is the hex20 box of twice the divisions, built by the generator:
//!   the same nodes (coordinates as a set), and the same spectrum to round-off;
//! - curved tet10 and penta15 meshes keep their volume exactly (each child is placed by its
//!   parent's shape functions, whose space is invariant under the split's affine maps), stay
//!   conforming, and their spectrum can only fall (the refined trial space contains the
//!   original: Rayleigh-Ritz), towards that of a much finer mesh;
//! - node sets take the new nodes of their faces: the split cantilever clamped on its `xmin`
//!   set is the doubled box clamped on its own.

use femu_fem::assembly::MassKind;
use femu_fem::generate::{BoxCells, BoxSpec, box_mesh, refine};
use femu_fem::material::Material;
use femu_fem::mesh::Mesh;
use femu_fem::model::Model;
use femu_sparse::eigen::{EigenOptions, Which};

fn lowest(mesh: &Mesh, clamp: bool, count: usize) -> Vec<f64> {
    let mut m = Model::new(mesh.clone()).unwrap();
    m.set_material(None, Material::steel()).unwrap();
    if clamp {
        m.fix_set("xmin", &[0, 1, 2]).unwrap();
    }
    let sys = m.assemble(MassKind::Consistent).unwrap();
    sys.modes(Which::Lowest(count), &EigenOptions::default())
        .unwrap()
        .values
}

/// The box bent into a quarter of an annulus about the z axis (x along the arc): every node,
/// mid-edge ones included, on the curved geometry.
fn bend(mesh: &mut Mesh) {
    let n = mesh.node_count();
    let coords: Vec<[f64; 3]> = mesh.coords().to_vec();
    let mut out = Mesh::new();
    for i in 0..n {
        let [x, y, z] = coords[i];
        let (r, t) = (0.1 + y, -x / 0.2 * std::f64::consts::FRAC_PI_2);
        out.add_node(mesh.node_id(i), [r * t.cos(), r * t.sin(), z])
            .unwrap();
    }
    for el in mesh.elements() {
        let ids: Vec<u64> = el.nodes.iter().map(|i| mesh.node_id(*i)).collect();
        out.add_element(el.id, el.kind, &ids).unwrap();
    }
    for (name, set) in mesh.node_sets() {
        out.add_node_set_indices(name.clone(), set.clone());
    }
    *mesh = out;
}

#[test]
fn a_split_hex20_box_is_the_box_of_twice_the_divisions() {
    let coarse = box_mesh(&BoxSpec::new(
        [0.2, 0.04, 0.02],
        [4, 2, 1],
        BoxCells::Hex,
        true,
    ))
    .unwrap();
    let fine = box_mesh(&BoxSpec::new(
        [0.2, 0.04, 0.02],
        [8, 4, 2],
        BoxCells::Hex,
        true,
    ))
    .unwrap();
    let r = refine(&coarse).unwrap();
    assert_eq!(r.mesh.element_count(), 8 * coarse.element_count());
    assert_eq!(r.mesh.node_count(), fine.node_count());
    assert_eq!(r.parent.len(), r.mesh.element_count());
    // the original nodes keep their ids and places
    for i in 0..coarse.node_count() {
        let j = r.mesh.node_index(coarse.node_id(i)).unwrap();
        assert_eq!(r.mesh.coords()[j], coarse.coords()[i]);
    }
    // the same node coordinates, as sets (to the generator's round-off)
    let key = |x: [f64; 3]| x.map(|v| (v * 1e9).round() as i64);
    let mut a: Vec<_> = r.mesh.coords().iter().map(|x| key(*x)).collect();
    let mut b: Vec<_> = fine.coords().iter().map(|x| key(*x)).collect();
    a.sort_unstable();
    b.sort_unstable();
    assert_eq!(a, b);
    assert!(r.mesh.check_conformity().is_conforming());
    // clamped on xmin (the set takes the split face's new nodes): the same spectrum
    let (got, want) = (lowest(&r.mesh, true, 6), lowest(&fine, true, 6));
    for (g, w) in got.iter().zip(&want) {
        assert!((g - w).abs() < 1e-9 * w, "{g} {w}");
    }
}

#[test]
fn curved_quadratic_meshes_keep_their_volume_and_only_soften() {
    for cells in [BoxCells::Tet6, BoxCells::Wedge, BoxCells::Hex] {
        let mut coarse =
            box_mesh(&BoxSpec::new([0.2, 0.03, 0.02], [4, 1, 1], cells, true)).unwrap();
        bend(&mut coarse);
        let mut finer =
            box_mesh(&BoxSpec::new([0.2, 0.03, 0.02], [16, 4, 4], cells, true)).unwrap();
        bend(&mut finer);
        let r = refine(&coarse).unwrap();
        let (v0, v1) = (coarse.volume().unwrap(), r.mesh.volume().unwrap());
        assert!((v1 - v0).abs() < 1e-12 * v0, "{cells:?}: {v0} {v1}");
        assert!(r.mesh.check_conformity().is_conforming(), "{cells:?}");
        let (a, b, c) = (
            lowest(&coarse, true, 4),
            lowest(&r.mesh, true, 4),
            lowest(&finer, true, 4),
        );
        for k in 0..4 {
            // nested trial spaces: never stiffer; and closer to the much finer mesh
            assert!(
                b[k] <= a[k] * (1.0 + 1e-10),
                "{cells:?} mode {k}: {} > {}",
                b[k],
                a[k]
            );
            assert!(
                (b[k] - c[k]).abs() < (a[k] - c[k]).abs(),
                "{cells:?} mode {k}: {} {} {}",
                a[k],
                b[k],
                c[k]
            );
        }
    }
}

#[test]
fn pyramids_are_refused_by_element() {
    let mut mesh = Mesh::new();
    for (i, x) in [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.5, 0.5, 1.0],
    ]
    .iter()
    .enumerate()
    {
        mesh.add_node(i as u64 + 1, *x).unwrap();
    }
    mesh.add_element(
        77,
        femu_fem::element::ElementKind::Pyramid5,
        &[1, 2, 3, 4, 5],
    )
    .unwrap();
    let e = refine(&mesh).unwrap_err().to_string();
    assert!(e.contains("element 77") && e.contains("pyramid"), "{e}");
}
