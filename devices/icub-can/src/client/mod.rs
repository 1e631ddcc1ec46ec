//! Driver cores: the host side of the iCub boards, in joint units, ready to be wrapped
//! as YARP devices (`canmotioncontrol`, `canBusAnalogSensor`/`canBusFtSensor`,
//! `canBusSkin`, `canBusInertialMTB`).
//!
//! Every client owns one bus endpoint and a reader thread that decodes frames, keeps the
//! latest broadcasts and matches polling replies. The API is synchronous: methods block
//! at most for the configured reply timeout and return [`ClientError`] — a board that
//! does not answer is [`ClientError::BoardTimeout`], broadcasts older than the
//! broadcast timeout are [`ClientError::Stale`]. Clients are `Send + Sync`; share them
//! with `Arc`. Dropping a client stops its thread (and stops sensor streaming).
//! Give each client its own endpoint (open the bus once per client): a client sets the
//! endpoint's acceptance filter to its boards' identifiers, like `sharedcan` users do.
//!
//! ```no_run
//! use icub_can::bus::config::open_from_params;
//! use icub_can::client::{McParams, MotorControlClient};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let bus = open_from_params(&|k| (k == "canBackend").then(|| "udp://127.0.0.1:20001".to_string()))?;
//! let params = McParams::uniform(&[1, 2, 3, 4], 8, 11.375);
//! let mc = MotorControlClient::open(bus, params)?;
//! mc.set_control_mode(0, icub_can::proto::ControlMode::Position)?;
//! mc.set_ref_speed(0, 20.0)?;
//! mc.position_move(0, 30.0)?;
//! println!("shoulder at {:.1} deg", mc.encoder(0)?);
//! # Ok(()) }
//! ```

mod link;
pub mod mc;
pub mod sensors;
pub mod strain;

pub use mc::{BoardHealth, JointPid, JointStatus, McParams, MotorControlClient};
pub use sensors::{InertialClient, SkinClient};
pub use strain::{SensorStatus, StrainClient, StrainParams};

use std::time::Duration;

use crate::bus::BusError;

/// Errors of the driver cores.
#[derive(Debug, thiserror::Error)]
pub enum ClientError {
    #[error(transparent)]
    Bus(#[from] BusError),
    #[error("configuration: {0}")]
    Config(String),
    #[error("joint {joint} out of range (0..{joints})")]
    BadJoint { joint: usize, joints: usize },
    #[error("board {board} did not answer {what} within {timeout:?}")]
    BoardTimeout {
        board: u8,
        what: String,
        timeout: Duration,
    },
    #[error("boards {boards:?} do not answer")]
    BoardsSilent { boards: Vec<u8> },
    #[error(
        "no broadcast from board {board} for joint {joint} ({}, timeout {timeout:?})",
        last_heard(.age)
    )]
    Stale {
        joint: usize,
        board: u8,
        age: Option<Duration>,
        timeout: Duration,
    },
    #[error("value {value} out of the board's range for {what}")]
    Range { what: &'static str, value: f64 },
}

/// "last heard 504 ms ago" / "never heard", for [`ClientError::Stale`].
fn last_heard(age: &Option<Duration>) -> String {
    match age {
        Some(a) => format!("last heard {} ms ago", a.as_millis()),
        None => "never heard".to_string(),
    }
}

#[cfg(test)]
mod tests;
