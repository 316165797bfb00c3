//! The three-node beam (Abaqus' and CalculiX's `B32`, Gmsh's 3-node line): a quadratic,
//! isoparametric Timoshenko beam that may be curved (docs/MATH.md, "The three-node beam").
//!
//! Its nodes are femu's order: the two ends, then the middle node. Positions, displacements `u`
//! and rotations `theta` are interpolated by the quadratic shape functions of `xi` in `[-1, 1]`
//! (ends at `-1` and `1`, the middle node at 0). At each point the axis is the tangent `t = x' /
//! |x'|`, the section's axis `y` the orientation vector made normal to it and `z = t x y`. The
//! strains are those of a linear Reissner beam, `Gamma = u' + t x theta` (axial `t . Gamma`,
//! shears `y . Gamma`, `z . Gamma`) and `kappa = theta'` (torsion `t . kappa`, bending `y .
//! kappa`, `z . kappa`), `'` the derivative by arc length; both vanish for a rigid motion of a
//! curved element exactly, as its interpolation holds `u = w x x` and `theta = w`. The stiffness
//! is integrated at two Gauss points (the shear strains then do not lock in thin beams), the
//! masses at five, with the same section constants and rotary inertia as the two-node
//! beam ([`crate::structural::Beam`]): `E A`, `K1 G A` and `K2 G A`, `G J`, `E I1` (plane 1, `x-y`,
//! about `z`) and `E I2`; `rho A + nsm` on the translations, `rho I1` about `z`, `rho I2` about `y`
//! and `rho (I1 + I2)` about the axis.

use crate::assembly::MassKind;
use crate::shell::dot;
use crate::structural::{Beam, line_axes};

type V3 = [f64; 3];

/// The shape functions and their derivatives by `xi` at `xi` (ends, then the middle node).
fn shape(xi: f64) -> ([f64; 3], [f64; 3]) {
    (
        [0.5 * xi * (xi - 1.0), 0.5 * xi * (xi + 1.0), 1.0 - xi * xi],
        [xi - 0.5, xi + 0.5, -2.0 * xi],
    )
}

/// `dx/dxi` at `xi`.
fn tangent(x: &[V3; 3], xi: f64) -> V3 {
    let (_, d) = shape(xi);
    std::array::from_fn(|c| (0..3).map(|a| d[a] * x[a][c]).sum())
}

/// The local axes `[t, y, z]` and `|dx/dxi|` at `xi`: the two-node beam's axes
/// ([`line_axes`]) of the tangent `dx/dxi`.
///
/// # Errors
/// A message for a degenerate point or an orientation vector along the axis there.
fn axes(x: &[V3; 3], v: V3, xi: f64) -> Result<([V3; 3], f64), String> {
    let (j, axes) =
        line_axes([0.0; 3], tangent(x, xi), v).map_err(|e| format!("{e} (at xi = {xi})"))?;
    Ok((axes, j))
}

/// Checks a three-node beam's geometry at node positions `x` (ends, then the middle node): the
/// mapping's tangent at the ends and the middle keeps the direction of the chord (the middle node
/// lies between the quarter points, where the mapping turns singular), and the orientation vector
/// is not along the axis anywhere it is evaluated.
///
/// # Errors
/// A message naming what is wrong.
pub fn check(b: &Beam, x: &[V3; 3]) -> Result<(), String> {
    let chord: V3 = std::array::from_fn(|c| x[1][c] - x[0][c]);
    let l = dot(chord, chord).sqrt();
    if !(l > 0.0 && l.is_finite()) {
        return Err(format!("its ends coincide (length {l:e})"));
    }
    for xi in [-1.0, 0.0, 1.0] {
        if !(dot(tangent(x, xi), chord) > 0.0) {
            return Err(format!(
                "its middle node {:?} lies outside the middle half of its ends {:?} and {:?}: the element folds back on itself",
                x[2], x[0], x[1]
            ));
        }
    }
    for xi in [
        -1.0,
        -(1.0f64 / 3.0).sqrt(),
        0.0,
        (1.0f64 / 3.0).sqrt(),
        1.0,
    ] {
        axes(x, b.orientation, xi)?;
    }
    Ok(())
}

/// The 5-point Gauss rule on `[-1, 1]`: the mass's and the length's (exact for a straight
/// element's mass, of degree 4, and close for a curved one's, whose `|x'|` is not a polynomial).
const GAUSS5: [(f64, f64); 5] = [
    (0.0, 0.568_888_888_888_888_9),
    (0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
    (-0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
    (0.906_179_845_938_664, 0.236_926_885_056_189_08),
    (-0.906_179_845_938_664, 0.236_926_885_056_189_08),
];

/// The beam's length along its axis (the 5-point Gauss rule: the consistent and lumped masses
/// add up to `(rho A + nsm)` times it).
pub fn length(x: &[V3; 3]) -> f64 {
    GAUSS5
        .iter()
        .map(|(xi, w)| {
            let d = tangent(x, *xi);
            w * dot(d, d).sqrt()
        })
        .sum()
}

/// Stiffness and mass (18 x 18, row-major) on `(u, theta)` of the ends and the middle node in
/// the basic frame, at node positions `x`.
///
/// # Errors
/// As [`check`].
pub fn matrices(b: &Beam, x: &[V3; 3], mass: MassKind) -> Result<(Vec<f64>, Vec<f64>), String> {
    check(b, x)?;
    const N: usize = 18;
    let s = &b.section;
    let Some([k1, k2]) = s.shear else {
        return Err("a three-node beam is shear-flexible: its section needs shear factors".into());
    };
    let ga = b.g * s.area;
    // D on (axial, shear y, shear z, torsion, bending about y, bending about z)
    let d = [
        b.e * s.area,
        k1 * ga,
        k2 * ga,
        b.g * s.j,
        b.e * s.i2,
        b.e * s.i1,
    ];
    let mut k = vec![0.0; N * N];
    let g = (1.0f64 / 3.0).sqrt();
    for xi in [-g, g] {
        let ([t, y, z], j) = axes(x, b.orientation, xi)?;
        let (n, dn) = shape(xi);
        // B: rows the six strains, columns (u, theta) of each node
        let mut bm = [[0.0; N]; 6];
        for a in 0..3 {
            let (u, r) = (6 * a, 6 * a + 3);
            let ds = dn[a] / j;
            for c in 0..3 {
                bm[0][u + c] = ds * t[c];
                bm[1][u + c] = ds * y[c];
                bm[1][r + c] = -n[a] * z[c];
                bm[2][u + c] = ds * z[c];
                bm[2][r + c] = n[a] * y[c];
                bm[3][r + c] = ds * t[c];
                bm[4][r + c] = ds * y[c];
                bm[5][r + c] = ds * z[c];
            }
        }
        for (row, dr) in bm.iter().zip(d) {
            for p in 0..N {
                if row[p] == 0.0 {
                    continue;
                }
                let f = dr * row[p] * j;
                for q in 0..N {
                    k[p * N + q] += f * row[q];
                }
            }
        }
    }
    let mpl = b.rho * s.area + s.nsm;
    let mut m = vec![0.0; N * N];
    for &(xi, w) in &GAUSS5 {
        let ([t, y, z], j) = axes(x, b.orientation, xi)?;
        let (n, _) = shape(xi);
        let dl = w * j;
        match mass {
            MassKind::Consistent => {
                // rotary inertia rho (I1 z z^T + I2 y y^T + (I1 + I2) t t^T)
                let inertia: [[f64; 3]; 3] = std::array::from_fn(|p| {
                    std::array::from_fn(|q| {
                        b.rho
                            * (s.i1 * z[p] * z[q]
                                + s.i2 * y[p] * y[q]
                                + (s.i1 + s.i2) * t[p] * t[q])
                    })
                });
                for a in 0..3 {
                    for c in 0..3 {
                        let f = n[a] * n[c] * dl;
                        for p in 0..3 {
                            m[(6 * a + p) * N + 6 * c + p] += f * mpl;
                            for q in 0..3 {
                                m[(6 * a + 3 + p) * N + 6 * c + 3 + q] += f * inertia[p][q];
                            }
                        }
                    }
                }
            }
            MassKind::Lumped => {
                // each node's share of the length, its translational mass (and the torsional
                // inertia about the axis there, when the beam lumps it)
                for a in 0..3 {
                    let f = n[a] * dl;
                    for p in 0..3 {
                        m[(6 * a + p) * N + 6 * a + p] += f * mpl;
                    }
                    if b.lumped_torsion {
                        let (ta, _) = axes(x, b.orientation, [-1.0, 1.0, 0.0][a])?;
                        for p in 0..3 {
                            m[(6 * a + 3 + p) * N + 6 * a + 3 + p] +=
                                f * b.rho * (s.i1 + s.i2) * ta[0][p] * ta[0][p];
                        }
                    }
                }
            }
        }
    }
    Ok((k, m))
}
