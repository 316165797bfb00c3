//! Sensor placement by Effective Independence (EfI, Kammer 1991), the method test planners and
//! FEMtools use: keep the sensors that make the target mode shapes most linearly independent,
//! measured by the Fisher information `A = Phi_s^T Phi_s` of the modes at the sensors.
//!
//! Removing one row `phi_i` multiplies `det A` by `1 - E_i`, with `E_i` the effective independence
//! (leverage) `E = diag(Phi_s A^-1 Phi_s^T)`, `sum_i E_i = m`. femu removes or adds whole nodes (all
//! their sensors), choosing at each step the node whose removal keeps (or whose addition gives)
//! the largest `det A`, computed exactly with the determinant lemma
//! `det(A -+ V^T V) = det A det(I -+ V A^-1 V^T)`; for a node with one sensor this is classic EfI.

use crate::{CorrelateError, SensorLayout};
use faer::{Mat, MatRef};
use femu_fem::mesh::Mesh;

/// A regular sensor grid on a face: for each cell of an `nx x ny` grid over the x-y bounding box
/// of node set `set`, the id of the set's node nearest (in x-y) to the cell centre, x-major
/// (`i` outer, `j` inner). The paper's 15 upper-surface nodes are `grid_nodes(mesh, "zmax", [5, 3])`.
///
/// # Errors
/// An unknown or empty node set, a zero grid size.
pub fn grid_nodes(mesh: &Mesh, set: &str, grid: [usize; 2]) -> Result<Vec<u64>, CorrelateError> {
    let nodes = mesh.node_set(set)?;
    if nodes.is_empty() || grid[0] == 0 || grid[1] == 0 {
        return Err(CorrelateError::Invalid {
            what: "sensor grid",
            reason: format!("node set {set} has {} nodes, grid {grid:?}", nodes.len()),
        });
    }
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for &n in nodes {
        let p = mesh.coords()[n];
        for c in 0..2 {
            lo[c] = lo[c].min(p[c]);
            hi[c] = hi[c].max(p[c]);
        }
    }
    let mut out = Vec::with_capacity(grid[0] * grid[1]);
    for i in 0..grid[0] {
        for j in 0..grid[1] {
            let t = [
                lo[0] + (hi[0] - lo[0]) * (i as f64 + 0.5) / grid[0] as f64,
                lo[1] + (hi[1] - lo[1]) * (j as f64 + 0.5) / grid[1] as f64,
            ];
            let d = |n: usize| {
                let p = mesh.coords()[n];
                (p[0] - t[0]).powi(2) + (p[1] - t[1]).powi(2)
            };
            let best = nodes
                .iter()
                .min_by(|a, b| d(**a).total_cmp(&d(**b)))
                .expect("the set is not empty");
            out.push(mesh.node_id(*best));
        }
    }
    Ok(out)
}

/// Effective independence `E_i` of each row of `phi_s` (`s x m`, `s >= m`, full column rank).
///
/// # Errors
/// Fewer rows than columns, or modes linearly dependent at the sensors.
pub fn effective_independence(phi_s: MatRef<'_, f64>) -> Result<Vec<f64>, CorrelateError> {
    let ainv = fisher_inverse(phi_s)?;
    Ok((0..phi_s.nrows())
        .map(|i| {
            let r: Vec<f64> = phi_s.row(i).iter().copied().collect();
            quad(&ainv, &r, &r)
        })
        .collect())
}

fn quad(a: &Mat<f64>, x: &[f64], y: &[f64]) -> f64 {
    let mut s = 0.0;
    for i in 0..x.len() {
        for j in 0..y.len() {
            s += x[i] * a[(i, j)] * y[j];
        }
    }
    s
}

/// `(Phi_s^T Phi_s)^-1`, checked for rank.
fn fisher_inverse(phi_s: MatRef<'_, f64>) -> Result<Mat<f64>, CorrelateError> {
    let (s, m) = (phi_s.nrows(), phi_s.ncols());
    if s < m || m == 0 {
        return Err(CorrelateError::Invalid {
            what: "effective independence",
            reason: format!("{s} sensors for {m} target modes: need at least as many sensors"),
        });
    }
    let a = phi_s.transpose() * phi_s;
    let eig = femu_sparse::dense::symmetric_eigen(a.as_ref())?;
    let (lo, hi) = (eig.0[0], eig.0[m - 1]);
    if !(lo > 1e-12 * hi) {
        return Err(CorrelateError::Invalid {
            what: "effective independence",
            reason: format!(
                "the {m} target modes are linearly dependent at the sensors (Fisher eigenvalues {hi:e} .. {lo:e})"
            ),
        });
    }
    let v = &eig.1;
    Ok(Mat::from_fn(m, m, |i, j| {
        (0..m).map(|k| v[(i, k)] * v[(j, k)] / eig.0[k]).sum()
    }))
}

/// Rows of the layout grouped by node, in first-appearance order.
fn node_groups(layout: &SensorLayout) -> Vec<(u64, Vec<usize>)> {
    let mut groups: Vec<(u64, Vec<usize>)> = Vec::new();
    for (s, sensor) in layout.sensors().iter().enumerate() {
        match groups.iter_mut().find(|g| g.0 == sensor.node) {
            Some(g) => g.1.push(s),
            None => groups.push((sensor.node, vec![s])),
        }
    }
    groups
}

/// `det(I + sign V A^-1 V^T)` for the rows `rows` of `phi_s`.
fn det_factor(ainv: &Mat<f64>, phi_s: MatRef<'_, f64>, rows: &[usize], sign: f64) -> f64 {
    let g = rows.len();
    let vs: Vec<Vec<f64>> = rows
        .iter()
        .map(|r| phi_s.row(*r).iter().copied().collect())
        .collect();
    let b = Mat::from_fn(g, g, |i, j| {
        (if i == j { 1.0 } else { 0.0 }) + sign * quad(ainv, &vs[i], &vs[j])
    });
    // determinant of a tiny matrix by LU with partial pivoting
    let mut a = b;
    let mut det = 1.0;
    for k in 0..g {
        let p = (k..g)
            .max_by(|x, y| a[(*x, k)].abs().total_cmp(&a[(*y, k)].abs()))
            .unwrap_or(k);
        if a[(p, k)] == 0.0 {
            return 0.0;
        }
        if p != k {
            for j in 0..g {
                let t = a[(k, j)];
                a[(k, j)] = a[(p, j)];
                a[(p, j)] = t;
            }
            det = -det;
        }
        det *= a[(k, k)];
        for i in k + 1..g {
            let f = a[(i, k)] / a[(k, k)];
            for j in k..g {
                let v = a[(k, j)];
                a[(i, j)] -= f * v;
            }
        }
    }
    det
}

/// The order in which to remove the layout's nodes, least informative first, for the target
/// modes `phi` (`n x m`, full length): at each step the node whose removal keeps the largest
/// `det(Phi_s^T Phi_s)`. Stops when removing any further node would leave fewer sensors than modes
/// or a rank-deficient set; the nodes not listed are the ones to keep.
///
/// `docs/MATH.md`, "Expansion": the sensor sets of the paper's Figure 1 (Effective Independence, Kammer 1991).
///
/// # Errors
/// Sizes; target modes dependent at the initial sensors.
pub fn efi_removal_order(
    layout: &SensorLayout,
    phi: MatRef<'_, f64>,
) -> Result<Vec<u64>, CorrelateError> {
    let phi_s = layout.measure_all(phi)?;
    let m = phi.ncols();
    let mut groups = node_groups(layout);
    let mut order = Vec::new();
    loop {
        let rows: Vec<usize> = groups.iter().flat_map(|g| g.1.iter().copied()).collect();
        let sub = Mat::from_fn(rows.len(), m, |i, j| phi_s[(rows[i], j)]);
        let ainv = fisher_inverse(sub.as_ref())?;
        let mut best: Option<(usize, f64)> = None;
        for (gi, g) in groups.iter().enumerate() {
            if rows.len() - g.1.len() < m {
                continue;
            }
            let keep = det_factor(&ainv, phi_s.as_ref(), &g.1, -1.0);
            if keep > 1e-12 && best.is_none_or(|b| keep > b.1) {
                best = Some((gi, keep));
            }
        }
        match best {
            Some((gi, _)) => order.push(groups.remove(gi).0),
            None => return Ok(order),
        }
    }
}

/// The order in which to add the layout's (candidate) nodes, most informative first: at each
/// step the node that gives the largest `det(Phi_s^T Phi_s + eps I)` (`eps = 1e-10` of the full
/// set's trace keeps the first, rank-deficient steps well defined).
///
/// # Errors
/// Sizes; an empty layout.
pub fn efi_addition_order(
    layout: &SensorLayout,
    phi: MatRef<'_, f64>,
) -> Result<Vec<u64>, CorrelateError> {
    let phi_s = layout.measure_all(phi)?;
    let m = phi.ncols();
    if layout.is_empty() || m == 0 {
        return Err(CorrelateError::Invalid {
            what: "effective independence",
            reason: "no candidate sensors or no target modes".into(),
        });
    }
    let trace: f64 = phi_s.squared_norm_l2();
    let eps = 1e-10 * trace / m as f64;
    let mut a = Mat::from_fn(m, m, |i, j| if i == j { eps } else { 0.0 });
    let mut groups = node_groups(layout);
    let mut order = Vec::new();
    while !groups.is_empty() {
        let eig = femu_sparse::dense::symmetric_eigen(a.as_ref())?;
        let ainv = Mat::from_fn(m, m, |i, j| {
            (0..m)
                .map(|k| eig.1[(i, k)] * eig.1[(j, k)] / eig.0[k])
                .sum()
        });
        let (gi, _) = groups
            .iter()
            .enumerate()
            .map(|(gi, g)| (gi, det_factor(&ainv, phi_s.as_ref(), &g.1, 1.0)))
            .fold((0, f64::NEG_INFINITY), |b, c| if c.1 > b.1 { c } else { b });
        let (node, rows) = groups.remove(gi);
        for r in rows {
            for i in 0..m {
                for j in 0..m {
                    a[(i, j)] += phi_s[(r, i)] * phi_s[(r, j)];
                }
            }
        }
        order.push(node);
    }
    Ok(order)
}
