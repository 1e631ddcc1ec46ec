//! The wire of icub-main's raw values publisher (`rawValuesPublisher.thrift`, YARP's thrift
//! encoding): the stream's `rawValuesDataVectorsMap` and the `RawValuesPublisherMetadata`
//! service's one method, `getMetadata`.
//!
//! Written as C++'s generated code writes them, which no Bottle encodes to (strings carry
//! no NUL, and those inside a string list no tag); read from the Bottle the bytes decode to.
//!
//! - stream: `[list 1] [list N] N × ([list 2] key [list|int32 n] n raw int32)`;
//! - `getMetadata`: the call `[list 1] "getMetadata"`, the reply `[list 1] [list N] N ×
//!   ([list 2] key [list 3] [list|string r] names… [list|string a] axes… [int32 size])`.

use std::collections::BTreeMap;
use yarp_devices::raw_values::RawValuesKeyMetadata;
use yarp_devices::sensors::wire::WireWriter;
use yarp_devices::thrift::{fail_reply, is_protocol_version_request, protocol_version_reply, word};
use yarp_proto::tags::Generation;
use yarp_proto::{Bottle, Value, Vocab32};

/// The service's one method.
pub const GET_METADATA: &str = "getMetadata";

/// The stream message of `map`.
pub fn encode_data_map(map: &BTreeMap<String, Vec<i32>>) -> Vec<u8> {
    let mut w = WireWriter::new();
    w.list_header(1).list_header(map.len());
    for (key, values) in map {
        w.list_header(2)
            .string(key)
            .int32_list(values.iter().copied());
    }
    w.into_bytes()
}

/// The `getMetadata` reply: its one-element reply list, then the map.
pub fn encode_metadata_reply(map: &BTreeMap<String, RawValuesKeyMetadata>) -> Vec<u8> {
    let mut w = WireWriter::new();
    w.list_header(1).list_header(map.len());
    for (key, m) in map {
        w.list_header(2).string(key);
        w.list_header(3)
            .string_list(&m.raw_value_names)
            .string_list(&m.axes_names)
            .int32(m.size);
    }
    w.into_bytes()
}

/// The `getMetadata` call.
pub fn encode_get_metadata() -> Vec<u8> {
    let mut w = WireWriter::new();
    w.list_header(1).string(GET_METADATA);
    w.into_bytes()
}

/// Why a message is not what the protocol says.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("not a raw values {what}: {why}")]
pub struct WireError {
    what: &'static str,
    why: String,
}

fn bad(what: &'static str, why: impl Into<String>) -> WireError {
    WireError {
        what,
        why: why.into(),
    }
}

/// The entries of a map: the single list a one-element struct or reply holds.
fn entries<'a>(b: &'a Bottle, what: &'static str) -> Result<&'a Bottle, WireError> {
    match b.items() {
        [Value::List(map)] => Ok(map),
        _ => Err(bad(what, format!("expected one list, got {b}"))),
    }
}

fn key_and_value<'a>(e: &'a Value, what: &'static str) -> Result<(String, &'a Value), WireError> {
    match e.as_list().map(Bottle::items) {
        Some([k, v]) => {
            let key = word(k).ok_or_else(|| bad(what, format!("key {k}")))?;
            Ok((key, v))
        }
        _ => Err(bad(what, format!("entry {e}"))),
    }
}

/// A stream message.
pub fn decode_data_map(b: &Bottle) -> Result<BTreeMap<String, Vec<i32>>, WireError> {
    const WHAT: &str = "rawValuesDataVectorsMap";
    let mut map = BTreeMap::new();
    for e in entries(b, WHAT)?.iter() {
        let (key, v) = key_and_value(e, WHAT)?;
        let values = v
            .as_list()
            .and_then(|l| l.iter().map(Value::as_i32).collect::<Option<Vec<_>>>())
            .ok_or_else(|| bad(WHAT, format!("values of {key}: {v}")))?;
        map.insert(key, values);
    }
    Ok(map)
}

fn strings(v: &Value, what: &'static str) -> Result<Vec<String>, WireError> {
    v.as_list()
        .and_then(|l| l.iter().map(|s| s.as_str().map(str::to_string)).collect())
        .ok_or_else(|| bad(what, format!("a string list, got {v}")))
}

/// A `getMetadata` reply.
pub fn decode_metadata_reply(
    b: &Bottle,
) -> Result<BTreeMap<String, RawValuesKeyMetadata>, WireError> {
    const WHAT: &str = "rawValuesKeyMetadataMap";
    let mut map = BTreeMap::new();
    for e in entries(b, WHAT)?.iter() {
        let (key, v) = key_and_value(e, WHAT)?;
        let m = match v.as_list().map(Bottle::items) {
            Some([names, axes, size]) => RawValuesKeyMetadata {
                raw_value_names: strings(names, WHAT)?,
                axes_names: strings(axes, WHAT)?,
                size: size
                    .as_i32()
                    .ok_or_else(|| bad(WHAT, format!("size of {key}: {size}")))?,
            },
            _ => return Err(bad(WHAT, format!("metadata of {key}: {v}"))),
        };
        map.insert(key, m);
    }
    Ok(map)
}

/// Answers one request on the server's RPC port: `getMetadata` with `metadata()` (an
/// error answers an empty map, as C++'s cache holds nothing then), `help` as C++'s
/// generated reader, `getRemoteProtocolVersion`; anything else fails.
pub fn handle_rpc(
    cmd: &Bottle,
    metadata: impl FnOnce() -> Option<BTreeMap<String, RawValuesKeyMetadata>>,
    generation: Generation,
) -> Vec<u8> {
    if is_protocol_version_request(cmd) {
        return protocol_version_reply(generation);
    }
    let words: Option<Vec<String>> = cmd.iter().map(word).collect();
    let mut words = words.unwrap_or_default();
    if words.first().map(String::as_str) == Some("__direct__") {
        words.remove(0);
    }
    match words.iter().map(String::as_str).collect::<Vec<_>>()[..] {
        [GET_METADATA] => encode_metadata_reply(&metadata().unwrap_or_default()),
        ["help"] | ["help", "--all"] => {
            let mut w = WireWriter::new();
            w.list_header(2).vocab(Vocab32::new("many")).list_header(3);
            for s in ["*** Available commands:", GET_METADATA, "help"] {
                w.string(s);
            }
            w.into_bytes()
        }
        _ => fail_reply(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decoded(bytes: &[u8]) -> Bottle {
        Bottle::decode(bytes).expect("a Bottle")
    }

    #[test]
    fn the_stream_has_cpps_bytes_and_reads_back() {
        // one key "k" with [5, -1], as C++'s generated code writes it
        let map = BTreeMap::from([("k".to_string(), vec![5, -1])]);
        let want = "000100000100000000010000010000000001000002000000\
                    04000000010000006b\
                    0101000002000000\
                    05000000ffffffff";
        assert_eq!(hex(&encode_data_map(&map)), want);
        assert_eq!(decode_data_map(&decoded(&encode_data_map(&map))), Ok(map));
        let empty = BTreeMap::new();
        assert_eq!(
            decode_data_map(&decoded(&encode_data_map(&empty))),
            Ok(empty)
        );
        assert!(decode_data_map(&Bottle::from_text("1 2")).is_err());
        assert!(decode_data_map(&Bottle::from_text("((k (1 x)))")).is_err());
    }

    fn hex(b: &[u8]) -> String {
        b.iter().map(|x| format!("{x:02x}")).collect()
    }

    #[test]
    fn metadata_round_trip_and_the_call() {
        let m = RawValuesKeyMetadata {
            raw_value_names: vec!["j0_primary".into(), "j0_secondary".into()],
            axes_names: vec!["j0".into()],
            size: 2,
        };
        let map = BTreeMap::from([("eoprot_tag_mc_joint_status_addinfo_multienc".to_string(), m)]);
        let reply = encode_metadata_reply(&map);
        assert_eq!(decode_metadata_reply(&decoded(&reply)), Ok(map.clone()));
        let call = encode_get_metadata();
        assert_eq!(call.len(), 27);
        let cmd = decoded(&call);
        assert_eq!(
            handle_rpc(&cmd, || Some(map.clone()), Generation::V3),
            reply
        );
        assert_eq!(
            handle_rpc(&Bottle::from_text("getMetadata 1"), || None, Generation::V3),
            fail_reply()
        );
        let help = decoded(&handle_rpc(
            &Bottle::from_text("help"),
            || None,
            Generation::V3,
        ));
        assert_eq!(
            help.to_string(),
            "[many] (\"*** Available commands:\" getMetadata help)"
        );
    }
}
