//! The complex modes of a damped model (docs/MATH.md, "Damped modes"), found in the space of its
//! real modes `Phi` (mass-normalised, `Phi^T K Phi = Lambda`), `phi = Phi q`:
//!
//! - structural damping alone (each material's `GE`, a model-wide loss factor): the eigenpairs of
//!   `(K + i K_4) phi = mu M phi`, in the real modes `(Lambda + i G) q = mu q` with `G = Phi^T K_4
//!   Phi`, a complex symmetric matrix of the modes' count; the root is `p = i sqrt(mu)`;
//! - with viscous damping `C` (dampers, Rayleigh's `alpha M + beta K`, modal ratios): the
//!   quadratic eigenproblem `(p^2 M + p C + K + i K_4) phi = 0`, in the real modes `(p^2 I + p D +
//!   Lambda + i G) q = 0` with `D = Phi^T C Phi`, solved as the companion problem of twice the
//!   modes' count; each oscillating mode is the root with `Im p > 0` (its conjugate partner is the
//!   same motion), a non-oscillating one (a rigid-body mode, an overdamped one) its slower real
//!   root.
//!
//! `p` is Nastran's complex eigenvalue (`u = phi e^(p t)`): the mode's frequency is `Im p / (2
//! pi)` and its damping coefficient `g = -2 Re p / Im p` (a loss factor's `eta` up to `eta^2 / 4`,
//! twice a viscous ratio up to `zeta^2`). With every mode kept this is the full problem; with the
//! lowest modes kept it is the Rayleigh-Ritz approximation of the lowest damped modes, which the
//! tests measure.

use crate::CorrelateError;
use crate::frf::ModalDampers;
use faer::{Mat, MatRef, c64};

/// Complex modes in the coordinates of the real ones.
#[derive(Debug, Clone)]
pub struct DampedModes {
    /// The roots `p_r` (Nastran's complex eigenvalues, `u = phi e^(p t)`), `Im p >= 0`, by
    /// ascending `Im p` (non-oscillating modes, `Im p = 0`, first).
    pub roots: Vec<c64>,
    /// The coordinates `q_r` in the real modes (real modes x complex modes), each of unit length
    /// and turned so that its largest component is real and positive.
    pub coordinates: Mat<c64>,
}

impl DampedModes {
    /// The damped mode's frequency `Im p / (2 pi)`, Hz (0 for a non-oscillating mode).
    pub fn frequency_hz(&self, r: usize) -> f64 {
        self.roots[r].im / (2.0 * std::f64::consts::PI)
    }

    /// Nastran's damping coefficient `g = -2 Re p / Im p` (0 where `Im p` is 0: a mode that does
    /// not oscillate).
    pub fn damping(&self, r: usize) -> f64 {
        let p = self.roots[r];
        if p.im == 0.0 { 0.0 } else { -2.0 * p.re / p.im }
    }

    /// The damping ratio `-Re p / |p|` (1 for a non-oscillating mode that decays, 0 for `p = 0`).
    pub fn ratio(&self, r: usize) -> f64 {
        let p = self.roots[r];
        if p.norm() == 0.0 {
            0.0
        } else {
            -p.re / p.norm()
        }
    }

    /// The eigenvalue `mu = -p^2` of `(K + i K_4) phi = mu M phi` (structural damping:
    /// `omega^2 (1 + i eta)`).
    pub fn mu(&self, r: usize) -> c64 {
        -(self.roots[r] * self.roots[r])
    }
}

/// The complex modes of the real modes' eigenvalues `values` with the damping `damping` projected
/// on them (`structural` `G = Phi^T K_4 Phi`, `viscous` `D = Phi^T C Phi`, each modes x modes and
/// symmetric; the symmetric part is used): the module's linear problem without `viscous`, its
/// quadratic one with it. In the quadratic problem, a rigid-body mode (`lambda` below `1e-8` of the
/// largest) that no damping couples (its rows of `D` and `G` below `1e-8` of their largest entry)
/// is kept apart with `p = 0` (its companion block is defective); the companion matrix is the
/// balanced one of the state `[Omega q; p q]`, `Omega = diag(omega_r)`, whose undamped blocks are
/// normal.
///
/// # Errors
/// [`CorrelateError::DimensionMismatch`] for a projection of another size;
/// [`CorrelateError::Invalid`] for a non-finite value or an eigensolve that does not converge.
pub fn damped_modes(values: &[f64], damping: &ModalDampers) -> Result<DampedModes, CorrelateError> {
    let n = values.len();
    for (what, m) in [
        (
            "projected structural damping (modes x modes)",
            &damping.structural,
        ),
        (
            "projected viscous damping (modes x modes)",
            &damping.viscous,
        ),
    ] {
        if let Some(m) = m
            && (m.nrows() != n || m.ncols() != n)
        {
            return Err(CorrelateError::DimensionMismatch {
                what,
                expected: n,
                got: m.nrows(),
            });
        }
    }
    let finite = |m: &Option<Mat<f64>>| {
        m.as_ref()
            .is_none_or(|m| (0..n).all(|j| (0..n).all(|i| m[(i, j)].is_finite())))
    };
    if !(values.iter().all(|v| v.is_finite())
        && finite(&damping.structural)
        && finite(&damping.viscous))
    {
        return Err(CorrelateError::Invalid {
            what: "damped modes",
            reason: "an eigenvalue or a projected damping term is not a finite number".into(),
        });
    }
    // the symmetric parts: the projections are symmetric up to round-off
    let sym = |m: &Option<Mat<f64>>| {
        Mat::<f64>::from_fn(n, n, |i, j| {
            m.as_ref().map_or(0.0, |m| 0.5 * (m[(i, j)] + m[(j, i)]))
        })
    };
    let g = sym(&damping.structural);
    let (roots, vectors) = match &damping.viscous {
        None => linear(values, g.as_ref())?,
        Some(_) => quadratic(values, g.as_ref(), sym(&damping.viscous).as_ref())?,
    };
    if roots
        .iter()
        .any(|p| !(p.re.is_finite() && p.im.is_finite()))
    {
        return Err(CorrelateError::Invalid {
            what: "damped modes",
            reason: "the reduced eigenproblem gave a root that is not a finite number".into(),
        });
    }
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&x, &y| {
        let (a, b) = (roots[x], roots[y]);
        a.im.total_cmp(&b.im).then(a.norm().total_cmp(&b.norm()))
    });
    let mut vectors = vectors;
    real_bases(&roots, &order, &mut vectors)?;
    let mut coordinates = Mat::<c64>::zeros(n, n);
    for (k, &j) in order.iter().enumerate() {
        // unit length, turned by the conjugate phase of the largest component
        let v = &vectors[j];
        let norm = v.iter().map(|c| c.norm_sqr()).sum::<f64>().sqrt();
        let big = v
            .iter()
            .copied()
            .max_by(|a, b| a.norm_sqr().total_cmp(&b.norm_sqr()))
            .unwrap_or(c64::new(1.0, 0.0));
        if !(norm > 0.0 && norm.is_finite()) {
            return Err(CorrelateError::Invalid {
                what: "damped modes",
                reason: format!("damped mode {} has no finite shape", k + 1),
            });
        }
        let turn = big.conj() / (big.norm() * norm);
        for (i, c) in v.iter().enumerate() {
            coordinates[(i, k)] = c * turn;
        }
    }
    Ok(DampedModes {
        roots: order.iter().map(|&j| roots[j]).collect(),
        coordinates,
    })
}

/// Repeated roots (equal to `1e-10` of their size) span a space of modes in which the eigensolver
/// picks complex combinations at random; where that space has a real basis (`[Re V, Im V]` of
/// rank the roots' count: the damping does not mix the real modes there, as proportional damping
/// of a symmetric structure's pairs), its modes are that basis (the left singular vectors), so
/// that such modes stay real.
fn real_bases(
    roots: &[c64],
    order: &[usize],
    vectors: &mut [Vec<c64>],
) -> Result<(), CorrelateError> {
    let mut start = 0;
    while start < order.len() {
        let p = roots[order[start]];
        let end = start
            + order[start..]
                .iter()
                .take_while(|&&j| (roots[j] - p).norm() <= 1e-10 * p.norm().max(f64::MIN_POSITIVE))
                .count();
        let cluster = &order[start..end.max(start + 1)];
        start = end.max(start + 1);
        let c = cluster.len();
        if c < 2 {
            continue;
        }
        let n = vectors[cluster[0]].len();
        let parts = Mat::<f64>::from_fn(n, 2 * c, |i, k| {
            let v = vectors[cluster[k % c]][i];
            if k < c { v.re } else { v.im }
        });
        let svd = parts.thin_svd().map_err(|e| CorrelateError::Invalid {
            what: "damped modes",
            reason: format!("the SVD of a repeated root's modes did not converge ({e:?})"),
        })?;
        let sv = svd.S();
        if sv.dim() > c && sv[c] <= 1e-8 * sv[0] {
            for (k, &j) in cluster.iter().enumerate() {
                vectors[j] = (0..n).map(|i| c64::new(svd.U()[(i, k)], 0.0)).collect();
            }
        }
    }
    Ok(())
}

/// Roots `p` and coordinates `q` of the modes, unsorted.
type Eigenpairs = (Vec<c64>, Vec<Vec<c64>>);

/// Roots and coordinates (unsorted) of the linear problem `(Lambda + i G) q = mu q`, `p = i
/// sqrt(mu)`.
fn linear(values: &[f64], g: MatRef<'_, f64>) -> Result<Eigenpairs, CorrelateError> {
    let n = values.len();
    let a = Mat::<c64>::from_fn(n, n, |i, j| {
        c64::new(if i == j { values[i] } else { 0.0 }, g[(i, j)])
    });
    let evd = eigen(a.as_ref())?;
    let (s, u) = (evd.S(), evd.U());
    Ok((0..n)
        .map(|j| {
            let p = c64::new(0.0, 1.0) * s[j].sqrt();
            (p, (0..n).map(|i| u[(i, j)]).collect())
        })
        .unzip())
}

/// Roots and coordinates (unsorted) of the quadratic problem `(p^2 I + p D + Lambda + i G) q = 0`
/// by its companion matrix `[[0, I], [-(Lambda + i G), -D]]`, `n` of its `2 n` roots kept.
fn quadratic(
    values: &[f64],
    g: MatRef<'_, f64>,
    d: MatRef<'_, f64>,
) -> Result<Eigenpairs, CorrelateError> {
    let n = values.len();
    let top = values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let largest = |m: MatRef<'_, f64>| {
        (0..n).fold(0.0f64, |a, j| (0..n).fold(a, |a, i| a.max(m[(i, j)].abs())))
    };
    let (gmax, dmax) = (largest(g), largest(d));
    // rigid-body modes that no damping touches: p = 0 apart (a defective companion block)
    let apart: Vec<bool> = (0..n)
        .map(|r| {
            values[r].abs() <= 1e-8 * top
                && (0..n).all(|j| g[(r, j)].abs() <= 1e-8 * gmax && d[(r, j)].abs() <= 1e-8 * dmax)
        })
        .collect();
    let kept: Vec<usize> = (0..n).filter(|r| !apart[*r]).collect();
    let m = kept.len();
    let mut roots = Vec::with_capacity(n);
    let mut vectors = Vec::with_capacity(n);
    for r in (0..n).filter(|r| apart[*r]) {
        roots.push(c64::new(0.0, 0.0));
        vectors.push(
            (0..n)
                .map(|i| c64::new(f64::from(u8::from(i == r)), 0.0))
                .collect(),
        );
    }
    if m == 0 {
        return Ok((roots, vectors));
    }
    // the balanced state z = [S q; p q], S = diag(omega_r) (a rigid-body mode's omega: the
    // smallest elastic one, or 1), whose undamped 2 x 2 blocks [[0, omega], [-omega, 0]] are
    // normal: each root's error is round-off of the largest frequency, not of its square
    let floor = kept
        .iter()
        .map(|&r| values[r])
        .filter(|v| *v > 1e-8 * top)
        .fold(f64::INFINITY, f64::min);
    let floor = if floor.is_finite() { floor.sqrt() } else { 1.0 };
    let scale: Vec<f64> = kept
        .iter()
        .map(|&r| {
            if values[r] > 1e-8 * top {
                values[r].sqrt()
            } else {
                floor
            }
        })
        .collect();
    let a = Mat::<c64>::from_fn(2 * m, 2 * m, |i, j| match (i < m, j < m) {
        (true, true) => c64::new(0.0, 0.0),
        (true, false) => c64::new(if j - m == i { scale[i] } else { 0.0 }, 0.0),
        (false, true) => {
            let (r, c) = (kept[i - m], kept[j]);
            let lambda = if r == c { values[r] } else { 0.0 };
            -c64::new(lambda, g[(r, c)]) / scale[j]
        }
        (false, false) => c64::new(-d[(kept[i - m], kept[j - m])], 0.0),
    });
    let evd = eigen(a.as_ref())?;
    let (s, u) = (evd.S(), evd.U());
    let tiny = |p: c64| p.im.abs() <= 1e-8 * p.norm();
    let shape = |k: usize| -> Vec<c64> {
        let mut v = vec![c64::new(0.0, 0.0); n];
        for (i, &r) in kept.iter().enumerate() {
            v[r] = u[(i, k)] / scale[i];
        }
        v
    };
    let oscillating: Vec<usize> = (0..2 * m)
        .filter(|&k| s[k].im > 0.0 && !tiny(s[k]))
        .collect();
    // each non-oscillating mode by its slower real root
    let mut real: Vec<usize> = (0..2 * m).filter(|&k| tiny(s[k])).collect();
    real.sort_by(|&x, &y| s[x].norm().total_cmp(&s[y].norm()));
    let still = m
        .checked_sub(oscillating.len())
        .filter(|k| *k <= real.len());
    let Some(still) = still else {
        return Err(CorrelateError::Invalid {
            what: "damped modes",
            reason: format!(
                "the quadratic eigenproblem of {m} modes gave {} oscillating and {} real roots, which pair into no {m} modes",
                oscillating.len(),
                real.len()
            ),
        });
    };
    for &k in &oscillating {
        roots.push(s[k]);
        vectors.push(shape(k));
    }
    for &k in &real[..still] {
        roots.push(c64::new(s[k].re, 0.0));
        vectors.push(shape(k));
    }
    Ok((roots, vectors))
}

/// The dense complex eigendecomposition of `a`.
fn eigen(a: MatRef<'_, c64>) -> Result<faer::linalg::solvers::Eigen<f64>, CorrelateError> {
    faer::linalg::solvers::Eigen::<f64>::new(a).map_err(|e| CorrelateError::Invalid {
        what: "damped modes",
        reason: format!("the reduced eigenproblem did not converge ({e:?})"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn structural(s: Mat<f64>) -> ModalDampers {
        ModalDampers {
            structural: Some(s),
            viscous: None,
        }
    }

    /// Whether `q` is `e_r` to `tol`.
    fn is_unit(d: &DampedModes, k: usize, r: usize, tol: f64) -> bool {
        (0..d.coordinates.nrows()).all(|i| {
            let want = if i == r { 1.0 } else { 0.0 };
            (d.coordinates[(i, k)] - c64::new(want, 0.0)).norm() < tol
        })
    }

    /// Proportional damping `K_4 = g K` leaves the modes real: `mu_r = lambda_r (1 + i g)` and `q_r
    /// = e_r`, exactly (to round-off); the damping coefficient is `2 g / (1 + sqrt(1 + g^2))` (from
    /// `p = i omega sqrt(1 + i g)` by hand).
    #[test]
    fn proportional_damping_keeps_the_real_modes() {
        let values = [4.0, 9.0, 25.0, 100.0];
        let g = 0.03;
        let s = Mat::<f64>::from_fn(4, 4, |i, j| if i == j { g * values[i] } else { 0.0 });
        let d = damped_modes(&values, &structural(s)).unwrap();
        for r in 0..4 {
            assert!((d.mu(r) - c64::new(values[r], g * values[r])).norm() < 1e-12 * values[r]);
            let want = 2.0 * g / (1.0 + (1.0 + g * g).sqrt());
            assert!((d.damping(r) - want).abs() < 1e-13, "{}", d.damping(r));
            assert!(is_unit(&d, r, r, 1e-12));
        }
    }

    /// One mode of `lambda = omega^2` with a viscous `D = 2 zeta omega`: the root of `p^2 + 2 zeta
    /// omega p + omega^2 = 0` by hand, `p = -zeta omega + i omega sqrt(1 - zeta^2)` (damping
    /// coefficient `2 zeta / sqrt(1 - zeta^2)`, ratio `zeta`) for `zeta < 1`, the slower real root
    /// `-omega (zeta - sqrt(zeta^2 - 1))` for an overdamped `zeta = 2`.
    #[test]
    fn one_viscous_mode_has_the_textbook_root() {
        let omega = 2.0 * std::f64::consts::PI * 12.5;
        for zeta in [0.001, 0.05, 0.7, 2.0] {
            let damping = ModalDampers {
                structural: None,
                viscous: Some(Mat::from_fn(1, 1, |_, _| 2.0 * zeta * omega)),
            };
            let d = damped_modes(&[omega * omega], &damping).unwrap();
            let p = d.roots[0];
            if zeta < 1.0 {
                let want = c64::new(-zeta * omega, omega * (1.0 - zeta * zeta).sqrt());
                assert!((p - want).norm() < 1e-13 * omega, "{zeta}: {p:?}");
                let g = 2.0 * zeta / (1.0 - zeta * zeta).sqrt();
                assert!((d.damping(0) - g).abs() < 1e-12 * g, "{zeta}");
                assert!((d.ratio(0) - zeta).abs() < 1e-12, "{zeta}");
            } else {
                let want = -omega * (zeta - (zeta * zeta - 1.0).sqrt());
                assert!(p.im == 0.0 && (p.re - want).abs() < 1e-12 * omega, "{p:?}");
                assert_eq!(d.frequency_hz(0), 0.0);
            }
        }
    }

    /// Rayleigh damping `C = alpha M + beta K` is proportional: each elastic mode keeps its shape
    /// with `zeta_r = alpha / (2 omega_r) + beta omega_r / 2` and the textbook root; a rigid-body
    /// mode (`lambda` of round-off) has the roots `0` and `-alpha`, and is reported by the slower,
    /// `p = 0`; without `alpha` it is undamped and kept apart, `p = 0` again.
    #[test]
    fn rayleigh_damping_keeps_the_real_modes_and_the_rigid_body_mode() {
        let values = [1e-9, 400.0, 2500.0, 1.6e5];
        for (alpha, beta) in [(3.0, 2e-4), (0.0, 2e-4)] {
            let damping = ModalDampers {
                structural: None,
                viscous: Some(Mat::from_fn(4, 4, |i, j| {
                    if i == j {
                        alpha + beta * values[i]
                    } else {
                        0.0
                    }
                })),
            };
            let d = damped_modes(&values, &damping).unwrap();
            assert!(d.roots[0].norm() < 1e-6, "{:?}", d.roots[0]);
            assert!(is_unit(&d, 0, 0, 1e-9));
            for r in 1..4 {
                let omega = values[r].sqrt();
                let zeta = alpha / (2.0 * omega) + beta * omega / 2.0;
                let want = c64::new(-zeta * omega, omega * (1.0 - zeta * zeta).sqrt());
                assert!(
                    (d.roots[r] - want).norm() < 1e-12 * 400.0,
                    "{r}: {:?}",
                    d.roots[r]
                );
                assert!(is_unit(&d, r, r, 1e-10), "{r}");
            }
        }
    }

    /// A repeated real mode (a symmetric structure's pair) under proportional damping: the
    /// repeated root's space has a real basis, and its modes are real (imaginary parts below 1e-12
    /// after the turn), spanning the pair's two real modes; the same with a structural loss factor.
    #[test]
    fn a_repeated_root_keeps_real_modes() {
        // the pair equal to round-off, and coupled by round-off, as a real eigensolver gives it
        let values = [400.0, 900.0, 900.0 * (1.0 + 3e-14), 2500.0];
        let diagonal = |f: &dyn Fn(f64) -> f64| {
            Mat::from_fn(4, 4, |i, j| match (i, j) {
                _ if i == j => f(values[i]),
                (1, 2) | (2, 1) => 1e-13 * f(values[1]),
                _ => 0.0,
            })
        };
        for damping in [
            ModalDampers {
                structural: None,
                viscous: Some(diagonal(&|l| 0.5 + 1e-4 * l)),
            },
            structural(diagonal(&|l| 0.02 * l)),
        ] {
            let d = damped_modes(&values, &damping).unwrap();
            for k in 1..3 {
                let q = d.coordinates.col(k);
                assert!((0..4).all(|i| q[i].im.abs() < 1e-12), "{q:?}");
                assert!(q[0].norm() < 1e-12 && q[3].norm() < 1e-12, "{q:?}");
            }
            assert!((d.roots[1] - d.roots[2]).norm() < 1e-12 * d.roots[1].norm());
        }
    }

    /// A chain of 30 masses (unequal) and springs, the first spring grounded; stiffness `K`, the
    /// first ten springs with a loss factor of 0.1 and the rest 0.01 (`K_4`) and dashpots `C` on
    /// three of them and from mass 20 to ground (non-proportional: the modes turn complex). The
    /// reference solves the full problem in physical coordinates: `(p^2 M + p C + K + i K_4) x =
    /// 0` by its own companion matrix `[[0, I], [-M^-1 (K + i K_4), -M^-1 C]]`, the roots with `Im
    /// p > 0` ascending; without `C`, the pencil `(K + i K_4, M)` directly. With all 30 real modes
    /// kept the damped modes equal it: roots to 1e-9 of the largest, shapes parallel to 1e-9. With
    /// the lowest 10, 15 and 20 kept, the three lowest roots approach it (errors falling).
    #[test]
    fn every_mode_kept_is_the_full_problem() {
        let n = 30;
        let mut k = Mat::<f64>::zeros(n, n);
        let mut k4 = Mat::<f64>::zeros(n, n);
        let mut c = Mat::<f64>::zeros(n, n);
        let joint = |mat: &mut Mat<f64>, e: usize, v: f64| {
            // element e joins mass e - 1 (ground for e = 0) to mass e
            mat[(e, e)] += v;
            if e >= 1 {
                mat[(e - 1, e - 1)] += v;
                mat[(e - 1, e)] -= v;
                mat[(e, e - 1)] -= v;
            }
        };
        for e in 0..n {
            let ke = 1000.0 * (1.0 + 0.3 * (e % 3) as f64);
            joint(&mut k, e, ke);
            joint(&mut k4, e, if e < 10 { 0.1 } else { 0.01 } * ke);
        }
        for e in [3, 11, 17] {
            joint(&mut c, e, 0.8);
        }
        c[(20, 20)] += 1.5;
        let mass: Vec<f64> = (0..n).map(|i| 1.0 + 0.1 * (i % 4) as f64).collect();
        // the real modes in the coordinates y = M^(1/2) x
        let root: Vec<f64> = mass.iter().map(|m| m.sqrt()).collect();
        let scaled =
            |a: &Mat<f64>| Mat::<f64>::from_fn(n, n, |i, j| a[(i, j)] / (root[i] * root[j]));
        let eig = scaled(&k).self_adjoint_eigen(faer::Side::Lower).unwrap();
        let lambda: Vec<f64> = (0..n).map(|j| eig.S()[j]).collect();
        assert!(lambda.windows(2).all(|w| w[0] <= w[1]));
        let v = eig.U().to_owned();
        let top = lambda[n - 1];
        for viscous in [false, true] {
            // the full problem in x
            let mut direct: Vec<(c64, Vec<c64>)> = if viscous {
                let a = Mat::<c64>::from_fn(2 * n, 2 * n, |i, j| match (i < n, j < n) {
                    (true, true) => c64::new(0.0, 0.0),
                    (true, false) => c64::new(f64::from(u8::from(j - n == i)), 0.0),
                    (false, true) => -c64::new(k[(i - n, j)], k4[(i - n, j)]) / mass[i - n],
                    (false, false) => c64::new(-c[(i - n, j - n)] / mass[i - n], 0.0),
                });
                let evd = faer::linalg::solvers::Eigen::<f64>::new(a.as_ref()).unwrap();
                (0..2 * n)
                    .filter(|&j| evd.S()[j].im > 0.0)
                    .map(|j| (evd.S()[j], (0..n).map(|i| evd.U()[(i, j)]).collect()))
                    .collect()
            } else {
                let (a, b) = (scaled(&k), scaled(&k4));
                let full = Mat::<c64>::from_fn(n, n, |i, j| c64::new(a[(i, j)], b[(i, j)]));
                let evd = faer::linalg::solvers::Eigen::<f64>::new(full.as_ref()).unwrap();
                (0..n)
                    .map(|j| {
                        let p = c64::new(0.0, 1.0) * evd.S()[j].sqrt();
                        let x = (0..n).map(|i| evd.U()[(i, j)] / root[i]).collect();
                        (p, x)
                    })
                    .collect()
            };
            assert_eq!(direct.len(), n);
            direct.sort_by(|x, y| x.0.im.total_cmp(&y.0.im));
            // Phi = M^(-1/2) V, so Phi^T A Phi = V^T (M^(-1/2) A M^(-1/2)) V
            let project = |a: &Mat<f64>, kept: usize| {
                let p = v.transpose() * scaled(a) * &v;
                Mat::<f64>::from_fn(kept, kept, |i, j| p[(i, j)])
            };
            let damped = |kept: usize| {
                let damping = ModalDampers {
                    structural: Some(project(&k4, kept)),
                    viscous: viscous.then(|| project(&c, kept)),
                };
                damped_modes(&lambda[..kept], &damping).unwrap()
            };
            let all = damped(n);
            for r in 0..n {
                let (p, x) = &direct[r];
                assert!(
                    (all.roots[r] - p).norm() < 1e-9 * top.sqrt(),
                    "{viscous} {r}: {:?} {p:?}",
                    all.roots[r]
                );
                // Phi q against the direct shape
                let phi: Vec<c64> = (0..n)
                    .map(|i| {
                        (0..n)
                            .map(|j| c64::new(v[(i, j)] / root[i], 0.0) * all.coordinates[(j, r)])
                            .sum()
                    })
                    .collect();
                let dot: c64 = phi.iter().zip(x).map(|(a, b)| a.conj() * b).sum();
                let na: f64 = phi.iter().map(|a| a.norm_sqr()).sum();
                let nb: f64 = x.iter().map(|b| b.norm_sqr()).sum();
                assert!(
                    (dot.norm_sqr() / (na * nb) - 1.0).abs() < 1e-9,
                    "{viscous} {r}"
                );
            }
            // the modes are complex: their damping differs from mode to mode
            assert!((all.damping(0) - all.damping(5)).abs() > 1e-3);
            let mut previous = [f64::INFINITY; 3];
            for kept in [10, 15, 20] {
                let d = damped(kept);
                for r in 0..3 {
                    let e = (d.roots[r] - all.roots[r]).norm() / all.roots[r].norm();
                    assert!(
                        e < previous[r] || e < 1e-14,
                        "{viscous} {kept} {r}: {e} after {}",
                        previous[r]
                    );
                    previous[r] = e;
                }
            }
        }
    }
}
