//! # femu-correlate
//!
//! Test-analysis correlation and the a priori error estimators of F. Hemez, "Can model updating
//! tell the truth?" (the paper), with the exact definitions of `docs/MATH.md`:
//!
//! - [`modes`]: model mode sets (s^-2, M-normalisation recorded) and test modes (Hz, shapes at
//!   sensors); [`sensors`]: sensor layouts (node + any direction) mapped to model DOFs.
//! - [`residues`]: force (3), forced (4), displacement (5), ECL (7)-(8), EIL (10)-(11), with the
//!   free-free convention of docs/MATH.md for a singular `K`.
//! - [`correlation`]: frequency errors, eigenvalue gaps, `MAC_M` (16) and MAC on sensors, AutoMAC,
//!   COMAC, MSD (17), cross-orthogonality; [`pairing`]: optimal assignment with a MAC threshold.
//! - [`estimators`]: `rho_M` and `rho_2`, Theorems 1-4 (26)-(29) in the paper's and the rigorous
//!   form, a priori MAC and MSD bounds, Kato-Temple; [`bounds`]: `lambda_max` and `mu_min(M)`
//!   bounds from element matrices; [`mass`]: the cheap `M^-1` products they need.
//! - [`expansion`], [`sensor_space`], [`placement`], [`study`]: modal expansion from sensors
//!   (static, dynamic, SEREP, minimum residual, MDRE-WE), sensor sets (EfI) and the paper's
//!   Figure 1 study.
//! - [`report`]: one-call correlation and estimation with serialisable, printable results.
//!
//! ```
//! use femu_correlate::prelude::*;
//! use femu_fem::prelude::*;
//!
//! // A clamped steel bar and a "test" that is the model's own first mode with a 2 % frequency
//! // error: the estimator brackets a model eigenvalue without any eigen extraction.
//! let mesh = box_mesh(&BoxSpec::new([0.2, 0.02, 0.02], [10, 1, 1], BoxCells::Hex, false)).unwrap();
//! let mut model = Model::new(mesh).unwrap();
//! model.set_material(None, Material::steel()).unwrap();
//! model.fix_set("xmin", &[0, 1, 2]).unwrap();
//! let sys = model.assemble(MassKind::Consistent).unwrap();
//! let modes = femu_sparse::eigen::eigs(&sys.k, &sys.m, femu_sparse::eigen::Which::Lowest(1),
//!     &Default::default()).unwrap();
//! let lambda_id = modes.values[0] * 1.02f64.powi(2);
//! let est = Estimator::new(&sys.k, &sys.m).unwrap();
//! // (the square section makes the first bending mode double: the solver returns both copies)
//! assert_eq!(modes.values.len(), 2);
//! let x = modes.vectors.as_ref().subcols(0, 1);
//! let (norms, _) = est.residual_norms(&[lambda_id], x).unwrap();
//! // x is an exact eigenvector, so rho_M is exactly the eigenvalue gap (identity (25)).
//! let gap = lambda_id - modes.values[0];
//! assert!((norms[0].rho_m / gap - 1.0).abs() < 1e-8);
//! // Theorem 2: a model eigenvalue lies in [lambda_id - rho_M, lambda_id + rho_M]; here on its
//! // edge, to the eigensolver's accuracy.
//! let (lo, hi) = norms[0].eigenvalue_interval();
//! assert!(lo <= modes.values[0] * (1.0 + 1e-9) && modes.values[0] <= hi);
//! ```

pub mod bounds;
pub mod complexity;
pub mod correlation;
pub mod damped;
mod error;
pub mod estimators;
pub mod expansion;
pub mod frf;
mod hz;
pub mod mapping;
pub mod mass;
pub mod modes;
pub mod pairing;
pub mod placement;
pub mod report;
pub mod residues;
pub mod sensor_space;
pub mod sensors;
pub mod study;
pub mod test_data;

pub use bounds::{ElementBounds, element_bounds, inertia_bounds};
pub use complexity::Complexity;
pub use error::CorrelateError;
pub use estimators::{
    Bound, BoundKind, Estimator, Form, ModelSpectrum, PairedModel, Relation, ResidualNorms,
    SpectrumProof, assess, is_identity, sin_theta_bound,
};
pub use expansion::{
    Expander, Method, Partition, SENSOR_SPACE_LIMIT, SensorBasis, TestErrorExpansion,
};
pub use mass::MassSolver;
pub use modes::{ModeSet, TestModes};
pub use pairing::{Pair, Pairing, PairingOptions, pair_by_frequency, pair_modes};
pub use report::{Assessment, CorrelationReport, correlate, estimate};
pub use residues::StiffnessSolver;
pub use sensor_space::SensorSpace;
pub use sensors::{Sensor, SensorLayout};
pub use test_data::TestData;

/// The types most programs need.
pub mod prelude {
    pub use crate::correlation::{complex_mac, mac, mac_m, mac_m_matrix, mac_matrix, msd, msd_m};
    pub use crate::{
        Bound, BoundKind, CorrelateError, ElementBounds, Estimator, Form, MassSolver, ModeSet,
        ModelSpectrum, PairedModel, Pairing, PairingOptions, Sensor, SensorLayout, StiffnessSolver,
        TestModes, assess, correlate, element_bounds, estimate, pair_modes,
    };
}
