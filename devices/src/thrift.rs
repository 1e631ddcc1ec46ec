//! What every thrift service of C++ YARP's devices shares, in both generations: the
//! `yarp::dev::ReturnValue` its methods return, `getRemoteProtocolVersion`, and the
//! `[fail]` its generated reader answers a call it cannot read.
//!
//! `ReturnValue` is where 3.12 and 4.0 part: 3.12 writes it as a tagged int32 code
//! (8 bytes), 4.0 as a list of one tagged vocab (16 bytes, `ok`, `err1`..`err7`, `miss`).
//! Neither reader checks the tags, so each peer must get its own form.

use crate::error::DeviceError;
use crate::sensors::wire::WireWriter;
use yarp_proto::tags::{self, Generation};
use yarp_proto::{Bottle, Value, Vocab32};

/// C++ `yarp::dev::ReturnValue`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ReturnValue {
    Ok,
    Generic,
    NotImplemented,
    Communication,
    Deprecated,
    MethodFailed,
    NotReady,
    /// 4.0's `err7`; 3.12 has no such code and gets `MethodFailed`.
    OutOfBounds,
    /// `miss` (3.12: 100): what a C++ client holds when the call itself failed.
    Uninitialized,
}

const ALL: [ReturnValue; 9] = [
    ReturnValue::Ok,
    ReturnValue::Generic,
    ReturnValue::NotImplemented,
    ReturnValue::Communication,
    ReturnValue::Deprecated,
    ReturnValue::MethodFailed,
    ReturnValue::NotReady,
    ReturnValue::OutOfBounds,
    ReturnValue::Uninitialized,
];

impl ReturnValue {
    /// The code for a device call that failed with `e`.
    pub fn of(e: &DeviceError) -> ReturnValue {
        match e {
            // C++'s wrappers answer a call their device has no interface for "not ready"
            DeviceError::NotOpen | DeviceError::NotReady(_) | DeviceError::NoInterface(_) => {
                ReturnValue::NotReady
            }
            DeviceError::Unsupported(_) => ReturnValue::NotImplemented,
            DeviceError::UnservedByCpp(_) => ReturnValue::Uninitialized,
            DeviceError::Timeout { .. } | DeviceError::PeerLost { .. } => {
                ReturnValue::Communication
            }
            DeviceError::InvalidJoint { .. } | DeviceError::WrongSize { .. } => {
                ReturnValue::OutOfBounds
            }
            _ => ReturnValue::MethodFailed,
        }
    }

    /// The return value of a device call's result.
    pub fn of_result<T>(r: &Result<T, DeviceError>) -> ReturnValue {
        r.as_ref().err().map_or(ReturnValue::Ok, ReturnValue::of)
    }

    /// 4.0's vocab.
    pub fn vocab(self) -> Vocab32 {
        Vocab32::new(match self {
            ReturnValue::Ok => "ok",
            ReturnValue::Generic => "err1",
            ReturnValue::NotImplemented => "err2",
            ReturnValue::Communication => "err3",
            ReturnValue::Deprecated => "err4",
            ReturnValue::MethodFailed => "err5",
            ReturnValue::NotReady => "err6",
            ReturnValue::OutOfBounds => "err7",
            ReturnValue::Uninitialized => "miss",
        })
    }

    /// The value of 4.0's vocab `v` (an unknown one is a generic error).
    pub fn from_vocab(v: Vocab32) -> ReturnValue {
        ALL.into_iter()
            .find(|r| r.vocab() == v)
            .unwrap_or(ReturnValue::Generic)
    }

    /// 3.12's int32 code.
    pub fn code(self) -> i32 {
        match self {
            ReturnValue::Ok => 0,
            ReturnValue::Generic => 1,
            ReturnValue::NotImplemented => 2,
            ReturnValue::Communication => 3,
            ReturnValue::Deprecated => 4,
            ReturnValue::MethodFailed | ReturnValue::OutOfBounds => 5,
            ReturnValue::NotReady => 6,
            ReturnValue::Uninitialized => 100,
        }
    }

    /// The value of 3.12's code `c` (an unknown one is a generic error).
    pub fn from_code(c: i32) -> ReturnValue {
        ALL.into_iter()
            .find(|r| r.code() == c && *r != ReturnValue::OutOfBounds)
            .unwrap_or(ReturnValue::Generic)
    }

    /// Writes it in `w`'s generation: 3.12's tagged int32, 4.0's list of one vocab.
    pub fn put(self, w: &mut WireWriter) {
        match w.generation() {
            Generation::V3 => w.int32(self.code()),
            Generation::V4 => w.list_header(1).vocab(self.vocab()),
        };
    }

    /// Reads it from a decoded reply element of either generation.
    pub fn from_value(v: &Value) -> Option<ReturnValue> {
        match v {
            Value::Int32(c) => Some(ReturnValue::from_code(*c)),
            Value::List(l) if l.len() == 1 => Some(ReturnValue::from_vocab(l.get(0)?.as_vocab()?)),
            _ => None,
        }
    }

    /// A method's reply that is its return value alone, in `generation`'s bytes (3.12's
    /// is no Bottle: a tag and a code).
    pub fn bare(self, generation: Generation) -> Vec<u8> {
        let mut w = WireWriter::for_generation(generation);
        self.put(&mut w);
        w.into_bytes()
    }

    /// Reads a bare reply's bytes, of either generation.
    pub fn from_bare(bytes: &[u8]) -> Option<ReturnValue> {
        let word = |i: usize| {
            bytes
                .get(i * 4..i * 4 + 4)
                .map(|b| i32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        };
        match (bytes.len(), word(0)?) {
            (8, tags::INT32) => Some(ReturnValue::from_code(word(1)?)),
            (16, tags::LIST) if word(1)? == 1 && word(2)? == tags::VOCAB32 => {
                Some(ReturnValue::from_vocab(Vocab32(word(3)?)))
            }
            _ => None,
        }
    }

    /// The error a client reports for a call `command` of `device` that returned this.
    pub fn error(self, device: &str, command: &str) -> DeviceError {
        match self {
            ReturnValue::NotImplemented => {
                DeviceError::Unsupported("not implemented by the remote device")
            }
            ReturnValue::NotReady => DeviceError::NotReady("the remote device is not ready"),
            ReturnValue::Communication => DeviceError::PeerLost {
                device: device.to_string(),
                reason: format!("`{command}`: the server lost its own device"),
            },
            _ => DeviceError::Refused {
                device: device.to_string(),
                command: format!("{command} ({:?})", self),
            },
        }
    }
}

/// A decoded reply of either generation: its return value and the fields after it. A
/// bare `ReturnValue` decodes as a Bottle too: 4.0's as its one vocab, 3.12's `ok` (a tag
/// and 0) as an empty compact list; 3.12's other codes are no Bottle
/// ([`ReturnValue::from_bare`] reads those bytes).
pub fn parse_reply(reply: &Bottle) -> Option<(ReturnValue, Vec<Value>)> {
    match reply.items() {
        [] => Some((ReturnValue::Ok, Vec::new())),
        [Value::Vocab32(v)] => Some((ReturnValue::from_vocab(*v), Vec::new())),
        [first, rest @ ..] => Some((ReturnValue::from_value(first)?, rest.to_vec())),
    }
}

/// The protocol number C++'s generated services compare (no `.thrift` of ours declares
/// one: 0 in both generations).
pub const PROTOCOL: i16 = 0;

/// The YARP version each generation's services report: the C++ releases we follow.
pub fn yarp_version(generation: Generation) -> [i16; 3] {
    match generation {
        Generation::V3 => [3, 12, 3],
        Generation::V4 => [4, 0, 0],
    }
}

/// The method every generated service answers besides its own (not listed by `help`).
pub const GET_PROTOCOL_VERSION: &str = "getRemoteProtocolVersion";

/// The `getRemoteProtocolVersion` reply: a one-element list header, then an
/// `ApplicationNetworkProtocolVersion` written untagged (four int16: the protocol, then
/// YARP's major, minor and patch): not a Bottle.
pub fn protocol_version_reply(generation: Generation) -> Vec<u8> {
    let mut w = WireWriter::for_generation(generation);
    w.list_header(1).raw_int16(PROTOCOL);
    for part in yarp_version(generation) {
        w.raw_int16(part);
    }
    w.into_bytes()
}

/// The `getRemoteProtocolVersion` call.
pub fn protocol_version_request() -> Vec<u8> {
    let mut w = WireWriter::new();
    w.list_header(1).string(GET_PROTOCOL_VERSION);
    w.into_bytes()
}

/// The protocol number and YARP version in a `getRemoteProtocolVersion` reply's bytes.
pub fn protocol_version_of(reply: &[u8]) -> Option<(i16, [i16; 3])> {
    if reply.len() != 16 {
        return None;
    }
    let half = |i: usize| i16::from_le_bytes([reply[8 + 2 * i], reply[9 + 2 * i]]);
    Some((half(0), [half(1), half(2), half(3)]))
}

/// The generation of the server that sent a `getRemoteProtocolVersion` reply.
pub fn generation_of_version(version: [i16; 3]) -> Generation {
    if version[0] >= 4 {
        Generation::V4
    } else {
        Generation::V3
    }
}

/// Whether `cmd` is `getRemoteProtocolVersion`, optionally behind `__direct__`, without
/// arguments (with arguments C++ fails the request).
pub fn is_protocol_version_request(cmd: &Bottle) -> bool {
    let mut words = cmd.iter().map(word).peekable();
    if words.peek() == Some(&Some("__direct__".to_string())) {
        words.next();
    }
    words.next() == Some(Some(GET_PROTOCOL_VERSION.to_string())) && words.next().is_none()
}

/// Whether `cmd` calls one of `methods` (or `getRemoteProtocolVersion`), optionally
/// behind `__direct__`: a thrift call, not a vocab command sharing its port.
pub fn is_call_of(cmd: &Bottle, methods: &[&str]) -> bool {
    let mut items = cmd.items();
    if items.first().and_then(word).as_deref() == Some("__direct__") {
        items = &items[1..];
    }
    match items.first() {
        Some(first @ Value::String(_)) => {
            word(first).is_some_and(|w| methods.contains(&w.as_str()) || w == GET_PROTOCOL_VERSION)
        }
        _ => false,
    }
}

/// The method a classic thrift request calls and its arguments: the first words joined
/// with `_` until they name one of `methods`, as C++'s generated `read` joins tags
/// (`getScanRate RPC` and `getScanRate_RPC` are the same call), after an optional
/// `__direct__`.
pub fn split_method<'a>(
    cmd: &'a Bottle,
    methods: &[&'static str],
) -> Option<(&'static str, &'a [Value])> {
    let mut items = cmd.items();
    if items.first().and_then(word).as_deref() == Some("__direct__") {
        items = &items[1..];
    }
    let most_words = methods.iter().map(|m| m.split('_').count()).max()?;
    let mut tag = String::new();
    for (i, v) in items.iter().enumerate().take(most_words) {
        if i > 0 {
            tag.push('_');
        }
        tag.push_str(&word(v)?);
        if let Some(m) = methods.iter().find(|m| **m == tag) {
            return Some((m, &items[i + 1..]));
        }
    }
    None
}

/// The `[fail]` reply (a plain Bottle, compact vocab list, as C++ writes it).
pub fn fail_reply() -> Vec<u8> {
    Bottle::new().with(Vocab32::new("fail")).encode()
}

/// A command word: thrift tags may be strings or vocabs.
pub fn word(v: &Value) -> Option<String> {
    match v {
        Value::String(s) => Some(String::from_utf8_lossy(s).into_owned()),
        Value::Vocab32(v) => Some(v.as_string()),
        _ => None,
    }
}

// ---------------------------------------------------------------------------------------
// Values as 4.0's generated code writes and reads them
// ---------------------------------------------------------------------------------------

/// A value as 4.0's generated code writes it and reads it.
pub trait Wire4: Sized {
    /// The elements it adds to a call or reply: a thrift struct is written flat.
    const COUNT: usize = 1;
    fn put4(&self, w: &mut WireWriter);
    fn take4(c: &mut Cursor4<'_>) -> Option<Self>;
    /// What C++ writes in a reply whose call failed.
    fn zero() -> Self;
    /// The return value a successful call with this reply carries.
    fn ret(&self) -> ReturnValue {
        ReturnValue::Ok
    }
    /// The reply a return value other than `ok` stands for, if it stands for one.
    fn from_failure(_: ReturnValue) -> Option<Self> {
        None
    }
}

/// The values of a call or reply not read yet.
pub struct Cursor4<'a>(std::slice::Iter<'a, Value>);

impl<'a> Cursor4<'a> {
    pub fn new(items: &'a [Value]) -> Self {
        Cursor4(items.iter())
    }
    pub fn item(&mut self) -> Option<&'a Value> {
        self.0.next()
    }
    /// Whether every value was read.
    pub fn is_done(&self) -> bool {
        self.0.len() == 0
    }
}

impl Wire4 for () {
    const COUNT: usize = 0;
    fn put4(&self, _: &mut WireWriter) {}
    fn take4(_: &mut Cursor4<'_>) -> Option<Self> {
        Some(())
    }
    fn zero() -> Self {}
}

impl Wire4 for f64 {
    fn put4(&self, w: &mut WireWriter) {
        w.float64(*self);
    }
    fn take4(c: &mut Cursor4<'_>) -> Option<Self> {
        c.item()?.as_f64()
    }
    fn zero() -> Self {
        0.0
    }
}

impl Wire4 for i32 {
    fn put4(&self, w: &mut WireWriter) {
        w.int32(*self);
    }
    fn take4(c: &mut Cursor4<'_>) -> Option<Self> {
        c.item().filter(|v| v.is_int() || v.is_vocab())?.as_i32()
    }
    fn zero() -> Self {
        0
    }
}

/// Joints, motors and counts are i32 (i16 in some calls: C++ reads either).
impl Wire4 for usize {
    fn put4(&self, w: &mut WireWriter) {
        w.int32(i32::try_from(*self).unwrap_or(i32::MAX));
    }
    fn take4(c: &mut Cursor4<'_>) -> Option<Self> {
        usize::try_from(i32::take4(c)?).ok()
    }
    fn zero() -> Self {
        0
    }
}

impl Wire4 for u32 {
    fn put4(&self, w: &mut WireWriter) {
        w.int32(i32::try_from(*self).unwrap_or(i32::MAX));
    }
    fn take4(c: &mut Cursor4<'_>) -> Option<Self> {
        u32::try_from(i32::take4(c)?).ok()
    }
    fn zero() -> Self {
        0
    }
}

/// `writeBool`: the vocab `ok` or `fail`; read true unless 0 or `fail`.
impl Wire4 for bool {
    fn put4(&self, w: &mut WireWriter) {
        w.bool(*self);
    }
    fn take4(c: &mut Cursor4<'_>) -> Option<Self> {
        let v = c.item().filter(|v| v.is_int() || v.is_vocab())?.as_i32()?;
        Some(v != 0 && v != Vocab32::new("fail").0)
    }
    fn zero() -> Self {
        false
    }
}

impl Wire4 for Option<bool> {
    fn put4(&self, w: &mut WireWriter) {
        w.bool(self.unwrap_or(false));
    }
    fn take4(c: &mut Cursor4<'_>) -> Option<Self> {
        bool::take4(c).map(Some)
    }
    fn zero() -> Self {
        None
    }
}

impl Wire4 for String {
    fn put4(&self, w: &mut WireWriter) {
        w.string(self);
    }
    fn take4(c: &mut Cursor4<'_>) -> Option<Self> {
        c.item()?.as_str().map(str::to_string)
    }
    fn zero() -> Self {
        String::new()
    }
}

/// Control modes, interaction modes, PID types and joint types are thrift enums whose
/// values are vocabs, written with the int32 tag.
impl Wire4 for Vocab32 {
    fn put4(&self, w: &mut WireWriter) {
        w.int32(self.0);
    }
    fn take4(c: &mut Cursor4<'_>) -> Option<Self> {
        i32::take4(c).map(Vocab32)
    }
    fn zero() -> Self {
        Vocab32(0)
    }
}

/// A list of items of one type: the compact form C++ writes (and requires).
pub fn take_list<'a, T>(
    c: &mut Cursor4<'a>,
    item: impl Fn(&'a Value) -> Option<T>,
) -> Option<Vec<T>> {
    c.item()?.as_list()?.iter().map(item).collect()
}

impl Wire4 for Vec<f64> {
    fn put4(&self, w: &mut WireWriter) {
        w.float_vector(self);
    }
    fn take4(c: &mut Cursor4<'_>) -> Option<Self> {
        take_list(c, Value::as_f64)
    }
    fn zero() -> Self {
        Vec::new()
    }
}

impl Wire4 for Vec<i32> {
    fn put4(&self, w: &mut WireWriter) {
        w.int32_list(self.iter().copied());
    }
    fn take4(c: &mut Cursor4<'_>) -> Option<Self> {
        take_list(c, Value::as_i32)
    }
    fn zero() -> Self {
        Vec::new()
    }
}

impl Wire4 for Vec<Vocab32> {
    fn put4(&self, w: &mut WireWriter) {
        w.int32_list(self.iter().map(|v| v.0));
    }
    fn take4(c: &mut Cursor4<'_>) -> Option<Self> {
        take_list(c, |v| v.as_i32().map(Vocab32))
    }
    fn zero() -> Self {
        Vec::new()
    }
}

impl<A: Wire4, B: Wire4> Wire4 for (A, B) {
    const COUNT: usize = A::COUNT + B::COUNT;
    fn put4(&self, w: &mut WireWriter) {
        self.0.put4(w);
        self.1.put4(w);
    }
    fn take4(c: &mut Cursor4<'_>) -> Option<Self> {
        Some((A::take4(c)?, B::take4(c)?))
    }
    fn zero() -> Self {
        (A::zero(), B::zero())
    }
}

impl<A: Wire4, B: Wire4, C: Wire4> Wire4 for (A, B, C) {
    const COUNT: usize = A::COUNT + B::COUNT + C::COUNT;
    fn put4(&self, w: &mut WireWriter) {
        self.0.put4(w);
        self.1.put4(w);
        self.2.put4(w);
    }
    fn take4(c: &mut Cursor4<'_>) -> Option<Self> {
        Some((A::take4(c)?, B::take4(c)?, C::take4(c)?))
    }
    fn zero() -> Self {
        (A::zero(), B::zero(), C::zero())
    }
}

/// The reply of a 4.0 method returning `R` that gave `result`: the bare `ReturnValue`
/// when `R` has no fields, otherwise a list of the return value and the fields, flat.
pub fn reply4<R: Wire4>(result: crate::error::DevResult<R>, method: &str) -> Vec<u8> {
    let mut w = WireWriter::for_generation(Generation::V4);
    let (ret, value) = match result {
        Ok(v) => (v.ret(), v),
        Err(e) => {
            tracing::warn!("{method} failed: {e}");
            (ReturnValue::of(&e), R::zero())
        }
    };
    if R::COUNT == 0 {
        ret.put(&mut w);
    } else {
        w.list_header(1 + R::COUNT);
        ret.put(&mut w);
        value.put4(&mut w);
    }
    w.into_bytes()
}

/// What a 4.0 reply of `R` says: its return value, and the value when it is `ok`.
pub fn answer4<R: Wire4>(reply: &Bottle) -> Option<(ReturnValue, Option<R>)> {
    if R::COUNT == 0 {
        // the bare ReturnValue: its one vocab is the Bottle's
        let code = ReturnValue::from_vocab(reply.get(0)?.as_vocab()?);
        let value = match code {
            ReturnValue::Ok => R::take4(&mut Cursor4::new(&[])),
            failed => R::from_failure(failed),
        };
        return Some((code, value));
    }
    let code = ReturnValue::from_value(reply.get(0)?)?;
    let value = R::take4(&mut Cursor4::new(&reply.items()[1..]));
    Some((code, value.filter(|_| code == ReturnValue::Ok)))
}

/// Declares a YARP 4.0 thrift service once, as its `.thrift` file does: each method's
/// name, arguments and reply type, and how a device (named after `for`) serves it
/// (interfaces missing are
/// `DeviceError::NoInterface`, which C++'s servers answer `not ready`). Generates, in
/// module `$module`:
/// - `enum Call`, a variant per method with its arguments, and `METHODS`;
/// - `Call::decode` (a request as the generated `read` accepts it, `__direct__` allowed),
///   `Call::encode` (as C++'s client writes it), `Call::name`;
/// - `Call::serve(self, device)`: the reply bytes;
/// - a function per method building a typed [`Request`] for clients.
#[macro_export]
macro_rules! thrift_service {
    (
        $(#[$doc:meta])*
        $vis:vis mod $module:ident for $d:ident {
            $(
                $(#[$mdoc:meta])*
                $name:ident ( $($arg:ident : $aty:ty),* ) -> $rty:ty = $body:expr;
            )*
        }
    ) => {
        $(#[$doc])*
        #[allow(non_snake_case, non_camel_case_types, unused_variables, unused_mut)]
        $vis mod $module {
            use super::*;
            use $crate::thrift::{Cursor4, Request, Wire4};

            /// A call of the service.
            #[derive(Debug, Clone, PartialEq)]
            pub enum Call {
                $( $(#[$mdoc])* $name { $($arg: $aty),* }, )*
            }

            /// The methods, by name.
            pub const METHODS: &[&str] = &[$(stringify!($name)),*];

            impl Call {
                pub fn name(&self) -> &'static str {
                    match self {
                        $( Call::$name { .. } => stringify!($name), )*
                    }
                }

                /// A request, if it is a call of this service with all its arguments.
                pub fn decode(cmd: &yarp_proto::Bottle) -> Option<Call> {
                    let mut items = cmd.items();
                    if items.first().and_then($crate::thrift::word).as_deref() == Some("__direct__") {
                        items = &items[1..];
                    }
                    let name = $crate::thrift::word(items.first()?)?;
                    let mut c = Cursor4::new(&items[1..]);
                    let call = match name.as_str() {
                        $( stringify!($name) => {
                            $( let $arg = <$aty as Wire4>::take4(&mut c)?; )*
                            Call::$name { $($arg),* }
                        } )*
                        _ => return None,
                    };
                    c.is_done().then_some(call)
                }

                /// The call's bytes, as C++'s client writes them.
                pub fn encode(&self) -> Vec<u8> {
                    let mut w = $crate::sensors::wire::WireWriter::for_generation(
                        yarp_proto::tags::Generation::V4,
                    );
                    match self {
                        $( Call::$name { $($arg),* } => {
                            w.list_header(1 $(+ <$aty as Wire4>::COUNT)*).string(stringify!($name));
                            $( $arg.put4(&mut w); )*
                        } )*
                    }
                    w.into_bytes()
                }

                /// Serves the call on `device`: the reply's bytes.
                #[allow(clippy::redundant_closure_call)]
                pub fn serve(self, $d: &mut dyn $crate::driver::DeviceDriver) -> Vec<u8> {
                    match self {
                        $( Call::$name { $($arg),* } => {
                            let result: $crate::error::DevResult<$rty> = (|| $body)();
                            $crate::thrift::reply4(result, stringify!($name))
                        } )*
                    }
                }
            }

            $(
                $(#[$mdoc])*
                pub fn $name($($arg: $aty),*) -> Request<$rty> {
                    Request::new(Call::$name { $($arg),* }.encode(), stringify!($name))
                }
            )*
        }
    };
}

/// A call whose reply is an `R`, ready to send.
pub struct Request<R> {
    pub bytes: Vec<u8>,
    pub name: &'static str,
    reply: std::marker::PhantomData<fn() -> R>,
}

impl<R: Wire4> Request<R> {
    pub fn new(bytes: Vec<u8>, name: &'static str) -> Self {
        Request {
            bytes,
            name,
            reply: std::marker::PhantomData,
        }
    }

    /// What its reply says, as a client reports it (`device` names the client).
    pub fn answer(&self, reply: &Bottle, device: &str) -> Result<R, DeviceError> {
        match answer4::<R>(reply) {
            Some((ReturnValue::Ok, Some(v))) => Ok(v),
            Some((ReturnValue::Ok, None)) | None => Err(DeviceError::failed(
                device,
                format!("{}: malformed reply {reply}", self.name),
            )),
            Some((ret, _)) => Err(ret.error(device, self.name)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_generation_reads_back() {
        for r in ALL {
            for g in [Generation::V3, Generation::V4] {
                let want = if g == Generation::V3 && r == ReturnValue::OutOfBounds {
                    ReturnValue::MethodFailed
                } else {
                    r
                };
                assert_eq!(
                    ReturnValue::from_bare(&r.bare(g)),
                    Some(want),
                    "{r:?} {g:?}"
                );
            }
        }
        // 3.12's: tag then code; 4.0's: a list of one vocab
        assert_eq!(
            ReturnValue::NotReady.bare(Generation::V3),
            [1, 0, 0, 0, 6, 0, 0, 0]
        );
        assert_eq!(ReturnValue::Ok.bare(Generation::V4).len(), 16);
        assert_eq!(ReturnValue::from_bare(&[0; 12]), None);
    }

    #[test]
    fn protocol_versions() {
        let r = protocol_version_reply(Generation::V4);
        assert_eq!(protocol_version_of(&r), Some((0, [4, 0, 0])));
        let r = protocol_version_reply(Generation::V3);
        assert_eq!(protocol_version_of(&r), Some((0, [3, 12, 3])));
        assert_eq!(generation_of_version([3, 12, 3]), Generation::V3);
        assert_eq!(generation_of_version([4, 0, 0]), Generation::V4);
    }
}
