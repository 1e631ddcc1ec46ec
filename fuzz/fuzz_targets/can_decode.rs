//! A cannelloni datagram (CAN frames over UDP) and every iCub CAN message in it, from
//! arbitrary bytes: what the CAN-over-UDP backend reads from the network. Must never panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = icub_can::proto::decode_any(data);
});
