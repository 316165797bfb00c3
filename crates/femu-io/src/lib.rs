//! # femu-io
//!
//! The files engineers have. This release reads and writes Abaqus/CalculiX input decks
//! ([`inp`]) and writes VTK files for ParaView ([`vtk`]); test modes as CSV ([`csv`]);
//! Gmsh and the Universal File Format follow.
//!
//! Every parse error names the file and the line; unknown keywords become warnings, never
//! failures.

pub mod csv;
mod error;
pub mod gmsh;
pub mod inp;
pub mod json;
pub mod uff;
pub mod vtk;

pub use error::{IoError, Warning};
