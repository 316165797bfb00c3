//! # femu-study
//!
//! femu's workflows, each written once and used by the `femu` command, the demo and library
//! users alike: a function with typed options and a typed, serialisable result.
//!
//! | workflow | function | command |
//! |---|---|---|
//! | load a model and a test | [`load::load_model`], [`load::load_test`] | every command |
//! | modes with their Sturm evidence | [`modes::solve_modes`] | `femu modes` |
//! | correlation and the a priori estimators (the paper's Tables 1 and 2) | [`estimate::estimate_with_bounds`] | `femu correlate`, `femu estimate` |
//! | expansion and the sensor-removal study (the paper's Figure 1) | [`expand::expansion_report`], [`removal::removal_study`] | `femu expand` |
//! | localise, update, check held-out modes | [`updating::localise_update_check`] | `femu update` |
//! | a whole study from a TOML file, the model assembled once | [`study_file::run_study_file`] | `femu run` |
//! | the paper's plate study end to end | [`demo::run_demo`] | `femu demo` |
//!
//! Charts are in [`chart`] (SVG, and PNG with the font shipped in this crate), report writers in
//! [`report`]. The mathematics is in `docs/MATH.md`, the data flow in `docs/ARCHITECTURE.md`.
//!
//! ```
//! use femu_study::demo::{DemoOptions, run_demo};
//! # let out = std::env::temp_dir().join(format!("femu-study-doc-{}", std::process::id()));
//! # if false {
//! let report = run_demo(&DemoOptions::quick(), |line| eprintln!("{line}"))?;
//! println!("{}", report.truth_check.verdict());
//! # }
//! # Ok::<(), femu_study::StudyError>(())
//! ```

pub mod chart;
pub mod demo;
pub use femu_update::discretisation;
mod error;
pub mod estimate;
pub mod expand;
pub mod external;
pub mod frf;
pub mod info;
pub mod load;
pub use femu_correlate::mapping;
pub mod modes;
pub use femu_update::reach;
pub mod removal;
pub mod report;
pub mod study_file;
pub mod updating;

pub use error::StudyError;

/// The workflows and their settings.
pub mod prelude {
    pub use crate::StudyError;
    pub use crate::demo::{DemoOptions, DemoReport, run_demo};
    pub use crate::estimate::{EstimateOptions, EstimateResult, estimate_with_bounds};
    pub use crate::expand::{ExpansionReport, expand_shapes, expansion_report};
    pub use crate::load::{
        LoadedModel, LoadedTest, MaterialOptions, ModelOptions, load_model, load_test,
    };
    pub use crate::modes::{EigenReport, ModesOptions, ModesReport, solve_modes};
    pub use crate::removal::{RemovalOptions, RemovalStudy, removal_study};
    pub use crate::study_file::{StudyFile, StudyRun, run_study_file};
    pub use crate::updating::{UpdateStudy, UpdateStudyOptions, localise_update_check};
}
