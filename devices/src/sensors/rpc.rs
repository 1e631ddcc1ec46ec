//! The `MultipleAnalogSensorsMetadata` thrift service served on `/<name>/rpc:o`, as a
//! pure function from the request Bottle to the reply bytes.
//!
//! Commands (the C++ generated `read`): `getMetadata` (no arguments),
//! `getRemoteProtocolVersion` (every 3.12 thrift service has it) and `help [function]`,
//! optionally behind `__direct__`. Anything else, or extra arguments,
//! gets `[fail]`, as C++ `WireReader::fail` answers.

use super::wire::{SensorRpcData, WireWriter};
use yarp_proto::{Bottle, Value, Vocab32};

/// The one service method.
pub const GET_METADATA: &str = "getMetadata";
const HELP: &str = "help";
const PROTOTYPE: &str = "SensorRPCData MultipleAnalogSensorsMetadata::getMetadata()";
const METHOD_HELP: &str =
    "Read the sensor metadata necessary to configure the MultipleAnalogSensorsClient device.";

/// The method every thrift service of C++ YARP 3.12 answers besides its own (not listed
/// by `help`): newer clients call it on connecting and refuse a server whose
/// `protocol_version` differs from theirs.
pub const GET_PROTOCOL_VERSION: &str = "getRemoteProtocolVersion";

/// The YARP version this implementation speaks the protocols of, as C++ reports it in
/// `getRemoteProtocolVersion`.
pub const YARP_VERSION: [i16; 3] = [3, 12, 3];

/// The `getRemoteProtocolVersion` reply: a one-element list header followed by an
/// `ApplicationNetworkProtocolVersion` written untagged (four int16: the service's
/// protocol version, 0 for every 3.12 service, then YARP's major, minor and patch).
pub fn protocol_version_reply() -> Vec<u8> {
    let mut w = WireWriter::new();
    w.list_header(1).raw_int16(0);
    for part in YARP_VERSION {
        w.raw_int16(part);
    }
    w.into_bytes()
}

/// Whether `cmd` is `getRemoteProtocolVersion`, optionally behind `__direct__`, without
/// arguments (with arguments C++ fails the request).
pub fn is_protocol_version_request(cmd: &Bottle) -> bool {
    let mut words = cmd.iter().map(Some).map(tag).peekable();
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
fn tag(v: Option<&Value>) -> Option<String> {
    match v? {
        Value::String(s) => Some(String::from_utf8_lossy(s).into_owned()),
        Value::Vocab32(v) => Some(v.as_string()),
        _ => None,
    }
}

/// Lines of C++ `MultipleAnalogSensorsMetadata::help(functionName)`.
fn help_lines(function: &str) -> Vec<&'static str> {
    let lines = match function {
        "--all" => vec!["*** Available commands:", GET_METADATA, HELP],
        GET_METADATA => vec![PROTOTYPE, METHOD_HELP],
        HELP => vec![
            "std::vector<std::string> help(const std::string& functionName = \"--all\")",
            "Return list of available commands, or help message for a specific function",
            "@param functionName name of command for which to get a detailed description. If none or '--all' is provided, print list of available commands",
            "@return list of strings (one string per line)",
        ],
        _ => vec![],
    };
    if lines.is_empty() {
        vec!["Command not found"]
    } else {
        lines
    }
}

/// The `help` reply: `[many] ("line" ...)`, every string tagged.
fn help_reply(function: &str) -> Vec<u8> {
    let lines = help_lines(function);
    let mut w = WireWriter::new();
    w.list_header(2).vocab(Vocab32::new("many"));
    w.list_header(lines.len());
    for l in lines {
        w.string(l);
    }
    w.into_bytes()
}

/// Serves one request against the server's metadata; returns the reply bytes.
pub fn handle_rpc(cmd: &Bottle, metadata: &SensorRpcData) -> Vec<u8> {
    if is_protocol_version_request(cmd) {
        return protocol_version_reply();
    }
    let mut args = cmd.iter().peekable();
    let mut word = tag(args.next());
    if word.as_deref() == Some("__direct__") {
        word = tag(args.next());
    }
    match word.as_deref() {
        Some(GET_METADATA) if args.peek().is_none() => metadata.encode_reply(),
        Some(HELP) => {
            let function = match args.next() {
                Some(Value::String(s)) => String::from_utf8_lossy(s).into_owned(),
                _ => "--all".to_string(),
            };
            help_reply(&function)
        }
        other => {
            tracing::warn!("multipleanalogsensorsserver rpc: cannot serve {cmd} ({other:?})");
            fail_reply()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sensors::wire::SensorMetadata;

    fn md() -> SensorRpcData {
        let mut d = SensorRpcData::default();
        d.families[5].push(SensorMetadata::new("ft", "ft_frame"));
        d
    }

    fn reply(text: &str) -> String {
        Bottle::decode(&handle_rpc(&Bottle::from_text(text), &md()))
            .unwrap()
            .to_string()
    }

    #[test]
    fn get_metadata_in_every_spelling() {
        let want = "() () () () () ((ft ft_frame \"\")) () () () () () ()";
        assert_eq!(reply("getMetadata"), want);
        assert_eq!(reply("\"getMetadata\""), want);
        assert_eq!(reply("__direct__ getMetadata"), want);
        assert_eq!(reply("getMetadata 3"), "[fail]");
    }

    #[test]
    fn help_for_each_function() {
        assert!(reply("help getMetadata").contains("SensorRPCData"));
        assert!(reply("help help").contains("@return list of strings"));
        assert_eq!(reply("help nothing"), "[many] (\"Command not found\")");
        assert_eq!(reply("[help]"), reply("help"));
    }

    #[test]
    fn protocol_version_as_cpp_writes_it() {
        // WireWriter::writeListHeader(1), then ApplicationNetworkProtocolVersion::write:
        // appendInt16 of protocol_version (0), yarp_major, yarp_minor, yarp_patch.
        let want: [u8; 16] = [
            0x00, 0x01, 0x00, 0x00, // BOTTLE_TAG_LIST (256)
            0x01, 0x00, 0x00, 0x00, // one element
            0x00, 0x00, // protocol_version 0
            0x03, 0x00, // 3
            0x0c, 0x00, // 12
            0x03, 0x00, // 3
        ];
        for text in [
            "getRemoteProtocolVersion",
            "__direct__ getRemoteProtocolVersion",
        ] {
            assert_eq!(handle_rpc(&Bottle::from_text(text), &md()), want, "{text}");
        }
    }

    #[test]
    fn anything_else_fails() {
        for text in [
            "",
            "42",
            "(getMetadata)",
            "getRemoteProtocolVersion 1",
            "[zzz] 1",
        ] {
            assert_eq!(reply(text), "[fail]", "{text:?}");
        }
    }
}
