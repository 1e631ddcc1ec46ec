//! An embObj ropframe from an Ethernet iCub board (or from the host, for the emulator),
//! from arbitrary bytes: what `icub-eth` decodes from every UDP datagram on port 12345.
//! Must never panic; the ROPs it accepts re-encode to ROPs that decode the same; the
//! board engine and the host transceiver take the datagram without panicking.
#![no_main]

use icub_eth::board::{BoardConfig, BoardEngine};
use icub_eth::entities::boards::EthBoardType;
use icub_eth::host::{HostConfig, HostTransceiver};
use icub_eth::{decode_datagram, FrameBuilder, Rop};
use libfuzzer_sys::fuzz_target;
use std::net::Ipv4Addr;
use std::time::Duration;

fuzz_target!(|data: &[u8]| {
    if let Ok((header, rops, _)) = decode_datagram(data) {
        let mut fb = FrameBuilder::new(usize::from(u16::MAX));
        for r in &rops {
            let _ = fb.push(r);
        }
        let again = fb.finish(header.sequence, header.age);
        let (_, back, err) = decode_datagram(&again).expect("re-encoded frame is valid");
        assert!(err.is_none());
        assert_eq!(back.len(), rops.len());
        for (a, b) in back.iter().zip(&rops) {
            assert_eq!(a.encode().ok(), b.encode().ok());
        }
    }
    let _ = Rop::decode(data);

    let ip = Ipv4Addr::new(10, 0, 1, 1);
    let mut cfg = BoardConfig::new("fuzz", ip, EthBoardType::Ems4);
    cfg.joints = 4;
    cfg.fts = 1;
    cfg.skins = 1;
    let mut board = BoardEngine::new(cfg);
    let _ = board.handle_datagram(data);
    board.step(0.001);
    let mut n = 0;
    while let Some(out) = board.poll_transmit(Duration::from_millis(1)) {
        n += 1;
        assert!(n < 10_000, "board keeps transmitting");
        let _ = decode_datagram(&out).expect("board frames are valid");
    }
    let mut host = HostTransceiver::new(HostConfig::new("fuzz", ip, EthBoardType::Ems4));
    let _ = host.handle_datagram(data, Duration::from_millis(1));
    host.handle_timeout(Duration::from_secs(1));
    while host.poll_event().is_some() {}
});
