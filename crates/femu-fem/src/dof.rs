//! Degrees of freedom: three displacement components per node, fixed ones removed, dependent ones
//! eliminated by multipoint constraints.
//!
//! The DOFs live on *points*: the mesh nodes (indices `0..node_count`), then one extra point per
//! node that carries rotations (a rigid link's reference node), whose three components are the
//! rotations about x, y and z. The full numbering is `3 * point + component`. A DOF is fixed (zero,
//! absent from `K` and `M`), free (numbered point-major in the same order, so the DOFs of a point
//! stay contiguous), or dependent: `u_d = sum_i w_i u_i` over free DOFs, a row of the
//! transformation `u = T z` of docs/MATH.md ("Multipoint constraints"), with `K_r = T^T K T`.

use crate::FemError;

/// What one DOF is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Slot {
    Fixed,
    Free(usize),
    /// Index into the dependent rows.
    Dependent(usize),
}

/// A linear homogeneous multipoint constraint `u_dependent = sum_i w_i u_i` between DOFs given as
/// `(internal node index, component)`: components 0, 1, 2 are translations, 3, 4, 5 rotations
/// (only on nodes that carry rotations, see [`crate::model::Model::add_rotations`]).
#[derive(Debug, Clone, PartialEq)]
pub struct LinearConstraint {
    /// The dependent DOF.
    pub dependent: (usize, usize),
    /// The independent DOFs and their weights (they may be fixed or dependent themselves).
    pub terms: Vec<((usize, usize), f64)>,
    /// Where the constraint comes from (card or keyword, id, file and line) for error messages.
    pub label: String,
}

/// The map between full (3 per point) and free DOF numberings, with the dependent DOFs' rows of
/// `T`.
#[derive(Debug, Clone, PartialEq)]
pub struct DofMap {
    node_count: usize,
    /// Node of each rotation point `node_count + k`.
    rotation_nodes: Vec<usize>,
    /// Rotation point of each node (`usize::MAX` if none); empty when no node has rotations.
    rotation_point: Vec<usize>,
    slots: Vec<Slot>,
    free_to_full: Vec<usize>,
    /// `(f, 1.0)` for every free DOF `f`: the one-term row of a free DOF.
    unit: Vec<(usize, f64)>,
    dep_ptr: Vec<usize>,
    dep_terms: Vec<(usize, f64)>,
}

impl Eq for DofMap {}

impl DofMap {
    /// The map for `node_count` nodes with the listed `(node, component)` pairs fixed (internal
    /// node indices; duplicates allowed), no rotations and no multipoint constraints.
    ///
    /// # Panics
    /// If a node index is out of range or a component is not 0, 1 or 2 (callers validate user input).
    pub fn new(node_count: usize, fixed: impl IntoIterator<Item = (usize, usize)>) -> Self {
        let fixed: Vec<(usize, usize)> = fixed.into_iter().collect();
        for &(n, c) in &fixed {
            assert!(n < node_count && c < 3, "fixed DOF ({n}, {c}) out of range");
        }
        match Self::with_constraints(node_count, fixed, &[], &[], |n| n as u64) {
            Ok(m) => m,
            Err(e) => unreachable!("no constraints cannot fail: {e}"),
        }
    }

    /// The map with rotations on `rotation_nodes`, the `fixed` DOFs (components 0 to 5; rotations
    /// only on those nodes) and the multipoint constraints, resolved so that every dependent DOF
    /// is a combination of free ones: fixed independents drop out, dependent independents are
    /// substituted (chains of any depth).
    ///
    /// # Errors
    /// [`FemError::Constraint`] naming the constraint (with `node_id` turning internal indices into
    /// the user's ids): a DOF made dependent twice, a dependent DOF that is also fixed, a cycle of
    /// dependencies, a node or component out of range, a weight that is not finite.
    pub fn with_constraints(
        node_count: usize,
        fixed: impl IntoIterator<Item = (usize, usize)>,
        rotation_nodes: &[usize],
        constraints: &[LinearConstraint],
        node_id: impl Fn(usize) -> u64,
    ) -> Result<Self, FemError> {
        let mut rotation_point = Vec::new();
        if !rotation_nodes.is_empty() {
            rotation_point = vec![usize::MAX; node_count];
            for (k, &n) in rotation_nodes.iter().enumerate() {
                rotation_point[n] = node_count + k;
            }
        }
        let points = node_count + rotation_nodes.len();
        let full_of = |n: usize, c: usize| -> Option<usize> {
            if n >= node_count {
                return None;
            }
            match c {
                0..=2 => Some(3 * n + c),
                3..=5 => rotation_point
                    .get(n)
                    .filter(|p| **p != usize::MAX)
                    .map(|p| 3 * p + c - 3),
                _ => None,
            }
        };
        let dof_name = |n: usize, c: usize| {
            let id = if n < node_count { node_id(n) } else { n as u64 };
            format!(
                "node {id} {}",
                ["x", "y", "z", "rx", "ry", "rz"].get(c).unwrap_or(&"?")
            )
        };
        let mut slots = vec![Slot::Free(0); 3 * points];
        let mut fixed_list = Vec::new();
        for (n, c) in fixed {
            let d = full_of(n, c).ok_or_else(|| FemError::Constraint {
                label: "fixed DOF".into(),
                reason: format!("{} does not exist", dof_name(n, c)),
            })?;
            slots[d] = Slot::Fixed;
            fixed_list.push(d);
        }
        // dependents
        let mut dep_full = Vec::with_capacity(constraints.len());
        let mut owner: std::collections::HashMap<usize, usize> = Default::default();
        for (ci, con) in constraints.iter().enumerate() {
            let bad = |reason: String| FemError::Constraint {
                label: con.label.clone(),
                reason,
            };
            let (n, c) = con.dependent;
            let d = full_of(n, c).ok_or_else(|| {
                bad(format!(
                    "its dependent DOF, {}, does not exist",
                    dof_name(n, c)
                ))
            })?;
            match slots[d] {
                Slot::Fixed => {
                    return Err(bad(format!(
                        "its dependent DOF, {}, is also fixed (a boundary condition on it): a DOF is either fixed or dependent",
                        dof_name(n, c)
                    )));
                }
                Slot::Dependent(_) => {
                    return Err(bad(format!(
                        "its dependent DOF, {}, is already dependent in {}",
                        dof_name(n, c),
                        constraints[owner[&d]].label
                    )));
                }
                Slot::Free(_) => {}
            }
            for &((m, k), w) in &con.terms {
                if full_of(m, k).is_none() {
                    return Err(bad(format!(
                        "its term on {} does not exist",
                        dof_name(m, k)
                    )));
                }
                if !w.is_finite() {
                    return Err(bad(format!("the weight of {} is {w}", dof_name(m, k))));
                }
            }
            slots[d] = Slot::Dependent(ci);
            owner.insert(d, ci);
            dep_full.push(d);
        }
        // free numbering, point-major
        let mut free_to_full = Vec::new();
        for (d, s) in slots.iter_mut().enumerate() {
            if let Slot::Free(f) = s {
                *f = free_to_full.len();
                free_to_full.push(d);
            }
        }
        // resolve every constraint to free DOFs (explicit stack: chains of any depth)
        let mut resolved: Vec<Option<Vec<(usize, f64)>>> = vec![None; constraints.len()];
        let mut on_stack = vec![false; constraints.len()];
        for start in 0..constraints.len() {
            if resolved[start].is_some() {
                continue;
            }
            let mut stack = vec![start];
            on_stack[start] = true;
            while let Some(&ci) = stack.last() {
                let mut pending = None;
                for &((m, k), _) in &constraints[ci].terms {
                    let d = full_of(m, k).unwrap_or(usize::MAX);
                    if let Slot::Dependent(cj) = slots[d]
                        && resolved[cj].is_none()
                    {
                        if on_stack[cj] {
                            let from = stack.iter().position(|s| *s == cj).unwrap_or(0);
                            let chain: Vec<String> = stack[from..]
                                .iter()
                                .map(|s| {
                                    let (n, c) = constraints[*s].dependent;
                                    format!("{} ({})", dof_name(n, c), constraints[*s].label)
                                })
                                .collect();
                            return Err(FemError::Constraint {
                                label: constraints[ci].label.clone(),
                                reason: format!(
                                    "its dependent DOFs form a cycle: {} depends on itself",
                                    chain.join(" -> ")
                                ),
                            });
                        }
                        pending = Some(cj);
                        break;
                    }
                }
                if let Some(cj) = pending {
                    on_stack[cj] = true;
                    stack.push(cj);
                    continue;
                }
                let mut row: Vec<(usize, f64)> = Vec::new();
                for &((m, k), w) in &constraints[ci].terms {
                    let d = full_of(m, k).unwrap_or(usize::MAX);
                    match slots[d] {
                        Slot::Fixed => {}
                        Slot::Free(f) => row.push((f, w)),
                        Slot::Dependent(cj) => {
                            if let Some(r) = &resolved[cj] {
                                row.extend(r.iter().map(|(f, v)| (*f, w * v)));
                            }
                        }
                    }
                }
                row.sort_by_key(|(f, _)| *f);
                let mut merged: Vec<(usize, f64)> = Vec::with_capacity(row.len());
                for (f, w) in row {
                    match merged.last_mut() {
                        Some((g, v)) if *g == f => *v += w,
                        _ => merged.push((f, w)),
                    }
                }
                merged.retain(|(_, w)| *w != 0.0);
                resolved[ci] = Some(merged);
                on_stack[ci] = false;
                stack.pop();
            }
        }
        let mut dep_ptr = vec![0];
        let mut dep_terms = Vec::new();
        for r in resolved {
            dep_terms.extend(r.unwrap_or_default());
            dep_ptr.push(dep_terms.len());
        }
        let unit = (0..free_to_full.len()).map(|f| (f, 1.0)).collect();
        Ok(Self {
            node_count,
            rotation_nodes: rotation_nodes.to_vec(),
            rotation_point,
            slots,
            free_to_full,
            unit,
            dep_ptr,
            dep_terms,
        })
    }

    /// Number of free DOFs (the size of `K` and `M`).
    pub fn free_count(&self) -> usize {
        self.free_to_full.len()
    }

    /// Number of translational DOFs of the mesh nodes (`3 * node_count`): the length of
    /// [`DofMap::expand`]'s vectors.
    pub fn full_count(&self) -> usize {
        3 * self.node_count
    }

    /// Number of points: the mesh nodes, then one per node with rotations.
    pub fn point_count(&self) -> usize {
        self.node_count + self.rotation_nodes.len()
    }

    /// Number of mesh nodes.
    pub fn node_count(&self) -> usize {
        self.node_count
    }

    /// Whether some DOF is dependent (the model has multipoint constraints).
    pub fn has_dependents(&self) -> bool {
        self.dep_ptr.len() > 1
    }

    /// The nodes that carry rotations, in the order of their points `node_count + k`.
    pub fn rotation_nodes(&self) -> &[usize] {
        &self.rotation_nodes
    }

    /// The point holding node `n`'s rotations, if it has them.
    pub fn rotation_point(&self, n: usize) -> Option<usize> {
        self.rotation_point
            .get(n)
            .copied()
            .filter(|p| *p != usize::MAX)
    }

    /// The node of point `p` and whether the point is that node's rotations.
    ///
    /// # Panics
    /// If `p >= point_count()`.
    pub fn point_node(&self, p: usize) -> (usize, bool) {
        if p < self.node_count {
            (p, false)
        } else {
            (self.rotation_nodes[p - self.node_count], true)
        }
    }

    /// Free index of component `c` (0, 1, 2) of point `p`, or `None` if it is fixed or dependent.
    #[inline]
    pub fn free_index(&self, p: usize, c: usize) -> Option<usize> {
        match self.slots[3 * p + c] {
            Slot::Free(f) => Some(f),
            _ => None,
        }
    }

    /// The row of `T` of component `c` (0, 1, 2) of point `p`: `(free index, weight)` pairs, one
    /// `(f, 1)` for a free DOF, none for a fixed one, the resolved combination for a dependent one.
    #[inline]
    pub fn terms(&self, p: usize, c: usize) -> &[(usize, f64)] {
        match self.slots[3 * p + c] {
            Slot::Fixed => &[],
            Slot::Free(f) => &self.unit[f..f + 1],
            Slot::Dependent(k) => &self.dep_terms[self.dep_ptr[k]..self.dep_ptr[k + 1]],
        }
    }

    /// Whether any component of point `p` is dependent.
    #[inline]
    pub fn has_dependent(&self, p: usize) -> bool {
        self.slots[3 * p..3 * p + 3]
            .iter()
            .any(|s| matches!(s, Slot::Dependent(_)))
    }

    /// Whether component `c` of point `p` is dependent.
    #[inline]
    pub fn is_dependent(&self, p: usize, c: usize) -> bool {
        matches!(self.slots[3 * p + c], Slot::Dependent(_))
    }

    /// Free DOF indices of a point's three components (`None` where fixed or dependent).
    #[inline]
    pub fn node_dofs(&self, p: usize) -> [Option<usize>; 3] {
        [
            self.free_index(p, 0),
            self.free_index(p, 1),
            self.free_index(p, 2),
        ]
    }

    /// Full index `3 * point + component` of free DOF `f` (a point beyond the mesh nodes is a
    /// node's rotations, see [`DofMap::point_node`]).
    #[inline]
    pub fn full_of_free(&self, f: usize) -> usize {
        self.free_to_full[f]
    }

    /// The point and component (0, 1, 2) of free DOF `f`; see [`DofMap::point_node`] for the node.
    #[inline]
    pub fn free_dof(&self, f: usize) -> (usize, usize) {
        let d = self.free_to_full[f];
        (d / 3, d % 3)
    }

    /// The six rigid-body motions of the nodes at `coords` as free vectors (`free_count() x 6`):
    /// translations along x, y, z, then rotations about axes through the centroid of the nodes,
    /// scaled by their largest distance from it so that every column is of order one. A point
    /// carrying rotations gets the rotation itself. At fixed DOFs the motions are simply absent,
    /// so a vector is a null vector of `K` only where the supports and constraints allow that
    /// motion: the eigensolver keeps the combinations that are ([`femu_sparse::eigen::NullSpaceHint`]).
    ///
    /// # Panics
    /// If `coords` has fewer entries than the map's nodes.
    pub fn rigid_body_motions(&self, coords: &[[f64; 3]]) -> faer::Mat<f64> {
        let nodes = &coords[..self.node_count];
        let count = nodes.len().max(1) as f64;
        let mut c0 = [0.0; 3];
        for x in nodes {
            (0..3).for_each(|i| c0[i] += x[i] / count);
        }
        let reach = nodes
            .iter()
            .map(|x| (0..3).map(|i| (x[i] - c0[i]).powi(2)).sum::<f64>().sqrt())
            .fold(0.0_f64, f64::max);
        let scale = if reach > 0.0 { 1.0 / reach } else { 1.0 };
        faer::Mat::from_fn(self.free_count(), 6, |f, k| {
            let (p, c) = self.free_dof(f);
            let (node, rotation) = self.point_node(p);
            if k < 3 {
                return if !rotation && c == k { 1.0 } else { 0.0 };
            }
            let axis = k - 3;
            if rotation {
                return if c == axis { scale } else { 0.0 };
            }
            // (e_axis x d)_c with d the node's offset from the centroid
            let d: [f64; 3] = std::array::from_fn(|i| (nodes[node][i] - c0[i]) * scale);
            match (axis, c) {
                (0, 1) => -d[2],
                (0, 2) => d[1],
                (1, 0) => d[2],
                (1, 2) => -d[0],
                (2, 0) => -d[1],
                (2, 1) => d[0],
                _ => 0.0,
            }
        })
    }

    /// The translations of every mesh node from a free vector `z`: `u = T z` (zeros at fixed
    /// DOFs, the constraint's combination at dependent ones), `3 * node + component`.
    ///
    /// # Errors
    /// [`FemError::LengthMismatch`].
    pub fn expand(&self, free: &[f64]) -> Result<Vec<f64>, FemError> {
        if free.len() != self.free_count() {
            return Err(FemError::LengthMismatch {
                what: "free DOF vector",
                expected: self.free_count(),
                got: free.len(),
            });
        }
        Ok((0..self.full_count())
            .map(|d| {
                self.terms(d / 3, d % 3)
                    .iter()
                    .map(|(f, w)| w * free[*f])
                    .sum()
            })
            .collect())
    }

    /// The rotations of node `n` (radians) from a free vector, if the node carries rotations.
    ///
    /// # Errors
    /// [`FemError::LengthMismatch`].
    pub fn rotations(&self, n: usize, free: &[f64]) -> Result<Option<[f64; 3]>, FemError> {
        if free.len() != self.free_count() {
            return Err(FemError::LengthMismatch {
                what: "free DOF vector",
                expected: self.free_count(),
                got: free.len(),
            });
        }
        Ok(self.rotation_point(n).map(|p| {
            std::array::from_fn(|c| self.terms(p, c).iter().map(|(f, w)| w * free[*f]).sum())
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbering_skips_fixed_dofs_and_expands() {
        let m = DofMap::new(3, [(0, 0), (0, 1), (0, 2), (2, 1), (2, 1)]);
        assert_eq!(m.free_count(), 5);
        assert_eq!(m.node_dofs(0), [None, None, None]);
        assert_eq!(m.node_dofs(1), [Some(0), Some(1), Some(2)]);
        assert_eq!(m.node_dofs(2), [Some(3), None, Some(4)]);
        let full = m.expand(&[1.0, 2.0, 3.0, 4.0, 5.0]).unwrap();
        assert_eq!(full, vec![0.0, 0.0, 0.0, 1.0, 2.0, 3.0, 4.0, 0.0, 5.0]);
        assert_eq!(m.free_dof(3), (2, 0));
        assert!(matches!(
            m.expand(&[1.0]),
            Err(FemError::LengthMismatch {
                expected: 5,
                got: 1,
                ..
            })
        ));
    }

    fn con(dep: (usize, usize), terms: &[((usize, usize), f64)], label: &str) -> LinearConstraint {
        LinearConstraint {
            dependent: dep,
            terms: terms.to_vec(),
            label: label.into(),
        }
    }

    #[test]
    fn chains_resolve_to_free_dofs_and_fixed_terms_drop() {
        // u(0,x) = 2 u(1,x) + u(2,y); u(1,x) = 0.5 u(2,x) - u(2,z); u(2,y) fixed
        let cons = [
            con((0, 0), &[((1, 0), 2.0), ((2, 1), 1.0)], "a"),
            con((1, 0), &[((2, 0), 0.5), ((2, 2), -1.0)], "b"),
        ];
        let m = DofMap::with_constraints(3, [(2, 1)], &[], &cons, |n| 100 + n as u64).unwrap();
        // free: (0,y) (0,z) (1,y) (1,z) (2,x) (2,z)
        assert_eq!(m.free_count(), 6);
        assert_eq!(m.terms(0, 0), &[(4, 1.0), (5, -2.0)]);
        let z = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
        let u = m.expand(&z).unwrap();
        // by hand: u(1,x) = 0.5*5 - 6 = -3.5; u(0,x) = 2*(-3.5) + 0 = -7
        assert_eq!(u, vec![-7.0, 1.0, 2.0, -3.5, 3.0, 4.0, 5.0, 0.0, 6.0]);
    }

    #[test]
    fn conflicts_and_cycles_are_named() {
        let twice = [
            con((0, 0), &[((1, 0), 1.0)], "RBE2 7"),
            con((0, 0), &[((2, 0), 1.0)], "RBE2 8"),
        ];
        let e = DofMap::with_constraints(3, [], &[], &twice, |n| 10 + n as u64).unwrap_err();
        let s = e.to_string();
        assert!(
            s.contains("RBE2 8") && s.contains("node 10 x") && s.contains("RBE2 7"),
            "{s}"
        );
        let fixed = [con((0, 1), &[((1, 1), 1.0)], "EQ")];
        let s = DofMap::with_constraints(2, [(0, 1)], &[], &fixed, |n| n as u64)
            .unwrap_err()
            .to_string();
        assert!(s.contains("also fixed"), "{s}");
        let cycle = [
            con((0, 0), &[((1, 0), 1.0)], "A"),
            con((1, 0), &[((2, 0), 1.0)], "B"),
            con((2, 0), &[((0, 0), 1.0)], "C"),
        ];
        let s = DofMap::with_constraints(3, [], &[], &cycle, |n| n as u64)
            .unwrap_err()
            .to_string();
        assert!(
            s.contains("cycle") && s.contains("(A)") && s.contains("(C)"),
            "{s}"
        );
        let rot = [con((0, 3), &[((1, 0), 1.0)], "R")];
        let s = DofMap::with_constraints(2, [], &[], &rot, |n| n as u64)
            .unwrap_err()
            .to_string();
        assert!(
            s.contains("node 0 rx") && s.contains("does not exist"),
            "{s}"
        );
    }
}
