//! ergoCubSN001's ROS 2 wrapper files, unmodified (`alljoints-mc_nws_ros2.xml`, the four
//! `*-FT_nws_ros2.xml`, `sensors/ros2_repeaters/head_imu_ros2.xml`), brought up by the
//! robot-interface runner (what `yarprobotinterface` runs) against the emulated Ethernet
//! boards (address map 10.0.1.0/24 -> 127.0.5.0/24), under netns-run; the top file is the
//! test's own (`tests/ergocub/mod.rs`).
//!
//! rclpy receives JointState with the robot's 45 joint names, WrenchStamped on the four F/T
//! topics and Imu, each publisher announcing rclpy's own type hash. Then a ROS 2 client on
//! the project's ROS layer (rclpy cannot load `yarp_control_msgs` here: the venv has no
//! generated Python types for it) calls GetJointsNames, GetAvailableControlModes,
//! SetControlModes and GetControlModes and publishes `yarp_control_msgs/Position`: the
//! left shoulder roll moves, seen on `/ergocub/left_arm/state:o`. rclpy sees that topic's
//! endpoints with rosidl's hash of Position.

#[path = "../../tests/common/mod.rs"]
mod common;
mod ergocub;
#[path = "../../../devices/icub-emulators/tests/eth_common/mod.rs"]
mod eth_common;

use ergocub::*;
use eth_common::{bring_up_with, T};
use ros2_client::{Client, Publisher};
use serde_json::Value as Json;
use std::time::{Duration, Instant};
use yarp_devices::robotinterface::{read_robot_file, ActionPhase, RobotRunner};
use yarp_devices_ros2::control_msgs::{
    JointIndexes, JointNames, OnlyImplemented, Outcome, SetModes, StringsOutcome,
};
use yarp_net::blocking::{BufferedPort, Network};
use yarp_proto::Property;
use yarp_ros2_gateway::dynmsg::Value as Ros;
use yarp_ros2_gateway::hash::rihs01;
use yarp_ros2_gateway::mapping::Qos;
use yarp_ros2_gateway::ros;

/// rosidl's hash of `yarp_control_msgs/msg/Position` (tests/type_hashes.rs).
const POSITION_HASH: &str =
    "RIHS01_499fa67073eb1080970ec46ebdeba1d0180d81609bd09a28b0691257a7aa4967";

struct RosClient {
    rt: tokio::runtime::Runtime,
    node: std::sync::Arc<ros2_client::Node>,
    position: Publisher<Ros>,
    names: Client<JointIndexes, StringsOutcome>,
    available: Client<OnlyImplemented, StringsOutcome>,
    set_modes: Client<SetModes, Outcome>,
    get_modes: Client<JointNames, StringsOutcome>,
}

impl RosClient {
    fn start(domain: u16) -> RosClient {
        let rt = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(2)
            .enable_all()
            .build()
            .unwrap();
        let ctx = ros::start_context(domain, &["127.0.0.1".parse().unwrap()]).unwrap();
        let mut node = ros::new_node(&ctx, "/", "ergocub_ros2_test").unwrap();
        let srv = |s: &str| format!("yarp_control_msgs/srv/{s}");
        let position = ros::publisher(
            &mut node,
            &format!("{CONTROL}/position"),
            "yarp_control_msgs/msg/Position",
            &Qos::default(),
        )
        .unwrap();
        let names = ros::client(
            &mut node,
            &format!("{CONTROL}/get_joints_names"),
            &srv("GetJointsNames"),
        )
        .unwrap();
        let available = ros::client(
            &mut node,
            &format!("{CONTROL}/get_available_modes"),
            &srv("GetAvailableControlModes"),
        )
        .unwrap();
        let set_modes = ros::client(
            &mut node,
            &format!("{CONTROL}/set_modes"),
            &srv("SetControlModes"),
        )
        .unwrap();
        let get_modes = ros::client(
            &mut node,
            &format!("{CONTROL}/get_modes"),
            &srv("GetControlModes"),
        )
        .unwrap();
        let spinner = node.spinner().unwrap();
        rt.spawn(async move {
            let _ = spinner.spin().await;
        });
        RosClient {
            rt,
            node: std::sync::Arc::new(node),
            position,
            names,
            available,
            set_modes,
            get_modes,
        }
    }

    fn call<Req, Resp>(&self, c: &Client<Req, Resp>, req: Req) -> Resp
    where
        Req: ros2_client::Message + Clone + 'static,
        Resp: ros2_client::Message + 'static,
    {
        let node = self.node.clone();
        self.rt
            .block_on(async {
                tokio::time::timeout(T, async {
                    c.wait_for_service(&node).await;
                    c.async_call_service(req).await
                })
                .await
            })
            .expect("a service answer in time")
            .unwrap_or_else(|e| panic!("service call: {e:?}"))
    }
}

/// `yarp_control_msgs/Position` for one joint, no reference speed.
fn position(joint: &str, rad: f64) -> Ros {
    Ros::Struct(vec![
        Ros::List(vec![Ros::Str(joint.into())]),
        Ros::List(vec![Ros::F64(rad)]),
        Ros::List(vec![]),
    ])
}

fn json(s: &str) -> Json {
    serde_json::from_str(s).unwrap_or_else(|e| panic!("{e}: {s}"))
}

#[test]
fn ergocub_ros2_wrappers_serve_rclpy_and_take_ros_commands() {
    let Some(venv) = ros_venv("ergocub_ros2") else {
        return;
    };
    // a domain of the gateway's test harness (index 19: no other test's)
    let domain = common::domain_id(19);
    std::env::set_var("ROS_DOMAIN_ID", domain.to_string());
    std::env::set_var("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST");
    // What yarprobotinterface registers besides the framework's and icubmod's drivers.
    yarp_devices::Registry::install(yarp_devices_ros2::register);

    let dir = robot_dir();
    let tmp = tempfile::tempdir().unwrap();
    let top = top_file(&dir, tmp.path(), true);
    let (mut runner, _conf) = bring_up_with(&dir, &top, "10.0.1.0/24=127.0.5.0/24", &ros2_tags());
    for f in runner.failures() {
        assert!(!f.contains("ros2") && !f.contains("strain"), "{f}");
    }
    assert!(
        runner
            .unavailable_devices()
            .iter()
            .all(|(_, kind)| !kind.contains("ros2")),
        "{:?}",
        runner.unavailable_devices()
    );
    // The head IMU repeater: a robot file of its own, reading the robot's head IMU port.
    let imu_file = dir.join("sensors/ros2_repeaters/head_imu_ros2.xml");
    let imu_robot = read_robot_file(&imu_file, &Property::default())
        .unwrap_or_else(|e| panic!("{e}"))
        .robot;
    let mut imu_runner = RobotRunner::new(imu_robot);
    imu_runner.set_keep_going(true);
    imu_runner.enter_phase(ActionPhase::Startup).unwrap();
    assert!(
        imu_runner.failures().is_empty(),
        "{:?}",
        imu_runner.failures()
    );
    imu_runner.enter_phase(ActionPhase::Run).unwrap();

    // The ROS client exists before rclpy looks at the Position topic's endpoints.
    let client = RosClient::start(domain);

    let mut args = watched(true);
    args.extend([
        "--info".to_string(),
        format!("{CONTROL}/position"),
        "--timeout".into(),
        "120".into(),
    ]);
    let watch = watch(&venv, domain, &args);
    let started = Instant::now();
    watch.expect("READY", T);
    let mut first = std::collections::HashMap::new();
    let mut hashes = std::collections::HashMap::new();
    let mut info = None;
    let end = Instant::now() + Duration::from_secs(120);
    while first.len() < 6 || hashes.len() < 6 || info.is_none() {
        let left = end.saturating_duration_since(Instant::now());
        let line = watch.expect("", left);
        let mut parts = line.splitn(3, ' ');
        match (parts.next(), parts.next(), parts.next()) {
            (Some("FIRST"), Some(t), Some(j)) => {
                eprintln!(
                    "{t} after {:?}: {}",
                    started.elapsed(),
                    &j[..j.len().min(300)]
                );
                first.insert(t.to_string(), json(j));
            }
            (Some("HASH"), Some(t), Some(j)) => {
                hashes.insert(t.to_string(), json(j));
            }
            (Some("INFO"), Some(_), Some(j)) => info = Some(json(j)),
            (Some("DONE"), ..) => break,
            _ => {}
        }
    }

    // JointState with the robot's joint names.
    let names = alljoints_names(&dir);
    assert_eq!(names.len(), 45);
    let js = &first[JOINT_STATES];
    assert_eq!(js["name"], serde_json::json!(names));
    assert_eq!(js["position"].as_array().unwrap().len(), 45);
    for t in FT_TOPICS {
        assert_eq!(first[t]["type"], "WrenchStamped", "{t}");
        assert_eq!(first[t]["force"].as_array().unwrap().len(), 3, "{t}");
    }
    let imu = &first[HEAD_IMU];
    assert_eq!(imu["type"], "Imu");
    let q: Vec<f64> = serde_json::from_value(imu["orientation"].clone()).unwrap();
    assert!(
        (q.iter().map(|x| x * x).sum::<f64>() - 1.0).abs() < 1e-6,
        "{q:?}"
    );
    // Real type hashes: what our publishers announce is rclpy's own hash of the type.
    for (topic, ty) in [
        (JOINT_STATES, "sensor_msgs/msg/JointState"),
        (HEAD_IMU, "sensor_msgs/msg/Imu"),
    ]
    .into_iter()
    .chain(FT_TOPICS.map(|t| (t, "geometry_msgs/msg/WrenchStamped")))
    {
        let h = &hashes[topic];
        let want = rihs01(ty).unwrap();
        assert_eq!(h["own"], want.as_str(), "{topic}");
        let pubs = h["pubs"].as_array().unwrap();
        assert!(!pubs.is_empty(), "{topic}");
        for p in pubs {
            assert_eq!(p["hash"], want.as_str(), "{topic}: {p}");
        }
    }
    let info = info.expect("INFO of the Position topic");
    for e in info["pubs"]
        .as_array()
        .unwrap()
        .iter()
        .chain(info["subs"].as_array().unwrap())
    {
        assert_eq!(e["type"], "yarp_control_msgs/msg/Position", "{e}");
        assert_eq!(e["hash"], POSITION_HASH, "{e}");
    }
    eprintln!("rclpy: every topic and hash after {:?}", started.elapsed());

    // The four services.
    let r = client.call(&client.names, JointIndexes::default());
    assert_eq!(
        (r.values.clone(), r.response.as_str()),
        (names.clone(), "OK")
    );
    let r = client.call(
        &client.available,
        OnlyImplemented {
            only_implemented: true,
        },
    );
    assert_eq!(r.values, ["POSITION", "POSITION_DIRECT", "VELOCITY"]);
    let joint = "l_shoulder_roll";
    let r = client.call(
        &client.set_modes,
        SetModes {
            names: vec![joint.into()],
            modes: vec!["POSITION".into()],
        },
    );
    assert_eq!(r.response, "OK");
    let r = client.call(
        &client.get_modes,
        JointNames {
            names: vec![joint.into()],
        },
    );
    assert_eq!(
        (r.values, r.response.as_str()),
        (vec!["POSITION".to_string()], "OK")
    );

    // Position moves the joint (joint 1 of the left arm), seen on its state:o.
    let net = Network::from_conf().expect("network");
    let state = BufferedPort::open(&net, "/test/left_arm/state:i").unwrap();
    net.connect("/ergocub/left_arm/state:o", "/test/left_arm/state:i", None)
        .expect("connect state:o");
    let joint1 = |timeout| -> Option<f64> {
        state
            .read_timeout(timeout)
            .and_then(|m| m.bottle.get(1).and_then(|v| v.as_f64()))
    };
    let q0 = joint1(T).expect("a state:o bottle");
    let target = if (q0 - 60.0).abs() > 5.0 { 60.0 } else { 40.0 };
    let node = client.node.clone();
    client.rt.block_on(async {
        tokio::time::timeout(T, client.position.wait_for_subscription(&node))
            .await
            .expect("the device's Position subscription matches")
    });
    let sent = Instant::now();
    client
        .position
        .publish(position(joint, f64::to_radians(target)))
        .unwrap();
    let end = Instant::now() + T;
    let mut at = q0;
    while (at - target).abs() > 0.5 {
        assert!(
            Instant::now() < end,
            "{joint} at {at}, not {target} (from {q0})"
        );
        at = joint1(T).unwrap_or(at);
    }
    eprintln!("{joint} {q0} -> {target} after {:?}", sent.elapsed());

    state.close();
    drop(watch);
    // The file also detaches its multipleanalogsensorsclient, which is no wrapper: that
    // action fails (C++ yarprobotinterface reports it too); the rest shuts down.
    if let Err(e) = imu_runner.enter_phase(ActionPhase::Shutdown) {
        eprintln!("head_imu_ros2.xml shutdown: {e:?}");
    }
    runner.enter_phase(ActionPhase::Interrupt1).unwrap();
    runner.enter_phase(ActionPhase::Shutdown).unwrap();
}
