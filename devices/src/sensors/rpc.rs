//! The `MultipleAnalogSensorsMetadata` thrift service served on `/<name>/rpc:o`, as a
//! pure function from the request Bottle to the reply bytes.
//!
//! Commands (the C++ generated `read`): `getMetadata` (no arguments),
//! `getRemoteProtocolVersion` (every thrift service has it) and `help [function]`,
//! optionally behind `__direct__`. Anything else, or extra arguments,
//! gets `[fail]`, as C++ `WireReader::fail` answers. The service is the same in YARP
//! 3.12 and 4.0 and so are its replies' bytes (they hold no floats).

use super::wire::{SensorRpcData, WireWriter};
use crate::thrift::{fail_reply, is_protocol_version_request, protocol_version_reply, word};
use yarp_proto::tags::Generation;
use yarp_proto::{Bottle, Value, Vocab32};

/// The one service method.
pub const GET_METADATA: &str = "getMetadata";
const HELP: &str = "help";
const PROTOTYPE: &str = "SensorRPCData MultipleAnalogSensorsMetadata::getMetadata()";
const METHOD_HELP: &str =
    "Read the sensor metadata necessary to configure the MultipleAnalogSensorsClient device.";

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

/// Serves one request of a client of `generation` against the server's metadata;
/// returns the reply bytes.
pub fn handle_rpc(cmd: &Bottle, metadata: &SensorRpcData, generation: Generation) -> Vec<u8> {
    if is_protocol_version_request(cmd) {
        return protocol_version_reply(generation);
    }
    let mut args = cmd.iter().peekable();
    let mut method = args.next().and_then(word);
    if method.as_deref() == Some("__direct__") {
        method = args.next().and_then(word);
    }
    match method.as_deref() {
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
        Bottle::decode(&handle_rpc(&Bottle::from_text(text), &md(), Generation::V3))
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
            assert_eq!(
                handle_rpc(&Bottle::from_text(text), &md(), Generation::V3),
                want,
                "{text}"
            );
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
