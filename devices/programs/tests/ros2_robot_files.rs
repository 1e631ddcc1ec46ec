//! ergoCubSN001's ROS 2 sensor files from robots-configuration (`sensors_ros2.xml`, which
//! includes `sensors/rplidar_ros2.xml` and `sensors/realsense_ros2.xml`) brought up by our
//! `yarprobotinterface` (a child process, under netns-run), with rclpy as the ROS 2 side.
//!
//! The test's copy swaps the hardware for fakes with the same attach names (`rpLidar4` ->
//! `fakeLaser`, `realsense2` -> `fakeDepthCamera`) and adds the robot's
//! `rgbdToPointCloudSensor_nws_ros2` element (`pc_nws_ros`, from
//! `sensors/ros2_repeaters/depth_compressed_ros2.xml`, where it serves an
//! `RGBDSensorClient`) attached to the camera. Everything else is the robot's own text,
//! the YARP wrappers it also starts (`rangefinder2D_nws_yarp`, `rgbdSensor_nws_yarp`)
//! included: their ports answer too.
//!
//! Then the robot's ROS 2 repeaters (`sensors/ros2_repeaters/depth_compressed_ros2.xml`,
//! `lidar_compressed_ros2.xml`), unmodified, in further `yarprobotinterface`s: they read
//! the robot's YARP streams over mjpeg and the zlib port monitors, as on a laptop beside
//! the robot, and republish them to ROS 2.
//! Domain indices 34 and 31 of the gateway's harness.

#[path = "../../tests/fixtures/robotinterface/live_support.rs"]
mod support;

#[path = "../../../gateway/tests/common/mod.rs"]
mod common;

use std::path::{Path, PathBuf};
use std::time::Duration;
use support::{ask, start_network, wait_reply, Child};
use yarp_ros2_gateway::hash::rihs01;

const BIN: &str = env!("CARGO_BIN_EXE_yarprobotinterface");
/// Peers start while the robot comes up on a loaded machine: a generous bound.
const LONG: Duration = Duration::from_secs(60);

fn ergocub() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/robots-configuration/ergoCubSN001")
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// `text` with `from` replaced exactly once.
fn swap(text: &str, from: &str, to: &str) -> String {
    assert_eq!(text.matches(from).count(), 1, "{from} in the robot file");
    text.replace(from, to)
}

/// The `<device ...>` element whose opening tag contains `marker`.
fn element<'a>(text: &'a str, marker: &str) -> &'a str {
    let at = text.find(marker).expect("marker");
    let start = text[..at].rfind("<device").expect("<device");
    let end = at + text[at..].find("</device>").expect("</device>") + "</device>".len();
    &text[start..end]
}

/// The test's copy of the robot's files in `dir`; with `pc`, the repeater's point cloud
/// wrapper attached to the camera itself.
fn robot_copy(dir: &Path, pc: bool) {
    let src = ergocub();
    std::fs::create_dir_all(dir.join("sensors")).unwrap();
    std::fs::copy(src.join("sensors_ros2.xml"), dir.join("sensors_ros2.xml")).unwrap();
    let lidar = read(&src.join("sensors/rplidar_ros2.xml"));
    let lidar = swap(&lidar, r#"type="rpLidar4""#, r#"type="fakeLaser""#);
    std::fs::write(dir.join("sensors/rplidar_ros2.xml"), lidar).unwrap();
    let camera = read(&src.join("sensors/realsense_ros2.xml"));
    let camera = swap(&camera, r#"type="realsense2""#, r#"type="fakeDepthCamera""#);
    let camera = if pc {
        let repeater = read(&src.join("sensors/ros2_repeaters/depth_compressed_ros2.xml"));
        let pc = element(&repeater, r#"name="pc_nws_ros""#);
        let pc = swap(pc, "depth_nwc_yarp", "realsenseD450");
        let at = camera.rfind("</devices>").expect("</devices>");
        format!("{}    {pc}\n\n{}", &camera[..at], &camera[at..])
    } else {
        camera
    };
    std::fs::write(dir.join("sensors/realsense_ros2.xml"), camera).unwrap();
}

fn json(line: &str) -> serde_json::Value {
    // Python's json writes infinite ranges as `Infinity`, which JSON has not.
    let line = line
        .replace("-Infinity", "-1e300")
        .replace("Infinity", "1e300");
    serde_json::from_str(&line).unwrap_or_else(|e| panic!("{e}: {line}"))
}

/// The peer's next `prefix` line; on timeout the robot's output goes into the panic.
async fn line(peer: &common::Peer, prefix: &str, robot: &Child) -> String {
    let end = std::time::Instant::now() + LONG;
    loop {
        if let Some(l) = peer.try_line(prefix) {
            return l;
        }
        if std::time::Instant::now() > end {
            panic!(
                "no {prefix} within {LONG:?}; yarprobotinterface:\n{}",
                robot.output()
            );
        }
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
}

/// Whether robots-configuration is beside the repository (a failure under CI).
fn robot_files_present() -> bool {
    if ergocub().exists() {
        return true;
    }
    let why = format!("no robots-configuration at {}", ergocub().display());
    assert!(std::env::var("CI").as_deref() != Ok("true"), "{why}");
    eprintln!("\n*** SKIPPED: {why} ***\n");
    false
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn ergocub_lidar_and_realsense_files_publish_to_rclpy() {
    let distros = common::first_distro("ergocub_lidar_and_realsense_files_publish_to_rclpy");
    let Some(distro) = distros.first() else {
        return;
    };
    if !robot_files_present() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    robot_copy(dir.path(), true);
    let net = start_network().await;
    let domain = distro.domain(34).to_string();
    let mut child = Child::spawn_env(
        BIN,
        &["--config", "sensors_ros2.xml"],
        dir.path(),
        Some(net.conf_home.path()),
        &[
            ("ROS_DOMAIN_ID", Path::new(&domain)),
            ("ROS_AUTOMATIC_DISCOVERY_RANGE", Path::new("LOCALHOST")),
        ],
    );
    let ri = "/ergocub/yarprobotinterface";
    wait_reply(&net.client, ri, "is_ready", "[ok]", &mut child).await;

    let d: u16 = domain.parse().unwrap();
    let topics = [
        ("/scan", "sensor_msgs/msg/LaserScan"),
        (
            "/camera_rgbd/color/image_rect_color",
            "sensor_msgs/msg/Image",
        ),
        (
            "/camera_rgbd/color/camera_info",
            "sensor_msgs/msg/CameraInfo",
        ),
        ("/camera_rgbd/depth/image_rect", "sensor_msgs/msg/Image"),
        (
            "/camera_rgbd/depth/camera_info",
            "sensor_msgs/msg/CameraInfo",
        ),
        ("/camera/depth/color/points", "sensor_msgs/msg/PointCloud2"),
    ];
    let peers: Vec<common::Peer> = topics
        .iter()
        .map(|(topic, ty)| {
            let mut args = vec!["sub", ty, topic, "--timeout", "60"];
            if ty.ends_with("Image") || ty.ends_with("PointCloud2") {
                args.push("--summary");
            }
            common::Peer::start(distro, d, &args)
        })
        .collect();
    let mut info_args = vec!["info_many"];
    info_args.extend(topics.iter().map(|(t, _)| *t));
    info_args.extend(["--timeout", "60"]);
    let info_peer = common::Peer::start(distro, d, &info_args);
    let mut got = Vec::new();
    for p in &peers {
        got.push(json(&line(p, "MSG", &child).await));
    }
    let info = json(&line(&info_peer, "INFO", &child).await);

    // rplidar_ros2.xml: fakeLaser with the lidar's SENSOR group, published at 0.1 s
    let scan = &got[0];
    assert_eq!(scan["header"]["frame_id"], "head_laser_frame", "{scan}");
    assert_eq!(scan["ranges"].as_array().unwrap().len(), 3000);
    assert!(close(
        scan["angle_max"].as_f64().unwrap(),
        std::f64::consts::TAU,
        1e-5
    ));
    assert!(close(
        scan["angle_increment"].as_f64().unwrap(),
        0.12f64.to_radians(),
        1e-6
    ));
    assert!(close(scan["range_max"].as_f64().unwrap(), 30.0, 1e-6));
    assert!(close(scan["scan_time"].as_f64().unwrap(), 0.1, 1e-6));
    // realsense_ros2.xml: fakeDepthCamera (fakeFrameGrabber's 320x240)
    let (color, color_info, depth, depth_info, cloud) =
        (&got[1], &got[2], &got[3], &got[4], &got[5]);
    assert_eq!(color["encoding"], "rgb8", "{color}");
    assert_eq!(
        (color["width"].as_u64(), color["height"].as_u64()),
        (Some(320), Some(240))
    );
    assert_eq!(color["frame_id"], "realsense_rgb_frame");
    assert_eq!(color["len"].as_u64(), Some(320 * 3 * 240));
    assert!(color["sec"].as_u64().unwrap() > 1_600_000_000, "{color}");
    assert_eq!(depth["encoding"], "32FC1", "{depth}");
    assert_eq!(depth["len"].as_u64(), Some(320 * 4 * 240));
    for ci in [color_info, depth_info] {
        assert_eq!(ci["header"]["frame_id"], "realsense_rgb_frame", "{ci}");
        assert_eq!(
            (ci["width"].as_u64(), ci["height"].as_u64()),
            (Some(320), Some(240))
        );
        assert_eq!(ci["distortion_model"], "plumb_bob");
        assert_eq!(ci["k"][0].as_f64(), Some(512.0));
        assert_eq!(ci["k"][2].as_f64(), Some(235.0));
        assert_eq!(ci["d"].as_array().unwrap().len(), 5);
    }
    // the point cloud: one coloured point per pixel, 32 bytes each
    assert_eq!(cloud["frame_id"], "realsense_rgb_frame", "{cloud}");
    assert_eq!(
        (cloud["width"].as_u64(), cloud["height"].as_u64()),
        (Some(76800), Some(1))
    );
    assert_eq!(cloud["point_step"].as_u64(), Some(32));
    assert_eq!(cloud["len"].as_u64(), Some(76800 * 32));
    assert_eq!(cloud["fields"][3], serde_json::json!(["rgb", 16, 7, 1]));

    // every endpoint with its REP-2016 hash, seen by rclpy
    for (topic, ty) in topics {
        let hash = rihs01(ty).unwrap();
        let endpoints = info[topic].as_array().cloned().unwrap_or_default();
        assert!(!endpoints.is_empty(), "{topic}: {info}");
        for e in endpoints {
            let h = e["hash"].as_str().unwrap_or_default();
            assert!(
                h.contains(&hash[7..]),
                "{topic}: rclpy sees {h}, want {hash}"
            );
        }
    }
    for (topic, node) in [
        ("/scan", "rangefinder_ros2_node"),
        (
            "/camera_rgbd/color/image_rect_color",
            "rgbdsensor_ros2_node",
        ),
        ("/camera/depth/color/points", "pc_ros2_node"),
    ] {
        let nodes: Vec<&str> = info[topic]
            .as_array()
            .unwrap()
            .iter()
            .filter_map(|e| e["node"].as_str())
            .collect();
        assert!(nodes.contains(&node), "{topic}: {nodes:?}");
    }

    // the robot's YARP wrappers of the same devices
    let laser = ask(
        &net.client,
        "/ergocub/laser:o/rpc:i",
        "getDistanceRange RPC",
        &mut child,
    )
    .await;
    let range: Vec<f64> = yarp_proto::Bottle::from_text(&laser)
        .iter()
        .filter_map(|v| v.as_f64())
        .collect();
    assert_eq!(range, [0.0, 0.1, 30.0], "{laser}");
    let width = ask(
        &net.client,
        "/depthCamera/rpc:i",
        "[visd] [get] [w]",
        &mut child,
    )
    .await;
    assert_eq!(width, "[visd] [w] [is] 320");
    for port in [
        "/ergocub/laser:o",
        "/depthCamera/rgbImage:o",
        "/depthCamera/depthImage:o",
    ] {
        assert!(net.client.query(port).await.unwrap().is_some(), "{port}");
    }

    assert_eq!(ask(&net.client, ri, "quit", &mut child).await, "bye");
    let status = child.wait_exit(common::T).await;
    let out = child.output();
    assert!(status.is_some(), "yarprobotinterface did not quit:\n{out}");
    assert!(!out.contains("unknown device"), "{out}");
}

/// The robot's ROS 2 repeaters, unmodified, read the (fake) robot's camera and lidar over
/// the carriers their files name (`ImageCarrier mjpeg`, the depth and the laser scan
/// through the zlib port monitors) and republish them: rclpy receives the colour and depth
/// images, the point cloud and the scan.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn ergocub_ros2_repeaters_run_unmodified() {
    let distros = common::first_distro("ergocub_ros2_repeaters_run_unmodified");
    let Some(distro) = distros.first() else {
        return;
    };
    if !robot_files_present() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    robot_copy(dir.path(), false);
    let net = start_network().await;
    let domain = distro.domain(31).to_string();
    let env = [
        ("ROS_DOMAIN_ID", Path::new(&domain)),
        ("ROS_AUTOMATIC_DISCOVERY_RANGE", Path::new("LOCALHOST")),
    ];
    // the robot: its camera and lidar served on YARP (and on ROS 2, unused here)
    let mut robot = Child::spawn_env(
        BIN,
        &["--config", "sensors_ros2.xml"],
        dir.path(),
        Some(net.conf_home.path()),
        &env,
    );
    wait_reply(
        &net.client,
        "/ergocub/yarprobotinterface",
        "is_ready",
        "[ok]",
        &mut robot,
    )
    .await;
    // the repeaters, from robots-configuration as published
    let repeaters = ergocub().join("sensors/ros2_repeaters");
    let mut depth = Child::spawn_env(
        BIN,
        &[
            "--config",
            &repeaters
                .join("depth_compressed_ros2.xml")
                .to_string_lossy(),
            "--portprefix",
            "/depthRepeater",
        ],
        dir.path(),
        Some(net.conf_home.path()),
        &env,
    );
    let mut lidar = Child::spawn_env(
        BIN,
        &[
            "--config",
            &repeaters
                .join("lidar_compressed_ros2.xml")
                .to_string_lossy(),
            "--portprefix",
            "/lidarRepeater",
        ],
        dir.path(),
        Some(net.conf_home.path()),
        &env,
    );
    wait_reply(
        &net.client,
        "/depthRepeater/yarprobotinterface",
        "is_ready",
        "[ok]",
        &mut depth,
    )
    .await;
    wait_reply(
        &net.client,
        "/lidarRepeater/yarprobotinterface",
        "is_ready",
        "[ok]",
        &mut lidar,
    )
    .await;

    let d: u16 = domain.parse().unwrap();
    let topics = [
        ("/camera/rgbd/img", "sensor_msgs/msg/Image", &depth),
        ("/camera/rgbd/depth", "sensor_msgs/msg/Image", &depth),
        (
            "/camera/depth/color/points",
            "sensor_msgs/msg/PointCloud2",
            &depth,
        ),
        ("/scan_local", "sensor_msgs/msg/LaserScan", &lidar),
    ];
    let peers: Vec<common::Peer> = topics
        .iter()
        .map(|(topic, ty, _)| {
            let mut args = vec!["sub", ty, topic, "--timeout", "60"];
            if !ty.ends_with("LaserScan") {
                args.push("--summary");
            }
            common::Peer::start(distro, d, &args)
        })
        .collect();
    let mut got = Vec::new();
    for (p, (_, _, child)) in peers.iter().zip(&topics) {
        got.push(json(&line(p, "MSG", child).await));
    }
    let (color, depth_img, cloud, scan) = (&got[0], &got[1], &got[2], &got[3]);
    // the colour image came through JPEG: rgb8, the camera's size
    assert_eq!(color["encoding"], "rgb8", "{color}");
    assert_eq!(
        (color["width"].as_u64(), color["height"].as_u64()),
        (Some(320), Some(240))
    );
    assert_eq!(color["frame_id"], "realsense_rgb_frame");
    assert!(color["sec"].as_u64().unwrap() > 1_600_000_000, "{color}");
    assert_eq!(depth_img["encoding"], "32FC1", "{depth_img}");
    assert_eq!(depth_img["len"].as_u64(), Some(320 * 4 * 240));
    assert_eq!(
        (cloud["width"].as_u64(), cloud["height"].as_u64()),
        (Some(76800), Some(1)),
        "{cloud}"
    );
    assert_eq!(scan["header"]["frame_id"], "head_laser_frame", "{scan}");
    assert_eq!(scan["ranges"].as_array().unwrap().len(), 3000);
    assert!(close(scan["range_max"].as_f64().unwrap(), 30.0, 1e-6));

    // the repeaters' own YARP side: the connections they made, with the files' carriers
    let carrier = |from: &'static str, to: &'static str| {
        let ns = net.client.clone();
        async move {
            yarp_net::network::connection_carrier(&ns, from, to)
                .await
                .ok()
                .flatten()
        }
    };
    assert_eq!(
        carrier("/ergocub/laser:o", "/laser_client_repeater:i").await.as_deref(),
        Some("fast_tcp+send.portmonitor+file.bottle_compression_zlib+recv.portmonitor+file.bottle_compression_zlib+type.dll")
    );
    assert_eq!(
        carrier("/depthCamera/depthImage:o", "/camera/depth/image_depth:i").await.as_deref(),
        Some("fast_tcp+send.portmonitor+file.depthimage_compression_zlib+recv.portmonitor+file.depthimage_compression_zlib+type.dll")
    );
    assert!(net
        .client
        .query("/ergoCubSN000/realsense_repeater/rgbImage:o")
        .await
        .unwrap()
        .is_some());

    for (port, child) in [
        ("/lidarRepeater/yarprobotinterface", &mut lidar),
        ("/depthRepeater/yarprobotinterface", &mut depth),
        ("/ergocub/yarprobotinterface", &mut robot),
    ] {
        assert_eq!(ask(&net.client, port, "quit", child).await, "bye");
        let status = child.wait_exit(common::T).await;
        let out = child.output();
        assert!(status.is_some(), "{port} did not quit:\n{out}");
        assert!(!out.contains("unknown device"), "{out}");
        assert!(!out.contains("Cannot connect"), "{out}");
    }
}
