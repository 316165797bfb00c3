//! Degrees of freedom: three displacement components per node, fixed ones removed.
//!
//! The full numbering is `3 * node + component` (internal node index, component 0 = x, 1 = y,
//! 2 = z). Free DOFs are numbered node-major in the same order, skipping fixed ones, so the DOFs of
//! a node stay contiguous. Fixed DOFs have zero displacement and are absent from `K` and `M`.

use crate::FemError;

const FIXED: usize = usize::MAX;

/// The map between full (3 per node) and free DOF numberings.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DofMap {
    full_to_free: Vec<usize>,
    free_to_full: Vec<usize>,
}

impl DofMap {
    /// The map for `node_count` nodes with the listed `(node, component)` pairs fixed (internal
    /// node indices; duplicates allowed).
    ///
    /// # Panics
    /// If a node index is out of range or a component is not 0, 1 or 2 (callers validate user input).
    pub fn new(node_count: usize, fixed: impl IntoIterator<Item = (usize, usize)>) -> Self {
        let mut is_fixed = vec![false; 3 * node_count];
        for (n, c) in fixed {
            assert!(n < node_count && c < 3, "fixed DOF ({n}, {c}) out of range");
            is_fixed[3 * n + c] = true;
        }
        let mut full_to_free = vec![FIXED; 3 * node_count];
        let mut free_to_full = Vec::with_capacity(3 * node_count);
        for (d, f) in is_fixed.iter().enumerate() {
            if !f {
                full_to_free[d] = free_to_full.len();
                free_to_full.push(d);
            }
        }
        Self {
            full_to_free,
            free_to_full,
        }
    }

    /// Number of free DOFs (the size of `K` and `M`).
    pub fn free_count(&self) -> usize {
        self.free_to_full.len()
    }

    /// Number of DOFs with fixed ones included (`3 * node_count`).
    pub fn full_count(&self) -> usize {
        self.full_to_free.len()
    }

    /// Free index of component `c` of internal node `n`, or `None` if it is fixed.
    #[inline]
    pub fn free_index(&self, n: usize, c: usize) -> Option<usize> {
        let f = self.full_to_free[3 * n + c];
        (f != FIXED).then_some(f)
    }

    /// Free index of full DOF `d`, or `None` if it is fixed.
    #[inline]
    pub fn free_of_full(&self, d: usize) -> Option<usize> {
        let f = self.full_to_free[d];
        (f != FIXED).then_some(f)
    }

    /// Full index of free DOF `f`.
    #[inline]
    pub fn full_of_free(&self, f: usize) -> usize {
        self.free_to_full[f]
    }

    /// Free DOF indices of a node's three components (`None` where fixed).
    #[inline]
    pub fn node_dofs(&self, n: usize) -> [Option<usize>; 3] {
        [
            self.free_index(n, 0),
            self.free_index(n, 1),
            self.free_index(n, 2),
        ]
    }

    /// A full-length vector from a free one, with zeros at fixed DOFs.
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
        let mut full = vec![0.0; self.full_count()];
        for (f, d) in self.free_to_full.iter().enumerate() {
            full[*d] = free[f];
        }
        Ok(full)
    }

    /// The free entries of a full-length vector.
    ///
    /// # Errors
    /// [`FemError::LengthMismatch`].
    pub fn restrict(&self, full: &[f64]) -> Result<Vec<f64>, FemError> {
        if full.len() != self.full_count() {
            return Err(FemError::LengthMismatch {
                what: "full DOF vector",
                expected: self.full_count(),
                got: full.len(),
            });
        }
        Ok(self.free_to_full.iter().map(|d| full[*d]).collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbering_skips_fixed_dofs_and_round_trips() {
        let m = DofMap::new(3, [(0, 0), (0, 1), (0, 2), (2, 1), (2, 1)]);
        assert_eq!(m.free_count(), 5);
        assert_eq!(m.node_dofs(0), [None, None, None]);
        assert_eq!(m.node_dofs(1), [Some(0), Some(1), Some(2)]);
        assert_eq!(m.node_dofs(2), [Some(3), None, Some(4)]);
        let full = m.expand(&[1.0, 2.0, 3.0, 4.0, 5.0]).unwrap();
        assert_eq!(full, vec![0.0, 0.0, 0.0, 1.0, 2.0, 3.0, 4.0, 0.0, 5.0]);
        assert_eq!(m.restrict(&full).unwrap(), vec![1.0, 2.0, 3.0, 4.0, 5.0]);
        assert!(matches!(
            m.expand(&[1.0]),
            Err(FemError::LengthMismatch {
                expected: 5,
                got: 1,
                ..
            })
        ));
    }
}
