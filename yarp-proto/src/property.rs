//! Property / Searchable configuration (placeholder, being written).

/// A YARP Property: key -> value groups.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Property {}
