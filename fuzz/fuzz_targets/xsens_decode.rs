//! Bytes from an Xsens IMU's serial port (MT protocol: the iCub head's MTx, the ergoCub
//! waist's MTi): every message found in them, every payload read as an `MTData` sample,
//! an `MTData2` and an output configuration. Must never panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = icub_can::xsens::decode_any(data);
});
