//! YARP images -> sensor_msgs/Image into rclpy, checked by SHA-256 (run under netns-run):
//! a real fakeFrameGrabber camera, and synthetic frames written on a port.
//! Domain indices: 15, 18, 23.

mod common;

use common::{Peer, T};
use sha2::{Digest, Sha256};
use std::collections::HashMap;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};
use yarp_net::port::Port;
use yarp_proto::Stamp;
use yarp_ros2_gateway::image::yarp_image;

/// Frame `i`: a pattern that repeats every 251 frames, made unique by `i` in its first
/// 4 bytes (frames the pattern alone makes equal would be taken for one another).
fn frame(w: usize, h: usize, i: usize) -> Vec<u8> {
    let mut px: Vec<u8> = (0..w * h * 3)
        .map(|k| ((k / 7 + i * 31) % 251) as u8)
        .collect();
    px[..4].copy_from_slice(&(i as u32).to_le_bytes());
    px
}

fn hex(d: &[u8]) -> String {
    d.iter().map(|b| format!("{b:02x}")).collect()
}

/// What one image stream run measured.
struct Run {
    sent: usize,
    /// Indices of the frames that arrived intact, in arrival order.
    got: Vec<usize>,
    /// Age of each arrived frame at the subscriber (stamp to receipt), sorted, ms.
    ages: Vec<f64>,
}

/// An rclpy subscriber of `/cam/image_raw` printing each image as a digest (Fast DDS's
/// large-data profile).
fn image_subscriber(venv: &common::Distro, domain: u16) -> Peer {
    Peer::start_with_profile(
        venv,
        domain,
        &[
            "sub",
            "sensor_msgs/msg/Image",
            "/cam/image_raw",
            "--summary",
            "--count",
            "100000",
            "--timeout",
            "60",
        ],
        Some("fastdds_large_data.xml"),
    )
}

/// Streams `n` `w`x`h` rgb8 frames at `hz` from a YARP port through the gateway to an
/// rclpy subscriber that reports each frame's SHA-256.
async fn stream(venv: &common::Distro, index: u16, w: usize, h: usize, hz: f64, n: usize) -> Run {
    let domain = venv.domain(index);
    let (ns, stop) = common::name_server().await;
    let port = Port::open("/test/cam:o", ns.clone()).await.unwrap();
    let gw = common::gateway(
        r#"
[[topic]]
name = "cam"
direction = "yarp_to_ros"
yarp_port = "/gw/cam:i"
yarp_source = "/test/cam:o"
ros_topic = "/cam/image_raw"
ros_type = "sensor_msgs/msg/Image"
frame_id = "camera"
qos = { depth = 10 }
"#,
        &ns,
        domain,
    )
    .await;
    let sub = image_subscriber(venv, domain);
    sub.expect_async("READY", T).await;
    // Warm up with one frame until it arrives (discovery, connections).
    let warm = frame(w, h, 100_000);
    let warm_sha = hex(&Sha256::digest(&warm));
    common::repeat_until(
        "the first image",
        Duration::from_millis(100),
        async || {
            port.write(&yarp_image("rgb", 3, w, h, warm.clone())).await;
        },
        || sub.try_line("MSG"),
    )
    .await;
    tokio::time::sleep(Duration::from_millis(300)).await;
    while sub.try_line("MSG").is_some() {}

    // Frames and digests are prepared before the timed loop.
    let frames: Vec<Vec<u8>> = (0..n).map(|i| frame(w, h, i)).collect();
    let sent: HashMap<String, usize> = frames
        .iter()
        .enumerate()
        .map(|(i, px)| (hex(&Sha256::digest(px)), i))
        .collect();
    let mut tick = tokio::time::interval(Duration::from_secs_f64(1.0 / hz));
    let t0 = Instant::now();
    for (i, px) in frames.into_iter().enumerate() {
        tick.tick().await;
        let now = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .unwrap()
            .as_secs_f64();
        port.write_stamped(&yarp_image("rgb", 3, w, h, px), Stamp::new(i as i32, now))
            .await;
    }
    let send_time = t0.elapsed();
    let (mut got, mut ages) = (Vec::new(), Vec::new());
    let end = Instant::now() + Duration::from_secs(5);
    while got.len() < n && Instant::now() < end {
        let Some(l) = sub.try_line("MSG") else {
            tokio::time::sleep(Duration::from_millis(5)).await;
            continue;
        };
        let m: serde_json::Value = serde_json::from_str(&l).unwrap();
        assert_eq!(m["width"], w);
        assert_eq!(m["height"], h);
        assert_eq!(m["encoding"], "rgb8");
        assert_eq!(m["step"], w * 3);
        assert_eq!(m["frame_id"], "camera");
        let sha = m["sha256"].as_str().unwrap();
        if sha == warm_sha {
            continue; // a late warm-up frame
        }
        let i = *sent
            .get(sha)
            .unwrap_or_else(|| panic!("image not as sent: {l}"));
        got.push(i);
        ages.push(m["age_ms"].as_f64().unwrap_or(f64::NAN));
    }
    ages.sort_by(f64::total_cmp);
    let missing: Vec<usize> = (0..n).filter(|i| !got.contains(i)).collect();
    if !missing.is_empty() {
        eprintln!("frames that did not arrive: {missing:?}");
    }
    let snap = gw.bridges()[0].counters.snapshot();
    eprintln!(
        "images {w}x{h} rgb8 at {hz} Hz: sent {n} in {send_time:?}, received {} intact, \
         gateway drops {}, age p50 {:.1} ms p99 {:.1} ms max {:.1} ms; inside the gateway \
         mean {:?} max {:?}",
        got.len(),
        snap.drops,
        ages.get(ages.len() / 2).copied().unwrap_or(f64::NAN),
        ages.get(ages.len() * 99 / 100).copied().unwrap_or(f64::NAN),
        ages.last().copied().unwrap_or(f64::NAN),
        snap.latency_mean,
        snap.latency_max
    );
    gw.shutdown().await;
    stop.shutdown();
    Run { sent: n, got, ages }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn rgb8_images_at_30_hz_arrive_intact() {
    for d in common::distros("rgb8_images_at_30_hz_arrive_intact") {
        rgb8_images_at_30_hz_arrive_intact_on(&d).await;
    }
}

async fn rgb8_images_at_30_hz_arrive_intact_on(venv: &common::Distro) {
    let r = stream(venv, 23, 640, 480, 30.0, 60).await;
    assert!(
        r.got.windows(2).all(|p| p[0] < p[1]),
        "in order: {:?}",
        r.got
    );
    if cfg!(debug_assertions) {
        // Unoptimized RustDDS and Bottle codecs cannot keep 30 Hz of 640x480; the rate is
        // checked in optimized builds.
        eprintln!(
            "*** debug build: integrity and order checked; the 30 Hz rate needs --release ***"
        );
        assert!(!r.got.is_empty(), "no image arrived");
    } else {
        assert!(
            r.got.len() >= r.sent * 9 / 10,
            "only {} of {} images arrived",
            r.got.len(),
            r.sent
        );
    }
}

/// A real camera: `fakeFrameGrabber` (640x480 rgb, 30 frames per second) served by
/// `frameGrabber_nws_yarp`. A probe port in the test reads the same stream and records
/// each image's SHA-256 by its envelope stamp; every image rclpy receives must equal the
/// one YARP sent with its stamp.
// One distro: image content is checked per distro by rgb8_images_at_30_hz_arrive_intact;
// here the frame grabber's stamps are matched, which a second device in the process (or a
// second suite beside it) on a busy machine makes the probe miss.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn fake_frame_grabber_images_arrive_intact_at_30_hz() {
    for d in common::first_distro("fake_frame_grabber_images_arrive_intact_at_30_hz") {
        fake_frame_grabber_images_arrive_intact_at_30_hz_on(&d).await;
    }
}

async fn fake_frame_grabber_images_arrive_intact_at_30_hz_on(venv: &common::Distro) {
    let domain = venv.domain(15);
    // YARP names of their own per distro: the device name server lives on in the process.
    let t15 = format!("/t15{}", venv.name);
    let ns = common::device_name_server();
    let _cam = common::blocking({
        let t15 = t15.clone();
        move || {
            common::open_device(&format!(
                "device frameGrabber_nws_yarp\nsubdevice fakeFrameGrabber\nname {t15}/cam\n\
             width 640\nheight 480\nmode line\nfreq 30\nperiod 0.0333333\n"
            ))
        }
    })
    .await;
    // What YARP sent: (envelope time, SHA-256 of the pixel bytes).
    let sent: Arc<Mutex<Vec<(f64, String)>>> = Arc::default();
    let probe = Port::open(&format!("{t15}/probe:i"), ns.clone())
        .await
        .unwrap();
    yarp_net::network::connect(&ns, &format!("{t15}/cam"), &format!("{t15}/probe:i"), None)
        .await
        .unwrap();
    let recorder = {
        let sent = sent.clone();
        tokio::spawn(async move {
            while let Some(m) = probe.read().await {
                let (Some(s), Ok(b)) = (m.stamp, m.bottle()) else {
                    continue;
                };
                let img = yarp_proto::image::Image::from_bottle(&b).expect("a YARP image");
                assert_eq!((img.width(), img.height()), (640, 480));
                // ROS images are top row first: hash the rows in that order.
                let mut h = Sha256::new();
                let rows: Vec<&[u8]> = img.data().chunks(img.row_size()).collect();
                if img.top_is_low() {
                    rows.iter().for_each(|r| h.update(r));
                } else {
                    rows.iter().rev().for_each(|r| h.update(r));
                }
                sent.lock().unwrap().push((s.time, hex(&h.finalize())));
            }
        })
    };
    let gw = common::gateway(
        &r#"
[[topic]]
name = "cam"
direction = "yarp_to_ros"
yarp_port = "/gw/t15/cam:i"
yarp_source = "/t15/cam"
ros_topic = "/cam/image_raw"
ros_type = "sensor_msgs/msg/Image"
frame_id = "camera"
qos = { depth = 10 }
"#
        .replace("/t15", &t15),
        &ns,
        domain,
    )
    .await;
    let sub = image_subscriber(venv, domain);
    sub.expect_async("READY", T).await;
    sub.expect_async("MSG", T).await; // discovery done, the stream flows
    while sub.try_line("MSG").is_some() {}
    // Two seconds of stream.
    let (mut got, mut ages) = (Vec::new(), Vec::new());
    let end = Instant::now() + Duration::from_secs(2);
    while Instant::now() < end {
        let Some(l) = sub.try_line("MSG") else {
            tokio::time::sleep(Duration::from_millis(5)).await;
            continue;
        };
        let m: serde_json::Value = serde_json::from_str(&l).unwrap();
        assert_eq!(m["width"], 640);
        assert_eq!(m["height"], 480);
        assert_eq!(m["encoding"], "rgb8");
        assert_eq!(m["step"], 640 * 3);
        assert_eq!(m["frame_id"], "camera");
        let t = m["sec"].as_f64().unwrap() + m["nanosec"].as_f64().unwrap() * 1e-9;
        got.push((t, m["sha256"].as_str().unwrap().to_string()));
        ages.push(m["age_ms"].as_f64().unwrap_or(f64::NAN));
    }
    tokio::time::sleep(Duration::from_millis(300)).await; // the probe may lag
    recorder.abort();
    let sent = sent.lock().unwrap().clone();
    let (first, last) = (got.first().unwrap().0, got.last().unwrap().0);
    let mut matched = 0;
    for (t, sha) in &got {
        let Some((_, want)) = sent.iter().find(|(s, _)| (s - t).abs() < 2e-6) else {
            continue; // the probe missed this one
        };
        assert_eq!(sha, want, "image stamped {t} differs from what YARP sent");
        matched += 1;
    }
    let in_window = sent
        .iter()
        .filter(|(s, _)| *s >= first - 1e-6 && *s <= last + 1e-6)
        .count();
    ages.sort_by(f64::total_cmp);
    eprintln!(
        "fakeFrameGrabber 640x480 rgb8 @30 Hz: rclpy got {} images in 2 s ({matched} checked \
         against the probe's SHA-256), the probe saw {in_window} in the same span; age p50 \
         {:.1} ms",
        got.len(),
        ages.get(ages.len() / 2).copied().unwrap_or(f64::NAN)
    );
    assert!(matched >= 1, "no image could be checked");
    if !cfg!(debug_assertions) {
        // 30 Hz for 2 s, and nothing the probe saw went missing on the way to rclpy.
        assert!(got.len() >= 50, "only {} images in 2 s", got.len());
        assert!(
            got.len() * 10 >= in_window * 9,
            "{} of {in_window}",
            got.len()
        );
    }
    gw.shutdown().await;
}

/// The benchmark of the issue: 1280x720 rgb8 at 60 fps end to end (a measurement: run
/// with `--release --ignored --nocapture`).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[ignore = "measurement; run explicitly with --release"]
async fn rgb8_720p_at_60_hz() {
    for d in common::first_distro("rgb8_720p_at_60_hz") {
        rgb8_720p_at_60_hz_on(&d).await;
    }
}

async fn rgb8_720p_at_60_hz_on(venv: &common::Distro) {
    let r = stream(venv, 18, 1280, 720, 60.0, 300).await;
    eprintln!(
        "720p60: {} of {} arrived ({} dropped), age p50 {:.1} ms p99 {:.1} ms",
        r.got.len(),
        r.sent,
        r.sent - r.got.len(),
        r.ages.get(r.ages.len() / 2).copied().unwrap_or(f64::NAN),
        r.ages
            .get(r.ages.len() * 99 / 100)
            .copied()
            .unwrap_or(f64::NAN)
    );
    assert!(!r.got.is_empty());
}

/// The reference for [`rgb8_720p_at_60_hz`]: the same stream published by rclpy
/// (`peers/image_pub.py`) straight to the same rclpy subscriber, so what rclpy's own
/// send and receive paths cost at this size and rate is measured in the same run. Shares
/// domain index 18 with `rgb8_720p_at_60_hz`: run the measurements one at a time
/// (`--test-threads 1`).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
#[ignore = "measurement; run explicitly with --release"]
async fn rclpy_720p_at_60_hz_baseline() {
    for d in common::first_distro("rclpy_720p_at_60_hz_baseline") {
        rclpy_720p_at_60_hz_baseline_on(&d).await;
    }
}

async fn rclpy_720p_at_60_hz_baseline_on(venv: &common::Distro) {
    let (n, w, h) = (300usize, 1280usize, 720usize);
    let domain = venv.domain(18);
    let sub = image_subscriber(venv, domain);
    sub.expect_async("READY", T).await;
    let script =
        std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/peers/image_pub.py");
    let mut cmd = std::process::Command::new(venv.join("bin/python"));
    cmd.arg("-u")
        .arg(script)
        .args(["/cam/image_raw", "--count", &n.to_string(), "--rate", "60"])
        .env("ROS_DOMAIN_ID", domain.to_string())
        .env("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
        .env("ROS_DISTRO", "kilted")
        .env(
            "FASTDDS_DEFAULT_PROFILES_FILE",
            std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
                .join("tests/peers/fastdds_large_data.xml"),
        );
    let publisher = Peer::spawn(cmd, "image_pub.py");
    publisher.expect_async("START", T).await;
    let done = publisher.expect_async("DONE", T).await;
    let (mut got, mut ages) = (Vec::new(), Vec::new());
    let end = Instant::now() + Duration::from_secs(5);
    while got.len() < n && Instant::now() < end {
        let Some(l) = sub.try_line("MSG") else {
            tokio::time::sleep(Duration::from_millis(5)).await;
            continue;
        };
        let m: serde_json::Value = serde_json::from_str(&l).unwrap();
        assert_eq!(
            (m["width"].as_u64(), m["height"].as_u64()),
            (Some(w as u64), Some(h as u64))
        );
        let i = m["head"].as_u64().unwrap() as usize;
        if i >= n {
            continue; // a warm-up frame
        }
        got.push(i);
        ages.push(m["age_ms"].as_f64().unwrap_or(f64::NAN));
    }
    ages.sort_by(f64::total_cmp);
    let missing: Vec<usize> = (0..n).filter(|i| !got.contains(i)).collect();
    if !missing.is_empty() {
        eprintln!("frames that did not arrive: {missing:?}");
    }
    eprintln!(
        "rclpy -> rclpy 720p60 (sent in {}s): {} of {n} arrived ({} dropped), age p50 {:.1} ms \
         p99 {:.1} ms max {:.1} ms",
        done.trim_start_matches("DONE").trim(),
        got.len(),
        n - got.len(),
        ages.get(ages.len() / 2).copied().unwrap_or(f64::NAN),
        ages.get(ages.len() * 99 / 100).copied().unwrap_or(f64::NAN),
        ages.last().copied().unwrap_or(f64::NAN),
    );
    assert!(!got.is_empty());
}
