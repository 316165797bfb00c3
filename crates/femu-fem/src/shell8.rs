//! The 8-node curved shell: a degenerated continuum on the serendipity quadrilateral (Ahmad, Irons
//! and Zienkiewicz 1970) in resultant form, with the membrane and the transverse shear sampled at
//! the 2 x 2 Gauss points and the bending at the 3 x 3 ones, and the drilling stiffness of the
//! 4-node shell (docs/MATH.md, "The 8-node shell").
//!
//! The mid-surface and the displacement are interpolated from the eight nodes (corners 1-4, then
//! the midsides of edges 1-2, 2-3, 3-4, 4-1, the order of Nastran's CQUAD8 and Abaqus' S8R): a
//! point at distance `z` along the directors is `X = sum N_i (x_i + z n_i)` and moves by `u = sum
//! N_i (u_i + z theta_i x n_i)`, `n_i` the surface's unit normal at node `i`. The strains in the
//! tangent axes of each sampling point are `eps_0 + z kappa` to first order in `z`; the section's
//! membrane, bending and transverse shear matrices act on `eps_0`, `kappa` and the shear (the
//! 4-node shell's sections: [`crate::shell::Shell`]). A rigid motion of the element strains it
//! nowhere, whatever its curvature; fields linear in the plane and constant curvatures of a flat
//! element are exact.

use crate::assembly::MassKind;
use crate::shell::{Scales, Shell, V3, add_btdb, cross, dot, section, unit};

/// The 8-node quadrilateral's nodes in `(xi, eta)`: corners, then the midsides of edges 1-2, 2-3,
/// 3-4, 4-1.
const NODES: [(f64, f64); 8] = [
    (-1.0, -1.0),
    (1.0, -1.0),
    (1.0, 1.0),
    (-1.0, 1.0),
    (0.0, -1.0),
    (1.0, 0.0),
    (0.0, 1.0),
    (-1.0, 0.0),
];

/// Shape functions and their derivatives in the two parametric coordinates.
type Shapes<const M: usize> = ([f64; M], [f64; M], [f64; M]);

/// Serendipity shape functions and their derivatives in `(xi, eta)`.
fn shape(xi: f64, eta: f64) -> Shapes<8> {
    let mut n = [0.0; 8];
    let mut dxi = [0.0; 8];
    let mut deta = [0.0; 8];
    for (i, &(a, b)) in NODES.iter().enumerate() {
        if i < 4 {
            let (p, q) = (1.0 + a * xi, 1.0 + b * eta);
            n[i] = 0.25 * p * q * (a * xi + b * eta - 1.0);
            dxi[i] = 0.25 * a * q * (2.0 * a * xi + b * eta);
            deta[i] = 0.25 * b * p * (a * xi + 2.0 * b * eta);
        } else if a == 0.0 {
            n[i] = 0.5 * (1.0 - xi * xi) * (1.0 + b * eta);
            dxi[i] = -xi * (1.0 + b * eta);
            deta[i] = 0.5 * b * (1.0 - xi * xi);
        } else {
            n[i] = 0.5 * (1.0 + a * xi) * (1.0 - eta * eta);
            dxi[i] = 0.5 * a * (1.0 - eta * eta);
            deta[i] = -eta * (1.0 + a * xi);
        }
    }
    (n, dxi, deta)
}

/// A curved shell's topology: its nodes' parametric coordinates, its functions, and its rules
/// (points and weights): `low` for the membrane and the transverse shear, `high` for the bending,
/// the mass and the checks. The quadratic triangle on the same formulation (three points low, six
/// high) locks in membrane on curved surfaces (a thin ring 2.1 times too stiff at `t/R = 1/100`,
/// 6.9 times at 1/1000) and is not built.
struct Topology<const M: usize> {
    nodes: [(f64, f64); M],
    shape: fn(f64, f64) -> Shapes<M>,
    low: Vec<(f64, f64, f64)>,
    high: Vec<(f64, f64, f64)>,
}

/// The Gauss points and weights of an `n x n` rule on the square (n = 2 or 3).
fn rule(n: usize) -> Vec<(f64, f64, f64)> {
    let (p, w): (Vec<f64>, Vec<f64>) = if n == 2 {
        let g = 1.0 / 3f64.sqrt();
        (vec![-g, g], vec![1.0, 1.0])
    } else {
        let g = 0.6f64.sqrt();
        (vec![-g, 0.0, g], vec![5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0])
    };
    let mut out = Vec::with_capacity(n * n);
    for (b, wb) in p.iter().zip(&w) {
        for (a, wa) in p.iter().zip(&w) {
            out.push((*a, *b, wa * wb));
        }
    }
    out
}

fn quad8() -> Topology<8> {
    Topology {
        nodes: NODES,
        shape,
        low: rule(2),
        high: rule(3),
    }
}

/// `sum c_i x_i` over the nodes.
fn combine<const M: usize>(c: &[f64; M], x: &[V3; M]) -> V3 {
    std::array::from_fn(|k| (0..M).map(|i| c[i] * x[i][k]).sum())
}

/// The unit normals of the mid-surface at the nodes, refused where the surface's tangents do not
/// span a plane or the normal turns over against the element's centre normal (an inverted or
/// folded element), and checked at the `high` points likewise.
fn normals<const M: usize>(topo: &Topology<M>, x: &[V3; M]) -> Result<[V3; M], String> {
    let tangent_normal = |xi: f64, eta: f64| {
        let (_, dxi, deta) = (topo.shape)(xi, eta);
        cross(combine(&dxi, x), combine(&deta, x))
    };
    let (cx, cy) = centre(topo);
    let centre = unit(tangent_normal(cx, cy))
        .ok_or("its mid-surface has no normal at its centre (degenerate or folded)")?;
    let mut out = [[0.0; 3]; M];
    for (i, &(a, b)) in topo.nodes.iter().enumerate() {
        let g = tangent_normal(a, b);
        let n = unit(g)
            .ok_or_else(|| format!("its mid-surface has no normal at its node {}", i + 1))?;
        if !(dot(n, centre) > 0.1) {
            return Err(format!(
                "its mid-surface turns over at its node {} (the normal there is at {:.0} degrees from the centre's): the element is inverted, its nodes are out of order, or a midside node lies too far along its edge",
                i + 1,
                dot(n, centre).clamp(-1.0, 1.0).acos().to_degrees()
            ));
        }
        out[i] = n;
    }
    for &(xi, eta, _) in &topo.high {
        let g = tangent_normal(xi, eta);
        if !(dot(g, centre) > 0.0) {
            return Err(format!(
                "its Jacobian is {:e} at a Gauss point: the element is inverted or degenerate (a midside node too far along its edge?)",
                dot(g, centre)
            ));
        }
    }
    Ok(out)
}

/// The parametric centre: the mean of the corners' coordinates.
fn centre<const M: usize>(topo: &Topology<M>) -> (f64, f64) {
    let (mut a, mut b) = (0.0, 0.0);
    for &(x, y) in &topo.nodes[..4] {
        a += x;
        b += y;
    }
    (a / 4.0, b / 4.0)
}

/// Checks an 8-node shell's geometry (basic frame) without forming its matrices.
///
/// # Errors
/// The message [`matrices8`] would give for the geometry.
pub fn check8(x: &[V3; 8]) -> Result<(), String> {
    normals(&quad8(), x).map(|_| ())
}

/// Whether an 8-node shell's `xi` direction (the tangent `x_,xi`; `x` its eight nodes) is the same
/// at every 3 x 3 Gauss point, to 1e-9 radians: true for a flat parallelogram with its midside
/// nodes at the middles of its edges, false for a curved or tapered element (or not eight nodes).
pub fn uniform_xi(x: &[V3]) -> bool {
    fn along<const M: usize>(topo: &Topology<M>, x: &[V3; M]) -> bool {
        let dir = |xi: f64, eta: f64| {
            let (_, dxi, _) = (topo.shape)(xi, eta);
            unit(combine(&dxi, x))
        };
        let (cx, cy) = centre(topo);
        let Some(c) = dir(cx, cy) else {
            return false;
        };
        topo.high.iter().all(|&(xi, eta, _)| {
            dir(xi, eta).is_some_and(|a| {
                let s = cross(a, c);
                dot(s, s).sqrt() < 1e-9 && dot(a, c) > 0.0
            })
        })
    }
    match x.len() {
        8 => along(&quad8(), &std::array::from_fn(|i| x[i])),
        _ => false,
    }
}

/// The area of an 8-node shell's mid-surface (`x` its eight nodes; 0 otherwise), by the 3 x 3
/// rule (exact for a flat element with straight edges and midside nodes at their middles).
pub fn area8(x: &[V3]) -> f64 {
    fn area<const M: usize>(topo: &Topology<M>, x: &[V3; M]) -> f64 {
        topo.high
            .iter()
            .map(|&(xi, eta, w)| {
                let (_, dxi, deta) = (topo.shape)(xi, eta);
                let g = cross(combine(&dxi, x), combine(&deta, x));
                w * dot(g, g).sqrt()
            })
            .sum()
    }
    match x.len() {
        8 => area(&quad8(), &std::array::from_fn(|i| x[i])),
        _ => 0.0,
    }
}

/// The displacement gradients at a point of the mid-surface: for each of the element's DOFs
/// (node-major, `u, v, w, theta_x, theta_y, theta_z` in the basic frame), the tangent-axes
/// gradient `L[p][q] = d u_q / d x_p` at `z = 0` and its derivative in `z`, with the axes (rows
/// `e1`, `e2`, `e3`) and the area element `|x_,xi x x_,eta|`.
struct Point {
    l0: Vec<[[f64; 3]; 3]>,
    l1: Vec<[[f64; 3]; 3]>,
    axes: [V3; 3],
    da: f64,
}

fn point<const M: usize>(topo: &Topology<M>, x: &[V3; M], n: &[V3; M], xi: f64, eta: f64) -> Point {
    let (nn, dxi, deta) = (topo.shape)(xi, eta);
    let g1 = combine(&dxi, x);
    let g2 = combine(&deta, x);
    let nbar = combine(&nn, n);
    let (a1, a2) = (combine(&dxi, n), combine(&deta, n));
    let gn = cross(g1, g2);
    let da = dot(gn, gn).sqrt();
    // checked by `normals`: the tangents span a plane
    let e3 = [gn[0] / da, gn[1] / da, gn[2] / da];
    let e1 = unit(g1).unwrap_or([1.0, 0.0, 0.0]);
    let e2 = cross(e3, e1);
    let axes = [e1, e2, e3];
    // J0 rows (x_,xi, x_,eta, x_,z), J1 = d J / d z
    let j0 = nalgebra::Matrix3::from_rows(&[
        nalgebra::RowVector3::from(g1),
        nalgebra::RowVector3::from(g2),
        nalgebra::RowVector3::from(nbar),
    ]);
    let j1 = nalgebra::Matrix3::from_rows(&[
        nalgebra::RowVector3::from(a1),
        nalgebra::RowVector3::from(a2),
        nalgebra::RowVector3::zeros(),
    ]);
    let p = j0.try_inverse().unwrap_or_else(nalgebra::Matrix3::zeros);
    let q = -p * j1 * p;
    let r = nalgebra::Matrix3::from_rows(&axes.map(nalgebra::RowVector3::from));
    // du/dX = sum_a P[:, a] (x) G_a (G_a = du/dxi_a, the rows of G), so in the tangent axes L =
    // sum_a (R P[:, a]) (x) (R G_a): each DOF's gradient is an outer product
    let turned = |m: &nalgebra::Matrix3<f64>, a: usize| -> V3 {
        let v = r * m.column(a);
        [v[0], v[1], v[2]]
    };
    let (rp, rq) = (
        [turned(&p, 0), turned(&p, 1), turned(&p, 2)],
        [turned(&q, 0), turned(&q, 1), turned(&q, 2)],
    );
    let outer = |a: V3, b: V3| -> [[f64; 3]; 3] {
        std::array::from_fn(|i| std::array::from_fn(|j| a[i] * b[j]))
    };
    let mut l0 = Vec::with_capacity(6 * M);
    let mut l1 = Vec::with_capacity(6 * M);
    for node in 0..M {
        let (d1, d2, w) = (dxi[node], deta[node], nn[node]);
        let along: V3 = std::array::from_fn(|k| d1 * rp[0][k] + d2 * rp[1][k]);
        // a translation along c: G_xi = d1 e_c, G_eta = d2 e_c, no z derivative
        let bent: V3 = std::array::from_fn(|k| d1 * rq[0][k] + d2 * rq[1][k]);
        for c in 0..3 {
            let beta = [r[(0, c)], r[(1, c)], r[(2, c)]];
            l0.push(outer(along, beta));
            l1.push(outer(bent, beta));
        }
        // a rotation about c moves the director by e_c x n: G_z = w (e_c x n), and the z
        // derivatives G_xi = d1 (e_c x n), G_eta = d2 (e_c x n)
        let normal: V3 = std::array::from_fn(|k| w * rp[2][k]);
        let curl: V3 = std::array::from_fn(|k| along[k] + w * rq[2][k]);
        for c in 0..3 {
            let mut e = [0.0; 3];
            e[c] = 1.0;
            let rot = cross(e, n[node]);
            let beta = std::array::from_fn(|k| dot(axes[k], rot));
            l0.push(outer(normal, beta));
            l1.push(outer(curl, beta));
        }
    }
    Point { l0, l1, axes, da }
}

/// In-plane strain rows `(eps_11, eps_22, gamma_12)` of gradients `l` (`ND` of them).
fn in_plane<const ND: usize>(l: &[[[f64; 3]; 3]]) -> [[f64; ND]; 3] {
    let mut b = [[0.0; ND]; 3];
    for (c, g) in l.iter().enumerate() {
        b[0][c] = g[0][0];
        b[1][c] = g[1][1];
        b[2][c] = g[0][1] + g[1][0];
    }
    b
}

/// The 8-node shell's stiffness and mass (48 x 48, row-major) on `(u, v, w, theta_x, theta_y,
/// theta_z)` of each node in the basic frame. The consistent mass is the 4-node shell's
/// (translations `rho t + nsm`, every rotation `rho I`) on the serendipity functions, integrated
/// exactly; the lumped mass is its translational diagonal scaled to the element's mass (Hinton,
/// Rock and Zienkiewicz 1976: the serendipity corners would get a negative share by row sums).
///
/// # Errors
/// A message for a degenerate, folded or inverted element.
pub fn matrices8(s: &Shell, x: &[V3; 8], mass: MassKind) -> Result<(Vec<f64>, Vec<f64>), String> {
    matrices8_scaled(s, x, mass, Scales::ALL)
}

/// [`matrices8`] with its parts scaled by `sc`.
pub(crate) fn matrices8_scaled(
    s: &Shell,
    x: &[V3; 8],
    mass: MassKind,
    sc: Scales,
) -> Result<(Vec<f64>, Vec<f64>), String> {
    curved::<8, 48>(&quad8(), s, x, mass, sc)
}

/// The curved shell of `topo` with `M` nodes and `ND = 6 M` DOFs.
fn curved<const M: usize, const ND: usize>(
    topo: &Topology<M>,
    s: &Shell,
    x: &[V3; M],
    mass: MassKind,
    sc: Scales,
) -> Result<(Vec<f64>, Vec<f64>), String> {
    debug_assert_eq!(ND, 6 * M);
    let n0 = normals(topo, x)?;
    let n = n0;
    // an offset reference surface: the element is formed on it, driven by the grids through
    // rigid links (u_ref = u + theta x (offset n))
    let xm: [V3; M] =
        std::array::from_fn(|i| std::array::from_fn(|k| x[i][k] + s.offset * n[i][k]));
    let n = if s.offset != 0.0 {
        normals(topo, &xm)?
    } else {
        n
    };
    let mut k = vec![0.0; ND * ND];
    let mut m = vec![0.0; ND * ND];
    let zero3 = [[0.0; 3]; 3];
    // membrane and transverse shear at the low points (free of membrane and shear locking)
    for &(xi, eta, w) in &topo.low {
        let pt = point(topo, &xm, &n, xi, eta);
        let (cm, _, cs, _) = section(s, &pt.axes, sc)?;
        add_btdb(&mut k, &in_plane::<ND>(&pt.l0), &cm, 3, w * pt.da);
        let mut bs = [[0.0; ND]; 2];
        for (c, g) in pt.l0.iter().enumerate() {
            bs[0][c] = g[0][2] + g[2][0];
            bs[1][c] = g[1][2] + g[2][1];
        }
        let cs3 = [
            [cs[0][0], cs[0][1], 0.0],
            [cs[1][0], cs[1][1], 0.0],
            zero3[0],
        ];
        add_btdb(&mut k, &bs, &cs3, 2, w * pt.da);
    }
    // bending, and the mass, at the high points
    let (mt, mr) = (
        sc.linear * s.rho * s.t + sc.nsm * s.nsm,
        sc.cubic * s.rho * s.bending * s.t.powi(3) / 12.0,
    );
    let mut area = 0.0;
    let mut diag = [0.0; M];
    for &(xi, eta, w) in &topo.high {
        let pt = point(topo, &xm, &n, xi, eta);
        let (_, cb, _, _) = section(s, &pt.axes, sc)?;
        add_btdb(&mut k, &in_plane::<ND>(&pt.l1), &cb, 3, w * pt.da);
        let (nn, _, _) = (topo.shape)(xi, eta);
        area += w * pt.da;
        for a in 0..M {
            diag[a] += nn[a] * nn[a] * w * pt.da;
            if mass == MassKind::Consistent {
                for b in 0..M {
                    let v = nn[a] * nn[b] * w * pt.da;
                    for c in 0..3 {
                        m[(6 * a + c) * ND + 6 * b + c] += mt * v;
                        m[(6 * a + 3 + c) * ND + 6 * b + 3 + c] += mr * v;
                    }
                }
            }
        }
    }
    if mass == MassKind::Lumped {
        let total: f64 = diag.iter().sum();
        for a in 0..M {
            for c in 0..3 {
                m[(6 * a + c) * ND + 6 * a + c] = mt * area * diag[a] / total;
            }
        }
    }
    let (kg, mg) = if s.offset == 0.0 {
        (k, m)
    } else {
        // u_ref = u + theta x (offset n) at each node
        let mut t = vec![0.0; ND * ND];
        for i in 0..ND {
            t[i * ND + i] = 1.0;
        }
        for (node, ni) in n0.iter().enumerate() {
            let (u, th) = (6 * node, 6 * node + 3);
            for c in 0..3 {
                let mut e = [0.0; 3];
                e[c] = 1.0;
                let col = cross(e, *ni);
                for r in 0..3 {
                    t[(u + r) * ND + th + c] += s.offset * col[r];
                }
            }
        }
        let mg = match mass {
            MassKind::Consistent => crate::structural::congruence(&m, &t, ND, ND),
            MassKind::Lumped => m,
        };
        (crate::structural::congruence(&k, &t, ND, ND), mg)
    };
    // drilling, on the grids' surface (an offset leaves it alone): k_d (theta_i . n_i -
    // omega_i)^2 at each node, omega the tangent rotation (u_2,1 - u_1,2) / 2 of the grids'
    // in-plane motion there (zero for every rigid motion)
    let mut kg = kg;
    let (cx, cy) = centre(topo);
    let (_, _, _, g) = section(s, &point(topo, x, &n0, cx, cy).axes, sc)?;
    let kd = sc.linear * crate::shell::drilling(s) * g * s.t * area * 4.0 / M as f64;
    for (i, &(a, b)) in topo.nodes.iter().enumerate() {
        let pt = point(topo, x, &n0, a, b);
        let mut d = [0.0; ND];
        for (c, l) in pt.l0.iter().enumerate() {
            d[c] = -0.5 * (l[0][1] - l[1][0]);
        }
        for c in 0..3 {
            d[6 * i + 3 + c] += pt.axes[2][c];
        }
        for r in 0..ND {
            for c in 0..ND {
                kg[r * ND + c] += kd * d[r] * d[c];
            }
        }
    }
    Ok((kg, mg))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shape_functions_are_a_partition_of_unity_and_interpolate() {
        for &(xi, eta) in &[(0.3, -0.7), (0.0, 0.0), (-0.5, 0.9)] {
            let (n, dx, de) = shape(xi, eta);

            assert!((n.iter().sum::<f64>() - 1.0).abs() < 1e-14);
            assert!(dx.iter().sum::<f64>().abs() < 1e-14);
            assert!(de.iter().sum::<f64>().abs() < 1e-14);
        }
        for (i, &(a, b)) in NODES.iter().enumerate() {
            let (n, _, _) = shape(a, b);
            for (j, v) in n.iter().enumerate() {
                assert!((v - if i == j { 1.0 } else { 0.0 }).abs() < 1e-14);
            }
        }
    }
}
