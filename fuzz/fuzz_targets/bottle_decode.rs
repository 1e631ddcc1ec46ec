//! Bottle::decode on arbitrary bytes. Whatever decodes must survive a round trip:
//! decode(encode(x)) == x, and the re-encoding is canonical (encoding it again gives the
//! same bytes). The input bytes themselves may legitimately differ from the re-encoding
//! (trailing bytes, a non-compacted list that could be compacted, negative counts...).
//! The round trip is in the input's generation (YARP 4.0's vocab64 has no 3.x form).
#![no_main]

use libfuzzer_sys::fuzz_target;
use yarp_proto::Bottle;

fuzz_target!(|data: &[u8]| {
    let Ok(b) = Bottle::decode(data) else {
        return;
    };
    let generation = yarp_proto::binary::generation_of(data);
    let bytes = b.encode_as(generation);
    // read back in that generation: a 4.0 encoding without 4.0-only tags (a float32 is
    // tagged as 3.x's float64) is not told apart by its bytes
    let back = match yarp_proto::binary::decode_as(&bytes, generation) {
        Ok((back, _)) => back,
        Err(e) => panic!("re-encoding of a decoded bottle does not decode: {e}\n{b:?}"),
    };
    assert_eq!(back, b, "decode(encode(x)) != x");
    assert_eq!(back.encode_as(generation), bytes, "re-encoding is not canonical");
    // the text printer must cope with anything the decoder accepts
    let _ = b.to_text();
});
