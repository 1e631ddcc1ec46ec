//! Bottle::decode on arbitrary bytes. Whatever decodes must survive a round trip:
//! decode(encode(x)) == x, and the re-encoding is canonical (encoding it again gives the
//! same bytes). The input bytes themselves may legitimately differ from the re-encoding
//! (trailing bytes, a non-compacted list that could be compacted, negative counts...).
#![no_main]

use libfuzzer_sys::fuzz_target;
use yarp_proto::Bottle;

fuzz_target!(|data: &[u8]| {
    let Ok(b) = Bottle::decode(data) else {
        return;
    };
    let bytes = b.encode();
    let back = match Bottle::decode(&bytes) {
        Ok(back) => back,
        Err(e) => panic!("re-encoding of a decoded bottle does not decode: {e}\n{b:?}"),
    };
    assert_eq!(back, b, "decode(encode(x)) != x");
    assert_eq!(back.encode(), bytes, "re-encoding is not canonical");
    // the text printer must cope with anything the decoder accepts
    let _ = b.to_text();
});
