//! The iCub CAN protocol as a pure codec (no I/O).
//!
//! Every iCub message uses an 11-bit identifier split as `class(3) | source(4) | low(4)`
//! (`iCubCanProto_classes.h`):
//!
//! | class | name | `low` nibble | first data byte |
//! |-------|------|--------------|-----------------|
//! | 0 | polling motor control | destination | `axis << 7 \| opcode` |
//! | 1 | periodic motor control | message type | — |
//! | 2 | polling analog sensor (strain, MAIS, skin/MTB setup) | destination | opcode |
//! | 3 | periodic analog sensor (F/T, hall effect) | message type | — |
//! | 4 | periodic skin (triangle data) | triangle | head/tail flag |
//! | 5 | periodic inertial (MTB gyro/accelerometer) | message type | — |
//!
//! The host PC uses address 0 (`CanMyAddress`), boards use 1..=14, 15 is broadcast.
//! A polling frame addressed *to* the host is a reply, otherwise it is a request.
//! Multi-byte fields are little-endian, except the strain full scale and calibration
//! matrix entries, which the boards send big-endian. Units are the boards' raw units
//! (encoder ticks, PWM counts, sensor counts); conversion lives in [`crate::client`].

pub mod analog;
pub mod mc;
pub mod sensors;

pub use analog::{AsCommand, AsPeriodic, AsReply, TareOp, VectorKind};
pub use mc::{BoardStatus, ControlMode, McCommand, McPeriodic, McReply, Pid, PidKind, PidLimits};
pub use sensors::{InertialMsg, SkinFrame};

use crate::bus::cannelloni::{self, CannelloniError};
use crate::frame::CanFrame;

/// Address of the host (the PC104 / driver side).
pub const HOST_ADDRESS: u8 = 0;

/// Message classes (bits 8..10 of the identifier).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum MsgClass {
    PollingMotorControl = 0,
    PeriodicMotorControl = 1,
    PollingAnalogSensor = 2,
    PeriodicAnalogSensor = 3,
    PeriodicSkin = 4,
    PeriodicInertial = 5,
    Bootloader = 7,
}

impl MsgClass {
    /// The class of a 3-bit value (6 is unassigned).
    pub fn from_bits(v: u8) -> Option<Self> {
        Some(match v {
            0 => Self::PollingMotorControl,
            1 => Self::PeriodicMotorControl,
            2 => Self::PollingAnalogSensor,
            3 => Self::PeriodicAnalogSensor,
            4 => Self::PeriodicSkin,
            5 => Self::PeriodicInertial,
            7 => Self::Bootloader,
            _ => return None,
        })
    }
}

/// Builds an 11-bit identifier; addresses and the low nibble are masked to 4 bits.
pub fn make_id(class: MsgClass, src: u8, low: u8) -> u16 {
    (u16::from(class as u8) << 8) | (u16::from(src & 0xF) << 4) | u16::from(low & 0xF)
}

/// Splits an 11-bit identifier into (class bits, source, low nibble).
pub fn split_id(id: u16) -> (u8, u8, u8) {
    (
        ((id >> 8) & 0x7) as u8,
        ((id >> 4) & 0xF) as u8,
        (id & 0xF) as u8,
    )
}

/// Why a frame is not a valid iCub message.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ProtoError {
    #[error("iCub messages use 11-bit identifiers, got an extended frame")]
    Extended,
    #[error("iCub messages are data frames, got a remote or error frame")]
    NotData,
    #[error("message class {0} is not handled")]
    UnknownClass(u8),
    #[error("polling message without an opcode byte")]
    NoOpcode,
    #[error("unknown {class:?} opcode or type {code:#04x}")]
    Unknown { class: MsgClass, code: u8 },
    #[error("{what}: expected {expected} data bytes, got {got}")]
    Length {
        what: &'static str,
        expected: &'static str,
        got: usize,
    },
    #[error("{what}: invalid value {value:#x}")]
    Value { what: &'static str, value: u32 },
}

/// Checks a payload length against an exact value or a minimum.
pub(crate) fn need(
    what: &'static str,
    data: &[u8],
    min: usize,
    max: usize,
    expected: &'static str,
) -> Result<(), ProtoError> {
    if data.len() < min || data.len() > max {
        Err(ProtoError::Length {
            what,
            expected,
            got: data.len(),
        })
    } else {
        Ok(())
    }
}

pub(crate) fn i16_at(d: &[u8], i: usize) -> i16 {
    i16::from_le_bytes([d[i], d[i + 1]])
}
pub(crate) fn u16_at(d: &[u8], i: usize) -> u16 {
    u16::from_le_bytes([d[i], d[i + 1]])
}
pub(crate) fn i32_at(d: &[u8], i: usize) -> i32 {
    i32::from_le_bytes([d[i], d[i + 1], d[i + 2], d[i + 3]])
}

/// Up to 8 raw payload bytes (for messages whose content is opaque, e.g. board prints).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct Payload {
    len: u8,
    bytes: [u8; 8],
}

impl Payload {
    /// Copies at most 8 bytes (longer input is truncated).
    pub fn new(data: &[u8]) -> Self {
        let n = data.len().min(8);
        let mut bytes = [0; 8];
        bytes[..n].copy_from_slice(&data[..n]);
        Self {
            len: n as u8,
            bytes,
        }
    }
    pub fn as_slice(&self) -> &[u8] {
        &self.bytes[..usize::from(self.len)]
    }
}

impl std::fmt::Debug for Payload {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:02x?}", self.as_slice())
    }
}

/// Any iCub CAN message.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Message {
    /// Class 0 from the host to a motor board; `axis` is 0 or 1 (the joint on the board).
    McRequest {
        src: u8,
        dst: u8,
        axis: u8,
        cmd: McCommand,
    },
    /// Class 0 from a motor board back to the host.
    McReply {
        src: u8,
        dst: u8,
        axis: u8,
        reply: McReply,
    },
    /// Class 1 broadcast of motor board `board` (two joints per message).
    McPeriodic { board: u8, msg: McPeriodic },
    /// Class 2 from the host to a sensor board.
    AsRequest { src: u8, dst: u8, cmd: AsCommand },
    /// Class 2 from a sensor board back to the host.
    AsReply { src: u8, dst: u8, reply: AsReply },
    /// Class 3 broadcast of analog sensor `board`.
    AsPeriodic { board: u8, msg: AsPeriodic },
    /// Class 4 skin triangle data of MTB `board`.
    Skin { board: u8, msg: SkinFrame },
    /// Class 5 inertial data of MTB `board`.
    Inertial { board: u8, msg: InertialMsg },
}

impl Message {
    /// Decodes a frame, taking polling frames addressed to [`HOST_ADDRESS`] as replies.
    pub fn decode(frame: &CanFrame) -> Result<Self, ProtoError> {
        Self::decode_for(frame, HOST_ADDRESS)
    }

    /// Decodes a frame; polling frames addressed to `host` are replies.
    pub fn decode_for(frame: &CanFrame, host: u8) -> Result<Self, ProtoError> {
        let id = frame.std_id().ok_or(ProtoError::Extended)?;
        if frame.is_remote() || frame.is_error() {
            return Err(ProtoError::NotData);
        }
        let (class, src, low) = split_id(id);
        let class = MsgClass::from_bits(class).ok_or(ProtoError::UnknownClass(class))?;
        let d = frame.data();
        Ok(match class {
            MsgClass::PollingMotorControl => {
                let first = *d.first().ok_or(ProtoError::NoOpcode)?;
                let (axis, op) = (first >> 7, first & 0x7F);
                if low == host {
                    Self::McReply {
                        src,
                        dst: low,
                        axis,
                        reply: McReply::decode(op, d)?,
                    }
                } else {
                    Self::McRequest {
                        src,
                        dst: low,
                        axis,
                        cmd: McCommand::decode(op, d)?,
                    }
                }
            }
            MsgClass::PeriodicMotorControl => Self::McPeriodic {
                board: src,
                msg: McPeriodic::decode(low, d)?,
            },
            MsgClass::PollingAnalogSensor => {
                let op = *d.first().ok_or(ProtoError::NoOpcode)?;
                if low == host {
                    Self::AsReply {
                        src,
                        dst: low,
                        reply: AsReply::decode(op, d)?,
                    }
                } else {
                    Self::AsRequest {
                        src,
                        dst: low,
                        cmd: AsCommand::decode(op, d)?,
                    }
                }
            }
            MsgClass::PeriodicAnalogSensor => Self::AsPeriodic {
                board: src,
                msg: AsPeriodic::decode(low, d)?,
            },
            MsgClass::PeriodicSkin => Self::Skin {
                board: src,
                msg: SkinFrame::decode(low, d)?,
            },
            MsgClass::PeriodicInertial => Self::Inertial {
                board: src,
                msg: InertialMsg::decode(low, d)?,
            },
            MsgClass::Bootloader => return Err(ProtoError::UnknownClass(7)),
        })
    }

    /// Encodes to a frame (addresses are masked to 4 bits, `axis` to 1 bit).
    pub fn encode(&self) -> CanFrame {
        let mut buf = [0u8; 8];
        let (id, len) = match *self {
            Self::McRequest {
                src,
                dst,
                axis,
                cmd,
            } => {
                let n = cmd.encode(&mut buf);
                buf[0] |= (axis & 1) << 7;
                (make_id(MsgClass::PollingMotorControl, src, dst), n)
            }
            Self::McReply {
                src,
                dst,
                axis,
                reply,
            } => {
                let n = reply.encode(&mut buf);
                buf[0] |= (axis & 1) << 7;
                (make_id(MsgClass::PollingMotorControl, src, dst), n)
            }
            Self::McPeriodic { board, msg } => {
                let (kind, n) = msg.encode(&mut buf);
                (make_id(MsgClass::PeriodicMotorControl, board, kind), n)
            }
            Self::AsRequest { src, dst, cmd } => (
                make_id(MsgClass::PollingAnalogSensor, src, dst),
                cmd.encode(&mut buf),
            ),
            Self::AsReply { src, dst, reply } => (
                make_id(MsgClass::PollingAnalogSensor, src, dst),
                reply.encode(&mut buf),
            ),
            Self::AsPeriodic { board, msg } => {
                let (kind, n) = msg.encode(&mut buf);
                (make_id(MsgClass::PeriodicAnalogSensor, board, kind), n)
            }
            Self::Skin { board, msg } => {
                let n = msg.encode(&mut buf);
                (make_id(MsgClass::PeriodicSkin, board, msg.triangle), n)
            }
            Self::Inertial { board, msg } => {
                let (kind, n) = msg.encode(&mut buf);
                (make_id(MsgClass::PeriodicInertial, board, kind), n)
            }
        };
        CanFrame::new(id, &buf[..len])
            .expect("ids are 11-bit and payloads at most 8 bytes by construction")
    }
}

/// Errors of [`decode_any`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum DecodeAnyError {
    #[error("datagram: {0}")]
    Datagram(#[from] CannelloniError),
    #[error("frame {index} ({frame}): {source}")]
    Message {
        index: usize,
        frame: CanFrame,
        #[source]
        source: ProtoError,
    },
}

/// Decodes untrusted bytes end to end: a cannelloni datagram, then every frame as an
/// iCub message. This is the fuzzing entry point: it must never panic or hang.
pub fn decode_any(bytes: &[u8]) -> Result<Vec<Message>, DecodeAnyError> {
    let packet = cannelloni::decode(bytes)?;
    packet
        .frames
        .iter()
        .enumerate()
        .map(|(index, f)| {
            Message::decode(f).map_err(|source| DecodeAnyError::Message {
                index,
                frame: *f,
                source,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests;
