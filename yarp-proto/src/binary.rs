//! Binary Bottle codec, byte-exact with C++ YARP 3.12 (`BottleImpl::synch` / `read`).
//!
//! Layout: a Bottle is `int32 tag` (LIST | subtype) + `int32 count` + elements. When every
//! element has the same simple type the list is compacted: the tag carries that type and the
//! elements are written without their own tags. All numbers are little-endian.

use crate::error::DecodeError;
use crate::tags::{self, Generation};
use crate::value::{Bottle, Value};
use crate::vocab::Vocab32;

/// Nesting limit when decoding untrusted input (C++ has none and would overflow its stack).
pub const MAX_DEPTH: usize = 256;

/// Encodes a top-level Bottle.
pub fn encode(b: &Bottle) -> Vec<u8> {
    encode_as(b, Generation::V3)
}

/// The encoding of a top-level Bottle in `generation`'s numbering of tags.
pub fn encode_as(b: &Bottle, generation: Generation) -> Vec<u8> {
    let mut out = Vec::with_capacity(encoded_len_hint(b));
    Writer(generation).top_level(b, &mut out);
    out
}

/// Appends the encoding of a top-level Bottle to `out`.
pub fn encode_into(b: &Bottle, out: &mut Vec<u8>) {
    Writer(Generation::V3).top_level(b, out);
}

fn encoded_len_hint(b: &Bottle) -> usize {
    8 + b.len() * 12
}

/// Writes Bottles in one generation's numbering of tags.
#[derive(Clone, Copy)]
struct Writer(Generation);

impl Writer {
    fn top_level(self, b: &Bottle, out: &mut Vec<u8>) {
        let sub = b.homogeneous_tag_in(self.0);
        put_i32(out, tags::LIST | sub);
        self.content(b, sub, out);
    }

    fn content(self, b: &Bottle, sub: i32, out: &mut Vec<u8>) {
        put_i32(out, b.len() as i32);
        for v in b.iter() {
            if sub == 0 {
                put_i32(out, v.tag_in(self.0));
            }
            self.raw(v, out);
        }
    }

    /// The element body (everything after its tag).
    fn raw(self, v: &Value, out: &mut Vec<u8>) {
        match v {
            Value::Int8(x) => out.push(*x as u8),
            Value::Int16(x) => out.extend_from_slice(&x.to_le_bytes()),
            Value::Int32(x) => put_i32(out, *x),
            Value::Int64(x) => out.extend_from_slice(&x.to_le_bytes()),
            Value::Float32(x) => out.extend_from_slice(&x.to_le_bytes()),
            Value::Float64(x) => out.extend_from_slice(&x.to_le_bytes()),
            Value::Vocab32(x) => put_i32(out, x.0),
            Value::Vocab64(x) => out.extend_from_slice(&x.to_le_bytes()),
            Value::String(s) | Value::Blob(s) => {
                put_i32(out, s.len() as i32);
                out.extend_from_slice(s);
            }
            Value::List(b) => self.content(b, b.homogeneous_tag_in(self.0), out),
            Value::Dict(b) => self.top_level(b, out),
        }
    }
}

fn write_raw(v: &Value, out: &mut Vec<u8>) {
    Writer(Generation::V3).raw(v, out)
}

fn put_i32(out: &mut Vec<u8>, x: i32) {
    out.extend_from_slice(&x.to_le_bytes());
}

/// Strings and blobs at least this long are lent, not copied, by [`encode_segments`].
pub const LEND_MIN: usize = 16 * 1024;

/// The encoding of a top-level Bottle as a list of byte segments whose concatenation is
/// exactly [`encode`]'s output: large strings and blobs are borrowed from the Bottle, so
/// a vectored write sends them without a copy.
pub fn encode_segments(b: &Bottle) -> Vec<std::borrow::Cow<'_, [u8]>> {
    let mut segs = Vec::new();
    let mut cur = Vec::with_capacity(64);
    let sub = b.homogeneous_tag();
    put_i32(&mut cur, tags::LIST | sub);
    segment_content(b, sub, &mut cur, &mut segs);
    if !cur.is_empty() {
        segs.push(std::borrow::Cow::Owned(cur));
    }
    segs
}

fn segment_content<'a>(
    b: &'a Bottle,
    sub: i32,
    cur: &mut Vec<u8>,
    segs: &mut Vec<std::borrow::Cow<'a, [u8]>>,
) {
    put_i32(cur, b.len() as i32);
    for v in b.iter() {
        if sub == 0 {
            put_i32(cur, v.tag());
        }
        match v {
            Value::String(s) | Value::Blob(s) if s.len() >= LEND_MIN => {
                put_i32(cur, s.len() as i32);
                segs.push(std::borrow::Cow::Owned(std::mem::take(cur)));
                segs.push(std::borrow::Cow::Borrowed(s.as_slice()));
            }
            Value::List(inner) => segment_content(inner, inner.homogeneous_tag(), cur, segs),
            Value::Dict(inner) => {
                let isub = inner.homogeneous_tag();
                put_i32(cur, tags::LIST | isub);
                segment_content(inner, isub, cur, segs);
            }
            other => write_raw(other, cur),
        }
    }
}

/// Decodes a top-level Bottle; returns it with the number of bytes it used. Read as
/// YARP 3's unless it holds a tag only YARP 4.0 has ([`generation_of`]).
pub fn decode(bytes: &[u8]) -> Result<(Bottle, usize), DecodeError> {
    match decode_as(bytes, Generation::V3) {
        Err(DecodeError::UnknownTag { tag, .. }) if Generation::V4.owns(tag) => {
            decode_as(bytes, Generation::V4)
        }
        r => r,
    }
}

/// Decodes a top-level Bottle written in `generation`'s numbering of tags.
pub fn decode_as(bytes: &[u8], generation: Generation) -> Result<(Bottle, usize), DecodeError> {
    let mut r = Reader::new(bytes);
    r.generation = generation;
    let b = r.top_level(0)?;
    Ok((b, r.pos))
}

/// The generation whose numbering `bytes` (a binary Bottle) is written in, as
/// [`decode`] reads it: YARP 4.0 when 3's reading meets a tag only 4.0 has.
pub fn generation_of(bytes: &[u8]) -> Generation {
    match decode_as(bytes, Generation::V3) {
        Err(DecodeError::UnknownTag { tag, .. }) if Generation::V4.owns(tag) => Generation::V4,
        _ => Generation::V3,
    }
}

/// A string or blob at least this long may take over the buffer given to
/// [`decode_owned`].
const REUSE_MIN: usize = 64 * 1024;

/// Decodes a top-level Bottle from a buffer it may keep: exactly [`decode`], but a string
/// or blob that makes up at least half of `bytes` (and 64 KiB) is moved to the front of
/// `bytes` and becomes that value, instead of being copied into a new allocation.
pub fn decode_owned(mut bytes: Vec<u8>) -> Result<(Bottle, usize), DecodeError> {
    let min = (bytes.len() / 2).max(REUSE_MIN);
    let mut r = Reader::new(&bytes);
    r.reuse = Some(Reuse {
        min,
        path: Vec::new(),
        found: None,
    });
    let mut b = match r.top_level(0) {
        Err(DecodeError::UnknownTag { tag, .. }) if Generation::V4.owns(tag) => {
            return decode_as(&bytes, Generation::V4);
        }
        b => b?,
    };
    let used = r.pos;
    if let Some((path, start, len)) = r.reuse.and_then(|r| r.found) {
        bytes.copy_within(start..start + len, 0);
        bytes.truncate(len);
        if let Some(Value::String(s) | Value::Blob(s)) = value_at(&mut b, &path) {
            *s = bytes;
        }
    }
    Ok((b, used))
}

/// The value at `path` (element indices, through lists and dicts).
fn value_at<'a>(b: &'a mut Bottle, path: &[usize]) -> Option<&'a mut Value> {
    let (&last, outer) = path.split_last()?;
    let mut b = b;
    for &i in outer {
        match b.get_mut(i)? {
            Value::List(inner) | Value::Dict(inner) => b = inner,
            _ => return None,
        }
    }
    b.get_mut(last)
}

/// Decodes one element body of the given tag (used by carriers and Portables that embed
/// single values).
pub fn decode_value(tag: i32, bytes: &[u8]) -> Result<(Value, usize), DecodeError> {
    let mut r = Reader::new(bytes);
    let v = r.value(tag, 0)?;
    Ok((v, r.pos))
}

struct Reader<'a> {
    buf: &'a [u8],
    pos: usize,
    generation: Generation,
    /// Set by [`decode_owned`]: looks for the one string or blob that will take over the
    /// buffer (decoded as empty, filled in afterwards).
    reuse: Option<Reuse>,
}

struct Reuse {
    /// Shortest string or blob taken.
    min: usize,
    /// Index of the element being decoded in each enclosing list.
    path: Vec<usize>,
    /// Where the taken value is: its path, and its bytes' offset and length.
    found: Option<(Vec<usize>, usize, usize)>,
}

impl<'a> Reader<'a> {
    fn new(buf: &'a [u8]) -> Reader<'a> {
        Reader {
            buf,
            pos: 0,
            generation: Generation::V3,
            reuse: None,
        }
    }

    fn take(&mut self, n: usize, what: &'static str) -> Result<&[u8], DecodeError> {
        let remaining = self.buf.len() - self.pos;
        if n > remaining {
            return Err(DecodeError::Truncated {
                offset: self.pos,
                needed: n - remaining,
                what,
            });
        }
        let s = &self.buf[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }

    fn array<const N: usize>(&mut self, what: &'static str) -> Result<[u8; N], DecodeError> {
        let s = self.take(N, what)?;
        let mut a = [0u8; N];
        a.copy_from_slice(s);
        Ok(a)
    }

    fn i32(&mut self, what: &'static str) -> Result<i32, DecodeError> {
        Ok(i32::from_le_bytes(self.array(what)?))
    }

    /// A top-level (or dict-content) Bottle: the tag's unit bits select compaction; C++
    /// does not insist on the LIST bit here, and neither do we.
    fn top_level(&mut self, depth: usize) -> Result<Bottle, DecodeError> {
        let code = self.i32("bottle tag")?;
        self.content(code & tags::UNIT_MASK, depth)
    }

    fn content(&mut self, sub: i32, depth: usize) -> Result<Bottle, DecodeError> {
        if depth > MAX_DEPTH {
            return Err(DecodeError::TooDeep {
                limit: MAX_DEPTH,
                offset: self.pos,
            });
        }
        let count_at = self.pos;
        let count = self.i32("element count")?;
        if count <= 0 {
            // C++ loops `for (i = 0; i < len; i++)`: a negative count is an empty list.
            return Ok(Bottle::new());
        }
        let remaining = self.buf.len() - self.pos;
        if count as usize > remaining {
            // every element takes at least one byte
            return Err(DecodeError::CountTooLarge {
                count,
                remaining,
                offset: count_at,
            });
        }
        // A Value is 32 bytes while an element can be 1: reserve modestly and let the Vec
        // grow with elements that really decode, so forged counts cost nothing.
        let mut items = Vec::with_capacity((count as usize).min(remaining / 4).min(1024));
        if let Some(r) = &mut self.reuse {
            r.path.push(0);
        }
        for i in 0..count as usize {
            if let Some(at) = self.reuse.as_mut().and_then(|r| r.path.last_mut()) {
                *at = i;
            }
            let tag = if sub == 0 {
                self.i32("element tag")?
            } else {
                sub
            };
            items.push(self.value(tag, depth)?);
        }
        if let Some(r) = &mut self.reuse {
            r.path.pop();
        }
        Ok(Bottle::from(items))
    }

    fn value(&mut self, tag: i32, depth: usize) -> Result<Value, DecodeError> {
        let at = self.pos;
        let g = self.generation;
        Ok(match tag {
            t if t == g.float32() => Value::Float32(f32::from_le_bytes(self.array("float32")?)),
            t if t == g.float64() => Value::Float64(f64::from_le_bytes(self.array("float64")?)),
            tags::INT8 => Value::Int8(self.array::<1>("int8")?[0] as i8),
            tags::INT16 => Value::Int16(i16::from_le_bytes(self.array("int16")?)),
            tags::INT32 => Value::Int32(self.i32("int32")?),
            tags::INT64 => Value::Int64(i64::from_le_bytes(self.array("int64")?)),
            tags::VOCAB32 => Value::Vocab32(Vocab32(self.i32("vocab")?)),
            t if g == Generation::V4 && t == tags::v4::VOCAB64 => {
                Value::Vocab64(u64::from_le_bytes(self.array("vocab64")?))
            }
            tags::STRING => Value::String(self.sized("string")?),
            tags::BLOB => Value::Blob(self.sized("blob")?),
            t if t & tags::GROUP_MASK != 0 => {
                if t & tags::DICT != 0 {
                    Value::Dict(self.top_level(depth + 1)?)
                } else {
                    Value::List(self.content(t & tags::UNIT_MASK, depth + 1)?)
                }
            }
            t => return Err(DecodeError::UnknownTag { tag: t, offset: at }),
        })
    }

    fn sized(&mut self, what: &'static str) -> Result<Vec<u8>, DecodeError> {
        let at = self.pos;
        let len = self.i32(what)?;
        if len < 0 {
            return Err(DecodeError::NegativeLength {
                len,
                what,
                offset: at,
            });
        }
        let len = len as usize;
        if let Some(r) = &mut self.reuse {
            if r.found.is_none() && len >= r.min && len <= self.buf.len() - self.pos {
                r.found = Some((r.path.clone(), self.pos, len));
                self.pos += len;
                return Ok(Vec::new());
            }
        }
        // bounds-checked before allocating: a forged length cannot reserve memory
        Ok(self.take(len, what)?.to_vec())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bottle;

    #[test]
    fn compacts_homogeneous_lists() {
        let b = bottle![1, 2, 3];
        assert_eq!(hex(&b.encode()), "0101000003000000010000000200000003000000");
        let mixed = bottle!["hello", 42];
        assert_eq!(
            hex(&mixed.encode()),
            "0001000002000000040000000500000068656c6c6f010000002a000000"
        );
    }

    #[test]
    fn hostile_lengths_are_errors_not_allocations() {
        // string claiming 4 GiB - 1 in a 20-byte message
        let evil = [
            0x00, 0x01, 0, 0, 1, 0, 0, 0, 4, 0, 0, 0, 0xff, 0xff, 0xff, 0x7f, b'a', b'b', b'c',
            b'd',
        ];
        assert!(matches!(
            Bottle::decode(&evil),
            Err(DecodeError::Truncated { offset: 16, .. })
        ));
        let many = [0x00, 0x01, 0, 0, 0xff, 0xff, 0xff, 0x7f];
        assert!(matches!(
            Bottle::decode(&many),
            Err(DecodeError::CountTooLarge { .. })
        ));
    }

    #[test]
    fn deep_nesting_is_bounded() {
        let mut bytes = vec![0x00, 0x01, 0, 0];
        for _ in 0..10_000 {
            bytes.extend_from_slice(&[1, 0, 0, 0, 0x00, 0x01, 0, 0]);
        }
        bytes.extend_from_slice(&[0, 0, 0, 0]);
        assert!(matches!(
            Bottle::decode(&bytes),
            Err(DecodeError::TooDeep { .. })
        ));
    }

    /// A deterministic pseudo-random Bottle: mixed and homogeneous lists, dicts, strings
    /// and blobs (sometimes large).
    fn random_bottle(next: &mut impl FnMut() -> u64, depth: usize) -> Bottle {
        let mut b = Bottle::new();
        let n = next() % 6;
        let homogeneous = next() % 3 == 1;
        let kind = next() % 10;
        for _ in 0..n {
            let k = if homogeneous { kind } else { next() % 10 };
            let r = next();
            b.push(match k {
                0 => Value::Int8(r as i8),
                1 => Value::Int32(r as i32),
                2 => Value::Int64(r as i64),
                3 => Value::Float64(r as f64),
                4 => Value::Vocab32(Vocab32(r as i32)),
                5 => Value::String(vec![b's'; (r % 20) as usize]),
                6 => {
                    let len = if r % 4 == 1 { 70_000 + r % 9 } else { r % 30 };
                    Value::Blob((0..len).map(|i| i as u8).collect())
                }
                7 if depth < 3 => Value::List(random_bottle(next, depth + 1)),
                8 if depth < 3 => Value::Dict(random_bottle(next, depth + 1)),
                _ => Value::Int16(r as i16),
            });
        }
        b
    }

    #[test]
    fn decode_owned_matches_decode() {
        let mut x: u64 = 0x9e3779b97f4a7c15;
        let mut next = move || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        let mut large = 0;
        for _ in 0..400 {
            let b = random_bottle(&mut next, 0);
            let mut bytes = b.encode();
            if next() % 2 == 1 {
                bytes.extend_from_slice(&[1, 2, 3]);
            }
            let (owned, used) = decode_owned(bytes.clone()).unwrap();
            assert_eq!(owned, b);
            assert_eq!(used, b.encode().len());
            large += usize::from(bytes.len() >= 70_000);
            // corrupt or truncated input: the same error
            for _ in 0..3 {
                let mut bad = bytes.clone();
                if next() % 2 == 1 {
                    bad.truncate((next() as usize) % (bad.len() + 1));
                } else {
                    let at = (next() as usize) % bad.len();
                    bad[at] = next() as u8;
                }
                let a = decode(&bad);
                let o = decode_owned(bad);
                assert_eq!(a, o);
            }
        }
        assert!(large > 10);
        // the large blob keeps the buffer
        let mut b = bottle![1, 2];
        b.add_list()
            .push("x")
            .push(Value::Dict(bottle![bottle!["k", 1]]));
        let mut inner = bottle!["k"];
        inner.push(Value::Blob(vec![5; 200_000]));
        b.push(Value::Dict(bottle![inner]));
        let bytes = b.encode();
        let ptr = bytes.as_ptr();
        let (owned, _) = decode_owned(bytes).unwrap();
        assert_eq!(owned, b);
        let Some(Value::Dict(d)) = owned.get(3) else {
            panic!()
        };
        let Some(Value::List(kv)) = d.get(0) else {
            panic!()
        };
        assert_eq!(
            kv.get(1).and_then(Value::as_bytes).map(<[u8]>::as_ptr),
            Some(ptr)
        );
    }

    fn hex(b: &[u8]) -> String {
        b.iter().map(|x| format!("{x:02x}")).collect()
    }
}

#[cfg(test)]
mod segment_tests {
    use super::*;
    use crate::bottle;

    #[test]
    fn segments_concatenate_to_the_encoding() {
        let big = vec![7u8; LEND_MIN + 3];
        let mut nested = Bottle::new();
        nested.push(Value::Blob(big.clone())).push("x");
        let mut dict = Bottle::new();
        dict.add_list().push("k").push(Value::String(big.clone()));
        let cases = [
            bottle![1, 2, 3],
            bottle![Value::Blob(big.clone())],
            bottle![
                Value::Blob(big.clone()),
                4,
                Value::List(nested),
                Value::Dict(dict)
            ],
            Bottle::new(),
        ];
        for b in cases {
            let joined: Vec<u8> = encode_segments(&b).concat();
            assert_eq!(joined, b.encode());
        }
    }

    #[test]
    fn yarp_4_numbers_floats_anew_and_is_read_as_it_says() {
        let b = Bottle::from_text("1 2.5 (0.5 1.5) [ok]");
        let v4 = encode_as(&b, Generation::V4);
        // the mixed top level tags each element; the list of doubles is compacted
        assert_eq!(&v4[..8], &[0x00, 0x01, 0, 0, 4, 0, 0, 0]);
        assert_eq!(&v4[16..20], &tags::v4::FLOAT64.to_le_bytes());
        assert_eq!(&v4[28..32], &(tags::LIST | tags::v4::FLOAT64).to_le_bytes());
        assert_eq!(generation_of(&v4), Generation::V4);
        assert_eq!(generation_of(&encode(&b)), Generation::V3);
        assert_eq!(decode(&v4).unwrap().0, b);
        assert_eq!(decode_owned(v4.clone()).unwrap().0, b);
        // 4.0's FLOAT32 is 3's FLOAT64: read as 4.0 only when asked
        let f32s = Bottle::from(vec![Value::Float32(0.5)]);
        let bytes = encode_as(&f32s, Generation::V4);
        assert_eq!(decode_as(&bytes, Generation::V4).unwrap().0, f32s);
        assert!(decode(&bytes).is_err(), "4 bytes read as 3.12's float64");
        // without floats both generations write the same bytes
        let plain = Bottle::from_text("[get] [axes] 3 \"s\"");
        assert_eq!(encode_as(&plain, Generation::V4), encode(&plain));
    }
}
