//! Bytes from the head IMU's serial port (Xsens MT protocol): every message found in
//! them, and every `MTData` payload read as a sample. Must never panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = icub_can::xsens::decode_any(data);
});
