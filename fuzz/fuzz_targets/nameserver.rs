//! The name server's command handling on arbitrary command lines (as a telnet user or a
//! hostile client would send them), both as text and as binary Bottles, plus the client's
//! reply parsers on arbitrary reply text. Nothing may panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use yarp_proto::nameserver::{
    parse_check_reply, parse_property_reply, parse_registration, reply_text, Registry,
    RegistryConfig,
};
use yarp_proto::Bottle;

fuzz_target!(|data: &[u8]| {
    let mut reg = Registry::new(RegistryConfig::new("127.0.0.1", 10000));
    for line in data.split(|&b| b == b'\n').take(64) {
        let cmd = Bottle::from_text(line);
        let reply = reg.apply(&cmd, Some("127.0.0.1"));
        let _ = reply_text(&reply);
    }
    if let Ok(b) = Bottle::decode(data) {
        let _ = reg.apply(&b, None);
    }
    let text = String::from_utf8_lossy(data);
    let _ = parse_registration(&text);
    let _ = parse_property_reply(&text);
    let _ = parse_check_reply(&text);
});
