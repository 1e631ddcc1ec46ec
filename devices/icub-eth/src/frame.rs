//! Ropframes (`EOropframe`): the UDP payload exchanged with a board.
//!
//! ```text
//! offset size field (EOropframeHeader_t, 24 bytes)
//!      0    4 startofframe   0x12345678 (EOFRAME_START), u32 little endian
//!      4    2 ropssizeof     bytes of ROPs that follow the header
//!      6    2 ropsnumberof   number of ROPs
//!      8    8 ageofframe     sender's time of life at transmission, µs
//!     16    8 sequencenumber 1 for the first frame a transceiver sends, then +1
//!     24    n ROPs           ropssizeof bytes
//! 24 + n    4 endoframe      0x87654321 (EOFRAME_END)
//! ```
//! An empty ropframe is 28 bytes (`eo_ropframe_sizeforZEROrops`).

use crate::id::Id32;
use crate::rop::{padded, Rop, RopError, RopRef, ROP_HEAD_SIZE};
use thiserror::Error;

pub const FRAME_START: u32 = 0x1234_5678;
pub const FRAME_END: u32 = 0x8765_4321;
pub const HEADER_SIZE: usize = 24;
pub const FOOTER_SIZE: usize = 4;
/// Size of a ropframe without ROPs.
pub const EMPTY_FRAME_SIZE: usize = HEADER_SIZE + FOOTER_SIZE;

/// Why a datagram is not a valid ropframe.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
pub enum FrameError {
    #[error("ropframe of {0} bytes is shorter than the 28 of an empty one")]
    TooShort(usize),
    #[error("bad start code {0:#010x} (expected 0x12345678)")]
    StartCode(u32),
    #[error("ropssizeof {rops_size} does not fit a datagram of {len} bytes")]
    RopsSize { rops_size: usize, len: usize },
    #[error("bad end code {0:#010x} (expected 0x87654321)")]
    EndCode(u32),
    #[error("{0} bytes after the end code")]
    TrailingBytes(usize),
}

/// The header fields of a ropframe.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FrameHeader {
    pub rops_size: u16,
    pub rops_count: u16,
    /// `ageofframe`, µs.
    pub age: u64,
    pub sequence: u64,
}

/// A validated ropframe borrowing its datagram.
#[derive(Debug, Clone, Copy)]
pub struct Frame<'a> {
    pub header: FrameHeader,
    /// The `ropssizeof` bytes of ROPs.
    pub rops: &'a [u8],
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

fn u64_at(b: &[u8], at: usize) -> u64 {
    let mut a = [0u8; 8];
    a.copy_from_slice(&b[at..at + 8]);
    u64::from_le_bytes(a)
}

impl<'a> Frame<'a> {
    /// Validates start code, sizes and end code (as `eo_ropframe_IsValid`, and stricter:
    /// the datagram must end at the end code).
    pub fn decode(b: &'a [u8]) -> Result<Self, FrameError> {
        if b.len() < EMPTY_FRAME_SIZE {
            return Err(FrameError::TooShort(b.len()));
        }
        let start = u32_at(b, 0);
        if start != FRAME_START {
            return Err(FrameError::StartCode(start));
        }
        let rops_size = u16::from_le_bytes([b[4], b[5]]);
        let rops_count = u16::from_le_bytes([b[6], b[7]]);
        let end_at = HEADER_SIZE + usize::from(rops_size);
        if end_at + FOOTER_SIZE > b.len() {
            return Err(FrameError::RopsSize {
                rops_size: rops_size.into(),
                len: b.len(),
            });
        }
        let end = u32_at(b, end_at);
        if end != FRAME_END {
            return Err(FrameError::EndCode(end));
        }
        let trailing = b.len() - end_at - FOOTER_SIZE;
        if trailing != 0 {
            return Err(FrameError::TrailingBytes(trailing));
        }
        Ok(Self {
            header: FrameHeader {
                rops_size,
                rops_count,
                age: u64_at(b, 8),
                sequence: u64_at(b, 16),
            },
            rops: &b[HEADER_SIZE..end_at],
        })
    }

    /// The ROPs, as `EOreceiver` parses them: `ropsnumberof` ROPs one after the other. A
    /// malformed ROP ends the parse (its length cannot be trusted); bytes left after
    /// the counted ROPs, or too few ROPs, are reported as [`RopsError::Count`].
    pub fn parse_rops(&self) -> (Vec<Rop>, Option<RopsError>) {
        let mut rops = Vec::with_capacity(usize::from(self.header.rops_count).min(64));
        let err = self.visit_rops(|r| rops.push(r.to_rop()));
        (rops, err)
    }

    /// Calls `f` on each ROP without copying (see [`Self::parse_rops`]); returns the first
    /// problem.
    pub fn visit_rops(&self, mut f: impl FnMut(RopRef<'a>)) -> Option<RopsError> {
        let mut at = 0;
        let mut parsed = 0usize;
        for _ in 0..self.header.rops_count {
            if at == self.rops.len() {
                break;
            }
            match RopRef::decode(&self.rops[at..]) {
                Ok((rop, n)) => {
                    f(rop);
                    parsed += 1;
                    at += n;
                }
                Err(e) => {
                    return Some(RopsError::Rop {
                        index: parsed,
                        error: e,
                    })
                }
            }
        }
        (at != self.rops.len() || parsed != usize::from(self.header.rops_count)).then_some(
            RopsError::Count {
                declared: self.header.rops_count,
                parsed,
                unparsed_bytes: self.rops.len() - at,
            },
        )
    }
}

/// A problem in the ROPs of a valid ropframe.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
pub enum RopsError {
    #[error("ROP #{index}: {error}")]
    Rop { index: usize, error: RopError },
    #[error("ropsnumberof {declared} but {parsed} ROPs parsed with {unparsed_bytes} bytes left")]
    Count {
        declared: u16,
        parsed: usize,
        unparsed_bytes: usize,
    },
}

/// The ROP does not fit in what is left of the frame's capacity.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
#[error("ROP of {rop} bytes does not fit: {left} bytes left in the ropframe")]
pub struct FrameFull {
    pub rop: usize,
    pub left: usize,
}

/// Builds a ropframe of at most `capacity` bytes (the peer's `maxSizeRXpacket`).
#[derive(Debug, Clone)]
pub struct FrameBuilder {
    capacity: usize,
    rops: Vec<u8>,
    count: u16,
}

impl FrameBuilder {
    pub fn new(capacity: usize) -> Self {
        Self {
            capacity: capacity.clamp(EMPTY_FRAME_SIZE, usize::from(u16::MAX)),
            rops: Vec::new(),
            count: 0,
        }
    }

    pub fn len(&self) -> usize {
        self.count.into()
    }
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }
    /// Bytes still available for ROPs.
    pub fn room(&self) -> usize {
        self.capacity - EMPTY_FRAME_SIZE - self.rops.len()
    }

    /// Appends a ROP if it fits; an invalid ROP is an error too.
    pub fn push(&mut self, rop: &Rop) -> Result<(), PushError> {
        let n = rop.wire_size();
        if n > self.room() || self.count == u16::MAX {
            return Err(PushError::Full(FrameFull {
                rop: n,
                left: self.room(),
            }));
        }
        rop.encode_into(&mut self.rops).map_err(PushError::Rop)?;
        self.count += 1;
        Ok(())
    }

    /// Appends a plain `sig<id>` with `data` (no signature, no time) without building a
    /// [`Rop`]: the regulars' path.
    pub fn push_sig(&mut self, id: Id32, data: &[u8]) -> Result<(), PushError> {
        let n = ROP_HEAD_SIZE + padded(data.len());
        if data.is_empty() {
            return Err(PushError::Rop(RopError::MissingData(
                crate::rop::RopCode::Sig,
            )));
        }
        let dsiz = u16::try_from(data.len())
            .map_err(|_| PushError::Rop(RopError::DataTooLong(data.len())))?;
        if n > self.room() || self.count == u16::MAX {
            return Err(PushError::Full(FrameFull {
                rop: n,
                left: self.room(),
            }));
        }
        self.rops.push(0);
        self.rops.push(crate::rop::RopCode::Sig as u8);
        self.rops.extend_from_slice(&dsiz.to_le_bytes());
        self.rops.extend_from_slice(&id.0.to_le_bytes());
        self.rops.extend_from_slice(data);
        self.rops
            .resize(self.rops.len() + padded(data.len()) - data.len(), 0);
        self.count += 1;
        Ok(())
    }

    /// The datagram, with the sender's sequence number and age (µs).
    pub fn finish(&self, sequence: u64, age: u64) -> Vec<u8> {
        encode_frame(&self.rops, self.count, sequence, age)
    }

    pub fn clear(&mut self) {
        self.rops.clear();
        self.count = 0;
    }
}

/// Why a ROP was not added to a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
pub enum PushError {
    #[error(transparent)]
    Full(FrameFull),
    #[error(transparent)]
    Rop(RopError),
}

/// A ropframe around already encoded ROPs.
pub fn encode_frame(rops: &[u8], count: u16, sequence: u64, age: u64) -> Vec<u8> {
    let mut v = Vec::with_capacity(EMPTY_FRAME_SIZE + rops.len());
    v.extend_from_slice(&FRAME_START.to_le_bytes());
    v.extend_from_slice(&(rops.len() as u16).to_le_bytes());
    v.extend_from_slice(&count.to_le_bytes());
    v.extend_from_slice(&age.to_le_bytes());
    v.extend_from_slice(&sequence.to_le_bytes());
    v.extend_from_slice(rops);
    v.extend_from_slice(&FRAME_END.to_le_bytes());
    v
}

/// Decodes a datagram and all its ROPs (the fuzz target's entry point): a frame error,
/// or the header, the ROPs parsed and the first problem among them.
pub fn decode_datagram(b: &[u8]) -> Result<(FrameHeader, Vec<Rop>, Option<RopsError>), FrameError> {
    let f = Frame::decode(b)?;
    let (rops, err) = f.parse_rops();
    Ok((f.header, rops, err))
}
