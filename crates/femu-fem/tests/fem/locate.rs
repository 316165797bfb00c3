//! The inverse isoparametric map and the element search (`femu_fem::locate`), against points
//! built from known local coordinates, analytic distances and linear fields that every element
//! kind interpolates exactly.

use super::common::{Rng, element_coords};
use femu_fem::element::{ALL_KINDS, ElementKind};
use femu_fem::locate::{Locator, in_reference, inverse_map};
use femu_fem::prelude::*;

/// A random point of the reference cell of `kind`.
fn random_xi(kind: ElementKind, rng: &mut Rng) -> [f64; 3] {
    loop {
        let xi = match kind {
            ElementKind::Hex8 | ElementKind::Hex20 => [rng.sym(), rng.sym(), rng.sym()],
            ElementKind::Tet4 | ElementKind::Tet10 => [
                0.5 + 0.5 * rng.sym(),
                0.5 + 0.5 * rng.sym(),
                0.5 + 0.5 * rng.sym(),
            ],
            _ => [0.5 + 0.5 * rng.sym(), 0.5 + 0.5 * rng.sym(), rng.sym()],
        };
        if in_reference(kind, xi, -0.02) {
            return xi;
        }
    }
}

/// `x(xi) = sum_a N_a(xi) x_a`.
fn forward(kind: ElementKind, x: &[[f64; 3]], xi: [f64; 3]) -> [f64; 3] {
    let mut n = vec![0.0; kind.num_nodes()];
    kind.shape(xi, &mut n);
    std::array::from_fn(|i| (0..n.len()).map(|a| n[a] * x[a][i]).sum())
}

#[test]
fn known_local_coordinates_are_recovered_in_distorted_elements() {
    let mut rng = Rng(17);
    for kind in ALL_KINDS {
        for (distortion, curved) in [(0.0, false), (0.12, false), (0.12, true)] {
            let x = element_coords(kind, distortion, curved, &mut rng);
            for _ in 0..50 {
                let xi = random_xi(kind, &mut rng);
                let p = forward(kind, &x, xi);
                let m = inverse_map(kind, &x, p);
                assert!(
                    m.inside,
                    "{kind} d={distortion} curved={curved}: {xi:?} -> {m:?}"
                );
                let err = (0..3).map(|k| (m.xi[k] - xi[k]).abs()).fold(0.0, f64::max);
                assert!(err < 1e-10, "{kind} d={distortion}: {xi:?} -> {:?}", m.xi);
                assert!(m.distance < 1e-12);
            }
        }
    }
}

#[test]
fn points_outside_an_element_get_the_nearest_point_and_its_distance() {
    // unit cube hex8 / hex20 and unit tetrahedron: analytic nearest points
    for kind in [ElementKind::Hex8, ElementKind::Hex20] {
        let x: Vec<[f64; 3]> = kind
            .reference_nodes()
            .iter()
            .map(|r| r.map(|v| 0.5 * (v + 1.0)))
            .collect();
        let m = inverse_map(kind, &x, [1.5, 0.25, 0.5]);
        assert!(!m.inside);
        assert!((m.distance - 0.5).abs() < 1e-12, "{kind}: {m:?}");
        assert!((m.xi[0] - 1.0).abs() < 1e-12 && (m.xi[1] + 0.5).abs() < 1e-10);
        // beyond an edge: the point (1.3, 1.4, 0.5) is 0.5 from the edge x = y = 1
        let m = inverse_map(kind, &x, [1.3, 1.4, 0.5]);
        assert!((m.distance - 0.5).abs() < 1e-10, "{kind}: {m:?}");
    }
    for kind in [ElementKind::Tet4, ElementKind::Tet10] {
        let x = kind.reference_nodes();
        // distance from (1, 1, 1) to the face x + y + z = 1 is 2 / sqrt(3), at (1/3, 1/3, 1/3)
        let m = inverse_map(kind, &x, [1.0, 1.0, 1.0]);
        assert!(
            (m.distance - 2.0 / 3f64.sqrt()).abs() < 1e-10,
            "{kind}: {m:?}"
        );
        assert!(m.xi.iter().all(|v| (v - 1.0 / 3.0).abs() < 1e-8));
        // beyond a vertex: (-1, -1, -1) is sqrt(3) from the origin
        let m = inverse_map(kind, &x, [-1.0, -1.0, -1.0]);
        assert!((m.distance - 3f64.sqrt()).abs() < 1e-10, "{kind}: {m:?}");
    }
    for kind in [ElementKind::Penta6, ElementKind::Penta15] {
        let x = kind.reference_nodes();
        // the wedge spans z in [-1, 1]: (0.2, 0.2, 1.75) is 0.75 above its top
        let m = inverse_map(kind, &x, [0.2, 0.2, 1.75]);
        assert!((m.distance - 0.75).abs() < 1e-10, "{kind}: {m:?}");
    }
}

/// `u(x) = a + B x`, which every isoparametric element reproduces exactly.
fn linear_field(x: [f64; 3]) -> f64 {
    0.3 - 1.2 * x[0] + 0.7 * x[1] + 2.1 * x[2]
}

#[test]
fn every_point_of_a_mesh_is_found_and_interpolates_a_linear_field_exactly() {
    let mut rng = Rng(5);
    for cells in [
        BoxCells::Hex,
        BoxCells::Wedge,
        BoxCells::Tet5,
        BoxCells::Tet6,
    ] {
        for quadratic in [false, true] {
            let spec = BoxSpec::new([0.4, 0.2, 0.1], [4, 3, 2], cells, quadratic);
            let mesh = box_mesh(&spec).unwrap();
            let locator = Locator::new(&mesh);
            for _ in 0..200 {
                let p = [
                    0.2 + 0.2 * rng.sym(),
                    0.1 + 0.1 * rng.sym(),
                    0.05 + 0.05 * rng.sym(),
                ];
                let loc = locator.locate(&mesh, p, 0.0).expect("inside the box");
                assert_eq!(loc.distance, 0.0);
                let sum: f64 = loc.weights.iter().map(|w| w.1).sum();
                assert!((sum - 1.0).abs() < 1e-12);
                let u: f64 = loc
                    .weights
                    .iter()
                    .map(|(a, w)| w * linear_field(mesh.coords()[*a]))
                    .sum();
                assert!(
                    (u - linear_field(p)).abs() < 1e-12,
                    "{cells:?} quadratic={quadratic} at {p:?}"
                );
            }
            // 0.03 m beyond the face x = 0.4: found within 0.05, not within 0.02
            let p = [0.43, 0.1, 0.05];
            let loc = locator
                .locate(&mesh, p, 0.05)
                .expect("within the tolerance");
            assert!((loc.distance - 0.03).abs() < 1e-10, "{cells:?}: {loc:?}");
            assert!(locator.locate(&mesh, p, 0.02).is_none());
        }
    }
}

#[test]
fn the_nearest_node_equals_a_scan_of_all_nodes() {
    let mesh = box_mesh(&BoxSpec::new(
        [1.0, 0.5, 0.2],
        [10, 6, 3],
        BoxCells::Tet6,
        true,
    ))
    .unwrap();
    let locator = Locator::new(&mesh);
    let mut rng = Rng(9);
    for _ in 0..300 {
        let p = [
            0.5 + 0.6 * rng.sym(),
            0.25 + 0.3 * rng.sym(),
            0.1 + 0.2 * rng.sym(),
        ];
        let scan = (0..mesh.node_count())
            .map(|i| {
                let c = mesh.coords()[i];
                (
                    i,
                    ((c[0] - p[0]).powi(2) + (c[1] - p[1]).powi(2) + (c[2] - p[2]).powi(2)).sqrt(),
                )
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap();
        for tol in [0.02, 0.1, 10.0] {
            let found = locator.nearest_node(&mesh, p, tol);
            if scan.1 <= tol {
                let (i, d) = found.expect("a node within the tolerance");
                assert_eq!(d, scan.1);
                assert!(i == scan.0 || d == scan.1);
            } else {
                assert!(found.is_none());
            }
        }
    }
}
