use crate::element::ElementKind;
use thiserror::Error;

/// Errors of the finite element core. Every variant names the offender by the user's id.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum FemError {
    /// Two nodes with the same id.
    #[error("duplicate node id {id}")]
    DuplicateNodeId {
        /// The id.
        id: u64,
    },
    /// Two elements with the same id.
    #[error("duplicate element id {id}")]
    DuplicateElementId {
        /// The id.
        id: u64,
    },
    /// A NaN or infinite coordinate.
    #[error("node {node} has a non-finite coordinate")]
    NonFiniteCoordinate {
        /// Node id.
        node: u64,
    },
    /// An element refers to a node that does not exist.
    #[error("element {element} refers to missing node {node}")]
    MissingNode {
        /// Element id.
        element: u64,
        /// The missing node id.
        node: u64,
    },
    /// An element lists a node twice.
    #[error("element {element} lists node {node} more than once")]
    RepeatedNode {
        /// Element id.
        element: u64,
        /// The repeated node id.
        node: u64,
    },
    /// An element has the wrong number of nodes for its kind.
    #[error("element {element} ({kind}) needs {expected} nodes, got {got}")]
    WrongNodeCount {
        /// Element id.
        element: u64,
        /// Its kind.
        kind: ElementKind,
        /// Nodes required.
        expected: usize,
        /// Nodes given.
        got: usize,
    },
    /// A negative Jacobian determinant: the element is inverted (wrong node order or tangled).
    #[error(
        "element {element} is inverted: det J = {det_j:e} at reference point ({:.4}, {:.4}, {:.4}) (check its node order)",
        point[0], point[1], point[2]
    )]
    InvertedElement {
        /// Element id.
        element: u64,
        /// The determinant found.
        det_j: f64,
        /// Where, in reference coordinates.
        point: [f64; 3],
    },
    /// A (near-)zero Jacobian determinant: the element is flat or collapsed.
    #[error("element {element} is degenerate: min det J = {det_j:e}")]
    DegenerateElement {
        /// Element id.
        element: u64,
        /// The smallest determinant.
        det_j: f64,
    },
    /// A node id not in the mesh.
    #[error("unknown node {node}")]
    UnknownNode {
        /// Node id.
        node: u64,
    },
    /// An element id not in the mesh.
    #[error("unknown element {element}")]
    UnknownElement {
        /// Element id.
        element: u64,
    },
    /// A node set name not in the mesh.
    #[error("unknown node set {name:?}")]
    UnknownNodeSet {
        /// Set name.
        name: String,
    },
    /// An element set name not in the mesh.
    #[error("unknown element set {name:?}")]
    UnknownElementSet {
        /// Set name.
        name: String,
    },
    /// An unphysical material.
    #[error("material {name:?}: {reason}")]
    InvalidMaterial {
        /// Material name.
        name: String,
        /// What is wrong.
        reason: String,
    },
    /// A formulation the element's kind does not have (incompatible modes are for 8-node bricks).
    #[error("element {element} is a {kind}: {reason}")]
    InvalidFormulation {
        /// Element id.
        element: u64,
        /// Its kind (Abaqus name).
        kind: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// An element without a material.
    #[error("element {element} has no material (assign one to its element set)")]
    NoMaterial {
        /// Element id.
        element: u64,
    },
    /// A DOF component outside 0..3.
    #[error("node {node}: DOF component {component} is not 0, 1 or 2")]
    InvalidComponent {
        /// Node id.
        node: u64,
        /// The component given.
        component: usize,
    },
    /// Every DOF is fixed, or the mesh is empty.
    #[error("the model has no free degree of freedom")]
    NoFreeDofs,
    /// A vector of the wrong length.
    #[error("{what}: expected length {expected}, got {got}")]
    LengthMismatch {
        /// Which vector.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Given length.
        got: usize,
    },
    /// Invalid arguments to a mesh generator.
    #[error("mesh generator: {reason}")]
    InvalidGenerator {
        /// What is wrong.
        reason: String,
    },
    /// A parameter group refers to nothing or is malformed.
    #[error("parameter group {name:?}: {reason}")]
    InvalidGroup {
        /// Group name.
        name: String,
        /// What is wrong.
        reason: String,
    },
    /// A structural element (beam, rod, spring, bushing) with invalid values or geometry.
    #[error("element {element}: {reason}")]
    InvalidStructural {
        /// The element's id.
        element: u64,
        /// What is wrong.
        reason: String,
    },
    /// A multipoint constraint that cannot be applied: a DOF made dependent twice or also fixed, a
    /// cycle of dependencies, a term on a missing DOF (`label` names the card or keyword, its id
    /// and where it was read).
    #[error("constraint {label}: {reason}")]
    Constraint {
        /// The constraint: card or keyword, id, file and line.
        label: String,
        /// What is wrong.
        reason: String,
    },
    /// A test wireframe that cannot be aligned onto the model.
    #[error("alignment: {reason}")]
    Alignment {
        /// What is wrong.
        reason: String,
    },
}
