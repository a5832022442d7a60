//! Errors the FEM reference model returns for bad input. It never panics on user data.

use thiserror::Error;

/// What went wrong when building or driving the linear FEM model.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum FemError {
    /// A grid dimension is too small to hold a tetrahedron.
    #[error("a tetrahedral block needs at least 2 nodes along each axis, got {dims:?}")]
    EmptyGrid {
        /// The dimensions given.
        dims: [usize; 3],
    },
    /// More nodes than the model accepts, or a dense matrix larger than the memory limit.
    #[error("{what} needs {needed_mib:.1} MiB, more than the limit of {limit_mib:.1} MiB")]
    TooBig {
        /// What would be too big, with its size (e.g. "the condensed inverse (3288 × 3288 f64)").
        what: String,
        /// Memory it would take, MiB.
        needed_mib: f64,
        /// The limit, MiB.
        limit_mib: f64,
    },
    /// A number that must be finite is NaN or infinite.
    #[error("{what} must be a finite number, got {value}")]
    NotFinite {
        /// Which value.
        what: &'static str,
        /// The value.
        value: f64,
    },
    /// Material parameters outside their physical range.
    #[error("invalid material: {0}")]
    BadMaterial(String),
    /// Other parameters outside their range.
    #[error("invalid parameter: {0}")]
    BadParameter(String),
    /// A node id past the end.
    #[error("node {id} is out of range (the mesh has {count} nodes)")]
    NodeOutOfRange {
        /// The id given.
        id: u32,
        /// How many nodes there are.
        count: usize,
    },
    /// A node that is not a free surface node was used where one is needed.
    #[error("node {id} is not a free surface node: {reason}")]
    NotSurfaceNode {
        /// The id given.
        id: u32,
        /// Why (interior, or fully fixed).
        reason: &'static str,
    },
    /// The same node was imposed twice in one call.
    #[error("node {id} is imposed twice")]
    DuplicateNode {
        /// The id given.
        id: u32,
    },
    /// A tetrahedron with (near) zero volume.
    #[error("tetrahedron {index} is degenerate (volume {volume:e} m³)")]
    DegenerateElement {
        /// Index of the tetrahedron.
        index: usize,
        /// Its volume.
        volume: f64,
    },
    /// The stiffness matrix is not positive definite: the supports do not stop every rigid motion.
    #[error(
        "the {which} stiffness matrix is not positive definite ({detail}); the supports must stop every rigid motion"
    )]
    Singular {
        /// Which matrix (interior, condensed, full, dynamic).
        which: &'static str,
        /// What the factorisation reported.
        detail: String,
    },
    /// The model has no free surface node to condense onto.
    #[error("the model has no free surface node: nothing to condense onto")]
    NoSurface,
    /// Cutting is refused: condensation and the explicit inverse assume a fixed topology.
    #[error(
        "cutting is not supported by the condensed FEM model: condensation onto the surface nodes and the explicit \
         inverse computed at load time assume a fixed mesh topology; a cut would change the stiffness matrix and \
         need the whole precomputation redone"
    )]
    CutUnsupported,
    /// A slice of the wrong length was passed.
    #[error("{what} has length {got}, expected {expected}")]
    WrongLength {
        /// Which argument.
        what: &'static str,
        /// Its length.
        got: usize,
        /// The length expected.
        expected: usize,
    },
    /// The linear-algebra backend failed (allocation, index overflow).
    #[error("linear algebra backend: {0}")]
    Backend(String),
}

/// Checks that a value is finite.
pub(crate) fn finite(what: &'static str, value: f64) -> Result<f64, FemError> {
    if value.is_finite() { Ok(value) } else { Err(FemError::NotFinite { what, value }) }
}
