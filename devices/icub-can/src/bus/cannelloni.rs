//! The cannelloni UDP wire format (version 2), sans I/O.
//!
//! One datagram carries a 5-byte header and `count` frames; everything is big-endian:
//!
//! | bytes | field   | meaning                                  |
//! |-------|---------|------------------------------------------|
//! | 1     | version | protocol version, always 2               |
//! | 1     | op code | 0 = DATA (1 = ACK, 2 = NACK are unused)  |
//! | 1     | seq no  | sender's sequence number, wraps at 255   |
//! | 2     | count   | number of CAN frames that follow         |
//!
//! Each frame: `can_id` (4 bytes, the Linux identifier word with the EFF `0x80000000`,
//! RTR `0x40000000` and ERR `0x20000000` flags), `len` (1 byte; bit 7 set marks a CAN FD
//! frame and is followed by one CAN FD `flags` byte), then `len` data bytes — except for
//! RTR frames, which carry a length but no data bytes. A datagram with `count == 0` is
//! valid and empty. This crate speaks classic CAN only: CAN FD frames are reported as
//! errors rather than truncated.

use crate::frame::{CanFrame, FrameError, CAN_RTR_FLAG};

/// Protocol version written and accepted.
pub const VERSION: u8 = 2;
/// Op code of data packets.
pub const OP_DATA: u8 = 0;
/// Header size in bytes.
pub const HEADER_LEN: usize = 5;
/// Bit of `len` marking a CAN FD frame.
pub const CANFD_FRAME: u8 = 0x80;
/// Largest datagram we build (cannelloni's default buffer is 1500 bytes).
pub const MAX_PACKET: usize = 1400;

/// Why a datagram was rejected.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CannelloniError {
    #[error("datagram of {0} bytes is shorter than the 5-byte header")]
    ShortHeader(usize),
    #[error("unsupported cannelloni version {0} (expected 2)")]
    Version(u8),
    #[error("unsupported op code {0} (expected DATA = 0)")]
    OpCode(u8),
    #[error("frame {index} truncated at byte {offset}")]
    Truncated { index: usize, offset: usize },
    #[error("frame {index} is a CAN FD frame, which is not supported")]
    CanFd { index: usize },
    #[error("frame {index}: {source}")]
    Frame {
        index: usize,
        #[source]
        source: FrameError,
    },
    #[error("{0} trailing bytes after the last frame")]
    Trailing(usize),
}

/// A decoded datagram.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Packet {
    pub seq: u8,
    pub frames: Vec<CanFrame>,
}

/// Bytes one frame takes on the wire.
pub fn frame_wire_len(frame: &CanFrame) -> usize {
    5 + if frame.is_remote() { 0 } else { frame.len() }
}

/// Appends one datagram holding `frames` to `out`.
pub fn encode(seq: u8, frames: &[CanFrame], out: &mut Vec<u8>) {
    out.reserve(HEADER_LEN + frames.iter().map(frame_wire_len).sum::<usize>());
    out.extend_from_slice(&[VERSION, OP_DATA, seq]);
    out.extend_from_slice(&(frames.len() as u16).to_be_bytes());
    for f in frames {
        out.extend_from_slice(&f.id_word().to_be_bytes());
        out.push(f.len() as u8);
        out.extend_from_slice(f.data());
    }
}

/// Splits `frames` into datagrams of at most [`MAX_PACKET`] bytes.
pub fn encode_packets(first_seq: u8, frames: &[CanFrame]) -> Vec<Vec<u8>> {
    let mut packets = Vec::new();
    let mut start = 0;
    let mut seq = first_seq;
    while start < frames.len() {
        let mut size = HEADER_LEN;
        let mut end = start;
        while end < frames.len() && size + frame_wire_len(&frames[end]) <= MAX_PACKET {
            size += frame_wire_len(&frames[end]);
            end += 1;
        }
        let mut buf = Vec::with_capacity(size);
        encode(seq, &frames[start..end], &mut buf);
        packets.push(buf);
        seq = seq.wrapping_add(1);
        start = end;
    }
    packets
}

/// Decodes one datagram; any malformed part rejects the whole datagram.
pub fn decode(buf: &[u8]) -> Result<Packet, CannelloniError> {
    if buf.len() < HEADER_LEN {
        return Err(CannelloniError::ShortHeader(buf.len()));
    }
    if buf[0] != VERSION {
        return Err(CannelloniError::Version(buf[0]));
    }
    if buf[1] != OP_DATA {
        return Err(CannelloniError::OpCode(buf[1]));
    }
    let seq = buf[2];
    let count = usize::from(u16::from_be_bytes([buf[3], buf[4]]));
    let mut pos = HEADER_LEN;
    // Each frame takes at least 5 bytes, which bounds the allocation by the input size.
    let mut frames = Vec::with_capacity(count.min(buf.len() / 5));
    for index in 0..count {
        let head = buf
            .get(pos..pos + 5)
            .ok_or(CannelloniError::Truncated { index, offset: pos })?;
        let word = u32::from_be_bytes([head[0], head[1], head[2], head[3]]);
        let len = head[4];
        pos += 5;
        if len & CANFD_FRAME != 0 {
            return Err(CannelloniError::CanFd { index });
        }
        let frame = if word & CAN_RTR_FLAG != 0 {
            CanFrame::from_id_word(word, &[], len)
        } else {
            let data = buf
                .get(pos..pos + usize::from(len))
                .ok_or(CannelloniError::Truncated { index, offset: pos })?;
            pos += usize::from(len);
            CanFrame::from_id_word(word, data, 0)
        }
        .map_err(|source| CannelloniError::Frame { index, source })?;
        frames.push(frame);
    }
    if pos != buf.len() {
        return Err(CannelloniError::Trailing(buf.len() - pos));
    }
    Ok(Packet { seq, frames })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_bytes_of_a_known_packet() {
        let frames = [
            CanFrame::new(0x123, &[0xAA, 0xBB]).unwrap(),
            CanFrame::new_extended(0x1ABCDEF, &[]).unwrap(),
            CanFrame::new_remote(0x7FF, false, 3).unwrap(),
        ];
        let mut buf = Vec::new();
        encode(9, &frames, &mut buf);
        let expected: Vec<u8> = vec![
            2, 0, 9, 0, 3, // header
            0x00, 0x00, 0x01, 0x23, 2, 0xAA, 0xBB, // std frame
            0x81, 0xAB, 0xCD, 0xEF, 0, // extended, empty
            0x40, 0x00, 0x07, 0xFF, 3, // remote: len but no data
        ];
        assert_eq!(buf, expected);
        assert_eq!(
            decode(&buf).unwrap(),
            Packet {
                seq: 9,
                frames: frames.to_vec()
            }
        );
    }

    #[test]
    fn empty_packet_is_valid() {
        assert_eq!(decode(&[2, 0, 1, 0, 0]).unwrap().frames.len(), 0);
    }

    #[test]
    fn malformed_packets_are_errors() {
        assert_eq!(decode(&[2, 0]), Err(CannelloniError::ShortHeader(2)));
        assert_eq!(decode(&[1, 0, 0, 0, 0]), Err(CannelloniError::Version(1)));
        assert_eq!(decode(&[2, 1, 0, 0, 0]), Err(CannelloniError::OpCode(1)));
        assert!(matches!(
            decode(&[2, 0, 0, 0, 1, 0, 0]),
            Err(CannelloniError::Truncated { .. })
        ));
        assert!(matches!(
            decode(&[2, 0, 0, 0, 1, 0, 0, 1, 0, 4, 1]),
            Err(CannelloniError::Truncated { index: 0, .. })
        ));
        assert!(matches!(
            decode(&[2, 0, 0, 0, 1, 0, 0, 1, 0, 0x81, 0, 1]),
            Err(CannelloniError::CanFd { .. })
        ));
        assert!(matches!(
            decode(&[2, 0, 0, 0, 1, 0, 0, 1, 0, 9, 0, 0, 0, 0, 0, 0, 0, 0, 0]),
            Err(CannelloniError::Frame { .. })
        ));
        assert!(matches!(
            decode(&[2, 0, 0, 0, 1, 0, 0, 0x09, 0, 0]),
            Err(CannelloniError::Frame { .. })
        ));
        assert_eq!(
            decode(&[2, 0, 0, 0, 0, 7]),
            Err(CannelloniError::Trailing(1))
        );
        // A huge count with no data must fail fast, not allocate.
        assert!(decode(&[2, 0, 0, 0xFF, 0xFF]).is_err());
    }

    #[test]
    fn large_batches_are_split() {
        let frames: Vec<CanFrame> = (0..500)
            .map(|i| CanFrame::new(i, &[0; 8]).unwrap())
            .collect();
        let packets = encode_packets(254, &frames);
        assert!(packets.len() > 1);
        let mut all = Vec::new();
        for (i, p) in packets.iter().enumerate() {
            assert!(p.len() <= MAX_PACKET);
            let d = decode(p).unwrap();
            assert_eq!(d.seq, 254u8.wrapping_add(i as u8));
            all.extend(d.frames);
        }
        assert_eq!(all, frames);
    }
}
