//! Classic CAN 2.0 frames, with the identifier word laid out as Linux `<linux/can.h>` does.

use std::fmt;

/// Extended frame format flag in the identifier word (bit 31).
pub const CAN_EFF_FLAG: u32 = 0x8000_0000;
/// Remote transmission request flag in the identifier word (bit 30).
pub const CAN_RTR_FLAG: u32 = 0x4000_0000;
/// Error frame flag in the identifier word (bit 29).
pub const CAN_ERR_FLAG: u32 = 0x2000_0000;
/// Mask of an 11-bit standard identifier.
pub const CAN_SFF_MASK: u32 = 0x0000_07FF;
/// Mask of a 29-bit extended identifier.
pub const CAN_EFF_MASK: u32 = 0x1FFF_FFFF;
/// Largest payload of a classic CAN frame.
pub const CAN_MAX_DLEN: usize = 8;

/// Why a frame could not be built.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum FrameError {
    #[error("CAN identifier {id:#x} does not fit in {bits} bits")]
    IdTooLarge { id: u32, bits: u8 },
    #[error("CAN payload of {0} bytes is longer than 8")]
    PayloadTooLong(usize),
}

/// One classic CAN frame (up to 8 data bytes).
///
/// Remote (RTR) frames carry a length code but no data; error frames carry the
/// kernel's error class in the identifier and details in the data.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct CanFrame {
    id: u32,
    extended: bool,
    rtr: bool,
    error: bool,
    len: u8,
    data: [u8; CAN_MAX_DLEN],
}

impl CanFrame {
    /// A data frame with an 11-bit identifier.
    pub fn new(id: u16, data: &[u8]) -> Result<Self, FrameError> {
        if u32::from(id) > CAN_SFF_MASK {
            return Err(FrameError::IdTooLarge {
                id: id.into(),
                bits: 11,
            });
        }
        Self::build(u32::from(id), false, false, false, data)
    }

    /// A data frame with a 29-bit identifier.
    pub fn new_extended(id: u32, data: &[u8]) -> Result<Self, FrameError> {
        if id > CAN_EFF_MASK {
            return Err(FrameError::IdTooLarge { id, bits: 29 });
        }
        Self::build(id, true, false, false, data)
    }

    /// A remote frame asking for `len` bytes.
    pub fn new_remote(id: u32, extended: bool, len: u8) -> Result<Self, FrameError> {
        let (mask, bits) = if extended {
            (CAN_EFF_MASK, 29)
        } else {
            (CAN_SFF_MASK, 11)
        };
        if id > mask {
            return Err(FrameError::IdTooLarge { id, bits });
        }
        if usize::from(len) > CAN_MAX_DLEN {
            return Err(FrameError::PayloadTooLong(len.into()));
        }
        Ok(Self {
            id,
            extended,
            rtr: true,
            error: false,
            len,
            data: [0; 8],
        })
    }

    /// Builds a frame from a Linux identifier word (with EFF/RTR/ERR flags) and payload.
    ///
    /// For remote frames `data` is ignored and `len` is taken from `rtr_len`.
    pub fn from_id_word(word: u32, data: &[u8], rtr_len: u8) -> Result<Self, FrameError> {
        let extended = word & CAN_EFF_FLAG != 0;
        let rtr = word & CAN_RTR_FLAG != 0;
        let error = word & CAN_ERR_FLAG != 0;
        let id = if extended {
            word & CAN_EFF_MASK
        } else {
            word & CAN_SFF_MASK
        };
        if !extended && word & CAN_EFF_MASK & !CAN_SFF_MASK != 0 {
            return Err(FrameError::IdTooLarge {
                id: word & CAN_EFF_MASK,
                bits: 11,
            });
        }
        if rtr {
            let mut f = Self::new_remote(id, extended, rtr_len)?;
            f.error = error;
            return Ok(f);
        }
        Self::build(id, extended, false, error, data)
    }

    fn build(
        id: u32,
        extended: bool,
        rtr: bool,
        error: bool,
        data: &[u8],
    ) -> Result<Self, FrameError> {
        if data.len() > CAN_MAX_DLEN {
            return Err(FrameError::PayloadTooLong(data.len()));
        }
        let mut buf = [0u8; CAN_MAX_DLEN];
        buf[..data.len()].copy_from_slice(data);
        Ok(Self {
            id,
            extended,
            rtr,
            error,
            len: data.len() as u8,
            data: buf,
        })
    }

    /// The identifier without flags.
    pub fn id(&self) -> u32 {
        self.id
    }
    /// The 11-bit identifier, or `None` for extended frames.
    pub fn std_id(&self) -> Option<u16> {
        (!self.extended).then_some(self.id as u16)
    }
    /// Whether this frame uses a 29-bit identifier.
    pub fn is_extended(&self) -> bool {
        self.extended
    }
    /// Whether this is a remote transmission request.
    pub fn is_remote(&self) -> bool {
        self.rtr
    }
    /// Whether this is an error frame.
    pub fn is_error(&self) -> bool {
        self.error
    }
    /// The identifier word as in `struct can_frame` (identifier plus EFF/RTR/ERR flags).
    pub fn id_word(&self) -> u32 {
        let mut w = self.id;
        if self.extended {
            w |= CAN_EFF_FLAG;
        }
        if self.rtr {
            w |= CAN_RTR_FLAG;
        }
        if self.error {
            w |= CAN_ERR_FLAG;
        }
        w
    }
    /// The data length code (for remote frames: the requested length).
    pub fn len(&self) -> usize {
        self.len.into()
    }
    /// Whether the frame carries no data.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
    /// The payload (empty for remote frames).
    pub fn data(&self) -> &[u8] {
        if self.rtr {
            &[]
        } else {
            &self.data[..self.len.into()]
        }
    }
}

impl fmt::Debug for CanFrame {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{self}")
    }
}

/// `candump`-like rendering: `123#0102AB`, `12345678#..`, `123#R2`.
impl fmt::Display for CanFrame {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.extended {
            write!(f, "{:08X}#", self.id)?;
        } else {
            write!(f, "{:03X}#", self.id)?;
        }
        if self.rtr {
            return write!(f, "R{}", self.len);
        }
        for b in self.data() {
            write!(f, "{b:02X}")?;
        }
        if self.error {
            write!(f, " (error)")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn standard_frame_roundtrips_through_id_word() {
        let f = CanFrame::new(0x1A3, &[1, 2, 3]).unwrap();
        assert_eq!(f.id_word(), 0x1A3);
        let back = CanFrame::from_id_word(f.id_word(), f.data(), 0).unwrap();
        assert_eq!(back, f);
        assert_eq!(f.to_string(), "1A3#010203");
    }

    #[test]
    fn flags_are_kept() {
        let f = CanFrame::new_extended(0x1234567, &[9]).unwrap();
        assert_eq!(f.id_word(), 0x1234567 | CAN_EFF_FLAG);
        let r = CanFrame::new_remote(0x10, false, 4).unwrap();
        assert_eq!(r.id_word(), 0x10 | CAN_RTR_FLAG);
        assert!(r.data().is_empty());
        assert_eq!(r.len(), 4);
        let back = CanFrame::from_id_word(r.id_word(), &[], 4).unwrap();
        assert_eq!(back, r);
    }

    #[test]
    fn rejects_bad_frames() {
        assert!(matches!(
            CanFrame::new(0x800, &[]),
            Err(FrameError::IdTooLarge { .. })
        ));
        assert!(matches!(
            CanFrame::new(1, &[0; 9]),
            Err(FrameError::PayloadTooLong(9))
        ));
        assert!(CanFrame::new_extended(0x2000_0000, &[]).is_err());
        assert!(CanFrame::from_id_word(0x0000_0900, &[], 0).is_err());
        assert!(CanFrame::new_remote(1, false, 9).is_err());
    }
}
