//! ROS messages as dynamic values, encoded and decoded by serde against a catalog type.
//!
//! The gateway carries many message types through one code path: a [`Value`] tree
//! serializes to exactly the CDR layout of the [`crate::types`] description (structs as
//! tuples, sequences length-prefixed, `uint8[]` as one byte block), and [`MsgSeed`]
//! decodes CDR back into a [`Value`] guided by the same description.

use crate::types::{lookup, Base, Field, MsgType, Prim, Shape};
use serde::de::{self, DeserializeSeed, SeqAccess, Visitor};
use serde::ser::{SerializeSeq, SerializeTuple};
use serde::{Deserializer, Serialize, Serializer};
use std::fmt;

/// A `builtin_interfaces/Duration` below zero, where a time from now is needed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NegativeDuration;

/// One value of a ROS message (a whole message is a [`Value::Struct`]).
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    Bool(bool),
    I8(i8),
    U8(u8),
    I16(i16),
    U16(u16),
    I32(i32),
    U32(u32),
    I64(i64),
    U64(u64),
    F32(f32),
    F64(f64),
    Str(String),
    /// A `wstring` (UTF-16 on the wire).
    WStr(String),
    /// `uint8[]` / `byte[]` sequences.
    Bytes(Vec<u8>),
    /// Unbounded or bounded sequences of anything else.
    List(Vec<Value>),
    /// Fixed-size arrays.
    Array(Vec<Value>),
    /// A nested message: its fields in declaration order.
    Struct(Vec<Value>),
}

impl Value {
    /// The default value of a type, as rosidl's default constructor gives it: the
    /// `.msg` default values where the definition has them, else zeros and empties.
    pub fn zero(type_name: &str) -> Option<Value> {
        let t = lookup(type_name)?;
        t.fields
            .iter()
            .map(field_default)
            .collect::<Option<Vec<_>>>()
            .map(Value::Struct)
    }

    /// A number as f64 (ints and floats), for conversions.
    pub fn as_f64(&self) -> Option<f64> {
        Some(match *self {
            Value::I8(v) => v.into(),
            Value::U8(v) => v.into(),
            Value::I16(v) => v.into(),
            Value::U16(v) => v.into(),
            Value::I32(v) => v.into(),
            Value::U32(v) => v.into(),
            Value::I64(v) => v as f64,
            Value::U64(v) => v as f64,
            Value::F32(v) => v.into(),
            Value::F64(v) => v,
            _ => return None,
        })
    }

    /// A `builtin_interfaces/msg/Time` of `ns` nanoseconds since the epoch.
    pub fn time(ns: u64) -> Value {
        Value::Struct(vec![
            Value::I32((ns / 1_000_000_000) as i32),
            Value::U32((ns % 1_000_000_000) as u32),
        ])
    }

    /// The elements of a sequence.
    pub fn as_list(&self) -> Option<&[Value]> {
        match self {
            Value::List(l) => Some(l),
            _ => None,
        }
    }

    /// A sequence of numbers as f64s.
    pub fn as_f64s(&self) -> Option<Vec<f64>> {
        self.as_list()?.iter().map(Value::as_f64).collect()
    }

    /// A sequence of strings.
    pub fn as_strings(&self) -> Option<Vec<String>> {
        self.as_list()?
            .iter()
            .map(|x| match x {
                Value::Str(s) => Some(s.clone()),
                _ => None,
            })
            .collect()
    }

    /// A `builtin_interfaces/Duration`: `Err` when it is negative.
    pub fn as_duration(&self) -> Option<Result<std::time::Duration, NegativeDuration>> {
        match self.fields()? {
            [Value::I32(s), Value::U32(ns)] => Some(match u64::try_from(*s) {
                Ok(s) => Ok(std::time::Duration::new(s, 0)
                    + std::time::Duration::from_nanos(u64::from(*ns))),
                Err(_) => Err(NegativeDuration),
            }),
            _ => None,
        }
    }

    /// Fields of a struct value.
    pub fn fields(&self) -> Option<&[Value]> {
        match self {
            Value::Struct(f) => Some(f),
            _ => None,
        }
    }

    /// Sets field `name` of a struct value of type `ty` (false if it has none: a field
    /// that only some releases of a type have).
    pub fn set(&mut self, ty: &MsgType, name: &str, v: Value) -> bool {
        let i = ty.fields.iter().position(|f| f.name == name);
        match (self, i) {
            (Value::Struct(f), Some(i)) if i < f.len() => {
                f[i] = v;
                true
            }
            _ => false,
        }
    }

    /// Whether this value has exactly the shape of catalog type `type_name`.
    pub fn conforms_to(&self, type_name: &str) -> bool {
        match (lookup(type_name), self) {
            (Some(t), Value::Struct(vals)) => {
                vals.len() == t.fields.len()
                    && t.fields.iter().zip(vals).all(|(f, v)| field_conforms(f, v))
            }
            _ => false,
        }
    }
}

fn zero_prim(p: Prim) -> Value {
    match p {
        Prim::Bool => Value::Bool(false),
        Prim::Byte | Prim::U8 => Value::U8(0),
        Prim::I8 => Value::I8(0),
        Prim::I16 => Value::I16(0),
        Prim::U16 => Value::U16(0),
        Prim::I32 => Value::I32(0),
        Prim::U32 => Value::U32(0),
        Prim::I64 => Value::I64(0),
        Prim::U64 => Value::U64(0),
        Prim::F32 => Value::F32(0.0),
        Prim::F64 => Value::F64(0.0),
        Prim::String => Value::Str(String::new()),
        Prim::WString => Value::WStr(String::new()),
    }
}

/// One primitive value from its `.msg` text (rosidl's rules: `true`/`1`/`false`/`0`,
/// decimal or `0x` integers, quoted or bare strings).
pub fn parse_prim(p: Prim, text: &str) -> Option<Value> {
    let t = text.trim();
    let int = || -> Option<i128> {
        let (neg, digits) = match t.strip_prefix('-') {
            Some(d) => (true, d),
            None => (false, t.strip_prefix('+').unwrap_or(t)),
        };
        let v = if let Some(h) = digits
            .strip_prefix("0x")
            .or_else(|| digits.strip_prefix("0X"))
        {
            i128::from_str_radix(h, 16).ok()?
        } else if let Some(o) = digits.strip_prefix("0o") {
            i128::from_str_radix(o, 8).ok()?
        } else if let Some(b) = digits.strip_prefix("0b") {
            i128::from_str_radix(b, 2).ok()?
        } else {
            digits.parse().ok()?
        };
        Some(if neg { -v } else { v })
    };
    Some(match p {
        Prim::Bool => match t.to_ascii_lowercase().as_str() {
            "true" | "1" => Value::Bool(true),
            "false" | "0" => Value::Bool(false),
            _ => return None,
        },
        Prim::Byte | Prim::U8 => Value::U8(int()?.try_into().ok()?),
        Prim::I8 => Value::I8(int()?.try_into().ok()?),
        Prim::I16 => Value::I16(int()?.try_into().ok()?),
        Prim::U16 => Value::U16(int()?.try_into().ok()?),
        Prim::I32 => Value::I32(int()?.try_into().ok()?),
        Prim::U32 => Value::U32(int()?.try_into().ok()?),
        Prim::I64 => Value::I64(int()?.try_into().ok()?),
        Prim::U64 => Value::U64(int()?.try_into().ok()?),
        Prim::F32 => Value::F32(t.parse().ok()?),
        Prim::F64 => Value::F64(t.parse().ok()?),
        Prim::String => Value::Str(crate::msgdef::unquote(t)),
        Prim::WString => Value::WStr(crate::msgdef::unquote(t)),
    })
}

/// A field's value in a default-constructed message: its `.msg` default, else zero.
pub fn field_default(f: &Field) -> Option<Value> {
    default_field(f).or_else(|| zero_field(f))
}

/// A field's `.msg` default value, if it has one that fits.
fn default_field(f: &Field) -> Option<Value> {
    let (Base::Prim(p), Some(text)) = (f.base, f.default) else {
        return None;
    };
    let items = || -> Option<Vec<Value>> {
        crate::msgdef::split_array_default(text)?
            .iter()
            .map(|e| parse_prim(p, e))
            .collect()
    };
    Some(match f.shape {
        Shape::Single => parse_prim(p, text)?,
        Shape::Array(n) => {
            let v = items()?;
            (v.len() as u64 == n).then_some(Value::Array(v))?
        }
        Shape::Seq | Shape::BoundedSeq(_) if is_bytes(f.base) => Value::Bytes(
            items()?
                .into_iter()
                .map(|v| match v {
                    Value::U8(b) => Some(b),
                    _ => None,
                })
                .collect::<Option<_>>()?,
        ),
        Shape::Seq | Shape::BoundedSeq(_) => Value::List(items()?),
    })
}

fn zero_single(b: Base) -> Option<Value> {
    match b {
        Base::Prim(p) => Some(zero_prim(p)),
        Base::Nested(n) => Value::zero(n),
    }
}

fn is_bytes(b: Base) -> bool {
    matches!(b, Base::Prim(Prim::U8 | Prim::Byte))
}

fn zero_field(f: &Field) -> Option<Value> {
    Some(match f.shape {
        Shape::Single => zero_single(f.base)?,
        Shape::Array(n) => Value::Array(
            (0..n)
                .map(|_| zero_single(f.base))
                .collect::<Option<Vec<_>>>()?,
        ),
        Shape::Seq | Shape::BoundedSeq(_) if is_bytes(f.base) => Value::Bytes(Vec::new()),
        Shape::Seq | Shape::BoundedSeq(_) => Value::List(Vec::new()),
    })
}

fn single_conforms(b: Base, v: &Value) -> bool {
    match b {
        Base::Nested(n) => v.conforms_to(n),
        Base::Prim(p) => matches!(
            (p, v),
            (Prim::Bool, Value::Bool(_))
                | (Prim::Byte | Prim::U8, Value::U8(_))
                | (Prim::I8, Value::I8(_))
                | (Prim::I16, Value::I16(_))
                | (Prim::U16, Value::U16(_))
                | (Prim::I32, Value::I32(_))
                | (Prim::U32, Value::U32(_))
                | (Prim::I64, Value::I64(_))
                | (Prim::U64, Value::U64(_))
                | (Prim::F32, Value::F32(_))
                | (Prim::F64, Value::F64(_))
                | (Prim::String, Value::Str(_))
                | (Prim::WString, Value::WStr(_))
        ),
    }
}

fn field_conforms(f: &Field, v: &Value) -> bool {
    match (f.shape, v) {
        (Shape::Single, v) => single_conforms(f.base, v),
        (Shape::Array(n), Value::Array(items)) => {
            items.len() as u64 == n && items.iter().all(|i| single_conforms(f.base, i))
        }
        (Shape::Seq | Shape::BoundedSeq(_), Value::Bytes(_)) => is_bytes(f.base),
        (Shape::Seq, Value::List(items)) => {
            !is_bytes(f.base) && items.iter().all(|i| single_conforms(f.base, i))
        }
        (Shape::BoundedSeq(n), Value::List(items)) => {
            !is_bytes(f.base)
                && items.len() as u64 <= n
                && items.iter().all(|i| single_conforms(f.base, i))
        }
        _ => false,
    }
}

impl Serialize for Value {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Value::Bool(v) => s.serialize_bool(*v),
            Value::I8(v) => s.serialize_i8(*v),
            Value::U8(v) => s.serialize_u8(*v),
            Value::I16(v) => s.serialize_i16(*v),
            Value::U16(v) => s.serialize_u16(*v),
            Value::I32(v) => s.serialize_i32(*v),
            Value::U32(v) => s.serialize_u32(*v),
            Value::I64(v) => s.serialize_i64(*v),
            Value::U64(v) => s.serialize_u64(*v),
            Value::F32(v) => s.serialize_f32(*v),
            Value::F64(v) => s.serialize_f64(*v),
            Value::Str(v) => s.serialize_str(v),
            // rmw_fastrtps: a u32 length, then each UTF-16 unit as a 4-byte wchar.
            Value::WStr(v) => {
                let units: Vec<u16> = v.encode_utf16().collect();
                let mut seq = s.serialize_seq(Some(units.len()))?;
                for u in units {
                    seq.serialize_element(&u32::from(u))?;
                }
                seq.end()
            }
            Value::Bytes(v) => s.serialize_bytes(v),
            Value::List(items) => {
                let mut seq = s.serialize_seq(Some(items.len()))?;
                for i in items {
                    seq.serialize_element(i)?;
                }
                seq.end()
            }
            Value::Array(items) | Value::Struct(items) => {
                let mut t = s.serialize_tuple(items.len())?;
                for i in items {
                    t.serialize_element(i)?;
                }
                t.end()
            }
        }
    }
}

/// A [`Value`] has no type of its own to decode against: it is read with its type's
/// [`MsgSeed`] (ros2-client's `*_seed` calls). This impl only lets it travel through
/// ros2-client's typed services and publishers, and refuses.
impl<'de> serde::Deserialize<'de> for Value {
    fn deserialize<D: Deserializer<'de>>(_: D) -> Result<Value, D::Error> {
        Err(de::Error::custom(
            "a message of a run-time type is decoded with its MsgSeed",
        ))
    }
}

impl ros2_client::Message for Value {}

/// Decodes one message of a catalog type (use with ros2-client's `async_stream_seed`).
#[derive(Debug, Clone, Copy)]
pub struct MsgSeed(pub &'static MsgType);

impl MsgSeed {
    pub fn new(type_name: &str) -> Option<MsgSeed> {
        lookup(type_name).map(MsgSeed)
    }
}

impl<'de> DeserializeSeed<'de> for MsgSeed {
    type Value = Value;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<Value, D::Error> {
        d.deserialize_tuple(self.0.fields.len(), StructVisitor(self.0))
    }
}

struct StructVisitor(&'static MsgType);

impl<'de> Visitor<'de> for StructVisitor {
    type Value = Value;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "a {}", self.0.name)
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Value, A::Error> {
        let mut out = Vec::with_capacity(self.0.fields.len());
        for field in self.0.fields {
            let v = seq
                .next_element_seed(FieldSeed(field))?
                .ok_or_else(|| de::Error::custom(format!("{} ends early", self.0.name)))?;
            out.push(v);
        }
        Ok(Value::Struct(out))
    }
}

struct FieldSeed(&'static Field);

impl<'de> DeserializeSeed<'de> for FieldSeed {
    type Value = Value;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<Value, D::Error> {
        let f = self.0;
        match f.shape {
            Shape::Single => SingleSeed(f.base).deserialize(d),
            Shape::Array(n) => d.deserialize_tuple(
                n as usize,
                ListVisitor {
                    base: f.base,
                    fixed: true,
                },
            ),
            Shape::Seq | Shape::BoundedSeq(_) if is_bytes(f.base) => {
                d.deserialize_byte_buf(PrimVisitor)
            }
            Shape::Seq | Shape::BoundedSeq(_) => d.deserialize_seq(ListVisitor {
                base: f.base,
                fixed: false,
            }),
        }
    }
}

struct ListVisitor {
    base: Base,
    fixed: bool,
}

impl<'de> Visitor<'de> for ListVisitor {
    type Value = Value;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a sequence")
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Value, A::Error> {
        // Cap the pre-allocation: the length prefix comes from the network.
        let mut out = Vec::with_capacity(seq.size_hint().unwrap_or(0).min(4096));
        if let Base::Nested(n) = self.base {
            // Resolved once for the whole sequence, not per element.
            let t =
                lookup(n).ok_or_else(|| de::Error::custom(format!("unknown nested type {n}")))?;
            while let Some(v) = seq.next_element_seed(MsgSeed(t))? {
                out.push(v);
            }
        } else {
            while let Some(v) = seq.next_element_seed(SingleSeed(self.base))? {
                out.push(v);
            }
        }
        Ok(if self.fixed {
            Value::Array(out)
        } else {
            Value::List(out)
        })
    }
}

#[derive(Clone, Copy)]
struct SingleSeed(Base);

impl<'de> DeserializeSeed<'de> for SingleSeed {
    type Value = Value;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<Value, D::Error> {
        let p = match self.0 {
            Base::Nested(n) => {
                let t = lookup(n)
                    .ok_or_else(|| de::Error::custom(format!("unknown nested type {n}")))?;
                return MsgSeed(t).deserialize(d);
            }
            Base::Prim(p) => p,
        };
        match p {
            Prim::Bool => d.deserialize_bool(PrimVisitor),
            Prim::Byte | Prim::U8 => d.deserialize_u8(PrimVisitor),
            Prim::I8 => d.deserialize_i8(PrimVisitor),
            Prim::I16 => d.deserialize_i16(PrimVisitor),
            Prim::U16 => d.deserialize_u16(PrimVisitor),
            Prim::I32 => d.deserialize_i32(PrimVisitor),
            Prim::U32 => d.deserialize_u32(PrimVisitor),
            Prim::I64 => d.deserialize_i64(PrimVisitor),
            Prim::U64 => d.deserialize_u64(PrimVisitor),
            Prim::F32 => d.deserialize_f32(PrimVisitor),
            Prim::F64 => d.deserialize_f64(PrimVisitor),
            Prim::String => d.deserialize_string(PrimVisitor),
            Prim::WString => d.deserialize_seq(WStrVisitor),
        }
    }
}

/// A `wstring`: its wchars (4 bytes each) as UTF-16 units.
struct WStrVisitor;

impl<'de> Visitor<'de> for WStrVisitor {
    type Value = Value;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a wstring")
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Value, A::Error> {
        let mut units = Vec::with_capacity(seq.size_hint().unwrap_or(0).min(4096));
        while let Some(u) = seq.next_element::<u32>()? {
            units.push(u as u16);
        }
        Ok(Value::WStr(String::from_utf16_lossy(&units)))
    }
}

/// Accepts whatever primitive the deserializer was asked for.
struct PrimVisitor;

macro_rules! visit {
    ($($fn:ident $t:ty => $v:ident),* $(,)?) => {
        $(fn $fn<E: de::Error>(self, v: $t) -> Result<Value, E> { Ok(Value::$v(v)) })*
    };
}

impl<'de> Visitor<'de> for PrimVisitor {
    type Value = Value;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a primitive value")
    }
    visit!(visit_bool bool => Bool, visit_i8 i8 => I8, visit_u8 u8 => U8, visit_i16 i16 => I16,
           visit_u16 u16 => U16, visit_i32 i32 => I32, visit_u32 u32 => U32,
           visit_i64 i64 => I64, visit_u64 u64 => U64, visit_f32 f32 => F32,
           visit_f64 f64 => F64, visit_string String => Str, visit_byte_buf Vec<u8> => Bytes);
    fn visit_str<E: de::Error>(self, v: &str) -> Result<Value, E> {
        Ok(Value::Str(v.to_string()))
    }
    fn visit_bytes<E: de::Error>(self, v: &[u8]) -> Result<Value, E> {
        Ok(Value::Bytes(v.to_vec()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use byteorder::LittleEndian;

    fn decode(bytes: &[u8], seed: MsgSeed) -> Result<(Value, usize), cdr_encoding::Error> {
        let mut d = cdr_encoding::CdrDeserializer::<LittleEndian>::new(bytes);
        let v = seed.deserialize(&mut d)?;
        Ok((v, d.bytes_consumed()))
    }

    fn roundtrip(type_name: &str, v: &Value) -> Vec<u8> {
        assert!(v.conforms_to(type_name), "{v:?} is not a {type_name}");
        let bytes = cdr_encoding::to_vec::<_, LittleEndian>(v).unwrap();
        let (back, used) = decode(&bytes, MsgSeed::new(type_name).unwrap()).unwrap();
        assert_eq!(&back, v);
        assert_eq!(used, bytes.len());
        bytes
    }

    #[test]
    fn string_layout_is_cdr() {
        let b = roundtrip(
            "std_msgs/msg/String",
            &Value::Struct(vec![Value::Str("hi".into())]),
        );
        assert_eq!(b, [3, 0, 0, 0, b'h', b'i', 0]);
    }

    #[test]
    fn zero_values_conform_and_roundtrip() {
        for t in crate::types::MESSAGES {
            let z = Value::zero(t.name).unwrap();
            roundtrip(t.name, &z);
        }
    }

    #[test]
    fn nested_sequences_and_alignment() {
        let dim = Value::Struct(vec![
            Value::Str("rows".into()),
            Value::U32(2),
            Value::U32(6),
        ]);
        let layout = Value::Struct(vec![Value::List(vec![dim]), Value::U32(0)]);
        let m = Value::Struct(vec![
            layout,
            Value::List((0..6).map(|i| Value::F64(i as f64)).collect()),
        ]);
        let b = roundtrip("std_msgs/msg/Float64MultiArray", &m);
        // dim count 4, label 4+5 ("rows\0") + 3 pad, size 4, stride 4, data_offset 4,
        // data length 4 (now at 32: f64-aligned), 6 doubles 48.
        assert_eq!(b.len(), 80);
    }

    #[test]
    fn bytes_and_fixed_arrays() {
        let mut img = Value::zero("sensor_msgs/msg/Image").unwrap();
        if let Value::Struct(f) = &mut img {
            f[6] = Value::Bytes(vec![1, 2, 3]);
        }
        roundtrip("sensor_msgs/msg/Image", &img);
        let imu = Value::zero("sensor_msgs/msg/Imu").unwrap();
        roundtrip("sensor_msgs/msg/Imu", &imu);
    }

    #[test]
    fn truncated_input_is_an_error_not_a_panic() {
        let seed = MsgSeed::new("std_msgs/msg/Float64MultiArray").unwrap();
        for bytes in [&[][..], &[1, 0, 0, 0], &[255, 255, 255, 255, 0, 0]] {
            assert!(decode(bytes, seed).is_err());
        }
    }

    /// Network input: random bytes and corrupted valid messages of every catalog type
    /// decode to a value or an error, never a panic (a cheap stand-in for a fuzz target,
    /// which would drag RustDDS into the fuzz build).
    #[test]
    fn garbage_of_every_type_is_an_error_or_a_value_never_a_panic() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for t in crate::types::MESSAGES {
            let Some(seed) = MsgSeed::new(t.name) else {
                continue;
            };
            let valid =
                cdr_encoding::to_vec::<_, LittleEndian>(&Value::zero(t.name).unwrap()).unwrap();
            for round in 0..2000 {
                let mut bytes = if round % 2 == 0 {
                    let len = (next() % 200) as usize;
                    (0..len).map(|_| next() as u8).collect::<Vec<u8>>()
                } else {
                    valid.clone()
                };
                if !bytes.is_empty() {
                    for _ in 0..1 + next() % 4 {
                        let i = (next() as usize) % bytes.len();
                        bytes[i] = next() as u8;
                    }
                    bytes.truncate((next() as usize) % (bytes.len() + 1));
                }
                let _ = decode(&bytes, seed);
            }
        }
    }

    #[test]
    fn conformance_rejects_wrong_shapes() {
        assert!(!Value::Struct(vec![Value::I32(1)]).conforms_to("std_msgs/msg/Int64"));
        assert!(!Value::Struct(vec![]).conforms_to("std_msgs/msg/Int64"));
        assert!(!Value::I64(1).conforms_to("std_msgs/msg/Int64"));
        assert!(Value::Struct(vec![Value::I64(1)]).conforms_to("std_msgs/msg/Int64"));
    }
}
