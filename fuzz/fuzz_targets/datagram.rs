//! The udp/mcast datagram reader on arbitrary datagrams: the input is cut into datagrams
//! at 0xff bytes; CRCs, counters, reassembly and message decoding must never panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use yarp_proto::wire::datagram::DatagramReader;
use yarp_proto::wire::{Carrier, DecoderConfig};

fuzz_target!(|data: &[u8]| {
    let config = DecoderConfig {
        max_message_size: 1 << 20,
        ..DecoderConfig::default()
    };
    let mut reader = DatagramReader::for_carrier(Carrier::Udp, config);
    for datagram in data.split(|&b| b == 0xff) {
        let _ = reader.push(datagram);
    }
    let _ = reader.stats();
});
