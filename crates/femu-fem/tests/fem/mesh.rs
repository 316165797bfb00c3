//! Mesh validation errors and conformity checks.

use femu_fem::FemError;
use femu_fem::element::ElementKind;
use femu_fem::generate::{BoxCells, BoxSpec, PlateSpec, box_mesh, mixed_plate};
use femu_fem::mesh::{ConformityProblem, Mesh};
use femu_fem::model::Model;

fn unit_hex_nodes(mesh: &mut Mesh, first_id: u64, x0: f64) -> Vec<u64> {
    let c = [
        [0., 0., 0.],
        [1., 0., 0.],
        [1., 1., 0.],
        [0., 1., 0.],
        [0., 0., 1.],
        [1., 0., 1.],
        [1., 1., 1.],
        [0., 1., 1.],
    ];
    c.iter()
        .enumerate()
        .map(|(i, p)| {
            let id = first_id + 10 * i as u64;
            mesh.add_node(id, [p[0] + x0, p[1], p[2]]).unwrap();
            id
        })
        .collect()
}

#[test]
fn bad_input_gets_errors_that_name_the_offender() {
    let mut m = Mesh::new();
    let ids = unit_hex_nodes(&mut m, 100, 0.0);
    assert_eq!(
        m.add_node(100, [0.0; 3]),
        Err(FemError::DuplicateNodeId { id: 100 })
    );
    assert_eq!(
        m.add_node(7, [0.0, f64::NAN, 0.0]),
        Err(FemError::NonFiniteCoordinate { node: 7 })
    );
    m.add_element(5, ElementKind::Hex8, &ids).unwrap();
    assert_eq!(
        m.add_element(5, ElementKind::Hex8, &ids),
        Err(FemError::DuplicateElementId { id: 5 })
    );
    assert!(matches!(
        m.add_element(6, ElementKind::Hex8, &ids[..7]),
        Err(FemError::WrongNodeCount {
            element: 6,
            expected: 8,
            got: 7,
            ..
        })
    ));
    let mut missing = ids.clone();
    missing[3] = 999;
    assert_eq!(
        m.add_element(6, ElementKind::Hex8, &missing),
        Err(FemError::MissingNode {
            element: 6,
            node: 999
        })
    );
    let mut repeated = ids.clone();
    repeated[3] = ids[0];
    assert_eq!(
        m.add_element(6, ElementKind::Hex8, &repeated),
        Err(FemError::RepeatedNode {
            element: 6,
            node: ids[0]
        })
    );
    assert_eq!(
        m.add_node_set("s", &[1]),
        Err(FemError::UnknownNode { node: 1 })
    );
    assert_eq!(
        m.add_element_set("e", &[42]),
        Err(FemError::UnknownElement { element: 42 })
    );
    m.validate().unwrap();

    // Inverted: top and bottom faces swapped.
    let mut inv = Mesh::new();
    let ids = unit_hex_nodes(&mut inv, 1, 0.0);
    let swapped: Vec<u64> = ids[4..].iter().chain(&ids[..4]).copied().collect();
    inv.add_element(77, ElementKind::Hex8, &swapped).unwrap();
    assert!(matches!(
        inv.validate(),
        Err(FemError::InvertedElement { element: 77, .. })
    ));
    assert!(matches!(
        Model::new(inv),
        Err(FemError::InvertedElement { element: 77, .. })
    ));

    // Degenerate: a flat tetrahedron.
    let mut flat = Mesh::new();
    for (i, p) in [[0., 0., 0.], [1., 0., 0.], [0., 1., 0.], [0.3, 0.3, 0.0]]
        .iter()
        .enumerate()
    {
        flat.add_node(i as u64 + 1, *p).unwrap();
    }
    flat.add_element(9, ElementKind::Tet4, &[1, 2, 3, 4])
        .unwrap();
    assert!(matches!(
        flat.validate(),
        Err(FemError::DegenerateElement { element: 9, .. })
    ));

    // A hex8 folded so that det J changes sign inside (a corner pushed through the opposite face).
    let mut folded = Mesh::new();
    let ids = unit_hex_nodes(&mut folded, 1, 0.0);
    folded.add_node(1000, [0.9, 0.9, 0.9]).unwrap();
    let mut f = ids.clone();
    f[0] = 1000;
    folded.add_element(3, ElementKind::Hex8, &f).unwrap();
    assert!(matches!(
        folded.validate(),
        Err(FemError::InvertedElement { element: 3, .. })
    ));

    // Materials and sets.
    let mesh = box_mesh(&BoxSpec::new(
        [1.0, 1.0, 1.0],
        [1, 1, 1],
        BoxCells::Hex,
        false,
    ))
    .unwrap();
    let mut model = Model::new(mesh).unwrap();
    assert_eq!(
        model.fix_set("nope", &[0]),
        Err(FemError::UnknownNodeSet {
            name: "nope".into()
        })
    );
    assert!(matches!(
        model.fix_set("xmin", &[3]),
        Err(FemError::InvalidComponent { component: 3, .. })
    ));
    assert!(matches!(
        model.assemble(femu_fem::assembly::MassKind::Consistent),
        Err(FemError::NoMaterial { element: 1 })
    ));
    model.fix_set("all", &[0, 1, 2]).unwrap();
    assert!(matches!(
        femu_fem::assembly::Assembler::new(&model),
        Err(FemError::NoFreeDofs)
    ));
}

#[test]
fn generated_meshes_are_conforming_with_the_expected_counts() {
    for cells in [
        BoxCells::Hex,
        BoxCells::Wedge,
        BoxCells::Tet5,
        BoxCells::Tet6,
    ] {
        for quadratic in [false, true] {
            let mesh =
                box_mesh(&BoxSpec::new([1.0, 0.7, 0.4], [3, 2, 2], cells, quadratic)).unwrap();
            let r = mesh.check_conformity();
            assert!(
                r.is_conforming(),
                "{cells:?} quadratic={quadratic}: {:?}",
                r.problems
            );
            let per_cell = match cells {
                BoxCells::Hex => 1,
                BoxCells::Wedge => 2,
                BoxCells::Tet5 => 5,
                BoxCells::Tet6 => 6,
            };
            assert_eq!(mesh.element_count(), 12 * per_cell);
            assert!((mesh.volume().unwrap() - 0.28).abs() < 1e-14);
            mesh.validate().unwrap();
        }
    }
    let plate = mixed_plate(&PlateSpec::default()).unwrap();
    assert_eq!(plate.node_count(), 1845);
    assert_eq!(plate.element_count(), 1360);
    let counts = plate.kind_counts();
    assert_eq!(counts[&ElementKind::Hex8], 912);
    assert_eq!(counts[&ElementKind::Penta6], 400);
    assert_eq!(counts[&ElementKind::Tet4], 48);
    let r = plate.check_conformity();
    assert!(r.is_conforming(), "{:?}", r.problems);
    // Boundary faces of a 40 x 14 x 2 plate: hex quads and split faces (2 triangles per tet or
    // wedge cell face where the face is triangulated).
    assert!(r.boundary_faces > 2 * 40 * 14);
    assert!((plate.volume().unwrap() - 0.2 * 0.07 * 0.01).abs() < 1e-15);
    let q = mixed_plate(&PlateSpec {
        quadratic: true,
        ..PlateSpec::default()
    })
    .unwrap();
    assert!(q.check_conformity().is_conforming());
    assert_eq!(q.kind_counts()[&ElementKind::Penta15], 400);
}

#[test]
fn non_conforming_meshes_are_reported() {
    // A hex8 beside two wedges whose shared face is a quad against... a hexahedron beside six
    // tetrahedra: the hex's quad face meets two triangles.
    let mut m = Mesh::new();
    let left = box_mesh(&BoxSpec::new(
        [2.0, 1.0, 1.0],
        [2, 1, 1],
        BoxCells::Tet6,
        false,
    ))
    .unwrap();
    for i in 0..left.node_count() {
        m.add_node(left.node_id(i), left.coords()[i]).unwrap();
    }
    for el in left.elements() {
        let ids: Vec<u64> = el.nodes.iter().map(|n| left.node_id(*n)).collect();
        if el.id <= 6 {
            m.add_element(el.id, el.kind, &ids).unwrap();
        }
    }
    // a hexahedron on the second cell, corners from the grid (ids: i + 3 (j + 2 k) + 1)
    let id = |i: u64, j: u64, k: u64| i + 3 * (j + 2 * k) + 1;
    let hex = [
        id(1, 0, 0),
        id(2, 0, 0),
        id(2, 1, 0),
        id(1, 1, 0),
        id(1, 0, 1),
        id(2, 0, 1),
        id(2, 1, 1),
        id(1, 1, 1),
    ];
    m.add_element(100, ElementKind::Hex8, &hex).unwrap();
    let r = m.check_conformity();
    assert!(!r.is_conforming());
    assert!(r.problems.iter().any(|p| matches!(p, ConformityProblem::HangingFace { elements, .. } if elements.contains(&100))), "{:?}", r.problems);

    // hex20 beside hex8: corners shared, mid-edge nodes not.
    let two = box_mesh(&BoxSpec::new(
        [2.0, 1.0, 1.0],
        [2, 1, 1],
        BoxCells::Hex,
        false,
    ))
    .unwrap();
    let quad = femu_fem::generate::to_quadratic(&two);
    let mut mixed = Mesh::new();
    for i in 0..quad.node_count() {
        mixed.add_node(quad.node_id(i), quad.coords()[i]).unwrap();
    }
    let e0: Vec<u64> = quad
        .element(0)
        .nodes
        .iter()
        .map(|n| quad.node_id(*n))
        .collect();
    mixed.add_element(1, ElementKind::Hex20, &e0).unwrap();
    let e1: Vec<u64> = two
        .element(1)
        .nodes
        .iter()
        .map(|n| two.node_id(*n))
        .collect();
    mixed.add_element(2, ElementKind::Hex8, &e1).unwrap();
    let r = mixed.check_conformity();
    assert_eq!(r.problems.len(), 1, "{:?}", r.problems);
    assert!(matches!(
        &r.problems[0],
        ConformityProblem::MismatchedFaceNodes {
            elements: [1, 2],
            ..
        }
    ));
    assert!(r.problems[0].to_string().contains("elements 1 and 2"));

    // Two cubes touching with duplicated (unmerged) nodes: a crack, reported as hanging faces.
    let mut crack = Mesh::new();
    let a = unit_hex_nodes(&mut crack, 1, 0.0);
    let b = unit_hex_nodes(&mut crack, 1001, 1.0);
    crack.add_element(1, ElementKind::Hex8, &a).unwrap();
    crack.add_element(2, ElementKind::Hex8, &b).unwrap();
    let r = crack.check_conformity();
    assert!(
        r.problems
            .iter()
            .any(|p| matches!(p, ConformityProblem::HangingFace { .. })),
        "{:?}",
        r.problems
    );
}
