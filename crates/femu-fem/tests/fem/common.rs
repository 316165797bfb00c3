//! Shared helpers: distorted elements, dense copies, simple random numbers.

use femu_fem::element::ElementKind;

pub use femu_testkit::Rng;

/// The affine map used for "undistorted" elements: a general (sheared, rotated, scaled) map with
/// positive determinant.
pub const AFFINE: [[f64; 3]; 3] = [[0.9, 0.2, 0.1], [-0.15, 1.1, 0.25], [0.05, -0.1, 0.8]];
pub const SHIFT: [f64; 3] = [0.3, -0.2, 1.1];

pub fn det3(a: &[[f64; 3]; 3]) -> f64 {
    a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
        - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
        + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0])
}

pub fn affine(p: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| SHIFT[i] + (0..3).map(|k| AFFINE[i][k] * p[k]).sum::<f64>())
}

/// Node coordinates of an affinely mapped element, with corners perturbed by `distortion`
/// (relative to the reference size) and, when `curved`, mid-edge nodes moved off the edge.
pub fn element_coords(
    kind: ElementKind,
    distortion: f64,
    curved: bool,
    rng: &mut Rng,
) -> Vec<[f64; 3]> {
    let r = kind.reference_nodes();
    let mut x: Vec<[f64; 3]> = r.iter().map(|p| affine(*p)).collect();
    let nc = kind.num_corners();
    for a in 0..nc {
        for i in 0..3 {
            x[a][i] += distortion * rng.sym();
        }
    }
    for (e, [a, b]) in kind.edges().iter().enumerate() {
        if kind.is_quadratic() {
            let m = nc + e;
            for i in 0..3 {
                x[m][i] = 0.5 * (x[*a][i] + x[*b][i])
                    + if curved {
                        0.5 * distortion * rng.sym()
                    } else {
                        0.0
                    };
            }
        }
    }
    x
}

/// Dense square matrix from a row-major slice.
pub fn dense(a: &[f64], n: usize) -> faer::Mat<f64> {
    faer::Mat::from_fn(n, n, |i, j| a[i * n + j])
}

/// Rigid-body motions of a point set: 3 translations, 3 rotations (node-major vectors).
pub fn rigid_modes(x: &[[f64; 3]]) -> Vec<Vec<f64>> {
    let mut modes = Vec::new();
    for i in 0..3 {
        modes.push(
            x.iter()
                .flat_map(|_| (0..3).map(move |k| if k == i { 1.0 } else { 0.0 }))
                .collect(),
        );
    }
    // rotation about axis i: u = e_i x p
    for i in 0..3 {
        modes.push(
            x.iter()
                .flat_map(|p| {
                    let w: [f64; 3] = std::array::from_fn(|k| if k == i { 1.0 } else { 0.0 });
                    [
                        w[1] * p[2] - w[2] * p[1],
                        w[2] * p[0] - w[0] * p[2],
                        w[0] * p[1] - w[1] * p[0],
                    ]
                })
                .collect(),
        );
    }
    modes
}

/// The distance of `z` from the span of the columns of `basis`, relative to `|z|`: the residual of
/// its projection on an orthonormal basis of that span (two passes of Gram-Schmidt).
pub fn distance_from_span(basis: faer::MatRef<'_, f64>, z: &[f64]) -> f64 {
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let mut q: Vec<Vec<f64>> = Vec::new();
    for j in 0..basis.ncols() {
        let mut v: Vec<f64> = basis.col(j).iter().copied().collect();
        let before = dot(&v, &v).sqrt();
        for _ in 0..2 {
            for u in &q {
                let c = dot(u, &v);
                v.iter_mut().zip(u).for_each(|(a, b)| *a -= c * b);
            }
        }
        let nrm = dot(&v, &v).sqrt();
        if nrm > 1e-10 * before {
            q.push(v.iter().map(|a| a / nrm).collect());
        }
    }
    let mut r = z.to_vec();
    for _ in 0..2 {
        for u in &q {
            let c = dot(u, &r);
            r.iter_mut().zip(u).for_each(|(a, b)| *a -= c * b);
        }
    }
    dot(&r, &r).sqrt() / dot(z, z).sqrt()
}

/// The shear-locking check of a cantilevered steel strip (1 m long, E = 200 GPa, nu = 0.3, rho =
/// 8000) at thicknesses 0.1, 0.01 and 0.001 m: `clamped(t)` builds the strip of that thickness,
/// clamped. Its first bending frequency lies between Euler-Bernoulli's with `E` and with
/// `E / (1 - nu^2)` (0.5 % either way) for the two thin strips, the frequency over the thickness
/// changes by under 1 % from 1/100 to 1/1000, and shear deformation lowers the thick strip's.
pub fn assert_no_shear_locking(clamped: impl Fn(f64) -> femu_fem::model::Model) {
    use femu_fem::assembly::MassKind;
    use femu_sparse::eigen::{EigenOptions, Which};
    let mut per_t = Vec::new();
    for t in [0.1, 0.01, 0.001] {
        let sys = clamped(t).assemble(MassKind::Consistent).unwrap();
        let f = sys
            .modes(Which::Lowest(1), &EigenOptions::default())
            .unwrap()
            .values[0]
            .sqrt();
        let beam = |e: f64| 1.875_104_07f64.powi(2) * (e * t * t / (12.0 * 8000.0)).sqrt();
        if t < 0.05 {
            assert!(
                f > beam(2.0e11) * 0.995 && f < beam(2.0e11 / 0.91) * 1.005,
                "t = {t}: {f} against {} .. {}",
                beam(2.0e11),
                beam(2.0e11 / 0.91)
            );
        }
        per_t.push(f / t);
    }
    assert!((per_t[2] / per_t[1] - 1.0).abs() < 1e-2, "{per_t:?}");
    assert!(per_t[0] < per_t[1], "{per_t:?}");
}

/// `w^2` of mode `n` of a simply supported Timoshenko beam (shear and rotary inertia), the lower
/// root of its frequency equation `(rho A w^2 - k G A q^2)(rho I w^2 - E I q^2 - k G A) = (k G A
/// q)^2`, `q = n pi / L`.
#[allow(clippy::too_many_arguments)]
pub fn timoshenko_simply_supported(
    e: f64,
    g: f64,
    rho: f64,
    area: f64,
    i: f64,
    k: f64,
    l: f64,
    n: f64,
) -> f64 {
    let kga = k * g * area;
    let q = n * std::f64::consts::PI / l;
    // a x^2 + b x + c = 0 in x = w^2
    let a = rho * area * rho * i;
    let b = -(rho * area * (e * i * q * q + kga) + kga * q * q * rho * i);
    let c = kga * q * q * e * i * q * q;
    (-b - (b * b - 4.0 * a * c).sqrt()) / (2.0 * a)
}

/// A rectangle `b x h` (plane 1 bends over `h`, along local y): Roark's torsion constant of a
/// rectangle, shear factors 5/6 when `shear`.
pub fn rect_section(b: f64, h: f64, shear: bool) -> femu_fem::structural::BeamSection {
    let (a, c) = if b > h { (b, h) } else { (h, b) };
    let j = a * c.powi(3) * (1.0 / 3.0 - 0.21 * c / a * (1.0 - c.powi(4) / (12.0 * a.powi(4))));
    femu_fem::structural::BeamSection {
        area: b * h,
        i1: b * h.powi(3) / 12.0,
        i2: h * b.powi(3) / 12.0,
        j,
        shear: shear.then_some([5.0 / 6.0, 5.0 / 6.0]),
        nsm: 0.0,
    }
}

/// A beam of modulus `e`, Poisson's ratio `nu`, density `rho`, `section` and `orientation`, no
/// offsets or releases.
pub fn beam_kind(
    (e, nu, rho): (f64, f64, f64),
    section: femu_fem::structural::BeamSection,
    orientation: [f64; 3],
) -> femu_fem::structural::StructuralKind {
    femu_fem::structural::StructuralKind::Beam(femu_fem::structural::Beam {
        e,
        g: e / (2.0 * (1.0 + nu)),
        rho,
        section,
        taper: None,
        orientation,
        offsets: [[0.0; 3]; 2],
        lumped_torsion: false,
        coupled_torsion: true,
        releases: [[false; 6]; 2],
    })
}
