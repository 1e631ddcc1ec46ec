//! Bottle::from_text on arbitrary bytes, then print: printing must be a fixed point of
//! parse-then-print, except for the documented C++-compatible quirks (see `quirk`), which
//! C++ YARP 3.12 shares.
#![no_main]

use libfuzzer_sys::fuzz_target;
use yarp_proto::{Bottle, Value, Vocab32};

fuzz_target!(|data: &[u8]| {
    let b = Bottle::from_text(data);
    let p1 = b.to_text();
    let b2 = Bottle::from_text(&p1);
    let p2 = b2.to_text();
    if p2 != p1 && !quirk(&b) && !quirk(&b2) {
        panic!(
            "print is not a fixed point\ninput: {:?}\np1:    {:?}\np2:    {:?}\nb:  {b:?}\nb2: {b2:?}",
            String::from_utf8_lossy(data),
            String::from_utf8_lossy(&p1),
            String::from_utf8_lossy(&p2),
        );
    }
    // what parses also round-trips through the binary codec
    assert_eq!(Bottle::decode(&b.encode()).ok().as_ref(), Some(&b));
});

/// Values whose text C++ reads back as something printing differently: vocabs with bytes
/// outside printable ASCII or with text delimiters (or none at all: `[]` reads as
/// `false`; nothing but `1` and NULs: `[1]` reads as `'1'`, printed `true`), the bare word `null` (read as the vocab `[null]`) and sign-bit NaNs
/// (printed `-nan.0`, read as a string). Same list as yarp-proto/tests/roundtrip.rs.
fn quirk(b: &Bottle) -> bool {
    b.iter().any(|v| match v {
        Value::Vocab32(voc) => vocab_quirk(*voc),
        Value::String(s) => s == b"null",
        Value::Float32(x) => x.is_nan() && x.is_sign_negative(),
        Value::Float64(x) => x.is_nan() && x.is_sign_negative(),
        Value::List(l) | Value::Dict(l) => quirk(l),
        _ => false,
    })
}

fn vocab_quirk(voc: Vocab32) -> bool {
    if voc == Vocab32::TRUE || voc == Vocab32::FALSE {
        return false;
    }
    let text = voc.decode();
    text.is_empty()
        || text == b"1"
        || text.iter().any(|&c| {
            !(0x21..0x7f).contains(&c)
                || matches!(c, b',' | b'"' | b'\\' | b'(' | b')' | b'{' | b'}')
        })
}
