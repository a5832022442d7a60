//! Errors the engine returns for bad input. The engine never panics on user data.

use thiserror::Error;

/// What went wrong when building or driving a ChainMail body.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ChainMailError {
    /// A lattice dimension is zero.
    #[error("a lattice needs at least one element along each axis, got {dims:?}")]
    EmptyGrid {
        /// The dimensions given.
        dims: [usize; 3],
    },
    /// More elements than the engine accepts.
    #[error("{count} elements is more than the limit of {limit} (about {limit_mib} MiB of state)")]
    TooManyElements {
        /// Elements asked for.
        count: u128,
        /// The limit.
        limit: usize,
        /// The limit's memory in MiB.
        limit_mib: usize,
    },
    /// Coordinates along an axis do not match the dimension or are not strictly increasing.
    #[error("coordinates along axis {axis}: {reason}")]
    BadCoordinates {
        /// Axis index 0, 1 or 2.
        axis: usize,
        /// What is wrong.
        reason: String,
    },
    /// A number that must be finite is NaN or infinite.
    #[error("{what} must be a finite number, got {value}")]
    NotFinite {
        /// Which value.
        what: &'static str,
        /// The value.
        value: f32,
    },
    /// Material limits that cannot hold.
    #[error("invalid material: {0}")]
    BadMaterial(String),
    /// An element id past the end.
    #[error("element {id} is out of range (the body has {count} elements)")]
    ElementOutOfRange {
        /// The id given.
        id: u32,
        /// How many elements there are.
        count: usize,
    },
    /// A link id past the end.
    #[error("link {id} is out of range (the body has {count} links)")]
    LinkOutOfRange {
        /// The id given.
        id: u32,
        /// How many links there are.
        count: usize,
    },
    /// A material id past the end.
    #[error("material {id} is out of range (the body has {count} materials)")]
    MaterialOutOfRange {
        /// The id given.
        id: u16,
        /// How many materials there are.
        count: usize,
    },
    /// A link that joins an element to itself or has zero rest length.
    #[error("link {index} is degenerate: {reason}")]
    DegenerateLink {
        /// Index of the link in the list given.
        index: usize,
        /// What is wrong.
        reason: &'static str,
    },
    /// Too many materials.
    #[error("a body holds at most {0} materials")]
    TooManyMaterials(usize),
}

/// Checks that a value is finite.
pub(crate) fn finite(what: &'static str, value: f32) -> Result<f32, ChainMailError> {
    if value.is_finite() { Ok(value) } else { Err(ChainMailError::NotFinite { what, value }) }
}
