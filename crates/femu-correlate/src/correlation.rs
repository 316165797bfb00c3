//! Test-analysis correlation measures (docs/MATH.md, "Correlation"; the paper's (16)-(17), Table 1).
//!
//! Mass-weighted measures need full-length vectors (every free DOF); the test engineer's measures
//! work on the sensors. Matrices of measures have one row per test mode and one column per model
//! mode.

use crate::CorrelateError;
use faer::{Mat, MatMut, MatRef};
use femu_sparse::SparseMatrix;
use femu_sparse::csc::sym_mul_mat;

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn col(m: MatRef<'_, f64>, j: usize) -> Vec<f64> {
    m.col(j).iter().copied().collect()
}

fn same_len(what: &'static str, a: usize, b: usize) -> Result<(), CorrelateError> {
    if a == b {
        Ok(())
    } else {
        Err(CorrelateError::DimensionMismatch {
            what,
            expected: a,
            got: b,
        })
    }
}

fn nonzero(what: &'static str, index: usize, norm2: f64) -> Result<(), CorrelateError> {
    if norm2 > 0.0 && norm2.is_finite() {
        Ok(())
    } else {
        Err(CorrelateError::ZeroVector { what, index })
    }
}

/// `M x` for one vector.
fn m_times(m: &SparseMatrix, x: &[f64]) -> Result<Vec<f64>, CorrelateError> {
    let mut y = vec![0.0; m.rows()];
    femu_sparse::csc::mul_vec(m, x, &mut y)?;
    Ok(y)
}

/// Mass-weighted MAC (16): `MAC_M(x, phi) = (x^T M phi)^2 / ((x^T M x)(phi^T M phi)) = cos^2 theta`.
///
/// # Errors
/// Mismatched lengths or a zero vector.
pub fn mac_m(m: &SparseMatrix, x: &[f64], phi: &[f64]) -> Result<f64, CorrelateError> {
    same_len("x against M", m.rows(), x.len())?;
    same_len("phi against M", m.rows(), phi.len())?;
    let (mx, mphi) = (m_times(m, x)?, m_times(m, phi)?);
    let (xx, pp, xp) = (dot(x, &mx), dot(phi, &mphi), dot(x, &mphi));
    nonzero("test vector", 0, xx)?;
    nonzero("model vector", 0, pp)?;
    Ok(xp * xp / (xx * pp))
}

/// The test engineer's MAC on measured DOFs: `(x_a^T phi_a)^2 / ((x_a^T x_a)(phi_a^T phi_a))`.
///
/// # Errors
/// Mismatched lengths or a zero vector.
pub fn mac(xa: &[f64], phia: &[f64]) -> Result<f64, CorrelateError> {
    same_len("phi_a against x_a", xa.len(), phia.len())?;
    let (xx, pp, xp) = (dot(xa, xa), dot(phia, phia), dot(xa, phia));
    nonzero("test vector", 0, xx)?;
    nonzero("model vector", 0, pp)?;
    Ok(xp * xp / (xx * pp))
}

/// The MAC of two complex vectors `a = a_re + i a_im` and `b = b_re + i b_im`:
/// `|a^H b|^2 / ((a^H a)(b^H b))` (docs/MATH.md, "Complex modes"). It is 1 for `b` any complex
/// multiple of `a`, and equals [`mac`] when both are real. A real model shape is `b_im = 0`.
///
/// # Errors
/// Mismatched lengths or a zero vector.
pub fn complex_mac(
    a_re: &[f64],
    a_im: &[f64],
    b_re: &[f64],
    b_im: &[f64],
) -> Result<f64, CorrelateError> {
    same_len(
        "a's imaginary part against its real part",
        a_re.len(),
        a_im.len(),
    )?;
    same_len("b against a", a_re.len(), b_re.len())?;
    same_len(
        "b's imaginary part against its real part",
        b_re.len(),
        b_im.len(),
    )?;
    let aa = dot(a_re, a_re) + dot(a_im, a_im);
    let bb = dot(b_re, b_re) + dot(b_im, b_im);
    nonzero("test vector", 0, aa)?;
    nonzero("model vector", 0, bb)?;
    // a^H b = sum (a_re - i a_im)(b_re + i b_im)
    let re = dot(a_re, b_re) + dot(a_im, b_im);
    let im = dot(a_re, b_im) - dot(a_im, b_re);
    Ok((re * re + im * im) / (aa * bb))
}

fn mac_from_products(
    xx: &[f64],
    pp: &[f64],
    xp: MatRef<'_, f64>,
) -> Result<Mat<f64>, CorrelateError> {
    for (i, v) in xx.iter().enumerate() {
        nonzero("test vector", i, *v)?;
    }
    for (j, v) in pp.iter().enumerate() {
        nonzero("model vector", j, *v)?;
    }
    Ok(Mat::from_fn(xx.len(), pp.len(), |i, j| {
        xp[(i, j)] * xp[(i, j)] / (xx[i] * pp[j])
    }))
}

/// Full `MAC_M` matrix between the columns of `X` (test, rows) and `Phi` (model, columns).
///
/// # Errors
/// Mismatched sizes or a zero vector.
pub fn mac_m_matrix(
    m: &SparseMatrix,
    x: MatRef<'_, f64>,
    phi: MatRef<'_, f64>,
) -> Result<Mat<f64>, CorrelateError> {
    same_len("test vectors against M", m.rows(), x.nrows())?;
    same_len("model vectors against M", m.rows(), phi.nrows())?;
    let (mx, mphi) = (sym_mul_mat(m, x)?, sym_mul_mat(m, phi)?);
    let xx: Vec<f64> = (0..x.ncols())
        .map(|i| dot(&col(x, i), &col(mx.as_ref(), i)))
        .collect();
    let pp: Vec<f64> = (0..phi.ncols())
        .map(|j| dot(&col(phi, j), &col(mphi.as_ref(), j)))
        .collect();
    let xp = x.transpose() * &mphi;
    mac_from_products(&xx, &pp, xp.as_ref())
}

/// Full MAC matrix on sensors between the columns of `X_a` (test) and `Phi_a` (model at the same
/// sensors).
///
/// # Errors
/// Mismatched sizes or a zero vector.
pub fn mac_matrix(xa: MatRef<'_, f64>, phia: MatRef<'_, f64>) -> Result<Mat<f64>, CorrelateError> {
    same_len(
        "model vectors against test vectors (sensors)",
        xa.nrows(),
        phia.nrows(),
    )?;
    let xx: Vec<f64> = (0..xa.ncols())
        .map(|i| xa.col(i).squared_norm_l2())
        .collect();
    let pp: Vec<f64> = (0..phia.ncols())
        .map(|j| phia.col(j).squared_norm_l2())
        .collect();
    let xp = xa.transpose() * phia;
    mac_from_products(&xx, &pp, xp.as_ref())
}

/// AutoMAC of a set of vectors on sensors (`MAC(phi_i, phi_j)`): off-diagonal values near 1 mean
/// the sensors cannot tell those modes apart.
///
/// # Errors
/// A zero vector.
pub fn auto_mac(phia: MatRef<'_, f64>) -> Result<Mat<f64>, CorrelateError> {
    mac_matrix(phia, phia)
}

/// Mass-weighted AutoMAC (the identity for M-orthogonal modes).
///
/// # Errors
/// Mismatched sizes or a zero vector.
pub fn auto_mac_m(m: &SparseMatrix, phi: MatRef<'_, f64>) -> Result<Mat<f64>, CorrelateError> {
    mac_m_matrix(m, phi, phi)
}

/// Modal scale factor: the `alpha` minimising `||x - alpha phi||_2`, `alpha = phi^T x / phi^T phi`.
///
/// # Errors
/// Mismatched lengths or a zero `phi`.
pub fn modal_scale_factor(x: &[f64], phi: &[f64]) -> Result<f64, CorrelateError> {
    same_len("phi against x", x.len(), phi.len())?;
    let pp = dot(phi, phi);
    nonzero("model vector", 0, pp)?;
    Ok(dot(phi, x) / pp)
}

/// Mode shape difference (17), femu's default: `x` and `phi` M-normalised and sign-aligned
/// (`x^T M phi >= 0`), `MSD_M = ||x - phi||_M`, so `MSD_M^2 = 2 (1 - cos theta)`.
///
/// # Errors
/// Mismatched lengths or a zero vector.
pub fn msd_m(m: &SparseMatrix, x: &[f64], phi: &[f64]) -> Result<f64, CorrelateError> {
    let cos2 = mac_m(m, x, phi)?;
    Ok((2.0 * (1.0 - cos2.min(1.0).sqrt())).max(0.0).sqrt())
}

/// Mode shape difference (17) in the Euclidean norm after the modal scale factor: the model vector
/// takes the test vector's normalisation, `MSD_2 = ||x - alpha phi||_2 / ||x||_2` with
/// `alpha = modal_scale_factor(x, phi)`, which equals `sin theta_2` (the Euclidean angle).
///
/// This is the normalisation under which the paper's Theorems 3 and 4 hold when `M = I`: with
/// both vectors at unit norm instead, `MSD = 2 sin(theta / 2) > sin theta` and Theorem 4 fails for
/// `x = cos t phi_k + sin t phi_{k+1}`, `lambda_id = lambda_k` (a named regression test).
///
/// # Errors
/// Mismatched lengths or a zero vector.
pub fn msd(x: &[f64], phi: &[f64]) -> Result<f64, CorrelateError> {
    let alpha = modal_scale_factor(x, phi)?;
    let xx = dot(x, x);
    nonzero("test vector", 0, xx)?;
    let r2: f64 = x
        .iter()
        .zip(phi)
        .map(|(a, b)| (a - alpha * b) * (a - alpha * b))
        .sum();
    Ok((r2 / xx).sqrt())
}

/// Coordinate MAC per sensor over paired modes (Lieven and Ewins):
/// `COMAC_i = (sum_p |x_ip phi_ip|)^2 / (sum_p x_ip^2 sum_p phi_ip^2)`, after scaling each model
/// vector to its test partner by the modal scale factor. Low values point at sensors where the
/// model and the test disagree. `pairs` holds `(test column, model column)`.
///
/// # Errors
/// Mismatched sizes, an index out of range, no pairs, or a zero vector.
pub fn comac(
    xa: MatRef<'_, f64>,
    phia: MatRef<'_, f64>,
    pairs: &[(usize, usize)],
) -> Result<Vec<f64>, CorrelateError> {
    same_len(
        "model vectors against test vectors (sensors)",
        xa.nrows(),
        phia.nrows(),
    )?;
    if pairs.is_empty() {
        return Err(CorrelateError::Invalid {
            what: "COMAC pairs",
            reason: "no paired modes".into(),
        });
    }
    let s = xa.nrows();
    let (mut num, mut sx, mut sp) = (vec![0.0; s], vec![0.0; s], vec![0.0; s]);
    for &(t, k) in pairs {
        if t >= xa.ncols() || k >= phia.ncols() {
            return Err(CorrelateError::Invalid {
                what: "COMAC pair",
                reason: format!("({t}, {k}) is out of range"),
            });
        }
        let (x, p) = (col(xa, t), col(phia, k));
        let alpha = modal_scale_factor(&x, &p)?;
        for i in 0..s {
            let q = alpha * p[i];
            num[i] += (x[i] * q).abs();
            sx[i] += x[i] * x[i];
            sp[i] += q * q;
        }
    }
    Ok((0..s)
        .map(|i| {
            let d = sx[i] * sp[i];
            if d > 0.0 { num[i] * num[i] / d } else { 0.0 }
        })
        .collect())
}

/// Cross-orthogonality `X^T M Phi` (rows: test, columns: model). With both sets M-normalised,
/// paired entries near +-1 and the rest near 0 mean good correlation; each entry is `c_j` of
/// docs/MATH.md, the modal coordinate of the test vector on the model mode.
///
/// # Errors
/// Mismatched sizes.
pub fn cross_orthogonality(
    m: &SparseMatrix,
    x: MatRef<'_, f64>,
    phi: MatRef<'_, f64>,
) -> Result<Mat<f64>, CorrelateError> {
    same_len("test vectors against M", m.rows(), x.nrows())?;
    same_len("model vectors against M", m.rows(), phi.nrows())?;
    let mphi = sym_mul_mat(m, phi)?;
    Ok(x.transpose() * &mphi)
}

/// Scales every column of `x` to `x^T M x = 1`.
///
/// # Errors
/// Mismatched sizes or a zero column.
pub fn mass_normalise(m: &SparseMatrix, mut x: MatMut<'_, f64>) -> Result<(), CorrelateError> {
    same_len("vectors against M", m.rows(), x.nrows())?;
    let mx = sym_mul_mat(m, x.as_ref())?;
    for j in 0..x.ncols() {
        let q: f64 = x
            .as_ref()
            .col(j)
            .iter()
            .zip(mx.col(j).iter())
            .map(|(a, b)| a * b)
            .sum();
        nonzero("vector", j, q)?;
        let s = 1.0 / q.sqrt();
        x.as_mut().col_mut(j).iter_mut().for_each(|v| *v *= s);
    }
    Ok(())
}

/// Relative frequency error `(f_model - f_test) / f_test` (Table 1).
pub fn frequency_error(f_test: f64, f_model: f64) -> f64 {
    (f_model - f_test) / f_test
}

/// Eigenvalue gap `|lambda_id - lambda_j|` in s^-2 from two frequencies in Hz (Table 2).
pub fn eigenvalue_gap_hz(f_test: f64, f_model: f64) -> f64 {
    (crate::hz::eigenvalue_of_hz(f_test) - crate::hz::eigenvalue_of_hz(f_model)).abs()
}

/// Model modes whose eigenvalues are equal to this relative tolerance are one repeated
/// eigenvalue for [`align_repeated`].
pub const REPEATED_TOLERANCE: f64 = 1e-8;

/// Turns the basis of each repeated model eigenvalue (a cluster of equal `values`, as a symmetric
/// structure has) towards the test: any orthonormal basis of a repeated eigenvalue's eigenspace
/// is an equally valid set of mode shapes, and the eigensolver's is decided by round-off, so a MAC
/// against it can be anything from 0 to 1 (docs/MATH.md, "Repeated modes"). For a cluster of `k`
/// modes with readings `Phi_c` (`s x k`), the test modes with at least half their energy in the
/// span of `Phi_c` (at most `k`, the most first) are matched: their coefficients
/// `r_t = Phi_c^+ y_t` in the cluster's basis, at unit norm, are replaced by their nearest
/// orthonormal set `Q = U V^T` (the SVD `[r_t] = U S V^T`); `Phi_c` becomes `Phi_c Q`, completed
/// by an orthonormal complement when fewer test modes than `k` match. Test modes that are
/// eigenvectors of the same eigenvalue have orthogonal coefficients, and each is then matched
/// exactly (MAC 1). A cluster the sensors cannot tell apart is left as it is. The result does not depend on the basis the eigensolver returned. Returns the
/// rotated readings and, per cluster, its model modes and `Q` (apply `Q` to the full shapes to
/// turn them the same way).
///
/// # Errors
/// Mismatched sizes, or an SVD that does not converge.
#[allow(clippy::type_complexity)]
pub fn align_repeated(
    values: &[f64],
    phia: MatRef<'_, f64>,
    test: MatRef<'_, f64>,
) -> Result<(Mat<f64>, Vec<(Vec<usize>, Mat<f64>)>), CorrelateError> {
    if values.len() != phia.ncols() {
        return Err(CorrelateError::DimensionMismatch {
            what: "model eigenvalues against their readings",
            expected: phia.ncols(),
            got: values.len(),
        });
    }
    if test.nrows() != phia.nrows() {
        return Err(CorrelateError::DimensionMismatch {
            what: "test shapes against the model's sensors",
            expected: phia.nrows(),
            got: test.nrows(),
        });
    }
    let scale = values.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let mut out = phia.to_owned();
    let mut turned = Vec::new();
    let mut start = 0;
    while start < values.len() {
        let mut end = start + 1;
        while end < values.len()
            && (values[end] - values[start]).abs()
                <= REPEATED_TOLERANCE * values[start].abs().max(1e-6 * scale)
        {
            end += 1;
        }
        let k = end - start;
        if k >= 2 {
            let cluster: Vec<usize> = (start..end).collect();
            let pc = Mat::from_fn(phia.nrows(), k, |i, j| phia[(i, start + j)]);
            if let Some(q) = procrustes_towards(pc.as_ref(), test)? {
                let turned_pc = &pc * &q;
                for j in 0..k {
                    for i in 0..phia.nrows() {
                        out[(i, start + j)] = turned_pc[(i, j)];
                    }
                }
                turned.push((cluster, q));
            }
        }
        start = end;
    }
    Ok((out, turned))
}

/// The rotation of [`align_repeated`] for one cluster, `None` when no test mode lies in its span.
fn procrustes_towards(
    pc: MatRef<'_, f64>,
    test: MatRef<'_, f64>,
) -> Result<Option<Mat<f64>>, CorrelateError> {
    let k = pc.ncols();
    let svd_err = |e| {
        CorrelateError::Sparse(femu_sparse::SparseError::NoConvergence {
            reason: format!("SVD of a repeated mode's readings: {e:?}"),
        })
    };
    // an orthonormal basis of span(Phi_c) at the sensors
    let basis = pc.thin_svd().map_err(svd_err)?;
    // fewer readings than the cluster has modes: the sensors cannot tell them apart (and the
    // thin SVD has only that many singular values)
    if pc.nrows() < k {
        return Ok(None);
    }
    let smax = (0..k).fold(0.0_f64, |m, i| m.max(basis.S()[i]));
    if !(smax > 0.0) {
        return Ok(None);
    }
    let u = basis.U();
    let mut energy: Vec<(usize, f64)> = (0..test.ncols())
        .filter_map(|t| {
            let y = test.col(t);
            let total = y.squared_norm_l2();
            let inside = (u.transpose() * y).squared_norm_l2();
            (total > 0.0 && inside >= 0.5 * total).then_some((t, inside / total))
        })
        .collect();
    energy.sort_by(|a, b| b.1.total_cmp(&a.1));
    energy.truncate(k);
    energy.sort_by_key(|e| e.0);
    let j = energy.len();
    if j == 0 {
        return Ok(None);
    }
    let smin = (0..k).fold(f64::INFINITY, |m, i| m.min(basis.S()[i]));
    if !(smin > 1e-10 * smax) {
        // the sensors cannot tell the cluster's modes apart: nothing to turn
        return Ok(None);
    }
    // the coefficients r_t = Phi_c^+ y_t of each matched test mode in the cluster's basis, at
    // unit norm; their nearest orthonormal set (polar factor, U V^T of its SVD) is the rotation
    let y = Mat::from_fn(pc.nrows(), j, |i, c| test[(i, energy[c].0)]);
    let uty = u.transpose() * &y;
    let scaled = Mat::from_fn(k, j, |i, c| uty[(i, c)] / basis.S()[i]);
    let mut m = basis.V() * &scaled; // k x j
    for c in 0..j {
        let n = m.col(c).norm_l2();
        m.col_mut(c).iter_mut().for_each(|v| *v /= n);
    }
    let svd = m.thin_svd().map_err(svd_err)?;
    let qj = svd.U() * svd.V().transpose(); // k x j, orthonormal columns
    // complete to an orthonormal k x k by Gram-Schmidt of the unit vectors against Q_j
    let mut cols: Vec<Vec<f64>> = (0..j)
        .map(|c| qj.col(c).iter().copied().collect())
        .collect();
    for e in 0..k {
        if cols.len() == k {
            break;
        }
        let mut v: Vec<f64> = (0..k).map(|i| if i == e { 1.0 } else { 0.0 }).collect();
        for _ in 0..2 {
            for c in &cols {
                let d: f64 = c.iter().zip(&v).map(|(a, b)| a * b).sum();
                v.iter_mut().zip(c).for_each(|(x, a)| *x -= d * a);
            }
        }
        let n = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        if n > 1e-8 {
            v.iter_mut().for_each(|x| *x /= n);
            cols.push(v);
        }
    }
    Ok(Some(Mat::from_fn(k, k, |i, c| cols[c][i])))
}
