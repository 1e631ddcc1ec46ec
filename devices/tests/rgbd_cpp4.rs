//! The RGB-D pair against C++ YARP 4.0.0, whose `RGBDSensor_nws_yarp` /
//! `RGBDSensor_nwc_yarp` speak the thrift service `RGBDSensorMsgs`: C++ 4.0's client
//! reads our server (through C++'s server over it, `yarp rpc` at it prints what the
//! same chain over C++ 4.0's own server prints, and `yarp read` gets its images), and our
//! client reads C++ 4.0's server.
//! Run under ../shared/netns-run (C++ 4.0: tests/peers/install-cpp-peers.sh yarp4).

use std::time::{Duration, Instant};
use yarp_devices::rgbd::RgbdStatus;
use yarp_devices::PolyDriver;
use yarp_interop_tests::{assert_same_rpc_session, cpp4_devices, cpp_yarpdev, name_client};
use yarp_proto::Property;

const WAIT: Duration = Duration::from_secs(10);

/// Calls whose answers both fakes share (sizes, clip planes, status, extrinsics...).
const SESSION: &[&str] = &[
    "getRgbWidthRPC",
    "getRgbHeightRPC",
    "getDepthWidthRPC",
    "getDepthHeightRPC",
    "getRgbResolutionRPC",
    "getDepthResolutionRPC",
    "getRgbFOVRPC",
    "getDepthFOVRPC",
    "getDepthAccuracyRPC",
    "getDepthClipPlanesRPC",
    "setDepthClipPlanesRPC 0.5 5.0",
    "getDepthClipPlanesRPC",
    "getRgbMirroringRPC",
    "getSensorStatusRPC",
    "getExtrinsicParamRPC",
];

/// C++'s server named `name` over its fake camera, 32x24.
fn fake_args(name: &str) -> Vec<String> {
    [
        "--device",
        "RGBDSensor_nws_yarp",
        "--subdevice",
        "fakeDepthCamera",
        "--name",
        name,
        "--rgb_w",
        "32",
        "--rgb_h",
        "24",
        "--dep_w",
        "32",
        "--dep_h",
        "24",
        // what C++ 3.12's fake (and ours, which follows it) takes the size from
        "--width",
        "32",
        "--height",
        "24",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect()
}

/// `RGBDSensor_nwc_yarp`'s parameters for `local` reading the server `server`.
fn client_params(local: &str, server: &str) -> Vec<String> {
    [
        ("localImagePort", format!("{local}/rgbImage:i")),
        ("localDepthPort", format!("{local}/depthImage:i")),
        ("localRpcPort", format!("{local}/rpc:o")),
        ("remoteImagePort", format!("{server}/rgbImage:o")),
        ("remoteDepthPort", format!("{server}/depthImage:o")),
        ("remoteRpcPort", format!("{server}/rpc:i")),
        ("ImageCarrier", "tcp".to_string()),
        ("DepthCarrier", "tcp".to_string()),
    ]
    .into_iter()
    .flat_map(|(k, v)| [format!("--{k}"), v])
    .collect()
}

#[test]
fn cpp_4_rgbd_client_reads_ours() {
    let test = "cpp_4_rgbd_client_reads_ours";
    let Some(bin) = cpp4_devices(
        test,
        &[
            "RGBDSensor_nws_yarp",
            "RGBDSensor_nwc_yarp",
            "fakeDepthCamera",
        ],
    ) else {
        return;
    };
    name_client();
    let chain = |name: &str, server: &str| {
        let mut args: Vec<String> = [
            "--device",
            "RGBDSensor_nws_yarp",
            "--subdevice",
            "RGBDSensor_nwc_yarp",
            "--name",
            name,
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        args.extend(client_params(&format!("{name}/client"), server));
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        cpp_yarpdev(&bin, &args, &format!("{name}/rpc:i"))
    };
    let ours_cfg = "device RGBDSensor_nws_yarp\nsubdevice fakeDepthCamera\nname /rg4_ours\n\
                    rgb_w 32\nrgb_h 24\ndep_w 32\ndep_h 24\nwidth 32\nheight 24\n";
    let mut ours = PolyDriver::open(&Property::from_config_text(ours_cfg).unwrap())
        .expect("our RGBDSensor_nws_yarp");
    let _chain_ours = chain("/rg4_chain_ours", "/rg4_ours");
    let yarp = bin.join("yarp");
    let args = fake_args("/rg4_cpp");
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let _cpp = cpp_yarpdev(&bin, &args, "/rg4_cpp/rpc:i");
    let _chain_cpp = chain("/rg4_chain_cpp", "/rg4_cpp");
    assert_same_rpc_session(
        &yarp,
        SESSION,
        "/rg4_chain_ours/rpc:i",
        "/rg4_chain_cpp/rpc:i",
    );
    // the images the C++ 4.0 client read from ours, republished: 4.0's header (the
    // quantum alone), a float depth image
    for (port, head) in [
        ("/rg4_chain_ours/rgbImage:o", "[mat] [rgb] (3 2304 8 32 24)"),
        (
            "/rg4_chain_ours/depthImage:o",
            "[mat] [dec] (4 3072 8 32 24)",
        ),
    ] {
        let reader = format!("{}_rd", port.replace(':', "_"));
        yarp_interop_tests::cpp_read_until(&yarp, &reader, port, |l| {
            l.starts_with(head).then_some(())
        });
    }
    eprintln!("interop: C++ 4.0 RGBDSensor_nwc_yarp -> our RGBDSensor_nws_yarp OK");
    ours.close().unwrap();
}

/// Our client reads C++ 4.0's `RGBDSensor_nws_yarp` + `fakeDepthCamera`: 4.0 is found
/// at open, the parameters come through `RGBDSensorMsgs` and both images stream in.
#[test]
fn our_rgbd_client_reads_cpp_4() {
    let test = "our_rgbd_client_reads_cpp_4";
    let Some(bin) = cpp4_devices(test, &["RGBDSensor_nws_yarp", "fakeDepthCamera"]) else {
        return;
    };
    name_client();
    let args = fake_args("/rg4r_cpp");
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let _cpp = cpp_yarpdev(&bin, &args, "/rg4r_cpp/rpc:i");
    let params = client_params("/rg4r_ours", "/rg4r_cpp");
    let cfg: String = params
        .chunks(2)
        .map(|kv| format!("{} {}\n", kv[0].trim_start_matches("--"), kv[1]))
        .collect();
    let mut pd = PolyDriver::open(
        &Property::from_config_text(format!("device RGBDSensor_nwc_yarp\n{cfg}")).unwrap(),
    )
    .expect("our client opens against C++ 4.0");
    let d = pd.device().as_rgbd_sensor().expect("IRGBDSensor");
    assert_eq!((d.rgb_width(), d.rgb_height()), (32, 24));
    assert_eq!(d.depth_resolution().unwrap(), (32, 24));
    assert_eq!(d.sensor_status(), RgbdStatus::OkInUse);
    d.set_depth_clip_planes(0.5, 5.0).unwrap();
    assert_eq!(d.depth_clip_planes().unwrap(), (0.5, 5.0));
    d.set_rgb_mirroring(true).unwrap();
    assert!(d.rgb_mirroring().unwrap());
    let ext = d.extrinsic_param().unwrap();
    assert_eq!((ext[0], ext[5], ext[15], ext[1]), (1.0, 1.0, 1.0, 0.0));
    assert_eq!(d.last_error_msg(), "no error");
    let end = Instant::now() + WAIT;
    let ((rgb, _), (depth, _)) = loop {
        if let Ok(both) = d.get_images() {
            break both;
        }
        assert!(Instant::now() < end, "no images from C++ 4.0");
        std::thread::sleep(Duration::from_millis(20));
    };
    assert_eq!((rgb.width(), depth.width()), (32, 32));
    pd.close().unwrap();
    eprintln!("interop: our RGBDSensor_nwc_yarp -> C++ 4.0 RGBDSensor_nws_yarp OK");
}
