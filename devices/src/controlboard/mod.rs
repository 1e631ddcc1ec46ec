//! The control-board network wrapper `controlBoard_nws_yarp`, wire-compatible with C++
//! YARP 3.12: the RPC protocol (`rpc`), streaming commands (`streaming`), the published
//! state (`state`) and the ports and tasks that serve them (`nws`); and YARP 2's
//! single-port mode of YARP's design paper (`single_port`).

pub mod methods;
mod nws;
mod rpc;
mod single_port;
mod state;
pub mod streaming;
pub mod v3;
pub mod v4;

pub use nws::{port_prefix, ControlBoardNws, ControlBoardNwsDevice, DEFAULT_PERIOD};
pub use rpc::{handle_rpc, RpcStamp, PROTOCOL_VERSION_NUMBER};
pub use single_port::{handle_single_port, help_reply, usage};
pub use state::{
    envelope_time, positions_bottle, positions_from_bottle, Channel, JointData, StateError,
};
pub use streaming::{handle_command, CommandError, CommandMessage};

/// Drivers of this family, by C++ name.
pub(crate) const DRIVERS: &[(&str, crate::driver::Factory)] =
    &[(nws::NAME, || Box::new(ControlBoardNwsDevice::new()))];
