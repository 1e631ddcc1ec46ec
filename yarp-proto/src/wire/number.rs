//! YARP numbers: the 8-byte `'Y' 'A' <int32 LE> 'R' 'P'` used for connection headers,
//! header replies, message index markers and acknowledgements
//! (C++ `AbstractCarrier::createYarpNumber` / `interpretYarpNumber`).

/// Length of a YARP number on the wire.
pub const LEN: usize = 8;

/// The acknowledgement a tcp receiver sends after each message: YARP number 0.
pub const ACK: [u8; 8] = YarpNumber(0).to_bytes();

/// The marker that starts every message index: YARP number 10.
pub const INDEX_MARKER: [u8; 8] = YarpNumber(INDEX_VALUE).to_bytes();

/// The value carried by the index marker.
pub const INDEX_VALUE: i32 = 10;

/// An int32 wrapped as `'Y' 'A' <int32 LE> 'R' 'P'`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct YarpNumber(pub i32);

impl YarpNumber {
    /// The 8 wire bytes.
    pub const fn to_bytes(self) -> [u8; 8] {
        let v = self.0.to_le_bytes();
        [b'Y', b'A', v[0], v[1], v[2], v[3], b'R', b'P']
    }

    /// Reads the first 8 bytes of `bytes`; `None` when there are fewer than 8 or the
    /// `YA`/`RP` markers are missing.
    pub fn decode(bytes: &[u8]) -> Option<YarpNumber> {
        match bytes {
            [b'Y', b'A', a, b, c, d, b'R', b'P', ..] => {
                Some(YarpNumber(i32::from_le_bytes([*a, *b, *c, *d])))
            }
            _ => None,
        }
    }

    /// Whether the first 8 bytes of `bytes` are a YARP number.
    pub fn is_at(bytes: &[u8]) -> bool {
        YarpNumber::decode(bytes).is_some()
    }
}

/// `YarpNumber(value).to_bytes()`.
pub const fn encode(value: i32) -> [u8; 8] {
    YarpNumber(value).to_bytes()
}

/// The value of the YARP number at the start of `bytes`.
pub fn decode(bytes: &[u8]) -> Option<i32> {
    YarpNumber::decode(bytes).map(|n| n.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_known_bytes() {
        assert_eq!(encode(7908), [0x59, 0x41, 0xe4, 0x1e, 0, 0, 0x52, 0x50]);
        assert_eq!(decode(&encode(-5)), Some(-5));
        assert_eq!(ACK, *b"YA\0\0\0\0RP");
        assert_eq!(INDEX_MARKER, [0x59, 0x41, 10, 0, 0, 0, 0x52, 0x50]);
        assert_eq!(decode(b"YA\0\0\0\0R"), None);
        assert_eq!(decode(b"XA\0\0\0\0RP"), None);
        assert_eq!(decode(b"YA\x12\x27\0\0RPtrailing"), Some(10002));
    }
}
