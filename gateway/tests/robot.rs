//! The whole robot as ROS tools expect it, against rclpy (run under netns-run): two real
//! control boards (`fakeMotionControl` behind `controlBoard_nws_yarp`) merged into one
//! `/joint_states` that a default-QoS rclpy node receives, and `/robot_description` from
//! a URDF named in the mapping, received by a transient-local subscriber that joins after
//! the gateway published it; `/tf` of the joints reported and `/tf_static` of the fixed
//! ones (received late, as a tf2 static listener does). Domain indices: 33, 34.

mod common;

use common::{blocking, Peer, T};
use serde_json::Value as Json;
use std::path::{Path, PathBuf};
use std::time::Instant;
use yarp_proto::Value;
use yarp_ros2_gateway::gateway::{Gateway, Options};
use yarp_ros2_gateway::mapping::Mappings;

/// A directory of its own for this test's files (removed on drop).
struct TempDir(PathBuf);

impl TempDir {
    fn new(tag: &str) -> TempDir {
        let d = std::env::temp_dir().join(format!("gw-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&d).expect("temp dir");
        TempDir(d)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Starts a gateway for the mapping file `file` in `domain`, DDS on loopback only.
async fn gateway_for(file: &Path, ns: &yarp_net::nameserver::NameClient, domain: u16) -> Gateway {
    std::env::set_var("ROS_DISTRO", "kilted");
    let m = Mappings::load(&[file]).expect("test mapping");
    let opt = Options {
        domain_id: domain,
        networks: vec!["127.0.0.1".parse().unwrap()],
        ..Default::default()
    };
    Gateway::start(&m, ns.clone(), opt)
        .await
        .expect("gateway starts")
}

const URDF: &str = r#"<?xml version="1.0"?>
<robot name="t10_bot">
  <link name="base"/><link name="neck"/><link name="head"/>
  <link name="shoulder"/><link name="forearm"/><link name="slider"/>
  <joint name="neck_pitch" type="revolute"><parent link="base"/><child link="neck"/>
    <axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="neck_yaw" type="revolute"><parent link="neck"/><child link="head"/>
    <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="shoulder"/>
    <axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
  <joint name="elbow" type="revolute"><parent link="shoulder"/><child link="forearm"/>
    <origin xyz="0 0 -0.3"/>
    <axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
  <link name="camera"/>
  <joint name="camera_mount" type="fixed"><parent link="head"/><child link="camera"/>
    <origin xyz="0.1 0 0.2" rpy="0 0 1.5707963267948966"/></joint>
  <joint name="rail" type="prismatic"><parent link="forearm"/><child link="slider"/>
    <axis xyz="1 0 0"/><limit lower="0" upper="0.5" effort="1" velocity="1"/></joint>
</robot>
"#;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn merged_joint_states_and_latched_robot_description() {
    for d in common::distros("merged_joint_states_and_latched_robot_description") {
        merged_joint_states_and_latched_robot_description_on(&d).await;
    }
}

async fn merged_joint_states_and_latched_robot_description_on(venv: &common::Distro) {
    let domain = venv.domain(33);
    let ns = common::device_name_server();
    let boards = [
        (
            "/t10/head",
            "neck_pitch neck_yaw",
            "revolute revolute",
            vec![10.0, -20.0],
        ),
        (
            "/t10/arm",
            "shoulder elbow rail",
            "revolute revolute prismatic",
            vec![30.0, 45.0, 0.25],
        ),
    ];
    let mut devices = Vec::new();
    for (name, axes, types, pos) in boards.clone() {
        let quoted = |s: &str| {
            s.split(' ')
                .map(|w| format!("\"{w}\""))
                .collect::<Vec<_>>()
                .join(" ")
        };
        let n = pos.len();
        let (axes, types) = (quoted(axes), quoted(types));
        devices.push(
            blocking(move || {
                common::open_device(&format!(
                    "device controlBoard_nws_yarp\nsubdevice fakeMotionControl\nname {name}\n\
                     period 0.01\n[GENERAL]\njoints {n}\nAxisName {axes}\nAxisType {types}\n"
                ))
            })
            .await,
        );
        // Move the joints (instantly: the fake's reference speed is 0) through a client.
        devices.push(
            blocking(move || {
                let mut c = common::open_device(&format!(
                    "device remote_controlboard\nremote {name}\nlocal {name}/mover\ncarrier tcp\n"
                ));
                c.device()
                    .as_position_control()
                    .unwrap()
                    .position_moves(&pos)
                    .unwrap();
                c
            })
            .await,
        );
    }
    let dir = TempDir::new("robot");
    std::fs::create_dir_all(dir.0.join("description")).unwrap();
    std::fs::write(dir.0.join("description/t10.urdf"), URDF).unwrap();
    let file = dir.0.join("robot.toml");
    std::fs::write(
        &file,
        r#"
[[topic]]
name = "head_joints"
direction = "yarp_to_ros"
yarp_port = "/gw10/head/state:i"
yarp_source = "/t10/head/state:o"
ros_topic = "/t10/head/joint_states"
ros_type = "sensor_msgs/msg/JointState"
joint_names = { from = "axis_info", rpc_port = "/t10/head/rpc:i" }

[[topic]]
name = "arm_joints"
direction = "yarp_to_ros"
yarp_port = "/gw10/arm/state:i"
yarp_source = "/t10/arm/state:o"
ros_topic = "/t10/arm/joint_states"
ros_type = "sensor_msgs/msg/JointState"
joint_names = { from = "axis_info", rpc_port = "/t10/arm/rpc:i" }

[[robot]]
name = "t10_bot"
joint_states = { parts = ["head_joints", "arm_joints"], rate_hz = 20 }
robot_description = { urdf = "description/t10.urdf" }
"#,
    )
    .unwrap();
    let gw = gateway_for(&file, &ns, domain).await;

    // A default-QoS rclpy node (reliable, volatile, keep-last 10) on /joint_states.
    let sub = Peer::start(
        venv,
        domain,
        &[
            "sub",
            "sensor_msgs/msg/JointState",
            "/joint_states",
            "--count",
            "1000",
        ],
    );
    sub.expect_async("READY", T).await;
    let names = ["neck_pitch", "neck_yaw", "shoulder", "elbow", "rail"];
    let want = [
        10f64.to_radians(),
        (-20f64).to_radians(),
        30f64.to_radians(),
        45f64.to_radians(),
        0.25,
    ];
    // Until both boards answered their axis names, a message may hold one part only; and
    // the first states may predate the moves.
    let end = Instant::now() + T;
    let (m, first) = loop {
        let line = sub.expect_async("MSG", T).await;
        let m: Json = serde_json::from_str(&line).unwrap();
        let pos: Vec<f64> = m["position"]
            .as_array()
            .unwrap()
            .iter()
            .filter_map(Json::as_f64)
            .collect();
        if m["name"] == serde_json::json!(names)
            && pos.len() == want.len()
            && pos.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-9)
        {
            break (m, Instant::now());
        }
        assert!(Instant::now() < end, "no merged state matched: {m}");
    };
    assert_eq!(m["velocity"], serde_json::json!([]), "{m}");
    assert_eq!(m["header"]["frame_id"], "");
    let stamp = m["header"]["stamp"]["sec"].as_f64().unwrap()
        + m["header"]["stamp"]["nanosec"].as_f64().unwrap() * 1e-9;
    let now = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .as_secs_f64();
    assert!((now - stamp).abs() < 10.0, "stamp {stamp}, now {now}");
    // At most rate_hz (20) merged messages a second: count one second's worth.
    let mut n = 0;
    while first.elapsed().as_secs_f64() < 1.0 {
        if sub.try_line("MSG").is_some() {
            n += 1;
        }
        tokio::time::sleep(std::time::Duration::from_millis(5)).await;
    }
    assert!(
        (5..=22).contains(&n),
        "{n} merged messages in 1 s at rate_hz 20"
    );
    eprintln!("merged /joint_states: {m} ({n} in 1 s)");

    // The description was published at start: a transient-local subscriber that joins
    // now still gets it (latched), as robot_state_publisher's readers do.
    let desc = Peer::start(
        venv,
        domain,
        &[
            "sub",
            "std_msgs/msg/String",
            "/robot_description",
            "--transient",
            "--depth",
            "1",
        ],
    );
    desc.expect_async("READY", T).await;
    let m: Json = serde_json::from_str(&desc.expect_async("MSG", T).await).unwrap();
    assert_eq!(m["data"], URDF);

    // TF as robot_state_publisher gives it. PyPI has no tf2_msgs for rclpy: rclpy checks
    // the endpoints (type, hash, durability), and a reader on our ROS layer that joins
    // late reads the messages (transient local, depth 1: /tf_static as tf2 reads it).
    let info = Peer::start(
        venv,
        domain,
        &["info_many", "/tf_static", "/tf", "--timeout", "20"],
    );
    let found: Json = serde_json::from_str(&info.expect_async("INFO", T).await).unwrap();
    let hash = yarp_ros2_gateway::hash::rihs01("tf2_msgs/msg/TFMessage").unwrap();
    for (topic, durability) in [("/tf_static", "TRANSIENT_LOCAL"), ("/tf", "VOLATILE")] {
        let e = &found[topic][0];
        assert_eq!(e["type"], "tf2_msgs/msg/TFMessage", "{found}");
        assert_eq!(e["hash"], hash, "{found}");
        assert_eq!(e["durability"], durability, "{found}");
        assert_eq!(e["kind"], "pub", "{found}");
    }
    let (_ctx, mut listener) = yarp_ros2_gateway::ros::start_node(
        domain,
        &["127.0.0.1".parse().unwrap()],
        "/",
        "t10_tf_listener",
    )
    .unwrap();
    let latched = yarp_ros2_gateway::mapping::Qos {
        reliability: Some(yarp_ros2_gateway::mapping::Reliability::Reliable),
        durability: yarp_ros2_gateway::mapping::Durability::TransientLocal,
        depth: 1,
    };
    let tf_type = "tf2_msgs/msg/TFMessage";
    let statics =
        yarp_ros2_gateway::ros::subscription(&mut listener, "/tf_static", tf_type, &latched)
            .unwrap();
    let moving =
        yarp_ros2_gateway::ros::subscription(&mut listener, "/tf", tf_type, &Default::default())
            .unwrap();
    // A message, in the generic Bottle layout.
    let read = async |sub: &ros2_client::Subscription<yarp_ros2_gateway::dynmsg::Value>| {
        let seed = yarp_ros2_gateway::dynmsg::MsgSeed::new(tf_type).unwrap();
        let stream = sub.async_stream_seed(seed);
        futures::pin_mut!(stream);
        let (m, _) = tokio::time::timeout(T, futures::StreamExt::next(&mut stream))
            .await
            .expect("a TF message in time")
            .expect("a stream")
            .expect("a TFMessage");
        yarp_ros2_gateway::generic::to_yarp(seed.0, &m).unwrap()
    };
    let close = |v: &Value, want: &[f64]| {
        let l = v.as_list().expect("a list");
        l.len() == want.len()
            && l.iter()
                .zip(want)
                .all(|(x, y)| (x.as_f64().unwrap() - y).abs() < 1e-9)
    };
    // (transforms): each ((stamp frame_id) child_frame_id ((x y z) (x y z w)))
    let b = read(&statics).await;
    let t = b.get(0).and_then(Value::as_list).expect("transforms");
    assert_eq!(t.len(), 1, "{b}");
    let cam = t.get(0).and_then(Value::as_list).unwrap();
    let header = cam.get(0).and_then(Value::as_list).unwrap();
    assert_eq!(header.get(1).and_then(Value::as_str), Some("head"), "{b}");
    assert_eq!(cam.get(1).and_then(Value::as_str), Some("camera"), "{b}");
    let tr = cam.get(2).and_then(Value::as_list).unwrap();
    let h = std::f64::consts::FRAC_1_SQRT_2;
    assert!(close(tr.get(0).unwrap(), &[0.1, 0.0, 0.2]), "{b}");
    assert!(close(tr.get(1).unwrap(), &[0.0, 0.0, h, h]), "{b}");
    // /tf: every moving joint, at the positions the boards report.
    let b = read(&moving).await;
    let t = b.get(0).and_then(Value::as_list).expect("transforms");
    assert_eq!(t.len(), 5, "{b}");
    let child = |c: &str| {
        t.iter()
            .filter_map(Value::as_list)
            .find(|x| x.get(1).and_then(Value::as_str) == Some(c))
            .unwrap_or_else(|| panic!("no transform of {c}: {b}"))
    };
    let elbow = child("forearm");
    let parent = elbow.get(0).and_then(Value::as_list).and_then(|h| h.get(1));
    assert_eq!(parent.and_then(Value::as_str), Some("shoulder"), "{b}");
    let tr = elbow.get(2).and_then(Value::as_list).unwrap();
    let (s, c) = (22.5f64.to_radians().sin(), 22.5f64.to_radians().cos());
    assert!(close(tr.get(0).unwrap(), &[0.0, 0.0, -0.3]), "{b}");
    assert!(close(tr.get(1).unwrap(), &[0.0, s, 0.0, c]), "{b}");
    let rail = child("slider").get(2).and_then(Value::as_list).unwrap();
    assert!(close(rail.get(0).unwrap(), &[0.25, 0.0, 0.0]), "{b}");
    gw.shutdown().await;
    drop(devices);
}

const EYES_INI: &str = "\
// as icub-main's stereoCalib writes it
[CAMERA_CALIBRATION_LEFT]
projection pinhole
drawCenterCross 0
w 320
h 240
fx 215.622
fy 215.056
cx 163.367
cy 111.212
k1 -0.367522
k2 0.132343
p1 -0.000399841
p2 -0.00016906
";

/// A real camera (`fakeFrameGrabber` served by `frameGrabber_nws_yarp`, 320x240 at 10 Hz)
/// as sensor_msgs/Image, and beside it `camera_info` with the intrinsics of an
/// icubEyes.ini-style group: a default-QoS rclpy node gets a CameraInfo with the same
/// stamp and frame_id as each Image.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn camera_info_beside_each_image() {
    for d in common::distros("camera_info_beside_each_image") {
        camera_info_beside_each_image_on(&d).await;
    }
}

async fn camera_info_beside_each_image_on(venv: &common::Distro) {
    let domain = venv.domain(34);
    // YARP names of their own per distro: the device name server lives on in the process.
    let t34 = format!("/t34{}", venv.name);
    let ns = common::device_name_server();
    let _cam = blocking({
        let t34 = t34.clone();
        move || {
            common::open_device(&format!(
                "device frameGrabber_nws_yarp\nsubdevice fakeFrameGrabber\nname {t34}/cam\n\
                 width 320\nheight 240\nmode line\nfreq 10\nperiod 0.1\n"
            ))
        }
    })
    .await;
    let dir = TempDir::new(&format!("camera-{}", venv.name));
    std::fs::create_dir_all(dir.0.join("calib")).unwrap();
    std::fs::write(dir.0.join("calib/icubEyes.ini"), EYES_INI).unwrap();
    let file = dir.0.join("camera.toml");
    std::fs::write(
        &file,
        r#"
[[topic]]
name = "left_camera"
direction = "yarp_to_ros"
yarp_port = "/gw34/cam:i"
yarp_source = "/t34/cam"
ros_topic = "/cam/left/image_raw"
ros_type = "sensor_msgs/msg/Image"
frame_id = "left_camera"
qos = { reliability = "best_effort", depth = 2 }
camera_info = { ini = "calib/icubEyes.ini", group = "CAMERA_CALIBRATION_LEFT" }
"#
        .replace("/t34", &t34)
        .replace("/gw34", &format!("/gw{t34}")),
    )
    .unwrap();
    let gw = gateway_for(&file, &ns, domain).await;
    let images = Peer::start_with_profile(
        venv,
        domain,
        &[
            "sub",
            "sensor_msgs/msg/Image",
            "/cam/left/image_raw",
            "--summary",
            "--best-effort",
            "--count",
            "100000",
        ],
        Some("fastdds_large_data.xml"),
    );
    // Default QoS: reliable, volatile, keep-last 10.
    let infos = Peer::start(
        venv,
        domain,
        &[
            "sub",
            "sensor_msgs/msg/CameraInfo",
            "/cam/left/camera_info",
            "--count",
            "100000",
        ],
    );
    images.expect_async("READY", T).await;
    infos.expect_async("READY", T).await;
    let first: Json = serde_json::from_str(&infos.expect_async("MSG", T).await).unwrap();
    assert_eq!(first["width"], 320);
    assert_eq!(first["height"], 240);
    assert_eq!(first["distortion_model"], "plumb_bob");
    assert_eq!(
        first["d"],
        serde_json::json!([-0.367522, 0.132343, -0.000399841, -0.00016906, 0.0])
    );
    assert_eq!(
        first["k"],
        serde_json::json!([215.622, 0.0, 163.367, 0.0, 215.056, 111.212, 0.0, 0.0, 1.0])
    );
    assert_eq!(
        first["p"],
        serde_json::json!([
            215.622, 0.0, 163.367, 0.0, 0.0, 215.056, 111.212, 0.0, 0.0, 0.0, 1.0, 0.0
        ])
    );
    assert_eq!(
        first["r"],
        serde_json::json!([1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0])
    );
    assert_eq!(first["header"]["frame_id"], "left_camera");
    // Each Image has its CameraInfo: same stamp, same frame (images older than the first
    // CameraInfo this subscriber got were sent before it matched the gateway).
    let s = &first["header"]["stamp"];
    let since = (s["sec"].as_i64().unwrap(), s["nanosec"].as_i64().unwrap());
    let (mut image_stamps, mut info_stamps) = (Vec::new(), vec![since]);
    // Ten images (a busy machine may take a while to match the best-effort reader).
    let end = Instant::now() + T;
    while image_stamps.len() < 10 && Instant::now() < end {
        while let Some(l) = images.try_line("MSG") {
            let m: Json = serde_json::from_str(&l).unwrap();
            assert_eq!(m["frame_id"], "left_camera");
            assert_eq!(
                (m["width"].as_u64(), m["height"].as_u64()),
                (Some(320), Some(240))
            );
            let stamp = (m["sec"].as_i64().unwrap(), m["nanosec"].as_i64().unwrap());
            if stamp >= since {
                image_stamps.push(stamp);
            }
        }
        while let Some(l) = infos.try_line("MSG") {
            let m: Json = serde_json::from_str(&l).unwrap();
            assert_eq!(m["header"]["frame_id"], "left_camera");
            assert_eq!(m["k"], first["k"]);
            let s = &m["header"]["stamp"];
            info_stamps.push((s["sec"].as_i64().unwrap(), s["nanosec"].as_i64().unwrap()));
        }
        tokio::time::sleep(std::time::Duration::from_millis(10)).await;
    }
    // The last image's info may still be on its way; images are best effort (a lost
    // one has no partner to check).
    tokio::time::sleep(std::time::Duration::from_millis(300)).await;
    while let Some(l) = infos.try_line("MSG") {
        let m: Json = serde_json::from_str(&l).unwrap();
        let s = &m["header"]["stamp"];
        info_stamps.push((s["sec"].as_i64().unwrap(), s["nanosec"].as_i64().unwrap()));
    }
    assert!(
        image_stamps.len() >= 5,
        "{} images within {T:?}",
        image_stamps.len()
    );
    for s in &image_stamps {
        assert!(
            info_stamps.contains(s),
            "image stamped {s:?} has no CameraInfo (got those of {info_stamps:?})"
        );
    }
    eprintln!(
        "{} images, {} camera infos; each image's stamp has its CameraInfo",
        image_stamps.len(),
        info_stamps.len()
    );
    gw.shutdown().await;
}
