//! The three-node beam: rigid-body modes and mass of a curved element, no shear locking from
//! thickness ratios 1/10 to 1/1000, a deep simply supported beam against Timoshenko's frequency
//! equation, and a free circular ring against the classical ring frequencies in and out of its
//! plane.

use femu_fem::assembly::MassKind;
use femu_fem::mesh::Mesh;
use femu_fem::model::Model;
use femu_fem::structural::{Beam, BeamSection, StructuralElement, StructuralKind};
use femu_sparse::eigen::{EigenOptions, Which};
use std::f64::consts::PI;

const E: f64 = 2.0e11;
const NU: f64 = 0.3;
const RHO: f64 = 8000.0;

fn g() -> f64 {
    E / (2.0 * (1.0 + NU))
}

/// A rectangle `b x h` (plane 1 bends over `h`, along local y), shear factors 5/6.
fn rect(b: f64, h: f64) -> BeamSection {
    super::common::rect_section(b, h, true)
}

fn beam(section: BeamSection, orientation: [f64; 3]) -> StructuralKind {
    super::common::beam_kind((E, NU, RHO), section, orientation)
}

/// `n` three-node beams along the curve `place(s)`, `s` in `[0, 1]`: nodes `1 + k` at `s = k /
/// (2 n)` (the middle nodes placed on the curve too); `closed` joins the last end to the first.
fn curve(n: usize, place: impl Fn(f64) -> [f64; 3], kind: StructuralKind, closed: bool) -> Model {
    let mut mesh = Mesh::new();
    let count = if closed { 2 * n } else { 2 * n + 1 };
    for k in 0..count {
        mesh.add_node(k as u64 + 1, place(k as f64 / (2 * n) as f64))
            .unwrap();
    }
    let mut model = Model::new(mesh).unwrap();
    for e in 0..n {
        let end = (2 * e + 2) % count;
        model
            .add_structural(StructuralElement {
                id: 100 + e as u64,
                nodes: vec![2 * e, end, 2 * e + 1],
                kind,
            })
            .unwrap();
    }
    model
}

fn lowest(model: &Model, count: usize) -> Vec<f64> {
    let sys = model.assemble(MassKind::Consistent).unwrap();
    sys.modes(Which::Lowest(count), &EigenOptions::default())
        .unwrap()
        .values
}

/// One element on a helix (its middle node on the helix: a curved, twisted axis). Its 18 x 18
/// stiffness has exactly six zero eigenvalues (below 1e-12 of the largest; the seventh above
/// 1e-6 of it), and the six rigid motions `u = w x x`, `theta = w` (and translations) are among
/// them (`|K r|` below 1e-12 of `|K| |r|`). Its mass in each direction, consistent and lumped,
/// is `rho A` times the length of its quadratic axis (integrated here by a 20,000-interval
/// midpoint rule on `|x'(xi)|`) to 1e-6 (measured 9e-8 on this element, which turns through 69
/// degrees: the element's 5-point rule on a `|x'|` that is not a polynomial) and equals the
/// element's own mass to 1e-12; its lumped masses are 1/6, 2/3, 1/6 of a straight element's.
#[test]
fn a_curved_element_has_six_rigid_body_modes_and_its_mass() {
    let helix = |s: f64| [(1.2 * s).cos(), (1.2 * s).sin(), 0.4 * s];
    let x = [helix(0.0), helix(1.0), helix(0.5)];
    let mut mesh = Mesh::new();
    for (i, p) in x.iter().enumerate() {
        mesh.add_node(i as u64 + 1, *p).unwrap();
    }
    let section = rect(0.03, 0.05);
    let el = StructuralElement {
        id: 1,
        nodes: vec![0, 1, 2],
        kind: beam(section, [0.0, 0.0, 1.0]),
    };
    let m = el.matrices(&x, MassKind::Consistent).unwrap();
    let n = 18;
    let k = faer::Mat::from_fn(n, n, |i, j| m.k[i * n + j]);
    let eig = k.self_adjoint_eigen(faer::Side::Lower).unwrap();
    let mut values: Vec<f64> = (0..n).map(|i| eig.S()[i]).collect();
    values.sort_by(f64::total_cmp);
    let top = values[n - 1];
    assert!(
        values[..6].iter().all(|v| v.abs() < 1e-12 * top),
        "{values:?}"
    );
    assert!(values[6] > 1e-6 * top, "{values:?}");
    let knorm = (0..n * n).map(|i| m.k[i] * m.k[i]).sum::<f64>().sqrt();
    for axis in 0..6 {
        let w: [f64; 3] = std::array::from_fn(|c| f64::from(u8::from(c + 3 == axis)));
        let r: Vec<f64> = x
            .iter()
            .flat_map(|p| {
                let u = if axis < 3 {
                    std::array::from_fn(|c| f64::from(u8::from(c == axis)))
                } else {
                    [
                        w[1] * p[2] - w[2] * p[1],
                        w[2] * p[0] - w[0] * p[2],
                        w[0] * p[1] - w[1] * p[0],
                    ]
                };
                [u[0], u[1], u[2], w[0], w[1], w[2]]
            })
            .collect();
        let rn = r.iter().map(|v| v * v).sum::<f64>().sqrt();
        let kr = (0..n)
            .map(|i| (0..n).map(|j| m.k[i * n + j] * r[j]).sum::<f64>().powi(2))
            .sum::<f64>()
            .sqrt();
        assert!(kr < 1e-12 * knorm * rn, "rigid motion {axis}: {kr}");
    }
    // the quadratic axis's length by the midpoint rule
    let steps = 20_000;
    let length: f64 = (0..steps)
        .map(|i| {
            let xi = -1.0 + (i as f64 + 0.5) * 2.0 / steps as f64;
            let d: Vec<f64> = (0..3)
                .map(|c| (xi - 0.5) * x[0][c] + (xi + 0.5) * x[1][c] - 2.0 * xi * x[2][c])
                .collect();
            d.iter().map(|v| v * v).sum::<f64>().sqrt() * 2.0 / steps as f64
        })
        .sum();
    let want = RHO * section.area * length;
    assert!((el.mass(&x) / want - 1.0).abs() < 1e-6);
    for mass in [MassKind::Consistent, MassKind::Lumped] {
        let mm = el.matrices(&x, mass).unwrap().m;
        for c in 0..3 {
            let total: f64 = (0..3)
                .flat_map(|a| (0..3).map(move |b| (a, b)))
                .map(|(a, b)| mm[(6 * a + c) * n + 6 * b + c])
                .sum();
            assert!((total / want - 1.0).abs() < 1e-6, "{mass:?} {c}: {total}");
            assert!(
                (total / el.mass(&x) - 1.0).abs() < 1e-12,
                "{mass:?} {c}: {total}"
            );
        }
    }
    let straight = [[0.0; 3], [2.0, 0.0, 0.0], [1.0, 0.0, 0.0]];
    let mm = el.matrices(&straight, MassKind::Lumped).unwrap().m;
    let total = RHO * section.area * 2.0;
    for (a, share) in [(0, 1.0 / 6.0), (1, 1.0 / 6.0), (2, 2.0 / 3.0)] {
        assert!((mm[(6 * a) * n + 6 * a] / (share * total) - 1.0).abs() < 1e-12);
    }
}

/// A cantilevered strip of eight three-node beams (the 4- and 8-node shells' check): its first
/// bending frequency is Euler-Bernoulli's at thicknesses 1/100 and 1/1000 of its length (0.5 %),
/// unchanged over the thickness between them (1 %): no shear locking.
#[test]
fn a_thin_strip_does_not_lock() {
    super::common::assert_no_shear_locking(|t| {
        let mut model = curve(
            8,
            |s| [s, 0.0, 0.0],
            beam(rect(0.05, t), [0.0, 0.0, 1.0]),
            false,
        );
        model.fix_node_dofs(1, &[0, 1, 2, 3, 4, 5]).unwrap();
        model
    });
}

/// A simply supported deep beam (L/h = 5) against Timoshenko's frequency equation with shear and
/// rotary inertia (`common::timoshenko_simply_supported`), bending in plane 1: with 10, 20 and
/// 40 elements the three lowest bending frequencies converge as `h^4` (errors falling 16-fold per
/// halving: 1.5e-7, 2.0e-6 and 8.6e-6 with 40).
#[test]
fn a_deep_simply_supported_beam_matches_timoshenko() {
    let (b, h, l) = (0.1, 0.2, 1.0);
    let section = rect(b, h);
    let solve = |n: usize| {
        let mut model = curve(
            n,
            |s| [l * s, 0.0, 0.0],
            beam(section, [0.0, 1.0, 0.0]),
            false,
        );
        // plane 1 only (y, theta_z): z, x-rotation and y-rotation held, x held at one end
        for i in 0..=2 * n {
            model.fix_node_dofs(i as u64 + 1, &[2, 3, 4]).unwrap();
        }
        model.fix_node_dofs(1, &[0, 1]).unwrap();
        model.fix_node_dofs(2 * n as u64 + 1, &[1]).unwrap();
        lowest(&model, 4)
    };
    let want: Vec<f64> = [1.0, 2.0, 3.0]
        .iter()
        .map(|m| {
            super::common::timoshenko_simply_supported(
                E,
                g(),
                RHO,
                section.area,
                section.i1,
                5.0 / 6.0,
                l,
                *m,
            )
        })
        .collect();
    let mut previous = [f64::INFINITY; 3];
    for n in [10, 20, 40] {
        let got = solve(n);
        // the axial mode lies among them: each Timoshenko value is matched by the nearest
        for (r, w) in want.iter().enumerate() {
            let e = got
                .iter()
                .map(|g| (g / w - 1.0).abs())
                .fold(f64::INFINITY, f64::min);
            assert!(
                e < previous[r] / 8.0 || e < 1e-9,
                "{n} {r}: {e} after {}",
                previous[r]
            );
            previous[r] = e;
        }
    }
    assert!(previous.iter().all(|e| *e < 1e-5), "{previous:?}");
}

/// A free circular ring (radius 1 m, a 2 cm square section, 24 three-node beams): its lowest
/// flexural modes against the classical thin-ring frequencies (Blevins, "Formulas for natural
/// frequency and mode shape", the ring's in-plane and out-of-plane flexure):
/// `w^2 = E I n^2 (n^2 - 1)^2 / (rho A R^4 (n^2 + 1))` in its plane and
/// `w^2 = E I n^2 (n^2 - 1)^2 / (rho A R^4 (n^2 + E I / (G J)))` out of it, for `n = 2, 3`, each
/// a pair. Six rigid-body modes come first; the thin ring theory leaves out shear, rotary inertia
/// and stretching (of order `(h / R)^2 n^2`, 1e-4 here): within 1e-3 (measured -3.6e-4 to
/// 1.8e-4).
#[test]
fn a_free_ring_has_the_classical_frequencies() {
    let h = 0.02;
    let section = rect(h, h);
    let model = curve(
        24,
        |s| [(2.0 * PI * s).cos(), (2.0 * PI * s).sin(), 0.0],
        beam(section, [0.0, 0.0, 1.0]),
        true,
    );
    let got = lowest(&model, 14);
    assert!(got[..6].iter().all(|v| v.abs() < 1e-6 * got[6]), "{got:?}");
    let base = E * section.i1 / (RHO * section.area);
    let ratio = E * section.i1 / (g() * section.j);
    let mut want = Vec::new();
    for n in [2.0f64, 3.0] {
        let top = n * n * (n * n - 1.0).powi(2);
        want.extend([base * top / (n * n + 1.0); 2]);
        want.extend([base * top / (n * n + ratio); 2]);
    }
    want.sort_by(f64::total_cmp);
    for (g, w) in got[6..].iter().zip(&want) {
        assert!((g / w - 1.0).abs() < 1e-3, "{g} against {w}: {got:?}");
    }
}

/// Refused by element id with the reason: a three-node beam without shear factors, with offsets,
/// whose middle node folds it back (beyond the quarter point) or whose orientation vector lies
/// along its axis, and one with two nodes alike.
#[test]
fn bad_three_node_beams_are_refused() {
    let x = [[0.0; 3], [2.0, 0.0, 0.0], [1.0, 0.0, 0.0]];
    let kind = |f: &dyn Fn(&mut Beam)| {
        let StructuralKind::Beam(mut b) = beam(rect(0.1, 0.2), [0.0, 0.0, 1.0]) else {
            unreachable!()
        };
        f(&mut b);
        StructuralKind::Beam(b)
    };
    let refused = |nodes: Vec<usize>, kind: StructuralKind, x: &[[f64; 3]], says: &str| {
        let el = StructuralElement { id: 7, nodes, kind };
        let e = el.check_geometry(x).unwrap_err().to_string();
        assert!(e.contains('7') && e.contains(says), "{e}");
    };
    refused(
        vec![0, 1, 2],
        kind(&|b| b.section.shear = None),
        &x,
        "shear factors",
    );
    refused(
        vec![0, 1, 2],
        kind(&|b| b.offsets[1] = [0.0, 0.1, 0.0]),
        &x,
        "offsets",
    );
    refused(
        vec![0, 1, 2],
        kind(&|_| {}),
        &[[0.0; 3], [2.0, 0.0, 0.0], [0.3, 0.0, 0.0]],
        "folds back",
    );
    refused(
        vec![0, 1, 2],
        kind(&|b| b.orientation = [1.0, 0.0, 0.0]),
        &x,
        "parallel",
    );
    refused(vec![0, 1, 1], kind(&|_| {}), &x, "distinct");
}
