//! The laser, camera and mobile-base wrappers opened as devices in this process (as
//! `yarpdev --device W --subdevice fake...` does), with rclpy on the other side: rclpy
//! receives `frameGrabber_nws_ros2`'s Image + CameraInfo, `battery_nws_ros2`'s
//! BatteryState and `odometry2D_nws_ros2`'s Odometry (and sees `/tf` with the TFMessage
//! hash); rclpy's Twist commands reach `fakeNavigation` through
//! `mobileBaseVelocityControl_nws_ros2`; rclpy's LaserScan feeds `rangefinder2D_nwc_ros2`
//! and its Imu `imu_nwc_ros2`; `rgbdSensor_nwc_ros2` reads `rgbdSensor_nws_ros2`. Domain
//! indices 27..33; the frame-transform clients talk to each other of the gateway's harness; each test is its own process, so
//! `ROS_DOMAIN_ID` set here is the devices' alone.

#[path = "../../tests/common/mod.rs"]
mod common;

use serde_json::Value as Json;
use std::time::{Duration, Instant};
use yarp_devices::{shared, PolyDriver, Registry};
use yarp_proto::Property;
use yarp_ros2_gateway::hash::rihs01;

/// Sets the devices' ROS domain (before their first node) and registers the wrappers.
fn setup(test: &str, index: u16) -> Option<(common::Distro, u16)> {
    let distro = common::first_distro(test).into_iter().next()?;
    let domain = distro.domain(index);
    std::env::set_var("ROS_DOMAIN_ID", domain.to_string());
    std::env::set_var("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST");
    Registry::install(yarp_devices_ros2::register);
    Some((distro, domain))
}

fn open(text: &str) -> PolyDriver {
    PolyDriver::open(&Property::from_text(text)).unwrap_or_else(|e| panic!("{text}: {e}"))
}

fn json(line: &str) -> Json {
    serde_json::from_str(&line.replace("NaN", "null")).unwrap_or_else(|e| panic!("{e}: {line}"))
}

fn near(v: &Json, want: f64) -> bool {
    v.as_f64().is_some_and(|x| (x - want).abs() < 1e-4)
}

#[test]
fn frame_grabber_publishes_image_and_camera_info() {
    let Some((distro, d)) = setup("frame_grabber_publishes_image_and_camera_info", 30) else {
        return;
    };
    let _fg = open(
        "(device frameGrabber_nws_ros2) (subdevice fakeFrameGrabber) (width 64) (height 48) \
         (node_name h16b_camera) (topic_name /h16b/cam/image_raw) (frame_id cam_optical) \
         (period 0.05)",
    );
    let img = common::Peer::start(
        &distro,
        d,
        &[
            "sub",
            "sensor_msgs/msg/Image",
            "/h16b/cam/image_raw",
            "--summary",
        ],
    );
    let info = common::Peer::start(
        &distro,
        d,
        &["sub", "sensor_msgs/msg/CameraInfo", "/h16b/cam/camera_info"],
    );
    let m = json(&img.expect("MSG", common::T));
    assert_eq!(
        (m["width"].as_u64(), m["height"].as_u64()),
        (Some(64), Some(48)),
        "{m}"
    );
    assert_eq!(m["encoding"], "rgb8");
    assert_eq!(m["frame_id"], "cam_optical");
    assert_eq!(m["len"].as_u64(), Some(64 * 3 * 48));
    let ci = json(&info.expect("MSG", common::T));
    assert_eq!(ci["header"]["frame_id"], "cam_optical", "{ci}");
    assert_eq!(
        (ci["width"].as_u64(), ci["height"].as_u64()),
        (Some(64), Some(48))
    );
    assert!(ci["k"][0].as_f64().is_some_and(|f| f > 0.0), "{ci}");
}

#[test]
fn battery_and_odometry_reach_rclpy() {
    let Some((distro, d)) = setup("battery_and_odometry_reach_rclpy", 31) else {
        return;
    };
    let _battery = open(
        "(device battery_nws_ros2) (subdevice fakeBattery) (voltage 24.5) (charge 80) \
         (node_name h16b_battery) (topic_name /h16b/battery) (period 0.05)",
    );
    let _odometry = open(
        "(device odometry2D_nws_ros2) (subdevice fakeOdometry2D) (node_name h16b_odometry) \
         (topic_name /h16b/odom) (odom_frame odom) (base_frame base_link) (period 0.05)",
    );
    let battery = common::Peer::start(
        &distro,
        d,
        &["sub", "sensor_msgs/msg/BatteryState", "/h16b/battery"],
    );
    let odom = common::Peer::start(&distro, d, &["sub", "nav_msgs/msg/Odometry", "/h16b/odom"]);
    let info = common::Peer::start(
        &distro,
        d,
        &[
            "info_many",
            "/h16b/battery",
            "/h16b/odom",
            "/tf",
            "--timeout",
            "20",
        ],
    );
    let b = json(&battery.expect("MSG", common::T));
    assert!(near(&b["voltage"], 24.5), "{b}");
    assert!(
        near(&b["current"], 3.0) && near(&b["temperature"], 20.0),
        "{b}"
    );
    let pct = b["percentage"].as_f64().unwrap();
    assert!(
        pct <= 80.0 && pct > 79.0,
        "the YARP charge (%), as C++ sends it: {b}"
    );
    assert!(b["present"].as_bool().unwrap());
    let o = json(&odom.expect("MSG", common::T));
    assert_eq!(o["header"]["frame_id"], "odom", "{o}");
    assert_eq!(o["child_frame_id"], "base_link");
    let vx = o["twist"]["twist"]["linear"]["x"].as_f64().unwrap();
    assert!((0.0..5.0).contains(&vx), "{o}");
    let q = &o["pose"]["pose"]["orientation"];
    let norm: f64 = ["x", "y", "z", "w"]
        .iter()
        .map(|k| q[k].as_f64().unwrap().powi(2))
        .sum();
    assert!((norm - 1.0).abs() < 1e-9, "{o}");
    let info = json(&info.expect("INFO", common::T));
    for (topic, ty) in [
        ("/h16b/battery", "sensor_msgs/msg/BatteryState"),
        ("/h16b/odom", "nav_msgs/msg/Odometry"),
        ("/tf", "tf2_msgs/msg/TFMessage"),
    ] {
        let hash = rihs01(ty).unwrap();
        let e = &info[topic][0];
        assert_eq!(e["type"], ty, "{info}");
        assert!(
            e["hash"].as_str().unwrap().contains(&hash[7..]),
            "{topic}: {e}"
        );
    }
}

#[test]
fn rclpy_twist_commands_the_mobile_base() {
    let Some((distro, d)) = setup("rclpy_twist_commands_the_mobile_base", 32) else {
        return;
    };
    let nav = shared(open("(device fakeNavigation)"));
    let mut wrapper = open(
        "(device mobileBaseVelocityControl_nws_ros2) (node_name h16b_base) \
         (topic_name /h16b/cmd_vel)",
    );
    wrapper
        .device()
        .as_wrapper()
        .unwrap()
        .attach(nav.clone())
        .unwrap();
    let twist =
        r#"{"linear": {"x": 0.5, "y": -0.1, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 1.0}}"#;
    let _pub = common::Peer::start(
        &distro,
        d,
        &[
            "pub",
            "geometry_msgs/msg/Twist",
            "/h16b/cmd_vel",
            twist,
            "--wait-sub",
            "--count",
            "50",
            "--rate",
            "10",
        ],
    );
    let end = Instant::now() + common::T;
    let last = loop {
        let last = nav
            .lock()
            .device()
            .as_navigation_2d_velocity()
            .unwrap()
            .get_last_velocity_command()
            .unwrap();
        if last != (0.0, 0.0, 0.0) || Instant::now() > end {
            break last;
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    // angular z in rad/s becomes degrees/s, as C++ converts it
    assert_eq!((last.0, last.1), (0.5, -0.1));
    assert!((last.2 - 1f64.to_degrees()).abs() < 1e-9, "{last:?}");
}

#[test]
fn rclpy_laser_scans_feed_the_rangefinder_client() {
    let Some((distro, d)) = setup("rclpy_laser_scans_feed_the_rangefinder_client", 33) else {
        return;
    };
    let mut client = open(
        "(device rangefinder2D_nwc_ros2) (node_name h16b_laser_client) (topic_name /h16b/scan)",
    );
    let scan = r#"{"header": {"frame_id": "laser"}, "angle_min": -1.5707964, "angle_max": 1.5707964,
        "angle_increment": 0.7853982, "range_min": 0.1, "range_max": 10.0,
        "ranges": [1.0, 2.0, 3.0, 4.0, 5.0]}"#;
    let _pub = common::Peer::start(
        &distro,
        d,
        &[
            "pub",
            "sensor_msgs/msg/LaserScan",
            "/h16b/scan",
            scan,
            "--wait-sub",
            "--count",
            "50",
            "--rate",
            "10",
        ],
    );
    let laser = client.device().as_rangefinder_2d().unwrap();
    let end = Instant::now() + common::T;
    let (ranges, _) = loop {
        match laser.get_raw_data() {
            Ok(r) => break r,
            Err(e) if Instant::now() > end => panic!("no scan: {e}"),
            Err(_) => std::thread::sleep(Duration::from_millis(20)),
        }
    };
    assert_eq!(ranges, vec![1.0, 2.0, 3.0, 4.0, 5.0]);
    let (lo, hi) = laser.get_scan_limits().unwrap();
    assert!(
        (lo + 90.0).abs() < 1e-4 && (hi - 90.0).abs() < 1e-4,
        "{lo} {hi}"
    );
    assert!((laser.get_horizontal_resolution().unwrap() - 45.0).abs() < 1e-4);
    assert_eq!(laser.get_distance_range().unwrap(), (0.1f32 as f64, 10.0));
}

#[test]
fn rclpy_imu_feeds_the_imu_client() {
    let Some((distro, d)) = setup("rclpy_imu_feeds_the_imu_client", 29) else {
        return;
    };
    let mut client = open(
        "(device imu_nwc_ros2) (node_name h16b_imu_client) (topic_name /h16b/imu) \
         (sensor_name head_imu)",
    );
    // yaw 90 degrees; 1 rad/s about x
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let imu = format!(
        r#"{{"header": {{"frame_id": "head_imu_frame", "stamp": {{"sec": 100, "nanosec": 500000000}}}},
            "orientation": {{"x": 0.0, "y": 0.0, "z": {h}, "w": {h}}},
            "angular_velocity": {{"x": 1.0, "y": 0.0, "z": 0.0}},
            "linear_acceleration": {{"x": 0.0, "y": 0.0, "z": 9.81}}}}"#
    );
    let _pub = common::Peer::start(
        &distro,
        d,
        &[
            "pub",
            "sensor_msgs/msg/Imu",
            "/h16b/imu",
            &imu,
            "--wait-sub",
            "--count",
            "50",
            "--rate",
            "10",
        ],
    );
    let dev = client.device();
    let end = Instant::now() + common::T;
    while dev
        .as_orientation_sensors()
        .unwrap()
        .get_orientation_sensor_status(0)
        != yarp_devices::sensors::MasStatus::Ok
    {
        assert!(Instant::now() < end, "no Imu received");
        std::thread::sleep(Duration::from_millis(20));
    }
    let rpy = dev
        .as_orientation_sensors()
        .unwrap()
        .get_orientation_sensor_measure_as_roll_pitch_yaw(0)
        .unwrap();
    assert!(
        (rpy.values[2] - 90.0).abs() < 1e-6 && rpy.values[0].abs() < 1e-6,
        "{rpy:?}"
    );
    assert_eq!(rpy.timestamp, 100.5);
    let gyro = dev.as_three_axis_gyroscopes().unwrap();
    let g = gyro.get_three_axis_gyroscope_measure(0).unwrap();
    assert!((g.values[0] - 1f64.to_degrees()).abs() < 1e-9, "{g:?}");
    assert_eq!(gyro.get_three_axis_gyroscope_name(0).unwrap(), "head_imu");
    assert_eq!(
        gyro.get_three_axis_gyroscope_frame_name(0).unwrap(),
        "head_imu_frame"
    );
    let acc = dev.as_three_axis_linear_accelerometers().unwrap();
    assert_eq!(
        acc.get_three_axis_linear_accelerometer_measure(0)
            .unwrap()
            .values,
        vec![0.0, 0.0, 9.81]
    );
}

/// Not rclpy: our own server and client over DDS, the colour and depth images (and the
/// intrinsics from CameraInfo) arriving as `fakeDepthCamera` made them.
#[test]
fn rgbd_client_reads_the_rgbd_server() {
    let Some((_distro, _d)) = setup("rgbd_client_reads_the_rgbd_server", 28) else {
        return;
    };
    let camera = shared(open(
        "(device fakeDepthCamera) (width 32) (height 24) (mode grid)",
    ));
    let mut server = open(
        "(device rgbdSensor_nws_ros2) (node_name h16b_rgbd) (period 0.05) \
         (color_topic_name /h16b/rgbd/color/image_raw) (depth_topic_name /h16b/rgbd/depth/image_raw) \
         (color_frame_id rgb_frame) (depth_frame_id depth_frame)",
    );
    server
        .device()
        .as_wrapper()
        .unwrap()
        .attach(camera.clone())
        .unwrap();
    let mut client = open(
        "(device rgbdSensor_nwc_ros2) (node_name h16b_rgbd_client) \
         (color_topic_name /h16b/rgbd/color/image_raw) (depth_topic_name /h16b/rgbd/depth/image_raw)",
    );
    let rgbd = client.device().as_rgbd_sensor().unwrap();
    let end = Instant::now() + common::T;
    while rgbd.sensor_status() != yarp_devices::rgbd::RgbdStatus::OkInUse {
        assert!(Instant::now() < end, "no images from the server");
        std::thread::sleep(Duration::from_millis(20));
    }
    let ((color, cs), (depth, ds)) = rgbd.get_images().unwrap();
    assert_eq!((color.width(), color.height()), (32, 24));
    assert_eq!(depth.pixel_code(), yarp_proto::image::PixelCode::MONO_FLOAT);
    assert!(cs.time > 1.6e9 && ds.time > 1.6e9, "{cs:?} {ds:?}");
    // the grid pattern: red grows along x, green along y (fakeFrameGrabber's images are
    // bottom-up: ROS's top row is the grid's last), one scrolling blue row; depth is the
    // mean of the channels over 255 (the two images may be of adjacent frames, whose
    // blue rows differ)
    let p = color.pixel(31, 0).to_vec();
    assert_eq!((p[0], p[1]), (255, 255), "{p:?}");
    let d = f32::from_ne_bytes(depth.pixel(31, 0).try_into().unwrap());
    assert!(
        (d - 2.0 / 3.0).abs() < 1e-3 || (d - 1.0).abs() < 1e-3,
        "{d}"
    );
    let k = rgbd.rgb_intrinsic_param().unwrap();
    assert_eq!(k.find("focalLengthX").and_then(|v| v.as_f64()), Some(512.0));
    assert_eq!((rgbd.rgb_width(), rgbd.depth_height()), (32, 24));
}

/// `frameTransformSet_nwc_ros2` publishes what it is given on its `/tf` and `/tf_static`
/// topics (rclpy sees them with the TFMessage hash, the static writer transient local as
/// tf2's static listener needs) and `frameTransformGet_nwc_ros2` reads them back.
#[test]
fn frame_transforms_go_out_and_come_back() {
    let Some((distro, d)) = setup("frame_transforms_go_out_and_come_back", 27) else {
        return;
    };
    let groups = "(ROS2 (ft_topic /h16b/tf) (ft_topic_static /h16b/tf_static)) \
                  (GENERAL (period 0.02) (refresh_interval 5.0))";
    let mut get = open(&format!("(device frameTransformGet_nwc_ros2) {groups}"));
    let mut set = open(&format!("(device frameTransformSet_nwc_ros2) {groups}"));
    let info = common::Peer::start(
        &distro,
        d,
        &[
            "info_many",
            "/h16b/tf",
            "/h16b/tf_static",
            "--timeout",
            "20",
        ],
    );
    let now = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .as_secs_f64();
    let ft = |src: &str, dst: &str, is_static, x| yarp_devices::frames::FrameTransform {
        src_frame_id: src.into(),
        dst_frame_id: dst.into(),
        timestamp: now,
        is_static,
        translation: [x, 0.0, 0.5],
        rotation: [0.0, 0.0, 0.0, 1.0],
    };
    let sent = vec![
        ft("map", "odom", true, 1.0),
        ft("odom", "base_link", false, 2.0),
    ];
    let setter = set.device().as_frame_transform_storage_set().unwrap();
    setter.set_transforms(&sent).unwrap();
    let getter = get.device().as_frame_transform_storage_get().unwrap();
    let end = Instant::now() + common::T;
    let got = loop {
        let mut got = getter.get_transforms().unwrap();
        if got.len() == 2 || Instant::now() > end {
            got.sort_by(|a, b| a.src_frame_id.cmp(&b.src_frame_id));
            break got;
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    assert_eq!(got.len(), 2, "{got:?}");
    assert_eq!(
        (got[0].src_frame_id.as_str(), got[0].is_static),
        ("map", true)
    );
    assert_eq!(got[1].dst_frame_id, "base_link");
    assert_eq!(got[1].translation, [2.0, 0.0, 0.5]);
    assert!((got[1].timestamp - now).abs() < 1e-6);
    let info = json(&info.expect("INFO", common::T));
    let hash = rihs01("tf2_msgs/msg/TFMessage").unwrap();
    for topic in ["/h16b/tf", "/h16b/tf_static"] {
        let endpoints = info[topic].as_array().unwrap();
        assert!(
            endpoints.len() >= 2,
            "the setter's writer, the getter's reader: {info}"
        );
        for e in endpoints {
            // the static writer is transient local (C++'s, and what a tf2 static listener
            // asks: a volatile writer never matches it)
            if topic.ends_with("tf_static") && e["kind"] == "pub" {
                assert_eq!(e["durability"], "TRANSIENT_LOCAL", "{info}");
            }
            assert_eq!(e["type"], "tf2_msgs/msg/TFMessage", "{info}");
            assert!(
                e["hash"].as_str().unwrap().contains(&hash[7..]),
                "{topic}: {e}"
            );
        }
    }
}

/// `rgbdSensor_nws_ros2` with `pub_status_topic`: `/<node_name>/publisher_status` says
/// 3 (colour and depth published).
#[test]
fn rgbd_server_publishes_its_status() {
    let Some((distro, d)) = setup("rgbd_server_publishes_its_status", 28) else {
        return;
    };
    let _server = open(
        "(device rgbdSensor_nws_ros2) (subdevice fakeDepthCamera) (width 16) (height 12) \
         (node_name h16b_rgbd_status) (period 0.05) (pub_status_topic 1) \
         (color_topic_name /h16b/status/color/image_raw) \
         (depth_topic_name /h16b/status/depth/image_raw) \
         (color_frame_id rgb_frame) (depth_frame_id depth_frame)",
    );
    let status = common::Peer::start(
        &distro,
        d,
        &[
            "sub",
            "std_msgs/msg/UInt8",
            "/h16b_rgbd_status/publisher_status",
        ],
    );
    let m = json(&status.expect("MSG", common::T));
    assert_eq!(m["data"].as_u64(), Some(3), "{m}");
}
