//! # femu-update
//!
//! Model updating for femu, after F. Hemez, "Can model updating tell the truth?" (the paper), with
//! the formulation of `docs/MATH.md` ("Updating"): `K(p) = K_0 + sum_g p_g K_g`,
//! `M(q) = M_0 + sum_g q_g M_g` over groups of elements.
//!
//! - [`problem`]: the parameterised model ([`UpdateModel`]) on the fixed sparse pattern, with
//!   bounds and the element-by-element sensitivity columns `K_g x`, `-lambda M_g x`.
//! - [`localise`](mod@localise): element (group) indicators from the residues: residual force and strain
//!   energy of the displacement residual (5), ranked, with a selection rule.
//! - [`sbebe`]: SB-EBE, alternating minimum-residual expansion and bounded least-squares
//!   corrections (13)-(15), nondimensionalised, with the total-mass guard.
//! - [`select`]: which parameters the data support (forward selection with an F-test on the
//!   weighted objective), and how stable that choice is under resampling.
//! - [`sensitivity`]: inverse eigensensitivity (Levenberg-Marquardt on relative eigenvalue errors,
//!   modes re-solved on the reused symbolic analysis).
//! - [`frf`](mod@frf): localisation and SB-EBE from measured frequency responses (the paper's
//!   FRF residue (4) on responses expanded at each line), with the loss factor.
//! - [`truth`]: the held-out check that answers the paper's title.
//!
//! ```
//! use femu_fem::prelude::*;
//! use femu_update::prelude::*;
//! use femu_correlate::prelude::*;
//!
//! // A clamped bar (rectangular section: no double modes) in 4 groups; the "truth" has group 1 20 % softer. With every DOF measured,
//! // inverse eigensensitivity on the 4 lowest modes finds it.
//! let mut mesh = box_mesh(&BoxSpec::new([0.4, 0.03, 0.02], [8, 1, 1], BoxCells::Hex, false)).unwrap();
//! for g in 0..4 {
//!     let ids: Vec<u64> = mesh.elements().filter(|e| e.index / 2 == g).map(|e| e.id).collect();
//!     mesh.add_element_set(format!("g{g}"), &ids).unwrap();
//! }
//! let mut model = Model::new(mesh).unwrap();
//! model.set_material(None, Material::steel()).unwrap();
//! model.fix_set("xmin", &[0, 1, 2]).unwrap();
//! let sets = ["g0", "g1", "g2", "g3"];
//! let mut truth = UpdateModel::from_element_sets(&model, &sets, MassKind::Consistent,
//!     Corrections::Stiffness).unwrap();
//! truth.set_theta(&[0.0, -0.2, 0.0, 0.0]).unwrap();
//! let modes = model_modes(&mut truth, 4, &Default::default()).unwrap();
//! let layout = SensorLayout::full(model.mesh(), &truth.matrices().dofs);
//! let test = TestModes::new(modes.frequencies_hz(), None, modes.shapes.clone()).unwrap();
//! let mut up = UpdateModel::from_element_sets(&model, &sets, MassKind::Consistent,
//!     Corrections::Stiffness).unwrap();
//! let result = inverse_eigensensitivity(&mut up, &layout, &test, &Default::default(), |_| {}).unwrap();
//! assert!((result.theta[1] + 0.2).abs() < 1e-4, "{result}");
//! ```

pub mod derivatives;
pub mod discretisation;
mod error;
pub mod frf;
pub mod localise;
pub mod lsq;
pub mod problem;
pub mod reach;
pub mod sbebe;
pub mod select;
pub mod sensitivity;
pub mod truth;

pub use derivatives::{EigenpairDerivatives, eigenpair_derivatives};
pub use error::UpdateError;
pub use frf::{
    FrfDamping, FrfIteration, FrfMethod, FrfTest, FrfUpdate, FrfUpdateOptions, frf_errors,
    frf_localise, frf_update, frf_update_logged,
};
pub use localise::{Indicator, Localisation, SelectionRule, localise, localise_expanded};
pub use lsq::{MassGuard, UpdateOptions};
pub use problem::{Corrections, Parameter, UpdateModel};
pub use sbebe::{
    Confidence, Iteration, SbebeOptions, StopReason, UpdateMethod, UpdateResult, sb_ebe,
};
pub use select::{
    EQUIVALENT_COSINE, ParameterSelection, SelectionOptions, SelectionStep, Stability, forward_at,
    select_parameters,
};
pub use sensitivity::{SensitivityOptions, TestUncertainty, inverse_eigensensitivity, model_modes};
pub use truth::{
    JudgeInputs, Judgement, ModeCheck, ParameterCheck, ParameterFinding, TruthCheck, Verdict,
    truth_check,
};

/// The types most programs need.
pub mod prelude {
    pub use crate::{
        Corrections, Indicator, Localisation, MassGuard, SbebeOptions, SelectionRule,
        SensitivityOptions, StopReason, TestUncertainty, TruthCheck, UpdateError, UpdateMethod,
        UpdateModel, UpdateOptions, UpdateResult, inverse_eigensensitivity, localise,
        localise_expanded, model_modes, sb_ebe, truth_check,
    };
}
