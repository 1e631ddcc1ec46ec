//! The generic conversion: any ROS message type <-> one Bottle layout (pure; no I/O).
//!
//! A message is a Bottle of its fields in declaration order. A nested message is a list
//! of its fields, an array or sequence is a list, `uint8[]`/`byte[]` (and their fixed
//! arrays) a blob; numbers, bools and strings are YARP's (ints as Int32 or Int64, float32
//! as Float32, float64 as Float64, bool as YARP's bool vocab). So `nav_msgs/Odometry`
//! reads `((sec nanosec) frame_id) child_frame_id (((x y z) (x y z w)) (36 covariances))
//! (...)`.
//!
//! Towards ROS, trailing fields may be left out at any level (they take their default
//! values, so `()` is a nested message's default), ints are accepted for floats, `0`/`1`
//! for bools and a list of numbers for a blob; a top-level `std_msgs/Header` whose stamp
//! is `(0 0)` gets the YARP envelope's time (else now). Towards YARP, the envelope carries
//! the top-level `header.stamp`. Anything else that does not fit is a [`ConvertError`].

use crate::convert::ConvertError;
use crate::dynmsg::{parse_prim, Value as Ros};
use crate::types::{lookup, Base, Field, MsgType, Prim, Shape};
use yarp_proto::{Bottle, Value as Yv};

const HEADER: &str = "std_msgs/msg/Header";

/// Nesting deeper than this is refused (a type that contains itself through a sequence
/// could otherwise recurse as deep as the Bottle is).
const MAX_DEPTH: usize = 64;

/// Converts a Bottle in the generic layout of `t` into a message; `stamp_ns` fills an
/// unset top-level `header.stamp`.
pub fn to_ros(t: &'static MsgType, b: &Bottle, stamp_ns: u64) -> Result<Ros, ConvertError> {
    to_ros_owned(t, b.clone(), stamp_ns)
}

/// Like [`to_ros`], taking the Bottle: blobs (image pixels) and strings move into the
/// message instead of being copied.
pub fn to_ros_owned(t: &'static MsgType, b: Bottle, stamp_ns: u64) -> Result<Ros, ConvertError> {
    let mut m = structure(t, b.into_items(), 0)?;
    if let (Some(i), Ros::Struct(fields)) = (header_index(t), &mut m) {
        if let Some(Ros::Struct(h)) = fields.get_mut(i) {
            if matches!(h.first(), Some(Ros::Struct(s)) if s.iter().all(is_zero)) {
                h[0] = Ros::time(stamp_ns);
            }
        }
    }
    Ok(m)
}

/// Converts a message of `t` into its generic Bottle.
pub fn to_yarp(t: &'static MsgType, m: &Ros) -> Result<Bottle, ConvertError> {
    match m {
        Ros::Struct(fields) if fields.len() == t.fields.len() => {
            let mut b = Bottle::with_capacity(fields.len());
            for (f, v) in t.fields.iter().zip(fields) {
                b.push(value_to_yarp(f, v)?);
            }
            Ok(b)
        }
        _ => Err(ConvertError::Layout(t.name.to_string())),
    }
}

/// The top-level `header.stamp` of a message of `t`, in seconds (for the envelope).
pub fn header_time(t: &MsgType, m: &Ros) -> Option<f64> {
    let i = header_index(t)?;
    let h = m.fields()?.get(i)?.fields()?;
    match h.first()?.fields()? {
        [Ros::I32(s), Ros::U32(ns)] => Some(*s as f64 + *ns as f64 * 1e-9),
        _ => None,
    }
}

/// Sets an empty top-level `header.frame_id` to `frame_id` (the mapping entry's).
pub fn fill_frame_id(t: &MsgType, m: &mut Ros, frame_id: &str) {
    if frame_id.is_empty() {
        return;
    }
    let Some(i) = header_index(t) else {
        return;
    };
    if let Ros::Struct(fields) = m {
        if let Some(Ros::Struct(h)) = fields.get_mut(i) {
            if let Some(Ros::Str(f)) = h.get_mut(1) {
                if f.is_empty() {
                    *f = frame_id.to_string();
                }
            }
        }
    }
}

/// Where a top-level `std_msgs/Header` field is (the first one).
fn header_index(t: &MsgType) -> Option<usize> {
    t.fields
        .iter()
        .position(|f| f.base == Base::Nested(HEADER) && f.shape == Shape::Single)
}

fn is_zero(v: &Ros) -> bool {
    v.as_f64() == Some(0.0)
}

/// A nested type by name. Field types name their nested types with `&'static str`s that
/// live as long as the process, so each thread remembers them by address: the registry is
/// asked once per name instead of once per nested value.
fn nested_type(name: &'static str) -> Result<&'static MsgType, ConvertError> {
    thread_local! {
        static SEEN: std::cell::RefCell<Vec<((usize, usize), &'static MsgType)>> =
            const { std::cell::RefCell::new(Vec::new()) };
    }
    let key = (name.as_ptr() as usize, name.len());
    if let Some(t) = SEEN.with_borrow(|v| v.iter().find(|(k, _)| *k == key).map(|(_, t)| *t)) {
        return Ok(t);
    }
    let t =
        lookup(name).ok_or_else(|| ConvertError::Layout(format!("unknown nested type {name}")))?;
    SEEN.with_borrow_mut(|v| {
        // Bounded (a linear scan): beyond that, the registry is asked each time.
        if v.len() < 256 {
            v.push((key, t));
        }
    });
    Ok(t)
}

fn structure(t: &'static MsgType, items: Vec<Yv>, depth: usize) -> Result<Ros, ConvertError> {
    if depth > MAX_DEPTH {
        return Err(ConvertError::Shape(format!("{} nests too deep", t.name)));
    }
    if items.len() > t.fields.len() {
        return Err(ConvertError::Count {
            want: t.fields.len(),
            got: items.len(),
        });
    }
    let mut out = Vec::with_capacity(t.fields.len());
    let mut items = items.into_iter();
    for f in t.fields {
        out.push(match items.next() {
            Some(v) => field(f, v, depth).map_err(|e| in_field(t, f, e))?,
            None => default_of(f)?,
        });
    }
    Ok(Ros::Struct(out))
}

/// Names the field an error is in (`Odometry.pose: ...`).
fn in_field(t: &MsgType, f: &Field, e: ConvertError) -> ConvertError {
    match e {
        ConvertError::Shape(s) if s.starts_with("field ") => ConvertError::Shape(s),
        e => ConvertError::Shape(format!(
            "field {}.{}: {e}",
            t.name.rsplit('/').next().unwrap_or(t.name),
            f.name
        )),
    }
}

fn default_of(f: &Field) -> Result<Ros, ConvertError> {
    crate::dynmsg::field_default(f)
        .ok_or_else(|| ConvertError::Layout(format!("no default for field {}", f.name)))
}

fn field(f: &Field, v: Yv, depth: usize) -> Result<Ros, ConvertError> {
    let bytes = matches!(f.base, Base::Prim(Prim::U8 | Prim::Byte));
    match f.shape {
        Shape::Single => single(f, v, depth),
        _ if bytes => {
            let data: Vec<u8> = match v {
                Yv::Blob(b) => b,
                Yv::List(l) => l
                    .items()
                    .iter()
                    .enumerate()
                    .map(|(i, x)| {
                        x.as_i64()
                            .filter(|_| x.is_int())
                            .and_then(|x| u8::try_from(x).ok())
                            .ok_or_else(|| type_err(i, "a byte (0..255)", x))
                    })
                    .collect::<Result<_, _>>()?,
                other => return Err(type_err(0, "a blob or a list of bytes", &other)),
            };
            check_len(f.shape, data.len())?;
            Ok(match f.shape {
                Shape::Array(_) => Ros::Array(data.into_iter().map(Ros::U8).collect()),
                _ => Ros::Bytes(data),
            })
        }
        Shape::Array(_) | Shape::BoundedSeq(_) | Shape::Seq => {
            let Yv::List(l) = v else {
                return Err(type_err(0, "a list", &v));
            };
            check_len(f.shape, l.len())?;
            let items = l.into_items().into_iter().enumerate();
            let elems = match f.base {
                Base::Nested(name) => {
                    let t = nested_type(name)?;
                    items
                        .map(|(i, x)| match x {
                            Yv::List(inner) => structure(t, inner.into_items(), depth + 1),
                            other => Err(type_err(i, "a list (a nested message)", &other)),
                        })
                        .collect::<Result<Vec<_>, _>>()?
                }
                Base::Prim(p) => items
                    .map(|(i, x)| prim(p, f.string_capacity, x).map_err(|e| at(i, e)))
                    .collect::<Result<Vec<_>, _>>()?,
            };
            Ok(if matches!(f.shape, Shape::Array(_)) {
                Ros::Array(elems)
            } else {
                Ros::List(elems)
            })
        }
    }
}

fn check_len(shape: Shape, len: usize) -> Result<(), ConvertError> {
    match shape {
        Shape::Array(n) if len as u64 != n => Err(ConvertError::Count {
            want: n as usize,
            got: len,
        }),
        Shape::BoundedSeq(n) if len as u64 > n => {
            Err(ConvertError::Range(format!("{len} elements (at most {n})")))
        }
        _ => Ok(()),
    }
}

fn at(i: usize, e: ConvertError) -> ConvertError {
    match e {
        ConvertError::Type { want, found, .. } => ConvertError::Type {
            index: i,
            want,
            found,
        },
        e => e,
    }
}

fn single(f: &Field, v: Yv, depth: usize) -> Result<Ros, ConvertError> {
    match f.base {
        Base::Nested(name) => match v {
            Yv::List(l) => structure(nested_type(name)?, l.into_items(), depth + 1),
            other => Err(type_err(0, "a list (a nested message)", &other)),
        },
        Base::Prim(p) => prim(p, f.string_capacity, v),
    }
}

fn type_err(index: usize, want: &'static str, v: &Yv) -> ConvertError {
    ConvertError::Type {
        index,
        want,
        found: String::from_utf8_lossy(&v.to_text_bare()).into_owned(),
    }
}

fn prim(p: Prim, string_capacity: u64, v: Yv) -> Result<Ros, ConvertError> {
    // Strings move out of the Bottle (no copy unless they are not UTF-8).
    if let (Prim::String | Prim::WString, Yv::String(bytes)) = (p, &v) {
        if string_capacity > 0 && bytes.len() as u64 > string_capacity {
            return Err(ConvertError::Range(format!(
                "a string of {} bytes (at most {string_capacity})",
                bytes.len()
            )));
        }
        let Yv::String(bytes) = v else {
            unreachable!("matched above")
        };
        let s = String::from_utf8(bytes)
            .unwrap_or_else(|e| String::from_utf8_lossy(e.as_bytes()).into_owned());
        return Ok(if p == Prim::String {
            Ros::Str(s)
        } else {
            Ros::WStr(s)
        });
    }
    let v = &v;
    let int = || -> Result<i64, ConvertError> {
        if v.is_int() {
            Ok(v.as_i64().unwrap_or_default())
        } else {
            Err(type_err(0, "an integer", v))
        }
    };
    let range = |x: i64| ConvertError::Range(x.to_string());
    let float = || -> Result<f64, ConvertError> {
        if v.is_int() || v.is_float() {
            Ok(v.as_f64().unwrap_or_default())
        } else {
            Err(type_err(0, "a number", v))
        }
    };
    Ok(match p {
        Prim::Bool => match v {
            Yv::Vocab32(_) => Ros::Bool(v.as_bool().unwrap_or_default()),
            _ if v.is_int() => Ros::Bool(int()? != 0),
            Yv::String(s) => match parse_prim(Prim::Bool, &String::from_utf8_lossy(s)) {
                Some(b) => b,
                None => return Err(type_err(0, "a bool", v)),
            },
            other => return Err(type_err(0, "a bool", other)),
        },
        Prim::Byte | Prim::U8 => Ros::U8(int().and_then(|x| x.try_into().map_err(|_| range(x)))?),
        Prim::I8 => Ros::I8(int().and_then(|x| x.try_into().map_err(|_| range(x)))?),
        Prim::I16 => Ros::I16(int().and_then(|x| x.try_into().map_err(|_| range(x)))?),
        Prim::U16 => Ros::U16(int().and_then(|x| x.try_into().map_err(|_| range(x)))?),
        Prim::I32 => Ros::I32(int().and_then(|x| x.try_into().map_err(|_| range(x)))?),
        Prim::U32 => Ros::U32(int().and_then(|x| x.try_into().map_err(|_| range(x)))?),
        Prim::I64 => Ros::I64(int()?),
        Prim::U64 => match v {
            // uint64 above 2^63-1 travel as Float64 (see `to_yarp`).
            Yv::Float64(x) if *x >= 9.223_372_036_854_776e18 && *x < 1.844_674_407_370_955_2e19 => {
                Ros::U64(*x as u64)
            }
            _ => Ros::U64(int().and_then(|x| x.try_into().map_err(|_| range(x)))?),
        },
        Prim::F32 => Ros::F32(float()? as f32),
        Prim::F64 => Ros::F64(float()?),
        Prim::String | Prim::WString => return Err(type_err(0, "a string", v)),
    })
}

fn value_to_yarp(f: &Field, v: &Ros) -> Result<Yv, ConvertError> {
    Ok(match (f.shape, v) {
        (_, Ros::Bytes(b)) => Yv::Blob(b.clone()),
        (Shape::Array(_), Ros::Array(items))
            if matches!(f.base, Base::Prim(Prim::U8 | Prim::Byte)) =>
        {
            Yv::Blob(
                items
                    .iter()
                    .map(|x| match x {
                        Ros::U8(b) => Ok(*b),
                        _ => Err(ConvertError::Layout(f.name.to_string())),
                    })
                    .collect::<Result<_, _>>()?,
            )
        }
        (Shape::Single, v) => element_to_yarp(f.base, v)?,
        (_, Ros::List(items) | Ros::Array(items)) => {
            let mut b = Bottle::with_capacity(items.len());
            for x in items {
                b.push(element_to_yarp(f.base, x)?);
            }
            Yv::List(b)
        }
        _ => return Err(ConvertError::Layout(f.name.to_string())),
    })
}

fn element_to_yarp(base: Base, v: &Ros) -> Result<Yv, ConvertError> {
    Ok(match (base, v) {
        (Base::Nested(n), m) => Yv::List(to_yarp(nested_type(n)?, m)?),
        (_, Ros::Bool(b)) => Yv::from(*b),
        (_, Ros::I8(x)) => Yv::Int32((*x).into()),
        (_, Ros::U8(x)) => Yv::Int32((*x).into()),
        (_, Ros::I16(x)) => Yv::Int32((*x).into()),
        (_, Ros::U16(x)) => Yv::Int32((*x).into()),
        (_, Ros::I32(x)) => Yv::Int32(*x),
        (_, Ros::U32(x)) => Yv::Int64((*x).into()),
        (_, Ros::I64(x)) => Yv::Int64(*x),
        (_, Ros::U64(x)) => match i64::try_from(*x) {
            Ok(i) => Yv::Int64(i),
            Err(_) => Yv::Float64(*x as f64),
        },
        (_, Ros::F32(x)) => Yv::Float32(*x),
        (_, Ros::F64(x)) => Yv::Float64(*x),
        (_, Ros::Str(s) | Ros::WStr(s)) => Yv::string(s.as_bytes()),
        (_, Ros::Bytes(b)) => Yv::Blob(b.clone()),
        _ => return Err(ConvertError::Layout(format!("{v:?}"))),
    })
}

/// The Bottle layout of `t` for people: one line per field, nested messages indented.
pub fn layout(t: &'static MsgType) -> String {
    let mut out = String::new();
    describe(t, 0, &mut out, &mut Vec::new());
    out
}

fn describe(t: &'static MsgType, depth: usize, out: &mut String, path: &mut Vec<&'static str>) {
    for (i, f) in t.fields.iter().enumerate() {
        let pad = "  ".repeat(depth);
        let what = match (f.base, f.shape) {
            (Base::Prim(Prim::U8 | Prim::Byte), Shape::Single) => "int".to_string(),
            (Base::Prim(Prim::U8 | Prim::Byte), Shape::Array(n)) => format!("blob of {n} bytes"),
            (Base::Prim(Prim::U8 | Prim::Byte), _) => "blob".to_string(),
            (base, shape) => {
                let one = match base {
                    Base::Prim(p) => prim_word(p).to_string(),
                    Base::Nested(n) => format!("({n})"),
                };
                match shape {
                    Shape::Single => one,
                    Shape::Array(n) => format!("list of {n} {one}"),
                    Shape::BoundedSeq(n) => format!("list of at most {n} {one}"),
                    Shape::Seq => format!("list of {one}"),
                }
            }
        };
        let default = f.default.map(|d| format!(" = {d}")).unwrap_or_default();
        out.push_str(&format!("{pad}{i:>2} {:<24} {what}{default}\n", f.name));
        if let Base::Nested(n) = f.base {
            // A type that contains itself is described once.
            if let (Some(nt), false) = (lookup(n), path.contains(&n)) {
                path.push(n);
                describe(nt, depth + 1, out, path);
                path.pop();
            }
        }
    }
}

fn prim_word(p: Prim) -> &'static str {
    match p {
        Prim::Bool => "bool (0/1)",
        Prim::F32 | Prim::F64 => "float",
        Prim::String | Prim::WString => "string",
        _ => "int",
    }
}

/// A Bottle of `t` as `yarp write` would send it: its default value (with every sequence
/// holding one element, so the element's layout shows).
pub fn example(t: &'static MsgType) -> Result<Bottle, ConvertError> {
    let m = example_value(t, 0)?;
    to_yarp(t, &m)
}

fn example_value(t: &'static MsgType, depth: usize) -> Result<Ros, ConvertError> {
    let mut out = Vec::with_capacity(t.fields.len());
    for f in t.fields {
        let d = default_of(f)?;
        let v = match (f.base, f.shape, d) {
            (Base::Nested(n), Shape::Single, _) if depth < 8 => {
                example_value(nested_type(n)?, depth + 1)?
            }
            (Base::Nested(n), Shape::Seq | Shape::BoundedSeq(_), Ros::List(l))
                if l.is_empty() && depth < 8 =>
            {
                Ros::List(vec![example_value(nested_type(n)?, depth + 1)?])
            }
            (Base::Prim(_), Shape::Seq | Shape::BoundedSeq(_), Ros::List(l)) if l.is_empty() => {
                let holder = Field {
                    shape: Shape::Single,
                    default: None,
                    ..*f
                };
                Ros::List(vec![default_of(&holder)?])
            }
            (_, _, d) => d,
        };
        out.push(v);
    }
    Ok(Ros::Struct(out))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::types::builtin;

    fn t(name: &str) -> &'static MsgType {
        builtin(name).unwrap()
    }

    #[test]
    fn twist_both_ways_as_nested_lists() {
        let b = Bottle::from_text("(0.5 0 0) (0 0 -0.25)");
        let m = to_ros(t("geometry_msgs/msg/Twist"), &b, 0).unwrap();
        assert!(m.conforms_to("geometry_msgs/msg/Twist"));
        assert_eq!(
            to_yarp(t("geometry_msgs/msg/Twist"), &m)
                .unwrap()
                .to_string(),
            "(0.5 0.0 0.0) (0.0 0.0 -0.25)"
        );
    }

    #[test]
    fn joint_state_with_header_stamp_from_the_envelope() {
        let ty = t("sensor_msgs/msg/JointState");
        let b = Bottle::from_text("((0 0) base) (a b) (1 2.5) () ()");
        let m = to_ros(ty, &b, 3_000_000_007).unwrap();
        assert!(m.conforms_to(ty.name));
        assert_eq!(header_time(ty, &m), Some(3.000_000_007));
        let back = to_yarp(ty, &m).unwrap();
        assert_eq!(back.to_string(), "((3 7) base) (a b) (1.0 2.5) () ()");
        // a stamp that is set stays
        let set = Bottle::from_text("((5 1) base) (a) (1)");
        let m = to_ros(ty, &set, 3).unwrap();
        assert_eq!(header_time(ty, &m), Some(5.000_000_001));
    }

    #[test]
    fn trailing_fields_take_their_defaults() {
        let ty = t("sensor_msgs/msg/Image");
        let m = to_ros(ty, &Bottle::from_text("() 2 3"), 0).unwrap();
        assert!(m.conforms_to(ty.name));
        let f = m.fields().unwrap();
        assert_eq!((&f[1], &f[2]), (&Ros::U32(2), &Ros::U32(3)));
        assert_eq!(f[6], Ros::Bytes(vec![]));
    }

    #[test]
    fn bytes_as_blobs_or_lists() {
        let ty = t("sensor_msgs/msg/Image");
        let m = to_ros(ty, &Bottle::from_text("() 1 3 rgb8 0 3 (1 2 255)"), 0).unwrap();
        assert_eq!(m.fields().unwrap()[6], Ros::Bytes(vec![1, 2, 255]));
        let b = to_yarp(ty, &m).unwrap();
        assert_eq!(b.get(6), Some(&Yv::Blob(vec![1, 2, 255])));
        assert_eq!(
            to_ros(ty, &b, 0).unwrap().fields().unwrap()[6],
            Ros::Bytes(vec![1, 2, 255])
        );
        assert!(to_ros(ty, &Bottle::from_text("() 1 3 rgb8 0 3 (1 2 256)"), 0).is_err());
        // a fixed uint8 array (ServiceEventInfo.client_gid) is a blob of its size
        let info = t("service_msgs/msg/ServiceEventInfo");
        let z = Ros::zero(info.name).unwrap();
        let b = to_yarp(info, &z).unwrap();
        assert_eq!(b.get(2), Some(&Yv::Blob(vec![0; 16])));
        assert_eq!(to_ros(info, &b, 0).unwrap(), z);
        assert!(to_ros(info, &Bottle::from_text("0 (0 0) {1 2}"), 0).is_err());
    }

    #[test]
    fn what_does_not_fit_is_an_error() {
        let ty = t("geometry_msgs/msg/Twist");
        for bad in [
            "(1 2 3) (4 5 6) (7)",
            "1 2",
            "(1 2 3 4)",
            "(a 2 3)",
            "((1) 2 3)",
        ] {
            assert!(to_ros(ty, &Bottle::from_text(bad), 0).is_err(), "{bad}");
        }
        let imu = t("sensor_msgs/msg/Imu");
        let e = to_ros(imu, &Bottle::from_text("() () (1 2)"), 0).unwrap_err();
        assert!(e.to_string().contains("orientation_covariance"), "{e}");
        assert!(to_ros(t("std_msgs/msg/Int32"), &Bottle::from_text("5000000000"), 0).is_err());
        assert!(to_ros(t("std_msgs/msg/Int32"), &Bottle::from_text("1.5"), 0).is_err());
        assert!(to_ros(t("std_msgs/msg/Bool"), &Bottle::from_text("x"), 0).is_err());
        assert!(to_yarp(ty, &Ros::Struct(vec![])).is_err());
    }

    #[test]
    fn scalars_and_bools() {
        let m = to_ros(t("std_msgs/msg/Bool"), &Bottle::from_text("1"), 0).unwrap();
        assert_eq!(m, Ros::Struct(vec![Ros::Bool(true)]));
        let b = to_yarp(t("std_msgs/msg/Bool"), &m).unwrap();
        assert_eq!(to_ros(t("std_msgs/msg/Bool"), &b, 0).unwrap(), m);
        let m = to_ros(t("std_msgs/msg/Float32"), &Bottle::from_text("2"), 0).unwrap();
        assert_eq!(m, Ros::Struct(vec![Ros::F32(2.0)]));
        let m = to_ros(
            t("std_msgs/msg/String"),
            &Bottle::from_text("\"two words\""),
            0,
        )
        .unwrap();
        assert_eq!(
            to_yarp(t("std_msgs/msg/String"), &m).unwrap().to_string(),
            "\"two words\""
        );
    }

    #[test]
    fn every_builtin_type_round_trips_its_example_and_has_a_layout() {
        for ty in crate::types::MESSAGES {
            let ex = example(ty).unwrap_or_else(|e| panic!("{}: {e}", ty.name));
            let m = to_ros(ty, &ex, 0).unwrap_or_else(|e| panic!("{}: {e}", ty.name));
            assert!(m.conforms_to(ty.name), "{}", ty.name);
            assert_eq!(to_yarp(ty, &m).unwrap(), ex, "{}", ty.name);
            assert!(!layout(ty).is_empty());
        }
    }

    /// Network and user input: random Bottles never panic.
    #[test]
    fn random_bottles_are_errors_or_values() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let atoms = [
            "1",
            "-1",
            "2.5",
            "x",
            "\"s\"",
            "()",
            "(1 2)",
            "((0 0) f)",
            "{1 2}",
            "[ok]",
        ];
        for ty in crate::types::MESSAGES {
            for _ in 0..300 {
                let n = (next() % 8) as usize;
                let text: Vec<&str> = (0..n).map(|_| atoms[(next() % 10) as usize]).collect();
                let b = Bottle::from_text(text.join(" "));
                if let Ok(m) = to_ros(ty, &b, 1) {
                    assert!(m.conforms_to(ty.name), "{} {b}", ty.name);
                }
            }
        }
    }
}
