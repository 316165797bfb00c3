//! VTK output: the node order of every cell type obeys VTK's conventions (checked geometrically
//! on the written connectivity), fields are sized and finite.

use femu_fem::prelude::*;
use femu_io::vtk::{CellField, PointField, pvd_string, vtu_string};

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The connectivity, offsets and types arrays of a written file.
fn arrays(text: &str) -> (Vec<usize>, Vec<usize>, Vec<u8>) {
    let grab = |name: &str| -> Vec<String> {
        let start = text.find(&format!("Name=\"{name}\"")).unwrap();
        let body = &text[start..];
        let open = body.find('>').unwrap() + 1;
        let close = body.find("</DataArray>").unwrap();
        body[open..close]
            .split_whitespace()
            .map(String::from)
            .collect()
    };
    (
        grab("connectivity")
            .iter()
            .map(|s| s.parse().unwrap())
            .collect(),
        grab("offsets").iter().map(|s| s.parse().unwrap()).collect(),
        grab("types").iter().map(|s| s.parse().unwrap()).collect(),
    )
}

#[test]
fn cells_follow_vtk_conventions() {
    for (cells, quadratic, ty) in [
        (BoxCells::Tet6, false, 10u8),
        (BoxCells::Tet6, true, 24),
        (BoxCells::Hex, false, 12),
        (BoxCells::Hex, true, 25),
        (BoxCells::Wedge, false, 13),
        (BoxCells::Wedge, true, 26),
    ] {
        let mesh = box_mesh(&BoxSpec::new([1.0, 0.7, 0.4], [2, 2, 1], cells, quadratic)).unwrap();
        let n = mesh.node_count();
        let disp: Vec<f64> = (0..3 * n).map(|i| i as f64 * 1e-3).collect();
        let ind: Vec<f64> = (0..mesh.element_count()).map(|e| e as f64).collect();
        let text = vtu_string(
            &mesh,
            &[PointField {
                name: "mode 1 (123.4 Hz)",
                components: 3,
                values: &disp,
            }],
            &[CellField {
                name: "indicator",
                values: &ind,
            }],
        )
        .unwrap();
        let (conn, offsets, types) = arrays(&text);
        assert_eq!(types.len(), mesh.element_count());
        assert!(types.iter().all(|t| *t == ty));
        let x = mesh.coords();
        let mut start = 0;
        for end in offsets {
            let c = &conn[start..end];
            let p = |i: usize| x[c[i]];
            let base = cross(sub(p(1), p(0)), sub(p(2), p(0)));
            match ty {
                // tetra: (0,1,2) normal towards 3; hexahedron: (0,1,2,3) normal towards 4
                10 | 24 | 12 | 25 => {
                    let apex = if ty == 10 || ty == 24 { 3 } else { 4 };
                    assert!(dot(base, sub(p(apex), p(0))) > 0.0, "type {ty}: {c:?}");
                }
                // wedge: (0,1,2) normal away from (3,4,5)
                _ => assert!(dot(base, sub(p(3), p(0))) < 0.0, "type {ty}: {c:?}"),
            }
            // quadratic cells: each mid-edge node is the midpoint of its VTK edge
            let edges: &[(usize, usize)] = match ty {
                24 => &[(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)],
                25 => &[
                    (0, 1),
                    (1, 2),
                    (2, 3),
                    (3, 0),
                    (4, 5),
                    (5, 6),
                    (6, 7),
                    (7, 4),
                    (0, 4),
                    (1, 5),
                    (2, 6),
                    (3, 7),
                ],
                26 => &[
                    (0, 1),
                    (1, 2),
                    (2, 0),
                    (3, 4),
                    (4, 5),
                    (5, 3),
                    (0, 3),
                    (1, 4),
                    (2, 5),
                ],
                _ => &[],
            };
            let corners = c.len() - edges.len();
            for (k, (a, b)) in edges.iter().enumerate() {
                let m = p(corners + k);
                for d in 0..3 {
                    assert!(
                        (m[d] - 0.5 * (p(*a)[d] + p(*b)[d])).abs() < 1e-12,
                        "type {ty} edge {k}"
                    );
                }
            }
            start = end;
        }
        assert!(text.contains("Name=\"mode 1 (123.4 Hz)\" NumberOfComponents=\"3\""));
    }
    // wrong sizes and NaN are errors naming the field (and node)
    let mesh = box_mesh(&BoxSpec::new(
        [1.0, 1.0, 1.0],
        [1, 1, 1],
        BoxCells::Hex,
        false,
    ))
    .unwrap();
    assert!(
        vtu_string(
            &mesh,
            &[PointField {
                name: "u",
                components: 3,
                values: &[0.0; 5]
            }],
            &[]
        )
        .is_err()
    );
    let mut nan = vec![0.0; 24];
    nan[7] = f64::NAN;
    let err = vtu_string(
        &mesh,
        &[PointField {
            name: "u",
            components: 3,
            values: &nan,
        }],
        &[],
    )
    .unwrap_err();
    assert!(err.to_string().contains("node"), "{err}");
    assert!(
        vtu_string(
            &mesh,
            &[],
            &[CellField {
                name: "e",
                values: &[1.0, 2.0]
            }]
        )
        .is_err()
    );
    let pvd = pvd_string(&[(100.0, "mode1.vtu"), (250.5, "mode2.vtu")]);
    assert!(pvd.contains("timestep=\"250.5\" file=\"mode2.vtu\""));
}

/// Beams and springs are lines after the solids (a grounded spring a vertex), with their section
/// as cell data (zero on the solids) and the element ids of both; a cell field given per solid is
/// padded with zeros, one given per cell is written whole.
#[test]
fn structural_elements_are_lines_with_their_sections() {
    use femu_fem::structural::{
        Beam, BeamSection, Part, Spring, SpringEnd, StructuralElement, StructuralKind,
    };
    use femu_io::vtk::vtu_string_with;
    let mesh = box_mesh(&BoxSpec::new(
        [1.0, 1.0, 1.0],
        [1, 1, 1],
        BoxCells::Hex,
        false,
    ))
    .unwrap();
    let section = BeamSection {
        area: 2e-4,
        i1: 3e-9,
        i2: 4e-9,
        j: 5e-9,
        shear: None,
        nsm: 0.0,
    };
    let beam = StructuralElement {
        id: 77,
        nodes: vec![0, 1],
        kind: StructuralKind::Beam(Beam {
            e: 2e11,
            g: 8e10,
            rho: 7800.0,
            section,
            taper: None,
            orientation: [0.0, 0.0, 1.0],
            offsets: [[0.0; 3]; 2],
            lumped_torsion: false,
            coupled_torsion: true,
            releases: [[false; 6]; 2],
        }),
    };
    let spring = StructuralElement {
        id: 78,
        nodes: vec![2],
        kind: StructuralKind::Spring(Spring {
            k: 1234.0,
            ge: 0.0,
            viscous: 0.0,
            mass: 0.0,
            a: SpringEnd {
                node: 2,
                part: Part::Translations,
                direction: [0.0, 0.0, 1.0],
            },
            b: None,
        }),
    };
    let structural = [beam, spring];
    let per_solid = [0.5];
    let per_cell = [1.0, 2.0, 3.0];
    let text = vtu_string_with(
        &mesh,
        &structural,
        &[],
        &[
            CellField {
                name: "solid",
                values: &per_solid,
            },
            CellField {
                name: "all",
                values: &per_cell,
            },
        ],
    )
    .unwrap();
    let (conn, offsets, types) = arrays(&text);
    assert_eq!(types, vec![12, 3, 1]);
    assert_eq!(offsets, vec![8, 10, 11]);
    assert_eq!(&conn[8..], &[0, 1, 2]);
    let values = |name: &str| -> Vec<f64> {
        let start = text.find(&format!("Name=\"{name}\"")).unwrap();
        let body = &text[start..];
        let open = body.find('>').unwrap() + 1;
        let close = body.find("</DataArray>").unwrap();
        body[open..close]
            .split_whitespace()
            .map(|s| s.parse().unwrap())
            .collect()
    };
    assert_eq!(values("element_id"), vec![1.0, 77.0, 78.0]);
    assert_eq!(values("area"), vec![0.0, 2e-4, 0.0]);
    assert_eq!(values("J"), vec![0.0, 5e-9, 0.0]);
    assert_eq!(values("stiffness"), vec![0.0, 0.0, 1234.0]);
    assert_eq!(values("solid"), vec![0.5, 0.0, 0.0]);
    assert_eq!(values("all"), per_cell.to_vec());
    let wrong = [1.0, 2.0];
    let e = vtu_string_with(
        &mesh,
        &structural,
        &[],
        &[CellField {
            name: "short",
            values: &wrong,
        }],
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("2 values for 3 elements"), "{e}");
}

/// An 8-node shell is a VTK_QUADRATIC_QUAD (type 23) whose eight points are its nodes in femu's
/// order (corners, then the midsides of edges 1-2, 2-3, 3-4, 4-1: VTK's order), with its
/// thickness as cell data.
#[test]
fn eight_node_shells_are_quadratic_quads() {
    use femu_fem::structural::{StructuralElement, StructuralKind};
    use femu_io::vtk::vtu_string_with;
    let mesh = box_mesh(&BoxSpec::new(
        [1.0, 1.0, 1.0],
        [1, 1, 1],
        BoxCells::Hex,
        false,
    ))
    .unwrap();
    let shell = StructuralElement {
        id: 9,
        nodes: vec![7, 6, 5, 4, 3, 2, 1, 0],
        kind: StructuralKind::Shell(femu_fem::shell::Shell {
            e: 2e11,
            nu: 0.3,
            rho: 7800.0,
            t: 0.004,
            bending: 1.0,
            shear: Some(5.0 / 6.0),
            nsm: 0.0,
            material: None,
            offset: 0.0,
            membrane: femu_fem::shell::Membrane::Incompatible,
        }),
    };
    let text = vtu_string_with(&mesh, &[shell], &[], &[]).unwrap();
    let (conn, offsets, types) = arrays(&text);
    assert_eq!(types, vec![12, 23]);
    assert_eq!(offsets, vec![8, 16]);
    assert_eq!(&conn[8..], &[7, 6, 5, 4, 3, 2, 1, 0]);
    assert!(text.contains("Name=\"thickness\""), "{text}");
}
