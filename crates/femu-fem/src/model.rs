//! A model: a mesh, materials assigned to element sets, fixed DOFs and point masses.

use crate::FemError;
use crate::assembly::{Assembler, MassKind, SystemMatrices};
use crate::dof::DofMap;
use crate::material::Material;
use crate::mesh::Mesh;
use std::collections::BTreeSet;

/// A finite element model ready to assemble.
#[derive(Debug, Clone)]
pub struct Model {
    mesh: Mesh,
    materials: Vec<Material>,
    element_material: Vec<Option<usize>>,
    fixed: BTreeSet<(usize, usize)>,
    point_masses: Vec<PointMass>,
}

/// A concentrated mass on a node: sensors, shakers, attached equipment.
///
/// femu's nodes carry translations only, so a point mass is its 3x3 translational mass matrix
/// (`m I` for a plain mass). A mass offset from its node moves rigidly with it: with rotations
/// the offset would couple them to the translations, but without rotational DOFs its
/// translational mass is unchanged by the offset, and rotational inertia has no DOF to act on
/// (readers warn when they drop it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointMass {
    /// Internal node index.
    pub node: usize,
    /// The translational mass matrix (kg), symmetric positive semi-definite.
    pub mass: [[f64; 3]; 3],
}

impl Model {
    /// A model on a mesh, after [`Mesh::validate`] (every element must have a positive Jacobian).
    ///
    /// # Errors
    /// The first geometry error of [`Mesh::validate`].
    pub fn new(mesh: Mesh) -> Result<Self, FemError> {
        mesh.validate()?;
        let n = mesh.element_count();
        Ok(Self {
            mesh,
            materials: Vec::new(),
            element_material: vec![None; n],
            fixed: BTreeSet::new(),
            point_masses: Vec::new(),
        })
    }

    /// The mesh.
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// Assigns `material` to the elements of the named set, or to every element when `set` is
    /// `None`. Later assignments override earlier ones element by element.
    ///
    /// # Errors
    /// [`FemError::InvalidMaterial`] or [`FemError::UnknownElementSet`].
    pub fn set_material(&mut self, set: Option<&str>, material: Material) -> Result<(), FemError> {
        material.validate()?;
        let elements: Vec<usize> = match set {
            Some(name) => self.mesh.element_set(name)?.to_vec(),
            None => (0..self.mesh.element_count()).collect(),
        };
        self.materials.push(material);
        let m = self.materials.len() - 1;
        for e in elements {
            self.element_material[e] = Some(m);
        }
        Ok(())
    }

    /// The material of element `e` (internal index).
    ///
    /// # Errors
    /// [`FemError::NoMaterial`] naming the element id.
    pub fn material_of(&self, e: usize) -> Result<&Material, FemError> {
        self.element_material[e]
            .map(|m| &self.materials[m])
            .ok_or(FemError::NoMaterial {
                element: self.mesh.element(e).id,
            })
    }

    /// Fixes components (0 = x, 1 = y, 2 = z) of every node of a named node set.
    ///
    /// # Errors
    /// [`FemError::UnknownNodeSet`] or [`FemError::InvalidComponent`].
    pub fn fix_set(&mut self, set: &str, components: &[usize]) -> Result<(), FemError> {
        let nodes = self.mesh.node_set(set)?.to_vec();
        self.fix_indices(&nodes, components)
    }

    /// Fixes components of nodes given by user id.
    ///
    /// # Errors
    /// [`FemError::UnknownNode`] or [`FemError::InvalidComponent`].
    pub fn fix_nodes(&mut self, node_ids: &[u64], components: &[usize]) -> Result<(), FemError> {
        let nodes = node_ids
            .iter()
            .map(|n| {
                self.mesh
                    .node_index(*n)
                    .ok_or(FemError::UnknownNode { node: *n })
            })
            .collect::<Result<Vec<_>, _>>()?;
        self.fix_indices(&nodes, components)
    }

    fn fix_indices(&mut self, nodes: &[usize], components: &[usize]) -> Result<(), FemError> {
        if let Some(c) = components.iter().find(|c| **c > 2) {
            let node = nodes.first().map(|n| self.mesh.node_id(*n)).unwrap_or(0);
            return Err(FemError::InvalidComponent {
                node,
                component: *c,
            });
        }
        for n in nodes {
            for c in components {
                self.fixed.insert((*n, *c));
            }
        }
        Ok(())
    }

    /// Removes every constraint (a free-free model).
    pub fn clear_constraints(&mut self) {
        self.fixed.clear();
    }

    /// The fixed `(internal node, component)` pairs.
    pub fn fixed_dofs(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        self.fixed.iter().copied()
    }

    /// Adds a point mass `m` (kg) on node `node_id` (`m I`, the same in every direction).
    ///
    /// # Errors
    /// [`FemError::UnknownNode`]; [`FemError::InvalidMaterial`] for a mass that is not positive
    /// and finite.
    pub fn add_point_mass(&mut self, node_id: u64, m: f64) -> Result<(), FemError> {
        self.add_point_mass_matrix(node_id, [[m, 0.0, 0.0], [0.0, m, 0.0], [0.0, 0.0, m]])
    }

    /// Adds a point mass with a general symmetric translational mass matrix (kg).
    ///
    /// # Errors
    /// [`FemError::UnknownNode`]; [`FemError::InvalidMaterial`] for a matrix that is not finite,
    /// symmetric and positive semi-definite with a positive trace.
    pub fn add_point_mass_matrix(
        &mut self,
        node_id: u64,
        mass: [[f64; 3]; 3],
    ) -> Result<(), FemError> {
        let node = self
            .mesh
            .node_index(node_id)
            .ok_or(FemError::UnknownNode { node: node_id })?;
        let bad = |reason: String| FemError::InvalidMaterial {
            name: format!("point mass on node {node_id}"),
            reason,
        };
        if mass.iter().flatten().any(|v| !v.is_finite()) {
            return Err(bad(format!("{mass:?} is not finite")));
        }
        let trace = mass[0][0] + mass[1][1] + mass[2][2];
        let scale = mass.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        for i in 0..3 {
            for j in 0..3 {
                if (mass[i][j] - mass[j][i]).abs() > 1e-12 * scale {
                    return Err(bad(format!("{mass:?} is not symmetric")));
                }
            }
        }
        // positive semi-definite: the leading minors of the symmetric 3x3 (with a tolerance)
        let m = nalgebra::Matrix3::from_fn(|i, j| mass[i][j]);
        let low = m.symmetric_eigenvalues().min();
        if !(trace > 0.0) || low < -1e-12 * scale {
            return Err(bad(format!(
                "the mass must be positive (the matrix {mass:?} has eigenvalue {low:e})"
            )));
        }
        self.point_masses.push(PointMass { node, mass });
        Ok(())
    }

    /// The point masses.
    pub fn point_masses(&self) -> &[PointMass] {
        &self.point_masses
    }

    /// The DOF map of the current constraints.
    pub fn dof_map(&self) -> DofMap {
        DofMap::new(self.mesh.node_count(), self.fixed.iter().copied())
    }

    /// Total mass `sum_e rho_e V_e` plus the point masses (kg; a point mass counts the mean of
    /// its three directional masses).
    ///
    /// # Errors
    /// [`FemError::NoMaterial`] or a geometry error.
    pub fn total_mass(&self) -> Result<f64, FemError> {
        let mut x = Vec::new();
        let mut m = 0.0;
        for e in 0..self.mesh.element_count() {
            self.mesh.element_coords(e, &mut x);
            let el = self.mesh.element(e);
            let v = crate::kernel::element_volume(el.kind, &x).map_err(|b| {
                FemError::InvertedElement {
                    element: el.id,
                    det_j: b.det,
                    point: b.point,
                }
            })?;
            m += v * self.material_of(e)?.density;
        }
        // a point mass moves with its node: its mass in one direction, the mean of the three
        for p in &self.point_masses {
            m += (p.mass[0][0] + p.mass[1][1] + p.mass[2][2]) / 3.0;
        }
        Ok(m)
    }

    /// Assembles `K` and `M` (free DOFs) in one call; see [`Assembler`] to reuse the pattern.
    ///
    /// # Errors
    /// [`FemError::NoMaterial`], [`FemError::NoFreeDofs`] or an element geometry error.
    pub fn assemble(&self, mass: MassKind) -> Result<SystemMatrices, FemError> {
        Assembler::new(self)?.assemble(self, mass)
    }
}
