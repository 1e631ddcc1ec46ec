//! Finding where a binary Bottle ends in a stream that is still arriving.
//!
//! RPC replies carry no length: the caller has to parse the Bottle to find its end. Re-running
//! the full decoder on every new TCP segment would be quadratic, so this scanner walks the
//! encoding once, resumably, keeping only a stack of element counters. It follows the same
//! rules as [`crate::binary::decode`] (which then validates the complete bytes).

use crate::binary::MAX_DEPTH;
use crate::tags::{self, Generation};
use crate::DecodeError;

/// Outcome of a scan step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scan {
    /// The Bottle ends after this many bytes.
    Complete(usize),
    /// At least this many bytes (in total, from the start) are needed to go on.
    NeedAtLeast(u64),
}

#[derive(Debug, Clone, Copy)]
enum Want {
    /// A top-level (or dict content) tag.
    TopTag,
    /// An element count of a list with this homogeneous subtype (0 = tagged elements).
    Count(i32),
    /// The next element of the innermost list (or the end of the Bottle).
    Element,
}

#[derive(Debug, Clone, Copy)]
struct Frame {
    remaining: u32,
    sub: i32,
}

/// Resumable scanner over one binary Bottle starting at byte 0 of the buffers it is given.
#[derive(Debug, Clone)]
pub struct BottleScanner {
    stack: Vec<Frame>,
    want: Want,
    pos: usize,
    /// Read as YARP 3's until a tag only 4.0 has shows the Bottle is 4.0's (as
    /// `Bottle::decode` does); then scanned again from the start.
    generation: Generation,
}

impl Default for BottleScanner {
    fn default() -> Self {
        BottleScanner::new()
    }
}

fn read_i32(buf: &[u8], at: usize) -> Option<i32> {
    let b = buf.get(at..at.checked_add(4)?)?;
    Some(i32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

impl BottleScanner {
    pub fn new() -> BottleScanner {
        BottleScanner {
            stack: Vec::new(),
            want: Want::TopTag,
            pos: 0,
            generation: Generation::V3,
        }
    }

    /// Continues scanning. `buf` must start at the Bottle's first byte and extend the
    /// buffer given in earlier calls (more bytes appended, none changed).
    pub fn scan(&mut self, buf: &[u8]) -> Result<Scan, DecodeError> {
        loop {
            let need = |n: usize, pos: usize| Scan::NeedAtLeast(pos as u64 + n as u64);
            match self.want {
                Want::TopTag => {
                    let Some(tag) = read_i32(buf, self.pos) else {
                        return Ok(need(4, self.pos));
                    };
                    self.pos += 4;
                    self.want = Want::Count(tag & tags::UNIT_MASK);
                }
                Want::Count(sub) => {
                    if self.stack.len() > MAX_DEPTH {
                        return Err(DecodeError::TooDeep {
                            limit: MAX_DEPTH,
                            offset: self.pos,
                        });
                    }
                    let Some(count) = read_i32(buf, self.pos) else {
                        return Ok(need(4, self.pos));
                    };
                    self.pos += 4;
                    if count > 0 {
                        self.stack.push(Frame {
                            remaining: count as u32,
                            sub,
                        });
                    }
                    self.want = Want::Element;
                }
                Want::Element => {
                    let Some(top) = self.stack.last_mut() else {
                        return Ok(Scan::Complete(self.pos));
                    };
                    if top.remaining == 0 {
                        self.stack.pop();
                        continue;
                    }
                    let (tag, tag_len) = if top.sub != 0 {
                        (top.sub, 0usize)
                    } else {
                        match read_i32(buf, self.pos) {
                            Some(t) => (t, 4usize),
                            None => return Ok(need(4, self.pos)),
                        }
                    };
                    let body_at = self.pos + tag_len;
                    let g = self.generation;
                    let fixed = match tag {
                        tags::INT8 => Some(1usize),
                        tags::INT16 => Some(2),
                        tags::INT32 | tags::VOCAB32 => Some(4),
                        tags::INT64 => Some(8),
                        t if g == Generation::V4 && t == tags::v4::VOCAB64 => Some(8),
                        t if t == g.float32() => Some(4),
                        t if t == g.float64() => Some(8),
                        _ => None,
                    };
                    if let Some(n) = fixed {
                        if buf.len() < body_at + n {
                            return Ok(need(tag_len + n, self.pos));
                        }
                        top.remaining -= 1;
                        self.pos = body_at + n;
                        continue;
                    }
                    if tag == tags::STRING || tag == tags::BLOB {
                        let Some(len) = read_i32(buf, body_at) else {
                            return Ok(need(tag_len + 4, self.pos));
                        };
                        if len < 0 {
                            return Err(DecodeError::NegativeLength {
                                len,
                                what: if tag == tags::STRING {
                                    "string"
                                } else {
                                    "blob"
                                },
                                offset: body_at,
                            });
                        }
                        let end = body_at as u64 + 4 + len as u64;
                        if (buf.len() as u64) < end {
                            return Ok(Scan::NeedAtLeast(end));
                        }
                        top.remaining -= 1;
                        self.pos = end as usize;
                        continue;
                    }
                    if tag & tags::GROUP_MASK != 0 {
                        top.remaining -= 1;
                        self.pos = body_at;
                        self.want = if tag & tags::DICT != 0 {
                            Want::TopTag
                        } else {
                            Want::Count(tag & tags::UNIT_MASK)
                        };
                        continue;
                    }
                    if self.generation == Generation::V3 && Generation::V4.owns(tag) {
                        *self = BottleScanner {
                            generation: Generation::V4,
                            ..BottleScanner::new()
                        };
                        continue;
                    }
                    return Err(DecodeError::UnknownTag {
                        tag,
                        offset: self.pos,
                    });
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{bottle, Bottle, Value};

    fn scan_bytewise(bytes: &[u8]) -> Option<usize> {
        let mut s = BottleScanner::new();
        for n in 0..=bytes.len() {
            match s.scan(&bytes[..n]) {
                Ok(Scan::Complete(end)) => return Some(end),
                Ok(Scan::NeedAtLeast(k)) => assert!(k > n as u64),
                Err(_) => return None,
            }
        }
        None
    }

    #[test]
    fn finds_the_end_of_bottles() {
        let mut nested = bottle!["a", 1, 2.5];
        nested.add_list().push(1i8).push(2i8);
        nested.push(Value::Blob(vec![1, 2, 3]));
        nested.push(Value::Dict(bottle![bottle!["k", 1]]));
        let cases = [Bottle::new(), bottle![1, 2, 3], nested, bottle!["x", 1i64]];
        for b in cases {
            let mut bytes = b.encode();
            let len = bytes.len();
            bytes.extend_from_slice(b"YA\0\0\0\0RP");
            assert_eq!(scan_bytewise(&bytes), Some(len), "{b}");
        }
    }

    #[test]
    fn hostile_lengths_do_not_allocate() {
        // string claiming 2 GiB: asks for the bytes, reserves nothing
        let evil = [0, 1, 0, 0, 1, 0, 0, 0, 4, 0, 0, 0, 0xff, 0xff, 0xff, 0x7f];
        let mut s = BottleScanner::new();
        assert_eq!(s.scan(&evil), Ok(Scan::NeedAtLeast(16 + 0x7fff_ffff)));
        let bad = [0, 1, 0, 0, 1, 0, 0, 0, 0x33, 0, 0, 0];
        assert!(matches!(
            BottleScanner::new().scan(&bad),
            Err(DecodeError::UnknownTag { .. })
        ));
    }

    /// The decoder no longer decodes a reply to validate it: whatever the scanner finds
    /// complete must decode, to the same length, and whatever decodes the scanner finds.
    #[test]
    fn scanner_agrees_with_decode() {
        let mut x: u64 = 0x2545f4914f6cdd1d;
        let mut next = move || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        let pieces: [&[u8]; 12] = [
            &[0, 1, 0, 0],
            &[1, 0, 0, 0],
            &[2, 0, 0, 0],
            &[0xff, 0xff, 0xff, 0xff],
            &[1, 1, 0, 0],
            &[4, 0, 0, 0],
            &[12, 0, 0, 0],
            &[0x20, 0, 0, 0],
            &[0x0a, 0x01, 0, 0],
            &[0, 2, 0, 0],
            &[0x33, 0, 0, 0],
            &[7],
        ];
        let mut complete = 0;
        for round in 0..50_000 {
            let mut bytes = Vec::new();
            if round % 2 == 1 {
                let mut b = bottle!["a", 1];
                b.add_list()
                    .push(2.5)
                    .push(Value::Blob(vec![1; (next() % 9) as usize]));
                b.push(Value::Dict(bottle![bottle!["k", 1i64]]));
                bytes = b.encode();
                for _ in 0..1 + next() % 3 {
                    let at = (next() as usize) % bytes.len();
                    bytes[at] = match next() % 3 {
                        0 => next() as u8,
                        1 => 0,
                        _ => 1,
                    };
                }
            } else {
                bytes.extend_from_slice(pieces[(next() % 10) as usize]);
                for _ in 0..next() % 16 {
                    bytes.extend_from_slice(pieces[(next() % 12) as usize]);
                }
            }
            let scanned = BottleScanner::new().scan(&bytes);
            match (scanned.clone(), crate::binary::decode(&bytes)) {
                (Ok(Scan::Complete(n)), Ok((_, used))) => {
                    assert_eq!(n, used, "{bytes:?}");
                    complete += 1;
                }
                (Ok(Scan::Complete(n)), Err(e)) => panic!("scanned {n}, decode {e:?}: {bytes:?}"),
                (Ok(Scan::NeedAtLeast(_)) | Err(_), Ok(_)) => {
                    panic!("decodes, scanner {scanned:?}: {bytes:?}")
                }
                (Ok(Scan::NeedAtLeast(_)) | Err(_), Err(_)) => {}
            }
        }
        assert!(complete > 1000, "{complete}");
    }

    #[test]
    fn deep_nesting_is_an_error() {
        let mut bytes = vec![0, 1, 0, 0];
        for _ in 0..1000 {
            bytes.extend_from_slice(&[1, 0, 0, 0, 0, 1, 0, 0]);
        }
        assert!(matches!(
            BottleScanner::new().scan(&bytes),
            Err(DecodeError::TooDeep { .. })
        ));
    }
}
