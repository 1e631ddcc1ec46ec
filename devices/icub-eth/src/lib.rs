//! The embObj protocol of the Ethernet boards of iCub and ergoCub (EMS4, MC4plus, MC2plus,
//! AMC, ...), without I/O: what icub-firmware-shared (`eth/embobj`) defines and
//! icub-main's `embObjLib` speaks over UDP port 12345.
//!
//! | module | what |
//! |--------|------|
//! | [`frame`] | ropframes: header (start code, sizes, age, sequence number), footer; [`frame::decode_datagram`] (fuzz entry point) |
//! | [`rop`] | ROPs: ctrl byte, ropcode, id32, data, signature, time |
//! | [`id`] | [`Id32`] and the layout (offset, size) of every variable of every entity |
//! | [`entities`] | typed variables with their C layout (management, motion control, analog sensors, skin) |
//! | [`nvstore`] | the variables of one board as both sides store them |
//! | [`host`] | [`host::HostTransceiver`]: what `embObj*` devices use (asks with signatures and timeouts, sets, commands, regulars, presence, sequence checks) and [`host::Startup`], the board bring-up sequence of `EthResource` |
//! | [`board`] | [`board::BoardEngine`]: a board as the emulator runs it (management, services, regulars at the configured rate, MC/AS/SK variables) |
//! | [`plant`] | the pluggable joint model ([`plant::JointModel`]) the board engine drives |
//! | [`retry`] | [`Retry`]: icub-main's retry policies (attempts, timeout, settle), named where used |
//! | [`addressmap`] | [`AddressMap`]: the robot's board addresses served elsewhere (`YARP_ICUB_ETH_ADDRESS_MAP`), as host and emulator both apply it |
//!
//! See the crate's README.md for the wire layouts, the start-up sequence and its timeouts.
#![forbid(unsafe_code)]

pub mod addressmap;
pub mod board;
pub mod entities;
pub mod frame;
pub mod host;
pub mod id;
pub mod nvstore;
pub mod plant;
pub mod retry;
pub mod rop;
pub mod wire;

pub use addressmap::{AddressMap, ADDRESS_MAP_ENV};
pub use frame::{decode_datagram, Frame, FrameBuilder, FrameError, FrameHeader};
pub use id::Id32;
pub use nvstore::{NvError, NvStore};
pub use retry::Retry;
pub use rop::{ConfInfo, Rop, RopCode, RopCtrl, RopError};
pub use wire::Entity;
