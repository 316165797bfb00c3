//! # femu
//!
//! Finite element model updating and test-analysis correlation in structural dynamics, after
//! F. Hemez, "Can model updating tell the truth?". This crate is the facade: it re-exports the
//! member crates without their prefix and gathers their preludes (`docs/ARCHITECTURE.md`).
//!
//! | module | crate | what |
//! |---|---|---|
//! | [`sparse`] | `femu-sparse` | sparse matrix type, factorizations, eigensolvers |
//! | [`fem`] | `femu-fem` | meshes, solid elements, materials, assembly of `K` and `M` |
//! | [`correlate`] | `femu-correlate` | residues, MAC/MSD, pairing, estimators, expansion |
//! | [`update`] | `femu-update` | localisation, SB-EBE, inverse eigensensitivity, truth check |
//! | [`io`] | `femu-io` | `.inp`, Gmsh, Universal File, CSV/JSON, VTK |
//! | [`study`] | `femu-study` | the workflows, charts and reports (`femu demo`, `femu run`) |
//!
//! ```
//! use femu::prelude::*;
//!
//! let mesh = mixed_plate(&PlateSpec::default())?;
//! let mut model = Model::new(mesh)?;
//! model.set_material(None, Material::steel())?;
//! let sys = model.assemble(MassKind::Consistent)?;
//! assert_eq!(sys.k.rows(), 5535); // free-free: 1,845 nodes x 3
//! # Ok::<(), femu::fem::FemError>(())
//! ```

pub use femu_correlate as correlate;
pub use femu_fem as fem;
pub use femu_io as io;
pub use femu_sparse as sparse;
pub use femu_study as study;
pub use femu_update as update;

/// Everything most programs need, from every member crate.
pub mod prelude {
    pub use femu_correlate::prelude::*;
    pub use femu_fem::prelude::*;
    pub use femu_sparse::SparseMatrix;
    pub use femu_study::prelude::*;
    pub use femu_update::prelude::*;
}

/// The README's code, compiled and run as a doctest so that it cannot drift from the API.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
