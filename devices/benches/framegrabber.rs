//! Frame-grabber benchmarks:
//!
//! * image codec: `encode_image` / `decode_image` of a 640x480 RGB frame, and the
//!   Bottle path the ports use (`to_bottle` + `Bottle::encode`, `Bottle::decode` +
//!   `from_bottle`);
//! * end to end on loopback: `fakeFrameGrabber` 640x480 -> `frameGrabber_nws_yarp`
//!   (period 10 ms) -> `frameGrabber_nwc_yarp`: frames received per second and the age
//!   of each frame when the client sees it (envelope time to arrival).
//!
//! Run (a private loopback-only network namespace):
//!
//! ```text
//! /work/shared/netns-run cargo bench -p yarp-devices --bench framegrabber [-- <filter>]
//! ```

use criterion::{criterion_group, Criterion};
use std::hint::black_box;
use std::time::{Duration, Instant};
use yarp_devices::framegrabber::{decode_image, encode_image, Image, PixelCode};
use yarp_devices::{runtime, PolyDriver};
use yarp_net::nameserver::NameServer;
use yarp_proto::{Bottle, Property};

fn frame() -> Image {
    let mut img = Image::new(PixelCode::RGB, 640, 480).unwrap();
    for (i, b) in img.data_mut().iter_mut().enumerate() {
        *b = (i % 251) as u8;
    }
    img
}

fn codec(c: &mut Criterion) {
    let img = frame();
    let bytes = encode_image(&img);
    c.bench_function("image_encode_640x480_rgb", |b| {
        b.iter(|| black_box(encode_image(black_box(&img))))
    });
    c.bench_function("image_decode_640x480_rgb", |b| {
        b.iter(|| black_box(decode_image(black_box(&bytes)).unwrap()))
    });
    c.bench_function("image_bottle_encode_640x480_rgb", |b| {
        b.iter(|| black_box(img.to_bottle().encode()))
    });
    c.bench_function("image_bottle_decode_640x480_rgb", |b| {
        b.iter(|| Image::from_bottle(&Bottle::decode(black_box(&bytes)).unwrap()).unwrap())
    });
}

use yarp_proto::stamp::now;

/// Streams for a few seconds and prints frames/s and frame age percentiles.
fn end_to_end() {
    let dir = tempfile::tempdir().unwrap();
    std::env::set_var("YARP_CONFIG_HOME", dir.path());
    let addr = runtime::block_on(async {
        let ns = NameServer::bind("127.0.0.1:0", "127.0.0.1").await.unwrap();
        let addr = ns.local_addr();
        tokio::spawn(ns.serve());
        addr
    })
    .expect("the device runtime");
    yarp_net::network::write_conf("127.0.0.1", addr.port()).unwrap();
    let open = |t: &str| PolyDriver::open(&Property::from_config_text(t).unwrap()).unwrap();
    let mut server = open(
        "device frameGrabber_nws_yarp\nsubdevice fakeFrameGrabber\nname /bcam\n\
         width 640\nheight 480\nmode grid\nperiod 0.01\n",
    );
    let mut client = open("device frameGrabber_nwc_yarp\nremote /bcam\nlocal /bcamc\n");
    let fg = client.device().as_frame_grabber_image().unwrap();
    let mut last = -1;
    let mut ages = Vec::new();
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(3) {
        if let Some(s) = fg.last_input_stamp() {
            if s.count != last {
                last = s.count;
                ages.push((now() - s.time) * 1000.0);
            }
        }
        std::thread::sleep(Duration::from_micros(200));
    }
    ages.sort_by(|a, b| a.total_cmp(b));
    let pct = |p: f64| ages[((ages.len() - 1) as f64 * p) as usize];
    println!(
        "framegrabber end-to-end 640x480 rgb @100 Hz: {:.1} frames/s received, frame age ms p50 {:.2} p90 {:.2} p99 {:.2}",
        ages.len() as f64 / 3.0,
        pct(0.5),
        pct(0.9),
        pct(0.99)
    );
    client.close().unwrap();
    server.close().unwrap();
}

criterion_group!(benches, codec);

fn main() {
    benches();
    // `-- <filter>`: the end-to-end run has the name `end_to_end`
    let filters: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    if filters.is_empty() || filters.iter().any(|f| "end_to_end".contains(f.as_str())) {
        end_to_end();
    }
    Criterion::default().configure_from_args().final_summary();
}
