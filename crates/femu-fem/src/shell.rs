//! The 4-node flat shell: a bilinear membrane, a Reissner-Mindlin plate whose transverse shear is
//! interpolated from tying points (MITC4, Bathe and Dvorkin 1985), free of shear locking, and a
//! drilling stiffness tying each node's in-plane rotation to the membrane's rotation
//! (docs/MATH.md, "Shells").
//!
//! The element is formed in its own plane: `e1` along the mean of the edges 1-2 and 4-3, `n` the
//! normal of the two mid-lines, `e2 = n x e1`; nodes off that plane (a warped quadrilateral) are
//! projected onto it, up to a warp of [`MAX_WARP`].

use crate::FemError;
use crate::assembly::MassKind;

/// The largest warp femu builds a flat quadrilateral for: the largest distance of a corner from
/// the element's mean plane over the square root of its area (Nastran warns above 0.05).
pub const MAX_WARP: f64 = 0.05;

/// A shell's material and section (Nastran PSHELL with an isotropic MAT1, Abaqus *SHELL
/// SECTION).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shell {
    /// Young's modulus (Pa).
    pub e: f64,
    /// Poisson's ratio.
    pub nu: f64,
    /// Density (kg/m^3).
    pub rho: f64,
    /// Thickness (m).
    pub t: f64,
    /// The bending stiffness's factor over a solid section's `t^3 / 12` (Nastran's `12I/T^3`).
    /// Zero makes a membrane alone (Nastran's PSHELL with MID2 blank): no bending, no transverse
    /// shear, no drilling stiffness, and the element does not reach its nodes' rotations (its
    /// `shear` must then be `None` and its `offset` zero).
    pub bending: f64,
    /// The transverse shear factor (Nastran's `TS/T`, 5/6 for a solid section); `None`: no shear
    /// flexibility (Nastran's blank MID3), built as a shear stiffness 1,000 times a solid
    /// section's, which the tying points keep from locking.
    pub shear: Option<f64>,
    /// Non-structural mass per area (kg/m^2).
    pub nsm: f64,
    /// An anisotropic section (Nastran MAT2 or MAT8, or different materials for membrane,
    /// bending and shear): its matrices replace `e` and `nu`'s (docs/MATH.md, "Shells").
    pub material: Option<ShellMaterial>,
    /// The reference plane's offset from the grids along the element's normal (m; Nastran's
    /// ZOFFS): the grids drive it through rigid links (docs/MATH.md, "Shells").
    pub offset: f64,
    /// The 4-node shell's membrane (docs/MATH.md, "Shells"); the 3- and 8-node shells have one
    /// membrane each and ignore it.
    pub membrane: Membrane,
}

/// The 4-node shell's membrane (docs/MATH.md, "Shells").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Membrane {
    /// The bilinear membrane: the strains of the corners' displacements at the 2 x 2 Gauss
    /// points. It is stiff in in-plane bending on coarse meshes (a bending strain linear across
    /// the element comes with a parasitic shear); Abaqus's and CalculiX's M3D4.
    Full,
    /// The bilinear membrane enriched by the incompatible modes `(1 - xi^2)` and `(1 - eta^2)` of
    /// each in-plane displacement, their gradients taken with the centre's Jacobian (Taylor,
    /// Beresford and Wilson's QM6, which passes the patch test on any quadrilateral) and condensed
    /// out in the element: exact in-plane bending on rectangles. MSC and Simcenter Nastran's
    /// CQUAD4 membrane (their eigenvalues to the printed digits; docs/VERIFICATION.md) and the
    /// in-plane behaviour of Abaqus's S4.
    #[default]
    Incompatible,
}

/// A shell section's material matrices in its material axes, and the material's first axis.
/// The membrane stiffness is `t membrane`, the bending stiffness `bending t^3 / 12 bending`, the
/// transverse shear `TS/T t shear` (Nastran's PSHELL with the MID1, MID2 and MID3 materials).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShellMaterial {
    /// The membrane material (Pa) on `(eps_11, eps_22, gamma_12)` in the material axes.
    pub membrane: [[f64; 3]; 3],
    /// The bending material (Pa), in the same order.
    pub bending: [[f64; 3]; 3],
    /// The transverse shear material (Pa) on `(gamma_1z, gamma_2z)`.
    pub shear: [[f64; 2]; 2],
    /// The material's first axis (basic frame); the element projects it onto its plane.
    pub axis: [f64; 3],
}

/// One ply of a laminate ([`laminate`]): its plane-stress material `q` (Pa, on `(eps_1, eps_2,
/// gamma_12)` in the ply's axes), its transverse shear material (Pa, on `(gamma_1z, gamma_2z)`;
/// `None`: no shear flexibility), its density, thickness and angle (degrees) from the section's
/// material axis about the normal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ply {
    /// Plane-stress material in the ply's axes.
    pub q: [[f64; 3]; 3],
    /// Transverse shear material in the ply's axes, or none (rigid in shear).
    pub shear: Option<[[f64; 2]; 2]>,
    /// Density (kg/m^3).
    pub rho: f64,
    /// Thickness (m).
    pub t: f64,
    /// Angle of the ply's first axis from the section's material axis (degrees).
    pub theta: f64,
}

/// Why a stack of plies is not a section femu builds ([`laminate`]).
#[derive(Debug, Clone, PartialEq)]
pub enum LaminateError {
    /// No ply, or a ply without a positive thickness (its index).
    Ply(usize),
    /// The laminate is not symmetric about its mid-plane: its membrane-bending coupling `B`
    /// reaches this fraction of `A T`.
    Unsymmetric(f64),
    /// The plies' transverse shear materials, turned to the material axes, differ (or some plies
    /// have one and some not).
    Shear,
}

impl std::fmt::Display for LaminateError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LaminateError::Ply(k) => write!(f, "ply {} has no positive thickness", k + 1),
            LaminateError::Unsymmetric(r) => write!(
                f,
                "the laminate is not symmetric about its mid-plane (its membrane-bending coupling B reaches {r:.2e} of A T): femu's shells do not model that coupling (Nastran's PSHELL MID4)"
            ),
            LaminateError::Shear => write!(
                f,
                "its plies' transverse shear moduli differ (turned to the material axes, or given for some plies and not others): the laminate's shear stiffness then depends on the stacking, which femu does not compute (give the plies no transverse shear flexibility, Nastran's blank MAT8 G1Z and G2Z, or an equivalent homogeneous section)"
            ),
        }
    }
}

/// The shell section of a laminate by classical lamination theory (docs/MATH.md, "Laminates"):
/// each ply's `Qbar = T^T Q T` turned by its angle (`T` the strain rotation of [`ShellMaterial`]'s
/// element turn), stacked from the bottom surface (`z_0 = -T/2` from the mid-plane, `T` the plies'
/// total), `A = sum Qbar t`, `B = sum Qbar (z_k^2 - z_(k-1)^2) / 2`, `D = sum Qbar (z_k^3 -
/// z_(k-1)^3) / 3`: the anisotropic section of thickness `T` with membrane material `A / T`,
/// bending material `12 D / T^3`, the plies' one transverse shear material with the homogeneous
/// section's factor 5/6 (or none), density `sum rho t / T`; no non-structural mass and no offset
/// (the caller's). The material axis is the basic x axis until the element sets it.
///
/// # Errors
/// [`LaminateError`]: no ply or one of no thickness; `B` above `1e-9 A T` (unsymmetric); plies of
/// different transverse shear.
pub fn laminate(plies: &[Ply]) -> Result<Shell, LaminateError> {
    if plies.is_empty() {
        return Err(LaminateError::Ply(0));
    }
    if let Some(k) = plies.iter().position(|p| !(p.t > 0.0 && p.t.is_finite())) {
        return Err(LaminateError::Ply(k));
    }
    let total: f64 = plies.iter().map(|q| q.t).sum();
    let mut a = [[0.0; 3]; 3];
    let mut b = [[0.0; 3]; 3];
    let mut d = [[0.0; 3]; 3];
    let mut mass = 0.0;
    let mut shears: Vec<Option<[[f64; 2]; 2]>> = Vec::with_capacity(plies.len());
    let mut z0 = -total / 2.0;
    for ply in plies {
        let (sn, cs) = ply.theta.to_radians().sin_cos();
        // strains (eps_x, eps_y, gamma_xy) in the material axes to the ply's (1, 2)
        let tr = [
            [cs * cs, sn * sn, cs * sn],
            [sn * sn, cs * cs, -cs * sn],
            [-2.0 * cs * sn, 2.0 * cs * sn, cs * cs - sn * sn],
        ];
        let z1 = z0 + ply.t;
        for r in 0..3 {
            for c in 0..3 {
                let mut qb = 0.0;
                for k in 0..3 {
                    for l in 0..3 {
                        qb += tr[k][r] * ply.q[k][l] * tr[l][c];
                    }
                }
                a[r][c] += qb * ply.t;
                b[r][c] += qb * (z1 * z1 - z0 * z0) / 2.0;
                d[r][c] += qb * (z1.powi(3) - z0.powi(3)) / 3.0;
            }
        }
        mass += ply.rho * ply.t;
        // (gamma_1z, gamma_2z) of the ply from the material axes' (gamma_xz, gamma_yz)
        let rot = [[cs, sn], [-sn, cs]];
        shears.push(ply.shear.map(|g| {
            let mut gb = [[0.0; 2]; 2];
            for r in 0..2 {
                for c in 0..2 {
                    for k in 0..2 {
                        for l in 0..2 {
                            gb[r][c] += rot[k][r] * g[k][l] * rot[l][c];
                        }
                    }
                }
            }
            gb
        }));
        z0 = z1;
    }
    let largest = |m: &[[f64; 3]; 3]| m.iter().flatten().fold(0.0f64, |x, v| x.max(v.abs()));
    let coupling = largest(&b) / (largest(&a) * total);
    if coupling > 1e-9 {
        return Err(LaminateError::Unsymmetric(coupling));
    }
    let same = |x: &[[f64; 2]; 2], y: &[[f64; 2]; 2]| {
        let scale = x.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        x.iter()
            .flatten()
            .zip(y.iter().flatten())
            .all(|(u, v)| (u - v).abs() <= 1e-9 * scale)
    };
    let shear = match shears[0] {
        None if shears.iter().all(Option::is_none) => None,
        Some(g)
            if shears
                .iter()
                .all(|s| s.as_ref().is_some_and(|h| same(&g, h))) =>
        {
            Some(g)
        }
        _ => return Err(LaminateError::Shear),
    };
    let scale = |m: &[[f64; 3]; 3], f: f64| m.map(|r| r.map(|v| v * f));
    Ok(Shell {
        e: 0.0,
        nu: 0.0,
        rho: mass / total,
        t: total,
        bending: 1.0,
        // the homogeneous section's factor on the plies' one transverse shear material
        shear: shear.map(|_| 5.0 / 6.0),
        nsm: 0.0,
        material: Some(ShellMaterial {
            membrane: scale(&a, 1.0 / total),
            bending: scale(&d, 12.0 / total.powi(3)),
            shear: shear.unwrap_or([[0.0; 2]; 2]),
            axis: [1.0, 0.0, 0.0],
        }),
        offset: 0.0,
        membrane: Membrane::Incompatible,
    })
}

/// The section's membrane, bending and transverse shear matrices in the element's axes `e` (rows
/// `e1`, `e2`, `n`) with the parts scaled by `sc`, and the shear modulus of the drilling
/// stiffness.
pub(crate) fn section(s: &Shell, e: &[V3; 3], sc: Scales) -> Result<SectionMatrices, String> {
    let t = s.t;
    // a membrane alone has no transverse shear
    let shear_factor = if s.bending == 0.0 {
        0.0
    } else {
        s.shear.unwrap_or(1000.0 * 5.0 / 6.0)
    };
    let Some(mat) = &s.material else {
        let (e, nu) = (s.e, s.nu);
        let g = e / (2.0 * (1.0 + nu));
        let ds = sc.linear * shear_factor * g * t;
        return Ok((
            plane_stress(sc.linear * e * t / (1.0 - nu * nu), nu),
            plane_stress(
                sc.cubic * s.bending * e * t.powi(3) / (12.0 * (1.0 - nu * nu)),
                nu,
            ),
            [[ds, 0.0], [0.0, ds]],
            g,
        ));
    };
    // the material axis in the element's plane: cos and sin of its angle from e1
    let a = mat.axis;
    let (c, sn) = (dot(a, e[0]), dot(a, e[1]));
    let len = (c * c + sn * sn).sqrt();
    if !(len > 1e-6 * dot(a, a).sqrt()) {
        return Err("its material axis is normal to the element".into());
    }
    let (c, sn) = (c / len, sn / len);
    // engineering strains in the material axes from the element's: eps_m = T eps_e
    let tr = [
        [c * c, sn * sn, c * sn],
        [sn * sn, c * c, -c * sn],
        [-2.0 * c * sn, 2.0 * c * sn, c * c - sn * sn],
    ];
    let turn = |d: &[[f64; 3]; 3], f: f64| -> [[f64; 3]; 3] {
        std::array::from_fn(|i| {
            std::array::from_fn(|j| {
                let mut v = 0.0;
                for a in 0..3 {
                    for b in 0..3 {
                        v += tr[a][i] * d[a][b] * tr[b][j];
                    }
                }
                f * v
            })
        })
    };
    let cm = turn(&mat.membrane, sc.linear * t);
    let cb = turn(&mat.bending, sc.cubic * s.bending * t.powi(3) / 12.0);
    let g = turn(&mat.membrane, 1.0)[2][2];
    let rs = [[c, sn], [-sn, c]];
    let cs: [[f64; 2]; 2] = match s.shear {
        Some(k) if s.bending > 0.0 => std::array::from_fn(|i| {
            std::array::from_fn(|j| {
                let mut v = 0.0;
                for a in 0..2 {
                    for b in 0..2 {
                        v += rs[a][i] * mat.shear[a][b] * rs[b][j];
                    }
                }
                sc.linear * k * t * v
            })
        }),
        _ => {
            let ds = sc.linear * shear_factor * g * t;
            [[ds, 0.0], [0.0, ds]]
        }
    };
    Ok((cm, cb, cs, g))
}

/// Membrane, bending and shear matrices of a section in an element's axes, and the drilling's
/// shear modulus.
type SectionMatrices = ([[f64; 3]; 3], [[f64; 3]; 3], [[f64; 2]; 2], f64);

pub(crate) type V3 = [f64; 3];

fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub(crate) fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub(crate) fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

pub(crate) fn unit(a: V3) -> Option<V3> {
    let n = dot(a, a).sqrt();
    (n > 0.0 && n.is_finite()).then(|| [a[0] / n, a[1] / n, a[2] / n])
}

const CORNERS: [(f64, f64); 4] = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];

/// Shape functions and their derivatives in `(xi, eta)`.
fn shape(xi: f64, eta: f64) -> ([f64; 4], [f64; 4], [f64; 4]) {
    let mut n = [0.0; 4];
    let mut dxi = [0.0; 4];
    let mut deta = [0.0; 4];
    for (i, (a, b)) in CORNERS.iter().enumerate() {
        n[i] = 0.25 * (1.0 + a * xi) * (1.0 + b * eta);
        dxi[i] = 0.25 * a * (1.0 + b * eta);
        deta[i] = 0.25 * b * (1.0 + a * xi);
    }
    (n, dxi, deta)
}

/// The axes of a shell's plane (rows `e1`, `e2`, `n`), its corners in that plane, and its warp.
pub type ShellFrame = ([V3; 3], [[f64; 2]; 4], f64);

/// `D (1, nu, 0; nu, 1, 0; 0, 0, (1 - nu) / 2)`: plane stress of stiffness `d`.
fn plane_stress(d: f64, nu: f64) -> [[f64; 3]; 3] {
    [
        [d, d * nu, 0.0],
        [d * nu, d, 0.0],
        [0.0, 0.0, d * (1.0 - nu) / 2.0],
    ]
}

/// `k += w B^T D B` for the first `rows` rows of `b` (each `N` columns) and `d`, row-major `k`
/// (`D` symmetric: the upper triangle is formed and mirrored; columns of `B` that are zero in
/// every row are skipped).
pub(crate) fn add_btdb<const N: usize>(
    k: &mut [f64],
    b: &[[f64; N]],
    d: &[[f64; 3]; 3],
    rows: usize,
    w: f64,
) {
    // w D B, rows x N
    let mut db = [[0.0; N]; 3];
    for a in 0..rows {
        for c in 0..N {
            let mut v = 0.0;
            for q in 0..rows {
                v += d[a][q] * b[q][c];
            }
            db[a][c] = w * v;
        }
    }
    for r in 0..N {
        if (0..rows).all(|a| b[a][r] == 0.0) {
            continue;
        }
        for c in r..N {
            let mut v = 0.0;
            for a in 0..rows {
                v += b[a][r] * db[a][c];
            }
            k[r * N + c] += v;
            if c != r {
                k[c * N + r] += v;
            }
        }
    }
}

/// The membrane rows `(u_,x, v_,y, u_,y + v_,x)` and the curvature rows `(beta_x,x, beta_y,y,
/// beta_x,y + beta_y,x)` (`beta_x = theta_y`, `beta_y = -theta_x`) of the corners with gradients
/// `(nx, ny)`, on `N = 6 corners` DOFs.
fn strain_rows<const N: usize>(nx: &[f64], ny: &[f64]) -> ([[f64; N]; 3], [[f64; N]; 3]) {
    let mut bm = [[0.0; N]; 3];
    let mut bb = [[0.0; N]; 3];
    for i in 0..nx.len() {
        bm[0][6 * i] = nx[i];
        bm[1][6 * i + 1] = ny[i];
        bm[2][6 * i] = ny[i];
        bm[2][6 * i + 1] = nx[i];
        bb[0][6 * i + 4] = nx[i];
        bb[1][6 * i + 3] = -ny[i];
        bb[2][6 * i + 4] = ny[i];
        bb[2][6 * i + 3] = -nx[i];
    }
    (bm, bb)
}

/// The drilling stiffness's factor on `G t A`: `1e-3`, or none for a membrane alone (which does
/// not reach the rotations).
pub(crate) fn drilling(s: &Shell) -> f64 {
    if s.bending == 0.0 { 0.0 } else { 1e-3 }
}

/// The drilling stiffness `kd sum_i (theta_z,i - omega)^2`, `omega = (v_,x - u_,y) / 2` from the
/// corners' gradients `(nx, ny)` (at the centre), added to `k`.
fn add_drilling<const N: usize>(k: &mut [f64], nx: &[f64], ny: &[f64], kd: f64) {
    let mut omega = [0.0; N];
    for i in 0..nx.len() {
        omega[6 * i + 1] = 0.5 * nx[i];
        omega[6 * i] = -0.5 * ny[i];
    }
    for i in 0..nx.len() {
        let mut d = omega.map(|v| -v);
        d[6 * i + 5] += 1.0;
        for r in 0..N {
            for c in 0..N {
                k[r * N + c] += kd * d[r] * d[c];
            }
        }
    }
}

/// The element's stiffness and mass turned from its axes (rows of `axes`) to the basic frame; a
/// lumped (translational) mass is the same in every frame.
fn to_basic<const N: usize>(
    k: &[f64],
    m: Vec<f64>,
    axes: &[V3; 3],
    mass: MassKind,
    offset: f64,
) -> (Vec<f64>, Vec<f64>) {
    let mut tm = vec![0.0; N * N];
    for blk in 0..N / 3 {
        for r in 0..3 {
            for c in 0..3 {
                tm[(3 * blk + r) * N + 3 * blk + c] = axes[r][c];
            }
        }
    }
    // an offset reference plane: u_ref = u + theta x (z n), in the element's axes (u_x += z
    // theta_y, u_y -= z theta_x), on each corner's translations from its rotations
    if offset != 0.0 {
        for corner in 0..N / 6 {
            let (u, th) = (6 * corner, 6 * corner + 3);
            for c in 0..3 {
                tm[u * N + th + c] += offset * axes[1][c];
                tm[(u + 1) * N + th + c] -= offset * axes[0][c];
            }
        }
    }
    let kg = crate::structural::congruence(k, &tm, N, N);
    let mg = match mass {
        MassKind::Consistent => crate::structural::congruence(&m, &tm, N, N),
        MassKind::Lumped => m,
    };
    (kg, mg)
}

/// The Jacobian `[[x_,xi, y_,xi], [x_,eta, y_,eta]]` of the map from `(xi, eta)` to the
/// element's plane, whose corners are `p`.
fn jacobian(p: &[[f64; 2]; 4], xi: f64, eta: f64) -> [[f64; 2]; 2] {
    let (_, dxi, deta) = shape(xi, eta);
    let mut j = [[0.0; 2]; 2];
    for i in 0..4 {
        j[0][0] += dxi[i] * p[i][0];
        j[0][1] += dxi[i] * p[i][1];
        j[1][0] += deta[i] * p[i][0];
        j[1][1] += deta[i] * p[i][1];
    }
    j
}

/// A quadrilateral's axes and corners in its plane ([`frame`]), refused when it is warped beyond
/// [`MAX_WARP`] or its Jacobian is not positive at every 2 x 2 Gauss point.
fn checked_quad(x: &[V3; 4]) -> Result<([V3; 3], [[f64; 2]; 4]), String> {
    let (axes, p, warp) = frame(x)?;
    if warp > MAX_WARP {
        return Err(format!(
            "it is warped: a corner lies {warp:.3} times the square root of its area from its mean plane, above femu's limit of {MAX_WARP} for a flat shell (split it into flatter elements)"
        ));
    }
    let gp = 1.0 / 3f64.sqrt();
    for (xi, eta) in [(-gp, -gp), (gp, -gp), (gp, gp), (-gp, gp)] {
        let j = jacobian(&p, xi, eta);
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        if !(det > 0.0) {
            return Err(format!(
                "its Jacobian is {det:e} at a Gauss point: the quadrilateral is inverted or degenerate"
            ));
        }
    }
    Ok((axes, p))
}

/// Checks a shell's nodes (three, four or eight, basic frame) without forming its matrices: a
/// triangle that spans an area; a quadrilateral whose corners go round it, warped no more than
/// [`MAX_WARP`], with a positive Jacobian at every Gauss point; an 8-node shell as
/// [`crate::shell8::check8`].
///
/// # Errors
/// The message [`matrices`] or [`matrices3`] would give for the geometry.
pub fn check(x: &[V3]) -> Result<(), String> {
    if x.len() == 6 {
        for (k, t) in SIX_NODE_TRIANGLES.iter().enumerate() {
            unit(cross(sub(x[t[1]], x[t[0]]), sub(x[t[2]], x[t[0]]))).ok_or_else(|| {
                format!(
                    "its sub-triangle {} (nodes {}, {}, {}) has no area: a midside node on a corner or off its edge",
                    k + 1,
                    t[0] + 1,
                    t[1] + 1,
                    t[2] + 1
                )
            })?;
        }
        return Ok(());
    }
    match x {
        [a, b, c, d] => checked_quad(&[*a, *b, *c, *d]).map(|_| ()),
        [a, b, c] => unit(cross(sub(*b, *a), sub(*c, *a)))
            .map(|_| ())
            .ok_or_else(|| "its corners do not span a triangle (collinear or coincident)".into()),
        [_, _, _, _, _, _, _, _] => crate::shell8::check8(&std::array::from_fn(|i| x[i])),
        _ => Err(format!("a shell has 3, 4, 6 or 8 nodes, not {}", x.len())),
    }
}

/// The four three-node triangles (local node indices) a six-node triangle is built from: one at
/// each corner and the middle one, on the corners 1-3 and the midside nodes 4 (edge 1-2), 5
/// (2-3), 6 (3-1), each counter-clockwise as the element (docs/MATH.md, "Six-node triangles").
pub const SIX_NODE_TRIANGLES: [[usize; 3]; 4] = [[0, 3, 5], [3, 1, 4], [5, 4, 2], [3, 4, 5]];

/// The element's plane: its axes (rows `e1`, `e2`, `n`), its corners in that plane, and its warp.
///
/// # Errors
/// A message for a degenerate quadrilateral.
pub fn frame(x: &[V3; 4]) -> Result<ShellFrame, String> {
    let c: V3 = std::array::from_fn(|k| 0.25 * (x[0][k] + x[1][k] + x[2][k] + x[3][k]));
    let g1: V3 = std::array::from_fn(|k| 0.5 * (x[1][k] - x[0][k] + x[2][k] - x[3][k]));
    let g2: V3 = std::array::from_fn(|k| 0.5 * (x[2][k] - x[1][k] + x[3][k] - x[0][k]));
    let n = unit(cross(g1, g2))
        .ok_or("its corners do not span a quadrilateral (collinear or coincident)")?;
    let e1 = unit(g1).ok_or("its corners do not span a quadrilateral")?;
    let e2 = cross(n, e1);
    let mut local = [[0.0; 2]; 4];
    let mut h: f64 = 0.0;
    for i in 0..4 {
        let d = sub(x[i], c);
        local[i] = [dot(d, e1), dot(d, e2)];
        h = h.max(dot(d, n).abs());
    }
    // area of the projected quadrilateral (shoelace)
    let area = 0.5
        * (0..4)
            .map(|i| {
                let j = (i + 1) % 4;
                local[i][0] * local[j][1] - local[j][0] * local[i][1]
            })
            .sum::<f64>();
    if !(area > 0.0) {
        return Err(format!(
            "its corners are not in order around it (area {area:e} in its own plane)"
        ));
    }
    Ok(([e1, e2, n], local, h / area.sqrt()))
}

/// The shell's stiffness and mass (24 x 24, row-major) on `(u, v, w, theta_x, theta_y,
/// theta_z)` of each corner in the basic frame. The lumped mass puts a quarter of the mass on
/// each corner's translations and nothing on rotations; the consistent mass carries the section's
/// rotary inertia `rho I` on every rotation, the drilling one included (it makes the consistent
/// mass positive definite, so that the `M^-1` norms of the estimators exist; the low modes move by
/// `O((t / L)^2)` of the bending rotary inertia's own small effect: docs/MATH.md, "Shells").
///
/// # Errors
/// A message for a degenerate, inverted (a non-positive Jacobian at a Gauss point) or warped
/// quadrilateral.
pub fn matrices(s: &Shell, x: &[V3; 4], mass: MassKind) -> Result<(Vec<f64>, Vec<f64>), String> {
    matrices_scaled(s, x, mass, Scales::ALL)
}

/// Multipliers of the parts of a shell's matrices by how they depend on the thickness `t`: the
/// membrane, transverse shear and drilling stiffness and the mass `rho t` are linear in `t`, the
/// bending stiffness and the rotary inertia cubic, the non-structural mass independent of it.
/// `Scales::ALL` gives the element's matrices; `(1, 0, 0)` and `(0, 1, 0)` its parts, from which
/// the matrices at any thickness `t (1 + p)` are `(1 + p) K_1 + (1 + p)^3 K_3` exactly
/// (docs/MATH.md, "Thickness parameters").
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Scales {
    pub linear: f64,
    pub cubic: f64,
    pub nsm: f64,
}

impl Scales {
    pub const ALL: Scales = Scales {
        linear: 1.0,
        cubic: 1.0,
        nsm: 1.0,
    };
}

/// [`matrices`] with its parts scaled by `sc`.
pub(crate) fn matrices_scaled(
    s: &Shell,
    x: &[V3; 4],
    mass: MassKind,
    sc: Scales,
) -> Result<(Vec<f64>, Vec<f64>), String> {
    let (axes, p) = checked_quad(x)?;
    let t = s.t;
    let (cm, cb, ds, g) = section(s, &axes, sc)?;
    let mut k = vec![0.0; 576];
    let mut m = vec![0.0; 576];
    let jac = |xi: f64, eta: f64| jacobian(&p, xi, eta);
    // the covariant shear strain rows at a point: gamma_xi (along xi) or gamma_eta
    let shear_row = |xi: f64, eta: f64, along_xi: bool| -> [f64; 24] {
        let (nn, dxi, deta) = shape(xi, eta);
        let j = jac(xi, eta);
        let (d, r) = if along_xi { (dxi, j[0]) } else { (deta, j[1]) };
        let mut row = [0.0; 24];
        for i in 0..4 {
            row[6 * i + 2] = d[i];
            // beta_x = theta_y, beta_y = -theta_x: gamma = w_,s + beta . x_,s
            row[6 * i + 4] = nn[i] * r[0];
            row[6 * i + 3] = -nn[i] * r[1];
        }
        row
    };
    let (a_row, c_row) = (shear_row(0.0, 1.0, true), shear_row(0.0, -1.0, true));
    let (b_row, d_row) = (shear_row(1.0, 0.0, false), shear_row(-1.0, 0.0, false));
    // the centre's Jacobian: the drilling's rotation and the incompatible modes' gradients
    let (inv0, det0) = {
        let j = jac(0.0, 0.0);
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        let inv = [
            [j[1][1] / det, -j[0][1] / det],
            [-j[1][0] / det, j[0][0] / det],
        ];
        (inv, det)
    };
    // the incompatible modes (u: 0, 1; v: 2, 3) with the membrane (rows) and with each other
    let incompatible = s.membrane == Membrane::Incompatible && sc.linear != 0.0;
    let mut k_ma = [[0.0; 4]; 24];
    let mut k_aa = [[0.0; 4]; 4];
    let gp = 1.0 / 3f64.sqrt();
    let mut area = 0.0;
    for (xi, eta) in [(-gp, -gp), (gp, -gp), (gp, gp), (-gp, gp)] {
        let (nn, dxi, deta) = shape(xi, eta);
        let j = jac(xi, eta);
        // positive at every Gauss point: checked_quad
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        area += det;
        let inv = [
            [j[1][1] / det, -j[0][1] / det],
            [-j[1][0] / det, j[0][0] / det],
        ];
        let mut nx = [0.0; 4];
        let mut ny = [0.0; 4];
        for i in 0..4 {
            nx[i] = inv[0][0] * dxi[i] + inv[0][1] * deta[i];
            ny[i] = inv[1][0] * dxi[i] + inv[1][1] * deta[i];
        }
        let (bm, bb) = strain_rows::<24>(&nx, &ny);
        if incompatible {
            // Taylor's QM6: the modes' strains B_a (1 - xi^2, 1 - eta^2 for u, then for v) with
            // J0^-1, weighted by det0 in place of det, so that their integral vanishes
            let grad = |q: usize| {
                let d = if q == 0 {
                    [-2.0 * xi, 0.0]
                } else {
                    [0.0, -2.0 * eta]
                };
                [
                    inv0[0][0] * d[0] + inv0[0][1] * d[1],
                    inv0[1][0] * d[0] + inv0[1][1] * d[1],
                ]
            };
            let mut ba = [[0.0; 4]; 3];
            for q in 0..2 {
                let [gx, gy] = grad(q);
                ba[0][q] = gx;
                ba[2][q] = gy;
                ba[1][2 + q] = gy;
                ba[2][2 + q] = gx;
            }
            let cba: [[f64; 4]; 3] = std::array::from_fn(|a| {
                std::array::from_fn(|c| (0..3).map(|b| cm[a][b] * ba[b][c]).sum())
            });
            for c in 0..4 {
                for r in 0..24 {
                    k_ma[r][c] += (0..3).map(|a| bm[a][r] * cba[a][c]).sum::<f64>() * det0;
                }
                for r in 0..4 {
                    k_aa[r][c] +=
                        (0..3).map(|a| ba[a][r] * cba[a][c]).sum::<f64>() * det0 * det0 / det;
                }
            }
        }
        // MITC4: gamma_xi from A (0, 1) and C (0, -1), gamma_eta from B (1, 0) and D (-1, 0),
        // then (gamma_xz, gamma_yz) = J^-1 (gamma_xi, gamma_eta)
        let mut gxi = [0.0; 24];
        let mut geta = [0.0; 24];
        for c in 0..24 {
            gxi[c] = 0.5 * (1.0 + eta) * a_row[c] + 0.5 * (1.0 - eta) * c_row[c];
            geta[c] = 0.5 * (1.0 + xi) * b_row[c] + 0.5 * (1.0 - xi) * d_row[c];
        }
        let mut bs = [[0.0; 24]; 2];
        for c in 0..24 {
            bs[0][c] = inv[0][0] * gxi[c] + inv[0][1] * geta[c];
            bs[1][c] = inv[1][0] * gxi[c] + inv[1][1] * geta[c];
        }
        add_btdb(&mut k, &bm, &cm, 3, det);
        add_btdb(&mut k, &bb, &cb, 3, det);
        let cs = [
            [ds[0][0], ds[0][1], 0.0],
            [ds[1][0], ds[1][1], 0.0],
            [0.0, 0.0, 0.0],
        ];
        add_btdb(&mut k, &bs, &cs, 2, det);
        if mass == MassKind::Consistent {
            let (mt, mr) = (
                sc.linear * s.rho * t + sc.nsm * s.nsm,
                sc.cubic * s.rho * s.bending * t.powi(3) / 12.0,
            );
            for a in 0..4 {
                for b in 0..4 {
                    let v = nn[a] * nn[b] * det;
                    for c in 0..3 {
                        m[(6 * a + c) * 24 + 6 * b + c] += mt * v;
                    }
                    for c in 3..6 {
                        m[(6 * a + c) * 24 + 6 * b + c] += mr * v;
                    }
                }
            }
        }
    }
    if mass == MassKind::Lumped {
        let each = (sc.linear * s.rho * t + sc.nsm * s.nsm) * area / 4.0;
        for a in 0..4 {
            for c in 0..3 {
                m[(6 * a + c) * 24 + 6 * a + c] = each;
            }
        }
    }
    if incompatible {
        condense(&mut k, &k_ma, &k_aa)?;
    }
    // drilling: k_d (theta_z,i - omega)^2 at each corner, omega = (v_,x - u_,y) / 2 at the centre
    let (_, dxi, deta) = shape(0.0, 0.0);
    let nx: [f64; 4] = std::array::from_fn(|i| inv0[0][0] * dxi[i] + inv0[0][1] * deta[i]);
    let ny: [f64; 4] = std::array::from_fn(|i| inv0[1][0] * dxi[i] + inv0[1][1] * deta[i]);
    add_drilling::<24>(&mut k, &nx, &ny, sc.linear * drilling(s) * g * t * area);
    Ok(to_basic::<24>(&k, m, &axes, mass, s.offset))
}

/// The incompatible modes condensed out of the element's stiffness: `k -= k_ma k_aa^-1 k_ma^T`
/// (`k_aa` is positive definite for a membrane material that is and a convex quadrilateral).
fn condense(k: &mut [f64], k_ma: &[[f64; 4]; 24], k_aa: &[[f64; 4]; 4]) -> Result<(), String> {
    crate::kernel::condensation::<4, 24>(
        k_aa,
        |i, c| k_ma[c][i],
        |r, c, v| {
            k[r * 24 + c] -= v;
            if r != c {
                k[c * 24 + r] -= v;
            }
        },
    )
    .map_err(|_| {
        "its membrane's incompatible modes have no stiffness (a membrane material that is not positive definite)"
            .to_string()
    })
}

/// The 3-node shell (MITC3, Lee and Bathe 2004) on `(u, v, w, theta_x, theta_y, theta_z)` of
/// each corner in the basic frame (18 x 18, row-major): a constant-strain membrane, constant
/// curvatures, and the transverse shear tied at the edges' midpoints. With `gamma_r = w_,r +
/// beta . x_,r` and `gamma_s` likewise, and `c = (gamma_s(0, 1/2) - gamma_r(1/2, 0)) -
/// (gamma_s(1/2, 1/2) - gamma_r(1/2, 1/2))`, the element's strains are `gamma_r(1/2, 0) + c s`
/// and `gamma_s(0, 1/2) - c r`: each edge's tangential shear is its midpoint's. Drilling and
/// mass are the 4-node shell's (docs/MATH.md, "Shells").
///
/// # Errors
/// A message for corners that do not span a triangle.
pub fn matrices3(s: &Shell, x: &[V3; 3], mass: MassKind) -> Result<(Vec<f64>, Vec<f64>), String> {
    matrices3_scaled(s, x, mass, Scales::ALL)
}

/// [`matrices3`] with its parts scaled by `sc`.
pub(crate) fn matrices3_scaled(
    s: &Shell,
    x: &[V3; 3],
    mass: MassKind,
    sc: Scales,
) -> Result<(Vec<f64>, Vec<f64>), String> {
    let g1 = sub(x[1], x[0]);
    let g2 = sub(x[2], x[0]);
    let n = unit(cross(g1, g2))
        .ok_or("its corners do not span a triangle (collinear or coincident)")?;
    let e1 = unit(g1).ok_or("its corners do not span a triangle")?;
    let e2 = cross(n, e1);
    let p: [[f64; 2]; 3] = std::array::from_fn(|i| {
        let d = sub(x[i], x[0]);
        [dot(d, e1), dot(d, e2)]
    });
    // J = [[x_,r, y_,r], [x_,s, y_,s]], constant
    let j = [
        [p[1][0] - p[0][0], p[1][1] - p[0][1]],
        [p[2][0] - p[0][0], p[2][1] - p[0][1]],
    ];
    let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
    if !(det > 0.0) {
        return Err(format!("its area is {:e}", det / 2.0));
    }
    let area = det / 2.0;
    let inv = [
        [j[1][1] / det, -j[0][1] / det],
        [-j[1][0] / det, j[0][0] / det],
    ];
    let (dr, ds) = ([-1.0, 1.0, 0.0], [-1.0, 0.0, 1.0]);
    let nx: [f64; 3] = std::array::from_fn(|i| inv[0][0] * dr[i] + inv[0][1] * ds[i]);
    let ny: [f64; 3] = std::array::from_fn(|i| inv[1][0] * dr[i] + inv[1][1] * ds[i]);
    let t = s.t;
    let (cm, cb, dsh, g) = section(s, &[e1, e2, n], sc)?;
    let nd = 18;
    let mut k = vec![0.0; nd * nd];
    let mut m = vec![0.0; nd * nd];
    // membrane and bending: constant
    let (bm, bb) = strain_rows::<18>(&nx, &ny);
    add_btdb(&mut k, &bm, &cm, 3, area);
    add_btdb(&mut k, &bb, &cb, 3, area);
    // covariant shear rows at (r, s): gamma_r (along r) or gamma_s
    let shape3 = |r: f64, s: f64| [1.0 - r - s, r, s];
    let row = |r: f64, s: f64, along_r: bool| -> [f64; 18] {
        let nn = shape3(r, s);
        let (d, jr) = if along_r { (dr, j[0]) } else { (ds, j[1]) };
        let mut out = [0.0; 18];
        for i in 0..3 {
            out[6 * i + 2] = d[i];
            out[6 * i + 4] = nn[i] * jr[0];
            out[6 * i + 3] = -nn[i] * jr[1];
        }
        out
    };
    let (r1, s2) = (row(0.5, 0.0, true), row(0.0, 0.5, false));
    let (r3, s3) = (row(0.5, 0.5, true), row(0.5, 0.5, false));
    let c: [f64; 18] = std::array::from_fn(|q| (s2[q] - r1[q]) - (s3[q] - r3[q]));
    let (mt, mr) = (
        sc.linear * s.rho * t + sc.nsm * s.nsm,
        sc.cubic * s.rho * s.bending * t.powi(3) / 12.0,
    );
    for (r, sp) in [
        (1.0 / 6.0, 1.0 / 6.0),
        (2.0 / 3.0, 1.0 / 6.0),
        (1.0 / 6.0, 2.0 / 3.0),
    ] {
        let w = det / 6.0;
        let gr: [f64; 18] = std::array::from_fn(|q| r1[q] + c[q] * sp);
        let gs: [f64; 18] = std::array::from_fn(|q| s2[q] - c[q] * r);
        let mut bs = [[0.0; 18]; 2];
        for q in 0..18 {
            bs[0][q] = inv[0][0] * gr[q] + inv[0][1] * gs[q];
            bs[1][q] = inv[1][0] * gr[q] + inv[1][1] * gs[q];
        }
        let cs = [
            [dsh[0][0], dsh[0][1], 0.0],
            [dsh[1][0], dsh[1][1], 0.0],
            [0.0, 0.0, 0.0],
        ];
        add_btdb(&mut k, &bs, &cs, 2, w);
        if mass == MassKind::Consistent {
            let nn = shape3(r, sp);
            for a in 0..3 {
                for b in 0..3 {
                    let v = nn[a] * nn[b] * w;
                    for q in 0..3 {
                        m[(6 * a + q) * nd + 6 * b + q] += mt * v;
                    }
                    for q in 3..6 {
                        m[(6 * a + q) * nd + 6 * b + q] += mr * v;
                    }
                }
            }
        }
    }
    if mass == MassKind::Lumped {
        for a in 0..3 {
            for q in 0..3 {
                m[(6 * a + q) * nd + 6 * a + q] = mt * area / 3.0;
            }
        }
    }
    // drilling: k_d (theta_z,i - omega)^2, omega = (v_,x - u_,y) / 2
    add_drilling::<18>(&mut k, &nx, &ny, sc.linear * drilling(s) * g * t * area);
    Ok(to_basic::<18>(&k, m, &[e1, e2, n], mass, s.offset))
}

impl Shell {
    /// Checks the values.
    ///
    /// # Errors
    /// [`FemError::InvalidStructural`] naming `element`.
    pub fn validate(&self, element: u64) -> Result<(), FemError> {
        let bad = |reason: String| Err(FemError::InvalidStructural { element, reason });
        if !(self.t > 0.0 && self.t.is_finite()) {
            return bad(format!(
                "its thickness is {}; a shell needs a positive thickness",
                self.t
            ));
        }
        match &self.material {
            None => {
                if !(self.e > 0.0 && self.e.is_finite() && self.nu > -1.0 && self.nu < 0.5) {
                    return bad(format!(
                        "E = {} and nu = {} are not a material",
                        self.e, self.nu
                    ));
                }
            }
            Some(m) => {
                for (what, d) in [("membrane", &m.membrane), ("bending", &m.bending)] {
                    let a = nalgebra::Matrix3::from_fn(|i, j| d[i][j]);
                    let scale = a.iter().fold(0.0f64, |x, v| x.max(v.abs()));
                    if a.iter().any(|v| !v.is_finite())
                        || (a - a.transpose()).iter().any(|v| v.abs() > 1e-9 * scale)
                        || !(a.symmetric_eigenvalues().min() > 1e-12 * scale)
                    {
                        return bad(format!(
                            "its {what} material {d:?} is not symmetric positive definite"
                        ));
                    }
                }
                let sh = m.shear;
                if self.shear.is_some()
                    && !(sh[0][0] > 0.0
                        && sh[1][1] > 0.0
                        && (sh[0][1] - sh[1][0]).abs() <= 1e-9 * sh[0][0].max(sh[1][1])
                        && sh[0][0] * sh[1][1] > sh[0][1] * sh[1][0])
                {
                    return bad(format!(
                        "its transverse shear material {sh:?} is not symmetric positive definite"
                    ));
                }
                if !m.axis.iter().all(|v| v.is_finite()) || m.axis.iter().all(|v| *v == 0.0) {
                    return bad(format!("its material axis {:?} is not a direction", m.axis));
                }
            }
        }
        if !self.offset.is_finite() {
            return bad(format!("its offset {} is not a number", self.offset));
        }
        if !(self.rho >= 0.0 && self.nsm >= 0.0 && self.rho.is_finite() && self.nsm.is_finite()) {
            return bad(format!(
                "density {} and nsm {} must not be negative",
                self.rho, self.nsm
            ));
        }
        if !(self.bending >= 0.0 && self.bending.is_finite())
            || self.shear.is_some_and(|k| !(k > 0.0))
        {
            return bad(format!(
                "its bending factor {} and shear factor {:?} must be positive (a bending factor of 0: a membrane)",
                self.bending, self.shear
            ));
        }
        if self.bending == 0.0 && (self.shear.is_some() || self.offset != 0.0) {
            return bad(format!(
                "it is a membrane (no bending), which has no transverse shear and no offset: shear factor {:?}, offset {}",
                self.shear, self.offset
            ));
        }
        Ok(())
    }
}
