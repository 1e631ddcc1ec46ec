//! Property::from_config_text on arbitrary UTF-8: must never panic (errors are fine), and
//! what it reads must print.
//!
//! `[include file]` reads files relative to the current directory (the fuzz directory
//! when run by cargo fuzz, which holds no `.ini` files outside seeds/). Inputs naming
//! device or kernel filesystems are skipped: `[include /dev/zero]` would read forever,
//! which is the caller's trust in its config files, not a parser bug. (Changing directory
//! here is not an option: libFuzzer reads its corpus files lazily by relative path.)
#![no_main]

use libfuzzer_sys::fuzz_target;
use yarp_proto::Property;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if ["/dev", "/proc", "/sys"].iter().any(|p| text.contains(p)) {
        return;
    }
    if let Ok(p) = Property::from_config_text(text) {
        let _ = p.to_text();
    }
});
