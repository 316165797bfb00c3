//! What every test reader returns: [`femu_correlate::TestData`], kept here under its reading
//! name.

pub use femu_correlate::TestData;
