//! Cost of the 1 kHz status stream of one running board (an arm board: 4 joints with core,
//! multienc and motor status, one F/T): the board engine producing a regulars frame
//! (`step` + `poll_transmit`) and the host transceiver taking it (`handle_datagram`).
//! Multiply by the boards of a robot × 1000 for the whole-robot load.

use criterion::{criterion_group, criterion_main, Criterion};
use icub_eth::board::{BoardConfig, BoardEngine};
use icub_eth::entities::boards::EthBoardType;
use icub_eth::entities::mn::{category, ServiceCommand, ServiceOperation};
use icub_eth::host::{HostConfig, HostTransceiver};
use icub_eth::id::{entity as en, ids, tag};
use icub_eth::{Entity, FrameBuilder, Rop};
use std::hint::black_box;
use std::net::Ipv4Addr;
use std::time::Duration;

fn running_board() -> BoardEngine {
    let ip = Ipv4Addr::new(10, 0, 1, 1);
    let mut cfg = BoardConfig::new("left_arm-eb1", ip, EthBoardType::Ems4);
    cfg.joints = 4;
    cfg.fts = 1;
    let mut b = BoardEngine::new(cfg);
    let mut regs = Vec::new();
    for j in 0..4 {
        regs.push(ids::joint(j, tag::MC_JOINT_STATUS_CORE));
        regs.push(ids::joint(j, tag::MC_JOINT_STATUS_ADDINFO_MULTIENC));
        regs.push(ids::motor(j, tag::MC_MOTOR_STATUS));
    }
    regs.push(ids::analog(en::AS_FT, 0, tag::AS_FT_STATUS));
    let mut fb = FrameBuilder::new(1500);
    for c in [
        ServiceCommand::bare(ServiceOperation::VerifyActivate, category::MC),
        ServiceCommand::regsig_load(category::MC, &regs),
        ServiceCommand::bare(ServiceOperation::Start, category::MC),
    ] {
        fb.push(&Rop::set(ids::SERVICE_COMMAND, c.to_bytes()))
            .unwrap();
        b.handle_datagram(&fb.finish(1, 0)).unwrap();
        fb.clear();
        while b.poll_transmit(Duration::ZERO).is_some() {}
    }
    b
}

fn bench(c: &mut Criterion) {
    let mut board = running_board();
    let mut host = HostTransceiver::new(HostConfig::new(
        "left_arm-eb1",
        Ipv4Addr::new(10, 0, 1, 1),
        EthBoardType::Ems4,
    ));
    let mut now = Duration::from_secs(1);
    let frame = {
        now += Duration::from_millis(1);
        board.step(0.001);
        board.poll_transmit(now).expect("regulars due")
    };
    println!("regulars frame: {} bytes, 13 ROPs", frame.len());
    c.bench_function("board: step + regulars frame (13 ROPs)", |b| {
        b.iter(|| {
            now += Duration::from_millis(1);
            board.step(0.001);
            black_box(board.poll_transmit(now))
        })
    });
    let mut datagram = frame.clone();
    let mut seq = 1u64;
    c.bench_function("host: handle regulars frame (13 ROPs)", |b| {
        b.iter(|| {
            now += Duration::from_millis(1);
            // A fresh sequence number each time (offset 16), as the board sends them.
            seq += 1;
            datagram[16..24].copy_from_slice(&seq.to_le_bytes());
            host.handle_datagram(black_box(&datagram), now).unwrap();
            while host.poll_event().is_some() {}
        })
    });
    c.bench_function("decode_datagram (13 ROPs, owned)", |b| {
        b.iter(|| black_box(icub_eth::decode_datagram(black_box(&frame)).unwrap()))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
