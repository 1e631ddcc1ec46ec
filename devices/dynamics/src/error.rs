//! Errors of model loading and of the computations' inputs.

use std::path::PathBuf;

/// What went wrong, naming the file, link, joint, frame or sensor.
#[derive(Debug, thiserror::Error)]
pub enum DynError {
    #[error("{path}: {reason}")]
    Urdf { path: PathBuf, reason: String },
    #[error("the model has no link or frame named '{0}'")]
    UnknownFrame(String),
    #[error("the model has no joint named '{0}'")]
    UnknownJoint(String),
    #[error("the model has no six-axis force/torque sensor named '{0}'")]
    UnknownSensor(String),
    #[error("joint '{joint}' is of type '{kind}', which the dynamics does not support")]
    UnsupportedJoint { joint: String, kind: String },
    #[error("the model's links do not form a tree: {0}")]
    NotATree(String),
    #[error("expected {expected} values for {what}, got {got}")]
    Size {
        what: &'static str,
        expected: usize,
        got: usize,
    },
    #[error("{0}")]
    Estimation(String),
}

pub type Result<T> = std::result::Result<T, DynError>;
