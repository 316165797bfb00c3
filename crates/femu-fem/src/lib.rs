//! # femu-fem
//!
//! The finite element core of femu: meshes of mixed 3D solid elements with the user's ids,
//! isoparametric elements (tet4, tet10, hex8, hex20, penta6, penta15, pyramid5, pyramid13), beams,
//! rods, springs, bushings and 3-, 4- and 8-node shells on nodes with rotations ([`structural`], [`shell`],
//! [`shell8`]), linear elastic materials,
//! point masses, multipoint constraints (docs/MATH.md),
//! DOF maps with fixed DOFs, and parallel assembly of the sparse stiffness `K` and mass `M` on a
//! pattern computed once, with parameter groups `K(p) = K_0 + sum_g p_g K_g` for updating
//! (docs/MATH.md, "Updating").
//!
//! ```
//! use femu_fem::prelude::*;
//!
//! // A free-free steel bar, 0.1 x 0.02 x 0.02 m, hex20.
//! let mesh = box_mesh(&BoxSpec::new([0.1, 0.02, 0.02], [5, 1, 1], BoxCells::Hex, true)).unwrap();
//! let mut model = Model::new(mesh).unwrap();
//! model.set_material(None, Material::steel()).unwrap();
//! let sys = model.assemble(MassKind::Consistent).unwrap();
//! assert_eq!(sys.k.rows(), sys.dofs.free_count());
//! // A unit rigid translation along x carries the whole mass: u^T M u = rho V.
//! let u: Vec<f64> = (0..sys.dofs.free_count())
//!     .map(|f| if sys.dofs.full_of_free(f) % 3 == 0 { 1.0 } else { 0.0 })
//!     .collect();
//! let mass = femu_sparse::csc::bilinear(&sys.m, &u, &u).unwrap();
//! assert!((mass / (7850.0 * 0.1 * 0.02 * 0.02) - 1.0).abs() < 1e-12);
//! ```

pub mod align;
pub mod assembly;
pub mod beam3;
pub mod dof;
pub mod element;
mod error;
pub mod generate;
pub mod groups;
pub mod kernel;
pub mod locate;
pub mod material;
pub mod mesh;
pub mod model;
pub mod quadrature;
pub mod shell;
pub mod shell8;
pub mod structural;

pub use error::FemError;

/// The types most programs need.
pub mod prelude {
    pub use crate::FemError;
    pub use crate::assembly::{Assembler, Dampers, MassKind, SystemMatrices};
    pub use crate::dof::DofMap;
    pub use crate::element::ElementKind;
    pub use crate::generate::{BoxCells, BoxSpec, PlateSpec, add_slab_sets, box_mesh, mixed_plate};
    pub use crate::groups::{ParameterGroup, ParameterGroups};
    pub use crate::material::Material;
    pub use crate::mesh::Mesh;
    pub use crate::model::Model;
}
