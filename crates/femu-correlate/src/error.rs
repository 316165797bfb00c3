use femu_fem::FemError;
use femu_sparse::SparseError;
use thiserror::Error;

/// Errors of correlation and estimation. Each names the offending sensor, node or mode.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum CorrelateError {
    /// From the sparse core (factorizations, shapes of matrices).
    #[error(transparent)]
    Sparse(#[from] SparseError),
    /// From the finite element core.
    #[error(transparent)]
    Fem(#[from] FemError),
    /// A sensor on a node the mesh does not have.
    #[error("sensor {} (in the order of the file) is on node {node}, which the model does not have", sensor + 1)]
    SensorOnMissingNode {
        /// Position of the sensor in the layout (0-based).
        sensor: usize,
        /// The node id.
        node: u64,
    },
    /// A sensor whose direction has a component along a constrained DOF: the model says that
    /// motion is zero, so the reading cannot be compared (usually a wrong node id).
    #[error(
        "sensor {} on node {node} measures along {}, which the model clamps (its motion there is zero by the boundary conditions; is the node id right?)",
        sensor + 1,
        ["x", "y", "z"].get(*component).copied().unwrap_or("an unknown direction")
    )]
    SensorOnConstrainedDof {
        /// Position of the sensor in the layout.
        sensor: usize,
        /// The node id.
        node: u64,
        /// The constrained component.
        component: usize,
    },
    /// A sensor direction that is zero or not finite.
    #[error(
        "sensor {} on node {node} has an invalid direction ({}, {}, {}): it must be finite and not zero",
        sensor + 1, direction[0], direction[1], direction[2]
    )]
    BadDirection {
        /// Position of the sensor in the layout.
        sensor: usize,
        /// The node id.
        node: u64,
        /// The direction given.
        direction: [f64; 3],
    },
    /// Two sensors measure the same motion (same node, parallel directions).
    #[error("sensors {first} and {second} both measure node {node} along the same direction")]
    DuplicateSensor {
        /// The first sensor.
        first: usize,
        /// The repeated one.
        second: usize,
        /// The node id.
        node: u64,
    },
    /// A NaN or infinity in input data.
    #[error("{what} is not finite at index {index}")]
    NonFinite {
        /// Which input.
        what: &'static str,
        /// Where (mode, entry, ...).
        index: usize,
    },
    /// A test wireframe that cannot be mapped onto the model, or an alignment or mapping
    /// method that cannot be read (`what`: `map`, `align`).
    #[error("{what}: {reason}")]
    Mapping {
        /// The setting or step.
        what: &'static str,
        /// What is wrong and what would fit.
        reason: String,
    },
    /// A value outside its allowed range.
    #[error("invalid {what}: {reason}")]
    Invalid {
        /// Which input.
        what: &'static str,
        /// Why.
        reason: String,
    },
    /// Operands of incompatible sizes.
    #[error("dimension mismatch: {what} (expected {expected}, got {got})")]
    DimensionMismatch {
        /// Which operand.
        what: &'static str,
        /// Size required.
        expected: usize,
        /// Size given.
        got: usize,
    },
    /// A zero vector where a mode shape is needed (MAC and MSD are undefined).
    #[error("{what} {index} is the zero vector")]
    ZeroVector {
        /// Which set of vectors.
        what: &'static str,
        /// Its index.
        index: usize,
    },
}
