//! Expansion for sensors that read combinations of DOFs (oblique sensors, sensors between nodes).
//!
//! The expansion formulas partition the DOFs into measured `a` and omitted `o` (docs/MATH.md,
//! "Expansion"); a sensor whose row of `C` has several entries has no DOF of its own. A change of
//! coordinates gives it one: for each sensor `i` pick a pivot DOF `p_i` among the DOFs it reads and
//! replace the coordinate `x_{p_i}` by the reading `y_i = sum_j c_ij x_j`. Sensors that share DOFs
//! (three directions at one point, two points in one element) form a group whose pivots come from
//! complete pivoting on the group's block of `C`, so that `C_P` (the block's pivot columns) is
//! well conditioned:
//!
//! `x = T z`, with `z_P = y` and `z_O = x_O` otherwise, so `x_P = C_P^{-1} (z_P - C_O z_O)`.
//!
//! `T` is square, sparse and invertible; `K_z = T^T K T`, `M_z = T^T M T` have the eigenvalues of
//! `(K, M)`, the readings are now DOFs (`z_a = y`), and every norm the estimators use is the same in
//! both coordinates (`r_z = T^T r`, `M_z^{-1} = T^{-1} M^{-1} T^{-T}`, so
//! `r_z^T M_z^{-1} r_z = r^T M^{-1} r`). Static and dynamic expansion in `z` are exactly the
//! constrained expansions in `x` (`C x = y`, `Z x` in the range of `C^T`); the minimum-residual
//! methods use their diagonal metric built from `M_z`.

use super::{Expander, Method};
use crate::{CorrelateError, SensorLayout};
use faer::linalg::solvers::Solve;
use faer::{Mat, MatRef};
use femu_sparse::SparseMatrix;

/// Smallest accepted |pivot weight| relative to the largest weight of its sensor's row.
const PIVOT_RATIO: f64 = 1e-3;

/// The coordinates `z` in which every sensor reading is a DOF, with `K_z` and `M_z`.
#[derive(Debug, Clone)]
pub struct SensorBasis {
    /// `T` (`n x n`, CSC): `x = T z`.
    t: SparseMatrix,
    /// The pivot DOF of each sensor: where its reading sits in `z`.
    pivots: Vec<usize>,
    /// The rows of `C`.
    rows: Vec<Vec<(usize, f64)>>,
    k: SparseMatrix,
    m: SparseMatrix,
}

impl SensorBasis {
    /// The basis of `layout` for `K` and `M`.
    ///
    /// # Errors
    /// Sizes; a sensor every DOF of which another sensor also reads, or whose own DOFs carry less
    /// than 1e-3 of its largest weight (two sensors on one point or too close together: the
    /// message names both).
    pub fn new(
        k: &SparseMatrix,
        m: &SparseMatrix,
        layout: &SensorLayout,
    ) -> Result<Self, CorrelateError> {
        let n = k.rows();
        if layout.dim() != n || m.rows() != n {
            return Err(CorrelateError::DimensionMismatch {
                what: "sensor layout against K and M",
                expected: n,
                got: layout.dim(),
            });
        }
        let rows: Vec<Vec<(usize, f64)>> =
            (0..layout.len()).map(|s| layout.row(s).to_vec()).collect();
        // sensors that share a DOF form a group (union-find over rows through their DOFs)
        let mut parent: Vec<usize> = (0..rows.len()).collect();
        fn root(parent: &mut [usize], mut i: usize) -> usize {
            while parent[i] != i {
                parent[i] = parent[parent[i]];
                i = parent[i];
            }
            i
        }
        let mut owner = vec![usize::MAX; n];
        for (i, r) in rows.iter().enumerate() {
            for (f, _) in r {
                if owner[*f] == usize::MAX {
                    owner[*f] = i;
                } else {
                    let (a, b) = (root(&mut parent, owner[*f]), root(&mut parent, i));
                    parent[a] = b;
                }
            }
        }
        let mut groups: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
        for i in 0..rows.len() {
            let g = root(&mut parent, i);
            groups.entry(g).or_default().push(i);
        }
        let mut pivots = vec![usize::MAX; rows.len()];
        let mut is_pivot = vec![false; n];
        let mut tri = sprs::TriMat::new((n, n));
        for members in groups.values() {
            // the group's DOFs and its dense block of C
            let mut dofs: Vec<usize> = members
                .iter()
                .flat_map(|i| rows[*i].iter().map(|e| e.0))
                .collect();
            dofs.sort_unstable();
            dofs.dedup();
            let col = |f: usize| dofs.binary_search(&f).expect("a DOF of the group");
            let mut block = Mat::<f64>::zeros(members.len(), dofs.len());
            for (r, i) in members.iter().enumerate() {
                for (f, w) in &rows[*i] {
                    block[(r, col(*f))] = *w;
                }
            }
            // pivots by complete pivoting: each step takes the largest remaining entry
            let largest = block
                .col_iter()
                .flat_map(|c| c.iter().copied().collect::<Vec<_>>())
                .fold(0.0f64, |m, v| m.max(v.abs()));
            let mut work = block.clone();
            let mut free_rows: Vec<usize> = (0..members.len()).collect();
            let mut chosen = vec![usize::MAX; members.len()];
            for _ in 0..members.len() {
                let mut best = (0.0f64, 0usize, 0usize);
                for &r in &free_rows {
                    for c in 0..dofs.len() {
                        if work[(r, c)].abs() > best.0 {
                            best = (work[(r, c)].abs(), r, c);
                        }
                    }
                }
                let (size, pr, pc) = best;
                if !(size > PIVOT_RATIO * largest) {
                    let weak = free_rows[0];
                    let other = members.iter().copied().find(|&i| i != members[weak]);
                    let names = layout.sensors();
                    let i = members[weak];
                    return Err(CorrelateError::Invalid {
                        what: "sensor layout",
                        reason: match other {
                            Some(o) => format!(
                                "sensor {i} (node {}) reads nothing that sensor {o} (node {}) and the sensors near them do not already read: two sensors on one point, or too close together for expansion",
                                names[i].node, names[o].node
                            ),
                            None => format!("sensor {i} (node {}) reads no DOF", names[i].node),
                        },
                    });
                }
                chosen[pr] = pc;
                free_rows.retain(|&r| r != pr);
                for &r in &free_rows {
                    let f = work[(r, pc)] / work[(pr, pc)];
                    for c in 0..dofs.len() {
                        let v = work[(pr, c)];
                        work[(r, c)] -= f * v;
                    }
                }
            }
            // x_P = C_P^{-1} (z_P - C_O x_O), C_P[r][k] = block[r][chosen[k]]
            let cp = Mat::from_fn(members.len(), members.len(), |r, k| block[(r, chosen[k])]);
            let inv = cp
                .partial_piv_lu()
                .solve(Mat::<f64>::identity(members.len(), members.len()));
            for (k, &c) in chosen.iter().enumerate() {
                let p = dofs[c];
                pivots[members[k]] = p;
                is_pivot[p] = true;
            }
            for (k, &c) in chosen.iter().enumerate() {
                let p = dofs[c];
                for (r, &i) in members.iter().enumerate() {
                    tri.add_triplet(p, pivots[i], inv[(k, r)]);
                }
                for (oc, &f) in dofs.iter().enumerate() {
                    if chosen.contains(&oc) {
                        continue;
                    }
                    let v: f64 = (0..members.len())
                        .map(|r| inv[(k, r)] * block[(r, oc)])
                        .sum();
                    if v != 0.0 {
                        tri.add_triplet(p, f, -v);
                    }
                }
            }
        }
        for (j, pivot) in is_pivot.iter().enumerate() {
            if !pivot {
                tri.add_triplet(j, j, 1.0);
            }
        }
        let t: SparseMatrix = tri.to_csc();
        let tt: SparseMatrix = t.transpose_view().to_csc();
        let congruence = |a: &SparseMatrix| -> SparseMatrix {
            let b: SparseMatrix = &(&tt * a) * &t;
            // symmetric up to round-off: take the average of both triangles
            let bt: SparseMatrix = b.transpose_view().to_csc();
            (&b + &bt).map(|v| 0.5 * v)
        };
        let mz = congruence(m);
        // K_z's pattern must hold M_z's (the expander forms K - lambda M on K's pattern)
        let kz = &congruence(k) + &mz.map(|_| 0.0);
        Ok(Self {
            t,
            pivots,
            rows,
            k: kz,
            m: mz,
        })
    }

    /// `K_z = T^T K T` (both triangles).
    pub fn k(&self) -> &SparseMatrix {
        &self.k
    }

    /// `M_z = T^T M T` (both triangles).
    pub fn m(&self) -> &SparseMatrix {
        &self.m
    }

    /// The DOF of `z` holding each sensor's reading.
    pub fn pivots(&self) -> &[usize] {
        &self.pivots
    }

    /// `x = T z` for the columns of `z`.
    pub fn to_model(&self, z: MatRef<'_, f64>) -> Mat<f64> {
        let mut x = Mat::zeros(z.nrows(), z.ncols());
        for c in 0..self.t.cols() {
            let col = self.t.outer_view(c).expect("column in range");
            for (r, v) in col.iter() {
                for j in 0..z.ncols() {
                    x[(r, j)] += v * z[(c, j)];
                }
            }
        }
        x
    }

    /// `z = T^{-1} x`: `x` with each pivot DOF replaced by its sensor's reading.
    pub fn to_basis(&self, x: MatRef<'_, f64>) -> Mat<f64> {
        let mut z = x.to_owned();
        for (i, r) in self.rows.iter().enumerate() {
            for j in 0..x.ncols() {
                z[(self.pivots[i], j)] = r.iter().map(|(f, w)| w * x[(*f, j)]).sum();
            }
        }
        z
    }

    /// Expands the readings `ya` (`s x m`) by `method` in `z` and returns `x = T z` (`n x m`): each
    /// column satisfies `C x = y` exactly. `serep_basis` holds model modes in `x`.
    ///
    /// # Errors
    /// As [`Expander::expand`].
    pub fn expand(
        &self,
        method: Method,
        lambdas: &[f64],
        ya: MatRef<'_, f64>,
        serep_basis: Option<MatRef<'_, f64>>,
    ) -> Result<Mat<f64>, CorrelateError> {
        let expander = Expander::with_measured_dofs(&self.k, &self.m, &self.pivots)?;
        let basis = serep_basis.map(|b| self.to_basis(b));
        let z = expander.expand(method, lambdas, ya, basis.as_ref().map(|b| b.as_ref()))?;
        Ok(self.to_model(z.as_ref()))
    }
}
