//! Alignment (`femu_fem::align`): known similarity transforms recovered from their point pairs,
//! the nearest boundary point against the analytic distance to a box, iterative closest points
//! recovering a known placement, and the errors.

use super::common::Rng;
use femu_fem::FemError;
use femu_fem::align::{Surface, Transform, fit_auto, fit_pairs, fit_surface};
use femu_fem::prelude::*;

/// Rotation by `angle` (rad) about the unit vector `axis` (Rodrigues).
fn rotation(axis: [f64; 3], angle: f64) -> [[f64; 3]; 3] {
    let n = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
    let [x, y, z] = axis.map(|v| v / n);
    let (s, c) = angle.sin_cos();
    let t = 1.0 - c;
    [
        [t * x * x + c, t * x * y - s * z, t * x * z + s * y],
        [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
        [t * x * z - s * y, t * y * z + s * x, t * z * z + c],
    ]
}

fn max_diff(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> f64 {
    (0..9)
        .map(|k| (a[k / 3][k % 3] - b[k / 3][k % 3]).abs())
        .fold(0.0, f64::max)
}

#[test]
fn pairs_give_back_the_transform_that_made_them() {
    let mut rng = Rng(3);
    let truth = Transform {
        rotation: rotation([0.3, -1.0, 0.5], 1.9),
        translation: [0.12, -3.4, 0.7],
        scale: 0.001, // millimetres to metres
    };
    let from: Vec<[f64; 3]> = (0..7)
        .map(|_| [100.0 * rng.sym(), 80.0 * rng.sym(), 5.0 * rng.sym()])
        .collect();
    let to: Vec<[f64; 3]> = from.iter().map(|p| truth.apply(*p)).collect();
    let fit = fit_pairs(&from, &to, true).unwrap();
    assert!(max_diff(&fit.transform.rotation, &truth.rotation) < 1e-12);
    assert!((fit.transform.scale / 0.001 - 1.0).abs() < 1e-12);
    assert!(fit.rms() < 1e-14);
    // without scale the fit is the best rotation of the unscaled points: the residuals are what
    // the scale explains, the rotation is still exact
    let rigid_from: Vec<[f64; 3]> = from.iter().map(|p| p.map(|v| v * 0.001)).collect();
    let fit = fit_pairs(&rigid_from, &to, false).unwrap();
    assert_eq!(fit.transform.scale, 1.0);
    assert!(max_diff(&fit.transform.rotation, &truth.rotation) < 1e-12);
    assert!((fit.transform.angle_degrees() - 1.9f64.to_degrees()).abs() < 1e-9);
    // mirrored points get the best proper rotation, never a reflection
    let mirrored: Vec<[f64; 3]> = to.iter().map(|p| [-p[0], p[1], p[2]]).collect();
    let fit = fit_pairs(&from, &mirrored, true).unwrap();
    let r = fit.transform.rotation;
    let det = r[0][0] * (r[1][1] * r[2][2] - r[1][2] * r[2][1])
        - r[0][1] * (r[1][0] * r[2][2] - r[1][2] * r[2][0])
        + r[0][2] * (r[1][0] * r[2][1] - r[1][1] * r[2][0]);
    assert!((det - 1.0).abs() < 1e-12);
    assert!(fit.rms() > 1e-3);
}

#[test]
fn too_few_collinear_or_non_finite_pairs_are_refused() {
    let err = |r: Result<_, FemError>| r.unwrap_err().to_string();
    let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]];
    assert!(
        err(fit_pairs(&p, &p, false))
            .contains("2 point pair(s) given: a rotation needs at least three")
    );
    let line = [
        [0.0, 0.0, 0.0],
        [1.0, 1.0, 1.0],
        [2.0, 2.0, 2.0],
        [3.0, 3.0, 3.0],
    ];
    assert!(err(fit_pairs(&line, &line, false)).contains("lie on one line"));
    let nan = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, f64::NAN, 0.0]];
    assert!(err(fit_pairs(&nan, &nan, false)).contains("non-finite"));
    assert!(
        err(fit_pairs(&line, &line[..3], false)).contains("4 test points against 3 model points")
    );
}

/// Distance from `p` to the boundary of the box `[0, l]`.
fn box_distance(p: [f64; 3], l: [f64; 3]) -> f64 {
    let inside = (0..3).all(|i| p[i] >= 0.0 && p[i] <= l[i]);
    if inside {
        (0..3)
            .map(|i| p[i].min(l[i] - p[i]))
            .fold(f64::INFINITY, f64::min)
    } else {
        (0..3)
            .map(|i| (0.0f64).max(-p[i]).max(p[i] - l[i]).powi(2))
            .sum::<f64>()
            .sqrt()
    }
}

#[test]
fn nearest_boundary_points_of_a_box() {
    let l = [0.5, 0.2, 0.05];
    let mut rng = Rng(11);
    for cells in [BoxCells::Hex, BoxCells::Tet5, BoxCells::Wedge] {
        let mesh = box_mesh(&BoxSpec::new(l, [10, 4, 2], cells, false)).unwrap();
        let surface = Surface::new(&mesh);
        for _ in 0..200 {
            let p = [
                0.25 + 0.4 * rng.sym(),
                0.1 + 0.2 * rng.sym(),
                0.025 + 0.1 * rng.sym(),
            ];
            let (q, d) = surface.nearest(p).unwrap();
            assert!(
                (d - box_distance(p, l)).abs() < 1e-12,
                "{cells:?} {p:?}: {d}"
            );
            assert!(box_distance(q, l) < 1e-12);
        }
    }
}

/// Points on the faces of an L-shaped body: two boxes, so that no symmetry maps it to itself.
fn l_body() -> (Mesh, Vec<[f64; 3]>) {
    let mut mesh = Mesh::new();
    let mut rng = Rng(21);
    // cells of 0.05 m on the L: x in [0, 0.4], y in [0, 0.1]  plus  x in [0, 0.1], y in [0.1, 0.3]
    let h = 0.05;
    let node = |i: usize, j: usize, k: usize| (1 + i + 20 * j + 400 * k) as u64;
    let cell_in = |i: usize, j: usize| (i < 8 && j < 2) || (i < 2 && j < 6);
    for k in 0..2 {
        for j in 0..7 {
            for i in 0..9 {
                mesh.add_node(node(i, j, k), [i as f64 * h, j as f64 * h, k as f64 * 0.02])
                    .unwrap();
            }
        }
    }
    let mut id = 1;
    for j in 0..6 {
        for i in 0..8 {
            if cell_in(i, j) {
                let n = [
                    node(i, j, 0),
                    node(i + 1, j, 0),
                    node(i + 1, j + 1, 0),
                    node(i, j + 1, 0),
                    node(i, j, 1),
                    node(i + 1, j, 1),
                    node(i + 1, j + 1, 1),
                    node(i, j + 1, 1),
                ];
                mesh.add_element(id, ElementKind::Hex8, &n).unwrap();
                id += 1;
            }
        }
    }
    // test points on the top face z = 0.02 and the outer edges
    let mut points = Vec::new();
    while points.len() < 12 {
        let (x, y) = (0.2 + 0.2 * rng.sym(), 0.15 + 0.15 * rng.sym());
        let (i, j) = ((x / h) as usize, (y / h) as usize);
        if cell_in(i, j) {
            points.push([x, y, 0.02]);
        }
    }
    points.push([0.4, 0.05, 0.01]);
    points.push([0.05, 0.3, 0.01]);
    points.push([0.0, 0.2, 0.0]);
    (mesh, points)
}

#[test]
fn iterative_closest_points_recover_a_known_placement() {
    let (mesh, points) = l_body();
    let surface = Surface::new(&mesh);
    // the test's frame: rotated 4 degrees and offset 3 mm from the model's
    let placement = Transform {
        rotation: rotation([0.2, 0.4, 1.0], 4f64.to_radians()),
        translation: [0.003, -0.002, 0.001],
        scale: 1.0,
    };
    let test: Vec<[f64; 3]> = points.iter().map(|p| placement.apply(*p)).collect();
    let fit = fit_surface(&test, &surface, Transform::IDENTITY, false).unwrap();
    assert!(fit.rms() < 1e-9, "{}", fit.rms());
    for (t, p) in test.iter().zip(&points) {
        let back = fit.transform.apply(*t);
        assert!(
            (0..3).all(|i| (back[i] - p[i]).abs() < 1e-7),
            "{back:?} vs {p:?}"
        );
    }
    // from far away (80 degrees, 0.5 m)
    let far = Transform {
        rotation: rotation([1.0, -0.3, 0.4], 80f64.to_radians()),
        translation: [0.5, 0.2, -0.3],
        scale: 1.0,
    };
    let test: Vec<[f64; 3]> = points.iter().map(|p| far.apply(*p)).collect();
    let auto = fit_auto(&test, &surface, false).unwrap();
    assert!(auto.rms() < 1e-9, "auto {}", auto.rms());
    for (t, p) in test.iter().zip(&points) {
        let back = auto.transform.apply(*t);
        assert!(
            (0..3).all(|i| (back[i] - p[i]).abs() < 1e-7),
            "{back:?} vs {p:?}"
        );
    }
    // upside down and turned (150 degrees)
    let flipped = Transform {
        rotation: rotation([0.1, 0.2, 1.0], 150f64.to_radians()),
        translation: [-0.2, 0.4, 0.1],
        scale: 1.0,
    };
    let test: Vec<[f64; 3]> = points.iter().map(|p| flipped.apply(*p)).collect();
    let auto = fit_auto(&test, &surface, false).unwrap();
    assert!(auto.rms() < 1e-9, "auto {}", auto.rms());
}

/// With a fitted scale, the fit measures distances in the wireframe's units: in the model's units
/// shrinking the wireframe onto one point of the surface drives every distance to zero, and the
/// fit collapsed to a scale of 0 (`--align auto --align-scale` on a wireframe in millimetres read
/// as metres printed scale 0.000000 and paired nothing; here 7.6e-12). The wireframe is the
/// L-body's nodes on its top and bottom faces (the thickness between them fixes the scale; points
/// on one face alone would leave it free): 3 % large, from the rigid part of its placement, and
/// 1000 times large and 60 degrees away through the automatic starts, the scale and the placement
/// come back to 1e-9.
#[test]
fn a_fitted_scale_does_not_collapse_the_wireframe() {
    let (mesh, _) = l_body();
    // the nodes the elements use (the grid's nodes in the L's notch belong to none)
    let mut used = vec![false; mesh.node_count()];
    for e in mesh.elements() {
        for n in e.nodes {
            used[*n] = true;
        }
    }
    let points: Vec<[f64; 3]> = (0..mesh.node_count())
        .filter(|i| used[*i])
        .map(|i| mesh.coords()[i])
        .collect();
    let surface = Surface::new(&mesh);
    let placed = |scale: f64| Transform {
        rotation: rotation([0.3, -0.2, 1.0], 60f64.to_radians()),
        translation: [0.05, -0.02, 0.03],
        scale,
    };
    // the inverse placement without its scale: R^T (x - t)
    let rigid_inverse = |t: &Transform| {
        let rt: [[f64; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|k| t.rotation[k][i]));
        Transform {
            rotation: rt,
            translation: std::array::from_fn(|i| {
                -(0..3).map(|k| rt[i][k] * t.translation[k]).sum::<f64>()
            }),
            scale: 1.0,
        }
    };
    let place = |t: &Transform| -> Vec<[f64; 3]> { points.iter().map(|p| t.apply(*p)).collect() };
    let (small, large) = (placed(1.03), placed(1000.0));
    let (t_small, t_large) = (place(&small), place(&large));
    for (scale, test, fit) in [
        (
            1.03,
            &t_small,
            fit_surface(&t_small, &surface, rigid_inverse(&small), true).unwrap(),
        ),
        (
            1000.0,
            &t_large,
            fit_auto(&t_large, &surface, true).unwrap(),
        ),
    ] {
        assert!(
            (fit.transform.scale * scale - 1.0).abs() < 1e-9,
            "scale {}",
            fit.transform.scale
        );
        for (t, p) in test.iter().zip(&points) {
            let back = fit.transform.apply(*t);
            assert!(
                (0..3).all(|i| (back[i] - p[i]).abs() < 1e-9),
                "{back:?} vs {p:?}"
            );
        }
    }
}
