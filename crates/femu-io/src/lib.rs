//! # femu-io
//!
//! The files engineers have. This release reads and writes Abaqus/CalculiX input decks
//! ([`inp`]) and writes VTK files for ParaView ([`vtk`]); Gmsh, Universal File Format and CSV/JSON
//! test data follow.
//!
//! Every parse error names the file and the line; unknown keywords become warnings, never
//! failures.

mod error;
pub mod inp;
pub mod vtk;

pub use error::{IoError, Warning};
