//! Measures polling round trips and command-to-encoder latency against the emulator,
//! on the in-process bus and over cannelloni/UDP on loopback.
//!
//! `cargo run --release -p icub-can --example can_latency` (run under netns-run).

use std::sync::Arc;
use std::time::{Duration, Instant};

use icub_can::bus::inproc::VirtualBus;
use icub_can::bus::udp::UdpBus;
use icub_can::client::{McParams, MotorControlClient};
use icub_can::emulator::{BusEmulator, McBoard, McBoardConfig};
use icub_can::proto::ControlMode;
use icub_can::CanBus;

fn percentile(v: &mut [f64], p: f64) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v[((v.len() - 1) as f64 * p).round() as usize]
}

fn measure(name: &str, emu_bus: Arc<dyn CanBus>, client_bus: impl FnOnce() -> Arc<dyn CanBus>) {
    let _emu = BusEmulator::new(emu_bus, vec![Box::new(McBoard::new(McBoardConfig::new(1)))])
        .spawn()
        .unwrap();
    let mc = MotorControlClient::open(client_bus(), McParams::uniform(&[1], 2, 11.375)).unwrap();
    let mut polls: Vec<f64> = (0..500)
        .map(|_| {
            let t = Instant::now();
            mc.poll_encoder(0).unwrap();
            t.elapsed().as_secs_f64() * 1e6
        })
        .collect();
    mc.set_control_mode(0, ControlMode::Direct).unwrap();
    std::thread::sleep(Duration::from_millis(50));
    let mut moves = Vec::new();
    for i in 0..100 {
        let before = loop {
            if let Ok(e) = mc.encoder(0) {
                break e;
            }
        };
        let target = if i % 2 == 0 { 10.0 } else { 0.0 };
        let t = Instant::now();
        mc.set_position(0, target).unwrap();
        while (mc.encoder(0).unwrap() - before).abs() < 0.05 {
            assert!(t.elapsed() < Duration::from_secs(1), "no motion");
            std::thread::sleep(Duration::from_micros(50));
        }
        moves.push(t.elapsed().as_secs_f64() * 1e3);
        std::thread::sleep(Duration::from_millis(300));
    }
    println!(
        "{name}: poll round trip median {:.0} us p99 {:.0} us; command->encoder median {:.1} ms p99 {:.1} ms",
        percentile(&mut polls, 0.5),
        percentile(&mut polls, 0.99),
        percentile(&mut moves, 0.5),
        percentile(&mut moves, 0.99)
    );
}

fn main() {
    let bus = VirtualBus::new("latency");
    let b2 = bus.clone();
    measure("inproc", Arc::new(bus.endpoint()), move || {
        Arc::new(b2.endpoint())
    });
    let hub = UdpBus::hub("127.0.0.1:0").unwrap();
    let addr = hub.local_addr().unwrap().to_string();
    measure("udp", Arc::new(hub), move || {
        Arc::new(UdpBus::connect(&addr, None).unwrap())
    });
}
