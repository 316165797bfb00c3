//! Quadrature rules on the reference cells, with the degree each integrates exactly.
//!
//! Reference cells (Abaqus/CalculiX conventions):
//! - hexahedron `[-1, 1]^3`;
//! - tetrahedron `{xi, eta, zeta >= 0, xi + eta + zeta <= 1}` (volume 1/6);
//! - wedge: triangle `{xi, eta >= 0, xi + eta <= 1}` times `zeta in [-1, 1]` (volume 1).
//!
//! Tensor and conical-product rules are built from Gauss-Legendre points computed to machine
//! precision (Newton on the Legendre recurrence), so no long tables of constants are needed.

/// A quadrature rule: points in reference coordinates and their weights.
#[derive(Debug, Clone, PartialEq)]
pub struct QuadratureRule {
    /// Points `(xi, eta, zeta)`.
    pub points: Vec<[f64; 3]>,
    /// Weights; they sum to the reference cell's volume.
    pub weights: Vec<f64>,
}

impl QuadratureRule {
    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether the rule has no points.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }
}

/// Gauss-Legendre points and weights on `[-1, 1]` with `n` points (exact to degree `2n - 1`).
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    assert!(n >= 1, "a Gauss rule needs at least one point");
    let mut x = vec![0.0; n];
    let mut w = vec![0.0; n];
    for i in 0..n.div_ceil(2) {
        // Chebyshev-like initial guess, then Newton on P_n.
        let mut z = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 0.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, z);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * z * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            let pn = if n == 1 { z } else { p1 };
            let pm = if n == 1 { 1.0 } else { p0 };
            dp = n as f64 * (z * pn - pm) / (z * z - 1.0);
            let dz = pn / dp;
            z -= dz;
            if dz.abs() < 1e-16 {
                break;
            }
        }
        if n == 1 {
            z = 0.0;
            dp = 1.0;
        }
        x[i] = -z;
        x[n - 1 - i] = z;
        let wi = 2.0 / ((1.0 - z * z) * dp * dp);
        w[i] = wi;
        w[n - 1 - i] = wi;
    }
    if n % 2 == 1 {
        x[n / 2] = 0.0;
    }
    (x, w)
}

/// Tensor Gauss rule `n x n x n` on the hexahedron (exact to degree `2n - 1` in each variable).
pub fn hex_gauss(n: usize) -> QuadratureRule {
    let (x, w) = gauss_legendre(n);
    let mut rule = QuadratureRule {
        points: Vec::new(),
        weights: Vec::new(),
    };
    // Abaqus order: xi fastest.
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                rule.points.push([x[i], x[j], x[k]]);
                rule.weights.push(w[i] * w[j] * w[k]);
            }
        }
    }
    rule
}

/// The centroid rule on the tetrahedron (exact to degree 1): tet4 stiffness.
pub fn tet_1() -> QuadratureRule {
    QuadratureRule {
        points: vec![[0.25; 3]],
        weights: vec![1.0 / 6.0],
    }
}

/// The symmetric 4-point rule on the tetrahedron, `a = (5 - sqrt 5) / 20` (exact to degree 2):
/// tet10 stiffness (as CalculiX's C3D10) and tet4 mass.
pub fn tet_4() -> QuadratureRule {
    let s5 = 5.0_f64.sqrt();
    let a = (5.0 - s5) / 20.0;
    let b = (5.0 + 3.0 * s5) / 20.0;
    QuadratureRule {
        points: vec![[a, a, a], [b, a, a], [a, b, a], [a, a, b]],
        weights: vec![1.0 / 24.0; 4],
    }
}

/// A conical-product (collapsed-cube) rule on the tetrahedron exact to total degree `degree`,
/// with positive weights: `xi = u`, `eta = (1 - u) v`, `zeta = (1 - u)(1 - v) w`, Jacobian
/// `(1 - u)^2 (1 - v)`.
pub fn tet_conical(degree: usize) -> QuadratureRule {
    let line = |deg: usize| {
        let n = (deg + 2).div_ceil(2);
        let (x, w) = gauss_legendre(n);
        // map to [0, 1]
        let x: Vec<f64> = x.iter().map(|t| 0.5 * (t + 1.0)).collect();
        let w: Vec<f64> = w.iter().map(|t| 0.5 * t).collect();
        (x, w)
    };
    let (xu, wu) = line(degree + 2);
    let (xv, wv) = line(degree + 1);
    let (xw, ww) = line(degree);
    let mut rule = QuadratureRule {
        points: Vec::new(),
        weights: Vec::new(),
    };
    for (u, a) in xu.iter().zip(&wu) {
        for (v, b) in xv.iter().zip(&wv) {
            for (w, c) in xw.iter().zip(&ww) {
                rule.points
                    .push([*u, (1.0 - u) * v, (1.0 - u) * (1.0 - v) * w]);
                rule.weights
                    .push(a * b * c * (1.0 - u) * (1.0 - u) * (1.0 - v));
            }
        }
    }
    rule
}

/// Triangle rules (2D points, weights summing to 1/2): the symmetric 3-point rule for degree 2
/// and Dunavant's 6-point rule for degree 4, both with positive weights.
fn triangle(degree: usize) -> (Vec<[f64; 2]>, Vec<f64>) {
    match degree {
        0..=2 => {
            let (a, b) = (1.0 / 6.0, 2.0 / 3.0);
            (vec![[a, a], [b, a], [a, b]], vec![1.0 / 6.0; 3])
        }
        3 | 4 => {
            let (a1, w1) = (0.445_948_490_915_965, 0.223_381_589_678_011);
            let (a2, w2) = (0.091_576_213_509_771, 0.109_951_743_655_322);
            let (b1, b2) = (1.0 - 2.0 * a1, 1.0 - 2.0 * a2);
            (
                vec![[a1, a1], [b1, a1], [a1, b1], [a2, a2], [b2, a2], [a2, b2]],
                vec![w1 / 2.0, w1 / 2.0, w1 / 2.0, w2 / 2.0, w2 / 2.0, w2 / 2.0],
            )
        }
        _ => panic!("triangle rules are provided up to degree 4"),
    }
}

/// A wedge rule: a triangle rule exact to `degree` times a Gauss rule exact to `degree` in zeta.
pub fn wedge(degree: usize) -> QuadratureRule {
    let (tp, tw) = triangle(degree);
    let (zx, zw) = gauss_legendre((degree + 2) / 2);
    let mut rule = QuadratureRule {
        points: Vec::new(),
        weights: Vec::new(),
    };
    for (z, wz) in zx.iter().zip(&zw) {
        for (p, w) in tp.iter().zip(&tw) {
            rule.points.push([p[0], p[1], *z]);
            rule.weights.push(w * wz);
        }
    }
    rule
}

/// A pyramid rule: the collapsed cube `(a, b, c) in [-1, 1]^2 x [0, 1]`, `xi = a (1 - c)`,
/// `eta = b (1 - c)`, `zeta = c`, with `n_ab x n_ab` Gauss points in `a, b`, `n_c` in `c`, and the
/// Jacobian `(1 - c)^2` in the weights (exact for polynomials on the cube of degree `2 n_ab - 1`
/// in `a` and `b` and `2 n_c - 3` in `c` before the Jacobian).
pub fn pyramid(n_ab: usize, n_c: usize) -> QuadratureRule {
    let (x, w) = gauss_legendre(n_ab);
    let (t, wt) = gauss_legendre(n_c);
    let mut rule = QuadratureRule {
        points: Vec::new(),
        weights: Vec::new(),
    };
    for (tk, wk) in t.iter().zip(&wt) {
        let c = 0.5 * (1.0 + tk);
        let s = 1.0 - c;
        for (b, wb) in x.iter().zip(&w) {
            for (a, wa) in x.iter().zip(&w) {
                rule.points.push([a * s, b * s, c]);
                rule.weights.push(wa * wb * 0.5 * wk * s * s);
            }
        }
    }
    rule
}

#[cfg(test)]
mod tests {
    use super::*;

    fn factorial(n: u32) -> f64 {
        (1..=n).map(f64::from).product()
    }

    /// Exact integral of xi^i eta^j zeta^k over the reference tetrahedron: i! j! k! / (i+j+k+3)!.
    fn tet_monomial(i: u32, j: u32, k: u32) -> f64 {
        factorial(i) * factorial(j) * factorial(k) / factorial(i + j + k + 3)
    }

    fn integrate(rule: &QuadratureRule, i: u32, j: u32, k: u32) -> f64 {
        rule.points
            .iter()
            .zip(&rule.weights)
            .map(|(p, w)| w * p[0].powi(i as i32) * p[1].powi(j as i32) * p[2].powi(k as i32))
            .sum()
    }

    #[test]
    fn gauss_legendre_integrates_to_its_degree() {
        for n in 1..=6 {
            let (x, w) = gauss_legendre(n);
            for d in 0..(2 * n) as i32 {
                let exact = if d % 2 == 1 {
                    0.0
                } else {
                    2.0 / (d as f64 + 1.0)
                };
                let q: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(d)).sum();
                assert!((q - exact).abs() < 1e-14, "n={n} d={d}: {q} vs {exact}");
            }
        }
    }

    #[test]
    fn tetrahedron_rules_are_exact_to_their_degree() {
        for (rule, deg) in [
            (tet_1(), 1),
            (tet_4(), 2),
            (tet_conical(4), 4),
            (tet_conical(6), 6),
        ] {
            for i in 0..=deg {
                for j in 0..=(deg - i) {
                    for k in 0..=(deg - i - j) {
                        let (q, e) = (integrate(&rule, i, j, k), tet_monomial(i, j, k));
                        assert!(
                            (q - e).abs() < 1e-15 + 1e-13 * e,
                            "deg {deg}: x^{i} y^{j} z^{k}: {q} vs {e}"
                        );
                    }
                }
            }
            assert!(rule.weights.iter().all(|w| *w > 0.0));
        }
        // The 4-point rule is not exact for degree 3: the test can fail.
        assert!((integrate(&tet_4(), 3, 0, 0) - tet_monomial(3, 0, 0)).abs() > 1e-6);
    }

    #[test]
    fn wedge_rules_are_exact_to_their_degree() {
        for deg in [2u32, 4] {
            let rule = wedge(deg as usize);
            for i in 0..=deg {
                for j in 0..=(deg - i) {
                    for k in 0..=deg {
                        // triangle: i! j! / (i+j+2)!, line: 2/(k+1) for even k
                        let tri = factorial(i) * factorial(j) / factorial(i + j + 2);
                        let line = if k % 2 == 1 {
                            0.0
                        } else {
                            2.0 / (k as f64 + 1.0)
                        };
                        let (q, e) = (integrate(&rule, i, j, k), tri * line);
                        assert!((q - e).abs() < 1e-14, "deg {deg}: {i} {j} {k}: {q} vs {e}");
                    }
                }
            }
        }
    }

    #[test]
    fn hex_rule_weights_sum_to_volume() {
        for n in 1..=4 {
            let s: f64 = hex_gauss(n).weights.iter().sum();
            assert!((s - 8.0).abs() < 1e-13);
        }
    }
}
