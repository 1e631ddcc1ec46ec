//! Vocabs: up to four characters packed into an int32, as `yarp::os::Vocab32`.

use std::fmt;

/// A 32-bit vocab (`[ok]`, `[set]`, `[pos]` ...). The raw value is what goes on the wire.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct Vocab32(pub i32);

impl Vocab32 {
    /// Vocab 0, which C++ prints as `false`.
    pub const FALSE: Vocab32 = Vocab32(0);
    /// Vocab `'1'`, which C++ prints as `true`.
    pub const TRUE: Vocab32 = Vocab32(b'1' as i32);

    /// Packs four bytes, as `createVocab32(a, b, c, d)`. C++ takes `char`, which is signed,
    /// so bytes above 0x7f are sign-extended before shifting; this keeps that arithmetic.
    pub const fn from_bytes(a: u8, b: u8, c: u8, d: u8) -> Vocab32 {
        let a = a as i8 as i32;
        let b = b as i8 as i32;
        let c = c as i8 as i32;
        let d = d as i8 as i32;
        Vocab32(
            a.wrapping_add(b << 8)
                .wrapping_add(c << 16)
                .wrapping_add(d << 24),
        )
    }

    /// Encodes the first (up to) four bytes of `s`, as `Vocab32::encode`.
    pub fn encode(s: impl AsRef<[u8]>) -> Vocab32 {
        let s = s.as_ref();
        let at = |i: usize| s.get(i).copied().unwrap_or(0);
        Vocab32::from_bytes(at(0), at(1), at(2), at(3))
    }

    /// Const-friendly encoding of a string literal (at most four ASCII characters).
    pub const fn new(s: &str) -> Vocab32 {
        const fn at(b: &[u8], i: usize) -> u8 {
            if i < b.len() {
                b[i]
            } else {
                0
            }
        }
        let b = s.as_bytes();
        Vocab32::from_bytes(at(b, 0), at(b, 1), at(b, 2), at(b, 3))
    }

    /// Decodes as `Vocab32::decode`: bytes taken with C's signed `%` and `/`, and
    /// only positive ones kept (so NUL padding and sign-extended bytes vanish).
    pub fn decode(self) -> Vec<u8> {
        let mut code = self.0;
        let mut out = Vec::with_capacity(4);
        for _ in 0..4 {
            let ch = code % 256;
            if ch > 0 {
                out.push(ch as u8);
            }
            code /= 256;
        }
        out
    }

    /// The decoded characters as a (lossy) string.
    pub fn as_string(self) -> String {
        String::from_utf8_lossy(&self.decode()).into_owned()
    }

    /// Text form inside a Bottle: `[abc]`, or `true` / `false` for the two special values.
    pub fn to_text(self) -> Vec<u8> {
        match self {
            Vocab32::FALSE => b"false".to_vec(),
            Vocab32::TRUE => b"true".to_vec(),
            v => {
                let mut out = Vec::with_capacity(6);
                out.push(b'[');
                out.extend(v.decode());
                out.push(b']');
                out
            }
        }
    }
}

impl fmt::Display for Vocab32 {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&String::from_utf8_lossy(&self.to_text()))
    }
}

impl fmt::Debug for Vocab32 {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Vocab32({self} = {:#x})", self.0)
    }
}

impl From<&str> for Vocab32 {
    fn from(s: &str) -> Self {
        Vocab32::encode(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_layout() {
        let v = Vocab32::new("set");
        assert_eq!(v.0.to_le_bytes(), *b"set\0");
        assert_eq!(v.decode(), b"set");
        assert_eq!(Vocab32::encode("abcde").decode(), b"abcd");
        assert_eq!(Vocab32::encode("").0, 0);
        assert_eq!(Vocab32::TRUE.to_string(), "true");
        assert_eq!(Vocab32::FALSE.to_string(), "false");
        assert_eq!(Vocab32::new("ok").to_string(), "[ok]");
    }

    #[test]
    fn embedded_nul_is_skipped_like_cpp() {
        // bytes a, NUL, b -> C++ decode skips the zero byte
        let v = Vocab32(i32::from_le_bytes([b'a', 0, b'b', 0]));
        assert_eq!(v.decode(), b"ab");
    }
}
