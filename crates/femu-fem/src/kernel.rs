//! Element matrices of the isoparametric solids.
//!
//! - Stiffness: `K_e = int_e B^T D B dV`, the weak form of linear elasticity
//!   `a(u, v) = int eps(v)^T D eps(u) dV`, with the rules of [`crate::element`].
//! - Consistent mass: `M_e = int_e rho N^T N dV` (each 3x3 block `rho int N_a N_b dV I_3`).
//! - Lumped mass: row sums of the consistent mass for linear elements; HRZ (the consistent
//!   diagonal scaled to conserve the element mass) for quadratic ones, whose row sums are zero or
//!   negative at corners.
//!
//! Element DOFs are node-major: DOF `3 a + i` is component `i` of node `a`. Matrices are dense
//! row-major `(3 n) x (3 n)` slices.

use crate::element::{ElementKind, Tabulated};

/// A non-positive or non-finite Jacobian determinant found at an integration point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BadJacobian {
    /// Reference coordinates of the integration point.
    pub point: [f64; 3],
    /// The determinant found.
    pub det: f64,
}

/// Jacobian `J[i][k] = dx_i / dxi_k` at a tabulated point from the reference gradients `dn`
/// (`3 * nn` values) and the node coordinates.
#[inline]
fn jacobian(coords: &[[f64; 3]], dn: &[f64]) -> [[f64; 3]; 3] {
    let mut j = [[0.0; 3]; 3];
    for (a, x) in coords.iter().enumerate() {
        let g = &dn[3 * a..3 * a + 3];
        for i in 0..3 {
            for k in 0..3 {
                j[i][k] += x[i] * g[k];
            }
        }
    }
    j
}

#[inline]
fn det3(j: &[[f64; 3]; 3]) -> f64 {
    j[0][0] * (j[1][1] * j[2][2] - j[1][2] * j[2][1])
        - j[0][1] * (j[1][0] * j[2][2] - j[1][2] * j[2][0])
        + j[0][2] * (j[1][0] * j[2][1] - j[1][1] * j[2][0])
}

/// Physical gradients `g[3 a + i] = dN_a / dx_i` at one point; returns `det J`.
#[inline]
fn physical_gradients(coords: &[[f64; 3]], dn: &[f64], g: &mut [f64]) -> f64 {
    let j = jacobian(coords, dn);
    let det = det3(&j);
    let inv = 1.0 / det;
    // (J^-1)[k][i] = cofactor(i, k) / det
    let c = [
        [
            j[1][1] * j[2][2] - j[1][2] * j[2][1],
            j[0][2] * j[2][1] - j[0][1] * j[2][2],
            j[0][1] * j[1][2] - j[0][2] * j[1][1],
        ],
        [
            j[1][2] * j[2][0] - j[1][0] * j[2][2],
            j[0][0] * j[2][2] - j[0][2] * j[2][0],
            j[0][2] * j[1][0] - j[0][0] * j[1][2],
        ],
        [
            j[1][0] * j[2][1] - j[1][1] * j[2][0],
            j[0][1] * j[2][0] - j[0][0] * j[2][1],
            j[0][0] * j[1][1] - j[0][1] * j[1][0],
        ],
    ];
    for a in 0..coords.len() {
        let d = &dn[3 * a..3 * a + 3];
        for i in 0..3 {
            // dN/dx_i = sum_k dN/dxi_k (J^-1)[k][i]
            g[3 * a + i] = (d[0] * c[0][i] + d[1] * c[1][i] + d[2] * c[2][i]) * inv;
        }
    }
    det
}

fn check_det(tab: &Tabulated, q: usize, det: f64) -> Result<(), BadJacobian> {
    if det.is_finite() && det > 0.0 {
        Ok(())
    } else {
        Err(BadJacobian {
            point: tab.rule.points[q],
            det,
        })
    }
}

/// The smallest Jacobian determinant over the stiffness and mass integration points and the
/// element's nodes (a cell is valid when it is positive everywhere), with where it occurs.
pub fn min_jacobian(kind: ElementKind, coords: &[[f64; 3]]) -> BadJacobian {
    let r = kind.reference();
    let mut worst = BadJacobian {
        point: [0.0; 3],
        det: f64::INFINITY,
    };
    let mut dn = vec![0.0; 3 * kind.num_nodes()];
    let nodes = kind.reference_nodes();
    let tabs = [&r.stiffness, &r.mass];
    let tab_points = tabs.iter().flat_map(|t| {
        (0..t.rule.len()).map(move |q| {
            (
                t.rule.points[q],
                Some(&t.dn[3 * q * kind.num_nodes()..3 * (q + 1) * kind.num_nodes()]),
            )
        })
    });
    let node_points = nodes.iter().map(|p| (*p, None));
    for (p, tab) in tab_points.chain(node_points) {
        let g = match tab {
            Some(g) => g,
            None => {
                kind.shape_gradients(p, &mut dn);
                &dn[..]
            }
        };
        let det = det3(&jacobian(coords, g));
        if det.is_nan() || det < worst.det {
            worst = BadJacobian { point: p, det };
        }
    }
    worst
}

/// Element volume `int_e dV` (with the mass rule, exact for undistorted elements).
///
/// # Errors
/// [`BadJacobian`] at the first integration point with `det J <= 0`.
pub fn element_volume(kind: ElementKind, coords: &[[f64; 3]]) -> Result<f64, BadJacobian> {
    let tab = &kind.reference().mass;
    let nn = kind.num_nodes();
    let mut v = 0.0;
    for q in 0..tab.rule.len() {
        let det = det3(&jacobian(coords, &tab.dn[3 * q * nn..3 * (q + 1) * nn]));
        check_det(tab, q, det)?;
        v += tab.rule.weights[q] * det;
    }
    Ok(v)
}

/// Element stiffness `K_e = int B^T D B dV` into `out` (row-major, `(3 nn)^2`, overwritten).
/// `d` is the 6x6 elasticity matrix in Voigt order `(11, 22, 33, 12, 13, 23)`.
///
/// # Errors
/// [`BadJacobian`] at the first integration point with `det J <= 0`.
pub fn element_stiffness(
    kind: ElementKind,
    coords: &[[f64; 3]],
    d: &[[f64; 6]; 6],
    out: &mut [f64],
) -> Result<(), BadJacobian> {
    let nn = kind.num_nodes();
    let nd = 3 * nn;
    debug_assert_eq!(coords.len(), nn);
    debug_assert_eq!(out.len(), nd * nd);
    out.iter_mut().for_each(|v| *v = 0.0);
    let tab = &kind.reference().stiffness;
    let mut g = [0.0; 60];
    for q in 0..tab.rule.len() {
        let det = physical_gradients(coords, &tab.dn[3 * q * nn..3 * (q + 1) * nn], &mut g[..nd]);
        check_det(tab, q, det)?;
        add_btdb_upper(&g[..nd], d, tab.rule.weights[q] * det, out);
    }
    mirror_upper_blocks(out, nn);
    Ok(())
}

/// Adds `w B^T D B` to the upper node-block triangle of `out` (`3 n` square, row-major), for the
/// physical gradients `g[3 a + i] = dN_a / dx_i` of `n = g.len() / 3 <= 20` shape functions and
/// the 6x6 `d` in Voigt order `(11, 22, 33, 12, 13, 23)`.
fn add_btdb_upper(g: &[f64], d: &[[f64; 6]; 6], w: f64, out: &mut [f64]) {
    let nn = g.len() / 3;
    let nd = 3 * nn;
    let mut db = [[0.0; 18]; 20];
    // D B_b for every node b (6x3, row-major)
    for b in 0..nn {
        let (gx, gy, gz) = (g[3 * b], g[3 * b + 1], g[3 * b + 2]);
        let m = &mut db[b];
        for r in 0..6 {
            let dr = &d[r];
            m[3 * r] = (dr[0] * gx + dr[3] * gy + dr[4] * gz) * w;
            m[3 * r + 1] = (dr[1] * gy + dr[3] * gx + dr[5] * gz) * w;
            m[3 * r + 2] = (dr[2] * gz + dr[4] * gx + dr[5] * gy) * w;
        }
    }
    for a in 0..nn {
        let (gx, gy, gz) = (g[3 * a], g[3 * a + 1], g[3 * a + 2]);
        for b in a..nn {
            let m = &db[b];
            for j in 0..3 {
                let k0 = gx * m[j] + gy * m[9 + j] + gz * m[12 + j];
                let k1 = gy * m[3 + j] + gx * m[9 + j] + gz * m[15 + j];
                let k2 = gz * m[6 + j] + gx * m[12 + j] + gy * m[15 + j];
                out[(3 * a) * nd + 3 * b + j] += k0;
                out[(3 * a + 1) * nd + 3 * b + j] += k1;
                out[(3 * a + 2) * nd + 3 * b + j] += k2;
            }
        }
    }
}

/// Stiffness of the 8-node brick with incompatible modes (docs/MATH.md, "The brick with
/// incompatible modes"): the trilinear displacement enriched, per component, by the three bubbles
/// `P_k = 1 - xi_k^2` with element-internal amplitudes `alpha`, whose gradients are formed with
/// the Jacobian at the centre `J_0` and scaled by `det J_0 / det J` (Taylor's form, so that a
/// constant strain leaves the bubbles at rest on any shape: the patch test); `K = K_uu - K_ua
/// K_aa^-1 K_au` after integration by the 2x2x2 rule. The bubbles carry no mass. On a
/// parallelepiped this is CalculiX's C3D8I stiffness; it represents pure bending of a rectangular
/// brick exactly, where the fully integrated brick locks in shear. `coords` are the 8 nodes in
/// [`ElementKind::Hex8`] order; `out` is `24 x 24`, row-major, overwritten.
///
/// # Errors
/// [`BadJacobian`] at the centre or at the first integration point with `det J <= 0`.
pub fn hex8_incompatible_stiffness(
    coords: &[[f64; 3]],
    d: &[[f64; 6]; 6],
    out: &mut [f64],
) -> Result<(), BadJacobian> {
    hex8_incompatible(coords, Elastic::Matrix(d), out)
}

/// The elasticity of a kernel: Lame parameters (the Gram-matrix form of
/// [`element_stiffness_isotropic`]) or a 6x6 matrix.
#[derive(Clone, Copy)]
enum Elastic<'a> {
    Isotropic { lambda: f64, mu: f64 },
    Matrix(&'a [[f64; 6]; 6]),
}

fn hex8_incompatible(
    coords: &[[f64; 3]],
    elastic: Elastic<'_>,
    out: &mut [f64],
) -> Result<(), BadJacobian> {
    const N: usize = 33; // 24 nodal DOFs and 9 bubble amplitudes
    const Q: usize = 8; // the 2x2x2 rule
    debug_assert_eq!(coords.len(), 8);
    debug_assert_eq!(out.len(), 24 * 24);
    let kind = ElementKind::Hex8;
    let tab = &kind.reference().stiffness;
    debug_assert_eq!(tab.rule.len(), Q);
    // the centre's Jacobian: the bubbles' gradients are mapped with it
    let mut dn0 = [0.0; 24];
    kind.shape_gradients([0.0; 3], &mut dn0);
    let j0 = jacobian(coords, &dn0);
    let det0 = det3(&j0);
    if !(det0.is_finite() && det0 > 0.0) {
        return Err(BadJacobian {
            point: [0.0; 3],
            det: det0,
        });
    }
    let inv0 = inverse(&j0, det0);
    // one row per point: sqrt(w |J|) times the 8 nodal gradients and the 3 bubbles' gradients
    // dP_b/dx_i = -2 xi_b (J_0^-1)[b][i] det0 / det
    let mut gs = [0.0; Q * N];
    for q in 0..Q {
        let g = &mut gs[q * N..(q + 1) * N];
        let det = physical_gradients(coords, &tab.dn[24 * q..24 * (q + 1)], &mut g[..24]);
        check_det(tab, q, det)?;
        let xi = tab.rule.points[q];
        for b in 0..3 {
            let scale = -2.0 * xi[b] * det0 / det;
            for i in 0..3 {
                g[24 + 3 * b + i] = scale * inv0[b][i];
            }
        }
        let sw = (tab.rule.weights[q] * det).sqrt();
        g.iter_mut().for_each(|v| *v *= sw);
    }
    let mut k = [0.0; N * N];
    match elastic {
        Elastic::Isotropic { lambda, mu } => isotropic_from_gradients(&gs, Q, lambda, mu, &mut k),
        Elastic::Matrix(d) => {
            for q in 0..Q {
                add_btdb_upper(&gs[q * N..(q + 1) * N], d, 1.0, &mut k);
            }
            mirror_upper_blocks(&mut k, 11);
        }
    }
    condense(&k, out)
}

/// `K_uu - K_ua K_aa^-1 K_au` of the 33 x 33 brick-and-bubbles matrix `k` into `out` (24 x 24).
fn condense(k: &[f64], out: &mut [f64]) -> Result<(), BadJacobian> {
    const N: usize = 33;
    let k_aa: [[f64; 9]; 9] =
        std::array::from_fn(|i| std::array::from_fn(|j| k[(24 + i) * N + 24 + j]));
    condensation::<9, 24>(
        &k_aa,
        |i, c| k[(24 + i) * N + c],
        |r, c, v| {
            let v = k[r * N + c] - v;
            out[r * 24 + c] = v;
            out[c * 24 + r] = v;
        },
    )
    .map_err(|det| BadJacobian {
        point: [0.0; 3],
        det,
    })
}

/// Static condensation of `A` internal DOFs from `N` outer ones: with `K_aa = L L^T` (Cholesky)
/// and `Y = L^-1 K_au`, `apply(r, c, (Y^T Y)[r][c])` for each outer pair `r <= c` (the matrix is
/// symmetric), the term `K_ua K_aa^-1 K_au` that `K_uu` loses. `K_au(i, c)` is internal row `i`,
/// outer column `c`. Fails with the pivot when `K_aa` is not positive definite (a pivot not above
/// `1e-12` of its diagonal).
pub(crate) fn condensation<const A: usize, const N: usize>(
    k_aa: &[[f64; A]; A],
    k_au: impl Fn(usize, usize) -> f64,
    mut apply: impl FnMut(usize, usize, f64),
) -> Result<(), f64> {
    let mut l = [[0.0; A]; A];
    for i in 0..A {
        for j in 0..=i {
            let mut v = k_aa[i][j];
            for p in 0..j {
                v -= l[i][p] * l[j][p];
            }
            if i == j {
                if !(v.is_finite() && v > 1e-12 * k_aa[i][i]) {
                    return Err(v);
                }
                l[i][i] = v.sqrt();
            } else {
                l[i][j] = v / l[j][j];
            }
        }
    }
    // Y = L^-1 K_au by forward substitution, column by column of K_au
    let mut y = [[0.0; A]; N];
    for (c, yc) in y.iter_mut().enumerate() {
        for i in 0..A {
            let mut v = k_au(i, c);
            for p in 0..i {
                v -= l[i][p] * yc[p];
            }
            yc[i] = v / l[i][i];
        }
    }
    for r in 0..N {
        for c in r..N {
            apply(r, c, (0..A).map(|i| y[r][i] * y[c][i]).sum());
        }
    }
    Ok(())
}

/// `J^-1` with `inv[k][i] = d xi_k / d x_i`, from `J[i][k] = dx_i / dxi_k` and its determinant.
fn inverse(j: &[[f64; 3]; 3], det: f64) -> [[f64; 3]; 3] {
    let mut inv = [[0.0; 3]; 3];
    for (k, row) in inv.iter_mut().enumerate() {
        for (i, v) in row.iter_mut().enumerate() {
            // cofactor of J[i][k] (transposed: the adjugate)
            let (i1, i2) = ((i + 1) % 3, (i + 2) % 3);
            let (k1, k2) = ((k + 1) % 3, (k + 2) % 3);
            *v = (j[i1][k1] * j[i2][k2] - j[i1][k2] * j[i2][k1]) / det;
        }
    }
    inv
}

/// Element stiffness of an isotropic material with Lame parameters `lambda`, `mu` (Pa), equal to
/// [`element_stiffness`] with its `D` to round-off and several times faster: with the Gram matrix
/// of the physical gradients `A[3a+i, 3b+j] = sum_q w_q dN_a/dx_i dN_b/dx_j` (one symmetric
/// rank-`n_q` product), `K[3a+i, 3b+j] = lambda A[3a+i, 3b+j] + mu A[3a+j, 3b+i] + mu delta_ij
/// sum_k A[3a+k, 3b+k]` (docs/MATH.md, "Isotropic element stiffness").
///
/// # Errors
/// [`BadJacobian`] at the first integration point with `det J <= 0`.
pub fn element_stiffness_isotropic(
    kind: ElementKind,
    coords: &[[f64; 3]],
    lambda: f64,
    mu: f64,
    out: &mut [f64],
) -> Result<(), BadJacobian> {
    let nn = kind.num_nodes();
    let nd = 3 * nn;
    debug_assert_eq!(coords.len(), nn);
    debug_assert_eq!(out.len(), nd * nd);
    let tab = &kind.reference().stiffness;
    let nq = tab.rule.len();
    // sqrt(w_q) dN_a/dx_i, one row per integration point (at most 45 points x 60 columns)
    let mut gs = [0.0; 45 * 60];
    for q in 0..nq {
        let row = &mut gs[q * nd..(q + 1) * nd];
        let det = physical_gradients(coords, &tab.dn[3 * q * nn..3 * (q + 1) * nn], row);
        check_det(tab, q, det)?;
        let sw = (tab.rule.weights[q] * det).sqrt();
        row.iter_mut().for_each(|v| *v *= sw);
    }
    isotropic_from_gradients(&gs[..nq * nd], nq, lambda, mu, out);
    Ok(())
}

/// `K` of an isotropic material from the rows `sqrt(w_q |J_q|) grad N` of `gs` (`nq` rows of
/// `3 n` values, row-major) into `out` (`3 n` square): the Gram matrix `A = G^T G` and `K[3a+i,
/// 3b+j] = lambda A[3a+i, 3b+j] + mu A[3a+j, 3b+i] + mu delta_ij sum_k A[3a+k, 3b+k]`.
fn isotropic_from_gradients(gs: &[f64], nq: usize, lambda: f64, mu: f64, out: &mut [f64]) {
    let nd = gs.len() / nq;
    let nn = nd / 3;
    // the upper triangle of A = G^T G (row-major), which is the lower triangle of the same storage
    // read column-major: one triangular product (faer's SIMD kernels; the strict lower triangle of
    // `out` is not written)
    {
        use faer::linalg::matmul::triangular::{BlockStructure, matmul};
        let g = faer::MatRef::from_row_major_slice(gs, nq, nd);
        let a = faer::MatMut::from_column_major_slice_mut(out, nd, nd);
        matmul(
            a,
            BlockStructure::TriangularLower,
            faer::Accum::Replace,
            g.transpose(),
            BlockStructure::Rectangular,
            g,
            BlockStructure::Rectangular,
            1.0,
            faer::Par::Seq,
        );
    }
    // K from A block by block over the upper node-block triangle, each block written with its
    // mirror image: a block of K needs only the same block of A, and for a < b that block lies in
    // A's upper triangle; the lower half of a diagonal block is read from its upper half, so the
    // diagonal blocks come out exactly symmetric.
    for a in 0..nn {
        for b in a..nn {
            let mut blk = [[0.0; 3]; 3];
            for (i, row) in blk.iter_mut().enumerate() {
                for (j, v) in row.iter_mut().enumerate() {
                    let (r, c) = (3 * a + i, 3 * b + j);
                    *v = if r <= c {
                        out[r * nd + c]
                    } else {
                        out[c * nd + r]
                    };
                }
            }
            let tr = blk[0][0] + blk[1][1] + blk[2][2];
            for i in 0..3 {
                for j in 0..3 {
                    let mut v = lambda * blk[i][j] + mu * blk[j][i];
                    if i == j {
                        v += mu * tr;
                    }
                    out[(3 * a + i) * nd + 3 * b + j] = v;
                    out[(3 * b + j) * nd + 3 * a + i] = v;
                }
            }
        }
    }
}

/// Element stiffness for `material` and `formulation`: incompatible modes for a brick that asks
/// for them ([`hex8_incompatible_stiffness`]), else the isotropic kernel for isotropic materials
/// and `B^T D B` otherwise.
///
/// # Errors
/// [`BadJacobian`] at the first integration point with `det J <= 0`.
pub fn element_stiffness_for(
    kind: ElementKind,
    formulation: crate::element::Formulation,
    coords: &[[f64; 3]],
    material: &crate::material::Material,
    out: &mut [f64],
) -> Result<(), BadJacobian> {
    if formulation == crate::element::Formulation::IncompatibleModes && kind == ElementKind::Hex8 {
        let elastic = match &material.elasticity {
            crate::material::Elasticity::Isotropic { e, nu } => {
                let (lambda, mu) = crate::material::lame_parameters(*e, *nu);
                Elastic::Isotropic { lambda, mu }
            }
            crate::material::Elasticity::Anisotropic(_) => {
                return hex8_incompatible_stiffness(coords, &material.elasticity_matrix(), out);
            }
        };
        return hex8_incompatible(coords, elastic, out);
    }
    match &material.elasticity {
        crate::material::Elasticity::Isotropic { e, nu } => {
            let (lambda, mu) = crate::material::lame_parameters(*e, *nu);
            element_stiffness_isotropic(kind, coords, lambda, mu, out)
        }
        crate::material::Elasticity::Anisotropic(_) => {
            element_stiffness(kind, coords, &material.elasticity_matrix(), out)
        }
    }
}

/// Copies the upper node-block triangle of an element matrix (`3 nn` square, row-major) onto the
/// lower one, and symmetrises the diagonal blocks' round-off.
fn mirror_upper_blocks(out: &mut [f64], nn: usize) {
    let nd = 3 * nn;
    for a in 0..nn {
        for b in a + 1..nn {
            for i in 0..3 {
                for j in 0..3 {
                    out[(3 * b + j) * nd + 3 * a + i] = out[(3 * a + i) * nd + 3 * b + j];
                }
            }
        }
        // Diagonal blocks are symmetric in exact arithmetic; symmetrise round-off.
        for i in 0..3 {
            for j in i + 1..3 {
                let s =
                    0.5 * (out[(3 * a + i) * nd + 3 * a + j] + out[(3 * a + j) * nd + 3 * a + i]);
                out[(3 * a + i) * nd + 3 * a + j] = s;
                out[(3 * a + j) * nd + 3 * a + i] = s;
            }
        }
    }
}

/// Scalar consistent mass `m_ab = rho int N_a N_b dV` into `out` (`nn x nn`, row-major).
///
/// # Errors
/// [`BadJacobian`] at the first integration point with `det J <= 0`.
pub fn scalar_mass(
    kind: ElementKind,
    coords: &[[f64; 3]],
    rho: f64,
    out: &mut [f64],
) -> Result<(), BadJacobian> {
    let nn = kind.num_nodes();
    out.iter_mut().for_each(|v| *v = 0.0);
    let tab = &kind.reference().mass;
    for q in 0..tab.rule.len() {
        let det = det3(&jacobian(coords, &tab.dn[3 * q * nn..3 * (q + 1) * nn]));
        check_det(tab, q, det)?;
        let w = tab.rule.weights[q] * det * rho;
        let n = &tab.n[q * nn..(q + 1) * nn];
        for a in 0..nn {
            let wa = w * n[a];
            for b in a..nn {
                out[a * nn + b] += wa * n[b];
            }
        }
    }
    for a in 0..nn {
        for b in a + 1..nn {
            out[b * nn + a] = out[a * nn + b];
        }
    }
    Ok(())
}

/// Consistent element mass `M_e` (row-major `(3 nn)^2`): `M_e[3a+i][3b+j] = m_ab delta_ij`.
///
/// # Errors
/// [`BadJacobian`] at the first integration point with `det J <= 0`.
pub fn element_mass(
    kind: ElementKind,
    coords: &[[f64; 3]],
    rho: f64,
    out: &mut [f64],
) -> Result<(), BadJacobian> {
    let nn = kind.num_nodes();
    let nd = 3 * nn;
    let mut m = [0.0; 400];
    scalar_mass(kind, coords, rho, &mut m[..nn * nn])?;
    out.iter_mut().for_each(|v| *v = 0.0);
    for a in 0..nn {
        for b in 0..nn {
            for i in 0..3 {
                out[(3 * a + i) * nd + 3 * b + i] = m[a * nn + b];
            }
        }
    }
    Ok(())
}

/// Lumped nodal masses (kg, one per node, the same for its three DOFs) into `out` (`nn`):
/// row sums for linear elements, HRZ for quadratic ones. Both conserve `rho * volume`.
///
/// # Errors
/// [`BadJacobian`] at the first integration point with `det J <= 0`.
pub fn lumped_mass(
    kind: ElementKind,
    coords: &[[f64; 3]],
    rho: f64,
    out: &mut [f64],
) -> Result<(), BadJacobian> {
    let nn = kind.num_nodes();
    let mut m = [0.0; 400];
    scalar_mass(kind, coords, rho, &mut m[..nn * nn])?;
    if kind.is_quadratic() {
        let total: f64 = m[..nn * nn].iter().sum();
        let diag: f64 = (0..nn).map(|a| m[a * nn + a]).sum();
        for a in 0..nn {
            out[a] = m[a * nn + a] * total / diag;
        }
    } else {
        for a in 0..nn {
            out[a] = m[a * nn..(a + 1) * nn].iter().sum();
        }
    }
    Ok(())
}

/// Strain (Voigt, engineering shear) at reference point `xi` for nodal displacements `u`
/// (`3 nn`, node-major).
///
/// # Errors
/// [`BadJacobian`] if `det J <= 0` at `xi`.
pub fn strain_at(
    kind: ElementKind,
    coords: &[[f64; 3]],
    u: &[f64],
    xi: [f64; 3],
) -> Result<[f64; 6], BadJacobian> {
    let nn = kind.num_nodes();
    let mut dn = vec![0.0; 3 * nn];
    let mut g = vec![0.0; 3 * nn];
    kind.shape_gradients(xi, &mut dn);
    let det = physical_gradients(coords, &dn, &mut g);
    if !(det.is_finite() && det > 0.0) {
        return Err(BadJacobian { point: xi, det });
    }
    let mut e = [0.0; 6];
    for a in 0..nn {
        let (gx, gy, gz) = (g[3 * a], g[3 * a + 1], g[3 * a + 2]);
        let (ux, uy, uz) = (u[3 * a], u[3 * a + 1], u[3 * a + 2]);
        e[0] += gx * ux;
        e[1] += gy * uy;
        e[2] += gz * uz;
        e[3] += gy * ux + gx * uy;
        e[4] += gz * ux + gx * uz;
        e[5] += gz * uy + gy * uz;
    }
    Ok(e)
}

/// Physical coordinates of reference point `xi` in the element.
pub fn map_point(kind: ElementKind, coords: &[[f64; 3]], xi: [f64; 3]) -> [f64; 3] {
    let mut n = vec![0.0; kind.num_nodes()];
    kind.shape(xi, &mut n);
    let mut x = [0.0; 3];
    for (a, c) in coords.iter().enumerate() {
        for i in 0..3 {
            x[i] += n[a] * c[i];
        }
    }
    x
}
