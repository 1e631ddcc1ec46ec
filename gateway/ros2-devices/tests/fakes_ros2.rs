//! Every server of this crate opened as `yarpdev` opens it (`--device W --subdevice D`),
//! over the framework's fakes, in one process: rclpy receives each one's topic with its
//! real type hash (`controlBoard_nws_ros2` over `fakeMotionControl` with a namespace;
//! `imu_nws_ros2` and `magneticField_nws_ros2` over `fakeIMU`; `wrenchStamped_nws_ros2` and
//! `temperature_nws_ros2` over `fakeFTs`).

#[path = "../../tests/common/mod.rs"]
mod common;
mod ergocub;

use ergocub::{ros_venv, watch};
use std::time::{Duration, Instant};
use yarp_devices::PolyDriver;
use yarp_proto::Property;
use yarp_ros2_gateway::hash::rihs01;

#[test]
fn every_server_over_fakes_reaches_rclpy() {
    let Some(venv) = ros_venv("fakes_ros2") else {
        return;
    };
    // a domain of the gateway's test harness (index 21: no other test's)
    let domain = common::domain_id(21);
    std::env::set_var("ROS_DOMAIN_ID", domain.to_string());
    std::env::set_var("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST");
    yarp_devices::Registry::install(yarp_devices_ros2::register);
    let open = |text: &str| {
        PolyDriver::open(&Property::from_text(text)).unwrap_or_else(|e| panic!("{text}: {e}"))
    };
    let _devices = [
        open(
            "(device controlBoard_nws_ros2) (subdevice fakeMotionControl) (axes 3) \
             (node_name fake_cb) (namespace fake) (topic_name /fake/joint_states) (period 0.01)",
        ),
        open(
            "(device imu_nws_ros2) (subdevice fakeIMU) (node_name fake_imu) (topic_name /fake/imu)",
        ),
        open(
            "(device magneticField_nws_ros2) (subdevice fakeIMU) (node_name fake_mag) \
             (topic_name /fake/magnetic_field)",
        ),
        open(
            "(device wrenchStamped_nws_ros2) (subdevice fakeFTs) (sensorNames (ft0)) \
             (node_name fake_ft) (topic_name /fake/wrench) (period 0.005)",
        ),
        open(
            "(device temperature_nws_ros2) (subdevice fakeFTs) (sensorNames (ft0)) \
             (node_name fake_temp) (topic_name /fake/temperature)",
        ),
    ];
    let topics = [
        ("/fake/joint_states", "sensor_msgs/msg/JointState"),
        (
            "/fake/joint_states/controlModes",
            "std_msgs/msg/Int8MultiArray",
        ),
        ("/fake/imu", "sensor_msgs/msg/Imu"),
        ("/fake/magnetic_field", "sensor_msgs/msg/MagneticField"),
        ("/fake/wrench", "geometry_msgs/msg/WrenchStamped"),
        ("/fake/temperature", "sensor_msgs/msg/Temperature"),
    ];
    let args: Vec<String> = topics
        .iter()
        .map(|(t, ty)| format!("{t}={ty}"))
        .chain(["--timeout".into(), "60".into()])
        .collect();
    let w = watch(&venv, domain, &args);
    w.expect("READY", Duration::from_secs(30));
    let (mut first, mut hashes) = (Vec::new(), Vec::new());
    let end = Instant::now() + Duration::from_secs(60);
    while first.len() < topics.len() || hashes.len() < topics.len() {
        let l = w.expect("", end.saturating_duration_since(Instant::now()));
        if let Some(rest) = l.strip_prefix("FIRST ") {
            eprintln!("{rest}");
            first.push(rest.to_string());
        } else if let Some(rest) = l.strip_prefix("HASH ") {
            hashes.push(rest.to_string());
        }
    }
    for (topic, ty) in topics {
        let h = hashes
            .iter()
            .find_map(|l| l.strip_prefix(&format!("{topic} ")))
            .unwrap_or_else(|| panic!("{topic}: no HASH"));
        let h: serde_json::Value = serde_json::from_str(h).unwrap();
        let want = rihs01(ty).unwrap();
        assert_eq!(h["own"], want.as_str(), "{topic}");
        assert_eq!(h["pubs"][0]["hash"], want.as_str(), "{topic}");
        // the node's name and namespace, as rclpy sees them
        if topic == "/fake/joint_states" {
            assert_eq!(h["pubs"][0]["node"], "fake_cb", "{h}");
            assert_eq!(h["pubs"][0]["namespace"], "/fake", "{h}");
        }
    }
    let js = first
        .iter()
        .find_map(|l| l.strip_prefix("/fake/joint_states "))
        .unwrap();
    let js: serde_json::Value = serde_json::from_str(js).unwrap();
    assert_eq!(js["name"].as_array().unwrap().len(), 3, "{js}");
}
