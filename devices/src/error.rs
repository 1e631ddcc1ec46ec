//! Errors of the device layer.

use crate::kind::Kind;
use thiserror::Error;

/// What can go wrong when opening a device or calling one of its interfaces.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum DeviceError {
    #[error("no `device` parameter given")]
    NoDeviceName,
    #[error("unknown device `{name}`{}", suggest(.closest, .kind))]
    UnknownDevice {
        name: String,
        /// Known names to suggest, best first.
        closest: Vec<String>,
        /// The kind of device the name asks for, when it says (`fake_motor`: a motor).
        kind: Option<Kind>,
    },
    #[error("device `{device}`: missing required parameter `{param}`")]
    MissingParam { device: String, param: String },
    #[error("device `{device}`: parameter `{param}` should be {expected}, got `{got}`")]
    BadParam {
        device: String,
        param: String,
        expected: &'static str,
        got: String,
    },
    #[error("joint {joint} out of range (the device has {axes} axes)")]
    InvalidJoint { joint: i64, axes: usize },
    #[error("expected {expected} values, got {got}")]
    WrongSize { expected: usize, got: usize },
    #[error("operation not supported: {0}")]
    Unsupported(&'static str),
    /// The device behind a wrapper lacks the interface a call needs (C++ 4.0's wrappers
    /// answer these "not ready").
    #[error("the device offers no {0}")]
    NoInterface(&'static str),
    #[error("device is not open")]
    NotOpen,
    /// The device works but has nothing to give yet (no image or measurement received
    /// from its server so far, a stream that timed out): C++'s `NOT_READY`.
    #[error("not ready: {0}")]
    NotReady(&'static str),
    /// A run-time fault of the hardware or of a remote peer: a silent CAN board, a bus-off,
    /// a remote device that does not answer. `device` names the device or the remote port.
    #[error("device `{device}`: {reason}")]
    Failed { device: String, reason: String },
    /// A remote peer understood the command and refused it (`[fail]`, or a reply without
    /// what was asked): the peer is alive, the command is what failed.
    #[error("`{device}` refused `{command}`")]
    Refused { device: String, command: String },
    /// A remote peer gave no reply within `after`: it may be stalled or gone.
    #[error("`{device}` did not answer `{command}` within {after:?}")]
    Timeout {
        device: String,
        command: String,
        after: std::time::Duration,
    },
    /// The connection to a remote peer broke while a command waited for its reply.
    #[error("`{device}`: connection lost ({reason})")]
    PeerLost { device: String, reason: String },
    /// A method C++ YARP 4.0.0's wrapper declares but leaves unserved: it answers with the
    /// return value never set (`[miss]`), and so do we.
    #[error("{0}: not served by C++ YARP 4.0.0's wrapper either")]
    UnservedByCpp(&'static str),
}

impl DeviceError {
    /// Whether the error says a remote peer is unreachable, as opposed to a command
    /// refused or not offered: a caller may reconnect on these.
    pub fn is_lost_peer(&self) -> bool {
        matches!(
            self,
            DeviceError::Timeout { .. } | DeviceError::PeerLost { .. }
        )
    }

    /// A [`DeviceError::Failed`] of `device`.
    pub fn failed(device: impl Into<String>, reason: impl ToString) -> DeviceError {
        DeviceError::Failed {
            device: device.into(),
            reason: reason.to_string(),
        }
    }
}

fn suggest(closest: &[String], kind: &Option<Kind>) -> String {
    let mut s = String::new();
    if !closest.is_empty() {
        s = format!("; closest known devices: {}", closest.join(", "));
    }
    if let Some(k) = kind {
        s.push_str(&format!(" (a {} was asked for)", k.label()));
    }
    s + "; `yarpdev --list` lists every device with its kind and interfaces"
}

pub type DevResult<T> = Result<T, DeviceError>;
