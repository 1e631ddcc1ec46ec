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
