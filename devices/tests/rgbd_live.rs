//! rgbdSensor_nws_yarp over fakeDepthCamera on real sockets, with an in-process name
//! server (run under netns-run): our readers get the colour and the float depth images
//! with envelopes, our RPC client and C++ `yarp rpc` (3.12.3 from
//! tests/peers/install-cpp-peers.sh icub, when installed; in CI required) the visual
//! parameters and the status, C++ `yarp read` the depth image.
//! Every wait is bounded.

use std::time::{Duration, Instant};
use yarp_devices::rgbd::fake::depth_of;
use yarp_devices::{runtime, PolyDriver};
use yarp_interop_tests::{name_client, T};
use yarp_net::buffered::BufferedPort;
use yarp_net::rpc::RpcClient;
use yarp_proto::image::{Image, PixelCode};
use yarp_proto::wire::Carrier;
use yarp_proto::{Bottle, Property, Value};

fn run<F>(fut: F) -> F::Output
where
    F: std::future::Future + Send + 'static,
    F::Output: Send + 'static,
{
    runtime::block_on(async move { tokio::time::timeout(T, fut).await.expect("timed out") })
        .expect("the device runtime")
}

fn camera(name: &str) -> PolyDriver {
    name_client();
    let cfg = format!(
        "device rgbdSensor_nws_yarp\nsubdevice fakeDepthCamera\nname {name}\nperiod 0.03\n\
         width 32\nheight 24\n"
    );
    PolyDriver::open(&Property::from_config_text(&cfg).unwrap())
        .unwrap_or_else(|e| panic!("open {cfg:?}: {e}"))
}

/// The first image `port` sends to a fresh reader, with its envelope's time.
async fn first_image(port: &str, reader: &str) -> (Image, f64) {
    let ns = yarp_interop_tests::name_client();
    let r = BufferedPort::open(reader, ns.clone()).await.unwrap();
    let (ok, msg) = yarp_net::network::connect(&ns, port, reader, None)
        .await
        .unwrap();
    assert!(ok, "{msg}");
    let m = r.read().await.expect("an image");
    r.close().await;
    (
        Image::from_bottle(&m.bottle).unwrap(),
        m.stamp.unwrap().time,
    )
}

#[test]
fn our_readers_get_both_images_and_rpc_answers() {
    let mut server = camera("/depthCamera");
    let ns = name_client();
    let ((rgb, t1), (depth, t2), replies) = run(async move {
        let rgb = first_image("/depthCamera/rgbImage:o", "/rgb_reader").await;
        let depth = first_image("/depthCamera/depthImage:o", "/depth_reader").await;
        let c = ns
            .query("/depthCamera/rpc:i")
            .await
            .unwrap()
            .expect("rpc port");
        let mut rpc = RpcClient::connect(&c, "/anon_rpc", Carrier::Tcp)
            .await
            .unwrap();
        let mut replies = Vec::new();
        for text in [
            "[visr] [get] [w]",
            "[visd] [get] [h]",
            "[visd] [get] [clip]",
            "[visr] [get] [intp]",
            "[rgdb] [get] [stat]",
            "[nope]",
        ] {
            replies.push(rpc.call(&Bottle::from_text(text)).await.unwrap());
        }
        rpc.close().await;
        (rgb, depth, replies)
    });
    assert_eq!((rgb.width(), rgb.height()), (32, 24));
    assert_eq!(rgb.pixel_code(), PixelCode::RGB);
    assert_eq!(depth.pixel_code(), PixelCode::MONO_FLOAT);
    assert_eq!((depth.width(), depth.height()), (32, 24));
    // the depth is the mean of the colour channels, in [0, 1] m
    for y in 0..24 {
        for x in 0..32 {
            let d = f32::from_ne_bytes(depth.pixel(x, y).try_into().unwrap());
            assert!((0.0..=1.0).contains(&d));
        }
    }
    assert_eq!(depth_of(&rgb).width(), 32);
    assert!(t1 > 1.6e9 && t2 > 1.6e9);
    assert_eq!(replies[0].to_string(), "[visr] [w] [is] 32");
    assert_eq!(replies[1].to_string(), "[visd] [h] [is] 24");
    let clip: Vec<f64> = replies[2]
        .iter()
        .skip(3)
        .filter_map(Value::as_f64)
        .collect();
    assert_eq!(clip, [0.2, 6.0]);
    let intp = replies[3]
        .get(3)
        .and_then(Value::as_list)
        .unwrap()
        .to_string();
    assert!(intp.contains("focalLengthX"), "{intp}");
    assert_eq!(replies[4].to_string(), "[rgdb] [stat] [is] 2");
    assert_eq!(replies[5].to_string(), "[fail]");
    server.close().unwrap();
    let ns = name_client();
    assert!(run(async move { ns.query("/depthCamera/rgbImage:o").await.unwrap() }).is_none());
}

#[test]
fn cpp_yarp_rpc_asks_our_wrapper() {
    let Some(yarp) = yarp_interop_tests::cpp_program("cpp_yarp_rpc_asks_our_wrapper", "yarp")
    else {
        return;
    };
    let mut server = camera("/cppdepth");
    let out = yarp_interop_tests::cpp_rpc_output(
        &yarp,
        "/cppdepth/rpc:i",
        "[visd] [get] [w]\n[rgdb] [get] [prot]\n[rgdb] [get] [stat]\n",
    );
    let responses: Vec<&str> = out
        .lines()
        .filter_map(|l| l.strip_prefix("Response: "))
        .collect();
    assert_eq!(
        responses,
        [
            "[visd] [w] [is] 32",
            "[rgdb] [prot] [is] 1 0",
            "[rgdb] [stat] [is] 2"
        ],
        "{out}"
    );

    // C++ yarp read gets the float depth image (it prints the image Bottle, `[mat] ...`)
    let line =
        yarp_interop_tests::cpp_read_until(&yarp, "/cpp_depth_rd", "/cppdepth/depthImage:o", |l| {
            l.starts_with("[mat]").then(|| l.to_string())
        });
    let img = Image::from_bottle(&Bottle::from_text(&line)).expect("an image");
    assert_eq!(img.pixel_code(), PixelCode::MONO_FLOAT);
    assert_eq!((img.width(), img.height()), (32, 24));
    eprintln!("interop: C++ yarp rpc and yarp read -> rgbdSensor_nws_yarp OK");
    server.close().unwrap();
}

fn client(server: &str, local: &str, carriers: &str) -> Result<PolyDriver, String> {
    name_client();
    let cfg = format!(
        "device RGBDSensorClient\nlocalImagePort {local}/rgbImage:i\nlocalDepthPort {local}/depthImage:i\n\
         localRpcPort {local}/rpc:o\nremoteImagePort {server}/rgbImage:o\n\
         remoteDepthPort {server}/depthImage:o\nremoteRpcPort {server}/rpc:i\n{carriers}"
    );
    PolyDriver::open(&Property::from_config_text(&cfg).unwrap()).map_err(|e| e.to_string())
}

/// RGBDSensorClient (C++ 3.12's parameters) on our server: the images stream in (over
/// udp, its default carrier, and over tcp), the visual parameters, extrinsics and status
/// come over RPC; a client without a server fails naming the port.
#[test]
fn rgbd_sensor_client_reads_our_wrapper() {
    let mut server = camera("/rgbdServer");
    for (local, carriers) in [
        ("/rgbdClientUdp", ""),
        (
            "/rgbdClientTcp",
            "ImageCarrier tcp\nDepthCarrier fast_tcp\n",
        ),
    ] {
        let mut pd = client("/rgbdServer", local, carriers).unwrap_or_else(|e| panic!("{e}"));
        let d = pd.device().as_rgbd_sensor().expect("IRGBDSensor");
        assert_eq!((d.rgb_width(), d.rgb_height()), (32, 24));
        assert_eq!((d.depth_width(), d.depth_height()), (32, 24));
        assert_eq!(d.rgb_fov().unwrap(), (36.0, 50.0));
        assert_eq!(d.depth_clip_planes().unwrap(), (0.2, 6.0));
        assert_eq!(d.depth_accuracy().unwrap(), 0.001);
        let intp = d.depth_intrinsic_param().unwrap();
        assert!(intp.find("focalLengthX").is_some(), "{intp:?}");
        let ext = d.extrinsic_param().unwrap();
        assert_eq!((ext[0], ext[5], ext[15], ext[1]), (1.0, 1.0, 1.0, 0.0));
        assert_eq!(d.sensor_status(), yarp_devices::rgbd::RgbdStatus::OkInUse);
        let end = Instant::now() + T;
        let images = loop {
            if let Ok(both) = d.get_images() {
                break both;
            }
            assert!(Instant::now() < end, "{local}: no images in {T:?}");
            std::thread::sleep(Duration::from_millis(20));
        };
        let ((rgb, t1), (depth, t2)) = images;
        assert_eq!(rgb.pixel_code(), PixelCode::RGB);
        assert_eq!(
            (depth.pixel_code(), depth.width()),
            (PixelCode::MONO_FLOAT, 32)
        );
        assert!(t1.time > 1.6e9 && t2.time > 1.6e9, "{local}: envelopes");
        pd.close().unwrap();
    }
    server.close().unwrap();
    let e = client("/rgbdServer", "/rgbdOrphan", "")
        .err()
        .expect("no server");
    assert!(e.contains("/rgbdServer"), "{e}");
}

const ERGOCUB_DEPTH_CARRIER: &str = "fast_tcp+send.portmonitor+file.depthimage_compression_zlib+recv.portmonitor+file.depthimage_compression_zlib+type.dll";

/// ergoCub's depth repeater carriers (`sensors/ros2_repeaters/depth_compressed_ros2.xml`:
/// `ImageCarrier mjpeg`, the depth through `depthimage_compression_zlib`) with our
/// RGBDSensorClient on our server: both images arrive, as images.
#[test]
fn rgbd_sensor_client_with_ergocub_repeater_carriers() {
    let mut server = camera("/rgbdServerErgo");
    let carriers = format!("ImageCarrier mjpeg\nDepthCarrier {ERGOCUB_DEPTH_CARRIER}\n");
    let mut pd =
        client("/rgbdServerErgo", "/rgbdClientErgo", &carriers).unwrap_or_else(|e| panic!("{e}"));
    let d = pd.device().as_rgbd_sensor().expect("IRGBDSensor");
    let end = Instant::now() + T;
    let ((rgb, t1), (depth, t2)) = loop {
        if let Ok(both) = d.get_images() {
            break both;
        }
        assert!(Instant::now() < end, "no images in {T:?}");
        std::thread::sleep(Duration::from_millis(20));
    };
    assert_eq!(
        (rgb.pixel_code(), rgb.width(), rgb.height()),
        (PixelCode::RGB, 32, 24)
    );
    assert_eq!(
        (depth.pixel_code(), depth.width(), depth.height()),
        (PixelCode::MONO_FLOAT, 32, 24)
    );
    // metres of the fake camera, decompressed whole
    for y in [0, 12, 23] {
        let d = f32::from_le_bytes(depth.pixel(16, y).try_into().unwrap());
        assert!(
            d.is_finite() && (0.0..=1.0).contains(&d),
            "depth {d} at row {y}"
        );
    }
    // the envelopes: the colour one rode in the JPEG's comment marker
    assert!(
        t1.time > 1.6e9 && t2.time > 1.6e9,
        "envelopes {t1:?} {t2:?}"
    );
    pd.close().unwrap();
    server.close().unwrap();
}

/// The same carriers against C++ YARP (3.12.3, with its mjpeg carrier and its
/// depthimage_compression_zlib port monitor): a C++ rgbdSensor_nws_yarp attached to
/// fakeDepthCamera (in C++ yarprobotinterface, see `cpp_yarpdev`) streams to our ports (C++ compresses, we decompress; we pull the JPEGs),
/// and our server streams to C++ `yarp read` (we compress, C++ decompresses; C++ pulls).
#[test]
fn ergocub_repeater_carriers_interoperate_with_cpp() {
    let test = "ergocub_repeater_carriers_interoperate_with_cpp";
    let Some(bin) =
        yarp_interop_tests::cpp_devices(test, &["rgbdSensor_nws_yarp", "fakeDepthCamera"])
    else {
        return;
    };
    if !bin
        .join("../share/yarp/plugins/depthimage_compression_zlib.ini")
        .exists()
    {
        yarp_interop_tests::peer_missing(
            test,
            "C++ YARP's depthimage_compression_zlib port monitor",
            "not built in this C++ YARP",
            yarp_interop_tests::CPP_YARP_INSTALL,
        );
        return;
    }
    // C++ server -> our readers
    let _cpp = yarp_interop_tests::cpp_yarpdev(
        &bin,
        &[
            "--device",
            "rgbdSensor_nws_yarp",
            "--subdevice",
            "fakeDepthCamera",
            "--name",
            "/cppCamera",
            "--period",
            "0.03",
        ],
        "/cppCamera/depthImage:o",
    );
    let (rgb, depth) = run(async {
        let ns = name_client();
        let rgb = BufferedPort::open("/ours/rgb:i", ns.clone()).await.unwrap();
        let depth = BufferedPort::open("/ours/depth:i", ns.clone())
            .await
            .unwrap();
        for (from, to, carrier) in [
            ("/cppCamera/rgbImage:o", "/ours/rgb:i", "mjpeg"),
            (
                "/cppCamera/depthImage:o",
                "/ours/depth:i",
                ERGOCUB_DEPTH_CARRIER,
            ),
        ] {
            let (ok, msg) = yarp_net::network::connect(&ns, from, to, Some(carrier))
                .await
                .unwrap();
            assert!(ok, "{from} -> {to} with {carrier}: {msg}");
        }
        let a = rgb.read().await.expect("a JPEG from C++");
        let b = depth
            .read()
            .await
            .expect("a compressed depth image from C++");
        (
            Image::from_bottle(&a.bottle).unwrap(),
            Image::from_bottle(&b.bottle).unwrap(),
        )
    });
    assert_eq!(rgb.pixel_code(), PixelCode::RGB);
    assert!(rgb.width() > 0 && rgb.height() > 0);
    assert_eq!(depth.pixel_code(), PixelCode::MONO_FLOAT);
    assert!(depth.width() > 0 && depth.height() > 0);
    eprintln!(
        "interop: C++ rgbdSensor_nws_yarp -> ours: mjpeg {}x{}, depth (zlib monitor) {}x{}",
        rgb.width(),
        rgb.height(),
        depth.width(),
        depth.height()
    );

    // our server -> C++ yarp read, on each carrier
    let mut server = camera("/oursCamera");
    let yarp = bin.join("yarp");
    for (from, reader, carrier, code) in [
        ("/oursCamera/rgbImage:o", "/cpp_rgb_rd", "mjpeg", "[rgb]"),
        (
            "/oursCamera/depthImage:o",
            "/cpp_depth_rd",
            ERGOCUB_DEPTH_CARRIER,
            "[dec]",
        ),
    ] {
        let line = yarp_interop_tests::cpp_read_over(&yarp, reader, from, carrier, |l| {
            l.starts_with("[mat]").then(|| l.to_string())
        });
        let img = Image::from_bottle(&Bottle::from_text(&line)).expect("an image");
        assert_eq!((img.width(), img.height()), (32, 24), "{carrier}");
        assert!(
            line.starts_with(&format!("[mat] {code}")),
            "{carrier}: {}",
            &line[..40]
        );
        eprintln!("interop: ours -> C++ yarp read over {carrier}: {code} 32x24");
    }
    server.close().unwrap();
}
