//! What the image carriers of ergoCub's ROS 2 repeaters cost per frame (criterion): the
//! mjpeg carrier's JPEG compression and decompression of a 640x480 colour image (the
//! writer and the reader of every frame), and the depthimage_compression_zlib monitor on
//! a 640x480 float depth image (sender and receiver).
//!
//! Run: `cargo bench -p yarp-proto --bench carriers -- --warm-up-time 1 --measurement-time 3`

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use std::hint::black_box;
use yarp_proto::image::{Image, PixelCode};
use yarp_proto::portmonitor::{Monitor, Side};
use yarp_proto::wire::mjpeg::{decode_jpeg, encode_jpeg};
use yarp_proto::wire::modifiers::CarrierName;
use yarp_proto::Stamp;

const W: usize = 640;
const H: usize = 480;

/// A camera-like colour image: smooth gradients with some texture.
fn colour() -> Image {
    let mut img = Image::new(PixelCode::RGB, W, H).unwrap();
    for y in 0..H {
        for x in 0..W {
            let t = ((x * 7 + y * 13) % 17) as u8;
            img.pixel_mut(x, y).copy_from_slice(&[
                (x / 3) as u8 ^ t,
                (y / 2) as u8,
                ((x + y) / 5) as u8,
            ]);
        }
    }
    img
}

/// A depth image of a scene: a floor plane and a box, in metres.
fn depth() -> Image {
    let mut img = Image::new(PixelCode::MONO_FLOAT, W, H).unwrap();
    for y in 0..H {
        for x in 0..W {
            let d = if (200..400).contains(&x) && (150..330).contains(&y) {
                1.2
            } else {
                0.8 + y as f32 * 0.004
            };
            img.pixel_mut(x, y).copy_from_slice(&d.to_le_bytes());
        }
    }
    img
}

fn mjpeg(c: &mut Criterion) {
    let img = colour();
    let stamp = Stamp::new(1, 1764240000.0);
    let jpeg = encode_jpeg(&img, Some(&stamp)).unwrap();
    let mut g = c.benchmark_group("mjpeg 640x480 rgb");
    g.throughput(Throughput::Bytes((W * H * 3) as u64));
    g.bench_function(format!("encode (-> {} bytes)", jpeg.len()), |b| {
        b.iter(|| encode_jpeg(black_box(&img), Some(&stamp)).unwrap())
    });
    g.bench_function("decode", |b| {
        b.iter(|| decode_jpeg(black_box(&jpeg)).unwrap())
    });
    g.finish();
}

fn depth_monitor(c: &mut Criterion) {
    let carrier = CarrierName::parse(
        "fast_tcp+send.portmonitor+file.depthimage_compression_zlib+recv.portmonitor+type.dll",
    );
    let tx = Monitor::for_side(&carrier, Side::Sender).unwrap().unwrap();
    let rx = Monitor::for_side(&carrier, Side::Receiver)
        .unwrap()
        .unwrap();
    let img = depth().to_bottle();
    let sent = tx.update(&img).unwrap();
    let size = sent.encode().len();
    let mut g = c.benchmark_group("depthimage_compression_zlib 640x480 float");
    g.throughput(Throughput::Bytes((W * H * 4) as u64));
    g.bench_function(format!("compress (-> {size} bytes)"), |b| {
        b.iter(|| tx.update(black_box(&img)).unwrap())
    });
    g.bench_function("decompress", |b| {
        b.iter(|| rx.update(black_box(&sent)).unwrap())
    });
    g.finish();
}

criterion_group!(benches, mjpeg, depth_monitor);
criterion_main!(benches);
