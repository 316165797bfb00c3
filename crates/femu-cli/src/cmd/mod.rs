//! One module per subcommand: its arguments and its `run`.

pub mod correlate;
pub mod demo;
pub mod estimate;
pub mod expand;
pub mod frf;
pub mod info;
pub mod matrices;
pub mod modes;
pub mod run;
pub mod update;
