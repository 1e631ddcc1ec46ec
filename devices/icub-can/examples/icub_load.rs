//! Listens to every network of an emulated iCub and reports frames per second, so the
//! emulator runs at its real broadcast rates with a peer attached to each bus.
//!
//! ```text
//! icub-board-emulator --preset icub --bus udp-hub://127.0.0.1:20000+n --stream &
//! cargo run --release -p icub-can --example icub_load -- 127.0.0.1:20000 10
//! ```

use std::time::{Duration, Instant};

use icub_can::bus::config::BusSpec;

fn main() {
    let mut args = std::env::args().skip(1);
    let base = args.next().unwrap_or_else(|| "127.0.0.1:20000".into());
    let secs: f64 = args.next().and_then(|s| s.parse().ok()).unwrap_or(10.0);
    let buses: Vec<_> = (0..10)
        .map(|n| {
            BusSpec::parse(&format!("udp://{base}+n"), Some(n))
                .unwrap()
                .open()
                .unwrap()
        })
        .collect();
    let threads: Vec<_> = buses
        .into_iter()
        .map(|bus| {
            std::thread::spawn(move || {
                let end = Instant::now() + Duration::from_secs_f64(secs);
                let mut n = 0u64;
                while Instant::now() < end {
                    if bus.recv(Duration::from_millis(50)).is_ok() {
                        n += 1;
                    }
                }
                (bus.name().to_string(), n, bus.stats().malformed)
            })
        })
        .collect();
    let mut total = 0;
    for t in threads {
        let (name, n, bad) = t.join().unwrap();
        println!(
            "{name}: {:.0} frames/s, {bad} malformed datagrams",
            n as f64 / secs
        );
        total += n;
    }
    println!("total: {:.0} frames/s", total as f64 / secs);
}
