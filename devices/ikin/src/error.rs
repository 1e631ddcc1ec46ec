//! Error type shared by every module of the crate.

use thiserror::Error;

/// Everything that can go wrong when building or evaluating a chain.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum KinError {
    /// A limb type string (e.g. `"left_v9"`) that iKin does not know.
    #[error("unknown {limb} type {given:?}; known types: {}", known.join(", "))]
    UnknownType {
        /// The iKin class name, e.g. `iCubArm`.
        limb: &'static str,
        /// The string that was given.
        given: String,
        /// Every type string accepted for this limb.
        known: Vec<String>,
    },
    /// A joint vector whose length is not the chain's number of DOF.
    #[error("expected {expected} joint values, got {got}")]
    DimensionMismatch {
        /// Number of released links (DOF).
        expected: usize,
        /// Length that was given.
        got: usize,
    },
    /// A link index past the end of the chain.
    #[error("link index {index} out of range (chain has {n} links)")]
    LinkIndex {
        /// The index given.
        index: usize,
        /// Number of links in the chain.
        n: usize,
    },
    /// `set_blocking_value` on a link that is not blocked.
    #[error("link {0} is not blocked")]
    NotBlocked(usize),
    /// An operation that needs at least one released link.
    #[error("the chain has no released links (DOF = 0)")]
    NoDof,
    /// NaN or infinite input.
    #[error("non-finite value in {0}")]
    NonFinite(&'static str),
    /// Joint bounds with `min > max`.
    #[error("invalid joint bounds: min {min} > max {max}")]
    InvalidBounds {
        /// Lower bound \[rad\].
        min: f64,
        /// Upper bound \[rad\].
        max: f64,
    },
    /// A malformed iKin links description (`numLinks`, `link_<i>`, …).
    #[error("invalid links properties: {0}")]
    Properties(String),
    /// Invalid solver settings.
    #[error("invalid IK configuration: {0}")]
    InvalidConfig(&'static str),
}

/// Result alias of the crate.
pub type Result<T> = std::result::Result<T, KinError>;
