//! A real control board (`fakeMotionControl` served by `controlBoard_nws_yarp`) as
//! sensor_msgs/JointState in rclpy: names from its IAxisInfo over `rpc:i`, positions from
//! `state:o` in radians (meters for the prismatic axis), stamps from the `state:o`
//! envelope. Domain indices: 14, 22.

mod common;

use common::{blocking, Peer, T};
use serde_json::Value as Json;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};
use yarp_net::port::Port;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn control_board_state_becomes_joint_state() {
    for d in common::distros("control_board_state_becomes_joint_state") {
        control_board_state_becomes_joint_state_on(&d).await;
    }
}

async fn control_board_state_becomes_joint_state_on(venv: &common::Distro) {
    let domain = venv.domain(14);
    let ns = common::device_name_server();
    let _server = blocking(|| {
        common::open_device(
            "device controlBoard_nws_yarp\nsubdevice fakeMotionControl\nname /t14/left_arm\n\
             period 0.01\n[GENERAL]\njoints 3\n\
             AxisName \"l_shoulder_pitch\" \"l_elbow\" \"l_slide\"\n\
             AxisType \"revolute\" \"revolute\" \"prismatic\"\n",
        )
    })
    .await;
    // Move the joints (instantly: the fake's reference speed is 0) through a client.
    let client = blocking(|| {
        let mut c = common::open_device(
            "device remote_controlboard\nremote /t14/left_arm\nlocal /t14/mover\ncarrier tcp\n",
        );
        c.device()
            .as_position_control()
            .unwrap()
            .position_moves(&[10.0, -90.0, 0.25])
            .unwrap();
        c
    })
    .await;
    // The envelopes of state:o, as the test sees them.
    let stamps: Arc<Mutex<Vec<f64>>> = Arc::default();
    let probe = Port::open("/t14/probe:i", ns.clone()).await.unwrap();
    yarp_net::network::connect(&ns, "/t14/left_arm/state:o", "/t14/probe:i", None)
        .await
        .unwrap();
    let recorder = {
        let stamps = stamps.clone();
        tokio::spawn(async move {
            while let Some(m) = probe.read().await {
                if let Some(s) = m.stamp {
                    stamps.lock().unwrap().push(s.time);
                }
            }
        })
    };
    let gw = common::gateway(
        r#"
[[topic]]
name = "left_arm"
direction = "yarp_to_ros"
yarp_port = "/gw/left_arm/state:i"
yarp_source = "/t14/left_arm/state:o"
ros_topic = "/left_arm/joint_states"
ros_type = "sensor_msgs/msg/JointState"
frame_id = "base"
joint_names = { from = "axis_info", rpc_port = "/t14/left_arm/rpc:i" }
"#,
        &ns,
        domain,
    )
    .await;
    let sub = Peer::start(
        venv,
        domain,
        &[
            "sub",
            "sensor_msgs/msg/JointState",
            "/left_arm/joint_states",
            "--count",
            "5",
        ],
    );
    sub.expect_async("READY", T).await;
    let line = sub.expect_async("MSG", T).await;
    let m: Json = serde_json::from_str(&line).unwrap();
    assert_eq!(
        m["name"],
        serde_json::json!(["l_shoulder_pitch", "l_elbow", "l_slide"])
    );
    let pos: Vec<f64> = m["position"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let want = [10f64.to_radians(), (-90f64).to_radians(), 0.25];
    assert!(
        pos.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-9),
        "{pos:?}"
    );
    assert_eq!(m["header"]["frame_id"], "base");
    // The stamp is one of the envelopes state:o sent, and recent.
    let stamp = m["header"]["stamp"]["sec"].as_f64().unwrap()
        + m["header"]["stamp"]["nanosec"].as_f64().unwrap() * 1e-9;
    let end = Instant::now() + T;
    loop {
        if stamps
            .lock()
            .unwrap()
            .iter()
            .any(|t| (t - stamp).abs() < 2e-6)
        {
            break;
        }
        assert!(
            Instant::now() < end,
            "stamp {stamp} is not a state:o envelope"
        );
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    let now = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .unwrap()
        .as_secs_f64();
    assert!((now - stamp).abs() < 10.0, "stamp {stamp}, now {now}");
    eprintln!(
        "JointState {pos:?} stamped {stamp:.6} ({:.1} ms old)",
        (now - stamp) * 1e3
    );
    gw.shutdown().await;
    recorder.abort();
    drop(client);
}

/// `stateExt:o` (C++ `jointData`) carries velocities and torques too: rclpy gets
/// `velocity` in rad/s for the revolute joint and m/s for the prismatic one.
/// Domain index: 22.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn state_ext_gives_velocity_and_effort() {
    for d in common::distros("state_ext_gives_velocity_and_effort") {
        state_ext_gives_velocity_and_effort_on(&d).await;
    }
}

async fn state_ext_gives_velocity_and_effort_on(venv: &common::Distro) {
    let domain = venv.domain(22);
    let ns = common::device_name_server();
    let _server = blocking(|| {
        common::open_device(
            "device controlBoard_nws_yarp\nsubdevice fakeMotionControl\nname /t22/arm\n\
             period 0.01\n[GENERAL]\njoints 2\nAxisName \"wrist\" \"rail\"\n\
             AxisType \"revolute\" \"prismatic\"\n",
        )
    })
    .await;
    let client = blocking(|| {
        use yarp_devices::vocabs::CM_VELOCITY;
        let mut c = common::open_device(
            "device remote_controlboard\nremote /t22/arm\nlocal /t22/mover\ncarrier tcp\n",
        );
        let d = c.device();
        d.as_control_mode()
            .unwrap()
            .set_control_modes(&[CM_VELOCITY, CM_VELOCITY])
            .unwrap();
        d.as_velocity_control()
            .unwrap()
            .velocity_moves(&[10.0, 0.02])
            .unwrap();
        c
    })
    .await;
    let gw = common::gateway(
        r#"
[[topic]]
name = "arm_ext"
direction = "yarp_to_ros"
yarp_port = "/gw/arm/stateExt:i"
yarp_source = "/t22/arm/stateExt:o"
ros_topic = "/arm/joint_states"
ros_type = "sensor_msgs/msg/JointState"
joint_names = { from = "axis_info", rpc_port = "/t22/arm/rpc:i" }
"#,
        &ns,
        domain,
    )
    .await;
    let sub = Peer::start(
        venv,
        domain,
        &[
            "sub",
            "sensor_msgs/msg/JointState",
            "/arm/joint_states",
            "--count",
            "1000",
        ],
    );
    sub.expect_async("READY", T).await;
    // The first states may predate the velocity command reaching the board.
    let want = [10f64.to_radians(), 0.02];
    let end = Instant::now() + T;
    let mut seen = 0;
    let m = loop {
        let m: Json = serde_json::from_str(&sub.expect_async("MSG", T).await).unwrap();
        seen += 1;
        assert!(seen < 500, "velocities never matched: {m}");
        let vel: Vec<f64> = m["velocity"]
            .as_array()
            .unwrap()
            .iter()
            .filter_map(Json::as_f64)
            .collect();
        if vel.len() == 2 && vel.iter().zip(want).all(|(a, b)| (a - b).abs() < 1e-6) {
            break m;
        }
        assert!(Instant::now() < end, "velocities never matched: {m}");
    };
    assert_eq!(m["name"], serde_json::json!(["wrist", "rail"]));
    assert_eq!(m["position"].as_array().unwrap().len(), 2);
    let effort = m["effort"].as_array().unwrap().len();
    assert!(effort == 2 || effort == 0, "{m}");
    eprintln!("stateExt JointState: {m}");
    gw.shutdown().await;
    drop(client);
}
