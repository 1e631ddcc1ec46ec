//! Multiple-analog-sensors streams of real devices (`fakeIMU`, `fakeFTs` behind
//! `multipleanalogsensorsserver`) as sensor_msgs/Imu and geometry_msgs/WrenchStamped, and
//! a YARP source that vanishes and returns, against rclpy. Domain indices: 12, 13.

mod common;

use common::{blocking, Peer, T};
use serde_json::Value as Json;
use std::time::Duration;
use yarp_net::port::Port;
use yarp_proto::{Bottle, Stamp};

async fn write_until(w: &Port, b: &Bottle, peer: &Peer) -> Json {
    let line = common::repeat_until(
        "rclpy to receive",
        Duration::from_millis(50),
        async || {
            w.write(b).await;
        },
        || peer.try_line("MSG"),
    )
    .await;
    serde_json::from_str(&line).unwrap()
}

fn f(m: &Json, path: &[&str]) -> f64 {
    path.iter()
        .fold(m, |v, k| &v[*k])
        .as_f64()
        .unwrap_or_else(|| panic!("{path:?} in {m}"))
}

/// Seconds of a `header.stamp`.
fn stamp(m: &Json) -> f64 {
    f(m, &["header", "stamp", "sec"]) + f(m, &["header", "stamp", "nanosec"]) * 1e-9
}

use yarp_proto::stamp::now;

/// Real devices: `fakeIMU` and `fakeFTs` (constant readings: every channel 10) each
/// served by a `multipleanalogsensorsserver`.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn imu_and_wrench_from_multiple_analog_sensors() {
    for d in common::distros("imu_and_wrench_from_multiple_analog_sensors") {
        imu_and_wrench_from_multiple_analog_sensors_on(&d).await;
    }
}

async fn imu_and_wrench_from_multiple_analog_sensors_on(venv: &common::Distro) {
    let domain = venv.domain(12);
    let ns = common::device_name_server();
    let _imu = blocking(|| {
        common::open_device(
            "device multipleanalogsensorsserver\nsubdevice fakeIMU\nname /t12/imu\nperiod 10\n\
             constantValue true\nsensorName head_imu\nframeName head_frame\n",
        )
    })
    .await;
    let _fts = blocking(|| {
        common::open_device(
            "device multipleanalogsensorsserver\nsubdevice fakeFTs\nname /t12/ft\nperiod 10\n\
             constantValue true\nsensorNames (l_arm_ft r_arm_ft)\n",
        )
    })
    .await;
    let gw = common::gateway(
        r#"
[[topic]]
name = "imu"
direction = "yarp_to_ros"
yarp_port = "/gw/imu:i"
yarp_source = "/t12/imu/measures:o"
ros_topic = "/imu"
ros_type = "sensor_msgs/msg/Imu"
frame_id = "imu_link"

[[topic]]
name = "ft"
direction = "yarp_to_ros"
yarp_port = "/gw/ft:i"
yarp_source = "/t12/ft/measures:o"
ros_topic = "/wrench"
ros_type = "geometry_msgs/msg/WrenchStamped"
frame_id = "r_arm_ft"
sensor_index = 1
qos = { reliability = "best_effort", depth = 5 }
"#,
        &ns,
        domain,
    )
    .await;
    let imu = Peer::start(venv, domain, &["sub", "sensor_msgs/msg/Imu", "/imu"]);
    let ft = Peer::start(
        venv,
        domain,
        &[
            "sub",
            "geometry_msgs/msg/WrenchStamped",
            "/wrench",
            "--best-effort",
        ],
    );
    imu.expect_async("READY", T).await;
    ft.expect_async("READY", T).await;
    let m: Json = serde_json::from_str(&imu.expect_async("MSG", T).await).unwrap();
    assert_eq!(m["header"]["frame_id"], "imu_link");
    assert!((now() - stamp(&m)).abs() < 10.0, "stamp of {m}");
    // gyroscope 10 deg/s on every axis
    for k in ["x", "y", "z"] {
        let w = f(&m, &["angular_velocity", k]);
        assert!((w - 10f64.to_radians()).abs() < 1e-12, "{m}");
    }
    // the fake's gravity for a body pitched by 10 * 3.14 / 180 rad
    let acc = yarp_devices::sensors::FakeImu::acceleration(10.0);
    for (k, want) in ["x", "y", "z"].into_iter().zip(acc) {
        assert!(
            (f(&m, &["linear_acceleration", k]) - want).abs() < 1e-12,
            "{m}"
        );
    }
    // roll = pitch = yaw = 10 deg as a quaternion (ZYX convention)
    let h = 5f64.to_radians();
    let (c, s) = (h.cos(), h.sin());
    let want = [
        s * c * c - c * s * s,
        c * s * c + s * c * s,
        c * c * s - s * s * c,
        c * c * c + s * s * s,
    ];
    for (k, want) in ["x", "y", "z", "w"].into_iter().zip(want) {
        assert!((f(&m, &["orientation", k]) - want).abs() < 1e-9, "{k}: {m}");
    }
    let m: Json = serde_json::from_str(&ft.expect_async("MSG", T).await).unwrap();
    assert_eq!(m["header"]["frame_id"], "r_arm_ft");
    assert!((now() - stamp(&m)).abs() < 10.0, "stamp of {m}");
    for part in ["force", "torque"] {
        for k in ["x", "y", "z"] {
            assert_eq!(f(&m, &["wrench", part, k]), 10.0, "{m}");
        }
    }
    gw.shutdown().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_yarp_source_that_vanishes_and_returns_is_reconnected() {
    for d in common::distros("a_yarp_source_that_vanishes_and_returns_is_reconnected") {
        a_yarp_source_that_vanishes_and_returns_is_reconnected_on(&d).await;
    }
}

async fn a_yarp_source_that_vanishes_and_returns_is_reconnected_on(venv: &common::Distro) {
    let domain = venv.domain(13);
    let (ns, stop) = common::name_server().await;
    let gw = common::gateway(
        r#"
[[topic]]
name = "counter"
direction = "yarp_to_ros"
yarp_port = "/gw/counter:i"
yarp_source = "/test/counter:o"
ros_topic = "/counter"
ros_type = "std_msgs/msg/Int32"
"#,
        &ns,
        domain,
    )
    .await;
    let sub = Peer::start(
        venv,
        domain,
        &["sub", "std_msgs/msg/Int32", "/counter", "--count", "1000"],
    );
    sub.expect_async("READY", T).await;
    // The source starts after the gateway, and the envelope travels along.
    let w = Port::open("/test/counter:o", ns.clone()).await.unwrap();
    let m = write_until(&w, &Bottle::from_text("1"), &sub).await;
    assert_eq!(m["data"], 1);
    w.close().await;
    // A new process with the same port name: the gateway connects again.
    let w = Port::open("/test/counter:o", ns.clone()).await.unwrap();
    while sub.try_line("MSG").is_some() {}
    let got = common::repeat_until(
        "the restarted source to reach ROS",
        Duration::from_millis(50),
        async || {
            w.write_stamped(&Bottle::from_text("2"), Stamp::new(1, 5.0))
                .await;
        },
        || sub.try_line("MSG").filter(|l| l.contains('2')),
    )
    .await;
    assert_eq!(got, r#"{"data": 2}"#);
    w.close().await;
    gw.shutdown().await;
    stop.shutdown();
}
