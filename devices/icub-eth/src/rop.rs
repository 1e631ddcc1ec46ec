//! ROPs (remote operations), as `EOrop` / `EOtheParser` / `EOtheFormer` of
//! icub-firmware-shared `eth/embobj/plus/comm-v2/transport` put them on the wire:
//!
//! ```text
//! offset size field
//!      0    1 ctrl   (eOropctrl_t) bit 0-1 confinfo, 2 plustime, 3 plussign,
//!                    4 rqsttime, 5 rqstconf, 6-7 version (must be 0)
//!      1    1 ropc   (eOropcodevalues_t) 1 ask, 2 say, 3 set, 4 sig, 5 rst
//!      2    2 dsiz   size of the data, u16 little endian
//!      4    4 id32   endpoint<<24 | entity<<16 | index<<8 | tag, u32 little endian
//!      8   4n data   dsiz bytes padded with zeros to a multiple of 4; present only when
//!                    confinfo is none and ropc is set, say or sig (then dsiz must be > 0)
//!    ...    4 signature, if plussign
//!    ...    8 time (µs), if plustime
//! ```

use crate::id::Id32;
use thiserror::Error;

/// Size of the ROP head (`eOrophead_t`).
pub const ROP_HEAD_SIZE: usize = 8;
/// The signature the C host uses for "no signature" (`eo_rop_SIGNATUREdummy`).
pub const SIGNATURE_DUMMY: u32 = 0xffff_ffff;

/// `eOropcodevalues_t`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum RopCode {
    /// Read a variable: the owner replies with `say`.
    Ask = 1,
    /// The reply to an `ask`, with the value.
    Say = 2,
    /// Write a variable.
    Set = 3,
    /// A value the owner signals spontaneously (regulars, command results).
    Sig = 4,
    /// Reset a variable to its default.
    Rst = 5,
}

impl RopCode {
    pub fn from_u8(v: u8) -> Option<Self> {
        Some(match v {
            1 => Self::Ask,
            2 => Self::Say,
            3 => Self::Set,
            4 => Self::Sig,
            5 => Self::Rst,
            _ => return None,
        })
    }
    /// `eo_rop_ropcode_has_data()`: set, say and sig carry a value.
    pub fn has_data(self) -> bool {
        matches!(self, Self::Set | Self::Say | Self::Sig)
    }
}

/// `eOropconfinfo_t`: whether the ROP is itself a confirmation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[repr(u8)]
pub enum ConfInfo {
    #[default]
    None = 0,
    Nak = 1,
    Ack = 2,
}

/// `eOropctrl_t`, the first byte of a ROP (version 0 only).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct RopCtrl {
    pub confinfo: ConfInfo,
    /// The ROP carries the 8-byte time field.
    pub plustime: bool,
    /// The ROP carries the 4-byte signature field.
    pub plussign: bool,
    /// The reply shall carry the time field.
    pub rqsttime: bool,
    /// The receiver shall confirm with ack/nak.
    pub rqstconf: bool,
}

impl RopCtrl {
    pub fn to_byte(self) -> u8 {
        (self.confinfo as u8)
            | u8::from(self.plustime) << 2
            | u8::from(self.plussign) << 3
            | u8::from(self.rqsttime) << 4
            | u8::from(self.rqstconf) << 5
    }

    pub fn from_byte(b: u8) -> Result<Self, RopError> {
        let version = b >> 6;
        if version != 0 {
            return Err(RopError::Version(version));
        }
        let confinfo = match b & 3 {
            0 => ConfInfo::None,
            1 => ConfInfo::Nak,
            2 => ConfInfo::Ack,
            _ => return Err(RopError::ConfInfo(3)),
        };
        Ok(Self {
            confinfo,
            plustime: b & 0x04 != 0,
            plussign: b & 0x08 != 0,
            rqsttime: b & 0x10 != 0,
            rqstconf: b & 0x20 != 0,
        })
    }
}

/// Why a ROP could not be decoded or encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
pub enum RopError {
    #[error("ROP truncated: needs {needed} bytes, {available} available")]
    Truncated { needed: usize, available: usize },
    #[error("ROP version {0} (only 0 exists)")]
    Version(u8),
    #[error("invalid ropcode {0}")]
    RopCode(u8),
    #[error("invalid confinfo {0}")]
    ConfInfo(u8),
    #[error("{0:?} ROP without data (dsiz 0)")]
    MissingData(RopCode),
    #[error("ROP data of {0} bytes does not fit the 16-bit size field")]
    DataTooLong(usize),
}

/// One remote operation.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Rop {
    pub ctrl: RopCtrl,
    pub code: RopCode,
    pub id32: Id32,
    /// The value (unpadded, `dsiz` bytes); empty for ask/rst and confirmations.
    pub data: Vec<u8>,
    /// Present exactly when `ctrl.plussign`.
    pub signature: Option<u32>,
    /// Present exactly when `ctrl.plustime`.
    pub time: Option<u64>,
}

/// Rounds a data size up to the 4-byte multiple it occupies (`eo_rop_datafield_effective_size`).
pub fn padded(size: usize) -> usize {
    (size + 3) & !3
}

impl Rop {
    fn new(code: RopCode, id32: Id32, data: Vec<u8>) -> Self {
        Self {
            ctrl: RopCtrl::default(),
            code,
            id32,
            data,
            signature: None,
            time: None,
        }
    }
    pub fn ask(id32: Id32) -> Self {
        Self::new(RopCode::Ask, id32, Vec::new())
    }
    pub fn say(id32: Id32, data: Vec<u8>) -> Self {
        Self::new(RopCode::Say, id32, data)
    }
    pub fn set(id32: Id32, data: Vec<u8>) -> Self {
        Self::new(RopCode::Set, id32, data)
    }
    pub fn sig(id32: Id32, data: Vec<u8>) -> Self {
        Self::new(RopCode::Sig, id32, data)
    }
    /// Adds the signature field (`plussign`).
    pub fn with_signature(mut self, s: u32) -> Self {
        self.ctrl.plussign = true;
        self.signature = Some(s);
        self
    }
    /// Adds the time field (`plustime`).
    pub fn with_time(mut self, t: u64) -> Self {
        self.ctrl.plustime = true;
        self.time = Some(t);
        self
    }

    /// `eo_rop_datafield_is_required()`: a value travels only in non-confirmation
    /// set/say/sig ROPs.
    pub fn carries_data(&self) -> bool {
        self.ctrl.confinfo == ConfInfo::None && self.code.has_data()
    }

    /// Bytes this ROP takes in a ropframe.
    pub fn wire_size(&self) -> usize {
        let data = if self.carries_data() {
            padded(self.data.len())
        } else {
            0
        };
        ROP_HEAD_SIZE
            + data
            + 4 * usize::from(self.ctrl.plussign)
            + 8 * usize::from(self.ctrl.plustime)
    }

    /// Appends the ROP to `out` (what `eo_former_GetStream` writes).
    pub fn encode_into(&self, out: &mut Vec<u8>) -> Result<(), RopError> {
        let carries = self.carries_data();
        if carries && self.data.is_empty() {
            return Err(RopError::MissingData(self.code));
        }
        let dsiz = if carries { self.data.len() } else { 0 };
        let dsiz16 = u16::try_from(dsiz).map_err(|_| RopError::DataTooLong(dsiz))?;
        out.push(self.ctrl.to_byte());
        out.push(self.code as u8);
        out.extend_from_slice(&dsiz16.to_le_bytes());
        out.extend_from_slice(&self.id32.0.to_le_bytes());
        if carries {
            out.extend_from_slice(&self.data);
            out.resize(out.len() + padded(dsiz) - dsiz, 0);
        }
        if self.ctrl.plussign {
            out.extend_from_slice(&self.signature.unwrap_or(SIGNATURE_DUMMY).to_le_bytes());
        }
        if self.ctrl.plustime {
            out.extend_from_slice(&self.time.unwrap_or(u64::MAX).to_le_bytes());
        }
        Ok(())
    }

    pub fn encode(&self) -> Result<Vec<u8>, RopError> {
        let mut v = Vec::with_capacity(self.wire_size());
        self.encode_into(&mut v)?;
        Ok(v)
    }

    /// Decodes one ROP from the start of `stream` (as `eo_parser_GetROP`) and returns it
    /// with the number of bytes it took.
    pub fn decode(stream: &[u8]) -> Result<(Rop, usize), RopError> {
        RopRef::decode(stream).map(|(r, n)| (r.to_rop(), n))
    }
}

/// A decoded ROP borrowing its data from the datagram (no allocation: what the state
/// machines use on the 1 kHz streams).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RopRef<'a> {
    pub ctrl: RopCtrl,
    pub code: RopCode,
    pub id32: Id32,
    pub data: &'a [u8],
    pub signature: Option<u32>,
    pub time: Option<u64>,
}

impl<'a> RopRef<'a> {
    /// See [`Rop::carries_data`].
    pub fn carries_data(&self) -> bool {
        self.ctrl.confinfo == ConfInfo::None && self.code.has_data()
    }

    pub fn to_rop(&self) -> Rop {
        Rop {
            ctrl: self.ctrl,
            code: self.code,
            id32: self.id32,
            data: self.data.to_vec(),
            signature: self.signature,
            time: self.time,
        }
    }

    /// See [`Rop::decode`].
    pub fn decode(stream: &'a [u8]) -> Result<(RopRef<'a>, usize), RopError> {
        let head = stream.get(..ROP_HEAD_SIZE).ok_or(RopError::Truncated {
            needed: ROP_HEAD_SIZE,
            available: stream.len(),
        })?;
        let ctrl = RopCtrl::from_byte(head[0])?;
        let code = RopCode::from_u8(head[1]).ok_or(RopError::RopCode(head[1]))?;
        let dsiz = usize::from(u16::from_le_bytes([head[2], head[3]]));
        let id32 = Id32(u32::from_le_bytes([head[4], head[5], head[6], head[7]]));
        let carries = ctrl.confinfo == ConfInfo::None && code.has_data();
        if carries && dsiz == 0 {
            return Err(RopError::MissingData(code));
        }
        let data_len = if carries { padded(dsiz) } else { 0 };
        let total = ROP_HEAD_SIZE
            + data_len
            + 4 * usize::from(ctrl.plussign)
            + 8 * usize::from(ctrl.plustime);
        if stream.len() < total {
            return Err(RopError::Truncated {
                needed: total,
                available: stream.len(),
            });
        }
        let mut at = ROP_HEAD_SIZE;
        let data = if carries {
            &stream[at..at + dsiz]
        } else {
            &[][..]
        };
        at += data_len;
        let signature = ctrl.plussign.then(|| {
            let s =
                u32::from_le_bytes([stream[at], stream[at + 1], stream[at + 2], stream[at + 3]]);
            at += 4;
            s
        });
        let time = ctrl.plustime.then(|| {
            let mut t = [0u8; 8];
            t.copy_from_slice(&stream[at..at + 8]);
            u64::from_le_bytes(t)
        });
        Ok((
            RopRef {
                ctrl,
                code,
                id32,
                data,
                signature,
                time,
            },
            total,
        ))
    }
}
