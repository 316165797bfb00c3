//! # femu-io
//!
//! The files engineers have. This release reads and writes Abaqus/CalculiX input decks
//! ([`inp`]) and writes VTK files for ParaView ([`vtk`]); test modes as CSV ([`csv`]);
//! Gmsh and the Universal File Format follow.
//!
//! Every parse error names the file and the line. Input is read as strictly as the reference
//! codes read it: an unknown keyword or parameter in a deck is an error naming the nearest known
//! spelling ([`inp::InpOptions::lenient`] turns unknown keywords, never unknown parameters, into
//! warnings); the warnings collected before an error travel with it ([`IoError::warnings`]).

pub mod ccx_dat;
pub mod csv;
mod error;
pub mod f06;
pub mod format;
pub mod frd;
pub mod gmsh;
pub mod inp;
pub mod json;
pub mod matrices;
mod memory;
pub mod nastran;
pub mod op2;
pub mod op4;
pub mod punch;
mod spelling;
mod stream;
pub mod test_data;
pub mod uff;
pub mod vtk;

pub use error::{IoError, Warning};
pub use format::Format;
pub use test_data::TestData;
