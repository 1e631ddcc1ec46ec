//! The `mjpeg` carrier and the `portmonitor` carrier modifier between real ports, as
//! ergoCub's `sensors/ros2_repeaters` files use them: an RGB stream pulled as JPEGs
//! (`ImageCarrier mjpeg`), a depth stream compressed on the wire (`fast_tcp+send.portmonitor
//! +file.depthimage_compression_zlib+recv.portmonitor+...+type.dll`), a laser scan through
//! `bottle_compression_zlib`; connections made and removed with `yarp connect`'s logic,
//! a web client reading the mjpeg stream, and what cannot be had refused by name.
//! Run under ../shared/netns-run.

mod common;
use common::{eventually, name_server, T};
use std::io::{Read, Write};
use std::time::Duration;
use tokio::time::timeout;
use yarp_net::network;
use yarp_net::port::Port;
use yarp_proto::image::{Image, PixelCode};
use yarp_proto::{bottle, Bottle, Stamp};

const DEPTH: &str = "fast_tcp+send.portmonitor+file.depthimage_compression_zlib+recv.portmonitor+file.depthimage_compression_zlib+type.dll";
const LASER: &str = "fast_tcp+send.portmonitor+file.bottle_compression_zlib+recv.portmonitor+file.bottle_compression_zlib+type.dll";

fn rgb(w: usize, h: usize, shift: usize) -> Image {
    let mut img = Image::new(PixelCode::RGB, w, h).unwrap();
    for y in 0..h {
        for x in 0..w {
            let p = img.pixel_mut(x, y);
            p[0] = ((x + shift) % 256) as u8;
            p[1] = (y % 256) as u8;
            p[2] = 128;
        }
    }
    img
}

fn depth(w: usize, h: usize) -> Image {
    let mut img = Image::new(PixelCode::MONO_FLOAT, w, h).unwrap();
    for y in 0..h {
        for x in 0..w {
            let d = 0.4 + 0.001 * (x + y) as f32;
            img.pixel_mut(x, y).copy_from_slice(&d.to_le_bytes());
        }
    }
    img
}

/// Writes `b` until `r` receives something (connections come up asynchronously).
async fn write_until_read(
    w: &Port,
    r: &Port,
    b: &Bottle,
    stamp: Stamp,
) -> yarp_net::port::Incoming {
    timeout(T, async {
        loop {
            w.write_stamped(b, stamp).await;
            if let Ok(Some(m)) = timeout(Duration::from_millis(200), r.read()).await {
                return m;
            }
        }
    })
    .await
    .expect("nothing arrived")
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn mjpeg_is_pulled_by_the_reader_and_keeps_the_envelope() {
    let (ns, stop) = name_server().await;
    let w = Port::open("/camera/rgbImage:o", ns.clone()).await.unwrap();
    let r = Port::open("/repeater/rgb:i", ns.clone()).await.unwrap();
    // as RGBDSensorClient does: yarp connect remote local mjpeg
    let (ok, msg) = network::connect(&ns, "/camera/rgbImage:o", "/repeater/rgb:i", Some("mjpeg"))
        .await
        .unwrap();
    assert!(ok, "{msg}");
    // the reader opened the connection: an input of the reader, an output of the writer
    eventually("the reader lists its input", || {
        r.inputs() == vec!["/camera/rgbImage:o".to_string()]
    })
    .await;
    eventually("the writer serves the reader", || w.has_outputs()).await;
    assert_eq!(
        network::connection_carrier(&ns, "/repeater/rgb:i", "/camera/rgbImage:o")
            .await
            .unwrap(),
        None,
        "a pulled connection is no output of the reader"
    );

    let img = rgb(64, 48, 0);
    let stamp = Stamp::new(7, 1764240000.5);
    let m = write_until_read(&w, &r, &img.to_bottle(), stamp).await;
    assert_eq!(m.from, "/camera/rgbImage:o");
    let got = Image::from_bottle(&m.bottle().unwrap()).unwrap();
    assert_eq!(
        (got.pixel_code(), got.width(), got.height()),
        (PixelCode::RGB, 64, 48)
    );
    assert!(m.stamp.is_some_and(|s| s.count >= 7), "{:?}", m.stamp);
    let (a, b) = (img.pixel(30, 20), got.pixel(30, 20));
    assert!(
        a.iter()
            .zip(b)
            .all(|(x, y)| (*x as i32 - *y as i32).abs() < 16),
        "{a:?} {b:?}"
    );

    // not an image: not sent (and the connection stays)
    w.write(&bottle!["hello"]).await;
    w.write_stamped(&rgb(64, 48, 1).to_bottle(), Stamp::new(99, 1.0))
        .await;
    let m = timeout(T, r.read()).await.unwrap().unwrap();
    assert_eq!(m.stamp.map(|s| s.count), Some(99));

    // yarp disconnect finds the pulled connection at the reader
    let (ok, msg) = network::disconnect(&ns, "/camera/rgbImage:o", "/repeater/rgb:i")
        .await
        .unwrap();
    assert!(ok, "{msg}");
    eventually("the input is gone", || r.inputs().is_empty()).await;
    eventually("the writer noticed", || !w.has_outputs()).await;
    stop.shutdown();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_web_client_reads_the_mjpeg_stream() {
    let (ns, stop) = name_server().await;
    let w = Port::open("/cam:o", ns.clone()).await.unwrap();
    let addr = format!("{}:{}", w.contact().host, w.contact().port);
    let reader = std::thread::spawn(move || {
        let mut s = std::net::TcpStream::connect(addr).unwrap();
        s.set_read_timeout(Some(T)).unwrap();
        s.write_all(b"GET /?action=stream HTTP/1.1\r\nHost: localhost\r\n\r\n")
            .unwrap();
        let mut got = Vec::new();
        let mut buf = [0u8; 4096];
        // until two whole parts arrived
        while got
            .windows(22)
            .filter(|w| w == b"--boundarydonotcross\r\n")
            .count()
            < 3
        {
            let n = s.read(&mut buf).unwrap();
            assert!(n > 0, "closed early");
            got.extend_from_slice(&buf[..n]);
        }
        got
    });
    eventually("the browser is an output", || w.has_outputs()).await;
    let b = rgb(32, 24, 5).to_bottle();
    let stop_writing = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let writing = {
        let stop_writing = stop_writing.clone();
        async move {
            while !stop_writing.load(std::sync::atomic::Ordering::Relaxed) {
                w.write(&b).await;
                tokio::time::sleep(Duration::from_millis(20)).await;
            }
        }
    };
    let got = tokio::select! {
        _ = writing => unreachable!(),
        got = tokio::task::spawn_blocking(move || reader.join().unwrap()) => got.unwrap(),
    };
    stop_writing.store(true, std::sync::atomic::Ordering::Relaxed);
    let text = String::from_utf8_lossy(&got);
    assert!(
        text.starts_with("HTTP/1.0 200 OK\r\n"),
        "{}",
        &text[..60.min(text.len())]
    );
    assert!(text.contains("Content-Type: multipart/x-mixed-replace;boundary=boundarydonotcross"));
    assert!(text.contains("Content-Type: image/jpeg\r\nContent-Length: "));
    // the JPEG's start of image right after the part's headers
    let at = got.windows(4).position(|w| w == b"\r\n\r\n").unwrap();
    let part = &got[at + 4..];
    let at = part.windows(4).position(|w| w == b"\r\n\r\n").unwrap();
    assert_eq!(&part[at + 4..at + 6], &[0xFF, 0xD8]);
    stop.shutdown();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn depth_images_travel_compressed_and_arrive_as_images() {
    let (ns, stop) = name_server().await;
    let w = Port::open("/camera/depthImage:o", ns.clone())
        .await
        .unwrap();
    let r = Port::open("/repeater/depth:i", ns.clone()).await.unwrap();
    let (ok, msg) = network::connect(
        &ns,
        "/camera/depthImage:o",
        "/repeater/depth:i",
        Some(DEPTH),
    )
    .await
    .unwrap();
    assert!(ok, "{msg}");
    assert_eq!(
        network::connection_carrier(&ns, "/camera/depthImage:o", "/repeater/depth:i")
            .await
            .unwrap()
            .as_deref(),
        Some(DEPTH)
    );
    let img = depth(80, 60);
    let m = write_until_read(&w, &r, &img.to_bottle(), Stamp::new(3, 2.5)).await;
    assert_eq!(m.from, "/camera/depthImage:o");
    assert_eq!(Image::from_bottle(&m.bottle().unwrap()).unwrap(), img);
    assert!(m.stamp.is_some());
    // the receiver's view of the connection: the carrier with its qualifiers
    eventually("the reader lists the input", || {
        r.inputs() == vec!["/camera/depthImage:o".to_string()]
    })
    .await;

    // a message the sender's monitor refuses is dropped, the next goes through
    w.write(&rgb(8, 8, 0).to_bottle()).await;
    let small = depth(4, 2);
    w.write(&small.to_bottle()).await;
    let m = timeout(T, r.read()).await.unwrap().unwrap();
    assert_eq!(Image::from_bottle(&m.bottle().unwrap()).unwrap(), small);
    stop.shutdown();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bottles_through_bottle_compression() {
    let (ns, stop) = name_server().await;
    let w = Port::open("/laser:o", ns.clone()).await.unwrap();
    let r = Port::open("/laser_client_repeater:i", ns.clone())
        .await
        .unwrap();
    let (ok, msg) = network::connect(&ns, "/laser:o", "/laser_client_repeater:i", Some(LASER))
        .await
        .unwrap();
    assert!(ok, "{msg}");
    let scan: Bottle = bottle![
        bottle![0.0, 6.25],
        bottle![0.1, 30.0],
        bottle![1.0, 1.1, 1.2, 1.3],
        true
    ];
    let m = write_until_read(&w, &r, &scan, Stamp::new(1, 1.0)).await;
    assert_eq!(m.bottle().unwrap(), scan);
    stop.shutdown();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn what_cannot_be_had_is_refused_by_name() {
    let (ns, stop) = name_server().await;
    let w = Port::open("/w:o", ns.clone()).await.unwrap();
    let _r = Port::open("/r:i", ns.clone()).await.unwrap();
    for (carrier, named) in [
        ("tcp+send.portmonitor+file.my_filter", "lua"),
        (
            "fast_tcp+send.portmonitor+file.segmentationimage_to_rgb+type.dll",
            "segmentationimage_to_rgb",
        ),
        ("tcp+send.bayer", "bayer"),
        (
            "udp+send.portmonitor+file.bottle_compression_zlib+type.dll",
            "qualifiers",
        ),
    ] {
        let (ok, msg) = network::connect(&ns, "/w:o", "/r:i", Some(carrier))
            .await
            .unwrap();
        assert!(!ok, "{carrier} connected: {msg}");
        assert_eq!(msg.trim(), format!("Cannot connect to {carrier}://r:i"));
        // the port's own error says why
        let e = w
            .connect("/r:i", Some(carrier))
            .await
            .unwrap_err()
            .to_string();
        assert!(e.contains(named), "{carrier}: {e}");
    }
    assert!(!w.has_outputs());
    stop.shutdown();
}
