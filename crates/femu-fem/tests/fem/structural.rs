//! Beams, rods, springs and bushings against hand-written matrices, analytic beam theory
//! (Euler-Bernoulli and Timoshenko) and spring-mass systems solved by hand.

use femu_fem::assembly::MassKind;
use femu_fem::mesh::Mesh;
use femu_fem::model::Model;
use femu_fem::structural::{
    Beam, BeamSection, Bushing, Part, Rod, Spring, SpringEnd, StructuralElement, StructuralKind,
    timoshenko_shape,
};
use femu_sparse::dense::generalized_symmetric_eigenvalues;
use femu_sparse::eigen::{EigenOptions, Which};
use std::f64::consts::PI;

const E: f64 = 210e9;
const NU: f64 = 0.3;
const RHO: f64 = 7850.0;

fn g() -> f64 {
    E / (2.0 * (1.0 + NU))
}

/// A rectangular section `b x h` (plane 1 bends over the height `h` along local y).
fn rect(b: f64, h: f64, shear: bool) -> BeamSection {
    super::common::rect_section(b, h, shear)
}

fn beam(section: BeamSection, orientation: [f64; 3]) -> StructuralKind {
    super::common::beam_kind((E, NU, RHO), section, orientation)
}

/// A straight beam of `n` elements from the origin along `dir` (unit), nodes 1..=n+1.
fn beam_model(n: usize, length: f64, dir: [f64; 3], kind: StructuralKind) -> Model {
    let mut mesh = Mesh::new();
    for i in 0..=n {
        let s = length * i as f64 / n as f64;
        mesh.add_node(i as u64 + 1, [s * dir[0], s * dir[1], s * dir[2]])
            .unwrap();
    }
    let mut model = Model::new(mesh).unwrap();
    for i in 0..n {
        model
            .add_structural(StructuralElement {
                id: 100 + i as u64,
                nodes: vec![i, i + 1],
                kind,
            })
            .unwrap();
    }
    model
}

fn lowest(model: &Model, mass: MassKind, count: usize) -> Vec<f64> {
    let sys = model.assemble(mass).unwrap();
    sys.modes(Which::Lowest(count), &EigenOptions::default())
        .unwrap()
        .values
}

fn element_matrices(
    el: &StructuralElement,
    coords: &[[f64; 3]],
) -> (faer::Mat<f64>, faer::Mat<f64>) {
    let m = el.matrices(coords, MassKind::Consistent).unwrap();
    let n = 3 * m.parts.len();
    (
        faer::Mat::from_fn(n, n, |i, j| m.k[i * n + j]),
        faer::Mat::from_fn(n, n, |i, j| m.m[i * n + j]),
    )
}

/// The closed-form stiffness is the energy of the interdependent shape functions (differentiated
/// here by central differences, integrated by a 2,000-interval midpoint rule): the shape
/// functions the mass is built from belong to that stiffness.
#[test]
fn the_timoshenko_shape_functions_carry_the_exact_stiffness() {
    let (l, ei, kga) = (0.7, 3.0e5, 2.0e6);
    let phi = 12.0 * ei / (kga * l * l);
    let n = 2000;
    let h = 1e-6;
    let mut k = [[0.0; 4]; 4];
    for s in 0..n {
        let xi = (s as f64 + 0.5) / n as f64;
        let (w, t) = timoshenko_shape(xi, l, phi);
        let (_, tp) = timoshenko_shape(xi + h, l, phi);
        let (_, tm) = timoshenko_shape(xi - h, l, phi);
        let (wp, _) = timoshenko_shape(xi + h, l, phi);
        let (wm, _) = timoshenko_shape(xi - h, l, phi);
        let _ = w;
        for a in 0..4 {
            for b in 0..4 {
                let kappa = |i: usize| (tp[i] - tm[i]) / (2.0 * h * l);
                let gamma = |i: usize| (wp[i] - wm[i]) / (2.0 * h * l) - t[i];
                k[a][b] += l / n as f64 * (ei * kappa(a) * kappa(b) + kga * gamma(a) * gamma(b));
            }
        }
    }
    let c = ei / ((1.0 + phi) * l.powi(3));
    let exact = [
        [12.0, 6.0 * l, -12.0, 6.0 * l],
        [6.0 * l, (4.0 + phi) * l * l, -6.0 * l, (2.0 - phi) * l * l],
        [-12.0, -6.0 * l, 12.0, -6.0 * l],
        [6.0 * l, (2.0 - phi) * l * l, -6.0 * l, (4.0 + phi) * l * l],
    ];
    for a in 0..4 {
        for b in 0..4 {
            let want = c * exact[a][b];
            assert!(
                (k[a][b] - want).abs() < 1e-6 * c * 12.0 * l * l,
                "K[{a}][{b}] = {} against {want}",
                k[a][b]
            );
        }
    }
}

/// A cantilever of one element under a tip load deflects `P L^3 / (3 E I) + P L / (k G A)`
/// (Timoshenko's flexibility, exact), in both planes of a beam turned in space; axial and
/// torsional flexibilities are `L / (E A)` and `L / (G J)`.
#[test]
fn one_element_cantilever_has_the_exact_flexibility() {
    let sec = rect(0.03, 0.05, true);
    let dir = [1.0 / 3f64.sqrt(), 1.0 / 3f64.sqrt(), 1.0 / 3f64.sqrt()];
    let v = [0.0, 0.0, 1.0];
    let l = 0.4;
    let el = StructuralElement {
        id: 1,
        nodes: vec![0, 1],
        kind: beam(sec, v),
    };
    let coords = [[0.0; 3], [l * dir[0], l * dir[1], l * dir[2]]];
    let (k, _) = element_matrices(&el, &coords);
    // free end: rows 6..12
    let kff = nalgebra::DMatrix::from_fn(6, 6, |i, j| k[(6 + i, 6 + j)]);
    let flex = kff.try_inverse().unwrap();
    let (_, axes) = femu_fem::structural::line_axes(coords[0], coords[1], v).unwrap();
    let ga = g() * sec.area * 5.0 / 6.0;
    let cases = [
        (axes[0], 0, l / (E * sec.area)),
        (axes[1], 0, l.powi(3) / (3.0 * E * sec.i1) + l / ga),
        (axes[2], 0, l.powi(3) / (3.0 * E * sec.i2) + l / ga),
        (axes[0], 3, l / (g() * sec.j)),
    ];
    for (d, block, want) in cases {
        let mut got = 0.0;
        for i in 0..3 {
            for j in 0..3 {
                got += d[i] * flex[(block + i, block + j)] * d[j];
            }
        }
        assert!((got / want - 1.0).abs() < 1e-10, "{got} against {want}");
    }
}

/// With `phi = 0` the consistent mass is the textbook Euler-Bernoulli one, `rho A L / 420 [[156,
/// 22L, 54, -13L], ...]`, and the axial block `rho A L / 6 [[2, 1], [1, 2]]`.
#[test]
fn euler_bernoulli_mass_is_the_textbook_matrix() {
    let sec = rect(0.02, 0.04, false);
    let l = 0.5;
    let el = StructuralElement {
        id: 1,
        nodes: vec![0, 1],
        kind: beam(sec, [0.0, 1.0, 0.0]),
    };
    let (_, m) = element_matrices(&el, &[[0.0; 3], [l, 0.0, 0.0]]);
    let c = RHO * sec.area * l / 420.0;
    // plane 1: (v1, theta_z1, v2, theta_z2) = (1, 5, 7, 11)
    let book = [
        [156.0, 22.0 * l, 54.0, -13.0 * l],
        [22.0 * l, 4.0 * l * l, 13.0 * l, -3.0 * l * l],
        [54.0, 13.0 * l, 156.0, -22.0 * l],
        [-13.0 * l, -3.0 * l * l, -22.0 * l, 4.0 * l * l],
    ];
    let d = [1, 5, 7, 11];
    for a in 0..4 {
        for b in 0..4 {
            assert!(
                (m[(d[a], d[b])] - c * book[a][b]).abs() < 1e-12 * c * 156.0,
                "M[{a}][{b}]"
            );
        }
    }
    let axial = RHO * sec.area * l / 6.0;
    assert!((m[(0, 0)] - 2.0 * axial).abs() < 1e-12 * axial);
    assert!((m[(0, 6)] - axial).abs() < 1e-12 * axial);
}

/// A free beam element turned in space, with offsets, has exactly six zero eigenvalues (dense,
/// against its mass), and its rigid translations carry `rho A L`.
#[test]
fn a_free_beam_has_six_rigid_body_modes() {
    let sec = BeamSection {
        nsm: 0.7,
        ..rect(0.02, 0.05, true)
    };
    let el = StructuralElement {
        id: 1,
        nodes: vec![0, 1],
        kind: StructuralKind::Beam(Beam {
            e: E,
            g: g(),
            rho: RHO,
            section: sec,
            taper: None,
            orientation: [0.3, -1.0, 0.2],
            offsets: [[0.0, 0.01, 0.02], [0.01, -0.02, 0.0]],
            lumped_torsion: false,
            coupled_torsion: true,
            releases: [[false; 6]; 2],
        }),
    };
    let coords = [[0.1, 0.2, 0.3], [0.5, 0.6, 0.1]];
    let (k, m) = element_matrices(&el, &coords);
    let vals = generalized_symmetric_eigenvalues(k.as_ref(), m.as_ref()).unwrap();
    let top = vals.last().unwrap();
    let zeros = vals.iter().filter(|v| v.abs() < 1e-9 * top).count();
    assert_eq!(zeros, 6, "{vals:?}");
    let ends: [[f64; 3]; 2] = [[0.1, 0.21, 0.32], [0.51, 0.58, 0.1]];
    let l = ((0..3)
        .map(|i| (ends[1][i] - ends[0][i]).powi(2))
        .sum::<f64>())
    .sqrt();
    let total = (RHO * sec.area + 0.7) * l;
    for dir in 0..3 {
        let u: Vec<f64> = (0..12)
            .map(|i| if i % 6 == dir { 1.0 } else { 0.0 })
            .collect();
        let mut mu = 0.0;
        for i in 0..12 {
            for j in 0..12 {
                mu += u[i] * m[(i, j)] * u[j];
            }
        }
        assert!((mu / total - 1.0).abs() < 1e-12, "{mu} against {total}");
    }
}

/// A cantilever's bending frequencies converge to Euler-Bernoulli's, `(beta_n L)^2 sqrt(E I /
/// (rho A L^4))` with `beta L = 1.8751, 4.6941, 7.8548, 10.9955` (roots of `cos cosh = -1`), in both
/// planes of a beam along a skew axis.
#[test]
fn cantilever_frequencies_converge_to_euler_bernoulli() {
    let (b, h, l) = (0.01, 0.02, 1.0);
    let sec = rect(b, h, false);
    let dir = [0.6, 0.0, 0.8];
    let mut model = beam_model(40, l, dir, beam(sec, [0.0, 1.0, 0.0]));
    model.fix_node_dofs(1, &[0, 1, 2, 3, 4, 5]).unwrap();
    let vals = lowest(&model, MassKind::Consistent, 6);
    // cos(x) cosh(x) = -1 solved here by bisection
    let root = |lo: f64, hi: f64| {
        let f = |x: f64| x.cos() * x.cosh() + 1.0;
        let (mut a, mut c) = (lo, hi);
        for _ in 0..200 {
            let m = 0.5 * (a + c);
            if f(a) * f(m) <= 0.0 { c = m } else { a = m }
        }
        0.5 * (a + c)
    };
    let betas = [
        root(1.0, 3.0),
        root(4.0, 5.5),
        root(7.0, 9.0),
        root(10.0, 12.0),
    ];
    let mut expected: Vec<f64> = Vec::new();
    for i in [sec.i1, sec.i2] {
        for bl in betas {
            expected.push(bl.powi(4) * E * i / (RHO * sec.area * l.powi(4)));
        }
    }
    // the first torsion mode and the axial mode are far above these six
    expected.sort_by(f64::total_cmp);
    for (got, want) in vals.iter().zip(&expected[..6]) {
        // 6.7e-9 on the first two, 2.6e-7 and 2.1e-6 on the next (the error falls as h^4)
        assert!((got / want - 1.0).abs() < 1e-5, "{got} against {want}");
    }
}

/// A simply supported deep beam (L/h = 5) against Timoshenko's frequency equation with shear and
/// rotary inertia, `(rho A w^2 - k G A q^2)(rho I w^2 - E I q^2 - k G A) = (k G A q)^2` for
/// `q = n pi / L`, which differs from Euler-Bernoulli's by 3-13 % on these modes.
#[test]
fn deep_simply_supported_beam_matches_timoshenko() {
    let (b, h, l) = (0.1, 0.2, 1.0);
    let sec = rect(b, h, true);
    let mut model = beam_model(120, l, [1.0, 0.0, 0.0], beam(sec, [0.0, 1.0, 0.0]));
    model.fix_node_dofs(1, &[0, 1, 2, 3]).unwrap();
    model.fix_node_dofs(121, &[1, 2]).unwrap();
    let vals = lowest(&model, MassKind::Consistent, 6);
    let timoshenko = |i: f64, n: f64| {
        super::common::timoshenko_simply_supported(E, g(), RHO, sec.area, i, 5.0 / 6.0, l, n)
    };
    let eb = |i: f64, n: f64| (n * PI / l).powi(4) * E * i / (RHO * sec.area);
    let mut bending: Vec<(f64, f64)> = Vec::new();
    for i in [sec.i1, sec.i2] {
        for n in [1.0, 2.0, 3.0] {
            bending.push((timoshenko(i, n), eb(i, n)));
        }
    }
    bending.sort_by(|a, b| a.0.total_cmp(&b.0));
    // the bending modes among the model's lowest (the axial and torsional ones are interleaved
    // above the first few): each Timoshenko value is matched by one computed value
    for (want, eb) in bending.iter().take(3) {
        let got = vals
            .iter()
            .min_by(|a, b| (*a / want - 1.0).abs().total_cmp(&(*b / want - 1.0).abs()))
            .unwrap();
        // the shear strain is constant in an element, so the error falls as h^2: 1.4e-6, 5.1e-6
        // and 2.0e-5 on these three with 120 elements, four times that with 60
        assert!((got / want - 1.0).abs() < 3e-5, "{got} against {want}");
        assert!(
            (eb / want - 1.0).abs() > 0.03,
            "shear matters here: {eb} {want}"
        );
    }
}

/// Two masses on a spring along a skew direction: `w^2 = k (m1 + m2) / (m1 m2)`; the same
/// spring to ground under one mass: `w^2 = k / m`; a grounded bushing with rotated axes under a
/// rigid mass with inertia: `k_i / m` along each axis and `k_{3+i} / J_i` about it.
#[test]
fn springs_and_bushings_match_hand_solved_oscillators() {
    let d = [0.0, 0.6, 0.8];
    let mut mesh = Mesh::new();
    mesh.add_node(1, [0.0; 3]).unwrap();
    mesh.add_node(2, [0.0, 0.3, 0.4]).unwrap();
    let mut model = Model::new(mesh).unwrap();
    let (k, m1, m2) = (4.0e4, 2.0, 3.0);
    let end = |node| SpringEnd {
        node,
        part: Part::Translations,
        direction: d,
    };
    model
        .add_structural(StructuralElement {
            id: 1,
            nodes: vec![0, 1],
            kind: StructuralKind::Spring(Spring {
                k,
                ge: 0.0,
                viscous: 0.0,
                mass: 0.0,
                a: end(0),
                b: Some(end(1)),
            }),
        })
        .unwrap();
    model.add_point_mass(1, m1).unwrap();
    model.add_point_mass(2, m2).unwrap();
    let vals = lowest(&model, MassKind::Consistent, 6);
    // five rigid motions (the spring acts along d only), one oscillation
    let want = k * (m1 + m2) / (m1 * m2);
    assert!((vals[5] / want - 1.0).abs() < 1e-10, "{vals:?}");
    assert!(vals[4].abs() < 1e-8 * want);

    // a bushing to ground, axes turned about z by 30 degrees, at the node
    let (c, s) = ((PI / 6.0).cos(), (PI / 6.0).sin());
    let axes = [[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]];
    let kb = [1.0e4, 2.0e4, 3.0e4, 500.0, 700.0, 900.0];
    let mut mesh = Mesh::new();
    mesh.add_node(7, [0.2, 0.1, 0.0]).unwrap();
    let mut model = Model::new(mesh).unwrap();
    model
        .add_structural(StructuralElement {
            id: 5,
            nodes: vec![0],
            kind: StructuralKind::Bushing(Bushing {
                k: kb,
                b: [0.0; 6],
                ge: 0.0,
                axes,
                point: None,
            }),
        })
        .unwrap();
    // inertia diagonal in the bushing's axes: J = R^T diag(j) R in basic axes
    let jd = [0.5, 0.7, 0.9];
    let mut jb = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            jb[i][j] = (0..3).map(|a| axes[a][i] * jd[a] * axes[a][j]).sum();
        }
    }
    let mass = 10.0;
    model.add_rigid_mass(7, mass, [0.0; 3], jb).unwrap();
    let vals = lowest(&model, MassKind::Consistent, 6);
    let mut want: Vec<f64> = (0..3)
        .map(|i| kb[i] / mass)
        .chain((0..3).map(|i| kb[3 + i] / jd[i]))
        .collect();
    want.sort_by(f64::total_cmp);
    for (g, w) in vals.iter().zip(&want) {
        assert!((g / w - 1.0).abs() < 1e-10, "{vals:?} against {want:?}");
    }
}

/// A rod's axial frequencies, fixed-free: `w_n = (2n - 1) pi / (2 L) sqrt(E / rho)`, converged
/// with 40 consistent-mass elements (error of order `(h w)^2`); torsion of the same rod with
/// `J = I_p` (a circular section) the same with `G`. The rotations no element stiffens are fixed
/// by the model, so that nothing is singular.
#[test]
fn rod_axial_and_torsion_frequencies_converge() {
    let (r, l) = (0.01, 2.0);
    let area = PI * r * r;
    let j = PI * r.powi(4) / 2.0;
    let kind = StructuralKind::Rod(Rod {
        e: E,
        g: g(),
        rho: RHO,
        area,
        j,
        nsm: 0.0,
    });
    let mut model = beam_model(40, l, [0.0, 0.0, 1.0], kind);
    model.fix_node_dofs(1, &[0, 1, 2, 3, 4, 5]).unwrap();
    // transverse translations have no stiffness: fixed here; the rotations about x and y have
    // none either, and the model fixes them itself (as Nastran's AUTOSPC would)
    for n in 2..=41 {
        model.fix_node_dofs(n, &[0, 1]).unwrap();
    }
    let vals = lowest(&model, MassKind::Consistent, 4);
    let mut want: Vec<f64> = [1.0, 3.0]
        .iter()
        .flat_map(|k| {
            let w = k * PI / (2.0 * l);
            [w * w * E / RHO, w * w * g() / RHO]
        })
        .collect();
    want.sort_by(f64::total_cmp);
    for (got, w) in vals.iter().zip(&want) {
        assert!((got / w - 1.0).abs() < 2e-3, "{got} against {w}");
    }
}

/// Bad values and geometry are refused with the element's id: a zero area, an orientation
/// vector along the axis, a bushing without stiffness or damping, coincident beam ends, a duplicate
/// id.
#[test]
fn bad_structural_elements_are_refused_by_id() {
    let mut mesh = Mesh::new();
    mesh.add_node(1, [0.0; 3]).unwrap();
    mesh.add_node(2, [1.0, 0.0, 0.0]).unwrap();
    mesh.add_node(3, [0.0; 3]).unwrap();
    let mut model = Model::new(mesh).unwrap();
    let try_add = |model: &mut Model, id: u64, nodes: Vec<usize>, kind| {
        model
            .add_structural(StructuralElement { id, nodes, kind })
            .map_err(|e| e.to_string())
    };
    let zero_area = BeamSection {
        area: 0.0,
        ..rect(0.01, 0.01, false)
    };
    let e = try_add(&mut model, 9, vec![0, 1], beam(zero_area, [0.0, 1.0, 0.0])).unwrap_err();
    assert!(e.contains("element 9") && e.contains("area"), "{e}");
    let e = try_add(
        &mut model,
        9,
        vec![0, 1],
        beam(rect(0.01, 0.01, false), [2.0, 0.0, 0.0]),
    )
    .unwrap_err();
    assert!(e.contains("parallel"), "{e}");
    let e = try_add(
        &mut model,
        9,
        vec![0, 2],
        beam(rect(0.01, 0.01, false), [0.0, 1.0, 0.0]),
    )
    .unwrap_err();
    assert!(e.contains("coincide"), "{e}");
    let e = try_add(
        &mut model,
        9,
        vec![0, 2],
        StructuralKind::Bushing(Bushing {
            k: [0.0; 6],
            b: [0.0; 6],
            ge: 0.02,
            axes: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            point: None,
        }),
    )
    .unwrap_err();
    assert!(e.contains("neither stiffness nor damping"), "{e}");
    try_add(
        &mut model,
        9,
        vec![0, 1],
        beam(rect(0.01, 0.01, false), [0.0, 1.0, 0.0]),
    )
    .unwrap();
    let e = try_add(
        &mut model,
        9,
        vec![0, 1],
        beam(rect(0.01, 0.01, false), [0.0, 1.0, 0.0]),
    )
    .unwrap_err();
    assert!(e.contains("duplicate element id 9"), "{e}");
}

/// NAFEMS FV2 (pin-ended double cross, in-plane vibration): eight arms 5 m long at 45 degrees,
/// square section 0.125 m, E = 200 GPa, rho = 8000, the arms' ends pinned (in-plane translations
/// held). The reference frequencies (NAFEMS, "Selected Benchmarks for Natural Frequency Analysis",
/// 1987, test 2): 11.336 Hz, seven at 17.709 Hz, 45.345 Hz, seven at 57.390 Hz. With 16
/// Euler-Bernoulli beams per arm twelve of them are within 3e-5; the two pairs in which the centre
/// moves are 0.16 % and 0.55 % lower (OptiStruct's CBAR reports 0.9958 and 0.9944 of the reference
/// on the same modes), because the reference's arms do not stretch: made inextensible (area x 1e4,
/// density / 1e4, the same mass), all sixteen are within 3e-5. NAFEMS's mesh, four beams per arm,
/// is within 0.7 % of every reference.
#[test]
fn nafems_fv2_pin_ended_double_cross() {
    let solve = |per_arm: usize, stretch: f64| -> Vec<f64> {
        let mut mesh = Mesh::new();
        mesh.add_node(1, [0.0; 3]).unwrap();
        let mut ends = Vec::new();
        for arm in 0..8 {
            let a = arm as f64 * PI / 4.0;
            for k in 1..=per_arm {
                let s = 5.0 * k as f64 / per_arm as f64;
                let id = (2 + arm * per_arm + k - 1) as u64;
                mesh.add_node(id, [s * a.cos(), s * a.sin(), 0.0]).unwrap();
                if k == per_arm {
                    ends.push(id);
                }
            }
        }
        let mut model = Model::new(mesh).unwrap();
        let h = 0.125;
        let section = BeamSection {
            area: h * h * stretch,
            i1: h.powi(4) / 12.0,
            i2: h.powi(4) / 12.0,
            j: 0.1406 * h.powi(4),
            shear: None,
            nsm: 0.0,
        };
        let kind = StructuralKind::Beam(Beam {
            e: 2.0e11,
            g: 2.0e11 / 2.6,
            rho: 8000.0 / stretch,
            section,
            taper: None,
            orientation: [0.0, 0.0, 1.0],
            offsets: [[0.0; 3]; 2],
            lumped_torsion: false,
            coupled_torsion: true,
            releases: [[false; 6]; 2],
        });
        for arm in 0..8 {
            for k in 0..per_arm {
                let a = if k == 0 { 1 } else { 2 + arm * per_arm + k - 1 };
                let b = 2 + arm * per_arm + k;
                let nodes = [a, b].map(|n| model.mesh().node_index(n as u64).unwrap());
                model
                    .add_structural(StructuralElement {
                        id: (1000 + arm * per_arm + k) as u64,
                        nodes: nodes.to_vec(),
                        kind,
                    })
                    .unwrap();
            }
        }
        // in-plane vibration: the out-of-plane translation and rotations held everywhere
        for i in 0..model.mesh().node_count() {
            let id = model.mesh().node_id(i);
            let dofs: &[usize] = if ends.contains(&id) {
                &[0, 1, 2, 3, 4]
            } else {
                &[2, 3, 4]
            };
            model.fix_node_dofs(id, dofs).unwrap();
        }
        let sys = model.assemble(MassKind::Consistent).unwrap();
        let modes = sys
            .modes(Which::Lowest(16), &EigenOptions::default())
            .unwrap();
        modes.values.iter().map(|l| l.sqrt() / (2.0 * PI)).collect()
    };
    let mut reference = vec![11.336];
    reference.extend([17.709; 7]);
    reference.push(45.345);
    reference.extend([57.390; 7]);
    let errors =
        |f: Vec<f64>| -> Vec<f64> { f.iter().zip(&reference).map(|(f, r)| f / r - 1.0).collect() };
    let nafems = errors(solve(4, 1.0));
    assert!(nafems.iter().all(|e| e.abs() < 7e-3), "{nafems:?}");
    let fine = errors(solve(16, 1.0));
    for (i, e) in fine.iter().enumerate() {
        match i {
            1 | 2 => assert!((e + 1.59e-3).abs() < 1e-4, "{fine:?}"),
            9 | 10 => assert!((e + 5.47e-3).abs() < 1e-4, "{fine:?}"),
            _ => assert!(e.abs() < 3e-5, "{fine:?}"),
        }
    }
    let inextensible = errors(solve(16, 1e4));
    assert!(
        inextensible.iter().all(|e| e.abs() < 3e-5),
        "{inextensible:?}"
    );
}

/// A cantilever of `n` tapered beams along x (nodes 1..=n+1, node 1 clamped), length `l`, whose
/// properties follow `law(x / l)` (each element's ends on it), orientation y.
fn tapered_cantilever(n: usize, l: f64, law: impl Fn(f64) -> BeamSection) -> Model {
    let mut mesh = Mesh::new();
    for i in 0..=n {
        mesh.add_node(i as u64 + 1, [l * i as f64 / n as f64, 0.0, 0.0])
            .unwrap();
    }
    let mut model = Model::new(mesh).unwrap();
    for i in 0..n {
        let (a, b) = (i as f64 / n as f64, (i + 1) as f64 / n as f64);
        model
            .add_structural(StructuralElement {
                id: 100 + i as u64,
                nodes: vec![i, i + 1],
                kind: StructuralKind::Beam(Beam {
                    e: E,
                    g: g(),
                    rho: RHO,
                    section: law(a),
                    taper: Some(law(b)),
                    orientation: [0.0, 1.0, 0.0],
                    offsets: [[0.0; 3]; 2],
                    lumped_torsion: false,
                    coupled_torsion: true,
                    releases: [[false; 6]; 2],
                }),
            })
            .unwrap();
    }
    model.fix_node_dofs(1, &[0, 1, 2, 3, 4, 5]).unwrap();
    model
}

/// A tapered cantilever's tip under each unit load against the integrals of its flexibility in
/// closed form (docs/MATH.md, "Tapered beams"), written here: with a property `p (1 - c x / L)`,
/// `int_0^L dx / (1 - c x/L) = -(L / c) ln(1 - c)`, `int (L - x) / (...) =
/// (L^2 / c^2) [u + (c - 1) ln u]` and `int (L - x)^2 / (...) =
/// (L^3 / c^3) [u^2 / 2 + 2 (c - 1) u + (c - 1)^2 ln u]`, both from `u = 1 - c` to 1. A, I1, I2 and J taper by different ratios (0.6, 0.8, 0.3, 0.5)
/// and the beam is shear-flexible (`5/6`): the tip's stretch, twist, both deflections and
/// rotations under a force and a moment, on one element and on three, to 1e-10 (the element is
/// exact for statics).
#[test]
fn a_tapered_cantilever_deflects_as_its_flexibility_integrals() {
    use faer::linalg::solvers::Solve;
    let l = 2.0;
    let (a0, i10, i20, j0, kf) = (3e-4, 4e-8, 2.5e-8, 5e-8, 5.0 / 6.0);
    let (ca, ci1, ci2, cj) = (0.6, 0.8, 0.3, 0.5);
    let law = |t: f64| BeamSection {
        area: a0 * (1.0 - ca * t),
        i1: i10 * (1.0 - ci1 * t),
        i2: i20 * (1.0 - ci2 * t),
        j: j0 * (1.0 - cj * t),
        shear: Some([kf, kf]),
        nsm: 0.0,
    };
    let f0 = |c: f64| -(l / c) * (1.0 - c).ln();
    let f1 = |c: f64| {
        let at = |u: f64| u + (c - 1.0) * u.ln();
        l * l / (c * c) * (at(1.0) - at(1.0 - c))
    };
    let f2 = |c: f64| {
        let at = |u: f64| u * u / 2.0 + 2.0 * (c - 1.0) * u + (c - 1.0).powi(2) * u.ln();
        l.powi(3) / c.powi(3) * (at(1.0) - at(1.0 - c))
    };
    let (ga0, ei1, ei2) = (kf * g() * a0, E * i10, E * i20);
    for n in [1, 3] {
        let model = tapered_cantilever(n, l, law);
        let sys = model.assemble(MassKind::Consistent).unwrap();
        let k = femu_sparse::csc::to_dense(&sys.k);
        let tip = model.mesh().node_index(n as u64 + 1).unwrap();
        // translations on the node's point, rotations on its rotation point
        let rotations = sys.dofs.rotation_point(tip).unwrap();
        let dof = |c: usize| {
            let (p, c) = if c < 3 { (tip, c) } else { (rotations, c - 3) };
            sys.dofs.free_index(p, c).unwrap()
        };
        let solve = |c: usize| {
            let mut f = faer::Mat::<f64>::zeros(k.nrows(), 1);
            f[(dof(c), 0)] = 1.0;
            k.full_piv_lu().solve(&f)
        };
        let close = |got: f64, want: f64, what: &str| {
            assert!(
                (got / want - 1.0).abs() < 1e-10,
                "{n} elements, {what}: {got} against {want}"
            );
        };
        let (ux, uy, uz, tx, rz) = (solve(0), solve(1), solve(2), solve(3), solve(5));
        close(ux[(dof(0), 0)], f0(ca) / (E * a0), "stretch");
        close(tx[(dof(3), 0)], f0(cj) / (g() * j0), "twist");
        close(
            uy[(dof(1), 0)],
            f2(ci1) / ei1 + f0(ca) / ga0,
            "deflection in plane 1",
        );
        close(
            uy[(dof(5), 0)],
            f1(ci1) / ei1,
            "rotation under the force in plane 1",
        );
        close(
            rz[(dof(5), 0)],
            f0(ci1) / ei1,
            "rotation under the moment in plane 1",
        );
        close(
            uz[(dof(2), 0)],
            f2(ci2) / ei2 + f0(ca) / ga0,
            "deflection in plane 2",
        );
        close(
            -uz[(dof(4), 0)],
            f1(ci2) / ei2,
            "rotation under the force in plane 2",
        );
    }
}

/// A tapered Euler-Bernoulli cantilever (A and I falling linearly to half at the tip) against
/// a Rayleigh-Ritz solution written here: the basis `xi^2 .. xi^12` (clamped at `xi = 0`), whose
/// stiffness `int E I(xi) phi_i'' phi_j''` and mass `int m(xi) phi_i phi_j` are exact polynomial
/// integrals, solved densely (the 10- and 11-term bases agree to 1e-10 on the first two
/// eigenvalues and 2e-8 on the third). femu's tapered beams with the consistent mass converge to
/// it from above at fourth order (the error of the worst of three eigenvalues 1.1e-3, 7.4e-5 and
/// 4.7e-6 on 8, 16 and 32 elements; at least tenfold per halving asked, 1e-4 and 1e-5 on 16 and
/// 32); and a tapered element whose ends are equal is the prismatic element (K and M to
/// 1e-13).
#[test]
fn a_tapered_cantilever_s_frequencies_converge_to_rayleigh_ritz() {
    let (l, c): (f64, f64) = (1.5, 0.5);
    let (a0, i0) = (4e-4, 3e-8);
    let law = |t: f64| BeamSection {
        area: a0 * (1.0 - c * t),
        i1: i0 * (1.0 - c * t),
        i2: i0 * (1.0 - c * t),
        j: 2.0 * i0 * (1.0 - c * t),
        shear: None,
        nsm: 0.0,
    };
    let ritz = |terms: usize| -> Vec<f64> {
        let kk = faer::Mat::from_fn(terms, terms, |i, j| {
            let p = (i + j) as f64;
            let d = ((i + 2) * (i + 1) * (j + 2) * (j + 1)) as f64;
            E * i0 * d * (1.0 / (p + 1.0) - c / (p + 2.0)) / l.powi(3)
        });
        let mm = faer::Mat::from_fn(terms, terms, |i, j| {
            let p = (i + j) as f64;
            RHO * a0 * l * (1.0 / (p + 5.0) - c / (p + 6.0))
        });
        generalized_symmetric_eigenvalues(kk.as_ref(), mm.as_ref()).unwrap()[..3].to_vec()
    };
    // the 10- and 11-term bases: 1e-10 apart on the first two, 2e-8 on the third (the
    // monomials' conditioning stops the basis there)
    let (r10, reference) = (ritz(10), ritz(11));
    for (m, (a, b)) in r10.iter().zip(&reference).enumerate() {
        let tol = if m < 2 { 1e-10 } else { 2e-8 };
        assert!((a / b - 1.0).abs() < tol, "{r10:?} {reference:?}");
    }
    let mut previous: Option<f64> = None;
    for n in [8, 16, 32] {
        let model = tapered_cantilever(n, l, law);
        // bending in plane 1 alone: the first three of its modes (planes 1 and 2 are alike, so
        // each frequency appears twice; torsion and stretching are far above)
        let vals = lowest(&model, MassKind::Consistent, 6);
        let worst = (0..3)
            .map(|m| {
                let (p, q) = (vals[2 * m], vals[2 * m + 1]);
                assert!((p / q - 1.0).abs() < 1e-9, "{vals:?}");
                let e = p / reference[m] - 1.0;
                assert!(e > -2e-8, "{n}: {vals:?} below {reference:?}");
                e
            })
            .fold(0.0f64, f64::max);
        if let Some(p) = previous {
            assert!(worst < 0.1 * p, "{n}: {worst} after {p}");
        }
        let bound = match n {
            16 => 1e-4,
            32 => 1e-5,
            _ => 1.0,
        };
        assert!(worst < bound, "{n}: {worst}");
        previous = Some(worst);
    }
    // equal ends: the prismatic element
    let section = law(0.3);
    let coords = [[0.0, 0.0, 0.0], [0.4, 0.3, 0.2]];
    let element = |taper: Option<BeamSection>| StructuralElement {
        id: 1,
        nodes: vec![0, 1],
        kind: StructuralKind::Beam(Beam {
            e: E,
            g: g(),
            rho: RHO,
            section: BeamSection {
                shear: Some([0.8, 0.7]),
                ..section
            },
            taper: taper.map(|s| BeamSection {
                shear: Some([0.8, 0.7]),
                ..s
            }),
            orientation: [0.0, 0.0, 1.0],
            offsets: [[0.0; 3]; 2],
            lumped_torsion: true,
            coupled_torsion: true,
            releases: [[false; 6]; 2],
        }),
    };
    for mass in [MassKind::Consistent, MassKind::Lumped] {
        let p = element(None).matrices(&coords, mass).unwrap();
        let t = element(Some(section)).matrices(&coords, mass).unwrap();
        for (x, y) in [(&p.k, &t.k), (&p.m, &t.m)] {
            let top = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for (a, b) in x.iter().zip(y.iter()) {
                assert!((a - b).abs() < 1e-13 * top, "{mass:?}: {a} vs {b}");
            }
        }
    }
}

/// Beam section parameters (docs/MATH.md, "Beam section parameters"): on a skewed beam of eight
/// elements with offsets and a turned orientation, `K(p)` of a group `EA:`, `GJ:`, `EI1:` or
/// `EI2:` over four of them equals the stiffness assembled from scratch with that set's section
/// changed (`A (1 + p)`, `J (1 + p)`, or `I1 (1 + p)` with the plane's shear factor `(1 + p)`,
/// which keeps its `phi`), to 1e-12 of the largest entry, Timoshenko and Euler-Bernoulli alike;
/// the mass does not move. The four parts of any two-node beam, tapered ones included, sum to its
/// stiffness (1e-12). A released beam and a spring are refused in such a group.
#[test]
fn section_parameters_equal_beams_of_the_changed_section() {
    use femu_fem::assembly::Assembler;
    use femu_fem::groups::{GroupLaw, ParameterGroups};
    use femu_fem::structural::SectionPart;
    let d = {
        let v = [1.0f64, 0.5, 0.3];
        let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        [v[0] / n, v[1] / n, v[2] / n]
    };
    for shear in [true, false] {
        let mut kind = beam(rect(0.03, 0.05, shear), [0.2, 1.0, -0.4]);
        if let StructuralKind::Beam(b) = &mut kind {
            b.offsets = [[0.0, 0.01, 0.02], [0.005, -0.01, 0.0]];
        }
        let mut model = beam_model(8, 2.0, d, kind);
        model.fix_node_dofs(1, &[0, 1, 2, 3, 4, 5]).unwrap();
        let ids: Vec<u64> = (104..108).collect();
        model.add_structural_set("B", &ids).unwrap();
        let asm = Assembler::new(&model).unwrap();
        let base = asm.assemble(&model, MassKind::Consistent).unwrap();
        let p = 0.35;
        for part in SectionPart::ALL {
            let name = format!("{}B", part.prefix());
            let groups =
                ParameterGroups::from_element_sets(&model, &[name.as_str()], MassKind::Consistent)
                    .unwrap();
            assert_eq!(groups.law(0).unwrap(), GroupLaw::Section(part));
            let got = groups
                .parameterized(&model, &asm, &base, &[p], &[0.0])
                .unwrap();
            let mut direct = model.clone();
            for id in &ids {
                let i = direct.structural_index(*id).unwrap();
                let mut el = direct.structural()[i].clone();
                let StructuralKind::Beam(mut b) = el.kind else {
                    unreachable!()
                };
                let s = &mut b.section;
                match part {
                    SectionPart::Axial => s.area *= 1.0 + p,
                    SectionPart::Torsion => s.j *= 1.0 + p,
                    SectionPart::Bending1 | SectionPart::Bending2 => {
                        let plane = usize::from(part == SectionPart::Bending2);
                        if plane == 0 {
                            s.i1 *= 1.0 + p;
                        } else {
                            s.i2 *= 1.0 + p;
                        }
                        if let Some(k) = &mut s.shear {
                            k[plane] *= 1.0 + p;
                        }
                    }
                }
                if part == SectionPart::Axial
                    && let Some(k) = &mut s.shear
                {
                    // phi holds 1 / (k A): the shear stiffness k G A stays
                    k[0] /= 1.0 + p;
                    k[1] /= 1.0 + p;
                }
                el.kind = StructuralKind::Beam(b);
                direct.set_structural(i, el).unwrap();
            }
            let want = asm.assemble(&direct, MassKind::Consistent).unwrap();
            let scale = want.k.data().iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            for ((i, j, x), (k, l, y)) in
                femu_sparse::csc::entries(&got.k).zip(femu_sparse::csc::entries(&want.k))
            {
                assert_eq!((i, j), (k, l));
                assert!(
                    (x - y).abs() <= 1e-12 * scale,
                    "{name} shear {shear}: {x} {y}"
                );
            }
            assert_eq!(got.m.data(), base.m.data(), "{name}: the mass moved");
        }
        // the parts sum to the element's stiffness, a tapered beam's too
        let coords = model.mesh().coords().to_vec();
        let mut tapered = model.structural()[2].clone();
        if let StructuralKind::Beam(b) = &mut tapered.kind {
            let mut end = b.section;
            end.area *= 0.6;
            end.i1 *= 0.4;
            end.i2 *= 0.5;
            end.j *= 0.45;
            b.taper = Some(end);
        }
        for el in [model.structural()[0].clone(), tapered] {
            let k = el.matrices(&coords, MassKind::Consistent).unwrap().k;
            let mut sum = vec![0.0; k.len()];
            for part in SectionPart::ALL {
                let kp = el.section_part(&coords, part).unwrap().unwrap();
                for (s, v) in sum.iter_mut().zip(&kp) {
                    *s += v;
                }
            }
            let scale = k.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            for (a, b) in sum.iter().zip(&k) {
                assert!((a - b).abs() <= 1e-12 * scale, "{a} {b}");
            }
        }
    }
    // a released beam and a spring are refused
    let mut kind = beam(rect(0.03, 0.05, true), [0.0, 1.0, 0.0]);
    if let StructuralKind::Beam(b) = &mut kind {
        b.releases[1][5] = true;
    }
    let mut model = beam_model(2, 1.0, [1.0, 0.0, 0.0], kind);
    model.add_structural_set("R", &[100]).unwrap();
    let e = ParameterGroups::from_element_sets(&model, &["EI1:R"], MassKind::Lumped)
        .unwrap_err()
        .to_string();
    assert!(e.contains("end releases"), "{e}");
    let mut model = beam_model(
        2,
        1.0,
        [1.0, 0.0, 0.0],
        beam(rect(0.03, 0.05, true), [0.0, 1.0, 0.0]),
    );
    let spring = StructuralElement {
        id: 300,
        nodes: vec![2],
        kind: StructuralKind::Spring(Spring {
            k: 1e5,
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
    model.add_structural(spring).unwrap();
    model.add_structural_set("S", &[300]).unwrap();
    let e = ParameterGroups::from_element_sets(&model, &["GJ:S"], MassKind::Lumped)
        .unwrap_err()
        .to_string();
    assert!(e.contains("two-node beams; element 300"), "{e}");
}
