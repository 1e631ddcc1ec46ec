//! The Bottle value model: every element type C++ YARP 3.12 puts in a Bottle.

use crate::tags;
use crate::vocab::Vocab32;
use std::fmt;

/// One Bottle element.
///
/// Strings and blobs are byte vectors: YARP strings are not required to be UTF-8 and may
/// contain NUL, and nothing received may be lost. Use [`Value::as_str`] for text.
#[derive(Clone)]
pub enum Value {
    Int8(i8),
    Int16(i16),
    Int32(i32),
    Int64(i64),
    Float32(f32),
    Float64(f64),
    Vocab32(Vocab32),
    /// YARP 4.0's eight-character vocab (little-endian characters, as C++
    /// `Vocab64::encode64`).
    Vocab64(u64),
    String(Vec<u8>),
    Blob(Vec<u8>),
    List(Bottle),
    /// A dictionary (C++ `Property` inside a Bottle). Its content is kept as the Bottle of
    /// `(key value...)` groups it travels as, in the order received.
    Dict(Bottle),
}

impl Value {
    /// Builds a string value.
    pub fn string(s: impl Into<Vec<u8>>) -> Value {
        Value::String(s.into())
    }

    /// Builds a YARP 4.0 vocab64 value from up to eight characters.
    pub fn vocab64(s: &str) -> Value {
        Value::Vocab64(vocab64_encode(s.as_bytes()))
    }

    /// Builds a vocab value from up to four characters.
    pub fn vocab(s: &str) -> Value {
        Value::Vocab32(Vocab32::encode(s))
    }

    /// The wire tag of this value (lists include their homogeneous subtype, as C++ does).
    pub fn tag(&self) -> i32 {
        self.tag_in(tags::Generation::V3)
    }

    /// The wire tag of this value in `generation`'s numbering.
    pub fn tag_in(&self, generation: tags::Generation) -> i32 {
        match self {
            Value::Int8(_) => tags::INT8,
            Value::Int16(_) => tags::INT16,
            Value::Int32(_) => tags::INT32,
            Value::Int64(_) => tags::INT64,
            Value::Float32(_) => generation.float32(),
            Value::Float64(_) => generation.float64(),
            Value::Vocab32(_) => tags::VOCAB32,
            // 3.x has no vocab64: its readers get the same eight bytes as an int64
            Value::Vocab64(_) => match generation {
                tags::Generation::V3 => tags::INT64,
                tags::Generation::V4 => tags::v4::VOCAB64,
            },
            Value::String(_) => tags::STRING,
            Value::Blob(_) => tags::BLOB,
            Value::List(b) => tags::LIST | b.homogeneous_tag_in(generation),
            Value::Dict(_) => tags::LIST | tags::DICT,
        }
    }

    pub fn is_int(&self) -> bool {
        matches!(
            self,
            Value::Int8(_) | Value::Int16(_) | Value::Int32(_) | Value::Int64(_)
        )
    }
    pub fn is_float(&self) -> bool {
        matches!(self, Value::Float32(_) | Value::Float64(_))
    }
    pub fn is_string(&self) -> bool {
        matches!(self, Value::String(_))
    }
    pub fn is_vocab(&self) -> bool {
        matches!(self, Value::Vocab32(_))
    }
    pub fn is_list(&self) -> bool {
        matches!(self, Value::List(_))
    }

    /// Integer view of any numeric value (C++ `asInt64`: floats truncate, vocabs give
    /// their code); `None` for strings, blobs and lists.
    pub fn as_i64(&self) -> Option<i64> {
        Some(match *self {
            Value::Int8(v) => v as i64,
            Value::Int16(v) => v as i64,
            Value::Int32(v) => v as i64,
            Value::Int64(v) => v,
            Value::Float32(v) => v as i64,
            Value::Float64(v) => v as i64,
            Value::Vocab32(v) => v.0 as i64,
            _ => return None,
        })
    }

    /// `as_i64` narrowed like C++ `asInt32` (a wrapping cast).
    pub fn as_i32(&self) -> Option<i32> {
        self.as_i64().map(|v| v as i32)
    }

    /// Float view of any numeric value (C++ `asFloat64`).
    pub fn as_f64(&self) -> Option<f64> {
        Some(match *self {
            Value::Int8(v) => v as f64,
            Value::Int16(v) => v as f64,
            Value::Int32(v) => v as f64,
            Value::Int64(v) => v as f64,
            Value::Float32(v) => v as f64,
            Value::Float64(v) => v,
            Value::Vocab32(v) => v.0 as f64,
            _ => return None,
        })
    }

    /// Truth value as C++ `asBool`: non-zero numbers and the vocab `true`.
    pub fn as_bool(&self) -> Option<bool> {
        match self {
            Value::Vocab32(v) => Some(v.0 != 0),
            _ => self.as_i64().map(|v| v != 0),
        }
    }

    pub fn as_vocab(&self) -> Option<Vocab32> {
        match *self {
            Value::Vocab32(v) => Some(v),
            _ => None,
        }
    }

    /// The string's text, if this is a string holding valid UTF-8.
    pub fn as_str(&self) -> Option<&str> {
        match self {
            Value::String(s) => std::str::from_utf8(s).ok(),
            _ => None,
        }
    }

    /// The raw bytes of a string or blob.
    pub fn as_bytes(&self) -> Option<&[u8]> {
        match self {
            Value::String(s) | Value::Blob(s) => Some(s),
            _ => None,
        }
    }

    pub fn as_list(&self) -> Option<&Bottle> {
        match self {
            Value::List(b) => Some(b),
            _ => None,
        }
    }

    pub fn as_list_mut(&mut self) -> Option<&mut Bottle> {
        match self {
            Value::List(b) => Some(b),
            _ => None,
        }
    }

    pub fn as_dict(&self) -> Option<&Bottle> {
        match self {
            Value::Dict(b) => Some(b),
            _ => None,
        }
    }

    /// Text of this value on its own (C++ `Value::toString`): strings unquoted, lists
    /// without their outer parentheses, vocabs without brackets.
    pub fn to_text_bare(&self) -> Vec<u8> {
        crate::text::value_to_text(self, false)
    }

    /// [`Self::to_text_bare`] as a `String`: what icub-main reads with `asString` or
    /// `toString` (a string's own text, a number's digits).
    pub fn to_string_bare(&self) -> String {
        String::from_utf8_lossy(&self.to_text_bare()).into_owned()
    }
}

impl PartialEq for Value {
    /// Exact equality: floats compare by bit pattern so that NaN == NaN and -0.0 != 0.0,
    /// which is what "the same bytes on the wire" means.
    fn eq(&self, other: &Self) -> bool {
        use Value::*;
        match (self, other) {
            (Int8(a), Int8(b)) => a == b,
            (Int16(a), Int16(b)) => a == b,
            (Int32(a), Int32(b)) => a == b,
            (Int64(a), Int64(b)) => a == b,
            (Float32(a), Float32(b)) => a.to_bits() == b.to_bits(),
            (Float64(a), Float64(b)) => a.to_bits() == b.to_bits(),
            (Vocab32(a), Vocab32(b)) => a == b,
            (String(a), String(b)) => a == b,
            (Blob(a), Blob(b)) => a == b,
            (List(a), List(b)) => a == b,
            (Vocab64(a), Vocab64(b)) => a == b,
            (Dict(a), Dict(b)) => a == b,
            _ => false,
        }
    }
}

impl fmt::Debug for Value {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Value::Int8(v) => write!(f, "Int8({v})"),
            Value::Int16(v) => write!(f, "Int16({v})"),
            Value::Int32(v) => write!(f, "Int32({v})"),
            Value::Int64(v) => write!(f, "Int64({v})"),
            Value::Float32(v) => write!(f, "Float32({v:?})"),
            Value::Float64(v) => write!(f, "Float64({v:?})"),
            Value::Vocab32(v) => write!(f, "{v:?}"),
            Value::Vocab64(v) => write!(
                f,
                "Vocab64([{}])",
                String::from_utf8_lossy(&vocab64_decode(*v))
            ),
            Value::String(s) => write!(f, "String({:?})", String::from_utf8_lossy(s)),
            Value::Blob(b) => write!(f, "Blob({b:?})"),
            Value::List(b) => write!(f, "List({b})"),
            Value::Dict(b) => write!(f, "Dict({b})"),
        }
    }
}

impl fmt::Display for Value {
    /// The nested text form, as an element inside a Bottle (`"quoted strings"`, `[vocab]`).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&String::from_utf8_lossy(&crate::text::value_to_text(
            self, true,
        )))
    }
}

macro_rules! value_from {
    ($($t:ty => $v:ident),*) => {$(
        impl From<$t> for Value {
            fn from(x: $t) -> Value { Value::$v(x) }
        }
    )*};
}
value_from!(i8 => Int8, i16 => Int16, i32 => Int32, i64 => Int64, f32 => Float32,
            f64 => Float64, Vocab32 => Vocab32, Bottle => List);

impl From<&str> for Value {
    fn from(s: &str) -> Value {
        Value::String(s.as_bytes().to_vec())
    }
}
impl From<String> for Value {
    fn from(s: String) -> Value {
        Value::String(s.into_bytes())
    }
}
impl From<bool> for Value {
    fn from(b: bool) -> Value {
        Value::Vocab32(if b { Vocab32::TRUE } else { Vocab32::FALSE })
    }
}

/// A Bottle: an ordered list of [`Value`]s, the unit of data in YARP.
#[derive(Clone, Default, PartialEq)]
pub struct Bottle {
    items: Vec<Value>,
}

impl Bottle {
    pub fn new() -> Bottle {
        Bottle { items: Vec::new() }
    }

    pub fn with_capacity(n: usize) -> Bottle {
        Bottle {
            items: Vec::with_capacity(n),
        }
    }

    /// Parses YARP text, exactly as C++ `Bottle::fromString` (never fails: text C++ cannot
    /// make sense of yields what C++ yields, often an empty Bottle).
    pub fn from_text(text: impl AsRef<[u8]>) -> Bottle {
        crate::text::parse(text.as_ref())
    }

    /// The text form as C++ `Bottle::toString` prints it, as raw bytes.
    pub fn to_text(&self) -> Vec<u8> {
        crate::text::bottle_to_text(self)
    }

    /// The binary encoding, exactly as C++ writes it.
    pub fn encode(&self) -> Vec<u8> {
        crate::binary::encode(self)
    }

    /// The binary encoding for a peer of `generation` (YARP 4.0 numbers floats anew).
    pub fn encode_as(&self, generation: crate::tags::Generation) -> Vec<u8> {
        crate::binary::encode_as(self, generation)
    }

    /// Decodes a binary Bottle. Trailing bytes after the Bottle are ignored, as C++ does.
    /// A Bottle of C++ YARP 4.0 is read as one when it says so (a tag only 4.0 has).
    pub fn decode(bytes: &[u8]) -> Result<Bottle, crate::DecodeError> {
        crate::binary::decode(bytes).map(|(b, _)| b)
    }

    /// [`Bottle::decode`] from a buffer it may keep: a large string or blob that makes up
    /// most of `bytes` takes over the buffer instead of being copied.
    pub fn decode_owned(bytes: Vec<u8>) -> Result<Bottle, crate::DecodeError> {
        crate::binary::decode_owned(bytes).map(|(b, _)| b)
    }

    pub fn len(&self) -> usize {
        self.items.len()
    }
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }
    pub fn get(&self, i: usize) -> Option<&Value> {
        self.items.get(i)
    }
    pub fn get_mut(&mut self, i: usize) -> Option<&mut Value> {
        self.items.get_mut(i)
    }
    pub fn iter(&self) -> std::slice::Iter<'_, Value> {
        self.items.iter()
    }
    pub fn items(&self) -> &[Value] {
        &self.items
    }
    pub fn into_items(self) -> Vec<Value> {
        self.items
    }
    pub fn clear(&mut self) {
        self.items.clear()
    }
    pub fn pop(&mut self) -> Option<Value> {
        self.items.pop()
    }

    /// Appends any value (`b.push(1)`, `b.push("text")`, `b.push(Vocab32::new("ok"))`).
    pub fn push(&mut self, v: impl Into<Value>) -> &mut Self {
        self.items.push(v.into());
        self
    }

    /// Builder-style append.
    pub fn with(mut self, v: impl Into<Value>) -> Self {
        self.items.push(v.into());
        self
    }

    pub fn add_vocab(&mut self, s: &str) -> &mut Self {
        self.push(Vocab32::encode(s))
    }

    /// Appends a nested list and returns it for filling.
    pub fn add_list(&mut self) -> &mut Bottle {
        self.items.push(Value::List(Bottle::new()));
        match self.items.last_mut() {
            Some(Value::List(b)) => b,
            _ => unreachable!("just pushed a list"),
        }
    }

    /// The tag of the homogeneous (compacted) form, or 0 when elements must be tagged:
    /// C++ compacts a non-empty list whose elements all share one simple type.
    pub fn homogeneous_tag(&self) -> i32 {
        self.homogeneous_tag_in(tags::Generation::V3)
    }

    /// [`Bottle::homogeneous_tag`] in `generation`'s numbering.
    pub fn homogeneous_tag_in(&self, generation: tags::Generation) -> i32 {
        let mut first = None;
        for v in &self.items {
            let t = v.tag_in(generation);
            match first {
                None => first = Some(t),
                Some(f) if f != t => return 0,
                _ => {}
            }
        }
        match first {
            Some(t) if t & tags::GROUP_MASK == 0 => t,
            _ => 0,
        }
    }

    /// Key lookup as C++ `Bottle::find`: the element after a matching key, or the second
    /// element of a nested `(key value)` group.
    pub fn find(&self, key: &str) -> Option<&Value> {
        for (i, v) in self.items.iter().enumerate() {
            match v {
                Value::List(group) if group.get(0).is_some_and(|k| key_matches(k, key)) => {
                    return group.get(1);
                }
                other if key_matches(other, key) => return self.items.get(i + 1),
                _ => {}
            }
        }
        None
    }

    /// Group lookup as C++ `Bottle::findGroup`: the nested list whose first element is `key`.
    pub fn find_group(&self, key: &str) -> Option<&Bottle> {
        self.items.iter().find_map(|v| match v {
            Value::List(group) if group.get(0).is_some_and(|k| key_matches(k, key)) => Some(group),
            _ => None,
        })
    }

    /// Whether `find` or `find_group` would succeed (C++ `check`).
    pub fn check(&self, key: &str) -> bool {
        self.find_group(key).is_some() || self.find(key).is_some()
    }

    /// `find(key)` or a default when absent.
    pub fn find_or(&self, key: &str, default: impl Into<Value>) -> Value {
        self.find(key).cloned().unwrap_or_else(|| default.into())
    }
}

/// C++ compares keys with `Value::toString()`: a string's bare text, a vocab without
/// brackets, a number's digits. Lists and blobs never match.
fn key_matches(v: &Value, key: &str) -> bool {
    match v {
        Value::String(s) => s == key.as_bytes(),
        Value::List(_) | Value::Dict(_) | Value::Blob(_) => false,
        other => other.to_text_bare() == key.as_bytes(),
    }
}

impl fmt::Display for Bottle {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&String::from_utf8_lossy(&self.to_text()))
    }
}

impl fmt::Debug for Bottle {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Bottle({self})")
    }
}

impl std::ops::Index<usize> for Bottle {
    type Output = Value;
    fn index(&self, i: usize) -> &Value {
        &self.items[i]
    }
}

impl<V: Into<Value>> FromIterator<V> for Bottle {
    fn from_iter<I: IntoIterator<Item = V>>(iter: I) -> Self {
        Bottle {
            items: iter.into_iter().map(Into::into).collect(),
        }
    }
}

impl From<Vec<Value>> for Bottle {
    fn from(items: Vec<Value>) -> Self {
        Bottle { items }
    }
}

impl IntoIterator for Bottle {
    type Item = Value;
    type IntoIter = std::vec::IntoIter<Value>;
    fn into_iter(self) -> Self::IntoIter {
        self.items.into_iter()
    }
}

impl<'a> IntoIterator for &'a Bottle {
    type Item = &'a Value;
    type IntoIter = std::slice::Iter<'a, Value>;
    fn into_iter(self) -> Self::IntoIter {
        self.items.iter()
    }
}

impl Extend<Value> for Bottle {
    fn extend<I: IntoIterator<Item = Value>>(&mut self, iter: I) {
        self.items.extend(iter)
    }
}

/// Builds a Bottle from values: `bottle![Vocab32::new("set"), 0, 100.0]`.
#[macro_export]
macro_rules! bottle {
    () => { $crate::Bottle::new() };
    ($($v:expr),+ $(,)?) => {{
        let mut b = $crate::Bottle::new();
        $( b.push($v); )+
        b
    }};
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn find_and_groups_like_cpp() {
        let b = Bottle::from_text("name /foo (axes 4) (gains 1.0 2.0) [ok] 7");
        assert_eq!(b.find("name").and_then(Value::as_str), Some("/foo"));
        assert_eq!(b.find("axes"), Some(&Value::Int32(4)));
        assert_eq!(b.find("ok"), Some(&Value::Int32(7)));
        assert_eq!(b.find_group("gains").map(|g| g.len()), Some(3));
        assert!(b.check("gains") && b.check("name") && !b.check("missing"));
        assert_eq!(b.find_or("missing", 3), Value::Int32(3));
    }

    #[test]
    fn builders_and_accessors() {
        let mut b = bottle![Vocab32::new("set"), 0, 1.5, "x", true];
        b.add_list().push(1).push(2);
        assert_eq!(b.to_string(), "[set] 0 1.5 x true (1 2)");
        assert_eq!(b[1].as_f64(), Some(0.0));
        assert_eq!(b[2].as_i32(), Some(1));
        assert_eq!(b[4].as_bool(), Some(true));
        assert_eq!(b[5].as_list().map(Bottle::len), Some(2));
        assert!(Value::Float64(f64::NAN) == Value::Float64(f64::NAN));
        assert!(Value::Float64(0.0) != Value::Float64(-0.0));
        let collected: Bottle = [1, 2, 3].into_iter().collect();
        assert_eq!(collected.homogeneous_tag(), crate::tags::INT32);
    }
}

/// C++ `Vocab64::encode64`: up to eight characters, the first in the lowest byte.
pub fn vocab64_encode(chars: &[u8]) -> u64 {
    chars
        .iter()
        .take(8)
        .enumerate()
        .fold(0, |code, (i, &c)| code | (u64::from(c) << (8 * i)))
}

/// C++ `Vocab64::decode64`: the characters, zero bytes skipped.
pub fn vocab64_decode(code: u64) -> Vec<u8> {
    code.to_le_bytes().into_iter().filter(|&c| c != 0).collect()
}

#[cfg(test)]
mod vocab64_tests {
    use super::*;
    use crate::tags::Generation;

    #[test]
    fn vocab64_in_each_generation_and_as_text() {
        let b = Bottle::new().with(Value::vocab64("velocity")).with(7);
        let v4 = b.encode_as(Generation::V4);
        // list, 2 elements, tag 18 and the characters, lowest first
        assert_eq!(&v4[8..12], &18i32.to_le_bytes());
        assert_eq!(&v4[12..20], b"velocity");
        assert_eq!(crate::binary::decode_as(&v4, Generation::V4).unwrap().0, b);
        assert_eq!(Bottle::decode(&v4).unwrap(), b, "told apart by its tag");
        // 3.x has no vocab64: the same bytes as an int64
        let v3 = b.encode();
        assert_eq!(&v3[8..12], &crate::tags::INT64.to_le_bytes());
        assert_eq!(b.to_string(), "[velocity] 7");
        assert_eq!(Value::vocab64("ok").to_string(), "[ok]");
        assert_eq!(Value::Vocab64(0).to_string(), "false");
    }
}
