//! Bytes between a host and a Slamtec RPLidar (robotology/yarp-device-rplidar's serial
//! protocol): the requests a lidar reads from them, and every descriptor, device
//! information, configuration answer, standard measurement, express and ultra capsule
//! the host reads, the capsules through the SDK's converters. Must never panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use rplidar::protocol::*;

fuzz_target!(|data: &[u8]| {
    let mut reader = RequestReader::default();
    reader.push(data);
    while reader.next_request().is_some() {}
    let _ = Descriptor::decode(data);
    let _ = DeviceInfo::decode(data);
    let _ = conf_value(conf::SCAN_MODE_NAME, data);
    for chunk in data.chunks_exact(5) {
        let _ = decode_standard(chunk.try_into().unwrap());
    }
    let mut express = CapsuleDecoder::default();
    for chunk in data.chunks_exact(Capsule::LEN) {
        if let Ok(c) = Capsule::decode(chunk) {
            let _ = express.push(c);
        }
    }
    let mut ultra = UltraCapsuleDecoder::default();
    for chunk in data.chunks_exact(UltraCapsule::LEN) {
        if let Ok(c) = UltraCapsule::decode(chunk) {
            let _ = ultra.push(c);
        }
    }
    // the same bytes as capsules whatever their checksums
    if data.len() >= 4 + 2 * UltraCapsule::LEN {
        let mut ultra = UltraCapsuleDecoder::default();
        for k in 0..2 {
            let at = 4 + k * UltraCapsule::LEN;
            let cabins = std::array::from_fn(|i| u32::from_le_bytes(data[at + 4 * i..at + 4 * i + 4].try_into().unwrap()));
            let _ = ultra.push(UltraCapsule { start_angle_sync_q6: u16::from_le_bytes([data[k], data[k + 1]]), cabins });
        }
    }
});
